//! The code readers' routines: a passage's scans, its verdict (the first scan, or the vote),
//! the registry's route and the switch; time supervision toward the next reader.

use regler_scan_cycle::Scan;
use regler_trolley_id::{NoRead, Passage, Route, TrolleyId, Verdict, decode};

use super::super::layout::{
    BINS_PER_DOCK, Dest, EXITS, R_CHAIN, R_EMPTYING, READER_NAMES, exit_toward, io,
};
use super::{Control, IW, OW, PORTION, Reading, SUPERVISE_TICKS, Timer, cost};

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
        if let Some(old) = self.supervision[usize::from(t)].take() {
            self.timers.remove(old);
        }
        if let Ok(timer) = self
            .timers
            .insert(SUPERVISE_TICKS, Timer::Supervise { trolley: t, next })
        {
            self.supervision[usize::from(t)] = Some(timer);
        }
    }

    /// A reader on the rails: samples while the trolley is present, judges at the passage's
    /// end and sets the switch toward the destination (or the reject gate).
    pub(super) fn reader(&mut self, r: usize, scan: &mut Scan<'_, IW, OW>) {
        let present = scan.inputs.get(io::present(r));
        if present {
            self.spend(cost::SAMPLE_US);
            let cams = scan.inputs.word(r).unwrap_or(0) & io::CAMS;
            if !self.in_passage[r] {
                self.in_passage[r] = true;
                self.first[r] = Some(cams);
            }
            self.voters[r].sample(cams);
            return;
        }
        if !self.in_passage[r] {
            return;
        }
        self.in_passage[r] = false;
        self.spend(cost::VERDICT_US);
        let first = self.first[r].take();
        let passage = self.verdict(r, first);
        if let Some(id) = passage.verdict.trolley() {
            if let Some(timer) = self.supervision[usize::from(id.get())].take() {
                self.timers.remove(timer);
            }
        }
        for e in 0..EXITS[r] {
            let _ = scan.outputs.set(io::switch(r, e), false);
        }
        let _ = scan.outputs.set(io::reject(r), false);
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
                    self.registry.release(trolley);
                    self.station_for(usize::from(l))
                } else {
                    exit_toward(r, destination)
                };
                match exit {
                    Some(e) => {
                        let _ = scan.outputs.set(io::switch(r, e), true);
                        if let Some(super::super::layout::Next::Reader(n)) =
                            super::super::layout::next(r, e)
                        {
                            self.supervise(trolley, n);
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
