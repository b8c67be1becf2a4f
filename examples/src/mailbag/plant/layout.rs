//! The plant's layout and its I/O map: the code readers and where their switches lead, the
//! destinations, the travel times, and which input and output bit is which. Everything the
//! field (`field.rs`) and the control program (`control.rs`) agree on is here.

#![allow(
    clippy::needless_range_loop,
    reason = "an index names a reader, lane, desk or exit across several arrays"
)]

use serde::Serialize;

use super::operator::{BUFFER_LANES, EMPTYING_STATIONS, LOADING_STATIONS, lane_name, station_name};

/// Dock chains.
pub const DOCKS: usize = 3;
/// Bins (tippers) on each dock chain.
pub const BINS_PER_DOCK: usize = 50;
/// Bins in all (the source's 150).
pub const BINS: usize = DOCKS * BINS_PER_DOCK;
/// Destinations: 150 bins, 15 buffer lanes, 7 emptying stations and the manual station (the
/// source's 173).
pub const DESTINATIONS: usize = BINS + BUFFER_LANES as usize + EMPTYING_STATIONS as usize + 1;
/// Code readers R1–R12.
pub const READERS: usize = 12;
/// Most trolleys the 12-cam code can number.
pub const MAX_TROLLEYS: u16 = 4095;

/// Where a sack (and its trolley) is going, as the registry cell of the trolley holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Dest {
    /// Buffer lane `0..15` (D1–D4, E1–E11): unsorted post, emptied later to an emptying station.
    Lane(u8),
    /// Bin `0..150`: bin `b` is bin `b % 50` of dock `b / 50`.
    Bin(u8),
}

/// The code readers, R1…R12, at every decision point.
///
/// | reader | where | switch exits |
/// |---|---|---|
/// | R1–R3 | at loading desks P1–P3 (reads the trolley being loaded) | none: onto the main rail |
/// | R4 | main junction | 0 buffer area (R5), 1 docks (R8) |
/// | R5 | buffer junction | 0 D lanes (R6), 1 E lanes (R7) |
/// | R6 | D lanes' switch bank | 0–3 D1–D4 |
/// | R7 | E lanes' switch bank | 0–10 E1–E11 |
/// | R8 | dock junction | 0–2 dock 1–3 (R10–R12) |
/// | R9 | emptying rail's switch bank | 0–6 A1–A3, B1–B2, C1–C2 |
/// | R10–R12 | start of dock chains 1–3 | none: onto the chain, tracked to the bin |
///
/// Every reader R4–R12 also has a reject gate to the manual station.
pub const READER_NAMES: [&str; READERS] = [
    "R1", "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9", "R10", "R11", "R12",
];
/// Reader at the main junction.
pub const R_MAIN: usize = 3;
/// Reader at the buffer junction.
pub const R_BUFFER: usize = 4;
/// Reader of the D lanes.
pub const R_D: usize = 5;
/// Reader of the E lanes.
pub const R_E: usize = 6;
/// Reader at the dock junction.
pub const R_DOCKS: usize = 7;
/// Reader on the emptying rail.
pub const R_EMPTYING: usize = 8;
/// Reader at the start of dock chain 1 (2 and 3 follow).
pub const R_CHAIN: usize = 9;

/// Switch exits of each reader (0 for the desks' and the chains' readers).
pub const EXITS: [usize; READERS] = [0, 0, 0, 2, 2, 4, 11, 3, 7, 0, 0, 0];

/// Where a reader's exit leads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// To another reader.
    Reader(usize),
    /// Into a buffer lane.
    Lane(u8),
    /// To an emptying station.
    Station(u8),
    /// Onto dock chain `0..3` (its reader).
    Chain(usize),
}

/// Where exit `exit` of `reader` leads (`None` past its exits).
#[must_use]
pub fn next(reader: usize, exit: usize) -> Option<Next> {
    Some(match (reader, exit) {
        (0..=2, _) => Next::Reader(R_MAIN),
        (R_MAIN, 0) => Next::Reader(R_BUFFER),
        (R_MAIN, 1) => Next::Reader(R_DOCKS),
        (R_BUFFER, 0) => Next::Reader(R_D),
        (R_BUFFER, 1) => Next::Reader(R_E),
        (R_D, l @ 0..4) => Next::Lane(l as u8),
        (R_E, l @ 0..11) => Next::Lane(4 + l as u8),
        (R_DOCKS, d @ 0..3) => Next::Reader(R_CHAIN + d),
        (R_EMPTYING, s @ 0..7) => Next::Station(s as u8),
        _ => return None,
    })
}

/// The exit of `reader` toward `dest` (`None`: this reader cannot lead there, a reject).
/// The emptying reader's exit is chosen by the control program (a lane's portions), not here.
#[must_use]
pub fn exit_toward(reader: usize, dest: Dest) -> Option<usize> {
    match (reader, dest) {
        (R_MAIN, Dest::Lane(_)) => Some(0),
        (R_MAIN, Dest::Bin(_)) => Some(1),
        (R_BUFFER, Dest::Lane(l)) => Some(usize::from(l >= 4)),
        (R_D, Dest::Lane(l)) if l < 4 => Some(usize::from(l)),
        (R_E, Dest::Lane(l)) if (4..BUFFER_LANES).contains(&l) => Some(usize::from(l - 4)),
        (R_DOCKS, Dest::Bin(b)) => Some(usize::from(b) / BINS_PER_DOCK),
        _ => None,
    }
}

/// The name of a destination (`D3`, `A1`, `bin 2/17`, `manual`).
#[must_use]
pub fn dest_name(dest: Dest) -> String {
    match dest {
        Dest::Lane(l) => lane_name(l).to_string(),
        Dest::Bin(b) => format!(
            "bin {}/{}",
            usize::from(b) / BINS_PER_DOCK + 1,
            usize::from(b) % BINS_PER_DOCK + 1
        ),
    }
}

/// Timing of the field, in milliseconds of plant time (the plant stands still while its drives
/// are off).
pub mod timing {
    /// A trolley is in front of a reader's cams this long: 5 scans of 50 ms.
    pub const PASSAGE_MS: u64 = 250;
    /// From a reader's cams to its switch: the switch must be set by then.
    pub const SWITCH_MS: u64 = 1_000;
    /// Least time between two trolleys at a reader (they queue on the gravity rail).
    pub const HEADWAY_MS: u64 = 2_000;
    /// From a loading desk to R4, and between readers on the way.
    pub const RAIL_MS: u64 = 20_000;
    /// From a lane's gate to R9 on the emptying rail.
    pub const EMPTYING_RAIL_MS: u64 = 30_000;
    /// From R9 to an emptying station.
    pub const STATION_RAIL_MS: u64 = 15_000;
    /// An emptying station empties one trolley in this time.
    pub const EMPTY_MS: u64 = 8_000;
    /// A buffer lane's gate lets one trolley go in this time while open.
    pub const GATE_MS: u64 = 2_000;
    /// The return rail, from any station back to a loading station.
    pub const RETURN_MS: u64 = 240_000;
    /// From any reject gate to the manual station.
    pub const MANUAL_MS: u64 = 60_000;
    /// One chain pulse (a decimetre at 0.5 m/s).
    pub const PULSE_MS: u64 = 200;
    /// A loading desk's trolley is replaced by the next empty in this time.
    pub const DESK_MS: u64 = 3_000;
}

/// Chain geometry, in pulses of new chain.
pub mod chain {
    /// Chain pulses in one revolution of the loop (800 m of new chain).
    pub const LOOP_PULSES: u64 = 8_000;
    /// Where a trolley leaves the chain (past the last bin), pulses from the reader.
    pub const END_PULSES: u64 = 4_000;
    /// SIA: pulses between the two reference initiators at commissioning (300 m).
    pub const SIA: u32 = 3_000;
    /// Bin `j`'s tipper from the reader, as commissioned (SA).
    #[must_use]
    pub fn bin_sa(j: usize) -> u32 {
        200 + 72 * j as u32
    }
    /// SA is set this many pulses short of the bin: the reader's verdict and the tracker's
    /// entry come 1–3 pulses after the trolley passed the cams, and the 6-pulse hold then
    /// covers the trolley whatever the scan's phase.
    pub const LEAD_PULSES: u32 = 4;
}

/// Capacities of the field.
pub mod capacity {
    /// Trolleys a buffer lane holds; its full photocell is on at this many.
    pub const LANE: usize = 60;
    /// Trolleys waiting at an emptying station before its full photocell comes on.
    pub const STATION: usize = 12;
}

/// The I/O map: 544 inputs in 34 words of 16, 240 outputs in 15 words.
///
/// Inputs (point = 16 × word + bit):
///
/// | words | bits | what |
/// |---|---|---|
/// | 0–11 | 0–12 | reader R1…R12's cams (12 number cams and the parity cam), raw |
/// | 0–11 | 13 | reader R1…R12's trolley-present sensor, debounced over 2 scans |
/// | 12 | 0–14 | buffer lane D1…E11 full (photocell), debounced over 3 scans |
/// | 13 | 0–14 | buffer lane D1…E11 has a trolley at its gate, debounced over 3 scans |
/// | 14 | 0–14 | a trolley left buffer lane D1…E11 (photocell pulse), latched |
/// | 15 | 0–6 | emptying station A1…C2 full (photocell), debounced over 3 scans |
/// | 16 | 0–2 | dock chain 1–3 pulse initiator (one per decimetre), latched |
/// | 16 | 4–6 | dock chain 1–3 first reference initiator, latched |
/// | 16 | 8–10 | dock chain 1–3 second reference initiator, latched |
/// | 17–33 | | spare |
///
/// Outputs:
///
/// | point | what |
/// |---|---|
/// | 0 | drives on (the lift chains and dock chains run) |
/// | 1–3 | loading desk P1–P3's release gate |
/// | 16 × (1 + r) + e, r = R4…R12 as 0…8 | reader's switch toward exit e |
/// | 16 × (1 + r) + 15 | reader's reject gate (to the manual station) |
/// | 160–174 | buffer lane D1…E11's emptying gate |
/// | every other point, in order | the 150 tippers, bin 1/1 first ([`io::TIPPER_POINTS`]) |
///
/// Safe outputs are all off: drives stopped, gates closed, switches toward the manual station.
pub mod io {
    use super::{BINS, BINS_PER_DOCK, BUFFER_LANES, DOCKS, EMPTYING_STATIONS, READERS};

    /// Input words.
    pub const IN_WORDS: usize = 34;
    /// Output words.
    pub const OUT_WORDS: usize = 15;

    /// Bit of the trolley-present sensor in a reader's word.
    pub const PRESENT_BIT: usize = 13;
    /// The 13 cam bits of a reader's word.
    pub const CAMS: u16 = 0x1FFF;

    /// Input: reader `r`'s presence sensor.
    #[must_use]
    pub const fn present(r: usize) -> usize {
        16 * r + PRESENT_BIT
    }
    /// Input word: lanes full.
    pub const LANE_FULL_WORD: usize = 12;
    /// Input word: lanes with a trolley at the gate.
    pub const LANE_WAITING_WORD: usize = 13;
    /// Input word: lane exit pulses.
    pub const LANE_EXIT_WORD: usize = 14;
    /// Input word: emptying stations full.
    pub const STATION_FULL_WORD: usize = 15;
    /// Input word: chain pulses and reference initiators.
    pub const CHAIN_WORD: usize = 16;
    /// Input: dock `d`'s chain pulse.
    #[must_use]
    pub const fn chain_pulse(d: usize) -> usize {
        16 * CHAIN_WORD + d
    }
    /// Input: dock `d`'s first reference initiator.
    #[must_use]
    pub const fn reference_start(d: usize) -> usize {
        16 * CHAIN_WORD + 4 + d
    }
    /// Input: dock `d`'s second reference initiator.
    #[must_use]
    pub const fn reference_end(d: usize) -> usize {
        16 * CHAIN_WORD + 8 + d
    }

    /// Output: drives on.
    pub const DRIVES: usize = 0;
    /// Output: desk `p`'s release gate.
    #[must_use]
    pub const fn release(p: usize) -> usize {
        1 + p
    }
    /// Output: reader `r`'s (R4…R12) switch toward exit `e`.
    #[must_use]
    pub const fn switch(r: usize, e: usize) -> usize {
        16 * (1 + r - 3) + e
    }
    /// Output: reader `r`'s reject gate.
    #[must_use]
    pub const fn reject(r: usize) -> usize {
        16 * (1 + r - 3) + 15
    }
    /// Output: lane `l`'s emptying gate.
    #[must_use]
    pub const fn lane_gate(l: usize) -> usize {
        160 + l
    }
    /// Output: the tipper of bin `b` (`0..150`): the free points of the output words taken in
    /// order (see [`TIPPER_POINTS`]).
    #[must_use]
    pub const fn tipper(b: usize) -> usize {
        if b < BINS { TIPPER_POINTS[b] } else { 0 }
    }

    /// Whether output `point` is a drive, release, switch, reject or lane gate.
    const fn is_taken(point: usize) -> bool {
        if point < 16 {
            return point <= 3; // drives and the three release gates
        }
        if point >= 160 {
            return point < 160 + BUFFER_LANES as usize; // lane gates, then tippers
        }
        let r = point / 16 - 1 + 3;
        let bit = point % 16;
        r < READERS && (bit < super::EXITS[r] || bit == 15)
    }

    const fn tipper_points() -> [usize; BINS] {
        let mut out = [0usize; BINS];
        let mut n = 0;
        let mut point = 0;
        while n < BINS && point < 16 * OUT_WORDS {
            if !is_taken(point) {
                out[n] = point;
                n += 1;
            }
            point += 1;
        }
        out
    }

    /// Output point of each bin's tipper: the points no gate or switch takes, in order.
    pub const TIPPER_POINTS: [usize; BINS] = tipper_points();

    const _: () = assert!(BINS == 150 && BINS_PER_DOCK * DOCKS == BINS);
    const _: () = assert!(EMPTYING_STATIONS as usize <= 16);
    const _: () = assert!(TIPPER_POINTS[BINS - 1] != 0, "every tipper has an output");
}

/// Name of input point `point`, as `--fault stuck@…:NAME` takes it (`present-R4`,
/// `full-E3`, `waiting-D1`, `exit-D2`, `full-A1`, `pulse-1`, `ref-start-1`, `ref-end-1`), or
/// `in-N` for any other point.
#[must_use]
pub fn input_name(point: usize) -> String {
    let (word, bit) = (point / 16, point % 16);
    let lane = || lane_name(bit as u8);
    match word {
        0..12 if bit == io::PRESENT_BIT => format!("present-{}", READER_NAMES[word]),
        0..12 if bit < 13 => format!("cam{bit}-{}", READER_NAMES[word]),
        io::LANE_FULL_WORD if bit < 15 => format!("full-{}", lane()),
        io::LANE_WAITING_WORD if bit < 15 => format!("waiting-{}", lane()),
        io::LANE_EXIT_WORD if bit < 15 => format!("exit-{}", lane()),
        io::STATION_FULL_WORD if bit < 7 => format!("full-{}", station_name(bit as u8)),
        io::CHAIN_WORD if bit < 3 => format!("pulse-{}", bit + 1),
        io::CHAIN_WORD if (4..7).contains(&bit) => format!("ref-start-{}", bit - 3),
        io::CHAIN_WORD if (8..11).contains(&bit) => format!("ref-end-{}", bit - 7),
        _ => format!("in-{point}"),
    }
}

/// The input point named `name` ([`input_name`]'s names, or a number 0–543).
#[must_use]
pub fn input_point(name: &str) -> Option<usize> {
    if let Ok(n) = name.parse::<usize>() {
        return (n < 16 * io::IN_WORDS).then_some(n);
    }
    (0..16 * io::IN_WORDS).find(|&p| input_name(p).eq_ignore_ascii_case(name))
}

/// Loading stations, as a count for arrays.
pub const DESKS: usize = LOADING_STATIONS as usize;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_output_point_is_used_once() {
        let mut used = [0u8; 240];
        let mut mark = |p: usize| used[p] += 1;
        mark(io::DRIVES);
        (0..DESKS).for_each(|p| mark(io::release(p)));
        for r in R_MAIN..READERS {
            (0..EXITS[r]).for_each(|e| mark(io::switch(r, e)));
            mark(io::reject(r));
        }
        (0..usize::from(BUFFER_LANES)).for_each(|l| mark(io::lane_gate(l)));
        (0..BINS).for_each(|b| mark(io::tipper(b)));
        assert!(used.iter().all(|&u| u <= 1), "an output point used twice");
        assert_eq!(DESTINATIONS, 173);
    }

    #[test]
    fn every_destination_is_reachable_from_the_main_junction() {
        let dests = (0..BUFFER_LANES)
            .map(Dest::Lane)
            .chain((0..BINS as u8).map(Dest::Bin));
        for dest in dests {
            let mut reader = R_MAIN;
            let mut hops = 0;
            loop {
                let exit = exit_toward(reader, dest).expect("reachable");
                match next(reader, exit).expect("an exit") {
                    Next::Reader(r) => reader = r,
                    Next::Lane(l) => {
                        assert_eq!(dest, Dest::Lane(l));
                        break;
                    }
                    Next::Chain(_) | Next::Station(_) => unreachable!(),
                }
                hops += 1;
                if reader >= R_CHAIN {
                    assert_eq!(dest, Dest::Bin(dest_bin(dest) as u8));
                    assert_eq!(reader - R_CHAIN, dest_bin(dest) / BINS_PER_DOCK);
                    break;
                }
                assert!(hops < 5);
            }
        }
    }

    fn dest_bin(d: Dest) -> usize {
        match d {
            Dest::Bin(b) => usize::from(b),
            Dest::Lane(_) => usize::MAX,
        }
    }

    #[test]
    fn input_names_round_trip() {
        for p in 0..16 * io::IN_WORDS {
            assert_eq!(input_point(&input_name(p)), Some(p));
        }
    }
}
