//! Multi-triangulation (MT) hierarchy of one mesh patch, after Holst and Schumann's reduced
//! MT hierarchies (the `holst-reduced-mt-hierarchy` paper, sections 2–3).
//!
//! The hierarchy is built by half-edge collapses ordered by quadric error (Garland–Heckbert
//! plane quadrics, plus constraint planes along the patch border so the border keeps its
//! shape). A half-edge collapse moves a vertex onto a neighbour, so no vertex is ever created:
//! the vertex buffer is the patch's own, built once. Every collapse is a **node**; every
//! triangle records the node that created it (0: the original mesh) and the node that removed
//! it (`NEVER`: still there at the coarsest level). Triangles sharing (creator, remover) form
//! the **arcs** of the DAG.
//!
//! **Node errors are two-sided Hausdorff distances**, sampled: between the fan a collapse
//! creates and the original triangles its region covers (each original triangle is assigned
//! to the nearest triangle of the fan that replaced it, so regions stay tight), maxed with the
//! errors of the nodes whose triangles it removes — monotone along the DAG. A **cut** for ε
//! draws the triangles whose creator's error is ≤ ε and whose remover's is > ε: the nodes with
//! error ≤ ε form a closed set (monotonicity), so the cut is a valid triangulation of the patch
//! within ε of the original, two-sided. Patch borders may collapse along themselves (corners,
//! where the border turns by more than 45°, stay); the gaps
//! to neighbouring patches are covered by fat borders like those of independently tessellated
//! surfaces.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

use glam::{DMat4, DVec3, DVec4, Vec3};

use crate::geom::point_triangle_distance;

/// Triangles per arc the hierarchies of loaded meshes are reduced to (see the Table-1 bench
/// `mt_table` for the trade-off: larger arcs, fewer draw ranges, more triangles drawn).
pub const DEFAULT_ARC_SIZE: f64 = 5.0;

/// A multiply-and-rotate hasher for the small integer keys of the arc-collapse maps (the
/// default SipHash took a quarter of the reduction time); keys are not attacker-chosen.
#[derive(Default)]
pub(crate) struct IntHasher(u64);

impl Hasher for IntHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u32(&mut self, x: u32) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

pub(crate) type IntMap<K, V> = HashMap<K, V, BuildHasherDefault<IntHasher>>;
type IntSet<K> = HashSet<K, BuildHasherDefault<IntHasher>>;

/// Remover of a triangle that is never removed.
pub const NEVER: u32 = u32::MAX;

/// The hierarchy of one patch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtHierarchy {
    /// Every triangle that exists at some level, indices into the patch's vertices: the
    /// original ones first.
    pub triangles: Vec<[u32; 3]>,
    /// Node that created each triangle (0 = the original mesh).
    pub created_by: Vec<u32>,
    /// Node that removed each triangle, or [`NEVER`].
    pub removed_by: Vec<u32>,
    /// Error of every node (index 0 = the original mesh, error 0); monotone along the DAG.
    pub node_error: Vec<f64>,
    /// Node whose collapse moved each vertex away, or [`NEVER`].
    pub vertex_removed_by: Vec<u32>,
    /// Vertex each removed vertex was moved onto by its half-edge collapse (itself when never
    /// removed). The cut after a prefix of [`MtHierarchy::order`] is the original mesh with
    /// every removed vertex replaced by the end of its chain of targets, degenerate triangles
    /// dropped — what multiresolution strips (`strips::mts`) substitute in their sequences.
    pub vertex_target: Vec<u32>,
    /// Arcs: the triangles are sorted so that every arc's triangles are contiguous, arc `k`
    /// being `triangles[arc_start[k]..arc_start[k + 1]]`, created by `arc_nodes[k].0` and
    /// removed by `arc_nodes[k].1`. One static index range per arc.
    pub arc_start: Vec<u32>,
    pub arc_nodes: Vec<(u32, u32)>,
    /// The nodes in the order a coarsening cut applies them: by error, then by index — a
    /// linear extension of the DAG, because errors are monotone and indices topological.
    pub order: Vec<u32>,
    /// Position of every node in `order`.
    rank: Vec<u32>,
    /// Arcs every node creates (`out`) and removes (`into`), as compressed rows.
    out_start: Vec<u32>,
    out_arcs: Vec<u32>,
    in_start: Vec<u32>,
    in_arcs: Vec<u32>,
}

/// A cut kept from frame to frame (Holst §3: moving a cut applies or undoes only the nodes
/// between the old and the new error). The applied nodes are a prefix of
/// [`MtHierarchy::order`]; an arc is drawn when its creator is applied and its remover not.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CutState {
    applied: usize,
    active: Vec<bool>,
}

impl CutState {
    /// Number of applied nodes (the original mesh counts as one).
    pub fn applied(&self) -> usize {
        self.applied
    }
}

/// A symmetric 4×4 quadric.
#[derive(Clone, Copy, Debug, Default)]
struct Quadric(DMat4);

impl Quadric {
    fn plane(n: DVec3, p: DVec3, weight: f64) -> Quadric {
        let v = DVec4::new(n.x, n.y, n.z, -n.dot(p));
        Quadric(DMat4::from_cols(v * v.x, v * v.y, v * v.z, v * v.w) * weight)
    }
    fn eval(&self, p: DVec3) -> f64 {
        let v = p.extend(1.0);
        v.dot(self.0 * v).max(0.0)
    }
    fn add(&mut self, o: &Quadric) {
        self.0 += o.0;
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Candidate {
    cost: f64,
    from: u32,
    to: u32,
    stamp: (u32, u32),
}
impl Eq for Candidate {}
impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap on cost; ties by vertex ids for reproducibility.
        o.cost
            .total_cmp(&self.cost)
            .then_with(|| (o.from, o.to).cmp(&(self.from, self.to)))
    }
}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Sample points of a triangle: corners, edge midpoints, centroid.
fn samples(a: DVec3, b: DVec3, c: DVec3) -> [DVec3; 7] {
    [
        a,
        b,
        c,
        (a + b) * 0.5,
        (b + c) * 0.5,
        (c + a) * 0.5,
        (a + b + c) / 3.0,
    ]
}

impl MtHierarchy {
    /// Builds the hierarchy of a patch (`positions`, `triangles`), collapsing until no valid
    /// collapse is left.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> MtHierarchy {
        Builder::new(positions, triangles).run()
    }

    pub fn node_count(&self) -> usize {
        self.node_error.len()
    }

    /// Whether triangle `t` is in the cut for error `eps`.
    pub fn in_cut(&self, t: usize, eps: f64) -> bool {
        let made = self.node_error[self.created_by[t] as usize];
        let gone = match self.removed_by[t] {
            NEVER => f64::INFINITY,
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
        Reducer::new(self).run(self, target)
    }

    /// Number of arcs (static index ranges).
    pub fn arc_count(&self) -> usize {
        self.arc_nodes.len()
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
    pub fn node_ranges(
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
    pub fn vertex_at(&self, v: u32, applied: usize) -> u32 {
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
    pub fn vertex_alive(&self, cut: &CutState, v: u32) -> bool {
        match self.vertex_removed_by.get(v as usize) {
            Some(&n) if n != NEVER => self.rank[n as usize] as usize >= cut.applied,
            _ => true,
        }
    }

    /// The border loops of `cut` from the patch's original loops: border vertices only ever
    /// collapse along the border onto a border neighbour, and interior vertices never onto
    /// the border, so the cut's loops are the original ones without the vertices moved away.
    pub fn cut_borders(&self, cut: &CutState, original: &[Vec<u32>], out: &mut Vec<Vec<u32>>) {
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
    fn layout(&mut self) {
        let n = self.node_error.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&a, &b| {
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
        let mut idx: Vec<usize> = (0..self.triangles.len()).collect();
        idx.sort_by_key(|&t| key(t));
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

/// Arc-collapse state: nodes merged by union-find, arcs as triangle lists.
struct Reducer {
    parent: Vec<u32>,
    arcs: IntMap<(u32, u32), Vec<u32>>,
    /// Successors and predecessors of every representative node.
    succ: Vec<std::collections::BTreeSet<u32>>,
    pred: Vec<std::collections::BTreeSet<u32>>,
    version: Vec<u32>,
    mu: f64,
    /// Triangles in all arcs, and the number of arcs (for the mean arc size).
    arc_triangles: usize,
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
        let mut arcs: IntMap<(u32, u32), Vec<u32>> = IntMap::default();
        let mut succ = vec![std::collections::BTreeSet::new(); n];
        let mut pred = vec![std::collections::BTreeSet::new(); n];
        for t in 0..h.triangles.len() {
            let (c, r) = (h.created_by[t], h.removed_by[t]);
            arcs.entry((c, r)).or_default().push(t as u32);
            if r != NEVER {
                succ[c as usize].insert(r);
                pred[r as usize].insert(c);
            }
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
    fn other_path(&self, c: u32, r: u32) -> bool {
        let mut stack: Vec<u32> = self.succ[c as usize]
            .iter()
            .copied()
            .filter(|&x| x != r)
            .collect();
        let mut seen = IntSet::default();
        while let Some(x) = stack.pop() {
            if x == r {
                return true;
            }
            // (Merged nodes break creation order, so no pruning by index.)
            if !seen.insert(x) {
                continue;
            }
            stack.extend(self.succ[x as usize].iter().copied());
        }
        false
    }

    /// The paper's weight of collapsing arc (c, r) (small first), `None` if not allowed.
    fn weight(&self, h: &MtHierarchy, (c, r): (u32, u32)) -> Option<f64> {
        if !self.collapsible((c, r)) {
            return None;
        }
        let size = self.arcs.get(&(c, r))?.len() as f64;
        let e = |n: u32| h.node_error[n as usize].max(self.mu);
        let e_diff = e(r) / e(c);
        // Arc pairs that merge: common predecessors and common successors of c and r.
        let mut pairs: Vec<(&Vec<u32>, &Vec<u32>)> = Vec::new();
        for &x in self.pred[c as usize].intersection(&self.pred[r as usize]) {
            if let (Some(a), Some(b)) = (self.arcs.get(&(x, c)), self.arcs.get(&(x, r))) {
                pairs.push((a, b));
            }
        }
        let succ_c: Vec<u32> = self.succ[c as usize]
            .iter()
            .copied()
            .chain([NEVER])
            .collect();
        for y in succ_c {
            if y == r {
                continue;
            }
            if let (Some(a), Some(b)) = (self.arcs.get(&(c, y)), self.arcs.get(&(r, y))) {
                pairs.push((a, b));
            }
        }
        if pairs.is_empty() {
            // Nothing merges: the collapse would not enlarge any arc.
            return None;
        }
        let ps: usize = pairs.iter().map(|(a, b)| a.len() + b.len()).sum();
        let ps_rel = ps as f64 / pairs.len() as f64;
        let touching = pairs
            .iter()
            .filter(|(a, b)| {
                let verts: IntSet<u32> = a.iter().flat_map(|&t| h.triangles[t as usize]).collect();
                b.iter()
                    .any(|&t| h.triangles[t as usize].iter().any(|v| verts.contains(v)))
            })
            .count();
        if touching == 0 {
            return None;
        }
        let adj = touching as f64 / pairs.len() as f64;
        Some(size * e_diff * ps_rel / adj)
    }

    fn push(&self, h: &MtHierarchy, arc: (u32, u32), heap: &mut BinaryHeap<ArcCandidate>) {
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

    fn run(mut self, h: &mut MtHierarchy, target: f64) -> usize {
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
            self.arc_triangles -= gone.len();
            for t in gone {
                h.created_by[t as usize] = r;
                h.removed_by[t as usize] = r;
            }
        }
        self.succ[c as usize].remove(&r);
        self.pred[r as usize].remove(&c);
        // Arcs into c now go into r.
        let preds: Vec<u32> = std::mem::take(&mut self.pred[c as usize])
            .into_iter()
            .collect();
        for x in preds {
            if let Some(tris) = self.arcs.remove(&(x, c)) {
                for &t in &tris {
                    h.removed_by[t as usize] = r;
                }
                self.arcs.entry((x, r)).or_default().extend(tris);
            }
            self.succ[x as usize].remove(&c);
            self.succ[x as usize].insert(r);
            self.pred[r as usize].insert(x);
            self.version[x as usize] += 1;
        }
        // Arcs out of c now come out of r (including to "never removed").
        let succs: Vec<u32> = std::mem::take(&mut self.succ[c as usize])
            .into_iter()
            .chain([NEVER])
            .collect();
        for y in succs {
            if let Some(tris) = self.arcs.remove(&(c, y)) {
                for &t in &tris {
                    h.created_by[t as usize] = r;
                }
                self.arcs.entry((r, y)).or_default().extend(tris);
            }
            if y != NEVER {
                self.pred[y as usize].remove(&c);
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

struct Builder {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    created_by: Vec<u32>,
    removed_by: Vec<u32>,
    node_error: Vec<f64>,
    /// Original triangles each live triangle stands for.
    covers: Vec<Vec<u32>>,
    /// Live triangles around each vertex.
    around: Vec<Vec<u32>>,
    quadric: Vec<Quadric>,
    /// Border vertices: the two border neighbours (fixed when it has other than two).
    border: Vec<Option<Vec<u32>>>,
    stamp: Vec<u32>,
    vertex_removed_by: Vec<u32>,
    vertex_target: Vec<u32>,
}

impl Builder {
    fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Builder {
        let pos: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
        let n = pos.len();
        let mut around = vec![Vec::new(); n];
        let mut quadric = vec![Quadric::default(); n];
        let mut edge_uses: IntMap<(u32, u32), u32> = IntMap::default();
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| pos[i as usize]);
            let cross = (b - a).cross(c - a);
            let area = cross.length() * 0.5;
            let normal = cross.normalize_or_zero();
            for k in 0..3 {
                around[tri[k] as usize].push(t as u32);
                quadric[tri[k] as usize].add(&Quadric::plane(normal, a, area));
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                *edge_uses.entry((u.min(v), u.max(v))).or_default() += 1;
            }
        }
        // Border edges: constraint planes through the edge, perpendicular to the surface,
        // weighted heavily so the border keeps its line.
        let mut border: Vec<Option<Vec<u32>>> = vec![None; n];
        for tri in triangles {
            let [a, b, c] = tri.map(|i| pos[i as usize]);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            for k in 0..3 {
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                if edge_uses[&(u.min(v), u.max(v))] != 1 {
                    continue;
                }
                let (pu, pv) = (pos[u as usize], pos[v as usize]);
                let along = pv - pu;
                let side = along.cross(normal).normalize_or_zero();
                let q = Quadric::plane(side, pu, 1e3 * along.length_squared().max(1e-30));
                for (x, y) in [(u, v), (v, u)] {
                    quadric[x as usize].add(&q);
                    border[x as usize].get_or_insert_with(Vec::new).push(y);
                }
            }
        }
        let m = triangles.len();
        Builder {
            pos,
            tris: triangles.to_vec(),
            created_by: vec![0; m],
            removed_by: vec![NEVER; m],
            node_error: vec![0.0],
            covers: (0..m as u32).map(|t| vec![t]).collect(),
            around,
            quadric,
            border,
            stamp: vec![0; n],
            vertex_removed_by: vec![NEVER; n],
            vertex_target: (0..n as u32).collect(),
        }
    }

    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut out: Vec<u32> = self.around[v as usize]
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&w| w != v)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Cost of moving `from` onto `to`, or `None` when the collapse is not allowed.
    fn candidate(&self, from: u32, to: u32) -> Option<Candidate> {
        let (f, t) = (from as usize, to as usize);
        // Border vertices move only along the border, onto a border neighbour; border
        // vertices with other than two border edges (corners, non-manifold) stay.
        if let Some(nb) = &self.border[f] {
            if nb.len() != 2 || !nb.contains(&to) {
                return None;
            }
            // Corners (the border turns by more than 45°) stay.
            let (a, b) = (self.pos[nb[0] as usize], self.pos[nb[1] as usize]);
            let (d0, d1) = (
                (self.pos[f] - a).normalize_or_zero(),
                (b - self.pos[f]).normalize_or_zero(),
            );
            if d0.dot(d1) < std::f64::consts::FRAC_1_SQRT_2 {
                return None;
            }
        }
        // An interior vertex may not move onto the border (it would pinch the patch).
        if self.border[f].is_none() && self.border[t].is_some() {
            return None;
        }
        // Link condition: the common neighbours are exactly the apexes of the shared edge.
        let shared: Vec<u32> = self.around[f]
            .iter()
            .copied()
            .filter(|&tr| self.tris[tr as usize].contains(&to))
            .collect();
        if shared.is_empty() {
            return None;
        }
        let nf = self.neighbours(from);
        let nt = self.neighbours(to);
        let common = nf.iter().filter(|w| nt.binary_search(w).is_ok()).count();
        if common != shared.len() {
            return None;
        }
        // No triangle may flip or degenerate.
        for &tr in &self.around[f] {
            let tri = self.tris[tr as usize];
            if tri.contains(&to) {
                continue;
            }
            let [a, b, c] = tri.map(|i| self.pos[i as usize]);
            let before = (b - a).cross(c - a);
            let moved = tri.map(|i| {
                if i == from {
                    self.pos[t]
                } else {
                    self.pos[i as usize]
                }
            });
            let after = (moved[1] - moved[0]).cross(moved[2] - moved[0]);
            if after.length_squared() <= 1e-24 * before.length_squared().max(1e-300)
                || after.normalize_or_zero().dot(before.normalize_or_zero()) < 0.2
            {
                return None;
            }
        }
        let mut q = self.quadric[f];
        q.add(&self.quadric[t]);
        Some(Candidate {
            cost: q.eval(self.pos[t]),
            from,
            to,
            stamp: (self.stamp[f], self.stamp[t]),
        })
    }

    fn run(mut self) -> MtHierarchy {
        let mut heap = BinaryHeap::new();
        for v in 0..self.pos.len() as u32 {
            for w in self.neighbours(v) {
                if let Some(c) = self.candidate(v, w) {
                    heap.push(c);
                }
            }
        }
        while let Some(c) = heap.pop() {
            if c.stamp != (self.stamp[c.from as usize], self.stamp[c.to as usize]) {
                continue;
            }
            // Re-validate (neighbourhoods changed since it was queued without a stamp bump
            // of these two vertices only if untouched; stamps guard that).
            let Some(c) = self.candidate(c.from, c.to) else {
                continue;
            };
            self.collapse(c.from, c.to);
            let touched = self.neighbours(c.to);
            for &w in touched.iter().chain(std::iter::once(&c.to)) {
                self.stamp[w as usize] += 1;
            }
            // Every edge at a touched vertex, once, both directions.
            let mut edges: Vec<(u32, u32)> = Vec::new();
            for &w in touched.iter().chain(std::iter::once(&c.to)) {
                edges.extend(self.neighbours(w).into_iter().map(|x| (w.min(x), w.max(x))));
            }
            edges.sort_unstable();
            edges.dedup();
            for (a, b) in edges {
                for (x, y) in [(a, b), (b, a)] {
                    if let Some(c) = self.candidate(x, y) {
                        heap.push(c);
                    }
                }
            }
        }
        let mut h = MtHierarchy {
            triangles: self.tris,
            created_by: self.created_by,
            removed_by: self.removed_by,
            node_error: self.node_error,
            vertex_removed_by: self.vertex_removed_by,
            vertex_target: self.vertex_target,
            ..Default::default()
        };
        h.layout();
        h
    }

    /// Moves `from` onto `to`: one node of the hierarchy.
    fn collapse(&mut self, from: u32, to: u32) {
        let node = self.node_error.len() as u32;
        let removed: Vec<u32> = self.around[from as usize].clone();
        self.vertex_removed_by[from as usize] = node;
        self.vertex_target[from as usize] = to;
        let mut region: Vec<u32> = Vec::new();
        let mut inherited = 0.0f64;
        for &t in &removed {
            self.removed_by[t as usize] = node;
            inherited = inherited.max(self.node_error[self.created_by[t as usize] as usize]);
            region.append(&mut self.covers[t as usize]);
            for v in self.tris[t as usize] {
                self.around[v as usize].retain(|&x| x != t);
            }
        }
        let mut fan = Vec::new();
        for &t in &removed {
            let tri = self.tris[t as usize];
            if tri.contains(&to) {
                continue;
            }
            let new = tri.map(|i| if i == from { to } else { i });
            let id = self.tris.len() as u32;
            self.tris.push(new);
            self.created_by.push(node);
            self.removed_by.push(NEVER);
            self.covers.push(Vec::new());
            for v in new {
                self.around[v as usize].push(id);
            }
            fan.push(id);
        }
        let q = self.quadric[from as usize];
        self.quadric[to as usize].add(&q);
        if let Some(nb) = self.border[from as usize].take() {
            // `to` takes over `from`'s other border neighbour.
            let other = nb.iter().copied().find(|&x| x != to);
            if let (Some(other), Some(tb)) = (other, self.border[to as usize].as_mut()) {
                for x in tb.iter_mut() {
                    if *x == from {
                        *x = other;
                    }
                }
                if let Some(ob) = self.border[other as usize].as_mut() {
                    for x in ob.iter_mut() {
                        if *x == from {
                            *x = to;
                        }
                    }
                }
            }
        }
        let error = self.hausdorff(&fan, &region);
        // Assign every covered original triangle to the nearest triangle of the fan.
        for o in region {
            let c = self.centroid(self.tris[o as usize]);
            let best = fan
                .iter()
                .copied()
                .min_by(|&a, &b| self.dist(c, a).total_cmp(&self.dist(c, b)));
            if let Some(b) = best {
                self.covers[b as usize].push(o);
            }
        }
        self.node_error.push(error.max(inherited));
    }

    fn centroid(&self, t: [u32; 3]) -> DVec3 {
        t.map(|i| self.pos[i as usize]).iter().sum::<DVec3>() / 3.0
    }

    fn dist(&self, p: DVec3, t: u32) -> f64 {
        let [a, b, c] = self.tris[t as usize].map(|i| self.pos[i as usize]);
        point_triangle_distance(p, a, b, c)
    }

    /// Sampled two-sided Hausdorff distance between the triangles `fan` and the original
    /// triangles `region`. A sample stops scanning as soon as it finds a triangle no farther
    /// than the worst distance so far (it cannot raise the maximum): exact, and most samples
    /// stop at once.
    fn hausdorff(&self, fan: &[u32], region: &[u32]) -> f64 {
        let mut worst = 0.0f64;
        let farthest = |from: &[u32], to: &[u32], worst: &mut f64| {
            for &t in from {
                let [a, b, c] = self.tris[t as usize].map(|i| self.pos[i as usize]);
                for s in samples(a, b, c) {
                    let mut best = f64::INFINITY;
                    for &o in to {
                        best = best.min(self.dist(s, o));
                        if best <= *worst {
                            break;
                        }
                    }
                    if best.is_finite() {
                        *worst = worst.max(best);
                    }
                }
            }
        };
        farthest(fan, region, &mut worst);
        farthest(region, fan, &mut worst);
        worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::mesh::{TriMesh, border_loops};

    /// A bumpy n × n grid patch: z = 0.1 sin(x) cos(y).
    fn bumpy(n: u32) -> TriMesh {
        let mut m = TriMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 * 0.25, j as f32 * 0.25);
                m.positions.push(Vec3::new(x, y, 0.1 * x.sin() * y.cos()));
            }
        }
        let at = |i: u32, j: u32| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        m
    }

    /// Sampled two-sided Hausdorff distance between two triangle sets over `pos`.
    fn sampled_hausdorff(pos: &[DVec3], x: &[[u32; 3]], y: &[[u32; 3]]) -> f64 {
        let dist_to = |p: DVec3, tris: &[[u32; 3]]| {
            tris.iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| pos[i as usize]);
                    point_triangle_distance(p, a, b, c)
                })
                .fold(f64::INFINITY, f64::min)
        };
        let mut worst = 0.0f64;
        for (from, to) in [(x, y), (y, x)] {
            for t in from {
                let [a, b, c] = t.map(|i| pos[i as usize]);
                for s in samples(a, b, c) {
                    worst = worst.max(dist_to(s, to));
                }
            }
        }
        worst
    }

    fn edges_used(tris: &[[u32; 3]]) -> HashMap<(u32, u32), u32> {
        let mut uses = HashMap::new();
        for t in tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        uses
    }

    #[test]
    fn errors_are_monotone_along_the_dag() {
        let m = bumpy(12);
        let h = MtHierarchy::build(&m.positions, &m.triangles);
        assert!(h.node_count() > 100, "{} nodes", h.node_count());
        for t in 0..h.triangles.len() {
            let (c, r) = (h.created_by[t], h.removed_by[t]);
            if r != NEVER {
                assert!(c < r, "arc goes back in time");
                assert!(h.node_error[c as usize] <= h.node_error[r as usize]);
            }
        }
    }

    #[test]
    fn every_cut_is_a_triangulation_of_the_patch_within_its_error() {
        let m = bumpy(12);
        let h = MtHierarchy::build(&m.positions, &m.triangles);
        let original_border: f64 = 12.0 * 4.0 * 0.25; // perimeter of the 3 × 3 square
        let mut errors: Vec<f64> = h.node_error.clone();
        errors.sort_by(f64::total_cmp);
        let mut cut = Vec::new();
        for q in [0.0, 0.1, 0.3, 0.6, 0.9, 1.0] {
            let eps = errors[((errors.len() - 1) as f64 * q) as usize];
            let achieved = h.cut(eps, &mut cut);
            assert!(achieved <= eps);
            // No overlaps, no holes: every edge used once (border) or twice (inside), and
            // exactly one border loop around the square.
            let uses = edges_used(&cut);
            assert!(uses.values().all(|&u| u <= 2), "overlap at ε {eps}");
            let loops = border_loops(&cut);
            assert_eq!(loops.len(), 1, "ε {eps}: {} border loops", loops.len());
            // Corners stay, so the border keeps the square's outline: same length.
            let ring = &loops[0];
            let len: f64 = (0..ring.len())
                .map(|k| {
                    let a = m.positions[ring[k] as usize].as_dvec3();
                    let b = m.positions[ring[(k + 1) % ring.len()] as usize].as_dvec3();
                    a.distance(b)
                })
                .sum();
            assert!(
                (len - original_border).abs() < 0.05 * original_border,
                "border length {len} at ε {eps}"
            );
            // Area is kept (a hole would lose some).
            let area: f64 = cut
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                    let n = (b - a).cross(c - a);
                    0.5 * DVec3::new(0.0, 0.0, 1.0).dot(n).abs()
                })
                .sum();
            assert!(
                (area - 9.0).abs() < 0.02,
                "projected area {area} at ε {eps}"
            );
        }
        // The coarsest cut is much smaller than the original.
        let coarsest = h.cut(f64::INFINITY, &mut cut);
        assert!(
            cut.len() * 10 < m.triangles.len(),
            "{} triangles",
            cut.len()
        );
        assert!(coarsest >= 0.0);
    }

    #[test]
    fn arc_collapse_reaches_the_target_size_and_keeps_cuts_valid() {
        let m = bumpy(12);
        let fine = MtHierarchy::build(&m.positions, &m.triangles);
        assert!(fine.mean_arc_size() < 3.0, "{}", fine.mean_arc_size());
        let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
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
                let area: f64 = cut
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|i| pos[i as usize]);
                        0.5 * (b - a).cross(c - a).z.abs()
                    })
                    .sum();
                assert!(
                    (area - 9.0).abs() < 0.02,
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

    #[test]
    fn cut_triangles_hold_the_hausdorff_bound() {
        let m = bumpy(10);
        let h = MtHierarchy::build(&m.positions, &m.triangles);
        let pos: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
        let mut cut = Vec::new();
        for eps in [0.002, 0.01, 0.05] {
            let achieved = h.cut(eps, &mut cut);
            let worst = sampled_hausdorff(&pos, &cut, &m.triangles);
            assert!(
                worst <= eps + 1e-9,
                "ε {eps}: Hausdorff {worst} (achieved {achieved})"
            );
        }
    }

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
