//! The 3D orientation shared by the 3D rigid families: a unit quaternion.
//!
//! A body's orientation is the rotation `R(o)` that carries body-frame
//! vectors to the world frame. The engine steps orientations by small
//! rotation vectors `ω` (FIRE sees increments, never the stored
//! representation): `o → exp(ω) ∘ o` for `ω` in the world frame, or
//! `o → o ∘ exp(ω_b)` for `ω_b` in the body frame (the same rotation,
//! since `o ∘ exp(ω_b) = exp(R(o) ω_b) ∘ o`). Bodies made of spheres
//! (`nmer`) and the spherical-harmonic near-spheres (`harmonic`) use it.

use crate::math::Vector;
use rand::{Rng, RngExt};
use std::f64::consts::PI;

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

    /// A rotation uniform on the rotation group (Shoemake 1992): from
    /// three uniform numbers `u₁, u₂, u₃` (drawn in this order),
    /// `q = (√(1−u₁) sin 2πu₂, √(1−u₁) cos 2πu₂, √u₁ sin 2πu₃, √u₁ cos 2πu₃)`.
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> Self {
        let (u1, u2, u3) = (
            rng.random::<f64>(),
            rng.random::<f64>(),
            rng.random::<f64>(),
        );
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let (s2, c2) = (2.0 * PI * u2).sin_cos();
        let (s3, c3) = (2.0 * PI * u3).sin_cos();
        Self::normalized(a * s2, a * c2, b * s3, b * c3).unwrap_or(Self::IDENTITY)
    }

    /// The inverse rotation `o⁻¹ = (w, −x, −y, −z)`.
    pub fn conjugate(&self) -> Self {
        Self {
            w: self.w,
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }

    /// `R(o)ᵀ v`: a world vector in the body frame.
    #[inline(always)]
    pub fn apply_inverse(&self, v: &Vector<3>) -> Vector<3> {
        let [a, b, c] = self.columns();
        Vector::<3>::new(a.dot(v), b.dot(v), c.dot(v))
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

    /// One step of the rotational coordinates `dq` of a body:
    /// `o → exp(ω) o` with `ω = (dq₀, dq₁, dq₂)` in the world frame, or, for
    /// a body symmetric about its own z axis (`axial`, two coordinates),
    /// `o → o exp((dq₀, dq₁, 0))` in the body frame; then renormalised.
    pub fn stepped(&self, dq: &[f64], axial: bool) -> Self {
        if axial {
            self.mul(&Self::exp(&Vector::<3>::new(dq[0], dq[1], 0.0)))
        } else {
            Self::exp(&Vector::<3>::new(dq[0], dq[1], dq[2])).mul(self)
        }
        .renormalized()
    }

    /// The rotation axes `e_p` of the coordinates [`Quaternion::stepped`]
    /// steps, from the columns of `R(o)`: the world axes, or the body's own
    /// `R(o) x̂, R(o) ŷ` (and `R(o) ẑ`, unused) for an `axial` body.
    #[inline(always)]
    pub fn step_axes(columns: &[Vector<3>; 3], axial: bool) -> [Vector<3>; 3] {
        if axial {
            *columns
        } else {
            [Vector::<3>::x(), Vector::<3>::y(), Vector::<3>::z()]
        }
    }

    /// The orientation stored as `[w, x, y, z]` ([`Quaternion::coords`]):
    /// four numbers of norm 1 to 10⁻⁶, renormalised; `None` otherwise.
    pub fn from_coords(coords: &[f64]) -> Option<Self> {
        match coords {
            [w, x, y, z] if ((w * w + x * x + y * y + z * z).sqrt() - 1.0).abs() < 1e-6 => {
                Self::normalized(*w, *x, *y, *z)
            }
            _ => None,
        }
    }

    /// The rotation matrix by rows (`rows()[r][k]` = `columns()[k][r]`).
    pub fn rows(&self) -> [[f64; 3]; 3] {
        let c = self.columns();
        std::array::from_fn(|r| std::array::from_fn(|k| c[k][r]))
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
    use rand::SeedableRng;

    /// `Rᵀ v` by the columns is the conjugate's rotation and undoes `R v`
    /// (1e-15: round-off of a few products of unit numbers).
    #[test]
    fn inverse_rotation_is_the_conjugate() {
        let q = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let v = Vector::<3>::new(0.4, -1.3, 0.8);
        let a = q.apply_inverse(&v);
        let b = q.conjugate().apply(&v);
        assert!((a - b).norm() < 1e-15);
        assert!((q.apply(&a) - v).norm() < 1e-15);
    }

    /// Random rotations are unit quaternions and carry `ẑ` uniformly over
    /// the sphere: over 20 000 draws the mean of `R ẑ` is 0 and the mean of
    /// each squared component 1/3, within 5 standard errors
    /// (`√(1/3/20000) ≈ 0.004` and `√(4/45/20000) ≈ 0.002`).
    #[test]
    fn random_rotations_are_uniform() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let n = 20_000;
        let (mut mean, mut sq) = (Vector::<3>::zeros(), Vector::<3>::zeros());
        for _ in 0..n {
            let q = Quaternion::random(&mut rng);
            let c = q.coords();
            let norm: f64 = c.iter().map(|x| x * x).sum();
            assert!((norm - 1.0).abs() < 1e-15);
            let z = q.apply(&Vector::<3>::z());
            mean += z / n as f64;
            sq += z.component_mul(&z) / n as f64;
        }
        for a in 0..3 {
            assert!(mean[a].abs() < 5.0 * 0.0041, "mean {mean:?}");
            assert!((sq[a] - 1.0 / 3.0).abs() < 5.0 * 0.0021, "squares {sq:?}");
        }
    }
}
