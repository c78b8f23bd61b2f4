//! Whole-program performance table (issue #8), reproducible:
//!
//! ```text
//! cargo run --release --example perf_table -- [--max 1e5] [--seed 1] [--block-cells 16]
//!     [--format json] [--tri-max N] [--warm-max N] [--force] [--no-build] [--huge-pages]
//!     [--runs N] [--periodic]
//! ```
//!
//! `--periodic` meshes `medial-blocks example periodic-bubbles` instead (the same bubbles in a
//! periodic box, `layouts::periodic_bubbles`) and prints only the CLI table.
//!
//! For n = 1e2, 1e3, 1e4, 1e5 (up to `--max`) it writes `layouts::bubbles(n, seed)` with the
//! release CLI (`medial-blocks example bubbles`), then meshes it in a child process:
//! `medial-blocks --quiet mesh IN -o DIR --timings --block-cells 16 --format json` (exact
//! mode, a 16 x 16 grid per block; `--format json` writes `report.json` and
//! `connectivity.json`, so the quality figures are computed once), `--runs` times per size
//! (default 5 up to 1e3, 3 at 1e4, 1 above), and keeps the run with the median total. It
//! prints a markdown table from that run's `timings.json`: per-stage seconds, total, the
//! child's wall time measured from outside (process start and exit included), its peak
//! resident memory (`VmHWM`), bytes per particle and the growth exponent
//! `ln(t2 / t1) / ln(n2 / n1)` between sizes.
//!
//! Then, in this process, the triangulation engine vs spade (`bulk_load`) vs delaunator on
//! the sample points the exact pipeline triangulates (its first sampling of the same layouts:
//! `mesher::exact_sampling()`, as `mesher` samples in exact mode; best of a
//! few runs each, interleaved), up to `--tri-max` (default: `--max`). Its last column is the
//! CLI's median total of the table above in units of spade's time on the same points: a
//! yardstick for the machine, since the sessions of this project run on machines whose speed
//! differs by more than 2x (the header names the processor).
//!
//! Then, in this process, the remeshing loop of a time-stepping solver (the library, not the
//! CLI): `mesh` and the quality report (`Report::from_mesh`) of the same layout again and
//! again, after one run to warm up, as a program that remeshes every time step does (its
//! memory comes back from the allocator instead of fresh pages); median of a few runs, up to
//! `--warm-max` (default: `--max`).
//!
//! Before running the largest sizes it projects the peak memory from the previous size's bytes
//! per particle and skips a size that would not fit in 85% of `MemAvailable` (`--force` runs
//! it anyway). The release binary is rebuilt first (`cargo build --release`, skipped with
//! `--no-build` or when `MEDIAL_BLOCKS_BIN` names a binary).

use medial_blocks::geometry::{Point, Triangulation};
use medial_blocks::layouts;
use medial_blocks::sampling::sample_and_triangulate;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const SIZES: [usize; 4] = [100, 1_000, 10_000, 100_000];

/// Stage columns: (header, stage keys of timings.json summed into it).
const COLUMNS: &[(&str, &[&str])] = &[
    ("input", &["input"]),
    ("sampling", &["sampling"]),
    ("triangulation", &["triangulation"]),
    ("medial graph", &["medial_graph"]),
    ("blocking", &["blocking"]),
    ("exact geometry", &["exact_geometry"]),
    ("node counts", &["node_counts"]),
    ("grids", &["grids"]),
    ("quality check", &["quality_check"]),
    ("quality", &["quality"]),
];

struct Args {
    max: usize,
    seed: u64,
    block_cells: usize,
    format: String,
    tri_max: Option<usize>,
    warm_max: Option<usize>,
    force: bool,
    build: bool,
    /// Pass `--huge-pages` to the meshing runs.
    huge_pages: bool,
    /// CLI runs per size (`--runs`); `None`: 5 up to 1e3, 3 at 1e4, 1 above.
    runs: Option<usize>,
    /// Periodic boxes (`example periodic-bubbles`) instead of bounded bubbles.
    periodic: bool,
}

fn parse_size(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 1.0)
        .map(|v| v as usize)
        .ok_or_else(|| format!("'{s}' is not a particle count (e.g. 1e4)"))
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        max: 100_000,
        seed: 1,
        block_cells: 16,
        format: "json".into(),
        tri_max: None,
        warm_max: None,
        force: false,
        build: true,
        huge_pages: false,
        runs: None,
        periodic: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--max" => a.max = parse_size(&value()?)?,
            "--seed" => a.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--block-cells" => {
                a.block_cells = value()?
                    .parse()
                    .map_err(|e| format!("--block-cells: {e}"))?
            }
            "--format" => a.format = value()?,
            "--tri-max" => a.tri_max = Some(parse_size(&value()?)?),
            "--warm-max" => a.warm_max = Some(parse_size(&value()?)?),
            "--force" => a.force = true,
            "--no-build" => a.build = false,
            "--huge-pages" => a.huge_pages = true,
            "--periodic" => a.periodic = true,
            "--runs" => {
                a.runs = Some(
                    value()?
                        .parse()
                        .ok()
                        .filter(|&r: &usize| r >= 1)
                        .ok_or("--runs needs a count of at least 1")?,
                )
            }
            "-h" | "--help" => {
                println!(
                    "perf_table [--max 1e5] [--seed 1] [--block-cells 16] [--format json] \
                     [--tri-max N] [--warm-max N] [--force] [--no-build] [--huge-pages] \
                     [--runs N] [--periodic]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument '{other}' (see --help)")),
        }
    }
    Ok(a)
}

/// The release CLI binary: `MEDIAL_BLOCKS_BIN`, else `target/release/medial-blocks` next to
/// this example (rebuilt first unless `--no-build`).
fn binary(build: bool) -> Result<PathBuf, String> {
    if let Ok(p) = std::env::var("MEDIAL_BLOCKS_BIN") {
        return Ok(PathBuf::from(p));
    }
    if build {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let status = Command::new(cargo)
            .args(["build", "--release", "--quiet", "--bin", "medial-blocks"])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .status()
            .map_err(|e| format!("cannot run cargo build: {e}"))?;
        if !status.success() {
            return Err("cargo build --release failed".into());
        }
    }
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    // target/release/examples/perf_table -> target/release/medial-blocks
    let bin = exe
        .parent()
        .and_then(Path::parent)
        .map(|d| d.join(format!("medial-blocks{}", std::env::consts::EXE_SUFFIX)))
        .ok_or("cannot locate target/release")?;
    if bin.exists() {
        Ok(bin)
    } else {
        Err(format!(
            "{} not found: run cargo build --release",
            bin.display()
        ))
    }
}

/// The 1-minute load average (`/proc/loadavg`), to judge how shared the machine was.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|t| t.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "n/a".into())
}

/// Microseconds per 4 KB page to touch `bytes` of memory fresh from the kernel, one write per
/// page: what the first touch of a large mesh's nodes costs on this machine (on the project's
/// virtual machines 1.5 to 8, depending on whether the host must supply the page; issue 8,
/// docs/performance-history.md, fortieth session).
fn first_touch_us(bytes: usize) -> f64 {
    // Large enough for malloc to map it on its own: fresh pages, untouched until written.
    let mut v: Vec<u8> = Vec::with_capacity(bytes);
    let p = v.as_mut_ptr();
    let t = std::time::Instant::now();
    for off in (0..bytes).step_by(4096) {
        // SAFETY: `off < bytes`, inside the allocation; a byte written, never read back.
        unsafe { p.add(off).write_volatile(1) };
    }
    let e = t.elapsed().as_secs_f64();
    drop(v);
    e * 1e6 / bytes.div_ceil(4096) as f64
}

/// `MemAvailable` of /proc/meminfo in bytes.
fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

struct Row {
    n: usize,
    blocks: u64,
    cells: u64,
    stages: serde_json::Value,
    cpu_stages: serde_json::Value,
    calls: serde_json::Value,
    fault_stages: serde_json::Value,
    faults: Option<u64>,
    /// `timings.json`'s `rework`: checks after the first and their seconds (the local-fix
    /// rounds of the exact build, and any resampling).
    rework: (u64, f64),
    total: f64,
    cpu: Option<f64>,
    wall: f64,
    peak: Option<u64>,
}

/// `runs` runs of `run`, the one with the median total (the lower middle of an even count):
/// its stages, CPU time and process time are one run's, not mixed.
fn median_run(runs: usize, mut run: impl FnMut() -> Result<Row, String>) -> Result<Row, String> {
    let mut all = (0..runs)
        .map(|_| run())
        .collect::<Result<Vec<Row>, String>>()?;
    all.sort_by(|x, y| x.total.total_cmp(&y.total));
    let mid = (all.len() - 1) / 2;
    Ok(all.swap_remove(mid))
}

fn run_size(bin: &Path, dir: &Path, n: usize, a: &Args) -> Result<Row, String> {
    let input = dir.join(format!("bubbles_{n}.json"));
    let out = dir.join(format!("out_{n}"));
    let kind = if a.periodic {
        "periodic-bubbles"
    } else {
        "bubbles"
    };
    let st = Command::new(bin)
        .args(["--quiet", "example", kind, "--holes"])
        .arg(n.to_string())
        .arg("--seed")
        .arg(a.seed.to_string())
        .arg("-o")
        .arg(&input)
        .status()
        .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    if !st.success() {
        return Err(format!("example {kind} --holes {n} failed"));
    }
    let start = Instant::now();
    let o = Command::new(bin)
        .args(["--quiet", "mesh"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--timings", "--block-cells"])
        .arg(a.block_cells.to_string())
        .args(["--format", &a.format])
        .args(a.huge_pages.then_some("--huge-pages"))
        .output()
        .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    let wall = start.elapsed().as_secs_f64();
    if !o.status.success() {
        return Err(format!(
            "mesh of {n} bubbles failed: {}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    let text = std::fs::read_to_string(out.join("timings.json"))
        .map_err(|e| format!("timings.json of {n}: {e}"))?;
    let t: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_file(&input);
    Ok(Row {
        n,
        blocks: t["blocks"].as_u64().unwrap_or(0),
        cells: t["cells"].as_u64().unwrap_or(0),
        total: t["total_seconds"].as_f64().unwrap_or(f64::NAN),
        cpu: t["cpu_seconds"].as_f64(),
        peak: t["peak_memory_bytes"].as_u64(),
        stages: t["stages"].clone(),
        cpu_stages: t["cpu_stages"].clone(),
        calls: t["calls"].clone(),
        fault_stages: t["fault_stages"].clone(),
        faults: t["page_faults"].as_u64(),
        rework: (
            t["rework"]["checks"].as_u64().unwrap_or(0),
            t["rework"]["seconds"].as_f64().unwrap_or(0.0),
        ),
        wall,
    })
}

fn stage_sum(stages: &serde_json::Value, keys: &[&str]) -> f64 {
    keys.iter().filter_map(|k| stages[*k].as_f64()).sum()
}

/// Writers: `write` (staging, publishing) and every `write_<format>`.
fn writers(stages: &serde_json::Value) -> f64 {
    stages.as_object().map_or(0.0, |o| {
        o.iter()
            .filter(|(k, _)| k.as_str() == "write" || k.starts_with("write_"))
            .filter_map(|(_, v)| v.as_f64())
            .sum()
    })
}

fn exponent(n0: usize, t0: f64, n1: usize, t1: f64) -> f64 {
    (t1 / t0).ln() / (n1 as f64 / n0 as f64).ln()
}

fn print_table(rows: &[Row]) {
    let mut head = vec!["particles", "blocks", "cells"];
    head.extend(COLUMNS.iter().map(|c| c.0));
    head.extend([
        "writers",
        "other",
        "total s",
        "CPU s",
        "process s",
        "peak MiB",
        "bytes/particle",
        "growth exp.",
    ]);
    println!("| {} |", head.join(" | "));
    println!("|{}", "---:|".repeat(head.len()));
    for (i, r) in rows.iter().enumerate() {
        let mut cells = vec![r.n.to_string(), r.blocks.to_string(), r.cells.to_string()];
        for (_, keys) in COLUMNS {
            cells.push(format!("{:.3}", stage_sum(&r.stages, keys)));
        }
        cells.push(format!("{:.3}", writers(&r.stages)));
        cells.push(format!("{:.3}", r.stages["other"].as_f64().unwrap_or(0.0)));
        cells.push(format!("{:.3}", r.total));
        cells.push(r.cpu.map_or("n/a".into(), |c| format!("{c:.2}")));
        cells.push(format!("{:.3}", r.wall));
        match r.peak {
            Some(p) => {
                cells.push(format!("{:.1}", p as f64 / (1024.0 * 1024.0)));
                cells.push(format!("{:.0}", p as f64 / r.n as f64));
            }
            None => cells.extend(["n/a".to_string(), "n/a".to_string()]),
        }
        cells.push(match i.checked_sub(1).map(|j| &rows[j]) {
            Some(p) => format!("{:.2}", exponent(p.n, p.total, r.n, r.total)),
            None => "-".into(),
        });
        println!("| {} |", cells.join(" | "));
    }
    let find = |n: usize| rows.iter().find(|r| r.n == n);
    if let (Some(a), Some(b)) = (find(1_000), find(100_000)) {
        println!(
            "\nGrowth exponent 1e3 -> 1e5 (total): {:.2}",
            exponent(a.n, a.total, b.n, b.total)
        );
    }
}

/// Process CPU seconds per stage (all threads; less sensitive to a shared machine than wall
/// time), how often the sampling loop triangulated, and the page faults of the run and of its
/// grids stage (fresh memory: on a virtual machine each costs microseconds).
fn print_cpu_table(rows: &[Row]) {
    let mut head = vec!["particles"];
    head.extend(COLUMNS.iter().map(|c| c.0));
    head.extend([
        "writers",
        "other",
        "CPU s",
        "triangulations",
        "page faults",
        "grids faults",
        "rebuilds",
        "rework s",
    ]);
    println!(
        "\nProcess CPU seconds per stage (all threads); `rebuilds` and `rework s`: the exact \
         build's local-fix rounds (checks after the first, and the wall seconds of the stages \
         redone, included in the stage columns above; `rework` of timings.json):\n"
    );
    println!("| {} |", head.join(" | "));
    println!("|{}", "---:|".repeat(head.len()));
    for r in rows {
        if r.cpu_stages.is_null() {
            continue;
        }
        let mut cells = vec![r.n.to_string()];
        for (_, keys) in COLUMNS {
            cells.push(format!("{:.3}", stage_sum(&r.cpu_stages, keys)));
        }
        cells.push(format!("{:.3}", writers(&r.cpu_stages)));
        cells.push(format!(
            "{:.3}",
            r.cpu_stages["other"].as_f64().unwrap_or(0.0)
        ));
        cells.push(r.cpu.map_or("n/a".into(), |c| format!("{c:.3}")));
        cells.push(r.calls["triangulation"].as_u64().unwrap_or(0).to_string());
        cells.push(r.faults.map_or("n/a".into(), |f| f.to_string()));
        cells.push(
            r.fault_stages["grids"]
                .as_u64()
                .map_or("n/a".into(), |f| f.to_string()),
        );
        cells.push(r.rework.0.to_string());
        cells.push(format!("{:.3}", r.rework.1));
        println!("| {} |", cells.join(" | "));
    }
}

/// Best of `reps` wall times (seconds) of `f`.
fn best<T>(reps: usize, mut f: impl FnMut() -> T) -> f64 {
    (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            std::hint::black_box(f());
            s.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The processor's name (`model name` of `/proc/cpuinfo`), or `unknown processor`.
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown processor".to_string())
}

/// `rows`: the CLI runs of the table above, for the last column (CLI total in units of
/// spade's time on the same points; `-` for a size without a CLI run).
fn triangulation_table(max: usize, seed: u64, rows: &[Row]) {
    println!(
        "\n| particles | sample points | engine ms | spade ms | delaunator ms | engine / spade \
         | CLI total / spade |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for n in SIZES.into_iter().filter(|&n| n <= max) {
        let Ok(domain) = layouts::bubbles(n, seed) else {
            continue;
        };
        // Exact mode's sampling (the mode of the table above).
        let exact_mode = medial_blocks::mesher::exact_sampling();
        let sampled = match sample_and_triangulate(&domain, &exact_mode) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("sampling of {n} bubbles failed: {e}");
                continue;
            }
        };
        let pts: Vec<Point> = sampled.samples.points.clone();
        let sp: Vec<spade::Point2<f64>> =
            pts.iter().map(|p| spade::Point2::new(p[0], p[1])).collect();
        let dp: Vec<delaunator::Point> = pts
            .iter()
            .map(|p| delaunator::Point { x: p[0], y: p[1] })
            .collect();
        let reps = if pts.len() <= 200_000 { 5 } else { 3 };
        let (mut e, mut s, mut d) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
        // Interleaved, so that machine load hits all three alike.
        for _ in 0..reps {
            e = e.min(best(1, || Triangulation::new(&pts).map(|t| t.len())));
            s = s.min(best(1, || {
                use spade::Triangulation as _;
                spade::DelaunayTriangulation::<spade::Point2<f64>>::bulk_load(sp.clone())
                    .map(|t| t.num_inner_faces())
            }));
            d = d.min(best(1, || delaunator::triangulate(&dp).triangles.len()));
        }
        let yardstick = rows
            .iter()
            .find(|r| r.n == n)
            .map_or("-".to_string(), |r| format!("{:.2}", r.total / s));
        println!(
            "| {n} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {yardstick} |",
            pts.len(),
            1e3 * e,
            1e3 * s,
            1e3 * d,
            e / s
        );
    }
}

/// The remeshing loop of a time-stepping solver, in this process: `mesh` (exact mode, `N x N`
/// blocks) and its quality report, the same layout meshed again and again after a first run.
fn remeshing_table(max: usize, seed: u64, block_cells: usize) {
    use medial_blocks::output::report::Report;
    use medial_blocks::{mesh, Options};
    println!(
        "\nRemeshing in a running program (library `mesh` + `Report::from_mesh`, the same \
         layout again after one warm-up run; median of the runs; `rework s`: the part of \
         `mesh` spent on the exact build's local-fix rounds, `Timings::rework`):\n"
    );
    println!(
        "| particles | runs | mesh s | rework s | mesh + report s | growth exp. (mesh + report) |"
    );
    println!("|---:|---:|---:|---:|---:|---:|");
    let options = Options {
        block_cells: Some(block_cells),
        ..Options::default()
    };
    let mut prev: Option<(usize, f64)> = None;
    for n in SIZES.into_iter().filter(|&n| n <= max) {
        let Ok(domain) = layouts::bubbles(n, seed) else {
            continue;
        };
        let runs = match n {
            0..=1_000 => 15,
            1_001..=10_000 => 5,
            _ => 3,
        };
        let mut times: Vec<(f64, f64, f64)> = Vec::new();
        for k in 0..=runs {
            let rec = medial_blocks::timings::Recording::start();
            let start = Instant::now();
            let Ok(m) = mesh(&domain, &options) else {
                eprintln!("meshing {n} bubbles in process failed");
                break;
            };
            let meshed = start.elapsed().as_secs_f64();
            let rework = rec.finish().rework().seconds;
            std::hint::black_box(Report::from_mesh(&m).cells);
            let reported = start.elapsed().as_secs_f64();
            drop(m);
            if k > 0 {
                times.push((meshed, reported, rework));
            }
        }
        if times.is_empty() {
            continue;
        }
        let median = |f: fn(&(f64, f64, f64)) -> f64| {
            let mut v: Vec<f64> = times.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (m, r, w) = (median(|t| t.0), median(|t| t.1), median(|t| t.2));
        let growth = prev.map_or("-".to_string(), |(n0, r0)| {
            format!("{:.2}", exponent(n0, r0, n, r))
        });
        println!(
            "| {n} | {} | {m:.3} | {w:.3} | {r:.3} | {growth} |",
            times.len()
        );
        prev = Some((n, r));
    }
}

fn main() {
    let a = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let bin = match binary(a.build) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let load_before = load_average();
    let touch_before = first_touch_us(256 << 20);
    let dir = tempfile::tempdir().expect("temporary directory");
    let mut rows: Vec<Row> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    for n in SIZES.into_iter().filter(|&n| n <= a.max) {
        if let (Some(prev), Some(avail), false) = (rows.last(), mem_available(), a.force) {
            if let Some(p) = prev.peak {
                let projected = p as f64 / prev.n as f64 * n as f64 * 1.15;
                if projected > 0.85 * avail as f64 {
                    eprintln!(
                        "skipping {n} particles: projected peak {:.1} GiB, {:.1} GiB available \
                         (--force runs it anyway)",
                        projected / f64::powi(1024.0, 3),
                        avail as f64 / f64::powi(1024.0, 3)
                    );
                    notes.push(format!(
                        "{n} particles skipped: projected peak {:.1} GiB > 85% of the {:.1} GiB \
                         available.",
                        projected / f64::powi(1024.0, 3),
                        avail as f64 / f64::powi(1024.0, 3)
                    ));
                    break;
                }
            }
        }
        let runs = a.runs.unwrap_or(match n {
            0..=1_000 => 5,
            1_001..=10_000 => 3,
            _ => 1,
        });
        eprintln!("meshing {n} bubbles ({runs} runs) ...");
        match median_run(runs, || run_size(&bin, dir.path(), n, &a)) {
            Ok(r) => {
                eprintln!("  {:.3} s (median), {} blocks", r.total, r.blocks);
                rows.push(r);
            }
            Err(e) => {
                // A size the pipeline cannot mesh is a result too: report it, stop growing.
                eprintln!("error: {e}");
                notes.push(format!("{n} particles: {}", e.trim()));
                break;
            }
        }
    }
    println!(
        "Exact mode, `--block-cells {}`, `--format {}`{}, {}bubbles seed {}, {} threads ({}); \
         each row the median of {} runs; load average {load_before} before, {} after the runs; \
         first touch of fresh memory {touch_before:.2} us per 4 KB page before, {:.2} after \
         (256 MiB, one write per page).\n",
        a.block_cells,
        a.format,
        if a.huge_pages { ", `--huge-pages`" } else { "" },
        if a.periodic { "periodic " } else { "" },
        a.seed,
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        cpu_model(),
        a.runs
            .map_or("5 (1e2, 1e3), 3 (1e4) and 1 (1e5)".to_string(), |r| r
                .to_string()),
        load_average(),
        first_touch_us(256 << 20)
    );
    print_table(&rows);
    print_cpu_table(&rows);
    for n in &notes {
        println!("\n{}", n.replace('\n', " "));
    }
    if a.periodic {
        // The triangulation and remeshing tables are of bounded bubbles.
        return;
    }
    triangulation_table(a.tri_max.unwrap_or(a.max), a.seed, &rows);
    remeshing_table(a.warm_max.unwrap_or(a.max), a.seed, a.block_cells);
}
