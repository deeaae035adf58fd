//! Power laws fitted on log–log axes, with errors from a bootstrap over
//! packings.
//!
//! A power law `y = A x^b` is a straight line through `(log x, log y)`; it
//! is fitted by least squares to the means of each point. The uncertainty
//! of `b` comes from resampling: each point's packings are drawn again
//! with replacement (as many as it has), the means recomputed and the line
//! refitted, `B` times; the error is the standard deviation of the `B`
//! slopes. The generator is seeded, so a report is reproducible.

use jamkit_core::stats::std_dev;
use rand::{RngExt, SeedableRng};

/// A fitted power law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLaw {
    /// Exponent `b`.
    pub exponent: f64,
    /// Bootstrap standard deviation of `b`.
    pub error: f64,
    /// Prefactor `A`.
    pub prefactor: f64,
    /// Smallest and largest `x` fitted.
    pub range: (f64, f64),
    /// Points fitted.
    pub points: usize,
}

impl PowerLaw {
    /// `A x^b`.
    pub fn at(&self, x: f64) -> f64 {
        self.prefactor * x.powf(self.exponent)
    }
}

/// Least-squares line `log y = log A + b log x`; `None` for fewer than two
/// distinct `x` or a non-positive value.
pub fn line(xy: &[(f64, f64)]) -> Option<(f64, f64)> {
    if xy.iter().any(|&(x, y)| !(x > 0.0 && y > 0.0)) {
        return None;
    }
    let n = xy.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = xy.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxx: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let b = sxy / sxx;
    Some(((my - b * mx).exp(), b))
}

/// Fit `y = A x^b` to points `(x, values of its packings)`, `y` the mean of
/// the values, with `resamples` bootstrap resamples. Points whose values
/// are empty are left out.
pub fn power_law(points: &[(f64, Vec<f64>)], resamples: usize, seed: u64) -> Option<PowerLaw> {
    let mean = |v: &[&f64]| Some(v.iter().copied().sum::<f64>() / v.len() as f64);
    power_law_of(points, mean, resamples, seed)
}

/// Fit `y = A x^b` where the `y` of a point is a statistic of its packings
/// (`stat`, e.g. ω₁ of their pooled density of states), with the bootstrap
/// resampling the packings of every point. Points with no packings, or
/// whose statistic is undefined, are left out.
pub fn power_law_of<T>(
    points: &[(f64, Vec<T>)],
    stat: impl Fn(&[&T]) -> Option<f64>,
    resamples: usize,
    seed: u64,
) -> Option<PowerLaw> {
    power_law_within(
        points,
        stat,
        resamples,
        seed,
        (f64::NEG_INFINITY, f64::INFINITY),
    )
}

/// [`power_law_of`] over the points with `lo ≤ x ≤ hi` only (for the
/// sensitivity of an exponent to its fit range).
pub fn power_law_within<T>(
    points: &[(f64, Vec<T>)],
    stat: impl Fn(&[&T]) -> Option<f64>,
    resamples: usize,
    seed: u64,
    (lo, hi): (f64, f64),
) -> Option<PowerLaw> {
    fn all<T>(v: &[T]) -> Vec<&T> {
        v.iter().collect()
    }
    let points: Vec<(f64, &Vec<T>)> = points
        .iter()
        .filter(|(x, _)| *x >= lo && *x <= hi)
        .filter(|(_, v)| !v.is_empty() && stat(&all(v)).is_some())
        .map(|(x, v)| (*x, v))
        .collect();
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|(x, v)| Some((*x, stat(&all(v))?)))
        .collect();
    let (prefactor, exponent) = line(&xy)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut slopes = Vec::with_capacity(resamples);
    for _ in 0..resamples {
        let xy: Option<Vec<(f64, f64)>> = points
            .iter()
            .map(|(x, v)| {
                let pick: Vec<&T> = (0..v.len())
                    .map(|_| &v[rng.random_range(0..v.len())])
                    .collect();
                Some((*x, stat(&pick)?))
            })
            .collect();
        if let Some((_, b)) = xy.and_then(|xy| line(&xy)) {
            slopes.push(b);
        }
    }
    let error = std_dev(&slopes);
    let xs = xy.iter().map(|p| p.0);
    Some(PowerLaw {
        exponent,
        error,
        prefactor,
        range: (
            xs.clone().fold(f64::INFINITY, f64::min),
            xs.fold(0.0, f64::max),
        ),
        points: xy.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact power-law data give the exponent to round-off, and the
    /// bootstrap of noise-free samples has zero spread.
    #[test]
    fn exact_power_law_is_recovered() {
        let pts: Vec<(f64, Vec<f64>)> = [1e-3, 1e-2, 1e-1]
            .iter()
            .map(|&x: &f64| (x, vec![3.0 * x.sqrt(); 4]))
            .collect();
        let f = power_law(&pts, 50, 1).unwrap();
        assert!((f.exponent - 0.5).abs() < 1e-12);
        assert!((f.prefactor - 3.0).abs() < 1e-10);
        assert!(f.error.abs() < 1e-12);
        assert_eq!(f.range, (1e-3, 1e-1));
    }

    /// Noisy samples give a bootstrap error of the size of the scatter:
    /// ±10 % noise on three points a decade apart moves the slope by
    /// ~0.1/√(samples) per decade, so the error lies in (0.005, 0.1).
    #[test]
    fn noisy_samples_give_a_finite_error() {
        let pts: Vec<(f64, Vec<f64>)> = [1e-3, 1e-2, 1e-1]
            .iter()
            .map(|&x: &f64| (x, vec![0.9 * x, 1.1 * x, x, 0.95 * x]))
            .collect();
        let f = power_law(&pts, 200, 7).unwrap();
        assert!((f.exponent - 1.0).abs() < 0.05, "{f:?}");
        assert!(f.error > 0.005 && f.error < 0.1, "{f:?}");
    }
}
