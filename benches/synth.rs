//! Seconds per synthetic photograph (release): the per-folder table plate, and one shot's
//! frame (paths → segments) plus rendering with noise, at 2400×1600 and 4000×3000.

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use streakfit::synth::{self, SynthArgs, Tier, render};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("synth");
    g.sample_size(10);
    for (size, tier) in [
        ("2400x1600", Tier::Clean),
        ("2400x1600", Tier::Hard),
        ("4000x3000", Tier::Realistic),
    ] {
        let mut args = SynthArgs::new("/nonexistent", tier, 1, 3);
        args.size = size.into();
        let folder = synth::plan_for(&args).expect("valid arguments");
        let shot = &folder.shots[0];
        g.bench_function(format!("table_plate_{}_{size}", tier.name()), |b| {
            b.iter(|| black_box(folder.backdrop.base_plate()))
        });
        let base = folder.backdrop.base_plate();
        g.bench_function(format!("render_shot_{}_{size}", tier.name()), |b| {
            b.iter(|| {
                let frame = synth::build_frame(shot);
                black_box(render::render(
                    &frame,
                    &folder.backdrop,
                    &base,
                    Some(shot.noise_seed),
                ))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
