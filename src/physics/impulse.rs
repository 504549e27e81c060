//! Impulse–momentum model of the impact, in 3-D vectors: the source of truth.
//!
//! Units: `v_o = 1`, `R = 1`, `m1 = 1`, so `1/m2 = M` and `I_j = (2/5) m_j`. Two steps, as in the
//! paper: (1) the ball–ball impulse `P` on ball 2 (ball 1 receives `-P`) at the contact point
//! `±R x`, normal part `P_n = (1+e) g_n / (n·K n)` with the collision matrix `K`; tangential part
//! `mu P_n ĝ_t` in gross slip, or the no-slip impulse `K_tt⁻¹ g_t` in slip–stick, whose angular
//! impulse is scaled by `k = 1 + (2/7) mu cos sigma` (Eqs. 32–33, 36), with
//! `cos sigma = -ĝ_t·z`; (2) the table impulse on ball 2 at `-R z`: normal `N = max(P_down, 0)`
//! (a ball lifted by draw leaves the cloth and feels no table friction), friction `-mu' N ĉ`
//! against the slip `c` of its bottom point in gross slip, or the no-slip `-(2/7) m2 c` with angular
//! impulse scaled by `1 + (2/7) mu'` in slip–stick. Ball 1 loses contact with the table when lifted;
//! when draw presses it down, the table's normal impulse cancels its vertical velocity (its
//! friction is neglected, as in the paper). Rolling velocities follow from conservation of angular
//! momentum about the table contact point (Eqs. 14–15).

use super::regime::select_regime;
use super::{Coefficients, Regime, RegimeChoice, Shot, ShotAngles, direction};
use nalgebra::{Matrix3, Vector3};

/// Everything the impact does, for diagnostics and for the path model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactState {
    pub regime: Regime,
    /// Ball 1 (cue ball) just after the impact: linear and angular velocity (units `v_o`, `v_o/R`).
    pub v1: Vector3<f64>,
    pub w1: Vector3<f64>,
    /// Ball 2 (object ball) just after the impact.
    pub v2: Vector3<f64>,
    pub w2: Vector3<f64>,
    /// Horizontal rolling velocities once pure rolling is reached.
    pub v1_roll: Vector3<f64>,
    pub v2_roll: Vector3<f64>,
    /// Ball–ball impulse on ball 2 (units `m1 v_o`).
    pub ball_ball_impulse: Vector3<f64>,
    /// Table impulse on ball 2 (normal and friction).
    pub table_impulse: Vector3<f64>,
    /// Kinetic energy (translational + rotational, 3-D) before and after, units `m1 v_o²`.
    pub energy_before: f64,
    pub energy_after: f64,
}

impl ImpactState {
    /// The four reported directions; undefined where a ball is at rest.
    pub fn angles(&self) -> ShotAngles {
        let dir = |v: &Vector3<f64>| direction(v.x, v.y, 1.0);
        let massive = self.v2.norm() > 0.0 || self.v2_roll.norm() > 0.0;
        ShotAngles {
            delta1: dir(&self.v1),
            theta1: dir(&self.v1_roll),
            delta2: if massive { dir(&self.v2) } else { None },
            theta2: if massive { dir(&self.v2_roll) } else { None },
        }
    }

    /// True if the regime's assumptions create kinetic energy (see `docs/physics.md`).
    pub fn gains_energy(&self) -> bool {
        self.energy_after > self.energy_before * (1.0 + 1e-12)
    }
}

/// One rigid ball in the dimensionless units of this module.
#[derive(Debug, Clone, Copy)]
struct Ball {
    inv_mass: f64,
    v: Vector3<f64>,
    w: Vector3<f64>,
}

impl Ball {
    /// Inverse moment of inertia of a solid sphere of radius 1: `1/I = (5/2)/m`.
    fn inv_inertia(&self) -> f64 {
        2.5 * self.inv_mass
    }

    fn point_velocity(&self, r: &Vector3<f64>) -> Vector3<f64> {
        self.v + self.w.cross(r)
    }

    /// Applies impulse `p` at offset `r`; its angular part scaled by `k` (the slip–stick rule).
    fn apply(&mut self, r: &Vector3<f64>, p: &Vector3<f64>, k: f64) {
        self.v += self.inv_mass * p;
        self.w += k * self.inv_inertia() * r.cross(p);
    }

    /// `K` with `Δ(point velocity) = K p` for an impulse `p` at offset `r`.
    fn compliance(&self, r: &Vector3<f64>) -> Matrix3<f64> {
        let mut k = Matrix3::zeros();
        for i in 0..3 {
            let mut e = Vector3::zeros();
            e[i] = 1.0;
            let col = self.inv_mass * e + self.inv_inertia() * r.cross(&e).cross(r);
            k.set_column(i, &col);
        }
        k
    }

    fn energy(&self) -> f64 {
        if self.inv_mass == 0.0 {
            return 0.0;
        }
        let m = 1.0 / self.inv_mass;
        0.5 * m * self.v.norm_squared() + 0.5 * (0.4 * m) * self.w.norm_squared()
    }

    /// Horizontal velocity once rolling: `L_h` about the contact point is conserved and the
    /// rolling ball has `L_h = (I + m) (z × v*)`, so `v* = -z × L_h / (I + m)` (per unit mass).
    fn rolling_velocity(&self) -> Vector3<f64> {
        let z = Vector3::z();
        // Per unit mass: L/m = (2/5) w + (z × v) (centre sits at +z from the contact point).
        let mut l = 0.4 * self.w + z.cross(&self.v);
        l.z = 0.0;
        -z.cross(&l) / 1.4
    }
}

/// Incoming cue-ball and object-ball states for `shot` in the impact frame.
fn initial_balls(shot: &Shot) -> (Ball, Ball) {
    let (sp, cp) = shot.psi.sin_cos();
    let b1 = Ball {
        inv_mass: 1.0,
        v: Vector3::new(cp, sp, 0.0),
        w: Vector3::new(-shot.spin * sp, shot.spin * cp, shot.english),
    };
    let b2 = Ball {
        inv_mass: shot.mass_ratio,
        v: Vector3::zeros(),
        w: Vector3::zeros(),
    };
    (b1, b2)
}

/// Ball–ball impulse on ball 2 and its angular scale for a given contact regime, or the stick
/// test's answer when `stick` is `None`. Returns (impulse, angular scale, stick used).
fn ball_ball_impulse(
    b1: &Ball,
    b2: &Ball,
    c: &Coefficients,
    stick: Option<bool>,
) -> (Vector3<f64>, f64, bool) {
    let n = Vector3::x();
    let (r1, r2) = (n, -n);
    let g = b1.point_velocity(&r1) - b2.point_velocity(&r2);
    let k = b1.compliance(&r1) + b2.compliance(&r2);
    let pn = (1.0 + c.e) * g.dot(&n) / n.dot(&(k * n));
    let gt = g - g.dot(&n) * n;
    // Tangential no-slip impulse: solve K restricted to the tangent plane (y, z).
    let ktt = k.fixed_view::<2, 2>(1, 1).into_owned();
    let stick_t = ktt
        .try_inverse()
        .map(|inv| inv * gt.fixed_rows::<2>(1).into_owned())
        .unwrap_or_default();
    let p_stick = Vector3::new(0.0, stick_t[0], stick_t[1]);
    let gt_norm = gt.norm();
    let stick = stick.unwrap_or(p_stick.norm() <= c.mu_static * pn);
    let cos_sigma = if gt_norm > 0.0 { -gt.z / gt_norm } else { 0.0 };
    if stick {
        (pn * n + p_stick, 1.0 + (2.0 / 7.0) * c.mu * cos_sigma, true)
    } else {
        let pt = if gt_norm > 0.0 {
            c.mu * pn * gt / gt_norm
        } else {
            Vector3::zeros()
        };
        (pn * n + pt, 1.0, false)
    }
}

/// Table impulse on ball 2 at its bottom point after the ball–ball impulse `p` acted.
fn table_impulse(
    b2: &Ball,
    p: &Vector3<f64>,
    c: &Coefficients,
    stick: Option<bool>,
) -> (Vector3<f64>, f64, bool) {
    let normal = (-p.z).max(0.0);
    if b2.inv_mass == 0.0 {
        return (Vector3::new(0.0, 0.0, normal), 1.0, stick.unwrap_or(false));
    }
    let rb = -Vector3::z();
    let mut slip = b2.point_velocity(&rb);
    slip.z = 0.0;
    let kb = b2.compliance(&rb);
    let kh = kb.fixed_view::<2, 2>(0, 0).into_owned();
    let q_stick_h = kh
        .try_inverse()
        .map(|inv| -(inv * slip.fixed_rows::<2>(0).into_owned()))
        .unwrap_or_default();
    let q_stick = Vector3::new(q_stick_h[0], q_stick_h[1], 0.0);
    let stick = stick.unwrap_or(normal > 0.0 && q_stick.norm() <= c.mu_table * normal);
    let z = Vector3::new(0.0, 0.0, normal);
    if stick {
        (q_stick + z, 1.0 + (2.0 / 7.0) * c.mu_table, true)
    } else {
        let s = slip.norm();
        let f = if s > 0.0 {
            -c.mu_table * normal * slip / s
        } else {
            Vector3::zeros()
        };
        (f + z, 1.0, false)
    }
}

/// Solves the impact for `shot` with coefficients `c` in the requested regime.
///
/// `RegimeChoice::Auto` decides each contact from its friction limit (static `mu0` at the
/// ball–ball contact, `mu'` at the table), see [`select_regime`].
pub fn solve(shot: &Shot, c: &Coefficients, choice: RegimeChoice) -> ImpactState {
    let regime = match choice {
        RegimeChoice::Fixed(r) => r,
        RegimeChoice::Auto => select_regime(shot, c),
    };
    let (mut b1, mut b2) = initial_balls(shot);
    let energy_before = b1.energy() + b2.energy();
    let (p, k_bb, _) = ball_ball_impulse(&b1, &b2, c, Some(regime.ball_ball_stick()));
    let (r1, r2) = (Vector3::x(), -Vector3::x());
    b1.apply(&r1, &(-p), k_bb);
    b2.apply(&r2, &p, k_bb);
    // Ball 1 pressed into the cloth (draw): the table's normal impulse cancels its vertical motion.
    if b1.v.z < 0.0 {
        b1.v.z = 0.0;
    }
    let (q, k_t, _) = table_impulse(&b2, &p, c, Some(regime.table_stick()));
    b2.apply(&(-Vector3::z()), &q, k_t);
    let energy_after = b1.energy() + b2.energy();
    ImpactState {
        regime,
        v1: b1.v,
        w1: b1.w,
        v2: b2.v,
        w2: b2.w,
        v1_roll: b1.rolling_velocity(),
        v2_roll: b2.rolling_velocity(),
        ball_ball_impulse: p,
        table_impulse: q,
        energy_before,
        energy_after,
    }
}

/// Stick test answers of the impulse model (ball–ball, table) for the auto regime. Used to
/// cross-check the closed-form limits in [`super::regime`].
pub fn stick_tests(shot: &Shot, c: &Coefficients) -> (bool, bool) {
    let (b1, b2) = initial_balls(shot);
    let (p, k_bb, bb) = ball_ball_impulse(&b1, &b2, c, None);
    let mut b2a = b2;
    b2a.apply(&(-Vector3::x()), &p, k_bb);
    let (_, _, t) = table_impulse(&b2a, &p, c, None);
    (bb, t)
}
