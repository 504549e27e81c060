//! `streakfit bench speed-error`: what each unit of speed costs in accuracy; `streakfit bench
//! psi-bound`: the best accuracy of `psi` that synthetic photos allow ([`crate::synth::bound`]);
//! `streakfit bench stability`: the extractor's decision noise ([`stability`]); `streakfit bench
//! stages`: where the extractor's time goes, stage by stage ([`stages`]).
//!
//! On a pinned (seeded) synthetic set with ground truth, every cost knob of a stage is swept and
//! each setting's seconds per item and angle errors are recorded:
//! - `extract`: the extractor's knobs ([`crate::vision::AnalysisOptions::speed_settings`]), seconds
//!   per image (decode excluded, one thread) against |error| of the angles that the default
//!   setting measures, an angle a setting leaves unmeasured counting as infinitely wrong: the
//!   `median_err_deg` and `p90_err_deg` of this stage are the means over `psi, delta1, delta2,
//!   theta1, theta2` of each angle's median and 90th percentile (angles with at least
//!   [`MIN_ANGLE_READINGS`] readings), and `median_err_sd_deg` the former's sampling noise
//!   (bootstrap over the images);
//! - `theory`: closed forms against the impulse model (the reference), seconds per evaluation;
//! - `fit`: seconds per fit of `n` shots against |e - e_true|, known and estimated spin.
//!
//! Writes `OUT/speed_error.csv` (`stage, setting, is_default, seconds_per_item, median_err_deg,
//! median_err_sd_deg, p90_err_deg, ok_fraction, n_items, on_pareto_front`) and a Pareto plot
//! `OUT/pareto.png|svg` (time against median error per stage, default marked).

pub mod stability;
pub mod stages;

use crate::cli::{CliError, CliResult, Outcome};
use crate::physics::{Coefficients, RegimeChoice, Shot, closed, impulse};
use anyhow::{Context, Result, anyhow};
use clap::{Args, Subcommand};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Args, Clone)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub kind: BenchKind,
}

#[derive(Debug, Subcommand, Clone)]
pub enum BenchKind {
    /// Sweep the cost knobs of extraction, theory and fit; write speed_error.csv and a Pareto plot.
    SpeedError(SpeedErrorArgs),
    /// The Cramér–Rao bound of psi for the photos that `synth` writes with the same flags:
    /// OUT/psi_bound.csv and a summary (no photo is written).
    PsiBound(PsiBoundArgs),
    /// How far the extractor's readings move when its input moves far less than the sensor's
    /// noise: status, path-model and angle changes, and misreadings per run against truth.csv.
    Stability(stability::StabilityArgs),
    /// Where the extractor's time goes: each photo decoded and analysed on one thread, the
    /// analysis split into its stages' exclusive times (mean ms per photo and share).
    Stages(stages::StagesArgs),
}

#[derive(Debug, Args, Clone)]
pub struct PsiBoundArgs {
    #[command(flatten)]
    pub synth: crate::synth::SynthArgs,
    /// Leave out the pixels within this many ball radii of the impact point (but for the
    /// waiting disc's): the bound of a reading that cannot use the streaks' light where they
    /// overlap there. A comma-separated list gives one bound per radius and a figure.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub blind_r: Vec<f64>,
    /// The extraction table of these photos (`streakfit extract DIR --out FILE`): its psi
    /// errors are compared with the bounds and drawn in the figure.
    #[arg(long)]
    pub table: Option<PathBuf>,
    /// Whether the outgoing paths move with `P` and `O` (their light helps to place them) or
    /// are held (only the incoming streak and the waiting disc do).
    #[arg(long, value_enum, default_value_t = crate::synth::bound::Outgoing::Attached)]
    pub outgoing: crate::synth::bound::Outgoing,
}

#[derive(Debug, Args, Clone)]
pub struct SpeedErrorArgs {
    /// Output folder (the synthetic set is cached under it).
    #[arg(long, default_value = "reports/bench")]
    pub out: PathBuf,
    /// Shots in the pinned synthetic photo set.
    #[arg(long, default_value_t = 24)]
    pub shots: usize,
    /// Seed of the pinned set.
    #[arg(long, default_value_t = 2026)]
    pub seed: u64,
    /// Tier of the pinned set (clean, realistic or hard).
    #[arg(long, default_value = "realistic")]
    pub tier: String,
    /// Stages to run (comma-separated subset of extract,theory,fit).
    #[arg(long, default_value = "extract,theory,fit")]
    pub stages: String,
    /// Only redraw the plot from OUT/speed_error.csv (no measurement).
    #[arg(long)]
    pub replot: bool,
}

/// One row of `speed_error.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchRow {
    pub stage: String,
    pub setting: String,
    pub is_default: bool,
    pub seconds_per_item: f64,
    pub median_err_deg: f64,
    /// Sampling noise of `median_err_deg` (bootstrap over the items; 0 where the items are
    /// not a sample, as for the theory's exact comparison).
    pub median_err_sd: f64,
    pub p90_err_deg: f64,
    pub ok_fraction: f64,
    /// Share of the default setting's readings (every angle it measures, over the photos) that
    /// this setting measures too: 1 for the default and for stages without angles. A setting
    /// that drops a reading the score is too sparse to rate (the realistic set's few `delta1`
    /// values without the arc fit) measures less, and cannot beat one that keeps it.
    pub coverage: f64,
    pub n_items: usize,
    pub on_pareto_front: bool,
}

/// Quantile `q` of `v` (linear interpolation); NaN for an empty slice.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < s.len() && f > 0.0 && s[i + 1].is_finite() {
        s[i] * (1.0 - f) + s[i + 1] * f
    } else if i + 1 < s.len() && f > 0.0 {
        // Interpolating towards a lost angle (infinite error) is infinite.
        f64::INFINITY
    } else {
        s[i]
    }
}

/// Standard deviation of `stat` when the items are resampled with replacement (`n` bootstrap
/// draws, seeded): the sampling noise of the statistic itself. Infinite when most draws give an
/// infinite statistic, NaN when most give none (too few readings in a resample).
pub fn bootstrap_sd<T>(items: &[T], n: usize, seed: u64, stat: impl Fn(&[&T]) -> f64) -> f64 {
    if items.is_empty() {
        return f64::NAN;
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let draws: Vec<f64> = (0..n)
        .map(|_| {
            let draw: Vec<&T> = (0..items.len())
                .map(|_| &items[rng.gen_range(0..items.len())])
                .collect();
            stat(&draw)
        })
        .collect();
    let vals: Vec<f64> = draws.iter().copied().filter(|v| v.is_finite()).collect();
    if vals.len() < n / 2 {
        let infinite = draws.iter().filter(|v| v.is_infinite()).count();
        return if infinite >= n / 2 {
            f64::INFINITY
        } else {
            f64::NAN
        };
    }
    let mean = vals.iter().sum::<f64>() / vals.len() as f64;
    (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (vals.len() - 1).max(1) as f64).sqrt()
}

/// One image's errors of `psi, delta1, delta2, theta1, theta2` (`None`: not a reference angle,
/// infinite: a reference angle the setting did not measure).
type AngleErrors = [Option<f64>; 5];

/// Fewest reference readings of an angle for its quantile to enter [`angle_score`]: the object
/// ball's `delta2` is measured on two or three photos of a realistic set, too few for a median
/// that means anything (one lost reading made it infinite, one resampling dropped it). A set
/// with fewer measured photos than this has no extraction score (NaN).
pub const MIN_ANGLE_READINGS: usize = 5;

/// The angles (indices into [`AngleErrors`]) with at least [`MIN_ANGLE_READINGS`] readings.
pub fn scored_angles(images: &[&AngleErrors]) -> Vec<usize> {
    (0..5)
        .filter(|&k| images.iter().filter(|a| a[k].is_some()).count() >= MIN_ANGLE_READINGS)
        .collect()
}

/// The mean over the angles `kinds` (of `psi, delta1, delta2, theta1, theta2`) of each angle's
/// `q`-quantile of |error| over the images: each angle weighs the same however many images
/// measure it (pooled, psi and theta, three fifths of the readings and the most accurate, hid
/// what a knob did to `delta1`). NaN when an angle has no reading (a bootstrap draw without
/// it).
pub fn angle_score(images: &[&AngleErrors], kinds: &[usize], q: f64) -> f64 {
    if kinds.is_empty() {
        return f64::NAN;
    }
    kinds
        .iter()
        .map(|&k| {
            let e: Vec<f64> = images.iter().filter_map(|a| a[k]).collect();
            quantile(&e, q)
        })
        .sum::<f64>()
        / kinds.len() as f64
}

/// Relative differences of seconds per item below this are timing noise: repeated runs of the
/// same extractor setting on this 2-core machine differ by 5–20 %.
pub const TIME_TOLERANCE: f64 = 0.05;
/// Relative differences of median error below this are not an improvement (the theory's and
/// the fit's comparisons; the extraction's medians come with their own sampling noise).
pub const ERROR_TOLERANCE: f64 = 0.01;
/// Bootstrap draws for the sampling noise of a median error.
pub const BOOTSTRAP_DRAWS: usize = 400;

/// Marks the rows of each stage that no other row of the stage beats. A row beats another if it
/// measures at least as many items and is clearly faster (by more than [`TIME_TOLERANCE`]) and not
/// less accurate, or clearly more accurate (by more than [`ERROR_TOLERANCE`] and the two
/// medians' combined sampling noise) and not clearly slower: ε-dominance, so that timing or
/// sampling noise alone moves no setting off the front.
pub fn mark_pareto(rows: &mut [BenchRow]) {
    let snapshot = rows.to_vec();
    let beats = |o: &BenchRow, r: &BenchRow| {
        let faster = o.seconds_per_item < r.seconds_per_item * (1.0 - TIME_TOLERANCE);
        let not_slower = o.seconds_per_item <= r.seconds_per_item * (1.0 + TIME_TOLERANCE);
        // A difference of medians within their combined sampling noise is no difference.
        let noise = o.median_err_sd.hypot(r.median_err_sd);
        let noise = if noise.is_finite() { noise } else { 0.0 };
        let more_accurate = o.median_err_deg < r.median_err_deg * (1.0 - ERROR_TOLERANCE) - noise;
        let not_less_accurate = o.median_err_deg <= r.median_err_deg + noise;
        (faster && not_less_accurate) || (more_accurate && not_slower)
    };
    for r in rows.iter_mut() {
        r.on_pareto_front = r.median_err_deg.is_finite()
            && !snapshot.iter().any(|o| {
                o.stage == r.stage
                    && o.median_err_deg.is_finite()
                    && o.ok_fraction >= r.ok_fraction
                    && o.coverage >= r.coverage
                    && beats(o, r)
            });
    }
}

/// Theory stage: closed forms vs the impulse model on random shots, auto regime.
pub fn theory_rows(n: usize, seed: u64) -> Vec<BenchRow> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let set: Vec<(Shot, Coefficients)> = (0..n)
        .map(|_| {
            let mu = rng.gen_range(0.02..0.7);
            (
                Shot {
                    psi: rng.gen_range(0.0..1.5),
                    mass_ratio: 1.0,
                    spin: rng.gen_range(-2.0..2.0),
                    english: rng.gen_range(-0.5..0.5),
                },
                Coefficients::new(rng.gen_range(0.5..1.0), mu, rng.gen_range(0.0..0.6))
                    .with_static(mu * 1.2),
            )
        })
        .collect();
    let reference: Vec<_> = set
        .iter()
        .map(|(s, c)| impulse::solve(s, c, RegimeChoice::Auto).angles())
        .collect();
    let time = |f: &dyn Fn(&Shot, &Coefficients) -> crate::physics::ShotAngles| {
        // Best of five passes: the machine's other load only ever adds time.
        (0..5)
            .map(|_| {
                let t = Instant::now();
                for (s, c) in &set {
                    std::hint::black_box(f(s, c));
                }
                t.elapsed().as_secs_f64() / set.len() as f64
            })
            .fold(f64::INFINITY, f64::min)
    };
    let closed_fn = |s: &Shot, c: &Coefficients| closed::predict_auto(s, c).1;
    let impulse_fn = |s: &Shot, c: &Coefficients| impulse::solve(s, c, RegimeChoice::Auto).angles();
    let errs = |f: &dyn Fn(&Shot, &Coefficients) -> crate::physics::ShotAngles| -> Vec<f64> {
        set.iter()
            .zip(&reference)
            .flat_map(|((s, c), r)| {
                f(s, c)
                    .as_array()
                    .into_iter()
                    .zip(r.as_array())
                    .filter_map(|(a, b)| Some((a? - b?).to_degrees().abs()))
                    .collect::<Vec<_>>()
            })
            .collect()
    };
    let mut out = Vec::new();
    for (name, f, default) in [
        (
            "closed-form",
            &closed_fn as &dyn Fn(&Shot, &Coefficients) -> _,
            true,
        ),
        (
            "impulse-model",
            &impulse_fn as &dyn Fn(&Shot, &Coefficients) -> _,
            false,
        ),
    ] {
        let e = errs(f);
        out.push(BenchRow {
            stage: "theory".into(),
            setting: name.into(),
            is_default: default,
            seconds_per_item: time(f),
            median_err_deg: quantile(&e, 0.5),
            median_err_sd: 0.0,
            p90_err_deg: quantile(&e, 0.9),
            ok_fraction: 1.0,
            coverage: 1.0,
            n_items: n,
            on_pareto_front: false,
        });
    }
    out
}

/// Fit stage: billiard-ball synthetic tables (0.3° noise) of growing size, known and estimated
/// spin; error is |e - e_true| in units of degrees' stand-in (the absolute error of `e` × 100
/// would mix units, so the column holds |e - e_true| itself, noted in the setting name).
pub fn fit_rows(seed: u64) -> Result<Vec<BenchRow>> {
    use crate::fit::synthetic::{SyntheticSpec, SyntheticSpin, synthetic_table};
    use crate::fit::{FitOptions, SpinMode, fit_materials};
    let truth = Coefficients::new(0.97, 0.07, 0.15);
    let mut out = Vec::new();
    for (spin_name, spin, mode) in [
        ("known-spin", SyntheticSpin::Rolling, SpinMode::Known),
        (
            "estimated-spin",
            SyntheticSpin::Mixed {
                r_lo: -1.0,
                r_hi: 1.5,
                s_max: 0.3,
                write: false,
            },
            SpinMode::Estimate,
        ),
    ] {
        for n in [30usize, 100, 300, 1000] {
            let mut errs = Vec::new();
            let mut secs = f64::INFINITY;
            for rep in 0..3u64 {
                let spec = SyntheticSpec {
                    material: "billiard".into(),
                    coefficients: truth,
                    n,
                    psi_lo_deg: 10.0,
                    psi_hi_deg: 70.0,
                    noise_deg: 0.3,
                    spin,
                    seed: seed + rep,
                };
                let (rows, _) = synthetic_table(&spec);
                let opts = FitOptions {
                    spin: mode,
                    bootstrap: 0,
                    ..FitOptions::default()
                };
                let t = Instant::now();
                let fit = fit_materials(&rows, &opts)?;
                secs = secs.min(t.elapsed().as_secs_f64());
                let e = fit
                    .fits
                    .first()
                    .and_then(|f| f.e)
                    .ok_or_else(|| anyhow!("fit returned no e"))?;
                errs.push((e - truth.e).abs());
            }
            out.push(BenchRow {
                stage: "fit".into(),
                setting: format!("{spin_name} n={n} (error = |e - e_true|)"),
                is_default: n == 30 && mode == SpinMode::Known,
                seconds_per_item: secs,
                median_err_deg: quantile(&errs, 0.5),
                median_err_sd: bootstrap_sd(&errs, BOOTSTRAP_DRAWS, seed, |d| {
                    quantile(&d.iter().map(|e| **e).collect::<Vec<_>>(), 0.5)
                }),
                p90_err_deg: quantile(&errs, 0.9),
                ok_fraction: 1.0,
                coverage: 1.0,
                n_items: n,
                on_pareto_front: false,
            });
        }
    }
    Ok(out)
}

/// The extractor's cost settings swept by the bench: `(name, options, is_default)`.
pub fn extract_settings() -> Vec<(String, crate::vision::AnalysisOptions, bool)> {
    crate::vision::AnalysisOptions::speed_settings()
}

/// Makes (or reuses) the pinned synthetic set `OUT/set_TIER_SEED_SHOTS`.
fn pinned_set(out: &Path, shots: usize, seed: u64, tier: &str) -> Result<PathBuf> {
    use clap::ValueEnum;
    let t = crate::synth::Tier::from_str(tier, true).map_err(|e| anyhow!("--tier: {e}"))?;
    let dir = out.join(format!("set_{tier}_{seed}_{shots}"));
    if !dir.join("truth.csv").exists() {
        let args = crate::synth::SynthArgs::new(&dir, t, shots, seed);
        crate::synth::run(&args).map_err(|e| anyhow!("synth for the bench: {e}"))?;
    }
    Ok(dir)
}

/// Extraction stage: every setting of [`extract_settings`] on the pinned set, one thread,
/// decode excluded; errors pooled over `psi, delta1, delta2, theta1, theta2` of `ok` rows.
pub fn extract_rows(out: &Path, shots: usize, seed: u64, tier: &str) -> Result<Vec<BenchRow>> {
    use crate::vision::{Cloth, analyse, image_io};
    let dir = pinned_set(out, shots, seed, tier)?;
    let truth_text = std::fs::read_to_string(dir.join("truth.csv"))?;
    let truth =
        crate::synth::truth::read_csv(&truth_text).map_err(|e| anyhow!("truth.csv: {e}"))?;
    let jobs = crate::extract::list_jobs(std::slice::from_ref(&dir)).map_err(|e| anyhow!("{e}"))?;
    // As `extract` does: the folder's cloth texture for photos without a plate (estimated once
    // per folder, outside the per-image times).
    let side = crate::vision::AnalysisOptions::default().coarse_side;
    let textures = crate::extract::folder_textures(&jobs, &jobs, side, false);
    // Each plate decoded once and shared by its photos, its block means with it.
    let plates = crate::extract::decode_plates(&jobs);
    let mut images = Vec::new();
    for j in &jobs {
        let img = image_io::load(&j.path).map_err(|e| anyhow!("{}: {e}", j.path.display()))?;
        let plate = match j.plate.as_ref().and_then(|p| plates.get(p)) {
            Some(p) => Some(p.clone().map_err(|e| anyhow!("{e}"))?),
            None => None,
        };
        let texture = textures
            .get(&crate::extract::folder_of(j))
            .filter(|_| plate.is_none())
            .cloned();
        let t = truth
            .iter()
            .find(|r| r.get("file") == Some(&j.file))
            .ok_or_else(|| anyhow!("{} has no truth row", j.file))?;
        images.push((img, plate, texture, j.scene.ball_radius_px_cloth(), t));
    }
    let angle = |a: f64, b: f64| ((a - b + 180.0).rem_euclid(360.0) - 180.0).abs();
    const KEYS: [&str; 5] = [
        "psi_deg",
        "delta1_deg",
        "delta2_deg",
        "theta1_deg",
        "theta2_deg",
    ];
    // The default is measured first and again last (the best time kept), so warm-up of the
    // machine does not count against the setting every other one is compared with.
    let mut settings = extract_settings();
    if let Some(d) = settings.iter().find(|s| s.2).cloned() {
        settings.push(d);
    }
    // Per setting: seconds per image, `ok` count and each image's five readings.
    struct Run {
        name: String,
        is_default: bool,
        secs_per_item: f64,
        ok: usize,
        /// `psi, delta1, delta2, theta1, theta2` per image (None: not measured).
        readings: Vec<[Option<f64>; 5]>,
    }
    let mut runs: Vec<Run> = Vec::new();
    for (name, opts, is_default) in settings {
        let (mut ok, mut secs, mut readings) = (0usize, 0.0, Vec::new());
        for (img, plate, texture, scale_r, _) in &images {
            // Best of three runs: other load on the machine only ever adds time; the analysis
            // is deterministic, so every run gives the same numbers.
            let mut best = f64::INFINITY;
            let mut a = None;
            for _ in 0..3 {
                let start = Instant::now();
                let cloth = Cloth::of(plate.as_deref(), texture.as_deref());
                let r = analyse(img, cloth, *scale_r, &opts);
                best = best.min(start.elapsed().as_secs_f64());
                a = Some(r);
            }
            secs += best;
            let a = a.expect("three runs");
            let is_ok = a.status == crate::table::Status::Ok;
            ok += usize::from(is_ok);
            readings.push(if is_ok {
                [
                    a.psi_deg,
                    a.delta1_deg,
                    a.delta2_deg,
                    a.theta1_deg,
                    a.theta2_deg,
                ]
            } else {
                [None; 5]
            });
        }
        let secs_per_item = secs / images.len().max(1) as f64;
        if let Some(prev) = runs.iter_mut().find(|r| r.name == name) {
            prev.secs_per_item = prev.secs_per_item.min(secs_per_item);
            continue;
        }
        runs.push(Run {
            name,
            is_default,
            secs_per_item,
            ok,
            readings,
        });
    }
    // The angles the default measures (and the truth defines) are the reference: a setting is
    // scored on those, and one it does not measure counts as lost (infinite error). Scoring
    // whatever each setting reports instead let a setting that leaves the hardest angle
    // unmeasured look more accurate (without the arc fit, delta1 is mostly unresolved).
    let truth_of =
        |i: usize, k: usize| images[i].4.get(KEYS[k]).and_then(|v| v.parse::<f64>().ok());
    let reference: Vec<Vec<usize>> = runs
        .iter()
        .find(|r| r.is_default)
        .map(|d| {
            (0..images.len())
                .map(|i| {
                    (0..5)
                        .filter(|&k| d.readings[i][k].is_some() && truth_of(i, k).is_some())
                        .collect()
                })
                .collect()
        })
        .ok_or_else(|| anyhow!("no default extraction setting"))?;
    let mut rows = Vec::new();
    for run in runs {
        let per_image: Vec<AngleErrors> = reference
            .iter()
            .enumerate()
            .map(|(i, ks)| {
                let mut e = [None; 5];
                for &k in ks {
                    e[k] = Some(match (run.readings[i][k], truth_of(i, k)) {
                        (Some(m), Some(t)) => angle(m, t),
                        _ => f64::INFINITY,
                    });
                }
                e
            })
            .collect();
        let all: Vec<&AngleErrors> = per_image.iter().collect();
        let (kept, of) = per_image
            .iter()
            .flatten()
            .flatten()
            .fold((0, 0), |(k, n), e| (k + usize::from(e.is_finite()), n + 1));
        // The same angles for every setting and every resample: those the default measures
        // often enough.
        let kinds = scored_angles(&all);
        rows.push(BenchRow {
            stage: "extract".into(),
            setting: run.name,
            is_default: run.is_default,
            seconds_per_item: run.secs_per_item,
            median_err_deg: angle_score(&all, &kinds, 0.5),
            median_err_sd: bootstrap_sd(&per_image, BOOTSTRAP_DRAWS, seed, |d| {
                angle_score(d, &kinds, 0.5)
            }),
            p90_err_deg: angle_score(&all, &kinds, 0.9),
            ok_fraction: run.ok as f64 / images.len().max(1) as f64,
            coverage: if of == 0 {
                1.0
            } else {
                kept as f64 / of as f64
            },
            n_items: images.len(),
            on_pareto_front: false,
        });
    }
    Ok(rows)
}

/// Writes the rows as CSV through polars, atomically.
pub fn write_csv(rows: &[BenchRow], path: &Path) -> Result<()> {
    use polars::prelude::*;
    let mut df = DataFrame::new(
        rows.len(),
        vec![
            Column::new(
                "stage".into(),
                rows.iter().map(|r| r.stage.clone()).collect::<Vec<_>>(),
            ),
            Column::new(
                "setting".into(),
                rows.iter().map(|r| r.setting.clone()).collect::<Vec<_>>(),
            ),
            Column::new(
                "is_default".into(),
                rows.iter().map(|r| r.is_default).collect::<Vec<_>>(),
            ),
            Column::new(
                "seconds_per_item".into(),
                rows.iter().map(|r| r.seconds_per_item).collect::<Vec<_>>(),
            ),
            Column::new(
                "median_err_deg".into(),
                rows.iter().map(|r| r.median_err_deg).collect::<Vec<_>>(),
            ),
            Column::new(
                "median_err_sd_deg".into(),
                rows.iter().map(|r| r.median_err_sd).collect::<Vec<_>>(),
            ),
            Column::new(
                "p90_err_deg".into(),
                rows.iter().map(|r| r.p90_err_deg).collect::<Vec<_>>(),
            ),
            Column::new(
                "ok_fraction".into(),
                rows.iter().map(|r| r.ok_fraction).collect::<Vec<_>>(),
            ),
            Column::new(
                "coverage".into(),
                rows.iter().map(|r| r.coverage).collect::<Vec<_>>(),
            ),
            Column::new(
                "n_items".into(),
                rows.iter().map(|r| r.n_items as u64).collect::<Vec<_>>(),
            ),
            Column::new(
                "on_pareto_front".into(),
                rows.iter().map(|r| r.on_pareto_front).collect::<Vec<_>>(),
            ),
        ],
    )?;
    crate::table::write_frame_atomic(path, crate::table::TableFormat::Csv, &mut df)
}

/// Reads a `speed_error.csv` written by [`write_csv`] (to redraw its plot).
pub fn read_csv(path: &Path) -> Result<Vec<BenchRow>> {
    use polars::prelude::DataType;
    let df = crate::table::read_frame(path)?;
    let f = |name: &str| -> Result<Vec<f64>> {
        let c = Context::with_context(df.column(name), || {
            format!("{}: no column '{name}'", path.display())
        })?;
        let c = c.cast(&DataType::Float64)?;
        let ca = c.f64()?;
        Ok((0..ca.len())
            .map(|i| ca.get(i).unwrap_or(f64::NAN))
            .collect())
    };
    let st = |name: &str| -> Result<Vec<String>> {
        let c = Context::with_context(df.column(name), || {
            format!("{}: no column '{name}'", path.display())
        })?;
        let c = c.cast(&DataType::String)?;
        let ca = c.str()?;
        Ok((0..ca.len())
            .map(|i| ca.get(i).unwrap_or_default().to_string())
            .collect())
    };
    let (stage, setting, default, front) = (
        st("stage")?,
        st("setting")?,
        st("is_default")?,
        st("on_pareto_front")?,
    );
    // Written since session 11; older files have no sampling noise.
    let med_sd = f("median_err_sd_deg").unwrap_or_else(|_| vec![0.0; df.height()]);
    // Written since session 21.
    let coverage = f("coverage").unwrap_or_else(|_| vec![1.0; df.height()]);
    let (secs, med, p90, ok, n) = (
        f("seconds_per_item")?,
        f("median_err_deg")?,
        f("p90_err_deg")?,
        f("ok_fraction")?,
        f("n_items")?,
    );
    Ok((0..df.height())
        .map(|i| BenchRow {
            stage: stage[i].clone(),
            setting: setting[i].clone(),
            is_default: default[i] == "true",
            seconds_per_item: secs[i],
            median_err_deg: med[i],
            median_err_sd: med_sd[i],
            p90_err_deg: p90[i],
            ok_fraction: ok[i],
            coverage: coverage[i],
            n_items: n[i] as usize,
            on_pareto_front: front[i] == "true",
        })
        .collect())
}

/// Pareto plot: log10 seconds per item against log10 median error, one panel per stage with a
/// positive error (the theory's closed forms are exact: that stage is in the CSV only).
pub fn pareto_figure(rows: &[BenchRow]) -> crate::report::plot::Figure {
    use crate::report::plot::{DataPoint, Figure, LegendAt, Marker, Note, Panel, Points};
    use plotters::style::RGBColor;
    let mut panels = Vec::new();
    for stage in ["extract", "theory", "fit"] {
        let rs: Vec<&BenchRow> = rows
            .iter()
            .filter(|r| {
                r.stage == stage
                    && r.median_err_deg > 0.0
                    && r.median_err_deg.is_finite()
                    && r.seconds_per_item > 0.0
            })
            .collect();
        if rs.is_empty() {
            continue;
        }
        let pt = |r: &BenchRow| DataPoint {
            x: r.seconds_per_item.log10(),
            y: r.median_err_deg.log10(),
            x_err: None,
            // The median's sampling noise, in log10 (its lower end held at a tenth of it).
            y_err: (r.median_err_sd > 0.0 && r.median_err_sd.is_finite()).then(|| {
                let (m, sd) = (r.median_err_deg, r.median_err_sd);
                (
                    m.log10() - (m - sd).max(0.1 * m).log10(),
                    (m + sd).log10() - m.log10(),
                )
            }),
        };
        let unit = match stage {
            "fit" => "|e - e_true|",
            "extract" => "mean of the angles' median |error| (deg)",
            _ => "median |error| (deg)",
        };
        let mut panel = Panel::new(
            format!("{stage}: speed against error"),
            "log10 seconds per item",
            format!("log10 {unit}"),
        );
        let group = |front: bool, default: bool| -> Vec<DataPoint> {
            rs.iter()
                .filter(|r| r.on_pareto_front == front && r.is_default == default)
                .map(|r| pt(r))
                .collect()
        };
        panel.points.push(Points {
            label: Some("on the Pareto front".into()),
            points: group(true, false),
            color: RGBColor(30, 140, 60),
            marker: Marker::Circle,
        });
        panel.points.push(Points {
            label: Some("dominated".into()),
            points: group(false, false),
            color: RGBColor(40, 90, 170),
            marker: Marker::Cross,
        });
        let mut default = group(true, true);
        default.extend(group(false, true));
        panel.points.push(Points {
            label: Some("default".into()),
            points: default,
            color: RGBColor(200, 40, 40),
            marker: Marker::Square,
        });
        let (xs, ys): (Vec<f64>, Vec<f64>) = rs.iter().map(|r| (pt(r).x, pt(r).y)).unzip();
        let span = |v: &[f64], lo_pad: f64, hi_pad: f64| {
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(*x), b.max(*x))
                });
            let w = (hi - lo).max(0.2);
            (lo - lo_pad * w, hi + hi_pad * w)
        };
        // Room on the right for the labels.
        let (xr, yr) = (span(&xs, 0.1, 0.6), span(&ys, 0.15, 0.15));
        // Each point carries a number and a key lists the settings in the room on the right:
        // full names next to the points ran into each other where settings tie (robust_rounds
        // and the default give the same readings). Points closer than about a character share
        // one label, "1,11" (about 17 px per line and 8 px per character in a plot area of some
        // 650 × 420 px). Bars: the median's sampling noise.
        let line = (yr.1 - yr.0) * 17.0 / 420.0;
        let char_w = (xr.1 - xr.0) * 8.0 / 650.0;
        let name = |r: &BenchRow| {
            r.setting
                .split(" (")
                .next()
                .unwrap_or(&r.setting)
                .to_string()
        };
        let mut groups: Vec<(f64, f64, Vec<usize>)> = Vec::new();
        for i in 0..rs.len() {
            match groups
                .iter_mut()
                .find(|g| (g.0 - xs[i]).abs() < 4.0 * char_w && (g.1 - ys[i]).abs() < line)
            {
                Some(g) => g.2.push(i + 1),
                None => groups.push((xs[i], ys[i], vec![i + 1])),
            }
        }
        for (x, y, ids) in &groups {
            let ids: Vec<String> = ids.iter().map(|i| i.to_string()).collect();
            panel.notes.push(Note {
                x: *x + 0.5 * char_w,
                y: *y,
                text: ids.join(","),
                color: RGBColor(60, 60, 60),
            });
        }
        let key_x = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max) + 0.12 * (xr.1 - xr.0);
        let key_top = yr.1 - 0.22 * (yr.1 - yr.0);
        for (i, r) in rs.iter().enumerate() {
            panel.notes.push(Note {
                x: key_x,
                y: key_top - i as f64 * line,
                text: format!("{} {}", i + 1, name(r)),
                color: RGBColor(60, 60, 60),
            });
        }
        panel = panel.ranges(xr, yr);
        panel.legend = LegendAt::UpperRight;
        panels.push(panel);
    }
    Figure::new(
        "pareto",
        "Speed against error for each stage's cost knobs (default in red, Pareto front in green; \
         bars: sampling noise of the median; settings that lose half of an angle's readings have \
         an infinite error and no point).",
        panels,
    )
}

/// Runs the chosen stages and writes the CSV and the plot; returns the rows.
pub fn speed_error(args: &SpeedErrorArgs) -> Result<Vec<BenchRow>, CliError> {
    let stages: Vec<&str> = args.stages.split(',').map(str::trim).collect();
    for s in &stages {
        if !["extract", "theory", "fit"].contains(s) {
            return Err(CliError::usage(format!(
                "--stages: unknown stage '{s}' (extract, theory, fit)"
            )));
        }
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    if args.replot {
        // The measured rows as they are; only the front (its rule may have changed) and the
        // plot are made again.
        let mut rows = read_csv(&args.out.join("speed_error.csv"))?;
        mark_pareto(&mut rows);
        write_csv(&rows, &args.out.join("speed_error.csv"))?;
        crate::report::plot::save(&pareto_figure(&rows), &args.out)?;
        return Ok(rows);
    }
    let mut rows = Vec::new();
    if stages.contains(&"extract") {
        rows.extend(extract_rows(&args.out, args.shots, args.seed, &args.tier)?);
    }
    if stages.contains(&"theory") {
        rows.extend(theory_rows(20_000, args.seed));
    }
    if stages.contains(&"fit") {
        rows.extend(fit_rows(args.seed)?);
    }
    mark_pareto(&mut rows);
    write_csv(&rows, &args.out.join("speed_error.csv"))?;
    crate::report::plot::save(&pareto_figure(&rows), &args.out)?;
    Ok(rows)
}

/// `bench psi-bound`: the bound of every planned shot ([`crate::synth::bound`]) at each blind
/// radius, written to `OUT/psi_bound.csv` (`file, material, psi_deg, blind_r,
/// sigma_psi_bound_deg, sigma_d_bound_px, incoming_px`), with a summary on standard output and,
/// for several radii, the figure `OUT/psi_bound/psi_bound.png|svg` (in a folder of its own, so
/// that `extract OUT` does not take it for a photo): the median |error| of a reader at the
/// bound against the blind radius, and the extractor's with `--table`.
pub fn psi_bound(a: &PsiBoundArgs) -> CliResult {
    use crate::synth::bound;
    let args = &a.synth;
    if let Some(k) = a.blind_r.iter().find(|k| !(k.is_finite() && **k >= 0.0)) {
        return Err(CliError::usage(format!(
            "--blind-r: expected numbers of ball radii ≥ 0, got {k}"
        )));
    }
    let folder = crate::synth::plan_for(args).map_err(CliError::usage)?;
    // The extractor's psi error per file, where its row is `ok` and has psi.
    let measured: Option<std::collections::HashMap<String, f64>> = match &a.table {
        None => None,
        Some(t) => {
            if !t.exists() {
                return Err(CliError::usage(format!(
                    "--table: '{}' does not exist",
                    t.display()
                )));
            }
            let rows = crate::table::read_angle_table(t)
                .map_err(|e| CliError::usage(format!("--table: {e:#}")))?;
            let truth: std::collections::HashMap<&str, f64> = folder
                .shots
                .iter()
                .map(|p| (p.file.as_str(), p.shot.psi.to_degrees()))
                .collect();
            Some(
                rows.iter()
                    .filter(|r| r.status == crate::table::Status::Ok)
                    .filter_map(|r| {
                        let t = truth.get(r.file.as_str())?;
                        Some((r.file.clone(), (r.psi_deg? - t).abs()))
                    })
                    .collect(),
            )
        }
    };
    let base = folder.backdrop.base_plate();
    let mut csv = String::from(
        "file,material,psi_deg,blind_r,sigma_psi_bound_deg,sigma_d_bound_px,incoming_px\n",
    );
    // Per radius: the median |error| of a reader at the bound on every shot, and on the rows the
    // extractor read.
    let mut curve: Vec<(f64, Option<f64>, Option<f64>)> = Vec::new();
    // Per shot, every radius's bound from one rendering.
    let per_shot: Vec<Vec<Option<bound::PsiBound>>> = folder
        .shots
        .iter()
        .map(|p| bound::psi_bound(p, &folder.backdrop, &base, &a.blind_r, a.outgoing))
        .collect();
    for (ik, &k) in a.blind_r.iter().enumerate() {
        let bounds: Vec<Option<bound::PsiBound>> = per_shot.iter().map(|b| b[ik]).collect();
        for (p, b) in folder.shots.iter().zip(&bounds) {
            let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
            csv.push_str(&format!(
                "{},{},{:.6},{k},{},{},{}\n",
                p.file,
                p.material_name,
                p.shot.psi.to_degrees(),
                cell(b.map(|b| b.sigma_psi_deg)),
                cell(b.map(|b| b.sigma_d_px)),
                cell(b.map(|b| b.incoming_px)),
            ));
        }
        let sigmas: Vec<f64> = bounds.iter().flatten().map(|b| b.sigma_psi_deg).collect();
        let read: Vec<f64> = folder
            .shots
            .iter()
            .zip(&bounds)
            .filter(|(p, _)| measured.as_ref().is_some_and(|m| m.contains_key(&p.file)))
            .filter_map(|(_, b)| b.map(|b| b.sigma_psi_deg))
            .collect();
        let all = bound::efficient_median(&sigmas);
        curve.push((k, all, bound::efficient_median(&read)));
        println!(
            "{} {} shots (seed {}): psi's Cramér–Rao bound for {} with an incoming streak in the image{}",
            folder.shots.len(),
            folder.tier.name(),
            args.seed,
            sigmas.len(),
            if k > 0.0 {
                format!(", pixels within {k} R of the impact left out")
            } else {
                String::new()
            }
        );
        if !sigmas.is_empty() {
            println!(
                "  sigma_psi bound: median {:.4}°, 10–90 % {:.4}–{:.4}°; above 1.5°: {}",
                quantile(&sigmas, 0.5),
                quantile(&sigmas, 0.1),
                quantile(&sigmas, 0.9),
                sigmas.iter().filter(|s| **s > 1.5).count()
            );
        }
        if let Some(m) = all {
            println!("  median |error| of a reader at the bound on every shot: {m:.4}°");
        }
    }
    let extractor = measured.as_ref().and_then(|m| {
        let mut e: Vec<f64> = m.values().copied().collect();
        crate::synth::render::median(&mut e).map(|med| (med, e.len()))
    });
    if let Some((med, n)) = extractor {
        println!("  the extractor: median |error| {med:.4}° over its {n} ok rows");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let file = args.out.join("psi_bound.csv");
    crate::io::write_atomic(&file, csv.as_bytes())?;
    println!("wrote {}", file.display());
    if a.blind_r.len() > 1 {
        let title = format!(
            "{} shots, {} tier, seed {}",
            folder.shots.len(),
            folder.tier.name(),
            args.seed
        );
        let fig = psi_bound_figure(&title, &curve, extractor);
        let saved = crate::report::plot::save(&fig, &args.out.join("psi_bound"))?;
        println!("wrote {}", saved.png.display());
    }
    Ok(Outcome::Ok)
}

/// The median |error| of a reader at psi's bound against the blind radius (log scale), on every
/// shot and on the extractor's `ok` rows, with the extractor's own median |error| over those rows.
pub fn psi_bound_figure(
    title: &str,
    curve: &[(f64, Option<f64>, Option<f64>)],
    extractor: Option<(f64, usize)>,
) -> crate::report::plot::Figure {
    use crate::report::plot::{Dash, Figure, Line, Panel};
    use plotters::style::RGBColor;
    let log = |v: Option<f64>| v.filter(|v| *v > 0.0).map(f64::log10);
    let mut panel = Panel::new(
        format!("psi's Cramér–Rao bound: {title}"),
        "streaks' light left out within K ball radii of the impact",
        "log10 median |psi error| (deg)",
    );
    type Point = (f64, Option<f64>, Option<f64>);
    let bound_line =
        |label: &str, colour: RGBColor, dash: Dash, pick: fn(&Point) -> Option<f64>| {
            Line::new(label, colour, dash)
                .with_samples(curve.iter().map(|c| (c.0, log(pick(c)), false)))
        };
    let k_max = curve.iter().map(|c| c.0).fold(0.0, f64::max);
    panel.lines.push(bound_line(
        "a reader at the bound, every shot",
        RGBColor(30, 90, 170),
        Dash::Solid,
        |c| c.1,
    ));
    if let Some((med, n)) = extractor {
        panel.lines.push(bound_line(
            "a reader at the bound, the extractor's ok rows",
            RGBColor(30, 140, 60),
            Dash::Dashed,
            |c| c.2,
        ));
        panel.lines.push(
            Line::new(
                format!("the extractor: median |error| over its {n} ok rows"),
                RGBColor(200, 40, 40),
                Dash::Dotted,
            )
            .with_samples([
                (0.0, Some(med.log10()), false),
                (k_max, Some(med.log10()), false),
            ]),
        );
    }
    let panel = panel.ranges((0.0, k_max.max(1.0)), (0.0, 1.0)).auto_y(0.5);
    Figure::new(
        "psi_bound",
        "psi's Cramér–Rao bound with the streaks' light near the impact left out (streakfit bench psi-bound)",
        vec![panel],
    )
}

pub fn run(args: &BenchArgs) -> CliResult {
    match &args.kind {
        BenchKind::PsiBound(a) => psi_bound(a),
        BenchKind::Stability(a) => stability::run(a),
        BenchKind::Stages(a) => stages::run(a),
        BenchKind::SpeedError(a) => {
            let rows = speed_error(a)?;
            println!(
                "{:<8} {:<44} {:>3} {:>12} {:>10} {:>8} {:>10} {:>5} {:>5} {:>6}",
                "stage", "setting", "def", "s/item", "median", "± sd", "p90", "ok", "cov", "pareto"
            );
            for r in &rows {
                println!(
                    "{:<8} {:<44} {:>3} {:>12.3e} {:>10.4} {:>8.4} {:>10.4} {:>5.2} {:>5.2} {:>6}",
                    r.stage,
                    r.setting,
                    if r.is_default { "*" } else { "" },
                    r.seconds_per_item,
                    r.median_err_deg,
                    r.median_err_sd,
                    r.p90_err_deg,
                    r.ok_fraction,
                    r.coverage,
                    if r.on_pareto_front { "yes" } else { "no" }
                );
            }
            let off: Vec<&BenchRow> = rows
                .iter()
                .filter(|r| r.is_default && !r.on_pareto_front)
                .collect();
            for r in &off {
                eprintln!(
                    "warning: default {} setting '{}' is not on the Pareto front",
                    r.stage, r.setting
                );
            }
            println!("wrote {}", a.out.join("speed_error.csv").display());
            Ok(if off.is_empty() {
                Outcome::Ok
            } else {
                Outcome::SomeFailed
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(stage: &str, t: f64, e: f64) -> BenchRow {
        BenchRow {
            stage: stage.into(),
            setting: format!("{t}/{e}"),
            is_default: false,
            seconds_per_item: t,
            median_err_deg: e,
            median_err_sd: 0.0,
            p90_err_deg: e,
            ok_fraction: 1.0,
            coverage: 1.0,
            n_items: 1,
            on_pareto_front: false,
        }
    }

    #[test]
    fn pareto_front_keeps_only_unbeaten_settings_per_stage() {
        let mut rows = vec![
            row("a", 1.0, 1.0),
            row("a", 2.0, 0.5),
            row("a", 3.0, 0.6),
            row("a", 1.0, 1.2),
            row("b", 9.0, 9.0),
            // 2 % faster with the same error: timing noise, beats nobody and is not beaten.
            row("a", 0.98, 1.0),
            // Fastest and most accurate, but it measured fewer items: beats nobody.
            row("a", 0.5, 0.4),
        ];
        rows[6].ok_fraction = 0.5;
        mark_pareto(&mut rows);
        let front: Vec<bool> = rows.iter().map(|r| r.on_pareto_front).collect();
        assert_eq!(front, [true, true, false, false, true, true, true]);
        // As accurate as a row it would beat and twice as fast, but it lost some of the
        // default's readings (an angle too sparse to score): it beats nobody.
        let mut rows = vec![row("a", 1.0, 1.0), row("a", 0.5, 1.0)];
        rows[1].coverage = 0.9;
        mark_pareto(&mut rows);
        let front: Vec<bool> = rows.iter().map(|r| r.on_pareto_front).collect();
        assert_eq!(front, [true, true]);
    }

    #[test]
    fn sampling_noise_keeps_a_setting_on_the_front() {
        // 0.10 against 0.11 with sampling noise 0.02 each: no more accurate, so the slower one
        // stays; with exact medians (theory, noise 0) the same numbers decide.
        let mut rows = vec![row("a", 1.0, 0.11), row("a", 1.5, 0.10)];
        rows[0].median_err_sd = 0.02;
        rows[1].median_err_sd = 0.02;
        mark_pareto(&mut rows);
        assert!(rows[0].on_pareto_front && !rows[1].on_pareto_front);
        let mut exact = vec![row("a", 1.0, 0.11), row("a", 1.02, 0.10)];
        mark_pareto(&mut exact);
        assert!(!exact[0].on_pareto_front && exact[1].on_pareto_front);
    }

    #[test]
    fn every_angle_weighs_the_same_and_a_lost_one_counts() {
        // Ten images: psi measured to 0.01 on all, delta1 to 1.0 on six of them, delta2 to 5.0
        // on two (too few to count).
        let full = [Some(0.01), Some(1.0), Some(5.0), None, None];
        let psi_d1 = [Some(0.01), Some(1.0), None, None, None];
        let psi = [Some(0.01), None, None, None, None];
        let mut imgs = vec![&full, &full];
        imgs.extend([&psi_d1; 4]);
        imgs.extend([&psi; 4]);
        let kinds = scored_angles(&imgs);
        assert_eq!(kinds, [0, 1]);
        let score = angle_score(&imgs, &kinds, 0.5);
        assert!((score - 0.505).abs() < 1e-12, "{score}");
        // The same delta1s, three of them lost by a setting: its median is infinite.
        let lost = [Some(0.01), Some(f64::INFINITY), None, None, None];
        let mut worse = vec![&full, &full, &psi_d1];
        worse.extend([&lost; 3]);
        worse.extend([&psi; 4]);
        assert!(angle_score(&worse, &kinds, 0.5).is_infinite());
        assert!((angle_score(&worse, &kinds, 0.0) - 0.505).abs() < 1e-12);
        // The bootstrap spread of a statistic of identical items is zero; with too few
        // readings for any angle there is no score and no spread.
        let same = [full; 6];
        let sd = bootstrap_sd(&same, 50, 1, |d| angle_score(d, &kinds, 0.5));
        assert!(sd.abs() < 1e-12, "{sd}");
        let few = [full; 3];
        let refs: Vec<&AngleErrors> = few.iter().collect();
        assert!(scored_angles(&refs).is_empty());
        assert!(bootstrap_sd(&few, 50, 1, |d| angle_score(d, &[], 0.5)).is_nan());
    }

    #[test]
    fn replot_redraws_from_the_csv_without_measuring() {
        let dir = std::env::temp_dir().join(format!("streakfit_replot_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut rows = vec![row("extract", 0.31, 0.4), row("extract", 0.27, 0.26)];
        rows[0].is_default = true;
        rows[0].median_err_sd = 0.43;
        rows[1].median_err_sd = 0.15;
        write_csv(&rows, &dir.join("speed_error.csv")).unwrap();
        let args = SpeedErrorArgs {
            out: dir.clone(),
            shots: 24,
            seed: 2026,
            tier: "realistic".into(),
            stages: "extract,theory,fit".into(),
            replot: true,
        };
        let back = speed_error(&args).unwrap();
        // The measured numbers come back as written (no theory or fit rows were measured);
        // the front is marked again: the faster setting, not measurably worse, beats the
        // default.
        assert_eq!(back.len(), 2);
        assert!((back[0].seconds_per_item - 0.31).abs() < 1e-15);
        assert!((back[1].median_err_sd - 0.15).abs() < 1e-15);
        assert!(!back[0].on_pareto_front && back[1].on_pareto_front);
        assert!(dir.join("pareto.png").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn quantiles_interpolate() {
        assert!((quantile(&[3.0, 1.0, 2.0, 4.0], 0.5) - 2.5).abs() < 1e-12);
        assert!((quantile(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.9) - 4.6).abs() < 1e-12);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn closed_forms_match_the_impulse_model_reference() {
        let rows = theory_rows(2000, 3);
        assert_eq!(
            (rows[0].setting.as_str(), rows[0].is_default),
            ("closed-form", true)
        );
        assert!(
            rows[0].median_err_deg < 1e-10 && rows[0].p90_err_deg < 1e-9,
            "{rows:?}"
        );
        assert!(rows[1].p90_err_deg.abs() < f64::MIN_POSITIVE);
    }
}
