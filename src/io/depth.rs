//! Linear view-space depth as a 16-bit greyscale image (`patchwork render --depth-out`).
//!
//! The encoding is linear between the view's near and far planes: 0 = the near plane,
//! 65535 = the far plane; depths outside are clamped, and a non-finite depth (nothing drawn)
//! is the far plane. One step is `(far − near) / 65535` object units, so a decoded depth is
//! within half a step of the encoded one when it lies between the planes.
//!
//! Not done: a non-linear (reversed or logarithmic) encoding for more precision near the
//! camera. The image is written with [`super::png::write_gray16`].

use thiserror::Error;

/// A 16-bit greyscale image, as [`super::png::write_gray16`] writes it.
pub(crate) type Gray16Image = image::ImageBuffer<image::Luma<u16>, Vec<u16>>;

/// The largest encoded value: the far plane.
pub(crate) const FAR: u16 = u16::MAX;

/// Why a depth buffer could not be encoded.
#[derive(Debug, Error)]
pub enum DepthError {
    /// The buffer does not hold one depth per pixel.
    #[error("the depth buffer has {len} values for {width}×{height} pixels")]
    Length { len: usize, width: u32, height: u32 },
    /// Near and far do not bound a range (`near < far`, both finite).
    #[error("cannot encode depth between near {near} and far {far}")]
    Range { near: f64, far: f64 },
}

/// The depth range of an encoding: 0 at `near`, `FAR` at `far` (object units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthRange {
    pub near: f64,
    pub far: f64,
}

impl DepthRange {
    fn check(&self) -> Result<(), DepthError> {
        if self.near.is_finite() && self.far.is_finite() && self.near < self.far {
            Ok(())
        } else {
            Err(DepthError::Range {
                near: self.near,
                far: self.far,
            })
        }
    }

    /// One depth → its 16-bit value (clamped to the range; non-finite = far).
    pub(crate) fn encode_one(&self, z: f64) -> u16 {
        let t = if z.is_finite() {
            ((z - self.near) / (self.far - self.near)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        (t * f64::from(FAR)).round() as u16
    }

    /// One 16-bit value → the depth it stands for.
    pub(crate) fn decode_one(&self, v: u16) -> f64 {
        self.near + (self.far - self.near) * f64::from(v) / f64::from(FAR)
    }

    /// A row-major depth buffer (top row first, as [`crate::render::Frame::depth`]) → image.
    pub fn encode(
        &self,
        depth: &[f32],
        width: u32,
        height: u32,
    ) -> Result<Gray16Image, DepthError> {
        self.check()?;
        if depth.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(DepthError::Length {
                len: depth.len(),
                width,
                height,
            });
        }
        Ok(image::ImageBuffer::from_fn(width, height, |x, y| {
            let z = depth[(y * width + x) as usize];
            image::Luma([self.encode_one(f64::from(z))])
        }))
    }

    /// An encoded image → row-major depths (top row first).
    pub fn decode(&self, image: &Gray16Image) -> Vec<f64> {
        image.pixels().map(|p| self.decode_one(p[0])).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RANGE: DepthRange = DepthRange {
        near: 0.5,
        far: 20.0,
    };

    #[test]
    fn round_trip_is_within_half_a_step() {
        let (w, h) = (7, 5);
        let depth: Vec<f32> = (0..w * h)
            .map(|i| 0.5 + 19.5 * i as f32 / (w * h - 1) as f32)
            .collect();
        let img = RANGE.encode(&depth, w, h).expect("encodes");
        assert_eq!(img.dimensions(), (w, h));
        let step = (RANGE.far - RANGE.near) / f64::from(FAR);
        for (z, back) in depth.iter().zip(RANGE.decode(&img)) {
            assert!(
                (f64::from(*z) - back).abs() <= 0.5 * step + 1e-6,
                "{z} → {back}"
            );
        }
        assert_eq!(img.get_pixel(0, 0)[0], 0, "near plane");
        assert_eq!(img.get_pixel(w - 1, h - 1)[0], FAR, "far plane");
    }

    #[test]
    fn outside_and_missing_depths_clamp() {
        let img = RANGE
            .encode(&[0.0, 100.0, f32::INFINITY, f32::NAN], 2, 2)
            .expect("encodes");
        let v: Vec<u16> = img.pixels().map(|p| p[0]).collect();
        assert_eq!(v, [0, FAR, FAR, FAR]);
    }

    #[test]
    fn wrong_length_and_empty_range_are_errors() {
        assert!(matches!(
            RANGE.encode(&[1.0; 5], 2, 2),
            Err(DepthError::Length { len: 5, .. })
        ));
        let flat = DepthRange {
            near: 1.0,
            far: 1.0,
        };
        assert!(matches!(
            flat.encode(&[1.0], 1, 1),
            Err(DepthError::Range { .. })
        ));
    }
}
