//! Streaks: coarse detection, then sub-pixel centre-lines at full resolution.
//!
//! Coarse: the coarse signal is box-smoothed over about one ball radius and thresholded at 4 σ of
//! its own MAD noise; streaks are found where they cross a ring around the object disc (see
//! [`find_coarse`]).
//!
//! Fine: each candidate is tracked outward (and inward towards the disc) in steps of `R/10`.
//! At each step the cross-profile perpendicular to the current direction is sampled at 1 px over
//! `±1.7 R` (averaged over the step length, so every pixel is used once), a straight baseline is
//! fitted to the flanks `|t - c| > 1.15 R`, and the centre `c` is the signal-weighted centroid over
//! `|t - c| ≤ 1.1 R`, iterated until the window is centred. For any profile symmetric about the
//! centre-line (sweep `∝ sqrt(R² - d²)`, shaded `∝ R² - d²`, blur) this is unbiased; its standard
//! error is `σ_c² = Σ (t - c)² σ_n² / (Σ s)²` with `σ_n` the flank scatter.

use std::sync::OnceLock;

use super::background::{Signal, mad_sigma, mad_sigma_about};

#[derive(Debug, Clone)]
pub struct CoarseStreak {
    /// Seed point on the centre-line (full resolution) at about 3.5 R from the disc centre.
    pub seed: (f64, f64),
    /// Unit direction at the seed, pointing away from the disc.
    pub dir: (f64, f64),
    /// Total signal of the part (for ranking).
    pub weight: f64,
    /// Unit colour direction of this ball's light (ball minus cloth).
    pub u: [f32; 3],
    /// Found by the line integrals of [`find_faint`] rather than at a ring crossing.
    pub faint: bool,
}

#[derive(Debug, Clone, Copy)]
pub struct Sample {
    pub x: f64,
    pub y: f64,
    /// 1-sigma standard error of the centre across the streak (px).
    pub sigma: f64,
    /// Mean baseline-subtracted signal in the core.
    pub amp: f64,
}

/// Streak candidates leaving the neighbourhood of the disc at `(ox, oy)`, radius `r` (full-res).
///
/// Every streak of the shot starts or ends within `2R` of `O`, so each crosses the ring
/// `3.5R ≤ |p - O| ≤ 4.5R` once (a short one only an inner ring around `2R`): runs of above-threshold ring samples are the crossings (this also
/// separates streaks that touch near the impact and form one connected part). A run wider than two
/// streaks is split in two. The seed is the run's signal-weighted centre, the direction the
/// principal axis of the thresholded pixels within `3R` of it and beyond `3.5R` from `O`.
pub fn find_coarse(map: &CoarseMap, ox: f64, oy: f64) -> Vec<CoarseStreak> {
    let (w, h, f, rc, thr) = (map.w, map.h, map.f, map.rc, map.thr);
    let s = &map.s;
    if let Some(path) = std::env::var_os("STREAKFIT_COARSE_PNG") {
        let mx = s.iter().cloned().fold(0f32, f32::max).max(1e-9);
        let _ = image::GrayImage::from_fn(w as u32, h as u32, |x, y| {
            image::Luma([(255.0 * (s[y as usize * w + x as usize] / (3.0 * thr)).min(1.0)) as u8])
        })
        .save(std::path::Path::new(&path));
        eprintln!("coarse: thr {thr} max {mx}");
    }
    let colour_at = |x: f64, y: f64| map.colour_at(x, y);
    let (ocx, ocy) = (ox / f - 0.5, oy / f - 0.5);
    let at = |x: f64, y: f64| -> Option<f32> {
        if x < 0.0 || y < 0.0 {
            return None;
        }
        let (xi, yi) = (x.round() as usize, y.round() as usize);
        (xi < w && yi < h).then(|| s[yi * w + xi])
    };
    let scan = |rho: f64| -> Vec<(f64, CoarseStreak)> {
        let n_ang = ((std::f64::consts::TAU * rho / 0.5).ceil() as usize).max(90);
        let mut val = vec![f32::NAN; n_ang];
        for (k, v) in val.iter_mut().enumerate() {
            let a = std::f64::consts::TAU * k as f64 / n_ang as f64;
            let (mut acc, mut n) = (0.0f32, 0);
            let mut q = rho - 0.5 * rc;
            while q <= rho + 0.5 * rc {
                if let Some(x) = at(ocx + q * a.cos(), ocy + q * a.sin()) {
                    acc += x;
                    n += 1;
                }
                q += 0.5;
            }
            if n > 0 {
                *v = acc / n as f32;
            }
        }
        // Ring averages are much less noisy than single smoothed pixels: threshold them against
        // their own robust spread around the ring (most of the ring is cloth).
        let finite: Vec<f32> = val.iter().copied().filter(|v| v.is_finite()).collect();
        let mut tmp = finite.clone();
        let med = super::background::median(&mut tmp);
        let thr_ring = (med + 5.0 * mad_sigma(&finite)).min(thr).max(med + 1e-7);
        let above: Vec<bool> = val.iter().map(|v| v.is_finite() && *v > thr_ring).collect();
        if above.iter().all(|b| *b) || !above.iter().any(|b| *b) {
            return Vec::new();
        }
        // Start scanning at a gap so runs do not wrap.
        let start = above.iter().position(|b| !*b).unwrap_or(0);
        let mut runs: Vec<Vec<usize>> = Vec::new();
        let mut cur: Vec<usize> = Vec::new();
        for i in 0..n_ang {
            let k = (start + i) % n_ang;
            if above[k] {
                cur.push(k);
            } else if !cur.is_empty() {
                runs.push(std::mem::take(&mut cur));
            }
        }
        if !cur.is_empty() {
            runs.push(cur);
        }
        let arc = |n: usize| n as f64 * std::f64::consts::TAU * rho / n_ang as f64;
        let mut pieces: Vec<Vec<usize>> = Vec::new();
        for run in runs {
            if arc(run.len()) < 0.8 * rc {
                continue;
            }
            if arc(run.len()) > 4.5 * rc {
                let m = run.len() / 2;
                pieces.push(run[..m].to_vec());
                pieces.push(run[m..].to_vec());
            } else {
                pieces.push(run);
            }
        }
        let mut out = Vec::new();
        for piece in pieces {
            // Weighted mean angle (unwrap relative to the first element).
            let a0 = std::f64::consts::TAU * piece[0] as f64 / n_ang as f64;
            let (mut sw, mut sa) = (0.0, 0.0);
            for &k in &piece {
                let a = std::f64::consts::TAU * k as f64 / n_ang as f64;
                let mut da = a - a0;
                if da < -std::f64::consts::PI {
                    da += std::f64::consts::TAU;
                }
                let wgt = (val[k] - thr_ring).max(0.0) as f64;
                sw += wgt;
                sa += wgt * da;
            }
            if sw <= 0.0 {
                continue;
            }
            let phi = a0 + sa / sw;
            let seed = (ocx + rho * phi.cos(), ocy + rho * phi.sin());
            // The streak's own colour direction (ball minus cloth) at its crossing.
            let mut col = [0f64; 3];
            for &k in &piece {
                let a = std::f64::consts::TAU * k as f64 / n_ang as f64;
                let wgt = (val[k] - thr_ring).max(0.0) as f64;
                let cc = colour_at(ocx + rho * a.cos(), ocy + rho * a.sin());
                for c in 0..3 {
                    col[c] += wgt * cc[c];
                }
            }
            let cn = (col[0] * col[0] + col[1] * col[1] + col[2] * col[2]).sqrt();
            let u = if cn > 0.0 {
                col.map(|v| (v / cn) as f32)
            } else {
                map.u
            };
            // Direction: the line through the seed (±2R) that carries the most light, a local
            // Radon transform. Both sides lie on the streak (it runs from near the disc outward)
            // and stay 2R clear of the disc; a bright end (a ball come to rest) on one side
            // cannot swing the line. Every streak passes within 2R of O, so at the ring it
            // points within 85° of the radial direction.
            let radial = (phi.cos(), phi.sin());
            let reach = 2.0 * rc;
            let line_mean = |a: f64| -> f64 {
                let (ca, sa) = (a.cos(), a.sin());
                let (mut acc, mut n, mut tot) = (0.0f64, 0usize, 0usize);
                let mut q = -reach;
                while q <= reach {
                    tot += 1;
                    if let Some(v) = at(seed.0 + q * ca, seed.1 + q * sa) {
                        acc += v as f64;
                        n += 1;
                    }
                    q += 0.5;
                }
                if 2 * n >= tot {
                    acc / n as f64
                } else {
                    f64::NEG_INFINITY
                }
            };
            let n_dir = 341;
            let angs: Vec<f64> = (0..n_dir)
                .map(|k| phi + (k as f64 / (n_dir - 1) as f64 - 0.5) * 170f64.to_radians())
                .collect();
            let vals: Vec<f64> = angs.iter().map(|&a| line_mean(a)).collect();
            let kbest = (0..n_dir)
                .max_by(|&a, &b| vals[a].total_cmp(&vals[b]))
                .unwrap_or(n_dir / 2);
            let mut a_best = angs[kbest];
            if kbest > 0 && kbest + 1 < n_dir {
                let (vm, v0, vp) = (vals[kbest - 1], vals[kbest], vals[kbest + 1]);
                let den = vm - 2.0 * v0 + vp;
                if den.is_finite() && den < 0.0 {
                    a_best += 0.5 * (vm - vp) / den * (angs[1] - angs[0]);
                }
            }
            let mut d = if vals[kbest].is_finite() {
                (a_best.cos(), a_best.sin())
            } else {
                radial
            };
            if d.0 * radial.0 + d.1 * radial.1 < 0.0 {
                d = (-d.0, -d.1);
            }
            out.push((
                phi,
                CoarseStreak {
                    seed: ((seed.0 + 0.5) * f, (seed.1 + 0.5) * f),
                    dir: d,
                    weight: sw,
                    u,
                    faint: false,
                },
            ));
        }
        out
    };
    let mut found = scan(4.0 * rc);
    // Crossings with a tiny fraction of the strongest one's light are noise.
    let wmax = found.iter().map(|(_, c)| c.weight).fold(0.0, f64::max);
    found.retain(|(_, c)| c.weight >= 0.05 * wmax);
    // A short streak (a slow object ball in a grazing shot) may end before the outer ring; an
    // inner ring at 2R adds crossings in new directions (duplicates are removed after tracking).
    {
        let inner = scan(2.0 * rc);
        for (phi, c) in inner.into_iter().filter(|(_, c)| c.weight >= 0.05 * wmax) {
            let new = found.iter().all(|(p, _)| {
                let d = (phi - p).rem_euclid(std::f64::consts::TAU);
                d.min(std::f64::consts::TAU - d) > 35f64.to_radians()
            });
            if new {
                found.push((phi, c));
            }
        }
    }
    let mut out: Vec<CoarseStreak> = found.into_iter().map(|(_, c)| c).collect();
    out.sort_by(|a, b| b.weight.total_cmp(&a.weight));
    out
}

/// The coarse detection map around one disc: the Mahalanobis norm of the colour difference
/// box-smoothed over half a ball radius (see [`find_coarse`]), the smoothed channels (for a
/// streak's colour), and the map's level (median), noise (MAD sigma) and threshold (level + 4
/// noise). Computed once per reading and shared by the ring scan and the faint-streak search.
pub struct CoarseMap {
    w: usize,
    h: usize,
    /// Downsampling factor and the ball radius on the coarse grid.
    f: f64,
    rc: f64,
    s: Vec<f32>,
    chans: Vec<Vec<f32>>,
    level: f32,
    noise: f32,
    thr: f32,
    /// The photo's mean ball colour direction (a crossing's colour when it has none).
    u: [f32; 3],
}

impl CoarseMap {
    /// The map of `sig`'s coarse grid for balls of radius `r` (full-resolution px).
    pub fn new(sig: &Signal, r: f64) -> CoarseMap {
        let f = sig.f as f64;
        let rc = r / f;
        let (s, chans) = norm_map(sig, rc);
        let level = super::background::median_of(&s);
        let noise = mad_sigma_about(&s, level);
        CoarseMap {
            w: sig.cw,
            h: sig.ch,
            f,
            rc,
            s,
            chans,
            level,
            noise,
            thr: level + 4.0 * noise.max(1e-7),
            u: sig.u,
        }
    }

    /// Smoothed colour difference at the nearest coarse cell (clamped to the grid).
    fn colour_at(&self, x: f64, y: f64) -> [f64; 3] {
        let (xi, yi) = (
            x.round().clamp(0.0, (self.w - 1) as f64) as usize,
            y.round().clamp(0.0, (self.h - 1) as f64) as usize,
        );
        [0, 1, 2].map(|c| self.chans[c][yi * self.w + xi] as f64)
    }
}

/// The Mahalanobis norm map and the box-smoothed channels it is made of.
fn norm_map(sig: &Signal, rc: f64) -> (Vec<f32>, Vec<Vec<f32>>) {
    let (w, h) = (sig.cw, sig.ch);
    let rb = ((rc / 2.0).round() as usize).max(1);
    // Detection works on every ball colour: the Mahalanobis norm of the smoothed colour
    // difference under the cloth's own colour covariance at this scale (a white cue ball and a
    // red object ball can project to nothing on one direction; texture blotches, which change
    // the cloth's brightness more than its hue, are weighted down). Its cloth level is a
    // positive constant, removed by the ring's own median.
    let chans = super::background::smoothed_channels(sig, rb);
    let blurred: Vec<[f32; 3]> = (0..w * h)
        .map(|i| [chans[0][i], chans[1][i], chans[2][i]])
        .collect();
    let ci = super::background::robust_cov_inv(&blurred);
    let s: Vec<f32> = blurred
        .iter()
        .map(|&b| super::background::mahalanobis_norm(b, &ci))
        .collect();
    (s, chans)
}

/// Faint streaks that no ring caught (see [`ray_candidates`]), in directions away from the ring
/// candidates `ring` (full-resolution seeds); seeds in full-resolution coordinates.
pub fn find_faint(map: &CoarseMap, ox: f64, oy: f64, ring: &[CoarseStreak]) -> Vec<CoarseStreak> {
    let f = map.f;
    let (ocx, ocy) = (ox / f - 0.5, oy / f - 0.5);
    let taken: Vec<Band> = ring
        .iter()
        .map(|c| {
            let p = (c.seed.0 / f - 0.5, c.seed.1 / f - 0.5);
            Band {
                phi: (p.1 - ocy).atan2(p.0 - ocx),
                p,
                d: c.dir,
            }
        })
        .collect();
    ray_candidates(map, (ocx, ocy), &taken)
        .into_iter()
        .map(|c| CoarseStreak {
            seed: ((c.seed.0 + 0.5) * f, (c.seed.1 + 0.5) * f),
            ..c
        })
        .collect()
}

/// A streak the rings found, as seen by the ray search (coarse coordinates): the angle of its
/// ring crossing around the disc, a point on it and its direction.
struct Band {
    phi: f64,
    p: (f64, f64),
    d: (f64, f64),
}

/// Significance above which a ray is a streak, in units of the coarse map's own noise `σ_s`
/// (MAD over the photo). On cloth alone the best ray of a direction reaches 2–3 (hard synthetic
/// photos: the maximum over offsets and lengths of a smoothed, mottled map); a brown object
/// ball's streak on light cloth that no ring caught, 5.9.
const RAY_SIGNIFICANCE: f64 = 4.5;

/// Streaks found by integrating the coarse signal `s` along rays that pass within `2R` of the
/// disc centre `o` (coarse pixels; `rc` the radius there), crossing the ring at `4R` at least
/// 20° from the ring's crossings `taken`. A ray of direction `a` at signed offset `b` from `o` is sampled from
/// `2.5R` beyond its foot point (clear of the impact) outward; its statistic is the best over
/// lengths `L ≥ 3R` of `mean(s - level) · sqrt(L / R)` (the matched
/// filter of a streak of unknown length; `level` the map's median) in units of `σ_s`. One
/// candidate per run of directions above [`RAY_SIGNIFICANCE`]: the seed where the run's best ray
/// crosses `4R`, the ray's direction, and the colour of its light.
fn ray_candidates(map: &CoarseMap, o: (f64, f64), taken: &[Band]) -> Vec<CoarseStreak> {
    let (s, w, h, rc) = (&map.s[..], map.w, map.h, map.rc);
    let colour_at = |x: f64, y: f64| map.colour_at(x, y);
    let level = map.level as f64;
    let sigma = (map.noise as f64).max(1e-9);
    // The streaks the rings found, as straight bands: a ray that crosses one skips it.
    let in_band = |x: f64, y: f64| {
        taken.iter().any(|b| {
            let (dx, dy) = (x - b.p.0, y - b.p.1);
            (dx * b.d.1 - dy * b.d.0).abs() < 1.8 * rc
        })
    };
    let at = |x: f64, y: f64| -> Option<f64> {
        if x < 0.0 || y < 0.0 {
            return None;
        }
        let (xi, yi) = (x.round() as usize, y.round() as usize);
        (xi < w && yi < h).then(|| s[yi * w + xi] as f64 - level)
    };
    let n_dir = 360usize;
    let offsets: Vec<f64> = (-4..=4).map(|k| k as f64 * 0.5 * rc).collect();
    let step = 1.0;
    let t0 = 2.5 * rc;
    let free = |a: f64| {
        taken.iter().all(|b| {
            let d = (a - b.phi).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d) > 20f64.to_radians()
        })
    };
    // Per direction: the best (statistic, offset, length) over offsets.
    let best: Vec<(f64, f64, f64)> = (0..n_dir)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n_dir as f64;
            let mut top = (f64::NEG_INFINITY, 0.0, 0.0);
            let (d, n) = ((a.cos(), a.sin()), (-a.sin(), a.cos()));
            for &b in &offsets {
                let t4 = (16.0 * rc * rc - b * b).sqrt();
                if !free((b * n.1 + t4 * d.1).atan2(b * n.0 + t4 * d.0)) {
                    continue;
                }
                let (mut acc, mut cnt) = (0.0, 0usize);
                let mut t = t0;
                let mut next_len = 3.0 * rc;
                loop {
                    let (x, y) = (o.0 + b * n.0 + t * d.0, o.1 + b * n.1 + t * d.1);
                    let Some(v) = at(x, y) else { break };
                    t += step;
                    if in_band(x, y) {
                        continue;
                    }
                    acc += v;
                    cnt += 1;
                    let len = t - t0;
                    if len >= next_len && cnt as f64 >= 0.5 * len / step {
                        let stat = acc / cnt as f64 * (cnt as f64 * step / rc).sqrt() / sigma;
                        if stat > top.0 {
                            top = (stat, b, len);
                        }
                        next_len *= 1.25;
                    }
                }
            }
            top
        })
        .collect();
    if std::env::var_os("STREAKFIT_DEBUG").is_some() {
        let peaks: Vec<String> = (0..n_dir)
            .filter(|&k| {
                let (p, q) = (best[(k + n_dir - 1) % n_dir].0, best[(k + 1) % n_dir].0);
                best[k].0 >= p && best[k].0 >= q && best[k].0 > 3.0
            })
            .map(|k| {
                format!(
                    "{k}°:{:.1} b{:.1} L{:.0}",
                    best[k].0,
                    best[k].1 / rc,
                    best[k].2 / rc
                )
            })
            .collect();
        eprintln!("rays: peaks {peaks:?}");
    }
    let above: Vec<bool> = best.iter().map(|b| b.0 > RAY_SIGNIFICANCE).collect();
    let Some(start) = above.iter().position(|b| !*b) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut run: Vec<usize> = Vec::new();
    for i in 0..=n_dir {
        let k = (start + i) % n_dir;
        if i < n_dir && above[k] {
            run.push(k);
            continue;
        }
        if let Some(&kb) = run
            .iter()
            .max_by(|&&x, &&y| best[x].0.total_cmp(&best[y].0))
        {
            let a = std::f64::consts::TAU * kb as f64 / n_dir as f64;
            let (d, n) = ((a.cos(), a.sin()), (-a.sin(), a.cos()));
            let (_, b, len) = best[kb];
            let rho = 4.0 * rc;
            let t = (rho * rho - b * b).max(0.0).sqrt();
            let seed = (o.0 + b * n.0 + t * d.0, o.1 + b * n.1 + t * d.1);
            let mut col = [0f64; 3];
            let mut q = t0;
            while q <= t0 + len {
                let cc = colour_at(o.0 + b * n.0 + q * d.0, o.1 + b * n.1 + q * d.1);
                for c in 0..3 {
                    col[c] += cc[c];
                }
                q += step;
            }
            let cn = (col[0] * col[0] + col[1] * col[1] + col[2] * col[2]).sqrt();
            if cn > 0.0 && at(seed.0, seed.1).is_some() {
                out.push(CoarseStreak {
                    seed,
                    dir: d,
                    weight: 0.0,
                    u: col.map(|v| (v / cn) as f32),
                    faint: true,
                });
            }
        }
        run.clear();
    }
    out
}

/// Result of one cross-profile: centre offset along the normal, its sigma, core amplitude and
/// flank noise.
#[derive(Debug, Clone, Copy)]
pub struct ProfileCentre {
    pub c: f64,
    pub sigma: f64,
    pub amp: f64,
    pub noise: f64,
    pub n_core: f64,
    /// Linear baseline `b0 + b1 t` under the profile.
    pub b0: f64,
    pub b1: f64,
}

/// Number of sub-samples along the streak averaged into one profile point (one per pixel of the
/// step length).
fn sub_steps(step: f64) -> usize {
    (step.round() as usize).max(1)
}

/// One cross-profile: offsets `t` (px along the normal `n = (-d.y, d.x)` from the profile's
/// centre point), the signal averaged over one step along the streak, and which offsets fall in
/// another ball's light.
#[derive(Debug, Clone)]
pub struct Profile {
    pub t: Vec<f64>,
    pub v: Vec<f64>,
    pub bad: Vec<bool>,
}

/// Samples the cross-profile through `p` perpendicular to unit `d` over `±1.7 R`, of the signal
/// projected on `w` (a [`Signal::projector`]); `None` when the core is cut by the image border.
pub fn sample_profile(
    sig: &Signal,
    p: (f64, f64),
    d: (f64, f64),
    r: f64,
    step: f64,
    excl: Option<&Exclusion>,
    w: [f32; 3],
) -> Option<Profile> {
    let n = (-d.1, d.0);
    let half = (1.7 * r).ceil() as i64;
    let n_a = sub_steps(step);
    let plane = sig.projected(w);
    let mut t = Vec::with_capacity(2 * half as usize + 1);
    let mut v = Vec::with_capacity(2 * half as usize + 1);
    // The points along the streak, `p + a d`, each offset by `tk n` below.
    let base: Vec<(f64, f64)> = (0..n_a)
        .map(|j| {
            let a = (j as f64 + 0.5) / n_a as f64 * step - step / 2.0;
            (p.0 + a * d.0, p.1 + a * d.1)
        })
        .collect();
    for k in -half..=half {
        let tk = k as f64;
        let Some(acc) = plane.sum_along(&base, (tk * n.0, tk * n.1)) else {
            // Near the border only the flanks may be cut off; the core must be complete.
            if tk.abs() <= 1.25 * r {
                return None;
            }
            continue;
        };
        t.push(tk);
        v.push((acc / n_a as f32) as f64);
    }
    // Points inside another ball's band (or the disc) carry that ball's light: they may not be
    // in the core, and are left out of the baseline.
    let bad: Vec<bool> = match excl {
        Some(e) => t
            .iter()
            .map(|tk| e.contains(p.0 + tk * n.0, p.1 + tk * n.1))
            .collect(),
        None => vec![false; t.len()],
    };
    Some(Profile { t, v, bad })
}

/// Measures the streak centre on the line through `p` perpendicular to unit `d` (symmetric
/// centroid with a baseline from the flanks), in the signal projected on `w`.
pub fn profile_centre(
    sig: &Signal,
    p: (f64, f64),
    d: (f64, f64),
    r: f64,
    step: f64,
    excl: Option<&Exclusion>,
    w: [f32; 3],
) -> Option<ProfileCentre> {
    let pr = sample_profile(sig, p, d, r, step, excl, w)?;
    let n_a = sub_steps(step);
    centroid(&pr, r, n_a)
}

fn centroid(pr: &Profile, r: f64, n_a: usize) -> Option<ProfileCentre> {
    let (t, v, bad) = (&pr.t, &pr.v, &pr.bad);
    let mut c = 0.0;
    let mut res = None;
    for _it in 0..6 {
        // Baseline from the flanks.
        let (mut s1, mut st, mut stt, mut sv, mut stv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut nl, mut nr) = (0, 0);
        for ((tk, vk), b) in t.iter().zip(v).zip(bad) {
            let dd = tk - c;
            if *b {
                if dd.abs() < 1.2 * r {
                    return None;
                }
                continue;
            }
            if dd.abs() >= 1.15 * r {
                s1 += 1.0;
                st += tk;
                stt += tk * tk;
                sv += vk;
                stv += tk * vk;
                if dd < 0.0 {
                    nl += 1;
                } else {
                    nr += 1;
                }
            }
        }
        if s1 < 4.0 {
            return None;
        }
        let (b0, b1) = if nl as f64 >= 0.15 * r && nr as f64 >= 0.15 * r {
            let den = s1 * stt - st * st;
            let b1 = (s1 * stv - st * sv) / den;
            ((sv - b1 * st) / s1, b1)
        } else {
            (sv / s1, 0.0)
        };
        let mut flank = Vec::new();
        let (mut sw, mut swt, mut swr) = (0.0, 0.0, 0.0);
        let mut nc = 0.0;
        for ((tk, vk), b) in t.iter().zip(v).zip(bad) {
            let s = vk - (b0 + b1 * tk);
            let dd = (tk - c).abs();
            if *b {
                continue;
            }
            if dd >= 1.15 * r {
                flank.push(s as f32);
            }
            let wgt = (1.1 * r + 0.5 - dd).clamp(0.0, 1.0);
            if wgt > 0.0 {
                sw += wgt * s;
                swt += wgt * s * tk;
                swr += wgt;
                nc += wgt;
            }
        }
        if sw <= 0.0 {
            return None;
        }
        let c_new = swt / sw;
        let noise = (mad_sigma(&flank) as f64).max(1e-9);
        let mut var = 0.0;
        for tk in t {
            let dd = (tk - c_new).abs();
            let wgt = (1.1 * r + 0.5 - dd).clamp(0.0, 1.0);
            var += wgt * wgt * (tk - c_new).powi(2);
        }
        let sigma = (var.sqrt() * noise / sw).max(1e-3);
        res = Some(ProfileCentre {
            c: c_new,
            sigma,
            amp: sw / swr,
            noise,
            n_core: nc * n_a as f64,
            b0,
            b1,
        });
        if (c_new - c).abs() < 1e-3 {
            break;
        }
        if c_new.abs() > 1.2 * r {
            return None;
        }
        c = c_new;
    }
    res
}

/// Degree of the polynomial baseline under a profile fit: measured on clean and realistic
/// synthetic sets (degrees 1, 2, 4, 6), degree ≥ 4 halves the centre-line wander that cloth
/// blotches cause; 6 gains little more.
const BASELINE_DEGREE: usize = 4;

/// The cross-profile shape of one streak, measured from its own profiles: baseline-subtracted,
/// amplitude-normalised, aligned on their centres, averaged and symmetrised. Cloth texture is the
/// same size as a ball, so a centroid follows its blotches; a fit of the streak's own shape takes
/// the centre from where the shape changes fastest (the ball's silhouette edges for a swept
/// disc), where smooth blotches have no leverage. The shape is not assumed (a swept uniform disc
/// gives `sqrt(R² - d²)`, a shaded one `R² - d²`); it is whatever the photo shows.
#[derive(Debug, Clone)]
pub struct Template {
    /// Bin width (px) and half-width of the support (px); `vals[i]` is the shape at
    /// `-half + i h`.
    h: f64,
    half: f64,
    vals: Vec<f64>,
}

/// Bin means `acc / cnt`, with bins that no profile reached filled in linearly from their
/// nearest reached neighbours. The profiles sample whole pixels across the streak, so only the
/// scatter of their centres spreads them over the quarter-pixel bins: on a clean photo, where
/// the centres sit within a few hundredths of a pixel of the walk's, a quarter of the bins stays
/// empty, and on a noisy one it fills. The 1-px smoothing of the shape spans the gaps either way;
/// refusing the template here had left half the streaks of a clean set without one, and an
/// imperceptible change of the photo's values switched it for 3 of those 61 streaks. The
/// outermost bins, where the shape is tapered to zero, take their nearest reached value. `None`
/// when fewer than half were reached.
fn fill_gaps(acc: &[f64], cnt: &[f64]) -> Option<Vec<f64>> {
    let nb = cnt.len();
    let reached: Vec<usize> = (0..nb).filter(|&i| cnt[i] > 0.0).collect();
    if 2 * reached.len() < nb {
        return None;
    }
    let (first, last) = (reached[0], reached[reached.len() - 1]);
    let at = |i: usize| acc[i] / cnt[i];
    let mut mean = vec![at(first); nb];
    for w in reached.windows(2) {
        let (a, b) = (w[0], w[1]);
        for (i, m) in mean.iter_mut().enumerate().take(b).skip(a) {
            *m = at(a) + (at(b) - at(a)) * (i - a) as f64 / (b - a) as f64;
        }
    }
    for m in &mut mean[last..] {
        *m = at(last);
    }
    Some(mean)
}

impl Template {
    /// Builds the shape from profiles with their centres `c`, linear baselines and amplitudes.
    pub fn estimate(profiles: &[(&Profile, ProfileCentre)], r: f64) -> Option<Template> {
        if profiles.len() < 12 {
            return None;
        }
        let h = 0.25;
        let half = 1.25 * r;
        let nb = (2.0 * half / h).round() as usize + 1;
        let mut acc = vec![0.0; nb];
        let mut cnt = vec![0.0; nb];
        for (pr, pc) in profiles {
            if pc.amp <= 0.0 {
                continue;
            }
            for ((tk, vk), b) in pr.t.iter().zip(&pr.v).zip(&pr.bad) {
                if *b {
                    continue;
                }
                let uu = tk - pc.c;
                if uu.abs() > half {
                    continue;
                }
                let s = (vk - pc.b0 - pc.b1 * tk) / pc.amp;
                // Linear splatting into the two nearest bins.
                let x = (uu + half) / h;
                let i0 = x as usize; // x ≥ 0: the floor
                let f = x - i0 as f64;
                if i0 < nb {
                    acc[i0] += (1.0 - f) * s;
                    cnt[i0] += 1.0 - f;
                }
                if i0 + 1 < nb {
                    acc[i0 + 1] += f * s;
                    cnt[i0 + 1] += f;
                }
            }
        }
        let mean = fill_gaps(&acc, &cnt)?;
        // Symmetrise (the swept silhouette is symmetric about the centre-line), smooth with a
        // 1-px box (sub-pixel alignment noise), and pin the tails to zero beyond the edge.
        let sym: Vec<f64> = (0..nb)
            .map(|i| 0.5 * (mean[i] + mean[nb - 1 - i]))
            .collect();
        let k = (0.5 / h).round() as usize;
        let mut vals: Vec<f64> = (0..nb)
            .map(|i| {
                let (a, b) = (i.saturating_sub(k), (i + k).min(nb - 1));
                sym[a..=b].iter().sum::<f64>() / (b - a + 1) as f64
            })
            .collect();
        let edge = 1.1 * r;
        for (i, v) in vals.iter_mut().enumerate() {
            let uu = (-half + i as f64 * h).abs();
            if uu > edge {
                *v *= ((half - uu) / (half - edge)).clamp(0.0, 1.0);
            }
        }
        let peak = vals.iter().cloned().fold(0.0, f64::max);
        (peak > 0.0).then_some(Template { h, half, vals })
    }

    /// Shape and its derivative at offset `x` from the centre (zero outside the support).
    #[inline]
    fn at(&self, x: f64) -> (f64, f64) {
        let q = (x + self.half) / self.h;
        if q <= 0.0 || q >= (self.vals.len() - 1) as f64 {
            return (0.0, 0.0);
        }
        // q > 0: truncation is the floor (without `f64::floor`'s library call).
        let i = q as usize;
        let f = q - i as f64;
        let v = self.vals[i] + f * (self.vals[i + 1] - self.vals[i]);
        // Derivative from a 1-px central difference of the interpolated shape (smooth enough for
        // Gauss–Newton, no kinks at bin boundaries).
        let d = 2;
        let (a, b) = (i.saturating_sub(d), (i + d + 1).min(self.vals.len() - 1));
        let g = (self.vals[b] - self.vals[a]) / ((b - a) as f64 * self.h);
        (v, g)
    }

    /// Least-squares fit of `A T(t - c) + B(t)` to a profile, `B` a polynomial baseline of degree
    /// `BASELINE_DEGREE` in `t / 1.7R` (Gauss–Newton in all parameters, from `c0`). The flexible
    /// baseline absorbs cloth blotches of the streak's own size, so the centre comes from the
    /// sharp parts of the shape; its standard error is from the fit's own residual scatter.
    pub fn fit(&self, pr: &Profile, c0: f64, r: f64, n_a: usize) -> Option<ProfileCentre> {
        const K: usize = BASELINE_DEGREE + 3;
        let scale = 1.0 / (1.7 * r);
        // With one flank only, a constant baseline (a slope would trade off with the shape).
        let (mut nl, mut nr) = (0usize, 0usize);
        for (tk, b) in pr.t.iter().zip(&pr.bad) {
            if *b {
                if (tk - c0).abs() < 1.2 * r {
                    return None;
                }
                continue;
            }
            nl += usize::from(tk - c0 <= -1.15 * r);
            nr += usize::from(tk - c0 >= 1.15 * r);
        }
        let deg = if (nl as f64) < 0.15 * r || (nr as f64) < 0.15 * r {
            0
        } else {
            BASELINE_DEGREE
        };
        let k = deg + 3;
        // Baseline basis per sample (fixed while c moves).
        let rows: Vec<(f64, f64, [f64; K])> =
            pr.t.iter()
                .zip(&pr.v)
                .zip(&pr.bad)
                .filter(|(_, b)| !**b)
                .map(|((tk, vk), _)| {
                    let mut f = [0.0; K];
                    let z = tk * scale;
                    let mut zp = 1.0;
                    for q in 0..=deg {
                        f[2 + q] = zp;
                        zp *= z;
                    }
                    (*tk, *vk, f)
                })
                .collect();
        let n = rows.len() as f64;
        // Parameters: [c, A, b_0..b_deg]; Gauss–Newton from the linear solution at c0.
        let mut p = [0.0; K];
        p[0] = c0;
        // Normal equations summed in fixed-size arrays (the same sums in the same order as
        // into the matrices, without their indexing in the loop over the profile).
        {
            let (mut ms, mut rs) = ([[0.0; K]; K], [0.0; K]);
            // The loops run to the fixed `K`: entries beyond `k` sum exact zeros and are not
            // read, and fixed bounds let the compiler unroll them.
            for (tk, vk, f) in &rows {
                let mut g = *f;
                g[1] = self.at(tk - c0).0;
                for a in 1..K {
                    rs[a - 1] += g[a] * vk;
                    for bb in a..K {
                        ms[a - 1][bb - 1] += g[a] * g[bb];
                    }
                }
            }
            let mut m = nalgebra::DMatrix::<f64>::from_fn(k - 1, k - 1, |a, b| ms[a][b]);
            let rv = nalgebra::DVector::<f64>::from_fn(k - 1, |a, _| rs[a]);
            m.fill_lower_triangle_with_upper_triangle();
            let lin = m.cholesky()?.solve(&rv);
            p[1..k].copy_from_slice(&lin.as_slice()[..k - 1]);
        }
        let mut last = None;
        for _it in 0..8 {
            if p[1] <= 0.0 {
                return None;
            }
            let (mut ms, mut bs) = ([[0.0; K]; K], [0.0; K]);
            let mut sse = 0.0;
            for (tk, vk, f) in &rows {
                let (tv, tg) = self.at(tk - p[0]);
                let mut j = *f;
                j[0] = -p[1] * tg;
                j[1] = tv;
                let model: f64 = (1..k).map(|q| p[q] * j[q]).sum();
                let e = vk - model;
                for a in 0..K {
                    bs[a] += j[a] * e;
                    for bb in a..K {
                        ms[a][bb] += j[a] * j[bb];
                    }
                }
                sse += e * e;
            }
            let mut ata = nalgebra::DMatrix::<f64>::from_fn(k, k, |a, b| ms[a][b]);
            let atb = nalgebra::DVector::<f64>::from_fn(k, |a, _| bs[a]);
            ata.fill_lower_triangle_with_upper_triangle();
            let chol = ata.cholesky()?;
            let step = chol.solve(&atb);
            let dc = step[0].clamp(-0.25 * r, 0.25 * r);
            let done = dc.abs() < 1e-3;
            last = Some((chol, sse));
            p[0] += dc;
            for q in 1..k {
                p[q] += step[q];
            }
            if done {
                break;
            }
            if (p[0] - c0).abs() > 0.5 * r {
                return None;
            }
        }
        let (chol, sse) = last?;
        let s2 = sse / (n - k as f64).max(1.0);
        let var_c = chol.inverse()[(0, 0)] * s2;
        // The baseline's value and slope at t = 0 (for the template of the next round).
        let (b0, b1) = (p[2], if deg >= 1 { p[3] * scale } else { 0.0 });
        Some(ProfileCentre {
            c: p[0],
            sigma: var_c.max(0.0).sqrt().max(1e-3),
            amp: p[1] * self.peak_mean(),
            noise: s2.sqrt(),
            n_core: 2.2 * r * n_a as f64,
            b0,
            b1,
        })
    }

    /// Mean of the shape over the core `|x| ≤ 1.1 R` relative to its normalisation, so that
    /// `amp` keeps the meaning "mean core signal" of the centroid.
    fn peak_mean(&self) -> f64 {
        let n = self.vals.len();
        let m = n / 2;
        let k = (0.88 * self.half / self.h) as usize;
        self.vals[m.saturating_sub(k)..(m + k).min(n)]
            .iter()
            .sum::<f64>()
            / (2 * k).max(1) as f64
    }
}

/// Where to stop tracking: the disc of the object ball (no profile line may come within
/// `keep_out` of its centre).
#[derive(Debug, Clone, Copy)]
pub struct KeepOut {
    pub ox: f64,
    pub oy: f64,
    pub radius: f64,
}

/// Tracks a streak of colour `u` from `seed` along `dir` (and backwards towards the disc),
/// returning the centre-line samples ordered from the disc end outward.
pub fn track(
    sig: &Signal,
    seed: (f64, f64),
    dir: (f64, f64),
    r: f64,
    step_r: f64,
    keep_out: KeepOut,
    u: [f32; 3],
) -> Vec<Sample> {
    let step = (r * step_r).max(2.0);
    let w = sig.projector(u);
    // A streak that leaves the frame early (the impact near an edge) can have its seed where the
    // cross-profile is already cut by the border: then start again nearer the disc.
    for k in 0..=4 {
        let back = 0.5 * r * k as f64;
        let s = (seed.0 - back * dir.0, seed.1 - back * dir.1);
        if k > 0 && (s.0 - keep_out.ox).hypot(s.1 - keep_out.oy) < keep_out.radius + r {
            break;
        }
        let outward = walk(sig, s, dir, r, step, keep_out, w);
        let inward = walk(sig, s, (-dir.0, -dir.1), r, step, keep_out, w);
        if outward.is_empty() && inward.is_empty() {
            continue;
        }
        let mut all: Vec<Sample> = inward.into_iter().skip(1).rev().collect();
        all.extend(outward);
        return all;
    }
    Vec::new()
}

fn walk(
    sig: &Signal,
    seed: (f64, f64),
    dir: (f64, f64),
    r: f64,
    step: f64,
    ko: KeepOut,
    w: [f32; 3],
) -> Vec<Sample> {
    let mut out: Vec<Sample> = Vec::new();
    let mut p = seed;
    let mut d = dir;
    let mut fails = 0;
    let mut skipped = 0usize;
    let max_steps = (4.0 * (sig.w + sig.h) as f64 / step) as usize;
    for _ in 0..max_steps {
        // The profile line must stay clear of the disc.
        let n = (-d.1, d.0);
        let (qx, qy) = (p.0 - ko.ox, p.1 - ko.oy);
        let along_n = qx * n.0 + qy * n.1;
        let perp = (qx * d.0 + qy * d.1).abs();
        let half = 1.7 * r;
        let closest = if along_n.abs() <= half {
            perp
        } else {
            (perp * perp + (along_n.abs() - half).powi(2)).sqrt()
        };
        if closest < ko.radius {
            // A short streak seeded on the inner ring starts with profiles that graze the disc:
            // step outward until they clear it (never inward, never after samples were taken).
            let outward = qx * d.0 + qy * d.1 > 0.0;
            if out.is_empty() && outward && skipped as f64 * step < 3.0 * r {
                skipped += 1;
                p = (p.0 + step * d.0, p.1 + step * d.1);
                continue;
            }
            break;
        }
        let Some(pc) = profile_centre(sig, p, d, r, step, None, w) else {
            break;
        };
        let snr = pc.amp / (pc.noise / pc.n_core.sqrt());
        // The streak ends where its light falls well below its running level (the ball stopped
        // or the streak faded); the last half radius before that is its rounded end, left out.
        let faded = out.len() >= 5 && {
            let mut a: Vec<f32> = out.iter().rev().take(40).map(|s| s.amp as f32).collect();
            (pc.amp as f32) < 0.35 * super::background::median(&mut a)
        };
        if snr < 5.0 || faded {
            fails += 1;
            if fails >= 3 {
                let trim = (0.5 * r / step).ceil() as usize;
                out.truncate(out.len().saturating_sub(trim));
                break;
            }
            p = (p.0 + step * d.0, p.1 + step * d.1);
            continue;
        }
        fails = 0;
        let q = (p.0 + pc.c * n.0, p.1 + pc.c * n.1);
        out.push(Sample {
            x: q.0,
            y: q.1,
            sigma: pc.sigma,
            amp: pc.amp,
        });
        // Direction from the chord over the last ~2R of samples (follows the parabola, ignores
        // single-sample noise).
        let back = ((2.0 * r / step) as usize).max(2);
        if out.len() > back / 2 {
            let a = &out[out.len().saturating_sub(back + 1)];
            let (dx, dy) = (q.0 - a.x, q.1 - a.y);
            let l = dx.hypot(dy);
            if l > 0.5 * r {
                let nd = (dx / l, dy / l);
                // Never turn back on itself.
                if nd.0 * d.0 + nd.1 * d.1 > 0.5 {
                    d = nd;
                }
            }
        }
        p = (q.0 + step * d.0, q.1 + step * d.1);
    }
    out
}

/// Regions where another ball's light falls: bands of half-width `half` around polylines, and
/// discs.
///
/// [`Exclusion::contains`] is asked for every pixel of a profile and of an incoming block, and
/// a band along a streak across the photo has some twenty segments, so the shapes are indexed
/// by a grid of cells one reach wide (built on first use): a point is tested only against the
/// shapes whose bounding box meets its cell, with the same comparisons as without the grid, so
/// the answer is the same to the bit.
#[derive(Debug, Clone, Default)]
pub struct Exclusion {
    bands: Vec<(Vec<(f64, f64)>, f64)>,
    discs: Vec<((f64, f64), f64)>,
    grid: OnceLock<Grid>,
}

/// One shape of an [`Exclusion`]: a disc (centre, radius) or one segment of a band (its ends
/// and half-width).
#[derive(Debug, Clone, Copy)]
enum Shape {
    Disc((f64, f64), f64),
    Segment((f64, f64), (f64, f64), f64),
}

impl Shape {
    fn contains(&self, x: f64, y: f64) -> bool {
        match *self {
            Shape::Disc(c, rr) => (x - c.0).powi(2) + (y - c.1).powi(2) < rr * rr,
            Shape::Segment(a, b, h) => seg_dist2((x, y), a, b) < h * h,
        }
    }

    /// Box outside which no point is contained: `(x0, y0, x1, y1)`.
    fn bounds(&self) -> (f64, f64, f64, f64) {
        match *self {
            Shape::Disc(c, rr) => (c.0 - rr, c.1 - rr, c.0 + rr, c.1 + rr),
            Shape::Segment(a, b, h) => (
                a.0.min(b.0) - h,
                a.1.min(b.1) - h,
                a.0.max(b.0) + h,
                a.1.max(b.1) + h,
            ),
        }
    }
}

/// The shapes of an [`Exclusion`] listed per grid cell (compressed rows: cell `k` holds
/// `shapes[index[start[k]..start[k + 1]]]`).
#[derive(Debug, Clone)]
struct Grid {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<usize>,
    index: Vec<usize>,
    shapes: Vec<Shape>,
}

impl Grid {
    fn new(shapes: Vec<Shape>) -> Grid {
        let bounds: Vec<(f64, f64, f64, f64)> = shapes.iter().map(Shape::bounds).collect();
        let reach = shapes
            .iter()
            .map(|s| match *s {
                Shape::Disc(_, r) | Shape::Segment(_, _, r) => r,
            })
            .fold(1.0, f64::max);
        let (x0, y0, x1, y1) = bounds.iter().fold(
            (
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ),
            |a, b| (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3)),
        );
        if shapes.is_empty() || !(x1 >= x0 && y1 >= y0) {
            return Grid {
                x0: 0.0,
                y0: 0.0,
                cell: 1.0,
                nx: 0,
                ny: 0,
                start: vec![0],
                index: Vec::new(),
                shapes,
            };
        }
        let cell = reach;
        let nx = ((x1 - x0) / cell).floor() as usize + 1;
        let ny = ((y1 - y0) / cell).floor() as usize + 1;
        let span = |lo: f64, hi: f64, o: f64, n: usize| {
            let a = (((lo - o) / cell).floor().max(0.0) as usize).min(n - 1);
            let b = (((hi - o) / cell).floor().max(0.0) as usize).min(n - 1);
            a..=b
        };
        let mut lists: Vec<Vec<usize>> = vec![Vec::new(); nx * ny];
        for (i, b) in bounds.iter().enumerate() {
            for cy in span(b.1, b.3, y0, ny) {
                for cx in span(b.0, b.2, x0, nx) {
                    lists[cy * nx + cx].push(i);
                }
            }
        }
        let mut start = Vec::with_capacity(nx * ny + 1);
        let mut index = Vec::new();
        start.push(0);
        for l in &lists {
            index.extend_from_slice(l);
            start.push(index.len());
        }
        Grid {
            x0,
            y0,
            cell,
            nx,
            ny,
            start,
            index,
            shapes,
        }
    }

    fn contains(&self, x: f64, y: f64) -> bool {
        let (fx, fy) = ((x - self.x0) / self.cell, (y - self.y0) / self.cell);
        // Outside the union of the shapes' boxes (or NaN): in none of them.
        if !(fx >= 0.0 && fy >= 0.0) {
            return false;
        }
        let (cx, cy) = (fx.floor() as usize, fy.floor() as usize);
        if cx >= self.nx || cy >= self.ny {
            return false;
        }
        let k = cy * self.nx + cx;
        self.index[self.start[k]..self.start[k + 1]]
            .iter()
            .any(|&i| self.shapes[i].contains(x, y))
    }
}

/// Squared distance from `p` to the segment `a → b`.
pub(super) fn seg_dist2(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a.0 + t * dx - p.0, a.1 + t * dy - p.1);
    qx * qx + qy * qy
}

impl Exclusion {
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.grid
            .get_or_init(|| {
                let discs = self.discs.iter().map(|&(c, rr)| Shape::Disc(c, rr));
                let segments = self.bands.iter().flat_map(|(pts, h)| {
                    pts.windows(2).map(move |w| Shape::Segment(w[0], w[1], *h))
                });
                Grid::new(discs.chain(segments).collect())
            })
            .contains(x, y)
    }

    /// The same test without the grid: every shape in turn (the definition the grid must meet).
    #[cfg(test)]
    fn contains_by_scan(&self, x: f64, y: f64) -> bool {
        self.discs
            .iter()
            .any(|(c, rr)| (x - c.0).powi(2) + (y - c.1).powi(2) < rr * rr)
            || self.bands.iter().any(|(pts, h)| {
                pts.windows(2)
                    .any(|w| seg_dist2((x, y), w[0], w[1]) < h * h)
            })
    }

    /// Adds a disc of radius `rr` about `c`.
    pub fn add_disc(&mut self, c: (f64, f64), rr: f64) {
        self.discs.push((c, rr));
        self.grid = OnceLock::new();
    }

    /// Adds a band along `pts`, decimated to vertices about `step` apart (paths are smooth on
    /// that scale).
    pub fn add_band(&mut self, pts: &[(f64, f64)], half: f64, step: f64) {
        let mut out: Vec<(f64, f64)> = Vec::new();
        for (i, p) in pts.iter().enumerate() {
            let keep = out
                .last()
                .is_none_or(|q: &(f64, f64)| (p.0 - q.0).hypot(p.1 - q.1) >= step)
                || i + 1 == pts.len();
            if keep {
                out.push(*p);
            }
        }
        if out.len() >= 2 {
            self.bands.push((out, half));
            self.grid = OnceLock::new();
        }
    }
}

/// One re-measured profile: its point, the streak direction there, the profile and its centre.
type Measured = ((f64, f64), (f64, f64), Profile, ProfileCentre);

/// Re-measures a streak's centre-line at its samples with other balls' light excluded, and
/// extends it towards `start` (the impact or the disc) while the core stays clean; `u` is the
/// streak's colour. Centroids
/// first; then two rounds of the streak's own [`Template`] fitted to every profile.
pub fn remeasure(
    sig: &Signal,
    samples: &[Sample],
    start: (f64, f64),
    r: f64,
    step_r: f64,
    excl: &Exclusion,
    u: [f32; 3],
) -> Vec<Sample> {
    let step = (r * step_r).max(2.0);
    let u = sig.projector(u);
    let n_a = sub_steps(step);
    let n = samples.len();
    let dir_at = |i: usize| {
        let k = ((2.0 * r / step) as usize).max(1);
        let (a, b) = (&samples[i.saturating_sub(k)], &samples[(i + k).min(n - 1)]);
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let l = dx.hypot(dy).max(1e-9);
        (dx / l, dy / l)
    };
    // Ordered from the start outward.
    let mut entries: Vec<Measured> = Vec::new();
    let snr_of = |pc: &ProfileCentre| pc.amp / (pc.noise / pc.n_core.sqrt());
    // Inward extension, from the first sample back towards the start point.
    if n >= 2 {
        let d = dir_at(0);
        let mut p = (samples[0].x - step * d.0, samples[0].y - step * d.1);
        let mut ext = Vec::new();
        let dist0 = (samples[0].x - start.0).hypot(samples[0].y - start.1);
        for _ in 0..((dist0 / step) as usize) {
            let Some(pr) = sample_profile(sig, p, d, r, step, Some(excl), u) else {
                break;
            };
            let Some(pc) = centroid(&pr, r, n_a) else {
                break;
            };
            if snr_of(&pc) < 5.0 || pc.c.abs() > 0.15 * r {
                break;
            }
            ext.push((p, d, pr, pc));
            // Step along the extrapolated line, not from the measured centre, so light from
            // elsewhere cannot drag the extension off the streak.
            p = (p.0 - step * d.0, p.1 - step * d.1);
        }
        entries.extend(ext.into_iter().rev());
    }
    for (i, smp) in samples.iter().enumerate() {
        let d = dir_at(i);
        let p = (smp.x, smp.y);
        if let Some(pr) = sample_profile(sig, p, d, r, step, Some(excl), u)
            && let Some(pc) = centroid(&pr, r, n_a)
            && snr_of(&pc) >= 5.0
            && pc.c.abs() < 0.3 * r
        {
            entries.push((p, d, pr, pc));
        }
    }
    let debug = std::env::var_os("STREAKFIT_DEBUG").is_some();
    for round in 0..2 {
        let refs: Vec<(&Profile, ProfileCentre)> = entries.iter().map(|e| (&e.2, e.3)).collect();
        let Some(tpl) = Template::estimate(&refs, r) else {
            if debug {
                eprintln!(
                    "remeasure: no template from {} profiles (round {round})",
                    refs.len()
                );
            }
            break;
        };
        let before = entries.len();
        entries = entries
            .into_iter()
            .filter_map(|(p, d, pr, pc)| {
                let f = tpl.fit(&pr, pc.c, r, n_a)?;
                (f.c.abs() < 0.3 * r).then_some((p, d, pr, f))
            })
            .collect();
        if debug {
            eprintln!(
                "remeasure: template round {round} fits {} of {before} profiles",
                entries.len()
            );
        }
    }
    entries
        .into_iter()
        .map(|(p, d, _, pc)| Sample {
            x: p.0 - pc.c * d.1,
            y: p.1 + pc.c * d.0,
            sigma: pc.sigma,
            amp: pc.amp,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::background;
    use crate::vision::image_io::RgbImage;

    proptest::proptest! {
        /// The grid answers as the scan over every shape does, on random discs and bands and on
        /// points drawn near their edges, on cell seams and far outside.
        #[test]
        fn the_exclusion_grid_answers_as_the_scan_over_every_shape(
            discs in proptest::collection::vec(((0.0f64..800.0, 0.0f64..600.0), 1.0f64..150.0), 0..3),
            bands in proptest::collection::vec(
                (proptest::collection::vec((0.0f64..800.0, 0.0f64..600.0), 2..12), 1.0f64..130.0),
                0..3,
            ),
            points in proptest::collection::vec((-200.0f64..1000.0, -200.0f64..800.0), 200),
        ) {
            let mut ex = Exclusion::default();
            for &(c, rr) in &discs {
                ex.add_disc(c, rr);
            }
            for (pts, h) in &bands {
                ex.add_band(pts, *h, 40.0);
            }
            let mut probe: Vec<(f64, f64)> = points.clone();
            // Points on the edges: a disc's rim, a band's edge, a cell's seam.
            for &(c, rr) in &discs {
                probe.push((c.0 + rr, c.1));
                probe.push((c.0, c.1 - rr));
            }
            for (pts, h) in &ex.bands {
                probe.push((pts[0].0, pts[0].1 + h));
                probe.push((pts[pts.len() - 1].0 - h, pts[pts.len() - 1].1));
            }
            ex.contains(0.0, 0.0);
            let g = ex.grid.get().expect("built by the query above");
            probe.push((g.x0 + g.cell, g.y0 + 2.0 * g.cell));
            probe.push((g.x0, g.y0));
            probe.push((f64::NAN, 10.0));
            for &(x, y) in &probe {
                proptest::prop_assert_eq!(ex.contains(x, y), ex.contains_by_scan(x, y), "at ({}, {})", x, y);
            }
            // A shape added after a query is seen.
            ex.add_disc((5000.0, 5000.0), 10.0);
            proptest::prop_assert!(ex.contains(5001.0, 5002.0));
        }
    }

    #[test]
    fn empty_template_bins_are_filled_from_their_neighbours() {
        // Bins 0, 2 and 5 empty: the gap between reached bins linear, the ends their nearest
        // reached value.
        let acc = [0.0, 4.0, 0.0, 8.0, 2.5, 0.0];
        let cnt = [0.0, 2.0, 0.0, 2.0, 0.5, 0.0];
        let m = fill_gaps(&acc, &cnt).expect("3 of 6 reached");
        let want = [2.0, 2.0, 3.0, 4.0, 5.0, 5.0];
        for (a, b) in m.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{m:?}");
        }
        assert!(fill_gaps(&[1.0, 0.0, 0.0, 1.0], &[1.0, 0.0, 0.0, 1.0]).is_some());
        assert!(fill_gaps(&[1.0, 0.0, 0.0, 0.0], &[1.0, 0.0, 0.0, 0.0]).is_none());
    }

    /// Profiles of a swept disc (`sqrt(R² - d²)`, R = 20 px) sampled at whole pixels, their
    /// centres within ±0.01 px of the profile points, as on a clean photo: a quarter of the
    /// template's quarter-pixel bins get no sample, and the template must still be built and
    /// find a profile's centre.
    #[test]
    fn a_template_is_built_from_profiles_centred_on_whole_pixels() {
        let r = 20.0;
        let shape = |d: f64| (1.0 - (d / r).powi(2)).max(0.0).sqrt();
        let profile = |c: f64| {
            let t: Vec<f64> = (-34..=34).map(f64::from).collect();
            let v = t.iter().map(|tk| 0.3 + 0.05 * shape(tk - c)).collect();
            let bad = vec![false; t.len()];
            Profile { t, v, bad }
        };
        let centre = |c: f64| ProfileCentre {
            c,
            sigma: 0.01,
            amp: 0.05,
            noise: 1e-3,
            n_core: 44.0,
            b0: 0.3,
            b1: 0.0,
        };
        let cs: Vec<f64> = (0..20).map(|k| 0.01 * f64::from(k % 3 - 1)).collect();
        let prs: Vec<Profile> = cs.iter().map(|&c| profile(c)).collect();
        let refs: Vec<(&Profile, ProfileCentre)> =
            prs.iter().zip(&cs).map(|(p, &c)| (p, centre(c))).collect();
        let tpl = Template::estimate(&refs, r).expect("a template");
        // Its shape at the middle of an empty bin (phase 0.5 px) lies on the swept disc.
        let (v_mid, _) = tpl.at(5.5);
        let (v0, _) = tpl.at(0.0);
        assert!(
            (v_mid / v0 - shape(5.5)).abs() < 0.01,
            "{v_mid} / {v0} against {}",
            shape(5.5)
        );
        for c in [0.3, -0.45, 1.2] {
            let f = tpl.fit(&profile(c), 0.0, r, 1).expect("a fit");
            assert!((f.c - c).abs() < 0.01, "centre {} for {c}", f.c);
        }
    }

    /// A streak of radius `R` = 20 px (chord-dwell profile) from a disc at (300, 300) up and out
    /// of the frame at 40° from the vertical, on flat cloth, seeded 5 px below the top edge: the
    /// tilted cross-profile there is cut by the border, so the walk must start nearer the disc.
    #[test]
    fn track_starts_nearer_the_disc_when_the_seed_profile_is_cut_by_the_border() {
        let (w, h, r) = (600usize, 400usize, 20.0f64);
        let (ox, oy) = (300.0, 300.0);
        let dir = (40f64.to_radians().sin(), -40f64.to_radians().cos());
        let mut data = vec![0f32; 3 * w * h];
        for y in 0..h {
            for x in 0..w {
                let (qx, qy) = (x as f64 - ox, y as f64 - oy);
                let along = qx * dir.0 + qy * dir.1;
                let d = (qx * dir.1 - qy * dir.0).abs();
                let streak = if along > 0.0 && d < r {
                    0.05 * (1.0 - (d / r).powi(2)).sqrt() as f32
                } else {
                    0.0
                };
                let disc = if qx.hypot(qy) < r { 0.6 } else { 0.0 };
                let i = 3 * (y * w + x);
                data[i] = 0.10 + streak + disc;
                data[i + 1] = 0.30 + streak + disc;
                data[i + 2] = 0.15 + streak + disc;
            }
        }
        let img = RgbImage::from_f32(w, h, data);
        let sig = background::build(&img, background::Cloth::Surface, 600).expect("signal");
        let ko = KeepOut {
            ox,
            oy,
            radius: 1.25 * r,
        };
        // A seed on the centre-line 5 px below the top edge.
        let t = (oy - 5.0) / -dir.1;
        let seed = (ox + t * dir.0, oy + t * dir.1);
        let s = track(&sig, seed, dir, r, 0.1, ko, [0.577, 0.577, 0.577]);
        assert!(s.len() >= 20, "{} samples", s.len());
        for q in &s {
            let d = ((q.x - ox) * dir.1 - (q.y - oy) * dir.0).abs();
            assert!(d < 0.2, "sample {:.2} px off the centre-line", d);
        }
    }
}
