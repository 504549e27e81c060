//! Closed-form angles of the paper, corrected, each as `atan2(numerator, denominator)`.
//!
//! With `v_o = R = 1`, `f = (1+e) cos psi` and `g = |(sin psi + s, r cos psi)|`, the ball–ball
//! impulse on ball 2 is `(f, h, -t)/(1+M)`:
//! - gross slip (`mu`): `h = mu f sin sigma`, `t = mu f cos sigma`, angular scale `k = 1`
//!   (Eqs. 16, 18–19; `tan sigma = (sin psi + s)/(r cos psi)`, Eq. 16 with the sidespin fix);
//! - slip–stick (`s`): `h = (2/7)(sin psi + s)`, `t = (2/7) r cos psi` (Eqs. 28–29),
//!   `k = 1 + (2/7) mu cos sigma` (Eq. 36).
//!
//! Every equation is multiplied through by `cos psi` (and other positive factors) so that
//! `psi → 90°` and `M = e` give exact, finite angles. The printed forms that differ from the
//! derivation are listed in `docs/physics.md`; the forms here are the derived ones and agree with
//! [`super::impulse`] to rounding (tests).

use super::{Coefficients, Regime, Shot, ShotAngles, direction};

const TWO_SEVENTHS: f64 = 2.0 / 7.0;

/// Ball–ball contact terms shared by the closed forms and the regime conditions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactTerms {
    pub sin_psi: f64,
    pub cos_psi: f64,
    pub sin_sigma: f64,
    pub cos_sigma: f64,
    /// `(1+e) cos psi`: normal impulse times `(1+M)`.
    pub f: f64,
    /// Horizontal tangential impulse on ball 2 times `(1+M)`.
    pub h: f64,
    /// Downward tangential impulse on ball 2 times `(1+M)`.
    pub t: f64,
    /// Angular-impulse scale of the ball–ball contact.
    pub k: f64,
}

impl ContactTerms {
    pub fn new(shot: &Shot, c: &Coefficients, stick: bool) -> Self {
        let (sin_psi, cos_psi) = shot.psi.sin_cos();
        let gy = sin_psi + shot.english;
        let gz = shot.spin * cos_psi;
        let g = (gy * gy + gz * gz).sqrt();
        let (sin_sigma, cos_sigma) = if g > 0.0 {
            (gy / g, gz / g)
        } else {
            (0.0, 0.0)
        };
        let f = (1.0 + c.e) * cos_psi;
        if stick {
            Self {
                sin_psi,
                cos_psi,
                sin_sigma,
                cos_sigma,
                f,
                h: TWO_SEVENTHS * gy,
                t: TWO_SEVENTHS * gz,
                k: 1.0 + TWO_SEVENTHS * c.mu * cos_sigma,
            }
        } else {
            Self {
                sin_psi,
                cos_psi,
                sin_sigma,
                cos_sigma,
                f,
                h: c.mu * f * sin_sigma,
                t: c.mu * f * cos_sigma,
                k: 1.0,
            }
        }
    }

    /// Slip of ball 2's bottom point after the ball–ball impulse, times `(1+M)/M`:
    /// `(f + (5/2) k t, h)` (Eqs. 17 and 36).
    pub fn table_slip(&self) -> (f64, f64) {
        (self.f + 2.5 * self.k * self.t, self.h)
    }

    /// Table normal impulse times `(1+M)`: the downward push, or zero if ball 2 is lifted.
    pub fn table_normal(&self) -> f64 {
        self.t.max(0.0)
    }
}

/// A direction written as the paper writes a tangent: numerator over denominator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tangent {
    pub num: f64,
    pub den: f64,
}

impl Tangent {
    fn angle(self) -> Option<f64> {
        direction(self.den, self.num, 1.0)
    }
}

/// `tan delta1`: Eq. (22) (gross slip) or Eq. (35) (slip–stick), times `cos psi`.
pub fn tan_delta1(shot: &Shot, c: &Coefficients, regime: Regime) -> Tangent {
    delta1_of(
        shot,
        c,
        regime,
        &ContactTerms::new(shot, c, regime.ball_ball_stick()),
    )
}

fn delta1_of(shot: &Shot, c: &Coefficients, regime: Regime, ct: &ContactTerms) -> Tangent {
    let m = shot.mass_ratio;
    let (sp, cp) = (ct.sin_psi, ct.cos_psi);
    if regime.ball_ball_stick() {
        Tangent {
            num: (m + 5.0 / 7.0) * sp - TWO_SEVENTHS * shot.english,
            den: (m - c.e) * cp,
        }
    } else {
        Tangent {
            num: (1.0 + m) * sp - c.mu * (1.0 + c.e) * ct.sin_sigma * cp,
            den: (m - c.e) * cp,
        }
    }
}

/// `tan theta1`: Eq. (24) (gross slip) or Eq. (40) corrected (slip–stick), times `cos psi`.
/// Eq. (40) as printed lacks the factor `(1+M)` on the spin term of its numerator.
pub fn tan_theta1(shot: &Shot, c: &Coefficients, regime: Regime) -> Tangent {
    theta1_of(
        shot,
        c,
        regime,
        &ContactTerms::new(shot, c, regime.ball_ball_stick()),
    )
}

fn theta1_of(shot: &Shot, c: &Coefficients, regime: Regime, ct: &ContactTerms) -> Tangent {
    let m = shot.mass_ratio;
    let r = shot.spin;
    let (sp, cp) = (ct.sin_psi, ct.cos_psi);
    if regime.ball_ball_stick() {
        Tangent {
            num: ((m + 5.0 / 7.0) + 0.4 * (1.0 + m) * r) * sp - TWO_SEVENTHS * shot.english,
            den: (m - c.e + 0.4 * (1.0 + m) * r - TWO_SEVENTHS * ct.k * r) * cp,
        }
    } else {
        let muf = c.mu * (1.0 + c.e);
        Tangent {
            num: (1.0 + m) * (2.5 + r) * sp - 2.5 * muf * ct.sin_sigma * cp,
            den: ((1.0 + m) * r + 2.5 * (m - c.e) - 2.5 * muf * ct.cos_sigma) * cp,
        }
    }
}

/// `tan delta2` for each regime: Eq. (23) (mu–mu), Eq. (39) corrected (s–mu: no `mu` term),
/// Eq. (44) (s–s), Eq. (48) (mu–s). Table friction acts only while ball 2 is pressed down.
pub fn tan_delta2(shot: &Shot, c: &Coefficients, regime: Regime) -> Tangent {
    delta2_of(
        shot,
        c,
        regime,
        &ContactTerms::new(shot, c, regime.ball_ball_stick()),
    )
}

fn delta2_of(shot: &Shot, c: &Coefficients, regime: Regime, ct: &ContactTerms) -> Tangent {
    let (sp, cp) = (ct.sin_psi, ct.cos_psi);
    let (cx, cy) = ct.table_slip();
    let cn = (cx * cx + cy * cy).sqrt();
    let (sin_phi, cos_phi) = if cn > 0.0 {
        (cy / cn, cx / cn)
    } else {
        (0.0, 0.0)
    };
    let r = shot.spin;
    let mu_t = c.mu_table;
    match regime {
        Regime::MuMu => {
            let cs = ct.cos_sigma.max(0.0);
            Tangent {
                num: c.mu * (ct.sin_sigma - mu_t * cs * sin_phi),
                den: 1.0 - c.mu * mu_t * cs * cos_phi,
            }
        }
        Regime::SlipMu => {
            let rp = r.max(0.0);
            Tangent {
                num: sp + shot.english - mu_t * rp * cp * sin_phi,
                den: (3.5 * (1.0 + c.e) - mu_t * rp * cos_phi) * cp,
            }
        }
        Regime::SlipSlip => Tangent {
            num: sp + shot.english,
            den: (3.5 * (1.0 + c.e) - ct.k * r) * cp,
        },
        Regime::MuSlip => Tangent {
            num: c.mu * ct.sin_sigma,
            den: 1.0 - c.mu * ct.cos_sigma,
        },
    }
}

/// `tan theta2` for each regime: Eq. (25) (mu–mu), Eq. (41) corrected (s–mu, with the
/// `cos sigma` of Eq. 36), and the derived mu–s and s–s forms that replace Eqs. (49) and (45).
pub fn tan_theta2(shot: &Shot, c: &Coefficients, regime: Regime) -> Tangent {
    theta2_of(
        shot,
        c,
        regime,
        &ContactTerms::new(shot, c, regime.ball_ball_stick()),
    )
}

fn theta2_of(shot: &Shot, c: &Coefficients, regime: Regime, ct: &ContactTerms) -> Tangent {
    let (sp, cp) = (ct.sin_psi, ct.cos_psi);
    let r = shot.spin;
    // (7/2) times the table-stick factor (25 + 10 k_t)/35 with k_t = 1 + (2/7) mu'.
    let kt = 3.5 + TWO_SEVENTHS * c.mu_table;
    let back = 3.5 - (5.0 / 7.0) * c.mu_table;
    match regime {
        Regime::MuMu => Tangent {
            num: c.mu * ct.sin_sigma,
            den: 1.0 - c.mu * ct.cos_sigma,
        },
        Regime::SlipMu => Tangent {
            num: sp + shot.english,
            den: (3.5 * (1.0 + c.e) - ct.k * r) * cp,
        },
        Regime::MuSlip => Tangent {
            num: kt * c.mu * ct.sin_sigma,
            den: kt - back * c.mu * ct.cos_sigma,
        },
        Regime::SlipSlip => Tangent {
            num: kt * (sp + shot.english),
            den: (3.5 * (1.0 + c.e) * kt - back * ct.k * r) * cp,
        },
    }
}

/// The auto regime and its four angles, sharing one evaluation of the contact terms: the fast
/// path used inside fits.
pub fn predict_auto(shot: &Shot, c: &Coefficients) -> (Regime, ShotAngles) {
    let bb = super::regime::ball_ball_sticks(shot, c);
    let ct = ContactTerms::new(shot, c, bb);
    let table = super::regime::table_margin_of(shot, c, &ct) >= 0.0;
    let regime = Regime::from_contacts(bb, table);
    (regime, angles_of(shot, c, regime, &ct))
}

/// All four angles from the closed forms in the given regime. For `M = 0` ball 2 does not move
/// and its angles are undefined.
pub fn angles(shot: &Shot, c: &Coefficients, regime: Regime) -> ShotAngles {
    angles_of(
        shot,
        c,
        regime,
        &ContactTerms::new(shot, c, regime.ball_ball_stick()),
    )
}

fn angles_of(shot: &Shot, c: &Coefficients, regime: Regime, ct: &ContactTerms) -> ShotAngles {
    let ball2 = shot.mass_ratio > 0.0;
    ShotAngles {
        delta1: delta1_of(shot, c, regime, ct).angle(),
        theta1: theta1_of(shot, c, regime, ct).angle(),
        delta2: if ball2 {
            delta2_of(shot, c, regime, ct).angle()
        } else {
            None
        },
        theta2: if ball2 {
            theta2_of(shot, c, regime, ct).angle()
        } else {
            None
        },
    }
}
