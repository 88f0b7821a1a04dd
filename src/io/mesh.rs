//! Triangle-mesh readers: glTF 2.0 (`.glb`, `.gltf`; every mesh primitive of every node in
//! the default scene, node transforms applied) with the `gltf` crate, and Wavefront OBJ with
//! `tobj`. The result is welded into one world-space [`TriMesh`] and split into patches
//! ([`crate::model::mesh::partition`]).

use std::path::Path;

use glam::{Mat4, Vec3};

use super::LoadError;
use crate::model::mesh::TriMesh;

/// Appends the triangles of a primitive, checking indices and positions.
fn append(
    path: &Path,
    what: &str,
    mesh: &mut TriMesh,
    positions: &[Vec3],
    indices: &[u32],
    transform: Mat4,
) -> Result<(), LoadError> {
    if !indices.len().is_multiple_of(3) {
        return Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!(
                "{what}: {} indices do not make whole triangles",
                indices.len()
            ),
        });
    }
    if let Some(i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!(
                "{what}: index {i} is out of range ({} vertices)",
                positions.len()
            ),
        });
    }
    let base = mesh.positions.len() as u32;
    for (k, p) in positions.iter().enumerate() {
        let w = transform.transform_point3(*p);
        if !w.is_finite() {
            return Err(LoadError::Unreadable {
                path: path.to_path_buf(),
                reason: format!("{what}: vertex {k} has a non-finite position {p}"),
            });
        }
        mesh.positions.push(w);
    }
    mesh.triangles.extend(
        indices
            .chunks_exact(3)
            .map(|t| [base + t[0], base + t[1], base + t[2]]),
    );
    Ok(())
}

/// Reads every triangle primitive of the default scene (or the first) of a glTF file.
pub fn read_gltf(path: &Path) -> Result<TriMesh, LoadError> {
    let unreadable = |reason: String| LoadError::Unreadable {
        path: path.to_path_buf(),
        reason,
    };
    let (doc, buffers, _) = gltf::import(path).map_err(|e| match e {
        gltf::Error::Io(source) => LoadError::Io {
            path: path.to_path_buf(),
            source,
        },
        other => unreadable(format!("not a valid glTF file: {other}")),
    })?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| unreadable("the glTF file has no scene".into()))?;
    let mut mesh = TriMesh::default();
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut skipped_modes = 0;
    while let Some((node, parent)) = stack.pop() {
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if let Some(m) = node.mesh() {
            for (k, prim) in m.primitives().enumerate() {
                let what = format!(
                    "mesh {:?} primitive {k}",
                    m.name().unwrap_or(&m.index().to_string())
                );
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    skipped_modes += 1;
                    continue;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(positions) = reader.read_positions() else {
                    return Err(unreadable(format!("{what} has no POSITION attribute")));
                };
                let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(ix) => ix.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                append(path, &what, &mut mesh, &positions, &indices, world)?;
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if mesh.triangles.is_empty() {
        let why = if skipped_modes > 0 {
            format!("no triangles ({skipped_modes} primitives of points or lines)")
        } else {
            "no triangles in its scene".into()
        };
        return Err(LoadError::NoFaces {
            path: path.to_path_buf(),
            reason: why,
        });
    }
    Ok(mesh)
}

/// Reads the faces of a Wavefront OBJ file (polygons are triangulated as fans).
pub fn read_obj(path: &Path) -> Result<TriMesh, LoadError> {
    let text = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(text), &options, |_| {
        Err(tobj::LoadError::GenericFailure)
    })
    .map_err(|e| LoadError::Unreadable {
        path: path.to_path_buf(),
        reason: format!("not a valid OBJ file: {e}"),
    })?;
    let mut mesh = TriMesh::default();
    for m in &models {
        let positions: Vec<Vec3> = m
            .mesh
            .positions
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect();
        let what = format!("object {:?}", m.name);
        append(
            path,
            &what,
            &mut mesh,
            &positions,
            &m.mesh.indices,
            Mat4::IDENTITY,
        )?;
    }
    if mesh.triangles.is_empty() {
        return Err(LoadError::NoFaces {
            path: path.to_path_buf(),
            reason: "no faces".into(),
        });
    }
    Ok(mesh)
}
