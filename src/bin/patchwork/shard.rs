//! Sharded runs: one command's cases split between machines (`check --shard I/N`), put back
//! together by `patchwork merge`.
//!
//! A **case** is one unit of work with an id that names it on every machine: for `check`, a
//! (file, view) pair, `FILE#viewNNN` with FILE as given on the command line (so relative paths
//! give ids that do not depend on where the corpus is mounted). A case belongs to shard
//! `1 + (fmix64(FNV-1a-64(id)) mod N)` ([`shard_of`]): FNV-1a over the id's UTF-8 bytes, then
//! MurmurHash3's 64-bit finalizer (FNV-1a alone leaves ids that differ in their last digit
//! close in the high bits, and its low k bits depend only on the low k bits of each byte). The
//! hash is fixed here, not std's `DefaultHasher` (whose algorithm may change between Rust
//! releases), so a case stays in its shard across machines and releases, and adding files
//! moves no other case: only changing N reshuffles.
//!
//! `--shard auto` reads the shard from the batch engine's environment ([`from_env`]), in this
//! order, the first index variable found winning:
//!
//! | engine | index | total |
//! |---|---|---|
//! | Kubernetes Indexed Job | `JOB_COMPLETION_INDEX` (0-based) | not in the environment: `auto/N` |
//! | Slurm job array | `SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN`, ÷ `SLURM_ARRAY_TASK_STEP` | `SLURM_ARRAY_TASK_COUNT` |
//! | AWS Batch array job | `AWS_BATCH_JOB_ARRAY_INDEX` (0-based) | not in the environment: `auto/N` |
//! | GitLab CI `parallel:` | `CI_NODE_INDEX` (1-based) | `CI_NODE_TOTAL` |
//!
//! `auto/N` gives the total where the environment has none and must agree with it where it
//! has one. What this module does not do: run anything, or read results (that is
//! `cmd::merge`).

use std::fmt;

use thiserror::Error;

/// The `format` field of a shard file (`check --shard … --out`); a later layout gets a new one.
pub const FORMAT: &str = "patchwork-shard/1";

/// One shard of a run: `index` of `total`, 1-based (`2/3`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub total: usize,
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.total)
    }
}

/// What `--shard` was given: a shard, or `auto` with an optional total.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardSpec {
    Fixed(Shard),
    Auto { total: Option<usize> },
}

#[derive(Debug, Error)]
pub enum ShardError {
    #[error("--shard {value:?}: {reason} (expected I/N with 1 ≤ I ≤ N, auto, or auto/N)")]
    Spec { value: String, reason: &'static str },
    #[error(
        "--shard auto: no batch index in the environment (JOB_COMPLETION_INDEX, SLURM_ARRAY_TASK_ID, AWS_BATCH_JOB_ARRAY_INDEX or CI_NODE_INDEX); give --shard I/N"
    )]
    NoIndex,
    #[error("--shard auto: {variable}={value:?}: {reason}")]
    Variable {
        variable: &'static str,
        value: String,
        reason: String,
    },
    #[error(
        "--shard auto: {variable} is set but the number of shards is not in the environment; give --shard auto/N"
    )]
    NoTotal { variable: &'static str },
    #[error("--shard auto/{given}: the environment says {found} shards ({variable})")]
    TotalDisagrees {
        given: usize,
        found: usize,
        variable: &'static str,
    },
}

/// Parses `I/N`, `auto` or `auto/N`.
pub fn parse_spec(value: &str) -> Result<ShardSpec, ShardError> {
    let bad = |reason| ShardError::Spec {
        value: value.to_owned(),
        reason,
    };
    let count = |s: &str| {
        s.trim()
            .parse::<usize>()
            .map_err(|_| bad("not a whole number"))
    };
    if value.trim() == "auto" {
        return Ok(ShardSpec::Auto { total: None });
    }
    let (left, right) = value.split_once('/').ok_or_else(|| bad("no '/'"))?;
    let total = count(right)?;
    if total == 0 {
        return Err(bad("the number of shards must be at least 1"));
    }
    if left.trim() == "auto" {
        return Ok(ShardSpec::Auto { total: Some(total) });
    }
    let index = count(left)?;
    if index == 0 || index > total {
        return Err(bad(
            "the shard index must be between 1 and the number of shards",
        ));
    }
    Ok(ShardSpec::Fixed(Shard { index, total }))
}

/// The shard `spec` names; `auto` through `env` (a variable's value, `std::env::var` in the
/// command, a table in tests). Also returns where an automatic shard came from.
pub fn resolve(
    spec: ShardSpec,
    env: impl Fn(&str) -> Option<String>,
) -> Result<(Shard, Option<&'static str>), ShardError> {
    match spec {
        ShardSpec::Fixed(shard) => Ok((shard, None)),
        ShardSpec::Auto { total } => {
            from_env(total, env).map(|(shard, variable)| (shard, Some(variable)))
        }
    }
}

/// The shard the batch engine gave this process (see the module's table), and the index
/// variable it was read from.
pub fn from_env(
    given_total: Option<usize>,
    env: impl Fn(&str) -> Option<String>,
) -> Result<(Shard, &'static str), ShardError> {
    let number = |variable: &'static str| -> Result<Option<usize>, ShardError> {
        let Some(value) = env(variable) else {
            return Ok(None);
        };
        value
            .trim()
            .parse::<usize>()
            .map(Some)
            .map_err(|_| ShardError::Variable {
                variable,
                value,
                reason: "not a whole number ≥ 0".into(),
            })
    };
    // (index variable, 0-based index, total variable and total found)
    let (variable, zero_based, found): (&'static str, usize, Option<(&'static str, usize)>) =
        if let Some(i) = number("JOB_COMPLETION_INDEX")? {
            ("JOB_COMPLETION_INDEX", i, None)
        } else if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let offset = id.checked_sub(min).ok_or_else(|| ShardError::Variable {
                variable: "SLURM_ARRAY_TASK_ID",
                value: id.to_string(),
                reason: format!("below SLURM_ARRAY_TASK_MIN={min}"),
            })?;
            if offset % step != 0 {
                return Err(ShardError::Variable {
                    variable: "SLURM_ARRAY_TASK_ID",
                    value: id.to_string(),
                    reason: format!(
                        "not on the array's range {min}, {}, … (SLURM_ARRAY_TASK_STEP={step}): use --array=A-B[:S]",
                        min + step
                    ),
                });
            }
            let total = number("SLURM_ARRAY_TASK_COUNT")?.map(|n| ("SLURM_ARRAY_TASK_COUNT", n));
            ("SLURM_ARRAY_TASK_ID", offset / step, total)
        } else if let Some(i) = number("AWS_BATCH_JOB_ARRAY_INDEX")? {
            ("AWS_BATCH_JOB_ARRAY_INDEX", i, None)
        } else if let Some(i) = number("CI_NODE_INDEX")? {
            let zero = i.checked_sub(1).ok_or_else(|| ShardError::Variable {
                variable: "CI_NODE_INDEX",
                value: i.to_string(),
                reason: "GitLab's node index starts at 1".into(),
            })?;
            let total = number("CI_NODE_TOTAL")?.map(|n| ("CI_NODE_TOTAL", n));
            ("CI_NODE_INDEX", zero, total)
        } else {
            return Err(ShardError::NoIndex);
        };
    let total = match (given_total, found) {
        (Some(given), Some((total_variable, n))) if given != n => {
            return Err(ShardError::TotalDisagrees {
                given,
                found: n,
                variable: total_variable,
            });
        }
        (Some(n), _) | (None, Some((_, n))) => n,
        (None, None) => return Err(ShardError::NoTotal { variable }),
    };
    if total == 0 || zero_based >= total {
        return Err(ShardError::Variable {
            variable,
            value: env(variable).unwrap_or_default(),
            reason: format!("shard {} of {total} does not exist", zero_based + 1),
        });
    }
    Ok((
        Shard {
            index: zero_based + 1,
            total,
        },
        variable,
    ))
}

/// FNV-1a, 64 bits, over `bytes` (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// MurmurHash3's 64-bit finalizer: every input bit flips each output bit with probability ½.
fn fmix64(mut h: u64) -> u64 {
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

/// The shard (1-based) of `total` that case `id` belongs to.
pub fn shard_of(id: &str, total: usize) -> usize {
    // A usize always fits in a u64 on the platforms we build for; the remainder is < total.
    (fmix64(fnv1a64(id.as_bytes())) % total as u64) as usize + 1
}

/// The id of `check`'s case: view `view` of `file` as given on the command line.
pub fn check_case_id(file: &str, view: usize) -> String {
    format!("{file}#view{view:03}")
}

/// A fingerprint of a run's whole case list, whatever order it is given in: FNV-1a 64 of the
/// sorted ids, each followed by a newline, as 16 hex digits.
pub fn fingerprint<'a>(ids: impl IntoIterator<Item = &'a str>) -> String {
    let mut sorted: Vec<&str> = ids.into_iter().collect();
    sorted.sort_unstable();
    let mut bytes = Vec::new();
    for id in sorted {
        bytes.extend_from_slice(id.as_bytes());
        bytes.push(b'\n');
    }
    format!("{:016x}", fnv1a64(&bytes))
}

/// `id` as part of a file name: `%` → `%25`, `/` → `%2F`, `\` → `%5C` (reversible, so two
/// cases never share a name; `models/a.step#view003` → `models%2Fa.step#view003`).
pub fn file_name_part(id: &str) -> String {
    let mut out = String::with_capacity(id.len());
    for c in id.chars() {
        match c {
            '%' => out.push_str("%25"),
            '/' => out.push_str("%2F"),
            '\\' => out.push_str("%5C"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| (*v).to_owned())
        }
    }

    #[test]
    fn fnv1a64_matches_the_published_test_vectors() {
        // From the FNV reference test suite (Fowler, Noll, Vo).
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn a_case_keeps_its_shard_when_cases_are_added() {
        // Pinned (worked out by a separate Python implementation of the module doc's formula):
        // these must never change, or the shards of one release disagree with another's.
        assert_eq!(shard_of("models/teapot.bpt#view000", 3), 2);
        assert_eq!(shard_of("models/teapot.bpt#view001", 3), 1);
        assert_eq!(shard_of("models/screw.step#view000", 7), 2);
        let before: Vec<String> = (0..50).map(|v| check_case_id("a.step", v)).collect();
        let shards: Vec<usize> = before.iter().map(|id| shard_of(id, 4)).collect();
        // More files and views: the earlier cases stay where they were (the hash sees only
        // the id).
        let _more: Vec<String> = (0..500).map(|v| check_case_id("b.step", v)).collect();
        let again: Vec<usize> = before.iter().map(|id| shard_of(id, 4)).collect();
        assert_eq!(shards, again);
    }

    #[test]
    fn cases_spread_evenly_over_shards() {
        for total in [2, 3, 4, 8] {
            let mut counts = vec![0usize; total];
            for f in 0..100 {
                for v in 0..30 {
                    let id = check_case_id(&format!("corpus/part-{f}.step"), v);
                    counts[shard_of(&id, total) - 1] += 1;
                }
            }
            // A fair die: each count within 4 standard deviations of the binomial mean.
            let p = 1.0 / total as f64;
            let (mean, sigma) = (3000.0 * p, (3000.0 * p * (1.0 - p)).sqrt());
            for &c in &counts {
                assert!(
                    (c as f64 - mean).abs() < 4.0 * sigma,
                    "{total} shards: {counts:?} (mean {mean}, σ {sigma:.1})"
                );
            }
        }
    }

    #[test]
    fn shard_specs_parse_and_bad_ones_are_refused() {
        assert_eq!(
            parse_spec("2/3").ok(),
            Some(ShardSpec::Fixed(Shard { index: 2, total: 3 }))
        );
        assert_eq!(
            parse_spec("auto").ok(),
            Some(ShardSpec::Auto { total: None })
        );
        assert_eq!(
            parse_spec("auto/5").ok(),
            Some(ShardSpec::Auto { total: Some(5) })
        );
        for bad in ["0/3", "4/3", "1/0", "3", "a/b", "-1/3", "auto/0", ""] {
            assert!(parse_spec(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn each_engine_s_index_becomes_a_one_based_shard() {
        let k8s = env(&[("JOB_COMPLETION_INDEX", "0")]);
        assert_eq!(
            from_env(Some(3), &k8s).ok(),
            Some((Shard { index: 1, total: 3 }, "JOB_COMPLETION_INDEX"))
        );
        assert!(matches!(
            from_env(None, &k8s),
            Err(ShardError::NoTotal { .. })
        ));
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "7"),
            ("SLURM_ARRAY_TASK_MIN", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        assert_eq!(
            from_env(None, &slurm).ok().map(|r| r.0),
            Some(Shard { index: 3, total: 3 })
        );
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "10"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_STEP", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        assert_eq!(
            from_env(None, &stepped).ok().map(|r| r.0),
            Some(Shard { index: 3, total: 3 })
        );
        assert!(matches!(
            from_env(Some(4), &slurm),
            Err(ShardError::TotalDisagrees { found: 3, .. })
        ));
        let aws = env(&[("AWS_BATCH_JOB_ARRAY_INDEX", "4")]);
        assert_eq!(
            from_env(Some(5), &aws).ok().map(|r| r.0),
            Some(Shard { index: 5, total: 5 })
        );
        assert!(from_env(Some(4), &aws).is_err(), "index 4 of 4 shards");
        let gitlab = env(&[("CI_NODE_INDEX", "2"), ("CI_NODE_TOTAL", "4")]);
        assert_eq!(
            from_env(None, &gitlab).ok().map(|r| r.0),
            Some(Shard { index: 2, total: 4 })
        );
        assert!(from_env(None, env(&[("CI_NODE_INDEX", "0"), ("CI_NODE_TOTAL", "4")])).is_err());
        assert!(matches!(
            from_env(Some(3), env(&[])),
            Err(ShardError::NoIndex)
        ));
        assert!(from_env(Some(3), env(&[("JOB_COMPLETION_INDEX", "x")])).is_err());
    }

    #[test]
    fn fingerprints_ignore_order_and_file_names_keep_ids_apart() {
        assert_eq!(fingerprint(["b", "a"]), fingerprint(["a", "b"]));
        assert_ne!(fingerprint(["a", "b"]), fingerprint(["a", "b", "c"]));
        assert_ne!(fingerprint(["ab"]), fingerprint(["a", "b"]));
        assert_eq!(
            file_name_part("models/a.step#view003"),
            "models%2Fa.step#view003"
        );
        assert_ne!(file_name_part("a/b"), file_name_part("a%2Fb"));
    }
}
