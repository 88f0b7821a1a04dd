//! Crack and growth pixels, measured with depth against a watertight reference.
//!
//! The **reference** is every patch evaluated on one shared uniform `n × n` parameter grid, fine
//! enough that each patch is within ε/4 of its surface, with border vertices that coincide
//! across patches welded to one position: a watertight tessellation whose silhouette and front
//! depth stand for the true ones.
//!
//! The **actual** image is the model tessellated independently per patch (T-junctions and all),
//! drawn with flat shading, a sentinel background and one sample per pixel, with or without fat
//! borders. Per pixel, over the `(2r+1)²` neighbourhood N of the pixel in the reference, with
//! `r = max(1, ⌈γ⌉)` px ([`contour_margin`]: the view lets every surface, silhouettes
//! included, be off by γ pixels):
//!
//! * **inside** — every pixel of N is covered and N holds no occluding contour (its depth range
//!   is at most what a surface sloping by `MAX_SLOPE` pixel sizes per pixel spans): the pixel
//!   is at least r px inside the true silhouette and r px away from where one surface passes in
//!   front of another, where the allowed error may legitimately show the surface behind;
//! * **crack** — inside, and the actual image shows the background, *or* a surface behind the
//!   farthest reference depth in N by more than `3.25 · ε(depth)`, where
//!   `ε(depth) = γ · pixel_size(depth)` is the object error the view allows at that depth:
//!   fat borders are pushed back by ε, the rendered patch and its neighbour each deviate by up to
//!   ε, and the reference by ε/4. A crack on a closed model usually reveals the far side's
//!   inside, which lies far behind that tolerance;
//! * **growth** — the pixel is more than r px outside the true silhouette, yet the actual image
//!   covers it: fat borders poking out. Its distance to the silhouette is reported.

use std::path::PathBuf;

use glam::{DVec3, Vec3};

use crate::model::{PatchSurface, Scene};
use crate::render::{FatBorders, Frame, RenderError, RenderOptions, Renderer, Shading};
use crate::tessellate::{
    BezierTessellator, MeshStats, PatchMesh, Resolution, tessellate_scene,
    tessellate_scene_uniform, tessellate_scene_with,
};
use crate::view::View;

/// Tolerance factor on ε for "behind the true front surface" (see module doc).
pub(crate) const DEPTH_TOLERANCE_EPS: f64 = 3.25;
/// Steepest depth slope (depth per pixel, in pixel sizes) of a surface still treated as
/// continuous; a larger depth jump within the window is an occluding contour.
pub(crate) const MAX_SLOPE: f64 = 4.0;
/// The reference is tessellated to this fraction of each patch's ε.
pub(crate) const REFERENCE_EPS_FRACTION: f64 = 0.25;
/// Upper limit on the reference grid.
pub(crate) const MAX_REFERENCE_GRID: u32 = 256;
/// Sentinel background for checks (magenta: never a flat-shaded surface colour here).
pub const SENTINEL: [u8; 3] = [255, 0, 255];
/// Flat surface colour for checks.
pub(crate) const CHECK_SURFACE: [f32; 3] = [0.5, 0.5, 0.5];

/// Pixel counts for one rendered image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CrackCounts {
    /// Pixels at least 1 px inside the reference silhouette (the population cracks come from).
    pub inside: usize,
    /// Inside pixels showing the background.
    pub background: usize,
    /// Inside pixels showing a surface behind the true front surface.
    pub behind: usize,
    /// Covered pixels more than 1 px outside the reference silhouette.
    pub growth: usize,
    /// Largest Chebyshev distance (px) from a growth pixel to the reference silhouette.
    pub growth_max_px: u32,
}

impl CrackCounts {
    pub fn cracks(&self) -> usize {
        self.background + self.behind
    }

    /// Adds `other`'s counts (pixels summed, the largest growth distance kept): the total of
    /// several images.
    pub fn add(&mut self, other: &CrackCounts) {
        self.inside += other.inside;
        self.background += other.background;
        self.behind += other.behind;
        self.growth += other.growth;
        self.growth_max_px = self.growth_max_px.max(other.growth_max_px);
    }
}

/// Reference meshes for `view`, welded along shared borders. Bézier patches: one shared
/// uniform grid fine enough for every patch (returned as the grid size). Trimmed faces: every
/// face at the smallest ε of the view (× `REFERENCE_EPS_FRACTION`) with border polylines
/// that depend only on the curve and ε, so that shared edges get the same points (grid size 0).
/// Mesh patches: the full-resolution mesh (exact; neighbours share their border vertices).
pub fn reference_meshes(scene: &Scene, view: &View, pixel_error: f64) -> (Vec<PatchMesh>, u32) {
    let trimmed = scene
        .patches
        .iter()
        .any(|p| !matches!(p.surface, PatchSurface::Bezier(_)));
    let mut n = 0;
    let mut meshes = if trimmed {
        let eps = scene
            .patches
            .iter()
            .map(|p| view.eps_obj(&p.bounds, pixel_error) * REFERENCE_EPS_FRACTION)
            .fold(f64::INFINITY, f64::min);
        tessellate_scene_with(scene, eps, true)
    } else {
        n = scene
            .patches
            .iter()
            .map(|p| {
                let eps = view.eps_obj(&p.bounds, pixel_error) * REFERENCE_EPS_FRACTION;
                let r = match &p.surface {
                    PatchSurface::Bezier(b) => BezierTessellator::resolution_for(b, eps).0,
                    PatchSurface::Trimmed(_) | PatchSurface::Mesh(_) => Resolution { nu: 1, nv: 1 },
                };
                r.nu.max(r.nv)
            })
            .max()
            .unwrap_or(1)
            .clamp(1, MAX_REFERENCE_GRID);
        tessellate_scene_uniform(scene, n)
    };
    weld_borders(&mut meshes, (scene.bounds.radius * 1e-6) as f32);
    (meshes, n)
}

/// Moves border vertices of different patches that lie within `tol` of each other onto one
/// position (the first seen), so shared borders coincide bit for bit.
pub(crate) fn weld_borders(meshes: &mut [PatchMesh], tol: f32) {
    use std::collections::HashMap;
    let tol = tol.max(f32::MIN_POSITIVE);
    let cell = |p: Vec3| ((p / tol).floor()).as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<Vec3>> = HashMap::new();
    for m in meshes.iter_mut() {
        let border: Vec<u32> = m.borders.iter().flatten().copied().collect();
        for k in border {
            let p = m.positions[k as usize];
            let c = cell(p);
            let mut found = None;
            'search: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz)))
                            && let Some(q) = list.iter().find(|q| q.distance(p) <= tol)
                        {
                            found = Some(*q);
                            break 'search;
                        }
                    }
                }
            }
            match found {
                Some(q) => m.positions[k as usize] = q,
                None => grid.entry(c).or_default().push(p),
            }
        }
    }
}

/// How far (px) from a silhouette or occluding contour a pixel must be before it has to show
/// the nearest surface: 1 px, or the pixel error when it is larger — the view allows every
/// surface, silhouettes included, to be off by that much.
pub fn contour_margin(pixel_error: f64) -> usize {
    (pixel_error.ceil() as usize).max(1)
}

/// Why two images cannot be compared, or why a check could not render.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A failure image could not be written.
    #[error(transparent)]
    Write(#[from] crate::io::png::WriteError),
    /// An image was rendered without depth (`RenderOptions::depth`).
    #[error("the {0} image has no depth buffer (render it with `RenderOptions::depth`)")]
    MissingDepth(&'static str),
    /// The two images differ in size.
    #[error("the reference is {reference:?} px but the actual image is {actual:?} px")]
    SizeMismatch {
        reference: (u32, u32),
        actual: (u32, u32),
    },
    /// An image's colour or depth buffer does not hold one value per pixel.
    #[error("the {which} image's {buffer} buffer has {len} values for {width}×{height} pixels")]
    BufferLength {
        which: &'static str,
        buffer: &'static str,
        len: usize,
        width: u32,
        height: u32,
    },
}

/// Checks that `frame` has depth and colour for each of its pixels; returns its depth.
fn depth_of<'a>(frame: &'a Frame, which: &'static str) -> Result<&'a [f32], CheckError> {
    let n = frame.width as usize * frame.height as usize;
    let depth = frame
        .depth
        .as_deref()
        .ok_or(CheckError::MissingDepth(which))?;
    for (buffer, len) in [("depth", depth.len()), ("colour", frame.color.len() / 4)] {
        if len != n || (buffer == "colour" && !frame.color.len().is_multiple_of(4)) {
            return Err(CheckError::BufferLength {
                which,
                buffer,
                len,
                width: frame.width,
                height: frame.height,
            });
        }
    }
    Ok(depth)
}

/// Counts crack and growth pixels of `actual` against `reference` (both rendered with depth,
/// the same view and size). Also returns a mask image: red = background crack, orange = a
/// surface behind showing, blue = growth. Images without depth or of different sizes are an
/// error, never "no cracks".
pub fn classify(
    reference: &Frame,
    actual: &Frame,
    view: &View,
    pixel_error: f64,
    background: [u8; 3],
) -> Result<(CrackCounts, image::RgbaImage), CheckError> {
    if (reference.width, reference.height) != (actual.width, actual.height) {
        return Err(CheckError::SizeMismatch {
            reference: (reference.width, reference.height),
            actual: (actual.width, actual.height),
        });
    }
    let rd = depth_of(reference, "reference")?;
    let ad = depth_of(actual, "actual")?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let mut mask = image::RgbaImage::new(w as u32, h as u32);
    let mut counts = CrackCounts::default();
    let r = contour_margin(pixel_error);
    // Over the (2r+1)² window: is every pixel covered, and the farthest covered depth.
    let cover: Vec<f32> = rd
        .iter()
        .map(|z| if z.is_finite() { 1.0 } else { 0.0 })
        .collect();
    let all_covered = window_filter(&cover, w, h, r, f32::min, 0.0);
    let depth0: Vec<f32> = rd
        .iter()
        .map(|z| if z.is_finite() { *z } else { 0.0 })
        .collect();
    let farthest = window_filter(&depth0, w, h, r, f32::max, 0.0);
    let nearest = window_filter(rd, w, h, r, f32::min, f32::INFINITY);
    let dist = silhouette_distance(rd, w, h);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let px = actual.pixel(x as u32, y as u32);
            let actual_bg = px[..3] == background;
            let gray = ((px[0] as u16 + px[1] as u16 + px[2] as u16) / 6) as u8;
            let mut colour = [gray, gray, gray];
            let far = farthest[i] as f64;
            let pixel = view.pixel_size_at(far);
            let continuous = far - (nearest[i] as f64) <= MAX_SLOPE * (2 * r) as f64 * pixel;
            if all_covered[i] > 0.5 && continuous {
                counts.inside += 1;
                let tol = DEPTH_TOLERANCE_EPS * pixel_error * pixel;
                if actual_bg {
                    counts.background += 1;
                    colour = [255, 0, 0];
                } else if ad[i] as f64 > far + tol {
                    counts.behind += 1;
                    colour = [255, 140, 0];
                }
            } else if dist[i] as usize > r && !actual_bg {
                counts.growth += 1;
                counts.growth_max_px = counts.growth_max_px.max(dist[i]);
                colour = [0, 80, 255];
            }
            mask.put_pixel(
                x as u32,
                y as u32,
                image::Rgba([colour[0], colour[1], colour[2], 255]),
            );
        }
    }
    Ok((counts, mask))
}

/// Separable min/max filter over a (2r+1)² window; pixels outside the image count as `outside`.
fn window_filter(
    src: &[f32],
    w: usize,
    h: usize,
    r: usize,
    op: fn(f32, f32) -> f32,
    outside: f32,
) -> Vec<f32> {
    let mut tmp = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut v = if x < r || x + r >= w {
                outside
            } else {
                src[y * w + x]
            };
            for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                v = op(v, src[y * w + xx]);
            }
            tmp[y * w + x] = v;
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut v = if y < r || y + r >= h {
                outside
            } else {
                tmp[y * w + x]
            };
            for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                v = op(v, tmp[yy * w + x]);
            }
            out[y * w + x] = v;
        }
    }
    out
}

/// Chebyshev distance (px) of every pixel to the nearest covered reference pixel (0 on it).
fn silhouette_distance(depth: &[f32], w: usize, h: usize) -> Vec<u32> {
    let big = (w + h) as u32;
    let mut d: Vec<u32> = depth
        .iter()
        .map(|z| if z.is_finite() { 0 } else { big })
        .collect();
    for y in 0..h {
        for x in 0..w {
            let mut v = d[y * w + x];
            if x > 0 {
                v = v.min(d[y * w + x - 1] + 1);
            }
            if y > 0 {
                v = v.min(d[(y - 1) * w + x] + 1);
                if x > 0 {
                    v = v.min(d[(y - 1) * w + x - 1] + 1);
                }
                if x + 1 < w {
                    v = v.min(d[(y - 1) * w + x + 1] + 1);
                }
            }
            d[y * w + x] = v;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let mut v = d[y * w + x];
            if x + 1 < w {
                v = v.min(d[y * w + x + 1] + 1);
            }
            if y + 1 < h {
                v = v.min(d[(y + 1) * w + x] + 1);
                if x + 1 < w {
                    v = v.min(d[(y + 1) * w + x + 1] + 1);
                }
                if x > 0 {
                    v = v.min(d[(y + 1) * w + x - 1] + 1);
                }
            }
            d[y * w + x] = v;
        }
    }
    d
}

/// A small deterministic generator (SplitMix64) for reproducible random views.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// View `index` of the random sequence `seed`: a direction uniform on the sphere, a distance
/// between 0.6× (close-up, model partly out of frame) and 1.6× the framing distance, and a
/// target jittered within 0.2 radii of the model centre.
pub fn random_view(scene: &Scene, seed: u64, index: usize, size: (u32, u32), fov_y: f64) -> View {
    let mut rng = SplitMix64::new(seed ^ (index as u64).wrapping_mul(0xA076_1D64_78BD_642F));
    let z = 2.0 * rng.next_f64() - 1.0;
    let phi = std::f64::consts::TAU * rng.next_f64();
    let r = (1.0 - z * z).sqrt();
    let dir = DVec3::new(r * phi.cos(), r * phi.sin(), z);
    let up = scene.up.vector();
    let up = if dir.cross(up).length() < 0.2 {
        up.any_orthonormal_vector()
    } else {
        up
    };
    let base = View::framing_from(&scene.bounds, up, dir, fov_y, size);
    let scale = 0.6 + rng.next_f64();
    let jitter = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - DVec3::ONE;
    let target = scene.bounds.center + jitter * 0.2 * scene.bounds.radius;
    let eye = target + (base.eye - base.target) * scale;
    View::new(eye, target, up, fov_y, size, &scene.bounds)
}

/// What [`run_check`] does.
#[derive(Clone, Debug)]
pub struct CheckOptions {
    pub views: usize,
    /// Run only these of the `views` random views (their indices, in this order): one shard
    /// of a run split between machines. `None`: views `0..views`.
    pub only_views: Option<Vec<usize>>,
    pub seed: u64,
    pub pixel_error: f64,
    pub size: (u32, u32),
    pub fov_y: f64,
    /// Orthographic views ([`View::orthographic`] of each random view: the image as tall as
    /// the perspective view's at its target).
    pub ortho: bool,
    /// Variants to measure; include [`FatBorders::Off`] to show the cracks they cover.
    pub variants: Vec<FatBorders>,
    /// Draw the stress tessellation ([`super::stress::stress_tessellation`]): every border
    /// pulled back towards its patch as far as the pixel error allows, so that shared borders
    /// gap by most of ε_a + ε_b and only fat borders of full width close them.
    pub stress: bool,
    /// Also measure every fat-border variant of `variants` with its ε scaled by this factor
    /// (a mutation: fat borders narrower than the paper's must let cracks through); the
    /// counts go to [`ViewResult::narrowed`].
    pub narrowed_width: Option<f64>,
    /// Where to write `view{i}-fb{v}-actual.png` / `-diff.png` for images with cracks.
    pub save_failures: Option<PathBuf>,
    /// Put before every saved image's name (`{prefix}view{i}-fb{v}-actual.png`): names that
    /// stay apart when the images of several files or machines meet in one folder.
    pub failure_prefix: String,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            views: 20,
            only_views: None,
            seed: 1,
            pixel_error: crate::view::DEFAULT_PIXEL_ERROR,
            size: (512, 384),
            fov_y: crate::view::DEFAULT_FOV_Y_DEG.to_radians(),
            ortho: false,
            variants: vec![
                FatBorders::Off,
                FatBorders::Six,
                FatBorders::Four,
                FatBorders::Two,
            ],
            stress: false,
            narrowed_width: None,
            save_failures: None,
            failure_prefix: String::new(),
        }
    }
}

impl CheckOptions {
    /// The indices of the views to run: [`CheckOptions::only_views`], else `0..views`.
    pub fn view_indices(&self) -> Vec<usize> {
        match &self.only_views {
            Some(only) => only.clone(),
            None => (0..self.views).collect(),
        }
    }
}

/// One view of a check.
#[derive(Clone, Debug)]
pub struct ViewResult {
    pub index: usize,
    pub view: View,
    pub reference_grid: u32,
    pub stats: MeshStats,
    pub counts: Vec<(FatBorders, CrackCounts)>,
    /// With [`CheckOptions::narrowed_width`]: the fat-border variants drawn that much
    /// narrower.
    pub narrowed: Vec<(FatBorders, CrackCounts)>,
}

/// All views of a check.
#[derive(Clone, Debug, Default)]
pub struct CheckReport {
    pub views: Vec<ViewResult>,
}

fn sum_counts<'a>(
    counts: impl Iterator<Item = &'a (FatBorders, CrackCounts)>,
    variant: FatBorders,
) -> CrackCounts {
    let mut t = CrackCounts::default();
    for (fb, c) in counts {
        if *fb == variant {
            t.add(c);
        }
    }
    t
}

impl CheckReport {
    /// Sum of counts over all views for one variant.
    pub fn total(&self, variant: FatBorders) -> CrackCounts {
        sum_counts(self.views.iter().flat_map(|v| &v.counts), variant)
    }

    /// Sum over all views for one variant drawn narrowed ([`CheckOptions::narrowed_width`]).
    pub fn total_narrowed(&self, variant: FatBorders) -> CrackCounts {
        sum_counts(self.views.iter().flat_map(|v| &v.narrowed), variant)
    }

    /// True when no view drawn with fat borders (of full width) shows a crack pixel.
    pub fn crack_free(&self) -> bool {
        self.views
            .iter()
            .flat_map(|v| &v.counts)
            .all(|(fb, c)| *fb == FatBorders::Off || c.cracks() == 0)
    }
}

/// How checks render: flat shading, the sentinel background, one sample per pixel, depth.
pub fn check_render_options(fat_borders: FatBorders) -> RenderOptions {
    RenderOptions {
        shading: Shading::Flat,
        background: SENTINEL,
        surface_color: CHECK_SURFACE,
        fat_borders,
        msaa: 1,
        depth: true,
        ids: false,
        sections: crate::render::Sections::NONE,
        edges: crate::render::Edges::Off,
    }
}

/// The crack check of one view — the only one: the watertight reference drawn once, then any
/// number of drawings of the same view counted against it. Still views (`patchwork check`),
/// the LOD frame loop and animations (through [`crate::frame::step`]) all use it.
#[derive(Debug)]
pub(crate) struct Judge {
    reference: Frame,
    view: View,
    pixel_error: f64,
}

/// One drawing counted by a `Judge`: the counts, the image and the crack mask.
#[derive(Debug)]
pub struct Verdict {
    pub counts: CrackCounts,
    pub actual: Frame,
    pub mask: image::RgbaImage,
}

impl Verdict {
    /// Whether anything is wrong (a crack or growth pixel).
    pub fn failed(&self) -> bool {
        self.counts.cracks() > 0 || self.counts.growth > 0
    }

    /// Writes `{stem}-actual.png` and `{stem}-diff.png` into `dir` (a diagnostic aid).
    pub fn save(
        &self,
        dir: &std::path::Path,
        stem: &str,
    ) -> Result<(), crate::io::png::WriteError> {
        let actual = self.actual.to_rgba_image();
        crate::io::png::write_rgba(&dir.join(format!("{stem}-actual.png")), &actual)?;
        crate::io::png::write_rgba(&dir.join(format!("{stem}-diff.png")), &self.mask)
    }
}

impl Judge {
    /// Draws `reference` (watertight meshes, e.g. [`reference_meshes`] for the view, moved as
    /// the drawing is) without fat borders; drawings are then judged at `pixel_error`.
    pub fn new(
        renderer: &mut Renderer,
        reference: &[PatchMesh],
        view: &View,
        pixel_error: f64,
    ) -> Result<Judge, CheckError> {
        let gpu = renderer.upload(reference);
        let reference = renderer.render(&gpu, view, &check_render_options(FatBorders::Off))?;
        Ok(Judge {
            reference,
            view: *view,
            pixel_error,
        })
    }

    /// Draws `gpu` with fat borders `variant` (flat check colours, depth) and counts crack
    /// and growth pixels against the reference ([`classify`]).
    pub fn count<'a>(
        &self,
        renderer: &mut Renderer,
        gpu: impl Into<crate::render::Geometry<'a>>,
        variant: FatBorders,
    ) -> Result<Verdict, CheckError> {
        let actual = renderer.render(gpu, &self.view, &check_render_options(variant))?;
        let (counts, mask) = classify(
            &self.reference,
            &actual,
            &self.view,
            self.pixel_error,
            SENTINEL,
        )?;
        Ok(Verdict {
            counts,
            actual,
            mask,
        })
    }
}

/// Scales the ε every mesh declares (target and achieved) by `factor`: their fat borders
/// are then drawn that much narrower; the triangles do not change.
pub(crate) fn narrow_fat_borders(meshes: &mut [PatchMesh], factor: f64) {
    for m in meshes {
        m.eps_target *= factor;
        m.error *= factor;
        m.border_error = m.border_error.map(|b| b * factor);
    }
}

/// Renders `opts.views` random views of `scene` (or those of [`CheckOptions::only_views`];
/// view `i` is the same view whichever others run) and counts cracks and growth per variant.
/// `on_view` is called after each view (progress).
pub fn run_check(
    renderer: &mut Renderer,
    scene: &Scene,
    opts: &CheckOptions,
    on_view: impl FnMut(&ViewResult),
) -> Result<CheckReport, CheckError> {
    run_check_with(renderer, scene, opts, |_, _| {}, on_view)
}

/// As [`run_check`], with `mutate` applied to every view's meshes before they are drawn
/// (tests inject faults with it to show the check finds them).
pub fn run_check_with(
    renderer: &mut Renderer,
    scene: &Scene,
    opts: &CheckOptions,
    mut mutate: impl FnMut(&View, &mut Vec<PatchMesh>),
    mut on_view: impl FnMut(&ViewResult),
) -> Result<CheckReport, CheckError> {
    let mut report = CheckReport::default();
    for index in opts.view_indices() {
        let view = random_view(scene, opts.seed, index, opts.size, opts.fov_y)
            .with_ortho(opts.ortho, &scene.bounds);
        let (ref_meshes, grid) = reference_meshes(scene, &view, opts.pixel_error);
        let judge = Judge::new(renderer, &ref_meshes, &view, opts.pixel_error)?;
        let mut meshes = if opts.stress {
            super::stress::stress_tessellation(scene, &view, opts.pixel_error)
        } else {
            tessellate_scene(scene, &view, opts.pixel_error)
        };
        mutate(&view, &mut meshes);
        let stats = MeshStats::of(&meshes);
        let gpu = renderer.upload(&meshes);
        let narrow_gpu = opts.narrowed_width.map(|factor| {
            narrow_fat_borders(&mut meshes, factor);
            (factor, renderer.upload(&meshes))
        });
        let mut counts = Vec::new();
        let mut measure = |gpu: &crate::render::GpuMeshes,
                           variant: FatBorders,
                           tag: &str|
         -> Result<CrackCounts, CheckError> {
            let verdict = judge.count(renderer, gpu, variant)?;
            if let Some(dir) = &opts.save_failures
                && verdict.failed()
            {
                let stem = format!(
                    "{}view{index:03}-fb{}{tag}",
                    opts.failure_prefix,
                    variant.name()
                );
                // Asked for and not written: an error, not a lost diagnostic.
                verdict.save(dir, &stem)?;
            }
            Ok(verdict.counts)
        };
        for &variant in &opts.variants {
            counts.push((variant, measure(&gpu, variant, "")?));
        }
        let mut narrowed = Vec::new();
        if let Some((factor, gpu)) = &narrow_gpu {
            for &variant in opts.variants.iter().filter(|v| **v != FatBorders::Off) {
                narrowed.push((variant, measure(gpu, variant, &format!("-x{factor}"))?));
            }
        }
        let result = ViewResult {
            index,
            view,
            reference_grid: grid,
            stats,
            counts,
            narrowed,
        };
        on_view(&result);
        report.views.push(result);
    }
    Ok(report)
}

#[cfg(test)]
mod tests;
