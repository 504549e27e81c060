//! Regime selection and the limit angles `psi_L` where a contact changes from stick to slip.
//!
//! Ball–ball contact (static friction `mu0`): it sticks when the friction limit can absorb the
//! no-slip impulse, `mu0 (1+e) cos psi ≥ (2/7) sqrt((sin psi + s)² + r² cos² psi)`; for a rolling
//! cue ball without sidespin this is Eq. (50), `cos psi_L = 2 / (7 mu0 (1+e))`, independent of `M`.
//! Ball 2–table contact (friction `mu'`, normal impulse `N = max(t, 0)`): it sticks when
//! `mu' N ≥ (2/7) |c|` with `c` the slip of ball 2's bottom point after the ball–ball impulse.
//! With gross slip at the ball–ball contact and `r = 1, s = 0` this is Eq. (51), whose printed
//! coefficient `4/49` must read `49/4`; with slip–stick it is Eq. (53) with `mu` read as `mu'`.

use super::closed::ContactTerms;
use super::{Coefficients, Regime, Shot};

const TWO_SEVENTHS: f64 = 2.0 / 7.0;

/// Does the ball–ball contact stick (slip–stick regime) for this shot?
pub fn ball_ball_sticks(shot: &Shot, c: &Coefficients) -> bool {
    ball_ball_margin(shot, c) >= 0.0
}

/// `mu0 (1+e) cos psi - (2/7) g`: positive where the ball–ball contact sticks.
pub fn ball_ball_margin(shot: &Shot, c: &Coefficients) -> f64 {
    let (sp, cp) = shot.psi.sin_cos();
    let (gy, gz) = (sp + shot.english, shot.spin * cp);
    let g = (gy * gy + gz * gz).sqrt();
    c.mu_static * (1.0 + c.e) * cp - TWO_SEVENTHS * g
}

/// `mu' N - (2/7)|c|` given the ball–ball regime: positive where the table contact sticks.
pub fn table_margin(shot: &Shot, c: &Coefficients, ball_ball_stick: bool) -> f64 {
    if shot.mass_ratio == 0.0 {
        return f64::NEG_INFINITY;
    }
    table_margin_of(shot, c, &ContactTerms::new(shot, c, ball_ball_stick))
}

/// [`table_margin`] from already computed contact terms.
pub fn table_margin_of(shot: &Shot, c: &Coefficients, ct: &ContactTerms) -> f64 {
    let n = ct.table_normal();
    if shot.mass_ratio == 0.0 || n <= 0.0 {
        return f64::NEG_INFINITY;
    }
    let (cx, cy) = ct.table_slip();
    c.mu_table * n - TWO_SEVENTHS * (cx * cx + cy * cy).sqrt()
}

/// The regime the stick/slip conditions select (the `auto` choice).
pub fn select_regime(shot: &Shot, c: &Coefficients) -> Regime {
    let bb = ball_ball_sticks(shot, c);
    let table = table_margin(shot, c, bb) >= 0.0;
    Regime::from_contacts(bb, table)
}

/// Eq. (50): the ball–ball limit angle for a rolling cue ball without sidespin, in radians.
/// `None` when `2/(7 mu0 (1+e)) > 1`: no real angle, gross slip at every `psi`.
pub fn psi_limit_rolling(e: f64, mu_static: f64) -> Option<f64> {
    let c = 2.0 / (7.0 * mu_static * (1.0 + e));
    (c.is_finite() && c <= 1.0).then(|| c.acos())
}

/// Eq. (53) (corrected to `mu'`): limit of the table contact when the ball–ball contact sticks,
/// rolling cue ball, no sidespin. Below it the table sticks (s–s). `None` if it never sticks.
pub fn psi_limit_table_after_stick(e: f64, mu: f64, mu_table: f64) -> Option<f64> {
    // The angular scale k = 1 + (2/7) mu cos psi depends on psi (the printed form takes k = 1),
    // so the root is found numerically.
    let shot = |psi: f64| Shot::rolling(psi);
    let c = Coefficients::new(e, mu, mu_table);
    boundaries(|psi| table_margin(&shot(psi), &c, true))
        .first()
        .copied()
}

/// Eq. (51) corrected: table limit under gross slip at the ball–ball contact, rolling cue ball,
/// no sidespin: `mu² (21/4 - (49/4) mu'²) cos² psi + 5 mu cos psi + 1 + mu² = 0`. Returns the
/// root in `[0°, 90°)`, below which the table sticks (mu–s), if any.
pub fn psi_limit_table_after_slip(mu: f64, mu_table: f64) -> Option<f64> {
    let a = mu * mu * (5.25 - 12.25 * mu_table * mu_table);
    let b = 5.0 * mu;
    let cc = 1.0 + mu * mu;
    let disc = b * b - 4.0 * a * cc;
    if a == 0.0 || disc < 0.0 {
        return None;
    }
    let roots = [
        (-b + disc.sqrt()) / (2.0 * a),
        (-b - disc.sqrt()) / (2.0 * a),
    ];
    roots
        .into_iter()
        .filter(|x| (0.0..=1.0).contains(x))
        .map(f64::acos)
        .reduce(f64::min)
}

/// Impact angles in `(0, 90°)` where a margin function changes sign, found by a scan of 2,000
/// steps refined by bisection to 1e-13 rad.
pub fn boundaries(margin: impl Fn(f64) -> f64) -> Vec<f64> {
    let n = 2000;
    let hi = std::f64::consts::FRAC_PI_2 * (1.0 - 1e-12);
    let mut out = Vec::new();
    let mut a = 0.0;
    let mut fa = margin(a) >= 0.0;
    for i in 1..=n {
        let b = hi * i as f64 / n as f64;
        let fb = margin(b) >= 0.0;
        if fb != fa {
            let (mut lo, mut up) = (a, b);
            while up - lo > 1e-13 {
                let mid = 0.5 * (lo + up);
                if (margin(mid) >= 0.0) == fa {
                    lo = mid;
                } else {
                    up = mid;
                }
            }
            out.push(0.5 * (lo + up));
        }
        a = b;
        fa = fb;
    }
    out
}

/// A change of the auto regime along `psi` for fixed spin and coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegimeBoundary {
    /// Impact angle of the change, radians.
    pub psi: f64,
    pub below: Regime,
    pub above: Regime,
}

/// Every `psi_L` where the auto regime changes, for a cue ball with the given spin and mass ratio.
pub fn regime_boundaries(template: &Shot, c: &Coefficients) -> Vec<RegimeBoundary> {
    let at = |psi: f64| select_regime(&Shot { psi, ..*template }, c);
    let mut out = Vec::new();
    // Each contact's margin changes sign separately; merge them.
    let mut psis = boundaries(|p| {
        ball_ball_margin(
            &Shot {
                psi: p,
                ..*template
            },
            c,
        )
    });
    psis.extend(boundaries(|p| {
        let s = Shot {
            psi: p,
            ..*template
        };
        table_margin(&s, c, ball_ball_sticks(&s, c))
    }));
    psis.sort_by(f64::total_cmp);
    psis.dedup_by(|a, b| (*a - *b).abs() < 1e-10);
    for psi in psis {
        let (below, above) = (at(psi - 1e-9), at(psi + 1e-9));
        if below != above {
            out.push(RegimeBoundary { psi, below, above });
        }
    }
    out
}
