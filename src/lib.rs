//! streakfit: long-exposure photographs of billiard-ball collisions to physics.
//!
//! Data flows one way: image → streaks → angles table → fit → report.
//! - [`physics`]: the non-smooth impact model (regimes, closed forms, paths);
//! - `synth`: synthetic photographs with exact ground truth;
//! - `vision`: segmentation, streaks and path fits (`extract`);
//! - `fit`: material coefficients with uncertainties and model selection;
//! - `report`: figures and HTML reports; `pipeline`: `streakfit run`.
#![deny(clippy::float_cmp)]

pub mod bench;
pub mod cli;
pub mod extract;
pub mod fit;
pub mod io;
pub mod physics;
pub mod pipeline;
pub mod predict;
pub mod report;
pub mod scene;
pub mod synth;
pub mod table;
pub mod vision;
