//! [`BodyOrientation`]: what every orientation type of a family can do by
//! itself, so that a family writes none of it.
//!
//! A family's [`Shape::Orientation`](crate::Shape::Orientation) is `()` for
//! balls, [`Rotation2`] or [`Angle`] in 2D and [`Quaternion`] in 3D. Each
//! knows its reference value, how to draw a uniformly random one, and how
//! it is written to and read from a packing file. What differs between
//! families, how a body turns under its rotational coordinates
//! ([`Shape::rotate`](crate::Shape::rotate)), stays with the family.

use crate::{Angle, Quaternion, Rotation2};
use rand::Rng;
use std::fmt::Debug;

/// An orientation type: its reference value, a uniformly random value,
/// and its numbers in a packing file.
pub trait BodyOrientation: Copy + Debug + PartialEq + Send + Sync + 'static {
    /// The orientation all bodies start from before randomisation.
    fn reference() -> Self;

    /// A uniformly random orientation (the random numbers it draws are part
    /// of a packing's reproducibility: never change them).
    fn random<R: Rng + ?Sized>(rng: &mut R) -> Self;

    /// The numbers written to a packing file (none for `()`).
    fn to_coords(&self) -> Vec<f64>;

    /// The inverse of [`BodyOrientation::to_coords`]; `None` when the
    /// numbers describe no orientation of this type.
    fn from_coords(coords: &[f64]) -> Option<Self>;
}

/// Balls: no orientation, no numbers, no random draws.
impl BodyOrientation for () {
    fn reference() -> Self {}

    fn random<R: Rng + ?Sized>(_rng: &mut R) -> Self {}

    fn to_coords(&self) -> Vec<f64> {
        Vec::new()
    }

    fn from_coords(coords: &[f64]) -> Option<Self> {
        coords.is_empty().then_some(())
    }
}

/// The planar angles ([`Rotation2`], [`Angle`]), alike: `θ = 0`; `θ`
/// uniform; `[θ]`.
macro_rules! planar_orientation {
    ($($impl_head:tt)*) => {
        $($impl_head)* {
            fn reference() -> Self {
                Self::new(0.0)
            }

            fn random<R: Rng + ?Sized>(rng: &mut R) -> Self {
                Self::random(rng)
            }

            fn to_coords(&self) -> Vec<f64> {
                self.coords()
            }

            fn from_coords(coords: &[f64]) -> Option<Self> {
                Self::from_coords(coords)
            }
        }
    };
}

planar_orientation!(impl BodyOrientation for Rotation2);
planar_orientation!(impl<const K: u32> BodyOrientation for Angle<K>);

/// The identity; uniform on the rotation group (Shoemake); `[w, x, y, z]`,
/// read back when of norm 1 to 10⁻⁶ (renormalised).
impl BodyOrientation for Quaternion {
    fn reference() -> Self {
        Self::IDENTITY
    }

    fn random<R: Rng + ?Sized>(rng: &mut R) -> Self {
        Self::random(rng)
    }

    fn to_coords(&self) -> Vec<f64> {
        self.coords().to_vec()
    }

    fn from_coords(coords: &[f64]) -> Option<Self> {
        Self::from_coords(coords)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Every orientation type reads back what it writes (to the bit for
    /// the angles, whose number is θ itself; to round-off for the
    /// quaternion, renormalised on reading), and refuses numbers of the
    /// wrong count.
    fn round_trip<O: BodyOrientation>(count: usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for o in [O::reference(), O::random(&mut rng), O::random(&mut rng)] {
            let c = o.to_coords();
            assert_eq!(c.len(), count);
            let back = O::from_coords(&c).expect("its own numbers");
            for (a, b) in back.to_coords().iter().zip(&c) {
                assert!((a - b).abs() <= 1e-15, "{a} against {b}");
            }
        }
        assert!(O::from_coords(&vec![0.5; count + 1]).is_none());
    }

    #[test]
    fn orientations_read_back_what_they_write() {
        round_trip::<()>(0);
        round_trip::<Rotation2>(1);
        round_trip::<Angle<1>>(1);
        round_trip::<Angle<2>>(1);
        round_trip::<Quaternion>(4);
    }
}
