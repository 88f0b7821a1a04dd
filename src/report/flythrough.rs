//! The per-frame table and the frame-rate-target figures of `bench --flythrough`
//! (`lod::flythrough::run`'s records; the row format is [`FrameRecord::csv_row`]).

use crate::lod::flythrough::FrameRecord;

/// Header ([`FrameRecord::CSV_HEADER`]) and one line per record, each ending in a newline.
pub fn frames_csv(records: &[FrameRecord]) -> String {
    let mut csv = String::from(FrameRecord::CSV_HEADER);
    csv.push('\n');
    for r in records {
        csv.push_str(&r.csv_row());
        csv.push('\n');
    }
    csv
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

#[cfg(test)]
mod tests {
    use super::*;

    fn record(frame: usize, frame_ms: f64, pixel_error: f64) -> FrameRecord {
        FrameRecord {
            frame,
            frame_ms,
            tessellation_ms: 0.5,
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
            [
                FrameRecord::CSV_HEADER,
                &records[0].csv_row(),
                &records[1].csv_row()
            ]
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
