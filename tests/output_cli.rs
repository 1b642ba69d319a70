//! Where the tool's output goes, end to end.
//!
//! - Standard output closed early by its reader (`| head -1`) stops every command that
//!   prints quietly, with exit status 0: no panic, nothing on standard error. Standard output
//!   that cannot be written (`> /dev/full`) is an error naming it.
//! - `-o` onto a device or a FIFO writes it in place; onto a symbolic link, replaces the file
//!   the link names and leaves the link.

use std::fs::{self, File};
use std::io::{BufRead, BufReader};
use std::os::unix::fs::{FileTypeExt, symlink};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::{root, scratch, shape};

mod common;

/// Every command that prints to standard output, with arguments that make it print; `dir`
/// takes what they write to files.
fn printing_commands(dir: &Path) -> Vec<Vec<String>> {
    let cape = root().join("assets/garments/cape.obj");
    let scene = root().join("assets/scenes/cape.toml");
    let out = dir.join("shot");
    [
        vec!["info", &shape("catmark_cube.obj")],
        vec!["check", cape.to_str().unwrap()],
        vec!["subdivide", &shape("catmark_cube.obj"), "-l", "5"],
        vec![
            "simulate",
            scene.to_str().unwrap(),
            "--frames",
            "..1",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
    ]
    .into_iter()
    .map(|args| args.into_iter().map(String::from).collect())
    .collect()
}

/// Runs tailor with `args`, standard output a pipe whose reader takes `lines` lines then
/// closes it.
fn with_reader_gone(args: &[String], lines: usize) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut reader = BufReader::new(child.stdout.take().unwrap());
    for _ in 0..lines {
        reader.read_line(&mut String::new()).unwrap();
    }
    drop(reader);
    child.wait_with_output().unwrap()
}

#[test]
fn a_closed_pipe_stops_quietly() {
    let dir = scratch("output_cli_pipe");
    for args in printing_commands(&dir) {
        // Closed before anything is printed, and after the first line of a long output.
        for lines in [0, 1] {
            let o = with_reader_gone(&args, lines);
            assert_eq!(
                o.status.code(),
                Some(0),
                "{args:?} after {lines} line(s): {}",
                String::from_utf8_lossy(&o.stderr)
            );
            assert!(
                o.stderr.is_empty(),
                "{args:?} after {lines} line(s) printed {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
    }
}

#[test]
fn a_full_standard_output_is_an_error_naming_it() {
    let dir = scratch("output_cli_full");
    for args in printing_commands(&dir) {
        let o = Command::new(env!("CARGO_BIN_EXE_tailor"))
            .args(&args)
            .stdout(File::options().write(true).open("/dev/full").unwrap())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        // `check` keeps 1 for cloth found wanting: it cannot check, 2.
        let code = if args[0] == "check" { 2 } else { 1 };
        assert_eq!(o.status.code(), Some(code), "{args:?}: {stderr}");
        assert!(
            stderr.contains("error: writing standard output"),
            "{args:?}: {stderr}"
        );
    }
}

/// `tailor subdivide` of the cube at level 1 into `out` (`-`: standard output).
fn subdivide_to(out: &Path) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(["subdivide", &shape("catmark_cube.obj"), "-l", "1", "-o"])
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "-o {}: {}",
        out.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The names in `dir` that start with a dot, as temporaries do.
fn hidden(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with('.'))
        .collect()
}

#[test]
fn a_device_is_written_in_place() {
    // First a node of our own for the null device, when it can be made (as root), so that
    // a tool replacing it fails here before it could replace the system's `/dev/null`.
    let dir = scratch("output_cli_device");
    let own = dir.join("null");
    let made = Command::new("mknod")
        .arg(&own)
        .args(["c", "1", "3"])
        .status()
        .is_ok_and(|s| s.success());
    let nodes = if made {
        vec![own, PathBuf::from("/dev/null")]
    } else {
        vec![PathBuf::from("/dev/null")]
    };
    for node in nodes {
        subdivide_to(&node);
        let kind = fs::symlink_metadata(&node).unwrap().file_type();
        assert!(kind.is_char_device(), "{} was replaced", node.display());
    }
    assert!(hidden(&dir).is_empty(), "left behind: {:?}", hidden(&dir));
}

#[test]
fn a_symlink_is_followed_and_stays() {
    let dir = scratch("output_cli_symlink");
    let expected = subdivide_to(Path::new("-")).stdout;
    fs::write(dir.join("real.obj"), "earlier").unwrap();
    symlink("real.obj", dir.join("out.obj")).unwrap();
    // A link to a link, and a dangling link whose target the write creates.
    symlink("out.obj", dir.join("again.obj")).unwrap();
    symlink("made.obj", dir.join("dangling.obj")).unwrap();
    for (link, target, real) in [
        ("out.obj", "real.obj", "real.obj"),
        ("again.obj", "out.obj", "real.obj"),
        ("dangling.obj", "made.obj", "made.obj"),
    ] {
        fs::write(dir.join("real.obj"), "earlier").unwrap();
        subdivide_to(&dir.join(link));
        assert!(
            fs::symlink_metadata(dir.join(link))
                .unwrap()
                .file_type()
                .is_symlink(),
            "{link} was replaced"
        );
        assert_eq!(fs::read_link(dir.join(link)).unwrap(), Path::new(target));
        assert!(fs::read(dir.join(real)).unwrap() == expected, "{real}");
    }
    assert!(hidden(&dir).is_empty(), "left behind: {:?}", hidden(&dir));
}

#[test]
fn a_fifo_is_written_in_place() {
    let dir = scratch("output_cli_fifo");
    let fifo = dir.join("fifo");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success(), "mkfifo failed");
    let expected = subdivide_to(Path::new("-")).stdout;
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || fs::read(fifo).unwrap())
    };
    subdivide_to(&fifo);
    // Checked before joining: a tool that replaced the FIFO never opened it, and the reader
    // would wait for ever.
    let kind = fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(kind.is_fifo(), "the FIFO was replaced");
    assert!(reader.join().unwrap() == expected);
}
