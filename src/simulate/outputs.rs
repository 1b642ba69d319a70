//! The files a run owns in its output directory: the frames of its three sequences, the
//! checkpoint and the summary, and the temporaries of any of them that a killed run left
//! (`.cloth_0020.obj.tmp-7257`: SIGKILL, or a second Ctrl-C, gives no chance to remove them).
//!
//! A run removes stale temporaries before its first frame, so they do not pile up over
//! interrupted runs. A run that starts from frame 0 also removes the files of an earlier run:
//! a shorter shot written over a longer one would otherwise leave the longer one's last
//! frames behind, and `tailor check` and `tailor preview`, which read every frame of a
//! sequence present, would take them for the new shot's. Nothing else in the directory is touched: the scene's inputs may live
//! there (the demo's `input/`), and so may the user's own files, hidden or not.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use super::summary;
use crate::checkpoint::{self, FrameStats};
use crate::output;
use crate::sequence::Pattern;

/// The frame sequences a run writes, in the order a checkpoint records their files' lengths
/// ([`crate::checkpoint::FrameStats::written`]).
const SEQUENCES: [&str; 3] = ["cloth_control_####.obj", "cloth_####.obj", "body_####.obj"];

/// Which sequence: an index into [`SEQUENCES`].
#[derive(Clone, Copy, Debug)]
pub enum Sequence {
    Control = 0,
    Surface = 1,
    Body = 2,
}

/// Frame `frame`'s file of `sequence` in `dir`.
pub fn frame_file(dir: &Path, sequence: Sequence, frame: u32) -> PathBuf {
    numbered(dir, sequence as usize, frame)
}

fn numbered(dir: &Path, sequence: usize, frame: u32) -> PathBuf {
    Pattern::parse(&dir.join(SEQUENCES[sequence]))
        .expect("a numbered file name")
        .path(frame)
}

/// Checks that the frames of `stats` (a checkpoint's) are in `dir` as the run wrote them:
/// every file it wrote there with the length it had. Files are not forced to disk (see
/// [`crate::output`]), so a power cut can lose the last frames a checkpoint counts as
/// written; resuming after them would leave those frames empty or missing for good.
///
/// # Errors
/// The first file missing or of another length, naming it, or one that cannot be read.
pub fn check_written(dir: &Path, stats: &[FrameStats]) -> Result<()> {
    for row in stats {
        for (sequence, &length) in row.written.iter().enumerate() {
            if length == 0 {
                continue;
            }
            let file = numbered(dir, sequence, row.frame);
            let found = match fs::metadata(&file) {
                Ok(meta) if meta.len() == length => continue,
                Ok(meta) => format!("is {} bytes", meta.len()),
                Err(e) if e.kind() == io::ErrorKind::NotFound => "is missing".to_owned(),
                Err(e) => return Err(e).with_context(|| format!("reading {}", file.display())),
            };
            bail!(
                "{} {found}, where the run that wrote the checkpoint wrote {length} bytes: a \
                 frame it counts as written was lost or changed since (files are not forced \
                 to disk, and a power cut can lose the last ones); run without --resume to \
                 start over",
                file.display()
            );
        }
    }
    Ok(())
}

/// Whether `name` is a file a run writes: a frame of its sequences, the checkpoint or the
/// summary.
fn is_output(name: &str) -> bool {
    name == checkpoint::FILE
        || name == summary::FILE
        || SEQUENCES
            .iter()
            .any(|s| Pattern::parse(Path::new(s)).is_some_and(|p| p.matches(name)))
}

/// Whether `name` is the temporary of a file a run writes.
fn is_temporary(name: &str) -> bool {
    output::temporary_of(name).is_some_and(is_output)
}

/// Removes the stale temporaries of a run's files from `dir`; returns how many.
///
/// # Errors
/// When `dir` cannot be listed or a temporary cannot be removed, naming it.
pub fn remove_temporaries(dir: &Path) -> Result<usize> {
    remove(dir, is_temporary)
}

/// Removes the files an earlier run wrote into `dir` (a run starting from frame 0 writes
/// them all afresh); returns how many.
///
/// # Errors
/// As [`remove_temporaries`].
pub fn remove_earlier(dir: &Path) -> Result<usize> {
    remove(dir, is_output)
}

/// Removes the files in `dir` whose names pass `which`; returns how many.
fn remove(dir: &Path, which: fn(&str) -> bool) -> Result<usize> {
    let listing = || format!("listing {}", dir.display());
    let mut removed = 0;
    for entry in fs::read_dir(dir).with_context(listing)? {
        let entry = entry.with_context(listing)?;
        if entry.file_name().to_str().is_some_and(which) {
            let path = entry.path();
            fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
            removed += 1;
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recognises_a_runs_files_only() {
        for name in [
            "cloth_0003.obj",
            "cloth_control_0003.obj",
            "body_12345.obj",
            "tailor_checkpoint.bin",
            "summary.json",
        ] {
            assert!(is_output(name), "{name}");
            assert!(is_temporary(&format!(".{name}.tmp-42")), "{name}");
        }
        for name in [
            "cloth_3.obj",
            "cloth_0003.obj.bak",
            "notes.txt",
            "preview.png",
            ".notes.tmp-1",
            ".cloth_0003.obj.tmp-x",
        ] {
            assert!(!is_output(name) && !is_temporary(name), "{name}");
        }
    }
}
