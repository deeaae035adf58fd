//! The curves of a shape plot (`jamkit draw-shape`): one panel per shape
//! (a mode number `n`, or a set of modes), one curve per `Δ`, each the
//! closed polar curve `R(θ)/R⁰ = 1 + Δ F(θ)` in units of `R⁰` (the paper's
//! Fig. 2 for `fourier` with `n = 2 … 5` and `Δ = 0, 0.1, 0.3`).

use crate::DrawError;
use crate::geometry::{Outline, Point};
use jamkit_fourier::Mode;

/// Points on each polar curve.
pub const CURVE_POINTS: usize = 720;

/// One curve of a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeCurve {
    /// Legend text, e.g. `Δ = 0.1`.
    pub label: String,
    /// The closed curve, in units of `R⁰`.
    pub points: Vec<Point>,
}

/// One panel: a title and its curves (drawn in order, with the styles of
/// [`crate::render::CURVE_STYLES`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapePanel {
    /// Panel title, e.g. `n = 3`.
    pub title: String,
    /// The curves.
    pub curves: Vec<ShapeCurve>,
}

fn curves(
    deltas: &[f64],
    outline: impl Fn(f64) -> Result<Outline, DrawError>,
) -> Result<Vec<ShapeCurve>, DrawError> {
    deltas
        .iter()
        .map(|&d| {
            Ok(ShapeCurve {
                label: format!("Δ = {d}"),
                points: outline(d)?.polar_curve(CURVE_POINTS),
            })
        })
        .collect()
}

fn check_lists(panels: usize, what: &str, deltas: &[f64]) -> Result<(), DrawError> {
    let bad = |message: String| DrawError::Params {
        family: "draw-shape".into(),
        message,
    };
    if panels == 0 {
        return Err(bad(format!("{what}: give at least one")));
    }
    if deltas.is_empty() {
        return Err(bad("delta: give at least one value".into()));
    }
    Ok(())
}

/// The `fourier` panels: one per `n`, one curve per `Δ`.
pub fn fourier_panels(ns: &[u32], deltas: &[f64]) -> Result<Vec<ShapePanel>, DrawError> {
    check_lists(ns.len(), "n", deltas)?;
    ns.iter()
        .map(|&n| {
            Ok(ShapePanel {
                title: format!("n = {n}"),
                curves: curves(deltas, |d| Outline::fourier(n, d))?,
            })
        })
        .collect()
}

/// A readable form of `F`: `0.5 sin(2θ) + 0.1 sin(3θ + 1)`.
pub fn describe_modes(modes: &[Mode]) -> String {
    modes
        .iter()
        .map(|m| {
            let phase = if m.b == 0.0 {
                String::new()
            } else {
                format!(" + {}", m.b)
            };
            format!("{} sin({}θ{phase})", m.a, m.n)
        })
        .collect::<Vec<_>>()
        .join(" + ")
}

/// The `fourier_sum` panels: one per mode set, one curve per `Δ`.
pub fn fourier_sum_panels(
    mode_sets: &[Vec<Mode>],
    deltas: &[f64],
) -> Result<Vec<ShapePanel>, DrawError> {
    check_lists(mode_sets.len(), "modes", deltas)?;
    mode_sets
        .iter()
        .map(|modes| {
            Ok(ShapePanel {
                title: format!("F = {}", describe_modes(modes)),
                curves: curves(deltas, |d| Outline::fourier_sum(modes.clone(), d))?,
            })
        })
        .collect()
}

/// Read a mode set written in RON as in experiment files:
/// `[(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)]`.
pub fn parse_modes(text: &str) -> Result<Vec<Mode>, DrawError> {
    ron::from_str(text).map_err(|e| DrawError::Params {
        family: "fourier_sum".into(),
        message: format!(
            "modes = {text}: {e} (write e.g. [(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)])"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn one_panel_per_n_and_one_curve_per_delta() {
        let panels = fourier_panels(&[2, 3, 4, 5], &[0.0, 0.1, 0.3]).unwrap();
        assert_eq!(panels.len(), 4);
        assert_eq!(panels[1].title, "n = 3");
        assert!(panels.iter().all(|p| p.curves.len() == 3));
        assert_eq!(panels[0].curves[2].label, "Δ = 0.3");
        // Δ = 0 is the unit circle.
        for p in &panels[0].curves[0].points {
            assert_relative_eq!(p[0].hypot(p[1]), 1.0, epsilon = 1e-12);
        }
        assert!(fourier_panels(&[], &[0.1]).is_err());
        assert!(fourier_panels(&[2], &[]).is_err());
        assert!(fourier_panels(&[1], &[2.0]).is_err());
    }

    #[test]
    fn mode_sets_parse_from_ron() {
        let modes = parse_modes("[(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)]").unwrap();
        assert_eq!(modes.len(), 2);
        assert_eq!((modes[1].n, modes[1].b), (3, 1.0));
        assert_eq!(describe_modes(&modes), "0.5 sin(2θ) + 0.1 sin(3θ + 1)");
        assert!(parse_modes("[(n: 2)]").is_err());
        let panels = fourier_sum_panels(&[modes], &[0.0, 0.2]).unwrap();
        assert_eq!(panels[0].curves.len(), 2);
    }
}
