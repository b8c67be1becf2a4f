//! Retentive state through serde: images and function blocks come back as they were.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    reason = "a test may panic: that is how it fails"
)]
#![cfg(feature = "serde")]

use regler_scan_cycle::{Conditioning, Ctu, DateTime, Image, Tof, Ton, Tp};

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

/// Stored state that breaks an invariant is an error, never a broken object.
#[test]
#[cfg_attr(
    miri,
    ignore = "hundreds of stored states through serde_json: minutes interpreted; runs natively in every CI run"
)]
fn bad_stored_state_is_refused() {
    let clock = DateTime::new(2026, 2, 28, 23, 59, 59).unwrap();
    let text = serde_json::to_string(&clock).unwrap();
    assert_eq!(serde_json::from_str::<DateTime>(&text).unwrap(), clock);
    let feb31 = text.replace("\"day\":28", "\"day\":31");
    let err = serde_json::from_str::<DateTime>(&feb31)
        .unwrap_err()
        .to_string();
    assert!(err.contains("the day must be 1..=28"), "{err}");

    let mut c: Conditioning<2> = Conditioning::new();
    c.set_debounce(3, 7).unwrap();
    let text = serde_json::to_string(&c).unwrap();
    assert_eq!(serde_json::from_str::<Conditioning<2>>(&text).unwrap(), c);
    // Clear point 0's count-1 bit in the first threshold plane: a count of 0.
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["thresholds"][0]["words"][0] = serde_json::json!(0xFFFE);
    let err = serde_json::from_value::<Conditioning<2>>(value)
        .unwrap_err()
        .to_string();
    assert!(err.contains("point 0 a debounce count of 0"), "{err}");
    // Latch point 3, which is debounced with count 7: a latched pulse would be lost.
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["latched"]["words"][0] = serde_json::json!(1 << 3);
    let err = serde_json::from_value::<Conditioning<2>>(value)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("point 3 cannot be latched and debounced (count 7)"),
        "{err}"
    );
    // A captured pulse on a point that is not latched (a torn or tampered block) is refused, on
    // every point: it would read as a phantom input for a cycle. On a latched point it is kept.
    for point in 0..32usize {
        let (w, bit) = (point / 16, point % 16);
        let mut value = serde_json::to_value(Conditioning::<2>::new()).unwrap();
        value["pending"]["words"][w] = serde_json::json!(1u16 << bit);
        let err = serde_json::from_value::<Conditioning<2>>(value.clone())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!(
                "captured pulse on point {point}, which is not latched"
            )),
            "{err}"
        );
        value["latched"]["words"][w] = serde_json::json!(1u16 << bit);
        let back = serde_json::from_value::<Conditioning<2>>(value).unwrap();
        let mut out = regler_scan_cycle::Image::<2>::new();
        let mut back = back;
        back.condition(&[0; 2], &mut out);
        assert!(
            out.get(point),
            "point {point}: the stored pulse on a latched point is read"
        );
    }
    // Every count above 1 on a latched point is refused; a latched point with count 1 comes back.
    for k in 1..=15u8 {
        let mut c: Conditioning<2> = Conditioning::new();
        c.set_latched(9, true).unwrap();
        let text = serde_json::to_string(&c).unwrap();
        assert_eq!(serde_json::from_str::<Conditioning<2>>(&text).unwrap(), c);
        let mut debounced: Conditioning<2> = Conditioning::new();
        debounced.set_debounce(9, k).unwrap();
        let mut value = serde_json::to_value(debounced).unwrap();
        value["latched"]["words"][0] = serde_json::json!(1 << 9);
        let back = serde_json::from_value::<Conditioning<2>>(value);
        if k == 1 {
            assert_eq!(back.unwrap(), c);
        } else {
            let err = back.unwrap_err().to_string();
            assert!(
                err.contains(&format!(
                    "point 9 cannot be latched and debounced (count {k})"
                )),
                "{err}"
            );
        }
    }
}

/// A block that is not a block at all is refused with a message naming the type the user
/// stores, not a private stored form.
#[test]
fn a_refused_block_names_the_type_stored() {
    let err = |e: serde_json::Error| e.to_string();
    let messages = [
        (
            err(serde_json::from_str::<Conditioning<2>>("null").unwrap_err()),
            "struct Conditioning",
        ),
        (
            err(serde_json::from_str::<DateTime>("null").unwrap_err()),
            "struct DateTime",
        ),
        (
            err(serde_json::from_str::<Ton>("null").unwrap_err()),
            "struct Ton or Tof",
        ),
        (
            err(serde_json::from_str::<Tof>("null").unwrap_err()),
            "struct Ton or Tof",
        ),
        (
            err(serde_json::from_str::<Tp>("null").unwrap_err()),
            "struct Tp",
        ),
    ];
    for (message, want) in messages {
        assert!(message.contains(want), "{message}");
        assert!(!message.contains("Raw"), "{message}");
    }
}

/// The root docs of `Conditioning`: "a restored debounced input with count k changes after at
/// most k consecutive differing readings — after k − c when it had counted c of them, and at the
/// first when c ≥ k"; a stored counter of 15, which the conditioning never holds, is refused.
/// Every point of a two-word image, every count 1..=15, every stored counter 0..=15, the input
/// stored off and on. (Before the restore refused it, a counter of 15 wrapped to 0 and the
/// input waited k more readings: 16 for count 15.)
#[test]
#[cfg_attr(
    miri,
    ignore = "15 360 stored states through serde_json, 16 cycles each: minutes interpreted; runs natively in every CI run"
)]
fn a_restored_counter_finishes_its_count_and_15_is_refused() {
    for point in 0..32usize {
        let (w, bit) = (point / 16, point % 16);
        for k in 1..=15u8 {
            for counter in 0..=15u16 {
                for stored_on in [false, true] {
                    let mut c: Conditioning<2> = Conditioning::new();
                    c.set_debounce(point, k).unwrap();
                    let mut value = serde_json::to_value(c).unwrap();
                    if stored_on {
                        value["stable"]["words"][w] = serde_json::json!(1u16 << bit);
                    }
                    for plane in 0..4 {
                        if counter >> plane & 1 == 1 {
                            value["counters"][plane]["words"][w] = serde_json::json!(1u16 << bit);
                        }
                    }
                    let restored = serde_json::from_value::<Conditioning<2>>(value);
                    if counter == 15 {
                        let err = restored.unwrap_err().to_string();
                        assert!(
                            err.contains(&format!(
                                "debounce counter of 15 readings on point {point}"
                            )),
                            "{err}"
                        );
                        continue;
                    }
                    let mut restored = restored.unwrap();
                    // The reading differs from the stored value at `point` only.
                    let mut reading = [0u16; 2];
                    if !stored_on {
                        reading[w] = 1 << bit;
                    }
                    let want = usize::from(k.saturating_sub(u8::try_from(counter).unwrap()).max(1));
                    let mut out = Image::<2>::new();
                    for n in 1..=16 {
                        restored.condition(&reading, &mut out);
                        for p in 0..32 {
                            let expect = if p == point {
                                (n >= want) != stored_on
                            } else {
                                false
                            };
                            assert_eq!(
                                out.get(p),
                                expect,
                                "point {point}, count {k}, stored counter {counter}, stored \
                                 {stored_on}: point {p} after {n} readings"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// A stored timer in a state no sequence of calls leaves it in is refused, naming what is wrong
/// (found by the fuzz target `scan-cycle/fuzz/fuzz_targets/snapshot.rs`: a TON stored with Q on
/// and not finished was on at once, before PT; a TP stored with Q on and no pulse running gave
/// a pulse that never ended).
#[test]
fn corrupt_stored_timers_are_refused() {
    let refused = |text: &str, ty: &str| -> String {
        let err = match ty {
            "ton" => serde_json::from_str::<Ton>(text).map(|_| ()),
            "tof" => serde_json::from_str::<Tof>(text).map(|_| ()),
            _ => serde_json::from_str::<Tp>(text).map(|_| ()),
        };
        err.expect_err(text).to_string()
    };
    let run = r#"{"last_ms":0,"total_ms":10}"#;
    for (ty, text, why) in [
        (
            "ton",
            r#"{"pt_ms":100000,"running":null,"q":true,"done_et":null}"#.to_string(),
            "stored TON has Q on but has not finished: it would be on before PT",
        ),
        (
            "ton",
            format!(r#"{{"pt_ms":100,"running":{run},"q":false,"done_et":100}}"#),
            "stored TON has finished but has Q off",
        ),
        (
            "tof",
            format!(r#"{{"pt_ms":100,"running":{run},"q":true,"done_et":100}}"#),
            "stored TOF has run out its off-delay but has Q on",
        ),
        (
            "tp",
            r#"{"pt_ms":100,"running":null,"q":true,"prev_in":false,"done_et":null}"#.to_string(),
            "stored TP has Q on without a pulse running: the pulse would never end",
        ),
        (
            "tp",
            format!(r#"{{"pt_ms":100,"running":{run},"q":false,"prev_in":true,"done_et":null}}"#),
            "stored TP has a pulse running with Q off",
        ),
        (
            "tp",
            r#"{"pt_ms":100,"running":null,"q":false,"prev_in":false,"done_et":100}"#.to_string(),
            "stored TP holds an ended pulse's ET while IN is off or a pulse runs",
        ),
    ] {
        assert_eq!(refused(&text, ty), why, "{text}");
    }
    // The states a timer does reach come back: a TP's ended pulse held while IN stays on.
    let mut tp = Tp::new(100);
    tp.call(true, 0);
    tp.call(true, 150);
    let back: Tp = serde_json::from_str(&serde_json::to_string(&tp).unwrap()).unwrap();
    assert_eq!(back, tp);
    assert_eq!(back.et(), 100);
}

mod stored_timers {
    use proptest::prelude::{any, prop, proptest};
    use regler_scan_cycle::{Tof, Ton, Tp};
    use serde::{Serialize, de::DeserializeOwned};

    /// A saved timer comes back equal and runs on exactly like the one that was not saved.
    fn round_trip_then_same<
        T: Serialize + DeserializeOwned + PartialEq + core::fmt::Debug + Clone,
    >(
        timer: &mut T,
        call: impl Fn(&mut T, bool, u32) -> bool,
        calls: &[(bool, u32, Option<u32>)],
        set_pt: impl Fn(&mut T, u32),
    ) {
        let mut now = 0u32;
        for (k, &(input, step, pt)) in calls.iter().enumerate() {
            now = now.wrapping_add(step);
            if let Some(pt) = pt {
                set_pt(timer, pt);
            }
            call(timer, input, now);
            let text = serde_json::to_string(&*timer).unwrap();
            let mut back: T = serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("a state a timer reached is refused: {text}: {e}"));
            assert_eq!(&back, &*timer);
            let mut original = timer.clone();
            let mut t = now;
            for &(input, step, _) in &calls[k..] {
                t = t.wrapping_add(step);
                assert_eq!(call(&mut back, input, t), call(&mut original, input, t));
            }
        }
    }

    proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(if cfg!(miri) { 4 } else { 64 }))]

        #[test]
        #[cfg_attr(
            miri,
            ignore = "every state three timers reach, through serde_json: minutes interpreted; runs natively in every CI run"
        )]
        fn every_state_a_timer_reaches_is_stored_and_restored(
            pt in 0u32..300,
            calls in prop::collection::vec((any::<bool>(), 0u32..200, prop::option::weighted(0.1, 0u32..300)), 0..24),
        ) {
            round_trip_then_same(&mut Ton::new(pt), Ton::call, &calls, Ton::set_pt);
            round_trip_then_same(&mut Tof::new(pt), Tof::call, &calls, Tof::set_pt);
            round_trip_then_same(&mut Tp::new(pt), Tp::call, &calls, Tp::set_pt);
        }
    }
}
