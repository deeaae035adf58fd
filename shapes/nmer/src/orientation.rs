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

use jamkit_core::Vector;

/// A 2D orientation: the shared planar rotation `e^{iθ}`
/// ([`jamkit_core::Rotation2`]); bodies made of spheres turn it by
/// [`Rotation2::turned_exact`](jamkit_core::Rotation2::turned_exact).
pub type Angle = jamkit_core::Rotation2;

/// A 3D orientation: the unit quaternion `w + x i + y j + z k`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    w: f64,
    x: f64,
    y: f64,
    z: f64,
}

impl Quaternion {
    /// The identity rotation.
    pub const IDENTITY: Self = Self {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// `(w, x, y, z)` normalised; `None` for a zero or non-finite input.
    pub fn normalized(w: f64, x: f64, y: f64, z: f64) -> Option<Self> {
        let n = (w * w + x * x + y * y + z * z).sqrt();
        (n > 0.0 && n.is_finite()).then(|| Self {
            w: w / n,
            x: x / n,
            y: y / n,
            z: z / n,
        })
    }

    /// `(w, x, y, z)`.
    pub fn coords(&self) -> [f64; 4] {
        [self.w, self.x, self.y, self.z]
    }

    /// `exp(ω)`: the rotation by the angle `|ω|` about `ω̂`,
    /// `(cos(|ω|/2), sin(|ω|/2) ω̂)`.
    ///
    /// NOTE: for `|ω| < 10⁻⁴` the Taylor series `sin(a/2)/a = ½ − a²/48`
    /// (next term `a⁴/3840 < 3·10⁻²⁰`) avoids dividing by a tiny angle.
    pub fn exp(omega: &Vector<3>) -> Self {
        let a2 = omega.norm_squared();
        let (c, k) = if a2 < 1e-8 {
            (1.0 - a2 / 8.0, 0.5 - a2 / 48.0)
        } else {
            let a = a2.sqrt();
            let (s, c) = (0.5 * a).sin_cos();
            (c, s / a)
        };
        Self {
            w: c,
            x: k * omega[0],
            y: k * omega[1],
            z: k * omega[2],
        }
    }

    /// The Hamilton product `self ∘ other` (apply `other` first).
    pub fn mul(&self, o: &Self) -> Self {
        Self {
            w: self.w * o.w - self.x * o.x - self.y * o.y - self.z * o.z,
            x: self.w * o.x + self.x * o.w + self.y * o.z - self.z * o.y,
            y: self.w * o.y - self.x * o.z + self.y * o.w + self.z * o.x,
            z: self.w * o.z + self.x * o.y - self.y * o.x + self.z * o.w,
        }
    }

    /// Rescale to unit norm (after a product, `|q| = 1 + O(10⁻¹⁶)`).
    pub fn renormalized(self) -> Self {
        let n2 = self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z;
        let inv = 1.0 / n2.sqrt();
        Self {
            w: self.w * inv,
            x: self.x * inv,
            y: self.y * inv,
            z: self.z * inv,
        }
    }

    /// The rotation matrix `R(o)`, as its three columns `R x̂, R ŷ, R ẑ`.
    #[inline(always)]
    pub fn columns(&self) -> [Vector<3>; 3] {
        let (w, x, y, z) = (self.w, self.x, self.y, self.z);
        [
            Vector::<3>::new(
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y + w * z),
                2.0 * (x * z - w * y),
            ),
            Vector::<3>::new(
                2.0 * (x * y - w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z + w * x),
            ),
            Vector::<3>::new(
                2.0 * (x * z + w * y),
                2.0 * (y * z - w * x),
                1.0 - 2.0 * (x * x + y * y),
            ),
        ]
    }

    /// `R(o) s`.
    #[inline(always)]
    pub fn apply(&self, s: &Vector<3>) -> Vector<3> {
        let [a, b, c] = self.columns();
        a * s[0] + b * s[1] + c * s[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

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
