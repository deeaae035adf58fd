//! A 3D packing file as bodies, and an orthographic ray-cast of its box.
//!
//! [`Packing3d::from_file`] reads what `jamkit run` writes for `dim = 3`.
//! A body is drawn from its family's shape through the registry, with no
//! family named here:
//!
//! * a ball ([`Look::ball`](jamkit_core::Look::ball)): radius `R⁰`;
//! * a star-shaped body with a [`Surface`](jamkit_core::Surface)
//!   ([`Shape::surface`](jamkit_core::Shape::surface)): the points
//!   `c + s M y`, `0 ≤ s ≤ R⁰ ρ(y)`, `M` the rotation of the file's
//!   `orientations[i]`;
//! * a body made of spheres
//!   ([`Shape::sphere_decomposition`](jamkit_core::Shape::sphere_decomposition)):
//!   the file's `spheres` rows (a body without rows is the ball of radius
//!   `R⁰`, as `nmer` with α = 1 runs).
//!
//! [`raycast`] looks at the periodic box `[0, L₁) × [0, L₂) × [0, L₃)`
//! along `−z` (the viewer above the top face `z = L₃`), in orthographic
//! projection: one ray per pixel centre, straight down. What it sees is the
//! content of the box: every body and every periodic image (shifts by
//! `±L` along each axis) cut to the box. A body that crosses the top face
//! shows its flat cut there ([`Hit::cut`]); one that crosses a side face
//! shows up on both sides.

use crate::DrawError;
use crate::colors::{Rgb, size_colors};
use jamkit_core::BodyOrientation;
use jamkit_core::{Shape, SharedSurface};
use jamkit_format::PackingFile;
use jamkit_registry::{self as registry, ParamMap, SceneVisitor};
use std::path::Path;

/// A point or vector of space.
pub type P3 = [f64; 3];

/// How the bodies of a 3D family are drawn.
#[derive(Clone, Debug)]
pub enum Solid {
    /// Balls of radius `R⁰`.
    Ball,
    /// Star-shaped bodies with a surface `ρ(y)`.
    Star(SharedSurface),
    /// Bodies made of spheres, from the file's `spheres` rows.
    Spheres,
}

/// The registry's visitor that asks a 3D shape how to draw it.
struct SolidOf;

impl SceneVisitor for SolidOf {
    type Output = Option<Solid>;

    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Option<Solid> {
        if D != 3 {
            return None;
        }
        let look = shape.look();
        if look.ball {
            return Some(Solid::Ball);
        }
        if let Some(s) = look.surface {
            return Some(Solid::Star(s));
        }
        let o = S::Orientation::reference();
        shape.sphere_decomposition(1.0, &o).map(|_| Solid::Spheres)
    }
}

impl Solid {
    /// How a registered 3D family is drawn, from its parameters as an
    /// experiment file gives them (defaults filled in).
    pub fn of(family: &str, params: &ParamMap) -> Result<Self, DrawError> {
        crate::drawing_of(family, 3, params, SolidOf)
    }

    /// As [`Solid::of`], from the parameters a packing file stores.
    pub fn from_family(family: &str, params: &serde_json::Value) -> Result<Self, DrawError> {
        crate::drawing_from_json(family, 3, params, SolidOf)
    }

    /// The sphere decomposition of a body of size 1 at the family's
    /// reference orientation (for `draw-shape`), if it is made of spheres.
    pub fn reference_spheres(family: &str, params: &ParamMap) -> Result<Vec<Ball>, DrawError> {
        struct Decompose;
        impl SceneVisitor for Decompose {
            type Output = Option<Vec<Ball>>;
            fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Option<Vec<Ball>> {
                let o = S::Orientation::reference();
                let d = shape.sphere_decomposition(1.0, &o)?;
                (D == 3).then(|| {
                    d.iter()
                        .map(|(c, r)| Ball {
                            center: [c[0], c[1], c[2]],
                            radius: *r,
                        })
                        .collect()
                })
            }
        }
        let info = registry::family_info(family).map_err(|e| DrawError::Params {
            family: family.into(),
            message: e.to_string(),
        })?;
        let params = registry::with_defaults(&info, params);
        registry::dispatch(family, 3, &params, Decompose)
            .map_err(|e| DrawError::Params {
                family: family.into(),
                message: e.to_string(),
            })?
            .ok_or_else(|| DrawError::UnknownFamily(family.to_string(), 3))
    }
}

/// A ball: centre (relative to its body's centre where it belongs to one)
/// and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    /// Centre.
    pub center: P3,
    /// Radius.
    pub radius: f64,
}

/// One body of a 3D packing.
#[derive(Clone, Debug, PartialEq)]
pub struct Body3d {
    /// Centre, wrapped into the box.
    pub center: P3,
    /// Size `R⁰`.
    pub size: f64,
    /// Rotation from body to world frame (rows); the identity for balls
    /// and bodies made of spheres.
    pub rotation: [[f64; 3]; 3],
    /// Whether the body is a rattler (false when the file has no flags).
    pub rattler: bool,
    /// For bodies made of spheres: each sphere's centre relative to the
    /// body's centre (world frame) and its radius.
    pub spheres: Vec<Ball>,
}

/// The identity rotation.
pub const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// What a 3D packing picture shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// Every body whose centre lies in the box, whole along `z`, seen from
    /// above; bodies crossing a side face (`x` or `y`) appear on both
    /// sides, cut at the box's sides. The default.
    #[default]
    Whole,
    /// The content of the periodic box: every body and periodic image
    /// (also along `z`) cut to `0 ≤ z ≤ L₃`; bodies crossing the top face
    /// show their flat cross-section there.
    Cut,
}

impl View {
    /// The heights between which a ray looks (`top` down to `floor`).
    pub fn z_range(self, box_edges: P3) -> (f64, f64) {
        match self {
            View::Whole => (f64::INFINITY, f64::NEG_INFINITY),
            View::Cut => (box_edges[2], 0.0),
        }
    }
}

/// A three-dimensional packing: the box, how its bodies are drawn, and
/// the bodies.
#[derive(Clone, Debug)]
pub struct Packing3d {
    /// The packing's id (from the file).
    pub id: String,
    /// The family name.
    pub family: String,
    /// Box edges `L₁, L₂, L₃`.
    pub box_edges: P3,
    /// How the family's bodies are drawn.
    pub solid: Solid,
    /// The bodies, in file order.
    pub bodies: Vec<Body3d>,
}

impl Packing3d {
    /// Read a packing file from disk.
    pub fn load(path: &Path) -> Result<Self, DrawError> {
        Self::from_file(&crate::packing::read_file(path)?)
    }

    /// Check a 3D packing record and turn it into bodies. Every
    /// inconsistency is an error naming the file's key, never a panic.
    pub fn from_file(file: &PackingFile) -> Result<Self, DrawError> {
        if file.dim != 3 {
            return Err(DrawError::Dimension(file.dim));
        }
        let solid = Solid::from_family(&file.family, &file.params)?;
        let bad = |what: String| DrawError::Inconsistent(format!("packing {}: {what}", file.id));
        let turns = matches!(solid, Solid::Star(_)).then_some("one orientation");
        let (box_edges, centers) = crate::packing::configuration::<3>(file, turns)?;
        let n = centers.len();
        let mut bodies = Vec::with_capacity(n);
        for (i, &center) in centers.iter().enumerate() {
            let size = file.radii[i];
            let rotation = match &solid {
                Solid::Star(s) => s.rotation(&file.orientations[i]).ok_or_else(|| {
                    bad(format!(
                        "orientations[{i}] = {:?}: not an orientation of family `{}` (a unit quaternion [w, x, y, z])",
                        file.orientations[i], file.family
                    ))
                })?,
                _ => IDENTITY,
            };
            bodies.push(Body3d {
                center,
                size,
                rotation,
                rattler: file.rattler.get(i).copied().unwrap_or(false),
                spheres: Vec::new(),
            });
        }
        for (k, row) in file.spheres.iter().enumerate() {
            match crate::packing::sphere_row::<3>(row, n) {
                Some(([x, y, z], r, i)) if matches!(solid, Solid::Spheres) => {
                    let p = &file.positions[i];
                    bodies[i].spheres.push(Ball {
                        center: [x - p[0], y - p[1], z - p[2]],
                        radius: r,
                    });
                }
                _ => {
                    return Err(bad(format!(
                        "spheres[{k}] = {row:?}: must be [x, y, z, radius > 0, body index < {n}] (and only for bodies made of spheres)"
                    )));
                }
            }
        }
        Ok(Self {
            id: file.id.clone(),
            family: file.family.clone(),
            box_edges,
            solid,
            bodies,
        })
    }

    /// The fill colour of each body by size (rattlers apart).
    pub fn size_colors(&self) -> Vec<Rgb> {
        size_colors(&self.bodies.iter().map(|b| b.size).collect::<Vec<_>>())
    }

    /// The primitives to ray-cast in `view`: every body (or each of its
    /// spheres) at every periodic shift whose bounding ball reaches into
    /// the box; shifts along `z` only in [`View::Cut`].
    pub fn primitives(&self, view: View) -> Vec<Primitive> {
        let l = self.box_edges;
        let mut out = Vec::new();
        for (i, b) in self.bodies.iter().enumerate() {
            let parts: Vec<(P3, Kind, f64)> = match &self.solid {
                Solid::Ball => vec![(b.center, Kind::Ball(b.size), b.size)],
                Solid::Spheres if b.spheres.is_empty() => {
                    vec![(b.center, Kind::Ball(b.size), b.size)]
                }
                Solid::Spheres => b
                    .spheres
                    .iter()
                    .map(|s| (add(b.center, s.center), Kind::Ball(s.radius), s.radius))
                    .collect(),
                Solid::Star(surface) => {
                    let reach = b.size * surface.relative_radius_bounds().1;
                    vec![(
                        b.center,
                        Kind::Star {
                            surface: surface.clone(),
                            size: b.size,
                            rotation: b.rotation,
                        },
                        reach,
                    )]
                }
            };
            for (center, kind, reach) in parts {
                let range = |a: usize| -> Vec<f64> {
                    [-1.0, 0.0, 1.0]
                        .into_iter()
                        .filter(|k| {
                            let c = center[a] + k * l[a];
                            c + reach > 0.0 && c - reach < l[a]
                        })
                        .collect()
                };
                let zs = match view {
                    View::Cut => range(2),
                    View::Whole => vec![0.0],
                };
                for &kx in &range(0) {
                    for &ky in &range(1) {
                        for &kz in &zs {
                            out.push(Primitive {
                                body: i,
                                shift: [kx as i8, ky as i8, kz as i8],
                                center: [
                                    center[0] + kx * l[0],
                                    center[1] + ky * l[1],
                                    center[2] + kz * l[2],
                                ],
                                reach,
                                kind: kind.clone(),
                            });
                        }
                    }
                }
            }
        }
        out
    }
}

fn add(a: P3, b: P3) -> P3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// What a primitive is.
#[derive(Clone, Debug)]
pub enum Kind {
    /// A ball of this radius.
    Ball(f64),
    /// A star-shaped body.
    Star {
        /// Its surface law.
        surface: SharedSurface,
        /// Its size `R⁰`.
        size: f64,
        /// Body to world rotation (rows).
        rotation: [[f64; 3]; 3],
    },
}

/// One thing to ray-cast: a ball or a star-shaped body, at one periodic
/// shift of its body.
#[derive(Clone, Debug)]
pub struct Primitive {
    /// Index of the body.
    pub body: usize,
    /// The periodic shift, in box edges (`[0, 0, 0]` for the body itself).
    pub shift: [i8; 3],
    /// World centre (shift included).
    pub center: P3,
    /// Radius of a ball about `center` that holds the primitive.
    pub reach: f64,
    /// What it is.
    pub kind: Kind,
}

/// Where a ray first meets a primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Height of the point met.
    pub z: f64,
    /// Outward unit normal there (`[0, 0, 1]` on a cut).
    pub normal: P3,
    /// Whether the point lies on the box's top face, where the body is cut.
    pub cut: bool,
}

/// Inside test of a star-shaped body at `x` relative to its centre.
fn star_inside(surface: &SharedSurface, size: f64, m: &[[f64; 3]; 3], x: P3) -> bool {
    star_level(surface, size, m, x) <= 0.0
}

/// `|x| − R⁰ ρ(Mᵀ x/|x|)`: negative inside.
fn star_level(surface: &SharedSurface, size: f64, m: &[[f64; 3]; 3], x: P3) -> f64 {
    let r = dot(x, x).sqrt();
    if r == 0.0 {
        return -size;
    }
    // Mᵀ x: the body-frame direction.
    let y = [
        (m[0][0] * x[0] + m[1][0] * x[1] + m[2][0] * x[2]) / r,
        (m[0][1] * x[0] + m[1][1] * x[1] + m[2][1] * x[2]) / r,
        (m[0][2] * x[0] + m[1][2] * x[1] + m[2][2] * x[2]) / r,
    ];
    r - size * surface.relative_radius(y)
}

/// Steps of the march down a star-shaped body's bounding ball.
const MARCH_STEPS: usize = 64;
/// Bisection steps that pin the surface once the march is inside.
const BISECTIONS: usize = 40;

impl Primitive {
    /// An id of the body image this primitive belongs to: the body and its
    /// shift.
    pub fn image_id(&self) -> u32 {
        let s = |a: usize| (self.shift[a] + 1) as u32;
        self.body as u32 * 27 + s(0) * 9 + s(1) * 3 + s(2)
    }

    /// The first point, coming down from the height `top` (the top face in
    /// [`View::Cut`], `+∞` in [`View::Whole`]) along the vertical ray
    /// through `(x, y)`, where the ray meets the primitive with
    /// `z ≥ floor`; `None` if it misses.
    pub fn hit(&self, x: f64, y: f64, top: f64, floor: f64) -> Option<Hit> {
        let (dx, dy) = (x - self.center[0], y - self.center[1]);
        let d2 = dx * dx + dy * dy;
        if d2 > self.reach * self.reach {
            return None;
        }
        let half = (self.reach * self.reach - d2).sqrt();
        let (hi, lo) = (self.center[2] + half, self.center[2] - half);
        if lo >= top || hi < floor {
            return None;
        }
        let cut = Hit {
            z: top,
            normal: [0.0, 0.0, 1.0],
            cut: true,
        };
        match &self.kind {
            Kind::Ball(r) => {
                // reach = r: [lo, hi] is the chord itself.
                debug_assert!(*r == self.reach);
                if hi > top {
                    Some(cut)
                } else {
                    Some(Hit {
                        z: hi,
                        normal: [dx / r, dy / r, half / r],
                        cut: false,
                    })
                }
            }
            Kind::Star {
                surface,
                size,
                rotation,
            } => {
                let rel = |z: f64| [dx, dy, z - self.center[2]];
                let start = hi.min(top);
                let end = lo.max(floor);
                if hi > top && star_inside(surface, *size, rotation, rel(top)) {
                    return Some(cut);
                }
                let step = (start - end) / MARCH_STEPS as f64;
                if step <= 0.0 {
                    return None;
                }
                let mut above = start;
                for k in 1..=MARCH_STEPS {
                    let z = start - step * k as f64;
                    if star_inside(surface, *size, rotation, rel(z)) {
                        let (mut out, mut inn) = (above, z);
                        for _ in 0..BISECTIONS {
                            let mid = 0.5 * (out + inn);
                            if star_inside(surface, *size, rotation, rel(mid)) {
                                inn = mid;
                            } else {
                                out = mid;
                            }
                        }
                        let p = rel(0.5 * (out + inn));
                        return Some(Hit {
                            z: 0.5 * (out + inn),
                            normal: star_normal(surface, *size, rotation, p),
                            cut: false,
                        });
                    }
                    above = z;
                }
                None
            }
        }
    }
}

/// The outward normal of a star-shaped body at `p` (relative to its
/// centre): the gradient of its level function, by central differences.
fn star_normal(surface: &SharedSurface, size: f64, m: &[[f64; 3]; 3], p: P3) -> P3 {
    let h = 1e-5 * size;
    let mut g = [0.0; 3];
    for (a, ga) in g.iter_mut().enumerate() {
        let (mut plus, mut minus) = (p, p);
        plus[a] += h;
        minus[a] -= h;
        *ga = star_level(surface, size, m, plus) - star_level(surface, size, m, minus);
    }
    let n = dot(g, g).sqrt();
    if n > 0.0 && n.is_finite() {
        [g[0] / n, g[1] / n, g[2] / n]
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// What one pixel sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    /// Index of the primitive's body.
    pub body: usize,
    /// Which image of it ([`Primitive::image_id`]: the spheres of one body
    /// image share it, different images do not).
    pub image: u32,
    /// The hit.
    pub hit: Hit,
}

/// The result of a ray-cast: one entry per pixel, row 0 at the top
/// (`y = L₂`), column 0 at the left (`x = 0`).
#[derive(Clone, Debug)]
pub struct Raster {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Pixels per unit length.
    pub scale: f64,
    /// What each pixel sees (`None`: nothing above the floor `z = 0`).
    pub seen: Vec<Option<Seen>>,
}

impl Raster {
    /// What pixel `(col, row)` sees.
    pub fn at(&self, col: usize, row: usize) -> Option<Seen> {
        self.seen[row * self.width + col]
    }

    /// Pixels that see body `i` (any image).
    pub fn count_body(&self, i: usize) -> usize {
        self.seen
            .iter()
            .filter(|s| matches!(s, Some(s) if s.body == i))
            .count()
    }
}

/// Ray-cast `primitives` over the box `box_edges` at `scale` pixels per
/// unit length: one vertical ray per pixel centre of `[0, L₁] × [0, L₂]`,
/// coming down through the heights of `view` ([`View::z_range`]); each
/// pixel keeps the highest point met. A 2D grid of
/// buckets (each holding the primitives whose bounding disk reaches it,
/// highest first) keeps the cost near one primitive per pixel.
pub fn raycast(primitives: &[Primitive], box_edges: P3, view: View, scale: f64) -> Raster {
    let width = (box_edges[0] * scale).round().max(1.0) as usize;
    let height = (box_edges[1] * scale).round().max(1.0) as usize;
    let (top, floor) = view.z_range(box_edges);
    let reach = primitives.iter().map(|p| p.reach).fold(0.0, f64::max);
    let cell = (2.0 * reach).max(box_edges[0].max(box_edges[1]) / 256.0);
    let nx = ((box_edges[0] / cell).ceil() as usize).max(1);
    let ny = ((box_edges[1] / cell).ceil() as usize).max(1);
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    let clamp = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
    for (k, p) in primitives.iter().enumerate() {
        let (x0, x1) = (
            clamp((p.center[0] - p.reach) / cell, nx),
            clamp((p.center[0] + p.reach) / cell, nx),
        );
        let (y0, y1) = (
            clamp((p.center[1] - p.reach) / cell, ny),
            clamp((p.center[1] + p.reach) / cell, ny),
        );
        for bx in x0..=x1 {
            for by in y0..=y1 {
                buckets[by * nx + bx].push(k as u32);
            }
        }
    }
    let high = |k: &u32| {
        let p = &primitives[*k as usize];
        p.center[2] + p.reach
    };
    for b in &mut buckets {
        b.sort_by(|a, c| high(c).total_cmp(&high(a)));
    }
    let mut seen = vec![None; width * height];
    for row in 0..height {
        let y = box_edges[1] - (row as f64 + 0.5) / scale;
        let by = clamp(y / cell, ny);
        for col in 0..width {
            let x = (col as f64 + 0.5) / scale;
            let bx = clamp(x / cell, nx);
            let mut best: Option<Seen> = None;
            for &k in &buckets[by * nx + bx] {
                let p = &primitives[k as usize];
                if let Some(b) = best
                    && p.center[2] + p.reach <= b.hit.z
                {
                    break;
                }
                if let Some(hit) = p.hit(x, y, top, floor)
                    && best.is_none_or(|b| hit.z > b.hit.z)
                {
                    best = Some(Seen {
                        body: p.body,
                        image: p.image_id(),
                        hit,
                    });
                }
            }
            seen[row * width + col] = best;
        }
    }
    Raster {
        width,
        height,
        scale,
        seen,
    }
}

/// The direction the light comes from (up-left, towards the viewer).
pub const LIGHT: P3 = [-0.4, 0.45, 0.8];

/// Lambert shading: the fraction of a surface's colour seen at a point of
/// normal `n` (`0.3` ambient plus `0.7 max(0, n·l)`).
pub fn lambert(n: P3) -> f64 {
    let l = LIGHT;
    let norm = dot(l, l).sqrt();
    0.3 + 0.7 * (dot(n, l) / norm).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3D packing record with placeholder metadata.
    pub(crate) fn record3(
        family: &str,
        params: serde_json::Value,
        box_edges: [f64; 3],
        positions: Vec<[f64; 3]>,
        radii: Vec<f64>,
        orientations: Vec<Vec<f64>>,
    ) -> PackingFile {
        let n = positions.len();
        serde_json::from_value(serde_json::json!({
            "id": "test", "experiment": "test", "family": family, "params": params,
            "dim": 3, "particles": n, "seed": 1, "protocol": "jam",
            "settings": {}, "phi": 0.6, "energy_per_particle": 0.0,
            "measures": {
                "phi": 0.6, "energy_per_particle": 0.0, "n_contacts": null,
                "n_rattlers": null, "z_j": null, "iso_margin": null, "pressure": null,
                "fire_steps": 0, "minimizations": 0, "wall_s": 0.0, "flag": ""
            },
            "box": box_edges, "positions": positions, "radii": radii,
            "orientations": orientations, "rattler": vec![false; n]
        }))
        .unwrap()
    }

    fn cast(p: &Packing3d, view: View, scale: f64) -> Raster {
        raycast(&p.primitives(view), p.box_edges, view, scale)
    }

    /// A ball of radius 1 at the centre of a 4³ box, at 50 pixels per unit:
    /// its picture is a disk of radius 50 px. The pixels whose centre lies
    /// in it number `π 50² = 7854` up to the lattice-point error of a circle
    /// (rigorously below the `√2`-pixel-wide ring round it, 444 px = 5.7 %;
    /// in practice of order `r^{2/3}` ≈ 14 px), so 1 % is a real test of
    /// the scale and of the centre. The height met at a pixel is the
    /// sphere's, `z = 2 + √(1 − ρ²)`, to rounding.
    #[test]
    fn a_ball_covers_the_disk_of_its_radius() {
        let f = record3(
            "sphere",
            serde_json::json!({}),
            [4.0; 3],
            vec![[2.0; 3]],
            vec![1.0],
            vec![],
        );
        let p = Packing3d::from_file(&f).unwrap();
        let r = cast(&p, View::Whole, 50.0);
        assert_eq!((r.width, r.height), (200, 200));
        let area = std::f64::consts::PI * 50.0 * 50.0;
        let count = r.count_body(0) as f64;
        assert!(
            (count - area).abs() < 0.01 * area,
            "{count} pixels vs {area}"
        );
        let s = r.at(120, 90).unwrap();
        let (x, y): (f64, f64) = (120.5 / 50.0 - 2.0, 2.0 - 90.5 / 50.0);
        let z = 2.0 + (1.0 - x * x - y * y).sqrt();
        assert!(
            (s.hit.z - z).abs() < 1e-12 && !s.hit.cut,
            "{:?} vs {z}",
            s.hit
        );
        // The corners of the box see nothing.
        assert!(r.at(0, 0).is_none() && r.at(199, 199).is_none());
    }

    /// A ball across the face x = 0 is seen on both sides of the box, and
    /// the two pieces make up its whole disk (same 1 % as above); in the
    /// `Cut` view a ball across the floor shows its image's flat cut on the
    /// top face (the image at z + L₃ crosses it), in the `Whole` view its
    /// own top.
    #[test]
    fn a_ball_across_a_face_appears_on_both_sides() {
        let f = record3(
            "sphere",
            serde_json::json!({}),
            [4.0; 3],
            vec![[0.2, 2.0, 0.1]],
            vec![0.5],
            vec![],
        );
        let p = Packing3d::from_file(&f).unwrap();
        let r = cast(&p, View::Whole, 50.0);
        let row = 100; // y = 1.99
        let left = (0..r.width)
            .filter(|&c| c < 100 && r.at(c, row).is_some())
            .count();
        let right = (0..r.width)
            .filter(|&c| c >= 100 && r.at(c, row).is_some())
            .count();
        // Chord at |y − 2| = 0.01: x ∈ 0.2 ± 0.4999 → 35 px left of 0.7,
        // 15 px right of 3.7 (4 − 0.2999).
        assert!(
            (left as i64 - 35).abs() <= 1 && (right as i64 - 15).abs() <= 1,
            "{left} {right}"
        );
        let area = std::f64::consts::PI * 25.0 * 25.0;
        let count = r.count_body(0) as f64;
        assert!((count - area).abs() < 0.01 * area, "{count} vs {area}");
        let images: std::collections::BTreeSet<u32> =
            r.seen.iter().flatten().map(|s| s.image).collect();
        assert_eq!(images.len(), 2);
        // Whole: the body's own top at z = 0.6; Cut: the image's cut at z = 4.
        let top = r.at(10, 100).unwrap().hit;
        assert!(!top.cut && (top.z - 0.6).abs() < 1e-3, "{top:?}");
        let c = cast(&p, View::Cut, 50.0);
        let cut = c.at(10, 100).unwrap().hit;
        assert!(
            cut.cut && cut.z == 4.0 && cut.normal == [0.0, 0.0, 1.0],
            "{cut:?}"
        );
    }

    /// A `harmonic` body `Ŷ_20`, `Δ = 0.3`, its axis turned onto world x
    /// (quaternion of a quarter turn about y): seen along z, its silhouette
    /// reaches `R⁰(1 + Δ F(pole)) = 1.2` along x and `R⁰(1 − Δ/3) = 0.9`
    /// along y (the waist is the widest section for Δ < 3/7: d²/dθ² of
    /// `R(θ) sin θ` at the equator is `2Δ − (1 − Δ/3) < 0`). At 100 px per
    /// unit: 240 px by 180 px through the centre, each within 2 px (one
    /// pixel of quantisation at each end; the march and bisection pin the
    /// surface to far below a pixel). The radii come from the family's own
    /// surface, checked against its documented `Ŷ_20 = (3cos²θ − 1)/3`.
    #[test]
    fn a_harmonic_body_has_its_true_silhouette() {
        let params = serde_json::json!({"l": 2, "delta": 0.3});
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let f = record3(
            "harmonic",
            params.clone(),
            [4.0; 3],
            vec![[2.0; 3]],
            vec![1.0],
            vec![vec![h, 0.0, h, 0.0]],
        );
        let p = Packing3d::from_file(&f).unwrap();
        let Solid::Star(surface) = &p.solid else {
            panic!("harmonic draws as a star-shaped body: {:?}", p.solid)
        };
        let pole = surface.relative_radius([0.0, 0.0, 1.0]);
        let waist = surface.relative_radius([1.0, 0.0, 0.0]);
        assert!(
            (pole - 1.2).abs() < 1e-12 && (waist - 0.9).abs() < 1e-12,
            "{pole} {waist}"
        );
        let r = cast(&p, View::Whole, 100.0);
        let row = (0..r.width).filter(|&c| r.at(c, 199).is_some()).count() as f64;
        let col = (0..r.height).filter(|&k| r.at(199, k).is_some()).count() as f64;
        assert!(
            (row - 200.0 * pole).abs() <= 2.0,
            "{row} px along x, expected {}",
            200.0 * pole
        );
        assert!(
            (col - 200.0 * waist).abs() <= 2.0,
            "{col} px along y, expected {}",
            200.0 * waist
        );
        // Seen along its axis (no turn) the same body is round: 180 px both ways.
        let mut g = f.clone();
        g.orientations = vec![vec![1.0, 0.0, 0.0, 0.0]];
        let r = cast(&Packing3d::from_file(&g).unwrap(), View::Whole, 100.0);
        let row = (0..r.width).filter(|&c| r.at(c, 199).is_some()).count() as f64;
        assert!((row - 180.0).abs() <= 2.0, "{row}");
        // The top of the pole-on body is the pole, at z = 2 + 1.2.
        assert!((r.at(199, 199).unwrap().hit.z - 3.2).abs() < 1e-3);
    }

    /// A 3D dimer is drawn from its `spheres` rows: two overlapping balls
    /// of radius 0.5 at distance 0.5 along x; its silhouette spans
    /// 1.5 along x, 1 along y through a sphere's centre and less at the
    /// neck (2 px tolerance at 100 px per unit: a pixel at each end).
    #[test]
    fn a_dimer_is_drawn_from_its_spheres() {
        let mut f = record3(
            "nmer",
            serde_json::json!({"alpha": 1.5}),
            [4.0; 3],
            vec![[2.0; 3]],
            vec![0.5],
            vec![vec![1.0, 0.0, 0.0, 0.0]],
        );
        f.spheres = vec![
            vec![1.75, 2.0, 2.0, 0.5, 0.0],
            vec![2.25, 2.0, 2.0, 0.5, 0.0],
        ];
        let p = Packing3d::from_file(&f).unwrap();
        assert!(matches!(p.solid, Solid::Spheres));
        let r = cast(&p, View::Whole, 100.0);
        let row = (0..r.width).filter(|&c| r.at(c, 199).is_some()).count() as f64;
        let col = |c: usize| (0..r.height).filter(|&k| r.at(c, k).is_some()).count() as f64;
        // Through a sphere's centre (x = 1.745): its diameter, 100 px; at
        // the neck (x = 1.995) the chord 2√(0.25 − 0.245²) = 0.872: 87 px.
        let (full, neck) = (col(174), col(199));
        assert!((row - 150.0).abs() <= 2.0, "{row}");
        assert!(
            (full - 100.0).abs() <= 2.0 && (neck - 87.2).abs() <= 2.0,
            "{full} {neck}"
        );
        let images: std::collections::BTreeSet<u32> =
            r.seen.iter().flatten().map(|s| s.image).collect();
        assert_eq!(images.len(), 1, "the two spheres are one body image");
    }

    #[test]
    fn bad_3d_files_are_errors_naming_the_key() {
        let ok = record3(
            "sphere",
            serde_json::json!({}),
            [4.0; 3],
            vec![[2.0; 3]],
            vec![1.0],
            vec![],
        );
        let check = |f: PackingFile, needle: &str| {
            let e = Packing3d::from_file(&f).unwrap_err().to_string();
            assert!(e.contains(needle), "{e} lacks {needle}");
        };
        let mut f = ok.clone();
        f.dim = 2;
        check(f, "dim = 2");
        let mut f = ok.clone();
        f.box_edges = vec![4.0, 4.0];
        check(f, "box = [4.0, 4.0]: must hold 3 positive");
        let mut f = ok.clone();
        f.positions = vec![vec![1.0, 2.0]];
        check(f, "positions[0] = [1.0, 2.0]: must be 3 finite numbers");
        let mut f = ok.clone();
        f.radii = vec![-1.0];
        check(f, "radii[0] = -1");
        let mut f = ok.clone();
        f.family = "ellipse".into();
        f.params = serde_json::json!({"aspect": 1.5});
        check(f, "family `ellipse`");
        let mut f = ok.clone();
        f.spheres = vec![vec![1.0, 1.0, 1.0, 0.5, 0.0]];
        check(f, "spheres[0]");
        let h = record3(
            "harmonic",
            serde_json::json!({"l": 2, "delta": 0.1}),
            [4.0; 3],
            vec![[2.0; 3]],
            vec![1.0],
            vec![],
        );
        check(h.clone(), "orientations has 0 entries for 1 positions");
        let mut f = h.clone();
        f.orientations = vec![vec![2.0, 0.0, 0.0, 0.0]];
        check(
            f,
            "orientations[0] = [2.0, 0.0, 0.0, 0.0]: not an orientation",
        );
        let mut f = h;
        f.params = serde_json::json!({"l": 2, "delta": 5.0});
        f.orientations = vec![vec![1.0, 0.0, 0.0, 0.0]];
        check(f, "params.delta");
    }
}
