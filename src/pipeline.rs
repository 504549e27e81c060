//! `streakfit run PIPELINE.toml`: photographs (or a synthetic stand-in) to a report, in stages
//! with caching.
//!
//! Stages, in order: `synth` (per folder that has a `[folders.synth]` table: render the shots),
//! `extract` (per folder: angles table + overlays), `fit` (all tables: coefficients per material
//! with model selection), `report` (figures, `index.html`, `report.md`). Each stage's key is a
//! BLAKE3 hash of the stage name, the streakfit build ([`build_id`]: a digest of the running
//! executable, so a rebuilt streakfit whose code changed recomputes every stage), the stage's
//! settings (canonical JSON) and
//! the content of its inputs (every file of an input folder, the tables, the fit, the materials
//! file). The key is stored beside the stage's outputs (`.streakfit-stage.json`); a stage whose key
//! is unchanged and whose outputs exist is skipped (`cached`). `--force` runs every stage.
//!
//! Paths in the pipeline file are relative to the current directory. Layout of a run named `N`:
//! `work/N/synth/FOLDER/` (rendered shots), `work/N/extract/FOLDER/{angles.parquet,overlays/}`,
//! `work/N/fit/fit.json`, `reports/N/` (report). A malformed pipeline file is a usage error
//! (exit code 2) that names the key and the problem; a failed stage exits with code 1.
//!
//! Pipeline file (every key besides `name` and the folders is optional):
//! ```toml
//! name = "demo"                  # letters, digits, '-', '_'
//! title = "..."                  # report title
//! work_dir = "work/demo"         # stage outputs (default work/NAME)
//! report_dir = "reports/demo"    # report (default reports/NAME)
//! [[folders]]
//! name = "steel"
//! path = "photos/steel"          # an existing folder of photographs ...
//! [folders.synth]                # ... or a synthetic one (exactly one of path/synth)
//! material = "steel"             # preset of datasets/materials.toml
//! shots = 20
//! seed = 2
//! tier = "clean"                 # clean | realistic | hard
//! psi = "5:80"                   # impact-angle range, degrees
//! spin = "1:1"                   # r range; english = "0:0"; size = "1800x1200"
//! background = false; known_spin = false
//! [extract]
//! jobs = 2                       # worker threads (default: all cores)
//! overlays = true
//! [fit]                          # keys of `streakfit fit`
//! regime = "auto"; criterion = "bic"; spin = "known"; sigma_deg = 0.3; psi_sigma_deg = 0.3
//! mass_ratio = 1.0; huber = 1.5; reject_sigma = 5.0; bootstrap = 100; seed = 1
//! [report]
//! gallery = 12                   # overlays per folder in the gallery
//! ```

use crate::cli::{CliError, CliResult, Outcome};
use crate::fit::{self, FitOptions, FitOutput, Loss};
use crate::report::{self, FitSummary, FolderInfo, ReportInput, StageInfo};
use crate::synth::materials::Materials;
use crate::synth::{self, SynthArgs, Tier};
use crate::table::{ShotRow, Status, read_angle_table};
use anyhow::{Context, anyhow};
use clap::{Args, ValueEnum};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Args, Clone)]
pub struct RunArgs {
    /// Pipeline description, e.g. pipelines/demo.toml.
    pub pipeline: PathBuf,
    /// Run every stage even when its cached output is up to date.
    #[arg(long)]
    pub force: bool,
}

/// File beside a stage's outputs that records the key it was made with.
pub const STAMP_FILE: &str = ".streakfit-stage.json";

// ---------------------------------------------------------------------------------------------
// The pipeline description.

/// A parsed pipeline file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pipeline {
    pub name: String,
    pub title: String,
    pub work_dir: PathBuf,
    pub report_dir: PathBuf,
    pub folders: Vec<Folder>,
    pub extract: ExtractSettings,
    pub fit: FitSettings,
    pub report: ReportSettings,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Folder {
    pub name: String,
    pub source: Source,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Source {
    Path(PathBuf),
    Synth(SynthSettings),
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SynthSettings {
    pub material: String,
    pub shots: usize,
    pub seed: u64,
    pub tier: String,
    pub psi: Option<String>,
    pub spin: Option<String>,
    pub english: Option<String>,
    pub size: Option<String>,
    pub background: bool,
    pub known_spin: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtractSettings {
    pub jobs: Option<usize>,
    pub overlays: bool,
}

/// The keys of `streakfit fit`, as the pipeline writes them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitSettings {
    pub regime: String,
    pub criterion: String,
    pub spin: String,
    pub sigma_deg: f64,
    pub psi_sigma_deg: f64,
    pub mass_ratio: f64,
    pub huber: Option<f64>,
    pub reject_sigma: f64,
    pub bootstrap: usize,
    pub seed: u64,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            regime: "auto".into(),
            criterion: "bic".into(),
            spin: "known".into(),
            sigma_deg: 0.3,
            psi_sigma_deg: 0.3,
            mass_ratio: 1.0,
            huber: None,
            reject_sigma: 5.0,
            bootstrap: 100,
            seed: 1,
        }
    }
}

impl FitSettings {
    /// The fit's options, through the same validation as `streakfit fit`'s flags.
    pub fn options(&self) -> Result<FitOptions, CliError> {
        let args = fit::FitArgs {
            tables: Vec::new(),
            out: PathBuf::from("unused.json"),
            residuals: None,
            material: None,
            regime: self.regime.clone(),
            criterion: self.criterion.clone(),
            spin: self.spin.clone(),
            sigma_deg: self.sigma_deg,
            psi_sigma_deg: self.psi_sigma_deg,
            mass_ratio: self.mass_ratio,
            huber: self.huber,
            reject_sigma: self.reject_sigma,
            bootstrap: self.bootstrap,
            seed: self.seed,
        };
        args.options().map_err(|e| match e {
            // The fit names its flags (`--regime`); the pipeline names its keys.
            CliError::Usage(m) => CliError::usage(format!("fit.{}", m.trim_start_matches("--"))),
            other => other,
        })
    }

    /// Options of the fit with the loss and rejection used.
    pub fn describe(&self) -> String {
        let o = self.options().ok();
        let loss = o.as_ref().map(|o| match o.loss {
            Loss::Squared => "least squares".to_string(),
            Loss::Huber(k) => format!("Huber {k}σ"),
        });
        format!(
            "regime {}, criterion {}, spin {}, {}",
            self.regime,
            self.criterion,
            self.spin,
            loss.unwrap_or_default()
        )
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportSettings {
    pub gallery: usize,
}

/// Reads typed keys from one TOML table and reports unknown keys, naming each by its full path.
struct Keys<'a> {
    table: &'a toml::Table,
    path: String,
    used: Vec<&'static str>,
}

fn bad(key: &str, msg: impl std::fmt::Display) -> String {
    format!("key '{key}': {msg}")
}

fn type_name(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a number",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        toml::Value::Array(_) => "an array",
        toml::Value::Table(_) => "a table",
    }
}

impl<'a> Keys<'a> {
    fn new(table: &'a toml::Table, path: impl Into<String>) -> Self {
        Self {
            table,
            path: path.into(),
            used: Vec::new(),
        }
    }

    fn full(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    fn get(&mut self, key: &'static str) -> Option<&'a toml::Value> {
        self.used.push(key);
        self.table.get(key)
    }

    fn string(&mut self, key: &'static str) -> Result<Option<String>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s.clone())),
            Some(v) => Err(bad(
                &self.full(key),
                format!("expected a string, found {}", type_name(v)),
            )),
        }
    }

    fn boolean(&mut self, key: &'static str) -> Result<Option<bool>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(toml::Value::Boolean(b)) => Ok(Some(*b)),
            Some(v) => Err(bad(
                &self.full(key),
                format!("expected true or false, found {}", type_name(v)),
            )),
        }
    }

    fn uint(&mut self, key: &'static str, min: u64) -> Result<Option<u64>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(toml::Value::Integer(i)) if *i >= min as i64 => Ok(Some(*i as u64)),
            Some(toml::Value::Integer(i)) => Err(bad(
                &self.full(key),
                format!("{i} is less than the minimum {min}"),
            )),
            Some(v) => Err(bad(
                &self.full(key),
                format!("expected an integer ≥ {min}, found {}", type_name(v)),
            )),
        }
    }

    fn number(&mut self, key: &'static str) -> Result<Option<f64>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(toml::Value::Integer(i)) => Ok(Some(*i as f64)),
            Some(toml::Value::Float(x)) if x.is_finite() => Ok(Some(*x)),
            Some(toml::Value::Float(x)) => {
                Err(bad(&self.full(key), format!("{x} is not a finite number")))
            }
            Some(v) => Err(bad(
                &self.full(key),
                format!("expected a number, found {}", type_name(v)),
            )),
        }
    }

    fn table(&mut self, key: &'static str) -> Result<Option<&'a toml::Table>, String> {
        match self.get(key) {
            None => Ok(None),
            Some(toml::Value::Table(t)) => Ok(Some(t)),
            Some(v) => Err(bad(
                &self.full(key),
                format!("expected a table, found {}", type_name(v)),
            )),
        }
    }

    /// Fails on keys that were never asked for (a misspelt key must not be ignored).
    fn finish(self) -> Result<(), String> {
        for k in self.table.keys() {
            if !self.used.contains(&k.as_str()) {
                let mut known: Vec<&str> = self.used.clone();
                known.sort_unstable();
                known.dedup();
                return Err(bad(
                    &self.full(k),
                    format!("unknown key (known here: {})", known.join(", ")),
                ));
            }
        }
        Ok(())
    }
}

fn valid_name(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 64
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
}

impl Pipeline {
    /// Parses a pipeline file's text; errors name the key and the problem.
    pub fn parse(text: &str) -> Result<Pipeline, String> {
        let root: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            format!("not valid TOML: {}", e.to_string().trim_end())
        })?;
        let mut k = Keys::new(&root, "");
        let name = k
            .string("name")?
            .ok_or_else(|| bad("name", "missing (the run's name, e.g. name = \"demo\")"))?;
        if !valid_name(&name) {
            return Err(bad(
                "name",
                format!("'{name}' must be 1–64 letters, digits, '-' or '_'"),
            ));
        }
        let title = k
            .string("title")?
            .unwrap_or_else(|| format!("streakfit report: {name}"));
        let work_dir = k
            .string("work_dir")?
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new("work").join(&name));
        let report_dir = k
            .string("report_dir")?
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new("reports").join(&name));
        let folders = match k.get("folders") {
            None => {
                return Err(bad(
                    "folders",
                    "missing: add at least one [[folders]] table",
                ));
            }
            Some(toml::Value::Array(a)) if a.is_empty() => {
                return Err(bad(
                    "folders",
                    "is empty: add at least one [[folders]] table",
                ));
            }
            Some(toml::Value::Array(a)) => {
                let mut out: Vec<Folder> = Vec::new();
                for (i, v) in a.iter().enumerate() {
                    let path = format!("folders[{i}]");
                    let toml::Value::Table(t) = v else {
                        return Err(bad(
                            &path,
                            format!("expected a table, found {}", type_name(v)),
                        ));
                    };
                    let f = Self::parse_folder(t, &path)?;
                    if out.iter().any(|o| o.name == f.name) {
                        return Err(bad(
                            &format!("{path}.name"),
                            format!("'{}' is used twice", f.name),
                        ));
                    }
                    out.push(f);
                }
                out
            }
            Some(v) => {
                return Err(bad(
                    "folders",
                    format!(
                        "expected an array of tables ([[folders]]), found {}",
                        type_name(v)
                    ),
                ));
            }
        };
        let extract = match k.table("extract")? {
            None => ExtractSettings {
                jobs: None,
                overlays: true,
            },
            Some(t) => {
                let mut e = Keys::new(t, "extract");
                let s = ExtractSettings {
                    jobs: e.uint("jobs", 1)?.map(|j| j as usize),
                    overlays: e.boolean("overlays")?.unwrap_or(true),
                };
                e.finish()?;
                s
            }
        };
        let fit = match k.table("fit")? {
            None => FitSettings::default(),
            Some(t) => {
                let mut f = Keys::new(t, "fit");
                let d = FitSettings::default();
                let s = FitSettings {
                    regime: f.string("regime")?.unwrap_or(d.regime),
                    criterion: f.string("criterion")?.unwrap_or(d.criterion),
                    spin: f.string("spin")?.unwrap_or(d.spin),
                    sigma_deg: f.number("sigma_deg")?.unwrap_or(d.sigma_deg),
                    psi_sigma_deg: f.number("psi_sigma_deg")?.unwrap_or(d.psi_sigma_deg),
                    mass_ratio: f.number("mass_ratio")?.unwrap_or(d.mass_ratio),
                    huber: f.number("huber")?,
                    reject_sigma: f.number("reject_sigma")?.unwrap_or(d.reject_sigma),
                    bootstrap: f.uint("bootstrap", 0)?.map_or(d.bootstrap, |b| b as usize),
                    seed: f.uint("seed", 0)?.unwrap_or(d.seed),
                };
                f.finish()?;
                for (key, v) in [("sigma_deg", s.sigma_deg), ("mass_ratio", s.mass_ratio)] {
                    if v <= 0.0 {
                        return Err(bad(&format!("fit.{key}"), format!("{v} must be positive")));
                    }
                }
                if s.psi_sigma_deg < 0.0 {
                    return Err(bad("fit.psi_sigma_deg", "must be ≥ 0"));
                }
                if s.huber.is_some_and(|h| h <= 0.0) {
                    return Err(bad("fit.huber", "must be positive"));
                }
                s.options().map_err(|e| e.to_string())?;
                s
            }
        };
        let report = match k.table("report")? {
            None => ReportSettings { gallery: 12 },
            Some(t) => {
                let mut r = Keys::new(t, "report");
                let s = ReportSettings {
                    gallery: r.uint("gallery", 0)?.map_or(12, |g| g as usize),
                };
                r.finish()?;
                s
            }
        };
        k.finish()?;
        Ok(Pipeline {
            name,
            title,
            work_dir,
            report_dir,
            folders,
            extract,
            fit,
            report,
        })
    }

    fn parse_folder(t: &toml::Table, path: &str) -> Result<Folder, String> {
        let mut k = Keys::new(t, path);
        let name = k
            .string("name")?
            .ok_or_else(|| bad(&format!("{path}.name"), "missing"))?;
        if !valid_name(&name) {
            return Err(bad(
                &format!("{path}.name"),
                format!("'{name}' must be 1–64 letters, digits, '-' or '_'"),
            ));
        }
        let dir = k.string("path")?;
        let synth = k.table("synth")?;
        let source = match (dir, synth) {
            (Some(_), Some(_)) => {
                return Err(bad(
                    &format!("{path}.synth"),
                    "give either 'path' or 'synth', not both",
                ));
            }
            (None, None) => {
                return Err(bad(
                    path,
                    "needs 'path' (a folder of photographs) or a 'synth' table",
                ));
            }
            (Some(d), None) => Source::Path(PathBuf::from(d)),
            (None, Some(t)) => {
                let sp = format!("{path}.synth");
                let mut s = Keys::new(t, sp.clone());
                let material = s.string("material")?.ok_or_else(|| {
                    bad(
                        &format!("{sp}.material"),
                        "missing (billiard, steel or rubber)",
                    )
                })?;
                let shots = s
                    .uint("shots", 1)?
                    .ok_or_else(|| bad(&format!("{sp}.shots"), "missing (number of shots)"))?;
                let tier = s.string("tier")?.unwrap_or_else(|| "clean".into());
                if Tier::from_str(&tier, true).is_err() {
                    return Err(bad(
                        &format!("{sp}.tier"),
                        format!("'{tier}' is not a tier (clean, realistic or hard)"),
                    ));
                }
                let settings = SynthSettings {
                    material,
                    shots: shots as usize,
                    seed: s.uint("seed", 0)?.unwrap_or(1),
                    tier,
                    psi: s.string("psi")?,
                    spin: s.string("spin")?,
                    english: s.string("english")?,
                    size: s.string("size")?,
                    background: s.boolean("background")?.unwrap_or(false),
                    known_spin: s.boolean("known_spin")?.unwrap_or(false),
                };
                s.finish()?;
                for (key, v) in [
                    ("psi", &settings.psi),
                    ("spin", &settings.spin),
                    ("english", &settings.english),
                ] {
                    if let Some(v) = v {
                        synth::parse_range(key, v).map_err(|e| bad(&format!("{sp}.{key}"), e))?;
                    }
                }
                if let Some(v) = &settings.size {
                    synth::parse_size(v).map_err(|e| bad(&format!("{sp}.size"), e))?;
                }
                Source::Synth(settings)
            }
        };
        k.finish()?;
        Ok(Folder { name, source })
    }

    /// Checks what the file alone cannot: materials exist, input folders exist.
    pub fn check(&self, materials: &Materials) -> Result<(), String> {
        for (i, f) in self.folders.iter().enumerate() {
            match &f.source {
                Source::Synth(s) => {
                    materials
                        .get(&s.material)
                        .map_err(|e| bad(&format!("folders[{i}].synth.material"), e))?;
                }
                Source::Path(p) => {
                    if !p.is_dir() {
                        return Err(bad(
                            &format!("folders[{i}].path"),
                            format!("'{}' is not a folder", p.display()),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Hashing and stamps.

/// Incremental BLAKE3 key of a stage.
struct KeyHasher(blake3::Hasher);

/// The running streakfit's identity in every stage key: its version and a BLAKE3 digest of its
/// executable. Keyed on the version alone, a stage served the tables of whatever code had made
/// them, so a changed extractor or fit went unseen until `--force` (which the README had to
/// ask for after every change). Any rebuild that changes the machine code changes the digest.
/// Read once per process (about 40 MB, some 20 ms); where the executable cannot be read the
/// version alone stands, as before.
pub fn build_id() -> &'static str {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let version = env!("CARGO_PKG_VERSION");
        match std::env::current_exe().and_then(std::fs::read) {
            Ok(bytes) => format!("{version}+{}", &blake3::hash(&bytes).to_hex()[..16]),
            Err(_) => version.to_string(),
        }
    })
}

impl KeyHasher {
    fn new(stage: &str) -> Self {
        let mut h = blake3::Hasher::new();
        h.update(b"streakfit-stage\0");
        h.update(build_id().as_bytes());
        h.update(b"\0");
        h.update(stage.as_bytes());
        h.update(b"\0");
        Self(h)
    }

    fn field(&mut self, label: &str, bytes: &[u8]) {
        self.0.update(label.as_bytes());
        self.0.update(&(bytes.len() as u64).to_le_bytes());
        self.0.update(bytes);
    }

    fn json(&mut self, label: &str, v: &impl Serialize) {
        let s = serde_json::to_string(v).expect("settings serialise to JSON");
        self.field(label, s.as_bytes());
    }

    fn hex(&self) -> String {
        self.0.finalize().to_hex()[..32].to_string()
    }
}

/// Digest of every file below `dir` (names relative to `dir`, sorted, and contents), hidden
/// files (the stamp, temporaries) excluded.
pub fn digest_dir(dir: &Path) -> anyhow::Result<String> {
    let mut files = Vec::new();
    collect_files(dir, dir, &mut files)?;
    files.sort();
    let mut h = blake3::Hasher::new();
    for rel in &files {
        let bytes = std::fs::read(dir.join(rel))
            .with_context(|| format!("reading {}", dir.join(rel).display()))?;
        h.update(rel.as_bytes());
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(blake3::hash(&bytes).as_bytes());
    }
    Ok(h.finalize().to_hex().to_string())
}

fn collect_files(root: &Path, dir: &Path, out: &mut Vec<String>) -> anyhow::Result<()> {
    for entry in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let path = entry.path();
        if path.is_dir() {
            collect_files(root, &path, out)?;
        } else {
            let rel = path.strip_prefix(root).unwrap_or(&path);
            out.push(rel.to_string_lossy().replace('\\', "/"));
        }
    }
    Ok(())
}

fn digest_file(path: &Path) -> anyhow::Result<String> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(blake3::hash(&bytes).to_hex().to_string())
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Stamp {
    stage: String,
    key: String,
    seconds: f64,
}

fn read_stamp(dir: &Path) -> Option<Stamp> {
    let text = std::fs::read_to_string(dir.join(STAMP_FILE)).ok()?;
    serde_json::from_str(&text).ok()
}

fn write_stamp(dir: &Path, stamp: &Stamp) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(stamp)?;
    report::write_atomic(&dir.join(STAMP_FILE), text.as_bytes())
}

/// Empties a stage's output folder before the stage rewrites it (stale files from an earlier
/// run with other settings must not leak into the next stage). Only folders inside the run's
/// own work or report folder are ever removed.
fn reset_dir(dir: &Path, owner: &Path) -> anyhow::Result<()> {
    if dir.exists() {
        if !dir.starts_with(owner) {
            return Err(anyhow!(
                "refusing to clear {}: it is outside {}",
                dir.display(),
                owner.display()
            ));
        }
        std::fs::remove_dir_all(dir).with_context(|| format!("clearing {}", dir.display()))?;
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))
}

// ---------------------------------------------------------------------------------------------
// Running.

/// One stage's record for the summary.
#[derive(Debug, Clone)]
pub struct StageRecord {
    pub name: String,
    /// `ran`, `cached` or `failed`.
    pub status: &'static str,
    pub seconds: f64,
    pub key: String,
    pub detail: String,
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub stages: Vec<StageRecord>,
    pub report_index: PathBuf,
    pub rows: Vec<ShotRow>,
    pub fits: Vec<FitSummary>,
    /// Materials whose fit failed, with the reason (the report shows the others).
    pub fit_failures: Vec<(String, String)>,
}

struct Runner {
    force: bool,
    records: Vec<StageRecord>,
    n_stages: usize,
}

impl Runner {
    /// Runs `work` unless `dir` holds a stamp with `key` (and `outputs_ok` agrees).
    fn stage(
        &mut self,
        name: &str,
        dir: &Path,
        key: String,
        outputs_ok: impl Fn() -> bool,
        work: impl FnOnce() -> anyhow::Result<String>,
    ) -> anyhow::Result<()> {
        let idx = self.records.len() + 1;
        if !self.force
            && let Some(st) = read_stamp(dir)
            && st.key == key
            && st.stage == name
            && outputs_ok()
        {
            eprintln!("[{idx}/{}] {name}: cached ({key})", self.n_stages);
            self.records.push(StageRecord {
                name: name.into(),
                status: "cached",
                seconds: 0.0,
                key,
                detail: format!("made in {:.1} s earlier", st.seconds),
            });
            return Ok(());
        }
        eprintln!("[{idx}/{}] {name}: running ...", self.n_stages);
        let t0 = Instant::now();
        let detail = match work().with_context(|| format!("stage {name}")) {
            Ok(d) => d,
            Err(e) => {
                self.records.push(StageRecord {
                    name: name.into(),
                    status: "failed",
                    seconds: t0.elapsed().as_secs_f64(),
                    key,
                    detail: format!("{e:#}"),
                });
                return Err(e);
            }
        };
        let seconds = t0.elapsed().as_secs_f64();
        write_stamp(
            dir,
            &Stamp {
                stage: name.into(),
                key: key.clone(),
                seconds,
            },
        )?;
        eprintln!(
            "[{idx}/{}] {name}: done in {seconds:.1} s — {detail}",
            self.n_stages
        );
        self.records.push(StageRecord {
            name: name.into(),
            status: "ran",
            seconds,
            key,
            detail,
        });
        Ok(())
    }
}

fn cli_to_anyhow(e: CliError) -> anyhow::Error {
    match e {
        CliError::Usage(m) => anyhow!(m),
        CliError::Failed(e) => e,
    }
}

/// Runs the pipeline file at `path` (see the module doc).
pub fn run_pipeline(path: &Path, force: bool) -> Result<RunSummary, CliError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::usage(format!("cannot read pipeline '{}': {e}", path.display())))?;
    let p =
        Pipeline::parse(&text).map_err(|e| CliError::usage(format!("{}: {e}", path.display())))?;
    let materials_path = Materials::default_path();
    let materials = Materials::load(&materials_path).map_err(CliError::usage)?;
    p.check(&materials)
        .map_err(|e| CliError::usage(format!("{}: {e}", path.display())))?;
    let materials_digest = digest_file(&materials_path).map_err(CliError::Failed)?;
    let fit_options = p.fit.options()?;

    let n_synth = p
        .folders
        .iter()
        .filter(|f| matches!(f.source, Source::Synth(_)))
        .count();
    let mut runner = Runner {
        force,
        records: Vec::new(),
        n_stages: n_synth + p.folders.len() + 2,
    };
    std::fs::create_dir_all(&p.work_dir).map_err(|e| {
        CliError::usage(format!(
            "work_dir: cannot create '{}': {e}",
            p.work_dir.display()
        ))
    })?;

    // Stage 1: synthetic folders.
    let mut inputs: Vec<(String, PathBuf)> = Vec::new();
    for f in &p.folders {
        match &f.source {
            Source::Path(d) => inputs.push((f.name.clone(), d.clone())),
            Source::Synth(s) => {
                let out = p.work_dir.join("synth").join(&f.name);
                let mut key = KeyHasher::new("synth");
                key.json("settings", s);
                key.field("materials", materials_digest.as_bytes());
                let args = synth_args(s, &out, &materials_path)?;
                let out2 = out.clone();
                let work_dir = p.work_dir.clone();
                runner
                    .stage(
                        &format!("synth {}", f.name),
                        &out,
                        key.hex(),
                        || out2.join(crate::scene::SCENE_FILE).exists(),
                        || {
                            reset_dir(&out, &work_dir)?;
                            synth::run(&args).map_err(cli_to_anyhow)?;
                            Ok(format!("{} {} shots of {}", s.shots, s.tier, s.material))
                        },
                    )
                    .map_err(CliError::Failed)?;
                inputs.push((f.name.clone(), out));
            }
        }
    }

    // Stage 2: extraction per folder.
    let mut folder_infos: Vec<FolderInfo> = Vec::new();
    let mut tables: Vec<PathBuf> = Vec::new();
    for (name, dir) in &inputs {
        let out = p.work_dir.join("extract").join(name);
        let table = out.join("angles.parquet");
        let overlays = p.extract.overlays.then(|| out.join("overlays"));
        let mut key = KeyHasher::new("extract");
        key.json("settings", &p.extract);
        key.field(
            "input",
            digest_dir(dir).map_err(CliError::Failed)?.as_bytes(),
        );
        let args = crate::extract::ExtractArgs {
            dirs: vec![dir.clone()],
            out: table.clone(),
            overlays: overlays.clone(),
            jobs: p.extract.jobs,
            shard: None,
            no_texture: false,
        };
        let table2 = table.clone();
        let work_dir = p.work_dir.clone();
        let out2 = out.clone();
        runner
            .stage(
                &format!("extract {name}"),
                &out,
                key.hex(),
                || table2.exists(),
                || {
                    reset_dir(&out2, &work_dir)?;
                    // Exit status 1 (some images `error`) is data for the report, not a failure.
                    crate::extract::run(&args).map_err(cli_to_anyhow)?;
                    let rows = read_angle_table(&args.out)?;
                    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
                    Ok(format!("{} images, {ok} measured", rows.len()))
                },
            )
            .map_err(CliError::Failed)?;
        let rows = read_angle_table(&table).map_err(CliError::Failed)?;
        folder_infos.push(FolderInfo {
            name: name.clone(),
            path: dir.clone(),
            overlays,
            rows,
        });
        tables.push(table);
    }
    let all_rows: Vec<ShotRow> = folder_infos
        .iter()
        .flat_map(|f| f.rows.iter().cloned())
        .collect();

    // Stage 3: fit.
    let fit_dir = p.work_dir.join("fit");
    let fit_file = fit_dir.join("fit.json");
    let mut key = KeyHasher::new("fit");
    key.json("settings", &p.fit);
    for t in &tables {
        key.field(
            "table",
            digest_file(t).map_err(CliError::Failed)?.as_bytes(),
        );
    }
    let fit_key = key.hex();
    let failures_file = fit_dir.join("fit_failures.json");
    let read_fit = |path: &Path| -> anyhow::Result<FitOutput> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
    };
    let read_failures = |path: &Path| -> anyhow::Result<Vec<(String, String)>> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
    };
    let fit_result = runner.stage(
        "fit",
        &fit_dir,
        fit_key,
        // A fit file written by another version of the fit's types counts as missing.
        || read_fit(&fit_file).is_ok() && read_failures(&failures_file).is_ok(),
        || {
            reset_dir(&fit_dir, &p.work_dir)?;
            // One material at a time: a material without enough shots must not cost the others
            // their fit.
            let mut names: Vec<String> = Vec::new();
            for r in &all_rows {
                if !names.contains(&r.material) {
                    names.push(r.material.clone());
                }
            }
            let mut out = FitOutput {
                fits: Vec::new(),
                residuals: Vec::new(),
            };
            let mut failures: Vec<(String, String)> = Vec::new();
            for m in &names {
                let opts = FitOptions {
                    material: Some(m.clone()),
                    ..fit_options.clone()
                };
                match fit::fit_materials(&all_rows, &opts) {
                    Ok(o) => {
                        out.fits.extend(o.fits);
                        out.residuals.extend(o.residuals);
                    }
                    Err(e) => failures.push((m.clone(), format!("{e:#}"))),
                }
            }
            report::write_atomic(&fit_file, fit::cli::to_json(&out)?.as_bytes())?;
            report::write_atomic(
                &failures_file,
                serde_json::to_string_pretty(&failures)?.as_bytes(),
            )?;
            let mut parts: Vec<String> = out
                .fits
                .iter()
                .map(|f| format!("{} {} ({} shots)", f.material, f.model, f.n_used))
                .collect();
            parts.extend(failures.iter().map(|(m, _)| format!("{m} FAILED")));
            Ok(parts.join("; "))
        },
    );
    let (fit_output, fit_failures) = match fit_result
        .and_then(|()| Ok((read_fit(&fit_file)?, read_failures(&failures_file)?)))
    {
        Ok((out, failures)) => (Some(out), failures),
        Err(e) => {
            // The report still shows the extraction and the paper's curves.
            let msg = format!("{e:#}");
            eprintln!("fit failed: {msg}");
            (None, vec![("all materials".to_string(), msg)])
        }
    };
    for (m, e) in &fit_failures {
        eprintln!("fit of {m} failed: {e}");
    }
    let fits: Vec<FitSummary> = fit_output
        .as_ref()
        .map(|o| {
            o.fits
                .iter()
                .map(|f| FitSummary::from_fit(f, materials.0.get(&f.material)))
                .collect()
        })
        .unwrap_or_default();

    // Stage 4: report.
    let mut key = KeyHasher::new("report");
    key.json("settings", &p.report);
    key.field("pipeline", text.as_bytes());
    key.field("materials", materials_digest.as_bytes());
    for t in &tables {
        key.field(
            "table",
            digest_file(t).map_err(CliError::Failed)?.as_bytes(),
        );
    }
    if fit_output.is_some() {
        key.field(
            "fit",
            digest_file(&fit_file).map_err(CliError::Failed)?.as_bytes(),
        );
    }
    for f in &folder_infos {
        if let Some(o) = &f.overlays
            && o.is_dir()
        {
            key.field(
                "overlays",
                digest_dir(o).map_err(CliError::Failed)?.as_bytes(),
            );
        }
    }
    let report_key = key.hex();
    let index = p.report_dir.join("index.html");
    let index2 = index.clone();
    let stages_before: Vec<StageInfo> = runner
        .records
        .iter()
        .map(|r| StageInfo {
            name: r.name.clone(),
            status: r.status.to_string(),
            seconds: r.seconds,
            key: r.key.clone(),
        })
        .collect();
    let input = ReportInput {
        title: p.title.clone(),
        rows: all_rows.clone(),
        fits: fits.clone(),
        residuals: fit_output
            .as_ref()
            .map(|o| o.residuals.clone())
            .unwrap_or_default(),
        materials: materials.clone(),
        folders: folder_infos,
        settings_text: text.clone(),
        settings_name: path.display().to_string(),
        stages: stages_before,
        gallery_per_folder: p.report.gallery,
        fit_settings: p.fit.describe(),
        fit_failures: fit_failures.clone(),
    };
    let report_dir = p.report_dir.clone();
    runner
        .stage(
            "report",
            &report_dir,
            report_key,
            || index2.exists(),
            || {
                std::fs::create_dir_all(&report_dir)?;
                // Figures and overlays of an earlier run with other materials must not linger.
                for sub in ["figures", "overlays"] {
                    let d = report_dir.join(sub);
                    if d.exists() {
                        std::fs::remove_dir_all(&d)
                            .with_context(|| format!("clearing {}", d.display()))?;
                    }
                }
                let out = report::write_report(&input, &report_dir)?;
                Ok(format!(
                    "{} figures, {} overlays → {}",
                    out.figures.len(),
                    out.gallery.len(),
                    out.index.display()
                ))
            },
        )
        .map_err(CliError::Failed)?;

    Ok(RunSummary {
        stages: runner.records,
        report_index: index,
        rows: all_rows,
        fits,
        fit_failures,
    })
}

fn synth_args(s: &SynthSettings, out: &Path, materials: &Path) -> Result<SynthArgs, CliError> {
    let tier = Tier::from_str(&s.tier, true).map_err(CliError::usage)?;
    let mut a = SynthArgs::new(out, tier, s.shots, s.seed);
    a.material = Some(s.material.clone());
    a.psi = s.psi.clone();
    a.spin = s.spin.clone();
    a.english = s.english.clone();
    if let Some(size) = &s.size {
        a.size = size.clone();
    }
    a.background = s.background;
    a.known_spin = s.known_spin;
    a.materials = Some(materials.to_path_buf());
    Ok(a)
}

/// The one-screen summary printed at the end of a run.
pub fn summary_text(s: &RunSummary) -> String {
    let mut out = String::new();
    out.push_str("stage                      status   seconds\n");
    for r in &s.stages {
        out.push_str(&format!(
            "{:<26} {:<8} {:>7.1}  {}\n",
            r.name, r.status, r.seconds, r.detail
        ));
    }
    let stats = report::ExtractionStats::of(&s.rows);
    out.push_str(&format!(
        "\nimages: {} ({} ok, {} declined, {} error)\n",
        stats.total, stats.ok, stats.declined, stats.error
    ));
    for (m, e) in &s.fit_failures {
        out.push_str(&format!("fit of {m}: FAILED: {e}\n"));
    }
    if !s.fits.is_empty() {
        out.push_str("\nmaterial    model        e               mu              mu0             mu'           shots\n");
        for f in &s.fits {
            let c = |i: usize, v: f64, e: Option<f64>| {
                if f.fitted[i] {
                    report::html::pm(v, e)
                } else {
                    "—".into()
                }
            };
            out.push_str(&format!(
                "{:<11} {:<12} {:<15} {:<15} {:<15} {:<13} {}\n",
                f.material,
                f.model,
                c(0, f.coeffs.e, f.errors.e),
                c(1, f.coeffs.mu, f.errors.mu),
                c(3, f.coeffs.mu_static, f.errors.mu_static),
                c(2, f.coeffs.mu_table, f.errors.mu_table),
                f.n_shots
            ));
        }
        for f in &s.fits {
            for n in f
                .notes
                .iter()
                .filter(|n| n.starts_with(crate::fit::POOR_FIT_NOTE))
            {
                out.push_str(&format!("warning: {}: {n}\n", f.material));
            }
        }
    }
    out.push_str(&format!("\nreport: {}\n", s.report_index.display()));
    out
}

pub fn run(args: &RunArgs) -> CliResult {
    let summary = run_pipeline(&args.pipeline, args.force)?;
    println!("{}", summary_text(&summary));
    let any_error = summary.rows.iter().any(|r| r.status == Status::Error);
    Ok(if !summary.fit_failures.is_empty() || any_error {
        Outcome::SomeFailed
    } else {
        Outcome::Ok
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_keys_carry_a_digest_of_the_running_executable() {
        let id = build_id();
        let exe = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        let digest = blake3::hash(&exe).to_hex();
        assert_eq!(
            id,
            format!("{}+{}", env!("CARGO_PKG_VERSION"), &digest[..16])
        );
        // The same build gives the same key; another build id would give another.
        let key = |id: &str| {
            let mut h = blake3::Hasher::new();
            h.update(b"streakfit-stage\0");
            h.update(id.as_bytes());
            h.update(b"\0");
            h.update(b"fit\0");
            h.finalize().to_hex()[..32].to_string()
        };
        assert_eq!(KeyHasher::new("fit").hex(), key(id));
        assert_ne!(KeyHasher::new("fit").hex(), key(env!("CARGO_PKG_VERSION")));
    }

    const MINIMAL: &str = r#"
name = "t"
[[folders]]
name = "steel"
[folders.synth]
material = "steel"
shots = 3
"#;

    #[test]
    fn minimal_pipeline_gets_defaults() {
        let p = Pipeline::parse(MINIMAL).unwrap();
        assert_eq!(p.name, "t");
        assert_eq!(p.work_dir, Path::new("work/t"));
        assert_eq!(p.report_dir, Path::new("reports/t"));
        assert_eq!(p.report.gallery, 12);
        assert!(p.extract.overlays);
        let Source::Synth(s) = &p.folders[0].source else {
            panic!()
        };
        assert_eq!((s.shots, s.seed, s.tier.as_str()), (3, 1, "clean"));
        assert_eq!(p.fit, FitSettings::default());
    }

    fn err_of(text: &str) -> String {
        Pipeline::parse(text).unwrap_err()
    }

    #[test]
    fn errors_name_the_key_and_the_problem() {
        let e = err_of(&MINIMAL.replace("shots = 3", "shots = \"ten\""));
        assert!(
            e.contains("folders[0].synth.shots") && e.contains("found a string"),
            "{e}"
        );
        let e = err_of(&MINIMAL.replace("shots = 3", "shots = 0"));
        assert!(
            e.contains("folders[0].synth.shots") && e.contains("minimum 1"),
            "{e}"
        );
        let e = err_of(&format!("{MINIMAL}\n[fit]\nregim = \"auto\"\n"));
        assert!(e.contains("fit.regim") && e.contains("unknown key"), "{e}");
        let e = err_of(&format!("{MINIMAL}\n[fit]\nregime = \"sideways\"\n"));
        assert!(e.contains("fit.regime"), "{e}");
        let e = err_of(&MINIMAL.replace("name = \"t\"", "name = \"a b\""));
        assert!(e.starts_with("key 'name'"), "{e}");
        let e = err_of("name = \"x\"\n");
        assert!(e.contains("'folders'") && e.contains("missing"), "{e}");
        let e = err_of(&MINIMAL.replace(
            "material = \"steel\"",
            "material = \"steel\"\ntier = \"easy\"",
        ));
        assert!(
            e.contains("folders[0].synth.tier") && e.contains("easy"),
            "{e}"
        );
        let e = err_of(&MINIMAL.replace("[folders.synth]", "path = \"x\"\n[folders.synth]"));
        assert!(
            e.contains("folders[0].synth") && e.contains("not both"),
            "{e}"
        );
        let e = err_of(&format!("{MINIMAL}\n[extract]\njobs = 0\n"));
        assert!(e.contains("extract.jobs"), "{e}");
        let e = err_of(&MINIMAL.replace("shots = 3", "shots = 3\npsi = \"80:5\""));
        assert!(e.contains("folders[0].synth.psi"), "{e}");
        let e = err_of("name = \n");
        assert!(e.starts_with("not valid TOML"), "{e}");
    }

    #[test]
    fn stage_keys_change_with_settings_and_inputs() {
        let mut a = KeyHasher::new("fit");
        a.json("settings", &FitSettings::default());
        let mut b = KeyHasher::new("fit");
        b.json(
            "settings",
            &FitSettings {
                bootstrap: 5,
                ..FitSettings::default()
            },
        );
        let mut c = KeyHasher::new("fit");
        c.json("settings", &FitSettings::default());
        assert_ne!(a.hex(), b.hex());
        assert_eq!(a.hex(), c.hex());
        assert_eq!(a.hex().len(), 32);
    }

    #[test]
    fn folder_digest_sees_content_and_ignores_hidden_files() {
        let dir = std::env::temp_dir().join(format!("streakfit-digest-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("a.png"), b"one").unwrap();
        std::fs::write(dir.join("sub/b.png"), b"two").unwrap();
        let d1 = digest_dir(&dir).unwrap();
        std::fs::write(dir.join(STAMP_FILE), b"{}").unwrap();
        assert_eq!(digest_dir(&dir).unwrap(), d1);
        std::fs::write(dir.join("sub/b.png"), b"twO").unwrap();
        assert_ne!(digest_dir(&dir).unwrap(), d1);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
