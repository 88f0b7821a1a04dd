//! Reducing an MT hierarchy by arc collapses (Holst and Schumann, the
//! `holst-reduced-mt-hierarchy` paper, section 4): greedy by the paper's weight, refused when
//! another path joins the arc's nodes, arcs from the original mesh and to "never removed" kept;
//! then renumbering in topological order and the breadth-first error adjustment (section 4.2)
//! that keeps every cut within its Hausdorff ε.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use super::{MtHierarchy, NEVER};
use crate::util::IntMap;

impl MtHierarchy {
    /// Reduces the hierarchy by arc collapses (Holst, section 4.1) until arcs hold `target`
    /// triangles on average (or no arc can be collapsed), then repairs node errors (section
    /// 4.2). Returns the number of collapses.
    ///
    /// An arc collapse merges the arc's creator c and remover r into one node (the arc's
    /// triangles, created and removed at once, disappear); arcs from the same node into c and
    /// r, and from c and r into the same node, merge into larger arcs. It is refused when
    /// another path joins c to r (a cycle would form). Greedy order by the paper's weight
    /// `w(a) = |p_a| · e_diff(a) · ps_rel(a) / adj(a)` with `e_diff = max(e_r, μ) / max(e_c, μ)`,
    /// μ = (smallest non-zero node error)/10, `ps_rel` the mean size of the arc pairs that
    /// merge and `adj` the share of those pairs whose triangles touch. Arcs from the original
    /// mesh (node 0) and to "never removed" are kept, so the finest and the coarsest levels
    /// stay exact.
    ///
    /// Errors: the merged node takes the larger error (e_r), so its triangles are never drawn
    /// for an ε below their Hausdorff error; a node removing triangles of the merged node may
    /// then have a smaller error than it, which the breadth-first adjustment repairs by raising
    /// it (and what follows it) — the Hausdorff bound of every cut still holds.
    pub fn reduce(&mut self, target: f64) -> usize {
        Reducer::new(self).run(self, target, f64::INFINITY)
    }

    /// [`MtHierarchy::reduce`], refusing every arc collapse whose remover's error exceeds its
    /// creator's by more than the factor `max_error_ratio` (≥ 1): the merged node takes the
    /// larger error, so each merge delays the finer node's triangles to a coarser ε, and
    /// unlimited merges to 5 triangles per arc made the bunny's ½-pixel cuts 3–6× larger
    /// than the unreduced hierarchy's (`examples/mt_breakdown`). Stops where no allowed arc
    /// is left, below `target` if need be.
    pub fn reduce_within(&mut self, target: f64, max_error_ratio: f64) -> usize {
        Reducer::new(self).run(self, target, max_error_ratio.max(1.0))
    }
}

/// The triangles of an arc and their vertices (sorted, each once), so that whether two arcs
/// touch is a merge of two short lists.
#[derive(Clone, Debug, Default)]
struct ArcTriangles {
    tris: Vec<u32>,
    vertices: Vec<u32>,
}

impl ArcTriangles {
    /// Adds triangle `t`; [`ArcTriangles::index`] must follow before `vertices` is read.
    fn push(&mut self, h: &MtHierarchy, t: u32) {
        self.tris.push(t);
        self.vertices.extend(h.triangles[t as usize]);
    }

    fn index(&mut self) {
        self.vertices.sort_unstable();
        self.vertices.dedup();
    }

    /// Takes in the triangles of another arc.
    fn append(&mut self, mut o: ArcTriangles) {
        self.tris.append(&mut o.tris);
        let mut merged = Vec::with_capacity(self.vertices.len() + o.vertices.len());
        let (a, b) = (&self.vertices, &o.vertices);
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            match a[i].cmp(&b[j]) {
                Ordering::Less => {
                    merged.push(a[i]);
                    i += 1;
                }
                Ordering::Greater => {
                    merged.push(b[j]);
                    j += 1;
                }
                Ordering::Equal => {
                    merged.push(a[i]);
                    i += 1;
                    j += 1;
                }
            }
        }
        merged.extend_from_slice(&a[i..]);
        merged.extend_from_slice(&b[j..]);
        self.vertices = merged;
    }
}

/// Whether a triangle of `a` shares a vertex with a triangle of `b`: their sorted vertex
/// lists walked together (or the shorter one's looked up in the much longer one).
fn touch(a: &ArcTriangles, b: &ArcTriangles) -> bool {
    let (mut a, mut b) = (a.vertices.as_slice(), b.vertices.as_slice());
    if a.len() > b.len() {
        std::mem::swap(&mut a, &mut b);
    }
    if a.len() * 16 < b.len() {
        return a.iter().any(|v| b.binary_search(v).is_ok());
    }
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            Ordering::Less => i += 1,
            Ordering::Greater => j += 1,
            Ordering::Equal => return true,
        }
    }
    false
}

/// Marks with generations: `mark[x] == generation` means marked, so clearing is free.
#[derive(Default)]
struct Marks {
    mark: Vec<u32>,
    generation: u32,
}

impl Marks {
    fn new(n: usize) -> Marks {
        Marks {
            mark: vec![0; n],
            generation: 0,
        }
    }

    fn fresh(&mut self) -> u32 {
        if self.generation == u32::MAX {
            self.mark.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
        self.generation
    }
}

/// A small set of node ids as a sorted vector: the sets of successors and predecessors hold a
/// handful each, where a vector beats a B-tree at every operation; iteration is in increasing
/// order, as a `BTreeSet`'s.
#[derive(Clone, Debug, Default)]
struct SortedSet(Vec<u32>);

impl SortedSet {
    fn insert(&mut self, x: u32) {
        if let Err(at) = self.0.binary_search(&x) {
            self.0.insert(at, x);
        }
    }

    fn remove(&mut self, x: u32) {
        if let Ok(at) = self.0.binary_search(&x) {
            self.0.remove(at);
        }
    }

    fn iter(&self) -> std::slice::Iter<'_, u32> {
        self.0.iter()
    }

    /// The elements of both, increasing.
    fn intersection<'a>(&'a self, o: &'a SortedSet) -> impl Iterator<Item = u32> + 'a {
        let (mut i, mut j) = (0, 0);
        std::iter::from_fn(move || {
            while i < self.0.len() && j < o.0.len() {
                match self.0[i].cmp(&o.0[j]) {
                    Ordering::Less => i += 1,
                    Ordering::Greater => j += 1,
                    Ordering::Equal => {
                        i += 1;
                        j += 1;
                        return Some(self.0[i - 1]);
                    }
                }
            }
            None
        })
    }
}

impl<'a> IntoIterator for &'a SortedSet {
    type Item = &'a u32;
    type IntoIter = std::slice::Iter<'a, u32>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

/// Arc-collapse state: nodes merged by union-find, arcs as triangle lists.
struct Reducer {
    parent: Vec<u32>,
    arcs: IntMap<(u32, u32), ArcTriangles>,
    /// Successors and predecessors of every representative node.
    succ: Vec<SortedSet>,
    pred: Vec<SortedSet>,
    version: Vec<u32>,
    mu: f64,
    /// Largest ratio of the errors of the two nodes an arc collapse may merge.
    max_ratio: f64,
    /// Triangles in all arcs, and the number of arcs (for the mean arc size).
    arc_triangles: usize,
    /// Depth-first search scratch: nodes seen and the stack.
    seen: Marks,
    stack: Vec<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct ArcCandidate {
    weight: f64,
    arc: (u32, u32),
    versions: (u32, u32),
}
impl Eq for ArcCandidate {}
impl Ord for ArcCandidate {
    fn cmp(&self, o: &Self) -> Ordering {
        o.weight
            .total_cmp(&self.weight)
            .then_with(|| o.arc.cmp(&self.arc))
    }
}
impl PartialOrd for ArcCandidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Reducer {
    fn new(h: &MtHierarchy) -> Reducer {
        let n = h.node_error.len();
        let mut arcs: IntMap<(u32, u32), ArcTriangles> = IntMap::default();
        let mut succ = vec![SortedSet::default(); n];
        let mut pred = vec![SortedSet::default(); n];
        for t in 0..h.triangles.len() {
            let (c, r) = (h.created_by[t], h.removed_by[t]);
            arcs.entry((c, r)).or_default().push(h, t as u32);
            if r != NEVER {
                succ[c as usize].insert(r);
                pred[r as usize].insert(c);
            }
        }
        for arc in arcs.values_mut() {
            arc.index();
        }
        let min_nonzero = h
            .node_error
            .iter()
            .copied()
            .filter(|&e| e > 0.0)
            .fold(f64::INFINITY, f64::min);
        Reducer {
            parent: (0..n as u32).collect(),
            arc_triangles: h.triangles.len(),
            arcs,
            succ,
            pred,
            version: vec![0; n],
            max_ratio: f64::INFINITY,
            seen: Marks::new(n),
            stack: Vec::new(),
            mu: if min_nonzero.is_finite() {
                min_nonzero / 10.0
            } else {
                1e-30
            },
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }

    fn collapsible(&self, (c, r): (u32, u32)) -> bool {
        c != 0 && r != NEVER && c != r
    }

    /// Whether a path other than the arc itself joins `c` to `r`.
    fn other_path(&mut self, c: u32, r: u32) -> bool {
        let mut stack = std::mem::take(&mut self.stack);
        stack.clear();
        stack.extend(self.succ[c as usize].iter().copied().filter(|&x| x != r));
        let g = self.seen.fresh();
        let mut found = false;
        while let Some(x) = stack.pop() {
            if x == r {
                found = true;
                break;
            }
            // (Merged nodes break creation order, so no pruning by index.)
            if self.seen.mark[x as usize] == g {
                continue;
            }
            self.seen.mark[x as usize] = g;
            stack.extend(self.succ[x as usize].iter().copied());
        }
        self.stack = stack;
        found
    }

    /// The paper's weight of collapsing arc (c, r) (small first), `None` if not allowed.
    fn weight(&mut self, h: &MtHierarchy, (c, r): (u32, u32)) -> Option<f64> {
        if !self.collapsible((c, r)) {
            return None;
        }
        let size = self.arcs.get(&(c, r))?.tris.len() as f64;
        let e = |n: u32| h.node_error[n as usize].max(self.mu);
        let e_diff = e(r) / e(c);
        if e_diff.max(1.0 / e_diff) > self.max_ratio {
            return None;
        }
        // Arc pairs that merge: common predecessors and common successors of c and r.
        let (mut pairs, mut ps, mut touching) = (0usize, 0usize, 0usize);
        let mut pair = |a: &ArcTriangles, b: &ArcTriangles| {
            pairs += 1;
            ps += a.tris.len() + b.tris.len();
            if touch(a, b) {
                touching += 1;
            }
        };
        for x in self.pred[c as usize].intersection(&self.pred[r as usize]) {
            if let (Some(a), Some(b)) = (self.arcs.get(&(x, c)), self.arcs.get(&(x, r))) {
                pair(a, b);
            }
        }
        for y in self.succ[c as usize].iter().copied().chain([NEVER]) {
            if y == r {
                continue;
            }
            if let (Some(a), Some(b)) = (self.arcs.get(&(c, y)), self.arcs.get(&(r, y))) {
                pair(a, b);
            }
        }
        if pairs == 0 {
            // Nothing merges: the collapse would not enlarge any arc.
            return None;
        }
        let ps_rel = ps as f64 / pairs as f64;
        if touching == 0 {
            return None;
        }
        let adj = touching as f64 / pairs as f64;
        Some(size * e_diff * ps_rel / adj)
    }

    fn push(&mut self, h: &MtHierarchy, arc: (u32, u32), heap: &mut BinaryHeap<ArcCandidate>) {
        if let Some(weight) = self.weight(h, arc) {
            heap.push(ArcCandidate {
                weight,
                arc,
                versions: (self.version[arc.0 as usize], self.version[arc.1 as usize]),
            });
        }
    }

    fn mean_size(&self) -> f64 {
        self.arc_triangles as f64 / self.arcs.len().max(1) as f64
    }

    fn run(mut self, h: &mut MtHierarchy, target: f64, max_ratio: f64) -> usize {
        self.max_ratio = max_ratio;
        let mut heap = BinaryHeap::new();
        let keys: Vec<(u32, u32)> = {
            let mut k: Vec<_> = self.arcs.keys().copied().collect();
            k.sort_unstable();
            k
        };
        for arc in keys {
            self.push(h, arc, &mut heap);
        }
        let mut collapses = 0;
        while self.mean_size() < target {
            let Some(cand) = heap.pop() else { break };
            let (c, r) = cand.arc;
            if cand.versions != (self.version[c as usize], self.version[r as usize])
                || !self.arcs.contains_key(&(c, r))
                || self.other_path(c, r)
            {
                continue;
            }
            self.merge(h, c, r);
            collapses += 1;
            // Re-weigh the arcs at the merged node.
            let m = r;
            let around: Vec<(u32, u32)> = self.pred[m as usize]
                .iter()
                .map(|&x| (x, m))
                .chain(self.succ[m as usize].iter().map(|&y| (m, y)))
                .collect();
            for arc in around {
                self.push(h, arc, &mut heap);
            }
        }
        self.finish(h);
        collapses
    }

    /// Merges node `c` into node `r` (the arc (c, r) disappears).
    fn merge(&mut self, h: &mut MtHierarchy, c: u32, r: u32) {
        self.parent[c as usize] = r;
        h.node_error[r as usize] = h.node_error[r as usize].max(h.node_error[c as usize]);
        self.version[c as usize] += 1;
        self.version[r as usize] += 1;
        // The arc's triangles are created and removed at once: never drawn.
        if let Some(gone) = self.arcs.remove(&(c, r)) {
            self.arc_triangles -= gone.tris.len();
            for t in gone.tris {
                h.created_by[t as usize] = r;
                h.removed_by[t as usize] = r;
            }
        }
        self.succ[c as usize].remove(r);
        self.pred[r as usize].remove(c);
        // Arcs into c now go into r.
        let preds: Vec<u32> = std::mem::take(&mut self.pred[c as usize]).0;
        for x in preds {
            if let Some(arc) = self.arcs.remove(&(x, c)) {
                for &t in &arc.tris {
                    h.removed_by[t as usize] = r;
                }
                self.arcs.entry((x, r)).or_default().append(arc);
            }
            self.succ[x as usize].remove(c);
            self.succ[x as usize].insert(r);
            self.pred[r as usize].insert(x);
            self.version[x as usize] += 1;
        }
        // Arcs out of c now come out of r (including to "never removed").
        let succs: Vec<u32> = std::mem::take(&mut self.succ[c as usize])
            .0
            .into_iter()
            .chain([NEVER])
            .collect();
        for y in succs {
            if let Some(arc) = self.arcs.remove(&(c, y)) {
                for &t in &arc.tris {
                    h.created_by[t as usize] = r;
                }
                self.arcs.entry((r, y)).or_default().append(arc);
            }
            if y != NEVER {
                self.pred[y as usize].remove(c);
                self.pred[y as usize].insert(r);
                self.succ[r as usize].insert(y);
                self.version[y as usize] += 1;
            }
        }
    }

    /// Drops never-drawn triangles, renumbers the nodes compactly in a topological order
    /// (a merged node may have to precede nodes created before it) and repairs monotonicity
    /// breadth first (section 4.2).
    fn finish(mut self, h: &mut MtHierarchy) {
        let n = h.node_error.len();
        let roots: Vec<u32> = (0..n as u32).filter(|&x| self.find(x) == x).collect();
        // Kahn's algorithm over the representatives (the node 0 first: it has no inputs).
        let mut indegree: HashMap<u32, usize> = roots.iter().map(|&x| (x, 0)).collect();
        for &x in &roots {
            for &y in &self.succ[x as usize] {
                if let Some(d) = indegree.get_mut(&y) {
                    *d += 1;
                }
            }
        }
        let mut ready: std::collections::VecDeque<u32> =
            roots.iter().copied().filter(|x| indegree[x] == 0).collect();
        let mut order = Vec::with_capacity(roots.len());
        while let Some(x) = ready.pop_front() {
            order.push(x);
            for &y in &self.succ[x as usize] {
                if let Some(d) = indegree.get_mut(&y) {
                    *d -= 1;
                    if *d == 0 {
                        ready.push_back(y);
                    }
                }
            }
        }
        // A cycle cannot form (collapses that would close one are refused); should one slip
        // through, its nodes go last and the numbering test (creator < remover) catches it.
        let mut placed = vec![false; n];
        for &x in &order {
            placed[x as usize] = true;
        }
        for &x in &roots {
            if !placed[x as usize] {
                order.push(x);
            }
        }
        let mut new_id = vec![u32::MAX; n];
        let mut errors = Vec::with_capacity(order.len());
        for &old in &order {
            new_id[old as usize] = errors.len() as u32;
            errors.push(h.node_error[old as usize]);
        }
        let map = |x: u32| {
            if x == NEVER {
                NEVER
            } else {
                new_id[x as usize]
            }
        };
        let mut tris = Vec::new();
        let (mut cb, mut rb) = (Vec::new(), Vec::new());
        for t in 0..h.triangles.len() {
            let (c, r) = (h.created_by[t], h.removed_by[t]);
            if c == r {
                continue;
            }
            tris.push(h.triangles[t]);
            cb.push(map(c));
            rb.push(map(r));
        }
        // In topological order: a node removing triangles of a node with a larger error
        // takes that error.
        let mut succ: Vec<Vec<u32>> = vec![Vec::new(); errors.len()];
        for (&c, &r) in cb.iter().zip(&rb) {
            if r != NEVER {
                succ[c as usize].push(r);
            }
        }
        for c in 0..errors.len() {
            for &r in &succ[c] {
                if errors[r as usize] < errors[c] {
                    errors[r as usize] = errors[c];
                }
            }
        }
        for v in 0..h.vertex_removed_by.len() {
            let x = h.vertex_removed_by[v];
            if x != NEVER {
                h.vertex_removed_by[v] = new_id[self.find(x) as usize];
            }
        }
        h.triangles = tris;
        h.created_by = cb;
        h.removed_by = rb;
        h.node_error = errors;
        h.layout();
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::super::fixtures::{bumpy, edges_used, sampled_hausdorff};
    use super::*;
    use crate::model::mesh::border_loops;

    #[test]
    fn arc_collapse_reaches_the_target_size_and_keeps_cuts_valid() {
        // 16 × 16: at 12 × 12 the hierarchy has a dozen nodes left at 20 triangles per arc,
        // and whether the last merges are allowed hangs on the order of the few collapses
        // near its root (16.1 per arc once the build merged its pieces back, 20.0 before).
        let m = bumpy(16);
        let fine = MtHierarchy::build(&m.positions, &m.triangles);
        assert!(fine.mean_arc_size() < 3.0, "{}", fine.mean_arc_size());
        let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
        let area_of = |tris: &[[u32; 3]]| -> f64 {
            (tris.iter())
                .map(|t| {
                    let [a, b, c] = t.map(|i| pos[i as usize]);
                    0.5 * (b - a).cross(c - a).z.abs()
                })
                .sum()
        };
        let full = area_of(&m.triangles);
        for target in [2.0, 5.0, 10.0, 20.0] {
            let mut h = fine.clone();
            let collapses = h.reduce(target);
            assert!(collapses > 0);
            assert!(
                h.mean_arc_size() >= target * 0.9,
                "{target}: {}",
                h.mean_arc_size()
            );
            assert!(h.node_count() < fine.node_count());
            // A DAG in topological numbering, errors monotone after the adjustment.
            for t in 0..h.triangles.len() {
                let (c, r) = (h.created_by[t], h.removed_by[t]);
                if r != NEVER {
                    assert!(c < r, "{target}: arc ({c}, {r}) against the order");
                    assert!(h.node_error[c as usize] <= h.node_error[r as usize]);
                }
            }
            // Every cut: a triangulation of the square within its Hausdorff error.
            let mut errors = h.node_error.clone();
            errors.sort_by(f64::total_cmp);
            let mut cut = Vec::new();
            for q in [0.0, 0.2, 0.5, 0.8, 1.0] {
                let eps = errors[((errors.len() - 1) as f64 * q) as usize];
                h.cut(eps, &mut cut);
                let uses = edges_used(&cut);
                assert!(
                    uses.values().all(|&u| u <= 2),
                    "{target}: overlap at ε {eps}"
                );
                assert_eq!(border_loops(&cut).len(), 1, "{target}: holes at ε {eps}");
                let area = area_of(&cut);
                // Up to what cutting the square's corners within ε removes.
                assert!(
                    (area - full).abs() < 0.02 + eps * 4.0 * full.sqrt(),
                    "{target}: area {area} at ε {eps}"
                );
                let worst = sampled_hausdorff(&pos, &cut, &m.triangles);
                assert!(worst <= eps + 1e-9, "{target}: Hausdorff {worst} > ε {eps}");
            }
            // The finest cut is still the original mesh.
            h.cut(0.0, &mut cut);
            let mut a = cut.clone();
            let mut b = m.triangles.clone();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b, "{target}: the finest level changed");
        }
    }
}
