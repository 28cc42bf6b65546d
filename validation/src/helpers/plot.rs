//! Line/scatter plots (plotters, bitmap backend, DejaVu Sans registered as "sans-serif").

use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, bail, Result};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::fmt_num;

static FONTS: Once = Once::new();

/// Registers the embedded DejaVu Sans as the "sans-serif" font (once per process); the
/// bitmap backend has no system fonts otherwise.
pub fn ensure_fonts() {
    FONTS.call_once(|| {
        // The bytes are a valid TrueType font shipped by the `dejavu` crate; a failure here
        // would be a packaging bug, and plots would then fail with a clear error below.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Marker shapes for scatter series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Open circle.
    Ring,
    /// Diagonal cross.
    Cross,
    /// Filled triangle.
    Triangle,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Solid line through the points.
    Line,
    /// Dashed line through the points.
    Dashed,
    /// Markers only (reference data).
    Markers(Marker),
    /// Solid line with markers.
    LineMarkers(Marker),
    /// Dashed line with markers.
    DashedMarkers(Marker),
    /// Dashed horizontal line across the whole x range at the first point's y.
    HorizontalLine,
}

/// A named series.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points; non-finite points (and non-positive ones on log axes) are skipped.
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub style: SeriesStyle,
    /// Palette index (same index = same colour, e.g. a result and its reference).
    pub color: usize,
}

impl Series {
    /// A solid line.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>, color: usize) -> Self {
        Self {
            name: name.into(),
            points,
            style: SeriesStyle::Line,
            color,
        }
    }

    /// Reference markers.
    pub fn markers(
        name: impl Into<String>,
        points: Vec<(f64, f64)>,
        marker: Marker,
        color: usize,
    ) -> Self {
        Self {
            name: name.into(),
            points,
            style: SeriesStyle::Markers(marker),
            color,
        }
    }

    /// A series with an explicit style.
    pub fn styled(
        name: impl Into<String>,
        points: Vec<(f64, f64)>,
        style: SeriesStyle,
        color: usize,
    ) -> Self {
        Self {
            name: name.into(),
            points,
            style,
            color,
        }
    }
}

/// Corner of the plot area holding the legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legend {
    /// Upper right.
    UpperRight,
    /// Upper left.
    UpperLeft,
    /// Lower right.
    LowerRight,
    /// Lower left.
    LowerLeft,
}

/// A plot: title, axis labels (with units), axes and series.
#[derive(Debug, Clone)]
pub struct PlotSpec {
    /// Title above the chart.
    pub title: String,
    /// x-axis label, with units.
    pub x_label: String,
    /// y-axis label, with units.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Fixed x range (else from the data).
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range (else from the data); points outside are clipped.
    pub y_range: Option<(f64, f64)>,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Corner of the legend.
    pub legend: Legend,
    /// Image size in pixels.
    pub size: (u32, u32),
}

impl PlotSpec {
    /// A linear plot of 1024×768 pixels without series.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: false,
            log_y: false,
            x_range: None,
            y_range: None,
            series: Vec::new(),
            legend: Legend::UpperRight,
            size: (1024, 768),
        }
    }

    /// Log-log axes.
    pub fn log_log(mut self) -> Self {
        self.log_x = true;
        self.log_y = true;
        self
    }
}

/// Tableau-10 palette.
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

fn color(i: usize) -> RGBColor {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    RGBColor(r, g, b)
}

fn usable(p: (f64, f64), log_x: bool, log_y: bool) -> bool {
    p.0.is_finite() && p.1.is_finite() && (!log_x || p.0 > 0.0) && (!log_y || p.1 > 0.0)
}

fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        // Start at a power of ten: plotters places log-axis ticks from the first power of ten
        // inside the range, so a range starting just below one would leave its start unlabelled.
        let (a, b) = (lo.log10(), hi.log10());
        let pad = ((b - a) * 0.05).max(0.05);
        (10f64.powf((a - 1e-9).floor()), 10f64.powf(b + pad))
    } else {
        let span = hi - lo;
        let pad = if span > 0.0 {
            span * 0.05
        } else {
            lo.abs().max(1.0) * 0.1
        };
        (lo - pad, hi + pad)
    }
}

fn data_range<I: Iterator<Item = f64>>(values: I, what: &str) -> Result<(f64, f64)> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        bail!("no plottable {what} values");
    }
    Ok((lo, hi))
}

/// Draws `spec` to a PNG at `path`.
pub fn plot_xy(path: &Path, spec: &PlotSpec) -> Result<()> {
    ensure_fonts();
    let (lx, ly) = (spec.log_x, spec.log_y);
    let pts = || {
        spec.series
            .iter()
            .filter(|s| s.style != SeriesStyle::HorizontalLine)
            .flat_map(|s| s.points.iter().copied())
            .filter(move |&p| usable(p, lx, ly))
    };
    let (x0, x1) = match spec.x_range {
        Some(r) => r,
        None => {
            let (a, b) = data_range(pts().map(|p| p.0), "x")?;
            padded(a, b, lx)
        }
    };
    let (y0, y1) = match spec.y_range {
        Some(r) => r,
        None => {
            let hlines = spec
                .series
                .iter()
                .filter(|s| s.style == SeriesStyle::HorizontalLine)
                .filter_map(|s| s.points.first().map(|p| p.1))
                .filter(|y| y.is_finite() && (!ly || *y > 0.0));
            let ys = pts()
                .filter(|p| p.0 >= x0 && p.0 <= x1)
                .map(|p| p.1)
                .chain(hlines);
            let (a, b) = data_range(ys, "y")?;
            padded(a, b, ly)
        }
    };
    if !(x0 < x1 && y0 < y1) {
        bail!("empty plot range x [{x0}, {x1}], y [{y0}, {y1}]");
    }
    let res = match (lx, ly) {
        (false, false) => draw(path, spec, x0..x1, y0..y1, (x0, x1), (y0, y1)),
        (true, false) => draw(path, spec, (x0..x1).log_scale(), y0..y1, (x0, x1), (y0, y1)),
        (false, true) => draw(path, spec, x0..x1, (y0..y1).log_scale(), (x0, x1), (y0, y1)),
        (true, true) => draw(
            path,
            spec,
            (x0..x1).log_scale(),
            (y0..y1).log_scale(),
            (x0, x1),
            (y0, y1),
        ),
    };
    res.map_err(|e| anyhow!("plotting {}: {e}", path.display()))
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// Splits a series into runs of points inside the plot box (so that clipped curves do not
/// draw over the axes).
fn runs_inside(
    points: &[(f64, f64)],
    spec: &PlotSpec,
    xr: (f64, f64),
    yr: (f64, f64),
) -> Vec<Vec<(f64, f64)>> {
    let mut runs = vec![Vec::new()];
    for &p in points {
        let inside = usable(p, spec.log_x, spec.log_y)
            && p.0 >= xr.0
            && p.0 <= xr.1
            && p.1 >= yr.0
            && p.1 <= yr.1;
        if inside {
            runs.last_mut().expect("non-empty").push(p);
        } else if !runs.last().expect("non-empty").is_empty() {
            runs.push(Vec::new());
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

fn draw<X, Y>(
    path: &Path,
    spec: &PlotSpec,
    x: X,
    y: Y,
    xr: (f64, f64),
    yr: (f64, f64),
) -> DrawResult
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let root = BitMapBackend::new(path, spec.size).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&spec.title, ("sans-serif", 26))
        .margin(20)
        .x_label_area_size(60)
        .y_label_area_size(90)
        .build_cartesian_2d(x, y)?;
    // On log axes label only 1, 2 and 5 × 10^k (plotters proposes every integer multiple).
    let log_fmt = |v: &f64| {
        let m = *v / 10f64.powf(v.log10().floor());
        if [1.0, 2.0, 5.0, 10.0]
            .iter()
            .any(|k| (m - k).abs() < 1e-6 * k)
        {
            fmt_num(*v)
        } else {
            String::new()
        }
    };
    let lin_fmt = |v: &f64| fmt_num(*v);
    let x_fmt: &dyn Fn(&f64) -> String = if spec.log_x { &log_fmt } else { &lin_fmt };
    let y_fmt: &dyn Fn(&f64) -> String = if spec.log_y { &log_fmt } else { &lin_fmt };
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_str())
        .y_desc(spec.y_label.as_str())
        .axis_desc_style(("sans-serif", 20))
        .label_style(("sans-serif", 16))
        .x_labels(if spec.log_x { 40 } else { 12 })
        .y_labels(if spec.log_y { 40 } else { 12 })
        .x_label_formatter(x_fmt)
        .y_label_formatter(y_fmt)
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()?;

    for s in &spec.series {
        let c = color(s.color);
        let line = ShapeStyle::from(&c).stroke_width(2);
        let runs = runs_inside(&s.points, spec, xr, yr);
        let (draw_line, dashed, marker) = match s.style {
            SeriesStyle::Line => (true, false, None),
            SeriesStyle::Dashed => (true, true, None),
            SeriesStyle::Markers(m) => (false, false, Some(m)),
            SeriesStyle::LineMarkers(m) => (true, false, Some(m)),
            SeriesStyle::DashedMarkers(m) => (true, true, Some(m)),
            SeriesStyle::HorizontalLine => (false, true, None),
        };
        // Draw the lines, then the markers; the legend entry goes on the first drawn part.
        let mut first = true;
        let style = s.style;
        let filled = ShapeStyle::from(&c).filled();
        let outline = ShapeStyle::from(&c).stroke_width(2);
        // Runs `$body` with `$mk` bound to a constructor `point -> marker element` of marker `$m`.
        macro_rules! with_marker {
            ($m:expr, |$mk:ident| $body:expr) => {
                match $m {
                    Marker::Circle => {
                        let $mk = move |p| Circle::new(p, 6, filled);
                        $body
                    }
                    Marker::Ring => {
                        let $mk = move |p| Circle::new(p, 7, outline);
                        $body
                    }
                    Marker::Cross => {
                        let $mk = move |p| Cross::new(p, 6, outline);
                        $body
                    }
                    Marker::Triangle => {
                        let $mk = move |p| TriangleMarker::new(p, 7, filled);
                        $body
                    }
                }
            };
        }
        macro_rules! label {
            ($anno:expr) => {{
                let anno = $anno;
                if std::mem::take(&mut first) && !s.name.is_empty() {
                    let anno = anno.label(s.name.as_str());
                    let dash = move |x: i32, y: i32| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (7, 0)], line)
                            + PathElement::new(vec![(14, 0), (22, 0)], line)
                    };
                    match style {
                        SeriesStyle::Line => {
                            anno.legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 22, y)], line)
                            });
                        }
                        SeriesStyle::Dashed | SeriesStyle::HorizontalLine => {
                            anno.legend(move |(x, y)| dash(x, y));
                        }
                        SeriesStyle::Markers(m) => with_marker!(m, |mk| {
                            anno.legend(move |(x, y)| mk((x + 11, y)));
                        }),
                        SeriesStyle::LineMarkers(m) => with_marker!(m, |mk| {
                            anno.legend(move |(x, y)| {
                                EmptyElement::at((x, y))
                                    + PathElement::new(vec![(0, 0), (22, 0)], line)
                                    + mk((11, 0))
                            });
                        }),
                        SeriesStyle::DashedMarkers(m) => with_marker!(m, |mk| {
                            anno.legend(move |(x, y)| dash(x, y) + mk((11, 0)));
                        }),
                    }
                }
            }};
        }
        if draw_line {
            for run in &runs {
                if dashed {
                    label!(chart.draw_series(DashedLineSeries::new(
                        run.iter().copied(),
                        10,
                        6,
                        line
                    ))?);
                } else {
                    label!(chart.draw_series(LineSeries::new(run.iter().copied(), line))?);
                }
            }
        }
        if s.style == SeriesStyle::HorizontalLine {
            if let Some(&(_, yv)) = s.points.first() {
                if yv >= yr.0 && yv <= yr.1 {
                    label!(chart.draw_series(DashedLineSeries::new(
                        [(xr.0, yv), (xr.1, yv)],
                        10,
                        6,
                        line
                    ))?);
                }
            }
        }
        if let Some(m) = marker {
            let inside: Vec<(f64, f64)> = runs.iter().flatten().copied().collect();
            with_marker!(m, |mk| label!(
                chart.draw_series(inside.iter().map(|&p| mk(p)))?
            ));
        }
    }

    chart
        .configure_series_labels()
        .position(match spec.legend {
            Legend::UpperRight => SeriesLabelPosition::UpperRight,
            Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
            Legend::LowerRight => SeriesLabelPosition::LowerRight,
            Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
        })
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
