//! The dock chains, pulse by pulse: initiators, reference marks, sacks falling where a tipper
//! is set as their trolley passes its bin, trolleys leaving the chain's end.

use rand::Rng;

use super::super::layout::{BINS_PER_DOCK, Dest, READERS, chain, io, timing};
use super::{Event, Field, Outcome, Place};

impl Field {
    /// One real pulse of dock `d`'s chain.
    pub(super) fn pulse(&mut self, d: usize, capture: &mut [u16; io::IN_WORDS]) {
        let missed = self.faults.missed_pulse[d];
        let counted = !(missed > 0.0 && self.rng.random_bool(missed.min(1.0)));
        let dock = &mut self.docks[d];
        dock.pulses += 1;
        let p = dock.pulses;
        if counted {
            capture[io::CHAIN_WORD] |= 1 << d;
        }
        if p.is_multiple_of(chain::LOOP_PULSES) {
            capture[io::CHAIN_WORD] |= 1 << (4 + d);
        }
        if p % chain::LOOP_PULSES == dock.dia {
            capture[io::CHAIN_WORD] |= 1 << (8 + d);
        }
        // Sacks fall where a tipper is set as their trolley passes its bin.
        let mut drops = Vec::new();
        for j in 0..BINS_PER_DOCK {
            let b = d * BINS_PER_DOCK + j;
            if self.outputs[io::tipper(b) / 16] >> (io::tipper(b) % 16) & 1 == 1 {
                let dock = &self.docks[d];
                if let Some(hooked) = p.checked_sub(dock.bin_at[j]) {
                    if let Some(&t) = dock.on_chain.get(&hooked) {
                        drops.push((t, b as u8));
                    }
                }
            }
        }
        for (t, b) in drops {
            if let Some(sack) = self.sacks[usize::from(t)] {
                let right = sack.right == Dest::Bin(b);
                if right {
                    self.counts.delivered_sorted += 1;
                }
                let outcome = if right {
                    Outcome::Delivered
                } else {
                    Outcome::Misdelivered
                };
                self.end(t, Place::Bin(b), outcome);
            }
        }
        // Trolleys past the last bin leave the chain: a sack still on goes to the manual station.
        while let Some((&hooked, &t)) = self.docks[d].on_chain.first_key_value() {
            if p.saturating_sub(hooked) < chain::END_PULSES {
                break;
            }
            self.docks[d].on_chain.pop_first();
            self.at(
                self.now_ms + timing::MANUAL_MS,
                Event::AtManual {
                    trolley: t,
                    from: READERS,
                },
            );
        }
    }
}
