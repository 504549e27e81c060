//! Tables of the data path (polars DataFrames, Parquet or CSV by extension).
//!
//! The angles table has one row per input image: `file, status (ok|declined|error), reason,
//! material, psi_deg, delta1_deg, delta2_deg, theta1_deg, theta2_deg, *_err_deg (1 sigma),
//! path_model1, path_model2, ball_radius_px, impact_x_px, impact_y_px, spin, english, seconds`.
//! Undefined angles (a ball that stops) are nulls, never numbers.

use serde::{Deserialize, Serialize};

/// Outcome of one input image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Ok,
    Declined,
    Error,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Declined => "declined",
            Status::Error => "error",
        }
    }
}

/// One row of the angles table (the output of `extract`, the input of `fit`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShotRow {
    pub file: String,
    pub status: Status,
    pub reason: String,
    /// Material label from `scene.toml` (`unknown` when absent).
    pub material: String,
    pub psi_deg: Option<f64>,
    pub delta1_deg: Option<f64>,
    pub delta2_deg: Option<f64>,
    pub theta1_deg: Option<f64>,
    pub theta2_deg: Option<f64>,
    pub psi_err_deg: Option<f64>,
    pub delta1_err_deg: Option<f64>,
    pub delta2_err_deg: Option<f64>,
    pub theta1_err_deg: Option<f64>,
    pub theta2_err_deg: Option<f64>,
    /// Path model used per outgoing ball: `line` or `parabola+line`.
    pub path_model1: Option<String>,
    pub path_model2: Option<String>,
    pub ball_radius_px: Option<f64>,
    pub impact_x_px: Option<f64>,
    pub impact_y_px: Option<f64>,
    /// Known cue-ball spin `r` and English `s` (from `scene.toml` or the input table), if given.
    pub spin: Option<f64>,
    pub english: Option<f64>,
    /// Analysis time for this image.
    pub seconds: f64,
}

impl ShotRow {
    /// A row for an image that produced no measurement.
    pub fn failed(
        file: impl Into<String>,
        status: Status,
        reason: impl Into<String>,
        material: impl Into<String>,
    ) -> Self {
        Self {
            file: file.into(),
            status,
            reason: reason.into(),
            material: material.into(),
            psi_deg: None,
            delta1_deg: None,
            delta2_deg: None,
            theta1_deg: None,
            theta2_deg: None,
            psi_err_deg: None,
            delta1_err_deg: None,
            delta2_err_deg: None,
            theta1_err_deg: None,
            theta2_err_deg: None,
            path_model1: None,
            path_model2: None,
            ball_radius_px: None,
            impact_x_px: None,
            impact_y_px: None,
            spin: None,
            english: None,
            seconds: 0.0,
        }
    }
}
