//! The end-of-run summary: time per frame, the worst edge strain, and what `tailor check`'s
//! test finds (body penetrations, self-intersections), for standard output and as
//! `summary.json` in the output directory, with the frames that failed their quality
//! ([`super::quality`]) under `failures`.

use std::path::Path;

use anyhow::Result;
use serde_json::json;

use crate::checkpoint::FrameStats;
use crate::output::write_atomically;

use super::quality::{self, Failure};

/// The summary's file name.
pub const FILE: &str = "summary.json";

/// Writes `summary.json` of `stats` (every frame simulated so far), `failures` the frames
/// that failed their quality, and returns the summary's lines for standard output.
///
/// # Errors
/// When `summary.json` cannot be written.
pub fn report(
    scene: &Path,
    dir: &Path,
    thickness: f64,
    stats: &[FrameStats],
    failures: &[Failure],
) -> Result<String> {
    let stepped: Vec<&FrameStats> = stats.iter().filter(|s| s.frame > 0).collect();
    // From +0, not `sum()`'s −0, so that a run of no steps took 0.0 s, not −0.0 s.
    let total_ms = stepped.iter().fold(0.0, |total, s| total + s.ms);
    let mean_ms = total_ms / stepped.len().max(1) as f64;
    let worst = stats
        .iter()
        .max_by(|a, b| a.max_strain.total_cmp(&b.max_strain))
        .copied()
        .unwrap_or_default();
    let penetrating: usize = stats.iter().map(|s| s.findings.penetrating_vertices).sum();
    let deepest = stats
        .iter()
        .map(|s| s.findings.max_penetration)
        .fold(0.0, f64::max);
    let crossing: usize = stats
        .iter()
        .map(|s| s.findings.self_intersecting_pairs)
        .sum();
    let dirty = stats.iter().filter(|s| !s.findings.is_clean()).count();
    let deepest_mm = deepest * 1e3;
    let frames: Vec<_> = stats
        .iter()
        .map(|s| {
            let mut row = s.findings.json();
            row["frame"] = json!(s.frame);
            row["ms"] = json!(s.ms);
            row["max_strain"] = json!(s.max_strain);
            row["strained_edge"] = json!(s.strained_edge);
            row["substeps"] = json!(s.substeps);
            row["cg_iterations"] = json!(s.cg_iterations);
            row
        })
        .collect();
    let summary = json!({
        "scene": scene.display().to_string(),
        "thickness": thickness,
        "frames": frames,
        "total": {
            "frames_simulated": stepped.len(),
            "ms": total_ms,
            "ms_per_frame": mean_ms,
            "max_strain": worst.max_strain,
            "max_strain_frame": worst.frame,
            "penetrating_vertices": penetrating,
            "max_penetration": deepest,
            "self_intersecting_pairs": crossing,
            "frames_not_clean": dirty,
        },
        "failures": quality::json(failures),
    });
    let text = serde_json::to_string_pretty(&summary)? + "\n";
    let path = dir.join(FILE);
    write_atomically(&path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    Ok(format!(
        "{}: {} frames simulated in {:.1} s ({mean_ms:.0} ms per frame)\n\
         worst edge strain {:.2}% (frame {})\n\
         tailor check (thickness {thickness} m): {penetrating} penetrating vertices (deepest \
         {deepest_mm:.2} mm), {crossing} self-intersecting face pairs, {dirty} of {} frames not \
         clean\n\
         summary: {}\n",
        scene.display(),
        stepped.len(),
        total_ms / 1e3,
        worst.max_strain * 100.0,
        worst.frame,
        stats.len(),
        path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run that only writes its rest pose (`--frames 0` or `[scene] frames = 0`) says it
    /// took 0.0 s, not the −0.0 s of an empty floating-point sum.
    #[test]
    fn a_run_of_no_steps_took_no_time() {
        let dir = std::env::temp_dir().join(format!("tailor-summary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rest = [FrameStats::default()];
        let text = report(Path::new("scene.toml"), &dir, 0.005, &rest, &[]).unwrap();
        assert!(
            text.starts_with("scene.toml: 0 frames simulated in 0.0 s (0 ms per frame)\n"),
            "{text}"
        );
        let written: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(FILE)).unwrap()).unwrap();
        let total = written["total"]["ms"].as_f64().unwrap();
        assert!(total == 0.0 && total.is_sign_positive(), "{total}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
