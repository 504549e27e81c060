//! `streakfit bench stability`: how far the extractor's readings move when its input moves far
//! less than the sensor's noise (its decision noise).
//!
//! Each photo is analysed as decoded and with `K` perturbations: every decoded value (0..1) plus
//! uniform noise of ±`amplitude` (default 1e-6, 1/4000 of an 8-bit grey level, where the
//! synthetic sets' sensor noise is a grey level or more), seeded by the file name and the
//! perturbation's number. A continuous estimate moves by at most about `amplitude / noise` of
//! its sigma under such a change;
//! what moves more is a discrete decision: which samples are inliers, which path model wins,
//! where a walk stops, which reading of the streaks is taken. Reported over all photos:
//! - status changes (`ok`, `declined`, `error`) of the perturbed analyses;
//! - path-model changes, where both analyses are `ok`;
//! - `|Δ| / σ` of every angle read in both (`σ` the decoded photo's stated 1-sigma);
//! - with a `truth.csv` beside the photos, the misread `ok` angles of every run (|error| over 1°
//!   and over 5 sigma), and each run's median |error| of `psi`.
//!
//! With `--out DIR`, every run's angle table (the schema of `streakfit extract`) is written as
//! `DIR/run_0.csv` (as decoded), `DIR/run_1.csv`, ….
//!
//! Each folder is analysed as `streakfit extract` does (scene.toml, plate or the folder's cloth
//! texture, the material's friction bound); the texture map comes from the photos as decoded.

use crate::cli::{CliError, CliResult, Outcome};
use crate::extract::{
    ball_friction_bounds, decode_plates, folder_of, folder_textures, job_options, list_jobs, row_of,
};
use crate::table::{ShotRow, Status, write_angle_table};
use crate::vision::{AnalysisOptions, Cloth, analyse, image_io};
use clap::Args;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::PathBuf;

#[derive(Debug, Args, Clone)]
pub struct StabilityArgs {
    /// Folders of photos, as for `streakfit extract`; a `truth.csv` beside them (as `synth`
    /// writes) adds the misreadings of every run.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Perturbed analyses per photo.
    #[arg(long, default_value_t = 2)]
    pub perturbations: usize,
    /// Half-width of the uniform perturbation of each decoded value (full scale 1).
    #[arg(long, default_value_t = 1e-6)]
    pub amplitude: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Folder for every run's angle table (`run_0.csv` as decoded, then the perturbed ones).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The five angles in table order.
pub const ANGLES: [&str; 5] = ["psi", "delta1", "delta2", "theta1", "theta2"];

/// The five angles and their stated 1-sigma of a row, in [`ANGLES`] order.
fn angles(r: &ShotRow) -> [(Option<f64>, Option<f64>); 5] {
    [
        (r.psi_deg, r.psi_err_deg),
        (r.delta1_deg, r.delta1_err_deg),
        (r.delta2_deg, r.delta2_err_deg),
        (r.theta1_deg, r.theta1_err_deg),
        (r.theta2_deg, r.theta2_err_deg),
    ]
}

/// One photo: its analysis as decoded (first) and perturbed, and its true angles if known.
#[derive(Debug, Clone)]
pub struct Photo {
    pub runs: Vec<ShotRow>,
    pub truth: Option<[Option<f64>; 5]>,
}

/// The decision noise of a set of photos ([`summarise`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    pub photos: usize,
    /// Perturbed analyses, and those whose status differs from the decoded photo's.
    pub perturbed: usize,
    pub status_changes: usize,
    /// Outgoing paths read `ok` in both analyses, and those whose path model differs.
    pub paths: usize,
    pub model_changes: usize,
    /// `|Δ| / σ` of every angle read in both, sorted.
    pub ratios: Vec<f64>,
    /// Per run (0: as decoded): misread `ok` angles, `ok` rows, median |psi error| (degrees);
    /// empty without truth.
    pub misreads: Vec<usize>,
    pub ok: Vec<usize>,
    pub psi_median_err: Vec<f64>,
}

/// A misread angle: more than 1° and more than 5 stated sigmas from the truth.
fn misread(v: f64, sd: f64, truth: f64) -> bool {
    let e = (v - truth).abs();
    e > 1.0 && e > 5.0 * sd
}

/// The summary of photos that were each analysed the same number of times.
pub fn summarise(photos: &[Photo]) -> Summary {
    let runs = photos.iter().map(|p| p.runs.len()).min().unwrap_or(0);
    let mut s = Summary {
        photos: photos.len(),
        perturbed: 0,
        status_changes: 0,
        paths: 0,
        model_changes: 0,
        ratios: Vec::new(),
        misreads: Vec::new(),
        ok: Vec::new(),
        psi_median_err: Vec::new(),
    };
    for p in photos {
        let base = &p.runs[0];
        for r in &p.runs[1..runs] {
            s.perturbed += 1;
            if r.status != base.status {
                s.status_changes += 1;
                continue;
            }
            if r.status != Status::Ok {
                continue;
            }
            for (m0, m1) in [
                (&base.path_model1, &r.path_model1),
                (&base.path_model2, &r.path_model2),
            ] {
                if m0.is_some() && m1.is_some() {
                    s.paths += 1;
                    s.model_changes += usize::from(m0 != m1);
                }
            }
            for ((a, sd), (b, _)) in angles(base).into_iter().zip(angles(r)) {
                if let (Some(a), Some(b), Some(sd)) = (a, b, sd)
                    && sd > 0.0
                {
                    s.ratios.push((a - b).abs() / sd);
                }
            }
        }
    }
    s.ratios.sort_by(f64::total_cmp);
    if photos.iter().any(|p| p.truth.is_some()) {
        for run in 0..runs {
            let (mut bad, mut ok, mut psi_err) = (0, 0, Vec::new());
            for p in photos {
                let (Some(t), r) = (&p.truth, &p.runs[run]) else {
                    continue;
                };
                if r.status != Status::Ok {
                    continue;
                }
                ok += 1;
                for (k, ((v, sd), tv)) in angles(r).into_iter().zip(t).enumerate() {
                    if let (Some(v), Some(sd), Some(tv)) = (v, sd, tv) {
                        bad += usize::from(misread(v, sd, *tv));
                        if k == 0 {
                            psi_err.push((v - tv).abs());
                        }
                    }
                }
            }
            s.misreads.push(bad);
            s.ok.push(ok);
            s.psi_median_err.push(crate::bench::quantile(&psi_err, 0.5));
        }
    }
    s
}

impl Summary {
    /// The `q`-quantile of `|Δ| / σ` (NaN without any).
    pub fn ratio_quantile(&self, q: f64) -> f64 {
        crate::bench::quantile(&self.ratios, q)
    }

    /// The printed report.
    pub fn report(&self, amplitude: f64) -> String {
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        let mut out = format!(
            "{} photos, {} perturbed analyses (each decoded value ± {amplitude:.0e}, uniform)\n\
             status changed:     {} ({:.1} %)\n\
             path model changed: {} of {} outgoing paths read in both ({:.1} %)\n\
             |Δ| / sigma of {} angles read in both: median {:.3}, p90 {:.3}, p99 {:.3}, max {:.2}; \
             over 0.5: {:.1} %, over 1: {:.1} %\n",
            self.photos,
            self.perturbed,
            self.status_changes,
            pct(self.status_changes, self.perturbed),
            self.model_changes,
            self.paths,
            pct(self.model_changes, self.paths),
            self.ratios.len(),
            self.ratio_quantile(0.5),
            self.ratio_quantile(0.9),
            self.ratio_quantile(0.99),
            self.ratios.last().copied().unwrap_or(f64::NAN),
            pct(
                self.ratios.iter().filter(|r| **r > 0.5).count(),
                self.ratios.len()
            ),
            pct(
                self.ratios.iter().filter(|r| **r > 1.0).count(),
                self.ratios.len()
            ),
        );
        if !self.misreads.is_empty() {
            out += "run          ok  misread angles  median |psi error|\n";
            for (i, ((b, ok), e)) in self
                .misreads
                .iter()
                .zip(&self.ok)
                .zip(&self.psi_median_err)
                .enumerate()
            {
                let name = if i == 0 {
                    "decoded".to_string()
                } else {
                    format!("perturbed {i}")
                };
                out += &format!("{name:<12} {ok:>3}  {b:>14}  {e:>17.4}°\n");
            }
        }
        out
    }
}

/// The decoded photo plus uniform noise of ± `amplitude`, seeded by `seed`.
fn perturbed(img: &image_io::RgbImage, amplitude: f64, seed: u64) -> image_io::RgbImage {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let a = amplitude as f32;
    let s = img.samples();
    let data = (0..s.len())
        .map(|k| s.at(k) + rng.gen_range(-a..=a))
        .collect();
    image_io::RgbImage::from_f32(img.w, img.h, data)
}

/// The true angles per file of the `truth.csv` in `dir`, if there is one.
fn truth_in(dir: &std::path::Path) -> HashMap<String, [Option<f64>; 5]> {
    let Ok(text) = std::fs::read_to_string(dir.join("truth.csv")) else {
        return HashMap::new();
    };
    let Ok(rows) = crate::synth::truth::read_csv(&text) else {
        return HashMap::new();
    };
    rows.iter()
        .filter_map(|row| {
            let angles = ANGLES.map(|k| {
                row.get(&format!("{k}_deg"))
                    .and_then(|v| v.parse::<f64>().ok())
            });
            Some((row.get("file")?.clone(), angles))
        })
        .collect()
}

/// Seed of perturbation `k` of `file`: FNV-1a of the name, then `k`.
fn seed(file: &str, k: usize) -> u64 {
    let h = file.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    });
    h ^ (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

pub fn run(args: &StabilityArgs) -> CliResult {
    if !(args.amplitude > 0.0 && args.amplitude < 0.01) {
        return Err(CliError::usage("--amplitude: must lie in (0, 0.01)"));
    }
    if args.perturbations == 0 {
        return Err(CliError::usage("--perturbations: must be at least 1"));
    }
    if args.jobs == Some(0) {
        return Err(CliError::usage("--jobs: must be at least 1"));
    }
    let jobs = list_jobs(&args.dirs)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .map_err(|e| CliError::Failed(anyhow::anyhow!("cannot start worker threads: {e}")))?;
    let base = AnalysisOptions::default();
    let friction = ball_friction_bounds(&jobs);
    let textures = pool.install(|| folder_textures(&jobs, &jobs, base.coarse_side, false));
    let plates = decode_plates(&jobs);
    let mut truths: HashMap<PathBuf, HashMap<String, [Option<f64>; 5]>> = HashMap::new();
    for j in &jobs {
        let dir = folder_of(j);
        truths.entry(dir.clone()).or_insert_with(|| truth_in(&dir));
    }
    let photos: Vec<Photo> = pool.install(|| {
        jobs.par_iter()
            .filter_map(|j| {
                let img = image_io::load(&j.path).ok()?;
                let plate = match j.plate.as_ref().and_then(|p| plates.get(p)) {
                    Some(Ok(p)) => Some(p.as_ref()),
                    Some(Err(_)) => return None,
                    None => None,
                };
                let opts = job_options(j, &base, &friction);
                let cloth = Cloth::of(plate, textures.get(&folder_of(j)).map(|t| t.as_ref()));
                let run = |img: &image_io::RgbImage| {
                    row_of(
                        j,
                        &analyse(img, cloth, j.scene.ball_radius_px_cloth(), &opts),
                    )
                };
                // `STREAKFIT_DEBUG`'s per-photo header, as `extract` prints it, with the run.
                let debug = std::env::var_os("STREAKFIT_DEBUG").is_some();
                let mut runs = Vec::with_capacity(args.perturbations + 1);
                for k in 0..=args.perturbations {
                    if debug {
                        eprintln!("== {} (run {k})", j.file);
                    }
                    runs.push(if k == 0 {
                        run(&img)
                    } else {
                        run(&perturbed(&img, args.amplitude, seed(&j.file, k)))
                    });
                }
                Some(Photo {
                    runs,
                    truth: truths
                        .get(&folder_of(j))
                        .and_then(|t| t.get(&j.file))
                        .copied(),
                })
            })
            .collect()
    });
    if photos.len() < jobs.len() {
        eprintln!(
            "bench stability: {} of {} photos could not be decoded and are left out",
            jobs.len() - photos.len(),
            jobs.len()
        );
    }
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).map_err(|e| {
            CliError::usage(format!("--out: cannot create '{}': {e}", dir.display()))
        })?;
        for run in 0..=args.perturbations {
            let rows: Vec<ShotRow> = photos.iter().map(|p| p.runs[run].clone()).collect();
            write_angle_table(dir.join(format!("run_{run}.csv")), &rows)
                .map_err(CliError::Failed)?;
        }
    }
    print!("{}", summarise(&photos).report(args.amplitude));
    Ok(Outcome::Ok)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(psi: f64, sd: f64, model: &str) -> ShotRow {
        let mut r = ShotRow::failed("shot.png", Status::Ok, "", "billiard");
        (r.psi_deg, r.psi_err_deg) = (Some(psi), Some(sd));
        (r.theta1_deg, r.theta1_err_deg) = (Some(psi + 30.0), Some(sd));
        (r.theta2_deg, r.theta2_err_deg) = (Some(2.0), Some(sd));
        r.path_model1 = Some("line".into());
        r.path_model2 = Some(model.into());
        r
    }

    fn declined() -> ShotRow {
        ShotRow::failed("shot.png", Status::Declined, "no disc", "billiard")
    }

    /// Status and model changes are counted per perturbed analysis, `|Δ| / σ` per angle read in
    /// both, and misreadings per run against the truth.
    #[test]
    fn the_summary_counts_what_moved() {
        let truth = Some([Some(30.0), None, None, Some(60.0), Some(2.0)]);
        let photos = vec![
            Photo {
                runs: vec![ok(30.0, 0.1, "line"), ok(30.05, 0.1, "line"), declined()],
                truth,
            },
            Photo {
                // A misreading in the second perturbed run only: psi 2° off at 0.1°.
                runs: vec![
                    ok(30.0, 0.1, "line"),
                    ok(30.0, 0.1, "parabola+line"),
                    ok(32.0, 0.1, "line"),
                ],
                truth,
            },
        ];
        let s = summarise(&photos);
        assert_eq!((s.photos, s.perturbed, s.status_changes), (2, 4, 1));
        // Three perturbed analyses `ok` in both, two paths each.
        assert_eq!((s.paths, s.model_changes), (6, 1));
        assert_eq!(s.ratios.len(), 9);
        assert!((s.ratios[8] - 20.0).abs() < 1e-9);
        assert_eq!(
            s.ratios.iter().filter(|r| (**r - 0.5).abs() < 1e-9).count(),
            2
        );
        assert_eq!(s.misreads, vec![0, 0, 2]);
        assert_eq!(s.ok, vec![2, 2, 1]);
        assert!((s.psi_median_err[1] - 0.025).abs() < 1e-9);
        let text = s.report(1e-6);
        assert!(text.contains("status changed:     1 (25.0 %)"), "{text}");
        assert!(text.contains("perturbed 2    1               2"), "{text}");
    }

    /// The perturbation is as wide as asked, centred, and the same for the same seed.
    #[test]
    fn the_perturbation_is_tiny_uniform_and_seeded() {
        let img = image_io::RgbImage::from_f32(100, 100, vec![0.5; 30_000]);
        let a = perturbed(&img, 1e-6, seed("shot_001.png", 1));
        let b = perturbed(&img, 1e-6, seed("shot_001.png", 1));
        let c = perturbed(&img, 1e-6, seed("shot_001.png", 2));
        let f = |i: &image_io::RgbImage| match &i.data {
            image_io::Samples::F32(v) => v.clone(),
            image_io::Samples::U8(_) => panic!("a perturbed photo holds f32"),
        };
        assert_eq!(f(&a), f(&b));
        assert_ne!(f(&a), f(&c));
        let d: Vec<f64> = f(&a).iter().map(|v| (*v - 0.5) as f64).collect();
        // Within the half-width plus half an f32 step at 0.5 (3e-8).
        assert!(d.iter().all(|x| x.abs() <= 1.03e-6));
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        let var = d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64;
        // Uniform on ±1e-6: variance 1e-12 / 3 (f32 rounding near 0.5 is 3e-8 of it).
        assert!(mean.abs() < 2e-8, "{mean}");
        assert!((var / (1e-12 / 3.0) - 1.0).abs() < 0.05, "{var}");
    }
}
