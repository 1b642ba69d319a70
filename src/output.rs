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
//! A file written again and again under one name (the checkpoint, after every frame) can
//! keep the file it replaces as its next temporary ([`write_exchanging`]): the temporary is
//! written over, and then swapped with the destination in one step (Linux's `renameat2` with
//! `RENAME_EXCHANGE`), so each write reuses the storage of the one two before it instead of
//! the system freeing a file's pages and handing out new ones. On the 2-core host that is
//! most of what writing a file costs: the 64² drape's checkpoints (440 KB after each of its
//! 61 frames) took 53–58 ms of the output thread's time written afresh and 14 ms written
//! over. Nothing else reads the temporary, so writing over it breaks no reader; the swap
//! keeps the destination whole at every moment, as the rename does; and where the swap is
//! not supported, the temporary is renamed over the destination as usual.
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
use std::io::{self, BufWriter, Seek, Write};
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
    write_file(path, write, false)
}

/// [`write_atomically`] for a file written again and again: the file replaced becomes the
/// temporary the next call writes over (see the module docs); [`remove_spare`] removes it
/// when the writing is done.
///
/// # Errors
/// As [`write_atomically`].
pub fn write_exchanging(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<u64> {
    write_file(path, write, true)
}

/// Removes the temporary [`write_exchanging`] keeps beside `path`, if there is one.
///
/// # Errors
/// When it exists and cannot be removed, naming it.
pub fn remove_spare(path: &Path) -> Result<()> {
    let spare = temporary_path(&follow_links(path)?);
    match fs::remove_file(&spare) {
        Err(err) if err.kind() != io::ErrorKind::NotFound => {
            Err(err).with_context(|| format!("removing {}", spare.display()))
        }
        _ => Ok(()),
    }
}

/// [`write_atomically`], keeping the replaced file as the next temporary when `exchange`.
fn write_file(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
    exchange: bool,
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
            Ok(meta) => replace(&target, write, exchange && meta.is_file()),
            Err(_) => replace(&target, write, false),
        }
    })()
    .with_context(|| format!("writing {}", path.display()))
}

/// The temporary at `tmp` opened to be written over from its start: only a regular file with
/// no other name (as [`replace`] leaves it; a hard link elsewhere would see it change), else a
/// new file in its place.
fn spare(tmp: &Path) -> io::Result<File> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match fs::symlink_metadata(tmp) {
            Ok(meta) if meta.is_file() && meta.nlink() == 1 => {
                return OpenOptions::new().write(true).open(tmp);
            }
            Ok(_) => fs::remove_file(tmp)?,
            Err(_) => {}
        }
    }
    File::create(tmp)
}

/// Puts the file at `tmp` in place of the one at `path`, keeping that one at `tmp` where the
/// system swaps two names in one step (Linux), else renaming `tmp` over `path`.
fn swap(tmp: &Path, path: &Path) -> io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        if renameat_with(CWD, tmp, CWD, path, RenameFlags::EXCHANGE).is_ok() {
            return Ok(());
        }
    }
    fs::rename(tmp, path)
}

/// Writes a temporary file beside `path` and renames it over `path`; returns its length. The
/// temporary is removed on failure. With `exchange` (`path` then a regular file) the
/// temporary is written over rather than made afresh, and swapped with `path` (see the
/// module docs).
fn replace(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
    exchange: bool,
) -> io::Result<u64> {
    let tmp = temporary_path(path);
    let result = (|| -> io::Result<u64> {
        let file = if exchange {
            spare(&tmp)?
        } else {
            File::create(&tmp)?
        };
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        out.flush()?;
        let file = out.get_mut();
        let length = file.stream_position()?;
        if exchange {
            file.set_len(length)?;
            swap(&tmp, path)?;
        } else {
            fs::rename(&tmp, path)?;
        }
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

    /// A file written again and again keeps the one it replaced as its next temporary, and
    /// writes over it: the destination holds each content whole, the temporary the one
    /// before (on Linux, where the two are swapped), until it is removed; a temporary with
    /// another name elsewhere (a hard link) is not written over.
    #[test]
    fn a_rewritten_file_writes_over_the_one_before_the_last() {
        let dir = std::env::temp_dir().join(format!("tailor-exchange-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("state.bin");
        let tmp = temporary_path(&path);
        for (i, text) in ["first, longer", "second", "third text"].iter().enumerate() {
            write_exchanging(&path, |w| w.write_all(text.as_bytes())).unwrap();
            assert_eq!(fs::read_to_string(&path).unwrap(), *text);
            if cfg!(target_os = "linux") && i > 0 {
                let before = ["first, longer", "second"][i - 1];
                assert_eq!(fs::read_to_string(&tmp).unwrap(), before, "write {i}");
            }
        }
        #[cfg(target_os = "linux")]
        {
            let kept = dir.join("kept.bin");
            fs::hard_link(&tmp, &kept).unwrap();
            write_exchanging(&path, |w| w.write_all(b"fourth")).unwrap();
            assert_eq!(fs::read_to_string(&path).unwrap(), "fourth");
            assert_eq!(fs::read_to_string(&kept).unwrap(), "second");
            fs::remove_file(&kept).unwrap();
        }
        remove_spare(&path).unwrap();
        remove_spare(&path).unwrap();
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["state.bin"]);
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
