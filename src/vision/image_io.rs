//! Decoding photographs (JPEG, PNG, TIFF; 8 or 16 bit per channel) into RGB `f32` in `[0, 1]`.

use std::path::Path;

/// An RGB image, interleaved, values in `[0, 1]`.
#[derive(Debug, Clone)]
pub struct RgbImage {
    pub w: usize,
    pub h: usize,
    pub data: Vec<f32>,
}

impl RgbImage {
    #[inline]
    pub fn px(&self, x: usize, y: usize) -> [f32; 3] {
        let i = 3 * (y * self.w + x);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Converts a decoded image (any bit depth, grey or colour) to RGB `f32`.
    ///
    /// 8-bit RGB, what JPEG and most PNG photos decode to, is divided by 255 in one vectorised
    /// pass: `image`'s own conversion to the bit, in a fifth of the time of its generic
    /// per-pixel path (a 2400×1600 photo: some 20 ms of its 40 ms decode). A 256-entry table
    /// of the same values took about as long (3.9 % against 3.5 % of eight clean photos'
    /// time, session 35): both are bound by writing the 46 MB.
    pub fn from_dynamic(img: &image::DynamicImage) -> Self {
        if let image::DynamicImage::ImageRgb8(buf) = img {
            return Self {
                w: buf.width() as usize,
                h: buf.height() as usize,
                data: buf.as_raw().iter().map(|&v| f32::from(v) / 255.0).collect(),
            };
        }
        let rgb = img.to_rgb32f();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        Self {
            w,
            h,
            data: rgb.into_raw(),
        }
    }
}

/// Smallest image side that can hold a ball, a streak and a background.
pub const MIN_SIDE: usize = 32;

/// Reads and decodes an image file; the error is a human-readable reason for the table.
pub fn load(path: &Path) -> Result<RgbImage, String> {
    convert(&decode(path)?)
}

/// Reads and decodes an image file, as its decoder gives it (8 or 16 bits, grey or colour):
/// the first half of [`load`].
pub fn decode(path: &Path) -> Result<image::DynamicImage, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read file: {e}"))?;
    if meta.len() == 0 {
        return Err("empty file (0 bytes)".into());
    }
    let reader = image::ImageReader::open(path)
        .map_err(|e| format!("cannot open file: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read file: {e}"))?;
    if reader.format().is_none() {
        return Err("not a recognised image format (JPEG, PNG or TIFF expected)".into());
    }
    // The JPEG decoder fills a truncated file's missing rows with grey instead of failing; a
    // complete JPEG ends with the end-of-image marker FF D9 (possibly followed by padding).
    if reader.format() == Some(image::ImageFormat::Jpeg) && !jpeg_is_complete(path)? {
        return Err("corrupt image: truncated JPEG (no end-of-image marker)".into());
    }
    reader
        .decode()
        .map_err(|e| format!("corrupt or unsupported image: {e}"))
}

/// A decoded image as RGB `f32`, refused when too small to hold a shot: the second half of
/// [`load`].
pub fn convert(img: &image::DynamicImage) -> Result<RgbImage, String> {
    let out = RgbImage::from_dynamic(img);
    if out.w < MIN_SIDE || out.h < MIN_SIDE {
        return Err(format!(
            "image too small ({}×{} px; at least {MIN_SIDE}×{MIN_SIDE} needed)",
            out.w, out.h
        ));
    }
    Ok(out)
}

/// True if the JPEG file ends with the end-of-image marker, allowing trailing padding bytes.
fn jpeg_is_complete(path: &Path) -> Result<bool, String> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = std::fs::File::open(path).map_err(|e| format!("cannot open file: {e}"))?;
    let len = f
        .metadata()
        .map_err(|e| format!("cannot read file: {e}"))?
        .len();
    let tail = len.min(4096);
    f.seek(SeekFrom::Start(len - tail))
        .map_err(|e| format!("cannot read file: {e}"))?;
    let mut buf = Vec::with_capacity(tail as usize);
    f.read_to_end(&mut buf)
        .map_err(|e| format!("cannot read file: {e}"))?;
    let end = buf
        .iter()
        .rposition(|&b| b != 0x00 && b != 0xFF)
        .map_or(0, |i| i + 1);
    // `end` points past the last byte that is not padding; the marker is FF D9 ending there.
    Ok(end >= 2 && buf[end - 1] == 0xD9 && buf[end - 2] == 0xFF)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 8-bit path gives `image`'s own conversion to the bit, for every value and channel.
    #[test]
    fn eight_bit_rgb_converts_as_image_does() {
        let raw: Vec<u8> = (0..=255u8).flat_map(|v| [v, 255 - v, v / 3]).collect();
        let buf = image::RgbImage::from_raw(16, 16, raw).unwrap();
        let dynamic = image::DynamicImage::ImageRgb8(buf);
        let ours = RgbImage::from_dynamic(&dynamic);
        let theirs = dynamic.into_rgb32f();
        assert_eq!((ours.w, ours.h), (16, 16));
        let same = ours
            .data
            .iter()
            .zip(theirs.as_raw())
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "8-bit conversion differs from image's");
        assert_eq!(ours.data[3 * 255].to_bits(), 1.0f32.to_bits());
    }
}
