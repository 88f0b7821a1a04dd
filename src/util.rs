//! Small helpers shared by several stages: integer-keyed hash maps, a 128-bit content
//! hash (cache keys and checksums), progress of long load steps ([`Progress`], re-exported by
//! `prep`), and the process's resident memory (Linux `/proc/self/status`).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

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

/// Progress of long load steps (reading, probing and preparing), for whoever loads; called
/// from worker threads. The binary draws a bar; the library itself prints nothing.
pub trait Progress: Sync {
    /// A step named `what` of `total` units begins.
    fn begin(&self, what: &str, total: usize);
    /// One more unit is done.
    fn advance(&self);
    /// The step is over.
    fn end(&self);
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn begin(&self, _: &str, _: usize) {}
    fn advance(&self) {}
    fn end(&self) {}
}

/// A step reported only when it has at least `min` units (short steps stay quiet); ends when
/// dropped.
pub(crate) struct Bar<'a>(Option<&'a dyn Progress>);

impl<'a> Bar<'a> {
    pub(crate) fn begin(
        progress: &'a dyn Progress,
        what: &str,
        total: usize,
        min: usize,
    ) -> Bar<'a> {
        if total < min {
            return Bar(None);
        }
        progress.begin(what, total);
        Bar(Some(progress))
    }

    pub(crate) fn advance(&self) {
        if let Some(p) = self.0 {
            p.advance();
        }
    }
}

impl Drop for Bar<'_> {
    fn drop(&mut self) {
        if let Some(p) = self.0 {
            p.end();
        }
    }
}

/// The process's peak resident set size in bytes (`VmHWM` of `/proc/self/status`): the most
/// physical memory it has held at once since it started. `None` where there is no such file
/// (not Linux).
pub fn peak_rss_bytes() -> Option<u64> {
    status_kb("VmHWM:")
}

/// The process's resident set size now, in bytes (`VmRSS`); `None` off Linux.
pub fn rss_bytes() -> Option<u64> {
    status_kb("VmRSS:")
}

/// A `kB` field of `/proc/self/status`, in bytes.
fn status_kb(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_status_kb(&status, field)
}

fn parse_status_kb(status: &str, field: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line[field.len()..]
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// A 128-bit hash of `bytes` (two independent 64-bit lanes over little-endian words, each
/// finished by MurmurHash3's `fmix64`; the length is hashed too). Not cryptographic: it tells
/// files and cache payloads apart (a collision by chance needs about 2⁶⁴ inputs), it does not
/// resist someone crafting a collision.
pub fn hash128(bytes: &[u8]) -> [u64; 2] {
    const K: [u64; 2] = [0x9e37_79b9_7f4a_7c15, 0xc2b2_ae3d_27d4_eb4f];
    let mut h = [0x243f_6a88_85a3_08d3u64, 0x1319_8a2e_0370_7344];
    let mix = |h: &mut [u64; 2], w: u64| {
        h[0] = (h[0] ^ w).wrapping_mul(K[0]).rotate_left(29);
        h[1] = (h[1].rotate_left(17) ^ w.wrapping_mul(K[1])).wrapping_mul(K[0] | 1);
    };
    let mut words = bytes.chunks_exact(8);
    for w in words.by_ref() {
        let mut b = [0u8; 8];
        b.copy_from_slice(w);
        mix(&mut h, u64::from_le_bytes(b));
    }
    let rest = words.remainder();
    let mut b = [0u8; 8];
    b[..rest.len()].copy_from_slice(rest);
    mix(&mut h, u64::from_le_bytes(b));
    mix(&mut h, bytes.len() as u64);
    let fmix = |mut k: u64| {
        k ^= k >> 33;
        k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
        k ^= k >> 33;
        k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        k ^ (k >> 33)
    };
    let (a, b) = (fmix(h[0]), fmix(h[1] ^ h[0]));
    [a, b]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_fields_are_read_in_bytes() {
        let s = "Name:\tx\nVmHWM:\t  2048 kB\nVmRSS:\t    12 kB\n";
        assert_eq!(parse_status_kb(s, "VmHWM:"), Some(2048 * 1024));
        assert_eq!(parse_status_kb(s, "VmRSS:"), Some(12 * 1024));
        assert_eq!(parse_status_kb(s, "VmPeak:"), None);
        if cfg!(target_os = "linux") {
            let now = rss_bytes().expect("linux has VmRSS");
            let peak = peak_rss_bytes().expect("and VmHWM");
            assert!(peak >= now && now > 0, "{peak} {now}");
        }
    }

    #[test]
    fn hash128_tells_single_bit_flips_and_lengths_apart() {
        let base: Vec<u8> = (0..100u32).map(|i| (i * 37 % 251) as u8).collect();
        let h = hash128(&base);
        let mut seen = std::collections::HashSet::new();
        seen.insert(h);
        for byte in 0..base.len() {
            for bit in 0..8 {
                let mut b = base.clone();
                b[byte] ^= 1 << bit;
                assert!(seen.insert(hash128(&b)), "flip at {byte}.{bit} collides");
            }
        }
        // Trailing zeros change the length, hence the hash.
        let mut longer = base.clone();
        longer.push(0);
        assert_ne!(hash128(&longer), h);
        assert_ne!(hash128(&[]), hash128(&[0]));
    }
}
