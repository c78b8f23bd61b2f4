//! Node counts of exact mode as one small integer problem.
//!
//! Unknowns: a wall-normal count `n_c >= 1` per circle (every block on circle `c` has `n_c`
//! cells along its spokes: the spokes at a medial vertex are shared by the two blocks on the
//! same circle, so all blocks around one circle share it) and a count `n_e >= 1` per medial arc
//! (the arc, and the two walls opposite it, are shared by the arc's two blocks). With the
//! conformity classes of the blocking these are all the classes, so every shared side matches
//! by construction once each class has one integer.
//!
//! Targets: `tau_c` per circle (from the target cell size and the clustering, see
//! [`super::clustering::cells_for`]) and, for arc `e` between circles `a, b` with the mean
//! wall-normal count `nbar = (n_a + n_b) / 2`, `t_e = sum_k max(nbar sq_k, ang_k)`: `sq_k` is the
//! sub-step's length along the spoke mid-curves divided by the spoke length (cells of
//! `nbar` rows with `t_e` columns are then square on average), `ang_k` the sub-step's largest
//! wall angle over 15 degrees (at most 15 degrees of wall per cell).
//!
//! Objective: `sum_c (n_c - tau_c)^2 / tau_c + sum_e (n_e - t_e)^2 / t_e`, subject to
//! `n_e >= ceil(sum_k ang_k)` and, for every circle `c` marked as an *inserted-hole template*
//! (an O-grid filled into a hole, whose four sides need `2a + 2b` wall cells), an even total
//! `sum_{e on c} n_e >= 4`.
//!
//! Solution: the `n_c` terms are independent of the arcs, so each `n_c` is its rounded target
//! (exactly optimal), raised to the least counts with no two circles that face each other
//! across a medial arc more than [`MAX_COUNT_RATIO`] apart (their facing cells differ by that
//! ratio; a count the user fixed is not raised); for fixed `n_c` the arc terms separate, so
//! each `n_e` is its rounded target clamped to its bound (exactly optimal without parity). Parity is then repaired as a
//! minimum-cost T-join, greedily: each odd template circle is joined by a cheapest path
//! (Dijkstra over circles, an arc costing the least increase of its term for a `+-1` change)
//! to another odd template circle or to any non-template circle (which absorbs parity), and
//! every arc on the path changes by one. Deterministic; not guaranteed globally optimal when
//! several paths interact, always feasible when every component has a non-template circle or
//! an even number of odd template circles.

/// One medial arc's data for the count problem (`Default`: no circles, no densities, nothing
/// known).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ArcTarget {
    /// The two circles' indices into the circle arrays.
    pub circles: [usize; 2],
    /// Per sub-step: length along the spoke mid-curves over the spoke length.
    pub sq: Vec<f64>,
    /// Per sub-step: the largest wall angle swept, over the 15-degree limit.
    pub ang: Vec<f64>,
    /// When `Some`, what an earlier computation of these same densities gave (exact mode
    /// reuses it across the rebuilds of one layout, [`super::piece_cache`]); `sq` and `ang`
    /// are then usually not held (empty).
    pub known: Option<Known>,
}

/// Results of [`ArcTarget::min_cells`] and of [`ArcTarget::target`] for one `nbar`, computed
/// from an arc's densities and kept instead of them (bitwise the values they give).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Known {
    pub min_cells: usize,
    /// `(nbar, target(nbar))`, if known.
    pub target: Option<(f64, f64)>,
    /// `(nbar, n, widths)`: the end-cell widths `[end][side]` of the natural node
    /// parameters for that `nbar` and `n` cells (`super::grading::end_widths`), if known.
    pub ends: Option<(f64, usize, [[f64; 2]; 2])>,
}

/// The weight of one sub-step of an arc (see the module docs): `max(nbar sq_k, ang_k)`, the
/// larger of the spoke-length density scaled to the mean wall-normal count `nbar` and the
/// wall-angle density. An arc's target count is the sum of its weights, and its nodes
/// equidistribute them (`super::equidistribution`); every caller forms them here, so the
/// counts and the nodes see the same values bit for bit.
#[inline]
pub(crate) fn weight(nbar: f64, sq: f64, ang: f64) -> f64 {
    (nbar * sq).max(ang)
}

impl ArcTarget {
    /// The target for `nbar` when it is known without the densities (see [`ArcTarget::known`]);
    /// `None` when the densities are needed but not held.
    pub fn known_target(&self, nbar: f64) -> Option<f64> {
        match self.known {
            Some(Known {
                target: Some((nb, t)),
                ..
            }) if nb.to_bits() == nbar.to_bits() => Some(t),
            _ if self.holds_densities() => Some(self.target(nbar)),
            _ => None,
        }
    }

    /// The natural end-cell widths for `nbar` and `n` cells when [`ArcTarget::known`] holds
    /// them.
    pub fn known_ends(&self, nbar: f64, n: usize) -> Option<[[f64; 2]; 2]> {
        match self.known {
            Some(Known {
                ends: Some((nb, m, w)),
                ..
            }) if nb.to_bits() == nbar.to_bits() && m == n => Some(w),
            _ => None,
        }
    }

    /// True when `sq` and `ang` are held (as many as the sub-steps, at least one).
    pub fn holds_densities(&self) -> bool {
        !self.sq.is_empty() && self.sq.len() == self.ang.len()
    }

    /// The real target `t_e` for a mean wall-normal count `nbar`: from [`ArcTarget::known`]
    /// for the `nbar` it holds, else from the densities (which must then be held).
    pub fn target(&self, nbar: f64) -> f64 {
        if let Some(Known {
            target: Some((nb, t)),
            ..
        }) = self.known
        {
            if nb.to_bits() == nbar.to_bits() {
                return t;
            }
        }
        self.sq
            .iter()
            .zip(&self.ang)
            .map(|(&s, &a)| weight(nbar, s, a))
            .sum()
    }
    /// The lower bound `ceil(sum ang)` (at least 1), or the known one.
    pub fn min_cells(&self) -> usize {
        if let Some(k) = self.known {
            return k.min_cells;
        }
        let s: f64 = self.ang.iter().sum();
        if s.is_finite() {
            ((s - 1e-9).ceil().max(1.0) as usize).min(super::super::grid::MAX_CELLS_PER_SIDE)
        } else {
            1
        }
    }
}

/// The integer problem (see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CountProblem {
    /// Per circle: the real target `tau_c`.
    pub circle_target: Vec<f64>,
    /// Per circle: a count fixed by the user, if any.
    pub circle_fixed: Vec<Option<usize>>,
    /// Per circle: true for an inserted-hole template (even perimeter count).
    pub template: Vec<bool>,
    pub arcs: Vec<ArcTarget>,
    /// Pairs of circles that face each other across a medial arc: their counts are kept
    /// within [`MAX_COUNT_RATIO`] of each other ([`CountProblem::circle_counts`]). Empty: no
    /// such constraint.
    pub neighbours: Vec<[usize; 2]>,
}

/// The largest ratio between the wall-normal counts of two circles that face each other
/// across a medial arc (`3 / 2`, the top of the report's acceptable interface growth).
///
/// Both spokes of a medial node have the same length (the node is equidistant from the two
/// circles) and are equally spaced without a first height, so the cells that face each other
/// across a medial arc differ in height by the ratio of the two counts: up to 3.2 at 1e3
/// bubbles before this bound (13 262 of 111 851 faces over 1.5).
pub const MAX_COUNT_RATIO: (usize, usize) = (3, 2);

/// The solution: one count per circle and per arc.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Counts {
    pub circle: Vec<usize>,
    pub arc: Vec<usize>,
}

/// [`CountProblem::neighbours`] from the circle pairs of the medial arcs: the pairs of two
/// distinct circles that are both equally spaced along their spokes (no first height), each
/// pair once, smaller index first, sorted.
pub fn facing_pairs(
    pairs: impl Iterator<Item = [usize; 2]>,
    equally_spaced: impl Fn(usize) -> bool,
) -> Vec<[usize; 2]> {
    let mut out: Vec<[usize; 2]> = pairs
        .filter(|&[a, b]| a != b && equally_spaced(a) && equally_spaced(b))
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    // On the pool (issue 8: 300 000 pairs at 1e5 particles); equal pairs are alike, so the
    // sorted list is the one a serial sort gives.
    rayon::slice::ParallelSliceMut::par_sort_unstable(&mut out[..]);
    out.dedup();
    out
}

fn round_count(x: f64) -> usize {
    if x.is_finite() && x > 1.0 {
        (x.round() as usize).min(super::super::grid::MAX_CELLS_PER_SIDE)
    } else {
        1
    }
}

/// An arc's count before the parity repair: its rounded target `t` raised to its lower bound
/// `lb` ([`CountProblem::solve`]).
pub fn arc_count(t: f64, lb: usize) -> usize {
    round_count(t).max(lb)
}

/// An arc's count with a fixed grid of `n` per block before the parity repair
/// ([`CountProblem::solve_uniform`]).
pub fn uniform_arc_count(n: usize, lb: usize) -> usize {
    n.clamp(1, super::super::grid::MAX_CELLS_PER_SIDE).max(lb)
}

fn term(n: usize, t: f64) -> f64 {
    let t = t.max(1e-9);
    (n as f64 - t).powi(2) / t
}

impl CountProblem {
    /// The circle counts [`CountProblem::solve`] gives: they depend on the circles only. Each
    /// is its rounded target, then raised (the least raise, by repeated passes over
    /// [`CountProblem::neighbours`] until none changes) until no count is more than
    /// [`MAX_COUNT_RATIO`] times a neighbour's; a count fixed by the user is never raised.
    pub fn circle_counts(&self) -> Vec<usize> {
        let mut n: Vec<usize> = (0..self.circle_target.len())
            .map(|c| {
                self.circle_fixed
                    .get(c)
                    .copied()
                    .flatten()
                    .map(|n| n.clamp(1, super::super::grid::MAX_CELLS_PER_SIDE))
                    .unwrap_or_else(|| round_count(self.circle_target[c]))
            })
            .collect();
        let fixed = |c: usize| self.circle_fixed.get(c).copied().flatten().is_some();
        let (num, den) = MAX_COUNT_RATIO;
        // Values only rise, each to at most the largest count: the passes end.
        loop {
            let mut changed = false;
            for &[a, b] in &self.neighbours {
                for (x, y) in [(a, b), (b, a)] {
                    if x >= n.len() || y >= n.len() || fixed(x) {
                        continue;
                    }
                    // ceil(n_y den / num): then n_y / n_x <= num / den.
                    let need = (n[y] * den).div_ceil(num);
                    if n[x] < need {
                        n[x] = need;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        n
    }

    /// Solve (see the module docs). `Err` when a template circle's parity cannot be repaired
    /// or an arc's target for its `nbar` is neither known nor computable (densities not held).
    pub fn solve(&self) -> Result<Counts, String> {
        let nc = self.circle_target.len();
        let circle = self.circle_counts();
        let mut targets = Vec::with_capacity(self.arcs.len());
        let mut lower = Vec::with_capacity(self.arcs.len());
        let mut arc = Vec::with_capacity(self.arcs.len());
        for a in &self.arcs {
            if a.circles.iter().any(|&c| c >= nc) {
                return Err("arc refers to an unknown circle".into());
            }
            let nbar = 0.5 * (circle[a.circles[0]] + circle[a.circles[1]]) as f64;
            let t = a
                .known_target(nbar)
                .ok_or("an arc's densities are needed but not held")?;
            let lb = a.min_cells();
            targets.push(t);
            lower.push(lb);
            arc.push(arc_count(t, lb));
        }
        self.repair_parity(&mut arc, &targets, &lower)?;
        Ok(Counts { circle, arc })
    }

    /// A fixed grid per block (`--block-cells n`, [`crate::mesher::Options::block_cells`]):
    /// every circle's count is `n` and every arc's count is `n` raised to its lower bound
    /// [`ArcTarget::min_cells`] (at most 15 degrees of wall per cell); the targets are not
    /// used. Template parity is repaired as in [`CountProblem::solve`]. Fixed circle counts
    /// are ignored (the caller refuses them with `block_cells`).
    pub fn solve_uniform(&self, n: usize) -> Result<Counts, String> {
        let n = n.clamp(1, super::super::grid::MAX_CELLS_PER_SIDE);
        let nc = self.circle_target.len();
        let mut arc = Vec::with_capacity(self.arcs.len());
        let mut lower = Vec::with_capacity(self.arcs.len());
        for a in &self.arcs {
            if a.circles.iter().any(|&c| c >= nc) {
                return Err("arc refers to an unknown circle".into());
            }
            let lb = a.min_cells();
            lower.push(lb);
            arc.push(uniform_arc_count(n, lb));
        }
        let targets: Vec<f64> = arc.iter().map(|&k| k as f64).collect();
        self.repair_parity(&mut arc, &targets, &lower)?;
        Ok(Counts {
            circle: vec![n; nc],
            arc,
        })
    }

    fn is_template(&self, c: usize) -> bool {
        self.template.get(c).copied().unwrap_or(false)
    }

    fn repair_parity(
        &self,
        arc: &mut [usize],
        targets: &[f64],
        lower: &[usize],
    ) -> Result<(), String> {
        let nc = self.circle_target.len();
        if !(0..nc).any(|c| self.is_template(c)) {
            return Ok(());
        }
        // Adjacency: circle -> arcs.
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nc];
        for (e, a) in self.arcs.iter().enumerate() {
            adj[a.circles[0]].push(e);
            adj[a.circles[1]].push(e);
        }
        let perimeter = |arc: &[usize], c: usize| adj[c].iter().map(|&e| arc[e]).sum::<usize>();
        // Best +-1 change of an arc: (cost, delta).
        let change = |arc: &[usize], e: usize| -> (f64, i64) {
            let n = arc[e];
            let base = term(n, targets[e]);
            let up = term(n + 1, targets[e]) - base;
            let down = if n > lower[e].max(1) {
                term(n - 1, targets[e]) - base
            } else {
                f64::INFINITY
            };
            if down < up {
                (down, -1)
            } else {
                (up, 1)
            }
        };
        for _round in 0..=nc {
            let odd: Vec<usize> = (0..nc)
                .filter(|&c| self.is_template(c) && perimeter(arc, c) % 2 == 1)
                .collect();
            let Some(&start) = odd.first() else {
                break;
            };
            // Dijkstra from `start` (deterministic: ties by index).
            let mut dist = vec![f64::INFINITY; nc];
            let mut prev: Vec<Option<(usize, usize)>> = vec![None; nc];
            let mut done = vec![false; nc];
            dist[start] = 0.0;
            let mut goal = None;
            loop {
                let mut u = None;
                for c in 0..nc {
                    if !done[c] && dist[c].is_finite() && u.is_none_or(|x: usize| dist[c] < dist[x])
                    {
                        u = Some(c);
                    }
                }
                let Some(u) = u else { break };
                done[u] = true;
                if u != start && (!self.is_template(u) || odd.contains(&u)) {
                    goal = Some(u);
                    break;
                }
                for &e in &adj[u] {
                    let a = &self.arcs[e];
                    let v = if a.circles[0] == u {
                        a.circles[1]
                    } else {
                        a.circles[0]
                    };
                    let w = dist[u] + change(arc, e).0.max(0.0) + 1e-12;
                    if w < dist[v] {
                        dist[v] = w;
                        prev[v] = Some((u, e));
                    }
                }
            }
            let Some(mut v) = goal else {
                return Err(format!(
                    "cannot make the wall count of template circle {start} even"
                ));
            };
            while let Some((u, e)) = prev[v] {
                let (_, d) = change(arc, e);
                arc[e] = (arc[e] as i64 + d) as usize;
                v = u;
            }
        }
        // Small templates: at least 4 wall cells (2a + 2b with a, b >= 1).
        for (c, arcs_of_c) in adj.iter().enumerate() {
            if self.is_template(c) {
                while perimeter(arc, c) < 4 {
                    // Two cells more on its first arc keeps parity.
                    match arcs_of_c.first() {
                        Some(&e) => arc[e] += 2,
                        None => return Err(format!("template circle {c} has no arc")),
                    }
                }
                if perimeter(arc, c) % 2 == 1 {
                    return Err(format!("template circle {c} keeps an odd wall count"));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(a: usize, b: usize, t: f64) -> ArcTarget {
        ArcTarget {
            circles: [a, b],
            sq: vec![t],
            ang: vec![0.0],
            known: None,
        }
    }

    #[test]
    fn rounding_without_templates() {
        let p = CountProblem {
            circle_target: vec![4.4, 7.6],
            circle_fixed: vec![None, Some(3)],
            template: vec![false, false],
            arcs: vec![arc(0, 1, 1.0), arc(0, 1, 2.3)],
            neighbours: vec![],
        };
        let c = p.solve().unwrap();
        assert_eq!(c.circle, vec![4, 3]);
        // nbar = 3.5: targets 3.5 and 8.05.
        assert_eq!(c.arc, vec![4, 8]);
    }

    #[test]
    fn uniform_counts_are_n_raised_only_by_the_wall_angle() {
        let mut wide = arc(0, 1, 1.0);
        wide.ang = vec![3.2, 3.0]; // 6.2 x 15 degrees: at least 7 cells
        let p = CountProblem {
            circle_target: vec![4.4, 7.6, 2.0],
            circle_fixed: vec![None, Some(3), None],
            template: vec![false; 3],
            arcs: vec![arc(0, 1, 9.0), wide, arc(1, 2, 0.1)],
            neighbours: vec![[0, 1], [1, 2]],
        };
        assert_eq!(
            p.solve_uniform(5).unwrap(),
            Counts {
                circle: vec![5, 5, 5],
                arc: vec![5, 7, 5]
            }
        );
        assert_eq!(p.solve_uniform(0).unwrap().circle, vec![1, 1, 1]);
    }

    #[test]
    fn template_perimeters_become_even() {
        // Circle 1 is a template touched by three arcs; circle 0 and 2 are free.
        let p = CountProblem {
            circle_target: vec![4.0, 4.0, 4.0],
            circle_fixed: vec![None; 3],
            template: vec![false, true, false],
            arcs: vec![
                arc(0, 1, 1.0),
                arc(1, 2, 1.3),
                arc(0, 1, 0.9),
                arc(0, 2, 1.0),
            ],
            neighbours: vec![],
        };
        let c = p.solve().unwrap();
        let per: usize = [0, 1, 2].iter().map(|&e| c.arc[e]).sum();
        assert_eq!(per % 2, 0, "{c:?}");
        assert!(per >= 4);
    }

    #[test]
    fn known_summaries_give_the_counts_of_the_densities() {
        let full = |a: usize, b: usize, k: u64| {
            let x = |i: u64| ((i * 7919 + k * 104_729) % 1000) as f64 / 700.0;
            ArcTarget {
                circles: [a, b],
                sq: (0..32).map(|i| x(i) * 0.05).collect(),
                ang: (0..32).map(|i| x(i + 13) * 0.08).collect(),
                known: None,
            }
        };
        let arcs: Vec<ArcTarget> = (0..6).map(|k| full(k % 3, (k + 1) % 3, k as u64)).collect();
        let p = CountProblem {
            circle_target: vec![4.4, 7.6, 2.0],
            circle_fixed: vec![None; 3],
            template: vec![false, true, false],
            arcs,
            neighbours: vec![[0, 1], [1, 2]],
        };
        let circle = p.circle_counts();
        let mut q = p.clone();
        for a in &mut q.arcs {
            let nbar = 0.5 * (circle[a.circles[0]] + circle[a.circles[1]]) as f64;
            a.known = Some(Known {
                min_cells: a.min_cells(),
                target: Some((nbar, a.target(nbar))),
                ends: None,
            });
            a.sq.clear();
            a.ang.clear();
        }
        assert_eq!(p.solve(), q.solve());
        assert_eq!(p.solve_uniform(5), q.solve_uniform(5));
        // A target for another `nbar` is not known: refused, not guessed.
        q.circle_target[0] = 9.0;
        assert!(q.solve().is_err());
    }

    /// The neighbour bound gives the least counts at or above the rounded targets with no
    /// count more than 3/2 of a neighbour's (fixed counts aside): every count is at least its
    /// rounded target, every pair is within the ratio unless the smaller is fixed, and every
    /// raised count is tight (lowering it by one breaks the bound with some neighbour), which
    /// characterises the least such vector. Checked on random graphs.
    #[test]
    fn neighbour_counts_are_the_least_within_the_ratio() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |m: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % m
        };
        let (num, den) = MAX_COUNT_RATIO;
        for _ in 0..200 {
            let nc = 2 + next(30) as usize;
            let circle_target: Vec<f64> = (0..nc).map(|_| 1.0 + next(400) as f64 / 7.0).collect();
            let circle_fixed: Vec<Option<usize>> = (0..nc)
                .map(|_| (next(8) == 0).then(|| 1 + next(60) as usize))
                .collect();
            let neighbours: Vec<[usize; 2]> = (0..2 * nc)
                .map(|_| [next(nc as u64) as usize, next(nc as u64) as usize])
                .collect();
            let p = CountProblem {
                circle_target,
                circle_fixed,
                template: vec![false; nc],
                arcs: vec![],
                neighbours,
            };
            let base = CountProblem {
                neighbours: vec![],
                ..p.clone()
            }
            .circle_counts();
            let n = p.circle_counts();
            let fixed = |c: usize| p.circle_fixed[c].is_some();
            for c in 0..nc {
                assert!(n[c] >= base[c]);
                if fixed(c) {
                    assert_eq!(n[c], base[c]);
                }
            }
            for &[a, b] in &p.neighbours {
                for (x, y) in [(a, b), (b, a)] {
                    assert!(fixed(x) || n[y] * den <= n[x] * num, "{n:?} {x} {y}");
                }
            }
            for c in (0..nc).filter(|&c| n[c] > base[c]) {
                let tight = p.neighbours.iter().any(|&[a, b]| {
                    (a == c && (n[b] * den).div_ceil(num) == n[c])
                        || (b == c && (n[a] * den).div_ceil(num) == n[c])
                });
                assert!(tight, "circle {c} raised to {} with no reason: {n:?}", n[c]);
            }
        }
    }
}
