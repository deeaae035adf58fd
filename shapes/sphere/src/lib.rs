//! # The `sphere` family
//!
//! Disks in 2D, spheres in 3D, hyperspheres in any `D`: a body of size `R`
//! is the ball of radius `R`. The gap between two balls is
//!
//! ```text
//! h_ij = |r_ij| − R_i − R_j,     ∂h/∂r_j = r̂_ij = −∂h/∂r_i,
//!
//! ∂²h/∂r_j∂r_j = (1 − r̂ r̂ᵀ) / |r_ij|
//! ```
//!
//! and a ball has no rotational coordinates: a sphere scene carries only
//! `D` coordinates per body.

use jamkit_core::math::unit_ball_volume;
use jamkit_core::{
    Contact, Dims, Family, FamilyInfo, FastContacts, GapHessian, Look, Matrix, Pair, RoundOutline,
    Shape, ShapeVisitor, Vector,
};

/// The family's self-description for the registry.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "sphere",
    about: "disks (2D), spheres (3D), hyperspheres: the ball of radius R0; no parameters, no rotations",
    dims: Dims::Any,
    params: &[],
};

/// The family's registration.
pub struct SphereFamily;

/// The parameters of a family that has none.
#[derive(Clone, Copy, Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoParams {}

impl Family for SphereFamily {
    const INFO: FamilyInfo = INFO;
    const EXAMPLE: &'static str = "()";
    type Params = NoParams;

    fn visit<V: ShapeVisitor>(
        _params: &NoParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        visit_ball(dim, visitor)
    }
}

/// Hand the ball to `visitor` in dimension `dim` (2, 3 or 4, the dimensions
/// the engine is compiled for): the sphere family, and the degenerate case
/// of the families whose bodies become balls (a near-disk with `Δ = 0`, an
/// ellipse with `α = 1`, a dimer with `α = 1`), which then run with no
/// rotational coordinates and the same random stream as `sphere`.
pub fn visit_ball<V: ShapeVisitor>(dim: usize, visitor: V) -> jamkit_core::Result<V::Output> {
    match dim {
        2 => Ok(visitor.visit::<2, _>(Sphere)),
        3 => Ok(visitor.visit::<3, _>(Sphere)),
        4 => Ok(visitor.visit::<4, _>(Sphere)),
        _ => Err(jamkit_core::Error::invalid(
            "dim",
            dim,
            "the engine is compiled for dim 2, 3 and 4",
        )),
    }
}

/// Balls in `D` dimensions; the family has no parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sphere;

impl<const D: usize> Shape<D> for Sphere {
    type Orientation = ();
    type Fast = Self;

    fn family(&self) -> &'static str {
        "sphere"
    }

    fn rot_dof(&self) -> usize {
        0
    }

    fn volume(&self, size: f64) -> f64 {
        unit_ball_volume(D) * size.powi(D as i32)
    }

    fn bounding_radius(&self, size: f64) -> f64 {
        size
    }

    fn rotate(&self, _orientation: &mut (), _dq: &[f64]) {}

    #[inline(always)]
    fn contacts<F: FnMut(Contact<D>)>(&self, pair: &Pair<D, ()>, _max_gap: f64, mut visit: F) {
        let size_i = pair.size_i;
        let size_j = pair.size_j;
        let r_ij = &pair.r_ij;
        // The exact gap is as cheap as any bound on it: always report it.
        let r = r_ij.norm();
        // NOTE: coincident centres have no direction; any unit vector is a
        // valid subgradient, and a fixed one keeps the run deterministic.
        let unit = if r > 0.0 {
            r_ij * (1.0 / r)
        } else {
            Vector::<D>::from_fn(|a, _| if a == 0 { 1.0 } else { 0.0 })
        };
        visit(Contact::translational(r - size_i - size_j, unit));
    }

    fn gap_hessians<F: FnMut(GapHessian<D>)>(
        &self,
        pair: &Pair<D, ()>,
        max_gap: f64,
        mut visit: F,
    ) -> jamkit_core::Result<()> {
        let r_ij = &pair.r_ij;
        let mut first = None;
        self.contacts(pair, max_gap, |c| first = Some(c));
        if let Some(c) = first {
            let r = r_ij.norm();
            // NOTE: at coincident centres the curvature 1/|r| is infinite;
            // such a pair has no defined Hessian, and zero keeps it finite.
            let rr = if r > 0.0 {
                (Matrix::<D>::identity() - c.grad_r * c.grad_r.transpose()) / r
            } else {
                Matrix::<D>::zeros()
            };
            visit(GapHessian::translational(c.gap, c.grad_r, rr));
        }
        Ok(())
    }

    fn look(&self) -> Look {
        Look {
            ball: true,
            outline: Some(std::sync::Arc::new(RoundOutline)),
            ..Look::default()
        }
    }
}

/// The engine's kernel for balls, several pairs per instruction.
impl<const D: usize> FastContacts<D, Sphere> for Sphere {
    const BALL: bool = true;
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn gap_of_touching_disks_is_zero() {
        let mut h = f64::NAN;
        Shape::<2>::contacts(
            &Sphere,
            &Pair::new(0.5, (), 0.7, (), Vector::<2>::new(0.0, 1.2)),
            0.0,
            |c| h = c.gap,
        );
        assert_relative_eq!(h, 0.0, epsilon = 1e-15);
    }

    #[test]
    fn volumes_are_disk_area_and_ball_volume() {
        assert_relative_eq!(
            Shape::<2>::volume(&Sphere, 0.5),
            std::f64::consts::PI * 0.25
        );
        assert_relative_eq!(
            Shape::<3>::volume(&Sphere, 2.0),
            4.0 / 3.0 * std::f64::consts::PI * 8.0
        );
    }
}
