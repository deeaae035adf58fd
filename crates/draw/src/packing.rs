//! A 2D packing file as bodies with outlines, ready to draw.
//!
//! [`Packing2d::from_file`] reads what `jamkit run` writes
//! (`packings/<id>.json`, see `docs/reference/output-files.md`): `dim`, `box`, `family`,
//! `params`, `positions`, `radii`, `orientations` and `rattler`. Every
//! inconsistency (lengths, non-finite numbers, missing orientations of a
//! near-disk) is an error naming the file's key, never a panic.

use crate::DrawError;
use crate::colors::{Rgb, size_colors};
use crate::geometry::{Outline, Point, periodic_pieces};
use jamkit_format::PackingFile;
use std::path::Path;

/// Read a packing file (any dimension) from disk.
pub fn read_file(path: &Path) -> Result<PackingFile, DrawError> {
    let text = std::fs::read(path).map_err(|error| DrawError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    serde_json::from_slice(&text).map_err(|e| DrawError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// One body: centre (wrapped into the box), size `R⁰`, orientation `θ`.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Centre, in `[0, L₁) × [0, L₂)`.
    pub center: Point,
    /// Size `R⁰` (the radius of a disk).
    pub size: f64,
    /// Orientation `θ` (0 for disks).
    pub theta: f64,
    /// Whether the body is a rattler (false when the file has no flags).
    pub rattler: bool,
    /// For bodies made of spheres: each sphere's centre relative to the
    /// body's centre and its radius (from the file's `spheres` rows).
    pub spheres: Vec<(Point, f64)>,
}

/// A piece of a body to draw: the body itself or one of its periodic
/// images, clipped to the box.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Index of the body.
    pub body: usize,
    /// The shift of this image (`[0, 0]` for the body itself).
    pub shift: Point,
    /// The clipped outline, counter-clockwise, not closed.
    pub points: Vec<Point>,
}

impl Piece {
    /// Whether this piece is a periodic image rather than the body itself.
    pub fn is_image(&self) -> bool {
        self.shift != [0.0, 0.0]
    }
}

/// A two-dimensional packing: the box, the family's outline and the bodies.
#[derive(Clone, Debug)]
pub struct Packing2d {
    /// The packing's id (from the file).
    pub id: String,
    /// The family name.
    pub family: String,
    /// Box edges `L₁, L₂`.
    pub box_edges: [f64; 2],
    /// The outline law of the family.
    pub outline: Outline,
    /// The bodies, in file order.
    pub bodies: Vec<Body>,
}

impl Packing2d {
    /// Read a packing file from disk.
    pub fn load(path: &Path) -> Result<Self, DrawError> {
        Self::from_file(&read_file(path)?)
    }

    /// Check a packing record and turn it into bodies.
    pub fn from_file(file: &PackingFile) -> Result<Self, DrawError> {
        if file.dim != 2 {
            return Err(DrawError::Dimension(file.dim));
        }
        let outline = Outline::from_family(&file.family, &file.params)?;
        let bad = |what: String| DrawError::Inconsistent(format!("packing {}: {what}", file.id));
        let needs_angles = outline.turns();
        // A Δ = 0 near-disk (α = 1 ellipse) is jammed as a disk and stores
        // no angles: its outline does not turn.
        let (box_edges, centers) = configuration::<2>(file, needs_angles.then_some("one angle"))?;
        let n = centers.len();
        let mut bodies = Vec::with_capacity(n);
        for (i, &center) in centers.iter().enumerate() {
            let size = file.radii[i];
            let theta = match file.orientations.get(i) {
                Some(o) if needs_angles => match o.first() {
                    Some(&t) if t.is_finite() => t,
                    _ => {
                        return Err(bad(format!(
                            "orientations[{i}] = {o:?}: must start with a finite angle"
                        )));
                    }
                },
                _ => 0.0,
            };
            bodies.push(Body {
                center,
                size,
                theta,
                rattler: file.rattler.get(i).copied().unwrap_or(false),
                spheres: Vec::new(),
            });
        }
        for (k, row) in file.spheres.iter().enumerate() {
            match sphere_row::<2>(row, n) {
                Some(([x, y], r, i)) => {
                    // Rows are written as the wrapped centre plus the offset.
                    let (px, py) = (file.positions[i][0], file.positions[i][1]);
                    bodies[i].spheres.push(([x - px, y - py], r));
                }
                None => {
                    return Err(bad(format!(
                        "spheres[{k}] = {row:?}: must be [x, y, radius > 0, body index < {n}]"
                    )));
                }
            }
        }
        Ok(Self {
            id: file.id.clone(),
            family: file.family.clone(),
            box_edges,
            outline,
            bodies,
        })
    }

    /// The outline of body `i` on `m` points, unwrapped (it may cross the
    /// box edges).
    pub fn outline_of(&self, i: usize, m: usize) -> Vec<Point> {
        let b = &self.bodies[i];
        self.outline.body_points(b.center, b.size, b.theta, m)
    }

    /// The polygons that draw body `i` (one, except for a body made of
    /// spheres whose union is not star-shaped about its centre; see
    /// [`union_outlines`](crate::geometry::union_outlines)).
    pub fn polygons_of(&self, i: usize, m: usize) -> Vec<Vec<Point>> {
        let b = &self.bodies[i];
        if b.spheres.is_empty() {
            return vec![self.outline_of(i, m)];
        }
        let disks: Vec<(Point, f64)> = b
            .spheres
            .iter()
            .map(|&(o, r)| ([b.center[0] + o[0], b.center[1] + o[1]], r))
            .collect();
        crate::geometry::union_outlines(b.center, &disks, m)
    }

    /// Every piece to draw, body by body: each body's outline on `m`
    /// points and its periodic images, clipped to the box.
    pub fn pieces(&self, m: usize) -> Vec<Piece> {
        (0..self.bodies.len())
            .flat_map(|i| {
                self.polygons_of(i, m).into_iter().flat_map(move |poly| {
                    periodic_pieces(&poly, self.box_edges).into_iter().map(
                        move |(shift, points)| Piece {
                            body: i,
                            shift,
                            points,
                        },
                    )
                })
            })
            .collect()
    }

    /// The fill colour of each body by size (see [`crate::colors`]);
    /// rattlers are coloured separately by the renderer.
    pub fn size_colors(&self) -> Vec<Rgb> {
        size_colors(&self.bodies.iter().map(|b| b.size).collect::<Vec<_>>())
    }
}

/// The box edges of a packing file that holds a configuration (`D`
/// positive, finite edges) and its bodies' centres wrapped into the box,
/// checked: as many radii and rattler flags (or none) as positions, every
/// position `D` finite numbers and every radius positive and finite. What
/// drawing needs of every file, in 2D and 3D; each error names the key and
/// the index. With `orientation = Some(what)` (a family whose bodies turn,
/// `what` naming one body's orientation) every body must have one.
pub(crate) fn configuration<const D: usize>(
    file: &PackingFile,
    orientation: Option<&str>,
) -> Result<([f64; D], Vec<[f64; D]>), DrawError> {
    let bad = |what: String| DrawError::Inconsistent(format!("packing {}: {what}", file.id));
    let box_edges: [f64; D] = match <[f64; D]>::try_from(&file.box_edges[..]) {
        Ok(edges) if edges.iter().all(|l| *l > 0.0 && l.is_finite()) => edges,
        _ => {
            return Err(bad(format!(
                "box = {:?}: must hold {D} positive edge lengths",
                file.box_edges
            )));
        }
    };
    let n = file.positions.len();
    if n == 0 {
        return Err(bad(
            "positions = []: the file holds no configuration (it was run with output.packings = false)"
                .into(),
        ));
    }
    if file.radii.len() != n {
        return Err(bad(format!(
            "radii has {} entries for {n} positions",
            file.radii.len()
        )));
    }
    if !(file.rattler.is_empty() || file.rattler.len() == n) {
        return Err(bad(format!(
            "rattler has {} entries for {n} positions",
            file.rattler.len()
        )));
    }
    if let Some(what) = orientation
        && file.orientations.len() != n
    {
        return Err(bad(format!(
            "orientations has {} entries for {n} positions (family `{}` needs {what} per body)",
            file.orientations.len(),
            file.family
        )));
    }
    let mut centers = Vec::with_capacity(n);
    for (i, (position, &size)) in file.positions.iter().zip(&file.radii).enumerate() {
        match <[f64; D]>::try_from(&position[..]) {
            Ok(r) if r.iter().all(|x| x.is_finite()) => {
                centers.push(std::array::from_fn(|a| r[a].rem_euclid(box_edges[a])));
            }
            _ => {
                return Err(bad(format!(
                    "positions[{i}] = {position:?}: must be {D} finite numbers"
                )));
            }
        }
        if !(size > 0.0 && size.is_finite()) {
            return Err(bad(format!(
                "radii[{i}] = {size}: must be positive and finite"
            )));
        }
    }
    Ok((box_edges, centers))
}

/// A row `[x_1 … x_D, radius, body]` of a packing file's `spheres`: the
/// centre, the radius and the body's index; `None` unless the row has
/// `D + 2` numbers, the centre is finite, the radius positive and finite,
/// and the index a whole number below `n` (2D here, 3D in
/// [`crate::scene3d`]).
pub(crate) fn sphere_row<const D: usize>(row: &[f64], n: usize) -> Option<([f64; D], f64, usize)> {
    if row.len() != D + 2 {
        return None;
    }
    let (x, r, b) = (&row[..D], row[D], row[D + 1]);
    let valid = x.iter().all(|v| v.is_finite())
        && r > 0.0
        && r.is_finite()
        && b >= 0.0
        && b.fract() == 0.0
        && (b as usize) < n;
    valid.then(|| (std::array::from_fn(|a| x[a]), r, b as usize))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A packing record with the given content and placeholder metadata.
    pub(crate) fn record(
        family: &str,
        params: serde_json::Value,
        box_edges: [f64; 2],
        positions: Vec<[f64; 2]>,
        radii: Vec<f64>,
        orientations: Vec<Vec<f64>>,
        rattler: Vec<bool>,
    ) -> PackingFile {
        serde_json::from_value(serde_json::json!({
            "id": "test", "experiment": "test", "family": family, "params": params,
            "dim": 2, "particles": positions.len(), "seed": 1, "protocol": "jam",
            "settings": {}, "phi": 0.8, "energy_per_particle": 0.0,
            "measures": {
                "phi": 0.8, "energy_per_particle": 0.0, "n_contacts": null,
                "n_rattlers": null, "z_j": null, "iso_margin": null, "pressure": null,
                "fire_steps": 0, "minimizations": 0, "wall_s": 0.0, "flag": ""
            },
            "box": box_edges, "positions": positions, "radii": radii,
            "orientations": orientations, "rattler": rattler
        }))
        .unwrap()
    }

    /// Three disks in a 4 × 4 box: one inside, one across the left edge,
    /// one on the bottom-right corner (a rattler).
    pub(crate) fn three_disks() -> PackingFile {
        record(
            "sphere",
            serde_json::json!({}),
            [4.0, 4.0],
            vec![[2.0, 2.0], [0.2, 2.0], [3.9, 0.1]],
            vec![0.5, 0.7, 0.5],
            vec![],
            vec![false, false, true],
        )
    }

    #[test]
    fn pieces_include_the_images_of_bodies_across_edges() {
        let p = Packing2d::from_file(&three_disks()).unwrap();
        let pieces = p.pieces(100);
        let count = |i: usize| pieces.iter().filter(|q| q.body == i).count();
        assert_eq!((count(0), count(1), count(2)), (1, 2, 4));
        assert_eq!(pieces.iter().filter(|q| q.is_image()).count(), 4);
        assert!(p.bodies[2].rattler && !p.bodies[0].rattler);
    }

    #[test]
    fn near_disks_take_their_angle_from_the_orientations() {
        let f = record(
            "fourier",
            serde_json::json!({"n": 3, "delta": 0.2, "inertia": null}),
            [4.0, 4.0],
            vec![[1.0, 1.0], [3.0, 3.0]],
            vec![0.5, 0.5],
            vec![vec![0.3], vec![-1.0]],
            vec![],
        );
        let p = Packing2d::from_file(&f).unwrap();
        assert_eq!(p.bodies[0].theta, 0.3);
        assert_eq!(p.bodies[1].theta, -1.0);
        assert!(!p.bodies[1].rattler);
    }

    #[test]
    fn bad_files_are_errors() {
        let mut f = three_disks();
        f.dim = 3;
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(e.to_string().contains("dim = 3"), "{e}");

        let mut f = three_disks();
        f.family = "dimer".into();
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(e.to_string().contains("family `dimer`"), "{e}");

        let mut f = three_disks();
        f.radii.pop();
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(e.to_string().contains("radii has 2 entries"), "{e}");

        let mut f = three_disks();
        f.positions.clear();
        f.radii.clear();
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(e.to_string().contains("output.packings"), "{e}");

        let mut f = three_disks();
        f.family = "fourier".into();
        f.params = serde_json::json!({"n": 2, "delta": 0.1});
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(
            e.to_string()
                .contains("orientations has 0 entries for 3 positions (family `fourier` needs one angle per body)"),
            "{e}"
        );
        // Δ = 0 near-disks are stored without angles and still drawable.
        f.params = serde_json::json!({"n": 2, "delta": 0.0});
        assert!(Packing2d::from_file(&f).is_ok());

        let mut f = three_disks();
        f.positions[1] = vec![f64::NAN, 1.0];
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(e.to_string().contains("positions[1]"), "{e}");
    }

    /// Two 2D dimers of the `nmer` family, drawn from their `spheres` rows:
    /// an α = 1.5 dimer (overlapping disks, one polygon whose area is the
    /// exact union area to the discretisation error ~(2π/m)², below 1e-4 at
    /// m = 400) and an α = 3 dimer (disjoint disks: one polygon each). A
    /// malformed row is refused with its key named.
    #[test]
    fn dimers_are_drawn_from_their_spheres() {
        let mut f = record(
            "nmer",
            serde_json::json!({"alpha": 1.5}),
            [10.0, 10.0],
            vec![[3.0, 3.0], [7.0, 7.0]],
            vec![0.5, 0.5],
            vec![vec![0.0], vec![0.0]],
            vec![false, false],
        );
        f.spheres = vec![
            vec![2.75, 3.0, 0.5, 0.0],
            vec![3.25, 3.0, 0.5, 0.0],
            vec![6.0, 7.0, 0.5, 1.0],
            vec![8.0, 7.0, 0.5, 1.0],
        ];
        let p = Packing2d::from_file(&f).unwrap();
        assert!(matches!(p.outline, Outline::Spheres));
        let first = p.polygons_of(0, 400);
        assert_eq!(first.len(), 1);
        // Two unit-radius-0.5 disks at distance 0.5: 2πr² minus the lens.
        let (r, d) = (0.5f64, 0.5f64);
        let lens = 2.0 * r * r * (d / (2.0 * r)).acos() - 0.5 * d * (4.0 * r * r - d * d).sqrt();
        let exact = 2.0 * std::f64::consts::PI * r * r - lens;
        let area = crate::geometry::polygon_area(&first[0]);
        assert!((area - exact).abs() < 1e-4 * exact, "{area} vs {exact}");
        assert_eq!(p.polygons_of(1, 100).len(), 2);
        assert_eq!(p.pieces(100).len(), 3);
        f.spheres[1][3] = 5.0;
        let e = Packing2d::from_file(&f).unwrap_err();
        assert!(e.to_string().contains("spheres[1]"), "{e}");
    }
}
