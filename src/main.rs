//! `tailor`: the command-line tool. Each subcommand lives in its own module with an `Args`
//! struct (clap) and a `run` function; this file only dispatches.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Subdivision-surface cloth for animated characters (DeRose, Kass & Truong 1998).
#[derive(Parser)]
#[command(name = "tailor", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: anyhow::Result<ExitCode> = match cli.command {
        None => Ok(ExitCode::SUCCESS),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::from(1)
        }
    }
}
