//! Workloads of the scan-cycle benches: the timer register in steady state, and one full cycle
//! at the 1977 plant's sizes (544 inputs, 240 outputs).

use regler_scan_cycle::{CycleConfig, Executive, Io, TimerQueue};

/// The source's method: every entry counted down on every tick.
pub struct CountDownTimers {
    entries: Vec<(u32, u32)>,
}

impl CountDownTimers {
    /// `n` timers, one expiring per tick, each re-armed with delay `n` when it fires.
    #[must_use]
    pub fn steady(n: u32) -> CountDownTimers {
        CountDownTimers {
            entries: (1..=n).map(|d| (d, d)).collect(),
        }
    }

    /// One tick; returns the actions that fired (and re-arms them).
    pub fn tick(&mut self) -> u32 {
        let n = u32::try_from(self.entries.len()).unwrap_or(u32::MAX);
        let mut fired = 0;
        for e in &mut self.entries {
            e.0 -= 1;
            if e.0 == 0 {
                fired += e.1;
                e.0 = n;
            }
        }
        fired
    }
}

/// regler's queue in the same steady state.
pub struct WheelTimers<const N: usize> {
    queue: TimerQueue<u32, N>,
    n: u32,
}

impl<const N: usize> WheelTimers<N> {
    /// `n` (≤ N) timers, one expiring per tick.
    ///
    /// # Panics
    /// If `n` exceeds `N`.
    #[must_use]
    pub fn steady(n: u32) -> WheelTimers<N> {
        let mut queue = TimerQueue::new();
        for d in 1..=n {
            queue.insert(d, d).expect("n <= N");
        }
        WheelTimers { queue, n }
    }

    /// One tick; returns the actions that fired (and re-arms them).
    ///
    /// # Panics
    /// Never: a fired timer frees the place it is re-armed in.
    pub fn tick(&mut self) -> u32 {
        let mut fired = [0u32; 4];
        let mut k = 0;
        self.queue.tick(|a| {
            if let Some(slot) = fired.get_mut(k) {
                *slot = a;
            }
            k += 1;
        });
        let mut sum = 0;
        for &a in fired.iter().take(k) {
            self.queue.insert(self.n, a).expect("room after an expiry");
            sum += a;
        }
        sum
    }
}

/// Input words of the 1977 plant.
pub const INPUT_WORDS: usize = 34;
/// Output words of the 1977 plant.
pub const OUTPUT_WORDS: usize = 15;

/// A plant that changes a few inputs every cycle.
pub struct Plant1977 {
    inputs: [u16; INPUT_WORDS],
    /// The outputs last written.
    pub outputs: [u16; OUTPUT_WORDS],
    t: u32,
}

impl Io<INPUT_WORDS, OUTPUT_WORDS> for Plant1977 {
    fn read_inputs(&mut self, raw: &mut [u16; INPUT_WORDS]) {
        self.t = self.t.wrapping_add(1);
        let w = (self.t as usize) % INPUT_WORDS;
        self.inputs[w] ^= 1 << (self.t % 16);
        *raw = self.inputs;
    }
    fn write_outputs(&mut self, out: &[u16; OUTPUT_WORDS]) {
        self.outputs = *out;
    }
    fn now_us(&mut self) -> u32 {
        self.t.wrapping_mul(50_000)
    }
}

impl Default for Plant1977 {
    fn default() -> Self {
        Plant1977 {
            inputs: [0x5A5A; INPUT_WORDS],
            outputs: [0; OUTPUT_WORDS],
            t: 0,
        }
    }
}

/// The executive at the 1977 sizes with every input debounced (k = 3), a latched input word and
/// forced points on both sides.
///
/// # Panics
/// Never: the points are within the images.
#[must_use]
pub fn executive_1977() -> Executive<INPUT_WORDS, OUTPUT_WORDS> {
    let mut plc = Executive::new(CycleConfig::source());
    // The first 16 inputs are latched (count 1: a latched input is not debounced), the rest
    // need three equal readings; the bit-sliced cycle costs the same whatever the counts.
    for p in 16..INPUT_WORDS * 16 {
        plc.conditioning_mut()
            .set_debounce(p, 3)
            .expect("point in range");
    }
    for p in 0..16 {
        plc.conditioning_mut()
            .set_latched(p, true)
            .expect("point in range");
    }
    for p in [3, 100, 543] {
        plc.force_input(p, true).expect("point in range");
    }
    for p in [7, 239] {
        plc.force_output(p, false).expect("point in range");
    }
    plc
}

/// One cycle with a program that maps input words onto outputs as a sorting program's tests
/// would (a few dozen bit operations).
///
/// # Panics
/// Never: the executive is running.
pub fn cycle_1977(plc: &mut Executive<INPUT_WORDS, OUTPUT_WORDS>, plant: &mut Plant1977) {
    plc.cycle(plant, |scan| {
        for o in 0..OUTPUT_WORDS {
            let a = scan.inputs.word(2 * o).unwrap_or(0);
            let b = scan.inputs.word(2 * o + 1).unwrap_or(0);
            let prev = scan.previous.word(o).unwrap_or(0);
            let _ = scan.outputs.set_word(o, (a & !b) | (prev & b));
        }
    })
    .expect("running");
}
