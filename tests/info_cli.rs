//! `tailor info` speaks to a person: coordinates with six significant digits, options by the
//! names of the flags that set them.

use common::{shape, tailor};

mod common;

#[test]
fn info_prints_readable_coordinates_and_option_names() {
    let out = tailor(&["info", &shape("catmark_cube.obj")]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The file gives ±1.414214 in x and y: six significant digits, the same decimals for all.
    assert!(
        stdout.contains(
            "  bounding box     [-1.41421, -1.41421, -1.00000] .. [1.41421, 1.41421, 1.00000]\n"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "  options          boundary edge-only, creases uniform, triangles catmark, \
             fvar-linear none\n"
        ),
        "{stdout}"
    );
}
