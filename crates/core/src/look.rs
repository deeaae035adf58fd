//! How a family's bodies look, for the crates that draw and export them:
//! the [`Look`] a shape returns, with its planar [`Outline`] or 3D
//! [`Surface`].

use std::fmt::Debug;
use std::sync::Arc;

/// The outline of a planar body, for drawing: its radius in the direction
/// at angle `ψ` from its body frame, in units of its size `R⁰`. A body of
/// size `R⁰` and orientation `θ` reaches `R⁰ ρ(θ − φ)` in the lab direction
/// `φ` (the convention of the near-disks, `R(φ) = R⁰ [1 + Δ F(θ − φ)]`).
/// Only star-shaped bodies have one; a body made of spheres is drawn from
/// its [`Shape::sphere_decomposition`] instead.
pub trait Outline: Debug + Send + Sync {
    /// `ρ(ψ) = R(ψ)/R⁰`.
    fn relative_radius(&self, psi: f64) -> f64;
}

/// A disk's outline: `ρ = 1`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RoundOutline;

impl Outline for RoundOutline {
    fn relative_radius(&self, _psi: f64) -> f64 {
        1.0
    }
}

/// A shared outline (what [`Shape::outline`] returns).
pub type SharedOutline = Arc<dyn Outline>;

/// The surface of a star-shaped 3D body, for drawing (the 3D counterpart
/// of [`Outline`]): its radius in the body-frame direction `y` (a unit
/// vector), in units of its size `R⁰`, and how the body frame is turned
/// by the orientation a packing file stores. A body of size `R⁰`, centre
/// `c` and rotation `M` (body to world) is the set of points `c + s M y`
/// with `0 ≤ s ≤ R⁰ ρ(y)`. Bodies made of spheres have none; they are
/// drawn from [`Shape::sphere_decomposition`](crate::Shape::sphere_decomposition).
pub trait Surface: Debug + Send + Sync {
    /// `ρ(y) = R(y)/R⁰` at the body-frame unit vector `y`.
    fn relative_radius(&self, y: [f64; 3]) -> f64;
    /// Certain bounds `(min, max)` on `ρ` over the unit sphere, with
    /// `0 < min ≤ max`.
    fn relative_radius_bounds(&self) -> (f64, f64);
    /// The rotation from body to world frame, as a matrix (rows), of a body
    /// whose orientation is written `coords`
    /// ([`BodyOrientation::to_coords`](crate::BodyOrientation::to_coords));
    /// `None` if the numbers are not an orientation. By default the
    /// orientation is a unit quaternion `[w, x, y, z]`
    /// ([`Quaternion::from_coords`](crate::Quaternion::from_coords)), as
    /// for every 3D family that turns.
    fn rotation(&self, coords: &[f64]) -> Option<[[f64; 3]; 3]> {
        crate::Quaternion::from_coords(coords).map(|q| q.rows())
    }
}

/// A shared surface (a [`Look`]'s `surface`).
pub type SharedSurface = Arc<dyn Surface>;

/// How a family's bodies are drawn and exported
/// ([`Shape::look`](crate::Shape::look)): read by `jamkit-draw` (pictures)
/// and the extended XYZ export. Bodies made of spheres need none of it: they
/// are drawn from [`Shape::sphere_decomposition`](crate::Shape::sphere_decomposition).
#[derive(Clone, Debug, Default)]
pub struct Look {
    /// Balls of radius `R⁰` (drawn as circles or spheres).
    pub ball: bool,
    /// The planar outline of a 2D body.
    pub outline: Option<SharedOutline>,
    /// The surface of a star-shaped 3D body.
    pub surface: Option<SharedSurface>,
    /// The semi-axes of an ellipse or ellipsoid body along its body axes,
    /// per unit size `R⁰`. Exporters write them where a viewer draws
    /// ellipsoids (extended XYZ's `aspherical_shape`, OVITO); a planar body
    /// gives its third axis as the second.
    pub ellipsoid_axes: Option<[f64; 3]>,
}
