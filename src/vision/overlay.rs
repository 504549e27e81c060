//! Overlays: the photo with what the extractor saw drawn on it.
//!
//! Yellow circle: the fitted object-ball disc (`O`, `R`); cyan circle: the cue ball at impact
//! (`P`, `R`); dots: centre-line samples (white incoming, one per radius where its line was read
//! from blocks of pixels, [`super::linefit`]; orange cue ball, magenta object ball, grey
//! rejected); green curves: fitted paths (parabola then rolling line); red and green arrows: the
//! frame axes `x` (line of centres) and `y` (after the mirror); text: status and angles with
//! 1-sigma uncertainties. The photo is brightened (gamma) so faint streaks are visible.

use super::image_io::RgbImage;
use super::shot::{Analysis, Role};
use ab_glyph::{FontRef, PxScale};
use image::{Rgb, RgbImage as Rgb8};
use imageproc::drawing::{
    draw_filled_circle_mut, draw_hollow_circle_mut, draw_line_segment_mut, draw_text_mut, text_size,
};

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn thick_line(img: &mut Rgb8, a: (f64, f64), b: (f64, f64), w: f64, c: Rgb<u8>) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l = dx.hypot(dy).max(1e-9);
    let n = (-dy / l, dx / l);
    let k = (w / 2.0).ceil() as i32;
    for i in -k..=k {
        let o = i as f64 * 0.5;
        draw_line_segment_mut(
            img,
            ((a.0 + o * n.0) as f32, (a.1 + o * n.1) as f32),
            ((b.0 + o * n.0) as f32, (b.1 + o * n.1) as f32),
            c,
        );
    }
}

fn arrow(img: &mut Rgb8, a: (f64, f64), b: (f64, f64), w: f64, c: Rgb<u8>) {
    thick_line(img, a, b, w, c);
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l = dx.hypot(dy).max(1e-9);
    let (ux, uy) = (dx / l, dy / l);
    let h = (0.15 * l).max(4.0);
    for s in [-1.0, 1.0] {
        let p = (
            b.0 - h * (ux * 0.87 - s * uy * 0.5),
            b.1 - h * (uy * 0.87 + s * ux * 0.5),
        );
        thick_line(img, b, p, w, c);
    }
}

/// `text` broken at spaces into lines no wider than `width` px at font size `fs`; continuation
/// lines are indented.
fn wrap(text: &str, width: f32, fs: f32, font: &FontRef) -> Vec<String> {
    let fits = |t: &str| text_size(PxScale::from(fs), font, t).0 as f32 <= width;
    let mut out = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let candidate = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if fits(&candidate) || line.trim().is_empty() {
            line = candidate;
        } else {
            out.push(line);
            line = format!("        {word}");
        }
    }
    out.push(line);
    out
}

/// An angle with its error; a missing one is "not resolved" when the reason says so (the photo
/// does not tell it), else "undefined" (a ball that stops has no direction).
fn fmt_angle(name: &str, v: Option<f64>, e: Option<f64>, reason: &str) -> String {
    match (v, e) {
        (Some(v), Some(e)) => format!("{name} = {v:.3}° ± {e:.3}°"),
        (Some(v), None) => format!("{name} = {v:.3}°"),
        _ if reason.contains(&format!("{name} not resolved")) => format!("{name}: not resolved"),
        _ => format!("{name}: undefined"),
    }
}

/// Draws the overlay for one analysed photo.
pub fn render(img: &RgbImage, a: &Analysis, title: &str) -> Rgb8 {
    let mut out = Rgb8::new(img.w as u32, img.h as u32);
    for (i, p) in out.pixels_mut().enumerate() {
        let q = img.px(i % img.w, i / img.w);
        *p = Rgb(q.map(|v| (v.clamp(0.0, 1.0).powf(0.6) * 255.0).round() as u8));
    }
    let font = FontRef::try_from_slice(FONT).expect("embedded DejaVuSans is a valid font");
    let side = img.w.min(img.h) as f64;
    let lw = (side / 500.0).max(1.0);
    let dot = (side / 400.0).max(1.0).round() as i32;
    let r = a.ball_radius_px.unwrap_or(side / 40.0);
    // The object ball's waiting disc, and its rest disc when it crept.
    for (d, c) in [
        (&a.disc, Rgb([255, 230, 0])),
        (&a.rest_disc, Rgb([255, 60, 255])),
    ] {
        if let Some(d) = d {
            let centre = (d.cx.round() as i32, d.cy.round() as i32);
            draw_hollow_circle_mut(&mut out, centre, d.r.round() as i32, c);
        }
    }
    for (role, samples) in &a.streaks {
        let (color, inl) = match role {
            Role::Incoming => (Rgb([255, 255, 255]), a.fit.as_ref().map(|f| &f.inliers[0])),
            Role::CueOut => (Rgb([255, 150, 0]), a.fit.as_ref().map(|f| &f.inliers[1])),
            Role::ObjectOut => (Rgb([255, 60, 255]), a.fit.as_ref().map(|f| &f.inliers[2])),
            Role::Unused => (Rgb([150, 150, 150]), None),
        };
        for (i, s) in samples.iter().enumerate() {
            let ok = inl.is_none_or(|v| v.get(i).copied().unwrap_or(true));
            let c = if ok { color } else { Rgb([120, 120, 120]) };
            draw_filled_circle_mut(&mut out, (s.x.round() as i32, s.y.round() as i32), dot, c);
        }
    }
    if let Some(fit) = &a.fit {
        let p = fit.impact();
        let o = fit.o();
        draw_hollow_circle_mut(
            &mut out,
            (p.0.round() as i32, p.1.round() as i32),
            fit.r().round() as i32,
            Rgb([0, 255, 255]),
        );
        let len = (img.w + img.h) as f64;
        // Incoming line (dashed look: drawn up to P).
        let u = (
            (fit.alpha() + fit.psi_s()).cos(),
            (fit.alpha() + fit.psi_s()).sin(),
        );
        thick_line(
            &mut out,
            (p.0 - len * u.0, p.1 - len * u.1),
            p,
            lw,
            Rgb([0, 200, 255]),
        );
        // The frame first, so that the paths and start tangents (along `y` for many shots) stay
        // visible on top of it.
        let x = (fit.alpha().cos(), fit.alpha().sin());
        let y = (-a.mirror * x.1, a.mirror * x.0);
        arrow(
            &mut out,
            p,
            (p.0 + 4.0 * r * x.0, p.1 + 4.0 * r * x.1),
            1.5 * lw,
            Rgb([255, 40, 40]),
        );
        arrow(
            &mut out,
            p,
            (p.0 + 4.0 * r * y.0, p.1 + 4.0 * r * y.1),
            1.5 * lw,
            Rgb([40, 255, 40]),
        );
        let fs = PxScale::from((side / 30.0) as f32);
        draw_text_mut(
            &mut out,
            Rgb([255, 40, 40]),
            (p.0 + 4.2 * r * x.0) as i32,
            (p.1 + 4.2 * r * x.1) as i32,
            fs,
            &font,
            "x",
        );
        draw_text_mut(
            &mut out,
            Rgb([40, 255, 40]),
            (p.0 + 4.2 * r * y.0) as i32,
            (p.1 + 4.2 * r * y.1) as i32,
            fs,
            &font,
            "y",
        );
        for (ball, g) in [(1, fit.geom1()), (2, Some(fit.geom2()))] {
            let Some(g) = g else { continue };
            let pts = g.polyline(len);
            for w in pts.windows(2) {
                thick_line(&mut out, w[0], w[1], lw, Rgb([0, 255, 0]));
            }
            // Start tangent, as long as 3 R: the pixel fit's sliding arc when `delta1` comes
            // from it (drawn over the centre-line fit's path), else the path's own.
            let (start, u0) = match (&a.arc, ball) {
                (Some(arc), 1) => {
                    let u = (arc.delta.cos(), arc.delta.sin());
                    let c = (p.0 + arc.l0 * u.0, p.1 + arc.l0 * u.1);
                    let bez = |t: f64| {
                        let (b0, b1, b2) = ((1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t);
                        (
                            b0 * p.0 + b1 * c.0 + b2 * arc.end.0,
                            b0 * p.1 + b1 * c.1 + b2 * arc.end.1,
                        )
                    };
                    for k in 0..32 {
                        let (t0, t1) = (k as f64 / 32.0, (k + 1) as f64 / 32.0);
                        thick_line(&mut out, bez(t0), bez(t1), 1.5 * lw, Rgb([255, 170, 0]));
                    }
                    (p, u)
                }
                _ => (g.start, g.u0),
            };
            arrow(
                &mut out,
                start,
                (start.0 + 3.0 * r * u0.0, start.1 + 3.0 * r * u0.1),
                lw,
                Rgb([255, 255, 0]),
            );
        }
        let _ = o;
    }
    let fs = (side / 35.0) as f32;
    let mut lines = vec![title.to_string()];
    // The status and its reasons, one note per line, wrapped to the photo's width (a reason
    // runs to a hundred characters, a line of text at this size to about seventy).
    let width = out.width() as f32 - fs;
    let notes: Vec<&str> = a.reason.split("; ").filter(|n| !n.is_empty()).collect();
    let head = format!("status: {}", a.status.as_str());
    if notes.is_empty() {
        lines.push(head.clone());
    }
    for (i, note) in notes.iter().enumerate() {
        let first = if i == 0 {
            format!("{head} {note}")
        } else {
            format!("    {note}")
        };
        lines.extend(wrap(&first, width, fs, &font));
    }
    if a.status == crate::table::Status::Ok {
        lines.push(fmt_angle("psi", a.psi_deg, a.psi_err_deg, &a.reason));
        lines.push(format!(
            "{}   ({}{})",
            fmt_angle("delta1", a.delta1_deg, a.delta1_err_deg, &a.reason),
            cue_model_label(a.path_model1.as_deref(), &a.reason),
            if a.arc.is_some() {
                "; delta1 from the arc fit at P, orange"
            } else {
                ""
            }
        ));
        lines.push(fmt_angle(
            "theta1",
            a.theta1_deg,
            a.theta1_err_deg,
            &a.reason,
        ));
        lines.push(format!(
            "{}   ({})",
            fmt_angle("delta2", a.delta2_deg, a.delta2_err_deg, &a.reason),
            a.path_model2.as_deref().unwrap_or("")
        ));
        lines.push(fmt_angle(
            "theta2",
            a.theta2_deg,
            a.theta2_err_deg,
            &a.reason,
        ));
        if let Some(rr) = a.ball_radius_px {
            lines.push(format!("R = {rr:.2} px"));
        }
    }
    if let Some(c) = a.cloth {
        lines.push(format!("cloth model: {}", c.as_str()));
    }
    for (i, l) in lines.iter().enumerate() {
        let y = (fs * 0.3 + i as f32 * fs * 1.25) as i32;
        draw_text_mut(
            &mut out,
            Rgb([0, 0, 0]),
            (fs * 0.4) as i32 + 1,
            y + 1,
            PxScale::from(fs),
            &font,
            l,
        );
        draw_text_mut(
            &mut out,
            Rgb([255, 255, 255]),
            (fs * 0.4) as i32,
            y,
            PxScale::from(fs),
            &font,
            l,
        );
    }
    out
}

/// The overlay's label of the cue ball's path model: the model's name, or, without a path,
/// whether the ball stopped at the impact, came back along its incoming streak (a draw shot,
/// its way back not measured), or its path was not found (hidden in the other streaks, or too
/// short to track), as the reason says.
fn cue_model_label<'a>(model: Option<&'a str>, reason: &str) -> &'a str {
    match model {
        Some(m) => m,
        None if reason.contains(super::shot::CUE_PATH_NOT_FOUND) => "path not found",
        None if reason.contains(super::shot::CUE_DRAWN_BACK) => "drawn back, not measured",
        None => "stopped",
    }
}

#[cfg(test)]
mod tests {
    use super::cue_model_label;

    #[test]
    fn a_cue_ball_without_a_path_is_labelled_by_the_reason() {
        assert_eq!(cue_model_label(Some("line"), ""), "line");
        assert_eq!(
            cue_model_label(
                None,
                "cue ball's path not found (hidden near the impact): delta1, theta1 undefined"
            ),
            "path not found"
        );
        assert_eq!(
            cue_model_label(
                None,
                "cue ball drawn back along its incoming streak (the incoming line measured \
                 beyond its way back, which is not measured): delta1, theta1 undefined; delta2 \
                 not resolved"
            ),
            "drawn back, not measured"
        );
        assert_eq!(
            cue_model_label(
                None,
                "cue ball stops at the impact: delta1, theta1 undefined"
            ),
            "stopped"
        );
    }
}
