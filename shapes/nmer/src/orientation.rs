//! Orientations of rigid bodies: an angle in 2D, a unit quaternion in 3D.
//!
//! A body's spheres sit at fixed body-frame offsets `s_a`; its orientation
//! is the rotation `R(o)` that carries them to the world frame. The engine
//! steps orientations by *increments* (FIRE sees small angles, never the
//! stored representation):
//!
//! * 2D: `θ → θ + dθ`, stored as `e^{iθ} = (cos θ, sin θ)`;
//! * 3D: `o → exp(ω) ∘ o` with `ω` a rotation vector in the **world**
//!   frame (for bodies with three rotational coordinates), or
//!   `o → o ∘ exp(ω_b)` with `ω_b = (dq₀, dq₁, 0)` in the **body** frame
//!   (linear bodies, whose axis is the body `z` axis: the two increments
//!   turn the axis about the world axes `R(o) x̂` and `R(o) ŷ`, both
//!   perpendicular to it). The two forms are the same rotation, since
//!   `o ∘ exp(ω_b) = exp(R(o) ω_b) ∘ o`.
//!
//! Quaternions are renormalised after every increment, so `|o| = 1` to
//! round-off however many steps accumulate.

/// A 2D orientation: the shared planar rotation `e^{iθ}`
/// ([`jamkit_core::Rotation2`]); bodies made of spheres turn it by
/// [`Rotation2::turned_exact`](jamkit_core::Rotation2::turned_exact).
pub type Angle = jamkit_core::Rotation2;

/// A 3D orientation: the unit quaternion, shared with the other 3D
/// families ([`jamkit_core::Quaternion`]).
pub use jamkit_core::Quaternion;

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::Vector;

    /// `exp(ω)` rotates a vector by Rodrigues' formula, for angles on both
    /// sides of the series threshold.
    #[test]
    fn quaternion_exponential_is_rodrigues() {
        let v = Vector::<3>::new(0.3, -1.2, 0.7);
        for scale in [1e-9, 1e-5, 1e-3, 0.4, 2.5] {
            let omega = Vector::<3>::new(0.6, 0.2, -0.77).normalize() * scale;
            let a = omega.norm();
            let k = omega / a;
            let rodrigues = v * a.cos() + k.cross(&v) * a.sin() + k * (k.dot(&v) * (1.0 - a.cos()));
            let q = Quaternion::exp(&omega);
            assert_relative_eq!(q.apply(&v), rodrigues, epsilon = 1e-15);
        }
    }

    /// `(p ∘ q)(v) = p(q(v))`, and the columns form a rotation.
    #[test]
    fn product_composes_rotations() {
        let p = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let q = Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap();
        let v = Vector::<3>::new(1.0, 2.0, -0.5);
        assert_relative_eq!(p.mul(&q).apply(&v), p.apply(&q.apply(&v)), epsilon = 1e-14);
        let [a, b, c] = p.columns();
        assert_relative_eq!(a.cross(&b), c, epsilon = 1e-15);
        assert_relative_eq!(a.norm(), 1.0, epsilon = 1e-15);
    }

    /// `o ∘ exp(ω_b) = exp(R(o) ω_b) ∘ o`: body-frame and world-frame
    /// increments describe the same rotation.
    #[test]
    fn body_and_world_increments_agree() {
        let o = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let wb = Vector::<3>::new(0.02, -0.05, 0.0);
        let v = Vector::<3>::new(0.4, 0.1, 1.0);
        let body = o.mul(&Quaternion::exp(&wb));
        let world = Quaternion::exp(&o.apply(&wb)).mul(&o);
        assert_relative_eq!(body.apply(&v), world.apply(&v), epsilon = 1e-15);
    }

    #[test]
    fn angles_turn_and_wrap() {
        let mut a = Angle::new(3.0);
        for _ in 0..1000 {
            a = a.turned_exact(0.01);
        }
        assert_relative_eq!(
            a.theta(),
            13.0 - 4.0 * std::f64::consts::PI,
            epsilon = 1e-12
        );
        let s = Angle::new(0.5).apply(&Vector::<2>::new(1.0, 0.0));
        assert_relative_eq!(s, Vector::<2>::new(0.5f64.cos(), 0.5f64.sin()));
    }
}
