//! STL files load like the other meshes: the bunny written as binary and as ASCII STL welds
//! into the same mesh as the bunny's glTF, and renders from the command line.

mod common;

use std::path::Path;
use std::process::Command;

use patchwork::io::{self, Model, mesh::TriMesh};

fn bunny() -> TriMesh {
    match io::read(&common::root().join("models/bunny.glb")) {
        Ok(Model::Mesh(m)) => m,
        other => panic!("the bunny should read as a mesh: {other:?}"),
    }
}

fn write_binary(mesh: &TriMesh, path: &Path) {
    let mut out = vec![b' '; 80];
    out.extend((mesh.triangles.len() as u32).to_le_bytes());
    for t in &mesh.triangles {
        out.extend([0u8; 12]);
        for &i in t {
            for c in mesh.positions[i as usize].to_array() {
                out.extend(c.to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    std::fs::write(path, out).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn write_ascii(mesh: &TriMesh, path: &Path) {
    let mut out = String::from("solid bunny\n");
    for t in &mesh.triangles {
        out.push_str(" facet normal 0 0 0\n  outer loop\n");
        for &i in t {
            let p = mesh.positions[i as usize];
            // `{:?}` prints the shortest text that reads back as the same f32.
            out.push_str(&format!("   vertex {:?} {:?} {:?}\n", p.x, p.y, p.z));
        }
        out.push_str("  endloop\n endfacet\n");
    }
    out.push_str("endsolid bunny\n");
    std::fs::write(path, out).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

#[test]
fn binary_and_ascii_stl_load_as_the_gltf_does() {
    let dir = common::scratch("stl");
    let mesh = bunny();
    let (bin, asc) = (dir.join("bunny-binary.stl"), dir.join("bunny-ascii.stl"));
    write_binary(&mesh, &bin);
    write_ascii(&mesh, &asc);
    // STL has no normals: welded like the glTF without its normals (creases computed).
    let mut welded = mesh.clone();
    welded.normals.clear();
    welded.weld();
    for path in [&bin, &asc] {
        let Ok(Model::Mesh(mut m)) = io::read(path) else {
            panic!("{} should read as a mesh", path.display());
        };
        assert_eq!(
            m.triangles.len(),
            mesh.triangles.len(),
            "{}",
            path.display()
        );
        // Three corners per facet in the file; welded, the glTF's shared vertices again.
        assert_eq!(m.positions.len(), 3 * mesh.triangles.len());
        m.weld();
        assert_eq!(m.positions, welded.positions, "{}", path.display());
        assert_eq!(m.triangles, welded.triangles, "{}", path.display());
        assert_eq!(m.normals, welded.normals, "{}", path.display());
    }
    let png = dir.join("bunny-stl.png");
    let _ = std::fs::remove_file(&png);
    let o = Command::new(env!("CARGO_BIN_EXE_patchwork"))
        .args(["render"])
        .arg(&bin)
        .args(["--size", "160x120", "-o"])
        .arg(&png)
        .output()
        .expect("the patchwork binary runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(png.is_file());
}
