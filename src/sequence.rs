//! Frame sequences named by a pattern: `cloth_####.obj` stands for `cloth_0001.obj`,
//! `cloth_0002.obj`, … where the run of `#` is the frame number zero-padded to its length
//! (longer numbers keep all their digits, as Maya and Houdini write them).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// A file name pattern with one run of `#` for the frame number.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    dir: PathBuf,
    prefix: String,
    width: usize,
    suffix: String,
}

impl Pattern {
    /// The pattern in `path`'s file name, or `None` when the name has no `#`.
    #[must_use]
    pub fn parse(path: &Path) -> Option<Self> {
        let name = path.file_name()?.to_str()?;
        let start = name.find('#')?;
        let width = name[start..]
            .find(|c| c != '#')
            .unwrap_or(name.len() - start);
        let dir = path.parent().map_or_else(PathBuf::new, Path::to_path_buf);
        Some(Self {
            dir,
            prefix: name[..start].to_owned(),
            width,
            suffix: name[start + width..].to_owned(),
        })
    }

    /// The path of frame `frame`.
    #[must_use]
    pub fn path(&self, frame: u32) -> PathBuf {
        let name = format!(
            "{}{frame:0width$}{}",
            self.prefix,
            self.suffix,
            width = self.width
        );
        self.dir.join(name)
    }

    /// The frame numbers whose files exist in the pattern's directory, ascending.
    ///
    /// # Errors
    /// When the directory cannot be listed.
    pub fn frames(&self) -> Result<Vec<u32>> {
        let dir = if self.dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &self.dir
        };
        let entries = fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?;
        let mut frames = Vec::new();
        for entry in entries {
            let entry = entry.with_context(|| format!("listing {}", dir.display()))?;
            if let Some(frame) = entry.file_name().to_str().and_then(|n| self.frame_of(n)) {
                frames.push(frame);
            }
        }
        frames.sort_unstable();
        Ok(frames)
    }

    /// Whether a file name (no directory) is one of the pattern's frames.
    #[must_use]
    pub fn matches(&self, name: &str) -> bool {
        self.frame_of(name).is_some()
    }

    /// The frame number a file name stands for under this pattern.
    fn frame_of(&self, name: &str) -> Option<u32> {
        let digits = name
            .strip_prefix(&self.prefix)?
            .strip_suffix(&self.suffix)?;
        let all_digits = !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit());
        let padded =
            digits.len() == self.width || (digits.len() > self.width && !digits.starts_with('0'));
        (all_digits && padded)
            .then(|| digits.parse().ok())
            .flatten()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pads_frame_numbers() {
        let p = Pattern::parse(Path::new("out/cloth_####.obj")).unwrap();
        assert_eq!(p.path(7), Path::new("out/cloth_0007.obj"));
        assert_eq!(p.path(12345), Path::new("out/cloth_12345.obj"));
        assert_eq!(Pattern::parse(Path::new("cloth.obj")), None);
        assert_eq!(
            Pattern::parse(Path::new("#")).unwrap().path(3),
            Path::new("3")
        );
    }

    #[test]
    fn recognises_its_own_names_only() {
        let p = Pattern::parse(Path::new("cloth_##.obj")).unwrap();
        assert_eq!(p.frame_of("cloth_07.obj"), Some(7));
        assert_eq!(p.frame_of("cloth_123.obj"), Some(123));
        for other in [
            "cloth_7.obj",
            "cloth_007.obj",
            "cloth_0a.obj",
            "body_07.obj",
            "cloth_07.obj.bak",
        ] {
            assert_eq!(p.frame_of(other), None, "{other}");
        }
    }

    #[test]
    fn lists_existing_frames() {
        let dir = std::env::temp_dir().join(format!("tailor-sequence-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        for name in ["f_0003.obj", "f_0001.obj", "f_01.obj", "g_0002.obj"] {
            fs::write(dir.join(name), "").unwrap();
        }
        let frames = Pattern::parse(&dir.join("f_####.obj")).unwrap().frames();
        fs::remove_dir_all(&dir).unwrap();
        assert_eq!(frames.unwrap(), vec![1, 3]);
    }
}
