//! `streakfit extract DIR... --out FILE.parquet|FILE.csv [--overlays DIR] [--jobs N] [--shard K/N]`:
//! the measuring instrument, run over folders of photographs.
//!
//! Every image file (`.png`, `.jpg`, `.jpeg`, `.tif`, `.tiff`, any case) in the folders gives
//! exactly one row, in sorted order: `ok`, `declined` (no collision, one ball only, saturated,
//! ambiguous) or `error` (empty, corrupt, unreadable, too small) with a reason; the batch always
//! goes on (a panic in the analysis of one image becomes that image's `error` row). A plate named
//! by `scene.toml` (`background`) is the cloth model for the images that name it, not a shot;
//! photos without a plate get their folder's fixed cloth texture, estimated from up to 15 of its
//! photos ([`folder_textures`]; `--no-texture` turns this off), which are then analysed as they
//! were decoded for it, up to 512 MB of them, instead of being decoded twice.
//! `--shard K/N` (1 ≤ K ≤ N) keeps the images whose index `i` in the sorted list of all images
//! satisfies `i mod N = K - 1`, so the shard tables of an array job concatenate into the full one.
//! Images are analysed in parallel (rayon, `--jobs` threads); a progress bar is drawn only when
//! stderr is a terminal. The table is written atomically; the exit code is 1 when any row is
//! `error`.

use crate::cli::{CliError, CliResult, Outcome};
use crate::scene::{ImageScene, SceneConfig};
use crate::synth::materials::Materials;
use crate::table::{ShotRow, Status, TableFormat, write_angle_table};
use crate::vision::{
    Analysis, AnalysisOptions, Cloth, Plate, analyse,
    image_io::{self, RgbImage},
    overlay,
    texture::{self, ClothTexture},
};
use anyhow::Context;
use clap::Args;
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering::Relaxed;
use std::time::Instant;

#[derive(Debug, Args, Clone)]
pub struct ExtractArgs {
    /// Folders of photographs (JPEG, PNG, TIFF), each optionally with a scene.toml.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output table: FILE.parquet or FILE.csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Write an overlay PNG per photo into this folder.
    #[arg(long)]
    pub overlays: Option<PathBuf>,
    /// Number of worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Process only shard K of N (1-based): every N-th image starting with the K-th.
    #[arg(long)]
    pub shard: Option<String>,
    /// Do not estimate the cloth's fixed texture from the folder's own photos (used by default
    /// for photos without a plate, in folders of at least 8 photos of one size).
    #[arg(long)]
    pub no_texture: bool,
}

/// One image to analyse.
#[derive(Debug, Clone)]
pub struct Job {
    pub path: PathBuf,
    pub file: String,
    pub scene: ImageScene,
    pub plate: Option<PathBuf>,
}

fn is_image(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .map(|e| {
            matches!(
                e.to_ascii_lowercase().as_str(),
                "png" | "jpg" | "jpeg" | "tif" | "tiff"
            )
        })
        .unwrap_or(false)
}

/// Parses `K/N` (1 ≤ K ≤ N).
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("--shard: '{s}' is not K/N"))?;
    let k: usize = k
        .trim()
        .parse()
        .map_err(|_| format!("--shard: '{k}' is not a whole number"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("--shard: '{n}' is not a whole number"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!("--shard: {k}/{n} needs 1 ≤ K ≤ N"));
    }
    Ok((k, n))
}

/// Lists the images of the folders (sorted per folder, folders in the given order), excluding
/// plates named by `scene.toml`.
pub fn list_jobs(dirs: &[PathBuf]) -> Result<Vec<Job>, CliError> {
    let mut jobs = Vec::new();
    for dir in dirs {
        if dir.is_file() {
            let parent = dir.parent().unwrap_or(Path::new("."));
            let scene = SceneConfig::load(parent).map_err(CliError::usage)?;
            let file = dir
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            let sc = scene.for_image(&file);
            let plate = sc.background.as_ref().map(|b| parent.join(b));
            jobs.push(Job {
                path: dir.clone(),
                file,
                scene: sc,
                plate,
            });
            continue;
        }
        if !dir.is_dir() {
            return Err(CliError::usage(format!(
                "input '{}' is neither a folder nor a file",
                dir.display()
            )));
        }
        let scene = SceneConfig::load(dir).map_err(CliError::usage)?;
        let mut plates: BTreeSet<String> = BTreeSet::new();
        plates.extend(scene.defaults.background.clone());
        for s in scene.images.values() {
            plates.extend(s.background.clone());
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| CliError::usage(format!("cannot read folder '{}': {e}", dir.display())))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_image(p))
            .collect();
        files.sort();
        for path in files {
            let file = path
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            if plates.contains(&file) {
                continue;
            }
            let sc = scene.for_image(&file);
            let plate = sc.background.as_ref().map(|b| dir.join(b));
            jobs.push(Job {
                path,
                file,
                scene: sc,
                plate,
            });
        }
    }
    Ok(jobs)
}

/// The folder a job's photo is in (the key of its cloth texture).
pub fn folder_of(job: &Job) -> PathBuf {
    job.path.parent().unwrap_or(Path::new(".")).to_path_buf()
}

/// The fixed cloth texture ([`crate::vision::texture`]) of every folder that `wanted` has photos
/// without a plate in, estimated from the folder's photos in `all` (the whole sorted list, so
/// that every shard of an array job uses the same texture). A folder too small, or whose photos
/// cannot be read, gets none (said on stderr when `verbose`).
pub fn folder_textures(
    all: &[Job],
    wanted: &[Job],
    coarse_side: usize,
    verbose: bool,
) -> HashMap<PathBuf, Arc<ClothTexture>> {
    folder_textures_keeping(all, wanted, coarse_side, verbose, 0).0
}

/// Decoded photos kept from the texture maps for their own analysis ([`process`]), by path.
pub type Decoded = HashMap<PathBuf, RgbImage>;

/// Bytes of decoded photos [`run`] keeps from the texture maps: all 15 of a folder of
/// 2400×1600 8-bit photos (11.5 MB each), some of larger ones.
const KEEP_DECODED_BYTES: usize = 512 << 20;

/// [`folder_textures`], and the photos of `wanted` it decoded, as the decoder gave them, up to
/// `keep_bytes` of them: each is decoded again for its analysis otherwise (23 ms of a
/// 2400×1600 JPEG or PNG, for 15 photos of every folder).
pub fn folder_textures_keeping(
    all: &[Job],
    wanted: &[Job],
    coarse_side: usize,
    verbose: bool,
    keep_bytes: usize,
) -> (HashMap<PathBuf, Arc<ClothTexture>>, Decoded) {
    let keep: BTreeSet<&Path> = wanted.iter().map(|j| j.path.as_path()).collect();
    let kept_bytes = std::sync::atomic::AtomicUsize::new(0);
    let mut decoded = Decoded::new();
    let needed: BTreeSet<PathBuf> = wanted
        .iter()
        .filter(|j| j.plate.is_none())
        .map(folder_of)
        .collect();
    let mut by_dir: BTreeMap<PathBuf, Vec<&Job>> = BTreeMap::new();
    for j in all.iter().filter(|j| j.plate.is_none()) {
        by_dir.entry(folder_of(j)).or_default().push(j);
    }
    let mut out = HashMap::new();
    for (dir, js) in by_dir.into_iter().filter(|(d, _)| needed.contains(d)) {
        if js.len() < texture::MIN_IMAGES {
            continue;
        }
        let t0 = Instant::now();
        let read: Vec<(texture::Residual, Option<(PathBuf, RgbImage)>)> = texture::pick(js.len())
            .par_iter()
            .filter_map(|&i| {
                let path = &js[i].path;
                let d = image_io::load(path).ok()?;
                let r = texture::residual(&d, coarse_side);
                // A wanted photo is kept while the budget lasts (which ones, when photos
                // race for its last bytes, changes only what is decoded twice).
                let n = d.byte_len();
                let room = keep.contains(path.as_path())
                    && kept_bytes
                        .fetch_update(Relaxed, Relaxed, |k| (k + n <= keep_bytes).then_some(k + n))
                        .is_ok();
                Some((r, room.then(|| (path.clone(), d))))
            })
            .collect();
        let mut res = Vec::with_capacity(read.len());
        for (r, d) in read {
            res.push(r);
            decoded.extend(d);
        }
        // Photos of the folder's most common size only.
        let mut sizes: HashMap<(usize, usize), usize> = HashMap::new();
        for r in &res {
            *sizes.entry(r.size()).or_default() += 1;
        }
        let common = sizes
            .into_iter()
            .max_by_key(|&(s, n)| (n, s))
            .map(|(s, _)| s);
        let res: Vec<texture::Residual> = res
            .into_iter()
            .filter(|r| Some(r.size()) == common)
            .collect();
        match ClothTexture::from_residuals(&res) {
            Ok(t) => {
                if let Some(path) = std::env::var_os("STREAKFIT_TEXTURE_PNG") {
                    let _ = t.debug_picture().save(path);
                }
                if verbose {
                    eprintln!(
                        "extract: cloth texture of '{}' from {} photos ({:.0}% of the table, \
                         {:.1} s)",
                        dir.display(),
                        t.images,
                        100.0 * t.coverage,
                        t0.elapsed().as_secs_f64()
                    );
                }
                out.insert(dir, Arc::new(t));
            }
            Err(e) if verbose => {
                eprintln!("extract: no cloth texture for '{}': {e}", dir.display())
            }
            Err(_) => {}
        }
    }
    (out, decoded)
}

/// Analyses one image into its row (and its overlay, when asked). Without a plate, `texture` is
/// the folder's cloth texture, if any. `decoded` is the image already decoded (kept from its
/// folder's texture map; the row's `seconds` then leave its decoding out), else it is read
/// from its file.
pub fn process(
    job: &Job,
    decoded: Option<RgbImage>,
    plate: Option<&Result<Arc<Plate>, String>>,
    texture: Option<&ClothTexture>,
    overlays: Option<&Path>,
    opts: &AnalysisOptions,
) -> ShotRow {
    let t0 = Instant::now();
    let material = job
        .scene
        .material
        .clone()
        .unwrap_or_else(|| "unknown".into());
    let img = match decoded {
        Some(d) => Ok(d),
        None => image_io::load(&job.path),
    };
    let mut row = match img {
        Err(e) => ShotRow::failed(&job.file, Status::Error, e, &material),
        Ok(img) => {
            let plate_img = match plate {
                Some(Err(e)) => {
                    let mut r = ShotRow::failed(&job.file, Status::Error, e.clone(), &material);
                    r.seconds = t0.elapsed().as_secs_f64();
                    return r;
                }
                Some(Ok(p)) => Some(p.as_ref()),
                None => None,
            };
            let cloth = Cloth::of(plate_img, texture);
            if std::env::var_os("STREAKFIT_DEBUG").is_some() {
                eprintln!("== {}", job.file);
            }
            let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                analyse(&img, cloth, job.scene.ball_radius_px_cloth(), opts)
            }));
            match res {
                Err(_) => ShotRow::failed(
                    &job.file,
                    Status::Error,
                    "internal error while analysing this image",
                    &material,
                ),
                Ok(a) => {
                    let mut row = row_of(job, &a);
                    if let Some(dir) = overlays
                        && let Err(e) = write_overlay(dir, &job.file, &img, &a)
                    {
                        if row.status == Status::Ok {
                            row.status = Status::Error;
                        }
                        row.reason = format!("{}; overlay not written: {e:#}", row.reason);
                    }
                    row
                }
            }
        }
    };
    row.spin = job.scene.spin;
    row.english = job.scene.english;
    row.seconds = t0.elapsed().as_secs_f64();
    row
}

/// The table row of an analysis of `job` (its `seconds` left at 0).
pub fn row_of(job: &Job, a: &Analysis) -> ShotRow {
    let material = job.scene.material.as_deref().unwrap_or("unknown");
    let mut row = ShotRow::failed(&job.file, a.status, a.reason.clone(), material);
    row.psi_deg = a.psi_deg;
    row.delta1_deg = a.delta1_deg;
    row.delta2_deg = a.delta2_deg;
    row.theta1_deg = a.theta1_deg;
    row.theta2_deg = a.theta2_deg;
    row.psi_err_deg = a.psi_err_deg;
    row.delta1_err_deg = a.delta1_err_deg;
    row.delta2_err_deg = a.delta2_err_deg;
    row.theta1_err_deg = a.theta1_err_deg;
    row.theta2_err_deg = a.theta2_err_deg;
    row.frame_err_deg = a.frame_err_deg;
    row.path_model1 = a.path_model1.clone();
    row.path_model2 = a.path_model2.clone();
    row.cloth_model = a.cloth.map(|c| c.as_str().to_string());
    row.ball_radius_px = a.ball_radius_px;
    row.impact_x_px = a.impact.map(|p| p.0);
    row.impact_y_px = a.impact.map(|p| p.1);
    row.spin = job.scene.spin;
    row.english = job.scene.english;
    row
}

/// Overlay file name for an image.
pub fn overlay_name(file: &str) -> String {
    let stem = Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.to_string());
    format!("{stem}_overlay.png")
}

fn write_overlay(
    dir: &Path,
    file: &str,
    img: &RgbImage,
    a: &crate::vision::Analysis,
) -> anyhow::Result<()> {
    let pic = overlay::render(img, a, file);
    let path = dir.join(overlay_name(file));
    let tmp = dir.join(format!(".{}.tmp{}", overlay_name(file), std::process::id()));
    pic.save_with_format(&tmp, image::ImageFormat::Png)
        .with_context(|| format!("cannot write '{}'", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("cannot rename to '{}'", path.display()))
}

/// How far the balls' friction may exceed their material preset's (Table 1 of the paper) and
/// still be read: a pair twice as grippy as the paper's. It bounds the object ball's throw
/// ([`AnalysisOptions::throw_max_deg`]: billiard 8.0°, steel 21°, rubber unbounded by it).
pub const FRICTION_MARGIN: f64 = 2.0;

/// The largest ball–ball friction (`FRICTION_MARGIN × max(mu, mu0)`) of each material named by
/// the jobs' scenes that the presets (`datasets/materials.toml`) hold. A material without a preset
/// is left out: its object ball's throw is bounded only by [`AnalysisOptions::throw_max_deg`]'s
/// default.
pub fn ball_friction_bounds(jobs: &[Job]) -> HashMap<String, f64> {
    let named: Vec<&String> = jobs
        .iter()
        .filter_map(|j| j.scene.material.as_ref())
        .collect();
    if named.is_empty() {
        return HashMap::new();
    }
    let presets = match Materials::load(&Materials::default_path()) {
        Ok(m) => m,
        Err(e) => {
            eprintln!(
                "extract: no material presets ({e}); the object ball's throw is not bounded by its friction"
            );
            return HashMap::new();
        }
    };
    named
        .into_iter()
        .filter_map(|m| {
            let p = presets.get(m).ok()?;
            Some((m.clone(), FRICTION_MARGIN * p.mu.max(p.mu_static)))
        })
        .collect()
}

/// The background plates the jobs name, each decoded once, to be shared by its photos.
pub fn decode_plates(jobs: &[Job]) -> HashMap<PathBuf, Result<Arc<Plate>, String>> {
    let mut plates = HashMap::new();
    for p in jobs.iter().filter_map(|j| j.plate.as_ref()) {
        plates.entry(p.clone()).or_insert_with(|| {
            image_io::load(p)
                .map(|img| Arc::new(Plate::new(img)))
                .map_err(|e| format!("background plate '{}': {e}", p.display()))
        });
    }
    plates
}

/// `base` with the friction bound of the job's material ([`ball_friction_bounds`]).
pub fn job_options(
    job: &Job,
    base: &AnalysisOptions,
    friction: &HashMap<String, f64>,
) -> AnalysisOptions {
    AnalysisOptions {
        ball_friction_max: job
            .scene
            .material
            .as_ref()
            .and_then(|m| friction.get(m).copied()),
        ..base.clone()
    }
}

pub fn run(args: &ExtractArgs) -> CliResult {
    TableFormat::from_path(&args.out).map_err(|e| CliError::usage(format!("--out: {e}")))?;
    let shard = args
        .shard
        .as_deref()
        .map(parse_shard)
        .transpose()
        .map_err(CliError::usage)?;
    if args.jobs == Some(0) {
        return Err(CliError::usage("--jobs: must be at least 1"));
    }
    let all_jobs = list_jobs(&args.dirs)?;
    let jobs: Vec<Job> = match shard {
        Some((k, n)) => all_jobs
            .iter()
            .enumerate()
            .filter(|(i, _)| i % n == k - 1)
            .map(|(_, j)| j.clone())
            .collect(),
        None => all_jobs.clone(),
    };
    if let Some(dir) = &args.overlays {
        std::fs::create_dir_all(dir).map_err(|e| {
            CliError::usage(format!(
                "--overlays: cannot create '{}': {e}",
                dir.display()
            ))
        })?;
    }
    let plates = decode_plates(&jobs);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .map_err(|e| CliError::Failed(anyhow::anyhow!("cannot start worker threads: {e}")))?;
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(jobs.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} images  {elapsed_precise} (eta {eta})",
            )
            .expect("valid progress template"),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let opts = AnalysisOptions::default();
    let friction = ball_friction_bounds(&jobs);
    let (textures, decoded) = if args.no_texture {
        (HashMap::new(), Decoded::new())
    } else {
        pool.install(|| {
            folder_textures_keeping(&all_jobs, &jobs, opts.coarse_side, true, KEEP_DECODED_BYTES)
        })
    };
    // Each kept photo is taken out for its analysis, and freed after it.
    let decoded = std::sync::Mutex::new(decoded);
    let rows: Vec<ShotRow> = pool.install(|| {
        jobs.par_iter()
            .map(|j| {
                let opts = job_options(j, &opts, &friction);
                let mine = decoded
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .remove(&j.path);
                let row = process(
                    j,
                    mine,
                    j.plate.as_ref().and_then(|p| plates.get(p)),
                    textures.get(&folder_of(j)).map(|t| t.as_ref()),
                    args.overlays.as_deref(),
                    &opts,
                );
                bar.inc(1);
                row
            })
            .collect()
    });
    bar.finish_and_clear();
    write_angle_table(&args.out, &rows).map_err(CliError::Failed)?;
    let n_ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    let n_err = rows.iter().filter(|r| r.status == Status::Error).count();
    eprintln!(
        "extract: {} images: {} ok, {} declined, {} error → {}",
        rows.len(),
        n_ok,
        rows.len() - n_ok - n_err,
        n_err,
        args.out.display()
    );
    Ok(if n_err > 0 {
        Outcome::SomeFailed
    } else {
        Outcome::Ok
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A photo kept decoded from its folder's texture map reads as the same row as from its
    /// file; only the wanted photos are kept (a shard's), and only as many as the byte budget
    /// holds.
    #[test]
    fn photos_kept_from_the_texture_map_read_as_from_their_files() {
        let dir = std::env::temp_dir().join(format!("streakfit_keep_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut args = crate::synth::SynthArgs::new(&dir, crate::synth::Tier::Realistic, 8, 7);
        args.size = "1200x800".into();
        crate::synth::run(&args).expect("synth");
        let all = list_jobs(std::slice::from_ref(&dir)).unwrap();
        assert_eq!(all.len(), 8);
        let side = AnalysisOptions::default().coarse_side;
        // Every photo wanted, room for all: each is kept, and reads as from its file.
        let (textures, mut kept) = folder_textures_keeping(&all, &all, side, false, 1 << 30);
        let texture = textures.get(&dir).expect("a texture map of 8 photos");
        assert_eq!(kept.len(), 8);
        let opts = AnalysisOptions::default();
        let mut ok = 0;
        for j in &all {
            let d = kept.remove(&j.path).expect("kept");
            let a = process(j, Some(d), None, Some(texture), None, &opts);
            let b = process(j, None, None, Some(texture), None, &opts);
            ok += usize::from(a.status == Status::Ok);
            let strip = |r: &ShotRow| {
                format!(
                    "{:?}",
                    ShotRow {
                        seconds: 0.0,
                        ..r.clone()
                    }
                )
            };
            assert_eq!(strip(&a), strip(&b), "{}", j.file);
        }
        assert!(
            ok >= 4,
            "only {ok} of 8 rows ok: the comparison would say little"
        );
        // A shard's photos only; a budget of two and a half photos keeps two.
        let shard: Vec<Job> = all.iter().step_by(2).cloned().collect();
        let one = 1200 * 800 * 3;
        let (_, kept) = folder_textures_keeping(&all, &shard, side, false, 5 * one / 2);
        assert_eq!(kept.len(), 2);
        assert!(kept.keys().all(|p| shard.iter().any(|j| &j.path == p)));
        let (_, kept) = folder_textures_keeping(&all, &shard, side, false, 1 << 30);
        assert_eq!(kept.len(), 4);
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn job(material: Option<&str>) -> Job {
        Job {
            path: PathBuf::from("shot.png"),
            file: "shot.png".into(),
            scene: ImageScene {
                material: material.map(String::from),
                ..ImageScene::default()
            },
            plate: None,
        }
    }

    /// Twice the larger of the preset's two ball–ball frictions (Table 1), per named material;
    /// a material without a preset gets no bound of its own.
    #[test]
    fn friction_bounds_come_from_the_presets() {
        let bounds = ball_friction_bounds(&[
            job(Some("billiard")),
            job(Some("steel")),
            job(Some("felt")),
            job(None),
        ]);
        assert_eq!(bounds.len(), 2);
        assert!((bounds["billiard"] - 0.14).abs() < 1e-12);
        assert!((bounds["steel"] - 0.36).abs() < 1e-12);
        let opts = AnalysisOptions {
            ball_friction_max: Some(bounds["billiard"]),
            ..AnalysisOptions::default()
        };
        assert!((opts.throw_max_deg() - 8.0478).abs() < 1e-4);
        assert!(ball_friction_bounds(&[job(None)]).is_empty());
    }
}
