//! The paper's figures and the summary table.
//!
//! Each figure is built from whatever the runs measured: φ_J and `f_r`
//! need `Contacts`, `δz_J` too, `Z(h)` needs `Gaps`, `D(ω)`, `ω₁` and `ω_*`
//! need `Spectrum`. "The largest N" is, for each `n`, the largest system
//! size present; the finite-size study (Fig. 9) needs `n = 2` at two sizes
//! or more.
//!
//! Fit ranges (stated in the summary with every exponent):
//!
//! * `δz_J ∝ Δ^{1/2}`: points with `δz_J ≥ 8/N_nr` (well above the
//!   finite-size floor `2/N_nr`, the paper's "δz_J ≫ 1/N") and `Δ ≤ 0.1`;
//! * `ω₁ ∝ Δ`: points with `Δ ≤ 0.1`, ω₁ of each point's pooled `D(ω)`;
//! * `ω_* ∝ Δ^{1/2}`: points where the pooled `D(ω)` defines ω_*;
//! * `Z(h) ∼ h^{1−γ}` at the smallest Δ: `10 Δ^μ ≤ h ≤ 0.1`, and `Z ∼ h` at
//!   the largest Δ: `h ≤ Δ^μ / 10`, both only where each sample point has at
//!   least 20 gaps below it (`μ = 1/(2(1 − γ))`).

use crate::ReportError;
use crate::data::{Point, Sample, load, mean_sem};
use crate::fit::{PowerLaw, line, power_law_of, power_law_within};
use crate::plot::{Figure, Guide, Series};
use jamkit_core::gap_model::GapModel;
use jamkit_observe::gaps::GapCounts;
use jamkit_observe::spectrum::DosHistogram;
use plotters::prelude::SeriesLabelPosition;
use rand::{RngExt, SeedableRng};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Report settings.
#[derive(Clone, Debug)]
pub struct Options {
    /// `γ` of the gap distribution (the paper: 0.41).
    pub gamma: f64,
    /// Bootstrap resamples per fit.
    pub resamples: usize,
    /// Seed of the bootstrap.
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            gamma: 0.41,
            resamples: 500,
            seed: 1,
        }
    }
}

/// One fitted exponent, beside its mean-field value.
#[derive(Clone, Debug)]
pub struct FitRow {
    /// What was fitted (`δz_J`, `ω₁`, …).
    pub quantity: String,
    /// Mode number.
    pub n: u32,
    /// Its name (`n` or `l`, [`Point::mode`]).
    pub mode: &'static str,
    /// System size.
    pub particles: usize,
    /// The fit.
    pub fit: PowerLaw,
    /// Mean-field exponent.
    pub expected: f64,
    /// Accepted deviation from it: within it the report says the exponent
    /// agrees.
    pub tolerance: f64,
    /// The same fit with the end points of its range left out one at a
    /// time (`without the smallest x`, `without the largest x`), where four
    /// points or more were fitted: how much the exponent depends on the
    /// choice of range.
    pub range_variants: Vec<(String, PowerLaw)>,
}

impl FitRow {
    /// A row not yet fitted.
    fn new(
        quantity: &str,
        (mode, n): (&'static str, u32),
        particles: usize,
        expected: f64,
        tolerance: f64,
    ) -> Self {
        Self {
            quantity: quantity.into(),
            n,
            mode,
            particles,
            fit: PowerLaw {
                exponent: f64::NAN,
                error: f64::NAN,
                prefactor: f64::NAN,
                range: (f64::NAN, f64::NAN),
                points: 0,
            },
            expected,
            tolerance,
            range_variants: Vec::new(),
        }
    }

    /// Whether the exponent is within the tolerance of the prediction.
    pub fn agrees(&self) -> bool {
        (self.fit.exponent - self.expected).abs() <= self.tolerance
    }
}

/// What a report produced.
#[derive(Clone, Debug)]
pub struct Report {
    /// Figure files written (without extension: each has `.svg` and `.png`).
    pub figures: Vec<PathBuf>,
    /// Every fitted exponent.
    pub fits: Vec<FitRow>,
    /// The markdown summary (also written to `OUT/report.md`).
    pub markdown: String,
}

/// Read the runs in `dirs`, write figures and `report.md` into `out`.
pub fn report(dirs: &[PathBuf], out: &Path, options: &Options) -> Result<Report, ReportError> {
    let (all, skipped) = load(dirs)?;
    // The paper's figures are those of its first-order gap; packings with
    // another gap model enter Fig. 5 only (as more near-disk series). Runs
    // of one other gap model alone (e.g. the exact gap throughout) give
    // the figures of that model.
    let (mut points, mut other_gaps): (Vec<Point>, Vec<Point>) =
        all.into_iter().partition(|p| p.gap == GapModel::FirstOrder);
    let mut gap_note = None;
    if points.is_empty()
        && let Some(first) = other_gaps.first().map(|p| p.gap)
        && other_gaps.iter().all(|p| p.gap == first)
    {
        gap_note = Some(format!(
            "The runs hold no packings of the paper's first-order gap: the figures are \
             those of the `{first:?}` gap model."
        ));
        points = std::mem::take(&mut other_gaps);
    }
    if points.is_empty() {
        let list: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        return Err(ReportError::NoData(list.join(", ")));
    }
    let mut kinds: Vec<String> = points
        .iter()
        .map(|p| format!("{}D, {}", p.dim, p.mode))
        .collect();
    kinds.sort();
    kinds.dedup();
    if kinds.len() > 1 {
        return Err(ReportError::Mixed(kinds.join("; ")));
    }
    std::fs::create_dir_all(out).map_err(|e| ReportError::Io {
        path: out.to_path_buf(),
        error: e,
    })?;
    let mut r = Builder {
        out: out.to_path_buf(),
        options: options.clone(),
        points,
        figures: Vec::new(),
        fits: Vec::new(),
        claims: Vec::new(),
        notes: gap_note.into_iter().collect(),
    };
    // Fig. 5 (ellipses) is drawn only when the runs hold ellipse packings;
    // those are not near-disk packings, but are not "left out" either.
    let fig05 = crate::ellipses::fig05(dirs, &r.points, &other_gaps, out)?;
    let skipped = skipped - fig05.as_ref().map_or(0, |f| f.files).min(skipped);
    if skipped > 0 {
        r.notes
            .push(format!("{skipped} packing files were not near-disk packings with n and Δ, or unreadable, and were left out."));
    }
    let used = fig05.as_ref().map_or(0, |f| f.other_gap_packings);
    let unused: usize = other_gaps.iter().map(|p| p.samples.len()).sum::<usize>() - used;
    if unused > 0 {
        r.notes.push(format!(
            "{unused} packings with a gap model other than the paper's first order \
             were left out of the figures (only Fig. 5 shows other gap models)."
        ));
    }
    r.phi_and_rattlers()?;
    r.finite_size()?;
    r.dz_against_delta()?;
    r.gaps()?;
    r.spectra()?;
    let mut markdown = r.markdown(dirs);
    if let Some(f) = fig05 {
        markdown += &f.markdown;
        for stem in &f.figures {
            let name = stem
                .file_name()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            let _ = writeln!(markdown, "\n![{name}]({name}.png)");
        }
        r.figures.extend(f.figures);
    }
    let path = out.join("report.md");
    std::fs::write(&path, &markdown).map_err(|e| ReportError::Io { path, error: e })?;
    Ok(Report {
        figures: r.figures,
        fits: r.fits,
        markdown,
    })
}

/// A row of the summary table.
struct Claim {
    claim: String,
    measured: String,
    agrees: String,
}

struct Builder {
    out: PathBuf,
    options: Options,
    points: Vec<Point>,
    figures: Vec<PathBuf>,
    fits: Vec<FitRow>,
    claims: Vec<Claim>,
    notes: Vec<String>,
}

fn fmt(x: f64) -> String {
    if x.is_nan() {
        "—".into()
    } else {
        format!("{x:.4}")
    }
}

impl Builder {
    /// The name of the mode number: `n` for near-disks, `l` for
    /// near-spheres (one kind per report, [`report`] checks).
    fn sym(&self) -> &'static str {
        self.points.first().map_or("n", |p| p.mode)
    }

    fn mode_numbers(&self) -> Vec<u32> {
        let mut ns: Vec<u32> = self.points.iter().map(|p| p.n).collect();
        ns.dedup();
        ns
    }

    /// The points of mode `n` at "the largest N" for a quantity that
    /// `has` tells is measured: the largest N at which every mode number
    /// has it (so that the n are compared at one N; a finite-size study of
    /// n = 2 alone does not set it), else the largest N of this `n`.
    fn largest(&self, n: u32, has: fn(&Sample) -> bool) -> Vec<&Point> {
        let measured = |p: &&Point| p.samples.iter().any(has);
        let sizes = |n: u32| -> Vec<usize> {
            self.points
                .iter()
                .filter(|p| p.n == n)
                .filter(measured)
                .map(|p| p.particles)
                .collect()
        };
        let ns = self.mode_numbers();
        let common = sizes(n)
            .into_iter()
            .filter(|&size| ns.iter().all(|&m| sizes(m).contains(&size)))
            .max();
        let big = common.or_else(|| sizes(n).into_iter().max()).unwrap_or(0);
        self.points
            .iter()
            .filter(|p| p.n == n && p.particles == big)
            .filter(measured)
            .collect()
    }

    fn save(&mut self, name: &str, figure: Figure) -> Result<(), ReportError> {
        let stem = self.out.join(name);
        figure.write(&stem)?;
        self.figures.push(stem);
        Ok(())
    }

    fn claim(&mut self, claim: &str, measured: String, agrees: &str) {
        self.claims.push(Claim {
            claim: claim.into(),
            measured,
            agrees: agrees.into(),
        });
    }

    /// Figs. 7 and 8.
    fn phi_and_rattlers(&mut self) -> Result<(), ReportError> {
        let ns = self.mode_numbers();
        let sym = self.sym();
        let mut phi = Vec::new();
        let mut fr = Vec::new();
        let mut rises = Vec::new();
        let mut falls = Vec::new();
        // φ_J with its s.e.m. per (n, Δ), for the ordering in n at each Δ.
        let mut by_delta: Vec<(u32, PhiSeries)> = Vec::new();
        for &n in &ns {
            let pts = self.largest(n, |s| s.phi.is_finite());
            let series = |f: &dyn Fn(&Sample) -> Option<f64>| -> Vec<(f64, f64, f64)> {
                pts.iter()
                    .map(|p| {
                        let (m, e) = mean_sem(&p.samples, f);
                        (p.delta, m, e)
                    })
                    .filter(|s| s.1.is_finite())
                    .collect()
            };
            let big = pts.first().map_or(0, |p| p.particles);
            let p_series = series(&|s| Some(s.phi));
            let r_series = series(&|s| s.rattler_fraction);
            if let (Some(a), Some(b)) = (p_series.first(), p_series.last()) {
                rises.push(format!(
                    "{sym} = {n}: {:.4} → {:.4} (Δ = {:e} → {:e})",
                    a.1, b.1, a.0, b.0
                ));
            }
            by_delta.push((n, p_series.clone()));
            if let (Some(a), Some(b)) = (r_series.first(), r_series.last()) {
                falls.push((n, a.1, b.1));
            }
            phi.push(Series {
                label: format!("{sym} = {n} (N = {big})"),
                points: p_series,
                line: false,
            });
            fr.push(Series {
                label: format!("{sym} = {n} (N = {big})"),
                points: r_series,
                line: false,
            });
        }
        let guides = if sym == "n" {
            convex_limits(&ns, &phi)
        } else {
            Vec::new()
        };
        self.save(
            "fig07_phi_j",
            Figure {
                title: "Fig. 7: packing fraction at jamming".into(),
                x_label: "Δ".into(),
                y_label: "φ_J".into(),
                log_x: true,
                log_y: false,
                series: phi,
                guides,
                legend: SeriesLabelPosition::LowerRight,
            },
        )?;
        if fr.iter().any(|s| !s.points.is_empty()) {
            self.save(
                "fig08_rattlers",
                Figure {
                    title: "Fig. 8: fraction of rattlers".into(),
                    x_label: "Δ".into(),
                    y_label: "f_r = N_r / N".into(),
                    log_x: true,
                    log_y: false,
                    series: fr,
                    guides: Vec::new(),
                    legend: SeriesLabelPosition::UpperRight,
                },
            )?;
        }
        // φ_J rises for every n; more slowly for larger n (the order in n
        // at every shared Δ, `phi_order`).
        let rise_ok = self.mode_numbers().iter().all(|&n| {
            let pts = self.largest(n, |s| s.phi.is_finite());
            let (a, b) = (pts.first(), pts.last());
            match (a, b) {
                (Some(a), Some(b)) => {
                    mean_sem(&b.samples, |s| Some(s.phi)).0
                        > mean_sem(&a.samples, |s| Some(s.phi)).0
                }
                _ => false,
            }
        });
        self.claim(
            &format!("φ_J rises with Δ for every {sym} (Fig. 7)"),
            rises.join("; "),
            if rise_ok { "yes" } else { "no" },
        );
        let (order, verdict) = phi_order(&by_delta, sym);
        self.claim(
            &format!("… and more slowly for larger {sym} (Fig. 7)"),
            order,
            verdict,
        );
        let fall_text: Vec<String> = falls
            .iter()
            .map(|(n, a, b)| format!("{sym} = {n}: {:.1} % → {:.1} %", 100.0 * a, 100.0 * b))
            .collect();
        let fall_ok = !falls.is_empty() && falls.iter().all(|(_, a, b)| b < a);
        self.claim(
            "f_r falls with Δ (Fig. 8)",
            fall_text.join("; "),
            if fall_ok { "yes" } else { "no" },
        );
        Ok(())
    }

    /// δz_J against Δ for every n at the largest N, with fits (Fig. 10).
    fn dz_against_delta(&mut self) -> Result<(), ReportError> {
        let mut series = Vec::new();
        let mut guides = Vec::new();
        for n in self.mode_numbers() {
            let pts = self.largest(n, |s| s.z_j.is_some());
            let dim = pts.first().map_or(2, |p| p.dim);
            let big = pts.first().map_or(0, |p| p.particles);
            let values: Vec<(f64, Vec<f64>, f64)> = pts
                .iter()
                .map(|p| {
                    let v: Vec<f64> = p.samples.iter().filter_map(|s| s.dz(dim)).collect();
                    let nnr = mean_sem(&p.samples, |s| s.n_nr.map(|x| x as f64)).0;
                    (p.delta, v, nnr)
                })
                .collect();
            series.push(Series {
                label: format!("{} = {n}", self.sym()),
                points: values
                    .iter()
                    .map(|(d, v, _)| {
                        let (m, e) = jamkit_format::mean_sem(v);
                        (*d, m, e)
                    })
                    .collect(),
                line: false,
            });
            let fit_points: Vec<(f64, Vec<f64>)> = values
                .iter()
                .filter(|(d, v, nnr)| {
                    let m = jamkit_format::mean_sem(v).0;
                    *d <= 0.1 && m >= 8.0 / nnr
                })
                .map(|(d, v, _)| (*d, v.clone()))
                .collect();
            let row = FitRow::new("δz_J", (self.sym(), n), big, 0.5, 0.1);
            if let Some(g) = self.fit_and_record(&fit_points, mean, row) {
                guides.push(g.fitting(series.len() - 1));
            }
        }
        if series
            .iter()
            .all(|s| s.points.iter().all(|p| !p.1.is_finite()))
        {
            return Ok(());
        }
        self.save(
            "fig10_dz",
            Figure {
                title: "Fig. 10: excess contacts at the largest N".into(),
                x_label: "Δ".into(),
                y_label: "δz_J = z_J − z_iso".into(),
                log_x: true,
                log_y: true,
                series,
                guides,
                legend: SeriesLabelPosition::LowerRight,
            },
        )?;
        let rows: Vec<&FitRow> = self.fits.iter().filter(|f| f.quantity == "δz_J").collect();
        let text: Vec<String> = rows.iter().map(|f| fit_text(f)).collect();
        let ok = !rows.is_empty() && rows.iter().all(|f| f.agrees());
        self.claim(
            &format!("δz_J ∝ Δ^{{1/2}} for all {} (Fig. 10)", self.sym()),
            text.join("; "),
            verdict(ok, rows.is_empty()),
        );
        Ok(())
    }

    /// Fit a power law with bootstrap errors to `points`, the `y` of a point
    /// being `stat` of its packings (at least three points where it is
    /// defined), record it as `row`, and return its guide line.
    fn fit_and_record<T>(
        &mut self,
        points: &[(f64, Vec<T>)],
        stat: impl Fn(&[&T]) -> Option<f64>,
        mut row: FitRow,
    ) -> Option<Guide> {
        let defined = points
            .iter()
            .filter(|(_, v)| !v.is_empty() && stat(&v.iter().collect::<Vec<_>>()).is_some())
            .count();
        if defined < 3 {
            return None;
        }
        let f = power_law_of(points, &stat, self.options.resamples, self.options.seed)?;
        if f.points >= 4 {
            // The same fit without its first, then without its last point.
            let xs: Vec<f64> = points
                .iter()
                .map(|p| p.0)
                .filter(|x| *x >= f.range.0 && *x <= f.range.1)
                .collect();
            let above = |x0: f64| {
                xs.iter()
                    .copied()
                    .filter(|x| *x > x0)
                    .fold(f64::INFINITY, f64::min)
            };
            let below = |x1: f64| {
                xs.iter()
                    .copied()
                    .filter(|x| *x < x1)
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            let (r, s) = (self.options.resamples, self.options.seed);
            for (name, range) in [
                ("without the smallest", (above(f.range.0), f.range.1)),
                ("without the largest", (f.range.0, below(f.range.1))),
            ] {
                if let Some(v) = power_law_within(points, &stat, r, s, range) {
                    row.range_variants.push((name.to_string(), v));
                }
            }
        }
        let guide = Guide::power_law(
            format!(
                "fit {}, {} = {}: Δ^{:.2}",
                row.quantity, row.mode, row.n, f.exponent
            ),
            f.prefactor,
            f.exponent,
            f.range.0,
            f.range.1,
        );
        row.fit = f;
        self.fits.push(row);
        Some(guide)
    }

    /// Standard deviation of `stat` over bootstrap resamples of `samples`.
    fn bootstrap_error(&self, samples: &[Sample], stat: fn(&[&Sample]) -> Option<f64>) -> f64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.options.seed);
        let values: Vec<f64> = (0..self.options.resamples)
            .filter_map(|_| {
                let pick: Vec<&Sample> = (0..samples.len())
                    .map(|_| &samples[rng.random_range(0..samples.len())])
                    .collect();
                stat(&pick)
            })
            .collect();
        jamkit_format::mean_sem(&values).1 * (values.len() as f64).sqrt()
    }

    /// Fig. 9: n = 2 (or l = 2) at several N, and the collapse.
    fn finite_size(&mut self) -> Result<(), ReportError> {
        let sym = self.sym();
        let pts: Vec<&Point> = self.points.iter().filter(|p| p.n == 2).collect();
        let mut sizes: Vec<usize> = pts.iter().map(|p| p.particles).collect();
        sizes.sort_unstable();
        sizes.dedup();
        if sizes.len() < 2 {
            self.notes.push(format!(
                "Fig. 9 (finite size) needs {sym} = 2 at two system sizes or more: skipped."
            ));
            return Ok(());
        }
        let mut raw = Vec::new();
        let mut collapse = Vec::new();
        let mut smallest: Option<(f64, f64, f64, usize, f64)> = None;
        for &size in &sizes {
            let mut a = Vec::new();
            let mut b = Vec::new();
            for p in pts.iter().filter(|p| p.particles == size) {
                let (dz, e) = mean_sem(&p.samples, |s| s.dz(p.dim));
                let nnr = mean_sem(&p.samples, |s| s.n_nr.map(|x| x as f64)).0;
                let scaled = mean_sem(&p.samples, |s| Some(s.dz(p.dim)? * s.n_nr? as f64));
                a.push((p.delta, dz, e));
                let x = nnr * nnr * p.delta;
                b.push((x, scaled.0, scaled.1));
                if smallest.is_none_or(|s| x < s.0) && scaled.0.is_finite() {
                    smallest = Some((x, scaled.0, scaled.1, size, p.delta));
                }
            }
            raw.push(Series {
                label: format!("N = {size}"),
                points: a,
                line: false,
            });
            collapse.push(Series {
                label: format!("N = {size}"),
                points: b,
                line: false,
            });
        }
        let (d0, d1) = x_span(&raw);
        let top_raw = rightmost(&raw);
        self.save(
            "fig09a_dz_finite_size",
            Figure {
                title: format!("Fig. 9(a): δz_J for {sym} = 2 and several N"),
                x_label: "Δ".into(),
                y_label: "δz_J = z_J − z_iso".into(),
                log_x: true,
                log_y: true,
                series: raw,
                guides: vec![Guide::power_law_through("∝ Δ^{1/2}", 0.5, top_raw, d0, d1)],
                legend: SeriesLabelPosition::LowerRight,
            },
        )?;
        let (x0, x1) = x_span(&collapse);
        // The Δ^{1/2} guides pass through the point of largest x.
        let top = rightmost(&collapse);
        self.save(
            "fig09b_dz_collapse",
            Figure {
                title: "Fig. 9(b): finite-size collapse".into(),
                x_label: "N_nr² Δ".into(),
                y_label: "δz_J N_nr".into(),
                log_x: true,
                log_y: true,
                series: collapse,
                guides: vec![
                    Guide::power_law("δz_J N_nr = 2", 2.0, 0.0, x0, x1),
                    Guide::power_law_through("∝ (N_nr² Δ)^{1/2}", 0.5, top, x0, x1),
                ],
                legend: SeriesLabelPosition::UpperLeft,
            },
        )?;
        if let Some((x, v, e, size, delta)) = smallest {
            let ok = (v - 2.0).abs() <= 0.5_f64.max(2.0 * e);
            self.claim(
                "δz_J N_nr → 2 as N_nr² Δ → 0, and the data collapse (Fig. 9)",
                format!(
                    "δz_J N_nr = {v:.2} ± {e:.2} at the smallest N_nr² Δ = {x:.3} (N = {size}, Δ = {delta:e}); collapse: see fig09b"
                ),
                if ok { "yes (within 0.5)" } else { "no" },
            );
        }
        Ok(())
    }

    /// Fig. 11: Z(h) per n, its collapse, and the two slopes.
    fn gaps(&mut self) -> Result<(), ReportError> {
        let gamma = self.options.gamma;
        let mu = 1.0 / (2.0 * (1.0 - gamma));
        let sym = self.sym();
        let mut any = false;
        for n in self.mode_numbers() {
            let pts: Vec<Point> = self
                .largest(n, |s| s.gaps.is_some())
                .into_iter()
                .cloned()
                .collect();
            let with: Vec<(&Point, GapCounts)> = pts
                .iter()
                .filter_map(|p| Some((p, pooled_gaps(&p.samples)?)))
                .collect();
            if with.is_empty() {
                continue;
            }
            any = true;
            let mut raw = Vec::new();
            let mut collapse = Vec::new();
            for (p, g) in &with {
                let z = g.cumulative();
                let curve: Vec<(f64, f64, f64)> =
                    g.h.iter()
                        .zip(&z)
                        .filter(|(_, z)| **z > 0.0)
                        .map(|(&h, &z)| (h, z, 0.0))
                        .collect();
                collapse.push(Series {
                    label: format!("Δ = {:e}", p.delta),
                    points: curve
                        .iter()
                        .map(|&(h, z, _)| (h / p.delta.powf(mu), z / p.delta.sqrt(), 0.0))
                        .collect(),
                    line: true,
                });
                raw.push(Series {
                    label: format!("Δ = {:e}", p.delta),
                    points: curve,
                    line: true,
                });
            }
            let (h0, h1) = x_span(&raw);
            self.save(
                &format!("fig11_gaps_{sym}{n}"),
                Figure {
                    title: format!("Fig. 11: cumulative gap distribution, {sym} = {n}"),
                    x_label: "h".into(),
                    y_label: "Z(h)".into(),
                    log_x: true,
                    log_y: true,
                    series: raw,
                    guides: vec![
                        Guide::power_law_through(
                            format!("∝ h^(1−γ), γ = {gamma}"),
                            1.0 - gamma,
                            anchor(&with[0].1, 0.1),
                            h0,
                            h1,
                        ),
                        Guide::power_law_through(
                            "∝ h",
                            1.0,
                            anchor(&with[with.len() - 1].1, 0.01),
                            h0,
                            h1,
                        ),
                    ],
                    legend: SeriesLabelPosition::LowerRight,
                },
            )?;
            self.save(
                &format!("fig11_gaps_collapse_{sym}{n}"),
                Figure {
                    title: format!("Fig. 11: collapse, {sym} = {n} (μ = {mu:.3})"),
                    x_label: "h / Δ^μ".into(),
                    y_label: "Z / Δ^{1/2}".into(),
                    log_x: true,
                    log_y: true,
                    series: collapse,
                    guides: Vec::new(),
                    legend: SeriesLabelPosition::LowerRight,
                },
            )?;
            // Slopes at the smallest and largest Δ.
            let big = with[0].0.particles;
            let (small, large) = (&with[0], &with[with.len() - 1]);
            let lo = fit_gap_slope(small.0, 10.0 * small.0.delta.powf(mu), 0.1, &self.options);
            if let Some(fit) = lo {
                let name = format!("Z(h) at Δ = {:e}", small.0.delta);
                self.fits.push(FitRow {
                    fit,
                    ..FitRow::new(&name, (sym, n), big, 1.0 - gamma, 0.15)
                });
            }
            if with.len() > 1 {
                let hi = fit_gap_slope(large.0, 0.0, large.0.delta.powf(mu) / 10.0, &self.options);
                if let Some(fit) = hi {
                    let name = format!("Z(h) at Δ = {:e}", large.0.delta);
                    self.fits.push(FitRow {
                        fit,
                        ..FitRow::new(&name, (sym, n), big, 1.0, 0.15)
                    });
                }
            }
        }
        if !any {
            self.notes
                .push("Fig. 11 (gaps) needs the Gaps observable: skipped.".into());
            return Ok(());
        }
        for (which, expected) in [("smallest", 1.0 - gamma), ("largest", 1.0)] {
            let rows: Vec<&FitRow> = self
                .fits
                .iter()
                .filter(|f| f.quantity.starts_with("Z(h)") && f.expected == expected)
                .collect();
            let text: Vec<String> = rows.iter().map(|f| fit_text(f)).collect();
            let ok = !rows.is_empty() && rows.iter().all(|f| f.agrees());
            self.claim(
                &if which == "smallest" {
                    format!("Z(h) ∼ h^(1−γ) = h^{:.2} at small Δ (Fig. 11)", 1.0 - gamma)
                } else {
                    "Z(h) ∼ h at large Δ (Fig. 11)".into()
                },
                text.join("; "),
                verdict(ok, rows.is_empty()),
            );
        }
        self.claim(
            "Z/Δ^{1/2} collapses against h/Δ^μ (Fig. 11)",
            format!("see fig11_gaps_collapse_{sym}*"),
            "by eye",
        );
        Ok(())
    }

    /// Figs. 12 and 13.
    fn spectra(&mut self) -> Result<(), ReportError> {
        let mut omega = Vec::new();
        let mut guides = Vec::new();
        let mut any = false;
        for n in self.mode_numbers() {
            let pts: Vec<Point> = self
                .largest(n, |s| s.dos.is_some())
                .into_iter()
                .cloned()
                .collect();
            let mut dos = Vec::new();
            for p in &pts {
                let Some(h) = pooled_dos(&p.samples) else {
                    continue;
                };
                // Empty bins break the line (log axis), so a band is not
                // joined to the plateau across the gap between them.
                let pts: Vec<(f64, f64, f64)> = h
                    .centres()
                    .iter()
                    .zip(h.density())
                    .map(|(&w, d)| (w, d, 0.0))
                    .collect();
                dos.push(Series {
                    label: format!("Δ = {:e}", p.delta),
                    points: pts,
                    line: true,
                });
            }
            if dos.is_empty() {
                continue;
            }
            any = true;
            self.save(
                &format!("fig12_dos_{}{n}", self.sym()),
                Figure {
                    title: format!(
                        "Fig. 12: density of states, {} = {n} (zero modes left out)",
                        self.sym()
                    ),
                    x_label: "ω".into(),
                    y_label: "D(ω)".into(),
                    log_x: true,
                    log_y: true,
                    series: dos,
                    guides: Vec::new(),
                    legend: SeriesLabelPosition::LowerLeft,
                },
            )?;
            let big = pts.first().map_or(0, |p| p.particles);
            // ω₁ and ω_* of each point's pooled D(ω) (the paper's are read
            // off the ensemble's D), with bootstrap errors over packings.
            type Stat = fn(&[&Sample]) -> Option<f64>;
            let omega_1: Stat = |s| pooled_dos_of(s)?.omega_1();
            let omega_star: Stat = |s| {
                let params = s.iter().find_map(|x| x.dos_params.clone())?;
                pooled_dos_of(s)?.omega_star(&params)
            };
            for (name, stat, expected, max_delta) in [
                ("ω₁", omega_1, 1.0, 0.1),
                ("ω_*", omega_star, 0.5, f64::INFINITY),
            ] {
                let values: Vec<(f64, Vec<Sample>)> = pts
                    .iter()
                    .filter(|p| p.delta <= max_delta)
                    .map(|p| (p.delta, p.samples.clone()))
                    .collect();
                omega.push(Series {
                    label: format!("{name}, {} = {n}", self.sym()),
                    points: values
                        .iter()
                        .filter_map(|(d, v)| {
                            let all: Vec<&Sample> = v.iter().collect();
                            let w = stat(&all)?;
                            Some((*d, w, self.bootstrap_error(v, stat)))
                        })
                        .collect(),
                    line: false,
                });
                let row = FitRow::new(name, (self.sym(), n), big, expected, 0.15);
                if let Some(g) = self.fit_and_record(&values, stat, row) {
                    guides.push(g.fitting(omega.len() - 1));
                }
            }
        }
        if !any {
            self.notes
                .push("Figs. 12 and 13 need the Spectrum observable: skipped.".into());
            return Ok(());
        }
        self.save(
            "fig13_omega",
            Figure {
                title: "Fig. 13: characteristic frequencies".into(),
                x_label: "Δ".into(),
                y_label: "ω₁, ω_*".into(),
                log_x: true,
                log_y: true,
                series: omega,
                guides,
                legend: SeriesLabelPosition::LowerRight,
            },
        )?;
        for (name, claim) in [
            ("ω₁", "ω₁ ∝ Δ (Fig. 13)"),
            ("ω_*", "ω_* ∝ Δ^{1/2} (Fig. 13)"),
        ] {
            let rows: Vec<&FitRow> = self.fits.iter().filter(|f| f.quantity == name).collect();
            let text: Vec<String> = rows.iter().map(|f| fit_text(f)).collect();
            let ok = !rows.is_empty() && rows.iter().all(|f| f.agrees());
            self.claim(claim, text.join("; "), verdict(ok, rows.is_empty()));
        }
        Ok(())
    }

    fn markdown(&self, dirs: &[PathBuf]) -> String {
        let mut m = String::from("# jamkit report\n\n");
        let list: Vec<String> = dirs.iter().map(|d| format!("`{}`", d.display())).collect();
        let _ = writeln!(m, "Runs: {}.\n", list.join(", "));
        let _ = writeln!(
            m,
            "| {} | N | Δ values | packings per point |\n|---|---|---|---|",
            self.sym()
        );
        for n in self.mode_numbers() {
            let mut sizes: Vec<usize> = self
                .points
                .iter()
                .filter(|p| p.n == n)
                .map(|p| p.particles)
                .collect();
            sizes.sort_unstable();
            sizes.dedup();
            for size in sizes {
                let pts: Vec<&Point> = self
                    .points
                    .iter()
                    .filter(|p| p.n == n && p.particles == size)
                    .collect();
                let deltas: Vec<String> = pts.iter().map(|p| format!("{:e}", p.delta)).collect();
                let counts: Vec<usize> = pts.iter().map(|p| p.samples.len()).collect();
                let (lo, hi) = (
                    counts.iter().min().unwrap_or(&0),
                    counts.iter().max().unwrap_or(&0),
                );
                let _ = writeln!(m, "| {n} | {size} | {} | {lo}–{hi} |", deltas.join(", "));
            }
        }
        m += "\n## The paper's claims\n\n| paper's claim | our measurement | agrees? |\n|---|---|---|\n";
        for c in &self.claims {
            let _ = writeln!(m, "| {} | {} | {} |", c.claim, c.measured, c.agrees);
        }
        m += "\nExponents are least-squares slopes on log–log axes through the point means; ± is the standard deviation over bootstrap resamples of the packings of each point. Fit ranges: δz_J over points with δz_J ≥ 8/N_nr and Δ ≤ 0.1; ω₁ and ω_* are read off each point's pooled D(ω) (the bootstrap resamples its packings), ω₁ over Δ ≤ 0.1 and ω_* where it is defined; Z(h) over 10 Δ^μ ≤ h ≤ 0.1 at the smallest Δ and h ≤ Δ^μ/10 at the largest, where each sample point has at least 20 gaps below it. \"Agrees\" means within the stated tolerance of the mean-field exponent (0.1 for δz_J, 0.15 otherwise).\n\n## Fits\n\n";
        let _ = writeln!(
            m,
            "| quantity | {} | N | exponent | mean field | range of Δ or h | points |\n|---|---|---|---|---|---|---|",
            self.sym()
        );
        for f in &self.fits {
            let _ = writeln!(
                m,
                "| {} | {} | {} | {:.3} ± {:.3} | {} | {:.3e} … {:.3e} | {} |",
                f.quantity,
                f.n,
                f.particles,
                f.fit.exponent,
                f.fit.error,
                fmt(f.expected),
                f.fit.range.0,
                f.fit.range.1,
                f.fit.points
            );
        }
        if self.fits.iter().any(|f| !f.range_variants.is_empty()) {
            m += "\n## How the exponents move with the fit range\n\nEach fit over Δ with four points or more, refitted without its smallest and without its largest Δ (same bootstrap). A claim that holds only on one side of this table depends on the choice of range.\n\n";
            let _ = writeln!(
                m,
                "| quantity | {} | N | full range | without the smallest Δ | without the largest Δ |\n|---|---|---|---|---|---|",
                self.sym()
            );
            for f in self.fits.iter().filter(|f| !f.range_variants.is_empty()) {
                let cell = |p: &PowerLaw| {
                    format!(
                        "{:.3} ± {:.3} ({:.1e} … {:.1e})",
                        p.exponent, p.error, p.range.0, p.range.1
                    )
                };
                let variant = |name: &str| {
                    f.range_variants
                        .iter()
                        .find(|(n, _)| n == name)
                        .map_or("–".to_string(), |(_, p)| cell(p))
                };
                let _ = writeln!(
                    m,
                    "| {} | {} | {} | {} | {} | {} |",
                    f.quantity,
                    f.n,
                    f.particles,
                    cell(&f.fit),
                    variant("without the smallest"),
                    variant("without the largest")
                );
            }
        }
        m += "\n## Figures\n\n";
        for f in &self.figures {
            let name = f
                .file_name()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            let _ = writeln!(m, "![{name}]({name}.png)\n");
        }
        if !self.notes.is_empty() {
            m += "## Notes\n\n";
            for n in &self.notes {
                let _ = writeln!(m, "* {n}");
            }
        }
        m
    }
}

/// The mean of a point's values.
fn mean(v: &[&f64]) -> Option<f64> {
    Some(v.iter().copied().sum::<f64>() / v.len() as f64)
}

/// A dashed vertical line at each near-disk mode's convex limit
/// `Δ = 1/(n + 1/n)` that falls within the Δ of the series (one series per
/// mode, in the order of `ns`), in the colour of its mode's series; the
/// first drawn carries the legend.
fn convex_limits(ns: &[u32], series: &[Series]) -> Vec<Guide> {
    let (lo, hi) = x_span(series);
    let mut guides: Vec<Guide> = Vec::new();
    for (k, &n) in ns.iter().enumerate() {
        let limit = jamkit_fourier::NearDisk::convex_limit(n);
        if !(lo..=hi).contains(&limit) {
            continue;
        }
        let label = if guides.is_empty() {
            "convex limit Δ = 1/(n + 1/n)".to_string()
        } else {
            String::new()
        };
        guides.push(Guide {
            label,
            // Clipped to the figure's box, so it spans the whole height.
            points: vec![(limit, -1e3), (limit, 1e3)],
            series: Some(k),
        });
    }
    guides
}

/// Smallest and largest positive `x` of the series.
fn x_span(series: &[Series]) -> (f64, f64) {
    series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .filter(|x| *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)))
}

/// The point of largest `x` with a positive `y` (where a guide is anchored).
fn rightmost(series: &[Series]) -> (f64, f64) {
    series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.1 > 0.0)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map_or((1.0, 1.0), |p| (p.0, p.1))
}

fn fit_text(f: &FitRow) -> String {
    format!(
        "{} = {}: {:.2} ± {:.2} ({:.3e}…{:.3e}, {} pts)",
        f.mode, f.n, f.fit.exponent, f.fit.error, f.fit.range.0, f.fit.range.1, f.fit.points
    )
}

fn verdict(ok: bool, none: bool) -> &'static str {
    match (none, ok) {
        (true, _) => "too few points to fit",
        (false, true) => "yes",
        (false, false) => "no",
    }
}

/// `(h, Z(h))` at the sample point nearest `h` (for anchoring a guide).
fn anchor(g: &GapCounts, h: f64) -> (f64, f64) {
    let z = g.cumulative();
    let k = (0..g.h.len())
        .min_by(|&a, &b| (g.h[a] / h).ln().abs().total_cmp(&(g.h[b] / h).ln().abs()))
        .unwrap_or(0);
    (g.h[k], z[k])
}

/// The gap counts of `samples` added up.
fn pooled_gaps(samples: &[Sample]) -> Option<GapCounts> {
    let mut it = samples.iter().filter_map(|s| s.gaps.as_ref());
    let mut g = it.next()?.clone();
    for other in it {
        g.merge(other).ok()?;
    }
    Some(g)
}

/// The histograms of `samples` added up.
fn pooled_dos(samples: &[Sample]) -> Option<DosHistogram> {
    pooled_dos_of(&samples.iter().collect::<Vec<_>>())
}

/// The histograms of `samples` added up.
fn pooled_dos_of(samples: &[&Sample]) -> Option<DosHistogram> {
    let mut it = samples.iter().filter_map(|s| s.dos.as_ref());
    let mut h = it.next()?.clone();
    for other in it {
        h.merge(other).ok()?;
    }
    Some(h)
}

/// Slope of `log Z` against `log h` over `lo ≤ h ≤ hi`, where the pooled
/// counts are at least 20 per sample point, with a bootstrap over packings.
fn fit_gap_slope(p: &Point, lo: f64, hi: f64, options: &Options) -> Option<PowerLaw> {
    let counts: Vec<&GapCounts> = p.samples.iter().filter_map(|s| s.gaps.as_ref()).collect();
    let pooled = pooled_gaps(&p.samples)?;
    let keep: Vec<usize> = (0..pooled.h.len())
        .filter(|&k| pooled.h[k] >= lo && pooled.h[k] <= hi && pooled.below[k] >= 20)
        .collect();
    if keep.len() < 3 {
        return None;
    }
    let z_at = |c: &[&GapCounts]| -> Option<Vec<(f64, f64)>> {
        let total: u64 = c.iter().map(|g| g.total()).sum();
        let pts: Vec<(f64, f64)> = keep
            .iter()
            .map(|&k| {
                let below: u64 = c.iter().map(|g| g.below[k]).sum();
                (pooled.h[k], below as f64 / total as f64)
            })
            .collect();
        pts.iter().all(|p| p.1 > 0.0).then_some(pts)
    };
    let xy = z_at(&counts)?;
    let (prefactor, exponent) = line(&xy)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(options.seed);
    let mut slopes = Vec::new();
    for _ in 0..options.resamples {
        let pick: Vec<&GapCounts> = (0..counts.len())
            .map(|_| counts[rng.random_range(0..counts.len())])
            .collect();
        if let Some((_, b)) = z_at(&pick).and_then(|xy| line(&xy)) {
            slopes.push(b);
        }
    }
    let mean = slopes.iter().sum::<f64>() / slopes.len().max(1) as f64;
    let var =
        slopes.iter().map(|b| (b - mean).powi(2)).sum::<f64>() / (slopes.len().max(2) - 1) as f64;
    Some(PowerLaw {
        exponent,
        error: var.sqrt(),
        prefactor,
        range: (xy[0].0, xy[xy.len() - 1].0),
        points: xy.len(),
    })
}
/// `(Δ, φ_J, s.e.m.)` of one n, Δ ascending.
type PhiSeries = Vec<(f64, f64, f64)>;

/// The ordering of φ_J in `n` at every Δ that all `n` share: `(n, [(Δ,
/// φ_J, s.e.m.)])` per n, n ascending. A pair of neighbouring n is
/// *ordered* when the larger n has the lower φ_J by more than 2 standard
/// errors of the difference, *inverted* when it has the higher φ_J by more
/// than 2, and *tied* otherwise. The text lists the Δ where every pair is
/// ordered, and each inverted or tied pair at the Δ where some pair is
/// ordered (below that, all n lie within their errors). The verdict: "no"
/// if a pair is inverted, "partly" if a pair is tied at a Δ where others
/// are ordered, "yes" if the order holds wherever the data can tell,
/// "cannot tell" if no pair is told apart anywhere.
fn phi_order(by_delta: &[(u32, PhiSeries)], sym: &str) -> (String, &'static str) {
    if by_delta.len() < 2 {
        return (String::new(), "needs several mode numbers");
    }
    let deltas: Vec<f64> = by_delta[0]
        .1
        .iter()
        .map(|p| p.0)
        .filter(|d| {
            by_delta
                .iter()
                .all(|(_, pts)| pts.iter().any(|p| p.0 == *d))
        })
        .collect();
    let (mut ordered, mut notes) = (Vec::new(), Vec::new());
    let (mut told, mut tied, mut inverted) = (false, false, false);
    for d in deltas {
        let at: Vec<(u32, f64, f64)> = by_delta
            .iter()
            .map(|(n, pts)| {
                let p = pts.iter().find(|p| p.0 == d).expect("a shared Δ");
                (*n, p.1, p.2)
            })
            .collect();
        let pairs: Vec<(u32, u32, f64)> = at
            .windows(2)
            .map(|w| {
                let se = (w[0].2 * w[0].2 + w[1].2 * w[1].2).sqrt();
                (w[0].0, w[1].0, (w[0].1 - w[1].1) / se)
            })
            .collect();
        told |= pairs.iter().any(|p| p.2 > 2.0);
        if pairs.iter().all(|p| p.2 > 2.0) {
            ordered.push(format!("{d:e}"));
        } else if pairs.iter().any(|p| p.2 > 2.0) {
            for &(a, b, z) in pairs.iter().filter(|p| p.2 <= 2.0) {
                if z < -2.0 {
                    inverted = true;
                    notes.push(format!(
                        "at Δ = {d:e}, {sym} = {b} lies above {sym} = {a} by {:.1} s.e.",
                        -z
                    ));
                } else {
                    tied = true;
                    notes.push(format!(
                        "at Δ = {d:e}, {sym} = {a} and {b} tie ({z:+.1} s.e.)"
                    ));
                }
            }
        }
    }
    let names: Vec<String> = by_delta.iter().map(|(n, _)| n.to_string()).collect();
    let mut text = if ordered.is_empty() {
        format!("no Δ where every {sym} is told apart")
    } else {
        format!(
            "φ_J({sym} = {}) in falling order at Δ = {}",
            names.join(" > "),
            ordered.join(", ")
        )
    };
    if !notes.is_empty() {
        text += "; ";
        text += &notes.join("; ");
    }
    let verdict = match (told, inverted, tied) {
        (_, true, _) => "no",
        (false, false, _) => "cannot tell",
        (true, false, true) => "partly",
        (true, false, false) => "yes",
    };
    (text, verdict)
}

#[cfg(test)]
mod tests {
    use super::{Series, convex_limits, phi_order};

    /// n = 2, 4, 5 at Δ from 0.01 to 0.3: the limits of n = 4 (0.235) and
    /// 5 (0.192) are drawn in their series' colours, the first with the
    /// legend; n = 2's (0.4) lies beyond the data and is left out.
    #[test]
    fn convex_limits_inside_the_data_are_drawn_in_their_modes_colours() {
        let series: Vec<Series> = (0..3)
            .map(|_| Series {
                label: String::new(),
                points: vec![(0.01, 0.84, 0.001), (0.3, 0.88, 0.001)],
                line: false,
            })
            .collect();
        let guides = convex_limits(&[2, 4, 5], &series);
        assert_eq!(guides.len(), 2);
        assert_eq!(guides[0].series, Some(1));
        assert_eq!(guides[1].series, Some(2));
        assert!((guides[0].points[0].0 - 4.0 / 17.0).abs() < 1e-15);
        assert!((guides[1].points[0].0 - 5.0 / 26.0).abs() < 1e-15);
        assert!(!guides[0].label.is_empty() && guides[1].label.is_empty());
    }

    /// Three n at two Δ, φ_J with s.e.m. 0.001: told apart by 0.01 (10
    /// s.e.), tied by 0.001 (0.7 s.e.), inverted by 0.01.
    #[test]
    fn the_order_in_n_is_judged_pair_by_pair_with_its_errors() {
        let series = |at_small: [f64; 3], at_large: [f64; 3]| {
            (2..5)
                .map(|n| {
                    let k = (n - 2) as usize;
                    (
                        n,
                        vec![(0.01, at_small[k], 0.001), (0.1, at_large[k], 0.001)],
                    )
                })
                .collect::<Vec<_>>()
        };
        let (text, verdict) = phi_order(&series([0.85, 0.85, 0.85], [0.9, 0.89, 0.88]), "n");
        assert_eq!(verdict, "yes", "{text}");
        assert!(
            text.contains("at Δ = 1e-1") && !text.contains("1e-2"),
            "{text}"
        );
        let (text, verdict) = phi_order(&series([0.85, 0.85, 0.85], [0.9, 0.89, 0.889]), "n");
        assert_eq!(verdict, "partly", "{text}");
        assert!(text.contains("n = 3 and 4 tie (+0.7 s.e.)"), "{text}");
        let (text, verdict) = phi_order(&series([0.85, 0.85, 0.85], [0.9, 0.88, 0.89]), "n");
        assert_eq!(verdict, "no", "{text}");
        assert!(
            text.contains("n = 4 lies above n = 3 by 7.1 s.e."),
            "{text}"
        );
        let (_, verdict) = phi_order(&series([0.85, 0.85, 0.85], [0.85, 0.85, 0.85]), "n");
        assert_eq!(verdict, "cannot tell");
        assert_eq!(
            phi_order(&series([0.9; 3], [0.9; 3])[..1], "n").1,
            "needs several mode numbers"
        );
    }
}
