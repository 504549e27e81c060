//! Tables of the data path (polars DataFrames, Parquet or CSV by extension).
//!
//! The angles table has one row per input image: `file, status (ok|declined|error), reason,
//! material, psi_deg, delta1_deg, delta2_deg, theta1_deg, theta2_deg, *_err_deg (1 sigma),
//! frame_err_deg, path_model1, path_model2, cloth_model, ball_radius_px, impact_x_px,
//! impact_y_px, spin, english, seconds`. `frame_err_deg` is the part of every `*_err_deg` that a
//! row's five angles share: all are read from the photo's line of centres, and an error in its
//! direction moves them all by the same amount, same sign (`fit` fits it as one shift per row). `cloth_model` says what the cloth was modelled from: `plate` (an empty-table photo),
//! `texture` (the folder's fixed cloth texture on the photo's own surface) or `surface` (the
//! photo's own smooth surface only); null when the photo never got that far.
//! Undefined angles (a ball that stops) are nulls, never numbers. Positions (`impact_x_px`,
//! `impact_y_px`) are in pixels from the image's top-left corner, `x` right and `y` down, with
//! pixel `(i, j)` covering `[i, i + 1) × [j, j + 1)`: its centre is `(i + ½, j + ½)`, the
//! convention of the synthetic truth tables ([`PIXEL_CENTRE`]).

use serde::{Deserialize, Serialize};

/// Offset from the analysis's coordinates (pixel `i`'s value sampled at `i`) to the table's
/// (pixel `i` covers `[i, i + 1)`), added where a position enters a row.
pub const PIXEL_CENTRE: f64 = 0.5;

/// Outcome of one input image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Ok,
    Declined,
    Error,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Declined => "declined",
            Status::Error => "error",
        }
    }
}

/// One row of the angles table (the output of `extract`, the input of `fit`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShotRow {
    pub file: String,
    pub status: Status,
    pub reason: String,
    /// Material label from `scene.toml` (`unknown` when absent).
    pub material: String,
    pub psi_deg: Option<f64>,
    pub delta1_deg: Option<f64>,
    pub delta2_deg: Option<f64>,
    pub theta1_deg: Option<f64>,
    pub theta2_deg: Option<f64>,
    pub psi_err_deg: Option<f64>,
    pub delta1_err_deg: Option<f64>,
    pub delta2_err_deg: Option<f64>,
    pub theta1_err_deg: Option<f64>,
    pub theta2_err_deg: Option<f64>,
    /// 1-sigma of the line of centres' direction, the part of every `*_err_deg` that the five
    /// angles share (an error in it moves them all by the same amount, same sign).
    pub frame_err_deg: Option<f64>,
    /// Path model used per outgoing ball: `line` or `parabola+line`.
    pub path_model1: Option<String>,
    pub path_model2: Option<String>,
    /// Cloth model of the analysis: `plate`, `texture` or `surface`.
    pub cloth_model: Option<String>,
    pub ball_radius_px: Option<f64>,
    pub impact_x_px: Option<f64>,
    pub impact_y_px: Option<f64>,
    /// Known cue-ball spin `r` and English `s` (from `scene.toml` or the input table), if given.
    pub spin: Option<f64>,
    pub english: Option<f64>,
    /// Analysis time for this image.
    pub seconds: f64,
}

impl ShotRow {
    /// A row for an image that produced no measurement.
    pub fn failed(
        file: impl Into<String>,
        status: Status,
        reason: impl Into<String>,
        material: impl Into<String>,
    ) -> Self {
        Self {
            file: file.into(),
            status,
            reason: reason.into(),
            material: material.into(),
            psi_deg: None,
            delta1_deg: None,
            delta2_deg: None,
            theta1_deg: None,
            theta2_deg: None,
            psi_err_deg: None,
            delta1_err_deg: None,
            delta2_err_deg: None,
            theta1_err_deg: None,
            theta2_err_deg: None,
            frame_err_deg: None,
            path_model1: None,
            path_model2: None,
            cloth_model: None,
            ball_radius_px: None,
            impact_x_px: None,
            impact_y_px: None,
            spin: None,
            english: None,
            seconds: 0.0,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// IO: Parquet or CSV by file extension.

use anyhow::{Context, Result, anyhow, bail};
use polars::prelude::{
    Column, CsvReadOptions, CsvWriter, DataFrame, DataType, ParquetReader, ParquetWriter,
    SerReader, SerWriter,
};
use std::path::Path;

/// Float columns of the angles table, in output order (after the string columns).
const FLOAT_COLUMNS: [&str; 17] = [
    "psi_deg",
    "delta1_deg",
    "delta2_deg",
    "theta1_deg",
    "theta2_deg",
    "psi_err_deg",
    "delta1_err_deg",
    "delta2_err_deg",
    "theta1_err_deg",
    "theta2_err_deg",
    "frame_err_deg",
    "ball_radius_px",
    "impact_x_px",
    "impact_y_px",
    "spin",
    "english",
    "seconds",
];

/// Table format chosen from a path's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableFormat {
    Parquet,
    Csv,
}

impl TableFormat {
    /// `.parquet`/`.pq` → Parquet, `.csv` → CSV; anything else is an error naming the path.
    pub fn from_path(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("parquet") | Some("pq") => Ok(TableFormat::Parquet),
            Some("csv") => Ok(TableFormat::Csv),
            _ => bail!(
                "table '{}': unknown extension (expected .parquet or .csv)",
                path.display()
            ),
        }
    }
}

fn float_of(row: &ShotRow, name: &str) -> Option<f64> {
    match name {
        "psi_deg" => row.psi_deg,
        "delta1_deg" => row.delta1_deg,
        "delta2_deg" => row.delta2_deg,
        "theta1_deg" => row.theta1_deg,
        "theta2_deg" => row.theta2_deg,
        "psi_err_deg" => row.psi_err_deg,
        "delta1_err_deg" => row.delta1_err_deg,
        "delta2_err_deg" => row.delta2_err_deg,
        "theta1_err_deg" => row.theta1_err_deg,
        "theta2_err_deg" => row.theta2_err_deg,
        "frame_err_deg" => row.frame_err_deg,
        "ball_radius_px" => row.ball_radius_px,
        "impact_x_px" => row.impact_x_px,
        "impact_y_px" => row.impact_y_px,
        "spin" => row.spin,
        "english" => row.english,
        "seconds" => Some(row.seconds),
        _ => None,
    }
}

/// The rows as a polars DataFrame with the documented columns.
pub fn angle_table_frame(rows: &[ShotRow]) -> Result<DataFrame> {
    let strings = |f: &dyn Fn(&ShotRow) -> Option<String>| -> Vec<Option<String>> {
        rows.iter().map(f).collect()
    };
    let mut cols: Vec<Column> = vec![
        Column::new("file".into(), strings(&|r| Some(r.file.clone()))),
        Column::new(
            "status".into(),
            strings(&|r| Some(r.status.as_str().to_string())),
        ),
        Column::new("reason".into(), strings(&|r| Some(r.reason.clone()))),
        Column::new("material".into(), strings(&|r| Some(r.material.clone()))),
    ];
    for name in FLOAT_COLUMNS {
        let v: Vec<Option<f64>> = rows.iter().map(|r| float_of(r, name)).collect();
        cols.push(Column::new(name.into(), v));
    }
    cols.push(Column::new(
        "path_model1".into(),
        strings(&|r| r.path_model1.clone()),
    ));
    cols.push(Column::new(
        "path_model2".into(),
        strings(&|r| r.path_model2.clone()),
    ));
    cols.push(Column::new(
        "cloth_model".into(),
        strings(&|r| r.cloth_model.clone()),
    ));
    Ok(DataFrame::new(rows.len(), cols)?)
}

/// Writes the angles table atomically (temp file in the same folder, then rename), as Parquet
/// or CSV by the path's extension.
pub fn write_angle_table(path: impl AsRef<Path>, rows: &[ShotRow]) -> Result<()> {
    let path = path.as_ref();
    let format = TableFormat::from_path(path)?;
    let mut df = angle_table_frame(rows)?;
    write_frame_atomic(path, format, &mut df)
}

/// Writes any DataFrame atomically as Parquet or CSV (by `format`).
pub fn write_frame_atomic(path: &Path, format: TableFormat, df: &mut DataFrame) -> Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| anyhow!("table path '{}' has no file name", path.display()))?
        .to_string_lossy()
        .into_owned();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| -> Result<()> {
        let file = std::fs::File::create(&tmp)
            .with_context(|| format!("cannot create '{}'", tmp.display()))?;
        match format {
            TableFormat::Parquet => {
                ParquetWriter::new(file).finish(df)?;
            }
            TableFormat::Csv => {
                CsvWriter::new(file).include_header(true).finish(df)?;
            }
        }
        std::fs::rename(&tmp, path)
            .with_context(|| format!("cannot rename to '{}'", path.display()))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("writing table '{}'", path.display()))
}

/// Reads a DataFrame from Parquet or CSV by extension.
pub fn read_frame(path: &Path) -> Result<DataFrame> {
    let format = TableFormat::from_path(path)?;
    let df = match format {
        TableFormat::Parquet => {
            let file = std::fs::File::open(path)
                .with_context(|| format!("cannot open table '{}'", path.display()))?;
            ParquetReader::new(file).finish()?
        }
        TableFormat::Csv => CsvReadOptions::default()
            .with_has_header(true)
            .with_infer_schema_length(None)
            .try_into_reader_with_file_path(Some(path.to_path_buf()))?
            .finish()
            .with_context(|| format!("cannot parse CSV table '{}'", path.display()))?,
    };
    Ok(df)
}

/// Reads an angles table (Parquet or CSV by extension). Besides tables written by
/// [`write_angle_table`], it accepts hand-made tables that carry only
/// `material, psi_deg, delta1_deg, delta2_deg, theta1_deg, theta2_deg` and optionally
/// `*_err_deg`, `spin`, `english`, `status`, `reason`, `file`: missing optional columns become
/// nulls, a missing `status` means `ok`, a missing `file` becomes `row N` (1-based).
pub fn read_angle_table(path: impl AsRef<Path>) -> Result<Vec<ShotRow>> {
    let path = path.as_ref();
    let df = read_frame(path)?;
    rows_from_frame(&df).with_context(|| format!("table '{}'", path.display()))
}

/// Converts a DataFrame with the angles-table columns into rows (see [`read_angle_table`]).
pub fn rows_from_frame(df: &DataFrame) -> Result<Vec<ShotRow>> {
    let n = df.height();
    let names: Vec<String> = df
        .get_column_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let has = |c: &str| names.iter().any(|n| n == c);
    for required in [
        "material",
        "psi_deg",
        "delta1_deg",
        "delta2_deg",
        "theta1_deg",
        "theta2_deg",
    ] {
        if !has(required) {
            bail!("missing required column '{required}'");
        }
    }
    let floats = |name: &str| -> Result<Vec<Option<f64>>> {
        if !has(name) {
            return Ok(vec![None; n]);
        }
        let col = df.column(name)?;
        let cast = col
            .cast(&DataType::Float64)
            .with_context(|| format!("column '{name}' is not numeric"))?;
        let ca = cast.f64()?;
        // A non-numeric string in a numeric column casts to null: report it instead.
        if col.dtype() == &DataType::String {
            let s = col.str()?;
            for i in 0..n {
                if let (Some(text), None) = (s.get(i), ca.get(i)) {
                    let t = text.trim();
                    if !t.is_empty()
                        && !t.eq_ignore_ascii_case("null")
                        && !t.eq_ignore_ascii_case("nan")
                    {
                        bail!("column '{name}', row {}: '{text}' is not a number", i + 1);
                    }
                }
            }
        }
        Ok((0..n)
            .map(|i| ca.get(i).filter(|v| v.is_finite()))
            .collect())
    };
    let strings = |name: &str| -> Result<Vec<Option<String>>> {
        if !has(name) {
            return Ok(vec![None; n]);
        }
        let cast = df.column(name)?.cast(&DataType::String)?;
        let ca = cast.str()?;
        Ok((0..n).map(|i| ca.get(i).map(str::to_string)).collect())
    };
    let file = strings("file")?;
    let status = strings("status")?;
    let reason = strings("reason")?;
    let material = strings("material")?;
    let pm1 = strings("path_model1")?;
    let pm2 = strings("path_model2")?;
    let cloth = strings("cloth_model")?;
    let mut f: std::collections::HashMap<&str, Vec<Option<f64>>> = Default::default();
    for name in FLOAT_COLUMNS {
        f.insert(name, floats(name)?);
    }
    let g = |name: &str, i: usize| f[name][i];
    let mut rows = Vec::with_capacity(n);
    for i in 0..n {
        let st = match status[i].as_deref().map(|s| s.trim().to_ascii_lowercase()) {
            None => Status::Ok,
            Some(s) if s.is_empty() || s == "ok" => Status::Ok,
            Some(s) if s == "declined" => Status::Declined,
            Some(s) if s == "error" => Status::Error,
            Some(s) => bail!(
                "column 'status', row {}: '{s}' (expected ok, declined or error)",
                i + 1
            ),
        };
        rows.push(ShotRow {
            file: file[i].clone().unwrap_or_else(|| format!("row {}", i + 1)),
            status: st,
            reason: reason[i].clone().unwrap_or_default(),
            material: material[i]
                .clone()
                .filter(|m| !m.trim().is_empty())
                .unwrap_or_else(|| "unknown".to_string()),
            psi_deg: g("psi_deg", i),
            delta1_deg: g("delta1_deg", i),
            delta2_deg: g("delta2_deg", i),
            theta1_deg: g("theta1_deg", i),
            theta2_deg: g("theta2_deg", i),
            psi_err_deg: g("psi_err_deg", i),
            delta1_err_deg: g("delta1_err_deg", i),
            delta2_err_deg: g("delta2_err_deg", i),
            theta1_err_deg: g("theta1_err_deg", i),
            theta2_err_deg: g("theta2_err_deg", i),
            frame_err_deg: g("frame_err_deg", i),
            path_model1: pm1[i].clone(),
            path_model2: pm2[i].clone(),
            cloth_model: cloth[i].clone(),
            ball_radius_px: g("ball_radius_px", i),
            impact_x_px: g("impact_x_px", i),
            impact_y_px: g("impact_y_px", i),
            spin: g("spin", i),
            english: g("english", i),
            seconds: g("seconds", i).unwrap_or(0.0),
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<ShotRow> {
        let mut a = ShotRow::failed("img_001.png", Status::Ok, "", "steel");
        a.psi_deg = Some(30.5);
        a.delta1_deg = Some(85.25);
        a.delta2_deg = Some(-3.5);
        a.theta1_deg = Some(60.0);
        a.theta2_deg = None;
        a.psi_err_deg = Some(0.2);
        a.theta1_err_deg = Some(0.4);
        a.frame_err_deg = Some(0.15);
        a.path_model1 = Some("parabola+line".into());
        a.spin = Some(1.0);
        a.seconds = 0.75;
        let b = ShotRow::failed("img_002.png", Status::Declined, "no impact found", "steel");
        vec![a, b]
    }

    #[test]
    fn round_trip_csv_and_parquet() {
        let dir = std::env::temp_dir().join(format!("streakfit_table_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for ext in ["csv", "parquet"] {
            let p = dir.join(format!("angles.{ext}"));
            write_angle_table(&p, &sample()).unwrap();
            let back = read_angle_table(&p).unwrap();
            assert_eq!(back, sample(), "{ext}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn hand_made_csv_minimal_columns() {
        let dir = std::env::temp_dir().join(format!("streakfit_hand_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("hand.csv");
        std::fs::write(
            &p,
            "material,psi_deg,delta1_deg,delta2_deg,theta1_deg,theta2_deg,theta1_err_deg\n\
             rubber,20,70.5,3,45,10,0.5\nrubber,40,,2.5,60,12,\n",
        )
        .unwrap();
        let rows = read_angle_table(&p).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].status, Status::Ok);
        assert_eq!(rows[0].file, "row 1");
        assert_eq!(rows[1].delta1_deg, None);
        assert_eq!(rows[0].theta1_err_deg, Some(0.5));
        assert_eq!(rows[1].theta2_deg, Some(12.0));
        assert_eq!(rows[0].spin, None);
        std::fs::write(&p, "material,psi_deg,delta1_deg\nx,1,2\n").unwrap();
        let err = format!("{:#}", read_angle_table(&p).unwrap_err());
        assert!(err.contains("delta2_deg"), "{err}");
        std::fs::write(
            &p,
            "material,psi_deg,delta1_deg,delta2_deg,theta1_deg,theta2_deg\nx,abc,2,3,4,5\n",
        )
        .unwrap();
        let err = format!("{:#}", read_angle_table(&p).unwrap_err());
        assert!(err.contains("psi_deg") && err.contains("abc"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
