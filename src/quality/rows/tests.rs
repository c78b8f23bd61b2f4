//! Tests of [`super`]: each fast path against its reference, bit for bit.

use super::*;
use crate::layouts::SplitMix64;

fn refs(a: &[Vec<f64>; 4]) -> [&[f64]; 4] {
    [&a[0][..], &a[1][..], &a[2][..], &a[3][..]]
}

/// The AVX2 build of loop 1 gives the bits of the portable one (where the CPU has AVX2),
/// on rows with ordinary, degenerate, inverted and extreme cells.
#[test]
fn wide_and_portable_rows_agree() {
    let t = Tables::new();
    if !t.wide {
        return;
    }
    let mut r = SplitMix64(3);
    let mut u = || r.next_f64();
    for n in [1usize, 2, 3, 5, 8, 16, 17, 33] {
        for round in 0..200 {
            let scale = [1.0, 1e-150, 1e150, 1e-3][round % 4];
            let mut edge = |len: usize| {
                let mut v = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
                for _ in 0..len {
                    let (x, y) = match (u() * 10.0) as u32 {
                        0 => (0.0, 0.0),
                        1 => (f64::NAN, 1.0),
                        _ => (scale * (2.0 * u() - 1.0), scale * (2.0 * u() - 1.0)),
                    };
                    v[0].push(x);
                    v[1].push(y);
                    v[2].push(checked_len(x, y));
                    v[3].push(angle_deg(y, x));
                }
                v
            };
            let (b, tt, v) = (edge(n), edge(n), edge(n + 1));
            let mut one = vec![Figures::default(); n];
            let mut two = vec![Figures::default(); n];
            let k1 = row_figures::<true>(refs(&b), refs(&tt), refs(&v), &t, &mut one);
            // SAFETY: `t.wide` says the CPU has AVX2.
            let k2 = unsafe { row_figures_avx2(refs(&b), refs(&tt), refs(&v), &t, &mut two) };
            assert_eq!(format!("{k1:?}"), format!("{k2:?}"));
            let bits = |f: &[Figures]| -> Vec<u64> {
                f.iter()
                    .flat_map(|c| c.fig.iter().map(|x| x.to_bits()).chain([c.bins]))
                    .collect()
            };
            assert_eq!(bits(&one), bits(&two));
        }
    }
}

/// The AVX2 and AVX-512 builds of a whole band (its edges, then loop 1) give the bits of
/// the portable one, on node lines with repeated, tiny, huge and non-finite nodes; and the
/// slots between node lines and the padding are never on the fast path.
#[test]
fn wide_and_portable_bands_agree() {
    let t = Tables::new();
    if !t.wide {
        return;
    }
    let mut r = SplitMix64(7);
    let mut u = || r.next_f64();
    for (ni, nb) in [
        (1usize, 1usize),
        (2, 3),
        (3, 1),
        (5, 2),
        (8, 4),
        (16, 16),
        (17, 2),
    ] {
        let w = ni + 1;
        for round in 0..100 {
            let scale = [1.0, 1e-150, 1e150, 1e-3][round % 4];
            let nodes: Vec<Point> = (0..(nb + 1) * w)
                .map(|_| match (u() * 12.0) as u32 {
                    0 => [0.0, 0.0],
                    1 => [f64::NAN, 1.0],
                    2 => [f64::INFINITY, 0.5],
                    _ => [scale * (2.0 * u() - 1.0), scale * (2.0 * u() - 1.0)],
                })
                .collect();
            let run = |wide: u8| {
                let mut rows = Rows::default();
                let tables = Tables {
                    wide: wide >= 1,
                    wider: wide >= 2,
                    ..Tables::new()
                };
                let k = rows.figures(&nodes, w, nb, &tables);
                for (p, c) in rows.cells.iter().enumerate() {
                    if p % w == ni || p >= nb * w {
                        assert_eq!(c.bins & FAST, 0, "slot {p} is no cell");
                    }
                }
                let bits: Vec<u64> = rows
                    .cells
                    .iter()
                    .enumerate()
                    .filter(|&(p, _)| p % w != ni && p < nb * w)
                    .flat_map(|(_, c)| c.fig.iter().map(|x| x.to_bits()).chain([c.bins]))
                    .collect();
                (format!("{k:?}"), bits)
            };
            let portable = run(0);
            assert_eq!(portable, run(1));
            if t.wider {
                assert_eq!(portable, run(2));
            }
        }
    }
}
