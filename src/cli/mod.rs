//! The command-line interface. Exit codes: 0 success, 1 failure to write output or an internal
//! error, 2 bad input (unreadable, malformed or invalid input, bad flags).

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod affinity;
mod allocator;
mod example;
mod mesh;
mod sequence;
mod triangulate;

/// Automatic multiblock structured meshes for 2D flow around circular particles.
#[derive(Parser, Debug)]
#[command(
    name = "medial-blocks",
    version,
    about,
    after_help = "Examples:
  medial-blocks mesh                                  # the built-in 7-hole example into out/
  medial-blocks example lattice -o lattice.json       # a starting layout
  medial-blocks mesh lattice.json -o lattice --format all
  medial-blocks --threads 2 mesh holes.csv --bounding 0,0,10

Exit codes: 0 success, 1 output could not be written or internal error, 2 bad input or flags.
Errors are printed on stderr."
)]
pub struct Cli {
    /// Print nothing on success (no summary, no progress bar).
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Worker threads for per-block work (default: one per core), 1 to 1024. Output does not
    /// depend on it.
    #[arg(long, global = true, value_name = "N", allow_negative_numbers = true)]
    threads: Option<usize>,
    /// Ask the kernel for 2 MiB pages (glibc on Linux, where transparent huge pages are given
    /// on request; the tool restarts itself once with GLIBC_TUNABLES=glibc.malloc.hugetlb=1).
    /// Faster for runs back to back; on virtual machines that hand free memory back to their
    /// host it can be slower. Output does not depend on it.
    #[arg(long, global = true)]
    huge_pages: bool,
    /// Leave the worker threads where the scheduler puts them. By default, with one worker
    /// per CPU the process may run on (no --threads, or --threads equal to that count), worker
    /// i runs on the i-th of those CPUs: on virtual machines an idle worker then starts
    /// sooner. Output does not depend on it.
    #[arg(long, global = true)]
    no_pin: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Delaunay-triangulate a CSV of points exactly (x,y per line).
    Triangulate(triangulate::Args),
    /// Mesh a domain of circles (JSON or CSV), or the built-in example.
    Mesh(Box<mesh::Args>),
    /// Write a ready-made domain JSON (hexagon, lattice, bubbles, square-lattice, periodic-bubbles).
    Example(example::Args),
    /// Mesh a sequence of frames (JSON Lines, one domain per line) in parallel, with a
    /// ParaView time series.
    MeshSequence(sequence::Args),
}

impl Command {
    /// Whether the global pool's workers may be pinned to CPUs for this command
    /// ([`affinity`]): not for `mesh-sequence`, which meshes on a pool of its own started from
    /// a worker, whose threads would inherit that worker's single CPU.
    fn may_pin(&self) -> bool {
        !matches!(self, Command::MeshSequence(_))
    }
}

/// Options every subcommand sees.
#[derive(Debug, Clone, Copy)]
pub struct Global {
    /// `--threads` (0: not given, one per core).
    pub threads: usize,
    /// `--quiet`.
    pub quiet: bool,
}

/// A CLI failure: the message for stderr and the exit code.
pub struct Failure {
    pub code: u8,
    pub message: String,
}

impl Failure {
    pub fn input(message: impl Into<String>) -> Self {
        Failure {
            code: 2,
            message: message.into(),
        }
    }
    pub fn output(message: impl Into<String>) -> Self {
        Failure {
            code: 1,
            message: message.into(),
        }
    }
}

/// Stack of each worker thread: the command runs on one of them (`run`), so it gets the
/// 8 MiB a main thread has, not the 2 MiB of a spawned thread (address space only: pages are
/// touched as the stack grows).
const WORKER_STACK_BYTES: usize = 8 << 20;

/// Start rayon's global pool: `--threads` workers, or one per core (`RAYON_NUM_THREADS` if
/// set) without the flag; pinned to their CPUs unless `no_pin` ([`affinity`]).
fn set_threads(threads: Option<usize>, no_pin: bool) -> Result<(), Failure> {
    let max = medial_blocks::ranges::MAX_THREADS;
    if let Some(n) = threads.filter(|&n| n == 0 || n > max) {
        return Err(Failure::input(format!(
            "--threads {n} is out of range: expected 1 <= N <= {max}"
        )));
    }
    let plan = affinity::plan(affinity::workers(threads), no_pin);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .stack_size(WORKER_STACK_BYTES)
        .start_handler(move |i| affinity::start(&plan, i))
        .build_global()
        .map_err(|e| {
            let n = threads.map_or_else(|| "the".to_string(), |n| n.to_string());
            Failure::output(format!("cannot start {n} worker threads: {e}"))
        })
}

/// A command line clap refuses: help and version as clap prints them, every other error (an
/// unknown flag, a value that does not parse, flags that conflict) as one line `error: ...` on
/// stderr with exit code 2, like every other bad input; clap's usage block is left out.
fn command_line_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp
        | ErrorKind::DisplayVersion
        | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
        _ => {
            // clap's first paragraph (its message, with the flags it names on their own
            // lines), joined into one line.
            let text = e.render().to_string();
            let first: Vec<&str> = text
                .lines()
                .map(str::trim)
                .take_while(|l| !l.is_empty())
                .collect();
            let first = first.join(" ");
            let message = first.strip_prefix("error: ").unwrap_or(&first);
            eprintln!("error: {message} (see --help)");
            ExitCode::from(2)
        }
    }
}

pub fn run() -> ExitCode {
    restore_sigpipe();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return command_line_error(e),
    };
    // Before any other thread exists (clap starts none).
    allocator::tune(cli.huge_pages);
    let global = Global {
        threads: cli.threads.unwrap_or(0),
        quiet: cli.quiet,
    };
    // The command runs on a worker of the global pool, this thread asleep until it returns
    // (issue 8): reading, meshing, the report and the writers all drive their parallel
    // loops from inside the pool. Output does not depend on it.
    let no_pin = cli.no_pin || !cli.command.may_pin();
    let result = set_threads(cli.threads, no_pin).and_then(|()| {
        medial_blocks::timings::on_pool_worker(move || match cli.command {
            Command::Triangulate(args) => triangulate::run(args),
            Command::Mesh(args) => mesh::run(*args, global),
            Command::Example(args) => example::run(args, global),
            Command::MeshSequence(args) => sequence::run(args, global),
        })
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

/// Let a closed pipe end the process quietly, as it ends `cat` or `grep`: Rust ignores
/// `SIGPIPE`, so `medial-blocks mesh ... | head -1` made the summary's `println!` panic with
/// "failed printing to stdout: Broken pipe" (and a backtrace) once `head` had exited. With
/// the default action the process stops at the first write to the closed pipe; the files it
/// writes are complete by then (the summary is printed after them), and writes to files are
/// unaffected.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting the disposition of SIGPIPE to its default, before any other thread
    // exists; no handler is installed.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `mesh-sequence` starts its own pool from a worker (threads inherit their creator's CPU
    /// mask): the global pool is not pinned for it, and is for the other commands.
    #[test]
    fn only_commands_without_a_pool_of_their_own_are_pinned() {
        let parse = |args: &[&str]| Cli::try_parse_from(args).unwrap().command;
        assert!(parse(&["medial-blocks", "mesh"]).may_pin());
        assert!(parse(&["medial-blocks", "triangulate", "p.csv"]).may_pin());
        assert!(parse(&["medial-blocks", "example", "lattice"]).may_pin());
        assert!(!parse(&["medial-blocks", "mesh-sequence", "f.jsonl"]).may_pin());
    }
}
