//! Small helpers shared by several stages: integer-keyed hash maps and sets, progress of long
//! load steps ([`Progress`], re-exported by `prep`), and the process's resident memory (Linux
//! `/proc/self/status`).

use std::collections::{HashMap, HashSet};
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
pub(crate) type IntSet<K> = HashSet<K, BuildHasherDefault<IntHasher>>;

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
}
