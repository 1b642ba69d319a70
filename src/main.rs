//! `tailor`: the command-line tool. Each subcommand lives in its own module with an `Args`
//! struct (clap) and a `run` function; this file only dispatches.

use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};

mod check;
mod info;
mod output;
mod polymesh_obj;
mod sequence;
mod subdivide;

/// Subdivision-surface cloth for animated characters (DeRose, Kass & Truong 1998).
#[derive(Parser)]
#[command(name = "tailor", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Refine an OBJ control mesh with Catmull-Clark subdivision, exactly as OpenSubdiv does.
    Subdivide(subdivide::Args),
    /// Describe a control mesh: counts, histograms, boundaries, creases, holes.
    Info(info::Args),
    /// Check a simulated cloth (or a frame sequence) for body penetration and self-intersection.
    Check(check::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: anyhow::Result<ExitCode> = match cli.command {
        Some(Command::Subdivide(args)) => subdivide::run(&args),
        Some(Command::Info(args)) => info::run(&args),
        Some(Command::Check(args)) => check::run(&args),
        None => {
            // The built-in demo arrives with the simulation pipeline; until then, the help.
            Cli::command()
                .print_help()
                .map(|()| ExitCode::SUCCESS)
                .map_err(Into::into)
        }
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::from(1)
        }
    }
}
