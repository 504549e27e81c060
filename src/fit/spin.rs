//! Per-shot spin uncertainty (issue 8): profile likelihood and regime ambiguity.
//!
//! With the globals held at the fit, a shot's `chi²(psi, r, s)` is often far from quadratic in
//! `(r, s)` (English barely moves billiard-ball angles in gross slip, and the object ball's throw
//! can be traded between `r` and `s`), so the curvature at the optimum understates the error.
//! Instead, the 2-sigma interval of `r` (and of `s`) is the set where the *profile*
//! `chi²_p(r) = min over (psi, s) of chi²(psi, r, s)` stays within `Δ = 4 k²` of its minimum
//! (`k` = the fit's error scale, `max(1, sqrt(chi²_red))`): walked outward from the estimate,
//! first to the quadratic guess of the boundary (the conditional Jacobian error times
//! `sqrt(Δ)`), then with growing steps; the crossing is refined by regula falsi in
//! `sqrt(Δchi²)` (exact for a quadratic profile; accepted within ±15 % of `Δ`). Beyond it a
//! coarse screen (the other spin component on its grid, psi held) looks for a second minimum
//! within `Δ`, which then joins the interval (reported as multi-modal). The reported 1-sigma is half the larger distance from
//! the estimate to the interval's ends, combined in quadrature with what the globals'
//! uncertainty adds (`local_var - local_var_cond` from the Schur complement).
//!
//! Regime ambiguity: for free spin a shot can often be reproduced in either state of the
//! ball–ball contact (gross slip or stick) with different `(r, s)`. Each shot is therefore also
//! fitted with the other ball–ball state (table contact kept). A hypothesis is *admissible* when
//! it is physically possible: a slipping ball–ball contact needs `mu0 < c(psi, r, s)` (the
//! critical static friction, [`critical_mu_static`]) and static friction is never below dynamic,
//! `mu0 ≥ mu`, so slip is excluded where `c ≤ mu`; stick needs only `mu0 ≥ c`, which the angles
//! of one shot cannot exclude. The best admissible hypothesis gives `regime_est` and the estimate;
//! when another admissible hypothesis lies within `Δ` of it, the shot's `r` is ambiguous and its
//! interval is the union of both hypotheses' intervals (the reason names both values).

use super::problem::{
    ENGLISH_PRIOR_SIGMA, LOCAL_HI, LOCAL_LO, NG, NL, NRES, SPIN_PRIOR_SIGMA, ShotData,
    critical_mu_static, residuals,
};
use super::solver::{FORWARD_STEP, Problem, State};
use crate::physics::Regime;

/// Reseeding grid of spin `r` (`[-2, 3]`, step 0.25) and English `s` (`[-1, 1]`, step 0.2).
pub fn spin_grid() -> impl Iterator<Item = (f64, f64)> {
    (0..=20).flat_map(|a| (0..=10).map(move |b| (-2.0 + 0.25 * a as f64, -1.0 + 0.2 * b as f64)))
}

/// How far the profile walk goes from the estimate (`r`, `s`): beyond this the component is
/// undetermined anyway (its 1-sigma would exceed half the prior width).
const SPAN: [f64; NL] = [0.0, SPIN_PRIOR_SIGMA, ENGLISH_PRIOR_SIGMA];
/// Step of the coarse screen beyond the first crossing.
const COARSE: [f64; NL] = [0.0, 0.2, 0.2];
/// How far above `Δ` a screened grid column may lie and still be refined (psi, held on the
/// screen, can lower the cost by about this much).
const SCREEN_SLACK: f64 = 9.0;

/// One shot's spin result.
#[derive(Debug, Clone, PartialEq)]
pub struct ShotSpin {
    pub regime: Regime,
    /// Locals `(psi, r, s)` of the reported hypothesis.
    pub l: [f64; NL],
    /// 1-sigma of `r` and `s` (infinite when the walk reached its span).
    pub r_err: f64,
    pub s_err: f64,
    /// Notes on ambiguity or multi-modality.
    pub notes: Vec<String>,
}

/// One regime hypothesis of a shot.
struct Hypothesis {
    regime: Regime,
    l: [f64; NL],
    cost: f64,
}

fn one_shot<'a>(s: &'a ShotData, regime: Regime, huber: Option<f64>) -> Problem<'a> {
    Problem {
        shots: vec![s],
        regimes: vec![regime],
        free_global: [false; NG],
        huber,
    }
}

/// Minimises the shot's cost over its free locals other than `k` (held at `l0[k]`), by
/// damped Gauss–Newton from `l0`. Returns the locals and the cost.
fn minimise_nuisance(
    p: &Problem,
    g: &[f64; NG],
    l0: [f64; NL],
    k: usize,
    iters: usize,
) -> ([f64; NL], f64) {
    let s = p.shots[0];
    let free = s.free_locals();
    let idx: Vec<usize> = (0..NL).filter(|&j| free[j] && j != k).collect();
    let mut l = l0;
    // Residuals at the current point, kept from its cost evaluation.
    let mut r0 = residuals(s, g, &l, p.regimes[0]);
    let mut cost = p.block_cost(&r0).0;
    if idx.is_empty() {
        return (l, cost);
    }
    let mut lambda = 1e-3;
    for _ in 0..iters {
        let n = idx.len();
        let mut jac = [[0.0; 2]; NRES];
        // Forward differences: the end point is set by the cost, not by the Jacobian.
        for (c, &j) in idx.iter().enumerate() {
            let h = FORWARD_STEP;
            let mut lp = l;
            lp[j] += h;
            let rp = residuals(s, g, &lp, p.regimes[0]);
            for q in 0..NRES {
                jac[q][c] = (rp[q] - r0[q]) / h;
            }
        }
        let mut a = [[0.0; 2]; 2];
        let mut b = [0.0; 2];
        for q in 0..NRES {
            for u in 0..n {
                b[u] -= jac[q][u] * r0[q];
                for v in 0..n {
                    a[u][v] += jac[q][u] * jac[q][v];
                }
            }
        }
        let mut improved = false;
        for _ in 0..6 {
            let mut d = a;
            for u in 0..n {
                d[u][u] += lambda * a[u][u].max(1e-9) + 1e-12;
            }
            let step = if n == 1 {
                [b[0] / d[0][0], 0.0]
            } else {
                let det = d[0][0] * d[1][1] - d[0][1] * d[1][0];
                if det.abs() < 1e-300 {
                    lambda *= 10.0;
                    continue;
                }
                [
                    (b[0] * d[1][1] - b[1] * d[0][1]) / det,
                    (d[0][0] * b[1] - d[1][0] * b[0]) / det,
                ]
            };
            let mut cand = l;
            for (c, &j) in idx.iter().enumerate() {
                cand[j] = (cand[j] + step[c]).clamp(LOCAL_LO[j], LOCAL_HI[j]);
            }
            let rc = residuals(s, g, &cand, p.regimes[0]);
            let c = p.block_cost(&rc).0;
            if c.is_finite() && c <= cost {
                let drop = cost - c;
                l = cand;
                r0 = rc;
                cost = c;
                lambda = (lambda / 4.0).max(1e-12);
                improved = drop > 1e-8;
                break;
            }
            lambda *= 8.0;
        }
        if !improved {
            break;
        }
    }
    (l, cost)
}

/// The profile point at `l[k] = x`: from a warm start, and when that ends above `accept` also
/// from `best` (the lower of the two is kept).
fn profile_point(
    p: &Problem,
    g: &[f64; NG],
    k: usize,
    x: f64,
    warm: [f64; NL],
    best: [f64; NL],
    accept: f64,
) -> ([f64; NL], f64) {
    let mut a = warm;
    a[k] = x;
    let ra = minimise_nuisance(p, g, a, k, 4);
    if ra.1 <= accept {
        return ra;
    }
    let mut b = best;
    b[k] = x;
    let rb = minimise_nuisance(p, g, b, k, 4);
    if ra.1 <= rb.1 { ra } else { rb }
}

/// Cheapest cost over the other spin component's grid at `l[k] = x` (psi held at `psi`):
/// `(cost, locals)`. A screen for second minima, refined by [`profile_point`] only when low.
fn grid_column(p: &Problem, g: &[f64; NG], k: usize, x: f64, psi: f64) -> (f64, [f64; NL]) {
    let other = 3 - k;
    let (lo, step, n) = if other == 1 {
        (-2.0, 0.25, 21)
    } else {
        (-1.0, 0.2, 11)
    };
    let mut best = (f64::INFINITY, [psi, 0.0, 0.0]);
    for j in 0..n {
        let mut l = [psi, 0.0, 0.0];
        l[k] = x;
        l[other] = lo + step * j as f64;
        let c = p.shot_cost(0, g, &l).0;
        if c < best.0 {
            best = (c, l);
        }
    }
    best
}

/// Result of a profile walk of local `k`.
struct Interval {
    lo: f64,
    hi: f64,
    /// The walk reached its span on this side (the component is not bounded there).
    open: bool,
    /// A separate minimum within `Δ` joined the interval.
    multimodal: bool,
    /// A point below the starting cost was found (the estimate was not the profile minimum).
    better: Option<([f64; NL], f64)>,
}

/// Walks the profile of local `k` outward from `lhat` (cost `c0`) in both directions, see the
/// module doc. `sigma_j`: the conditional Jacobian 1-sigma of `l[k]`, sets the first step.
fn profile_interval(
    p: &Problem,
    g: &[f64; NG],
    lhat: [f64; NL],
    c0: f64,
    k: usize,
    delta: f64,
    sigma_j: f64,
) -> Interval {
    let mut cmin = c0;
    let mut better: Option<([f64; NL], f64)> = None;
    let mut ends = [lhat[k]; 2];
    let mut open = false;
    let mut multimodal = false;
    for (side, dir) in [-1.0f64, 1.0].into_iter().enumerate() {
        let limit = if dir < 0.0 {
            LOCAL_LO[k].max(lhat[k] - SPAN[k])
        } else {
            LOCAL_HI[k].min(lhat[k] + SPAN[k])
        };
        // First step: the quadratic (Jacobian) guess of the Δ boundary, 2 sigma_j sqrt(Δ/4).
        let h0 = if sigma_j.is_finite() {
            (sigma_j * delta.sqrt()).clamp(0.002, 0.5)
        } else {
            0.2
        };
        let (mut x_in, mut l_in, mut d_in) = (lhat[k], lhat, c0 - cmin);
        let mut h = h0;
        'walk: loop {
            let x = x_in + dir * h;
            if (x - limit) * dir >= 0.0 {
                // Reached the span: the profile stays within Δ to here.
                x_in = limit;
                open = true;
                break;
            }
            let (l, c) = profile_point(p, g, k, x, l_in, lhat, cmin + delta);
            if c < cmin - 1e-9 {
                cmin = c;
                better = Some((l, c));
            }
            if c - cmin <= delta {
                x_in = x;
                l_in = l;
                d_in = c - cmin;
                h = (h * 1.6).min(0.5);
                continue;
            }
            // Crossing between x_in and x: regula falsi in sqrt(Δchi²) (linear for a quadratic
            // profile), accepted within ±15 % of Δ, else the bracket shrinks (at most 4 steps).
            let (mut a, mut b, mut la) = (x_in, x, l_in);
            let (mut da, mut db) = (d_in.max(0.0).sqrt(), (c - cmin).sqrt());
            let target = delta.sqrt();
            for _ in 0..4 {
                let t = ((target - da) / (db - da)).clamp(0.1, 0.9);
                let m = a + t * (b - a);
                let (lm, cm) = profile_point(p, g, k, m, la, lhat, cmin + delta);
                let dm = (cm - cmin).max(0.0);
                if (dm - delta).abs() <= 0.15 * delta {
                    a = m;
                    b = m;
                    break;
                }
                if dm <= delta {
                    a = m;
                    la = lm;
                    da = dm.sqrt();
                } else {
                    b = m;
                    db = dm.sqrt();
                }
            }
            x_in = 0.5 * (a + b);
            // Beyond the crossing: a second minimum within Δ joins the interval. Screened on
            // a coarse grid (the other component on its grid, psi held, an upper bound of the
            // profile that psi can lower by a few units), refined where low.
            let mut xc = b;
            loop {
                xc += dir * COARSE[k];
                if (xc - limit) * dir > 0.0 {
                    break 'walk;
                }
                let (cg, lg) = grid_column(p, g, k, xc, lhat[0]);
                if cg - cmin > delta + SCREEN_SLACK {
                    continue;
                }
                let (l, c) = profile_point(p, g, k, xc, lg, lhat, cmin + delta);
                if c < cmin - 1e-9 {
                    cmin = c;
                    better = Some((l, c));
                }
                if c - cmin <= delta {
                    multimodal = true;
                    x_in = xc;
                    l_in = l;
                    d_in = c - cmin;
                    h = h0;
                    continue 'walk;
                }
            }
        }
        ends[side] = x_in;
    }
    Interval {
        lo: ends[0],
        hi: ends[1],
        open,
        multimodal,
        better,
    }
}

/// Best fit of a shot's locals in `regime` with the globals held: best point of the
/// [`spin_grid`] (psi at its measured value), then Levenberg–Marquardt.
fn fit_locals(s: &ShotData, regime: Regime, g: &[f64; NG], huber: Option<f64>) -> Hypothesis {
    let p = one_shot(s, regime, huber);
    let mut best = (f64::INFINITY, s.start_locals());
    for (r, e) in spin_grid() {
        let l = [s.psi_meas, r, e];
        let c = p.shot_cost(0, g, &l).0;
        if c < best.0 {
            best = (c, l);
        }
    }
    let sol = p.solve(
        State {
            g: *g,
            l: vec![best.1],
        },
        30,
    );
    Hypothesis {
        regime,
        l: sol.state.l[0],
        cost: sol.cost,
    }
}

/// Whether a ball–ball contact state at locals `l` is physically possible (see the module doc):
/// slip needs `c > mu` (as `mu0 ≥ mu`); stick is always possible (`mu0` has no upper bound
/// from one shot, and the bounds from other shots rest on their own ambiguous states).
pub fn admissible(regime: Regime, l: &[f64; NL], g: &[f64; NG]) -> bool {
    regime.ball_ball_stick() || critical_mu_static(g[0], l) > g[1]
}

/// The shot refitted (locals only, globals held) with the other ball–ball contact state:
/// `(regime, locals, cost)`.
pub fn alternative(
    s: &ShotData,
    regime: Regime,
    g: &[f64; NG],
    huber: Option<f64>,
) -> (Regime, [f64; NL], f64) {
    let h = fit_locals(
        s,
        Regime::from_contacts(!regime.ball_ball_stick(), regime.table_stick()),
        g,
        huber,
    );
    (h.regime, h.l, h.cost)
}

/// Inputs of [`shot_spin`] besides the shot.
pub struct SpinContext {
    pub g: [f64; NG],
    pub huber: Option<f64>,
    /// Error scale `max(1, sqrt(chi²_red))`.
    pub scale: f64,
}

/// Spin estimate, errors and regime of one estimated-spin shot (see the module doc).
/// `l_fit`: the shot's locals in the global fit under `regime`; `var_cond`, `var_total`: its
/// conditional and marginal local variances from the Schur complement (unit-variance residuals).
pub fn shot_spin(
    s: &ShotData,
    regime: Regime,
    l_fit: [f64; NL],
    var_cond: [f64; NL],
    var_total: [f64; NL],
    ctx: &SpinContext,
) -> ShotSpin {
    let g = &ctx.g;
    let delta = 4.0 * ctx.scale * ctx.scale;
    let own = Hypothesis {
        regime,
        l: l_fit,
        cost: one_shot(s, regime, ctx.huber).shot_cost(0, g, &l_fit).0,
    };
    let other = fit_locals(
        s,
        Regime::from_contacts(!regime.ball_ball_stick(), regime.table_stick()),
        g,
        ctx.huber,
    );
    let mut hyps: Vec<Hypothesis> = vec![own, other];
    let adm: Vec<bool> = hyps.iter().map(|h| admissible(h.regime, &h.l, g)).collect();
    // Best admissible hypothesis (the model's own when none is admissible).
    let best = (0..hyps.len())
        .filter(|&i| adm[i])
        .min_by(|&a, &b| hyps[a].cost.total_cmp(&hyps[b].cost))
        .unwrap_or(0);
    // Profile interval of r: the best hypothesis first, then every admissible one within Δ of
    // it (a profile may find a lower point: the walk then restarts from there).
    let profile_r = |h: &mut Hypothesis| {
        let p = one_shot(s, h.regime, ctx.huber);
        let mut iv = profile_interval(&p, g, h.l, h.cost, 1, delta, var_cond[1].sqrt());
        if let Some((l, c)) = iv.better.take() {
            h.l = l;
            h.cost = c;
            iv = profile_interval(&p, g, h.l, h.cost, 1, delta, var_cond[1].sqrt());
        }
        iv
    };
    let mut r_int: Vec<Option<Interval>> = (0..hyps.len()).map(|_| None).collect();
    r_int[best] = Some(profile_r(&mut hyps[best]));
    for i in 0..hyps.len() {
        if i != best && adm[i] && hyps[i].cost - hyps[best].cost <= delta {
            r_int[i] = Some(profile_r(&mut hyps[i]));
        }
    }
    let mut notes = Vec::new();
    if !adm[best] {
        notes.push(format!(
            "no admissible regime: {} kept although the stick/slip condition contradicts it",
            hyps[best].regime.name()
        ));
    }
    let hb = &hyps[best];
    let ib = r_int[best]
        .as_ref()
        .expect("the best hypothesis is profiled");
    let (mut lo, mut hi, mut open) = (ib.lo, ib.hi, ib.open);
    if ib.multimodal {
        notes.push(format!(
            "spin r has separate minima in [{:.2}, {:.2}]",
            ib.lo, ib.hi
        ));
    }
    for i in 0..hyps.len() {
        if let Some(iv) = &r_int[i]
            && i != best
            && hyps[i].cost - hb.cost <= delta
        {
            lo = lo.min(iv.lo);
            hi = hi.max(iv.hi);
            open |= iv.open;
            notes.push(format!(
                "spin r ambiguous: {} gives r = {:.2}, {} gives r = {:.2} (Δchi² {:.1})",
                hb.regime.name(),
                hb.l[1],
                hyps[i].regime.name(),
                hyps[i].l[1],
                hyps[i].cost - hb.cost
            ));
        }
    }
    // Globals' share of the variance (Schur complement), added in quadrature.
    let glob = |k: usize| (var_total[k] - var_cond[k]).max(0.0) * ctx.scale * ctx.scale;
    let r_err = if open {
        f64::INFINITY
    } else {
        (0.5 * (hb.l[1] - lo).max(hi - hb.l[1])).hypot(glob(1).sqrt())
    };
    // English: profile of s under the reported hypothesis.
    let p = one_shot(s, hb.regime, ctx.huber);
    let s_iv = profile_interval(&p, g, hb.l, hb.cost, 2, delta, var_cond[2].sqrt());
    let s_err = if s_iv.open {
        f64::INFINITY
    } else {
        (0.5 * (hb.l[2] - s_iv.lo).max(s_iv.hi - hb.l[2])).hypot(glob(2).sqrt())
    };
    ShotSpin {
        regime: hb.regime,
        l: hb.l,
        r_err,
        s_err,
        notes,
    }
}
