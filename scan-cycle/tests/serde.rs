//! Retentive state through serde: images and function blocks come back as they were.
#![cfg(feature = "serde")]
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]

use regler_scan_cycle::{Ctu, Image, Ton};

#[test]
fn images_and_blocks_round_trip() {
    let mut image: Image<3> = Image::new();
    image.set(0, true).unwrap();
    image.set(47, true).unwrap();
    let back: Image<3> = serde_json::from_str(&serde_json::to_string(&image).unwrap()).unwrap();
    assert_eq!(back, image);
    assert!(
        serde_json::from_str::<Image<3>>("{\"words\":[1,2]}").is_err(),
        "wrong word count"
    );

    let mut ton = Ton::new(100);
    ton.call(true, 0);
    ton.call(true, 60);
    let mut back: Ton = serde_json::from_str(&serde_json::to_string(&ton).unwrap()).unwrap();
    assert!(back.call(true, 100), "the timer resumes where it was");
    let mut ctu = Ctu::new(2);
    ctu.call(true, false);
    let back: Ctu = serde_json::from_str(&serde_json::to_string(&ctu).unwrap()).unwrap();
    assert_eq!(back.cv(), 1);
}
