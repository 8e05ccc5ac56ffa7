//! Read-back images written as PNG files.

use std::path::{Path, PathBuf};

use caveclod_vulkan::RgbaImage;

/// Why [`write_png`] failed: the file, and the encoder's error (which carries I/O errors).
#[derive(Debug)]
pub struct PngWriteError {
    /// The file being written.
    pub path: PathBuf,
    /// Why.
    pub source: png::EncodingError,
}

impl std::fmt::Display for PngWriteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.source)
    }
}

impl std::error::Error for PngWriteError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.source)
    }
}

/// Writes `image` as an RGBA PNG at `path`, through a temporary file renamed into place, so
/// a reader never sees a partial image.
pub fn write_png(image: &RgbaImage, path: &Path) -> std::result::Result<(), PngWriteError> {
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let result = encode_png(image, &tmp).and_then(|()| Ok(std::fs::rename(&tmp, path)?));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|source| PngWriteError {
        path: path.to_path_buf(),
        source,
    })
}

/// Encodes `image` into a new file at `path` and syncs it.
fn encode_png(image: &RgbaImage, path: &Path) -> std::result::Result<(), png::EncodingError> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    {
        let mut enc = png::Encoder::new(&mut w, image.width, image.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&image.pixels)?;
        writer.finish()?;
    }
    let file = w.into_inner().map_err(|e| e.into_error())?;
    file.sync_all()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_through_a_temp_file() {
        let mut pixels = Vec::new();
        for y in 0..2u8 {
            for x in 0..3u8 {
                pixels.extend_from_slice(&[x * 80, y * 100, 7, 255]);
            }
        }
        let a = RgbaImage {
            width: 3,
            height: 2,
            pixels,
        };
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join("a.png");
        write_png(&a, &path).unwrap_or_else(|e| panic!("{e}"));
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&path).unwrap_or_else(|e| panic!("{e}")),
        ));
        let mut reader = decoder.read_info().unwrap_or_else(|e| panic!("{e}"));
        let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader
            .next_frame(&mut buf)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(&buf[..info.buffer_size()], &a.pixels[..]);
        assert!(!dir.path().join("a.png.tmp").exists());
    }

    #[test]
    fn a_png_into_a_missing_directory_names_the_file() {
        let a = RgbaImage {
            width: 1,
            height: 1,
            pixels: vec![0, 0, 0, 255],
        };
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let path = dir.path().join("missing").join("a.png");
        let e = write_png(&a, &path).err();
        assert!(e.as_ref().is_some_and(|e| e.path == path), "{e:?}");
        assert!(e.is_some_and(|e| e.to_string().contains("a.png")));
    }
}
