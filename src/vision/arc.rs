//! The cue ball's sliding arc near the impact, measured from pixels.
//!
//! A rolling or lightly spun cue ball slides for only about one ball radius after the impact, so
//! its arc lies where its light overlaps the incoming streak and touches the object ball's disc:
//! no clean centre-line sample exists there, and the centre-line fit fixes the rolling line but
//! not the start tangent `delta`. Here the light itself is modelled in a window around the
//! impact point `P` and fitted.
//!
//! Photometry (see [`super`]): the signal is linear in the dwell time, and a ball of radius `R`
//! moving along a straight piece of length `L` in time `dt` covers a pixel at offset `(x, y)`
//! (along, across) for `|[x - h, x + h] ∩ [0, L]| dt / L`, `h = √(R² - y²)`. Ball shading makes
//! the kernel radial rather than flat: the dwell is weighted by `k(d) = c₀ + c₂ d²/R²` (`d` the
//! pixel's distance from the ball centre), both terms integrated exactly along each piece.
//!
//! Sampling: the fit reads one value per `b × b` cell (`b ≈ R/25`), the cell's mean, not one
//! pixel of it. Reading single pixels threw away 15/16 of the light and, worse, made the cost
//! rugged: whether a sampled pixel sits on a streak's 1-px edge decides most of its information,
//! so noise moved `δ` by 0.25–0.6° between local minima (measured: 3 geometries × 11 noise seeds at
//! R = 100 px; the linearised sigma said 0.1°). The model of a cell mean is the dwell of a disc
//! whose edge is a ramp of the same variance as the 1-px antialiasing ramp and the cell together
//! ([`Kernel::for_cells`]): the mean of hard discs of radii spread uniformly over `R ± w/2`,
//! integrated along each piece in closed form ([`Prepared::dwell`]). With it the same test gives
//! mean errors of 0.03–0.07° and scatter of 0.04–0.14°.
//!
//! Paths: the sliding arc is the quadratic Bézier `S = P, C = P + L₀ u(δ), P₁ = C + L₁ u(θ)`
//! traversed uniformly in its parameter, which *is* constant acceleration; its speed runs from
//! `2L₀/T` to `2L₁/T`, and the rolling line continues from `P₁` at the end speed. So the arc's
//! brightness along its length follows from the same three numbers as its shape. The incoming
//! streak is a straight piece ending at `P` at its own (free) speed.
//!
//! Model per pixel: `a₀ D₀ + a₂ D₂ + a₁ D₁` (outgoing) `+ b₀ E₀ + b₂ E₂ + b₁ E₁` (incoming) plus
//! a quadratic baseline (cloth level and gradient; the plate is already subtracted when there is
//! one). `D₁`, `E₁` are the straight pieces' dwell weighted by the distance along them: a rolling
//! ball decelerates (rolling resistance), so its streak brightens along its path, by some 4 % per
//! `R` for a slow cue ball; without that ramp the arc fit read the brightness gradient beyond `P₁`
//! as a sharper arc (+0.3° to +1.8° at small psi, noise-free, true geometry). The
//! amplitudes enter linearly and are eliminated (variable projection); `δ, L₀, L₁` are found by
//! Levenberg–Marquardt from the best of a few starts on the measured rolling line, with the
//! projected residuals' Jacobian in closed form (Golub–Pereyra, from each piece's dwell
//! differentiated with respect to its ends: [`Prepared::gradients_of`]). `θ` and `P`
//! come from the centre-line fit (they are far better determined there). Pixels of the object
//! ball (its waiting disc and its streak) are left out; outliers beyond 4 MAD are dropped once.
//! Where the cloth's blotches dominate the residual (photos without a plate), `δ` comes from the
//! same fit on high-passed data and columns (each cell minus its ±R/4 box mean; [`HIGHPASS_R`]).
//! Rivals: the start tangent is held 10° either side of the optimum on a short arc (legs 0.4 R)
//! and the legs refitted; when a rival's cost is within 25 units of the correlation-widened
//! residual variance, the turn may hide where the streaks overlap and `δ` is not measured. After
//! the high-pass the rival turning more is tried again on the filtered light. An optimum whose
//! first leg is under [`MIN_ARC_R`] is [`ArcMiss::Hidden`]: the turn is inside the ball's disc.
//! The arc ends no farther along `θ` than the first clean centre-line sample plus `R/2`
//! ([`ArcGeometry::max_end`]): every step (and start) is projected onto that bound by shortening
//! `L₁`, and an optimum on it is no reading ([`ArcMiss::Beyond`]).

use super::background::{Signal, mad_sigma};
use super::streak::seg_dist2;
use nalgebra::{DMatrix, DVector};
use std::borrow::Cow;

/// Result of the pixel fit of the sliding arc (image angles, radians).
#[derive(Debug, Clone, Copy)]
pub struct ArcFit {
    /// Start tangent direction in the image.
    pub delta: f64,
    /// Its 1-sigma uncertainty: the fit's own (residual scale, curvature, correlation), the
    /// held rolling direction's (`∂δ/∂θ` times `theta_sd`) and a measured systematic part.
    pub delta_sd: f64,
    /// An arc turning [`RIVAL_TURN_DEG`] more or less fits nearly as well: the start tangent
    /// is not measured, whatever `delta_sd` says.
    pub rival: bool,
    pub l0: f64,
    pub l1: f64,
    /// End of the sliding arc `P₁` (image).
    pub end: (f64, f64),
    /// Pixels used and residual RMS (signal units).
    pub n_px: usize,
    pub rms: f64,
    /// `delta` comes from the high-passed fit ([`HIGHPASS_R`]).
    pub highpass: bool,
}

/// What the arc fit needs from the centre-line fit.
#[derive(Debug, Clone, Copy)]
pub struct ArcGeometry {
    /// Cue ball's centre at impact.
    pub p: (f64, f64),
    pub r: f64,
    /// Rolling direction `θ` and a point of the rolling line (image).
    pub theta: f64,
    pub line_point: (f64, f64),
    /// Unit direction of the incoming motion (towards `P`).
    pub incoming: (f64, f64),
    /// Object ball: its waiting centre and its path's start direction.
    pub o: (f64, f64),
    pub object_dir: (f64, f64),
    /// Starting guess of the start tangent (image angle), if the centre-line fit has one.
    pub delta_guess: Option<f64>,
    /// The stated 1-sigma uncertainty of `theta` (rad), propagated into `δ`'s.
    pub theta_sd: f64,
    /// How far along `θ` from `P` the arc may end (px): the clean centre-line samples lie on
    /// the rolling line, so an arc ending beyond them contradicts them. `None`: no bound.
    pub max_end: Option<f64>,
}

/// A disc with a soft edge of width `w`: coverage `K(d) = 1` out to `R - w/2`, falling linearly
/// to 0 at `R + w/2` (the mean of hard discs of radii uniform on `R ± w/2`).
#[derive(Debug, Clone, Copy)]
struct Kernel {
    /// Square of the inner radius `R - w/2`, and the ramp's inverse width.
    rmin2: f64,
    inv_w: f64,
    /// Outer radius `R + w/2`: a pixel farther than this from a piece is not covered.
    rmax: f64,
    rmax2: f64,
    /// `1/R²` and `1/R` (the shaded and ramp weights).
    inv_r2: f64,
    inv_r: f64,
}

impl Kernel {
    fn new(r: f64, w: f64) -> Kernel {
        let (rmin, rmax) = (r - 0.5 * w, r + 0.5 * w);
        Kernel {
            rmin2: rmin * rmin,
            inv_w: 1.0 / w,
            rmax,
            rmax2: rmax * rmax,
            inv_r2: 1.0 / (r * r),
            inv_r: 1.0 / r,
        }
    }

    /// The kernel matching cell means of `b × b` px: the 1-px ramp (variance 1/12) plus the cell's
    /// samples at offsets `k - (b - 1)/2` (variance `(b² - 1)/12`), which for even `b` fall on
    /// half pixels and are bilinear (another 1/4); a uniform ramp of that variance is `w` wide.
    fn for_cells(r: f64, b: usize) -> Kernel {
        let b2 = (b * b) as f64;
        let w2 = if b.is_multiple_of(2) { b2 + 3.0 } else { b2 };
        Kernel::new(r, w2.max(1.0).sqrt())
    }
}
/// Pieces of the Bézier: the sagitta of a piece, `(l/16)² κ / 8`, stays below 0.05 px for an arc of
/// length `l = R` turning by 1 rad (κ = 1/R) at R = 100 px.
const N_ARC: usize = 16;
/// Extent (in R) of the modelled rolling line beyond `P₁` and of the incoming streak before `P`,
/// longer than the window's so that no modelled end cap falls inside it.
const LINE_EXTRA_R: f64 = 12.0;
const INCOMING_R: f64 = 4.0;
/// The window (in R): the incoming streak this far before `P`, the rolling line this far beyond
/// `P₁`, and cloth this far beyond the streaks' edges (for the baseline).
const WINDOW_INCOMING_R: f64 = 1.5;
const WINDOW_LINE_R: f64 = 1.0;
const WINDOW_CLOTH_R: f64 = 0.5;
/// Linear columns: outgoing (2, the flat one times `x`, `y` for the lamp's gradient over the
/// window, and the rolling line's ramp), incoming (2 and its ramp), quadratic baseline (6).
const NLIN: usize = 14;
/// Fixed (per-pixel, parameter-free) columns: incoming (3) and baseline (6).
const NFIX: usize = 9;
/// Columns that depend on the nonlinear parameters (the first ones).
const NVAR: usize = NLIN - NFIX;

/// A pixel's dwell under a path: flat `D₀`, shaded `D₂` and the rolling line's ramp `D₁`.
#[derive(Debug, Clone, Copy, Default)]
struct Dwell {
    d0: f64,
    d2: f64,
    ramp: f64,
}

/// One pixel's outgoing (parameter-dependent) columns from its dwell and its unfiltered fixed
/// columns (whose `x`, `y` give the lamp's gradient).
#[inline]
fn var_columns(out: Dwell, fixed: &[f64; NFIX]) -> [f64; NVAR] {
    [
        out.d0,
        out.d2,
        out.d0 * fixed[4],
        out.d0 * fixed[5],
        out.ramp,
    ]
}

/// A pixel's full row of linear columns.
#[inline]
fn row_of(var: &[f64; NVAR], fixed: &[f64; NFIX]) -> [f64; NLIN] {
    let mut row = [0.0; NLIN];
    row[..NVAR].copy_from_slice(var);
    row[NVAR..].copy_from_slice(fixed);
    row
}

#[inline]
fn unit(a: f64) -> (f64, f64) {
    (a.cos(), a.sin())
}

/// A straight piece prepared for many pixels: start, unit direction, length, dwell density.
/// Its length and direction are computed once per piece instead of once per pixel (the arc's
/// 16 pieces are visited by every pixel near it).
#[derive(Debug, Clone, Copy)]
struct Prepared {
    a: (f64, f64),
    d: (f64, f64),
    len: f64,
    dens: f64,
}

impl Prepared {
    fn new(a: (f64, f64), b: (f64, f64), dens: f64) -> Prepared {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = dx.hypot(dy);
        let d = if len > 0.0 {
            (dx / len, dy / len)
        } else {
            (0.0, 0.0)
        };
        Prepared { a, d, len, dens }
    }

    /// Flat, `d²/R²`-weighted and ramp dwell of pixel `q` for a disc moving along the piece,
    /// under the kernel's soft edge. The ramp weights the flat dwell by the distance from `a`
    /// (in `R`): a ball that decelerates along a straight piece (rolling resistance, some 4 % of
    /// the speed per `R` for a slow billiard ball) brightens linearly along it,
    /// `1/v(s) ≈ (1 + k s)/v(0)`.
    ///
    /// With `t` the position along the piece relative to the foot of the perpendicular from `q`
    /// and `d = √(t² + y²)`, the three are `∫ K(d) (1, d²/R², s/R) dt` over the piece, integrated
    /// in closed form on the inner part (`K = 1`) and the ramp (`K = (R + w/2 - d)/w`), whose
    /// ends are where `d` crosses the two radii. So the dwell is smooth in the path's position:
    /// until session 18 the ramp was a midpoint rule over 8 hard radii, whose kinks every half
    /// pixel made the arc's cost rugged (two optimisers from one start ended in minima up to
    /// 1.4° of `δ` apart, Δχ² up to 14, on 14 of 79 readings). A piece that the inner radius
    /// covers whole (most pixel–piece pairs near the arc) is one product.
    #[inline]
    fn dwell(&self, q: (f64, f64), k: &Kernel) -> Dwell {
        self.dwell_impl::<false>(q, k).0
    }

    /// [`Prepared::dwell`], how the kernel covers the piece, and with `G` the [`Moments`] of
    /// the parts it integrates (none for [`Cover::Inner`]), from the same roots and logarithms.
    /// The dwell is the same to the bit either way: the moments only read what it computes.
    #[inline(always)]
    fn dwell_impl<const G: bool>(&self, q: (f64, f64), k: &Kernel) -> (Dwell, Cover, Moments) {
        let len = self.len;
        let none = Moments::default();
        if len <= 0.0 {
            return (Dwell::default(), Cover::Out, none);
        }
        let d = self.d;
        let (wx, wy) = (q.0 - self.a.0, q.1 - self.a.1);
        let x = wx * d.0 + wy * d.1;
        let y = d.0 * wy - d.1 * wx;
        let rmax = k.rmax;
        if y.abs() >= rmax || x < -rmax || x > len + rmax {
            return (Dwell::default(), Cover::Out, none);
        }
        let y2 = y * y;
        // The piece in `t = s - x`.
        let (t0, t1) = (-x, len - x);
        let far = t0.abs().max(t1.abs());
        if far * far + y2 <= k.rmin2 {
            let full2 = y2 * len + (t1.powi(3) - t0.powi(3)) / 3.0;
            return (
                Dwell {
                    d0: self.dens * len,
                    d2: self.dens * full2 * k.inv_r2,
                    ramp: self.dens * 0.5 * (len * len) * k.inv_r,
                },
                Cover::Inner,
                none,
            );
        }
        let mut acc = Integrals::default();
        let ha = (k.rmax2 - y2).sqrt();
        // Where the piece spans the whole chord (the rolling line, beyond its start), the two
        // ramps are mirror images: the same `∫ K`, `∫ K d²` and opposite `∫ K t`, to the last
        // bit (every term of [`Integrals::ramp`] is even or odd in `t` operation by operation),
        // so one is computed and added twice, in the order of two calls.
        let whole = t0 <= -ha && t1 >= ha;
        if y2 < k.rmin2 {
            let hb = (k.rmin2 - y2).sqrt();
            acc.inner::<G>(t0.max(-hb), t1.min(hb), y);
            if whole {
                acc.mirrored_ramps::<G>(hb, ha, y, k);
            } else {
                acc.ramp::<G>(t0.max(-ha), t1.min(-hb), y, k);
                acc.ramp::<G>(t0.max(hb), t1.min(ha), y, k);
            }
        } else if whole {
            acc.mirrored_ramps::<G>(0.0, ha, y, k);
        } else {
            // Beyond the inner radius the whole chord is ramp: split at the foot (one sign each).
            acc.ramp::<G>(t0.max(-ha), t1.min(0.0), y, k);
            acc.ramp::<G>(t0.max(0.0), t1.min(ha), y, k);
        }
        // `∫ K s dt = ∫ K t dt + x ∫ K dt`.
        (
            Dwell {
                d0: self.dens * acc.k0,
                d2: self.dens * acc.k2 * k.inv_r2,
                ramp: self.dens * (acc.kt + x * acc.k0) * k.inv_r,
            },
            Cover::Part,
            acc.m,
        )
    }
}

/// How a pixel's kernel covers a piece: not at all, the whole piece within the inner radius
/// (`K = 1` throughout), or partly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cover {
    Out,
    Inner,
    Part,
}

/// Gradients of one piece's dwell (see [`Prepared::gradients_of`]), image `(x, y)` components.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
struct PieceGrad {
    /// `∂D₀/∂a`, `∂D₀/∂b`, `∂D₂/∂a`, `∂D₂/∂b` with the piece's time `dens · len` held (an arc
    /// piece: its time is set by `L₁`, not by its length).
    d0a: [f64; 2],
    d0b: [f64; 2],
    d2a: [f64; 2],
    d2b: [f64; 2],
    /// `∂D₀`, `∂D₂`, `∂D₁` (the ramp) for the whole piece moved, `dens` and `len` held (the
    /// rolling line, which moves with `P₁`).
    d0m: [f64; 2],
    d2m: [f64; 2],
    rampm: [f64; 2],
}

/// `∫ (G'(d)/d) (t, -y) dt` (`m0`) and `∫ t (G'(d)/d) (t, -y) dt` (`m1`) over the parts of a
/// piece, along and across it, for `G = K` (`[0]`) and `G = K d²` (`[1]`): the pieces of the
/// gradient `∇ₚG = G'(d) (p - q)/d`, `p - q = t d̂ - y n̂`. `K' = -1/w` on the ramp and 0
/// elsewhere; `(K d²)'/d = 2K + K' d`, which is 2 inside and `(2 R₊ - 3d)/w` on the ramp.
#[derive(Debug, Default, Clone, Copy)]
struct Moments {
    m0: [[f64; 2]; 2],
    m1: [[f64; 2]; 2],
}

impl Moments {
    /// `K = 1` on `[u, v]`: only `G = K d²` changes there.
    #[inline]
    fn inner(&mut self, u: f64, v: f64, y: f64) {
        let (s1, s2, s3) = (v - u, v * v - u * u, v.powi(3) - u.powi(3));
        self.m0[1][0] += s2;
        self.m0[1][1] -= 2.0 * y * s1;
        self.m1[1][0] += 2.0 * s3 / 3.0;
        self.m1[1][1] -= y * s2;
    }

    /// The ramp's part on `[u, v]` (`u < v` of one sign), from the roots `du, dv` and the
    /// logarithm `l = asinh(v/|y|) - asinh(u/|y|)` (0 when `y = 0`, where it is only ever
    /// multiplied by `y`) that [`Integrals::ramp_parts`] computed.
    #[inline]
    fn ramp(u: f64, v: f64, y: f64, (du, dv, l): (f64, f64, f64), k: &Kernel) -> Moments {
        let y2 = y * y;
        let (ya, y2a) = (y * l, y2 * l);
        // ∫ t/d = d, ∫ 1/d = asinh(t/|y|), ∫ t²/d = (t d - y² asinh)/2,
        // ∫ d = (t d + y² asinh)/2, ∫ t d = d³/3, ∫ t² d = t (2t² + y²) d/8 - y⁴ asinh/8.
        let i_t_d = dv - du;
        let i_tt_d = 0.5 * (v * dv - u * du - y2a);
        let i_d = 0.5 * (v * dv - u * du + y2a);
        let i_td = (dv.powi(3) - du.powi(3)) / 3.0;
        let i_ttd =
            (v * (2.0 * v * v + y2) * dv - u * (2.0 * u * u + y2) * du) / 8.0 - y2 * y2a / 8.0;
        let (s1, s2, s3) = (v - u, v * v - u * u, v.powi(3) - u.powi(3));
        let (w, a) = (k.inv_w, k.rmax);
        Moments {
            // G = K: G'/d = -1/(w d).
            // G = K d²: (2 R₊ - 3d)/w.
            m0: [
                [-w * i_t_d, w * ya],
                [
                    w * (a * s2 - 3.0 * i_td),
                    -w * y * (2.0 * a * s1 - 3.0 * i_d),
                ],
            ],
            m1: [
                [-w * i_tt_d, w * y * i_t_d],
                [
                    w * (2.0 * a * s3 / 3.0 - 3.0 * i_ttd),
                    -w * y * (a * s2 - 3.0 * i_td),
                ],
            ],
        }
    }

    /// Adds a part, and with `mirror` also its image `t → -t` (the along components of `m0`
    /// and the across ones of `m1` change sign).
    #[inline]
    fn add(&mut self, p: &Moments, mirror: bool) {
        for g in 0..2 {
            if mirror {
                self.m0[g][1] += 2.0 * p.m0[g][1];
                self.m1[g][0] += 2.0 * p.m1[g][0];
            } else {
                for c in 0..2 {
                    self.m0[g][c] += p.m0[g][c];
                    self.m1[g][c] += p.m1[g][c];
                }
            }
        }
    }

    /// The [`PieceGrad`] of piece `p` at a pixel `(x, y)` from its foot, `t₀ = -x`: with `σ =
    /// (t - t₀)/len` along the piece and its time held, `∂I/∂b = dens ∫ σ ∇ₚG dt` and `∂I/∂a
    /// = dens ∫ (1 - σ) ∇ₚG dt`; moved whole, `dens ∫ ∇ₚG dt`, and for the ramp `D₁ = dens ∫
    /// K (t + x)/R dt` the same with the weight `(t + x)/R`.
    fn gradients(&self, p: &Prepared, x: f64, k: &Kernel) -> PieceGrad {
        let (d, len, t0) = (p.d, p.len, -x);
        let image = |v: [f64; 2]| [v[0] * d.0 - v[1] * d.1, v[0] * d.1 + v[1] * d.0];
        let scale = [p.dens, p.dens * k.inv_r2];
        let ends = |g: usize| {
            let s = scale[g];
            let b = [
                s * (self.m1[g][0] - t0 * self.m0[g][0]) / len,
                s * (self.m1[g][1] - t0 * self.m0[g][1]) / len,
            ];
            let a = [s * self.m0[g][0] - b[0], s * self.m0[g][1] - b[1]];
            (image(a), image(b))
        };
        let ((d0a, d0b), (d2a, d2b)) = (ends(0), ends(1));
        let moved = |g: usize| image([scale[g] * self.m0[g][0], scale[g] * self.m0[g][1]]);
        let sr = p.dens * k.inv_r;
        PieceGrad {
            d0a,
            d0b,
            d2a,
            d2b,
            d0m: moved(0),
            d2m: moved(1),
            rampm: image([
                sr * (self.m1[0][0] + x * self.m0[0][0]),
                sr * (self.m1[0][1] + x * self.m0[0][1]),
            ]),
        }
    }
}

impl Prepared {
    /// The pixel `q`'s position `x` along the piece from its start.
    #[inline]
    fn along(&self, q: (f64, f64)) -> f64 {
        (q.0 - self.a.0) * self.d.0 + (q.1 - self.a.1) * self.d.1
    }

    /// The gradients of the dwell of pixel `q` ([`PieceGrad`]; [`Moments::gradients`]), on
    /// their own: what the tests compare with differences of the dwell.
    #[cfg(test)]
    fn gradients(&self, q: (f64, f64), k: &Kernel) -> PieceGrad {
        let (_, cover, m) = self.dwell_impl::<true>(q, k);
        self.gradients_of(q, cover, &m, k)
    }

    /// The gradients of the dwell of pixel `q` ([`PieceGrad`]) from what
    /// [`Prepared::dwell_impl`] returned for it: [`Moments::gradients`] where the kernel
    /// covers the piece partly. Where the inner radius holds it whole, `D₀ = T` (its time)
    /// does not move and `D₂ = T/R² (|m - q|² + len²/12)` (`m` its middle);
    /// [`Pixels::outgoing_with`] folds the same formula into each arc piece's end derivatives
    /// once, outside its loop over the pixels.
    fn gradients_of(&self, q: (f64, f64), cover: Cover, m: &Moments, k: &Kernel) -> PieceGrad {
        match cover {
            Cover::Out => PieceGrad::default(),
            Cover::Part => m.gradients(self, self.along(q), k),
            Cover::Inner => {
                let b = (
                    self.a.0 + self.len * self.d.0,
                    self.a.1 + self.len * self.d.1,
                );
                let mq = [0.5 * (self.a.0 + b.0) - q.0, 0.5 * (self.a.1 + b.1) - q.1];
                let t = self.dens * self.len * k.inv_r2;
                let sixth = [(b.0 - self.a.0) / 6.0, (b.1 - self.a.1) / 6.0];
                let all = self.dens * self.len * 2.0 * k.inv_r2;
                PieceGrad {
                    d2a: [t * (mq[0] - sixth[0]), t * (mq[1] - sixth[1])],
                    d2b: [t * (mq[0] + sixth[0]), t * (mq[1] + sixth[1])],
                    d2m: [all * mq[0], all * mq[1]],
                    ..PieceGrad::default()
                }
            }
        }
    }
}

/// `∫ K dt`, `∫ K d² dt` and `∫ K t dt` over the parts of a piece, `d = √(t² + y²)`.
#[derive(Debug, Default, Clone, Copy)]
struct Integrals {
    k0: f64,
    k2: f64,
    kt: f64,
    /// The gradient's moments, when asked for ([`Prepared::dwell_impl`]).
    m: Moments,
}

/// `asinh(v/|y|) - asinh(u/|y|)` for `u ≤ v` of one sign, as one logarithm: `asinh(t/|y|) =
/// ln((t + d)/|y|)` for `t ≥ 0`, odd in `t` (so for `u ≤ v ≤ 0` the difference is `ln((|u| +
/// d_u)/(|v| + d_v))`). 0 when `y = 0`: it enters the primitives only times `y` or `y²`.
#[inline]
fn asinh_diff(u: f64, v: f64, du: f64, dv: f64, y2: f64) -> f64 {
    if y2 <= 0.0 {
        0.0
    } else if u >= 0.0 {
        ((v + dv) / (u + du)).ln()
    } else {
        ((-u + du) / (-v + dv)).ln()
    }
}

/// `∫ d² dt` and `∫ t dt` over `[u, v]`, `d² = t² + y²`: the parts of both integrands that are
/// polynomials in `t`.
#[inline]
fn polynomial_parts(u: f64, v: f64, y2: f64) -> (f64, f64) {
    (
        (v.powi(3) - u.powi(3)) / 3.0 + y2 * (v - u),
        0.5 * (v * v - u * u),
    )
}

impl Integrals {
    /// `K = 1` on `[u, v]`.
    #[inline]
    fn inner<const G: bool>(&mut self, u: f64, v: f64, y: f64) {
        if v <= u {
            return;
        }
        let (i2, it) = polynomial_parts(u, v, y * y);
        self.add((v - u, i2, it));
        if G {
            self.m.inner(u, v, y);
        }
    }

    /// Adds one part's `(∫ K, ∫ K d², ∫ K t)`.
    #[inline]
    fn add(&mut self, (k0, k2, kt): (f64, f64, f64)) {
        self.k0 += k0;
        self.k2 += k2;
        self.kt += kt;
    }

    /// `K = (R + w/2 - d)/w` on `[u, v]` (a part where `d` lies between the two radii, so
    /// `u, v` have one sign).
    #[inline]
    fn ramp<const G: bool>(&mut self, u: f64, v: f64, y: f64, k: &Kernel) {
        if v <= u {
            return;
        }
        let (parts, roots) = Integrals::ramp_parts(u, v, y * y, k);
        self.add(parts);
        if G {
            self.m.add(&Moments::ramp(u, v, y, roots, k), false);
        }
    }

    /// `ramp(-b, -a)` then `ramp(a, b)` (`0 ≤ a < b`), with the second computed from the first.
    #[inline]
    fn mirrored_ramps<const G: bool>(&mut self, a: f64, b: f64, y: f64, k: &Kernel) {
        if b <= a {
            return;
        }
        let ((k0, k2, kt), roots) = Integrals::ramp_parts(-b, -a, y * y, k);
        self.add((k0, k2, kt));
        self.add((k0, k2, -kt));
        if G {
            self.m.add(&Moments::ramp(-b, -a, y, roots, k), true);
        }
    }

    /// The three integrals of the ramp on `[u, v]`, `u < v` of one sign, and the roots `d_u,
    /// d_v` and logarithm `asinh(v/|y|) - asinh(u/|y|)` they use (the log 0 when `y = 0`).
    #[inline]
    fn ramp_parts(u: f64, v: f64, y2: f64, k: &Kernel) -> ((f64, f64, f64), (f64, f64, f64)) {
        let (du, dv) = ((u * u + y2).sqrt(), (v * v + y2).sqrt());
        let l = asinh_diff(u, v, du, dv, y2);
        let log = y2 * l;
        // ∫ d = (t d + y² asinh(t/|y|))/2; ∫ d² = t³/3 + y² t;
        // ∫ d³ = t (2t² + 5y²) d / 8 + 3 y² · y² asinh(t/|y|) / 8; ∫ t d = d³/3.
        let i1 = 0.5 * (v * dv - u * du + log);
        let (i2, it) = polynomial_parts(u, v, y2);
        let i3 = (v * (2.0 * v * v + 5.0 * y2) * dv - u * (2.0 * u * u + 5.0 * y2) * du) / 8.0
            + 0.375 * y2 * log;
        let itd = (dv.powi(3) - du.powi(3)) / 3.0;
        let a = k.rmax;
        (
            (
                (a * (v - u) - i1) * k.inv_w,
                (a * i2 - i3) * k.inv_w,
                (a * it - itd) * k.inv_w,
            ),
            (du, dv, l),
        )
    }
}

/// A straight piece of a path: start, end, dwell density (time per unit length).
type Piece = ((f64, f64), (f64, f64), f64);

/// The Bézier legs `(L₀, L₁)` of the parameters: kept positive and at least half a pixel, so
/// the optimiser may cross zero without a degenerate arc.
fn legs(x: &[f64; 3]) -> (f64, f64) {
    (x[1].abs() + 0.5, x[2].abs() + 0.5)
}

/// The outgoing path's pieces `(a, b, density)` for `(δ, L₀, L₁)`, rolling speed 1.
fn outgoing_pieces(g: &ArcGeometry, x: &[f64; 3]) -> Vec<Piece> {
    outgoing_pieces_at(g, x).0
}

/// [`outgoing_pieces`], with the Bézier parameters `(τ_a, τ_b)` of each arc piece's ends.
fn outgoing_pieces_at(g: &ArcGeometry, x: &[f64; 3]) -> (Vec<Piece>, Vec<(f64, f64)>) {
    let (delta, (l0, l1)) = (x[0], legs(x));
    let (u0, u1) = (unit(delta), unit(g.theta));
    let s = g.p;
    let c = (s.0 + l0 * u0.0, s.1 + l0 * u0.1);
    let e = (c.0 + l1 * u1.0, c.1 + l1 * u1.1);
    let bez = |t: f64| {
        let (a, b, cc) = ((1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t);
        (a * s.0 + b * c.0 + cc * e.0, a * s.1 + b * c.1 + cc * e.1)
    };
    // Time per unit τ is 2 L₁ (end speed 2L₁/T = 1).
    let dt = 2.0 * l1 / N_ARC as f64;
    let mut out = Vec::with_capacity(N_ARC + 1);
    let mut taus = Vec::with_capacity(N_ARC);
    let mut prev = s;
    for i in 1..=N_ARC {
        let q = bez(i as f64 / N_ARC as f64);
        let len = (q.0 - prev.0).hypot(q.1 - prev.1);
        if len > 1e-9 {
            out.push((prev, q, dt / len));
            taus.push(((i - 1) as f64 / N_ARC as f64, i as f64 / N_ARC as f64));
        }
        prev = q;
    }
    let end = (
        e.0 + LINE_EXTRA_R * g.r * u1.0,
        e.1 + LINE_EXTRA_R * g.r * u1.1,
    );
    out.push((e, end, 1.0));
    (out, taus)
}

/// `∂B(τ)/∂x` of the arc's point at `τ` for the parameters `x = (δ, L₀, L₁)` (legs `|x| + ½`,
/// [`legs`]): `B = (1-τ)² P + 2τ(1-τ) C + τ² P₁`, `C = P + L₀ u(δ)`, `P₁ = C + L₁ u(θ)`.
fn bezier_derivatives(g: &ArcGeometry, x: &[f64; 3], tau: f64) -> [[f64; 2]; 3] {
    let (l0, _) = legs(x);
    let (c, s) = (x[0].cos(), x[0].sin());
    let (ct, st) = (g.theta.cos(), g.theta.sin());
    let wc = tau * (2.0 - tau);
    let w1 = tau * tau;
    let (s1, s2) = (sign(x[1]), sign(x[2]));
    [
        [-wc * l0 * s, wc * l0 * c],
        [wc * c * s1, wc * s * s1],
        [w1 * ct * s2, w1 * st * s2],
    ]
}

/// The derivative of `|v|` on the side a step up from 0 sees (it lengthens the leg).
#[inline]
fn sign(v: f64) -> f64 {
    if v < 0.0 { -1.0 } else { 1.0 }
}

/// Grid positions `k < n` (at `o + k st`) within `[v0, v1]`: `ceil((v0 - o)/st) ..=
/// floor((v1 - o)/st)`, clamped to the grid (the float-to-usize casts saturate negative values
/// and NaN at 0), empty when the interval misses it.
fn grid_range(v0: f64, v1: f64, o: f64, st: f64, n: usize) -> std::ops::Range<usize> {
    let lo = ((v0 - o) / st).ceil() as usize;
    let hi = ((((v1 - o) / st).floor() + 1.0) as usize).min(n);
    lo..hi.max(lo)
}

/// The window's pixels with their fixed columns.
struct Pixels {
    /// The kernel that models a cell mean at this sampling.
    kernel: Kernel,
    q: Vec<(f64, f64)>,
    v: Vec<f64>,
    /// Incoming (3) and baseline (6) columns, row-major per pixel.
    fixed: Vec<[f64; NFIX]>,
    /// Cell position on the sampling grid (column, row), the grid's size, its first cell (px)
    /// and spacing, and each grid position's cell (`u32::MAX` where none).
    cell: Vec<(usize, usize)>,
    grid: (usize, usize),
    origin: (usize, usize),
    stride: usize,
    index: Vec<u32>,
    /// Half-width (cells) of the high-pass box (see [`HIGHPASS_R`]).
    highpass: usize,
    /// Evaluations of the outgoing path's dwell so far (each one pass over the cells), for the
    /// debug log of the stages' costs ([`Laps`]).
    evals: std::cell::Cell<usize>,
}

/// Start `(δ, L₀, L₁)` candidates: arcs from `P` onto the measured rolling line (offset `h`),
/// of several lengths, plus the centre-line fit's own start tangent.
fn starts(g: &ArcGeometry) -> Vec<[f64; 3]> {
    let u1 = unit(g.theta);
    let w = (g.line_point.0 - g.p.0, g.line_point.1 - g.p.1);
    // Signed offset of the rolling line from P (left of the rolling direction positive).
    let h = u1.0 * w.1 - u1.1 * w.0;
    let mut v = Vec::new();
    for k in [0.25, 0.5, 0.8, 1.2, 1.8, 2.6] {
        let l0 = k * g.r;
        let sn = (-h / l0).clamp(-0.99, 0.99);
        // Turn from δ to θ; δ = θ + turn with sin(turn) L₀ = -h.
        let turn = sn.asin();
        v.push([g.theta - turn, l0, l0]);
        // Turns beyond 90° (a drawn ball coming back).
        if sn.abs() > 0.5 {
            v.push([g.theta - (std::f64::consts::PI - turn), l0, l0]);
        }
    }
    if let Some(d) = g.delta_guess {
        let turn = d - g.theta;
        if turn.sin().abs() > 1e-3 {
            let l0 = (-h / turn.sin()).abs().clamp(0.1 * g.r, 4.0 * g.r);
            v.push([d, l0, l0]);
        }
    }
    v
}

impl Pixels {
    fn gather(
        sig: &Signal,
        u: [f32; 3],
        g: &ArcGeometry,
        cands: &[[f64; 3]],
        stride: usize,
    ) -> Pixels {
        let r = g.r;
        let margin = r * (1.0 + WINDOW_CLOTH_R);
        // Polylines that bound the window: every start's outgoing path and the incoming piece.
        let inc_a = (
            g.p.0 - INCOMING_R * r * g.incoming.0,
            g.p.1 - INCOMING_R * r * g.incoming.1,
        );
        let win_a = (
            g.p.0 - WINDOW_INCOMING_R * r * g.incoming.0,
            g.p.1 - WINDOW_INCOMING_R * r * g.incoming.1,
        );
        let mut polys: Vec<((f64, f64), (f64, f64))> = vec![(win_a, g.p)];
        for c in cands {
            let pieces = outgoing_pieces(g, c);
            for (k, (a, b, _)) in pieces.iter().enumerate() {
                if k + 1 == pieces.len() {
                    let d = (b.0 - a.0, b.1 - a.1);
                    let l = d.0.hypot(d.1).max(1e-9);
                    let f = (WINDOW_LINE_R * r / l).min(1.0);
                    polys.push((*a, (a.0 + f * d.0, a.1 + f * d.1)));
                } else {
                    polys.push((*a, *b));
                }
            }
        }
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for (a, b) in &polys {
            x0 = x0.min(a.0.min(b.0));
            y0 = y0.min(a.1.min(b.1));
            x1 = x1.max(a.0.max(b.0));
            y1 = y1.max(a.1.max(b.1));
        }
        let xa = (x0 - margin).floor().max(1.0) as usize;
        let ya = (y0 - margin).floor().max(1.0) as usize;
        let xb = ((x1 + margin).ceil() as usize).min(sig.w.saturating_sub(2));
        let yb = ((y1 + margin).ceil() as usize).min(sig.h.saturating_sub(2));
        let obj_end = (
            g.o.0 + 8.0 * r * g.object_dir.0,
            g.o.1 + 8.0 * r * g.object_dir.1,
        );
        let inc_piece = Prepared::new(inc_a, g.p, 1.0);
        let kernel = Kernel::for_cells(r, stride);
        let plane = sig.projected(sig.projector(u));
        // Offsets of the cell's pixels around its centre (half-pixel ones are bilinear).
        let half = (stride as f64 - 1.0) / 2.0;
        let cell = |q: (f64, f64)| -> Option<f64> {
            let mut acc = 0.0f64;
            for jy in 0..stride {
                for jx in 0..stride {
                    acc += plane.sample(q.0 - half + jx as f64, q.1 - half + jy as f64)? as f64;
                }
            }
            Some(acc / (stride * stride) as f64)
        };
        let highpass = ((HIGHPASS_R * r / stride as f64).round() as usize).max(1);
        let mut px = Pixels {
            kernel,
            q: Vec::new(),
            v: Vec::new(),
            fixed: Vec::new(),
            cell: Vec::new(),
            grid: ((xb - xa) / stride + 1, (yb - ya) / stride + 1),
            origin: (xa, ya),
            stride,
            index: Vec::new(),
            highpass,
            evals: std::cell::Cell::new(0),
        };
        // The window: grid positions within `margin` of a bounding polyline, each piece tested
        // only on the positions of its own box (the same test, so the same cells in the same
        // order, without testing every position against some hundred pieces).
        let (gw, gh) = px.grid;
        let mut near = vec![false; gw * gh];
        let cols =
            |v0: f64, v1: f64, o: usize, n: usize| grid_range(v0, v1, o as f64, stride as f64, n);
        for (a, b) in &polys {
            let xs = cols(a.0.min(b.0) - margin, a.0.max(b.0) + margin, xa, gw);
            for cy in cols(a.1.min(b.1) - margin, a.1.max(b.1) + margin, ya, gh) {
                let yy = (ya + cy * stride) as f64;
                for cx in xs.clone() {
                    let k = cy * gw + cx;
                    if !near[k]
                        && seg_dist2(((xa + cx * stride) as f64, yy), *a, *b) < margin * margin
                    {
                        near[k] = true;
                    }
                }
            }
        }
        for yy in (ya..=yb).step_by(stride) {
            for xx in (xa..=xb).step_by(stride) {
                let q = (xx as f64, yy as f64);
                if !near[(yy - ya) / stride * gw + (xx - xa) / stride] {
                    continue;
                }
                // The object ball: its waiting disc (bright, shaded, with a highlight) and
                // its streak are not modelled.
                if seg_dist2(q, g.o, obj_end) < (r + 3.0 + half).powi(2) {
                    continue;
                }
                let Some(val) = cell(q) else {
                    continue;
                };
                let e = inc_piece.dwell(q, &kernel);
                let (sx, sy) = ((q.0 - g.p.0) / (3.0 * r), (q.1 - g.p.1) / (3.0 * r));
                px.q.push(q);
                px.v.push(val);
                px.cell.push(((xx - xa) / stride, (yy - ya) / stride));
                px.fixed
                    .push([e.d0, e.d2, e.ramp, 1.0, sx, sy, sx * sx, sx * sy, sy * sy]);
            }
        }
        px.index = vec![u32::MAX; px.grid.0 * px.grid.1];
        for (i, &(cx, cy)) in px.cell.iter().enumerate() {
            px.index[cy * px.grid.0 + cx] = i as u32;
        }
        px
    }

    /// Calls `f` on the cells whose centres lie in the box `[x0, x1] × [y0, y1]` (px), row by
    /// row.
    #[inline]
    fn each_cell_in(&self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), mut f: impl FnMut(usize)) {
        let (gw, gh) = self.grid;
        let (ox, oy, st) = (
            self.origin.0 as f64,
            self.origin.1 as f64,
            self.stride as f64,
        );
        let (xs, ys) = (
            grid_range(x0, x1, ox, st, gw),
            grid_range(y0, y1, oy, st, gh),
        );
        if xs.is_empty() {
            return;
        }
        for cy in ys {
            let row = &self.index[cy * gw..(cy + 1) * gw];
            for &i in &row[xs.clone()] {
                if i != u32::MAX {
                    f(i as usize);
                }
            }
        }
    }

    /// Outgoing columns for the nonlinear parameters `x`.
    fn outgoing(&self, g: &ArcGeometry, x: &[f64; 3]) -> Vec<Dwell> {
        self.outgoing_with::<false>(g, x).0
    }

    /// [`Pixels::outgoing`] (the same values to the bit) and each cell's derivatives of its
    /// outgoing dwell with respect to `x = (δ, L₀, L₁)`: every piece's end gradients
    /// ([`Prepared::gradients_of`]) through the Bézier's ([`bezier_derivatives`]); an arc piece's
    /// time `2L₁/N` adds `D/L₁` to `∂/∂L₁`; the rolling line moves with `P₁ = B(1)`.
    fn outgoing_grad(&self, g: &ArcGeometry, x: &[f64; 3]) -> (Vec<Dwell>, Vec<[Dwell; 3]>) {
        self.outgoing_with::<true>(g, x)
    }

    /// The outgoing dwell of every cell, and with `G` its derivatives (else an empty list).
    fn outgoing_with<const G: bool>(
        &self,
        g: &ArcGeometry,
        x: &[f64; 3],
    ) -> (Vec<Dwell>, Vec<[Dwell; 3]>) {
        self.evals.set(self.evals.get() + 1);
        let (pieces, taus) = outgoing_pieces_at(g, x);
        let prepared: Vec<Prepared> = pieces
            .iter()
            .map(|&(a, b, d)| Prepared::new(a, b, d))
            .collect();
        // Each piece of the arc is visited only by the cells within reach of it (its box): a
        // piece of a few px covers a fifth of the window. A cell beyond a piece's reach gets
        // exactly 0 from it, and the sums run over the pieces in the same order, so this is the
        // same to the last bit as visiting every piece from every cell.
        let (arc, line) = prepared.split_at(prepared.len() - 1);
        let reach = self.kernel.rmax + 1.0;
        let l1 = legs(x).1;
        let s2 = sign(x[2]);
        let mut out = vec![Dwell::default(); self.q.len()];
        let mut dout = vec![[Dwell::default(); 3]; if G { self.q.len() } else { 0 }];
        let dot = |v: [f64; 2], w: [f64; 2]| v[0] * w[0] + v[1] * w[1];
        for ((piece, &(a, b, _)), &(ta, tb)) in arc.iter().zip(&pieces).zip(&taus) {
            let lo = (a.0.min(b.0) - reach, a.1.min(b.1) - reach);
            let hi = (a.0.max(b.0) + reach, a.1.max(b.1) + reach);
            if !G {
                self.each_cell_in(lo, hi, |i| {
                    let f = piece.dwell(self.q[i], &self.kernel);
                    out[i].d0 += f.d0;
                    out[i].d2 += f.d2;
                });
                continue;
            }
            let (da, db) = (bezier_derivatives(g, x, ta), bezier_derivatives(g, x, tb));
            // A pixel whose inner radius holds the whole piece sees `D₂ = T/R² (|m - q|² +
            // len²/12)` (`T` the piece's time, `m` its middle), so `∂D₂/∂a = T/R² ((m - q) +
            // (a - b)/6)`, `∂D₂/∂b = T/R² ((m - q) + (b - a)/6)`, and `D₀ = T` does not move.
            let mid = (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1));
            let both: [[f64; 2]; 3] =
                std::array::from_fn(|j| [da[j][0] + db[j][0], da[j][1] + db[j][1]]);
            let split: [f64; 3] = std::array::from_fn(|j| {
                ((a.0 - b.0) * (da[j][0] - db[j][0]) + (a.1 - b.1) * (da[j][1] - db[j][1])) / 6.0
            });
            let tw = piece.dens * piece.len * self.kernel.inv_r2;
            self.each_cell_in(lo, hi, |i| {
                let q = self.q[i];
                let (f, cover, m) = piece.dwell_impl::<true>(q, &self.kernel);
                out[i].d0 += f.d0;
                out[i].d2 += f.d2;
                let o = &mut dout[i];
                match cover {
                    Cover::Out => return,
                    Cover::Inner => {
                        let mq = [mid.0 - q.0, mid.1 - q.1];
                        for j in 0..3 {
                            o[j].d2 += tw * (dot(mq, both[j]) + split[j]);
                        }
                    }
                    Cover::Part => {
                        let gr = m.gradients(piece, piece.along(q), &self.kernel);
                        for j in 0..3 {
                            o[j].d0 += dot(gr.d0a, da[j]) + dot(gr.d0b, db[j]);
                            o[j].d2 += dot(gr.d2a, da[j]) + dot(gr.d2b, db[j]);
                        }
                    }
                }
                o[2].d0 += f.d0 * s2 / l1;
                o[2].d2 += f.d2 * s2 / l1;
            });
        }
        // Only the rolling line decelerates at a constant rate (the arc's own speed change is in
        // its shape): its ramp is the only one.
        let de = if G {
            bezier_derivatives(g, x, 1.0)
        } else {
            [[0.0; 2]; 3]
        };
        for (i, (o, &q)) in out.iter_mut().zip(&self.q).enumerate() {
            let (f, cover, m) = line[0].dwell_impl::<G>(q, &self.kernel);
            o.d0 += f.d0;
            o.d2 += f.d2;
            o.ramp = f.ramp;
            if !G {
                continue;
            }
            if cover == Cover::Out {
                continue;
            }
            // From the dwell just computed, not a second pass over the piece.
            let gr = line[0].gradients_of(q, cover, &m, &self.kernel);
            for (d, e) in dout[i].iter_mut().zip(&de) {
                d.d0 += dot(gr.d0m, *e);
                d.d2 += dot(gr.d2m, *e);
                d.ramp = dot(gr.rampm, *e);
            }
        }
        (out, dout)
    }

    /// Projected cost and residuals at the nonlinear parameters `x` (amplitudes eliminated).
    fn evaluate(&self, g: &ArcGeometry, x: &[f64; 3], mask: &Mask) -> Option<(f64, Vec<f64>)> {
        let out = self.outgoing(g, x);
        let res = self.solve(&out, mask)?.res;
        Some((cost(&res, &mask.keep), res))
    }

    /// Linear least squares of the amplitudes given the outgoing columns: the amplitudes, the
    /// residuals (only over the mask's pixels) and what the Jacobian needs.
    fn solve(&self, out: &[Dwell], mask: &Mask) -> Option<Solved> {
        // Accumulated in fixed-size arrays (bounds known at compile time): this loop over every
        // pixel was a third of the analysis when it indexed a `DMatrix`. Only the rows of the
        // outgoing columns change with `x`; the fixed block comes from the mask. Same order of
        // addition as a full accumulation, so the same sums to the last bit.
        let mut acc = mask.ata;
        let mut atb = mask.atb;
        let var = mask.var_columns(self, out);
        let (fixed, v) = (&mask.fixed[..], &mask.v[..]);
        for (((vc, fixed), &v), &k) in var.iter().zip(fixed).zip(v).zip(&mask.keep) {
            // A cell out of the outgoing ball's reach adds exactly nothing to these rows (its
            // fixed block is already in the mask's sums).
            if !k || vc.iter().all(|c| *c == 0.0) {
                continue;
            }
            let row = row_of(vc, fixed);
            for a in 0..NVAR {
                atb[a] += row[a] * v;
                let ra = row[a];
                // The whole row, a loop of fixed length that vectorises: the entries left of
                // the diagonal are never read (the lower triangle is filled from the upper one
                // below), and each entry read gets the same products in the same order.
                for (acc_ab, rb) in acc[a].iter_mut().zip(&row) {
                    *acc_ab += ra * rb;
                }
            }
        }
        let mut ata = DMatrix::<f64>::from_fn(NLIN, NLIN, |a, b| acc[a][b]);
        // Column scaling keeps the dwell (≈ R) and baseline (≈ 1) columns comparable.
        let scale = symmetrise_and_scale(&mut ata);
        let mut m = ata;
        for a in 0..NLIN {
            m[(a, a)] += 1e-12;
        }
        let rhs = DVector::from_iterator(NLIN, (0..NLIN).map(|a| atb[a] / scale[a]));
        let chol = m.cholesky()?;
        let sol = chol.solve(&rhs);
        let c: [f64; NLIN] = std::array::from_fn(|a| sol[a] / scale[a]);
        let res = var
            .iter()
            .zip(&mask.fixed[..])
            .zip(&mask.v[..])
            .map(|((vc, fixed), v)| {
                let row = row_of(vc, fixed);
                // Summed in column order from -0.0, as `Iterator::sum` does.
                let mut s = -0.0;
                for (ca, ra) in c.iter().zip(&row) {
                    s += ca * ra;
                }
                v - s
            })
            .collect();
        Some(Solved {
            coef: c,
            res,
            var,
            chol,
            scale,
        })
    }

    /// `∂A_j c` for every pixel (the model's change with `x_j` at fixed amplitudes, 0 outside
    /// the mask) and `∂A_jᵀ r` over the mask's pixels (only the outgoing columns move).
    fn model_derivatives(
        &self,
        mask: &Mask,
        s: &Solved,
        dout: &[[Dwell; 3]],
    ) -> (Vec<[f64; 3]>, [[f64; NVAR]; 3]) {
        let c = &s.coef;
        let raw = |i: usize| dout[i].map(|d| var_columns(d, &self.fixed[i]));
        let dot = |dv: &[f64; NVAR]| (0..NVAR).map(|a| dv[a] * c[a]).sum::<f64>();
        let mut e = [[0.0f64; NVAR]; 3];
        let mut g = vec![[0.0f64; 3]; self.q.len()];
        // With the high-pass `H` (linear): `H(∂A_j) c = H(∂A_j c)`, and `(H ∂A_j)ᵀ r = ∂A_jᵀ
        // Hᵀ r`: three filtered values and one adjoint-filtered residual per pixel instead of
        // fifteen filtered columns.
        let r = match &mask.highpass {
            Some(hp) => {
                let filtered = hp.apply(&self.cell, &mask.keep, |i| raw(i).map(|dv| dot(&dv)));
                for (i, gi) in filtered.into_iter().enumerate() {
                    if mask.keep[i] {
                        g[i] = gi;
                    }
                }
                Cow::Owned(hp.adjoint(&self.cell, &mask.keep, &s.res))
            }
            None => Cow::Borrowed(&s.res[..]),
        };
        for i in 0..self.q.len() {
            if !mask.keep[i] {
                continue;
            }
            let dv = raw(i);
            for j in 0..3 {
                if mask.highpass.is_none() {
                    g[i][j] = dot(&dv[j]);
                }
                for a in 0..NVAR {
                    e[j][a] += dv[j][a] * r[i];
                }
            }
        }
        (g, e)
    }

    /// The Gauss–Newton normal equations `JᵀJ`, `Jᵀr` of the projected residuals, without `J`:
    /// with `g_j = ∂A_j c`, `h_j = Aᵀ g_j`, `e_j = ∂A_jᵀ r` and `u_j = (AᵀA)⁻¹ (h_j - e_j)`,
    /// `J_j = -g_j + A u_j` ([`Pixels::jacobian`]), so `J_jᵀ J_k = g_j·g_k - h_j·u_k - u_j·h_k
    /// + u_j·(h_k - e_k)` and `J_jᵀ r = -g_j·r` (`Aᵀ r = 0` at the amplitudes' solution). The
    /// column of `δ` is 0 when it is held.
    fn normal_equations(
        &self,
        mask: &Mask,
        s: &Solved,
        dout: &[[Dwell; 3]],
        pin_delta: bool,
    ) -> ([[f64; 3]; 3], [f64; 3]) {
        let (g, e) = self.model_derivatives(mask, s, dout);
        let mut h = [[0.0f64; NLIN]; 3];
        let mut gg = [[0.0f64; 3]; 3];
        let mut gr = [0.0f64; 3];
        for (i, gi) in g.iter().enumerate() {
            if !mask.keep[i] {
                continue;
            }
            let (var, fixed) = (&s.var[i], &mask.fixed[i]);
            for j in 0..3 {
                gr[j] += gi[j] * s.res[i];
                for k in 0..3 {
                    gg[j][k] += gi[j] * gi[k];
                }
                for a in 0..NVAR {
                    h[j][a] += var[a] * gi[j];
                }
                for a in 0..NFIX {
                    h[j][NVAR + a] += fixed[a] * gi[j];
                }
            }
        }
        let he: [[f64; NLIN]; 3] = std::array::from_fn(|j| {
            std::array::from_fn(|a| h[j][a] - if a < NVAR { e[j][a] } else { 0.0 })
        });
        let u: [[f64; NLIN]; 3] = std::array::from_fn(|j| s.normal_solve(&he[j]));
        let dot =
            |a: &[f64; NLIN], b: &[f64; NLIN]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let live = |j: usize| !(pin_delta && j == 0);
        let jtj = std::array::from_fn(|j| {
            std::array::from_fn(|k| {
                if live(j) && live(k) {
                    gg[j][k] - dot(&h[j], &u[k]) - dot(&u[j], &h[k]) + dot(&u[j], &he[k])
                } else {
                    0.0
                }
            })
        });
        let jtr = std::array::from_fn(|j| if live(j) { -gr[j] } else { 0.0 });
        (jtj, jtr)
    }

    /// The Jacobian `∂r/∂x` of the projected residuals (amplitudes re-solved, Golub–Pereyra):
    /// `J = -[(I - A A⁺) ∂A c + (A⁺)ᵀ ∂Aᵀ r]`, the derivative the finite differences of
    /// [`Pixels::evaluate`] approximate, from the outgoing dwell's derivatives `dout`
    /// ([`Pixels::outgoing_grad`]); rows of pixels outside the mask are 0, and so is the
    /// column of `δ` when it is held.
    #[cfg(test)]
    fn jacobian(
        &self,
        mask: &Mask,
        s: &Solved,
        dout: &[[Dwell; 3]],
        pin_delta: bool,
    ) -> Vec<[f64; 3]> {
        let dvar = mask.dvar_columns(self, dout);
        let c = &s.coef;
        // ∂A_j c per pixel; Aᵀ(∂A_j c) and ∂A_jᵀ r over the kept pixels.
        let mut h = [[0.0f64; NLIN]; 3];
        let mut e = [[0.0f64; NLIN]; 3];
        let mut g = vec![[0.0f64; 3]; self.q.len()];
        for i in 0..self.q.len() {
            if !mask.keep[i] {
                continue;
            }
            let row = row_of(&s.var[i], &mask.fixed[i]);
            for j in 0..3 {
                let dv = &dvar[i][j];
                let gij: f64 = (0..NVAR).map(|a| dv[a] * c[a]).sum();
                g[i][j] = gij;
                for (hb, rb) in h[j].iter_mut().zip(&row) {
                    *hb += rb * gij;
                }
                for a in 0..NVAR {
                    e[j][a] += dv[a] * s.res[i];
                }
            }
        }
        let wz: [[f64; NLIN]; 3] = std::array::from_fn(|j| {
            let (w, z) = (s.normal_solve(&h[j]), s.normal_solve(&e[j]));
            std::array::from_fn(|a| w[a] - z[a])
        });
        (0..self.q.len())
            .map(|i| {
                if !mask.keep[i] {
                    return [0.0; 3];
                }
                let row = row_of(&s.var[i], &mask.fixed[i]);
                std::array::from_fn(|j| {
                    if j == 0 && pin_delta {
                        return 0.0;
                    }
                    let aw: f64 = (0..NLIN).map(|a| row[a] * wz[j][a]).sum();
                    aw - g[i][j]
                })
            })
            .collect()
    }
}

/// The amplitudes' solve at one point: coefficients, residuals, the outgoing columns as fitted
/// and the scaled normal matrix's factor (with its column scale).
struct Solved {
    coef: [f64; NLIN],
    res: Vec<f64>,
    var: Vec<[f64; NVAR]>,
    chol: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    scale: Vec<f64>,
}

impl Solved {
    /// `(AᵀA)⁻¹ y` through the scaled factor: `S⁻¹ M⁻¹ S⁻¹ y`.
    fn normal_solve(&self, y: &[f64; NLIN]) -> [f64; NLIN] {
        let rhs = DVector::from_iterator(NLIN, (0..NLIN).map(|a| y[a] / self.scale[a]));
        let sol = self.chol.solve(&rhs);
        std::array::from_fn(|a| sol[a] / self.scale[a])
    }
}

/// The pixels a fit uses, with the parts of the normal equations that do not depend on the
/// nonlinear parameters (the fixed columns' block), accumulated once per mask instead of once
/// per evaluation (they were 40 % of the accumulation).
struct Mask<'a> {
    keep: Vec<bool>,
    ata: [[f64; NLIN]; NLIN],
    atb: [f64; NLIN],
    /// The data and the fixed columns as fitted: high-passed when [`Pixels::highpass`] is set,
    /// else the grid's own.
    v: Cow<'a, [f64]>,
    fixed: Cow<'a, [[f64; NFIX]]>,
    highpass: Option<HighPass>,
}

impl<'a> Mask<'a> {
    /// The mask `keep`, with the data and columns high-passed when asked.
    fn new(px: &'a Pixels, keep: Vec<bool>, highpass: bool) -> Mask<'a> {
        let highpass = highpass.then(|| HighPass::new(px, &keep));
        let (v, fixed) = match &highpass {
            Some(hp) => {
                let both = hp.apply(&px.cell, &keep, |i| {
                    let mut a = [0.0; NFIX + 1];
                    a[..NFIX].copy_from_slice(&px.fixed[i]);
                    a[NFIX] = px.v[i];
                    a
                });
                let v: Vec<f64> = both.iter().map(|a| a[NFIX]).collect();
                let fixed: Vec<[f64; NFIX]> =
                    both.iter().map(|a| std::array::from_fn(|j| a[j])).collect();
                (Cow::Owned(v), Cow::Owned(fixed))
            }
            None => (Cow::Borrowed(&px.v[..]), Cow::Borrowed(&px.fixed[..])),
        };
        let mut ata = [[0.0f64; NLIN]; NLIN];
        let mut atb = [0.0f64; NLIN];
        for ((fixed, &v), &k) in fixed.iter().zip(v.iter()).zip(&keep) {
            if !k {
                continue;
            }
            for a in NVAR..NLIN {
                let ra = fixed[a - NVAR];
                atb[a] += ra * v;
                for b in a..NLIN {
                    ata[a][b] += ra * fixed[b - NVAR];
                }
            }
        }
        Mask {
            keep,
            ata,
            atb,
            v,
            fixed,
            highpass,
        }
    }

    /// The derivatives of the outgoing columns as fitted with respect to `x` (the columns are
    /// linear in the dwell, and so is the high-pass).
    #[cfg(test)]
    fn dvar_columns(&self, px: &Pixels, dout: &[[Dwell; 3]]) -> Vec<[[f64; NVAR]; 3]> {
        let raw = |i: usize| -> [f64; 3 * NVAR] {
            let mut v = [0.0; 3 * NVAR];
            for (j, d) in dout[i].iter().enumerate() {
                v[j * NVAR..(j + 1) * NVAR].copy_from_slice(&var_columns(*d, &px.fixed[i]));
            }
            v
        };
        let split = |v: [f64; 3 * NVAR]| -> [[f64; NVAR]; 3] {
            std::array::from_fn(|j| std::array::from_fn(|a| v[j * NVAR + a]))
        };
        match &self.highpass {
            Some(hp) => hp
                .apply(&px.cell, &self.keep, raw)
                .into_iter()
                .map(split)
                .collect(),
            None => (0..dout.len()).map(|i| split(raw(i))).collect(),
        }
    }

    /// The outgoing columns of every pixel as fitted.
    fn var_columns(&self, px: &Pixels, out: &[Dwell]) -> Vec<[f64; NVAR]> {
        let raw = |i: usize| var_columns(out[i], &px.fixed[i]);
        match &self.highpass {
            Some(hp) => hp.apply(&px.cell, &self.keep, raw),
            None => (0..out.len()).map(raw).collect(),
        }
    }
}

/// Half-width of the high-pass box (in R), for photos without a plate: the data and every column
/// minus their mean over the kept cells within `±HIGHPASS_R R` (summed-area tables). Around the
/// impacts the folder's texture map is blank (a ball covers that cloth in most shots), and the
/// blotches left after the colour projection, 70–90 px across, were most of `delta1`'s error
/// there; the arc's geometry is in its edges (a 1-px ramp), which the filter keeps. The model is
/// filtered with the data, so the fit stays unbiased; the constant baseline column becomes zero
/// and is carried with a zero coefficient. Measured (clean sets without a plate, seeds 101, 202,
/// 303, the same 54 readings): median |error| 0.324°, 0.351°, 0.232° unfiltered; 0.218°, 0.214°,
/// 0.188° at 0.15 R; 0.212°, 0.158°, 0.174° at 0.25 R; 0.281°, 0.198°, 0.223° at 0.4 R.
const HIGHPASS_R: f64 = 0.25;
/// Smallest correlation factor ([`correlation_factor`] of the unfiltered residuals) at which the
/// high-passed fit is used. The filter trades the streaks' plateau for the blotches: it pays
/// where they dominate the residual, not where sensor noise does. Measured factors: 7–17 on
/// clean photos (one 4.6), 2–6.7 on realistic ones (sensor noise 3–4× the clean tier's), above
/// 15 where the light holds something the model does not (both tiers). On the realistic sets of
/// seeds 101, 202, 404 and 505 the filtered fit on every reading was worse overall (summed
/// |error| of the 14 changed readings 5.4° against 3.9°).
const HIGHPASS_MIN_F: f64 = 6.0;

/// Box means over the kept cells of a [`Pixels`] grid (the cells and mask are the caller's), by
/// summed-area tables.
struct HighPass {
    /// Table size: the grid plus a border row and column of zeros.
    gw: usize,
    gh: usize,
    k: usize,
    /// Summed-area table of the kept indicator.
    count: Vec<f64>,
}

/// Turns `t` (`m` interleaved components on a `gw × gh` table whose first row and column are
/// zero) into its summed-area table in place.
fn integrate(t: &mut [f64], gw: usize, gh: usize, m: usize) {
    for y in 1..gh {
        for x in 1..gw {
            for j in 0..m {
                let i = (y * gw + x) * m + j;
                t[i] += t[i - m] + t[i - gw * m] - t[i - gw * m - m];
            }
        }
    }
}

impl HighPass {
    fn new(px: &Pixels, keep: &[bool]) -> HighPass {
        let (gw, gh) = (px.grid.0 + 1, px.grid.1 + 1);
        let mut count = vec![0.0; gw * gh];
        for (&(cx, cy), &k) in px.cell.iter().zip(keep) {
            if k {
                count[(cy + 1) * gw + cx + 1] = 1.0;
            }
        }
        integrate(&mut count, gw, gh, 1);
        HighPass {
            gw,
            gh,
            k: px.highpass,
            count,
        }
    }

    /// Corners (table indices) of the box around grid cell `(cx, cy)`: `[y1x1, y0x1, y1x0, y0x0]`.
    #[inline]
    fn corners(&self, (cx, cy): (usize, usize)) -> [usize; 4] {
        let (x0, y0) = (cx.saturating_sub(self.k), cy.saturating_sub(self.k));
        let (x1, y1) = (
            (cx + self.k + 1).min(self.gw - 1),
            (cy + self.k + 1).min(self.gh - 1),
        );
        [
            y1 * self.gw + x1,
            y0 * self.gw + x1,
            y1 * self.gw + x0,
            y0 * self.gw + x0,
        ]
    }

    /// `Hᵀ r` for the filter `H` of [`HighPass::apply`] over the kept cells: at a kept cell
    /// `k`, `r_k` minus the sum of `r_i / n_i` over the kept cells `i` whose box holds `k` (the
    /// boxes are symmetric, so those are the kept cells in `k`'s own box); 0 elsewhere.
    fn adjoint(&self, cell: &[(usize, usize)], keep: &[bool], r: &[f64]) -> Vec<f64> {
        let n_of = |c: (usize, usize)| {
            let [a, b, cc, d] = self.corners(c);
            self.count[a] - self.count[b] - self.count[cc] + self.count[d]
        };
        let mut t = vec![0.0; self.gw * self.gh];
        for ((&c, &k), &ri) in cell.iter().zip(keep).zip(r) {
            if k {
                t[(c.1 + 1) * self.gw + c.0 + 1] = ri / n_of(c);
            }
        }
        integrate(&mut t, self.gw, self.gh, 1);
        cell.iter()
            .zip(keep)
            .zip(r)
            .map(|((&c, &k), &ri)| {
                if !k {
                    return 0.0;
                }
                let [a, b, cc, d] = self.corners(c);
                ri - (t[a] - t[b] - t[cc] + t[d])
            })
            .collect()
    }

    /// `f(i)` minus the mean of `f` over the kept cells in `i`'s box, for every cell `i` of
    /// `cell` (grid positions; `keep` the mask the table was made with).
    fn apply<const M: usize>(
        &self,
        cell: &[(usize, usize)],
        keep: &[bool],
        f: impl Fn(usize) -> [f64; M],
    ) -> Vec<[f64; M]> {
        let vals: Vec<[f64; M]> = (0..cell.len()).map(f).collect();
        let mut t = vec![0.0; self.gw * self.gh * M];
        for ((&(cx, cy), v), &k) in cell.iter().zip(&vals).zip(keep) {
            if k {
                let i = ((cy + 1) * self.gw + cx + 1) * M;
                t[i..i + M].copy_from_slice(v);
            }
        }
        integrate(&mut t, self.gw, self.gh, M);
        cell.iter()
            .zip(vals)
            .map(|(&c, v)| {
                let [a, b, cc, d] = self.corners(c);
                let n = self.count[a] - self.count[b] - self.count[cc] + self.count[d];
                if n > 0.0 {
                    std::array::from_fn(|j| {
                        let s = t[a * M + j] - t[b * M + j] - t[cc * M + j] + t[d * M + j];
                        v[j] - s / n
                    })
                } else {
                    v
                }
            })
            .collect()
    }
}

/// Fills the lower triangle of a normal matrix accumulated in its upper one, and scales it to
/// unit diagonal; returns the scale `sqrt(diag)` (a column's solution divides by it).
fn symmetrise_and_scale(m: &mut DMatrix<f64>) -> Vec<f64> {
    let n = m.nrows();
    for a in 0..n {
        for b in 0..a {
            m[(a, b)] = m[(b, a)];
        }
    }
    // A column that is zero throughout (the constant baseline after the high-pass) is
    // decoupled: unit scale and diagonal, so its coefficient and covariance are 0 and 1.
    let scale: Vec<f64> = (0..n)
        .map(|a| {
            if m[(a, a)] > 0.0 {
                m[(a, a)].sqrt()
            } else {
                1.0
            }
        })
        .collect();
    for a in 0..n {
        if m[(a, a)] <= 0.0 {
            m[(a, a)] = 1.0;
        }
    }
    for a in 0..n {
        for b in 0..n {
            m[(a, b)] /= scale[a] * scale[b];
        }
    }
    scale
}

fn cost(res: &[f64], keep: &[bool]) -> f64 {
    res.iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|(r, _)| r * r)
        .sum()
}

/// Levenberg–Marquardt on the projected residuals from `x`, its normal equations in closed form
/// ([`Pixels::normal_equations`]); returns the final point and its residuals.
///
/// Until session 34 the Jacobian was forward differences (three more evaluations of the dwell
/// per step); the closed form costs about one more, so the arc fit takes 40 % less time
/// (eight clean photos: 710 → 430 ms summed), and on the 64 comparison tables (1,548 rows) no
/// status changed, only `delta1` moved (median 0.013 sigma, largest 0.5 sigma) and two weak
/// readings became unresolved (rivals on their threshold).
fn levenberg_marquardt(
    px: &Pixels,
    g: &ArcGeometry,
    x: [f64; 3],
    mask: &Mask,
    max_iter: usize,
) -> Option<([f64; 3], Vec<f64>)> {
    lm_free(px, g, x, mask, max_iter, false)
}

/// [`levenberg_marquardt`], optionally with `δ` held fixed (its profile).
fn lm_free(
    px: &Pixels,
    g: &ArcGeometry,
    mut x: [f64; 3],
    mask: &Mask,
    max_iter: usize,
    pin_delta: bool,
) -> Option<([f64; 3], Vec<f64>)> {
    let keep = &mask.keep;
    // Each point with its normal equations (closed form, [`Pixels::normal_equations`]): the
    // cost is the same to the bit as [`Pixels::evaluate`]'s.
    type Normal = ([[f64; 3]; 3], [f64; 3]);
    let eval = |x: &[f64; 3]| -> Option<(f64, Vec<f64>, Normal)> {
        let (out, dout) = px.outgoing_grad(g, x);
        let s = px.solve(&out, mask)?;
        let normal = px.normal_equations(mask, &s, &dout, pin_delta);
        Some((cost(&s.res, keep), s.res, normal))
    };
    x = bounded(x, g);
    let (mut f, mut res, mut normal) = eval(&x)?;
    let mut lm = 1e-3;
    for iteration in 0..max_iter {
        let jtj = DMatrix::<f64>::from_fn(3, 3, |a, b| normal.0[a][b]);
        let jtr = DVector::<f64>::from_row_slice(&normal.1);
        let mut improved = false;
        for _ in 0..8 {
            let mut a = jtj.clone();
            for k in 0..3 {
                a[(k, k)] *= 1.0 + lm;
                a[(k, k)] += 1e-12;
            }
            if pin_delta {
                a[(0, 0)] = 1.0;
            }
            let Some(ch) = a.cholesky() else {
                lm *= 10.0;
                continue;
            };
            let dx = ch.solve(&(-&jtr));
            let xn = bounded([x[0] + dx[0], x[1] + dx[1], x[2] + dx[2]], g);
            let dx = [xn[0] - x[0], xn[1] - x[1], xn[2] - x[2]];
            let large =
                dx[0].abs() > CONVERGED_DELTA || dx[1].abs().max(dx[2].abs()) > CONVERGED_LEG;
            // After a step too small to continue, or in the last iteration, no Jacobian is
            // needed: the trial's cost alone (the same to the bit) decides.
            let trial = if large && iteration + 1 < max_iter {
                eval(&xn).map(|(f, r, n)| (f, r, Some(n)))
            } else {
                px.evaluate(g, &xn, mask).map(|(f, r)| (f, r, None))
            };
            if let Some((fnew, rn, nn)) = trial
                && fnew < f
            {
                let rel = (f - fnew) / f.max(1e-300);
                x = xn;
                f = fnew;
                res = rn;
                if let Some(nn) = nn {
                    normal = nn;
                }
                lm = (lm * 0.3).max(1e-7);
                improved = rel > 1e-8 && large;
                break;
            }
            lm *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some((x, res))
}

/// Systematic part of the uncertainty of `δ`, added in quadrature. Recalibrated in session 18
/// for the closed-form edge ([`Prepared::dwell`]), whose smooth cost ends the fit at the
/// minimum instead of in one of the ripples the 8-radius kernel made: median |error| of the
/// 17 synthetic sets' readings (seeds 101–505, 2400×1600, R ≈ 104 px) went from 0.18° to 0.13°
/// on clean photos without a plate (87 readings), 0.15° to 0.10° with one (18), 0.39° to 0.32°
/// on realistic ones (41), and from 0.16° to 0.23° on the mixed-spin set (seed 8, plate, 19),
/// whose `P` and `θ` errors tilt the arc one way (the fitted arc turns more than the true one,
/// journal). Each constant gives median |error| / sigma near 1 over its readings:
/// - with a plate, 0.35° (statistical parts 0.03–0.1°): 0.83 over 37 readings, 0.92 on the
///   mixed-spin set and 0.41 on seed 101's clean set. 0.30° would give 0.95 overall, but the
///   mixed-spin errors are one-sided (the turn read too large), and with free spin `e` rests on
///   `delta1` alone: at 0.30° `tests/spin.rs` put `e` 2.2 sigma from the truth (0.9737 ±
///   0.0017) and 5 of 35 stun shots' `r` beyond 2 sigma; at 0.35° 0.9737 ± 0.0020, 2 of 35.
///   Session 29 measured 0.46 on the clean set with a plate (21 readings), 0.40 and 0.23 on
///   the grazing sets with one (seeds 77 and 81, 13 and 11) and 0.86 on the mixed-spin set
///   (17): kept for the latter's one-sided errors, which the free-spin fit rests on;
/// - without a plate, unfiltered (mostly noisy realistic photos), 0.4°: 0.96 over 41 (0.6°).
///   Lowered to 0.2° in session 29, when the readings had become better than their sigmas:
///   realistic seeds 101–505 0.70 → 0.89 over 21 readings, fresh seeds 606/707 0.57 → 0.75
///   over 8, none beyond 3 sigma, one of 29 beyond 2 (statistical parts median 0.5°);
/// - the high-passed fit ([`HIGHPASS_R`]), 0.1°: 0.86 over 92 readings, its statistical part
///   (0.05–0.19°) nearly all of it (0.25°).
const SYSTEMATIC_DELTA_DEG: f64 = 0.35;
const SYSTEMATIC_DELTA_NO_PLATE_DEG: f64 = 0.2;
/// See [`SYSTEMATIC_DELTA_DEG`].
const SYSTEMATIC_DELTA_HIGHPASS_DEG: f64 = 0.1;

/// Variance inflation for spatially correlated residuals (cloth texture, shared noise): the mean
/// of `n_b m_b² / s²` over blocks of `side` px (at least 4), `m_b` a block's mean residual, `n_b`
/// its pixel count, `s²` the residual variance (1 for independent pixels).
fn correlation_factor(px: &Pixels, res: &[f64], keep: &[bool], side: f64) -> f64 {
    let side = side.max(4.0);
    // Ordered, so that the sum below is the same to the last bit on every run (a hash map's
    // iteration order is random per instance).
    let mut blocks: std::collections::BTreeMap<(i64, i64), (f64, usize)> = Default::default();
    let (mut ss, mut n) = (0.0, 0usize);
    for i in 0..px.q.len() {
        if !keep[i] {
            continue;
        }
        let key = (
            (px.q[i].0 / side).floor() as i64,
            (px.q[i].1 / side).floor() as i64,
        );
        let b = blocks.entry(key).or_default();
        b.0 += res[i];
        b.1 += 1;
        ss += res[i] * res[i];
        n += 1;
    }
    if n == 0 || ss <= 0.0 {
        return 1.0;
    }
    let s2 = ss / n as f64;
    let full: Vec<f64> = blocks
        .values()
        .filter(|b| b.1 >= 4)
        .map(|b| b.0 * b.0 / b.1 as f64 / s2)
        .collect();
    if full.is_empty() {
        return 1.0;
    }
    (full.iter().sum::<f64>() / full.len() as f64).max(1.0)
}

/// The rival arcs' extra turn (degrees) and the cost rise (in units of the correlation-widened
/// residual variance) below which one of them counts as fitting as well as the optimum.
pub const RIVAL_TURN_DEG: f64 = 10.0;
const RIVAL_CHI2: f64 = 25.0;
/// Legs of the rival arcs' start (in R): a slide of under a radius, as on rubber-like cloth.
const RIVAL_LEG_R: f64 = 0.4;
/// Levenberg–Marquardt iterations of a rival's legs (measured: 4 and 10 give the same verdicts
/// on the clean and realistic sets).
const RIVAL_ITERATIONS: usize = 4;

/// Shortest resolvable first Bézier leg `L₀`, in ball radii.
const MIN_ARC_R: f64 = 0.25;

/// Finite-difference step of the rolling direction `θ` (rad) for `∂δ/∂θ` ([`statistics`]); the
/// fit's own parameters have closed-form derivatives ([`Pixels::outgoing_grad`]).
const THETA_STEP: f64 = 1e-3;

/// A step smaller than this in `δ` (rad, 0.003°) and in both legs (px) ends the fit. Near the
/// optimum the convergence is only linear (each step some 0.3–0.7 of the previous one, along
/// the valley where `δ` and `L₀` trade off; neither central differences nor 4–6× larger
/// finite-difference steps made it quadratic: likely the large residual, cloth texture the
/// model does not hold, whose curvature Gauss–Newton leaves out), and the fits ran 10–15
/// steps, the last ones of 1e-5 rad and less. The 2–3× step left is ≪ the statistical
/// 0.03–0.1° of `δ`: on the accuracy sets `δ` moved by at most 0.008°, and with the photo's
/// pixels borrowed instead of copied ([`Signal::rgb`]) the analysis of a photo took 12–26 % less
/// time (`cargo bench --bench extract`).
const CONVERGED_DELTA: f64 = 5e-5;
const CONVERGED_LEG: f64 = 0.02;

/// The fit's statistics at an optimum `x`: the variance of `δ` (from the full problem's
/// covariance, 3 nonlinear + linear amplitudes, widened by the residuals' correlation), the
/// cost, the residual variance, the correlation factor, the residuals and the pixels kept.
struct Stat {
    var: f64,
    /// `∂δ/∂θ` at the optimum (linearised refit with `θ` moved).
    d_delta_d_theta: f64,
    c0: f64,
    s2: f64,
    f: f64,
    res: Vec<f64>,
    n: usize,
}

fn statistics(px: &Pixels, g: &ArcGeometry, x: &[f64; 3], mask: &Mask) -> Option<Stat> {
    let keep = &mask.keep;
    let (out, dout) = px.outgoing_grad(g, x);
    let solved = px.solve(&out, mask)?;
    // The model's change with `x` at fixed amplitudes, in closed form.
    let (model_dx, _) = px.model_derivatives(mask, &solved, &dout);
    let Solved { coef, res, var, .. } = solved;
    let n: usize = keep.iter().filter(|k| **k).count();
    let np = 3 + NLIN;
    if n <= np + 10 {
        return None;
    }
    let c0 = cost(&res, keep);
    let s2 = c0 / (n - np) as f64;
    let mut jtj = DMatrix::<f64>::zeros(np, np);
    // The model's change with the rolling direction `θ` (held in the fit), for `∂δ/∂θ`.
    let moved_theta = ArcGeometry {
        theta: g.theta + THETA_STEP,
        ..*g
    };
    let dtheta = mask.var_columns(px, &px.outgoing(&moved_theta, x));
    let derivative = |moved: &[f64; NVAR], base: &[f64; NLIN], fixed: &[f64; NFIX], h: f64| {
        let moved = row_of(moved, fixed);
        (0..NLIN)
            .map(|a| coef[a] * (moved[a] - base[a]))
            .sum::<f64>()
            / h
    };
    let mut row = vec![0.0; np];
    let mut jt_theta = vec![0.0; np];
    for i in 0..px.q.len() {
        if !keep[i] {
            continue;
        }
        let base = row_of(&var[i], &mask.fixed[i]);
        row[..3].copy_from_slice(&model_dx[i]);
        row[3..].copy_from_slice(&base);
        let j_theta = derivative(&dtheta[i], &base, &mask.fixed[i], THETA_STEP);
        for a in 0..np {
            jt_theta[a] += row[a] * j_theta;
            for b in a..np {
                jtj[(a, b)] += row[a] * row[b];
            }
        }
    }
    let scale = symmetrise_and_scale(&mut jtj);
    let cov = jtj.try_inverse()?;
    // The Gauss–Newton shift of the optimum per unit `θ`: `-[(JᵀJ)⁻¹ Jᵀ J_θ]_δ`, with the
    // columns scaled as `cov` is.
    let d_delta_d_theta = -(0..np)
        .map(|b| cov[(0, b)] * jt_theta[b] / scale[b])
        .sum::<f64>()
        / scale[0];
    // Blocks of R/2; after the high-pass, whose box takes out every block mean at that scale,
    // blocks of the box's half-width.
    let side = if mask.highpass.is_some() {
        HIGHPASS_R * g.r
    } else {
        0.5 * g.r
    };
    let f = correlation_factor(px, &res, keep, side);
    let var = s2 * f * cov[(0, 0)] / (scale[0] * scale[0]);
    (var.is_finite() && var > 0.0).then_some(Stat {
        var,
        d_delta_d_theta,
        c0,
        s2,
        f,
        res,
        n,
    })
}

/// [`ArcMiss::Hidden`] when the arc `x`'s first leg is under [`MIN_ARC_R`]: it lies inside the
/// cue ball's own footprint at `P` (at small psi such fits had collapsed onto the rolling line,
/// 30–48° off, with small stated errors).
fn visible(x: &[f64; 3], g: &ArcGeometry) -> Result<(), ArcMiss> {
    let l0 = legs(x).0;
    if l0 < MIN_ARC_R * g.r {
        Err(ArcMiss::Hidden(l0 / g.r))
    } else {
        Ok(())
    }
}

/// How far along `θ` from `P` the arc `x` ends.
fn end_along(x: &[f64; 3], g: &ArcGeometry) -> f64 {
    let (l0, l1) = legs(x);
    l0 * (x[0] - g.theta).cos() + l1
}

/// `x` with its second leg shortened so that the arc ends no farther along `θ` than
/// [`ArcGeometry::max_end`] (as far as a leg of half a pixel allows): the fit's steps are
/// projected onto the bound, so that it slides along it.
///
/// Until session 24 the bound was applied to the finished fit only: 43 % of the arc fits in the
/// debug logs of 26 synthetic sets had run to a long shallow arc beyond it (a second leg of
/// 3–10 R, its window twice the usual size) and were discarded, 42 % of the arc fit's time.
/// Bounded, the fit finds the short arc within: on those 26 sets (624 photos) 29 more start
/// tangents were read, all within 2.0 stated sigmas of the truth (9 on the five clean sets), 2
/// right ones were lost, the errors of the others moved by at most 0.5°, and the sets ran in
/// 10 % less time.
fn bounded(x: [f64; 3], g: &ArcGeometry) -> [f64; 3] {
    let Some(m) = g.max_end else { return x };
    let (l0, l1) = legs(&x);
    let c = l0 * (x[0] - g.theta).cos();
    if c + l1 <= m {
        return x;
    }
    [x[0], x[1], ((m - c).max(0.5) - 0.5).copysign(x[2])]
}

/// [`ArcMiss::Beyond`] when the arc `x` ends on (or beyond) [`ArcGeometry::max_end`].
fn within(x: &[f64; 3], g: &ArcGeometry) -> Result<(), ArcMiss> {
    match g.max_end {
        Some(m) if end_along(x, g) >= m - END_BOUND_TOL => Err(ArcMiss::Beyond),
        _ => Ok(()),
    }
}

/// An arc ending within this of [`ArcGeometry::max_end`] (px) is on the bound ([`bounded`]
/// puts a projected step on it to rounding).
const END_BOUND_TOL: f64 = 0.01;

/// The least cost rise (in units of `s2f`, the correlation-widened residual variance) of the
/// arcs turning [`RIVAL_TURN_DEG`] more (and, unless `more_only`, less) than the optimum `x`
/// (cost `c0`), their start tangents held and their legs refitted from [`RIVAL_LEG_R`].
fn rival_cost(
    px: &Pixels,
    g: &ArcGeometry,
    x: &[f64; 3],
    mask: &Mask,
    (c0, s2f): (f64, f64),
    more_only: bool,
) -> f64 {
    let leg = RIVAL_LEG_R * g.r;
    // The sign of the turn from `θ` to `δ`: adding it turns the arc more.
    let more = 1f64.copysign((x[0] - g.theta).sin());
    let sides: &[f64] = if more_only { &[1.0] } else { &[-1.0, 1.0] };
    sides
        .iter()
        .filter_map(|sgn| {
            let d = x[0] + sgn * more * RIVAL_TURN_DEG.to_radians();
            lm_free(px, g, [d, leg, leg], mask, RIVAL_ITERATIONS, true)
        })
        .map(|(_, r1)| (cost(&r1, &mask.keep) - c0) / s2f)
        .fold(f64::INFINITY, f64::min)
}

/// Why the arc fit gives no start tangent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArcMiss {
    /// Too few pixels in the window, or a fit that did not converge.
    NoFit,
    /// The arc that fits best has a first leg this many `R` long ([`MIN_ARC_R`] at least is
    /// needed): it lies inside the cue ball's own footprint at `P`, and its start tangent is not
    /// in the light.
    Hidden(f64),
    /// The best arc within [`ArcGeometry::max_end`] ends on that bound: the light asks for an
    /// arc ending beyond the first clean centre-line sample, which contradicts them.
    Beyond,
}

/// The cost of each stage of [`fit`], for `STREAKFIT_DEBUG`: the dwell evaluations (passes
/// over the window's cells, the unit that sets the arc fit's time) and the wall time.
struct Laps {
    on: bool,
    t: std::time::Instant,
    log: Vec<String>,
}

impl Laps {
    fn new(on: bool) -> Laps {
        Laps {
            on,
            t: std::time::Instant::now(),
            log: Vec::new(),
        }
    }

    /// Closes the stage `name`, whose evaluations ran on `px`.
    fn lap(&mut self, name: &str, px: &Pixels) {
        if self.on {
            let ms = self.t.elapsed().as_secs_f64() * 1e3;
            let n = px.evals.replace(0);
            self.log
                .push(format!("{name} {n} × {} cells {ms:.1} ms", px.q.len()));
            self.t = std::time::Instant::now();
        }
    }
}

/// Printed when the fit ends, on every path out of it (a hidden arc returns early).
impl Drop for Laps {
    fn drop(&mut self) {
        if self.on {
            eprintln!("arc stages: {}", self.log.join("; "));
        }
    }
}

/// Fits the sliding arc to the pixels around the impact.
///
/// Two stages keep it cheap: the starts are compared and refined on a grid of one pixel per
/// `R/20` of a window that holds all of them, then the fit is repeated on a window around the
/// chosen arc only, on a grid of one pixel per `R/25` (some 10 000 pixels whatever the scale),
/// with one round of outlier rejection.
pub fn fit(sig: &Signal, u: [f32; 3], g: &ArcGeometry) -> Result<ArcFit, ArcMiss> {
    fit_with(sig, u, g, true)
}

/// [`fit`], with the high-passed refit allowed or not (the unit tests compare the two).
fn fit_with(
    sig: &Signal,
    u: [f32; 3],
    g: &ArcGeometry,
    allow_highpass: bool,
) -> Result<ArcFit, ArcMiss> {
    let debug = std::env::var_os("STREAKFIT_DEBUG").is_some();
    let mut laps = Laps::new(debug);
    let cands: Vec<[f64; 3]> = starts(g).into_iter().map(|c| bounded(c, g)).collect();
    let coarse = Pixels::gather(sig, u, g, &cands, ((g.r / 20.0).round() as usize).max(2));
    if coarse.q.len() < 100 {
        return Err(ArcMiss::NoFit);
    }
    let all = Mask::new(&coarse, vec![true; coarse.q.len()], false);
    let mut best: Option<([f64; 3], f64)> = None;
    for c in &cands {
        if let Some((f, _)) = coarse.evaluate(g, c, &all)
            && best.is_none_or(|b| f < b.1)
        {
            best = Some((*c, f));
        }
    }
    let best = best.ok_or(ArcMiss::NoFit)?;
    laps.lap("starts", &coarse);
    let (x, _) = levenberg_marquardt(&coarse, g, best.0, &all, 6).ok_or(ArcMiss::NoFit)?;
    laps.lap("coarse LM", &coarse);
    let stride = ((g.r / 25.0).round() as usize).max(1);
    let px = Pixels::gather(sig, u, g, &[x], stride);
    if px.q.len() < 200 {
        return Err(ArcMiss::NoFit);
    }
    let (x, res) = levenberg_marquardt(
        &px,
        g,
        x,
        &Mask::new(&px, vec![true; px.q.len()], false),
        15,
    )
    .ok_or(ArcMiss::NoFit)?;
    laps.lap("fine LM", &px);
    let kept: Vec<f32> = res.iter().map(|r| *r as f32).collect();
    let s = (mad_sigma(&kept) as f64).max(1e-9);
    let mask = Mask::new(&px, res.iter().map(|r| r.abs() <= 4.0 * s).collect(), false);
    let (x, _) = levenberg_marquardt(&px, g, x, &mask, 15).ok_or(ArcMiss::NoFit)?;
    laps.lap("outliers out", &px);
    let keep = &mask.keep;
    // An arc much shorter than the ball's radius: its start tangent is not in the light.
    visible(&x, g)?;
    within(&x, g)?;
    let Stat {
        var,
        d_delta_d_theta,
        c0,
        s2,
        f,
        res,
        n,
    } = statistics(&px, g, &x, &mask).ok_or(ArcMiss::NoFit)?;
    laps.lap("statistics", &px);
    // The cost near the optimum is not the whole story: a short arc turning ±10° more, refitted
    // with its start tangent held, may fit nearly as well when the turn hides where the streaks
    // overlap (a short slide on a high-friction cloth). Then the start tangent is not measured,
    // whatever the curvature at the optimum says. (Starting the rivals from the optimum's own
    // legs as well flagged good arcs too: realistic shot_020, 0.08° off.)
    let rival = rival_cost(&px, g, &x, &mask, (c0, s2 * f), false);
    laps.lap("rivals", &px);
    if debug {
        eprintln!("arc: an arc turning ±{RIVAL_TURN_DEG}° more costs Δχ² {rival:.1}");
    }
    if let Some(path) = std::env::var_os("STREAKFIT_ARC_DUMP") {
        dump(&px, &res, keep, std::path::Path::new(&path));
    }
    // Where the cloth's blotches dominate the residual (its correlation factor at least
    // [`HIGHPASS_MIN_F`]; with a plate only where the light holds what the model does not, as on
    // some mixed-spin shots), the start tangent and its statistical error come from the same fit
    // with the blotches filtered out ([`HIGHPASS_R`]). Whether it is resolved at all is decided
    // on the unfiltered light first (the rivals above), whose correlation factor sees the
    // blotches: on the filtered residuals it is near 1, and rivals alone there passed arcs that
    // fit nearly as well (a rubber shot 8° off at a stated 1.2°).
    let fmask =
        (allow_highpass && f >= HIGHPASS_MIN_F).then(|| Mask::new(&px, mask.keep.clone(), true));
    let refit = fmask
        .as_ref()
        .and_then(|fm| levenberg_marquardt(&px, g, x, fm, 15))
        .map(|(xf, _)| xf);
    if refit.is_some() {
        laps.lap("high-passed LM", &px);
    }
    // On the filtered light the arc is hidden in the cue ball's footprint at `P`: the
    // unfiltered optimum (a longer arc that fits the blotches' and the brightness profile's
    // slow changes) does not measure the turn either.
    if let Some(xf) = &refit {
        visible(xf, g)?;
        within(xf, g)?;
    }
    let filtered = refit.zip(fmask.as_ref()).and_then(|(xf, fmask)| {
        let st = statistics(&px, g, &xf, fmask)?;
        if debug {
            eprintln!(
                "arc high-pass: delta {:+.3}° from the unfiltered fit, sd {:.3}° against \
                 {:.3}° (correlation factor {f:.1})",
                (xf[0] - x[0]).to_degrees(),
                st.var.sqrt().to_degrees(),
                var.sqrt().to_degrees(),
            );
        }
        // The rivals again, on the filtered light, where the unfiltered ones did not
        // already decide: its cost may have a lower branch that the refit from the
        // unfiltered optimum does not reach (demo rubber shot_019, psi 16°: from a 2.9 R arc
        // turning 6° the refit ended on a 0.36 R arc still turning 6°, 19° off, while the
        // true 0.1 R arc turning 25° costs 236 units less; the rival turning 10° more finds
        // that branch, 142 units below the refit). Only the rival turning more: a turn
        // hidden where the streaks overlap reads too small.
        let rival_f = if rival < RIVAL_CHI2 {
            rival
        } else {
            rival_cost(&px, g, &xf, fmask, (st.c0, st.s2 * st.f), true)
        };
        if debug {
            eprintln!(
                "arc high-pass: an arc turning {RIVAL_TURN_DEG}° more costs Δχ² {rival_f:.1}"
            );
        }
        Some((xf, st.var, st.d_delta_d_theta, rival_f))
    });
    let highpass = filtered.is_some();
    if highpass {
        laps.lap("high-passed statistics and rival", &px);
    }
    let rival = rival.min(filtered.map_or(f64::INFINITY, |f| f.3));
    let (x, var, systematic, slope) = match filtered {
        Some((xf, vf, sf, _)) => (xf, vf, SYSTEMATIC_DELTA_HIGHPASS_DEG, sf),
        None if sig.plate => (x, var, SYSTEMATIC_DELTA_DEG, d_delta_d_theta),
        None => (x, var, SYSTEMATIC_DELTA_NO_PLATE_DEG, d_delta_d_theta),
    };
    // `θ` is held at the centre-line fit's value; where the arc is short or faint `δ` follows
    // it several-fold (grazing photos without a plate: `θ` 0.3–0.4° off moved `δ` 0.9–2.0°),
    // so its stated uncertainty enters `δ`'s through `∂δ/∂θ`.
    let theta_part = if g.theta_sd.is_finite() {
        (slope * g.theta_sd).powi(2)
    } else {
        f64::INFINITY
    };
    if debug {
        eprintln!(
            "arc: d delta / d theta {slope:.2}, theta's {:.3}° adds {:.3}° to delta's sigma",
            g.theta_sd.to_degrees(),
            theta_part.sqrt().to_degrees()
        );
    }
    let var = var + theta_part;
    let (l0, l1) = legs(&x);
    Ok(ArcFit {
        rival: rival < RIVAL_CHI2,
        delta: x[0],
        delta_sd: (var + systematic.to_radians().powi(2)).sqrt(),
        l0,
        l1,
        end: (
            g.p.0 + l0 * x[0].cos() + l1 * g.theta.cos(),
            g.p.1 + l0 * x[0].sin() + l1 * g.theta.sin(),
        ),
        n_px: n,
        highpass,
        rms: s2.sqrt(),
    })
}

/// Debug picture: data (left) and residual (right) of the window, grey 128 = 0.
fn dump(px: &Pixels, res: &[f64], keep: &[bool], path: &std::path::Path) {
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for q in &px.q {
        x0 = x0.min(q.0 as usize);
        y0 = y0.min(q.1 as usize);
        x1 = x1.max(q.0 as usize);
        y1 = y1.max(q.1 as usize);
    }
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let mut vals: Vec<f32> = px.v.iter().map(|v| *v as f32).collect();
    let base = super::background::median(&mut vals) as f64;
    let mut img = image::RgbImage::from_pixel(2 * w as u32, h as u32, image::Rgb([0, 0, 60]));
    // Residuals averaged over 6×6-px blocks so that systematic patterns stand out of the noise.
    let bw = w / 6 + 1;
    let mut sum = vec![(0.0f64, 0usize); bw * (h / 6 + 1)];
    for (q, r) in px.q.iter().zip(res) {
        let (x, y) = (q.0 as usize - x0, q.1 as usize - y0);
        let b = &mut sum[(y / 6) * bw + x / 6];
        b.0 += r;
        b.1 += 1;
    }
    for (i, q) in px.q.iter().enumerate() {
        let (x, y) = (q.0 as usize - x0, q.1 as usize - y0);
        let g = |v: f64| (128.0 + v * 8000.0).clamp(0.0, 255.0) as u8;
        let d = g((px.v[i] - base) / 4.0);
        img.put_pixel(x as u32, y as u32, image::Rgb([d, d, d]));
        let b = sum[(y / 6) * bw + x / 6];
        let r = g(b.0 / b.1 as f64);
        let c = if keep[i] { [r, r, r] } else { [255, 0, 0] };
        img.put_pixel((w + x) as u32, y as u32, image::Rgb(c));
    }
    let _ = img.save(path);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::render::{Backdrop, Frame, Segment, render};
    use crate::vision::image_io::RgbImage as FloatImage;
    use crate::vision::{Plate, background};

    const R: f64 = 40.0;

    /// A rolling-type shot: incoming from the upper left to `P`, an arc starting at `delta`
    /// that ends on the rolling line `theta` (Bézier `L₀, L₁`), drawn as 400 chords of equal
    /// time, then the rolling line at the arc's end speed. Renderer coordinates put pixel
    /// centres at +0.5; the returned geometry is in the extractor's (pixel index = centre).
    fn scene(delta: f64, theta: f64, l0: f64, l1: f64) -> (Frame, ArcGeometry) {
        let p = (200.5, 150.5);
        let inc = unit(35f64.to_radians());
        let rgb = [0.86, 0.85, 0.8];
        let seg = |a: (f64, f64), b: (f64, f64), frac: f64| Segment {
            a: [a.0, a.1],
            b: [b.0, b.1],
            frac,
            r: R,
            rgb,
        };
        // Speeds in px per unit frac: incoming 4000, rolling 2000.
        let mut segments = vec![seg(
            (p.0 - 900.0 * inc.0, p.1 - 900.0 * inc.1),
            p,
            900.0 / 4000.0,
        )];
        let (u0, u1) = (unit(delta), unit(theta));
        let c = (p.0 + l0 * u0.0, p.1 + l0 * u0.1);
        let e = (c.0 + l1 * u1.0, c.1 + l1 * u1.1);
        let bez = |t: f64| {
            let (a, b, cc) = ((1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t);
            (a * p.0 + b * c.0 + cc * e.0, a * p.1 + b * c.1 + cc * e.1)
        };
        // End speed 2 L₁ / T = 2000 per frac.
        let t_slide = 2.0 * l1 / 2000.0;
        let n = 400;
        for i in 0..n {
            let (a, b) = (bez(i as f64 / n as f64), bez((i + 1) as f64 / n as f64));
            segments.push(seg(a, b, t_slide / n as f64));
        }
        let end = (e.0 + 900.0 * u1.0, e.1 + 900.0 * u1.1);
        segments.push(seg(e, end, 900.0 / 2000.0));
        let frame = Frame {
            segments,
            discs: vec![],
        };
        let x = unit(delta + 0.5 * (theta - delta) - 1.2);
        let o = (p.0 - 0.5 + 2.0 * R * x.0, p.1 - 0.5 + 2.0 * R * x.1);
        let g = ArcGeometry {
            p: (p.0 - 0.5, p.1 - 0.5),
            r: R,
            theta,
            line_point: (e.0 - 0.5 + 50.0 * u1.0, e.1 - 0.5 + 50.0 * u1.1),
            incoming: inc,
            // No object ball is drawn; its mask is put well away from the streaks.
            o: (o.0 + 600.0, o.1 + 600.0),
            object_dir: (1.0, 0.0),
            delta_guess: None,
            theta_sd: 0.0,
            max_end: None,
        };
        (frame, g)
    }

    /// The arc fit on a rendering with sensor noise `a = b = noise` (seeded), against a
    /// noise-free plate.
    fn measure(frame: &Frame, g: &ArcGeometry, noise: f64, seed: Option<u64>) -> ArcFit {
        let (img, plate) = rendering(frame, noise, seed);
        let sig = background::build(&img, background::Cloth::Plate(&plate), 600).expect("signal");
        fit(&sig, sig.u, g).expect("arc fit")
    }

    /// A rendering of `frame` on a plain 520×420 cloth with sensor noise `a = b = noise`
    /// (seeded), and its noise-free plate.
    fn rendering(frame: &Frame, noise: f64, seed: Option<u64>) -> (FloatImage, Plate) {
        let bd = Backdrop::plain(520, 420, noise);
        crate::vision::rendered_with_plate(frame, &bd, seed)
    }

    /// The closed-form gradients of `piece` at pixel `q` next to central differences of its
    /// dwell with step `h`, as `(ours, theirs)` for each image component: the seven of
    /// [`PieceGrad`] in its order.
    fn gradient_pairs(piece: &Prepared, q: (f64, f64), k: &Kernel, h: f64) -> [[(f64, f64); 7]; 2] {
        let gr = piece.gradients(q, k);
        let (a, b, dens) = (
            piece.a,
            (
                piece.a.0 + piece.len * piece.d.0,
                piece.a.1 + piece.len * piece.d.1,
            ),
            piece.dens,
        );
        // Held time: move one end, scale the density so that `dens · len` stays.
        let with = |a: (f64, f64), b: (f64, f64)| {
            let l = (b.0 - a.0).hypot(b.1 - a.1);
            Prepared::new(a, b, dens * piece.len / l).dwell(q, k)
        };
        let moved = |a: (f64, f64), b: (f64, f64)| Prepared::new(a, b, dens).dwell(q, k);
        std::array::from_fn(|c| {
            let e = [(h, 0.0), (0.0, h)][c];
            let (ap, am) = ((a.0 + e.0, a.1 + e.1), (a.0 - e.0, a.1 - e.1));
            let (bp, bm) = ((b.0 + e.0, b.1 + e.1), (b.0 - e.0, b.1 - e.1));
            let fd = |p: Dwell, m: Dwell| {
                [
                    (p.d0 - m.d0) / (2.0 * h),
                    (p.d2 - m.d2) / (2.0 * h),
                    (p.ramp - m.ramp) / (2.0 * h),
                ]
            };
            let (da, db, dm) = (
                fd(with(ap, b), with(am, b)),
                fd(with(a, bp), with(a, bm)),
                fd(moved(ap, bp), moved(am, bm)),
            );
            [
                (gr.d0a[c], da[0]),
                (gr.d0b[c], db[0]),
                (gr.d2a[c], da[1]),
                (gr.d2b[c], db[1]),
                (gr.d0m[c], dm[0]),
                (gr.d2m[c], dm[1]),
                (gr.rampm[c], dm[2]),
            ]
        })
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4000))]
        /// The closed-form gradients against central differences over random pieces, kernels
        /// and pixels, including the hard places: a pixel on the piece's own line (`y = 0`,
        /// where the logarithms drop out), on the perpendicular through its start, and pieces
        /// far shorter than a pixel or far longer than the kernel.
        #[test]
        fn piece_gradients_hold_for_random_geometry(
            ax in -50.0f64..50.0,
            ay in -50.0f64..50.0,
            angle in 0.0f64..std::f64::consts::TAU,
            len in proptest::prop_oneof![0.01f64..0.5, 0.5f64..20.0, 20.0f64..400.0],
            dens in 0.1f64..5.0,
            r in 5.0f64..120.0,
            stride in 1usize..5,
            along in -1.3f64..1.3,
            across in -1.3f64..1.3,
            place in 0u8..4,
        ) {
            let k = Kernel::for_cells(r, stride);
            let (a, d) = ((ax, ay), (angle.cos(), angle.sin()));
            let b = (a.0 + len * d.0, a.1 + len * d.1);
            let piece = Prepared::new(a, b, dens);
            // Along: from before the start to beyond the end; across: within the kernel.
            let (mut x, mut y) = (along * (len + k.rmax) + 0.5 * len, across * k.rmax);
            match place {
                0 => y = 0.0,
                1 => x = 0.0,
                _ => {}
            }
            let q = (a.0 + x * d.0 - y * d.1, a.1 + x * d.1 + y * d.0);
            let f = piece.dwell(q, &k);
            // Absolute, in units of the piece's time: the central differences agree to about
            // 1e-9 of the gradients (a 1e-12 bound fails at 7e-12 on a 0.011 gradient). Where a
            // kernel radius crosses the piece close to its end the dwell's second derivative
            // jumps and the differences converge only as `h`: there the check is that they
            // converge to ours, the difference at `h/10` within its change from `h`.
            let tol = 1e-7 * dens * piece.len.max(1.0);
            let coarse = gradient_pairs(&piece, q, &k, 1e-6 * r);
            let fine = gradient_pairs(&piece, q, &k, 1e-7 * r);
            for ((ours, at_h), (_, at_tenth)) in
                coarse.into_iter().flatten().zip(fine.into_iter().flatten())
            {
                proptest::prop_assert!(
                    ours.is_finite() && (ours - at_tenth).abs() <= tol + (at_h - at_tenth).abs(),
                    "{} against {} at h and {} at h/10 (tol {:e}, dwell {:?})",
                    ours, at_h, at_tenth, tol, f
                );
            }
        }
    }

    /// The Jacobian of the projected residuals ([`Pixels::jacobian`]) against central
    /// differences of [`Pixels::evaluate`], on a rendered arc, at the truth and away from it,
    /// with a partial mask, with and without the high-pass and with `δ` held.
    #[test]
    fn projected_jacobian_is_the_residuals_derivative() {
        let (delta, theta) = (100f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.55 * R, 0.6 * R);
        let (img, plate) = rendering(&frame, 0.02, Some(3));
        let sig = background::build(&img, background::Cloth::Plate(&plate), 600).expect("signal");
        let px = Pixels::gather(&sig, sig.u, &g, &[[delta, 0.55 * R, 0.6 * R]], 2);
        let n = px.q.len();
        let keep: Vec<bool> = (0..n).map(|i| i % 7 != 3).collect();
        let steps = [2e-5, 1e-3, 1e-3];
        for highpass in [false, true] {
            let mask = Mask::new(&px, keep.clone(), highpass);
            for x in [
                [delta, 0.55 * R, 0.6 * R],
                [delta + 0.1, 0.3 * R, 1.1 * R],
                [delta - 0.2, -0.8 * R, 0.2 * R],
            ] {
                let (out, dout) = px.outgoing_grad(&g, &x);
                let plain = px.outgoing(&g, &x);
                assert!(
                    out.iter()
                        .zip(&plain)
                        .all(|(a, b)| a.d0.to_bits() == b.d0.to_bits()
                            && a.d2.to_bits() == b.d2.to_bits()
                            && a.ramp.to_bits() == b.ramp.to_bits())
                );
                let solved = px.solve(&out, &mask).expect("solve");
                for pin in [false, true] {
                    let jac = px.jacobian(&mask, &solved, &dout, pin);
                    // The normal equations formed without `J` are `JᵀJ` and `Jᵀr`.
                    let (jtj, jtr) = px.normal_equations(&mask, &solved, &dout, pin);
                    for a in 0..3 {
                        let r: f64 = (0..n).map(|i| jac[i][a] * solved.res[i]).sum();
                        let scale_a: f64 = (0..n).map(|i| jac[i][a].powi(2)).sum::<f64>().sqrt();
                        let rn: f64 = solved.res.iter().map(|r| r * r).sum::<f64>().sqrt();
                        assert!(
                            (r - jtr[a]).abs() <= 1e-7 * scale_a * rn + 1e-300,
                            "Jᵀr[{a}] {} against {r}",
                            jtr[a]
                        );
                        for b in 0..3 {
                            let v: f64 = (0..n).map(|i| jac[i][a] * jac[i][b]).sum();
                            let scale_b: f64 =
                                (0..n).map(|i| jac[i][b].powi(2)).sum::<f64>().sqrt();
                            assert!(
                                (v - jtj[a][b]).abs() <= 1e-8 * scale_a * scale_b + 1e-300,
                                "JᵀJ[{a}][{b}] {} against {v}",
                                jtj[a][b]
                            );
                        }
                    }
                    for k in 0..3 {
                        let (mut xp, mut xm) = (x, x);
                        xp[k] += steps[k];
                        xm[k] -= steps[k];
                        let (_, rp) = px.evaluate(&g, &xp, &mask).unwrap();
                        let (_, rm) = px.evaluate(&g, &xm, &mask).unwrap();
                        let (mut num, mut err) = (0.0, 0.0);
                        for i in 0..n {
                            let fd = if keep[i] && !(pin && k == 0) {
                                (rp[i] - rm[i]) / (2.0 * steps[k])
                            } else {
                                0.0
                            };
                            num += fd * fd;
                            err += (jac[i][k] - fd).powi(2);
                        }
                        let rel = (err / num.max(1e-300)).sqrt();
                        if pin && k == 0 {
                            assert!(err == 0.0, "held δ has a column");
                        } else {
                            assert!(
                                num > 0.0 && rel < 1e-4,
                                "highpass {highpass} x {x:?} column {k}: relative error {rel:e}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn recovers_the_start_tangent_of_a_rendered_arc() {
        // Follow-like arc: turns 25° over about one radius.
        let (delta, theta) = (100f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.55 * R, 0.6 * R);
        // Bias: the mean error over 8 renderings with faint noise (about 0.5 DN, enough to
        // dither the 8-bit rounding, whose fixed pattern alone moves δ by 0.3° on a noise-free
        // image) is -0.07° (scatter 0.3°, so the standard error of the mean is 0.1°).
        let errs: Vec<f64> = (1..=8)
            .map(|seed| (measure(&frame, &g, 0.005, Some(seed)).delta - delta).to_degrees())
            .collect();
        let mean = errs.iter().sum::<f64>() / errs.len() as f64;
        assert!(mean.abs() < 0.25, "mean δ error {mean:.3}° ({errs:.3?})");
        // Noise of about 1.7 DN on a 40-px ball: the error (0.55° here) must lie within the
        // stated uncertainty.
        let noisy = measure(&frame, &g, 0.05, Some(5));
        let err = (noisy.delta - delta).to_degrees();
        assert!(
            err.abs() < 2.0 && err.abs() < 3.0 * noisy.delta_sd.to_degrees(),
            "noisy: δ error {err:.3}° ({noisy:?})"
        );
    }

    /// The arc must end before the first clean centre-line sample ([`ArcGeometry::max_end`]):
    /// a bound short of the true arc's end leaves the fit on it, which is no reading; a bound
    /// beyond it finds the unbounded fit's arc.
    #[test]
    fn an_arc_ending_on_the_samples_bound_is_not_read() {
        let (delta, theta) = (100f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.55 * R, 0.6 * R);
        let (img, plate) = rendering(&frame, 0.005, Some(1));
        let sig = background::build(&img, background::Cloth::Plate(&plate), 600).expect("signal");
        let fit_to = |max_end: Option<f64>| fit(&sig, sig.u, &ArcGeometry { max_end, ..g });
        // The true arc ends 0.55 R cos 25° + 0.6 R = 1.10 R along θ.
        let free = fit_to(None).expect("unbounded fit");
        let loose = fit_to(Some(2.0 * R)).expect("fit within a loose bound");
        let moved = (loose.delta - free.delta).to_degrees();
        assert!(moved.abs() < 0.02, "a loose bound moved δ by {moved:.4}°");
        assert!((free.delta - delta).to_degrees().abs() < 0.25, "{free:?}");
        let tight = fit_to(Some(0.8 * R));
        assert!(matches!(tight, Err(ArcMiss::Beyond)), "{tight:?}");
        // Steps are projected onto the bound by shortening the second leg.
        let gb = ArcGeometry {
            max_end: Some(0.8 * R),
            ..g
        };
        let x = bounded([theta - 0.4, 0.55 * R, 0.6 * R], &gb);
        assert!((end_along(&x, &gb) - 0.8 * R).abs() < 1e-9, "{x:?}");
        assert!(
            (x[1] - 0.55 * R).abs() < 1e-12,
            "the first leg moved: {x:?}"
        );
    }

    /// Where a piece spans a pixel's whole chord, the dwell computes one of its two
    /// mirror-image ramps and uses it twice: the same bits as integrating both, for pixels
    /// inside and beyond the inner radius of a long piece.
    /// The closed-form end and move gradients of a piece's dwell against central differences
    /// of [`Prepared::dwell`], for pixels inside the inner radius, on the ramp, across the piece's
    /// ends and at the kernel's edge, on short (arc) and long (rolling line) pieces.
    #[test]
    fn piece_gradients_are_the_dwells_derivatives() {
        let k = Kernel::for_cells(40.0, 2);
        let h = 1e-5;
        let mut checked = [0usize; 3];
        for (a, b, dens) in [
            ((3.1, -2.7), (7.9, 1.3), 0.8),
            ((-1.3, 0.4), (-0.2, 5.1), 2.5),
            ((10.3, -7.1), (490.9, 203.2), 1.0),
        ] {
            let piece = Prepared::new(a, b, dens);
            for i in 0..2000 {
                let q = (
                    a.0 - 45.0 + 0.0731 * (i % 50) as f64 * 37.0,
                    a.1 - 45.0 + 0.0917 * (i / 50) as f64 * 27.0,
                );
                let f = piece.dwell(q, &k);
                if f.d0 == 0.0 {
                    continue;
                }
                for (c, pairs) in gradient_pairs(&piece, q, &k, h).into_iter().enumerate() {
                    for (j, (ours, theirs)) in pairs.into_iter().enumerate() {
                        // Central differences are good to about 1e-9 of the values here.
                        let tol = 1e-6 * (1.0 + f.d0.abs() + f.d2.abs() + f.ramp.abs());
                        assert!(
                            (ours - theirs).abs() < tol,
                            "piece {a:?}-{b:?} q {q:?} component {c} gradient {j}: \
                             {ours} against {theirs}"
                        );
                    }
                }
                let (wx, wy) = (q.0 - a.0, q.1 - a.1);
                let y = (piece.d.0 * wy - piece.d.1 * wx).abs();
                checked[if y * y < k.rmin2 { 0 } else { 1 }] += 1;
                if f.d0 < piece.dens * piece.len * 0.999 {
                    checked[2] += 1;
                }
            }
        }
        // Pixels inside the inner radius, beyond it (ramp only) and partly covered all occur.
        assert!(checked.iter().all(|&n| n > 50), "{checked:?}");
    }

    #[test]
    fn mirrored_ramps_are_two_ramp_calls_to_the_last_bit() {
        // The dwell as it was before the shortcut: both ramps integrated, always.
        let two_calls = |piece: &Prepared, q: (f64, f64), k: &Kernel| -> (Integrals, f64) {
            let (wx, wy) = (q.0 - piece.a.0, q.1 - piece.a.1);
            let x = wx * piece.d.0 + wy * piece.d.1;
            let y = piece.d.0 * wy - piece.d.1 * wx;
            let (y2, t0, t1) = (y * y, -x, piece.len - x);
            let mut acc = Integrals::default();
            let ha = (k.rmax2 - y2).sqrt();
            if y2 < k.rmin2 {
                let hb = (k.rmin2 - y2).sqrt();
                acc.inner::<false>(t0.max(-hb), t1.min(hb), y);
                acc.ramp::<false>(t0.max(-ha), t1.min(-hb), y, k);
                acc.ramp::<false>(t0.max(hb), t1.min(ha), y, k);
            } else {
                acc.ramp::<false>(t0.max(-ha), t1.min(0.0), y, k);
                acc.ramp::<false>(t0.max(0.0), t1.min(ha), y, k);
            }
            (acc, x)
        };
        let k = Kernel::for_cells(104.0, 4);
        // A long straight piece (the rolling line) and pixels across it, inside and beyond the
        // inner radius, at odd offsets so that no term is exact.
        let piece = Prepared::new((10.3, -7.1), (1210.9, 403.2), 1.0);
        let mut spanned = [0usize; 2];
        for i in 0..400 {
            let along = 150.0 + 2.37 * i as f64;
            let across = -108.0 + 0.541 * i as f64;
            let q = (
                piece.a.0 + along * piece.d.0 - across * piece.d.1,
                piece.a.1 + along * piece.d.1 + across * piece.d.0,
            );
            let ours = piece.dwell(q, &k);
            let (theirs, x) = two_calls(&piece, q, &k);
            if across.abs() >= k.rmax {
                continue;
            }
            spanned[usize::from(across * across >= k.rmin2)] += 1;
            let d = piece.dens;
            assert_eq!(
                ours.d0.to_bits(),
                (d * theirs.k0).to_bits(),
                "d0 at {across}"
            );
            assert_eq!(
                ours.d2.to_bits(),
                (d * theirs.k2 * k.inv_r2).to_bits(),
                "d2 at {across}"
            );
            assert_eq!(
                ours.ramp.to_bits(),
                (d * (theirs.kt + x * theirs.k0) * k.inv_r).to_bits(),
                "ramp at {across}"
            );
        }
        assert!(spanned[0] > 100 && spanned[1] > 5, "{spanned:?}");
    }

    /// The closed-form dwell is the limit of many hard discs of radii spread over the ramp: a
    /// midpoint rule of 20,000 radii agrees to 1e-6 of the piece's length (its own error where a
    /// chord starts inside the ramp, `√(ρ² - y²)`, is a few 1e-8), for pixels inside,
    /// on and beyond the edge, beside and beyond both ends, on the axis and off it.
    #[test]
    fn the_soft_edge_dwell_is_the_limit_of_many_hard_discs() {
        let k = Kernel::new(40.0, 2.3);
        let piece = Prepared::new((3.0, -2.0), (15.0, 7.0), 0.7);
        let hard = |q: (f64, f64)| -> Dwell {
            let n = 20_000;
            let (wx, wy) = (q.0 - piece.a.0, q.1 - piece.a.1);
            let x = wx * piece.d.0 + wy * piece.d.1;
            let y = piece.d.0 * wy - piece.d.1 * wx;
            let (mut f0, mut f2, mut f1) = (0.0, 0.0, 0.0);
            for i in 0..n {
                let rho = 40.0 - 1.15 + 2.3 * (i as f64 + 0.5) / n as f64;
                if y.abs() >= rho {
                    continue;
                }
                let h = (rho * rho - y * y).sqrt();
                let (lo, hi) = ((x - h).max(0.0), (x + h).min(piece.len));
                if hi > lo {
                    f0 += hi - lo;
                    f2 += y * y * (hi - lo) + ((x - lo).powi(3) - (x - hi).powi(3)) / 3.0;
                    f1 += 0.5 * (hi * hi - lo * lo);
                }
            }
            let wgt = piece.dens / n as f64;
            Dwell {
                d0: wgt * f0,
                d2: wgt * f2 * k.inv_r2,
                ramp: wgt * f1 * k.inv_r,
            }
        };
        let (mut partial, mut full) = (0, 0);
        for &(along, across) in &[
            (0.5f64, 0.0f64),
            (0.5, 20.0),
            (0.5, 39.5),
            (0.5, 40.0),
            (0.5, 40.9),
            (0.5, 41.2),
            (-38.0, 3.0),
            (-40.5, 0.0),
            (1.05, 30.0),
            (1.0 + 38.9 / 15.0, -5.0),
            (0.3, -39.2),
            (-1.0, 25.0),
        ] {
            // `along` in piece lengths from `a` (15 px), `across` in px.
            let l = piece.len;
            let along_px = if along.abs() > 2.0 { along } else { along * l };
            let q = (
                piece.a.0 + along_px * piece.d.0 - across * piece.d.1,
                piece.a.1 + along_px * piece.d.1 + across * piece.d.0,
            );
            let (ours, theirs) = (piece.dwell(q, &k), hard(q));
            for (name, a, b) in [
                ("d0", ours.d0, theirs.d0),
                ("d2", ours.d2, theirs.d2),
                ("ramp", ours.ramp, theirs.ramp),
            ] {
                assert!(
                    (a - b).abs() < 1e-6 * l,
                    "{name} at ({along}, {across}): {a} against {b}"
                );
            }
            if ours.d0 > 0.0 && ours.d0 < piece.dens * l * (1.0 - 1e-12) {
                partial += 1;
            } else if ours.d0 > 0.0 {
                full += 1;
            }
        }
        assert!(partial >= 5 && full >= 2, "partial {partial}, full {full}");
    }

    /// The held rolling direction's uncertainty reaches `δ`'s: handed a `θ` 0.3° off, a short
    /// arc's `δ` moves by twice that, and the stated sigma, told `θ`'s, grows to cover it.
    /// Measured (session 18): `δ` moves 0.78° (refits with `θ` ∓0.3° move it −0.79° and
    /// +1.02°; the linearised `∂δ/∂θ` is 2.1, so 0.64° of sigma); the error is 0.63°, the
    /// sigma 0.42° blind and 0.76° told.
    /// (At 1° the response is lopsided, −3.0° and +0.44°, beyond what one slope states.)
    #[test]
    fn a_wrong_rolling_direction_is_in_the_start_tangents_sigma() {
        let (delta, theta) = (100f64.to_radians(), 112f64.to_radians());
        let (frame, mut g) = scene(delta, theta, 0.4 * R, 0.5 * R);
        let exact = measure(&frame, &g, 0.005, Some(3));
        g.theta += 0.3f64.to_radians();
        let blind = measure(&frame, &g, 0.005, Some(3));
        g.theta_sd = 0.3f64.to_radians();
        let told = measure(&frame, &g, 0.005, Some(3));
        let moved = (blind.delta - exact.delta).to_degrees();
        assert!(moved.abs() > 0.6, "δ moved {moved:.3}° for θ's 0.3°");
        assert!(
            (told.delta - blind.delta).abs() < 1e-12,
            "the sigma alone changes"
        );
        let err = (told.delta - delta).to_degrees();
        let (sd_blind, sd_told) = (blind.delta_sd.to_degrees(), told.delta_sd.to_degrees());
        // θ's part of the sigma is at least 1.5 × θ's, and the error lies within two sigmas.
        let theta_part = (sd_told.powi(2) - sd_blind.powi(2)).sqrt();
        assert!(
            theta_part > 0.45 && err.abs() < 2.0 * sd_told,
            "error {err:.3}°, sigma {sd_blind:.3}° blind, {sd_told:.3}° told"
        );
    }

    #[test]
    fn the_high_pass_takes_out_box_means_over_kept_cells() {
        // A 9×7 grid of cells, one per 2 px, holding 3 + x (a ramp) and, at one cell, a spike.
        let (gw, gh) = (9usize, 7usize);
        let mut px = Pixels {
            kernel: Kernel::new(10.0, 1.0),
            q: Vec::new(),
            v: Vec::new(),
            fixed: Vec::new(),
            cell: Vec::new(),
            grid: (gw, gh),
            origin: (0, 0),
            stride: 2,
            index: Vec::new(),
            highpass: 1,
            evals: Default::default(),
        };
        for cy in 0..gh {
            for cx in 0..gw {
                px.q.push((2.0 * cx as f64, 2.0 * cy as f64));
                px.cell.push((cx, cy));
                px.v.push(if (cx, cy) == (4, 3) { 12.0 } else { 0.0 });
                px.fixed
                    .push([0.0, 0.0, 0.0, 1.0, cx as f64, 0.0, 0.0, 0.0, 0.0]);
            }
        }
        let mut keep = vec![true; gw * gh];
        // A rejected cell next to the spike: left out of every mean.
        keep[3 * gw + 5] = false;
        let m = Mask::new(&px, keep, true);
        let at = |cx: usize, cy: usize| cy * gw + cx;
        // The constant column vanishes everywhere; the ramp wherever the 3×3 box is symmetric.
        assert!(m.fixed.iter().all(|f| f[3] == 0.0));
        assert!(m.fixed[at(2, 2)][4].abs() < 1e-12);
        // At the border the box is cut: cell (0, 0) averages columns 0 and 1.
        assert!((m.fixed[at(0, 0)][4] + 0.5).abs() < 1e-12);
        // The spike's own cell: 12 minus the mean of the eight kept cells of its box.
        assert!((m.v[at(4, 3)] - (12.0 - 12.0 / 8.0)).abs() < 1e-12);
        // A neighbour's value loses the spike's share of its box (9 kept cells there).
        assert!((m.v[at(4, 2)] + 12.0 / 8.0).abs() < 1e-12);
        assert!(m.v[at(0, 0)].abs() < 1e-12);
    }

    #[test]
    fn blotchy_cloth_without_a_plate_is_filtered_out() {
        // The follow-like arc on a cloth with blotches (the clean tier's 3 % texture) and faint
        // noise, measured without a plate, against the same light read unfiltered. Measured
        // (session 18, closed-form edge), |error| filtered / unfiltered per texture seed where
        // the residual correlation called for the filter: 0.79° / 1.30°, 0.38° / 0.23°, 0.13° /
        // 0.38°, 0.70° / 0.64°; seeds 4 and 6 unfiltered at 0.17° and 0.29°. (With the
        // 8-radius edge until then: 1.19° / 1.39°, 0.13° / 0.35°, 0.29° / 0.47°, 0.16° / 0.67°.)
        // At this R = 40 px the gain is modest; on the clean sets at R ≈ 104 px the filter takes
        // the median |error| of 88 readings from 0.40° to 0.13°.
        let (delta, theta) = (100f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.55 * R, 0.6 * R);
        let (mut filtered, mut plain, mut used) = (Vec::new(), Vec::new(), 0);
        for seed in 1..=6u64 {
            let mut bd = Backdrop::plain(520, 420, 0.005);
            bd.texture = 0.03;
            bd.texture_seed = seed;
            let base = bd.base_plate();
            let img = FloatImage::from(render(&frame, &bd, &base, Some(seed)));
            let sig = background::build(&img, background::Cloth::Surface, 600).expect("signal");
            let a = fit(&sig, sig.u, &g).expect("arc fit");
            used += usize::from(a.highpass);
            filtered.push((a.delta - delta).to_degrees().abs());
            // The same light, unfiltered.
            let b = fit_with(&sig, sig.u, &g, false).expect("arc fit");
            assert!(!b.highpass);
            plain.push((b.delta - delta).to_degrees().abs());
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        assert!(used >= 4, "filter used on {used} of 6");
        assert!(
            mean(&filtered) < 0.9 * mean(&plain),
            "filtered {filtered:.3?}, unfiltered {plain:.3?}"
        );
    }

    #[test]
    fn a_turn_hidden_in_the_overlap_is_not_measured() {
        // A well resolved arc (25° over a radius): a short arc turning 10° more or less costs
        // Δχ² ≈ 300, far above the rival threshold.
        let (delta, theta) = (100f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.55 * R, 0.6 * R);
        let a = measure(&frame, &g, 0.05, Some(5));
        assert!(!a.rival, "{a:?}");
        // An 8° turn over legs of 0.35 R, inside the overlap with the incoming streak: the fit's
        // optimum is 1.6° off at a stated 0.56° (measured 2026-11-24), and a rival arc 10° away
        // costs only Δχ² ≈ 14: the start tangent is not measured.
        let (delta, theta) = (117f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.35 * R, 0.35 * R);
        let a = measure(&frame, &g, 0.05, Some(5));
        assert!(a.rival, "{a:?}");
        // The test's limit, for the record: a 20° turn over 0.3 R reads 3.1° off at a stated
        // 0.55°, and its rival costs Δχ² ≈ 30, just above the threshold that the synthetic sets
        // put between wrong and right readings (README).
    }

    #[test]
    fn a_turn_inside_the_balls_own_disc_is_hidden() {
        // A 25° turn over legs of 0.12 R and 0.2 R (a rubber-like slide): the arc that fits is
        // as short, its start tangent inside the cue ball's footprint at P. The fit says so
        // instead of giving no answer, so that the centre-line fit's start tangent (made without
        // these pixels) is not reported in its place.
        let (delta, theta) = (100f64.to_radians(), 125f64.to_radians());
        let (frame, g) = scene(delta, theta, 0.12 * R, 0.2 * R);
        for seed in 1..=3u64 {
            let bd = Backdrop::plain(520, 420, 0.05);
            let (img, plate) = crate::vision::rendered_with_plate(&frame, &bd, Some(seed));
            let sig =
                background::build(&img, background::Cloth::Plate(&plate), 600).expect("signal");
            match fit(&sig, sig.u, &g) {
                Err(ArcMiss::Hidden(l0)) => assert!((0.06..0.2).contains(&l0), "seed {seed}: {l0}"),
                other => panic!("seed {seed}: {other:?}"),
            }
        }
    }
}
