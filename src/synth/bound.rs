//! The best `psi` a synthetic photo allows: its Cramér–Rao bound.
//!
//! The extractor reads `psi` from geometry alone: the incoming cue-ball streak's line and the
//! object ball's waiting disc, `sin psi = d / |OP|`, with `d` the distance of the disc's centre
//! `O` from the line and `P` the line's end at the impact (the physics of the outgoing paths is
//! what the photos are taken to measure, so it cannot be assumed). The renderer's expected image
//! `μ(θ)` ([`render`]) and its sensor noise (per channel, variance `a μ + b`, plus `1/12` for the
//! rounding to 8 bits) give the Fisher information `F = Σ_px Σ_ch ∂μ/∂θ ∂μ/∂θᵀ / var` of the
//! image parameters `θ`: the incoming line's sideways shift (which moves `P` and the cue ball's
//! outgoing path with it) and its turn about `P`; the object ball's `x` and `y` (waiting disc and
//! outgoing path); and, as nuisances, the turns of both outgoing paths about where they start
//! ([`Outgoing::Attached`]; with [`Outgoing::Held`] the outgoing paths' light is known and fixed,
//! and only the incoming streak and the waiting disc place the line and `O`).
//! Then `σ_d² = gᵀ F⁻¹ g` with `g = ∂d/∂θ`, and `σ_psi = σ_d / √(|OP|² − d²)`.
//!
//! No unbiased reading of these pixels does better, and the bound is optimistic: the cloth's
//! texture, the lamp, the ball's radius, the streaks' speeds and colours and the outgoing paths'
//! shapes (the cue ball's sliding arc among them) are taken as known (as with a perfect plate),
//! the camera's tilt and distortion as calibrated, and JPEG's losses are ignored. Derivatives
//! are central differences of the exact dwell-time rendering.

use super::render::{self, Acc, Backdrop, Frame};
use super::{FrameParts, ShotPlan, build_frame_parts};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Rows per parallel band.
const BAND_ROWS: usize = 16;

/// Sideways shift (px) of the incoming streak for the central differences; its turn moves the
/// streak's far end by as much. The renderer draws the 1-px edge ramp as two hard radii 0.58 px
/// apart (two-point quadrature), whose chords have square-root corners that no camera's optics
/// and pixel area leave; a step well below their spacing sees them and inflates the
/// information (a scene's shift information is 130, 111, 101, 90 and 83 px⁻² at steps of 0.01,
/// 0.05, 0.1, 0.25 and 0.5 px; a 0.1-px shift reads back as 0.079, 0.093, 0.100, 0.102 and
/// 0.102 px). At a quarter pixel the bound is that of the smooth ramp, to about 5 % in sigma.
const H_SHIFT: f64 = 0.25;
/// Shift of the waiting disc (px): its rim is integrated on 16 × 16 sub-pixels per pixel, so the
/// step spans several of them (a 0.1-px shift reads back as 0.093, 0.098 and 0.100 px at steps
/// of 0.05, 0.25 and 0.5 px).
const H_DISC: f64 = 0.25;

/// What the bound lets the outgoing paths tell about `P` and `O`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Outgoing {
    /// They start at `P` and `O` and move with them, their shapes known and their directions
    /// unknown: their light helps to place `P` and `O` (more than a reader that does not know
    /// the sliding arc's shape can use).
    Attached,
    /// Their light is known and does not move: only the incoming streak and the waiting disc
    /// place the line and `O` (a reader that cannot separate `P`'s position from the unknown
    /// shape of the cue ball's sliding arc, which starts there).
    Held,
}

/// The bound for one shot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PsiBound {
    /// 1-sigma Cramér–Rao bound of `psi` (degrees).
    pub sigma_psi_deg: f64,
    /// Of the distance `d` between `O` and the incoming line (px).
    pub sigma_d_px: f64,
    /// Length of the incoming streak inside the image (px).
    pub incoming_px: f64,
}

/// The Cramér–Rao bounds of `psi` for shot `p` on the table `bd` (`base` is its
/// [`Backdrop::base_plate`]), one per blind radius of `blind_r`: from the waiting disc and every
/// pixel farther than that many ball radii from the impact point `P` (0: every pixel; a reading
/// that cannot use the streaks' light where they overlap near `P` has at best the bound with
/// that part left out). The image is rendered and differentiated once for all of them. `None`
/// when no part of the incoming streak is in the image or the information matrix is singular.
pub fn psi_bound(
    p: &ShotPlan,
    bd: &Backdrop,
    base: &[f32],
    blind_r: &[f64],
    outgoing: Outgoing,
) -> Vec<Option<PsiBound>> {
    let (frame, mut parts) = build_frame_parts(p);
    if outgoing == Outgoing::Held {
        parts = FrameParts {
            incoming: parts.incoming,
            ..FrameParts::default()
        };
    }
    frame_bound(&frame, &parts, bd, base, blind_r)
}

/// The bounds for a frame and its parts (the incoming streak ends at the impact), one per
/// blind radius.
fn frame_bound(
    frame: &Frame,
    parts: &FrameParts,
    bd: &Backdrop,
    base: &[f32],
    blind_r: &[f64],
) -> Vec<Option<PsiBound>> {
    let Some(geo) = Geometry::of(frame, parts) else {
        return vec![None; blind_r.len()];
    };
    let blind_px: Vec<f64> = blind_r.iter().map(|k| k * frame.discs[0].r).collect();
    let Some(fs) = fisher(frame, &geo, bd, base, &blind_px) else {
        return vec![None; blind_r.len()];
    };
    let (w, h) = (bd.width as f64, bd.height as f64);
    let incoming_px = frame.segments[parts.incoming.clone()]
        .iter()
        .map(|s| clipped_length(s.a, s.b, w, h))
        .sum();
    let cos_term = (geo.op2 - geo.d * geo.d).sqrt();
    fs.into_iter()
        .map(|f| {
            let cov = f.try_inverse()?;
            let var_d = (geo.g.transpose() * cov * &geo.g)[(0, 0)];
            if !(var_d > 0.0 && cos_term > 0.0) {
                return None;
            }
            let sigma_d_px = var_d.sqrt();
            Some(PsiBound {
                sigma_psi_deg: (sigma_d_px / cos_term).to_degrees(),
                sigma_d_px,
                incoming_px,
            })
        })
        .collect()
}

/// A rigid motion of some pieces of the frame.
#[derive(Debug, Clone, Copy)]
enum Motion {
    /// By `h` times a unit vector.
    Shift(f64, f64),
    /// By `h` radians about a point.
    Turn([f64; 2]),
}

/// One parameter: which pieces it moves, how, and its step for the central differences.
struct Param {
    segments: Vec<usize>,
    discs: Vec<usize>,
    motion: Motion,
    step: f64,
    /// `∂d/∂θ`.
    g: f64,
}

/// The impact geometry in the image and the parameters of [`psi_bound`].
struct Geometry {
    params: Vec<Param>,
    /// `d = (O − P)·n` and `|OP|²`.
    d: f64,
    op2: f64,
    g: DVector<f64>,
    /// Rows the parameters' pieces touch.
    y_range: (f64, f64),
    /// `P`, around which the blind radii leave pixels out, and the waiting disc (centre and
    /// radius plus a pixel), whose pixels they keep.
    pt: [f64; 2],
    o: (f64, f64, f64),
}

impl Geometry {
    fn of(frame: &Frame, parts: &FrameParts) -> Option<Geometry> {
        let n_in = parts.incoming.len();
        if n_in == 0 || frame.discs.is_empty() {
            return None;
        }
        let last = frame.segments[parts.incoming.end - 1];
        let (dx, dy) = (last.b[0] - last.a[0], last.b[1] - last.a[1]);
        let l = dx.hypot(dy);
        if l <= 0.0 {
            return None;
        }
        let t = (dx / l, dy / l);
        let n = (-t.1, t.0);
        let (pt, o) = (last.b, frame.discs[0].c);
        let (ox, oy) = (o[0] - pt[0], o[1] - pt[1]);
        let rest = |r: Option<usize>| r.into_iter().collect::<Vec<_>>();
        let (cue_out, obj_out): (Vec<usize>, Vec<usize>) = (
            parts.cue_out.clone().collect(),
            parts.object_out.clone().collect(),
        );
        // A turn's step moves the far end of its pieces by the shift's step.
        let reach = |segs: &[usize], c: [f64; 2]| {
            segs.iter()
                .flat_map(|&i| [frame.segments[i].a, frame.segments[i].b])
                .map(|q| (q[0] - c[0]).hypot(q[1] - c[1]))
                .fold(1.0, f64::max)
        };
        let incoming: Vec<usize> = parts.incoming.clone().collect();
        let mut with_cue = incoming.clone();
        with_cue.extend(&cue_out);
        let mut object_discs = vec![0];
        object_discs.extend(rest(parts.object_rest));
        let mut params = vec![
            // The incoming line sideways, with `P` and so the cue ball's outgoing path:
            // d = (O − P)·n falls by h.
            Param {
                segments: with_cue,
                discs: rest(parts.cue_rest),
                motion: Motion::Shift(n.0, n.1),
                step: H_SHIFT,
                g: -1.0,
            },
            // The incoming line turned by ε about `P`: n becomes n − ε t.
            Param {
                step: H_SHIFT / reach(&incoming, pt),
                segments: incoming,
                discs: vec![],
                motion: Motion::Turn(pt),
                g: -(ox * t.0 + oy * t.1),
            },
            // The object ball, waiting and leaving: d rises by h n_x or h n_y.
            Param {
                segments: obj_out.clone(),
                discs: object_discs.clone(),
                motion: Motion::Shift(1.0, 0.0),
                step: H_DISC,
                g: n.0,
            },
            Param {
                segments: obj_out.clone(),
                discs: object_discs,
                motion: Motion::Shift(0.0, 1.0),
                step: H_DISC,
                g: n.1,
            },
        ];
        // Nuisances: the directions of both outgoing paths, which the reading cannot assume
        // (they are what the photos measure). A path without pieces in the frame has none.
        for (segments, rest_disc, pivot) in [
            (cue_out, parts.cue_rest, pt),
            (obj_out, parts.object_rest, o),
        ] {
            if !segments.is_empty() {
                params.push(Param {
                    step: H_SHIFT / reach(&segments, pivot),
                    segments,
                    discs: rest(rest_disc),
                    motion: Motion::Turn(pivot),
                    g: 0.0,
                });
            }
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for prm in &params {
            for &i in &prm.segments {
                let s = frame.segments[i];
                lo = lo.min(s.a[1].min(s.b[1]) - s.r - 2.0);
                hi = hi.max(s.a[1].max(s.b[1]) + s.r + 2.0);
            }
            for &i in &prm.discs {
                let dsc = frame.discs[i];
                lo = lo.min(dsc.c[1] - dsc.r - 2.0);
                hi = hi.max(dsc.c[1] + dsc.r + 2.0);
            }
        }
        let g = DVector::from_iterator(params.len(), params.iter().map(|p| p.g));
        Some(Geometry {
            params,
            d: ox * n.0 + oy * n.1,
            op2: ox * ox + oy * oy,
            g,
            y_range: (lo, hi),
            pt,
            o: (o[0], o[1], frame.discs[0].r + 1.0),
        })
    }

    /// The pieces of parameter `k`, moved by `sign` times its step, alone in a frame.
    fn perturbed(&self, frame: &Frame, k: usize, sign: f64) -> Frame {
        let prm = &self.params[k];
        let h = sign * prm.step;
        let mv = |q: [f64; 2]| match prm.motion {
            Motion::Shift(ux, uy) => [q[0] + h * ux, q[1] + h * uy],
            Motion::Turn(c) => {
                let (cs, sn) = (h.cos(), h.sin());
                let (x, y) = (q[0] - c[0], q[1] - c[1]);
                [c[0] + cs * x - sn * y, c[1] + sn * x + cs * y]
            }
        };
        let mut f = Frame::default();
        for &i in &prm.segments {
            let mut seg = frame.segments[i];
            (seg.a, seg.b) = (mv(seg.a), mv(seg.b));
            f.segments.push(seg);
        }
        for &i in &prm.discs {
            let mut dsc = frame.discs[i];
            dsc.c = mv(dsc.c);
            f.discs.push(dsc);
        }
        f
    }

    /// The bands of rows the parameters' pieces touch, from a multiple of [`BAND_ROWS`].
    fn rows(&self, h: usize) -> std::ops::Range<usize> {
        let lo = (self.y_range.0.floor().max(0.0) as usize) / BAND_ROWS * BAND_ROWS;
        let hi = (self.y_range.1.ceil().max(0.0) as usize).min(h);
        lo..hi.max(lo)
    }
}

/// `∂μ/∂θ` of every channel at the pixels of one band (`None` where no parameter moves the
/// light), with the expected value `μ` of the whole frame and the pixel's distance from `P`
/// as the blind radii see it (infinite inside the waiting disc, whose pixels they keep).
type PixelJacobian = Option<([f64; 3], [DVector<f64>; 3], f64)>;

fn band_jacobian(
    frame: &Frame,
    geo: &Geometry,
    pairs: &[(Frame, Frame)],
    bd: &Backdrop,
    base: &[f32],
    y0: usize,
    rows: usize,
) -> Vec<PixelJacobian> {
    let w = bd.width as usize;
    let band = |fr: &Frame| {
        let mut acc = vec![Acc::default(); w * rows];
        render::accumulate_band(fr, bd, y0, rows, &mut acc);
        acc
    };
    let full = band(frame);
    let diffs: Vec<(Vec<Acc>, Vec<Acc>)> = pairs.iter().map(|(a, b)| (band(a), band(b))).collect();
    (0..w * rows)
        .map(|i| {
            if diffs
                .iter()
                .all(|(a, b)| a[i].alpha.to_bits() == b[i].alpha.to_bits())
            {
                return None;
            }
            let (x, y) = (i % w, y0 + i / w);
            // The waiting disc's own pixels stay whatever the blind radius: the reading
            // measures it apart.
            let (ex, ey) = (x as f64 + 0.5 - geo.o.0, y as f64 + 0.5 - geo.o.1);
            let seen_at = if ex * ex + ey * ey <= geo.o.2 * geo.o.2 {
                f64::INFINITY
            } else {
                (x as f64 + 0.5 - geo.pt[0]).hypot(y as f64 + 0.5 - geo.pt[1])
            };
            let b3 = &base[(y * w + x) * 3..(y * w + x) * 3 + 3];
            let mu = render::compose(bd, b3, x as u32, y as u32, &full[i]);
            let l = bd.illumination(x as f64 + 0.5, y as f64 + 0.5);
            // The expected value is linear in the ball light: L·Σ f b − base·Σ f.
            let jac = [0, 1, 2].map(|c| {
                DVector::from_iterator(
                    diffs.len(),
                    diffs.iter().zip(&geo.params).map(|((p, m), prm)| {
                        let da = (p[i].alpha - m[i].alpha) as f64;
                        let dr = (p[i].rgb[c] - m[i].rgb[c]) as f64;
                        (l * dr - b3[c] as f64 * da) / (2.0 * prm.step)
                    }),
                )
            });
            Some((mu, jac, seen_at))
        })
        .collect()
}

/// Sensor variance of a channel whose expected value is `mu`, with the 8-bit rounding.
fn variance(bd: &Backdrop, mu: f64) -> f64 {
    bd.noise_a * mu.max(0.0) + bd.noise_b + 1.0 / 12.0
}

/// The Fisher information of the parameters over the whole image, one matrix per blind radius
/// (px) from the same Jacobians.
fn fisher(
    frame: &Frame,
    geo: &Geometry,
    bd: &Backdrop,
    base: &[f32],
    blind_px: &[f64],
) -> Option<Vec<DMatrix<f64>>> {
    let h = bd.height as usize;
    let rows = geo.rows(h);
    let k = geo.params.len();
    if rows.is_empty() {
        return None;
    }
    let pairs: Vec<(Frame, Frame)> = (0..k)
        .map(|j| (geo.perturbed(frame, j, 1.0), geo.perturbed(frame, j, -1.0)))
        .collect();
    let zeros = || vec![DMatrix::<f64>::zeros(k, k); blind_px.len()];
    let mut fs = rows
        .step_by(BAND_ROWS)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|y0| {
            let n = BAND_ROWS.min(h - y0);
            let mut fb = zeros();
            for (mu, jac, seen_at) in band_jacobian(frame, geo, &pairs, bd, base, y0, n)
                .into_iter()
                .flatten()
            {
                for (f, _) in fb.iter_mut().zip(blind_px).filter(|(_, b)| seen_at >= **b) {
                    for c in 0..3 {
                        f.syger(1.0 / variance(bd, mu[c]), &jac[c], &jac[c], 1.0);
                    }
                }
            }
            fb
        })
        .reduce(zeros, |a, b| {
            a.into_iter().zip(b).map(|(a, b)| a + b).collect()
        });
    // `syger` fills the lower triangle only.
    for f in &mut fs {
        f.fill_upper_triangle_with_lower_triangle();
    }
    Some(fs)
}

/// Length of segment `a → b` inside `[0, w] × [0, h]`.
fn clipped_length(a: [f64; 2], b: [f64; 2], w: f64, h: f64) -> f64 {
    let (a, b) = ((a[0], a[1]), (b[0], b[1]));
    crate::report::plot::clip_interval(a, b, ((0.0, w), (0.0, h)))
        .map_or(0.0, |(t0, t1)| (t1 - t0) * (b.0 - a.0).hypot(b.1 - a.1))
}

/// The median |error| over a set of shots that a reader attaining each shot's bound `σ_i`
/// (Gaussian, unbiased) would have: the `m` at which `mean_i P(|N(0, σ_i²)| ≤ m) = ½`.
pub fn efficient_median(sigmas: &[f64]) -> Option<f64> {
    if sigmas.is_empty() || sigmas.iter().any(|s| s.is_nan() || *s <= 0.0) {
        return None;
    }
    let share = |m: f64| {
        sigmas
            .iter()
            .map(|s| libm::erf(m / (s * std::f64::consts::SQRT_2)))
            .sum::<f64>()
            / sigmas.len() as f64
    };
    let (mut lo, mut hi) = (0.0, sigmas.iter().cloned().fold(0.0, f64::max) * 10.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if share(mid) < 0.5 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::super::render::{Disc, Segment};
    use super::*;

    /// A small scene: a white ball's incoming streak, six pieces from off the left edge to `P`
    /// at (120, 78), and a red ball waiting at psi = 30° (`|OP| = 2R`), on a plain table.
    fn scene() -> (Frame, FrameParts, Backdrop, Vec<f32>) {
        let bd = Backdrop::plain(240, 160, 2.0);
        let base = bd.base_plate();
        let (a, p) = ([-60.0, 70.0], [120.0, 78.0]);
        let mut frame = Frame::default();
        for i in 0..6 {
            let at = |t: f64| [a[0] + t * (p[0] - a[0]), a[1] + t * (p[1] - a[1])];
            frame.segments.push(Segment {
                a: at(i as f64 / 6.0),
                b: at((i + 1) as f64 / 6.0),
                frac: 0.05,
                r: 12.0,
                rgb: [0.8, 0.8, 0.8],
            });
        }
        let dir = (p[1] - a[1]).atan2(p[0] - a[0]) + 30f64.to_radians();
        frame.discs.push(Disc {
            c: [p[0] + 24.0 * dir.cos(), p[1] + 24.0 * dir.sin()],
            r: 12.0,
            frac: 0.5,
            rgb: [0.7, 0.2, 0.1],
            specular: 0.0,
        });
        let parts = FrameParts {
            incoming: 0..6,
            ..FrameParts::default()
        };
        (frame, parts, bd, base)
    }

    /// Expected values `μ` and the Jacobian of every pixel channel the parameters move.
    fn pixels(
        frame: &Frame,
        parts: &FrameParts,
        bd: &Backdrop,
        base: &[f32],
    ) -> Vec<(usize, f64, DVector<f64>)> {
        let geo = Geometry::of(frame, parts).unwrap();
        let pairs: Vec<(Frame, Frame)> = (0..geo.params.len())
            .map(|k| (geo.perturbed(frame, k, 1.0), geo.perturbed(frame, k, -1.0)))
            .collect();
        let (w, h) = (bd.width as usize, bd.height as usize);
        let mut out = Vec::new();
        for (i, px) in band_jacobian(frame, &geo, &pairs, bd, base, 0, h)
            .into_iter()
            .enumerate()
        {
            if let Some((mu, jac, _)) = px {
                for (c, j) in jac.into_iter().enumerate() {
                    out.push(((i % w + (i / w) * w) * 3 + c, mu[c], j));
                }
            }
        }
        out
    }

    /// The noise-free image (no rounding) of `frame`.
    fn expected(frame: &Frame, bd: &Backdrop, base: &[f32]) -> Vec<f64> {
        let (w, h) = (bd.width as usize, bd.height as usize);
        let mut acc = vec![Acc::default(); w * h];
        render::accumulate_band(frame, bd, 0, h, &mut acc);
        (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                render::compose(bd, &base[i * 3..i * 3 + 3], x as u32, y as u32, &acc[i])
            })
            .collect()
    }

    /// The one-parameter linear reader `ŝ = Σ J (y − μ) / var / Σ J² / var` of parameter `k`.
    fn read(px: &[(usize, f64, DVector<f64>)], bd: &Backdrop, k: usize, y: &[f64]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (i, mu, jac) in px {
            let (i, mu) = (*i, *mu);
            let v = variance(bd, mu);
            num += jac[k] * (y[i] - mu) / v;
            den += jac[k] * jac[k] / v;
        }
        num / den
    }

    #[test]
    fn the_jacobian_reads_back_a_known_shift_of_the_streak_and_of_the_disc() {
        let (frame, parts, bd, base) = scene();
        let px = pixels(&frame, &parts, &bd, &base);
        // The streak moved 0.1 px along its normal, by hand.
        let mut moved = frame.clone();
        let (dx, dy) = (180.0f64, 8.0f64);
        let n = (-dy / dx.hypot(dy), dx / dx.hypot(dy));
        for s in &mut moved.segments {
            for q in [&mut s.a, &mut s.b] {
                q[0] += 0.1 * n.0;
                q[1] += 0.1 * n.1;
            }
        }
        let s = read(&px, &bd, 0, &expected(&moved, &bd, &base));
        assert!((s - 0.1).abs() < 0.005, "streak shift read as {s}");
        // The disc moved 0.1 px in y. (Its Lambert limb rises like √(R − ρ), so its light is
        // far from linear in larger shifts: 0.5 px reads back as 0.41. The disc's own
        // uncertainty is hundredths of a pixel, where the linear model holds.)
        let mut moved = frame.clone();
        moved.discs[0].c[1] += 0.1;
        let s = read(&px, &bd, 3, &expected(&moved, &bd, &base));
        assert!((s - 0.1).abs() < 0.005, "disc shift read as {s}");
    }

    #[test]
    fn the_information_is_the_inverse_spread_of_the_best_reader_on_noisy_renders() {
        // 400 renders with the renderer's own noise and 8-bit rounding: the linear reader's
        // spread must be what the information says (its variance estimate has a 7 % standard
        // error), and it must not be biased.
        let (frame, parts, bd, base) = scene();
        let px = pixels(&frame, &parts, &bd, &base);
        let info: f64 = px
            .iter()
            .map(|(_, mu, j)| j[0] * j[0] / variance(&bd, *mu))
            .sum();
        let reads: Vec<f64> = (0..400u64)
            .map(|seed| {
                let img = render::render(&frame, &bd, &base, Some(seed));
                let y: Vec<f64> = img.as_raw().iter().map(|v| *v as f64).collect();
                read(&px, &bd, 0, &y)
            })
            .collect();
        let n = reads.len() as f64;
        let mean = reads.iter().sum::<f64>() / n;
        let var = reads.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let ratio = var * info;
        assert!(
            (0.8..1.2).contains(&ratio),
            "spread² × information = {ratio}"
        );
        assert!(mean.abs() < 4.0 * (var / n).sqrt(), "mean read {mean}");
        // And the whole bound: sigma_psi from sigma_d and |OP| = 2R at psi = 30°.
        let b = frame_bound(&frame, &parts, &bd, &base, &[0.0])[0].unwrap();
        let expect = (b.sigma_d_px / (24.0 * 30f64.to_radians().cos())).to_degrees();
        assert!((b.sigma_psi_deg - expect).abs() < 1e-6 * expect);
        assert!(
            b.sigma_d_px >= 1.0 / info.sqrt(),
            "nuisances cannot add information"
        );
        assert!((b.incoming_px - 120.118).abs() < 0.001, "{}", b.incoming_px);
        // Leaving out the streak's light near P can only lose information: the bound grows
        // with the blind radius, and beyond the streak's visible length (10 R here) only the
        // streak's pixels inside the disc's remain, which hardly place the line.
        let blind =
            |k: f64| frame_bound(&frame, &parts, &bd, &base, &[k])[0].map(|b| b.sigma_psi_deg);
        let (s2, s4) = (blind(2.0).unwrap(), blind(4.0).unwrap());
        assert!(
            b.sigma_psi_deg < s2 && s2 < s4,
            "{} {s2} {s4}",
            b.sigma_psi_deg
        );
        let s12 = blind(12.0);
        assert!(s12.is_none_or(|s| s > 10.0 * s4), "{s12:?}");
    }

    #[test]
    fn efficient_median_of_one_sigma_is_the_gaussian_median() {
        // The median of |N(0, σ²)| is 0.6745 σ.
        let m = efficient_median(&[2.0]).unwrap();
        assert!((m - 2.0 * 0.674_489_750_196_081_7).abs() < 1e-9, "{m}");
        // Half the shots exact to 1e-9 and half at σ = 1: mean P = ½ needs P(|N| ≤ m) = 0 for
        // the wide half, so m sits at the narrow shots' edge, far below 0.6745.
        let m2 = efficient_median(&[1e-9, 1e-9, 1.0, 1.0]).unwrap();
        assert!(m2 < 1e-7, "{m2}");
        assert!(efficient_median(&[]).is_none());
    }

    #[test]
    fn clipped_length_of_segments() {
        assert!((clipped_length([-10.0, 5.0], [30.0, 5.0], 20.0, 10.0) - 20.0).abs() < 1e-12);
        assert!(clipped_length([-10.0, -5.0], [30.0, -5.0], 20.0, 10.0).abs() < 1e-12);
        assert!((clipped_length([1.0, 1.0], [4.0, 5.0], 20.0, 10.0) - 5.0).abs() < 1e-12);
    }
}
