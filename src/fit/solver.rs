//! Levenberg–Marquardt on the weighted residuals with a Schur complement on the globals.
//!
//! The Jacobian of all residuals is `J = [A | B]` with `A` the derivatives by the 4 globals and
//! `B` block-diagonal: shot `i`'s residuals depend only on its own locals `(psi_i, r_i, s_i)`.
//! The damped normal equations
//! `[U W; Wᵀ V] (dg, dl) = -(A ᵀr, Bᵀr)`, `U = AᵀA + λ D_U`, `V = blockdiag(V_i + λ D_Vi)`,
//! are solved by eliminating the locals shot by shot (as in bundle adjustment):
//! `S dg = -Aᵀr + Σ W_i V_i⁻¹ B_iᵀr_i` with `S = U - Σ W_i V_i⁻¹ W_iᵀ` (4×4), then
//! `dl_i = V_i⁻¹(-B_iᵀr_i - W_iᵀ dg)`. Every step is linear in the number of shots.
//! Derivatives are finite differences of the closed forms: forward differences during the
//! iterations (the residuals at the current point are kept from its cost evaluation, so a
//! shot's linearisation costs one evaluation per free parameter; the end point is set by the
//! residuals, the Jacobian only steers), central differences for the covariance at the end.
//! Bounds are kept by projection.
//! At the optimum (λ = 0) the covariance of the globals is `S⁻¹` (the globals block of
//! `(JᵀJ)⁻¹`) and that of shot `i`'s locals is
//! `V_i⁻¹ + V_i⁻¹ W_iᵀ S⁻¹ W_i V_i⁻¹`, both for unit-variance residuals.
//!
//! Robust loss (optional): Huber with threshold `k` (in sigmas) on the angle residuals,
//! `rho(r) = r²` for `|r| ≤ k`, `2k|r| - k²` beyond, by iteratively reweighted least squares.

use super::problem::{GLOBAL_HI, GLOBAL_LO, LOCAL_HI, LOCAL_LO, NG, NL, NRES, ShotData, residuals};
use crate::physics::Regime;
use nalgebra::{Matrix3, Matrix4, SMatrix, Vector3, Vector4};
use rayon::prelude::*;

type Matrix4x3 = SMatrix<f64, 4, 3>;

/// Forward-difference step of the Jacobian during the iterations (about `sqrt(eps)` times
/// the parameters' unit scale).
pub const FORWARD_STEP: f64 = 1e-7;

/// Shots from which the per-shot work runs on the rayon pool.
const PAR_MIN: usize = 128;

/// A problem instance: shots (possibly repeated, for the bootstrap), their regimes, free globals.
pub struct Problem<'a> {
    pub shots: Vec<&'a ShotData>,
    pub regimes: Vec<Regime>,
    pub free_global: [bool; NG],
    /// Huber threshold in sigmas, `None` for plain least squares.
    pub huber: Option<f64>,
}

/// Parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    pub g: [f64; NG],
    pub l: Vec<[f64; NL]>,
}

/// Result of a solve.
#[derive(Debug, Clone)]
pub struct Solution {
    pub state: State,
    /// Robust cost `Σ rho(r)` (equals chi² without a robust loss).
    pub cost: f64,
    /// Plain `Σ r²` over all residuals (data and priors).
    pub chi2: f64,
    pub iterations: usize,
    pub converged: bool,
    /// Covariance of the globals for unit-variance residuals (zero rows for fixed globals;
    /// infinite diagonal where the data do not constrain a free global).
    pub cov_g: Matrix4<f64>,
    /// Marginal variances of each shot's locals.
    pub local_var: Vec<[f64; NL]>,
    /// Variances of each shot's locals with the globals held (`diag V_i⁻¹`); the difference to
    /// [`Solution::local_var`] is what the globals' uncertainty adds.
    pub local_var_cond: Vec<[f64; NL]>,
}

fn huber_rho(r: f64, k: Option<f64>) -> f64 {
    match k {
        Some(k) if r.abs() > k => 2.0 * k * r.abs() - k * k,
        _ => r * r,
    }
}

fn huber_sqrt_weight(r: f64, k: Option<f64>) -> f64 {
    match k {
        Some(k) if r.abs() > k => (k / r.abs()).sqrt(),
        _ => 1.0,
    }
}

/// Per-shot normal-equation blocks.
#[derive(Clone, Copy)]
struct Block {
    v: Matrix3<f64>,
    w: Matrix4x3,
    el: Vector3<f64>,
}

impl Problem<'_> {
    /// `(robust cost, chi²)` of one shot's residual block.
    pub fn block_cost(&self, r: &[f64; NRES]) -> (f64, f64) {
        let mut cost = 0.0;
        let mut chi2 = 0.0;
        for (k, x) in r.iter().enumerate() {
            chi2 += x * x;
            cost += if k < 4 {
                huber_rho(*x, self.huber)
            } else {
                x * x
            };
        }
        (cost, chi2)
    }

    /// `(robust cost, chi²)` of shot `i` alone.
    pub fn shot_cost(&self, i: usize, g: &[f64; NG], l: &[f64; NL]) -> (f64, f64) {
        self.block_cost(&residuals(self.shots[i], g, l, self.regimes[i]))
    }

    /// `(robust cost, chi²)` of a state.
    pub fn cost(&self, st: &State) -> (f64, f64) {
        self.cost_res(st).0
    }

    /// `(robust cost, chi²)` of a state and every shot's residuals (kept so that the next
    /// linearisation at this state does not evaluate them again).
    fn cost_res(&self, st: &State) -> ((f64, f64), Vec<[f64; NRES]>) {
        let one = |i: usize| residuals(self.shots[i], &st.g, &st.l[i], self.regimes[i]);
        let res: Vec<[f64; NRES]> = if self.shots.len() >= PAR_MIN {
            (0..self.shots.len()).into_par_iter().map(one).collect()
        } else {
            (0..self.shots.len()).map(one).collect()
        };
        (self.total(&res), res)
    }

    /// `(robust cost, chi²)` summed over residual blocks in shot order (the same sum whatever
    /// the thread count).
    fn total(&self, res: &[[f64; NRES]]) -> (f64, f64) {
        res.iter().fold((0.0, 0.0), |a, r| {
            let c = self.block_cost(r);
            (a.0 + c.0, a.1 + c.1)
        })
    }

    /// Linearises shot `i`: weighted residuals, `A_i` (NRES×4) and `B_i` (NRES×3).
    /// `r0`: the residuals at `(g, l)` when already known. `central`: central differences
    /// (step `1e-6`, error `O(h²)`, for the covariance) or forward differences (half the
    /// evaluations; error `O(h)` ≈ 1e-7 relative, for the iterations, whose end point is set by
    /// the residuals, not by the Jacobian).
    fn linearise(
        &self,
        i: usize,
        g: &[f64; NG],
        l: &[f64; NL],
        r0: Option<&[f64; NRES]>,
        central: bool,
    ) -> ([f64; NRES], [[f64; NG]; NRES], [[f64; NL]; NRES]) {
        let s = self.shots[i];
        let reg = self.regimes[i];
        let r0 = match r0 {
            Some(r) => *r,
            None => residuals(s, g, l, reg),
        };
        let mut a = [[0.0; NG]; NRES];
        let mut b = [[0.0; NL]; NRES];
        // Column of the Jacobian from residuals at `x ± h` (central) or at `x + h` and `r0`.
        let column = |at: &dyn Fn(f64) -> [f64; NRES]| -> [f64; NRES] {
            let mut d = [0.0; NRES];
            if central {
                let h = 1e-6;
                let (rp, rm) = (at(h), at(-h));
                for k in 0..NRES {
                    d[k] = (rp[k] - rm[k]) / (2.0 * h);
                }
            } else {
                let h = FORWARD_STEP;
                let rp = at(h);
                for k in 0..NRES {
                    d[k] = (rp[k] - r0[k]) / h;
                }
            }
            d
        };
        for j in 0..NG {
            if !self.free_global[j] {
                continue;
            }
            let d = column(&|h| {
                let mut gh = *g;
                gh[j] += h;
                residuals(s, &gh, l, reg)
            });
            for k in 0..NRES {
                a[k][j] = d[k];
            }
        }
        let free_l = s.free_locals();
        for j in 0..NL {
            if !free_l[j] {
                continue;
            }
            let d = column(&|h| {
                let mut lh = *l;
                lh[j] += h;
                residuals(s, g, &lh, reg)
            });
            for k in 0..NRES {
                b[k][j] = d[k];
            }
        }
        // IRLS weights of the robust loss on the angle residuals.
        let mut r = r0;
        for k in 0..4 {
            let w = huber_sqrt_weight(r0[k], self.huber);
            r[k] *= w;
            for x in a[k].iter_mut() {
                *x *= w;
            }
            for x in b[k].iter_mut() {
                *x *= w;
            }
        }
        (r, a, b)
    }

    /// Normal-equation pieces at a state: `(U, eg, blocks)`; `res`: the state's residuals
    /// from [`Problem::cost_res`].
    /// `iterate`: a step of the iterations (active set, forward differences) rather than the
    /// covariance at the end (no active set, central differences).
    fn normal(
        &self,
        st: &State,
        res: &[[f64; NRES]],
        iterate: bool,
    ) -> (Matrix4<f64>, Vector4<f64>, Vec<Block>) {
        let active_set = iterate;
        let per_shot = |i: usize| {
            let (r, a, b) = self.linearise(i, &st.g, &st.l[i], Some(&res[i]), !iterate);
            let mut u = Matrix4::zeros();
            let mut eg = Vector4::zeros();
            let mut v = Matrix3::zeros();
            let mut w = Matrix4x3::zeros();
            let mut el = Vector3::zeros();
            for k in 0..NRES {
                for p in 0..NG {
                    eg[p] += a[k][p] * r[k];
                    for q in 0..NG {
                        u[(p, q)] += a[k][p] * a[k][q];
                    }
                    for q in 0..NL {
                        w[(p, q)] += a[k][p] * b[k][q];
                    }
                }
                for p in 0..NL {
                    el[p] += b[k][p] * r[k];
                    for q in 0..NL {
                        v[(p, q)] += b[k][p] * b[k][q];
                    }
                }
            }
            // Fixed locals: identity rows so their step is zero.
            let free_l = self.shots[i].free_locals();
            for p in 0..NL {
                if !free_l[p] {
                    v[(p, p)] = 1.0;
                }
            }
            (u, eg, Block { v, w, el })
        };
        let parts: Vec<(Matrix4<f64>, Vector4<f64>, Block)> = if self.shots.len() >= PAR_MIN {
            (0..self.shots.len())
                .into_par_iter()
                .map(per_shot)
                .collect()
        } else {
            (0..self.shots.len()).map(per_shot).collect()
        };
        let mut u = Matrix4::zeros();
        let mut eg = Vector4::zeros();
        let mut blocks: Vec<Block> = Vec::with_capacity(parts.len());
        for (ui, ei, b) in parts {
            u += ui;
            eg += ei;
            blocks.push(b);
        }
        // Active set: a global at a bound whose descent direction points out of the box is
        // held there for this step (plain projection would crawl along the bound).
        let mut held = [false; NG];
        for p in 0..NG {
            let at_lo = st.g[p] <= GLOBAL_LO[p] && eg[p] > 0.0;
            let at_hi = st.g[p] >= GLOBAL_HI[p] && eg[p] < 0.0;
            if active_set && self.free_global[p] && (at_lo || at_hi) {
                held[p] = true;
                for q in 0..NG {
                    u[(p, q)] = 0.0;
                    u[(q, p)] = 0.0;
                }
                for b in blocks.iter_mut() {
                    for q in 0..NL {
                        b.w[(p, q)] = 0.0;
                    }
                }
                eg[p] = 0.0;
            }
        }
        for p in 0..NG {
            if !self.free_global[p] || held[p] {
                u[(p, p)] = 1.0;
            }
        }
        (u, eg, blocks)
    }

    /// Solves the damped system; `None` if a block is not positive definite.
    fn step(
        &self,
        u: &Matrix4<f64>,
        eg: &Vector4<f64>,
        blocks: &[Block],
        lambda: f64,
    ) -> Option<(Vector4<f64>, Vec<Vector3<f64>>)> {
        let damp4 = |m: &Matrix4<f64>| {
            let mut d = *m;
            for p in 0..NG {
                d[(p, p)] += lambda * m[(p, p)].max(1e-9) + 1e-12;
            }
            d
        };
        let mut s = damp4(u);
        let mut rhs = -eg;
        let mut vinv = Vec::with_capacity(blocks.len());
        for b in blocks {
            let mut v = b.v;
            for p in 0..NL {
                v[(p, p)] += lambda * b.v[(p, p)].max(1e-9) + 1e-12;
            }
            let vi = v.cholesky()?.inverse();
            let wv = b.w * vi;
            s -= wv * b.w.transpose();
            rhs += wv * b.el;
            vinv.push(vi);
        }
        let dg = s.cholesky()?.solve(&rhs);
        let dg =
            Vector4::from_iterator((0..NG).map(|p| if self.free_global[p] { dg[p] } else { 0.0 }));
        let dl = blocks
            .iter()
            .zip(&vinv)
            .map(|(b, vi)| vi * (-b.el - b.w.transpose() * dg))
            .collect();
        Some((dg, dl))
    }

    fn apply(&self, st: &State, dg: &Vector4<f64>, dl: &[Vector3<f64>]) -> State {
        let mut g = st.g;
        for p in 0..NG {
            g[p] = (g[p] + dg[p]).clamp(GLOBAL_LO[p], GLOBAL_HI[p]);
        }
        let l =
            st.l.iter()
                .zip(dl)
                .map(|(l, d)| {
                    let mut n = *l;
                    for p in 0..NL {
                        n[p] = (n[p] + d[p]).clamp(LOCAL_LO[p], LOCAL_HI[p]);
                    }
                    n
                })
                .collect();
        State { g, l }
    }

    /// Levenberg–Marquardt from `start`, at most `max_iter` Jacobian evaluations.
    pub fn solve(&self, start: State, max_iter: usize) -> Solution {
        let mut st = start;
        let ((mut cost, _), mut res) = self.cost_res(&st);
        let mut lambda = 1e-3;
        let mut converged = false;
        let mut iterations = 0;
        while iterations < max_iter {
            iterations += 1;
            let (u, eg, blocks) = self.normal(&st, &res, true);
            let mut improved = false;
            for _ in 0..12 {
                let Some((dg, dl)) = self.step(&u, &eg, &blocks, lambda) else {
                    lambda *= 10.0;
                    continue;
                };
                let cand = self.apply(&st, &dg, &dl);
                let ((c, _), cand_res) = self.cost_res(&cand);
                if c.is_finite() && c <= cost {
                    let drop = cost - c;
                    let rel = drop / cost.max(1e-300);
                    let moved = dg
                        .amax()
                        .max(dl.iter().map(|d| d.amax()).fold(0.0, f64::max));
                    st = cand;
                    res = cand_res;
                    cost = c;
                    lambda = (lambda / 4.0).max(1e-12);
                    improved = true;
                    // chi² changes below 1e-6 (absolute, or relative) are far below one unit of
                    // chi²: the estimates no longer move on the scale of their errors.
                    if drop < 1e-6 || rel < 1e-9 || moved < 1e-12 {
                        converged = true;
                    }
                    break;
                }
                lambda *= 8.0;
            }
            if !improved {
                // No downhill step at any damping: a (constrained) minimum.
                converged = true;
            }
            if converged {
                break;
            }
        }
        self.finish(st, res, iterations, converged)
    }

    /// Covariances at a state (λ = 0), see the module doc.
    fn finish(
        &self,
        st: State,
        res: Vec<[f64; NRES]>,
        iterations: usize,
        converged: bool,
    ) -> Solution {
        let (cost, chi2) = self.total(&res);
        let (u, _, blocks) = self.normal(&st, &res, false);
        let mut s = u;
        let mut vinvs = Vec::with_capacity(blocks.len());
        for b in &blocks {
            let vi =
                b.v.try_inverse()
                    .unwrap_or_else(|| Matrix3::from_diagonal_element(f64::INFINITY));
            s -= b.w * vi * b.w.transpose();
            vinvs.push(vi);
        }
        let cov_g = covariance(&s, &self.free_global);
        let local_var = blocks
            .iter()
            .zip(&vinvs)
            .zip(&self.shots)
            .map(|((b, vi), shot)| {
                let t = vi * b.w.transpose();
                let c = vi + t * cov_g.map(|x| if x.is_finite() { x } else { 0.0 }) * t.transpose();
                let free = shot.free_locals();
                [0, 1, 2].map(|p| if free[p] { c[(p, p)] } else { 0.0 })
            })
            .collect();
        let local_var_cond = vinvs
            .iter()
            .zip(&self.shots)
            .map(|(vi, shot)| {
                let free = shot.free_locals();
                [0, 1, 2].map(|p| if free[p] { vi[(p, p)] } else { 0.0 })
            })
            .collect();
        Solution {
            state: st,
            cost,
            chi2,
            iterations,
            converged,
            cov_g,
            local_var,
            local_var_cond,
        }
    }
}

/// Inverse of the reduced normal matrix on the free globals. A direction the data do not
/// constrain (eigenvalue below 1e-10 of the largest) gives infinite variance to every free
/// global that has weight on it.
fn covariance(s: &Matrix4<f64>, free: &[bool; NG]) -> Matrix4<f64> {
    let idx: Vec<usize> = (0..NG).filter(|&p| free[p]).collect();
    let n = idx.len();
    let mut out = Matrix4::zeros();
    if n == 0 {
        return out;
    }
    let sub = nalgebra::DMatrix::from_fn(n, n, |a, b| s[(idx[a], idx[b])]);
    // Scale to unit diagonal so the eigenvalue test is unit-free.
    let d: Vec<f64> = (0..n).map(|a| sub[(a, a)].max(1e-300).sqrt()).collect();
    let scaled = nalgebra::DMatrix::from_fn(n, n, |a, b| sub[(a, b)] / (d[a] * d[b]));
    let eig = scaled.symmetric_eigen();
    let max_ev = eig.eigenvalues.amax();
    for a in 0..n {
        for b in 0..n {
            let mut c = 0.0;
            let mut inf = false;
            for k in 0..n {
                let ev = eig.eigenvalues[k];
                let wa = eig.eigenvectors[(a, k)];
                let wb = eig.eigenvectors[(b, k)];
                if ev <= 1e-10 * max_ev {
                    if wa.abs() > 1e-3 && wb.abs() > 1e-3 {
                        inf = true;
                    }
                } else {
                    c += wa * wb / ev;
                }
            }
            out[(idx[a], idx[b])] = if inf {
                f64::INFINITY
            } else {
                c / (d[a] * d[b])
            };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::problem::coefficients;
    use crate::physics::{Shot, closed};

    /// Reference: dense Gauss–Newton normal matrix of the full problem, inverted directly,
    /// must give the same global covariance as the Schur complement.
    #[test]
    fn schur_covariance_matches_dense_inverse() {
        let g = [0.9, 0.3, 0.4, 0.3];
        let shots: Vec<ShotData> = (0..6)
            .map(|i| {
                let psi = (10.0 + 10.0 * i as f64).to_radians();
                let a = closed::angles(&Shot::rolling(psi), &coefficients(&g), Regime::SlipMu);
                ShotData {
                    row: i,
                    psi_meas: psi,
                    psi_sigma: 0.01,
                    meas: a.as_array(),
                    sigma: [0.005, 0.006, 0.007, 0.008],
                    frame_sigma: 0.0,
                    mass_ratio: 1.0,
                    spin0: 1.0,
                    english0: 0.0,
                    estimate_spin: i % 2 == 0,
                }
            })
            .collect();
        let p = Problem {
            shots: shots.iter().collect(),
            regimes: vec![Regime::SlipMu; 6],
            free_global: [true, true, true, false],
            huber: None,
        };
        let st = State {
            g,
            l: shots.iter().map(|s| s.start_locals()).collect(),
        };
        let res = p.cost_res(&st).1;
        let sol = p.finish(st.clone(), res, 0, true);
        // Dense Jacobian: columns e, mu, mu_table, then each shot's free locals.
        let mut cols: Vec<(usize, Option<usize>)> = (0..3).map(|j| (j, None)).collect();
        for (i, s) in shots.iter().enumerate() {
            for (j, f) in s.free_locals().iter().enumerate() {
                if *f {
                    cols.push((j, Some(i)));
                }
            }
        }
        let m = shots.len() * NRES;
        let mut jac = nalgebra::DMatrix::zeros(m, cols.len());
        for (c, (j, who)) in cols.iter().enumerate() {
            for (i, s) in shots.iter().enumerate() {
                let (_, a, b) = p.linearise(i, &st.g, &st.l[i], None, true);
                for k in 0..NRES {
                    jac[(i * NRES + k, c)] = match who {
                        None => a[k][*j],
                        Some(w) if *w == i => b[k][*j],
                        _ => 0.0,
                    };
                }
                let _ = s;
            }
        }
        let cov = (jac.transpose() * &jac).try_inverse().unwrap();
        for a in 0..3 {
            for b in 0..3 {
                let rel = (cov[(a, b)] - sol.cov_g[(a, b)]).abs()
                    / cov[(a, a)].sqrt()
                    / cov[(b, b)].sqrt();
                assert!(
                    rel < 1e-6,
                    "({a},{b}): {} vs {}",
                    cov[(a, b)],
                    sol.cov_g[(a, b)]
                );
            }
        }
        // Local marginal variance of shot 0's spin equals the dense diagonal.
        let col = cols.iter().position(|c| *c == (1, Some(0))).unwrap();
        let rel = (cov[(col, col)] - sol.local_var[0][1]).abs() / cov[(col, col)];
        assert!(rel < 1e-6, "{} vs {}", cov[(col, col)], sol.local_var[0][1]);
    }

    #[test]
    fn recovers_noise_free_parameters_from_a_poor_start() {
        let truth = [0.88, 0.6, 0.55, 0.6];
        let shots: Vec<ShotData> = (0..12)
            .map(|i| {
                let psi = (10.0 + 5.0 * i as f64).to_radians();
                let a = closed::angles(&Shot::rolling(psi), &coefficients(&truth), Regime::SlipMu);
                ShotData {
                    row: i,
                    psi_meas: psi,
                    psi_sigma: 0.005,
                    meas: a.as_array(),
                    sigma: [0.005; 4],
                    frame_sigma: 0.0,
                    mass_ratio: 1.0,
                    spin0: 1.0,
                    english0: 0.0,
                    estimate_spin: false,
                }
            })
            .collect();
        let p = Problem {
            shots: shots.iter().collect(),
            regimes: vec![Regime::SlipMu; 12],
            free_global: [true, true, true, false],
            huber: None,
        };
        let start = State {
            g: [0.6, 0.3, 0.2, 0.6],
            l: shots.iter().map(|s| s.start_locals()).collect(),
        };
        let sol = p.solve(start, 100);
        assert!(sol.chi2 < 1e-12, "chi2 {}", sol.chi2);
        for k in 0..3 {
            assert!(
                (sol.state.g[k] - truth[k]).abs() < 1e-6,
                "{k}: {:?}",
                sol.state.g
            );
        }
    }
}
