//! Optional elliptic (Winslow) smoothing of a block's interior.
//!
//! Fixed nodes: the block's four sides (so shared sides stay bitwise identical and the mesh
//! stays conforming) and the rows `j <= fixed_rows` off the wall, at least the first layer
//! `j = 1` (so the first grid line off the wall keeps its direction, exactly normal in exact
//! mode, and the first cell height keeps its value). Exact mode also freezes the clustered
//! boundary layer ([`boundary_layer_rows`]), which Winslow would otherwise even out. The other nodes move by damped Jacobi sweeps of the Winslow equations
//! `alpha x_ss - 2 beta x_st + gamma x_tt = 0` (`alpha = |x_t|^2`, `beta = x_s . x_t`,
//! `gamma = |x_s|^2`, centred differences in the logical coordinates `s = i`, `t = j`).
//!
//! Guarantee: a sweep is accepted only when the block's smallest scaled Jacobian
//! ([`super::metrics::min_scaled_jacobian`]) does not decrease; otherwise the step is halved
//! (up to four times) and smoothing of the block stops if none is accepted. Since that minimum
//! starts positive on a valid block, no accepted step makes a Jacobian non-positive, and the
//! mesh's minimum scaled Jacobian never decreases. Winslow without control functions pulls
//! nodes towards equal spacing, hence the frozen boundary layer.

use super::metrics::min_scaled_jacobian;
use crate::geometry::Point;
use crate::mesh::BlockGrid;

/// The rows of the clustered boundary layer of a spoke-aligned block: the largest `j` such
/// that, on some column, the cells `1..=j` are all thinner than that column's spoke length over
/// `nj` (equal spacing). At least 1 (the first layer), at most `nj - 1`.
pub fn boundary_layer_rows(g: &BlockGrid) -> usize {
    if g.nj < 2 || g.nodes.len() != (g.ni + 1) * (g.nj + 1) {
        return 1;
    }
    let d = |a: Point, b: Point| (a[0] - b[0]).hypot(a[1] - b[1]);
    let mut rows = 1;
    for i in 0..=g.ni {
        let uniform = d(g.node(i, 0), g.node(i, g.nj)) / g.nj as f64;
        let mut j = 0;
        while j < g.nj && d(g.node(i, j), g.node(i, j + 1)) < 0.999 * uniform {
            j += 1;
        }
        rows = rows.max(j);
    }
    rows.min(g.nj - 1)
}

/// One damped Jacobi sweep with relaxation `omega` of the rows `fixed_rows + 1 .. nj`;
/// returns the new nodes.
fn sweep(g: &BlockGrid, omega: f64, fixed_rows: usize) -> Vec<Point> {
    let mut out = g.nodes.clone();
    let w = g.ni + 1;
    for j in (fixed_rows.max(1) + 1)..g.nj {
        for i in 1..g.ni {
            let p = |a: usize, b: usize| g.nodes[a + b * w];
            let (e, wv, n, s) = (p(i + 1, j), p(i - 1, j), p(i, j + 1), p(i, j - 1));
            let (ne, nw, se, sw) = (
                p(i + 1, j + 1),
                p(i - 1, j + 1),
                p(i + 1, j - 1),
                p(i - 1, j - 1),
            );
            let xs = [0.5 * (e[0] - wv[0]), 0.5 * (e[1] - wv[1])];
            let xt = [0.5 * (n[0] - s[0]), 0.5 * (n[1] - s[1])];
            let alpha = xt[0] * xt[0] + xt[1] * xt[1];
            let beta = xs[0] * xt[0] + xs[1] * xt[1];
            let gamma = xs[0] * xs[0] + xs[1] * xs[1];
            let den = 2.0 * (alpha + gamma);
            if !(den > 0.0 && den.is_finite()) {
                continue;
            }
            let old = p(i, j);
            let mut q = [0.0; 2];
            for d in 0..2 {
                let x = (alpha * (e[d] + wv[d]) + gamma * (n[d] + s[d])
                    - 0.5 * beta * (ne[d] - se[d] - nw[d] + sw[d]))
                    / den;
                q[d] = old[d] + omega * (x - old[d]);
            }
            if q[0].is_finite() && q[1].is_finite() {
                out[i + j * w] = q;
            }
        }
    }
    out
}

/// Smooth `g` in place with at most `iterations` accepted sweeps, the rows `j <= fixed_rows`
/// (at least 1) kept (see the module docs). Returns the number of accepted sweeps. Never
/// panics; malformed grids are left alone.
pub fn winslow(g: &mut BlockGrid, iterations: usize, fixed_rows: usize) -> usize {
    if g.ni < 2 || g.nj < 3 || g.nodes.len() != (g.ni + 1) * (g.nj + 1) {
        return 0;
    }
    let mut current = min_scaled_jacobian(g);
    if current.is_nan() || current <= 0.0 {
        return 0;
    }
    let mut accepted = 0;
    for _ in 0..iterations {
        let mut omega = 1.0;
        let mut ok = false;
        for _ in 0..5 {
            let nodes = sweep(g, omega, fixed_rows);
            let trial = BlockGrid {
                ni: g.ni,
                nj: g.nj,
                nodes,
            };
            let m = min_scaled_jacobian(&trial);
            if m >= current {
                *g = trial;
                current = m;
                ok = true;
                break;
            }
            omega *= 0.5;
        }
        if !ok {
            break;
        }
        accepted += 1;
    }
    accepted
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perturbed_grid_improves_and_keeps_fixed_nodes() {
        // A 6 x 6 unit grid with one interior node pushed off.
        let n = 6;
        let mut nodes = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                nodes.push([i as f64, j as f64]);
            }
        }
        nodes[3 + 3 * (n + 1)] = [3.3, 3.2];
        let mut g = BlockGrid {
            ni: n,
            nj: n,
            nodes,
        };
        let before = g.clone();
        let m0 = min_scaled_jacobian(&g);
        let done = winslow(&mut g, 50, 1);
        assert!(done > 0);
        assert!(min_scaled_jacobian(&g) >= m0);
        let p = g.node(3, 3);
        assert!(
            (p[0] - 3.0).abs() < 0.1 && (p[1] - 3.0).abs() < 0.1,
            "{p:?}"
        );
        for i in 0..=n {
            for j in [0, 1, n] {
                assert_eq!(g.node(i, j), before.node(i, j));
            }
        }
    }

    #[test]
    fn inverted_grids_are_left_alone() {
        let mut g = BlockGrid {
            ni: 2,
            nj: 3,
            nodes: vec![[0.0, 0.0]; 12],
        };
        assert_eq!(winslow(&mut g, 5, 1), 0);
    }
}

#[cfg(test)]
mod layer_tests {
    use super::*;

    #[test]
    fn boundary_layer_rows_counts_the_thin_cells() {
        // One column (ni = 1) of 5 cells: heights 0.01, 0.02, 0.04, then 0.465 twice.
        let ys = [0.0, 0.01, 0.03, 0.07, 0.535, 1.0];
        let mut nodes = Vec::new();
        for y in ys {
            nodes.push([0.0, y]);
            nodes.push([1.0, y]);
        }
        let g = BlockGrid {
            ni: 1,
            nj: 5,
            nodes,
        };
        assert_eq!(boundary_layer_rows(&g), 3);
    }
}
