//! Size distributions: the scale `R_i⁰` of each body.
//!
//! A family's body `i` is its reference shape scaled by `R_i⁰` (the radius
//! for disks and spheres, the reference-disk radius for near-disks, the
//! overall scale for n-mers). The paper uses an equimolar binary mixture
//! `R⁰ = 0.5` for `i < N/2` and `0.7` otherwise, which prevents
//! crystallisation.

use crate::error::{Error, Result};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

/// How the body scales `R_i⁰` are drawn.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SizeDistribution {
    /// Equimolar binary mixture: the first `⌊N/2⌋` bodies get `small`, the rest `large`.
    Binary { small: f64, large: f64 },
    /// Every body the same size.
    Mono { radius: f64 },
    /// Sizes drawn uniformly from `[min, max]` (from the sample's random stream).
    Uniform { min: f64, max: f64 },
}

impl Default for SizeDistribution {
    fn default() -> Self {
        SizeDistribution::Binary {
            small: 0.5,
            large: 0.7,
        }
    }
}

impl SizeDistribution {
    /// Check that every size is positive and finite.
    pub fn validate(&self) -> Result<()> {
        let check = |field: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(Error::invalid(
                    field,
                    v,
                    "must be a positive, finite number",
                ))
            }
        };
        match *self {
            SizeDistribution::Binary { small, large } => {
                check("sizes.small", small)?;
                check("sizes.large", large)
            }
            SizeDistribution::Mono { radius } => check("sizes.radius", radius),
            SizeDistribution::Uniform { min, max } => {
                check("sizes.min", min)?;
                check("sizes.max", max)?;
                if min > max {
                    return Err(Error::invalid(
                        "sizes.min",
                        min,
                        format!("must not exceed sizes.max = {max}"),
                    ));
                }
                Ok(())
            }
        }
    }

    /// Sizes of `n` bodies.
    pub fn sample<R: Rng>(&self, n: usize, rng: &mut R) -> Vec<f64> {
        match *self {
            SizeDistribution::Binary { small, large } => (0..n)
                .map(|i| if i < n / 2 { small } else { large })
                .collect(),
            SizeDistribution::Mono { radius } => vec![radius; n],
            SizeDistribution::Uniform { min, max } => (0..n)
                .map(|_| min + (max - min) * rng.random::<f64>())
                .collect(),
        }
    }

    /// The largest size the distribution can produce.
    pub fn max_size(&self) -> f64 {
        match *self {
            SizeDistribution::Binary { small, large } => small.max(large),
            SizeDistribution::Mono { radius } => radius,
            SizeDistribution::Uniform { max, .. } => max,
        }
    }
}
