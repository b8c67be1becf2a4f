//! The field: trolleys, rails, readers' cams, switches, lanes, stations and dock chains, as
//! the control program's I/O sees them. Event-driven: a trolley costs work only when it reaches
//! a place; the loop calls [`Field::advance`] every 10 ms of plant time and the executive reads
//! and writes it through [`Io`](regler_scan_cycle::Io) (`field/inputs.rs`) every 50 ms.

#![allow(
    clippy::needless_range_loop,
    reason = "an index names a reader, lane, desk or exit across several arrays"
)]

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap, VecDeque};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_trolley_id::{TrolleyId, encode};

use super::layout::{
    BINS_PER_DOCK, DESKS, DOCKS, Dest, EXITS, Next, R_CHAIN, R_EMPTYING, R_MAIN, READERS, capacity,
    chain, io, next, timing,
};
use super::operator::{BUFFER_LANES, EMPTYING_STATIONS};
use crate::mailbag::DISTURBED_SHARE;

/// How a sack ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// At its right destination.
    Delivered,
    /// At another destination.
    Misdelivered,
    /// At the manual station.
    Rejected,
}

/// Where a sack ended, for the tallies and the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// A buffer lane (a wrong lane: the sack is misdelivered when emptied).
    Station(u8),
    /// A bin.
    Bin(u8),
    /// The manual station, sent there by reader `r` (or `READERS` for a chain's end).
    Manual(usize),
}

/// A sack on a trolley.
#[derive(Clone, Copy, Debug)]
struct Sack {
    right: Dest,
    /// The buffer lane it was put in (unsorted post).
    lane: Option<u8>,
    /// At R9: whether the station it was switched to is one of its right lane's stations as
    /// panels A and B had them then.
    station_ok: bool,
}

mod dock_chain;
mod inputs;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Event {
    AtReader { reader: usize, trolley: u16 },
    PassageEnd { reader: usize },
    AtSwitch { reader: usize, trolley: u16 },
    IntoLane { lane: u8, trolley: u16 },
    AtStation { station: u8, trolley: u16 },
    StationDone { station: u8 },
    AtManual { trolley: u16, from: usize },
    Returned { trolley: u16 },
    GateRelease { lane: u8 },
}

/// Faults the field carries (the program's own faults are in `run.rs`).
#[derive(Clone, Debug, Default)]
pub struct FieldFaults {
    /// Single-scan misread rate per reader.
    pub misread: [f64; READERS],
    /// Readers that read nothing.
    pub dead: [bool; READERS],
    /// Inputs stuck at a value.
    pub stuck: Vec<(usize, bool)>,
    /// Inputs that chatter (toggle at every read).
    pub chatter: Vec<usize>,
    /// Chance that a chain's pulse initiator misses a pulse.
    pub missed_pulse: [f64; DOCKS],
}

/// What the field counted.
#[derive(Clone, Debug, Default)]
pub struct FieldCounts {
    /// Sacks loaded per desk.
    pub loaded: [u64; DESKS],
    /// Delivered, misdelivered, rejected.
    pub delivered: u64,
    /// Misdelivered.
    pub misdelivered: u64,
    /// Rejected.
    pub rejected: u64,
    /// Sacks that ended at each place (lanes/stations index, bins, manual per reader).
    pub ended: Vec<(Place, Outcome)>,
    /// Trolleys along each reader's exits (`[reader][exit]`, exit 15 the reject gate).
    pub passed: [[u64; 16]; READERS],
    /// Sacks delivered per destination class: lanes' stations, bins.
    pub delivered_letters: u64,
    /// Parcels delivered at B and C.
    pub delivered_parcels: u64,
    /// Sorted sacks tipped into their bin.
    pub delivered_sorted: u64,
    /// Trolleys let out of each buffer lane.
    pub lane_out: [u64; BUFFER_LANES as usize],
}

struct Dock {
    /// Real chain pulses so far.
    pulses: u64,
    /// Plant time of the next pulse.
    next_ms: u64,
    /// Trolleys on the chain by the pulse count at which they were hooked.
    on_chain: BTreeMap<u64, u16>,
    /// Each bin's tipper, pulses from the reader, on the chain as it is now.
    bin_at: [u64; BINS_PER_DOCK],
    /// DIA of the chain as it is now.
    dia: u64,
}

/// The simulated plant.
pub struct Field {
    rng: ChaCha8Rng,
    /// Plant time, ms (stands still while the drives are off or the power is off).
    pub now_ms: u64,
    seq: u64,
    events: BinaryHeap<Reverse<(u64, u64, Event)>>,
    sacks: Vec<Option<Sack>>,
    occupant: [Option<(u16, bool)>; READERS],
    reader_free_ms: [u64; READERS],
    desk_queue: [VecDeque<u16>; DESKS],
    desk_ready_ms: [u64; DESKS],
    lanes: [VecDeque<u16>; BUFFER_LANES as usize],
    gate_busy: [bool; BUFFER_LANES as usize],
    stations: [VecDeque<u16>; EMPTYING_STATIONS as usize],
    station_busy: [bool; EMPTYING_STATIONS as usize],
    docks: [Dock; DOCKS],
    outputs: [u16; io::OUT_WORDS],
    latched: [u16; io::IN_WORDS],
    chatter_phase: bool,
    /// Plant clock in µs for the executive, plus the program's modelled cost this cycle.
    pub clock_us: u64,
    /// The faults in force.
    pub faults: FieldFaults,
    /// What it counted.
    pub counts: FieldCounts,
    /// The emptying stations of each lane, as the computer has them (the right stations).
    pub emptying: [u8; BUFFER_LANES as usize],
    /// Watchdog kicks seen.
    pub kicks: u64,
    /// The program's modelled cost so far in this cycle, µs (added to the clock).
    pub cost: std::rc::Rc<std::cell::Cell<u64>>,
}

impl Field {
    /// A plant with `trolleys` empties spread over the desks; the chains stretched by
    /// `stretch_per_mille` since commissioning.
    #[must_use]
    pub fn new(
        seed: u64,
        trolleys: u16,
        stretch_per_mille: f64,
        misread: f64,
        spread: f64,
    ) -> Field {
        let dia = (f64::from(chain::SIA) * (1.0 - stretch_per_mille / 1000.0)).round() as u64;
        let dock = |d: usize| Dock {
            pulses: 0,
            next_ms: timing::PULSE_MS + d as u64 * 61,
            on_chain: BTreeMap::new(),
            bin_at: std::array::from_fn(|j| {
                (f64::from(chain::bin_sa(j)) * dia as f64 / f64::from(chain::SIA)).round() as u64
            }),
            dia,
        };
        let mut faults = FieldFaults::default();
        for (r, rate) in faults.misread.iter_mut().enumerate() {
            let position = 2.0 * r as f64 / (READERS - 1) as f64 - 1.0;
            *rate = misread * (1.0 + spread * position);
        }
        let mut desk_queue: [VecDeque<u16>; DESKS] = Default::default();
        for t in 1..=trolleys {
            desk_queue[usize::from(t) % DESKS].push_back(t);
        }
        Field {
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0xF1E1D),
            now_ms: 0,
            seq: 0,
            events: BinaryHeap::new(),
            sacks: vec![None; usize::from(trolleys) + 1],
            occupant: [None; READERS],
            reader_free_ms: [0; READERS],
            desk_queue,
            desk_ready_ms: [0; DESKS],
            lanes: Default::default(),
            gate_busy: [false; BUFFER_LANES as usize],
            stations: Default::default(),
            station_busy: [false; EMPTYING_STATIONS as usize],
            docks: std::array::from_fn(dock),
            outputs: [0; io::OUT_WORDS],
            latched: [0; io::IN_WORDS],
            chatter_phase: false,
            clock_us: 0,
            faults,
            counts: FieldCounts::default(),
            emptying: [0; BUFFER_LANES as usize],
            kicks: 0,
            cost: std::rc::Rc::default(),
        }
    }

    /// The DIA of dock `d`'s chain as it is now (what a perfect meter would measure).
    #[must_use]
    pub fn chain_dia(&self, d: usize) -> u32 {
        self.docks[d].dia as u32
    }

    fn at(&mut self, ms: u64, event: Event) {
        self.seq += 1;
        self.events.push(Reverse((ms, self.seq, event)));
    }

    fn output(&self, point: usize) -> bool {
        self.outputs[point / 16] >> (point % 16) & 1 == 1
    }

    /// Whether the drives run (output 0): the plant moves only then.
    #[must_use]
    pub fn drives_on(&self) -> bool {
        self.output(io::DRIVES)
    }

    /// A trolley waits at desk `p`, ready to take a sack.
    #[must_use]
    pub fn desk_ready(&self, p: usize) -> bool {
        !self.desk_queue[p].is_empty() && self.desk_ready_ms[p] <= self.now_ms
    }

    /// Desk `p`'s release gate is open.
    #[must_use]
    pub fn release_open(&self, p: usize) -> bool {
        self.output(io::release(p))
    }

    /// The operator at desk `p` puts a sack for `right` on the waiting trolley and it leaves
    /// (the release gate is open).
    pub fn load(&mut self, p: usize, right: Dest) {
        let Some(t) = self.desk_queue[p].pop_front() else {
            return;
        };
        self.sacks[usize::from(t)] = Some(Sack {
            right,
            lane: None,
            station_ok: false,
        });
        self.counts.loaded[p] += 1;
        self.desk_ready_ms[p] = self.now_ms + timing::DESK_MS;
        self.occupant[p] = None;
        self.at(
            self.now_ms + timing::RAIL_MS,
            Event::AtReader {
                reader: R_MAIN,
                trolley: t,
            },
        );
    }

    /// Sacks in the plant, counted place by place (not from the tallies).
    #[must_use]
    pub fn sacks_in_plant(&self) -> u64 {
        self.sacks.iter().filter(|s| s.is_some()).count() as u64
    }

    /// Trolleys waiting in each lane and at each station.
    #[must_use]
    pub fn fills(
        &self,
    ) -> (
        [usize; BUFFER_LANES as usize],
        [usize; EMPTYING_STATIONS as usize],
    ) {
        (
            std::array::from_fn(|l| self.lanes[l].len()),
            std::array::from_fn(|s| self.stations[s].len()),
        )
    }

    fn end(&mut self, trolley: u16, place: Place, outcome: Outcome) {
        self.sacks[usize::from(trolley)] = None;
        match outcome {
            Outcome::Delivered => self.counts.delivered += 1,
            Outcome::Misdelivered => self.counts.misdelivered += 1,
            Outcome::Rejected => self.counts.rejected += 1,
        }
        self.counts.ended.push((place, outcome));
    }

    /// 10 ms of plant time: events due, chain pulses. Does nothing while the drives are off.
    pub fn advance(&mut self, capture: &mut [u16; io::IN_WORDS]) {
        if !self.drives_on() {
            return;
        }
        self.now_ms += 10;
        while let Some(Reverse((ms, _, event))) = self.events.peek().copied() {
            if ms > self.now_ms {
                break;
            }
            self.events.pop();
            self.handle(event);
        }
        for d in 0..DOCKS {
            while self.docks[d].next_ms <= self.now_ms {
                self.docks[d].next_ms += timing::PULSE_MS;
                self.pulse(d, capture);
            }
        }
        for p in 0..DESKS {
            if self.desk_ready(p) {
                if self.occupant[p].is_none() {
                    let t = self.desk_queue[p][0];
                    let swinging = self.swinging(p);
                    self.occupant[p] = Some((t, swinging));
                }
            } else {
                self.occupant[p] = None;
            }
        }
    }

    fn swinging(&mut self, reader: usize) -> bool {
        let rate = self.faults.misread[reader];
        rate > 0.0 && self.rng.random_bool((rate / DISTURBED_SHARE).min(1.0))
    }

    fn handle(&mut self, event: Event) {
        let now = self.now_ms;
        match event {
            Event::AtReader { reader, trolley } => {
                let free = self.reader_free_ms[reader];
                if free > now || self.occupant[reader].is_some() {
                    self.at(free.max(now + 10), event);
                    return;
                }
                self.reader_free_ms[reader] = now + timing::HEADWAY_MS;
                let swinging = self.swinging(reader);
                self.occupant[reader] = Some((trolley, swinging));
                self.at(now + timing::PASSAGE_MS, Event::PassageEnd { reader });
            }
            Event::PassageEnd { reader } => {
                if let Some((trolley, _)) = self.occupant[reader].take() {
                    if reader >= R_CHAIN {
                        let dock = &mut self.docks[reader - R_CHAIN];
                        dock.on_chain.insert(dock.pulses, trolley);
                    }
                    self.at(now + timing::SWITCH_MS, Event::AtSwitch { reader, trolley });
                }
            }
            Event::AtSwitch { reader, trolley } => self.switch(reader, trolley),
            Event::IntoLane { lane, trolley } => {
                if let Some(sack) = &mut self.sacks[usize::from(trolley)] {
                    sack.lane = Some(lane);
                }
                self.lanes[usize::from(lane)].push_back(trolley);
            }
            Event::GateRelease { lane } => {
                let l = usize::from(lane);
                self.gate_busy[l] = false;
                if self.output(io::lane_gate(l)) {
                    if let Some(t) = self.lanes[l].pop_front() {
                        self.counts.lane_out[l] += 1;
                        self.latched[io::LANE_EXIT_WORD] |= 1 << l;
                        self.at(
                            now + timing::EMPTYING_RAIL_MS,
                            Event::AtReader {
                                reader: R_EMPTYING,
                                trolley: t,
                            },
                        );
                    }
                }
            }
            Event::AtStation { station, trolley } => {
                if let Some(sack) = self.sacks[usize::from(trolley)] {
                    let right = sack.station_ok;
                    if right {
                        if station < 3 {
                            self.counts.delivered_letters += 1;
                        } else {
                            self.counts.delivered_parcels += 1;
                        }
                    }
                    let outcome = if right {
                        Outcome::Delivered
                    } else {
                        Outcome::Misdelivered
                    };
                    self.end(trolley, Place::Station(station), outcome);
                }
                let s = usize::from(station);
                self.stations[s].push_back(trolley);
                if !self.station_busy[s] {
                    self.station_busy[s] = true;
                    self.at(now + timing::EMPTY_MS, Event::StationDone { station });
                }
            }
            Event::StationDone { station } => {
                let s = usize::from(station);
                if let Some(t) = self.stations[s].pop_front() {
                    self.at(now + timing::RETURN_MS, Event::Returned { trolley: t });
                }
                self.station_busy[s] = !self.stations[s].is_empty();
                if self.station_busy[s] {
                    self.at(now + timing::EMPTY_MS, Event::StationDone { station });
                }
            }
            Event::AtManual { trolley, from } => {
                if self.sacks[usize::from(trolley)].is_some() {
                    self.end(trolley, Place::Manual(from), Outcome::Rejected);
                }
                self.at(now + timing::RETURN_MS, Event::Returned { trolley });
            }
            Event::Returned { trolley } => {
                let p = (0..DESKS)
                    .min_by_key(|&p| self.desk_queue[p].len())
                    .unwrap_or(0);
                self.desk_queue[p].push_back(trolley);
            }
        }
    }

    /// The trolley reaches `reader`'s switch: it follows the outputs as written.
    fn switch(&mut self, reader: usize, trolley: u16) {
        let now = self.now_ms;
        let set: Vec<usize> = (0..EXITS[reader])
            .filter(|&e| self.output(io::switch(reader, e)))
            .collect();
        let reject = self.output(io::reject(reader));
        if reader >= R_CHAIN {
            if reject {
                let dock = &mut self.docks[reader - R_CHAIN];
                dock.on_chain.retain(|_, t| *t != trolley);
                self.counts.passed[reader][15] += 1;
                self.at(
                    now + timing::MANUAL_MS,
                    Event::AtManual {
                        trolley,
                        from: reader,
                    },
                );
            } else {
                self.counts.passed[reader][0] += 1;
            }
            return;
        }
        // Safe outputs (no exit, or two) lead to the manual station, as does the reject gate.
        let exit = match (reject, set.as_slice()) {
            (false, [e]) => *e,
            _ => {
                self.counts.passed[reader][15] += 1;
                self.at(
                    now + timing::MANUAL_MS,
                    Event::AtManual {
                        trolley,
                        from: reader,
                    },
                );
                return;
            }
        };
        self.counts.passed[reader][exit] += 1;
        if reader == R_EMPTYING {
            if let Some(sack) = &mut self.sacks[usize::from(trolley)] {
                sack.station_ok = match (sack.right, sack.lane) {
                    (Dest::Lane(l), Some(lane)) => {
                        l == lane && self.emptying[usize::from(l)] >> exit & 1 == 1
                    }
                    _ => false,
                };
            }
        }
        match next(reader, exit) {
            Some(Next::Reader(r)) => self.at(
                now + timing::RAIL_MS,
                Event::AtReader { reader: r, trolley },
            ),
            Some(Next::Lane(l)) => {
                if self.lanes[usize::from(l)].len() >= capacity::LANE {
                    // The lane is full: its entry is closed, the trolley runs on to the manual
                    // station.
                    self.at(
                        now + timing::MANUAL_MS,
                        Event::AtManual {
                            trolley,
                            from: reader,
                        },
                    );
                } else {
                    self.at(now + timing::RAIL_MS, Event::IntoLane { lane: l, trolley })
                }
            }
            Some(Next::Station(s)) => self.at(
                now + timing::STATION_RAIL_MS,
                Event::AtStation {
                    station: s,
                    trolley,
                },
            ),
            Some(Next::Chain(_)) | None => self.at(
                now + timing::MANUAL_MS,
                Event::AtManual {
                    trolley,
                    from: reader,
                },
            ),
        }
    }

    fn lane_gates(&mut self) {
        for l in 0..usize::from(BUFFER_LANES) {
            if self.output(io::lane_gate(l)) && !self.gate_busy[l] && !self.lanes[l].is_empty() {
                self.gate_busy[l] = true;
                self.at(
                    self.now_ms + timing::GATE_MS,
                    Event::GateRelease { lane: l as u8 },
                );
            }
        }
    }

    fn cams(&mut self, reader: usize, trolley: u16, swinging: bool) -> u16 {
        if self.faults.dead[reader] {
            return 0;
        }
        let word = TrolleyId::new(trolley).map_or(0, encode);
        if !(swinging && self.rng.random_bool(DISTURBED_SHARE)) {
            return word;
        }
        crate::mailbag::readers::misread(&mut self.rng, word)
    }
}
