//! `streakfit fit TABLE... --out FILE.json|FILE.csv`: the command-line face of [`super`].

use super::{Criterion, FitOptions, FitOutput, Loss, MaterialFit, Model, ResidualRow, SpinMode};
use crate::cli::{CliError, CliResult, Outcome};
use crate::table::{TableFormat, read_angle_table, write_frame_atomic};
use anyhow::Result;
use clap::Args;
use polars::prelude::{Column, DataFrame};
use std::path::{Path, PathBuf};

#[derive(Debug, Args, Clone)]
pub struct FitArgs {
    /// Angle tables (Parquet or CSV) from `extract` or made by hand.
    #[arg(required = true)]
    pub tables: Vec<PathBuf>,
    /// Output: one row per material, `.json` (array) or `.csv`.
    #[arg(long)]
    pub out: PathBuf,
    /// Per-shot residuals table (`.csv`, `.parquet` or `.json`).
    #[arg(long)]
    pub residuals: Option<PathBuf>,
    /// Fit only this material.
    #[arg(long)]
    pub material: Option<String>,
    /// auto (choose by the criterion), mu-mu, s-mu, mu-s, s-s or two-regime.
    #[arg(long, default_value = "auto")]
    pub regime: String,
    /// Model-selection criterion: bic or aic.
    #[arg(long, default_value = "bic")]
    pub criterion: String,
    /// Spin of each shot: known (table values, else rolling r = 1, s = 0), estimate, auto.
    #[arg(long, default_value = "known")]
    pub spin: String,
    /// Default 1-sigma of an angle without `*_err_deg`, degrees.
    #[arg(long, default_value_t = 0.3)]
    pub sigma_deg: f64,
    /// Default 1-sigma of psi without `psi_err_deg`, degrees (0: psi exact).
    #[arg(long, default_value_t = 0.3)]
    pub psi_sigma_deg: f64,
    /// Mass ratio M = m1/m2.
    #[arg(long, default_value_t = 1.0)]
    pub mass_ratio: f64,
    /// Huber loss threshold in sigmas (default: plain least squares).
    #[arg(long)]
    pub huber: Option<f64>,
    /// Reject shots with a residual above this many robust sigmas; 0 keeps every shot.
    #[arg(long, default_value_t = 5.0)]
    pub reject_sigma: f64,
    /// Bootstrap resamples over shots (0: none).
    #[arg(long, default_value_t = 100)]
    pub bootstrap: usize,
    /// Seed of the bootstrap.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl FitArgs {
    pub fn options(&self) -> Result<FitOptions, CliError> {
        let model = if self.regime.trim().eq_ignore_ascii_case("auto") {
            None
        } else {
            Some(
                self.regime
                    .parse::<Model>()
                    .map_err(|e| CliError::usage(format!("--regime: {e}")))?,
            )
        };
        let criterion = match self.criterion.trim().to_ascii_lowercase().as_str() {
            "aic" => Criterion::Aic,
            "bic" => Criterion::Bic,
            o => {
                return Err(CliError::usage(format!(
                    "--criterion: unknown '{o}' (expected aic or bic)"
                )));
            }
        };
        let spin: SpinMode = self.spin.parse().map_err(CliError::usage)?;
        Ok(FitOptions {
            material: self.material.clone(),
            model,
            criterion,
            spin,
            default_sigma_deg: self.sigma_deg,
            default_psi_sigma_deg: self.psi_sigma_deg,
            mass_ratio: self.mass_ratio,
            loss: self.huber.map_or(Loss::Squared, Loss::Huber),
            reject_sigma: (self.reject_sigma > 0.0).then_some(self.reject_sigma),
            bootstrap: self.bootstrap,
            seed: self.seed,
        })
    }
}

/// Output format by extension: `None` for JSON.
fn out_kind(path: &Path, flag: &str) -> Result<Option<TableFormat>, CliError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("json") => Ok(None),
        Some("csv") => Ok(Some(TableFormat::Csv)),
        Some("parquet") | Some("pq") => Ok(Some(TableFormat::Parquet)),
        _ => Err(CliError::usage(format!(
            "{flag}: '{}' must end in .json, .csv or .parquet",
            path.display()
        ))),
    }
}

pub fn run(args: &FitArgs) -> CliResult {
    let opts = args.options()?;
    out_kind(&args.out, "--out")?;
    if let Some(r) = &args.residuals {
        out_kind(r, "--residuals")?;
    }
    let mut rows = Vec::new();
    for t in &args.tables {
        if !t.exists() {
            return Err(CliError::usage(format!(
                "table '{}' does not exist",
                t.display()
            )));
        }
        let r = read_angle_table(t).map_err(|e| CliError::usage(format!("{e:#}")))?;
        rows.extend(r);
    }
    let out = super::fit_materials(&rows, &opts).map_err(|e| CliError::usage(format!("{e:#}")))?;
    write_fits(&args.out, &out.fits)?;
    if let Some(r) = &args.residuals {
        write_residuals(r, &out.residuals)?;
    }
    for f in &out.fits {
        eprintln!("{}", summary_line(f));
        for n in &f.notes {
            eprintln!("  note: {n}");
        }
    }
    Ok(Outcome::Ok)
}

/// One human-readable line per material.
pub fn summary_line(f: &MaterialFit) -> String {
    let pm = |v: Option<f64>, s: Option<f64>| match (v, s) {
        (Some(v), Some(s)) => format!("{v:.3} ± {s:.3}"),
        _ => "not identified".to_string(),
    };
    let mut line = format!(
        "{}: model {} (n = {}, rejected {}), e {}, mu {}, mu' {}",
        f.material,
        f.model,
        f.n_used,
        f.n_rejected,
        pm(f.e, f.e_se),
        pm(f.mu, f.mu_se),
        pm(f.mu_table, f.mu_table_se)
    );
    if f.model == "two-regime" {
        line.push_str(&format!(", mu0 {}", pm(f.mu_static, f.mu_static_se)));
        if let Some(p) = f.psi_l_deg {
            line.push_str(&format!(", psi_L {p:.1}°"));
        }
    }
    line
}

pub use crate::io::write_atomic as write_bytes_atomic;

fn fail(e: anyhow::Error) -> CliError {
    CliError::Failed(e)
}

/// The fits as a flat table (one row per material; scores, correlation and notes as JSON text).
pub fn fits_frame(fits: &[MaterialFit]) -> Result<DataFrame> {
    let f = |g: &dyn Fn(&MaterialFit) -> Option<f64>| -> Vec<Option<f64>> {
        fits.iter().map(g).collect()
    };
    let s = |g: &dyn Fn(&MaterialFit) -> String| -> Vec<String> { fits.iter().map(g).collect() };
    let mut cols = vec![
        Column::new("material".into(), s(&|m| m.material.clone())),
        Column::new("model".into(), s(&|m| m.model.clone())),
        Column::new("e".into(), f(&|m| m.e)),
        Column::new("e_se".into(), f(&|m| m.e_se)),
        Column::new("mu".into(), f(&|m| m.mu)),
        Column::new("mu_se".into(), f(&|m| m.mu_se)),
        Column::new("mu_table".into(), f(&|m| m.mu_table)),
        Column::new("mu_table_se".into(), f(&|m| m.mu_table_se)),
        Column::new("mu_static".into(), f(&|m| m.mu_static)),
        Column::new("mu_static_se".into(), f(&|m| m.mu_static_se)),
        Column::new("psi_l_deg".into(), f(&|m| m.psi_l_deg)),
        Column::new("psi_l_se_deg".into(), f(&|m| m.psi_l_se_deg)),
        Column::new("psi_l_min_deg".into(), f(&|m| m.psi_l_min_deg)),
        Column::new("psi_l_max_deg".into(), f(&|m| m.psi_l_max_deg)),
        Column::new("mu_static_min".into(), f(&|m| m.mu_static_min)),
        Column::new("mu_static_max".into(), f(&|m| m.mu_static_max)),
        Column::new(
            "n_used".into(),
            fits.iter().map(|m| m.n_used as u64).collect::<Vec<_>>(),
        ),
        Column::new(
            "n_rejected".into(),
            fits.iter().map(|m| m.n_rejected as u64).collect::<Vec<_>>(),
        ),
        Column::new(
            "n_skipped".into(),
            fits.iter().map(|m| m.n_skipped as u64).collect::<Vec<_>>(),
        ),
        Column::new("identified".into(), s(&|m| m.identified.join(";"))),
        Column::new("chi2".into(), f(&|m| Some(m.chi2))),
        Column::new(
            "dof".into(),
            fits.iter().map(|m| m.dof as u64).collect::<Vec<_>>(),
        ),
        Column::new("chi2_reduced".into(), f(&|m| Some(m.chi2_reduced))),
        Column::new("se_scale".into(), f(&|m| Some(m.se_scale))),
        Column::new("aic".into(), f(&|m| Some(m.aic))),
        Column::new("bic".into(), f(&|m| Some(m.bic))),
    ];
    for name in ["mu-mu", "s-mu", "mu-s", "s-s", "two-regime"] {
        let score = |m: &MaterialFit, aic: bool| {
            m.scores
                .iter()
                .find(|x| x.model == name)
                .map(|x| if aic { x.aic } else { x.bic })
        };
        cols.push(Column::new(
            format!("aic_{name}").into(),
            f(&|m| score(m, true)),
        ));
        cols.push(Column::new(
            format!("bic_{name}").into(),
            f(&|m| score(m, false)),
        ));
    }
    cols.extend([
        Column::new("rms_psi_deg".into(), f(&|m| m.rms_deg.psi)),
        Column::new("rms_delta1_deg".into(), f(&|m| m.rms_deg.delta1)),
        Column::new("rms_delta2_deg".into(), f(&|m| m.rms_deg.delta2)),
        Column::new("rms_theta1_deg".into(), f(&|m| m.rms_deg.theta1)),
        Column::new("rms_theta2_deg".into(), f(&|m| m.rms_deg.theta2)),
        Column::new(
            "bootstrap_e_se".into(),
            f(&|m| m.bootstrap.as_ref().and_then(|b| b.e_se)),
        ),
        Column::new(
            "bootstrap_mu_se".into(),
            f(&|m| m.bootstrap.as_ref().and_then(|b| b.mu_se)),
        ),
        Column::new(
            "bootstrap_mu_table_se".into(),
            f(&|m| m.bootstrap.as_ref().and_then(|b| b.mu_table_se)),
        ),
        Column::new(
            "spin_known".into(),
            fits.iter().map(|m| m.spin_known as u64).collect::<Vec<_>>(),
        ),
        Column::new(
            "spin_estimated".into(),
            fits.iter()
                .map(|m| m.spin_estimated as u64)
                .collect::<Vec<_>>(),
        ),
        Column::new(
            "spin_undetermined".into(),
            fits.iter()
                .map(|m| m.spin_undetermined as u64)
                .collect::<Vec<_>>(),
        ),
        Column::new(
            "correlation".into(),
            s(&|m| serde_json::to_string(&m.correlation).unwrap_or_default()),
        ),
        Column::new(
            "unidentified".into(),
            s(&|m| serde_json::to_string(&m.unidentified).unwrap_or_default()),
        ),
        Column::new("notes".into(), s(&|m| m.notes.join(" | "))),
    ]);
    Ok(DataFrame::new(fits.len(), cols)?)
}

/// The per-shot residuals as a table.
pub fn residuals_frame(rows: &[ResidualRow]) -> Result<DataFrame> {
    let f = |g: &dyn Fn(&ResidualRow) -> Option<f64>| -> Vec<Option<f64>> {
        rows.iter().map(g).collect()
    };
    let s = |g: &dyn Fn(&ResidualRow) -> Option<String>| -> Vec<Option<String>> {
        rows.iter().map(g).collect()
    };
    let cols = vec![
        Column::new("material".into(), s(&|r| Some(r.material.clone()))),
        Column::new("file".into(), s(&|r| Some(r.file.clone()))),
        Column::new("model".into(), s(&|r| Some(r.model.clone()))),
        Column::new("regime_est".into(), s(&|r| r.regime_est.clone())),
        Column::new(
            "used".into(),
            rows.iter().map(|r| r.used).collect::<Vec<_>>(),
        ),
        Column::new("rejected_reason".into(), s(&|r| r.rejected_reason.clone())),
        Column::new("psi_deg".into(), f(&|r| r.psi_deg)),
        Column::new("psi_fit_deg".into(), f(&|r| r.psi_fit_deg)),
        Column::new("delta1_deg".into(), f(&|r| r.delta1_deg)),
        Column::new("delta1_fit_deg".into(), f(&|r| r.delta1_fit_deg)),
        Column::new("delta1_resid_deg".into(), f(&|r| r.delta1_resid_deg)),
        Column::new("delta2_deg".into(), f(&|r| r.delta2_deg)),
        Column::new("delta2_fit_deg".into(), f(&|r| r.delta2_fit_deg)),
        Column::new("delta2_resid_deg".into(), f(&|r| r.delta2_resid_deg)),
        Column::new("theta1_deg".into(), f(&|r| r.theta1_deg)),
        Column::new("theta1_fit_deg".into(), f(&|r| r.theta1_fit_deg)),
        Column::new("theta1_resid_deg".into(), f(&|r| r.theta1_resid_deg)),
        Column::new("theta2_deg".into(), f(&|r| r.theta2_deg)),
        Column::new("theta2_fit_deg".into(), f(&|r| r.theta2_fit_deg)),
        Column::new("theta2_resid_deg".into(), f(&|r| r.theta2_resid_deg)),
        Column::new("max_pull".into(), f(&|r| r.max_pull)),
        Column::new("spin_source".into(), s(&|r| Some(r.spin_source.clone()))),
        Column::new("spin_est".into(), f(&|r| r.spin_est)),
        Column::new("spin_err".into(), f(&|r| r.spin_err)),
        Column::new("english_est".into(), f(&|r| r.english_est)),
        Column::new("english_err".into(), f(&|r| r.english_err)),
        Column::new("spin_reason".into(), s(&|r| r.spin_reason.clone())),
    ];
    Ok(DataFrame::new(rows.len(), cols)?)
}

/// Writes the material fits as JSON (array) or CSV/Parquet by extension, atomically.
pub fn write_fits(path: &Path, fits: &[MaterialFit]) -> Result<(), CliError> {
    match out_kind(path, "--out")? {
        None => {
            let text = serde_json::to_string_pretty(fits).map_err(|e| fail(e.into()))?;
            write_bytes_atomic(path, text.as_bytes()).map_err(fail)
        }
        Some(fmt) => {
            let mut df = fits_frame(fits).map_err(fail)?;
            write_frame_atomic(path, fmt, &mut df).map_err(fail)
        }
    }
}

/// Writes the per-shot residuals as JSON, CSV or Parquet by extension, atomically.
pub fn write_residuals(path: &Path, rows: &[ResidualRow]) -> Result<(), CliError> {
    match out_kind(path, "--residuals")? {
        None => {
            let text = serde_json::to_string_pretty(rows).map_err(|e| fail(e.into()))?;
            write_bytes_atomic(path, text.as_bytes()).map_err(fail)
        }
        Some(fmt) => {
            let mut df = residuals_frame(rows).map_err(fail)?;
            write_frame_atomic(path, fmt, &mut df).map_err(fail)
        }
    }
}

/// Convenience for library callers: the whole output as JSON text.
pub fn to_json(out: &FitOutput) -> Result<String> {
    Ok(serde_json::to_string_pretty(out)?)
}
