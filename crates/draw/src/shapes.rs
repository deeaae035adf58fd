//! The curves of a shape plot (`jamkit draw-shape`): one panel per
//! parameter set (a mode number `n`, a set of modes), one curve per
//! parameter set (`Δ`), each the closed polar curve `ρ(θ) = R(θ)/R⁰` in
//! units of `R⁰` (the paper's Fig. 2 for `fourier` with `n = 2 … 5` and
//! `Δ = 0, 0.1, 0.3`). Any registered family whose 2D shape has an outline
//! can be plotted; the outline comes through the registry.

use crate::DrawError;
use crate::geometry::{Outline, Point};
use jamkit_registry::{self as registry, ParamMap};

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

/// A parameter set of a shape plot: its parameters, by name.
pub type Params = ParamMap;

/// Read a parameter set written in RON as in an experiment file,
/// `(n: 3)` or `(modes: [(n: 2, a: 0.5)])`.
pub fn parse_params(family: &str, text: &str) -> Result<Params, DrawError> {
    registry::params_from_ron(text).map_err(|e| DrawError::Params {
        family: family.into(),
        message: format!(
            "{text}: {e} (write the parameters as in an experiment file, e.g. (n: 3, delta: 0.2))"
        ),
    })
}

/// The symbol of a parameter in titles and legends (`delta` → `Δ`).
fn symbol(name: &str) -> &str {
    match name {
        "delta" => "Δ",
        "kappa" => "κ",
        "alpha" | "aspect" => "α",
        other => other,
    }
}

/// `Δ = 0.1, n = 3`: a parameter set for a title or a legend.
pub fn describe(params: &Params) -> String {
    params
        .iter()
        .map(|(name, value)| {
            let shown = match value {
                ron::Value::Number(x) => x.into_f64().to_string(),
                other => ron::to_string(other).unwrap_or_default(),
            };
            format!("{} = {shown}", symbol(name))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The panels of a shape plot of `family`: one per parameter set of
/// `panels`, one curve per set of `curves`. A curve's parameters are the
/// family's example ([`jamkit_core::Family::EXAMPLE`]), overridden by its
/// panel's, overridden by its own; so `panels = [(n: 2), (n: 3)]`,
/// `curves = [(delta: 0), (delta: 0.1)]` is the paper's Fig. 2 for
/// `fourier`. An empty list stands for one set with nothing to override.
pub fn panels(
    family: &str,
    panels: &[Params],
    curves: &[Params],
) -> Result<Vec<ShapePanel>, DrawError> {
    merged_params(family, panels, curves)?
        .into_iter()
        .map(|(title, row)| {
            let curves = row
                .into_iter()
                .map(|(label, params, _)| {
                    let outline = Outline::of(family, &params)?;
                    if !matches!(outline, Outline::Polar { .. }) {
                        return Err(DrawError::Params {
                            family: family.into(),
                            message: "its bodies are made of spheres and have no polar outline R(θ) to plot; draw a packing instead (jamkit draw)".into(),
                        });
                    }
                    Ok(ShapeCurve {
                        label,
                        points: outline.polar_curve(CURVE_POINTS),
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok(ShapePanel { title, curves })
        })
        .collect()
}

/// The parameter sets of a shape plot, merged: per panel its title and,
/// per curve, its label and parameters (the family's example
/// ([`jamkit_core::Family::EXAMPLE`]), overridden by the panel's,
/// overridden by the curve's), and the panel's and curve's alone. An
/// empty list stands for one set with nothing to override.
#[allow(clippy::type_complexity)]
pub fn merged_params(
    family: &str,
    panels: &[Params],
    curves: &[Params],
) -> Result<Vec<(String, Vec<(String, Params, Params)>)>, DrawError> {
    let info = registry::family_info(family).map_err(|e| DrawError::Params {
        family: family.into(),
        message: e.to_string(),
    })?;
    let example = registry::FAMILIES
        .iter()
        .position(|f| f.name == info.name)
        .map(|k| registry::EXAMPLES[k])
        .unwrap_or("()");
    let example = parse_params(family, example)?;
    let one = [Params::new()];
    let panels = if panels.is_empty() { &one[..] } else { panels };
    let curves = if curves.is_empty() { &one[..] } else { curves };
    Ok(panels
        .iter()
        .map(|panel| {
            let row = curves
                .iter()
                .map(|curve| {
                    let mut own = panel.clone();
                    own.extend(curve.clone());
                    let mut params = example.clone();
                    params.extend(own.clone());
                    let label = if curve.is_empty() {
                        describe(&params)
                    } else {
                        describe(curve)
                    };
                    (label, params, own)
                })
                .collect();
            let title = if panel.is_empty() {
                family.to_string()
            } else {
                describe(panel)
            };
            (title, row)
        })
        .collect())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;

    pub(crate) fn fourier_panels(ns: &[u32], deltas: &[f64]) -> Vec<ShapePanel> {
        let sets = |name: &str, xs: Vec<String>| -> Vec<Params> {
            xs.iter()
                .map(|x| parse_params("fourier", &format!("({name}: {x})")).unwrap())
                .collect()
        };
        let ns = sets("n", ns.iter().map(|n| n.to_string()).collect());
        let deltas = sets("delta", deltas.iter().map(|d| format!("{d:?}")).collect());
        panels("fourier", &ns, &deltas).unwrap()
    }

    #[test]
    fn one_panel_per_n_and_one_curve_per_delta() {
        let p = fourier_panels(&[2, 3, 4, 5], &[0.0, 0.1, 0.3]);
        assert_eq!(p.len(), 4);
        assert_eq!(p[1].title, "n = 3");
        assert!(p.iter().all(|p| p.curves.len() == 3));
        assert_eq!(p[0].curves[2].label, "Δ = 0.3");
        // Δ = 0 is the unit circle.
        for q in &p[0].curves[0].points {
            assert_relative_eq!(q[0].hypot(q[1]), 1.0, epsilon = 1e-12);
        }
        let n1 = parse_params("fourier", "(n: 1, delta: 2.0)").unwrap();
        assert!(panels("fourier", &[n1], &[]).is_err());
        assert!(panels("no_such", &[], &[]).is_err());
        assert!(panels("nmer", &[], &[]).is_err());
        assert!(parse_params("fourier", "(n: ").is_err());
    }

    #[test]
    fn every_planar_family_has_a_default_panel() {
        for info in registry::FAMILIES {
            if registry::supports_dim(info, 2) && info.name != "nmer" {
                let p = panels(info.name, &[], &[]).unwrap();
                assert_eq!((p.len(), p[0].curves.len()), (1, 1), "{}", info.name);
            }
        }
        let modes = parse_params(
            "fourier_sum",
            "(modes: [(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)])",
        )
        .unwrap();
        let delta = parse_params("fourier_sum", "(delta: 0.2)").unwrap();
        let p = panels("fourier_sum", &[modes], &[delta.clone(), delta]).unwrap();
        assert_eq!(p[0].curves.len(), 2);
        assert!(p[0].title.starts_with("modes = "), "{}", p[0].title);
    }
}
