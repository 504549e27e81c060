//! The report's figures, in the style of the paper's Figs. 5 and 9–15.
//!
//! Per material (measured points with 1-sigma error bars against theory for the fitted
//! coefficients, solid, and the paper's Table 1 coefficients, dashed):
//! - Fig. 9: `tan delta1` and `tan theta1` against `tan psi`;
//! - Fig. 10: `alpha1 = delta1 - psi` and `theta1` against `psi`, with the paper's μ–μ and s–μ
//!   curves;
//! - Fig. 11: `delta2` against `psi` with the four regimes forced over the whole range;
//! - Figs. 12/13: `delta2` against `psi` in the auto regime (stick/slip decided with the static
//!   friction `mu0`), which jumps at `psi_L` when `mu0 != mu`, beside the gross-slip curve;
//! - residuals `measured - predicted(fitted)` of all four angles against `psi`;
//! - shots of unknown spin (fits with `--spin estimate|auto`): each shot's estimated spin `r`
//!   and English `s` with their 1-sigma errors against its fitted `psi`, coloured by its
//!   estimated contact regime, and the four residuals of the same shots;
//! - the regime map over (`psi`, `r = R omega/v`) for the fitted coefficients;
//! - predicted paths for a fan of spins at `psi = 45°`.
//!
//! Theory-only: Fig. 5 (regime map for `e = 0.5, mu = 0.3, mu' = 0.5`) and Figs. 14, 15 (paths for
//! the paper's billiard and rubber coefficients). Curves come from [`impulse::solve`]; the regime
//! map uses [`regime::select_regime`], i.e. the criteria as derived in `physics::regime`, which
//! need not reproduce every region of the paper's printed Fig. 5 (the captions say so).
//!
//! Display frame of the path figures: the cue ball arrives along `+X` and the impact happens at
//! the origin; the line of centres points at `-psi` from `+X` (object ball below the cue line),
//! so the impact frame `(x, y)` maps to the display by a rotation of `-psi`.

use super::plot::{
    self, Cells, Dash, DataPoint, Figure, LegendAt, Line, Marker, Note, Panel, Points,
};
use super::theory::{self, DELTA1, DELTA2, Sweep, THETA1, THETA2};
use crate::physics::path::{BallPath, Cloth};
use crate::physics::{Coefficients, Regime, RegimeChoice, Shot, impulse, regime};
use crate::table::{ShotRow, Status};
use nalgebra::{Vector2, Vector3};
use plotters::style::RGBColor;

/// Theory curves: every figure samples `psi` on this range (degrees) with this many steps.
const PSI_RANGE: (f64, f64) = (0.25, 89.5);
const PSI_STEPS: usize = 357;

const BLACK: RGBColor = RGBColor(20, 20, 20);
const GREY: RGBColor = RGBColor(120, 120, 120);

/// Line colour of each regime (the regime map uses lighter fills of the same hues).
pub fn regime_color(r: Regime) -> RGBColor {
    match r {
        Regime::MuMu => RGBColor(31, 119, 180),
        Regime::SlipMu => RGBColor(230, 110, 0),
        Regime::MuSlip => RGBColor(44, 150, 44),
        Regime::SlipSlip => RGBColor(200, 30, 40),
    }
}

fn regime_fill(r: Regime) -> RGBColor {
    match r {
        Regime::MuMu => RGBColor(190, 215, 240),
        Regime::SlipMu => RGBColor(255, 214, 170),
        Regime::MuSlip => RGBColor(195, 235, 190),
        Regime::SlipSlip => RGBColor(245, 185, 185),
    }
}

/// Colour of a material's points and fitted curves.
pub fn material_color(name: &str) -> RGBColor {
    match name {
        "billiard" => RGBColor(0, 120, 70),
        "steel" => RGBColor(40, 70, 170),
        "rubber" => RGBColor(185, 40, 30),
        _ => RGBColor(120, 50, 150),
    }
}

/// A set of coefficients with the regime rule used to draw its curves.
#[derive(Debug, Clone)]
pub struct Model {
    /// Legend text, e.g. `fit` or `paper Table 1`.
    pub label: String,
    pub coeffs: Coefficients,
    pub choice: RegimeChoice,
    /// Which of `e, mu, mu_table, mu_static` the data did not determine (drawn with the paper's
    /// value or a default): marked in the legend, so that a curve is not read as fitted there.
    pub assumed: [bool; 4],
}

impl Model {
    fn describe(&self) -> String {
        let c = &self.coeffs;
        let mark = |i: usize| if self.assumed[i] { " (not fitted)" } else { "" };
        let mut s = format!(
            "e={:.2}{}, μ={:.2}{}, μ'={:.2}{}",
            c.e,
            mark(0),
            c.mu,
            mark(1),
            c.mu_table,
            mark(2)
        );
        if (c.mu_static - c.mu).abs() > 1e-12 {
            s.push_str(&format!(", μ0={:.2}{}", c.mu_static, mark(3)));
        }
        s
    }

    fn legend(&self) -> String {
        format!("{} ({})", self.label, self.describe())
    }
}

/// Everything the per-material figures need.
#[derive(Debug, Clone)]
pub struct MaterialFigures {
    /// Key, e.g. `steel` (file names).
    pub name: String,
    /// Display label, e.g. `steel bearings`.
    pub label: String,
    /// Rows of the angles table for this material (only `ok` rows with a `psi` are plotted).
    pub rows: Vec<ShotRow>,
    pub fitted: Option<Model>,
    pub paper: Option<Model>,
    /// Cue-ball state for the theory curves (spin, English, mass ratio; `psi` ignored).
    pub template: Shot,
    /// Residuals of the fit per shot; when empty, residuals are computed here from the fitted
    /// coefficients at each shot's measured `psi`.
    pub fit_residuals: Vec<ResidualPoint>,
    /// Ball radius (m), cue speed (m/s) and cloth friction for the path figure.
    pub radius_m: f64,
    pub speed_mps: f64,
    pub cloth: Cloth,
}

impl MaterialFigures {
    fn measured(&self) -> impl Iterator<Item = &ShotRow> {
        self.rows
            .iter()
            .filter(|r| r.status == Status::Ok && r.psi_deg.is_some())
    }

    /// Measured points `(x, y)` from a row, with errors propagated by `f` (value, error).
    fn points(&self, marker: Marker, f: impl Fn(&ShotRow) -> Option<DataPoint>) -> Points {
        let points: Vec<DataPoint> = self.measured().filter_map(f).collect();
        // Not every shot measures every angle (an undefined or unresolved one has no point).
        let (k, n) = (points.len(), self.n_measured());
        let label = if k == n {
            format!("measured ({n} shots)")
        } else {
            format!("measured ({k} of {n} shots)")
        };
        Points {
            label: Some(label),
            points,
            color: material_color(&self.name),
            marker,
        }
    }

    fn models(&self) -> Vec<(&Model, RGBColor, Dash)> {
        let mut out = Vec::new();
        if let Some(m) = &self.fitted {
            out.push((m, material_color(&self.name), Dash::Solid));
        }
        if let Some(m) = &self.paper {
            out.push((m, BLACK, Dash::Dashed));
        }
        out
    }

    fn sweep(&self, m: &Model, choice: RegimeChoice) -> Sweep {
        theory::sweep(&m.coeffs, &self.template, choice, PSI_RANGE, PSI_STEPS)
    }

    fn n_measured(&self) -> usize {
        self.measured().count()
    }

    fn psi_max_deg(&self) -> f64 {
        self.measured()
            .filter_map(|r| r.psi_deg)
            .fold(0.0, f64::max)
    }

    fn spin_text(&self) -> String {
        format!(
            "r = Rω/v = {}, s = {}, M = {}",
            fmt_num(self.template.spin),
            fmt_num(self.template.english),
            fmt_num(self.template.mass_ratio)
        )
    }
}

fn fmt_num(x: f64) -> String {
    if (x - x.round()).abs() < 1e-9 {
        format!("{}", x.round() as i64)
    } else {
        format!("{x:.2}")
    }
}

/// A point with symmetric errors.
fn dp(x: f64, x_err: Option<f64>, y: f64, y_err: Option<f64>) -> DataPoint {
    DataPoint {
        x,
        y,
        x_err: plot::sym(x_err),
        y_err: plot::sym(y_err),
    }
}

/// `tan` of an angle in degrees and its 1-sigma interval `tan(x ± σ)` as (below, above): `tan`
/// is far from linear near 90°, where a linearised `sec² x · σ` misstates the interval. The
/// upper end stops short of the asymptote.
fn tan_err(x_deg: f64, err_deg: Option<f64>) -> (f64, Option<(f64, f64)>) {
    let t = x_deg.to_radians().tan();
    let e = err_deg.map(|e| {
        let lo = (x_deg - e).to_radians().tan();
        let hi = (x_deg + e).min(89.9).to_radians().tan();
        (t - lo, (hi - t).max(0.0))
    });
    (t, e)
}

/// Fig. 9: `tan delta1` (a) and `tan theta1` (b) against `tan psi`.
pub fn fig09(m: &MaterialFigures) -> Figure {
    let psi_hi = (m.psi_max_deg() + 5.0).clamp(60.0, 80.0);
    let x_hi = psi_hi.to_radians().tan();
    let mut panels = Vec::new();
    for (idx, name, sym, marker) in [
        (DELTA1, "(a)", "tan δ₁", Marker::Square),
        (THETA1, "(b)", "tan θ₁", Marker::Triangle),
    ] {
        let mut p = Panel::new(
            format!("{} {}: {sym} vs tan ψ", m.label, name),
            "tan ψ",
            sym,
        );
        p.x_range = (0.0, x_hi);
        for (model, color, dash) in m.models() {
            let sw = m.sweep(model, model.choice);
            let samples = sw.samples(|psi, a| {
                if psi > psi_hi {
                    return None;
                }
                // Break the curve at the asymptote of tan (a direction through ±90°).
                let d = a[idx]?;
                if d.abs() > 89.0 {
                    return None;
                }
                Some((psi.to_radians().tan(), d.to_radians().tan()))
            });
            let regimes = theory::regime_path(&sw.regimes());
            p.lines.push(
                Line::new(format!("{} [{regimes}]", model.legend()), color, dash)
                    .with_samples(samples),
            );
        }
        p.points.push(m.points(marker, |r| {
            let (x, xe) = tan_err(r.psi_deg?, r.psi_err_deg);
            let y_deg = if idx == DELTA1 {
                r.delta1_deg?
            } else {
                r.theta1_deg?
            };
            let y_err = if idx == DELTA1 {
                r.delta1_err_deg
            } else {
                r.theta1_err_deg
            };
            // Directions beyond 90° have negative tangents that belong to another branch:
            // plot only points on the branch of the theory curves.
            if y_deg.abs() >= 89.0 {
                return None;
            }
            let (y, ye) = tan_err(y_deg, y_err);
            Some(DataPoint {
                x,
                y,
                x_err: xe,
                y_err: ye,
            })
        }));
        // tan of a direction near 90° runs off to infinity: size the axis by the data when
        // there is any, else by a generous multiple of tan psi.
        let data_hi = p
            .points
            .iter()
            .flat_map(|s| &s.points)
            .map(|d| d.y)
            .fold(f64::NEG_INFINITY, f64::max);
        let cap = if data_hi.is_finite() {
            1.5 * data_hi + 1.0
        } else {
            15.0 * x_hi
        };
        let p = clamp_y(p.auto_y(1.0), -0.5, cap);
        panels.push(p);
    }
    Figure::new(
        format!("{}_fig09_tan", m.name),
        format!(
            "Fig. 9 style, {}: tan δ₁ (a) and tan θ₁ (b) against tan ψ ({}). Solid: fitted \
             coefficients; dashed: the paper's Table 1; the regime sequence along ψ is in brackets. \
             Directions within 1° of 90° have no finite tangent on this scale and are left out \
             (Fig. 10 shows every shot).",
            m.label,
            m.spin_text()
        ),
        panels,
    )
}

/// Fig. 10: `alpha1 = delta1 - psi` (a) and `theta1` (b) against `psi`.
pub fn fig10(m: &MaterialFigures) -> Figure {
    let mut panels = Vec::new();
    for (idx, name, sym) in [(DELTA1, "(a)", "α₁ = δ₁ − ψ"), (THETA1, "(b)", "θ₁")] {
        let mut p = Panel::new(
            format!("{} {}: {sym} vs ψ", m.label, name),
            "impact angle ψ (deg)",
            format!("{sym} (deg)"),
        );
        p.x_range = (0.0, 90.0);
        p.legend = LegendAt::Auto;
        let f = move |psi: f64, a: &[Option<f64>; 4]| {
            let v = a[idx]?;
            Some((psi, if idx == DELTA1 { v - psi } else { v }))
        };
        if let Some(model) = &m.fitted {
            let sw = m.sweep(model, model.choice);
            p.lines.push(
                Line::new(
                    format!(
                        "{} [{}]",
                        model.legend(),
                        theory::regime_path(&sw.regimes())
                    ),
                    material_color(&m.name),
                    Dash::Solid,
                )
                .with_samples(sw.samples(f)),
            );
        }
        p.points.push(m.points(
            if idx == DELTA1 {
                Marker::Square
            } else {
                Marker::Triangle
            },
            |r| {
                let psi = r.psi_deg?;
                let (y, ye) = if idx == DELTA1 {
                    let d = r.delta1_deg?;
                    // Errors of delta1 and psi are correlated in the measurement; quadrature is
                    // the conservative choice for a plot.
                    let e = match (r.delta1_err_deg, r.psi_err_deg) {
                        (Some(a), Some(b)) => Some(a.hypot(b)),
                        (a, b) => a.or(b),
                    };
                    (d - psi, e)
                } else {
                    (r.theta1_deg?, r.theta1_err_deg)
                };
                Some(dp(psi, r.psi_err_deg, y, ye))
            },
        ));
        // The axis follows the data, the fitted curve and the paper's auto-regime curve; a forced
        // regime far from them (μ–μ with rubber's friction below psi_L) may leave the window.
        let mut sizing = p.clone();
        if let Some(model) = &m.paper {
            let sw = m.sweep(model, RegimeChoice::Auto);
            sizing
                .lines
                .push(Line::new("", BLACK, Dash::Solid).with_samples(sw.samples(f)));
        }
        let mut p = p.ranges((0.0, 90.0), sizing.auto_y(10.0).y_range);
        if let Some(model) = &m.paper {
            // Paper's coefficients in black (dashed μ–μ), as in every figure; s–μ dotted.
            for (reg, dash, color) in [
                (Regime::MuMu, Dash::Dashed, BLACK),
                (Regime::SlipMu, Dash::Dotted, regime_color(Regime::SlipMu)),
            ] {
                let sw = m.sweep(model, RegimeChoice::Fixed(reg));
                let mut line = Line::new(
                    format!("{} {}", model.label, theory::pretty_regime(reg)),
                    color,
                    dash,
                )
                .with_samples(sw.samples(f));
                line.width = 2;
                p.lines.push(line);
            }
        }
        panels.push(p);
    }
    let paper = m
        .paper
        .as_ref()
        .map(|p| {
            format!(
                " Paper coefficients ({}): μ–μ dashed, s–μ dotted.",
                p.describe()
            )
        })
        .unwrap_or_default();
    Figure::new(
        format!("{}_fig10_deflection", m.name),
        format!(
            "Fig. 10 style, {}: α₁ = δ₁ − ψ (a) and θ₁ (b) against ψ ({}). Solid: fitted \
             coefficients in the regime the fit selected.{paper}",
            m.label,
            m.spin_text()
        ),
        panels,
    )
}

/// Fig. 11: `delta2` against `psi` with the four regime curves.
pub fn fig11(m: &MaterialFigures) -> Figure {
    let mut p = Panel::new(
        format!("{}: δ₂ vs ψ, the four regimes", m.label),
        "impact angle ψ (deg)",
        "δ₂ (deg)",
    );
    p.x_range = (0.0, 90.0);
    p.legend = LegendAt::Auto;
    let f = |psi: f64, a: &[Option<f64>; 4]| Some((psi, a[DELTA2]?));
    let reference = m.paper.as_ref().or(m.fitted.as_ref());
    // The axis follows the data and the auto-regime curves; forced regimes far from them (s–μ
    // at grazing incidence heads for 90°) leave through the top, as in the paper's Fig. 11.
    let mut sizing = p.clone();
    for (model, color, dash) in m.models() {
        let sw = m.sweep(model, RegimeChoice::Auto);
        sizing
            .lines
            .push(Line::new("", color, dash).with_samples(sw.samples(f)));
    }
    sizing.points.push(delta2_points(m));
    let sizing = sizing.auto_y(10.0);
    let y_range = (
        sizing.y_range.0,
        sizing.y_range.0 + 1.8 * (sizing.y_range.1 - sizing.y_range.0),
    );
    if let Some(model) = reference {
        for reg in Regime::ALL {
            let sw = m.sweep(model, RegimeChoice::Fixed(reg));
            let dash = if reg.ball_ball_stick() {
                Dash::Dotted
            } else {
                Dash::Solid
            };
            p.lines.push(
                Line::new(
                    format!("{} {}", model.label, theory::pretty_regime(reg)),
                    regime_color(reg),
                    dash,
                )
                .with_samples(sw.samples(f)),
            );
        }
    }
    if let Some(model) = &m.fitted {
        let sw = m.sweep(model, model.choice);
        let mut line = Line::new(
            format!(
                "{} [{}]",
                model.legend(),
                theory::regime_path(&sw.regimes())
            ),
            BLACK,
            Dash::Dashed,
        )
        .with_samples(sw.samples(f));
        line.width = 2;
        p.lines.push(line);
    }
    p.points.push(delta2_points(m));
    let who = reference.map(|r| r.describe()).unwrap_or_default();
    Figure::new(
        format!("{}_fig11_delta2_regimes", m.name),
        format!(
            "Fig. 11 style, {}: δ₂ against ψ ({}). Coloured: each regime forced over the whole \
             range with {who} (solid: gross slip at the ball–ball contact, dotted: slip–stick); \
             black dashed: fitted coefficients in the regime the fit selected.{}",
            m.label,
            m.spin_text(),
            delta2_coverage(m, n_delta2(m))
        ),
        vec![p.ranges((0.0, 90.0), y_range)],
    )
    .with_size(960, 640)
}

fn delta2_points(m: &MaterialFigures) -> Points {
    m.points(Marker::Circle, |r| {
        Some(dp(
            r.psi_deg?,
            r.psi_err_deg,
            r.delta2_deg?,
            r.delta2_err_deg,
        ))
    })
}

/// Shots with a `delta2` point.
fn n_delta2(m: &MaterialFigures) -> usize {
    m.measured().filter(|r| r.delta2_deg.is_some()).count()
}

/// Why some shots (or all) have no `delta2` point, for the captions of Figs. 11 and 12.
fn delta2_coverage(m: &MaterialFigures, k: usize) -> String {
    format!(
        " δ₂ is measured on {k} of the {} shots: the others' object-ball slide does not show (a \
         path straight from the waiting disc, whose slide hides under it, has no δ₂).",
        m.n_measured()
    )
}

/// Figs. 12, 13: `delta2` against `psi` in the auto regime (the `psi_L` jump) and in gross slip.
pub fn fig12(m: &MaterialFigures) -> Figure {
    let mut p = Panel::new(
        format!("{}: δ₂ vs ψ, stick/slip transition", m.label),
        "impact angle ψ (deg)",
        "δ₂ (deg)",
    );
    p.x_range = (0.0, 90.0);
    let f = |psi: f64, a: &[Option<f64>; 4]| Some((psi, a[DELTA2]?));
    let mut limits = Vec::new();
    for (model, color, dash) in m.models() {
        let sw = m.sweep(model, RegimeChoice::Auto);
        p.lines.push(
            Line::new(
                format!(
                    "{} auto [{}]",
                    model.legend(),
                    theory::regime_path(&sw.regimes())
                ),
                color,
                dash,
            )
            .with_samples(sw.samples(f)),
        );
        for b in regime::regime_boundaries(&m.template, &model.coeffs) {
            limits.push((model.label.clone(), b, color));
        }
    }
    p.points.push(delta2_points(m));
    // The axis follows the data and the auto-regime curves; the gross-slip comparison may leave
    // the window where it is far off (a large mu sends delta2 towards 180° at small psi).
    let mut p = p.auto_y(10.0);
    // As in the paper's Figs. 12, 13: the dotted gross-slip curve uses Table 1's coefficients.
    if let Some(model) = m.paper.as_ref().or(m.fitted.as_ref()) {
        let sw = m.sweep(model, RegimeChoice::Fixed(Regime::MuMu));
        p.lines.push(
            Line::new(
                format!("{} gross slip μ–μ", model.label),
                regime_color(Regime::MuMu),
                Dash::Dotted,
            )
            .with_samples(sw.samples(f)),
        );
    }
    let (y0, y1) = p.y_range;
    let mut limit_text = Vec::new();
    for (i, (label, b, color)) in limits.iter().enumerate() {
        let psi_l = b.psi.to_degrees();
        p.lines.push(Line::guide(
            vec![(psi_l, y0), (psi_l, y1)],
            *color,
            Dash::Dashed,
        ));
        let text = format!(
            "ψ_L = {psi_l:.1}° ({} → {})",
            theory::pretty_regime(b.below),
            theory::pretty_regime(b.above)
        );
        // Upper left: delta2 grows with psi, so that corner is free of curves and points.
        p.notes.push(Note {
            x: 2.0,
            y: y1 - (0.03 + 0.06 * i as f64) * (y1 - y0),
            text: format!("{label}: {text}"),
            color: *color,
        });
        limit_text.push(format!("{label} {text}"));
    }
    let k = n_delta2(m);
    if k == 0 {
        p.notes.push(Note {
            x: 2.0,
            y: y1 - (0.03 + 0.06 * limits.len() as f64) * (y1 - y0),
            text: "no shot measures δ₂ (its slide hides under the waiting disc)".into(),
            color: BLACK,
        });
    }
    let limits = if limit_text.is_empty() {
        " No regime change for ψ in (0°, 90°): the curve is continuous.".to_string()
    } else {
        format!(" Regime changes: {}.", limit_text.join("; "))
    };
    Figure::new(
        format!("{}_fig12_delta2_jump", m.name),
        format!(
            "Figs. 12/13 style, {}: δ₂ against ψ with the regime chosen by the stick/slip \
             conditions (static friction μ0 decides where stick gives way to slip, so δ₂ jumps at \
             ψ_L when μ0 ≠ μ), beside the gross-slip curve (dotted).{limits}{}",
            m.label,
            delta2_coverage(m, k)
        ),
        vec![p],
    )
    .with_size(960, 640)
}

/// One shot's residuals `[delta1, delta2, theta1, theta2]` (degrees) and their 1-sigma errors.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualPoint {
    pub psi_deg: f64,
    pub resid_deg: [Option<f64>; 4],
    pub err_deg: [Option<f64>; 4],
    /// The fit's estimate of the shot's spin; `None` when the spin was known or assumed.
    pub spin: Option<SpinEstimate>,
}

/// A shot's spin as the fit estimated it (`spin_est, spin_err, english_est, english_err,
/// regime_est` of the per-shot table); a component the shot does not determine is `None`.
#[derive(Debug, Clone, PartialEq)]
pub struct SpinEstimate {
    /// `r = R omega/v` and its 1-sigma error.
    pub spin: Option<f64>,
    pub spin_err: Option<f64>,
    /// `s = R omega_z/v` and its 1-sigma error.
    pub english: Option<f64>,
    pub english_err: Option<f64>,
    /// Contact regime of the shot at its estimate.
    pub regime: Option<Regime>,
}

/// Residuals computed from the fitted coefficients at each shot's measured `psi`, spin and
/// English (used when the fit did not provide its own).
fn model_residuals(m: &MaterialFigures, model: &Model) -> Vec<ResidualPoint> {
    m.measured()
        .filter_map(|r| {
            let psi = r.psi_deg?;
            let shot = Shot {
                psi: psi.to_radians(),
                spin: r.spin.unwrap_or(m.template.spin),
                english: r.english.unwrap_or(m.template.english),
                ..m.template
            };
            let pred = impulse::solve(&shot, &model.coeffs, model.choice)
                .angles()
                .to_degrees();
            let meas = [r.delta1_deg, r.delta2_deg, r.theta1_deg, r.theta2_deg];
            let mut resid = [None; 4];
            for i in 0..4 {
                resid[i] = match (meas[i], pred[i]) {
                    (Some(a), Some(b)) => Some(wrap_deg(a - b)),
                    _ => None,
                };
            }
            Some(ResidualPoint {
                psi_deg: psi,
                spin: None,
                resid_deg: resid,
                err_deg: [
                    r.delta1_err_deg,
                    r.delta2_err_deg,
                    r.theta1_err_deg,
                    r.theta2_err_deg,
                ],
            })
        })
        .collect()
}

/// Residuals `measured - predicted` of the four angles against `psi`, in degrees: the fit's own
/// (at its fitted `psi` of each shot) or, without them, from the fitted coefficients.
pub fn residuals(m: &MaterialFigures) -> Option<Figure> {
    let model = m.fitted.as_ref()?;
    let (points, source) = if m.fit_residuals.is_empty() {
        (
            model_residuals(m, model),
            "at each shot's measured ψ, spin and English",
        )
    } else {
        (
            m.fit_residuals.clone(),
            "as the fit computed them (at the fitted ψ of each shot)",
        )
    };
    let all = ResidualSeries {
        label: String::new(),
        color: material_color(&m.name),
        marker: Marker::Circle,
        points: points.iter().collect(),
    };
    let panels = residual_panels(&m.label, &[all]);
    Some(
        Figure::new(
            format!("{}_residuals", m.name),
            format!(
                "Residuals of the four angles against ψ, {}: measured minus the prediction of the \
                 fitted coefficients ({}), {source}; error bars are the extraction's 1σ.",
                m.label,
                model.describe()
            ),
            panels,
        )
        .with_size(1400, 1000),
    )
}

/// One coloured series of residual points (`label` empty: the legend gives counts only).
struct ResidualSeries<'a> {
    label: String,
    color: RGBColor,
    marker: Marker,
    points: Vec<&'a ResidualPoint>,
}

/// The four residual panels (`delta1, delta2, theta1, theta2` against `psi`), each series with
/// its shot count and rms in the legend; series without points in a panel are left out.
fn residual_panels(title: &str, series: &[ResidualSeries]) -> Vec<Panel> {
    let mut panels = Vec::new();
    for (idx, sym) in [
        (DELTA1, "δ₁"),
        (DELTA2, "δ₂"),
        (THETA1, "θ₁"),
        (THETA2, "θ₂"),
    ] {
        let mut p = Panel::new(
            format!("{title}: residual of {sym}"),
            "impact angle ψ (deg)",
            format!("{sym} measured − fit (deg)"),
        );
        p.x_range = (0.0, 90.0);
        p.legend = LegendAt::Auto;
        p.lines.push(Line::guide(
            vec![(0.0, 0.0), (90.0, 0.0)],
            GREY,
            Dash::Solid,
        ));
        for s in series {
            let pts: Vec<DataPoint> = s
                .points
                .iter()
                .filter_map(|q| {
                    Some(DataPoint {
                        x: q.psi_deg,
                        y: q.resid_deg[idx]?,
                        x_err: None,
                        y_err: plot::sym(q.err_deg[idx]),
                    })
                })
                .collect();
            if pts.is_empty() && series.len() > 1 {
                continue;
            }
            let rms = (pts.iter().map(|d| d.y * d.y).sum::<f64>() / pts.len().max(1) as f64).sqrt();
            let counts = format!("{}, rms {rms:.2}°", shots(pts.len()));
            p.points.push(Points {
                label: Some(if s.label.is_empty() {
                    counts
                } else {
                    format!("{}: {counts}", s.label)
                }),
                points: pts,
                color: s.color,
                marker: s.marker,
            });
        }
        if p.points.iter().all(|s| s.points.is_empty()) {
            p.notes.push(Note {
                x: 5.0,
                y: 0.5,
                text: format!("no {sym} residuals for these shots"),
                color: GREY,
            });
        }
        panels.push(p.auto_y(2.0));
    }
    panels
}

/// `n shots` with the singular for one.
fn shots(n: usize) -> String {
    if n == 1 {
        "1 shot".to_string()
    } else {
        format!("{n} shots")
    }
}

/// Marker of a regime in the spin figure (shape as well as colour tells the regimes apart).
fn regime_marker(r: Option<Regime>) -> Marker {
    match r {
        Some(Regime::MuMu) => Marker::Circle,
        Some(Regime::SlipMu) => Marker::Square,
        Some(Regime::MuSlip) => Marker::Triangle,
        Some(Regime::SlipSlip) | None => Marker::Cross,
    }
}

/// Shots of unknown spin (issue 8): (a) estimated spin `r` and (b) English `s` with their
/// 1-sigma errors against the fitted `psi`, one series per estimated regime, and (c–f) the four
/// residuals of the same shots in the same colours. `None` when no shot has an estimated spin
/// (all known or assumed) or there is no fit.
pub fn spin_estimates(m: &MaterialFigures) -> Option<Figure> {
    let model = m.fitted.as_ref()?;
    let est: Vec<&ResidualPoint> = m
        .fit_residuals
        .iter()
        .filter(|q| q.spin.is_some())
        .collect();
    if est.is_empty() {
        return None;
    }
    let spin_of = |q: &ResidualPoint| q.spin.clone().expect("filtered on spin");
    let mut series = Vec::new();
    for reg in Regime::ALL.map(Some).into_iter().chain([None]) {
        let points: Vec<&ResidualPoint> = est
            .iter()
            .copied()
            .filter(|q| spin_of(q).regime == reg)
            .collect();
        if points.is_empty() {
            continue;
        }
        series.push(ResidualSeries {
            label: reg
                .map_or("regime not given", theory::pretty_regime)
                .to_string(),
            color: reg.map_or(GREY, regime_color),
            marker: regime_marker(reg),
            points,
        });
    }
    // Panel of one spin component: points where the fit determined it (finite error bar).
    let component = |title: String,
                     y_label: &str,
                     get: fn(&SpinEstimate) -> (Option<f64>, Option<f64>),
                     guides: &[(f64, Dash)],
                     min_span: f64| {
        let mut p = Panel::new(title, "impact angle ψ (deg), fitted", y_label);
        p.x_range = (0.0, 90.0);
        p.legend = LegendAt::Auto;
        for (y, dash) in guides {
            p.lines
                .push(Line::guide(vec![(0.0, *y), (90.0, *y)], GREY, *dash));
        }
        let mut n_shown = 0;
        for s in &series {
            let points: Vec<DataPoint> = s
                .points
                .iter()
                .filter_map(|q| {
                    let (v, e) = get(&spin_of(q));
                    let v = v.filter(|v| v.is_finite())?;
                    Some(dp(q.psi_deg, None, v, e.filter(|e| e.is_finite())))
                })
                .collect();
            if points.is_empty() {
                continue;
            }
            n_shown += points.len();
            p.points.push(Points {
                label: Some(format!("{}: {}", s.label, shots(points.len()))),
                points,
                color: s.color,
                marker: s.marker,
            });
        }
        (p.auto_y(min_span), n_shown)
    };
    let n = est.len();
    let (pr, n_r) = component(
        format!("{}: estimated spin r", m.label),
        "spin r = Rω/v (1 rolling, 0 stun, <0 draw)",
        |s| (s.spin, s.spin_err),
        &[(1.0, Dash::Dashed), (0.0, Dash::Dotted)],
        2.0,
    );
    let (ps, n_s) = component(
        format!("{}: estimated English s", m.label),
        "English s = Rω_z/v",
        |s| (s.english, s.english_err),
        &[(0.0, Dash::Dashed)],
        1.0,
    );
    let mut panels = vec![pr, ps];
    panels.extend(residual_panels(
        &format!("{}, estimated-spin shots", m.label),
        &series,
    ));
    Some(
        Figure::new(
            format!("{}_spin_estimates", m.name),
            format!(
                "Shots of unknown spin, {}: (a) the spin r = Rω/v and (b) the English s = Rω_z/v \
                 estimated for each shot jointly with the coefficients ({}), against the shot's \
                 fitted ψ, with 1σ error bars from the shot's profile likelihood (widened where \
                 both ball–ball contact states fit); colour and marker give the shot's estimated \
                 regime (regime_est); dashed r = 1 rolling, dotted r = 0 stun, dashed s = 0 no \
                 English. (c–f) residuals measured − fit of the four angles of the same shots, \
                 same colours, error bars the extraction's 1σ. {n} shots with estimated spin; \
                 r is undetermined (not drawn) for {} of them and s for {}.",
                m.label,
                model.describe(),
                n - n_r,
                n - n_s
            ),
            panels,
        )
        .with_size(1400, 1500),
    )
}

/// Wraps an angle difference to (-180°, 180°].
pub fn wrap_deg(d: f64) -> f64 {
    let w = d.rem_euclid(360.0);
    if w > 180.0 { w - 360.0 } else { w }
}

/// Regime map over (`psi`, `r = R omega/v`), Fig. 5 style, from [`regime::select_regime`].
pub fn regime_map(
    name: &str,
    title: &str,
    c: &Coefficients,
    template: &Shot,
    measured: &[(f64, f64)],
) -> Figure {
    const PSI_STEP: f64 = 0.5;
    let (r_lo, r_hi, r_step): (f64, f64, f64) = (-2.0, 4.0, 0.04);
    let n_psi = (90.0 / PSI_STEP) as usize;
    let n_r = ((r_hi - r_lo) / r_step).round() as usize;
    let mut cells = Cells::default();
    let mut seen: Vec<Regime> = Vec::new();
    for j in 0..n_r {
        let r0 = r_lo + r_step * j as f64;
        let r_mid = r0 + 0.5 * r_step;
        // Run-length merge along psi: one rectangle per stretch of one regime.
        let mut run: Option<(usize, Regime)> = None;
        for i in 0..=n_psi {
            let reg = (i < n_psi).then(|| {
                let psi = (PSI_STEP * (i as f64 + 0.5)).to_radians();
                regime::select_regime(
                    &Shot {
                        psi,
                        spin: r_mid,
                        ..*template
                    },
                    c,
                )
            });
            match (run, reg) {
                (Some((start, cur)), Some(r)) if r == cur => {
                    let _ = start;
                }
                (prev, next) => {
                    if let Some((start, cur)) = prev {
                        cells.rects.push((
                            (PSI_STEP * start as f64, r0),
                            (PSI_STEP * i as f64, r0 + r_step),
                            regime_fill(cur),
                        ));
                        if !seen.contains(&cur) {
                            seen.push(cur);
                        }
                    }
                    run = next.map(|r| (i, r));
                }
            }
        }
    }
    let absent: Vec<&str> = Regime::ALL
        .iter()
        .filter(|r| !seen.contains(r))
        .map(|r| theory::pretty_regime(*r))
        .collect();
    for r in Regime::ALL {
        if seen.contains(&r) {
            cells
                .legend
                .push((theory::pretty_regime(r).to_string(), regime_fill(r)));
        }
    }
    let mut p = Panel::new(title, "impact angle ψ (deg)", "spin r = Rω₀/v₀")
        .ranges((0.0, 90.0), (r_lo, r_hi));
    p.cells = cells;
    p.legend = LegendAt::UpperRight;
    p.lines.push(Line::guide(
        vec![(0.0, 1.0), (90.0, 1.0)],
        GREY,
        Dash::Dashed,
    ));
    p.notes.push(Note {
        x: 1.5,
        y: 1.0 + 0.06 * (r_hi - r_lo),
        text: "rolling (r = 1)".into(),
        color: GREY,
    });
    if !measured.is_empty() {
        p.points.push(Points {
            label: Some(format!("measured shots ({})", measured.len())),
            points: measured
                .iter()
                .map(|&(x, y)| DataPoint {
                    x,
                    y,
                    x_err: None,
                    y_err: None,
                })
                .collect(),
            color: BLACK,
            marker: Marker::Cross,
        });
    }
    let absent = if absent.is_empty() {
        String::new()
    } else {
        format!(" Absent for these coefficients: {}.", absent.join(", "))
    };
    Figure::new(
        name,
        format!(
            "Fig. 5 style: impact regime selected by the derived stick/slip criteria \
             (physics::regime) over (ψ, r) for e = {}, μ = {}, μ0 = {}, μ' = {}, s = {}, M = {}.{absent} \
             The derivation's table criterion may differ from the paper's printed Fig. 5 \
             (see docs/physics notes).",
            c.e,
            c.mu,
            c.mu_static,
            c.mu_table,
            fmt_num(template.english),
            fmt_num(template.mass_ratio)
        ),
        vec![p],
    )
    .with_size(900, 680)
}

/// Spins of the path fan (Figs. 14, 15): draw, stun, follow.
pub const PATH_SPINS: [f64; 6] = [-1.0, -0.5, 0.0, 0.5, 1.0, 2.0];

/// Predicted paths at `psi = 45°` for a fan of spins (Figs. 14, 15).
#[allow(clippy::too_many_arguments)]
pub fn paths(
    name: &str,
    title: &str,
    c: &Coefficients,
    choice: RegimeChoice,
    radius_m: f64,
    speed_mps: f64,
    cloth: &Cloth,
    psi_deg: f64,
) -> Figure {
    let psi = psi_deg.to_radians();
    // Impact frame -> display: rotate by -psi (cue ball arrives along +X).
    let rot = |v: Vector2<f64>| {
        let (s, co) = (-psi).sin_cos();
        Vector2::new(co * v.x - s * v.y, s * v.x + co * v.y)
    };
    let half = 0.45;
    let mut p = Panel::new(title, "X (m), cue ball arrives along +X", "Y (m)")
        .ranges((-0.5 * half, 1.5 * half), (-half, half));
    p.legend = LegendAt::Auto;
    // Incoming line and the two balls at the moment of impact.
    p.lines.push({
        let mut l = Line::new("cue ball, incoming", BLACK, Dash::Solid);
        l.segments.push(vec![(-0.5 * half, 0.0), (0.0, 0.0)]);
        l
    });
    let x_hat = rot(Vector2::new(1.0, 0.0));
    let obj = x_hat * (2.0 * radius_m);
    for (centre, label) in [(Vector2::zeros(), "balls at impact"), (obj, "")] {
        let circle: Vec<(f64, f64)> = (0..=48)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 48.0;
                (centre.x + radius_m * a.cos(), centre.y + radius_m * a.sin())
            })
            .collect();
        let mut l = Line::guide(circle, GREY, Dash::Solid);
        if !label.is_empty() {
            l.label = Some(label.to_string());
        }
        p.lines.push(l);
    }
    let n = PATH_SPINS.len();
    let mut regimes_text = Vec::new();
    for (k, &spin) in PATH_SPINS.iter().enumerate() {
        let shot = Shot {
            psi,
            mass_ratio: 1.0,
            spin,
            english: 0.0,
        };
        let st = impulse::solve(&shot, c, choice);
        // Dimensionless (v_o = 1, R = 1) to SI, then rotate into the display frame.
        let w_scale = speed_mps / radius_m;
        let rot3 = |v: Vector3<f64>, s: f64| {
            let h = rot(Vector2::new(v.x, v.y)) * s;
            let vz = v.z * s;
            Vector3::new(h.x, h.y, vz)
        };
        let color = spin_color(k, n);
        let cue = BallPath::new(
            Vector2::zeros(),
            rot3(st.v1, speed_mps),
            rot3(st.w1, w_scale),
            radius_m,
            cloth,
        );
        let mut l = Line::new(
            format!(
                "cue ball r = {} ({})",
                fmt_num(spin),
                theory::pretty_regime(st.regime)
            ),
            color,
            Dash::Solid,
        );
        l.segments.push(sample_path(&cue));
        p.lines.push(l);
        regimes_text.push(format!(
            "r = {}: {}",
            fmt_num(spin),
            theory::pretty_regime(st.regime)
        ));
        if (spin - 1.0).abs() < 1e-12 || k == 0 {
            let ob = BallPath::new(
                obj,
                rot3(st.v2, speed_mps),
                rot3(st.w2, w_scale),
                radius_m,
                cloth,
            );
            let mut l2 = Line::new(
                format!("object ball (r = {})", fmt_num(spin)),
                color,
                Dash::Dashed,
            );
            l2.segments.push(sample_path(&ob));
            p.lines.push(l2);
        }
    }
    Figure::new(
        name,
        format!(
            "Figs. 14/15 style: predicted paths (sliding parabola, then rolling line, until rest) \
             at ψ = {psi_deg}°, M = 1, s = 0, for spins r = Rω₀/v₀ in {{{}}}; e = {}, μ = {}, μ0 = {}, μ' = {}; \
             ball radius {:.1} mm, cue speed {speed_mps} m/s, cloth sliding friction {}, rolling \
             resistance {}. Regimes: {}.",
            PATH_SPINS.map(fmt_num).join(", "),
            c.e,
            c.mu,
            c.mu_static,
            c.mu_table,
            radius_m * 1e3,
            cloth.mu_slide,
            cloth.mu_roll,
            regimes_text.join(", ")
        ),
        vec![p],
    )
    .with_size(820, 800)
}

/// The sliding parabola densely, then the rolling line by its two ends (a straight line drawn
/// from many short pieces looks ragged in a bitmap).
fn sample_path(b: &BallPath) -> Vec<(f64, f64)> {
    let t_end = b.t_stop.min(20.0);
    let t_slide = b.t_slide.min(t_end);
    let mut out: Vec<(f64, f64)> = (0..=80)
        .map(|i| b.position(t_slide * i as f64 / 80.0))
        .map(|q| (q.x, q.y))
        .collect();
    let q = b.position(t_end);
    out.push((q.x, q.y));
    out
}

/// Colours from draw (purple) to follow (orange).
fn spin_color(k: usize, n: usize) -> RGBColor {
    const STOPS: [(u8, u8, u8); 6] = [
        (90, 30, 150),
        (40, 80, 200),
        (20, 150, 160),
        (60, 160, 60),
        (220, 130, 0),
        (200, 40, 40),
    ];
    let i = if n <= 1 {
        0
    } else {
        k * (STOPS.len() - 1) / (n - 1)
    };
    let (r, g, b) = STOPS[i.min(STOPS.len() - 1)];
    RGBColor(r, g, b)
}

/// Clamps a panel's y range to `[lo, hi]` (theory curves can run off to infinity).
fn clamp_y(mut p: Panel, lo: f64, hi: f64) -> Panel {
    p.y_range = (p.y_range.0.max(lo), p.y_range.1.min(hi));
    p
}

/// All per-material figures, in report order.
pub fn material_figures(m: &MaterialFigures) -> Vec<Figure> {
    let mut out = vec![fig09(m), fig10(m), fig11(m), fig12(m)];
    if let Some(r) = residuals(m) {
        out.push(r);
    }
    if let Some(r) = spin_estimates(m) {
        out.push(r);
    }
    let model = m.fitted.as_ref().or(m.paper.as_ref());
    if let Some(model) = model {
        let measured: Vec<(f64, f64)> = m
            .measured()
            .filter_map(|r| Some((r.psi_deg?, r.spin.unwrap_or(m.template.spin))))
            .collect();
        out.push(regime_map(
            &format!("{}_regime_map", m.name),
            &format!("{}: regimes over (ψ, r), {}", m.label, model.label),
            &model.coeffs,
            &m.template,
            &measured,
        ));
        out.push(paths(
            &format!("{}_paths_psi45", m.name),
            &format!("{}: paths at ψ = 45°, {}", m.label, model.label),
            &model.coeffs,
            model.choice,
            m.radius_m,
            m.speed_mps,
            &m.cloth,
            45.0,
        ));
    }
    out
}

/// Fig. 5: the paper's regime map for `e = 0.50, mu = 0.30, mu' = 0.50` (rolling axis `r`).
pub fn fig05() -> Figure {
    let c = Coefficients::new(0.5, 0.3, 0.5);
    regime_map(
        "fig05_regime_map",
        "Fig. 5: regimes for e = 0.50, μ = μ0 = 0.30, μ' = 0.50",
        &c,
        &Shot::rolling(0.0),
        &[],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legend_marks_the_coefficients_the_fit_did_not_determine() {
        let m = Model {
            label: "fit".into(),
            coeffs: Coefficients::new(0.88, 0.6, 0.55).with_static(0.7),
            choice: RegimeChoice::Auto,
            assumed: [false, false, true, false],
        };
        assert_eq!(
            m.legend(),
            "fit (e=0.88, μ=0.60, μ'=0.55 (not fitted), μ0=0.70)"
        );
        let all = Model {
            assumed: [false; 4],
            ..m
        };
        assert_eq!(all.legend(), "fit (e=0.88, μ=0.60, μ'=0.55, μ0=0.70)");
    }

    #[test]
    fn wrap_keeps_differences_in_half_open_interval() {
        assert!((wrap_deg(350.0) + 10.0).abs() < 1e-12);
        assert!((wrap_deg(-190.0) - 170.0).abs() < 1e-12);
        assert!((wrap_deg(180.0) - 180.0).abs() < 1e-12);
        assert!((wrap_deg(3.5) - 3.5).abs() < 1e-12);
    }

    #[test]
    fn tan_error_is_the_image_of_the_angle_interval() {
        let (t, e) = tan_err(45.0, Some(1.0));
        assert!((t - 1.0).abs() < 1e-12);
        let (lo, hi) = e.unwrap();
        assert!((lo - (1.0 - 44f64.to_radians().tan())).abs() < 1e-12);
        assert!((hi - (46f64.to_radians().tan() - 1.0)).abs() < 1e-12);
        // Close to the asymptote the interval is strongly asymmetric and stays finite.
        let (_, e) = tan_err(89.5, Some(2.0));
        let (lo, hi) = e.unwrap();
        assert!(hi.is_finite() && hi > 4.0 * lo, "{lo} {hi}");
    }

    #[test]
    fn fig05_map_shows_no_slip_slip_region() {
        // The paper: for e 0.5, mu 0.3, mu' 0.5 the s–s regime is entirely absent.
        let f = fig05();
        let p = &f.panels[0];
        let names: Vec<&str> = p.cells.legend.iter().map(|(n, _)| n.as_str()).collect();
        assert!(!names.contains(&"s–s"), "{names:?}");
        assert!(
            names.contains(&"μ–μ") && names.contains(&"s–μ"),
            "{names:?}"
        );
        // Every rectangle lies inside the plotted window.
        for ((x0, y0), (x1, y1), _) in &p.cells.rects {
            assert!(*x0 >= 0.0 && *x1 <= 90.0 + 1e-9 && x0 < x1);
            assert!(*y0 >= -2.0 - 1e-9 && *y1 <= 4.0 + 1e-9 && y0 < y1);
        }
    }
}

#[cfg(test)]
mod render_tests {
    use super::*;
    use crate::report::plot;
    use crate::synth::materials::Materials;

    /// Renders the theory figures for every preset into `$STREAKFIT_FIG_DIR` (or a temp dir) and
    /// checks each PNG decodes at the requested size with more than one colour.
    #[test]
    fn theory_figures_render_to_png_and_svg() {
        let dir = std::env::var("STREAKFIT_FIG_DIR")
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|_| std::env::temp_dir().join("streakfit-fig-test"));
        let mats = Materials::load(&Materials::default_path()).unwrap();
        let mut figs = vec![fig05()];
        for (name, mat) in &mats.0 {
            let m = MaterialFigures {
                name: name.clone(),
                label: mat.label.clone(),
                rows: Vec::new(),
                fit_residuals: Vec::new(),
                fitted: None,
                paper: Some(Model {
                    label: "paper".into(),
                    coeffs: mat.coefficients(),
                    choice: RegimeChoice::Auto,
                    assumed: [false; 4],
                }),
                template: Shot::rolling(0.0),
                radius_m: mat.radius_m(),
                speed_mps: 0.75,
                cloth: mat.cloth(),
            };
            figs.extend(material_figures(&m));
        }
        for f in &figs {
            let saved = plot::save(f, &dir).unwrap();
            let img = image::open(&saved.png).unwrap().to_rgb8();
            assert_eq!((img.width(), img.height()), f.size);
            let first = *img.get_pixel(0, 0);
            assert!(img.pixels().any(|p| *p != first), "{} is blank", f.name);
            let svg = std::fs::read_to_string(&saved.svg).unwrap();
            assert!(svg.starts_with("<svg") && svg.contains("</svg>"));
        }
    }
}
