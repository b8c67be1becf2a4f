//! What each panel's registers show: the register layout of the three panel types, filled from
//! the control program's live lists ([`Live`]), the entry the computer's keyboard holds for the
//! panel ([`EntryDisplay`]) and the lamp test.
//!
//! # Encoding (registers carry 7 bits, 0–127: the link's reset byte is `0xFF`)
//! - A **digit register** drives two digit displays: `11 · left + right`, each digit `0..=9` or
//!   [`BLANK`] (10) for a dark display; `120` is both dark, `96` is "88" (the lamp test). A
//!   number spread over several digit registers is right-aligned, without leading zeros (a
//!   zero shows as `0`), and saturates at the largest number the positions hold (`99`,
//!   `9999`…).
//! - A **lamp register** drives seven lamps, bit `i` = lamp `i`.
//! - A **bit-field register** carries seven bits of a longer bit field, the field's bit `7k + i`
//!   in bit `i` of its `k`-th register.
//! - A **spare** register is wired to nothing and always 0.
//!
//! Register 0 of every panel is its lamp register; lamps common to all panels: bit 5 ([`KEYING`])
//! an entry is being keyed (the digits shown are the entry), bit 6 ([`ENTRY_REFUSED`]) the
//! computer's keyboard refused the last entry (lit until the next key arrives). The lamp test
//! lights every lamp and shows `8` on every digit display (spares stay dark).
//!
//! # Loading desk P1–P3 (7 registers)
//! | reg | kind | shows |
//! |---|---|---|
//! | 0 | lamps | bit 0 trolley ready, bit 1 entry accepted, bit 2 entry refused by the plant (not plausible), bit 3 keying a postcode |
//! | 1–3 | digits | the five big displays (positions 1–5; position 0 is dark): the entry being keyed, else the last entry the computer took |
//! | 4 | digits | the hour the count below is for |
//! | 5–6 | digits | sacks loaded at this station this hour (saturating at 9999) |
//!
//! # Panels A and B (29 registers)
//! Panel A serves the letter stations A1–A3 (`0..3`), panel B the parcel stations B1, B2, C1,
//! C2 (`3..7`; C's own panels are four lamp push-buttons wired as ordinary I/O, so B also shows
//! which lanes go to C).
//!
//! | reg | kind | shows |
//! |---|---|---|
//! | 0 | lamps | bit 0 keying an emptying choice |
//! | 1–2 | digits | the entry being keyed (its last four positions) |
//! | 3–17 | digits | trolleys waiting in buffer lanes D1…E11 (saturating at 99) |
//! | 18–20 (A), 18–19 (B) | digits | trolleys waiting at A1–A3 (A), at B1–B2 (B) |
//! | 21–27 (A), 20–28 (B) | bit field | emptying choice: bit `s + n·lane` = lane `lane` is emptied to the panel's `s`-th station (`n` = 3 for A, 4 for B) |
//! | 28 (A) | spare | |
//!
//! # Central desk (46 registers)
//! | reg | kind | shows |
//! |---|---|---|
//! | 0 | lamps | bit 0 schedule set here (override), bit 1 faults waiting, bit 2 a reader alarm, bit 3 keying a lane assignment, bit 4 keying a schedule |
//! | 1–3 | digits | the entry being keyed (six positions) |
//! | 4–17 | digits | the buffer lane of post types 0…13 |
//! | 18 | digits | the sorting schedule in force |
//! | 19, 20 | digits | the time: hour, minute |
//! | 21 | digits | faults waiting (saturating at 99) |
//! | 22–26 | bit field | code readers with their alarm on (bit `i` = reader `i`) |
//! | 27–41 | digits | trolleys waiting in buffer lanes D1…E11 (saturating at 99) |
//! | 42–45 | spare | |

use super::super::operator::{
    BUFFER_LANES, EMPTYING_STATIONS, EntryVerdict, LOADING_STATIONS, Live, POST_TYPES,
};

/// A dark digit display.
pub const BLANK: u8 = 10;
/// A digit register with both displays dark.
pub const DARK: u8 = pair(BLANK, BLANK);
/// Lamp common to every panel: an entry is being keyed.
pub const KEYING: u8 = 1 << 5;
/// Lamp common to every panel: the computer's keyboard refused the last entry.
pub const ENTRY_REFUSED: u8 = 1 << 6;

/// How a register drives its panel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Seven lamps.
    Lamps,
    /// Two digit displays.
    Digits,
    /// Seven bits of a bit field shown as lamps.
    Bits,
    /// Wired to nothing.
    Spare,
}

/// The entry the computer's keyboard holds for a panel, as the panel shows it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EntryDisplay {
    /// The entry's last six positions, right-aligned (`0..=9` or [`BLANK`]; fields are
    /// separated by a blank).
    pub positions: [u8; 6],
    /// An entry is being keyed.
    pub keying: bool,
    /// The panel's lamps for the function key pressed (bits 0–4 of its lamp register).
    pub function_lamps: u8,
    /// The last entry was refused by the keyboard.
    pub refused: bool,
}

/// Two digit positions in one register: `11 · left + right` (each `0..=9` or [`BLANK`]).
#[must_use]
pub const fn pair(left: u8, right: u8) -> u8 {
    let left = if left > BLANK { BLANK } else { left };
    let right = if right > BLANK { BLANK } else { right };
    11 * left + right
}

/// The two digit positions of a digit register (`None` for a value no pair makes).
#[must_use]
pub const fn unpair(register: u8) -> Option<(u8, u8)> {
    if register > DARK {
        None
    } else {
        Some((register / 11, register % 11))
    }
}

/// Register kinds of a loading desk.
pub const DESK: [Kind; 7] = {
    let mut k = [Kind::Digits; 7];
    k[0] = Kind::Lamps;
    k
};

/// Register kinds of panel A.
pub const PANEL_A: [Kind; 29] = {
    let mut k = [Kind::Digits; 29];
    k[0] = Kind::Lamps;
    let mut r = 21;
    while r < 28 {
        k[r] = Kind::Bits;
        r += 1;
    }
    k[28] = Kind::Spare;
    k
};

/// Register kinds of panel B.
pub const PANEL_B: [Kind; 29] = {
    let mut k = [Kind::Digits; 29];
    k[0] = Kind::Lamps;
    let mut r = 20;
    while r < 29 {
        k[r] = Kind::Bits;
        r += 1;
    }
    k
};

/// Register kinds of the central desk.
pub const CENTRAL: [Kind; 46] = {
    let mut k = [Kind::Digits; 46];
    k[0] = Kind::Lamps;
    let mut r = 22;
    while r < 27 {
        k[r] = Kind::Bits;
        r += 1;
    }
    let mut r = 42;
    while r < 46 {
        k[r] = Kind::Spare;
        r += 1;
    }
    k
};

/// Which of the two lane panels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Panel A: letter stations A1–A3.
    A,
    /// Panel B: parcel stations B1, B2, C1, C2.
    B,
}

impl Side {
    /// The emptying stations the panel chooses for (`first..end`).
    #[must_use]
    pub const fn stations(self) -> (u8, u8) {
        match self {
            Side::A => (0, 3),
            Side::B => (3, EMPTYING_STATIONS),
        }
    }

    /// The stations whose fill the panel shows (`first..end`).
    const fn shown_fill(self) -> (u8, u8) {
        match self {
            Side::A => (0, 3),
            Side::B => (3, 5),
        }
    }

    /// The register kinds.
    #[must_use]
    pub const fn kinds(self) -> &'static [Kind; 29] {
        match self {
            Side::A => &PANEL_A,
            Side::B => &PANEL_B,
        }
    }
}

/// `value` right-aligned over the digit registers `out` (two positions each), saturating.
fn number(value: u32, out: &mut [u8]) {
    if let [one] = out {
        // The common case, two positions: kept cheap (it runs every 50 ms for every lane).
        let v = value.min(99) as u8;
        *one = pair(if v >= 10 { v / 10 } else { BLANK }, v % 10);
        return;
    }
    let positions = out.len() * 2;
    let max = 10u32.saturating_pow(u32::try_from(positions).unwrap_or(9)) - 1;
    let mut rest = value.min(max);
    let mut digits = [BLANK; 12];
    for (k, slot) in digits.iter_mut().take(positions).enumerate() {
        if k == 0 || rest > 0 {
            *slot = (rest % 10) as u8;
            rest /= 10;
        }
    }
    // digits[0] is the rightmost position.
    for (r, reg) in out.iter_mut().rev().enumerate() {
        *reg = pair(digits[2 * r + 1], digits[2 * r]);
    }
}

/// The entry's last `out.len() · 2` positions over the digit registers `out`.
fn entry(positions: &[u8; 6], out: &mut [u8]) {
    let skip = 6usize.saturating_sub(out.len() * 2);
    for (reg, two) in out.iter_mut().zip(positions[skip..].chunks_exact(2)) {
        *reg = pair(two[0], two[1]);
    }
}

/// `bits` spread over the bit-field registers `out`, seven bits each.
fn bit_field(bits: u64, out: &mut [u8]) {
    for (k, reg) in out.iter_mut().enumerate() {
        *reg = ((bits >> (7 * k)) & 0x7F) as u8;
    }
}

/// Lights every lamp and digit of a panel with these register kinds.
fn lamp_test(kinds: &[Kind], out: &mut [u8]) {
    for (kind, reg) in kinds.iter().zip(out.iter_mut()) {
        *reg = match kind {
            Kind::Lamps | Kind::Bits => 0x7F,
            Kind::Digits => pair(8, 8),
            Kind::Spare => 0,
        };
    }
}

fn common_lamps(entry: &EntryDisplay) -> u8 {
    let mut lamps = entry.function_lamps & 0x1F;
    if entry.keying {
        lamps |= KEYING;
    }
    if entry.refused {
        lamps |= ENTRY_REFUSED;
    }
    lamps
}

/// The registers of loading desk `station` (`0..3`).
pub fn desk(
    live: &Live,
    station: u8,
    entry_shown: &EntryDisplay,
    lamps_on: bool,
    out: &mut [u8; 7],
) {
    if lamps_on {
        lamp_test(&DESK, out);
        return;
    }
    let d = live.desks[usize::from(station.min(LOADING_STATIONS - 1))];
    let mut lamps = common_lamps(entry_shown);
    lamps |= u8::from(d.trolley_ready);
    lamps |= match d.verdict {
        EntryVerdict::None => 0,
        EntryVerdict::Accepted => 1 << 1,
        EntryVerdict::Refused => 1 << 2,
    };
    out[0] = lamps;
    if entry_shown.keying {
        entry(&entry_shown.positions, &mut out[1..4]);
    } else if d.verdict == EntryVerdict::None {
        out[1..4].fill(DARK);
    } else {
        number(d.last_entry, &mut out[1..4]);
    }
    // Position 0 is not one of the five big displays.
    out[1] = pair(BLANK, unpair(out[1]).map_or(BLANK, |(_, right)| right));
    number(u32::from(live.minute_of_day / 60), &mut out[4..5]);
    number(u32::from(d.sacks_this_hour), &mut out[5..7]);
}

/// The registers of panel A or B.
pub fn lanes(
    live: &Live,
    side: Side,
    entry_shown: &EntryDisplay,
    lamps_on: bool,
    out: &mut [u8; 29],
) {
    if lamps_on {
        lamp_test(side.kinds(), out);
        return;
    }
    out[0] = common_lamps(entry_shown);
    entry(&entry_shown.positions, &mut out[1..3]);
    for (reg, fill) in out[3..18].iter_mut().zip(live.lane_fill) {
        number(u32::from(fill), core::slice::from_mut(reg));
    }
    let (first, end) = side.shown_fill();
    let fills = &live.station_fill[usize::from(first)..usize::from(end)];
    let field_start = 18 + fills.len();
    for (reg, fill) in out[18..field_start].iter_mut().zip(fills) {
        number(u32::from(*fill), core::slice::from_mut(reg));
    }
    let (first, end) = side.stations();
    let per_lane = end - first;
    let mut field = 0u64;
    for (lane, stations) in live.emptying.iter().enumerate() {
        let mine = u64::from((stations >> first) & ((1 << per_lane) - 1));
        field |= mine << (lane * usize::from(per_lane));
    }
    let field_end = field_start + (usize::from(BUFFER_LANES) * usize::from(per_lane)).div_ceil(7);
    bit_field(field, &mut out[field_start..field_end]);
    out[field_end..].fill(0);
}

/// The registers of the central desk.
pub fn central(live: &Live, entry_shown: &EntryDisplay, lamps_on: bool, out: &mut [u8; 46]) {
    if lamps_on {
        lamp_test(&CENTRAL, out);
        return;
    }
    let mut lamps = common_lamps(entry_shown);
    lamps |= u8::from(live.schedule_override);
    lamps |= u8::from(live.faults > 0) << 1;
    lamps |= u8::from(live.reader_alarms != 0) << 2;
    out[0] = lamps;
    entry(&entry_shown.positions, &mut out[1..4]);
    for (reg, lane) in out[4..4 + usize::from(POST_TYPES)]
        .iter_mut()
        .zip(live.type_lane)
    {
        number(u32::from(lane), core::slice::from_mut(reg));
    }
    number(u32::from(live.schedule), &mut out[18..19]);
    number(u32::from(live.minute_of_day / 60), &mut out[19..20]);
    number(u32::from(live.minute_of_day % 60), &mut out[20..21]);
    number(u32::from(live.faults), &mut out[21..22]);
    bit_field(u64::from(live.reader_alarms), &mut out[22..27]);
    for (reg, fill) in out[27..42].iter_mut().zip(live.lane_fill) {
        number(u32::from(fill), core::slice::from_mut(reg));
    }
    out[42..].fill(0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mailbag::plant::operator::DeskLive;

    /// The number a run of digit registers shows (the model: read the digits left to right).
    fn shown(regs: &[u8]) -> Option<u32> {
        let mut value = None::<u32>;
        for &r in regs {
            let (l, rr) = unpair(r)?;
            for d in [l, rr] {
                if d < BLANK {
                    value = Some(value.unwrap_or(0) * 10 + u32::from(d));
                }
            }
        }
        value
    }

    #[test]
    fn numbers_read_back_or_saturate() {
        for v in [0u32, 1, 9, 10, 99, 100, 1234, 9999, 10_000, u32::MAX] {
            let mut one = [0u8; 1];
            number(v, &mut one);
            assert_eq!(shown(&one), Some(v.min(99)), "{v}");
            let mut three = [0u8; 3];
            number(v, &mut three);
            assert_eq!(shown(&three), Some(v.min(999_999)), "{v}");
        }
        // Every register value a layout makes is a 7-bit value, never the reset byte.
        assert!(DARK <= 0x7F && pair(9, 9) <= DARK);
        assert_eq!(unpair(pair(3, BLANK)), Some((3, BLANK)));
        assert_eq!(unpair(121), None);
    }

    fn busy_live() -> Live {
        let mut live = Live {
            minute_of_day: 23 * 60 + 59,
            schedule: 5,
            schedule_override: true,
            reader_alarms: 0x8000_0001,
            faults: 200,
            ..Live::default()
        };
        live.desks[1] = DeskLive {
            trolley_ready: true,
            verdict: EntryVerdict::Accepted,
            last_entry: 21119,
            sacks_this_hour: 312,
        };
        for (k, lane) in live.type_lane.iter_mut().enumerate() {
            *lane = (k % 15) as u8;
        }
        for (k, e) in live.emptying.iter_mut().enumerate() {
            *e = (k * 37 % 128) as u8;
        }
        for (k, f) in live.lane_fill.iter_mut().enumerate() {
            *f = (k * 20) as u8;
        }
        live.station_fill = [1, 2, 3, 4, 5, 6, 255];
        live
    }

    #[test]
    fn desk_shows_its_station() {
        let live = busy_live();
        let mut out = [0u8; 7];
        desk(&live, 1, &EntryDisplay::default(), false, &mut out);
        assert_eq!(out[0], 0b011);
        assert_eq!(shown(&out[1..4]), Some(21119));
        assert_eq!(shown(&out[4..5]), Some(23));
        assert_eq!(shown(&out[5..7]), Some(312));
        // Keying: the entry replaces the last entry, the keying lamp is lit.
        let keyed = EntryDisplay {
            positions: [BLANK, BLANK, BLANK, BLANK, 1, 3],
            keying: true,
            function_lamps: 0,
            refused: true,
        };
        desk(&live, 1, &keyed, false, &mut out);
        assert_eq!(shown(&out[1..4]), Some(13));
        assert_eq!(out[0], 0b011 | KEYING | ENTRY_REFUSED);
        // P1: nothing entered yet, dark.
        desk(&live, 0, &EntryDisplay::default(), false, &mut out);
        assert_eq!(shown(&out[1..4]), None);
        assert!(out.iter().all(|&r| r <= 0x7F));
    }

    #[test]
    fn lane_panels_show_their_stations_choice() {
        let live = busy_live();
        for side in [Side::A, Side::B] {
            let mut out = [0u8; 29];
            lanes(&live, side, &EntryDisplay::default(), false, &mut out);
            let (first, end) = side.stations();
            let n = usize::from(end - first);
            let start = if side == Side::A { 21 } else { 20 };
            for lane in 0..15 {
                assert_eq!(
                    shown(&out[3 + lane..4 + lane]),
                    Some(u32::from(live.lane_fill[lane]).min(99))
                );
                for s in 0..n {
                    let bit = lane * n + s;
                    let lit = (out[start + bit / 7] >> (bit % 7)) & 1 == 1;
                    let chosen = (live.emptying[lane] >> (usize::from(first) + s)) & 1 == 1;
                    assert_eq!(lit, chosen, "{side:?} lane {lane} station {s}");
                }
            }
            assert_eq!(
                shown(&out[18..19]),
                Some(u32::from(live.station_fill[usize::from(first)]))
            );
            assert!(out.iter().all(|&r| r <= 0x7F));
            assert_eq!(side.kinds()[start - 1], Kind::Digits);
            assert_eq!(side.kinds()[start], Kind::Bits);
        }
    }

    #[test]
    fn central_shows_table_schedule_time_alarms() {
        let live = busy_live();
        let mut out = [0u8; 46];
        central(&live, &EntryDisplay::default(), false, &mut out);
        assert_eq!(out[0], 0b111);
        for t in 0..14 {
            assert_eq!(
                shown(&out[4 + t..5 + t]),
                Some(u32::from(live.type_lane[t]))
            );
        }
        assert_eq!(shown(&out[18..19]), Some(5));
        assert_eq!(
            (shown(&out[19..20]), shown(&out[20..21])),
            (Some(23), Some(59))
        );
        assert_eq!(shown(&out[21..22]), Some(99));
        let mut alarms = 0u64;
        for k in 0..5 {
            alarms |= u64::from(out[22 + k]) << (7 * k);
        }
        assert_eq!(alarms, u64::from(live.reader_alarms));
        assert_eq!(&out[42..], &[0; 4]);
    }

    #[test]
    fn lamp_test_lights_everything_wired() {
        let live = Live::default();
        let mut out = [0u8; 46];
        central(&live, &EntryDisplay::default(), true, &mut out);
        for (kind, reg) in CENTRAL.iter().zip(out) {
            match kind {
                Kind::Digits => assert_eq!(unpair(reg), Some((8, 8))),
                Kind::Lamps | Kind::Bits => assert_eq!(reg, 0x7F),
                Kind::Spare => assert_eq!(reg, 0),
            }
        }
        let mut out = [0u8; 7];
        desk(&live, 2, &EntryDisplay::default(), true, &mut out);
        assert_eq!(out, [0x7F, 96, 96, 96, 96, 96, 96]);
    }
}
