//! `tailor`: the command-line tool. Each subcommand lives in its own module with an `Args`
//! struct (clap) and a `run` function; this file only dispatches.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod check;
mod checkpoint;
mod demo;
mod info;
mod interrupt;
mod output;
mod polymesh_obj;
mod preview;
mod scene;
mod sequence;
mod simulate;
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
    /// Simulate a garment on an animated body from a scene file.
    Simulate(simulate::Args),
    /// Simulate the built-in demo (a mannequin in a cape) into ./tailor-out/.
    Demo(demo::Args),
    /// Draw chosen frames of a simulation output directory as a contact sheet (and a GIF).
    Preview(preview::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: anyhow::Result<ExitCode> = match cli.command {
        Some(Command::Subdivide(args)) => subdivide::run(&args),
        Some(Command::Info(args)) => info::run(&args),
        Some(Command::Check(args)) => check::run(&args),
        Some(Command::Simulate(args)) => simulate::run(&args),
        Some(Command::Demo(args)) => demo::run(&args),
        Some(Command::Preview(args)) => preview::run(&args),
        None => demo::run(&demo::Args::default()),
    };
    match result {
        Ok(code) => code,
        Err(err) if output::stdout_closed(&err) => ExitCode::SUCCESS,
        Err(err) => {
            output::print_error(&err);
            ExitCode::from(1)
        }
    }
}
