//! The knitted fabric as a PNG: every machine's last rows side by side, with a title that says
//! what and which run, each machine's number, speed and rows, and a legend. Text is set in a
//! small built-in 5 × 7 bitmap font (capitals, digits and a few signs): the picture needs no
//! system font and no further crate.

use std::path::Path;

use super::boards::{Board, RowSource};
use super::summary::Summary;
use crate::cli::number;

/// Yarn colours 0–3 of the master's jacquard: ecru, navy, crimson, black.
const YARN: [[u8; 3]; 4] = [[245, 240, 225], [40, 70, 150], [190, 40, 60], [30, 30, 30]];
/// The ROM's stripes (stand-alone) in greys: colour 0 light, colour 2 dark.
const ROM: [[u8; 3]; 4] = [
    [205, 205, 205],
    [160, 160, 160],
    [120, 120, 120],
    [90, 90, 90],
];
/// A needle that did not get the master's byte (an underrun or a fallback), and the stripe of a
/// row that has such needles: the one colour for "missed the master's byte".
const MISSED: [u8; 3] = [255, 0, 255];
/// Stripe of a whole row from the master.
const FROM_MASTER: [u8; 3] = [60, 170, 80];
/// Stripe of a row from the ROM.
const FROM_ROM: [u8; 3] = [150, 150, 150];
const INK: [u8; 3] = [20, 20, 20];
const PAPER: [u8; 3] = [255, 255, 255];

/// Pixels per needle and per row.
const SCALE: usize = 2;
/// Space between machines and around the picture.
const GAP: usize = 10;
/// The row-source stripe left of each machine's fabric.
const STRIPE: usize = 4;
/// Text: the font's pixels drawn 2 × 2, 6 font pixels a character (one of space), 9 a line.
const TEXT: usize = 2;
const ADVANCE: usize = 6 * TEXT;
const LINE: usize = 10 * TEXT;
const MARGIN: usize = 16;

/// Writes the fabric of every machine as a PNG: one column per machine, one pixel row per
/// knitted row (the last `max_rows`, newest at the bottom), needles across; a stripe left of
/// each column says where each row came from. Title, machine labels and legend as text.
///
/// # Errors
/// An I/O or encoding error, naming `--picture` and the path.
pub fn write_png(
    path: &Path,
    summary: &Summary,
    boards: &[Board],
    max_rows: usize,
) -> Result<(), crate::cli::Stop> {
    let needles = boards.first().map_or(0, |b| usize::from(b.needles()));
    let rows = boards
        .iter()
        .map(|b| b.rows.len().min(max_rows))
        .max()
        .unwrap_or(0)
        .max(1);
    let column = STRIPE + needles * SCALE;
    let fabric_width = boards.len() * (column + GAP) - GAP;
    let title = title(summary, max_rows);
    let legend = legend();
    let title_width = title.iter().map(|t| text_width(t)).max().unwrap_or(0);
    let width = (fabric_width.max(title_width).max(900)) + 2 * MARGIN;
    let legend_lines = flow(&legend, width - 2 * MARGIN).len();
    let top = MARGIN + title.len() * LINE + GAP;
    let fabric_top = top + LINE;
    let fabric_bottom = fabric_top + rows * SCALE;
    let legend_top = fabric_bottom + LINE + GAP;
    let height = legend_top + legend_lines * (LINE + 4) + MARGIN;
    let mut c = Canvas::new(width, height);

    for (i, line) in title.iter().enumerate() {
        c.text(MARGIN, MARGIN + i * LINE, line);
    }
    for (i, board) in boards.iter().enumerate() {
        let x0 = MARGIN + i * (column + GAP);
        let label = format!("MACHINE {}, {} RPM", board.index + 1, board.rpm);
        let label = if text_width(&label) <= column + GAP {
            label
        } else {
            format!("{}", board.index + 1)
        };
        c.text(x0, top, &label);
        let first = board.rows.len().saturating_sub(max_rows);
        for (r, row) in board.rows[first..].iter().enumerate() {
            let stripe = match row.source {
                RowSource::Master(_) => FROM_MASTER,
                RowSource::Local => FROM_ROM,
                RowSource::Patched => MISSED,
            };
            let y = fabric_top + r * SCALE;
            c.fill(x0, y, STRIPE - 1, SCALE, stripe);
            for (n, &colour) in row.needles.iter().enumerate() {
                let rgb = if colour & 0x80 != 0 {
                    MISSED
                } else if row.source == RowSource::Local {
                    ROM[usize::from(colour & 3)]
                } else {
                    YARN[usize::from(colour & 3)]
                };
                c.fill(x0 + STRIPE + n * SCALE, y, SCALE, SCALE, rgb);
            }
        }
        let span = if board.rows.is_empty() {
            "NO ROWS".to_string()
        } else {
            format!("ROWS {}-{}", first + 1, board.rows.len())
        };
        if text_width(&span) <= column + GAP {
            c.text(x0, fabric_bottom + 4, &span);
        }
    }
    for (i, line) in flow(&legend, width - 2 * MARGIN).iter().enumerate() {
        let y = legend_top + i * (LINE + 4);
        let mut x = MARGIN;
        for item in line {
            match item {
                Item::Text(t) => {
                    c.text(x, y, t);
                    x += text_width(t) + ADVANCE;
                }
                Item::Swatches(colours) => {
                    for &rgb in colours {
                        c.fill(x, y, 14, 14, INK);
                        c.fill(x + 1, y + 1, 12, 12, rgb);
                        x += 16;
                    }
                    x += 4;
                }
            }
        }
    }
    c.write(path)
}

/// The title: what the picture shows, and which run.
fn title(s: &Summary, max_rows: usize) -> Vec<String> {
    let cfg = &s.config;
    let mut run = format!(
        "SEED {}, {} S {}, {} NEEDLES, {} NS A BYTE, LOSS {}, DUPLICATE {}",
        cfg.seed,
        number(cfg.seconds),
        s.transport,
        cfg.needles,
        cfg.byte_ns,
        number(cfg.loss),
        number(cfg.duplicate)
    );
    if let Some((from, len)) = cfg.master_fault {
        run.push_str(&format!(
            ", MASTER SILENT FROM {} S FOR {} S",
            number(from),
            number(len)
        ));
    }
    vec![
        format!(
            "JACQUARD-KNITTER: THE FABRIC OF {} MACHINES, AT MOST THE LAST {max_rows} ROWS OF EACH, \
             NEWEST AT THE BOTTOM",
            cfg.machines
        ),
        run.to_uppercase(),
    ]
}

/// One thing in the legend: a run of colour swatches or a text.
enum Item {
    Swatches(Vec<[u8; 3]>),
    Text(String),
}

/// The legend: entries of swatches and their meaning, in groups (a group is not split).
fn legend() -> Vec<Vec<Item>> {
    let t = |s: &str| Item::Text(s.to_string());
    vec![
        vec![t("FABRIC:")],
        vec![
            Item::Swatches(YARN.to_vec()),
            t("YARN 1-4 FROM THE MASTER,"),
        ],
        vec![
            Item::Swatches(vec![ROM[0], ROM[2]]),
            t("ROM STRIPES (STAND-ALONE),"),
        ],
        vec![
            Item::Swatches(vec![MISSED]),
            t("NEEDLE THAT MISSED THE MASTER'S BYTE."),
        ],
        vec![t("STRIPE LEFT OF EACH MACHINE:")],
        vec![Item::Swatches(vec![FROM_MASTER]), t("ROW FROM THE MASTER,")],
        vec![Item::Swatches(vec![FROM_ROM]), t("ROW FROM THE ROM,")],
        vec![
            Item::Swatches(vec![MISSED]),
            t("ROW WITH NEEDLES THAT MISSED THE MASTER'S BYTE."),
        ],
    ]
}

fn item_width(item: &Item) -> usize {
    match item {
        Item::Text(t) => text_width(t) + ADVANCE,
        Item::Swatches(c) => 16 * c.len() + 4,
    }
}

/// The legend's groups in lines no wider than `width`; "STRIPE …" starts a new line.
fn flow(groups: &[Vec<Item>], width: usize) -> Vec<Vec<&Item>> {
    let mut lines: Vec<Vec<&Item>> = vec![Vec::new()];
    let mut x = 0;
    for group in groups {
        let w: usize = group.iter().map(item_width).sum();
        let heading = matches!(group.as_slice(), [Item::Text(t)] if t.starts_with("STRIPE"));
        if (x > 0 && x + w > width) || heading {
            lines.push(Vec::new());
            x = 0;
        }
        if let Some(line) = lines.last_mut() {
            line.extend(group.iter());
        }
        x += w;
    }
    lines
}

/// Pixels of `text` set in the font.
fn text_width(text: &str) -> usize {
    text.chars().count() * ADVANCE
}

/// An RGB picture being drawn.
struct Canvas {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
}

impl Canvas {
    fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: PAPER.repeat(width * height),
        }
    }

    fn fill(&mut self, x: usize, y: usize, w: usize, h: usize, rgb: [u8; 3]) {
        for yy in y..(y + h).min(self.height) {
            for xx in x..(x + w).min(self.width) {
                let at = (yy * self.width + xx) * 3;
                self.pixels[at..at + 3].copy_from_slice(&rgb);
            }
        }
    }

    /// `text` with its top left at (x, y).
    fn text(&mut self, x: usize, y: usize, text: &str) {
        for (i, ch) in text.chars().enumerate() {
            let rows = glyph(ch).unwrap_or(glyph('?').unwrap_or([0; 7]));
            for (r, bits) in rows.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        self.fill(x + i * ADVANCE + col * TEXT, y + r * TEXT, TEXT, TEXT, INK);
                    }
                }
            }
        }
    }

    fn write(&self, path: &Path) -> Result<(), crate::cli::Stop> {
        let cannot = |e: &dyn std::fmt::Display| format!("cannot encode the picture: {e}");
        let mut png = Vec::new();
        let mut encoder = png::Encoder::new(
            &mut png,
            u32::try_from(self.width).map_err(|_| "the picture is too wide")?,
            u32::try_from(self.height).map_err(|_| "the picture is too high")?,
        );
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Best);
        let mut writer = encoder.write_header().map_err(|e| cannot(&e))?;
        writer
            .write_image_data(&self.pixels)
            .map_err(|e| cannot(&e))?;
        writer.finish().map_err(|e| cannot(&e))?;
        crate::cli::write_picture(path, png)
    }
}

/// The 5 × 7 glyph of `ch` (rows top down, bit 4 the leftmost pixel): capitals (small letters
/// are set as capitals), digits, space and `- : , . ( ) / % ' + = ? < > _`.
#[must_use]
pub fn glyph(ch: char) -> Option<[u8; 7]> {
    Some(match ch.to_ascii_uppercase() {
        ' ' => [0; 7],
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        '-' => [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00],
        ':' => [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00],
        ',' => [0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '/' => [0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '\'' => [0x0C, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00],
        '+' => [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00],
        '=' => [0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00],
        '?' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04],
        '<' => [0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02],
        '>' => [0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08],
        '_' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F],
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knitter::{Config, Sim};

    /// Every character the picture writes has a glyph (none falls back to `?`).
    #[test]
    fn the_font_has_every_character_the_picture_writes() {
        let config = Config {
            seconds: 0.5,
            master_fault: Some((0.1, 0.2)),
            loss: 0.01,
            ..Config::default()
        };
        let mut sim = Sim::new(config, Vec::new()).unwrap();
        sim.run_until(1_000_000_000);
        let mut texts = title(&sim.summary(), 300);
        for group in legend() {
            for item in group {
                if let Item::Text(t) = item {
                    texts.push(t);
                }
            }
        }
        texts.push("MACHINE 100, 140 RPM ROWS 1-300 NO ROWS".into());
        for t in texts {
            for ch in t.chars() {
                assert!(glyph(ch).is_some(), "no glyph for {ch:?} in {t}");
            }
        }
    }

    /// No two meanings share a colour: yarns, ROM greys, missed bytes and the stripes.
    #[test]
    fn each_colour_has_one_meaning() {
        let fabric: Vec<[u8; 3]> = YARN
            .iter()
            .chain(ROM.iter())
            .copied()
            .chain([MISSED])
            .collect();
        for (i, a) in fabric.iter().enumerate() {
            for b in &fabric[i + 1..] {
                assert_ne!(a, b);
            }
        }
        for stripe in [FROM_MASTER, FROM_ROM] {
            assert!(!YARN.contains(&stripe) && stripe != MISSED);
        }
    }
}
