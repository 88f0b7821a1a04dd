//! `patchwork merge SHARD.json…`: the shards of a sharded run (`check --shard I/N`, `bench
//! --scale --shard I/N`) put back together. It prints what the unsharded run prints (`check`:
//! text or `--json`, through `check::FileBlock`; `bench --scale`: the table) and exits as it
//! would: `check` 0, 1 when a fat-bordered view cracked, 2 when a file failed; `bench --scale`
//! 1 when a point failed — or 2 when the shards do not make up one whole run exactly once.
//!
//! Checked before anything is printed: every file is a shard of this format; all ran the same
//! run (files, views and every option that changes a result) in the same number of shards N;
//! each of the shards 1..N is given exactly once; the run's case list (`check`: files × views;
//! `bench --scale`: the points), recomputed here, has the fingerprint the shards recorded;
//! every case is in the shard its id hashes to, and each case of the run comes exactly once.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::Value;
use thiserror::Error;

use patchwork::check::CrackCounts;
use patchwork::render::FatBorders;

use super::check::{CaseResult, FileBlock, Run};
use crate::error::CliError;
use crate::out::{data, note};
use crate::shard;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The shard files (`check --shard I/N --out FILE`, `bench --scale --shard I/N --out
    /// FILE`), one per shard, in any order.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
}

#[derive(Debug, Error)]
pub enum MergeError {
    #[error("no shard file given")]
    NoShards,
    #[error("{}: {source}", .path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a patchwork shard file: {reason}", .path.display())]
    NotShard { path: PathBuf, reason: String },
    #[error(
        "{}: {what} differs from {}'s: the shards are not of one run",
        .path.display(),
        .first.display()
    )]
    OtherRun {
        path: PathBuf,
        first: PathBuf,
        what: &'static str,
    },
    #[error("shard {index}/{total} given twice: {} and {}", .first.display(), .second.display())]
    DuplicateShard {
        index: usize,
        total: usize,
        first: PathBuf,
        second: PathBuf,
    },
    #[error("missing shard(s) {} of {total}: every shard must be given once", list(.missing))]
    MissingShards { missing: Vec<usize>, total: usize },
    #[error("{}: case {id:?} {reason}", .path.display())]
    BadCase {
        path: PathBuf,
        id: String,
        reason: &'static str,
    },
    #[error("{}: the run's case list does not have the fingerprint the shard recorded", .path.display())]
    Fingerprint { path: PathBuf },
    #[error("{count} case(s) of the run are in no shard, e.g. {first:?}")]
    MissingCases { count: usize, first: String },
}

fn list(numbers: &[usize]) -> String {
    let shown: Vec<String> = numbers.iter().map(usize::to_string).collect();
    shown.join(", ")
}

/// One shard file, read and checked on its own.
struct ShardFile {
    path: PathBuf,
    shard: shard::Shard,
    run: Value,
    cases_total: u64,
    fingerprint: String,
    cases: Vec<Value>,
}

fn read_shard(path: &Path) -> Result<ShardFile, MergeError> {
    let text = std::fs::read_to_string(path).map_err(|source| MergeError::Read {
        path: path.to_owned(),
        source,
    })?;
    let not = |reason: String| MergeError::NotShard {
        path: path.to_owned(),
        reason,
    };
    let value: Value = serde_json::from_str(&text).map_err(|e| not(e.to_string()))?;
    if value["format"] != shard::FORMAT {
        return Err(not(format!(
            "format is {}, not {:?}",
            value["format"],
            shard::FORMAT
        )));
    }
    let number = |v: &Value, what: &str| v.as_u64().ok_or_else(|| not(format!("no {what}")));
    let index = number(&value["shard"]["index"], "shard.index")? as usize;
    let total = number(&value["shard"]["total"], "shard.total")? as usize;
    if index == 0 || index > total {
        return Err(not(format!("shard {index}/{total} does not exist")));
    }
    Ok(ShardFile {
        path: path.to_owned(),
        shard: shard::Shard { index, total },
        run: value["run"].clone(),
        cases_total: number(&value["cases_total"], "cases_total")?,
        fingerprint: value["cases_fingerprint"]
            .as_str()
            .ok_or_else(|| not("no cases_fingerprint".into()))?
            .to_owned(),
        cases: value["cases"]
            .as_array()
            .ok_or_else(|| not("no cases".into()))?
            .clone(),
    })
}

/// A check run as a shard file records it.
/// A JSON list of strings, or `None` when it is not one.
fn strings(v: &Value) -> Option<Vec<String>> {
    v.as_array()?
        .iter()
        .map(|s| s.as_str().map(str::to_owned))
        .collect()
}

/// A JSON `[width, height]` in pixels, or `None` when it is not one.
fn image_size(v: &Value) -> Option<(u32, u32)> {
    let side = |k: usize| v[k].as_u64().and_then(|n| u32::try_from(n).ok());
    Some((side(0)?, side(1)?))
}

fn parse_run(path: &Path, v: &Value) -> Result<Run, MergeError> {
    let not = |what: &str| MergeError::NotShard {
        path: path.to_owned(),
        reason: format!("run.{what} missing or malformed"),
    };
    if v["command"] != "check" {
        return Err(not("command (only `check` runs are sharded)"));
    }
    let files = strings(&v["files"]).ok_or_else(|| not("files"))?;
    let variants = v["variants"]
        .as_array()
        .and_then(|a| {
            a.iter()
                .map(|f| f.as_str().and_then(|s| s.parse::<FatBorders>().ok()))
                .collect()
        })
        .ok_or_else(|| not("variants"))?;
    Ok(Run {
        files,
        views: v["views"].as_u64().ok_or_else(|| not("views"))? as usize,
        pixel_error: v["pixel_error"]
            .as_f64()
            .ok_or_else(|| not("pixel_error"))?,
        size: image_size(&v["size"]).ok_or_else(|| not("size"))?,
        variants,
        narrowed_width: match &v["narrowed_width"] {
            Value::Null => None,
            n => Some(n.as_f64().ok_or_else(|| not("narrowed_width"))?),
        },
        rest: v["options"].clone(),
    })
}

/// One case of a shard file: its file's index in the run, and its results or the error its
/// file had.
fn parse_case(
    path: &Path,
    run: &Run,
    case: &Value,
) -> Result<(String, usize, Result<CaseResult, String>), MergeError> {
    let id = case["id"].as_str().unwrap_or_default().to_owned();
    let bad = |reason| MergeError::BadCase {
        path: path.to_owned(),
        id: id.clone(),
        reason,
    };
    let view = case["view"].as_u64().ok_or_else(|| bad("has no view"))? as usize;
    let file = case["file"].as_str().ok_or_else(|| bad("has no file"))?;
    if shard::check_case_id(file, view) != id {
        return Err(bad("is not its file and view"));
    }
    if let Some(error) = case["error"].as_str() {
        return Ok((id, view, Err(error.to_owned())));
    }
    let counts = |key: &str| -> Option<Vec<(FatBorders, CrackCounts)>> {
        case[key]
            .as_array()?
            .iter()
            .map(|c| {
                let n = |k: &str| c[k].as_u64().and_then(|n| usize::try_from(n).ok());
                Some((
                    c["fat_borders"].as_str()?.parse().ok()?,
                    CrackCounts {
                        inside: n("inside")?,
                        background: n("background")?,
                        behind: n("behind")?,
                        growth: n("growth")?,
                        growth_max_px: u32::try_from(c["growth_max_px"].as_u64()?).ok()?,
                    },
                ))
            })
            .collect()
    };
    let result = CaseResult {
        view,
        triangles: case["triangles"]
            .as_u64()
            .ok_or_else(|| bad("has no triangles"))? as usize,
        reference_grid: case["reference_grid"]
            .as_u64()
            .and_then(|g| u32::try_from(g).ok())
            .ok_or_else(|| bad("has no reference_grid"))?,
        counts: counts("counts").ok_or_else(|| bad("has malformed counts"))?,
        narrowed: counts("narrowed").ok_or_else(|| bad("has malformed narrowed counts"))?,
    };
    if result
        .counts
        .iter()
        .map(|(v, _)| *v)
        .ne(run.variants.iter().copied())
    {
        return Err(bad("does not have the run's fat-border variants"));
    }
    Ok((id, view, Ok(result)))
}

/// The shards, read and checked to be of one run (same run, same number of shards), each of
/// 1..N given exactly once.
fn gather(paths: &[PathBuf]) -> Result<Vec<ShardFile>, MergeError> {
    let shards: Vec<ShardFile> = paths
        .iter()
        .map(|p| read_shard(p))
        .collect::<Result<_, _>>()?;
    let Some(first) = shards.first() else {
        return Err(MergeError::NoShards);
    };
    let total = first.shard.total;
    let mut by_index: BTreeMap<usize, &Path> = BTreeMap::new();
    for s in &shards {
        let other = |what| MergeError::OtherRun {
            path: s.path.clone(),
            first: first.path.clone(),
            what,
        };
        if s.shard.total != total {
            return Err(other("the number of shards"));
        }
        if s.run != first.run {
            return Err(other("the run (its cases or options)"));
        }
        if s.cases_total != first.cases_total || s.fingerprint != first.fingerprint {
            return Err(other("the case list"));
        }
        if let Some(before) = by_index.insert(s.shard.index, &s.path) {
            return Err(MergeError::DuplicateShard {
                index: s.shard.index,
                total,
                first: before.to_owned(),
                second: s.path.clone(),
            });
        }
    }
    let missing: Vec<usize> = (1..=total).filter(|i| !by_index.contains_key(i)).collect();
    if !missing.is_empty() {
        return Err(MergeError::MissingShards { missing, total });
    }
    Ok(shards)
}

/// Every case of the run (`all`: its ids, in the run's order, as recomputed from the run) with
/// the shard file it came from: each in the shard its id hashes to, none twice, none missing.
fn assign<'a>(
    shards: &'a [ShardFile],
    all: &[String],
) -> Result<Vec<(&'a Path, &'a Value)>, MergeError> {
    let Some(first) = shards.first() else {
        return Err(MergeError::NoShards);
    };
    if all.len() as u64 != first.cases_total
        || shard::fingerprint(all.iter().map(String::as_str)) != first.fingerprint
    {
        return Err(MergeError::Fingerprint {
            path: first.path.clone(),
        });
    }
    let position: BTreeMap<&str, usize> = all
        .iter()
        .enumerate()
        .map(|(k, id)| (id.as_str(), k))
        .collect();
    let mut slots: Vec<Option<(&Path, &Value)>> = vec![None; all.len()];
    for s in shards {
        for case in &s.cases {
            let id = case["id"].as_str().unwrap_or_default();
            let bad = |reason| MergeError::BadCase {
                path: s.path.clone(),
                id: id.to_owned(),
                reason,
            };
            let Some(&k) = position.get(id) else {
                return Err(bad("is not a case of the run"));
            };
            if shard::shard_of(id, s.shard.total) != s.shard.index {
                return Err(bad("belongs to another shard"));
            }
            if slots[k].replace((s.path.as_path(), case)).is_some() {
                return Err(bad("comes twice"));
            }
        }
    }
    let missing = slots.iter().filter(|s| s.is_none()).count();
    if missing > 0 {
        let first = slots
            .iter()
            .zip(all)
            .find(|(s, _)| s.is_none())
            .map(|(_, id)| id.clone())
            .unwrap_or_default();
        return Err(MergeError::MissingCases {
            count: missing,
            first,
        });
    }
    Ok(slots.into_iter().flatten().collect())
}

/// Prints the merged run as the unsharded run prints it; returns what it returns.
pub fn run(args: &MergeArgs) -> Result<bool, CliError> {
    let shards = gather(&args.shards)?;
    let Some(first) = shards.first() else {
        return Err(MergeError::NoShards.into());
    };
    match first.run["command"].as_str() {
        Some("check") => merge_check(&shards),
        Some("bench-scale") => merge_scale(&shards),
        _ => Err(MergeError::NotShard {
            path: first.path.clone(),
            reason: format!(
                "run.command {} is not check or bench-scale",
                first.run["command"]
            ),
        }
        .into()),
    }
}

/// `check`: file by file as the unsharded run prints them (`check::FileBlock`).
fn merge_check(shards: &[ShardFile]) -> Result<bool, CliError> {
    let Some(first) = shards.first() else {
        return Err(MergeError::NoShards.into());
    };
    let run = parse_run(&first.path, &first.run)?;
    let ids = run.case_ids();
    let all: Vec<String> = ids.iter().map(|(_, _, id)| id.clone()).collect();
    let mut files: Vec<BTreeMap<usize, Result<CaseResult, String>>> =
        vec![BTreeMap::new(); run.files.len()];
    for ((f, _, _), (path, case)) in ids.iter().zip(assign(shards, &all)?) {
        let (_, view, result) = parse_case(path, &run, case)?;
        files[*f].insert(view, result);
    }
    note!(
        "merged {} shards: {} cases ({} files × {} views)",
        first.shard.total,
        all.len(),
        run.files.len(),
        run.views
    );
    let block = FileBlock { run: &run };
    let paths: Vec<PathBuf> = run.files.iter().map(PathBuf::from).collect();
    let mut next = 0;
    super::for_each_file(&paths, |_| {
        let (name, cases) = (&run.files[next], &files[next]);
        next += 1;
        // The unsharded run stops a file at its first error (the load, usually).
        if let Some(Err(error)) = cases.values().find(|c| c.is_err()) {
            return Err(CliError::Recorded(error.clone()));
        }
        let cases: Vec<CaseResult> = cases.values().filter_map(|c| c.clone().ok()).collect();
        block.header();
        for case in &cases {
            block.row(case);
        }
        Ok(block.summary(name, &run.views.to_string(), &cases))
    })
}

/// `bench --scale`: the points' errors on stderr, then the heading and the table, in the
/// unsharded run's order; exit code 1 when a point failed.
fn merge_scale(shards: &[ShardFile]) -> Result<bool, CliError> {
    let Some(first) = shards.first() else {
        return Err(MergeError::NoShards.into());
    };
    let run = &first.run;
    let not = |what: &str| MergeError::NotShard {
        path: first.path.clone(),
        reason: format!("run.{what} missing or malformed"),
    };
    let all = strings(&run["cases"]).ok_or_else(|| not("cases"))?;
    let heading = super::bench::scale_heading(
        run["frames"].as_u64().ok_or_else(|| not("frames"))? as usize,
        image_size(&run["size"]).ok_or_else(|| not("size"))?,
        run["pixel_error"]
            .as_f64()
            .ok_or_else(|| not("pixel_error"))?,
        run["budget_ms"].as_f64().ok_or_else(|| not("budget_ms"))?,
    );
    let mut points = Vec::new();
    let mut failed = 0;
    for (path, case) in assign(shards, &all)? {
        let bad = |reason| MergeError::BadCase {
            path: path.to_owned(),
            id: case["id"].as_str().unwrap_or_default().to_owned(),
            reason,
        };
        if let Some(error) = case["error"].as_str() {
            eprintln!("error: {error}");
            failed += 1;
            continue;
        }
        let row = case["row"].as_str().ok_or_else(|| bad("has no row"))?;
        points.push(
            patchwork::report::scale::parse_row(row).map_err(|_| bad("has a malformed row"))?,
        );
    }
    note!("merged {} shards: {} points", first.shard.total, all.len());
    data!("{heading}");
    crate::out::write(format_args!(
        "{}",
        patchwork::report::scale::markdown(&points)
    ));
    Ok(failed == 0)
}
