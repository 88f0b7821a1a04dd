//! The per-frame table and the frame-rate-target figures of `bench --flythrough`
//! (`drive::flythrough::run`'s records): CSV rows and the plot.

use crate::drive::flythrough::FrameRecord;

/// Columns of the per-frame table.
pub const CSV_HEADER: &str = "frame,frame_ms,tessellation_ms,retessellated,from_cache,queue_length,max_error_px,p99_error_px,triangles,pixel_error,crack_pixels,crack_pixels_off,upload_ms,draw_ms,cpu_ms,uploaded_bytes";

/// One frame's row, columns as [`CSV_HEADER`].
pub fn csv_row(r: &FrameRecord) -> String {
    format!(
        "{},{:.3},{:.3},{},{},{},{:.4},{:.4},{},{:.4},{},{},{:.3},{:.3},{:.3},{}",
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
        r.uploaded_bytes
    )
}

/// Header ([`CSV_HEADER`]) and one line per record, each ending in a newline.
pub fn frames_csv(records: &[FrameRecord]) -> String {
    super::table(CSV_HEADER, records, csv_row)
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
    let (w, h) = (900u32, 520u32);
    let mut img = image::RgbaImage::from_pixel(w, h, image::Rgba([255, 255, 255, 255]));
    let n = records.len().max(2);
    let panel = |top: u32| (top + 10, top + 240);
    let (err_top, err_bottom) = panel(0);
    let (time_top, time_bottom) = panel(260);
    let x_of = |i: usize| 40.0 + (w as f64 - 60.0) * i as f64 / (n - 1) as f64;
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
            line(&mut img, (40.0, y), (w as f64 - 20.0, y), grey);
        }
        line(
            &mut img,
            (40.0, top as f64),
            (40.0, bottom as f64),
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
    img
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
        }
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
