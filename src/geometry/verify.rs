//! An independent exact checker for [`Triangulation`] results.
//!
//! It shares no arithmetic with the engine: every coordinate becomes an exact `rug::Rational`,
//! all of them are brought to integers with one common power-of-two denominator, and every test
//! is a plain integer determinant. It does not trust the triangulation's neighbour lists, hull or
//! duplicate report either: each is recomputed (duplicates by sorting, the hull by Andrew's
//! monotone chain) and compared.

use super::{Point, Triangulation, TriangulationError};
use rug::{Integer, Rational};
use std::cmp::Ordering;
use std::collections::{HashMap, HashSet};

/// All points as integers scaled by one common power of two (the sign of every homogeneous
/// predicate is unchanged by that scaling).
struct Exact {
    xy: Vec<[Integer; 2]>,
}

impl Exact {
    fn new(points: &[Point]) -> Result<Self, String> {
        let mut rats = Vec::with_capacity(points.len());
        let mut max_den_bits = 0u32;
        for (i, p) in points.iter().enumerate() {
            let r = [Rational::from_f64(p[0]), Rational::from_f64(p[1])];
            let [Some(x), Some(y)] = r else {
                return Err(format!("point {i} is not finite"));
            };
            for v in [&x, &y] {
                // Denominators of dyadic rationals are powers of two.
                max_den_bits = max_den_bits.max(v.denom().significant_bits() - 1);
            }
            rats.push([x, y]);
        }
        let xy = rats
            .into_iter()
            .map(|r| {
                r.map(|v| {
                    let shift = max_den_bits - (v.denom().significant_bits() - 1);
                    Integer::from(v.numer() << shift)
                })
            })
            .collect();
        Ok(Exact { xy })
    }

    fn orient(&self, a: u32, b: u32, c: u32) -> Ordering {
        let [ax, ay] = &self.xy[a as usize];
        let [bx, by] = &self.xy[b as usize];
        let [cx, cy] = &self.xy[c as usize];
        let l = Integer::from(bx - ax) * Integer::from(cy - ay);
        let r = Integer::from(by - ay) * Integer::from(cx - ax);
        l.cmp(&r)
    }

    /// `det[x y x²+y² 1]` over rows a, b, c, d (positive: d inside circle abc, abc CCW).
    fn incircle(&self, a: u32, b: u32, c: u32, d: u32) -> Ordering {
        let [dx, dy] = &self.xy[d as usize];
        let rel = |p: u32| {
            let [x, y] = &self.xy[p as usize];
            let (x, y) = (Integer::from(x - dx), Integer::from(y - dy));
            let lift = Integer::from(&x * &x) + Integer::from(&y * &y);
            (x, y, lift)
        };
        let (ax, ay, al) = rel(a);
        let (bx, by, bl) = rel(b);
        let (cx, cy, cl) = rel(c);
        let m1 = Integer::from(&bx * &cy) - Integer::from(&cx * &by);
        let m2 = Integer::from(&cx * &ay) - Integer::from(&ax * &cy);
        let m3 = Integer::from(&ax * &by) - Integer::from(&bx * &ay);
        let det = al * m1 + bl * m2 + cl * m3;
        det.cmp0()
    }

    /// Twice the signed area of triangle a, b, c.
    fn area2(&self, a: u32, b: u32, c: u32) -> Integer {
        let [ax, ay] = &self.xy[a as usize];
        let [bx, by] = &self.xy[b as usize];
        let [cx, cy] = &self.xy[c as usize];
        Integer::from(bx - ax) * Integer::from(cy - ay)
            - Integer::from(by - ay) * Integer::from(cx - ax)
    }

    fn lex(&self, a: u32, b: u32) -> Ordering {
        let (p, q) = (&self.xy[a as usize], &self.xy[b as usize]);
        p[0].cmp(&q[0]).then(p[1].cmp(&q[1]))
    }
}

/// Distinct representatives (smallest index of each exact-duplicate group) in lexicographic
/// order, and the expected `(first, duplicate)` pairs, sorted.
fn dedup(ex: &Exact) -> (Vec<u32>, Vec<(u32, u32)>) {
    let mut idx: Vec<u32> = (0..ex.xy.len() as u32).collect();
    idx.sort_by(|&a, &b| ex.lex(a, b).then(a.cmp(&b)));
    let mut reps = Vec::new();
    let mut dups = Vec::new();
    for &i in &idx {
        match reps.last() {
            Some(&r) if ex.lex(r, i) == Ordering::Equal => dups.push((r, i)),
            _ => reps.push(i),
        }
    }
    dups.sort_unstable();
    (reps, dups)
}

/// Convex hull by Andrew's monotone chain over lexicographically sorted points, counter-
/// clockwise, keeping points that lie on hull edges. Needs at least 3 non-collinear points.
fn hull_with_collinear(ex: &Exact, sorted: &[u32]) -> Vec<u32> {
    let mut lower: Vec<u32> = Vec::new();
    for &p in sorted {
        while lower.len() >= 2
            && ex.orient(lower[lower.len() - 2], lower[lower.len() - 1], p) == Ordering::Less
        {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<u32> = Vec::new();
    for &p in sorted.iter().rev() {
        while upper.len() >= 2
            && ex.orient(upper[upper.len() - 2], upper[upper.len() - 1], p) == Ordering::Less
        {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Check every guarantee of `dt` exactly. Returns the first violation found.
///
/// Checked: indices valid and not duplicates; every triangle counter-clockwise; neighbour
/// relation symmetric with matching reversed edges; every interior edge locally Delaunay;
/// hull edges are exactly the edges of the convex hull (points on hull edges included); the
/// triangle areas add up to the hull area; Euler count `T = 2n - 2 - h`; every distinct point a
/// vertex; the duplicate report; `vertex_triangle`; and the co-circular groups.
pub fn verify_exact(dt: &Triangulation) -> Result<(), String> {
    let ex = Exact::new(dt.points())?;
    let n_in = dt.points().len();
    let (reps, dups) = dedup(&ex);
    if dt.duplicates() != dups.as_slice() {
        return Err(format!(
            "duplicates: reported {} pairs, expected {}",
            dt.duplicates().len(),
            dups.len()
        ));
    }
    let is_rep = {
        let mut v = vec![false; n_in];
        reps.iter().for_each(|&r| v[r as usize] = true);
        v
    };
    let nt = dt.len();
    let mut used = vec![false; n_in];
    let mut directed: HashSet<(u32, u32)> = HashSet::with_capacity(3 * nt);
    let mut hull_edges: HashMap<u32, u32> = HashMap::new();
    let mut area = Integer::new();
    let mut cocircular_pairs = Vec::new();
    for t in 0..nt {
        let v = dt.triangle(t);
        for &x in &v {
            if x as usize >= n_in || !is_rep[x as usize] {
                return Err(format!("triangle {t} uses invalid or duplicate vertex {x}"));
            }
            used[x as usize] = true;
        }
        if ex.orient(v[0], v[1], v[2]) != Ordering::Greater {
            return Err(format!("triangle {t} {v:?} is not counter-clockwise"));
        }
        area += ex.area2(v[0], v[1], v[2]);
        let nb = dt.neighbors(t);
        for k in 0..3 {
            let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            if !directed.insert((a, b)) {
                return Err(format!("directed edge ({a},{b}) appears twice"));
            }
            match nb[k] {
                None => {
                    hull_edges.insert(a, b);
                }
                Some(m) => {
                    let m = m as usize;
                    if m >= nt {
                        return Err(format!("triangle {t} has neighbour {m} out of range"));
                    }
                    let w = dt.triangle(m);
                    let Some(j) = (0..3).find(|&j| w[(j + 1) % 3] == b && w[(j + 2) % 3] == a)
                    else {
                        return Err(format!("triangles {t} and {m} do not share edge ({a},{b})"));
                    };
                    if dt.neighbors(m)[j] != Some(t as u32) {
                        return Err(format!("neighbour relation {t} -> {m} is not symmetric"));
                    }
                    let ic = ex.incircle(v[0], v[1], v[2], w[j]);
                    match ic {
                        Ordering::Greater => {
                            return Err(format!(
                                "edge ({a},{b}) between {t} and {m} is not locally Delaunay"
                            ))
                        }
                        Ordering::Equal if t < m => cocircular_pairs.push((t, m)),
                        _ => {}
                    }
                    let flag = dt.is_cocircular_edge(t, k);
                    if flag != (ic == Ordering::Equal) {
                        return Err(format!("is_cocircular_edge({t},{k}) is wrong"));
                    }
                }
            }
        }
    }
    if let Some(r) = reps.iter().find(|&&r| !used[r as usize]) {
        return Err(format!("distinct point {r} is not a vertex"));
    }
    // Hull: recomputed independently, with points on hull edges.
    let hull = hull_with_collinear(&ex, &reps);
    let h = hull.len();
    if hull_edges.len() != h {
        return Err(format!(
            "{} hull edges, expected {h} (hull points incl. collinear)",
            hull_edges.len()
        ));
    }
    for i in 0..h {
        let (a, b) = (hull[i], hull[(i + 1) % h]);
        if hull_edges.get(&a) != Some(&b) {
            return Err(format!("hull edge ({a},{b}) missing"));
        }
    }
    let mut hull_area = Integer::new();
    for i in 1..h.saturating_sub(1) {
        hull_area += ex.area2(hull[0], hull[i], hull[i + 1]);
    }
    if area != hull_area {
        return Err("triangle areas do not add up to the hull area".into());
    }
    let n = reps.len();
    if nt + 2 + h != 2 * n {
        return Err(format!("Euler: {nt} triangles, expected 2*{n} - 2 - {h}"));
    }
    let mut dt_hull = dt.hull();
    let mut my_hull = hull.clone();
    dt_hull.sort_unstable();
    my_hull.sort_unstable();
    if dt_hull != my_hull {
        return Err("hull() differs from the recomputed hull".into());
    }
    let mut rep_of: Vec<u32> = (0..n_in as u32).collect();
    for &(first, d) in &dups {
        rep_of[d as usize] = first;
    }
    for (v, &rep) in rep_of.iter().enumerate() {
        let ok = dt
            .vertex_triangle(v)
            .is_some_and(|t| t < nt && dt.triangle(t).contains(&rep));
        if !ok {
            return Err(format!("vertex_triangle({v}) does not contain {rep}"));
        }
    }
    // Co-circular groups, recomputed from the zero in-circle edges found above.
    let mut parent: Vec<usize> = (0..nt).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            x = p[x];
        }
        x
    }
    for &(t, m) in &cocircular_pairs {
        let (a, b) = (root(&mut parent, t), root(&mut parent, m));
        parent[a.max(b)] = a.min(b);
    }
    let mut groups: HashMap<usize, (usize, Vec<u32>)> = HashMap::new();
    for t in 0..nt {
        let r = root(&mut parent, t);
        let g = groups.entry(r).or_default();
        g.0 += 1;
        g.1.extend(dt.triangle(t));
    }
    let mut expected: Vec<Vec<u32>> = groups
        .into_values()
        .filter(|(c, _)| *c > 1)
        .map(|(_, mut g)| {
            g.sort_unstable();
            g.dedup();
            g
        })
        .collect();
    expected.sort();
    if dt.cocircular_groups() != expected {
        return Err("co-circular groups differ from the recomputed ones".into());
    }
    Ok(())
}

/// Check that an error returned by [`Triangulation::new`] is justified by the input.
pub fn verify_error(points: &[Point], err: &TriangulationError) -> Result<(), String> {
    let first_bad = points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()));
    match err {
        TriangulationError::NonFinite { index } => {
            if first_bad == Some(*index) {
                Ok(())
            } else {
                Err(format!(
                    "NonFinite {{ {index} }} but first bad is {first_bad:?}"
                ))
            }
        }
        _ if first_bad.is_some() => {
            Err(format!("{err} although point {first_bad:?} is not finite"))
        }
        TriangulationError::TooFewPoints { distinct } => {
            let ex = Exact::new(points)?;
            let (reps, _) = dedup(&ex);
            if reps.len() == *distinct && *distinct < 3 {
                Ok(())
            } else {
                Err(format!("TooFewPoints {distinct}, really {}", reps.len()))
            }
        }
        TriangulationError::AllCollinear { distinct } => {
            let ex = Exact::new(points)?;
            let (reps, _) = dedup(&ex);
            let collinear = reps.len() < 3
                || reps[2..]
                    .iter()
                    .all(|&c| ex.orient(reps[0], reps[1], c) == Ordering::Equal);
            if reps.len() == *distinct && collinear && *distinct >= 3 {
                Ok(())
            } else {
                Err(format!("AllCollinear {distinct} is wrong"))
            }
        }
        TriangulationError::TooManyPoints { count, max } => {
            if *count == points.len() && count > max {
                Ok(())
            } else {
                Err(format!("{err} is wrong"))
            }
        }
        TriangulationError::Internal { message } => Err(format!("internal error: {message}")),
    }
}
