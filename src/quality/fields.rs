//! The per-cell figures of one block for the writers' cell arrays ([`super::cell_fields`]),
//! a band of rows at a time, with the reference formulas bit for bit.
//!
//! The same two loops as the per-block pass of [`super::rows`], with per-cell outputs instead
//! of histograms: loop 1 runs over every cell of a band at once in straight-line arithmetic
//! (vectorised: the edge vectors, lengths and directions once per edge, shared by the two
//! cells on either side, [`super::rows::band_edges`]; then the corner products, the four
//! corner angles as differences of edge directions, and the seven figures), and marks a cell
//! whose figures it cannot vouch for with a NaN smallest angle; loop 2 copies the cells in
//! cell order and measures the marked ones with the reference ([`cell_field_values`]).
//!
//! Why the fast path's figures are the reference's: the argument of [`super::rows`]'s module
//! doc (the same functions on the same operands, [`settled`](super::kernel::settled) corner candidates, the scaled
//! Jacobian from [`least_scaled_jacobian`](super::kernel::least_scaled_jacobian) only when its pick is certain, lengths in range);
//! besides, the smallest corner Jacobian is the least of four non-zero, non-NaN cross
//! products (a zero or NaN one is not [`settled`](super::kernel::settled)), which any order of comparisons gives, and
//! the skewness is `max(θmax - 90, 90 - θmin) / 90`, [`super::kernel::skewness`]'s expression.
//! The reference path costs four `atan2`, four square roots and up to four divisions more per
//! cell: writing the `.vtu` of 1 000 bubbles spent two fifths of its time there.

use super::kernel::cell_field_values;
use super::rows::BAND_NODES;
use super::rows::{band_edges, cell_core, edge_ratios, less, more, CellCore, EdgeArrays};
use super::{fold, CellFields};
use crate::geometry::Point;
use crate::mesh::BlockGrid;
use std::cell::RefCell;

/// Scratch space of [`cell_fields_into`]: the band's edges and loop 1's outputs, one array
/// per figure, indexed by the band's flat cell index `r w + i`.
#[derive(Default)]
struct FieldRows {
    edges: EdgeArrays,
    /// Smallest angle (NaN: the cell takes the reference path), largest angle, smallest
    /// Jacobian, skewness, edge ratio, scaled Jacobian, aspect ratio.
    out: [Vec<f64>; 7],
}

thread_local! {
    /// One scratch per thread: the writers call [`cell_fields_into`] once per block.
    static SCRATCH: RefCell<FieldRows> = RefCell::default();
}

/// Loop 1 over `lo.len()` cells from their edges (`b`, `t` bottom and top, `v` across the
/// row, as [`band_edges`] gives them): the seven figures of each cell into `lo` .. `ar`, and
/// NaN into `lo` for a cell that takes the reference path.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn field_loop(
    b: [&[f64]; 4],
    t: [&[f64]; 4],
    v: [&[f64]; 4],
    lo: &mut [f64],
    hi: &mut [f64],
    mj: &mut [f64],
    sk: &mut [f64],
    er: &mut [f64],
    sj: &mut [f64],
    ar: &mut [f64],
) {
    let n = lo.len();
    let (hi, mj, sk) = (&mut hi[..n], &mut mj[..n], &mut sk[..n]);
    let (er, sj, ar) = (&mut er[..n], &mut sj[..n], &mut ar[..n]);
    let (bx, by, bl, bt) = (&b[0][..n], &b[1][..n], &b[2][..n], &b[3][..n]);
    let (tx, ty, tl, tt) = (&t[0][..n], &t[1][..n], &t[2][..n], &t[3][..n]);
    let (ax, ay, al, at) = (&v[0][..n], &v[1][..n], &v[2][..n], &v[3][..n]);
    let (qx, qy, ql, qt) = (&v[0][1..=n], &v[1][1..=n], &v[2][1..=n], &v[3][1..=n]);
    for i in 0..n {
        let CellCore {
            c,
            edges,
            sj: s,
            a,
            fine,
            geom,
        } = cell_core(
            [bx[i], by[i], bl[i], bt[i]],
            [tx[i], ty[i], tl[i], tt[i]],
            [ax[i], ay[i], al[i], at[i]],
            [qx[i], qy[i], ql[i], qt[i]],
        );
        let (amin, amax) = (fold(a, less), fold(a, more));
        let (e, r) = edge_ratios(&edges);
        // NaN `lo`: the cell takes the reference path; NaN `sj` alone (its pick undecided,
        // `rows::REDO`): loop 2 takes the scaled Jacobian by the reference expression.
        lo[i] = if geom { amin } else { f64::NAN };
        hi[i] = amax;
        mj[i] = fold(c, less);
        sk[i] = more(amax - 90.0, 90.0 - amin) / 90.0;
        er[i] = e;
        sj[i] = if fine { s } else { f64::NAN };
        ar[i] = r;
    }
}

/// [`field_loop`] over a band (see [`band_edges`] for the arguments).
#[inline(always)]
fn band(nodes: &[Point], w: usize, nb: usize, edges: &mut EdgeArrays, out: &mut [Vec<f64>; 7]) {
    let m = EdgeArrays::cells_of_band(w, nb);
    for o in out.iter_mut() {
        o.resize(m, 0.0);
    }
    let (h, v) = edges.arrays(w, m);
    let (b, t, v) = band_edges(nodes, w, nb, h, v, m);
    let [lo, hi, mj, sk, er, sj, ar] = out;
    field_loop(b, t, v, lo, hi, mj, sk, er, sj, ar);
}

/// [`band`] compiled for AVX-512 (8-lane vectors; the same IEEE operations on the same
/// operands, no fused multiply-add, so the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn band_avx512(nodes: &[Point], w: usize, nb: usize, e: &mut EdgeArrays, out: &mut [Vec<f64>; 7]) {
    band(nodes, w, nb, e, out)
}

/// [`band`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn band_avx2(nodes: &[Point], w: usize, nb: usize, e: &mut EdgeArrays, out: &mut [Vec<f64>; 7]) {
    band(nodes, w, nb, e, out)
}

/// The figures of every cell of a well-formed `grid` with `ni, nj > 0`, appended to `f` in
/// cell order (`i + j ni`), equal bit for bit to [`cell_field_values`] of each cell.
pub(super) fn cell_fields_into(grid: &BlockGrid, f: &mut CellFields) {
    fields_with(grid, f, super::kernel::wide(), super::kernel::wider());
}

/// [`cell_fields_into`] with loop 1 in 4-lane (`wide`, AVX2) or 8-lane (`wider`, AVX-512)
/// vectors, else in the portable build; only what the CPU has may be asked for.
fn fields_with(grid: &BlockGrid, f: &mut CellFields, wide: bool, wider: bool) {
    SCRATCH.with(|s| {
        let mut s = s.borrow_mut();
        let FieldRows { edges, out } = &mut *s;
        let (ni, nj) = (grid.ni, grid.nj);
        let w = ni + 1;
        let per_band = (BAND_NODES / w).max(1);
        for j0 in (0..nj).step_by(per_band) {
            let nb = per_band.min(nj - j0);
            let nodes = &grid.nodes[j0 * w..(j0 + nb + 1) * w];
            #[cfg(target_arch = "x86_64")]
            if wider {
                // SAFETY: `wider` is only true when the CPU has these features.
                unsafe { band_avx512(nodes, w, nb, edges, out) };
            } else if wide {
                // SAFETY: `wide` is only true when the CPU has AVX2.
                unsafe { band_avx2(nodes, w, nb, edges, out) };
            } else {
                band(nodes, w, nb, edges, out);
            }
            #[cfg(not(target_arch = "x86_64"))]
            {
                let _ = (wide, wider);
                band(nodes, w, nb, edges, out);
            }
            // Loop 2, in cell order: whole rows where every cell took the fast path.
            for r in 0..nb {
                let row = r * w..r * w + ni;
                if !out[0][row.clone()].iter().any(|x| x.is_nan())
                    && !out[5][row.clone()].iter().any(|x| x.is_nan())
                {
                    for (dst, src) in f.arrays_mut().into_iter().zip(out.iter()) {
                        dst.extend_from_slice(&src[row.clone()]);
                    }
                    continue;
                }
                let (line, next) = (&nodes[r * w..(r + 1) * w], &nodes[(r + 1) * w..(r + 2) * w]);
                for (i, p) in row.enumerate() {
                    let q = [line[i], line[i + 1], next[i + 1], next[i]];
                    let v = if out[0][p].is_nan() {
                        cell_field_values(&q)
                    } else {
                        let mut v: [f64; 7] = std::array::from_fn(|k| out[k][p]);
                        if v[5].is_nan() {
                            v[5] = super::rows::reference_scaled_jacobian(&q);
                        }
                        v
                    };
                    for (dst, x) in f.arrays_mut().into_iter().zip(v) {
                        dst.push(x);
                    }
                }
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layouts::SplitMix64;

    /// The `(wide, wider)` builds of [`fields_with`] this CPU runs: the portable one, then
    /// AVX2 and AVX-512 where it has them.
    fn lane_widths() -> Vec<(bool, bool)> {
        let (wide, wider) = (super::super::kernel::wide(), super::super::kernel::wider());
        let mut widths = vec![(false, false)];
        if wide {
            widths.push((true, false));
        }
        if wider {
            widths.push((true, true));
        }
        widths
    }

    /// Every lane width gives the reference's figures bit for bit (NaN for NaN), on smooth
    /// grids (where every cell must take the fast path), on grids with folded, flat,
    /// repeated, tiny, huge and non-finite nodes, and on band sizes with padding.
    #[test]
    fn every_lane_width_gives_the_reference_figures() {
        let mut r = SplitMix64(11);
        let mut u = || r.next_f64();
        let same = |a: &CellFields, b: &CellFields| {
            let bits = |f: &CellFields| -> Vec<Vec<u64>> {
                let mut g = f.clone();
                g.arrays_mut()
                    .iter()
                    .map(|v| {
                        v.iter()
                            .map(|x| if x.is_nan() { 1 } else { x.to_bits() })
                            .collect()
                    })
                    .collect()
            };
            bits(a) == bits(b)
        };
        for (ni, nj) in [
            (1usize, 1usize),
            (2, 3),
            (3, 1),
            (5, 2),
            (16, 16),
            (17, 40),
            (40, 3),
        ] {
            for round in 0..60 {
                let scale = [1.0, 1e-150, 1e150, 1e-3][round % 4];
                let rough = round % 3 != 0;
                let nodes: Vec<Point> = (0..(nj + 1) * (ni + 1))
                    .map(|k| {
                        let (i, j) = ((k % (ni + 1)) as f64, (k / (ni + 1)) as f64);
                        // A sheared, curved grid, or scattered points with degenerate ones.
                        let smooth = [i + 0.3 * j + 0.01 * (j * i).sin(), j + 0.02 * i * i];
                        let p = if !rough {
                            smooth
                        } else {
                            match (u() * 14.0) as u32 {
                                0 => [0.0, 0.0],
                                1 => [f64::NAN, 1.0],
                                2 => [f64::INFINITY, 0.5],
                                3 | 4 => [2.0 * u() - 1.0, 2.0 * u() - 1.0],
                                _ => smooth,
                            }
                        };
                        [scale * p[0], scale * p[1]]
                    })
                    .collect();
                let grid = BlockGrid { ni, nj, nodes };
                let want = super::super::cell_fields_reference(&grid);
                for (a, b) in lane_widths() {
                    let mut got = CellFields::default();
                    fields_with(&grid, &mut got, a, b);
                    assert!(
                        same(&got, &want),
                        "{ni} x {nj}, round {round}, lanes {a} {b}"
                    );
                    if !rough && scale == 1.0 {
                        // Every cell of a smooth grid took the fast path.
                        SCRATCH.with(|s| {
                            let s = s.borrow();
                            let w = ni + 1;
                            let last = (nj - 1) % (BAND_NODES / w).max(1);
                            for r in 0..=last {
                                for i in 0..ni {
                                    assert!(!s.out[0][r * w + i].is_nan(), "cell {i} of row {r}");
                                }
                            }
                        });
                    }
                }
            }
        }
    }

    /// Annular sectors (isosceles trapezoids, whose scaled-Jacobian pick is often undecided:
    /// loop 2 then takes that figure alone by the reference expression): every lane width
    /// gives the reference's figures bit for bit.
    #[test]
    fn annular_sectors_give_the_reference_figures() {
        for (r0, r1, ni, nj) in [
            (1.0, 1.0001, 300, 4),
            (1.0, 2.0, 40, 40),
            (0.5, 0.75, 16, 16),
        ] {
            let nodes: Vec<Point> = (0..=nj)
                .flat_map(|j| {
                    (0..=ni).map(move |i| {
                        let rad = r0 + (r1 - r0) * j as f64 / nj as f64;
                        let t = 0.3 + 1.1 * i as f64 / ni as f64;
                        [2.0 + rad * t.cos(), -1.0 + rad * t.sin()]
                    })
                })
                .collect();
            let grid = BlockGrid { ni, nj, nodes };
            let want = super::super::cell_fields_reference(&grid);
            let bits = |f: &CellFields| -> Vec<Vec<u64>> {
                let mut g = f.clone();
                g.arrays_mut()
                    .iter()
                    .map(|v| v.iter().map(|x| x.to_bits()).collect())
                    .collect()
            };
            for (a, b) in lane_widths() {
                let mut got = CellFields::default();
                fields_with(&grid, &mut got, a, b);
                assert_eq!(bits(&got), bits(&want), "{ni} x {nj}, lanes {a} {b}");
            }
        }
    }
}
