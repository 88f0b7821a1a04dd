//! Cuts of an MT hierarchy (Holst and Schumann, the `holst-reduced-mt-hierarchy` paper,
//! section 3): the triangles whose creator's error is ≤ ε and whose remover's is > ε. The
//! triangles are laid out by arc ([`MtHierarchy::arc_start`]), so a cut is a few static index
//! ranges; a [`CutState`] moves from frame to frame applying or undoing only the nodes between
//! the old and the new ε. Also the vertex queries of a cut (where a vertex went, whether it is
//! alive) and its border loops.

use std::collections::HashMap;

use super::{CutState, MtHierarchy, NEVER};

impl MtHierarchy {
    /// Whether triangle `t` is in the cut for error `eps`.
    pub(crate) fn in_cut(&self, t: usize, eps: f64) -> bool {
        let made = self.node_error[self.created_by[t] as usize];
        // A triangle never removed stays in every cut it is created in, ε = ∞ included.
        let gone = match self.removed_by[t] {
            NEVER => return made <= eps,
            n => self.node_error[n as usize],
        };
        made <= eps && gone > eps
    }

    /// The triangles of the cut for `eps` and the largest error among their creators (the
    /// achieved error, ≤ `eps`).
    pub fn cut(&self, eps: f64, out: &mut Vec<[u32; 3]>) -> f64 {
        out.clear();
        let mut achieved = 0.0f64;
        for t in 0..self.triangles.len() {
            if self.in_cut(t, eps) {
                out.push(self.triangles[t]);
                achieved = achieved.max(self.node_error[self.created_by[t] as usize]);
            }
        }
        achieved
    }

    /// Average triangles per arc.
    pub fn mean_arc_size(&self) -> f64 {
        let arcs = self.arcs();
        if arcs.is_empty() {
            return 0.0;
        }
        arcs.values().sum::<usize>() as f64 / arcs.len() as f64
    }

    /// The finest cut: the original mesh.
    pub fn finest_cut(&self) -> CutState {
        CutState {
            applied: usize::from(!self.order.is_empty()),
            active: self.arc_nodes.iter().map(|&(c, _)| c == 0).collect(),
        }
    }

    /// Moves `cut` to error `eps` from wherever it is, applying or undoing only the nodes in
    /// between; returns how many it applied or undid. The result equals [`MtHierarchy::cut`]
    /// for `eps`. A state of another hierarchy is restarted from the finest cut.
    pub fn move_cut(&self, cut: &mut CutState, eps: f64) -> usize {
        if cut.active.len() != self.arc_nodes.len() || cut.applied == 0 {
            *cut = self.finest_cut();
        }
        let mut moved = 0;
        while cut.applied < self.order.len()
            && self.node_error[self.order[cut.applied] as usize] <= eps
        {
            self.switch(cut, self.order[cut.applied], true);
            cut.applied += 1;
            moved += 1;
        }
        while cut.applied > 1 && self.node_error[self.order[cut.applied - 1] as usize] > eps {
            cut.applied -= 1;
            self.switch(cut, self.order[cut.applied], false);
            moved += 1;
        }
        moved
    }

    fn switch(&self, cut: &mut CutState, node: u32, apply: bool) {
        let n = node as usize;
        for &a in &self.in_arcs[self.in_start[n] as usize..self.in_start[n + 1] as usize] {
            cut.active[a as usize] = !apply;
        }
        for &a in &self.out_arcs[self.out_start[n] as usize..self.out_start[n + 1] as usize] {
            cut.active[a as usize] = apply;
        }
    }

    /// The cut's triangles as ranges `[first, count]` of [`MtHierarchy::triangles`] (adjacent
    /// arcs merged into one range), and the achieved error (the largest creator error).
    pub fn cut_ranges(&self, cut: &CutState, out: &mut Vec<[u32; 2]>) -> f64 {
        out.clear();
        let mut achieved = 0.0f64;
        for (k, &on) in cut.active.iter().enumerate() {
            if !on {
                continue;
            }
            let (start, end) = (self.arc_start[k], self.arc_start[k + 1]);
            achieved = achieved.max(self.node_error[self.arc_nodes[k].0 as usize]);
            match out.last_mut() {
                Some(last) if last[0] + last[1] == start => last[1] += end - start,
                _ => out.push([start, end - start]),
            }
        }
        achieved
    }

    /// The triangle ranges node `node` removes (`created == false`) or creates (`true`):
    /// applying the node replaces the first by the second (an edge collapse, or several merged
    /// by arc collapse); undoing it is the vertex split.
    pub(crate) fn node_ranges(
        &self,
        node: u32,
        created: bool,
    ) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let n = node as usize;
        let (start, arcs) = if created {
            (&self.out_start, &self.out_arcs)
        } else {
            (&self.in_start, &self.in_arcs)
        };
        let list: &[u32] = match (start.get(n), start.get(n + 1)) {
            (Some(&a), Some(&b)) => &arcs[a as usize..b as usize],
            _ => &[],
        };
        list.iter()
            .map(|&a| self.arc_start[a as usize] as usize..self.arc_start[a as usize + 1] as usize)
    }

    /// Where vertex `v` is after the first `applied` nodes of [`MtHierarchy::order`]: the end
    /// of its chain of collapse targets through applied nodes.
    pub(crate) fn vertex_at(&self, v: u32, applied: usize) -> u32 {
        let mut v = v;
        for _ in 0..self.vertex_target.len() {
            match self.vertex_removed_by.get(v as usize) {
                Some(&n) if n != NEVER && (self.rank[n as usize] as usize) < applied => {
                    v = self.vertex_target[v as usize];
                }
                _ => break,
            }
        }
        v
    }

    /// Position of `node` in [`MtHierarchy::order`].
    pub fn rank_of(&self, node: u32) -> usize {
        self.rank[node as usize] as usize
    }

    /// Whether vertex `v` is still a vertex of `cut` (not moved away by an applied node).
    pub(crate) fn vertex_alive(&self, cut: &CutState, v: u32) -> bool {
        match self.vertex_removed_by.get(v as usize) {
            Some(&n) if n != NEVER => self.rank[n as usize] as usize >= cut.applied,
            _ => true,
        }
    }

    /// The border loops of `cut` from the patch's original loops: border vertices only ever
    /// collapse along the border onto a border neighbour, and interior vertices never onto
    /// the border, so the cut's loops are the original ones without the vertices moved away.
    pub(crate) fn cut_borders(
        &self,
        cut: &CutState,
        original: &[Vec<u32>],
        out: &mut Vec<Vec<u32>>,
    ) {
        out.clear();
        for ring in original {
            let kept: Vec<u32> = ring
                .iter()
                .copied()
                .filter(|&v| self.vertex_alive(cut, v))
                .collect();
            if kept.len() >= 2 {
                out.push(kept);
            }
        }
    }

    /// Sorts the triangles by arc and builds the arc ranges, the node order and the arcs of
    /// every node. Arcs are sorted by their creator's place in `order`, then their
    /// remover's, so the arcs a cut draws tend to be adjacent and merge into few ranges.
    pub(super) fn layout(&mut self) {
        let n = self.node_error.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        // Keys are unique (index last), so an unstable sort gives the one order.
        order.sort_unstable_by(|&a, &b| {
            self.node_error[a as usize]
                .total_cmp(&self.node_error[b as usize])
                .then(a.cmp(&b))
        });
        let mut rank = vec![0u32; n];
        for (i, &x) in order.iter().enumerate() {
            rank[x as usize] = i as u32;
        }
        let key = |t: usize| {
            let r = self.removed_by[t];
            (
                rank[self.created_by[t] as usize],
                if r == NEVER {
                    u32::MAX
                } else {
                    rank[r as usize]
                },
            )
        };
        // By arc, then by index (what a stable sort by arc gives), on packed keys.
        let mut keyed: Vec<(u64, u32)> = (0..self.triangles.len())
            .map(|t| {
                let (c, r) = key(t);
                (((c as u64) << 32) | r as u64, t as u32)
            })
            .collect();
        keyed.sort_unstable();
        let idx: Vec<usize> = keyed.iter().map(|&(_, t)| t as usize).collect();
        self.triangles = idx.iter().map(|&t| self.triangles[t]).collect();
        self.created_by = idx.iter().map(|&t| self.created_by[t]).collect();
        self.removed_by = idx.iter().map(|&t| self.removed_by[t]).collect();
        self.arc_start.clear();
        self.arc_nodes.clear();
        for t in 0..self.triangles.len() {
            let arc = (self.created_by[t], self.removed_by[t]);
            if self.arc_nodes.last() != Some(&arc) {
                self.arc_start.push(t as u32);
                self.arc_nodes.push(arc);
            }
        }
        self.arc_start.push(self.triangles.len() as u32);
        let rows = |of: &dyn Fn(&(u32, u32)) -> u32| {
            let mut start = vec![0u32; n + 1];
            for arc in &self.arc_nodes {
                let x = of(arc);
                if x != NEVER {
                    start[x as usize + 1] += 1;
                }
            }
            for i in 0..n {
                start[i + 1] += start[i];
            }
            let mut fill = start.clone();
            let mut list = vec![0u32; start[n] as usize];
            for (k, arc) in self.arc_nodes.iter().enumerate() {
                let x = of(arc);
                if x != NEVER {
                    list[fill[x as usize] as usize] = k as u32;
                    fill[x as usize] += 1;
                }
            }
            (start, list)
        };
        let (out_start, out_arcs) = rows(&|a| a.0);
        let (in_start, in_arcs) = rows(&|a| a.1);
        self.order = order;
        self.rank = rank;
        self.out_start = out_start;
        self.out_arcs = out_arcs;
        self.in_start = in_start;
        self.in_arcs = in_arcs;
    }

    /// Arcs of the DAG: (creator, remover) → triangle count.
    pub fn arcs(&self) -> HashMap<(u32, u32), usize> {
        let mut arcs = HashMap::new();
        for t in 0..self.triangles.len() {
            *arcs
                .entry((self.created_by[t], self.removed_by[t]))
                .or_default() += 1;
        }
        arcs
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::bumpy;
    use super::*;
    use crate::model::mesh::border_loops;

    /// Directed border edges of loops, as a sorted list.
    fn loop_edges(loops: &[Vec<u32>]) -> Vec<(u32, u32)> {
        let mut e: Vec<(u32, u32)> = loops
            .iter()
            .flat_map(|l| (0..l.len()).map(move |k| (l[k], l[(k + 1) % l.len()])))
            .collect();
        e.sort_unstable();
        e
    }

    #[test]
    fn a_moved_cut_equals_the_cut_from_scratch_with_its_ranges_and_borders() {
        let m = bumpy(12);
        let fine = MtHierarchy::build(&m.positions, &m.triangles);
        let original_loops = border_loops(&m.triangles);
        for target in [0.0, 5.0, 20.0] {
            let mut h = fine.clone();
            if target > 0.0 {
                h.reduce(target);
            }
            // Arcs are contiguous and in the triangle order.
            assert_eq!(h.arc_start.len(), h.arc_count() + 1);
            assert_eq!(
                *h.arc_start.last().expect("the end of the last arc") as usize,
                h.triangles.len()
            );
            for k in 0..h.arc_count() {
                for t in h.arc_start[k]..h.arc_start[k + 1] {
                    let t = t as usize;
                    assert_eq!((h.created_by[t], h.removed_by[t]), h.arc_nodes[k]);
                }
            }
            let mut errors = h.node_error.clone();
            errors.sort_by(f64::total_cmp);
            let mut state = h.finest_cut();
            let (mut full, mut ranges, mut from_ranges, mut borders) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            // Up and down and back, in uneven steps, ending past both ends.
            let steps = [0.5, 0.9, 0.1, 0.3, 1.0, 0.0, 0.7, 0.2, 0.95, 0.05];
            for q in steps {
                let eps = errors[((errors.len() - 1) as f64 * q) as usize] * 1.000001;
                h.move_cut(&mut state, eps);
                let achieved = h.cut(eps, &mut full);
                let achieved_ranges = h.cut_ranges(&state, &mut ranges);
                assert_eq!(achieved, achieved_ranges, "{target} at {q}");
                from_ranges.clear();
                for &[first, count] in &ranges {
                    from_ranges
                        .extend_from_slice(&h.triangles[first as usize..(first + count) as usize]);
                }
                let (mut a, mut b) = (full.clone(), from_ranges.clone());
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b, "{target}: moved cut differs at {q}");
                // Merged ranges: never more than arcs, no two adjacent.
                assert!(ranges.windows(2).all(|w| w[0][0] + w[0][1] < w[1][0]));
                h.cut_borders(&state, &original_loops, &mut borders);
                assert_eq!(
                    loop_edges(&borders),
                    loop_edges(&border_loops(&full)),
                    "{target}: borders differ at {q}"
                );
            }
        }
    }
}
