//! Regression tests from the attack on the rewritten `TimerQueue` (issue 23 §2): a panic in
//! `tick`'s callback, and the message of `UnknownTimer`.

use std::panic::{AssertUnwindSafe, catch_unwind};

use regler_scan_cycle::TimerQueue;

/// A panic in `on_expire`, caught: that action is gone, the queue stays whole. The two actions
/// due after it on the same tick come out first on the next tick, in order; a newer timer in the
/// same slot of a later block fires on time; no place is lost.
#[test]
fn a_panic_in_on_expire_loses_only_that_action() {
    let mut q: TimerQueue<u32, 4> = TimerQueue::new();
    let a = q.insert(5, 1).unwrap();
    let b = q.insert(5, 2).unwrap();
    let c = q.insert(5, 3).unwrap();
    for _ in 0..4 {
        q.tick(|x| panic!("nothing is due before tick 5, {x} fired"));
    }
    let caught = catch_unwind(AssertUnwindSafe(|| {
        q.tick(|x| assert_ne!(x, 1, "operator code panics on its action"));
    }));
    assert!(caught.is_err());
    assert_eq!(q.len(), 2, "a fired, b and c wait");
    assert_eq!(q.remaining(a), None);
    assert_eq!((q.remaining(b), q.remaining(c)), (Some(0), Some(0)));
    // The next tick hands out b and c first, then its own (d at tick 6).
    let d = q.insert(1, 4).unwrap();
    let mut fired = Vec::new();
    q.tick(|x| fired.push(x));
    assert_eq!(fired, [2, 3, 4]);
    assert!(q.is_empty());
    assert_eq!(
        (q.remaining(b), q.remaining(c), q.remaining(d)),
        (None, None, None)
    );
    // Slot 5 of the next block: two newer timers fire on time, in order.
    let e = q.insert(256 + 5 - 6, 5).unwrap();
    let f = q.insert(256 + 5 - 6, 6).unwrap();
    assert_eq!(q.remove(c), None, "a stale handle touches nothing");
    fired.clear();
    for _ in 0..(256 + 5 - 6) {
        q.tick(|x| fired.push(x));
    }
    assert_eq!(fired, [5, 6]);
    assert_eq!((q.remaining(e), q.remaining(f)), (None, None));
    // Every place is back: four timers fit, a fifth is refused.
    assert!((0..4).all(|i| q.insert(10, 100 + i).is_ok()));
    assert!(q.insert(10, 104).is_err());
}

/// A panic on the last action of a tick leaves nothing behind: the next tick is normal.
#[test]
fn a_panic_on_the_last_action_of_a_tick_leaves_the_queue_as_after_a_normal_tick() {
    let mut q: TimerQueue<u32, 2> = TimerQueue::new();
    q.insert(1, 1).unwrap();
    q.insert(1, 2).unwrap();
    let caught = catch_unwind(AssertUnwindSafe(|| {
        q.tick(|x| assert_ne!(x, 2, "panics on the last"));
    }));
    assert!(caught.is_err());
    assert!(q.is_empty());
    let mut fired = Vec::new();
    q.insert(2, 3).unwrap();
    q.tick(|x| fired.push(x));
    q.tick(|x| fired.push(x));
    assert_eq!(fired, [3]);
}

/// The message names the handle in words, not Rust's `Debug` text, and what may have happened.
#[test]
fn unknown_timer_says_what_happened_without_debug_text() {
    let mut q: TimerQueue<u8, 1> = TimerQueue::new();
    let id = q.insert(1, 0).unwrap();
    q.tick(|_| {});
    let message = q.replace(id, 5).unwrap_err().to_string();
    assert_eq!(
        message,
        "no waiting timer has the handle of place 0, use 0: it expired, was removed or never \
         existed in this queue"
    );
}

/// The actions left by a panic go in front of those already due on the next tick, also when
/// the next tick starts a new block of 256 (and timers come down from the higher levels into
/// it), and every handle keeps working on them.
#[test]
#[cfg_attr(
    miri,
    ignore = "a block of 256 ticks and more: minutes interpreted; runs natively in every CI run"
)]
fn left_actions_come_first_on_the_next_tick_also_across_a_block() {
    for due in [5u32, 255, 256 * 256 - 1] {
        let mut q: TimerQueue<u32, 8> = TimerQueue::new();
        let ids: Vec<_> = (1..=4).map(|x| q.insert(due, x).unwrap()).collect();
        // Already due on the next tick: one inserted now from far away (a higher level).
        let next = q.insert(due + 1, 10).unwrap();
        let also = q.insert(due + 1, 11).unwrap();
        for _ in 1..due {
            q.tick(|x| panic!("nothing is due yet, {x} fired"));
        }
        let caught = catch_unwind(AssertUnwindSafe(|| {
            q.tick(|x| assert_ne!(x, 2, "panics on the second action"));
        }));
        assert!(caught.is_err());
        assert_eq!(q.len(), 4, "due {due}: 3 and 4 left, 10 and 11 waiting");
        assert_eq!(q.remaining(ids[2]), Some(0));
        assert_eq!(q.remaining(next), Some(1));
        // A left action can still be removed: 3 goes, 4 stays.
        assert_eq!(q.remove(ids[2]), Some(3));
        let mut fired = Vec::new();
        q.tick(|x| fired.push(x));
        assert_eq!(fired, [4, 10, 11], "due {due}");
        assert_eq!((q.remaining(ids[3]), q.remaining(also)), (None, None));
        assert!(q.is_empty());
        assert!(
            (0..8).all(|i| q.insert(1 + i, i).is_ok()),
            "every place is back"
        );
    }
}

proptest::proptest! {
    /// Any set of timers, any action panicking (caught): every other action still comes out,
    /// once, in the order of their deadlines and insertion, and the queue ends empty with every
    /// place back. (Under Miri deadlines up to 300 ticks, not 700, so 400 ticks empty it.)
    #[test]
    #[cfg_attr(
        miri,
        ignore = "hundreds of ticks with a panic caught at each: minutes interpreted; runs natively in every CI run"
    )]
    fn a_panic_anywhere_loses_only_that_action(
        delays in proptest::collection::vec(1u32..if cfg!(miri) { 300 } else { 700 }, 1..40),
        panic_at in 0usize..40,
    ) {
        let mut q: TimerQueue<usize, 64> = TimerQueue::new();
        for (k, &d) in delays.iter().enumerate() {
            q.insert(d, k).unwrap();
        }
        // The model: sorted by deadline, ties by insertion; the panicking action dropped.
        let mut want: Vec<usize> = (0..delays.len()).collect();
        want.sort_by_key(|&k| (delays[k], k));
        let victim = want.get(panic_at).copied();
        want.retain(|&k| Some(k) != victim);
        let (mut fired, mut panics) = (Vec::new(), 0usize);
        for _ in 0..if cfg!(miri) { 400 } else { 800 } {
            let caught = catch_unwind(AssertUnwindSafe(|| {
                q.tick(|k| {
                    assert_ne!(Some(k), victim, "the operator code panics on this one");
                    fired.push(k);
                });
            }));
            panics = panics.wrapping_add(usize::from(caught.is_err()));
        }
        proptest::prop_assert_eq!(panics, usize::from(victim.is_some()));
        proptest::prop_assert_eq!(&fired, &want);
        proptest::prop_assert!(q.is_empty());
        proptest::prop_assert!((0..64).all(|k| q.insert(1, k).is_ok()));
    }
}
