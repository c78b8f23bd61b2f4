//! `medial-blocks mesh-sequence FRAMES.jsonl [-o DIR] [--cells N] [--format LIST] [--binary] [--threads N]`.

use super::{Failure, Global};
use medial_blocks::output::Format;
use medial_blocks::sequence::{parse_frames, run_sequence};
use medial_blocks::Options;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
#[command(
    after_help = "Input: JSON Lines, one domain per line (bounded or periodic JSON, as for
  `mesh`), the same domain with its holes moving.
Output in DIR: frame_00000/, frame_00001/, ... (the mesh of each frame, with --format's files),
  mesh.pvd (ParaView time series of the frames' mesh.vtm; open it to play the sequence) and
  summary.json (per frame: ok or its error, blocks, cells, angles, inverted cells, and whether
  the medial combinatorics, the blocks and their node counts are those of the previous frame).
Node counts: consecutive frames with the same medial combinatorics form a run; every frame of
  a run is meshed with the node counts of the run's first frame (same blocks, same ni x nj, so
  a solver can map its fields), unless they do not fit the frame (then its own counts are used
  and summary.json says why in node_counts_not_kept).
Frames are meshed in parallel; the output does not depend on --threads. A frame that fails
  (e.g. overlapping holes) is reported and the others are still meshed.
Exit codes: 0 every frame meshed, 2 some frame failed or bad input, 1 output not written."
)]
pub struct Args {
    /// The frames: JSON Lines, one domain per line.
    pub input: PathBuf,
    /// Output directory (created if missing).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Target number of cells along a block side; 1 to 100000.
    #[arg(long, default_value_t = 16, allow_negative_numbers = true)]
    pub cells: usize,
    /// Writers, comma separated: vtk, plot3d, gmsh, svg, png, json, or all.
    #[arg(long, default_value = "vtk,svg,json")]
    pub format: String,
    /// Write the VTK files with raw appended binary data and the Gmsh .msh as 4.1 binary (as
    /// `mesh --binary`).
    #[arg(long)]
    pub binary: bool,
}

/// Run `mesh-sequence`; the global `--threads` and `--quiet` apply.
pub fn run(args: Args, global: Global) -> Result<(), Failure> {
    let formats =
        Format::parse_list(&args.format).map_err(|e| Failure::input(format!("--format: {e}")))?;
    let text = std::fs::read_to_string(&args.input)
        .map_err(|e| Failure::input(format!("cannot read {}: {e}", args.input.display())))?;
    let frames = parse_frames(&text);
    if frames.is_empty() {
        return Err(Failure::input(format!(
            "{}: no frame (one domain JSON per line)",
            args.input.display()
        )));
    }
    let options = Options {
        cells: args.cells,
        ..Options::default()
    };
    // A bad flag is refused once, before any frame (not once per frame).
    medial_blocks::ranges::check_ranges(&options).map_err(|e| Failure::input(e.to_string()))?;
    let bar = if global.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        let b = indicatif::ProgressBar::new(frames.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} frames [{elapsed}]")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    };
    let tick = || bar.inc(1);
    let summary = run_sequence(
        &frames,
        &options,
        &formats,
        super::mesh::encoding(args.binary),
        &args.output,
        global.threads,
        &tick,
    )
    .map_err(|e| Failure::output(format!("cannot write into {}: {e}", args.output.display())))?;
    bar.finish_and_clear();
    for f in &summary.frames {
        if let Some(e) = &f.error {
            eprintln!("frame {}: error: {e}", f.index);
        }
    }
    if !global.quiet {
        println!("frame  blocks    cells  min angle  max angle  inverted  same combinatorics");
        for f in summary.frames.iter().filter(|f| f.ok) {
            println!(
                "{:>5}  {:>6}  {:>7}  {:>9.1}  {:>9.1}  {:>8}  {}",
                f.index,
                f.blocks,
                f.cells,
                f.min_angle_deg,
                f.max_angle_deg,
                f.inverted_cells,
                if f.same_combinatorics_as_previous {
                    if f.same_node_counts_as_previous {
                        "yes (same blocks and node counts)"
                    } else {
                        "yes (node counts differ)"
                    }
                } else {
                    "no"
                }
            );
        }
        println!(
            "{} of {} frames meshed; written to {}/ (mesh.pvd, summary.json)",
            summary.frames.len() - summary.failed,
            summary.frames.len(),
            args.output.display()
        );
    }
    if summary.failed > 0 {
        return Err(Failure::input(format!(
            "{} of {} frames failed",
            summary.failed,
            summary.frames.len()
        )));
    }
    Ok(())
}
