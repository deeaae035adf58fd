//! Numeric aliases: the one place that names `nalgebra`.
//!
//! Positions and separations are `Vector<D>`, a stack-allocated
//! `SVector<f64, D>`; the dimension is a const generic everywhere in jamkit.
//! Rotational coordinates of one body fit in a [`RotVec`]: at most three
//! (a rigid body in 3D), of which a family uses the first
//! [`Shape::rot_dof`](crate::Shape::rot_dof).

/// A point or displacement in `D` dimensions.
pub type Vector<const D: usize> = nalgebra::SVector<f64, D>;

/// A `D × D` matrix (second derivatives with respect to positions).
pub type Matrix<const D: usize> = nalgebra::SMatrix<f64, D, D>;

/// The largest number of rotational coordinates a body can have (3D rigid body).
pub const MAX_ROT: usize = 3;

/// Rotational coordinates (or their derivatives) of one body; entries beyond
/// the family's `rot_dof()` are zero and ignored.
pub type RotVec = [f64; MAX_ROT];

/// Volume of the unit ball in `d` dimensions, `π^{d/2} / Γ(d/2 + 1)`.
pub fn unit_ball_volume(d: usize) -> f64 {
    // Recurrence V_d = V_{d-2} · 2π/d with V_0 = 1, V_1 = 2: exact enough and
    // free of a Gamma function.
    match d {
        0 => 1.0,
        1 => 2.0,
        _ => unit_ball_volume(d - 2) * 2.0 * std::f64::consts::PI / d as f64,
    }
}

/// A unit complex number `e^{iθ} = (cos θ, sin θ)`: a direction in the
/// plane, turned without trigonometric calls by [`turn_unit`].
pub type Unit = (f64, f64);

/// Complex product `a b`.
#[inline(always)]
pub fn cmul(a: Unit, b: Unit) -> Unit {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

/// `e^{iθ}` of an angle, wrapped first so that angles that have wound many
/// turns keep full accuracy (θ and θ + 2π are the same direction).
#[inline]
pub fn unit_of_angle(theta: f64) -> Unit {
    let theta = theta - 2.0 * std::f64::consts::PI * (theta / (2.0 * std::f64::consts::PI)).round();
    let (sin, cos) = theta.sin_cos();
    (cos, sin)
}

/// `z e^{i dθ}`: turn the direction `z` by `dθ`. Small turns (`|dθ| < 10⁻²`)
/// multiply by `e^{i dθ}` from its Taylor series, exact in double precision
/// there (the next terms are below 3·10⁻²⁴), and renormalise by one Newton
/// step for `1/|z|`, so that `|z| = 1` to round-off however many turns
/// accumulate; larger turns go through the angle.
#[inline]
pub fn turn_unit(z: Unit, dtheta: f64) -> Unit {
    if dtheta.abs() >= 1e-2 {
        return unit_of_angle(z.1.atan2(z.0) + dtheta);
    }
    let x2 = dtheta * dtheta;
    let s = dtheta * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    let (cos, sin) = cmul(z, (c, s));
    let fix = 1.5 - 0.5 * (cos * cos + sin * sin);
    (cos * fix, sin * fix)
}

/// Gauss–Legendre nodes and weights on `[−1, 1]` (Newton on the Legendre
/// recurrence from the Chebyshev guesses, to round-off).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(n);
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pm) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        nodes.push(z);
        weights.push(2.0 / ((1.0 - z * z) * dp * dp));
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    #[test]
    fn unit_ball_volumes_match_closed_forms() {
        assert_relative_eq!(unit_ball_volume(2), PI, max_relative = 1e-15);
        assert_relative_eq!(unit_ball_volume(3), 4.0 * PI / 3.0, max_relative = 1e-15);
        assert_relative_eq!(unit_ball_volume(4), PI * PI / 2.0, max_relative = 1e-15);
    }

    /// Small turns accumulate to their sum: 10⁵ turns of ~1e-3 land within
    /// 1e-11 of the direction of the (compensated) total, and |z| = 1 to
    /// round-off (1e-15).
    #[test]
    fn small_turns_accumulate_exactly() {
        let mut z = super::unit_of_angle(0.3);
        let (mut sum, mut carry) = (0.3f64, 0.0f64);
        for k in 0..100_000 {
            let d = 1e-3 * ((k % 7) as f64 - 2.9);
            z = super::turn_unit(z, d);
            let y = d - carry;
            let t = sum + y;
            carry = (t - sum) - y;
            sum = t;
        }
        let w = super::unit_of_angle(sum);
        assert!((z.0 - w.0).abs() < 1e-11 && (z.1 - w.1).abs() < 1e-11);
        assert!((z.0 * z.0 + z.1 * z.1 - 1.0).abs() < 1e-15);
        // A large turn goes through the angle.
        let big = super::turn_unit((1.0, 0.0), 2.0);
        assert!((big.0 - 2f64.cos()).abs() < 1e-15 && (big.1 - 2f64.sin()).abs() < 1e-15);
    }
}
