//! Long-exposure photometry: each pixel integrates the scene over the exposure `T`.
//!
//! A pixel's expected value (digital numbers, DN) is
//! `L(p) · [ a_cloth(p) · (1 − Σ_k f_k(p)) + Σ_k f_k(p) · b_k(p) ]`, where `f_k(p)` is the
//! fraction of the exposure during which ball `k` covers `p` (dwell time / `T`), `b_k` its
//! reflectance (albedo × shading), `a_cloth` the textured cloth albedo and `L(p)` the lamp level
//! with a linear illumination gradient and vignetting `1 − v r²`. Streaks are therefore faint
//! (`f ≈ 2R/(vT)`, a few per cent) and get brighter where a ball slows; a resting ball is a
//! shaded disc weighted by the time it rests.
//!
//! Dwell time is integrated analytically: the path (in pixels) is cut into short segments
//! traversed at constant speed. For a disc of radius `ρ` moving along a segment of length `L` in
//! time `dt`, a pixel at distance `d < ρ` from the segment's line and at abscissa `s0` along it is
//! covered while the centre is in the chord interval `[s0 − h, s0 + h]`, `h = √(ρ² − d²)`; the
//! dwell is `|[s0 − h, s0 + h] ∩ [0, L]| · dt / L`. The disc edge is antialiased with a 1-px linear
//! ramp, which is the average of hard discs of radius `ρ ∈ [R − ½, R + ½]`; it is integrated by
//! two-point Gauss quadrature (`R ± 0.2887`). Moving balls are not shaded per pixel: a ball's
//! shading pattern sweeps over each pixel, so its mean over the disc ([`MOVING_SHADE`]) applies.
//! A resting ball is shaded per pixel, and where its rim crosses a pixel the covered part's
//! shading is integrated over sub-pixels ([`disc_pixel`]), as a sensor pixel averages light.
//!
//! Sensor: Poisson–Gaussian noise, variance `a · x + b` (shot noise with gain `a` plus read noise
//! `b`), per channel, then rounding and clipping to 8 bits. The image is rendered in horizontal
//! bands in parallel; each band's noise comes from its own ChaCha stream seeded by (seed, band),
//! so output is byte-identical whatever the thread count.

use image::RgbImage;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

/// Mean diffuse shading of a ball lit from above, averaged over its disc (see [`shade`]).
pub const MOVING_SHADE: f32 = 0.78;

/// Rows per parallel band.
const BAND_ROWS: usize = 16;

/// Offsets of the two-point Gauss rule for the 1-px edge ramp: ±1/(2√3).
const EDGE_GAUSS: f64 = 0.288_675_134_594_812_9;

/// A straight piece of a ball's path traversed at constant speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub a: [f64; 2],
    pub b: [f64; 2],
    /// Duration of the segment as a fraction of the exposure.
    pub frac: f64,
    /// Apparent ball radius (px).
    pub r: f64,
    /// Ball albedo (linear RGB, 0..1).
    pub rgb: [f32; 3],
}

/// A ball at rest for part of the exposure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    pub c: [f64; 2],
    pub r: f64,
    /// Resting time as a fraction of the exposure.
    pub frac: f64,
    pub rgb: [f32; 3],
    /// Strength of the fixed specular highlight.
    pub specular: f32,
}

/// What the balls do during one exposure, in pixels.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Frame {
    pub segments: Vec<Segment>,
    pub discs: Vec<Disc>,
}

/// Table, lamp and sensor: everything but the balls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Backdrop {
    pub width: u32,
    pub height: u32,
    /// Cloth albedo (linear RGB).
    pub cloth_rgb: [f32; 3],
    /// Relative amplitude of the cloth texture.
    pub texture: f32,
    pub texture_seed: u64,
    /// Lamp level: DN for albedo 1 at the image centre.
    pub lamp: f64,
    /// Relative illumination change across the image width / height.
    pub gradient: [f64; 2],
    /// Vignetting: relative loss at the image corners.
    pub vignette: f64,
    /// Light direction in image coordinates (`x` right, `y` down, `z` towards the camera).
    pub light: [f64; 3],
    /// Sensor noise: variance `a · x + b` (DN²).
    pub noise_a: f64,
    pub noise_b: f64,
}

impl Backdrop {
    /// A dim green table without texture, gradient or vignetting, lit from the upper left, with
    /// noise variance `noise · x + noise`: the scene of the vision modules' unit tests.
    #[cfg(test)]
    pub(crate) fn plain(width: u32, height: u32, noise: f64) -> Backdrop {
        Backdrop {
            width,
            height,
            cloth_rgb: [0.05, 0.2, 0.08],
            texture: 0.0,
            texture_seed: 1,
            lamp: 300.0,
            gradient: [0.0, 0.0],
            vignette: 0.0,
            light: [-0.3, -0.4, 1.0],
            noise_a: noise,
            noise_b: noise,
        }
    }

    /// Lamp level at pixel `(x, y)`.
    pub fn illumination(&self, x: f64, y: f64) -> f64 {
        let (w, h) = (self.width as f64, self.height as f64);
        let (dx, dy) = ((x - 0.5 * w) / w, (y - 0.5 * h) / h);
        let r2 = (4.0 * (dx * dx * w * w + dy * dy * h * h)) / (w * w + h * h);
        self.lamp
            * (1.0 + self.gradient[0] * dx + self.gradient[1] * dy)
            * (1.0 - self.vignette * r2)
    }

    /// Cloth albedo at pixel `(x, y)`: base colour times a texture of two octaves of value noise
    /// (pile and stains) and per-pixel weave grain, plus a chromatic part: an independent
    /// stain-scale noise per channel of [`CHROMA`] × the texture's amplitude (faded patches, dye
    /// and chalk change hue as well as brightness, so the cloth's texture is not a pure scaling
    /// of one colour that a projection could remove exactly).
    pub fn cloth(&self, x: u32, y: u32) -> [f32; 3] {
        let (xf, yf) = (x as f32, y as f32);
        let t = 0.55 * value_noise(xf / 90.0, yf / 90.0, self.texture_seed)
            + 0.3 * value_noise(xf / 11.0, yf / 11.0, self.texture_seed ^ 0x9e37)
            + 0.25 * hash01(x as i64, y as i64, self.texture_seed ^ 0x51ed);
        let mut out = self.cloth_rgb;
        for (c, v) in out.iter_mut().enumerate() {
            let tc = value_noise(
                xf / CHROMA_SCALE,
                yf / CHROMA_SCALE,
                chroma_seed(self.texture_seed, c),
            );
            *v *= 1.0 + self.texture * (t + CHROMA * tc);
        }
        out
    }

    /// Lit cloth without balls at pixel `(x, y)`: illumination × cloth albedo (DN). Stored as
    /// `f32` so that [`Backdrop::base_plate`] and [`expected_at`] agree exactly.
    pub fn base_at(&self, x: u32, y: u32) -> [f32; 3] {
        let l = self.illumination(x as f64 + 0.5, y as f64 + 0.5);
        self.cloth(x, y).map(|c| (l * c as f64) as f32)
    }

    /// [`Backdrop::base_at`] for every pixel (row-major RGB). The table is the same for every
    /// shot of a folder, so this is computed once and shared.
    pub fn base_plate(&self) -> Vec<f32> {
        let w = self.width as usize;
        let mut out = vec![0f32; w * self.height as usize * 3];
        out.par_chunks_mut(w * 3).enumerate().for_each(|(y, row)| {
            // Same arithmetic as `base_at`, with the lattice hashes of the two noise octaves
            // cached along the row (they change only every 90 and 11 pixels).
            let yf = y as f32;
            let mut coarse = NoiseRow::new(yf / 90.0, self.texture_seed);
            let mut fine = NoiseRow::new(yf / 11.0, self.texture_seed ^ 0x9e37);
            let mut chroma: [NoiseRow; 3] = std::array::from_fn(|c| {
                NoiseRow::new(yf / CHROMA_SCALE, chroma_seed(self.texture_seed, c))
            });
            let py = y as f64 + 0.5;
            for x in 0..w {
                let xf = x as f32;
                let t = 0.55 * coarse.at(xf / 90.0)
                    + 0.3 * fine.at(xf / 11.0)
                    + 0.25 * hash01(x as i64, y as i64, self.texture_seed ^ 0x51ed);
                let l = self.illumination(x as f64 + 0.5, py);
                for c in 0..3 {
                    let tc = chroma[c].at(xf / CHROMA_SCALE);
                    let m = 1.0 + self.texture * (t + CHROMA * tc);
                    row[x * 3 + c] = (l * (self.cloth_rgb[c] * m) as f64) as f32;
                }
            }
        });
        out
    }

    fn light_unit(&self) -> [f64; 3] {
        let [x, y, z] = self.light;
        let n = (x * x + y * y + z * z).sqrt();
        [x / n, y / n, z / n]
    }
}

/// Amplitude of the cloth's chromatic texture relative to its brightness texture.
pub const CHROMA: f32 = 0.25;
/// Length scale (px) of the chromatic texture: stains and faded patches.
const CHROMA_SCALE: f32 = 70.0;

fn chroma_seed(seed: u64, channel: usize) -> u64 {
    seed ^ 0xC0_10_0E ^ (channel as u64 + 1).wrapping_mul(0x2545_F491_4F6C_DD1D)
}

/// Integer hash to [-1, 1].
fn hash01(x: i64, y: i64, seed: u64) -> f32 {
    let mut h = seed
        ^ (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^= h >> 33;
    (h >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

/// Smooth value noise in [-1, 1] (bilinear with smoothstep weights), for `x, y ≥ 0`
/// (truncation is the floor there, and much cheaper than a libm call).
fn value_noise(x: f32, y: f32, seed: u64) -> f32 {
    let (ix, iy) = (x as i64, y as i64);
    let (fx, fy) = (x - ix as f32, y - iy as f32);
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    let v00 = hash01(ix, iy, seed);
    let v10 = hash01(ix + 1, iy, seed);
    let v01 = hash01(ix, iy + 1, seed);
    let v11 = hash01(ix + 1, iy + 1, seed);
    let a = v00 + sx * (v10 - v00);
    let b = v01 + sx * (v11 - v01);
    a + sy * (b - a)
}

/// [`value_noise`] along one row, caching the lattice values of the current cell.
struct NoiseRow {
    iy: i64,
    sy: f32,
    seed: u64,
    ix: i64,
    corners: [f32; 4],
}

impl NoiseRow {
    fn new(y: f32, seed: u64) -> Self {
        let iy = y as i64;
        let fy = y - iy as f32;
        NoiseRow {
            iy,
            sy: fy * fy * (3.0 - 2.0 * fy),
            seed,
            ix: i64::MIN,
            corners: [0.0; 4],
        }
    }

    /// Equals `value_noise(x, y, seed)` bit for bit.
    fn at(&mut self, x: f32) -> f32 {
        let ix = x as i64;
        if ix != self.ix {
            self.ix = ix;
            self.corners = [
                hash01(ix, self.iy, self.seed),
                hash01(ix + 1, self.iy, self.seed),
                hash01(ix, self.iy + 1, self.seed),
                hash01(ix + 1, self.iy + 1, self.seed),
            ];
        }
        let fx = x - ix as f32;
        let sx = fx * fx * (3.0 - 2.0 * fx);
        let [v00, v10, v01, v11] = self.corners;
        let a = v00 + sx * (v10 - v00);
        let b = v01 + sx * (v11 - v01);
        a + self.sy * (b - a)
    }
}

/// Diffuse shading (ambient + Lambert) and specular term of a resting ball at relative position
/// `(dx, dy)` (units of its radius) under unit light direction `l`.
pub fn shade(dx: f64, dy: f64, l: [f64; 3]) -> (f32, f32) {
    let rho2 = (dx * dx + dy * dy).min(1.0);
    let s = rho2.sqrt().max(1e-12);
    let (nx, ny) = if rho2 >= 1.0 {
        (dx / s, dy / s)
    } else {
        (dx, dy)
    };
    let n = [nx, ny, (1.0 - rho2).max(0.0).sqrt()];
    let ndl = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
    let diffuse = 0.35 + 0.65 * ndl.max(0.0);
    // Blinn half vector between the light and the camera (straight above).
    let hv = [l[0], l[1], l[2] + 1.0];
    let hn = (hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]).sqrt();
    let ndh = (n[0] * hv[0] + n[1] * hv[1] + n[2] * hv[2]) / hn;
    (diffuse as f32, ndh.max(0.0).powi(80) as f32)
}

/// Fraction of the exposure during which a segment covers pixel centre `(px, py)`.
#[inline]
fn segment_dwell(s: &Segment, px: f64, py: f64) -> f64 {
    let (dx, dy) = (s.b[0] - s.a[0], s.b[1] - s.a[1]);
    let len = (dx * dx + dy * dy).sqrt();
    let (qx, qy) = (px - s.a[0], py - s.a[1]);
    if len < 1e-9 {
        return s.frac * ramp_coverage(s.r, (qx * qx + qy * qy).sqrt());
    }
    let (ux, uy) = (dx / len, dy / len);
    let s0 = qx * ux + qy * uy;
    let d = (qx * uy - qy * ux).abs();
    let mut total = 0.0;
    for rho in [s.r - EDGE_GAUSS, s.r + EDGE_GAUSS] {
        if d < rho {
            let h = (rho * rho - d * d).sqrt();
            let ov = (s0 + h).min(len) - (s0 - h).max(0.0);
            if ov > 0.0 {
                total += ov;
            }
        }
    }
    0.5 * total / len * s.frac
}

/// Antialiased coverage of a pixel centre at distance `dist` from a disc of radius `r`.
#[inline]
fn ramp_coverage(r: f64, dist: f64) -> f64 {
    (r + 0.5 - dist).clamp(0.0, 1.0)
}

/// Sub-pixels per axis where a resting disc's rim crosses a pixel.
const RIM_SUBPIXELS: usize = 16;

/// A resting disc over the pixel whose centre is at `(dx, dy)` from the disc's centre: the
/// covered fraction of the pixel and the pixel means of the diffuse and specular shading over
/// the covered part (zero outside). Inside the rim the shading at the pixel centre stands for
/// the pixel. Where the rim crosses the pixel both are integrated over a 16 × 16 grid of
/// sub-pixels: the Lambert limb rises like `√(R − ρ)` within the rim's pixel, and taking the
/// shading at the pixel centre (clamped to the rim) times a 1-px coverage ramp made the rim
/// darker than it is, which moved the silhouette's measured radius 0.02–0.03 px inwards.
#[inline]
fn disc_pixel(d: &Disc, dx: f64, dy: f64, light: [f64; 3]) -> (f32, f32, f32) {
    let dist = (dx * dx + dy * dy).sqrt();
    // A pixel reaches at most √2/2 px from its centre; the limb's curvature matters within
    // 2 px of the rim.
    if dist >= d.r + std::f64::consts::FRAC_1_SQRT_2 {
        return (0.0, 0.0, 0.0);
    }
    if dist <= d.r - 2.0 {
        let (diff, spec) = shade(dx / d.r, dy / d.r, light);
        return (1.0, diff, spec);
    }
    let n = RIM_SUBPIXELS;
    let r2 = d.r * d.r;
    let (mut cov, mut diff, mut spec) = (0usize, 0.0f64, 0.0f64);
    for j in 0..n {
        let sy = dy - 0.5 + (j as f64 + 0.5) / n as f64;
        for i in 0..n {
            let sx = dx - 0.5 + (i as f64 + 0.5) / n as f64;
            if sx * sx + sy * sy < r2 {
                let (df, sp) = shade(sx / d.r, sy / d.r, light);
                cov += 1;
                diff += df as f64;
                spec += sp as f64;
            }
        }
    }
    let m = (n * n) as f64;
    (cov as f32 / m as f32, (diff / m) as f32, (spec / m) as f32)
}

/// Accumulated ball light at one pixel: total covered fraction and Σ f_k b_k.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Acc {
    pub(super) alpha: f32,
    pub(super) rgb: [f32; 3],
}

/// Adds the ball light of `frame` over rows `y0 .. y0 + rows` (all columns) into `acc`.
pub(super) fn accumulate_band(
    frame: &Frame,
    bd: &Backdrop,
    y0: usize,
    rows: usize,
    acc: &mut [Acc],
) {
    let w = bd.width as usize;
    let (by0, by1) = (y0 as f64, (y0 + rows) as f64);
    let light = bd.light_unit();
    for s in &frame.segments {
        let r = s.r + 1.0;
        let (xmin, xmax) = (s.a[0].min(s.b[0]) - r, s.a[0].max(s.b[0]) + r);
        let (ymin, ymax) = (s.a[1].min(s.b[1]) - r, s.a[1].max(s.b[1]) + r);
        if ymax < by0 || ymin > by1 || xmax < 0.0 || xmin > w as f64 {
            continue;
        }
        let ya = (ymin.floor().max(by0)) as usize;
        let yb = (ymax.ceil().min(by1 - 1.0)) as usize;
        let xa = xmin.floor().max(0.0) as usize;
        let xb = (xmax.ceil() as usize).min(w - 1);
        for y in ya..=yb {
            let row = &mut acc[(y - y0) * w..(y - y0 + 1) * w];
            let py = y as f64 + 0.5;
            for (x, a) in row.iter_mut().enumerate().take(xb + 1).skip(xa) {
                let f = segment_dwell(s, x as f64 + 0.5, py) as f32;
                if f > 0.0 {
                    a.alpha += f;
                    for c in 0..3 {
                        a.rgb[c] += f * s.rgb[c] * MOVING_SHADE;
                    }
                }
            }
        }
    }
    for d in &frame.discs {
        let r = d.r + 1.0;
        if d.c[1] + r < by0 || d.c[1] - r > by1 || d.c[0] + r < 0.0 || d.c[0] - r > w as f64 {
            continue;
        }
        let ya = ((d.c[1] - r).floor().max(by0)) as usize;
        let yb = ((d.c[1] + r).ceil().min(by1 - 1.0)) as usize;
        let xa = (d.c[0] - r).floor().max(0.0) as usize;
        let xb = (((d.c[0] + r).ceil()) as usize).min(w - 1);
        for y in ya..=yb {
            let row = &mut acc[(y - y0) * w..(y - y0 + 1) * w];
            let dy = y as f64 + 0.5 - d.c[1];
            for (x, a) in row.iter_mut().enumerate().take(xb + 1).skip(xa) {
                let dx = x as f64 + 0.5 - d.c[0];
                let (cov, diff, spec) = disc_pixel(d, dx, dy, light);
                if cov > 0.0 {
                    let f = d.frac as f32;
                    a.alpha += f * cov;
                    for c in 0..3 {
                        a.rgb[c] += f * (d.rgb[c] * diff + d.specular * spec);
                    }
                }
            }
        }
    }
}

/// Expected (noise-free) value of one pixel from the lit cloth `base` and its accumulated ball
/// light.
#[inline]
pub(super) fn compose(bd: &Backdrop, base: &[f32], x: u32, y: u32, a: &Acc) -> [f64; 3] {
    if a.alpha <= 0.0 {
        return [base[0] as f64, base[1] as f64, base[2] as f64];
    }
    let l = bd.illumination(x as f64 + 0.5, y as f64 + 0.5);
    let keep = (1.0 - a.alpha).max(0.0) as f64;
    [0, 1, 2].map(|c| base[c] as f64 * keep + l * a.rgb[c] as f64)
}

/// Renders `frame` over `bd` with sensor noise from `noise_seed` (`None`: noise-free).
/// `base` is [`Backdrop::base_plate`] (computed once per folder).
pub fn render(frame: &Frame, bd: &Backdrop, base: &[f32], noise_seed: Option<u64>) -> RgbImage {
    let (w, h) = (bd.width as usize, bd.height as usize);
    assert_eq!(
        base.len(),
        w * h * 3,
        "base plate does not match the backdrop size"
    );
    let mut buf = vec![0u8; w * h * 3];
    buf.par_chunks_mut(w * 3 * BAND_ROWS)
        .enumerate()
        .for_each(|(band, out)| {
            let y0 = band * BAND_ROWS;
            let rows = out.len() / (w * 3);
            let mut acc = vec![Acc::default(); w * rows];
            accumulate_band(frame, bd, y0, rows, &mut acc);
            let mut rng = noise_seed.map(|s| {
                ChaCha8Rng::seed_from_u64(s ^ (band as u64).wrapping_mul(0xA24B_AED4_963E_E407))
            });
            for yy in 0..rows {
                let row_base = &base[(y0 + yy) * w * 3..(y0 + yy + 1) * w * 3];
                for x in 0..w {
                    let b = &row_base[x * 3..x * 3 + 3];
                    let v = compose(bd, b, x as u32, (y0 + yy) as u32, &acc[yy * w + x]);
                    for c in 0..3 {
                        let mut val = v[c];
                        if let Some(rng) = rng.as_mut() {
                            let z: f64 = StandardNormal.sample(rng);
                            val += (bd.noise_a * val.max(0.0) + bd.noise_b).sqrt() * z;
                        }
                        // Round half up; truncation of a non-negative value is its floor.
                        out[(yy * w + x) * 3 + c] = (val.clamp(0.0, 255.0) + 0.5) as u8;
                    }
                }
            }
        });
    RgbImage::from_raw(bd.width, bd.height, buf).expect("buffer has width × height × 3 bytes")
}

/// Noise-free value at one pixel (for ground-truth contrast), same model as [`render`].
pub fn expected_at(frame: &Frame, bd: &Backdrop, x: u32, y: u32) -> [f64; 3] {
    let mut acc = vec![Acc::default(); bd.width as usize];
    accumulate_band(frame, bd, y as usize, 1, &mut acc);
    compose(bd, &bd.base_at(x, y), x, y, &acc[x as usize])
}

/// Rec. 601 luma of an RGB triple.
pub fn luma(c: [f64; 3]) -> f64 {
    0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
}

/// Streak contrast in grey levels (luma): the median over `samples` (pixel positions on a
/// streak's centre line) of the 3×3 mean luma of `img` minus that of `plate` (the empty table).
/// Samples whose 3×3 window leaves the image are skipped; `None` if none remain.
pub fn streak_contrast(img: &RgbImage, plate: &RgbImage, samples: &[[f64; 2]]) -> Option<f64> {
    let mean3 = |im: &RgbImage, x: i64, y: i64| -> f64 {
        let mut s = 0.0;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let p = im.get_pixel((x + dx) as u32, (y + dy) as u32).0;
                s += luma([p[0] as f64, p[1] as f64, p[2] as f64]);
            }
        }
        s / 9.0
    };
    let mut diffs: Vec<f64> = samples
        .iter()
        .filter_map(|&[x, y]| {
            let (xi, yi) = (x.floor() as i64, y.floor() as i64);
            if xi < 1 || yi < 1 || xi + 1 >= img.width() as i64 || yi + 1 >= img.height() as i64 {
                return None;
            }
            Some(mean3(img, xi, yi) - mean3(plate, xi, yi))
        })
        .collect();
    median(&mut diffs)
}

pub fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Naive reference: sample the disc's centre at many instants and count coverage.
    fn dwell_reference(s: &Segment, px: f64, py: f64, n: usize) -> f64 {
        let mut t = 0.0;
        for i in 0..n {
            let u = (i as f64 + 0.5) / n as f64;
            let cx = s.a[0] + u * (s.b[0] - s.a[0]);
            let cy = s.a[1] + u * (s.b[1] - s.a[1]);
            t += ramp_coverage(s.r, ((px - cx).powi(2) + (py - cy).powi(2)).sqrt());
        }
        t / n as f64 * s.frac
    }

    #[test]
    fn analytic_dwell_matches_time_sampling() {
        let s = Segment {
            a: [10.0, 20.0],
            b: [70.0, 45.0],
            frac: 0.1,
            r: 12.0,
            rgb: [1.0; 3],
        };
        let mut worst: f64 = 0.0;
        for y in 0..70 {
            for x in 0..90 {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let a = segment_dwell(&s, px, py);
                let b = dwell_reference(&s, px, py, 20000);
                worst = worst.max((a - b).abs());
            }
        }
        // Two-point quadrature of the 1-px edge ramp: worst error (at edge pixels, where the
        // chord length is a steep function of the radius) below 2 % of the segment's time.
        assert!(worst < 0.02 * s.frac, "worst {worst}");
        // On the centre line, mid-segment: dwell = 2R/L of the segment's time.
        let mid = segment_dwell(&s, 40.0, 32.5);
        let len = (60f64.powi(2) + 25f64.powi(2)).sqrt();
        assert!((mid - 2.0 * 12.0 / len * 0.1).abs() < 1e-3, "{mid}");
    }

    /// A dim green table with gradient, vignette and Poisson–Gaussian noise parameters.
    fn test_backdrop(width: u32, height: u32, texture: f32, texture_seed: u64) -> Backdrop {
        Backdrop {
            width,
            height,
            cloth_rgb: [0.05, 0.2, 0.08],
            texture,
            texture_seed,
            lamp: 300.0,
            gradient: [0.1, -0.05],
            vignette: 0.2,
            light: [-0.3, -0.4, 1.0],
            noise_a: 0.5,
            noise_b: 4.0,
        }
    }

    #[test]
    fn base_plate_equals_pixelwise_base() {
        let bd = test_backdrop(200, 30, 0.08, 11);
        let plate = bd.base_plate();
        for y in 0..30 {
            for x in 0..200 {
                let i = (y * 200 + x) * 3;
                assert_eq!(&plate[i..i + 3], &bd.base_at(x as u32, y as u32)[..]);
            }
        }
    }

    #[test]
    fn a_resting_disc_holds_its_area_and_its_light() {
        // Under a light straight above, the diffuse shading 0.35 + 0.65 √(1 − ρ²/R²) integrates
        // to π R² (0.35 + 0.65 · 2/3) over the disc; the pixels' sums must hold both that and
        // the area π R² however the rim falls on the pixel grid.
        let r = 23.7;
        for (cx, cy) in [(40.0, 40.0), (40.31, 39.77), (40.5, 40.5)] {
            let d = Disc {
                c: [cx, cy],
                r,
                frac: 1.0,
                rgb: [1.0; 3],
                specular: 0.0,
            };
            let (mut area, mut light) = (0.0f64, 0.0f64);
            for y in 0..80 {
                for x in 0..80 {
                    let (cov, diff, _) = disc_pixel(
                        &d,
                        x as f64 + 0.5 - cx,
                        y as f64 + 0.5 - cy,
                        [0.0, 0.0, 1.0],
                    );
                    area += cov as f64;
                    light += diff as f64;
                }
            }
            let a = std::f64::consts::PI * r * r;
            assert!((area / a - 1.0).abs() < 2e-4, "area {area} against {a}");
            let l = a * (0.35 + 0.65 * 2.0 / 3.0);
            assert!((light / l - 1.0).abs() < 5e-4, "light {light} against {l}");
        }
    }

    #[test]
    fn rendering_is_deterministic_and_noise_free_matches_expected() {
        let bd = test_backdrop(64, 40, 0.05, 3);
        let frame = Frame {
            segments: vec![Segment {
                a: [0.0, 20.0],
                b: [64.0, 20.0],
                frac: 0.2,
                r: 6.0,
                rgb: [0.9; 3],
            }],
            discs: vec![Disc {
                c: [32.0, 8.0],
                r: 5.0,
                frac: 0.5,
                rgb: [0.8, 0.6, 0.1],
                specular: 0.5,
            }],
        };
        let base = bd.base_plate();
        let a = render(&frame, &bd, &base, Some(7));
        let b = render(&frame, &bd, &base, Some(7));
        assert_eq!(a.as_raw(), b.as_raw());
        let clean = render(&frame, &bd, &base, None);
        let e = expected_at(&frame, &bd, 33, 20);
        let p = clean.get_pixel(33, 20).0;
        for c in 0..3 {
            assert!((p[c] as f64 - e[c]).abs() <= 0.5 + 1e-9);
        }
        // The streak adds light: 2R/L · frac = 12/64 · 0.2 of ball light on the centre line.
        let plate = render(&Frame::default(), &bd, &base, None);
        assert!(clean.get_pixel(33, 20).0[1] > plate.get_pixel(33, 20).0[1]);
    }
}
