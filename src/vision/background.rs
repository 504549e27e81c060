//! Cloth model and the ball signal.
//!
//! Without a plate, the cloth `B(x, y)` of each channel is a polynomial surface of total degree 4
//! in normalised image coordinates (illumination gradient and vignetting are smooth), fitted by
//! least squares to block medians of a downsampled image, with iterative rejection of blocks that
//! lie above the surface (balls only ever add light of their own colour, so the clipping is
//! one-sided: `r > 2 σ` out, `r < -4 σ` out, `σ = 1.4826 MAD`). With a plate of the empty table,
//! `B` is the plate itself, which also cancels the fixed cloth texture.
//!
//! Balls differ from the cloth along one colour direction per ball. The signal of a ball of
//! colour direction `u` is the projection `S = w·(I - B)` with `w = Σ⁻¹u / (uᵀΣ⁻¹u)`, where `Σ`
//! is the robust colour covariance of the cloth residual `I - B` (the generalised least-squares
//! estimate of the amplitude along `u`: `w·u = 1`, so `S` stays linear in the dwell fraction and
//! keeps the units of `u·(I - B)`). Cloth texture, stains, vignetting and illumination change the
//! cloth's brightness far more than its hue, so `Σ` is long along the cloth colour and `w` turns
//! away from it: texture blotches the size of a ball, which swamp a faint streak in `u·(I - B)`,
//! mostly cancel. With a plate (texture already gone) `Σ` is the sensor noise and `w` only
//! weights the channels by it. A ball of the cloth's own hue (black, or green on green) gains
//! nothing, as it should: its light then differs from the cloth only as a blotch does.

use super::image_io::{Px, RgbImage, Samples};
use super::texture::ClothTexture;
use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use std::sync::{Arc, Mutex, OnceLock};

/// Downsampled target size (longest side) for the coarse search.

#[derive(Debug, Clone)]
pub struct Signal<'a> {
    pub w: usize,
    pub h: usize,
    /// Full-resolution RGB of the photo, interleaved; projections on a ball's colour direction
    /// are taken where sampled (after the cloth's fixed part, [`Signal::fixed`], is taken off),
    /// and local baselines are subtracted where used, so the cloth surface need not be
    /// evaluated at full resolution.
    pub rgb: std::borrow::Cow<'a, Samples>,
    /// The cloth's fixed part, taken off each pixel where it is read: a copy of the photo minus
    /// a plate or a texture map would be 46 MB of page faults at 2400×1600 (13 ms a photo),
    /// for the few per cent of its pixels the samplers read.
    pub fixed: Fixed<'a>,
    /// Downsampling factor of the coarse grid.
    pub f: usize,
    pub cw: usize,
    pub ch: usize,
    /// Coarse background-subtracted signal `u·(C - B)`.
    pub coarse: Vec<f32>,
    /// Coarse background-subtracted colour difference `C - B` per channel (shared by the
    /// photo's signals of other colours, [`Signal::recoloured`]).
    pub coarse_diff: std::borrow::Cow<'a, [[f32; 3]]>,
    /// Robust (MAD) noise of `coarse`.
    pub sigma_coarse: f32,
    /// Unit ball-minus-cloth colour direction.
    pub u: [f32; 3],
    /// Projection vector of `u` ([`Signal::projector`]): what `coarse` and [`Signal::sample`] use.
    pub proj: [f32; 3],
    /// Inverse robust colour covariance of the coarse cloth residual (see the module doc).
    pub cov_inv: [[f64; 3]; 3],
    /// Median full-resolution cloth signal level `u·B` (for overlays and sanity checks).
    pub cloth_level: f32,
    /// Whether a background plate was subtracted (the cloth's texture is then gone too).
    pub plate: bool,
    /// The cloth's brightness on the coarse grid (the mean of its three channels: the fitted
    /// surface, or the plate's block means), which the lamp's irradiance scales as it scales a
    /// ball's light ([`Signal::illumination`]).
    pub cloth_brightness: std::borrow::Cow<'a, [f32]>,
    /// The cloth model used.
    pub cloth: ClothModel,
    /// Full-resolution projections of `rgb` already computed ([`Signal::projected`]), shared
    /// by the photo's [`Signal::recoloured`] signals (and clones), which read the same pixels:
    /// `rgb` is not to be changed once the signal is built.
    pub planes: PlaneCache,
    /// The plane of this signal's own projector `proj`, once [`Signal::sample`] has read it
    /// (taken from `planes`, so shared with every other reader of that projector).
    pub own: OnceLock<Arc<Tiles>>,
}

/// The pixel `(x0, y0)` whose cell holds `(x, y)` in a `w × h` image, and the fractions across
/// it; `None` where a bilinear sample would need a pixel outside.
#[inline]
pub(crate) fn bilinear_cell(
    x: f64,
    y: f64,
    w: usize,
    h: usize,
) -> Option<(usize, usize, f32, f32)> {
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    // Truncation is the floor here (both are at least 0), and unlike `f64::floor` it is not a
    // library call on the baseline x86-64 target (the samplers are the hottest loops).
    let (x0, y0) = (x as usize, y as usize);
    if x0 + 1 >= w || y0 + 1 >= h {
        return None;
    }
    Some((x0, y0, (x - x0 as f64) as f32, (y - y0 as f64) as f32))
}

/// What is taken off every full-resolution pixel before it is read ([`Signal::rgb`]).
#[derive(Debug, Clone, Copy, Default)]
pub enum Fixed<'a> {
    /// Nothing (the cloth surface is subtracted coarsely, where the signal is used).
    #[default]
    None,
    /// A plate of the empty table, interleaved as the photo.
    Plate(Px<'a>),
    /// The folder's cloth texture.
    Texture(&'a ClothTexture),
}

impl Fixed<'_> {
    /// Pixel `(x, y)` of the photo `rgb` (`w` wide) minus the fixed part, channel by channel:
    /// the same `f32` differences a subtracted copy of the photo would hold.
    #[inline]
    pub fn pixel(&self, rgb: Px, w: usize, x: usize, y: usize) -> [f32; 3] {
        let k = 3 * (y * w + x);
        let v = [rgb.at(k), rgb.at(k + 1), rgb.at(k + 2)];
        match self {
            Fixed::None => v,
            Fixed::Plate(p) => [v[0] - p.at(k), v[1] - p.at(k + 1), v[2] - p.at(k + 2)],
            Fixed::Texture(t) => {
                let tv = t.at(x, y);
                [v[0] - tv[0], v[1] - tv[1], v[2] - tv[2]]
            }
        }
    }

    /// Pixels `x0..x1` of row `y` minus the fixed part, as `f32` (interleaved); borrowed from
    /// the photo, without a copy, when it holds `f32` and nothing is subtracted, else written
    /// into `out`.
    pub fn row<'r>(
        &self,
        rgb: Px<'r>,
        w: usize,
        y: usize,
        (x0, x1): (usize, usize),
        out: &'r mut Vec<f32>,
    ) -> &'r [f32] {
        let (a, b) = (3 * (y * w + x0), 3 * (y * w + x1));
        if let Fixed::None = self {
            return rgb.span(a, b, out);
        }
        rgb.span_into(a, b, out);
        self.take_off(out, w, y, (x0, x1));
        out
    }

    /// Takes the fixed part off pixels `x0..x1` of row `y`, held in `row` (interleaved): each
    /// value `v` becomes `v - fixed`, as [`Fixed::pixel`] forms it.
    pub fn take_off(&self, row: &mut [f32], w: usize, y: usize, (x0, x1): (usize, usize)) {
        debug_assert_eq!(row.len(), 3 * (x1 - x0));
        let (a, b) = (3 * (y * w + x0), 3 * (y * w + x1));
        match self {
            Fixed::None => {}
            Fixed::Plate(Px::F32(p)) => {
                for (o, q) in row.iter_mut().zip(&p[a..b]) {
                    *o -= q;
                }
            }
            Fixed::Plate(Px::U8(p)) => {
                for (o, &q) in row.iter_mut().zip(&p[a..b]) {
                    *o -= super::image_io::unit(q);
                }
            }
            Fixed::Texture(t) => {
                let trow = t.row(y);
                let sub = |o: &mut [f32], tv: &[f32; 3]| {
                    o[0] -= tv[0];
                    o[1] -= tv[1];
                    o[2] -= tv[2];
                };
                // The pixels of a whole cell share its value: taken run by run, not looked up
                // pixel by pixel (this loop was 6 % of a realistic folder's time). A run
                // starting inside a cell, and the clamped last column, are done singly.
                const B: usize = super::texture::BLOCK;
                let first = x0.next_multiple_of(B).min(x1);
                let whole = (x1 / B).min(t.tw).max(first / B);
                let end = (whole * B).max(first);
                for x in (x0..first).chain(end..x1) {
                    let k = 3 * (x - x0);
                    sub(&mut row[k..k + 3], &trow[t.column(x)]);
                }
                let (o, v) = (3 * (first - x0), 3 * (end - x0));
                for (o, tv) in row[o..v]
                    .chunks_exact_mut(3 * B)
                    .zip(&trow[first / B..whole])
                {
                    for o in o.chunks_exact_mut(3) {
                        sub(o, tv);
                    }
                }
            }
        }
    }
}

/// Projected full-resolution planes by projector, computed on first use.
#[derive(Debug, Clone, Default)]
pub struct PlaneCache(Arc<Mutex<Vec<Arc<Tiles>>>>);

/// Side of a [`Projected`] tile (px); each tile stores one more row and column, so that a
/// bilinear sample never needs a second tile.
const TILE: usize = 64;

/// One projector's plane, in tiles computed on first read.
#[derive(Debug)]
pub struct Tiles {
    u: [f32; 3],
    tw: usize,
    tiles: Vec<OnceLock<Box<[f32]>>>,
}

/// The full-resolution signal of one colour projector (a [`Signal::projected`]), sampled
/// bilinearly. Holds at each pixel exactly `u · (pixel − fixed part)` ([`Fixed::pixel`], the
/// same products summed in the same order), so sampling it is bit-identical to projecting the
/// four pixels of each sample; its tiles are computed on first read, so only the pixels near
/// the streaks are ever projected.
#[derive(Debug, Clone)]
pub struct Projected<'s> {
    src: Source<'s>,
    tiles: Arc<Tiles>,
}

impl Projected<'_> {
    /// Bilinear sample at `(x, y)`; `None` where a sample would need a pixel outside.
    #[inline]
    pub fn sample(&self, x: f64, y: f64) -> Option<f32> {
        self.src.sample_in(&self.tiles, x, y)
    }

    /// The `f32` sum, in order, of the samples at `base[j] + off` (each coordinate `b + o`),
    /// to the bit what adding [`Projected::sample`]s gives; `None` when one falls outside.
    /// For a streak's cross-profile, whose points along the streak stay in one tile: the tile
    /// is looked up once per change, and the sampler is inlined into the loop.
    pub fn sum_along(&self, base: &[(f64, f64)], off: (f64, f64)) -> Option<f32> {
        let (src, tiles) = (&self.src, &*self.tiles);
        let mut key = usize::MAX;
        let mut z: &[f32] = &[];
        let mut acc = 0.0f32;
        for &(bx, by) in base {
            let (x0, y0, fx, fy) = bilinear_cell(bx + off.0, by + off.1, src.w, src.h)?;
            let (tx, ty) = (x0 / TILE, y0 / TILE);
            let k = ty * tiles.tw + tx;
            if k != key {
                key = k;
                z = tiles.tiles[k].get_or_init(|| src.tile(tiles.u, tx, ty));
            }
            acc += bilinear_in_tile(z, x0 - tx * TILE, y0 - ty * TILE, fx, fy);
        }
        Some(acc)
    }
}

/// Bilinear sample of a tile at cell `(cx, cy)` (within the tile), fractions `fx, fy`.
#[inline(always)]
fn bilinear_in_tile(z: &[f32], cx: usize, cy: usize, fx: f32, fy: f32) -> f32 {
    let i = cy * (TILE + 1) + cx;
    let a = z[i] + fx * (z[i + 1] - z[i]);
    let b = z[i + TILE + 1] + fx * (z[i + TILE + 2] - z[i + TILE + 1]);
    a + fy * (b - a)
}

/// The pixels a plane's tiles are formed from.
#[derive(Debug, Clone, Copy)]
struct Source<'s> {
    w: usize,
    h: usize,
    rgb: Px<'s>,
    fixed: Fixed<'s>,
}

impl Source<'_> {
    /// Bilinear sample at `(x, y)` of the plane whose tiles are `tiles`.
    #[inline]
    fn sample_in(&self, tiles: &Tiles, x: f64, y: f64) -> Option<f32> {
        let (x0, y0, fx, fy) = bilinear_cell(x, y, self.w, self.h)?;
        let (tx, ty) = (x0 / TILE, y0 / TILE);
        let z = tiles.tiles[ty * tiles.tw + tx].get_or_init(|| self.tile(tiles.u, tx, ty));
        Some(bilinear_in_tile(z, x0 - tx * TILE, y0 - ty * TILE, fx, fy))
    }

    /// Tile `(tx, ty)`: rows and columns `TILE·t ..= TILE·(t + 1)`, clamped to the photo (a
    /// clamped cell is never read: samples need `x0 + 1 < w`).
    #[cold]
    fn tile(&self, u: [f32; 3], tx: usize, ty: usize) -> Box<[f32]> {
        let mut z = vec![0.0f32; (TILE + 1) * (TILE + 1)];
        let mut buf = Vec::with_capacity(3 * (TILE + 1));
        for (j, row) in z.chunks_exact_mut(TILE + 1).enumerate() {
            let y = (ty * TILE + j).min(self.h - 1);
            let x_end = (tx * TILE + TILE + 1).min(self.w);
            let src = self
                .fixed
                .row(self.rgb, self.w, y, (tx * TILE, x_end), &mut buf);
            for (o, c) in row.iter_mut().zip(src.chunks_exact(3)) {
                *o = u[0] * c[0] + u[1] * c[1] + u[2] * c[2];
            }
        }
        z.into_boxed_slice()
    }
}

impl Signal<'_> {
    /// Bilinear sample of the full-resolution signal of the mean ball colour; `None` outside.
    /// Read from its projected plane ([`Signal::projected`]): the same value to the bit as
    /// projecting the four pixels on `proj`, at a third of the reads once a tile is formed (the
    /// disc's rays and rims sample the same few tiles thousands of times).
    #[inline]
    pub fn sample(&self, x: f64, y: f64) -> Option<f32> {
        let tiles = self.own.get_or_init(|| self.projected(self.proj).tiles);
        self.source().sample_in(tiles, x, y)
    }

    /// The pixels, for the projected planes.
    #[inline]
    fn source(&self) -> Source<'_> {
        Source {
            w: self.w,
            h: self.h,
            rgb: self.rgb.view(),
            fixed: self.fixed,
        }
    }

    /// The projection vector `w = Σ⁻¹u / (uᵀΣ⁻¹u)` of colour direction `u` (module doc): the
    /// amplitude along `u` of a colour difference, with the cloth's own variation weighted down.
    pub fn projector(&self, u: [f32; 3]) -> [f32; 3] {
        projector(&self.cov_inv, u)
    }

    /// Bilinear sample of the full-resolution RGB projected on vector `u`, each of the four
    /// pixels projected in turn: the definition the projected planes are tested against.
    #[cfg(test)]
    fn sample_u(&self, x: f64, y: f64, u: [f32; 3]) -> Option<f32> {
        let (x0, y0, fx, fy) = bilinear_cell(x, y, self.w, self.h)?;
        let v = |x: usize, y: usize| {
            let c = self.fixed.pixel(self.rgb.view(), self.w, x, y);
            u[0] * c[0] + u[1] * c[1] + u[2] * c[2]
        };
        let a = v(x0, y0) + fx * (v(x0 + 1, y0) - v(x0, y0));
        let b = v(x0, y0 + 1) + fx * (v(x0 + 1, y0 + 1) - v(x0, y0 + 1));
        Some(a + fy * (b - a))
    }

    /// The full-resolution signal projected on `u` (a [`Signal::projector`]), for the samplers
    /// that read many pixels of it: a profile reads each pixel of a streak's band once, and
    /// projecting the four corners of every bilinear sample on the fly was the extractor's
    /// hottest loop (the 46 MB of interleaved RGB read three times per sample). Computed once
    /// per projector and photo, a tile at a time where read.
    pub fn projected(&self, u: [f32; 3]) -> Projected<'_> {
        let mut planes = self.planes.0.lock().unwrap_or_else(|e| e.into_inner());
        // The same projector to the bit: a plane holds exactly its products.
        let bits = u.map(f32::to_bits);
        let tiles = match planes.iter().find(|t| t.u.map(f32::to_bits) == bits) {
            Some(t) => t.clone(),
            None => {
                let (tw, th) = (self.w.div_ceil(TILE), self.h.div_ceil(TILE));
                let t = Arc::new(Tiles {
                    u,
                    tw,
                    tiles: (0..tw * th).map(|_| OnceLock::new()).collect(),
                });
                planes.push(t.clone());
                t
            }
        };
        Projected {
            src: self.source(),
            tiles,
        }
    }

    /// The cloth's brightness at full-resolution point `(x, y)`, bilinear on the coarse grid
    /// (clamped at its edges): proportional to the lamp's irradiance there, to the texture's
    /// and the albedo's scale.
    pub fn illumination(&self, x: f64, y: f64) -> f32 {
        let f = self.f as f64;
        let gx = (x / f - 0.5).clamp(0.0, (self.cw - 1) as f64);
        let gy = (y / f - 0.5).clamp(0.0, (self.ch - 1) as f64);
        let (x0, y0) = (gx as usize, gy as usize);
        let (x1, y1) = ((x0 + 1).min(self.cw - 1), (y0 + 1).min(self.ch - 1));
        let (fx, fy) = ((gx - x0 as f64) as f32, (gy - y0 as f64) as f32);
        let b = |x: usize, y: usize| self.cloth_brightness[y * self.cw + x];
        let top = b(x0, y0) + fx * (b(x1, y0) - b(x0, y0));
        let bottom = b(x0, y1) + fx * (b(x1, y1) - b(x0, y1));
        top + fy * (bottom - top)
    }

    #[inline]
    pub fn coarse_at(&self, x: usize, y: usize) -> f32 {
        self.coarse[y * self.cw + x]
    }

    /// The same photo's signal for balls of colour direction `u` instead of the mean one (a
    /// dark object ball on a light cloth, whose light the mean direction, set by the brighter
    /// balls, shows as negative or not at all). Borrows the full-resolution pixels.
    pub fn recoloured(&self, u: [f32; 3]) -> Signal<'_> {
        let proj = projector(&self.cov_inv, u);
        let coarse: Vec<f32> = self
            .coarse_diff
            .iter()
            .map(|d| proj[0] * d[0] + proj[1] * d[1] + proj[2] * d[2])
            .collect();
        let sigma_coarse = mad_sigma(&coarse).max(1e-6);
        Signal {
            w: self.w,
            h: self.h,
            rgb: std::borrow::Cow::Borrowed(&self.rgb),
            fixed: self.fixed,
            f: self.f,
            cw: self.cw,
            ch: self.ch,
            coarse,
            coarse_diff: std::borrow::Cow::Borrowed(&self.coarse_diff),
            sigma_coarse,
            u,
            proj,
            cov_inv: self.cov_inv,
            cloth_level: self.cloth_level,
            plate: self.plate,
            cloth_brightness: std::borrow::Cow::Borrowed(&self.cloth_brightness),
            cloth: self.cloth,
            planes: self.planes.clone(),
            own: OnceLock::new(),
        }
    }
}

/// A channel value at or above this is at full scale (an 8-bit 255; 254 is 0.996).
const FULL_SCALE: f32 = 0.998;

/// Whether a pixel has a channel at full scale (no short-circuit: a branch per channel made the
/// separate pass over the photo that this test once had cost 5 % of a clean photo).
#[inline]
fn at_full_scale(p: &[f32]) -> bool {
    (p[0] >= FULL_SCALE) | (p[1] >= FULL_SCALE) | (p[2] >= FULL_SCALE)
}

/// Fraction of pixels with any channel at full scale, pixel by pixel: the definition that
/// [`CoarsePhoto::saturated`], counted in the block-mean pass, is tested against.
#[cfg(test)]
fn saturated_fraction(img: &RgbImage) -> f64 {
    let s = img.samples();
    let sat = (0..s.len() / 3)
        .filter(|&i| at_full_scale(&[s.at(3 * i), s.at(3 * i + 1), s.at(3 * i + 2)]))
        .count();
    sat as f64 / (img.w * img.h) as f64
}

/// A grid of block means: its width and height in blocks, and the means row by row.
pub(crate) type BlockGrid = (usize, usize, Vec<[f32; 3]>);

pub(crate) fn block_mean(img: &RgbImage, f: usize) -> BlockGrid {
    block_mean_fixed(img, Fixed::None, f)
}

/// [`block_mean`] of the photo minus the cloth's fixed part, to the bit what it gives for a
/// subtracted copy of the photo (each row is subtracted into a buffer, then summed as one).
fn block_mean_fixed(img: &RgbImage, fixed: Fixed, f: usize) -> BlockGrid {
    let ([m], _) = block_means::<false, 1>(img, [(fixed, f)]);
    m
}

/// [`block_mean_fixed`] for each `(fixed, f)` in one pass over the photo (a row is read from
/// memory once and summed from cache for each), and, with `COUNT`, the number of the photo's
/// pixels (all of them, the strips the blocks leave at its right and bottom edges included)
/// with a channel at full scale, before anything is subtracted; 0 without.
pub(crate) fn block_means<const COUNT: bool, const N: usize>(
    img: &RgbImage,
    grids: [(Fixed, usize); N],
) -> ([BlockGrid; N], usize) {
    let (mut plain_buf, mut buf) = (Vec::with_capacity(3 * img.w), Vec::with_capacity(3 * img.w));
    let mut out = grids.map(|(_, f)| {
        let (cw, ch) = (img.w / f, img.h / f);
        (cw, ch, vec![[0f32; 3]; cw * ch])
    });
    let mut sat = 0usize;
    let px = img.samples();
    for y in 0..img.h {
        // The row as `f32` once (converted from bytes, or borrowed), and each subtracted copy
        // from it.
        let plain = px.span(3 * y * img.w, 3 * (y + 1) * img.w, &mut plain_buf);
        for ((fixed, f), (cw, ch, sums)) in grids.iter().zip(out.iter_mut()) {
            let cy = y / f;
            if cy < *ch {
                let row = match fixed {
                    Fixed::None => plain,
                    _ => {
                        buf.clear();
                        buf.extend_from_slice(plain);
                        fixed.take_off(&mut buf, img.w, y, (0, img.w));
                        &buf
                    }
                };
                add_row(&mut sums[cy * *cw..(cy + 1) * *cw], row, *f);
            }
        }
        if COUNT {
            sat += plain
                .chunks_exact(3)
                .map(|p| usize::from(at_full_scale(p)))
                .sum::<usize>();
        }
    }
    for ((_, f), (_, _, sums)) in grids.iter().zip(out.iter_mut()) {
        let norm = 1.0 / (f * f) as f32;
        for v in sums.iter_mut().flatten() {
            *v *= norm;
        }
    }
    (out, sat)
}

/// Adds one row of pixels (interleaved) to the sums of the row of `blocks` it falls in, blocks
/// `f` pixels wide. Each block's sums take its pixels in the same order (row by row, left to
/// right), four blocks at a time: twelve independent chains of additions instead of three, the
/// same sums to the last bit.
#[inline]
fn add_row(blocks: &mut [[f32; 3]], row: &[f32], f: usize) {
    const LANES: usize = 4;
    let cw = blocks.len();
    let mut quads = blocks.chunks_exact_mut(LANES);
    for (q, group) in (&mut quads).enumerate() {
        let mut acc: [[f32; 3]; LANES] = [group[0], group[1], group[2], group[3]];
        for k in 0..f {
            for (l, a) in acc.iter_mut().enumerate() {
                let x = ((q * LANES + l) * f + k) * 3;
                a[0] += row[x];
                a[1] += row[x + 1];
                a[2] += row[x + 2];
            }
        }
        group.copy_from_slice(&acc);
    }
    let done = cw - cw % LANES;
    for (i, o) in quads.into_remainder().iter_mut().enumerate() {
        let cx = done + i;
        for x in cx * f..cx * f + f {
            o[0] += row[3 * x];
            o[1] += row[3 * x + 1];
            o[2] += row[3 * x + 2];
        }
    }
}

pub fn median(v: &mut [f32]) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let k = v.len() / 2;
    if v.len() >= RADIX_MIN {
        return kth_by_radix(v, k);
    }
    let (_, m, _) = v.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    *m
}

/// [`median`] of a slice left as it is: copied only when short enough for the comparison-based
/// selection (the radix selection reads without reordering).
pub fn median_of(v: &[f32]) -> f32 {
    if v.len() >= RADIX_MIN {
        kth_by_radix(v, v.len() / 2)
    } else {
        median(&mut v.to_vec())
    }
}

/// Length from which [`median`] selects by radix: a whole coarse grid's statistics (some 30
/// medians of 240,000 values per photo) take half the time of `select_nth_unstable`.
const RADIX_MIN: usize = 16_384;

/// `f32` bits mapped to `u32` so that integer order is `f32::total_cmp` order.
#[inline]
fn order_key(x: f32) -> u32 {
    let b = x.to_bits();
    b ^ ((((b as i32) >> 31) as u32) | 0x8000_0000)
}

fn from_order_key(k: u32) -> f32 {
    f32::from_bits(if k & 0x8000_0000 != 0 {
        k ^ 0x8000_0000
    } else {
        !k
    })
}

/// The `k`-th smallest value of `v` in `total_cmp` order (the value `select_nth_unstable_by`
/// puts at `k`, to the bit): a histogram of the keys' top 16 bits finds the bucket holding rank
/// `k`, and only that bucket is selected in.
fn kth_by_radix(v: &[f32], k: usize) -> f32 {
    let mut hist = vec![0u32; 1 << 16];
    for &x in v {
        hist[(order_key(x) >> 16) as usize] += 1;
    }
    let (mut below, mut bucket) = (0usize, 0u32);
    for (i, &c) in hist.iter().enumerate() {
        if below + c as usize > k {
            bucket = i as u32;
            break;
        }
        below += c as usize;
    }
    let mut keys: Vec<u32> = v
        .iter()
        .map(|&x| order_key(x))
        .filter(|q| q >> 16 == bucket)
        .collect();
    let (_, m, _) = keys.select_nth_unstable(k - below);
    from_order_key(*m)
}

/// Robust sigma: 1.4826 × median absolute deviation from the median.
pub fn mad_sigma(v: &[f32]) -> f32 {
    let m = median_of(v);
    mad_sigma_about(v, m)
}

/// [`mad_sigma`] about a centre `m` already known (the median, when the caller has it).
pub fn mad_sigma_about(v: &[f32], m: f32) -> f32 {
    let mut a: Vec<f32> = v.iter().map(|x| (x - m).abs()).collect();
    1.4826 * median(&mut a)
}

const POLY_DEGREE: usize = 4;
/// Coefficients of a polynomial of total degree [`POLY_DEGREE`] in two variables.
const POLY_TERMS: usize = (POLY_DEGREE + 1) * (POLY_DEGREE + 2) / 2;

/// The coarse colour difference's three channels, each box-blurred with half-width `r` cells.
pub fn smoothed_channels(sig: &Signal, r: usize) -> Vec<Vec<f32>> {
    (0..3)
        .map(|c| {
            let v: Vec<f32> = sig.coarse_diff.iter().map(|d| d[c]).collect();
            box_blur(&v, sig.cw, sig.ch, r)
        })
        .collect()
}

/// Mahalanobis norm `√(bᵀ C⁻¹ b)` of a colour difference `b` under the inverse covariance `ci`.
#[inline]
pub fn mahalanobis_norm(b: [f32; 3], ci: &[[f64; 3]; 3]) -> f32 {
    let b = b.map(f64::from);
    let q: f64 = (0..3)
        .map(|i| (0..3).map(|j| b[i] * ci[i][j] * b[j]).sum::<f64>())
        .sum();
    q.max(0.0).sqrt() as f32
}

/// Robust colour covariance of residuals that are mostly cloth: start from the per-channel MAD,
/// then four times keep the points within Mahalanobis distance² 11.34 (99 % of a 3-D Gaussian)
/// of the median and take their covariance, divided by 0.9647 (the variance a Gaussian keeps
/// inside that ellipsoid). Regularised by 1e-6 of its trace (a grey image has equal channels,
/// hence a singular covariance). Returns its inverse.
pub fn robust_cov_inv(d: &[[f32; 3]]) -> [[f64; 3]; 3] {
    robust_cov_inv_from(d, &ChannelSpread::of(d))
}

/// Each channel's median and MAD sigma ([`mad_sigma`]) of colour differences: the cloth
/// model's scatter test, the noise of each channel and the start of [`robust_cov_inv`] all
/// read them, and each is two selections over the whole coarse grid.
#[derive(Debug, Clone, Copy)]
struct ChannelSpread {
    median: [f32; 3],
    sigma: [f32; 3],
}

impl ChannelSpread {
    fn of(d: &[[f32; 3]]) -> Self {
        let mut median = [0f32; 3];
        let mut sigma = [0f32; 3];
        for c in 0..3 {
            let v: Vec<f32> = d.iter().map(|x| x[c]).collect();
            median[c] = median_of(&v);
            sigma[c] = mad_sigma_about(&v, median[c]);
        }
        ChannelSpread { median, sigma }
    }

    /// The summed sigmas: how much the cloth residual scatters.
    fn scatter(&self) -> f32 {
        self.sigma.iter().sum()
    }
}

/// [`robust_cov_inv`] with the channels' medians and MAD sigmas already known.
fn robust_cov_inv_from(d: &[[f32; 3]], spread: &ChannelSpread) -> [[f64; 3]; 3] {
    use nalgebra::{Matrix3, Vector3};
    let med: [f64; 3] = spread.median.map(f64::from);
    let sd: [f64; 3] = spread.sigma.map(|s| f64::from(s).max(1e-9));
    let mut inv = Matrix3::from_diagonal(&Vector3::new(
        1.0 / (sd[0] * sd[0]),
        1.0 / (sd[1] * sd[1]),
        1.0 / (sd[2] * sd[2]),
    ));
    for _ in 0..4 {
        let (mut m, mut n) = (Matrix3::<f64>::zeros(), 0usize);
        for v in d {
            let x = Vector3::new(
                v[0] as f64 - med[0],
                v[1] as f64 - med[1],
                v[2] as f64 - med[2],
            );
            if (x.transpose() * inv * x)[0] < 11.34 {
                m += x * x.transpose();
                n += 1;
            }
        }
        if n < 10 {
            break;
        }
        m /= n as f64 * 0.9647;
        let reg = 1e-6 * m.trace().max(1e-18);
        match (m + Matrix3::identity() * reg).try_inverse() {
            Some(i) => inv = i,
            None => break,
        }
    }
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| inv[(i, j)]))
}

/// `Σ⁻¹u / (uᵀΣ⁻¹u)` for the inverse covariance `ci` (see the module doc).
pub fn projector(ci: &[[f64; 3]; 3], u: [f32; 3]) -> [f32; 3] {
    let su: [f64; 3] = [0, 1, 2].map(|i| (0..3).map(|j| ci[i][j] * u[j] as f64).sum());
    let q: f64 = (0..3).map(|i| su[i] * u[i] as f64).sum();
    if q.is_finite() && q > 0.0 {
        su.map(|v| (v / q) as f32)
    } else {
        u
    }
}

/// The monomials `x^i y^(t-i)` of total degree `t ≤ POLY_DEGREE`, by degree, then by `i`.
fn poly_terms_into(x: f64, y: f64, out: &mut [f64; POLY_TERMS]) {
    let mut k = 0;
    for total in 0..=POLY_DEGREE {
        for i in 0..=total {
            out[k] = x.powi(i as i32) * y.powi((total - i) as i32);
            k += 1;
        }
    }
}

/// Fits the cloth surface per channel to block medians of the coarse image and returns it on
/// the coarse grid.
fn fit_cloth_surface(cw: usize, ch: usize, coarse: &[[f32; 3]]) -> Vec<[f32; 3]> {
    let coef = fit_cloth_poly(cw, ch, coarse);
    eval_surface(&coef, cw, ch, 1.0, cw as f64, ch as f64)
}

/// The cloth polynomial's coefficients per channel, in coordinates normalised to `[-1, 1]` over
/// the coarse grid's extent.
pub(crate) fn fit_cloth_poly(cw: usize, ch: usize, coarse: &[[f32; 3]]) -> [DVector<f64>; 3] {
    let g = (cw.max(ch) / 75).max(2);
    let (gw, gh) = (cw / g, ch / g);
    let mut pts: Vec<(f64, f64, [f32; 3])> = Vec::with_capacity(gw * gh);
    let mut buf: [Vec<f32>; 3] = [Vec::new(), Vec::new(), Vec::new()];
    for gy in 0..gh {
        for gx in 0..gw {
            for b in &mut buf {
                b.clear();
            }
            for y in gy * g..gy * g + g {
                for x in gx * g..gx * g + g {
                    let p = coarse[y * cw + x];
                    for c in 0..3 {
                        buf[c].push(p[c]);
                    }
                }
            }
            let m = [
                median(&mut buf[0]),
                median(&mut buf[1]),
                median(&mut buf[2]),
            ];
            let xn = 2.0 * ((gx * g) as f64 + g as f64 / 2.0) / cw as f64 - 1.0;
            let yn = 2.0 * ((gy * g) as f64 + g as f64 / 2.0) / ch as f64 - 1.0;
            pts.push((xn, yn, m));
        }
    }
    // The design rows once (the powers are the same in every pass); each pass solves the
    // normal equations of its inliers: a 15 × 15 Cholesky instead of an SVD of the 3,750 × 15
    // design (about 2 ms a pass, up to six passes, two fits a photo with a texture map and one
    // more for each of the map's photos). The monomials of degree ≤ 4 on this grid give the
    // design a condition number of 21, its Gram matrix 450, so the normal equations lose about
    // 1e-13 of the coefficients in f64, far below the f32 surface's rounding.
    let rows: Vec<[f64; POLY_TERMS]> = pts
        .iter()
        .map(|p| {
            let mut t = [0.0; POLY_TERMS];
            poly_terms_into(p.0, p.1, &mut t);
            t
        })
        .collect();
    let mut inlier = vec![true; pts.len()];
    let mut coef = [
        DVector::zeros(POLY_TERMS),
        DVector::zeros(POLY_TERMS),
        DVector::zeros(POLY_TERMS),
    ];
    for _iter in 0..6 {
        let n_in = inlier.iter().filter(|&&b| b).count();
        if n_in < 2 * POLY_TERMS {
            break;
        }
        let mut gram = SMatrix::<f64, POLY_TERMS, POLY_TERMS>::zeros();
        let mut rhs = [SVector::<f64, POLY_TERMS>::zeros(); 3];
        for ((t, p), _) in rows.iter().zip(&pts).zip(&inlier).filter(|(_, b)| **b) {
            for i in 0..POLY_TERMS {
                for j in i..POLY_TERMS {
                    gram[(i, j)] += t[i] * t[j];
                }
                for (r, v) in rhs.iter_mut().zip(p.2) {
                    r[i] += t[i] * v as f64;
                }
            }
        }
        gram.fill_lower_triangle_with_upper_triangle();
        match gram.cholesky() {
            Some(chol) => {
                for c in 0..3 {
                    coef[c] = DVector::from_column_slice(chol.solve(&rhs[c]).as_slice());
                }
            }
            // A degenerate grid (a strip one block high: every power of `y` the same) has no
            // unique surface; the SVD's least-norm one is still a fit of the cloth.
            None => {
                let kept: Vec<usize> = (0..pts.len()).filter(|&i| inlier[i]).collect();
                let a = DMatrix::from_fn(kept.len(), POLY_TERMS, |r, j| rows[kept[r]][j]);
                let svd = a.svd(true, true);
                for (c, k) in coef.iter_mut().enumerate() {
                    let b = DVector::from_iterator(
                        kept.len(),
                        kept.iter().map(|&i| pts[i].2[c] as f64),
                    );
                    if let Ok(x) = svd.solve(&b, 1e-10) {
                        *k = x;
                    }
                }
            }
        }
        // One-sided clipping on the summed residual: balls add light, texture is symmetric.
        let res: Vec<f32> = rows
            .iter()
            .zip(&pts)
            .map(|(t, p)| {
                (0..3)
                    .map(|c| {
                        p.2[c] as f64
                            - t.iter()
                                .zip(coef[c].iter())
                                .map(|(t, a)| t * a)
                                .sum::<f64>()
                    })
                    .sum::<f64>() as f32
            })
            .collect();
        let inl_res: Vec<f32> = res
            .iter()
            .zip(&inlier)
            .filter(|(_, b)| **b)
            .map(|(r, _)| *r)
            .collect();
        let s = mad_sigma(&inl_res).max(1e-6);
        let new: Vec<bool> = res.iter().map(|&r| r < 2.0 * s && r > -4.0 * s).collect();
        if new == inlier {
            break;
        }
        inlier = new;
    }
    coef
}

/// The cloth surface on a `gw × gh` grid of cells `cell` coarse cells wide, the polynomial's
/// normalised coordinates spanning `span_w × span_h` coarse cells.
pub(crate) fn eval_surface(
    coef: &[DVector<f64>; 3],
    gw: usize,
    gh: usize,
    cell: f64,
    span_w: f64,
    span_h: f64,
) -> Vec<[f32; 3]> {
    // Per row, the polynomial in x (coefficient of x^i: Σ_t a_(t,i) y^(t-i), in `poly_terms`'
    // order), then Horner along the row.
    let mut out = vec![[0f32; 3]; gw * gh];
    for (y, row) in out.chunks_exact_mut(gw.max(1)).enumerate().take(gh) {
        let yn = 2.0 * (y as f64 + 0.5) * cell / span_h - 1.0;
        let mut yp = [1.0; POLY_DEGREE + 1];
        for k in 1..=POLY_DEGREE {
            yp[k] = yp[k - 1] * yn;
        }
        let mut cx = [[0f64; POLY_DEGREE + 1]; 3];
        let mut k = 0;
        for total in 0..=POLY_DEGREE {
            for i in 0..=total {
                for c in 0..3 {
                    cx[c][i] += coef[c][k] * yp[total - i];
                }
                k += 1;
            }
        }
        for (x, o) in row.iter_mut().enumerate() {
            let xn = 2.0 * (x as f64 + 0.5) * cell / span_w - 1.0;
            *o = [0, 1, 2].map(|c| cx[c].iter().rev().fold(0.0, |acc, &a| acc * xn + a) as f32);
        }
    }
    out
}

/// What the cloth of a photo is modelled from.
#[derive(Debug, Clone, Copy)]
pub enum Cloth<'a> {
    /// The photo's own smooth surface.
    Surface,
    /// A plate of the empty table in the same light (`background` in `scene.toml`).
    Plate(&'a Plate),
    /// The folder's fixed texture ([`super::texture`]) on top of the photo's own surface, used
    /// when it lowers the photo's cloth scatter.
    Texture(&'a ClothTexture),
}

impl<'a> Cloth<'a> {
    /// The plate where there is one, else the folder's texture where there is one, else the
    /// photo's own surface.
    pub fn of(plate: Option<&'a Plate>, texture: Option<&'a ClothTexture>) -> Cloth<'a> {
        match (plate, texture) {
            (Some(p), _) => Cloth::Plate(p),
            (None, Some(t)) => Cloth::Texture(t),
            (None, None) => Cloth::Surface,
        }
    }
}

/// A plate of the empty table (`background` in `scene.toml`), with its coarse block means,
/// formed once for all the photos that share it: formed again for each, they were 5 % of a
/// folder's time (session 35).
#[derive(Debug)]
pub struct Plate {
    pub img: RgbImage,
    /// The block means of the first block size asked for, with that size.
    means: OnceLock<(usize, Vec<[f32; 3]>)>,
}

impl Plate {
    pub fn new(img: RgbImage) -> Plate {
        Plate {
            img,
            means: OnceLock::new(),
        }
    }

    /// The block means of blocks `f` pixels wide ([`block_mean`]); kept for the first `f`
    /// (a run's photos share one), formed anew for another.
    fn block_means(&self, f: usize) -> std::borrow::Cow<'_, [[f32; 3]]> {
        let (kept_f, m) = self.means.get_or_init(|| (f, block_mean(&self.img, f).2));
        if *kept_f == f {
            std::borrow::Cow::Borrowed(m)
        } else {
            std::borrow::Cow::Owned(block_mean(&self.img, f).2)
        }
    }
}

/// The cloth model a signal was built with (a column of the angle table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClothModel {
    Surface,
    Plate,
    Texture,
}

impl ClothModel {
    pub fn as_str(self) -> &'static str {
        match self {
            ClothModel::Surface => "surface",
            ClothModel::Plate => "plate",
            ClothModel::Texture => "texture",
        }
    }
}

fn residual_of(c_img: &[[f32; 3]], bg: &[[f32; 3]]) -> Vec<[f32; 3]> {
    c_img
        .iter()
        .zip(bg)
        .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
        .collect()
}

/// A photo's block means on the coarse grid (with a texture map that fits it, also those of
/// the photo minus the map), and how much of it is at full scale: one pass over its pixels,
/// read before anything else ([`build_from`]).
pub struct CoarsePhoto<'a> {
    /// Downsampling factor (pixels per block side) and grid size.
    f: usize,
    cw: usize,
    ch: usize,
    /// Block means, row by row.
    means: Vec<[f32; 3]>,
    /// Block means of the photo minus the texture map, where `cloth` gave one that fits, with
    /// that map.
    textured: Option<(&'a ClothTexture, Vec<[f32; 3]>)>,
    /// Fraction of the photo's pixels with a channel at full scale.
    pub saturated: f64,
}

impl<'a> CoarsePhoto<'a> {
    /// The block means of blocks `f` pixels wide, `f` chosen so that the longer side spans
    /// about `coarse_side` blocks.
    pub fn of(img: &RgbImage, cloth: Cloth<'a>, coarse_side: usize) -> CoarsePhoto<'a> {
        let f = img.w.max(img.h).div_ceil(coarse_side.max(16)).max(1);
        let ((cw, ch, means), textured, sat) = match cloth {
            Cloth::Texture(t) if t.fits(img) => {
                let ([m, mt], sat) =
                    block_means::<true, 2>(img, [(Fixed::None, f), (Fixed::Texture(t), f)]);
                (m, Some((t, mt.2)), sat)
            }
            _ => {
                let ([m], sat) = block_means::<true, 1>(img, [(Fixed::None, f)]);
                (m, None, sat)
            }
        };
        CoarsePhoto {
            f,
            cw,
            ch,
            means,
            textured,
            saturated: sat as f64 / (img.w * img.h) as f64,
        }
    }
}

/// Builds the ball signal of a photo with the given cloth model.
pub fn build<'a>(
    img: &'a RgbImage,
    cloth: Cloth<'a>,
    coarse_side: usize,
) -> Result<Signal<'a>, String> {
    build_from(img, cloth, CoarsePhoto::of(img, cloth, coarse_side))
}

/// [`build`] from the photo's block means, already formed.
pub fn build_from<'a>(
    img: &'a RgbImage,
    cloth: Cloth<'a>,
    coarse: CoarsePhoto<'a>,
) -> Result<Signal<'a>, String> {
    let plate = match cloth {
        Cloth::Plate(p) => Some(p),
        _ => None,
    };
    if let Some(p) = plate
        && (p.img.w != img.w || p.img.h != img.h)
    {
        return Err(format!(
            "background plate is {}×{} px but the photo is {}×{} px",
            p.img.w, p.img.h, img.w, img.h
        ));
    }
    let CoarsePhoto {
        f,
        cw,
        ch,
        means: c_img,
        textured,
        ..
    } = coarse;
    // `diff`, the residual the signal is built on, with its channels' spread; with a texture,
    // also `plain`, the residual of the photo without it, whose colour covariance is used (see
    // below). Each is a block-mean image minus its own fitted surface.
    let surface_residual = |c_img: &[[f32; 3]]| {
        let d = residual_of(c_img, &fit_cloth_surface(cw, ch, c_img));
        let s = ChannelSpread::of(&d);
        (d, s)
    };
    let ((diff, spread), plain, fixed, model) = match cloth {
        Cloth::Plate(p) => {
            let d = residual_of(&c_img, &p.block_means(f));
            let s = ChannelSpread::of(&d);
            (
                (d, s),
                None,
                Fixed::Plate(p.img.samples()),
                ClothModel::Plate,
            )
        }
        Cloth::Surface => (
            surface_residual(&c_img),
            None,
            Fixed::None,
            ClothModel::Surface,
        ),
        Cloth::Texture(t) => {
            let plain = surface_residual(&c_img);
            if t.fits(img) {
                // Formed with the photo's block means, unless they were formed for another
                // cloth model.
                let with = match &textured {
                    Some((tc, m)) if std::ptr::eq(*tc, t) => surface_residual(m),
                    _ => surface_residual(&block_mean_fixed(img, Fixed::Texture(t), f).2),
                };
                if with.1.scatter() < plain.1.scatter() {
                    (with, Some(plain), Fixed::Texture(t), ClothModel::Texture)
                } else {
                    (plain, None, Fixed::None, ClothModel::Surface)
                }
            } else {
                (plain, None, Fixed::None, ClothModel::Surface)
            }
        }
    };
    let bg: Vec<[f32; 3]> = c_img
        .iter()
        .zip(&diff)
        .map(|(a, d)| [a[0] - d[0], a[1] - d[1], a[2] - d[2]])
        .collect();
    let sig_c: [f32; 3] = spread.sigma.map(|s| s.max(1e-5));
    // Colour direction of the balls: mean difference of clearly non-cloth pixels.
    let mut acc = [0f64; 3];
    let mut n_sig = 0usize;
    for d in &diff {
        let z2: f32 = (0..3).map(|c| (d[c] / sig_c[c]).powi(2)).sum();
        if z2 > 36.0 {
            for c in 0..3 {
                acc[c] += d[c] as f64;
            }
            n_sig += 1;
        }
    }
    let norm = (acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]).sqrt();
    if n_sig < 4 || norm <= 0.0 {
        return Err("blank image: nothing differs from the cloth".into());
    }
    let u = [
        (acc[0] / norm) as f32,
        (acc[1] / norm) as f32,
        (acc[2] / norm) as f32,
    ];
    // With a texture, the colour weights come from the untextured residual: the texture map is
    // blank where the object ball waits in most shots, and there, near the impact, the weights
    // must still turn away from the cloth's brightness blotches.
    let cov_inv = match &plain {
        Some((d, s)) => robust_cov_inv_from(d, s),
        None => robust_cov_inv_from(&diff, &spread),
    };
    // The smooth surface (or the plate), without the texture map's blotches.
    let cloth_brightness: Vec<f32> = c_img
        .iter()
        .zip(plain.as_ref().map_or(&diff, |p| &p.0))
        .map(|(a, d)| (a[0] - d[0] + a[1] - d[1] + a[2] - d[2]) / 3.0)
        .collect();
    let proj = projector(&cov_inv, u);
    let coarse: Vec<f32> = diff
        .iter()
        .map(|d| proj[0] * d[0] + proj[1] * d[1] + proj[2] * d[2])
        .collect();
    let sigma_coarse = mad_sigma(&coarse).max(1e-6);
    let mut bl: Vec<f32> = bg
        .iter()
        .map(|b| u[0] * b[0] + u[1] * b[1] + u[2] * b[2])
        .collect();
    let cloth_level = if plate.is_some() {
        0.0
    } else {
        median(&mut bl)
    };
    Ok(Signal {
        w: img.w,
        h: img.h,
        rgb: std::borrow::Cow::Borrowed(&img.data),
        fixed,
        f,
        cw,
        ch,
        coarse,
        coarse_diff: diff.into(),
        sigma_coarse,
        u,
        proj,
        cov_inv,
        cloth_level,
        plate: plate.is_some(),
        cloth_brightness: cloth_brightness.into(),
        cloth: model,
        planes: PlaneCache::default(),
        own: OnceLock::new(),
    })
}

/// Separable box blur of radius `r` (window `2r + 1`, edges clamped) on a `w × h` grid.
pub fn box_blur(src: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    if r == 0 {
        return src.to_vec();
    }
    let norm = 1.0 / (2 * r + 1) as f32;
    let tmp = blur_rows(src, w, h, r, norm);
    let mut out = vec![0f32; w * h];
    // The columns' running sums advance together, row by row (the same additions in the same
    // order for each column as one column at a time, which strode through memory), each
    // started as `Iterator::sum` starts.
    let row = |y: usize| &tmp[y * w..(y + 1) * w];
    let mut s = vec![std::iter::empty::<f32>().sum::<f32>(); w];
    for k in 0..=2 * r {
        for (s, v) in s.iter_mut().zip(row(k.saturating_sub(r).min(h - 1))) {
            *s += v;
        }
    }
    for (y, o) in out.chunks_exact_mut(w).enumerate() {
        for (o, s) in o.iter_mut().zip(&s) {
            *o = s * norm;
        }
        let (add, sub) = (row((y + r + 1).min(h - 1)), row(y.saturating_sub(r)));
        for ((s, a), b) in s.iter_mut().zip(add).zip(sub) {
            *s += a - b;
        }
    }
    out
}

/// [`box_blur`]'s first pass: each row's running sums of `2r + 1` values, times `norm`.
fn blur_rows(src: &[f32], w: usize, h: usize, r: usize, norm: f32) -> Vec<f32> {
    let mut tmp = vec![0f32; w * h];
    for y in 0..h {
        let row = &src[y * w..(y + 1) * w];
        let mut s: f32 = (0..=2 * r)
            .map(|k| row[k.saturating_sub(r).min(w - 1)])
            .sum();
        for x in 0..w {
            tmp[y * w + x] = s * norm;
            let add = (x + r + 1).min(w - 1);
            let sub = x.saturating_sub(r);
            s += row[add] - row[sub];
        }
    }
    tmp
}

/// [`box_blur`] as first written, its second pass a column at a time: the definition it is
/// tested against.
#[cfg(test)]
fn box_blur_by_columns(src: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let norm = 1.0 / (2 * r + 1) as f32;
    let tmp = blur_rows(src, w, h, r, norm);
    let mut out = vec![0f32; w * h];
    for x in 0..w {
        let mut s: f32 = (0..=2 * r)
            .map(|k| tmp[k.saturating_sub(r).min(h - 1) * w + x])
            .sum();
        for y in 0..h {
            out[y * w + x] = s * norm;
            s += tmp[(y + r + 1).min(h - 1) * w + x] - tmp[y.saturating_sub(r) * w + x];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    /// The box blur gives, to the bit, what blurring a column at a time gives: on grids
    /// narrower and shorter than the window, with signed zeros, and with 0/1 masks whose
    /// running sums must come back to the same residue (the texture map's dilation).
    #[test]
    fn box_blur_is_the_column_by_column_blur() {
        for (w, h, r) in [(1, 1, 1), (5, 3, 4), (37, 23, 2), (64, 41, 8), (13, 90, 20)] {
            let v: Vec<f32> = (0..w * h)
                .map(|i| match i % 7 {
                    0 => -0.0,
                    1 => 0.0,
                    2 => f32::from(u8::from(i % 11 < 3)),
                    _ => ((i * 7919) % 1013) as f32 / 101.3 - 4.0,
                })
                .collect();
            let (a, b) = (
                super::box_blur(&v, w, h, r),
                super::box_blur_by_columns(&v, w, h, r),
            );
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "{w}×{h} r {r}");
        }
    }

    /// A signal over full-resolution pixels `rgb` only (its coarse grid a single cell).
    fn test_signal(w: usize, h: usize, rgb: super::Samples, fixed: super::Fixed) -> super::Signal {
        super::Signal {
            w,
            h,
            rgb: std::borrow::Cow::Owned(rgb),
            fixed,
            f: 1,
            cw: 1,
            ch: 1,
            coarse: vec![0.0],
            coarse_diff: vec![[0.0; 3]].into(),
            sigma_coarse: 1.0,
            u: [1.0, 0.0, 0.0],
            proj: [1.0, 0.0, 0.0],
            cov_inv: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            cloth_level: 0.0,
            plate: false,
            cloth_brightness: vec![1.0].into(),
            cloth: super::ClothModel::Surface,
            planes: super::PlaneCache::default(),
            own: std::sync::OnceLock::new(),
        }
    }

    /// The tiled projected plane samples exactly what `sample_u` forms, to the last bit: on
    /// tile seams (64 px), on the last row and column a sample may use, and outside.
    #[test]
    fn projected_planes_sample_bit_identically_to_the_interleaved_pixels() {
        let (w, h) = (203, 130);
        let rgb: Vec<f32> = (0..w * h * 3)
            .map(|i| ((i * 7919) % 1013) as f32 / 1013.0 - 0.3)
            .collect();
        let sig = test_signal(w, h, super::Samples::F32(rgb), super::Fixed::None);
        let u = [0.9f32, -0.2, 0.35];
        let plane = sig.projected(u);
        let mut xs: Vec<f64> = vec![0.0, 0.25, 63.0, 63.5, 63.999, 64.0, 127.7, 128.0, 201.0];
        xs.extend([201.5, 202.0, 202.5, 250.0, -0.5, f64::NAN]);
        let ys = [0.0, 0.75, 63.2, 64.0, 127.9, 128.0, 128.5, 129.0, -1.0];
        let mut inside = 0;
        for &x in &xs {
            for &y in &ys {
                let (a, b) = (sig.sample_u(x, y, u), plane.sample(x, y));
                assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "({x}, {y})");
                // `sample` reads the plane of the signal's own projector.
                assert_eq!(
                    sig.sample(x, y).map(f32::to_bits),
                    sig.sample_u(x, y, sig.proj).map(f32::to_bits),
                    "({x}, {y})"
                );
                inside += a.is_some() as usize;
            }
        }
        assert_eq!(inside, 10 * 7);
        // Sums along a line of points crossing tile seams (x = 64, y = 128) are the samples
        // added in order; a point that needs row 130 (y ≥ 129; the last is at 128.6 + the
        // offset) makes the sum `None`.
        let base: Vec<(f64, f64)> = (0..11)
            .map(|j| (55.3 + 1.7 * j as f64, 120.6 + 0.8 * j as f64))
            .collect();
        for (off, inside) in [
            ((0.0, 0.0), true),
            ((-0.4, -0.1), true),
            ((3.3, 0.35), true),
            ((0.0, 0.5), false),
            ((8.2, 6.9), false),
        ] {
            let by_sample = base.iter().try_fold(0.0f32, |acc, &(bx, by)| {
                plane.sample(bx + off.0, by + off.1).map(|v| acc + v)
            });
            let summed = plane.sum_along(&base, off);
            assert_eq!(
                summed.map(f32::to_bits),
                by_sample.map(f32::to_bits),
                "{off:?}"
            );
            assert_eq!(summed.is_some(), inside, "{off:?}");
        }
        // The same projector shares its tiles; a recoloured signal too (same pixels).
        let recoloured = sig.recoloured([0.2, 0.5, 0.3]);
        let again = recoloured.projected(u);
        assert_eq!(again.sample(100.3, 70.6), plane.sample(100.3, 70.6));
        // Two planes: `u`'s, and `sig.proj`'s, which `sample` formed once and then holds.
        assert_eq!(sig.planes.0.lock().unwrap().len(), 2);
        let own = sig.own.get().expect("sample formed its plane");
        assert!(Arc::ptr_eq(own, &sig.projected(sig.proj).tiles));
        assert_eq!(sig.planes.0.lock().unwrap().len(), 2);
    }

    /// The cloth's fixed part taken off where pixels are read gives, to the bit, what a
    /// subtracted copy of the photo gives: block means, single pixels, projected tiles and the
    /// interleaved sampler, for a plate and for a texture map whose cells do not divide the
    /// photo (its last row and column of cells reach the edge); photo and plate held as `f32`
    /// or as kept 8-bit bytes.
    #[test]
    fn the_fixed_cloth_taken_off_on_reading_is_the_subtracted_copy() {
        use super::super::image_io::{RgbImage, Samples};
        use super::super::texture::ClothTexture;
        use super::{Fixed, block_mean, block_mean_fixed};
        let (w, h) = (203, 131);
        let n = 3 * w * h;
        let px = |i: usize, k: usize| ((i * k) % 1009) as f32 / 1009.0 - 0.2;
        let byte = |i: usize, k: usize| ((i * k) % 256) as u8;
        let photos = [
            RgbImage::from_f32(w, h, (0..n).map(|i| px(i, 7919)).collect()),
            RgbImage {
                w,
                h,
                data: Samples::U8((0..n).map(|i| byte(i, 7919)).collect()),
            },
        ];
        let plates = [
            Samples::F32((0..n).map(|i| 0.5 * px(i, 104_729)).collect()),
            Samples::U8((0..n).map(|i| byte(i, 104_729)).collect()),
        ];
        let (tw, th) = (w / 2, h / 2);
        let tex = ClothTexture {
            w,
            h,
            tw,
            th,
            t: (0..tw * th)
                .map(|i| [0, 1, 2].map(|c| 0.1 * px(3 * i + c, 6151)))
                .collect(),
            coverage: 1.0,
            images: 8,
        };
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for img in &photos {
            let v = img.samples();
            let by_copy = |fixed: Fixed| -> Vec<f32> {
                (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .flat_map(|(x, y)| {
                        let k = 3 * (y * w + x);
                        let m = match fixed {
                            Fixed::None => [0.0; 3],
                            Fixed::Plate(p) => [p.at(k), p.at(k + 1), p.at(k + 2)],
                            Fixed::Texture(t) => {
                                t.t[(y / 2).min(t.th - 1) * t.tw + (x / 2).min(t.tw - 1)]
                            }
                        };
                        [v.at(k) - m[0], v.at(k + 1) - m[1], v.at(k + 2) - m[2]]
                    })
                    .collect()
            };
            for fixed in [
                Fixed::None,
                Fixed::Plate(plates[0].view()),
                Fixed::Plate(plates[1].view()),
                Fixed::Texture(&tex),
            ] {
                let copied = by_copy(fixed);
                let copy = RgbImage::from_f32(w, h, copied.clone());
                for f in [2, 4, 5] {
                    let (a, b) = (block_mean_fixed(img, fixed, f).2, block_mean(&copy, f).2);
                    assert_eq!(bits(a.as_flattened()), bits(b.as_flattened()), "f {f}");
                    // The same means from one pass that also sums the plain photo's.
                    let ([(_, _, plain), (_, _, both)], _) =
                        super::block_means::<false, 2>(img, [(Fixed::None, f), (fixed, f)]);
                    assert_eq!(bits(both.as_flattened()), bits(b.as_flattened()), "f {f}");
                    let alone = block_mean(img, f).2;
                    assert_eq!(
                        bits(plain.as_flattened()),
                        bits(alone.as_flattened()),
                        "f {f}"
                    );
                }
                for (x, y) in [(0, 0), (202, 130), (201, 129), (64, 65), (100, 7)] {
                    let k = 3 * (y * w + x);
                    assert_eq!(bits(&fixed.pixel(v, w, x, y)), bits(&copied[k..k + 3]));
                }
                // Runs of a row: whole texture cells, runs starting or ending inside a cell,
                // the clamped last column (x = 202 of an odd width), empty and one-pixel runs.
                let mut buf = Vec::new();
                for (x0, x1) in [
                    (0, 203),
                    (1, 50),
                    (3, 4),
                    (7, 7),
                    (64, 129),
                    (200, 203),
                    (202, 203),
                ] {
                    for y in [0, 64, 129, 130] {
                        let row = fixed.row(v, w, y, (x0, x1), &mut buf);
                        let want = &copied[3 * (y * w + x0)..3 * (y * w + x1)];
                        assert_eq!(bits(row), bits(want), "x {x0}..{x1} y {y}");
                    }
                }
                let lazy = test_signal(w, h, img.data.clone(), fixed);
                let copied = test_signal(w, h, copy.data.clone(), Fixed::None);
                let u = [0.9f32, -0.2, 0.35];
                let (pl, pc) = (lazy.projected(u), copied.projected(u));
                for (x, y) in [
                    (0.0, 0.0),
                    (63.5, 64.2),
                    (64.0, 127.9),
                    (201.9, 129.9),
                    (150.3, 2.7),
                ] {
                    assert_eq!(
                        lazy.sample_u(x, y, u).map(f32::to_bits),
                        copied.sample_u(x, y, u).map(f32::to_bits)
                    );
                    assert_eq!(
                        pl.sample(x, y).map(f32::to_bits),
                        pc.sample(x, y).map(f32::to_bits)
                    );
                }
            }
        }
    }

    /// Block means against the plain definition (and, to the bit, against the plain loop), on
    /// an image whose size the blocks do not divide; and the cloth polynomial of a smooth surface recovered to rounding.
    #[test]
    fn block_means_and_the_cloth_polynomial_hold_their_definitions() {
        use super::super::image_io::RgbImage;
        let (w, h) = (203, 151);
        let val = |x: usize, y: usize, c: usize| {
            let (xf, yf) = (x as f32 / w as f32, y as f32 / h as f32);
            0.2 + 0.3 * xf * xf - 0.1 * yf + 0.05 * c as f32 + 0.01 * ((x * 7 + y * 13) % 5) as f32
        };
        let data = (0..h)
            .flat_map(|y| (0..w).flat_map(move |x| (0..3).map(move |c| val(x, y, c))))
            .collect();
        let img = RgbImage::from_f32(w, h, data);
        let v = img.samples();
        // The block sums as a plain loop, pixel by pixel into each block: block_mean adds in
        // the same order, so it must agree to the bit.
        let plain = |f: usize| {
            let (cw, ch) = (w / f, h / f);
            let mut out = vec![[0f32; 3]; cw * ch];
            for y in 0..ch * f {
                for x in 0..cw * f {
                    let o = &mut out[(y / f) * cw + x / f];
                    for (c, o_c) in o.iter_mut().enumerate() {
                        *o_c += v.at(3 * (y * w + x) + c);
                    }
                }
            }
            out.iter()
                .map(|o| o.map(|v| v * (1.0 / (f * f) as f32)))
                .collect::<Vec<_>>()
        };
        for f in [1, 2, 4, 5] {
            let (cw, ch, m) = super::block_mean(&img, f);
            assert_eq!((cw, ch), (w / f, h / f));
            let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&m), bits(&plain(f)), "f {f}");
            for (cy, cx) in [(0, 0), (ch - 1, cw - 1), (ch / 2, cw / 3)] {
                for (c, got) in m[cy * cw + cx].iter().enumerate() {
                    let mut s = 0.0f64;
                    for y in cy * f..cy * f + f {
                        for x in cx * f..cx * f + f {
                            s += val(x, y, c) as f64;
                        }
                    }
                    let want = s / (f * f) as f64;
                    assert!((*got as f64 - want).abs() < 1e-6, "f {f}");
                }
            }
        }
        // A plate keeps the block means of the first block size asked for; another size is
        // formed anew, and the kept one is still served after it.
        let plate = super::Plate::new(img.clone());
        let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        for f in [4, 5, 4] {
            let m = plate.block_means(f);
            assert_eq!(bits(&m), bits(&super::block_mean(&img, f).2), "f {f}");
            assert_eq!(matches!(m, std::borrow::Cow::Borrowed(_)), f == 4, "f {f}");
        }
        // Pixels at full scale, counted in the same pass: some inside blocks, some in the
        // strips the blocks leave at the right (x ≥ 200 for f 4 and 5) and bottom edges, one
        // just below full scale (an 8-bit 254), each in one channel only.
        let mut lit = img.clone();
        let spots = [
            (0, 0, 0),
            (17, 33, 1),
            (201, 10, 2),
            (202, 150, 0),
            (40, 150, 1),
        ];
        let mut lit8 = RgbImage {
            w,
            h,
            data: super::Samples::U8(vec![128; 3 * w * h]),
        };
        for &(x, y, c) in &spots {
            lit.f32_mut()[3 * (y * w + x) + c] = 1.0;
            if let super::Samples::U8(b) = &mut lit8.data {
                b[3 * (y * w + x) + c] = 255;
            }
        }
        lit.f32_mut()[3 * (60 * w + 60) + 2] = 254.0 / 255.0;
        if let super::Samples::U8(b) = &mut lit8.data {
            b[3 * (60 * w + 60) + 2] = 254;
        }
        let want = spots.len() as f64 / (w * h) as f64;
        assert_eq!(super::saturated_fraction(&lit).to_bits(), want.to_bits());
        assert_eq!(super::saturated_fraction(&lit8).to_bits(), want.to_bits());
        for f in [1, 2, 4, 5] {
            let ([_], n) = super::block_means::<true, 1>(&lit8, [(super::Fixed::None, f)]);
            assert_eq!(n, spots.len(), "bytes, f {f}");
            let ([(_, _, m)], n) = super::block_means::<true, 1>(&lit, [(super::Fixed::None, f)]);
            assert_eq!(n, spots.len(), "f {f}");
            let plain_lit = super::block_mean(&lit, f).2;
            assert_eq!(m.as_flattened(), plain_lit.as_flattened());
        }
        assert_eq!(
            super::CoarsePhoto::of(&lit, super::Cloth::Surface, 40)
                .saturated
                .to_bits(),
            want.to_bits()
        );
        // A degree-4 surface on a 600 × 400 grid, one block lifted by a "ball".
        let (cw, ch) = (600, 400);
        let surf =
            |x: f64, y: f64| 0.4 + 0.1 * x - 0.05 * y * y + 0.02 * x * x * y * y - 0.03 * x.powi(4);
        let mut coarse: Vec<[f32; 3]> = (0..ch)
            .flat_map(|y| {
                (0..cw).map(move |x| {
                    let (xn, yn) = (
                        2.0 * (x as f64 + 0.5) / cw as f64 - 1.0,
                        2.0 * (y as f64 + 0.5) / ch as f64 - 1.0,
                    );
                    let v = surf(xn, yn) as f32;
                    [v, 0.5 * v, 0.25 * v]
                })
            })
            .collect();
        for y in 100..140 {
            for x in 300..340 {
                coarse[y * cw + x][0] += 0.3;
            }
        }
        // A strip one block high: the normal equations are singular (every power of `y` is
        // the same), and the least-norm fit still follows the cloth along the blocks' row
        // (`yn` = -0.2 for 10 rows in one block of 8).
        let (sw, sh) = (600, 10);
        let cloth = |xn: f64| 0.3 + 0.1 * xn;
        let strip: Vec<[f32; 3]> = (0..sw * sh)
            .map(|i| {
                let xn = 2.0 * ((i % sw) as f64 + 0.5) / sw as f64 - 1.0;
                [cloth(xn) as f32, 0.2, 0.1]
            })
            .collect();
        let coef = super::fit_cloth_poly(sw, sh, &strip);
        for xn in [-0.95, 0.0, 0.95] {
            let mut t = [0.0; super::POLY_TERMS];
            super::poly_terms_into(xn, -0.2, &mut t);
            let at = |c: usize| {
                t.iter()
                    .zip(coef[c].iter())
                    .map(|(t, a)| t * a)
                    .sum::<f64>()
            };
            assert!((at(0) - cloth(xn)).abs() < 1e-3, "strip at {xn}: {}", at(0));
            assert!((at(1) - 0.2).abs() < 1e-4, "strip at {xn}: {}", at(1));
        }
        let fitted = super::fit_cloth_surface(cw, ch, &coarse);
        for (x, y) in [(5, 5), (590, 395), (20, 380), (450, 60)] {
            let (xn, yn) = (
                2.0 * (x as f64 + 0.5) / cw as f64 - 1.0,
                2.0 * (y as f64 + 0.5) / ch as f64 - 1.0,
            );
            let want = surf(xn, yn);
            assert!(
                (fitted[y * cw + x][0] as f64 - want).abs() < 2e-4,
                "({x},{y})"
            );
            assert!(
                (fitted[y * cw + x][2] as f64 - 0.25 * want).abs() < 1e-4,
                "({x},{y})"
            );
        }
    }

    /// The cloth under a lamp that falls off by half across the photo (one ball-coloured blob so
    /// that the signal has a colour): `illumination` follows the lamp to a percent, which is
    /// what the time arrows divide the balls' light by.
    #[test]
    fn illumination_follows_the_lamp_across_the_cloth() {
        let (w, h) = (800usize, 500usize);
        let lamp = |x: f64| 1.0 - 0.5 * x / w as f64;
        let mut data = vec![0f32; 3 * w * h];
        for y in 0..h {
            for x in 0..w {
                let blob = (x as f64 - 400.0).hypot(y as f64 - 250.0) < 30.0;
                let c = if blob {
                    [0.9, 0.9, 0.85]
                } else {
                    [0.1, 0.35, 0.2]
                };
                for k in 0..3 {
                    data[3 * (y * w + x) + k] = (c[k] * lamp(x as f64)) as f32;
                }
            }
        }
        let img = super::RgbImage::from_f32(w, h, data);
        let sig = super::build(&img, super::Cloth::Surface, 400).unwrap();
        for (xa, xb) in [(100.0, 700.0), (200.0, 600.0), (50.0, 350.0)] {
            let got = sig.illumination(xa, 120.0) / sig.illumination(xb, 380.0);
            let want = (lamp(xa) / lamp(xb)) as f32;
            assert!(
                (got / want - 1.0).abs() < 0.01,
                "{xa}, {xb}: {got} against {want}"
            );
        }
    }

    proptest! {
        /// The radix median is the comparison-based one to the bit, signed zeros, infinities
        /// and NaNs included (their `total_cmp` places).
        #[test]
        fn radix_median_matches_select(
            mut v in prop::collection::vec(
                prop_oneof![
                    8 => -1.0f32..1.0,
                    1 => prop::sample::select(vec![
                        0.0f32, -0.0, 1e-30, -1e-30, f32::INFINITY, f32::NEG_INFINITY,
                        f32::NAN, -f32::NAN, f32::MAX, f32::MIN,
                    ]),
                    1 => (0u32..64).prop_map(|i| 0.25 + i as f32 * 1e-7),
                ],
                1..3000,
            ),
            k_frac in 0.0f64..1.0,
        ) {
            let k = ((v.len() as f64 * k_frac) as usize).min(v.len() - 1);
            let got = super::kth_by_radix(&v, k);
            let (_, want, _) = v.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
            prop_assert_eq!(got.to_bits(), want.to_bits());
        }
    }

    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn dot(a: [f32; 3], b: [f32; 3]) -> f64 {
        (0..3).map(|i| a[i] as f64 * b[i] as f64).sum()
    }

    /// Cloth residuals: a brightness texture along the cloth colour `c` (σ 4 DN) plus
    /// independent sensor noise (σ 0.5 DN per channel), with 5 % of gross outliers (ball light).
    fn residuals(c: [f32; 3], n: usize) -> Vec<[f32; 3]> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let tex = Normal::new(0.0, 4.0).unwrap();
        let noise = Normal::new(0.0, 0.5).unwrap();
        (0..n)
            .map(|i| {
                if i % 20 == 0 {
                    return [60.0, 55.0, 50.0];
                }
                let t: f32 = tex.sample(&mut rng);
                [0, 1, 2].map(|k| t * c[k] + noise.sample(&mut rng))
            })
            .collect()
    }

    fn unit(v: [f32; 3]) -> [f32; 3] {
        let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
        v.map(|x| x / n)
    }

    /// The cloth colour of both tests.
    const CLOTH: [f32; 3] = [0.3, 0.8, 0.52];

    #[test]
    fn robust_covariance_recovers_texture_and_noise() {
        let c = unit(CLOTH);
        let ci = robust_cov_inv(&residuals(c, 40_000));
        let inv = nalgebra::Matrix3::from_fn(|i, j| ci[i][j]);
        let cov = inv.try_inverse().unwrap();
        // Along the cloth colour: 16 + 0.25 DN²; across it: 0.25 DN² (the outliers are gone).
        let cv = nalgebra::Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64);
        let along = (cv.transpose() * cov * cv)[0];
        assert!(
            (along - 16.25).abs() < 0.6,
            "variance along the cloth colour {along}"
        );
        let across = nalgebra::Vector3::new(c[1] as f64, -c[0] as f64, 0.0).normalize();
        let v = (across.transpose() * cov * across)[0];
        assert!((v - 0.25).abs() < 0.03, "variance across it {v}");
    }

    #[test]
    fn projector_keeps_the_ball_amplitude_and_drops_the_cloth_colour() {
        let c = unit(CLOTH);
        let ci = robust_cov_inv(&residuals(c, 40_000));
        // A white ball on this cloth: ball minus cloth.
        let u = unit([0.66, 0.45, 0.6]);
        let w = projector(&ci, u);
        assert!((dot(w, u) - 1.0).abs() < 1e-5, "w·u = {}", dot(w, u));
        // The plain projection passes u·c of a blotch; the GLS one
        // (u·c / 16.25) / ((u·c)² / 16.25 + (1 - (u·c)²) / 0.25), a sixteenth of it here.
        let (plain, gls) = (dot(u, c), dot(w, c));
        let expected = (plain / 16.25) / (plain * plain / 16.25 + (1.0 - plain * plain) / 0.25);
        assert!(plain > 0.8, "u·c = {plain}");
        assert!(
            (gls - expected).abs() < 0.1 * expected,
            "w·c = {gls}, expected {expected}"
        );
        assert!(gls < plain / 15.0);
        // Isotropic noise (a plate): the projector is the colour direction itself.
        let iso = [[4.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 4.0]];
        let wi = projector(&iso, u);
        for k in 0..3 {
            assert!((wi[k] - u[k]).abs() < 1e-6);
        }
    }
}
