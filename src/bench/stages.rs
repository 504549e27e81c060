//! `streakfit bench stages`: where the extractor's time goes, stage by stage.
//!
//! Every photo of the folders is decoded and analysed as `streakfit extract` does (scene.toml,
//! plate or the folder's cloth texture, the material's friction bound), one photo at a time on
//! one thread, so that the times are those of one core. The decode is timed on its own; the
//! analysis's wall time is split into its stages' exclusive times ([`crate::vision::stages`]),
//! which add up to it. A folder's texture map is built first (its time is not a photo's) and
//! printed apart.
//!
//! Printed: per stage, the mean milliseconds per photo and its share of the analysis; the mean
//! decode, the mean analysis and their ratio (the target is at most 1). With `--out`,
//! `FILE.csv` holds one row per photo: `file, status, decode_ms, analysis_ms` and one column
//! per stage (ms), named by the stage with `_` for its spaces and commas.

use crate::cli::{CliError, CliResult, Outcome};
use crate::extract::{
    ball_friction_bounds, decode_plates, folder_of, folder_textures, job_options, list_jobs,
    process,
};
use crate::table::Status;
use crate::vision::{AnalysisOptions, image_io, stages};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Args, Clone)]
pub struct StagesArgs {
    /// Folders of photos, as for `streakfit extract`.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Per-photo times as CSV (`file, status, decode_ms, analysis_ms`, one column per stage).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// One photo's times.
#[derive(Debug, Clone)]
pub struct PhotoTimes {
    pub file: String,
    pub status: Status,
    pub decode_ms: f64,
    pub analysis_ms: f64,
    /// Exclusive milliseconds per stage.
    pub stages: Vec<(&'static str, f64)>,
}

/// The stages in the order first seen over all photos.
fn stage_names(photos: &[PhotoTimes]) -> Vec<&'static str> {
    let mut names: Vec<&'static str> = Vec::new();
    for p in photos {
        for (n, _) in &p.stages {
            if !names.contains(n) {
                names.push(n);
            }
        }
    }
    names
}

fn stage_ms(p: &PhotoTimes, name: &str) -> f64 {
    p.stages
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(0.0, |(_, ms)| *ms)
}

/// The printed summary: mean ms per photo and share of the analysis for each stage.
pub fn report(photos: &[PhotoTimes]) -> String {
    let n = photos.len().max(1) as f64;
    let mean = |f: &dyn Fn(&PhotoTimes) -> f64| photos.iter().map(f).sum::<f64>() / n;
    let analysis = mean(&|p| p.analysis_ms);
    let decode = mean(&|p| p.decode_ms);
    let mut names = stage_names(photos);
    names.sort_by(|a, b| mean(&|p| stage_ms(p, b)).total_cmp(&mean(&|p| stage_ms(p, a))));
    let mut out = format!(
        "{} photos, one thread; mean per photo:\n{:<32} {:>9} {:>7}\n",
        photos.len(),
        "stage",
        "ms",
        "share"
    );
    for name in names {
        let ms = mean(&|p| stage_ms(p, name));
        out += &format!(
            "{name:<32} {ms:>9.1} {:>6.1}%\n",
            100.0 * ms / analysis.max(1e-12)
        );
    }
    out += &format!(
        "{:<32} {analysis:>9.1}\n{:<32} {decode:>9.1}\nanalysis / decode: {:.2} (target: at most 1)\n",
        "analysis",
        "decode",
        analysis / decode.max(1e-12)
    );
    out
}

fn write_csv(photos: &[PhotoTimes], path: &std::path::Path) -> anyhow::Result<()> {
    let names = stage_names(photos);
    let mut text = String::from("file,status,decode_ms,analysis_ms");
    for n in &names {
        text += &format!(",{}", n.replace(", ", "_").replace([' ', ','], "_"));
    }
    text.push('\n');
    for p in photos {
        text += &format!(
            "{},{},{:.3},{:.3}",
            p.file,
            p.status.as_str(),
            p.decode_ms,
            p.analysis_ms
        );
        for n in &names {
            text += &format!(",{:.3}", stage_ms(p, n));
        }
        text.push('\n');
    }
    crate::io::write_atomic(path, text.as_bytes())
}

pub fn run(args: &StagesArgs) -> CliResult {
    if let Some(out) = &args.out
        && out.extension().and_then(|e| e.to_str()) != Some("csv")
    {
        return Err(CliError::usage("--out: must name a .csv file"));
    }
    let jobs = list_jobs(&args.dirs)?;
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| CliError::Failed(anyhow::anyhow!("cannot start a worker thread: {e}")))?;
    let base = AnalysisOptions::default();
    let friction = ball_friction_bounds(&jobs);
    let t = Instant::now();
    let textures = one.install(|| folder_textures(&jobs, &jobs, base.coarse_side, false));
    if !textures.is_empty() {
        println!(
            "cloth texture maps of {} folder(s): {:.2} s (one thread, not in the photos' times)",
            textures.len(),
            t.elapsed().as_secs_f64()
        );
    }
    let plates = decode_plates(&jobs);
    let mut photos = Vec::new();
    let mut failed = 0usize;
    for j in &jobs {
        let t = Instant::now();
        let img = match image_io::load(&j.path) {
            Ok(img) => img,
            Err(e) => {
                eprintln!("{}: {e}", j.path.display());
                failed += 1;
                continue;
            }
        };
        let decode_ms = t.elapsed().as_secs_f64() * 1e3;
        let plate = j.plate.as_ref().and_then(|p| plates.get(p));
        if let Some(Err(e)) = plate {
            eprintln!("{}: {e}", j.path.display());
            failed += 1;
            continue;
        }
        let opts = job_options(j, &base, &friction);
        let texture = textures.get(&folder_of(j)).map(|t| t.as_ref());
        let t = Instant::now();
        // As `extract` analyses it (its row without the overlay).
        let (row, times) =
            one.install(|| stages::record(|| process(j, Some(img), plate, texture, None, &opts)));
        photos.push(PhotoTimes {
            file: j.file.clone(),
            status: row.status,
            decode_ms,
            analysis_ms: t.elapsed().as_secs_f64() * 1e3,
            stages: times,
        });
    }
    if photos.is_empty() {
        return Err(CliError::Failed(anyhow::anyhow!(
            "no photo could be analysed"
        )));
    }
    print!("{}", report(&photos));
    if let Some(out) = &args.out {
        write_csv(&photos, out).map_err(CliError::Failed)?;
        println!("wrote {}", out.display());
    }
    Ok(if failed > 0 {
        Outcome::SomeFailed
    } else {
        Outcome::Ok
    })
}
