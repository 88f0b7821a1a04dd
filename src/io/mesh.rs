//! Triangle-mesh readers: glTF 2.0 (`.glb`, `.gltf`; every mesh primitive of every node in
//! the default scene, node transforms applied; each node with a mesh a part, each primitive a
//! group in its material's base colour) with the `gltf` crate, and Wavefront OBJ with
//! `tobj` (each material's `Kd` a group colour), PLY with `ply-rs` (vertex or face colours as
//! group colours). The file's normals (glTF `NORMAL`, OBJ `vn`, PLY `nx ny nz`) are kept in
//! [`TriMesh::normals`]; where a file has none, welding computes them with creases
//! ([`crate::model::creases`]). The result is welded into one world-space [`TriMesh`] and
//! split into patches ([`crate::prep::partition`](fn@crate::prep::partition)). Textures are not read.

use std::path::Path;

use glam::{Mat4, Vec3};

use super::LoadError;
use crate::model::bezier::MAX_COORDINATE;
pub use crate::model::mesh::TriMesh;

/// Whether `mesh` has something to draw (issue 21's bad-input policy): every vertex within
/// ±`MAX_COORDINATE` (the GPU's f32 range for squared lengths) and at least one triangle
/// with an area. A triangle counts as without area when its corners are collinear or
/// coincide up to f32 rounding: `|e1 × e2| ≤ 10⁻⁶ |e1| |e2|` (an angle below 10⁻⁶ rad) or
/// below the rounding of its coordinates. A model made only of such triangles would render as
/// a blank image; it is [`LoadError::NoFaces`] naming the file instead.
pub fn check_drawable(path: &Path, mesh: &TriMesh) -> Result<(), LoadError> {
    if let Some((k, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| f64::from(p.abs().max_element()) > MAX_COORDINATE)
    {
        return Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!(
                "vertex {k} at {p} is beyond ±{MAX_COORDINATE:e}, which the GPU's f32 cannot draw: scale the model down"
            ),
        });
    }
    let has_area = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let cross = e1.cross(e2).length();
        let scale = a.abs().max(b.abs()).max(c.abs()).max_element();
        let rounding = 4.0 * f64::from(f32::EPSILON) * scale;
        cross > 1e-6 * e1.length() * e2.length() && cross > rounding * rounding
    };
    if mesh.triangles.iter().any(has_area) {
        return Ok(());
    }
    Err(LoadError::NoFaces {
        path: path.to_path_buf(),
        reason: format!(
            "all {} triangles have zero area (collinear or coinciding corners)",
            mesh.triangles.len()
        ),
    })
}

/// Appends the triangles of a primitive, checking indices and positions; `normals` (the
/// file's, one per position, moved by the inverse transpose of `transform`) are kept in
/// [`TriMesh::normals`], zero for primitives without them.
fn append(
    path: &Path,
    what: &str,
    mesh: &mut TriMesh,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    indices: &[u32],
    transform: Mat4,
) -> Result<(), LoadError> {
    if let Some(n) = normals.filter(|n| n.len() != positions.len()) {
        return Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!(
                "{what}: {} normals for {} positions",
                n.len(),
                positions.len()
            ),
        });
    }
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
    if normals.is_some() || !mesh.normals.is_empty() {
        // Vertices before the first primitive with normals have none.
        mesh.normals.resize(base as usize, Vec3::ZERO);
        // A singular transform leaves no normal direction: they are computed instead.
        let m = glam::Mat3::from_mat4(transform);
        let to_world = (m.determinant() != 0.0).then(|| m.inverse().transpose());
        match (normals, to_world) {
            (Some(n), Some(to_world)) => mesh.normals.extend(n.iter().map(|&n| to_world * n)),
            _ => mesh.normals.resize(mesh.positions.len(), Vec3::ZERO),
        }
    }
    mesh.triangles.extend(
        indices
            .chunks_exact(3)
            .map(|t| [base + t[0], base + t[1], base + t[2]]),
    );
    Ok(())
}

/// Reads every triangle primitive of the default scene (or the first) of a glTF file.
///
/// Hardened against hostile files (issue 21): the whole file is read first and parsed from
/// memory (so a GLB header cannot ask for more bytes than the file has), buffers may only be
/// embedded, `data:` URIs or relative paths that stay inside the file's folder (no absolute
/// paths, `..` or `file:`), images are not loaded, the node graph must be a tree (a node
/// reached twice — a cycle — is an error), and a panic inside the gltf crates becomes an
/// error naming the file.
pub fn read_gltf(path: &Path) -> Result<TriMesh, LoadError> {
    parse_gltf(&read_bytes(path)?, path)
}

/// The whole file.
fn read_bytes(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// As [`read_gltf`], from the file's bytes (relative buffer URIs are still read from
/// `path`'s folder).
pub fn parse_gltf(bytes: &[u8], path: &Path) -> Result<TriMesh, LoadError> {
    match crate::isolate::isolated(|| gltf_mesh(path, bytes)) {
        Ok(result) => result,
        Err(panic) => Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: format!("not a valid glTF file: the glTF reader failed ({panic})"),
        }),
    }
}

/// Whether a buffer URI may be followed: a `data:` URI, or a relative path (after
/// percent-decoding) without `..`, a root, a drive or a scheme.
fn safe_buffer_uri(uri: &str) -> Result<(), String> {
    if uri.starts_with("data:") {
        return Ok(());
    }
    let decoded = percent_decode(uri).ok_or_else(|| format!("buffer URI {uri:?} is not valid"))?;
    let bad = decoded.contains(':')
        || decoded.starts_with('/')
        || decoded.contains('\\')
        || decoded.split('/').any(|c| c == "..");
    if bad {
        return Err(format!(
            "buffer URI {uri:?} points outside the file's folder (only embedded data and relative paths below it are read)"
        ));
    }
    Ok(())
}

/// `%XX` escapes decoded; `None` for a broken escape or bytes that are not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

fn gltf_mesh(path: &Path, bytes: &[u8]) -> Result<TriMesh, LoadError> {
    let unreadable = |reason: String| LoadError::Unreadable {
        path: path.to_path_buf(),
        reason,
    };
    let gltf = gltf::Gltf::from_slice(bytes)
        .map_err(|e| unreadable(format!("not a valid glTF file: {e}")))?;
    for b in gltf.document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source() {
            safe_buffer_uri(uri).map_err(|e| unreadable(format!("buffer {}: {e}", b.index())))?;
        }
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone()).map_err(
        |e| match e {
            gltf::Error::Io(source) => LoadError::Io {
                path: path.to_path_buf(),
                source,
            },
            other => unreadable(format!("not a valid glTF file: {other}")),
        },
    )?;
    let doc = &gltf.document;
    let mut reached = vec![false; doc.nodes().count()];
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| unreadable("the glTF file has no scene".into()))?;
    let mut mesh = TriMesh::default();
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut skipped_modes = 0;
    while let Some((node, parent)) = stack.pop() {
        match reached.get_mut(node.index()) {
            Some(r) if !*r => *r = true,
            _ => {
                return Err(unreadable(format!(
                    "node {} is reached twice: the node graph must be a tree (a cycle?)",
                    node.index()
                )));
            }
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if let Some(m) = node.mesh() {
            // Each node with a mesh is a part; each primitive a group in its material's colour.
            let part = mesh.part_names.len() as u32;
            mesh.part_names.push(
                node.name()
                    .or(m.name())
                    .map_or_else(|| format!("node {}", node.index()), str::to_owned),
            );
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
                let normals: Option<Vec<Vec3>> =
                    reader.read_normals().map(|n| n.map(Vec3::from).collect());
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(ix) => ix.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                let normals = normals.as_deref();
                append(path, &what, &mut mesh, &positions, normals, &indices, world)?;
                let [r, g, b, _] = prim.material().pbr_metallic_roughness().base_color_factor();
                let color =
                    (prim.material().index().is_some()).then(|| [r, g, b].map(linear_to_srgb));
                mesh.groups.push(crate::model::mesh::TriGroup {
                    part,
                    color,
                    end: mesh.triangles.len(),
                });
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

/// glTF's linear base colour → sRGB, the space colours are drawn in (IEC 61966-2-1).
fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        1.0
    };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Reads the faces of a Wavefront OBJ file (polygons are triangulated as fans), with their
/// `vn` normals where faces name them, and each material's diffuse colour (`Kd` of the
/// `mtllib` files, read as sRGB) as the colour of its faces' group.
#[cfg(feature = "obj")]
pub(crate) fn read_obj(path: &Path) -> Result<TriMesh, LoadError> {
    parse_obj(&read_bytes(path)?, path)
}

/// As `read_obj`, from the file's bytes (`path` names it in errors; material files are
/// read from its folder: relative names below it only, as glTF buffers — a material file
/// that is missing, unreadable or outside is a warning in [`TriMesh::warnings`] and its
/// faces are drawn in the default colour).
#[cfg(feature = "obj")]
pub fn parse_obj(text: &[u8], path: &Path) -> Result<TriMesh, LoadError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let base = path.parent().unwrap_or(Path::new("."));
    let problems = std::cell::RefCell::new(Vec::new());
    let load_mtl = |name: &Path| {
        let text = name.to_string_lossy();
        let read = safe_buffer_uri(&text)
            .and_then(|()| std::fs::read(base.join(name)).map_err(|e| e.to_string()));
        match read {
            Ok(bytes) => tobj::load_mtl_buf(&mut std::io::Cursor::new(bytes)).inspect_err(|e| {
                problems
                    .borrow_mut()
                    .push(format!("material file {text:?}: {e}"))
            }),
            Err(e) => {
                problems
                    .borrow_mut()
                    .push(format!("material file {text:?}: {e}"));
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(text), &options, load_mtl).map_err(|e| {
            LoadError::Unreadable {
                path: path.to_path_buf(),
                reason: format!("not a valid OBJ file: {e}"),
            }
        })?;
    let materials = materials.unwrap_or_default();
    let mut mesh = TriMesh::default();
    // Every triangle's material colour: a file may switch materials face by face (`usemtl`
    // runs), and each run a group of its own would cut the surface into as many patches
    // (a generated plane in two interleaved materials, mgen-1-3: 5 667 patches for 21 000
    // triangles). Triangles of one colour are one group, as for PLY.
    let mut colors: Vec<Option<[f32; 3]>> = Vec::new();
    for m in &models {
        let positions: Vec<Vec3> = m
            .mesh
            .positions
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect();
        let what = format!("object {:?}", m.name);
        let (ix, nix) = (&m.mesh.indices, &m.mesh.normal_indices);
        if !m.mesh.normals.is_empty() && nix.len() == ix.len() {
            // One vertex per corner with its normal; welding merges them again.
            let normals: Vec<Vec3> = m
                .mesh
                .normals
                .chunks_exact(3)
                .map(|n| Vec3::new(n[0], n[1], n[2]))
                .collect();
            let mut corners = Vec::with_capacity(ix.len());
            let mut corner_normals = Vec::with_capacity(ix.len());
            for (&i, &n) in ix.iter().zip(nix) {
                let (Some(&p), Some(&n)) = (positions.get(i as usize), normals.get(n as usize))
                else {
                    return Err(LoadError::Unreadable {
                        path: path.to_path_buf(),
                        reason: format!("{what}: a face index is out of range"),
                    });
                };
                corners.push(p);
                corner_normals.push(n);
            }
            let indices: Vec<u32> = (0..corners.len() as u32).collect();
            let normals = Some(&corner_normals[..]);
            append(
                path,
                &what,
                &mut mesh,
                &corners,
                normals,
                &indices,
                Mat4::IDENTITY,
            )?;
        } else {
            append(path, &what, &mut mesh, &positions, None, ix, Mat4::IDENTITY)?;
        }
        let color = m
            .mesh
            .material_id
            .and_then(|k| materials.get(k))
            .and_then(|mat| mat.diffuse)
            .map(|kd| {
                kd.map(|c| {
                    if c.is_finite() {
                        c.clamp(0.0, 1.0)
                    } else {
                        1.0
                    }
                })
            });
        colors.resize(mesh.triangles.len(), color);
    }
    if mesh.triangles.is_empty() {
        return Err(LoadError::NoFaces {
            path: path.to_path_buf(),
            reason: "no faces".into(),
        });
    }
    // No colours: no groups, as a file without materials always was.
    color_groups(&mut mesh, &colors, usize::MAX);
    mesh.warnings = problems.into_inner();
    Ok(mesh)
}

#[cfg(any(feature = "obj", feature = "ply"))]
/// Ends a group in `color` at the mesh's last triangle (extending the previous group when it
/// has the same colour).
fn push_group(mesh: &mut TriMesh, color: Option<[f32; 3]>) {
    let end = mesh.triangles.len();
    match mesh.groups.last_mut() {
        Some(g) if g.color == color => g.end = end,
        _ => mesh.groups.push(crate::model::mesh::TriGroup {
            part: 0,
            color,
            end,
        }),
    }
}

/// Reads the faces of a PLY file (ASCII or binary, with `ply-rs`): the `x`, `y`, `z` of every
/// `vertex` (and `nx`, `ny`, `nz` when the vertices have them) and the `vertex_indices` (or
/// `vertex_index`) list of every `face`; polygons are triangulated as fans. Colours
/// (`red`, `green`, `blue`: a face's own, else the one two of its corners share, else its first
/// corner's) become groups, triangles reordered so each colour is one run; more than
/// [`MAX_COLOR_GROUPS`] colours are drawn in their mean with a warning. Element counts larger than the file could hold are refused before
/// anything is allocated, and a panic inside the parser becomes an error.
#[cfg(feature = "ply")]
pub fn read_ply(path: &Path) -> Result<TriMesh, LoadError> {
    parse_ply(&read_bytes(path)?, path)
}

/// As [`read_ply`], from the file's bytes (`path` names it in errors).
#[cfg(feature = "ply")]
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<TriMesh, LoadError> {
    use ply_rs::ply::{DefaultElement, Property};
    let unreadable = |reason: String| LoadError::Unreadable {
        path: path.to_path_buf(),
        reason,
    };
    if !bytes.starts_with(b"ply") {
        return Err(unreadable(
            "not a PLY file (it does not start with \"ply\")".into(),
        ));
    }
    // Every element takes at least one byte of the file, in any format. The header ends at
    // the first line that is `end_header` (the words may also stand inside a comment line,
    // which the parser reads on past: fuzzing found one hiding a 4·10⁹-vertex element).
    let mut header = Vec::new();
    let mut ended = false;
    for line in bytes.split(|&b| b == b'\n').map(<[u8]>::trim_ascii) {
        if line == b"end_header" {
            ended = true;
            break;
        }
        header.push(line);
    }
    if !ended {
        return Err(unreadable("the PLY header has no end_header".into()));
    }
    for line in header {
        let line = String::from_utf8_lossy(line);
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.first() == Some(&"element") {
            let count: u64 = words
                .get(2)
                .and_then(|c| c.parse().ok())
                .ok_or_else(|| unreadable(format!("bad element line in the header: {line:?}")))?;
            if count > bytes.len() as u64 {
                return Err(unreadable(format!(
                    "the header declares {count} {} elements, more than the file's {} bytes could hold",
                    words.get(1).unwrap_or(&"?"),
                    bytes.len()
                )));
            }
        }
    }
    let parser = ply_rs::parser::Parser::<DefaultElement>::new();
    let ply = crate::isolate::isolated(|| parser.read_ply(&mut &bytes[..]))
        .map_err(|e| unreadable(format!("not a valid PLY file: {e}")))?
        .map_err(|e| unreadable(format!("not a valid PLY file: {e}")))?;
    let scalar = |p: &Property| -> Option<f64> {
        Some(match *p {
            Property::Char(x) => x as f64,
            Property::UChar(x) => x as f64,
            Property::Short(x) => x as f64,
            Property::UShort(x) => x as f64,
            Property::Int(x) => x as f64,
            Property::UInt(x) => x as f64,
            Property::Float(x) => x as f64,
            Property::Double(x) => x,
            _ => return None,
        })
    };
    let list = |p: &Property| -> Option<Vec<i64>> {
        Some(match p {
            Property::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
            _ => return None,
        })
    };
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| unreadable("no vertex element".into()))?;
    let mut positions = Vec::with_capacity(vertices.len());
    for (k, v) in vertices.iter().enumerate() {
        let mut xyz = [0f32; 3];
        for (c, name) in xyz.iter_mut().zip(["x", "y", "z"]) {
            *c =
                v.get(name).and_then(scalar).ok_or_else(|| {
                    unreadable(format!("vertex {k} has no numeric property {name:?}"))
                })? as f32;
        }
        positions.push(Vec3::from(xyz));
    }
    // Normals when every vertex has all three (a vertex with a broken one gets none: zero).
    let has = |name: &str| vertices.first().is_some_and(|v| v.contains_key(name));
    let normals: Option<Vec<Vec3>> = ["nx", "ny", "nz"].iter().all(|n| has(n)).then(|| {
        let get = |v: &DefaultElement, n: &str| v.get(n).and_then(scalar).map(|x| x as f32);
        (vertices.iter())
            .map(|v| match (get(v, "nx"), get(v, "ny"), get(v, "nz")) {
                (Some(x), Some(y), Some(z)) => Vec3::new(x, y, z),
                _ => Vec3::ZERO,
            })
            .collect()
    });
    let vertex_colors: Vec<Option<[f32; 3]>> = vertices.iter().map(ply_color).collect();
    let mut indices = Vec::new();
    let mut face_colors: Vec<Option<[f32; 3]>> = Vec::new();
    for (k, f) in ply.payload.get("face").into_iter().flatten().enumerate() {
        let corners = f
            .get("vertex_indices")
            .or_else(|| f.get("vertex_index"))
            .and_then(list)
            .ok_or_else(|| unreadable(format!("face {k} has no vertex_indices list")))?;
        if corners.len() < 3 {
            return Err(unreadable(format!(
                "face {k} has {} corners, a face needs 3 or more",
                corners.len()
            )));
        }
        let corner = |i: i64| {
            u32::try_from(i).map_err(|_| unreadable(format!("face {k}: index {i} is negative")))
        };
        let color = ply_color(f);
        for j in 1..corners.len() - 1 {
            indices.extend([
                corner(corners[0])?,
                corner(corners[j])?,
                corner(corners[j + 1])?,
            ]);
            face_colors.push(color);
        }
    }
    let mut mesh = TriMesh::default();
    let normals = normals.as_deref();
    append(
        path,
        "PLY",
        &mut mesh,
        &positions,
        normals,
        &indices,
        Mat4::IDENTITY,
    )?;
    if mesh.triangles.is_empty() {
        return Err(LoadError::NoFaces {
            path: path.to_path_buf(),
            reason: "no faces".into(),
        });
    }
    // A face's own colour, else its corners' (indices were checked by `append`).
    let colors: Vec<Option<[f32; 3]>> = (mesh.triangles.iter().zip(&face_colors))
        .map(|(t, &face)| face.or_else(|| majority(t.map(|v| vertex_colors[v as usize]))))
        .collect();
    color_groups(&mut mesh, &colors, MAX_COLOR_GROUPS);
    Ok(mesh)
}

#[cfg(feature = "ply")]
/// Most distinct triangle colours a PLY file is split into groups by (each group is patched
/// on its own); beyond it, colours vary per vertex (a scan) and the mesh is drawn in their
/// mean, with a warning.
pub const MAX_COLOR_GROUPS: usize = 64;

/// The `red`, `green`, `blue` (or `diffuse_red`, …) of a PLY element: integers are 0–255,
/// floating-point values 0–1; sRGB.
#[cfg(feature = "ply")]
fn ply_color(e: &ply_rs::ply::DefaultElement) -> Option<[f32; 3]> {
    use ply_rs::ply::Property;
    let channel = |name: &str| {
        let p = e.get(name).or_else(|| e.get(&format!("diffuse_{name}")))?;
        let x = match *p {
            Property::UChar(x) => x as f32 / 255.0,
            Property::Char(x) => x as f32 / 255.0,
            Property::UShort(x) => x as f32 / 255.0,
            Property::Short(x) => x as f32 / 255.0,
            Property::UInt(x) => x as f32 / 255.0,
            Property::Int(x) => x as f32 / 255.0,
            Property::Float(x) => x,
            Property::Double(x) => x as f32,
            _ => return None,
        };
        x.is_finite().then(|| x.clamp(0.0, 1.0))
    };
    Some([channel("red")?, channel("green")?, channel("blue")?])
}

#[cfg(feature = "ply")]
/// The colour two or three corners share, else the first corner's.
fn majority(c: [Option<[f32; 3]>; 3]) -> Option<[f32; 3]> {
    if c[1] == c[2] { c[1] } else { c[0] }
}

#[cfg(any(feature = "obj", feature = "ply"))]
/// Groups `mesh`'s triangles by `colors` (one per triangle): triangles reordered so each
/// colour is one run (in the order colours first occur, stable within a colour), one group
/// per colour. More than `cap` colours (PLY: [`MAX_COLOR_GROUPS`]): one group in their mean,
/// and a warning. No colours: no groups.
fn color_groups(mesh: &mut TriMesh, colors: &[Option<[f32; 3]>], cap: usize) {
    if colors.iter().all(Option::is_none) {
        return;
    }
    let mut distinct: Vec<Option<[f32; 3]>> = Vec::new();
    let mut index: std::collections::HashMap<Option<[u32; 3]>, u32> = Default::default();
    let keys: Vec<u32> = colors
        .iter()
        .map(|c| {
            *index
                .entry(c.map(|c| c.map(f32::to_bits)))
                .or_insert_with(|| {
                    distinct.push(*c);
                    (distinct.len() - 1) as u32
                })
        })
        .collect();
    if distinct.len() > cap {
        let known: Vec<[f32; 3]> = colors.iter().flatten().copied().collect();
        let sum = known.iter().fold(Vec3::ZERO, |s, &c| s + Vec3::from(c));
        let mean = (sum / known.len() as f32).to_array();
        mesh.warnings.push(format!(
            "{} distinct colours (more than {cap}): drawn in their mean colour, \
             colours per vertex are not drawn",
            distinct.len()
        ));
        push_group(mesh, Some(mean));
        return;
    }
    let mut order: Vec<usize> = (0..mesh.triangles.len()).collect();
    order.sort_by_key(|&t| keys[t]);
    mesh.triangles = order.iter().map(|&t| mesh.triangles[t]).collect();
    let mut end = 0;
    for (k, c) in distinct.iter().enumerate() {
        end += keys.iter().filter(|&&x| x == k as u32).count();
        mesh.groups.push(crate::model::mesh::TriGroup {
            part: 0,
            color: *c,
            end,
        });
    }
}

/// Without the `obj` feature: an error naming it.
#[cfg(not(feature = "obj"))]
pub(crate) fn read_obj(path: &Path) -> Result<TriMesh, LoadError> {
    Err(LoadError::NotBuiltIn {
        path: path.to_path_buf(),
        format: "OBJ",
        feature: "obj",
    })
}

/// Without the `ply` feature: an error naming it.
#[cfg(not(feature = "ply"))]
pub fn read_ply(path: &Path) -> Result<TriMesh, LoadError> {
    Err(LoadError::NotBuiltIn {
        path: path.to_path_buf(),
        format: "PLY",
        feature: "ply",
    })
}
