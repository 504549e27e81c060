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
    pub fn from_dynamic(img: image::DynamicImage) -> Self {
        let rgb = img.into_rgb32f();
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
    let img = reader
        .decode()
        .map_err(|e| format!("corrupt or unsupported image: {e}"))?;
    let out = RgbImage::from_dynamic(img);
    if out.w < MIN_SIDE || out.h < MIN_SIDE {
        return Err(format!(
            "image too small ({}×{} px; at least {MIN_SIDE}×{MIN_SIDE} needed)",
            out.w, out.h
        ));
    }
    Ok(out)
}
