//! Argument groups shared by several commands, and the one place each is validated.
//!
//! Values that are wrong on their own (`--size 0x1`, `--msaa 3`, `--eye 1,2`) are refused by
//! clap's value parsers while parsing; ranges that depend on nothing else are checked by the
//! `validate`-style functions here into typed values, called where the command first needs
//! them (after the model is loaded for the camera, so a missing file is reported first).

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use glam::DVec3;

use patchwork::lod::LodOptions;
use patchwork::model::Scene;
use patchwork::prep::{Hierarchies, LoadOptions};
use patchwork::render::{
    Edges, FatBorders, Primitives, RenderOptions, SectionPlane, Sections, Shading,
};
use patchwork::view::{self, Framing, NamedView, View};

use crate::error::CliError;

fn parse_triple<T: std::str::FromStr>(s: &str, what: &str) -> Result<[T; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected {what} as three comma-separated numbers, got {s:?}"
        ));
    }
    let mut out = Vec::with_capacity(3);
    for p in parts {
        out.push(
            p.parse::<T>()
                .map_err(|_| format!("{p:?} is not a valid {what} component"))?,
        );
    }
    out.try_into()
        .map_err(|_| format!("expected three numbers, got {s:?}"))
}

pub fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let [x, y, z] = parse_triple::<f64>(s, "X,Y,Z")?;
    let v = DVec3::new(x, y, z);
    if !v.is_finite() {
        return Err(format!("{s:?} is not finite"));
    }
    Ok(v)
}

pub fn parse_rgb(s: &str) -> Result<[u8; 3], String> {
    parse_triple::<u8>(s, "R,G,B (0-255)")
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 {
        return Err(format!("image size must be at least 1x1, got {w}x{h}"));
    }
    Ok((w, h))
}

pub fn parse_msaa(s: &str) -> Result<u32, String> {
    match s {
        "1" => Ok(1),
        "4" => Ok(4),
        _ => Err(format!("MSAA must be 1 or 4, got {s:?}")),
    }
}

/// `--pixel-error`: a positive number of pixels.
pub fn pixel_error(px: f64) -> Result<f64, CliError> {
    if !(px.is_finite() && px > 0.0) {
        return Err(CliError::OutOfRange {
            flag: "--pixel-error",
            value: px,
            range: "a positive number of pixels",
        });
    }
    Ok(px)
}

/// `--fov` in degrees → the vertical field of view in radians.
pub fn fov_y(deg: f64) -> Result<f64, CliError> {
    if !(deg.is_finite() && (0.5..=179.0).contains(&deg)) {
        return Err(CliError::OutOfRange {
            flag: "--fov",
            value: deg,
            range: "from 0.5 to 179 degrees",
        });
    }
    Ok(deg.to_radians())
}

/// A finite number (angles in degrees).
pub fn finite(flag: &'static str, value: f64) -> Result<f64, CliError> {
    if !value.is_finite() {
        return Err(CliError::OutOfRange {
            flag,
            value,
            range: "a finite number",
        });
    }
    Ok(value)
}

/// `--margin`: from -0.9 (the model's sphere cropped to a tenth) to 100.
pub fn margin(value: f64) -> Result<f64, CliError> {
    if !(value.is_finite() && (-0.9..=100.0).contains(&value)) {
        return Err(CliError::OutOfRange {
            flag: "--margin",
            value,
            range: "from -0.9 to 100",
        });
    }
    Ok(value)
}

/// A positive finite number of milliseconds → a duration.
pub fn positive_ms(flag: &'static str, ms: f64) -> Result<Duration, CliError> {
    if !(ms.is_finite() && ms > 0.0) {
        return Err(CliError::NotPositive { flag, value: ms });
    }
    Ok(Duration::from_secs_f64(ms / 1e3))
}

/// A count of at least `min`.
pub fn at_least(flag: &'static str, value: usize, min: usize) -> Result<usize, CliError> {
    if value < min {
        return Err(CliError::TooFew { flag, value, min });
    }
    Ok(value)
}

/// `--distance`: a flight distance ≥ 0 (× the model's radius).
pub fn distance(value: f64) -> Result<f64, CliError> {
    if !(value.is_finite() && value >= 0.0) {
        return Err(CliError::Negative {
            flag: "--distance",
            value,
        });
    }
    Ok(value)
}

#[derive(Args, Debug, Clone)]
pub struct CameraArgs {
    /// Image size in pixels.
    #[arg(long, default_value = "1024x768", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Eye position (default: frames the model's bounding sphere from a three-quarter view,
    /// or from --view, --azimuth and --elevation).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Named view, in the model's frame (front is -y for z-up models, +z for y-up ones):
    /// front, back, left, right, top, bottom or iso.
    #[arg(long, conflicts_with = "eye")]
    pub view: Option<NamedView>,
    /// Turn the camera about the model's up axis by this many degrees (positive: towards the
    /// model's right), after --view.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        conflicts_with = "eye"
    )]
    pub azimuth: f64,
    /// Raise the camera by this many degrees towards the up axis (negative lowers it), after
    /// --view and --azimuth; the result is kept within ±90°.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        conflicts_with = "eye"
    )]
    pub elevation: f64,
    /// Room around the model: the camera stands 1 + MARGIN times the distance at which the
    /// model's bounding sphere touches the nearer image edges (0 touches; negative zooms in).
    #[arg(long, default_value_t = view::DEFAULT_MARGIN, allow_hyphen_values = true, conflicts_with = "eye")]
    pub margin: f64,
    /// Point looked at (default: the model's centre).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Up vector (default 0,1,0; for z-up formats such as .bpt, 0,0,1).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = view::DEFAULT_FOV_Y_DEG)]
    pub fov: f64,
    /// Orthographic projection: parallel rays, sizes independent of depth. The framing view
    /// fits the model's bounding sphere (with --margin); with --eye the image is as tall as
    /// the perspective view's at the target.
    #[arg(long)]
    pub ortho: bool,
    /// Allowed screen-space error in pixels (ε per patch follows from it).
    #[arg(long, default_value_t = view::DEFAULT_PIXEL_ERROR)]
    pub pixel_error: f64,
}

/// [`CameraArgs`] with the field of view and pixel error checked.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    pub size: (u32, u32),
    pub eye: Option<DVec3>,
    pub target: Option<DVec3>,
    pub up: Option<DVec3>,
    /// Radians.
    pub fov_y: f64,
    pub pixel_error: f64,
    /// Direction and margin of the default camera (when no eye is given).
    pub framing: Framing,
}

impl CameraArgs {
    pub fn validate(&self) -> Result<Camera, CliError> {
        Ok(Camera {
            size: self.size,
            eye: self.eye,
            target: self.target,
            up: self.up,
            fov_y: fov_y(self.fov)?,
            pixel_error: pixel_error(self.pixel_error)?,
            framing: Framing {
                view: self.view,
                azimuth_deg: finite("--azimuth", self.azimuth)?,
                elevation_deg: finite("--elevation", self.elevation)?,
                margin: margin(self.margin)?,
                ortho: self.ortho,
            },
        })
    }
}

impl Camera {
    /// The view of `scene`: the given eye, or the framing view shifted to the target; up and
    /// target default to the scene's.
    pub fn view(&self, scene: &Scene) -> Result<View, CliError> {
        let up = self.up.unwrap_or_else(|| scene.up.vector());
        if up.length() < 1e-12 {
            return Err(CliError::ZeroUp);
        }
        let target = self.target.unwrap_or(scene.bounds.center);
        let (fov, size) = (self.fov_y, self.size);
        let view = match self.eye {
            Some(eye) => {
                if eye.distance(target) < 1e-12 {
                    return Err(CliError::EyeAtTarget { eye });
                }
                let direction = target - eye;
                if direction.cross(up).length() < 1e-9 * direction.length() * up.length() {
                    return Err(CliError::UpAlongView { up, direction });
                }
                View::new(eye, target, up, fov, size, &scene.bounds)
                    .with_ortho(self.framing.ortho, &scene.bounds)
            }
            None => {
                let mut v = View::framed(&scene.bounds, up, &self.framing, fov, size);
                let shift = target - v.target;
                v.eye += shift;
                v.target = target;
                // The framing's screen up: the model's up, or its back in a top view.
                View::new(v.eye, v.target, v.up, fov, size, &scene.bounds)
                    .with_projection(v.projection, &scene.bounds)
            }
        };
        Ok(view)
    }
}

#[derive(Args, Debug, Clone, Copy)]
pub struct BudgetArgs {
    /// Re-tessellation time budget per frame, milliseconds.
    #[arg(long, default_value_t = 40.0)]
    pub budget_ms: f64,
    /// Memory for cached tessellation levels (those not drawn now, kept to go back to
    /// them for free), MiB over all patches; the least recently used go first.
    #[arg(long, default_value_t = (patchwork::lod::DEFAULT_CACHE_BYTES >> 20) as f64)]
    pub cache_mib: f64,
}

/// Checked [`BudgetArgs`]: time per frame and bytes of cached levels.
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    pub time: Duration,
    pub cache_bytes: usize,
}

impl BudgetArgs {
    pub fn validate(&self) -> Result<Budget, CliError> {
        let time = positive_ms("--budget-ms", self.budget_ms)?;
        if !(self.cache_mib.is_finite() && self.cache_mib >= 0.0) {
            return Err(CliError::Negative {
                flag: "--cache-mib",
                value: self.cache_mib,
            });
        }
        let cache_bytes = (self.cache_mib * (1u64 << 20) as f64).min(usize::MAX as f64) as usize;
        Ok(Budget { time, cache_bytes })
    }
}

/// The frame loop's options from a checked pixel error and budget.
pub fn lod_options(pixel_error: f64, budget: Budget) -> LodOptions {
    LodOptions {
        pixel_error,
        budget: budget.time,
        cache_bytes: budget.cache_bytes,
        ..LodOptions::default()
    }
}

#[derive(Args, Debug, Clone, Copy)]
pub struct PrimitivesArg {
    /// Surface primitives: `auto` (lists for tessellated patches, multiresolution strips for
    /// mesh patches: fastest measured over many frames; lists for `render`'s one image),
    /// `list` (indexed triangles), `strips` (static triangle
    /// strips by tunneling; per arc for mesh patches), `mts` (mesh patches: multiresolution
    /// strips at each cut) or `repair` (mesh patches: strips repaired by tunneling as the cut
    /// moves).
    #[arg(long, default_value = "auto")]
    pub primitives: Primitives,
}

// How images are drawn (shared by `render` and `implode`); every value is checked by its
// parser.
#[derive(Args, Debug, Clone, Copy)]
pub struct DrawArgs {
    /// lit, flat or ids.
    #[arg(long, default_value = "lit")]
    pub shading: Shading,
    /// Background colour R,G,B (0–255).
    #[arg(long, default_value = "255,255,255", value_parser = parse_rgb)]
    pub background: [u8; 3],
    /// Fat-border variant: off, 6 or 4 displaced vertices per border vertex (a segment quad
    /// and fans), or 2 (2 triangles per border vertex: each segment's quad extended by ε).
    #[arg(long, default_value = "6")]
    pub fat_borders: FatBorders,
    /// Samples per pixel: 1 or 4.
    #[arg(long, default_value_t = 4, value_parser = parse_msaa)]
    pub msaa: u32,
    #[command(flatten)]
    pub primitives: PrimitivesArg,
    #[command(flatten)]
    pub edges: EdgesArg,
}

/// Edges of the model drawn over the surfaces (`render`, `implode`, `view`).
#[derive(Args, Debug, Clone, Copy)]
pub struct EdgesArg {
    /// Edges drawn as dark lines: off, feature (sharp edges: free edges, creases, faces
    /// meeting at an angle; edges between faces meeting smoothly within 1 degree left out) or
    /// all (every edge between faces). STEP faces, Bezier patches, mesh creases.
    #[arg(long, default_value = "off")]
    pub edges: Edges,
}

impl DrawArgs {
    pub fn options(&self) -> RenderOptions {
        RenderOptions {
            shading: self.shading,
            background: self.background,
            fat_borders: self.fat_borders,
            msaa: self.msaa,
            depth: false,
            edges: self.edges.edges,
            ..RenderOptions::default()
        }
    }
}

/// The MT hierarchy cache of mesh models.
#[derive(Args, Clone, Copy, Debug)]
pub struct CacheArgs {
    /// Neither read nor write the mesh hierarchy cache (in $PATCHWORK_CACHE, else
    /// $XDG_CACHE_HOME/patchwork or ~/.cache/patchwork; PATCHWORK_CACHE=off also turns it off).
    #[arg(long)]
    pub no_cache: bool,
}

impl CacheArgs {
    /// The cache directory, unless turned off.
    pub fn dir(&self) -> Option<PathBuf> {
        if self.no_cache {
            None
        } else {
            patchwork::io::mt_cache::default_dir()
        }
    }

    /// Load options with this cache and `hierarchies`.
    pub fn options(&self, hierarchies: Hierarchies) -> LoadOptions {
        LoadOptions::new(hierarchies, self.dir())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bounds the message names are accepted; just past them are not.
    #[test]
    fn fov_accepts_the_range_it_names() {
        assert!(fov_y(0.5).is_ok() && fov_y(179.0).is_ok() && fov_y(45.0).is_ok());
        for bad in [0.49, 179.01, f64::NAN, f64::INFINITY, -45.0] {
            let e = fov_y(bad).expect_err("out of range").to_string();
            assert!(e.contains("from 0.5 to 179 degrees"), "{e}");
        }
    }
}

/// Parts of an assembly to draw or write (`stats --list-parts` lists them).
#[derive(Args, Debug, Clone, Default)]
pub struct PartArgs {
    /// Only these parts: a part name, an occurrence path or a leading part of it
    /// (`rod-assembly_1` keeps everything below it), or `#N` (index in `stats --list-parts`);
    /// `*` and `?` match as in file names. Repeat the flag or separate with commas.
    #[arg(long, value_delimiter = ',', value_name = "PART")]
    pub only: Vec<String>,
    /// Leave out these parts (same patterns as --only; applied after it).
    #[arg(long, value_delimiter = ',', value_name = "PART")]
    pub hide: Vec<String>,
}

impl PartArgs {
    /// `scene` with only the chosen parts; every pattern must name some instance, and
    /// something must be left.
    pub fn apply(&self, scene: Scene, file: &std::path::Path) -> Result<Scene, CliError> {
        if self.only.is_empty() && self.hide.is_empty() {
            return Ok(scene);
        }
        let named = |pattern: &str| -> Result<Vec<bool>, CliError> {
            let hits: Vec<bool> = (scene.instances.iter().enumerate())
                .map(|(i, inst)| patchwork::model::select::names(&scene, i, inst, pattern))
                .collect();
            if !hits.contains(&true) {
                return Err(CliError::NoSuchPart {
                    path: file.to_owned(),
                    pattern: pattern.to_owned(),
                });
            }
            Ok(hits)
        };
        let n = scene.instances.len();
        let mut keep = vec![self.only.is_empty(); n];
        for pattern in &self.only {
            for (k, hit) in keep.iter_mut().zip(named(pattern)?) {
                *k |= hit;
            }
        }
        for pattern in &self.hide {
            for (k, hit) in keep.iter_mut().zip(named(pattern)?) {
                *k &= !hit;
            }
        }
        scene
            .with_instances(&keep)
            .ok_or_else(|| CliError::NothingSelected {
                path: file.to_owned(),
            })
    }
}

/// Section planes (`render`, `implode`, `view`).
#[derive(Args, Debug, Clone, Default)]
pub struct SectionArgs {
    /// Cut the model with the plane through X,Y,Z with normal NX,NY,NZ: the side the normal
    /// points into is removed and the cut is capped in the part's colour (repeat for up to 3
    /// planes; the kept region is on the back side of all of them).
    #[arg(
        long = "section",
        value_name = "X,Y,Z,NX,NY,NZ",
        allow_hyphen_values = true
    )]
    pub sections: Vec<String>,
}

impl SectionArgs {
    /// The planes, each parsed and checked (six finite numbers, a normal that is not zero),
    /// at most [`Sections::MAX`].
    pub fn validate(&self) -> Result<Sections, CliError> {
        let planes = (self.sections.iter())
            .map(|s| s.parse::<SectionPlane>())
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Sections::new(&planes)?)
    }
}
