//! STL reader (ASCII and binary), into a [`TriMesh`] that `prep` welds and splits into
//! patches like any other mesh.
//!
//! Binary or ASCII is decided by the size rule first: a file of exactly 84 + 50·n bytes, n
//! being the little-endian count at byte 80, is binary even when its header starts with
//! `solid` (many exporters write that); otherwise a file starting with `solid` is read as
//! ASCII, and anything else is a binary file whose count does not match its size (an error
//! naming both). The count is checked against the file size before anything is allocated.
//! Facet normals are not kept: STL's are per facet; welding computes vertex normals that are
//! smooth across edges of at most 40° and hard beyond (`model::creases`).

use std::path::Path;

use glam::Vec3;

use super::LoadError;
use crate::model::mesh::TriMesh;

/// Bytes of a binary STL header (80) plus its triangle count (4).
const HEADER: usize = 84;
/// Bytes per binary triangle record: normal, three vertices, attribute count.
const RECORD: usize = 50;

/// Reads an STL file, ASCII or binary.
pub fn read(path: &Path) -> Result<TriMesh, LoadError> {
    let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&bytes, path)
}

/// Parses the bytes of an STL file (`path` names it in errors).
pub fn parse(bytes: &[u8], path: &Path) -> Result<TriMesh, LoadError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(LoadError::Empty {
            path: path.to_path_buf(),
        });
    }
    let mesh = match binary_count(bytes) {
        Some(n) if HEADER + RECORD * n == bytes.len() => binary(bytes, n, path)?,
        _ if starts_with_solid(bytes) => ascii(bytes, path)?,
        Some(n) => {
            return Err(LoadError::Unreadable {
                path: path.to_path_buf(),
                reason: format!(
                    "binary STL declares {n} triangles ({} bytes) but the file has {} bytes",
                    HEADER as u128 + RECORD as u128 * n as u128,
                    bytes.len()
                ),
            });
        }
        None => {
            return Err(LoadError::Unreadable {
                path: path.to_path_buf(),
                reason: format!(
                    "not an STL file: {} bytes, shorter than a binary header and not ASCII `solid`",
                    bytes.len()
                ),
            });
        }
    };
    if mesh.triangles.is_empty() {
        return Err(LoadError::Unreadable {
            path: path.to_path_buf(),
            reason: "no triangles in the STL file".into(),
        });
    }
    Ok(mesh)
}

/// The triangle count of a binary header, when the file is long enough to have one.
fn binary_count(bytes: &[u8]) -> Option<usize> {
    let c = bytes.get(80..84)?;
    Some(u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize)
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(0);
    bytes[start..]
        .get(..5)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"))
}

/// `n` binary records (the size was checked by the caller).
fn binary(bytes: &[u8], n: usize, path: &Path) -> Result<TriMesh, LoadError> {
    let mut mesh = TriMesh {
        positions: Vec::with_capacity(3 * n),
        triangles: Vec::with_capacity(n),
        ..TriMesh::default()
    };
    let f = |b: &[u8], k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
    for (t, rec) in bytes[HEADER..].chunks_exact(RECORD).enumerate() {
        let base = mesh.positions.len() as u32;
        for v in 0..3 {
            let o = 12 + 12 * v;
            let p = Vec3::new(f(rec, o), f(rec, o + 4), f(rec, o + 8));
            if !p.is_finite() {
                return Err(LoadError::Unreadable {
                    path: path.to_path_buf(),
                    reason: format!("triangle {t}: vertex {v} has a non-finite position {p}"),
                });
            }
            mesh.positions.push(p);
        }
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    Ok(mesh)
}

/// ASCII STL: `solid [name]`, then facets `facet normal x y z / outer loop / vertex x y z` ×3
/// `/ endloop / endfacet`, then `endsolid [name]`; several solids may follow each other.
fn ascii(bytes: &[u8], path: &Path) -> Result<TriMesh, LoadError> {
    let text = std::str::from_utf8(bytes).map_err(|e| LoadError::NotText {
        path: path.to_path_buf(),
        offset: e.valid_up_to(),
        what: "bytes that are not UTF-8",
    })?;
    let mut tokens = text
        .lines()
        .enumerate()
        .flat_map(|(i, l)| l.split_whitespace().map(move |w| (i + 1, w)))
        .peekable();
    let last_line = text.lines().count().max(1);
    let err = |line: usize, reason: String| LoadError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut mesh = TriMesh::default();
    // The keyword expected next; names after `solid` / `endsolid` run to the end of their line.
    let expect = |tokens: &mut dyn Iterator<Item = (usize, &str)>, word: &str| match tokens.next() {
        Some((_, w)) if w.eq_ignore_ascii_case(word) => Ok(()),
        Some((line, w)) => Err(err(line, format!("expected `{word}`, found `{w}`"))),
        None => Err(err(
            last_line,
            format!("the file ends where `{word}` is due"),
        )),
    };
    let number = |tok: Option<(usize, &str)>| -> Result<f32, LoadError> {
        match tok {
            Some((line, w)) => match w.parse::<f32>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(x) => Err(err(line, format!("coordinate {x} is not finite"))),
                Err(_) => Err(err(line, format!("`{w}` is not a number"))),
            },
            None => Err(err(last_line, "the file ends inside a facet".into())),
        }
    };
    let mut line_of_solid = 0;
    let mut in_solid = false;
    while let Some((line, w)) = tokens.next() {
        if !in_solid {
            if !w.eq_ignore_ascii_case("solid") {
                return Err(err(line, format!("expected `solid`, found `{w}`")));
            }
            in_solid = true;
            line_of_solid = line;
            // Skip the name: the rest of this line.
            while tokens.peek().is_some_and(|&(l, _)| l == line) {
                tokens.next();
            }
            continue;
        }
        if w.eq_ignore_ascii_case("endsolid") {
            in_solid = false;
            while tokens.peek().is_some_and(|&(l, _)| l == line) {
                tokens.next();
            }
            continue;
        }
        if !w.eq_ignore_ascii_case("facet") {
            return Err(err(
                line,
                format!("expected `facet` or `endsolid`, found `{w}`"),
            ));
        }
        expect(&mut tokens, "normal")?;
        for _ in 0..3 {
            number(tokens.next())?;
        }
        expect(&mut tokens, "outer")?;
        expect(&mut tokens, "loop")?;
        let base = mesh.positions.len() as u32;
        for _ in 0..3 {
            expect(&mut tokens, "vertex")?;
            let p = Vec3::new(
                number(tokens.next())?,
                number(tokens.next())?,
                number(tokens.next())?,
            );
            mesh.positions.push(p);
        }
        expect(&mut tokens, "endloop")?;
        expect(&mut tokens, "endfacet")?;
        mesh.triangles.push([base, base + 1, base + 2]);
    }
    if in_solid {
        return Err(err(
            last_line,
            format!("the solid opened on line {line_of_solid} has no `endsolid`"),
        ));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TETRA: &str = "solid tetra made by hand
  facet normal 0 0 -1
    outer loop
      vertex 0 0 0
      vertex 0 1 0
      vertex 1 0 0
    endloop
  endfacet
  facet normal 0 -1 0
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 0 0 1
    endloop
  endfacet
  facet normal -1 0 0
    outer loop
      vertex 0 0 0
      vertex 0 0 1
      vertex 0 1 0
    endloop
  endfacet
  facet normal 1 1 1
    outer loop
      vertex 1 0 0
      vertex 0 1 0
      vertex 0 0 1
    endloop
  endfacet
endsolid tetra
";

    /// The same triangles as a binary file, its header starting with `solid` as many
    /// exporters write it.
    fn binary_of(mesh: &TriMesh) -> Vec<u8> {
        let mut out = b"solid binary header".to_vec();
        out.resize(80, b' ');
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
        out
    }

    fn tetra() -> TriMesh {
        parse(TETRA.as_bytes(), p()).expect("the ASCII tetrahedron reads")
    }

    fn p() -> &'static Path {
        Path::new("test.stl")
    }

    #[test]
    fn ascii_and_binary_give_the_same_triangles() {
        let a = tetra();
        assert_eq!(a.triangles.len(), 4);
        assert_eq!(a.positions.len(), 12);
        assert_eq!(a.positions[11], Vec3::new(0.0, 0.0, 1.0));
        let b = parse(&binary_of(&a), p()).expect("the binary tetrahedron reads");
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.triangles, b.triangles);
        // Welding shares the corners: a closed tetrahedron of 4 positions; every edge is a
        // crease (no normals in the file), so each corner is one vertex per face.
        let mut w = a.clone();
        assert_eq!(w.weld(), 0);
        assert_eq!(w.position_ids.iter().max(), Some(&3));
        assert_eq!(w.positions.len(), 12);
    }

    #[test]
    fn a_binary_count_that_lies_is_refused_before_allocating() {
        let a = tetra();
        let mut b = binary_of(&a);
        b[0..5].copy_from_slice(b"xxxxx"); // not ASCII either
        b[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = parse(&b, p()).expect_err("a lying count").to_string();
        assert!(e.contains("declares 4294967295 triangles"), "{e}");
        b.truncate(83);
        let e = parse(&b, p()).expect_err("a lying count").to_string();
        assert!(e.contains("not an STL file"), "{e}");
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let cases = [
            (
                TETRA.replace(
                    "vertex 0 1 0\n      vertex 1 0 0",
                    "vertex 0 1 0\n      vertex 1 nan 0",
                ),
                6,
                "not finite",
            ),
            (
                TETRA.replace(
                    "vertex 1 0 0\n      vertex 0 0 1",
                    "vertex 1 0 0\n      vertex 0 zero 1",
                ),
                13,
                "not a number",
            ),
            (
                TETRA.replace(
                    "    endloop\n  endfacet\n  facet normal -1",
                    "  endfacet\n  facet normal -1",
                ),
                14,
                "expected `endloop`",
            ),
            (TETRA.replace("endsolid tetra\n", ""), 29, "no `endsolid`"),
        ];
        for (text, line, what) in cases {
            match parse(text.as_bytes(), p()) {
                Err(LoadError::Parse {
                    line: l, reason, ..
                }) => {
                    assert_eq!(l, line, "{reason}");
                    assert!(reason.contains(what), "{reason}");
                }
                other => panic!("expected a parse error for {what}, got {other:?}"),
            }
        }
    }

    #[test]
    fn empty_and_triangle_free_files_are_errors() {
        assert!(matches!(parse(b"  \n", p()), Err(LoadError::Empty { .. })));
        let e = parse(b"solid x\nendsolid x\n", p())
            .expect_err("no triangles")
            .to_string();
        assert!(e.contains("no triangles"), "{e}");
        let mut nan = binary_of(&tetra());
        nan[HEADER + 16..HEADER + 20].copy_from_slice(&f32::INFINITY.to_le_bytes());
        let e = parse(&nan, p())
            .expect_err("an infinite vertex")
            .to_string();
        assert!(e.contains("triangle 0: vertex 0 has a non-finite"), "{e}");
    }
}
