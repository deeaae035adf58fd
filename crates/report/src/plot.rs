//! One kind of figure: markers with error bars and guide lines, on linear
//! or logarithmic axes, written as SVG and PNG.
//!
//! Logarithmic axes are drawn in `log₁₀` coordinates with ticks labelled
//! as powers of ten, which keeps one code path for every combination of
//! axes. Text needs a font (to draw it in PNG, to measure it in both):
//! `jamkit_draw::fonts` registers the bundled DejaVu Sans.

use crate::ReportError;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::path::Path;

/// A series of points `(x, y, error of y)` (error 0 or NaN: none). A
/// point whose `y` is not finite (or not positive on a log axis) breaks a
/// line there.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text (empty: not in the legend).
    pub label: String,
    /// Points.
    pub points: Vec<(f64, f64, f64)>,
    /// Join the points with a line (and draw no markers).
    pub line: bool,
}

/// A guide: the straight line `y = a x^b` (on log–log axes), or any curve
/// given by points, drawn dashed.
#[derive(Clone, Debug)]
pub struct Guide {
    /// Legend text (empty: not in the legend).
    pub label: String,
    /// Points of the curve (two suffice for a power law).
    pub points: Vec<(f64, f64)>,
    /// Draw it in the colour of this series (a fit to that series'
    /// points); `None`: a colour of its own.
    pub series: Option<usize>,
}

impl Guide {
    /// `y = a x^b` between `x0` and `x1`.
    pub fn power_law(label: impl Into<String>, a: f64, b: f64, x0: f64, x1: f64) -> Self {
        Self {
            label: label.into(),
            points: vec![(x0, a * x0.powf(b)), (x1, a * x1.powf(b))],
            series: None,
        }
    }

    /// The same guide in the colour of series `k` (the series it fits).
    pub fn fitting(mut self, k: usize) -> Self {
        self.series = Some(k);
        self
    }

    /// `y ∝ x^b` through the point `at`, between `x0` and `x1`.
    pub fn power_law_through(
        label: impl Into<String>,
        b: f64,
        at: (f64, f64),
        x0: f64,
        x1: f64,
    ) -> Self {
        Self::power_law(label, at.1 / at.0.powf(b), b, x0, x1)
    }
}

/// A whole figure.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Title above the plot.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Data.
    pub series: Vec<Series>,
    /// Dashed guides.
    pub guides: Vec<Guide>,
    /// Corner of the legend (where the data leave room).
    pub legend: SeriesLabelPosition,
}

const WIDTH: u32 = 720;
const HEIGHT: u32 = 540;

const COLORS: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(23, 190, 207),
];

impl Figure {
    /// Write `<stem>.svg` and `<stem>.png`. A figure with no finite point
    /// is an error (nothing to show).
    pub fn write(&self, stem: &Path) -> Result<(), ReportError> {
        let (x, y) = self
            .ranges()
            .ok_or_else(|| ReportError::Empty(self.title.clone()))?;
        // Both backends measure text with the registered font.
        jamkit_draw::fonts::register();
        let svg = stem.with_extension("svg");
        self.draw(
            SVGBackend::new(&svg, (WIDTH, HEIGHT)).into_drawing_area(),
            x,
            y,
        )
        .map_err(|e| ReportError::Plot(format!("{}: {e}", svg.display())))?;
        let png = stem.with_extension("png");
        self.draw(
            BitMapBackend::new(&png, (WIDTH, HEIGHT)).into_drawing_area(),
            x,
            y,
        )
        .map_err(|e| ReportError::Plot(format!("{}: {e}", png.display())))?;
        Ok(())
    }

    fn tx(&self, x: f64) -> Option<f64> {
        transform(x, self.log_x)
    }

    fn ty(&self, y: f64) -> Option<f64> {
        transform(y, self.log_y)
    }

    /// Axis ranges in drawing coordinates, with a 5 % margin.
    fn ranges(&self) -> Option<((f64, f64), (f64, f64))> {
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for s in &self.series {
            for &(x, y, e) in &s.points {
                if let (Some(x), Some(y)) = (self.tx(x), self.ty(y)) {
                    xs.push(x);
                    ys.push(y);
                    // The error bars are part of the data: keep them inside.
                    if e > 0.0 {
                        ys.extend(self.ty(y + e));
                        ys.extend(self.ty(y - e));
                    }
                }
            }
        }
        if xs.is_empty() {
            return None;
        }
        let span = |v: &[f64]| {
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            let pad = if hi > lo { 0.05 * (hi - lo) } else { 0.5 };
            (lo - pad, hi + pad)
        };
        Some((span(&xs), span(&ys)))
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> Result<(), Box<dyn std::error::Error + '_>>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        // A linear axis whose data are all whole numbers (seeds, n) is
        // labelled at whole numbers only.
        let whole = |log: bool, y: bool| {
            !log && self.series.iter().all(|s| {
                s.points.iter().all(|p| {
                    let v = if y { p.1 } else { p.0 };
                    !v.is_finite() || (v == v.round() && v.abs() < 1e9)
                })
            })
        };
        let label = |log: bool, span: f64, whole: bool| {
            move |v: &f64| {
                if log {
                    log_label(*v, span)
                } else {
                    linear_label(*v, span, whole)
                }
            }
        };
        let (fx, fy) = (
            label(self.log_x, x1 - x0, whole(self.log_x, false)),
            label(self.log_y, y1 - y0, whole(self.log_y, true)),
        );
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .axis_desc_style(("sans-serif", 18))
            .label_style(("sans-serif", 14))
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        for (k, s) in self.series.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter_map(|&(x, y, _)| Some((self.tx(x)?, self.ty(y)?)))
                .collect();
            let anno = if s.line {
                // One polyline per run of drawable points.
                let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
                for &(x, y, _) in &s.points {
                    match (self.tx(x), self.ty(y)) {
                        (Some(x), Some(y)) => runs.last_mut().expect("one run").push((x, y)),
                        _ => runs.push(Vec::new()),
                    }
                }
                // A run of one point (a bin between empty ones) is a dot.
                let dots: Vec<(f64, f64)> =
                    runs.iter().filter(|r| r.len() == 1).map(|r| r[0]).collect();
                chart.draw_series(dots.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
                chart.draw_series(
                    runs.into_iter()
                        .filter(|r| r.len() > 1)
                        .map(|r| PathElement::new(r, color.stroke_width(2))),
                )?
            } else {
                chart.draw_series(
                    pts.iter()
                        .map(|&(x, y)| Circle::new((x, y), 4, color.filled())),
                )?
            };
            anno.label(s.label.clone()).legend(move |(x, y)| {
                Rectangle::new([(x, y - 4), (x + 12, y + 4)], color.filled())
            });
            // Error bars: y ± err, in drawing coordinates.
            let bars = s.points.iter().filter_map(|&(x, y, e)| {
                if !(e > 0.0) {
                    return None;
                }
                let x = self.tx(x)?;
                let lo = self.ty(y - e).unwrap_or(y0);
                let hi = self.ty(y + e)?;
                Some(PathElement::new(
                    vec![(x, lo.max(y0)), (x, hi.min(y1))],
                    color.stroke_width(1),
                ))
            });
            chart.draw_series(bars)?;
        }
        for (k, g) in self.guides.iter().enumerate() {
            let color = COLORS[g.series.unwrap_or(k + 1) % COLORS.len()].mix(0.7);
            let pts: Vec<(f64, f64)> = g
                .points
                .iter()
                .filter_map(|&(x, y)| Some((self.tx(x)?, self.ty(y)?)))
                .collect();
            let pts = clip_line(&pts, (x0, x1), (y0, y1));
            // Liang–Barsky leaves the ends on the box (up to round-off).
            if pts.len() < 2 {
                continue;
            }
            let drawn = chart.draw_series(std::iter::once(DashedPathElement::new(
                pts,
                8,
                6,
                color.stroke_width(2),
            )))?;
            // A guide without a label stays out of the legend.
            if !g.label.is_empty() {
                drawn
                    .label(g.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 12, y)], color));
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(self.legend.clone())
            .draw()?;
        root.present()?;
        Ok(())
    }
}

/// `log₁₀ v` on a log axis, `v` on a linear one; `None` where undefined.
fn transform(v: f64, log: bool) -> Option<f64> {
    match (log, v.is_finite()) {
        (_, false) => None,
        (true, _) if v > 0.0 => Some(v.log10()),
        (true, _) => None,
        (false, _) => Some(v),
    }
}

/// A tick label for `log₁₀ v = e`: `10^e` for whole `e`, else the value.
fn power_of_ten(e: f64) -> String {
    if (e - e.round()).abs() < 1e-9 {
        let k = e.round() as i64;
        match k {
            0 => "1".into(),
            1 => "10".into(),
            _ => format!("1e{k}"),
        }
    } else {
        format!("{:.1e}", 10f64.powf(e))
    }
}

/// A tick label at `log₁₀ v = e` on a log axis spanning `span` decades:
/// over two decades or more only whole decades are labelled (the other
/// ticks keep their grid lines), below that every tick.
fn log_label(e: f64, span: f64) -> String {
    if span >= 2.0 && (e - e.round()).abs() >= 1e-9 {
        String::new()
    } else {
        power_of_ten(e)
    }
}

/// A tick label on a linear axis spanning `span`: as many decimals as
/// tell ticks about a tenth of the span apart from each other, trailing
/// zeros dropped; on an axis of whole numbers, only whole ticks are
/// labelled.
fn linear_label(v: f64, span: f64, whole: bool) -> String {
    if whole {
        let r = v.round();
        return if (v - r).abs() <= 1e-9 * span.max(1.0) {
            format!("{r:.0}")
        } else {
            String::new()
        };
    }
    let decimals = if span > 0.0 && span.is_finite() {
        (1.0 - (span / 10.0).log10().floor()).clamp(0.0, 15.0) as usize
    } else {
        3
    };
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" { "0".into() } else { s }
}

/// The part of the straight segments through `pts` inside the box (guides
/// are straight lines in drawing coordinates, so two end points suffice).
fn clip_line(pts: &[(f64, f64)], (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> Vec<(f64, f64)> {
    if pts.len() != 2 {
        return pts.to_vec();
    }
    let ((ax, ay), (bx, by)) = (pts[0], pts[1]);
    // Liang–Barsky: parameter t ∈ [0, 1] along a → b.
    let (dx, dy) = (bx - ax, by - ay);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, ax - x0), (dx, x1 - ax), (-dy, ay - y0), (dy, y1 - ay)] {
        if p == 0.0 {
            if q < 0.0 {
                return Vec::new();
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
    if t0 > t1 {
        return Vec::new();
    }
    vec![(ax + t0 * dx, ay + t0 * dy), (ax + t1 * dx, ay + t1 * dy)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_powers_of_ten() {
        assert_eq!(power_of_ten(-3.0), "1e-3");
        assert_eq!(power_of_ten(0.0), "1");
        assert_eq!(power_of_ten(-0.5), "3.2e-1");
        // Half decades are labelled on a short log axis only.
        assert_eq!(log_label(-0.5, 1.5), "3.2e-1");
        assert_eq!(log_label(-0.5, 4.0), "");
        assert_eq!(log_label(-2.0, 4.0), "1e-2");
    }

    #[test]
    fn linear_tick_labels_resolve_the_span() {
        // A span of 1e-4 around 5.984 needs 5 decimals to tell ticks apart.
        assert_eq!(linear_label(5.98412, 1e-4, false), "5.98412");
        assert_eq!(linear_label(5.98413, 1e-4, false), "5.98413");
        assert_eq!(linear_label(1.5, 1.0, false), "1.5");
        assert_eq!(linear_label(1.0, 1.0, false), "1");
        assert_eq!(linear_label(-0.0001, 1.0, false), "0");
        // Whole-number axes (seeds): half-way ticks carry no label.
        assert_eq!(linear_label(2.0, 3.0, true), "2");
        assert_eq!(linear_label(2.5, 3.0, true), "");
    }

    #[test]
    fn error_bars_are_inside_the_ranges() {
        let f = Figure {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: false,
            log_y: false,
            series: vec![Series {
                label: "s".into(),
                points: vec![(1.0, 5.0, 0.5), (2.0, 5.001, 0.0)],
                line: false,
            }],
            guides: vec![],
            legend: SeriesLabelPosition::UpperLeft,
        };
        let (_, (y0, y1)) = f.ranges().expect("points");
        assert!(y0 < 4.5 && y1 > 5.5, "{y0} {y1}");
    }

    #[test]
    fn guides_are_clipped_to_the_box() {
        let c = clip_line(&[(-1.0, -1.0), (3.0, 3.0)], (0.0, 2.0), (0.0, 1.0));
        assert_eq!(c, vec![(0.0, 0.0), (1.0, 1.0)]);
        assert!(clip_line(&[(5.0, 5.0), (6.0, 6.0)], (0.0, 1.0), (0.0, 1.0)).is_empty());
    }
}
