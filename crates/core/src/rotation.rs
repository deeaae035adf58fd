//! One 2D orientation type for the planar families.
//!
//! A planar body's orientation is the rotation by `θ`, stored as the unit
//! complex number `e^{iθ} = (cos θ, sin θ)`: the pair loops need nothing
//! else, and `θ = atan2(sin θ, cos θ)` in `(−π, π]` is recovered for output.
//! [`Rotation2`] carries the orientation methods that every planar family
//! with one angle writes the same way (the reference, a uniformly random
//! one, the coordinates written to a packing file and read back), and two
//! ways to turn by an increment `dθ`:
//!
//! * [`Rotation2::turned`]: small turns from the Taylor series of `e^{i dθ}`
//!   ([`turn_unit`](crate::math::turn_unit)), the near-disks' choice (a
//!   `sin_cos` per body and FIRE step cost a sixth of a near-disk step);
//! * [`Rotation2::turned_exact`]: `e^{iθ} e^{i dθ}` by `sin_cos`, the
//!   choice of bodies made of spheres (`nmer`).
//!
//! Both renormalise `|z| = 1` to round-off. The two give results that
//! differ in the last bits, so a family keeps the one its recorded packings
//! were made with.
//!
//! [`Angle`] is the other planar orientation: it accumulates `θ` itself
//! (wrapped into `(−π, π]`) and caches `cos Kθ` and `sin Kθ` by `sin_cos`
//! after every turn, for families whose pair loop needs a multiple of the
//! angle: `K = 1` for the profiled near-disks (`lobed`), `K = 2` for
//! `ellipse` (symmetric under `θ → θ + π`). Their packings were made this
//! way, so they keep it rather than [`Rotation2`].

use crate::math::{Unit, Vector, turn_unit, unit_of_angle};
use rand::{Rng, RngExt};
use std::f64::consts::PI;

/// A rotation of the plane by `θ`, stored as `e^{iθ}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotation2 {
    cos: f64,
    sin: f64,
}

impl Rotation2 {
    /// The rotation by `θ` (radians).
    pub fn new(theta: f64) -> Self {
        // NOTE: wrapping first keeps sin/cos accurate for angles that have
        // wound many turns; θ and θ + 2π are the same orientation.
        let (cos, sin) = unit_of_angle(theta);
        Self { cos, sin }
    }

    /// A uniformly random rotation: `θ = 2π u − π`, `u` uniform in `[0, 1)`.
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> Self {
        Self::new(2.0 * PI * rng.random::<f64>() - PI)
    }

    /// `θ` in `(−π, π]`.
    pub fn theta(&self) -> f64 {
        self.sin.atan2(self.cos)
    }

    /// `e^{iθ} = (cos θ, sin θ)`.
    #[inline(always)]
    pub fn unit(&self) -> Unit {
        (self.cos, self.sin)
    }

    /// Turn by `dθ`, small turns by the Taylor series of `e^{i dθ}`
    /// ([`turn_unit`]).
    #[inline]
    pub fn turned(self, dtheta: f64) -> Self {
        let (cos, sin) = turn_unit((self.cos, self.sin), dtheta);
        Self { cos, sin }
    }

    /// Turn by `dθ`: `e^{iθ} e^{i dθ}` with `e^{i dθ}` by `sin_cos`,
    /// renormalised (one Newton step for `1/|z|`, exact to round-off since
    /// `|z| = 1 + O(10⁻¹⁶)`).
    pub fn turned_exact(self, dtheta: f64) -> Self {
        let (s, c) = dtheta.sin_cos();
        let cos = self.cos * c - self.sin * s;
        let sin = self.cos * s + self.sin * c;
        let fix = 1.5 - 0.5 * (cos * cos + sin * sin);
        Self {
            cos: cos * fix,
            sin: sin * fix,
        }
    }

    /// `R(θ) s`.
    #[inline(always)]
    pub fn apply(&self, s: &Vector<2>) -> Vector<2> {
        Vector::<2>::new(
            self.cos * s[0] - self.sin * s[1],
            self.sin * s[0] + self.cos * s[1],
        )
    }

    /// The coordinates written to a packing file: `[θ]`.
    pub fn coords(&self) -> Vec<f64> {
        vec![self.theta()]
    }

    /// The inverse of [`Rotation2::coords`]: one finite angle, else `None`.
    pub fn from_coords(coords: &[f64]) -> Option<Self> {
        match coords {
            [theta] if theta.is_finite() => Some(Self::new(*theta)),
            _ => None,
        }
    }
}

/// A planar orientation that accumulates `θ` and caches `e^{iKθ}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angle<const K: u32> {
    theta: f64,
    cos: f64,
    sin: f64,
}

impl<const K: u32> Angle<K> {
    /// The orientation `θ`, wrapped into `(−π, π]`.
    pub fn new(theta: f64) -> Self {
        // NOTE: wrapping keeps sin/cos accurate for bodies that have turned
        // many times; θ and θ + 2π are the same orientation.
        let mut theta = theta - 2.0 * PI * (theta / (2.0 * PI)).round();
        if theta <= -PI {
            theta += 2.0 * PI;
        }
        let (sin, cos) = (K as f64 * theta).sin_cos();
        Self { theta, cos, sin }
    }

    /// A uniformly random orientation: `θ = 2π u − π`, `u` uniform in
    /// `[0, 1)`.
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> Self {
        Self::new(2.0 * PI * rng.random::<f64>() - PI)
    }

    /// `θ` in `(−π, π]`.
    #[inline(always)]
    pub fn theta(&self) -> f64 {
        self.theta
    }

    /// `e^{iKθ} = (cos Kθ, sin Kθ)`.
    #[inline(always)]
    pub fn unit(&self) -> Unit {
        (self.cos, self.sin)
    }

    /// Turned by `dθ` (θ accumulated, then `sin_cos`).
    #[inline]
    pub fn turned(self, dtheta: f64) -> Self {
        Self::new(self.theta + dtheta)
    }

    /// The coordinates written to a packing file: `[θ]`.
    pub fn coords(&self) -> Vec<f64> {
        vec![self.theta]
    }

    /// The inverse of [`Angle::coords`]: one finite angle, else `None`.
    pub fn from_coords(coords: &[f64]) -> Option<Self> {
        match coords {
            [theta] if theta.is_finite() => Some(Self::new(*theta)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn both_turns_wrap_and_agree_to_round_off() {
        let (mut a, mut b) = (Rotation2::new(3.0), Rotation2::new(3.0));
        for _ in 0..1000 {
            a = a.turned(0.01);
            b = b.turned_exact(0.01);
        }
        let want = 13.0 - 4.0 * PI;
        assert_relative_eq!(a.theta(), want, epsilon = 1e-12);
        assert_relative_eq!(b.theta(), want, epsilon = 1e-12);
        let s = Rotation2::new(0.5).apply(&Vector::<2>::new(1.0, 0.0));
        assert_relative_eq!(s, Vector::<2>::new(0.5f64.cos(), 0.5f64.sin()));
    }

    #[test]
    fn angles_wrap_cache_their_multiple_and_round_trip() {
        let mut a = Angle::<2>::new(3.0);
        a = a.turned(0.5);
        assert_relative_eq!(a.theta(), 3.5 - 2.0 * PI, epsilon = 1e-15);
        assert_relative_eq!(a.unit().0, 7.0f64.cos(), epsilon = 1e-14);
        assert_relative_eq!(a.unit().1, 7.0f64.sin(), epsilon = 1e-14);
        // −π is the same orientation as π: kept in (−π, π].
        assert_eq!(Angle::<1>::new(-PI).theta(), PI);
        assert_eq!(
            Angle::<1>::from_coords(&a.coords()),
            Some(Angle::<1>::new(a.theta()))
        );
        assert!(Angle::<1>::from_coords(&[f64::NAN]).is_none());
        assert!(Angle::<1>::from_coords(&[0.1, 0.2]).is_none());
    }

    #[test]
    fn coordinates_round_trip_and_bad_ones_are_refused() {
        let a = Rotation2::new(-2.5);
        let b = Rotation2::from_coords(&a.coords()).unwrap();
        assert_relative_eq!(a.theta(), b.theta(), epsilon = 1e-15);
        assert!(Rotation2::from_coords(&[f64::NAN]).is_none());
        assert!(Rotation2::from_coords(&[1.0, 2.0]).is_none());
        assert!(Rotation2::from_coords(&[]).is_none());
    }
}
