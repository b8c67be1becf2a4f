//! An operator's hands at one panel: the keys still to press, when the next one goes down, and
//! what the operator does when the panel restarts under their fingers.
//!
//! The operator presses one key at a time at a human pace (the caller draws it). A panel holds
//! up to [`KEY_QUEUE`] keys the computer has not taken; when it is full the operator waits.
//!
//! **A panel that restarts** (its power fails and comes back) forgets the keys it held, and the
//! computer cannot see that: it would join what it took of the entry to what the operator keys
//! next, and could make a command nobody keyed. The operator sees the panel go dark and come
//! back; they press CLEAR and key again, whole, the command whose keys were lost, then go on
//! with the keys the panel lost of later commands and those not pressed yet.

use std::collections::VecDeque;

use regler_panel_link::panel::KEY_QUEUE;

use super::super::operator::Command;
use super::keys::{CLEAR, keys_for};

/// One operator's keys at one panel; keys are tagged with the number of the command they key.
#[derive(Clone, Debug, Default)]
pub(super) struct Typist {
    /// Keys still to press.
    keys: VecDeque<(u64, u8)>,
    /// The last keys pressed (at most [`KEY_QUEUE`]: the panel may still hold them).
    pressed: VecDeque<(u64, u8)>,
    /// Commands with keys still to press or held by the panel.
    typed: VecDeque<(u64, Command)>,
    next_id: u64,
    /// When the next key goes down.
    next_ms: u64,
}

impl Typist {
    /// No key left to press.
    pub(super) fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// The operator starts keying `command` (after what they are still keying); the first key
    /// goes down `pace_ms` from `now_ms` if nothing was waiting.
    pub(super) fn type_in(&mut self, command: Command, now_ms: u64, pace_ms: u64) {
        if self.keys.is_empty() {
            self.next_ms = now_ms.saturating_add(pace_ms);
        }
        let id = self.next_id;
        self.next_id += 1;
        let mut keys = Vec::new();
        keys_for(command, &mut keys);
        self.keys.extend(keys.into_iter().map(|k| (id, k)));
        self.typed.push_back((id, command));
    }

    /// The key due at `now_ms`, if any.
    pub(super) fn due(&self, now_ms: u64) -> Option<u8> {
        self.keys
            .front()
            .filter(|_| now_ms >= self.next_ms)
            .map(|&(_, key)| key)
    }

    /// The due key went down; the next one `pace_ms` later.
    pub(super) fn pressed(&mut self, now_ms: u64, pace_ms: u64) {
        if let Some(key) = self.keys.pop_front() {
            if self.pressed.len() == KEY_QUEUE {
                self.pressed.pop_front();
            }
            self.pressed.push_back(key);
        }
        self.next_ms = now_ms.saturating_add(pace_ms);
        // Commands no longer keyed nor held are done.
        let oldest = self
            .pressed
            .front()
            .or(self.keys.front())
            .map(|&(id, _)| id);
        while self
            .typed
            .front()
            .is_some_and(|&(id, _)| oldest.is_none_or(|o| id < o))
        {
            self.typed.pop_front();
        }
    }

    /// The panel restarted and lost the `lost` keys it held that the computer had not taken
    /// (the last pressed): from `pace_ms` after `now_ms` (the operator sees it), CLEAR, the
    /// first command hit keyed again whole, then the lost keys of later commands and the rest.
    pub(super) fn panel_restarted(&mut self, lost: usize, now_ms: u64, pace_ms: u64) {
        let lost: Vec<(u64, u8)> = self
            .pressed
            .iter()
            .skip(self.pressed.len().saturating_sub(lost))
            .copied()
            .collect();
        self.pressed.clear();
        let Some(&(first, _)) = lost.first() else {
            return;
        };
        self.next_ms = now_ms.saturating_add(pace_ms);
        let Some(&(_, command)) = self.typed.iter().find(|&&(id, _)| id == first) else {
            return;
        };
        let mut again = vec![(first, CLEAR)];
        let mut keys = Vec::new();
        keys_for(command, &mut keys);
        again.extend(keys.into_iter().map(|k| (first, k)));
        again.extend(lost.into_iter().filter(|&(id, _)| id != first));
        again.extend(self.keys.drain(..).filter(|&(id, _)| id != first));
        self.keys = again.into();
    }
}
