//! The cloth's fixed texture, estimated from a folder's own photos when there is no plate.
//!
//! A camera fixed over one table sees the same cloth in every shot; only the balls move. So the
//! median of many shots, each minus its own smooth cloth surface, is the cloth's texture: the
//! blotches that a per-photo polynomial cannot follow and that bias a faint streak's centre-line.
//! For each of up to [`MAX_IMAGES`] photos (evenly spaced in the folder's sorted list) the
//! residual `r_i = I_i - B_i` of 2×2 block means from the photo's own cloth surface `B_i` (the
//! polynomial of [`super::background`]) is formed; cells near balls (box-smoothed `Σ|r_i|` above
//! its median by more than 5 MAD, dilated by 1/60 of the photo's longer side: 40 px at 2400 px,
//! 0.4 R there) are masked; the texture `T` is
//! the per-cell median of the unmasked residuals within 3 noise sigmas of their median (twice;
//! streak light the mask missed is clipped) where at least a third of the photos (and no
//! fewer than [`MIN_SAMPLES`]) see cloth, and 0 elsewhere: the middle of the table, where the
//! object ball waits in most shots, keeps its texture rather than receive a ghost of the balls.
//! A photo uses `T` only when subtracting it lowers the scatter of its own cloth residual
//! ([`super::background::build`]), so a camera that moved, or another table, gets the plain
//! surface.

use super::background::{
    Fixed, block_means, box_blur, eval_surface, fit_cloth_poly, mad_sigma, mad_sigma_about, median,
    median_of,
};
use super::image_io::RgbImage;
use rayon::prelude::*;

/// Block size (px) of the texture map: fine enough for the cloth's ball-sized blotches and their
/// finer grain, coarse enough to halve the sensor noise of each photo's residual.
pub const BLOCK: usize = 2;
/// Photos used at most (the median's noise falls as `1/√n`; memory grows as `n`).
pub const MAX_IMAGES: usize = 15;
/// Fewest photos for a texture: fewer cannot outvote the balls where shots overlap, and the
/// map's own noise eats the gain (the 24-photo realistic set with the texture from 6 of its
/// photos: psi 0.19°, theta2 0.22° median, against 0.11°, 0.11° from 15 and 0.22°, 0.24°
/// without; clean 0.041° / 0.050° against 0.033° / 0.027° and 0.060° / 0.11°).
pub const MIN_IMAGES: usize = 8;
/// Fewest unmasked photos for a cell's median.
pub const MIN_SAMPLES: usize = 4;

/// The median of the values of `v` within 3 `noise` of its median, twice: a ball's light that
/// the mask missed, in up to a third of the photos where the streaks converge on the middle of
/// the table, moves a plain median by most of a noise sigma (measured on the realistic set:
/// delta1 1.5° median error with the plain median, 0.7° clipped). Stops when fewer than `need`
/// values would be left.
fn clipped_median(v: &mut [f32], noise: f32, need: usize) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    // Sorted once (a cell has at most [`MAX_IMAGES`] values), each pass's values within 3
    // `noise` of the centre are a run of the sorted ones (`x - centre` is monotone in `x`), and
    // a median is the run's middle element: the values [`median`] selects, to the bit.
    sort_total(v);
    let mut centre = v[v.len() / 2];
    for _ in 0..2 {
        let lo = v.partition_point(|&x| x - centre < -3.0 * noise);
        let hi = v.partition_point(|&x| x - centre <= 3.0 * noise);
        let kept = &v[lo..hi.max(lo)];
        if kept.len() < need {
            break;
        }
        centre = kept[kept.len() / 2];
    }
    centre
}

/// Batcher's odd–even merge sort for 16 inputs; its first 19 compare–exchanges sort the
/// first 8 on their own.
#[rustfmt::skip]
const NETWORK_16: [(u8, u8); 63] = [
    (0, 1), (2, 3), (0, 2), (1, 3), (1, 2), (4, 5), (6, 7), (4, 6), (5, 7), (5, 6), (0, 4),
    (2, 6), (2, 4), (1, 5), (3, 7), (3, 5), (1, 2), (3, 4), (5, 6), (8, 9), (10, 11), (8, 10),
    (9, 11), (9, 10), (12, 13), (14, 15), (12, 14), (13, 15), (13, 14), (8, 12), (10, 14),
    (10, 12), (9, 13), (11, 15), (11, 13), (9, 10), (11, 12), (13, 14), (0, 8), (4, 12), (4, 8),
    (2, 10), (6, 14), (6, 10), (2, 4), (6, 8), (10, 12), (1, 9), (5, 13), (5, 9), (3, 11),
    (7, 15), (7, 11), (3, 5), (7, 9), (11, 13), (1, 2), (3, 4), (5, 6), (7, 8), (9, 10),
    (11, 12), (13, 14),
];

/// Sorts `v` in `f32::total_cmp`'s order. Up to 16 values (a texture cell holds at most
/// [`MAX_IMAGES`]) go through a sorting network on their total-order keys (`total_cmp`'s own
/// map of the bits to an `i32`, its own inverse), padded with the largest key: no branch to
/// mispredict, where the insertion sort that `sort_unstable_by` uses on short slices made
/// the per-cell medians 7 % of a realistic folder's time. Values with equal keys have equal
/// bits, so the result is the same to the bit.
fn sort_total(v: &mut [f32]) {
    if v.len() > 16 {
        v.sort_unstable_by(f32::total_cmp);
        return;
    }
    let key = |b: i32| b ^ ((((b >> 31) as u32) >> 1) as i32);
    let mut k = [i32::MAX; 16];
    for (k, x) in k.iter_mut().zip(v.iter()) {
        *k = key(x.to_bits() as i32);
    }
    let network = if v.len() <= 8 {
        &NETWORK_16[..19]
    } else {
        &NETWORK_16[..]
    };
    for &(a, b) in network {
        let (a, b) = (usize::from(a), usize::from(b));
        let (x, y) = (k[a], k[b]);
        k[a] = x.min(y);
        k[b] = x.max(y);
    }
    for (x, k) in v.iter_mut().zip(k) {
        *x = f32::from_bits(key(k) as u32);
    }
}

/// One photo's residual from its own cloth surface, on the texture grid, with its ball mask.
#[derive(Debug, Clone)]
pub struct Residual {
    w: usize,
    h: usize,
    r: Vec<[f32; 3]>,
    cloth: Vec<bool>,
}

/// The texture map of a folder (see the module doc).
#[derive(Debug, Clone)]
pub struct ClothTexture {
    /// Size of the photos it belongs to (full resolution).
    pub w: usize,
    pub h: usize,
    /// Grid size (`w / BLOCK`, `h / BLOCK`).
    pub tw: usize,
    pub th: usize,
    /// Texture per cell and channel; 0 where not estimated.
    pub t: Vec<[f32; 3]>,
    /// Fraction of cells estimated.
    pub coverage: f64,
    /// Photos the median was taken over.
    pub images: usize,
}

/// Coarse grid factor of [`super::background::build`] for this photo size.
pub fn coarse_factor(w: usize, h: usize, coarse_side: usize) -> usize {
    w.max(h).div_ceil(coarse_side.max(16)).max(1)
}

/// Which of `n` sorted photos to use: up to [`MAX_IMAGES`], evenly spaced.
pub fn pick(n: usize) -> Vec<usize> {
    let k = n.min(MAX_IMAGES);
    (0..k).map(|i| i * n / k).collect()
}

/// The residual of one photo from its own cloth surface, and its cloth mask.
pub fn residual(img: &RgbImage, coarse_side: usize) -> Residual {
    let f = coarse_factor(img.w, img.h, coarse_side);
    // Both grids' block means from one pass over the photo.
    let ([(cw, ch, coarse), (tw, th, blocks)], _) =
        block_means::<false, 2>(img, [(Fixed::None, f), (Fixed::None, BLOCK)]);
    let coef = fit_cloth_poly(cw, ch, &coarse);
    let surface = eval_surface(&coef, tw, th, BLOCK as f64 / f as f64, cw as f64, ch as f64);
    let r: Vec<[f32; 3]> = blocks
        .iter()
        .zip(&surface)
        .map(|(b, s)| [b[0] - s[0], b[1] - s[1], b[2] - s[2]])
        .collect();
    // Balls: where the summed |r|, smoothed over a fraction of a ball, stands out.
    let a: Vec<f32> = r
        .iter()
        .map(|d| d[0].abs() + d[1].abs() + d[2].abs())
        .collect();
    let side = tw.max(th);
    let sm = box_blur(&a, tw, th, (side / 150).max(1));
    let level = median_of(&sm);
    let thr = level + 5.0 * mad_sigma_about(&sm, level).max(1e-6);
    let hot: Vec<f32> = sm.iter().map(|&v| f32::from(v > thr)).collect();
    let rd = (side / 60).max(1);
    let near = box_blur(&hot, tw, th, rd);
    // Half a hot cell in the window: a running box sum does not return to exactly 0.
    let tiny = 0.5 / ((2 * rd + 1) * (2 * rd + 1)) as f32;
    let cloth = near.iter().map(|&v| v < tiny).collect();
    Residual {
        w: img.w,
        h: img.h,
        r,
        cloth,
    }
}

impl Residual {
    /// Size of the photo (full resolution).
    pub fn size(&self) -> (usize, usize) {
        (self.w, self.h)
    }
}

impl ClothTexture {
    /// The median texture of the residuals (all of one photo size), or why there is none.
    pub fn from_residuals(res: &[Residual]) -> Result<ClothTexture, String> {
        if res.len() < MIN_IMAGES {
            return Err(format!(
                "{} photos of one size (a cloth texture needs at least {MIN_IMAGES})",
                res.len()
            ));
        }
        let (w, h) = (res[0].w, res[0].h);
        if res.iter().any(|r| r.w != w || r.h != h) {
            return Err("photos of different sizes".into());
        }
        let (tw, th) = (w / BLOCK, h / BLOCK);
        let need = MIN_SAMPLES.max(res.len().div_ceil(3));
        let gather = |i: usize, buf: &mut [Vec<f32>; 3]| {
            for b in buf.iter_mut() {
                b.clear();
            }
            for rr in res.iter().filter(|rr| rr.cloth[i]) {
                for (b, v) in buf.iter_mut().zip(rr.r[i]) {
                    b.push(v);
                }
            }
        };
        // The photos' noise per cell and channel: the median over a sample of cells of the
        // scatter across photos (the texture itself is the same in every photo).
        let mut spread: [Vec<f32>; 3] = Default::default();
        let mut buf: [Vec<f32>; 3] = Default::default();
        for i in (0..tw * th).step_by(97) {
            gather(i, &mut buf);
            if buf[0].len() >= need {
                for c in 0..3 {
                    spread[c].push(mad_sigma(&buf[c]));
                }
            }
        }
        let noise = [0, 1, 2].map(|c| median(&mut spread[c]).max(1e-9));
        let mut t = vec![[0f32; 3]; tw * th];
        t.par_chunks_mut(tw).enumerate().for_each(|(y, row)| {
            let mut buf: [Vec<f32>; 3] = Default::default();
            for (x, cell) in row.iter_mut().enumerate() {
                gather(y * tw + x, &mut buf);
                if buf[0].len() >= need {
                    *cell = [0, 1, 2].map(|c| clipped_median(&mut buf[c], noise[c], need));
                }
            }
        });
        let estimated = t.iter().filter(|v| v.iter().any(|&c| c != 0.0)).count();
        Ok(ClothTexture {
            w,
            h,
            tw,
            th,
            t,
            coverage: estimated as f64 / (tw * th) as f64,
            images: res.len(),
        })
    }

    /// Whether the map belongs to photos of this size.
    pub fn fits(&self, img: &RgbImage) -> bool {
        self.w == img.w && self.h == img.h
    }

    /// The map as a grey picture (128 = 0, the channels summed, 1/2000 per grey level): the
    /// `STREAKFIT_TEXTURE_PNG` debug hook.
    pub fn debug_picture(&self) -> image::GrayImage {
        image::GrayImage::from_fn(self.tw as u32, self.th as u32, |x, y| {
            let v = self.t[y as usize * self.tw + x as usize];
            let s = v[0] + v[1] + v[2];
            image::Luma([(128.0 + 2000.0 * s).clamp(0.0, 255.0) as u8])
        })
    }

    /// The texture at full-resolution pixel `(x, y)`: its cell's value (nearest cell; the
    /// last row and column of cells extend to the photo's edge).
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> [f32; 3] {
        self.row(y)[self.column(x)]
    }

    /// The index, within a [`ClothTexture::row`], of the cell that covers full-resolution
    /// column `x`.
    #[inline]
    pub fn column(&self, x: usize) -> usize {
        (x / BLOCK).min(self.tw - 1)
    }

    /// The row of cells that covers full-resolution row `y`.
    #[inline]
    pub fn row(&self, y: usize) -> &[[f32; 3]] {
        &self.t[(y / BLOCK).min(self.th - 1) * self.tw..][..self.tw]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A cloth with a smooth gradient and a fixed blotch pattern, and a bright "ball" that sits
    /// in a different place in each photo.
    fn photo(i: usize, w: usize, h: usize) -> RgbImage {
        let mut data = Vec::with_capacity(3 * w * h);
        let (bx, by) = (40.0 + 25.0 * i as f64, 30.0 + 10.0 * (i % 4) as f64);
        for y in 0..h {
            for x in 0..w {
                let (xf, yf) = (x as f64, y as f64);
                let tex = 0.02 * ((xf / 7.0).sin() * (yf / 5.0).cos());
                let grad = 0.3 + 0.1 * xf / w as f64;
                let ball = if (xf - bx).hypot(yf - by) < 12.0 {
                    0.5
                } else {
                    0.0
                };
                let v = (grad + tex + ball) as f32;
                data.extend_from_slice(&[v, 0.8 * v, 0.5 * v]);
            }
        }
        RgbImage::from_f32(w, h, data)
    }

    #[test]
    fn texture_is_the_fixed_pattern_and_balls_leave_no_ghost() {
        let (w, h) = (320, 200);
        let res: Vec<Residual> = (0..8).map(|i| residual(&photo(i, w, h), 80)).collect();
        let tex = ClothTexture::from_residuals(&res).expect("eight photos");
        assert!(tex.coverage > 0.9, "coverage {}", tex.coverage);
        // Away from the edges, where the degree-4 surface follows the gradient closely, the
        // map reproduces the blotches' 2×2 block means.
        let mut worst = 0f64;
        for cy in 10..tex.th - 10 {
            for cx in 10..tex.tw - 10 {
                let v = tex.t[cy * tex.tw + cx][0] as f64;
                if v == 0.0 {
                    continue;
                }
                let mut want = 0.0;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (xf, yf) = ((2 * cx + dx) as f64, (2 * cy + dy) as f64);
                    want += 0.25 * 0.02 * ((xf / 7.0).sin() * (yf / 5.0).cos());
                }
                worst = worst.max((v - want).abs());
            }
        }
        assert!(worst < 0.004, "worst texture error {worst}");
        // Subtracting it flattens a new photo's cloth to the gradient.
        let img = photo(9, w, h);
        let (x, y) = (250usize, 150usize);
        let flat = super::super::background::Fixed::Texture(&tex).pixel(img.samples(), w, x, y);
        let want = 0.3 + 0.1 * x as f64 / w as f64;
        assert!((flat[0] as f64 - want).abs() < 0.005);
    }

    /// The clipped median as first written: select, filter the whole cell, select again.
    fn clipped_median_by_selection(v: &mut [f32], noise: f32, need: usize) -> f32 {
        let mut centre = median(v);
        let mut kept: Vec<f32> = Vec::new();
        for _ in 0..2 {
            kept.clear();
            kept.extend(
                v.iter()
                    .copied()
                    .filter(|x| (x - centre).abs() <= 3.0 * noise),
            );
            if kept.len() < need {
                break;
            }
            centre = median(&mut kept);
        }
        centre
    }

    /// The network sort puts values in `total_cmp`'s order, to the bit: signed zeros,
    /// infinities, NaNs of both signs, subnormals, repeated values; every length up to 16 (the
    /// network, whole or its first half) and beyond (the fallback).
    #[test]
    fn network_sort_is_total_cmp_order() {
        let specials = [
            0.0f32,
            -0.0,
            1.5,
            -1.5,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::MIN_POSITIVE / 4.0,
            -f32::MIN_POSITIVE / 4.0,
            f32::MAX,
            f32::MIN,
            3e-3,
            -7.25,
            0.0,
            1.5,
            f32::from_bits(0x7FFF_FFFF),
        ];
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for n in (0..=17).chain([40]) {
            for shift in 0..specials.len() {
                let v: Vec<f32> = (0..n)
                    .map(|i| specials[(i * 7 + shift) % specials.len()])
                    .collect();
                let (mut a, mut b) = (v.clone(), v);
                a.sort_unstable_by(f32::total_cmp);
                sort_total(&mut b);
                assert_eq!(bits(&a), bits(&b), "n {n} shift {shift}");
            }
        }
    }

    proptest! {
        /// The network sort is `total_cmp`'s order on random cells of up to 16 values.
        #[test]
        fn network_sort_holds_on_random_cells(
            vals in prop::collection::vec(prop_oneof![any::<f32>(), -2f32..2.0], 0..17),
        ) {
            let (mut a, mut b) = (vals.clone(), vals);
            a.sort_unstable_by(f32::total_cmp);
            sort_total(&mut b);
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            prop_assert_eq!(bits(&a), bits(&b));
        }

        /// The sorted-run clipped median is the selecting one to the bit, on cells of up to
        /// 15 values with ties, signed zeros and outliers of either sign.
        #[test]
        fn the_sorted_clipped_median_is_the_selecting_one(
            vals in prop::collection::vec(
                prop_oneof![
                    (-300i32..300).prop_map(|k| k as f32 * 0.01),
                    Just(0.0f32),
                    Just(-0.0f32),
                    -1e3f32..1e3,
                ],
                0..16,
            ),
            noise in 0.001f32..2.0,
            need in 1usize..8,
        ) {
            let (mut a, mut b) = (vals.clone(), vals);
            let want = clipped_median_by_selection(&mut a, noise, need);
            let got = clipped_median(&mut b, noise, need);
            prop_assert_eq!(got.to_bits(), want.to_bits());
        }
    }

    #[test]
    fn clipping_removes_a_minority_of_bright_values() {
        // Ten cloth values around 0 (noise 1) and five with a streak's light (+8).
        let mut v: Vec<f32> = vec![-1.2, -0.8, -0.5, -0.2, 0.0, 0.1, 0.3, 0.6, 0.9, 1.1];
        v.extend([8.0, 8.3, 7.6, 8.1, 7.9]);
        let plain = median_of(&v);
        assert!(plain > 0.5, "plain median {plain}");
        let c = clipped_median(&mut v, 1.0, 4);
        // The ten cloth values are left; `median` takes the upper of the middle two.
        assert!((c - 0.1).abs() < 1e-6, "clipped {c}");
    }

    #[test]
    fn too_few_photos_give_no_texture() {
        let res: Vec<Residual> = (0..3).map(|i| residual(&photo(i, 160, 100), 80)).collect();
        let err = ClothTexture::from_residuals(&res).unwrap_err();
        assert!(err.contains("at least 8"), "{err}");
    }
}
