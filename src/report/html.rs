//! `index.html` and `report.md`: the coefficient table against the paper's Table 1, the model
//! selection, per-material figures, extraction statistics, the overlay gallery, and the settings
//! and versions that made the report.
//!
//! The page is self-contained: inline CSS, no scripts, no fonts or images from elsewhere; every
//! image is a file in the report folder linked by a relative path.

use super::figures::MaterialFigures;
use super::plot::SavedFigure;
use super::{ExtractionStats, GalleryItem, ReportInput, write_atomic};
use crate::table::Status;
use anyhow::{Context, Result};
use std::fmt::Write as _;
use std::path::Path;

/// Escapes text for HTML element content and attribute values.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Path of `p` relative to `base` (both inside the report folder), with `/` separators.
fn rel(p: &Path, base: &Path) -> String {
    p.strip_prefix(base)
        .unwrap_or(p)
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

/// `value ± err` with the error's significant digits.
pub fn pm(value: f64, err: Option<f64>) -> String {
    match err {
        Some(e) if e.is_finite() && e > 0.0 => {
            let digits = (-(e.log10().floor()) + 1.0).clamp(2.0, 6.0) as usize;
            format!("{value:.digits$} ± {e:.digits$}")
        }
        _ => format!("{value:.3}"),
    }
}

/// Copies (downscaled to at most 900 px wide) the overlays shown in the gallery into
/// `dir/overlays/FOLDER/`: per folder the declined and error images first (they need a look),
/// then `ok` ones, up to `gallery_per_folder`.
pub fn copy_gallery(input: &ReportInput, dir: &Path) -> Result<Vec<GalleryItem>> {
    let mut out = Vec::new();
    for folder in &input.folders {
        let Some(src_dir) = &folder.overlays else {
            continue;
        };
        let rows = gallery_pick(&folder.rows, input.gallery_per_folder, |r| {
            src_dir.join(crate::extract::overlay_name(&r.file)).exists()
        });
        let dest = dir.join("overlays").join(&folder.name);
        for r in rows {
            let name = crate::extract::overlay_name(&r.file);
            let src = src_dir.join(&name);
            std::fs::create_dir_all(&dest)
                .with_context(|| format!("creating {}", dest.display()))?;
            let img =
                image::open(&src).with_context(|| format!("reading overlay {}", src.display()))?;
            let img = if img.width() > 900 {
                img.resize(
                    900,
                    900 * img.height() / img.width().max(1),
                    image::imageops::FilterType::Triangle,
                )
            } else {
                img
            };
            let target = dest.join(&name);
            let mut bytes = Vec::new();
            img.to_rgb8()
                .write_to(
                    &mut std::io::Cursor::new(&mut bytes),
                    image::ImageFormat::Png,
                )
                .with_context(|| format!("encoding {}", target.display()))?;
            write_atomic(&target, &bytes)?;
            out.push(GalleryItem {
                folder: folder.name.clone(),
                file: r.file.clone(),
                rel_path: rel(&target, dir),
                status: r.status.as_str().to_string(),
                reason: r.reason.clone(),
            });
        }
    }
    Ok(out)
}

/// Up to `n` rows (with an overlay) for the gallery: up to half of them declined or failed (they
/// need a look), the rest measured, each group in file order; a group that runs short leaves its
/// places to the other. Returned declined/failed first.
pub fn gallery_pick(
    rows: &[crate::table::ShotRow],
    n: usize,
    has_overlay: impl Fn(&crate::table::ShotRow) -> bool,
) -> Vec<&crate::table::ShotRow> {
    let mut bad: Vec<&crate::table::ShotRow> = rows
        .iter()
        .filter(|r| r.status != Status::Ok && has_overlay(r))
        .collect();
    let mut good: Vec<&crate::table::ShotRow> = rows
        .iter()
        .filter(|r| r.status == Status::Ok && has_overlay(r))
        .collect();
    bad.sort_by(|a, b| a.file.cmp(&b.file));
    good.sort_by(|a, b| a.file.cmp(&b.file));
    let n_bad = bad
        .len()
        .min(n.div_ceil(2))
        .max(n.saturating_sub(good.len()))
        .min(bad.len());
    let n_good = good.len().min(n - n_bad);
    bad.truncate(n_bad);
    good.truncate(n_good);
    bad.extend(good);
    bad
}

const CSS: &str = "body{font-family:'DejaVu Sans',Verdana,sans-serif;max-width:1500px;margin:1.5em auto;\
padding:0 1em;color:#222;line-height:1.4}h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;\
padding-bottom:.2em;margin-top:2em}table{border-collapse:collapse;margin:.8em 0}th,td{border:1px solid #bbb;\
padding:.25em .6em;text-align:right}th{background:#f0f0f0}td.l,th.l{text-align:left}figure{margin:1em 0 2em}\
figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.92em;color:#444;max-width:1100px}\
.gallery{display:flex;flex-wrap:wrap;gap:12px}.gallery figure{width:440px;margin:0}\
.gallery img{width:100%}pre{background:#f6f6f6;padding:.8em;overflow-x:auto;font-size:.88em}\
.ok{color:#176c2f}.declined{color:#a05a00}.error{color:#b00020}.note{color:#555;font-size:.92em}";

/// The HTML page.
pub fn render_html(
    input: &ReportInput,
    global: &[SavedFigure],
    per_material: &[(MaterialFigures, Vec<SavedFigure>)],
    gallery: &[GalleryItem],
    dir: &Path,
) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n\
         <style>{CSS}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
        esc(&input.title),
        esc(&input.title)
    );
    let _ = writeln!(
        h,
        "<p class=\"note\">streakfit {} · pipeline <code>{}</code> · {} shots in {} folders · \
         figures are PNG (click for SVG).</p>",
        env!("CARGO_PKG_VERSION"),
        esc(&input.settings_name),
        input.rows.len(),
        input.folders.len()
    );
    h.push_str("<nav><a href=\"#coefficients\">Coefficients</a> · <a href=\"#selection\">Model selection</a> · \
                <a href=\"#extraction\">Extraction</a> · <a href=\"#theory\">Theory figures</a>");
    for (m, _) in per_material {
        let _ = write!(
            h,
            " · <a href=\"#m-{}\">{}</a>",
            esc(&m.name),
            esc(&m.label)
        );
    }
    h.push_str(" · <a href=\"#gallery\">Overlays</a> · <a href=\"#settings\">Settings</a></nav>\n");

    // Coefficients against Table 1.
    h.push_str("<h2 id=\"coefficients\">Coefficients against the paper's Table 1</h2>\n");
    h.push_str(&coefficient_table_html(input));
    for (m, e) in &input.fit_failures {
        let _ = writeln!(
            h,
            "<p class=\"error\">Fit of {}: failed: {}</p>",
            esc(m),
            esc(e)
        );
    }

    // Model selection.
    h.push_str("<h2 id=\"selection\">Model selection</h2>\n");
    if input.fits.iter().all(|f| f.scores.is_empty()) {
        h.push_str("<p>No model-selection scores were produced by the fit.</p>\n");
    }
    for f in input.fits.iter().filter(|f| !f.scores.is_empty()) {
        let _ = writeln!(
            h,
            "<h3>{}</h3>\n<table><tr><th class=\"l\">model</th><th>k</th><th>χ²</th><th>AIC</th>\
             <th>BIC</th><th class=\"l\">selected</th></tr>",
            esc(&f.material)
        );
        for s in &f.scores {
            let _ = writeln!(
                h,
                "<tr><td class=\"l\">{}</td><td>{}</td><td>{:.2}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td></tr>",
                esc(&s.name),
                s.k,
                s.chi2,
                opt(s.aic, 2),
                opt(s.bic, 2),
                if s.selected { "✔" } else { "" }
            );
        }
        h.push_str("</table>\n");
        for n in &f.notes {
            let _ = writeln!(h, "<p class=\"note\">{}</p>", esc(n));
        }
    }

    // Extraction statistics.
    h.push_str("<h2 id=\"extraction\">Extraction</h2>\n");
    h.push_str(&extraction_html(input));

    // Theory figures.
    h.push_str("<h2 id=\"theory\">Theory figures</h2>\n");
    for f in global {
        h.push_str(&figure_html(f, dir));
    }

    for (m, figs) in per_material {
        let n_ok = m.rows.iter().filter(|r| r.status == Status::Ok).count();
        let _ = writeln!(
            h,
            "<h2 id=\"m-{}\">{} ({} shots, {} measured)</h2>",
            esc(&m.name),
            esc(&m.label),
            m.rows.len(),
            n_ok
        );
        if m.fitted.is_none() {
            h.push_str("<p class=\"note\">No fit for this material: the curves show the paper's coefficients only.</p>\n");
        }
        for f in figs {
            h.push_str(&figure_html(f, dir));
        }
    }

    h.push_str("<h2 id=\"gallery\">Extraction overlays</h2>\n");
    if gallery.is_empty() {
        h.push_str("<p>No overlays were written for this run.</p>\n");
    } else {
        h.push_str("<p class=\"note\">Per folder, images that were declined or failed come first, then measured ones.</p>\n<div class=\"gallery\">\n");
        for g in gallery {
            let _ = writeln!(
                h,
                "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"overlay of {1}\"></a><figcaption>{2}/{1}: \
                 <span class=\"{3}\">{3}</span>{4}</figcaption></figure>",
                esc(&g.rel_path),
                esc(&g.file),
                esc(&g.folder),
                esc(&g.status),
                if g.reason.is_empty() {
                    String::new()
                } else {
                    format!(" — {}", esc(&g.reason))
                }
            );
        }
        h.push_str("</div>\n");
    }

    h.push_str("<h2 id=\"settings\">Settings and versions</h2>\n");
    let _ = writeln!(
        h,
        "<p>streakfit {} ({} {}); theory: impulse–momentum model with the corrections documented in \
         docs/ (physics::impulse); paper: “Non-smooth modelling of billiard- and superbilliard-ball \
         collisions”, Table 1 values from <code>datasets/materials.toml</code>.</p>",
        env!("CARGO_PKG_VERSION"),
        std::env::consts::OS,
        std::env::consts::ARCH
    );
    let _ = writeln!(h, "<p>Fit: {}</p>", esc(&input.fit_settings));
    if !input.stages.is_empty() {
        h.push_str("<table><tr><th class=\"l\">stage</th><th class=\"l\">status</th><th>seconds</th><th class=\"l\">key</th></tr>\n");
        for s in &input.stages {
            let _ = writeln!(
                h,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{:.1}</td><td class=\"l\"><code>{}</code></td></tr>",
                esc(&s.name),
                esc(&s.status),
                s.seconds,
                esc(&s.key)
            );
        }
        h.push_str("</table>\n");
    }
    let _ = writeln!(h, "<pre>{}</pre>", esc(&input.settings_text));
    h.push_str("</body>\n</html>\n");
    h
}

fn opt(v: Option<f64>, d: usize) -> String {
    v.map_or("—".to_string(), |x| format!("{x:.d$}"))
}

fn figure_html(f: &SavedFigure, dir: &Path) -> String {
    format!(
        "<figure id=\"{name}\"><a href=\"{svg}\"><img src=\"{png}\" alt=\"{cap}\"></a>\
         <figcaption><b>{name}</b>: {cap}</figcaption></figure>\n",
        name = esc(&f.name),
        svg = esc(&rel(&f.svg, dir)),
        png = esc(&rel(&f.png, dir)),
        cap = esc(&f.caption)
    )
}

/// Rows of the coefficient table: `(material, label, [(name, fitted, paper)], n, model, chi2)`.
fn coefficient_rows(input: &ReportInput) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for name in super::report_materials(input) {
        let preset = input.materials.0.get(&name);
        let fit = input.fits.iter().find(|f| f.material == name);
        let label = preset
            .map(|p| p.label.clone())
            .unwrap_or_else(|| name.clone());
        let fitted = |i: usize, get: fn(&super::FitSummary) -> (f64, Option<f64>)| {
            fit.map(|f| {
                let (v, e) = get(f);
                if f.fitted[i] {
                    pm(v, e)
                } else {
                    "not identified".to_string()
                }
            })
            .unwrap_or_else(|| "—".into())
        };
        let paper = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.2}"));
        out.push(vec![
            label,
            fitted(0, |f| (f.coeffs.e, f.errors.e)),
            paper(preset.map(|p| p.e)),
            fitted(1, |f| (f.coeffs.mu, f.errors.mu)),
            paper(preset.map(|p| p.mu)),
            fitted(3, |f| (f.coeffs.mu_static, f.errors.mu_static)),
            paper(preset.map(|p| p.mu_static)),
            fitted(2, |f| (f.coeffs.mu_table, f.errors.mu_table)),
            paper(preset.map(|p| p.mu_table)),
            fit.map(|f| f.n_shots.to_string())
                .unwrap_or_else(|| "0".into()),
            fit.map(|f| f.model.clone())
                .unwrap_or_else(|| "no fit".into()),
            fit.and_then(|f| f.chi2_red)
                .map_or("—".into(), |c| format!("{c:.2}")),
        ]);
    }
    out
}

const COEFF_HEADER: [&str; 12] = [
    "material",
    "e (fit)",
    "e (paper)",
    "μ (fit)",
    "μ (paper)",
    "μ0 (fit)",
    "μ0 (paper)",
    "μ' (fit)",
    "μ' (paper)",
    "shots",
    "selected model",
    "χ²/dof",
];

fn coefficient_table_html(input: &ReportInput) -> String {
    let mut h = String::from("<table><tr>");
    for (i, c) in COEFF_HEADER.iter().enumerate() {
        let cls = if i == 0 || i == 10 {
            " class=\"l\""
        } else {
            ""
        };
        let _ = write!(h, "<th{cls}>{}</th>", esc(c));
    }
    h.push_str("</tr>\n");
    for row in coefficient_rows(input) {
        h.push_str("<tr>");
        for (i, c) in row.iter().enumerate() {
            let cls = if i == 0 || i == 10 {
                " class=\"l\""
            } else {
                ""
            };
            let _ = write!(h, "<td{cls}>{}</td>", esc(c));
        }
        h.push_str("</tr>\n");
    }
    h.push_str(
        "</table>\n<p class=\"note\">Fit values ± 1σ. Paper: Table 1 (where it gives no μ0, \
                μ0 = μ). μ' (ball–table friction during the impact) is weakly determined by angles \
                alone in gross slip (it cancels from θ₂).</p>\n",
    );
    h
}

fn extraction_groups(input: &ReportInput) -> Vec<(String, ExtractionStats)> {
    let mut out = Vec::new();
    for f in &input.folders {
        out.push((f.name.clone(), ExtractionStats::of(&f.rows)));
    }
    if input.folders.is_empty() {
        out.push(("all".into(), ExtractionStats::of(&input.rows)));
    }
    out
}

fn extraction_html(input: &ReportInput) -> String {
    let mut h = String::from(
        "<table><tr><th class=\"l\">folder</th><th>images</th><th>ok</th><th>declined</th>\
         <th>error</th><th>analysis s</th></tr>\n",
    );
    let groups = extraction_groups(input);
    for (name, s) in &groups {
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{}</td><td class=\"ok\">{}</td><td class=\"declined\">{}</td>\
             <td class=\"error\">{}</td><td>{:.1}</td></tr>",
            esc(name),
            s.total,
            s.ok,
            s.declined,
            s.error,
            s.seconds
        );
    }
    h.push_str("</table>\n");
    let any_reasons = groups.iter().any(|(_, s)| !s.reasons.is_empty());
    if any_reasons {
        h.push_str("<table><tr><th class=\"l\">folder</th><th class=\"l\">status</th><th class=\"l\">reason</th><th>images</th></tr>\n");
        for (name, s) in &groups {
            for (status, reason, n) in &s.reasons {
                let _ = writeln!(
                    h,
                    "<tr><td class=\"l\">{}</td><td class=\"l {1}\">{1}</td><td class=\"l\">{2}</td><td>{3}</td></tr>",
                    esc(name),
                    esc(status),
                    esc(reason),
                    n
                );
            }
        }
        h.push_str("</table>\n");
    } else {
        h.push_str("<p>Every image was measured.</p>\n");
    }
    h
}

/// The Markdown summary (same content, figures linked).
pub fn render_markdown(
    input: &ReportInput,
    global: &[SavedFigure],
    per_material: &[(MaterialFigures, Vec<SavedFigure>)],
    gallery: &[GalleryItem],
    dir: &Path,
) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# {}\n", input.title);
    let _ = writeln!(
        m,
        "streakfit {} · pipeline `{}` · {} shots in {} folders. The HTML version is `index.html`.\n",
        env!("CARGO_PKG_VERSION"),
        input.settings_name,
        input.rows.len(),
        input.folders.len()
    );
    m.push_str("## Coefficients against the paper's Table 1\n\n");
    m.push_str(&format!("| {} |\n", COEFF_HEADER.join(" | ")));
    m.push_str(&format!("|{}\n", "---|".repeat(COEFF_HEADER.len())));
    for row in coefficient_rows(input) {
        let _ = writeln!(m, "| {} |", row.join(" | "));
    }
    m.push_str("\nFit values ± 1σ; paper: Table 1 (where it gives no μ0, μ0 = μ).\n\n");
    for (mat, e) in &input.fit_failures {
        let _ = writeln!(m, "**Fit of {mat} failed:** {e}\n");
    }
    m.push_str("## Model selection\n\n");
    for f in input.fits.iter().filter(|f| !f.scores.is_empty()) {
        let _ = writeln!(
            m,
            "### {}\n\n| model | k | χ² | AIC | BIC | selected |\n|---|---|---|---|---|---|",
            f.material
        );
        for s in &f.scores {
            let _ = writeln!(
                m,
                "| {} | {} | {:.2} | {} | {} | {} |",
                s.name,
                s.k,
                s.chi2,
                opt(s.aic, 2),
                opt(s.bic, 2),
                if s.selected { "yes" } else { "" }
            );
        }
        for n in &f.notes {
            let _ = writeln!(m, "\n{n}");
        }
        m.push('\n');
    }
    m.push_str(
        "## Extraction\n\n| folder | images | ok | declined | error |\n|---|---|---|---|---|\n",
    );
    let groups = extraction_groups(input);
    for (name, s) in &groups {
        let _ = writeln!(
            m,
            "| {name} | {} | {} | {} | {} |",
            s.total, s.ok, s.declined, s.error
        );
    }
    for (name, s) in &groups {
        for (status, reason, n) in &s.reasons {
            let _ = writeln!(m, "- {name}: {n} × {status}: {reason}");
        }
    }
    m.push_str("\n## Theory figures\n\n");
    for f in global {
        let _ = writeln!(m, "![{}]({})\n\n{}\n", f.name, rel(&f.png, dir), f.caption);
    }
    for (mat, figs) in per_material {
        let _ = writeln!(m, "## {}\n", mat.label);
        for f in figs {
            let _ = writeln!(m, "![{}]({})\n\n{}\n", f.name, rel(&f.png, dir), f.caption);
        }
    }
    if !gallery.is_empty() {
        m.push_str("## Extraction overlays\n\n");
        for g in gallery {
            let _ = writeln!(
                m,
                "- [{}/{}]({}): {} {}",
                g.folder, g.file, g.rel_path, g.status, g.reason
            );
        }
        m.push('\n');
    }
    m.push_str("## Settings\n\n");
    let _ = writeln!(m, "Fit: {}\n", input.fit_settings);
    for s in &input.stages {
        let _ = writeln!(
            m,
            "- stage {}: {} in {:.1} s (key `{}`)",
            s.name, s.status, s.seconds, s.key
        );
    }
    let _ = writeln!(m, "\n```toml\n{}\n```", input.settings_text.trim_end());
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gallery_mixes_declined_and_measured() {
        use crate::table::ShotRow;
        let mk =
            |i: usize, st: Status| ShotRow::failed(format!("shot_{i:03}.png"), st, "", "steel");
        let mut rows: Vec<ShotRow> = (0..10).map(|i| mk(i, Status::Ok)).collect();
        rows.extend((10..20).map(|i| mk(i, Status::Declined)));
        let pick = gallery_pick(&rows, 5, |_| true);
        let files: Vec<&str> = pick.iter().map(|r| r.file.as_str()).collect();
        assert_eq!(
            files,
            [
                "shot_010.png",
                "shot_011.png",
                "shot_012.png",
                "shot_000.png",
                "shot_001.png"
            ]
        );
        // Only two measured shots: the declined ones fill the remaining places.
        let pick = gallery_pick(&rows[8..], 6, |_| true);
        assert_eq!(pick.iter().filter(|r| r.status == Status::Ok).count(), 2);
        assert_eq!(pick.len(), 6);
        // Shots without an overlay are never picked.
        assert!(
            gallery_pick(&rows, 4, |r| r.status == Status::Ok)
                .iter()
                .all(|r| r.status == Status::Ok)
        );
    }

    #[test]
    fn escaping_and_plus_minus() {
        assert_eq!(
            esc("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
        assert_eq!(pm(0.9213, Some(0.012)), "0.921 ± 0.012");
        assert_eq!(pm(0.14, Some(0.0004)), "0.14000 ± 0.00040");
        assert_eq!(pm(0.5, None), "0.500");
    }
}
