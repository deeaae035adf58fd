//! Outlines, periodic images and clipping, with no plotting.
//!
//! A body of size `R⁰`, centre `r` and orientation `θ` has the polar outline
//! `R(φ) = R⁰ [1 + Δ F(θ − φ)]` in the lab direction `φ` (the convention of
//! `jamkit-fourier`; a disk is `Δ = 0`), so its outline points are
//! `r + R(φ) (cos φ, sin φ)`. A body that crosses an edge of the periodic
//! box `[0, L₁) × [0, L₂)` is drawn as several pieces: the body and its
//! periodic images, each clipped to the box. An ellipse (`jamkit-ellipse`)
//! has `R(φ) = R⁰/√(α⁻¹cos²(θ − φ) + α sin²(θ − φ))`, its long axis along
//! `e(θ)`.

use crate::DrawError;
use jamkit_core::BodyOrientation;
use jamkit_core::{RoundOutline, Shape, SharedOutline};
use jamkit_registry::{self as registry, ParamMap, SceneVisitor};
use std::f64::consts::PI;
use std::sync::Arc;

/// A point of the plane, `[x, y]`.
pub type Point = [f64; 2];

/// The outline law of a family, shared by all bodies of a packing. It comes
/// from the family's shape through the registry ([`Outline::of`]): a
/// family draws if its 2D shape has an outline
/// ([`Shape::outline`](jamkit_core::Shape::outline)) or is made of spheres
/// ([`Shape::sphere_decomposition`](jamkit_core::Shape::sphere_decomposition)).
#[derive(Clone, Debug)]
pub enum Outline {
    /// A star-shaped body: `R(φ) = R⁰ ρ(θ − φ)`.
    Polar {
        /// `ρ(ψ) = R(ψ)/R⁰`.
        shape: SharedOutline,
        /// Whether the bodies have an orientation (false for disks, and for
        /// the degenerate members of a family that run as disks: a
        /// near-disk with `Δ = 0`, an ellipse with `α = 1`).
        turns: bool,
    },
    /// A body made of spheres (`nmer`), drawn from the packing file's
    /// `spheres` rows as the union of its disks ([`union_outlines`]); a
    /// body without rows (α = 1 runs as disks) is the disk of radius `R⁰`.
    Spheres,
}

/// The registry's visitor that asks a 2D shape for its outline.
struct OutlineOf;

impl SceneVisitor for OutlineOf {
    type Output = Option<Outline>;

    fn visit<const D: usize, S: Shape<D>>(self, shape: S) -> Option<Outline> {
        if D != 2 {
            return None;
        }
        if let Some(o) = shape.look().outline {
            return Some(Outline::Polar {
                shape: o,
                turns: shape.rot_dof() > 0,
            });
        }
        let o = S::Orientation::reference();
        shape
            .sphere_decomposition(1.0, &o)
            .map(|_| Outline::Spheres)
    }
}

impl Outline {
    /// The disk: `R(φ) = R⁰`.
    pub fn disk() -> Self {
        Outline::Polar {
            shape: Arc::new(RoundOutline),
            turns: false,
        }
    }

    /// The outline of a registered family in 2D, from its parameters as an
    /// experiment file gives them (`(n: 3, delta: 0.2)` for `fourier`;
    /// defaults filled in).
    pub fn of(family: &str, params: &ParamMap) -> Result<Self, DrawError> {
        crate::drawing_of(family, 2, params, OutlineOf)
    }

    /// The outline of a registered family from its parameters as stored in
    /// a packing file (`{}` for spheres, `{"n": 3, "delta": 0.2, …}` for
    /// `fourier`, `{"modes": [...], "delta": …}` for `fourier_sum`).
    pub fn from_family(family: &str, params: &serde_json::Value) -> Result<Self, DrawError> {
        crate::drawing_from_json(family, 2, params, OutlineOf)
    }

    /// The outline of a registered family from its parameters written in
    /// RON as in an experiment file: `(n: 3, delta: 0.2)`.
    pub fn from_ron(family: &str, text: &str) -> Result<Self, DrawError> {
        let params = registry::params_from_ron(text).map_err(|e| DrawError::Params {
            family: family.to_string(),
            message: format!("{text}: {e} (write the parameters as in an experiment file, e.g. (n: 3, delta: 0.2))"),
        })?;
        Self::of(family, &params)
    }

    /// `R/R⁰` as a function of the body-frame angle `ψ` (1 for bodies made
    /// of spheres, drawn from their spheres instead).
    pub fn relative_radius(&self, psi: f64) -> f64 {
        match self {
            Outline::Polar { shape, .. } => shape.relative_radius(psi),
            Outline::Spheres => 1.0,
        }
    }

    /// Whether the bodies carry an angle `θ` in the packing file.
    pub fn turns(&self) -> bool {
        matches!(self, Outline::Polar { turns: true, .. })
    }

    /// True for outlines that are disks (a near-disk with `Δ = 0`, an
    /// ellipse with `α = 1`): they are jammed as disks and store no angles.
    pub fn is_round(&self) -> bool {
        matches!(self, Outline::Polar { turns: false, .. })
    }

    /// The radius `R(φ) = R⁰ ρ(θ − φ)` of a body of size `size` and
    /// orientation `theta` in the lab direction `phi`.
    pub fn radius(&self, size: f64, theta: f64, phi: f64) -> f64 {
        size * self.relative_radius(theta - phi)
    }

    /// `m` outline points of a body, counter-clockwise from `φ = 0`, not
    /// closed (the last point is not repeated).
    pub fn body_points(&self, center: Point, size: f64, theta: f64, m: usize) -> Vec<Point> {
        (0..m)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / m as f64;
                let r = self.radius(size, theta, phi);
                [center[0] + r * phi.cos(), center[1] + r * phi.sin()]
            })
            .collect()
    }

    /// The closed outline of a body of orientation 0, `R(φ)/R⁰ (cos φ,
    /// sin φ)` with `R(φ) = R⁰ ρ(0 − φ)` as [`Outline::radius`] and the gap
    /// read it, on `m + 1` points (`φ = 0 … 2π`): the shape plot of
    /// `draw-shape`, the body as a packing at orientation 0 holds it.
    pub fn polar_curve(&self, m: usize) -> Vec<Point> {
        (0..=m)
            .map(|k| {
                let theta = 2.0 * PI * k as f64 / m as f64;
                let r = self.relative_radius(-theta);
                [r * theta.cos(), r * theta.sin()]
            })
            .collect()
    }
}

/// The outline of a union of disks `(centre, radius)` around the body
/// centre `center`, `m` points per disk. When `center` lies in every disk
/// the union is star-shaped about it (a union of convex sets sharing a
/// point), and its outline is one polygon: the points of each circle that
/// lie in no other disk, sorted by angle about `center`. Otherwise (a
/// dimer with α > 2, a bent chain) each disk is its own polygon, drawn
/// over one another in the body's colour.
pub fn union_outlines(center: Point, disks: &[(Point, f64)], m: usize) -> Vec<Vec<Point>> {
    let dist = |p: Point, q: Point| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
    let circle = |(c, r): (Point, f64)| -> Vec<Point> {
        (0..m)
            .map(|k| {
                let t = 2.0 * PI * k as f64 / m as f64;
                [c[0] + r * t.cos(), c[1] + r * t.sin()]
            })
            .collect()
    };
    // NOTE: a relative slack of 1e-12 keeps the tangent point of an α = 2
    // dimer (the body centre, on both circles) inside both disks.
    let star = disks
        .iter()
        .all(|&(c, r)| dist(center, c) <= r * (1.0 + 1e-12));
    if !star {
        return disks.iter().map(|&d| circle(d)).collect();
    }
    let mut points: Vec<(f64, Point)> = Vec::new();
    for (a, &d) in disks.iter().enumerate() {
        for p in circle(d) {
            let hidden = disks
                .iter()
                .enumerate()
                .any(|(b, &(c, r))| b != a && dist(p, c) < r);
            if !hidden {
                points.push(((p[1] - center[1]).atan2(p[0] - center[0]), p));
            }
        }
    }
    points.sort_by(|x, y| x.0.total_cmp(&y.0));
    vec![points.into_iter().map(|(_, p)| p).collect()]
}

/// Signed area of a polygon (shoelace; positive when counter-clockwise).
pub fn polygon_area(poly: &[Point]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % n]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum::<f64>()
        / 2.0
}

/// Keep the part of `poly` with `sign (p[axis] − c) ≥ 0` (one step of
/// Sutherland–Hodgman).
fn clip_half_plane(poly: &[Point], axis: usize, c: f64, sign: f64) -> Vec<Point> {
    let value = |p: &Point| sign * (p[axis] - c);
    let mut out = Vec::with_capacity(poly.len() + 4);
    for i in 0..poly.len() {
        let s = poly[i];
        let e = poly[(i + 1) % poly.len()];
        let (vs, ve) = (value(&s), value(&e));
        if vs >= 0.0 {
            out.push(s);
        }
        if (vs >= 0.0) != (ve >= 0.0) {
            let t = vs / (vs - ve);
            let mut p = [s[0] + t * (e[0] - s[0]), s[1] + t * (e[1] - s[1])];
            p[axis] = c; // exactly on the edge, whatever the rounding
            out.push(p);
        }
    }
    out
}

/// The part of `poly` inside the box `[0, L₁] × [0, L₂]`
/// (Sutherland–Hodgman; correct for any polygon since the box is convex,
/// though a non-convex polygon cut in two keeps a zero-width bridge along
/// the edge). Empty when nothing is inside.
pub fn clip_to_box(poly: &[Point], box_edges: [f64; 2]) -> Vec<Point> {
    let mut out = poly.to_vec();
    for (axis, c, sign) in [
        (0, 0.0, 1.0),
        (0, box_edges[0], -1.0),
        (1, 0.0, 1.0),
        (1, box_edges[1], -1.0),
    ] {
        if out.is_empty() {
            break;
        }
        out = clip_half_plane(&out, axis, c, sign);
    }
    out
}

/// The shifts (multiples of the box edges, `[0, 0]` first) that bring a part
/// of `poly` into the box `[0, L₁) × [0, L₂)`. A polygon inside the box has
/// only `[0, 0]`; one crossing a single edge has two shifts; one crossing a
/// corner has four. Assumes the polygon is smaller than the box.
pub fn image_shifts(poly: &[Point], box_edges: [f64; 2]) -> Vec<Point> {
    let mut per_axis: [Vec<f64>; 2] = [vec![0.0], vec![0.0]];
    for axis in 0..2 {
        let lo = poly.iter().map(|p| p[axis]).fold(f64::INFINITY, f64::min);
        let hi = poly
            .iter()
            .map(|p| p[axis])
            .fold(f64::NEG_INFINITY, f64::max);
        if lo < 0.0 {
            per_axis[axis].push(box_edges[axis]);
        }
        if hi > box_edges[axis] {
            per_axis[axis].push(-box_edges[axis]);
        }
    }
    let mut shifts = Vec::new();
    for &sx in &per_axis[0] {
        for &sy in &per_axis[1] {
            shifts.push([sx, sy]);
        }
    }
    shifts
}

/// The pieces of `poly` to draw in the periodic box: the polygon and its
/// periodic images, each clipped to the box, with its shift. Pieces of
/// (relatively) zero area are dropped. The first piece, if any, is the
/// unshifted one.
pub fn periodic_pieces(poly: &[Point], box_edges: [f64; 2]) -> Vec<(Point, Vec<Point>)> {
    let min_area = 1e-12 * box_edges[0] * box_edges[1];
    image_shifts(poly, box_edges)
        .into_iter()
        .filter_map(|s| {
            let shifted: Vec<Point> = poly.iter().map(|p| [p[0] + s[0], p[1] + s[1]]).collect();
            let clipped = clip_to_box(&shifted, box_edges);
            (clipped.len() >= 3 && polygon_area(&clipped).abs() > min_area).then_some((s, clipped))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn fourier(n: u32, delta: f64) -> Result<Outline, DrawError> {
        Outline::from_ron("fourier", &format!("(n: {n}, delta: {delta:?})"))
    }

    #[test]
    fn disk_outline_points_lie_at_distance_r() {
        let c = [1.5, 2.0];
        for p in Outline::disk().body_points(c, 0.7, 0.3, 200) {
            assert_relative_eq!((p[0] - c[0]).hypot(p[1] - c[1]), 0.7, epsilon = 1e-12);
        }
    }

    #[test]
    fn near_disk_radius_at_its_orientation_is_one_plus_delta_f0() {
        // fourier: F(0) = sin(0)/n = 0, so R(θ_i) = R⁰.
        let o = fourier(3, 0.2).unwrap();
        let (size, theta) = (0.6, 1.1);
        assert_relative_eq!(o.radius(size, theta, theta), size, epsilon = 1e-12);
        // fourier_sum with a phase: F(0) = a sin(b).
        let o = Outline::from_ron(
            "fourier_sum",
            "(modes: [(n: 2, a: 0.5, b: 0.7)], delta: 0.3)",
        )
        .unwrap();
        let expected = size * (1.0 + 0.3 * 0.5 * 0.7f64.sin());
        assert_relative_eq!(o.radius(size, theta, theta), expected, epsilon = 1e-12);
        // And the outline point in the direction θ_i sits at that radius.
        let m = 200;
        let theta = 2.0 * PI * 17.0 / m as f64; // on the sampling grid
        let c = [0.0, 0.0];
        let p = o.body_points(c, size, theta, m)[17];
        assert_relative_eq!(p[0].hypot(p[1]), expected, epsilon = 1e-12);
    }

    #[test]
    fn near_disk_follows_the_outline_convention() {
        // R(φ) = R⁰ [1 + Δ sin(n(θ − φ))/n]: at φ = θ − π/(2n) it is maximal.
        let (n, delta, size, theta) = (2, 0.3, 1.0, 0.4);
        let o = fourier(n, delta).unwrap();
        let phi = theta - PI / (2.0 * n as f64);
        assert_relative_eq!(
            o.radius(size, theta, phi),
            1.0 + delta / n as f64,
            epsilon = 1e-12
        );
    }

    #[test]
    fn ellipse_outline_has_the_area_of_its_disk_and_its_long_axis_along_theta() {
        let o = Outline::from_family(
            "ellipse",
            &serde_json::json!({"aspect": 2.0, "inertia": null}),
        )
        .unwrap();
        let poly = o.body_points([0.0, 0.0], 0.5, 0.7, 4000);
        // Area π (R⁰)² to the polygon's O(1/m²) deficit (~1e-6 here).
        assert_relative_eq!(polygon_area(&poly), PI * 0.25, max_relative = 1e-5);
        // The farthest point is at a = R⁰√α along e(θ).
        let far = poly
            .iter()
            .max_by(|p, q| (p[0].hypot(p[1])).total_cmp(&q[0].hypot(q[1])))
            .unwrap();
        assert_relative_eq!(far[0].hypot(far[1]), 0.5 * 2f64.sqrt(), max_relative = 1e-6);
        let t = far[1].atan2(far[0]);
        assert!((t - 0.7).abs() < 2e-3 || (t - 0.7 + PI).abs() < 2e-3, "{t}");
        assert!(Outline::from_family("ellipse", &serde_json::json!({"aspect": 0.5})).is_err());
        assert!(
            Outline::from_ron("ellipse", "(aspect: 1.0)")
                .unwrap()
                .is_round()
        );
    }

    #[test]
    fn polar_curve_is_closed_and_is_the_body_at_orientation_zero() {
        let o = fourier(4, 0.1).unwrap();
        let c = o.polar_curve(100);
        assert_eq!(c.len(), 101);
        assert_relative_eq!(c[0][0], c[100][0], epsilon = 1e-12);
        assert_relative_eq!(c[0][1], c[100][1], epsilon = 1e-12);
        let theta = 2.0 * PI * 13.0 / 100.0;
        assert_relative_eq!(
            c[13][0].hypot(c[13][1]),
            1.0 + 0.1 * (-4.0 * theta).sin() / 4.0,
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_body_inside_the_box_has_one_piece() {
        let poly = Outline::disk().body_points([2.0, 2.0], 0.5, 0.0, 64);
        let pieces = periodic_pieces(&poly, [4.0, 4.0]);
        assert_eq!(pieces.len(), 1);
        assert_eq!(pieces[0].0, [0.0, 0.0]);
        assert_relative_eq!(
            polygon_area(&pieces[0].1),
            polygon_area(&poly),
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_body_crossing_an_edge_gets_an_image_and_keeps_its_area() {
        let box_edges = [4.0, 5.0];
        let poly = Outline::disk().body_points([0.2, 2.5], 0.5, 0.0, 200);
        let pieces = periodic_pieces(&poly, box_edges);
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[1].0, [4.0, 0.0]);
        for (_, piece) in &pieces {
            assert!(
                piece
                    .iter()
                    .all(|p| (0.0..=4.0).contains(&p[0]) && (0.0..=5.0).contains(&p[1]))
            );
        }
        let total: f64 = pieces.iter().map(|(_, p)| polygon_area(p)).sum();
        assert_relative_eq!(total, polygon_area(&poly), epsilon = 1e-12);
    }

    #[test]
    fn a_body_on_a_corner_gets_three_images() {
        let box_edges = [4.0, 4.0];
        let poly = fourier(3, 0.2)
            .unwrap()
            .body_points([3.9, 0.1], 0.5, 0.8, 200);
        let pieces = periodic_pieces(&poly, box_edges);
        assert_eq!(pieces.len(), 4);
        let total: f64 = pieces.iter().map(|(_, p)| polygon_area(p)).sum();
        assert_relative_eq!(total, polygon_area(&poly), epsilon = 1e-12);
    }

    #[test]
    fn families_and_parameters_are_checked() {
        let p = serde_json::json!({"n": 3, "delta": 0.2, "inertia": null});
        assert!(Outline::from_family("fourier", &p).unwrap().turns());
        let p = serde_json::json!({"modes": [{"n": 2, "a": 0.5, "b": 0.0}], "delta": 0.1});
        assert!(Outline::from_family("fourier_sum", &p).is_ok());
        assert!(
            Outline::from_family("sphere", &serde_json::json!({}))
                .unwrap()
                .is_round()
        );
        // Every registered 2D family draws from its example parameters.
        for (info, example) in registry::FAMILIES.iter().zip(registry::EXAMPLES) {
            if registry::supports_dim(info, 2) {
                assert!(
                    Outline::from_ron(info.name, example).is_ok(),
                    "{}",
                    info.name
                );
            }
        }
        assert!(matches!(
            Outline::from_ron("nmer", "(alpha: 1.5)"),
            Ok(Outline::Spheres)
        ));
        let lobed = Outline::from_ron("lobed", "(delta: 0.2)").unwrap();
        assert_relative_eq!(lobed.relative_radius(0.0), 1.2, epsilon = 1e-12);
        let e = Outline::from_family("dimer", &serde_json::json!({})).unwrap_err();
        assert!(e.to_string().contains("dimer"), "{e}");
        let e = Outline::from_family("fourier", &serde_json::json!({"n": 2})).unwrap_err();
        assert!(e.to_string().contains("delta"), "{e}");
        let e = fourier(1, 5.0).unwrap_err();
        assert!(e.to_string().contains("params.delta"), "{e}");
        assert!(fourier(2, 0.0).is_ok());
    }
}
