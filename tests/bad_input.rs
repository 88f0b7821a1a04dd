//! Issue 21's bad-input policy: a model with nothing drawable — every triangle without area
//! (collinear or coinciding corners) in OBJ, PLY, STL or glTF — is an error naming the file
//! (exit 2), not a blank image; a `.bpt` coordinate beyond ±1e19 (1e308 here) is an error
//! naming its line, not a million-triangle tessellation of an unframeable model.

mod common;

use std::path::PathBuf;
use std::process::Command;

use patchwork::io::{self, LoadError};

fn bad(name: &str) -> PathBuf {
    common::root().join("tests/data/bad").join(name)
}

#[test]
fn meshes_without_area_are_errors_naming_the_file() {
    for name in [
        "collinear.obj",
        "zero_area.ply",
        "zero_area.stl",
        "zero_area.gltf",
    ] {
        let e = io::read(&bad(name)).expect_err(name);
        assert!(matches!(e, LoadError::NoFaces { .. }), "{name}: {e}");
        let msg = e.to_string();
        assert!(
            msg.contains(name) && msg.contains("zero area"),
            "{name}: {msg}"
        );
    }
}

#[test]
fn a_mesh_with_one_real_triangle_is_drawable() {
    // The control: collinear.obj plus one triangle with an area loads.
    let dir = common::scratch("bad-input");
    let path = dir.join("one_real.obj");
    let mut text = std::fs::read_to_string(bad("collinear.obj")).expect("fixture");
    text.push_str("v 0 1 0\nf 1 2 6\n");
    std::fs::write(&path, text).expect("write");
    io::read(&path).expect("one triangle with an area is enough");
}

#[test]
fn huge_bpt_coordinates_are_an_error_with_the_line() {
    let e = io::read(&bad("huge_coordinate.bpt")).expect_err("1e308");
    assert!(matches!(e, LoadError::Patch { .. }), "{e}");
    assert_eq!(e.line(), Some(4), "{e}");
    assert!(e.to_string().contains("beyond"), "{e}");
}

#[test]
fn the_cli_exits_2_and_writes_nothing() {
    for name in [
        "collinear.obj",
        "zero_area.ply",
        "zero_area.stl",
        "zero_area.gltf",
        "huge_coordinate.bpt",
    ] {
        let out = common::scratch("bad-input").join("out.png");
        let _ = std::fs::remove_file(&out);
        let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
            .args(["render"])
            .arg(bad(name))
            .arg("-o")
            .arg(&out)
            .args(["--size", "32x24"])
            .output()
            .expect("runs");
        let msg = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {msg}");
        assert!(msg.contains(name), "{name}: {msg}");
        assert!(!out.exists(), "{name}: wrote an image");
    }
}
