//! The per-frame table and the frame-rate-target figures of `bench --flythrough`
//! (`drive::flythrough::run`'s records): CSV rows and the plot.

use super::text::{draw_text, text_height, text_width};
use crate::drive::flythrough::FrameRecord;

/// Columns of the per-frame table.
pub(crate) const CSV_HEADER: &str = "frame,frame_ms,tessellation_ms,retessellated,from_cache,queue_length,max_error_px,p99_error_px,triangles,pixel_error,crack_pixels,crack_pixels_off,upload_ms,draw_ms,cpu_ms,uploaded_bytes,trimmed_waiting,made,made_cpu_ms,made_triangles,redone,redone_cpu_ms,reused";

/// One frame's row, columns as `CSV_HEADER`.
pub fn csv_row(r: &FrameRecord) -> String {
    format!(
        "{},{:.3},{:.3},{},{},{},{:.4},{:.4},{},{:.4},{},{},{:.3},{:.3},{:.3},{},{},{},{:.3},{},{},{:.3},{}",
        r.frame,
        r.frame_ms,
        r.tessellation_ms,
        r.retessellated,
        r.from_cache,
        r.queue_left,
        r.max_error_px,
        r.p99_error_px,
        r.triangles,
        r.pixel_error,
        r.crack_pixels.map_or(String::new(), |c| c.to_string()),
        r.crack_pixels_off.map_or(String::new(), |c| c.to_string()),
        r.upload_ms,
        r.draw_ms,
        r.cpu_ms,
        r.uploaded_bytes,
        r.trimmed_waiting,
        r.made,
        r.made_cpu_ms,
        r.made_triangles,
        r.redone,
        r.redone_cpu_ms,
        r.reused
    )
}

/// Header (`CSV_HEADER`) and one line per record, each ending in a newline.
pub fn frames_csv(records: &[FrameRecord]) -> String {
    super::table(CSV_HEADER, records, csv_row)
}

/// The frames from the jump (`jump_frame`, at most `rows` of them) as a text table: trimmed
/// faces still waiting, tessellations made, worker ms and triangles per tessellation, how
/// many (and what share of the worker time) were redone work, and the largest and 99th
/// percentile screen error (pixels).
pub fn jump_table(records: &[FrameRecord], jump_frame: usize, rows: usize) -> String {
    let mut t = String::from(
        "frame  waiting  made  ms/face  tris/face  redone  redone_time  reused  max_px  p99_px\n",
    );
    for r in records.iter().filter(|r| r.frame >= jump_frame).take(rows) {
        let per = |x: f64| if r.made > 0 { x / r.made as f64 } else { 0.0 };
        let share = if r.made_cpu_ms > 0.0 {
            100.0 * r.redone_cpu_ms / r.made_cpu_ms
        } else {
            0.0
        };
        t.push_str(&format!(
            "+{:<5} {:>7} {:>5} {:>8.3} {:>10.0} {:>7} {:>11.0}% {:>7} {:>7.3} {:>7.3}\n",
            r.frame - jump_frame,
            r.trimmed_waiting,
            r.made,
            per(r.made_cpu_ms),
            per(r.made_triangles as f64),
            r.redone,
            share,
            r.reused,
            r.max_error_px,
            r.p99_error_px
        ));
    }
    t
}

/// How a frame-rate target was met: mean frame time over all frames, and over the second half
/// (after the controller settled) with the pixel error it chose there on average.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetSummary {
    pub mean_ms: f64,
    pub tail_mean_ms: f64,
    pub tail_pixel_error: f64,
}

impl TargetSummary {
    /// `None` for no frames.
    pub fn of(records: &[FrameRecord]) -> Option<TargetSummary> {
        if records.is_empty() {
            return None;
        }
        let mean = |rs: &[FrameRecord], f: fn(&FrameRecord) -> f64| {
            rs.iter().map(f).sum::<f64>() / rs.len() as f64
        };
        let tail = &records[records.len() / 2..];
        Some(TargetSummary {
            mean_ms: mean(records, |r| r.frame_ms),
            tail_mean_ms: mean(tail, |r| r.frame_ms),
            tail_pixel_error: mean(tail, |r| r.pixel_error),
        })
    }
}

/// A plot of the run: top, screen error (max red, p99 orange, pixel error asked grey);
/// bottom, frame time (blue) and re-tessellation time (green) with the budget (grey); the
/// jump as a vertical black line. Scales: error 0..max(4 × pixel error, largest error), time
/// 0..max(2 × budget, longest frame), both linear, marked by grid lines every quarter.
pub fn plot(records: &[FrameRecord], budget_ms: f64, jump_frame: usize) -> image::RgbaImage {
    let (w, h) = (900u32, 560u32);
    let mut img = image::RgbaImage::from_pixel(w, h, image::Rgba([255, 255, 255, 255]));
    let n = records.len().max(2);
    // Each panel: a title line with the legend above it, the plot below.
    let panel = |top: u32| (top + 26, top + 256);
    let (err_top, err_bottom) = panel(0);
    let (time_top, time_bottom) = panel(262);
    let left = 56.0;
    let x_of = |i: usize| left + (w as f64 - left - 20.0) * i as f64 / (n - 1) as f64;
    let pe = records.iter().map(|r| r.pixel_error).fold(0.0, f64::max);
    let err_max = records
        .iter()
        .map(|r| r.max_error_px)
        .fold(4.0 * pe, f64::max)
        .max(1e-9);
    let time_max = records
        .iter()
        .map(|r| r.frame_ms)
        .fold(2.0 * budget_ms, f64::max)
        .max(1e-9);
    let y_in = |v: f64, max: f64, top: u32, bottom: u32| {
        bottom as f64 - (bottom - top) as f64 * (v / max).clamp(0.0, 1.0)
    };
    let grey = image::Rgba([200, 200, 200, 255]);
    for (top, bottom) in [(err_top, err_bottom), (time_top, time_bottom)] {
        for q in 0..=4 {
            let y = top as f64 + (bottom - top) as f64 * q as f64 / 4.0;
            line(&mut img, (left, y), (w as f64 - 20.0, y), grey);
        }
        line(
            &mut img,
            (left, top as f64),
            (left, bottom as f64),
            image::Rgba([0, 0, 0, 255]),
        );
    }
    let series = |img: &mut image::RgbaImage,
                  f: &dyn Fn(&FrameRecord) -> f64,
                  max: f64,
                  (top, bottom): (u32, u32),
                  color: [u8; 3]| {
        for pair in records.windows(2) {
            let a = (x_of(pair[0].frame), y_in(f(&pair[0]), max, top, bottom));
            let b = (x_of(pair[1].frame), y_in(f(&pair[1]), max, top, bottom));
            line(img, a, b, image::Rgba([color[0], color[1], color[2], 255]));
        }
    };
    let dark = [110, 110, 110];
    series(
        &mut img,
        &|r| r.pixel_error,
        err_max,
        (err_top, err_bottom),
        dark,
    );
    series(
        &mut img,
        &|r| r.p99_error_px,
        err_max,
        (err_top, err_bottom),
        [255, 150, 0],
    );
    series(
        &mut img,
        &|r| r.max_error_px,
        err_max,
        (err_top, err_bottom),
        [220, 0, 0],
    );
    series(
        &mut img,
        &|_| budget_ms,
        time_max,
        (time_top, time_bottom),
        dark,
    );
    series(
        &mut img,
        &|r| r.tessellation_ms,
        time_max,
        (time_top, time_bottom),
        [0, 160, 0],
    );
    series(
        &mut img,
        &|r| r.frame_ms,
        time_max,
        (time_top, time_bottom),
        [0, 70, 220],
    );
    let x = x_of(jump_frame);
    line(
        &mut img,
        (x, err_top as f64),
        (x, time_bottom as f64),
        image::Rgba([0, 0, 0, 255]),
    );
    let black = image::Rgba([0, 0, 0, 255]);
    draw_text(
        &mut img,
        (x as i64 + 4, err_top as i64 + 4),
        "JUMP",
        2,
        black,
    );
    label_panel(
        &mut img,
        (err_top, err_bottom),
        err_max,
        "SCREEN ERROR (PX)",
        &[
            ([220, 0, 0], "MAX"),
            ([255, 150, 0], "P99"),
            (dark, "ASKED"),
        ],
    );
    label_panel(
        &mut img,
        (time_top, time_bottom),
        time_max,
        "TIME PER FRAME (MS)",
        &[
            ([0, 70, 220], "FRAME"),
            ([0, 160, 0], "RE-TESSELLATION"),
            (dark, "BUDGET"),
        ],
    );
    // The frame axis under the lower panel.
    let below = time_bottom as i64 + 6;
    for q in 0..=4 {
        let frame = (n - 1) * q / 4;
        let t = frame.to_string();
        let tx = x_of(frame) as i64 - i64::from(text_width(&t, 2)) / 2;
        draw_text(&mut img, (tx, below), &t, 2, black);
    }
    let name = "FRAME";
    let nx = i64::from(w) - 20 - i64::from(text_width(name, 2));
    draw_text(&mut img, (nx, below + 14), name, 2, black);
    img
}

/// A panel's title and legend (a colour swatch before each series' name) above it, and the
/// values of its five grid lines at the left.
fn label_panel(
    img: &mut image::RgbaImage,
    (top, bottom): (u32, u32),
    max: f64,
    title: &str,
    legend: &[([u8; 3], &str)],
) {
    let black = image::Rgba([0, 0, 0, 255]);
    let y = top as i64 - 18;
    draw_text(img, (56, y), title, 2, black);
    let mut x = 56 + i64::from(text_width(title, 2)) + 24;
    for (color, name) in legend {
        let c = image::Rgba([color[0], color[1], color[2], 255]);
        for dy in 3..6 {
            line(
                img,
                (x as f64, (y + dy) as f64),
                ((x + 16) as f64, (y + dy) as f64),
                c,
            );
        }
        draw_text(img, (x + 22, y), name, 2, black);
        x += 22 + i64::from(text_width(name, 2)) + 20;
    }
    for q in 0..=4 {
        let v = max * (4 - q) as f64 / 4.0;
        let t = tick(v);
        let ty = top as i64 + (bottom - top) as i64 * q / 4 - i64::from(text_height(2)) / 2;
        draw_text(img, (52 - i64::from(text_width(&t, 2)), ty), &t, 2, black);
    }
}

/// A grid value in at most 4 characters where it can be (`0`, `0.25`, `12.5`, `480`, `1e4`).
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    for decimals in (0..=2).rev() {
        let t = format!("{v:.decimals$}");
        let t = if decimals > 0 {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        };
        if t.len() <= 4 && (t.parse::<f64>().unwrap_or(f64::NAN) - v).abs() <= 0.05 * v.abs() {
            return t;
        }
    }
    format!("{v:.0e}")
}

/// A 1-px line (DDA), clipped to the image.
fn line(img: &mut image::RgbaImage, a: (f64, f64), b: (f64, f64), c: image::Rgba<u8>) {
    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
            img.put_pixel(x as u32, y as u32, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_rows_have_every_column() {
        let cols = CSV_HEADER.split(',').count();
        let row = csv_row(&FrameRecord {
            crack_pixels: Some(0),
            ..record(3, 1.0, 0.2)
        });
        assert_eq!(row.split(',').count(), cols);
        assert!(row.starts_with("3,1.000,"));
        // The upload columns, by name.
        let at = |name: &str| {
            let k = CSV_HEADER
                .split(',')
                .position(|c| c == name)
                .unwrap_or_else(|| panic!("no column {name}"));
            row.split(',').nth(k).unwrap_or_default().to_owned()
        };
        assert_eq!(at("upload_ms"), "0.250");
        assert_eq!(at("draw_ms"), "0.750");
        assert_eq!(at("cpu_ms"), "0.900");
        assert_eq!(at("uploaded_bytes"), "123456");
    }

    /// The plot names its panels, units and series, and labels its grid and frame axis: there
    /// is black ink in the title rows, at the left of the grid lines and under the lower
    /// panel, and each legend colour appears in the legend row.
    #[test]
    fn plot_has_titles_legends_and_tick_labels() {
        let records: Vec<FrameRecord> = (0..30).map(|i| record(i, 20.0 + i as f64, 0.5)).collect();
        let img = plot(&records, 40.0, 10);
        let black = image::Rgba([0, 0, 0, 255]);
        let ink_in = |x0: u32, x1: u32, y0: u32, y1: u32| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y) == &black)
                .count()
        };
        // The titles, exactly: every ink pixel of the text drawn alone is black in the plot.
        for (text, y) in [("SCREEN ERROR (PX)", 8), ("TIME PER FRAME (MS)", 270)] {
            let mut alone = image::RgbaImage::from_pixel(900, 560, image::Rgba([255; 4]));
            draw_text(&mut alone, (56, y), text, 2, black);
            let missing = (alone.enumerate_pixels())
                .filter(|(x, y, p)| **p == black && img.get_pixel(*x, *y) != &black)
                .count();
            assert_eq!(missing, 0, "title {text:?}");
        }
        assert!(
            ink_in(0, 54, 20, 290) > 30,
            "grid values of the upper panel"
        );
        assert!(ink_in(0, 900, 524, 556) > 30, "frame numbers and axis name");
        for colour in [[220, 0, 0], [255, 150, 0], [0, 70, 220], [0, 160, 0]] {
            let c = image::Rgba([colour[0], colour[1], colour[2], 255]);
            let in_legends = (0..900u32)
                .flat_map(|x| [(x, 11u32), (x, 273u32)])
                .any(|(x, y)| img.get_pixel(x, y) == &c);
            assert!(in_legends, "legend swatch {colour:?}");
        }
    }

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(480.0), "480");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(12345.0), "1e4");
    }

    fn record(frame: usize, frame_ms: f64, pixel_error: f64) -> FrameRecord {
        FrameRecord {
            frame,
            frame_ms,
            tessellation_ms: 0.5,
            upload_ms: 0.25,
            draw_ms: 0.75,
            cpu_ms: 0.9,
            uploaded_bytes: 123_456,
            retessellated: 1,
            from_cache: 0,
            queue_left: 0,
            max_error_px: 0.4,
            p99_error_px: 0.3,
            triangles: 100,
            pixel_error,
            crack_pixels: Some(0),
            crack_pixels_off: None,
            ..FrameRecord::default()
        }
    }

    #[test]
    fn the_jump_table_shows_the_work_per_frame_from_the_jump() {
        let mut r = [
            record(0, 10.0, 0.5),
            record(1, 10.0, 0.5),
            record(2, 10.0, 0.5),
            record(3, 10.0, 0.5),
        ];
        r[1].trimmed_waiting = 120;
        r[1].made = 40;
        r[1].made_cpu_ms = 80.0;
        r[1].made_triangles = 4000;
        r[1].redone = 10;
        r[1].redone_cpu_ms = 20.0;
        r[1].reused = 7;
        r[1].max_error_px = 1.25;
        let t = jump_table(&r, 1, 2);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.len(), 3, "{t}");
        assert!(lines[0].starts_with("frame"), "{t}");
        // Frame 1: 120 waiting, 40 made at 2 ms and 100 triangles each, a quarter redone.
        let cols: Vec<&str> = lines[1].split_whitespace().collect();
        assert_eq!(
            cols,
            [
                "+0", "120", "40", "2.000", "100", "10", "25%", "7", "1.250", "0.300"
            ],
            "{t}"
        );
        assert!(lines[2].starts_with("+1"), "{t}");
    }

    #[test]
    fn csv_has_the_header_and_a_row_per_frame() {
        let records = [record(0, 10.0, 0.5), record(1, 20.0, 1.0)];
        let csv = frames_csv(&records);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines,
            [CSV_HEADER, &csv_row(&records[0]), &csv_row(&records[1])]
        );
        assert!(csv.ends_with('\n'));
    }

    #[test]
    fn target_summary_averages_the_second_half() {
        let records = [
            record(0, 40.0, 0.5),
            record(1, 20.0, 1.0),
            record(2, 10.0, 2.0),
            record(3, 10.0, 4.0),
        ];
        let t = TargetSummary::of(&records).expect("frames");
        assert_eq!(t.mean_ms, 20.0);
        assert_eq!(t.tail_mean_ms, 10.0);
        assert_eq!(t.tail_pixel_error, 3.0);
        assert_eq!(TargetSummary::of(&[]), None);
    }
}
