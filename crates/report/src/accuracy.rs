//! The accuracy comparisons of docs/reports/speed-vs-error.md, from run
//! directories: every packing against a reference packing of the same seed
//! (`jamkit report --accuracy …`, and `jamkit bench accuracy`, which runs
//! `experiments/accuracy/*.ron` and then these).
//!
//! * [`gap_models`]: packings per gap model and `Δ` (the runs of
//!   `experiments/accuracy/gap_models.ron`), each against the packing of
//!   the same `Δ` and seed with the most accurate model the runs hold
//!   (`Exact`): `φ_J`, `z_J`, `N_c`, rattlers; a table and `packings.csv`.
//! * [`tolerances`]: packings per setting of FIRE's force tolerance and the
//!   jamming window (the `scan` of `experiments/accuracy/tolerances.ron`),
//!   each against the tightest force tolerance that converged in the
//!   tightest window on the same seed; a table, `tolerances.csv` and the
//!   figure of time per packing against the change of `φ_J`.
//!
//! The packings are read from `DIR/packings/<id>.json`; a sample that
//! failed is read from the state it stopped at (`<id>.failed.json`, whose
//! `flag` is its error), or counted as missing when it left none.

use crate::ReportError;
use crate::plot::{Figure, Series};
use jamkit_core::stats::{mean, std_dev};
use jamkit_format::PackingFile;
use plotters::prelude::SeriesLabelPosition;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Where an unchanged φ_J is drawn on the log axis of the tolerance figure.
const ZERO_FLOOR: f64 = 1e-12;

/// One packing of a run, as the runner recorded it.
#[derive(Clone, Debug)]
pub struct PackRow {
    /// Its seed.
    pub seed: u64,
    /// `Err`: the protocol failed (its error).
    pub result: Result<PackResult, String>,
}

/// What a converged packing measured.
#[derive(Clone, Copy, Debug)]
pub struct PackResult {
    /// Wall time of the packing (s).
    pub wall_s: f64,
    /// FIRE steps.
    pub steps: u64,
    /// `φ_J`.
    pub phi: f64,
    /// `z_J`.
    pub z: f64,
    /// Contacts `N_c`.
    pub n_c: usize,
    /// Rattlers.
    pub rattlers: usize,
}

/// One packing file with what the comparisons group it by.
struct Record {
    file: PackingFile,
    failed: Option<String>,
}

impl Record {
    fn row(&self) -> PackRow {
        let m = &self.file.measures;
        PackRow {
            seed: self.file.seed,
            result: match &self.failed {
                Some(e) => Err(e.clone()),
                None => Ok(PackResult {
                    wall_s: m.wall_s,
                    steps: m.fire_steps,
                    phi: m.phi,
                    z: m.z_j.unwrap_or(f64::NAN),
                    n_c: m.n_contacts.unwrap_or(0),
                    rattlers: m.n_rattlers.unwrap_or(0),
                }),
            },
        }
    }

    /// A family parameter as text (`0.01`, `Exact`, `2`).
    fn param(&self, name: &str) -> Option<String> {
        self.file.params.get(name).map(text)
    }

    /// A setting by its path in the packing's `settings`, looking through
    /// an enum variant's name (`protocol.energy_low` reaches the `Jam`'s).
    fn setting(&self, path: &str) -> Option<&Value> {
        let mut node = &self.file.settings;
        for part in path.split('.') {
            node = match node.get(part) {
                Some(v) => v,
                None => node.as_object()?.values().next()?.get(part)?,
            };
        }
        Some(node)
    }

    fn number(&self, path: &str) -> f64 {
        self.setting(path)
            .and_then(Value::as_f64)
            .unwrap_or(f64::NAN)
    }
}

fn text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The packing files of `dirs`, with the failed samples' states, in name
/// order; every one must hold the contacts (`z_J`, `N_c` are compared).
fn records(dirs: &[impl AsRef<Path>]) -> Result<Vec<Record>, ReportError> {
    let mut out = Vec::new();
    for dir in dirs {
        let dir = dir.as_ref().join("packings");
        let entries = std::fs::read_dir(&dir).map_err(|error| ReportError::Io {
            path: dir.clone(),
            error,
        })?;
        let mut paths: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .collect();
        paths.sort();
        for path in paths {
            let failed = path.to_string_lossy().ends_with(".failed.json");
            let file = PackingFile::load(&path).ok_or_else(|| {
                ReportError::Accuracy(format!("{}: not a packing file", path.display()))
            })?;
            if !failed && file.measures.n_contacts.is_none() {
                return Err(ReportError::Accuracy(format!(
                    "{}: no contacts measured: the comparison needs the Contacts observable",
                    path.display()
                )));
            }
            let failed = failed.then(|| file.measures.flag.clone());
            out.push(Record { file, failed });
        }
    }
    if out.is_empty() {
        return Err(ReportError::NoPackings(names(dirs)));
    }
    Ok(out)
}

fn names(dirs: &[impl AsRef<Path>]) -> String {
    dirs.iter()
        .map(|d| d.as_ref().display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Packings by comparison group: `(key, one row per seed)`.
type Groups<K> = Vec<(K, Vec<PackRow>)>;

/// Group `records` by `key` (in the order `cmp` sorts the keys), one row
/// per seed that any group holds (`Err("no packing file")` where a group
/// lacks it: a failure that left no state), seeds ascending.
fn group<K: Clone + PartialEq>(
    records: &[Record],
    key: impl Fn(&Record) -> Result<K, ReportError>,
    cmp: impl Fn(&K, &K) -> std::cmp::Ordering,
) -> Result<(Groups<K>, Vec<u64>), ReportError> {
    let mut seeds: Vec<u64> = records.iter().map(|r| r.file.seed).collect();
    seeds.sort_unstable();
    seeds.dedup();
    let mut groups: Vec<(K, Vec<&Record>)> = Vec::new();
    for r in records {
        let k = key(r)?;
        match groups.iter_mut().find(|g| g.0 == k) {
            Some(g) => {
                if g.1.iter().any(|o| o.file.seed == r.file.seed) {
                    return Err(ReportError::Accuracy(format!(
                        "{} and another packing share their seed and comparison group: \
                         the runs scan something the comparison does not group by",
                        r.file.id
                    )));
                }
                g.1.push(r)
            }
            None => groups.push((k, vec![r])),
        }
    }
    groups.sort_by(|a, b| cmp(&a.0, &b.0));
    let groups = groups
        .into_iter()
        .map(|(k, rs)| {
            let rows = seeds
                .iter()
                .map(|&seed| match rs.iter().find(|r| r.file.seed == seed) {
                    Some(r) => r.row(),
                    None => PackRow {
                        seed,
                        result: Err("no packing file (a failed sample that left no state)".into()),
                    },
                })
                .collect();
            (k, rows)
        })
        .collect();
    Ok((groups, seeds))
}

/// `x` with `digits` decimals, "–" when undefined (no packing converged).
pub fn fixed(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

/// `x` as `1.23e-4`, "–" when undefined.
pub fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2e}")
    } else {
        "–".into()
    }
}

/// `(Δφ_J, Δz_J, ΔN_c, Δrattlers)` of one packing from its reference.
pub type Diff = (f64, f64, i64, i64);

/// The differences of `rows` from `reference`, seed by seed (both
/// converged).
pub fn differences(rows: &[PackRow], reference: &[PackRow]) -> Vec<Diff> {
    rows.iter()
        .filter_map(|r| {
            let e = reference.iter().find(|e| e.seed == r.seed)?;
            let (a, b) = (r.result.as_ref().ok()?, e.result.as_ref().ok()?);
            Some((
                a.phi - b.phi,
                a.z - b.z,
                a.n_c as i64 - b.n_c as i64,
                a.rattlers as i64 - b.rattlers as i64,
            ))
        })
        .collect()
}

fn ok_results(rows: &[PackRow]) -> Vec<PackResult> {
    rows.iter()
        .filter_map(|r| r.result.as_ref().ok().copied())
        .collect()
}

fn write(path: &Path, text: &str) -> Result<(), ReportError> {
    jamkit_format::write_atomic(path, text.as_bytes())
        .map_err(|e| ReportError::Accuracy(format!("writing {}: {e}", path.display())))
}

const CSV_HEADER: &str = "seed,wall_s,fire_steps,phi_j,z_j,n_c,rattlers,\
                          d_phi_j,d_z_j,d_n_c,d_rattlers,error\n";

/// One line per packing, with its differences from the reference packing
/// of its seed (empty when either failed; exactly 0 on the reference's own
/// line).
fn csv_line(s: &mut String, prefix: String, r: &PackRow, reference: &[PackRow]) {
    let d = differences(std::slice::from_ref(r), reference);
    let d = match d.first() {
        Some((dp, dz, dn, dr)) => format!("{dp:e},{dz:e},{dn},{dr}"),
        None => ",,,".into(),
    };
    let _ = match &r.result {
        Ok(p) => writeln!(
            s,
            "{prefix},{},{:.3},{},{:.9},{:.5},{},{},{d},",
            r.seed, p.wall_s, p.steps, p.phi, p.z, p.n_c, p.rattlers
        ),
        Err(e) => writeln!(
            s,
            "{prefix},{},,,,,,,{d},\"{}\"",
            r.seed,
            e.replace(['"', ','], ";")
        ),
    };
}

fn seed_list(seeds: &[u64]) -> String {
    seeds
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The packings of a gap-model run, per `Δ` and model.
pub struct GapModels {
    /// `(Δ, n, model, rows)`, by `Δ` and then model name.
    pub runs: Vec<(String, String, String, Vec<PackRow>)>,
    seeds: Vec<u64>,
    particles: usize,
    force_tol: f64,
    window: (f64, f64),
}

/// How close a gap model is to the exact gap (the most accurate one of a
/// `Δ` is the reference of its packings).
fn accuracy_rank(model: &str) -> usize {
    ["FirstOrder", "SecondOrder", "Exact"]
        .iter()
        .position(|m| *m == model)
        .unwrap_or(0)
}

impl GapModels {
    /// The packings of `dirs`, grouped by `params.delta` and `params.gap`.
    pub fn load(dirs: &[impl AsRef<Path>]) -> Result<Self, ReportError> {
        let records = records(dirs)?;
        let key = |r: &Record| match (r.param("delta"), r.param("gap"), r.param("n")) {
            (Some(d), Some(g), Some(n)) => Ok((d, n, g)),
            _ => Err(ReportError::Accuracy(format!(
                "{}: family {}: the gap-model comparison needs the parameters n, delta and gap \
                 (family fourier)",
                r.file.id, r.file.family
            ))),
        };
        let num = |s: &String| s.parse::<f64>().unwrap_or(f64::NAN);
        let (groups, seeds) = group(&records, key, |a, b| {
            num(&a.0).total_cmp(&num(&b.0)).then(a.2.cmp(&b.2))
        })?;
        let first = &records[0];
        Ok(GapModels {
            runs: groups
                .into_iter()
                .map(|((d, n, g), rows)| (d, n, g, rows))
                .collect(),
            seeds,
            particles: first.file.particles,
            force_tol: first.number("minimizer.force_tol"),
            window: (
                first.number("protocol.energy_low"),
                first.number("protocol.energy_high"),
            ),
        })
    }

    /// The model whose packings are the reference at `delta`: the most
    /// accurate one the runs hold (`Exact`).
    pub fn reference_model(&self, delta: &str) -> String {
        self.runs
            .iter()
            .filter(|r| r.0 == delta)
            .max_by_key(|r| accuracy_rank(&r.2))
            .map(|r| r.2.clone())
            .unwrap_or_default()
    }

    fn reference_rows(&self, delta: &str) -> &[PackRow] {
        let model = self.reference_model(delta);
        self.runs
            .iter()
            .find(|r| r.0 == delta && r.2 == model)
            .map(|r| r.3.as_slice())
            .unwrap_or(&[])
    }

    /// `packings.csv`: one line per packing with its differences.
    pub fn csv(&self) -> String {
        let mut s = format!("model,n,delta,particles,reference,{CSV_HEADER}");
        for (delta, n, model, rows) in &self.runs {
            let reference = self.reference_model(delta);
            for r in rows {
                let prefix = format!("{model},{n},{delta},{},{reference}", self.particles);
                csv_line(&mut s, prefix, r, self.reference_rows(delta));
            }
        }
        s
    }

    /// The markdown table; `source` names the experiment file.
    pub fn table(&self, source: &str) -> String {
        let mut md = String::new();
        let particles = self.particles;
        let (lo, hi) = self.window;
        let _ = writeln!(
            md,
            "## Packings\n\n\
             `{source}`: near-disks, N = {particles}{}, the paper's protocol (FIRE force tolerance \
             {:e}, window {lo:e} < V/N < {hi:e}, bisection), seeds {}: one packing per seed \
             and model, each seed the same random start for every model (the runner seeds a \
             start by its seed alone). Means over seeds; \"vs ref.\": the largest difference \
             over seeds from the packing of the same seed with the most accurate model of the \
             run (the \"ref.\" row: Exact), signed mean in brackets; \"sd\": the standard \
             deviation of φ_J across seeds, the statistical error one pays anyway. The run: \
             `RUNS/gap_models` (`results.csv`, `summary.csv`).\n",
            if particles < 256 {
                " (not more: Exact packings take minutes each at N = 256; the N = 256 \
                 comparison is the Fig. 5 gap-model run of docs/reports/paper-2d.md)"
            } else {
                ""
            },
            self.force_tol,
            seed_list(&self.seeds),
        );
        md.push_str(
            "| Δ | model | ok | wall s | FIRE steps | φ_J | sd φ_J | z_J | N_c | rattlers \
             | max \\|Δφ_J\\| (mean Δφ_J) | max \\|Δz_J\\| | max \\|ΔN_c\\| | max \\|Δrattlers\\| |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for (delta, _, model, rows) in &self.runs {
            let ok = ok_results(rows);
            let col = |f: fn(&PackResult) -> f64, digits: usize| {
                fixed(mean(&ok.iter().map(f).collect::<Vec<_>>()), digits)
            };
            let phis: Vec<f64> = ok.iter().map(|r| r.phi).collect();
            let diffs = if *model == self.reference_model(delta) {
                None
            } else {
                Some(differences(rows, self.reference_rows(delta)))
            };
            let dcol = |f: &dyn Fn(&Diff) -> f64, digits: usize| match &diffs {
                Some(d) if !d.is_empty() => {
                    format!("{:.*}", digits, d.iter().map(f).fold(0.0f64, f64::max))
                }
                Some(_) => "–".into(),
                None => "ref.".into(),
            };
            let dphi = match &diffs {
                Some(d) if !d.is_empty() => format!(
                    "{} ({:+.1e})",
                    sci(d.iter().map(|x| x.0.abs()).fold(0.0f64, f64::max)),
                    mean(&d.iter().map(|x| x.0).collect::<Vec<_>>())
                ),
                Some(_) => "–".into(),
                None => "ref.".into(),
            };
            let _ = writeln!(
                md,
                "| {delta} | {model} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {dphi} | {} | {} | {} |",
                ok.len(),
                rows.len(),
                col(|r| r.wall_s, 2),
                col(|r| r.steps as f64, 0),
                col(|r| r.phi, 6),
                sci(std_dev(&phis)),
                col(|r| r.z, 4),
                col(|r| r.n_c as f64, 1),
                col(|r| r.rattlers as f64, 1),
                dcol(&|x| x.1.abs(), 4),
                dcol(&|x| x.2.abs() as f64, 0),
                dcol(&|x| x.3.abs() as f64, 0),
            );
        }
        for (delta, _, model, rows) in &self.runs {
            for r in rows {
                if let Err(e) = &r.result {
                    let _ = writeln!(md, "\nΔ = {delta}, {model}, seed {}: failed: {e}", r.seed);
                }
            }
        }
        md.push_str("\nPer packing: [packings.csv](packings.csv).\n\n");
        md
    }
}

/// A setting of the ladder: `((energy_low, energy_high), force_tol)`.
pub type Setting = ((f64, f64), f64);

/// The packings of a tolerance ladder, per setting.
pub struct Tolerances {
    /// Per setting (windows tightest first, then force tolerances loosest
    /// first), its packings.
    pub runs: Vec<(Setting, Vec<PackRow>)>,
    seeds: Vec<u64>,
    particles: usize,
    max_steps: String,
    /// `(gap, n, delta)` of the near-disks.
    params: (String, String, String),
}

impl Tolerances {
    /// The packings of `dirs`, grouped by `protocol.energy_low`,
    /// `protocol.energy_high` and `minimizer.force_tol`.
    pub fn load(dirs: &[impl AsRef<Path>]) -> Result<Self, ReportError> {
        let records = records(dirs)?;
        let key = |r: &Record| {
            let k = (
                (
                    r.number("protocol.energy_low"),
                    r.number("protocol.energy_high"),
                ),
                r.number("minimizer.force_tol"),
            );
            if k.0.0.is_finite() && k.0.1.is_finite() && k.1.is_finite() {
                Ok(k)
            } else {
                Err(ReportError::Accuracy(format!(
                    "{}: protocol {}: the tolerance comparison needs Jam packings \
                     (energy_low, energy_high and minimizer.force_tol in their settings)",
                    r.file.id, r.file.protocol
                )))
            }
        };
        let (runs, seeds) = group(&records, key, |a: &Setting, b: &Setting| {
            (a.0.0.total_cmp(&b.0.0))
                .then(a.0.1.total_cmp(&b.0.1))
                .then(b.1.total_cmp(&a.1))
        })?;
        let first = &records[0];
        let p = |name| first.param(name).unwrap_or_default();
        Ok(Tolerances {
            runs,
            seeds,
            particles: first.file.particles,
            max_steps: first
                .setting("minimizer.max_steps")
                .map(text)
                .unwrap_or_default(),
            params: (p("gap"), p("n"), p("delta")),
        })
    }

    /// The tightest window (the paper's), where references are taken.
    fn reference_window(&self) -> Option<(f64, f64)> {
        self.runs.first().map(|((w, _), _)| *w)
    }

    /// Per seed, the packing of the tightest force tolerance that converged
    /// in the tightest window, with that tolerance.
    pub fn reference(&self) -> Vec<(PackRow, f64)> {
        let mut refs: Vec<(PackRow, f64)> = Vec::new();
        for ((w, ft), rows) in self.runs.iter().rev() {
            if Some(*w) != self.reference_window() {
                continue;
            }
            for r in rows {
                if r.result.is_ok() && !refs.iter().any(|(e, _)| e.seed == r.seed) {
                    refs.push((r.clone(), *ft));
                }
            }
        }
        refs.sort_by_key(|(r, _)| r.seed);
        refs
    }

    /// True when `setting` is the reference of every seed.
    fn is_reference(&self, refs: &[(PackRow, f64)], setting: Setting) -> bool {
        Some(setting.0) == self.reference_window()
            && !refs.is_empty()
            && refs.iter().all(|(_, ft)| *ft == setting.1)
    }

    /// `tolerances.csv`: one line per packing with its differences.
    pub fn csv(&self) -> String {
        let reference: Vec<PackRow> = self.reference().into_iter().map(|(r, _)| r).collect();
        let mut s = format!("energy_low,energy_high,force_tol,particles,{CSV_HEADER}");
        for (((lo, hi), ft), rows) in &self.runs {
            for r in rows {
                let prefix = format!("{lo:e},{hi:e},{ft:e},{}", self.particles);
                csv_line(&mut s, prefix, r, &reference);
            }
        }
        s
    }

    /// The markdown table; `source` names the experiment file.
    pub fn table(&self, source: &str) -> String {
        let mut md = String::new();
        let refs = self.reference();
        let reference: Vec<PackRow> = refs.iter().map(|(r, _)| r.clone()).collect();
        let ref_text: Vec<String> = refs
            .iter()
            .map(|(r, ft)| format!("seed {}: {ft:.0e}", r.seed))
            .collect();
        let (gap, n, delta) = &self.params;
        let _ = writeln!(
            md,
            "## Tolerances\n\n\
             `{source}`: {gap} near-disks n = {n}, Δ = {delta}, N = {}, seeds {}, one grid point \
             per setting (its `scan`; the run: `RUNS/tolerances`): FIRE's force \
             tolerance (stop when Σ(∂V/∂q)² falls below it; the default is 1e-25) and \
             the jamming window (the paper's 1e-16 < V/N < 2e-16, and one 100× looser, \
             the shortcut a user would try; a tighter one would need FIRE's \
             energy_tol = 1e-16 moved as well, mixing two changes). At most {} \
             FIRE steps per minimisation: a tolerance FIRE cannot reach fails. Differences \
             are from the tightest force tolerance that converged in the paper's window on \
             the same seed ({}), largest over seeds; \"sd φ_J\" is the spread across seeds \
             at that setting.\n",
            self.particles,
            seed_list(&self.seeds),
            self.max_steps,
            ref_text.join(", ")
        );
        md.push_str(
            "| window V/N | force tol | ok | wall s | FIRE steps | max \\|Δφ_J\\| | max \\|ΔN_c\\| \
             | max \\|Δrattlers\\| | sd φ_J |\n|---|---|---|---|---|---|---|---|---|\n",
        );
        for (((lo, hi), ft), rows) in &self.runs {
            let ok = ok_results(rows);
            let d = differences(rows, &reference);
            let is_ref = self.is_reference(&refs, ((*lo, *hi), *ft));
            let dmax = |f: &dyn Fn(&Diff) -> f64, fmt: &dyn Fn(f64) -> String| {
                if is_ref {
                    "ref.".to_string()
                } else if d.is_empty() {
                    "–".into()
                } else {
                    fmt(d.iter().map(f).fold(0.0f64, f64::max))
                }
            };
            let phis: Vec<f64> = ok.iter().map(|r| r.phi).collect();
            let _ = writeln!(
                md,
                "| {lo:.0e}…{hi:.0e} | {ft:.0e} | {}/{} | {} | {} | {} | {} | {} | {} |",
                ok.len(),
                rows.len(),
                fixed(mean(&ok.iter().map(|r| r.wall_s).collect::<Vec<_>>()), 2),
                fixed(
                    mean(&ok.iter().map(|r| r.steps as f64).collect::<Vec<_>>()),
                    0
                ),
                dmax(&|x| x.0.abs(), &sci),
                dmax(&|x| x.2.abs() as f64, &|v| format!("{v:.0}")),
                dmax(&|x| x.3.abs() as f64, &|v| format!("{v:.0}")),
                sci(std_dev(&phis)),
            );
        }
        for (((lo, _), ft), rows) in &self.runs {
            for r in rows {
                if let Err(e) = &r.result {
                    let _ = writeln!(
                        md,
                        "\nwindow from {lo:e}, force tolerance {ft:e}, seed {}: failed: {e}",
                        r.seed
                    );
                }
            }
        }
        md.push_str(
            "\nPer packing: [tolerances.csv](tolerances.csv). Figure: [time per packing \
             against the change of φ_J](tolerances.png) ([SVG](tolerances.svg)).\n",
        );
        md
    }

    /// The figure of time per packing against the largest change of φ_J
    /// from the reference, one series per window, as `stem`.png and .svg.
    pub fn figure(&self, stem: &Path) -> Result<(), ReportError> {
        let refs = self.reference();
        let reference: Vec<PackRow> = refs.iter().map(|(r, _)| r.clone()).collect();
        // (window, time, largest |Δφ_J|) per setting but the reference.
        let points: Vec<((f64, f64), f64, f64)> = self
            .runs
            .iter()
            .filter(|(setting, _)| !self.is_reference(&refs, *setting))
            .filter_map(|((w, _), rows)| {
                let ok = ok_results(rows);
                let d = differences(rows, &reference);
                if ok.is_empty() || d.is_empty() {
                    return None;
                }
                let t = mean(&ok.iter().map(|r| r.wall_s).collect::<Vec<_>>());
                Some((*w, t, d.iter().map(|x| x.0.abs()).fold(0.0f64, f64::max)))
            })
            .collect();
        let mut windows: Vec<(f64, f64)> = self.runs.iter().map(|((w, _), _)| *w).collect();
        windows.dedup();
        let mut series: Vec<Series> = windows
            .iter()
            .map(|&w| Series {
                label: format!("window {:.0e} < V/N < {:.0e}", w.0, w.1),
                points: points
                    .iter()
                    .filter(|p| p.0 == w && p.2 > 0.0)
                    .map(|p| (p.1, p.2, 0.0))
                    .collect(),
                line: false,
            })
            .collect();
        series.push(Series {
            label: format!("φ_J unchanged (drawn at {ZERO_FLOOR:.0e})"),
            points: points
                .iter()
                .filter(|p| p.2 == 0.0)
                .map(|p| (p.1, ZERO_FLOOR, 0.0))
                .collect(),
            line: false,
        });
        let (gap, n, delta) = &self.params;
        Figure {
            title: format!(
                "FIRE tolerance: time against change of φ_J ({gap}, n = {n}, Δ = {delta})"
            ),
            x_label: "wall time per packing (s)".into(),
            y_label: "max |φ_J − φ_J(tightest converged)|".into(),
            log_x: true,
            log_y: true,
            series,
            guides: Vec::new(),
            legend: SeriesLabelPosition::UpperRight,
        }
        .write(stem)
    }
}

/// Which comparison `jamkit report --accuracy` makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Study {
    /// [`GapModels`].
    GapModels,
    /// [`Tolerances`].
    Tolerances,
}

impl Study {
    /// `gap-models` or `tolerances`, naming the option in the error.
    pub fn parse(text: &str) -> Result<Self, ReportError> {
        match text {
            "gap-models" => Ok(Study::GapModels),
            "tolerances" => Ok(Study::Tolerances),
            other => Err(ReportError::Accuracy(format!(
                "--accuracy {other}: must be gap-models (the runs of \
                 experiments/accuracy/gap_models.ron) or tolerances (of tolerances.ron)"
            ))),
        }
    }
}

/// The comparison `study` of the runs in `dirs` into `out`: its CSV
/// (`packings.csv` or `tolerances.csv`), the tolerance figure, and the
/// markdown section, which is returned; `source` names the experiment file
/// in the text.
pub fn report(
    study: Study,
    dirs: &[impl AsRef<Path>],
    out: &Path,
    source: &str,
) -> Result<String, ReportError> {
    std::fs::create_dir_all(out).map_err(|error| ReportError::Io {
        path: out.to_path_buf(),
        error,
    })?;
    match study {
        Study::GapModels => {
            let g = GapModels::load(dirs)?;
            write(&out.join("packings.csv"), &g.csv())?;
            Ok(g.table(source))
        }
        Study::Tolerances => {
            let t = Tolerances::load(dirs)?;
            write(&out.join("tolerances.csv"), &t.csv())?;
            t.figure(&out.join("tolerances"))?;
            Ok(t.table(source))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(seed: u64, phi: f64, n_c: usize) -> PackRow {
        PackRow {
            seed,
            result: Ok(PackResult {
                wall_s: 1.0,
                steps: 10,
                phi,
                z: 4.0,
                n_c,
                rattlers: 0,
            }),
        }
    }

    fn failed(seed: u64) -> PackRow {
        PackRow {
            seed,
            result: Err("FIRE did not converge".into()),
        }
    }

    /// A ladder where seed 1 fails at the tightest tolerance: its reference
    /// is the next one that converged, and no setting is everyone's
    /// reference then.
    #[test]
    fn tolerance_reference_is_the_tightest_converged_per_seed() {
        let (w, loose) = ((1e-16, 2e-16), (1e-14, 2e-14));
        let t = Tolerances {
            runs: vec![
                ((w, 1e-20), vec![ok(1, 0.84, 30), ok(2, 0.85, 31)]),
                ((w, 1e-26), vec![ok(1, 0.841, 32), ok(2, 0.851, 31)]),
                ((w, 1e-28), vec![failed(1), ok(2, 0.852, 33)]),
                ((loose, 1e-28), vec![ok(1, 0.9, 32), ok(2, 0.9, 33)]),
            ],
            seeds: vec![1, 2],
            particles: 12,
            max_steps: "1000".into(),
            params: ("FirstOrder".into(), "2".into(), "0.1".into()),
        };
        let refs: Vec<(u64, f64)> = t.reference().iter().map(|(r, ft)| (r.seed, *ft)).collect();
        assert_eq!(refs, vec![(1, 1e-26), (2, 1e-28)]);
        let refs = t.reference();
        assert!(!t.is_reference(&refs, (w, 1e-28)));
        let csv = t.csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 1 + 8);
        // Seed 1 at 1e-20 against its reference 1e-26: Δφ = 0.84 − 0.841.
        let d: f64 = lines[1].split(',').nth(11).unwrap().parse().unwrap();
        assert_eq!(d, 0.84 - 0.841);
        assert_eq!(lines[1].split(',').nth(13), Some("-2"));
        // The failed packing: no numbers, no differences, its error.
        assert!(
            lines[5].starts_with("1e-16,2e-16,1e-28,12,1,,,,,,,,,,,\"FIRE"),
            "{}",
            lines[5]
        );
        let md = t.table("tolerances.ron");
        assert!(md.contains("seed 1: 1e-26, seed 2: 1e-28"), "{md}");
        assert!(md.contains("| 1e-16…2e-16 | 1e-28 | 1/2 |"), "{md}");
        assert!(md.contains("seed 1: failed: FIRE did not converge"), "{md}");
    }

    #[test]
    fn the_most_accurate_model_of_a_delta_is_its_reference() {
        let runs = [
            ("0.1", "Exact", 0.8, 20),
            ("0.1", "FirstOrder", 0.81, 21),
            ("0.2", "FirstOrder", 0.7, 20),
            ("0.2", "SecondOrder", 0.72, 20),
        ];
        let g = GapModels {
            runs: runs
                .iter()
                .map(|&(d, m, phi, n_c)| (d.into(), "2".into(), m.into(), vec![ok(1, phi, n_c)]))
                .collect(),
            seeds: vec![1],
            particles: 10,
            force_tol: 1e-25,
            window: (1e-16, 2e-16),
        };
        assert_eq!(g.reference_model("0.1"), "Exact");
        assert_eq!(g.reference_model("0.2"), "SecondOrder");
        let csv = g.csv();
        let row = csv.lines().nth(3).unwrap();
        assert!(
            row.starts_with("FirstOrder,2,0.2,10,SecondOrder,1,"),
            "{row}"
        );
        let d: f64 = row.split(',').nth(12).unwrap().parse().unwrap();
        assert_eq!(d, 0.7 - 0.72);
    }
}
