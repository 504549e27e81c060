//! The least-squares problem of one material: per-shot data, parameters and weighted residuals.
//!
//! Global parameters `g = (e, mu, mu_table, mu_static)`; per-shot latent parameters
//! `l = (psi, r, s)`: the true impact angle (errors-in-variables) and, where estimated, the spin
//! `r = R omega/v` and English `s = R omega_z/v`. Each shot contributes a fixed block of
//! [`NRES`] normalised residuals:
//! `(angle_pred + a - angle_meas)/sigma` for `delta1, delta2, theta1, theta2` (wrapped to
//! `(-180°, 180°]`; zero where the angle is not measured or the prediction undefined),
//! `(psi + a - psi_meas)/sigma_psi`, for estimated spin weak priors `(r - 1)/SPIN_PRIOR_SIGMA`,
//! `s/ENGLISH_PRIOR_SIGMA` that keep an undetermined component finite (its posterior error then
//! stays near the prior width, which is how it is recognised as undetermined), and `a/sigma_a`.
//!
//! `a` is the photo's error in the direction of the line of centres, from which the extractor
//! reads all five angles, so it moves them all alike (`frame_err_deg`, its 1-sigma `sigma_a`;
//! the `sigma`s are then the angles' own, independent parts). Being linear, it is profiled out
//! in closed form for each evaluation: `a = Σ w_k d_k / (Σ w_k + 1/sigma_a²)` with `d_k` the
//! measured minus predicted angles and `w_k = 1/sigma_k²`. Where `sigma_a = 0` it is absent
//! and the angles are independent. Marginalising `a` gives each photo's angles the covariance
//! `diag(sigma_k²) + sigma_a² 1 1ᵀ`; the dof are unchanged (one residual, one parameter).

use crate::physics::wrap;
use crate::physics::{Coefficients, Regime, Shot, closed};

/// Number of global parameters (e, mu, mu_table, mu_static).
pub const NG: usize = 4;
/// Number of per-shot parameters (psi, spin, english).
pub const NL: usize = 3;
/// Residuals per shot: four angles, the psi prior, two spin priors and the shared shift's prior.
pub const NRES: usize = 8;
pub const GLOBAL_NAMES: [&str; NG] = ["e", "mu", "mu_table", "mu_static"];
/// Prior of an estimated spin: `r ~ N(1, 2²)` (rolling cue ball, wide).
pub const SPIN_PRIOR_MEAN: f64 = 1.0;
pub const SPIN_PRIOR_SIGMA: f64 = 2.0;
/// Prior of an estimated English: `s ~ N(0, 1²)`.
pub const ENGLISH_PRIOR_SIGMA: f64 = 1.0;

/// Box bounds of the globals: `0 ≤ e ≤ 1`, frictions in `[0, 3]`.
pub const GLOBAL_LO: [f64; NG] = [0.0, 0.0, 0.0, 0.0];
pub const GLOBAL_HI: [f64; NG] = [1.0, 3.0, 3.0, 3.0];
/// Bounds of the locals: `psi` in `[0, 89.9°]`, `r` in `[-6, 6]`, `s` in `[-4, 4]`.
pub const LOCAL_LO: [f64; NL] = [0.0, -6.0, -4.0];
pub const LOCAL_HI: [f64; NL] = [89.9 * std::f64::consts::PI / 180.0, 6.0, 4.0];

/// One usable shot, angles in radians.
#[derive(Debug, Clone, PartialEq)]
pub struct ShotData {
    /// Index of the row in the caller's table.
    pub row: usize,
    pub psi_meas: f64,
    /// 1-sigma of the measured psi; `0` fixes psi at its measured value.
    pub psi_sigma: f64,
    /// Measured `delta1, delta2, theta1, theta2`.
    pub meas: [Option<f64>; 4],
    pub sigma: [f64; 4],
    /// 1-sigma of the shared shift `a` of all five angles (the line of centres' direction);
    /// `0` where the angles' errors are independent. `sigma` and `psi_sigma` are then the
    /// independent parts.
    pub frame_sigma: f64,
    pub mass_ratio: f64,
    /// Known spin (or the starting value when estimated).
    pub spin0: f64,
    pub english0: f64,
    pub estimate_spin: bool,
}

impl ShotData {
    /// Which locals are free for this shot.
    pub fn free_locals(&self) -> [bool; NL] {
        [self.psi_sigma > 0.0, self.estimate_spin, self.estimate_spin]
    }

    /// Starting locals: measured psi, known or default spin.
    pub fn start_locals(&self) -> [f64; NL] {
        [self.psi_meas, self.spin0, self.english0]
    }

    /// Number of angle residuals that carry data.
    pub fn n_angles(&self) -> usize {
        self.meas.iter().filter(|m| m.is_some()).count()
    }

    pub fn shot(&self, l: &[f64; NL]) -> Shot {
        Shot {
            psi: l[0],
            mass_ratio: self.mass_ratio,
            spin: l[1],
            english: l[2],
        }
    }
}

pub fn coefficients(g: &[f64; NG]) -> Coefficients {
    Coefficients {
        e: g[0],
        mu: g[1],
        mu_table: g[2],
        mu_static: g[3],
    }
}

/// Normalised residuals of one shot (see the module doc).
pub fn residuals(s: &ShotData, g: &[f64; NG], l: &[f64; NL], regime: Regime) -> [f64; NRES] {
    let pred = closed::angles(&s.shot(l), &coefficients(g), regime).as_array();
    // Measured minus predicted, with its weight, for each angle that carries data.
    let mut d = [None; 5];
    for k in 0..4 {
        if let (Some(m), Some(p)) = (s.meas[k], pred[k]) {
            d[k] = Some((wrap(m - p), s.sigma[k]));
        }
    }
    if s.psi_sigma > 0.0 {
        d[4] = Some((s.psi_meas - l[0], s.psi_sigma));
    }
    let a = shared_shift(&d, s.frame_sigma);
    let mut out = [0.0; NRES];
    for (k, dk) in d.iter().enumerate() {
        if let Some((dk, sk)) = dk {
            out[k] = (a - dk) / sk;
        }
    }
    if s.estimate_spin {
        out[5] = (l[1] - SPIN_PRIOR_MEAN) / SPIN_PRIOR_SIGMA;
        out[6] = l[2] / ENGLISH_PRIOR_SIGMA;
    }
    if s.frame_sigma > 0.0 {
        out[7] = a / s.frame_sigma;
    }
    out
}

/// The shared shift `a` that minimises `Σ ((a - d_k)/sigma_k)² + (a/frame_sigma)²` over the
/// angles `(d_k, sigma_k)` present; 0 without a shared part.
fn shared_shift(d: &[Option<(f64, f64)>; 5], frame_sigma: f64) -> f64 {
    if frame_sigma <= 0.0 {
        return 0.0;
    }
    let (num, den) = d
        .iter()
        .flatten()
        .fold((0.0, frame_sigma.powi(-2)), |(n, w), (dk, sk)| {
            (n + dk / (sk * sk), w + 1.0 / (sk * sk))
        });
    num / den
}

/// The smallest static friction `mu0` at which the ball–ball contact of a shot with locals `l`
/// sticks (the two-regime model puts it in s–mu when `mu0 ≥` this, in mu–mu otherwise).
pub fn critical_mu_static(e: f64, l: &[f64; NL]) -> f64 {
    // Ball–ball contact sticks iff mu0 (1+e) cos psi ≥ (2/7) |(sin psi + s, r cos psi)|,
    // i.e. iff mu0 ≥ c with c below (Eq. 50 generalised to any spin).
    let (sp, cp) = l[0].sin_cos();
    let g = (sp + l[2]).hypot(l[1] * cp);
    2.0 * g / (7.0 * (1.0 + e) * cp.max(1e-12))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_maps_into_half_open_interval() {
        use std::f64::consts::PI;
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap(-PI) - PI).abs() < 1e-12);
        assert!((wrap(0.25) - 0.25).abs() < 1e-15);
    }

    #[test]
    fn residuals_vanish_at_truth() {
        let g = [0.92, 0.14, 0.15, 0.18];
        let psi = 0.5;
        let shot = Shot::rolling(psi);
        let a = closed::angles(&shot, &coefficients(&g), Regime::MuMu).as_array();
        let s = ShotData {
            row: 0,
            psi_meas: psi,
            psi_sigma: 0.005,
            meas: a,
            sigma: [0.005; 4],
            frame_sigma: 0.0,
            mass_ratio: 1.0,
            spin0: 1.0,
            english0: 0.0,
            estimate_spin: false,
        };
        let r = residuals(&s, &g, &s.start_locals(), Regime::MuMu);
        assert!(r.iter().all(|x| x.abs() < 1e-9), "{r:?}");
        // A 0.01 rad error in delta1 is two sigma.
        let mut s2 = s.clone();
        s2.meas[0] = Some(a[0].unwrap() + 0.01);
        let r2 = residuals(&s2, &g, &s.start_locals(), Regime::MuMu);
        assert!((r2[0] + 2.0).abs() < 1e-9);
        // Critical mu0 of a rolling shot reproduces Eq. (50): c = 2/(7(1+e) cos psi).
        let c = critical_mu_static(0.92, &s.start_locals());
        assert!((c - 2.0 / (7.0 * 1.92 * psi.cos())).abs() < 1e-12);
    }

    #[test]
    fn a_shift_shared_by_every_angle_is_profiled_out() {
        // All five angles read 0.01 rad high (psi too, so the predicted angles are those of the
        // true psi): with a shared part of 0.05 rad the shift is the photo's, and only its prior
        // and the remainder 0.01 (n/s²)/(n/s² + 1/f²) - 0.01 show; treated as independent,
        // each angle is 10 sigma off.
        let g = [0.92, 0.14, 0.15, 0.18];
        let psi = 0.5;
        let a = closed::angles(&Shot::rolling(psi), &coefficients(&g), Regime::MuMu).as_array();
        let (c, s, f) = (0.01, 0.001, 0.05);
        let mut shot = ShotData {
            row: 0,
            psi_meas: psi + c,
            psi_sigma: s,
            meas: a.map(|x| x.map(|v| v + c)),
            sigma: [s; 4],
            frame_sigma: f,
            mass_ratio: 1.0,
            spin0: 1.0,
            english0: 0.0,
            estimate_spin: false,
        };
        let l = [psi, 1.0, 0.0];
        let w = 5.0 / (s * s);
        let shift = c * w / (w + 1.0 / (f * f));
        let r = residuals(&shot, &g, &l, Regime::MuMu);
        for k in 0..5 {
            assert!(((r[k] - (shift - c) / s) / r[k]).abs() < 1e-6, "{k}: {r:?}");
        }
        assert!((r[7] - shift / f).abs() < 1e-9, "{r:?}");
        assert!(r[..5].iter().all(|x| x.abs() < 1e-3), "{r:?}");
        shot.frame_sigma = 0.0;
        let r = residuals(&shot, &g, &l, Regime::MuMu);
        for k in 0..5 {
            assert!((r[k] + 10.0).abs() < 1e-6, "{k}: {r:?}");
        }
        assert!(r[7].abs() < f64::MIN_POSITIVE, "{r:?}");
    }
}
