//! The command-line interface. Exit codes: 0 success, 1 failure to write output or an internal
//! error, 2 bad input (unreadable, malformed or invalid).

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod mesh;
mod sequence;
mod triangulate;

/// Automatic multiblock structured meshes for 2D flow around circular particles.
#[derive(Parser, Debug)]
#[command(name = "medial-blocks", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Delaunay-triangulate a CSV of points exactly (x,y per line).
    Triangulate(triangulate::Args),
    /// Mesh a domain of circles (JSON), or the built-in example.
    Mesh(mesh::Args),
    /// Mesh a sequence of frames (JSON Lines, one domain per line) in parallel, with a
    /// ParaView time series.
    MeshSequence(sequence::Args),
}

/// A CLI failure: the message for stderr and the exit code.
pub struct Failure {
    pub code: u8,
    pub message: String,
}

impl Failure {
    pub fn input(message: impl Into<String>) -> Self {
        Failure {
            code: 2,
            message: message.into(),
        }
    }
    pub fn output(message: impl Into<String>) -> Self {
        Failure {
            code: 1,
            message: message.into(),
        }
    }
}

pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Triangulate(args) => triangulate::run(args),
        Command::Mesh(args) => mesh::run(args),
        Command::MeshSequence(args) => sequence::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}
