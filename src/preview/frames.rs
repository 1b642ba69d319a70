//! Which frames to show and where their meshes are: the `--frames` list, the default choice,
//! and reading `cloth_####.obj` and `body_####.obj` (or a `--body` file or pattern) for each.

use std::path::Path;
use std::str::FromStr;

use anyhow::{Result, bail};
use rayon::prelude::*;

use crate::polymesh_obj::{self, PolyMesh};
use crate::sequence::Pattern;

/// How many frames the sheet shows when `--frames` is not given.
const DEFAULT_COUNT: usize = 12;

/// Most frames a `--frames` list may name: counted before any is listed, so that
/// `0-4294967295` is an error, not a 16 GB allocation.
const MAX_LISTED: u64 = 10_000;

/// The cloth file pattern in a simulation output directory.
pub const CLOTH: &str = "cloth_####.obj";
/// The body file pattern in a simulation output directory.
pub const BODY: &str = "body_####.obj";

/// Frame numbers as written on the command line: `0,30,60`, ranges `0-120`, ranges with a step
/// `0-120x20` (every 20th frame from 0 to 120, as Nuke writes it), or a mix; kept in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameList(Vec<u32>);

impl FromStr for FrameList {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let number = |s: &str| {
            s.trim()
                .parse::<u32>()
                .map_err(|_| format!("{s:?} is not a frame number"))
        };
        let mut frames = Vec::new();
        for item in text.split(',') {
            let (range, step) = item.split_once('x').unwrap_or((item, "1"));
            let step = number(step)?;
            if step == 0 {
                return Err(format!("{item:?}: the step must be at least 1"));
            }
            match range.split_once('-') {
                None if item == range => frames.push(number(range)?),
                None => return Err(format!("{item:?}: a step needs a range, as in 0-120x10")),
                Some((first, last)) => {
                    let (first, last) = (number(first)?, number(last)?);
                    if last < first {
                        return Err(format!("{item:?}: the range runs backwards"));
                    }
                    let count = u64::from(last - first) / u64::from(step) + 1;
                    if frames.len() as u64 + count > MAX_LISTED {
                        return Err(format!(
                            "{item:?}: names {count} frames; a contact sheet shows at most \
                             {MAX_LISTED}"
                        ));
                    }
                    frames.extend((first..=last).step_by(step as usize));
                }
            }
        }
        Ok(Self(frames))
    }
}

/// The meshes of one frame, read from files.
pub struct Loaded {
    /// The frame number.
    pub frame: u32,
    /// The cloth.
    pub cloth: PolyMesh,
    /// The body, when there is one.
    pub body: Option<PolyMesh>,
}

/// The frame numbers of the cloth files in `dir`, ascending.
///
/// # Errors
/// When `dir` cannot be listed.
pub fn available(dir: &Path) -> Result<Vec<u32>> {
    cloth(dir).frames()
}

fn cloth(dir: &Path) -> Pattern {
    Pattern::parse(&dir.join(CLOTH)).expect("the cloth pattern has a #")
}

/// The frames to show: `list` when given (each must exist in `available`), otherwise all of
/// `available` when they are few, else [`DEFAULT_COUNT`] of them evenly spaced from the first to
/// the last.
///
/// # Errors
/// When `available` is empty or `list` names a frame that is not there.
pub fn choose(dir: &Path, available: &[u32], list: Option<&FrameList>) -> Result<Vec<u32>> {
    let Some((&first, &last)) = available.first().zip(available.last()) else {
        bail!("no frames: {} has no {CLOTH} files", dir.display());
    };
    let Some(FrameList(list)) = list else {
        let n = available.len();
        if n <= DEFAULT_COUNT {
            return Ok(available.to_vec());
        }
        let pick =
            |i: usize| available[(i * (n - 1) + (DEFAULT_COUNT - 1) / 2) / (DEFAULT_COUNT - 1)];
        return Ok((0..DEFAULT_COUNT).map(pick).collect());
    };
    if list.is_empty() {
        bail!("--frames names no frame");
    }
    if let Some(missing) = list.iter().find(|f| available.binary_search(f).is_err()) {
        bail!(
            "no frame {missing} in {}: it has {} frames from {first} to {last}",
            dir.display(),
            available.len()
        );
    }
    Ok(list.clone())
}

/// Reads the cloth of each frame from `dir`, and its body from `body` (a file, or a pattern with
/// `#` for the frame number) or else from `dir`'s `body_####.obj` files when it has any.
///
/// # Errors
/// When a file cannot be read, or a body is missing for some frames but not others.
pub fn load(dir: &Path, frames: &[u32], body: Option<&Path>) -> Result<Vec<Loaded>> {
    let cloth = cloth(dir);
    let in_dir = Pattern::parse(&dir.join(BODY)).expect("the body pattern has a #");
    let pattern = match body {
        Some(path) => Pattern::parse(path),
        None => (!in_dir.frames()?.is_empty()).then_some(in_dir),
    };
    let body_path = |frame| match (&pattern, body) {
        (Some(pattern), _) => Some(pattern.path(frame)),
        (None, file) => file.map(Path::to_path_buf),
    };
    frames
        .par_iter()
        .map(|&frame| {
            let body = match body_path(frame) {
                Some(path) if body.is_none() && !path.exists() => bail!(
                    "{} has {BODY} files but none for frame {frame}: {} is missing",
                    dir.display(),
                    path.display()
                ),
                Some(path) => Some(polymesh_obj::read(&path)?),
                None => None,
            };
            Ok(Loaded {
                frame,
                cloth: polymesh_obj::read(&cloth.path(frame))?,
                body,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn list(text: &str) -> Result<Vec<u32>, String> {
        text.parse::<FrameList>().map(|l| l.0)
    }

    #[test]
    fn parses_lists_ranges_and_steps() {
        assert_eq!(list("7"), Ok(vec![7]));
        assert_eq!(list("0,30, 60"), Ok(vec![0, 30, 60]));
        assert_eq!(list("3-6"), Ok(vec![3, 4, 5, 6]));
        assert_eq!(list("0-120x30,5"), Ok(vec![0, 30, 60, 90, 120, 5]));
        assert_eq!(list("0-10x4"), Ok(vec![0, 4, 8]));
        assert_eq!(list("0-9999").map(|l| l.len()), Ok(10_000));
        for bad in [
            "",
            "a",
            "5-3",
            "0-10x0",
            "4x2",
            "-3",
            "1,,2",
            "0-4294967295",
            "0-10000",
        ] {
            assert!(list(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn default_choice_spreads_from_first_to_last() {
        let dir = Path::new("out");
        let few: Vec<u32> = (0..5).collect();
        assert_eq!(choose(dir, &few, None).unwrap(), few);
        let many: Vec<u32> = (0..=120).collect();
        let picked = choose(dir, &many, None).unwrap();
        assert_eq!(picked.len(), DEFAULT_COUNT);
        assert_eq!((picked[0], picked[11]), (0, 120));
        assert_eq!(picked[1], 11);
        assert!(choose(dir, &[], None).is_err());
    }

    #[test]
    fn listed_frames_must_exist() {
        let dir = Path::new("out");
        let err = choose(dir, &[0, 1, 2], Some(&FrameList(vec![1, 5]))).unwrap_err();
        assert_eq!(
            err.to_string(),
            "no frame 5 in out: it has 3 frames from 0 to 2"
        );
    }
}
