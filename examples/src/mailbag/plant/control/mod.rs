//! The control program, level B: a chain of tests on the input image ([`StepChain`]) calling
//! routines — the desks' entries, every code reader, the dock chains, the buffer lanes'
//! emptying, the calendar — with the timer shift register ([`TimerQueue`]) for timed sequences
//! and time supervision, and the teletype's [`Spool`].
//!
//! A switch is set for the passage judged and goes back to its safe position (the manual
//! station) on the timer queue once that trolley has passed; presence inputs, the trolleys
//! routed toward a reader and the lanes' exits toward R9 are supervised (the plant's module
//! docs, "Switches and supervision").
//!
//! Each routine adds its cost in simulated µs to the cycle ([`cost`]): the executive measures
//! the cycle's busy time on that clock, as the source's idle counter measured its load.

#![allow(
    clippy::needless_range_loop,
    reason = "an index names a reader, lane, desk or exit across several arrays"
)]

use std::cell::Cell;
use std::collections::VecDeque;
use std::rc::Rc;

use regler_chain_tracker::{
    DistanceTable, SOURCE_HOLD_PULSES, StretchConfig, StretchMeter, Tracker,
};
use regler_scan_cycle::{
    DateTime, MinuteTable, Scan, Spool, Start, StepChain, TimerId, TimerQueue, Weekdays,
};
use regler_trolley_id::{AlarmLimits, ReaderHealth, Registry, Strategy, Verdict, Voter};

use super::layout::{BINS_PER_DOCK, DESKS, DOCKS, Dest, R_MAIN, READER_NAMES, READERS, chain, io};
use super::operator::{
    BUFFER_LANES, Command, DeskLive, EntryVerdict, Live, POST_TYPES, PanelId, SCHEDULES,
};
use super::traffic::bin_for;

mod calendar;
mod conveyors;
mod readers;

use self::calendar::STATISTICS;
pub use self::calendar::{SCHEDULE_STARTS, schedule_for};

/// Input and output words, for short types.
pub const IW: usize = io::IN_WORDS;
/// Output words.
pub const OW: usize = io::OUT_WORDS;

/// How a reader's scans become a verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reading {
    /// The source: decode the first scan, parity checked.
    ParityOnly,
    /// Majority over the scans (`Voter`, at least 3 with cams).
    Voting,
}

impl Reading {
    /// `parity_only` or `voting`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Reading::ParityOnly => "parity_only",
            Reading::Voting => "voting",
        }
    }
}

/// The cost model, simulated µs per routine on the source's machine (a 1970s minicomputer,
/// about 1 µs per instruction): set so the plant's traffic loads it about as the source said
/// (≈ 30 %).
pub mod cost {
    /// Level A's 50 ms part: read 34 input words, condition them, write 15 output words.
    pub const IO_US: u32 = 6_000;
    /// One test of the chain (a word compared).
    pub const TEST_US: u32 = 60;
    /// One scan of a reader's cams taken into the passage.
    pub const SAMPLE_US: u32 = 250;
    /// A passage's verdict, registry look-up and switch.
    pub const VERDICT_US: u32 = 1_500;
    /// A command from a panel (plausibility, registry).
    pub const COMMAND_US: u32 = 2_000;
    /// A chain pulse through the tracker and the stretch meter.
    pub const PULSE_US: u32 = 300;
    /// A tipper set or reset.
    pub const TIPPER_US: u32 = 200;
    /// The buffer lanes' emptying logic.
    pub const LANES_US: u32 = 1_200;
    /// The timer shift register's tick.
    pub const TIMERS_US: u32 = 400;
    /// The calendar and the minute table, once a minute.
    pub const CALENDAR_US: u32 = 3_000;
    /// Copying the live lists for the displays (every cycle).
    pub const LIVE_US: u32 = 4_000;
}

/// What the timer shift register times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Timer {
    /// A desk's release gate closes.
    CloseRelease(usize),
    /// A trolley routed at a reader should be read at the next one by now.
    Supervise { trolley: u16, next: usize },
    /// An emptying portion did not finish in time.
    PortionTimeout,
    /// A reader's switch goes back to its safe position (no exit set, the reject gate shut:
    /// the manual station) once the trolley it was set for has passed it.
    SafeSwitch(usize),
    /// A buffer lane let a trolley go: R9 should have read one by now.
    ExpectAtR9 { lane: u8 },
}

/// A teletype printout.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Printout(pub String);

/// One desk's entry being read.
#[derive(Clone, Copy, Debug)]
struct Entry {
    dest: Dest,
    scans: u8,
    first: Option<u16>,
    waited: u8,
}

/// Reader alarms: the crate's limits (5 ‰ no-reads, 10 ‰ disagreements) over a full window
/// of 1000 passages, judged from 200 passages on, so one misread among the first hundred raises
/// nothing.
const ALARM_LIMITS: AlarmLimits = AlarmLimits {
    no_read_per_mille: 5,
    disagreement_per_mille: 10,
    min_passages: 200,
};
/// `minute_seen` before the first cycle.
const MINUTE_UNSEEN: u8 = 255;
/// Scans of a standing trolley taken at a desk for one entry.
const DESK_SCANS: u8 = 5;
/// Trolleys per emptying portion.
pub const PORTION: u32 = 5;
/// Time supervision: a trolley must reach the next reader within this (ticks of 50 ms).
const SUPERVISE_TICKS: u32 = 2 * 60 * 20;
/// A switch set at a passage's end holds this long (ticks of 50 ms), then goes back to its safe
/// position: the trolley reaches the switch 1 s after its passage ends
/// ([`timing::SWITCH_MS`](super::layout::timing::SWITCH_MS)), the next trolley's passage ends
/// 2 s after at the earliest ([`timing::HEADWAY_MS`](super::layout::timing::HEADWAY_MS)).
const SWITCH_HOLD_TICKS: u32 = 30;
/// A presence input on for more than this many cycles (1 s) at a rail reader — a passage
/// lasts 250 ms — or on without a trolley's code at a desk's reader is a fault.
const PRESENCE_LIMIT_CYCLES: u32 = 20;

/// A test of the chain and the routine it calls.
type Step = (
    fn(&Scan<'_, IW, OW>) -> bool,
    fn(&mut Scan<'_, IW, OW>, &mut Control),
);

/// The dock chain's tracker: up to 512 trolleys on a chain, 50 tippers.
pub type DockTracker = Tracker<u16, 512, BINS_PER_DOCK>;

/// The control program's state: everything it remembers between cycles.
pub struct Control {
    reading: Reading,
    cost: Rc<Cell<u64>>,
    /// Trolley → destination.
    pub registry: Registry<Dest>,
    voters: [Voter; READERS],
    first: [Option<u16>; READERS],
    in_passage: [bool; READERS],
    /// Reader health.
    pub health: Vec<ReaderHealth<1000>>,
    /// Post type → buffer lane.
    pub type_lane: [u8; POST_TYPES as usize],
    /// Buffer lane → emptying stations.
    pub emptying: [u8; BUFFER_LANES as usize],
    through_r9: [u32; BUFFER_LANES as usize],
    portion: Option<(usize, u32, TimerId)>,
    next_lane: usize,
    /// Trackers.
    pub trackers: Vec<DockTracker>,
    /// Stretch meters.
    pub meters: Vec<StretchMeter>,
    timers: Box<TimerQueue<Timer, 8192>>,
    /// Per trolley: its time supervision's timer and the reader it is expected at.
    supervision: Vec<Option<(TimerId, usize)>>,
    /// Per reader: the timer that puts its switch back to the safe position.
    switch_timer: [Option<TimerId>; READERS],
    /// Per reader: cycles its presence input has been on (at a desk: on without a code).
    presence_on: [u32; READERS],
    /// Per reader: its presence input is faulty (on too long); the alarm is on, the switch safe.
    presence_fault: [bool; READERS],
    /// Per desk: an entry found no trolley at the desk, reported; cleared when one is seen.
    desk_unseen: [bool; DESKS],
    /// Per trolley: the buffer lane R6 or R7 switched it into (taken at R9).
    routed_lane: Vec<Option<u8>>,
    /// The lane-exit supervision timers, oldest first: one per trolley a lane let go, until R9
    /// has a passage.
    to_r9: VecDeque<TimerId>,
    /// The calendar.
    pub calendar: DateTime,
    table: MinuteTable<u8, 16>,
    /// The schedule the calendar chose.
    pub calendar_schedule: u8,
    /// The central desk's override.
    pub schedule_override: Option<u8>,
    /// The teletype's queue.
    pub spool: Spool<Printout, 64>,
    /// Printouts the spool could not take.
    pub spool_overflow: u64,
    /// Commands received from the panels, for the next cycle.
    pub commands: VecDeque<(PanelId, Command)>,
    entries: [Option<Entry>; DESKS],
    /// The destination of the entry accepted at each desk, from the keyed entry alone (not from
    /// the number read): the sack's right destination, which the field loads with it.
    pub accepted: [Option<Dest>; DESKS],
    /// What the displays show.
    pub live: Live,
    /// Entries refused (not plausible, or no trolley read at the desk).
    pub refused: u64,
    /// Trolleys sent to the manual station by each reader.
    pub rejected_by: [u64; READERS],
    /// Time supervision faults.
    pub supervision_faults: u64,
    /// Reader alarms raised.
    pub alarms_raised: u64,
    /// Stretch measurements accepted.
    pub recalibrations: u64,
    /// Reader passages judged.
    pub passages: u64,
    minute_seen: u8,
    /// Sacks loaded this hour per desk (for the displays).
    hour_loaded: [u16; DESKS],
}

impl Control {
    /// The program at start-up, on `calendar`, with the chains' last stored DIA.
    #[must_use]
    pub fn new(
        reading: Reading,
        cost: Rc<Cell<u64>>,
        calendar: DateTime,
        dia: [u32; DOCKS],
    ) -> Control {
        let sa: [u32; BINS_PER_DOCK] =
            std::array::from_fn(|j| chain::bin_sa(j) - chain::LEAD_PULSES);
        let trackers = (0..DOCKS)
            .map(|d| {
                let table = DistanceTable::new(chain::SIA, &sa).expect("commissioned table");
                let mut t = DockTracker::new(table, SOURCE_HOLD_PULSES).expect("tracker");
                t.recalibrate(dia[d]).expect("stored DIA");
                t
            })
            .collect();
        let meters = (0..DOCKS)
            .map(|d| StretchMeter::with_dia(StretchConfig::new(chain::SIA), dia[d]).expect("meter"))
            .collect();
        let mut table = MinuteTable::new();
        for (hour, schedule, days) in SCHEDULE_STARTS {
            let _ = table.add(Start {
                hour,
                minute: 0,
                days,
                program: schedule,
            });
        }
        let _ = table.add(Start {
            hour: 0,
            minute: 0,
            days: Weekdays::ALL,
            program: STATISTICS,
        });
        let calendar_schedule = schedule_for(&calendar);
        Control {
            reading,
            cost,
            registry: Registry::new(),
            voters: std::array::from_fn(|_| {
                Voter::new(Strategy::Majority { min_samples: 3 }).expect("strategy")
            }),
            first: [None; READERS],
            in_passage: [false; READERS],
            health: (0..READERS)
                .map(|_| ReaderHealth::new(ALARM_LIMITS).expect("limits"))
                .collect(),
            type_lane: [0; POST_TYPES as usize],
            emptying: [0; BUFFER_LANES as usize],
            through_r9: [0; BUFFER_LANES as usize],
            portion: None,
            next_lane: 0,
            trackers,
            meters,
            timers: Box::new(TimerQueue::new()),
            supervision: vec![None; 4096],
            switch_timer: [None; READERS],
            presence_on: [0; READERS],
            presence_fault: [false; READERS],
            desk_unseen: [false; DESKS],
            routed_lane: vec![None; 4096],
            to_r9: VecDeque::new(),
            calendar,
            table,
            calendar_schedule,
            schedule_override: None,
            spool: Spool::new(),
            spool_overflow: 0,
            commands: VecDeque::new(),
            entries: [None; DESKS],
            accepted: [None; DESKS],
            live: Live::default(),
            refused: 0,
            rejected_by: [0; READERS],
            supervision_faults: 0,
            alarms_raised: 0,
            recalibrations: 0,
            passages: 0,
            minute_seen: MINUTE_UNSEEN,
            hour_loaded: [0; DESKS],
        }
    }

    fn spend(&self, us: u32) {
        self.cost.set(self.cost.get() + u64::from(us));
    }

    /// Queues a printout for the teletype (a fault report, statistics).
    pub fn print(&mut self, text: String) {
        if self.spool.push(Printout(text)).is_err() {
            self.spool_overflow += 1;
        }
    }

    fn stamp(&self) -> String {
        format!(
            "{:02}:{:02}:{:02}",
            self.calendar.hour(),
            self.calendar.minute(),
            self.calendar.second()
        )
    }

    /// Whether reader `r`'s presence input is reported faulty (its alarm is on).
    #[must_use]
    pub fn presence_fault(&self, r: usize) -> bool {
        self.presence_fault.get(r).copied().unwrap_or(false)
    }

    /// The sorting schedule in force.
    #[must_use]
    pub fn schedule(&self) -> u8 {
        self.schedule_override.unwrap_or(self.calendar_schedule)
    }

    /// The chain of tests, in the order the program runs them.
    #[must_use]
    pub fn chain() -> StepChain<Control, IW, OW, 32> {
        let mut c = StepChain::new();
        let steps: [Step; 17] = [
            (always, Control::housekeeping),
            (always, Control::take_commands),
            (always, Control::desks),
            (always, reader_step::<3>),
            (always, reader_step::<4>),
            (always, reader_step::<5>),
            (always, reader_step::<6>),
            (always, reader_step::<7>),
            (always, reader_step::<8>),
            (always, reader_step::<9>),
            (always, reader_step::<10>),
            (always, reader_step::<11>),
            (chain_test, Control::chains),
            (
                |s| s.inputs.word(io::LANE_EXIT_WORD) != Some(0),
                Control::lane_exits,
            ),
            (always, Control::lanes),
            (always, Control::timers_tick),
            (always, Control::live_lists),
        ];
        for (test, routine) in steps {
            let _ = c.push(test, routine);
        }
        c
    }

    fn housekeeping(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        c.spend(cost::IO_US + 20 * cost::TEST_US);
        let _ = scan.outputs.set(io::DRIVES, true);
        if c.calendar.minute() != c.minute_seen {
            // The first cycle only notes the minute: the schedule in force at the start is set
            // at start-up, and the statistics are printed at a midnight *after* the start.
            let first = c.minute_seen == MINUTE_UNSEEN;
            c.minute_seen = c.calendar.minute();
            if first {
                return;
            }
            c.spend(cost::CALENDAR_US);
            let mut due = Vec::new();
            let now = c.calendar;
            c.table.check(&now, |d| due.push(*d.program));
            for program in due {
                if program == STATISTICS {
                    c.statistics();
                } else {
                    c.calendar_schedule = program;
                }
            }
            if c.calendar.minute() == 0 {
                c.hour_loaded = [0; DESKS];
            }
        }
    }

    fn statistics(&mut self) {
        let text = format!(
            "{} statistics: passages {}, rejects {}, entries refused {}, supervision faults {}",
            self.stamp(),
            self.passages,
            self.rejected_by.iter().sum::<u64>(),
            self.refused,
            self.supervision_faults
        );
        self.print(text);
    }

    fn take_commands(_scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        // At most four commands a cycle: the keyboards' handshake delivers a key per 10 ms,
        // and a burst (the start-up settings) is spread over cycles rather than overrunning one.
        for _ in 0..4 {
            let Some((panel, command)) = c.commands.pop_front() else {
                break;
            };
            c.spend(cost::COMMAND_US);
            c.command(panel, command);
        }
    }

    fn command(&mut self, panel: PanelId, command: Command) {
        match (panel, command) {
            (PanelId::Desk(p), Command::PostType(t)) => {
                let dest = (t < POST_TYPES).then(|| Dest::Lane(self.type_lane[usize::from(t)]));
                self.entry(usize::from(p), dest, u32::from(t));
            }
            (PanelId::Desk(p), Command::Postcode(code)) if p < 2 => {
                let dest = bin_for(self.schedule(), code).map(Dest::Bin);
                self.entry(usize::from(p), dest, code);
            }
            (PanelId::Desk(p), _) => self.entry(usize::from(p), None, 0),
            (PanelId::Central, Command::AssignType { post_type, lane })
                if post_type < POST_TYPES && lane < BUFFER_LANES =>
            {
                self.type_lane[usize::from(post_type)] = lane;
            }
            (PanelId::A | PanelId::B, Command::Emptying { lane, stations })
                if lane < BUFFER_LANES =>
            {
                self.emptying[usize::from(lane)] = stations & 0x7F;
            }
            (PanelId::Central, Command::Schedule(s)) => {
                self.schedule_override = s.filter(|&s| s < SCHEDULES);
            }
            _ => {}
        }
    }

    fn entry(&mut self, p: usize, dest: Option<Dest>, shown: u32) {
        let p = p.min(DESKS - 1);
        self.live.desks[p].last_entry = shown;
        match dest {
            Some(dest) if self.entries[p].is_none() => {
                self.accepted[p] = None;
                self.entries[p] = Some(Entry {
                    dest,
                    scans: 0,
                    first: None,
                    waited: 0,
                });
                self.voters[p].finish();
                self.live.desks[p].verdict = EntryVerdict::None;
            }
            _ => {
                self.refused += 1;
                self.live.desks[p].verdict = EntryVerdict::Refused;
            }
        }
    }

    /// Desks: an entry being read takes its scans of the standing trolley, then the registry
    /// cell is written and the release gate opens for a second.
    fn desks(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        for p in 0..DESKS {
            let raw = scan.inputs.word(p).unwrap_or(0);
            if raw >> io::PRESENT_BIT & 1 == 1 {
                c.desk_unseen[p] = false;
            }
            // The desk's presence input on without a trolley's code: a stuck sensor (or a
            // dead reader).
            if raw >> io::PRESENT_BIT & 1 == 1 && raw & io::CAMS == 0 {
                c.presence_on[p] = c.presence_on[p].saturating_add(1);
                if c.presence_on[p] > PRESENCE_LIMIT_CYCLES && !c.presence_fault[p] {
                    c.set_presence_fault(p, true);
                }
            } else {
                c.presence_on[p] = 0;
                if c.presence_fault[p] {
                    c.set_presence_fault(p, false);
                }
            }
            let Some(mut entry) = c.entries[p] else {
                continue;
            };
            c.spend(cost::SAMPLE_US);
            let raw = scan.inputs.word(p).unwrap_or(0);
            if raw >> io::PRESENT_BIT & 1 == 0 {
                // No trolley seen at the desk yet (its sensor is debounced): wait a second.
                entry.waited += 1;
                if entry.waited > 20 {
                    c.entries[p] = None;
                    c.refused += 1;
                    c.live.desks[p].verdict = EntryVerdict::Refused;
                    if !c.desk_unseen[p] {
                        c.desk_unseen[p] = true;
                        c.supervision_faults += 1;
                        let text = format!(
                            "{} desk P{}: no trolley seen at {} for an entry, refused",
                            c.stamp(),
                            p + 1,
                            READER_NAMES[p]
                        );
                        c.print(text);
                    }
                } else {
                    c.entries[p] = Some(entry);
                }
                continue;
            }
            let cams = raw & io::CAMS;
            c.voters[p].sample(cams);
            entry.first.get_or_insert(cams);
            entry.scans += 1;
            c.entries[p] = Some(entry);
            if entry.scans < DESK_SCANS {
                continue;
            }
            c.entries[p] = None;
            c.spend(cost::VERDICT_US);
            let passage = c.verdict(p, entry.first);
            match passage.verdict {
                Verdict::Identified(id) => {
                    c.registry.assign(id, entry.dest);
                    c.routed_lane[usize::from(id.get())] = None;
                    c.accepted[p] = Some(entry.dest);
                    let _ = scan.outputs.set(io::release(p), true);
                    let _ = c.timers.insert(20, Timer::CloseRelease(p));
                    c.live.desks[p].verdict = EntryVerdict::Accepted;
                    c.hour_loaded[p] = c.hour_loaded[p].saturating_add(1);
                    c.supervise(id, R_MAIN);
                }
                _ => {
                    c.refused += 1;
                    c.live.desks[p].verdict = EntryVerdict::Refused;
                }
            }
        }
    }

    fn timers_tick(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        c.spend(cost::TIMERS_US);
        let mut due = Vec::new();
        c.timers.tick(|t| due.push(t));
        for t in due {
            match t {
                Timer::CloseRelease(p) => {
                    let _ = scan.outputs.set(io::release(p), false);
                }
                Timer::SafeSwitch(r) => {
                    c.switch_timer[r] = None;
                    c.safe_switch(r, scan);
                }
                Timer::ExpectAtR9 { lane } => {
                    c.to_r9.pop_front();
                    c.supervision_faults += 1;
                    let text = format!(
                        "{} trolley from lane {} not seen at R9 in time",
                        c.stamp(),
                        super::operator::lane_name(lane)
                    );
                    c.print(text);
                }
                Timer::Supervise { trolley, next } => {
                    c.supervision[usize::from(trolley)] = None;
                    c.supervision_faults += 1;
                    let text = format!(
                        "{} trolley {trolley} not seen at {} in time",
                        c.stamp(),
                        READER_NAMES[next]
                    );
                    c.print(text);
                }
                Timer::PortionTimeout => {
                    if let Some((lane, _, _)) = c.portion.take() {
                        let _ = scan.outputs.set(io::lane_gate(lane), false);
                    }
                }
            }
        }
    }

    fn live_lists(_scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
        c.spend(cost::LIVE_US);
        c.live.minute_of_day = u16::from(c.calendar.hour()) * 60 + u16::from(c.calendar.minute());
        c.live.type_lane = c.type_lane;
        c.live.emptying = c.emptying;
        c.live.schedule = c.schedule();
        c.live.schedule_override = c.schedule_override.is_some();
        c.live.reader_alarms = (0..READERS)
            .filter(|&r| c.health[r].alarm() || c.presence_fault[r])
            .fold(0, |a, r| a | 1 << r);
        for p in 0..DESKS {
            c.live.desks[p].sacks_this_hour = c.hour_loaded[p];
        }
    }

    /// Updates the displayed trolley-ready lamps and lane/station fills (what the program
    /// knows from its inputs).
    pub fn show_field(&mut self, ready: [bool; DESKS], lanes: &[usize], stations: &[usize]) {
        for p in 0..DESKS {
            self.live.desks[p] = DeskLive {
                trolley_ready: ready[p],
                ..self.live.desks[p]
            };
        }
        for (f, &n) in self.live.lane_fill.iter_mut().zip(lanes) {
            *f = n.min(255) as u8;
        }
        for (f, &n) in self.live.station_fill.iter_mut().zip(stations) {
            *f = n.min(255) as u8;
        }
    }
}

/// The chain's test for steps whose routine tests state of its own (a reader's passage ends
/// when its presence input goes off, so the test is in the routine).
fn always(_scan: &Scan<'_, IW, OW>) -> bool {
    true
}

fn reader_step<const R: usize>(scan: &mut Scan<'_, IW, OW>, c: &mut Control) {
    c.reader(R, scan);
}

fn chain_test(scan: &Scan<'_, IW, OW>) -> bool {
    scan.inputs.word(io::CHAIN_WORD) != Some(0)
}
