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
}
