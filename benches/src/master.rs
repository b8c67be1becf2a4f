//! The master's workload, shared by the `ring_transfer` bench and the `master-decisions`
//! instruction counter: `n` slaves of mixed rates and rings, every one of them owed items, and
//! one step = one EDF decision (`next_refill`, one item) and one slave's report of one more item
//! consumed (each a heap update). A slave consumes in turn (a stride through all of them), so
//! the backlog stays the same, every slave stays in the heap and the earliest deadline moves
//! from slave to slave: the heap is exercised at its full size.

use regler_ring_transfer::{Master, Report, SlaveParams};

/// Most slaves a bench master holds.
pub const MAX_SLAVES: usize = 512;

/// A master in steady state, and what each slave has consumed and received.
pub struct Scheduler {
    master: Box<Master<MAX_SLAVES>>,
    consumed: Vec<u16>,
    received: Vec<u16>,
    stride: usize,
    next: usize,
    now: u64,
}

fn report(consumed: u16, received: u16) -> Report {
    Report {
        slave: 0,
        consumed,
        received,
        standalone: false,
        retry: false,
        boot: 0,
        hello: false,
    }
}

impl Scheduler {
    /// `n` slaves (1 ≤ n ≤ [`MAX_SLAVES`]), each with its own period and ring, each ring filled
    /// and then half consumed, so each is owed half its ring; `None` if `n` is out of range.
    #[must_use]
    pub fn new(n: usize) -> Option<Scheduler> {
        if n == 0 || n > MAX_SLAVES {
            return None;
        }
        let mut master: Box<Master<MAX_SLAVES>> = Box::default();
        let mut consumed = vec![0u16; n];
        let mut received = vec![0u16; n];
        for i in 0..n {
            let k = u32::try_from(i).ok()?;
            let t0 = 2_000 + (k * 37) % 400;
            let capacity = 64 + u16::try_from((k * 13) % 192).ok()?;
            master.attach(i, SlaveParams { capacity, t0 }).ok()?;
            master.on_report(0, i, &report(0, 0)).ok()?;
        }
        while let Some(grant) = master.next_refill(0, 64) {
            let r = received.get_mut(grant.slave)?;
            *r = r.wrapping_add(u16::try_from(grant.count).ok()?);
        }
        for i in 0..n {
            let (c, r) = (consumed.get_mut(i)?, *received.get(i)?);
            *c = r / 2;
            master.on_report(1, i, &report(*c, r)).ok()?;
        }
        // A stride coprime to n visits every slave, in a mixed order.
        let stride = (n / 3..n).find(|s| gcd(*s, n) == 1).unwrap_or(1);
        Some(Scheduler {
            master,
            consumed,
            received,
            stride,
            next: 0,
            now: 1,
        })
    }

    /// One decision (one item to the slave with the earliest deadline) and one report (the next
    /// slave in turn has consumed one more item). Returns the slave served.
    pub fn step(&mut self) -> usize {
        self.now += 1;
        let served = match self.master.next_refill(self.now, 1) {
            Some(grant) => {
                if let Some(r) = self.received.get_mut(grant.slave) {
                    *r = r.wrapping_add(1);
                }
                grant.slave
            }
            None => usize::MAX,
        };
        let n = self.consumed.len();
        self.next = (self.next + self.stride) % n;
        if let (Some(c), Some(&r)) = (
            self.consumed.get_mut(self.next),
            self.received.get(self.next),
        ) {
            *c = c.wrapping_add(1);
            let _ = self.master.on_report(self.now, self.next, &report(*c, r));
        }
        served
    }
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_step_serves_and_the_earliest_deadline_moves_through_the_slaves() {
        for n in [8, 80, 500] {
            let mut s = Scheduler::new(n).expect("in range");
            let mut served = vec![0u32; n];
            for _ in 0..40 * n {
                let slave = s.step();
                assert!(slave < n, "{n} slaves: a step without a grant");
                served[slave] += 1;
            }
            // Slaves with long rings and slow periods have later deadlines and wait longer; most
            // are served within 40 steps a slave (a degenerate workload served one slave only).
            let distinct = served.iter().filter(|&&k| k > 0).count();
            assert!(
                distinct >= n / 2,
                "{n} slaves, {distinct} served: {served:?}"
            );
        }
        assert!(Scheduler::new(0).is_none());
        assert!(Scheduler::new(MAX_SLAVES + 1).is_none());
    }
}
