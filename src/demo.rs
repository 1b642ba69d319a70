//! `tailor demo` (and `tailor` with no arguments): the mannequin in the cape, from assets
//! embedded in the binary, so a fresh clone shows cloth with one command.
//!
//! The embedded `assets/` files (the scene `assets/scenes/cape.toml`, the cape, the 121 body
//! frames) are first copied to `tailor-out/input/` in the same layout, so the scene's relative
//! paths hold and the shot can be re-run or edited there; then [`crate::simulate`] runs it into
//! `tailor-out/`, and `tailor preview`'s contact sheet of it is drawn to
//! `tailor-out/preview.png`. The demo simulates the whole walk, [`FRAMES`] frames at the
//! scene's resolution (the 525-vertex cape, its level-2 surface, the body at level 2): a few
//! seconds on a two-core machine in a release build (`docs/BENCHMARKS.md`), so nothing had to
//! be coarsened.
//! `--frames` runs fewer.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;

use crate::output::{self, write_atomically};
use crate::simulate::{self, FrameRange};

/// Frames the demo simulates after the rest pose.
pub const FRAMES: u32 = 120;

/// Arguments of `tailor demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory.
    #[arg(long, default_value = "tailor-out", value_name = "DIR")]
    pub out: PathBuf,
    /// Frames to simulate after the rest pose (the mannequin's animation has 120).
    #[arg(long, default_value_t = FRAMES, value_parser = clap::value_parser!(u32).range(1..=120))]
    pub frames: u32,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            out: "tailor-out".into(),
            frames: FRAMES,
            quiet: false,
        }
    }
}

/// `tailor preview`'s arguments, parsed so the demo's picture uses the command's defaults.
#[derive(clap::Parser)]
struct PreviewCli {
    #[command(flatten)]
    args: crate::preview::Args,
}

/// The embedded mannequin frames: `(number, OBJ text)`.
macro_rules! body_frames {
    ($($n:literal)*) => {
        [$((stringify!($n), include_str!(concat!("../assets/mannequin/body_", stringify!($n), ".obj")))),*]
    };
}

const BODY: [(&str, &str); 121] = body_frames!(
    0000 0001 0002 0003 0004 0005 0006 0007 0008 0009 0010 0011
    0012 0013 0014 0015 0016 0017 0018 0019 0020 0021 0022 0023
    0024 0025 0026 0027 0028 0029 0030 0031 0032 0033 0034 0035
    0036 0037 0038 0039 0040 0041 0042 0043 0044 0045 0046 0047
    0048 0049 0050 0051 0052 0053 0054 0055 0056 0057 0058 0059
    0060 0061 0062 0063 0064 0065 0066 0067 0068 0069 0070 0071
    0072 0073 0074 0075 0076 0077 0078 0079 0080 0081 0082 0083
    0084 0085 0086 0087 0088 0089 0090 0091 0092 0093 0094 0095
    0096 0097 0098 0099 0100 0101 0102 0103 0104 0105 0106 0107
    0108 0109 0110 0111 0112 0113 0114 0115 0116 0117 0118 0119
    0120
);

/// The embedded files other than the body, by path under `input/`.
const FILES: [(&str, &str); 2] = [
    (
        "scenes/cape.toml",
        include_str!("../assets/scenes/cape.toml"),
    ),
    (
        "garments/cape.obj",
        include_str!("../assets/garments/cape.obj"),
    ),
];

/// Runs the demo.
///
/// # Errors
/// When the output cannot be written or the simulation fails.
pub fn run(args: &Args) -> Result<ExitCode> {
    let input = args.out.join("input");
    let bodies = BODY
        .iter()
        .map(|(n, text)| (format!("mannequin/body_{n}.obj"), *text));
    let files = FILES.iter().map(|(p, text)| ((*p).to_owned(), *text));
    for (path, text) in files.chain(bodies) {
        write_file(&input.join(path), text)?;
    }
    let scene = input.join("scenes/cape.toml");
    if !args.quiet {
        eprintln!(
            "tailor demo: a cape on the walking mannequin, {} frames (scene: {})",
            args.frames,
            scene.display()
        );
    }
    let outcome = simulate::run_in_pool(&simulate::Args {
        scene,
        out: Some(args.out.clone()),
        frames: Some(FrameRange {
            start: None,
            end: Some(args.frames),
        }),
        threads: None,
        resume: false,
        quiet: args.quiet,
        strict: false,
        stop_after: None,
    })?;
    if outcome.interrupted {
        return Ok(ExitCode::from(crate::interrupt::STATUS));
    }
    let dir = outcome.dir;
    let picture = dir.join("preview.png");
    let preview = PreviewCli::try_parse_from([
        "preview".as_ref(),
        dir.as_os_str(),
        "--output".as_ref(),
        picture.as_os_str(),
    ])?;
    crate::preview::run(&preview.args)?;
    output::print(&format!(
        "a contact sheet of the cape: {}\n\
         the cape: {}, its control mesh: {}, the body: {}\n\
         check it with: tailor check '{}' --against '{}' --thickness 0.005\n",
        picture.display(),
        dir.join("cloth_####.obj").display(),
        dir.join("cloth_control_####.obj").display(),
        dir.join("body_####.obj").display(),
        dir.join("cloth_####.obj").display(),
        dir.join("body_####.obj").display()
    ))?;
    Ok(ExitCode::SUCCESS)
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    write_atomically(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    Ok(())
}
