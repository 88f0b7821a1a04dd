//! Hostile glTF files (issue 21): cycles in the node graph, buffers outside the file's folder,
//! accessor and index values past what the gltf crates check, and a GLB header asking for
//! 4 GiB are typed errors naming the file — no panic, no hang, no file read outside the
//! model's folder — while a relative buffer beside the file still loads.

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The one-triangle glTF of `tests/data/mesh/index_out_of_range.gltf` with its index fixed.
fn triangle() -> String {
    let path = common::root().join("tests/data/mesh/index_out_of_range.gltf");
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        // Indices 0 1 5 → 0 1 2 (the last bytes 00 00 05 → 00 00 02 of the base64 buffer).
        .replace("AAEAAAAFAAAA\"", "AAEAAAACAAAA\"")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    path
}

fn refused(path: &Path, why: &str) {
    let t0 = Instant::now();
    let msg = match patchwork::io::read(path) {
        Ok(_) => panic!("{}: loaded", path.display()),
        Err(e) => e.to_string(),
    };
    assert!(
        t0.elapsed() < Duration::from_secs(10),
        "{}: too slow",
        path.display()
    );
    assert!(msg.contains(&path.display().to_string()), "{msg}");
    assert!(msg.contains(why), "{}: {msg}", path.display());
}

#[test]
fn the_fixed_triangle_loads() {
    let dir = common::scratch("gltf-hostile");
    let ok = write(&dir, "ok.gltf", triangle().as_bytes());
    assert!(patchwork::io::read(&ok).is_ok());
}

#[test]
fn node_cycles_are_errors() {
    let dir = common::scratch("gltf-hostile");
    let tri = triangle();
    let nodes = "\"nodes\": [\n  {\n   \"mesh\": 0\n  }\n ]";
    assert!(tri.contains(nodes));
    for (name, graph) in [
        ("self.gltf", r#""nodes": [{"mesh": 0, "children": [0]}]"#),
        (
            "loop.gltf",
            r#""nodes": [{"mesh": 0, "children": [1]}, {"children": [0]}]"#,
        ),
    ] {
        let path = write(&dir, name, tri.replace(nodes, graph).as_bytes());
        refused(&path, "is reached twice");
    }
}

#[test]
fn buffers_outside_the_folder_are_not_read() {
    let dir = common::scratch("gltf-hostile");
    let tri = triangle();
    let start = tri.find("data:").expect("a data URI");
    let end = start + tri[start..].find('"').expect("end of the URI");
    let bin = &tri[start..end];
    for (k, uri) in [
        "/etc/passwd",
        "../../../../../../etc/passwd",
        "file:///etc/passwd",
        "%2e%2e/%2e%2e/%2e%2e/etc/passwd",
        "C:\\\\Windows\\\\win.ini",
    ]
    .iter()
    .enumerate()
    {
        let path = write(
            &dir,
            &format!("uri{k}.gltf"),
            tri.replace(bin, uri).as_bytes(),
        );
        refused(&path, "points outside the file's folder");
    }
    // A relative buffer next to the file is fine.
    let data = base64_decode(bin.rsplit(',').next().expect("base64"));
    write(&dir, "tri.bin", &data);
    let rel = write(
        &dir,
        "relative.gltf",
        tri.replace(bin, "tri.bin").as_bytes(),
    );
    assert!(patchwork::io::read(&rel).is_ok());
}

#[test]
fn values_past_the_crates_checks_are_errors() {
    let dir = common::scratch("gltf-hostile");
    let tri = triangle();
    for (name, from, to) in [
        ("accessor.gltf", "\"POSITION\": 0", "\"POSITION\": 7"),
        ("indices.gltf", "\"indices\": 1", "\"indices\": 4294967296"),
    ] {
        assert!(tri.contains(from));
        let path = write(&dir, name, tri.replace(from, to).as_bytes());
        refused(&path, "not a valid glTF");
    }
}

#[test]
fn a_glb_header_cannot_ask_for_more_than_the_file() {
    let dir = common::scratch("gltf-hostile");
    let json = triangle();
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(u32::MAX.to_le_bytes());
    let mut chunk = json.into_bytes();
    while !chunk.len().is_multiple_of(4) {
        chunk.push(b' ');
    }
    glb.extend((chunk.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(chunk);
    let path = write(&dir, "huge.glb", &glb);
    refused(&path, "not a valid glTF");
}

/// Standard base64 (the test's own decoder: the buffer of the triangle).
fn base64_decode(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let bytes: Vec<u8> = s.bytes().filter(|&c| c != b'=').map(val).collect();
    let mut out = Vec::new();
    for c in bytes.chunks(4) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &v)| n | (v as u32) << (18 - 6 * i));
        let k = c.len() * 6 / 8;
        out.extend(&n.to_be_bytes()[1..1 + k]);
    }
    out
}
