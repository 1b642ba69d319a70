//! The crate against OpenSubdiv 3.6.0's own output, on the subset of reference files carried in
//! `tests/data/opensubdiv` (the full set lives in `../shared`; see the conformance example).
//! Every refined vertex, face, UV, limit point and normal must match in OpenSubdiv's order.

use std::path::Path;

#[test]
fn refined_limit_and_face_varying_results_match_opensubdiv() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/opensubdiv");
    let checked = tailor_subdiv::conformance::run(&dir);
    let face_varying = checked
        .iter()
        .filter(|o| o.name.starts_with("facevarying"))
        .count();
    assert!(
        checked.len() >= 60 && face_varying >= 12,
        "reference subset missing: {} files, {face_varying} face-varying",
        checked.len()
    );
    let failures: Vec<String> = checked
        .iter()
        .filter(|o| o.failure.is_some())
        .map(ToString::to_string)
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
