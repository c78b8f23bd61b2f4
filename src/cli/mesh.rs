//! `medial-blocks mesh [INPUT.json] [-o DIR] [--mode paper] [--cells N]` (STUB).

use super::Failure;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Domain JSON; without it, the built-in 7-hole hexagon example.
    pub input: Option<PathBuf>,
    /// Output directory.
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Target number of cells along a block side.
    #[arg(long, default_value_t = 16)]
    pub cells: usize,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let _ = args;
    Err(Failure::output("not implemented yet"))
}
