//! `truth.csv`: the exact parameters and angles behind every synthetic image.
//!
//! Angles are in the impact frame of `PHYSICS.md` (line of centres, mirrored so `psi ≥ 0`), in
//! degrees; an undefined angle (a ball at rest) is an empty cell. Pixel geometry is where things
//! appear in the image (after perspective, tilt and distortion): `impact_*_px` is the cue ball's
//! centre at impact, `object_*_px` the waiting object ball's centre, `ball_radius_px` the apparent
//! radius there (ball centres sit `R` above the cloth, so this exceeds
//! `ball_diameter_mm / 2 · px_per_mm`), `px_per_mm` the true cloth-level scale at the impact point
//! and `scene_px_per_mm` the perturbed "ruler reading" written to `scene.toml`. `rotation_deg` is
//! the on-screen counter-clockwise angle of the impact frame's `x` axis from the image's `+x`
//! axis; `mirrored = true` means the frame's `y` axis is `x` turned clockwise on screen.
//! `streak_contrast_grey` is the noise-free luma contrast of the incoming cue-ball streak's centre
//! line over the empty cloth (median along the streak). `*_image_deg` are the five angles as the
//! camera shows them (`synth::image_angles`): the same directions mapped through the tilted,
//! distorting camera and measured in the image, so `|image − table|` is the camera's part of an
//! extractor's error.

/// Column names of `truth.csv`, in order.
pub const COLUMNS: [&str; 39] = [
    "file",
    "material",
    "psi_deg",
    "delta1_deg",
    "delta2_deg",
    "theta1_deg",
    "theta2_deg",
    "e",
    "mu",
    "mu_table",
    "mu_static",
    "mass_ratio",
    "spin",
    "english",
    "speed_mps",
    "regime",
    "exposure_s",
    "t_impact_s",
    "impact_x_px",
    "impact_y_px",
    "object_x_px",
    "object_y_px",
    "ball_radius_px",
    "px_per_mm",
    "scene_px_per_mm",
    "rotation_deg",
    "mirrored",
    "tilt_deg",
    "distortion_k1",
    "cloth_mu_slide",
    "cloth_mu_roll",
    "stray_ball",
    "tier",
    "streak_contrast_grey",
    "psi_image_deg",
    "delta1_image_deg",
    "delta2_image_deg",
    "theta1_image_deg",
    "theta2_image_deg",
];

/// One row of `truth.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthRow {
    pub file: String,
    pub material: String,
    pub psi_deg: f64,
    pub delta1_deg: Option<f64>,
    pub delta2_deg: Option<f64>,
    pub theta1_deg: Option<f64>,
    pub theta2_deg: Option<f64>,
    pub e: f64,
    pub mu: f64,
    pub mu_table: f64,
    pub mu_static: f64,
    pub mass_ratio: f64,
    pub spin: f64,
    pub english: f64,
    pub speed_mps: f64,
    pub regime: String,
    pub exposure_s: f64,
    /// Time of the impact after the exposure starts.
    pub t_impact_s: f64,
    pub impact_x_px: f64,
    pub impact_y_px: f64,
    pub object_x_px: f64,
    pub object_y_px: f64,
    pub ball_radius_px: f64,
    pub px_per_mm: f64,
    pub scene_px_per_mm: f64,
    pub rotation_deg: f64,
    pub mirrored: bool,
    pub tilt_deg: f64,
    pub distortion_k1: f64,
    pub cloth_mu_slide: f64,
    pub cloth_mu_roll: f64,
    pub stray_ball: bool,
    pub tier: String,
    pub streak_contrast_grey: Option<f64>,
    /// The angles as the camera shows them (`synth::image_angles`): what a perfect measurement in
    /// the image reads without knowing the camera's tilt and distortion.
    pub psi_image_deg: f64,
    pub delta1_image_deg: Option<f64>,
    pub delta2_image_deg: Option<f64>,
    pub theta1_image_deg: Option<f64>,
    pub theta2_image_deg: Option<f64>,
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

/// A CSV field: quoted only if it needs to be.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl TruthRow {
    /// Cells in [`COLUMNS`] order. Floats use Rust's shortest round-trip formatting, so values
    /// read back bit-identical.
    pub fn cells(&self) -> Vec<String> {
        vec![
            field(&self.file),
            field(&self.material),
            self.psi_deg.to_string(),
            opt(self.delta1_deg),
            opt(self.delta2_deg),
            opt(self.theta1_deg),
            opt(self.theta2_deg),
            self.e.to_string(),
            self.mu.to_string(),
            self.mu_table.to_string(),
            self.mu_static.to_string(),
            self.mass_ratio.to_string(),
            self.spin.to_string(),
            self.english.to_string(),
            self.speed_mps.to_string(),
            field(&self.regime),
            self.exposure_s.to_string(),
            self.t_impact_s.to_string(),
            self.impact_x_px.to_string(),
            self.impact_y_px.to_string(),
            self.object_x_px.to_string(),
            self.object_y_px.to_string(),
            self.ball_radius_px.to_string(),
            self.px_per_mm.to_string(),
            self.scene_px_per_mm.to_string(),
            self.rotation_deg.to_string(),
            self.mirrored.to_string(),
            self.tilt_deg.to_string(),
            self.distortion_k1.to_string(),
            self.cloth_mu_slide.to_string(),
            self.cloth_mu_roll.to_string(),
            self.stray_ball.to_string(),
            field(&self.tier),
            opt(self.streak_contrast_grey),
            self.psi_image_deg.to_string(),
            opt(self.delta1_image_deg),
            opt(self.delta2_image_deg),
            opt(self.theta1_image_deg),
            opt(self.theta2_image_deg),
        ]
    }
}

/// CSV text of `rows` with a header line.
pub fn to_csv(rows: &[TruthRow]) -> String {
    let mut s = COLUMNS.join(",");
    s.push('\n');
    for r in rows {
        s.push_str(&r.cells().join(","));
        s.push('\n');
    }
    s
}

pub use crate::io::write_atomic;

/// Parses a `truth.csv` written by [`to_csv`] into rows of (column → cell). Intended for tests and
/// tools; handles the quoting [`to_csv`] produces.
pub fn read_csv(text: &str) -> Result<Vec<std::collections::BTreeMap<String, String>>, String> {
    let mut lines = text.lines();
    let header: Vec<String> = split_csv_line(lines.next().ok_or("truth.csv is empty")?);
    let mut out = Vec::new();
    for (i, line) in lines.enumerate() {
        if line.is_empty() {
            continue;
        }
        let cells = split_csv_line(line);
        if cells.len() != header.len() {
            return Err(format!(
                "truth.csv line {}: {} cells, header has {}",
                i + 2,
                cells.len(),
                header.len()
            ));
        }
        out.push(header.iter().cloned().zip(cells).collect());
    }
    Ok(out)
}

fn split_csv_line(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    cells.push(cur);
    cells
}
