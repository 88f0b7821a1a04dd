//! The error of a collapse (`super`): a certified upper bound of the two-sided Hausdorff
//! distance between its fan and the original surface ([`Builder::measure`]), from the bounds of
//! [`super::super::bound`].
//!
//! It measures against the original pieces, not against the triangles the collapse removes:
//! the cheaper additive bound (inherited error plus a certified Hausdorff bound between the
//! ring before and after the collapse, no piece touched) was tried on 2026-12-07 and
//! compounds up the DAG: the bunny's cuts at 0.5 / 1 / 2 % of its diagonal drew 11 414 /
//! 5 705 / 2 338 triangles against 2 462 / 1 075 / 529, and its build was slower (39.6 s on
//! one thread against 5.5 s: 0.87 M ring bounds per build, collapses and their re-keying
//! estimates, each split into 68 parts on average).

use glam::DVec3;

use super::super::bound::{self, Piece};
use super::super::nearest::PieceBound;
use super::{Builder, FAN_DEPTH, NEVER, PIECE_DEPTH, SLACK, samples};
use crate::geom::Prepared;

impl Builder {
    /// Distance from `p` to the live or fan triangle `t`.
    #[cfg(test)]
    fn dist(&self, p: DVec3, t: u32) -> f64 {
        let [a, b, c] = self.corners[t as usize];
        crate::geom::point_triangle_distance(p, a, b, c)
    }

    /// A new piece of the original surface, `depth` splits below an original triangle.
    fn add_piece(&mut self, piece: Piece, depth: u8, parent: u32) -> u32 {
        let id = self.pieces.len() as u32;
        let origin = self.piece_origin[parent as usize];
        self.pieces.push(piece);
        self.piece_parent.push(parent);
        self.piece_parts.push((0, 0));
        self.piece_mark.push(0);
        let ids = piece.map(|p| self.point_id(p));
        self.piece_points.push(ids);
        self.piece_depth.push(depth);
        self.piece_origin.push(origin);
        id
    }

    /// The id of point `p` (a corner of a piece), a new one if it is not known yet.
    fn point_id(&mut self, p: DVec3) -> u32 {
        let key = (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
        let next = self.points.len() as u32;
        let id = *self.point_ids.entry(key).or_insert(next);
        if id == next {
            self.points.push(p);
            self.point_mark.push(0);
            self.point_slot.push(0);
        }
        id
    }

    /// The error of a collapse: a certified upper bound of the two-sided Hausdorff distance
    /// between the triangles `fan` and the original surface, no lower than `inherited`
    /// (see [`bound`] for the facts it rests on).
    ///
    /// - **Original → fan**, against one triangle: every piece of the original surface in
    ///   `region` (`own[i]`: the index in `fan` of the triangle that the one covering
    ///   `region[i]` became, or [`NEVER`]) stays with that triangle when its farthest point
    ///   (exact at its corners: convexity) is within the floor, `inherited` and the sampled
    ///   distances of the fan ([`Builder::sample_lower`]); any other is given to the fan
    ///   triangle whose farthest point from it is nearest. It stays in that triangle's cover
    ///   until the triangle is removed, so every cut holding the triangle holds the bound. A
    ///   piece whose bound is loose is split along the side of its triangle that it overhangs
    ///   (at most [`PIECE_DEPTH`] times), and merged back when its parts come together in one
    ///   cover ([`Builder::coalesce`]).
    /// - **Fan → original**: a fan triangle that the original surface around it covers without
    ///   folding is bounded by its height over it ([`Builder::height_bound`]); any other, against
    ///   the patch's whole original surface (a box hierarchy, [`super::super::nearest`]), by the
    ///   convex bound against the one nearest original triangle, or the corners' distances plus
    ///   the Lipschitz term, split where loose (along the side of that triangle, at most
    ///   [`FAN_DEPTH`] times) and bounded part by part.
    ///
    /// "Loose" means above the bound so far (at least `inherited`) and above `(1 + `[`SLACK`]`)`
    /// times `lower`: the largest distance measured from a point of the fan or of the region
    /// to the nearest of the other ([`Builder::sample_lower`], and the corners the bounds
    /// measure), which no bound of this collapse can be below. Slack over `inherited` would
    /// compound up the DAG. What is returned is never below the true distance, and above
    /// `max(inherited, (1 + SLACK) · lower)` only where a depth limit stopped.
    pub(super) fn measure(
        &mut self,
        fan: &[u32],
        region: &[u32],
        own: &[u32],
        inherited: f64,
    ) -> f64 {
        let mut assigned = std::mem::take(&mut self.scratch_assigned);
        assigned.clear();
        // A new collapse: no corner's distances to this fan are known yet.
        self.point_generation = self.point_generation.wrapping_add(1);
        if self.point_generation == 0 {
            self.point_mark.fill(0);
            self.point_generation = 1;
        }
        self.fan_dist.clear();
        self.fan_prepared.clear();
        for &t in fan {
            let [a, b, c] = self.corners[t as usize];
            self.fan_prepared.push(Prepared::new(a, b, c));
        }
        let mut lower = self.sample_lower(fan, 0.0);
        let floor = lower.max(inherited);
        for (&o, &k) in region.iter().zip(own) {
            // A piece within the floor of the triangle it was given to, as that triangle
            // moved: kept there, the other fan triangles unmeasured.
            if k != NEVER {
                let bound = self.bound_against(fan, o, k as usize);
                if bound <= floor {
                    assigned.push((o, fan[k as usize], bound));
                    continue;
                }
            }
            let (at, bound, near) = self.nearest_fan_triangle(fan, o);
            lower = lower.max(near);
            assigned.push((o, at, bound));
        }
        // `lower`: distances measured at points (no bound of this collapse is below them);
        // `worst`: the bound so far. A bound within `limit` is taken as it is; slack is allowed
        // over the collapse's own distances only, not over the inherited error (it would
        // compound from node to node up the DAG: 1.2 allowed over it drew 2–4× the bunny's
        // triangles).
        let mut worst = lower.max(inherited);
        let limit = |worst: f64, lower: f64| worst.max(lower * (1.0 + SLACK));
        // Original → fan: the loose pieces split, the rest kept where assigned.
        let mut stack = std::mem::take(&mut self.scratch_pieces);
        stack.clear();
        for &(o, at, bound) in &assigned {
            if bound <= limit(worst, lower) || self.piece_depth[o as usize] >= PIECE_DEPTH {
                self.covers[at as usize].push(o);
                worst = worst.max(bound);
            } else {
                stack.push((o, at));
            }
        }
        let mut parts = std::mem::take(&mut self.scratch_parts);
        while let Some((o, at)) = stack.pop() {
            parts.clear();
            let piece = self.pieces[o as usize];
            let tri = self.corners[at as usize];
            bound::split(&piece, Some(&tri), &mut parts);
            let depth = self.piece_depth[o as usize] + 1;
            self.piece_parts[o as usize] = (self.pieces.len() as u32, parts.len() as u32);
            for &part in &parts {
                let id = self.add_piece(part, depth, o);
                let (at, bound, near) = self.nearest_fan_triangle(fan, id);
                lower = lower.max(near);
                worst = worst.max(near);
                if bound <= limit(worst, lower) || depth >= PIECE_DEPTH {
                    self.covers[at as usize].push(id);
                    worst = worst.max(bound);
                } else {
                    stack.push((id, at));
                }
            }
        }
        for &t in fan {
            self.coalesce(t);
        }
        // Fan → original.
        let mut todo = std::mem::take(&mut self.scratch_fan_pieces);
        for &t in fan {
            let height = self.height_bound(t, worst);
            if let Some(bound) = height
                && bound <= limit(worst, lower)
            {
                worst = worst.max(bound);
                continue;
            }
            // A loose height bound still caps what splitting is worth: once a part is
            // bounded no tighter (past the depth limit or within the slack), the height bound
            // is taken for the whole triangle instead.
            let cap = height.unwrap_or(f64::INFINITY);
            todo.clear();
            todo.push((
                self.corners[t as usize],
                0u8,
                self.covers[t as usize]
                    .first()
                    .map(|&o| self.piece_origin[o as usize]),
            ));
            while let Some((piece, depth, hint)) = todo.pop() {
                let (bound, nearest, near) = self.bound_piece(&piece, worst, hint);
                lower = lower.max(near);
                worst = worst.max(near);
                if bound <= worst {
                    continue;
                }
                if bound <= limit(worst, lower) || depth >= FAN_DEPTH {
                    // `cap` is above `worst` (it was loose), so it bounds this triangle and
                    // every one before it.
                    worst = bound.min(cap);
                    if bound >= cap {
                        break;
                    }
                    continue;
                }
                parts.clear();
                let along = nearest.map(|o| self.pieces[o as usize]);
                bound::split(&piece, along.as_ref(), &mut parts);
                todo.extend(parts.iter().map(|&p| (p, depth + 1, nearest)));
            }
        }
        self.scratch_fan_pieces = todo;
        self.scratch_parts = parts;
        self.scratch_pieces = stack;
        self.scratch_assigned = assigned;
        worst
    }

    /// The invariant the original → fan half of every node error rests on, checked after each
    /// collapse in tests: every piece in the cover of a fan triangle is within the node's
    /// error of it (at its corners: convexity).
    #[cfg(test)]
    pub(super) fn check_covers(&self, fan: &[u32]) {
        for &t in fan {
            let error = self.node_error[self.created_by[t as usize] as usize];
            for &o in &self.covers[t as usize] {
                let far = (self.pieces[o as usize].iter())
                    .map(|&p| self.dist(p, t))
                    .fold(0.0, f64::max);
                assert!(
                    far <= error,
                    "piece {o} is {far} from triangle {t}, error {error}"
                );
            }
        }
    }

    /// Replaces, in the cover of fan triangle `t`, the parts of a split piece by the piece
    /// when all of them are there (repeatedly: up to an original triangle). The piece's bound
    /// against `t` is no looser than its parts' (the distance to a triangle is convex: its
    /// largest over the piece is at one of the piece's corners, which are corners of parts),
    /// so the collapse's error stands, and later collapses measure fewer pieces.
    fn coalesce(&mut self, t: u32) {
        self.piece_generation = self.piece_generation.wrapping_add(1);
        if self.piece_generation == 0 {
            self.piece_mark.fill(0);
            self.piece_generation = 1;
        }
        let g = self.piece_generation;
        let mut list = std::mem::take(&mut self.covers[t as usize]);
        for &p in &list {
            self.piece_mark[p as usize] = g;
        }
        let mut merged = false;
        let mut i = 0;
        while i < list.len() {
            let q = self.piece_parent[list[i] as usize];
            i += 1;
            if q == NEVER || self.piece_mark[q as usize] == g {
                continue;
            }
            let (first, count) = self.piece_parts[q as usize];
            let parts = first as usize..(first + count) as usize;
            if self.piece_mark[parts.clone()].iter().all(|&m| m == g) {
                self.piece_mark[parts].fill(0);
                self.piece_mark[q as usize] = g;
                list.push(q);
                merged = true;
            }
        }
        if merged {
            list.retain(|&p| self.piece_mark[p as usize] == g);
        }
        self.covers[t as usize] = list;
    }

    /// [`bound::height_over`] for fan triangle `t` over the original triangles of the pieces
    /// it covers, grown across every original edge that enters the prism over `t` (up to a
    /// cap): the surface under it. Each live border edge at a corner of `t` adds the original
    /// border edges it replaced and their triangles ([`Builder::border_chain`]), so the parts
    /// of `t` between such an edge and its chain are bounded too. Any list of originals
    /// gives a certified bound (or none): the list only decides how often one is found.
    /// `floor`: the node's bound so far, below which heights are taken as they are.
    fn height_bound(&mut self, t: u32, floor: f64) -> Option<f64> {
        let mut near = std::mem::take(&mut self.scratch_near);
        near.clear();
        // Each original once: marked with a fresh generation as it is listed.
        self.origin_generation = self.origin_generation.wrapping_add(1);
        if self.origin_generation == 0 {
            self.origin_mark.fill(0);
            self.origin_generation = 1;
        }
        let g = self.origin_generation;
        let tri = self.tris[t as usize];
        let mut mark = std::mem::take(&mut self.origin_mark);
        let mut chain = std::mem::take(&mut self.scratch_chain);
        let mut points = std::mem::take(&mut self.scratch_chain_points);
        let mut spans = std::mem::take(&mut self.scratch_spans);
        let mut keys = std::mem::take(&mut self.scratch_keys);
        points.clear();
        spans.clear();
        keys.clear();
        for &o in &self.covers[t as usize] {
            let origin = self.piece_origin[o as usize];
            if mark[origin as usize] != g {
                mark[origin as usize] = g;
                near.push(origin);
            }
        }
        for k in 0..3 {
            let u = tri[k];
            // The live border edges at the corner, each once (from its first corner of `t`).
            let Some(along) = &self.border[u as usize] else {
                continue;
            };
            for &v in along {
                if tri[..k].contains(&v) {
                    continue;
                }
                chain.clear();
                if !self.border_chain(u, v, &mut chain) {
                    continue;
                }
                let start = points.len();
                for (i, &(w, via)) in chain.iter().enumerate() {
                    points.push(self.pos[w as usize]);
                    if i > 0 {
                        let prev = chain[i - 1].0;
                        keys.push((prev.min(w), prev.max(w)));
                        if mark[via as usize] != g {
                            mark[via as usize] = g;
                            near.push(via);
                        }
                    }
                }
                spans.push((start, points.len(), tri.contains(&v)));
            }
        }
        keys.sort_unstable();
        // Grown across every original edge that enters the prism over `t` (up to a cap): the
        // union's boundary inside the prism is then the patch border and the folds.
        let (sides, margin) = bound::prism(&self.corners[t as usize]);
        let cap = 4 * near.len() + 64;
        let mut i = 0;
        while i < near.len() && near.len() < cap {
            let o = near[i] as usize;
            i += 1;
            let c = self.corners[o];
            for k in 0..3 {
                let x = self.across[o][k];
                if x != NEVER
                    && mark[x as usize] != g
                    && bound::enters(&sides, margin, c[k], c[(k + 1) % 3])
                {
                    mark[x as usize] = g;
                    near.push(x);
                }
            }
        }
        self.origin_mark = mark;
        let mut originals = std::mem::take(&mut self.scratch_originals);
        originals.clear();
        originals.extend(
            near.iter()
                .map(|&o| (self.corners[o as usize], self.tris[o as usize])),
        );
        let mut edges = std::mem::take(&mut self.scratch_edges3);
        let chains = bound::Chains {
            spans: &spans,
            points: &points,
            keys: &keys,
        };
        let bound = bound::height_over(
            &self.corners[t as usize],
            &originals,
            &chains,
            floor,
            &mut edges,
        );
        self.scratch_edges3 = edges;
        self.scratch_originals = originals;
        self.scratch_near = near;
        self.scratch_chain = chain;
        self.scratch_chain_points = points;
        self.scratch_spans = spans;
        self.scratch_keys = keys;
        bound
    }

    /// The original border edges that the border edge from `u` to `v` (live vertices)
    /// stands for, appended to `out` from `u` to `v`: each vertex with the original triangle of
    /// the edge that reaches it ([`NEVER`] for `u`). Border vertices are only ever collapsed
    /// onto a border neighbour, their neighbour taken over (`Builder::collapse`), so a live
    /// border edge replaces the original border path between its ends through removed
    /// vertices (each with two border neighbours). `false`, nothing appended, when no such path
    /// or two (both ways round a loop) lead from `u` to `v`.
    fn border_chain(&self, u: u32, v: u32, out: &mut Vec<(u32, u32)>) -> bool {
        let start = out.len();
        let mut found = false;
        for &(first, via) in &self.border_links[u as usize] {
            let from = out.len();
            out.push((u, NEVER));
            let (mut prev, mut cur, mut via) = (u, first, via);
            loop {
                out.push((cur, via));
                if self.vertex_removed_by[cur as usize] == NEVER
                    || out.len() - from > self.pos.len()
                {
                    break;
                }
                let links = &self.border_links[cur as usize];
                if links.len() != 2 {
                    break;
                }
                let next = if links[0].0 == prev {
                    links[1]
                } else {
                    links[0]
                };
                (prev, cur, via) = (cur, next.0, next.1);
            }
            if cur == v && self.vertex_removed_by[cur as usize] == NEVER {
                if found {
                    out.truncate(start);
                    return false;
                }
                found = true;
            } else {
                out.truncate(from);
            }
        }
        found
    }

    /// The fan triangle whose farthest point from piece `o` is nearest, that distance (exact,
    /// convexity), and the largest over the piece's corners of their distance to the nearest
    /// fan triangle (a true distance to the fan: a lower bound of what the piece needs).
    ///
    /// Pieces share corners (an original vertex is a corner of about six), so each corner's
    /// distances to the fan are measured once per collapse ([`Builder::fan_distances`]); ties
    /// go to the first fan triangle.
    fn nearest_fan_triangle(&mut self, fan: &[u32], o: u32) -> (u32, f64, f64) {
        let ids = self.piece_points[o as usize];
        let rows = ids.map(|id| self.fan_distances(fan, id));
        let mut corner_best = [f64::INFINITY; 3];
        let mut best = (fan[0], f64::INFINITY);
        for (i, &t) in fan.iter().enumerate() {
            let mut far = 0.0f64;
            for k in 0..3 {
                let d = self.fan_distance(ids[k], rows[k], i);
                corner_best[k] = corner_best[k].min(d);
                far = far.max(d);
            }
            if far < best.1 {
                best = (t, far);
            }
        }
        let near = corner_best.into_iter().fold(0.0, f64::max);
        (best.0, best.1, near)
    }

    /// The farthest distance from piece `o` to fan triangle `fan[k]` (exact: at a corner).
    fn bound_against(&mut self, fan: &[u32], o: u32, k: usize) -> f64 {
        let mut far = 0.0f64;
        for id in self.piece_points[o as usize] {
            let row = self.fan_distances(fan, id);
            far = far.max(self.fan_distance(id, row, k));
        }
        far
    }

    /// Entry `k` of a row of [`Builder::fan_distances`], measured if it is not yet.
    fn fan_distance(&mut self, id: u32, row: usize, k: usize) -> f64 {
        let d = self.fan_dist[row + k];
        if !d.is_nan() {
            return d;
        }
        let d = self.fan_prepared[k].distance(self.points[id as usize]);
        self.fan_dist[row + k] = d;
        d
    }

    /// Where the distances from point `id` to the triangles of `fan` (in its order) start in
    /// `fan_dist`: a row made the first time the collapse asks (`point_generation`), its
    /// entries NaN until [`Builder::fan_distance`] measures them.
    fn fan_distances(&mut self, fan: &[u32], id: u32) -> usize {
        let i = id as usize;
        if self.point_mark[i] != self.point_generation {
            self.point_mark[i] = self.point_generation;
            self.point_slot[i] = self.fan_dist.len() as u32;
            self.fan_dist.extend(fan.iter().map(|_| f64::NAN));
        }
        self.point_slot[i] as usize
    }

    /// A certified bound of the distance from every point of `piece` to the original surface
    /// ([`SurfaceBvh::piece_bound`]), or a value no above `worst` once the piece is known to be
    /// within it; the original triangle whose convex bound is the nearest (what to split
    /// along); and the largest true distance from a corner to the surface (0 when within).
    /// `hint`: an original triangle measured first.
    fn bound_piece(&self, piece: &Piece, worst: f64, hint: Option<u32>) -> (f64, Option<u32>, f64) {
        match self.surface.piece_bound(piece, worst, hint) {
            PieceBound::Within { far, at } => (far, Some(at), 0.0),
            PieceBound::Full {
                corners,
                convex,
                at,
            } => {
                let near = corners.into_iter().fold(0.0, f64::max);
                let lipschitz = near + bound::covering_radius(piece);
                (convex.min(lipschitz), at, near)
            }
        }
    }

    /// Sampled lower bound of the fan → original distance: the largest of `worst` and the
    /// true distance from every sample of the fan ([`samples`]) but its corners (original
    /// vertices: on the surface) to the original surface. It
    /// tells [`Builder::measure`] which certified bounds are loose.
    fn sample_lower(&mut self, fan: &[u32], mut worst: f64) -> f64 {
        // Edges the fan triangles share are sampled once; corners never: they are original
        // vertices (collapses move a vertex onto another), on the surface.
        let mut edges = std::mem::take(&mut self.fan_edges);
        edges.clear();
        let mut seed = None;
        for &t in fan {
            let tri = self.tris[t as usize];
            let [a, b, c] = self.corners[t as usize];
            let mut todo = [false, false, false, true, true, true, true];
            for k in 0..3 {
                let e = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                todo[3 + k] = !edges.contains(&e);
                if todo[3 + k] {
                    edges.push(e);
                }
            }
            for (s, _) in samples(a, b, c).into_iter().zip(todo).filter(|x| x.1) {
                // The outcome, max(worst, nearest), is unchanged once a triangle within
                // `worst` is found: the search stops there. The last triangle found is
                // measured first (samples of a fan are close together).
                let (best, at) = self.surface.nearest(s, worst, seed);
                seed = at.or(seed);
                if best.is_finite() {
                    worst = worst.max(best);
                }
            }
        }
        self.fan_edges = edges;
        worst
    }
}
