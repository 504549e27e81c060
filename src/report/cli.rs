//! `streakfit report TABLE... --fit FITS.json [--residuals RES.json] [--overlays DIR] --out DIR`:
//! the report of [`super::write_report`] from files made by `streakfit extract` and
//! `streakfit fit` by hand (the pipeline's `report` stage does the same from its own stages).
//!
//! `--fit` takes the JSON of `streakfit fit --out FILE.json` (an array of material fits) or a
//! pipeline's `fit.json` (`{fits, residuals}`); `--residuals` the JSON of `--residuals FILE.json`.
//! Each table becomes one folder of the extraction statistics; `--overlays` (one per table, in
//! the same order) feeds the gallery.

use super::{FitSummary, FolderInfo, ReportInput};
use crate::cli::{CliError, CliResult, Outcome};
use crate::fit::{FitOutput, MaterialFit, ResidualRow};
use crate::synth::materials::Materials;
use crate::table::read_angle_table;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Debug, Args, Clone)]
pub struct ReportArgs {
    /// Angle tables (Parquet or CSV) from `streakfit extract`.
    #[arg(required = true)]
    pub tables: Vec<PathBuf>,
    /// Fitted coefficients: JSON from `streakfit fit --out FILE.json`.
    #[arg(long)]
    pub fit: Option<PathBuf>,
    /// Per-shot residuals: JSON from `streakfit fit --residuals FILE.json`.
    #[arg(long)]
    pub residuals: Option<PathBuf>,
    /// Overlay folder of each table (`extract --overlays`), in the order of the tables.
    #[arg(long)]
    pub overlays: Vec<PathBuf>,
    /// Report folder (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Title of the report.
    #[arg(long, default_value = "streakfit report")]
    pub title: String,
    /// Overlays per table in the gallery.
    #[arg(long, default_value_t = 12)]
    pub gallery: usize,
}

/// Reads `--fit`: an array of material fits, or an object with `fits` (and `residuals`).
pub fn read_fits(path: &Path) -> Result<(Vec<MaterialFit>, Vec<ResidualRow>), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("--fit: cannot read '{}': {e}", path.display()))?;
    if let Ok(out) = serde_json::from_str::<FitOutput>(&text) {
        return Ok((out.fits, out.residuals));
    }
    serde_json::from_str::<Vec<MaterialFit>>(&text)
        .map(|f| (f, Vec::new()))
        .map_err(|e| {
            format!(
                "--fit: '{}' is not the JSON of `streakfit fit`: {e}",
                path.display()
            )
        })
}

/// A folder name for table `i`: its file stem, or `PARENT-STEM` when another table has the same
/// stem (each extraction folder's table is `angles.parquet` in the pipeline), or with the index
/// appended when even that repeats. Names become sub-folders of the report's gallery.
pub fn folder_name(t: &Path, all: &[PathBuf], i: usize) -> String {
    let stem = |p: &Path| {
        p.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "table".into())
    };
    let parent = |p: &Path| {
        p.parent()
            .and_then(|d| d.file_name())
            .map(|s| s.to_string_lossy().into_owned())
    };
    let long = |p: &Path| match parent(p) {
        Some(d) => format!("{d}-{}", stem(p)),
        None => stem(p),
    };
    let clean = |s: String| -> String {
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    };
    if all.iter().filter(|p| stem(p) == stem(t)).count() == 1 {
        return clean(stem(t));
    }
    if all.iter().filter(|p| long(p) == long(t)).count() == 1 {
        return clean(long(t));
    }
    clean(format!("{}-{i}", long(t)))
}

pub fn run(args: &ReportArgs) -> CliResult {
    if !args.overlays.is_empty() && args.overlays.len() != args.tables.len() {
        return Err(CliError::usage(format!(
            "--overlays: give one folder per table ({} tables, {} folders)",
            args.tables.len(),
            args.overlays.len()
        )));
    }
    let materials = Materials::load(&Materials::default_path()).map_err(CliError::usage)?;
    let mut folders = Vec::new();
    for (i, t) in args.tables.iter().enumerate() {
        if !t.exists() {
            return Err(CliError::usage(format!(
                "table '{}' does not exist",
                t.display()
            )));
        }
        let rows = read_angle_table(t).map_err(|e| CliError::usage(format!("{e:#}")))?;
        let name = folder_name(t, &args.tables, i);
        folders.push(FolderInfo {
            name,
            path: t.clone(),
            overlays: args.overlays.get(i).cloned(),
            rows,
        });
    }
    let (fits, mut residuals) = match &args.fit {
        Some(p) => read_fits(p).map_err(CliError::usage)?,
        None => (Vec::new(), Vec::new()),
    };
    if let Some(p) = &args.residuals {
        let text = std::fs::read_to_string(p).map_err(|e| {
            CliError::usage(format!("--residuals: cannot read '{}': {e}", p.display()))
        })?;
        residuals = serde_json::from_str(&text).map_err(|e| {
            CliError::usage(format!(
                "--residuals: '{}' is not residuals JSON: {e}",
                p.display()
            ))
        })?;
    }
    let input = ReportInput {
        title: args.title.clone(),
        rows: folders
            .iter()
            .flat_map(|f| f.rows.iter().cloned())
            .collect(),
        fits: fits
            .iter()
            .map(|f| FitSummary::from_fit(f, materials.0.get(&f.material)))
            .collect(),
        residuals,
        materials,
        folders,
        settings_text: std::env::args().collect::<Vec<_>>().join(" "),
        settings_name: "command line".into(),
        stages: Vec::new(),
        gallery_per_folder: args.gallery,
        fit_settings: args
            .fit
            .as_ref()
            .map_or("no fit given".into(), |p| format!("from {}", p.display())),
        fit_failures: Vec::new(),
    };
    let out = super::write_report(&input, &args.out)?;
    eprintln!(
        "report: {} figures, {} overlays → {}",
        out.figures.len(),
        out.gallery.len(),
        out.index.display()
    );
    Ok(Outcome::Ok)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folder_names_are_unique() {
        let all: Vec<PathBuf> = [
            "w/steel/angles.parquet",
            "w/rubber/angles.parquet",
            "x/lab.csv",
            "y/lab.csv",
            "y2/y/lab.csv",
        ]
        .iter()
        .map(PathBuf::from)
        .collect();
        let names: Vec<String> = all
            .iter()
            .enumerate()
            .map(|(i, t)| folder_name(t, &all, i))
            .collect();
        assert_eq!(
            names,
            [
                "steel-angles",
                "rubber-angles",
                "x-lab",
                "y-lab-3",
                "y-lab-4"
            ]
        );
        let one = vec![PathBuf::from("a b/t 1.parquet")];
        assert_eq!(folder_name(&one[0], &one, 0), "t_1");
    }
}
