//! The least-squares problem of one material: per-shot data, parameters and weighted residuals.
//!
//! Global parameters `g = (e, mu, mu_table, mu_static)`; per-shot latent parameters
//! `l = (psi, r, s)`: the true impact angle (errors-in-variables) and, where estimated, the spin
//! `r = R omega/v` and English `s = R omega_z/v`. Each shot contributes a fixed block of
//! [`NRES`] normalised residuals:
//! `(angle_pred - angle_meas)/sigma` for `delta1, delta2, theta1, theta2` (wrapped to
//! `(-180°, 180°]`; zero where the angle is not measured or the prediction undefined),
//! `(psi - psi_meas)/sigma_psi`, and, for estimated spin, weak priors `(r - 1)/SPIN_PRIOR_SIGMA`,
//! `s/ENGLISH_PRIOR_SIGMA` that keep an undetermined component finite (its posterior error then
//! stays near the prior width, which is how it is recognised as undetermined).

use crate::physics::{Coefficients, Regime, Shot, closed};

/// Number of global parameters (e, mu, mu_table, mu_static).
pub const NG: usize = 4;
/// Number of per-shot parameters (psi, spin, english).
pub const NL: usize = 3;
/// Residuals per shot: four angles, the psi prior and two spin priors.
pub const NRES: usize = 7;
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

/// Wraps an angle difference into `(-pi, pi]`.
pub fn wrap(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    // A difference of two principal angles is within (-2 pi, 2 pi), where the remainder is the
    // identity: skipping it gives the same value (the remainder took ~6 % of a fit's time).
    let mut x = if a.abs() < two_pi { a } else { a % two_pi };
    if x > std::f64::consts::PI {
        x -= two_pi;
    } else if x <= -std::f64::consts::PI {
        x += two_pi;
    }
    x
}

/// Normalised residuals of one shot (see the module doc).
pub fn residuals(s: &ShotData, g: &[f64; NG], l: &[f64; NL], regime: Regime) -> [f64; NRES] {
    let pred = closed::angles(&s.shot(l), &coefficients(g), regime).as_array();
    let mut out = [0.0; NRES];
    for k in 0..4 {
        if let (Some(m), Some(p)) = (s.meas[k], pred[k]) {
            out[k] = wrap(p - m) / s.sigma[k];
        }
    }
    if s.psi_sigma > 0.0 {
        out[4] = (l[0] - s.psi_meas) / s.psi_sigma;
    }
    if s.estimate_spin {
        out[5] = (l[1] - SPIN_PRIOR_MEAN) / SPIN_PRIOR_SIGMA;
        out[6] = l[2] / ENGLISH_PRIOR_SIGMA;
    }
    out
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
}
