//! Decoding photographs (JPEG, PNG, TIFF; 8 or 16 bit per channel) into RGB in `[0, 1]`.
//!
//! An 8-bit colour photo (what JPEG and most PNG photos decode to) is kept as its decoder's
//! bytes and converted where read, by [`unit`]; grey and 16-bit photos are converted to `f32`
//! once. Every reader
//! goes through [`Px`], so both give the same `f32` values to the bit. A `f32` copy of a
//! 2400×1600 photo is 46 MB written and read back whole by the block means, where the bytes are
//! 11.5 MB already in memory (session 36: the conversion, its fresh pages and the page zeroing
//! were some 8 % of a clean photo's time).

use std::path::Path;

/// An 8-bit sample as the photo's value in `[0, 1]`: `image`'s own conversion to the bit.
#[inline(always)]
pub fn unit(v: u8) -> f32 {
    f32::from(v) / 255.0
}

/// A photo's samples, interleaved RGB, row by row.
#[derive(Debug, Clone)]
pub enum Samples {
    /// 8-bit samples as decoded; each stands for [`unit`] of itself.
    U8(Vec<u8>),
    /// Samples in `[0, 1]` (16-bit and grey photos, and photos changed after decoding).
    F32(Vec<f32>),
}

impl Samples {
    #[inline]
    pub fn view(&self) -> Px<'_> {
        match self {
            Samples::U8(v) => Px::U8(v),
            Samples::F32(v) => Px::F32(v),
        }
    }
}

/// A borrowed view of [`Samples`]: what the readers of a photo take.
#[derive(Debug, Clone, Copy)]
pub enum Px<'a> {
    U8(&'a [u8]),
    F32(&'a [f32]),
}

impl<'a> Px<'a> {
    /// Sample `k` in `[0, 1]`.
    #[inline(always)]
    pub fn at(self, k: usize) -> f32 {
        match self {
            Px::U8(v) => unit(v[k]),
            Px::F32(v) => v[k],
        }
    }

    /// Number of samples (three per pixel).
    pub fn len(self) -> usize {
        match self {
            Px::U8(v) => v.len(),
            Px::F32(v) => v.len(),
        }
    }

    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// Samples `a..b` as `f32`: borrowed when they are `f32` already, else converted into
    /// `out`.
    #[inline]
    pub fn span<'r>(self, a: usize, b: usize, out: &'r mut Vec<f32>) -> &'r [f32]
    where
        'a: 'r,
    {
        match self {
            Px::F32(v) => &v[a..b],
            Px::U8(_) => {
                self.span_into(a, b, out);
                out
            }
        }
    }

    /// Samples `a..b` as `f32`, into `out` (resized to hold them).
    #[inline]
    pub fn span_into(self, a: usize, b: usize, out: &mut Vec<f32>) {
        out.clear();
        match self {
            Px::F32(v) => out.extend_from_slice(&v[a..b]),
            Px::U8(v) => out.extend(v[a..b].iter().map(|&x| unit(x))),
        }
    }
}

/// An RGB image, interleaved, values in `[0, 1]` (see [`Samples`]).
#[derive(Debug, Clone)]
pub struct RgbImage {
    pub w: usize,
    pub h: usize,
    pub data: Samples,
}

impl RgbImage {
    /// An image of `f32` samples.
    pub fn from_f32(w: usize, h: usize, data: Vec<f32>) -> Self {
        assert_eq!(
            data.len(),
            3 * w * h,
            "{w}×{h} RGB needs {} samples",
            3 * w * h
        );
        Self {
            w,
            h,
            data: Samples::F32(data),
        }
    }

    /// The samples, for reading.
    #[inline]
    pub fn samples(&self) -> Px<'_> {
        self.data.view()
    }

    #[inline]
    pub fn px(&self, x: usize, y: usize) -> [f32; 3] {
        let (i, s) = (3 * (y * self.w + x), self.samples());
        [s.at(i), s.at(i + 1), s.at(i + 2)]
    }

    /// Bytes the samples take in memory.
    pub fn byte_len(&self) -> usize {
        match &self.data {
            Samples::U8(v) => v.len(),
            Samples::F32(v) => 4 * v.len(),
        }
    }

    /// The samples as `f32`, for changing them (bytes are converted first, once).
    pub fn f32_mut(&mut self) -> &mut Vec<f32> {
        if let Samples::U8(v) = &self.data {
            self.data = Samples::F32(v.iter().map(|&x| unit(x)).collect());
        }
        match &mut self.data {
            Samples::F32(v) => v,
            Samples::U8(_) => unreachable!("converted above"),
        }
    }

    /// Takes a decoded image (any bit depth, grey or colour). 8-bit RGB keeps its decoder's
    /// buffer, without a copy; 8-bit RGBA is made RGB bytes by `image` (alpha dropped: the
    /// same values its `f32` conversion gives); anything else is converted to RGB `f32` by
    /// `image` (grey among them: its conversion of a grey byte is not `unit`'s to the bit).
    /// Whichever way, a photo reads the values `image` converts it to.
    pub fn from_dynamic(img: image::DynamicImage) -> Self {
        use image::DynamicImage as D;
        let (w, h) = (img.width() as usize, img.height() as usize);
        let data = match img {
            D::ImageRgb8(buf) => return buf.into(),
            D::ImageRgba8(_) => Samples::U8(img.into_rgb8().into_raw()),
            other => Samples::F32(other.into_rgb32f().into_raw()),
        };
        Self { w, h, data }
    }
}

/// An 8-bit RGB buffer (a decoder's, or a rendering's) kept as it is, without a copy.
impl From<image::RgbImage> for RgbImage {
    fn from(buf: image::RgbImage) -> Self {
        Self {
            w: buf.width() as usize,
            h: buf.height() as usize,
            data: Samples::U8(buf.into_raw()),
        }
    }
}

/// Smallest image side that can hold a ball, a streak and a background.
pub const MIN_SIDE: usize = 32;

/// Reads and decodes an image file, 8-bit photos kept as their bytes ([`Samples`]); the error
/// is a human-readable reason for the table.
pub fn load(path: &Path) -> Result<RgbImage, String> {
    convert(decode(path)?)
}

/// Reads and decodes an image file, as its decoder gives it (8 or 16 bits, grey or colour):
/// the first half of [`load`].
fn decode(path: &Path) -> Result<image::DynamicImage, String> {
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

/// A decoded image as an [`RgbImage`], refused when too small to hold a shot: the second half
/// of [`load`].
fn convert(img: image::DynamicImage) -> Result<RgbImage, String> {
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

    /// Kept bytes read as `image`'s own conversion to `f32`, to the bit, for every value and
    /// channel, whichever way they are read; the bytes are the decoder's, not a copy.
    #[test]
    fn eight_bit_rgb_reads_as_image_converts() {
        let raw: Vec<u8> = (0..=255u8).flat_map(|v| [v, 255 - v, v / 3]).collect();
        let buf = image::RgbImage::from_raw(16, 16, raw).unwrap();
        let dynamic = image::DynamicImage::ImageRgb8(buf);
        let theirs = dynamic.to_rgb32f().into_raw();
        let ptr = dynamic.as_bytes().as_ptr();
        let mut ours = RgbImage::from_dynamic(dynamic);
        assert_eq!((ours.w, ours.h), (16, 16));
        let Samples::U8(bytes) = &ours.data else {
            panic!("8-bit RGB is kept as bytes");
        };
        assert_eq!(bytes.as_ptr(), ptr, "the decoder's buffer, not a copy");
        let s = ours.samples();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let by_one: Vec<f32> = (0..s.len()).map(|k| s.at(k)).collect();
        assert_eq!(bits(&by_one), bits(&theirs));
        let mut buf = Vec::new();
        assert_eq!(bits(s.span(3, 300, &mut buf)), bits(&theirs[3..300]));
        assert_eq!(
            ours.px(15, 15).map(f32::to_bits),
            [0, 1, 2].map(|c| theirs[765 + c].to_bits())
        );
        assert_eq!(s.at(3 * 255).to_bits(), 1.0f32.to_bits());
        assert_eq!(bits(ours.f32_mut()), bits(&theirs));
        assert!(matches!(ours.data, Samples::F32(_)));
    }

    /// An 8-bit RGBA image is kept as RGB bytes that read as `image`'s `f32` conversion, to the
    /// bit; a grey one, whose conversion differs from `unit` in the last bit for some values,
    /// is converted by `image` and reads the same.
    #[test]
    fn other_eight_bit_layouts_read_as_image_converts() {
        use image::{DynamicImage as D, ImageBuffer};
        let v = |i: u32| ((i * 37 + 11) % 256) as u8;
        let images = [
            D::ImageRgba8(ImageBuffer::from_fn(16, 16, |x, y| {
                let i = x + 16 * y;
                image::Rgba([v(i), v(i + 1), v(i + 2), v(i + 3)])
            })),
            D::ImageLuma8(ImageBuffer::from_fn(16, 16, |x, y| {
                image::Luma([v(x + 16 * y)])
            })),
            D::ImageLumaA8(ImageBuffer::from_fn(16, 16, |x, y| {
                image::LumaA([v(x + 16 * y), v(3 * x + y)])
            })),
        ];
        for (img, bytes) in images.into_iter().zip([true, false, false]) {
            let kind = img.color();
            let theirs = img.to_rgb32f().into_raw();
            let ours = RgbImage::from_dynamic(img);
            assert_eq!(matches!(ours.data, Samples::U8(_)), bytes, "{kind:?}");
            let s = ours.samples();
            assert_eq!(s.len(), theirs.len());
            let bad = (0..s.len()).find(|&k| s.at(k).to_bits() != theirs[k].to_bits());
            assert!(bad.is_none(), "{kind:?}: sample {bad:?} differs");
        }
    }

    /// Other depths are converted once, as `image` converts them.
    #[test]
    fn sixteen_bit_rgb_is_converted_by_image() {
        let raw: Vec<u16> = (0..48u16).map(|v| v * 1365).collect();
        let buf = image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(4, 4, raw).unwrap();
        let dynamic = image::DynamicImage::ImageRgb16(buf);
        let theirs = dynamic.to_rgb32f().into_raw();
        let ours = RgbImage::from_dynamic(dynamic);
        let Samples::F32(v) = &ours.data else {
            panic!("16-bit is converted");
        };
        assert_eq!(v, &theirs);
        let mut buf = Vec::new();
        assert_eq!(
            ours.samples().span(0, 48, &mut buf).as_ptr(),
            v.as_ptr(),
            "borrowed"
        );
    }
}
