//! The triangle classes and the sampling invariants in one pass (issue 8).

use super::{Samples, Violation, ViolationKind};
use crate::domain::BOUNDING;
use crate::geometry::Triangulation;
use crate::medial::TriangleKind;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// [`crate::medial::classify`] and [`super::check_invariants`] of `tri` in one pass over the
/// triangles: the same classes and the same violations in the same order (tested in
/// `tests/perf_resample.rs`). Each triangle's circles and boundary edges are looked up once
/// (issue 8: the samples' circles, indices and counts are read in triangle order, scattered
/// over the sample arrays, and the two functions each read them for every triangle).
///
/// # Panics
/// When `tri` is not a triangulation of `samples.points`, as both.
pub fn classify_and_check(
    samples: &Samples,
    tri: &Triangulation,
) -> (Vec<TriangleKind>, Vec<Violation>) {
    let parts = if tri.len() >= PARALLEL_MIN {
        2 * rayon::current_num_threads()
    } else {
        1
    };
    classify_and_check_in(samples, tri, parts)
}

/// Fewest triangles classified on several threads (1e3 bubbles make ~65 000: 1.0 -> 0.7 ms
/// on two cores since the pipeline runs inside the pool; it was 2^18 before).
const PARALLEL_MIN: usize = 1 << 15;

/// [`classify_and_check`] by `parts` ranges of triangles, on the thread pool when more than
/// one: each range fills its own part of the classes (allocated here, so no worker's malloc
/// arena holds them) and lists its violations in triangle order; the boundary edges seen are
/// marked in one shared array (a mark is only ever set). The ranges' violations, in range
/// order, are the single pass's, so the result does not depend on `parts` (tests vary it).
#[doc(hidden)]
pub fn classify_and_check_in(
    samples: &Samples,
    tri: &Triangulation,
    parts: usize,
) -> (Vec<TriangleKind>, Vec<Violation>) {
    let mut out = super::duplicate_violations(samples, tri);
    let seen: Vec<AtomicBool> = (0..samples.len()).map(|_| AtomicBool::new(false)).collect();
    let mut kinds = vec![TriangleKind::Interior; tri.len()];
    let step = tri.len().div_ceil(parts.max(1)).max(1);
    let found: Vec<Vec<Violation>> = kinds
        .par_chunks_mut(step)
        .enumerate()
        .map(|(i, chunk)| classify_range(samples, tri, i * step, chunk, &seen))
        .collect();
    out.extend(found.into_iter().flatten());
    let seen: Vec<bool> = seen.into_iter().map(AtomicBool::into_inner).collect();
    super::push_missing_edges(&mut out, samples, tri, &seen);
    (kinds, out)
}

/// Classes of triangles `first..first + kinds.len()` into `kinds`, boundary edges marked in
/// `seen`; the violations of those triangles, in order.
fn classify_range(
    samples: &Samples,
    tri: &Triangulation,
    first: usize,
    kinds: &mut [TriangleKind],
    seen: &[AtomicBool],
) -> Vec<Violation> {
    let mut out = Vec::new();
    for (i, slot) in kinds.iter_mut().enumerate() {
        let t = first + i;
        let v = tri.triangle(t);
        let c = v.map(|s| samples.circle_of[s as usize]);
        // Per edge k (opposite vertex k), its first sample when it is a boundary edge.
        let mut from = [u32::MAX; 3];
        let mut count = 0;
        let mut edge = 0u8;
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (a, b) = (v[i], v[j]);
            if c[i] == c[j] && a != b {
                if samples.next(a) == b {
                    from[k] = a;
                } else if samples.next(b) == a {
                    from[k] = b;
                }
            }
            if from[k] != u32::MAX {
                seen[from[k] as usize].store(true, Ordering::Relaxed);
                count += 1;
                edge = k as u8;
            }
        }
        let kind = if c[0] == c[1] && c[1] == c[2] {
            if c[0] < 0 {
                TriangleKind::Outside
            } else {
                TriangleKind::Hole(c[0])
            }
        } else {
            match count {
                0 => TriangleKind::Interior,
                1 => TriangleKind::Boundary { edge },
                _ => TriangleKind::MultiBoundary,
            }
        };
        *slot = kind;
        let tt = t as u32;
        match kind {
            TriangleKind::Outside => out.push(Violation {
                circle: BOUNDING,
                kind: ViolationKind::Outside { triangle: tt },
            }),
            TriangleKind::MultiBoundary => {
                // Blame the circle of a vertex shared by two boundary edges (the edges
                // `(v[k], v[k + 1])` and `(v[k], v[k + 2])` are opposite `k + 2` and `k + 1`).
                let circle = (0..3)
                    .find(|&k| from[(k + 2) % 3] != u32::MAX && from[(k + 1) % 3] != u32::MAX)
                    .map(|k| c[k])
                    .unwrap_or(c[0]);
                out.push(Violation {
                    circle,
                    kind: ViolationKind::TwoBoundaryEdges { triangle: tt },
                });
            }
            TriangleKind::Interior => super::push_repeated_circle(&mut out, c, tt),
            TriangleKind::Hole(_) | TriangleKind::Boundary { .. } => {}
        }
    }
    out
}
