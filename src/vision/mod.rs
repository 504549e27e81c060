//! Vision: from one long-exposure photograph to the impact, post-collision and post-transition
//! angles (`streakfit extract`).
//!
//! Photometry. A pixel records the exposure-weighted mix of ball and cloth,
//! `I = (1 - w) B + w C_ball`, with `w` the fraction of the exposure a ball covered it. So the
//! object ball's waiting position is a bright disc (`w` ≈ waiting time / exposure), and a ball
//! moving at speed `v` paints a faint streak whose cross-profile at distance `d` from its
//! centre-line is `w(d) ∝ 2 sqrt(R² - d²) / v` (chord dwell; ball shading makes it closer to
//! `R² - d²`). Both are symmetric about the centre-line, which is what the sub-pixel estimate uses.
//!
//! Stages (one module each):
//! - [`image_io`]: decode JPEG/PNG/TIFF (8/16 bit) to linear-in-file RGB in `[0, 1]` (8-bit
//!   photos kept as bytes, read as `f32`);
//! - [`background`]: cloth model (the `background` plate of `scene.toml`, or a robust polynomial
//!   surface fitted to the photo itself, with the folder's fixed cloth texture from [`texture`]
//!   when there is no plate), the ball-minus-cloth colour direction `u`, the projected signal
//!   `S = u·(I - B)` and its MAD noise;
//! - [`disc`]: the object ball's waiting disc, centre `O` and radius `R` from a circle fit to
//!   sub-pixel edge points (and the edges' consensus circle where a run of them strays);
//! - [`streak`]: coarse streak detection on a downsampled signal, then full-resolution tracking of
//!   each streak's centre-line by symmetric centroids of baseline-subtracted cross-profiles;
//! - [`linefit`]: the incoming streak re-measured from its pixels in blocks one radius long
//!   (the dwell model of a straight streak fitted to each block's cells), where profile-by-profile
//!   centres scatter at a few grey levels of contrast;
//! - [`pathfit`]: the joint physical model (incoming line, contact geometry, one path per outgoing
//!   ball: line, or sliding parabola tangent to the rolling line), robust start, Levenberg–Marquardt,
//!   model choice by BIC and covariance;
//! - [`arc`]: the cue ball's start tangent `delta1` from the pixels around the impact, where its
//!   short sliding arc overlaps the incoming streak (a dwell-time model of the light, fitted);
//! - [`shot`]: scene reading (which streak is which ball) and the whole per-image analysis;
//! - [`overlay`]: drawings that show why each number is what it is;
//! - [`stages`]: each stage's share of an analysis's time (`streakfit bench stages`).
//!
//! Frame (see `shared/PHYSICS.md`): `x` points from the cue ball's centre at impact `P` to the
//! object ball's centre `O`, with `P = O - 2R x̂` on the incoming centre-line; the scene is mirrored
//! so that the incoming direction has `v_y ≥ 0`, hence `psi ∈ [0°, 90°)`. `delta` is the start
//! tangent of a ball's path, `theta` the direction of its straight rolling part.

//!
//! Debug hooks (environment variables, read-only side effects): `STREAKFIT_DEBUG=1` prints, per
//! photo (`== FILE`), the disc candidates and each one's reading, the streak candidates, the ray
//! search, the fits, the start tangents' profiles, the arc fit's rival cost and the cost of its
//! stages (dwell evaluations, each one pass over the window's cells, and ms) to stderr;
//! `STREAKFIT_COARSE_PNG=FILE` writes the coarse detection map (Mahalanobis norm, 0 to 3× its
//! threshold); `STREAKFIT_TEXTURE_PNG=FILE` writes the folder's cloth texture map (grey 128 = 0);
//! `STREAKFIT_ARC_DUMP=FILE` writes the arc fit's window (data and residual). Use them with one
//! photo (or `--jobs 1`): every analysis writes to the same file.

pub mod arc;
pub mod background;
pub mod disc;
pub mod image_io;
pub mod linefit;
pub mod overlay;
pub mod pathfit;
pub mod shot;
pub mod stages;
pub mod streak;
pub mod texture;

pub use background::{Cloth, ClothModel, Plate};
pub use shot::{Analysis, AnalysisOptions, PathModels, analyse};

/// A test frame rendered on `bd` (sensor noise from `seed`, none for `None`) and the noise-free
/// plate of the same table: what the vision modules' unit tests build their signal from.
#[cfg(test)]
pub(crate) fn rendered_with_plate(
    frame: &crate::synth::render::Frame,
    bd: &crate::synth::render::Backdrop,
    seed: Option<u64>,
) -> (image_io::RgbImage, Plate) {
    use crate::synth::render::{Frame, render};
    let base = bd.base_plate();
    let img = image_io::RgbImage::from(render(frame, bd, &base, seed));
    let plate = Plate::new(image_io::RgbImage::from(render(
        &Frame::default(),
        bd,
        &base,
        None,
    )));
    (img, plate)
}
