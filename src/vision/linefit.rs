//! A straight streak's centre-line from its pixels, block by block.
//!
//! The centre-line samples of [`super::streak`] read one cross-profile `R/10` long at a time. At a
//! few grey levels of contrast such a profile holds too little light for its centre: the centroid
//! and template estimates break down and scatter several times their stated sigma (hard photos:
//! 5.7 px about the incoming line at a stated 1.05 px). Here the streak's pixels in a band of
//! `±1.6 R` around its line are binned into cells 1 px across and a block long, and the dwell
//! model of a ball of radius `R` moving along the line `n = n₀ + φ s` is fitted to them:
//!
//! `z(s, d) = a₀ K₀(d) + a₂ K₂(d) + b₀ + b₁ d/R`,  `d = n − n₀ − φ s`,
//!
//! `K₀ = 2h`, `K₂ = (2h³/3 + 2h d²)/R²`, `h = √(R² − d²)`: the chord dwell with the flat and the
//! quadratic shading term ([`super::arc`] uses the same kernel), averaged over the cell's width.
//! The amplitudes and the baseline are linear and eliminated per block (variable projection);
//! first `(n₀, φ)` is fitted over all blocks at once (Gauss–Newton, from the samples' line), then
//! each block's own offset `n₀ + δ_b` with `φ` and the shading's share `a₂/a₀` of all blocks
//! held. Each block gives one [`Sample`] at its centre with the sigma of its offset (from its
//! cells' residual scatter and the offset's curvature), so the joint path fit
//! ([`super::pathfit`]) weighs, rescales and tests them like any samples. The scene reading uses
//! them for the incoming streak where its profile samples scatter 1.5 times their sigma or more
//! (`shot::BLOCKS_FROM_SCATTER`: where the profiles hold, their measured template reads better).
//!
//! Frame: `s` runs along the line's unit direction `d` from its point `p`, `n = d × (q − p)`.

use super::background::Signal;
use super::streak::{Exclusion, Sample};
use nalgebra::{SMatrix, SVector};

/// Half-width of the fitted band across the line, in units of `R` (the streak's light reaches
/// `R`; the rest fixes the baseline).
const BAND_R: f64 = 1.6;
/// A block keeps at least this share of its band's cells (others: another ball's light).
const MIN_COVER: f64 = 0.5;
/// Fewest blocks that make a line: the joint fit needs five samples in a group.
const MIN_BLOCKS: usize = 5;

/// One block's cells: mean signal, mean position, pixel count.
struct Block {
    s_mid: f64,
    cells: Vec<Cell>,
}

#[derive(Clone, Copy)]
struct Cell {
    s: f64,
    n: f64,
    z: f64,
    m: f64,
}

/// The dwell kernels `K₀, K₂` at distance `d`, averaged over a cell about 1.4 px wide (a pixel's
/// footprint across an oblique line); three points are enough away from the edge, and the edge's
/// own shape is symmetric about the line.
fn kernels(d: f64, r: f64) -> (f64, f64) {
    let one = |x: f64| {
        let h2 = r * r - x * x;
        if h2 <= 0.0 {
            return (0.0, 0.0);
        }
        let h = h2.sqrt();
        (2.0 * h, (2.0 * h * h2 / 3.0 + 2.0 * h * x * x) / (r * r))
    };
    let (a, b, c) = (one(d - 0.45), one(d), one(d + 0.45));
    ((a.0 + 2.0 * b.0 + c.0) / 4.0, (a.1 + 2.0 * b.1 + c.1) / 4.0)
}

/// Weighted least squares of cell values on `rows` (the basis at each cell): the weighted
/// residuals (appended to `out`) and the amplitudes.
fn project<const N: usize>(
    rows: &[SVector<f64, N>],
    cells: &[Cell],
    out: &mut Vec<f64>,
) -> Option<SVector<f64, N>> {
    let mut ata = SMatrix::<f64, N, N>::zeros();
    let mut atz = SVector::<f64, N>::zeros();
    for (row, c) in rows.iter().zip(cells) {
        ata += row * row.transpose() * c.m;
        atz += row * (c.z * c.m);
    }
    let coef = ata.cholesky()?.solve(&atz);
    for (row, c) in rows.iter().zip(cells) {
        out.push((c.z - row.dot(&coef)) * c.m.sqrt());
    }
    Some(coef)
}

/// The block's fit at line offset `n0 + phi s`: weighted residuals appended to `out`, and the
/// amplitudes `[a₀, a₂, b₀, b₁]`. With `shape = Some(κ)` the shading's share is held
/// (`a₂ = κ a₀`): one amplitude instead of two nearly collinear ones, whose freedom lets noise
/// at a faint streak's edges move its offset.
fn block_residuals(
    b: &Block,
    n0: f64,
    phi: f64,
    r: f64,
    shape: Option<f64>,
    out: &mut Vec<f64>,
) -> Option<[f64; 4]> {
    let at = |c: &Cell| {
        let d = c.n - n0 - phi * c.s;
        let (k0, k2) = kernels(d, r);
        (k0, k2, d / r)
    };
    match shape {
        None => {
            let rows: Vec<SVector<f64, 4>> = b
                .cells
                .iter()
                .map(|c| {
                    let (k0, k2, dr) = at(c);
                    SVector::<f64, 4>::new(k0, k2, 1.0, dr)
                })
                .collect();
            let c = project(&rows, &b.cells, out)?;
            Some([c[0], c[1], c[2], c[3]])
        }
        Some(k) => {
            let rows: Vec<SVector<f64, 3>> = b
                .cells
                .iter()
                .map(|c| {
                    let (k0, k2, dr) = at(c);
                    SVector::<f64, 3>::new(k0 + k * k2, 1.0, dr)
                })
                .collect();
            let c = project(&rows, &b.cells, out)?;
            Some([c[0], k * c[0], c[1], c[2]])
        }
    }
}

/// A converged Gauss–Newton fit: parameters, weighted residuals, and the Jacobian's columns.
struct Solved {
    x: Vec<f64>,
    res: Vec<f64>,
    jac: Vec<Vec<f64>>,
}

/// Gauss–Newton on the offsets `x` (`phi` held when `x` has one entry) of the blocks given,
/// with forward differences.
fn gauss_newton(
    blocks: &[&Block],
    x0: &[f64],
    phi_held: f64,
    r: f64,
    shape: Option<f64>,
) -> Option<Solved> {
    let eval = |x: &[f64]| -> Option<Vec<f64>> {
        let (n0, phi) = (x[0], if x.len() > 1 { x[1] } else { phi_held });
        let mut out = Vec::new();
        for b in blocks {
            block_residuals(b, n0, phi, r, shape, &mut out)?;
        }
        Some(out)
    };
    let steps = [0.02, 2e-5];
    let mut x = x0.to_vec();
    let mut res = eval(&x)?;
    let mut cost: f64 = res.iter().map(|v| v * v).sum();
    let mut jac = Vec::new();
    for _ in 0..12 {
        jac = (0..x.len())
            .map(|k| {
                let mut y = x.clone();
                y[k] += steps[k];
                eval(&y).map(|ry| {
                    ry.iter()
                        .zip(&res)
                        .map(|(a, b)| (a - b) / steps[k])
                        .collect()
                })
            })
            .collect::<Option<Vec<Vec<f64>>>>()?;
        let k = x.len();
        let mut a = nalgebra::DMatrix::<f64>::zeros(k, k);
        let mut g = nalgebra::DVector::<f64>::zeros(k);
        for i in 0..k {
            for j in 0..k {
                a[(i, j)] = jac[i].iter().zip(&jac[j]).map(|(p, q)| p * q).sum();
            }
            g[i] = -jac[i].iter().zip(&res).map(|(p, q)| p * q).sum::<f64>();
        }
        let step = a.cholesky()?.solve(&g);
        // Halve the step until the cost falls (the kernel's edge makes the cost only piecewise
        // smooth far from the minimum).
        let mut t = 1.0;
        let mut moved = false;
        for _ in 0..6 {
            let y: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + t * b).collect();
            if let Some(ry) = eval(&y) {
                let c: f64 = ry.iter().map(|v| v * v).sum();
                if c < cost {
                    (x, res, cost, moved) = (y, ry, c, true);
                    break;
                }
            }
            t *= 0.5;
        }
        if !moved || (t * step[0]).abs() < 1e-4 {
            break;
        }
    }
    Some(Solved { x, res, jac })
}

/// Re-measures a straight streak (the incoming one) along the line through `p` with unit
/// direction `d`, between `s_lo` and `s_hi` along it, in blocks `block` px long, with `excl`'s
/// pixels left out; `proj` is the streak colour's projector ([`Signal::projector`]). `None` when
/// the pixels do not give a line (fewer than five blocks, or a singular fit).
#[allow(clippy::too_many_arguments)]
pub fn block_samples(
    sig: &Signal,
    proj: [f32; 3],
    p: (f64, f64),
    d: (f64, f64),
    s_lo: f64,
    s_hi: f64,
    r: f64,
    excl: &Exclusion,
    block: f64,
) -> Option<Vec<Sample>> {
    let half = BAND_R * r;
    let n_blocks = ((s_hi - s_lo) / block).floor() as usize;
    if n_blocks < MIN_BLOCKS {
        return None;
    }
    let n_bins = (2.0 * half).ceil() as usize;
    // Accumulate pixels into (block, 1-px bin across) cells.
    let mut acc = vec![[0.0f64; 4]; n_blocks * n_bins];
    let corners = [(s_lo, -half), (s_lo, half), (s_hi, -half), (s_hi, half)]
        .map(|(s, n)| (p.0 + s * d.0 - n * d.1, p.1 + s * d.1 + n * d.0));
    let x0 = corners
        .iter()
        .map(|c| c.0)
        .fold(f64::INFINITY, f64::min)
        .max(0.0) as usize;
    let y0 = corners
        .iter()
        .map(|c| c.1)
        .fold(f64::INFINITY, f64::min)
        .max(0.0) as usize;
    let x1 = (corners.iter().map(|c| c.0).fold(0.0, f64::max).ceil() as usize).min(sig.w - 1);
    let y1 = (corners.iter().map(|c| c.1).fold(0.0, f64::max).ceil() as usize).min(sig.h - 1);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (qx, qy) = (x as f64 - p.0, y as f64 - p.1);
            let s = qx * d.0 + qy * d.1;
            let n = d.0 * qy - d.1 * qx;
            if s < s_lo || n.abs() >= half {
                continue;
            }
            let b = ((s - s_lo) / block) as usize;
            if b >= n_blocks || excl.contains(x as f64, y as f64) {
                continue;
            }
            let c = sig.fixed.pixel(sig.rgb.view(), sig.w, x, y);
            let z = proj[0] * c[0] + proj[1] * c[1] + proj[2] * c[2];
            let c = &mut acc[b * n_bins + ((n + half) as usize).min(n_bins - 1)];
            c[0] += z as f64;
            c[1] += s;
            c[2] += n;
            c[3] += 1.0;
        }
    }
    let blocks: Vec<Block> = (0..n_blocks)
        .filter_map(|b| {
            let cells: Vec<Cell> = acc[b * n_bins..(b + 1) * n_bins]
                .iter()
                .filter(|c| c[3] > 0.0)
                .map(|c| Cell {
                    z: c[0] / c[3],
                    s: c[1] / c[3],
                    n: c[2] / c[3],
                    m: c[3],
                })
                .collect();
            // Both flanks and the core must be there for the offset and the baseline.
            let covered = |lo: f64, hi: f64| cells.iter().any(|c| c.n >= lo * r && c.n < hi * r);
            ((cells.len() as f64) >= MIN_COVER * n_bins as f64
                && covered(-BAND_R, -1.0)
                && covered(1.0, BAND_R)
                && covered(-0.5, 0.5))
            .then_some(Block {
                s_mid: s_lo + (b as f64 + 0.5) * block,
                cells,
            })
        })
        .collect();
    if blocks.len() < MIN_BLOCKS {
        return None;
    }
    let all: Vec<&Block> = blocks.iter().collect();
    let x = gauss_newton(&all, &[0.0, 0.0], 0.0, r, None)?.x;
    let (n0, phi) = (x[0], x[1]);
    if n0.abs() > 0.5 * r {
        return None;
    }
    // The shading's share of the light, from all blocks together.
    let (mut sa0, mut sa2) = (0.0, 0.0);
    for b in &blocks {
        let c = block_residuals(b, n0, phi, r, None, &mut Vec::new())?;
        sa0 += c[0];
        sa2 += c[1];
    }
    let shape = (sa0 > 0.0).then(|| sa2 / sa0)?;
    let mut out = Vec::with_capacity(blocks.len());
    for b in &blocks {
        let one = [b];
        let Some(Solved { x: xb, res, jac }) = gauss_newton(&one, &[n0], phi, r, Some(shape))
        else {
            continue;
        };
        let n_c = res.len() as f64;
        let s2 = res.iter().map(|v| v * v).sum::<f64>() / (n_c - 4.0).max(1.0);
        let jj: f64 = jac[0].iter().map(|v| v * v).sum();
        let Some(coef) = block_residuals(b, xb[0], phi, r, Some(shape), &mut Vec::new()) else {
            continue;
        };
        if jj <= 0.0 || (xb[0] - n0).abs() > 0.5 * r || coef[0] <= 0.0 {
            continue;
        }
        let n = xb[0] + phi * b.s_mid;
        out.push(Sample {
            x: p.0 + b.s_mid * d.0 - n * d.1,
            y: p.1 + b.s_mid * d.1 + n * d.0,
            sigma: (s2 / jj).sqrt(),
            // The model's light on the line (`K₀(0) = 2R`, `K₂(0) = 2R/3`).
            amp: (coef[0] + coef[1] / 3.0) * 2.0 * r,
        });
    }
    (out.len() >= MIN_BLOCKS).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::render::{self, Backdrop, Frame, Segment};
    use crate::vision::background;

    const R: f64 = 30.0;
    /// The streak's ends in renderer coordinates (pixel centres at half-integers).
    const A: [f64; 2] = [40.0, 150.0];
    const B: [f64; 2] = [560.0, 190.0];

    /// Samples, the true line's point and direction.
    type Read = (Option<Vec<Sample>>, (f64, f64), (f64, f64));

    /// A faint straight streak (about 2 DN on its centre-line) with sensor noise `noise`
    /// (seeded), against a noise-free plate: the samples of [`block_samples`] started on a
    /// line 1.5 px and 0.4° off the true one, blocks `R` long, and the true line (extractor
    /// coordinates: renderer − 0.5) as point and unit direction.
    fn blocks(noise: f64, seed: u64, excl: &Exclusion) -> Read {
        let bd = Backdrop::plain(600, 340, noise);
        let frame = Frame {
            segments: vec![Segment {
                a: A,
                b: B,
                frac: 0.08,
                r: R,
                rgb: [0.86, 0.85, 0.8],
            }],
            // A waiting ball clear of the band (a frame with nothing but faint light is blank).
            discs: vec![render::Disc {
                c: [300.0, 45.0],
                r: R,
                frac: 0.5,
                rgb: [0.86, 0.85, 0.8],
                specular: 0.3,
            }],
        };
        let (img, plate) = crate::vision::rendered_with_plate(&frame, &bd, Some(seed));
        let sig = background::build(&img, background::Cloth::Plate(&plate), 600).expect("signal");
        let p = (A[0] - 0.5, A[1] - 0.5);
        let l = (B[0] - A[0]).hypot(B[1] - A[1]);
        let d = ((B[0] - A[0]) / l, (B[1] - A[1]) / l);
        let turn = 0.4f64.to_radians();
        let d0 = (
            d.0 * turn.cos() - d.1 * turn.sin(),
            d.0 * turn.sin() + d.1 * turn.cos(),
        );
        let p0 = (p.0 - 1.5 * d.1, p.1 + 1.5 * d.0);
        let out = block_samples(&sig, sig.proj, p0, d0, 2.0 * R, l - 2.0 * R, R, excl, R);
        (out, p, d)
    }

    /// Signed distances of the samples from the true line, over their sigmas.
    fn pulls(samples: &[Sample], p: (f64, f64), d: (f64, f64)) -> Vec<f64> {
        samples
            .iter()
            .map(|q| (d.0 * (q.y - p.1) - d.1 * (q.x - p.0)) / q.sigma)
            .collect()
    }

    #[test]
    fn faint_streak_blocks_lie_on_the_true_line_within_their_sigmas() {
        // 6 noise draws × 13 blocks: the pulls' mean is the bias (0 within its standard error,
        // 1/√78) and their mean square the sigmas' honesty. At this contrast (about 2 DN, a
        // block's offset known to 0.4 px) the mean square is 1.75: a streak's edges carry most
        // of its offset and are sharp on the scale of the noise's shift, so the linearised
        // sigma is short by about 1.3 (at a quarter of the noise variance it is honest). The
        // joint fit rescales each group of samples by its own reduced χ² (`pathfit`).
        let mut all = Vec::new();
        let mut sigmas = Vec::new();
        for seed in 1..=6 {
            let (s, p, d) = blocks(0.2, seed, &Exclusion::default());
            let s = s.expect("a line");
            assert_eq!(s.len(), 13, "every block of the span is clean");
            all.extend(pulls(&s, p, d));
            sigmas.extend(s.iter().map(|q| q.sigma));
        }
        let n = all.len() as f64;
        let mean = all.iter().sum::<f64>() / n;
        let ms = all.iter().map(|v| v * v).sum::<f64>() / n;
        sigmas.sort_by(f64::total_cmp);
        let med = sigmas[sigmas.len() / 2];
        assert!(med > 0.1 && med < 1.5, "median block sigma {med:.3} px");
        assert!(
            mean.abs() < 3.0 / n.sqrt(),
            "mean pull {mean:.3} ({all:.2?})"
        );
        assert!(
            (0.5..2.2).contains(&ms),
            "mean square pull {ms:.3}, median sigma {med:.3} px"
        );
    }

    #[test]
    fn excluded_light_drops_its_blocks_and_short_spans_give_no_line() {
        // Another ball's band across the middle third of the streak: its blocks go, the
        // others still lie on the line.
        let mut excl = Exclusion::default();
        excl.add_band(&[(300.0, 0.0), (300.0, 340.0)], 80.0, 30.0);
        let (s, p, d) = blocks(0.2, 3, &excl);
        let s = s.expect("a line");
        assert!((7..=9).contains(&s.len()), "{} blocks", s.len());
        assert!(s.iter().all(|q| (q.x - 299.5).abs() > 80.0));
        assert!(pulls(&s, p, d).iter().all(|v| v.abs() < 4.0));
        // A span of four blocks makes no line.
        let mut excl = Exclusion::default();
        excl.add_band(&[(330.0, 0.0), (330.0, 340.0)], 190.0, 30.0);
        assert!(blocks(0.2, 3, &excl).0.is_none());
    }
}
