//! The periodic box.
//!
//! An orthorhombic box `[0, L_1) × … × [0, L_D)` with periodic boundaries in
//! every direction. Separations use the minimum-image convention,
//! `d ← d − L ⌊d/L⌉`, which is exact as long as interactions are shorter than
//! half an edge; the engine refuses boxes smaller than that
//! (`Scene::check_box` in `jamkit-engine`).

use crate::math::Vector;
use serde::{Deserialize, Serialize};

/// An orthorhombic periodic box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PeriodicBox<const D: usize> {
    edges: Vector<D>,
    #[serde(skip, default = "Vector::zeros")]
    inv_edges: Vector<D>,
}

impl<const D: usize> PeriodicBox<D> {
    /// A box with the given edge lengths (all must be positive and finite).
    pub fn new(edges: Vector<D>) -> Self {
        debug_assert!(edges.iter().all(|&l| l > 0.0 && l.is_finite()));
        Self {
            edges,
            inv_edges: edges.map(|l| 1.0 / l),
        }
    }

    /// A cubic box of edge `l`.
    pub fn cubic(l: f64) -> Self {
        Self::new(Vector::repeat(l))
    }

    /// Edge lengths.
    pub fn edges(&self) -> &Vector<D> {
        &self.edges
    }

    /// Volume `Π L_a`.
    pub fn volume(&self) -> f64 {
        self.edges.iter().product()
    }

    /// The shortest edge.
    pub fn min_edge(&self) -> f64 {
        self.edges.min()
    }

    /// Minimum image of a separation vector.
    #[inline(always)]
    pub fn minimum_image(&self, mut d: Vector<D>) -> Vector<D> {
        for a in 0..D {
            d[a] -= self.edges[a] * round_fast(d[a] * self.inv_edges[a]);
        }
        d
    }

    /// The point brought back into the primary cell `[0, L)`.
    pub fn wrap(&self, mut r: Vector<D>) -> Vector<D> {
        for a in 0..D {
            r[a] -= self.edges[a] * (r[a] * self.inv_edges[a]).floor();
            // NOTE: r − L⌊r/L⌋ can round to exactly L for r a hair below 0.
            if r[a] >= self.edges[a] {
                r[a] = 0.0;
            }
        }
        r
    }

    /// Rescale every edge by `factor` (affine compression for `factor < 1`).
    pub fn scale(&mut self, factor: f64) {
        *self = Self::new(self.edges * factor);
    }

    /// Restore the cached inverse edges after deserialisation.
    pub fn refreshed(self) -> Self {
        Self::new(self.edges)
    }
}

/// Round to the nearest integer (ties to even) for `|x| < 2⁵¹`.
///
/// NOTE: `f64::round` is a library call on baseline x86-64 (no SSE4.1) and
/// cost a tenth of a force evaluation. Adding and subtracting `1.5 · 2⁵²`
/// makes the FPU round in its default nearest-even mode; it is exact for
/// `|x| < 2⁵¹`, and separations are never more than a few box edges.
#[inline(always)]
fn round_fast(x: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    (x + MAGIC) - MAGIC
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn minimum_image_is_shortest_and_periodic() {
        let b = PeriodicBox::<2>::new(Vector::<2>::new(10.0, 4.0));
        let d = b.minimum_image(Vector::<2>::new(9.0, -3.5));
        assert_relative_eq!(d[0], -1.0, epsilon = 1e-12);
        assert_relative_eq!(d[1], 0.5, epsilon = 1e-12);
        for a in 0..2 {
            assert!(d[a].abs() <= 0.5 * b.edges()[a]);
        }
    }

    #[test]
    fn fast_rounding_matches_round_off_ties() {
        for x in [-3.7, -2.2, -0.49, -0.0, 0.3, 0.51, 1.49, 7.6, 1e6 + 0.4] {
            assert_eq!(round_fast(x), x.round(), "{x}");
        }
    }

    #[test]
    fn wrap_lands_in_primary_cell() {
        let b = PeriodicBox::<3>::cubic(2.0);
        for x in [-4.1, -1e-17, 0.0, 1.999_999, 2.0, 7.3] {
            let r = b.wrap(Vector::<3>::repeat(x));
            assert!(r.iter().all(|&c| (0.0..2.0).contains(&c)), "{x} -> {r:?}");
        }
    }
}
