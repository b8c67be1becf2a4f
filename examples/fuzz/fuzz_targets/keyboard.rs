//! Arbitrary key bytes and lost keys at one of the mailbag plant's panels (the 1977 plant's
//! operator panels, `mailbag-sorter`): the computer's side of the keyboard,
//! `panels::keyboard::Keyboard`, against a model written from its module documentation and the
//! key table of `panels::keys`.
//!
//! Checked after every key: the outcome (nothing yet, a command, refused) is the model's — a
//! command only at ENTER (or LAMP TEST) and only the one the entry spells at this panel (post
//! type `0..14` at a desk, a five-digit postcode at P1/P2, post type NEXT lane at the central
//! desk, lane NEXT stations of the panel's side at A/B, a schedule `0..6` or CALENDAR at the
//! central desk); a key the link lost spoils its entry, so a lost digit never makes another
//! command; a key byte that is no key is refused at once; the ENTRY REFUSED lamp is lit from a
//! refusal until the next key. And every command made is the one its keys (`keys_for`) make on
//! a fresh keyboard of that panel.
#![no_main]

use libfuzzer_sys::fuzz_target;
use regler_examples::mailbag::plant::operator::{Command, PanelId};
use regler_examples::mailbag::plant::panels::keyboard::{Keyboard, Outcome};
use regler_examples::mailbag::plant::panels::keys::{
    ASSIGN, CALENDAR, CLEAR, DIGIT_0, EMPTYING, ENTER, LAMP_TEST, NEXT, POSTCODE, SCHEDULE,
    keys_for,
};

/// The keys, for bytes below 0xC0.
const KEYS: [u8; 19] = [
    DIGIT_0,
    DIGIT_0 + 1,
    DIGIT_0 + 2,
    DIGIT_0 + 3,
    DIGIT_0 + 4,
    DIGIT_0 + 5,
    DIGIT_0 + 6,
    DIGIT_0 + 7,
    DIGIT_0 + 8,
    DIGIT_0 + 9,
    NEXT,
    ENTER,
    CLEAR,
    POSTCODE,
    ASSIGN,
    EMPTYING,
    SCHEDULE,
    CALENDAR,
    LAMP_TEST,
];

/// The entry as the documentation describes it.
#[derive(Default)]
struct Entry {
    function: Option<u8>,
    fields: [Vec<u8>; 2],
    second: bool,
    spoiled: bool,
}

fn number(field: &[u8], min: usize, max: usize) -> Option<u32> {
    (min..=max)
        .contains(&field.len())
        .then(|| field.iter().fold(0, |n, &d| n * 10 + u32::from(d)))
}

fn small(field: &[u8], below: u8) -> Option<u8> {
    number(field, 1, 2)
        .and_then(|n| u8::try_from(n).ok())
        .filter(|&n| n < below)
}

impl Entry {
    fn command(&self, panel: PanelId) -> Option<Command> {
        if self.spoiled {
            return None;
        }
        let [first, second] = &self.fields;
        match (self.function, panel, self.second) {
            (None, PanelId::Desk(_), false) => small(first, 14).map(Command::PostType),
            (Some(POSTCODE), PanelId::Desk(0 | 1), false) => {
                number(first, 5, 5).map(Command::Postcode)
            }
            (Some(ASSIGN), PanelId::Central, true) => Some(Command::AssignType {
                post_type: small(first, 14)?,
                lane: small(second, 15)?,
            }),
            (Some(EMPTYING), PanelId::A | PanelId::B, true) => {
                // A1–A3 are stations 0–2 (panel A); B1, B2, C1, C2 are 3–6 (panel B).
                let side = if panel == PanelId::A { 0..3 } else { 3..7 };
                if second.len() > 6 || second.iter().any(|s| !side.contains(s)) {
                    return None;
                }
                Some(Command::Emptying {
                    lane: small(first, 15)?,
                    stations: second.iter().fold(0, |m, &s| m | 1 << s),
                })
            }
            (Some(SCHEDULE), PanelId::Central, false) => number(first, 1, 1)
                .filter(|&n| n < 6)
                .map(|n| Command::Schedule(Some(n as u8))),
            (Some(CALENDAR), PanelId::Central, false) if first.is_empty() => {
                Some(Command::Schedule(None))
            }
            _ => None,
        }
    }

    /// The model's outcome of `key` (`None`: a lost key).
    fn key(&mut self, panel: PanelId, key: Option<u8>) -> Outcome {
        let Some(key) = key else {
            self.spoiled = true;
            return Outcome::Nothing;
        };
        match key {
            d if (DIGIT_0..DIGIT_0 + 10).contains(&d) => {
                self.fields[usize::from(self.second)].push(d - DIGIT_0);
                Outcome::Nothing
            }
            NEXT => {
                if self.second || !matches!(self.function, Some(ASSIGN | EMPTYING)) {
                    self.spoiled = true;
                }
                self.second = true;
                Outcome::Nothing
            }
            CLEAR => {
                *self = Entry::default();
                Outcome::Nothing
            }
            LAMP_TEST => {
                *self = Entry::default();
                Outcome::Command(Command::LampTest)
            }
            ENTER => {
                let made = self.command(panel);
                *self = Entry::default();
                made.map_or(Outcome::Refused, Outcome::Command)
            }
            POSTCODE | ASSIGN | EMPTYING | SCHEDULE | CALENDAR => {
                *self = Entry {
                    function: Some(key),
                    ..Entry::default()
                };
                Outcome::Nothing
            }
            _ => {
                *self = Entry::default();
                Outcome::Refused
            }
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&which, mut rest)) = data.split_first() else {
        return;
    };
    let panel = PanelId::ALL[usize::from(which) % PanelId::ALL.len()];
    let mut keyboard = Keyboard::new(panel);
    let mut model = Entry::default();
    while let Some((&b, tail)) = rest.split_first() {
        rest = tail;
        let key = match b {
            0xFF => None,
            0xC0..=0xFE => {
                let Some((&raw, tail)) = rest.split_first() else {
                    break;
                };
                rest = tail;
                Some(raw)
            }
            _ => Some(KEYS[usize::from(b) % KEYS.len()]),
        };
        let got = match key {
            Some(k) => keyboard.key(k),
            None => {
                keyboard.key_lost();
                Outcome::Nothing
            }
        };
        let want = model.key(panel, key);
        assert_eq!(got, want, "panel {panel:?}, key {key:?}");
        if key.is_some() {
            assert_eq!(
                keyboard.display().refused,
                got == Outcome::Refused,
                "ENTRY REFUSED lamp"
            );
        }
        if let Outcome::Command(command) = got {
            let mut keys = Vec::new();
            keys_for(command, &mut keys);
            let mut fresh = Keyboard::new(panel);
            let made: Vec<Outcome> = keys
                .iter()
                .map(|&k| fresh.key(k))
                .filter(|o| *o != Outcome::Nothing)
                .collect();
            assert_eq!(
                made,
                [Outcome::Command(command)],
                "keys_for({command:?}) = {keys:?}"
            );
        }
    }
});
