//! Theory curves for the figures: the four post-impact directions swept over the impact angle.
//!
//! Every point comes from [`impulse::solve`] (the 3-D impulse–momentum model, the project's source
//! of truth) for a cue ball with fixed spin `r`, English `s` and mass ratio `M`; the regime is either
//! forced (the paper draws each regime's curve over the whole `psi` range, Figs. 10, 11) or chosen
//! by the stick/slip conditions with the static friction `mu0` (`auto`, which produces the `psi_L`
//! jump of Figs. 12, 13 when `mu0 != mu`). Angles are returned in degrees.

use crate::physics::{Coefficients, Regime, RegimeChoice, Shot, impulse};

/// A sweep over `psi` (degrees) with the regime used at each sample.
#[derive(Debug, Clone)]
pub struct Sweep {
    pub psi_deg: Vec<f64>,
    pub regime: Vec<Regime>,
    /// `[delta1, delta2, theta1, theta2]` in degrees; `None` where a ball is at rest.
    pub angles_deg: Vec<[Option<f64>; 4]>,
}

/// Index of each angle in [`Sweep::angles_deg`].
pub const DELTA1: usize = 0;
pub const DELTA2: usize = 1;
pub const THETA1: usize = 2;
pub const THETA2: usize = 3;

/// Samples `psi` from `lo_deg` to `hi_deg` (inclusive) in `n` steps.
pub fn sweep(
    c: &Coefficients,
    template: &Shot,
    choice: RegimeChoice,
    (lo_deg, hi_deg): (f64, f64),
    n: usize,
) -> Sweep {
    let n = n.max(2);
    let mut out = Sweep {
        psi_deg: Vec::with_capacity(n + 1),
        regime: Vec::with_capacity(n + 1),
        angles_deg: Vec::with_capacity(n + 1),
    };
    for i in 0..=n {
        let psi_deg = lo_deg + (hi_deg - lo_deg) * i as f64 / n as f64;
        let shot = Shot {
            psi: psi_deg.to_radians(),
            ..*template
        };
        let state = impulse::solve(&shot, c, choice);
        out.psi_deg.push(psi_deg);
        out.regime.push(state.regime);
        out.angles_deg.push(state.angles().to_degrees());
    }
    out
}

impl Sweep {
    /// Samples `(x, y, break_before)` for a plot line: `f(psi_deg, angles)` gives the point, and
    /// a change of regime between neighbours breaks the line (a jump is not a steep slope).
    pub fn samples(
        &self,
        f: impl Fn(f64, &[Option<f64>; 4]) -> Option<(f64, f64)>,
    ) -> Vec<(f64, Option<f64>, bool)> {
        let mut out = Vec::with_capacity(self.psi_deg.len());
        for i in 0..self.psi_deg.len() {
            let brk = i > 0 && self.regime[i] != self.regime[i - 1];
            match f(self.psi_deg[i], &self.angles_deg[i]) {
                Some((x, y)) => out.push((x, Some(y), brk)),
                None => out.push((f64::NAN, None, brk)),
            }
        }
        out
    }

    /// The regimes met along the sweep, in order of first appearance.
    pub fn regimes(&self) -> Vec<Regime> {
        let mut out: Vec<Regime> = Vec::new();
        for r in &self.regime {
            if !out.contains(r) {
                out.push(*r);
            }
        }
        out
    }
}

/// Human-readable list of regimes, e.g. `s–μ → μ–μ`.
pub fn regime_path(regimes: &[Regime]) -> String {
    regimes
        .iter()
        .map(|r| pretty_regime(*r))
        .collect::<Vec<_>>()
        .join(" → ")
}

/// The paper's typography for a regime name (`μ–μ`, `s–μ`, `μ–s`, `s–s`).
pub fn pretty_regime(r: Regime) -> &'static str {
    match r {
        Regime::MuMu => "μ–μ",
        Regime::SlipMu => "s–μ",
        Regime::MuSlip => "μ–s",
        Regime::SlipSlip => "s–s",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frictionless_rolling_sweep_follows_the_30_degree_rule() {
        // mu = mu' = 0, e = 1, rolling: tan theta1 = 3.5 tan psi (PHYSICS.md).
        let c = Coefficients::new(1.0, 0.0, 0.0);
        let s = sweep(
            &c,
            &Shot::rolling(0.0),
            RegimeChoice::Auto,
            (10.0, 80.0),
            14,
        );
        assert_eq!(s.psi_deg.len(), 15);
        for (psi, a) in s.psi_deg.iter().zip(&s.angles_deg) {
            let theta1 = a[THETA1].unwrap();
            let expect = (3.5 * psi.to_radians().tan()).atan().to_degrees();
            assert!(
                (theta1 - expect).abs() < 1e-9,
                "psi {psi}: {theta1} vs {expect}"
            );
            assert!(a[DELTA2].unwrap().abs() < 1e-9);
        }
    }

    #[test]
    fn steel_auto_sweep_breaks_the_line_at_psi_l() {
        // Steel, Table 1: e 0.92, mu 0.14, mu' 0.15, mu0 0.18: s–mu below psi_L, mu–mu above.
        let c = Coefficients::new(0.92, 0.14, 0.15).with_static(0.18);
        let s = sweep(
            &c,
            &Shot::rolling(0.0),
            RegimeChoice::Auto,
            (1.0, 80.0),
            316,
        );
        let samples = s.samples(|p, a| a[DELTA2].map(|d| (p, d)));
        let breaks: Vec<f64> = samples.iter().filter(|s| s.2).map(|s| s.0).collect();
        assert_eq!(breaks.len(), 1, "one regime change, got {breaks:?}");
        let psi_l = crate::physics::regime::psi_limit_rolling(0.92, 0.18)
            .unwrap()
            .to_degrees();
        assert!(
            (breaks[0] - psi_l).abs() <= 0.25 + 1e-9,
            "{} vs {psi_l}",
            breaks[0]
        );
        assert_eq!(s.regimes(), vec![Regime::SlipMu, Regime::MuMu]);
        assert_eq!(regime_path(&s.regimes()), "s–μ → μ–μ");
    }
}
