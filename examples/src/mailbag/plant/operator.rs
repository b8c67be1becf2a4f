//! What passes between the operators, their six panels and the control program.
//!
//! This module is the contract between the plant's control program (`plant::computer`) and the
//! operator subsystem (`plant::panels`: the six panel links on `regler-panel-link`, the panels'
//! keyboards and the seeded or scripted operators). The control program never sees a key byte:
//! it asks the operators to type a [`Command`] ([`Desks::type_in`]), and every 10 ms it is
//! handed the commands the computer's keyboards completed ([`Desks::tick_10ms`]); every 50 ms
//! it hands the live lists to the displays ([`Desks::refresh`]).
//!
//! Numbering, used everywhere in the plant:
//! - post types `0..10` are the ten letter types, `10..14` the four parcel types;
//! - buffer lanes `0..4` are D1–D4, `4..15` are E1–E11;
//! - emptying stations `0..3` are A1–A3 (letters), `3..5` B1–B2 and `5..7` C1–C2 (parcels);
//! - sorting schedules `0..6`.

use serde::Serialize;

/// Letter post types (`0..10`).
pub const LETTER_TYPES: u8 = 10;
/// Parcel post types (`10..14`).
pub const PARCEL_TYPES: u8 = 4;
/// All post types.
pub const POST_TYPES: u8 = LETTER_TYPES + PARCEL_TYPES;
/// Buffer lanes: D1–D4 then E1–E11.
pub const BUFFER_LANES: u8 = 15;
/// Emptying stations: A1–A3, B1–B2, C1–C2.
pub const EMPTYING_STATIONS: u8 = 7;
/// Sorting schedules.
pub const SCHEDULES: u8 = 6;
/// Loading stations P1–P3.
pub const LOADING_STATIONS: u8 = 3;

/// The name of buffer lane `lane` (`D1`…`D4`, `E1`…`E11`), or `?` past the last.
pub fn lane_name(lane: u8) -> &'static str {
    const NAMES: [&str; BUFFER_LANES as usize] = [
        "D1", "D2", "D3", "D4", "E1", "E2", "E3", "E4", "E5", "E6", "E7", "E8", "E9", "E10", "E11",
    ];
    NAMES.get(usize::from(lane)).copied().unwrap_or("?")
}

/// The name of emptying station `station` (`A1`…`C2`), or `?` past the last.
pub fn station_name(station: u8) -> &'static str {
    const NAMES: [&str; EMPTYING_STATIONS as usize] = ["A1", "A2", "A3", "B1", "B2", "C1", "C2"];
    NAMES.get(usize::from(station)).copied().unwrap_or("?")
}

/// One of the six panels on the serial links.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum PanelId {
    /// The loading desk at P1, P2 or P3 (`0..3`); 7 display registers.
    Desk(u8),
    /// Panel A (letters' emptying); 29 registers.
    A,
    /// Panel B (parcels' emptying); 29 registers.
    B,
    /// The central desk; 46 registers.
    Central,
}

impl PanelId {
    /// The six panels, in link order.
    pub const ALL: [PanelId; 6] = [
        PanelId::Desk(0),
        PanelId::Desk(1),
        PanelId::Desk(2),
        PanelId::A,
        PanelId::B,
        PanelId::Central,
    ];

    /// The panel's place in [`PanelId::ALL`] (a desk past P3 counts as P3).
    pub fn index(self) -> usize {
        match self {
            PanelId::Desk(d) => usize::from(d.min(2)),
            PanelId::A => 3,
            PanelId::B => 4,
            PanelId::Central => 5,
        }
    }

    /// Display registers the computer sends this panel after the reset byte (the source's
    /// 7, 29 and 46).
    pub fn registers(self) -> usize {
        match self {
            PanelId::Desk(_) => 7,
            PanelId::A | PanelId::B => 29,
            PanelId::Central => 46,
        }
    }

    /// The panel's name as the plant's staff say it: `P1`, `P2`, `P3`, `A`, `B`, `central`.
    pub fn name(self) -> &'static str {
        match self {
            PanelId::Desk(0) => "P1",
            PanelId::Desk(1) => "P2",
            PanelId::Desk(_) => "P3",
            PanelId::A => "A",
            PanelId::B => "B",
            PanelId::Central => "central",
        }
    }
}

/// What an operator tells the control program by keying it on a panel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Command {
    /// At a loading desk: the sack on the waiting trolley is unsorted post of this type
    /// (`0..POST_TYPES`).
    PostType(u8),
    /// At P1 or P2: the sack is sorted post for this postcode (five digits), bound for a dock
    /// bin.
    Postcode(u32),
    /// At the central desk: post type `post_type` goes to buffer lane `lane`.
    AssignType {
        /// Post type, `0..POST_TYPES`.
        post_type: u8,
        /// Buffer lane, `0..BUFFER_LANES`.
        lane: u8,
    },
    /// At panel A (letters) or B (parcels): buffer lane `lane` is emptied to these emptying
    /// stations (bit `i` = station `i`), in portions taken in turn so they fill evenly.
    Emptying {
        /// Buffer lane, `0..BUFFER_LANES`.
        lane: u8,
        /// Emptying stations, a bit set over `0..EMPTYING_STATIONS`.
        stations: u8,
    },
    /// At the central desk: run this sorting schedule whatever the calendar says (`Some`), or
    /// follow the calendar's minute table again (`None`).
    Schedule(Option<u8>),
    /// At any panel: light every lamp and digit (no local echo: it goes through the computer).
    LampTest,
}

/// What a loading desk's display shows of its station.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DeskLive {
    /// An empty trolley waits at the station, ready to take a sack.
    pub trolley_ready: bool,
    /// The computer's answer to the last complete entry.
    pub verdict: EntryVerdict,
    /// The last entry the computer took (post type or postcode), for the display.
    pub last_entry: u32,
    /// Sacks loaded at this station in the current hour (saturating).
    pub sacks_this_hour: u16,
}

/// The computer's answer to an operator's entry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum EntryVerdict {
    /// Nothing entered yet.
    #[default]
    None,
    /// Plausible: the trolley was released.
    Accepted,
    /// Not plausible (unknown post type, or a postcode without a bin in the active
    /// schedule): the trolley stays.
    Refused,
}

/// The control program's live lists that the panels display, refreshed every 50 ms.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Live {
    /// Simulated time of day, minutes since midnight.
    pub minute_of_day: u16,
    /// One per loading desk.
    pub desks: [DeskLive; LOADING_STATIONS as usize],
    /// Buffer lane of each post type.
    pub type_lane: [u8; POST_TYPES as usize],
    /// Emptying stations of each buffer lane (bit set).
    pub emptying: [u8; BUFFER_LANES as usize],
    /// Trolleys waiting in each buffer lane (saturating at 255).
    pub lane_fill: [u8; BUFFER_LANES as usize],
    /// Trolleys waiting at each emptying station (saturating at 255).
    pub station_fill: [u8; EMPTYING_STATIONS as usize],
    /// The sorting schedule in force.
    pub schedule: u8,
    /// The schedule was set at the central desk, not by the calendar.
    pub schedule_override: bool,
    /// Code readers whose health alarm is on (bit `i` = reader `i`).
    pub reader_alarms: u32,
    /// Faults reported and not yet cleared (saturating).
    pub faults: u8,
}

/// What the operator subsystem counted over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PanelTotals {
    /// Bytes the computer sent to the panels (reset bytes and registers).
    pub bytes_sent: u64,
    /// Of those, bytes a line error changed (what the noise did, counted at the line).
    pub bytes_corrupted: u64,
    /// Line errors a panel or the computer detected (parity or framing).
    pub errors_detected: u64,
    /// Display registers found wrong one whole sequence after a corrupted byte (the source
    /// says the next sequence corrects a single error: this should stay 0).
    pub displays_wrong_after_next_sequence: u64,
    /// Keys the operators pressed.
    pub keys_pressed: u64,
    /// Commands the computer's keyboards completed.
    pub commands: u64,
    /// Entries the computer's keyboards could not make a command of (an unknown key sequence).
    pub entries_refused: u64,
}

/// The operator subsystem as the control program sees it.
pub trait Desks {
    /// The operator at `panel` starts keying `command` (after whatever they are still keying).
    fn type_in(&mut self, panel: PanelId, command: Command);
    /// One tick of the 10 ms clock on all six links, `now_ms` after the start: every command
    /// the computer's keyboards completed in it is passed to `received`.
    fn tick_10ms(&mut self, now_ms: u64, received: &mut dyn FnMut(PanelId, Command));
    /// The 50 ms refresh: every display's registers from the live lists.
    fn refresh(&mut self, live: &Live);
    /// Bit error rate of `panel`'s line from now on (0 for a clean line).
    fn set_noise(&mut self, panel: PanelId, bit_error_rate: f64);
    /// What was counted so far.
    fn totals(&self) -> PanelTotals;
}

/// Keys that arrive the moment they are typed, over no link: for tests that look at the plant
/// alone. The plant runs on the panel links (`plant::panels`).
#[derive(Clone, Debug, Default)]
pub struct Immediate {
    waiting: Vec<(PanelId, Command)>,
    commands: u64,
}

impl Desks for Immediate {
    fn type_in(&mut self, panel: PanelId, command: Command) {
        self.waiting.push((panel, command));
    }

    fn tick_10ms(&mut self, _now_ms: u64, received: &mut dyn FnMut(PanelId, Command)) {
        for (panel, command) in self.waiting.drain(..) {
            self.commands += 1;
            received(panel, command);
        }
    }

    fn refresh(&mut self, _live: &Live) {}

    fn set_noise(&mut self, _panel: PanelId, _bit_error_rate: f64) {}

    fn totals(&self) -> PanelTotals {
        PanelTotals {
            commands: self.commands,
            ..PanelTotals::default()
        }
    }
}
