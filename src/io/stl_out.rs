//! Binary STL export of an [`ExportScene`]: every placed mesh's triangles in the file's
//! coordinates (each node's matrix composed with its groups' up to the root).
//!
//! Format: the de-facto binary STL layout (80-byte header, `u32` triangle count, then per
//! triangle a facet normal, three vertices as little-endian `f32` and a zero attribute
//! word). STL has no units, names, colours or instancing: every placement is written out, and
//! the unit is whatever the export chose (`export --unit`, millimetres by default for STL).
//! Written to a temporary name and renamed (`crate::io::png::write_bytes`).

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use crate::io::gltf_out::ExportScene;
use crate::io::png::{WriteError, write_bytes};

/// What was written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StlStats {
    pub triangles: usize,
    pub bytes: usize,
}

/// Why an STL file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum StlWriteError {
    #[error("{}: nothing to export: no placed mesh has a triangle", .path.display())]
    Empty { path: PathBuf },
    #[error("{}: {reason}", .path.display())]
    Invalid { path: PathBuf, reason: String },
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// Writes every placed triangle of `scene` as binary STL at `path`.
pub fn write_stl(path: &Path, scene: &ExportScene) -> Result<StlStats, StlWriteError> {
    let invalid = |reason: String| StlWriteError::Invalid {
        path: path.to_owned(),
        reason,
    };
    // World matrices of the groups (parents come first).
    let mut group_world: Vec<Mat4> = Vec::with_capacity(scene.groups.len());
    for (i, g) in scene.groups.iter().enumerate() {
        let parent = match g.parent {
            Some(p) if p < i => group_world[p],
            Some(p) => return Err(invalid(format!("group {i} has parent {p} after it"))),
            None => Mat4::IDENTITY,
        };
        group_world.push(parent * Mat4::from_cols_array(&g.matrix));
    }
    let mut body = Vec::new();
    let mut triangles = 0usize;
    for (i, node) in scene.nodes.iter().enumerate() {
        let mesh = scene
            .meshes
            .get(node.mesh)
            .ok_or_else(|| invalid(format!("node {i} names mesh {} of none", node.mesh)))?;
        let parent = match node.parent {
            Some(p) => *group_world
                .get(p)
                .ok_or_else(|| invalid(format!("node {i} names group {p} of none")))?,
            None => Mat4::IDENTITY,
        };
        let world = parent * Mat4::from_cols_array(&node.matrix);
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let mut v = [Vec3::ZERO; 3];
            for (k, &index) in tri.iter().enumerate() {
                let p = mesh.positions.get(index as usize).ok_or_else(|| {
                    invalid(format!(
                        "mesh {}: triangle {t} names vertex {index}",
                        node.mesh
                    ))
                })?;
                v[k] = world.transform_point3(Vec3::from(*p));
            }
            if !v.iter().all(|p| p.is_finite()) {
                return Err(invalid(format!(
                    "mesh {}: triangle {t} has a non-finite vertex",
                    node.mesh
                )));
            }
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            for c in [n, v[0], v[1], v[2]] {
                for x in c.to_array() {
                    body.extend_from_slice(&x.to_le_bytes());
                }
            }
            body.extend_from_slice(&0u16.to_le_bytes());
            triangles += 1;
        }
    }
    if triangles == 0 {
        return Err(StlWriteError::Empty {
            path: path.to_owned(),
        });
    }
    let count = u32::try_from(triangles)
        .map_err(|_| invalid(format!("{triangles} triangles: more than STL can count")))?;
    let mut bytes = Vec::with_capacity(84 + body.len());
    let mut header = [b' '; 80];
    let title = b"binary STL written by patchwork";
    header[..title.len()].copy_from_slice(title);
    bytes.extend_from_slice(&header);
    bytes.extend_from_slice(&count.to_le_bytes());
    bytes.extend_from_slice(&body);
    write_bytes(path, &bytes)?;
    Ok(StlStats {
        triangles,
        bytes: bytes.len(),
    })
}
