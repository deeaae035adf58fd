//! Packings as extended XYZ, the format OVITO and ASE read.
//!
//! One frame per packing: the body count, a comment line with the box as
//! `Lattice` (3 × 3, row by row; a 2D box gets `L_z = 1` and `pbc="T T F"`),
//! the column list (`Properties=`), and the packing's id, family, φ and
//! `V/N`; then one line per body (per sphere for bodies made of spheres):
//!
//! | column | meaning |
//! |---|---|
//! | `species` | `B` for a body; `S` for one sphere of a rigid body |
//! | `pos` | the centre, three coordinates (`z = 0` in 2D) |
//! | `radius` | the size `R⁰` (the sphere's radius for a rigid body's sphere) |
//! | `orientation` | the rotation as a unit quaternion in OVITO's order `(x, y, z, w)`: a planar angle θ is `(0, 0, sin θ/2, cos θ/2)` |
//! | `angle` | planar families: θ itself (radians), for colouring |
//! | `aspherical_shape` | families whose shape gives [`Look::ellipsoid_axes`](jamkit_core::Look::ellipsoid_axes): ellipses the semi-axes `(a, b, b)`, `a = R⁰√α`, `b = R⁰/√α`; ellipsoids `R⁰ (ξ_x, ξ_y, ξ_z)` along the body axes |
//! | `body` | rigid bodies: the body a sphere belongs to |
//! | `contacts` | the body's contacts (`h < 0`), each contact counted at both bodies |
//! | `rattler` | 1 for a rattler, 0 otherwise (only when contacts were measured) |
//!
//! Numbers are written in Rust's shortest form that reads back to the same
//! double, so nothing is lost.

use crate::error::ExperimentError;
use crate::reload::{PackingVisitor, reload};
use jamkit_core::Shape;
use jamkit_engine::Scene;
use jamkit_format::PackingFile;
use std::fmt::Write;

/// What the frame needs of the packing's shape: contacts per body
/// (`h < 0`), and the semi-axes per unit size if its family's shape is an
/// ellipse or ellipsoid ([`Look::ellipsoid_axes`](jamkit_core::Look::ellipsoid_axes)).
fn contacts_and_axes(
    file: &PackingFile,
) -> Result<(Vec<usize>, Option<[f64; 3]>), ExperimentError> {
    struct Count;
    impl PackingVisitor for Count {
        type Output = (Vec<usize>, Option<[f64; 3]>);
        fn visit<const D: usize, S: Shape<D>>(self, mut scene: Scene<D, S>) -> Self::Output {
            let mut count = vec![0; scene.packing().positions.len()];
            scene.for_each_contact(0.0, |i, j, _, c| {
                if c.gap < 0.0 {
                    count[i] += 1;
                    count[j] += 1;
                }
            });
            (count, scene.packing().shape.look().ellipsoid_axes)
        }
    }
    reload(file, Count)
}

/// Refuse to export `file` to `format` unless it is a valid packing file
/// holding its configuration, in 2D or 3D.
pub(crate) fn exportable(file: &PackingFile, format: &str) -> Result<(), ExperimentError> {
    file.check_as(format_args!("packing {}", file.id))?;
    if file.positions.len() != file.particles {
        return Err(ExperimentError::invalid(
            format!("packing {}: positions", file.id),
            "[]",
            "export needs the configuration (the run had output.packings = false)",
        ));
    }
    if !(2..=3).contains(&file.dim) {
        return Err(ExperimentError::invalid(
            format!("packing {}: dim", file.id),
            file.dim,
            format!("{format} holds 2D and 3D packings"),
        ));
    }
    Ok(())
}

/// One frame of extended XYZ for `file`.
pub fn frame(file: &PackingFile) -> Result<String, ExperimentError> {
    exportable(file, "extended XYZ")?;
    let (contacts, semi_axes) = contacts_and_axes(file)?;
    let dim = file.dim;
    let planar = dim == 2 && file.orientations.first().is_some_and(|o| o.len() == 1);
    let quaternion = dim == 3 && file.orientations.first().is_some_and(|o| o.len() == 4);
    let rigid = !file.spheres.is_empty();
    // Semi-axes per unit size along the body axes, from the shape's
    // optional ability (ellipses (a, b, b), ellipsoids their ratios ξ).
    let rattlers = file.rattler.len() == file.particles;

    let mut props = String::from("species:S:1:pos:R:3:radius:R:1");
    if planar || quaternion {
        props.push_str(":orientation:R:4");
    }
    if planar {
        props.push_str(":angle:R:1");
    }
    if semi_axes.is_some() {
        props.push_str(":aspherical_shape:R:3");
    }
    if rigid {
        props.push_str(":body:I:1");
    }
    props.push_str(":contacts:I:1");
    if rattlers {
        props.push_str(":rattler:I:1");
    }
    let l = &file.box_edges;
    let (lz, pbc) = if dim == 2 {
        (1.0, "T T F")
    } else {
        (l[2], "T T T")
    };
    let rows = if rigid {
        file.spheres.len()
    } else {
        file.particles
    };
    let mut out = String::new();
    let _ = writeln!(out, "{rows}");
    let _ = writeln!(
        out,
        "Lattice=\"{} 0 0 0 {} 0 0 0 {lz}\" Properties={props} pbc=\"{pbc}\" id={} family={} phi={} energy_per_particle={:e}",
        l[0], l[1], file.id, file.family, file.phi, file.energy_per_particle
    );
    // The orientation columns of body `b`.
    let orientation = |b: usize| -> String {
        let o = file.orientations.get(b).map(Vec::as_slice).unwrap_or(&[]);
        match o {
            [theta] if planar => {
                let (s, c) = (0.5 * theta).sin_cos();
                format!(" 0 0 {s} {c} {theta}")
            }
            [w, x, y, z] if quaternion => format!(" {x} {y} {z} {w}"),
            _ => String::new(),
        }
    };
    let tail = |b: usize| -> String {
        let mut t = String::new();
        if let Some(xi) = semi_axes {
            let r = file.radii[b];
            let _ = write!(t, " {} {} {}", r * xi[0], r * xi[1], r * xi[2]);
        }
        if rigid {
            let _ = write!(t, " {b}");
        }
        let _ = write!(t, " {}", contacts[b]);
        if rattlers {
            let _ = write!(t, " {}", u8::from(file.rattler[b]));
        }
        t
    };
    if rigid {
        for s in &file.spheres {
            let b = s[dim + 1] as usize;
            let z = if dim == 2 { 0.0 } else { s[2] };
            let _ = writeln!(
                out,
                "S {} {} {z} {}{}{}",
                s[0],
                s[1],
                s[dim],
                orientation(b),
                tail(b)
            );
        }
    } else {
        for (b, r) in file.positions.iter().enumerate() {
            let z = if dim == 2 { 0.0 } else { r[2] };
            let _ = writeln!(
                out,
                "B {} {} {z} {}{}{}",
                r[0],
                r[1],
                file.radii[b],
                orientation(b),
                tail(b)
            );
        }
    }
    Ok(out)
}
