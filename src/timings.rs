//! Per-stage wall time and peak memory of one run (`medial-blocks mesh --timings`, issue #8).
//!
//! A [`Recording`] activates a recorder on the current thread; the pipeline marks its stages
//! with [`enter`] (a guard) or [`span`] (a closure). Times are *exclusive*: a stage entered
//! inside another is subtracted from the outer one, so the stages plus the unattributed rest
//! ([`Timings::other_seconds`]) add up to [`Timings::total_seconds`]. A stage entered twice
//! (resampling attempts, the report computed twice) accumulates.
//!
//! Without an active recording on the thread every call is one thread-local read and does
//! nothing else. Work done on other threads (rayon workers) is counted in the stage that is
//! open on the recording thread while it waits. Timings never feed into the mesh or any other
//! output: they go to `timings.json` and stderr only when asked for.

use std::borrow::Cow;
use std::cell::RefCell;
use std::time::{Duration, Instant};

/// The pipeline's stage names, in pipeline order. [`Timings::to_json`] writes every one of
/// them (0 when the stage did not run); writers add `write_<format>` stages.
///
/// - `input`: reading, parsing and validating the domain (the CLI);
/// - `sampling`: boundary sampling, triangle classes, invariant checks and resampling;
/// - `triangulation`: the exact Delaunay triangulation of the samples;
/// - `medial_graph`: the medial graph (Algorithm 1) and the thin-wall check;
/// - `blocking`: Blocking2D (Algorithm 2), and in the paper pipeline refinement and collapse;
/// - `exact_geometry`: exact mode's Apollonius vertices, conic arcs and their densities;
/// - `node_counts`: choosing the cell counts (exact mode's count problem);
/// - `grids`: grid nodes (exact mode's spoke grids, or node counts + TFI of the paper pipeline);
/// - `quality_check`: exact mode's inverted-cell check of each attempt;
/// - `quality`: the quality figures of the report (`report.json`, the summary);
/// - `write`: creating, staging and publishing the output files (not the writers themselves).
pub const STAGES: &[&str] = &[
    "input",
    "sampling",
    "triangulation",
    "medial_graph",
    "blocking",
    "exact_geometry",
    "node_counts",
    "grids",
    "quality_check",
    "quality",
    "write",
];

/// The stage name of a writer: `write_<format>`.
pub fn writer_stage(format: &str) -> String {
    format!("write_{format}")
}

/// The meshing stages whose spans after the first check count as [`Timings::rework`]:
/// [`STAGES`] from `sampling` to `quality_check`.
pub const REWORK_STAGES: &[&str] = STAGES.split_at(1).1.split_at(8).0;

/// What [`Timings::rework`] found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rework {
    /// Checks after the first (one per rebuild that got as far as its check).
    pub checks: usize,
    /// Exclusive wall seconds of the rework spans.
    pub seconds: f64,
    /// Their exclusive process CPU seconds (0 where the CPU clock is unavailable).
    pub cpu_seconds: f64,
}

/// One closing of a stage: what [`Timings::spans`] lists, in the order the stages closed.
///
/// A stage entered several times (the exact build's local-fix rounds: `blocking`,
/// `exact_geometry`, `grids` and `quality_check` again per round; resampling attempts) has
/// one span per entry; the stage's row in [`Timings::stages`] is their sum.
#[derive(Debug, Clone, PartialEq)]
pub struct Span {
    pub stage: String,
    /// Stages open around it when it closed (0: entered directly under the recording).
    pub depth: usize,
    /// Exclusive wall seconds (time in stages entered inside it not counted).
    pub seconds: f64,
    /// Exclusive process CPU seconds (all threads); 0 where the CPU clock is unavailable.
    pub cpu_seconds: f64,
    /// Exclusive page faults; 0 where the count is unavailable.
    pub page_faults: u64,
}

/// What a recording measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Timings {
    /// Exclusive wall time (seconds) per stage, in order of first closing.
    pub stages: Vec<(String, f64)>,
    /// Exclusive process CPU time (seconds, all threads; [`process_cpu_seconds`]) per stage, same
    /// order; empty where the CPU clock is unavailable.
    pub cpu: Vec<(String, f64)>,
    /// Exclusive page faults (minor plus major, all threads; [`process_page_faults`]) per
    /// stage, same order; empty where the count is unavailable. On a virtual machine a fresh
    /// page can cost microseconds, so at large sizes this often explains a stage's time.
    pub faults: Vec<(String, u64)>,
    /// How many times each stage was entered (resampling attempts, repeated figures), same
    /// order.
    pub calls: Vec<(String, u64)>,
    /// Every entry of every stage, in the order they closed (see [`Span`]): per stage, the
    /// spans' count is its `calls` and their exclusive times add up to its row.
    pub spans: Vec<Span>,
    /// Wall time (seconds) from [`Recording::start`] to [`Recording::finish`].
    pub total_seconds: f64,
    /// Peak resident memory of the process so far (`VmHWM` of `/proc/self/status`), `None`
    /// where unavailable.
    pub peak_memory_bytes: Option<u64>,
    /// CPU time (user + system, all threads of the process) spent during the recording
    /// ([`process_cpu_seconds`]); `None` where unavailable. Less sensitive
    /// than wall time to other processes on a shared machine.
    pub cpu_seconds: Option<f64>,
    /// Page faults of the process during the recording; `None` where unavailable.
    pub page_faults: Option<u64>,
}

impl Timings {
    /// Seconds of `stage` (0 when it did not run).
    pub fn seconds(&self, stage: &str) -> f64 {
        self.stages
            .iter()
            .find(|(n, _)| n == stage)
            .map_or(0.0, |(_, s)| *s)
    }

    /// Page faults of `stage` (0 when it did not run or the count is unavailable).
    pub fn stage_faults(&self, stage: &str) -> u64 {
        self.faults
            .iter()
            .find(|(n, _)| n == stage)
            .map_or(0, |(_, f)| *f)
    }

    /// The work redone after the first exact build was checked: the spans of the meshing
    /// stages (`sampling` through `quality_check`, see [`REWORK_STAGES`]) that closed after
    /// the first `quality_check` span, up to the first span of another stage (the mesh is
    /// done then: `quality`, a writer, `--compare-modes`' second mesh after them are not
    /// rework). In exact mode these are the local-fix rounds (recollapse, cached rebuild,
    /// check again), any resampling and a fallback to the paper pipeline; zero when nothing
    /// was redone or no check ran (paper mode, a single hole).
    pub fn rework(&self) -> Rework {
        let Some(first) = self.spans.iter().position(|s| s.stage == "quality_check") else {
            return Rework::default();
        };
        let mut r = Rework::default();
        for s in self.spans[first + 1..]
            .iter()
            .take_while(|s| REWORK_STAGES.contains(&s.stage.as_str()))
        {
            r.seconds += s.seconds;
            r.cpu_seconds += s.cpu_seconds;
            r.checks += usize::from(s.stage == "quality_check");
        }
        r
    }

    /// Total time not attributed to any stage (never negative).
    pub fn other_seconds(&self) -> f64 {
        let sum: f64 = self.stages.iter().map(|(_, s)| s).sum();
        (self.total_seconds - sum).max(0.0)
    }

    /// The stages to report: every one of [`STAGES`], then the others in order of first
    /// entry, then `other`.
    pub fn rows(&self) -> Vec<(String, f64)> {
        let mut rows: Vec<(String, f64)> = STAGES
            .iter()
            .map(|s| (s.to_string(), self.seconds(s)))
            .collect();
        for (n, s) in &self.stages {
            if !STAGES.contains(&n.as_str()) {
                rows.push((n.clone(), *s));
            }
        }
        rows.push(("other".into(), self.other_seconds()));
        rows
    }

    /// `{"stages": {name: seconds, ...}, "cpu_stages": {name: seconds, ...} | null,
    /// "fault_stages": {name: count, ...} | null, "calls": {name: count, ...},
    /// "spans": [{"stage": name, "depth": d, "seconds": s, "cpu_seconds": c|null,
    /// "page_faults": n|null}, ...], "total_seconds": t, "cpu_seconds": c|null,
    /// "page_faults": n|null, "peak_memory_bytes": n|null}` with every row of
    /// [`Timings::rows`] in `stages` (wall time; `other` is the unattributed rest), in
    /// `cpu_stages` (process CPU time) and in `fault_stages` (page faults); `spans` is
    /// [`Timings::spans`] (each entry of a stage on its own: the local-fix rounds of the
    /// exact build show as repeated `blocking`, `exact_geometry` and `grids` spans), and
    /// `"rework": {"checks": n, "seconds": s, "cpu_seconds": c|null}` is [`Timings::rework`].
    pub fn to_json(&self) -> serde_json::Value {
        let stages: serde_json::Map<String, serde_json::Value> = self
            .rows()
            .into_iter()
            .map(|(n, s)| (n, serde_json::Value::from(s)))
            .collect();
        let cpu_stages = self.cpu_seconds.map(|total| {
            let mut m: serde_json::Map<String, serde_json::Value> = self
                .rows()
                .into_iter()
                .filter(|(n, _)| n != "other")
                .map(|(n, _)| {
                    let c = self
                        .cpu
                        .iter()
                        .find(|(k, _)| *k == n)
                        .map_or(0.0, |(_, c)| *c);
                    (n, serde_json::Value::from(c))
                })
                .collect();
            let sum: f64 = self.cpu.iter().map(|(_, c)| c).sum();
            m.insert("other".into(), (total - sum).max(0.0).into());
            m
        });
        let fault_stages = self.page_faults.map(|total| {
            let mut m: serde_json::Map<String, serde_json::Value> = self
                .rows()
                .into_iter()
                .filter(|(n, _)| n != "other")
                .map(|(n, _)| (n.clone(), self.stage_faults(&n).into()))
                .collect();
            let sum: u64 = self.faults.iter().map(|(_, f)| f).sum();
            m.insert("other".into(), total.saturating_sub(sum).into());
            m
        });
        let calls: serde_json::Map<String, serde_json::Value> = self
            .calls
            .iter()
            .map(|(n, c)| (n.clone(), serde_json::Value::from(*c)))
            .collect();
        let rework = self.rework();
        let spans: Vec<serde_json::Value> = self
            .spans
            .iter()
            .map(|sp| {
                serde_json::json!({
                    "stage": sp.stage,
                    "depth": sp.depth,
                    "seconds": sp.seconds,
                    "cpu_seconds": self.cpu_seconds.map(|_| sp.cpu_seconds),
                    "page_faults": self.page_faults.map(|_| sp.page_faults),
                })
            })
            .collect();
        serde_json::json!({
            "stages": stages,
            "cpu_stages": cpu_stages,
            "fault_stages": fault_stages,
            "calls": calls,
            "spans": spans,
            "rework": {
                "checks": rework.checks,
                "seconds": rework.seconds,
                "cpu_seconds": self.cpu_seconds.map(|_| rework.cpu_seconds),
            },
            "total_seconds": self.total_seconds,
            "cpu_seconds": self.cpu_seconds,
            "page_faults": self.page_faults,
            "peak_memory_bytes": self.peak_memory_bytes,
        })
    }

    /// A plain-text table: stage, milliseconds, share of the total, CPU milliseconds, calls
    /// and page faults; then the total, the part of it that was [`Timings::rework`] (when
    /// something was redone) and the peak memory.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<18}{:>12}{:>8}{:>12}{:>7}{:>10}\n",
            "stage", "ms", "share", "cpu ms", "calls", "faults"
        );
        let fault_sum: u64 = self.faults.iter().map(|(_, f)| f).sum();
        let total = self.total_seconds;
        for (n, sec) in self.rows() {
            let share = if total > 0.0 {
                100.0 * sec / total
            } else {
                0.0
            };
            let cpu = self
                .cpu
                .iter()
                .find(|(k, _)| *k == n)
                .map_or("-".to_string(), |(_, c)| format!("{:.0}", 1e3 * c));
            let calls = self
                .calls
                .iter()
                .find(|(k, _)| *k == n)
                .map_or("-".to_string(), |(_, c)| c.to_string());
            let faults = match self.page_faults {
                None => "-".to_string(),
                Some(all) if n == "other" => all.saturating_sub(fault_sum).to_string(),
                Some(_) => self.stage_faults(&n).to_string(),
            };
            s.push_str(&format!(
                "{n:<18}{:>12.2}{share:>7.1}%{cpu:>12}{calls:>7}{faults:>10}\n",
                1e3 * sec
            ));
        }
        s.push_str(&format!("{:<18}{:>12.2}\n", "total", 1e3 * total));
        let rework = self.rework();
        if rework.checks > 0 {
            // Already inside the stage rows: a share of them, not a row of its own.
            s.push_str(&format!(
                "{:<18}{:>12.2}   local-fix rounds: {} rebuild(s) after the first check\n",
                "  of which rework",
                1e3 * rework.seconds,
                rework.checks
            ));
        }
        if let Some(c) = self.cpu_seconds {
            s.push_str(&format!("{:<18}{:>12.2}\n", "cpu (all threads)", 1e3 * c));
        }
        match self.peak_memory_bytes {
            Some(b) => s.push_str(&format!(
                "{:<18}{:>12.1} MiB\n",
                "peak memory",
                b as f64 / (1024.0 * 1024.0)
            )),
            None => s.push_str(&format!("{:<18}{:>12}\n", "peak memory", "n/a")),
        }
        s
    }
}

/// Peak resident memory of this process in bytes: `VmHWM` from `/proc/self/status` (Linux);
/// `None` where that file or line is missing.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

/// CPU time (user + system, all threads) of this process so far in seconds: the process CPU
/// clock (`clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`, nanoseconds, one system call) on Unix;
/// else fields 14 and 15 of `/proc/self/stat` in clock ticks of 1/100 s (Linux's fixed
/// `USER_HZ`); `None` where neither exists.
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `t` is a valid timespec for the call to fill; it returns a status.
        if unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) } == 0 {
            return Some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9);
        }
    }
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    parse_stat_cpu(&stat)
}

/// Page faults of this process so far (minor plus major, all threads): `getrusage(RUSAGE_SELF)`
/// on Unix, `None` elsewhere. A minor fault is a fresh page handed out by the kernel (or one
/// already in memory mapped in); a major one had to be read from disk.
pub fn process_page_faults() -> Option<u64> {
    #[cfg(unix)]
    {
        // SAFETY: an all-zero `rusage` is a valid value for the call to fill.
        let mut u: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: `u` is a valid rusage for the call to fill; it returns a status.
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } == 0 {
            let (minor, major) = (u.ru_minflt, u.ru_majflt);
            return Some(minor.max(0) as u64 + major.max(0) as u64);
        }
    }
    None
}

/// User + system seconds of a `/proc/PID/stat` line (fields after the `)` of the name).
pub fn parse_stat_cpu(stat: &str) -> Option<f64> {
    let rest = &stat[stat.rfind(')')? + 1..];
    // rest starts at field 3 (state): utime and stime are fields 14 and 15.
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: u64 = fields.get(11)?.parse().ok()?;
    let stime: u64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) as f64 / 100.0)
}

/// The `VmHWM:  1234 kB` line of a `/proc/PID/status` text, in bytes.
pub fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut parts = line["VmHWM:".len()..].split_whitespace();
    let value: u64 = parts.next()?.parse().ok()?;
    let scale = match parts.next() {
        Some("kB") | Some("KB") | Some("kb") => 1024,
        Some("mB") | Some("MB") => 1024 * 1024,
        Some("B") | None => 1,
        Some(_) => return None,
    };
    value.checked_mul(scale)
}

/// Wall time, process CPU seconds and page faults of a stretch of work.
#[derive(Debug, Clone, Copy, Default)]
struct Measure {
    wall: Duration,
    cpu: f64,
    faults: u64,
}

impl Measure {
    fn plus(self, o: Measure) -> Measure {
        Measure {
            wall: self.wall + o.wall,
            cpu: self.cpu + o.cpu,
            faults: self.faults + o.faults,
        }
    }
    fn minus(self, o: Measure) -> Measure {
        Measure {
            wall: self.wall.saturating_sub(o.wall),
            cpu: (self.cpu - o.cpu).max(0.0),
            faults: self.faults.saturating_sub(o.faults),
        }
    }
}

struct Open {
    name: Cow<'static, str>,
    start: Instant,
    cpu_start: Option<f64>,
    faults_start: Option<u64>,
    /// Time spent in stages entered inside this one.
    children: Measure,
}

struct Recorder {
    id: u64,
    start: Instant,
    cpu_start: Option<f64>,
    faults_start: Option<u64>,
    /// Every closing, in order: name, depth and exclusive measure (the per-stage rows are
    /// their sums, [`per_stage`]).
    spans: Vec<(Cow<'static, str>, usize, Measure)>,
    stack: Vec<Open>,
}

impl Recorder {
    /// Close the innermost open stage.
    fn close(&mut self) {
        if let Some(open) = self.stack.pop() {
            let total = Measure {
                wall: open.start.elapsed(),
                cpu: match (open.cpu_start, process_cpu_seconds()) {
                    (Some(a), Some(b)) => (b - a).max(0.0),
                    _ => 0.0,
                },
                faults: match (open.faults_start, process_page_faults()) {
                    (Some(a), Some(b)) => b.saturating_sub(a),
                    _ => 0,
                },
            };
            let own = total.minus(open.children);
            self.spans.push((open.name, self.stack.len(), own));
            if let Some(parent) = self.stack.last_mut() {
                parent.children = parent.children.plus(total);
            }
        }
    }
}

/// Per stage, in order of first closing: the sum of its spans' exclusive measures and their
/// number.
fn per_stage<'a>(spans: &'a [(Cow<'static, str>, usize, Measure)]) -> Vec<(&'a str, Measure, u64)> {
    let mut stages: Vec<(&str, Measure, u64)> = Vec::new();
    for (name, _, m) in spans {
        match stages.iter_mut().find(|(n, _, _)| *n == name.as_ref()) {
            Some((_, t, c)) => {
                *t = t.plus(*m);
                *c += 1;
            }
            None => stages.push((name.as_ref(), *m, 1)),
        }
    }
    stages
}

thread_local! {
    static ACTIVE: RefCell<Option<Recorder>> = const { RefCell::new(None) };
    static NEXT_ID: std::cell::Cell<u64> = const { std::cell::Cell::new(1) };
}

/// Records the stages entered on this thread until [`Recording::finish`].
///
/// The record is the thread's, not the call's: while this thread waits inside a parallel
/// loop, rayon may have it run a job of another caller of the same pool (work stealing), and
/// the stages that job enters are recorded here too. Timings of concurrent meshes on one
/// pool can therefore include each other's stages; the meshes themselves never depend on it.
///
/// Recordings nest: starting one while another is active sets the outer one aside; finishing
/// the inner one returns its timings and hands its stages on to the outer one (as if they had
/// been entered there), so a timed call inside a timed run is counted once.
#[must_use = "finish() returns the timings"]
pub struct Recording {
    id: u64,
    outer: Option<Recorder>,
}

impl Recording {
    /// Start recording on this thread.
    pub fn start() -> Recording {
        let id = NEXT_ID.with(|n| {
            let id = n.get();
            n.set(id.wrapping_add(1));
            id
        });
        let outer = ACTIVE.with(|a| {
            a.borrow_mut().replace(Recorder {
                id,
                start: Instant::now(),
                cpu_start: process_cpu_seconds(),
                faults_start: process_page_faults(),
                spans: Vec::new(),
                stack: Vec::new(),
            })
        });
        Recording { id, outer }
    }

    /// Stop recording: the exclusive time of every stage, the total and the peak memory.
    pub fn finish(mut self) -> Timings {
        let outer = self.outer.take();
        let mine = ACTIVE.with(|a| {
            let mut a = a.borrow_mut();
            let mine = match a.take() {
                Some(r) if r.id == self.id => Some(r),
                other => {
                    // Not ours (finished out of order): leave it in place.
                    *a = other;
                    None
                }
            };
            if mine.is_some() {
                *a = outer;
            }
            mine
        });
        let Some(mut r) = mine else {
            return Timings {
                stages: Vec::new(),
                cpu: Vec::new(),
                faults: Vec::new(),
                calls: Vec::new(),
                spans: Vec::new(),
                total_seconds: 0.0,
                peak_memory_bytes: peak_memory_bytes(),
                cpu_seconds: None,
                page_faults: None,
            };
        };
        while !r.stack.is_empty() {
            r.close();
        }
        let total = r.start.elapsed();
        // Hand the stages on to the outer recording, if any.
        ACTIVE.with(|a| {
            if let Some(o) = a.borrow_mut().as_mut() {
                let mut sum = Measure::default();
                let depth = o.stack.len();
                for (n, d, m) in &r.spans {
                    o.spans.push((n.clone(), depth + d, *m));
                    sum = sum.plus(*m);
                }
                if let Some(parent) = o.stack.last_mut() {
                    parent.children = parent.children.plus(sum);
                }
            }
        });
        let cpu_seconds = match (r.cpu_start, process_cpu_seconds()) {
            (Some(a), Some(b)) => Some((b - a).max(0.0)),
            _ => None,
        };
        let page_faults = match (r.faults_start, process_page_faults()) {
            (Some(a), Some(b)) => Some(b.saturating_sub(a)),
            _ => None,
        };
        let stages = per_stage(&r.spans);
        let name = |n: &str| n.to_string();
        Timings {
            stages: stages
                .iter()
                .map(|(n, m, _)| (name(n), m.wall.as_secs_f64()))
                .collect(),
            cpu: if cpu_seconds.is_some() {
                stages.iter().map(|(n, m, _)| (name(n), m.cpu)).collect()
            } else {
                Vec::new()
            },
            faults: if page_faults.is_some() {
                stages.iter().map(|(n, m, _)| (name(n), m.faults)).collect()
            } else {
                Vec::new()
            },
            calls: stages.iter().map(|(n, _, c)| (name(n), *c)).collect(),
            spans: r
                .spans
                .iter()
                .map(|(n, depth, m)| Span {
                    stage: name(n),
                    depth: *depth,
                    seconds: m.wall.as_secs_f64(),
                    cpu_seconds: if cpu_seconds.is_some() { m.cpu } else { 0.0 },
                    page_faults: if page_faults.is_some() { m.faults } else { 0 },
                })
                .collect(),
            total_seconds: total.as_secs_f64(),
            peak_memory_bytes: peak_memory_bytes(),
            cpu_seconds,
            page_faults,
        }
    }
}

impl Drop for Recording {
    /// A recording dropped without [`Recording::finish`] stops without reporting.
    fn drop(&mut self) {
        let outer = self.outer.take();
        let id = self.id;
        ACTIVE.with(|a| {
            if let Ok(mut a) = a.try_borrow_mut() {
                if a.as_ref().is_some_and(|r| r.id == id) {
                    *a = outer;
                }
            }
        });
    }
}

/// An open stage; it closes when dropped.
#[must_use = "the stage closes when this guard is dropped"]
pub struct Stage {
    /// `(recording id, stack depth)` when a recording was active.
    at: Option<(u64, usize)>,
    _not_send: std::marker::PhantomData<*const ()>,
}

impl Drop for Stage {
    fn drop(&mut self) {
        let Some((id, depth)) = self.at else { return };
        ACTIVE.with(|a| {
            if let Ok(mut a) = a.try_borrow_mut() {
                if let Some(r) = a.as_mut() {
                    // Close this stage and anything left open inside it.
                    if r.id == id {
                        while r.stack.len() > depth {
                            r.close();
                        }
                    }
                }
            }
        });
    }
}

/// Enter stage `name` until the returned guard is dropped (a no-op without an active
/// [`Recording`] on this thread).
pub fn enter(name: impl Into<Cow<'static, str>>) -> Stage {
    let at = ACTIVE.with(|a| {
        let mut a = a.try_borrow_mut().ok()?;
        let r = a.as_mut()?;
        let depth = r.stack.len();
        let cpu_start = r.cpu_start.and_then(|_| process_cpu_seconds());
        let faults_start = r.faults_start.and_then(|_| process_page_faults());
        r.stack.push(Open {
            name: name.into(),
            start: Instant::now(),
            cpu_start,
            faults_start,
            children: Measure::default(),
        });
        Some((r.id, depth))
    });
    Stage {
        at,
        _not_send: std::marker::PhantomData,
    }
}

/// Run `f` as stage `name`.
pub fn span<T>(name: &'static str, f: impl FnOnce() -> T) -> T {
    let _stage = enter(name);
    f()
}

/// Run `f` on a worker thread of rayon's pool, with this thread's recording (if any) moved
/// there for the call and back after it, so that the stages `f` enters are recorded as if it
/// ran here. On a worker thread already, `f` simply runs.
///
/// Issue 8: a pipeline driven from a thread outside the pool wakes every worker and puts
/// itself to sleep at each of its many parallel loops, and on two cores its idle workers
/// spin beside it; driven from a worker, each loop starts on a thread that does its share
/// and wakes only the others (1e3 bubbles: ~1 200 context switches per mesh -> ~65, the
/// `--timings` total 65-69 -> 56-57 ms median). The result does not depend on the thread
/// (same pool, same thread count).
pub fn on_pool_worker<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    if rayon::current_thread_index().is_some() {
        return f();
    }
    let here = ACTIVE.with(|a| a.try_borrow_mut().ok().and_then(|mut a| a.take()));
    let (out, back) = rayon::scope(move |_| {
        // The worker may be in the middle of other work (stealing while it waits): its own
        // recording is set aside and put back, also if `f` panics.
        struct Restore(Option<Option<Recorder>>);
        impl Drop for Restore {
            fn drop(&mut self) {
                if let Some(saved) = self.0.take() {
                    ACTIVE.with(|a| {
                        if let Ok(mut a) = a.try_borrow_mut() {
                            *a = saved;
                        }
                    });
                }
            }
        }
        let saved = ACTIVE.with(|a| {
            a.try_borrow_mut()
                .ok()
                .map(|mut a| std::mem::replace(&mut *a, here))
        });
        let restore = Restore(saved);
        let out = f();
        let back = match restore.0 {
            Some(_) => ACTIVE.with(|a| a.try_borrow_mut().ok().and_then(|mut a| a.take())),
            None => None,
        };
        drop(restore);
        (out, back)
    });
    if back.is_some() {
        ACTIVE.with(|a| {
            if let Ok(mut a) = a.try_borrow_mut() {
                *a = back;
            }
        });
    }
    out
}

/// Whether a recording is active on this thread.
pub fn is_recording() -> bool {
    ACTIVE.with(|a| a.try_borrow().map(|a| a.is_some()).unwrap_or(false))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stages entered inside [`on_pool_worker`] run on a pool worker and land in the calling
    /// thread's recording; the worker keeps no recording afterwards, also after a panic.
    #[test]
    fn on_pool_worker_carries_the_recording_there_and_back() {
        std::thread::spawn(|| {
            assert!(rayon::current_thread_index().is_none());
            let r = Recording::start();
            let before = enter("outer");
            let on = on_pool_worker(|| {
                let _s = enter("inside");
                assert!(is_recording(), "the recording moved to the worker");
                rayon::current_thread_index()
            });
            assert!(on.is_some(), "ran on a pool worker");
            assert!(is_recording(), "and came back");
            drop(before);
            let t = r.finish();
            let calls = |n: &str| t.calls.iter().find(|(m, _)| m == n).map(|c| c.1);
            assert_eq!(calls("inside"), Some(1));
            assert_eq!(calls("outer"), Some(1));
            // A panic inside: caught by the caller; no worker is left recording.
            let r = Recording::start();
            let caught = std::panic::catch_unwind(|| on_pool_worker(|| panic!("inside")));
            assert!(caught.is_err());
            assert!(rayon::broadcast(|_| !is_recording()).into_iter().all(|b| b));
            drop(r);
            assert!(!is_recording());
            // On a worker already, it runs in place.
            let same = rayon::scope(|_| {
                let here = rayon::current_thread_index();
                (here, on_pool_worker(rayon::current_thread_index))
            });
            assert_eq!(same.0, same.1);
        })
        .join()
        .unwrap();
    }

    /// The process CPU clock resolves a couple of milliseconds (the `/proc/self/stat` ticks
    /// it replaced jump by 10 ms), and only goes forward. Other test threads of the process
    /// add to the clock, so an attempt may overshoot: the best of three counts.
    #[cfg(unix)]
    #[test]
    fn process_cpu_clock_is_fine_grained() {
        let attempt = || {
            let start = process_cpu_seconds().expect("a process CPU clock on Unix");
            let wall = Instant::now();
            let mut last = start;
            let mut x = 1u64;
            while last - start < 0.002 && wall.elapsed() < Duration::from_secs(10) {
                for _ in 0..1000 {
                    x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
                }
                let now = process_cpu_seconds().unwrap();
                assert!(now >= last, "backwards: {last} -> {now}");
                last = now;
            }
            last - start
        };
        let best = (0..3).map(|_| attempt()).fold(f64::INFINITY, f64::min);
        assert!(
            (0.002..0.008).contains(&best),
            "first reading past 2 ms of CPU is {best} s after the start"
        );
    }

    #[test]
    fn vm_hwm_is_parsed_in_bytes() {
        let s = "Name:\tx\nVmPeak:\t  2000 kB\nVmHWM:\t    1234 kB\nVmRSS:\t 99 kB\n";
        assert_eq!(parse_vm_hwm(s), Some(1234 * 1024));
        assert_eq!(parse_vm_hwm("VmRSS: 1 kB\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM: x kB\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM: 5 parsecs\n"), None);
    }

    #[test]
    fn stat_cpu_is_utime_plus_stime() {
        // pid (comm with ) and spaces) state ppid ... utime=250 stime=50 ...
        let s = "42 (a) b c) R 1 2 3 4 5 6 7 8 9 10 250 50 0 0 20 0 1 0 100 200 300";
        assert_eq!(parse_stat_cpu(s), Some(3.0));
        assert_eq!(parse_stat_cpu("garbage"), None);
        if cfg!(target_os = "linux") {
            assert!(process_cpu_seconds().is_some_and(|c| c >= 0.0));
        }
    }

    #[test]
    fn stages_are_exclusive_and_add_up() {
        let rec = Recording::start();
        {
            let _a = enter("a");
            span("b", || std::hint::black_box((0..10_000u64).sum::<u64>()));
            span("b", || ());
        }
        span("c", || ());
        let t = rec.finish();
        let calls: Vec<u64> = t.calls.iter().map(|(_, c)| *c).collect();
        assert_eq!(calls, [2, 1, 1]);
        let names: Vec<&str> = t.stages.iter().map(|(n, _)| n.as_str()).collect();
        // "b" closes before "a", so it is recorded first.
        assert_eq!(names, ["b", "a", "c"]);
        assert!(t.stages.iter().all(|(_, s)| *s >= 0.0));
        let sum: f64 = t.stages.iter().map(|(_, s)| s).sum();
        assert!(sum <= t.total_seconds + 1e-9, "{t:?}");
        // One span per entry, in closing order, at the depth it was entered.
        let spans: Vec<(&str, usize)> = t
            .spans
            .iter()
            .map(|s| (s.stage.as_str(), s.depth))
            .collect();
        assert_eq!(spans, [("b", 1), ("b", 1), ("a", 0), ("c", 0)]);
        assert_spans_add_up(&t);
        assert!(!is_recording());
    }

    /// Per stage, the spans' count is its calls, their wall and CPU seconds add up to its row
    /// (sums of the same durations, to rounding) and their faults to its faults exactly.
    fn assert_spans_add_up(t: &Timings) {
        for (name, calls) in &t.calls {
            let mine: Vec<&Span> = t.spans.iter().filter(|s| &s.stage == name).collect();
            assert_eq!(mine.len() as u64, *calls, "{name}");
            let wall: f64 = mine.iter().map(|s| s.seconds).sum();
            assert!(
                (wall - t.seconds(name)).abs() <= 1e-9,
                "{name}: {wall} vs {t:?}"
            );
            if let Some((_, cpu)) = t.cpu.iter().find(|(n, _)| n == name) {
                let sum: f64 = mine.iter().map(|s| s.cpu_seconds).sum();
                assert!((sum - cpu).abs() <= 1e-9, "{name}: {sum} vs {cpu}");
            }
            let faults: u64 = mine.iter().map(|s| s.page_faults).sum();
            assert_eq!(faults, t.stage_faults(name), "{name}");
        }
        assert!(t
            .spans
            .iter()
            .all(|s| t.calls.iter().any(|(n, _)| *n == s.stage)));
    }

    #[test]
    fn rework_is_what_follows_the_first_check() {
        let sp = |stage: &str, seconds: f64| Span {
            stage: stage.into(),
            depth: 0,
            seconds,
            cpu_seconds: 2.0 * seconds,
            page_faults: 0,
        };
        let mut t = Timings {
            stages: Vec::new(),
            cpu: Vec::new(),
            faults: Vec::new(),
            calls: Vec::new(),
            spans: vec![
                sp("sampling", 1.0),
                sp("blocking", 2.0),
                sp("grids", 4.0),
                sp("quality_check", 0.5),
                sp("blocking", 0.25),
                sp("grids", 0.125),
                sp("quality_check", 0.0625),
                sp("quality", 8.0),
                sp("write_json", 16.0),
                // A second mesh after the first one was done (`--compare-modes`).
                sp("grids", 64.0),
                sp("quality_check", 128.0),
            ],
            total_seconds: 256.0,
            peak_memory_bytes: None,
            cpu_seconds: None,
            page_faults: None,
        };
        assert_eq!(REWORK_STAGES.first(), Some(&"sampling"));
        assert_eq!(REWORK_STAGES.last(), Some(&"quality_check"));
        assert!(!REWORK_STAGES.contains(&"quality") && !REWORK_STAGES.contains(&"input"));
        let r = t.rework();
        assert_eq!(r.checks, 1);
        let line = t.table();
        let line = line
            .lines()
            .find(|l| l.contains("rework"))
            .expect("a rework line");
        assert!(
            line.contains("437.50") && line.contains("1 rebuild"),
            "{line}"
        );
        assert_eq!(r.seconds, 0.25 + 0.125 + 0.0625);
        assert_eq!(r.cpu_seconds, 2.0 * r.seconds);
        // No check: nothing counts as rework.
        t.spans.retain(|s| s.stage != "quality_check");
        assert_eq!(t.rework(), Rework::default());
        assert!(!t.table().contains("rework"));
    }

    #[test]
    fn nothing_is_recorded_without_a_recording() {
        assert!(!is_recording());
        let g = enter("x");
        assert!(g.at.is_none());
        drop(g);
        let rec = Recording::start();
        let t = rec.finish();
        assert!(t.stages.is_empty());
        assert!(t.rows().iter().any(|(n, _)| n == "other"));
    }

    #[test]
    fn nested_recordings_hand_their_stages_on() {
        let outer = Recording::start();
        let _s = enter("outer_stage");
        let inner = Recording::start();
        span("inner_stage", || ());
        let ti = inner.finish();
        assert_eq!(ti.stages.len(), 1);
        drop(_s);
        let to = outer.finish();
        let names: Vec<&str> = to.stages.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["inner_stage", "outer_stage"]);
        // The inner span is handed on below the stage that was open around the inner
        // recording.
        let spans: Vec<(&str, usize)> = to
            .spans
            .iter()
            .map(|s| (s.stage.as_str(), s.depth))
            .collect();
        assert_eq!(spans, [("inner_stage", 1), ("outer_stage", 0)]);
        assert_spans_add_up(&to);
    }

    #[test]
    fn json_has_every_stage() {
        let t = Timings {
            stages: vec![("write_vtk".into(), 0.5), ("grids".into(), 0.25)],
            cpu: vec![("write_vtk".into(), 0.75), ("grids".into(), 0.25)],
            faults: vec![("write_vtk".into(), 7), ("grids".into(), 900)],
            calls: vec![("write_vtk".into(), 1), ("grids".into(), 2)],
            spans: vec![
                Span {
                    stage: "grids".into(),
                    depth: 0,
                    seconds: 0.125,
                    cpu_seconds: 0.125,
                    page_faults: 800,
                },
                Span {
                    stage: "grids".into(),
                    depth: 0,
                    seconds: 0.125,
                    cpu_seconds: 0.125,
                    page_faults: 100,
                },
                Span {
                    stage: "write_vtk".into(),
                    depth: 1,
                    seconds: 0.5,
                    cpu_seconds: 0.75,
                    page_faults: 7,
                },
            ],
            total_seconds: 1.0,
            peak_memory_bytes: None,
            cpu_seconds: Some(1.5),
            page_faults: Some(1000),
        };
        let v = t.to_json();
        for s in STAGES.iter().chain(&["write_vtk", "other"]) {
            assert!(v["stages"][s].as_f64().is_some(), "{s}");
        }
        assert_eq!(v["stages"]["other"].as_f64(), Some(0.25));
        assert_eq!(v["cpu_stages"]["other"].as_f64(), Some(0.5));
        assert_eq!(v["cpu_stages"]["input"].as_f64(), Some(0.0));
        assert_eq!(v["calls"]["grids"].as_u64(), Some(2));
        assert!(v["peak_memory_bytes"].is_null());
        assert_eq!(v["page_faults"].as_u64(), Some(1000));
        assert_eq!(v["fault_stages"]["grids"].as_u64(), Some(900));
        assert_eq!(v["fault_stages"]["input"].as_u64(), Some(0));
        // The unattributed rest: 1000 - 907.
        assert_eq!(v["fault_stages"]["other"].as_u64(), Some(93));
        let spans = v["spans"].as_array().unwrap();
        assert_eq!(spans.len(), 3);
        assert_eq!(spans[1]["stage"], "grids");
        assert_eq!(spans[1]["page_faults"].as_u64(), Some(100));
        assert_eq!(spans[2]["depth"].as_u64(), Some(1));
        assert_eq!(spans[2]["cpu_seconds"].as_f64(), Some(0.75));
        // No `quality_check` span: no rework.
        assert_eq!(v["rework"]["checks"].as_u64(), Some(0));
        assert_eq!(v["rework"]["seconds"].as_f64(), Some(0.0));
        let table = t.table();
        assert!(table.contains("write_vtk"));
        let other = table.lines().find(|l| l.starts_with("other")).unwrap();
        assert!(other.trim_end().ends_with(" 93"), "{other}");
        // Without a count: null in JSON, "-" in the table.
        let none = Timings {
            faults: Vec::new(),
            page_faults: None,
            ..t
        };
        assert!(none.to_json()["fault_stages"].is_null());
        assert!(none.to_json()["spans"][0]["page_faults"].is_null());
        assert!(none.to_json()["page_faults"].is_null());
        let grids = none.table();
        let grids = grids.lines().find(|l| l.starts_with("grids")).unwrap();
        assert!(grids.trim_end().ends_with('-'), "{grids}");
    }

    /// A stage that touches fresh memory is charged its page faults, and the stage around it
    /// only its own: 64 MiB mapped and written page by page is at least 16 384 faults of 4 KiB
    /// (fewer with 2 MiB pages, so the bound is taken from the page size the kernel used: at
    /// least one fault per 2 MiB), counted in the inner stage and not in the outer one.
    #[cfg(target_os = "linux")]
    #[test]
    fn fresh_memory_is_charged_to_its_stage() {
        const BYTES: usize = 64 << 20;
        let rec = Recording::start();
        {
            let _outer = enter("outer");
            span("touch", || {
                // A fresh mapping of its own (not the allocator's recycled memory).
                // SAFETY: an anonymous private mapping; checked for failure; unmapped below.
                let p = unsafe {
                    libc::mmap(
                        std::ptr::null_mut(),
                        BYTES,
                        libc::PROT_READ | libc::PROT_WRITE,
                        libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                        -1,
                        0,
                    )
                };
                assert_ne!(p, libc::MAP_FAILED);
                let bytes = p.cast::<u8>();
                for off in (0..BYTES).step_by(4096) {
                    // SAFETY: `off < BYTES`, inside the mapping.
                    unsafe { bytes.add(off).write_volatile(1) };
                }
                // SAFETY: the mapping made above, of that length.
                assert_eq!(unsafe { libc::munmap(p, BYTES) }, 0);
            });
        }
        let t = rec.finish();
        let touch = t.stage_faults("touch");
        assert!(touch >= (BYTES >> 21) as u64, "{t:?}");
        assert!(t.page_faults.is_some_and(|all| all >= touch), "{t:?}");
        // The outer stage did nothing itself; other test threads may fault meanwhile, so
        // allow a little.
        assert!(t.stage_faults("outer") < touch.max(64) / 4 + 64, "{t:?}");
        let v = t.to_json();
        assert_eq!(v["fault_stages"]["touch"].as_u64(), Some(touch));
    }
}
