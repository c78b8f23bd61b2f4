//! `medial-blocks triangulate POINTS.csv [-o OUT.json]` (STUB).

use super::Failure;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV of `x,y` per line (an optional header line is skipped).
    pub points: Option<PathBuf>,
    /// Output JSON file (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let _ = args;
    Err(Failure::output("not implemented yet"))
}
