//! Strips of an MT hierarchy's cut kept by tunneling while the cut moves node by node: the
//! view-dependent use of A. James Stewart, "Tunneling for Triangle Strips in Continuous
//! Level-of-Detail Meshes" (Graphics Interface 2001, §4.2; `stewart-tunneling-strips`), on
//! Holst and Schumann's MT hierarchy (`crate::mt`). Every node applied is an edge collapse and
//! every node undone a vertex split, repaired at once by [`TunnelStrips::replace`]; the strips
//! are always those of the cut after [`CutStrips::applied`] nodes of the hierarchy's order.

use super::tunnel::{NONE, TunnelOptions, TunnelStrips};

/// Strips of an MT hierarchy's cut kept by tunneling while the cut moves node by node — the
/// paper's view-dependent use (§4.2): applying a node is an edge collapse (its removed
/// triangles out, its created ones in), undoing it a vertex split; each is repaired at once.
#[derive(Clone, Debug)]
pub struct CutStrips {
    pub strips: TunnelStrips,
    /// Slot of every hierarchy triangle in the cut (`NONE` otherwise).
    slot_of: Vec<u32>,
    applied: usize,
    removed: Vec<u32>,
    added: Vec<[u32; 3]>,
    added_ids: Vec<u32>,
    slots: Vec<u32>,
}

impl CutStrips {
    /// Stripifies the finest cut (the original triangles) of `h`.
    pub fn new(h: &crate::mt::MtHierarchy, opts: TunnelOptions) -> CutStrips {
        let mut slot_of = vec![NONE; h.triangles.len()];
        let mut tris = Vec::new();
        for (t, tri) in h.triangles.iter().enumerate() {
            if h.created_by[t] == 0 {
                slot_of[t] = tris.len() as u32;
                tris.push(*tri);
            }
        }
        CutStrips {
            strips: TunnelStrips::build(&tris, opts),
            slot_of,
            applied: usize::from(!h.order.is_empty()),
            removed: Vec::new(),
            added: Vec::new(),
            added_ids: Vec::new(),
            slots: Vec::new(),
        }
    }

    /// Nodes of `h.order` applied (the original mesh counts as one).
    pub fn applied(&self) -> usize {
        self.applied
    }

    /// Applies the next node (`collapse = true`) or undoes the last one; returns false at
    /// either end of the hierarchy.
    pub fn step(&mut self, h: &crate::mt::MtHierarchy, collapse: bool) -> bool {
        let node = if collapse {
            if self.applied >= h.order.len() {
                return false;
            }
            h.order[self.applied]
        } else {
            if self.applied <= 1 {
                return false;
            }
            h.order[self.applied - 1]
        };
        self.removed.clear();
        self.added.clear();
        self.added_ids.clear();
        for r in h.node_ranges(node, !collapse) {
            for t in r {
                if self.slot_of[t] != NONE {
                    self.removed.push(self.slot_of[t]);
                    self.slot_of[t] = NONE;
                }
            }
        }
        for r in h.node_ranges(node, collapse) {
            for t in r {
                self.added.push(h.triangles[t]);
                self.added_ids.push(t as u32);
            }
        }
        self.slots.clear();
        self.strips
            .replace(&self.removed, &self.added, &mut self.slots);
        for (&t, &s) in self.added_ids.iter().zip(&self.slots) {
            self.slot_of[t as usize] = s;
        }
        if collapse {
            self.applied += 1;
        } else {
            self.applied -= 1;
        }
        true
    }

    /// Moves to `applied` nodes, one collapse or split at a time; returns the steps taken.
    pub fn move_to(&mut self, h: &crate::mt::MtHierarchy, applied: usize) -> usize {
        let mut steps = 0;
        while self.applied < applied && self.step(h, true) {
            steps += 1;
        }
        while self.applied > applied.max(1) && self.step(h, false) {
            steps += 1;
        }
        steps
    }
}
