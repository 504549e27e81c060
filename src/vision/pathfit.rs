//! The joint physical model of one shot, fitted to all centre-line samples at once.
//!
//! Parameters: object-ball centre `O = (ox, oy)`, ball radius `R`, direction `α` of the line of
//! centres `x̂ = (cos α, sin α)` in the image, the signed incoming angle `ψs` (incoming direction
//! `u(α + ψs)`), and one path per outgoing ball. The cue ball's centre at impact is
//! `P = O - 2R x̂`; the incoming centre-line passes through `P`; the cue ball's path starts at
//! `P`, the object ball's at `O`. Paths (angles relative to `x̂`, so they *are* the paper's angles
//! up to the mirror sign of `ψs`):
//! - `line`: the ray from the start `S` along `u(α + θ)` (`delta = theta`; 1 parameter);
//! - `parabola+line`: a sliding parabola from `S` with start tangent `u(α + δ)` that ends tangent
//!   to the rolling line of direction `u(α + θ)`. Constant acceleration makes it a quadratic Bézier
//!   `B(τ) = (1-τ)² S + 2τ(1-τ) C + τ² P₁` with control point `C = S + L₀ u(α+δ)` and end
//!   `P₁ = C + L₁ u(α+θ)`, followed by the ray from `P₁` (4 parameters `δ, θ, L₀, L₁`).
//!
//! Residuals: signed perpendicular distance of each centre-line sample to its model curve divided
//! by the sample's sigma, plus priors `(O - O_disc)/σ_O`, `(R - R_disc)/σ_R` from the disc fit.
//! Levenberg–Marquardt with an analytic Jacobian (envelope theorem at the exact nearest point of
//! each curve, see [`PathGeom::distance_grad`]; tested against central differences) and normal
//! equations summed over the columns each residual group touches. Outliers (crossing streaks, highlights): samples beyond
//! `max(4 s, 3)` normalised units (`s` = MAD scale) are dropped and the fit repeated.
//! Model choice per ball by BIC, `Σ_g χ²_g/(s_g² f_g) + k ln(Σ_g n_g/f_g)`, with each residual
//! group's `s_g²` and correlation factor `f_g` (below) from the richest model, so correlated
//! samples are not counted as independent and groups that state their sigmas differently (the
//! incoming blocks of [`super::linefit`], the profile samples) are each on their own scale. The
//! lowest BIC gives the path models; what all combinations share (`O, R, alpha, psi`, each
//! `theta`) is their average weighted by `exp(-ΔBIC/2)`, its covariance widened by their spread
//! (`average_models`), so the angles do not jump where two BICs cross.
//! Covariance `(J'ᵀ J')⁻¹`, where each residual group's rows are divided by `sqrt(s_g² f_g)`:
//! `s_g²` its reduced χ² and `f_g = 1 + 2 Σ ρ_k` the correlation factor of its ordered residuals
//! (neighbouring centre-line samples share cloth texture and noise), so the stated sigma counts
//! independent information only.

use super::streak::Sample;
use crate::physics::wrap;
use nalgebra::{DMatrix, DVector};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathModel {
    Line,
    ParabolaLine,
}

impl PathModel {
    pub fn n_params(self) -> usize {
        match self {
            PathModel::Line => 1,
            PathModel::ParabolaLine => 4,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            PathModel::Line => "line",
            PathModel::ParabolaLine => "parabola+line",
        }
    }
}

#[inline]
fn unit(a: f64) -> (f64, f64) {
    (a.cos(), a.sin())
}

#[inline]
fn cross(u: (f64, f64), v: (f64, f64)) -> f64 {
    u.0 * v.1 - u.1 * v.0
}

/// Root of `g` in `[lo, hi]` given `g(lo) < 0 ≤ g(hi)` and `g` monotone there: Newton from
/// `start` (the secant point when that is not inside the bracket), falling back to bisection whenever a step leaves the shrinking bracket. Stops
/// when the error after the last step, `|g''/2g'| Δτ²` by Newton's quadratic convergence, is
/// below 1e-15 (a Δτ near 1e-8 for a well-conditioned foot).
fn newton_root(
    g: &impl Fn(f64) -> f64,
    gp: &impl Fn(f64) -> (f64, f64),
    mut lo: f64,
    mut hi: f64,
    glo: f64,
    ghi: f64,
    start: f64,
) -> f64 {
    let mut t = if start > lo && start < hi {
        start
    } else {
        lo - glo * (hi - lo) / (ghi - glo)
    };
    if !(t >= lo && t <= hi) {
        t = 0.5 * (lo + hi);
    }
    let mut tried_end = false;
    for _ in 0..100 {
        let gt = g(t);
        if gt == 0.0 {
            return t;
        }
        if gt < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let (d1, d2) = gp(t);
        let step = gt / d1;
        let tn = t - step;
        if !(tn >= lo && tn <= hi) {
            // Overshooting a bracket end the root sits next to (rounding) would make bisection
            // crawl towards it: try that end once, bisect otherwise.
            t = if !tried_end && tn.is_finite() {
                tried_end = true;
                if tn > hi { hi } else { lo }
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo <= 1e-15 {
                return t;
            }
            continue;
        }
        t = tn;
        if (0.5 * d2 / d1).abs() * step * step <= 1e-15 || hi - lo <= 1e-15 {
            return t;
        }
    }
    t
}

/// Derivatives of a signed distance with respect to the path's start point and its own
/// parameters (see [`PathGeom::distance_grad`]).
#[derive(Debug, Clone, Copy)]
struct DistGrad {
    start: (f64, f64),
    path: [f64; 4],
}

/// The Bézier legs `(L₀, L₁)` of a `parabola+line` path's parameters `[δ, θ, L₀, L₁, …]`: the
/// lengths are `|L| + 0.5` px, so the start tangent never loses its meaning.
pub fn legs(p: &[f64]) -> (f64, f64) {
    (p[2].abs() + 0.5, p[3].abs() + 0.5)
}

/// Geometry of one outgoing path in image coordinates.
#[derive(Debug, Clone, Copy)]
pub struct PathGeom {
    pub start: (f64, f64),
    /// Start tangent and rolling direction (unit).
    pub u0: (f64, f64),
    pub u1: (f64, f64),
    /// Bézier control point and the end of the parabola (= start for a line).
    pub ctrl: (f64, f64),
    pub end: (f64, f64),
    pub model: PathModel,
}

impl PathGeom {
    pub fn new(model: PathModel, start: (f64, f64), alpha: f64, p: &[f64]) -> Self {
        match model {
            PathModel::Line => {
                let u = unit(alpha + p[0]);
                Self {
                    start,
                    u0: u,
                    u1: u,
                    ctrl: start,
                    end: start,
                    model,
                }
            }
            PathModel::ParabolaLine => {
                let u0 = unit(alpha + p[0]);
                let u1 = unit(alpha + p[1]);
                let (l0, l1) = legs(p);
                let ctrl = (start.0 + l0 * u0.0, start.1 + l0 * u0.1);
                let end = (ctrl.0 + l1 * u1.0, ctrl.1 + l1 * u1.1);
                Self {
                    start,
                    u0,
                    u1,
                    ctrl,
                    end,
                    model,
                }
            }
        }
    }

    pub fn bezier(&self, t: f64) -> (f64, f64) {
        let (a, b, c) = ((1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t);
        (
            a * self.start.0 + b * self.ctrl.0 + c * self.end.0,
            a * self.start.1 + b * self.ctrl.1 + c * self.end.1,
        )
    }

    fn bezier_d(&self, t: f64) -> (f64, f64) {
        (
            2.0 * (1.0 - t) * (self.ctrl.0 - self.start.0) + 2.0 * t * (self.end.0 - self.ctrl.0),
            2.0 * (1.0 - t) * (self.ctrl.1 - self.start.1) + 2.0 * t * (self.end.1 - self.ctrl.1),
        )
    }

    /// Signed distance (left of the direction of motion positive) of `q` from the path.
    pub fn signed_distance(&self, q: (f64, f64)) -> f64 {
        self.distance_grad(q).0
    }

    /// Parameter `τ ∈ [0, 1]` of the point of the Bézier nearest to `q`: the global minimum of
    /// the quartic `|B(τ) - q|²`. With `A = C - S`, `K = P₁ - 2C + S`, `w = S - q`, its
    /// stationarity condition `(B - q)·B'/2 = 0` is the cubic
    /// `g(τ) = |K|² τ³ + 3 A·K τ² + (2|A|² + w·K) τ + w·A`. The real roots of the quadratic `g'`
    /// cut `[0, 1]` into pieces on which `g` is monotone; a minimum is an endpoint where `g`
    /// points inwards or the single root of a piece where `g` rises through zero, found by
    /// bracketed Newton (bisection when a step leaves the bracket) to `|Δτ| ≲ 1e-15`.
    fn bezier_foot(&self, q: (f64, f64)) -> f64 {
        let a = (self.ctrl.0 - self.start.0, self.ctrl.1 - self.start.1);
        let k = (
            self.end.0 - 2.0 * self.ctrl.0 + self.start.0,
            self.end.1 - 2.0 * self.ctrl.1 + self.start.1,
        );
        let w = (self.start.0 - q.0, self.start.1 - q.1);
        let c3 = k.0 * k.0 + k.1 * k.1;
        let c2 = 3.0 * (a.0 * k.0 + a.1 * k.1);
        let c1 = 2.0 * (a.0 * a.0 + a.1 * a.1) + w.0 * k.0 + w.1 * k.1;
        let c0 = w.0 * a.0 + w.1 * a.1;
        let g = |t: f64| ((c3 * t + c2) * t + c1) * t + c0;
        // g' and g''.
        let gp = |t: f64| ((3.0 * c3 * t + 2.0 * c2) * t + c1, 6.0 * c3 * t + 2.0 * c2);
        // Cut points: 0, the roots of g' = 3 c3 τ² + 2 c2 τ + c1 inside (0, 1), 1. The stable
        // form of the quadratic formula keeps both roots accurate when the Bézier is nearly
        // straight (c3 → 0).
        let mut cuts = [0.0, 1.0, 1.0, 1.0];
        let mut n_cuts = 1;
        let disc = c2 * c2 - 3.0 * c3 * c1;
        if disc > 0.0 {
            let qq = -(c2 + disc.sqrt().copysign(c2));
            let (mut r1, mut r2) = (qq / (3.0 * c3), c1 / qq);
            if r1 > r2 {
                std::mem::swap(&mut r1, &mut r2);
            }
            for r in [r1, r2] {
                if r > 0.0 && r < 1.0 {
                    cuts[n_cuts] = r;
                    n_cuts += 1;
                }
            }
        }
        cuts[n_cuts] = 1.0;
        let dist2 = |t: f64| {
            let b = self.bezier(t);
            (b.0 - q.0).powi(2) + (b.1 - q.1).powi(2)
        };
        let mut best = (f64::NAN, f64::INFINITY);
        let mut consider = |t: f64| {
            let d2 = dist2(t);
            if d2 < best.1 {
                best = (t, d2);
            }
        };
        let g0 = g(0.0);
        let g1 = g(1.0);
        // Newton starts where a straight Bézier with the same control lengths would put the
        // foot: the chord fraction σ of q solves 2 a₀ τ + (a₁ - a₀) τ² = σ (a₀ + a₁ = 1).
        let start = {
            let dch = (
                a.0 + self.end.0 - self.ctrl.0,
                a.1 + self.end.1 - self.ctrl.1,
            );
            let dd = dch.0 * dch.0 + dch.1 * dch.1;
            let a0 = (a.0 * dch.0 + a.1 * dch.1) / dd;
            let sigma = -(w.0 * dch.0 + w.1 * dch.1) / dd;
            let disc = a0 * a0 + (1.0 - 2.0 * a0) * sigma;
            if a0 > 0.0 && disc >= 0.0 {
                sigma / (a0 + disc.sqrt())
            } else {
                f64::NAN
            }
        };
        if n_cuts == 1 {
            // g is monotone on [0, 1] (the common case). Rising: one minimum; falling: one
            // maximum inside, so the minimum is the nearer end.
            match (g0 >= 0.0, g1 <= 0.0) {
                (true, false) => return 0.0,
                (false, true) => return 1.0,
                (false, false) => return newton_root(&g, &gp, 0.0, 1.0, g0, g1, start),
                (true, true) => {}
            }
        }
        if g0 >= 0.0 {
            consider(0.0);
        }
        if g1 <= 0.0 {
            consider(1.0);
        }
        let mut ga = g0;
        for i in 0..n_cuts {
            let (lo, hi) = (cuts[i], cuts[i + 1]);
            let gb = if i + 1 == n_cuts { g1 } else { g(hi) };
            if ga < 0.0 && gb >= 0.0 {
                consider(newton_root(&g, &gp, lo, hi, ga, gb, start));
            }
            ga = gb;
        }
        if best.0.is_nan() {
            // Unreachable for a finite quartic (it has a minimum on [0, 1]); kept finite anyway.
            return if g0 >= 0.0 { 0.0 } else { 1.0 };
        }
        best.0
    }

    /// Signed distance of `q` from the path and its derivatives with respect to the path's start
    /// point and to its own parameters: `[theta]` for a line, `[delta, theta, l0, l1]` for
    /// parabola+line, with `l0, l1` the effective lengths `|L| + 0.5`.
    ///
    /// The distance is `n̂·(q - F)` with `F` the foot point on the curve and `n̂` its left normal.
    /// At an interior foot `q - F ∥ n̂`, so moving the foot along the curve or turning the tangent
    /// changes nothing to first order (envelope theorem): `∂d/∂p = -n̂·∂F/∂p` with the curve
    /// parameter held fixed. Where the foot is pinned (the Bézier's ends, a ray's start) the
    /// tangent's turn adds `-(T̂·(q - F)) ∂φ_T/∂p`. A point behind a line's start gets
    /// `±|q - S|`, whose derivative is `∓ (q - S)/|q - S|·∂S/∂p`. The curve point is
    /// `B(τ) = S + b₀ l₀ u₀ + b₁ l₁ u₁` with `b₀ = 2τ - τ²`, `b₁ = τ²` (`τ = 1` plus `σ u₁` on
    /// the ray), so `∂B/∂δ = b₀ l₀ n̂₀`, `∂B/∂θ = b₁ l₁ n̂₁`, `∂B/∂l₀ = b₀ u₀`, `∂B/∂l₁ = b₁ u₁`.
    fn distance_grad(&self, q: (f64, f64)) -> (f64, DistGrad) {
        let perp = |v: (f64, f64)| (-v.1, v.0);
        let dot = |u: (f64, f64), v: (f64, f64)| u.0 * v.0 + u.1 * v.1;
        if self.model == PathModel::Line {
            // A ray, not a line: a point behind the start is as far as the start itself (this
            // also keeps theta from flipping by 180°).
            let w = (q.0 - self.start.0, q.1 - self.start.1);
            let c = cross(self.u1, w);
            let along = dot(w, self.u1);
            if along >= 0.0 {
                let n = perp(self.u1);
                return (
                    c,
                    DistGrad {
                        start: (-n.0, -n.1),
                        path: [-along, 0.0, 0.0, 0.0],
                    },
                );
            }
            let len = w.0.hypot(w.1);
            let d = len.copysign(c);
            let f = if len > 0.0 { d / (len * len) } else { 0.0 };
            return (
                d,
                DistGrad {
                    start: (-f * w.0, -f * w.1),
                    path: [0.0; 4],
                },
            );
        }
        // l₀ n̂₀ and l₁ n̂₁ straight from the control polygon (no lengths needed).
        let l0n0 = perp((self.ctrl.0 - self.start.0, self.ctrl.1 - self.start.1));
        let l1n1 = perp((self.end.0 - self.ctrl.0, self.end.1 - self.ctrl.1));
        let rel = (q.0 - self.end.0, q.1 - self.end.1);
        let s = dot(rel, self.u1);
        let ray = |s: f64| {
            let n1 = perp(self.u1);
            (
                cross(self.u1, rel),
                DistGrad {
                    start: (-n1.0, -n1.1),
                    path: [-dot(n1, l0n0), -s - dot(n1, l1n1), -dot(n1, self.u0), 0.0],
                },
            )
        };
        let d_ray = if s >= 0.0 {
            cross(self.u1, rel)
        } else {
            f64::INFINITY
        };
        // With u₀·u₁ ≥ 0 the whole Bézier lies at or behind its end along u₁, so its Euclidean
        // distance from a point `s` ahead of the end is at least `s`; when `q` is also ahead of
        // the start along u₀ the Bézier distance is Euclidean (the foot is not pinned at τ = 0,
        // where only the part across the start tangent counts): the ray wins without a search.
        if s > d_ray.abs()
            && dot(self.u0, self.u1) >= 0.0
            && dot((q.0 - self.start.0, q.1 - self.start.1), self.u0) > 0.0
        {
            return ray(s);
        }
        let t = self.bezier_foot(q);
        let b = self.bezier(t);
        let d = self.bezier_d(t);
        let l = (d.0 * d.0 + d.1 * d.1).sqrt();
        let tg = if l < 1e-12 {
            self.u0
        } else {
            (d.0 / l, d.1 / l)
        };
        let w = (q.0 - b.0, q.1 - b.1);
        let d_bez = cross(tg, w);
        if d_ray.abs() < d_bez.abs() {
            return ray(s);
        }
        let n = perp(tg);
        let (b0, b1) = (t * (2.0 - t), t * t);
        let mut path = [
            -b0 * dot(n, l0n0),
            -b1 * dot(n, l1n1),
            -b0 * dot(n, self.u0),
            -b1 * dot(n, self.u1),
        ];
        // Pinned foot (bezier_foot returns the ends exactly): the end tangent turns with delta
        // (τ = 0) or theta (τ = 1).
        if t <= 0.0 {
            path[0] -= dot(tg, w);
        } else if t >= 1.0 {
            path[1] -= dot(tg, w);
        }
        (
            d_bez,
            DistGrad {
                start: (-n.0, -n.1),
                path,
            },
        )
    }

    /// Points along the fitted path up to arc length `len` (for drawing).
    pub fn polyline(&self, len: f64) -> Vec<(f64, f64)> {
        let mut pts = Vec::new();
        let mut used = 0.0;
        if self.model == PathModel::ParabolaLine {
            let mut prev = self.start;
            for i in 0..=40 {
                let b = self.bezier(i as f64 / 40.0);
                used += (b.0 - prev.0).hypot(b.1 - prev.1);
                pts.push(b);
                prev = b;
            }
        } else {
            pts.push(self.start);
        }
        let rest = (len - used).max(0.0);
        pts.push((self.end.0 + rest * self.u1.0, self.end.1 + rest * self.u1.1));
        pts
    }
}

/// Which ball a group of samples belongs to.
#[derive(Debug, Clone)]
pub struct Problem {
    pub o_meas: (f64, f64),
    pub sigma_o: f64,
    pub r_meas: f64,
    pub sigma_r: f64,
    pub incoming: Vec<Sample>,
    /// Cue ball after impact (`None` when it stops at the impact).
    pub out1: Option<Vec<Sample>>,
    pub out2: Vec<Sample>,
    /// `out2` is the object ball's rest centre (one point, with its disc fit's sigma), not
    /// centre-line samples: it crept to a stop and left no streak (`vision::disc::Companion`).
    /// Its path is then a line from `O`, and the point's sigma is not rescaled by its scatter.
    pub object_rest: bool,
}

/// Path models of (cue ball, object ball); the cue ball's is `None` when it stops.
type Combo = (Option<PathModel>, PathModel);

/// Parameter vector layout: `[ox, oy, R, α, ψs, ball1…, ball2…]`.
#[derive(Debug, Clone)]
pub struct JointFit {
    pub params: Vec<f64>,
    pub cov: DMatrix<f64>,
    pub m1: Option<PathModel>,
    pub m2: PathModel,
    /// Inlier flags per group (incoming, ball 1, ball 2).
    pub inliers: [Vec<bool>; 3],
    /// Reduced χ² and correlation factor per group.
    pub s2: [f64; 3],
    pub corr: [f64; 3],
    pub bic: f64,
    /// Profile 1-sigma of each ball's start tangent `delta` (cue ball, object ball) where its
    /// chosen model is a parabola ([`profile_sd`]); `None` elsewhere.
    pub delta_profile: [Option<f64>; 2],
    /// The linearised 1-sigma of a parabola's `delta` (before the profile widened it).
    pub delta_lin: [Option<f64>; 2],
}

impl JointFit {
    pub fn o(&self) -> (f64, f64) {
        (self.params[0], self.params[1])
    }
    pub fn r(&self) -> f64 {
        self.params[2]
    }
    pub fn alpha(&self) -> f64 {
        self.params[3]
    }
    pub fn psi_s(&self) -> f64 {
        self.params[4]
    }
    pub fn impact(&self) -> (f64, f64) {
        impact_point(&self.params)
    }
    pub fn ball1_offset(&self) -> usize {
        5
    }
    pub fn ball2_offset(&self) -> usize {
        object_offset(self.m1)
    }
    pub fn geom1(&self) -> Option<PathGeom> {
        self.m1
            .map(|m| PathGeom::new(m, self.impact(), self.alpha(), &self.params[5..]))
    }
    pub fn geom2(&self) -> PathGeom {
        PathGeom::new(
            self.m2,
            self.o(),
            self.alpha(),
            &self.params[self.ball2_offset()..],
        )
    }
    /// Indices of (delta, theta) of a ball in the parameter vector.
    pub fn angle_indices(&self, ball: usize) -> Option<(usize, usize)> {
        let (m, off) = if ball == 1 {
            (self.m1?, self.ball1_offset())
        } else {
            (self.m2, self.ball2_offset())
        };
        Some(angle_slots(m, off))
    }
    /// Standard error of ball `ball`'s (1 or 2) start tangent: for a parabola its profile-widened
    /// variance. A straight path does not measure its start tangent (it states `delta = theta`,
    /// and a slide short enough to hide under a disc or in the other streak's light turns the
    /// start unseen: the demo's rubber shot_019, 0.5° at a profile sigma of 0.05°): infinite.
    pub fn delta_sd(&self, ball: usize) -> f64 {
        match self.angle_indices(ball) {
            Some((id, it)) if id != it => self.sd(id),
            _ => f64::INFINITY,
        }
    }

    /// Standard error of parameter `i`; infinite when the fit does not determine it (a
    /// non-positive variance from an ill-conditioned normal matrix).
    pub fn sd(&self, i: usize) -> f64 {
        let v = self.cov[(i, i)];
        if v > 0.0 && v.is_finite() {
            v.sqrt()
        } else {
            f64::INFINITY
        }
    }
}

/// Index of the object ball's first path parameter, after the shared five and the cue ball's
/// path of model `m1` (none when it stops).
fn object_offset(m1: Option<PathModel>) -> usize {
    5 + m1.map_or(0, |m| m.n_params())
}

/// Indices of (delta, theta) of a ball's path of model `m` whose parameters start at `off`: a
/// straight path's one direction is both.
fn angle_slots(m: PathModel, off: usize) -> (usize, usize) {
    match m {
        PathModel::Line => (off, off),
        PathModel::ParabolaLine => (off, off + 1),
    }
}

fn impact_point(p: &[f64]) -> (f64, f64) {
    let x = unit(p[3]);
    (p[0] - 2.0 * p[2] * x.0, p[1] - 2.0 * p[2] * x.1)
}

/// Residual groups: 0 priors, 1 incoming, 2 ball 1, 3 ball 2.
struct Model<'a> {
    pb: &'a Problem,
    m1: Option<PathModel>,
    m2: PathModel,
    use_: [Vec<bool>; 3],
}

/// Residuals stacked by group, the group bounds (`r[bounds[g]..bounds[g + 1]]`) and, when asked
/// for, their Jacobian.
struct Eval {
    r: Vec<f64>,
    bounds: [usize; 5],
    j: Option<Jac>,
}

impl Eval {
    fn cost(&self) -> f64 {
        self.r.iter().map(|v| v * v).sum()
    }
}

/// Jacobian stored by rows: a row touches few columns (the shared five and its own ball's), and
/// the normal equations are summed row by row over those columns only.
struct Jac {
    k: usize,
    data: Vec<f64>,
}

impl Jac {
    fn zeros(n: usize, k: usize) -> Self {
        Self {
            k,
            data: vec![0.0; n * k],
        }
    }
    fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.k..(i + 1) * self.k]
    }
    #[cfg(test)]
    fn to_dmatrix(&self) -> DMatrix<f64> {
        DMatrix::from_row_slice(self.data.len() / self.k, self.k, &self.data)
    }
}

impl std::ops::Index<(usize, usize)> for Jac {
    type Output = f64;
    fn index(&self, (i, c): (usize, usize)) -> &f64 {
        &self.data[i * self.k + c]
    }
}

impl std::ops::IndexMut<(usize, usize)> for Jac {
    fn index_mut(&mut self, (i, c): (usize, usize)) -> &mut f64 {
        &mut self.data[i * self.k + c]
    }
}

/// Columns (ascending) that residual group `g` can depend on: priors all, incoming the shared
/// five, the cue ball `O, R, α` and its own, the object ball `O, α` and its own.
fn group_cols(m1: Option<PathModel>, m2: PathModel) -> [Vec<usize>; 4] {
    let off2 = object_offset(m1);
    let k = off2 + m2.n_params();
    [
        (0..k).collect(),
        (0..5).collect(),
        (0..4).chain(5..off2).collect(),
        [0, 1, 3].into_iter().chain(off2..k).collect(),
    ]
}

/// `Σ_g w_g J_gᵀ J_g` and `Σ_g w_g J_gᵀ r_g` over the residual groups.
fn normal_equations(
    j: &Jac,
    r: &[f64],
    bounds: &[usize; 5],
    cols: &[Vec<usize>; 4],
    w: [f64; 4],
) -> (DMatrix<f64>, DVector<f64>) {
    const MAX: usize = 13; // 5 shared + 4 + 4 parameters
    let k = j.k;
    assert!(k <= MAX, "at most {MAX} parameters");
    let mut a = vec![0.0; k * k];
    let mut g = vec![0.0; k];
    for grp in 0..4 {
        let cs = &cols[grp];
        let m = cs.len();
        // Dense m×m sums over the group's own columns, scattered once at the end.
        let mut acc = [0.0f64; MAX * MAX];
        let mut gacc = [0.0f64; MAX];
        let mut v = [0.0f64; MAX];
        let rows = bounds[grp]..bounds[grp + 1];
        for (i, &ri) in rows.clone().zip(&r[rows]) {
            let row = j.row(i);
            for (t, &c) in cs.iter().enumerate() {
                v[t] = row[c];
            }
            for p in 0..m {
                let vp = v[p];
                gacc[p] += vp * ri;
                for q in p..m {
                    acc[p * MAX + q] += vp * v[q];
                }
            }
        }
        for (p, &cp) in cs.iter().enumerate() {
            g[cp] += w[grp] * gacc[p];
            for (q, &cq) in cs.iter().enumerate().skip(p) {
                a[cp * k + cq] += w[grp] * acc[p * MAX + q];
            }
        }
    }
    // Mirror the upper triangle.
    for ca in 0..k {
        for cb in 0..ca {
            a[ca * k + cb] = a[cb * k + ca];
        }
    }
    (DMatrix::from_row_slice(k, k, &a), DVector::from_vec(g))
}

impl Model<'_> {
    fn n_params(&self) -> usize {
        self.off2() + self.m2.n_params()
    }
    fn off2(&self) -> usize {
        object_offset(self.m1)
    }
    fn ball1(&self) -> Option<(PathModel, &[Sample])> {
        Some((self.m1?, self.pb.out1.as_deref()?))
    }
    /// Residuals at `p`, and with `want_jac` their analytic Jacobian (each signed distance
    /// differentiated by [`PathGeom::distance_grad`], chained through `S = P = O - 2R x̂` for
    /// the cue ball and `S = O` for the object ball).
    fn eval(&self, p: &[f64], want_jac: bool) -> Eval {
        let used = |u: &[bool]| u.iter().filter(|k| **k).count();
        let walls = usize::from(self.m1 == Some(PathModel::ParabolaLine))
            + usize::from(self.m2 == PathModel::ParabolaLine);
        let n = 3
            + walls
            + used(&self.use_[0])
            + self.ball1().map_or(0, |_| used(&self.use_[1]))
            + used(&self.use_[2]);
        let mut r = Vec::with_capacity(n);
        let mut jac = want_jac.then(|| Jac::zeros(n, p.len()));
        let mut bounds = [0usize; 5];
        let pb = self.pb;
        // Group 0: priors from the disc fit.
        r.push((p[0] - pb.o_meas.0) / pb.sigma_o);
        r.push((p[1] - pb.o_meas.1) / pb.sigma_o);
        r.push((p[2] - pb.r_meas) / pb.sigma_r);
        if let Some(j) = &mut jac {
            j[(0, 0)] = 1.0 / pb.sigma_o;
            j[(1, 1)] = 1.0 / pb.sigma_o;
            j[(2, 2)] = 1.0 / pb.sigma_r;
        }
        // Sliding arcs are short (cloth friction 0.15–0.55: one to three diameters); a soft
        // wall at L0 + L1 = 12 R keeps a parabola from absorbing the whole path.
        let big_r = p[2];
        for (present, off) in [
            (self.m1 == Some(PathModel::ParabolaLine), 5),
            (self.m2 == PathModel::ParabolaLine, self.off2()),
        ] {
            if !present {
                continue;
            }
            let l = p[off + 2].abs() + p[off + 3].abs();
            let v = ((l - 12.0 * big_r).max(0.0) / (0.1 * big_r)).min(1e6);
            let row = r.len();
            r.push(v);
            if let Some(j) = &mut jac
                && v > 0.0
                && v < 1e6
            {
                // v = 10 l / R - 120 on the slope.
                let dl = 10.0 / big_r;
                j[(row, off + 2)] = dl * p[off + 2].signum();
                j[(row, off + 3)] = dl * p[off + 3].signum();
                j[(row, 2)] = -10.0 * l / (big_r * big_r);
            }
        }
        bounds[1] = r.len();
        // Group 1: incoming line through P along u(α + ψs).
        let pi = impact_point(p);
        let xh = unit(p[3]);
        let nx = (-xh.1, xh.0);
        let u = unit(p[3] + p[4]);
        let nu = (-u.1, u.0);
        for (s, _) in pb.incoming.iter().zip(&self.use_[0]).filter(|(_, k)| **k) {
            let w = (s.x - pi.0, s.y - pi.1);
            let row = r.len();
            r.push(cross(u, w) / s.sigma);
            if let Some(j) = &mut jac {
                let inv = 1.0 / s.sigma;
                let along = u.0 * w.0 + u.1 * w.1;
                j[(row, 0)] = -nu.0 * inv;
                j[(row, 1)] = -nu.1 * inv;
                j[(row, 2)] = 2.0 * (nu.0 * xh.0 + nu.1 * xh.1) * inv;
                j[(row, 3)] = (-along + 2.0 * big_r * (nu.0 * nx.0 + nu.1 * nx.1)) * inv;
                j[(row, 4)] = -along * inv;
            }
        }
        bounds[2] = r.len();
        // Groups 2 and 3: the outgoing paths.
        if let Some((m, samples)) = self.ball1() {
            let geom = PathGeom::new(m, pi, p[3], &p[5..]);
            self.path_rows(&geom, 5, true, samples, &self.use_[1], p, &mut r, &mut jac);
        }
        bounds[3] = r.len();
        let off2 = self.off2();
        let geom = PathGeom::new(self.m2, (p[0], p[1]), p[3], &p[off2..]);
        self.path_rows(
            &geom,
            off2,
            false,
            &pb.out2,
            &self.use_[2],
            p,
            &mut r,
            &mut jac,
        );
        bounds[4] = r.len();
        Eval { r, bounds, j: jac }
    }

    /// Residual rows of one outgoing path (parameters from `off`; `from_impact`: its start is
    /// `P`, else `O`).
    #[allow(clippy::too_many_arguments)]
    fn path_rows(
        &self,
        geom: &PathGeom,
        off: usize,
        from_impact: bool,
        samples: &[Sample],
        use_: &[bool],
        p: &[f64],
        r: &mut Vec<f64>,
        jac: &mut Option<Jac>,
    ) {
        let xh = unit(p[3]);
        let nx = (-xh.1, xh.0);
        for (s, _) in samples.iter().zip(use_).filter(|(_, k)| **k) {
            let (d, gr) = geom.distance_grad((s.x, s.y));
            let row = r.len();
            r.push(d / s.sigma);
            let Some(j) = jac else { continue };
            let inv = 1.0 / s.sigma;
            let ds = gr.start;
            // α turns both directions (u(α + δ), u(α + θ)) as well as moving `P`.
            let mut da = match geom.model {
                PathModel::Line => gr.path[0],
                PathModel::ParabolaLine => gr.path[0] + gr.path[1],
            };
            j[(row, 0)] = ds.0 * inv;
            j[(row, 1)] = ds.1 * inv;
            if from_impact {
                j[(row, 2)] = -2.0 * (ds.0 * xh.0 + ds.1 * xh.1) * inv;
                da -= 2.0 * p[2] * (ds.0 * nx.0 + ds.1 * nx.1);
            }
            j[(row, 3)] = da * inv;
            match geom.model {
                PathModel::Line => j[(row, off)] = gr.path[0] * inv,
                PathModel::ParabolaLine => {
                    j[(row, off)] = gr.path[0] * inv;
                    j[(row, off + 1)] = gr.path[1] * inv;
                    // Lengths enter as |L| + 0.5.
                    j[(row, off + 2)] = gr.path[2] * p[off + 2].signum() * inv;
                    j[(row, off + 3)] = gr.path[3] * p[off + 3].signum() * inv;
                }
            }
        }
    }

    /// Central-difference Jacobian: the oracle the analytic one is tested against.
    #[cfg(test)]
    fn jacobian_numeric(&self, p: &[f64]) -> DMatrix<f64> {
        let n = self.eval(p, false).r.len();
        let mut j = DMatrix::zeros(n, p.len());
        let mut pp = p.to_vec();
        for c in 0..p.len() {
            let h = if c <= 2 || (c >= 5 && self.is_length(c)) {
                1e-4
            } else {
                1e-6
            };
            pp[c] = p[c] + h;
            let a = self.eval(&pp, false).r;
            pp[c] = p[c] - h;
            let b = self.eval(&pp, false).r;
            pp[c] = p[c];
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                j[(i, c)] = (x - y) / (2.0 * h);
            }
        }
        j
    }
    #[cfg(test)]
    fn is_length(&self, c: usize) -> bool {
        let check = |m: PathModel, off: usize| {
            m == PathModel::ParabolaLine && (c == off + 2 || c == off + 3)
        };
        self.m1.is_some_and(|m| check(m, 5)) || check(self.m2, self.off2())
    }
}

/// Levenberg–Marquardt from `x0`; returns the solution and its evaluation (with Jacobian).
fn lm(model: &Model, x0: &[f64], s: &FitSettings) -> (Vec<f64>, Eval) {
    lm_pinned(model, x0, s, None)
}

/// [`lm`] with parameter `pin` (if any) held at its value in `x0`.
fn lm_pinned(model: &Model, x0: &[f64], s: &FitSettings, pin: Option<usize>) -> (Vec<f64>, Eval) {
    let mut x = x0.to_vec();
    let mut ev = model.eval(&x, true);
    let mut cost = ev.cost();
    let mut lambda = 1e-3;
    let cols = group_cols(model.m1, model.m2);
    for _ in 0..s.lm_max_iter {
        let (a, g) = {
            let j = ev.j.as_ref().expect("evaluated with the Jacobian");
            let (mut a, mut g) = normal_equations(j, &ev.r, &ev.bounds, &cols, [1.0; 4]);
            if let Some(p) = pin {
                for i in 0..a.nrows() {
                    a[(p, i)] = 0.0;
                    a[(i, p)] = 0.0;
                }
                a[(p, p)] = 1.0;
                g[p] = 0.0;
            }
            (a, g)
        };
        let mut improved = false;
        for _ in 0..12 {
            let mut m = a.clone();
            for i in 0..m.nrows() {
                m[(i, i)] += lambda * a[(i, i)].max(1e-9);
            }
            let Some(step) = m.cholesky().map(|c| c.solve(&(-&g))) else {
                lambda *= 10.0;
                continue;
            };
            let xn: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            // The Jacobian comes with the trial: most trials are accepted and need it next.
            let en = model.eval(&xn, true);
            let cn = en.cost();
            if cn.is_finite() && cn <= cost {
                let rel = (cost - cn) / cost.max(1e-300);
                x = xn;
                ev = en;
                cost = cn;
                lambda = (lambda / 3.0).max(1e-12);
                improved = true;
                if rel < s.lm_rel_tol {
                    return (x, ev);
                }
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    (x, ev)
}

/// Correlation factor of an ordered residual sequence: the larger of `1 + 2 Σ ρ_k` (sum stops at
/// the first non-positive `ρ_k`) and the batch-means estimate.
pub fn correlation_factor(r: &[f64]) -> f64 {
    let n = r.len();
    if n < 8 {
        return 1.0;
    }
    let m = r.iter().sum::<f64>() / n as f64;
    let var: f64 = r.iter().map(|v| (v - m).powi(2)).sum::<f64>();
    if var <= 0.0 {
        return 1.0;
    }
    // Batch means over eight blocks catch correlation longer than the first lags show (cloth
    // texture bends a centre-line over several radii): f ≥ L var(block means) / var(r).
    let l = (n / 8).max(4);
    let means: Vec<f64> = r
        .chunks_exact(l)
        .map(|c| c.iter().sum::<f64>() / l as f64 - m)
        .collect();
    let f_batch = if means.len() >= 3 {
        l as f64 * means.iter().map(|v| v * v).sum::<f64>() / means.len() as f64 / (var / n as f64)
    } else {
        1.0
    };
    let mut f = 1.0;
    for k in 1..(n / 4).min(40) {
        let c: f64 = (0..n - k).map(|i| (r[i] - m) * (r[i + k] - m)).sum::<f64>() / var;
        if c <= 0.0 {
            break;
        }
        f += 2.0 * c;
    }
    f.max(f_batch)
}

fn model_fit<'a>(
    pb: &'a Problem,
    m1: Option<PathModel>,
    m2: PathModel,
    x0: &[f64],
    use_: [Vec<bool>; 3],
    s: &FitSettings,
) -> (Vec<f64>, Eval, Model<'a>) {
    let model = Model { pb, m1, m2, use_ };
    let (x, ev) = lm(&model, x0, s);
    (x, ev, model)
}

/// Converts a parameter vector between path models (keeps shared angles).
fn convert(
    x: &[f64],
    from: (Option<PathModel>, PathModel),
    to: (Option<PathModel>, PathModel),
    r: f64,
) -> Vec<f64> {
    let mut out = x[..5].to_vec();
    let mut off = 5;
    let push_ball = |m_from: Option<PathModel>,
                     m_to: Option<PathModel>,
                     off: &mut usize,
                     out: &mut Vec<f64>| {
        let Some(mf) = m_from else { return };
        let p = &x[*off..*off + mf.n_params()];
        *off += mf.n_params();
        let (d, t, l0, l1) = match mf {
            PathModel::Line => (p[0], p[0], r, r),
            PathModel::ParabolaLine => (p[0], p[1], p[2], p[3]),
        };
        match m_to {
            Some(PathModel::Line) => out.push(t),
            Some(PathModel::ParabolaLine) => out.extend_from_slice(&[d, t, l0, l1]),
            None => {}
        }
    };
    push_ball(from.0, to.0, &mut off, &mut out);
    push_ball(Some(from.1), Some(to.1), &mut off, &mut out);
    out
}

/// `(J'ᵀ J')⁻¹`, except where the fit does not determine a parameter: one that no residual
/// depends on (an all-zero Jacobian column, e.g. the parabola's length `L1` when every sample
/// lies on the rolling line), or one with a part along a direction in which the normal matrix
/// is singular to working precision, gets infinite variance and no covariance; the rest is
/// the inverse on the determined directions.
///
/// The matrix is scaled to a unit diagonal first (the parameters span pixels of position,
/// radians and lengths) and inverted through its eigen-decomposition: a plain inverse of a
/// numerically singular matrix (an arc's legs trading against each other) gave well-determined
/// parameters such as `psi` variances of either sign, which were reported as infinite.
fn covariance(a: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let k = a.nrows();
    let keep: Vec<usize> = (0..k).filter(|&i| a[(i, i)] > 0.0).collect();
    let d: Vec<f64> = keep.iter().map(|&i| a[(i, i)].sqrt()).collect();
    let n = keep.len();
    let sub = DMatrix::from_fn(n, n, |r, c| {
        0.5 * (a[(keep[r], keep[c])] + a[(keep[c], keep[r])]) / (d[r] * d[c])
    });
    if sub.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let eig = nalgebra::SymmetricEigen::new(sub);
    let (v, lambda) = (&eig.eigenvectors, &eig.eigenvalues);
    let null: Vec<usize> = (0..n)
        .filter(|&j| lambda[j] < SINGULAR_EIGENVALUE)
        .collect();
    let undetermined: Vec<bool> = (0..n)
        .map(|r| null.iter().map(|&j| v[(r, j)].powi(2)).sum::<f64>() > NULL_WEIGHT)
        .collect();
    let mut cov = DMatrix::zeros(k, k);
    for i in 0..k {
        cov[(i, i)] = f64::INFINITY;
    }
    for r in (0..n).filter(|&r| !undetermined[r]) {
        for c in (0..n).filter(|&c| !undetermined[c]) {
            let s: f64 = (0..n)
                .filter(|&j| lambda[j] >= SINGULAR_EIGENVALUE)
                .map(|j| v[(r, j)] * v[(c, j)] / lambda[j])
                .sum();
            cov[(keep[r], keep[c])] = s / (d[r] * d[c]);
        }
    }
    Some(cov)
}

/// Eigenvalue of the unit-diagonal normal matrix below which its direction is undetermined
/// (a correlation of 1 − 10⁻¹⁰ between two parameters), and the weight on such directions
/// above which a parameter is.
const SINGULAR_EIGENVALUE: f64 = 1e-10;
const NULL_WEIGHT: f64 = 1e-6;

/// Farthest the profile of a start tangent is walked (radians): beyond it the angle counts as
/// undetermined.
const PROFILE_SPAN: f64 = 0.5;

/// 1-sigma of parameter `idx` from the profile of the group-weighted cost (the cost whose
/// curvature is the covariance): walked out on each side from `x` in doubling steps (first
/// `sd_lin`) with the parameter pinned and the rest refitted, until it rises by 1; the crossing
/// is interpolated in `sqrt(Δ)`; the larger side counts. Why: a sliding parabola whose curved
/// part lies where no centre-line sample is (inside the waiting disc's keep-out, under the
/// incoming streak) leaves a valley of arcs from P or O to the rolling line, short and sharp to
/// long and shallow; the curvature at the optimum sees only its floor's local width (rubber
/// balls: `delta2` 0.4–3.3° off with stated sigmas of 0.05–0.5°).
fn profile_sd(
    model: &Model,
    x: &[f64],
    idx: usize,
    sd_lin: f64,
    w: [f64; 4],
    s: &FitSettings,
) -> f64 {
    let wcost = |ev: &Eval| -> f64 {
        (0..4)
            .map(|g| {
                w[g] * ev.r[ev.bounds[g]..ev.bounds[g + 1]]
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
            })
            .sum()
    };
    let c0 = wcost(&model.eval(x, false));
    // Each refit starts on the valley floor next to the last one: a few iterations suffice.
    let pinned = FitSettings {
        lm_max_iter: s.lm_max_iter.min(10),
        ..*s
    };
    let mut worst: f64 = 0.0;
    for dir in [-1.0, 1.0] {
        let mut xs = x.to_vec();
        let (mut prev_off, mut prev_root) = (0.0, 0.0);
        // Steps below 0.1° would only refine an interval that ends far below the 10° at which an
        // angle counts as unresolved; each costs a refit.
        let mut step = sd_lin.max(0.1f64.to_radians());
        let mut side = PROFILE_SPAN;
        loop {
            let off = (prev_off + step).min(PROFILE_SPAN);
            // Start on the valley floor: keep the rolling line where it is (the arc's lateral
            // offset L0 sin(δ - θ) and its reach along θ, L0 cos(δ - θ) + L1).
            let (d_old, th, l0, l1) = (xs[idx], xs[idx + 1], xs[idx + 2].abs(), xs[idx + 3].abs());
            let d_new = x[idx] + dir * off;
            let (sin_old, sin_new) = ((d_old - th).sin(), (d_new - th).sin());
            if sin_new.abs() > 1e-6 && sin_old * sin_new > 0.0 {
                let l0n = (l0 * sin_old / sin_new).clamp(0.05 * l0, 20.0 * l0);
                let reach = l0 * (d_old - th).cos() + l1;
                xs[idx + 2] = l0n;
                xs[idx + 3] = (reach - l0n * (d_new - th).cos()).max(0.05 * l1);
            }
            xs[idx] = d_new;
            let (xf, ev) = lm_pinned(model, &xs, &pinned, Some(idx));
            let root = (wcost(&ev) - c0).max(0.0).sqrt();
            if root >= 1.0 {
                side = prev_off + (off - prev_off) * (1.0 - prev_root) / (root - prev_root);
                break;
            }
            if off >= PROFILE_SPAN {
                break;
            }
            (prev_off, prev_root) = (off, root);
            xs = xf;
            step *= 2.0;
        }
        worst = worst.max(side);
    }
    worst
}

/// Cost knobs of [`fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    /// Only straight lines for the outgoing balls (no sliding parabola).
    pub line_only: bool,
    /// Rounds of outlier rejection (refit on inliers) on the richest model.
    pub robust_rounds: usize,
    /// Levenberg–Marquardt: iteration cap and relative cost decrease that stops it.
    pub lm_max_iter: usize,
    pub lm_rel_tol: f64,
}

impl Default for FitSettings {
    fn default() -> Self {
        // 20 iterations to a relative cost decrease of 1e-6: on the pinned clean and realistic sets
        // of `streakfit bench speed-error` this is faster than (80, 1e-9) and the only setting on
        // both Pareto fronts (README, "Speed against error").
        Self {
            line_only: false,
            robust_rounds: 3,
            lm_max_iter: 20,
            lm_rel_tol: 1e-6,
        }
    }
}

/// Reduced χ² and correlation factor of each residual group (incoming, ball 1, ball 2) under
/// path models `combo`; 1 for an empty group and for a crept object ball's one rest point.
fn group_scales(
    r: &[f64],
    bounds: &[usize; 5],
    combo: Combo,
    object_rest: bool,
) -> ([f64; 3], [f64; 3]) {
    let mut s2 = [1.0; 3];
    let mut corr = [1.0; 3];
    for g in 0..3 {
        let rows = &r[bounds[g + 1]..bounds[g + 2]];
        if rows.is_empty() || (g == 2 && object_rest) {
            continue;
        }
        let k_g = match g {
            0 => 2.0,
            1 => combo.0.map_or(0.0, |m| m.n_params() as f64) + 1.0,
            _ => combo.1.n_params() as f64 + 1.0,
        };
        s2[g] = (rows.iter().map(|v| v * v).sum::<f64>() / (rows.len() as f64 - k_g).max(1.0))
            .max(1e-6);
        corr[g] = correlation_factor(rows);
    }
    (s2, corr)
}

/// Fits the joint model, robustly, for every combination of path models, and keeps the one with
/// the lowest BIC. `x0` is a start in the richest layout: `parabola+line` for each ball (ball 1
/// absent when `out1` is), the object ball a `line` when `object_rest`.
pub fn fit(pb: &Problem, x0: &[f64], settings: &FitSettings) -> Option<JointFit> {
    let m2_richest = if pb.object_rest {
        PathModel::Line
    } else {
        PathModel::ParabolaLine
    };
    let richest = (
        pb.out1.as_ref().map(|_| PathModel::ParabolaLine),
        m2_richest,
    );
    let full = if settings.line_only {
        (pb.out1.as_ref().map(|_| PathModel::Line), PathModel::Line)
    } else {
        richest
    };
    let mut use_ = [
        vec![true; pb.incoming.len()],
        vec![true; pb.out1.as_ref().map_or(0, |v| v.len())],
        vec![true; pb.out2.len()],
    ];
    let mut x = if full == richest {
        x0.to_vec()
    } else {
        convert(x0, richest, full, x0[2])
    };
    // Robust loop on the richest model allowed.
    let mut ev_full = None;
    for _round in 0..settings.robust_rounds.max(1) {
        let (xf, ev, model) = model_fit(pb, full.0, full.1, &x, use_.clone(), settings);
        x = xf;
        // Normalised residuals of all samples (inliers and outliers).
        let geom1 = full
            .0
            .map(|m| PathGeom::new(m, impact_point(&x), x[3], &x[5..]));
        let geom2 = PathGeom::new(full.1, (x[0], x[1]), x[3], &x[model.off2()..]);
        let pi = impact_point(&x);
        let u = unit(x[3] + x[4]);
        let res: [Vec<f64>; 3] = [
            pb.incoming
                .iter()
                .map(|s| cross(u, (s.x - pi.0, s.y - pi.1)) / s.sigma)
                .collect(),
            pb.out1.as_ref().map_or(Vec::new(), |v| {
                v.iter()
                    .map(|s| geom1.unwrap().signed_distance((s.x, s.y)) / s.sigma)
                    .collect()
            }),
            pb.out2
                .iter()
                .map(|s| geom2.signed_distance((s.x, s.y)) / s.sigma)
                .collect(),
        ];
        let inl: Vec<f32> = res
            .iter()
            .zip(&use_)
            .flat_map(|(r, u)| r.iter().zip(u).filter(|(_, k)| **k).map(|(v, _)| *v as f32))
            .collect();
        let mut a: Vec<f32> = inl.iter().map(|v| v.abs()).collect();
        let s = (1.4826 * super::background::median(&mut a) as f64).max(1e-9);
        let cut = (4.0 * s).max(3.0);
        let new: [Vec<bool>; 3] = [0, 1, 2].map(|g| {
            res[g]
                .iter()
                .map(|v| v.abs() < cut || (g == 2 && pb.object_rest))
                .collect()
        });
        if new == use_ {
            ev_full = Some(ev);
            break;
        }
        use_ = new;
    }
    for (g, u) in use_.iter().enumerate() {
        let n = u.iter().filter(|k| **k).count();
        if n < 5 && !(g == 1 && pb.out1.is_none()) && !(g == 2 && pb.object_rest) {
            return None;
        }
    }
    // Reference noise scale from the richest model.
    let model_full = Model {
        pb,
        m1: full.0,
        m2: full.1,
        use_: use_.clone(),
    };
    // The last fit's evaluation holds when its inliers did not change, else evaluate afresh.
    let ev_full = ev_full.unwrap_or_else(|| model_full.eval(&x, true));
    // Each group's own noise scale and correlation (the blocks of `linefit` and the profile
    // samples of `streak` state their sigmas differently): a pooled scale let one group's
    // conservative sigmas make the others' χ² improvements look significant.
    let (s2_ref, corr_ref) = group_scales(&ev_full.r, &ev_full.bounds, full, pb.object_rest);
    let corr_ref = corr_ref.map(|c| c.max(1.0));
    let k_full = model_full.n_params();
    let combos: Vec<(Option<PathModel>, PathModel)> = if settings.line_only {
        vec![full]
    } else {
        let ms = [PathModel::Line, PathModel::ParabolaLine];
        let m2s = if pb.object_rest { &ms[..1] } else { &ms[..] };
        let m1s: Vec<Option<PathModel>> = if pb.out1.is_some() {
            ms.iter().map(|m| Some(*m)).collect()
        } else {
            vec![None]
        };
        m1s.iter()
            .flat_map(|a| m2s.iter().map(move |b| (*a, *b)))
            .collect()
    };
    let mut ev_full = Some(ev_full);
    let mut best: Option<(f64, Vec<f64>, Combo, Eval)> = None;
    let mut fitted: Vec<(f64, Vec<f64>, Combo)> = Vec::new();
    for c in combos {
        let (xs, ev, k) = if c == full {
            (x.clone(), ev_full.take().expect("one full combo"), k_full)
        } else {
            let start = convert(&x, full, c, x[2]);
            let (xs, ev, model) = model_fit(pb, c.0, c.1, &start, use_.clone(), settings);
            (xs, ev, model.n_params())
        };
        // Neighbouring samples are correlated: count independent information only.
        let (mut chi, mut n_eff) = (0.0, 0.0);
        for g in 0..3 {
            let rows = &ev.r[ev.bounds[g + 1]..ev.bounds[g + 2]];
            chi += rows.iter().map(|v| v * v).sum::<f64>() / (s2_ref[g] * corr_ref[g]);
            n_eff += rows.len() as f64 / corr_ref[g];
        }
        let bic = chi + k as f64 * n_eff.ln();
        fitted.push((bic, xs.clone(), c));
        if best.as_ref().is_none_or(|b| bic < b.0) {
            best = Some((bic, xs, c, ev));
        }
    }
    let (bic, mut xb, cb, ev) = best?;
    let Eval { r, bounds, j } = ev;
    let j = j.expect("evaluated with the Jacobian");
    let (s2, corr) = group_scales(&r, &bounds, cb, pb.object_rest);
    // Rows of group g divided by sqrt(s_g² f_g): weights 1 / (s_g² f_g) in J'ᵀ J'.
    let w = [
        1.0,
        1.0 / (s2[0] * corr[0]),
        1.0 / (s2[1] * corr[1]),
        1.0 / (s2[2] * corr[2]),
    ];
    let (a, _) = normal_equations(&j, &r, &bounds, &group_cols(cb.0, cb.1), w);
    let mut cov = covariance(&a)?;
    // A sliding parabola's start tangent: the profile of the weighted cost, not its curvature.
    let model = Model {
        pb,
        m1: cb.0,
        m2: cb.1,
        use_: use_.clone(),
    };
    let mut delta_profile = [None, None];
    let mut delta_lin = [None, None];
    for (ball, m) in [(0, cb.0), (1, Some(cb.1))] {
        if (ball == 1 && pb.object_rest) || m != Some(PathModel::ParabolaLine) {
            continue;
        }
        let i = if ball == 0 { 5 } else { model.off2() };
        // The walk's first step: the linearised sigma.
        let lin = cov[(i, i)];
        if !(lin.is_finite() && lin > 0.0) {
            continue;
        }
        let sd = profile_sd(&model, &xb, i, lin.sqrt(), w, settings);
        if std::env::var_os("STREAKFIT_DEBUG").is_some() {
            eprintln!(
                "profile ball {} start d-th {:.3}° L0 {:.1} L1 {:.1}: sd {:.3}°",
                ball + 1,
                (xb[i] - xb[i + 1]).to_degrees(),
                xb[i + 2],
                xb[i + 3],
                sd.to_degrees()
            );
        }
        delta_lin[ball] = Some(lin.sqrt());
        cov[(i, i)] = lin.max(sd * sd);
        delta_profile[ball] = Some(sd);
    }
    average_models(&mut xb, &mut cov, cb, &fitted);
    Some(JointFit {
        params: xb,
        cov,
        m1: cb.0,
        m2: cb.1,
        inliers: use_,
        s2,
        corr,
        bic,
        delta_profile,
        delta_lin,
    })
}

/// Bayesian model averaging of what every combination of path models shares: the waiting
/// disc `O, R`, the line of centres `alpha`, `psi` and each ball's rolling direction `theta`.
/// Combination `c` weighs `w_c ∝ exp(-(BIC_c - BIC_min)/2)`; the winner's (lowest BIC) values
/// move to the weighted mean, and its covariance gains the weighted spread of the combinations
/// about it, `Σ w_c (x_c - x̄)(x_c - x̄)ᵀ`. Choosing one model flips its angles when two BICs
/// cross; averaged, they move continuously with the data: `theta2` of grazing seed 77's shot_019
/// (plate) had jumped between 1.9° (line) and 11.8° (parabola+line) under a perturbation of the
/// photo 1/4000 of a grey level wide (`streakfit bench stability`). The start tangents and legs
/// of a sliding parabola stay the winner's: a straight path has none.
fn average_models(
    x: &mut [f64],
    cov: &mut DMatrix<f64>,
    win: Combo,
    fitted: &[(f64, Vec<f64>, Combo)],
) {
    if fitted.len() < 2 {
        return;
    }
    let off2 = object_offset(win.0);
    let mut idx: Vec<usize> = (0..5).collect();
    if let Some(m) = win.0 {
        idx.push(angle_slots(m, 5).1);
    }
    idx.push(angle_slots(win.1, off2).1);
    // Angles (alpha, psi, thetas) differ modulo a turn.
    let diff = |i: usize, d: f64| if i >= 3 { wrap(d) } else { d };
    let b_min = fitted.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
    let w: Vec<f64> = fitted
        .iter()
        .map(|f| (-(f.0 - b_min) / 2.0).exp())
        .collect();
    let total: f64 = w.iter().sum();
    // Each combination's shared values, less the winner's.
    let d: Vec<Vec<f64>> = fitted
        .iter()
        .map(|(_, xs, c)| {
            let xc = convert(xs, *c, win, x[2]);
            idx.iter().map(|&i| diff(i, xc[i] - x[i])).collect()
        })
        .collect();
    let mean: Vec<f64> = (0..idx.len())
        .map(|a| d.iter().zip(&w).map(|(dc, wc)| wc * dc[a]).sum::<f64>() / total)
        .collect();
    for (a, &ia) in idx.iter().enumerate() {
        for (b, &ib) in idx.iter().enumerate() {
            cov[(ia, ib)] += d
                .iter()
                .zip(&w)
                .map(|(dc, wc)| wc * (dc[a] - mean[a]) * (dc[b] - mean[b]))
                .sum::<f64>()
                / total;
        }
        x[ia] += mean[a];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two combinations of equal BIC: the shared angles move halfway and their variance gains
    /// the half-difference squared, correlated where both moved; the parabola's own start
    /// tangent and legs are not touched. At a BIC 20 worse the other combination weighs
    /// `e^-10`: nothing moves by more than that share.
    #[test]
    fn models_of_equal_evidence_are_averaged() {
        let win = (Some(PathModel::Line), PathModel::Line);
        let other = (Some(PathModel::Line), PathModel::ParabolaLine);
        let xw = vec![100.0, 50.0, 20.0, 0.3, 0.5, 1.2, 0.02];
        // The other: psi 0.01 rad larger, theta2 0.04 rad larger (start tangent 0.2, legs 5).
        let xo = vec![100.0, 50.0, 20.0, 0.3, 0.51, 1.2, 0.2, 0.06, 5.0, 5.0];
        for (gap, share) in [(0.0, 0.5), (20.0, (-10f64).exp() / (1.0 + (-10f64).exp()))] {
            let mut x = xw.clone();
            let mut cov = DMatrix::<f64>::identity(7, 7) * 1e-6;
            average_models(
                &mut x,
                &mut cov,
                win,
                &[(10.0, xw.clone(), win), (10.0 + gap, xo.clone(), other)],
            );
            assert!(
                (x[4] - (0.5 + 0.01 * share)).abs() < 1e-12,
                "{gap}: psi {}",
                x[4]
            );
            assert!(
                (x[6] - (0.02 + 0.04 * share)).abs() < 1e-12,
                "{gap}: theta2 {}",
                x[6]
            );
            for i in [0, 1, 2, 3, 5] {
                assert!((x[i] - xw[i]).abs() < 1e-12);
            }
            let spread = share * (1.0 - share);
            assert!((cov[(6, 6)] - (1e-6 + spread * 0.04 * 0.04)).abs() < 1e-15);
            assert!((cov[(4, 6)] - spread * 0.01 * 0.04).abs() < 1e-15);
            assert!((cov[(5, 5)] - 1e-6).abs() < 1e-15);
        }
    }

    /// Deterministic xorshift in [0, 1): the tests need no seeded-RNG plumbing.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
    }

    /// Samples along a path (from `geom`, arc positions `0..len`, scattered `spread` px across
    /// it), plus one a hair past the Bézier/ray junction and one behind the start.
    fn samples_along(
        geom: &PathGeom,
        len: f64,
        n: usize,
        spread: f64,
        rng: &mut Rng,
    ) -> Vec<Sample> {
        let poly = geom.polyline(len);
        let mut out = Vec::new();
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for w in poly.windows(2) {
            let seg = (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1);
            let m = ((n as f64) * seg / len).ceil().max(1.0) as usize;
            for i in 0..m {
                let f = (i as f64 + rng.next()) / m as f64;
                pts.push((
                    w[0].0 + f * (w[1].0 - w[0].0),
                    w[0].1 + f * (w[1].1 - w[0].1),
                ));
            }
        }
        let n1 = (-geom.u1.1, geom.u1.0);
        pts.push((
            geom.end.0 + 1e-3 * geom.u1.0 + 0.7 * n1.0,
            geom.end.1 + 1e-3 * geom.u1.1 + 0.7 * n1.1,
        ));
        pts.push((
            geom.start.0 - 3.0 * geom.u0.0 + 0.4 * n1.0,
            geom.start.1 - 3.0 * geom.u0.1 + 0.4 * n1.1,
        ));
        for p in pts {
            let n = (rng.range(-1.0, 1.0) * spread, rng.range(-1.0, 1.0) * spread);
            out.push(Sample {
                x: p.0 + n.0,
                y: p.1 + n.1,
                sigma: rng.range(0.05, 0.5),
                amp: 1.0,
            });
        }
        out
    }

    /// A shot in the `parabola+line` layout with both balls moving.
    fn truth(rng: &mut Rng) -> Vec<f64> {
        let r = rng.range(60.0, 120.0);
        let sign = |rng: &mut Rng| if rng.next() < 0.5 { -1.0 } else { 1.0 };
        let d1 = rng.range(-1.3, 1.3);
        let d2 = rng.range(-1.0, 1.0);
        vec![
            rng.range(900.0, 1500.0),
            rng.range(600.0, 1000.0),
            r,
            rng.range(-3.1, 3.1),
            rng.range(-1.2, 1.2),
            d1,
            d1 + rng.range(-0.6, 0.6),
            sign(rng) * rng.range(0.5, 3.0) * r,
            sign(rng) * rng.range(0.5, 3.0) * r,
            d2,
            d2 + rng.range(-0.3, 0.3),
            sign(rng) * rng.range(0.5, 3.0) * r,
            sign(rng) * rng.range(0.5, 3.0) * r,
        ]
    }

    fn problem(x: &[f64], spread: f64, rng: &mut Rng) -> Problem {
        let pi = impact_point(x);
        let back = unit(x[3] + x[4]);
        let incoming = (0..60)
            .map(|i| {
                let a = -(i as f64 + 1.0) * 8.0 - 2.0 * x[2];
                Sample {
                    x: pi.0 + a * back.0 + rng.range(-1.0, 1.0) * spread,
                    y: pi.1 + a * back.1 + rng.range(-1.0, 1.0) * spread,
                    sigma: rng.range(0.05, 0.5),
                    amp: 1.0,
                }
            })
            .collect();
        let g1 = PathGeom::new(PathModel::ParabolaLine, pi, x[3], &x[5..9]);
        let g2 = PathGeom::new(PathModel::ParabolaLine, (x[0], x[1]), x[3], &x[9..13]);
        Problem {
            o_meas: (x[0] + 0.3, x[1] - 0.2),
            sigma_o: 0.5,
            r_meas: x[2] + 0.4,
            sigma_r: 0.5,
            incoming,
            out1: Some(samples_along(&g1, 900.0, 80, spread, rng)),
            out2: samples_along(&g2, 900.0, 80, spread, rng),
            object_rest: false,
        }
    }

    fn combos(with_cue: bool) -> Vec<Combo> {
        let ms = [PathModel::Line, PathModel::ParabolaLine];
        if with_cue {
            ms.iter()
                .flat_map(|a| ms.iter().map(move |b| (Some(*a), *b)))
                .collect()
        } else {
            ms.iter().map(|b| (None, *b)).collect()
        }
    }

    #[test]
    fn analytic_jacobian_matches_central_differences() {
        let mut rng = Rng(0x5eed_1234_abcd_0001);
        let mut checked = 0;
        for case in 0..12 {
            let xt = truth(&mut rng);
            let mut pb = problem(&xt, 3.0, &mut rng);
            let with_cue = case % 3 != 2;
            if !with_cue {
                pb.out1 = None;
            }
            let richest = (
                with_cue.then_some(PathModel::ParabolaLine),
                PathModel::ParabolaLine,
            );
            let x0: Vec<f64> = if with_cue {
                xt.clone()
            } else {
                [&xt[..5], &xt[9..]].concat()
            };
            for c in combos(with_cue) {
                // Evaluate away from the truth so residuals are not all small.
                let mut x = convert(&x0, richest, c, x0[2]);
                for (i, v) in x.iter_mut().enumerate() {
                    *v += match i {
                        0..=2 => rng.range(-2.0, 2.0),
                        3..=4 => rng.range(-0.02, 0.02),
                        _ => rng.range(-0.02, 0.02) * if v.abs() > 10.0 { 100.0 } else { 1.0 },
                    };
                }
                let use_ = [
                    vec![true; pb.incoming.len()],
                    vec![true; pb.out1.as_ref().map_or(0, |v| v.len())],
                    vec![true; pb.out2.len()],
                ];
                let model = Model {
                    pb: &pb,
                    m1: c.0,
                    m2: c.1,
                    use_,
                };
                let ja = model.eval(&x, true).j.unwrap().to_dmatrix();
                let jn = model.jacobian_numeric(&x);
                assert_eq!(ja.shape(), jn.shape());
                for col in 0..ja.ncols() {
                    let scale = jn.column(col).amax();
                    assert!(scale > 0.0, "case {case} {c:?}: column {col} all zero");
                    for row in 0..ja.nrows() {
                        let (a, n) = (ja[(row, col)], jn[(row, col)]);
                        // The floor covers the differences' own rounding (~1e-16 |r| / h).
                        assert!(
                            (a - n).abs() <= 1e-5 * n.abs().max(1e-3 * scale) + 1e-6,
                            "case {case} {c:?} row {row} col {col}: analytic {a} numeric {n}"
                        );
                    }
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 8 * 4 + 4 * 2);
    }

    #[test]
    fn bezier_foot_is_the_global_nearest_point() {
        let mut rng = Rng(0x0b0e_2e11_f00d_0002);
        for _ in 0..20000 {
            let p = [
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
                rng.range(-120.0, 280.0),
                rng.range(-120.0, 280.0),
            ];
            let g = PathGeom::new(
                PathModel::ParabolaLine,
                (1000.0, 800.0),
                rng.range(-3.1, 3.1),
                &p,
            );
            let b = g.bezier(rng.next());
            let spread = [5.0, 50.0, 1000.0][(rng.next() * 3.0) as usize];
            let q = (
                b.0 + rng.range(-spread, spread),
                b.1 + rng.range(-spread, spread),
            );
            let dist = |t: f64| {
                let b = g.bezier(t);
                (b.0 - q.0).hypot(b.1 - q.1)
            };
            // Brute force: a fine scan, then golden-section refinement around its best.
            let n = 4000;
            let i = (0..=n)
                .min_by(|a, b| dist(*a as f64 / n as f64).total_cmp(&dist(*b as f64 / n as f64)))
                .unwrap();
            let (mut lo, mut hi) = (
                ((i as f64 - 1.0) / n as f64).max(0.0),
                ((i as f64 + 1.0) / n as f64).min(1.0),
            );
            for _ in 0..200 {
                let (m1, m2) = (lo + 0.381966 * (hi - lo), hi - 0.381966 * (hi - lo));
                if dist(m1) < dist(m2) {
                    hi = m2;
                } else {
                    lo = m1;
                }
            }
            let best = dist(0.5 * (lo + hi));
            let t = g.bezier_foot(q);
            assert!((0.0..=1.0).contains(&t));
            assert!(
                dist(t) <= best + 1e-9,
                "p={p:?} q={q:?}: foot {t} at {} px, brute force {best} px",
                dist(t)
            );
        }
    }

    #[test]
    fn covariance_of_an_undetermined_parameter_is_infinite() {
        // Parameter 1 enters no residual; 0 and 2 are correlated.
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.0]);
        let cov = covariance(&a).unwrap();
        assert!(cov[(1, 1)].is_infinite());
        assert!(cov[(0, 1)].abs() < 1e-300);
        // Inverse of [[4, 1], [1, 2]] = [[2, -1], [-1, 4]] / 7.
        assert!((cov[(0, 0)] - 2.0 / 7.0).abs() < 1e-15);
        assert!((cov[(0, 2)] + 1.0 / 7.0).abs() < 1e-15);
        assert!((cov[(2, 2)] - 4.0 / 7.0).abs() < 1e-15);
    }

    #[test]
    fn covariance_keeps_a_determined_parameter_beside_a_degenerate_pair() {
        // Parameters 1 and 2 enter only as their sum 1e3·x1 + x2 (a position in px and a leg
        // trading against it): the pair is undetermined, parameter 0 (an angle, scale 1) is
        // determined and coupled to neither: its variance is 1/a00 whatever the pair does.
        let (s1, s2) = (1e3, 1.0);
        let mut a = DMatrix::<f64>::zeros(3, 3);
        a[(0, 0)] = 2.5e4;
        for (i, si) in [(1, s1), (2, s2)] {
            for (j, sj) in [(1, s1), (2, s2)] {
                a[(i, j)] = 7.0 * si * sj;
            }
        }
        let cov = covariance(&a).unwrap();
        assert!((cov[(0, 0)] * 2.5e4 - 1.0).abs() < 1e-12, "{}", cov[(0, 0)]);
        assert!(cov[(1, 1)].is_infinite() && cov[(2, 2)].is_infinite());
        // Badly scaled but determined (unit-diagonal correlations 0.3, 0.1, 0.2): the inverse
        // to working precision, entry (i, j) of b·cov measured in units of d_i / d_j.
        let b = DMatrix::from_row_slice(3, 3, &[1e8, 3e3, 1e-1, 3e3, 1.0, 2e-5, 1e-1, 2e-5, 1e-8]);
        let cov = covariance(&b).unwrap();
        let id = &b * &cov;
        let d = [1e4, 1.0, 1e-4];
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((id[(i, j)] - want).abs() * d[j] / d[i] < 1e-12, "{id}");
            }
        }
    }

    #[test]
    fn fit_recovers_a_shot_and_picks_its_path_models() {
        let mut rng = Rng(0xfeed_beef_0003);
        for _ in 0..3 {
            // Cue ball: a clear sliding parabola; object ball: a straight line.
            let mut xt = truth(&mut rng);
            xt[6] = xt[5] + 0.4;
            xt[7] = 1.5 * xt[2];
            xt[8] = 1.5 * xt[2];
            xt[10] = xt[9];
            let mut pb = problem(&xt, 0.02, &mut rng);
            // Drop the two probe samples (junction, behind the start) from each ball.
            for v in [pb.out1.as_mut().unwrap(), &mut pb.out2] {
                v.truncate(v.len() - 2);
            }
            // Unbiased disc priors (`problem` offsets them for the Jacobian test).
            pb.o_meas = (xt[0], xt[1]);
            pb.r_meas = xt[2];
            let mut x0 = xt.clone();
            for (i, v) in x0.iter_mut().enumerate() {
                *v += match i {
                    0..=2 => 0.5,
                    3..=6 | 9 | 10 => 0.01,
                    _ => 0.1 * *v,
                };
            }
            let f = fit(&pb, &x0, &FitSettings::default()).expect("fit");
            assert_eq!(f.m1, Some(PathModel::ParabolaLine));
            assert_eq!(f.m2, PathModel::Line);
            let (d1, t1) = f.angle_indices(1).unwrap();
            let (d2, t2) = f.angle_indices(2).unwrap();
            assert_eq!(d2, t2);
            // 0.02 px of noise on ~80 samples a path: thousandths of a degree for directions,
            // hundredths for the start tangent of a short parabola.
            for (name, got, want, tol_deg) in [
                ("alpha", f.alpha(), xt[3], 0.01),
                ("psi_s", f.psi_s(), xt[4], 0.01),
                ("delta1", f.params[d1], xt[5], 0.1),
                ("theta1", f.params[t1], xt[6], 0.01),
                ("theta2", f.params[t2], xt[10], 0.01),
            ] {
                assert!(
                    (got - want).abs() < f64::to_radians(tol_deg),
                    "{name}: {:.4}° off",
                    (got - want).to_degrees()
                );
            }
            assert!((f.o().0 - xt[0]).abs() < 0.05 && (f.r() - xt[2]).abs() < 0.05);
            assert!(f.sd(t1).is_finite() && f.sd(t1) > 0.0);
        }
    }

    /// An object ball that crept to rest: its "streak" is one point, the rest disc's centre `Q`,
    /// with the disc fit's sigma. Its path is a line from `O` through `Q`: theta2 is the
    /// direction of `Q`, with a sigma of about that of `Q` across the line over `|Q − O|` (with
    /// `O`'s and alpha's own added; measured 1.05–1.3 of it), the point is never an outlier and
    /// its group is not rescaled, and psi is that of the fit with a full object streak.
    #[test]
    fn a_rest_point_sets_the_object_balls_line() {
        let mut rng = Rng(0xfeed_beef_0007);
        for _ in 0..3 {
            let mut xt = truth(&mut rng);
            xt[11] = 0.5 * xt[2];
            xt[12] = 0.5 * xt[2];
            let mut pb = problem(&xt, 0.02, &mut rng);
            pb.out1.as_mut().unwrap().truncate(78);
            // Disc priors as a disc fit gives them.
            (pb.o_meas, pb.sigma_o) = ((xt[0], xt[1]), 0.02);
            (pb.r_meas, pb.sigma_r) = (xt[2], 0.01);
            // The rest centre 1.5 R from O, along alpha + theta2, read 0.3 sigma across the line.
            let (d, sq) = (1.5 * xt[2], 0.05);
            let u = unit(xt[3] + xt[10]);
            pb.out2 = vec![Sample {
                x: xt[0] + d * u.0 - 0.3 * sq * u.1,
                y: xt[1] + d * u.1 + 0.3 * sq * u.0,
                sigma: sq,
                amp: 1.0,
            }];
            pb.object_rest = true;
            let mut x0: Vec<f64> = xt[..9].to_vec();
            x0.push(xt[10] + 0.02);
            let f = fit(&pb, &x0, &FitSettings::default()).expect("fit");
            assert_eq!(f.m2, PathModel::Line);
            let (d2, t2) = f.angle_indices(2).unwrap();
            assert_eq!(d2, t2);
            // A straight path does not measure its start tangent.
            assert!(f.delta_sd(2).is_infinite());
            let sd = f.sd(t2);
            let ratio = sd / (sq / d);
            assert!((1.0..1.6).contains(&ratio), "sd {sd} against {}", sq / d);
            let want = xt[10] + 0.3 * sq / d;
            assert!(
                (f.params[t2] - want).abs() < sd,
                "theta2 {:.5}° against {:.5}° ± {:.5}°",
                f.params[t2].to_degrees(),
                want.to_degrees(),
                sd.to_degrees()
            );
            assert!((f.psi_s() - xt[4]).abs() < 0.01f64.to_radians());
            assert!((f.s2[2] - 1.0).abs() < 1e-12, "{:?}", f.s2);
            assert!(f.inliers[2][0]);
        }
    }

    /// The profile of a start tangent: where the parabola is well sampled it agrees with the
    /// linearised sigma (the cost is nearly quadratic); where its curve is hidden (an object
    /// ball's 3° hook over its first 0.8 R, no sample within 2 R of O, as under the waiting
    /// disc's keep-out) the walk finds no rise of the cost and reports the angle undetermined.
    #[test]
    fn profile_of_a_start_tangent() {
        let mut rng = Rng(0xfeed_beef_0042);
        let mut xt = truth(&mut rng);
        xt[6] = xt[5] + 0.4;
        xt[7] = 1.5 * xt[2];
        xt[8] = 1.5 * xt[2];
        xt[10] = xt[9] - 3f64.to_radians();
        xt[11] = 0.4 * xt[2];
        xt[12] = 0.4 * xt[2];
        let run = |hide: bool, rng: &mut Rng| {
            let mut pb = problem(&xt, 0.05, rng);
            for v in [pb.out1.as_mut().unwrap(), &mut pb.out2] {
                v.truncate(v.len() - 2);
            }
            pb.o_meas = (xt[0], xt[1]);
            pb.r_meas = xt[2];
            pb.sigma_o = 0.05;
            pb.sigma_r = 0.05;
            if hide {
                let r = xt[2];
                pb.out2
                    .retain(|s| (s.x - xt[0]).hypot(s.y - xt[1]) > 2.0 * r);
            } else {
                let g2 = PathGeom::new(PathModel::ParabolaLine, (xt[0], xt[1]), xt[3], &xt[9..13]);
                pb.out2
                    .extend(samples_along(&g2, 0.8 * xt[2], 40, 0.05, rng));
            }
            fit(&pb, &xt, &FitSettings::default()).expect("fit")
        };
        let seen = run(false, &mut rng);
        assert_eq!(seen.m2, PathModel::ParabolaLine);
        for ball in [0, 1] {
            let (p, l) = (
                seen.delta_profile[ball].unwrap(),
                seen.delta_lin[ball].unwrap(),
            );
            assert!(
                p > 0.7 * l && p < 1.5 * l,
                "ball {}: profile {:.4}° against linear {:.4}°",
                ball + 1,
                p.to_degrees(),
                l.to_degrees()
            );
        }
        assert!(seen.delta_sd(2).to_degrees() < 1.0);
        let hidden = run(true, &mut rng);
        // Undetermined: the walk reaches its span, or the legs have no information at all.
        assert!(
            hidden.delta_sd(2) >= 0.9 * PROFILE_SPAN,
            "hidden hook: delta2 sigma {:.2}° (profile {:?})",
            hidden.delta_sd(2).to_degrees(),
            hidden.delta_profile[1]
        );
        assert!(
            hidden.delta_sd(1).to_degrees() < 0.5,
            "the cue ball's parabola is in sight"
        );
    }
}
