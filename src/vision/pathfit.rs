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
//! Levenberg–Marquardt with a central-difference Jacobian (each parameter only re-evaluates the
//! residual groups it affects). Outliers (crossing streaks, highlights): samples beyond
//! `max(4 s, 3)` normalised units (`s` = MAD scale) are dropped and the fit repeated.
//! Model choice per ball by BIC, `χ²/(s² f) + k ln(n/f)`, with `s²` and the correlation factor
//! `f` (below) from the richest model, so correlated samples are not counted as independent.
//! Covariance `(J'ᵀ J')⁻¹`, where each residual group's rows are divided by `sqrt(s_g² f_g)`:
//! `s_g²` its reduced χ² and `f_g = 1 + 2 Σ ρ_k` the correlation factor of its ordered residuals
//! (neighbouring centre-line samples share cloth texture and noise), so the stated sigma counts
//! independent information only.

use super::streak::Sample;
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
                // Lengths are |L| + 0.5 px so the start tangent never loses its meaning.
                let (l0, l1) = (p[2].abs() + 0.5, p[3].abs() + 0.5);
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
        if self.model == PathModel::Line {
            // A ray, not a line: a point behind the start is as far as the start itself (this
            // also keeps theta from flipping by 180°).
            let w = (q.0 - self.start.0, q.1 - self.start.1);
            let c = cross(self.u1, w);
            let along = w.0 * self.u1.0 + w.1 * self.u1.1;
            return if along >= 0.0 {
                c
            } else {
                w.0.hypot(w.1).copysign(c)
            };
        }
        let rel = (q.0 - self.end.0, q.1 - self.end.1);
        let s = rel.0 * self.u1.0 + rel.1 * self.u1.1;
        let d_ray = if s >= 0.0 {
            cross(self.u1, rel)
        } else {
            f64::INFINITY
        };
        // Closest point on the Bézier: coarse scan, then Newton on (B - q)·B' = 0.
        let mut best = (0.0, f64::INFINITY);
        for i in 0..=12 {
            let t = i as f64 / 12.0;
            let b = self.bezier(t);
            let d2 = (b.0 - q.0).powi(2) + (b.1 - q.1).powi(2);
            if d2 < best.1 {
                best = (t, d2);
            }
        }
        let mut t = best.0;
        let dd = (
            2.0 * (self.end.0 - 2.0 * self.ctrl.0 + self.start.0),
            2.0 * (self.end.1 - 2.0 * self.ctrl.1 + self.start.1),
        );
        for _ in 0..8 {
            let b = self.bezier(t);
            let d = self.bezier_d(t);
            let e = (b.0 - q.0, b.1 - q.1);
            let g = e.0 * d.0 + e.1 * d.1;
            let gp = d.0 * d.0 + d.1 * d.1 + e.0 * dd.0 + e.1 * dd.1;
            if gp.abs() < 1e-12 {
                break;
            }
            t = (t - g / gp).clamp(0.0, 1.0);
        }
        let b = self.bezier(t);
        let mut d = self.bezier_d(t);
        let l = d.0.hypot(d.1);
        if l < 1e-12 {
            d = self.u0;
        } else {
            d = (d.0 / l, d.1 / l);
        }
        let d_bez = cross(d, (q.0 - b.0, q.1 - b.1));
        if d_ray.abs() < d_bez.abs() {
            d_ray
        } else {
            d_bez
        }
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
        5 + self.m1.map_or(0, |m| m.n_params())
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
        Some(match m {
            PathModel::Line => (off, off),
            PathModel::ParabolaLine => (off, off + 1),
        })
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

impl Model<'_> {
    fn n_params(&self) -> usize {
        5 + self.m1.map_or(0, |m| m.n_params()) + self.m2.n_params()
    }
    fn off2(&self) -> usize {
        5 + self.m1.map_or(0, |m| m.n_params())
    }
    /// Which residual groups depend on parameter `j`.
    fn groups_of(&self, j: usize) -> [bool; 4] {
        match j {
            0 | 1 => [true, true, true, true],
            2 => [true, true, true, false],
            3 => [false, true, true, true],
            4 => [false, true, false, false],
            _ if j < self.off2() => [true, false, true, false],
            _ => [true, false, false, true],
        }
    }
    fn group(&self, g: usize, p: &[f64], out: &mut Vec<f64>) {
        out.clear();
        match g {
            0 => {
                out.push((p[0] - self.pb.o_meas.0) / self.pb.sigma_o);
                out.push((p[1] - self.pb.o_meas.1) / self.pb.sigma_o);
                out.push((p[2] - self.pb.r_meas) / self.pb.sigma_r);
                // Sliding arcs are short (cloth friction 0.15–0.55: one to three diameters);
                // a soft wall at L0 + L1 = 12 R keeps a parabola from absorbing the whole path.
                let wall = |l: f64| ((l - 12.0 * p[2]).max(0.0) / (0.1 * p[2])).min(1e6);
                if self.m1 == Some(PathModel::ParabolaLine) {
                    out.push(wall(p[7].abs() + p[8].abs()));
                }
                if self.m2 == PathModel::ParabolaLine {
                    let o = self.off2();
                    out.push(wall(p[o + 2].abs() + p[o + 3].abs()));
                }
            }
            1 => {
                let pi = impact_point(p);
                let u = unit(p[3] + p[4]);
                for (s, &k) in self.pb.incoming.iter().zip(&self.use_[0]) {
                    if k {
                        out.push(cross(u, (s.x - pi.0, s.y - pi.1)) / s.sigma);
                    }
                }
            }
            2 => {
                if let (Some(m), Some(samples)) = (self.m1, &self.pb.out1) {
                    let geom = PathGeom::new(m, impact_point(p), p[3], &p[5..]);
                    for (s, &k) in samples.iter().zip(&self.use_[1]) {
                        if k {
                            out.push(geom.signed_distance((s.x, s.y)) / s.sigma);
                        }
                    }
                }
            }
            _ => {
                let geom = PathGeom::new(self.m2, (p[0], p[1]), p[3], &p[self.off2()..]);
                for (s, &k) in self.pb.out2.iter().zip(&self.use_[2]) {
                    if k {
                        out.push(geom.signed_distance((s.x, s.y)) / s.sigma);
                    }
                }
            }
        }
    }
    fn residuals(&self, p: &[f64]) -> (Vec<f64>, [usize; 5]) {
        let mut all = Vec::new();
        let mut bounds = [0usize; 5];
        let mut buf = Vec::new();
        for g in 0..4 {
            self.group(g, p, &mut buf);
            all.extend_from_slice(&buf);
            bounds[g + 1] = all.len();
        }
        (all, bounds)
    }
    fn jacobian(&self, p: &[f64], bounds: &[usize; 5]) -> DMatrix<f64> {
        let n = bounds[4];
        let k = p.len();
        let mut j = DMatrix::zeros(n, k);
        let mut pp = p.to_vec();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for c in 0..k {
            let h = if c <= 2 || (c >= 5 && self.is_length(c)) {
                1e-4
            } else {
                1e-6
            };
            let deps = self.groups_of(c);
            for g in 0..4 {
                if !deps[g] {
                    continue;
                }
                pp[c] = p[c] + h;
                self.group(g, &pp, &mut a);
                pp[c] = p[c] - h;
                self.group(g, &pp, &mut b);
                pp[c] = p[c];
                for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                    j[(bounds[g] + i, c)] = (x - y) / (2.0 * h);
                }
            }
        }
        j
    }
    fn is_length(&self, c: usize) -> bool {
        let check = |m: PathModel, off: usize| {
            m == PathModel::ParabolaLine && (c == off + 2 || c == off + 3)
        };
        self.m1.is_some_and(|m| check(m, 5)) || check(self.m2, self.off2())
    }
}

fn lm(model: &Model, x0: &[f64], s: &FitSettings) -> Vec<f64> {
    let mut x = x0.to_vec();
    let (mut r, mut bounds) = model.residuals(&x);
    let mut cost: f64 = r.iter().map(|v| v * v).sum();
    let mut lambda = 1e-3;
    for _ in 0..s.lm_max_iter {
        let j = model.jacobian(&x, &bounds);
        let rv = DVector::from_vec(r.clone());
        let a = j.transpose() * &j;
        let g = j.transpose() * rv;
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
            let (rn, bn) = model.residuals(&xn);
            let cn: f64 = rn.iter().map(|v| v * v).sum();
            if cn.is_finite() && cn <= cost {
                let rel = (cost - cn) / cost.max(1e-300);
                x = xn;
                r = rn;
                bounds = bn;
                cost = cn;
                lambda = (lambda / 3.0).max(1e-12);
                improved = true;
                if rel < s.lm_rel_tol {
                    return x;
                }
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    x
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
) -> (Vec<f64>, Model<'a>) {
    let model = Model { pb, m1, m2, use_ };
    let x = lm(&model, x0, s);
    (x, model)
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

/// Fits the joint model, robustly, for every combination of path models, and keeps the one with
/// the lowest BIC. `x0` is a start in the `parabola+line` layout (ball 1 absent when `out1` is).
pub fn fit(pb: &Problem, x0: &[f64], settings: &FitSettings) -> Option<JointFit> {
    let richest = (
        pb.out1.as_ref().map(|_| PathModel::ParabolaLine),
        PathModel::ParabolaLine,
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
    for _round in 0..settings.robust_rounds.max(1) {
        let (xf, model) = model_fit(pb, full.0, full.1, &x, use_.clone(), settings);
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
        let new: [Vec<bool>; 3] = [0, 1, 2].map(|g| res[g].iter().map(|v| v.abs() < cut).collect());
        if new == use_ {
            break;
        }
        use_ = new;
    }
    for (g, u) in use_.iter().enumerate() {
        let n = u.iter().filter(|k| **k).count();
        if n < 5 && !(g == 1 && pb.out1.is_none()) {
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
    let (r_full, b_full) = model_full.residuals(&x);
    let n_obs = r_full.len() - b_full[1];
    let k_full = model_full.n_params();
    let chi_full: f64 = r_full[b_full[1]..].iter().map(|v| v * v).sum();
    let s2_ref = (chi_full / (n_obs.saturating_sub(k_full)).max(1) as f64).max(1e-12);
    let corr_ref = {
        let (r, b) = model_full.residuals(&x);
        let mut acc = 0.0;
        let mut n = 0.0;
        for g in 1..4 {
            let rows = &r[b[g]..b[g + 1]];
            if !rows.is_empty() {
                acc += correlation_factor(rows) * rows.len() as f64;
                n += rows.len() as f64;
            }
        }
        (acc / n.max(1.0)).max(1.0)
    };
    let combos: Vec<(Option<PathModel>, PathModel)> = if settings.line_only {
        vec![full]
    } else if pb.out1.is_some() {
        let ms = [PathModel::Line, PathModel::ParabolaLine];
        ms.iter()
            .flat_map(|a| ms.iter().map(move |b| (Some(*a), *b)))
            .collect()
    } else {
        vec![(None, PathModel::Line), (None, PathModel::ParabolaLine)]
    };
    let mut best: Option<(f64, Vec<f64>, Combo)> = None;
    for c in combos {
        let xs = if c == full {
            x.clone()
        } else {
            let start = convert(&x, full, c, x[2]);
            model_fit(pb, c.0, c.1, &start, use_.clone(), settings).0
        };
        let model = Model {
            pb,
            m1: c.0,
            m2: c.1,
            use_: use_.clone(),
        };
        let (r, b) = model.residuals(&xs);
        let chi: f64 = r[b[1]..].iter().map(|v| v * v).sum();
        // Neighbouring samples are correlated: count independent information only.
        let bic =
            chi / (s2_ref * corr_ref) + model.n_params() as f64 * (n_obs as f64 / corr_ref).ln();
        if best.as_ref().is_none_or(|b| bic < b.0) {
            best = Some((bic, xs, c));
        }
    }
    let (bic, xb, cb) = best?;
    let model = Model {
        pb,
        m1: cb.0,
        m2: cb.1,
        use_: use_.clone(),
    };
    let (r, bounds) = model.residuals(&xb);
    let mut j = model.jacobian(&xb, &bounds);
    let mut s2 = [1.0; 3];
    let mut corr = [1.0; 3];
    for g in 0..3 {
        let rows = &r[bounds[g + 1]..bounds[g + 2]];
        if rows.is_empty() {
            continue;
        }
        let k_g = match g {
            0 => 2.0,
            1 => cb.0.map_or(0.0, |m| m.n_params() as f64) + 1.0,
            _ => cb.1.n_params() as f64 + 1.0,
        };
        s2[g] = (rows.iter().map(|v| v * v).sum::<f64>() / (rows.len() as f64 - k_g).max(1.0))
            .max(1e-6);
        corr[g] = correlation_factor(rows);
        let scale = 1.0 / (s2[g] * corr[g]).sqrt();
        for i in bounds[g + 1]..bounds[g + 2] {
            for c in 0..j.ncols() {
                j[(i, c)] *= scale;
            }
        }
    }
    let cov = (j.transpose() * &j).try_inverse()?;
    Some(JointFit {
        params: xb,
        cov,
        m1: cb.0,
        m2: cb.1,
        inliers: use_,
        s2,
        corr,
        bic,
    })
}
