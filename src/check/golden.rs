//! Golden images compared with FLIP (nv-flip): mean and 99th-percentile error thresholds;
//! patch-ID goldens compared patch by patch; fat-border shading measured against a watertight
//! reference.
//!
//! On a mismatch `NAME-actual.png` and `NAME-diff.png` (the FLIP error map, magma colours) are
//! written next to the golden. Goldens are (re)written only when `GOLDEN_UPDATE=1`.
//!
//! FLIP averages over the image, so a missing small patch, a 1 px shift or a coarser
//! tessellation hide under its thresholds. [`IdImage`] goldens (`NAME-ids.png`, patch ID + 1 in
//! RGB) see them: [`compare_ids`] reports per patch its pixel count, bounding box and centroid
//! against the golden's, the pixels whose ID differs, and the background pixels that opened
//! inside the golden's silhouette (holes: cracks of fat borders that are off), each against
//! an [`IdThresholds`] limit.
//!
//! [`border_shading`] measures the fat borders' own cost (Balázs et al. 2004, §3: a fat border
//! covers a crack with the border's colour and may stick out of the silhouette by ε): FLIP of
//! the lit image against the crack check's watertight reference (`crack::reference_meshes`,
//! no fat borders), with fat borders on and off, and how far the silhouette grew (px).

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::io::png::{WriteError, write_rgba};
use crate::model::Scene;
use crate::render::{FatBorders, Frame, RenderError, RenderOptions, Renderer, Shading};
use crate::view::View;

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
    #[error(
        "{}: patch IDs differ from the golden: {report}; wrote {} and {}",
        .path.display(), .actual.display(), .diff.display()
    )]
    IdMismatch {
        path: PathBuf,
        report: String,
        comparison: Box<IdComparison>,
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

/// A patch-ID image: patch ID + 1 per pixel, 0 where nothing was drawn (as
/// [`Frame::ids`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IdImage {
    pub width: u32,
    pub height: u32,
    pub ids: Vec<u32>,
}

/// Where one patch shows in an [`IdImage`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    pub pixels: usize,
    /// Inclusive pixel bounds: min x, min y, max x, max y.
    pub bbox: [u32; 4],
    /// Mean pixel centre (x, y).
    pub centroid: [f64; 2],
}

impl IdImage {
    /// The ID buffer of a frame rendered with [`RenderOptions::ids`].
    pub fn from_frame(frame: &Frame) -> Option<IdImage> {
        let ids = frame.ids.as_ref()?;
        (ids.len() == frame.width as usize * frame.height as usize).then(|| IdImage {
            width: frame.width,
            height: frame.height,
            ids: ids.clone(),
        })
    }

    /// ID + 1 as 24 bits: red = low byte, green = middle, blue = high; alpha 255.
    pub fn to_rgba(&self) -> image::RgbaImage {
        let rgba: Vec<u8> = self
            .ids
            .iter()
            .flat_map(|&v| [v as u8, (v >> 8) as u8, (v >> 16) as u8, 255])
            .collect();
        image::RgbaImage::from_raw(self.width, self.height, rgba)
            .unwrap_or_else(|| image::RgbaImage::new(self.width, self.height))
    }

    /// Inverse of [`IdImage::to_rgba`].
    pub(crate) fn from_rgba(img: &image::RgbaImage) -> IdImage {
        IdImage {
            width: img.width(),
            height: img.height(),
            ids: img
                .pixels()
                .map(|p| p[0] as u32 | (p[1] as u32) << 8 | (p[2] as u32) << 16)
                .collect(),
        }
    }

    /// Footprint of every ID + 1 that shows (index = ID + 1; `None` where it does not).
    pub fn footprints(&self) -> Vec<Option<Footprint>> {
        let mut out: Vec<Option<Footprint>> = Vec::new();
        let mut sums: Vec<[f64; 2]> = Vec::new();
        let w = self.width.max(1) as usize;
        for (i, &v) in self.ids.iter().enumerate() {
            if v == 0 {
                continue;
            }
            let (x, y) = ((i % w) as u32, (i / w) as u32);
            let k = v as usize;
            if out.len() <= k {
                out.resize(k + 1, None);
                sums.resize(k + 1, [0.0; 2]);
            }
            let f = out[k].get_or_insert(Footprint {
                pixels: 0,
                bbox: [x, y, x, y],
                centroid: [0.0; 2],
            });
            f.pixels += 1;
            f.bbox = [
                f.bbox[0].min(x),
                f.bbox[1].min(y),
                f.bbox[2].max(x),
                f.bbox[3].max(y),
            ];
            sums[k][0] += x as f64 + 0.5;
            sums[k][1] += y as f64 + 0.5;
        }
        for (f, s) in out.iter_mut().zip(&sums) {
            if let Some(f) = f {
                f.centroid = [s[0] / f.pixels as f64, s[1] / f.pixels as f64];
            }
        }
        out
    }

    /// A picture for people: a colour per patch, white background, red where `other` differs.
    pub(crate) fn diff_image(&self, other: &IdImage) -> image::RgbaImage {
        let rgba: Vec<u8> = self
            .ids
            .iter()
            .zip(&other.ids)
            .flat_map(|(&a, &b)| {
                if a != b {
                    [255, 0, 0, 255]
                } else if a == 0 {
                    [255, 255, 255, 255]
                } else {
                    let g = 90 + (a.wrapping_mul(37) % 140) as u8;
                    [g, g, g, 255]
                }
            })
            .collect();
        image::RgbaImage::from_raw(self.width, self.height, rgba)
            .unwrap_or_else(|| image::RgbaImage::new(self.width, self.height))
    }
}

/// Largest differences of an ID image from its golden still accepted as the same picture.
/// Both are rendered at one sample per pixel, where lavapipe and llvmpipe-GL agree bit for
/// bit; the limits leave room for a few rasterization-rule pixels per patch, no more (see
/// `tests/golden.rs` for the measured margins to each mutation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IdThresholds {
    /// Fraction of all pixels whose ID differs.
    pub differing: f64,
    /// A patch's pixel count may change by `count_abs` pixels or `count_rel` of its count,
    /// whichever is larger.
    pub count_abs: usize,
    pub count_rel: f64,
    /// Largest centroid move (px) of a patch with at least `min_pixels`.
    pub centroid_px: f64,
    /// Largest move (px) of a bounding-box side of a patch with at least `min_pixels`.
    pub bbox_px: u32,
    /// Patches smaller than this (in the golden and the image) are only held to `count_abs`.
    pub min_pixels: usize,
    /// Background pixels allowed where the golden's whole 3×3 neighbourhood is covered.
    pub holes: usize,
}

impl Default for IdThresholds {
    fn default() -> Self {
        IdThresholds {
            differing: 0.002,
            count_abs: 12,
            count_rel: 0.01,
            centroid_px: 0.25,
            bbox_px: 1,
            min_pixels: 60,
            holes: 0,
        }
    }
}

/// How an ID image differs from its golden.
#[derive(Clone, Debug, PartialEq)]
pub struct IdComparison {
    pub total: usize,
    /// Pixels whose ID differs.
    pub differing: usize,
    /// Background pixels whose 3×3 neighbourhood is all covered in the golden.
    pub holes: usize,
    /// The patch (ID) whose pixel count is furthest outside its limit, with the golden's and
    /// the image's counts and the ratio |Δ| / limit (> 1 fails).
    pub worst_count: Option<(u32, usize, usize, f64)>,
    /// Largest centroid move (px) and its patch.
    pub worst_centroid: Option<(u32, f64)>,
    /// Largest bounding-box side move (px) and its patch.
    pub worst_bbox: Option<(u32, u32)>,
}

impl IdComparison {
    /// The fraction of pixels whose ID differs.
    pub fn differing_fraction(&self) -> f64 {
        self.differing as f64 / self.total.max(1) as f64
    }

    /// Which limits are exceeded, in words (empty when none is).
    pub fn failures(&self, t: &IdThresholds) -> Vec<String> {
        let mut out = Vec::new();
        if self.differing_fraction() > t.differing {
            out.push(format!(
                "{} pixels ({:.3} %) have another ID (max {:.3} %)",
                self.differing,
                100.0 * self.differing_fraction(),
                100.0 * t.differing
            ));
        }
        if self.holes > t.holes {
            out.push(format!(
                "{} background pixels inside the silhouette (max {})",
                self.holes, t.holes
            ));
        }
        if let Some((id, g, a, r)) = self.worst_count
            && r > 1.0
        {
            out.push(format!(
                "patch {id} covers {a} pixels, the golden {g} ({r:.2} × the limit)"
            ));
        }
        if let Some((id, d)) = self.worst_centroid
            && d > t.centroid_px
        {
            out.push(format!(
                "patch {id}'s centroid moved {d:.3} px (max {})",
                t.centroid_px
            ));
        }
        if let Some((id, d)) = self.worst_bbox
            && d > t.bbox_px
        {
            out.push(format!(
                "patch {id}'s bounding box moved {d} px (max {})",
                t.bbox_px
            ));
        }
        out
    }
}

/// Compares `actual` with `golden` (same size) patch by patch.
pub fn compare_ids(golden: &IdImage, actual: &IdImage, t: &IdThresholds) -> IdComparison {
    let (w, h) = (golden.width as usize, golden.height as usize);
    let differing = golden
        .ids
        .iter()
        .zip(&actual.ids)
        .filter(|(a, b)| a != b)
        .count();
    let mut holes = 0;
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            if actual.ids[y * w + x] == 0
                && (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| golden.ids[yy * w + xx] != 0))
            {
                holes += 1;
            }
        }
    }
    let (fg, fa) = (golden.footprints(), actual.footprints());
    let mut c = IdComparison {
        total: w * h,
        differing,
        holes,
        worst_count: None,
        worst_centroid: None,
        worst_bbox: None,
    };
    for k in 1..fg.len().max(fa.len()) {
        let g = fg.get(k).copied().flatten();
        let a = fa.get(k).copied().flatten();
        let id = k as u32 - 1;
        let (gp, ap) = (g.map_or(0, |f| f.pixels), a.map_or(0, |f| f.pixels));
        let limit = (t.count_abs as f64).max(t.count_rel * gp as f64);
        let ratio = gp.abs_diff(ap) as f64 / limit.max(1e-9);
        if c.worst_count.is_none_or(|w| ratio > w.3) {
            c.worst_count = Some((id, gp, ap, ratio));
        }
        if let (Some(g), Some(a)) = (g, a)
            && g.pixels >= t.min_pixels
            && a.pixels >= t.min_pixels
        {
            let d = (g.centroid[0] - a.centroid[0]).hypot(g.centroid[1] - a.centroid[1]);
            if c.worst_centroid.is_none_or(|w| d > w.1) {
                c.worst_centroid = Some((id, d));
            }
            let b = (0..4)
                .map(|i| g.bbox[i].abs_diff(a.bbox[i]))
                .max()
                .unwrap_or(0);
            if c.worst_bbox.is_none_or(|w| b > w.1) {
                c.worst_bbox = Some((id, b));
            }
        }
    }
    c
}

/// Reads an ID golden written by [`compare_ids_with_golden`].
pub fn read_id_golden(path: &Path) -> Result<IdImage, GoldenError> {
    if !path.exists() {
        return Err(GoldenError::Missing(path.to_owned()));
    }
    let img = image::open(path)
        .map_err(|e| GoldenError::Unreadable {
            path: path.to_owned(),
            reason: e.to_string(),
        })?
        .to_rgba8();
    Ok(IdImage::from_rgba(&img))
}

/// Compares an ID image with the golden at `golden` (or rewrites it under `GOLDEN_UPDATE=1`).
/// On a mismatch writes `NAME-actual.png` (the IDs) and `NAME-diff.png` (red = other ID).
pub fn compare_ids_with_golden(
    golden: &Path,
    actual: &IdImage,
    limits: &IdThresholds,
) -> Result<Option<IdComparison>, GoldenError> {
    if update_requested() {
        write_rgba(golden, &actual.to_rgba())?;
        return Ok(None);
    }
    let reference = read_id_golden(golden)?;
    if (reference.width, reference.height) != (actual.width, actual.height) {
        return Err(GoldenError::SizeMismatch {
            path: golden.to_owned(),
            golden: (reference.width, reference.height),
            actual: (actual.width, actual.height),
        });
    }
    let c = compare_ids(&reference, actual, limits);
    let (actual_path, diff_path) = (sibling(golden, "actual"), sibling(golden, "diff"));
    let failures = c.failures(limits);
    if !failures.is_empty() {
        write_rgba(&actual_path, &actual.to_rgba())?;
        write_rgba(&diff_path, &reference.diff_image(actual))?;
        return Err(GoldenError::IdMismatch {
            path: golden.to_owned(),
            report: failures.join("; "),
            comparison: Box::new(c),
            actual: actual_path,
            diff: diff_path,
        });
    }
    let _ = std::fs::remove_file(&actual_path);
    let _ = std::fs::remove_file(&diff_path);
    Ok(Some(c))
}

/// Fat borders on and off against the watertight reference, at one view and pixel error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BorderShading {
    /// FLIP of the lit image with fat borders ([`FatBorders::Six`]) against the reference,
    /// over the whole image.
    pub on: FlipScore,
    /// The same without fat borders (the cracks they hide).
    pub off: FlipScore,
    /// Mean FLIP over the pixels outside the band a contour may grow into (within ⌈γ⌉ + 1 px
    /// of the reference's silhouette or of an occluding contour, a depth jump steeper than
    /// `crack::MAX_SLOPE`): what the fat borders cost where they are not allowed to differ,
    /// against what the cracks cost there.
    pub interior_on: f32,
    pub interior_off: f32,
    /// Largest Chebyshev distance (px) from a covered pixel to the reference's silhouette,
    /// with fat borders and without.
    pub growth_on_px: u32,
    pub growth_off_px: u32,
    /// Pixels covered with fat borders but not in the reference (fins), one sample per pixel.
    pub fin_pixels: usize,
    /// Mean over the fins of the largest RGB channel difference (0–1) from the nearest
    /// reference pixel: how unlike the surface they extend the fins are shaded.
    pub fin_contrast: f32,
}

/// Per-pixel FLIP error of `test` against `reference`.
pub(crate) fn flip_map(reference: &image::RgbaImage, test: &image::RgbaImage) -> Vec<f32> {
    nv_flip::flip(
        to_flip(reference),
        to_flip(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    )
    .to_vec()
}

/// Renders `scene` at `pixel_error` lit (4× MSAA) with fat borders on and off, and the crack
/// check's watertight reference (`crack::reference_meshes`, no fat borders), and measures
/// both against it. Returns the measurement and the three images (reference, on, off).
pub fn border_shading(
    renderer: &mut Renderer,
    scene: &Scene,
    view: &View,
    pixel_error: f64,
) -> Result<(BorderShading, [image::RgbaImage; 3]), RenderError> {
    let lit = |fat_borders, msaa| RenderOptions {
        shading: Shading::Lit,
        fat_borders,
        msaa,
        ids: true,
        depth: msaa == 1,
        ..RenderOptions::default()
    };
    let (ref_meshes, _) = super::crack::reference_meshes(scene, view, pixel_error);
    let ref_gpu = renderer.upload(&ref_meshes);
    let reference = renderer.render(&ref_gpu, view, &lit(FatBorders::Off, 4))?;
    let reference1 = renderer.render(&ref_gpu, view, &lit(FatBorders::Off, 1))?;
    let meshes = crate::tessellate::tessellate_scene(scene, view, pixel_error);
    let gpu = renderer.upload(&meshes);
    let on = renderer.render(&gpu, view, &lit(FatBorders::Six, 4))?;
    let on1 = renderer.render(&gpu, view, &lit(FatBorders::Six, 1))?;
    let off = renderer.render(&gpu, view, &lit(FatBorders::Off, 4))?;
    let ref_img = reference.to_rgba_image();
    let (on_img, off_img) = (on.to_rgba_image(), off.to_rgba_image());
    let cover: Vec<bool> = match &reference.ids {
        Some(ids) => ids.iter().map(|&i| i != 0).collect(),
        None => Vec::new(),
    };
    let (dist, nearest) = distance_to(&cover, reference.width as usize);
    let contours = contour_pixels(&reference1, view);
    let (near_contour, _) = distance_to(&contours, reference.width as usize);
    let covered = |f: &Frame, k: usize| f.ids.as_ref().is_some_and(|ids| ids[k] != 0);
    let growth = |f: &Frame| {
        (0..dist.len())
            .filter(|&k| covered(f, k))
            .map(|k| dist[k])
            .max()
            .unwrap_or(0)
    };
    let band = pixel_error.ceil() as u32 + 1;
    let counted: Vec<bool> = (0..dist.len())
        .map(|k| (covered(&reference, k) || dist[k] > band) && near_contour[k] > band)
        .collect();
    let interior = |map: &[f32]| {
        let (sum, n) = map
            .iter()
            .zip(&counted)
            .filter(|(_, c)| **c)
            .fold((0.0f64, 0usize), |(s, n), (v, _)| (s + *v as f64, n + 1));
        (sum / n.max(1) as f64) as f32
    };
    let (mut fin_pixels, mut fin_sum) = (0usize, 0.0f64);
    for (k, &near) in nearest.iter().enumerate() {
        if covered(&on1, k) && !covered(&reference1, k) {
            let (a, b) = (
                &on1.color[4 * k..4 * k + 3],
                &reference1.color[4 * near..4 * near + 3],
            );
            let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
            fin_pixels += 1;
            fin_sum += d as f64 / 255.0;
        }
    }
    let m = BorderShading {
        on: flip_score(&ref_img, &on_img).0,
        off: flip_score(&ref_img, &off_img).0,
        interior_on: interior(&flip_map(&ref_img, &on_img)),
        interior_off: interior(&flip_map(&ref_img, &off_img)),
        growth_on_px: growth(&on),
        growth_off_px: growth(&off),
        fin_pixels,
        fin_contrast: (fin_sum / fin_pixels.max(1) as f64) as f32,
    };
    Ok((m, [ref_img, on_img, off_img]))
}

/// Pixels on a silhouette or an occluding contour of `frame` (rendered with depth): covered
/// pixels next to an uncovered one, or next to one whose depth differs by more than
/// `crack::MAX_SLOPE` pixel sizes.
fn contour_pixels(frame: &Frame, view: &View) -> Vec<bool> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let Some(depth) = &frame.depth else {
        return vec![false; w * h];
    };
    let mut out = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let z = depth[y * w + x];
            if !z.is_finite() {
                continue;
            }
            let jump = |j: usize| {
                let zj = depth[j];
                !zj.is_finite()
                    || ((z - zj).abs() as f64)
                        > super::crack::MAX_SLOPE * view.pixel_size_at(z.max(zj) as f64)
            };
            out[y * w + x] = (x > 0 && jump(y * w + x - 1))
                || (x + 1 < w && jump(y * w + x + 1))
                || (y > 0 && jump((y - 1) * w + x))
                || (y + 1 < h && jump((y + 1) * w + x));
        }
    }
    out
}

/// Chebyshev distance (px) of every pixel to the nearest `true` pixel of `mask` (rows of
/// `w`), and that pixel's index (two-pass chamfer; 0 and itself on `true` pixels).
fn distance_to(mask: &[bool], w: usize) -> (Vec<u32>, Vec<usize>) {
    let n = mask.len();
    let h = n / w.max(1);
    let big = (w + h) as u32;
    let mut d: Vec<u32> = mask.iter().map(|&m| if m { 0 } else { big }).collect();
    let mut near: Vec<usize> = (0..n).collect();
    let neighbours: [(isize, isize); 4] = [(-1, 0), (-1, -1), (0, -1), (1, -1)];
    for pass in 0..2 {
        for k in 0..n {
            let k = if pass == 0 { k } else { n - 1 - k };
            let (x, y) = ((k % w) as isize, (k / w) as isize);
            for (dx, dy) in neighbours {
                let (dx, dy) = if pass == 0 { (dx, dy) } else { (-dx, -dy) };
                let (xx, yy) = (x + dx, y + dy);
                if xx >= 0 && yy >= 0 && (xx as usize) < w && (yy as usize) < h {
                    let j = yy as usize * w + xx as usize;
                    if d[j] + 1 < d[k] {
                        d[k] = d[j] + 1;
                        near[k] = near[j];
                    }
                }
            }
        }
    }
    (d, near)
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

    fn squares(shift: u32, second: bool) -> IdImage {
        let (w, h) = (80u32, 60u32);
        let mut ids = vec![0; (w * h) as usize];
        for y in 10..50 {
            for x in 10 + shift..40 + shift {
                ids[(y * w + x) as usize] = 1;
            }
            if second {
                for x in 40 + shift..70 + shift {
                    ids[(y * w + x) as usize] = 300;
                }
            }
        }
        IdImage {
            width: w,
            height: h,
            ids,
        }
    }

    #[test]
    fn id_images_round_trip_through_rgb() {
        let a = squares(0, true);
        assert_eq!(IdImage::from_rgba(&a.to_rgba()), a);
        let f = a.footprints();
        assert_eq!(f[300].map(|f| f.pixels), Some(1200));
        assert_eq!(f[1].map(|f| f.bbox), Some([10, 10, 39, 49]));
        assert_eq!(f[1].map(|f| f.centroid), Some([25.0, 30.0]));
    }

    #[test]
    fn id_comparison_sees_a_missing_patch_a_shift_and_a_hole() {
        let t = IdThresholds::default();
        let a = squares(0, true);
        assert!(compare_ids(&a, &a, &t).failures(&t).is_empty());
        let missing = compare_ids(&a, &squares(0, false), &t);
        assert_eq!(missing.worst_count.map(|w| (w.0, w.2)), Some((299, 0)));
        assert!(!missing.failures(&t).is_empty());
        let shifted = compare_ids(&a, &squares(1, true), &t);
        assert!(
            shifted.worst_centroid.is_some_and(|w| w.1 > 0.99),
            "{shifted:?}"
        );
        assert!(!shifted.failures(&t).is_empty());
        let mut holed = a.clone();
        holed.ids[30 * 80 + 40] = 0;
        let c = compare_ids(&a, &holed, &t);
        assert_eq!((c.holes, c.differing), (1, 1));
        assert_eq!(c.failures(&t).len(), 1, "{c:?}");
    }
}
