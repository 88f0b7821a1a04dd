//! Spatial indices over the fidelity measure's boundary segments, so that a sample's boundary
//! queries (nearest segment in 3D, nearest segment in parameter space, even-odd crossings)
//! look at the segments near it instead of scanning every segment of the face.
//!
//! Uniform grids with ring search (Cleary & Wyvill, "Analysis of an algorithm for fast ray
//! tracing using uniform space subdivision", The Visual Computer 4(2), 1988, for the cell
//! walk; the expanding-ring nearest-neighbour search as in `fidelity::TriangleGrid`), and for
//! even-odd a 1D bucketing of the segments along the crossing axis (each bucket lists the
//! segments whose extent along that axis overlaps it).
//!
//! **Guarantee: the answers are the exhaustive scan's, bit for bit.** The index only chooses
//! which segments are tested; every test is the exhaustive one, ties between equally near
//! segments go to the first in loop order as the scan's strict `<` does, a ring search stops
//! only when every untested segment is provably farther (with a relative slack of 1e-9 for
//! rounding), buckets get one bucket of margin each side, and a query at a non-finite point
//! scans. `tests` in `boundary.rs` compare both on every query of a few faces.
//!
//! What it does not do: it is rebuilt per measured face (per ε); it does not speed a face
//! with a handful of segments (the scan is as fast there).

/// A uniform grid of cubic cells in `D` dimensions over items' bounding boxes, each item in
/// every cell its box overlaps.
#[derive(Debug)]
pub(super) struct BoxGrid<const D: usize> {
    lo: [f64; D],
    hi: [f64; D],
    cell: f64,
    dims: [usize; D],
    /// Per cell, the range of `items` holding its items.
    start: Vec<u32>,
    items: Vec<u32>,
    count: usize,
    /// Rounding slack on distance bounds (1e-9 of the grid's coordinates' magnitude).
    slack: f64,
}

impl<const D: usize> BoxGrid<D> {
    /// Most cells per axis.
    const MAX_DIM: usize = 32;

    /// A grid over `boxes` (lower, upper corner); non-finite boxes are put in every cell.
    pub(super) fn new(boxes: &[([f64; D], [f64; D])]) -> BoxGrid<D> {
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        for (a, b) in boxes {
            for i in 0..D {
                if a[i].is_finite() && b[i].is_finite() {
                    lo[i] = lo[i].min(a[i]);
                    hi[i] = hi[i].max(b[i]);
                }
            }
        }
        if lo.iter().chain(&hi).any(|x| !x.is_finite()) {
            lo = [0.0; D];
            hi = [0.0; D];
        }
        let extent = (0..D).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
        // About one to two segments of a curve per occupied cell.
        let per_axis = (boxes.len() as f64 / 4.0)
            .ceil()
            .clamp(1.0, Self::MAX_DIM as f64);
        let cell = if extent > 0.0 { extent / per_axis } else { 1.0 };
        let mut dims = [1usize; D];
        for i in 0..D {
            dims[i] = (((hi[i] - lo[i]) / cell).floor() as usize + 1).clamp(1, Self::MAX_DIM);
        }
        let magnitude = (0..D)
            .map(|i| lo[i].abs().max(hi[i].abs()))
            .fold(extent, f64::max);
        let mut grid = BoxGrid {
            lo,
            hi,
            cell,
            dims,
            start: Vec::new(),
            items: Vec::new(),
            count: boxes.len(),
            slack: 1e-9 * magnitude,
        };
        let n: usize = dims.iter().product();
        let range = |g: &BoxGrid<D>, (a, b): &([f64; D], [f64; D])| {
            let finite = a.iter().chain(b).all(|x| x.is_finite());
            let mut r = [(0usize, 0usize); D];
            for i in 0..D {
                r[i] = match finite {
                    true => (g.axis_cell(a[i], i), g.axis_cell(b[i], i)),
                    false => (0, g.dims[i] - 1),
                };
            }
            r
        };
        let mut count = vec![0u32; n + 1];
        for bx in boxes {
            grid.each_cell(range(&grid, bx), |c, _| count[c + 1] += 1);
        }
        for k in 1..=n {
            count[k] += count[k - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[n] as usize];
        for (k, bx) in boxes.iter().enumerate() {
            grid.each_cell(range(&grid, bx), |c, _| {
                items[fill[c] as usize] = k as u32;
                fill[c] += 1;
            });
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    fn axis_cell(&self, x: f64, i: usize) -> usize {
        let c = (x - self.lo[i]) / self.cell;
        if c.is_nan() {
            0
        } else {
            (c.floor().max(0.0) as usize).min(self.dims[i] - 1)
        }
    }

    fn index(&self, c: [usize; D]) -> usize {
        let mut k = 0;
        for (i, ci) in c.into_iter().enumerate() {
            k = k * self.dims[i] + ci;
        }
        k
    }

    /// Calls `f` with every cell index in the box of cell ranges `r` (inclusive).
    fn each_cell(&self, r: [(usize, usize); D], mut f: impl FnMut(usize, [usize; D])) {
        let mut c = [0usize; D];
        for i in 0..D {
            c[i] = r[i].0;
        }
        loop {
            f(self.index(c), c);
            let mut i = D;
            loop {
                if i == 0 {
                    return;
                }
                i -= 1;
                if c[i] < r[i].1 {
                    c[i] += 1;
                    break;
                }
                c[i] = r[i].0;
            }
        }
    }

    /// The grid's box (lower, upper corner).
    pub(super) fn bounds(&self) -> ([f64; D], [f64; D]) {
        (self.lo, self.hi)
    }

    /// The rounding slack the distance bounds allow.
    pub(super) fn slack(&self) -> f64 {
        self.slack
    }

    /// Distance from `q` to the grid's box (0 inside).
    pub(super) fn box_distance(&self, q: [f64; D]) -> f64 {
        let mut s = 0.0;
        for (i, qi) in q.into_iter().enumerate() {
            let d = (self.lo[i] - qi).max(qi - self.hi[i]).max(0.0);
            s += d * d;
        }
        s.sqrt()
    }

    /// The item with the smallest `key` (ties: the smallest item index) among those that can
    /// be nearer `q` than `best`, merged into `best`. `key(item)` must be an increasing
    /// function `to_key` of a value never below the item's box's distance from `q`
    /// (squared distance: `to_key = x²`). `best` starts as `None` or a previous answer.
    pub(super) fn nearest(
        &self,
        q: [f64; D],
        key: &mut impl FnMut(u32) -> f64,
        to_key: impl Fn(f64) -> f64,
        best: &mut Option<(f64, u32)>,
    ) {
        let mut consider = |best: &mut Option<(f64, u32)>, t: u32| {
            let k = key(t);
            let better = match *best {
                None => true,
                Some((bk, bt)) => k < bk || (k == bk && t < bt),
            };
            if better {
                *best = Some((k, t));
            }
        };
        if q.iter().any(|x| !x.is_finite()) {
            (0..self.count as u32).for_each(|t| consider(best, t));
            return;
        }
        let mut c = [0usize; D];
        for i in 0..D {
            c[i] = self.axis_cell(q[i], i);
        }
        let max_k = self.dims.iter().copied().max().unwrap_or(1);
        for k in 0..=max_k {
            // A ring as large as the grid's contents: every item instead.
            if (2 * k + 1).pow(D as u32) > self.count {
                (0..self.count as u32).for_each(|t| consider(best, t));
                return;
            }
            let mut r = [(0usize, 0usize); D];
            for i in 0..D {
                r[i] = (c[i].saturating_sub(k), (c[i] + k).min(self.dims[i] - 1));
            }
            // Only the cells on ring k (the inner ones were tested before).
            self.each_cell(r, |cell, at| {
                let ring = (0..D).map(|i| at[i].abs_diff(c[i])).max().unwrap_or(0);
                if ring == k {
                    let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
                    for &t in &self.items[s..e] {
                        consider(best, t);
                    }
                }
            });
            // Untested items lie outside the rings' box: at least this far, across its faces
            // inside the grid (no item reaches beyond the grid's own faces).
            let mut bound = f64::INFINITY;
            for (i, (a, b)) in r.into_iter().enumerate() {
                if a > 0 {
                    bound = bound.min(q[i] - (self.lo[i] + a as f64 * self.cell));
                }
                if b + 1 < self.dims[i] {
                    bound = bound.min(self.lo[i] + (b + 1) as f64 * self.cell - q[i]);
                }
            }
            if bound == f64::INFINITY {
                return;
            }
            let bound = bound - self.slack;
            if best.is_some_and(|(bk, _)| bound > 0.0 && bk < to_key(bound)) {
                return;
            }
        }
    }
}

/// Segments bucketed by their extent along one axis (periodic or not), for even-odd: the
/// segments a ray at coordinate `x` can cross are in `x`'s bucket.
#[derive(Debug, Default)]
pub(super) struct Buckets {
    lo: f64,
    width: f64,
    /// Number of buckets.
    n: usize,
    period: Option<f64>,
    /// Per bucket, the range of `items`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Segments in every bucket (longer than half a period, or not finite).
    everywhere: Vec<u32>,
    count: usize,
}

impl Buckets {
    /// Buckets over segments' extents `(a, b)` along the axis, of period `period` if any.
    pub(super) fn new(extents: &[(f64, f64)], period: Option<f64>) -> Buckets {
        let period = period.filter(|p| *p > 0.0 && p.is_finite());
        let n = (extents.len() / 2).clamp(1, 4096);
        let (lo, hi) = match period {
            Some(p) => (0.0, p),
            None => extents
                .iter()
                .flat_map(|&(a, b)| [a, b])
                .filter(|x| x.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                    (l.min(x), h.max(x))
                }),
        };
        let width = if lo.is_finite() && hi > lo {
            (hi - lo) / n as f64
        } else {
            0.0
        };
        let mut out = Buckets {
            lo: if lo.is_finite() { lo } else { 0.0 },
            width,
            n,
            period,
            start: Vec::new(),
            items: Vec::new(),
            everywhere: Vec::new(),
            count: extents.len(),
        };
        // Per segment: first bucket and how many (one bucket of margin each side).
        let span = |o: &Buckets, &(a, b): &(f64, f64)| -> Option<(usize, usize)> {
            let (a, b) = (a.min(b), a.max(b));
            if !(a.is_finite() && b.is_finite()) || o.width <= 0.0 {
                return None;
            }
            match o.period {
                Some(p) => {
                    if b - a >= 0.5 * p {
                        return None;
                    }
                    let first = o.bucket(a) + n - 1;
                    let len = ((b - a) / o.width).ceil() as usize + 3;
                    (len < n).then_some((first % n, len))
                }
                None => {
                    let first = o.bucket(a).saturating_sub(1);
                    let last = (o.bucket(b) + 1).min(n - 1);
                    Some((first, last - first + 1))
                }
            }
        };
        let mut count = vec![0u32; n + 1];
        for (k, e) in extents.iter().enumerate() {
            match span(&out, e) {
                Some((first, len)) => (0..len).for_each(|j| count[(first + j) % n + 1] += 1),
                None => out.everywhere.push(k as u32),
            }
        }
        for k in 1..=n {
            count[k] += count[k - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[n] as usize];
        for (k, e) in extents.iter().enumerate() {
            if let Some((first, len)) = span(&out, e) {
                for j in 0..len {
                    let b = (first + j) % n;
                    items[fill[b] as usize] = k as u32;
                    fill[b] += 1;
                }
            }
        }
        out.start = count;
        out.items = items;
        out
    }

    fn bucket(&self, x: f64) -> usize {
        let n = self.n;
        let x = match self.period {
            Some(p) => (x - self.lo).rem_euclid(p),
            None => x - self.lo,
        };
        let b = (x / self.width).floor();
        if b.is_nan() {
            0
        } else {
            (b.max(0.0) as usize).min(n - 1)
        }
    }

    /// Calls `f` with every segment whose extent can contain `x` (every segment when `x` is
    /// not finite), each once.
    pub(super) fn each(&self, x: f64, mut f: impl FnMut(u32)) {
        if !x.is_finite() || self.width <= 0.0 {
            (0..self.count as u32).for_each(f);
            return;
        }
        if self.period.is_none() {
            let hi = self.lo + self.width * self.n as f64;
            // Outside every extent (with a bucket of margin): nothing to cross.
            if x < self.lo - self.width || x > hi + self.width {
                self.everywhere.iter().copied().for_each(&mut f);
                return;
            }
        }
        let b = self.bucket(x);
        let (s, e) = (self.start[b] as usize, self.start[b + 1] as usize);
        self.items[s..e].iter().copied().for_each(&mut f);
        self.everywhere.iter().copied().for_each(f);
    }
}
