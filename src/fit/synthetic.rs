//! Synthetic angle tables from the theory, for tests, benchmarks and coverage studies.
//!
//! Each shot: true `psi` uniform in a range, the regime the stick/slip conditions select
//! ([`crate::physics::regime::select_regime`]), closed-form angles, then Gaussian noise of
//! `noise_deg` on `psi` and on every angle; the stated `*_err_deg` equal `noise_deg`.

use crate::physics::{Coefficients, Shot, closed, regime};
use crate::table::{ShotRow, Status};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

/// How the cue ball's spin of synthetic shots is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SyntheticSpin {
    /// Rolling, `r = 1, s = 0`, not written to the table (the fit's default).
    Rolling,
    /// `r` uniform in `[r_lo, r_hi]`, `s` uniform in `[-s_max, s_max]`; written to the table
    /// only when `write` is true.
    Mixed {
        r_lo: f64,
        r_hi: f64,
        s_max: f64,
        write: bool,
    },
}

/// Parameters of a synthetic table.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticSpec {
    pub material: String,
    pub coefficients: Coefficients,
    pub n: usize,
    pub psi_lo_deg: f64,
    pub psi_hi_deg: f64,
    pub noise_deg: f64,
    pub spin: SyntheticSpin,
    pub seed: u64,
}

/// One synthetic table row per shot plus the true `(psi, r, s)` of each shot.
pub fn synthetic_table(spec: &SyntheticSpec) -> (Vec<ShotRow>, Vec<[f64; 3]>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(spec.seed);
    let noise = Normal::new(0.0, spec.noise_deg.max(0.0)).expect("finite noise");
    let mut rows = Vec::with_capacity(spec.n);
    let mut truth = Vec::with_capacity(spec.n);
    for i in 0..spec.n {
        let psi_deg = rng.gen_range(spec.psi_lo_deg..=spec.psi_hi_deg);
        let (r, s, write) = match spec.spin {
            SyntheticSpin::Rolling => (1.0, 0.0, false),
            SyntheticSpin::Mixed {
                r_lo,
                r_hi,
                s_max,
                write,
            } => (
                rng.gen_range(r_lo..=r_hi),
                if s_max > 0.0 {
                    rng.gen_range(-s_max..=s_max)
                } else {
                    0.0
                },
                write,
            ),
        };
        let shot = Shot {
            psi: psi_deg.to_radians(),
            mass_ratio: 1.0,
            spin: r,
            english: s,
        };
        let reg = regime::select_regime(&shot, &spec.coefficients);
        let a = closed::angles(&shot, &spec.coefficients, reg).to_degrees();
        let mut row = ShotRow::failed(
            format!("synthetic_{i:04}"),
            Status::Ok,
            "",
            spec.material.clone(),
        );
        row.psi_deg = Some(psi_deg + noise.sample(&mut rng));
        let mut noisy = |x: Option<f64>| x.map(|v| v + noise.sample(&mut rng));
        row.delta1_deg = noisy(a[0]);
        row.delta2_deg = noisy(a[1]);
        row.theta1_deg = noisy(a[2]);
        row.theta2_deg = noisy(a[3]);
        let err = Some(spec.noise_deg);
        row.psi_err_deg = err;
        row.delta1_err_deg = err;
        row.delta2_err_deg = err;
        row.theta1_err_deg = err;
        row.theta2_err_deg = err;
        if write {
            row.spin = Some(r);
            row.english = Some(s);
        }
        rows.push(row);
        truth.push([psi_deg, r, s]);
    }
    (rows, truth)
}

/// The paper's Table 1 values: `(material, coefficients)` for billiard, steel and rubber balls
/// (`mu0 = mu` where the paper gives no static value).
pub fn paper_materials() -> [(&'static str, Coefficients); 3] {
    [
        ("billiard", Coefficients::new(0.97, 0.07, 0.15)),
        (
            "steel",
            Coefficients::new(0.92, 0.14, 0.15).with_static(0.18),
        ),
        ("rubber", Coefficients::new(0.88, 0.60, 0.55)),
    ]
}
