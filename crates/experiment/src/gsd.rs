//! Packings as GSD files in HOOMD-blue's `hoomd` schema (version 1.4),
//! the format HOOMD-blue, OVITO and the Python package `gsd` read.
//!
//! One frame per packing, every chunk written in every frame:
//!
//! | chunk | type | meaning |
//! |---|---|---|
//! | `configuration/step` | uint64 | the frame's index in the file |
//! | `configuration/dimensions` | uint8 | 2 or 3 |
//! | `configuration/box` | float32 × 6 | `(L_x, L_y, L_z, 0, 0, 0)`; a 2D box has `L_z = 0` |
//! | `particles/N` | uint32 | the body count |
//! | `particles/position` | float32 N × 3 | the centres, shifted to HOOMD's box `[−L/2, L/2)` (jamkit's is `[0, L)`); `z = 0` in 2D |
//! | `particles/orientation` | float32 N × 4 | the rotation body → world as a unit quaternion `(w, x, y, z)`; a planar angle θ is `(cos θ/2, 0, 0, sin θ/2)`; `(1, 0, 0, 0)` for bodies that do not turn |
//! | `particles/diameter` | float32 N | `2 R⁰` |
//! | `particles/types`, `particles/typeid` | text, uint32 N | one type per distinct size `R⁰`, named `R<size>`, in increasing size |
//! | `particles/type_shapes` | text | each type's shape as JSON, in absolute lengths, in the body frame |
//! | `log/jamkit/phi`, `log/jamkit/energy_per_particle` | float64 | φ and `V/N` |
//!
//! The shape of a type comes from the family's [`Look`] and, for bodies
//! made of spheres, its [`Shape::sphere_decomposition`], in this order:
//!
//! * bodies made of spheres: `SphereUnion` (the spheres' diameters and
//!   body-frame centres at size `R⁰`);
//! * balls ([`Look::ball`]): `Sphere` of diameter `2R⁰`;
//! * ellipses and ellipsoids ([`Look::ellipsoid_axes`]): `Ellipsoid` with
//!   semi-axes `a, b, c = R⁰ (ξ_x, ξ_y, ξ_z)`;
//! * other planar outlines ([`Look::outline`], the near-disks): `Polygon` of
//!   [`POLYGON_VERTICES`] vertices, counter-clockwise at equal body-frame
//!   angles, each on the outline;
//! * other 3D surfaces ([`Look::surface`], the near-spheres): `Mesh`, a
//!   latitude–longitude triangulation of [`MESH_RINGS`] bands and
//!   [`MESH_SEGMENTS`] meridians with its vertices on the surface,
//!   triangles counter-clockwise seen from outside;
//! * anything else: `{}` (a viewer chooses).
//!
//! Positions, box, orientations and diameters are float32, as the schema
//! has them: a centre keeps about 7 significant digits, too few to
//! recompute the contacts of a packing at φ_J (overlaps ~10⁻⁸); use the
//! packing file or extended XYZ for that.

use crate::error::ExperimentError;
use crate::reload::{PackingVisitor, reload};
use jamkit_core::{BodyOrientation, Look, Quaternion, Shape, Vector};
use jamkit_engine::Scene;
use jamkit_format::PackingFile;
use jamkit_format::gsd::{Chunk, Writer};
use serde_json::json;
use std::f64::consts::PI;

/// Vertices of the polygon that stands for a planar outline. Between two
/// vertices the polygon's edge lies inside a round outline by at most
/// `R (1 − cos(π/128)) ≈ 3·10⁻⁴ R`.
pub const POLYGON_VERTICES: usize = 128;
/// Latitude bands of the mesh that stands for a 3D surface.
pub const MESH_RINGS: usize = 16;
/// Meridians of that mesh.
pub const MESH_SEGMENTS: usize = 32;

/// The `hoomd` schema version whose chunks are written.
pub const SCHEMA_VERSION: (u16, u16) = (1, 4);

/// How far a body's spheres, turned by its exported orientation, may lie
/// from where the family puts them, in units of its size: the two differ
/// by the rounding of a few trigonometric functions (`~10⁻¹⁵`); `10⁻⁹`
/// catches any other convention.
const SPHERES_TOLERANCE: f64 = 1e-9;

/// The per-body and per-type data that need the family.
struct Bodies {
    /// `(w, x, y, z)` per body.
    orientations: Vec<[f64; 4]>,
    typeid: Vec<u32>,
    types: Vec<String>,
    shapes: Vec<String>,
}

struct Visit;

impl PackingVisitor for Visit {
    type Output = Result<Bodies, String>;

    fn visit<const D: usize, S: Shape<D>>(self, scene: Scene<D, S>) -> Result<Bodies, String> {
        let p = scene.packing();
        let look = p.shape.look();
        let mut sizes = p.sizes.clone();
        sizes.sort_by(f64::total_cmp);
        sizes.dedup();
        let typeid = p
            .sizes
            .iter()
            .map(|s| sizes.binary_search_by(|x| x.total_cmp(s)).unwrap() as u32)
            .collect();
        let types = sizes.iter().map(|s| format!("R{s}")).collect();
        let shapes = sizes
            .iter()
            .map(|&s| type_shape::<D, S>(&p.shape, &look, s).to_string())
            .collect();
        let mut orientations = Vec::with_capacity(p.sizes.len());
        for (i, o) in p.orientations.iter().enumerate() {
            let q = quaternion(&look, &o.to_coords())
                .ok_or_else(|| format!("body {i}: orientation {:?}", o.to_coords()))?;
            check_spheres::<D, S>(&p.shape, p.sizes[i], o, q)
                .map_err(|e| format!("body {i}: {e}"))?;
            orientations.push(q);
        }
        Ok(Bodies {
            orientations,
            typeid,
            types,
            shapes,
        })
    }
}

/// The rotation of a body whose orientation is written `coords`, as a
/// unit quaternion `(w, x, y, z)`: none → identity; a planar angle θ → the
/// turn by θ about `z`; in 3D the surface's rotation
/// ([`Surface::rotation`](jamkit_core::Surface::rotation)) when the
/// family has a surface, else the quaternion `[w, x, y, z]` itself.
fn quaternion(look: &Look, coords: &[f64]) -> Option<[f64; 4]> {
    match coords {
        [] => Some([1.0, 0.0, 0.0, 0.0]),
        [theta] => {
            let (s, c) = (0.5 * theta).sin_cos();
            Some([c, 0.0, 0.0, s])
        }
        _ => match &look.surface {
            Some(surface) => surface.rotation(coords).map(from_rows),
            None => Quaternion::from_coords(coords).map(|q| q.coords()),
        },
    }
}

/// The unit quaternion (w ≥ 0) of a rotation matrix given by rows
/// (Shepperd's method: the largest of the four squared components first).
fn from_rows(m: [[f64; 3]; 3]) -> [f64; 4] {
    let t = m[0][0] + m[1][1] + m[2][2];
    let q = if t >= m[0][0].max(m[1][1]).max(m[2][2]) {
        let w = 0.5 * (1.0 + t).sqrt();
        let f = 0.25 / w;
        [
            w,
            (m[2][1] - m[1][2]) * f,
            (m[0][2] - m[2][0]) * f,
            (m[1][0] - m[0][1]) * f,
        ]
    } else if m[0][0] >= m[1][1] && m[0][0] >= m[2][2] {
        let x = 0.5 * (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt();
        let f = 0.25 / x;
        [
            (m[2][1] - m[1][2]) * f,
            x,
            (m[0][1] + m[1][0]) * f,
            (m[0][2] + m[2][0]) * f,
        ]
    } else if m[1][1] >= m[2][2] {
        let y = 0.5 * (1.0 - m[0][0] + m[1][1] - m[2][2]).sqrt();
        let f = 0.25 / y;
        [
            (m[0][2] - m[2][0]) * f,
            (m[0][1] + m[1][0]) * f,
            y,
            (m[1][2] + m[2][1]) * f,
        ]
    } else {
        let z = 0.5 * (1.0 - m[0][0] - m[1][1] + m[2][2]).sqrt();
        let f = 0.25 / z;
        [
            (m[1][0] - m[0][1]) * f,
            (m[0][2] + m[2][0]) * f,
            (m[1][2] + m[2][1]) * f,
            z,
        ]
    };
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let s = if q[0] < 0.0 { -1.0 / n } else { 1.0 / n };
    q.map(|v| v * s)
}

/// `q v q*` for the unit quaternion `q = (w, x, y, z)`.
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let u = [x, y, z];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    std::array::from_fn(|k| v[k] + w * t[k] + ut[k])
}

/// Three coordinates of a `D`-vector (`z = 0` in 2D).
fn xyz<const D: usize>(v: &Vector<D>) -> [f64; 3] {
    std::array::from_fn(|k| if k < D { v[k] } else { 0.0 })
}

/// For bodies made of spheres: the spheres at the reference orientation
/// turned by `q` must be where the family puts them at `o`, so that the
/// `SphereUnion` type shape and the orientation together draw the body.
fn check_spheres<const D: usize, S: Shape<D>>(
    shape: &S,
    size: f64,
    o: &S::Orientation,
    q: [f64; 4],
) -> Result<(), String> {
    let reference = S::Orientation::reference();
    let (Some(body), Some(world)) = (
        shape.sphere_decomposition(size, &reference),
        shape.sphere_decomposition(size, o),
    ) else {
        return Ok(());
    };
    for ((b, _), (w, _)) in body.iter().zip(&world) {
        let turned = rotate(q, xyz(b));
        let want = xyz(w);
        let off = (0..3)
            .map(|k| (turned[k] - want[k]).abs())
            .fold(0.0, f64::max);
        if off > SPHERES_TOLERANCE * size {
            return Err(format!(
                "its spheres are not those of the reference orientation turned by {q:?} ({off:e} apart)"
            ));
        }
    }
    Ok(())
}

/// The `type_shapes` entry of bodies of size `size`.
fn type_shape<const D: usize, S: Shape<D>>(shape: &S, look: &Look, size: f64) -> serde_json::Value {
    if let Some(spheres) = shape.sphere_decomposition(size, &S::Orientation::reference()) {
        let diameters: Vec<f64> = spheres.iter().map(|(_, r)| 2.0 * r).collect();
        let centers: Vec<[f64; 3]> = spheres.iter().map(|(c, _)| xyz(c)).collect();
        return json!({"type": "SphereUnion", "diameters": diameters, "centers": centers});
    }
    if look.ball {
        return json!({"type": "Sphere", "diameter": 2.0 * size});
    }
    if let Some(xi) = look.ellipsoid_axes {
        return json!({"type": "Ellipsoid", "a": size * xi[0], "b": size * xi[1], "c": size * xi[2]});
    }
    if let (2, Some(outline)) = (D, &look.outline) {
        // A body at orientation 0 reaches R⁰ ρ(−φ) in the direction φ
        // (jamkit_core::Outline), so that turning it by θ gives R⁰ ρ(θ − φ).
        let vertices: Vec<[f64; 2]> = (0..POLYGON_VERTICES)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / POLYGON_VERTICES as f64;
                let r = size * outline.relative_radius(-phi);
                [r * phi.cos(), r * phi.sin()]
            })
            .collect();
        return json!({"type": "Polygon", "rounding_radius": 0.0, "vertices": vertices});
    }
    if let (3, Some(surface)) = (D, &look.surface) {
        let (vertices, indices) = mesh(|y| size * surface.relative_radius(y));
        return json!({"type": "Mesh", "vertices": vertices, "indices": indices});
    }
    json!({})
}

/// A latitude–longitude triangulation of the star-shaped surface whose
/// radius in the unit direction `y` is `radius(y)`: both poles, then
/// `MESH_RINGS − 1` rings of `MESH_SEGMENTS` vertices; triangles
/// counter-clockwise seen from outside.
fn mesh(radius: impl Fn([f64; 3]) -> f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let (rings, segments) = (MESH_RINGS, MESH_SEGMENTS);
    let at = |y: [f64; 3]| y.map(|c| c * radius(y));
    let mut vertices = vec![at([0.0, 0.0, 1.0]), at([0.0, 0.0, -1.0])];
    for i in 1..rings {
        let polar = PI * i as f64 / rings as f64;
        for j in 0..segments {
            let azimuth = 2.0 * PI * j as f64 / segments as f64;
            vertices.push(at([
                polar.sin() * azimuth.cos(),
                polar.sin() * azimuth.sin(),
                polar.cos(),
            ]));
        }
    }
    let v = |i: usize, j: usize| (2 + (i - 1) * segments + j % segments) as u32;
    let mut indices = Vec::new();
    for j in 0..segments {
        indices.push([0, v(1, j), v(1, j + 1)]);
        indices.push([1, v(rings - 1, j + 1), v(rings - 1, j)]);
        for i in 1..rings - 1 {
            indices.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            indices.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    (vertices, indices)
}

/// The chunks of one frame for `file`, with `configuration/step = step`.
pub fn frame(file: &PackingFile, step: u64) -> Result<Vec<Chunk>, ExperimentError> {
    crate::extxyz::exportable(file, "GSD")?;
    let dim = file.dim;
    let bodies = reload(file, Visit)?.map_err(|e| {
        ExperimentError::invalid(
            format!("packing {}: family {}", file.id, file.family),
            e,
            "GSD export needs orientations that turn the body frame",
        )
    })?;
    let l = &file.box_edges;
    let lz = if dim == 3 { l[2] } else { 0.0 };
    let mut position = Vec::with_capacity(3 * file.particles);
    for r in &file.positions {
        for k in 0..3 {
            position.push(if k < dim { centred(r[k], l[k]) } else { 0.0 });
        }
    }
    let orientation: Vec<f64> = bodies.orientations.iter().flatten().copied().collect();
    let diameter: Vec<f64> = file.radii.iter().map(|r| 2.0 * r).collect();
    Ok(vec![
        Chunk::u64("configuration/step", step),
        Chunk::u8("configuration/dimensions", dim as u8),
        Chunk::f32("configuration/box", 1, &[l[0], l[1], lz, 0.0, 0.0, 0.0]),
        Chunk::u32("particles/N", &[file.particles as u32]),
        Chunk::strings("particles/types", &bodies.types),
        Chunk::u32("particles/typeid", &bodies.typeid),
        Chunk::strings("particles/type_shapes", &bodies.shapes),
        Chunk::f32("particles/diameter", 1, &diameter),
        Chunk::f32("particles/position", 3, &position),
        Chunk::f32("particles/orientation", 4, &orientation),
        Chunk::f64("log/jamkit/phi", 1, &[file.phi]),
        Chunk::f64(
            "log/jamkit/energy_per_particle",
            1,
            &[file.energy_per_particle],
        ),
    ])
}

/// The coordinate `x` of jamkit's box `[0, L)` in HOOMD's `[−L/2, L/2)`,
/// such that its float32 lies in `[−L/2, L/2)` of the float32 edge.
fn centred(x: f64, l: f64) -> f64 {
    let mut c = x - l * (x / l).floor() - 0.5 * l;
    let half = (l as f32) / 2.0;
    if c as f32 >= half {
        c -= l;
    }
    if (c as f32) < -half {
        c = -(half as f64);
    }
    c
}

/// An empty GSD file of the `hoomd` schema, written by this jamkit (the
/// header's application): append [`frame`]s to it.
pub fn writer() -> Writer {
    Writer::new(
        &jamkit_format::provenance::describe(),
        "hoomd",
        SCHEMA_VERSION,
    )
}

/// A GSD file holding `files`, one frame each, in order.
pub fn file(files: &[PackingFile]) -> Result<Vec<u8>, ExperimentError> {
    let mut writer = writer();
    for (k, f) in files.iter().enumerate() {
        writer.frame(frame(f, k as u64)?)?;
    }
    Ok(writer.to_bytes()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shepperd's method gives back the quaternion of each rotation,
    /// whichever component is largest.
    #[test]
    fn quaternion_of_a_matrix_is_the_rotations() {
        let h = 0.5f64.sqrt();
        for q in [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [h, 0.0, 0.0, h],
            [0.5, -0.5, 0.5, 0.5],
            [0.1, 0.7, -0.5, 0.5],
        ] {
            let n = q.iter().map(|v: &f64| v * v).sum::<f64>().sqrt();
            let q = q.map(|v| v / n);
            let rows = Quaternion::from_coords(&q).unwrap().rows();
            let back = from_rows(rows);
            // q and −q are the same rotation
            let dot: f64 = back.iter().zip(&q).map(|(a, b)| a * b).sum();
            for k in 0..4 {
                assert!(
                    (back[k] - dot.signum() * q[k]).abs() < 1e-14,
                    "{q:?} → {back:?}"
                );
            }
            assert!(back[0] >= 0.0);
            // and `rotate` turns as the matrix does
            let v = [0.3, -1.2, 0.7];
            let turned = rotate(q, v);
            for r in 0..3 {
                let want: f64 = (0..3).map(|c| rows[r][c] * v[c]).sum();
                assert!((turned[r] - want).abs() < 1e-14);
            }
        }
    }

    /// The mesh of the unit sphere is closed and outward: its signed
    /// volume is positive and within the inscribed polyhedron's deficit
    /// of 4π/3 (the chords cut inside, by less than 1 %).
    #[test]
    fn mesh_is_closed_and_faces_outward() {
        let (v, f) = mesh(|_| 1.0);
        assert_eq!(v.len(), 2 + (MESH_RINGS - 1) * MESH_SEGMENTS);
        assert_eq!(f.len(), 2 * MESH_SEGMENTS * (MESH_RINGS - 1));
        let volume: f64 = f
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| v[i as usize]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum();
        let sphere = 4.0 * PI / 3.0;
        assert!(volume > 0.98 * sphere && volume < sphere, "{volume}");
        // every edge is shared by exactly two triangles, in opposite directions
        let mut edges = std::collections::HashMap::new();
        for t in &f {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1));
        }
    }

    /// Centres land in `[−L/2, L/2)` of the float32 box, also at its ends.
    #[test]
    fn centred_positions_stay_in_the_float32_box() {
        let l = 10.3;
        let half = (l as f32) / 2.0;
        for x in [0.0, 1e-17, 5.15, l - 1e-15, l, -1e-15, 3.0, 20.0, -7.0] {
            let c = centred(x, l) as f32;
            assert!(c >= -half && c < half, "{x} → {c}");
        }
        assert_eq!(centred(3.0, 10.0), -2.0);
        assert_eq!(centred(7.5, 10.0), 2.5);
    }
}
