//! `medial-blocks example hexagon|lattice|bubbles|square-lattice|periodic-bubbles [--holes N]
//! [--seed S] [-o FILE.json]`: write a ready-made domain in the `mesh` input format.

use super::{Failure, Global};
use medial_blocks::layouts::{generate, periodic_bubbles, Layout, LayoutError, DEFAULT_BUBBLES};
use medial_blocks::output::write_atomic;
use medial_blocks::periodic::PeriodicDomain;
use medial_blocks::Domain;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The paper's Hexagon: 7 equal holes in hexagonal packing (36 blocks).
    Hexagon,
    /// The paper's Lattice: 12 large holes interleaved with 9 small ones (120 blocks).
    Lattice,
    /// N random non-overlapping bubbles (default 20) from --seed.
    Bubbles,
    /// k x k equal holes on a square grid (N rounded to k², default 16): co-circular case.
    SquareLattice,
    /// N random bubbles (default 20) in a periodic square box, crossing its edges, from --seed.
    PeriodicBubbles,
}

#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  medial-blocks example hexagon                       # JSON on standard output
  medial-blocks example bubbles --holes 100 --seed 7 -o bubbles.json
  medial-blocks example square-lattice --holes 25 -o square.json
  medial-blocks example periodic-bubbles --holes 1000 -o box.json
  medial-blocks mesh bubbles.json -o bubbles

Output JSON: {\"bounding\": {\"center\": [x, y], \"radius\": R},
              \"holes\": [{\"center\": [x, y], \"radius\": r}, ...]}
(periodic-bubbles: {\"periodic\": {\"size\": [L, L]}, \"holes\": [...]})")]
pub struct Args {
    /// Which layout.
    #[arg(value_enum)]
    pub kind: Kind,
    /// Number of holes (bubbles, square-lattice, periodic-bubbles; hexagon and lattice are
    /// fixed).
    #[arg(long, value_name = "N")]
    pub holes: Option<usize>,
    /// Seed of the random layouts (bubbles, periodic-bubbles).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Output file (default: standard output).
    #[arg(short, long, value_name = "FILE.json")]
    pub output: Option<PathBuf>,
}

/// The domain as JSON, one hole a line.
pub fn domain_json(domain: &Domain) -> String {
    let b = domain.bounding();
    let mut s = format!(
        "{{\"bounding\": {},\n \"holes\": [",
        serde_json::to_string(&b).unwrap_or_default()
    );
    for (k, h) in domain.holes().iter().enumerate() {
        s.push_str(if k == 0 { "\n  " } else { ",\n  " });
        s.push_str(&serde_json::to_string(h).unwrap_or_default());
    }
    s.push_str("\n]}\n");
    s
}

/// The periodic domain as JSON, one hole a line.
pub fn periodic_json(pd: &PeriodicDomain) -> String {
    let mut s = format!(
        "{{\"periodic\": {{\"size\": {}}},\n \"holes\": [",
        serde_json::to_string(&pd.size()).unwrap_or_default()
    );
    for (k, h) in pd.holes().iter().enumerate() {
        s.push_str(if k == 0 { "\n  " } else { ",\n  " });
        s.push_str(&serde_json::to_string(h).unwrap_or_default());
    }
    s.push_str("\n]}\n");
    s
}

pub fn run(args: Args, global: Global) -> Result<(), Failure> {
    let layout = match args.kind {
        Kind::Hexagon => Layout::Hexagon,
        Kind::Lattice => Layout::Lattice,
        Kind::Bubbles => Layout::Bubbles,
        Kind::SquareLattice => Layout::SquareLattice,
        Kind::PeriodicBubbles => Layout::Bubbles,
    };
    let failure = |e: LayoutError| match e {
        LayoutError::Placement { .. } => Failure::output(e.to_string()),
        _ => Failure::input(e.to_string()),
    };
    let (json, holes) = if args.kind == Kind::PeriodicBubbles {
        let pd =
            periodic_bubbles(args.holes.unwrap_or(DEFAULT_BUBBLES), args.seed).map_err(failure)?;
        (periodic_json(&pd), pd.hole_count())
    } else {
        let domain = generate(layout, args.holes, args.seed).map_err(failure)?;
        (domain_json(&domain), domain.hole_count())
    };
    match &args.output {
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(json.as_bytes())
                .and_then(|()| out.flush())
                .map_err(|e| Failure::output(format!("cannot write standard output: {e}")))?;
        }
        Some(path) => {
            write_atomic(path, |w| w.write_all(json.as_bytes()))
                .map_err(|e| Failure::output(format!("cannot write {}: {e}", path.display())))?;
            if !global.quiet {
                eprintln!("{holes} holes written to {}", path.display());
            }
        }
    }
    Ok(())
}
