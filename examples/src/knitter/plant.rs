//! The plant: knitting machines turning at their own speeds, and the jacquard designs a job
//! knits (the master's) or the board's ROM stripes (stand-alone).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::Config;

/// Colour (0–3) of needle `col` in row `row` of job `job`: four jacquard designs, so a shifted,
/// lost or repeated row shows as a break in the pattern.
#[must_use]
pub fn pattern(job: u32, row: u64, col: u16) -> u8 {
    let (r, c) = (row as i64, i64::from(col));
    match job % 4 {
        // Argyle diamonds with a diagonal over-check.
        0 => {
            let (dr, dc) = ((r % 32) - 16, (c % 32) - 16);
            if (r + c) % 16 == 0 || (r - c).rem_euclid(16) == 0 {
                3
            } else if dr.abs() + dc.abs() < 14 {
                1
            } else {
                0
            }
        }
        // Zig-zag bands.
        1 => (((r + (c % 20 - 10).abs()) / 5) % 3) as u8,
        // Checks with a dot.
        2 => {
            let check = ((r / 8) + (c / 8)) % 2;
            if r % 8 == 4 && c % 8 == 4 {
                3
            } else {
                check as u8
            }
        }
        // Hearts-ish: concentric rings.
        _ => {
            let (dr, dc) = ((r % 24) - 12, (c % 24) - 12);
            (((dr * dr + dc * dc) / 30) % 3) as u8 + u8::from(job % 8 >= 4)
        }
    }
}

/// The board's ROM pattern (stand-alone): plain stripes, recognisably not a jacquard.
#[must_use]
pub fn rom_pattern(row: u32, _col: u16) -> u8 {
    if row % 4 < 2 { 2 } else { 0 }
}

/// Machine speeds for a seed: 120–140 rpm.
#[must_use]
pub fn speeds(config: &Config) -> Vec<u32> {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    (0..config.machines)
        .map(|_| rng.random_range(120..=140))
        .collect()
}
