//! Serde: a trolley number is its integer, and a number that is no trolley is refused.
#![allow(clippy::unwrap_used, reason = "a test may panic: that is how it fails")]
#![cfg(feature = "serde")]

use regler_trolley_id::{TrolleyId, Verdict};

#[test]
fn trolley_ids_serialise_as_numbers_and_are_checked_on_the_way_in() {
    let id = TrolleyId::new(1977).unwrap();
    assert_eq!(serde_json::to_string(&id).unwrap(), "1977");
    assert_eq!(serde_json::from_str::<TrolleyId>("1977").unwrap(), id);
    assert!(serde_json::from_str::<TrolleyId>("0").is_err());
    assert!(serde_json::from_str::<TrolleyId>("4096").is_err());
    let v = Verdict::Identified(id);
    assert_eq!(
        serde_json::from_str::<Verdict>(&serde_json::to_string(&v).unwrap()).unwrap(),
        v
    );
}
