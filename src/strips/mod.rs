//! Triangle strips: the encoding shared by every stripifier, and the stripifiers.
//!
//! - [`tunnel`]: Stewart's tunneling (static meshes, and incremental repair after edge
//!   collapses / vertex splits) — the `stewart-tunneling-strips` paper.
//! - [`cut_strips`]: tunneling strips kept while an MT hierarchy's cut moves node by node.
//! - [`mts`]: Belmonte et al.'s multiresolution triangle strips for a patch's MT hierarchy —
//!   the `belmonte-multiresolution-strips` paper.
//! - Static strips per arc of an MT hierarchy (Holst §5.2) are [`arc_strips`].
//!
//! A strip is drawn with wgpu's `TriangleStrip` topology: window `j` of a strip is the
//! triangle `(s_j, s_j+1, s_j+2)` when `j` is even and `(s_j+1, s_j, s_j+2)` when odd, so every
//! triangle keeps its orientation. A *swap* (a strip turning the same way twice) costs one
//! repeated vertex, which makes one zero-area window; strips are joined by the primitive
//! restart index [`RESTART`] (`strip_index_format: Uint32`), or — where primitive restart
//! is unreliable — by zero-area windows ([`join_degenerate`], [`Join`]).

pub mod cut_strips;
pub mod mts;
pub mod store;
pub mod tunnel;

pub use store::StripStore;

use crate::mt::MtHierarchy;

/// Primitive restart index for `u32` strip indices.
pub const RESTART: u32 = u32::MAX;

/// Strips of a triangle set, joined by [`RESTART`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StripIndices {
    pub indices: Vec<u32>,
    /// Number of strips.
    pub strips: usize,
    /// Triangles the strips draw.
    pub triangles: usize,
}

impl StripIndices {
    /// Indices sent per triangle drawn (restarts and swaps included); a list costs 3.
    pub fn indices_per_triangle(&self) -> f64 {
        if self.triangles == 0 {
            0.0
        } else {
            self.indices.len() as f64 / self.triangles as f64
        }
    }
}

/// How the strips of one index buffer are joined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Join {
    /// The primitive restart index [`RESTART`]: one index per join.
    #[default]
    Restart,
    /// Zero-area windows ([`join_degenerate`]): two or three indices per join, for backends
    /// whose primitive restart draws wrong triangles (wgpu's GL backend on llvmpipe).
    Degenerate,
}

impl std::str::FromStr for Join {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "restart" => Ok(Join::Restart),
            "degenerate" => Ok(Join::Degenerate),
            _ => Err(format!(
                "strip joins must be restart or degenerate, not {s:?}"
            )),
        }
    }
}

/// Rewrites strips joined by [`RESTART`] as one strip joined by zero-area windows: between a
/// strip ending in `a` and the next one starting with `b`, the indices `a, b` — and `b` once
/// more when the next strip would start at an odd index — so every strip starts at an even
/// index and keeps its orientation. `starts` (ascending positions in `indices`, e.g. the
/// per-arc block boundaries of [`arc_strips`]) are mapped to the rewritten buffer: each is
/// even (but the end) and the join before it belongs to the range in front, so a draw of any
/// `starts[i]..starts[j]` draws exactly the triangles the same range of `indices` draws.
pub fn join_degenerate(indices: &[u32], starts: &mut [u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(indices.len() + indices.len() / 8);
    let mut next = 0; // first entry of `starts` not mapped yet
    let mut pos = 0usize;
    for strip in indices.split(|&i| i == RESTART) {
        let begin = pos;
        pos += strip.len() + 1;
        let Some((&first, _)) = strip.split_first() else {
            continue;
        };
        if let Some(&last) = out.last() {
            out.extend([last, first]);
            if out.len() % 2 == 1 {
                out.push(first);
            }
        }
        while next < starts.len() && starts[next] as usize <= begin {
            starts[next] = out.len() as u32;
            next += 1;
        }
        out.extend_from_slice(strip);
    }
    for s in &mut starts[next..] {
        *s = out.len() as u32;
    }
    out
}

/// Whether `a` and `b` are the same triangle with the same orientation.
pub(crate) fn same_oriented(a: [u32; 3], b: [u32; 3]) -> bool {
    a == b || a == [b[1], b[2], b[0]] || a == [b[2], b[0], b[1]]
}

/// `t` rotated so its smallest index comes first (orientation kept): a key for comparing
/// oriented triangle sets.
pub(crate) fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

fn degenerate(t: [u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

/// The third vertex of `t` when `t` contains both `p` and `q`.
fn third(t: [u32; 3], p: u32, q: u32) -> Option<u32> {
    let has = |x| t.contains(&x);
    (has(p) && has(q) && p != q)
        .then(|| t.into_iter().find(|&x| x != p && x != q))
        .flatten()
}

/// `t` rotated so that its last two vertices are the edge it shares with `next`.
fn rotate_to_exit(t: [u32; 3], next: [u32; 3]) -> Option<[u32; 3]> {
    (0..3)
        .map(|k| [t[k], t[(k + 1) % 3], t[(k + 2) % 3]])
        .find(|r| next.contains(&r[1]) && next.contains(&r[2]))
}

/// The triangle window `j` of a strip draws (with its orientation).
fn window(j: usize, a: u32, b: u32, c: u32) -> [u32; 3] {
    if j.is_multiple_of(2) {
        [a, b, c]
    } else {
        [b, a, c]
    }
}

/// Appends the strips of a path of triangles to `out` (a [`RESTART`] before each strip but
/// the first of `out`); returns the number of strips written. Consecutive triangles that share
/// an edge continue the strip — with one repeated vertex when the strip turns the same way
/// twice (a swap); a triangle that shares no edge with the previous one, or whose orientation
/// the strip's parity would flip, starts a new strip. Triangles with a repeated index draw
/// nothing and are dropped.
pub fn encode_path(path: &[[u32; 3]], out: &mut Vec<u32>) -> usize {
    let mut strips = 0;
    let mut i = 0;
    let path: Vec<[u32; 3]> = path.iter().copied().filter(|&t| !degenerate(t)).collect();
    while i < path.len() {
        if !out.is_empty() && out.last() != Some(&RESTART) {
            out.push(RESTART);
        }
        strips += 1;
        let start = out.len();
        let first = path[i];
        let first = path
            .get(i + 1)
            .and_then(|&n| rotate_to_exit(first, n))
            .unwrap_or(first);
        out.extend(first);
        i += 1;
        while i < path.len() {
            let t = path[i];
            let (p, q) = (out[out.len() - 2], out[out.len() - 1]);
            let Some(n) = third(t, p, q) else { break };
            let j = out.len() - 2 - start;
            let swap = path.get(i + 1).is_some_and(|nx| {
                !(nx.contains(&q) && nx.contains(&n)) && nx.contains(&p) && nx.contains(&n)
            });
            // With a swap the window (q, p, n) is drawn one position later: same orientation
            // as (p, q, n) at position j.
            if !same_oriented(window(j, p, q, n), t) {
                break;
            }
            if swap {
                out.push(p);
            }
            out.push(n);
            i += 1;
        }
    }
    strips
}

/// The triangles a `TriangleStrip` index buffer with [`RESTART`] draws, with the orientation
/// the rasterizer gives them; zero-area windows (swaps) are skipped.
pub fn decode(indices: &[u32]) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for strip in indices.split(|&i| i == RESTART) {
        for j in 0..strip.len().saturating_sub(2) {
            let t = window(j, strip[j], strip[j + 1], strip[j + 2]);
            if !degenerate(t) {
                out.push(t);
            }
        }
    }
    out
}

/// Whether `a` and `b` hold the same oriented triangles, each as often.
pub fn same_triangles(a: &[[u32; 3]], b: &[[u32; 3]]) -> bool {
    let key = |v: &[[u32; 3]]| {
        let mut k: Vec<[u32; 3]> = v.iter().map(|&t| canonical(t)).collect();
        k.sort_unstable();
        k
    };
    a.len() == b.len() && key(a) == key(b)
}

/// Static strips per arc of a hierarchy (Holst §5.2): every arc's triangles stripified by
/// tunneling on their own, the arcs' strips concatenated in arc order, each arc's block ending
/// in a [`RESTART`]. Returns the indices and, per arc boundary, the first index of the arc
/// (`starts[k]..starts[k + 1]` is arc `k`), so a run of adjacent arcs is one index range.
pub fn arc_strips(h: &MtHierarchy, opts: &tunnel::TunnelOptions) -> (StripIndices, Vec<u32>) {
    let mut out = StripIndices::default();
    let mut starts = Vec::with_capacity(h.arc_start.len());
    let mut strip = tunnel::TunnelStrips::new(opts.clone());
    for k in 0..h.arc_nodes.len() {
        starts.push(out.indices.len() as u32);
        let tris = &h.triangles[h.arc_start[k] as usize..h.arc_start[k + 1] as usize];
        strip.reset(tris);
        strip.optimize();
        let before = out.indices.len();
        out.strips += strip.write_indices(&mut out.indices);
        out.triangles += tris.len();
        if out.indices.len() > before {
            out.indices.push(RESTART);
        }
    }
    starts.push(out.indices.len() as u32);
    (out, starts)
}
