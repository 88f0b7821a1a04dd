//! Multiresolution triangle strips (MTS), after Belmonte, Remolar, Ribelles, Chover and
//! Fernández, "Efficiently using connectivity information between triangles in a mesh for
//! real-time rendering" (2004; `belmonte-multiresolution-strips`).
//!
//! One multiresolution strip holds a strip of the finest mesh and every coarser version of
//! it at once: a graph whose nodes are vertex occurrences and whose arcs carry the levels of
//! detail at which they may be traversed (the paper's `ColumnNode` / `RowNode` with `res`).
//! Here the levels are the prefixes of a patch hierarchy's node order
//! ([`MtHierarchy::order`]: level k = the first k nodes applied = the cut for the k-th error),
//! and the graph is stored as the list of occurrences in strip order, each with the interval
//! `[lo, hi)` of levels it belongs to: the arc from one occurrence to the next one valid at
//! a level is the paper's compatible arc, and restarts inside a strip are its `-1`/`-2`
//! special nodes (the strip split into sub-strips).
//!
//! Building (§3.1): the finest cut is stripified by tunneling; for every node in order, each
//! strip holding a vertex the node removes gets that vertex replaced by where the collapse
//! moved it, the triangles left are encoded again (degenerate ones dropped, swaps and
//! restarts where the strip now needs them), and only the changed middle of the sequence gets
//! new occurrences (the common prefix and suffix keep theirs, their intervals growing).
//!
//! Recovery (§3.2) walks each strip's occurrences and emits those valid at the level.
//! Coherence (§4): each strip keeps the sequence it last extracted and the interval of
//! levels over which it stays valid (`minRes`, `maxRes`: the nearest bounds of the
//! occurrences around the level), so a new level re-walks only the strips that changed.

use super::{RESTART, decode, encode_path};
use crate::mt::MtHierarchy;

/// One occurrence of a vertex (or a restart) in a multiresolution strip, valid for the
/// levels `lo..hi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Occurrence {
    v: u32,
    lo: u32,
    hi: u32,
}

/// One multiresolution strip, with its coherence cache.
#[derive(Clone, Debug, Default)]
struct MStrip {
    occ: Vec<Occurrence>,
    /// Last extracted sequence and the levels over which it stays valid.
    cached: Vec<u32>,
    valid: (u32, u32),
}

/// The multiresolution strips of one patch hierarchy.
#[derive(Clone, Debug, Default)]
pub struct MultiresStrips {
    strips: Vec<MStrip>,
    levels: u32,
}

/// What one extraction did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Extraction {
    /// Strips walked again (their cached sequence was not valid at the level).
    pub walked: usize,
    /// Occurrences visited by those walks (compatible or not).
    pub visited: usize,
    /// Indices written.
    pub indices: usize,
}

impl MultiresStrips {
    /// Builds the strips of every level of `h` from a tunneling stripification of its finest
    /// cut.
    pub fn build(h: &MtHierarchy, opts: &super::tunnel::TunnelOptions) -> MultiresStrips {
        let finest: Vec<[u32; 3]> = h
            .triangles
            .iter()
            .zip(&h.created_by)
            .filter(|&(_, &c)| c == 0)
            .map(|(t, _)| *t)
            .collect();
        let levels = h.order.len().max(1) as u32;
        let open = u32::MAX;
        // Current sequence of every strip, with the occurrence index of every position.
        let mut seqs: Vec<Vec<u32>> = Vec::new();
        let mut at: Vec<Vec<usize>> = Vec::new();
        let mut strips: Vec<MStrip> = Vec::new();
        let n_vertices = h.vertex_target.len();
        let mut holders: Vec<Vec<u32>> = vec![Vec::new(); n_vertices];
        let all = super::tunnel::stripify(&finest, opts).indices;
        for seq in all.split(|&i| i == RESTART).filter(|s| !s.is_empty()) {
            let k = strips.len() as u32;
            for &v in seq {
                if let Some(list) = holders.get_mut(v as usize) {
                    list.push(k);
                }
            }
            strips.push(MStrip {
                occ: seq
                    .iter()
                    .map(|&v| Occurrence { v, lo: 1, hi: open })
                    .collect(),
                ..Default::default()
            });
            at.push((0..seq.len()).collect());
            seqs.push(seq.to_vec());
        }
        // Vertices each node removes.
        let mut removes: Vec<Vec<u32>> = vec![Vec::new(); h.node_count()];
        for (v, &n) in h.vertex_removed_by.iter().enumerate() {
            if n != crate::mt::NEVER {
                removes[n as usize].push(v as u32);
            }
        }
        let mut touched: Vec<u32> = Vec::new();
        let mut tris: Vec<[u32; 3]> = Vec::new();
        let mut fresh: Vec<u32> = Vec::new();
        for level in 2..=levels {
            let node = h.order[level as usize - 1];
            touched.clear();
            for &u in &removes[node as usize] {
                touched.extend(holders[u as usize].iter().copied());
            }
            touched.sort_unstable();
            touched.dedup();
            for &k in &touched {
                let k = k as usize;
                let old = &seqs[k];
                let subst: Vec<u32> = old
                    .iter()
                    .map(|&v| {
                        if v == RESTART {
                            v
                        } else {
                            h.vertex_at(v, level as usize)
                        }
                    })
                    .collect();
                if subst == *old {
                    continue;
                }
                tris.clear();
                tris.extend(decode(&subst));
                fresh.clear();
                encode_path(&tris, &mut fresh);
                // Common prefix and suffix keep their occurrences.
                let p = old.iter().zip(&fresh).take_while(|(a, b)| a == b).count();
                let max_s = old.len().min(fresh.len()) - p;
                let s = old
                    .iter()
                    .rev()
                    .zip(fresh.iter().rev())
                    .take(max_s)
                    .take_while(|(a, b)| a == b)
                    .count();
                let strip = &mut strips[k];
                for &o in &at[k][p..old.len() - s] {
                    strip.occ[o].hi = level;
                }
                // New occurrences go after the last old one of the middle (or of the prefix).
                let insert_at = if old.len() - s > 0 {
                    at[k][old.len() - s - 1] + 1
                } else {
                    0
                };
                let new_mid = &fresh[p..fresh.len() - s];
                strip.occ.splice(
                    insert_at..insert_at,
                    new_mid.iter().map(|&v| Occurrence {
                        v,
                        lo: level,
                        hi: open,
                    }),
                );
                // Re-index positions (occurrence indices after the insertion point shift).
                let shift = new_mid.len();
                let mut idx: Vec<usize> = Vec::with_capacity(fresh.len());
                idx.extend(
                    at[k][..p]
                        .iter()
                        .map(|&o| if o >= insert_at { o + shift } else { o }),
                );
                idx.extend(insert_at..insert_at + shift);
                idx.extend(
                    at[k][old.len() - s..]
                        .iter()
                        .map(|&o| if o >= insert_at { o + shift } else { o }),
                );
                at[k] = idx;
                for &v in new_mid {
                    if let Some(list) = holders.get_mut(v as usize)
                        && list.last() != Some(&(k as u32))
                    {
                        list.push(k as u32);
                    }
                }
                seqs[k] = fresh.clone();
            }
        }
        for s in &mut strips {
            s.valid = (1, 0); // empty interval: nothing cached yet
        }
        MultiresStrips { strips, levels }
    }

    /// Number of levels (nodes in the hierarchy's order).
    pub fn levels(&self) -> usize {
        self.levels as usize
    }

    /// Occurrences stored (the size of the strip graphs).
    pub fn occurrences(&self) -> usize {
        self.strips.iter().map(|s| s.occ.len()).sum()
    }

    /// Level of an error: the number of nodes of `h.order` with error ≤ `eps`.
    pub fn level_for(h: &MtHierarchy, eps: f64) -> usize {
        h.order
            .partition_point(|&n| h.node_error[n as usize] <= eps)
            .max(1)
    }

    /// The strips at `level` (1 = finest), joined by [`RESTART`], into `out`. With
    /// `coherent`, strips whose cached sequence is still valid are copied, not walked.
    pub fn extract(&mut self, level: usize, coherent: bool, out: &mut Vec<u32>) -> Extraction {
        out.clear();
        let lv = level.clamp(1, self.levels as usize) as u32;
        let mut ex = Extraction::default();
        for s in &mut self.strips {
            let hit = coherent && s.valid.0 <= lv && lv < s.valid.1;
            if !hit {
                ex.walked += 1;
                ex.visited += s.occ.len();
                s.cached.clear();
                let (mut min_res, mut max_res) = (0u32, u32::MAX);
                for o in &s.occ {
                    if o.lo <= lv && lv < o.hi {
                        s.cached.push(o.v);
                        max_res = max_res.min(o.hi);
                        min_res = min_res.max(o.lo);
                    } else if o.hi <= lv {
                        min_res = min_res.max(o.hi);
                    } else {
                        max_res = max_res.min(o.lo);
                    }
                }
                // Restarts at either end of a sub-sequence draw nothing: trim them.
                while s.cached.last() == Some(&RESTART) {
                    s.cached.pop();
                }
                let lead = s.cached.iter().take_while(|&&v| v == RESTART).count();
                s.cached.drain(..lead);
                s.valid = (min_res, max_res);
            }
            if s.cached.is_empty() {
                continue;
            }
            if !out.is_empty() {
                out.push(RESTART);
            }
            out.extend_from_slice(&s.cached);
        }
        ex.indices = out.len();
        ex
    }
}
