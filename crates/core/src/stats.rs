//! The statistics every table and report uses, written once: the mean, the
//! sample standard deviation (`n − 1`), and the standard error of the mean.

/// The mean; NaN when there are no values.
pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.iter().sum::<f64>() / values.len() as f64
}

/// The sample standard deviation, `√(Σ (x − x̄)² / (n − 1))`; NaN for fewer
/// than two values.
pub fn std_dev(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return f64::NAN;
    }
    let m = mean(values);
    (values.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt()
}

/// The mean and the standard error of the mean, `s / √n` (0 for a single
/// value; NaN for none).
pub fn mean_sem(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = mean(values);
    if values.len() < 2 {
        return (mean, 0.0);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1, 2, 3, 4: mean 2.5, s² = 5/3, s.e. = √(5/12); the empty and
    /// single cases.
    #[test]
    fn known_values() {
        let v = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(mean(&v), 2.5);
        assert!((std_dev(&v) - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        let (m, se) = mean_sem(&v);
        assert_eq!(m, 2.5);
        assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-15);
        assert!(mean(&[]).is_nan() && std_dev(&[1.0]).is_nan());
        assert_eq!(mean_sem(&[7.0]), (7.0, 0.0));
        assert!(mean_sem(&[]).0.is_nan());
    }
}
