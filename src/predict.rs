//! `streakfit predict`: the theory's angles for given coefficients and shot parameters.

use crate::cli::{CliError, CliResult, Outcome};
use crate::physics::{Coefficients, RegimeChoice, Shot, impulse};
use clap::Args;

#[derive(Debug, Args, Clone)]
pub struct PredictArgs {
    /// Impact angle psi in degrees, or a range START:STOP:STEP (inclusive), e.g. 0:85:5.
    #[arg(long, allow_hyphen_values = true)]
    pub psi: String,
    /// Mass ratio M = m1/m2.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub mass_ratio: f64,
    /// Coefficient of restitution e (ball–ball), in [0, 1].
    #[arg(long, allow_hyphen_values = true)]
    pub e: f64,
    /// Dynamic ball–ball friction mu.
    #[arg(long, allow_hyphen_values = true)]
    pub mu: f64,
    /// Ball–table friction mu' during the impact.
    #[arg(long, allow_hyphen_values = true)]
    pub mu_table: f64,
    /// Static ball–ball friction mu0 (default: mu).
    #[arg(long, allow_hyphen_values = true)]
    pub mu_static: Option<f64>,
    /// Horizontal spin ratio r = R omega / v (rolling 1, stun 0, draw < 0).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub spin: f64,
    /// Sidespin ratio s = R omega_z / v.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub english: f64,
    /// auto, mu-mu, s-mu, mu-s or s-s.
    #[arg(long, default_value = "auto")]
    pub regime: String,
    /// Print JSON (one object, or an array for a range).
    #[arg(long)]
    pub json: bool,
}

/// Parses `A` or `A:B:STEP` (degrees) into a list of angles.
pub fn parse_psi_range(s: &str) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = s.split(':').collect();
    let num = |p: &str| -> Result<f64, String> {
        p.trim()
            .parse::<f64>()
            .map_err(|_| format!("--psi: '{p}' is not a number"))
    };
    match parts.as_slice() {
        [a] => Ok(vec![num(a)?]),
        [a, b, step] => {
            let (a, b, step) = (num(a)?, num(b)?, num(step)?);
            if !(step.is_finite() && step > 0.0) {
                return Err(format!("--psi: step {step} must be positive"));
            }
            if !(a.is_finite() && b.is_finite()) || b < a {
                return Err(format!("--psi: range {a}:{b} must have start ≤ stop"));
            }
            let n = ((b - a) / step + 1e-9).floor() as usize;
            Ok((0..=n).map(|i| a + step * i as f64).collect())
        }
        _ => Err(format!(
            "--psi: '{s}' is neither an angle nor START:STOP:STEP"
        )),
    }
}

/// One row of `predict` output.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PredictRow {
    pub psi_deg: f64,
    pub regime: String,
    pub delta1_deg: Option<f64>,
    pub delta2_deg: Option<f64>,
    pub theta1_deg: Option<f64>,
    pub theta2_deg: Option<f64>,
}

pub fn predict_rows(args: &PredictArgs) -> Result<Vec<PredictRow>, CliError> {
    let psis = parse_psi_range(&args.psi).map_err(CliError::usage)?;
    let coeffs = Coefficients::new(args.e, args.mu, args.mu_table)
        .with_static(args.mu_static.unwrap_or(args.mu));
    coeffs.validate().map_err(CliError::usage)?;
    let choice: RegimeChoice = args.regime.parse().map_err(CliError::usage)?;
    let mut rows = Vec::with_capacity(psis.len());
    for psi_deg in psis {
        let shot = Shot {
            psi: psi_deg.to_radians(),
            mass_ratio: args.mass_ratio,
            spin: args.spin,
            english: args.english,
        };
        shot.validate().map_err(CliError::usage)?;
        let state = impulse::solve(&shot, &coeffs, choice);
        // `+ 0.0` turns -0.0 into 0.0 so a head-on shot prints 0, not -0.
        let [d1, d2, t1, t2] = state.angles().to_degrees().map(|a| a.map(|v| v + 0.0));
        rows.push(PredictRow {
            psi_deg,
            regime: state.regime.to_string(),
            delta1_deg: d1,
            delta2_deg: d2,
            theta1_deg: t1,
            theta2_deg: t2,
        });
    }
    Ok(rows)
}

pub fn run(args: &PredictArgs) -> CliResult {
    let rows = predict_rows(args)?;
    if args.json {
        // One angle: exactly the four angles and the regime (the contract); a range: an
        // array whose objects also carry psi_deg.
        let json = if rows.len() == 1 {
            let mut v = serde_json::to_value(&rows[0]).map_err(anyhow::Error::from)?;
            if let Some(o) = v.as_object_mut() {
                o.remove("psi_deg");
            }
            serde_json::to_string_pretty(&v)
        } else {
            serde_json::to_string_pretty(&rows)
        };
        println!("{}", json.map_err(anyhow::Error::from)?);
    } else {
        let fmt = |a: Option<f64>| a.map_or("undefined".to_string(), |v| format!("{v:.4}"));
        println!(
            "{:>8} {:>7} {:>11} {:>11} {:>11} {:>11}",
            "psi_deg", "regime", "delta1_deg", "delta2_deg", "theta1_deg", "theta2_deg"
        );
        for r in &rows {
            println!(
                "{:>8.3} {:>7} {:>11} {:>11} {:>11} {:>11}",
                r.psi_deg,
                r.regime,
                fmt(r.delta1_deg),
                fmt(r.delta2_deg),
                fmt(r.theta1_deg),
                fmt(r.theta2_deg)
            );
        }
    }
    Ok(Outcome::Ok)
}
