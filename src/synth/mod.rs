//! `streakfit synth`: synthetic long-exposure photographs of shots with exact ground truth.
//!
//! Each shot follows the paper's experiment (Section 3): a camera 75 cm above the impact point,
//! a cue ball arriving at `0.75 ± 0.05 m/s`, an exposure of 1.2–2.0 s during which the impact
//! happens at a random fraction (35–65 %) of the exposure. Until the impact the object ball waits
//! (a bright disc); the cue ball's incoming line, the impact ([`impulse::solve`], auto regime) and
//! both balls' sliding parabolas and rolling lines ([`BallPath`]) are drawn as exposure-weighted
//! streaks by [`render`]; a ball that stops within the exposure leaves a disc where it rests.
//! Geometry and photometry are described in [`camera`] and [`render`]; the outputs in
//! [`truth`] and [`crate::scene`].
//!
//! Tiers (all: random in-plane rotation and mirroring of the whole scene):
//! - `clean`: one material, rolling cue ball (`r = 1, s = 0`), `psi ∈ [5°, 75°]`, level camera,
//!   weak noise, PNG, streak contrast ≈ 8–18 grey levels for billiard balls.
//! - `realistic`: mixed materials, follow/stun/draw and English, coloured object ball, blue or
//!   green cloth, tilt ≤ 1°, slight barrel distortion, moderate noise, JPEG; contrast ≈ 4–13.
//! - `hard`: contrast of a few grey levels (≈ 1–5), strong noise, tilt ≤ 3°, barrel distortion,
//!   head-on (`psi < 5°`) and grazing (`psi > 75°`) shots, a stray ball crossing the streaks,
//!   the impact near the frame edge so paths leave early, JPEG.
//!
//! `--spin-modes rolling|mixed` overrides the tier's spin (e.g. a clean folder of one material
//! with follow, stun, draw and English shots, for fitting unknown spin).
//!
//! Randomness: one ChaCha stream per folder draws the folder's table and one seed per shot; each
//! shot draws everything else from its own stream, and each image band has its own noise stream,
//! so output is byte-identical for a seed whatever the thread count.

pub mod bound;
pub mod camera;
pub mod materials;
pub mod render;
pub mod truth;

use crate::cli::{CliError, CliResult, Outcome};
use crate::physics::path::{BallPath, Cloth};
use crate::physics::{RegimeChoice, Shot, impulse};
use crate::scene::{ImageScene, SceneConfig};
use camera::Camera;
use clap::{Args, ValueEnum};
use image::{ExtendedColorType, ImageEncoder, RgbImage};
use materials::{Material, Materials};
use nalgebra::Vector2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use render::{Backdrop, Disc, Frame, Segment};
use std::path::PathBuf;
use truth::TruthRow;

/// Difficulty tier of a synthetic folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Tier {
    Clean,
    Realistic,
    Hard,
}

impl Tier {
    pub fn name(self) -> &'static str {
        match self {
            Tier::Clean => "clean",
            Tier::Realistic => "realistic",
            Tier::Hard => "hard",
        }
    }

    /// Stated range of the incoming cue-ball streak contrast (grey levels of luma over the empty
    /// cloth) for billiard and rubber balls; steel balls (25 mm) give about half of it.
    pub fn contrast_range(self) -> (f64, f64) {
        match self {
            Tier::Clean => (8.0, 18.0),
            Tier::Realistic => (4.0, 13.0),
            Tier::Hard => (1.0, 5.0),
        }
    }

    /// Target contrast that sets the folder's lamp level (for billiard balls, 1.6 s exposure).
    fn target_contrast(self) -> f64 {
        match self {
            Tier::Clean => 12.0,
            Tier::Realistic => 8.5,
            Tier::Hard => 2.6,
        }
    }
}

/// How the cue ball's spin of each shot is drawn (`--spin-modes`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpinModes {
    /// Rolling cue ball, `r = 1, s = 0` (the paper's track experiments).
    Rolling,
    /// One of rolling (`r = 1`), follow (`r ∈ [1, 1.6)`), stun (`|r| < 0.1`) or draw
    /// (`r ∈ [-1.2, -0.3)`), equally likely, with English `s ∈ [-0.4, 0.4)` in 40 % of shots.
    Mixed,
}

/// Image file format of the shots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ImgFormat {
    Png,
    Jpg,
}

#[derive(Debug, Args, Clone)]
pub struct SynthArgs {
    /// Output folder (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// billiard, steel, rubber (presets in datasets/materials.toml) or mixed
    /// [default: mixed for --tier realistic, billiard otherwise].
    #[arg(long)]
    pub material: Option<String>,
    /// Number of shots.
    #[arg(long, default_value_t = 10)]
    pub shots: usize,
    /// Random seed; the same seed gives byte-identical output.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, value_enum, default_value_t = Tier::Clean)]
    pub tier: Tier,
    /// Impact angle range A:B in degrees (uniform), 0 ≤ A ≤ B < 90.
    #[arg(long, allow_hyphen_values = true)]
    pub psi: Option<String>,
    /// Cue-ball spin range A:B of r = R omega / v at impact (uniform).
    #[arg(long, allow_hyphen_values = true)]
    pub spin: Option<String>,
    /// Sidespin range A:B of s = R omega_z / v at impact (uniform).
    #[arg(long, allow_hyphen_values = true)]
    pub english: Option<String>,
    /// Cue-ball spin modes in the folder: rolling, or mixed follow/stun/draw with English
    /// [default: rolling for clean, mixed otherwise]. --spin/--english ranges override.
    #[arg(long, value_enum)]
    pub spin_modes: Option<SpinModes>,
    /// Image format [default: png for clean, jpg otherwise].
    #[arg(long, value_enum)]
    pub format: Option<ImgFormat>,
    /// Image size WxH in pixels.
    #[arg(long, default_value = "2400x1600")]
    pub size: String,
    /// Also write background.png (the empty table, same light, own noise) and name it in scene.toml.
    #[arg(long)]
    pub background: bool,
    /// Write the cue ball's spin and english into scene.toml (as if known).
    #[arg(long)]
    pub known_spin: bool,
    /// Print render and encode times per image.
    #[arg(long)]
    pub timing: bool,
    /// Materials file [default: $STREAKFIT_MATERIALS or datasets/materials.toml].
    #[arg(long)]
    pub materials: Option<PathBuf>,
}

impl SynthArgs {
    /// Arguments with the defaults of the command line.
    pub fn new(out: impl Into<PathBuf>, tier: Tier, shots: usize, seed: u64) -> Self {
        SynthArgs {
            out: out.into(),
            material: None,
            shots,
            seed,
            tier,
            psi: None,
            spin: None,
            english: None,
            spin_modes: None,
            format: None,
            size: "2400x1600".into(),
            background: false,
            known_spin: false,
            timing: false,
            materials: None,
        }
    }
}

/// Parses `A:B` (A ≤ B, both finite) for flag `flag`.
pub fn parse_range(flag: &str, s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = s.split(':').collect();
    let num = |p: &str| -> Result<f64, String> {
        p.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("--{flag}: '{p}' is not a finite number"))
    };
    match parts.as_slice() {
        [a] => {
            let a = num(a)?;
            Ok((a, a))
        }
        [a, b] => {
            let (a, b) = (num(a)?, num(b)?);
            if b < a {
                return Err(format!("--{flag}: range {a}:{b} must have A ≤ B"));
            }
            Ok((a, b))
        }
        _ => Err(format!(
            "--{flag}: '{s}' is neither a value nor a range A:B"
        )),
    }
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("--size: '{s}' is not WxH (e.g. 2400x1600)"))?;
    let p = |v: &str| -> Result<u32, String> {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (64..=12000).contains(n))
            .ok_or_else(|| format!("--size: '{v}' must be an integer in 64..=12000"))
    };
    Ok((p(w)?, p(h)?))
}

/// A ball rolling across the table, unrelated to the shot (hard tier): a streak that crosses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stray {
    /// Position at the start of the exposure and velocity (impact frame, m and m/s).
    pub p0: Vector2<f64>,
    pub v: Vector2<f64>,
    pub rgb: [f32; 3],
}

/// Everything random about one shot, drawn before any rendering.
#[derive(Debug, Clone, PartialEq)]
pub struct ShotPlan {
    pub index: usize,
    pub file: String,
    pub material_name: String,
    pub material: Material,
    pub shot: Shot,
    pub speed_mps: f64,
    pub exposure_s: f64,
    /// Fraction of the exposure elapsed at the impact.
    pub impact_fraction: f64,
    pub camera: Camera,
    pub cue_rgb: [f32; 3],
    pub object_rgb: [f32; 3],
    pub specular: f32,
    pub stray: Option<Stray>,
    pub noise_seed: u64,
    pub scene_px_per_mm: f64,
    pub jpeg_quality: u8,
}

/// A planned folder: the table (shared by all shots) and the shots.
#[derive(Debug, Clone, PartialEq)]
pub struct FolderPlan {
    pub tier: Tier,
    pub format: ImgFormat,
    pub backdrop: Backdrop,
    pub plate_seed: u64,
    pub shots: Vec<ShotPlan>,
}

const OBJECT_PALETTE: [[f32; 3]; 8] = [
    [0.85, 0.62, 0.10], // yellow
    [0.10, 0.18, 0.62], // blue
    [0.78, 0.12, 0.08], // red
    [0.38, 0.14, 0.50], // purple
    [0.90, 0.42, 0.08], // orange
    [0.10, 0.48, 0.22], // green
    [0.48, 0.10, 0.09], // maroon
    [0.06, 0.06, 0.06], // black
];

fn uniform(rng: &mut ChaCha8Rng, (a, b): (f64, f64)) -> f64 {
    if b > a { rng.gen_range(a..b) } else { a }
}

fn luma32(c: [f32; 3]) -> f64 {
    render::luma(c.map(f64::from))
}

/// Draws the folder and every shot from the seed. Pure: the same arguments give the same plan.
pub fn plan(args: &SynthArgs, mats: &Materials) -> Result<FolderPlan, String> {
    if args.shots == 0 {
        return Err("--shots must be at least 1".into());
    }
    let (width, height) = parse_size(&args.size)?;
    let psi_range = args
        .psi
        .as_deref()
        .map(|s| parse_range("psi", s))
        .transpose()?;
    if let Some((a, b)) = psi_range
        && (a < 0.0 || b >= 90.0)
    {
        return Err(format!("--psi: range {a}:{b} must lie in [0, 90)"));
    }
    let spin_range = args
        .spin
        .as_deref()
        .map(|s| parse_range("spin", s))
        .transpose()?;
    let english_range = args
        .english
        .as_deref()
        .map(|s| parse_range("english", s))
        .transpose()?;
    let tier = args.tier;
    let material_choice = args.material.clone().unwrap_or_else(|| {
        if tier == Tier::Realistic {
            "mixed".into()
        } else {
            "billiard".into()
        }
    });
    let pool: Vec<String> = if material_choice == "mixed" {
        mats.names()
    } else {
        mats.get(&material_choice)
            .map_err(|e| format!("--material: {e}"))?;
        vec![material_choice.clone()]
    };
    let format = args.format.unwrap_or(match tier {
        Tier::Clean => ImgFormat::Png,
        _ => ImgFormat::Jpg,
    });

    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    // The table and lamp are shared by the folder, so one background plate fits every shot.
    let cloth_rgb: [f32; 3] = match tier {
        Tier::Clean => [0.045, 0.15, 0.075],
        Tier::Realistic => {
            if rng.gen_bool(0.5) {
                [0.045, 0.15, 0.075]
            } else {
                [0.04, 0.085, 0.17]
            }
        }
        Tier::Hard => {
            // Worn, light cloth: little contrast between a white ball and the cloth.
            if rng.gen_bool(0.5) {
                [0.16, 0.42, 0.24]
            } else {
                [0.14, 0.28, 0.46]
            }
        }
    };
    let (texture, grad, vignette, noise_a, noise_b) = match tier {
        Tier::Clean => (0.03, 0.05, 0.08, 0.05, 0.3),
        Tier::Realistic => (0.06, 0.15, 0.2, 0.3, 2.0),
        Tier::Hard => (0.08, 0.25, 0.3, 1.0, 12.0),
    };
    // Lamp level: the tier's target contrast for a reference shot (the folder's first material,
    // or billiard when mixed; v = 0.75 m/s, T = 1.6 s): contrast = f (b_cue − a_cloth) L with
    // f = 2R/(vT) on the streak's centre line. Kept within a plausible cloth brightness.
    let ref_mat = mats.get(if pool.len() == 1 {
        &pool[0]
    } else {
        "billiard"
    })?;
    let alpha_ref = ref_mat.diameter_mm * 1e-3 / (0.75 * 1.6);
    let cloth_luma = luma32(cloth_rgb);
    let cue_luma = luma32(ref_mat.cue_rgb.map(|c| c as f32)) * render::MOVING_SHADE as f64;
    let lamp = (tier.target_contrast() / (alpha_ref * (cue_luma - cloth_luma)))
        .clamp(12.0 / cloth_luma, 120.0 / cloth_luma);
    let backdrop = Backdrop {
        width,
        height,
        cloth_rgb,
        texture,
        texture_seed: rng.r#gen(),
        lamp,
        gradient: [rng.gen_range(-grad..=grad), rng.gen_range(-grad..=grad)],
        vignette,
        light: [rng.gen_range(-0.4..0.4), rng.gen_range(-0.4..0.4), 1.0],
        noise_a,
        noise_b,
    };
    let plate_seed: u64 = rng.r#gen();
    let base_px_per_mm = 3.5 * width as f64 / 2400.0
        * match tier {
            Tier::Clean => 1.0,
            _ => rng.gen_range(0.9..1.1),
        };
    let digits = args.shots.to_string().len().max(3);
    let ext = match format {
        ImgFormat::Png => "png",
        ImgFormat::Jpg => "jpg",
    };

    let mut shots = Vec::with_capacity(args.shots);
    for index in 0..args.shots {
        let mut r = ChaCha8Rng::seed_from_u64(rng.r#gen());
        let material_name = pool[r.gen_range(0..pool.len())].clone();
        let material = mats.get(&material_name)?.clone();
        let psi_deg = match (psi_range, tier) {
            (Some(range), _) => uniform(&mut r, range),
            (None, Tier::Clean) => r.gen_range(5.0..75.0),
            (None, Tier::Realistic) => r.gen_range(0.0..80.0),
            (None, Tier::Hard) => match r.gen_range(0..3) {
                0 => r.gen_range(0.0..5.0),
                1 => r.gen_range(75.0..85.0),
                _ => r.gen_range(5.0..75.0),
            },
        };
        // Follow, stun, draw and plain rolling, sometimes with English, beyond the clean tier
        // (or wherever asked for). The draws stay where they were, so a seed's folder without
        // --spin-modes is unchanged.
        let modes = args.spin_modes.unwrap_or(if tier == Tier::Clean {
            SpinModes::Rolling
        } else {
            SpinModes::Mixed
        });
        let (spin, english) = if tier == Tier::Clean && modes == SpinModes::Rolling {
            (1.0, 0.0)
        } else {
            let spin = match r.gen_range(0..4) {
                0 => 1.0,
                1 => r.gen_range(1.0..1.6),
                2 => r.gen_range(-0.1..0.1),
                _ => r.gen_range(-1.2..-0.3),
            };
            let english = if r.gen_bool(0.4) {
                r.gen_range(-0.4..0.4)
            } else {
                0.0
            };
            if modes == SpinModes::Rolling {
                (1.0, 0.0)
            } else {
                (spin, english)
            }
        };
        let spin = spin_range.map_or(spin, |rg| uniform(&mut r, rg));
        let english = english_range.map_or(english, |rg| uniform(&mut r, rg));
        let shot = Shot {
            psi: psi_deg.to_radians(),
            mass_ratio: 1.0,
            spin,
            english,
        };
        shot.validate()?;
        let speed_mps = r.gen_range(0.70..0.80);
        // Camera shutter settings come in tenths of a second.
        let exposure_s = (r.gen_range(1.2f64..2.0) * 10.0).round() / 10.0;
        let impact_fraction = r.gen_range(0.35..0.65);
        let height_m = match tier {
            Tier::Clean => 0.75,
            _ => r.gen_range(0.73..0.77),
        };
        let mut camera = Camera::level(width, height, base_px_per_mm, 0.75);
        // Same lens, camera raised or lowered: the cloth scale changes with 1/height.
        camera.height_m = height_m;
        let (tilt_max, k1_range, offset_frac) = match tier {
            Tier::Clean => (0.0, (0.0, 0.0), 0.1),
            Tier::Realistic => (1.0, (-0.02, 0.0), 0.25),
            Tier::Hard => (3.0, (-0.06, -0.02), 0.55),
        };
        if tilt_max > 0.0 {
            camera = camera.with_tilt(
                r.gen_range(0.0..tilt_max),
                r.gen_range(0.0..std::f64::consts::TAU),
            );
        }
        camera.k1 = uniform(&mut r, k1_range);
        camera.rotation = r.gen_range(0.0..std::f64::consts::TAU);
        camera.mirrored = r.gen_bool(0.5);
        let half_w = 0.5 * width as f64 / camera.f_px * height_m;
        let half_h = 0.5 * height as f64 / camera.f_px * height_m;
        camera.offset = Vector2::new(
            r.gen_range(-offset_frac..=offset_frac) * half_w,
            r.gen_range(-offset_frac..=offset_frac) * half_h,
        );
        let cue_rgb = material.cue_rgb.map(|c| c as f32);
        let object_rgb = if tier == Tier::Clean || material_name == "steel" {
            material.object_rgb.map(|c| c as f32)
        } else {
            let n = if tier == Tier::Hard { 8 } else { 7 };
            OBJECT_PALETTE[r.gen_range(0..n)]
        };
        let stray = (tier == Tier::Hard && r.gen_bool(0.5)).then(|| {
            let dir = r.gen_range(0.0..std::f64::consts::TAU);
            let v = Vector2::new(dir.cos(), dir.sin()) * r.gen_range(0.25..0.5);
            // Passes within 15 cm of the impact point at mid-exposure.
            let through = Vector2::new(r.gen_range(-0.15..0.15), r.gen_range(-0.15..0.15));
            let t_mid = exposure_s * (0.5 - impact_fraction);
            Stray {
                p0: through - v * (t_mid + impact_fraction * exposure_s),
                v,
                rgb: OBJECT_PALETTE[r.gen_range(0..7)],
            }
        });
        let noise_seed = r.r#gen();
        let ruler = camera.px_per_mm_at(Vector2::zeros());
        let normal = Normal::new(0.0, 0.01).expect("valid sigma");
        let scene_px_per_mm = (ruler * (1.0 + normal.sample(&mut r)) * 1000.0).round() / 1000.0;
        let jpeg_quality = match tier {
            Tier::Clean => 95,
            Tier::Realistic => r.gen_range(85..=95),
            Tier::Hard => r.gen_range(70..=85),
        };
        shots.push(ShotPlan {
            index,
            file: format!("shot_{:0digits$}.{ext}", index + 1),
            material_name,
            material,
            shot,
            speed_mps,
            exposure_s,
            impact_fraction,
            camera,
            cue_rgb,
            object_rgb,
            specular: 0.0,
            stray,
            noise_seed,
            scene_px_per_mm,
            jpeg_quality,
        });
        let last = shots.last_mut().expect("just pushed");
        last.specular = last.material.specular as f32;
    }
    Ok(FolderPlan {
        tier,
        format,
        backdrop,
        plate_seed,
        shots,
    })
}

/// The balls of one shot in SI units (impact frame) and time (s, impact at 0).
struct Motion {
    radius: f64,
    cue_in: crate::physics::path::IncomingPath,
    cue_out: BallPath,
    object: BallPath,
    t0: f64,
    t1: f64,
}

fn motion(p: &ShotPlan) -> (Motion, impulse::ImpactState) {
    let radius = p.material.radius_m();
    let cloth: Cloth = p.material.cloth();
    let state = impulse::solve(&p.shot, &p.material.coefficients(), RegimeChoice::Auto);
    let v = p.speed_mps;
    let w = v / radius;
    let cue_out = BallPath::new(Vector2::zeros(), state.v1 * v, state.w1 * w, radius, &cloth);
    let object = BallPath::new(
        Vector2::new(2.0 * radius, 0.0),
        state.v2 * v,
        state.w2 * w,
        radius,
        &cloth,
    );
    let dir = Vector2::new(p.shot.psi.cos(), p.shot.psi.sin());
    let cue_in = BallPath::incoming(Vector2::zeros(), dir, v, &cloth);
    let t0 = -p.impact_fraction * p.exposure_s;
    let m = Motion {
        radius,
        cue_in,
        cue_out,
        object,
        t0,
        t1: t0 + p.exposure_s,
    };
    (m, state)
}

/// Cuts the path `pos` (impact frame, m) over `[ta, tb]` into image segments traversed at
/// nearly constant speed: a piece is accepted when its projected length is at most `3 R_px`, the
/// path at its mid-time lies within [`SIDE_TOLERANCE_PX`] of its chord sideways and within
/// [`ALONG_TOLERANCE`] of its length (or [`SIDE_TOLERANCE_PX`], whichever is larger, so that
/// pieces of a few px are not split for speed changes that move their dwell by less than that)
/// from the chord's midpoint (which bounds the deceleration); otherwise it is halved.
fn push_segments(
    out: &mut Vec<Segment>,
    cam: &Camera,
    radius: f64,
    pos: &dyn Fn(f64) -> Vector2<f64>,
    (ta, tb): (f64, f64),
    exposure: f64,
    rgb: [f32; 3],
) {
    if tb <= ta {
        return;
    }
    let cutter = Cutter {
        cam,
        radius,
        pos,
        exposure,
        rgb,
    };
    let pa = cam.project(pos(ta), radius);
    let pb = cam.project(pos(tb), radius);
    cutter.cut(out, (ta, tb), (pa, pb), 0);
}

/// Largest sideways distance (px) between a rendered chord and the path at its middle; the
/// sagitta of a chord of length `l` on a path of curvature `κ` is `l²κ/8`.
const SIDE_TOLERANCE_PX: f64 = 0.01;

/// Largest offset between the path at a piece's mid-time and its chord's midpoint, as a fraction
/// of the chord. A piece is painted at its mean speed; under a constant deceleration the offset
/// is `l Δv / (8 v)`, so this keeps the speed change across a piece below 0.8 % and the painted
/// dwell within 0.4 % of the true one at its ends. (It was 2 %: a rolling ball's first piece,
/// 2 R long, then changed speed by 8 %, which left a 4 % step in brightness where the sliding arc
/// meets the rolling line and turned the arc fit's `delta1` by +0.3° to +1°.)
const ALONG_TOLERANCE: f64 = 0.001;

/// The fixed inputs of [`push_segments`]'s recursive bisection.
struct Cutter<'a> {
    cam: &'a Camera,
    radius: f64,
    pos: &'a dyn Fn(f64) -> Vector2<f64>,
    exposure: f64,
    rgb: [f32; 3],
}

impl Cutter<'_> {
    fn cut(
        &self,
        out: &mut Vec<Segment>,
        (ta, tb): (f64, f64),
        (pa, pb): (Vector2<f64>, Vector2<f64>),
        depth: u32,
    ) {
        let (cam, radius) = (self.cam, self.radius);
        let tm = 0.5 * (ta + tb);
        let wm = (self.pos)(tm);
        let pm = cam.project(wm, radius);
        let r_px = cam.scale_at(wm, radius) * radius;
        let len = (pb - pa).norm();
        let dev = (pm - 0.5 * (pa + pb)).norm();
        // Sideways deviation of the path from the chord: the extractor measures centre-lines to
        // a few hundredths of a pixel, and a chord drawn instead of a sliding arc turns the
        // streak's start tangent towards the rolling line (half the turn of the first chord).
        let side = if len > 0.0 {
            let d = (pb - pa) / len;
            (pm - 0.5 * (pa + pb)).perp(&d).abs()
        } else {
            dev
        };
        // A piece far outside the image only needs its time accounted, not its shape. (If it
        // crossed the image, an endpoint would lie within `len` of it.)
        let far = !cam.contains(pa, 3.0 * r_px + len) && !cam.contains(pb, 3.0 * r_px + len);
        if depth >= 30
            || far
            || (len <= 3.0 * r_px
                && dev <= (ALONG_TOLERANCE * len).max(SIDE_TOLERANCE_PX)
                && side <= SIDE_TOLERANCE_PX)
        {
            if !far {
                out.push(Segment {
                    a: [pa.x, pa.y],
                    b: [pb.x, pb.y],
                    frac: (tb - ta) / self.exposure,
                    r: r_px,
                    rgb: self.rgb,
                });
            }
            return;
        }
        self.cut(out, (ta, tm), (pa, pm), depth + 1);
        self.cut(out, (tm, tb), (pm, pb), depth + 1);
    }
}

/// A ball at rest at impact-frame point `p` for `dt` seconds.
fn rest_disc(p: &ShotPlan, m: &Motion, at: Vector2<f64>, dt: f64, rgb: [f32; 3]) -> Disc {
    let c = p.camera.project(at, m.radius);
    Disc {
        c: [c.x, c.y],
        r: p.camera.scale_at(at, m.radius) * m.radius,
        frac: dt / p.exposure_s,
        rgb,
        specular: p.specular,
    }
}

/// Splits `[0, t_end]` of an outgoing path at its slide→roll and stop times.
fn outgoing_pieces(path: &BallPath, t_end: f64) -> Vec<(f64, f64)> {
    let mut cuts = vec![0.0];
    for t in [path.t_slide, path.t_stop] {
        if t > 0.0 && t < t_end {
            cuts.push(t);
        }
    }
    cuts.push(t_end.min(path.t_stop.max(0.0)));
    cuts.windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| (w[0], w[1]))
        .collect()
}

/// The image-space frame (segments and discs) of a planned shot.
pub fn build_frame(p: &ShotPlan) -> Frame {
    build_frame_parts(p).0
}

/// Which pieces of a [`Frame`] belong to which path: the object ball's waiting disc is
/// `discs[0]`; a ball that stops within the exposure has a resting disc too.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameParts {
    pub incoming: std::ops::Range<usize>,
    pub cue_out: std::ops::Range<usize>,
    pub object_out: std::ops::Range<usize>,
    pub cue_rest: Option<usize>,
    pub object_rest: Option<usize>,
}

/// [`build_frame`] and its [`FrameParts`].
pub fn build_frame_parts(p: &ShotPlan) -> (Frame, FrameParts) {
    let (m, _) = motion(p);
    let cam = &p.camera;
    let mut frame = Frame::default();
    let cue_in = m.cue_in;
    push_segments(
        &mut frame.segments,
        cam,
        m.radius,
        &|t| cue_in.position(t),
        (m.t0, 0.0),
        p.exposure_s,
        p.cue_rgb,
    );
    let mut parts = FrameParts {
        incoming: 0..frame.segments.len(),
        ..FrameParts::default()
    };
    // The object ball waits, touching the cue ball's position at impact, until t = 0.
    frame.discs.push(rest_disc(
        p,
        &m,
        Vector2::new(2.0 * m.radius, 0.0),
        -m.t0,
        p.object_rgb,
    ));
    for (ball, (path, rgb)) in [(m.cue_out, p.cue_rgb), (m.object, p.object_rgb)]
        .into_iter()
        .enumerate()
    {
        let first = frame.segments.len();
        for piece in outgoing_pieces(&path, m.t1) {
            push_segments(
                &mut frame.segments,
                cam,
                m.radius,
                &|t| path.position(t),
                piece,
                p.exposure_s,
                rgb,
            );
        }
        let pieces = first..frame.segments.len();
        let rest = (path.t_stop < m.t1).then(|| {
            let at = path.position(path.t_stop);
            frame
                .discs
                .push(rest_disc(p, &m, at, m.t1 - path.t_stop.max(0.0), rgb));
            frame.discs.len() - 1
        });
        if ball == 0 {
            (parts.cue_out, parts.cue_rest) = (pieces, rest);
        } else {
            (parts.object_out, parts.object_rest) = (pieces, rest);
        }
    }
    if let Some(s) = p.stray {
        let t0 = m.t0;
        push_segments(
            &mut frame.segments,
            cam,
            m.radius,
            &|t| s.p0 + s.v * (t - t0),
            (m.t0, m.t1),
            p.exposure_s,
            s.rgb,
        );
    }
    (frame, parts)
}

/// Pixel positions on the centre line of the incoming cue-ball streak, from the start of the
/// exposure to four radii before the impact (clear of the object ball's disc), inside the image,
/// and more than 2.2 ball radii from every other path of the exposure (the outgoing balls, e.g.
/// a drawn cue ball coming back, and a stray ball), so only the incoming streak is measured.
pub fn streak_samples(p: &ShotPlan) -> Vec<[f64; 2]> {
    let (m, _) = motion(p);
    let cam = &p.camera;
    let r_px = cam.scale_at(Vector2::zeros(), m.radius) * m.radius;
    // Other paths as dense point lists (about one point per 2 mm of travel).
    let n_other = 1000;
    let mut others: Vec<Vector2<f64>> = Vec::new();
    for i in 0..=n_other {
        let t = m.t1 * i as f64 / n_other as f64;
        others.push(cam.project(m.cue_out.position(t), m.radius));
        others.push(cam.project(m.object.position(t), m.radius));
        if let Some(s) = p.stray {
            let ts = m.t0 + (m.t1 - m.t0) * i as f64 / n_other as f64;
            others.push(cam.project(s.p0 + s.v * (ts - m.t0), m.radius));
        }
    }
    let t_end = -4.0 * m.radius / p.speed_mps;
    let n = 200;
    (0..n)
        .filter_map(|i| {
            let t = m.t0 + (t_end - m.t0) * (i as f64 + 0.5) / n as f64;
            let q = cam.project(m.cue_in.position(t), m.radius);
            let clear = others.iter().all(|o| (o - q).norm() > 2.2 * r_px);
            (cam.contains(q, -2.0) && clear).then_some([q.x, q.y])
        })
        .collect()
}

/// The five angles as the camera shows them (degrees, same order and sign convention as the
/// table's): each direction is mapped through the camera where the ball has it (the cue ball's
/// incoming and start directions at `P`, the object ball's start at `O`, a rolling line by the
/// image chord of its part within the exposure, or at its ball's start when it does not roll
/// within it), all at ball-centre height, and measured from the image of the line of centres
/// `P → O`. This is what an extractor that measures the image perfectly but knows nothing of the
/// camera's tilt and distortion would read; it equals the table's angles for a level camera
/// without distortion (a similarity). The difference is the camera's part of the error.
fn image_angles(
    p: &ShotPlan,
    m: &Motion,
    psi: f64,
    table: [Option<f64>; 4],
) -> (f64, [Option<f64>; 4]) {
    let cam = &p.camera;
    let h = m.radius;
    let proj = |q: Vector2<f64>| cam.project(q, h);
    let (pp, po) = (Vector2::zeros(), Vector2::new(2.0 * m.radius, 0.0));
    let line = proj(po) - proj(pp);
    let signed = |d: Vector2<f64>| (line.x * d.y - line.y * d.x).atan2(line.dot(&d));
    // A step of a micrometre keeps the difference quotient's error far below 1e-9 rad.
    let eps = 1e-6;
    let at = |x: Vector2<f64>, a: f64| proj(x + eps * Vector2::new(a.cos(), a.sin())) - proj(x);
    // The image of the frame's +y at P fixes the sense (mirroring, and v pointing down).
    let sense = signed(at(pp, std::f64::consts::FRAC_PI_2)).signum();
    let dir = |d: Vector2<f64>| (sense * signed(d)).to_degrees();
    let rolling = |path: &BallPath, x: Vector2<f64>, a: f64| {
        // `m.t1`: the end of the exposure, in time after the impact.
        let (ta, tb) = (path.t_slide, path.t_stop.min(m.t1));
        let chord = proj(path.position(tb)) - proj(path.position(ta));
        if tb > ta && chord.norm() > 1.0 {
            dir(chord)
        } else {
            dir(at(x, a))
        }
    };
    let [d1, d2, t1, t2] = table.map(|v| v.map(f64::to_radians));
    (
        dir(at(pp, psi.to_radians())),
        [
            d1.map(|a| dir(at(pp, a))),
            d2.map(|a| dir(at(po, a))),
            t1.map(|a| rolling(&m.cue_out, pp, a)),
            t2.map(|a| rolling(&m.object, po, a)),
        ],
    )
}

/// Ground truth of a planned shot; the contrast is computed on the noise-free model.
pub fn truth_row(p: &ShotPlan, tier: Tier, bd: &Backdrop, frame: &Frame) -> TruthRow {
    let (m, state) = motion(p);
    let [d1, d2, t1, t2] = state.angles().to_degrees();
    let (psi_image, [delta1_image, delta2_image, theta1_image, theta2_image]) =
        image_angles(p, &m, p.shot.psi.to_degrees(), [d1, d2, t1, t2]);
    let cam = &p.camera;
    let impact = cam.project(Vector2::zeros(), m.radius);
    let object = cam.project(Vector2::new(2.0 * m.radius, 0.0), m.radius);
    let empty = Frame::default();
    let mut diffs: Vec<f64> = streak_samples(p)
        .iter()
        .map(|&[x, y]| {
            let (xi, yi) = (x.floor() as u32, y.floor() as u32);
            render::luma(render::expected_at(frame, bd, xi, yi))
                - render::luma(render::expected_at(&empty, bd, xi, yi))
        })
        .collect();
    let c = &p.material;
    TruthRow {
        file: p.file.clone(),
        material: p.material_name.clone(),
        psi_deg: p.shot.psi.to_degrees(),
        delta1_deg: d1,
        delta2_deg: d2,
        theta1_deg: t1,
        theta2_deg: t2,
        e: c.e,
        mu: c.mu,
        mu_table: c.mu_table,
        mu_static: c.mu_static,
        mass_ratio: p.shot.mass_ratio,
        spin: p.shot.spin,
        english: p.shot.english,
        speed_mps: p.speed_mps,
        regime: state.regime.to_string(),
        exposure_s: p.exposure_s,
        t_impact_s: -m.t0,
        impact_x_px: impact.x,
        impact_y_px: impact.y,
        object_x_px: object.x,
        object_y_px: object.y,
        ball_radius_px: cam.scale_at(Vector2::zeros(), m.radius) * m.radius,
        px_per_mm: cam.px_per_mm_at(Vector2::zeros()),
        scene_px_per_mm: p.scene_px_per_mm,
        rotation_deg: cam.rotation.to_degrees(),
        mirrored: cam.mirrored,
        tilt_deg: cam.tilt_deg,
        distortion_k1: cam.k1,
        cloth_mu_slide: c.cloth_mu_slide,
        cloth_mu_roll: c.cloth_mu_roll,
        stray_ball: p.stray.is_some(),
        tier: tier.name().to_string(),
        streak_contrast_grey: render::median(&mut diffs),
        psi_image_deg: psi_image,
        delta1_image_deg: delta1_image,
        delta2_image_deg: delta2_image,
        theta1_image_deg: theta1_image,
        theta2_image_deg: theta2_image,
    }
}

/// Encodes an image as PNG or JPEG bytes.
pub fn encode(img: &RgbImage, format: ImgFormat, quality: u8) -> anyhow::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    match format {
        ImgFormat::Png => image::codecs::png::PngEncoder::new_with_quality(
            &mut bytes,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Sub,
        )
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )?,
        ImgFormat::Jpg => image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality)
            .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )?,
    }
    Ok(bytes)
}

/// File name of the background plate.
pub const BACKGROUND_FILE: &str = "background.png";

/// Loads the materials named by `args` (or the default file).
pub fn load_materials(args: &SynthArgs) -> Result<Materials, String> {
    let path = args
        .materials
        .clone()
        .unwrap_or_else(Materials::default_path);
    Materials::load(&path)
}

pub fn run(args: &SynthArgs) -> CliResult {
    let mats = load_materials(args).map_err(CliError::usage)?;
    let folder = plan(args, &mats).map_err(CliError::usage)?;
    let out = &args.out;
    std::fs::create_dir_all(out)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", out.display()))?;
    let start = std::time::Instant::now();
    let base = folder.backdrop.base_plate();
    if args.timing {
        eprintln!(
            "table plate (cloth texture × illumination, once per folder): {:.3} s",
            start.elapsed().as_secs_f64()
        );
    }
    let results: Vec<anyhow::Result<TruthRow>> = folder
        .shots
        .par_iter()
        .map(|p| {
            let start = std::time::Instant::now();
            let frame = build_frame(p);
            let img = render::render(&frame, &folder.backdrop, &base, Some(p.noise_seed));
            let t_render = start.elapsed().as_secs_f64();
            let bytes = encode(&img, folder.format, p.jpeg_quality)?;
            truth::write_atomic(&out.join(&p.file), &bytes)?;
            let t_total = start.elapsed().as_secs_f64();
            let row = truth_row(p, folder.tier, &folder.backdrop, &frame);
            if args.timing {
                eprintln!(
                    "{}: {}x{} rendered in {:.3} s, rendered+encoded+written in {:.3} s ({} segments)",
                    p.file,
                    img.width(),
                    img.height(),
                    t_render,
                    t_total,
                    frame.segments.len()
                );
            }
            Ok(row)
        })
        .collect();
    let rows = results.into_iter().collect::<anyhow::Result<Vec<_>>>()?;
    if args.background {
        let plate = render::render(
            &Frame::default(),
            &folder.backdrop,
            &base,
            Some(folder.plate_seed),
        );
        let bytes = encode(&plate, ImgFormat::Png, 95)?;
        truth::write_atomic(&out.join(BACKGROUND_FILE), &bytes)?;
    }
    let scene = scene_config(args, &folder);
    truth::write_atomic(
        &out.join(crate::scene::SCENE_FILE),
        scene.to_toml_string().as_bytes(),
    )?;
    truth::write_atomic(&out.join("truth.csv"), truth::to_csv(&rows).as_bytes())?;
    eprintln!(
        "wrote {} {} images, scene.toml and truth.csv to {}",
        rows.len(),
        folder.tier.name(),
        out.display()
    );
    Ok(Outcome::Ok)
}

/// What an experimenter would write down for this folder.
pub fn scene_config(args: &SynthArgs, folder: &FolderPlan) -> SceneConfig {
    let per_image: Vec<(String, ImageScene)> = folder
        .shots
        .iter()
        .map(|p| {
            (
                p.file.clone(),
                ImageScene {
                    ball_diameter_mm: Some(p.material.diameter_mm),
                    px_per_mm: Some(p.scene_px_per_mm),
                    exposure_s: Some(p.exposure_s),
                    material: Some(p.material_name.clone()),
                    background: args.background.then(|| BACKGROUND_FILE.to_string()),
                    spin: args.known_spin.then_some(p.shot.spin),
                    english: args.known_spin.then_some(p.shot.english),
                },
            )
        })
        .collect();
    SceneConfig::from_images(&per_image)
}

/// Convenience for tools and tests: plan the folder that `args` would produce.
pub fn plan_for(args: &SynthArgs) -> Result<FolderPlan, String> {
    plan(args, &load_materials(args)?)
}
