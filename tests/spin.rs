//! Issue 8 end to end: a clean folder of 36 billiard shots with mixed follow, stun, draw and
//! English (`synth --spin-modes mixed`, background plate, 2400×1600) → `extract` →
//! `fit --spin estimate`. Target: `e` and `mu` within 0.01 of the generating values and each
//! shot's spin `r` within its stated 2 sigma in at least 90 % of the shots that report one.
//!
//! Two tests share the folder recipe:
//! - `fit_recovers_spin_from_true_angles_with_extractor_errors`: the fit alone on this folder's
//!   shots: true angles with Gaussian noise of the extractor's stated errors, its nulls and its
//!   stated errors (what the fit would see from an extractor whose errors are as stated).
//! - `synth_extract_fit_recovers_spin_and_coefficients`: the full chain, all three targets
//!   checked. Measured 2026-11-24 (seed 8): e 0.9742 ± 0.0019, mu 0.0718 ± 0.0060, r within
//!   2 sigma for 29 of 29 shots; the same recipe on seeds 9, 10, 11 (CLI, not in the test): e
//!   0.973, 0.970, 0.968, mu 0.071 each, r within 2 sigma for 30/31, 28/28, 28/33.
//!
//! With unknown spin `e` rests on `delta1` alone (without it `e` is not identified), so the
//! chain's `e` follows the arc fit's remaining bias, which scales about as 1/R. Until session 6
//! the test ran at 1200×800 (R ≈ 52 px) and could not check `e`: session 2 (centre-line
//! `delta1`) e 0.940, session 3 (pixel arc fit) 0.991, session 5 (rolling-line ramp) 0.9845,
//! session 6 (colour projection) 0.9807 ± 0.0020 against 0.97. At full size (R ≈ 104 px, the
//! size of every accuracy table in the README) it is within the target.
//!
//! Run with `cargo test --release --test spin`.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use streakfit::extract::ExtractArgs;
use streakfit::fit::{FitOptions, FitOutput, SpinMode, fit_materials};
use streakfit::synth::{SpinModes, SynthArgs, Tier, truth};
use streakfit::table::{ShotRow, Status, read_angle_table};

type Truth = BTreeMap<String, BTreeMap<String, String>>;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("streakfit_spin_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn num(row: &BTreeMap<String, String>, k: &str) -> Option<f64> {
    let v = &row[k];
    (!v.is_empty()).then(|| v.parse().unwrap_or_else(|_| panic!("{k} = '{v}'")))
}

/// Synth (clean tier, billiard, mixed spin, plate) and extract: the angle rows and the truth.
fn synth_and_extract(dir: &Path) -> (Vec<ShotRow>, Truth) {
    let shots_dir = dir.join("shots");
    let mut a = SynthArgs::new(&shots_dir, Tier::Clean, 36, 8);
    a.material = Some("billiard".into());
    a.size = "2400x1600".into();
    a.background = true;
    a.spin_modes = Some(SpinModes::Mixed);
    a.psi = Some("15:65".into());
    streakfit::synth::run(&a).expect("synth");
    let table = dir.join("angles.csv");
    // Exit code 1 only flags `error` rows; the rows are checked by the callers.
    let _ = streakfit::extract::run(&ExtractArgs {
        dirs: vec![shots_dir.clone()],
        out: table.clone(),
        overlays: None,
        jobs: None,
        shard: None,
        no_texture: false,
    });
    let rows = read_angle_table(&table).expect("angle table");
    let truth_rows =
        truth::read_csv(&std::fs::read_to_string(shots_dir.join("truth.csv")).unwrap()).unwrap();
    assert_eq!(rows.len(), 36);
    assert_eq!(truth_rows.len(), 36);
    // The folder really mixes the spin modes.
    let spins: Vec<f64> = truth_rows.iter().map(|t| num(t, "spin").unwrap()).collect();
    assert!(spins.iter().any(|r| *r < -0.3), "no draw shot: {spins:?}");
    assert!(
        spins.iter().any(|r| r.abs() < 0.1),
        "no stun shot: {spins:?}"
    );
    assert!(spins.iter().any(|r| *r > 1.0), "no follow shot: {spins:?}");
    assert!(
        spins.iter().any(|r| (r - 1.0).abs() < 1e-12),
        "no rolling shot: {spins:?}"
    );
    let truth = truth_rows
        .into_iter()
        .map(|t| (t["file"].clone(), t))
        .collect();
    (rows, truth)
}

fn fit(rows: &[ShotRow]) -> FitOutput {
    let opts = FitOptions {
        spin: SpinMode::Estimate,
        bootstrap: 0,
        ..FitOptions::default()
    };
    fit_materials(rows, &opts).expect("fit")
}

/// Prints and checks the targets: e (when `check_e`), mu within 0.01; r within 2 sigma
/// in ≥ 90 %.
fn check(out: &FitOutput, truth: &Truth, label: &str, check_e: bool) {
    let f = &out.fits[0];
    assert_eq!(f.material, "billiard");
    let (mut inside, mut n) = (0, 0);
    for r in out.residuals.iter().filter(|r| r.used) {
        let t = &truth[&r.file];
        let r_true = num(t, "spin").unwrap();
        if let (Some(est), Some(err)) = (r.spin_est, r.spin_err) {
            n += 1;
            if (est - r_true).abs() <= 2.0 * err {
                inside += 1;
            } else {
                eprintln!(
                    "  {label} {}: r true {r_true:+.3} est {est:+.3} ± {err:.3} ({})",
                    r.file,
                    r.regime_est.clone().unwrap_or_default()
                );
            }
        }
    }
    eprintln!(
        "{label}: model {}; e {:.4} ± {:.4}; mu {:.4} ± {:.4}; used {} rejected {}; spin \
         estimated {} undetermined {}; r within 2 sigma {inside} of {n}",
        f.model,
        f.e.unwrap_or(f64::NAN),
        f.e_se.unwrap_or(f64::NAN),
        f.mu.unwrap_or(f64::NAN),
        f.mu_se.unwrap_or(f64::NAN),
        f.n_used,
        f.n_rejected,
        f.spin_estimated,
        f.spin_undetermined
    );
    if check_e {
        assert!((f.e.unwrap() - 0.97).abs() < 0.01, "{label}: e {:?}", f.e);
    }
    assert!(
        (f.mu.unwrap() - 0.07).abs() < 0.01,
        "{label}: mu {:?}",
        f.mu
    );
    assert!(n >= 20, "{label}: only {n} shots report a spin estimate");
    assert!(
        inside as f64 >= 0.9 * n as f64,
        "{label}: {inside} of {n} within 2 sigma"
    );
}

#[test]
fn fit_recovers_spin_from_true_angles_with_extractor_errors() {
    let dir = scratch("control");
    let (rows, truth) = synth_and_extract(&dir);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    let mut control = Vec::new();
    for r in rows.iter().filter(|r| r.status == Status::Ok) {
        let t = &truth[&r.file];
        let mut c = r.clone();
        let mut noisy = |meas: Option<f64>, err: Option<f64>, key: &str| match (meas, err) {
            (Some(_), Some(e)) => {
                num(t, key).map(|x| x + Normal::new(0.0, e).unwrap().sample(&mut rng))
            }
            _ => None,
        };
        c.psi_deg = noisy(r.psi_deg, r.psi_err_deg, "psi_deg");
        c.delta1_deg = noisy(r.delta1_deg, r.delta1_err_deg, "delta1_deg");
        c.delta2_deg = noisy(r.delta2_deg, r.delta2_err_deg, "delta2_deg");
        c.theta1_deg = noisy(r.theta1_deg, r.theta1_err_deg, "theta1_deg");
        c.theta2_deg = noisy(r.theta2_deg, r.theta2_err_deg, "theta2_deg");
        control.push(c);
    }
    assert!(control.len() >= 25, "only {} ok rows", control.len());
    check(&fit(&control), &truth, "true angles + stated errors", true);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn synth_extract_fit_recovers_spin_and_coefficients() {
    let dir = scratch("chain");
    let (rows, truth) = synth_and_extract(&dir);
    // Extraction accuracy per shot, for the record.
    for r in rows.iter().filter(|r| r.status == Status::Ok) {
        let t = &truth[&r.file];
        let d = |m: Option<f64>, e: Option<f64>, k: &str| match (m, num(t, k)) {
            (Some(m), Some(x)) => format!("{:+.2}/{:.2}", m - x, e.unwrap_or(f64::NAN)),
            (None, Some(_)) => "null".into(),
            (_, None) => "-".into(),
        };
        eprintln!(
            "{} r {:+.2} s {:+.2} {}: error/stated psi {} delta1 {} delta2 {} theta1 {} theta2 {}",
            r.file,
            num(t, "spin").unwrap(),
            num(t, "english").unwrap(),
            t["regime"],
            d(r.psi_deg, r.psi_err_deg, "psi_deg"),
            d(r.delta1_deg, r.delta1_err_deg, "delta1_deg"),
            d(r.delta2_deg, r.delta2_err_deg, "delta2_deg"),
            d(r.theta1_deg, r.theta1_err_deg, "theta1_deg"),
            d(r.theta2_deg, r.theta2_err_deg, "theta2_deg"),
        );
    }
    // With free spin e rests on delta1 alone, whose remaining bias (the arc turns a few tenths
    // of a degree too far, about 1/R) moved it by 0.011 at 1200×800; at full size it is within
    // the target (module doc).
    check(&fit(&rows), &truth, "extracted angles", true);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--spin-modes rolling` turns a realistic folder's mixed spins into rolling ones (the rest of
/// each shot drawn as before); an unknown mode is a usage error naming the flag.
#[test]
fn spin_modes_option_sets_the_folders_spin() {
    let dir = scratch("modes");
    let mut a = SynthArgs::new(dir.join("rolling"), Tier::Realistic, 6, 3);
    a.size = "600x400".into();
    a.spin_modes = Some(SpinModes::Rolling);
    streakfit::synth::run(&a).expect("synth");
    let mut b = a.clone();
    b.out = dir.join("mixed");
    b.spin_modes = None;
    streakfit::synth::run(&b).expect("synth");
    let read = |d: &str| {
        truth::read_csv(&std::fs::read_to_string(dir.join(d).join("truth.csv")).unwrap()).unwrap()
    };
    let (rolling, mixed) = (read("rolling"), read("mixed"));
    for (r, m) in rolling.iter().zip(&mixed) {
        assert_eq!(num(r, "spin"), Some(1.0));
        assert_eq!(num(r, "english"), Some(0.0));
        // Same shot geometry: only the spin differs.
        assert_eq!(r["psi_deg"], m["psi_deg"]);
        assert_eq!(r["material"], m["material"]);
    }
    assert!(mixed.iter().any(|m| num(m, "spin") != Some(1.0)));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_streakfit"))
        .args(["synth", "--out"])
        .arg(dir.join("bad"))
        .args(["--spin-modes", "wobble"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--spin-modes"));
    std::fs::remove_dir_all(&dir).unwrap();
}
