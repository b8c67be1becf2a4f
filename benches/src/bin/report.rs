//! The whole performance report in one command: criterion medians, instruction counts (N and 2N
//! under callgrind, both shapes) and the on-target counts, written to `docs/PERFORMANCE.md` and
//! summed up between the markers of `README.md` and `benches/README.md`; each crate README gets
//! its own figures and its cost statements, which the run asserts (`cost_statements`).
//!
//! ```sh
//! cargo run --release -p regler-benches --bin report                     # everything (~15 min)
//! cargo run --release -p regler-benches --bin report -- --skip criterion # the exact parts
//! cargo run --release -p regler-benches --bin report -- --check --skip criterion
//! ```

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use clap::Parser;
use regler_benches::report::{
    BENCHES, Count, Counter, Data, Part, Provenance, cost_statements, counters, differences,
    on_target_tables, parse, readme_blocks, render, replace_block,
};

/// Measures regler's hot paths beside their anchors and writes docs/PERFORMANCE.md.
///
/// Parts: `instructions` (valgrind's callgrind on the counter binaries, N and 2N operations;
/// needs valgrind), `on-target` (`on-target/cycles` under QEMU: Cortex-M instruction counts),
/// `criterion` (every criterion bench, short warm-up and measurement). A part not run keeps
/// its figures from the existing file. The summary, the scaling tables and every README block
/// (the summary in the workspace README and `benches/README.md`, each crate's own figures in its
/// README) are derived from the figures. Every run (and `--check`) fails when a README's cost statement
/// does not hold on the figures (`docs/PERFORMANCE.md`, "Cost statements, checked").
#[derive(Parser, Debug)]
#[command(name = "report")]
struct Args {
    /// Run only these parts (comma-separated: instructions, on-target, criterion).
    #[arg(long, value_delimiter = ',', value_parser = part)]
    only: Vec<Part>,
    /// Skip these parts (comma-separated or repeated).
    #[arg(long, value_delimiter = ',', value_parser = part)]
    skip: Vec<Part>,
    /// Compare a fresh measurement of the parts that repeat exactly (instructions, on-target)
    /// with the file instead of writing it; also check that the file's derived tables and every
    /// README block match its figures and that every cost statement holds on what was measured.
    /// Exit 1 on any difference. A part measured with another compiler than this one is not
    /// compared (noted); its statements are still checked on the fresh figures.
    #[arg(long)]
    check: bool,
    /// Take the on-target tables from this file (e.g. the docs/FOOTPRINT.md that
    /// `footprint/measure` has just written, which runs `on-target/cycles`) instead of
    /// running `on-target/cycles` again.
    #[arg(long, value_name = "FILE")]
    on_target_from: Option<PathBuf>,
    /// Criterion warm-up time per benchmark, seconds.
    #[arg(long, default_value_t = 0.5, value_name = "SECONDS")]
    warm_up: f64,
    /// Criterion measurement time per benchmark, seconds.
    #[arg(long, default_value_t = 1.0, value_name = "SECONDS")]
    measure: f64,
    /// Leave out criterion's two-thread transfer (10 × 1 million items through the split halves
    /// and through heapless's, two spinning threads): on a machine whose cores are busy with
    /// other work a spinning thread waits for a time slice, and the run takes much longer.
    #[arg(long)]
    no_threads: bool,
    /// Instruction counters run at once (default: the machine's cores).
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// The file to write (or check). Writing another file than docs/PERFORMANCE.md leaves the
    /// READMEs alone.
    #[arg(long, value_name = "FILE")]
    output: Option<PathBuf>,
}

fn part(s: &str) -> Result<Part, String> {
    Part::parse(s).ok_or_else(|| format!("no part `{s}` (instructions, on-target, criterion)"))
}

type Error = String;

fn root() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest).to_path_buf()
}

/// Runs a command, returns its stdout; an error with its stderr when it fails.
fn output(cmd: &mut Command) -> Result<String, Error> {
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {cmd:?}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{cmd:?} failed ({}):\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

fn rustc_version() -> String {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    output(Command::new(rustc).arg("--version").current_dir(root()))
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "rustc (unknown version)".into())
}

fn machine() -> String {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map_or_else(
            || std::env::consts::ARCH.to_string(),
            |m| m.trim().to_string(),
        );
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let os = std::fs::read_to_string("/etc/os-release")
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix("PRETTY_NAME="))
        .map_or_else(
            || std::env::consts::OS.to_string(),
            |v| v.trim_matches('"').to_string(),
        );
    format!("{} {model}, {cores} cores, {os}", std::env::consts::ARCH)
}

fn commit() -> String {
    let head = output(
        Command::new("git")
            .args(["rev-parse", "--short=10", "HEAD"])
            .current_dir(root()),
    )
    .map(|s| s.trim().to_string())
    .unwrap_or_else(|_| "(not a git checkout)".into());
    // The code, not the docs this command writes: a change outside the Markdown files marks
    // the figures as measured on something else than the commit.
    let clean = Command::new("git")
        .args(["diff", "--quiet", "HEAD", "--", ".", ":(exclude)*.md"])
        .current_dir(root())
        .status()
        .is_ok_and(|s| s.success());
    if clean { head } else { format!("{head}-dirty") }
}

fn today() -> String {
    output(Command::new("date").args(["-u", "+%Y-%m-%d %H:%M"]))
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

/// Builds the counter binaries; returns each binary's path by name.
fn build_counters(bins: &[&str]) -> Result<BTreeMap<String, PathBuf>, Error> {
    let mut cmd = cargo();
    cmd.args([
        "build",
        "--release",
        "--locked",
        "-p",
        "regler-benches",
        "--message-format=json-render-diagnostics",
    ]);
    for bin in bins {
        cmd.args(["--bin", bin]);
    }
    let out = output(cmd.stderr(Stdio::inherit()))?;
    let mut paths = BTreeMap::new();
    for line in out.lines() {
        let Ok(msg) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if let (Some(name), Some(exe)) =
            (msg["target"]["name"].as_str(), msg["executable"].as_str())
        {
            paths.insert(name.to_string(), PathBuf::from(exe));
        }
    }
    Ok(paths)
}

/// Total instructions of one run under callgrind.
fn callgrind(exe: &Path, args: &[String], ops: u64) -> Result<u64, Error> {
    let dir = std::env::temp_dir().join(format!(
        "regler-report-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let out_file = dir.join("callgrind.out");
    // N with a fixed width (the counters accept leading zeros): the N and 2N runs then have
    // arguments of the same length, so the start-up's string handling, whose cost moves with the
    // alignment the environment leaves them at, cancels; without it a fresh clone at another
    // path differed by up to 16 instructions a run (0.3 per operation at N = 50).
    let n = format!("{ops:012}");
    let argv: Vec<String> = args.iter().map(|a| a.replace("{N}", &n)).collect();
    let result = Command::new("valgrind")
        .arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", out_file.display()))
        .arg(exe)
        .args(&argv)
        .stdout(Stdio::null())
        .output();
    let text = std::fs::read_to_string(&out_file).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    let out = result
        .map_err(|e| format!("cannot run valgrind ({e}); Debian: apt-get install valgrind"))?;
    if !out.status.success() {
        return Err(format!(
            "valgrind {} {}: {}",
            exe.display(),
            argv.join(" "),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    // callgrind's output ends with "summary: <Ir>" ("totals:" in older versions).
    text.lines()
        .filter_map(|l| {
            l.strip_prefix("summary:")
                .or_else(|| l.strip_prefix("totals:"))
        })
        .filter_map(|v| v.split_whitespace().next()?.parse().ok())
        .next_back()
        .ok_or_else(|| format!("no instruction total from callgrind for {}", exe.display()))
}

static COUNTER: AtomicUsize = AtomicUsize::new(0);

fn count_instructions(jobs: usize) -> Result<(Vec<(String, Count)>, String), Error> {
    let valgrind = output(Command::new("valgrind").arg("--version"))
        .map_err(|_| "valgrind is not installed (Debian: apt-get install valgrind)".to_string())?;
    let plan = counters();
    let mut bins: Vec<&str> = plan.iter().map(|c| c.bin).collect();
    bins.sort_unstable();
    bins.dedup();
    let paths = build_counters(&bins)?;
    let results: Mutex<Vec<Option<Result<Count, Error>>>> = Mutex::new(vec![None; plan.len()]);
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let measure = |c: &Counter| -> Result<Count, Error> {
        let exe = paths
            .get(c.bin)
            .ok_or_else(|| format!("cargo built no `{}`", c.bin))?;
        let once = callgrind(exe, &c.args, c.n)?;
        let twice = callgrind(exe, &c.args, 2 * c.n)?;
        let per_op = (twice as f64 - once as f64) / c.n as f64;
        Ok(Count {
            n: c.n,
            per_op: format!("{per_op:.1}"),
        })
    };
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| {
                while let Some(c) = plan.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let at = plan.iter().position(|p| p == c).unwrap_or(0);
                    let r = measure(c);
                    let k = done.fetch_add(1, Ordering::Relaxed) + 1;
                    match &r {
                        Ok(v) => eprintln!("[{k}/{}] {}: {}", plan.len(), c.key(), v.per_op),
                        Err(e) => eprintln!("[{k}/{}] {}: {e}", plan.len(), c.key()),
                    }
                    if let Ok(mut all) = results.lock() {
                        if let Some(slot) = all.get_mut(at) {
                            *slot = Some(r);
                        }
                    }
                }
            });
        }
    });
    let results = results.into_inner().map_err(|e| e.to_string())?;
    let mut counts = Vec::new();
    for (c, r) in plan.iter().zip(results) {
        let r = r.ok_or_else(|| format!("{} was not measured", c.key()))?;
        counts.push((c.key(), r?));
    }
    Ok((counts, valgrind.trim().to_string()))
}

fn on_target(from: Option<&Path>) -> Result<Vec<String>, Error> {
    let text = match from {
        Some(file) => {
            std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?
        }
        None => output(
            Command::new(root().join("on-target/cycles"))
                .arg("both")
                .current_dir(root().join("on-target"))
                .stderr(Stdio::inherit()),
        )?,
    };
    let tables = on_target_tables(&text);
    if tables.is_empty() {
        return Err("no instruction table in the on-target output".into());
    }
    Ok(tables)
}

fn walk(dir: &Path, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(&p, found);
        } else if p.ends_with("new/benchmark.json") {
            found.push(p);
        }
    }
}

/// Runs every criterion bench with its results in a fresh directory (so neither old results nor
/// the user's baselines are touched) and reads each benchmark's median.
fn criterion(warm_up: f64, measure: f64, threads: bool) -> Result<BTreeMap<String, f64>, Error> {
    let home = std::env::temp_dir().join(format!("regler-report-criterion-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&home);
    let mut medians = BTreeMap::new();
    let result = (|| {
        for bench in BENCHES {
            eprintln!("criterion: --bench {bench}");
            let mut cmd = cargo();
            cmd.args([
                "bench",
                "--locked",
                "-p",
                "regler-benches",
                "--bench",
                bench,
                "--",
            ])
            .args(["--warm-up-time", &warm_up.to_string()])
            .args(["--measurement-time", &measure.to_string()])
            .args((bench == "ring_transfer" && !threads).then_some("^ring/(pair|scheduler)"))
            .env("CRITERION_HOME", &home)
            .stdout(Stdio::piped());
            let mut child = cmd
                .spawn()
                .map_err(|e| format!("cannot run cargo bench: {e}"))?;
            // Criterion's lines stay visible: they are the progress.
            if let Some(out) = child.stdout.take() {
                for line in BufReader::new(out).lines().map_while(Result::ok) {
                    if line.contains("time:") {
                        eprintln!("  {}", line.trim());
                    }
                }
            }
            let status = child.wait().map_err(|e| e.to_string())?;
            if !status.success() {
                return Err(format!("cargo bench --bench {bench} failed ({status})"));
            }
        }
        let mut files = Vec::new();
        walk(&home, &mut files);
        for file in files {
            let read = |p: &Path| -> Option<serde_json::Value> {
                serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()
            };
            let (Some(bench), Some(est)) = (
                read(&file),
                file.parent().and_then(|d| read(&d.join("estimates.json"))),
            ) else {
                continue;
            };
            if let (Some(id), Some(median)) = (
                bench["full_id"].as_str(),
                est["median"]["point_estimate"].as_f64(),
            ) {
                // As the file keeps it (0.1 ns), so what is derived from it now is what a later
                // run derives from the file.
                medians.insert(id.to_string(), (median * 10.0).round() / 10.0);
            }
        }
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&home);
    result?;
    if medians.is_empty() {
        return Err(format!(
            "criterion wrote no results under {}",
            home.display()
        ));
    }
    Ok(medians)
}

/// The READMEs' blocks, updated (writing) or compared (checking).
fn readmes(data: &Data, write: bool) -> Result<Vec<String>, Error> {
    let mut problems = Vec::new();
    let mut texts: BTreeMap<&str, (String, String)> = BTreeMap::new();
    for block in readme_blocks(data) {
        let readme = block.file;
        if !texts.contains_key(readme) {
            let text = std::fs::read_to_string(root().join(readme))
                .map_err(|e| format!("{readme}: {e}"))?;
            texts.insert(readme, (text.clone(), text));
        }
        let Some((_, new)) = texts.get_mut(readme) else {
            continue;
        };
        match replace_block(new, &block.begin, &block.end, &block.text) {
            Some(replaced) => *new = replaced,
            None => problems.push(format!(
                "{readme} lacks the markers `{}` … `{}` (each once, in that order)",
                block.begin, block.end
            )),
        }
    }
    for (readme, (old, new)) in texts {
        if new == old {
            continue;
        }
        if write {
            std::fs::write(root().join(readme), new).map_err(|e| format!("{readme}: {e}"))?;
            eprintln!("wrote {readme}'s performance block");
        } else {
            problems.push(format!(
                "{readme}'s performance block is not what the report writes from docs/PERFORMANCE.md"
            ));
        }
    }
    Ok(problems)
}

/// The cost statements that do not hold on `data`, one line each.
fn broken_statements(data: &Data) -> Vec<String> {
    cost_statements(data)
        .into_iter()
        .filter(|c| !c.holds())
        .map(|c| {
            format!(
                "regler-{}: a cost statement does not hold: {} (measured {:?}, bound {})",
                c.krate, c.statement, c.measured, c.bound
            )
        })
        .collect()
}

fn run(args: &Args) -> Result<bool, Error> {
    let started = Instant::now();
    let parts: Vec<Part> = Part::ALL
        .into_iter()
        .filter(|p| args.only.is_empty() || args.only.contains(p))
        .filter(|p| !args.skip.contains(p))
        .filter(|p| !args.check || *p != Part::Criterion)
        .collect();
    let default_output = root().join("docs/PERFORMANCE.md");
    let file = args
        .output
        .clone()
        .unwrap_or_else(|| default_output.clone());
    let old_text = std::fs::read_to_string(&file).unwrap_or_default();
    let committed = parse(&old_text);
    let mut fresh = committed.clone();
    let compiler = rustc_version();
    let provenance = |tools: String| Provenance {
        machine: machine(),
        compiler: tools,
        commit: commit(),
        date: today(),
    };
    for &p in &parts {
        let t = Instant::now();
        match p {
            Part::Instructions => {
                let jobs = args.jobs.unwrap_or_else(|| {
                    std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
                });
                let (counts, valgrind) = count_instructions(jobs)?;
                fresh.counts = counts;
                fresh
                    .provenance
                    .insert(p, provenance(format!("{compiler}, {valgrind}")));
            }
            Part::OnTarget => {
                fresh.on_target = on_target(args.on_target_from.as_deref())?;
                fresh
                    .provenance
                    .insert(p, provenance(format!("{compiler}, QEMU")));
            }
            Part::Criterion => {
                fresh.medians = criterion(args.warm_up, args.measure, !args.no_threads)?;
                fresh.provenance.insert(p, provenance(compiler.clone()));
            }
        }
        eprintln!("{}: {:.0} s", p.name(), t.elapsed().as_secs_f64());
    }
    if !args.check {
        std::fs::write(&file, render(&fresh)).map_err(|e| format!("{}: {e}", file.display()))?;
        eprintln!(
            "wrote {} in {:.0} s",
            file.display(),
            started.elapsed().as_secs_f64()
        );
        if file == default_output {
            for problem in readmes(&fresh, true)? {
                eprintln!("note: {problem}");
            }
        }
        let broken = broken_statements(&fresh);
        for b in &broken {
            eprintln!("{b}");
        }
        return Ok(broken.is_empty());
    }
    // Checking: the exact parts measured now against the file, where the compiler is the same.
    let mut compared = Vec::new();
    for &p in &parts {
        let was = committed
            .provenance
            .get(&p)
            .map(|v| v.compiler.as_str())
            .unwrap_or("");
        if was.split(", ").next() == Some(compiler.as_str()) {
            compared.push(p);
        } else {
            println!(
                "note: the file's {} figures were measured with `{was}`, not `{compiler}`: not compared",
                p.name()
            );
        }
    }
    let mut problems = differences(&committed, &fresh, &compared);
    if render(&committed) != old_text {
        problems.push(format!(
            "{} is not what the report command writes from its own figures (edited by hand, or written by an older command)",
            file.display()
        ));
    }
    if file == default_output {
        problems.extend(readmes(&committed, false)?);
    }
    // On what was measured now (the committed figures where a part was not re-measured).
    problems.extend(broken_statements(&fresh));
    for p in &problems {
        println!("{p}");
    }
    let names: Vec<&str> = compared.iter().map(|p| p.name()).collect();
    println!(
        "{}: {} ({} compared) in {:.0} s",
        file.display(),
        if problems.is_empty() {
            "up to date"
        } else {
            "STALE"
        },
        if names.is_empty() {
            "nothing".to_string()
        } else {
            names.join(", ")
        },
        started.elapsed().as_secs_f64()
    );
    Ok(problems.is_empty())
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("report: {e}");
            ExitCode::from(2)
        }
    }
}
