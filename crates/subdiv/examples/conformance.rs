//! Compares the crate with OpenSubdiv 3.6.0's reference output and prints a pass count.
//!
//! `cargo run --release -p tailor-subdiv --example conformance -- ../shared/reference/opensubdiv [FILTER]`
//!
//! Exits 1 when any file fails.

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let Some(dir) = args.next().map(PathBuf::from) else {
        eprintln!("usage: conformance REFERENCE_DIR [FILTER]");
        return ExitCode::from(2);
    };
    let filter = args.next().unwrap_or_default();
    let outcomes: Vec<_> = tailor_subdiv::conformance::run(&dir)
        .into_iter()
        .filter(|o| o.name.contains(&filter))
        .collect();
    let passed = outcomes.iter().filter(|o| o.failure.is_none()).count();
    for o in outcomes.iter().filter(|o| o.failure.is_some()) {
        println!("{o}");
    }
    println!(
        "conformance: {passed} of {} reference files match OpenSubdiv ({} differ)",
        outcomes.len(),
        outcomes.len() - passed
    );
    if passed == outcomes.len() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
