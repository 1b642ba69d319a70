//! Atomic output: every file the tool writes appears whole or not at all.
//!
//! The content goes to a temporary file beside the destination (same directory, so the final
//! rename stays on one file system), is flushed, then renamed over the destination. An
//! interrupted run leaves the previous file intact, never a half-written one.
//!
//! Files are not forced to disk (no `fsync`), as compilers, renderers and DCC caches do not
//! force theirs: a process killed at any point (Ctrl-C, SIGKILL, a farm's preemption, out of
//! memory) leaves every file whole, since the rename and the data are in the system's cache
//! either way; only a power cut or a crash of the system itself can lose what it had not yet
//! written. Syncing cost a journal commit per file, four a frame of `tailor simulate`: 2% of
//! the 64² drape's wall time re-run into its own directory (`docs/DESIGN.md`). What a power
//! cut can break is a resumed run's premise that the frames before its checkpoint are on
//! disk; the checkpoint records each frame file's length and `--resume` refuses files that
//! lost theirs (`crate::simulate`).
//!
//! Renaming over a path replaces whatever the path named, so the destination is looked at
//! first. A symbolic link is followed (link after link) to the file it names, which is
//! replaced atomically in its own directory; the link stays, as a user who linked
//! `out.obj -> /shots/real.obj` wants `real.obj` written. A destination that exists and is
//! neither a regular file nor a directory (a device such as `/dev/null`, a FIFO, a socket) is
//! opened and written in place, since it cannot be half-written the way a file can, and
//! replacing it with a regular file would break whatever else uses it (as root, `-o /dev/null`
//! would replace the system's `/dev/null`). A FIFO's write waits for its reader.
//!
//! Standard output is written through [`print`] and [`write_to`]: a reader that goes away
//! early (`tailor info x.obj | head -1`, a broken pipe) is not an error worth a message, as
//! it has read all it wanted, so the command stops quietly with exit status 0
//! ([`stdout_closed`]); any other failure (a full disk behind a redirection) is an error
//! naming standard output. Rust ignores SIGPIPE, so without this a closed pipe would make
//! `println!` panic.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Standard output was closed by its reader: the command stops quietly, with exit status 0.
#[derive(Debug)]
struct StdoutClosed;

impl std::fmt::Display for StdoutClosed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("standard output was closed by its reader")
    }
}

impl std::error::Error for StdoutClosed {}

/// Whether `err` is standard output closed by its reader, which ends a command quietly.
#[must_use]
pub fn stdout_closed(err: &anyhow::Error) -> bool {
    err.is::<StdoutClosed>()
}

/// A failed write to standard output: [`stdout_closed`] for a broken pipe, else an error
/// naming standard output.
fn stdout_error(err: io::Error) -> anyhow::Error {
    if err.kind() == io::ErrorKind::BrokenPipe {
        StdoutClosed.into()
    } else {
        anyhow::Error::new(err).context("writing standard output")
    }
}

/// Writes `text` to standard output and flushes it.
///
/// # Errors
/// As [`write_to`] with `-`.
pub fn print(text: &str) -> Result<()> {
    write_to(Path::new("-"), |w| w.write_all(text.as_bytes()))
}

/// Writes `path` atomically with the bytes `write` produces. Returns the length of the file
/// written, 0 for a device or FIFO written in place.
///
/// # Errors
/// Any I/O error, with the path in the message; the temporary file is removed on failure.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<u64> {
    (|| -> io::Result<u64> {
        let target = follow_links(path)?;
        match fs::metadata(&target) {
            Ok(meta) if !meta.is_file() && !meta.is_dir() => {
                let mut out = BufWriter::new(OpenOptions::new().write(true).open(&target)?);
                write(&mut out)?;
                out.flush()?;
                Ok(0)
            }
            _ => replace(&target, write),
        }
    })()
    .with_context(|| format!("writing {}", path.display()))
}

/// Writes a temporary file beside `path` and renames it over `path`; returns its length. The
/// temporary is removed on failure.
fn replace(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<u64> {
    let tmp = temporary_path(path);
    let result = (|| -> io::Result<u64> {
        let mut out = BufWriter::new(File::create(&tmp)?);
        write(&mut out)?;
        out.flush()?;
        let length = out.get_ref().metadata()?.len();
        fs::rename(&tmp, path)?;
        Ok(length)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Symbolic links the destination may go through before it is refused, as the kernel's
/// `ELOOP` limit.
const MAX_LINKS: usize = 40;

/// `path` with its symbolic links followed to the path they end at, which need not exist
/// yet (a dangling link is written through, creating its target).
fn follow_links(path: &Path) -> io::Result<PathBuf> {
    let mut path = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&path) {
            Ok(meta) if meta.file_type().is_symlink() => {
                // A relative target is relative to the link's directory; `join` keeps an
                // absolute one as it is.
                let target = fs::read_link(&path)?;
                path = path.parent().unwrap_or(Path::new("")).join(target);
            }
            _ => return Ok(path),
        }
    }
    Err(io::Error::other(format!(
        "more than {MAX_LINKS} symbolic links to follow"
    )))
}

/// The temporary file written before `path`: `.NAME.tmp-PID` beside it, hidden, and named
/// after the file and the process so that [`temporary_of`] can tell whose it is.
fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}{TEMPORARY}{}", std::process::id()))
}

/// What separates a temporary's destination name from its process id.
const TEMPORARY: &str = ".tmp-";

/// The name of the file whose temporary (a [`write_atomically`] killed before its rename)
/// is called `name`, or `None` when `name` is not such a temporary.
#[must_use]
pub fn temporary_of(name: &str) -> Option<&str> {
    let (destination, pid) = name.strip_prefix('.')?.rsplit_once(TEMPORARY)?;
    let is_pid = !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit());
    (is_pid && !destination.is_empty()).then_some(destination)
}

/// Writes to `path`, or to standard output when `path` is `-`.
///
/// # Errors
/// As [`write_atomically`]; for `-`, a broken pipe is [`stdout_closed`] and any other failure
/// names standard output.
pub fn write_to(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
    if path.as_os_str() == "-" {
        let stdout = io::stdout();
        let mut lock = io::BufWriter::new(stdout.lock());
        write(&mut lock)
            .and_then(|()| lock.flush())
            .map_err(stdout_error)
    } else {
        write_atomically(path, |w| write(w))?;
        Ok(())
    }
}

/// Characters an error line keeps from its start and from its end when it is cut.
const ERROR_LINE_HEAD: usize = 600;
const ERROR_LINE_TAIL: usize = 200;

/// Prints `error: …` for `err` and its causes on standard error, each line of the message
/// longer than [`ERROR_LINE_HEAD`] + [`ERROR_LINE_TAIL`] characters cut to its start and its
/// end (where the reason usually is): parsers quote the input they reject (the TOML parser a
/// whole line of it), and a 100 MB line of bad input must not become 100 MB of message.
pub fn print_error(err: &anyhow::Error) {
    let text = format!("{err:#}");
    let cut: Vec<String> = text
        .lines()
        .map(|line| {
            let chars = line.chars().count();
            if chars <= ERROR_LINE_HEAD + ERROR_LINE_TAIL {
                return line.to_owned();
            }
            let head: String = line.chars().take(ERROR_LINE_HEAD).collect();
            let tail: String = line.chars().skip(chars - ERROR_LINE_TAIL).collect();
            format!("{head} … ({} bytes) … {tail}", line.len())
        })
        .collect();
    eprintln!("error: {}", cut.join("\n"));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_keeps_the_old_file() {
        let dir = std::env::temp_dir().join(format!("tailor-output-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.txt");
        write_atomically(&path, |w| w.write_all(b"first")).unwrap();
        let err = write_atomically(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("disk full"))
        });
        assert!(err.is_err());
        assert_eq!(fs::read_to_string(&path).unwrap(), "first");
        assert_eq!(
            fs::read_dir(&dir).unwrap().count(),
            1,
            "temporary file left behind"
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn recognises_its_own_temporaries() {
        let tmp = temporary_path(Path::new("out/cloth_0003.obj"));
        let name = tmp.file_name().unwrap().to_str().unwrap();
        assert_eq!(temporary_of(name), Some("cloth_0003.obj"));
        for other in [
            "cloth_0003.obj",
            "cloth_0003.obj.tmp-12",
            ".cloth_0003.obj.tmp-",
            ".cloth_0003.obj.tmp-12a",
            "..tmp-12",
        ] {
            assert_eq!(temporary_of(other), None, "{other}");
        }
    }
}
