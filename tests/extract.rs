//! `streakfit extract` end to end: synthetic photographs with known truth (written by
//! `streakfit synth`) through the extractor, plus the batch guarantees (one row per image, bad
//! files become `error` rows, shards concatenate, overlays written).
//!
//! Images are 1200×800 (R ≈ 52 px) to keep the suite fast; run with
//! `cargo test --release --test extract`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use streakfit::table::{ShotRow, Status, read_angle_table};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_streakfit")
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("streakfit_extract_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn synth(dir: &Path, tier: &str, shots: usize, seed: u64, extra: &[&str]) {
    let st = Command::new(bin())
        .args(["synth", "--out"])
        .arg(dir)
        .args([
            "--tier",
            tier,
            "--shots",
            &shots.to_string(),
            "--seed",
            &seed.to_string(),
        ])
        .args(if extra.contains(&"--size") {
            &[][..]
        } else {
            &["--size", "1200x800"][..]
        })
        .args(extra)
        .status()
        .unwrap();
    assert!(st.success(), "synth failed");
}

fn extract(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(bin())
        .arg("extract")
        .args(args)
        .output()
        .unwrap()
}

/// Truth table: file → column → value.
fn truth(dir: &Path) -> HashMap<String, HashMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("truth.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            let vals: Vec<String> = l.split(',').map(String::from).collect();
            let m: HashMap<String, String> = head.iter().cloned().zip(vals).collect();
            (m["file"].clone(), m)
        })
        .collect()
}

/// |measured − true| of row `r`'s value `v` of the truth column `key`.
fn abs_error(
    t: &HashMap<String, HashMap<String, String>>,
    r: &ShotRow,
    v: Option<f64>,
    key: &str,
) -> f64 {
    (v.expect("a measured value") - t[&r.file][key].parse::<f64>().unwrap()).abs()
}

/// Row `file` of a synthesised folder of 24 full-size photos (the folder's cloth texture needs
/// all of them: a single photo reads differently), with the folder's truth; the folder is
/// removed afterwards.
fn one_of_24(
    name: &str,
    tier: &str,
    seed: u64,
    file: &str,
) -> (ShotRow, HashMap<String, HashMap<String, String>>) {
    one_of_24_with(name, tier, seed, &[], file)
}

/// [`one_of_24`] with more `synth` flags (`extra`).
fn one_of_24_with(
    name: &str,
    tier: &str,
    seed: u64,
    extra: &[&str],
    file: &str,
) -> (ShotRow, HashMap<String, HashMap<String, String>>) {
    let dir = scratch(name);
    let mut args = extra.to_vec();
    args.extend(["--size", "2400x1600"]);
    synth(&dir, tier, 24, seed, &args);
    let (_, rows) = extract_errors(&dir, 24, &[]);
    let t = truth(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    let shot = rows.into_iter().find(|r| r.file == file).unwrap();
    (shot, t)
}

/// Asserts that `r` is `ok` and reads each of `angles` (`psi`, `theta1`, ...) within 3 stated
/// sigmas of the truth `t`, at a sigma under 0.6°.
fn assert_ok_within_3_sigma(
    r: &ShotRow,
    t: &HashMap<String, HashMap<String, String>>,
    angles: &[&str],
) {
    assert_eq!(r.status, Status::Ok, "{r:#?}");
    for a in angles {
        let (v, sd) = match *a {
            "psi" => (r.psi_deg, r.psi_err_deg),
            "delta1" => (r.delta1_deg, r.delta1_err_deg),
            "delta2" => (r.delta2_deg, r.delta2_err_deg),
            "theta1" => (r.theta1_deg, r.theta1_err_deg),
            "theta2" => (r.theta2_deg, r.theta2_err_deg),
            other => panic!("no angle {other}"),
        };
        let (e, sd) = (
            abs_error(t, r, v, &format!("{a}_deg")),
            sd.expect("a sigma"),
        );
        assert!(e < 3.0 * sd && sd < 0.6, "{a}: {e}° off at {sd}°: {r:#?}");
    }
}

/// Asserts that `r` is the photo of true psi `psi_deg` (its truth row `tr`) and is declined.
fn assert_declined_photo(r: &ShotRow, tr: &HashMap<String, String>, psi_deg: f64) {
    assert!(
        (tr["psi_deg"].parse::<f64>().unwrap() - psi_deg).abs() < 0.01,
        "{tr:?}"
    );
    assert_eq!(r.status, Status::Declined, "{r:#?}");
}

/// The row of `file` in realistic seed `seed`'s folder of 24 (with its texture map; `extra`
/// synth flags), asserted `declined` and at true psi `psi_deg`, for its reason to be checked.
fn declined_of_24(name: &str, seed: u64, extra: &[&str], file: &str, psi_deg: f64) -> ShotRow {
    let (shot, t) = one_of_24_with(name, "realistic", seed, extra, file);
    assert_declined_photo(&shot, &t[&shot.file], psi_deg);
    shot
}

/// Asserts the row of `file` in realistic seed `seed`'s folder of 24 (with its texture map;
/// `extra` synth flags) at true psi `psi_deg`, `ok` with psi and `theta2` within 3 stated
/// sigmas, and its reason starting with `reason_start`.
fn ok_of_24(name: &str, seed: u64, extra: &[&str], file: &str, psi_deg: f64, reason_start: &str) {
    let (shot, t) = one_of_24_with(name, "realistic", seed, extra, file);
    assert!(
        (t[&shot.file]["psi_deg"].parse::<f64>().unwrap() - psi_deg).abs() < 0.01,
        "{:?}",
        t[&shot.file]
    );
    assert_ok_within_3_sigma(&shot, &t, &["psi", "theta2"]);
    assert!(shot.reason.starts_with(reason_start), "{}", shot.reason);
}

/// `synth` flags of the near head-on realistic sets of session 31 (seeds 911–934).
const NEAR_HEAD_ON_MIXED: &[&str] = &["--material", "mixed", "--psi", "0:12"];

/// Removes every photo of a synthetic folder but `file` (each shot draws from its own stream, so
/// the one left is the same photo as in the full set; the plate and `scene.toml` stay).
fn keep_only(dir: &Path, file: &str) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if name.starts_with("shot_") && name != file {
            std::fs::remove_file(&p).unwrap();
        }
    }
}

/// The row of photo `file` extracted alone from a synthesised folder of `shots` full-size
/// photos (`extra`: more `synth` flags), with that photo's truth; the folder is removed
/// afterwards.
fn only_photo(
    name: &str,
    tier: &str,
    shots: usize,
    seed: u64,
    extra: &[&str],
    file: &str,
) -> (ShotRow, HashMap<String, String>) {
    let dir = scratch(name);
    let mut args = extra.to_vec();
    args.extend(["--size", "2400x1600"]);
    synth(&dir, tier, shots, seed, &args);
    keep_only(&dir, file);
    let out = dir.join("angles.csv");
    let o = extract(&[dir.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = read_angle_table(&out).unwrap();
    let mut t = truth(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(rows.len(), 1, "{rows:#?}");
    (rows.into_iter().next().unwrap(), t.remove(file).unwrap())
}

/// Asserts that `r` reads psi and `theta2` within 0.1° of the truth `tr` at stated sigmas under
/// 0.1°, without the cue ball's path (`theta1`, `delta1` undefined).
fn assert_psi_theta2_without_cue_path(r: &ShotRow, tr: &HashMap<String, String>) {
    assert_eq!(r.status, Status::Ok, "{r:#?}");
    assert_eq!((r.theta1_deg, r.delta1_deg), (None, None), "{r:#?}");
    let want = |k: &str| tr[k].parse::<f64>().unwrap();
    let (psi, psi_sd) = (r.psi_deg.unwrap(), r.psi_err_deg.unwrap());
    let (t2, t2_sd) = (r.theta2_deg.unwrap(), r.theta2_err_deg.unwrap());
    assert!(
        (psi - want("psi_deg")).abs() < 0.1 && psi_sd < 0.1,
        "{r:#?}"
    );
    assert!(
        (t2 - want("theta2_deg")).abs() < 0.1 && t2_sd < 0.1,
        "{r:#?}"
    );
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Runs synth + extract and returns per-angle absolute errors of the `ok` rows and the rows.
fn accuracy(
    tier: &str,
    seed: u64,
    shots: usize,
    size: &str,
) -> (HashMap<&'static str, Vec<f64>>, Vec<ShotRow>) {
    let dir = scratch(&format!("acc_{tier}"));
    // Near head-on shots (a ball stopping at the impact) are the subject of their own test
    // (`head_on_stun_shots_stop_the_cue_ball`).
    synth(&dir, tier, shots, seed, &["--psi", "15:75", "--size", size]);
    let res = extract_errors(&dir, shots, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    res
}

/// Extracts a synthetic folder (with extra `extract` arguments) and returns the absolute errors
/// of the `ok` rows against truth.csv, per angle (and the ball radius), with the rows.
fn extract_errors(
    dir: &Path,
    shots: usize,
    extra: &[&str],
) -> (HashMap<&'static str, Vec<f64>>, Vec<ShotRow>) {
    let out = dir.join(format!("angles{}.csv", extra.join("")));
    let mut args: Vec<&std::ffi::OsStr> = vec![dir.as_os_str(), "--out".as_ref(), out.as_os_str()];
    args.extend(extra.iter().map(|a| std::ffi::OsStr::new(*a)));
    let o = extract(&args);
    assert!(o.status.code().is_some(), "extract crashed");
    let rows = read_angle_table(&out).unwrap();
    assert_eq!(rows.len(), shots, "one row per image");
    let t = truth(dir);
    let mut errs: HashMap<&'static str, Vec<f64>> = HashMap::new();
    for r in rows.iter().filter(|r| r.status == Status::Ok) {
        // A start tangent is only reported with its rolling line.
        assert!(r.theta1_deg.is_some() || r.delta1_deg.is_none(), "{r:?}");
        assert!(r.theta2_deg.is_some() || r.delta2_deg.is_none(), "{r:?}");
        // A straight object-ball path does not measure its start tangent.
        if r.path_model2.as_deref() == Some("line") {
            assert!(r.delta2_deg.is_none(), "{r:?}");
            assert!(r.reason.contains("delta2 not resolved ("), "{r:?}");
        }
        let tr = &t[&r.file];
        for (name, v, sd) in [
            ("psi", r.psi_deg, r.psi_err_deg),
            ("theta1", r.theta1_deg, r.theta1_err_deg),
            ("theta2", r.theta2_deg, r.theta2_err_deg),
            ("delta2", r.delta2_deg, r.delta2_err_deg),
            ("delta1", r.delta1_deg, r.delta1_err_deg),
        ] {
            if let (Some(v), Ok(tv)) = (v, tr[&format!("{name}_deg")].parse::<f64>()) {
                errs.entry(name).or_default().push((v - tv).abs());
                // |error| / stated sigma of the angles whose sigma is calibrated
                // (`vision::shot::calibrated_sd`).
                if ["psi", "theta1", "theta2"].contains(&name) {
                    let sd = sd.expect("a measured angle states its sigma");
                    errs.entry("pull").or_default().push((v - tv).abs() / sd);
                }
            }
        }
        let tr_r: f64 = tr["ball_radius_px"].parse().unwrap();
        errs.entry("radius")
            .or_default()
            .push((r.ball_radius_px.unwrap() - tr_r).abs());
    }
    (errs, rows)
}

#[test]
fn clean_tier_accuracy() {
    let (errs, rows) = accuracy("clean", 11, 6, "1200x800");
    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    assert!(ok >= 5, "ok {ok}/6: {rows:#?}");
    for r in rows.iter().filter(|r| r.status == Status::Ok) {
        assert_eq!(r.material, "billiard");
        assert!(r.psi_err_deg.unwrap() > 0.0);
        assert!(["line", "parabola+line"].contains(&r.path_model2.as_deref().unwrap()));
    }
    let m = |k: &str| median(errs[k].clone());
    assert!(m("radius") < 0.1, "radius median error {}", m("radius"));
    // Regression guards above the values measured on this set (2026-11-22, 1200×800: psi 0.22°,
    // theta1 0.18°, theta2 0.27°, delta2 0.26°); README's table gives the accuracy on larger,
    // full-size sets.
    assert!(m("psi") < 0.3, "psi median error {}", m("psi"));
    assert!(m("theta1") < 0.3, "theta1 median error {}", m("theta1"));
    assert!(m("theta2") < 0.6, "theta2 median error {}", m("theta2"));
    // Stated sigmas of psi and theta (`vision::shot::calibrated_sd`): measured 1.72 on these 17
    // angles (2026-11-24; honest Gaussian errors give 0.67, and 24 shots of the same size give
    // sigma ratios 0.9–1.5, see the README); the bounds fail when the sigmas fall to two thirds
    // of today's or grow eightfold (a lost systematic part, a unit slip).
    assert!(
        (0.2..2.5).contains(&m("pull")),
        "median |error| / sigma {}",
        m("pull")
    );
    // Since 2026-11-24 no delta2 is left on this set: its one value came with an unresolved
    // theta2, and a start tangent is now reported only with its rolling line.
    if let Some(d2) = errs.get("delta2") {
        assert!(median(d2.clone()) < 0.8, "delta2 errors {d2:?}");
    }
}

/// 25 mm steel balls at the synthetic sets' scale (R ≈ 44 px) on the clean tier. The disc's edge
/// rule read the lit side of the waiting ball's limb short, moving `O` up to 0.06 px away from
/// the lamp, which at this size was most of psi's error (median 0.061° here, against the clean
/// target's 0.05°). Session 40 takes that bias off the joint fit's `O` and `R`
/// (`vision::disc::shading_bias`): measured psi 0.039°, theta1 0.037°, theta2 0.034°, 24 of 24
/// `ok` (seed 4002: 0.049°, 0.045°, 0.046°).
#[test]
fn small_steel_balls_meet_the_clean_targets() {
    let dir = scratch("steel_clean");
    synth(
        &dir,
        "clean",
        24,
        4001,
        &["--material", "steel", "--size", "2400x1600"],
    );
    let (errs, rows) = extract_errors(&dir, 24, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    assert!(ok >= 23, "ok {ok}/24");
    for k in ["psi", "theta1", "theta2"] {
        let m = median(errs[k].clone());
        assert!(m < 0.05, "{k} median error {m:.4}°");
    }
}

/// Without a plate the cloth's fixed texture (blotches of the ball's size) moves the faint
/// streaks' centre-lines. The folder's own photos give it (`vision::texture`, the default); with
/// `--no-texture` the colour projection of `vision::background` (cloth covariance weighted down)
/// is all that keeps it from the cue ball's arc. Full size, as the README's table.
#[test]
fn folder_texture_without_plate() {
    let dir = scratch("texture");
    synth(
        &dir,
        "clean",
        12,
        101,
        &["--psi", "15:75", "--size", "2400x1600"],
    );
    let (tex, rows_tex) = extract_errors(&dir, 12, &[]);
    let (plain, rows_plain) = extract_errors(&dir, 12, &["--no-texture"]);
    // Every shard of an array job builds the texture from the same photos of the whole folder,
    // so the shard tables are the full table's rows, number for number.
    let mut sharded: Vec<ShotRow> = Vec::new();
    for k in ["1/2", "2/2"] {
        let out = dir.join(format!("shard{}.csv", &k[..1]));
        let o = extract(&[
            dir.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
            "--shard".as_ref(),
            k.as_ref(),
        ]);
        assert!(o.status.code().is_some(), "extract crashed");
        sharded.extend(read_angle_table(&out).unwrap());
    }
    sharded.sort_by(|a, b| a.file.cmp(&b.file));
    assert_eq!(sharded.len(), rows_tex.len());
    for (a, b) in sharded.iter().zip(&rows_tex) {
        assert_eq!(
            (&a.file, a.status, a.psi_deg, a.theta2_deg, &a.cloth_model),
            (&b.file, b.status, b.psi_deg, b.theta2_deg, &b.cloth_model)
        );
    }
    // Every angle is read from the line of centres, whose own error moves them all alike:
    // the stated shared part is within each angle's sigma, and psi's and theta1's signed errors
    // move together: their difference is far smaller than their sum, which independent errors
    // of equal spread would make alike (measured 2026-11-25: medians 0.014° and 0.05° here; on
    // seeds 101-505, clean, no plate, their correlation is 0.96).
    let t = truth(&dir);
    let (mut both, mut diff) = (Vec::new(), Vec::new());
    for r in rows_tex.iter().filter(|r| r.status == Status::Ok) {
        let fr = r.frame_err_deg.expect("an ok row states its frame sigma");
        assert!(fr > 0.0 && fr <= r.psi_err_deg.unwrap() + 1e-12, "{r:?}");
        let (Some(th1), Some(sd1)) = (r.theta1_deg, r.theta1_err_deg) else {
            continue;
        };
        assert!(fr <= sd1 + 1e-12, "{r:?}");
        let tr = &t[&r.file];
        let e_psi = r.psi_deg.unwrap() - tr["psi_deg"].parse::<f64>().unwrap();
        let e_th1 = th1 - tr["theta1_deg"].parse::<f64>().unwrap();
        both.push((e_psi + e_th1).abs());
        diff.push((e_psi - e_th1).abs());
    }
    assert!(both.len() >= 8, "psi and theta1 on {} rows", both.len());
    let (ms, md) = (median(both), median(diff));
    eprintln!("median |e_psi + e_theta1| {ms:.4}°, median |e_psi - e_theta1| {md:.4}°");
    assert!(md < 0.5 * ms, "psi and theta1 errors do not move together");
    let _ = std::fs::remove_dir_all(&dir);
    for (rows, model) in [(&rows_tex, "texture"), (&rows_plain, "surface")] {
        let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
        assert!(ok >= 10, "{model}: ok {ok}/12");
        for r in rows {
            assert_eq!(r.cloth_model.as_deref(), Some(model), "{}", r.file);
        }
    }
    let m = |e: &HashMap<&'static str, Vec<f64>>, k: &str| median(e[k].clone());
    for k in ["psi", "theta1", "theta2", "delta1"] {
        eprintln!(
            "{k}: texture n {} median {:.3}; surface n {} median {:.3}",
            tex[k].len(),
            m(&tex, k),
            plain[k].len(),
            m(&plain, k)
        );
    }
    // Measured 2026-11-24 (texture / surface): psi 0.041° / 0.072°, theta1 0.044° / 0.069°,
    // theta2 0.032° / 0.091°, delta1 0.215° / 0.138° (9 of 12 each; session 12's code: 0.456° /
    // 0.335°). delta1 comes from pixels near the impact, where the object ball waits in
    // most shots and the map is blank; the arc's high-passed refit (`vision::arc`) takes the
    // blotches out there, with or without the map. The target is 0.3°.
    for (k, bound) in [("psi", 0.06), ("theta1", 0.06), ("theta2", 0.05)] {
        assert!(m(&tex, k) < bound, "{k} median error {}", m(&tex, k));
        assert!(m(&tex, k) < m(&plain, k), "{k}: the texture must help");
    }
    assert!(
        tex["delta1"].len() >= 8,
        "delta1 measured on {}",
        tex["delta1"].len()
    );
    assert!(
        m(&tex, "delta1") < 0.3,
        "delta1 median error {}",
        m(&tex, "delta1")
    );
    assert!(
        m(&plain, "delta1") < 0.3,
        "delta1 median error {}",
        m(&plain, "delta1")
    );
}

/// Head-on stun shots (psi < 1.5°, |r| < 0.05): the cue ball stops against the object ball. A
/// white cue ball is the brighter of the two resting discs, so the first reading takes it for
/// the object ball; the light's arrow of time (the object ball leaves sliding and brightens
/// away from its disc) swaps the roles back. The cue ball's angles are undefined, psi and
/// theta2 are measured. Full size with a plate, as the README's table. Measured 2026-11-24 on
/// this set (seed 41): 6/8 ok, psi errors 0.001–0.05° but one of 0.82°, theta2 0.002–0.04°
/// but one of 0.60° (the same shot); before the swap every ok row measured theta2 on the cue
/// ball's incoming streak (0.5–1.8° off at stated sigmas of 0.05–0.1°). Since the resting
/// ball's rim is integrated over each pixel (2026-11-25): 7/8 ok, psi 0.001–0.13° but one of
/// 0.25°; theta2 0.002–0.07° on six, and on shot_006 not resolved (its object ball's path fits
/// best as a near-straight parabola whose rolling line is undetermined; as a line it read 1.2°
/// off at a stated 0.38°, so "not resolved" is the honest answer).
#[test]
fn head_on_stun_shots_stop_the_cue_ball() {
    let dir = scratch("head_on");
    synth(
        &dir,
        "clean",
        8,
        41,
        &[
            "--psi",
            "0:1.5",
            "--spin=-0.05:0.05",
            "--background",
            "--size",
            "2400x1600",
        ],
    );
    let out = dir.join("angles.csv");
    let o = extract(&[dir.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(o.status.code().is_some(), "extract crashed");
    let rows = read_angle_table(&out).unwrap();
    assert_eq!(rows.len(), 8, "one row per image");
    let t = truth(&dir);
    let ok: Vec<&ShotRow> = rows.iter().filter(|r| r.status == Status::Ok).collect();
    assert!(ok.len() >= 5, "ok {}/8: {rows:#?}", ok.len());
    let (mut psi, mut theta2) = (Vec::new(), Vec::new());
    for r in &ok {
        assert!(r.delta1_deg.is_none() && r.theta1_deg.is_none(), "{r:#?}");
        assert!(
            r.reason.starts_with("cue ball stops at the impact"),
            "{r:#?}"
        );
        let tr = &t[&r.file];
        let err = |v: Option<f64>, k: &str| (v.unwrap() - tr[k].parse::<f64>().unwrap()).abs();
        psi.push(err(r.psi_deg, "psi_deg"));
        if r.theta2_deg.is_some() {
            theta2.push(err(r.theta2_deg, "theta2_deg"));
        } else {
            assert!(r.reason.contains("theta2 not resolved"), "{r:#?}");
        }
    }
    assert!(
        theta2.len() >= 5,
        "theta2 measured on {} rows",
        theta2.len()
    );
    assert!(median(psi.clone()) < 0.1, "psi errors {psi:?}");
    assert!(median(theta2.clone()) < 0.1, "theta2 errors {theta2:?}");
}

/// A rolling cue ball at small psi runs alongside the object ball's streak: seed 202's clean
/// shot_007 (psi 7.9°, `delta1` 83.4°, `theta1` 28.0°) hooks within a fraction of a radius under
/// the object ball's light, and its rolling line is clear of the other streaks for only 1.3 R.
/// The arc fit used to read `delta1` 30.3° at a stated 0.6°; now it is unresolved with the
/// reason, while the same folder's other rolling shots keep theirs (measured 2026-11-24:
/// `delta1` read on shots 1, 2, 3 and 5, 0.02–0.19° off).
/// Realistic head-on stun shots: the cue ball rests against the object ball, and only the
/// object ball's slowing down away from its disc tells the two resting balls apart. Where the
/// two streaks' brightening does not differ by two standard errors in either reading, the row
/// is declined with that reason (session 21: on this set those readings had `theta2` 0.98° off
/// at a stated 0.14°, 0.39° at 0.16°, 0.35° at 0.11°); every reading kept is within 3 sigma.
#[test]
fn resting_balls_told_apart_only_by_a_clear_time_arrow() {
    let dir = scratch("head_on_realistic");
    synth(
        &dir,
        "realistic",
        16,
        43,
        &["--psi", "0:1.5", "--spin=-0.05:0.05", "--size", "2400x1600"],
    );
    let (_, rows) = extract_errors(&dir, 16, &[]);
    let t = truth(&dir);
    let ok: Vec<&ShotRow> = rows.iter().filter(|r| r.status == Status::Ok).collect();
    assert!(ok.len() >= 3, "ok {}/16: {rows:#?}", ok.len());
    for r in &ok {
        for (v, e, k) in [
            (r.psi_deg, r.psi_err_deg, "psi_deg"),
            (r.theta2_deg, r.theta2_err_deg, "theta2_deg"),
        ] {
            if v.is_some() {
                let err = abs_error(&t, r, v, k);
                assert!(err < 3.0 * e.unwrap(), "{k} {err:.2}° off: {r:#?}");
            }
        }
    }
    let undecided = rows
        .iter()
        .filter(|r| {
            r.reason.starts_with(
                "cannot tell which resting ball is the object ball (the object ball brightens",
            )
        })
        .count();
    assert!(undecided >= 2, "{rows:#?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_hook_hidden_along_the_object_balls_streak_is_not_read() {
    let dir = scratch("hidden_hook");
    synth(
        &dir,
        "clean",
        7,
        202,
        &["--background", "--size", "2400x1600"],
    );
    let out = dir.join("angles.csv");
    let o = extract(&[dir.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(o.status.code().is_some(), "extract crashed");
    let rows = read_angle_table(&out).unwrap();
    let t = truth(&dir);
    let err = |r: &ShotRow, v: Option<f64>, k: &str| abs_error(&t, r, v, k);
    let hook = rows.iter().find(|r| r.file == "shot_007.png").unwrap();
    assert_eq!(hook.status, Status::Ok, "{hook:#?}");
    assert!(hook.delta1_deg.is_none(), "{hook:#?}");
    assert!(
        hook.reason
            .contains("rolling line is clear of the other streaks for only 1.3 R"),
        "{hook:#?}"
    );
    assert!(err(hook, hook.psi_deg, "psi_deg") < 0.1, "{hook:#?}");
    assert!(err(hook, hook.theta1_deg, "theta1_deg") < 0.5, "{hook:#?}");
    let read: Vec<f64> = rows
        .iter()
        .filter(|r| r.delta1_deg.is_some())
        .map(|r| err(r, r.delta1_deg, "delta1_deg"))
        .collect();
    assert!(
        read.len() >= 4,
        "delta1 read on {} shots: {rows:#?}",
        read.len()
    );
    assert!(read.iter().all(|e| *e < 1.0), "delta1 errors {read:?}");
}

#[test]
fn realistic_tier_accuracy() {
    // Full size: at 1200×800 the realistic tier's psi uncertainty often exceeds the 1.5° below
    // which a shot is reported `ok` (vision::shot::PSI_RESOLVED_DEG).
    let (errs, rows) = accuracy("realistic", 12, 6, "2400x1600");
    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    assert!(ok >= 4, "ok {ok}/6: {rows:#?}");
    let m = |k: &str| median(errs[k].clone());
    // Measured 2026-11-23 (renderer with continuous rolling deceleration): 6/6 ok, psi 0.54°,
    // theta1 0.39°, theta2 0.43° (sigma ratios 1.1, 0.7, 1.0); two of the six have theta2 errors
    // of 0.75° at stated sigmas of 0.56° and 0.70°. On the 24 realistic shots of
    // docs/accuracy.sh the medians are psi 0.16°, theta1 0.15°, theta2 0.17°.
    assert!(m("psi") < 0.8, "psi median error {}", m("psi"));
    assert!(m("theta1") < 0.9, "theta1 median error {}", m("theta1"));
    assert!(m("theta2") < 0.9, "theta2 median error {}", m("theta2"));
    // Stated sigmas of psi and theta (`vision::shot::calibrated_sd`): the median |error| /
    // sigma of honest Gaussian errors is 0.67; measured 0.78 on these 18 angles (2026-11-24).
    // The bounds fail when the sigmas shrink or grow some threefold, which six shots can tell.
    assert!(
        (0.2..2.5).contains(&m("pull")),
        "median |error| / sigma {}",
        m("pull")
    );
}

#[test]
fn one_row_per_image_with_bad_files_shards_and_overlays() {
    let dir = scratch("batch");
    synth(&dir, "clean", 2, 5, &[]);
    std::fs::write(
        dir.join("corrupt.png"),
        b"\x89PNG\r\n\x1a\nthis is not a png at all",
    )
    .unwrap();
    std::fs::write(dir.join("empty.jpg"), b"").unwrap();
    image::RgbImage::new(300, 200)
        .save(dir.join("black.png"))
        .unwrap();
    image::RgbImage::new(1, 1)
        .save(dir.join("tiny.tif"))
        .unwrap();
    let out = dir.join("angles.parquet");
    let ov = dir.join("overlays");
    let o = extract(&[
        dir.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--overlays".as_ref(),
        ov.as_os_str(),
        "--jobs".as_ref(),
        "2".as_ref(),
    ]);
    // Error rows make the exit code 1, but the table is complete.
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let rows = read_angle_table(&out).unwrap();
    let by: HashMap<&str, &ShotRow> = rows.iter().map(|r| (r.file.as_str(), r)).collect();
    assert_eq!(rows.len(), 6, "{rows:#?}");
    assert_eq!(by["corrupt.png"].status, Status::Error);
    assert_eq!(by["empty.jpg"].status, Status::Error);
    assert!(
        by["empty.jpg"].reason.contains("empty"),
        "{}",
        by["empty.jpg"].reason
    );
    assert_eq!(by["tiny.tif"].status, Status::Error);
    assert_eq!(by["black.png"].status, Status::Declined);
    assert!(by["black.png"].psi_deg.is_none());
    for f in ["shot_001.png", "shot_002.png"] {
        assert_eq!(by[f].status, Status::Ok, "{f}: {}", by[f].reason);
        let pic = image::open(ov.join(f.replace(".png", "_overlay.png"))).unwrap();
        assert_eq!((pic.width(), pic.height()), (1200, 800));
    }
    // Shards 1/2 and 2/2 partition the images.
    let mut files = Vec::new();
    for k in ["1/2", "2/2"] {
        let so = dir.join(format!("shard{}.csv", &k[..1]));
        extract(&[
            dir.as_os_str(),
            "--out".as_ref(),
            so.as_os_str(),
            "--shard".as_ref(),
            k.as_ref(),
        ]);
        files.extend(read_angle_table(&so).unwrap().into_iter().map(|r| r.file));
    }
    files.sort();
    let mut all: Vec<String> = rows.iter().map(|r| r.file.clone()).collect();
    all.sort();
    assert_eq!(files, all);
    // Bad usage: exit code 2 with the flag named.
    let bad = extract(&[dir.as_os_str(), "--out".as_ref(), "x.txt".as_ref()]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--out"));
    let bad = extract(&[
        dir.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--shard".as_ref(),
        "3/2".as_ref(),
    ]);
    assert_eq!(bad.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plate_is_not_a_shot_and_is_used() {
    let dir = scratch("plate");
    // Grazing shots beyond 70° can leave an object-ball streak too short to read (declined with
    // the reason); this test is about the plate, so it keeps to ordinary shots.
    synth(&dir, "clean", 2, 7, &["--background", "--psi", "15:70"]);
    let out = dir.join("angles.csv");
    extract(&[dir.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    let rows = read_angle_table(&out).unwrap();
    assert_eq!(rows.len(), 2, "background.png must not be a row: {rows:#?}");
    assert!(rows.iter().all(|r| r.file.starts_with("shot_")));
    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    assert_eq!(ok, 2, "{rows:#?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A drawn cue ball at small psi comes back past the impact point and stops a few radii away:
/// a short, bright streak that the scene reading took for the incoming one when the real
/// incoming streak (fast, so faint) was not found, and psi came out 6.9° off at a stated 0.28°
/// (seed 8's mixed-spin set, shot_006: psi 7.4°, spin −0.8). An arriving ball fades away from
/// the impact point; this one brightens 17-fold per radius away from it, so the shot is declined
/// with the reason. Each shot draws from its own stream, so a folder of the first six shots holds
/// the same photo and plate (checked byte for byte).
#[test]
fn a_drawn_cue_balls_way_back_is_not_read_as_the_incoming_streak() {
    let dir = scratch("draw_back");
    synth(
        &dir,
        "clean",
        6,
        8,
        &[
            "--spin-modes",
            "mixed",
            "--background",
            "--size",
            "2400x1600",
        ],
    );
    keep_only(&dir, "shot_006.png");
    let out = dir.join("angles.csv");
    let o = extract(&[dir.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(o.status.code().is_some(), "extract crashed");
    let rows = read_angle_table(&out).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(rows.len(), 1, "{rows:#?}");
    assert_eq!(rows[0].status, Status::Declined, "{rows:#?}");
    assert!(
        rows[0]
            .reason
            .starts_with("the streak read as the incoming cue ball's comes to rest"),
        "{rows:#?}"
    );
}

/// A rolling cue ball at psi 13.5° (clean seed 101 shot_008, with its plate) leaves P at 42° and
/// stops about three radii away: its short path is not found as a streak, and no ball rests at
/// P. Until session 28 every such two-streak reading was declined ("the cue ball's path is
/// hidden"); the incoming line and the object ball's path place the impact without it, and the
/// row is read with `theta1` and `delta1` undefined and the reason. Measured 2026-11-27: psi
/// 13.500° ± 0.028° (true 13.454°), `theta2` 1.022° ± 0.026° (true 1.001°).
#[test]
fn a_shot_whose_cue_ball_path_is_not_found_reads_psi_and_theta2() {
    let (r, tr) = only_photo(
        "path_not_found",
        "clean",
        8,
        101,
        &["--background"],
        "shot_008.png",
    );
    assert!(r.reason.starts_with("cue ball's path not found"), "{r:#?}");
    assert_psi_theta2_without_cue_path(&r, &tr);
}

/// A stun shot at psi 11.4° (spin −0.08): the cue ball leaves P across the line of centres at
/// `v sin psi` and rolls to rest within about a radius of it, so the light at P shows a resting
/// ball. Until session 29 a ball resting at P above psi 3° was taken for a misreading and the
/// shot declined; within 12° of head-on such a reading is kept when it passes the checks of a
/// hidden path (psi's sigma, the streaks' light), with `theta1` and `delta1` undefined.
/// Measured 2026-11-27: psi 11.416° ± 0.040° (true 11.381°), `theta2` 0.851° ± 0.033° (true
/// 0.822°).
#[test]
fn a_stunned_cue_ball_resting_near_the_impact_is_read_without_its_path() {
    let (r, tr) = only_photo(
        "rest_near_p",
        "clean",
        16,
        905,
        &["--psi", "0:12", "--spin-modes", "mixed"],
        "shot_016.png",
    );
    let want = |k: &str| tr[k].parse::<f64>().unwrap();
    assert!(
        (want("psi_deg") - 11.381).abs() < 0.01 && want("spin").abs() < 0.1,
        "{tr:?}"
    );
    assert!(
        r.reason
            .starts_with("cue ball comes to rest near the impact"),
        "{r:#?}"
    );
    assert_psi_theta2_without_cue_path(&r, &tr);
}

/// A draw shot at psi 7.2° (spin −0.94): the cue ball's way back lies along the incoming streak
/// and is not found as a streak of its own, and no ball rests at P. Read as a two-streak shot
/// without the cue ball's path (session 28's rule), the way back's light pulls the incoming
/// line: on session 28's code psi 13.38° ± 0.16° (true 7.23°) and `theta2` −3.63° ± 0.09°
/// (true −0.78°), past the rules on psi (at least 12°, sigma at most 0.5°). The object ball's
/// streak has 0.16 of the incoming streak's light, where a ball leaving no faster than the cue
/// ball arrived has at least as much (`vision::shot::HIDDEN_PATH_LIGHT_MIN`, session 29): the
/// shot is declined with that reason.
#[test]
fn a_drawn_cue_balls_way_back_along_the_incoming_streak_is_not_read_as_a_hidden_path() {
    let (r, tr) = only_photo(
        "draw_way_back",
        "clean",
        15,
        904,
        &["--psi", "0:12", "--spin-modes", "mixed"],
        "shot_015.png",
    );
    let want = |k: &str| tr[k].parse::<f64>().unwrap();
    assert!(
        (want("psi_deg") - 7.232).abs() < 0.01 && want("spin") < -0.9,
        "{tr:?}"
    );
    assert_eq!(r.status, Status::Declined, "{r:#?}");
    assert!(
        r.reason
            .contains("the cue ball's way back probably lies along the incoming streak"),
        "{r:#?}"
    );
    let ratio: f64 = r
        .reason
        .split("streak has ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .expect("the light ratio in the reason");
    assert!(ratio < 0.25, "{r:#?}");
}

/// A stunned cue ball at psi 25–32° leaves P across the object ball's line and stops a few radii
/// away: its short streak lies wholly within the wide margin the scene reading keeps around the
/// other streaks, and was dropped (the shot declined as "only two streaks"; 4 of these 6 without
/// the narrow margin). Its samples clear of the narrow margin read it. Measured 2026-11-25 on
/// this set (seed 1): 6/6 ok, psi 0.004–0.029° off, theta2 0.011–0.028°, theta1 0.014–0.094°
/// but 0.73° at a stated 0.89° and 1.9° at 2.5° (rolling lines clear of the other streaks for
/// little more than R). Since session 26 (the joint fit's model choice weighs each group of
/// samples by its own noise scale) shot_001's cue ball path is a straight line from P, clear of
/// the other streaks for 2.8 R, and its theta1 (1.9° off at a stated 4.9° before) is reported
/// unresolved with that reason; the other five read as before.
#[test]
fn a_stunned_cue_balls_short_path_is_read() {
    let dir = scratch("stun_short");
    synth(
        &dir,
        "clean",
        6,
        1,
        &[
            "--psi",
            "25:32",
            "--spin=-0.1:0.0",
            "--background",
            "--size",
            "2400x1600",
        ],
    );
    let (errs, rows) = extract_errors(&dir, 6, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    assert_eq!(ok, 6, "{rows:#?}");
    // theta1 on every shot, or stated unresolved for the one reason a short path allows.
    let unresolved = rows
        .iter()
        .filter(|r| r.theta1_deg.is_none())
        .inspect(|r| {
            assert!(
                r.reason
                    .contains("too short to tell a straight path from P from a hidden slide"),
                "{r:#?}"
            )
        })
        .count();
    assert!(unresolved <= 1, "{rows:#?}");
    assert_eq!(errs["theta1"].len() + unresolved, 6, "{rows:#?}");
    for (k, bound) in [("psi", 0.1), ("theta2", 0.1)] {
        let worst = errs[k].iter().cloned().fold(0.0, f64::max);
        assert!(worst < bound, "{k} errors {:?}", errs[k]);
    }
    assert!(
        median(errs["theta1"].clone()) < 0.15,
        "{:?}",
        errs["theta1"]
    );
    // |error| / sigma of psi, theta1 and theta2: none beyond 3.
    let worst_pull = errs["pull"].iter().cloned().fold(0.0, f64::max);
    assert!(worst_pull < 3.0, "pulls {:?}", errs["pull"]);
}

/// At grazing incidence (psi 72–86°) the object ball leaves at `v cos psi` and stops within a
/// couple of radii: its waiting disc, the band it swept and its rest disc make one patch of light
/// and no streak, and such shots were declined as "no physical reading". The two discs are now
/// found (`vision::disc::companion`), each refined from its half facing away from the other, and
/// the object ball's path is the line between them. Measured 2026-11-25 on these 4 shots (seed
/// 77, with a plate): shots 1, 3 and 4 read that way (all three were declined before), psi
/// 0.019°, 0.52° and 0.14° off at stated 0.33°, 0.25° and 0.26°, theta2 0.10°, 0.55°, 0.12°.
#[test]
fn a_crept_object_ball_is_read_from_its_two_discs() {
    let dir = scratch("creep");
    synth(
        &dir,
        "clean",
        4,
        77,
        &["--psi", "72:86", "--background", "--size", "2400x1600"],
    );
    let (_, rows) = extract_errors(&dir, 4, &[]);
    let t = truth(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    let crept: Vec<&ShotRow> = rows
        .iter()
        .filter(|r| r.status == Status::Ok && r.reason.contains("object ball crept"))
        .collect();
    assert!(crept.len() >= 3, "{rows:#?}");
    for r in &crept {
        // Its path between the discs is a chord: not its start direction.
        assert!(r.delta2_deg.is_none(), "{r:?}");
        assert!(
            r.reason.contains("delta2 not resolved (a crept ball's"),
            "{r:?}"
        );
        assert_eq!(r.path_model2.as_deref(), Some("line"), "{r:?}");
        for (name, v, sd) in [
            ("psi", r.psi_deg, r.psi_err_deg),
            ("theta1", r.theta1_deg, r.theta1_err_deg),
            ("theta2", r.theta2_deg, r.theta2_err_deg),
        ] {
            let tv: f64 = t[&r.file][&format!("{name}_deg")].parse().unwrap();
            let (v, sd) = (v.expect("measured"), sd.expect("with its sigma"));
            assert!((v - tv).abs() < 0.8, "{name} {v} against {tv}: {r:?}");
            assert!(
                (v - tv).abs() < 3.0 * sd,
                "{name} {v} ± {sd} against {tv}: {r:?}"
            );
        }
    }
}

/// The row of `file` in `tier`'s seed `seed` folder of 24 (`extra` synth flags) at true psi
/// `psi_deg`, asserted `ok` from a crept object ball's reading, with psi, `theta1` and `theta2`
/// within 3 stated sigmas.
fn crept_ok_of_24(
    name: &str,
    tier: &str,
    seed: u64,
    extra: &[&str],
    file: &str,
    psi_deg: f64,
) -> ShotRow {
    let (r, t) = one_of_24_with(name, tier, seed, extra, file);
    assert!(
        (t[&r.file]["psi_deg"].parse::<f64>().unwrap() - psi_deg).abs() < 0.01,
        "{:?}",
        t[&r.file]
    );
    assert_ok_within_3_sigma(&r, &t, &["psi", "theta1", "theta2"]);
    assert!(
        r.reason.starts_with("the object ball crept"),
        "{}",
        r.reason
    );
    r
}

#[test]
fn a_crept_balls_sweep_tracked_as_a_streak_gives_way_to_its_two_discs() {
    // Grazing seed 77's shot_015 (clean, no plate, psi 80.58°): the object ball crept 1.4 R and
    // stopped. The walk from the waiting disc tracked its sweep and rest disc as a short streak,
    // and the three-streak reading with it cost less than the reading from the two discs; its
    // path fit then failed ("too few consistent centre-line points") and the photo was declined
    // until session 45. A streak wholly within the band around the discs' chord is now the
    // sweep, and the discs tell the ball's direction.
    crept_ok_of_24(
        "creep_sweep",
        "clean",
        77,
        &["--psi", "72:86"],
        "shot_015.png",
        80.583,
    );
}

#[test]
fn a_crept_ball_still_moving_at_the_exposures_end_is_read_from_its_bands_sides() {
    // Realistic seed 3610's shot_005 (billiard, psi 78.14°, a green object ball on blue
    // cloth): the object ball crept 2 R and was still moving when the exposure ended, so its
    // band ends in a soft cap with no rest disc, and the walk from the disc found no streak of
    // it clear of the cue ball's. The cap read as a disc 12 % small, and the photo was declined
    // ("no physical reading") until session 45. The band's sides now give its centre-line.
    let r = crept_ok_of_24(
        "moving_creep",
        "realistic",
        3610,
        &["--material", "mixed"],
        "shot_005.jpg",
        78.142,
    );
    assert!(r.reason.contains("still moving"), "{}", r.reason);
}

#[test]
fn a_turn_hidden_at_a_rubber_impact_is_not_read() {
    // The demo's rubber shot_019 (psi 16°): the cue ball turns 25° within 0.4 R of P, inside its
    // own light there. The unfiltered arc fit ends on a long shallow arc that follows the cloth's
    // blotches, and the high-passed refit from it on a 0.36 R arc turning 6°: delta1 read 57.4°
    // against a true 76.7° at a stated 0.47° (session 18). The rival turning 10° more, on the
    // filtered light, fitted better than that refit: the start tangent was not measured. Since
    // session 24 the arc fit stays within the first centre-line sample's bound, never reaches
    // that long arc, and its best arc turns within 0.1 R of P, inside the ball's own disc: the
    // start tangent is not measured, now because it is hidden.
    let dir = scratch("hidden_rubber_turn");
    synth(
        &dir,
        "clean",
        19,
        103,
        &[
            "--material",
            "rubber",
            "--psi",
            "5:80",
            "--size",
            "2400x1600",
        ],
    );
    let one = dir.join("one");
    std::fs::create_dir_all(&one).unwrap();
    for f in ["shot_019.png", "scene.toml", "truth.csv"] {
        std::fs::copy(dir.join(f), one.join(f)).unwrap();
    }
    let (_, rows) = extract_errors(&one, 1, &[]);
    let t = truth(&one);
    let shot = &rows[0];
    assert_eq!(shot.status, Status::Ok, "{shot:#?}");
    assert!(shot.delta1_deg.is_none(), "{shot:#?}");
    assert!(
        shot.reason.contains(
            "delta1 not resolved (the arc that best fits the light at the impact has a first leg"
        ) && shot.reason.contains("inside the cue ball's own disc there"),
        "{shot:#?}"
    );
    assert!(
        abs_error(&t, shot, shot.psi_deg, "psi_deg") < 0.15,
        "{shot:#?}"
    );
    assert!(
        abs_error(&t, shot, shot.theta1_deg, "theta1_deg") < 0.2,
        "{shot:#?}"
    );
    // The object ball's slide hides under its waiting disc (true delta2 2.64°, theta2 3.12°).
    // Read with its folder (the cloth texture from all its photos) it states no delta2: in the
    // demo's folder its path was a line from O, which until session 21 stated theta2's 3.10° as
    // delta2 at 0.07°; here it is a parabola whose start the profile cannot pin. Its theta2 is
    // measured.
    let (_, rows) = extract_errors(&dir, 19, &[]);
    let shot = rows.iter().find(|r| r.file == "shot_019.png").unwrap();
    assert_eq!(shot.status, Status::Ok, "{shot:#?}");
    assert!(shot.delta2_deg.is_none(), "{shot:#?}");
    assert!(shot.reason.contains("delta2 not resolved ("), "{shot:#?}");
    assert!(
        abs_error(&t, shot, shot.theta2_deg, "theta2_deg") < 3.0 * shot.theta2_err_deg.unwrap(),
        "{shot:#?}"
    );
}

#[test]
fn a_straight_cue_path_over_a_short_stretch_is_not_read() {
    // Near head-on clean seed 901's shot_013 (psi 8.6°, rolling): the cue ball's streak is clear
    // of the others for only 1.7 R, and the joint fit takes it for a straight path from P, whose
    // direction the hidden sliding arc's offset tilts. (Seed 202's clean shot_024, 0.9 R, read
    // 1.4° off at a stated 0.06° until session 19, was this test's photo until session 33's
    // cloth polynomial moved its walk: it is now declined, too few consistent centre-line
    // points.) Needs the folder's texture: 24 photos.
    let (shot, t) = one_of_24_with(
        "short_straight_cue",
        "clean",
        901,
        &["--psi", "0:12"],
        "shot_013.png",
    );
    let shot = &shot;
    assert_eq!(shot.status, Status::Ok, "{shot:#?}");
    assert!(shot.theta1_deg.is_none(), "{shot:#?}");
    assert!(
        shot.reason
            .contains("too short to tell a straight path from P from a hidden slide"),
        "{shot:#?}"
    );
    assert!(
        abs_error(&t, shot, shot.psi_deg, "psi_deg") < 0.1,
        "{shot:#?}"
    );
    assert!(
        abs_error(&t, shot, shot.theta2_deg, "theta2_deg") < 0.1,
        "{shot:#?}"
    );
}

#[test]
fn a_coloured_ball_resting_at_the_impact_point_is_seen() {
    // Realistic seed 404's shot_019 (psi 7°, stun, rubber): the white cue ball creeps to rest
    // 1.7 R from the coloured object ball's waiting disc. Read as the object ball's disc, it put
    // the coloured ball at P, where along the photo's mean ball colour its rim is only 0.28 of
    // the white disc's contrast, below the 0.3 of a resting ball: the streaks were read with
    // their roles swapped, psi 12° off at a stated 0.16°, theta2 24° off. Against the light of
    // the streak the reading calls its own (7.7 times it), it is a ball at rest, and a ball
    // resting at P at psi 19° is a misreading: declined. Since session 21 the swapped reading
    // is declined one step earlier, its time arrows telling neither ball from the other (−0.9 ±
    // 1.9 % per R). Needs the folder's texture: 24 photos.
    let (shot, _) = one_of_24("coloured_rest_at_p", "realistic", 404, "shot_019.jpg");
    let shot = &shot;
    assert_eq!(shot.status, Status::Declined, "{shot:#?}");
    assert!(
        shot.reason.contains("a ball rests at the impact point")
            || shot
                .reason
                .starts_with("cannot tell which resting ball is the object ball"),
        "{shot:#?}"
    );
    assert!(shot.theta2_deg.is_none(), "{shot:#?}");
}

#[test]
fn a_drawn_cue_ball_coming_back_beyond_150_degrees_is_read() {
    // Realistic seed 404's shot_016 (steel, psi 12.0°, spin -1.11): the drawn cue ball comes
    // back at theta1 153.3°, its streak clear of the incoming one. Until session 30 a reading
    // could give the cue ball's rolling line at most 150° from x (passed by a billiard draw
    // with `r = -1` below psi 19°), so the right assignment was never tried and the photo was
    // declined as ambiguous between two wrong ones; on near head-on realistic seed 906 the same
    // bound made shot_003 (psi 9.0°, theta1 159°) a misreading, psi 0.25° and theta1 23.7°.
    let (shot, t) = one_of_24("draw_beyond_150", "realistic", 404, "shot_016.jpg");
    let shot = &shot;
    let want = |k: &str| t[&shot.file][k].parse::<f64>().unwrap();
    assert!(
        want("theta1_deg") > 150.0 && want("spin") < -0.5,
        "{:?}",
        t[&shot.file]
    );
    assert_ok_within_3_sigma(shot, &t, &["psi", "theta1", "delta1", "theta2"]);
}

#[test]
fn a_faint_incoming_streak_is_told_the_cue_balls_by_its_own_colour() {
    // Realistic seed 707's shot_005 (steel, psi 35.5°): three clear streaks in a Y, the
    // incoming one found only along its length (a faint streak). Its colour, the mean along its
    // line on the coarse map, was the cloth's blotches as much as the white ball's
    // (`[0.77, -0.10, 0.63]`), 0.81 like the cue ball's outgoing streak, under the 0.9 the two
    // must share: no reading. Measured along its samples (axis minus flanks) it is 0.9998 like
    // it (session 30).
    let (shot, t) = one_of_24("faint_colour", "realistic", 707, "shot_005.jpg");
    let shot = &shot;
    assert_ok_within_3_sigma(shot, &t, &["psi", "theta1", "theta2"]);
}

#[test]
fn a_rolling_line_over_a_short_stretch_states_a_wider_sigma() {
    // Realistic seed 505's shot_013 (psi 15°, a drawn cue ball with English): the cue ball's
    // streak is clear of the others for only 1.7 R. Its rolling line, read as parabola+line,
    // was 2.6° off at a stated 0.66° (4 sigma); over stretches under 3 R such readings were 2.1
    // times their sigmas at the median, and the sigma now says so.
    let (shot, t) = one_of_24("short_span_sigma", "realistic", 505, "shot_013.jpg");
    let shot = &shot;
    assert_eq!(shot.status, Status::Ok, "{shot:#?}");
    let e = abs_error(&t, shot, shot.theta1_deg, "theta1_deg");
    let sd = shot.theta1_err_deg.unwrap();
    assert!(
        sd > 1.2 && e < 2.5 * sd,
        "theta1 {e}° off at {sd}°: {shot:#?}"
    );
}

#[test]
fn a_dark_object_ball_is_found_in_its_own_colour() {
    // Hard seed 101's shot_022 (psi 10°): a maroon object ball on a light cloth is darker than
    // the cloth along the photo's mean ball colour, so the disc search (brightest blob) found
    // none ("5.7 σ above the cloth"). Searched in every colour and read on its own, with all
    // three paths found, it is read: psi 10.59° ± 0.51° (true 10.15°), theta2 1.09° ± 0.47°
    // (0.76°). Needs the folder's texture: 24 photos.
    let (shot, t) = one_of_24("dark_object_ball", "hard", 101, "shot_022.jpg");
    let shot = &shot;
    assert_eq!(shot.status, Status::Ok, "{shot:#?}");
    for (v, sd, key) in [
        (shot.psi_deg, shot.psi_err_deg, "psi_deg"),
        (shot.theta2_deg, shot.theta2_err_deg, "theta2_deg"),
    ] {
        let e = abs_error(&t, shot, v, key);
        assert!(
            e < 2.0 * sd.unwrap() && e < 1.0,
            "{key} {e}° off: {shot:#?}"
        );
    }
}

#[test]
fn the_overlay_draws_the_arc_that_gives_delta1() {
    // Where `delta1` comes from the pixel fit of the sliding arc at P, the overlay draws that
    // arc and its start tangent: until session 24 it drew the joint fit's start tangent there,
    // mostly unresolved and tens of degrees from the number printed beside it (clean seed 101
    // shot_007: an arrow 40° off the stated 88.55°).
    use streakfit::vision::{AnalysisOptions, Cloth, analyse, image_io, overlay};
    let dir = scratch("overlay_arc");
    synth(&dir, "clean", 1, 7, &["--psi", "30:40", "--background"]);
    let img = image_io::load(&dir.join("shot_001.png")).unwrap();
    let plate = image_io::load(&dir.join("background.png")).unwrap();
    let plate = streakfit::vision::Plate::new(plate);
    let a = analyse(
        &img,
        Cloth::Plate(&plate),
        None,
        &AnalysisOptions::default(),
    );
    assert_eq!(a.status, Status::Ok, "{}", a.reason);
    let (arc, fit) = (
        a.arc.expect("delta1 from the arc fit"),
        a.fit.as_ref().unwrap(),
    );
    let wrap = |x: f64| {
        (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    let drawn = (a.mirror * wrap(arc.delta - fit.alpha())).to_degrees();
    let stated = a.delta1_deg.unwrap();
    assert!(
        (drawn - stated).abs() < 1e-9,
        "arrow {drawn}° against {stated}°"
    );
    // The arc's middle, in the arc's colour.
    let p = fit.impact();
    let c = (
        p.0 + arc.l0 * arc.delta.cos(),
        p.1 + arc.l0 * arc.delta.sin(),
    );
    let mid = (
        0.25 * p.0 + 0.5 * c.0 + 0.25 * arc.end.0,
        0.25 * p.1 + 0.5 * c.1 + 0.25 * arc.end.1,
    );
    let out = overlay::render(&img, &a, "test");
    let orange = (-2..=2).any(|dy| {
        (-2..=2).any(|dx| {
            let (x, y) = (mid.0.round() as i64 + dx, mid.1.round() as i64 + dy);
            out.get_pixel(x as u32, y as u32).0 == [255, 170, 0]
        })
    });
    assert!(orange, "no arc drawn at {mid:?}");
}

/// `streakfit bench KIND DIR FLAGS... OUT`, which must succeed: its standard output.
fn bench_ok(kind: &str, dir: &Path, flags: &[&str], out: &Path) -> String {
    let o = Command::new(bin())
        .args(["bench", kind])
        .arg(dir)
        .args(flags)
        .arg(out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    text
}

/// `bench stability` reads a folder as `extract` does: its decoded run's table is `extract`'s
/// (every column but `seconds`), each perturbed run gives a row per photo, and the summary counts
/// them. Three clean photos with their plate at 1200×800, one perturbation.
#[test]
fn the_stability_bench_reads_as_extract_does() {
    let dir = scratch("stability");
    synth(&dir, "clean", 3, 5, &["--background"]);
    let (_, rows) = extract_errors(&dir, 3, &[]);
    let out = dir.join("stability");
    let text = bench_ok("stability", &dir, &["--perturbations", "1", "--out"], &out);
    assert!(
        text.starts_with("3 photos, 3 perturbed analyses (each decoded value ± 1e-6"),
        "{text}"
    );
    assert!(text.contains("\ndecoded "), "{text}");
    let decoded = read_angle_table(out.join("run_0.csv")).unwrap();
    let mut want = rows;
    for r in want.iter_mut() {
        r.seconds = 0.0;
    }
    assert_eq!(decoded, want);
    let perturbed = read_angle_table(out.join("run_1.csv")).unwrap();
    assert_eq!(perturbed.len(), 3);
    assert!(!out.join("run_2.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bench stages` analyses a folder as `extract` does and splits each analysis into its stages:
/// one CSV row per photo with `extract`'s status, every stage's time non-negative and their sum
/// the analysis's whole time (no stage counted twice, none lost). Three clean photos with their
/// plate at 1200×800; a `.parquet` output is bad usage (exit 2).
#[test]
fn the_stages_bench_splits_each_analysis_into_stages_that_add_up() {
    let dir = scratch("stages");
    synth(&dir, "clean", 3, 5, &["--background"]);
    let (_, rows) = extract_errors(&dir, 3, &[]);
    let csv = dir.join("stages.csv");
    let text = bench_ok("stages", &dir, &["--out"], &csv);
    assert!(text.starts_with("3 photos, one thread"), "{text}");
    assert!(text.contains("\narc fit "), "{text}");
    assert!(text.contains("\nanalysis / decode: "), "{text}");
    let table = std::fs::read_to_string(&csv).unwrap();
    let mut lines = table.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&head[..4], &["file", "status", "decode_ms", "analysis_ms"]);
    for s in [
        "cloth_model",
        "discs",
        "streak_tracking",
        "joint_path_fit",
        "arc_fit",
    ] {
        assert!(head.contains(&s), "{head:?}");
    }
    let body: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(body.len(), 3);
    for (cells, row) in body.iter().zip(&rows) {
        assert_eq!(cells[0], row.file);
        assert_eq!(cells[1], row.status.as_str());
        let ms: Vec<f64> = cells[2..].iter().map(|c| c.parse().unwrap()).collect();
        assert!(ms.iter().all(|v| *v >= 0.0), "{cells:?}");
        let (analysis, stages) = (ms[1], ms[2..].iter().sum::<f64>());
        // The stages are booked from inside the analysis; the whole is timed around it.
        assert!(
            stages <= analysis + 0.01 && stages > 0.95 * analysis,
            "{stages} of {analysis}: {cells:?}"
        );
    }
    let bad = Command::new(bin())
        .args(["bench", "stages"])
        .arg(&dir)
        .arg("--out")
        .arg(dir.join("stages.parquet"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_resting_balls_read_by_the_only_story_the_streaks_tell() {
    // Near head-on realistic seed 929's shot_019 (steel, psi 6.50°, a stun shot): the cue ball
    // rests by the object ball's waiting disc, and the time arrows lean only weakly the right
    // way (+1.8 ± 4.5 % per R). Until session 41 the roles were swapped to try the other
    // resting ball as the object ball, and when that reading found no scene at all (only one
    // streak meets that ball) the shot was declined with that reading's reason. Now the first
    // reading, the only one that explains the streaks, stands where its arrows lean its way.
    ok_of_24(
        "only_story",
        929,
        NEAR_HEAD_ON_MIXED,
        "shot_019.jpg",
        6.50,
        "cue ball comes to rest near the impact (a stun or draw shot): delta1, theta1 \
         undefined; the roles of the two resting balls from the only reading that explains the \
         streaks (the object ball brightens +1.8 ± 4.5 % per R",
    );
}

/// Realistic seed 3602 shot_008 (billiard, psi 43.9°, a stun shot): read either way round, the
/// cue ball's two streaks leave the object ball's throw within 3° of each other, and until
/// session 42 the shot was declined ("cannot tell which ball is which"). The reverse story has
/// the cue ball arriving 2.4 times as bright near `P` as it leaves, which a ball that loses
/// speed at the impact cannot do: it is refused, and the right one is read.
#[test]
fn a_cue_ball_is_read_arriving_along_its_fainter_streak() {
    ok_of_24(
        "cue_light",
        3602,
        &["--material", "mixed"],
        "shot_008.jpg",
        43.888,
        "delta2 not resolved",
    );
}

#[test]
fn an_object_streak_must_have_its_waiting_discs_colour() {
    // Fresh realistic seed 707's shot_021 (rubber, psi 10.65°): a white cue ball and a coloured
    // object ball. Until session 31 it was read `ok` with psi 14.50° ± 0.69° and `theta2`
    // 23.1° for 2.0°: the streak taken for the object ball's leaves the disc in another colour
    // (likeness 0.61 to the disc's own, measured on an annulus that leaves the highlight out;
    // every right reading on 45 comparison tables is at 0.917 or more). One ball paints both.
    // Since session 40 a scene whose streaks give no reading is also tried without the cue
    // ball's path (two of its streaks); that reading, psi 22.4° ± 1.22°, is held to the checks
    // of a hidden path and refused as well.
    let (shot, t) = one_of_24("object_colour", "realistic", 707, "shot_021.jpg");
    assert_declined_photo(&shot, &t[&shot.file], 10.65);
    assert!(
        shot.reason.starts_with(
            "only two streaks and no ball at rest at the impact point: the cue ball's path is \
             not found, and psi = 22.4° ± 1.22° is too uncertain"
        ),
        "{}",
        shot.reason
    );
}

#[test]
fn a_drawn_cue_balls_incoming_streak_is_read_beyond_its_way_back() {
    // Near head-on realistic seed 934's shot_023 (rubber, psi 6.82°, a draw shot): the cue ball
    // comes back along its incoming streak and rests beside it, and the walk from the disc
    // follows its bright way back to that end. Until session 44 the shot was declined ("the
    // cue ball's way back probably lies along the incoming streak": the object ball's streak
    // held a fraction of its light). The incoming streak goes on beyond the resting ball, and
    // the shot is read on that part of it: psi and `theta2` right, the way back not measured.
    let (r, t) = one_of_24_with(
        "drawn_back",
        "realistic",
        934,
        NEAR_HEAD_ON_MIXED,
        "shot_023.jpg",
    );
    assert!(
        (t[&r.file]["psi_deg"].parse::<f64>().unwrap() - 6.822).abs() < 0.01,
        "{:?}",
        t[&r.file]
    );
    assert_ok_within_3_sigma(&r, &t, &["psi", "theta2"]);
    assert!(r.psi_err_deg.unwrap() < 0.2, "{r:#?}");
    assert_eq!((r.theta1_deg, r.delta1_deg), (None, None), "{r:#?}");
    assert!(
        r.reason
            .starts_with("cue ball drawn back along its incoming streak"),
        "{}",
        r.reason
    );
}

#[test]
fn a_two_streak_reading_with_light_but_no_ball_at_p_is_held_to_the_hidden_path_checks() {
    // Near head-on realistic seed 920's shot_019 (steel, psi 6.93°, a draw shot): the drawn cue
    // ball's short, bright way back is taken for the incoming streak, and its rounded end lights
    // `P` without the rim of a resting ball. Until session 31 the checks of a reading without
    // the cue ball's path (psi's sigma at most 0.5°, the object streak's light) held only where
    // `P` was dark, and this photo was `ok` at psi 30.15° ± 0.64° with the reason "cue ball's
    // path not found". Now every two-streak reading without a resting ball at `P` is held to
    // them. Since session 37 the light check comes before psi's uncertainty, and it names
    // what happened: the object ball's streak holds 0.09 of the "incoming" streak's light.
    let (r, t) = only_photo(
        "draw_back_as_incoming",
        "realistic",
        24,
        920,
        NEAR_HEAD_ON_MIXED,
        "shot_019.jpg",
    );
    assert_declined_photo(&r, &t, 6.93);
    assert!(
        r.reason
            .contains("the cue ball's way back probably lies along the incoming streak"),
        "{}",
        r.reason
    );
}

#[test]
fn a_reading_without_the_cue_balls_path_needs_psi_within_a_quarter_degree() {
    // Near head-on realistic seed 3702's shot_001 (rubber, psi 2.84°, a follow shot): the cue
    // ball, nearly stopped at `P` before it follows the object ball, leaves a white blob there
    // that is taken for the object ball's disc (the green object ball on green cloth is not
    // found). Until session 36 the reading passed the checks of a hidden path, `ok` at psi
    // 17.16° ± 0.40° (under the 0.5° bound then) with theta2 19.3° for 0.55°. Right readings
    // without the cue ball's path state psi to 0.22° or better on 80 synthetic sets (the demo
    // loses one right steel reading at 0.45°).
    let r = declined_of_24(
        "hidden_path_quarter_degree",
        3702,
        NEAR_HEAD_ON_MIXED,
        "shot_001.jpg",
        2.84,
    );
    assert!(
        r.reason
            .contains("too uncertain to read the shot without it (more than 0.25°)"),
        "{}",
        r.reason
    );
}

#[test]
fn a_disc_crossed_by_the_cue_balls_path_is_read_from_its_rims_circle() {
    // Near head-on realistic seed 3706's shot_024 (billiard, psi 11.96°, a follow shot): the
    // white cue ball rolls on over a third of the blue object ball's waiting place, on blue
    // cloth. The circle of every edge of that disc is 3.7 px off with its radius 6.7 px short,
    // and until session 37 the shot read `ok` at psi 13.74° ± 0.31° and theta2 2.72° for
    // 0.83°. The consensus of the rim's edges lies 11 px from it and reads psi 12.2° ± 0.20°.
    ok_of_24(
        "rim_circle",
        3706,
        NEAR_HEAD_ON_MIXED,
        "shot_024.jpg",
        11.96,
        "read from the circle of the object ball's rim alone",
    );
}

#[test]
fn a_cue_ball_drawn_back_to_rest_shows_which_resting_ball_it_is() {
    // Near head-on realistic seed 919's shot_020 (rubber, psi 4.05°, a draw shot): a white cue
    // ball drawn back to rest against the red object ball's disc. The first reading (right
    // roles) has the object ball brightening +7.7 ± 4.8 % per R more than the incoming streak,
    // short of 2 standard errors; the swapped one +6.1 ± 1.7 %. Until session 31 the swapped
    // reading stood (`ok` at psi 0.21°, the red ball taken for the cue ball); sessions 31–38
    // declined the shot, the swapped reading's arrows not beating the first one's. The light
    // beside the ball resting at `P` is 14 times its streak's farther on: it slowed down into
    // its disc, so it is the cue ball, and since session 39 the first reading stands.
    ok_of_24(
        "swapped_rest",
        919,
        NEAR_HEAD_ON_MIXED,
        "shot_020.jpg",
        4.05,
        "cue ball comes to rest near the impact",
    );
}

#[test]
fn a_faint_third_streak_that_fits_no_role_leaves_a_two_streak_reading() {
    // Near head-on realistic seed 918's shot_024 (billiard, psi 3.99°, a stun shot): the cue
    // ball stops against the object ball; besides the incoming and the object ball's streaks a
    // faint short streak (18 samples) is found, which is no way out of `P` for the cue ball. Until
    // session 40 no reading was tried without the cue ball's path when three streaks were
    // found, and the shot was declined ("no physical reading of the streaks"); it is now read
    // as the two streaks it has, with the checks of a two-streak reading (on the 100 sets: 19
    // rows gained, 18 of them right).
    ok_of_24(
        "third_streak",
        918,
        NEAR_HEAD_ON_MIXED,
        "shot_024.jpg",
        3.99,
        "cue ball comes to rest near the impact",
    );
}

#[test]
fn a_follow_shot_is_not_read_as_a_stun_shot() {
    // Near head-on realistic seed 924's shot_004 (billiard, psi 5.03°, follow r = 1.41): the
    // cue ball stops at `P` for a moment and then rolls after the object ball along its path.
    // Read as a stun shot (a ball resting at `P`), psi came out 10.9° ± 0.34°: the object
    // ball's streak holds both balls' light, 3.1 times the incoming streak's, where one ball
    // leaving a stopped cue ball paints at most 1.9 times (`REST_LIGHT_MAX` 2.5).
    let shot = declined_of_24(
        "follow_not_stun",
        924,
        NEAR_HEAD_ON_MIXED,
        "shot_004.jpg",
        5.03,
    );
    assert!(
        shot.reason
            .contains("the cue ball probably rolled on after it"),
        "{}",
        shot.reason
    );
}

#[test]
fn a_ball_with_a_slow_balls_light_beside_it_is_not_the_object_ball() {
    // Near head-on realistic seed 934's shot_018 (rubber, psi 2.42°, a draw shot): the white
    // cue ball stopped at `P` against the purple object ball and was drawn back 1 R to rest,
    // leaving a bright smear from `P` to its rest. A rubber ball's slide ends under its disc's
    // edge, so the time arrows do not tell the roles (the right reading: −1.9 ± 2.1 % per R),
    // and until session 39 the swapped reading stood on its own arrows: the smear's end at `P`
    // taken for the object ball, `ok` at psi 0.31° ± 0.25°. An object ball leaves at full
    // speed; the light beside that disc is seven times its streak's farther on, a ball that
    // came to rest. (The smear also pulls the circle at `P`, so the first reading cannot stand
    // on it either: the shot is declined.)
    let r = declined_of_24(
        "slow_light_beside",
        934,
        NEAR_HEAD_ON_MIXED,
        "shot_018.jpg",
        2.42,
    );
    assert!(
        r.reason.contains(
            "the one at the first reading's impact point, tried because the time arrows did not \
             tell, has a slow ball's light beside it"
        ),
        "{}",
        r.reason
    );
}

#[test]
fn the_incoming_line_is_not_measured_on_a_resting_cue_balls_light() {
    // Near head-on realistic seed 919's shot_019 (billiard, psi 0.86°, a draw shot): the white
    // cue ball was drawn back about 1.5 R and stopped, and its faint incoming streak was not
    // found beyond that light. Until session 32 the 21 incoming samples, all in the resting
    // ball's light 0–2 R from `P`, gave the incoming line: `ok` at psi 2.36° ± 0.24°. Samples
    // there measure where the ball came to rest; the line must come from the streak beyond.
    let shot = declined_of_24("rest_light", 919, NEAR_HEAD_ON_MIXED, "shot_019.jpg", 0.86);
    assert!(
        shot.reason
            .contains("its incoming streak is not found beyond 2.5 R"),
        "{}",
        shot.reason
    );
}

#[test]
fn a_cue_ball_resting_at_p_is_seen_in_its_own_colour() {
    // Near head-on realistic seed 911's shot_003 (rubber, psi 6.12°, a stun shot): the white cue
    // ball rests against the purple object ball's disc. The reading took the white ball for the
    // object ball, and so the purple disc for the cue ball resting at `P`. On the photo's mean
    // colour that disc is faint, so no ball was seen resting there, and the shot was read as one
    // whose cue-ball path is hidden: `ok` at psi 12.19° ± 0.33°, `theta2` 17.4° for 0.9°. In the
    // incoming streak's own colour the disc's rim is 8.8 times the streak's light (3 marks a
    // resting ball; hidden paths at −1.1 to 2.0 on 45 tables, session 31). Seen, the two resting
    // balls go to the time arrows, which cannot tell them apart here.
    let shot = declined_of_24(
        "cue_colour_rest",
        911,
        NEAR_HEAD_ON_MIXED,
        "shot_003.jpg",
        6.12,
    );
    assert!(
        shot.reason
            .starts_with("cannot tell which resting ball is the object ball"),
        "{}",
        shot.reason
    );
}

#[test]
fn a_fainter_disc_next_to_a_brighter_one_is_not_read_as_the_object_balls() {
    // Near head-on realistic seed 908's shot_017 (steel, psi 6.39°, a stun shot): the brighter
    // disc is the waiting object ball's, and its reading is refused (no physical assignment of
    // the streaks). Until session 31 the next candidate, the cue ball at rest 1.9 R away with
    // 0.74 of that contrast, then gave a three-streak reading `ok` at psi 0.16° ± 0.28°,
    // `theta2` 5.35° for 1.37°, leaving the brighter disc unexplained.
    let shot = declined_of_24(
        "brighter_near",
        908,
        &["--psi", "0:12"],
        "shot_017.jpg",
        6.39,
    );
    assert!(
        shot.reason
            .starts_with("the streaks read only around a fainter disc"),
        "{}",
        shot.reason
    );
}

/// Clean seed 202 shot_022 (billiard, psi 6.63°, a rolling cue ball): the cue ball follows the
/// object ball within `2R` of its streak, and no path of its own is found. Until session 42 every
/// such reading below 12° was declined ("near head-on shot ... and the cue ball's path not
/// found"); the object ball's path is straight, as an object ball's is after a near head-on
/// impact, so the reading stands without the cue ball's path (`theta1`, `delta1` undefined).
/// Measured 2026-11-28, the photo alone (no texture map): psi 6.642° ± 0.121° (true 6.631°),
/// `theta2` 0.506° ± 0.098° (true 0.498°); in its folder of 24, 6.620° ± 0.028°.
#[test]
fn a_near_head_on_follow_shot_is_read_without_the_cue_balls_path() {
    let (r, tr) = only_photo("follow_hidden", "clean", 22, 202, &[], "shot_022.png");
    assert_eq!(r.status, Status::Ok, "{r:#?}");
    assert!(r.reason.starts_with("cue ball's path not found"), "{r:#?}");
    assert_eq!((r.theta1_deg, r.delta1_deg), (None, None), "{r:#?}");
    for (v, sd, key) in [
        (r.psi_deg, r.psi_err_deg, "psi_deg"),
        (r.theta2_deg, r.theta2_err_deg, "theta2_deg"),
    ] {
        let (v, sd) = (v.unwrap(), sd.unwrap());
        let e = (v - tr[key].parse::<f64>().unwrap()).abs();
        assert!(e < 3.0 * sd && sd < 0.2, "{key}: {e}° off at {sd}°: {r:#?}");
    }
}

/// Near head-on, where the cue ball's path is hidden in the streaks, a curve in the path read
/// as the object ball's is the cue ball's: an object ball leaves a near head-on impact nearly
/// straight (within 0.6° for steel's friction,
/// `near_head_on_an_object_ball_leaves_straight_and_a_cue_ball_turns`), a cue ball slides on a
/// parabola. Near head-on realistic seed 3702 shot_012 (steel, psi 1.02°, a follow shot): read
/// without the rule (the photo alone), `theta2` is 4.56° ± 0.13° for 0.22°, the followed cue
/// ball's `theta1`.
#[test]
fn a_curved_object_path_near_head_on_is_the_hidden_cue_balls() {
    let (r, t) = only_photo(
        "object_path_curves",
        "realistic",
        12,
        3702,
        NEAR_HEAD_ON_MIXED,
        "shot_012.jpg",
    );
    assert_declined_photo(&r, &t, 1.017);
    assert!(
        r.reason.contains("the object ball's path curves"),
        "{}",
        r.reason
    );
}
