//! Trimmed tessellation against Open CASCADE `BRepMesh`, per surface kind and in total: time
//! and triangles at equal tolerance (issue 31 item 3).
//!
//! `cargo bench --bench occt_faces` prints a Markdown table (also written to
//! `target/occt_faces.md`): for the three corpus boards (`models/corpus/kicad-demo-*.step.gz`,
//! decompressed into `target/occt_faces/` for OCCT) and two machined parts (`models/screw.step`,
//! `models/as1-oc-214.stp`), at [`REL_TOLERANCES`] × our bounding-box diagonal, one row per
//! surface kind (plane, cylinder, cone, torus, B-spline, …) and one total row.
//!
//! * **ours**: every trimmed face once (a face the assembly places several times is
//!   tessellated once, as the frame loop and `export` do) through `Tessellators::unplaced` at
//!   ε = the tolerance, one after the other on this thread; a face's time is the fastest of
//!   [`OUR_RUNS`] runs (reading excluded), the total is their sum.
//! * **occt**: `benches/occt_mesh.py --by-kind` (in the OCCT venv `~/.cache/patchwork-occt-venv`
//!   when it exists, else `python3`): `BRepMesh_IncrementalMesh(shape, ε, False, 0.5, False)`,
//!   linear deflection ε, angular deflection 0.5 rad, one thread, timed once around that call
//!   (reading excluded); its triangulation is stored once per `TShape`, so its triangles are
//!   counted once per face, like ours. Kinds are `GeomAdaptor_Surface` types mapped to ours.
//!
//! Faces are compared by kind, not one by one: OCCT's `TopExp_Explorer` order is not our face
//! order, and finding each face's STEP entity through the transfer reader takes minutes per
//! board (a linear search per face). `PATCHWORK_OCCT_FACES_FILES` (comma-separated) replaces
//! the file list. Outside `cargo bench` (`cargo test --benches`) nothing is run.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use patchwork::model::PatchSurface;
use patchwork::tessellate::{PatchMesh, Tessellators};

/// Tolerances, as fractions of our bounding-box diagonal.
const REL_TOLERANCES: [f64; 3] = [1e-2, 3e-3, 1e-3];
/// Runs of our tessellation; each face's fastest is kept.
const OUR_RUNS: usize = 3;
const FILES_ENV: &str = "PATCHWORK_OCCT_FACES_FILES";
const FILES: [&str; 5] = [
    "models/corpus/kicad-demo-tinytapeout.step.gz",
    "models/corpus/kicad-demo-video.step.gz",
    "models/corpus/kicad-demo-kit-dev-coldfire-xilinx_5213.step.gz",
    "models/screw.step",
    "models/as1-oc-214.stp",
];

/// Per surface kind: faces, triangles, milliseconds, and (ours) the largest error / ε.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    faces: usize,
    triangles: usize,
    ms: f64,
    ratio: f64,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !args.iter().any(|a| a == "--bench") || args.iter().any(|a| a == "--list") {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files: Vec<PathBuf> = match std::env::var(FILES_ENV) {
        Ok(list) => list.split(',').map(PathBuf::from).collect(),
        Err(_) => FILES.iter().map(|f| root.join(f)).collect(),
    };
    let mut md = String::from(
        "## Trimmed tessellation vs OCCT BRepMesh, per surface kind\n\n\
         ε = tol × our bounding-box diagonal (OCCT: linear deflection ε, angular 0.5 rad). \
         Faces counted once however often placed. ours ms: sum over faces of each face's \
         fastest of 3 runs, one thread; occt ms: one `BRepMesh_IncrementalMesh` call on the \
         whole shape, one thread (not split by kind). err/ε: our largest `PatchMesh::error`.\n\n\
         | file | tol | kind | faces ours/occt | ours tris | occt tris | tris ours/occt \
         | ours ms | occt ms | ours err/ε |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for path in &files {
        if let Err(e) = compare(root, path, &mut md) {
            let _ = writeln!(md, "| {} | error: {e} |", label(path));
        }
    }
    println!("{md}");
    let out = root.join("target/occt_faces.md");
    if let Err(e) = std::fs::write(&out, &md) {
        eprintln!("cannot write {}: {e}", out.display());
    }
}

fn label(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    )
}

/// OCCT reads files itself: a `.gz` is decompressed into `target/occt_faces/` once.
fn plain_file(root: &Path, path: &Path) -> Result<PathBuf, String> {
    if path.extension().is_none_or(|e| e != "gz") {
        return Ok(path.to_path_buf());
    }
    let dir = root.join("target/occt_faces");
    let out = dir.join(path.file_stem().ok_or("no file name")?);
    if out.exists() {
        return Ok(out);
    }
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let data = Command::new("gzip")
        .arg("-dc")
        .arg(path)
        .output()
        .map_err(|e| format!("gzip: {e}"))?;
    if !data.status.success() {
        return Err(format!("gzip -dc {} failed", path.display()));
    }
    let tmp = out.with_extension("part");
    std::fs::write(&tmp, &data.stdout).map_err(|e| e.to_string())?;
    std::fs::rename(&tmp, &out).map_err(|e| e.to_string())?;
    Ok(out)
}

fn compare(root: &Path, path: &Path, md: &mut String) -> Result<(), String> {
    let scene = patchwork::prep::load(path).map_err(|e| e.to_string())?;
    let diag = scene.bbox_diagonal();
    let faces: Vec<_> = {
        let mut seen = std::collections::HashSet::new();
        (scene.patches.iter())
            .filter(|p| matches!(&p.surface, PatchSurface::Trimmed(f) if seen.insert(f.id)))
            .collect()
    };
    let tols: Vec<f64> = REL_TOLERANCES.iter().map(|r| r * diag).collect();
    let occt = occt(root, &plain_file(root, path)?, &tols, diag)?;
    let mut t = Tessellators::new();
    let mut mesh = PatchMesh::default();
    for (&rel, &tol) in REL_TOLERANCES.iter().zip(&tols) {
        let mut ours: BTreeMap<&str, Tally> = BTreeMap::new();
        for p in &faces {
            let PatchSurface::Trimmed(f) = &p.surface else {
                continue;
            };
            let mut ms = f64::INFINITY;
            for _ in 0..OUR_RUNS {
                let t0 = Instant::now();
                t.unplaced(p, tol, &mut mesh);
                ms = ms.min(t0.elapsed().as_secs_f64() * 1e3);
            }
            let k = ours.entry(f.kind()).or_default();
            k.faces += 1;
            k.triangles += mesh.triangles.len();
            k.ms += ms;
            k.ratio = k.ratio.max(mesh.error / tol);
        }
        let (occt_kinds, occt_ms) = occt
            .iter()
            .find(|(t, ..)| (t - tol).abs() <= 1e-9 * tol)
            .map(|(_, k, ms)| (k.clone(), *ms))
            .unwrap_or_default();
        let kinds: std::collections::BTreeSet<&str> = ours
            .keys()
            .copied()
            .chain(occt_kinds.keys().map(String::as_str))
            .collect();
        let mut total = (Tally::default(), Tally::default());
        for k in kinds {
            let a = ours.get(k).copied().unwrap_or_default();
            let b = occt_kinds.get(k).copied().unwrap_or_default();
            row(md, path, rel, k, a, b, None);
            total.0.faces += a.faces;
            total.0.triangles += a.triangles;
            total.0.ms += a.ms;
            total.0.ratio = total.0.ratio.max(a.ratio);
            total.1.faces += b.faces;
            total.1.triangles += b.triangles;
        }
        row(md, path, rel, "**total**", total.0, total.1, Some(occt_ms));
    }
    Ok(())
}

fn row(
    md: &mut String,
    path: &Path,
    rel: f64,
    kind: &str,
    a: Tally,
    b: Tally,
    occt_ms: Option<f64>,
) {
    let ratio = if b.triangles > 0 {
        format!("{:.3}", a.triangles as f64 / b.triangles as f64)
    } else {
        "—".into()
    };
    let occt_ms = occt_ms.map_or("".into(), |ms| format!("{ms:.1}"));
    let _ = writeln!(
        md,
        "| {} | {rel:.0e} | {kind} | {}/{} | {} | {} | {ratio} | {:.1} | {occt_ms} | {:.3} |",
        label(path),
        a.faces,
        b.faces,
        a.triangles,
        b.triangles,
        a.ms,
        a.ratio
    );
}

/// Per tolerance asked: (tolerance, triangles per kind, mesh ms) from `occt_mesh.py --by-kind`.
type OcctRun = (f64, BTreeMap<String, Tally>, f64);

fn occt(root: &Path, file: &Path, tols: &[f64], diag: f64) -> Result<Vec<OcctRun>, String> {
    let venv = std::env::var_os("HOME")
        .map(|h| Path::new(&h).join(".cache/patchwork-occt-venv/bin/python"))
        .filter(|p| p.exists());
    let mut cmd = Command::new(venv.unwrap_or_else(|| "python3".into()));
    cmd.arg(root.join("benches/occt_mesh.py"))
        .arg(file)
        .args(tols.iter().map(f64::to_string))
        .args(["--units", "auto", "--by-kind", "--match-diag"])
        .arg(diag.to_string());
    let out = cmd.output().map_err(|e| format!("occt_mesh.py: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let mut runs: Vec<OcctRun> = Vec::new();
    for line in text.lines() {
        if let Some(e) = field(line, "error") {
            return Err(format!("occt: {e}"));
        }
        let (Some(tool), Some(tol)) = (field(line, "tool"), num(line, "tol")) else {
            continue;
        };
        match tool.trim_matches('"') {
            "occt" => runs.push((
                tol,
                BTreeMap::new(),
                num(line, "mesh_ms").unwrap_or(f64::NAN),
            )),
            "occt-kind" => {
                let (Some(run), Some(k)) = (runs.last_mut(), field(line, "kind")) else {
                    continue;
                };
                let t = run.1.entry(k.trim_matches('"').to_owned()).or_default();
                t.faces += num(line, "faces").unwrap_or(0.0) as usize;
                t.triangles += num(line, "triangles").unwrap_or(0.0) as usize;
            }
            _ => {}
        }
    }
    if runs.is_empty() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(format!(
            "occt_mesh.py printed no result: {}",
            err.lines().last().unwrap_or("")
        ));
    }
    Ok(runs)
}

/// The raw value of `"key": value` in one flat JSON line (strings keep their quotes).
fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!("\"{key}\": ");
    let rest = &line[line.find(&pat)? + pat.len()..];
    let end = if let Some(quoted) = rest.strip_prefix('"') {
        quoted.find('"')? + 2
    } else {
        rest.find([',', '}']).unwrap_or(rest.len())
    };
    Some(&rest[..end])
}

fn num(line: &str, key: &str) -> Option<f64> {
    field(line, key)?.trim().parse().ok()
}
