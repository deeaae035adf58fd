//! SVG and PNG output with `plotters`.
//!
//! [`draw_packing`] paints a [`Packing2d`]: a white background, every piece
//! (body or periodic image, clipped to the box) filled by size with a thin
//! black outline, rattlers in light grey with a dashed grey outline, and the
//! box outline on top. Pictures have `y` pointing up and carry no text, so
//! PNG needs no font. [`draw_shapes`] paints shape panels (titles, axes,
//! legends), as SVG or PNG; their text uses the bundled font.

use crate::DrawError;
use crate::colors::{EDGE, RATTLER_EDGE, RATTLER_FILL, Rgb, size_key};
use crate::packing::Packing2d;
use crate::shapes::ShapePanel;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Outline points per body.
pub const POINTS_PER_BODY: usize = 200;
/// Default length in pixels of the longer side of a packing picture.
pub const DEFAULT_SIZE: u32 = 800;
/// Default side in pixels of one shape panel.
pub const DEFAULT_PANEL_SIZE: u32 = 360;
/// Smallest accepted `--size`.
pub const MIN_SIZE: u32 = 64;
/// Largest accepted `--size`.
pub const MAX_SIZE: u32 = 16384;

/// An output format, chosen by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.svg`: vector graphics.
    Svg,
    /// `.png`: a bitmap, without text.
    Png,
}

impl Format {
    /// The format of `path` from its extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, DrawError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(DrawError::Format {
                path: path.to_path_buf(),
                message: "the output must end in .svg or .png".into(),
            }),
        }
    }
}

/// The style of the `k`-th curve of a shape panel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveStyle {
    /// Line colour.
    pub color: Rgb,
    /// `None`: solid; `Some((dash, gap))` in pixels.
    pub dash: Option<(u32, u32)>,
}

/// Curve styles in order (cycled): black solid, red dotted, blue dashed
/// (the paper's Fig. 2 for `Δ = 0, 0.1, 0.3`), then green, purple, orange.
pub const CURVE_STYLES: [CurveStyle; 6] = [
    CurveStyle {
        color: (0, 0, 0),
        dash: None,
    },
    CurveStyle {
        color: (220, 30, 30),
        dash: Some((2, 4)),
    },
    CurveStyle {
        color: (30, 70, 220),
        dash: Some((10, 6)),
    },
    CurveStyle {
        color: (0, 150, 60),
        dash: None,
    },
    CurveStyle {
        color: (150, 50, 170),
        dash: Some((6, 3)),
    },
    CurveStyle {
        color: (230, 120, 0),
        dash: Some((2, 4)),
    },
];

pub(crate) fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

pub(crate) fn check_size(size: u32) -> Result<(), DrawError> {
    if (MIN_SIZE..=MAX_SIZE).contains(&size) {
        Ok(())
    } else {
        Err(DrawError::Size(size))
    }
}

/// The picture `path` can be written where the user asked: its directory
/// exists (it is not created). Checked before anything is drawn, so that a
/// missing directory is named, by the user's path, instead of surfacing as
/// the plotting library's error after the drawing.
pub(crate) fn check_output(path: &Path) -> Result<(), DrawError> {
    let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) else {
        return Ok(());
    };
    let problem = if !dir.exists() {
        format!(
            "the directory {} does not exist (create it first)",
            dir.display()
        )
    } else if !dir.is_dir() {
        format!("{} is not a directory", dir.display())
    } else {
        return Ok(());
    };
    Err(DrawError::Io {
        path: path.to_path_buf(),
        error: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("cannot write the picture: {problem}"),
        ),
    })
}

pub(crate) fn render_error(path: &Path, e: impl std::fmt::Display) -> DrawError {
    DrawError::Render {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Pixel layout of a packing picture: the box fills the picture but for a
/// margin, `y` up, and a strip underneath for the colour key.
pub(crate) struct Canvas {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) margin: f64,
    pub(crate) scale: f64,
    /// Height of the key strip.
    pub(crate) key: u32,
}

impl Canvas {
    pub(crate) fn new(box_edges: [f64; 2], size: u32) -> Self {
        let margin = (size as f64 / 50.0).round().max(4.0);
        let scale = (size as f64 - 2.0 * margin) / box_edges[0].max(box_edges[1]);
        let side = |l: f64| ((l * scale).round() + 2.0 * margin).max(1.0) as u32;
        let key = (size as f64 / 16.0).round().max(14.0) as u32;
        Self {
            width: side(box_edges[0]),
            height: side(box_edges[1]) + key,
            margin,
            scale,
            key,
        }
    }

    pub(crate) fn px(&self, p: [f64; 2]) -> (i32, i32) {
        (
            (self.margin + p[0] * self.scale).round() as i32,
            (self.height as f64 - self.key as f64 - self.margin - p[1] * self.scale).round() as i32,
        )
    }
}

/// The colour key under a packing: a swatch and its size per fill colour,
/// and the rattlers' swatch (dashed edge) when there are rattlers.
pub(crate) fn paint_key<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    sizes: &[f64],
    rattlers: usize,
    canvas: &Canvas,
    line: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let mut entries: Vec<(Rgb, bool, String)> = size_key(sizes)
        .into_iter()
        .map(|(c, label)| (c, false, label))
        .collect();
    if rattlers > 0 {
        entries.push((RATTLER_FILL, true, format!("rattler ({rattlers})")));
    }
    let k = canvas.key as f64;
    let side = (0.5 * k).round() as i32;
    let y = canvas.height as i32 - (0.5 * k).round() as i32 - (canvas.margin * 0.5) as i32;
    let font = ("sans-serif", (0.5 * k).round().max(8.0))
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let mut x = canvas.margin as i32;
    for (fill, dashed, label) in entries {
        let corners = [(x, y - side / 2), (x + side, y + side / 2)];
        root.draw(&Rectangle::new(corners, rgb(fill).filled()))?;
        let (x1, y1, x2, y2) = (x, y - side / 2, x + side, y + side / 2);
        let edge = vec![(x1, y1), (x2, y1), (x2, y2), (x1, y2), (x1, y1)];
        if dashed {
            let dash = 2 * line;
            root.draw(&DashedPathElement::new(
                edge,
                dash,
                dash,
                rgb(RATTLER_EDGE).stroke_width(line),
            ))?;
        } else {
            root.draw(&PathElement::new(edge, rgb(EDGE).stroke_width(line)))?;
        }
        let at = x + side + side / 2;
        let (w, _) = root.estimate_text_size(&label, &font)?;
        root.draw(&Text::new(label, (at, y), font.clone()))?;
        x = at + w as i32 + side;
    }
    Ok(())
}

fn paint_packing<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    packing: &Packing2d,
    canvas: &Canvas,
    size: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    crate::fonts::register();
    root.fill(&WHITE)?;
    let line = ((size as f64 / 800.0).round() as u32).max(1);
    let dash = 4 * line;
    let colors = packing.size_colors();
    for piece in packing.pieces(POINTS_PER_BODY) {
        let body = &packing.bodies[piece.body];
        let mut pts: Vec<(i32, i32)> = piece.points.iter().map(|&p| canvas.px(p)).collect();
        let fill = if body.rattler {
            RATTLER_FILL
        } else {
            colors[piece.body]
        };
        root.draw(&Polygon::new(pts.clone(), rgb(fill).filled()))?;
        pts.push(pts[0]);
        if body.rattler {
            root.draw(&DashedPathElement::new(
                pts,
                dash,
                dash,
                rgb(RATTLER_EDGE).stroke_width(line),
            ))?;
        } else {
            root.draw(&PathElement::new(pts, rgb(EDGE).stroke_width(line)))?;
        }
    }
    let [l1, l2] = packing.box_edges;
    root.draw(&Rectangle::new(
        [canvas.px([0.0, l2]), canvas.px([l1, 0.0])],
        rgb(EDGE).stroke_width(2 * line),
    ))?;
    let sizes: Vec<f64> = packing.bodies.iter().map(|b| b.size).collect();
    let rattlers = packing.bodies.iter().filter(|b| b.rattler).count();
    paint_key(root, &sizes, rattlers, canvas, line)
}

/// The SVG text of a packing picture whose longer side is `size` pixels.
pub fn packing_svg(packing: &Packing2d, size: u32) -> Result<String, DrawError> {
    check_size(size)?;
    let canvas = Canvas::new(packing.box_edges, size);
    let mut text = String::new();
    {
        let root =
            SVGBackend::with_string(&mut text, (canvas.width, canvas.height)).into_drawing_area();
        paint_packing(&root, packing, &canvas, size).map_err(|e| render_error(Path::new(""), e))?;
        root.present().map_err(|e| render_error(Path::new(""), e))?;
    }
    Ok(text)
}

/// Draw a packing to `path` (`.svg` or `.png`, see [`Format`]); the longer
/// side of the picture is `size` pixels.
pub fn draw_packing(packing: &Packing2d, path: &Path, size: u32) -> Result<(), DrawError> {
    let format = Format::from_path(path)?;
    check_output(path)?;
    match format {
        Format::Svg => write_file(path, packing_svg(packing, size)?.as_bytes()),
        Format::Png => {
            check_size(size)?;
            let canvas = Canvas::new(packing.box_edges, size);
            let root = BitMapBackend::new(path, (canvas.width, canvas.height)).into_drawing_area();
            paint_packing(&root, packing, &canvas, size).map_err(|e| render_error(path, e))?;
            root.present().map_err(|e| render_error(path, e))
        }
    }
}

pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), DrawError> {
    std::fs::write(path, bytes).map_err(|error| DrawError::Io {
        path: path.to_path_buf(),
        error,
    })
}

/// Round `x` up to a multiple of `0.1`.
fn ceil_tenth(x: f64) -> f64 {
    (x * 10.0 - 1e-9).ceil() / 10.0
}

fn paint_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &ShapePanel,
    side: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let s = side as f64;
    let font = |k: f64| ("sans-serif", (s * k).round().max(8.0));
    let area = area.titled(&panel.title, font(0.055))?;
    let (margin, x_area, y_area) = ((s * 0.03) as u32, (s * 0.11) as u32, (s * 0.13) as u32);
    // Equal scales on both axes: extend the range of the longer side.
    let (w, h) = area.dim_in_pixel();
    let plot_w = (w as f64 - (2 * margin + y_area) as f64).max(1.0);
    let plot_h = (h as f64 - (2 * margin + x_area) as f64).max(1.0);
    let reach = panel
        .curves
        .iter()
        .flat_map(|c| c.points.iter())
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(1.0, f64::max);
    let lim = ceil_tenth(1.12 * reach);
    let (xl, yl) = if plot_w >= plot_h {
        (lim * plot_w / plot_h, lim)
    } else {
        (lim, lim * plot_h / plot_w)
    };
    let mut chart = ChartBuilder::on(&area)
        .margin(margin)
        .x_label_area_size(x_area)
        .y_label_area_size(y_area)
        .build_cartesian_2d(-xl..xl, -yl..yl)?;
    chart
        .configure_mesh()
        .x_labels(5)
        .y_labels(5)
        .light_line_style(WHITE)
        .bold_line_style(RGBColor(225, 225, 225))
        .x_desc("x / R⁰")
        .y_desc("y / R⁰")
        .label_style(font(0.04))
        .axis_desc_style(font(0.045))
        .x_label_formatter(&|v| format!("{v:.1}"))
        .y_label_formatter(&|v| format!("{v:.1}"))
        .draw()?;
    let width = ((s / 180.0).round() as u32).max(1);
    for (k, curve) in panel.curves.iter().enumerate() {
        let st = CURVE_STYLES[k % CURVE_STYLES.len()];
        let style = rgb(st.color).stroke_width(width);
        let pts = curve.points.iter().map(|p| (p[0], p[1]));
        match st.dash {
            None => chart.draw_series(LineSeries::new(pts, style))?,
            Some((d, g)) => chart.draw_series(DashedLineSeries::new(pts, d, g, style))?,
        };
    }
    Ok(())
}

/// The shared legend under the panels: one sample line and label per curve.
fn paint_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    labels: &[&str],
    side: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let s = side as f64;
    let (w, h) = area.dim_in_pixel();
    let (line, gap) = ((s * 0.1) as i32, (s * 0.025) as i32);
    let entry = (s * 0.42).min(w as f64 / labels.len().max(1) as f64) as i32;
    let width = ((s / 180.0).round() as u32).max(1);
    let font = ("sans-serif", (s * 0.045).round().max(8.0))
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let y = h as i32 / 2;
    let mut x = (w as i32 - entry * labels.len() as i32).max(0) / 2;
    for (k, label) in labels.iter().enumerate() {
        let st = CURVE_STYLES[k % CURVE_STYLES.len()];
        let (d, g) = st.dash.unwrap_or((line as u32, 0));
        area.draw(&DashedPathElement::new(
            vec![(x, y), (x + line, y)],
            d,
            g,
            rgb(st.color).stroke_width(width),
        ))?;
        area.draw(&Text::new(
            label.to_string(),
            (x + line + gap, y),
            font.clone(),
        ))?;
        x += entry;
    }
    Ok(())
}

/// The size in pixels of a picture of `panels`: at most four panels to a
/// row, `panel_size` square each, and a legend strip underneath.
fn shapes_size(panels: &[ShapePanel], panel_size: u32) -> (u32, u32, usize, usize) {
    let cols = panels.len().clamp(1, 4);
    let rows = panels.len().div_ceil(cols).max(1);
    let width = cols as u32 * panel_size;
    let height = rows as u32 * panel_size + panel_size / 8;
    (width, height, rows, cols)
}

/// Paint shape panels and their legend (the curve labels of the first
/// panel) on `root`.
fn paint_shapes<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[ShapePanel],
    panel_size: u32,
    path: &Path,
) -> Result<(), DrawError> {
    let (_, _, rows, cols) = shapes_size(panels, panel_size);
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| render_error(path, e);
    root.fill(&WHITE).map_err(err)?;
    let (grid, legend) = root.split_vertically(rows as u32 * panel_size);
    for (area, panel) in grid.split_evenly((rows, cols)).iter().zip(panels) {
        paint_panel(area, panel, panel_size).map_err(err)?;
    }
    if let Some(first) = panels.first() {
        let labels: Vec<&str> = first.curves.iter().map(|c| c.label.as_str()).collect();
        paint_legend(&legend, &labels, panel_size).map_err(err)?;
    }
    root.present().map_err(err)
}

/// The SVG text of shape panels, `panel_size` pixels square each, at most
/// four to a row, with one legend (the curve labels of the first panel)
/// underneath.
pub fn shapes_svg(panels: &[ShapePanel], panel_size: u32) -> Result<String, DrawError> {
    // Titles and legends are measured (and, in PNG, drawn) with the
    // bundled font.
    crate::fonts::register();
    check_size(panel_size)?;
    let (width, height, _, _) = shapes_size(panels, panel_size);
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (width, height)).into_drawing_area();
        paint_shapes(&root, panels, panel_size, Path::new(""))?;
    }
    Ok(text)
}

/// Draw shape panels to `path` (`.svg` or `.png`; text in PNG uses the
/// bundled DejaVu Sans).
pub fn draw_shapes(panels: &[ShapePanel], path: &Path, panel_size: u32) -> Result<(), DrawError> {
    let format = Format::from_path(path)?;
    check_output(path)?;
    match format {
        Format::Svg => write_file(path, shapes_svg(panels, panel_size)?.as_bytes()),
        Format::Png => {
            crate::fonts::register();
            check_size(panel_size)?;
            let (width, height, _, _) = shapes_size(panels, panel_size);
            let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
            paint_shapes(&root, panels, panel_size, path)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packing::tests::three_disks;
    use crate::shapes::tests::fourier_panels;

    #[test]
    fn a_small_packing_gives_one_filled_polygon_per_piece() {
        let p = Packing2d::from_file(&three_disks()).unwrap();
        let svg = packing_svg(&p, 400).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        // 1 + 2 + 4 pieces (see packing::tests), one <polygon> each.
        assert_eq!(svg.matches("<polygon").count(), 7);
        // Solid outlines of the 3 non-rattler pieces, dashes for the rattler.
        assert!(svg.matches("<polyline").count() > 3);
        // Both sizes and the rattler grey appear as fills.
        for c in [crate::colors::SMALL, crate::colors::LARGE, RATTLER_FILL] {
            let hex = format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
            assert!(svg.contains(&hex), "{hex} missing");
        }
        // The colour key: each size and the rattlers, with their fills.
        for label in ["R⁰ = 0.5", "R⁰ = 0.7", "rattler (1)"] {
            assert!(svg.contains(label), "{label} missing from the key");
        }
        assert_eq!(svg.matches("<text").count(), 3);
    }

    #[test]
    fn png_and_svg_files_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let p = Packing2d::from_file(&three_disks()).unwrap();
        for name in ["a.svg", "a.png", "b.PNG"] {
            let path = dir.path().join(name);
            draw_packing(&p, &path, 200).unwrap();
            assert!(std::fs::metadata(&path).unwrap().len() > 100, "{name}");
        }
        let png = std::fs::read(dir.path().join("a.png")).unwrap();
        assert_eq!(&png[..4], b"\x89PNG");
        let e = draw_packing(&p, &dir.path().join("a.jpg"), 200).unwrap_err();
        assert!(e.to_string().contains(".svg or .png"), "{e}");
        let e = draw_packing(&p, &dir.path().join("a.svg"), 3).unwrap_err();
        assert!(e.to_string().contains("--size = 3"), "{e}");
    }

    #[test]
    fn shape_panels_have_titles_curves_and_legends() {
        let panels = fourier_panels(&[2, 3], &[0.0, 0.1, 0.3]);
        let svg = shapes_svg(&panels, 300).unwrap();
        assert!(svg.contains("n = 2") && svg.contains("n = 3"));
        assert!(svg.contains("Δ = 0.3") && svg.contains("x / R⁰"));
        // The red dotted curve is drawn as many short dashes.
        assert!(svg.matches("#DC1E1E").count() > 50);
        let dir = tempfile::tempdir().unwrap();
        draw_shapes(&panels, &dir.path().join("s.png"), 300).unwrap();
        let png = std::fs::read(dir.path().join("s.png")).unwrap();
        assert_eq!(&png[..4], b"\x89PNG");
        draw_shapes(&panels, &dir.path().join("s.svg"), 300).unwrap();
    }
}
