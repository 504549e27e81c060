//! Plotting infrastructure: a small declarative chart description rendered by plotters to PNG and
//! SVG from one drawing routine.
//!
//! A [`Figure`] holds one or more [`Panel`]s (laid out in a grid); a panel holds theory curves
//! ([`Line`], possibly broken into segments where a curve is undefined or jumps), measured points
//! with 1-sigma error bars ([`Points`]), filled cells ([`Cells`], for regime maps) and text notes.
//! Fonts: the DejaVu Sans file in `assets/fonts/` is compiled into the binary and registered under
//! plotters' default family `sans-serif`, so figures render identically on a machine without
//! fontconfig or any system font. The SVG files name the family `sans-serif` and leave glyph
//! rendering to the viewer. Files are written to a temporary name and renamed (atomic replace).

use anyhow::{Context, Result, anyhow};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The embedded font (SIL/Bitstream Vera licence in `assets/fonts/DejaVu-LICENSE`).
static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font as `sans-serif` (once per process).
pub fn ensure_font() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok =
        *DONE.get_or_init(|| register_font("sans-serif", FontStyle::Normal, DEJAVU_SANS).is_ok());
    if ok {
        Ok(())
    } else {
        Err(anyhow!("embedded font DejaVuSans.ttf could not be parsed"))
    }
}

/// Line pattern of a theory curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dash {
    Solid,
    Dashed,
    Dotted,
}

/// A curve, possibly in several pieces (gaps where undefined, breaks at jumps).
#[derive(Debug, Clone)]
pub struct Line {
    pub label: Option<String>,
    pub segments: Vec<Vec<(f64, f64)>>,
    pub color: RGBColor,
    pub dash: Dash,
    pub width: u32,
}

impl Line {
    pub fn new(label: impl Into<String>, color: RGBColor, dash: Dash) -> Self {
        Self {
            label: Some(label.into()),
            segments: Vec::new(),
            color,
            dash,
            width: 2,
        }
    }

    /// An unlabelled guide line (e.g. a vertical marker at a limit angle).
    pub fn guide(points: Vec<(f64, f64)>, color: RGBColor, dash: Dash) -> Self {
        Self {
            label: None,
            segments: vec![points],
            color,
            dash,
            width: 1,
        }
    }

    /// Builds segments from samples `(x, Some(y))`; `None` ends a segment, and so does a sample
    /// whose `break_before` flag is set (a discontinuity such as a regime change).
    pub fn with_samples(
        mut self,
        samples: impl IntoIterator<Item = (f64, Option<f64>, bool)>,
    ) -> Self {
        let mut cur: Vec<(f64, f64)> = Vec::new();
        for (x, y, break_before) in samples {
            if break_before && !cur.is_empty() {
                self.segments.push(std::mem::take(&mut cur));
            }
            match y {
                Some(y) if y.is_finite() && x.is_finite() => cur.push((x, y)),
                _ => {
                    if !cur.is_empty() {
                        self.segments.push(std::mem::take(&mut cur));
                    }
                }
            }
        }
        if !cur.is_empty() {
            self.segments.push(cur);
        }
        self
    }

    pub fn is_empty(&self) -> bool {
        self.segments.iter().all(|s| s.is_empty())
    }
}

/// Marker shape of measured points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Square,
    Triangle,
    Cross,
}

/// A measured value with optional 1-sigma errors `(below, above)` (asymmetric after a
/// non-linear transformation such as `tan`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataPoint {
    pub x: f64,
    pub y: f64,
    pub x_err: Option<(f64, f64)>,
    pub y_err: Option<(f64, f64)>,
}

/// A symmetric error.
pub fn sym(e: Option<f64>) -> Option<(f64, f64)> {
    e.map(|e| (e, e))
}

#[derive(Debug, Clone)]
pub struct Points {
    pub label: Option<String>,
    pub points: Vec<DataPoint>,
    pub color: RGBColor,
    pub marker: Marker,
}

/// A filled rectangle `((x0, y0), (x1, y1), colour)`.
pub type Cell = ((f64, f64), (f64, f64), RGBColor);

/// Filled rectangles with their own legend entries.
#[derive(Debug, Clone, Default)]
pub struct Cells {
    pub rects: Vec<Cell>,
    pub legend: Vec<(String, RGBColor)>,
}

/// Text at data coordinates.
#[derive(Debug, Clone)]
pub struct Note {
    pub x: f64,
    pub y: f64,
    pub text: String,
    pub color: RGBColor,
}

/// Where a panel's legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegendAt {
    UpperLeft,
    UpperRight,
    LowerLeft,
    LowerRight,
    /// The corner with the fewest curve samples and data points under it.
    Auto,
    None,
}

/// One set of axes.
#[derive(Debug, Clone)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    pub cells: Cells,
    pub lines: Vec<Line>,
    pub points: Vec<Points>,
    pub notes: Vec<Note>,
    pub legend: LegendAt,
}

impl Panel {
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_range: (0.0, 1.0),
            y_range: (0.0, 1.0),
            cells: Cells::default(),
            lines: Vec::new(),
            points: Vec::new(),
            notes: Vec::new(),
            legend: LegendAt::Auto,
        }
    }

    pub fn ranges(mut self, x: (f64, f64), y: (f64, f64)) -> Self {
        self.x_range = x;
        self.y_range = y;
        self
    }

    /// Sets the y range to cover every curve and point (with error bars), padded by 5 %,
    /// and never narrower than `min_span`.
    pub fn auto_y(mut self, min_span: f64) -> Self {
        let (lo, hi) = self.data_bounds(
            |p| (p.1, p.1),
            |d| {
                let (a, b) = d.y_err.unwrap_or((0.0, 0.0));
                (d.y - a, d.y + b)
            },
        );
        self.y_range = padded(lo, hi, min_span);
        self
    }

    /// Same as [`Panel::auto_y`] for x.
    pub fn auto_x(mut self, min_span: f64) -> Self {
        let (lo, hi) = self.data_bounds(
            |p| (p.0, p.0),
            |d| {
                let (a, b) = d.x_err.unwrap_or((0.0, 0.0));
                (d.x - a, d.x + b)
            },
        );
        self.x_range = padded(lo, hi, min_span);
        self
    }

    fn data_bounds(
        &self,
        on_line: impl Fn(&(f64, f64)) -> (f64, f64),
        on_point: impl Fn(&DataPoint) -> (f64, f64),
    ) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let xr = self.x_range;
        for l in &self.lines {
            for p in l.segments.iter().flatten() {
                let (a, b) = on_line(p);
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        for ps in &self.points {
            for d in &ps.points {
                if d.x < xr.0 || d.x > xr.1 {
                    continue;
                }
                let (a, b) = on_point(d);
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        (lo, hi)
    }
}

fn padded(lo: f64, hi: f64, min_span: f64) -> (f64, f64) {
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, min_span.max(1.0));
    }
    let mid = 0.5 * (lo + hi);
    let span = (hi - lo).max(min_span);
    (mid - 0.55 * span, mid + 0.55 * span)
}

/// A figure: panels on a grid, saved as `NAME.png` and `NAME.svg`.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem, e.g. `steel_fig12_delta2_jump`.
    pub name: String,
    /// Caption for the report (what is plotted, which coefficients).
    pub caption: String,
    pub panels: Vec<Panel>,
    pub cols: usize,
    /// Size in pixels of the PNG (the SVG uses the same units).
    pub size: (u32, u32),
}

impl Figure {
    pub fn new(name: impl Into<String>, caption: impl Into<String>, panels: Vec<Panel>) -> Self {
        let cols = panels.len().clamp(1, 2);
        let rows = panels.len().div_ceil(cols).max(1) as u32;
        Self {
            name: name.into(),
            caption: caption.into(),
            panels,
            cols,
            size: (760 * cols as u32, 560 * rows),
        }
    }

    pub fn with_size(mut self, w: u32, h: u32) -> Self {
        self.size = (w, h);
        self
    }
}

/// Paths of a saved figure.
#[derive(Debug, Clone)]
pub struct SavedFigure {
    pub name: String,
    pub caption: String,
    pub png: PathBuf,
    pub svg: PathBuf,
}

/// Renders `fig` into `dir/NAME.png` and `dir/NAME.svg`.
pub fn save(fig: &Figure, dir: &Path) -> Result<SavedFigure> {
    ensure_font()?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let png = dir.join(format!("{}.png", fig.name));
    let svg = dir.join(format!("{}.svg", fig.name));
    // Temporary names keep the extension: the bitmap backend picks the encoder from it.
    let png_tmp = dir.join(format!(".{}.tmp.png", fig.name));
    let svg_tmp = dir.join(format!(".{}.tmp.svg", fig.name));
    {
        // The bitmap backend draws into an RGB buffer; our `image` crate encodes it (plotters'
        // own encoder would pull in a second `image` version).
        let (w, h) = fig.size;
        let mut buf = vec![0u8; (w as usize) * (h as usize) * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buf, fig.size).into_drawing_area();
            draw_figure(fig, &root).map_err(|e| anyhow!("drawing {}: {e}", png.display()))?;
            root.present()
                .map_err(|e| anyhow!("drawing {}: {e}", png.display()))?;
        }
        let img = image::RgbImage::from_raw(w, h, buf)
            .ok_or_else(|| anyhow!("bitmap buffer of {} has the wrong size", png.display()))?;
        img.save_with_format(&png_tmp, image::ImageFormat::Png)
            .with_context(|| format!("writing {}", png_tmp.display()))?;
    }
    {
        let root = SVGBackend::new(&svg_tmp, fig.size).into_drawing_area();
        draw_figure(fig, &root).map_err(|e| anyhow!("drawing {}: {e}", svg.display()))?;
        root.present()
            .map_err(|e| anyhow!("writing {}: {e}", svg_tmp.display()))?;
    }
    std::fs::rename(&png_tmp, &png).with_context(|| format!("renaming to {}", png.display()))?;
    std::fs::rename(&svg_tmp, &svg).with_context(|| format!("renaming to {}", svg.display()))?;
    Ok(SavedFigure {
        name: fig.name.clone(),
        caption: fig.caption.clone(),
        png,
        svg,
    })
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

fn draw_figure<DB: DrawingBackend>(fig: &Figure, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let cols = fig.cols.max(1);
    let rows = fig.panels.len().div_ceil(cols).max(1);
    let areas = root.split_evenly((rows, cols));
    for (panel, area) in fig.panels.iter().zip(areas.iter()) {
        draw_panel(panel, area)?;
    }
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(p: &Panel, area: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(52)
        .y_label_area_size(70)
        .build_cartesian_2d(p.x_range.0..p.x_range.1, p.y_range.0..p.y_range.1)?;
    let (xs, ys) = (p.x_range.1 - p.x_range.0, p.y_range.1 - p.y_range.0);
    let fx = move |v: &f64| tick_label(*v, xs);
    let fy = move |v: &f64| tick_label(*v, ys);
    chart
        .configure_mesh()
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(215, 215, 215))
        .x_labels(8)
        .y_labels(8)
        .draw()?;

    let clip_x = p.x_range;
    let clip_y = p.y_range;
    let inside = |&(x, y): &(f64, f64)| {
        x >= clip_x.0 && x <= clip_x.1 && y >= clip_y.0 - 1e-9 && y <= clip_y.1 + 1e-9
    };

    chart.draw_series(
        p.cells
            .rects
            .iter()
            .map(|(a, b, c)| Rectangle::new([*a, *b], c.filled())),
    )?;
    for (label, color) in &p.cells.legend {
        let c = *color;
        chart
            .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())?
            .label(label.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 18, y + 6)], c.filled()));
    }

    for line in &p.lines {
        let style = line.color.stroke_width(line.width);
        let mut first = true;
        for seg in &line.segments {
            // Split a segment at points outside the y range so clipping never draws across the
            // frame (plotters clips only at the drawing area, not the plotting area).
            let pieces = clip_pieces(seg, (clip_x, clip_y));
            for piece in pieces {
                let (size, gap) = dash_pattern(line.dash);
                let anno = match line.dash {
                    Dash::Solid => chart.draw_series(LineSeries::new(piece, style))?,
                    _ => chart.draw_series(DashedLineSeries::new(piece, size, gap, style))?,
                };
                if first && let Some(label) = &line.label {
                    let (size, gap) = if line.dash == Dash::Solid {
                        (26, 1)
                    } else {
                        (size, gap)
                    };
                    anno.label(label.as_str()).legend(move |(x, y)| {
                        DashedPathElement::new(vec![(x, y), (x + 26, y)], size, gap, style)
                    });
                    first = false;
                }
            }
        }
    }

    for set in p.points.iter().filter(|s| !s.points.is_empty()) {
        let color = set.color;
        let bar = color.stroke_width(1);
        let pts: Vec<&DataPoint> = set.points.iter().filter(|d| inside(&(d.x, d.y))).collect();
        for d in &pts {
            if let Some((a, b)) = d.y_err.filter(|e| e.0 > 0.0 || e.1 > 0.0) {
                let lo = (d.y - a).max(clip_y.0);
                let hi = (d.y + b).min(clip_y.1);
                chart.draw_series(std::iter::once(ErrorBar::new_vertical(
                    d.x, lo, d.y, hi, bar, 6,
                )))?;
            }
            if let Some((a, b)) = d.x_err.filter(|e| e.0 > 0.0 || e.1 > 0.0) {
                let lo = (d.x - a).max(clip_x.0);
                let hi = (d.x + b).min(clip_x.1);
                chart.draw_series(std::iter::once(ErrorBar::new_horizontal(
                    d.y, lo, d.x, hi, bar, 6,
                )))?;
            }
        }
        // One branch per marker: plotters' legend closures need a concrete element type.
        macro_rules! markers {
            ($c:ident => $make:expr) => {{
                let anno = chart.draw_series(pts.iter().map(|d| {
                    let $c = (d.x, d.y);
                    $make
                }))?;
                if let Some(label) = &set.label {
                    anno.label(label.as_str()).legend(move |(x, y)| {
                        let $c = (x + 13, y);
                        $make
                    });
                }
            }};
        }
        match set.marker {
            Marker::Circle => markers!(c => Circle::new(c, 4, color.filled())),
            Marker::Square => markers!(c => {
                EmptyElement::at(c) + Rectangle::new([(-4, -4), (4, 4)], color.filled())
            }),
            Marker::Triangle => markers!(c => TriangleMarker::new(c, 6, color.filled())),
            Marker::Cross => markers!(c => Cross::new(c, 5, color.stroke_width(2))),
        }
    }

    for n in &p.notes {
        chart.draw_series(std::iter::once(Text::new(
            n.text.clone(),
            (n.x, n.y),
            ("sans-serif", 15).into_font().color(&n.color),
        )))?;
    }

    let legend = if p.legend == LegendAt::Auto {
        emptiest_corner(p, chart.plotting_area().dim_in_pixel())
    } else {
        p.legend
    };
    let pos = match legend {
        LegendAt::UpperLeft => Some(SeriesLabelPosition::UpperLeft),
        LegendAt::UpperRight => Some(SeriesLabelPosition::UpperRight),
        LegendAt::LowerLeft => Some(SeriesLabelPosition::LowerLeft),
        LegendAt::LowerRight => Some(SeriesLabelPosition::LowerRight),
        LegendAt::None | LegendAt::Auto => None,
    };
    let has_labels = p.lines.iter().any(|l| l.label.is_some() && !l.is_empty())
        || p.points
            .iter()
            .any(|s| s.label.is_some() && !s.points.is_empty())
        || !p.cells.legend.is_empty();
    if let Some(pos) = pos
        && has_labels
    {
        chart
            .configure_series_labels()
            .position(pos)
            .label_font(("sans-serif", 15))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .margin(8)
            .draw()?;
    }
    Ok(())
}

/// The corner of the plotting window (a box of 45 % × 40 % of it) that holds the fewest curve
/// samples and measured points, weighting points (with error bars) heavier than curves.
fn emptiest_corner(p: &Panel, plot_px: (u32, u32)) -> LegendAt {
    let ((x0, x1), (y0, y1)) = (p.x_range, p.y_range);
    let (w, h) = (x1 - x0, y1 - y0);
    // The legend's size in pixels (15 px font: about 20 px per entry, 8 px per character plus
    // the sample and margins), as fractions of the plotting area.
    let labels: Vec<&str> = p
        .lines
        .iter()
        .filter(|l| !l.is_empty())
        .filter_map(|l| l.label.as_deref())
        .chain(
            p.points
                .iter()
                .filter(|s| !s.points.is_empty())
                .filter_map(|s| s.label.as_deref()),
        )
        .chain(p.cells.legend.iter().map(|(l, _)| l.as_str()))
        .collect();
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    let (pw, ph) = (plot_px.0.max(1) as f64, plot_px.1.max(1) as f64);
    let fw = ((8.0 * longest as f64 + 70.0) / pw).clamp(0.15, 0.95);
    let fh = ((20.0 * labels.len() as f64 + 24.0) / ph).clamp(0.1, 0.95);
    let corners = [
        (LegendAt::UpperLeft, (x0, x0 + fw * w), (y1 - fh * h, y1)),
        (LegendAt::UpperRight, (x1 - fw * w, x1), (y1 - fh * h, y1)),
        (LegendAt::LowerRight, (x1 - fw * w, x1), (y0, y0 + fh * h)),
        (LegendAt::LowerLeft, (x0, x0 + fw * w), (y0, y0 + fh * h)),
    ];
    let mut best = (LegendAt::UpperLeft, f64::INFINITY);
    for (corner, (a, b), (c, d)) in corners {
        let inside = |x: f64, y: f64| x >= a && x <= b && y >= c && y <= d;
        let mut score = 0.0;
        for l in &p.lines {
            for seg in &l.segments {
                // Sample every 1 % of the window along each piece, so that a long straight
                // piece counts wherever it runs.
                for win in seg.windows(2) {
                    let len = ((win[1].0 - win[0].0) / w).hypot((win[1].1 - win[0].1) / h);
                    let n = ((len / 0.01).ceil() as usize).clamp(1, 400);
                    for k in 0..n {
                        let t = k as f64 / n as f64;
                        let (x, y) = (
                            win[0].0 + t * (win[1].0 - win[0].0),
                            win[0].1 + t * (win[1].1 - win[0].1),
                        );
                        if inside(x, y) {
                            score += 1.0;
                        }
                    }
                }
            }
        }
        for s in &p.points {
            for d in &s.points {
                if inside(d.x, d.y) {
                    score += 40.0;
                }
            }
        }
        for n in &p.notes {
            // A note's text runs about a quarter of the width to the right of its anchor.
            for k in 0..4 {
                if inside(n.x + 0.06 * k as f64 * w, n.y) {
                    score += 40.0;
                }
            }
        }
        if score < best.1 {
            best = (corner, score);
        }
    }
    best.0
}

/// Tick label with as many decimals as the axis span needs (no `-0`, no `20.0` for degrees).
pub fn tick_label(v: f64, span: f64) -> String {
    let decimals = if span >= 20.0 {
        0
    } else if span >= 2.0 {
        1
    } else if span >= 0.2 {
        2
    } else {
        3
    };
    let mut s = format!("{v:.decimals$}");
    if s.trim_start_matches('-') == format!("{:.decimals$}", 0.0) {
        s = format!("{:.decimals$}", 0.0);
    }
    if decimals > 0 && s.ends_with('0') && span >= 2.0 {
        // 1.0, 2.0 ... on a span of a few units read better as 1, 2.
        let t = s.trim_end_matches('0').trim_end_matches('.');
        t.to_string()
    } else {
        s
    }
}

/// The part `[t0, t1]` of the segment `a + t (b − a)`, `t ∈ [0, 1]`, inside the window
/// `[x0, x1] × [y0, y1]` (Liang–Barsky), `None` where it misses it.
pub fn clip_interval(
    a: (f64, f64),
    b: (f64, f64),
    ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64)),
) -> Option<(f64, f64)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Clips a polyline to the window `[x0, x1] × [y0, y1]` (Liang–Barsky per segment) and returns
/// the visible runs; a curve that leaves and re-enters the window becomes two runs.
fn clip_pieces(seg: &[(f64, f64)], win: ((f64, f64), (f64, f64))) -> Vec<Vec<(f64, f64)>> {
    let ((x0, x1), (y0, y1)) = win;
    let inside = |p: &(f64, f64)| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1;
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    if seg.len() == 1 && inside(&seg[0]) {
        return vec![seg.to_vec()];
    }
    for w in seg.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let Some((t0, t1)) = clip_interval(a, b, win) else {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            continue;
        };
        let pa = (a.0 + t0 * dx, a.1 + t0 * dy);
        let pb = (a.0 + t1 * dx, a.1 + t1 * dy);
        if cur.is_empty() {
            cur.push(pa);
        }
        cur.push(pb);
        if t1 < 1.0 {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Dash and gap lengths in pixels for a pattern (solid: one dash longer than the legend sample).
fn dash_pattern(dash: Dash) -> (i32, i32) {
    match dash {
        Dash::Solid => (40, 1),
        Dash::Dashed => (10, 6),
        Dash::Dotted => (2, 5),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_fit_the_span() {
        assert_eq!(tick_label(20.0, 90.0), "20");
        assert_eq!(tick_label(-0.0001, 90.0), "0");
        assert_eq!(tick_label(-0.0, 1.0), "0.00");
        assert_eq!(tick_label(2.0, 8.0), "2");
        assert_eq!(tick_label(2.5, 8.0), "2.5");
        assert_eq!(tick_label(0.0, 10.5), "0");
        assert_eq!(tick_label(-0.01, 10.5), "0");
        assert_eq!(tick_label(0.25, 1.5), "0.25");
    }

    #[test]
    fn clipping_cuts_segments_at_the_window_edge() {
        let win = ((0.0, 1.0), (0.0, 1.0));
        // Leaves through the right edge at x = 1 (y = 0.5) and never comes back.
        let runs = clip_pieces(&[(0.5, 0.25), (1.5, 0.75), (2.0, 0.5)], win);
        assert_eq!(runs, vec![vec![(0.5, 0.25), (1.0, 0.5)]]);
        // Enters, leaves, re-enters: two runs.
        let runs = clip_pieces(&[(-1.0, 0.5), (0.5, 0.5), (0.5, 2.0), (0.25, 0.5)], win);
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0], vec![(0.0, 0.5), (0.5, 0.5), (0.5, 1.0)]);
        assert_eq!(runs[1][1], (0.25, 0.5));
    }

    #[test]
    fn samples_split_at_gaps_and_breaks() {
        let l = Line::new("x", BLACK, Dash::Solid).with_samples(vec![
            (0.0, Some(0.0), false),
            (1.0, Some(1.0), false),
            (2.0, None, false),
            (3.0, Some(3.0), false),
            (4.0, Some(4.0), true),
        ]);
        assert_eq!(
            l.segments,
            vec![
                vec![(0.0, 0.0), (1.0, 1.0)],
                vec![(3.0, 3.0)],
                vec![(4.0, 4.0)]
            ]
        );
    }
}
