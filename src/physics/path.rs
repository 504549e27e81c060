//! Motion of a ball on the cloth after the impact (Hopkins & Patterson).
//!
//! While the bottom point slips with velocity `c = v + omega × (-R z)`, cloth friction
//! `-mu_s g ĉ` acts in a fixed direction (for a solid sphere `dc/dt = -(7/2) mu_s g ĉ`), so the
//! centre follows a parabola for `t_s = 2|c0| / (7 mu_s g)`; it then rolls along a straight line
//! (tangent to the parabola's end) decelerated by rolling resistance `mu_r g` until it stops.
//! Positions in metres, times in seconds, velocities in m/s.

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

pub const GRAVITY: f64 = 9.81;

/// Friction of the cloth on a moving ball.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cloth {
    /// Sliding friction ball–cloth.
    pub mu_slide: f64,
    /// Rolling resistance (fraction of g), about 0.005–0.015 on cloth.
    pub mu_roll: f64,
}

impl Default for Cloth {
    fn default() -> Self {
        Self {
            mu_slide: 0.2,
            mu_roll: 0.01,
        }
    }
}

/// Piecewise path of one ball: sliding parabola, rolling line, rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallPath {
    pub p0: Vector2<f64>,
    pub v0: Vector2<f64>,
    /// Constant acceleration while sliding.
    pub a_slide: Vector2<f64>,
    pub t_slide: f64,
    /// Velocity when rolling starts.
    pub v_roll: Vector2<f64>,
    /// Time at which the ball stops (from the path's start).
    pub t_stop: f64,
    pub decel_roll: f64,
}

impl BallPath {
    /// Path from position `p0` with velocity `v` and spin `w` (3-D, SI units).
    pub fn new(
        p0: Vector2<f64>,
        v: Vector3<f64>,
        w: Vector3<f64>,
        radius: f64,
        cloth: &Cloth,
    ) -> Self {
        let slip = Vector2::new(v.x - radius * w.y, v.y + radius * w.x);
        let v0 = Vector2::new(v.x, v.y);
        let s = slip.norm();
        let (a_slide, t_slide) = if s > 1e-12 && cloth.mu_slide > 0.0 {
            (
                -cloth.mu_slide * GRAVITY * slip / s,
                2.0 * s / (7.0 * cloth.mu_slide * GRAVITY),
            )
        } else {
            (Vector2::zeros(), 0.0)
        };
        let v_roll = v0 + a_slide * t_slide;
        let decel_roll = cloth.mu_roll * GRAVITY;
        let t_stop = if decel_roll > 0.0 {
            t_slide + v_roll.norm() / decel_roll
        } else {
            f64::INFINITY
        };
        Self {
            p0,
            v0,
            a_slide,
            t_slide,
            v_roll,
            t_stop,
            decel_roll,
        }
    }

    /// A ball that arrives along `dir` at `speed` and reaches `p_impact` at `t = 0`, rolling with
    /// rolling resistance; use negative times for its incoming path.
    pub fn incoming(
        p_impact: Vector2<f64>,
        dir: Vector2<f64>,
        speed: f64,
        cloth: &Cloth,
    ) -> IncomingPath {
        IncomingPath {
            p_impact,
            dir: dir.normalize(),
            speed,
            decel: cloth.mu_roll * GRAVITY,
        }
    }

    /// Centre position at time `t ≥ 0` after the impact.
    pub fn position(&self, t: f64) -> Vector2<f64> {
        let t = t.max(0.0);
        if t <= self.t_slide {
            return self.p0 + self.v0 * t + 0.5 * self.a_slide * t * t;
        }
        let p1 =
            self.p0 + self.v0 * self.t_slide + 0.5 * self.a_slide * self.t_slide * self.t_slide;
        let speed = self.v_roll.norm();
        if speed == 0.0 {
            return p1;
        }
        let tr = (t.min(self.t_stop) - self.t_slide).max(0.0);
        p1 + self.v_roll / speed * (speed * tr - 0.5 * self.decel_roll * tr * tr)
    }

    /// Centre velocity at time `t ≥ 0`.
    pub fn velocity(&self, t: f64) -> Vector2<f64> {
        let t = t.max(0.0);
        if t <= self.t_slide {
            return self.v0 + self.a_slide * t;
        }
        if t >= self.t_stop {
            return Vector2::zeros();
        }
        let speed = self.v_roll.norm();
        if speed == 0.0 {
            return Vector2::zeros();
        }
        self.v_roll / speed * (speed - self.decel_roll * (t - self.t_slide))
    }

    /// Length of the sliding arc.
    pub fn slide_length(&self) -> f64 {
        (self.position(self.t_slide) - self.p0).norm()
    }
}

/// Straight incoming path of the cue ball before the impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncomingPath {
    pub p_impact: Vector2<f64>,
    pub dir: Vector2<f64>,
    pub speed: f64,
    pub decel: f64,
}

impl IncomingPath {
    /// Position at time `t ≤ 0` (the ball was faster earlier).
    pub fn position(&self, t: f64) -> Vector2<f64> {
        let t = t.min(0.0);
        self.p_impact + self.dir * (self.speed * t - 0.5 * self.decel * t * t)
    }

    pub fn speed_at(&self, t: f64) -> f64 {
        self.speed - self.decel * t.min(0.0)
    }
}
