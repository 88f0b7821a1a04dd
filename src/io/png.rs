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
    /// An image file name whose extension says another format: PNG bytes would be written
    /// under a name that promises something else.
    #[error("{}: patchwork writes PNG images; name the file .png, not .{extension}", .path.display())]
    NotPng { path: PathBuf, extension: String },
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

/// Writes bytes (a cache file) atomically, like the images.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|source| WriteError::Io {
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
    if let Some(e) = path.extension()
        && !e.eq_ignore_ascii_case("png")
    {
        return Err(WriteError::NotPng {
            path: path.to_owned(),
            extension: e.to_string_lossy().into_owned(),
        });
    }
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

/// An animated GIF written frame by frame to a temporary name and renamed by
/// [`GifWriter::finish`]; dropped unfinished, it removes the temporary file.
pub struct GifWriter {
    path: PathBuf,
    tmp: PathBuf,
    encoder: Option<image::codecs::gif::GifEncoder<std::io::BufWriter<std::fs::File>>>,
    delay_ms: u32,
}

impl GifWriter {
    /// Starts `path`, showing every frame for `delay_ms` and looping forever.
    pub fn create(path: &Path, delay_ms: u32) -> Result<GifWriter, WriteError> {
        let tmp = temp_name(path);
        let file = std::fs::File::create(&tmp).map_err(|source| WriteError::Io {
            path: path.to_owned(),
            source,
        })?;
        // Speed 10 of 30: NeuQuant sampling every 10th pixel, a good trade for renders.
        let mut encoder =
            image::codecs::gif::GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
        let mut writer = GifWriter {
            path: path.to_owned(),
            tmp,
            encoder: None,
            delay_ms,
        };
        encoder
            .set_repeat(image::codecs::gif::Repeat::Infinite)
            .map_err(|e| encode_err(path, e))?;
        writer.encoder = Some(encoder);
        Ok(writer)
    }

    /// Appends a frame.
    pub fn add(&mut self, image: &image::RgbaImage) -> Result<(), WriteError> {
        let (width, height) = image.dimensions();
        if width == 0 || height == 0 {
            return Err(WriteError::EmptyImage {
                path: self.path.clone(),
                width,
                height,
            });
        }
        let Some(encoder) = self.encoder.as_mut() else {
            return Ok(());
        };
        let frame = image::Frame::from_parts(
            image.clone(),
            0,
            0,
            image::Delay::from_numer_denom_ms(self.delay_ms, 1),
        );
        encoder
            .encode_frame(frame)
            .map_err(|e| encode_err(&self.path, e))
    }

    /// Ends the file (the encoder writes the trailer and flushes when dropped), makes sure it
    /// reached the disk and renames it to its final name.
    pub fn finish(mut self) -> Result<(), WriteError> {
        drop(self.encoder.take());
        let io = |source| WriteError::Io {
            path: self.path.clone(),
            source,
        };
        std::fs::File::open(&self.tmp)
            .and_then(|f| f.sync_all())
            .map_err(io)?;
        std::fs::rename(&self.tmp, &self.path).map_err(io)
    }
}

impl std::fmt::Debug for GifWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GifWriter")
            .field("path", &self.path)
            .field("delay_ms", &self.delay_ms)
            .finish_non_exhaustive()
    }
}

impl Drop for GifWriter {
    fn drop(&mut self) {
        // Unfinished (or failed): leave nothing behind.
        self.encoder.take();
        let _ = std::fs::remove_file(&self.tmp);
    }
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

    /// `render -o x.jpg` used to write PNG bytes under a .jpg name; now nothing is written.
    #[test]
    fn a_name_promising_another_format_is_refused() {
        let dir = std::env::temp_dir().join(format!("patchwork-notpng-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let img = image::RgbaImage::new(4, 4);
        for name in ["x.jpg", "x.JPEG", "x.gif"] {
            let path = dir.join(name);
            let e = write_rgba(&path, &img).expect_err(name).to_string();
            assert!(e.contains("writes PNG images"), "{e}");
            assert!(!path.exists());
        }
        for name in ["x.png", "x.PNG", "no-extension"] {
            let path = dir.join(name);
            write_rgba(&path, &img).expect(name);
            assert!(path.is_file());
        }
        let _ = std::fs::remove_dir_all(&dir);
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
    fn gif_is_written_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("patchwork-gif-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("a.gif");
        let mut gif = GifWriter::create(&path, 40).expect("create");
        for k in 0..3u8 {
            gif.add(&image::RgbaImage::from_pixel(
                4,
                3,
                image::Rgba([k * 80, 0, 0, 255]),
            ))
            .expect("frame");
        }
        assert!(!path.exists(), "visible before finish");
        gif.finish().expect("finish");
        let frames = {
            use image::AnimationDecoder;
            let file = std::io::BufReader::new(std::fs::File::open(&path).expect("open"));
            image::codecs::gif::GifDecoder::new(file)
                .expect("decode")
                .into_frames()
                .count()
        };
        assert_eq!(frames, 3);
        // Dropped unfinished: nothing.
        let other = dir.join("b.gif");
        let mut gif = GifWriter::create(&other, 40).expect("create");
        gif.add(&image::RgbaImage::new(4, 3)).expect("frame");
        drop(gif);
        assert!(!other.exists());
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 1);
        let _ = std::fs::remove_dir_all(&dir);
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
