//! Speed of the extractor on a 2400×1600 synthetic photo: decode time versus analysis time
//! (the target is analysis ≤ decode), for a PNG (clean tier) and a JPEG (realistic tier).
//! Images/second on the machine's cores: `streakfit extract` on a folder, see the README.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;
use streakfit::synth::{SynthArgs, Tier};
use streakfit::vision::{AnalysisOptions, Cloth, analyse, image_io};

fn make(tier: Tier, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("streakfit_bench_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    let args = SynthArgs::new(&dir, tier, 1, 4);
    streakfit::synth::run(&args).expect("synth for the bench");
    std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("shot_"))
        })
        .expect("one shot written")
}

fn bench(c: &mut Criterion) {
    let opts = AnalysisOptions::default();
    for (tier, name) in [
        (Tier::Clean, "clean_png"),
        (Tier::Realistic, "realistic_jpg"),
    ] {
        let path = make(tier, name);
        let img = image_io::load(&path).unwrap();
        let mut g = c.benchmark_group(name);
        g.sample_size(10);
        g.bench_function("decode", |b| {
            b.iter(|| black_box(image_io::load(&path).unwrap()))
        });
        g.bench_function("analyse", |b| {
            b.iter(|| black_box(analyse(&img, Cloth::Surface, None, &opts)))
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
