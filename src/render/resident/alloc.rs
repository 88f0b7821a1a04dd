//! A range suballocator: first fit over a free list of `[start, start + len)` ranges in some
//! unit (vertices, indices), with growth and compaction. CPU bookkeeping only: the GPU
//! buffers it describes live in [`super::pool`].
//!
//! Guarantees: live ranges never overlap and stay where they are, except through
//! [`Allocator::compact`], which returns every move so the caller can copy the data and fix
//! whatever refers to it. Free ranges are kept sorted and coalesced, so a freed range merges
//! with its free neighbours at once. First fit takes the lowest free range long enough: new
//! ranges land low, and consecutive allocations into a fresh allocator are adjacent (the
//! resident geometry relies on that to merge the draws of neighbouring patches).

use std::collections::BTreeMap;

/// One live range moved by [`Allocator::compact`]: `len` units from `from` to `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Move {
    pub from: u64,
    pub to: u64,
    pub len: u64,
}

/// First-fit range allocator over `[0, capacity)`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Allocator {
    capacity: u64,
    /// Free ranges, start → length; sorted, coalesced (no two touch).
    free: BTreeMap<u64, u64>,
    /// Live ranges, start → length.
    live: BTreeMap<u64, u64>,
    used: u64,
}

impl Allocator {
    pub fn new(capacity: u64) -> Allocator {
        let mut a = Allocator {
            capacity,
            ..Allocator::default()
        };
        if capacity > 0 {
            a.free.insert(0, capacity);
        }
        a
    }

    pub(crate) fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Units in live ranges.
    pub fn used(&self) -> u64 {
        self.used
    }

    /// Units in free ranges.
    pub fn free(&self) -> u64 {
        self.capacity - self.used
    }

    /// Free ranges (1 when packed).
    pub(crate) fn free_ranges(&self) -> usize {
        self.free.len()
    }

    /// The longest free range.
    pub(crate) fn largest_free(&self) -> u64 {
        self.free.values().copied().max().unwrap_or(0)
    }

    /// Live ranges, by start.
    pub fn live(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        self.live.iter().map(|(&s, &l)| (s, l))
    }

    /// The start of `len` (> 0) free units, the lowest free range long enough; `None` when no
    /// free range is (grow or compact, then ask again).
    pub fn alloc(&mut self, len: u64) -> Option<u64> {
        assert!(len > 0, "zero-length allocation");
        let (&start, &free_len) = self.free.iter().find(|&(_, &l)| l >= len)?;
        self.free.remove(&start);
        if free_len > len {
            self.free.insert(start + len, free_len - len);
        }
        self.live.insert(start, len);
        self.used += len;
        Some(start)
    }

    /// Frees the live range starting at `start`; panics when there is none (a caller bug
    /// that would otherwise corrupt other ranges).
    pub(crate) fn free_range(&mut self, start: u64) {
        let len = self
            .live
            .remove(&start)
            .unwrap_or_else(|| panic!("no live range at {start}"));
        self.used -= len;
        self.insert_free(start, len);
    }

    fn insert_free(&mut self, mut start: u64, mut len: u64) {
        if let Some((&s, &l)) = self.free.range(..start).next_back()
            && s + l == start
        {
            self.free.remove(&s);
            start = s;
            len += l;
        }
        if let Some(&l) = self.free.get(&(start + len)) {
            self.free.remove(&(start + len));
            len += l;
        }
        self.free.insert(start, len);
    }

    /// Grows the range to `capacity` units (never shrinks); live ranges stay where they are.
    pub(crate) fn grow(&mut self, capacity: u64) {
        if capacity > self.capacity {
            let old = self.capacity;
            self.capacity = capacity;
            self.insert_free(old, capacity - old);
        }
    }

    /// Moves every live range down, packed from 0 in the order `order` gives (starts of
    /// live ranges; ranges it leaves out follow in address order), leaving one free range at
    /// the end. Returns the moved ranges (`from != to`).
    ///
    /// The moves may overlap their sources (a range slides onto where another was): copy
    /// from a snapshot of the old contents, as the GPU pool does (old buffer → new buffer).
    pub(crate) fn compact(&mut self, order: impl IntoIterator<Item = u64>) -> Vec<Move> {
        let mut old = std::mem::take(&mut self.live);
        let mut sequence: Vec<(u64, u64)> = Vec::with_capacity(old.len());
        for start in order {
            if let Some(len) = old.remove(&start) {
                sequence.push((start, len));
            }
        }
        sequence.extend(old);
        let mut moves = Vec::new();
        let mut at = 0;
        for (from, len) in sequence {
            if from != at {
                moves.push(Move { from, to: at, len });
            }
            self.live.insert(at, len);
            at += len;
        }
        self.free.clear();
        if at < self.capacity {
            self.free.insert(at, self.capacity - at);
        }
        moves
    }

    /// Checks the invariants (tests): ranges inside the capacity, free and live disjoint and
    /// covering everything, free ranges coalesced.
    #[cfg(test)]
    pub fn check(&self) -> Result<(), String> {
        let mut all: Vec<(u64, u64, bool)> = self
            .free
            .iter()
            .map(|(&s, &l)| (s, l, true))
            .chain(self.live.iter().map(|(&s, &l)| (s, l, false)))
            .collect();
        all.sort();
        let mut at = 0;
        let mut prev_free = false;
        for (s, l, is_free) in all {
            if s != at {
                return Err(format!("range at {s}, expected {at}"));
            }
            if l == 0 {
                return Err(format!("empty range at {s}"));
            }
            if is_free && prev_free {
                return Err(format!("free ranges not coalesced at {s}"));
            }
            prev_free = is_free;
            at = s + l;
        }
        if at != self.capacity {
            return Err(format!("ranges end at {at}, capacity {}", self.capacity));
        }
        let used: u64 = self.live.values().sum();
        if used != self.used {
            return Err(format!("used {} but live ranges hold {used}", self.used));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CPU "buffer" driven by an allocator: every live range filled with its own tag, so a
    /// range that moves or is overwritten shows.
    struct Model {
        alloc: Allocator,
        memory: Vec<u32>,
        /// tag → (start, len)
        ranges: BTreeMap<u32, (u64, u64)>,
        next_tag: u32,
    }

    impl Model {
        fn new(capacity: u64) -> Model {
            Model {
                alloc: Allocator::new(capacity),
                memory: vec![0; capacity as usize],
                ranges: BTreeMap::new(),
                next_tag: 1,
            }
        }

        /// Allocates, growing ×2 (copying the memory) or compacting when it does not fit.
        fn add(&mut self, len: u64) -> u32 {
            let start = match self.alloc.alloc(len) {
                Some(s) => s,
                None if self.alloc.free() >= len => {
                    self.compact(Vec::new());
                    self.alloc.alloc(len).expect("fits after compaction")
                }
                None => {
                    let cap = (self.alloc.capacity() * 2).max(self.alloc.used() + len);
                    self.alloc.grow(cap);
                    self.memory.resize(cap as usize, 0);
                    self.alloc.alloc(len).expect("fits after growth")
                }
            };
            let tag = self.next_tag;
            self.next_tag += 1;
            self.memory[start as usize..(start + len) as usize].fill(tag);
            self.ranges.insert(tag, (start, len));
            tag
        }

        fn remove(&mut self, tag: u32) {
            let (start, len) = self.ranges.remove(&tag).expect("live tag");
            self.alloc.free_range(start);
            self.memory[start as usize..(start + len) as usize].fill(0);
        }

        fn compact(&mut self, order_tags: Vec<u32>) {
            let order: Vec<u64> = order_tags.iter().map(|t| self.ranges[t].0).collect();
            let moves = self.alloc.compact(order);
            let old = self.memory.clone();
            let mut moved_to: BTreeMap<u64, u64> = BTreeMap::new();
            for m in &moves {
                self.memory[m.to as usize..(m.to + m.len) as usize]
                    .copy_from_slice(&old[m.from as usize..(m.from + m.len) as usize]);
                moved_to.insert(m.from, m.to);
            }
            for r in self.ranges.values_mut() {
                if let Some(&to) = moved_to.get(&r.0) {
                    r.0 = to;
                }
            }
        }

        fn intact(&self) {
            self.alloc.check().expect("allocator invariants");
            let live: BTreeMap<u64, u64> = self.alloc.live().collect();
            assert_eq!(live.len(), self.ranges.len());
            for (&tag, &(start, len)) in &self.ranges {
                assert_eq!(live.get(&start), Some(&len), "tag {tag}");
                let data = &self.memory[start as usize..(start + len) as usize];
                assert!(data.iter().all(|&t| t == tag), "tag {tag} overwritten");
            }
        }
    }

    #[test]
    fn allocations_are_adjacent_and_first_fit() {
        let mut a = Allocator::new(100);
        assert_eq!(a.alloc(10), Some(0));
        assert_eq!(a.alloc(20), Some(10));
        assert_eq!(a.alloc(5), Some(30));
        a.free_range(10);
        // The hole is reused by the first allocation that fits it.
        assert_eq!(a.alloc(30), Some(35));
        assert_eq!(a.alloc(15), Some(10));
        assert_eq!(a.alloc(6), Some(65));
        assert_eq!(a.alloc(5), Some(25));
        assert_eq!(a.alloc(30), None);
        a.check().expect("invariants");
        assert_eq!(a.used(), 10 + 15 + 5 + 5 + 30 + 6);
    }

    #[test]
    fn freed_neighbours_coalesce() {
        let mut a = Allocator::new(30);
        let (x, y, z) = (a.alloc(10), a.alloc(10), a.alloc(10));
        assert_eq!(a.alloc(1), None);
        a.free_range(x.expect("fits"));
        a.free_range(z.expect("fits"));
        assert_eq!(a.largest_free(), 10);
        a.free_range(y.expect("fits"));
        assert_eq!(a.largest_free(), 30);
        assert_eq!(a.alloc(30), Some(0));
        a.check().expect("invariants");
    }

    #[test]
    #[should_panic(expected = "no live range")]
    fn freeing_twice_is_caught() {
        let mut a = Allocator::new(10);
        let s = a.alloc(4).expect("fits");
        a.free_range(s);
        a.free_range(s);
    }

    #[test]
    fn growth_keeps_live_ranges_and_joins_the_free_tail() {
        let mut a = Allocator::new(10);
        let s = a.alloc(8).expect("fits");
        assert_eq!(a.alloc(5), None);
        a.grow(20);
        // The 2 free units at the old end and the new 10 are one range.
        assert_eq!(a.alloc(12), Some(8));
        assert_eq!(a.live().next(), Some((s, 8)));
        a.check().expect("invariants");
    }

    #[test]
    fn compaction_packs_in_the_given_order_and_reports_moves() {
        let mut a = Allocator::new(100);
        let r: Vec<u64> = (0..5).map(|_| a.alloc(10).expect("fits")).collect();
        a.free_range(r[1]);
        a.free_range(r[3]);
        // Order: the last first, then the rest by address.
        let moves = a.compact([r[4]]);
        let mv = |from, to| Move { from, to, len: 10 };
        // 20 stays where it is: not a move.
        assert_eq!(moves, vec![mv(40, 0), mv(0, 10)]);
        assert_eq!(a.largest_free(), 70);
        a.check().expect("invariants");
    }

    #[test]
    fn random_churn_keeps_every_live_range_intact() {
        // A deterministic pseudo-random mix of allocations, frees, growth and compactions.
        let mut m = Model::new(64);
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rand = |n: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % n
        };
        for step in 0..4000 {
            match rand(10) {
                0..=5 => {
                    m.add(1 + rand(40));
                }
                6..=8 if !m.ranges.is_empty() => {
                    let k = rand(m.ranges.len() as u64) as usize;
                    let tag = *m.ranges.keys().nth(k).expect("k < len");
                    m.remove(tag);
                }
                _ => {
                    // Compact in tag order (the resident geometry's patch order).
                    let tags: Vec<u32> = m.ranges.keys().copied().collect();
                    m.compact(tags);
                    let mut at = 0;
                    for &(s, l) in m.ranges.values() {
                        assert_eq!(s, at, "step {step}: not packed in order");
                        at += l;
                    }
                }
            }
            m.intact();
        }
        assert!(m.alloc.capacity() > 64, "never grew");
    }
}
