//! The median radius of the exact vertices around each circle, for the wall-normal counts
//! (issue 8).
//!
//! [`near_medians`] is `radii_by_circle(vertices, ncirc)` with `median` applied to each list
//! (see `super::radii_by_circle` and `super::median`), without a vector per circle: the radii
//! are bucketed by circle into one array (counted, then placed: [`crate::buckets::group`])
//! and each bucket's median is selected in place. The median is the element a sort by
//! `f64::total_cmp` of the bucket's finite radii puts at `len / 2`: a total order, so the same
//! value, bit for bit, whatever the order of the bucket. Tested against the per-circle lists below.

use super::ExactVertex;
use crate::domain::CircleId;

/// Per circle slot (`c + 1`, `ncirc` slots): the median of the finite radii of the vertices
/// touching circle `c` (a vertex listing a circle twice counts once; circles outside
/// `-1..ncirc - 1` are ignored), `None` when there is none.
pub(crate) fn near_medians(vertices: &[ExactVertex], ncirc: usize) -> Vec<Option<f64>> {
    let slot = |c: CircleId| usize::try_from(c + 1).ok().filter(|&i| i < ncirc);
    // Each vertex's circles once, in the order `radii_by_circle` lists them.
    let (start, mut radii) = crate::buckets::group(ncirc, || {
        vertices.iter().flat_map(|v| {
            v.circles
                .iter()
                .enumerate()
                .filter(|&(k, c)| !v.circles[..k].contains(c))
                .filter_map(move |(_, &c)| slot(c).map(|i| (i, v.radius)))
        })
    });
    (0..ncirc)
        .map(|i| median_in_place(&mut radii[start[i]..start[i + 1]]))
        .collect()
}

/// The median of the finite values of `v` (`super::median` of them; `v` is reordered).
fn median_in_place(v: &mut [f64]) -> Option<f64> {
    let mut n = 0;
    for i in 0..v.len() {
        if v[i].is_finite() {
            v.swap(n, i);
            n += 1;
        }
    }
    if n == 0 {
        return None;
    }
    let k = n / 2;
    Some(*v[..n].select_nth_unstable_by(k, f64::total_cmp).1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random vertices (circles repeated within a vertex, out of range, collapsed vertices
    /// with more circles; radii with ties, signed zeros, infinities and NaN): the same bits as
    /// `median` of each list of `radii_by_circle`.
    #[test]
    fn near_medians_are_the_medians_of_the_per_circle_lists() {
        let mut rng = crate::layouts::SplitMix64(31);
        for case in 0..400u64 {
            let ncirc = 1 + (case % 13) as usize;
            let nv = (case % 37) as usize;
            let vertices: Vec<ExactVertex> = (0..nv)
                .map(|_| {
                    let deg = 2 + (rng.next_u64() % 4) as usize;
                    let circles: Vec<CircleId> = (0..deg)
                        .map(|_| (rng.next_u64() % (ncirc as u64 + 2)) as CircleId - 2)
                        .collect();
                    let radius = match rng.next_u64() % 9 {
                        0 => f64::NAN,
                        1 => f64::INFINITY,
                        2 => 0.0,
                        3 => -0.0,
                        4 => 0.5,
                        _ => rng.next_f64(),
                    };
                    ExactVertex {
                        center: [0.0; 2],
                        radius,
                        tangent: vec![[0.0; 2]; circles.len()],
                        circles,
                    }
                })
                .collect();
            let want: Vec<Option<u64>> = super::super::radii_by_circle(&vertices, ncirc)
                .into_iter()
                .map(|l| super::super::median(l).map(f64::to_bits))
                .collect();
            let got: Vec<Option<u64>> = near_medians(&vertices, ncirc)
                .into_iter()
                .map(|m| m.map(f64::to_bits))
                .collect();
            assert_eq!(got, want, "case {case}");
        }
    }
}
