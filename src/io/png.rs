//! PNG output, written to a temporary name in the same directory and renamed, so a failed run
//! never leaves a half-written image behind.

use std::path::{Path, PathBuf};

use thiserror::Error;

/// Why an image could not be written.
#[derive(Debug, Error)]
pub enum WriteError {
    #[error("{}: cannot write an image of size {width}x{height}", .path.display())]
    EmptyImage {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    #[error("{}: cannot write: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: cannot encode PNG: {reason}", .path.display())]
    Encode { path: PathBuf, reason: String },
}

/// The temporary name used while `path` is being written.
fn temp_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes encoded bytes atomically (temporary file + rename).
fn write_atomic(
    path: &Path,
    encode: impl FnOnce(&Path) -> Result<(), WriteError>,
) -> Result<(), WriteError> {
    let tmp = temp_name(path);
    let result = encode(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path).map_err(|source| WriteError::Io {
            path: path.to_owned(),
            source,
        })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes a text file (a CSV) atomically, like the images.
pub fn write_text(path: &Path, text: &str) -> Result<(), WriteError> {
    write_atomic(path, |tmp| {
        std::fs::write(tmp, text).map_err(|source| WriteError::Io {
            path: path.to_owned(),
            source,
        })
    })
}

fn encode_err(path: &Path, e: image::ImageError) -> WriteError {
    match e {
        image::ImageError::IoError(source) => WriteError::Io {
            path: path.to_owned(),
            source,
        },
        other => WriteError::Encode {
            path: path.to_owned(),
            reason: other.to_string(),
        },
    }
}

/// Writes any 8- or 16-bit image buffer as PNG, atomically.
pub fn write_png<P>(
    path: &Path,
    image: &image::ImageBuffer<P, Vec<P::Subpixel>>,
) -> Result<(), WriteError>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
{
    let (width, height) = image.dimensions();
    if width == 0 || height == 0 {
        return Err(WriteError::EmptyImage {
            path: path.to_owned(),
            width,
            height,
        });
    }
    write_atomic(path, |tmp| {
        image
            .save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| encode_err(path, e))
    })
}

/// Writes an 8-bit RGBA image as PNG.
pub fn write_rgba(path: &Path, image: &image::RgbaImage) -> Result<(), WriteError> {
    write_png(path, image)
}

/// Writes a 16-bit greyscale PNG.
pub fn write_gray16(
    path: &Path,
    image: &image::ImageBuffer<image::Luma<u16>, Vec<u16>>,
) -> Result<(), WriteError> {
    write_png(path, image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("patchwork-png-{}", std::process::id()));
        let path = dir.join("missing-subdir").join("x.png");
        let img = image::RgbaImage::new(4, 4);
        assert!(matches!(
            write_rgba(&path, &img),
            Err(WriteError::Io { .. })
        ));
        assert!(!path.exists());
    }

    #[test]
    fn zero_size_is_an_error() {
        let path = std::env::temp_dir().join("patchwork-zero.png");
        let img = image::RgbaImage::new(0, 3);
        assert!(matches!(
            write_rgba(&path, &img),
            Err(WriteError::EmptyImage { .. })
        ));
    }

    #[test]
    fn writes_and_renames() {
        let path = std::env::temp_dir().join(format!("patchwork-ok-{}.png", std::process::id()));
        let img = image::RgbaImage::from_pixel(3, 2, image::Rgba([1, 2, 3, 255]));
        write_rgba(&path, &img).expect("write");
        let back = image::open(&path).expect("read").to_rgba8();
        assert_eq!(back, img);
        assert!(!temp_name(&path).exists());
        let _ = std::fs::remove_file(&path);
    }
}
