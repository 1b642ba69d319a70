//! Ctrl-C (SIGINT) during `tailor simulate`: the run stops cleanly between frames.
//!
//! The default SIGINT kills the process wherever it is, leaving the temporary of the file
//! being written and a checkpoint one frame behind. Instead, once [`watch`] is called, the
//! first Ctrl-C only sets a flag; the frame loop reads it ([`requested`]) after each frame's
//! files and checkpoint are written, so no write is cut short, no temporary is left, and
//! `--resume` continues from the checkpoint with the same bytes. Exit status 130 (128 +
//! SIGINT), as the shell reports a process killed by Ctrl-C. A second Ctrl-C, for a frame
//! that takes too long, ends the process at once, as the default would; the temporary it may
//! leave is removed by the next run ([`crate::simulate`]). The handler comes from the `ctrlc`
//! crate, since installing one by hand takes `unsafe`, which the workspace forbids.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result, anyhow};

/// Exit status of a run stopped by Ctrl-C.
pub const STATUS: u8 = 130;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the handler (once per process; later calls do nothing).
///
/// # Errors
/// When the handler cannot be installed.
pub fn watch() -> Result<()> {
    static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();
    INSTALLED
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                if REQUESTED.swap(true, Ordering::SeqCst) {
                    std::process::exit(i32::from(STATUS));
                }
            })
            .map_err(|e| e.to_string())
        })
        .clone()
        .map_err(|e| anyhow!(e))
        .context("watching for Ctrl-C")
}

/// Whether Ctrl-C was pressed since [`watch`].
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
