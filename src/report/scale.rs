//! The table of `bench --scale` ([`crate::drive::scale::ScalePoint`]s): CSV rows (also the
//! line a child process hands its point back on, so [`parse_row`] reads what [`csv_row`]
//! writes) and a Markdown table with memory per patch.

use crate::drive::scale::ScalePoint;

/// Columns of the CSV table (times in ms, memory in bytes; an empty cell = not measured).
pub(crate) const CSV_HEADER: &str = "model,patches,load_ms,first_frame_ms,tessellate_ms,upload_ms,frame_p50_ms,frame_max_ms,retessellate_ms,cpu_ms,uploaded_bytes,frames,jump_frame,converge_frames,triangles_first,triangles_last,scene_bytes,lod_bytes_first,lod_bytes_last,rss_start_bytes,rss_load_bytes,rss_tessellate_bytes,peak_rss_bytes,failure";

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// Text for a cell: commas, quotes and line breaks replaced by `_`, so rows split on commas.
fn clean(s: &str) -> String {
    s.chars()
        .map(|c| {
            if matches!(c, ',' | '"' | '\n' | '\r') {
                '_'
            } else {
                c
            }
        })
        .collect()
}

/// One point's row, columns as `CSV_HEADER` (the model's name and the failure through
/// `clean`).
pub fn csv_row(p: &ScalePoint) -> String {
    let model: String = p
        .model
        .chars()
        .map(|c| {
            if matches!(c, ',' | '"' | '\n') {
                '_'
            } else {
                c
            }
        })
        .collect();
    format!(
        "{model},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        p.patches,
        p.load_ms,
        p.first_frame_ms,
        p.tessellate_ms,
        p.upload_ms,
        p.frame_p50_ms,
        p.frame_max_ms,
        p.retessellate_ms,
        opt(p.cpu_ms.map(|c| format!("{c:.3}"))),
        opt(p.uploaded_bytes),
        p.frames,
        p.jump_frame,
        opt(p.converge_frames),
        p.triangles_first,
        p.triangles_last,
        p.scene_bytes,
        p.lod_bytes_first,
        p.lod_bytes_last,
        opt(p.rss_start_bytes),
        opt(p.rss_load_bytes),
        opt(p.rss_tessellate_bytes),
        opt(p.peak_rss_bytes),
        p.failure.as_deref().map_or(String::new(), clean),
    )
}

/// Header and one line per point.
pub fn csv(points: &[ScalePoint]) -> String {
    super::table(CSV_HEADER, points, csv_row)
}

/// Reads a row written by [`csv_row`] (times as written, rounded to µs).
pub fn parse_row(line: &str) -> Result<ScalePoint, String> {
    let cells: Vec<&str> = line.trim_end().split(',').collect();
    let want = CSV_HEADER.split(',').count();
    if cells.len() != want {
        return Err(format!("{} cells, expected {want}: {line:?}", cells.len()));
    }
    let names: Vec<&str> = CSV_HEADER.split(',').collect();
    let num = |k: usize| -> Result<f64, String> {
        cells[k]
            .parse()
            .map_err(|_| format!("{}: not a number: {:?}", names[k], cells[k]))
    };
    let int = |k: usize| -> Result<u64, String> {
        cells[k]
            .parse()
            .map_err(|_| format!("{}: not a count: {:?}", names[k], cells[k]))
    };
    let opt_int = |k: usize| (!cells[k].is_empty()).then(|| int(k)).transpose();
    Ok(ScalePoint {
        model: cells[0].to_owned(),
        patches: int(1)? as usize,
        load_ms: num(2)?,
        first_frame_ms: num(3)?,
        tessellate_ms: num(4)?,
        upload_ms: num(5)?,
        frame_p50_ms: num(6)?,
        frame_max_ms: num(7)?,
        retessellate_ms: num(8)?,
        cpu_ms: (!cells[9].is_empty()).then(|| num(9)).transpose()?,
        uploaded_bytes: opt_int(10)?,
        frames: int(11)? as usize,
        jump_frame: int(12)? as usize,
        converge_frames: opt_int(13)?.map(|c| c as usize),
        triangles_first: int(14)? as usize,
        triangles_last: int(15)? as usize,
        scene_bytes: int(16)? as usize,
        lod_bytes_first: int(17)? as usize,
        lod_bytes_last: int(18)? as usize,
        rss_start_bytes: opt_int(19)?,
        rss_load_bytes: opt_int(20)?,
        rss_tessellate_bytes: opt_int(21)?,
        peak_rss_bytes: opt_int(22)?,
        failure: (!cells[23].is_empty()).then(|| cells[23].to_owned()),
    })
}

const MB: f64 = 1024.0 * 1024.0;

/// A Markdown table of the points: load and first-frame times, frame times, convergence after
/// the jump, triangles, and memory (resident sizes in MiB; per patch: the scene's and the
/// frame loop's own accounting, and the resident peak above the process's size before
/// loading).
pub fn markdown(points: &[ScalePoint]) -> String {
    let mut s = String::from(
        "| model | patches | load s | first frame s | frame p50 ms | CPU ms/frame | uploaded MB/frame | converge frames | triangles (last) | scene B/patch | LOD B/patch (first → last) | RSS start MiB | RSS peak after load / first tessellation MiB | RSS peak MiB | (peak − start) B/patch |\n\
         |---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    let mut failures = String::new();
    for p in points {
        if let Some(f) = &p.failure {
            failures.push_str(&format!(
                "\n{}: stopped after the first tessellation: {f}\n",
                p.model
            ));
        }
        let per = |b: f64| b / p.patches.max(1) as f64;
        let mib = |b: Option<u64>| b.map_or("—".to_owned(), |b| format!("{:.0}", b as f64 / MB));
        // A point that stopped before drawing has no frame figures.
        let drawn = |f: String| {
            if p.failure.is_some() {
                "—".to_owned()
            } else {
                f
            }
        };
        let converge = drawn(match p.converge_frames {
            Some(c) => c.to_string(),
            None => format!("> {}", p.frames - p.jump_frame),
        });
        let after_load = format!(
            "{} / {}",
            mib(p.rss_load_bytes),
            mib(p.rss_tessellate_bytes)
        );
        s.push_str(&format!(
            "| {} | {} | {:.2} | {} | {} | {} | {} | {} | {} | {:.0} | {:.0} → {:.0} | {} | {} | {} | {} |\n",
            p.model,
            p.patches,
            p.load_ms / 1e3,
            drawn(format!("{:.2}", p.first_frame_ms / 1e3)),
            drawn(format!("{:.1}", p.frame_p50_ms)),
            p.cpu_ms.map_or("—".to_owned(), |c| format!("{c:.1}")),
            p.uploaded_bytes
                .map_or("—".to_owned(), |b| format!("{:.1}", b as f64 / MB)),
            converge,
            drawn(p.triangles_last.to_string()),
            per(p.scene_bytes as f64),
            per(p.lod_bytes_first as f64),
            per(p.lod_bytes_last as f64),
            mib(p.rss_start_bytes),
            after_load,
            mib(p.peak_rss_bytes),
            match (p.peak_rss_bytes, p.rss_start_bytes) {
                (Some(peak), Some(start)) => format!("{:.0}", per(peak.saturating_sub(start) as f64)),
                _ => "—".to_owned(),
            },
        ));
    }
    s + &failures
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point() -> ScalePoint {
        ScalePoint {
            model: "teapots 2x2".into(),
            patches: 128,
            load_ms: 1500.0,
            first_frame_ms: 20.25,
            tessellate_ms: 3.0,
            upload_ms: 4.0,
            frame_p50_ms: 5.5,
            frame_max_ms: 9.0,
            retessellate_ms: 0.5,
            cpu_ms: None,
            uploaded_bytes: Some(1 << 20),
            frames: 20,
            jump_frame: 13,
            converge_frames: Some(2),
            triangles_first: 1000,
            triangles_last: 3000,
            scene_bytes: 100_000,
            lod_bytes_first: 50_000,
            lod_bytes_last: 70_000,
            rss_start_bytes: Some(16 << 20),
            rss_load_bytes: Some(40 << 20),
            rss_tessellate_bytes: Some(50 << 20),
            peak_rss_bytes: Some(80 << 20),
            failure: None,
        }
    }

    #[test]
    fn rows_read_back_as_written() {
        let p = point();
        assert_eq!(parse_row(&csv_row(&p)), Ok(p.clone()));
        let never = ScalePoint {
            converge_frames: None,
            peak_rss_bytes: None,
            cpu_ms: Some(2.25),
            model: "a,b.step".into(),
            failure: Some("Buffer size 3 is greater than 2, really".into()),
            ..p
        };
        let back = parse_row(&csv_row(&never)).expect("row");
        assert_eq!(back.model, "a_b.step");
        assert_eq!(back.converge_frames, None);
        assert_eq!(back.cpu_ms, Some(2.25));
        assert_eq!(
            back.failure.as_deref(),
            Some("Buffer size 3 is greater than 2_ really")
        );
        assert!(parse_row("x,1,2").is_err());
        let header_cells = CSV_HEADER.split(',').count();
        assert_eq!(csv_row(&never).split(',').count(), header_cells);
    }

    #[test]
    fn the_markdown_table_shows_per_patch_memory_and_unmeasured_cells() {
        let t = markdown(&[point()]);
        let row = t.lines().nth(2).expect("a row");
        // (80 − 16) MiB over 128 patches; 100 000 B of scene over 128 patches ≈ 781.
        assert!(row.contains("| 524288 |"), "{row}");
        assert!(row.contains("| 781 |"), "{row}");
        assert!(row.contains("| — |"), "{row}");
        let never = markdown(&[ScalePoint {
            converge_frames: None,
            ..point()
        }]);
        assert!(never.contains("| > 7 |"), "{never}");
        let failed = markdown(&[ScalePoint {
            failure: Some("too big".into()),
            ..point()
        }]);
        assert!(failed.contains("| 1.50 | — | — |"), "{failed}");
        assert!(failed.ends_with("teapots 2x2: stopped after the first tessellation: too big\n"));
    }
}
