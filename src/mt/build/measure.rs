//! The error of a collapse (`super`): a certified upper bound of the two-sided Hausdorff
//! distance between its fan and the original surface ([`Builder::measure`]), from the bounds of
//! [`super::super::bound`].

use glam::DVec3;

use super::super::bound::{self, Piece};
use super::{Builder, FAN_DEPTH, Group, PIECE_DEPTH, SLACK, outside, samples};
use crate::geom::point_triangle_distance;

impl Builder {
    /// Distance from `p` to the live or fan triangle `t`.
    fn dist(&self, p: DVec3, t: u32) -> f64 {
        let [a, b, c] = self.corners[t as usize];
        point_triangle_distance(p, a, b, c)
    }

    /// Distance from `p` to the piece of the original surface `o`.
    fn piece_dist(&self, p: DVec3, o: u32) -> f64 {
        let [a, b, c] = self.pieces[o as usize];
        point_triangle_distance(p, a, b, c)
    }

    /// Whether piece `o` is certainly farther than `d` from `p`.
    fn piece_beyond(&self, p: DVec3, o: u32, d: f64) -> bool {
        outside(p, self.piece_spheres[o as usize], d)
    }

    /// A new piece of the original surface, `depth` splits below an original triangle.
    fn add_piece(&mut self, piece: Piece, depth: u8, origin: u32) -> u32 {
        let id = self.pieces.len() as u32;
        self.pieces.push(piece);
        self.piece_spheres.push(bound::sphere(&piece));
        self.piece_depth.push(depth);
        self.piece_origin.push(origin);
        id
    }

    /// The error of a collapse: a certified upper bound of the two-sided Hausdorff distance
    /// between the triangles `fan` and the original surface, no lower than `inherited`
    /// (see [`bound`] for the facts it rests on).
    ///
    /// - **Original → fan**, against one triangle: every piece of the original surface in
    ///   `region` is given to the fan triangle whose farthest point from it is nearest
    ///   (exact at its corners: convexity) and stays in its cover until that
    ///   triangle is removed, so every cut holding the triangle holds the bound. A piece
    ///   whose bound is loose is split along the side of its triangle that it overhangs
    ///   (kept split, at most [`PIECE_DEPTH`] times).
    /// - **Fan → original**, against the original surface near it (the region's pieces and
    ///   those covered by the live triangles around the fan): a fan triangle that surface
    ///   covers without folding is bounded by its height over it ([`Builder::height_bound`]);
    ///   any other by the convex bound against the one nearest piece, or the corners'
    ///   distances plus the Lipschitz term, split where loose (along the side of that piece,
    ///   at most [`FAN_DEPTH`] times) and bounded part by part.
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
        groups: &[Group],
        inherited: f64,
    ) -> f64 {
        let mut assigned = std::mem::take(&mut self.scratch_assigned);
        assigned.clear();
        let mut lower = 0.0f64;
        for &o in region {
            let (at, bound, near) = self.nearest_fan_triangle(fan, o);
            lower = lower.max(near);
            self.covers[at as usize].push(o);
            assigned.push((o, at, bound));
        }
        // The pieces covered by the live triangles around the fan: original surface near the
        // fan, as true a target for the fan → original distance as the region's own.
        let mut cands = std::mem::take(&mut self.scratch_cands);
        let mut cand_groups = std::mem::take(&mut self.scratch_cand_groups);
        cands.clear();
        cands.extend_from_slice(region);
        cand_groups.clear();
        cand_groups.extend_from_slice(groups);
        let mut ring = std::mem::take(&mut self.scratch_ring);
        ring.clear();
        let first_fan = fan.first().copied().unwrap_or(u32::MAX);
        for &t in fan {
            for v in self.tris[t as usize] {
                ring.extend(self.around[v as usize].iter().filter(|&&r| r < first_fan));
            }
        }
        ring.sort_unstable();
        ring.dedup();
        for &r in &ring {
            let start = cands.len() as u32;
            cands.extend_from_slice(&self.covers[r as usize]);
            cand_groups.push(Group {
                start,
                end: cands.len() as u32,
                sphere: self.cover_spheres[r as usize],
            });
        }
        lower = self.sample_lower(fan, &cands, &cand_groups, lower);
        // `lower`: distances measured at points (no bound of this collapse is below them);
        // `worst`: the bound so far. A bound within `limit` is taken as it is; slack is allowed
        // over the collapse's own distances only, not over the inherited error (it would
        // compound from node to node up the DAG: 1.2 allowed over it drew 2–4× the bunny's
        // triangles).
        let mut worst = lower.max(inherited);
        let limit = |worst: f64, lower: f64| worst.max(lower * (1.0 + SLACK));
        // Original → fan: the loose pieces split, the rest kept where assigned.
        for &t in fan {
            self.covers[t as usize].clear();
        }
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
            for &part in &parts {
                let id = self.add_piece(part, depth, self.piece_origin[o as usize]);
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
        // Fan → original.
        let mut todo = std::mem::take(&mut self.scratch_fan_pieces);
        for &t in fan {
            if let Some(bound) = self.height_bound(t)
                && bound <= limit(worst, lower)
            {
                worst = worst.max(bound);
                continue;
            }
            todo.clear();
            todo.push((
                self.corners[t as usize],
                0u8,
                self.covers[t as usize].first().copied(),
            ));
            while let Some((piece, depth, hint)) = todo.pop() {
                let (bound, nearest, near) =
                    self.bound_piece(&piece, &cands, &cand_groups, worst, hint);
                lower = lower.max(near);
                worst = worst.max(near);
                if bound <= worst {
                    continue;
                }
                if bound <= limit(worst, lower) || depth >= FAN_DEPTH {
                    worst = bound;
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
        self.scratch_ring = ring;
        self.scratch_cands = cands;
        self.scratch_cand_groups = cand_groups;
        self.scratch_assigned = assigned;
        worst
    }

    /// [`bound::height_over`] for fan triangle `t` over the original triangles of the pieces
    /// it covers and those covered by the triangles across its edges (live ones, the fan's
    /// included): the surface under it and around its edges.
    fn height_bound(&mut self, t: u32) -> Option<f64> {
        let mut near = std::mem::take(&mut self.scratch_near);
        near.clear();
        let tri = self.tris[t as usize];
        near.extend(
            self.covers[t as usize]
                .iter()
                .map(|&o| self.piece_origin[o as usize]),
        );
        for k in 0..3 {
            let (u, v) = (tri[k], tri[(k + 1) % 3]);
            for &x in &self.around[u as usize] {
                if x != t && self.tris[x as usize].contains(&v) {
                    near.extend(
                        self.covers[x as usize]
                            .iter()
                            .map(|&o| self.piece_origin[o as usize]),
                    );
                }
            }
        }
        near.sort_unstable();
        near.dedup();
        let mut originals = std::mem::take(&mut self.scratch_originals);
        originals.clear();
        originals.extend(
            near.iter()
                .map(|&o| (self.corners[o as usize], self.tris[o as usize])),
        );
        let mut edges = std::mem::take(&mut self.scratch_edges3);
        let bound = bound::height_over(&self.corners[t as usize], &originals, &mut edges);
        self.scratch_edges3 = edges;
        self.scratch_originals = originals;
        self.scratch_near = near;
        bound
    }

    /// The fan triangle whose farthest point from piece `o` is nearest, that distance (exact,
    /// convexity), and the largest over the piece's corners of their distance to the nearest
    /// fan triangle (a true distance to the fan: a lower bound of what the piece needs).
    fn nearest_fan_triangle(&self, fan: &[u32], o: u32) -> (u32, f64, f64) {
        let piece = self.pieces[o as usize];
        let mut corner_best = [f64::INFINITY; 3];
        let mut best = (fan[0], f64::INFINITY);
        for &t in fan {
            // A corner whose distance cannot matter (beyond its nearest so far, and the
            // triangle already farther than the best) is not measured.
            let sphere = self.spheres[t as usize];
            let mut far = 0.0f64;
            for (k, &p) in piece.iter().enumerate() {
                if far > best.1 && outside(p, sphere, corner_best[k]) {
                    continue;
                }
                let d = self.dist(p, t);
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

    /// A certified bound of the distance from every point of `piece` to the pieces `cands`
    /// (grouped by `groups`), or a value no above `worst` once the piece is known to be within
    /// it; and the piece whose convex bound is the nearest (what to split along).
    fn bound_piece(
        &self,
        piece: &Piece,
        cands: &[u32],
        groups: &[Group],
        worst: f64,
        hint: Option<u32>,
    ) -> (f64, Option<u32>, f64) {
        let mut corner_best = [f64::INFINITY; 3];
        let mut convex = (f64::INFINITY, None);
        // The hint first: a part of a piece split along `hint` often lies over it.
        if let Some(o) = hint {
            let mut far = 0.0f64;
            for (k, &p) in piece.iter().enumerate() {
                let d = self.piece_dist(p, o);
                corner_best[k] = corner_best[k].min(d);
                far = far.max(d);
            }
            convex = (far, Some(o));
            if far <= worst {
                return (far, convex.1, 0.0);
            }
        }
        for g in groups {
            if piece
                .iter()
                .zip(&corner_best)
                .all(|(&p, &b)| outside(p, g.sphere, b))
                && piece.iter().any(|&p| outside(p, g.sphere, convex.0))
            {
                continue;
            }
            for &o in &cands[g.start as usize..g.end as usize] {
                // Skipped when it can lower no corner's distance and not the convex bound.
                if piece
                    .iter()
                    .zip(&corner_best)
                    .all(|(&p, &b)| self.piece_beyond(p, o, b))
                    && piece.iter().any(|&p| self.piece_beyond(p, o, convex.0))
                {
                    continue;
                }
                let mut far = 0.0f64;
                for (k, &p) in piece.iter().enumerate() {
                    let d = self.piece_dist(p, o);
                    corner_best[k] = corner_best[k].min(d);
                    far = far.max(d);
                }
                if far < convex.0 {
                    convex = (far, Some(o));
                    if far <= worst {
                        return (far, convex.1, 0.0);
                    }
                }
            }
        }
        // Every piece that could be nearer to a corner was measured: true distances.
        let near = corner_best.into_iter().fold(0.0, f64::max);
        let lipschitz = near + bound::covering_radius(piece);
        (convex.0.min(lipschitz), convex.1, near)
    }

    /// Sampled lower bound of the fan → original distance: the largest of `worst` and the
    /// true distance from every sample of the fan ([`samples`]) to the pieces `cands`
    /// (grouped by `groups`). It tells [`Builder::measure`] which certified bounds are loose.
    fn sample_lower(
        &mut self,
        fan: &[u32],
        cands: &[u32],
        groups: &[Group],
        mut worst: f64,
    ) -> f64 {
        // Corners and edges the fan triangles share are sampled once.
        let g = self.next_generation();
        let mut edges = std::mem::take(&mut self.fan_edges);
        edges.clear();
        for &t in fan {
            let tri = self.tris[t as usize];
            let [a, b, c] = self.corners[t as usize];
            let mut todo = [true; 7];
            for k in 0..3 {
                todo[k] = self.mark[tri[k] as usize] != g;
                self.mark[tri[k] as usize] = g;
                let e = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                todo[3 + k] = !edges.contains(&e);
                if todo[3 + k] {
                    edges.push(e);
                }
            }
            let own = &self.covers[t as usize];
            for (s, _) in samples(a, b, c).into_iter().zip(todo).filter(|x| x.1) {
                // Its own pieces first, then the groups, a group skipped whole when its sphere
                // is beyond the nearest so far. The outcome, max(worst, nearest) — unchanged
                // once a piece within `worst` is found — does not depend on the order.
                let mut best = f64::INFINITY;
                let scan = |list: &[u32], best: &mut f64| {
                    for &o in list {
                        if self.piece_beyond(s, o, *best) {
                            continue;
                        }
                        *best = best.min(self.piece_dist(s, o));
                        if *best <= worst {
                            return true;
                        }
                    }
                    false
                };
                if !scan(own, &mut best) {
                    for g in groups {
                        if !outside(s, g.sphere, best)
                            && scan(&cands[g.start as usize..g.end as usize], &mut best)
                        {
                            break;
                        }
                    }
                }
                if best.is_finite() {
                    worst = worst.max(best);
                }
            }
        }
        self.fan_edges = edges;
        worst
    }
}
