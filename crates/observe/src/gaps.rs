//! The gap distribution between non-rattlers.
//!
//! The paper (section "Gap distribution") looks at the positive gaps `h > 0`
//! between pairs of non-rattlers (its Eq. (22) writes `Θ(−h)`; the gaps are
//! the pairs *not* in contact, so we read it as `Θ(h)`), through the
//! cumulative distribution
//!
//! ```text
//! Z(h) = ∫₀^h g(h') dh' / ∫₀^{h_cut} g(h') dh',   h_cut = 2,
//! ```
//!
//! which is sampled here on log-spaced points down to `h_min` (10⁻¹² by
//! default, below the smallest gaps a packing at `V/N ~ 10⁻¹⁶` resolves).
//! Each packing stores counts, not ratios, so that samples add exactly:
//! `Z` of a parameter point is the summed counts over the summed total.

pub use jamkit_core::records::GapCounts;
use jamkit_core::{Error, Result, Shape};
use jamkit_engine::Scene;
use serde::{Deserialize, Serialize};

/// Where to sample `Z(h)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GapParams {
    /// Largest gap counted (the paper: 2).
    pub h_cut: f64,
    /// Smallest sample point of `Z(h)`.
    pub h_min: f64,
    /// Log-spaced sample points per decade.
    pub points_per_decade: usize,
}

impl Default for GapParams {
    fn default() -> Self {
        Self {
            h_cut: 2.0,
            h_min: 1e-12,
            points_per_decade: 10,
        }
    }
}

impl GapParams {
    /// Check ranges; names the offending field.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        if !(self.h_cut > 0.0 && self.h_cut.is_finite()) {
            return Err(Error::invalid(
                format!("{prefix}.h_cut"),
                self.h_cut,
                "must be positive and finite",
            ));
        }
        if !(self.h_min > 0.0 && self.h_min < self.h_cut) {
            return Err(Error::invalid(
                format!("{prefix}.h_min"),
                self.h_min,
                format!("must be positive and below h_cut = {}", self.h_cut),
            ));
        }
        if !(1..=1000).contains(&self.points_per_decade) {
            return Err(Error::invalid(
                format!("{prefix}.points_per_decade"),
                self.points_per_decade,
                "must lie between 1 and 1000",
            ));
        }
        Ok(())
    }

    /// The sample points: log-spaced from `h_min`, ending exactly at `h_cut`.
    pub fn points(&self) -> Vec<f64> {
        let decades = (self.h_cut / self.h_min).log10();
        let n = (decades * self.points_per_decade as f64).ceil() as usize;
        let mut h: Vec<f64> = (0..n)
            .map(|k| self.h_min * 10f64.powf(k as f64 / self.points_per_decade as f64))
            .take_while(|&h| h < self.h_cut)
            .collect();
        h.push(self.h_cut);
        h
    }
}

/// Counting the gaps of a scene into [`GapCounts`] (stored data, defined
/// in `jamkit_core::records`): `GapCounts::of_scene(…)` with this trait
/// in scope.
pub trait CountGaps {
    /// The gaps `0 < h < h_cut` between non-rattlers of `scene`, counted
    /// below each sample point. Every contact point a family reports is a
    /// gap of its own (bodies made of spheres have several per pair).
    fn of_scene<const D: usize, S: Shape<D>>(
        scene: &mut Scene<D, S>,
        rattler: &[bool],
        params: &GapParams,
    ) -> GapCounts;
}

impl CountGaps for GapCounts {
    fn of_scene<const D: usize, S: Shape<D>>(
        scene: &mut Scene<D, S>,
        rattler: &[bool],
        params: &GapParams,
    ) -> GapCounts {
        let mut gaps = Vec::new();
        scene.for_each_contact(params.h_cut, |i, j, _, c| {
            let rattles = |b: usize| rattler.get(b).copied().unwrap_or(false);
            if !rattles(i) && !rattles(j) && c.gap > 0.0 && c.gap < params.h_cut {
                gaps.push(c.gap);
            }
        });
        gaps.sort_by(f64::total_cmp);
        let h = params.points();
        let below = h
            .iter()
            .map(|&x| gaps.partition_point(|&g| g < x) as u64)
            .collect();
        GapCounts { h, below }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_points_end_at_the_cut_and_are_log_spaced() {
        let p = GapParams {
            h_cut: 2.0,
            h_min: 1e-3,
            points_per_decade: 2,
        };
        let h = p.points();
        assert_eq!(*h.last().unwrap(), 2.0);
        assert_eq!(h[0], 1e-3);
        assert!((h[2] / h[0] - 10.0).abs() < 1e-12);
        assert!(h.windows(2).all(|w| w[1] > w[0]));
    }
}
