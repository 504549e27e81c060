//! Rebound of a sphere without spin on a heavy rough plate (`M = 0`, paper Section 2.3).
//!
//! With `X = v_ox / (mu v_oy)` (tangential over normal incoming velocity of the contact point,
//! over `mu`), the tangential velocity of the contact point at separation is, in units of
//! `mu v_oy`: gross slip (Eq. 30) `X - (7/2)(1+e)`, a line of slope 1; slip–stick with the
//! torque rule of Eqs. (32)–(33): `V_x = -(10/49) mu v_ox` (Eq. 34), i.e. `-(10/49) mu X`, a line
//! of slope `-(10/49) mu` (the text's "slope -10/49" holds for `V_x / v_oy`, not `V_x / mu v_oy`).
//! Slip persists when the friction impulse cannot stop the slip: `X > (7/2)(1+e)`.

use super::Regime;

/// `V_x / (mu v_oy)` at separation in gross slip.
pub fn slip_line(x: f64, e: f64) -> f64 {
    x - 3.5 * (1.0 + e)
}

/// `V_x / (mu v_oy)` at separation in slip–stick.
pub fn stick_line(x: f64, mu: f64) -> f64 {
    -(10.0 / 49.0) * mu * x
}

/// Which regime a rebound with ratio `x = v_ox / (mu v_oy)` is in (`Regime::MuMu` for slip,
/// `Regime::SlipMu` for slip–stick; the table contact plays no part here).
pub fn rebound_regime(x: f64, e: f64) -> Regime {
    if x > 3.5 * (1.0 + e) {
        Regime::MuMu
    } else {
        Regime::SlipMu
    }
}

/// `V_x / (mu v_oy)` at separation with the regime chosen by [`rebound_regime`].
pub fn contact_velocity(x: f64, e: f64, mu: f64) -> f64 {
    match rebound_regime(x, e) {
        Regime::MuMu => slip_line(x, e),
        _ => stick_line(x, mu),
    }
}
