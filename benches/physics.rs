//! Nanoseconds per evaluation of the theory: closed forms against the impulse model, on random
//! shots (fixed seed) in the auto regime.

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use streakfit::physics::{Coefficients, RegimeChoice, Shot, closed, impulse};

fn shots(n: usize) -> Vec<(Shot, Coefficients)> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    (0..n)
        .map(|_| {
            let shot = Shot {
                psi: rng.gen_range(0.0..1.5),
                mass_ratio: rng.gen_range(0.5..2.0),
                spin: rng.gen_range(-2.0..2.0),
                english: rng.gen_range(-0.5..0.5),
            };
            let mu = rng.gen_range(0.0..0.7);
            (
                shot,
                Coefficients::new(rng.gen_range(0.5..1.0), mu, rng.gen_range(0.0..0.6))
                    .with_static(mu * 1.2),
            )
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let set = shots(1024);
    let mut g = c.benchmark_group("theory_per_shot");
    g.throughput(criterion::Throughput::Elements(set.len() as u64));
    g.bench_function("closed_form_auto", |b| {
        b.iter(|| {
            for (s, k) in &set {
                black_box(closed::predict_auto(black_box(s), k));
            }
        })
    });
    g.bench_function("impulse_model_auto", |b| {
        b.iter(|| {
            for (s, k) in &set {
                black_box(impulse::solve(black_box(s), k, RegimeChoice::Auto).angles());
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
