//! Strips kept between frames by whoever draws them (the renderer), never by the scene.
//!
//! A patch's strips are static while its tessellation lives (Holst §5.2 and Stewart's static
//! case): tunneling strips of a tessellation are built once and kept while the same triangles
//! are drawn again. A mesh patch drawn as a cut of its hierarchy keeps Belmonte et al.'s
//! multiresolution strips ([`super::mts`]) or Stewart's strips repaired by tunneling
//! ([`super::tunnel::CutStrips`]), both built on first use and moved with the cut.
//!
//! This is per-view state: each [`crate::render::Renderer`] owns one store, so two frame loops
//! with their own renderers never share it, and the scene stays immutable.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use super::mts::MultiresStrips;
use super::tunnel::{self, CutStrips, TunnelOptions};
use crate::model::mesh::MeshPatch;

/// Uploads a tessellation's strips survive unused before they are dropped.
const KEEP_UPLOADS: u64 = 8;

/// Strips per patch, kept between uploads (see the module doc).
#[derive(Debug, Default)]
pub struct StripStore {
    /// Tunneling strips per (patch id, fingerprint of its triangles), with the upload that
    /// last used them.
    tessellated: Mutex<HashMap<(u32, u64), Kept>>,
    /// Strips that follow a mesh patch's cut, by the patch's address (the entry keeps the
    /// patch alive, so the address is not reused while the entry lives).
    cuts: Mutex<HashMap<usize, Arc<Mutex<CutStripsEntry>>>>,
    /// Uploads begun.
    epoch: AtomicU64,
}

/// Strips and the upload that last used them.
type Kept = (Arc<Vec<u32>>, u64);

#[derive(Debug)]
struct CutStripsEntry {
    patch: Arc<MeshPatch>,
    mts: Option<MultiresStrips>,
    repaired: Option<CutStrips>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// A fingerprint of a triangle list (FNV-1a over the indices). Strips depend on the indices
/// only, so two lists with one fingerprint have the same strips (up to hash collisions).
fn fingerprint(tris: &[[u32; 3]]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64 ^ tris.len() as u64;
    for &i in tris.iter().flatten() {
        h = (h ^ i as u64).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

impl StripStore {
    pub fn new() -> Self {
        Self::default()
    }

    /// Marks the start of an upload: drops tessellation strips unused for
    /// `KEEP_UPLOADS` uploads and cut strips of patches nobody else holds any more.
    pub(crate) fn begin_upload(&self) {
        let now = self.epoch.fetch_add(1, Ordering::Relaxed) + 1;
        lock(&self.tessellated).retain(|_, (_, used)| now - *used <= KEEP_UPLOADS);
        lock(&self.cuts).retain(|_, e| Arc::strong_count(&lock(e).patch) > 1);
    }

    /// The tunneling strips (default options, joined by [`super::RESTART`]) of patch
    /// `patch_id`'s triangles `tris`, from the store when it holds them.
    pub fn tessellation(&self, patch_id: u32, tris: &[[u32; 3]]) -> Arc<Vec<u32>> {
        let key = (patch_id, fingerprint(tris));
        let now = self.epoch.load(Ordering::Relaxed);
        if let Some((s, used)) = lock(&self.tessellated).get_mut(&key) {
            *used = now;
            return s.clone();
        }
        // Built outside the lock: uploads stripify patches in parallel.
        let s = Arc::new(tunnel::stripify(tris, &TunnelOptions::default()).indices);
        lock(&self.tessellated).insert(key, (s.clone(), now));
        s
    }

    /// The strips (joined by [`super::RESTART`]) of the cut of `patch`'s hierarchy after
    /// `applied` nodes of its order, into `out`: extracted from its multiresolution strips
    /// (`mts`, coherent with the last extraction) or repaired from the last cut by tunneling.
    pub fn cut(&self, patch: &Arc<MeshPatch>, applied: usize, mts: bool, out: &mut Vec<u32>) {
        let entry = lock(&self.cuts)
            .entry(Arc::as_ptr(patch) as usize)
            .or_insert_with(|| {
                Arc::new(Mutex::new(CutStripsEntry {
                    patch: patch.clone(),
                    mts: None,
                    repaired: None,
                }))
            })
            .clone();
        let mut e = lock(&entry);
        let h = &patch.hierarchy;
        let opts = TunnelOptions::default();
        out.clear();
        if mts {
            let s = e.mts.get_or_insert_with(|| MultiresStrips::build(h, &opts));
            s.extract(applied, true, out);
        } else {
            let s = e.repaired.get_or_insert_with(|| CutStrips::new(h, opts));
            s.move_to(h, applied);
            s.strips.write_indices(out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: u32) -> Vec<[u32; 3]> {
        let mut t = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let v = y * (n + 1) + x;
                t.push([v, v + 1, v + n + 2]);
                t.push([v, v + n + 2, v + n + 1]);
            }
        }
        t
    }

    #[test]
    fn tessellation_strips_are_kept_while_used_and_rebuilt_when_the_triangles_change() {
        let store = StripStore::new();
        store.begin_upload();
        let a = store.tessellation(3, &grid(4));
        assert!(Arc::ptr_eq(&a, &store.tessellation(3, &grid(4))));
        let b = store.tessellation(3, &grid(5));
        assert!(!Arc::ptr_eq(&a, &b));
        assert!(b.len() > a.len());
        // Unused for longer than KEEP_UPLOADS uploads: dropped.
        for _ in 0..=KEEP_UPLOADS {
            store.begin_upload();
        }
        assert!(!Arc::ptr_eq(&a, &store.tessellation(3, &grid(4))));
    }
}
