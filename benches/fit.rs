//! Fit speed: 1,000 synthetic shots (steel, the two-regime case: every candidate model plus the
//! threshold profile), with and without the bootstrap; and 30 to 1,000 shots with estimated spin.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use streakfit::fit::synthetic::{SyntheticSpec, SyntheticSpin, paper_materials, synthetic_table};
use streakfit::fit::{FitOptions, SpinMode, fit_materials};

fn table(material: usize, n: usize, spin: SyntheticSpin) -> Vec<streakfit::table::ShotRow> {
    let (name, c) = paper_materials()[material];
    synthetic_table(&SyntheticSpec {
        material: name.into(),
        coefficients: c,
        n,
        psi_lo_deg: 10.0,
        psi_hi_deg: 70.0,
        noise_deg: 0.3,
        spin,
        seed: 42,
    })
    .0
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("fit");
    g.sample_size(10);
    for n in [30, 1000] {
        let rows = table(1, n, SyntheticSpin::Rolling);
        let opts = FitOptions {
            bootstrap: 0,
            ..FitOptions::default()
        };
        g.bench_function(format!("steel_auto_model_{n}_shots"), |b| {
            b.iter(|| fit_materials(black_box(&rows), &opts).unwrap())
        });
        let fixed = FitOptions {
            model: Some("mu-mu".parse().unwrap()),
            bootstrap: 0,
            ..FitOptions::default()
        };
        let rows_b = table(0, n, SyntheticSpin::Rolling);
        g.bench_function(format!("billiard_mu_mu_{n}_shots"), |b| {
            b.iter(|| fit_materials(black_box(&rows_b), &fixed).unwrap())
        });
    }
    // Estimated spin (latent r, s per shot, profile intervals, regime hypotheses): the cost
    // must grow linearly with the number of shots.
    let spin = FitOptions {
        model: Some("mu-mu".parse().unwrap()),
        spin: SpinMode::Estimate,
        bootstrap: 0,
        ..FitOptions::default()
    };
    for n in [30, 100, 300, 1000] {
        let rows_s = table(
            0,
            n,
            SyntheticSpin::Mixed {
                r_lo: -1.0,
                r_hi: 1.5,
                s_max: 0.3,
                write: false,
            },
        );
        g.bench_function(format!("billiard_estimated_spin_{n}_shots"), |b| {
            b.iter(|| fit_materials(black_box(&rows_s), &spin).unwrap())
        });
    }
    let rows = table(1, 30, SyntheticSpin::Rolling);
    g.bench_function("steel_auto_model_30_shots_bootstrap_100", |b| {
        b.iter(|| fit_materials(black_box(&rows), &FitOptions::default()).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
