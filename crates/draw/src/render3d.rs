//! Pictures of 3D packings and bodies: the ray-cast of [`crate::scene3d`],
//! shaded, outlined and keyed, written as PNG or as SVG (the ray-cast
//! embedded as a PNG image, the box and the key as vector graphics).
//!
//! Shading: each body's fill by size (as in 2D: [`crate::colors`]), times
//! the Lambert factor of its surface normal ([`crate::scene3d::lambert`]);
//! a body cut by the box's top face shows its cut flat and paler (40 %
//! white); rattlers are light grey. A one-pixel line (black, dark grey
//! round rattlers) is drawn wherever neighbouring pixels see different
//! body images, so bodies stand apart as in the 2D pictures.

use crate::DrawError;
use crate::colors::{EDGE, RATTLER_EDGE, RATTLER_FILL, Rgb};
use crate::render::{Canvas, Format, check_size, paint_key, render_error, rgb, write_file};
use crate::scene3d::{Ball, Kind, P3, Packing3d, Primitive, Raster, Solid, View, lambert, raycast};
use jamkit_registry::{self as registry};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Share of white mixed into the colour of a cut face.
const CUT_WHITE: f64 = 0.4;

fn scaled(c: Rgb, f: f64) -> Rgb {
    let s = |v: u8| (v as f64 * f).round().clamp(0.0, 255.0) as u8;
    (s(c.0), s(c.1), s(c.2))
}

fn whitened(c: Rgb, w: f64) -> Rgb {
    let s = |v: u8| {
        (v as f64 + w * (255.0 - v as f64))
            .round()
            .clamp(0.0, 255.0) as u8
    };
    (s(c.0), s(c.1), s(c.2))
}

/// The RGB bytes (row 0 at the top) of a ray-cast: `fill(body)` shaded,
/// cuts pale, white where nothing is seen, and a line between different
/// body images (`edge(body)` gives its colour).
pub fn shade(raster: &Raster, fill: impl Fn(usize) -> Rgb, edge: impl Fn(usize) -> Rgb) -> Vec<u8> {
    let (w, h) = (raster.width, raster.height);
    let mut out = Vec::with_capacity(3 * w * h);
    for row in 0..h {
        for col in 0..w {
            let here = raster.at(col, row);
            let id = |c: usize, r: usize| raster.at(c, r).map(|s| s.image);
            let mine = here.map(|s| s.image);
            let border = (col + 1 < w && id(col + 1, row) != mine)
                || (row + 1 < h && id(col, row + 1) != mine);
            let c = if border {
                let who = here.or_else(|| {
                    raster
                        .at((col + 1).min(w - 1), row)
                        .or_else(|| raster.at(col, (row + 1).min(h - 1)))
                });
                who.map_or(EDGE, |s| edge(s.body))
            } else {
                match here {
                    None => (255, 255, 255),
                    Some(s) if s.hit.cut => {
                        scaled(whitened(fill(s.body), CUT_WHITE), lambert(s.hit.normal))
                    }
                    Some(s) => scaled(fill(s.body), lambert(s.hit.normal)),
                }
            };
            out.extend_from_slice(&[c.0, c.1, c.2]);
        }
    }
    out
}

/// PNG bytes of an RGB buffer.
pub fn encode_png(width: usize, height: usize, rgb: &[u8]) -> Result<Vec<u8>, DrawError> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width as u32, height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let err = |e: png::EncodingError| render_error(Path::new(""), e);
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(rgb).map_err(err)?;
    }
    Ok(bytes)
}

fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Insert an `<image>` of `png` at `(x, y)` right after the opening tag of
/// an SVG document, under everything plotters drew.
fn embed_png(svg: &str, png: &[u8], (x, y): (i32, i32), (w, h): (usize, usize)) -> String {
    let open = svg
        .find("<svg")
        .map_or(0, |k| k + svg[k..].find('>').map_or(0, |e| e + 1));
    format!(
        "{}\n<image x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\" image-rendering=\"pixelated\" href=\"data:image/png;base64,{}\"/>{}",
        &svg[..open],
        base64(png),
        &svg[open..]
    )
}

/// A 3D packing, ray-cast and shaded at the scale of a picture whose
/// longer box side spans `size` pixels less the margins.
pub struct Picture3d {
    canvas: Canvas,
    raster: Raster,
    rgb: Vec<u8>,
}

/// Ray-cast and shade a 3D packing for a picture of longer side `size`.
pub fn picture_3d(packing: &Packing3d, view: View, size: u32) -> Result<Picture3d, DrawError> {
    check_size(size)?;
    let [l1, l2, _] = packing.box_edges;
    let canvas = Canvas::new([l1, l2], size);
    let raster = raycast(
        &packing.primitives(view),
        packing.box_edges,
        view,
        canvas.scale,
    );
    let colors = packing.size_colors();
    let fill = |i: usize| {
        if packing.bodies[i].rattler {
            RATTLER_FILL
        } else {
            colors[i]
        }
    };
    let edge = |i: usize| {
        if packing.bodies[i].rattler {
            RATTLER_EDGE
        } else {
            EDGE
        }
    };
    let rgb = shade(&raster, fill, edge);
    Ok(Picture3d {
        canvas,
        raster,
        rgb,
    })
}

impl Picture3d {
    /// The ray-cast behind the picture.
    pub fn raster(&self) -> &Raster {
        &self.raster
    }
}

fn paint_frame<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    packing: &Packing3d,
    pic: &Picture3d,
    size: u32,
    pixels: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    crate::fonts::register();
    let canvas = &pic.canvas;
    if pixels {
        root.fill(&WHITE)?;
        let (x0, y0) = canvas.px([0.0, packing.box_edges[1]]);
        let w = pic.raster.width;
        for (k, c) in pic.rgb.chunks(3).enumerate() {
            let (col, row) = ((k % w) as i32, (k / w) as i32);
            root.draw_pixel((x0 + col, y0 + row), &RGBColor(c[0], c[1], c[2]))?;
        }
    }
    let line = ((size as f64 / 800.0).round() as u32).max(1);
    let [l1, l2, _] = packing.box_edges;
    root.draw(&Rectangle::new(
        [canvas.px([0.0, l2]), canvas.px([l1, 0.0])],
        rgb(EDGE).stroke_width(2 * line),
    ))?;
    let sizes: Vec<f64> = packing.bodies.iter().map(|b| b.size).collect();
    let rattlers = packing.bodies.iter().filter(|b| b.rattler).count();
    paint_key(root, &sizes, rattlers, canvas, line)
}

/// The SVG text of a 3D packing picture: the ray-cast as an embedded PNG
/// image, the box outline and the colour key as vector graphics.
pub fn packing_3d_svg(packing: &Packing3d, view: View, size: u32) -> Result<String, DrawError> {
    let pic = picture_3d(packing, view, size)?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (pic.canvas.width, pic.canvas.height))
            .into_drawing_area();
        paint_frame(&root, packing, &pic, size, false)
            .map_err(|e| render_error(Path::new(""), e))?;
        root.present().map_err(|e| render_error(Path::new(""), e))?;
    }
    let png = encode_png(pic.raster.width, pic.raster.height, &pic.rgb)?;
    let at = pic.canvas.px([0.0, packing.box_edges[1]]);
    let background = format!(
        "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#FFFFFF\"/>",
        pic.canvas.width, pic.canvas.height
    );
    let svg = embed_png(&text, &png, at, (pic.raster.width, pic.raster.height));
    // White under the picture (plotters' own fill would hide the image).
    let open = svg.find("<image").unwrap_or(0);
    Ok(format!("{}{background}\n{}", &svg[..open], &svg[open..]))
}

/// Draw a 3D packing seen as `view` to `path` (`.png` or `.svg`); the
/// longer side of the box spans `size` pixels, margins included.
pub fn draw_packing_3d(
    packing: &Packing3d,
    view: View,
    path: &Path,
    size: u32,
) -> Result<(), DrawError> {
    let format = Format::from_path(path)?;
    crate::render::check_output(path)?;
    match format {
        Format::Svg => write_file(path, packing_3d_svg(packing, view, size)?.as_bytes()),
        Format::Png => {
            let pic = picture_3d(packing, view, size)?;
            let root =
                BitMapBackend::new(path, (pic.canvas.width, pic.canvas.height)).into_drawing_area();
            paint_frame(&root, packing, &pic, size, true).map_err(|e| render_error(path, e))?;
            root.present().map_err(|e| render_error(path, e))
        }
    }
}

// ---------------------------------------------------------------------------
// draw-shape in 3D: one shaded body per parameter set.

/// Angle (degrees) by which `draw-shape` tilts a body's `z` axis towards
/// the viewer: the body is seen from 20° above its `x–y` plane.
pub const TILT_DEGREES: f64 = 20.0;

/// The rotation (rows) that shows a body with its `x` axis to the right
/// and its `z` axis up, tilted by [`TILT_DEGREES`] towards the viewer.
pub fn view_rotation() -> [[f64; 3]; 3] {
    let a = TILT_DEGREES.to_radians();
    let (c, s) = (a.cos(), a.sin());
    // Columns: body x → (1, 0, 0), body y → (0, s, −c), body z → (0, c, s).
    [[1.0, 0.0, 0.0], [0.0, s, c], [0.0, -c, s]]
}

fn mat_vec(m: &[[f64; 3]; 3], v: P3) -> P3 {
    std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// One body of a `draw-shape` picture (size `R⁰ = 1`).
#[derive(Clone, Debug)]
pub struct ShapeBody {
    /// Caption, e.g. `Δ = 0.1`.
    pub label: String,
    /// The primitives, centred at the origin, body frame turned by
    /// [`view_rotation`].
    pub primitives: Vec<Primitive>,
}

/// One row of a `draw-shape` picture.
#[derive(Clone, Debug)]
pub struct BodyPanel {
    /// Row title, e.g. `l = 2`.
    pub title: String,
    /// The bodies.
    pub bodies: Vec<ShapeBody>,
}

/// The primitives of one body of size 1 of `family` with `params`, turned
/// by `rotation` (body to world), centred at the origin.
pub fn body_primitives(
    family: &str,
    params: &registry::ParamMap,
    rotation: [[f64; 3]; 3],
) -> Result<Vec<Primitive>, DrawError> {
    let prim = |center: P3, reach: f64, kind: Kind| Primitive {
        body: 0,
        shift: [0, 0, 0],
        center,
        reach,
        kind,
    };
    Ok(match Solid::of(family, params)? {
        Solid::Ball => vec![prim([0.0; 3], 1.0, Kind::Ball(1.0))],
        Solid::Star(surface) => {
            let reach = surface.relative_radius_bounds().1;
            vec![prim(
                [0.0; 3],
                reach,
                Kind::Star {
                    surface,
                    size: 1.0,
                    rotation,
                },
            )]
        }
        Solid::Spheres => Solid::reference_spheres(family, params)?
            .into_iter()
            .map(|Ball { center, radius }| {
                prim(mat_vec(&rotation, center), radius, Kind::Ball(radius))
            })
            .collect(),
    })
}

/// The bodies of a 3D `draw-shape`: one row per parameter set of
/// `panels`, one body per set of `curves`, parameters merged as in 2D
/// ([`crate::shapes::panels`]).
pub fn body_panels(
    family: &str,
    panels: &[registry::ParamMap],
    curves: &[registry::ParamMap],
) -> Result<Vec<BodyPanel>, DrawError> {
    let merged = crate::shapes::merged_params(family, panels, curves)?;
    merged
        .into_iter()
        .map(|(title, row)| {
            let bodies = row
                .into_iter()
                .map(|(label, params, own)| {
                    // The example fills in what the user's sets leave out;
                    // where they clash with it (`l` given against the
                    // example's `modes`), the user's sets alone are used.
                    let primitives =
                        body_primitives(family, &params, view_rotation()).or_else(|e| {
                            body_primitives(family, &own, view_rotation()).map_err(|_| e)
                        })?;
                    Ok(ShapeBody { label, primitives })
                })
                .collect::<Result<Vec<_>, DrawError>>()?;
            Ok(BodyPanel { title, bodies })
        })
        .collect()
}

/// Ray-cast one body in a cube of half side `half`, at `scale` pixels per
/// unit, its centre at the cube's centre.
pub fn body_raster(body: &ShapeBody, half: f64, scale: f64) -> Raster {
    let shifted: Vec<Primitive> = body
        .primitives
        .iter()
        .map(|p| Primitive {
            center: [p.center[0] + half, p.center[1] + half, p.center[2] + half],
            ..p.clone()
        })
        .collect();
    raycast(&shifted, [2.0 * half; 3], View::Whole, scale)
}

fn body_reach(body: &ShapeBody) -> f64 {
    body.primitives
        .iter()
        .map(|p| (p.center[0].powi(2) + p.center[1].powi(2) + p.center[2].powi(2)).sqrt() + p.reach)
        .fold(1.0, f64::max)
}

fn paint_bodies<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[BodyPanel],
    cell: u32,
    images: &mut Vec<((i32, i32), usize, Vec<u8>)>,
    pixels: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    crate::fonts::register();
    if pixels {
        root.fill(&WHITE)?;
    }
    let half = panels
        .iter()
        .flat_map(|p| p.bodies.iter())
        .map(body_reach)
        .fold(1.0, f64::max)
        * 1.05;
    let c = cell as f64;
    let title_h = (0.12 * c).round() as i32;
    let side = (c - title_h as f64 - 0.04 * c).max(8.0);
    let scale = side / (2.0 * half);
    let font = ("sans-serif", (0.055 * c).round().max(8.0))
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Center, VPos::Center));
    let width = ((c / 180.0).round() as u32).max(1);
    for (r, panel) in panels.iter().enumerate() {
        for (k, body) in panel.bodies.iter().enumerate() {
            let (x0, y0) = (k as i32 * cell as i32, r as i32 * cell as i32);
            let caption = if panel.title.is_empty() {
                body.label.clone()
            } else {
                format!("{}; {}", panel.title, body.label)
            };
            root.draw(&Text::new(
                caption,
                (x0 + cell as i32 / 2, y0 + title_h / 2),
                font.clone(),
            ))?;
            let raster = body_raster(body, half, scale);
            let px = shade(&raster, |_| crate::colors::MONO, |_| EDGE);
            let (ox, oy) = (
                x0 + ((c - raster.width as f64) / 2.0).round() as i32,
                y0 + title_h,
            );
            if pixels {
                for (q, v) in px.chunks(3).enumerate() {
                    let (col, row) = ((q % raster.width) as i32, (q / raster.width) as i32);
                    root.draw_pixel((ox + col, oy + row), &RGBColor(v[0], v[1], v[2]))?;
                }
            } else {
                images.push(((ox, oy), raster.width, px));
            }
            // The sphere of radius R⁰, for reference (dashed grey).
            let (cx, cy) = (
                ox as f64 + half * scale,
                oy as f64 + raster.height as f64 - half * scale,
            );
            let ring: Vec<(i32, i32)> = (0..=120)
                .map(|t| {
                    let a = std::f64::consts::TAU * t as f64 / 120.0;
                    (
                        (cx + scale * a.cos()).round() as i32,
                        (cy - scale * a.sin()).round() as i32,
                    )
                })
                .collect();
            root.draw(&DashedPathElement::new(
                ring,
                3 * width,
                3 * width,
                rgb((120, 120, 120)).stroke_width(width),
            ))?;
        }
    }
    Ok(())
}

fn bodies_size(panels: &[BodyPanel], cell: u32) -> (u32, u32) {
    let cols = panels
        .iter()
        .map(|p| p.bodies.len())
        .max()
        .unwrap_or(1)
        .max(1);
    (cols as u32 * cell, panels.len().max(1) as u32 * cell)
}

/// Draw 3D shape panels to `path` (`.png` or `.svg`): one row per panel,
/// one shaded body per curve, each `cell` pixels square, captioned, with
/// the sphere of radius `R⁰` dashed for reference.
pub fn draw_bodies(panels: &[BodyPanel], path: &Path, cell: u32) -> Result<(), DrawError> {
    let format = Format::from_path(path)?;
    crate::render::check_output(path)?;
    check_size(cell)?;
    let (w, h) = bodies_size(panels, cell);
    let err = |e: DrawingAreaErrorKind<_>| render_error(path, e);
    match format {
        Format::Png => {
            let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
            paint_bodies(&root, panels, cell, &mut Vec::new(), true)
                .map_err(|e| render_error(path, e))?;
            root.present().map_err(|e| render_error(path, e))
        }
        Format::Svg => {
            let mut text = String::new();
            let mut images = Vec::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                paint_bodies(&root, panels, cell, &mut images, false).map_err(err)?;
                root.present().map_err(err)?;
            }
            let mut svg = text;
            for (at, width, px) in images.iter().rev() {
                let height = px.len() / 3 / width;
                let png = encode_png(*width, height, px)?;
                svg = embed_png(&svg, &png, *at, (*width, height));
            }
            let open = svg.find("<image").unwrap_or(0);
            let background =
                format!("<rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" fill=\"#FFFFFF\"/>\n");
            write_file(
                path,
                format!("{}{background}{}", &svg[..open], &svg[open..]).as_bytes(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::parse_params;

    #[test]
    fn base64_is_the_standard_alphabet_with_padding() {
        assert_eq!(base64(b"Man"), "TWFu");
        assert_eq!(base64(b"Ma"), "TWE=");
        assert_eq!(base64(b"M"), "TQ==");
        assert_eq!(base64(b""), "");
        // PNG's magic number, as every embedded picture starts.
        assert_eq!(&base64(b"\x89PNG\r\n\x1a\n")[..11], "iVBORw0KGgo");
    }

    /// The view of `draw-shape` is a proper rotation that keeps the body's
    /// x axis along the picture's x and tilts its z axis 20° to the viewer.
    #[test]
    fn the_shape_view_is_a_rotation() {
        let m = view_rotation();
        for a in 0..3 {
            for b in 0..3 {
                let d: f64 = (0..3).map(|r| m[r][a] * m[r][b]).sum();
                assert!((d - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        assert!((det - 1.0).abs() < 1e-15);
        let z = mat_vec(&m, [0.0, 0.0, 1.0]);
        assert!((z[2] - 20f64.to_radians().sin()).abs() < 1e-15 && z[1] > 0.0);
    }

    /// `draw-shape harmonic`: one row per panel, one body per curve; the
    /// `Δ = 0` body (a ball, run as the sphere family) covers `π (s R⁰)²`
    /// pixels within 1 % (lattice-point error, see scene3d's tests); the
    /// `Δ = 0.3` `Ŷ_20` body, its axis tilted 20° towards the viewer,
    /// stands taller than wide. A family with no 3D bodies is refused.
    #[test]
    fn harmonic_bodies_are_drawn_one_per_delta() {
        let panel = parse_params("harmonic", "(l: 2)").unwrap();
        let curves: Vec<_> = ["(delta: 0.0)", "(delta: 0.3)"]
            .iter()
            .map(|c| parse_params("harmonic", c).unwrap())
            .collect();
        let panels = body_panels("harmonic", &[panel], &curves).unwrap();
        assert_eq!((panels.len(), panels[0].bodies.len()), (1, 2));
        assert_eq!(panels[0].bodies[1].label, "Δ = 0.3");
        let scale = 60.0;
        let ball = body_raster(&panels[0].bodies[0], 1.5, scale);
        let area = std::f64::consts::PI * scale * scale;
        let n = ball.count_body(0) as f64;
        assert!((n - area).abs() < 0.01 * area, "{n} vs {area}");
        let body = body_raster(&panels[0].bodies[1], 1.5, scale);
        let mid = body.width / 2;
        let wide = (0..body.width)
            .filter(|&c| body.at(c, mid).is_some())
            .count();
        let tall = (0..body.height)
            .filter(|&r| body.at(mid, r).is_some())
            .count();
        // Width 2 · 0.9 R⁰ = 108 px; height above 2 · 0.9 and below 2 · 1.2.
        assert!((wide as f64 - 108.0).abs() <= 2.0, "{wide}");
        assert!(tall as f64 > 118.0 && (tall as f64) < 144.0, "{tall}");
        let e = body_panels("fourier", &[], &[]).unwrap_err();
        assert!(e.to_string().contains("family `fourier`"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        for name in ["b.png", "b.svg"] {
            draw_bodies(&panels, &dir.path().join(name), 160).unwrap();
        }
        let svg = std::fs::read_to_string(dir.path().join("b.svg")).unwrap();
        assert_eq!(svg.matches("data:image/png;base64,iVBORw0KGgo").count(), 2);
        assert!(svg.contains("l = 2; Δ = 0.3"), "caption missing");
    }

    /// A small 3D packing to PNG and SVG: the SVG embeds the ray-cast as a
    /// PNG and carries the key as text; the PNG is a real PNG.
    #[test]
    fn a_3d_packing_is_written_as_png_and_svg() {
        let f: jamkit_format::PackingFile = serde_json::from_value(serde_json::json!({
            "id": "t", "experiment": "t", "family": "sphere", "params": {},
            "dim": 3, "particles": 2, "seed": 1, "protocol": "jam",
            "settings": {}, "phi": 0.6, "energy_per_particle": 0.0,
            "measures": {
                "phi": 0.6, "energy_per_particle": 0.0, "n_contacts": null,
                "n_rattlers": null, "z_j": null, "iso_margin": null, "pressure": null,
                "fire_steps": 0, "minimizations": 0, "wall_s": 0.0, "flag": ""
            },
            "box": [3.0, 3.0, 3.0], "positions": [[1.0, 1.0, 1.0], [2.9, 2.0, 2.0]],
            "radii": [0.5, 0.7], "orientations": [], "rattler": [false, true]
        }))
        .unwrap();
        let p = Packing3d::from_file(&f).unwrap();
        let svg = packing_3d_svg(&p, View::Whole, 300).unwrap();
        assert_eq!(svg.matches("<image").count(), 1);
        assert!(svg.contains("data:image/png;base64,iVBORw0KGgo"));
        for label in ["R⁰ = 0.5", "R⁰ = 0.7", "rattler (1)"] {
            assert!(svg.contains(label), "{label} missing from the key");
        }
        let dir = tempfile::tempdir().unwrap();
        draw_packing_3d(&p, View::Cut, &dir.path().join("p.png"), 200).unwrap();
        let png = std::fs::read(dir.path().join("p.png")).unwrap();
        assert_eq!(&png[..4], b"\x89PNG");
        let e = draw_packing_3d(&p, View::Whole, &dir.path().join("p.jpg"), 200).unwrap_err();
        assert!(e.to_string().contains(".svg or .png"), "{e}");
        let e = draw_packing_3d(&p, View::Whole, &dir.path().join("p.png"), 20).unwrap_err();
        assert!(e.to_string().contains("--size = 20"), "{e}");
        // The rattler is grey: its shaded pixels are grey (r = g = b).
        let pic = picture_3d(&p, View::Whole, 300).unwrap();
        let r = pic.raster();
        let k = (0..r.seen.len())
            .find(|&k| matches!(r.seen[k], Some(s) if s.body == 1))
            .unwrap();
        let k = k + 3 * r.width; // inside, away from the outline
        assert_eq!(r.seen[k].unwrap().body, 1);
        let px = &pic.rgb[3 * k..3 * k + 3];
        assert!(px[0] == px[1] && px[1] == px[2], "{px:?}");
    }
}
