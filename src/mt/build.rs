//! Building an MT hierarchy by half-edge collapses (Holst and Schumann, the
//! `holst-reduced-mt-hierarchy` paper, section 2): collapses ordered by the error they are
//! expected to have (Garland–Heckbert quadric error, with constraint planes along the patch
//! border, as a distance, raised to a cheap estimate of the node error when popped: see
//! [`Builder::predict`]; borders collapse along themselves, corners too: the node error says
//! what that costs; an interior vertex may move onto the border), the link condition,
//! no flipped or degenerate triangles and no collapse that removes every triangle of its
//! vertex (an ear: its fan would be empty, the removed surface unmeasured). One node per
//! collapse; node error = a certified upper bound ([`super::bound`], [`Builder::measure`]) of
//! the two-sided Hausdorff distance between the collapse's fan and the original surface —
//! original → fan against the one fan triangle each piece of the surface is given to, fan →
//! original against the surface around it — maxed with the errors of the nodes whose
//! triangles it removes (monotone along the DAG), so every cut is within its ε both ways.
//!
//! It does not reduce the hierarchy (that is [`super::reduce`]) nor cut it ([`super::cut`]).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{DVec3, Vec3};

use super::bound::{self, Piece};
use super::nearest::SurfaceBvh;
use super::{MtHierarchy, NEVER};
use crate::geom::point_triangle_distance;
use crate::util::IntMap;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Candidate {
    /// The error the collapse is expected to have, a distance (see [`Builder::candidate`] and
    /// [`Builder::predict`]).
    cost: f64,
    /// `cost` without the inherited errors: what breaks ties (a region's inherited error).
    own: f64,
    from: u32,
    to: u32,
    stamp: (u32, u32),
    /// `ring[from]` when `cost` was raised to [`Builder::predict`]'s estimate (still exact
    /// while the triangles around `from` are the same), else [`NEVER`].
    ring: u32,
}
impl Eq for Candidate {}
impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap on cost; ties (candidates in a region whose inherited error is above their
        // own) by their own distance, then by vertex ids for reproducibility.
        o.cost
            .total_cmp(&self.cost)
            .then_with(|| o.own.total_cmp(&self.own))
            .then_with(|| (o.from, o.to).cmp(&(self.from, self.to)))
    }
}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Sample points of a triangle: corners, edge midpoints, centroid.
pub(super) fn samples(a: DVec3, b: DVec3, c: DVec3) -> [DVec3; 7] {
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

/// How far above the largest sampled distance (or inherited error) a certified bound may
/// be taken as it is, relative, before the piece it bounds is split to tighten it.
const SLACK: f64 = 0.2;

/// How many times a piece of the original surface may be split (each split kept). A piece
/// is given to one fan triangle, so on a flat region a piece that straddles two fan triangles
/// is bounded by its in-plane overhang until it is split along their shared side: with 3, a
/// generated plane with a step (`tools/mesh_generator.py`, mgen-1-5 reduced to its step) kept
/// 1 843 of its 3 150 triangles at an error of 1e-9 of its size, and 557 with 8; the bunny
/// builds about 15 % longer.
const PIECE_DEPTH: u8 = 8;

/// How many times a fan triangle may be split while it is bounded (the parts are not kept).
/// Long thin fan triangles need many: beside a step along a strip of slivers
/// (`models/generated/mgen-2-3-step.obj`), where only parts shorter than the grid's cells are
/// bounded below the step's height, 6 kept 28 of its 1 800 triangles at 1e-3 of its diagonal,
/// 10 keep 11 (14: 10). Building costs 0–4 % more (`benches/mt_build`, two runs each: the
/// bunny on one thread 4.94–5.06 → 5.02–5.14 s, the bumpy torus 1.57–1.62 → 1.63–1.66 s).
const FAN_DEPTH: u8 = 10;

/// A popped candidate whose estimated error ([`Builder::predict`]) exceeds its key by more
/// than this ratio goes back into the heap keyed by the estimate.
const REKEY_RATIO: f64 = 1.1;

impl MtHierarchy {
    /// Builds the hierarchy of a patch (`positions`, `triangles`), collapsing until no valid
    /// collapse is left.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> MtHierarchy {
        Builder::new(positions, triangles, None).run()
    }
}

struct Builder {
    /// Split vertices (`None`: every vertex at its own position).
    split: Option<Split>,
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    created_by: Vec<u32>,
    removed_by: Vec<u32>,
    node_error: Vec<f64>,
    /// The original triangles in a box hierarchy: the fan → original distances.
    surface: SurfaceBvh,
    /// Pieces of the original surface each live triangle stands for (see [`Builder::measure`]).
    covers: Vec<Vec<u32>>,
    /// Pieces of the original surface: the original triangles first, then the parts of
    /// those split to tighten a bound, and how many splits below its original triangle each
    /// is.
    pieces: Vec<Piece>,
    piece_depth: Vec<u8>,
    /// The original triangle each piece is part of.
    piece_origin: Vec<u32>,
    /// The piece each was split from ([`NEVER`]: an original triangle), and the parts of
    /// each piece's latest split (first id, count: consecutive ids).
    piece_parent: Vec<u32>,
    piece_parts: Vec<(u32, u32)>,
    /// Per piece: `piece_generation` while it is in the cover [`Builder::coalesce`] merges.
    piece_mark: Vec<u32>,
    piece_generation: u32,
    /// Each piece's corners as ids of `points`: the original vertices first, then the corners
    /// splits made (`point_ids`: by their bits, so parts sharing a corner share its id).
    piece_points: Vec<[u32; 3]>,
    points: Vec<DVec3>,
    point_ids: IntMap<(u64, u64, u64), u32>,
    /// Per point: `point_generation` when its distances to the current fan are at
    /// `fan_dist[point_slot..]`.
    point_mark: Vec<u32>,
    point_slot: Vec<u32>,
    point_generation: u32,
    /// The fan's triangles, prepared for [`Builder::fan_distance`]'s many points.
    fan_prepared: Vec<crate::geom::Prepared>,
    fan_dist: Vec<f64>,
    /// Per original triangle: `origin_generation` when [`Builder::height_bound`] has listed it.
    origin_mark: Vec<u32>,
    origin_generation: u32,
    /// Every triangle's corners, and a sphere around it (centroid, radius): distances are
    /// measured without looking up vertices, and a sphere far from a point skips the exact
    /// distance (see [`Builder::beyond`]).
    corners: Vec<[DVec3; 3]>,
    spheres: Vec<(DVec3, f64)>,
    /// Live triangles around each vertex.
    around: Vec<Vec<u32>>,
    quadric: Vec<Quadric>,
    /// Border vertices: the two border neighbours (fixed when it has other than two).
    border: Vec<Option<Vec<u32>>>,
    stamp: Vec<u32>,
    vertex_removed_by: Vec<u32>,
    vertex_target: Vec<u32>,
    /// Per-vertex marks for the link condition (`mark[v] == generation`: marked), so a
    /// candidate allocates nothing.
    mark: Vec<u32>,
    generation: u32,
    /// Scratch lists reused by every collapse.
    scratch_vertices: Vec<u32>,
    scratch_edges: Vec<(u32, u32)>,
    fan_edges: Vec<(u32, u32)>,
    scratch_removed: Vec<u32>,
    scratch_fan: Vec<u32>,
    scratch_region: Vec<u32>,
    /// Per piece of the region, the fan triangle (index) its removed triangle became.
    scratch_own: Vec<u32>,
    scratch_assigned: Vec<(u32, u32, f64)>,
    scratch_pieces: Vec<(u32, u32)>,
    scratch_parts: Vec<Piece>,
    scratch_fan_pieces: Vec<(Piece, u8, Option<u32>)>,
    scratch_near: Vec<u32>,
    scratch_originals: Vec<(Piece, [u32; 3])>,
    scratch_edges3: Vec<bound::Edge>,
    /// Per original vertex: its original border neighbours and the original triangle of
    /// each border edge (the chains [`Builder::height_bound`] walks).
    border_links: Vec<Vec<(u32, u32)>>,
    /// Per original triangle, the original triangle across each side (`tri[k]` to
    /// `tri[k + 1]`; [`NEVER`] on the border or where more than two meet).
    across: Vec<[u32; 3]>,
    scratch_chain: Vec<(u32, u32)>,
    scratch_chain_points: Vec<DVec3>,
    scratch_spans: Vec<(usize, usize, bool)>,
    scratch_keys: Vec<(u32, u32)>,
    /// Emptied cover lists of removed triangles, reused by new ones.
    spare_covers: Vec<Vec<u32>>,
    /// Per vertex: a counter bumped whenever a triangle around it is removed (what
    /// [`Builder::predict`] looks at changed).
    ring: Vec<u32>,
    /// The prospective fan of a candidate ([`Builder::predict`]).
    scratch_predict: Vec<crate::geom::Prepared>,
}

impl Builder {
    fn new(positions: &[Vec3], triangles: &[[u32; 3]], wedges: Option<Wedges>) -> Builder {
        let pos: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
        let n = pos.len();
        // Split vertices, if any: the topology below is that of the positions.
        let split = wedges
            .filter(|w| w.rep.iter().enumerate().any(|(v, &r)| r != v as u32))
            .map(|w| {
                let mut at = vec![Vec::new(); n];
                for (v, &r) in w.rep.iter().enumerate() {
                    at[r as usize].push(v as u32);
                }
                Split {
                    tris: triangles.to_vec(),
                    target: (0..n as u32).collect(),
                    rep: w.rep,
                    normals: w.normals,
                    at,
                }
            });
        let merged: Vec<[u32; 3]>;
        let triangles = match &split {
            Some(s) => {
                merged = (triangles.iter())
                    .map(|t| t.map(|v| s.rep[v as usize]))
                    .collect();
                &merged[..]
            }
            None => triangles,
        };
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
        // weighted as a surface plane of the edge's length squared, so a border collapse is
        // ordered among the others by what it moves the border (weighted 1e3, border collapses
        // came last, each inheriting the errors of the coarse interior around it).
        let mut border: Vec<Option<Vec<u32>>> = vec![None; n];
        let mut border_links: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
        for (t, tri) in triangles.iter().enumerate() {
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
                let q = Quadric::plane(side, pu, along.length_squared().max(1e-30));
                for (x, y) in [(u, v), (v, u)] {
                    quadric[x as usize].add(&q);
                    border[x as usize].get_or_insert_with(Vec::new).push(y);
                    border_links[x as usize].push((y, t as u32));
                }
            }
        }
        let m = triangles.len();
        let mut across = vec![[NEVER; 3]; m];
        let mut first_use: IntMap<(u32, u32), u32> = IntMap::default();
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                let key = (u.min(v), u.max(v));
                if edge_uses[&key] != 2 {
                    continue;
                }
                let here = 3 * t as u32 + k as u32;
                if let Some(&there) = first_use.get(&key) {
                    across[t][k] = there / 3;
                    across[(there / 3) as usize][(there % 3) as usize] = t as u32;
                } else {
                    first_use.insert(key, here);
                }
            }
        }
        let corners: Vec<[DVec3; 3]> = triangles
            .iter()
            .map(|t| t.map(|i| pos[i as usize]))
            .collect();
        let spheres: Vec<(DVec3, f64)> = corners.iter().map(bound::sphere).collect();
        Builder {
            split,
            surface: SurfaceBvh::new(&corners),
            pieces: corners.clone(),
            piece_depth: vec![0; m],
            piece_origin: (0..m as u32).collect(),
            piece_parent: vec![NEVER; m],
            piece_parts: vec![(0, 0); m],
            piece_mark: vec![0; m],
            piece_generation: 0,
            piece_points: triangles.to_vec(),
            point_ids: pos
                .iter()
                .enumerate()
                .map(|(i, p)| ((p.x.to_bits(), p.y.to_bits(), p.z.to_bits()), i as u32))
                .collect(),
            points: pos.clone(),
            point_mark: vec![0; n],
            point_slot: vec![0; n],
            point_generation: 0,
            fan_dist: Vec::new(),
            fan_prepared: Vec::new(),
            origin_mark: vec![0; m],
            origin_generation: 0,
            corners,
            spheres,
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
            mark: vec![0; n],
            generation: 0,
            scratch_vertices: Vec::new(),
            scratch_edges: Vec::new(),
            fan_edges: Vec::new(),
            scratch_removed: Vec::new(),
            scratch_fan: Vec::new(),
            scratch_region: Vec::new(),
            scratch_own: Vec::new(),
            scratch_assigned: Vec::new(),
            scratch_pieces: Vec::new(),
            scratch_parts: Vec::new(),
            scratch_fan_pieces: Vec::new(),
            scratch_near: Vec::new(),
            scratch_originals: Vec::new(),
            scratch_edges3: Vec::new(),
            border_links,
            across,
            scratch_chain: Vec::new(),
            scratch_chain_points: Vec::new(),
            scratch_spans: Vec::new(),
            scratch_keys: Vec::new(),
            spare_covers: Vec::new(),
            ring: vec![0; n],
            scratch_predict: Vec::new(),
        }
    }

    /// The neighbours of `v`, sorted, appended to `out`.
    fn neighbours_into(&self, v: u32, out: &mut Vec<u32>) {
        let from = out.len();
        out.extend(
            self.around[v as usize]
                .iter()
                .flat_map(|&t| self.tris[t as usize])
                .filter(|&w| w != v),
        );
        out[from..].sort_unstable();
        let mut keep = from;
        for k in from..out.len() {
            if k == from || out[k] != out[keep - 1] {
                out[keep] = out[k];
                keep += 1;
            }
        }
        out.truncate(keep);
    }

    /// A fresh mark generation (all marks cleared when the counter wraps).
    fn next_generation(&mut self) -> u32 {
        if self.generation >= u32::MAX - 2 {
            self.mark.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
        self.generation
    }

    /// Cost of moving `from` onto `to`, or `None` when the border rules forbid it. The costly
    /// checks (link condition, flips) wait until the candidate is popped ([`Self::allowed`]):
    /// what they look at changes only with the stamps of `from` and `to`, so a candidate
    /// popped with current stamps is allowed exactly when it was when pushed.
    ///
    /// The cost is a distance, a cheap guess of the node error: the largest of the quadric
    /// error as a root mean square distance (the summed quadric over its weight), the distance
    /// from `from` to the fan the collapse would make, and the errors the collapse would
    /// inherit (the node error is no lower: monotone); ties go to the smallest own distance
    /// (tests/generated_meshes.rs's flat tube). The inherited errors and the fan only change
    /// with the triangles around `from`, without a new stamp, so they can be stale (low) by
    /// the time the candidate is popped: [`Builder::predict`] checks it then.
    fn candidate(&self, from: u32, to: u32) -> Option<Candidate> {
        let (f, t) = (from as usize, to as usize);
        // Border vertices move only along the border, onto a border neighbour; border
        // vertices with other than two border edges (non-manifold) stay. A corner of the border
        // may go like any other border vertex: the border of a region grown over a mesh's
        // triangles zigzags, and the node error measures what cutting a corner costs (kept,
        // corners turning by more than 45° held 10 000 of the bunny's 15 700 border vertices
        // at every ε).
        if let Some(nb) = &self.border[f]
            && (nb.len() != 2 || !nb.contains(&to))
        {
            return None;
        }
        // An interior vertex may move onto the border, as meshoptimizer's manifold vertices
        // may: the border stays as it is, and the link condition ([`Self::allowed`]) keeps
        // the patch a disk. (Forbidden until 2026-12-05 but along a crease, the interior
        // vertices next to a patch's border stayed at every error: the bunny's patches drew
        // 1 373 / 749 triangles at 1 / 2 % of its diagonal, 1 101 / 530 since.)
        let mut q = self.quadric[f];
        q.add(&self.quadric[t]);
        let (pf, pt) = (self.pos[f], self.pos[t]);
        let mut own = (q.eval(pt) / q.weight().max(1e-300)).sqrt();
        let mut inherited = 0.0f64;
        let mut to_fan = f64::INFINITY;
        for &tr in &self.around[f] {
            inherited = inherited.max(self.node_error[self.created_by[tr as usize] as usize]);
            let tri = self.tris[tr as usize];
            if !tri.contains(&to) {
                let [a, b, c] = tri.map(|i| if i == from { pt } else { self.pos[i as usize] });
                to_fan = to_fan.min(point_triangle_distance(pf, a, b, c));
            }
        }
        if to_fan.is_finite() {
            own = own.max(to_fan);
        }
        Some(Candidate {
            cost: own.max(inherited),
            own,
            from,
            to,
            stamp: (self.stamp[f], self.stamp[t]),
            ring: NEVER,
        })
    }

    /// The link condition and no flipped or degenerate triangle.
    fn allowed(&mut self, from: u32, to: u32) -> bool {
        let (f, t) = (from as usize, to as usize);
        // Link condition: the common neighbours are exactly the apexes of the shared edge.
        let shared = self.around[f]
            .iter()
            .filter(|&&tr| self.tris[tr as usize].contains(&to))
            .count();
        // Some triangle of `from` must survive: a collapse that removes them all (an ear on
        // the border: a corner in one triangle, common where creases bound a flat fan) would
        // delete surface with an empty fan, whose measured error is nothing.
        if shared == 0 || shared == self.around[f].len() {
            return false;
        }
        let marked = self.next_generation();
        let counted = self.next_generation();
        for &tr in &self.around[f] {
            for w in self.tris[tr as usize] {
                if w != from {
                    self.mark[w as usize] = marked;
                }
            }
        }
        let mut common = 0;
        for &tr in &self.around[t] {
            for w in self.tris[tr as usize] {
                if w != to && self.mark[w as usize] == marked {
                    self.mark[w as usize] = counted;
                    common += 1;
                }
            }
        }
        if common != shared {
            return false;
        }
        // Split vertices at `from` go onto those at `to` one way each.
        if let Some(split) = &self.split {
            let around = &self.around[f];
            for &w in &split.at[f] {
                if split.target_of(w, to, around, &self.tris).is_none() {
                    return false;
                }
            }
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
                return false;
            }
        }
        true
    }

    fn run(mut self) -> MtHierarchy {
        let mut first = Vec::new();
        let mut around = Vec::new();
        for v in 0..self.pos.len() as u32 {
            around.clear();
            self.neighbours_into(v, &mut around);
            for &w in &around {
                if let Some(c) = self.candidate(v, w) {
                    first.push(c);
                }
            }
        }
        let mut heap = BinaryHeap::from(first);
        let mut touched = std::mem::take(&mut self.scratch_vertices);
        let mut edges = std::mem::take(&mut self.scratch_edges);
        // Candidates refused when popped, listed at both ends: a collapse that changes the
        // triangles around either end pushes them again (they may be allowed now).
        let mut refused: Vec<Vec<(u32, u32)>> = vec![Vec::new(); self.pos.len()];
        while let Some(c) = heap.pop() {
            if c.stamp != (self.stamp[c.from as usize], self.stamp[c.to as usize]) {
                continue;
            }
            // Current stamps: the cost and the border rules hold; now the checks left for
            // later, on the neighbourhoods as they are.
            if !self.allowed(c.from, c.to) {
                refused[c.from as usize].push((c.from, c.to));
                refused[c.to as usize].push((c.from, c.to));
                continue;
            }
            // Lazy re-keying: the cost may be stale or too low a guess. A candidate whose
            // estimated error is well above it goes back keyed by the estimate, so collapses
            // happen roughly in the order of their node errors: one whose error comes out
            // high early gives its high error to every later collapse around it (monotone),
            // which keeps the cuts below it fine there (ordered by the quadric alone, 727 of
            // the 2 899 nodes of `models/spot.obj` as one hierarchy inherited an error above
            // 0.5 % of the diagonal, passed on from 85 nodes above it on their own).
            let ring = self.ring[c.from as usize];
            if c.ring != ring {
                let estimate = self.predict(c.from, c.to);
                if estimate > c.cost * REKEY_RATIO {
                    heap.push(Candidate {
                        cost: estimate,
                        ring,
                        ..c
                    });
                    continue;
                }
            }
            // The border neighbour of `from` that `to` takes over: its border rules change.
            let other = self.border[c.from as usize]
                .as_ref()
                .and_then(|nb| nb.iter().copied().find(|&x| x != c.to));
            self.collapse(c.from, c.to);
            // Costs change only at `to` (its quadric grew) and border rules only at `to` and
            // `other`: their stamps retire every candidate they are in, which are pushed
            // again. The triangles around `to` and its neighbours changed, so candidates
            // refused there get another chance; every other candidate in the heap stands.
            edges.clear();
            for w in [Some(c.to), other].into_iter().flatten() {
                self.stamp[w as usize] += 1;
                touched.clear();
                self.neighbours_into(w, &mut touched);
                edges.extend(touched.iter().flat_map(|&x| [(w, x), (x, w)]));
            }
            self.stamp[c.from as usize] += 1;
            touched.clear();
            self.neighbours_into(c.to, &mut touched);
            touched.push(c.to);
            for &w in &touched {
                edges.append(&mut refused[w as usize]);
            }
            edges.sort_unstable();
            edges.dedup();
            for &(x, y) in &edges {
                if self.vertex_removed_by[x as usize] != NEVER
                    || self.vertex_removed_by[y as usize] != NEVER
                {
                    continue;
                }
                if let Some(c) = self.candidate(x, y) {
                    heap.push(c);
                }
            }
        }
        // With split vertices, the triangles' own vertices, each removed with its position.
        let (triangles, vertex_removed_by, vertex_target) = match self.split {
            Some(split) => (
                split.tris,
                (split.rep.iter())
                    .map(|&r| self.vertex_removed_by[r as usize])
                    .collect(),
                split.target,
            ),
            None => (self.tris, self.vertex_removed_by, self.vertex_target),
        };
        let mut h = MtHierarchy {
            triangles,
            created_by: self.created_by,
            removed_by: self.removed_by,
            node_error: self.node_error,
            vertex_removed_by,
            vertex_target,
            ..Default::default()
        };
        h.layout();
        h
    }

    /// A cheap estimate of the error the collapse of `from` onto `to` would have, from below
    /// (its node error is never lower: [`Builder::measure`] starts from the inherited error and
    /// the distance of every corner of the region to the fan): the largest of the errors it
    /// would inherit and the distance from every original vertex that the triangles around
    /// `from` stand for (a corner of a piece they cover) to the fan it would make. Depends
    /// only on the triangles around `from` (and their covers, fixed while they live), so it
    /// holds while `ring[from]` does.
    fn predict(&mut self, from: u32, to: u32) -> f64 {
        let pt = self.pos[to as usize];
        let mut fan = std::mem::take(&mut self.scratch_predict);
        fan.clear();
        let mut error = 0.0f64;
        for &t in &self.around[from as usize] {
            error = error.max(self.node_error[self.created_by[t as usize] as usize]);
            let tri = self.tris[t as usize];
            if !tri.contains(&to) {
                let [a, b, c] = tri.map(|i| if i == from { pt } else { self.pos[i as usize] });
                fan.push(crate::geom::Prepared::new(a, b, c));
            }
        }
        if fan.is_empty() {
            self.scratch_predict = fan;
            return error;
        }
        let seen = self.next_generation();
        let originals = self.pos.len() as u32;
        let mut k = 0;
        for &t in &self.around[from as usize] {
            // The fan triangle this one becomes, if any, is tried first: the usual nearest.
            let own = match self.tris[t as usize].contains(&to) {
                true => 0,
                false => {
                    k += 1;
                    k - 1
                }
            };
            for &o in &self.covers[t as usize] {
                for v in self.piece_points[o as usize] {
                    // Original vertices only (with the corners of split pieces too, the
                    // bunny's build took 1.2× as long for under 1 % fewer triangles).
                    if v >= originals || self.mark[v as usize] == seen {
                        continue;
                    }
                    self.mark[v as usize] = seen;
                    let p = self.pos[v as usize];
                    let mut d = fan[own].distance(p);
                    // Only the largest distance counts: the search for the nearest stops
                    // once one triangle is within it.
                    for (j, t) in fan.iter().enumerate() {
                        if d <= error {
                            break;
                        }
                        if j != own {
                            d = d.min(t.distance(p));
                        }
                    }
                    error = error.max(d);
                }
            }
        }
        self.scratch_predict = fan;
        error
    }

    /// Moves `from` onto `to`: one node of the hierarchy.
    fn collapse(&mut self, from: u32, to: u32) {
        let node = self.node_error.len() as u32;
        let mut removed = std::mem::take(&mut self.scratch_removed);
        removed.clone_from(&self.around[from as usize]);
        self.vertex_removed_by[from as usize] = node;
        self.vertex_target[from as usize] = to;
        if let Some(split) = &mut self.split {
            for i in 0..split.at[from as usize].len() {
                let w = split.at[from as usize][i];
                // `allowed` checked that every vertex has its one target.
                let target = split.target_of(w, to, &removed, &self.tris).unwrap_or(to);
                split.target[w as usize] = target;
            }
        }
        let mut region = std::mem::take(&mut self.scratch_region);
        region.clear();
        let mut own = std::mem::take(&mut self.scratch_own);
        own.clear();
        let mut inherited = 0.0f64;
        let mut next = 0;
        for &t in &removed {
            self.removed_by[t as usize] = node;
            inherited = inherited.max(self.node_error[self.created_by[t as usize] as usize]);
            // The fan triangle `t` becomes (fans are made in the order of `removed`).
            let k = match self.tris[t as usize].contains(&to) {
                true => NEVER,
                false => {
                    next += 1;
                    next - 1
                }
            };
            own.extend(self.covers[t as usize].iter().map(|_| k));
            region.append(&mut self.covers[t as usize]);
            // The emptied list keeps its capacity for a triangle of the fan.
            let emptied = std::mem::take(&mut self.covers[t as usize]);
            self.spare_covers.push(emptied);
            for v in self.tris[t as usize] {
                self.around[v as usize].retain(|&x| x != t);
                self.ring[v as usize] = (self.ring[v as usize] + 1) % NEVER;
            }
        }
        let mut fan = std::mem::take(&mut self.scratch_fan);
        fan.clear();
        for &t in &removed {
            let tri = self.tris[t as usize];
            if tri.contains(&to) {
                continue;
            }
            let new = tri.map(|i| if i == from { to } else { i });
            if let Some(split) = &mut self.split {
                let own = split.tris[t as usize];
                let moved = std::array::from_fn(|k| match tri[k] == from {
                    true => split.target[own[k] as usize],
                    false => own[k],
                });
                split.tris.push(moved);
            }
            let id = self.tris.len() as u32;
            self.tris.push(new);
            let corners = new.map(|i| self.pos[i as usize]);
            self.corners.push(corners);
            self.spheres.push(bound::sphere(&corners));
            self.created_by.push(node);
            self.removed_by.push(NEVER);
            self.covers
                .push(self.spare_covers.pop().unwrap_or_default());
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
        let error = self.measure(&fan, &region, &own, inherited);
        self.scratch_own = own;
        self.node_error.push(error.max(inherited));
        #[cfg(test)]
        self.check_covers(&fan);
        self.scratch_removed = removed;
        self.scratch_region = region;
        self.scratch_fan = fan;
    }
}

mod measure;
mod quadric;
mod split;

use quadric::Quadric;

use split::{Split, Wedges};

#[cfg(test)]
mod tests;
