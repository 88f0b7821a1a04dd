//! `frames.csv` and the summary line of an implosion / explosion (`drive::implode::run`'s records).

use std::path::Path;

use crate::drive::implode::AnimRecord;
use crate::io::png::{self, WriteError};

/// The header of `frames.csv`; one row per frame follows.
pub(crate) const CSV_HEADER: &str = "frame,amount,frame_ms,tessellation_ms,retessellated,triangles,max_error_px,crack_pixels,growth_pixels,growth_max_px";

/// One frame's row (no newline): amount to 4 decimals, times and error to 3; the crack columns
/// are empty when the frame was not checked.
pub fn csv_row(r: &AnimRecord) -> String {
    let (cracks, growth, growth_max) =
        r.cracks
            .map_or((String::new(), String::new(), String::new()), |c| {
                (
                    c.cracks().to_string(),
                    c.growth.to_string(),
                    c.growth_max_px.to_string(),
                )
            });
    format!(
        "{},{:.4},{:.3},{:.3},{},{},{:.3},{cracks},{growth},{growth_max}",
        r.frame,
        r.amount,
        r.frame_ms,
        r.tessellation_ms,
        r.retessellated,
        r.triangles,
        r.max_error_px
    )
}

/// The whole table: header and one line per record, each ending in a newline.
pub fn frames_csv(records: &[AnimRecord]) -> String {
    super::table(CSV_HEADER, records, csv_row)
}

/// Writes [`frames_csv`] to `path` atomically.
pub fn write_frames_csv(path: &Path, records: &[AnimRecord]) -> Result<(), WriteError> {
    png::write_text(path, &frames_csv(records))
}

/// Frame times of a run (`AnimRecord::frame_ms`: frame loop, upload, draw; no PNG writing).
/// All zero for no frames.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameTimes {
    pub frames: usize,
    pub per_second: f64,
    pub mean_ms: f64,
    /// The upper median.
    pub p50_ms: f64,
    pub max_ms: f64,
}

impl FrameTimes {
    pub fn of(records: &[AnimRecord]) -> FrameTimes {
        let mut ms: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
        ms.sort_by(f64::total_cmp);
        let (Some(&p50_ms), Some(&max_ms)) = (ms.get(ms.len() / 2), ms.last()) else {
            return FrameTimes::default();
        };
        let n = records.len() as f64;
        let total_ms: f64 = records.iter().map(|r| r.frame_ms).sum();
        FrameTimes {
            frames: records.len(),
            per_second: 1e3 * n / total_ms.max(1e-9),
            mean_ms: total_ms / n,
            p50_ms,
            max_ms,
        }
    }
}

/// Crack and growth pixels over the checked frames (`AnimOptions::check`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CrackSummary {
    /// Frames that were checked.
    pub checked: usize,
    /// Crack pixels summed over all checked frames.
    pub cracks: usize,
    /// Checked frames with at least one crack pixel.
    pub frames_with_cracks: usize,
    /// Crack pixels of the last checked frame.
    pub last: usize,
    /// Most growth pixels in one frame.
    pub most_growth: usize,
    /// Farthest growth pixel from the reference silhouette, px.
    pub worst_growth_px: u32,
}

impl CrackSummary {
    pub fn of(records: &[AnimRecord]) -> CrackSummary {
        let counts: Vec<_> = records.iter().filter_map(|r| r.cracks).collect();
        CrackSummary {
            checked: counts.len(),
            cracks: counts.iter().map(|c| c.cracks()).sum(),
            frames_with_cracks: counts.iter().filter(|c| c.cracks() > 0).count(),
            last: counts.last().map_or(0, |c| c.cracks()),
            most_growth: counts.iter().map(|c| c.growth).max().unwrap_or(0),
            worst_growth_px: counts.iter().map(|c| c.growth_max_px).max().unwrap_or(0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::crack::CrackCounts;

    fn record(frame: usize, frame_ms: f64, cracks: Option<CrackCounts>) -> AnimRecord {
        AnimRecord {
            frame,
            amount: 1.0 - frame as f64 / 2.0,
            frame_ms,
            tessellation_ms: 0.25,
            retessellated: 3,
            triangles: 1790,
            max_error_px: 0.4567,
            cracks,
            cracks_off: None,
        }
    }

    fn counts(background: usize, growth: usize, growth_max_px: u32) -> CrackCounts {
        CrackCounts {
            inside: 100,
            background,
            behind: 1,
            growth,
            growth_max_px,
        }
    }

    #[test]
    fn csv_has_a_header_and_a_row_per_frame_with_every_column() {
        let records = [
            record(0, 12.3456, Some(counts(2, 5, 3))),
            record(1, 4.0, None),
        ];
        let csv = frames_csv(&records);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], CSV_HEADER);
        assert_eq!(lines[1], "0,1.0000,12.346,0.250,3,1790,0.457,3,5,3");
        assert_eq!(lines[2], "1,0.5000,4.000,0.250,3,1790,0.457,,,");
        let cols = CSV_HEADER.split(',').count();
        assert!(lines.iter().all(|l| l.split(',').count() == cols));
        assert!(csv.ends_with('\n'));
    }

    #[test]
    fn csv_file_is_written_whole() {
        let dir = std::env::temp_dir().join(format!("patchwork-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("frames.csv");
        let records = [record(0, 1.0, None)];
        write_frames_csv(&path, &records).expect("writes");
        assert_eq!(
            std::fs::read_to_string(&path).expect("reads"),
            frames_csv(&records)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn frame_times_and_crack_summary() {
        let records = [
            record(0, 30.0, Some(counts(0, 4, 2))),
            record(1, 10.0, Some(counts(3, 1, 1))),
            record(2, 20.0, Some(counts(0, 0, 0))),
        ];
        let t = FrameTimes::of(&records);
        assert_eq!(
            (t.frames, t.mean_ms, t.p50_ms, t.max_ms),
            (3, 20.0, 20.0, 30.0)
        );
        assert!((t.per_second - 50.0).abs() < 1e-9);
        assert_eq!(FrameTimes::of(&[]), FrameTimes::default());

        // `counts` has one surface-behind pixel per frame.
        let c = CrackSummary::of(&records);
        assert_eq!(
            c,
            CrackSummary {
                checked: 3,
                cracks: 1 + 4 + 1,
                frames_with_cracks: 3,
                last: 1,
                most_growth: 4,
                worst_growth_px: 2,
            }
        );
        assert_eq!(CrackSummary::of(&[record(0, 1.0, None)]).checked, 0);
    }
}
