//! The master: one link, many slaves, earliest deadline first.

use core::fmt;

use crate::edf::Edf;
use crate::link::{Refill, Report, newer_boot};

/// What the master must know of a slave: its ring size and how fast it consumes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SlaveParams {
    /// Ring slots (1..=32 767: the wrapping 16-bit counters tell old from new within half
    /// their range).
    pub capacity: u16,
    /// Time per item consumed, in the master's time unit (≥ 1).
    pub t0: u32,
}

/// Why the master refused a call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum MasterError {
    /// The index is not below the master's slave capacity `S`.
    UnknownSlave(usize),
    /// No [`Master::attach`] for this slave (or it was detached).
    NotAttached(usize),
    /// A ring of 0 slots, or above 32 767.
    Capacity(u16),
    /// `t0` = 0: a slave that consumes infinitely fast cannot be served.
    ZeroRate,
}

impl fmt::Display for MasterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::UnknownSlave(i) => write!(f, "slave {i} is beyond the master's capacity"),
            Self::NotAttached(i) => write!(f, "slave {i} is not attached"),
            Self::Capacity(c) => write!(f, "ring capacity must be 1..=32767 slots, got {c}"),
            Self::ZeroRate => write!(f, "t0 must be at least 1 time unit per item"),
        }
    }
}

impl core::error::Error for MasterError {}

/// What the master made of a report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReportOutcome {
    /// The newest word from this slave: `owed` items are now owed to it. With nothing owed, answer
    /// with an empty refill (a keep-alive) so a slave running stand-alone knows the master is back.
    Accepted {
        /// Items the slave has room for and the master has not yet sent.
        owed: u32,
    },
    /// Older than, or the same as, a report already seen (a late or repeated message), or a
    /// report of another boot than the current session's, or a hello of an earlier start (the
    /// board before a reboot): ignored. A report ignored for its boot number is answered by a
    /// session offer from [`Master::next_refill`].
    /// A stand-alone report of the current session is stale only if it is older than the
    /// newest: the same counters again ask for a keep-alive and are accepted.
    Stale,
}

/// A decision of the scheduler: send `count` items of `slave`'s stream from index `first`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Grant {
    /// The slave served.
    pub slave: usize,
    /// Stream index (64-bit, never wraps in practice) of the first item; the frame carries its
    /// low 16 bits ([`Grant::first_wire`]).
    pub first: u64,
    /// Items to send: at least 1, except in a **session offer** (0 items, [`Grant::sync`] set,
    /// [`Grant::boot`] the session's): the answer to a report of another boot than the
    /// session's, telling that board which start the master serves (it then says hello, see
    /// [`Master::on_report`]). Send it like any grant: [`Grant::refill`] with no items.
    pub count: u32,
    /// The deadline this grant served (the source's `slack · t0` after the slave's report).
    pub deadline: u64,
    /// `true` when the grant came after its deadline: the slave may underrun. Counted in
    /// [`SlaveStatus::missed`]. Never set while a slave is being filled after attach or after
    /// a hello (it has reported no consumption yet: its machine has not started).
    pub late: bool,
    /// The boot number of the session (the board's, from its reports).
    pub boot: u8,
    /// The board has said hello, has not yet reported from its new place, and this grant
    /// starts where the session starts: the refill must be sent as a sync refill, which places
    /// the board at `first`. (If it is lost, the board says hello again and the master starts
    /// the session again from the same place.) Also set on a session offer (no items), which
    /// never places a board.
    pub sync: bool,
}

impl Grant {
    /// The low 16 bits of `first`, as a refill frame carries them.
    #[must_use]
    pub fn first_wire(&self) -> u16 {
        low16(self.first)
    }

    /// The refill frame for this grant, carrying `items` (the stream's items from `first`),
    /// to the slave at link address `address`.
    #[must_use]
    pub fn refill<'a>(&self, address: u8, items: &'a [u8]) -> Refill<'a> {
        Refill {
            slave: address,
            first: self.first_wire(),
            items,
            boot: self.boot,
            sync: self.sync,
        }
    }
}

/// One slave as the master sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SlaveStatus {
    /// The slave's newest report says it takes the master's stream: it is placed in the
    /// current session (not saying hello) and not stand-alone.
    pub linked: bool,
    /// Items owed now.
    pub owed: u32,
    /// When the next item is due, if any is owed.
    pub deadline: Option<u64>,
    /// Grants made after their deadline.
    pub missed: u32,
    /// The latest of those, by how much.
    pub worst_lateness: u64,
    /// The slave's last report said it runs stand-alone.
    pub standalone: bool,
    /// Reports accepted.
    pub reports: u32,
    /// Reports ignored as late or repeated, or as another start's than the session's.
    pub stale_reports: u32,
    /// Retry reports (the slave waited too long or saw a gap): the master sent again.
    pub retries: u32,
    /// Stream items the slave has consumed (or skipped), as of its last report.
    pub consumed: u64,
    /// Stream items the slave had taken in, as of its last report.
    pub received: u64,
    /// Stream items granted (the next index to send).
    pub sent: u64,
    /// Hellos of a later start than the session's ([`newer_boot`]): the board restarted (a
    /// power cycle, a watchdog) and was placed again where the board before it stopped. A late
    /// hello of an earlier start is not counted.
    pub reboots: u32,
    /// The current session's boot number.
    pub boot: u8,
}

#[derive(Debug, Clone, Copy)]
struct Link {
    params: Option<SlaveParams>,
    status: SlaveStatus,
    report_at: u64,
    /// The consumed count of the first report after attach, or where the session started.
    first_consumed: u64,
    /// A report has been accepted since attach: the counters mean something.
    heard: bool,
    /// The board said hello and has not reported from its place yet: grants are sync grants.
    syncing: bool,
    /// A report of another boot than the session's arrived at this time and has not been
    /// answered yet: the next grant is a session offer.
    offer: Option<u64>,
}

impl Link {
    const DETACHED: Self = Self {
        params: None,
        status: SlaveStatus {
            linked: false,
            owed: 0,
            deadline: None,
            missed: 0,
            worst_lateness: 0,
            standalone: false,
            reports: 0,
            stale_reports: 0,
            retries: 0,
            consumed: 0,
            received: 0,
            sent: 0,
            reboots: 0,
            boot: 0,
        },
        report_at: 0,
        first_consumed: 0,
        heard: false,
        syncing: false,
        offer: None,
    };

    fn owed(&self) -> u32 {
        let Some(params) = self.params else { return 0 };
        let room = self
            .status
            .consumed
            .saturating_add(u64::from(params.capacity));
        u32::try_from(room.saturating_sub(self.status.sent)).unwrap_or(u32::MAX)
    }

    /// The source's rule: the slave holds (or will hold, counting items in flight) `sent −
    /// consumed` items at its last report; the next one is due that many periods after it.
    fn deadline(&self) -> Option<u64> {
        let params = self.params?;
        if !self.heard || self.owed() == 0 {
            return None;
        }
        let ahead = self.status.sent.saturating_sub(self.status.consumed);
        Some(
            self.report_at
                .saturating_add(ahead.saturating_mul(u64::from(params.t0))),
        )
    }
}

fn low16(x: u64) -> u16 {
    let [a, b, ..] = x.to_le_bytes();
    u16::from_le_bytes([a, b])
}

/// Extends a wrapping 16-bit count to 64 bits next to the last known value; `None` if it lies
/// behind it (an older message).
fn extend(known: u64, wire: u16) -> Option<u64> {
    let ahead = wire.wrapping_sub(low16(known));
    (ahead < 0x8000).then(|| known.saturating_add(u64::from(ahead)))
}

/// The master of source 001, generalised: up to `S` slaves on one link, each with its own ring
/// size and rate; [`next_refill`](Self::next_refill) always serves the slave whose ring would
/// run dry first (earliest deadline first) in O(log S), and counts every grant that came late.
///
/// Time is a `u64` in any unit the caller likes (the same unit as each slave's `t0`).
///
/// ```
/// use regler_ring_transfer::{Master, Report, SlaveParams};
///
/// let mut master: Master<8> = Master::new();
/// master.attach(0, SlaveParams { capacity: 256, t0: 2_300 })?; // µs per needle
/// master.attach(1, SlaveParams { capacity: 64, t0: 2_100 })?;
/// let report = |slave: u8, consumed, received| {
///     Report { slave, consumed, received, standalone: false, retry: false, boot: 0, hello: false }
/// };
/// // Both start empty and are filled.
/// for slave in 0..2 {
///     master.on_report(0, slave, &report(slave as u8, 0, 0))?;
/// }
/// while master.next_refill(0, 64).is_some() {}
/// // Ten needles later each has used ten items: the smaller ring runs dry first.
/// master.on_report(23_000, 0, &report(0, 10, 256))?;
/// master.on_report(21_000, 1, &report(1, 10, 64))?;
/// let grant = master.next_refill(21_000, 64); // slave 1 is owed 10 items
/// assert_eq!(grant.map(|g| (g.slave, g.first, g.count)), Some((1, 64, 10)));
/// assert_eq!(grant.map(|g| g.deadline), Some(21_000 + 54 * 2_100)); // 54 items left, 2.1 ms each
/// # Ok::<(), regler_ring_transfer::MasterError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Master<const S: usize> {
    links: [Link; S],
    edf: Edf<S>,
}

impl<const S: usize> Default for Master<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const S: usize> Master<S> {
    /// A master with no slaves attached; `const`, so it can live in a `static`.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            links: [Link::DETACHED; S],
            edf: Edf::new(),
        }
    }

    /// Attaches (or re-attaches) slave `slave`. It is served once its first report arrives,
    /// which sets the master's view of its counters.
    ///
    /// # Errors
    /// [`MasterError::UnknownSlave`] past `S`, [`MasterError::Capacity`] for a ring of 0 or
    /// more than 32 767 slots, [`MasterError::ZeroRate`] for `t0` = 0.
    pub fn attach(&mut self, slave: usize, params: SlaveParams) -> Result<(), MasterError> {
        if params.capacity == 0 || params.capacity > 0x7FFF {
            return Err(MasterError::Capacity(params.capacity));
        }
        if params.t0 == 0 {
            return Err(MasterError::ZeroRate);
        }
        let link = self
            .links
            .get_mut(slave)
            .ok_or(MasterError::UnknownSlave(slave))?;
        *link = Link {
            params: Some(params),
            ..Link::DETACHED
        };
        self.edf.set(slave, None);
        Ok(())
    }

    /// Forgets a slave (it is never served until attached again).
    ///
    /// # Errors
    /// [`MasterError::UnknownSlave`] past `S`.
    pub fn detach(&mut self, slave: usize) -> Result<(), MasterError> {
        let link = self
            .links
            .get_mut(slave)
            .ok_or(MasterError::UnknownSlave(slave))?;
        *link = Link::DETACHED;
        self.edf.set(slave, None);
        Ok(())
    }

    /// Re-initialises a slave's interface (the source's Shift 1–8): its counters are taken
    /// afresh from its next report; statistics start again. The parameters stay.
    ///
    /// # Errors
    /// [`MasterError::UnknownSlave`] or [`MasterError::NotAttached`].
    pub fn reinit(&mut self, slave: usize) -> Result<(), MasterError> {
        let params = self.params(slave)?;
        self.attach(slave, params)
    }

    fn params(&self, slave: usize) -> Result<SlaveParams, MasterError> {
        self.links
            .get(slave)
            .ok_or(MasterError::UnknownSlave(slave))?
            .params
            .ok_or(MasterError::NotAttached(slave))
    }

    /// Takes a slave's report received at `now`. The first report after `attach` (or
    /// [`reinit`](Self::reinit)) sets the counters, `received` read as at most half the 16-bit
    /// range ahead of `consumed` (so a pair straddling the wrap, consumed 65 533 and received 5,
    /// is 8 items held); after that a report counts only if it is of the current session's boot number
    /// and newer than every one before it, so any pattern of lost, repeated and reordered
    /// reports leaves the master owing exactly what the newest report says. A retry report
    /// makes the master send again from the slave's `received` count (a refill was lost); a
    /// slave that skipped items after an underrun moves the master past them. `report.slave`
    /// is not looked at: `slave` says who sent it.
    ///
    /// **A hello** (a board that has just started) starts a new session with its boot number:
    /// the stream resumes at the newest `consumed` count this master holds for the slave (0
    /// after attach) — the items the board before it held in its ring are sent again, nothing
    /// is skipped; repeated are only the items that board consumed after its newest report that
    /// reached the master. Grants are then [`Grant::sync`] until the board reports from its new
    /// place (only the one that starts at the session's first index is a sync grant); a hello
    /// of a later start counts in [`SlaveStatus::reboots`]. A hello of the session's own boot
    /// number (repeated, or the board's answer to an offer) starts the session again at the
    /// newest `consumed` count; a placed board takes only the items it has not yet received.
    ///
    /// **Boot numbers are ordered** ([`newer_boot`](crate::link::newer_boot)): a hello of an
    /// earlier start than the session's — a late or repeated frame of a board that has since
    /// restarted — is ignored like any report of another boot, so no frame of an earlier start
    /// ever moves the session or is counted as a reboot. Every report ignored for its boot
    /// number is answered: the next [`next_refill`](Self::next_refill) for this slave is a
    /// **session offer** (a sync refill of no items with the session's boot number). A live
    /// board that gets one says hello again (and, if the offer names a later start than its
    /// own, takes the number after it), so a board the master does not serve — because the
    /// master took an earlier start for the session after [`reinit`](Self::reinit), or the
    /// board's boot number went back — is placed again within two round trips of its next
    /// report.
    ///
    /// # Errors
    /// [`MasterError::UnknownSlave`] or [`MasterError::NotAttached`].
    pub fn on_report(
        &mut self,
        now: u64,
        slave: usize,
        report: &Report,
    ) -> Result<ReportOutcome, MasterError> {
        self.params(slave)?;
        let link = self
            .links
            .get_mut(slave)
            .ok_or(MasterError::UnknownSlave(slave))?;
        let status = &mut link.status;
        let other_boot = link.heard && report.boot != status.boot;
        if other_boot && !(report.hello && newer_boot(report.boot, status.boot)) {
            // A report of another start than the session's, or a hello of an earlier start (a
            // late or repeated frame of a board that has since restarted): ignored, so it never
            // moves the session. Its sender learns which start the master serves: if it is a
            // live board (the master took an earlier start for the session, or the board's
            // boot number went back), it says hello again.
            status.stale_reports = status.stale_reports.saturating_add(1);
            link.offer = Some(now);
            self.refresh(slave);
            return Ok(ReportOutcome::Stale);
        }
        if report.hello {
            if other_boot {
                status.reboots = status.reboots.saturating_add(1);
            }
            link.heard = true;
            link.syncing = true;
            status.boot = report.boot;
            status.linked = false;
            status.standalone = report.standalone;
            status.received = status.consumed;
            status.sent = status.consumed;
            link.first_consumed = status.consumed;
            status.reports = status.reports.saturating_add(1);
            link.report_at = now;
            let owed = link.owed();
            self.refresh(slave);
            return Ok(ReportOutcome::Accepted { owed });
        }
        if link.heard {
            let (Some(consumed), Some(received)) = (
                extend(status.consumed, report.consumed),
                extend(status.received, report.received),
            ) else {
                status.stale_reports = status.stale_reports.saturating_add(1);
                return Ok(ReportOutcome::Stale);
            };
            let unchanged = consumed == status.consumed && received == status.received;
            if unchanged && !report.retry && !report.standalone {
                status.stale_reports = status.stale_reports.saturating_add(1);
                return Ok(ReportOutcome::Stale);
            }
            status.consumed = consumed;
            status.received = received;
        } else {
            link.heard = true;
            status.boot = report.boot;
            let consumed = u64::from(report.consumed);
            link.first_consumed = consumed;
            status.consumed = consumed;
            // Received is read next to consumed (a slave holds 0..=N items, N < 2^15, so it is
            // never behind): read on its own, a pair straddling the wrap (consumed 65 533,
            // received 5) put received 65 536 behind, and the master owed 65 536 items for good.
            // A pair no slave sends (received behind consumed) counts as an empty ring.
            status.received = extend(consumed, report.received).unwrap_or(consumed);
            status.sent = status.received;
        }
        if report.retry {
            status.retries = status.retries.saturating_add(1);
            status.sent = status.received;
        }
        // Items the slave took or used that the master's count had not reached (skipped after
        // an underrun, or a master restarted behind its slave): never send them again. No slave
        // reports more used than taken; a frame that does (corrupt, yet past the CRC) is held to
        // the same rule, so the master never owes more than the ring holds.
        status.sent = status.sent.max(status.received).max(status.consumed);
        status.standalone = report.standalone;
        link.syncing = false;
        status.linked = !report.standalone;
        status.reports = status.reports.saturating_add(1);
        link.report_at = now;
        let owed = link.owed();
        self.refresh(slave);
        Ok(ReportOutcome::Accepted { owed })
    }

    fn refresh(&mut self, slave: usize) {
        let Some(link) = self.links.get_mut(slave) else {
            return;
        };
        let deadline = link.deadline();
        link.status.owed = link.owed();
        link.status.deadline = deadline;
        let key = match (deadline, link.offer) {
            (None, None) => None,
            (deadline, offer) => Some(deadline.unwrap_or(u64::MAX).min(offer.unwrap_or(u64::MAX))),
        };
        self.edf.set(slave, key);
    }

    /// The scheduler's decision at `now`: the slave with the earliest deadline that is owed
    /// anything gets up to `max` items (at least 1). `None` when nothing is owed. O(log S).
    /// Pass `max` = 1 for strict EDF item by item; a larger batch saves frames when the link's
    /// cost is per frame.
    pub fn next_refill(&mut self, now: u64, max: u32) -> Option<Grant> {
        let (slave, deadline) = self.edf.earliest()?;
        let link = self.links.get_mut(slave)?;
        if link.offer.take().is_some() {
            let grant = Grant {
                slave,
                first: link.status.sent,
                count: 0,
                deadline,
                late: false,
                boot: link.status.boot,
                sync: true,
            };
            self.refresh(slave);
            return Some(grant);
        }
        let count = link.owed().min(max.max(1));
        if count == 0 {
            return None;
        }
        // A slave that has consumed nothing since it was attached is being filled: its machine
        // has not started, so its grants cannot be late.
        let late = now > deadline && link.status.consumed != link.first_consumed;
        if late {
            link.status.missed = link.status.missed.saturating_add(1);
            link.status.worst_lateness =
                link.status.worst_lateness.max(now.saturating_sub(deadline));
        }
        let first = link.status.sent;
        link.status.sent = first.saturating_add(u64::from(count));
        // Only the grant that starts at the session's first index places the board: a later one
        // taken as a sync (its predecessor lost) would skip the items between.
        let sync = link.syncing && first == link.first_consumed;
        let boot = link.status.boot;
        self.refresh(slave);
        Some(Grant {
            slave,
            first,
            count,
            deadline,
            late,
            boot,
            sync,
        })
    }

    /// The earliest deadline of any slave, and whose it is.
    #[must_use]
    pub fn earliest(&self) -> Option<(usize, u64)> {
        self.edf.earliest()
    }

    /// One slave's state and statistics.
    ///
    /// # Errors
    /// [`MasterError::UnknownSlave`] or [`MasterError::NotAttached`].
    pub fn status(&self, slave: usize) -> Result<SlaveStatus, MasterError> {
        self.params(slave)?;
        self.links
            .get(slave)
            .map(|l| l.status)
            .ok_or(MasterError::UnknownSlave(slave))
    }

    /// Slaves attached.
    #[must_use]
    pub fn attached(&self) -> usize {
        self.links.iter().filter(|l| l.params.is_some()).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_first_report_straddling_the_counters_wrap_owes_only_the_free_slots() {
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 8,
                t0: 10,
            },
        )
        .unwrap();
        // 8 items held: consumed 65 533, received 65 541 = 5 on the wire.
        let report = Report {
            slave: 0,
            consumed: 65_533,
            received: 5,
            standalone: false,
            retry: false,
            boot: 0,
            hello: false,
        };
        assert_eq!(
            m.on_report(0, 0, &report),
            Ok(ReportOutcome::Accepted { owed: 0 })
        );
        assert_eq!(m.next_refill(0, 64), None);
        // Three consumed (wire 0): three owed, from index 65 541 (wire 5).
        let report = Report {
            consumed: 0,
            ..report
        };
        assert_eq!(
            m.on_report(1, 0, &report),
            Ok(ReportOutcome::Accepted { owed: 3 })
        );
        let grant = m.next_refill(1, 64).unwrap();
        assert_eq!(
            (grant.first, grant.first_wire(), grant.count),
            (65_541, 5, 3)
        );
        // A pair no slave sends (received behind consumed) counts as an empty ring.
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 8,
                t0: 10,
            },
        )
        .unwrap();
        let odd = Report {
            consumed: 100,
            received: 90,
            ..report
        };
        assert_eq!(
            m.on_report(0, 0, &odd),
            Ok(ReportOutcome::Accepted { owed: 8 })
        );
        assert_eq!(m.next_refill(0, 64).map(|g| g.first), Some(100));
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

    #[test]
    fn parameters_are_checked() {
        let mut m: Master<2> = Master::new();
        assert_eq!(
            m.attach(2, SlaveParams { capacity: 4, t0: 1 }),
            Err(MasterError::UnknownSlave(2))
        );
        assert_eq!(
            m.attach(0, SlaveParams { capacity: 0, t0: 1 }),
            Err(MasterError::Capacity(0))
        );
        assert_eq!(
            m.attach(
                0,
                SlaveParams {
                    capacity: 0x8000,
                    t0: 1
                }
            ),
            Err(MasterError::Capacity(0x8000))
        );
        assert_eq!(
            m.attach(0, SlaveParams { capacity: 4, t0: 0 }),
            Err(MasterError::ZeroRate)
        );
        assert_eq!(
            m.on_report(0, 1, &report(0, 0)),
            Err(MasterError::NotAttached(1))
        );
        assert_eq!(m.next_refill(0, 1), None);
    }

    #[test]
    fn owed_follows_the_newest_report_only() {
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 4,
                t0: 10,
            },
        )
        .unwrap();
        assert_eq!(
            m.on_report(0, 0, &report(0, 0)),
            Ok(ReportOutcome::Accepted { owed: 4 })
        );
        let g = m.next_refill(0, 8).unwrap();
        assert_eq!((g.first, g.count, g.deadline, g.late), (0, 4, 0, false));
        assert_eq!(m.next_refill(0, 8), None);
        // The slave took all four and used two.
        assert_eq!(
            m.on_report(5, 0, &report(2, 4)),
            Ok(ReportOutcome::Accepted { owed: 2 })
        );
        // A late copy of an older report changes nothing.
        assert_eq!(m.on_report(6, 0, &report(1, 4)), Ok(ReportOutcome::Stale));
        assert_eq!(m.on_report(6, 0, &report(2, 4)), Ok(ReportOutcome::Stale));
        let s = m.status(0).unwrap();
        assert_eq!(
            (s.owed, s.deadline, s.stale_reports),
            (2, Some(5 + 2 * 10), 2)
        );
    }

    /// Found by the fuzz target `ring-transfer/fuzz/fuzz_targets/decode.rs`: a report whose
    /// consumed count ran ahead of its received count made the master owe more than the ring
    /// holds and send again items the slave had used.
    #[test]
    fn a_report_using_more_than_it_took_never_makes_the_master_owe_more_than_the_ring() {
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 4,
                t0: 10,
            },
        )
        .unwrap();
        // First report after attach, and a later one: consumed ahead of received.
        for (consumed, received) in [(10, 4), (30, 12)] {
            assert_eq!(
                m.on_report(0, 0, &report(consumed, received)),
                Ok(ReportOutcome::Accepted { owed: 4 })
            );
            let g = m.next_refill(0, 8).unwrap();
            assert_eq!((g.first, g.count), (u64::from(consumed), 4));
            assert_eq!(m.status(0).unwrap().owed, 0);
        }
    }

    #[test]
    fn a_retry_sends_again_from_received() {
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 4,
                t0: 10,
            },
        )
        .unwrap();
        m.on_report(0, 0, &report(0, 0)).unwrap();
        // Filling before the machine starts is never late.
        assert!(!m.next_refill(1_000, 4).unwrap().late);
        m.on_report(1_010, 0, &report(2, 4)).unwrap();
        let lost = m.next_refill(1_010, 4).unwrap();
        assert_eq!((lost.first, lost.count), (4, 2));
        let retry = Report {
            retry: true,
            ..report(2, 4)
        };
        assert_eq!(
            m.on_report(1_050, 0, &retry),
            Ok(ReportOutcome::Accepted { owed: 2 })
        );
        let g = m.next_refill(1_071, 4).unwrap();
        assert_eq!((g.first, g.count), (4, 2));
        assert!(g.late, "due at 1 050 + 2·t0 = 1 070, served at 1 071");
        assert_eq!(m.status(0).unwrap().missed, 1);
    }

    #[test]
    fn counters_wrap() {
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 100,
                t0: 1,
            },
        )
        .unwrap();
        m.on_report(0, 0, &report(65_500, 65_500)).unwrap();
        m.next_refill(0, 100).unwrap();
        assert_eq!(
            m.on_report(1, 0, &report(64, 64)),
            Ok(ReportOutcome::Accepted { owed: 100 })
        );
        assert_eq!(m.status(0).unwrap().consumed, 65_600);
    }

    #[test]
    fn a_slave_that_skipped_moves_the_master_on() {
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity: 4, t0: 1 }).unwrap();
        m.on_report(0, 0, &report(0, 0)).unwrap();
        // Nothing sent; the slave underran three times and skipped three items.
        assert_eq!(
            m.on_report(3, 0, &report(3, 3)),
            Ok(ReportOutcome::Accepted { owed: 4 })
        );
        assert_eq!(m.next_refill(3, 4).unwrap().first, 3);
    }

    #[test]
    fn a_stand_alone_report_of_the_session_is_never_stale() {
        // Any counters (near the half range and the wrap too), the same stand-alone report any
        // number of times: accepted every time; an older one is stale.
        for start in [0u16, 100, 32_767, 32_768, 65_535] {
            let mut m: Master<1> = Master::new();
            m.attach(0, SlaveParams { capacity: 8, t0: 1 }).unwrap();
            m.on_report(0, 0, &report(start, start)).unwrap();
            let alone = Report {
                standalone: true,
                ..report(start.wrapping_add(5), start.wrapping_add(8))
            };
            for now in 1..5 {
                assert_eq!(
                    m.on_report(now, 0, &alone),
                    Ok(ReportOutcome::Accepted { owed: 5 }),
                    "start {start}"
                );
            }
            let older = Report {
                standalone: true,
                ..report(start.wrapping_add(4), start.wrapping_add(8))
            };
            assert_eq!(m.on_report(6, 0, &older), Ok(ReportOutcome::Stale));
            let s = m.status(0).unwrap();
            assert!(
                s.standalone && !s.linked,
                "a stand-alone slave is not linked"
            );
        }
    }

    #[test]
    fn a_grant_on_its_deadline_is_on_time_and_only_a_hellos_first_grant_syncs() {
        let mut m: Master<1> = Master::new();
        m.attach(
            0,
            SlaveParams {
                capacity: 4,
                t0: 10,
            },
        )
        .unwrap();
        // A first report of an empty ring: the grant starts where the board is, but the board
        // said no hello, so it is a plain refill, not a sync.
        m.on_report(0, 0, &report(0, 0)).unwrap();
        let g = m.next_refill(0, 4).unwrap();
        assert_eq!((g.first, g.count, g.sync, g.late), (0, 4, false, false));
        // Running: one item consumed, one owed. Served exactly at its deadline: on time.
        m.on_report(100, 0, &report(1, 4)).unwrap();
        let (_, deadline) = m.earliest().unwrap();
        let g = m.next_refill(deadline, 1).unwrap();
        assert_eq!(
            (g.count, g.deadline, g.late, g.sync),
            (1, deadline, false, false)
        );
        assert_eq!(m.status(0).unwrap().missed, 0);
        // One step after its deadline: late, and counted.
        m.on_report(200, 0, &report(2, 5)).unwrap();
        let (_, deadline) = m.earliest().unwrap();
        let g = m.next_refill(deadline + 1, 1).unwrap();
        assert_eq!((g.count, g.late), (1, true));
        assert_eq!(m.status(0).unwrap().missed, 1);
        assert_eq!(m.status(0).unwrap().worst_lateness, 1);
    }

    #[test]
    fn a_hello_starts_a_session_where_the_board_before_stopped() {
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity: 8, t0: 1 }).unwrap();
        // The board ran 40 000 items (past half the counter range) and reported them.
        let mut at = 0u64;
        while at < 40_000 {
            at += 10_000;
            m.on_report(0, 0, &report(at as u16, at as u16)).unwrap();
        }
        // Everything owed is granted in a few grants (a master that kept granting fails here).
        let grants = (0..100)
            .take_while(|_| m.next_refill(0, 64).is_some())
            .count();
        assert!(grants < 100, "the master never stopped granting");
        assert!(m.status(0).unwrap().linked);
        let hello = Report {
            boot: 1,
            hello: true,
            standalone: true,
            ..report(0, 0)
        };
        assert_eq!(
            m.on_report(1, 0, &hello),
            Ok(ReportOutcome::Accepted { owed: 8 })
        );
        let s = m.status(0).unwrap();
        assert_eq!((s.reboots, s.boot, s.linked), (1, 1, false));
        let g = m.next_refill(1, 3).unwrap();
        assert_eq!(
            (g.first, g.count, g.sync, g.boot, g.late),
            (40_000, 3, true, 1, false)
        );
        let g = m.next_refill(1, 3).unwrap();
        assert_eq!(
            (g.first, g.sync),
            (40_003, false),
            "only the first grant places the board"
        );
        // A late report of the board before the reboot is ignored, so is a late hello's copy
        // counted once.
        assert_eq!(
            m.on_report(2, 0, &report(40_005, 40_008)),
            Ok(ReportOutcome::Stale)
        );
        m.on_report(2, 0, &hello).unwrap();
        assert_eq!(m.status(0).unwrap().reboots, 1);
        // The board reports from its place: linked.
        let placed = Report {
            boot: 1,
            ..report(40_001, 40_003)
        };
        assert_eq!(
            m.on_report(3, 0, &placed),
            Ok(ReportOutcome::Accepted { owed: 6 })
        );
        let s = m.status(0).unwrap();
        assert!(s.linked);
        assert_eq!(s.consumed, 40_001);
    }

    /// Every pair (session boot, hello boot): a hello of a later start (1..=127 ahead, wrapping)
    /// starts a session and counts a reboot; the session's own starts it again without
    /// counting; any other (an earlier start) is ignored, moves nothing and is answered by one
    /// session offer (no items, sync, the session's boot) before any grant.
    #[test]
    #[cfg_attr(
        miri,
        ignore = "exhaustive: 65 536 session and boot pairs: hours under Miri; safe code, run natively in every CI run"
    )]
    fn hellos_of_earlier_starts_are_ignored_and_answered_with_an_offer() {
        for session in 0..=255u8 {
            for boot in 0..=255u8 {
                let mut m: Master<1> = Master::new();
                m.attach(0, SlaveParams { capacity: 8, t0: 1 }).unwrap();
                let running = Report {
                    boot: session,
                    ..report(1_000, 1_000)
                };
                m.on_report(0, 0, &running).unwrap();
                while m.next_refill(0, 64).is_some() {}
                m.on_report(
                    1,
                    0,
                    &Report {
                        boot: session,
                        ..report(1_004, 1_008)
                    },
                )
                .unwrap();
                let hello = Report {
                    boot,
                    hello: true,
                    standalone: true,
                    ..report(0, 0)
                };
                let outcome = m.on_report(2, 0, &hello).unwrap();
                let s = m.status(0).unwrap();
                let ahead = boot.wrapping_sub(session);
                let g = m.next_refill(2, 64).unwrap();
                if ahead == 0 || ahead < 128 {
                    assert_eq!(outcome, ReportOutcome::Accepted { owed: 8 });
                    assert_eq!((s.boot, s.reboots), (boot, u32::from(ahead != 0)));
                    assert_eq!((g.first, g.count, g.sync, g.boot), (1_004, 8, true, boot));
                } else {
                    assert_eq!(outcome, ReportOutcome::Stale, "{session} {boot}");
                    assert_eq!(
                        (s.boot, s.reboots, s.consumed, s.sent),
                        (session, 0, 1_004, 1_008)
                    );
                    assert_eq!((g.count, g.sync, g.boot, g.late), (0, true, session, false));
                    let g = m.next_refill(2, 64).unwrap();
                    assert_eq!((g.first, g.count, g.sync), (1_008, 4, false));
                }
            }
        }
    }

    #[test]
    fn a_report_of_another_boot_is_answered_with_an_offer() {
        let mut m: Master<1> = Master::new();
        m.attach(0, SlaveParams { capacity: 4, t0: 1 }).unwrap();
        m.on_report(
            0,
            0,
            &Report {
                boot: 5,
                ..report(0, 0)
            },
        )
        .unwrap();
        while m.next_refill(0, 64).is_some() {}
        for boot in [4, 6, 200] {
            assert_eq!(
                m.on_report(
                    1,
                    0,
                    &Report {
                        boot,
                        ..report(2, 4)
                    }
                ),
                Ok(ReportOutcome::Stale)
            );
            let g = m.next_refill(1, 64).unwrap();
            assert_eq!((g.count, g.sync, g.boot), (0, true, 5));
            assert_eq!(m.next_refill(1, 64), None, "one offer per report");
        }
        assert_eq!(m.status(0).unwrap().stale_reports, 3);
    }
}
