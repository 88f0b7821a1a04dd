//! Golden images compared with FLIP (nv-flip): mean and 99th-percentile error thresholds.
//!
//! On a mismatch `NAME-actual.png` and `NAME-diff.png` (the FLIP error map, magma colours) are
//! written next to the golden. Goldens are (re)written only when `GOLDEN_UPDATE=1`.

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::io::png::{WriteError, write_rgba};

/// FLIP statistics of a test image against its reference (0 = identical, 1 = opposite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipScore {
    pub mean: f32,
    pub p99: f32,
    pub max: f32,
}

/// Largest FLIP scores accepted as "the same picture". FACTS: MSAA vs no MSAA 0.002–0.005
/// mean, a 2 px shift 0.056; so 0.02 mean catches a shift or a missing patch while allowing
/// rasterizer differences between Mesa versions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    pub mean: f32,
    pub p99: f32,
}

impl Default for Thresholds {
    fn default() -> Self {
        Thresholds {
            mean: 0.02,
            p99: 0.5,
        }
    }
}

#[derive(Debug, Error)]
pub enum GoldenError {
    #[error(
        "{}: golden image missing; render it with GOLDEN_UPDATE=1 (and say why in the commit)",
        .0.display()
    )]
    Missing(PathBuf),
    #[error("{}: cannot read golden image: {reason}", .path.display())]
    Unreadable { path: PathBuf, reason: String },
    #[error("{}: golden is {golden:?}, actual image is {actual:?}", .path.display())]
    SizeMismatch {
        path: PathBuf,
        golden: (u32, u32),
        actual: (u32, u32),
    },
    #[error(
        "{}: FLIP mean {:.4} (max {:.4}), p99 {:.4} (max {:.4}); wrote {} and {}",
        .path.display(), .score.mean, .limits.mean, .score.p99, .limits.p99,
        .actual.display(), .diff.display()
    )]
    Mismatch {
        path: PathBuf,
        score: FlipScore,
        limits: Thresholds,
        actual: PathBuf,
        diff: PathBuf,
    },
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// What [`compare_with_golden`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GoldenOutcome {
    Matched(FlipScore),
    /// `GOLDEN_UPDATE=1`: the golden was (re)written from the actual image.
    Updated,
}

fn to_flip(img: &image::RgbaImage) -> nv_flip::FlipImageRgb8 {
    let rgb: Vec<u8> = img.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect();
    nv_flip::FlipImageRgb8::with_data(img.width(), img.height(), &rgb)
}

/// FLIP error of `test` against `reference` (same size), with the error map as an image.
pub fn flip_score(
    reference: &image::RgbaImage,
    test: &image::RgbaImage,
) -> (FlipScore, image::RgbaImage) {
    let map = nv_flip::flip(
        to_flip(reference),
        to_flip(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let mut pool = nv_flip::FlipPool::from_image(&map);
    let score = FlipScore {
        mean: pool.mean(),
        p99: pool.get_percentile(0.99, false),
        max: pool.max_value(),
    };
    let colour = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let rgba: Vec<u8> = colour
        .chunks_exact(3)
        .flat_map(|c| [c[0], c[1], c[2], 255])
        .collect();
    let diff = image::RgbaImage::from_raw(reference.width(), reference.height(), rgba)
        .unwrap_or_else(|| image::RgbaImage::new(reference.width(), reference.height()));
    (score, diff)
}

/// Whether `GOLDEN_UPDATE=1` is set.
pub fn update_requested() -> bool {
    std::env::var("GOLDEN_UPDATE").is_ok_and(|v| v == "1")
}

/// `dir/NAME-actual.png` style sibling of a golden path.
pub fn sibling(golden: &Path, suffix: &str) -> PathBuf {
    let stem = golden
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    golden.with_file_name(format!("{stem}-{suffix}.png"))
}

/// Compares `actual` with the golden at `golden` (or rewrites it under `GOLDEN_UPDATE=1`).
pub fn compare_with_golden(
    golden: &Path,
    actual: &image::RgbaImage,
    limits: Thresholds,
) -> Result<GoldenOutcome, GoldenError> {
    if update_requested() {
        write_rgba(golden, actual)?;
        return Ok(GoldenOutcome::Updated);
    }
    if !golden.exists() {
        return Err(GoldenError::Missing(golden.to_owned()));
    }
    let reference = image::open(golden)
        .map_err(|e| GoldenError::Unreadable {
            path: golden.to_owned(),
            reason: e.to_string(),
        })?
        .to_rgba8();
    if reference.dimensions() != actual.dimensions() {
        return Err(GoldenError::SizeMismatch {
            path: golden.to_owned(),
            golden: reference.dimensions(),
            actual: actual.dimensions(),
        });
    }
    let (score, diff) = flip_score(&reference, actual);
    let (actual_path, diff_path) = (sibling(golden, "actual"), sibling(golden, "diff"));
    if score.mean > limits.mean || score.p99 > limits.p99 {
        write_rgba(&actual_path, actual)?;
        write_rgba(&diff_path, &diff)?;
        return Err(GoldenError::Mismatch {
            path: golden.to_owned(),
            score,
            limits,
            actual: actual_path,
            diff: diff_path,
        });
    }
    // A passing comparison clears stale failure images.
    let _ = std::fs::remove_file(&actual_path);
    let _ = std::fs::remove_file(&diff_path);
    Ok(GoldenOutcome::Matched(score))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_score_zero_and_shifted_ones_do_not() {
        let mut a = image::RgbaImage::from_pixel(64, 48, image::Rgba([255, 255, 255, 255]));
        for y in 10..30 {
            for x in 10..40 {
                a.put_pixel(x, y, image::Rgba([40, 60, 200, 255]));
            }
        }
        let (same, _) = flip_score(&a, &a);
        assert_eq!(same.mean, 0.0);
        let mut b = image::RgbaImage::from_pixel(64, 48, image::Rgba([255, 255, 255, 255]));
        for y in 10..30 {
            for x in 14..44 {
                b.put_pixel(x, y, image::Rgba([40, 60, 200, 255]));
            }
        }
        let (moved, diff) = flip_score(&a, &b);
        assert!(moved.mean > Thresholds::default().mean, "{moved:?}");
        assert_eq!(diff.dimensions(), (64, 48));
    }
}
