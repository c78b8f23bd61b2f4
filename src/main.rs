use std::process::ExitCode;

fn main() -> ExitCode {
    medial_blocks_cli::run()
}

#[path = "cli/mod.rs"]
mod medial_blocks_cli;
