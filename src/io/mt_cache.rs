//! The on-disk cache of built MT hierarchies ([`crate::mt`]): building the hierarchies of a
//! large mesh takes seconds, reading them back milliseconds.
//!
//! One file per model, named by a [`CacheKey`]: a 128-bit hash of the model file's bytes, the
//! preparation parameters (patch size, arc size) and `FORMAT_VERSION` — a changed file, other
//! parameters or another format never match. The file is our own little-endian format:
//!
//! ```text
//! magic "PWMTCACH" · version u32 · key 2×u64 · payload length u64 · payload hash 2×u64
//! payload: patch count u32, then per patch: vertex count u32, triangle count u32,
//!          node count u32, triangles 3×u32 each, created_by u32 each, removed_by u32 each,
//!          node errors f64 each, vertex_removed_by u32 each, vertex_target u32 each
//! ```
//!
//! Reading checks everything before trusting it: magic, version, key, the payload's length
//! against the file's and its hash (a flipped bit or a truncated file is refused), every count
//! against the bytes left before allocating, the patch count and vertex counts against the
//! patches being prepared, and each hierarchy's invariants (`MtHierarchy::from_parts`:
//! index bounds, node order, monotone errors). A refused file is a [`CacheError`], never a
//! panic; callers rebuild. Writes go to a temporary name and are renamed into place.
//! Nothing is ever evicted.

use std::path::{Path, PathBuf};

use crate::mt::{MtHierarchy, MtParts};

/// Version of the file format *and* of the hierarchy build: bump it whenever either changes,
/// so older caches stop matching. 3: patches' vertices split by normal at creases and where
/// the file's normals differ (`model::creases`), so a patch's vertex numbering changed. 4: the
/// build's quadrics start at zero (not glam's identity), border corners collapse, and the
/// reduction merges nodes within `mt::MAX_MERGE_ERROR_RATIO`: other hierarchies. 5: node
/// errors are certified bounds (`mt::bound`), not samples: other errors and hierarchies. 6: the
/// patches' coarse groups' hierarchies follow the patches' (`prep::groups`). 7: fan → original
/// bounds against the whole original patch surface (`mt::nearest`): other (tighter) errors.
/// 8: collapses ordered by their expected node error (`mt::build`: lazy re-keying), not the
/// quadric alone: other hierarchies. 9: height bounds at the patch border (`mt::bound`: the
/// part of a fan triangle between a border chord and the original border it replaced) and over
/// originals grown across the prism: other (tighter) errors. 10: pieces of the original
/// surface split up to 8 times, not 3 (`mt::build::PIECE_DEPTH`): other (tighter) errors on
/// flat regions. 11: hierarchies built across creases (`MtHierarchy::build_across_seams`):
/// other hierarchies wherever vertices are split by their normals. 12: an interior vertex may
/// move onto the border along a crease: other hierarchies where a crease meets the outline.
/// 13: split pieces merged back and pieces kept by the triangle they moved with
/// (`mt::build::measure`): other errors and hierarchies.
/// 14: an interior vertex may move onto the border anywhere: other hierarchies.
/// 15: height bounds take the distance to a steep original (`mt::bound::height_over`) and fan
/// triangles split up to 10 times, not 6 (`mt::build::FAN_DEPTH`): other (tighter) errors.
/// 16: the height bound's cover argument tries points off the fan triangle's centroid
/// (`mt::bound::height_over`): other (tighter) errors.
/// 17: candidates tied on cost taken by their own distance (`mt::build`): other hierarchies.
pub(crate) const FORMAT_VERSION: u32 = 17;

const MAGIC: &[u8; 8] = b"PWMTCACH";
const HEADER: usize = 8 + 4 + 16 + 8 + 16;

/// What a cache file is for: the model's bytes and the parameters its hierarchies were built
/// with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CacheKey(pub [u64; 2]);

impl CacheKey {
    /// The key of a model file's `bytes` prepared with `params` (e.g. patch size and the arc
    /// size's bits), for this `FORMAT_VERSION`.
    pub fn new(bytes: &[u8], params: &[u64]) -> CacheKey {
        let file = crate::util::hash128(bytes);
        let mut all = Vec::with_capacity(8 * (3 + params.len()));
        all.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        for w in file.iter().chain(params) {
            all.extend_from_slice(&w.to_le_bytes());
        }
        CacheKey(crate::util::hash128(&all))
    }

    /// The cache file's name.
    pub fn file_name(&self) -> String {
        format!("{:016x}{:016x}.mtc", self.0[0], self.0[1])
    }
}

/// Why a cache file was not used or not written.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("{}: cannot read the hierarchy cache: {source}", .path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: hierarchy cache refused: {reason}", .path.display())]
    Invalid { path: PathBuf, reason: String },
    #[error("cannot write the hierarchy cache: {0}")]
    Write(String),
}

/// The cache directory: `$PATCHWORK_CACHE` when set (`off` or empty: no cache), else
/// `$XDG_CACHE_HOME/patchwork`, else `~/.cache/patchwork`; `None` when caching is off or no
/// home is known.
pub fn default_dir() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(v) = std::env::var_os("PATCHWORK_CACHE") {
        return (!v.is_empty() && v != "off").then(|| PathBuf::from(v));
    }
    if let Some(x) = var("XDG_CACHE_HOME") {
        return Some(PathBuf::from(x).join("patchwork"));
    }
    var("HOME").map(|h| PathBuf::from(h).join(".cache").join("patchwork"))
}

/// The hierarchies cached under `key` in `dir` for patches with `vertex_counts` vertices:
/// `Ok(None)` when there is no such file, an error when there is one that cannot be used.
pub fn read(
    dir: &Path,
    key: CacheKey,
    vertex_counts: &[usize],
) -> Result<Option<Vec<MtHierarchy>>, CacheError> {
    let path = dir.join(key.file_name());
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => return Err(CacheError::Read { path, source }),
    };
    decode(&bytes, key, vertex_counts)
        .map(Some)
        .map_err(|reason| CacheError::Invalid { path, reason })
}

/// Writes `hierarchies` under `key` into `dir` (created if missing), atomically.
pub fn write(dir: &Path, key: CacheKey, hierarchies: &[&MtHierarchy]) -> Result<(), CacheError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| CacheError::Write(format!("{}: {e}", dir.display())))?;
    let path = dir.join(key.file_name());
    super::png::write_bytes(&path, &encode(key, hierarchies))
        .map_err(|e| CacheError::Write(e.to_string()))
}

/// The file's bytes for `hierarchies` under `key`.
pub fn encode(key: CacheKey, hierarchies: &[&MtHierarchy]) -> Vec<u8> {
    let mut p = Vec::new();
    let u32s = |p: &mut Vec<u8>, xs: &mut dyn Iterator<Item = u32>| {
        for x in xs {
            p.extend_from_slice(&x.to_le_bytes());
        }
    };
    u32s(&mut p, &mut std::iter::once(hierarchies.len() as u32));
    for h in hierarchies {
        let counts = [h.vertex_target.len(), h.triangles.len(), h.node_error.len()];
        u32s(&mut p, &mut counts.iter().map(|&c| c as u32));
        u32s(&mut p, &mut h.triangles.iter().flatten().copied());
        u32s(&mut p, &mut h.created_by.iter().copied());
        u32s(&mut p, &mut h.removed_by.iter().copied());
        for e in &h.node_error {
            p.extend_from_slice(&e.to_le_bytes());
        }
        u32s(&mut p, &mut h.vertex_removed_by.iter().copied());
        u32s(&mut p, &mut h.vertex_target.iter().copied());
    }
    let mut out = Vec::with_capacity(HEADER + p.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    for w in key.0 {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&(p.len() as u64).to_le_bytes());
    for w in crate::util::hash128(&p) {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&p);
    out
}

/// Little-endian reads that fail at the end of the bytes instead of panicking.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end =
            end.ok_or_else(|| format!("ends early (at byte {} of {})", self.at, self.bytes.len()))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u32(&mut self) -> Result<u32, String> {
        let mut b = [0u8; 4];
        b.copy_from_slice(self.take(4)?);
        Ok(u32::from_le_bytes(b))
    }

    fn u64(&mut self) -> Result<u64, String> {
        let mut b = [0u8; 8];
        b.copy_from_slice(self.take(8)?);
        Ok(u64::from_le_bytes(b))
    }

    /// `count` items of `size` bytes each, refused before allocating when the bytes left
    /// cannot hold them.
    fn items<T>(
        &mut self,
        count: usize,
        size: usize,
        mut item: impl FnMut(&mut Self) -> Result<T, String>,
    ) -> Result<Vec<T>, String> {
        let left = self.bytes.len() - self.at;
        if count.checked_mul(size).is_none_or(|n| n > left) {
            return Err(format!(
                "{count} items of {size} bytes but {left} bytes left"
            ));
        }
        (0..count).map(|_| item(self)).collect()
    }
}

/// The hierarchies in a cache file's `bytes`, checked as the module doc says.
pub fn decode(
    bytes: &[u8],
    key: CacheKey,
    vertex_counts: &[usize],
) -> Result<Vec<MtHierarchy>, String> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(8)? != MAGIC {
        return Err("not a patchwork hierarchy cache (magic)".into());
    }
    let version = r.u32()?;
    if version != FORMAT_VERSION {
        return Err(format!(
            "format version {version}, expected {FORMAT_VERSION}"
        ));
    }
    if [r.u64()?, r.u64()?] != key.0 {
        return Err("written for another file or other parameters (key)".into());
    }
    let len = r.u64()?;
    let hash = [r.u64()?, r.u64()?];
    let payload = &bytes[HEADER..];
    if len != payload.len() as u64 {
        return Err(format!(
            "payload of {} bytes, the header says {len} (truncated?)",
            payload.len()
        ));
    }
    if crate::util::hash128(payload) != hash {
        return Err("payload checksum mismatch (corrupt)".into());
    }
    let patches = r.u32()? as usize;
    if patches != vertex_counts.len() {
        return Err(format!(
            "{patches} patches, the model has {}",
            vertex_counts.len()
        ));
    }
    let mut out = Vec::with_capacity(patches);
    for (k, &expected) in vertex_counts.iter().enumerate() {
        let (vertices, tris, nodes) = (r.u32()? as usize, r.u32()? as usize, r.u32()? as usize);
        if vertices != expected {
            return Err(format!(
                "patch {k}: {vertices} vertices, the model's patch has {expected}"
            ));
        }
        let parts = MtParts {
            triangles: r.items(tris, 12, |r| Ok([r.u32()?, r.u32()?, r.u32()?]))?,
            created_by: r.items(tris, 4, Reader::u32)?,
            removed_by: r.items(tris, 4, Reader::u32)?,
            node_error: r.items(nodes, 8, |r| r.u64().map(f64::from_bits))?,
            vertex_removed_by: r.items(vertices, 4, Reader::u32)?,
            vertex_target: r.items(vertices, 4, Reader::u32)?,
        };
        let h = MtHierarchy::from_parts(parts, vertices).map_err(|e| format!("patch {k}: {e}"))?;
        out.push(h);
    }
    if r.at != bytes.len() {
        return Err(format!("{} bytes after the last patch", bytes.len() - r.at));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::mesh::TriMesh;

    /// Two small built and reduced hierarchies.
    fn hierarchies() -> (Vec<MtHierarchy>, Vec<usize>) {
        let mut out = Vec::new();
        for n in [5u32, 7] {
            let mut m = TriMesh::default();
            for j in 0..=n {
                for i in 0..=n {
                    let (x, y) = (i as f32 * 0.3, j as f32 * 0.3);
                    m.positions
                        .push(glam::Vec3::new(x, y, 0.2 * x.sin() * y.cos()));
                }
            }
            let at = |i: u32, j: u32| j * (n + 1) + i;
            for j in 0..n {
                for i in 0..n {
                    m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                    m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
            let mut h = MtHierarchy::build(&m.positions, &m.triangles);
            h.reduce(3.0);
            out.push(h);
        }
        let counts = out.iter().map(|h| h.vertex_target.len()).collect();
        (out, counts)
    }

    #[test]
    fn a_cache_round_trips_exactly() {
        let (hs, counts) = hierarchies();
        assert!(hs.iter().all(|h| h.node_count() > 5));
        let key = CacheKey::new(b"model", &[1500, 5]);
        let bytes = encode(key, &hs.iter().collect::<Vec<_>>());
        assert_eq!(decode(&bytes, key, &counts).expect("decodes"), hs);
        // Through a directory too.
        let dir = std::env::temp_dir().join(format!("pw-mtc-{}", std::process::id()));
        write(&dir, key, &hs.iter().collect::<Vec<_>>()).expect("writes");
        assert_eq!(read(&dir, key, &counts).expect("reads"), Some(hs));
        let other = CacheKey::new(b"model", &[1500, 6]);
        assert_eq!(read(&dir, other, &counts).expect("no file"), None);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn truncated_flipped_or_foreign_files_are_refused() {
        let (hs, counts) = hierarchies();
        let key = CacheKey::new(b"model", &[1500, 5]);
        let bytes = encode(key, &hs.iter().collect::<Vec<_>>());
        for cut in [
            0,
            7,
            HEADER - 1,
            HEADER,
            HEADER + 5,
            bytes.len() / 2,
            bytes.len() - 1,
        ] {
            assert!(decode(&bytes[..cut], key, &counts).is_err(), "cut at {cut}");
        }
        // Every single flipped bit (a sample of bytes, every bit of them) is caught.
        for at in (0..bytes.len()).step_by(7) {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[at] ^= 1 << bit;
                assert!(decode(&b, key, &counts).is_err(), "flip at {at}.{bit}");
            }
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode(&longer, key, &counts).is_err());
        assert!(decode(&bytes, CacheKey::new(b"model2", &[1500, 5]), &counts).is_err());
        assert!(decode(&bytes, key, &counts[..1]).is_err());
        assert!(decode(&bytes, key, &[counts[0], counts[1] + 1]).is_err());
        assert!(CacheKey::new(b"model", &[1500, 5]) != CacheKey::new(b"model", &[1501, 5]));
    }

    /// A payload whose checksum is right but whose content breaks an invariant (a crafted
    /// or buggy writer) is refused by the structural checks, not trusted.
    #[test]
    fn structurally_broken_hierarchies_are_refused_even_with_a_good_checksum() {
        let (hs, counts) = hierarchies();
        let key = CacheKey::new(b"model", &[]);
        type Breaker = (&'static str, fn(&mut MtHierarchy));
        let breakers: [Breaker; 6] = [
            ("vertex out of range", |h| h.triangles[0][1] = 1_000_000),
            ("creator out of range", |h| h.created_by[3] = 1_000_000),
            ("remover before creator", |h| {
                let t = h
                    .removed_by
                    .iter()
                    .position(|&r| r != crate::mt::NEVER)
                    .unwrap_or(0);
                h.removed_by[t] = h.created_by[t];
            }),
            ("non-monotone errors", |h| {
                let last = h.node_error.len() - 1;
                h.node_error[last] = 0.0;
                h.node_error[1] = 1e9;
            }),
            ("NaN error", |h| h.node_error[1] = f64::NAN),
            ("target out of range", |h| h.vertex_target[0] = 1_000_000),
        ];
        for (what, brk) in breakers {
            let mut broken = hs.clone();
            brk(&mut broken[1]);
            let bytes = encode(key, &broken.iter().collect::<Vec<_>>());
            let err = decode(&bytes, key, &counts).expect_err(what);
            assert!(err.starts_with("patch 1"), "{what}: {err}");
        }
    }
}
