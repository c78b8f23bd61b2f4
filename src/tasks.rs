//! Leaf sizes of the parallel loops (issue 8).
//!
//! rayon cuts an indexed parallel loop into a few leaves per thread up front, and cuts a
//! leaf further only when another thread steals it; once a leaf has started, it runs to its
//! end on its thread. The last leaf of a loop can then be a large part of the loop, and on a
//! two-core machine the other core waits for it: at 1e5 bubbles the quality pass's last leaf
//! kept one CPU alone for about 40 ms (a system-wide profile, the other CPU idle). Each heavy
//! loop therefore caps its leaves with `with_max_len`, at about a millisecond of work, which
//! still leaves it a dozen leaves or more at 1e3 particles. The cut changes which thread
//! computes what, never a result: every loop it applies to collects in index order.

/// Blocks per leaf of loops that cost some microseconds per block (the quality pass, whose
/// items are chunks of blocks, takes this many blocks' worth of chunks).
pub(crate) const BLOCKS: usize = 256;

/// Medial pieces (two blocks each) per leaf of exact mode's per-piece loops.
pub(crate) const PIECES: usize = 128;

/// Circles per leaf of the sampling's per-circle plans.
pub(crate) const CIRCLES: usize = 256;

/// Triangles per leaf, at least, of loops that cost some nanoseconds per triangle (a class
/// looked up or computed).
pub(crate) const TRIANGLES: usize = 16_384;

/// Medial arcs (or exact mode's pieces, one per arc) per leaf, at least, of loops that cost
/// some nanoseconds per arc (a check of its chains or triangles, a product of its counts).
pub(crate) const ARCS: usize = 4096;

/// The parts' items in order, in one vector, moved in parallel: each part into its own
/// range of the result. rayon's `collect` of a flattened iterator (and the serial
/// `into_iter().flatten().collect()`) append the parts on one thread, into fresh pages: at
/// 1e5 bubbles exact mode's per-piece results (60 MB) took 60 ms on one CPU while the other
/// waited (issue 8). The same vector for any pool.
pub(crate) fn concat<T: Send>(parts: Vec<Vec<T>>) -> Vec<T> {
    use rayon::prelude::*;
    let total: usize = parts.iter().map(Vec::len).sum();
    let mut out: Vec<T> = Vec::with_capacity(total);
    let mut rest = &mut out.spare_capacity_mut()[..total];
    let mut jobs = Vec::with_capacity(parts.len());
    for part in parts {
        let (range, tail) = std::mem::take(&mut rest).split_at_mut(part.len());
        rest = tail;
        jobs.push((range, part));
    }
    jobs.into_par_iter().for_each(|(range, part)| {
        for (slot, item) in range.iter_mut().zip(part) {
            slot.write(item);
        }
    });
    // SAFETY: the ranges cover `out`'s first `total` slots (the parts' lengths add up to
    // `total`) and each slot of a range was written by the loop above, which moves every
    // item of its part (a range is exactly as long as its part).
    unsafe { out.set_len(total) };
    out
}

/// The parts' items, in order (flat index `f`, part by part), each moved to place `dest[f]`
/// of the result, in parallel; `None` (the parts dropped) unless `dest` is a permutation of
/// `0..total`, `total` the number of items. A serial `Vec::push` of a permutation of 36 MB
/// of medial arcs took 35-40 ms at 1e5 bubbles on one CPU while the other waited (issue 8).
/// The same vector for any pool.
pub(crate) fn scatter<T: Send>(parts: Vec<Vec<T>>, dest: &[u32]) -> Option<Vec<T>> {
    use rayon::prelude::*;
    let total: usize = parts.iter().map(Vec::len).sum();
    if dest.len() != total {
        return None;
    }
    // `total` values below `total`, no two equal: every place exactly once.
    let mut seen = vec![false; total];
    for &d in dest {
        let s = seen.get_mut(d as usize)?;
        if *s {
            return None;
        }
        *s = true;
    }
    let mut firsts = Vec::with_capacity(parts.len());
    let mut first = 0;
    for part in &parts {
        firsts.push(first);
        first += part.len();
    }
    let mut out: Vec<T> = Vec::with_capacity(total);
    let base = Places(out.as_mut_ptr());
    parts.into_par_iter().zip(firsts).for_each(|(part, first)| {
        for (j, item) in part.into_iter().enumerate() {
            // SAFETY: `dest` is a permutation of `0..total` (checked above), so the place
            // is inside `out`'s allocation (capacity `total`) and no other item is
            // written there; `out` is not read or moved until every write is done.
            unsafe { base.at(dest[first + j] as usize).write(item) };
        }
    });
    // SAFETY: every place `0..total` was written exactly once above (a permutation).
    unsafe { out.set_len(total) };
    Some(out)
}

/// The start of [`scatter`]'s result, shared by its tasks, which write disjoint places.
struct Places<T>(*mut T);

// SAFETY: the tasks write `T`s (which are `Send`) to distinct places only (see `scatter`).
unsafe impl<T: Send> Sync for Places<T> {}

impl<T> Places<T> {
    /// Place `i` (a method, so that a closure captures the whole `Places`, which is `Sync`,
    /// not its raw pointer field).
    fn at(&self, i: usize) -> *mut T {
        self.0.wrapping_add(i)
    }
}

/// Items of a slice that parallel tasks take out (each at most once, whoever asks first),
/// leaving `T::default()` in their place: for a gather whose sources are distinct by
/// construction (an earlier result's parts moved into a new one) but not split into disjoint
/// ranges. A second take of an item gives `None`.
pub(crate) struct Claims<'a, T> {
    items: *mut T,
    claimed: Vec<std::sync::atomic::AtomicBool>,
    _items: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: an item is reached only by the one `take` that flips its flag (an atomic swap), so
// no two threads touch the same item, and the items are `T: Send` moved to the taker; the
// slice is borrowed exclusively for `'a`, so nothing else reads it meanwhile.
unsafe impl<T: Send> Sync for Claims<'_, T> {}
// SAFETY: as above (the `Claims` only holds the exclusive borrow).
unsafe impl<T: Send> Send for Claims<'_, T> {}

impl<'a, T: Default> Claims<'a, T> {
    pub(crate) fn new(items: &'a mut [T]) -> Claims<'a, T> {
        Claims {
            claimed: (0..items.len())
                .map(|_| std::sync::atomic::AtomicBool::new(false))
                .collect(),
            items: items.as_mut_ptr(),
            _items: std::marker::PhantomData,
        }
    }

    /// Item `i`, moved out; `None` when `i` is out of range or was taken before.
    pub(crate) fn take(&self, i: usize) -> Option<T> {
        let flag = self.claimed.get(i)?;
        if flag.swap(true, std::sync::atomic::Ordering::AcqRel) {
            return None;
        }
        // SAFETY: `i` is in range (it has a flag) and this call is the only one that flipped
        // its flag, so no other reference to the item exists (see the `Sync` impl).
        Some(std::mem::take(unsafe { &mut *self.items.add(i) }))
    }
}

#[cfg(test)]
mod tests {
    use super::{concat, scatter, Claims};

    /// Up to `parts` parts of owned items (empty, single and longer ones), for case `case`.
    fn random_parts(
        rng: &mut crate::layouts::SplitMix64,
        case: usize,
        parts: usize,
        longest: f64,
    ) -> Vec<Vec<String>> {
        (0..case % parts)
            .map(|p| {
                let n = match (case + p) % 4 {
                    0 => 0,
                    1 => 1,
                    _ => (rng.next_f64() * longest) as usize,
                };
                (0..n).map(|i| format!("{case}:{p}:{i}")).collect()
            })
            .collect()
    }

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    /// [`Claims::take`] from many tasks at once: every item reaches exactly one taker (the
    /// others get `None`), out-of-range indices give `None`, and the slice is left with the
    /// defaults in place of the taken items and the others untouched.
    #[test]
    fn claims_give_each_item_once() {
        use rayon::prelude::*;
        for threads in 1..=4 {
            let pool = pool(threads);
            let mut items: Vec<String> = (0..500).map(|i| format!("item {i}")).collect();
            let taken: Vec<Option<String>> = {
                let claims = Claims::new(&mut items[..400]);
                // Every index asked three times, out of order, plus some out of range.
                pool.install(|| {
                    (0..1300usize)
                        .into_par_iter()
                        .map(|k| claims.take((k * 7919) % 1300 % 410))
                        .collect()
                })
            };
            let mut got: Vec<String> = taken.into_iter().flatten().collect();
            got.sort();
            let mut want: Vec<String> = (0..400).map(|i| format!("item {i}")).collect();
            want.sort();
            assert_eq!(got, want, "{threads} threads");
            assert!(items[..400].iter().all(String::is_empty));
            assert!((400..500).all(|i| items[i] == format!("item {i}")));
        }
    }

    /// [`scatter`] against placing the flattened items one by one: random permutations,
    /// uneven and empty parts, items that own memory, pools of 1 to 3 threads; and `None`
    /// for a `dest` that is not a permutation (too short, too long, a repeated or an
    /// out-of-range place).
    #[test]
    fn scatter_places_every_item_once() {
        let mut rng = crate::layouts::SplitMix64(12);
        for case in 0..60usize {
            let parts = random_parts(&mut rng, case, 13, 40.0);
            let flat: Vec<String> = parts.iter().flatten().cloned().collect();
            let n = flat.len();
            // A random permutation (Fisher-Yates).
            let mut dest: Vec<u32> = (0..n as u32).collect();
            for i in (1..n).rev() {
                let j = ((rng.next_f64() * (i + 1) as f64) as usize).min(i);
                dest.swap(i, j);
            }
            let mut want = vec![String::new(); n];
            for (f, item) in flat.iter().enumerate() {
                want[dest[f] as usize] = item.clone();
            }
            for threads in 1..=3 {
                let got = pool(threads).install(|| scatter(parts.clone(), &dest));
                assert_eq!(got.as_ref(), Some(&want), "case {case}, {threads} threads");
            }
            if n >= 2 {
                let mut repeated = dest.clone();
                repeated[1] = repeated[0];
                assert_eq!(scatter(parts.clone(), &repeated), None);
                let mut outside = dest.clone();
                outside[n - 1] = n as u32;
                assert_eq!(scatter(parts.clone(), &outside), None);
            }
            if n >= 1 {
                assert_eq!(scatter(parts.clone(), &dest[..n - 1]), None);
            }
            let mut longer = dest.clone();
            longer.push(n as u32);
            assert_eq!(scatter(parts.clone(), &longer), None);
        }
    }

    /// [`concat`] against the serial flatten: empty and uneven parts, items that own memory
    /// (each dropped once: the strings compare equal after the move), on pools of 1 to 3
    /// threads.
    #[test]
    fn concat_is_the_serial_flatten() {
        let mut rng = crate::layouts::SplitMix64(11);
        for case in 0..60usize {
            let parts = random_parts(&mut rng, case, 17, 50.0);
            let want: Vec<String> = parts.iter().flatten().cloned().collect();
            for threads in 1..=3 {
                let got = pool(threads).install(|| concat(parts.clone()));
                assert_eq!(got, want, "case {case}, {threads} threads");
            }
        }
    }
}
