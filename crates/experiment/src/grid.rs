//! Grid expansion: from an experiment to parameter points and samples.
//!
//! A family parameter given as a list (or, for a parameter that is itself a
//! list, as a list of lists) scans; so do `dim` and `particles`. The grid is
//! the Cartesian product, `dim` outermost, then `particles`, then the
//! parameters in the order the family declares them (the first declared
//! varies slowest), then the protocol's target (`Phi`'s φ, `Pressure`'s
//! pressure, `AboveJam`'s δφ) when the file gives a list of them.
//! The axes of `scan` (settings of the minimiser and the protocol, e.g. a
//! ladder of force tolerances) come between the parameters and the target,
//! the first axis varying slowest.
//! Each point runs `samples` packings with seeds `seed, seed + 1, …`: the
//! same seeds at every point, so points differ only by their parameters.

use crate::error::ExperimentError;
use crate::schema::{Experiment, Protocol, ScanSetting, scan_value_text};
use jamkit_core::FamilyInfo;
use jamkit_engine::{FireParams, JamSearch};
use jamkit_registry::{self as registry, ParamMap};

/// One parameter point of the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Position in the grid.
    pub index: usize,
    /// Spatial dimension.
    pub dim: usize,
    /// Number of bodies.
    pub particles: usize,
    /// Every family parameter (defaults filled in): what the family reads.
    pub params: ParamMap,
    /// The parameters as the point's label and packings record them:
    /// `params` without the added parameters that hold their value of
    /// before they existed (or `None`, which reads as a missing key), or
    /// that the file does not give and the family does not read here
    /// ([`jamkit_core::Added`]).
    pub record: ParamMap,
    /// The minimiser at this point (a scanned setting written in); the
    /// plan fills in the family's defaults (`dt_max`: the experiment's,
    /// else the family's, else 0.5) where it builds the point's shape
    /// (`Plan::new`).
    pub minimizer: FireParams,
    /// The protocol with this point's one target (φ, pressure or δφ: a
    /// list in the file scans, as the innermost axis of the grid).
    pub protocol: Protocol,
    /// The target's name in the label when the file scans it (`phi`, `p`,
    /// `dphi`), else `None` (labels as before targets could scan).
    pub target_label: Option<&'static str>,
    /// This point's values of the file's `scan` axes (empty when nothing
    /// scans), already written into `minimizer` and `protocol`.
    pub scan: ScanSetting,
}

impl Point {
    /// A file-name-safe label: `sphere_d2_N1024`, `fourier_d2_N256_delta0.01_n2`.
    pub fn label(&self, family: &str) -> String {
        let mut s = format!("{family}_d{}_N{}", self.dim, self.particles);
        // `None` (a default such as "inertia: None") says nothing: left out.
        for (k, v) in self
            .record
            .iter()
            .filter(|(_, v)| !matches!(v, ron::Value::Option(None) | ron::Value::Unit))
        {
            s.push('_');
            s.push_str(k);
            s.push_str(&short(&sanitize(&value_text(v))));
        }
        // A scanned setting by its last path part: `_force_tol1e-22`.
        for (k, v) in &self.scan {
            s.push('_');
            s.push_str(k.rsplit('.').next().unwrap_or(k));
            s.push_str(&short(&sanitize(&scan_value_text(v))));
        }
        if let Some(name) = self.target_label {
            let value = match &self.protocol {
                Protocol::Phi { phi: t, .. }
                | Protocol::Pressure { pressure: t, .. }
                | Protocol::AboveJam { delta_phi: t, .. } => t.first(),
                Protocol::Jam { .. } => None,
            };
            if let Some(v) = value {
                s.push('_');
                s.push_str(name);
                s.push_str(&sanitize(&format!("{v:e}")));
            }
        }
        s
    }
}

/// One packing to make.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// Index of its point.
    pub point: usize,
    /// Sample number within the point.
    pub sample: usize,
    /// Seed of its random stream.
    pub seed: u64,
    /// File-name-safe identifier, `<point label>_s<seed>`.
    pub id: String,
    /// Everything that shapes its packing, as the packing file records it
    /// ([`settings`]): a packing on disk with other settings is refused,
    /// one with the same is reused.
    pub settings: serde_json::Value,
}

/// A parameter value as compact RON text.
pub fn value_text(v: &ron::Value) -> String {
    ron::to_string(v).unwrap_or_else(|_| format!("{v:?}"))
}

/// Long values (mode lists) become a stable 16-hex-digit FNV-1a hash, so
/// file names stay short; the full value is in the packing file's `params`.
fn short(text: &str) -> String {
    if text.len() <= 24 {
        return text.to_string();
    }
    let hash = text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{hash:016x}")
}

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '+') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Values a parameter scans over.
fn scan_values(
    name: &str,
    value: &ron::Value,
    is_list: bool,
) -> Result<Vec<ron::Value>, ExperimentError> {
    let values = match value {
        ron::Value::Seq(items) if !is_list => items.clone(),
        ron::Value::Seq(items)
            if items
                .first()
                .is_some_and(|x| matches!(x, ron::Value::Seq(_))) =>
        {
            items.clone()
        }
        other => vec![other.clone()],
    };
    if values.is_empty() {
        return Err(ExperimentError::invalid(
            format!("params.{name}"),
            "[]",
            "a scan needs at least one value",
        ));
    }
    Ok(values)
}

/// The grid points of an experiment, in grid order: its lists and scans
/// expanded, every family parameter filled in (the family's defaults where
/// the file gives none). The plan builds each point's shape
/// (`Plan::new`).
pub fn points(experiment: &Experiment) -> Result<Vec<Point>, ExperimentError> {
    // Also checked by `validate`; a dimension listed twice would give two
    // points with the same label, hence the same packing ids.
    experiment.validate_dims()?;
    let info = registry::family_info(&experiment.family)?;
    let axes = param_axes(experiment, &info)?;
    let mut combos: Vec<ParamMap> = vec![ParamMap::new()];
    for (name, values) in &axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.insert(name.clone(), v.clone());
                    c
                })
            })
            .collect();
    }
    let scanned = experiment.scanned()?;
    let mut out = Vec::new();
    for dim in experiment.dim.values() {
        for particles in experiment.particles.values() {
            for params in &combos {
                for (scan, e) in &scanned {
                    let (protocols, target_label) = e.protocol.targets();
                    for protocol in protocols {
                        out.push(Point {
                            index: out.len(),
                            dim,
                            particles,
                            params: params.clone(),
                            record: record(experiment, &info, params),
                            minimizer: e.minimizer.clone(),
                            protocol,
                            target_label,
                            scan: scan.clone(),
                        });
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Every packing of the experiment, point by point.
pub fn jobs(experiment: &Experiment, points: &[Point]) -> Vec<Job> {
    let mut out = Vec::new();
    for p in points {
        let label = p.label(&experiment.family);
        for sample in 0..experiment.samples {
            let seed = experiment.seed.wrapping_add(sample as u64);
            out.push(Job {
                point: p.index,
                sample,
                seed,
                id: format!("{label}_s{seed}"),
                settings: settings(experiment, p, seed),
            });
        }
    }
    out
}

/// One part of an experiment's jobs, for running it as `count` processes
/// (`jamkit run --shard index/count`, e.g. one per task of a cluster job
/// array): job `j` (in grid order) belongs to part `j mod count + 1`, so
/// every part gets a share of every point. Packings are seeded per job, so
/// they are the same bits whatever the split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This part, `1 ≤ index ≤ count`.
    pub index: usize,
    /// Number of parts.
    pub count: usize,
}

impl Shard {
    /// Parse `I/K` (`1 ≤ I ≤ K`), naming `--shard` and the value when it is
    /// not one.
    pub fn parse(text: &str) -> Result<Self, ExperimentError> {
        let bad = || {
            ExperimentError::invalid(
                "--shard",
                text,
                "must be I/K with whole numbers 1 ≤ I ≤ K (part I of K, e.g. 2/4)",
            )
        };
        let (i, k) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = k.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether job number `j` (its place in [`jobs`]' list) is this part's.
    pub fn owns(&self, j: usize) -> bool {
        j % self.count + 1 == self.index
    }
}

/// The parameters of a point as its label and packings record them
/// ([`Point::record`]).
fn record(experiment: &Experiment, info: &FamilyInfo, params: &ParamMap) -> ParamMap {
    let value = |text: &str| ron::from_str::<ron::Value>(text).expect("family specs are valid RON");
    let mut out = params.clone();
    for spec in info.params {
        let Some(added) = spec.added else { continue };
        let here = params.get(spec.name);
        // `None` reads as a missing key, i.e. as `before`.
        let before = here
            .is_some_and(|v| *v == ron::Value::Option(None) || same_value(v, &value(added.before)));
        let unread = !experiment.params.contains_key(spec.name)
            && added.read_with.is_some_and(|(other, want)| {
                !params
                    .get(other)
                    .is_some_and(|v| same_value(v, &value(want)))
            });
        if before || unread {
            out.remove(spec.name);
        }
    }
    out
}

/// Two parameter values equal, strings compared without case (the families
/// read their named choices so).
fn same_value(a: &ron::Value, b: &ron::Value) -> bool {
    match (a, b) {
        (ron::Value::String(a), ron::Value::String(b)) => a.eq_ignore_ascii_case(b),
        _ => a == b,
    }
}

fn param_axes(
    experiment: &Experiment,
    info: &FamilyInfo,
) -> Result<Vec<(String, Vec<ron::Value>)>, ExperimentError> {
    for name in experiment.params.keys() {
        if info.param(name).is_none() {
            let known: Vec<&str> = info.params.iter().map(|p| p.name).collect();
            let allowed = if known.is_empty() {
                format!("family `{}` has no parameters", info.name)
            } else {
                format!(
                    "family `{}` has parameters: {}",
                    info.name,
                    known.join(", ")
                )
            };
            return Err(ExperimentError::invalid(
                format!("params.{name}"),
                "(given)",
                allowed,
            ));
        }
    }
    let mut axes = Vec::new();
    for spec in info.params {
        let value = match (experiment.params.get(spec.name), spec.default) {
            (Some(v), _) => v.clone(),
            (None, Some(default)) => ron::from_str(default).expect("family defaults are valid RON"),
            (None, None) => {
                return Err(ExperimentError::invalid(
                    format!("params.{}", spec.name),
                    "(missing)",
                    format!("is required: {}", spec.about),
                ));
            }
        };
        axes.push((
            spec.name.to_string(),
            scan_values(spec.name, &value, spec.is_list)?,
        ));
    }
    Ok(axes)
}

/// Everything that shapes one packing, for the resume check.
pub fn settings(experiment: &Experiment, point: &Point, seed: u64) -> serde_json::Value {
    let e = experiment;
    let minimizer = &point.minimizer;
    serde_json::json!({
        "dim": point.dim,
        "family": e.family,
        "params": point.record,
        "particles": point.particles,
        "seed": seed,
        "sizes": e.sizes,
        "protocol": protocol_settings(&point.protocol),
        "minimizer": minimizer_settings(minimizer, &point.protocol),
        "potential": e.potential,
        "rattlers": e.rattlers,
        "engine": e.engine,
    })
}

/// The protocol as a packing records it: as written to `experiment.ron`,
/// except that `search: Bisection`, `escape_saddles: false` and
/// `AboveJam`'s `rejams: 0` are left out. Packings made before these
/// fields existed were bisection packings without saddle escapes or
/// re-jams and record none, so they still resume under an explicit
/// `search: Bisection`, `escape_saddles: false` or `rejams: 0`; the others
/// (`Adaptive`, the default, and `Extrapolated`) are always written, so no
/// packing of one search is ever taken for another's.
fn protocol_settings(protocol: &Protocol) -> serde_json::Value {
    let mut value = serde_json::to_value(protocol).expect("protocol serialises");
    if let Some(jam) = value.get_mut("Jam").and_then(|j| j.as_object_mut()) {
        if jam.get("search") == Some(&serde_json::json!("Bisection")) {
            jam.remove("search");
        }
        if jam.get("escape_saddles") == Some(&serde_json::json!(false)) {
            jam.remove("escape_saddles");
        }
    }
    if let Some(above) = value.get_mut("AboveJam").and_then(|j| j.as_object_mut())
        && above.get("rejams") == Some(&serde_json::json!(0))
    {
        above.remove("rejams");
    }
    value
}

/// The minimiser as a packing records it: as resolved for the family
/// (`FireParams::for_family`), with five fields left out where packings
/// made before they existed hold them, so that those still resume under
/// an explicit setting: `lbfgs: None` (they ran without L-BFGS),
/// `masses: Plain`, `unjam_forecast` where it is off or does not act
/// (it acts in `Jam` and `AboveJam` with a search other than `Bisection`:
/// `jamkit_engine::jam`), `escape_plateaus` where it is off or does
/// not act (it acts with the Newton finish), and `stable_dt` where it is
/// off. Where the family's default is L-BFGS it is always
/// written, so no packing of one minimiser is ever taken for the other's.
fn minimizer_settings(minimizer: &FireParams, protocol: &Protocol) -> serde_json::Value {
    let mut value = serde_json::to_value(minimizer).expect("minimizer serialises");
    let forecast_acts = matches!(
        protocol,
        Protocol::Jam { search, .. } | Protocol::AboveJam { search, .. }
            if *search != JamSearch::Bisection
    );
    if let Some(m) = value.as_object_mut() {
        if m.get("lbfgs") == Some(&serde_json::Value::Null) {
            m.remove("lbfgs");
        }
        if !forecast_acts || m.get("unjam_forecast") == Some(&serde_json::Value::Bool(false)) {
            m.remove("unjam_forecast");
        }
        if m.get("newton") == Some(&serde_json::Value::Null)
            || m.get("escape_plateaus") == Some(&serde_json::Value::Bool(false))
        {
            m.remove("escape_plateaus");
        }
        if m.get("stable_dt") == Some(&serde_json::Value::Bool(false)) {
            m.remove("stable_dt");
        }
        if m.get("masses") == Some(&serde_json::json!("Plain")) {
            m.remove("masses");
        }
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn particles_list_expands_and_seeds_repeat_per_point() {
        let e = Experiment::from_ron(
            r#"(name: "g", family: "sphere", particles: [8, 16], samples: 2, seed: 5)"#,
            "g",
        )
        .unwrap();
        let pts = points(&e).unwrap();
        assert_eq!(
            pts.iter().map(|p| p.particles).collect::<Vec<_>>(),
            vec![8, 16]
        );
        let js = jobs(&e, &pts);
        let ids: Vec<&str> = js.iter().map(|j| j.id.as_str()).collect();
        assert_eq!(
            ids,
            vec![
                "sphere_d2_N8_s5",
                "sphere_d2_N8_s6",
                "sphere_d2_N16_s5",
                "sphere_d2_N16_s6"
            ]
        );
    }

    /// An added parameter (harmonic's `exact_solver`, added after
    /// packings were written without it, when they were `"Nested"`): the
    /// family reads the default the grid fills in, `"Joint"`; the record
    /// leaves it out where it is `"Nested"` (given, in any case) and, when
    /// the file does not give it, where the gap is not exact (the family
    /// does not read it there), so those points keep the labels and records
    /// of before it existed. Another optional parameter left out
    /// (`inertia`) is still recorded as `None`.
    #[test]
    fn an_added_parameter_is_recorded_only_where_it_differs_from_before_and_is_read() {
        let point = |gap: &str, extra: &str| {
            let e = Experiment::from_ron(
                &format!(
                    r#"(name: "g", dim: 3, family: "harmonic", particles: 8, params: {{"l": 2, "delta": 0.1, "gap": "{gap}"{extra}}})"#
                ),
                "g",
            )
            .unwrap();
            points(&e).unwrap().remove(0)
        };
        let joint = ron::Value::String("Joint".into());
        let absent = point("Exact", "");
        assert_eq!(absent.params.get("exact_solver"), Some(&joint));
        assert_eq!(absent.record.get("exact_solver"), Some(&joint));
        assert!(absent.label("harmonic").contains("exact_solver_Joint"));
        assert_eq!(
            absent.record.get("inertia"),
            Some(&ron::Value::Option(None))
        );
        // Read with an exact gap only; `gap` is read without case.
        let first = point("FirstOrder", "");
        assert_eq!(first.params.get("exact_solver"), Some(&joint));
        assert!(!first.record.contains_key("exact_solver"));
        assert!(!first.label("harmonic").contains("exact_solver"));
        assert!(point("exact", "").record.contains_key("exact_solver"));
        for nested in ["Nested", "nested"] {
            let given = point("Exact", &format!(r#", "exact_solver": "{nested}""#));
            assert_eq!(
                given.params.get("exact_solver"),
                Some(&ron::Value::String(nested.into()))
            );
            assert!(!given.record.contains_key("exact_solver"));
            assert!(!given.label("harmonic").contains("exact_solver"));
        }
        // Given, it is recorded wherever it differs from before.
        let given = point("FirstOrder", r#", "exact_solver": "Joint""#);
        assert_eq!(given.record.get("exact_solver"), Some(&joint));
        // `None` reads as a missing key: as before.
        let none = point("Exact", r#", "exact_solver": None"#);
        assert!(!none.record.contains_key("exact_solver"));
    }

    /// `ellipsoid`'s `warm_start` (added when packings were cold): absent,
    /// the family reads `true` and the record says so; `false` and `None`
    /// are left out of the record, as before the parameter existed.
    #[test]
    fn the_ellipsoid_warm_start_is_recorded_where_it_is_on() {
        let point = |extra: &str| {
            let e = Experiment::from_ron(
                &format!(
                    r#"(name: "g", dim: 3, family: "ellipsoid", particles: 8, params: {{"alpha": 1.5{extra}}})"#
                ),
                "g",
            )
            .unwrap();
            points(&e).unwrap().remove(0)
        };
        let on = ron::Value::Bool(true);
        let absent = point("");
        assert_eq!(absent.params.get("warm_start"), Some(&on));
        assert_eq!(absent.record.get("warm_start"), Some(&on));
        for off in ["false", "None"] {
            let p = point(&format!(r#", "warm_start": {off}"#));
            assert!(!p.record.contains_key("warm_start"), "{off}");
            assert!(!p.label("ellipsoid").contains("warm_start"), "{off}");
        }
    }

    #[test]
    fn unknown_parameter_is_rejected_with_the_family_named() {
        let e = Experiment::from_ron(
            r#"(name: "g", family: "sphere", particles: 8, params: {"delta": 0.1})"#,
            "g",
        )
        .unwrap();
        let err = points(&e).unwrap_err().to_string();
        assert!(
            err.contains("params.delta") && err.contains("no parameters"),
            "{err}"
        );
    }

    #[test]
    fn dim_list_is_the_outermost_axis_with_the_same_seeds() {
        let e = Experiment::from_ron(
            r#"(name: "g", dim: [2, 3], family: "sphere", particles: [8, 16], samples: 2, seed: 5)"#,
            "g",
        )
        .unwrap();
        e.validate().unwrap();
        let pts = points(&e).unwrap();
        assert_eq!(
            pts.iter()
                .map(|p| (p.index, p.dim, p.particles))
                .collect::<Vec<_>>(),
            vec![(0, 2, 8), (1, 2, 16), (2, 3, 8), (3, 3, 16)]
        );
        let labels: Vec<String> = pts.iter().map(|p| p.label("sphere")).collect();
        assert_eq!(
            labels,
            vec![
                "sphere_d2_N8",
                "sphere_d2_N16",
                "sphere_d3_N8",
                "sphere_d3_N16"
            ]
        );
        let js = jobs(&e, &pts);
        let ids: Vec<(usize, u64, &str)> = js
            .iter()
            .map(|j| (j.point, j.seed, j.id.as_str()))
            .collect();
        assert_eq!(
            ids,
            vec![
                (0, 5, "sphere_d2_N8_s5"),
                (0, 6, "sphere_d2_N8_s6"),
                (1, 5, "sphere_d2_N16_s5"),
                (1, 6, "sphere_d2_N16_s6"),
                (2, 5, "sphere_d3_N8_s5"),
                (2, 6, "sphere_d3_N8_s6"),
                (3, 5, "sphere_d3_N16_s5"),
                (3, 6, "sphere_d3_N16_s6"),
            ]
        );
    }

    #[test]
    fn scalar_dim_keeps_its_labels_and_default() {
        let e = Experiment::from_ron(
            r#"(name: "g", dim: 3, family: "sphere", particles: 8)"#,
            "g",
        )
        .unwrap();
        assert_eq!(e.dim, crate::schema::OneOrMany::One(3));
        let pts = points(&e).unwrap();
        assert_eq!(jobs(&e, &pts)[0].id, "sphere_d3_N8_s1");
        let e =
            Experiment::from_ron(r#"(name: "g", family: "sphere", particles: 8)"#, "g").unwrap();
        assert_eq!(points(&e).unwrap()[0].label("sphere"), "sphere_d2_N8");
    }

    /// The errors of `validate` and of `points` for an experiment text
    /// (both must refuse a bad `dim` list: `points` may run unvalidated).
    fn dim_errors(text: &str) -> [String; 2] {
        let e = Experiment::from_ron(text, "g").unwrap();
        [
            e.validate().unwrap_err().to_string(),
            points(&e).unwrap_err().to_string(),
        ]
    }

    #[test]
    fn bad_dim_in_a_list_is_named_with_its_value() {
        for err in dim_errors(r#"(name: "g", dim: [2, 7], family: "sphere", particles: 8)"#) {
            assert!(
                err.contains("dim = 7") && err.contains("supports dim 2 or 3 or 4"),
                "{err}"
            );
        }
        // A dimension the family lacks, in a list of otherwise good ones.
        let e = Experiment::from_ron(
            r#"(name: "g", dim: [3, 4], family: "nmer", particles: 8, params: {"alpha": 1.5})"#,
            "g",
        )
        .unwrap();
        let err = e.validate().unwrap_err().to_string();
        assert!(
            err.contains("dim = 4") && err.contains("`nmer` supports dim 2 or 3"),
            "{err}"
        );
    }

    #[test]
    fn duplicated_or_empty_dim_list_is_refused() {
        for err in dim_errors(r#"(name: "g", dim: [2, 3, 2], family: "sphere", particles: 8)"#) {
            assert!(
                err.contains("dim = 2") && err.contains("listed twice"),
                "{err}"
            );
        }
        let e = Experiment::from_ron(
            r#"(name: "g", dim: [], family: "sphere", particles: 8)"#,
            "g",
        )
        .unwrap();
        let err = e.validate().unwrap_err().to_string();
        assert!(
            err.contains("dim = []") && err.contains("at least one dimension"),
            "{err}"
        );
    }

    const LADDER: &str = r#"(name: "g", family: "sphere", particles: 8, samples: 2,
        protocol: Jam(energy_low: 1e-16, energy_high: 2e-16),
        scan: [
            {"protocol.energy_low": [1e-16, 1e-14], "protocol.energy_high": [2e-16, 2e-14]},
            {"minimizer.force_tol": [1e-20, 1e-25, 1e-28]},
        ])"#;

    #[test]
    fn scan_axes_cross_move_together_and_match_the_same_set() {
        let e = Experiment::from_ron(LADDER, "g").unwrap();
        e.validate().unwrap();
        let pts = points(&e).unwrap();
        // 2 windows × 3 tolerances, the first axis slowest.
        let got: Vec<(f64, f64, f64)> = pts
            .iter()
            .map(|p| match p.protocol {
                Protocol::Jam {
                    energy_low,
                    energy_high,
                    ..
                } => (energy_low, energy_high, p.minimizer.force_tol),
                _ => panic!("not Jam"),
            })
            .collect();
        assert_eq!(
            got,
            vec![
                (1e-16, 2e-16, 1e-20),
                (1e-16, 2e-16, 1e-25),
                (1e-16, 2e-16, 1e-28),
                (1e-14, 2e-14, 1e-20),
                (1e-14, 2e-14, 1e-25),
                (1e-14, 2e-14, 1e-28),
            ]
        );
        assert_eq!(
            pts[4].label("sphere"),
            "sphere_d2_N8_energy_high2e-14_energy_low1e-14_force_tol1e-25"
        );
        // Each point is the file with the same `--set`s, scan removed.
        let mut plain = e.clone();
        plain.scan.clear();
        let set = crate::overrides::apply(
            &plain,
            &[
                "protocol.energy_low=1e-14".into(),
                "protocol.energy_high=2e-14".into(),
                "minimizer.force_tol=1e-25".into(),
            ],
        )
        .unwrap();
        let one = &points(&set).unwrap()[0];
        assert_eq!(
            (&one.minimizer, &one.protocol),
            (&pts[4].minimizer, &pts[4].protocol)
        );
        let ids: Vec<String> = jobs(&e, &pts).into_iter().map(|j| j.id).collect();
        let mut unique = ids.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), 12, "{ids:?}");
        // Without a scan nothing changes: no scan in the label or the file.
        assert!(points(&plain).unwrap()[0].scan.is_empty());
        assert!(
            crate::overrides::apply(&plain, &[])
                .unwrap()
                .scan
                .is_empty()
        );
    }

    #[test]
    fn bad_scans_are_named_with_what_is_allowed() {
        for (scan, names) in [
            (r#"[{"params.delta": [0.1]}]"#, "scan[0].params.delta"),
            (
                r#"[{"engine.skin": [0.5]}]"#,
                "field of `minimizer` or `protocol`",
            ),
            (
                r#"[{"protocol.energy_low": [1e-16, 1e-14], "protocol.energy_high": [2e-16]}]"#,
                "as many as every other list",
            ),
            (r#"[{"minimizer.force_tol": []}]"#, "at least one value"),
            (
                r#"[{"minimizer.force_tol": [1e-20, 1e-22, 1e-20]}]"#,
                "minimizer.force_tol = 1e-20: is listed twice",
            ),
            (r#"[{}]"#, "an axis names at least one field"),
            (
                r#"[{"minimizer.force_tol": [1e-20]}, {"protocol.force_tol": [1e-20]}]"#,
                "second scanned field named `force_tol`",
            ),
            // Each setting is checked like the file: FIRE's energy_tol
            // (1e-16 by default) must stay below the window.
            (
                r#"[{"protocol.energy_low": [1e-18]}]"#,
                "protocol.energy_low = 1e-18",
            ),
            (
                r#"[{"minimizer.force_tol": [-1.0]}]"#,
                "minimizer.force_tol",
            ),
            (r#"[{"minimizer.no_such": [1.0]}]"#, "no_such"),
        ] {
            let text = format!(r#"(name: "g", family: "sphere", particles: 8, scan: {scan})"#);
            let e = Experiment::from_ron(&text, "g").unwrap();
            let err = e.validate().unwrap_err().to_string();
            assert!(err.contains(names), "{scan}: {err}");
            assert!(points(&e).is_err(), "{scan}");
        }
    }
}
