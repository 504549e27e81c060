//! Theory core: the checks of PHYSICS.md, closed forms against the impulse model, regimes,
//! energy, rebound, and the `predict` command.

use proptest::prelude::*;
use std::f64::consts::FRAC_PI_2;
use std::process::Command;
use streakfit::physics::{
    Coefficients, Regime, RegimeChoice, Shot, ShotAngles, closed, impulse, rebound, regime,
};

const DEG: f64 = std::f64::consts::PI / 180.0;

fn shot(psi_deg: f64, m: f64, r: f64, s: f64) -> Shot {
    Shot {
        psi: psi_deg * DEG,
        mass_ratio: m,
        spin: r,
        english: s,
    }
}

fn deg(a: Option<f64>) -> f64 {
    a.expect("angle should be defined").to_degrees()
}

fn frictionless(e: f64) -> Coefficients {
    Coefficients::new(e, 0.0, 0.0)
}

/// Angle difference wrapped to (-pi, pi].
fn ang_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d - std::f64::consts::TAU
    } else {
        d
    }
}

#[test]
fn ninety_degree_rule_for_stun_shots() {
    for psi in [0.5, 10.0, 30.0, 45.0, 60.0, 89.0] {
        let st = impulse::solve(
            &shot(psi, 1.0, 0.0, 0.0),
            &frictionless(1.0),
            RegimeChoice::Auto,
        );
        let a = st.angles();
        assert!(
            (deg(a.delta1) - 90.0).abs() < 1e-9,
            "psi {psi}: delta1 {:?}",
            a.delta1
        );
        assert!(
            (deg(a.theta1) - 90.0).abs() < 1e-9,
            "psi {psi}: theta1 {:?}",
            a.theta1
        );
        assert!(deg(a.delta2).abs() < 1e-9 && deg(a.theta2).abs() < 1e-9);
    }
}

#[test]
fn thirty_degree_rule_for_rolling_cue_ball() {
    let c = frictionless(1.0);
    for psi in [5.0, 20.0, 28.1, 45.0, 70.0] {
        let a = impulse::solve(&shot(psi, 1.0, 1.0, 0.0), &c, RegimeChoice::Auto).angles();
        let expect = (3.5 * (psi * DEG).tan()).atan().to_degrees();
        assert!((deg(a.theta1) - expect).abs() < 1e-9, "psi {psi}");
    }
    // Peak of the deflection theta1 - psi: 33.7° at psi = 28.1°.
    let (mut best_psi, mut best) = (0.0, f64::MIN);
    for i in 1..9000 {
        let psi = i as f64 * 0.01;
        let a = closed::angles(&shot(psi, 1.0, 1.0, 0.0), &c, Regime::MuMu);
        let dev = deg(a.theta1) - psi;
        if dev > best {
            best = dev;
            best_psi = psi;
        }
    }
    assert!((best - 33.7).abs() < 0.05, "peak deflection {best}");
    assert!((best_psi - 28.1).abs() < 0.05, "peak at {best_psi}");
}

#[test]
fn frictionless_object_ball_leaves_along_line_of_centres() {
    for e in [0.0, 0.5, 0.97, 1.0] {
        for psi in [0.0, 20.0, 60.0, 85.0] {
            for (r, s) in [(1.0, 0.0), (0.0, 0.3), (-1.0, -0.5)] {
                let st =
                    impulse::solve(&shot(psi, 1.0, r, s), &frictionless(e), RegimeChoice::Auto);
                let a = st.angles();
                assert!(
                    deg(a.delta2).abs() < 1e-12 && deg(a.theta2).abs() < 1e-12,
                    "e {e} psi {psi}"
                );
            }
        }
    }
}

#[test]
fn mirror_symmetry_flips_every_angle() {
    let c = Coefficients::new(0.9, 0.2, 0.3).with_static(0.25);
    for psi in [3.0, 25.0, 50.0, 80.0] {
        for (r, s) in [(1.0, 0.0), (0.5, 0.4), (-0.7, -0.2)] {
            for choice in [RegimeChoice::Auto, RegimeChoice::Fixed(Regime::SlipSlip)] {
                let a = impulse::solve(&shot(psi, 1.0, r, s), &c, choice);
                let b = impulse::solve(&shot(-psi, 1.0, r, -s), &c, choice);
                assert_eq!(a.regime, b.regime);
                for (x, y) in a.angles().as_array().iter().zip(b.angles().as_array()) {
                    assert!((x.unwrap() + y.unwrap()).abs() < 1e-12);
                }
            }
        }
    }
}

#[test]
fn heavy_cue_ball_goes_on_undeflected_in_every_regime() {
    let c = Coefficients::new(0.9, 0.3, 0.5);
    for regime in Regime::ALL {
        for psi in [5.0, 30.0, 60.0] {
            for (r, s) in [(1.0, 0.0), (0.3, 0.2)] {
                let sh = shot(psi, 1e9, r, s);
                let a = impulse::solve(&sh, &c, RegimeChoice::Fixed(regime)).angles();
                let b = closed::angles(&sh, &c, regime);
                for x in [a.delta1, a.theta1, b.delta1, b.theta1] {
                    assert!((deg(x) - psi).abs() < 1e-6, "{regime} psi {psi}: {x:?}");
                }
            }
        }
    }
}

#[test]
fn table_friction_cancels_from_theta2_in_gross_slip() {
    for psi in [10.0, 40.0, 70.0] {
        let a = closed::angles(
            &shot(psi, 1.0, 1.0, 0.0),
            &Coefficients::new(0.97, 0.07, 0.0),
            Regime::MuMu,
        );
        let b = closed::angles(
            &shot(psi, 1.0, 1.0, 0.0),
            &Coefficients::new(0.97, 0.07, 0.5),
            Regime::MuMu,
        );
        assert!((deg(a.theta2) - deg(b.theta2)).abs() < 1e-12);
        // ... and moves delta2 only a little for billiard-ball values.
        let d = (deg(a.delta2) - deg(b.delta2)).abs();
        assert!(d > 1e-4 && d < 0.5, "delta2 shift {d}");
    }
}

#[test]
fn limit_angles_of_table_one_materials() {
    assert_eq!(regime::psi_limit_rolling(0.97, 0.07), None);
    let steel = regime::psi_limit_rolling(0.92, 0.18).unwrap().to_degrees();
    assert!((steel - 34.24).abs() < 0.01, "steel psi_L {steel}");
    let rubber = regime::psi_limit_rolling(0.88, 0.60).unwrap().to_degrees();
    assert!((rubber - 75.33).abs() < 0.01, "rubber psi_L {rubber}");
    // The auto regime switches exactly there, from slip–stick to gross slip.
    let c = Coefficients::new(0.92, 0.14, 0.15).with_static(0.18);
    let b = regime::regime_boundaries(&Shot::rolling(0.0), &c);
    assert_eq!(b.len(), 1);
    assert!((b[0].psi.to_degrees() - steel).abs() < 1e-9);
    assert_eq!((b[0].below, b[0].above), (Regime::SlipMu, Regime::MuMu));
    // Billiard balls: gross slip at every angle.
    let billiard = Coefficients::new(0.97, 0.07, 0.15);
    for psi in [0.0, 10.0, 45.0, 89.0] {
        assert_eq!(
            regime::select_regime(&shot(psi, 1.0, 1.0, 0.0), &billiard),
            Regime::MuMu
        );
    }
}

#[test]
fn table_limit_closed_forms_match_the_stick_conditions() {
    // Eq. (51) corrected (49/4 mu'^2): gross slip at the ball–ball contact.
    let c = Coefficients::new(0.9, 0.5, 2.0);
    let roots = regime::boundaries(|p| regime::table_margin(&Shot::rolling(p), &c, false));
    let eq51 = regime::psi_limit_table_after_slip(0.5, 2.0).unwrap();
    assert_eq!(roots.len(), 1);
    assert!((roots[0] - eq51).abs() < 1e-10, "{} vs {}", roots[0], eq51);
    // Eq. (53), table under a sticking ball–ball contact, needs mu' above ~(7/2)(1+e)/(7/2)+..: none for 0.55.
    assert_eq!(regime::psi_limit_table_after_stick(0.88, 0.6, 0.55), None);
    let s = regime::psi_limit_table_after_stick(0.5, 0.3, 4.0).unwrap();
    assert!(
        regime::table_margin(
            &Shot::rolling(s - 1e-6),
            &Coefficients::new(0.5, 0.3, 4.0),
            true
        ) > 0.0
    );
}

#[test]
fn auto_regime_matches_impulse_model_stick_tests() {
    for &(e, mu, mt, m0) in &[
        (0.97, 0.07, 0.15, 0.07),
        (0.92, 0.14, 0.15, 0.18),
        (0.88, 0.6, 0.55, 0.6),
        (0.5, 0.3, 0.5, 0.3),
        (0.6, 0.5, 3.0, 0.6),
    ] {
        let c = Coefficients::new(e, mu, mt).with_static(m0);
        for i in 0..90 {
            for r in [-2.0, -0.5, 0.0, 0.5, 1.0, 3.0] {
                for s in [-0.5, 0.0, 0.3] {
                    let sh = shot(i as f64, 1.0, r, s);
                    let (bb, tb) = impulse::stick_tests(&sh, &c);
                    assert_eq!(
                        regime::select_regime(&sh, &c),
                        Regime::from_contacts(bb, tb),
                        "{sh:?} {c:?}"
                    );
                }
            }
        }
    }
}

fn grid() -> Vec<(Shot, Coefficients)> {
    let mut out = Vec::new();
    for psi in [0.0, 1e-6, 3.0, 17.0, 33.0, 52.0, 71.0, 86.0, 89.99] {
        for m in [0.0, 0.3, 1.0, 2.5] {
            for r in [-1.5, -0.3, 0.0, 0.6, 1.0, 2.5] {
                for s in [-0.6, 0.0, 0.25] {
                    for (e, mu, mt, m0) in [
                        (0.97, 0.07, 0.15, 0.07),
                        (0.5, 0.3, 0.5, 0.4),
                        (0.88, 0.6, 2.5, 0.6),
                        (1.0, 0.0, 0.0, 0.0),
                    ] {
                        out.push((
                            shot(psi, m, r, s),
                            Coefficients::new(e, mu, mt).with_static(m0),
                        ));
                    }
                }
            }
        }
    }
    out
}

#[test]
fn closed_forms_agree_with_impulse_model_in_every_regime() {
    let mut compared = 0;
    for (sh, c) in grid() {
        let auto = regime::select_regime(&sh, &c);
        for regime in Regime::ALL {
            let st = impulse::solve(&sh, &c, RegimeChoice::Fixed(regime));
            let a = st.angles();
            let b = closed::angles(&sh, &c, regime);
            let speeds = [
                st.v1.xy().norm(),
                st.v2.xy().norm(),
                st.v1_roll.norm(),
                st.v2_roll.norm(),
            ];
            for (k, speed) in speeds.into_iter().enumerate() {
                let (x, y) = (a.as_array()[k], b.as_array()[k]);
                // Directions of near-stopped balls are ill-conditioned: skipped here, their
                // edge cases are pinned in tests/stability.rs.
                if speed < 1e-3 * sh.mass_ratio.max(1.0) {
                    continue;
                }
                let (x, y) = (x.expect("impulse angle"), y.expect("closed angle"));
                assert!(
                    ang_diff(x, y).abs() < 1e-12,
                    "{} {regime} (auto {auto}) {sh:?} {c:?}: {x} vs {y}",
                    ShotAngles::NAMES[k]
                );
                compared += 1;
            }
        }
    }
    assert!(compared > 20_000, "compared {compared}");
}

#[test]
fn edge_angles_are_exact_and_finite() {
    let c = Coefficients::new(0.9, 0.1, 0.2);
    // M = e exactly: tan delta1 infinite in slip–stick, delta1 exactly 90° for psi > 0, s = 0.
    let a = closed::angles(&shot(20.0, 0.9, 1.0, 0.0), &c, Regime::SlipMu);
    assert!((deg(a.delta1) - 90.0).abs() < 1e-12);
    // psi -> 90°: the cue ball is barely touched and goes on at ~psi.
    let a = closed::angles(&shot(89.999, 1.0, 1.0, 0.0), &c, Regime::MuMu);
    assert!((deg(a.delta1) - 89.999).abs() < 1e-3);
    assert!(a.as_array().iter().all(|x| x.is_some_and(f64::is_finite)));
    // Head-on stun, e = 1, M = 1: the cue ball stops; its direction is undefined.
    let st = impulse::solve(
        &shot(0.0, 1.0, 0.0, 0.0),
        &Coefficients::new(1.0, 0.07, 0.15),
        RegimeChoice::Auto,
    );
    assert_eq!(st.angles().delta1, None);
    assert_eq!(
        closed::angles(
            &shot(0.0, 1.0, 0.0, 0.0),
            &Coefficients::new(1.0, 0.07, 0.15),
            st.regime
        )
        .delta1,
        None
    );
    // M = 0: the object ball (a heavy plate) does not move.
    let st = impulse::solve(&shot(30.0, 0.0, 1.0, 0.0), &c, RegimeChoice::Auto);
    assert_eq!((st.angles().delta2, st.angles().theta2), (None, None));
}

#[test]
fn printed_eq40_fails_heavy_ball_limit_and_derived_form_passes() {
    // Eq. (40) as printed: [(M + 5/7) + (2/5) r] tan psi / [M - e + ((2/5)(1+M) - (2/7) k) r].
    let (m, e, mu, r, psi) = (1e6, 0.9, 0.2, 1.0, 40.0 * DEG);
    let k = 1.0 + 2.0 / 7.0 * mu * psi.cos();
    let printed =
        (((m + 5.0 / 7.0) + 0.4 * r) * psi.tan()) / (m - e + (0.4 * (1.0 + m) - 2.0 / 7.0 * k) * r);
    assert!(
        (printed.atan() - psi).abs() > 0.05,
        "printed form passes unexpectedly"
    );
    let derived = closed::angles(
        &Shot {
            psi,
            mass_ratio: m,
            spin: r,
            english: 0.0,
        },
        &Coefficients::new(e, mu, 0.1),
        Regime::SlipMu,
    );
    assert!((derived.theta1.unwrap() - psi).abs() < 1e-5);
}

#[test]
fn energy_does_not_increase_for_table_one_materials_or_the_test_grid() {
    for (sh, c) in grid() {
        let st = impulse::solve(&sh, &c, RegimeChoice::Auto);
        assert!(
            !st.gains_energy(),
            "energy gain {:?} {c:?} {sh:?}",
            st.energy_after / st.energy_before
        );
    }
    for c in [
        Coefficients::new(0.97, 0.07, 0.15),
        Coefficients::new(0.92, 0.14, 0.15).with_static(0.18),
        Coefficients::new(0.88, 0.60, 0.55),
    ] {
        for i in 0..90 {
            for r in [-2.0, -1.0, -0.3, 0.0, 0.5, 1.0, 2.0] {
                for s in [-0.5, -0.2, 0.0, 0.2, 0.5] {
                    let st = impulse::solve(&shot(i as f64, 1.0, r, s), &c, RegimeChoice::Auto);
                    assert!(
                        st.energy_after <= st.energy_before * (1.0 + 1e-12),
                        "{c:?} psi {i} r {r} s {s}"
                    );
                }
            }
        }
    }
}

#[test]
fn slip_stick_torque_rules_can_create_energy_and_it_is_reported() {
    // Found by a scan (docs/physics.md, "Energy"): the extra angular impulse (2/7) mu' of the
    // table's slip–stick rule adds energy in an s–s impact with very rough cloth, elastic balls.
    let c = Coefficients::new(1.0, 0.2, 3.0);
    let st = impulse::solve(&shot(0.0, 3.0, 0.9, 0.0), &c, RegimeChoice::Auto);
    assert_eq!(st.regime, Regime::SlipSlip);
    assert!(st.gains_energy());
    let gain = st.energy_after / st.energy_before - 1.0;
    assert!((gain - 0.0370).abs() < 5e-4, "gain {gain}");
    // The ball–ball rule k = 1 + (2/7) mu cos sigma with draw (cos sigma < 0) and large mu.
    let c = Coefficients::new(1.0, 5.0, 0.0);
    let st = impulse::solve(&shot(0.0, 0.0, -5.0, 0.0), &c, RegimeChoice::Auto);
    assert_eq!(st.regime, Regime::SlipMu);
    assert!(st.gains_energy());
    // Forcing gross slip where the friction limit would stop the slip reverses it: energy appears.
    let st = impulse::solve(
        &shot(1.0, 0.0, 0.0, 0.0),
        &c,
        RegimeChoice::Fixed(Regime::MuMu),
    );
    assert!(st.gains_energy());
}

#[test]
fn rebound_on_heavy_plate() {
    let (e, mu) = (0.8, 0.3);
    let c = Coefficients::new(e, mu, 0.0);
    for psi in [5.0, 20.0, 40.0, 60.0, 80.0, 85.0, 88.0] {
        let sh = shot(psi, 0.0, 0.0, 0.0);
        let st = impulse::solve(&sh, &c, RegimeChoice::Auto);
        // Tangential velocity of ball 1's contact point at separation, over mu v_oy.
        let vt = st.v1.y + st.w1.cross(&nalgebra::Vector3::x()).y;
        let got = vt / (mu * (psi * DEG).cos());
        let x = (psi * DEG).tan() / mu;
        if rebound::rebound_regime(x, e) == Regime::MuMu {
            // Gross slip: the M = 0 limit of the two-ball model is Section 2.3's line (Eq. 30).
            assert!((got - rebound::slip_line(x, e)).abs() < 1e-9, "psi {psi}");
        } else {
            // Slip–stick: the two-ball rule scales only the vertical slip (cos sigma = 0 without
            // spin), so it stops the contact (classical no-slip); Section 2.3's plate rule
            // reverses it, Eq. (34).
            assert!(got.abs() < 1e-12, "psi {psi}: {got}");
            assert!((rebound::contact_velocity(x, e, mu) + 10.0 / 49.0 * mu * x).abs() < 1e-12);
        }
    }
    // The switch is at X = (7/2)(1+e): psi = atan(mu (7/2)(1+e)) = 62.1° here.
    assert_eq!(rebound::rebound_regime(3.5 * 1.8 - 1e-9, e), Regime::SlipMu);
    assert_eq!(rebound::rebound_regime(3.5 * 1.8 + 1e-9, e), Regime::MuMu);
    // Slopes of Fig. 6: 1 in gross slip, -(10/49) mu in slip–stick.
    assert!((rebound::slip_line(10.0, e) - rebound::slip_line(9.0, e) - 1.0).abs() < 1e-12);
    assert!(
        (rebound::stick_line(2.0, mu) - rebound::stick_line(1.0, mu) + 10.0 / 49.0 * mu).abs()
            < 1e-12
    );
}

#[test]
fn paths_end_tangent_to_the_rolling_line() {
    use nalgebra::{Vector2, Vector3};
    use streakfit::physics::path::{BallPath, Cloth};
    let c = Coefficients::new(0.97, 0.07, 0.15);
    let st = impulse::solve(&shot(45.0, 1.0, 1.0, 0.0), &c, RegimeChoice::Auto);
    let (v0, radius) = (0.75, 0.028575);
    let cloth = Cloth {
        mu_slide: 0.2,
        mu_roll: 0.01,
    };
    let p = BallPath::new(
        Vector2::zeros(),
        st.v1 * v0,
        st.w1 * (v0 / radius),
        radius,
        &cloth,
    );
    // Start tangent = delta1, final direction = theta1.
    assert!(ang_diff(p.v0.y.atan2(p.v0.x), st.angles().delta1.unwrap()).abs() < 1e-12);
    let vr = p.velocity(p.t_slide + 0.1);
    assert!(ang_diff(vr.y.atan2(vr.x), st.angles().theta1.unwrap()).abs() < 1e-12);
    // Rolling speed matches the impulse model's rolling velocity (Eqs. 14–15).
    assert!((p.v_roll.norm() - st.v1_roll.norm() * v0).abs() < 1e-12);
    // Continuous position; at rest after t_stop.
    let (a, b) = (p.position(p.t_slide - 1e-9), p.position(p.t_slide + 1e-9));
    assert!((a - b).norm() < 1e-8);
    assert_eq!(p.velocity(p.t_stop + 1.0), Vector2::zeros());
    let _ = Vector3::<f64>::zeros();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]
    #[test]
    fn every_output_is_finite_or_undefined(
        psi in 0.0..FRAC_PI_2, m in 0.0..20.0f64, r in -5.0..5.0f64, s in -5.0..5.0f64,
        e in 0.0..=1.0f64, mu in 0.0..2.0f64, mt in 0.0..3.0f64, m0 in 0.0..2.0f64,
    ) {
        let sh = Shot { psi, mass_ratio: m, spin: r, english: s };
        let c = Coefficients::new(e, mu, mt).with_static(m0);
        let st = impulse::solve(&sh, &c, RegimeChoice::Auto);
        for a in st.angles().as_array().into_iter().chain(closed::angles(&sh, &c, st.regime).as_array()) {
            prop_assert!(a.is_none_or(|x| x.is_finite() && x.abs() <= std::f64::consts::PI));
        }
        prop_assert!(st.energy_after.is_finite());
    }
}

fn streakfit(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_streakfit"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn predict_prints_json_with_exactly_the_documented_keys() {
    let (code, out, _) = streakfit(&[
        "predict",
        "--psi",
        "45",
        "--e",
        "0.97",
        "--mu",
        "0.07",
        "--mu-table",
        "0.15",
        "--json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let mut keys: Vec<_> = v.as_object().unwrap().keys().cloned().collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "delta1_deg",
            "delta2_deg",
            "regime",
            "theta1_deg",
            "theta2_deg"
        ]
    );
    assert_eq!(v["regime"], "mu-mu");
    let expect = closed::angles(
        &Shot::rolling(45.0 * DEG),
        &Coefficients::new(0.97, 0.07, 0.15),
        Regime::MuMu,
    );
    assert!((v["theta1_deg"].as_f64().unwrap() - deg(expect.theta1)).abs() < 1e-9);
}

#[test]
fn predict_range_and_bad_input() {
    let (code, out, _) = streakfit(&[
        "predict",
        "--psi",
        "0:85:5",
        "--e",
        "0.92",
        "--mu",
        "0.14",
        "--mu-table",
        "0.15",
        "--mu-static",
        "0.18",
    ]);
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), 1 + 18);
    assert!(
        out.lines().nth(1).unwrap().contains("s-mu")
            && out.lines().last().unwrap().contains("mu-mu")
    );
    for bad in [
        vec!["--psi", "45", "--e", "-0.1"],
        vec!["--psi", "45", "--e", "1.2"],
        vec!["--psi", "90", "--e", "0.9"],
        vec!["--psi", "-3", "--e", "0.9"],
        vec!["--psi", "NaN", "--e", "0.9"],
        vec!["--psi", "45", "--e", "NaN"],
        vec!["--psi", "45", "--e", "0.9", "--regime", "slip"],
    ] {
        let mut args = vec!["predict"];
        args.extend(bad.iter());
        args.extend(["--mu", "0.1", "--mu-table", "0.1"]);
        let (code, out, err) = streakfit(&args);
        assert_eq!(code, 2, "{bad:?}: {out} {err}");
        assert!(out.is_empty() && !err.is_empty(), "{bad:?}");
    }
    let (_, out, _) = streakfit(&[
        "predict",
        "--psi",
        "0",
        "--e",
        "1",
        "--mu",
        "0.07",
        "--mu-table",
        "0.15",
        "--spin",
        "0",
    ]);
    assert!(out.lines().nth(1).unwrap().contains("undefined"));
}

#[test]
fn fast_auto_path_matches_regime_selection_and_closed_forms() {
    for (sh, c) in grid() {
        let (r, a) = closed::predict_auto(&sh, &c);
        assert_eq!(r, regime::select_regime(&sh, &c));
        assert_eq!(a, closed::angles(&sh, &c, r));
    }
}

/// What `vision::shot::OBJECT_SLIDE_END_MIN` and the README rest on: after a rolling cue ball
/// hits it, the object ball of Table 1's billiard, steel and rubber ends its slide at 0.63–0.70
/// of its start speed (5/7 but for the vertical friction impulse), and a rubber object ball's
/// slide is so short, and its rolling line passes so close to its start, that the turn from
/// `delta2` to `theta2` hides under the waiting disc.
#[test]
fn object_ball_slide_speed_ratio_and_hidden_rubber_turn() {
    use nalgebra::Vector2;
    use streakfit::physics::path::{BallPath, Cloth};
    // (e, mu, mu', cloth sliding and rolling friction, radius m): datasets/materials.toml; a
    // cue-ball speed (m/s) as in the demo's photos.
    let materials = [
        ("billiard", 0.97, 0.07, 0.15, 0.20, 0.010, 0.028575, 1.0),
        ("steel", 0.92, 0.14, 0.15, 0.15, 0.008, 0.0125, 0.8),
        ("rubber", 0.88, 0.60, 0.55, 0.55, 0.015, 0.023, 0.77),
    ];
    for (name, e, mu, mu_table, slide, roll, radius, v) in materials {
        let c = Coefficients {
            e,
            mu,
            mu_table,
            mu_static: mu,
        };
        let cloth = Cloth {
            mu_slide: slide,
            mu_roll: roll,
        };
        for psi_deg in [10.0, 20.0, 35.0, 50.0, 65.0, 75.0] {
            let st = impulse::solve(&shot(psi_deg, 1.0, 1.0, 0.0), &c, RegimeChoice::Auto);
            let o = Vector2::new(2.0 * radius, 0.0);
            let p = BallPath::new(o, st.v2 * v, st.w2 * (v / radius), radius, &cloth);
            let ratio = p.v_roll.norm() / p.v0.norm();
            assert!(
                (0.62..0.71).contains(&ratio),
                "{name} psi {psi_deg}: slide ends at {ratio:.3} of its start speed"
            );
            assert!(ratio > streakfit::vision::shot::OBJECT_SLIDE_END_MIN);
            if name == "rubber" {
                let end = p.position(p.t_slide) - o;
                let u = p.v_roll / p.v_roll.norm();
                let offset = (u.x * end.y - u.y * end.x).abs() / radius;
                let turn = (p.v_roll.y.atan2(p.v_roll.x) - p.v0.y.atan2(p.v0.x)).to_degrees();
                // Slides of 0.09–1.0 R at 0.77 m/s; offsets 0.003–0.008 R; turns 0.3–3.9°.
                assert!(
                    p.slide_length() < 1.1 * radius,
                    "{psi_deg}: {}",
                    p.slide_length()
                );
                assert!(offset < 0.01, "psi {psi_deg}: offset {offset:.4} R");
                assert!(turn > 0.2, "psi {psi_deg}: turn {turn:.2}°");
            }
        }
    }
}
