//! The command-line layer every example program shares: the common options, checked number
//! arguments with one message style, the progress bar, output that ends quietly on a closed
//! pipe, and the end of `main`.
//!
//! A program names its defaults once ([`Program`]), flattens [`Common`] into its own clap
//! arguments, writes everything for the user through [`print()`] / [`Out`], and returns a
//! [`Stop`] from its `run` to [`finish`]. User-facing text is built with `Display` only — never
//! `{:?}` — so a type's Rust spelling never reaches the user.

use std::fmt;
use std::io::{self, Write};
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use indicatif::{ProgressBar, ProgressStyle};

/// What one example program is called and what it starts from.
pub trait Program: Clone + Send + Sync + 'static {
    /// The binary's name, as error messages begin with it.
    const NAME: &'static str;
    /// The seed of a run without `--seed`.
    const SEED: u64;
    /// Where the picture goes without `--picture`.
    const PICTURE: &'static str;
    /// The picture's format, also accepted as the option's name (`--svg PATH` / `--no-svg`).
    const FORMAT: &'static str;
    /// `--no-` and the format (`no-svg`): an alias of `--no-picture`.
    const NO_FORMAT: &'static str;
}

/// Declares a program's type and its [`Program`] defaults in one line:
/// `regler_examples::program!(Highway, "serial-highway", seed 1976, picture "serial-highway.svg", "svg");`
/// (the last is the picture's format, also accepted as an option name: `--svg` / `--no-svg`).
#[macro_export]
macro_rules! program {
    ($ty:ident, $name:literal, seed $seed:literal, picture $picture:literal, $format:literal) => {
        /// The program's name and defaults for the shared options.
        #[derive(Debug, Clone)]
        struct $ty;

        impl $crate::cli::Program for $ty {
            const NAME: &'static str = $name;
            const SEED: u64 = $seed;
            const PICTURE: &'static str = $picture;
            const FORMAT: &'static str = $format;
            const NO_FORMAT: &'static str = concat!("no-", $format);
        }
    };
}

/// The options every example program takes, flattened into its own (`#[command(flatten)]`).
#[derive(Debug, Clone, clap::Args)]
pub struct Common<P: Program> {
    /// Seed of the run: the same seed gives the same run, figure for figure.
    #[arg(long, default_value_t = P::SEED, allow_hyphen_values = true,
          value_parser = whole(0, u64::MAX))]
    pub seed: u64,
    /// Print the results as JSON on stdout (for machines) instead of the text summary.
    #[arg(long)]
    pub json: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// Where to write the picture.
    #[arg(long = "picture", visible_alias = P::FORMAT, value_name = "PATH",
          default_value = P::PICTURE, conflicts_with = "no_picture")]
    picture: PathBuf,
    /// Write no picture.
    #[arg(long = "no-picture", visible_alias = P::NO_FORMAT)]
    no_picture: bool,
    #[arg(skip)]
    program: PhantomData<P>,
}

impl<P: Program> Common<P> {
    /// The picture's path, or `None` with `--no-picture`.
    #[must_use]
    pub fn picture(&self) -> Option<&Path> {
        (!self.no_picture).then_some(self.picture.as_path())
    }

    /// A progress bar over `len` steps on stderr, hidden with `--quiet` (and by indicatif when
    /// stderr is not a terminal). `what` says what is being done; `unit` follows the counts.
    #[must_use]
    pub fn progress(&self, len: u64, what: &str, unit: &str) -> ProgressBar {
        progress(len, what, unit, self.quiet)
    }
}

/// A progress bar over `len` steps on stderr (hidden when `quiet`): `what [=====>   ] 40/100
/// unit (12s left)`.
#[must_use]
pub fn progress(len: u64, what: &str, unit: &str, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let template = format!("{{spinner}} {what} [{{bar:40}}] {{pos}}/{{len}} {unit} ({{eta}} left)");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// Why a program stops before its end: the reader closed the pipe (a quiet, successful end,
/// as `| head` expects), or an error for the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Stop {
    /// Stdout was closed by its reader: nothing more to say, and nobody to say it to.
    Closed,
    /// What went wrong, for stderr.
    Error(String),
}

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Closed => f.write_str("the output was closed"),
            Self::Error(e) => f.write_str(e),
        }
    }
}

impl From<String> for Stop {
    fn from(e: String) -> Self {
        Self::Error(e)
    }
}

impl From<&str> for Stop {
    fn from(e: &str) -> Self {
        Self::Error(e.to_owned())
    }
}

impl From<io::Error> for Stop {
    fn from(e: io::Error) -> Self {
        stop_for(&e)
    }
}

impl From<serde_json::Error> for Stop {
    fn from(e: serde_json::Error) -> Self {
        match e.io_error_kind() {
            Some(io::ErrorKind::BrokenPipe) => Self::Closed,
            _ => Self::Error(format!("cannot write the JSON: {e}")),
        }
    }
}

/// The `Stop` for a failed write to stdout: a closed pipe ends quietly, anything else is named.
#[must_use]
pub fn stop_for(e: &io::Error) -> Stop {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Stop::Closed
    } else {
        Stop::Error(format!("cannot write: {}", io_message(e)))
    }
}

/// An I/O error as a sentence (its `Display`, which for the standard library's own errors names
/// the cause; never the `Custom { kind: … }` debug form).
#[must_use]
pub fn io_message(e: &io::Error) -> String {
    let text = e.to_string();
    if text.is_empty() {
        e.kind().to_string()
    } else {
        text
    }
}

/// Writes `text` and a newline to stdout; a closed pipe is [`Stop::Closed`].
///
/// # Errors
/// [`Stop::Closed`] when stdout's reader has gone, [`Stop::Error`] for any other write error.
pub fn print(text: &str) -> Result<(), Stop> {
    let mut out = io::stdout().lock();
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .map_err(|e| stop_for(&e))
}

/// Stdout for a program that writes as it goes (a stream of JSON points, a live monitor):
/// every write ends the program quietly on a closed pipe.
pub struct Out {
    inner: io::BufWriter<io::Stdout>,
}

impl Default for Out {
    fn default() -> Self {
        Self::new()
    }
}

impl Out {
    /// Buffered stdout.
    #[must_use]
    pub fn new() -> Self {
        Self {
            inner: io::BufWriter::new(io::stdout()),
        }
    }

    /// Writes `text` (no newline added).
    ///
    /// # Errors
    /// As [`print()`].
    pub fn text(&mut self, text: &str) -> Result<(), Stop> {
        self.inner
            .write_all(text.as_bytes())
            .map_err(|e| stop_for(&e))
    }

    /// Writes `text` and a newline.
    ///
    /// # Errors
    /// As [`print()`].
    pub fn line(&mut self, text: &str) -> Result<(), Stop> {
        self.text(text)?;
        self.text("\n")
    }

    /// Sends what is buffered (before the program waits for input, and at the end).
    ///
    /// # Errors
    /// As [`print()`].
    pub fn flush(&mut self) -> Result<(), Stop> {
        self.inner.flush().map_err(|e| stop_for(&e))
    }

    /// The writer itself, for `serde_json::to_writer` and `write!` (map its errors with
    /// [`stop_for`] or `Stop::from`).
    pub fn writer(&mut self) -> &mut impl Write {
        &mut self.inner
    }
}

/// Writes a line to an [`Out`] or to stdout with `format!` arguments: `outln!(out, "{x}")?` or
/// `outln!("{x}")?`.
#[macro_export]
macro_rules! outln {
    ($out:ident, $($arg:tt)*) => {
        $out.line(&::std::format!($($arg)*))
    };
    ($($arg:tt)*) => {
        $crate::cli::print(&::std::format!($($arg)*))
    };
}

/// The end of every example's `main`: success (also when the reader closed the pipe), or the
/// error on stderr prefixed with the program's name and exit code 2 — never a panic.
#[must_use]
pub fn finish(program: &str, result: Result<(), Stop>) -> ExitCode {
    match result {
        Ok(()) | Err(Stop::Closed) => ExitCode::SUCCESS,
        Err(Stop::Error(e)) => {
            // stderr closed as well: nothing left to tell anyone.
            let _ = writeln!(io::stderr(), "{program}: {e}");
            ExitCode::from(2)
        }
    }
}

/// Writes the picture to `path`; a failure names the option and the path in the one wording
/// every program uses (`--picture: cannot write PATH: why`).
///
/// # Errors
/// [`Stop::Error`] when the file cannot be written.
pub fn write_picture(path: &Path, bytes: impl AsRef<[u8]>) -> Result<(), Stop> {
    std::fs::write(path, bytes).map_err(|e| {
        bad(
            "--picture",
            format!("cannot write {}: {}", path.display(), io_message(&e)),
        )
    })
}

/// What a user typed, for a message: as typed, or its first characters and `…` when it is long
/// (a 10 MB script line is not echoed whole).
#[must_use]
pub fn excerpt(s: &str) -> String {
    let t = s.trim();
    if t.chars().count() > 24 {
        let head: String = t.chars().take(20).collect();
        format!("{head}…")
    } else {
        t.to_owned()
    }
}

/// A refusal of `option`'s value, in the one style every program uses (`--crates: must be from
/// 1 to 62, got 99`), as clap prints its own range errors with exit code 2.
#[must_use]
pub fn bad(option: &str, why: impl fmt::Display) -> Stop {
    Stop::Error(format!("{option}: {why}"))
}

/// A number as a user typed it or would: up to 6 significant digits, exponent form beyond
/// ±1e9 or below 1e-4 (so 1e300 prints as `1e300`, not 301 digits).
#[must_use]
pub fn number(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "NaN".into()
        } else if x > 0.0 {
            "infinity".into()
        } else {
            "-infinity".into()
        };
    }
    let a = x.abs();
    if a != 0.0 && !(1e-4..1e9).contains(&a) {
        let s = format!("{x:e}");
        // 1.2345678e300 → at most 6 significant digits.
        if let Some((mantissa, exp)) = s.split_once('e') {
            if let Ok(m) = mantissa.parse::<f64>() {
                let m = format!("{m:.5}");
                let m = m.trim_end_matches('0').trim_end_matches('.');
                return format!("{m}e{exp}");
            }
        }
        return s;
    }
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// A clap value parser for a real number in `lo..=hi` (finite; negative numbers need
/// `allow_hyphen_values = true` on the argument so that `-1` reaches it).
pub fn real(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s: &str| {
        let x = parse_real(s)?;
        if (lo..=hi).contains(&x) {
            Ok(x)
        } else {
            Err(format!(
                "must be from {} to {}, got {}",
                number(lo),
                number(hi),
                excerpt(s)
            ))
        }
    }
}

/// A clap value parser for a real number above `lo` and at most `hi` (`lo` itself refused: a
/// duration of 0, a rate of 0).
pub fn real_above(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s: &str| {
        let x = parse_real(s)?;
        if x > lo && x <= hi {
            Ok(x)
        } else {
            Err(format!(
                "must be more than {} and at most {}, got {}",
                number(lo),
                number(hi),
                excerpt(s)
            ))
        }
    }
}

/// A clap value parser for a whole number in `lo..=hi`, in the same words as [`real`].
pub fn whole<T>(lo: T, hi: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync
where
    T: Copy + PartialOrd + fmt::Display + std::str::FromStr + Send + Sync + 'static,
{
    move |s: &str| {
        let out_of_range = || format!("must be from {lo} to {hi}, got {}", excerpt(s));
        let t = s.trim().replace('_', "");
        match t.parse::<T>() {
            Ok(x) if x >= lo && x <= hi => Ok(x),
            Ok(_) => Err(out_of_range()),
            // A number too large (or negative) for the type is out of the range too.
            Err(_)
                if !t.is_empty()
                    && t.trim_start_matches('-')
                        .bytes()
                        .all(|b| b.is_ascii_digit()) =>
            {
                Err(out_of_range())
            }
            Err(_) => Err(format!(
                "must be a whole number from {lo} to {hi}, got {}",
                excerpt(s)
            )),
        }
    }
}

fn parse_real(s: &str) -> Result<f64, String> {
    match s.trim().replace('_', "").parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(format!("must be a finite number, got {}", excerpt(s))),
        Err(_) => Err(format!("must be a number, got {}", excerpt(s))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_as_typed() {
        assert_eq!(number(1e300), "1e300");
        assert_eq!(number(1.234_567_89e300), "1.23457e300");
        assert_eq!(number(86400.0), "86400");
        assert_eq!(number(0.5), "0.5");
        assert_eq!(number(-0.0), "0");
        assert_eq!(number(1e-5), "1e-5");
        assert_eq!(number(5e6), "5000000");
        assert_eq!(number(f64::NAN), "NaN");
    }

    #[test]
    fn ranges_name_the_bounds_and_the_input() {
        let p = real(0.0, 86400.0);
        assert_eq!(p("12.5"), Ok(12.5));
        assert_eq!(p("-1"), Err("must be from 0 to 86400, got -1".into()));
        assert_eq!(p("nan"), Err("must be a finite number, got nan".into()));
        assert_eq!(p("x"), Err("must be a number, got x".into()));
        let long = "1".repeat(400);
        let e = p(&long).unwrap_err();
        assert!(e.len() < 80, "{e}");
        let q = real_above(0.0, 86400.0);
        assert_eq!(
            q("0"),
            Err("must be more than 0 and at most 86400, got 0".into())
        );
        assert_eq!(q("86400"), Ok(86400.0));
        let w = whole(1u8, 62);
        assert_eq!(w("62"), Ok(62));
        assert_eq!(w("63"), Err("must be from 1 to 62, got 63".into()));
        assert_eq!(w("300"), Err("must be from 1 to 62, got 300".into()));
        assert_eq!(w("-1"), Err("must be from 1 to 62, got -1".into()));
        assert_eq!(
            w("1.5"),
            Err("must be a whole number from 1 to 62, got 1.5".into())
        );
        let m = whole(1u64, 100_000_000);
        assert_eq!(
            m("99999999999999"),
            Err("must be from 1 to 100000000, got 99999999999999".into())
        );
    }

    #[test]
    fn a_closed_pipe_is_a_quiet_success() {
        let e = io::Error::from(io::ErrorKind::BrokenPipe);
        assert_eq!(stop_for(&e), Stop::Closed);
        assert_eq!(finish("x", Err(Stop::Closed)), ExitCode::SUCCESS);
        assert_eq!(finish("x", Err("bad".into())), ExitCode::from(2));
        let other = io::Error::other("disk full");
        assert_eq!(
            stop_for(&other),
            Stop::Error("cannot write: disk full".into())
        );
    }
}
