//! The panels' keys: the key code table and the keys an operator presses for a [`Command`]
//! ([`keys_for`]). The computer's side of each keyboard is in [`super::keyboard`].
//!
//! # Key codes (the byte a panel sends for a key)
//! | key | byte | what it does |
//! |---|---|---|
//! | `0`–`9` | `0x30`–`0x39` | a digit of the field being keyed |
//! | NEXT | `0x2C` | ends the first field (post type, lane), starts the second (lane, stations) |
//! | ENTER | `0x0D` | the entry is complete: the computer makes a command of it or refuses it |
//! | CLEAR | `0x18` | forgets the entry (not counted as refused) |
//! | POSTCODE | `0x50` | P1/P2: the digits that follow are a postcode (exactly five) |
//! | ASSIGN | `0x41` | central: post type NEXT lane ENTER |
//! | EMPTYING | `0x45` | A/B: lane NEXT stations ENTER (one digit per emptying station, none = stop emptying the lane) |
//! | SCHEDULE | `0x53` | central: schedule (one digit) ENTER |
//! | CALENDAR | `0x4B` | central: CALENDAR ENTER = follow the calendar's minute table again |
//! | LAMP TEST | `0x54` | any panel: a command by itself |
//!
//! Without a function key, digits ENTER at a loading desk is a post type. Numbers are the plant's
//! numbering (`operator`): post types `0..14`, lanes `0..15` (D1 = 0 … E11 = 14), emptying
//! stations `0..7` (A1 = 0 … C2 = 6), schedules `0..6`.

use super::super::operator::Command;

/// Key byte of digit `0` (digit `d` is `DIGIT_0 + d`).
pub const DIGIT_0: u8 = 0x30;
/// Ends the first field of an entry.
pub const NEXT: u8 = 0x2C;
/// Completes an entry.
pub const ENTER: u8 = 0x0D;
/// Forgets the entry.
pub const CLEAR: u8 = 0x18;
/// The digits that follow are a postcode.
pub const POSTCODE: u8 = 0x50;
/// Post type NEXT lane: a lane assignment.
pub const ASSIGN: u8 = 0x41;
/// Lane NEXT stations: an emptying choice.
pub const EMPTYING: u8 = 0x45;
/// A sorting schedule to run whatever the calendar says.
pub const SCHEDULE: u8 = 0x53;
/// Follow the calendar again.
pub const CALENDAR: u8 = 0x4B;
/// Light every lamp.
pub const LAMP_TEST: u8 = 0x54;

/// Appends the decimal digits of `value` (at least `width` of them, zero-padded).
fn digits(value: u32, width: usize, keys: &mut Vec<u8>) {
    let text = format!("{value:0width$}");
    keys.extend(text.bytes().map(|b| b - b'0' + DIGIT_0));
}

/// The keys an operator presses for `command`, in order (whatever panel they stand at: the
/// computer refuses what the panel cannot take).
pub fn keys_for(command: Command, keys: &mut Vec<u8>) {
    match command {
        Command::PostType(t) => {
            digits(u32::from(t), 1, keys);
            keys.push(ENTER);
        }
        Command::Postcode(code) => {
            keys.push(POSTCODE);
            digits(code, 5, keys);
            keys.push(ENTER);
        }
        Command::AssignType { post_type, lane } => {
            keys.push(ASSIGN);
            digits(u32::from(post_type), 1, keys);
            keys.push(NEXT);
            digits(u32::from(lane), 1, keys);
            keys.push(ENTER);
        }
        Command::Emptying { lane, stations } => {
            keys.push(EMPTYING);
            digits(u32::from(lane), 1, keys);
            keys.push(NEXT);
            for s in 0..8u8 {
                if stations & (1 << s) != 0 {
                    keys.push(DIGIT_0 + s);
                }
            }
            keys.push(ENTER);
        }
        Command::Schedule(Some(s)) => {
            keys.push(SCHEDULE);
            digits(u32::from(s), 1, keys);
            keys.push(ENTER);
        }
        Command::Schedule(None) => keys.extend([CALENDAR, ENTER]),
        Command::LampTest => keys.push(LAMP_TEST),
    }
}
