//! Every way an OBJ file can be wrong gives an error naming the file, the exact line and the
//! problem, and no input (truncated or garbled real shapes included) makes the reader panic.

use std::path::{Path, PathBuf};

use tailor_subdiv::MeshError;
use tailor_subdiv::obj::{ObjError, Problem, parse, read};

/// A unit square's four vertices, lines 1-4.
const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

/// The line and problem of a parse that must fail on a line.
fn at(text: &str) -> (usize, Problem) {
    match parse(text, "test.obj") {
        Err(ObjError::At {
            file,
            line,
            problem,
        }) => {
            assert_eq!(file, "test.obj");
            (line, problem)
        }
        other => panic!("expected a line error, got {other:?}"),
    }
}

fn square_with(rest: &str) -> String {
    format!("{SQUARE}{rest}")
}

#[test]
fn malformed_numbers() {
    let token = |t: &str| Problem::MalformedNumber {
        token: t.to_owned(),
    };
    assert_eq!(at("v 0 0 0\nv 1 x 0\n"), (2, token("x")));
    assert_eq!(at("v 0 0 0\n\n# c\nvt 0.5 1..0\n"), (4, token("1..0")));
    assert_eq!(at("vn 0 0 1,0\n"), (1, token("1,0")));
    assert_eq!(at(&square_with("f 1 2 3a\n")), (5, token("3a")));
    assert_eq!(
        at(&square_with("t crease 2/1/0 0 1 sharp\n")),
        (5, token("sharp"))
    );
    assert_eq!(
        at(&square_with("t corner 1/1/0 1.5 2\n")),
        (5, token("1.5"))
    );
}

#[test]
fn wrong_arity() {
    assert_eq!(
        at("v 0 0 0\nv 1 2\n"),
        (
            2,
            Problem::Arity {
                statement: "v",
                expected: "3, 4 or 6 numbers",
                found: 2
            }
        )
    );
    assert_eq!(at("v 1 2 3 4 5\n").0, 1);
    assert_eq!(at("vt\n").0, 1);
    assert_eq!(at("vn 0 1\n").0, 1);
}

#[test]
fn non_finite_coordinates() {
    let nf = |t: &str| Problem::NonFinite {
        token: t.to_owned(),
    };
    assert_eq!(at("v 0 0 0\nv 0 NaN 0\n"), (2, nf("NaN")));
    assert_eq!(at("v 0 0 inf\n"), (1, nf("inf")));
    assert_eq!(at(&square_with("vt -infinity 0\n")), (5, nf("-infinity")));
    assert_eq!(at("vn 0 0 1e999\n"), (1, nf("1e999")));
}

#[test]
fn indices_out_of_range() {
    let out = |kind, index, count| Problem::IndexOutOfRange { kind, index, count };
    assert_eq!(
        at(&square_with("f 1 2 3\nf 0 1 2\n")),
        (6, Problem::IndexZero { kind: "vertex" })
    );
    assert_eq!(at(&square_with("f 1 2 5\n")), (5, out("vertex", 5, 4)));
    assert_eq!(at(&square_with("f -1 -2 -5\n")), (5, out("vertex", -5, 4)));
    // Indices name elements defined above the face, not below it.
    assert_eq!(
        at("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 1 1 0\n"),
        (2, out("vertex", 2, 1))
    );
    let uv = square_with("vt 0 0\nvt 1 0\nf 1/1 2/2 3/3\n");
    assert_eq!(at(&uv), (7, out("texture coordinate", 3, 2)));
    assert_eq!(
        at(&square_with("vt 0 0\nf 1/0 2/1 3/1\n")),
        (
            6,
            Problem::IndexZero {
                kind: "texture coordinate"
            }
        )
    );
    assert_eq!(
        at(&square_with("vn 0 0 1\nf 1//1 2//2 3//1\n")),
        (6, out("normal", 2, 1))
    );
    assert_eq!(
        at(&square_with("f 1//1 2//1 3//1\n")),
        (5, out("normal", 1, 0))
    );
}

#[test]
fn malformed_corners() {
    for corner in ["1/1/1/1", "1/", "/1", "1//", "//", "1/1/"] {
        let text = square_with(&format!("vt 0 0\nvn 0 0 1\nf 2 3 {corner}\n"));
        assert_eq!(
            at(&text),
            (
                7,
                Problem::MalformedCorner {
                    token: corner.to_owned()
                }
            ),
            "{corner}"
        );
    }
}

#[test]
fn bad_faces_are_mapped_to_their_lines() {
    assert_eq!(
        at(&square_with("f 1 2 3\n\nf 1 2\n")),
        (
            7,
            Problem::Mesh(MeshError::TooFewVertices {
                face: 1,
                corners: 2
            })
        )
    );
    assert_eq!(
        at(&square_with("# a comment\r\nf 1 2 3 4\r\nf 1 2 -4 3\r\n")),
        (
            7,
            Problem::Mesh(MeshError::RepeatedVertex { face: 1, vertex: 0 })
        )
    );
    assert_eq!(
        at(&square_with("f 1 2 3\nf\n")),
        (
            6,
            Problem::Mesh(MeshError::TooFewVertices {
                face: 1,
                corners: 0
            })
        )
    );
}

#[test]
fn uvs_on_some_faces_only() {
    let text = square_with("vt 0 0\nf 1/1 2/1 3/1\nf 1 3 4\n");
    assert_eq!(
        at(&text),
        (
            7,
            Problem::UvsOnSomeFaces {
                has_uvs: false,
                first_line: 6
            }
        )
    );
    let text = square_with("vt 0 0\nf 1 2 3\ng x\nf 1/1 3/1 4/1\n");
    assert_eq!(
        at(&text),
        (
            8,
            Problem::UvsOnSomeFaces {
                has_uvs: true,
                first_line: 6
            }
        )
    );
    assert_eq!(
        at(&square_with("vt 0 0\nf 1/1 2 3/1\n")),
        (6, Problem::UvsOnSomeCorners)
    );
    let message = parse(&square_with("vt 0 0\nf 1/1 2/1 3/1\nf 1 3 4\n"), "a.obj").unwrap_err();
    assert_eq!(
        message.to_string(),
        "a.obj:7: this face has no texture coordinates but the face on line 6 has them"
    );
}

#[test]
fn bad_sharpness() {
    let text = square_with("f 1 2 3 4\nt crease 2/1/0 0 1 1\nt crease 4/2/0 1 2 2 3 1 -0.5\n");
    assert_eq!(
        at(&text),
        (
            7,
            Problem::Mesh(MeshError::BadSharpness {
                tag: "crease",
                sharpness: -0.5
            })
        )
    );
    let text = square_with("f 1 2 3 4\nt corner 2/1/0 0 1 -2\n");
    assert_eq!(
        at(&text),
        (
            6,
            Problem::Mesh(MeshError::BadSharpness {
                tag: "corner",
                sharpness: -2.0
            })
        )
    );
    let (line, problem) = at(&square_with("f 1 2 3 4\nt corner 1/1/0 0 nan\n"));
    assert_eq!(line, 6);
    assert!(matches!(
        problem,
        Problem::Mesh(MeshError::BadSharpness { tag: "corner", .. })
    ));
}

#[test]
fn tags_naming_missing_elements() {
    let quad = "f 1 2 3 4\n";
    let missing = |tag, vertex| {
        Problem::Mesh(MeshError::TagVertexOutOfRange {
            tag,
            vertex,
            count: 4,
        })
    };
    let text = square_with(&format!(
        "{quad}t crease 2/1/0 0 1 1\n\nt crease 2/1/0 3 4 1\n"
    ));
    assert_eq!(at(&text), (8, missing("crease", 4)));
    let text = square_with(&format!("t corner 1/1/0 9 1\n{quad}"));
    assert_eq!(at(&text), (5, missing("corner", 9)));
    let text = square_with(&format!("{quad}t hole 2/0/0 0 1\n"));
    assert_eq!(
        at(&text),
        (
            6,
            Problem::Mesh(MeshError::HoleOutOfRange { face: 1, count: 1 })
        )
    );
    let text = square_with(&format!("{quad}t crease 2/1/0 0 -1 1\n"));
    assert_eq!(
        at(&text),
        (
            6,
            Problem::TagIndex {
                tag: "crease",
                kind: "vertex",
                index: -1
            }
        )
    );
    let text = square_with(&format!("{quad}t hole 1/0/0 -2\n"));
    assert_eq!(
        at(&text),
        (
            6,
            Problem::TagIndex {
                tag: "hole",
                kind: "face",
                index: -2
            }
        )
    );
}

#[test]
fn crease_on_vertices_without_an_edge() {
    let text = square_with("f 1 2 3 4\nt crease 4/1/0 0 1 0 2 3\n");
    assert_eq!(
        at(&text),
        (6, Problem::Mesh(MeshError::CreaseNotAnEdge(0, 2)))
    );
}

#[test]
fn bad_tags() {
    let quad = square_with("f 1 2 3 4\n");
    let tag = |t: &str| at(&format!("{quad}{t}\n"));
    let value = |tag, value: &str, expected| Problem::UnknownTagValue {
        tag,
        value: value.to_owned(),
        expected,
    };
    assert_eq!(
        tag("t interpolateboundary 1/0/0 3"),
        (6, value("interpolateboundary", "3", "0 1 2"))
    );
    assert_eq!(
        tag("t facevaryinginterpolateboundary 1/0/0 6"),
        (
            6,
            value("facevaryinginterpolateboundary", "6", "0 1 2 3 4 5")
        )
    );
    assert_eq!(
        tag("t creasemethod 0/0/1 uniform"),
        (6, value("creasemethod", "uniform", "normal chaikin"))
    );
    assert_eq!(
        tag("t smoothtriangles 0/0/1 loop"),
        (6, value("smoothtriangles", "loop", "catmark smooth"))
    );
    assert_eq!(
        tag("t sharpen 1/0/0 1"),
        (
            6,
            Problem::UnknownTag {
                name: "sharpen".to_owned()
            }
        )
    );
    assert_eq!(tag("t crease"), (6, Problem::TagHeader));
    assert_eq!(tag("t crease 2/1 0 1 1"), (6, Problem::TagHeader));
    assert_eq!(tag("t crease 2/1/0/0 0 1 1"), (6, Problem::TagHeader));
    assert_eq!(tag("t crease a/1/0 0 1 1"), (6, Problem::TagHeader));
    assert_eq!(
        tag("t crease 2/1/0 0 1"),
        (
            6,
            Problem::TagArgumentCount {
                tag: "crease".to_owned(),
                declared: 3,
                found: 2
            }
        )
    );
    assert_eq!(
        tag("t crease 3/1/0 0 1 2 1"),
        (
            6,
            Problem::TagShape {
                tag: "crease",
                expected: "2N/1/0 or 2N/N/0",
                counts: "3/1/0".to_owned()
            }
        )
    );
    assert!(matches!(
        tag("t crease 4/3/0 0 1 1 2 1 1 1").1,
        Problem::TagShape { .. }
    ));
    assert!(matches!(
        tag("t corner 2/3/0 0 1 1 1 1").1,
        Problem::TagShape { .. }
    ));
    assert!(matches!(
        tag("t hole 1/1/0 0 1").1,
        Problem::TagShape { .. }
    ));
    assert!(matches!(
        tag("t interpolateboundary 0/0/1 edge").1,
        Problem::TagShape { .. }
    ));
}

#[test]
fn unknown_statements() {
    assert_eq!(
        at(&square_with("cstype bspline\ncurv 0 1 1 2\n")),
        (
            5,
            Problem::UnknownStatement {
                keyword: "cstype".to_owned()
            }
        )
    );
}

#[test]
fn empty_mesh() {
    for text in ["", "# nothing\n", SQUARE, "v 0 0 0\nl 1 1\np 1\n"] {
        match parse(text, "e.obj") {
            Err(
                e @ ObjError::Mesh {
                    error: MeshError::Empty,
                    ..
                },
            ) => {
                assert_eq!(e.line(), None);
                assert_eq!(e.to_string(), "e.obj: the mesh has no faces");
            }
            other => panic!("expected an empty-mesh error, got {other:?}"),
        }
    }
}

#[test]
fn io_error_names_the_file() {
    let err = read(Path::new("/nonexistent/dir/shape.obj")).unwrap_err();
    assert!(matches!(err, ObjError::Io { .. }));
    assert!(
        err.to_string().starts_with("/nonexistent/dir/shape.obj: "),
        "{err}"
    );
}

#[test]
fn message_names_file_line_and_problem() {
    let err = parse(&square_with("f 1 2 9\n"), "<stdin>").unwrap_err();
    assert_eq!(err.line(), Some(5));
    assert_eq!(
        err.to_string(),
        "<stdin>:5: vertex index 9 is out of range: 4 defined so far"
    );
}

/// A small shape with every kind of line, used when the reference shapes are absent.
const TAGGED: &str = "\
# cube with tags
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v -0.5 0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
vt 0.375 0
vt 0.625 0
vt 0.375 0.25
vt 0.625 0.25
vn 0 0 1
g cube top
s off
f 1/1/1 2/2/1 4/4/1 3/3/1
f 3/3 4/4 6/2 5/1
f 5/1 6/2 8/4 7/3
f 7/3 8/4 2/2 1/1
f 2/2 8/4 6/2 4/4
f -2/1 -8/3 -6/4 -4/2
t crease 4/2/0 0 1 1 3 2.5 10
t corner 1/1/0 7 3
t hole 1/0/0 5
t interpolateboundary 1/0/0 1
t creasemethod 0/0/1 chaikin
";

fn reference_shapes() -> Option<PathBuf> {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/reference/opensubdiv/shapes");
    dir.is_dir().then_some(dir)
}

/// Texts to torture: the inline shape and, when present, two reference shapes with tags.
fn victims() -> Vec<String> {
    let mut texts = vec![TAGGED.to_owned()];
    match reference_shapes() {
        Some(dir) => {
            for name in ["catmark_cube_creases1.obj", "catmark_fvar_bound2.obj"] {
                texts.push(std::fs::read_to_string(dir.join(name)).unwrap());
            }
        }
        None => println!(
            "note: ../shared/reference/opensubdiv/shapes absent; garbling the inline shape only"
        ),
    }
    texts
}

#[test]
fn truncated_and_garbled_input_errs_without_panicking() {
    let lines = |t: &str| t.lines().count();
    for text in victims() {
        assert!(parse(&text, "whole").is_ok());
        // Every truncation: a cut inside a line leaves a malformed or shortened statement.
        let mut errors = 0;
        for cut in (0..text.len()).filter(|&i| text.is_char_boundary(i)) {
            if let Err(e) = parse(&text[..cut], "cut") {
                errors += 1;
                assert!(e.line().is_none_or(|l| l <= lines(&text)));
            }
        }
        assert!(errors > 0);
        // Garbling: overwrite single characters with troublesome ones (deterministic LCG).
        let garbage = [
            "/",
            "-",
            "0",
            "x",
            " ",
            "\n",
            "#",
            "9999999999999999999999",
            "-1",
            "nan",
            "t",
            "f",
        ];
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for _ in 0..4000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let at = (state >> 33) as usize % text.len();
            if !text.is_char_boundary(at) || !text.is_char_boundary(at + 1) {
                continue;
            }
            let junk = garbage[(state >> 20) as usize % garbage.len()];
            let garbled = format!("{}{junk}{}", &text[..at], &text[at + 1..]);
            // Ok or Err are both possible (an overwritten comment is harmless); a panic fails.
            let _ = parse(&garbled, "garbled");
        }
    }
    // Specific corruptions of a real line must be errors at that line.
    let text = TAGGED.replace("f 5/1 6/2 8/4 7/3", "f 5/1 6/2 8/0 7/3");
    assert_eq!(parse(&text, "x").unwrap_err().line(), Some(19));
    let text = TAGGED.replace("v 0.5 0.5 -0.5", "v 0.5 0.5");
    assert_eq!(parse(&text, "x").unwrap_err().line(), Some(7));
}

/// A grid of `n` × `n` quads as OBJ text: vertex lines, then face lines.
fn grid_text(n: usize) -> String {
    let mut text = String::new();
    for j in 0..=n {
        for i in 0..=n {
            text += &format!("v {} {} 0.{}\n", i, j, (i * 7919 + j) % 1000);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            text += &format!("f {a} {} {} {}\n", a + 1, a + n + 2, a + n + 1);
        }
    }
    text
}

/// A file of megabytes is parsed in parallel chunks; an error far into it, in a chunk
/// parsed before the ones ahead of it were joined, still names its own line, and the first
/// of two errors is the one reported.
#[test]
fn errors_far_into_a_large_file_name_their_line() {
    let n = 300;
    let text = grid_text(n);
    assert!(text.len() > 2 << 20, "{} bytes: too few chunks", text.len());
    let lines: Vec<&str> = text.lines().collect();
    let vertices = (n + 1) * (n + 1);
    let doc = parse(&text, "test.obj").unwrap();
    assert_eq!(doc.mesh.face_count(), n * n);
    let z: f64 = format!("0.{}", (n * 7919 + n) % 1000).parse().unwrap();
    assert_eq!(doc.mesh.positions()[vertices - 1].z, z);

    let with = |edits: &[(usize, &str)]| {
        let mut lines = lines.clone();
        for &(k, line) in edits {
            lines[k] = line;
        }
        lines.join("\n") + "\n"
    };
    let last = lines.len() - 1;
    let out_of_range = format!("f 1 2 {} 3", vertices + 1);
    assert_eq!(
        at(&with(&[(last, &out_of_range)])),
        (
            last + 1,
            Problem::IndexOutOfRange {
                kind: "vertex",
                index: i64::try_from(vertices + 1).unwrap(),
                count: vertices,
            }
        )
    );
    let bad_number = Problem::MalformedNumber {
        token: "x".to_owned(),
    };
    assert_eq!(
        at(&with(&[(last - 5, "v 1 x 0")])),
        (last - 4, bad_number.clone())
    );
    // Two errors: the earlier line's wins, whichever chunk finds its own first.
    let early = vertices + 10;
    assert_eq!(
        at(&with(&[(early, "f 1 2 0"), (last, "v 1 x 0")])),
        (early + 1, Problem::IndexZero { kind: "vertex" })
    );
    assert_eq!(
        at(&with(&[(early, "v 1 x 0"), (last, &out_of_range)])).0,
        early + 1
    );
}
