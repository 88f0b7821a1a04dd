//! PNG, GIF, CSV and cache output, through [`super::atomic`]: written to a temporary name in
//! the same directory, every write, flush and sync checked, and renamed, so a failed run (a
//! full disk, a signal) never leaves a half-written file behind nor touches the previous one.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::atomic::AtomicFile;

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

/// Writes through an [`AtomicFile`]: `encode` writes the bytes, then the file is flushed,
/// synced and renamed over `path` (every step checked; on error the temporary file goes and
/// the previous file stays).
fn write_atomic(
    path: &Path,
    encode: impl FnOnce(&mut AtomicFile) -> Result<(), WriteError>,
) -> Result<(), WriteError> {
    let io = |source| WriteError::Io {
        path: path.to_owned(),
        source,
    };
    let mut file = AtomicFile::create(path).map_err(io)?;
    encode(&mut file)?;
    file.commit().map_err(io)
}

/// Writes a text file (a CSV) atomically, like the images.
pub fn write_text(path: &Path, text: &str) -> Result<(), WriteError> {
    write_bytes(path, text.as_bytes())
}

/// Writes bytes (a cache file) atomically, like the images.
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic(path, |file| {
        file.write_all(bytes).map_err(|source| WriteError::Io {
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
pub(crate) fn write_png<P>(
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
    write_atomic(path, |file| {
        image
            .write_with_encoder(image::codecs::png::PngEncoder::new(file))
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
    encoder: Option<gif::Encoder<AtomicFile>>,
    /// The temporary file until the first frame fixes the GIF's size.
    file: Option<AtomicFile>,
    /// Width and height, fixed by the first frame.
    size: (u16, u16),
    delay_ms: u32,
}

impl GifWriter {
    /// Starts `path`, showing every frame for `delay_ms` and looping forever.
    pub fn create(path: &Path, delay_ms: u32) -> Result<GifWriter, WriteError> {
        let file = AtomicFile::create(path).map_err(|source| WriteError::Io {
            path: path.to_owned(),
            source,
        })?;
        Ok(GifWriter {
            path: path.to_owned(),
            encoder: None,
            file: Some(file),
            size: (0, 0),
            delay_ms,
        })
    }

    fn gif_err(&self, e: gif::EncodingError) -> WriteError {
        match e {
            gif::EncodingError::Io(source) => WriteError::Io {
                path: self.path.clone(),
                source,
            },
            other => WriteError::Encode {
                path: self.path.clone(),
                reason: other.to_string(),
            },
        }
    }

    /// Appends a frame (every frame must have the first one's size).
    pub fn add(&mut self, image: &image::RgbaImage) -> Result<(), WriteError> {
        let (width, height) = image.dimensions();
        let size = (u16::try_from(width), u16::try_from(height));
        let (Ok(w), Ok(h)) = size else {
            return Err(WriteError::Encode {
                path: self.path.clone(),
                reason: format!("a GIF frame is at most 65535x65535, not {width}x{height}"),
            });
        };
        if w == 0 || h == 0 {
            return Err(WriteError::EmptyImage {
                path: self.path.clone(),
                width,
                height,
            });
        }
        if let Some(file) = self.file.take() {
            let started = gif::Encoder::new(file, w, h, &[])
                .and_then(|mut e| e.set_repeat(gif::Repeat::Infinite).map(|()| e));
            self.encoder = Some(started.map_err(|e| self.gif_err(e))?);
            self.size = (w, h);
        }
        let Some(encoder) = self.encoder.as_mut() else {
            return Err(WriteError::Encode {
                path: self.path.clone(),
                reason: "the GIF failed earlier".to_owned(),
            });
        };
        if self.size != (w, h) {
            return Err(WriteError::Encode {
                path: self.path.clone(),
                reason: format!(
                    "frame of {width}x{height} in a GIF of {}x{}",
                    self.size.0, self.size.1
                ),
            });
        }
        let mut pixels = image.as_raw().clone();
        // Speed 10 of 30: NeuQuant sampling every 10th pixel, a good trade for renders.
        let mut frame = gif::Frame::from_rgba_speed(w, h, &mut pixels, 10);
        frame.delay = u16::try_from(self.delay_ms / 10).unwrap_or(u16::MAX);
        frame.dispose = gif::DisposalMethod::Background;
        let written = encoder.write_frame(&frame);
        written.map_err(|e| self.gif_err(e))
    }

    /// Ends the file (the trailer), makes sure it reached the disk and renames it to its
    /// final name; every step checked.
    pub fn finish(mut self) -> Result<(), WriteError> {
        let file = match (self.encoder.take(), self.file.take()) {
            (Some(encoder), _) => encoder.into_inner().map_err(|e| self.gif_err(e))?,
            (None, _) => {
                return Err(WriteError::EmptyImage {
                    path: self.path.clone(),
                    width: 0,
                    height: 0,
                });
            }
        };
        file.commit().map_err(|source| WriteError::Io {
            path: self.path.clone(),
            source,
        })
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
        let _ = std::fs::remove_file(&path);
    }
}
