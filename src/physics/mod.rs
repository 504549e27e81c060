//! Collision theory of the non-smooth billiard-ball impact model (paper in `shared/seed/`).
//!
//! Frame (right-handed): `x` from the cue ball's centre (ball 1) to the object ball's centre
//! (ball 2) at impact, `z` up, `y = z × x`; the scene is mirrored so the incoming cue-ball velocity
//! `v_o (cos psi, sin psi, 0)` has `psi ∈ [0°, 90°)`. Spin inputs are dimensionless:
//! `r = R omega_o / v_o` (rolling `r = 1`: `omega = (r v_o/R)(-sin psi, cos psi, 0)`) and
//! `s = R omega_zo / v_o` (sidespin about `z`). All angles are directions of horizontal velocities
//! measured from `x` towards `y`.
//!
//! - [`impulse`]: the source of truth, impulse–momentum with 3-D vectors.
//! - [`closed`]: the paper's angle equations (corrected), as numerator/denominator pairs.
//! - [`regime`]: stick/slip selection and the limit angles `psi_L`.
//! - [`path`]: post-impact motion on the cloth (sliding parabola, rolling line).
//! - [`rebound`]: the `M = 0` sphere-on-plate case of Section 2.3.

pub mod closed;
pub mod impulse;
pub mod path;
pub mod rebound;
pub mod regime;
mod types;

pub use types::*;
