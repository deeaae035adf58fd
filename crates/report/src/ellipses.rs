//! The paper's Fig. 5: ellipses against `n = 2` near-disks at equal
//! asphericity `A = P²/(4πS)`, drawn when the runs hold packings of the
//! `ellipse` family.
//!
//! φ_J and `z_J` (non-rattlers) of both families against `A − 1` on a
//! logarithmic axis, at the system size of the ellipses, and a markdown
//! table pairing the points of equal `A` (mean ± s.e.m. over packings).

use crate::ReportError;
use crate::data::{Point, mean_sem, packing_paths};
use crate::plot::{Figure, Series};
use jamkit_core::gap_model::GapModel;
use jamkit_format::PackingFile;
use plotters::prelude::SeriesLabelPosition;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One ellipse packing, reduced to what Fig. 5 needs.
#[derive(Clone, Debug)]
struct Sample {
    phi: f64,
    z_j: Option<f64>,
    rattler_fraction: Option<f64>,
}

/// All ellipse packings of one aspect ratio and size.
#[derive(Clone, Debug)]
struct EllipsePoint {
    aspect: f64,
    particles: usize,
    samples: Vec<Sample>,
}

/// One row of the comparison: a point of either family at its `A − 1`.
#[derive(Clone, Debug)]
struct Row {
    a_minus_1: f64,
    /// `Δ` (near-disks) or `α` (ellipses).
    parameter: f64,
    packings: usize,
    phi: (f64, f64),
    z_j: (f64, f64),
    rattlers: (f64, f64),
}

/// The ellipse packings under `dirs` (each a run's output directory), by
/// aspect ratio and size, and how many files they were.
fn load(dirs: &[PathBuf]) -> (Vec<EllipsePoint>, usize) {
    let mut files: Vec<PackingFile> = Vec::new();
    for dir in dirs {
        // A missing directory was reported by the near-disks' loader.
        for path in packing_paths(dir).unwrap_or_default() {
            let Some(file) = PackingFile::load(&path) else {
                continue;
            };
            if file.family != "ellipse" {
                continue;
            }
            // A packing present in several runs counts once.
            if !files
                .iter()
                .any(|f| f.id == file.id && f.settings == file.settings)
            {
                files.push(file);
            }
        }
    }
    let mut points: Vec<EllipsePoint> = Vec::new();
    for f in &files {
        let Some(aspect) = f.params.get("aspect").and_then(|v| v.as_f64()) else {
            continue;
        };
        let m = &f.measures;
        let sample = Sample {
            phi: m.phi,
            z_j: m.z_j,
            rattler_fraction: m.n_rattlers.map(|r| r as f64 / f.particles as f64),
        };
        match points
            .iter_mut()
            .find(|p| p.aspect == aspect && p.particles == f.particles)
        {
            Some(p) => p.samples.push(sample),
            None => points.push(EllipsePoint {
                aspect,
                particles: f.particles,
                samples: vec![sample],
            }),
        }
    }
    points.sort_by(|a, b| {
        a.particles
            .cmp(&b.particles)
            .then(a.aspect.total_cmp(&b.aspect))
    });
    (points, files.len())
}

/// `A` of the body of `family` with `params` (JSON), as the registry
/// builds it; `None` where the family refuses them.
fn asphericity(family: &str, params: serde_json::Value) -> Option<f64> {
    let params = jamkit_registry::params_from_json(&params).ok()?;
    jamkit_registry::asphericity(family, &params).ok().flatten()
}

/// `A` of the `n = 2` near-disk of amplitude `delta`.
fn near_disk_asphericity(delta: f64) -> Option<f64> {
    asphericity(
        "fourier",
        serde_json::json!({"n": 2, "delta": delta, "inertia": 1.0}),
    )
}

/// `A` of the ellipse of aspect ratio `aspect`.
fn ellipse_asphericity(aspect: f64) -> Option<f64> {
    asphericity("ellipse", serde_json::json!({ "aspect": aspect }))
}

/// What Fig. 5 produced: figure stems, the markdown section, and the
/// number of ellipse packing files read (they are not near-disk packings
/// and are otherwise counted as left out).
pub(crate) struct Fig05 {
    pub figures: Vec<PathBuf>,
    pub markdown: String,
    pub files: usize,
    /// Packings of `other_gaps` drawn (near-disks at the ellipses' size).
    pub other_gap_packings: usize,
}

/// The `n = 2` near-disk rows of `points` at `size` with gap model `gap`.
fn near_disk_rows(points: &[Point], size: usize, gap: GapModel) -> Vec<Row> {
    points
        .iter()
        .filter(|p| p.family == "fourier" && p.n == 2 && p.dim == 2 && p.particles == size)
        .filter(|p| p.gap == gap)
        .filter_map(|p| {
            Some(Row {
                a_minus_1: near_disk_asphericity(p.delta)? - 1.0,
                parameter: p.delta,
                packings: p.samples.len(),
                phi: mean_sem(&p.samples, |s| Some(s.phi)),
                z_j: mean_sem(&p.samples, |s| s.z_j),
                rattlers: mean_sem(&p.samples, |s| s.rattler_fraction),
            })
        })
        .filter(|r| r.a_minus_1 > 0.0)
        .collect()
}

/// The series label of a gap model.
fn gap_label(gap: GapModel) -> &'static str {
    match gap {
        GapModel::FirstOrder => "first order",
        GapModel::SecondOrder => "second order",
        GapModel::Exact => "exact gap",
    }
}

/// Fig. 5 from the ellipse packings under `dirs` and the near-disk
/// `points` (the paper's first-order gap), with the near-disks of
/// `other_gaps` (second-order and exact gaps) as more series; `None` when
/// there are no ellipse packings.
pub(crate) fn fig05(
    dirs: &[PathBuf],
    points: &[Point],
    other_gaps: &[Point],
    out: &Path,
) -> Result<Option<Fig05>, ReportError> {
    let (ellipses, files) = load(dirs);
    // The largest size with ellipses; near-disks at that size.
    let Some(size) = ellipses.iter().map(|p| p.particles).max() else {
        return Ok(None);
    };
    let stat = |v: &[Sample], f: &dyn Fn(&Sample) -> Option<f64>| mean_sem(v, f);
    let ell: Vec<Row> = ellipses
        .iter()
        .filter(|p| p.particles == size)
        .filter_map(|p| {
            Some(Row {
                a_minus_1: ellipse_asphericity(p.aspect)? - 1.0,
                parameter: p.aspect,
                packings: p.samples.len(),
                phi: stat(&p.samples, &|s| Some(s.phi)),
                z_j: stat(&p.samples, &|s| s.z_j),
                rattlers: stat(&p.samples, &|s| s.rattler_fraction),
            })
        })
        .filter(|r| r.a_minus_1 > 0.0)
        .collect();
    let disks = near_disk_rows(points, size, GapModel::FirstOrder);
    let more: Vec<(GapModel, Vec<Row>)> = [GapModel::SecondOrder, GapModel::Exact]
        .into_iter()
        .map(|g| (g, near_disk_rows(other_gaps, size, g)))
        .filter(|(_, rows)| !rows.is_empty())
        .collect();
    let other_gap_packings = more
        .iter()
        .flat_map(|(_, rows)| rows.iter().map(|r| r.packings))
        .sum();
    let series = |rows: &[Row], f: fn(&Row) -> (f64, f64), label: String| Series {
        label,
        points: rows
            .iter()
            .map(|r| (r.a_minus_1, f(r).0, f(r).1))
            .filter(|p| p.1.is_finite())
            .collect(),
        line: true,
    };
    let mut figures = Vec::new();
    for (name, title, y_label, f, legend) in [
        (
            "fig05a_phi_ellipses",
            "Fig. 5: φ_J, ellipses and n = 2 near-disks",
            "φ_J",
            (|r: &Row| r.phi) as fn(&Row) -> (f64, f64),
            SeriesLabelPosition::UpperLeft,
        ),
        (
            "fig05b_z_ellipses",
            "Fig. 5: z_J, ellipses and n = 2 near-disks",
            "z_J (non-rattlers)",
            |r: &Row| r.z_j,
            SeriesLabelPosition::UpperLeft,
        ),
    ] {
        let mut s = vec![
            series(&ell, f, format!("ellipses, exact gap (N = {size})")),
            series(
                &disks,
                f,
                format!("n = 2 near-disks, first order (N = {size})"),
            ),
        ];
        for (gap, rows) in &more {
            let label = format!("n = 2 near-disks, {} (N = {size})", gap_label(*gap));
            s.push(series(rows, f, label));
        }
        if s.iter().all(|s| s.points.is_empty()) {
            continue;
        }
        let stem = out.join(name);
        Figure {
            title: title.into(),
            x_label: "A − 1".into(),
            y_label: y_label.into(),
            log_x: true,
            log_y: false,
            series: s,
            guides: Vec::new(),
            legend,
        }
        .write(&stem)?;
        figures.push(stem);
    }
    let mut markdown = table(&ell, &disks, size);
    if !more.is_empty() {
        markdown += &gap_table(&ell, &disks, &more, size);
    }
    Ok(Some(Fig05 {
        figures,
        markdown,
        files,
        other_gap_packings,
    }))
}

/// The markdown table: rows of equal `A` (relative difference below 1e-6)
/// side by side, the others on their own.
fn table(ell: &[Row], disks: &[Row], size: usize) -> String {
    let pct = |v: (f64, f64)| {
        if v.0.is_finite() {
            format!("{:.1} % ± {:.1}", 100.0 * v.0, 100.0 * v.1)
        } else {
            "—".into()
        }
    };
    let mut m = format!(
        "\n## Fig. 5: ellipses against n = 2 near-disks (N = {size})\n\n\
         Mean ± s.e.m. over packings; z_J among non-rattlers; f_r the rattler fraction.\n\n\
         | A − 1 | Δ (near-disk) | α (ellipse) | φ_J near-disk | φ_J ellipse | z_J near-disk | z_J ellipse | f_r near-disk | f_r ellipse | packings |\n\
         |---|---|---|---|---|---|---|---|---|---|\n"
    );
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
    let mut all: Vec<(f64, Option<&Row>, Option<&Row>)> = Vec::new();
    for d in disks {
        all.push((
            d.a_minus_1,
            Some(d),
            ell.iter().find(|e| same(e.a_minus_1, d.a_minus_1)),
        ));
    }
    for e in ell {
        if !disks.iter().any(|d| same(e.a_minus_1, d.a_minus_1)) {
            all.push((e.a_minus_1, None, Some(e)));
        }
    }
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let nan = (f64::NAN, f64::NAN);
    for (a, d, e) in all {
        let g = |r: Option<&Row>, f: fn(&Row) -> (f64, f64)| r.map_or(nan, f);
        let _ = writeln!(
            m,
            "| {a:.3e} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} |",
            d.map_or("—".into(), |r| format!("{}", r.parameter)),
            e.map_or("—".into(), |r| format!("{:.6}", r.parameter)),
            pm(g(d, |r| r.phi), 4),
            pm(g(e, |r| r.phi), 4),
            pm(g(d, |r| r.z_j), 3),
            pm(g(e, |r| r.z_j), 3),
            pct(g(d, |r| r.rattlers)),
            pct(g(e, |r| r.rattlers)),
            d.map_or(0, |r| r.packings),
            e.map_or(0, |r| r.packings),
        );
    }
    m
}

/// `mean ± s.e.m.` with `digits` decimals, `—` when there is none.
fn pm(v: (f64, f64), digits: usize) -> String {
    if v.0.is_finite() {
        format!("{:.*} ± {:.*}", digits, v.0, digits, v.1)
    } else {
        "—".into()
    }
}

/// The markdown table of the gap models: at each `Δ` measured with another
/// gap model, φ_J and `z_J` of the near-disks with every gap model beside
/// the ellipse of equal `A`.
fn gap_table(ell: &[Row], disks: &[Row], more: &[(GapModel, Vec<Row>)], size: usize) -> String {
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
    let mut columns: Vec<(String, &[Row])> = vec![("first order".into(), disks)];
    for (gap, rows) in more {
        columns.push((gap_label(*gap).into(), rows));
    }
    columns.push(("ellipse".into(), ell));
    let names: Vec<&str> = columns.iter().map(|(n, _)| n.as_str()).collect();
    let head = |q: &str| -> String { names.iter().map(|n| format!(" {q} {n} |")).collect() };
    let mut m = format!(
        "\n### Fig. 5: the gap models of the near-disks (N = {size})\n\n\
         The same seeds with the paper's first-order gap, its second-order \
         correction and the exact gap, beside the ellipse of equal A.\n\n\
         | Δ | A − 1 |{}{} packings |\n|---|---|{}---|\n",
        head("φ_J"),
        head("z_J"),
        "---|".repeat(2 * names.len())
    );
    let mut deltas: Vec<(f64, f64)> = more
        .iter()
        .flat_map(|(_, rows)| rows.iter().map(|r| (r.parameter, r.a_minus_1)))
        .collect();
    deltas.sort_by(|a, b| a.0.total_cmp(&b.0));
    deltas.dedup_by(|a, b| a.0 == b.0);
    for (delta, a) in deltas {
        let cells: Vec<Option<&Row>> = columns
            .iter()
            .enumerate()
            .map(|(k, (_, rows))| {
                rows.iter().find(|r| {
                    // Near-disks by Δ, the ellipse by its asphericity.
                    if k + 1 == columns.len() {
                        same(r.a_minus_1, a)
                    } else {
                        r.parameter == delta
                    }
                })
            })
            .collect();
        let nan = (f64::NAN, f64::NAN);
        let phi: String = cells
            .iter()
            .map(|c| format!(" {} |", pm(c.map_or(nan, |r| r.phi), 4)))
            .collect();
        let z: String = cells
            .iter()
            .map(|c| format!(" {} |", pm(c.map_or(nan, |r| r.z_j), 3)))
            .collect();
        let counts: Vec<String> = cells
            .iter()
            .map(|c| c.map_or(0, |r| r.packings).to_string())
            .collect();
        let _ = writeln!(m, "| {delta} | {a:.3e} |{phi}{z} {} |", counts.join(" / "));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(a_minus_1: f64, parameter: f64, phi: f64) -> Row {
        Row {
            a_minus_1,
            parameter,
            packings: 3,
            phi: (phi, 0.001),
            z_j: (4.5, 0.01),
            rattlers: (0.02, 0.005),
        }
    }

    /// Rows of equal A (to 1e-6 relative) share a line; others get their
    /// own, sorted by A, with dashes for the missing family.
    #[test]
    fn table_pairs_rows_of_equal_asphericity() {
        let disks = [row(3.7e-3, 0.1, 0.85), row(1e-4, 0.02, 0.84)];
        let ell = [row(3.7e-3 * (1.0 + 1e-9), 1.105, 0.86), row(0.5, 3.0, 0.9)];
        let t = table(&ell, &disks, 128);
        let lines: Vec<&str> = t
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| A"))
            .collect();
        assert_eq!(lines.len(), 3, "{t}");
        assert!(
            lines[0].starts_with("| 1.000e-4 | 0.02 | — |"),
            "{}",
            lines[0]
        );
        assert!(
            lines[1].contains("| 0.1 | 1.105000 | 0.8500 ± 0.0010 | 0.8600 ± 0.0010 |"),
            "{}",
            lines[1]
        );
        assert!(
            lines[2].starts_with("| 5.000e-1 | — | 3.000000 |"),
            "{}",
            lines[2]
        );
        assert!(t.contains("N = 128"));
    }

    /// The gap-model table has one line per Δ measured with another gap
    /// model, its cells in the order first order, the other models, the
    /// ellipse of equal A, and a dash where a model has no packing there.
    #[test]
    fn gap_table_lines_up_the_models_by_delta() {
        let disks = [row(3.7e-3, 0.1, 0.85), row(1e-4, 0.02, 0.84)];
        let second = [row(3.7e-3, 0.1, 0.851)];
        let exact = [row(3.7e-3, 0.1, 0.852), row(2e-2, 0.2, 0.86)];
        let ell = [row(3.7e-3 * (1.0 + 1e-9), 1.105, 0.853)];
        let more = vec![
            (GapModel::SecondOrder, second.to_vec()),
            (GapModel::Exact, exact.to_vec()),
        ];
        let t = gap_table(&ell, &disks, &more, 512);
        let lines: Vec<&str> = t
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| Δ"))
            .collect();
        assert_eq!(lines.len(), 2, "{t}");
        assert!(
            lines[0].starts_with(
                "| 0.1 | 3.700e-3 | 0.8500 ± 0.0010 | 0.8510 ± 0.0010 | 0.8520 ± 0.0010 | 0.8530 ± 0.0010 |"
            ),
            "{}",
            lines[0]
        );
        assert!(lines[0].ends_with(" 3 / 3 / 3 / 3 |"), "{}", lines[0]);
        assert!(
            lines[1].starts_with("| 0.2 | 2.000e-2 | — | — | 0.8600 ± 0.0010 | — |"),
            "{}",
            lines[1]
        );
        assert!(lines[1].ends_with(" 0 / 0 / 3 / 0 |"), "{}", lines[1]);
        assert!(t.contains("| φ_J second order |") && t.contains("N = 512"));
    }

    /// The near-disk and ellipse asphericities of the Fig. 5 grid agree
    /// (the files' aspect ratios match A to ~1e-9 in α, so A to ~1e-10).
    #[test]
    fn grid_asphericities_match() {
        for (delta, alpha) in [(0.01, 1.010050054), (0.3, 1.345872045)] {
            let (a, b) = (
                near_disk_asphericity(delta).unwrap(),
                ellipse_asphericity(alpha).unwrap(),
            );
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
        assert!(ellipse_asphericity(0.5).is_none());
    }
}
