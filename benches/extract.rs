//! Speed of the extractor on 2400×1600 synthetic photos: decode time versus analysis time (the
//! target is analysis ≤ decode), for PNG photos (clean tier) and JPEG photos (realistic tier).
//! Each benchmark runs over the same [`FRAMES`] photos of a tier (seed 4), so one iteration is
//! that many photos: divide by it for the time per photo. These photos are analysed without a
//! plate or texture map (`Cloth::Surface`). A third group analyses [`FRAMES`] photos of a
//! realistic folder of [`FOLDER`] with the folder's cloth texture map, as `streakfit extract`
//! does for photos without a plate, and times building that map (15 of its photos decoded and
//! reduced, one thread). Images/second on the machine's cores: `streakfit extract` on a
//! folder, see the README.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;
use streakfit::synth::{SynthArgs, Tier};
use streakfit::vision::texture::{self, ClothTexture};
use streakfit::vision::{AnalysisOptions, Cloth, analyse, image_io};

/// Photos per tier: one frame's time depends on which paths its shot takes (a clean frame's arc
/// fit, a declined photo's early exit), so the mean over several is what the README quotes.
const FRAMES: usize = 6;

/// Photos of the folder whose texture map the third group uses (a campaign's folder holds
/// dozens; the map is built from up to 15 of them).
const FOLDER: usize = 24;

fn make(tier: Tier, name: &str, n: usize) -> Vec<PathBuf> {
    let dir = std::env::temp_dir().join(format!("streakfit_bench_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    let args = SynthArgs::new(&dir, tier, n, 4);
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
    assert_eq!(shots.len(), n, "synth wrote {n} shots");
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
        let paths = make(tier, name, FRAMES);
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
    // A folder without a plate, as the CLI reads it: the texture map once, then each photo
    // with it. The map's build runs on one thread (its per-cell medians are parallel in the
    // CLI).
    let paths = make(Tier::Realistic, "realistic_jpg_folder", FOLDER);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let build = || -> ClothTexture {
        let res: Vec<_> = texture::pick(paths.len())
            .into_iter()
            .map(|i| texture::residual(&image_io::load(&paths[i]).unwrap(), opts.coarse_side))
            .collect();
        one.install(|| ClothTexture::from_residuals(&res))
            .expect("a texture map")
    };
    let map = build();
    let imgs: Vec<_> = paths[..FRAMES]
        .iter()
        .map(|p| image_io::load(p).unwrap())
        .collect();
    let mut g = c.benchmark_group(format!("realistic_jpg_texture_x{FRAMES}"));
    g.sample_size(10);
    g.bench_function("analyse", |b| {
        b.iter(|| {
            for img in &imgs {
                black_box(analyse(img, Cloth::Texture(&map), None, &opts));
            }
        })
    });
    g.bench_function(format!("texture_map_of_{FOLDER}"), |b| {
        b.iter(|| black_box(build()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
