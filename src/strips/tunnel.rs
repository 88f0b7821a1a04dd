//! Triangle strips by tunneling, after A. James Stewart, "Tunneling for Triangle Strips in
//! Continuous Level-of-Detail Meshes" (Graphics Interface 2001; `stewart-tunneling-strips`).
//!
//! The dual graph has a node per triangle and an edge per pair of edge-adjacent triangles;
//! every dual edge is a **strip edge** or not, each node has at most two strip edges and the
//! strip edges form no cycle, so every connected run of strip edges is one strip
//! (strips = nodes − strip edges). A **tunnel** is an alternating path (non-strip, strip, …,
//! non-strip) between two strip ends (nodes with fewer than two strip edges); complementing
//! its edges joins two strips into one (§3.2). The search is breadth-first from a strip end,
//! bounded to `max_len` dual edges (§4.1), with the paper's special cases:
//! - a one-edge tunnel joins two strips that end in adjacent triangles;
//! - a tunnel may end at an isolated triangle (zero strip edges);
//! - the last edge may not join two nodes of the same strip (it would close a loop, Fig. 6);
//! - after a non-strip edge that joins two nodes of one strip, the next (strip) edge must turn
//!   toward the tail of that edge (Fig. 7).
//!
//! Those rules use the strips before complementing; a tunnel that passes one strip several
//! times can still close a loop, so every complemented tunnel is checked by walking its strips
//! (the relabelling the paper needs anyway, §3.2) and undone if a loop formed.
//!
//! Dynamic meshes (§4.2): [`TunnelStrips::replace`] removes and adds triangles — an edge
//! collapse, a vertex split, or a merged MT node — then tunnels from every strip end among the
//! triangles around the change and from `extra` strip ends elsewhere (the paper's "E 5").
//!
//! Choices the paper leaves open: two triangles are adjacent only when they share an edge with
//! opposite directions (consistent orientation), so a strip never needs an orientation fix;
//! a non-manifold edge links the first two triangles that claim it. Static meshes start from a
//! greedy labelling that prefers sequential turns (SGI-like, fewer swaps), then tunnel until no
//! tunnel is found (`TunnelOptions::greedy_start = false` starts from single triangles, as the
//! paper does).

use std::collections::VecDeque;

use super::{StripIndices, encode_path};
use crate::util::IntMap;

// `CutStrips` lives in `cut_strips`; kept at its old path too.
pub use super::cut_strips::CutStrips;

pub(super) const NONE: u32 = u32::MAX;

/// Parameters of the tunnel search.
#[derive(Clone, Debug, PartialEq)]
pub struct TunnelOptions {
    /// Longest tunnel searched, in dual edges (the paper: 75 for static meshes).
    pub max_len: usize,
    /// Longest tunnel when repairing after a mesh change (the paper's "T 10" … "T 50").
    pub repair_len: usize,
    /// Strip ends elsewhere in the mesh tunneled from after every change ("E 5").
    pub extra: usize,
    /// Start static stripification from greedy sequential strips instead of single triangles.
    pub greedy_start: bool,
    /// Accept a tunnel only when it sends fewer indices: joining two strips saves 3 (two
    /// vertices and a restart) but may add swaps, so a tunnel adding more than 2 swaps is
    /// undone. Off: every tunnel is taken (the paper's pure strip count).
    pub swap_aware: bool,
    /// Candidate tunnels one search may complement and undo (loops, swaps) before it gives up.
    pub max_tries: usize,
    /// Passes over all strip ends in `TunnelStrips::optimize` (stops early when a pass finds
    /// no tunnel).
    pub passes: usize,
}

impl Default for TunnelOptions {
    fn default() -> Self {
        TunnelOptions {
            max_len: 75,
            repair_len: 20,
            extra: 5,
            greedy_start: true,
            swap_aware: true,
            max_tries: 8,
            passes: 8,
        }
    }
}

/// Counters of the work done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TunnelStats {
    /// Tunnels complemented (strips joined).
    pub tunnels: usize,
    /// Tunnels undone because they closed a loop.
    pub loops_undone: usize,
    /// Tunnels undone because they would add more swaps than they save.
    pub costly_undone: usize,
    /// Breadth-first searches run.
    pub searches: usize,
}

/// A stripification of a triangle set that changes: the labelled dual graph.
#[derive(Clone, Debug, Default)]
pub struct TunnelStrips {
    opts: TunnelOptions,
    tri: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// Neighbour across side k = the edge (tri[k], tri[k+1]).
    nb: Vec<[u32; 3]>,
    /// Bit k: side k is a strip edge.
    strip: Vec<u8>,
    /// Strip id and position along the strip (for the special cases).
    sid: Vec<u32>,
    pos: Vec<u32>,
    free: Vec<u32>,
    edges: IntMap<(u32, u32), u32>,
    alive_count: usize,
    strip_edges: usize,
    next_sid: u32,
    // Scratch of the breadth-first search and the walks.
    mark: Vec<u32>,
    parent: Vec<u32>,
    depth: Vec<u32>,
    epoch: u32,
    queue: VecDeque<u32>,
    seen: Vec<u32>,
    seen_epoch: u32,
    path: Vec<u32>,
    /// Strip ends to try tunnels from after changes (validated lazily).
    ends: Vec<u32>,
    end_cursor: usize,
    pub stats: TunnelStats,
}

impl TunnelStrips {
    /// An empty stripification.
    pub fn new(opts: TunnelOptions) -> TunnelStrips {
        TunnelStrips {
            opts,
            ..Default::default()
        }
    }

    /// Stripifies `triangles` (slot `i` = triangle `i`): greedy or single-triangle start, then
    /// tunnels until none is found.
    pub fn build(triangles: &[[u32; 3]], opts: TunnelOptions) -> TunnelStrips {
        let mut s = TunnelStrips::new(opts);
        s.reset(triangles);
        s.optimize();
        s
    }

    /// Replaces everything by `triangles` as single-triangle strips (slot `i` = triangle `i`),
    /// keeping the scratch buffers.
    pub fn reset(&mut self, triangles: &[[u32; 3]]) {
        self.tri.clear();
        self.alive.clear();
        self.nb.clear();
        self.strip.clear();
        self.sid.clear();
        self.pos.clear();
        self.free.clear();
        self.edges.clear();
        self.ends.clear();
        self.alive_count = 0;
        self.strip_edges = 0;
        for &t in triangles {
            self.add_one(t);
        }
    }

    pub fn options(&self) -> &TunnelOptions {
        &self.opts
    }

    /// Number of strips (isolated triangles count as strips).
    pub fn strip_count(&self) -> usize {
        self.alive_count - self.strip_edges
    }

    pub fn triangle_count(&self) -> usize {
        self.alive_count
    }

    /// The triangle in `slot`, if alive.
    pub fn triangle(&self, slot: u32) -> Option<[u32; 3]> {
        let s = slot as usize;
        (s < self.tri.len() && self.alive[s]).then(|| self.tri[s])
    }

    fn degree(&self, x: u32) -> u32 {
        self.strip[x as usize].count_ones()
    }

    fn side_to(&self, x: u32, y: u32) -> Option<usize> {
        self.nb[x as usize].iter().position(|&n| n == y)
    }

    fn add_one(&mut self, t: [u32; 3]) -> u32 {
        let slot = match self.free.pop() {
            Some(s) => s,
            None => {
                self.tri.push(t);
                self.alive.push(false);
                self.nb.push([NONE; 3]);
                self.strip.push(0);
                self.sid.push(0);
                self.pos.push(0);
                self.mark.push(0);
                self.parent.push(NONE);
                self.depth.push(0);
                self.seen.push(0);
                (self.tri.len() - 1) as u32
            }
        };
        let s = slot as usize;
        self.tri[s] = t;
        self.alive[s] = true;
        self.nb[s] = [NONE; 3];
        self.strip[s] = 0;
        self.sid[s] = self.next_sid;
        self.next_sid = self.next_sid.wrapping_add(1);
        self.pos[s] = 0;
        self.alive_count += 1;
        self.ends.push(slot);
        if super::degenerate(t) {
            return slot;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if self.edges.contains_key(&(a, b)) {
                continue; // non-manifold or inconsistently oriented: not linked
            }
            self.edges.insert((a, b), slot);
            if let Some(&n) = self.edges.get(&(b, a)) {
                let j = (0..3).find(|&j| {
                    let u = self.tri[n as usize];
                    (u[j], u[(j + 1) % 3]) == (b, a)
                });
                if let Some(j) = j
                    && self.nb[n as usize][j] == NONE
                    && !self.nb[s].contains(&n)
                {
                    self.nb[n as usize][j] = slot;
                    self.nb[s][k] = n;
                }
            }
        }
        slot
    }

    /// Removes the triangle in `slot`; its strips break. Returns nothing; neighbours whose
    /// strip changed are pushed to `touched`.
    fn remove_one(&mut self, slot: u32, touched: &mut Vec<u32>) {
        let s = slot as usize;
        if s >= self.tri.len() || !self.alive[s] {
            return;
        }
        for k in 0..3 {
            let n = self.nb[s][k];
            if n == NONE {
                continue;
            }
            if let Some(j) = self.side_to(n, slot) {
                self.nb[n as usize][j] = NONE;
                if self.strip[n as usize] & (1 << j) != 0 {
                    self.strip[n as usize] &= !(1 << j);
                    self.strip_edges -= 1;
                }
            }
            touched.push(n);
        }
        let t = self.tri[s];
        for k in 0..3 {
            let e = (t[k], t[(k + 1) % 3]);
            if self.edges.get(&e) == Some(&slot) {
                self.edges.remove(&e);
            }
        }
        self.nb[s] = [NONE; 3];
        self.strip[s] = 0;
        self.alive[s] = false;
        self.alive_count -= 1;
        self.free.push(slot);
    }

    fn toggle(&mut self, x: u32, y: u32) {
        let (Some(i), Some(j)) = (self.side_to(x, y), self.side_to(y, x)) else {
            return;
        };
        let on = self.strip[x as usize] & (1 << i) == 0;
        self.strip[x as usize] ^= 1 << i;
        self.strip[y as usize] ^= 1 << j;
        if on {
            self.strip_edges += 1;
        } else {
            self.strip_edges -= 1;
        }
    }

    /// The strip neighbours of `x`.
    fn strip_nbs(&self, x: u32) -> impl Iterator<Item = u32> + '_ {
        let s = self.strip[x as usize];
        (0..3)
            .filter(move |k| s & (1 << k) != 0)
            .map(move |k| self.nb[x as usize][k])
    }

    /// The vertex shared by the two strip sides of `y` (its pivot), if it has two.
    fn pivot(&self, y: u32) -> Option<u32> {
        let s = self.strip[y as usize];
        if s.count_ones() != 2 {
            return None;
        }
        // Sides k and k+1 share vertex t[k+1].
        let t = self.tri[y as usize];
        let k = (0..3).find(|&k| s & (1 << k) != 0 && s & (1 << ((k + 1) % 3)) != 0)?;
        Some(t[(k + 1) % 3])
    }

    /// Swaps on the strips around `nodes`: a strip needs a repeated vertex between two
    /// consecutive inner triangles that turn around the same vertex (equal pivots), so a
    /// swap is a property of a strip edge.
    fn swaps_around(&self, nodes: &[u32], pairs: &mut Vec<(u32, u32)>) -> usize {
        pairs.clear();
        for &y in nodes {
            let Some(py) = self.pivot(y) else { continue };
            for z in self.strip_nbs(y) {
                if self.pivot(z) == Some(py) {
                    pairs.push((y.min(z), y.max(z)));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        pairs.len()
    }

    /// Swaps of the whole stripification.
    pub fn swap_count(&self) -> usize {
        let all: Vec<u32> = (0..self.tri.len() as u32)
            .filter(|&x| self.alive[x as usize])
            .collect();
        self.swaps_around(&all, &mut Vec::new())
    }

    /// The strip end reached from `x` walking along strip edges (one way), or `None` when
    /// the walk comes back to `x` (a loop). Marks the nodes walked with `seen_epoch`.
    fn walk_end(&mut self, x: u32) -> Option<u32> {
        let Some(first) = self.strip_nbs(x).next() else {
            self.seen[x as usize] = self.seen_epoch;
            return Some(x);
        };
        let (mut prev, mut cur) = (x, first);
        self.seen[x as usize] = self.seen_epoch;
        for _ in 0..=self.alive_count {
            if cur == x {
                return None;
            }
            self.seen[cur as usize] = self.seen_epoch;
            let next = self.strip_nbs(cur).find(|&n| n != prev);
            match next {
                Some(n) => (prev, cur) = (cur, n),
                None => return Some(cur),
            }
        }
        None
    }

    /// Gives the strip starting at end `e` a new id and positions 0, 1, … along it, marking
    /// its nodes with `done`.
    fn relabel_from(&mut self, e: u32, done: u32) {
        let id = self.next_sid;
        self.next_sid = self.next_sid.wrapping_add(1);
        self.ends.push(e);
        let (mut prev, mut cur, mut k) = (NONE, e, 0u32);
        loop {
            let c = cur as usize;
            self.sid[c] = id;
            self.pos[c] = k;
            self.seen[c] = done;
            k += 1;
            let next = self.strip_nbs(cur).find(|&n| n != prev);
            match next {
                Some(n) if (k as usize) <= self.alive_count => (prev, cur) = (cur, n),
                _ => {
                    self.ends.push(cur);
                    break;
                }
            }
        }
    }

    /// Relabels the strips through `nodes` (each strip once).
    fn relabel(&mut self, nodes: &[u32]) {
        self.seen_epoch = self.seen_epoch.wrapping_add(1);
        let done = self.seen_epoch;
        for &x in nodes {
            if !self.alive[x as usize] || self.seen[x as usize] == done {
                continue;
            }
            if let Some(e) = self.walk_end(x) {
                self.relabel_from(e, done);
            }
        }
    }

    /// One tunnel search from strip end `s`, at most `max_len` dual edges; complements the
    /// first tunnel found that closes no loop. Returns whether strips were joined.
    pub(crate) fn tunnel_from(&mut self, s: u32, max_len: usize) -> bool {
        let su = s as usize;
        if su >= self.tri.len() || !self.alive[su] || self.degree(s) >= 2 {
            return false;
        }
        self.stats.searches += 1;
        self.epoch = self.epoch.wrapping_add(1);
        let epoch = self.epoch;
        self.mark[su] = epoch;
        self.parent[su] = NONE;
        self.depth[su] = 0;
        self.queue.clear();
        self.queue.push_back(s);
        let mut tries = 0;
        while let Some(x) = self.queue.pop_front() {
            let d = self.depth[x as usize] as usize;
            if d + 1 > max_len {
                continue;
            }
            for k in 0..3 {
                let xs = x as usize;
                if self.strip[xs] & (1 << k) != 0 {
                    continue;
                }
                let y = self.nb[xs][k];
                if y == NONE || self.mark[y as usize] == epoch {
                    continue;
                }
                let yu = y as usize;
                self.parent[yu] = x;
                self.depth[yu] = (d + 1) as u32;
                self.mark[yu] = epoch;
                if self.degree(y) < 2 && self.sid[yu] != self.sid[xs] {
                    if self.complement(y) {
                        return true;
                    }
                    tries += 1;
                    if tries >= self.opts.max_tries {
                        return false;
                    }
                }
                if self.degree(y) == 0 || d + 3 > max_len {
                    continue;
                }
                // y is passed: leave it along one of its strip edges.
                let same = self.sid[yu] == self.sid[xs];
                let toward_x = self.pos[xs] < self.pos[yu];
                for j in 0..3 {
                    if self.strip[yu] & (1 << j) == 0 {
                        continue;
                    }
                    let z = self.nb[yu][j];
                    if self.mark[z as usize] == epoch {
                        continue;
                    }
                    if same && ((self.pos[z as usize] < self.pos[yu]) != toward_x) {
                        continue; // Fig. 7: turn toward the tail of the non-strip edge
                    }
                    self.mark[z as usize] = epoch;
                    self.parent[z as usize] = y;
                    self.depth[z as usize] = (d + 2) as u32;
                    self.queue.push_back(z);
                }
            }
        }
        false
    }

    /// Complements the tunnel ending at `t` (followed back by `parent`); undoes it if a loop
    /// formed, else relabels the strips it touched.
    fn complement(&mut self, t: u32) -> bool {
        self.path.clear();
        let mut x = t;
        while x != NONE {
            self.path.push(x);
            x = self.parent[x as usize];
        }
        let path = std::mem::take(&mut self.path);
        let mut pairs = Vec::new();
        let before = if self.opts.swap_aware {
            self.swaps_around(&path, &mut pairs)
        } else {
            0
        };
        for w in path.windows(2) {
            self.toggle(w[0], w[1]);
        }
        if self.opts.swap_aware && self.swaps_around(&path, &mut pairs) > before + 2 {
            for w in path.windows(2) {
                self.toggle(w[0], w[1]);
            }
            self.stats.costly_undone += 1;
            self.path = path;
            return false;
        }
        self.seen_epoch = self.seen_epoch.wrapping_add(1);
        let mut looped = false;
        for &x in &path {
            if self.seen[x as usize] != self.seen_epoch && self.walk_end(x).is_none() {
                looped = true;
                break;
            }
        }
        if looped {
            for w in path.windows(2) {
                self.toggle(w[0], w[1]);
            }
            self.stats.loops_undone += 1;
            self.path = path;
            return false;
        }
        self.relabel(&path);
        self.stats.tunnels += 1;
        self.path = path;
        true
    }

    /// Static stripification: tunnels from every strip end, pass after pass, until a pass
    /// joins nothing (or `passes` ran). Returns the tunnels made.
    pub(crate) fn optimize(&mut self) -> usize {
        let before = self.stats.tunnels;
        if self.opts.greedy_start && self.strip_edges == 0 {
            self.greedy();
        }
        for _ in 0..self.opts.passes.max(1) {
            let pass = self.stats.tunnels;
            for x in 0..self.tri.len() as u32 {
                if self.alive[x as usize] && self.degree(x) < 2 {
                    self.tunnel_from(x, self.opts.max_len);
                }
            }
            if self.stats.tunnels == pass {
                break;
            }
        }
        self.ends.clear();
        for x in 0..self.tri.len() as u32 {
            if self.alive[x as usize] && self.degree(x) < 2 {
                self.ends.push(x);
            }
        }
        self.stats.tunnels - before
    }

    /// Greedy sequential strips (SGI-like): from each unused triangle with the fewest unused
    /// neighbours, extend across the edge that needs no swap when its neighbour is unused,
    /// else across the other one.
    fn greedy(&mut self) {
        let n = self.tri.len();
        let mut used = vec![false; n];
        let free_nbs = |s: &Self, used: &[bool], x: u32| {
            s.nb[x as usize]
                .iter()
                .filter(|&&y| y != NONE && !used[y as usize])
                .count()
        };
        let mut starts: Vec<u32> = (0..n as u32).filter(|&x| self.alive[x as usize]).collect();
        starts.sort_by_key(|&x| free_nbs(self, &used, x));
        for &x0 in &starts {
            if used[x0 as usize] {
                continue;
            }
            used[x0 as usize] = true;
            // First exit: the unused neighbour with the fewest unused neighbours.
            let t = self.tri[x0 as usize];
            let exit = (0..3)
                .filter(|&k| {
                    let y = self.nb[x0 as usize][k];
                    y != NONE && !used[y as usize]
                })
                .min_by_key(|&k| free_nbs(self, &used, self.nb[x0 as usize][k]));
            let Some(k) = exit else { continue };
            // Strip so far ends with the exit edge (t[k], t[k+1]) as (p, q).
            let (mut p, mut q) = (t[k], t[(k + 1) % 3]);
            let mut cur = x0;
            let mut next = self.nb[x0 as usize][k];
            loop {
                used[next as usize] = true;
                self.toggle(cur, next);
                let u = self.tri[next as usize];
                let Some(nv) = u.into_iter().find(|&v| v != p && v != q) else {
                    break;
                };
                // Sides of `next` across {q, nv} (no swap) and {p, nv} (swap).
                let side = |a: u32, b: u32| {
                    (0..3).find(|&j| {
                        let e = (u[j], u[(j + 1) % 3]);
                        e == (a, b) || e == (b, a)
                    })
                };
                let avail = |j: Option<usize>, used: &[bool]| {
                    j.map(|j| self.nb[next as usize][j])
                        .filter(|&y| y != NONE && !used[y as usize])
                };
                if let Some(y) = avail(side(q, nv), &used) {
                    (p, q) = (q, nv);
                    cur = next;
                    next = y;
                } else if let Some(y) = avail(side(p, nv), &used) {
                    q = nv;
                    cur = next;
                    next = y;
                } else {
                    break;
                }
            }
        }
        let all: Vec<u32> = (0..n as u32).filter(|&x| self.alive[x as usize]).collect();
        self.relabel(&all);
    }

    /// Removes the triangles in `removed` (slots) and adds `added` (their slots pushed to
    /// `slots`), then repairs: a tunnel search of `repair_len` from every strip end among the
    /// triangles around the change, and from `extra` strip ends elsewhere. Returns the tunnels
    /// made.
    pub fn replace(&mut self, removed: &[u32], added: &[[u32; 3]], slots: &mut Vec<u32>) -> usize {
        let before = self.stats.tunnels;
        let mut touched = Vec::new();
        for &r in removed {
            self.remove_one(r, &mut touched);
        }
        touched.retain(|&x| self.alive[x as usize]);
        self.relabel(&touched.clone());
        for &t in added {
            let s = self.add_one(t);
            slots.push(s);
            touched.push(s);
            for n in self.nb[s as usize] {
                if n != NONE {
                    touched.push(n);
                }
            }
        }
        let len = self.opts.repair_len;
        for &x in &touched {
            if self.alive[x as usize] && self.degree(x) < 2 {
                self.tunnel_from(x, len);
            }
        }
        let mut tried = 0;
        let mut guard = 0;
        while tried < self.opts.extra && !self.ends.is_empty() && guard < 4 * self.opts.extra + 8 {
            guard += 1;
            self.end_cursor = (self.end_cursor + 1) % self.ends.len();
            let x = self.ends[self.end_cursor];
            if !self.alive[x as usize] || self.degree(x) >= 2 {
                self.ends.swap_remove(self.end_cursor);
                continue;
            }
            tried += 1;
            self.tunnel_from(x, len);
        }
        if self.ends.len() > 4 * self.alive_count + 64 {
            let ends = std::mem::take(&mut self.ends);
            self.ends = ends
                .into_iter()
                .filter(|&x| self.alive[x as usize] && self.degree(x) < 2)
                .collect();
            self.ends.sort_unstable();
            self.ends.dedup();
        }
        self.stats.tunnels - before
    }

    /// Appends the strips to `out` (joined by [`RESTART`](super::RESTART)); returns how many were written.
    pub(crate) fn write_indices(&mut self, out: &mut Vec<u32>) -> usize {
        self.seen_epoch = self.seen_epoch.wrapping_add(1);
        let done = self.seen_epoch;
        let mut strips = 0;
        let mut path = Vec::new();
        for x in 0..self.tri.len() as u32 {
            if !self.alive[x as usize] || self.seen[x as usize] == done || self.degree(x) >= 2 {
                continue;
            }
            path.clear();
            let (mut prev, mut cur) = (NONE, x);
            loop {
                self.seen[cur as usize] = done;
                path.push(self.tri[cur as usize]);
                match self.strip_nbs(cur).find(|&n| n != prev) {
                    Some(n) if self.seen[n as usize] != done => (prev, cur) = (cur, n),
                    _ => break,
                }
            }
            strips += encode_path(&path, out);
        }
        strips
    }

    /// The strips as one index buffer.
    pub fn to_indices(&mut self) -> StripIndices {
        let mut indices = Vec::new();
        let strips = self.write_indices(&mut indices);
        StripIndices {
            indices,
            strips,
            triangles: self.alive_count,
        }
    }

    /// Checks the labelling: symmetric adjacency and strip bits, at most two strip edges per
    /// node, no loop, and the strip count. For tests.
    pub fn check(&mut self) -> Result<(), String> {
        let mut edges = 0;
        for x in 0..self.tri.len() as u32 {
            if !self.alive[x as usize] {
                continue;
            }
            for k in 0..3 {
                let y = self.nb[x as usize][k];
                if y == NONE {
                    if self.strip[x as usize] & (1 << k) != 0 {
                        return Err(format!("strip bit without neighbour at {x}"));
                    }
                    continue;
                }
                if !self.alive[y as usize] {
                    return Err(format!("{x} linked to dead {y}"));
                }
                let Some(j) = self.side_to(y, x) else {
                    return Err(format!("asymmetric adjacency {x}-{y}"));
                };
                let a = self.strip[x as usize] & (1 << k) != 0;
                let b = self.strip[y as usize] & (1 << j) != 0;
                if a != b {
                    return Err(format!("asymmetric strip edge {x}-{y}"));
                }
                edges += usize::from(a);
            }
            if self.degree(x) > 2 {
                return Err(format!("{x} has {} strip edges", self.degree(x)));
            }
        }
        if edges / 2 != self.strip_edges {
            return Err(format!(
                "{} strip edges counted as {}",
                edges / 2,
                self.strip_edges
            ));
        }
        self.seen_epoch = self.seen_epoch.wrapping_add(1);
        for x in 0..self.tri.len() as u32 {
            if self.alive[x as usize] && self.walk_end(x).is_none() {
                return Err(format!("strip loop through {x}"));
            }
        }
        Ok(())
    }
}

/// Stripifies a static triangle set by tunneling.
pub fn stripify(triangles: &[[u32; 3]], opts: &TunnelOptions) -> StripIndices {
    TunnelStrips::build(triangles, opts.clone()).to_indices()
}
