//! `patchwork check`: random views with fat borders off and on; crack and growth pixels per
//! view and in sum. Exit code 1 when fat borders leave a crack.
//!
//! `--shard I/N` (or `auto`, from the batch engine's environment: `crate::shard`) runs only
//! the (file, view) cases of that shard and writes them, each with its id, as one JSON object
//! (`--out FILE`, and on stdout with `--json`); `patchwork merge` (`cmd::merge`) puts the
//! shards back together and prints what the unsharded run prints, through the same
//! [`FileBlock`] printing.

use std::path::{Path, PathBuf};

use clap::Args;
use serde_json::{Value, json};

use patchwork::check::{CheckOptions, CrackCounts, run_check};
use patchwork::render::{FatBorders, Renderer};
use patchwork::view;

use super::{load_built, progress};
use crate::args::{PrimitivesArg, at_least, fov_y, parse_size, pixel_error};
use crate::error::CliError;
use crate::out::{data, note};
use crate::shard::{self, Shard};

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Model files (`-` reads stdin, with --format); several: one block (one JSON object in
    /// an array) per file, exit code the worst.
    #[arg(required_unless_present = "files_from")]
    files: Vec<PathBuf>,
    /// Also check the files listed in LIST, one path per line (after those given; blank
    /// lines and lines starting with `#` skipped): corpora longer than a command line.
    #[arg(long, value_name = "LIST")]
    files_from: Option<PathBuf>,
    #[command(flatten)]
    cache: crate::args::CacheArgs,
    /// Number of random views.
    #[arg(long, default_value_t = 20)]
    views: usize,
    /// Seed of the random views.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Allowed screen-space error in pixels.
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pixel_error: f64,
    /// Image size of every view.
    #[arg(long, default_value = "512x384", value_parser = parse_size)]
    size: (u32, u32),
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    fov: f64,
    /// Orthographic views (each as tall as the perspective view's at its target).
    #[arg(long)]
    ortho: bool,
    /// Write actual and crack-mask images of views with cracks or growth into this folder
    /// (with --shard named after their case: `models%2Fa.step#view003-fb6-actual.png`).
    #[arg(long)]
    save_failures: Option<PathBuf>,
    #[command(flatten)]
    primitives: PrimitivesArg,
    /// Stress tessellation: every border pulled back towards its patch as far as the pixel
    /// error allows, so that only fat borders of full width close the gaps.
    #[arg(long)]
    stress: bool,
    /// Also measure the fat borders drawn this much narrower (a mutation: 0.5 must crack).
    #[arg(long)]
    narrowed_width: Option<f64>,
    /// Run one shard of the (file, view) cases: `I/N` (1-based), or `auto` / `auto/N` from
    /// the batch engine's environment (JOB_COMPLETION_INDEX, SLURM_ARRAY_TASK_ID,
    /// AWS_BATCH_JOB_ARRAY_INDEX, CI_NODE_INDEX; N where it holds no total). The shard's
    /// results go to --out / --json; `patchwork merge` combines the shards.
    #[arg(long, value_name = "I/N|auto[/N]", value_parser = shard::parse_spec)]
    shard: Option<shard::ShardSpec>,
    /// With --shard: write the shard's results (JSON) to this file (temporary name, renamed).
    #[arg(short, long, requires = "shard")]
    out: Option<PathBuf>,
}

/// What a check run measures, as the shard files record it (`merge` refuses shards whose
/// runs differ) and as the printing needs it.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    pub files: Vec<String>,
    pub views: usize,
    pub pixel_error: f64,
    pub size: (u32, u32),
    pub variants: Vec<FatBorders>,
    pub narrowed_width: Option<f64>,
    /// The rest of the options, as JSON (seed, field of view, projection, stress,
    /// primitives): compared, never interpreted.
    pub rest: Value,
}

impl Run {
    pub fn to_json(&self) -> Value {
        json!({
            "command": "check",
            "files": self.files,
            "views": self.views,
            "pixel_error": self.pixel_error,
            "size": [self.size.0, self.size.1],
            "variants": self.variants.iter().map(|v| v.name()).collect::<Vec<_>>(),
            "narrowed_width": self.narrowed_width,
            "options": self.rest,
        })
    }

    /// Every case id of the run, file by file, view by view.
    pub fn case_ids(&self) -> Vec<(usize, usize, String)> {
        let mut ids = Vec::with_capacity(self.files.len() * self.views);
        for (f, file) in self.files.iter().enumerate() {
            for view in 0..self.views {
                ids.push((f, view, shard::check_case_id(file, view)));
            }
        }
        ids
    }
}

/// One view's results: a row of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseResult {
    pub view: usize,
    pub triangles: usize,
    pub reference_grid: u32,
    pub counts: Vec<(FatBorders, CrackCounts)>,
    pub narrowed: Vec<(FatBorders, CrackCounts)>,
}

pub fn counts_json(variant: FatBorders, t: &CrackCounts) -> Value {
    json!({
        "fat_borders": variant.name(),
        "cracks": t.cracks(),
        "background": t.background,
        "behind": t.behind,
        "growth": t.growth,
        "growth_max_px": t.growth_max_px,
        "inside": t.inside,
    })
}

impl CaseResult {
    fn row(&self) -> String {
        let cells: Vec<String> = self
            .counts
            .iter()
            .map(|(_, c)| format!("{:>13}", c.cracks()))
            .collect();
        let growth = self
            .counts
            .iter()
            .find(|(v, _)| *v == FatBorders::Six)
            .map(|(_, c)| c.growth)
            .unwrap_or(0);
        format!(
            "{:>4}  {:>9}  {:>8}  {}  {:>10}",
            self.view,
            self.triangles,
            self.reference_grid,
            cells.join("  "),
            growth
        )
    }

    /// The case as a shard file stores it (with its id and file).
    pub fn to_json(&self, id: &str, file: &str) -> Value {
        let counts = |c: &[(FatBorders, CrackCounts)]| -> Vec<Value> {
            c.iter().map(|(v, t)| counts_json(*v, t)).collect()
        };
        json!({
            "id": id,
            "file": file,
            "view": self.view,
            "triangles": self.triangles,
            "reference_grid": self.reference_grid,
            "counts": counts(&self.counts),
            "narrowed": counts(&self.narrowed),
        })
    }
}

/// The text and JSON of one file's check: the table's header, its rows, the summary.
pub struct FileBlock<'a> {
    pub run: &'a Run,
}

impl FileBlock<'_> {
    pub fn header(&self) {
        let header: Vec<String> = self
            .run
            .variants
            .iter()
            .map(|v| format!("cracks fb={:<3}", v.name()))
            .collect();
        data!(
            "{:>4}  {:>9}  {:>8}  {}  {:>10}",
            "view",
            "triangles",
            "ref grid",
            header.join("  "),
            "growth(6)"
        );
    }

    pub fn row(&self, case: &CaseResult) {
        data!("{}", case.row());
    }

    /// Prints the summary over `cases` (`views` says how many: "20", or "7 of 20 … (shard
    /// 1/3)") and returns whether no fat-bordered view cracked, with the file's JSON object.
    pub fn summary(&self, file: &str, views: &str, cases: &[CaseResult]) -> (bool, Value) {
        let run = self.run;
        let total = |narrowed: bool, v: FatBorders| {
            let mut t = CrackCounts::default();
            for case in cases {
                let list = if narrowed {
                    &case.narrowed
                } else {
                    &case.counts
                };
                for (_, c) in list.iter().filter(|(w, _)| *w == v) {
                    t.add(c);
                }
            }
            t
        };
        data!();
        data!(
            "summary over {} views at {} px pixel error, {}x{}:",
            views,
            run.pixel_error,
            run.size.0,
            run.size.1
        );
        for v in &run.variants {
            let t = total(false, *v);
            data!(
                "  fat borders {:<3}  crack pixels {:>7} (background {}, surface behind {}), growth pixels {} (max {} px out), of {} inside pixels",
                v.name(),
                t.cracks(),
                t.background,
                t.behind,
                t.growth,
                t.growth_max_px,
                t.inside
            );
        }
        let on: Vec<FatBorders> = run
            .variants
            .iter()
            .copied()
            .filter(|v| *v != FatBorders::Off)
            .collect();
        if let Some(f) = run.narrowed_width {
            for v in &on {
                let t = total(true, *v);
                data!(
                    "  fat borders {:<3} × {f}  crack pixels {:>7} (background {}, surface behind {}), growth pixels {}",
                    v.name(),
                    t.cracks(),
                    t.background,
                    t.behind,
                    t.growth
                );
            }
        }
        let ok = cases.iter().all(|c| {
            c.counts
                .iter()
                .all(|(fb, t)| *fb == FatBorders::Off || t.cracks() == 0)
        });
        let value = json!({
            "file": file,
            "views": run.views,
            "pixel_error": run.pixel_error,
            "size": [run.size.0, run.size.1],
            "variants": run.variants.iter().map(|v| counts_json(*v, &total(false, *v))).collect::<Vec<_>>(),
            "narrowed": run.narrowed_width.map(|f| json!({
                "factor": f,
                "variants": on.iter().map(|v| counts_json(*v, &total(true, *v))).collect::<Vec<_>>(),
            })),
            "crack_free": ok,
        });
        data!(
            "{}",
            if ok {
                "OK: no crack pixel with fat borders"
            } else {
                "FAIL: crack pixels with fat borders"
            }
        );
        (ok, value)
    }
}

/// The validated options of one invocation.
struct Checked {
    files: Vec<PathBuf>,
    run: Run,
    opts: CheckOptions,
}

/// The files given, then those `--files-from` lists.
fn files(args: &CheckArgs) -> Result<Vec<PathBuf>, CliError> {
    let mut files = args.files.clone();
    if let Some(list) = &args.files_from {
        let text = std::fs::read_to_string(list).map_err(|source| CliError::Io {
            path: list.clone(),
            source,
        })?;
        files.extend(
            text.lines()
                .map(str::trim_end)
                .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
                .map(PathBuf::from),
        );
        if files.is_empty() {
            return Err(CliError::NoFiles { list: list.clone() });
        }
    }
    Ok(files)
}

fn checked(args: &CheckArgs) -> Result<Checked, CliError> {
    let files = files(args)?;
    let fov_y = fov_y(args.fov)?;
    let pixel_error = pixel_error(args.pixel_error)?;
    let views = at_least("--views", args.views, 1)?;
    let opts = CheckOptions {
        views,
        seed: args.seed,
        pixel_error,
        size: args.size,
        fov_y,
        ortho: args.ortho,
        save_failures: args.save_failures.clone(),
        stress: args.stress,
        narrowed_width: args.narrowed_width,
        ..CheckOptions::default()
    };
    let run = Run {
        files: files.iter().map(|f| f.display().to_string()).collect(),
        views,
        pixel_error,
        size: args.size,
        variants: opts.variants.clone(),
        narrowed_width: args.narrowed_width,
        rest: json!({
            "seed": args.seed,
            "fov": args.fov,
            "ortho": args.ortho,
            "stress": args.stress,
            "primitives": format!("{:?}", args.primitives.primitives),
        }),
    };
    Ok(Checked { files, run, opts })
}

/// Whether the check passed (no crack pixel with fat borders) for every file.
pub fn run(args: &CheckArgs) -> Result<bool, CliError> {
    let checked = checked(args)?;
    let mut renderer = None;
    if let Some(spec) = args.shard {
        let (shard, from) = shard::resolve(spec, |v| std::env::var(v).ok())?;
        if let Some(variable) = from {
            note!("shard {shard} (from {variable})");
        }
        return run_shard(args, &checked, shard, &mut renderer);
    }
    let block = FileBlock { run: &checked.run };
    super::for_each_file(&checked.files, |file| {
        let cases = run_views(args, &checked, file, None, &mut renderer)?;
        Ok(block.summary(
            &file.display().to_string(),
            &checked.run.views.to_string(),
            &cases,
        ))
    })
}

/// One file's views (`only`: these indices, else all): the table's header and rows printed
/// as they come. The renderer is made once, after the first file loads (a missing file is
/// reported first).
fn run_views(
    args: &CheckArgs,
    checked: &Checked,
    file: &Path,
    only: Option<(Vec<usize>, String)>,
    renderer: &mut Option<Renderer>,
) -> Result<Vec<CaseResult>, CliError> {
    let scene = load_built(file, &args.cache)?;
    let renderer = match renderer {
        Some(r) => r,
        None => {
            let mut r = Renderer::new()?;
            r.primitives = args.primitives.primitives;
            note!("adapter: {}", r.gpu().describe());
            renderer.insert(r)
        }
    };
    if let Some(dir) = &args.save_failures {
        std::fs::create_dir_all(dir).map_err(|source| CliError::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let mut opts = checked.opts.clone();
    if let Some((views, prefix)) = only {
        opts.only_views = Some(views);
        opts.failure_prefix = prefix;
    }
    let block = FileBlock { run: &checked.run };
    let pb = progress(opts.view_indices().len(), "views");
    block.header();
    let mut cases = Vec::new();
    run_check(renderer, &scene, &opts, |r| {
        let case = CaseResult {
            view: r.index,
            triangles: r.stats.triangles,
            reference_grid: r.reference_grid,
            counts: r.counts.clone(),
            narrowed: r.narrowed.clone(),
        };
        pb.suspend(|| block.row(&case));
        pb.inc(1);
        cases.push(case);
    })?;
    pb.finish_and_clear();
    Ok(cases)
}

/// Runs this shard's cases, file by file (files with none are not loaded), and writes them
/// with the run they belong to. A file that fails is recorded as an error on each of its
/// cases here (the shard file is still written: `merge` reports it as the unsharded run
/// would); the exit code is the worst, as for several files.
fn run_shard(
    args: &CheckArgs,
    checked: &Checked,
    shard: Shard,
    renderer: &mut Option<Renderer>,
) -> Result<bool, CliError> {
    let run = &checked.run;
    let all = run.case_ids();
    let fingerprint = shard::fingerprint(all.iter().map(|(_, _, id)| id.as_str()));
    let mut mine: Vec<Vec<usize>> = vec![Vec::new(); run.files.len()];
    for (f, view, id) in &all {
        if shard::shard_of(id, shard.total) == shard.index {
            mine[*f].push(*view);
        }
    }
    let count: usize = mine.iter().map(Vec::len).sum();
    data!("shard {shard}: {count} of {} cases", all.len());
    let (mut cases, mut failed, mut passed) = (Vec::new(), 0, true);
    for ((file, name), views) in checked.files.iter().zip(&run.files).zip(mine) {
        if views.is_empty() {
            continue;
        }
        data!();
        data!("== {name} ==");
        let prefix = format!("{}#", shard::file_name_part(name));
        let label = format!("{} of {}", views.len(), run.views);
        match run_views(args, checked, file, Some((views.clone(), prefix)), renderer) {
            Ok(results) => {
                let (ok, _) = FileBlock { run }.summary(name, &label, &results);
                passed &= ok;
                for r in &results {
                    cases.push(r.to_json(&shard::check_case_id(name, r.view), name));
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                failed += 1;
                for view in views {
                    cases.push(json!({
                        "id": shard::check_case_id(name, view),
                        "file": name,
                        "view": view,
                        "error": e.to_string(),
                    }));
                }
            }
        }
    }
    let value = json!({
        "format": shard::FORMAT,
        "shard": { "index": shard.index, "total": shard.total },
        "run": run.to_json(),
        "cases_total": all.len(),
        "cases_fingerprint": fingerprint,
        "cases": cases,
    });
    if let Some(path) = &args.out {
        patchwork::io::png::write_text(path, &format!("{value}\n"))?;
        note!("wrote {}", path.display());
    }
    crate::out::emit(&value);
    if failed > 0 {
        return Err(CliError::FilesFailed {
            failed,
            total: checked.files.len(),
        });
    }
    Ok(passed)
}
