//! The valid range of every real-valued option, each decided from what the option means, and
//! the one check that refuses a value outside it ([`check_ranges`], run by [`crate::mesh()`]
//! and [`crate::mesh_periodic`] before any work) with a message naming the flag, the value and
//! the range.
//!
//! | Flag | Range | Why |
//! |------|-------|-----|
//! | `--refine-ratio R` | `1/sqrt(3) <= R`, finite | `R` bounds circumradius / shortest edge; no triangle is below `1/sqrt(3)` (the equilateral one), so a smaller `R` calls every triangle poor |
//! | `--growth G` (and `--circle-clustering`'s) | `1 <= G <=` [`MAX_GROWTH`] | the largest ratio of neighbouring wall-normal cells: below 1 cells would shrink away from the wall; the one transition cell may reach `G^2` |
//! | `--collapse-fraction F` | `0 <= F <=` [`MAX_COLLAPSE_FRACTION`] | arcs shorter than `F` local empty-circle radii are merged into one vertex; see [`MAX_COLLAPSE_FRACTION`] |
//! | `--first-height H`, `--first-height-rel F`, `--circle-clustering`'s `FIRST` | `> 0`, finite | a length (or a fraction of a radius); too large for a spoke gives equal spacing |
//! | `--cell-size H` | `> 0`, finite | a length; one too small for the node limit is refused by the grid ([`crate::grid::GridError::TooManyNodes`]) |
//!
//! `--cells` is in `1..=`[`crate::grid::MAX_CELLS_PER_SIDE`] ([`check_cells`]). The other
//! integer options are checked where they are used: `--block-cells` and the `N` of
//! `--wall-cells` in the same range, `--smooth` in
//! `0..=`[`crate::exact_mode::MAX_SMOOTH_SWEEPS`], `--threads` in `1..=`[`MAX_THREADS`] (the
//! CLI), `--transition`'s spacing by [`crate::transition`].

use crate::exact_mode::{Clustering, FirstCell};
use crate::grid::{GridError, MAX_CELLS_PER_SIDE};
use crate::mesher::{MeshError, Options};
use crate::numfmt::Num;

/// The smallest `--refine-ratio`: `1/sqrt(3)`, the circumradius / shortest edge ratio of the
/// equilateral triangle, the smallest any triangle has. (It is the double nearest
/// `1/sqrt(3)`, `1.0 / 3f64.sqrt()`.)
pub const MIN_REFINE_RATIO: f64 = 0.577_350_269_189_625_8;

/// The largest `--growth`: a neighbour ten times the size of its cell (and the one transition
/// cell up to a hundred times) is already far beyond any wall clustering a solver accepts
/// (1.05 to 1.3 is usual); larger values only overflow the geometric series.
pub const MAX_GROWTH: f64 = 10.0;

/// The largest `--collapse-fraction`: an arc no longer than the radius of the smaller empty
/// circle at its ends has its ends within that radius of each other, so the merged vertex
/// (their mean) lies well inside both empty circles, in the fluid. Longer arcs are not short
/// in the paper's sense (its default is 0.05), and the blocking does not always recover from
/// merging them: the `neartouch` layout meshes up to 1.2 but ends in an internal error (a
/// block of negative area) from 1.3 on.
pub const MAX_COLLAPSE_FRACTION: f64 = 1.0;

/// The most worker threads `--threads` may ask for (each reserves a stack; 100 000 threads
/// took minutes to start).
pub const MAX_THREADS: usize = 1024;

/// The refusal of `flag value`: `"--growth 1e308 is out of range: expected 1 <= G <= 10"`.
pub fn out_of_range(flag: &str, value: f64, range: &str) -> MeshError {
    MeshError::Options(format!(
        "{flag} {} is out of range: expected {range}",
        Num(value)
    ))
}

/// `--refine-ratio`: finite and at least [`MIN_REFINE_RATIO`].
pub fn check_refine_ratio(ratio: f64) -> Result<(), MeshError> {
    if ratio.is_finite() && ratio >= MIN_REFINE_RATIO {
        Ok(())
    } else {
        Err(out_of_range(
            "--refine-ratio",
            ratio,
            &format!(
                "a finite R >= {} (1/sqrt(3): no triangle has a smaller circumradius / \
                 shortest edge; --no-refine turns refinement off)",
                Num(MIN_REFINE_RATIO)
            ),
        ))
    }
}

/// `--collapse-fraction`: in `0..=`[`MAX_COLLAPSE_FRACTION`].
pub fn check_collapse_fraction(fraction: f64) -> Result<(), MeshError> {
    if (0.0..=MAX_COLLAPSE_FRACTION).contains(&fraction) {
        Ok(())
    } else {
        Err(out_of_range(
            "--collapse-fraction",
            fraction,
            &format!("0 <= F <= {}", Num(MAX_COLLAPSE_FRACTION)),
        ))
    }
}

/// A positive finite length or fraction.
fn check_positive(flag: &str, value: f64) -> Result<(), MeshError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(out_of_range(flag, value, "a finite number > 0"))
    }
}

/// One clustering: the growth in `1..=`[`MAX_GROWTH`], the first height positive. `flags`
/// names what it came from: the growth, the absolute and the relative first height.
fn check_clustering(k: &Clustering, flags: [&str; 3]) -> Result<(), MeshError> {
    if !(1.0..=MAX_GROWTH).contains(&k.growth) {
        return Err(out_of_range(
            flags[0],
            k.growth,
            &format!("1 <= G <= {}", Num(MAX_GROWTH)),
        ));
    }
    match k.first {
        Some(FirstCell::Absolute(h)) => check_positive(flags[1], h),
        Some(FirstCell::Relative(f)) => check_positive(flags[2], f),
        None => Ok(()),
    }
}

/// `--cells`: in `1..=`[`crate::grid::MAX_CELLS_PER_SIDE`] (above it the typed
/// [`GridError::TooManyCellsPerSide`], refused before any grid allocation).
pub fn check_cells(cells: usize) -> Result<(), MeshError> {
    if cells == 0 {
        return Err(MeshError::Options(
            "--cells must be at least 1 (cells along a block side)".into(),
        ));
    }
    if cells > MAX_CELLS_PER_SIDE {
        return Err(MeshError::Grid(GridError::TooManyCellsPerSide {
            cells,
            limit: MAX_CELLS_PER_SIDE,
        }));
    }
    Ok(())
}

/// Check `--cells` ([`check_cells`]) and every real-valued option against its range (see the
/// module documentation), in both modes (an option the mode does not read is still refused
/// when out of range). Needs no domain, so the CLI runs it once before meshing a sequence.
pub fn check_ranges(options: &Options) -> Result<(), MeshError> {
    check_cells(options.cells)?;
    if let Some(r) = options.refine_ratio {
        check_refine_ratio(r)?;
    }
    check_collapse_fraction(options.collapse_fraction)?;
    if let Some(h) = options.cell_size {
        check_positive("--cell-size", h)?;
    }
    check_clustering(
        &options.clustering,
        ["--growth", "--first-height", "--first-height-rel"],
    )?;
    for (c, k) in &options.circle_clustering {
        let flag = format!("--circle-clustering of circle {c}:");
        check_clustering(
            k,
            [
                &format!("{flag} GROWTH"),
                &format!("{flag} FIRST"),
                &format!("{flag} FIRST (relative)"),
            ],
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_refine_ratio_is_one_over_sqrt_3() {
        assert_eq!(MIN_REFINE_RATIO, 1.0 / 3f64.sqrt());
        // The equilateral triangle's circumradius over its edge, exactly as the refinement
        // measures it, is not below the limit by more than rounding.
        let r = 1.0 / (2.0 * (std::f64::consts::PI / 3.0).sin());
        assert!((r - MIN_REFINE_RATIO).abs() <= 2.0 * f64::EPSILON);
    }

    #[test]
    fn ends_of_each_range() {
        assert!(check_refine_ratio(MIN_REFINE_RATIO).is_ok());
        assert!(check_refine_ratio(f64::MAX).is_ok());
        for bad in [0.5, 0.577, 0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(check_refine_ratio(bad).is_err(), "{bad}");
        }
        assert!(check_collapse_fraction(0.0).is_ok());
        assert!(check_collapse_fraction(MAX_COLLAPSE_FRACTION).is_ok());
        for bad in [-0.0001, 1.0000001, 1e9, f64::NAN, f64::INFINITY] {
            assert!(check_collapse_fraction(bad).is_err(), "{bad}");
        }
        let k = |growth, first| Clustering { first, growth };
        let f = ["--growth", "--first-height", "--first-height-rel"];
        assert!(check_clustering(&k(1.0, None), f).is_ok());
        assert!(check_clustering(&k(MAX_GROWTH, Some(FirstCell::Absolute(1e-300))), f).is_ok());
        for bad in [0.999, 10.000001, 1e308, f64::NAN] {
            assert!(check_clustering(&k(bad, None), f).is_err(), "{bad}");
        }
        let e = check_clustering(&k(1.2, Some(FirstCell::Relative(0.0))), f).unwrap_err();
        assert_eq!(
            e.to_string(),
            "invalid options: --first-height-rel 0 is out of range: expected a finite number > 0"
        );
    }
}
