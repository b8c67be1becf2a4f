//! The computer's side of each panel's keyboard ([`Keyboard`]): it turns the key bytes it took
//! over the MOT/SÄN handshake (the table in [`super::keys`]) into commands.
//!
//! # Refused entries
//! ENTER on an entry that makes no command is **refused**: counted, shown on the panel (its
//! ENTRY REFUSED lamp, until the next key), and nothing reaches the control program. That is:
//! ENTER with no digits (except CALENDAR ENTER); a number out of range (a post type ≥ 14, a
//! lane ≥ 15, a schedule ≥ 6, a station that is not the panel's); a postcode of other than five
//! digits; a field of more than six digits; NEXT where the function has no second field; a
//! function the panel does not have (a postcode at P3 or at panel A, a lane assignment at a
//! desk…). A key byte that is no key is refused at once. A key the link lost (the computer gave
//! up waiting for two equal bytes: [`Keyboard::key_lost`]) spoils the entry it fell in, so a lost
//! digit can never make another valid command (post type `12` keyed, `1` taken). The computer
//! cannot tell a lost key from a MOT line that rose with no key behind it (a stuck or glitching
//! line): both spoil the entry, so after such a fault the next entry at a desk (digits ENTER,
//! no function key to start it afresh) is refused once — refused, never taken wrong.

use super::super::operator::{BUFFER_LANES, Command, POST_TYPES, PanelId, SCHEDULES};
use super::keys::{
    ASSIGN, CALENDAR, CLEAR, DIGIT_0, EMPTYING, ENTER, LAMP_TEST, NEXT, POSTCODE, SCHEDULE,
};
use super::layout::{BLANK, EntryDisplay, Side};

/// Most digits of one field.
const FIELD_DIGITS: usize = 6;

/// The function key that started an entry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Function {
    /// Digits only: a post type at a loading desk.
    #[default]
    Plain,
    Postcode,
    Assign,
    Emptying,
    Schedule,
    Calendar,
}

impl Function {
    fn of(key: u8) -> Option<Self> {
        Some(match key {
            POSTCODE => Self::Postcode,
            ASSIGN => Self::Assign,
            EMPTYING => Self::Emptying,
            SCHEDULE => Self::Schedule,
            CALENDAR => Self::Calendar,
            _ => return None,
        })
    }

    fn key(self) -> Option<u8> {
        Some(match self {
            Self::Plain => return None,
            Self::Postcode => POSTCODE,
            Self::Assign => ASSIGN,
            Self::Emptying => EMPTYING,
            Self::Schedule => SCHEDULE,
            Self::Calendar => CALENDAR,
        })
    }

    fn has_second_field(self) -> bool {
        matches!(self, Self::Assign | Self::Emptying)
    }

    /// The panel's lamp for the function (bits 0–4 of its lamp register; see `layout`).
    fn lamp(self, panel: PanelId) -> u8 {
        match (panel, self) {
            (PanelId::Desk(_), Self::Postcode) => 1 << 3,
            (PanelId::A | PanelId::B, Self::Emptying) => 1,
            (PanelId::Central, Self::Assign) => 1 << 3,
            (PanelId::Central, Self::Schedule) => 1 << 4,
            _ => 0,
        }
    }
}

/// One field of an entry: its digits as keyed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Field {
    digits: [u8; FIELD_DIGITS],
    len: usize,
    /// More digits were keyed than a field holds.
    overflow: bool,
}

impl Field {
    fn push(&mut self, digit: u8) {
        match self.digits.get_mut(self.len) {
            Some(slot) => {
                *slot = digit;
                self.len += 1;
            }
            None => self.overflow = true,
        }
    }

    fn keyed(&self) -> &[u8] {
        &self.digits[..self.len]
    }

    /// The field as a number with `min..=max` digits.
    fn number(&self, min: usize, max: usize) -> Option<u32> {
        if self.overflow || !(min..=max).contains(&self.len) {
            return None;
        }
        Some(self.keyed().iter().fold(0, |n, &d| n * 10 + u32::from(d)))
    }
}

/// What one key did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The entry goes on.
    Nothing,
    /// The entry made this command.
    Command(Command),
    /// The entry made no command.
    Refused,
}

/// The computer's side of one panel's keyboard: the entry being keyed.
#[derive(Clone, Debug)]
pub struct Keyboard {
    panel: PanelId,
    function: Function,
    fields: [Field; 2],
    /// In the second field (NEXT was keyed).
    second: bool,
    /// A key was keyed that spoils the entry (NEXT twice, a lost key).
    spoiled: bool,
    /// Any key of the entry so far.
    keying: bool,
    /// The last entry was refused (the panel's lamp, until the next key).
    refused: bool,
}

impl Keyboard {
    /// An idle keyboard for `panel`.
    #[must_use]
    pub fn new(panel: PanelId) -> Self {
        Self {
            panel,
            function: Function::Plain,
            fields: [Field::default(); 2],
            second: false,
            spoiled: false,
            keying: false,
            refused: false,
        }
    }

    fn clear(&mut self) {
        *self = Self::new(self.panel);
    }

    /// A key byte taken from the panel.
    pub fn key(&mut self, key: u8) -> Outcome {
        self.refused = false;
        match key {
            b if (DIGIT_0..DIGIT_0 + 10).contains(&b) => {
                self.keying = true;
                self.fields[usize::from(self.second)].push(b - DIGIT_0);
                Outcome::Nothing
            }
            NEXT => {
                self.keying = true;
                if self.second || !self.function.has_second_field() {
                    self.spoiled = true;
                }
                self.second = true;
                Outcome::Nothing
            }
            CLEAR => {
                self.clear();
                Outcome::Nothing
            }
            LAMP_TEST => {
                self.clear();
                Outcome::Command(Command::LampTest)
            }
            ENTER => {
                let made = self.command();
                self.clear();
                match made {
                    Some(command) => Outcome::Command(command),
                    None => self.refuse(),
                }
            }
            other => match Function::of(other) {
                // A function key starts a new entry (what was keyed before it is forgotten).
                Some(function) => {
                    self.clear();
                    self.function = function;
                    self.keying = true;
                    Outcome::Nothing
                }
                None => {
                    self.clear();
                    self.refuse()
                }
            },
        }
    }

    /// The link gave up on a key of this panel: the entry it fell in is spoiled (refused at
    /// ENTER), unless nothing was keyed yet.
    pub fn key_lost(&mut self) {
        self.spoiled = true;
        self.keying = true;
    }

    fn refuse(&mut self) -> Outcome {
        self.refused = true;
        Outcome::Refused
    }

    /// The command the entry makes at this panel, if any.
    fn command(&self) -> Option<Command> {
        if self.spoiled {
            return None;
        }
        let [first, second] = &self.fields;
        let small = |field: &Field, below: u8| {
            field
                .number(1, 2)
                .and_then(|n| u8::try_from(n).ok())
                .filter(|&n| n < below)
        };
        let one_field = !self.second;
        match (self.function, self.panel) {
            (Function::Plain, PanelId::Desk(_)) if one_field => {
                small(first, POST_TYPES).map(Command::PostType)
            }
            (Function::Postcode, PanelId::Desk(0 | 1)) if one_field => {
                first.number(5, 5).map(Command::Postcode)
            }
            (Function::Assign, PanelId::Central) if self.second => Some(Command::AssignType {
                post_type: small(first, POST_TYPES)?,
                lane: small(second, BUFFER_LANES)?,
            }),
            (Function::Emptying, PanelId::A | PanelId::B) if self.second => {
                let side = if self.panel == PanelId::A {
                    Side::A
                } else {
                    Side::B
                };
                let (from, to) = side.stations();
                let mut stations = 0u8;
                for &s in second.keyed() {
                    if !(from..to).contains(&s) {
                        return None;
                    }
                    stations |= 1 << s;
                }
                (!second.overflow).then_some(())?;
                Some(Command::Emptying {
                    lane: small(first, BUFFER_LANES)?,
                    stations,
                })
            }
            (Function::Schedule, PanelId::Central) if one_field => first
                .number(1, 1)
                .and_then(|n| u8::try_from(n).ok())
                .filter(|&n| n < SCHEDULES)
                .map(|n| Command::Schedule(Some(n))),
            (Function::Calendar, PanelId::Central) if one_field && first.len == 0 => {
                Some(Command::Schedule(None))
            }
            _ => None,
        }
    }

    /// What the panel shows of the entry.
    #[must_use]
    pub fn display(&self) -> EntryDisplay {
        // The entry as keyed (first field, a blank and the second field), right-aligned in six
        // positions: filled from the right.
        let mut positions = [BLANK; 6];
        let mut slots = positions.iter_mut().rev();
        if self.second {
            for (&d, slot) in self.fields[1].keyed().iter().rev().zip(&mut slots) {
                *slot = d;
            }
            slots.next(); // the blank between the fields
        }
        for (&d, slot) in self.fields[0].keyed().iter().rev().zip(&mut slots) {
            *slot = d;
        }
        EntryDisplay {
            positions,
            keying: self.keying,
            function_lamps: self.function.lamp(self.panel),
            refused: self.refused,
        }
    }

    /// The function key that starts the entry now being keyed, if any (for tests and logs).
    #[must_use]
    pub fn function_key(&self) -> Option<u8> {
        self.function.key()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mailbag::plant::panels::keys::keys_for;

    fn run(panel: PanelId, keys: &[u8]) -> Vec<Outcome> {
        let mut kb = Keyboard::new(panel);
        keys.iter()
            .map(|&k| kb.key(k))
            .filter(|o| *o != Outcome::Nothing)
            .collect()
    }

    fn typed(panel: PanelId, command: Command) -> Vec<Outcome> {
        let mut keys = Vec::new();
        keys_for(command, &mut keys);
        run(panel, &keys)
    }

    /// Which panel may take which command (the model, written from the table in the docs).
    fn allowed(panel: PanelId, command: Command) -> bool {
        match command {
            Command::PostType(t) => matches!(panel, PanelId::Desk(_)) && t < 14,
            Command::Postcode(c) => matches!(panel, PanelId::Desk(0 | 1)) && c <= 99_999,
            Command::AssignType { post_type, lane } => {
                panel == PanelId::Central && post_type < 14 && lane < 15
            }
            Command::Emptying { lane, stations } => {
                let mine = match panel {
                    PanelId::A => 0b000_0111,
                    PanelId::B => 0b111_1000,
                    _ => return false,
                };
                lane < 15 && stations & !mine == 0
            }
            Command::Schedule(Some(s)) => panel == PanelId::Central && s < 6,
            Command::Schedule(None) => panel == PanelId::Central,
            Command::LampTest => true,
        }
    }

    fn commands() -> Vec<Command> {
        let mut all = vec![Command::LampTest, Command::Schedule(None)];
        for v in 0..=20u8 {
            all.push(Command::PostType(v));
            all.push(Command::Schedule(Some(v)));
            for lane in [0u8, 9, 14, 15, 99, 100] {
                all.push(Command::AssignType { post_type: v, lane });
                all.push(Command::Emptying {
                    lane: v,
                    stations: lane,
                });
            }
        }
        for stations in 0..=255u8 {
            all.push(Command::Emptying { lane: 3, stations });
        }
        for code in [0u32, 1, 21_119, 99_999, 100_000, u32::MAX] {
            all.push(Command::Postcode(code));
        }
        all
    }

    #[test]
    fn every_command_is_taken_where_it_belongs_and_refused_elsewhere() {
        for panel in PanelId::ALL {
            for command in commands() {
                let got = typed(panel, command);
                if allowed(panel, command) {
                    assert_eq!(
                        got,
                        vec![Outcome::Command(command)],
                        "{panel:?} {command:?}"
                    );
                } else {
                    assert_eq!(got, vec![Outcome::Refused], "{panel:?} {command:?}");
                }
            }
        }
    }

    proptest::proptest! {
        /// Any key bytes at all (noise, a confused operator): no panic, and every command the
        /// keyboard makes is one the panel may take.
        #[test]
        fn any_key_bytes_make_only_commands_the_panel_may_take(
            panel in proptest::sample::select(PanelId::ALL.to_vec()),
            keys in proptest::collection::vec(
                proptest::prop_oneof![
                    proptest::sample::select(vec![ENTER, NEXT, CLEAR, POSTCODE, ASSIGN, EMPTYING, SCHEDULE, CALENDAR, LAMP_TEST]),
                    DIGIT_0..DIGIT_0 + 10,
                    proptest::arbitrary::any::<u8>(),
                ],
                0..40,
            ),
            lost in proptest::collection::vec(proptest::arbitrary::any::<bool>(), 40),
        ) {
            let mut kb = Keyboard::new(panel);
            for (k, lose) in keys.into_iter().zip(lost) {
                if lose && k % 7 == 0 {
                    kb.key_lost();
                }
                if let Outcome::Command(c) = kb.key(k) {
                    proptest::prop_assert!(allowed(panel, c), "{:?} at {:?}", c, panel);
                }
                let shown = kb.display();
                proptest::prop_assert!(shown.positions.iter().all(|&p| p <= BLANK));
            }
        }
    }

    #[test]
    fn entries_that_make_no_command() {
        let d = PanelId::Desk(0);
        assert_eq!(run(d, &[ENTER]), vec![Outcome::Refused]);
        assert_eq!(run(d, &[0x31, NEXT, 0x32, ENTER]), vec![Outcome::Refused]);
        assert_eq!(
            run(d, &[POSTCODE, 0x31, 0x32, ENTER]),
            vec![Outcome::Refused]
        );
        assert_eq!(
            run(
                d,
                &[0x31; 7].iter().copied().chain([ENTER]).collect::<Vec<_>>()
            ),
            vec![Outcome::Refused]
        );
        assert_eq!(run(d, &[0x7E]), vec![Outcome::Refused]); // no such key
        assert_eq!(
            run(PanelId::Central, &[ASSIGN, 0x31, NEXT, 0x32, NEXT, ENTER]),
            vec![Outcome::Refused]
        );
        assert_eq!(
            run(PanelId::Central, &[CALENDAR, 0x31, ENTER]),
            vec![Outcome::Refused]
        );
        // CLEAR forgets quietly; a function key starts afresh.
        assert_eq!(
            run(d, &[0x39, 0x39, CLEAR, 0x33, ENTER]),
            vec![Outcome::Command(Command::PostType(3))]
        );
        assert_eq!(
            run(
                d,
                &[0x39, 0x39, POSTCODE, 0x32, 0x31, 0x31, 0x31, 0x39, ENTER]
            ),
            vec![Outcome::Command(Command::Postcode(21119))]
        );
    }

    #[test]
    fn a_lost_key_spoils_its_entry() {
        let mut kb = Keyboard::new(PanelId::Desk(2));
        assert_eq!(kb.key(0x31), Outcome::Nothing);
        kb.key_lost(); // the "2" of "12"
        assert_eq!(kb.key(ENTER), Outcome::Refused);
        assert!(kb.display().refused);
        assert_eq!(kb.key(0x31), Outcome::Nothing);
        assert!(!kb.display().refused);
        assert_eq!(kb.key(ENTER), Outcome::Command(Command::PostType(1)));
    }

    #[test]
    fn the_display_shows_the_entry_as_keyed() {
        let mut kb = Keyboard::new(PanelId::Central);
        for k in [ASSIGN, 0x31, 0x32, NEXT, 0x33] {
            kb.key(k);
        }
        let shown = kb.display();
        assert_eq!(shown.positions, [BLANK, BLANK, 1, 2, BLANK, 3]);
        assert!(shown.keying);
        assert_eq!(shown.function_lamps, 1 << 3);
        assert_eq!(kb.function_key(), Some(ASSIGN));
        kb.key(ENTER);
        assert!(!kb.display().keying);
    }
}
