//! The code readers' routines: a passage's scans, its verdict (the first scan, or the vote),
//! the registry's route and the switch; time supervision toward the next reader.

use regler_scan_cycle::Scan;
use regler_trolley_id::{NoRead, Passage, Route, TrolleyId, Verdict, decode};

use super::super::layout::{
    BINS_PER_DOCK, Dest, EXITS, R_CHAIN, R_EMPTYING, R_MAIN, READER_NAMES, exit_toward, io,
};
use super::{
    Control, IW, OW, PORTION, PRESENCE_LIMIT_CYCLES, Reading, SUPERVISE_TICKS, SWITCH_HOLD_TICKS,
    Timer, cost,
};

impl Control {
    /// The passage's verdict as this program reads: the first scan, or the vote.
    pub(super) fn verdict(&mut self, r: usize, first: Option<u16>) -> Passage {
        let voted = self.voters[r].finish();
        let passage = match self.reading {
            Reading::Voting => voted,
            Reading::ParityOnly => {
                let raw = first.unwrap_or(0);
                let verdict = match decode(raw) {
                    Ok(id) => Verdict::Identified(id),
                    Err(e) => Verdict::NoRead(NoRead::Undecodable(e)),
                };
                Passage {
                    verdict,
                    samples: 1,
                    ..voted
                }
            }
        };
        self.passages += 1;
        if self.health[r].record(&voted).is_some() {
            let on = self.health[r].alarm();
            if on {
                self.alarms_raised += 1;
            }
            let text = format!(
                "{} reader {} alarm {}",
                self.stamp(),
                READER_NAMES[r],
                if on { "raised" } else { "cleared" }
            );
            self.print(text);
        }
        passage
    }

    pub(super) fn supervise(&mut self, id: TrolleyId, next: usize) {
        let t = id.get();
        if let Some((old, _)) = self.supervision[usize::from(t)].take() {
            self.timers.remove(old);
        }
        if let Ok(timer) = self
            .timers
            .insert(SUPERVISE_TICKS, Timer::Supervise { trolley: t, next })
        {
            self.supervision[usize::from(t)] = Some((timer, next));
        }
    }

    /// Reader `r`'s switch to its safe position: no exit set, the reject gate shut (a trolley
    /// runs to the manual station; at a chain's reader it runs onto the chain untracked, to the
    /// manual station at the chain's end).
    pub(super) fn safe_switch(&mut self, r: usize, scan: &mut Scan<'_, IW, OW>) {
        for e in 0..EXITS[r] {
            let _ = scan.outputs.set(io::switch(r, e), false);
        }
        let _ = scan.outputs.set(io::reject(r), false);
    }

    /// The switch of `r` was set for the passage just judged: it goes back to its safe
    /// position once that trolley has passed it.
    fn hold_switch(&mut self, r: usize) {
        if let Some(old) = self.switch_timer[r].take() {
            self.timers.remove(old);
        }
        if let Ok(timer) = self.timers.insert(SWITCH_HOLD_TICKS, Timer::SafeSwitch(r)) {
            self.switch_timer[r] = Some(timer);
        }
    }

    /// Reader `r`'s presence input found faulty (`on`) or well again: the report on the
    /// teletype, the reader's alarm (shown with the health alarms), its switch safe.
    pub(super) fn set_presence_fault(&mut self, r: usize, on: bool) {
        self.presence_fault[r] = on;
        let text = if on {
            self.supervision_faults += 1;
            let what = if r < R_MAIN {
                "on without a trolley's code: input faulty, alarm raised"
            } else {
                "on too long: input faulty, alarm raised, switch safe"
            };
            format!(
                "{} reader {} presence input {what}",
                self.stamp(),
                READER_NAMES[r]
            )
        } else {
            format!(
                "{} reader {} presence input off again, alarm cleared",
                self.stamp(),
                READER_NAMES[r]
            )
        };
        self.print(text);
    }

    /// A reader on the rails: samples while the trolley is present, judges at the passage's
    /// end and sets the switch toward the destination (or the reject gate) for that passage
    /// only: it goes back to safe once the trolley has passed. A presence input on too long is
    /// a fault (reported, the switch safe, no passage judged until it goes off).
    pub(super) fn reader(&mut self, r: usize, scan: &mut Scan<'_, IW, OW>) {
        let present = scan.inputs.get(io::present(r));
        if present {
            self.presence_on[r] = self.presence_on[r].saturating_add(1);
            if self.presence_fault[r] {
                return;
            }
            if self.presence_on[r] > PRESENCE_LIMIT_CYCLES {
                // On longer than any passage: the input is faulty. The passage is dropped,
                // unjudged; the switch stays safe.
                self.set_presence_fault(r, true);
                self.in_passage[r] = false;
                self.first[r] = None;
                let _ = self.voters[r].finish();
                if let Some(old) = self.switch_timer[r].take() {
                    self.timers.remove(old);
                }
                self.safe_switch(r, scan);
                return;
            }
            self.spend(cost::SAMPLE_US);
            let cams = scan.inputs.word(r).unwrap_or(0) & io::CAMS;
            if !self.in_passage[r] {
                self.in_passage[r] = true;
                self.first[r] = Some(cams);
            }
            self.voters[r].sample(cams);
            return;
        }
        self.presence_on[r] = 0;
        if self.presence_fault[r] {
            self.set_presence_fault(r, false);
        }
        if !self.in_passage[r] {
            return;
        }
        self.in_passage[r] = false;
        self.spend(cost::VERDICT_US);
        let first = self.first[r].take();
        let passage = self.verdict(r, first);
        if let Some(id) = passage.verdict.trolley() {
            // Seen where it was expected: its supervision ends. Seen elsewhere, the timer runs
            // on and reports it missing at the reader it was sent to.
            let t = usize::from(id.get());
            if let Some((timer, next)) = self.supervision[t] {
                if next == r {
                    self.supervision[t] = None;
                    self.timers.remove(timer);
                }
            }
        }
        if r == R_EMPTYING {
            // A passage at R9: the oldest lane exit's supervision ends.
            if let Some(timer) = self.to_r9.pop_front() {
                self.timers.remove(timer);
            }
        }
        self.safe_switch(r, scan);
        // Whatever the passage's route, the switch (or the reject gate) goes back to safe
        // once this trolley has passed.
        self.hold_switch(r);
        let route = self.registry.route(&passage.verdict, |&dest| match dest {
            Dest::Lane(_) => r == R_EMPTYING || exit_toward(r, dest).is_some(),
            Dest::Bin(b) => {
                if r >= R_CHAIN {
                    usize::from(b) / BINS_PER_DOCK == r - R_CHAIN
                } else {
                    exit_toward(r, dest).is_some()
                }
            }
        });
        match route {
            Route::Deliver {
                trolley,
                destination,
            } => {
                if r >= R_CHAIN {
                    let Dest::Bin(b) = destination else { return };
                    let d = r - R_CHAIN;
                    self.registry.release(trolley);
                    if self.trackers[d]
                        .enter(trolley.get(), usize::from(b) % BINS_PER_DOCK)
                        .is_err()
                    {
                        self.reject(r, scan);
                    }
                    return;
                }
                let exit = if r == R_EMPTYING {
                    let Dest::Lane(l) = destination else { return };
                    if self.routed_lane[usize::from(trolley.get())].take() != Some(l) {
                        // Not switched into its lane by this program (a switch not judged for
                        // it, a misread at R6 or R7): off its way, to the manual station.
                        self.supervision_faults += 1;
                        let text = format!(
                            "{} trolley {} at R9 not from its lane {}: rejected",
                            self.stamp(),
                            trolley.get(),
                            super::super::operator::lane_name(l)
                        );
                        self.print(text);
                        self.reject(r, scan);
                        return;
                    }
                    self.registry.release(trolley);
                    self.station_for(usize::from(l))
                } else {
                    exit_toward(r, destination)
                };
                match exit {
                    Some(e) => {
                        let _ = scan.outputs.set(io::switch(r, e), true);
                        match super::super::layout::next(r, e) {
                            Some(super::super::layout::Next::Reader(n)) => {
                                self.supervise(trolley, n);
                            }
                            Some(super::super::layout::Next::Lane(l)) => {
                                self.routed_lane[usize::from(trolley.get())] = Some(l);
                            }
                            _ => {}
                        }
                    }
                    None => self.reject(r, scan),
                }
            }
            Route::Reject(_) => self.reject(r, scan),
        }
    }

    pub(super) fn reject(&mut self, r: usize, scan: &mut Scan<'_, IW, OW>) {
        self.rejected_by[r] += 1;
        let _ = scan.outputs.set(io::reject(r), true);
    }

    /// The emptying station for the next trolley of lane `l`: its stations in turn, a
    /// portion of [`PORTION`] trolleys each.
    pub(super) fn station_for(&mut self, l: usize) -> Option<usize> {
        let stations = self.emptying[l];
        let n = stations.count_ones();
        if n == 0 {
            return None;
        }
        let k = (self.through_r9[l] / PORTION) % n;
        self.through_r9[l] += 1;
        (0..7).filter(|s| stations >> s & 1 == 1).nth(k as usize)
    }
}
