//! Small typed values shared by the physics modules and the rest of the crate.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Material coefficients of the impact model (paper's Table 1 symbols).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Coefficients {
    /// Normal coefficient of restitution (ball–ball), `0 ≤ e ≤ 1`.
    pub e: f64,
    /// Dynamic ball–ball friction `mu`.
    pub mu: f64,
    /// Dynamic ball–table friction `mu'` during the impact.
    pub mu_table: f64,
    /// Static ball–ball friction `mu0`: where stick gives way to slip.
    pub mu_static: f64,
}

impl Coefficients {
    /// Coefficients with `mu0 = mu` (the paper's usual approximation).
    pub fn new(e: f64, mu: f64, mu_table: f64) -> Self {
        Self {
            e,
            mu,
            mu_table,
            mu_static: mu,
        }
    }

    pub fn with_static(mut self, mu_static: f64) -> Self {
        self.mu_static = mu_static;
        self
    }

    /// Checks physical ranges; the message names the offending coefficient.
    pub fn validate(&self) -> Result<(), String> {
        let check = |name: &str, v: f64, lo: f64, hi: f64| {
            if !v.is_finite() || v < lo || v > hi {
                Err(format!(
                    "{name} = {v} is outside its physical range [{lo}, {hi}]"
                ))
            } else {
                Ok(())
            }
        };
        check("e", self.e, 0.0, 1.0)?;
        check("mu", self.mu, 0.0, 10.0)?;
        check("mu_table", self.mu_table, 0.0, 10.0)?;
        check("mu_static", self.mu_static, 0.0, 10.0)
    }
}

/// Incoming state of the cue ball, dimensionless.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Shot {
    /// Impact angle in radians, `[0, pi/2)`.
    pub psi: f64,
    /// Mass ratio `M = m1/m2` (billiards 1, heavy plate 0).
    pub mass_ratio: f64,
    /// Horizontal spin ratio `r = R omega_o / v_o` (rolling 1, stun 0, draw < 0).
    pub spin: f64,
    /// Sidespin ratio `s = R omega_zo / v_o` (English).
    pub english: f64,
}

impl Shot {
    /// A rolling cue ball (`r = 1, s = 0`) of equal mass at impact angle `psi` (radians).
    pub fn rolling(psi: f64) -> Self {
        Self {
            psi,
            mass_ratio: 1.0,
            spin: 1.0,
            english: 0.0,
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if !self.psi.is_finite() || self.psi < 0.0 || self.psi >= std::f64::consts::FRAC_PI_2 {
            return Err(format!(
                "psi = {}° is outside [0°, 90°)",
                self.psi.to_degrees()
            ));
        }
        if !self.mass_ratio.is_finite() || self.mass_ratio < 0.0 {
            return Err(format!(
                "mass ratio M = {} must be finite and ≥ 0",
                self.mass_ratio
            ));
        }
        if !self.spin.is_finite() {
            return Err(format!("spin r = {} must be finite", self.spin));
        }
        if !self.english.is_finite() {
            return Err(format!("english s = {} must be finite", self.english));
        }
        Ok(())
    }
}

/// Impact regime: (ball–ball contact)–(ball 2–table contact), each gross slip (`mu`) or
/// slip–stick (`s`), named as in the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Regime {
    /// Gross slip at both contacts (paper Section 2.2).
    MuMu,
    /// Slip–stick at the ball–ball contact, slip at the table (Section 2.4).
    SlipMu,
    /// Slip at the ball–ball contact, slip–stick at the table (Section 2.6).
    MuSlip,
    /// Slip–stick at both contacts (Section 2.5).
    SlipSlip,
}

impl Regime {
    pub const ALL: [Regime; 4] = [
        Regime::MuMu,
        Regime::SlipMu,
        Regime::MuSlip,
        Regime::SlipSlip,
    ];

    pub fn from_contacts(ball_ball_stick: bool, table_stick: bool) -> Self {
        match (ball_ball_stick, table_stick) {
            (false, false) => Regime::MuMu,
            (true, false) => Regime::SlipMu,
            (false, true) => Regime::MuSlip,
            (true, true) => Regime::SlipSlip,
        }
    }

    /// Slip–stick at the ball–ball contact?
    pub fn ball_ball_stick(self) -> bool {
        matches!(self, Regime::SlipMu | Regime::SlipSlip)
    }

    /// Slip–stick at the ball 2–table contact?
    pub fn table_stick(self) -> bool {
        matches!(self, Regime::MuSlip | Regime::SlipSlip)
    }

    pub fn name(self) -> &'static str {
        match self {
            Regime::MuMu => "mu-mu",
            Regime::SlipMu => "s-mu",
            Regime::MuSlip => "mu-s",
            Regime::SlipSlip => "s-s",
        }
    }
}

impl fmt::Display for Regime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Regime {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s
            .trim()
            .to_ascii_lowercase()
            .replace(['–', '_'], "-")
            .as_str()
        {
            "mu-mu" => Ok(Regime::MuMu),
            "s-mu" => Ok(Regime::SlipMu),
            "mu-s" => Ok(Regime::MuSlip),
            "s-s" => Ok(Regime::SlipSlip),
            other => Err(format!(
                "unknown regime '{other}' (expected mu-mu, s-mu, mu-s or s-s)"
            )),
        }
    }
}

/// Regime requested by a caller: chosen from the stick/slip conditions, or forced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum RegimeChoice {
    #[default]
    Auto,
    Fixed(Regime),
}

impl FromStr for RegimeChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("auto") {
            Ok(RegimeChoice::Auto)
        } else {
            s.parse().map(RegimeChoice::Fixed)
        }
    }
}

/// The four measurable directions after the impact, in radians; `None` where the ball stops
/// (its direction is undefined) or does not move at all (`M = 0`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ShotAngles {
    pub delta1: Option<f64>,
    pub delta2: Option<f64>,
    pub theta1: Option<f64>,
    pub theta2: Option<f64>,
}

impl ShotAngles {
    pub fn as_array(&self) -> [Option<f64>; 4] {
        [self.delta1, self.delta2, self.theta1, self.theta2]
    }

    pub fn to_degrees(&self) -> [Option<f64>; 4] {
        self.as_array().map(|a| a.map(f64::to_degrees))
    }

    pub const NAMES: [&'static str; 4] = ["delta1", "delta2", "theta1", "theta2"];
}

/// Wraps an angle (difference) into `(-pi, pi]`.
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

/// Speeds below this fraction of `v_o` count as a ball at rest: its direction is undefined.
pub const SPEED_EPS: f64 = 1e-9;

/// Direction of a horizontal vector `(x, y)`, or `None` if it is (numerically) zero.
pub fn direction(x: f64, y: f64, scale: f64) -> Option<f64> {
    let eps = SPEED_EPS * scale.max(f64::MIN_POSITIVE);
    if x * x + y * y <= eps * eps {
        None
    } else {
        Some(y.atan2(x))
    }
}
