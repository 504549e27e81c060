//! streakfit: long-exposure photographs of billiard-ball collisions to physics.
//!
//! Data flows one way: image → streaks → angles table → fit → report.
//! - [`physics`]: the non-smooth impact model (regimes, closed forms, paths);
//! - `synth`: synthetic photographs with exact ground truth;
//! - `vision`: segmentation, streaks and path fits (`extract`);
//! - `fit`: material coefficients with uncertainties and model selection;
//! - `report`: figures and HTML reports; `pipeline`: `streakfit run`.
#![deny(clippy::float_cmp)]

pub mod bench;
pub mod cli;
pub mod extract;
pub mod fit;
pub mod io;
pub mod physics;
pub mod pipeline;
pub mod predict;
pub mod report;
pub mod scene;
pub mod synth;
pub mod table;
pub mod vision;

/// Keeps freed memory in the process instead of returning it to the kernel after every use.
///
/// The extractor allocates and frees scratch arrays of a few hundred kB thousands of times per
/// photo (the arc fit's columns and residuals at each evaluation) and a decoded photo per file
/// (11.5 MB of bytes at 2400×1600 since session 36, 46 MB of `f32` before and for 16-bit
/// photos). glibc serves blocks above its mmap threshold (128 kB to start) from fresh
/// pages and trims the heap's top when it frees, so each one cost page faults and the kernel's
/// zeroing: 13–22 % of a folder's time was system time on 2 cores (`extract --jobs 2`, 48
/// photos: 1.4–2.5 s in 10.8–11.3 s). With blocks up to 64 MB kept on the heap and trimming
/// above 256 MB it was 0.7–1.3 s in 10.0–10.2 s (session 22, three alternating runs; the same
/// tables to the last digit). The photos are analysed on rayon's threads, whose arenas are
/// heaps of at most 64 MB that glibc unmaps whole once empty unless the top pad says to keep
/// that much: a 46 MB photo freed was such a heap, and the next one faulted its pages in
/// again (12,000 faults a photo, 144,000 for 12 clean photos with `--jobs 1`; with a top pad
/// of 64 MB 30,000, and user plus system time 2.72 → 2.61 s, session 33). Other platforms keep
/// their allocator's defaults. Call it once, before any work (the CLI and the extract bench
/// do).
pub fn tune_allocator() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only sets three of the allocator's parameters; it is called before any
    // thread of ours exists and has no other precondition.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 64 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
    }
}
