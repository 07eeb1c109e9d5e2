//! Figures with plotters: SVG or PNG (chosen by the file extension), drawn with the DejaVu Sans
//! font compiled into the binary (registered with plotters' `ab_glyph` backend; no system font
//! lookup, so figures look the same on every machine).
//!
//! Used for central-node trajectories and energies ([`plot_series`]), the mass-candidate scan
//! (log-scale axes, [`PlotOptions::log_x`] and [`PlotOptions::log_y`]) and modal spectra
//! ([`plot_spectrum`]). Points with a non-finite coordinate (and, on a log axis, a non-positive
//! one) are skipped, counted in
//! [`PlotSummary`] and mentioned in the caption, so a diverged run still gives a figure.
//!
//! ```
//! use nurbspring_io::plot::{Series, plot_series};
//! # let dir = tempfile::tempdir().unwrap();
//! let t: Vec<f64> = (0..50).map(|k| 0.08 * k as f64).collect();
//! let msm = Series::line("MSM", t.iter().map(|&t| (t, 2.0 - 0.2 * t.sin())).collect());
//! let summary = plot_series(dir.path().join("z.svg"), "central node", "t [s]", "z", &[msm]).unwrap();
//! assert_eq!(summary.skipped, 0);
//! ```

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;

use crate::OutputError;
use crate::atomic::write_atomic_bytes;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A polyline through the points (in the given order).
    #[default]
    Line,
    /// Markers only (the marker shape changes with the series index).
    Points,
    /// A polyline with markers.
    LinePoints,
}

/// One named data series.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` pairs.
    pub points: Vec<(f64, f64)>,
    /// Line, markers or both.
    pub style: SeriesStyle,
}

impl Series {
    /// A series drawn as a line.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: SeriesStyle::Line,
        }
    }

    /// A series drawn as markers.
    pub fn points(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: SeriesStyle::Points,
        }
    }
}

/// Title, labels, scale and size of a figure.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotOptions {
    /// Caption above the plot.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// Logarithmic x axis (non-positive x values are skipped).
    pub log_x: bool,
    /// Logarithmic y axis (non-positive y values are skipped).
    pub log_y: bool,
    /// x values are whole numbers (mode numbers): ticks at integers only.
    pub integer_x: bool,
    /// Width in pixels (default 1024).
    pub width: u32,
    /// Height in pixels (default 640).
    pub height: u32,
}

impl PlotOptions {
    /// Linear axes, 1024 × 640 pixels.
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
            integer_x: false,
            width: 1024,
            height: 640,
        }
    }
}

/// What was drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlotSummary {
    /// Points drawn, over all series.
    pub drawn: usize,
    /// Points skipped: a non-finite coordinate, or y ≤ 0 on a log axis.
    pub skipped: usize,
}

/// Output format, from the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Svg,
    Png,
}

/// Colours (Tableau 10) cycled over the series.
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The family name under which the embedded font is registered. SVG files name it too, so
/// viewers fall back to their own sans-serif font.
const FONT_FAMILY: &str = "sans-serif";

/// Registers the embedded DejaVu Sans once per process.
fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let fail = |_| "the embedded DejaVu Sans font could not be loaded".to_string();
            plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, dejavu::sans::regular())
                .map_err(fail)?;
            plotters::style::register_font(FONT_FAMILY, FontStyle::Bold, dejavu::sans::bold())
                .map_err(fail)
        })
        .clone()
}

/// Plots several named series with linear axes (1024 × 640); the format (`.svg` or `.png`)
/// comes from the extension of `path`.
pub fn plot_series(
    path: impl AsRef<Path>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<PlotSummary, OutputError> {
    plot_series_with(path, &PlotOptions::new(title, x_label, y_label), series)
}

/// Plots a spectrum: each set of values (e.g. D-NURBS and MSM eigenfrequencies) as markers at
/// x = mode number 1, 2, ….
pub fn plot_spectrum(
    path: impl AsRef<Path>,
    title: &str,
    y_label: &str,
    sets: &[(&str, &[f64])],
) -> Result<PlotSummary, OutputError> {
    let series: Vec<Series> = sets
        .iter()
        .map(|(name, values)| {
            Series::points(
                *name,
                values
                    .iter()
                    .enumerate()
                    .map(|(k, &v)| ((k + 1) as f64, v))
                    .collect(),
            )
        })
        .collect();
    let mut options = PlotOptions::new(title, "mode", y_label);
    options.integer_x = true;
    plot_series_with(path, &options, &series)
}

/// Plots several named series with the given options.
pub fn plot_series_with(
    path: impl AsRef<Path>,
    options: &PlotOptions,
    series: &[Series],
) -> Result<PlotSummary, OutputError> {
    let path = path.as_ref();
    let format = match path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("svg") => Format::Svg,
        Some("png") => Format::Png,
        other => {
            return Err(OutputError::invalid(
                path,
                format!(
                    "cannot tell the figure format from the extension {:?}: use .svg or .png",
                    other.unwrap_or("")
                ),
            ));
        }
    };
    if options.width < 200 || options.height < 150 || options.width > 8192 || options.height > 8192
    {
        return Err(OutputError::invalid(
            path,
            format!(
                "figure size {} x {} is outside 200 x 150 ..= 8192 x 8192",
                options.width, options.height
            ),
        ));
    }
    let plot_err = |message: String| OutputError::Plot {
        path: path.to_path_buf(),
        message,
    };
    ensure_font().map_err(plot_err)?;

    // Keep only drawable points.
    let mut summary = PlotSummary::default();
    let clean: Vec<Series> = series
        .iter()
        .map(|s| {
            let points: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&(x, y)| {
                    x.is_finite()
                        && y.is_finite()
                        && (!options.log_x || x > 0.0)
                        && (!options.log_y || y > 0.0)
                })
                .collect();
            summary.drawn += points.len();
            summary.skipped += s.points.len() - points.len();
            Series {
                name: s.name.clone(),
                points,
                style: s.style,
            }
        })
        .collect();
    let caption = if summary.skipped > 0 {
        let what = if options.log_x || options.log_y {
            "non-finite or non-positive"
        } else {
            "non-finite"
        };
        let noun = if summary.skipped == 1 {
            "point"
        } else {
            "points"
        };
        format!(
            "{} ({} {what} {noun} omitted)",
            options.title, summary.skipped
        )
    } else {
        options.title.clone()
    };

    let size = (options.width, options.height);
    let bytes = match format {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                draw(&root, options, &caption, &clean, 1).map_err(plot_err)?;
                root.present().map_err(|e| plot_err(e.to_string()))?;
            }
            svg.into_bytes()
        }
        Format::Png => {
            // plotters' bitmap backend draws lines and markers without anti-aliasing: draw at
            // SUPERSAMPLE times the size and average down (a box filter over each block).
            let (w, h) = size;
            let (sw, sh) = (w * SUPERSAMPLE, h * SUPERSAMPLE);
            let mut big = vec![0u8; sw as usize * sh as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut big, (sw, sh)).into_drawing_area();
                draw(&root, options, &caption, &clean, SUPERSAMPLE).map_err(plot_err)?;
                root.present().map_err(|e| plot_err(e.to_string()))?;
            }
            let rgb = box_downsample(&big, w, h, SUPERSAMPLE);
            let mut png = Vec::new();
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(&mut png),
                &rgb,
                w,
                h,
                image::ColorType::Rgb8,
            )
            .map_err(|e| plot_err(format!("PNG encoding failed: {e}")))?;
            png
        }
    };
    write_atomic_bytes(path, &bytes)?;
    Ok(summary)
}

/// PNG figures are drawn at this many times their size and averaged down (anti-aliasing).
pub const SUPERSAMPLE: u32 = 2;

/// Segments per piece of a thick line drawn on a raster (see `fill_chart`).
const RASTER_PIECE: usize = 8;

/// Averages each `k × k` block of the RGB image `big` (`w·k × h·k` pixels) into one pixel.
fn box_downsample(big: &[u8], w: u32, h: u32, k: u32) -> Vec<u8> {
    let (w, h, k) = (w as usize, h as usize, k as usize);
    let stride = w * k * 3;
    let n = (k * k) as u32;
    let mut out = vec![0u8; w * h * 3];
    // Row sums of one output row: the k input rows added pixel block by pixel block, in
    // memory order.
    let mut sums = vec![0u32; w * 3];
    for (y, out_row) in out.chunks_exact_mut(w * 3).enumerate() {
        sums.fill(0);
        for row in big[y * k * stride..(y + 1) * k * stride].chunks_exact(stride) {
            for (sum, block) in sums.chunks_exact_mut(3).zip(row.chunks_exact(3 * k)) {
                for px in block.chunks_exact(3) {
                    sum[0] += u32::from(px[0]);
                    sum[1] += u32::from(px[1]);
                    sum[2] += u32::from(px[2]);
                }
            }
        }
        for (o, &s) in out_row.iter_mut().zip(&sums) {
            *o = ((s + n / 2) / n) as u8;
        }
    }
    out
}

/// Axis range covering `values` with a 5 % margin (a unit range when empty or degenerate).
fn linear_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if lo > hi {
        return 0.0..1.0;
    }
    let span = hi - lo;
    if span == 0.0 {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - d)..(hi + d);
    }
    let pad = 0.05 * span;
    if pad.is_finite() && (lo - pad).is_finite() && (hi + pad).is_finite() {
        (lo - pad)..(hi + pad)
    } else {
        lo..hi
    }
}

/// Positive axis range for a log scale, padded by a factor 1.5 at each end.
fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if lo > hi {
        return 0.1..10.0;
    }
    let (lo, hi) = if lo == hi {
        (lo / 10.0, hi * 10.0)
    } else {
        (lo / 1.5, hi * 1.5)
    };
    let lo = if lo > 0.0 { lo } else { f64::MIN_POSITIVE };
    let hi = if hi.is_finite() { hi } else { f64::MAX };
    // Out to the nearest 1, 2 or 5 times a power of ten, so both ends carry a label.
    let nice = |x: f64, up: bool| {
        let e = 10f64.powf(x.log10().floor());
        let steps = [1.0, 2.0, 5.0, 10.0];
        let m = x / e;
        let pick = if up {
            steps.iter().copied().find(|&s| s >= m * (1.0 - 1e-12))
        } else {
            steps
                .iter()
                .rev()
                .copied()
                .find(|&s| s <= m * (1.0 + 1e-12))
        };
        let v = pick.unwrap_or(1.0) * e;
        if v.is_finite() && v > 0.0 { v } else { x }
    };
    nice(lo, false)..nice(hi, true)
}

/// The corner of the plot area covering the fewest data points, how many it covers there, and
/// the fraction of the plot's height the legend box takes.
fn legend_place(series: &[Series], options: &PlotOptions) -> (SeriesLabelPosition, usize, f64) {
    let scaled = |v: f64, log: bool| if log { v.log10() } else { v };
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| {
            s.points
                .iter()
                .map(|&(x, y)| (scaled(x, options.log_x), scaled(y, options.log_y)))
        })
        .collect();
    let x = linear_range(pts.iter().map(|p| p.0));
    let y = linear_range(pts.iter().map(|p| p.1));
    let norm = |v: f64, r: &Range<f64>| (v - r.start) / (r.end - r.start);
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let rows = series.len() as f64;
    let height = (0.06 + 0.045 * rows).min(0.6);
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, right, upper) in corners {
        let count = pts
            .iter()
            .filter(|&&(px, py)| {
                let (u, v) = (norm(px, &x), norm(py, &y));
                let in_x = if right { u > 0.68 } else { u < 0.32 };
                let in_y = if upper { v > 1.0 - height } else { v < height };
                in_x && in_y
            })
            .count();
        if count < best.0 {
            best = (count, pos);
        }
    }
    (best.1, best.0, height)
}

/// The largest caption font size (at most `size`, at least 10 pixels a unit of `px`) whose
/// text fits `width` pixels, so a long title is not clipped at both edges.
fn caption_size<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    caption: &str,
    size: u32,
    width: u32,
    px: u32,
) -> u32 {
    let mut s = size;
    while s > 10 * px {
        match root.estimate_text_size(caption, &(FONT_FAMILY, s).into_text_style(root)) {
            Ok((w, _)) if w <= width => return s,
            Err(_) => return s,
            _ => s -= px,
        }
    }
    s
}

/// A log axis label with two significant digits (`0.2`, `0.015`, `3e-5`).
fn log_label(v: &f64) -> String {
    if *v <= 0.0 || !v.is_finite() {
        return String::new();
    }
    let e = v.log10().floor();
    if (-3.0..=4.0).contains(&e) {
        let digits = (1.0 - e).max(0.0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.1e}")
    }
}

/// An axis label for a whole number, none between two (`3` for 3.0, empty for 2.5).
fn integer_label(v: &f64) -> String {
    let r = v.round();
    if (v - r).abs() <= 1e-9 * r.abs().max(1.0) {
        format!("{:.0}", r + 0.0)
    } else {
        String::new()
    }
}

/// Draws the whole figure on `root`, whose pixels are `px` times those of the figure (sizes,
/// widths and fonts scale with it).
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    options: &PlotOptions,
    caption: &str,
    series: &[Series],
    px: u32,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let x_values = || series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let y_values = || series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    // Room above the data for the legend when every corner would cover some of it.
    let (_, covered, height) = legend_place(series, options);
    let headroom = if covered > 0 && !series.is_empty() {
        height / (1.0 - height)
    } else {
        0.0
    };
    let width = root.dim_in_pixel().0.saturating_sub(32 * px);
    let title = caption_size(root, caption, 24 * px, width, px);
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(caption, (FONT_FAMILY, title))
        .margin(16 * px)
        .x_label_area_size(48 * px)
        .y_label_area_size(80 * px);
    let x = if options.log_x {
        log_range(x_values())
    } else {
        linear_range(x_values())
    };
    let y = if options.log_y {
        let r = log_range(y_values());
        let top = r.end * (r.end / r.start).powf(headroom);
        r.start..if top.is_finite() { top } else { r.end }
    } else {
        let r = linear_range(y_values());
        let top = r.end + headroom * (r.end - r.start);
        r.start..if top.is_finite() { top } else { r.end }
    };
    let fail = |e: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    match (options.log_x, options.log_y) {
        (false, false) => {
            let chart = builder.build_cartesian_2d(x, y).map_err(fail)?;
            fill_chart(chart, options, series, px)
        }
        (false, true) => {
            let chart = builder.build_cartesian_2d(x, y.log_scale()).map_err(fail)?;
            fill_chart(chart, options, series, px)
        }
        (true, false) => {
            let chart = builder.build_cartesian_2d(x.log_scale(), y).map_err(fail)?;
            fill_chart(chart, options, series, px)
        }
        (true, true) => {
            let chart = builder
                .build_cartesian_2d(x.log_scale(), y.log_scale())
                .map_err(fail)?;
            fill_chart(chart, options, series, px)
        }
    }
}

/// Mesh, series and legend, for either scale of each axis.
fn fill_chart<'a, DB, X, Y>(
    mut chart: ChartContext<'a, DB, Cartesian2d<X, Y>>,
    options: &PlotOptions,
    series: &[Series],
    px: u32,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let x_span = chart.x_range();
    let integer_ticks = (x_span.end.floor() - x_span.start.ceil()).max(0.0) as usize + 1;
    let mut mesh = chart.configure_mesh();
    if options.integer_x {
        // Whole numbers only: a tick between two integers gets no label.
        mesh.x_labels(integer_ticks.clamp(2, 12))
            .x_label_formatter(&integer_label);
    }
    let (d, t) = (px as i32, px);
    // Enough labels on a log axis that every decade in view, and the values between, are
    // named.
    if options.log_x {
        mesh.x_labels(16).x_label_formatter(&log_label);
    }
    if options.log_y {
        mesh.y_labels(16).y_label_formatter(&log_label);
    }
    mesh.x_desc(options.x_label.as_str())
        .y_desc(options.y_label.as_str())
        .label_style((FONT_FAMILY, 14 * t))
        .axis_desc_style((FONT_FAMILY, 16 * t))
        .set_all_tick_mark_size(5 * t)
        .axis_style(BLACK.stroke_width(t))
        .bold_line_style(BLACK.mix(0.2).stroke_width(t))
        .light_line_style(RGBColor(235, 235, 235).stroke_width(t))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, s) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let marker = k % 3;
        let has_line = matches!(s.style, SeriesStyle::Line | SeriesStyle::LinePoints);
        let has_markers = matches!(s.style, SeriesStyle::Points | SeriesStyle::LinePoints);
        if has_line {
            // Earlier series are drawn wider, so a later curve on top of one (the MSM's
            // total energy on the D-NURBS') leaves it visible on both sides.
            let wide = if k + 1 < series.len() { 4 } else { 2 };
            let style = color.stroke_width(wide * t);
            let anno = if px > 1 {
                // At raster scale a thick line is filled as a polygon whose cost grows with its
                // bounding box times its vertex count: short overlapping pieces of the path
                // (one shared point between pieces) fill the same pixels far faster.
                let n = s.points.len();
                let pieces = (0..n.saturating_sub(1)).step_by(RASTER_PIECE).map(|i| {
                    PathElement::new(s.points[i..n.min(i + RASTER_PIECE + 1)].to_vec(), style)
                });
                chart.draw_series(pieces)
            } else {
                chart.draw_series(LineSeries::new(s.points.iter().copied(), style))
            }
            .map_err(|e| e.to_string())?;
            anno.label(s.name.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20 * d, y)], color.stroke_width(2 * t))
            });
        }
        if has_markers {
            let pts = s.points.iter().copied();
            let label = if has_line { "" } else { s.name.as_str() };
            match marker {
                0 => {
                    let anno = chart
                        .draw_series(pts.map(|p| Circle::new(p, 4 * t, color.filled())))
                        .map_err(|e| e.to_string())?;
                    if !has_line {
                        anno.label(label).legend(move |(x, y)| {
                            Circle::new((x + 10 * d, y), 4 * t, color.filled())
                        });
                    }
                }
                1 => {
                    let anno = chart
                        .draw_series(pts.map(|p| Cross::new(p, 5 * t, color.stroke_width(2 * t))))
                        .map_err(|e| e.to_string())?;
                    if !has_line {
                        anno.label(label).legend(move |(x, y)| {
                            Cross::new((x + 10 * d, y), 5 * t, color.stroke_width(2 * t))
                        });
                    }
                }
                _ => {
                    let anno = chart
                        .draw_series(pts.map(|p| TriangleMarker::new(p, 5 * t, color.filled())))
                        .map_err(|e| e.to_string())?;
                    if !has_line {
                        anno.label(label).legend(move |(x, y)| {
                            TriangleMarker::new((x + 10 * d, y), 5 * t, color.filled())
                        });
                    }
                }
            }
        }
    }
    if !series.is_empty() {
        chart
            .configure_series_labels()
            .label_font((FONT_FAMILY, 14 * t))
            .legend_area_size(30 * t)
            .margin(5 * t)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.stroke_width(t))
            .position(match legend_place(series, options) {
                // `draw` left room above the data for the legend.
                (_, covered, _) if covered > 0 => SeriesLabelPosition::UpperRight,
                (corner, _, _) => corner,
            })
            .draw()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_labels_only_at_whole_numbers() {
        assert_eq!(integer_label(&3.0), "3");
        assert_eq!(integer_label(&-0.0), "0");
        assert_eq!(integer_label(&(0.1 + 0.2 + 2.7)), "3");
        assert_eq!(integer_label(&2.5), "");
        assert_eq!(integer_label(&17.25), "");
    }

    #[test]
    fn box_downsample_averages_blocks() {
        // 2 × 1 pixels from a 4 × 2 image at k = 2: a white and a black block, then a mixed one.
        let mut big = vec![0u8; 4 * 2 * 3];
        for (i, px) in big.chunks_mut(3).enumerate() {
            let (x, y) = (i % 4, i / 4);
            let v = match (x, y) {
                (0 | 1, _) => 255,
                (2, 0) => 255,
                _ => 0,
            };
            px.copy_from_slice(&[v, v, v]);
        }
        let small = box_downsample(&big, 2, 1, 2);
        // (255·4)/4 = 255 and (255 + 0 + 0 + 0)/4 = 63.75 → 64.
        assert_eq!(small, vec![255, 255, 255, 64, 64, 64]);
    }
}
