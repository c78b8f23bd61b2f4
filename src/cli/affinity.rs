//! Worker threads pinned to CPUs (issue 8).
//!
//! The tool's parallel loops are short (1 000 particles mesh in about 60 ms, in some fifty
//! parallel steps), so how fast an idle worker starts on the next one matters. On this
//! project's virtual machines it often did not: the guest scheduler packs runnable threads
//! onto fewer virtual CPUs (an idle virtual CPU halts, and waking it goes through the host),
//! so a worker woken for the second half of a `rayon::join` was at times queued behind the
//! thread that woke it. Measured on 1 000 bubbles (`mesh --block-cells 16 --format json
//! --timings`, 16 runs): the triangulation (two halves on two threads) took 8.8-9.1 ms in
//! most runs and 10-15.6 ms in 6 of 16, its CPU time unchanged, i.e. up to fully serial; with
//! each worker pinned to its own CPU it took 8.8-9.6 ms in every run, and the `--timings`
//! total went from a median of 64.8 ms (57.3-97.2) to 58.3 ms (57.2-61.6) over 20 interleaved
//! runs of each (1e4 and 1e5 bubbles: the same within the noise).
//!
//! Pinning applies only when there is one worker per CPU the process may run on (its
//! affinity mask, e.g. from `taskset` or a cgroup cpuset): worker `i` runs on the `i`-th of
//! those CPUs. A smaller `--threads` leaves the scheduler free (several such processes side
//! by side would otherwise all crowd onto the first CPUs), and so does `--no-pin`, and so does
//! `mesh-sequence`, which meshes on a pool of its own started from a worker (a thread inherits
//! the CPU mask of the thread that starts it, so that whole pool would share one CPU). Nothing
//! but the speed depends on it: the files are the same byte for byte (`tests/ux_affinity.rs`).
//! Linux only; elsewhere nothing is pinned.

use std::sync::atomic::{AtomicUsize, Ordering};

/// Workers asked to pin themselves, and those that did.
static ASKED: AtomicUsize = AtomicUsize::new(0);
static PINNED: AtomicUsize = AtomicUsize::new(0);

/// The CPUs for `workers` worker threads (worker `i` on the `i`-th): the CPUs this process
/// may run on when there are exactly `workers` of them (and more than one), else `None`.
pub fn plan(workers: usize, no_pin: bool) -> Option<Vec<usize>> {
    if no_pin || workers < 2 {
        return None;
    }
    let cpus = allowed_cpus();
    (cpus.len() == workers).then_some(cpus)
}

/// The number of workers rayon's global pool starts for `--threads` (`None`: one per CPU
/// the process may run on, or `RAYON_NUM_THREADS`), without starting it.
pub fn workers(threads: Option<usize>) -> usize {
    threads.unwrap_or_else(|| {
        std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            .filter(|&n| n > 0)
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
    })
}

/// The start handler of worker `i` under `plan`: pin it to its CPU.
pub fn start(plan: &Option<Vec<usize>>, i: usize) {
    if let Some(&cpu) = plan.as_ref().and_then(|p| p.get(i)) {
        ASKED.fetch_add(1, Ordering::Relaxed);
        if pin_current(cpu) {
            PINNED.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Whether the workers were pinned (each one that was asked succeeded; `timings.json`'s
/// `pinned_threads`).
pub fn pinned() -> bool {
    let asked = ASKED.load(Ordering::Relaxed);
    asked > 0 && PINNED.load(Ordering::Relaxed) == asked
}

/// The CPUs this process may run on, in increasing order (empty when unknown).
pub fn allowed_cpus() -> Vec<usize> {
    #[cfg(target_os = "linux")]
    // SAFETY: a zeroed `cpu_set_t` is a valid empty set; `sched_getaffinity` writes at most
    // its size.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) == 0 {
            return (0..libc::CPU_SETSIZE as usize)
                .filter(|&c| libc::CPU_ISSET(c, &set))
                .collect();
        }
    }
    Vec::new()
}

/// Pin the calling thread to CPU `cpu`; false when the kernel refused (or not Linux).
pub fn pin_current(cpu: usize) -> bool {
    #[cfg(target_os = "linux")]
    // SAFETY: as in `allowed_cpus`; `CPU_SET` is given a CPU below `CPU_SETSIZE`.
    unsafe {
        if cpu >= libc::CPU_SETSIZE as usize {
            return false;
        }
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        return libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0;
    }
    #[allow(unreachable_code)]
    {
        let _ = cpu;
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pinned thread may run on its CPU alone, and nothing changes for other threads.
    #[test]
    #[cfg(target_os = "linux")]
    fn a_pinned_thread_runs_on_its_cpu_alone() {
        let all = allowed_cpus();
        assert!(!all.is_empty(), "sched_getaffinity answers on Linux");
        let last = *all.last().unwrap();
        let seen = std::thread::spawn(move || (pin_current(last), allowed_cpus()))
            .join()
            .unwrap();
        assert_eq!(seen, (true, vec![last]));
        assert_eq!(allowed_cpus(), all, "the spawning thread keeps its mask");
        assert!(!pin_current(usize::MAX), "an impossible CPU is refused");
    }

    /// Pinning only with one worker per allowed CPU, more than one, and without `--no-pin`.
    #[test]
    fn pinning_is_planned_only_for_one_worker_per_cpu() {
        let n = allowed_cpus().len();
        assert_eq!(plan(1, false), None);
        assert_eq!(plan(n + 1, false), None);
        assert_eq!(plan(n.max(2), true), None);
        if n >= 2 {
            assert_eq!(plan(n, false), Some(allowed_cpus()));
            assert_eq!(plan(n - 1, false), None);
        }
        assert_eq!(workers(Some(3)), 3);
    }
}
