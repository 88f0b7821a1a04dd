//! The `.bpt` reader on bad inputs (fixtures in `tests/data/bad/`, one per failure), on the real
//! Utah teapot, and under fuzzing with proptest.

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use patchwork::io::LoadError;
use patchwork::io::bpt::parse;
use patchwork::model::UpAxis;
use patchwork::model::bezier::PatchError;
use patchwork::prep::load;
use proptest::prelude::*;

fn bad(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/bad")
        .join(name)
}

/// Loads a bad fixture, which must fail; checks the message names the file (and the line).
fn load_bad(name: &str, line: Option<usize>) -> LoadError {
    let err = match load(&bad(name)) {
        Ok(scene) => panic!("{name} loaded {} patches", scene.patches.len()),
        Err(err) => err,
    };
    let msg = err.to_string();
    let expected = match line {
        Some(line) => format!("{name}:{line}: "),
        None => format!("{name}: "),
    };
    assert!(
        msg.contains(&expected),
        "{msg:?} does not contain {expected:?}"
    );
    assert_eq!(err.line(), line, "{msg}");
    err
}

#[test]
fn too_few_control_points_is_unexpected_end_of_file() {
    let err = load_bad("too_few_points.bpt", Some(5));
    assert!(matches!(err, LoadError::Parse { line: 5, .. }), "{err:?}");
    assert!(err.to_string().contains("unexpected end of file"), "{err}");
    assert!(
        err.to_string().contains("control point 3 of patch 0"),
        "{err}"
    );
}

#[test]
fn too_few_patches_is_unexpected_end_of_file() {
    let err = load_bad("too_few_patches.bpt", Some(6));
    assert!(matches!(err, LoadError::Parse { .. }), "{err:?}");
    assert!(
        err.to_string()
            .contains("u degree of patch 1 (the file declares 2 patches)"),
        "{err}"
    );
}

#[test]
fn extra_control_point_is_reported_at_next_header() {
    let err = load_bad("extra_control_point.bpt", Some(7));
    assert!(matches!(err, LoadError::Parse { .. }), "{err:?}");
    assert!(
        err.to_string()
            .contains("does patch 0 have more than 4 control points"),
        "{err}"
    );
}

#[test]
fn trailing_tokens_are_rejected() {
    let err = load_bad("trailing_tokens.bpt", Some(8));
    assert!(matches!(err, LoadError::Parse { .. }), "{err:?}");
    assert!(
        err.to_string()
            .contains("unexpected \"extra\" after the last of the 1 patches"),
        "{err}"
    );
}

#[test]
fn non_number_names_the_coordinate_and_token() {
    let err = load_bad("not_a_number.bpt", Some(5));
    assert!(matches!(err, LoadError::Parse { .. }), "{err:?}");
    let expected = "not_a_number.bpt:5: expected a number for the y coordinate of control point 2 \
                    of patch 0, found \"abc\"";
    assert!(err.to_string().ends_with(expected), "{err}");
}

#[test]
fn nan_coordinate_is_non_finite_at_its_line() {
    let err = load_bad("nan_coordinate.bpt", Some(6));
    assert!(
        matches!(
            err,
            LoadError::Patch {
                patch: 0,
                source: PatchError::NonFinite { index: 3, .. },
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn inf_coordinate_is_non_finite_at_its_line() {
    let err = load_bad("inf_coordinate.bpt", Some(4));
    assert!(
        matches!(
            err,
            LoadError::Patch {
                patch: 0,
                source: PatchError::NonFinite { index: 1, .. },
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn zero_patches() {
    let err = load_bad("zero_patches.bpt", None);
    assert!(matches!(err, LoadError::NoPatches { .. }), "{err:?}");
}

#[test]
fn absurd_patch_count() {
    let err = load_bad("huge_patch_count.bpt", Some(1));
    assert!(matches!(err, LoadError::Parse { .. }), "{err:?}");
    assert!(err.to_string().contains("more than the limit"), "{err}");
}

#[test]
fn degree_above_15_is_reported_from_the_header() {
    let err = load_bad("degree_16.bpt", Some(2));
    assert!(
        matches!(
            err,
            LoadError::Patch {
                patch: 0,
                source: PatchError::DegreeTooHigh { du: 16, dv: 3 },
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn negative_degree() {
    let err = load_bad("negative_degree.bpt", Some(2));
    assert!(matches!(err, LoadError::Parse { .. }), "{err:?}");
    assert!(
        err.to_string()
            .contains("v degree of patch 0 must not be negative, found \"-1\""),
        "{err}"
    );
}

#[test]
fn empty_file() {
    let err = load_bad("empty.bpt", None);
    assert!(matches!(err, LoadError::Empty { .. }), "{err:?}");
}

#[test]
fn whitespace_only_file() {
    let err = load_bad("whitespace_only.bpt", None);
    assert!(matches!(err, LoadError::Empty { .. }), "{err:?}");
}

#[test]
fn binary_garbage_names_the_byte_offset() {
    let err = load_bad("binary_garbage.bpt", None);
    assert!(
        matches!(err, LoadError::NotText { offset: 6, .. }),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("NUL byte at byte offset 6"),
        "{err}"
    );
}

#[test]
fn invalid_utf8_names_the_byte_offset() {
    let err = parse(b"1\n1 1\n0 0 \xff 0\n", Path::new("x.bpt")).expect_err("not UTF-8");
    assert!(
        matches!(err, LoadError::NotText { offset: 10, .. }),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("invalid UTF-8 at byte offset 10"),
        "{err}"
    );
}

#[test]
fn missing_file_is_io_error() {
    let err = load_bad("does_not_exist.bpt", None);
    assert!(
        matches!(&err, LoadError::Io { source, .. } if source.kind() == ErrorKind::NotFound),
        "{err:?}"
    );
}

#[test]
fn unsupported_extension() {
    let err = load_bad("teapot.xyz", None);
    assert!(
        matches!(&err, LoadError::UnsupportedFormat { extension, .. } if extension == "xyz"),
        "{err:?}"
    );
    let err = load(Path::new("no_extension")).expect_err("no extension");
    assert!(
        matches!(&err, LoadError::UnsupportedFormat { extension, .. } if extension.is_empty()),
        "{err:?}"
    );
}

#[test]
fn extension_is_case_insensitive() {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bpt_reader_upper_case.BPT");
    std::fs::write(&path, "1\n1 1\n0 0 0\n0 1 0\n1 0 0\n1 1 1\n").expect("write temp file");
    let scene = load(&path).expect("valid file");
    assert_eq!(scene.patches.len(), 1);
}

#[test]
fn degenerate_patch_is_reported_at_its_header() {
    let err = load_bad("degenerate.bpt", Some(2));
    assert!(
        matches!(
            err,
            LoadError::Patch {
                patch: 0,
                source: PatchError::Degenerate,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn utah_teapot() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/teapot.bpt");
    let scene = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.patches.len(), 32);
    assert!(scene.patches.iter().all(|p| matches!(
        &p.surface,
        patchwork::model::PatchSurface::Bezier(b) if b.degree() == (3, 3)
    )));
    assert_eq!(scene.up, UpAxis::Z);
    assert!(
        (2.5..4.5).contains(&scene.bounds.radius),
        "radius {}",
        scene.bounds.radius
    );
}

/// A valid two-patch file, as tokens, for mutation.
const VALID: &str = "2\n3 1\n0 0 0\n0 1 0\n1 0 0\n1 1 1\n2 0 1\n2 1 0\n3 0 0\n3 1 1\n\
                     1 2\n0 0 0\n0 1 1\n0 2 0\n1 0 1\n1 1 0\n1 2 1\n";

/// Invariants of any result: errors name the file, and lines exist in the input.
fn check_result(bytes: &[u8], result: Result<Vec<patchwork::model::BezierPatch>, LoadError>) {
    if let Err(err) = result {
        assert!(err.to_string().starts_with("fuzz.bpt:"), "{err}");
        if let Some(line) = err.line() {
            let lines = bytes.split(|&b| b == b'\n').count();
            assert!((1..=lines).contains(&line), "line {line} of {lines}: {err}");
        }
    }
}

proptest! {
    #[test]
    fn parse_never_panics_on_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        check_result(&bytes, parse(&bytes, Path::new("fuzz.bpt")));
    }

    #[test]
    fn parse_never_panics_on_mutated_valid_file(
        index in any::<prop::sample::Index>(),
        replacement in prop_oneof![
            any::<String>(),
            "[-+]?[0-9]{1,25}",
            "[-+]?(nan|inf|NaN|Infinity|[0-9]*\\.[0-9]*e[-+]?[0-9]{1,4})",
            Just(String::new()),
            "[ \t\r\n]{1,3}",
        ],
    ) {
        let mut tokens: Vec<&str> = VALID.split_ascii_whitespace().collect();
        let i = index.index(tokens.len());
        tokens[i] = &replacement;
        let text = tokens.join("\n");
        check_result(text.as_bytes(), parse(text.as_bytes(), Path::new("fuzz.bpt")));
    }
}
