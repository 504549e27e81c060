//! `streakfit fit` on synthetic tables made from the theory (paper's Table 1 values).

use streakfit::fit::synthetic::{SyntheticSpec, SyntheticSpin, paper_materials, synthetic_table};
use streakfit::fit::{FitArgs, FitOptions, MaterialFit, SpinMode, fit_materials};
use streakfit::physics::Coefficients;
use streakfit::table::{ShotRow, write_angle_table};

fn spec(material: &str, c: Coefficients, n: usize, seed: u64) -> SyntheticSpec {
    SyntheticSpec {
        material: material.into(),
        coefficients: c,
        n,
        psi_lo_deg: 10.0,
        psi_hi_deg: 70.0,
        noise_deg: 0.3,
        spin: SyntheticSpin::Rolling,
        seed,
    }
}

fn fit_one(rows: &[ShotRow], opts: &FitOptions) -> MaterialFit {
    let out = fit_materials(rows, opts).unwrap();
    assert_eq!(out.fits.len(), 1);
    out.fits.into_iter().next().unwrap()
}

#[test]
fn reproduces_the_papers_regime_findings() {
    let [(_, billiard), (_, steel), (_, rubber)] = paper_materials();
    // Billiard balls: gross slip only; mu' not identified (cancels from theta2).
    let (rows, _) = synthetic_table(&spec("billiard", billiard, 30, 11));
    let f = fit_one(&rows, &FitOptions::default());
    assert_eq!(f.model, "mu-mu", "{:?}", f.scores);
    assert!((f.e.unwrap() - 0.97).abs() < 0.02, "e {:?}", f.e);
    assert!((f.mu.unwrap() - 0.07).abs() < 0.01, "mu {:?}", f.mu);
    assert_eq!(f.mu_table, None);
    assert_eq!(f.mu_table_se, None);
    assert!(!f.identified.contains(&"mu_table".to_string()));
    assert!(f.unidentified.contains_key("mu_table"));
    assert_eq!(f.scores.len(), 5);
    assert!(f.mu_static.is_none() && f.psi_l_deg.is_none());

    // Steel: the jump of Fig. 12 near 34° (Eq. 50 with mu0 = 0.18, e = 0.92).
    let (rows, _) = synthetic_table(&spec("steel", steel, 30, 12));
    let f = fit_one(&rows, &FitOptions::default());
    assert_eq!(f.model, "two-regime", "{:?}", f.scores);
    let mu0 = f.mu_static.unwrap();
    assert!((mu0 - 0.18).abs() < 0.01, "mu0 {mu0}");
    let psi_l = f.psi_l_deg.unwrap();
    assert!((psi_l - 34.2).abs() < 3.0, "psi_L {psi_l}");
    assert!((f.e.unwrap() - 0.92).abs() < 0.01);
    assert!((f.mu.unwrap() - 0.14).abs() < 0.01);
    let two = f.scores.iter().find(|s| s.model == "two-regime").unwrap();
    let mumu = f.scores.iter().find(|s| s.model == "mu-mu").unwrap();
    assert!(mumu.bic - two.bic > 10.0, "{:?}", f.scores);

    // Rubber: slip–stick over the whole range; mu0 = mu = 0.6 would put psi_L near 75°.
    let (rows, _) = synthetic_table(&spec("rubber", rubber, 30, 13));
    let f = fit_one(&rows, &FitOptions::default());
    assert_eq!(f.model, "s-mu", "{:?}", f.scores);
    let max_psi = rows.iter().filter_map(|r| r.psi_deg).fold(0.0, f64::max);
    assert!(
        (f.psi_l_min_deg.unwrap() - max_psi).abs() < 1.0,
        "{:?}",
        f.psi_l_min_deg
    );
    let note = f.notes.iter().find(|n| n.contains("Eq. (50)")).unwrap();
    let psi_l_eq50: f64 = note
        .rsplit("at ")
        .next()
        .unwrap()
        .trim_end_matches('°')
        .parse()
        .unwrap();
    assert!((psi_l_eq50 - 75.0).abs() < 3.0, "{note}");
    assert!((f.e.unwrap() - 0.88).abs() < 0.01);
    assert!((f.mu.unwrap() - 0.60).abs() < 0.1);
    // mu' shows in delta2 of s–mu shots; with 30 shots it is only just identified (≈ 25%).
    if let (Some(mt), Some(se)) = (f.mu_table, f.mu_table_se) {
        assert!((mt - 0.55).abs() < 3.0 * se, "mu' {mt} ± {se}");
    }
    assert!(
        f.notes.iter().any(|n| n.contains("Eq. (50)")),
        "{:?}",
        f.notes
    );
}

/// Coverage over 50 seeds for each of the paper's materials: every identified parameter lies
/// within its stated 2 sigma of the truth in at least 90% of seeds.
#[test]
fn two_sigma_coverage_over_fifty_seeds() {
    let opts = FitOptions {
        bootstrap: 0,
        ..FitOptions::default()
    };
    for (name, c) in paper_materials() {
        let truth = [c.e, c.mu, c.mu_table, c.mu_static];
        let (mut inside, mut total) = ([0usize; 4], [0usize; 4]);
        let mut worst_e: f64 = 0.0;
        for seed in 0..50 {
            let (rows, _) = synthetic_table(&spec(name, c, 30, 1000 + seed));
            let f = fit_one(&rows, &opts);
            let est = [
                (f.e, f.e_se),
                (f.mu, f.mu_se),
                (f.mu_table, f.mu_table_se),
                (f.mu_static, f.mu_static_se),
            ];
            for k in 0..4 {
                if let (Some(v), Some(se)) = est[k] {
                    total[k] += 1;
                    if (v - truth[k]).abs() <= 2.0 * se {
                        inside[k] += 1;
                    }
                }
            }
            worst_e = worst_e.max((f.e.unwrap() - c.e).abs());
        }
        eprintln!("{name}: inside {inside:?} of {total:?}, worst |e error| {worst_e:.4}");
        assert!(
            total[0] == 50 && total[1] == 50,
            "{name}: e, mu identified every time"
        );
        for k in 0..4 {
            if total[k] >= 10 {
                assert!(
                    inside[k] as f64 >= 0.9 * total[k] as f64,
                    "{name}: parameter {k} covered {} of {}",
                    inside[k],
                    total[k]
                );
            }
        }
        assert!(worst_e < 0.02, "{name}: e error {worst_e}");
    }
}

#[test]
fn bootstrap_agrees_with_jacobian_errors() {
    let [(_, _), (_, _), (_, rubber)] = paper_materials();
    let (rows, _) = synthetic_table(&spec("rubber", rubber, 40, 21));
    let f = fit_one(&rows, &FitOptions::default());
    let b = f.bootstrap.as_ref().unwrap();
    assert_eq!(b.resamples, 100);
    for (j, bs) in [(f.e_se, b.e_se), (f.mu_se, b.mu_se)] {
        let ratio = bs.unwrap() / j.unwrap();
        assert!((0.5..2.0).contains(&ratio), "bootstrap/Jacobian {ratio}");
    }
    assert_eq!(f.correlation.params.len(), f.correlation.matrix.len());
    assert!((f.correlation.matrix[0][0] - 1.0).abs() < 1e-9);
}

#[test]
fn gross_outlier_is_rejected() {
    let [(_, billiard), _, _] = paper_materials();
    let (mut rows, _) = synthetic_table(&spec("billiard", billiard, 30, 5));
    rows[3].theta1_deg = rows[3].theta1_deg.map(|t| t + 15.0);
    let out = fit_materials(&rows, &FitOptions::default()).unwrap();
    let f = &out.fits[0];
    assert_eq!(f.n_rejected, 1);
    assert_eq!(f.n_used, 29);
    assert!((f.e.unwrap() - 0.97).abs() < 0.02);
    let r = out
        .residuals
        .iter()
        .find(|r| r.file == rows[3].file)
        .unwrap();
    assert!(!r.used && r.rejected_reason.as_deref().unwrap().contains("outlier"));
}

#[test]
fn cli_writes_json_csv_and_residuals_from_a_hand_made_table() {
    let dir = std::env::temp_dir().join(format!("streakfit_fit_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let [(_, billiard), _, (_, rubber)] = paper_materials();
    // Hand-made CSV: only the required columns, two materials.
    let mut text = String::from("material,psi_deg,delta1_deg,delta2_deg,theta1_deg,theta2_deg\n");
    for (name, c, seed) in [("billiard", billiard, 1), ("rubber", rubber, 2)] {
        let (rows, _) = synthetic_table(&spec(name, c, 25, seed));
        for r in rows {
            text.push_str(&format!(
                "{name},{},{},{},{},{}\n",
                r.psi_deg.unwrap(),
                r.delta1_deg.unwrap(),
                r.delta2_deg.unwrap(),
                r.theta1_deg.unwrap(),
                r.theta2_deg.unwrap()
            ));
        }
    }
    let table = dir.join("hand.csv");
    std::fs::write(&table, text).unwrap();
    let json = dir.join("fit.json");
    let resid = dir.join("resid.csv");
    let args = FitArgs {
        tables: vec![table.clone()],
        out: json.clone(),
        residuals: Some(resid.clone()),
        material: None,
        regime: "auto".into(),
        criterion: "bic".into(),
        spin: "known".into(),
        sigma_deg: 0.3,
        psi_sigma_deg: 0.3,
        mass_ratio: 1.0,
        huber: None,
        reject_sigma: 5.0,
        bootstrap: 10,
        seed: 1,
    };
    streakfit::fit::run(&args).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let arr = v.as_array().unwrap();
    assert_eq!(arr.len(), 2);
    for key in [
        "material",
        "model",
        "e",
        "e_se",
        "mu",
        "mu_se",
        "mu_table",
        "mu_table_se",
        "mu_static",
        "mu_static_se",
        "psi_l_deg",
        "n_used",
        "n_rejected",
        "identified",
        "scores",
        "rms_deg",
        "correlation",
    ] {
        assert!(arr[0].get(key).is_some(), "missing key {key}");
    }
    assert_eq!(arr[0]["material"], "billiard");
    assert_eq!(arr[0]["model"], "mu-mu");
    assert!(arr[0]["mu_table"].is_null());
    assert_eq!(arr[1]["model"], "s-mu");
    assert_eq!(arr[1]["n_used"], 25);
    let res = std::fs::read_to_string(&resid).unwrap();
    assert_eq!(res.lines().count(), 51);
    assert!(res.lines().next().unwrap().contains("theta1_resid_deg"));
    // CSV output with the same columns.
    let csv = dir.join("fit.csv");
    streakfit::fit::run(&FitArgs {
        out: csv.clone(),
        residuals: None,
        material: Some("rubber".into()),
        ..args.clone()
    })
    .unwrap();
    let c = std::fs::read_to_string(&csv).unwrap();
    let header = c.lines().next().unwrap();
    for key in [
        "material",
        "model",
        "e_se",
        "mu_table_se",
        "psi_l_deg",
        "identified",
        "bic_two-regime",
    ] {
        assert!(
            header.split(',').any(|h| h == key),
            "csv lacks {key}: {header}"
        );
    }
    assert_eq!(c.lines().count(), 2);
    // Bad flag values are usage errors naming the flag.
    let err = streakfit::fit::run(&FitArgs {
        regime: "sticky".into(),
        ..args.clone()
    })
    .unwrap_err();
    assert!(err.to_string().contains("--regime"), "{err}");
    let err = streakfit::fit::run(&FitArgs {
        material: Some("glass".into()),
        ..args.clone()
    })
    .unwrap_err();
    assert!(err.to_string().contains("glass"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn angle_table_round_trip_feeds_the_fit() {
    let dir = std::env::temp_dir().join(format!("streakfit_fit_pq_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let [_, (_, steel), _] = paper_materials();
    let (rows, _) = synthetic_table(&spec("steel", steel, 30, 3));
    let p = dir.join("angles.parquet");
    write_angle_table(&p, &rows).unwrap();
    let back = streakfit::table::read_angle_table(&p).unwrap();
    assert_eq!(back, rows);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// 80 billiard shots at psi 15–65°, mixed follow/stun/draw (r in [-1, 1.5)) with English
/// |s| < 0.3, the spins not written to the table.
fn mixed_spin_billiard(billiard: Coefficients, seed: u64) -> SyntheticSpec {
    let mut s = spec("billiard", billiard, 80, seed);
    s.psi_lo_deg = 15.0;
    s.psi_hi_deg = 65.0;
    s.spin = SyntheticSpin::Mixed {
        r_lo: -1.0,
        r_hi: 1.5,
        s_max: 0.3,
        write: false,
    };
    s
}

/// Issue 8: mixed follow/stun/draw with English, spin unknown to the fit.
#[test]
fn estimates_per_shot_spin_with_the_coefficients() {
    let [(_, billiard), _, _] = paper_materials();
    let s = mixed_spin_billiard(billiard, 8);
    let (rows, truth) = synthetic_table(&s);
    let opts = FitOptions {
        spin: SpinMode::Estimate,
        bootstrap: 0,
        ..FitOptions::default()
    };
    let out = fit_materials(&rows, &opts).unwrap();
    let f = &out.fits[0];
    assert!((f.e.unwrap() - 0.97).abs() < 0.01, "e {:?}", f.e);
    assert!((f.mu.unwrap() - 0.07).abs() < 0.01, "mu {:?}", f.mu);
    assert_eq!(f.spin_estimated + f.spin_undetermined, 80);
    let (mut ok, mut n) = (0, 0);
    for r in out.residuals.iter().filter(|r| r.used) {
        let i: usize = r.file.trim_start_matches("synthetic_").parse().unwrap();
        if let (Some(est), Some(err)) = (r.spin_est, r.spin_err) {
            n += 1;
            if (est - truth[i][1]).abs() <= 2.0 * err {
                ok += 1;
            }
        }
    }
    eprintln!(
        "model {}; spin within 2 sigma: {ok} of {n}; estimated {}; e {:?} mu {:?}",
        f.model, f.spin_estimated, f.e, f.mu
    );
    assert!(n >= 70, "only {n} shots determined their spin");
    // Issue 8: r within its stated 2 sigma in at least 90 % of shots (measured: 76 of 80).
    assert!(ok as f64 >= 0.9 * n as f64, "{ok} of {n}");
    // The ambiguous shots say so.
    assert!(
        out.residuals
            .iter()
            .filter_map(|r| r.spin_reason.as_deref())
            .all(|w| w.contains("ambiguous")
                || w.contains("not determined")
                || w.contains("minima")),
        "unexpected reasons"
    );
}

/// Issue 8: spin coverage over ten seeds (80 billiard shots each, mixed follow/stun/draw with
/// English, spin unknown to the fit): e and mu within 0.01 in every seed, each shot's r within
/// its stated 2 sigma in at least 90 % of all shots (measured: 772 of 800, 96.5 %).
#[test]
fn spin_coverage_over_seeds() {
    let [(_, billiard), _, _] = paper_materials();
    let opts = FitOptions {
        spin: SpinMode::Estimate,
        bootstrap: 0,
        ..FitOptions::default()
    };
    let (mut ok, mut n, mut worst_e, mut worst_mu) = (0, 0, 0.0f64, 0.0f64);
    let mut errs: Vec<f64> = Vec::new();
    for seed in 0..10u64 {
        let s = mixed_spin_billiard(billiard, 100 + seed);
        let (rows, truth) = synthetic_table(&s);
        let out = fit_materials(&rows, &opts).unwrap();
        let f = &out.fits[0];
        worst_e = worst_e.max((f.e.unwrap() - 0.97).abs());
        worst_mu = worst_mu.max((f.mu.unwrap() - 0.07).abs());
        let (mut ok_s, mut n_s) = (0, 0);
        for r in out.residuals.iter().filter(|r| r.used) {
            let i: usize = r.file.trim_start_matches("synthetic_").parse().unwrap();
            if let (Some(est), Some(err)) = (r.spin_est, r.spin_err) {
                n_s += 1;
                errs.push(err);
                let shot = streakfit::physics::Shot {
                    psi: truth[i][0].to_radians(),
                    mass_ratio: 1.0,
                    spin: truth[i][1],
                    english: truth[i][2],
                };
                let reg = streakfit::physics::regime::select_regime(&shot, &billiard);
                if (est - truth[i][1]).abs() <= 2.0 * err {
                    ok_s += 1;
                } else {
                    eprintln!(
                        "  seed {seed} {}: psi {:.1} r {:+.3} s {:+.3} ({}) est r {est:+.3} ± {err:.3} s {:?} ± {:?} ({:?})",
                        r.file,
                        truth[i][0],
                        truth[i][1],
                        truth[i][2],
                        reg.name(),
                        r.english_est,
                        r.english_err,
                        r.regime_est
                    );
                }
            }
        }
        eprintln!(
            "seed {seed}: model {} e {:.4} mu {:.4}; spin within 2 sigma {ok_s} of {n_s}; undetermined {}",
            f.model,
            f.e.unwrap(),
            f.mu.unwrap(),
            f.spin_undetermined
        );
        ok += ok_s;
        n += n_s;
    }
    errs.sort_by(f64::total_cmp);
    eprintln!(
        "all seeds: {ok} of {n} ({:.1} %); worst |e error| {worst_e:.4}, |mu error| {worst_mu:.4}; \
         r error median {:.3}, 90th percentile {:.3}",
        100.0 * ok as f64 / n as f64,
        errs[errs.len() / 2],
        errs[errs.len() * 9 / 10]
    );
    assert!(
        worst_e < 0.01 && worst_mu < 0.01,
        "e {worst_e} mu {worst_mu}"
    );
    assert!(n >= 760, "only {n} of 800 shots determined their spin");
    assert!(ok as f64 >= 0.9 * n as f64, "{ok} of {n}");
}

/// Every angle of a photo is read from its line of centres, so an error in that direction moves
/// all five alike (the extractor states it as `frame_err_deg`). Billiard tables with a shared
/// error of 0.1° per photo and independent errors of 0.01°: treated as independent, each angle
/// weighs 0.1° and `e` comes out loose; with the shared part stated, the fit profiles it out
/// per photo and the deflection (cue ball's rolling line against the incoming line, free of it)
/// carries `e`. Measured 2026-11-25 on these three seeds: e's stated error 5.4–6.5× smaller
/// (±0.00004–0.00005 against ±0.00024–0.00027), every estimate of `e` and `mu` within 1.2
/// stated sigmas of the truth in both fits.
#[test]
fn a_shared_error_of_all_five_angles_is_profiled_out() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let [(_, billiard), _, _] = paper_materials();
    let (shared, own) = (0.1, 0.01);
    for seed in [31u64, 32, 33] {
        let mut sp = spec("billiard", billiard, 40, seed);
        sp.noise_deg = own;
        let (mut rows, _) = synthetic_table(&sp);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let shift = Normal::new(0.0, shared).unwrap();
        let stated = f64::hypot(shared, own);
        for r in rows.iter_mut() {
            let a = shift.sample(&mut rng);
            for (v, e) in [
                (&mut r.psi_deg, &mut r.psi_err_deg),
                (&mut r.delta1_deg, &mut r.delta1_err_deg),
                (&mut r.delta2_deg, &mut r.delta2_err_deg),
                (&mut r.theta1_deg, &mut r.theta1_err_deg),
                (&mut r.theta2_deg, &mut r.theta2_err_deg),
            ] {
                if let Some(x) = v.as_mut() {
                    *x += a;
                    *e = Some(stated);
                }
            }
            r.frame_err_deg = Some(shared);
        }
        let opts = FitOptions {
            bootstrap: 0,
            ..FitOptions::default()
        };
        let with = fit_one(&rows, &opts);
        for r in rows.iter_mut() {
            r.frame_err_deg = None;
        }
        let without = fit_one(&rows, &opts);
        for f in [&with, &without] {
            assert_eq!(f.model, "mu-mu", "seed {seed}: {:?}", f.scores);
            let (e, se) = (f.e.unwrap(), f.e_se.unwrap());
            let (mu, mu_se) = (f.mu.unwrap(), f.mu_se.unwrap());
            eprintln!("seed {seed}: e {e:.5} ± {se:.5}, mu {mu:.5} ± {mu_se:.5}");
            assert!((e - 0.97).abs() < 3.0 * se, "seed {seed}: e {e} ± {se}");
            assert!(
                (mu - 0.07).abs() < 3.0 * mu_se,
                "seed {seed}: mu {mu} ± {mu_se}"
            );
        }
        // The error model used is stated.
        assert!(
            with.notes
                .iter()
                .any(|n| n.starts_with("40 of 40 shots state")),
            "{:?}",
            with.notes
        );
        assert!(!without.notes.iter().any(|n| n.contains("frame_err_deg")));
        // A shared part larger than an angle's whole error is bad input: that row is not used,
        // and the reason names both columns.
        if seed == 31 {
            let mut bad = rows.clone();
            for r in bad.iter_mut() {
                r.frame_err_deg = Some(shared);
            }
            bad[0].frame_err_deg = Some(2.0 * stated);
            let out = fit_materials(&bad, &opts).unwrap();
            assert_eq!(out.fits[0].n_rejected, 1);
            let why = out
                .residuals
                .iter()
                .find_map(|r| r.rejected_reason.clone())
                .unwrap();
            assert!(
                why.contains("frame_err_deg = ") && why.contains("exceeds psi_err_deg"),
                "{why}"
            );
        }
        let ratio = without.e_se.unwrap() / with.e_se.unwrap();
        assert!(
            ratio > 4.0,
            "seed {seed}: e's error only {ratio:.2}× smaller"
        );
    }
}

/// A table without spin is fitted as rolling shots by default (`--spin known`). When its shots
/// were struck with spin the model cannot reproduce them, and the fit says so and what to do
/// (the 36 mixed-spin photos of `docs/accuracy.sh` read this way gave `e` 0.864 for 0.97 at a
/// reduced χ² of 2270); a rolling table of the same size does not raise it.
#[test]
fn a_table_without_spin_that_rolling_shots_cannot_explain_says_so() {
    let [(_, billiard), _, _] = paper_materials();
    let poor = |f: &MaterialFit| {
        f.notes
            .iter()
            .any(|n| n.starts_with(streakfit::fit::POOR_FIT_NOTE))
    };
    let opts = FitOptions {
        bootstrap: 0,
        ..FitOptions::default()
    };
    let (rows, _) = synthetic_table(&mixed_spin_billiard(billiard, 8));
    let f = fit_one(&rows, &opts);
    let note = f
        .notes
        .iter()
        .find(|n| n.starts_with(streakfit::fit::POOR_FIT_NOTE))
        .unwrap_or_else(|| panic!("chi²/dof {}, notes {:?}", f.chi2_reduced, f.notes));
    assert!(
        note.contains("state no spin") && note.contains("--spin estimate"),
        "{note}"
    );
    // Fitted with estimated spin, or as rolling shots that were rolling, no such note.
    let estimated = fit_one(
        &rows,
        &FitOptions {
            spin: SpinMode::Estimate,
            ..opts.clone()
        },
    );
    assert!(!poor(&estimated), "{:?}", estimated.notes);
    let mut rolling = spec("billiard", billiard, 80, 8);
    rolling.psi_lo_deg = 15.0;
    rolling.psi_hi_deg = 65.0;
    let (rows, _) = synthetic_table(&rolling);
    let f = fit_one(&rows, &opts);
    assert!(
        !poor(&f),
        "chi²/dof {}, notes {:?}",
        f.chi2_reduced,
        f.notes
    );
    assert!(f.chi2_reduced < 2.0, "chi²/dof {}", f.chi2_reduced);
}

/// The demo's rubber campaign as session 27's extractor read it (`tests/data`, its 33 `ok` rows):
/// nearly every shot sticks, and shot_016 (psi 75.7°) and shot_029 (79.2°) lie beyond `psi_L`
/// (75.3°, Eq. 50 with `mu0 = mu = 0.6`, `e = 0.88`). The two-regime threshold profile was
/// once swept only upwards from a single sticking shot, and its warm starts carried that gross-
/// slip valley to every threshold: chi² 150,000 with `e` 0.91, `s–mu` chosen, and shot_029
/// rejected as a 33-sigma outlier. Swept both ways it finds chi² 31 and keeps every shot.
#[test]
fn the_slipping_shots_of_the_demos_rubber_campaign_give_the_two_regime_model() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/rubber_demo_session27.csv"
    );
    let rows = streakfit::table::read_angle_table(path).unwrap();
    let f = fit_one(&rows, &FitOptions::default());
    assert_eq!(f.model, "two-regime", "{:?}", f.scores);
    assert_eq!(f.n_rejected, 0);
    assert!(f.chi2 < 100.0, "chi² {}", f.chi2);
    assert!((f.e.unwrap() - 0.88).abs() < 0.002, "e {:?}", f.e);
    assert!((f.mu.unwrap() - 0.60).abs() < 0.005, "mu {:?}", f.mu);
    let psi_l = f.psi_l_deg.unwrap();
    assert!(
        (75.7..79.2).contains(&psi_l),
        "psi_L {psi_l} between the two slipping shots' psi"
    );
}
