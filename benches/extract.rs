//! Speed of the extractor on 2400×1600 synthetic photos: decode time versus analysis time (the
//! target is analysis ≤ decode), for PNG photos (clean tier) and JPEG photos (realistic tier).
//! Each benchmark runs over the same [`FRAMES`] photos of a tier (seed 4), so one iteration is
//! that many photos: divide by it for the time per photo. The photos are analysed without a
//! plate or texture map (`Cloth::Surface`). Images/second on the machine's cores: `streakfit
//! extract` on a folder, see the README.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;
use streakfit::synth::{SynthArgs, Tier};
use streakfit::vision::{AnalysisOptions, Cloth, analyse, image_io};

/// Photos per tier: one frame's time depends on which paths its shot takes (a clean frame's arc
/// fit, a declined photo's early exit), so the mean over several is what the README quotes.
const FRAMES: usize = 6;

fn make(tier: Tier, name: &str) -> Vec<PathBuf> {
    let dir = std::env::temp_dir().join(format!("streakfit_bench_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    let args = SynthArgs::new(&dir, tier, FRAMES, 4);
    streakfit::synth::run(&args).expect("synth for the bench");
    let mut shots: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("shot_"))
        })
        .collect();
    shots.sort();
    assert_eq!(shots.len(), FRAMES, "synth wrote {FRAMES} shots");
    shots
}

fn bench(c: &mut Criterion) {
    // As the CLI runs.
    streakfit::tune_allocator();
    let opts = AnalysisOptions::default();
    for (tier, name) in [
        (Tier::Clean, "clean_png"),
        (Tier::Realistic, "realistic_jpg"),
    ] {
        let paths = make(tier, name);
        let imgs: Vec<_> = paths.iter().map(|p| image_io::load(p).unwrap()).collect();
        let mut g = c.benchmark_group(format!("{name}_x{FRAMES}"));
        g.sample_size(10);
        g.bench_function("decode", |b| {
            b.iter(|| {
                for p in &paths {
                    black_box(image_io::load(p).unwrap());
                }
            })
        });
        g.bench_function("analyse", |b| {
            b.iter(|| {
                for img in &imgs {
                    black_box(analyse(img, Cloth::Surface, None, &opts));
                }
            })
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
