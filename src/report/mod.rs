//! Comparison reports: figures in the style of the paper (plotters, PNG + SVG with an embedded
//! font) and a self-contained HTML page plus a Markdown summary.
//!
//! - [`plot`]: declarative charts rendered to PNG and SVG;
//! - [`theory`]: sampled theory curves (angles vs `psi` for a regime or the auto regime);
//! - [`figures`]: the paper's figures (Figs. 5, 9–15), residuals;
//! - [`html`]: `index.html` and `report.md`;
//! - [`cli`]: `streakfit report` from tables and fit files made by hand.
//!
//! [`write_report`] takes the angles table (all folders), the fitted coefficients per material
//! ([`FitSummary`], filled by the pipeline from the fit stage) and the paper's Table 1 presets
//! (`datasets/materials.toml`), and writes into one folder: `index.html`, `report.md`,
//! `figures/*.png|svg` and `overlays/*.png` (downscaled copies of the extraction overlays). Every
//! link is relative and nothing is fetched from the network, so the folder can be moved or zipped.

pub mod cli;
pub mod figures;
pub mod html;
pub mod plot;
pub mod theory;

use crate::fit::{MaterialFit, ResidualRow};
use crate::physics::{Coefficients, RegimeChoice, Shot};
use crate::synth::materials::Material;
use crate::synth::materials::Materials;
use crate::table::{ShotRow, Status};
use anyhow::{Context, Result};
use figures::{MaterialFigures, Model};
use plot::SavedFigure;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Cue speed of the paper's experiment (Section 3), used for the path figures.
pub const CUE_SPEED_MPS: f64 = 0.75;

/// 1-sigma uncertainties of fitted coefficients (`None`: not fitted or not determined).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CoefficientErrors {
    pub e: Option<f64>,
    pub mu: Option<f64>,
    pub mu_table: Option<f64>,
    pub mu_static: Option<f64>,
}

/// Score of one candidate model of the model selection.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelScore {
    pub name: String,
    /// Number of free parameters.
    pub k: usize,
    pub chi2: f64,
    pub aic: Option<f64>,
    pub bic: Option<f64>,
    pub selected: bool,
}

/// The fit of one material, as the report shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSummary {
    pub material: String,
    pub coeffs: Coefficients,
    pub errors: CoefficientErrors,
    /// Regime rule of the selected model (auto or a fixed regime).
    pub choice: RegimeChoice,
    /// Name of the selected model, e.g. `auto (mu0 free)`.
    pub model: String,
    /// Shots used by the fit.
    pub n_shots: usize,
    /// Reduced chi-square of the selected model, if defined.
    pub chi2_red: Option<f64>,
    pub scores: Vec<ModelScore>,
    /// Free-form remarks of the fit (parameters at bounds, poorly determined ones).
    pub notes: Vec<String>,
    /// Which of `e, mu, mu_table, mu_static` the fit determined (others are drawn with the
    /// paper's values).
    pub fitted: [bool; 4],
}

/// One folder of photographs that went into the report.
#[derive(Debug, Clone)]
pub struct FolderInfo {
    pub name: String,
    pub path: PathBuf,
    /// Extraction overlays of this folder (file names from `extract::overlay_name`).
    pub overlays: Option<PathBuf>,
    /// The angles-table rows of this folder (file names repeat across folders).
    pub rows: Vec<ShotRow>,
}

/// A stage of the run, for the settings section.
#[derive(Debug, Clone)]
pub struct StageInfo {
    pub name: String,
    /// `ran` or `cached`.
    pub status: String,
    pub seconds: f64,
    pub key: String,
}

/// Everything a report is made from.
#[derive(Debug, Clone)]
pub struct ReportInput {
    pub title: String,
    /// All rows of all folders.
    pub rows: Vec<ShotRow>,
    pub fits: Vec<FitSummary>,
    /// Per-shot residuals of the selected models (from the fit).
    pub residuals: Vec<ResidualRow>,
    pub materials: Materials,
    pub folders: Vec<FolderInfo>,
    /// The pipeline file as written (shown verbatim).
    pub settings_text: String,
    pub settings_name: String,
    pub stages: Vec<StageInfo>,
    /// Overlays shown per folder in the gallery.
    pub gallery_per_folder: usize,
    /// One line on how the fit was run.
    pub fit_settings: String,
    /// Materials whose fit failed, with the reason.
    pub fit_failures: Vec<(String, String)>,
}

/// What was written.
#[derive(Debug, Clone)]
pub struct ReportOutput {
    pub dir: PathBuf,
    pub index: PathBuf,
    pub markdown: PathBuf,
    pub figures: Vec<SavedFigure>,
    pub gallery: Vec<GalleryItem>,
}

/// An overlay copied into the report.
#[derive(Debug, Clone)]
pub struct GalleryItem {
    pub folder: String,
    pub file: String,
    /// Relative to the report folder.
    pub rel_path: String,
    pub status: String,
    pub reason: String,
}

/// Extraction statistics of one group of rows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtractionStats {
    pub total: usize,
    pub ok: usize,
    pub declined: usize,
    pub error: usize,
    /// `(status, reason, count)`, most frequent first.
    pub reasons: Vec<(String, String, usize)>,
    pub seconds: f64,
}

impl ExtractionStats {
    pub fn of<'a>(rows: impl IntoIterator<Item = &'a ShotRow>) -> Self {
        let mut s = ExtractionStats::default();
        let mut reasons: BTreeMap<(String, String), usize> = BTreeMap::new();
        for r in rows {
            s.total += 1;
            s.seconds += r.seconds;
            match r.status {
                Status::Ok => s.ok += 1,
                Status::Declined => s.declined += 1,
                Status::Error => s.error += 1,
            }
            if r.status != Status::Ok {
                *reasons
                    .entry((r.status.as_str().to_string(), reason_class(&r.reason)))
                    .or_default() += 1;
            }
        }
        let mut v: Vec<(String, String, usize)> =
            reasons.into_iter().map(|((a, b), n)| (a, b, n)).collect();
        v.sort_by(|a, b| b.2.cmp(&a.2).then_with(|| a.1.cmp(&b.1)));
        s.reasons = v;
        s
    }
}

/// A reason without its per-image numbers, so that equal causes group together
/// (`"only one ball found (area 123 px)"` → `"only one ball found (area # px)"`).
pub fn reason_class(reason: &str) -> String {
    let mut out = String::with_capacity(reason.len());
    let mut in_num = false;
    for ch in reason.chars() {
        if ch.is_ascii_digit() || (in_num && (ch == '.' || ch == 'e' || ch == '-')) {
            if !in_num {
                out.push('#');
                in_num = true;
            }
        } else {
            in_num = false;
            out.push(ch);
        }
    }
    let t = out.trim();
    if t.is_empty() {
        "(no reason given)".to_string()
    } else {
        t.to_string()
    }
}

/// Materials in the report: those of the rows, in the order of the presets file, then others.
pub fn report_materials(input: &ReportInput) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for name in input.materials.names() {
        if input.rows.iter().any(|r| r.material == name)
            || input.fits.iter().any(|f| f.material == name)
        {
            seen.push(name);
        }
    }
    for r in &input.rows {
        if !seen.contains(&r.material) {
            seen.push(r.material.clone());
        }
    }
    seen
}

/// Median of the known values, or `default`.
fn median_or(values: impl Iterator<Item = f64>, default: f64) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return default;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Per-material figure inputs.
pub fn material_inputs(input: &ReportInput) -> Vec<MaterialFigures> {
    report_materials(input)
        .into_iter()
        .map(|name| {
            let rows: Vec<ShotRow> = input
                .rows
                .iter()
                .filter(|r| r.material == name)
                .cloned()
                .collect();
            let preset = input.materials.0.get(&name);
            let fit = input.fits.iter().find(|f| f.material == name);
            let template = Shot {
                psi: 0.0,
                mass_ratio: 1.0,
                spin: median_or(rows.iter().filter_map(|r| r.spin), 1.0),
                english: median_or(rows.iter().filter_map(|r| r.english), 0.0),
            };
            let fit_residuals = input
                .residuals
                .iter()
                .filter(|r| r.material == name)
                .filter_map(|r| residual_point(r, &rows))
                .collect();
            MaterialFigures {
                fit_residuals,
                label: preset
                    .map(|p| p.label.clone())
                    .unwrap_or_else(|| name.clone()),
                rows,
                fitted: fit.map(|f| Model {
                    label: "fit".into(),
                    coeffs: f.coeffs,
                    choice: f.choice,
                    assumed: f.fitted.map(|b| !b),
                }),
                paper: preset.map(|p| Model {
                    label: "paper".into(),
                    coeffs: p.coefficients(),
                    choice: RegimeChoice::Auto,
                    assumed: [false; 4],
                }),
                template,
                radius_m: preset.map(|p| p.radius_m()).unwrap_or(0.028575),
                speed_mps: CUE_SPEED_MPS,
                cloth: preset.map(|p| p.cloth()).unwrap_or_default(),
                name,
            }
        })
        .collect()
}

/// A residual row of the fit as a plotted point (errors from the matching angles-table row).
fn residual_point(r: &ResidualRow, rows: &[ShotRow]) -> Option<figures::ResidualPoint> {
    if !r.used {
        return None;
    }
    let row = rows.iter().find(|x| x.file == r.file);
    let err = |f: fn(&ShotRow) -> Option<f64>| row.and_then(f);
    // Estimated spin: `estimated`, or `undetermined` when a component is null (the shot is
    // still an estimated-spin shot); `known` and `assumed` spins are not estimates.
    let spin = matches!(r.spin_source.as_str(), "estimated" | "undetermined").then(|| {
        figures::SpinEstimate {
            spin: r.spin_est,
            spin_err: r.spin_err,
            english: r.english_est,
            english_err: r.english_err,
            regime: r.regime_est.as_deref().and_then(|x| x.parse().ok()),
        }
    });
    Some(figures::ResidualPoint {
        psi_deg: r.psi_fit_deg.or(r.psi_deg)?,
        spin,
        resid_deg: [
            r.delta1_resid_deg,
            r.delta2_resid_deg,
            r.theta1_resid_deg,
            r.theta2_resid_deg,
        ],
        err_deg: [
            err(|x| x.delta1_err_deg),
            err(|x| x.delta2_err_deg),
            err(|x| x.theta1_err_deg),
            err(|x| x.theta2_err_deg),
        ],
    })
}

impl FitSummary {
    /// The report's view of a fit. Coefficients the data do not determine (reported as null by
    /// the fit) are drawn with the paper's value, and a note says so; `mu0 = mu` unless the
    /// selected model has a static-friction switch.
    pub fn from_fit(f: &MaterialFit, preset: Option<&Material>) -> FitSummary {
        let mut notes = f.notes.clone();
        for (k, why) in &f.unidentified {
            notes.push(format!("{k} not identified: {why}"));
        }
        let mut fallback = |name: &str, v: Option<f64>, paper: Option<f64>, default: f64| match v {
            Some(x) => x,
            None => {
                let (val, src) = match paper {
                    Some(p) => (p, "the paper's value"),
                    None => (default, "a default"),
                };
                notes.push(format!("{name}: curves drawn with {src} {val}"));
                val
            }
        };
        let e = fallback("e", f.e, preset.map(|p| p.e), 1.0);
        let mu = fallback("mu", f.mu, preset.map(|p| p.mu), 0.0);
        let mu_table = fallback("mu_table", f.mu_table, preset.map(|p| p.mu_table), 0.0);
        let model: Result<crate::fit::Model, String> = f.model.parse();
        let (choice, mu_static) = match model {
            Ok(crate::fit::Model::Single(r)) => (RegimeChoice::Fixed(r), mu),
            // The two-regime model switches at the static-friction limit: the auto regime.
            _ => {
                let ms = f
                    .mu_static
                    .or(f.mu_static_min)
                    .or(f.mu_static_max)
                    .unwrap_or(mu);
                (RegimeChoice::Auto, ms)
            }
        };
        if let Some(psi_l) = f.psi_l_deg {
            notes.push(format!(
                "psi_L (Eq. 50, rolling cue ball) = {}°",
                html::pm(psi_l, f.psi_l_se_deg)
            ));
        }
        FitSummary {
            material: f.material.clone(),
            coeffs: Coefficients::new(e, mu, mu_table).with_static(mu_static),
            errors: CoefficientErrors {
                e: f.e_se,
                mu: f.mu_se,
                mu_table: f.mu_table_se,
                mu_static: f.mu_static_se,
            },
            choice,
            model: f.model.clone(),
            n_shots: f.n_used,
            chi2_red: f.chi2_reduced.is_finite().then_some(f.chi2_reduced),
            scores: f
                .scores
                .iter()
                .map(|s| ModelScore {
                    name: if s.converged {
                        s.model.clone()
                    } else {
                        format!("{} (not converged)", s.model)
                    },
                    k: s.k,
                    chi2: s.chi2,
                    aic: Some(s.aic),
                    bic: Some(s.bic),
                    selected: s.model == f.model,
                })
                .collect(),
            notes,
            fitted: [
                f.e.is_some(),
                f.mu.is_some(),
                f.mu_table.is_some(),
                f.mu_static.is_some(),
            ],
        }
    }
}

/// Theory figures independent of the data: Fig. 5 and, when the presets have them, Fig. 14
/// (billiard balls) and Fig. 15 (rubber balls) with the paper's coefficients.
pub fn theory_figures(materials: &Materials) -> Vec<plot::Figure> {
    let mut out = vec![figures::fig05()];
    for (key, fig, name) in [
        ("billiard", "Fig. 14", "fig14_paths_billiard"),
        ("rubber", "Fig. 15", "fig15_paths_rubber"),
    ] {
        if let Some(m) = materials.0.get(key) {
            out.push(figures::paths(
                name,
                &format!("{fig}: {}, ψ = 45°, paper coefficients", m.label),
                &m.coefficients(),
                RegimeChoice::Auto,
                m.radius_m(),
                CUE_SPEED_MPS,
                &m.cloth(),
                45.0,
            ));
        }
    }
    out
}

/// Writes the report into `dir` (created; existing files of the same names are replaced).
pub fn write_report(input: &ReportInput, dir: &Path) -> Result<ReportOutput> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let fig_dir = dir.join("figures");
    let mut saved_global = Vec::new();
    for f in theory_figures(&input.materials) {
        saved_global.push(plot::save(&f, &fig_dir)?);
    }
    let mut per_material: Vec<(MaterialFigures, Vec<SavedFigure>)> = Vec::new();
    for m in material_inputs(input) {
        let mut saved = Vec::new();
        for f in figures::material_figures(&m) {
            saved.push(plot::save(&f, &fig_dir)?);
        }
        per_material.push((m, saved));
    }
    let gallery = html::copy_gallery(input, dir)?;
    let index = dir.join("index.html");
    let markdown = dir.join("report.md");
    let page = html::render_html(input, &saved_global, &per_material, &gallery, dir);
    write_atomic(&index, page.as_bytes())?;
    let md = html::render_markdown(input, &saved_global, &per_material, &gallery, dir);
    write_atomic(&markdown, md.as_bytes())?;
    let mut all = saved_global;
    all.extend(per_material.into_iter().flat_map(|(_, s)| s));
    Ok(ReportOutput {
        dir: dir.to_path_buf(),
        index,
        markdown,
        figures: all,
        gallery,
    })
}

pub use crate::io::write_atomic;

#[cfg(test)]
mod tests {
    use super::*;

    /// A report input from a real fit of a synthetic billiard table (30 shots, mu–mu).
    fn fitted_input(
        spin: crate::fit::synthetic::SyntheticSpin,
        mode: crate::fit::SpinMode,
    ) -> ReportInput {
        use crate::fit::synthetic::{SyntheticSpec, paper_materials, synthetic_table};
        let (name, c) = paper_materials()[0];
        let (rows, _) = synthetic_table(&SyntheticSpec {
            material: name.into(),
            coefficients: c,
            n: 30,
            psi_lo_deg: 10.0,
            psi_hi_deg: 70.0,
            noise_deg: 0.3,
            spin,
            seed: 8,
        });
        let opts = crate::fit::FitOptions {
            model: Some("mu-mu".parse().unwrap()),
            spin: mode,
            bootstrap: 0,
            ..crate::fit::FitOptions::default()
        };
        let out = crate::fit::fit_materials(&rows, &opts).unwrap();
        let materials = Materials::load(&Materials::default_path()).unwrap();
        let fits = out
            .fits
            .iter()
            .map(|f| FitSummary::from_fit(f, materials.0.get(&f.material)))
            .collect();
        ReportInput {
            title: "spin".into(),
            rows,
            fits,
            residuals: out.residuals,
            materials,
            folders: Vec::new(),
            settings_text: String::new(),
            settings_name: String::new(),
            stages: Vec::new(),
            gallery_per_folder: 0,
            fit_settings: String::new(),
            fit_failures: Vec::new(),
        }
    }

    /// Issue 8: the spin figure appears for a fit with estimated spins (one point per shot
    /// whose `r` the fit determined, with its error bar) and not when every spin is known.
    #[test]
    fn spin_figure_only_for_estimated_spins() {
        use crate::fit::SpinMode;
        use crate::fit::synthetic::SyntheticSpin;
        let mixed = SyntheticSpin::Mixed {
            r_lo: -1.0,
            r_hi: 1.5,
            s_max: 0.3,
            write: false,
        };
        let input = fitted_input(mixed, SpinMode::Estimate);
        let m = &material_inputs(&input)[0];
        let figs = figures::material_figures(m);
        let fig = figs
            .iter()
            .find(|f| f.name == "billiard_spin_estimates")
            .expect("spin figure for estimated spins");
        assert_eq!(fig.panels.len(), 6);
        let determined: Vec<&ResidualRow> = input
            .residuals
            .iter()
            .filter(|r| r.used && r.spin_est.is_some())
            .collect();
        assert!(determined.len() >= 20, "{} shots with r", determined.len());
        let drawn: Vec<&plot::DataPoint> = fig.panels[0]
            .points
            .iter()
            .flat_map(|s| &s.points)
            .collect();
        assert_eq!(drawn.len(), determined.len());
        for r in &determined {
            let (psi, spin, err) = (
                r.psi_fit_deg.unwrap(),
                r.spin_est.unwrap(),
                r.spin_err.unwrap(),
            );
            assert!(
                drawn.iter().any(|d| (d.x - psi).abs() < 1e-12
                    && (d.y - spin).abs() < 1e-12
                    && d.y_err
                        .is_some_and(|e| (e.0 - err).abs() < 1e-12 && (e.1 - err).abs() < 1e-12)),
                "{} not drawn with its error bar",
                r.file
            );
        }
        // Every series is a regime of the fit, in that regime's colour.
        for s in &fig.panels[0].points {
            let label = s.label.as_deref().unwrap();
            let reg = crate::physics::Regime::ALL
                .into_iter()
                .find(|r| label.starts_with(theory::pretty_regime(*r)))
                .unwrap_or_else(|| panic!("series {label} is not a regime"));
            assert_eq!(s.color, figures::regime_color(reg));
        }
        // Residual panels hold the same shots (delta1 is measured for all).
        let n_resid: usize = fig.panels[2].points.iter().map(|s| s.points.len()).sum();
        let n_est = input
            .residuals
            .iter()
            .filter(|r| r.used && matches!(r.spin_source.as_str(), "estimated" | "undetermined"))
            .count();
        assert_eq!(n_resid, n_est);

        // Known spins (written to the table): no spin figure, the residual figure stays.
        let input = fitted_input(
            SyntheticSpin::Mixed {
                r_lo: -1.0,
                r_hi: 1.5,
                s_max: 0.3,
                write: true,
            },
            SpinMode::Known,
        );
        let used: Vec<&ResidualRow> = input.residuals.iter().filter(|r| r.used).collect();
        assert!(used.len() >= 20 && used.iter().all(|r| r.spin_source == "known"));
        let names: Vec<String> = figures::material_figures(&material_inputs(&input)[0])
            .into_iter()
            .map(|f| f.name)
            .collect();
        assert!(
            names.contains(&"billiard_residuals".to_string()),
            "{names:?}"
        );
        assert!(
            !names.iter().any(|n| n.contains("spin_estimates")),
            "{names:?}"
        );
    }

    #[test]
    fn reasons_group_without_numbers() {
        assert_eq!(
            reason_class("only one ball found (area 123 px, 4.5%)"),
            "only one ball found (area # px, #%)"
        );
        assert_eq!(reason_class(""), "(no reason given)");
    }

    #[test]
    fn extraction_stats_count_statuses_and_reasons() {
        let mut rows = vec![
            ShotRow::failed("a.png", Status::Ok, "", "steel"),
            ShotRow::failed(
                "b.png",
                Status::Declined,
                "no collision (gap 12 px)",
                "steel",
            ),
            ShotRow::failed(
                "c.png",
                Status::Declined,
                "no collision (gap 40 px)",
                "steel",
            ),
            ShotRow::failed("d.png", Status::Error, "corrupt PNG", "steel"),
        ];
        rows[0].seconds = 1.5;
        let s = ExtractionStats::of(&rows);
        assert_eq!((s.total, s.ok, s.declined, s.error), (4, 1, 2, 1));
        assert_eq!(
            s.reasons[0],
            ("declined".into(), "no collision (gap # px)".into(), 2)
        );
        assert_eq!(s.reasons[1], ("error".into(), "corrupt PNG".into(), 1));
        assert!((s.seconds - 1.5).abs() < 1e-12);
    }
}
