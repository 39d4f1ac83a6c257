//! Dataset image files: finding numbered files, decoding PNG/JPEG into flat pixel buffers, and the
//! resampling the readers need (nearest and bilinear resize, border crop).
//!
//! Decoders write into flat buffers (at most a raw-sample buffer and the typed result per image,
//! never an allocation per pixel). The `*_from_bytes` functions are pure; the `read_*` wrappers only
//! add the file read. Every error names the file and the reason.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use image::{ColorType, ImageDecoder, ImageReader};

use super::decode_guard::{png_chunk_problem, without_panics};
use crate::error::{CatmapError, Result};

/// Largest image this module decodes (8192 × 8192): guards allocations against corrupt headers.
pub const MAX_PIXELS: u64 = 1 << 26;

/// A row-major image: pixel `(u, v)` is `pixels[v * width + u]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image<T> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels, row-major.
    pub pixels: Vec<T>,
}

impl<T: Copy> Image<T> {
    /// `(width, height)`.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The image without a `border`-pixel frame on every side; `None` when the border leaves no pixel.
    pub fn crop_border(&self, border: u32) -> Option<Image<T>> {
        let width = self.width.checked_sub(border.checked_mul(2)?).filter(|&w| w > 0)?;
        let height = self.height.checked_sub(border * 2).filter(|&h| h > 0)?;
        let (w, b) = (self.width as usize, border as usize);
        let mut pixels = Vec::with_capacity(width as usize * height as usize);
        for row in self.pixels.chunks_exact(w).skip(b).take(height as usize) {
            pixels.extend_from_slice(row.get(b..b + width as usize)?);
        }
        (pixels.len() == width as usize * height as usize).then_some(Image { width, height, pixels })
    }
}

/// Renders `(width, height)` as `W×H` for messages.
pub fn size_text((width, height): (u32, u32)) -> String {
    format!("{width}×{height}")
}

/// Files in `dir` named `{prefix}{n}{suffix}` with `n` a decimal integer, sorted by `n` (so `2`
/// comes before `10`). Other names are skipped with one warning per folder.
pub fn numbered_files(dir: &Path, prefix: &str, suffix: &str) -> Result<Vec<(u64, PathBuf)>> {
    let entries = std::fs::read_dir(dir).map_err(|e| CatmapError::io(dir, e))?;
    let mut files = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| CatmapError::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let number = name.strip_prefix(prefix).and_then(|rest| rest.strip_suffix(suffix));
        match number
            .filter(|n| n.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|n| n.parse().ok())
        {
            Some(n) => files.push((n, entry.path())),
            None => skipped.push(name),
        }
    }
    if !skipped.is_empty() {
        skipped.sort();
        tracing::warn!(
            folder = %dir.display(),
            count = skipped.len(),
            first = %skipped[0],
            "skipping files not named {prefix}<number>{suffix}"
        );
    }
    files.sort();
    Ok(files)
}

fn image_error(path: &Path, reason: impl std::fmt::Display) -> CatmapError {
    CatmapError::Image {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| CatmapError::io(path, e))
}

/// Opens a decoder on `bytes` (format guessed from the content) and checks the size is sane.
fn decoder_of<'a>(bytes: &'a [u8], path: &Path) -> Result<(impl ImageDecoder + 'a, usize)> {
    if let Some(problem) = png_chunk_problem(bytes) {
        return Err(image_error(path, problem));
    }
    let reader = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| image_error(path, e))?;
    let decoder = reader.into_decoder().map_err(|e| image_error(path, e))?;
    let pixel_count = checked_pixel_count(decoder.dimensions(), path)?;
    Ok((decoder, pixel_count))
}

/// The pixel count of an image of `size`, refused when zero or above [`MAX_PIXELS`] (before
/// anything of that size is allocated).
fn checked_pixel_count((width, height): (u32, u32), path: &Path) -> Result<usize> {
    let pixel_count = u64::from(width) * u64::from(height);
    if pixel_count == 0 || pixel_count > MAX_PIXELS {
        let reason = format!(
            "is {} pixels, expected 1 to {MAX_PIXELS} pixels",
            size_text((width, height))
        );
        return Err(image_error(path, reason));
    }
    usize::try_from(pixel_count).map_err(|e| image_error(path, e))
}

/// Decodes an 8- or 16-bit single-channel image into values of `T` (any type holding a `u16`,
/// e.g. `f32` for depth that is then converted in place).
pub fn grey_from_bytes_as<T: From<u16>>(bytes: &[u8], path: &Path) -> Result<Image<T>> {
    without_panics(|| decode_grey(bytes, path)).map_err(|e| image_error(path, e))?
}

fn decode_grey<T: From<u16>>(bytes: &[u8], path: &Path) -> Result<Image<T>> {
    let (decoder, n) = decoder_of(bytes, path)?;
    let (width, height) = decoder.dimensions();
    let pixels = match decoder.color_type() {
        ColorType::L8 => {
            let mut raw = vec![0u8; n];
            decoder.read_image(&mut raw).map_err(|e| image_error(path, e))?;
            raw.into_iter().map(|v| T::from(u16::from(v))).collect()
        }
        ColorType::L16 => {
            // The decoder returns 16-bit samples in native byte order.
            let mut raw = vec![[0u8; 2]; n];
            decoder
                .read_image(raw.as_flattened_mut())
                .map_err(|e| image_error(path, e))?;
            raw.into_iter().map(|b| T::from(u16::from_ne_bytes(b))).collect()
        }
        other => {
            let reason = format!("expected an 8- or 16-bit single-channel image, found {other:?}");
            return Err(image_error(path, reason));
        }
    };
    Ok(Image { width, height, pixels })
}

/// Decodes an 8- or 16-bit single-channel image into unsigned values (class or instance ids).
pub fn grey_from_bytes(bytes: &[u8], path: &Path) -> Result<Image<u32>> {
    grey_from_bytes_as(bytes, path)
}

/// Decodes an 8- or 16-bit single-channel image into `u16` values (raw depth).
pub fn grey16_from_bytes(bytes: &[u8], path: &Path) -> Result<Image<u16>> {
    grey_from_bytes_as(bytes, path)
}

/// Decodes an 8-bit RGB image (PNG or JPEG); RGBA drops alpha, grey is replicated to RGB.
pub fn rgb_from_bytes(bytes: &[u8], path: &Path) -> Result<Image<[u8; 3]>> {
    without_panics(|| decode_rgb(bytes, path)).map_err(|e| image_error(path, e))?
}

fn decode_rgb(bytes: &[u8], path: &Path) -> Result<Image<[u8; 3]>> {
    let (decoder, n) = decoder_of(bytes, path)?;
    let (width, height) = decoder.dimensions();
    let pixels = match decoder.color_type() {
        ColorType::Rgb8 => {
            let mut rgb = vec![[0u8; 3]; n];
            decoder
                .read_image(rgb.as_flattened_mut())
                .map_err(|e| image_error(path, e))?;
            rgb
        }
        ColorType::Rgba8 => {
            let mut rgba = vec![[0u8; 4]; n];
            decoder
                .read_image(rgba.as_flattened_mut())
                .map_err(|e| image_error(path, e))?;
            rgba.into_iter().map(|[r, g, b, _]| [r, g, b]).collect()
        }
        ColorType::L8 => {
            let mut grey = vec![0u8; n];
            decoder.read_image(&mut grey).map_err(|e| image_error(path, e))?;
            grey.into_iter().map(|l| [l; 3]).collect()
        }
        other => {
            return Err(image_error(
                path,
                format!("expected an 8-bit RGB or RGBA image, found {other:?}"),
            ));
        }
    };
    Ok(Image { width, height, pixels })
}

/// Reads and decodes a single-channel image file into `u32` values.
pub fn read_grey(path: &Path) -> Result<Image<u32>> {
    grey_from_bytes(&read_bytes(path)?, path)
}

/// Reads and decodes a single-channel image file into `u16` values.
pub fn read_grey16(path: &Path) -> Result<Image<u16>> {
    grey16_from_bytes(&read_bytes(path)?, path)
}

/// Reads and decodes a single-channel image file into values of `T`.
pub fn read_grey_as<T: From<u16>>(path: &Path) -> Result<Image<T>> {
    grey_from_bytes_as(&read_bytes(path)?, path)
}

/// Reads and decodes an RGB(A) image file.
pub fn read_rgb(path: &Path) -> Result<Image<[u8; 3]>> {
    rgb_from_bytes(&read_bytes(path)?, path)
}

/// Width and height of an image file, reading only its header.
pub fn read_size(path: &Path) -> Result<(u32, u32)> {
    let reader = ImageReader::open(path).map_err(|e| CatmapError::io(path, e))?;
    let reader = reader.with_guessed_format().map_err(|e| image_error(path, e))?;
    let size = reader.into_dimensions().map_err(|e| image_error(path, e))?;
    // Found by the ScanNet folder fuzzer: a header claiming 32×4 278 190 108 pixels made the
    // reader allocate 100 GB for the cropped camera and abort.
    checked_pixel_count(size, path)?;
    Ok(size)
}

/// Fails unless `image` is `expected` in size; `what` completes "… but {what} is W×H".
pub fn require_size<T: Copy>(image: &Image<T>, expected: (u32, u32), path: &Path, what: &str) -> Result<()> {
    if image.size() == expected {
        return Ok(());
    }
    let reason = format!(
        "is {} pixels, but {what} is {}",
        size_text(image.size()),
        size_text(expected)
    );
    Err(image_error(path, reason))
}

/// Checks depth-conversion options: a positive finite scale and a positive maximum depth.
pub fn check_depth_options(depth_scale: f32, max_depth_m: f32) -> Result<()> {
    if !depth_scale.is_finite() || depth_scale <= 0.0 {
        return Err(CatmapError::ConfigValue(format!(
            "depth_scale must be positive and finite, got {depth_scale}"
        )));
    }
    if max_depth_m.is_nan() || max_depth_m <= 0.0 {
        return Err(CatmapError::ConfigValue(format!(
            "max_depth_m must be positive, got {max_depth_m}"
        )));
    }
    Ok(())
}

/// Raw depth values to metres, in place: `raw / depth_scale`; 0 stays 0 (invalid) and depth
/// beyond `max_depth_m` becomes 0 (invalid), as vMAP's `DepthFilter` does.
pub fn depth_to_metres_in_place(depth: &mut [f32], depth_scale: f32, max_depth_m: f32) {
    for value in depth {
        let depth_m = *value / depth_scale;
        *value = if depth_m > max_depth_m { 0.0 } else { depth_m };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(width: u32, height: u32) -> Image<u32> {
        Image {
            width,
            height,
            pixels: (0..width * height).collect(),
        }
    }

    #[test]
    fn crop_border_removes_a_frame_on_every_side() {
        let cropped = ramp(5, 4).crop_border(1).expect("3×2 remain");
        assert_eq!(cropped.size(), (3, 2));
        assert_eq!(cropped.pixels, [6, 7, 8, 11, 12, 13]);
        assert_eq!(
            ramp(4, 4).crop_border(2),
            None,
            "a border of half the side leaves nothing"
        );
    }

    #[test]
    fn sixteen_bit_png_round_trips() {
        let values: Vec<u16> = vec![0, 1, 1000, 65535, 300, 7];
        let png = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(3, 2, values.clone()).expect("3×2");
        let mut bytes = Vec::new();
        png.write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
            .expect("encode");
        let decoded = grey16_from_bytes(&bytes, Path::new("x.png")).expect("decode");
        assert_eq!(decoded.pixels, values);
    }

    #[test]
    fn random_bytes_are_an_image_error_naming_the_file() {
        let err = grey_from_bytes(&[0x13, 0x37, 0, 1, 2, 3, 4, 5], Path::new("bad.png")).expect_err("not an image");
        assert!(err.to_string().contains("bad.png: bad image:"), "{err}");
    }
}
