//! Material coefficients `e, mu, mu' (mu_table), mu0 (mu_static)` from tables of measured
//! angles, with standard errors, a bootstrap check and model selection (`streakfit fit`).
//!
//! Objective: for each material, minimise `Σ_shots Σ_angles ((angle_pred - angle_meas)/sigma)²
//! + ((psi_i - psi_meas,i)/sigma_psi)²` where `angle_pred` comes from the closed forms
//! ([`crate::physics::closed::angles`]) at the shot's *true* `psi_i`, a latent parameter
//! (errors-in-variables). Missing uncertainties default to [`FitOptions::default_sigma_deg`].
//! Where the table states the part of the angles' sigmas that a photo's five angles share
//! (`frame_err_deg`: all are read from its line of centres), that shift is a further per-shot
//! parameter with that prior, profiled out in closed form, and the sigmas above become the
//! angles' own parts ([`problem`]).
//! Spin `r = R omega/v`, English `s = R omega_z/v`: known (table, or rolling `r = 1, s = 0` as in
//! the paper's track experiments) or estimated per shot ([`SpinMode`]). Estimated spin: each
//! shot starts the joint fit from the best point of a coarse `(r, s)` grid at the start globals
//! (not from rolling) and is re-seeded from the grid once the globals have moved; a shot
//! whose assigned ball–ball state is physically impossible at its fitted spin (gross slip where
//! even `mu0 = mu` would stick) is moved to the other state and the fit repeated; each shot's
//! `r, s` errors come from its profile likelihood, widened to cover the other contact state when
//! that fits as well (see [`spin`]); a component whose profile stays flat over the prior's width
//! is reported as `null` with the reason.
//!
//! Candidate models ([`Model`]): a single regime for every shot (`mu-mu`, `s-mu`, `mu-s`, `s-s`,
//! with `e, mu, mu'` free) and the two-regime switch (`two-regime`): the ball–ball contact sticks
//! (s–mu) where `mu0 (1+e) cos psi ≥ (2/7) |(sin psi + s, r cos psi)|` and slips (mu–mu)
//! elsewhere, which for a rolling cue ball is Eq. (50), `cos psi_L = 2/(7 mu0 (1+e))`. Its `mu0`
//! is a threshold between shots, found by profiling chi² over the partition; its standard error
//! spans the thresholds within Δchi² ≤ 1 of the best (uniform over that interval) plus the
//! propagated error of `e`. Each model is scored by `AIC = chi² + 2k` and
//! `BIC = chi² + k ln N` (`k` free globals, `N` angle measurements); the lower score wins
//! ([`Criterion`]).
//!
//! Uncertainty: the globals' covariance is `(JᵀJ)⁻¹` at the optimum (Schur complement, see
//! [`solver`]), scaled by the reduced chi² when that exceeds 1 (stated errors too small); it is
//! checked against a bootstrap over shots. A parameter counts as *identified* when its standard
//! error is finite and below `0.1` (`e`) or below `max(0.3 |estimate|, 0.02)` (frictions);
//! otherwise its estimate and error are reported as `null` with the reason. In gross slip
//! (mu–mu) `mu'` cancels from `theta2` and barely moves `delta2`, so it is typically not
//! identified there.
//!
//! Outliers: shots with a normalised angle residual above [`FitOptions::reject_sigma`] times the
//! robust residual scale are rejected and the fit repeated (at most 3 rounds); a Huber loss is
//! available as well ([`Loss`]).

// Parameter indices address several parallel arrays (values, errors, bounds, names).
#![allow(clippy::needless_range_loop)]

pub mod cli;
pub mod problem;
pub mod solver;
pub mod spin;
pub mod synthetic;

use crate::physics::Regime;
use crate::table::{ShotRow, Status};
use anyhow::{Result, bail};
use problem::{
    ENGLISH_PRIOR_SIGMA, GLOBAL_NAMES, NG, NL, SPIN_PRIOR_SIGMA, ShotData, critical_mu_static,
};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use solver::{Problem, Solution, State};
use std::collections::BTreeMap;

pub use cli::{FitArgs, run};

/// A candidate regime model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Model {
    /// One regime for every shot.
    Single(Regime),
    /// Ball–ball stick (s–mu) below the static-friction limit, gross slip (mu–mu) above.
    TwoRegime,
}

impl Model {
    pub const ALL: [Model; 5] = [
        Model::Single(Regime::MuMu),
        Model::Single(Regime::SlipMu),
        Model::Single(Regime::MuSlip),
        Model::Single(Regime::SlipSlip),
        Model::TwoRegime,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Model::Single(r) => r.name(),
            Model::TwoRegime => "two-regime",
        }
    }

    /// Free globals of the model.
    pub fn free_globals(self) -> [bool; NG] {
        match self {
            Model::Single(_) => [true, true, true, false],
            Model::TwoRegime => [true, true, true, true],
        }
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        if matches!(t.as_str(), "two-regime" | "switch" | "two_regime") {
            return Ok(Model::TwoRegime);
        }
        t.parse::<Regime>().map(Model::Single).map_err(|_| {
            format!("unknown model '{s}' (expected auto, mu-mu, s-mu, mu-s, s-s or two-regime)")
        })
    }
}

/// How the cue ball's spin of each shot is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpinMode {
    /// Use the table's `spin`/`english`; where absent, a rolling cue ball (`r = 1, s = 0`).
    #[default]
    Known,
    /// Estimate `r, s` for every shot (latent, jointly with the globals).
    Estimate,
    /// Known where the table gives `spin`, estimated elsewhere.
    Auto,
}

impl std::str::FromStr for SpinMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "known" => Ok(SpinMode::Known),
            "estimate" => Ok(SpinMode::Estimate),
            "auto" => Ok(SpinMode::Auto),
            o => Err(format!(
                "--spin: unknown mode '{o}' (expected known, estimate or auto)"
            )),
        }
    }
}

/// Loss on the normalised angle residuals.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum Loss {
    #[default]
    Squared,
    /// Huber loss with threshold in sigmas.
    Huber(f64),
}

/// Information criterion used to choose among the candidate models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Criterion {
    Aic,
    #[default]
    Bic,
}

/// Options of [`fit_materials`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitOptions {
    /// Fit only this material (all when `None`).
    pub material: Option<String>,
    /// A fixed model, or `None` to choose among [`Model::ALL`] by the criterion.
    pub model: Option<Model>,
    pub criterion: Criterion,
    pub spin: SpinMode,
    /// 1-sigma of an angle whose `*_err_deg` is absent, degrees.
    pub default_sigma_deg: f64,
    /// 1-sigma of psi when `psi_err_deg` is absent, degrees (`0` treats psi as exact).
    pub default_psi_sigma_deg: f64,
    pub mass_ratio: f64,
    pub loss: Loss,
    /// Reject shots with a normalised residual above this many robust sigmas (`None`: keep all).
    pub reject_sigma: Option<f64>,
    /// Bootstrap resamples over shots (0: none).
    pub bootstrap: usize,
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            material: None,
            model: None,
            criterion: Criterion::Bic,
            spin: SpinMode::Known,
            default_sigma_deg: 0.3,
            default_psi_sigma_deg: 0.3,
            mass_ratio: 1.0,
            loss: Loss::Squared,
            reject_sigma: Some(5.0),
            bootstrap: 100,
            seed: 1,
        }
    }
}

/// One candidate model's score.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelScore {
    pub model: String,
    /// Free global parameters.
    pub k: usize,
    pub chi2: f64,
    pub aic: f64,
    pub bic: f64,
    pub converged: bool,
    /// Fraction of shots whose table contact, by the stick/slip condition at the fitted
    /// coefficients, is in the state the model assumes. Models below 0.8 are not chosen.
    pub consistency: f64,
}

/// Residual RMS per angle, degrees (`psi`: fitted minus measured impact angle).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct AngleRms {
    pub psi: Option<f64>,
    pub delta1: Option<f64>,
    pub delta2: Option<f64>,
    pub theta1: Option<f64>,
    pub theta2: Option<f64>,
}

/// Correlation matrix of the identified globals.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Correlation {
    pub params: Vec<String>,
    pub matrix: Vec<Vec<f64>>,
}

/// Bootstrap over shots of the chosen model (regime partition kept).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BootstrapSummary {
    pub resamples: usize,
    pub e_se: Option<f64>,
    pub mu_se: Option<f64>,
    pub mu_table_se: Option<f64>,
}

/// Result for one material (one row of the paper's Table 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaterialFit {
    pub material: String,
    /// Chosen model: `mu-mu`, `s-mu`, `mu-s`, `s-s` or `two-regime`.
    pub model: String,
    pub e: Option<f64>,
    pub e_se: Option<f64>,
    pub mu: Option<f64>,
    pub mu_se: Option<f64>,
    pub mu_table: Option<f64>,
    pub mu_table_se: Option<f64>,
    pub mu_static: Option<f64>,
    pub mu_static_se: Option<f64>,
    /// Eq. (50) limit for a rolling cue ball from the fitted `mu0, e` (two-regime model).
    pub psi_l_deg: Option<f64>,
    pub psi_l_se_deg: Option<f64>,
    /// Bounds when the data lie on one side of the switch: slip–stick up to the largest psi
    /// (`psi_l_min_deg`, `mu_static_min`) or gross slip down to the smallest psi.
    pub psi_l_min_deg: Option<f64>,
    pub psi_l_max_deg: Option<f64>,
    pub mu_static_min: Option<f64>,
    pub mu_static_max: Option<f64>,
    pub n_used: usize,
    /// Rows with status ok that were not used (outliers, missing psi or angles).
    pub n_rejected: usize,
    /// Rows with status declined or error.
    pub n_skipped: usize,
    /// Parameters the data determine.
    pub identified: Vec<String>,
    /// Why a model parameter is not identified.
    pub unidentified: BTreeMap<String, String>,
    pub chi2: f64,
    pub dof: usize,
    pub chi2_reduced: f64,
    /// Factor applied to the Jacobian standard errors, `max(1, sqrt(chi2_reduced))`.
    pub se_scale: f64,
    pub aic: f64,
    pub bic: f64,
    pub scores: Vec<ModelScore>,
    pub rms_deg: AngleRms,
    pub correlation: Correlation,
    pub bootstrap: Option<BootstrapSummary>,
    pub spin_known: usize,
    pub spin_estimated: usize,
    pub spin_undetermined: usize,
    pub notes: Vec<String>,
}

/// Per-shot residuals of the chosen model (for the report's plots).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualRow {
    pub material: String,
    pub file: String,
    pub model: String,
    /// Regime this shot has under the chosen model.
    pub regime_est: Option<String>,
    pub used: bool,
    /// Why the shot was not used.
    pub rejected_reason: Option<String>,
    pub psi_deg: Option<f64>,
    pub psi_fit_deg: Option<f64>,
    pub delta1_deg: Option<f64>,
    pub delta1_fit_deg: Option<f64>,
    pub delta1_resid_deg: Option<f64>,
    pub delta2_deg: Option<f64>,
    pub delta2_fit_deg: Option<f64>,
    pub delta2_resid_deg: Option<f64>,
    pub theta1_deg: Option<f64>,
    pub theta1_fit_deg: Option<f64>,
    pub theta1_resid_deg: Option<f64>,
    pub theta2_deg: Option<f64>,
    pub theta2_fit_deg: Option<f64>,
    pub theta2_resid_deg: Option<f64>,
    /// Largest |residual|/sigma of the shot's angles.
    pub max_pull: Option<f64>,
    /// `known`, `assumed` (rolling default), `estimated` or `undetermined`.
    pub spin_source: String,
    pub spin_est: Option<f64>,
    pub spin_err: Option<f64>,
    pub english_est: Option<f64>,
    pub english_err: Option<f64>,
    /// Why a spin component is reported as null.
    pub spin_reason: Option<String>,
}

/// Everything [`fit_materials`] produces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitOutput {
    pub fits: Vec<MaterialFit>,
    pub residuals: Vec<ResidualRow>,
}

/// Fits every material in `rows` (rows with status `ok`), see the module doc.
pub fn fit_materials(rows: &[ShotRow], opts: &FitOptions) -> Result<FitOutput> {
    validate_options(opts)?;
    let mut materials: Vec<String> = Vec::new();
    for r in rows {
        if !materials.contains(&r.material) {
            materials.push(r.material.clone());
        }
    }
    if let Some(m) = &opts.material {
        if !materials.contains(m) {
            bail!(
                "--material: no rows with material '{m}' (found: {})",
                materials.join(", ")
            );
        }
        materials.retain(|x| x == m);
    }
    let mut out = FitOutput {
        fits: Vec::new(),
        residuals: Vec::new(),
    };
    for m in materials {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].material == m).collect();
        let (fit, res) = fit_material(&m, rows, &idx, opts)?;
        out.fits.push(fit);
        out.residuals.extend(res);
    }
    Ok(out)
}

fn validate_options(o: &FitOptions) -> Result<()> {
    if !(o.default_sigma_deg.is_finite() && o.default_sigma_deg > 0.0) {
        bail!("--sigma-deg must be positive, got {}", o.default_sigma_deg);
    }
    if !(o.default_psi_sigma_deg.is_finite() && o.default_psi_sigma_deg >= 0.0) {
        bail!(
            "--psi-sigma-deg must be ≥ 0, got {}",
            o.default_psi_sigma_deg
        );
    }
    if !(o.mass_ratio.is_finite() && o.mass_ratio > 0.0) {
        bail!("--mass-ratio must be positive, got {}", o.mass_ratio);
    }
    if let Loss::Huber(k) = o.loss
        && !(k.is_finite() && k > 0.0)
    {
        bail!("--huber must be positive, got {k}");
    }
    if let Some(k) = o.reject_sigma
        && !(k.is_finite() && k > 0.0)
    {
        bail!("--reject-sigma must be positive, got {k}");
    }
    Ok(())
}

/// Least independent part (degrees) of an angle's 1-sigma where the table states a shared part
/// (`frame_err_deg`), added in quadrature to what remains of the stated sigma: the extractor's
/// shared part is nearly all of psi's and `theta1`'s sigmas (0.92 and 1.00 of them on synthetic
/// photos), yet the two angles' errors differ by a median 0.005–0.014° (clean sets without a
/// plate), an independent part of about 0.01° each; the extractor's own floor is the same.
const INDEPENDENT_FLOOR_DEG: f64 = 0.01;

/// Reduced χ² above which, or share of shots rejected above which, a fit that assumed rolling
/// cue balls says so ([`summarise`]). Rolling synthetic tables fit at 0.3–3.7 (the demo's
/// three materials and 13 clean, plate and grazing sets, session 21); the 36 mixed-spin shots of
/// `docs/accuracy.sh` fitted as rolling gave 2270, with 14 of 33 rejected and `e` 0.864 ±
/// 0.014 for 0.97.
const POOR_FIT_CHI2_REDUCED: f64 = 10.0;
const POOR_FIT_REJECTED: f64 = 0.25;
/// How the note of a fit that assumed rolling cue balls and failed begins (the run's summary
/// repeats such notes as warnings).
pub const POOR_FIT_NOTE: &str = "poor fit:";

/// Converts a table row into shot data, or the reason it cannot be used.
fn shot_data(i: usize, r: &ShotRow, opts: &FitOptions) -> std::result::Result<ShotData, String> {
    let psi = r.psi_deg.ok_or("psi_deg is missing")?;
    if !(0.0..90.0).contains(&psi) {
        return Err(format!("psi_deg = {psi} is outside [0, 90)"));
    }
    // A straight-line path does not measure its start tangent (the sliding arc was too short
    // to see): the extractor leaves it unresolved since session 21, and older tables state
    // delta = theta there, which would count theta twice and impose delta = theta on the model.
    let line = |m: &Option<String>| m.as_deref() == Some("line");
    let meas = [
        r.delta1_deg.filter(|_| !line(&r.path_model1)),
        r.delta2_deg.filter(|_| !line(&r.path_model2)),
        r.theta1_deg,
        r.theta2_deg,
    ];
    if meas.iter().all(Option::is_none) {
        return Err("no angle measured".into());
    }
    let errs = [
        r.delta1_err_deg,
        r.delta2_err_deg,
        r.theta1_err_deg,
        r.theta2_err_deg,
    ];
    let mut sigma = [0.0; 4];
    for k in 0..4 {
        let s = errs[k].unwrap_or(opts.default_sigma_deg);
        if !(s.is_finite() && s > 0.0) {
            return Err(format!(
                "{}_err_deg = {s} must be positive",
                crate::physics::ShotAngles::NAMES[k]
            ));
        }
        sigma[k] = s.to_radians();
    }
    let psi_sigma = r.psi_err_deg.unwrap_or(opts.default_psi_sigma_deg);
    if !(psi_sigma.is_finite() && psi_sigma >= 0.0) {
        return Err(format!("psi_err_deg = {psi_sigma} must be ≥ 0"));
    }
    // The part the angles share (the line of centres' direction): the sigmas become their
    // independent parts, and the shared shift is a (profiled) parameter of the shot.
    let frame = r.frame_err_deg.unwrap_or(0.0);
    if !(frame.is_finite() && frame >= 0.0) {
        return Err(format!("frame_err_deg = {frame} must be ≥ 0"));
    }
    // The shared part of an angle's error cannot exceed the whole of it.
    let stated = [("psi", r.psi_err_deg)].into_iter().chain(
        crate::physics::ShotAngles::NAMES
            .iter()
            .zip(errs)
            .zip(meas)
            .filter(|(_, m)| m.is_some())
            .map(|((n, e), _)| (*n, e)),
    );
    for (name, e) in stated {
        if let Some(e) = e
            && frame > e * (1.0 + 1e-9)
        {
            return Err(format!(
                "frame_err_deg = {frame} exceeds {name}_err_deg = {e}: the part of the angles' \
                 errors they share cannot be larger than an angle's whole error"
            ));
        }
    }
    let own = |s: f64| {
        if frame > 0.0 {
            (s * s - frame * frame)
                .max(0.0)
                .sqrt()
                .hypot(INDEPENDENT_FLOOR_DEG)
        } else {
            s
        }
    };
    let psi_sigma = if psi_sigma > 0.0 { own(psi_sigma) } else { 0.0 };
    for s in sigma.iter_mut() {
        *s = own(s.to_degrees()).to_radians();
    }
    let estimate_spin = match opts.spin {
        SpinMode::Known => false,
        SpinMode::Estimate => true,
        SpinMode::Auto => r.spin.is_none(),
    };
    Ok(ShotData {
        row: i,
        psi_meas: psi.to_radians(),
        psi_sigma: psi_sigma.to_radians(),
        meas: meas.map(|m| m.map(f64::to_radians)),
        sigma,
        frame_sigma: frame.to_radians(),
        mass_ratio: opts.mass_ratio,
        spin0: if estimate_spin {
            1.0
        } else {
            r.spin.unwrap_or(1.0)
        },
        english0: if estimate_spin {
            0.0
        } else {
            r.english.unwrap_or(0.0)
        },
        estimate_spin,
    })
}

/// A fitted model on a set of shots.
#[derive(Debug, Clone)]
struct ModelFit {
    model: Model,
    regimes: Vec<Regime>,
    sol: Solution,
    /// Two-regime: (mu0 estimate, se before e-propagation, interval lo, hi).
    threshold: Option<(f64, f64)>,
}

const MAX_ITER: usize = 60;
const PROFILE_ITER: usize = 8;

fn problem<'a>(
    shots: &'a [ShotData],
    regimes: Vec<Regime>,
    model: Model,
    opts: &FitOptions,
) -> Problem<'a> {
    Problem {
        shots: shots.iter().collect(),
        regimes,
        // mu0 never enters the closed forms: in the two-regime model it is the partition
        // threshold, profiled outside the least squares.
        free_global: {
            let mut f = model.free_globals();
            f[3] = false;
            f
        },
        huber: match opts.loss {
            Loss::Squared => None,
            Loss::Huber(k) => Some(k),
        },
    }
}

/// Starting globals: the best few points of a coarse grid, scored on up to 100 shots.
fn grid_starts(
    shots: &[ShotData],
    regimes: &[Regime],
    model: Model,
    opts: &FitOptions,
) -> Vec<[f64; NG]> {
    let step = shots.len().div_ceil(100).max(1);
    let sub: Vec<ShotData> = shots.iter().step_by(step).cloned().collect();
    let sub_reg: Vec<Regime> = regimes.iter().step_by(step).copied().collect();
    let p = problem(&sub, sub_reg, model, opts);
    let locals: Vec<[f64; NL]> = sub.iter().map(ShotData::start_locals).collect();
    let mut scored = Vec::new();
    for e in [0.3, 0.6, 0.8, 0.9, 0.95, 0.99] {
        for mu in [0.02, 0.06, 0.12, 0.25, 0.45, 0.7, 1.0] {
            for mt in [0.1, 0.3, 0.6] {
                let st = State {
                    g: [e, mu, mt, mu],
                    l: locals.clone(),
                };
                scored.push((p.cost(&st).0, [e, mu, mt, mu]));
            }
        }
    }
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<[f64; NG]> = Vec::new();
    for (_, g) in scored {
        // Distinct starts: differ in e or mu from those already taken.
        if out
            .iter()
            .all(|o| (o[0] - g[0]).abs() > 1e-9 || (o[1] - g[1]).abs() > 1e-9)
        {
            out.push(g);
        }
        if out.len() == 3 {
            break;
        }
    }
    out
}

/// Fits a single-regime model from several starts and keeps the lowest cost.
fn fit_single(shots: &[ShotData], regime: Regime, opts: &FitOptions) -> ModelFit {
    use rayon::prelude::*;
    let model = Model::Single(regime);
    let regimes = vec![regime; shots.len()];
    let p = problem(shots, regimes.clone(), model, opts);
    let mut best: Option<Solution> = None;
    let starts = grid_starts(shots, &regimes, model, opts);
    // Many shots: choose among the starts on a subsample of about 100 shots, then polish once.
    let starts = if shots.len() > 150 {
        let step = shots.len().div_ceil(100);
        let sub: Vec<ShotData> = shots.iter().step_by(step).cloned().collect();
        let ps = problem(&sub, vec![regime; sub.len()], model, opts);
        // The starts are independent (and the subsample too small for the solver's own
        // parallel loops): solved in parallel.
        let mut scored: Vec<(f64, [f64; NG])> = starts
            .par_iter()
            .map(|g| {
                let st = State {
                    g: *g,
                    l: sub.iter().map(ShotData::start_locals).collect(),
                };
                let sol = ps.solve(st, MAX_ITER);
                (sol.cost, sol.state.g)
            })
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        vec![scored[0].1]
    } else {
        starts
    };
    let estimate = shots.iter().any(|s| s.estimate_spin);
    for g in starts {
        let mut st = State {
            g,
            l: shots.iter().map(ShotData::start_locals).collect(),
        };
        // Estimated spin: each shot starts from its best grid spin at the start globals, not
        // from rolling (a draw shot started as rolling holds the globals back for tens of
        // iterations and can stay in a worse minimum).
        if estimate {
            st = reseed_spin(&p, &st).0;
        }
        let sol = p.solve(st, MAX_ITER);
        if best.as_ref().is_none_or(|b| sol.cost < b.cost) {
            best = Some(sol);
        }
    }
    let mut best = best.expect("grid gives at least one start");
    // Estimated spin: the per-shot likelihood in (r, s) can have several minima (a draw shot
    // started as rolling); re-seed each shot from a grid at the current globals and refit.
    if estimate {
        for _ in 0..2 {
            let (st, moved) = reseed_spin(&p, &best.state);
            if moved == 0 {
                break;
            }
            let sol = p.solve(st, MAX_ITER);
            if sol.cost < best.cost - 1e-9 {
                best = sol;
            } else {
                break;
            }
        }
    }
    ModelFit {
        model,
        regimes,
        sol: best,
        threshold: None,
    }
}

/// Each estimated-spin shot moved to its best `(r, s)` grid point if that beats its current
/// locals (globals and psi held). Returns the state and the number of shots moved.
fn reseed_spin(p: &Problem, st: &State) -> (State, usize) {
    use rayon::prelude::*;
    let picked: Vec<([f64; NL], bool)> = (0..p.shots.len())
        .into_par_iter()
        .map(|i| {
            let cur = st.l[i];
            if !p.shots[i].estimate_spin {
                return (cur, false);
            }
            let mut best = (p.shot_cost(i, &st.g, &cur).0, cur, false);
            for (r, s) in spin::spin_grid() {
                let l = [cur[0], r, s];
                let c = p.shot_cost(i, &st.g, &l).0;
                if c < best.0 {
                    best = (c, l, true);
                }
            }
            (best.1, best.2)
        })
        .collect();
    let moved = picked.iter().filter(|x| x.1).count();
    let l = picked.into_iter().map(|x| x.0).collect();
    (State { g: st.g, l }, moved)
}

/// Two-regime model: profile chi² over the stick/slip partition ordered by each shot's critical
/// `mu0` (see [`critical_mu_static`]), warm-started from `(g0, l0)` (the better single-regime
/// fit). Up to 60 shots every threshold is fitted. With more shots, holding the globals,
/// moving the threshold by one shot changes only that shot's chi² (its latents re-fitted in
/// each regime), so the profile over all `n` thresholds is a prefix sum, O(n); the best
/// threshold is then fitted in full, and the two steps alternate until the threshold is stable
/// (at most 4 rounds).
fn fit_two_regime(
    shots: &[ShotData],
    g0: [f64; NG],
    l0: &[[f64; NL]],
    opts: &FitOptions,
) -> Option<ModelFit> {
    let n = shots.len();
    if n < 4 {
        return None;
    }
    let crit: Vec<f64> = l0.iter().map(|l| critical_mu_static(g0[0], l)).collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| crit[a].total_cmp(&crit[b]));
    let model = Model::TwoRegime;
    // k shots (lowest critical mu0) stick.
    let regimes_for = |k: usize| {
        let mut r = vec![Regime::MuMu; n];
        for &i in &order[..k] {
            r[i] = Regime::SlipMu;
        }
        r
    };
    let (lo_k, hi_k) = (1, n - 1);
    // Profile: threshold k -> chi² (robust cost).
    let mut profile: BTreeMap<usize, f64> = BTreeMap::new();
    let best_state: State;
    if n <= 60 {
        // Neighbouring thresholds differ by one shot: each is warm-started from the previous
        // one, in two sweeps, up from one sticking shot and down from all but one, and each
        // threshold keeps the better. One sweep alone carries the valley of its first
        // thresholds along: a rubber campaign whose shots nearly all stick, swept up from one
        // sticking shot, had ended at chi² 150,000 with `e` 0.91 where the down sweep finds 40.
        let mut best: Option<(f64, State)> = None;
        let mut sweep = |ks: Vec<usize>| {
            let mut state = State {
                g: g0,
                l: l0.to_vec(),
            };
            for k in ks {
                let sol =
                    problem(shots, regimes_for(k), model, opts).solve(state.clone(), PROFILE_ITER);
                let entry = profile.entry(k).or_insert(f64::INFINITY);
                *entry = entry.min(sol.cost);
                if best.as_ref().is_none_or(|b| sol.cost < b.0) {
                    best = Some((sol.cost, sol.state.clone()));
                }
                state = sol.state;
            }
        };
        sweep((lo_k..=hi_k).collect());
        sweep((lo_k..=hi_k).rev().collect());
        best_state = best?.1;
    } else {
        let huber = match opts.loss {
            Loss::Squared => None,
            Loss::Huber(k) => Some(k),
        };
        let mut state = State {
            g: g0,
            l: l0.to_vec(),
        };
        let mut last_k = None;
        // Alternate: O(n) profile at fixed globals, full fit at the best threshold.
        for _ in 0..4 {
            let g = state.g;
            let l_now = state.l.clone();
            let per_shot = |i: usize| {
                let one = |reg: Regime| {
                    Problem {
                        shots: vec![&shots[i]],
                        regimes: vec![reg],
                        free_global: [false; NG],
                        huber,
                    }
                    .solve(
                        State {
                            g,
                            l: vec![l_now[i]],
                        },
                        10,
                    )
                };
                let (s, m) = (one(Regime::SlipMu), one(Regime::MuMu));
                (s.cost, m.cost, s.state.l[0], m.state.l[0])
            };
            use rayon::prelude::*;
            let parts: Vec<(f64, f64, [f64; NL], [f64; NL])> =
                (0..n).into_par_iter().map(per_shot).collect();
            profile.clear();
            let mut cost: f64 = order.iter().map(|&i| parts[i].1).sum();
            for (j, &i) in order.iter().enumerate().take(hi_k) {
                cost += parts[i].0 - parts[i].1;
                profile.insert(j + 1, cost);
            }
            let (&k, _) = profile.iter().min_by(|a, b| a.1.total_cmp(b.1))?;
            if last_k == Some(k) {
                break;
            }
            last_k = Some(k);
            let mut rank = vec![0; n];
            for (j, &i) in order.iter().enumerate() {
                rank[i] = j;
            }
            let l = (0..n)
                .map(|i| if rank[i] < k { parts[i].2 } else { parts[i].3 })
                .collect();
            state = problem(shots, regimes_for(k), model, opts)
                .solve(State { g, l }, MAX_ITER)
                .state;
        }
        best_state = state;
    }
    let (&best_k, &best_cost) = profile.iter().min_by(|a, b| a.1.total_cmp(b.1))?;
    let best = problem(shots, regimes_for(best_k), model, opts).solve(best_state, MAX_ITER);
    // Critical mu0 of each shot at the fitted e and true psi.
    let crit_fit: Vec<f64> = best
        .state
        .l
        .iter()
        .map(|l| critical_mu_static(best.state.g[0], l))
        .collect();
    let sorted: Vec<f64> = order.iter().map(|&i| crit_fit[i]).collect();
    let gap = |k: usize| (sorted[k - 1], sorted[k]);
    let (a, b) = gap(best_k);
    let mu0 = 0.5 * (a + b);
    // 1-sigma interval: every threshold within Δchi² ≤ 1 of the best.
    let within: Vec<usize> = profile
        .iter()
        .filter(|(_, c)| **c - best_cost <= 1.0)
        .map(|(k, _)| *k)
        .collect();
    let klo = *within.iter().min()?;
    let khi = *within.iter().max()?;
    let (lo, hi) = (gap(klo).0.min(a), gap(khi).1.max(b));
    let se = (hi - lo) / 12f64.sqrt();
    let mut sol = best;
    sol.state.g[3] = mu0;
    Some(ModelFit {
        model,
        regimes: regimes_for(best_k),
        sol,
        threshold: Some((mu0, se)),
    })
}

fn n_angles(shots: &[ShotData]) -> usize {
    shots.iter().map(ShotData::n_angles).sum()
}

fn score(f: &ModelFit, shots: &[ShotData]) -> ModelScore {
    let k = f.model.free_globals().iter().filter(|x| **x).count();
    let n = n_angles(shots) as f64;
    // Data chi² only: the latent-psi and spin-prior terms are common to every model.
    let chi2 = f.sol.cost;
    ModelScore {
        model: f.model.name().to_string(),
        k,
        chi2,
        aic: chi2 + 2.0 * k as f64,
        bic: chi2 + k as f64 * n.ln(),
        converged: f.sol.converged,
        consistency: consistency(f, shots),
    }
}

/// Fits every requested model; returns all fits (for scoring) in [`Model::ALL`] order.
fn fit_models(shots: &[ShotData], opts: &FitOptions) -> Vec<ModelFit> {
    let wanted: Vec<Model> = match opts.model {
        Some(m) => vec![m],
        None => Model::ALL.to_vec(),
    };
    let mut fits: Vec<ModelFit> = Vec::new();
    let need_single = |r: Regime| {
        wanted.contains(&Model::Single(r))
            || (wanted.contains(&Model::TwoRegime) && matches!(r, Regime::MuMu | Regime::SlipMu))
    };
    // The single-regime candidates are independent: fit them in parallel.
    {
        use rayon::prelude::*;
        let regimes: Vec<Regime> = Regime::ALL
            .into_iter()
            .filter(|r| need_single(*r))
            .collect();
        fits.extend(
            regimes
                .into_par_iter()
                .map(|r| fit_single(shots, r, opts))
                .collect::<Vec<_>>(),
        );
    }
    if wanted.contains(&Model::TwoRegime) {
        let start = fits
            .iter()
            .filter(|f| matches!(f.model, Model::Single(Regime::MuMu | Regime::SlipMu)))
            .min_by(|a, b| a.sol.cost.total_cmp(&b.sol.cost))
            .map(|f| f.sol.clone());
        if let Some(s) = start
            && let Some(f) = fit_two_regime(shots, s.state.g, &s.state.l, opts)
        {
            fits.push(f);
        }
    }
    fits.retain(|f| wanted.contains(&f.model));
    fits
}

/// Fit of one material including outlier rejection, uncertainty and the residual table.
fn fit_material(
    material: &str,
    rows: &[ShotRow],
    idx: &[usize],
    opts: &FitOptions,
) -> Result<(MaterialFit, Vec<ResidualRow>)> {
    let mut rejected: BTreeMap<usize, String> = BTreeMap::new();
    let mut n_skipped = 0;
    let mut shots: Vec<ShotData> = Vec::new();
    for &i in idx {
        if rows[i].status != Status::Ok {
            n_skipped += 1;
            continue;
        }
        match shot_data(i, &rows[i], opts) {
            Ok(s) => shots.push(s),
            Err(why) => {
                rejected.insert(i, why);
            }
        }
    }
    if shots.len() < 3 {
        bail!(
            "material '{material}': {} usable shots, at least 3 are needed",
            shots.len()
        );
    }
    // Fit, reject outliers, refit (at most 3 rounds).
    let mut fits = fit_models(&shots, opts);
    for _round in 0..3 {
        let Some(k) = opts.reject_sigma else { break };
        let chosen = choose(&fits, &shots, opts.criterion);
        let f = &fits[chosen];
        let p = problem(&shots, f.regimes.clone(), f.model, opts);
        let pulls: Vec<f64> = (0..shots.len())
            .map(|i| {
                let r =
                    problem::residuals(&shots[i], &f.sol.state.g, &f.sol.state.l[i], f.regimes[i]);
                r[..4].iter().fold(0.0f64, |m, x| m.max(x.abs()))
            })
            .collect();
        let _ = p;
        let mut all: Vec<f64> = (0..shots.len())
            .flat_map(|i| {
                let r =
                    problem::residuals(&shots[i], &f.sol.state.g, &f.sol.state.l[i], f.regimes[i]);
                (0..4)
                    .filter(|&k| shots[i].meas[k].is_some())
                    .map(move |k| r[k].abs())
                    .collect::<Vec<_>>()
            })
            .collect();
        all.sort_by(f64::total_cmp);
        let scale = (1.4826 * all[all.len() / 2]).max(1.0);
        let bad: Vec<usize> = (0..shots.len()).filter(|&i| pulls[i] > k * scale).collect();
        if bad.is_empty() || shots.len() - bad.len() < 3 {
            break;
        }
        for &i in bad.iter().rev() {
            rejected.insert(
                shots[i].row,
                format!(
                    "outlier: residual {:.1} sigma (limit {:.1})",
                    pulls[i],
                    k * scale
                ),
            );
            shots.remove(i);
        }
        fits = fit_models(&shots, opts);
    }
    let chosen = choose(&fits, &shots, opts.criterion);
    let scores: Vec<ModelScore> = fits.iter().map(|f| score(f, &shots)).collect();
    let mut f = fits[chosen].clone();
    let moved = refine_regimes(&shots, &mut f, opts);
    let bootstrap = (opts.bootstrap > 0).then(|| bootstrap(&shots, &f, opts));
    let (mut fit, res) = summarise(
        material, rows, &shots, &f, scores, bootstrap, rejected, n_skipped, opts,
    );
    if moved > 0 {
        fit.notes.push(format!(
            "{moved} estimated-spin shots moved to the other ball–ball contact state by the \
             stick/slip condition at their spin (static friction mu0 ≥ mu: the contact sticks \
             where even mu0 = mu would hold it); regime_est gives each shot's state"
        ));
    }
    Ok((fit, res))
}

/// Ball–ball contact state of each estimated-spin shot from the stick/slip condition.
///
/// With free spin, a shot can often be reproduced in either contact state, so the model's
/// assignment can be physically impossible (gross slip where even `mu0 = mu` would stick, see
/// [`spin::admissible`]); such shots bias `mu`. A shot whose state is impossible moves to the
/// other state when that one is possible (locals refitted, globals held), then the whole
/// problem is refitted with the per-shot states; at most 3 rounds. Returns the number of shots
/// whose state differs from the model's.
fn refine_regimes(shots: &[ShotData], f: &mut ModelFit, opts: &FitOptions) -> usize {
    use rayon::prelude::*;
    if !shots.iter().any(|s| s.estimate_spin) {
        return 0;
    }
    let huber = match opts.loss {
        Loss::Squared => None,
        Loss::Huber(k) => Some(k),
    };
    let original = f.regimes.clone();
    for _ in 0..3 {
        let g = f.sol.state.g;
        let changes: Vec<Option<(Regime, [f64; NL])>> = (0..shots.len())
            .into_par_iter()
            .map(|i| {
                let s = &shots[i];
                if !s.estimate_spin {
                    return None;
                }
                let (reg, l) = (f.regimes[i], f.sol.state.l[i]);
                // Only the physics moves a shot: between two admissible states the chi²
                // difference of mimicking spins is mostly noise (measured: choosing by chi²
                // moved true gross-slip shots to stick and biased mu by a further +0.001).
                if spin::admissible(reg, &l, &g) {
                    return None;
                }
                let (areg, al, _) = spin::alternative(s, reg, &g, huber);
                spin::admissible(areg, &al, &g).then_some((areg, al))
            })
            .collect();
        if changes.iter().all(Option::is_none) {
            break;
        }
        let mut regimes = f.regimes.clone();
        let mut l = f.sol.state.l.clone();
        for (i, c) in changes.into_iter().enumerate() {
            if let Some((r, li)) = c {
                regimes[i] = r;
                l[i] = li;
            }
        }
        let sol = problem(shots, regimes.clone(), f.model, opts).solve(State { g, l }, MAX_ITER);
        f.regimes = regimes;
        f.sol = sol;
    }
    f.regimes
        .iter()
        .zip(&original)
        .filter(|(a, b)| a != b)
        .count()
}

/// Self-consistency of a fit: the table contact of each shot must be in the state its regime
/// assumes (`mu' N ≥ (2/7)|c|` for stick) at the fitted coefficients. E.g. mu–s for billiard
/// balls would need `mu' ≈ 5`; its chi² can be as low as mu–mu's because mu' barely shows.
fn consistency(f: &ModelFit, shots: &[ShotData]) -> f64 {
    let c = problem::coefficients(&f.sol.state.g);
    let agree = shots
        .iter()
        .zip(&f.sol.state.l)
        .zip(&f.regimes)
        .filter(|((s, l), reg)| {
            let m = crate::physics::regime::table_margin(&s.shot(l), &c, reg.ball_ball_stick());
            (m >= 0.0) == reg.table_stick()
        })
        .count();
    agree as f64 / shots.len().max(1) as f64
}

fn choose(fits: &[ModelFit], shots: &[ShotData], c: Criterion) -> usize {
    let s: Vec<ModelScore> = fits.iter().map(|f| score(f, shots)).collect();
    let any_consistent = s.iter().any(|x| x.consistency >= 0.8);
    // Inconsistent models only compete when no model is consistent.
    let key = |x: &ModelScore| {
        let penalty = if any_consistent && x.consistency < 0.8 {
            f64::INFINITY
        } else {
            0.0
        };
        penalty
            + match c {
                Criterion::Aic => x.aic,
                Criterion::Bic => x.bic,
            }
    };
    (0..s.len())
        .min_by(|&a, &b| key(&s[a]).total_cmp(&key(&s[b])))
        .expect("at least one model was fitted")
}

fn bootstrap(shots: &[ShotData], f: &ModelFit, opts: &FitOptions) -> BootstrapSummary {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let n = shots.len();
    let mut free = f.model.free_globals();
    free[3] = false; // the partition (hence mu0) is kept
    let mut samples: Vec<[f64; NG]> = Vec::new();
    for _ in 0..opts.bootstrap {
        let pick: Vec<usize> = (0..n).map(|_| rng.gen_range(0..n)).collect();
        let p = Problem {
            shots: pick.iter().map(|&i| &shots[i]).collect(),
            regimes: pick.iter().map(|&i| f.regimes[i]).collect(),
            free_global: free,
            huber: match opts.loss {
                Loss::Squared => None,
                Loss::Huber(k) => Some(k),
            },
        };
        let st = State {
            g: f.sol.state.g,
            l: pick.iter().map(|&i| f.sol.state.l[i]).collect(),
        };
        let sol = p.solve(st, 30);
        samples.push(sol.state.g);
    }
    let sd = |k: usize| {
        let m = samples.len() as f64;
        if m < 2.0 {
            return None;
        }
        let mean = samples.iter().map(|s| s[k]).sum::<f64>() / m;
        Some((samples.iter().map(|s| (s[k] - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt())
    };
    BootstrapSummary {
        resamples: samples.len(),
        e_se: sd(0),
        mu_se: sd(1),
        mu_table_se: sd(2),
    }
}

fn rms(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt())
}

#[allow(clippy::too_many_arguments)]
fn summarise(
    material: &str,
    rows: &[ShotRow],
    shots: &[ShotData],
    f: &ModelFit,
    scores: Vec<ModelScore>,
    bootstrap: Option<BootstrapSummary>,
    rejected: BTreeMap<usize, String>,
    n_skipped: usize,
    opts: &FitOptions,
) -> (MaterialFit, Vec<ResidualRow>) {
    let g = f.sol.state.g;
    let n_data = n_angles(shots);
    let n_local_free: usize = shots
        .iter()
        .map(|s| s.free_locals().iter().filter(|x| **x).count())
        .sum();
    let n_prior: usize = shots
        .iter()
        .map(|s| usize::from(s.psi_sigma > 0.0) + 2 * usize::from(s.estimate_spin))
        .sum();
    let k = f.model.free_globals().iter().filter(|x| **x).count();
    let dof = (n_data + n_prior).saturating_sub(k + n_local_free).max(1);
    let chi2 = f.sol.chi2;
    let chi2_red = chi2 / dof as f64;
    let scale = chi2_red.max(1.0).sqrt();
    let mut se = [0.0; NG];
    for p in 0..NG {
        se[p] = f.sol.cov_g[(p, p)].sqrt() * scale;
    }
    let mut notes = Vec::new();
    let mut mu0_se = None;
    if let Some((_, s)) = f.threshold {
        // Threshold interval plus the propagated error of e (mu0 ∝ 1/(1+e)).
        let s = s.hypot(g[3] * se[0] / (1.0 + g[0]));
        se[3] = s;
        mu0_se = Some(s);
    }
    let free = f.model.free_globals();
    let mut identified = Vec::new();
    let mut unidentified = BTreeMap::new();
    for p in 0..NG {
        if !free[p] {
            continue;
        }
        let limit = if p == 0 {
            0.1
        } else {
            (0.3 * g[p].abs()).max(0.02)
        };
        if se[p].is_finite() && se[p] <= limit {
            identified.push(GLOBAL_NAMES[p].to_string());
        } else {
            let mut why = if se[p].is_finite() {
                format!(
                    "standard error {:.3} exceeds {:.3}: the data do not determine {}",
                    se[p], limit, GLOBAL_NAMES[p]
                )
            } else {
                format!(
                    "the angles do not depend on {} in this model",
                    GLOBAL_NAMES[p]
                )
            };
            if p == 2 && f.regimes.iter().all(|r| *r == Regime::MuMu) {
                why.push_str(" (in gross slip mu' cancels from theta2 and barely moves delta2)");
            }
            unidentified.insert(GLOBAL_NAMES[p].to_string(), why);
        }
    }
    let is_id = |p: usize| identified.iter().any(|x| x == GLOBAL_NAMES[p]);
    let val = |p: usize| is_id(p).then_some(g[p]);
    let err = |p: usize| is_id(p).then_some(se[p]);
    // psi_L from Eq. (50) for a rolling cue ball.
    let eq50 = |mu0: f64, e: f64| crate::physics::regime::psi_limit_rolling(e, mu0);
    let (mut psi_l, mut psi_l_se) = (None, None);
    if let Some((mu0, _)) = f.threshold
        && is_id(3)
        && let Some(pl) = eq50(mu0, g[0])
    {
        psi_l = Some(pl.to_degrees());
        let x = pl.cos();
        let rel = (mu0_se.unwrap_or(0.0) / mu0).hypot(se[0] / (1.0 + g[0]));
        psi_l_se = Some((x / pl.sin().max(1e-9) * rel).to_degrees());
    }
    // Which error model the angles had: a shared shift of each photo's five angles (the
    // extractor's `frame_err_deg`) changes what the stated errors mean.
    let n_frame = shots.iter().filter(|s| s.frame_sigma > 0.0).count();
    if n_frame > 0 {
        notes.push(format!(
            "{n_frame} of {} shots state their angles' shared error (frame_err_deg): fitted as \
             one shift per shot",
            shots.len()
        ));
    }
    // Bounds on mu0 when every shot is on one side of the switch.
    let crit: Vec<f64> = shots
        .iter()
        .zip(&f.sol.state.l)
        .map(|(_, l)| critical_mu_static(g[0], l))
        .collect();
    let psis: Vec<f64> = f.sol.state.l.iter().map(|l| l[0].to_degrees()).collect();
    let (mut ps_min, mut ps_max, mut mu0_min, mut mu0_max) = (None, None, None, None);
    if f.regimes.iter().all(|r| r.ball_ball_stick()) {
        mu0_min = crit.iter().copied().reduce(f64::max);
        ps_min = psis.iter().copied().reduce(f64::max);
        notes.push(format!(
            "ball–ball contact sticks at every shot (psi up to {:.1}°): psi_L above it, mu0 ≥ {:.3}",
            ps_min.unwrap_or(f64::NAN),
            mu0_min.unwrap_or(f64::NAN)
        ));
        if let Some(pl) = eq50(g[1], g[0]) {
            notes.push(format!(
                "with mu0 = mu = {:.3}, Eq. (50) puts psi_L at {:.1}°",
                g[1],
                pl.to_degrees()
            ));
        }
    } else if f.regimes.iter().all(|r| !r.ball_ball_stick()) {
        mu0_max = crit.iter().copied().reduce(f64::min);
        ps_max = psis.iter().copied().reduce(f64::min);
        notes.push(format!(
            "gross slip at every shot (psi down to {:.1}°): psi_L below it or absent, mu0 < {:.3}",
            ps_max.unwrap_or(f64::NAN),
            mu0_max.unwrap_or(f64::NAN)
        ));
    }
    // Correlation of identified globals.
    let id_idx: Vec<usize> = (0..NG)
        .filter(|&p| is_id(p) && p != 3 || (p == 3 && is_id(3) && f.threshold.is_none()))
        .collect();
    let correlation = Correlation {
        params: id_idx
            .iter()
            .map(|&p| GLOBAL_NAMES[p].to_string())
            .collect(),
        matrix: id_idx
            .iter()
            .map(|&a| {
                id_idx
                    .iter()
                    .map(|&b| {
                        f.sol.cov_g[(a, b)] / (f.sol.cov_g[(a, a)] * f.sol.cov_g[(b, b)]).sqrt()
                    })
                    .collect()
            })
            .collect(),
    };
    // Per-shot residuals.
    let coeff = problem::coefficients(&g);
    let prob = problem(shots, f.regimes.clone(), f.model, opts);
    let mut res_rows = Vec::new();
    let mut resid: [Vec<f64>; 5] = Default::default();
    let (mut n_known, mut n_est, mut n_undet, mut n_assumed) = (0, 0, 0, 0);
    // Estimated spin: profile intervals and regime hypotheses per shot (independent, parallel).
    let ctx = spin::SpinContext {
        g,
        huber: prob.huber,
        scale,
    };
    let spins: Vec<Option<spin::ShotSpin>> = {
        use rayon::prelude::*;
        (0..shots.len())
            .into_par_iter()
            .map(|i| {
                shots[i].estimate_spin.then(|| {
                    spin::shot_spin(
                        &shots[i],
                        f.regimes[i],
                        f.sol.state.l[i],
                        f.sol.local_var_cond[i],
                        f.sol.local_var[i],
                        &ctx,
                    )
                })
            })
            .collect()
    };
    let mut n_ambiguous = 0;
    for (i, s) in shots.iter().enumerate() {
        // The reported hypothesis (regime, locals) of an estimated-spin shot may differ from the
        // global fit's; the fitted angles and residuals below are those of the reported one.
        let (regime_i, l) = match &spins[i] {
            Some(sp) => (sp.regime, sp.l),
            None => (f.regimes[i], f.sol.state.l[i]),
        };
        let pred = crate::physics::closed::angles(&s.shot(&l), &coeff, regime_i).as_array();
        let row = &rows[s.row];
        let mut fit_deg = [None; 4];
        let mut res_deg = [None; 4];
        let mut max_pull: f64 = 0.0;
        // Pulls net of the photo's shared shift (the normalised residuals); the residuals in
        // degrees are the plain data-minus-theory differences the figures show.
        let pulls = problem::residuals(s, &f.sol.state.g, &l, regime_i);
        for k in 0..4 {
            fit_deg[k] = pred[k].map(f64::to_degrees);
            if let (Some(m), Some(p)) = (s.meas[k], pred[k]) {
                let d = crate::physics::wrap(p - m);
                res_deg[k] = Some(d.to_degrees());
                resid[k + 1].push(d.to_degrees());
                max_pull = max_pull.max(pulls[k].abs());
            }
        }
        resid[0].push((l[0] - s.psi_meas).to_degrees());
        let (spin_source, spin_est, spin_err, english_est, english_err, spin_reason) =
            if let Some(sp) = &spins[i] {
                let (r_se, s_se) = (sp.r_err, sp.s_err);
                // Undetermined: the interval is as wide as half the prior or more.
                let r_ok = r_se.is_finite() && r_se < 0.5 * SPIN_PRIOR_SIGMA;
                let s_ok = s_se.is_finite() && s_se < 0.5 * ENGLISH_PRIOR_SIGMA;
                let mut why = sp.notes.clone();
                if sp.notes.iter().any(|n| n.contains("ambiguous")) {
                    n_ambiguous += 1;
                }
                if !r_ok {
                    why.push(format!(
                        "spin r not determined by the angles (error {r_se:.2})"
                    ));
                }
                if !s_ok {
                    why.push(format!(
                        "english s not determined by the angles (error {s_se:.2})"
                    ));
                }
                if r_ok {
                    n_est += 1;
                } else {
                    n_undet += 1;
                }
                (
                    if r_ok { "estimated" } else { "undetermined" },
                    r_ok.then_some(l[1]),
                    r_ok.then_some(r_se),
                    s_ok.then_some(l[2]),
                    s_ok.then_some(s_se),
                    (!why.is_empty()).then(|| why.join("; ")),
                )
            } else {
                n_known += 1;
                n_assumed += usize::from(row.spin.is_none());
                (
                    if row.spin.is_some() {
                        "known"
                    } else {
                        "assumed"
                    },
                    Some(l[1]),
                    None,
                    Some(l[2]),
                    None,
                    None,
                )
            };
        res_rows.push(ResidualRow {
            material: material.to_string(),
            file: row.file.clone(),
            model: f.model.name().to_string(),
            regime_est: Some(regime_i.name().to_string()),
            used: true,
            rejected_reason: None,
            psi_deg: row.psi_deg,
            psi_fit_deg: Some(l[0].to_degrees()),
            delta1_deg: row.delta1_deg,
            delta1_fit_deg: fit_deg[0],
            delta1_resid_deg: res_deg[0],
            delta2_deg: row.delta2_deg,
            delta2_fit_deg: fit_deg[1],
            delta2_resid_deg: res_deg[1],
            theta1_deg: row.theta1_deg,
            theta1_fit_deg: fit_deg[2],
            theta1_resid_deg: res_deg[2],
            theta2_deg: row.theta2_deg,
            theta2_fit_deg: fit_deg[3],
            theta2_resid_deg: res_deg[3],
            max_pull: Some(max_pull),
            spin_source: spin_source.to_string(),
            spin_est,
            spin_err,
            english_est,
            english_err,
            spin_reason,
        });
    }
    if n_ambiguous > 0 {
        notes.push(format!(
            "{n_ambiguous} shots fit in either ball–ball contact state with different spin: \
             their spin interval spans both (spin_reason)"
        ));
    }
    // A table without spin, fitted as rolling shots, that the model cannot reproduce: the
    // likeliest cause is spin the table does not state (follow, stun, draw, English), and the
    // coefficients are then wrong whatever their error bars say.
    let n_total = shots.len() + rejected.len();
    if n_assumed > 0
        && (chi2_red > POOR_FIT_CHI2_REDUCED
            || rejected.len() as f64 > POOR_FIT_REJECTED * n_total as f64)
    {
        notes.push(format!(
            "{POOR_FIT_NOTE} {n_assumed} of {} shots state no spin and were fitted as rolling (r = 1, \
             s = 0), and the model does not reproduce them (chi²/dof {chi2_red:.1}, {} of \
             {n_total} shots rejected): if the cue ball was struck with follow, stun, draw or \
             English, fit with --spin estimate (or auto)",
            shots.len(),
            rejected.len()
        ));
    }
    for (&i, why) in &rejected {
        let row = &rows[i];
        res_rows.push(ResidualRow {
            material: material.to_string(),
            file: row.file.clone(),
            model: f.model.name().to_string(),
            regime_est: None,
            used: false,
            rejected_reason: Some(why.clone()),
            psi_deg: row.psi_deg,
            psi_fit_deg: None,
            delta1_deg: row.delta1_deg,
            delta1_fit_deg: None,
            delta1_resid_deg: None,
            delta2_deg: row.delta2_deg,
            delta2_fit_deg: None,
            delta2_resid_deg: None,
            theta1_deg: row.theta1_deg,
            theta1_fit_deg: None,
            theta1_resid_deg: None,
            theta2_deg: row.theta2_deg,
            theta2_fit_deg: None,
            theta2_resid_deg: None,
            max_pull: None,
            spin_source: "n/a".into(),
            spin_est: None,
            spin_err: None,
            english_est: None,
            english_err: None,
            spin_reason: None,
        });
    }
    let sc = score(f, shots);
    let fit = MaterialFit {
        material: material.to_string(),
        model: f.model.name().to_string(),
        e: val(0),
        e_se: err(0),
        mu: val(1),
        mu_se: err(1),
        mu_table: val(2),
        mu_table_se: err(2),
        mu_static: val(3),
        mu_static_se: err(3),
        psi_l_deg: psi_l,
        psi_l_se_deg: psi_l_se,
        psi_l_min_deg: ps_min,
        psi_l_max_deg: ps_max,
        mu_static_min: mu0_min,
        mu_static_max: mu0_max,
        n_used: shots.len(),
        n_rejected: rejected.len(),
        n_skipped,
        identified,
        unidentified,
        chi2,
        dof,
        chi2_reduced: chi2_red,
        se_scale: scale,
        aic: sc.aic,
        bic: sc.bic,
        scores,
        rms_deg: AngleRms {
            psi: rms(&resid[0]),
            delta1: rms(&resid[1]),
            delta2: rms(&resid[2]),
            theta1: rms(&resid[3]),
            theta2: rms(&resid[4]),
        },
        correlation,
        bootstrap,
        spin_known: n_known,
        spin_estimated: n_est,
        spin_undetermined: n_undet,
        notes,
    };
    (fit, res_rows)
}
