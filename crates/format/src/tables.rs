//! The tables a run writes beside its packings: `results.csv` (a row per
//! packing), `summary.csv` (mean and standard error per parameter point),
//! `dos.csv` (pooled `D(ω)`) and `gaps.csv` (pooled `Z(h)`). Cells are
//! formatted here (one number format per column, an empty cell for what
//! was not measured or a mean of nothing); quoting and line ends are the
//! `csv` crate's. Columns: `docs/reference/output-files.md`.

use crate::record::{ModuliMeasures, PackingFile, SpectrumMeasures};
use jamkit_core::records::DosHistogram;
use jamkit_core::stats::mean_sem;

/// `head` and `rows` as CSV text: a cell is quoted where it holds a comma,
/// a quote or a line end; every row has the header's columns.
fn table(head: &[String], rows: Vec<Vec<String>>) -> String {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    for row in std::iter::once(head).chain(rows.iter().map(Vec::as_slice)) {
        debug_assert_eq!(row.len(), head.len(), "a row of {} cells", row.len());
        w.write_record(row).expect("writing to memory cannot fail");
    }
    let bytes = w.into_inner().expect("flushing to memory cannot fail");
    String::from_utf8(bytes).expect("cells are UTF-8")
}

fn opt<T: ToString>(v: &Option<T>) -> String {
    v.as_ref().map(T::to_string).unwrap_or_default()
}

/// A number for a CSV cell; a mean of nothing (NaN) is an empty cell.
fn num(x: f64, scientific: bool) -> String {
    match (x.is_nan(), scientific) {
        (true, _) => String::new(),
        (false, true) => format!("{x:e}"),
        (false, false) => format!("{x}"),
    }
}

/// The parameter names of a set of packings, in order.
fn param_names(files: &[PackingFile]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for f in files {
        if let Some(obj) = f.params.as_object() {
            for k in obj.keys() {
                if !names.contains(k) {
                    names.push(k.clone());
                }
            }
        }
    }
    names
}

fn param_cells(f: &PackingFile, names: &[String]) -> Vec<String> {
    names
        .iter()
        .map(|n| {
            // An absent optional (`None`, JSON null) is an empty cell, a
            // text value its text (no JSON quotes), a number its digits.
            match f.params.get(n) {
                None | Some(serde_json::Value::Null) => String::new(),
                Some(serde_json::Value::String(s)) => s.clone(),
                Some(v) => v.to_string(),
            }
        })
        .collect()
}

/// The value at a setting path (`minimizer.force_tol`,
/// `protocol.energy_low`) of a packing's `settings`, as a cell: a float in
/// exponent form (`1e-22`, as in the packing ids), an integer as its
/// digits, a text as its plain text, anything else as compact JSON; empty
/// where the packing records no such setting.
fn setting_cell(settings: &serde_json::Value, path: &str) -> String {
    let mut v = settings;
    for part in path.split('.') {
        let next = v.get(part).or_else(|| {
            // An enum in its tagged form (`"protocol": {"Jam": {…}}`): the
            // field of its one variant.
            let o = v.as_object().filter(|o| o.len() == 1)?;
            o.values().next()?.get(part)
        });
        match next {
            Some(n) => v = n,
            None => return String::new(),
        }
    }
    match v {
        serde_json::Value::Null => String::new(),
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) if n.is_f64() => num(n.as_f64().unwrap_or(f64::NAN), true),
        other => other.to_string(),
    }
}

/// `results.csv`: one row per packing. `scanned` are the setting paths of
/// the experiment's `scan` (empty when it has none): one column each,
/// named by the path, after the family parameters, with the value the
/// packing's `settings` record.
pub fn results_csv(files: &[PackingFile], scanned: &[String]) -> String {
    let names = param_names(files);
    let mut head = vec!["id", "family", "dim", "particles", "seed"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    head.extend(names.iter().cloned());
    head.extend(scanned.iter().cloned());
    head.extend(
        [
            "protocol",
            "phi_j",
            "energy_per_particle",
            "n_contacts",
            "n_rattlers",
            "n_rot_rattlers",
            "z_j",
            "z_corr",
            "iso_margin",
            "pressure",
            "fire_steps",
            "minimizations",
            "wall_s",
            "flag",
        ]
        .map(String::from),
    );
    let with_spectrum = files.iter().any(|f| f.measures.spectrum.is_some());
    let with_gaps = files.iter().any(|f| f.measures.gaps.is_some());
    let with_moduli = files.iter().any(|f| f.measures.moduli.is_some());
    // Only when some packing escaped saddles, so that tables of runs
    // without the escape keep their columns.
    let with_escapes = files.iter().any(|f| f.measures.saddle_escapes.is_some());
    if with_escapes {
        head.push("saddle_escapes".into());
    }
    // Likewise only when some packing ran L-BFGS, escaped a plateau or
    // had FIRE's `Δt_max` lowered.
    let with_lbfgs = files.iter().any(|f| f.measures.lbfgs_evaluations.is_some());
    if with_lbfgs {
        head.push("lbfgs_evals".into());
    }
    let with_plateaus = files.iter().any(|f| f.measures.plateau_escapes.is_some());
    if with_plateaus {
        head.push("plateau_escapes".into());
    }
    let with_dt_cuts = files.iter().any(|f| f.measures.dt_cuts.is_some());
    if with_dt_cuts {
        head.push("dt_cuts".into());
    }
    if with_spectrum {
        head.extend(SPECTRUM_COLUMNS.map(String::from));
    }
    if with_gaps {
        head.push("gaps".into());
    }
    if with_moduli {
        head.extend(MODULI_COLUMNS.map(String::from));
    }
    let with_jam_point = files.iter().any(|f| f.measures.jam_point.is_some());
    if with_jam_point {
        head.extend(JAM_POINT_COLUMNS.map(String::from));
    }
    // Only when some packing was shear-stabilised with its cell's contacts
    // recorded, so that other tables keep their columns.
    let cell_contacts = |f: &PackingFile| {
        (f.measures.moduli.as_ref())
            .and_then(|m| m.stabilisation.as_ref())
            .and_then(|s| s.contacts.clone())
    };
    let with_cell_contacts = files.iter().any(|f| cell_contacts(f).is_some());
    if with_cell_contacts {
        head.extend(CELL_CONTACTS_COLUMNS.map(String::from));
    }
    // How often each `AboveJam` packing was jammed again after unjamming
    // on its way up; only when some was, so that other tables keep their
    // columns.
    let rejams = |f: &PackingFile| f.measures.jam_point.as_ref().map_or(0, |j| j.left.len());
    let with_rejams = files.iter().any(|f| rejams(f) > 0);
    if with_rejams {
        head.push("jam_rejams".into());
    }
    let mut rows = Vec::with_capacity(files.len());
    for f in files {
        let m = &f.measures;
        let mut row = vec![
            f.id.clone(),
            f.family.clone(),
            f.dim.to_string(),
            f.particles.to_string(),
            f.seed.to_string(),
        ];
        row.extend(param_cells(f, &names));
        row.extend(scanned.iter().map(|path| setting_cell(&f.settings, path)));
        row.extend([
            f.protocol.clone(),
            format!("{}", m.phi),
            format!("{:e}", m.energy_per_particle),
            opt(&m.n_contacts),
            opt(&m.n_rattlers),
            opt(&m.n_rot_rattlers),
            opt(&m.z_j),
            opt(&f.z_corr()),
            opt(&m.iso_margin),
            m.pressure.map(|p| format!("{p:e}")).unwrap_or_default(),
            m.fire_steps.to_string(),
            m.minimizations.to_string(),
            format!("{:.3}", m.wall_s),
            m.flag.clone(),
        ]);
        if with_escapes {
            row.push(opt(&m.saddle_escapes));
        }
        if with_lbfgs {
            row.push(opt(&m.lbfgs_evaluations));
        }
        // A packing without escapes or cuts had none: 0, not unknown.
        if with_plateaus {
            row.push(m.plateau_escapes.unwrap_or(0).to_string());
        }
        if with_dt_cuts {
            row.push(m.dt_cuts.unwrap_or(0).to_string());
        }
        if with_spectrum {
            row.extend(spectrum_cells(m.spectrum.as_ref()));
        }
        if with_gaps {
            row.push(
                m.gaps
                    .as_ref()
                    .map(|g| g.total().to_string())
                    .unwrap_or_default(),
            );
        }
        if with_moduli {
            row.extend(moduli_cells(m.moduli.as_ref()));
        }
        if with_jam_point {
            row.extend(match &m.jam_point {
                Some(j) => [
                    format!("{}", j.phi),
                    opt(&j.z),
                    opt(&j.n_rattlers),
                    opt(&j.iso_margin),
                ],
                None => Default::default(),
            });
        }
        if with_cell_contacts {
            row.extend(match cell_contacts(f) {
                Some(c) => [
                    c.n_contacts.to_string(),
                    c.n_rattlers.to_string(),
                    format!("{}", c.z),
                    c.iso_margin.to_string(),
                ],
                None => Default::default(),
            });
        }
        if with_rejams {
            row.push(rejams(f).to_string());
        }
        rows.push(row);
    }
    table(&head, rows)
}

/// The columns of a shear-stabilised cell's contacts (docs/reference/output-files.md).
const CELL_CONTACTS_COLUMNS: [&str; 4] = [
    "stab_contacts",
    "stab_rattlers",
    "stab_z",
    "stab_iso_margin",
];

/// The columns of `AboveJam`'s jamming point (docs/reference/output-files.md).
const JAM_POINT_COLUMNS: [&str; 4] = ["jam_phi", "jam_z", "jam_rattlers", "jam_iso_margin"];

const SPECTRUM_COLUMNS: [&str; 12] = [
    "omega_1",
    "omega_star",
    "zero_modes",
    "zero_translations",
    "zero_rattlers",
    "zero_extra",
    "lambda_min",
    "lambda_max",
    "softest_omega",
    "softest_participation",
    "softest_rotational_share",
    "spectrum_s",
];

/// The columns of `Moduli` (docs/reference/output-files.md).
const MODULI_COLUMNS: [&str; 11] = [
    "G",
    "G_min",
    "B",
    "G_affine",
    "B_affine",
    "moduli_pressure",
    "moduli_zero_extra",
    "moduli_negative_modes",
    "moduli_floppy_share",
    "moduli_soft_share",
    "moduli_s",
];

fn moduli_cells(m: Option<&ModuliMeasures>) -> Vec<String> {
    let Some(m) = m else {
        return vec![String::new(); MODULI_COLUMNS.len()];
    };
    let v = &m.moduli;
    vec![
        format!("{:e}", v.shear),
        format!("{:e}", v.shear_min()),
        format!("{:e}", v.bulk),
        format!("{:e}", v.shear_affine),
        format!("{:e}", v.bulk_affine),
        format!("{:e}", v.pressure),
        v.zero_modes.extra.to_string(),
        v.negative_modes.to_string(),
        format!("{:e}", v.floppy_share),
        v.soft_share.map(|x| format!("{x:e}")).unwrap_or_default(),
        format!("{:.3}", m.wall_s),
    ]
}

fn spectrum_cells(s: Option<&SpectrumMeasures>) -> Vec<String> {
    let Some(s) = s else {
        return vec![String::new(); SPECTRUM_COLUMNS.len()];
    };
    let e = |x: Option<f64>| x.map(|v| format!("{v:e}")).unwrap_or_default();
    vec![
        e(s.omega_1()),
        e(s.omega_star()),
        s.zero_modes.total.to_string(),
        s.zero_modes.translations.to_string(),
        s.zero_modes.rattlers.to_string(),
        s.zero_modes.extra.to_string(),
        format!("{:e}", s.lambda_min),
        format!("{:e}", s.lambda_max),
        e(s.softest.map(|m| m.omega)),
        e(s.softest.map(|m| m.participation)),
        e(s.softest.map(|m| m.rotational_share)),
        format!("{:.3}", s.wall_s),
    ]
}

impl SpectrumMeasures {
    /// `ω₁` of this packing's `D(ω)` (derived from the histogram, so that
    /// it always follows the current definition).
    pub fn omega_1(&self) -> Option<f64> {
        self.histogram.omega_1()
    }

    /// `ω_*` of this packing's `D(ω)`.
    pub fn omega_star(&self) -> Option<f64> {
        self.histogram.omega_star(&self.dos)
    }
}

/// `dos.csv`: `D(ω)` of each point, summed over its packings, one row per
/// (point, bin).
pub fn dos_csv(groups: &[(String, Vec<&PackingFile>)]) -> String {
    let head = ["point", "omega", "omega_lo", "omega_hi", "count", "dos"].map(String::from);
    let mut rows = Vec::new();
    for (label, files) in groups {
        let Some(h) = pooled_histogram(files) else {
            continue;
        };
        for (((c, w), d), &n) in h
            .centres()
            .iter()
            .zip(h.edges.windows(2))
            .zip(h.density())
            .zip(&h.counts)
        {
            rows.push(vec![
                label.clone(),
                format!("{c:e}"),
                format!("{:e}", w[0]),
                format!("{:e}", w[1]),
                n.to_string(),
                format!("{d:e}"),
            ]);
        }
    }
    table(&head, rows)
}

/// `ω₁` and `ω_*` of the pooled `D(ω)` of `files`.
fn pooled_frequencies(files: &[&PackingFile]) -> (Option<f64>, Option<f64>) {
    let params = files.iter().find_map(|f| f.measures.spectrum.as_ref());
    match (pooled_histogram(files), params) {
        (Some(h), Some(s)) => (h.omega_1(), h.omega_star(&s.dos)),
        _ => (None, None),
    }
}

/// The histograms of `files` added up (`None` when none has a spectrum or
/// their bins differ).
pub fn pooled_histogram(files: &[&PackingFile]) -> Option<DosHistogram> {
    let mut it = files.iter().filter_map(|f| f.measures.spectrum.as_ref());
    let mut h = it.next()?.histogram.clone();
    for s in it {
        h.merge(&s.histogram).ok()?;
    }
    Some(h)
}

/// `gaps.csv`: `Z(h)` of each point from the summed counts of its
/// packings, with `g(h)` between a sample point and the one before.
pub fn gaps_csv(groups: &[(String, Vec<&PackingFile>)]) -> String {
    let head = ["point", "h", "count_below", "z", "g"].map(String::from);
    let mut rows = Vec::new();
    for (label, files) in groups {
        let mut it = files.iter().filter_map(|f| f.measures.gaps.as_ref());
        let Some(first) = it.next() else {
            continue;
        };
        let mut c = first.clone();
        if it.any(|g| c.merge(g).is_err()) {
            continue;
        }
        let (_, g) = c.density();
        for (k, (h, z)) in c.h.iter().zip(c.cumulative()).enumerate() {
            let g = if k == 0 {
                String::new()
            } else {
                num(g[k - 1], true)
            };
            rows.push(vec![
                label.clone(),
                format!("{h:e}"),
                c.below[k].to_string(),
                num(z, true),
                g,
            ]);
        }
    }
    table(&head, rows)
}

/// One row of `summary.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSummary {
    /// Label of the point.
    pub label: String,
    /// Packings in it.
    pub samples: usize,
    /// φ mean and s.e.m.
    pub phi: (f64, f64),
    /// z_J mean and s.e.m.
    pub z_j: (f64, f64),
    /// [`PackingFile::z_iso`] mean and s.e.m.
    pub z_iso: (f64, f64),
    /// [`PackingFile::z_corr`] mean and s.e.m.
    pub z_corr: (f64, f64),
    /// Rattler fraction mean and s.e.m.
    pub rattler_fraction: (f64, f64),
    /// [`PackingFile::rot_rattler_fraction`] mean and s.e.m.
    pub rot_rattler_fraction: (f64, f64),
    /// Smallest isostaticity margin.
    pub iso_margin_min: Option<i64>,
    /// Pressure mean and s.e.m.
    pub pressure: (f64, f64),
    /// Mean FIRE steps.
    pub fire_steps: f64,
    /// Mean wall seconds.
    pub wall_s: f64,
    /// Packings flagged.
    pub flagged: usize,
    /// `ω₁` mean and s.e.m. over packings.
    pub omega_1: (f64, f64),
    /// `ω_*` mean and s.e.m. over packings (those where it is defined).
    pub omega_star: (f64, f64),
    /// `ω₁` and `ω_*` of the pooled `D(ω)` of the point.
    pub pooled: (Option<f64>, Option<f64>),
    /// Extra zero modes (quartic, for near-disks), mean and s.e.m.
    pub zero_extra: (f64, f64),
}

/// Summaries of packings grouped by point (files must be grouped already,
/// in order; `labels[k]` is the label of group `k`).
pub fn summarize_points(groups: &[(String, Vec<&PackingFile>)]) -> Vec<PointSummary> {
    groups
        .iter()
        .map(|(label, files)| {
            let col = |f: &dyn Fn(&PackingFile) -> Option<f64>| -> Vec<f64> {
                files.iter().filter_map(|p| f(p)).collect()
            };
            PointSummary {
                label: label.clone(),
                samples: files.len(),
                phi: mean_sem(&col(&|p| Some(p.measures.phi))),
                z_j: mean_sem(&col(&|p| p.measures.z_j)),
                z_iso: mean_sem(&col(&|p| p.z_iso())),
                z_corr: mean_sem(&col(&|p| p.z_corr())),
                rattler_fraction: mean_sem(&col(&|p| {
                    p.measures.n_rattlers.map(|r| r as f64 / p.particles as f64)
                })),
                rot_rattler_fraction: mean_sem(&col(&|p| p.rot_rattler_fraction())),
                iso_margin_min: files.iter().filter_map(|p| p.measures.iso_margin).min(),
                pressure: mean_sem(&col(&|p| p.measures.pressure)),
                fire_steps: mean_sem(&col(&|p| Some(p.measures.fire_steps as f64))).0,
                wall_s: mean_sem(&col(&|p| Some(p.measures.wall_s))).0,
                flagged: files.iter().filter(|p| !p.measures.flag.is_empty()).count(),
                omega_1: mean_sem(&col(&|p| p.measures.spectrum.as_ref()?.omega_1())),
                omega_star: mean_sem(&col(&|p| p.measures.spectrum.as_ref()?.omega_star())),
                pooled: pooled_frequencies(files),
                zero_extra: mean_sem(&col(&|p| {
                    Some(p.measures.spectrum.as_ref()?.zero_modes.extra as f64)
                })),
            }
        })
        .collect()
}

/// `summary.csv`: the point's identity (from its first packing) and the summary.
pub fn summary_csv(groups: &[(String, Vec<&PackingFile>)]) -> String {
    let firsts: Vec<PackingFile> = groups
        .iter()
        .filter_map(|(_, g)| g.first().map(|f| (*f).clone()))
        .collect();
    let names = param_names(&firsts);
    let mut head: Vec<String> = ["point", "family", "dim", "particles"]
        .map(String::from)
        .to_vec();
    head.extend(names.iter().cloned());
    head.extend(
        [
            "samples",
            "phi_j_mean",
            "phi_j_sem",
            "z_j_mean",
            "z_j_sem",
            "z_iso_mean",
            "z_iso_sem",
            "z_corr_mean",
            "z_corr_sem",
            "rattler_fraction_mean",
            "rattler_fraction_sem",
            "rot_rattler_fraction_mean",
            "rot_rattler_fraction_sem",
            "iso_margin_min",
            "pressure_mean",
            "pressure_sem",
            "fire_steps_mean",
            "wall_s_mean",
            "flagged",
        ]
        .map(String::from),
    );
    let with_spectrum = firsts.iter().any(|f| f.measures.spectrum.is_some());
    if with_spectrum {
        head.extend(
            [
                "omega_1_mean",
                "omega_1_sem",
                "omega_star_mean",
                "omega_star_sem",
                "omega_1_pooled",
                "omega_star_pooled",
                "zero_extra_mean",
                "zero_extra_sem",
            ]
            .map(String::from),
        );
    }
    let mut rows = Vec::new();
    for (s, first) in summarize_points(groups).iter().zip(&firsts) {
        let mut row = vec![
            s.label.clone(),
            first.family.clone(),
            first.dim.to_string(),
            first.particles.to_string(),
        ];
        row.extend(param_cells(first, &names));
        row.extend([
            s.samples.to_string(),
            num(s.phi.0, false),
            num(s.phi.1, true),
            num(s.z_j.0, false),
            num(s.z_j.1, true),
            num(s.z_iso.0, false),
            num(s.z_iso.1, true),
            num(s.z_corr.0, false),
            num(s.z_corr.1, true),
            num(s.rattler_fraction.0, false),
            num(s.rattler_fraction.1, true),
            num(s.rot_rattler_fraction.0, false),
            num(s.rot_rattler_fraction.1, true),
            opt(&s.iso_margin_min),
            num(s.pressure.0, true),
            num(s.pressure.1, true),
            format!("{:.0}", s.fire_steps),
            format!("{:.3}", s.wall_s),
            s.flagged.to_string(),
        ]);
        if with_spectrum {
            let e = |x: Option<f64>| x.map(|v| format!("{v:e}")).unwrap_or_default();
            row.extend([
                num(s.omega_1.0, true),
                num(s.omega_1.1, true),
                num(s.omega_star.0, true),
                num(s.omega_star.1, true),
                e(s.pooled.0),
                e(s.pooled.1),
                num(s.zero_extra.0, false),
                num(s.zero_extra.1, true),
            ]);
        }
        rows.push(row);
    }
    table(&head, rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_standard_error() {
        let (m, s) = mean_sem(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        // sample variance 5/3, sem = sqrt(5/12)
        assert!((s - (5.0f64 / 12.0).sqrt()).abs() < 1e-15);
        assert_eq!(mean_sem(&[7.0]), (7.0, 0.0));
    }

    /// Scanned settings are read from a packing's `settings`: through the
    /// tagged protocol, floats as in the ids, integers and texts plain; a
    /// path the packing does not record is an empty cell.
    #[test]
    fn setting_cells_follow_the_path_through_the_tagged_protocol() {
        let settings = serde_json::json!({
            "protocol": {"Jam": {"energy_low": 1e-14, "search": "Extrapolated"}},
            "minimizer": {"force_tol": 1e-22, "max_steps": 1000000, "dt_max": null,
                          "masses": {"Blocks": {"jammed_only": true}}},
        });
        for (path, cell) in [
            ("protocol.energy_low", "1e-14"),
            ("protocol.search", "Extrapolated"),
            ("minimizer.force_tol", "1e-22"),
            ("minimizer.max_steps", "1000000"),
            ("minimizer.dt_max", ""),
            ("minimizer.masses", r#"{"Blocks":{"jammed_only":true}}"#),
            ("minimizer.absent", ""),
            ("protocol.absent", ""),
        ] {
            assert_eq!(setting_cell(&settings, path), cell, "{path}");
        }
    }

    /// A 2D dimer packing of 10 bodies, 2 rattlers, written before the
    /// rotational rattlers were recorded: it loads, with no `z_corr`. With
    /// them (3 rotational rattlers, 3 free rotations, margin 1): `z_corr =
    /// z_J + 2·3/8`, which is also `2f + 2 (margin − d) / N_nr` and
    /// `z_J − z_iso + 2f`; the new fields are written, and left out when
    /// `None`.
    #[test]
    fn z_corr_counts_free_rotations_and_old_files_have_none() {
        // N_c = Σ r_b − d + margin = (8·3 − 3) − 2 + 1 = 20, z_J = 40/8.
        let mut file: PackingFile = serde_json::from_value(serde_json::json!({
            "id": "old", "experiment": "e", "family": "nmer", "params": {},
            "dim": 2, "particles": 10, "seed": 1, "protocol": "jam",
            "settings": {}, "phi": 0.8, "energy_per_particle": 0.0,
            "measures": {
                "phi": 0.8, "energy_per_particle": 0.0, "n_contacts": 20,
                "n_rattlers": 2, "z_j": 5.0, "iso_margin": 1, "pressure": 1e-3,
                "fire_steps": 0, "minimizations": 0, "wall_s": 0.0, "flag": ""
            },
            "box": [1.0, 1.0], "positions": [], "radii": [],
            "orientations": [], "rattler": []
        }))
        .unwrap();
        assert_eq!(file.measures.n_rot_rattlers, None);
        assert_eq!(file.z_corr(), None);
        assert_eq!(file.rot_rattler_fraction(), None);
        assert!(!results_csv(std::slice::from_ref(&file), &[]).contains("NaN"));
        file.measures.n_rot_rattlers = Some(3);
        file.measures.free_rotations = Some(3);
        let z_corr = file.z_corr().unwrap();
        assert_eq!(z_corr, 5.0 + 0.75);
        assert_eq!(z_corr, 6.0 + 2.0 * (1.0 - 2.0) / 8.0);
        assert_eq!(z_corr, 5.0 - file.z_iso().unwrap() + 6.0);
        assert_eq!(file.rot_rattler_fraction(), Some(3.0 / 8.0));
        let json = serde_json::to_string(&file.measures).unwrap();
        assert!(json.contains("\"n_rot_rattlers\":3"), "{json}");
        file.measures.free_rotations = None;
        let json = serde_json::to_string(&file.measures).unwrap();
        assert!(!json.contains("free_rotations"), "{json}");
        // results.csv: n_rot_rattlers after n_rattlers, z_corr after z_j.
        file.measures.free_rotations = Some(3);
        let csv = results_csv(&[file], &[]);
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let row: Vec<&str> = lines.next().unwrap().split(',').collect();
        let cell = |c: &str| row[head.iter().position(|h| *h == c).unwrap()];
        assert_eq!(cell("n_rot_rattlers"), "3");
        assert_eq!(cell("z_corr"), "5.75");
    }

    /// The minimiser's plateau escapes and `Δt_max` cuts: columns only
    /// when some packing of the table made any, 0 for the others; files
    /// that made none (or were written before they were recorded) neither
    /// carry the fields nor add the columns.
    #[test]
    fn escapes_and_dt_cuts_appear_only_when_some_packing_made_them() {
        let file = |id: &str| -> PackingFile {
            serde_json::from_value(serde_json::json!({
                "id": id, "experiment": "e", "family": "fourier", "params": {},
                "dim": 2, "particles": 4, "seed": 1, "protocol": "jam",
                "settings": {}, "phi": 0.8, "energy_per_particle": 0.0,
                "measures": {
                    "phi": 0.8, "energy_per_particle": 0.0,
                    "fire_steps": 100, "minimizations": 3, "wall_s": 0.0, "flag": ""
                },
                "box": [1.0, 1.0], "positions": [], "radii": [],
                "orientations": [], "rattler": []
            }))
            .unwrap()
        };
        let (plain, mut cut) = (file("plain"), file("cut"));
        assert_eq!(
            (plain.measures.plateau_escapes, plain.measures.dt_cuts),
            (None, None)
        );
        let head = |csv: &str| csv.lines().next().unwrap().to_string();
        let without = results_csv(&[plain.clone(), cut.clone()], &[]);
        assert!(!head(&without).contains("dt_cuts") && !head(&without).contains("plateau"));
        assert!(
            !serde_json::to_string(&plain.measures)
                .unwrap()
                .contains("dt_cuts")
        );
        cut.measures.dt_cuts = Some(2);
        let csv = results_csv(&[plain, cut.clone()], &[]);
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert!(!head.contains(&"plateau_escapes"), "{head:?}");
        let at = head.iter().position(|h| *h == "dt_cuts").unwrap();
        let cells: Vec<&str> = lines.map(|l| l.split(',').nth(at).unwrap()).collect();
        assert_eq!(cells, ["0", "2"]);
        let back: crate::record::Measures =
            serde_json::from_str(&serde_json::to_string(&cut.measures).unwrap()).unwrap();
        assert_eq!(back.dt_cuts, Some(2));
    }

    /// A cell with a comma, quotes or a line end comes back whole through
    /// a CSV reader; a plain cell is not quoted.
    #[test]
    fn cells_are_quoted_where_needed_and_read_back() {
        let cells = ["a,b", "say \"x\"", "plain", "a\"b,", "two\nlines", ""];
        let head: Vec<String> = (0..cells.len()).map(|k| format!("c{k}")).collect();
        let text = table(&head, vec![cells.map(String::from).to_vec()]);
        assert!(text.ends_with('\n') && !text.contains('\r'), "{text:?}");
        assert!(text.contains(",plain,"), "{text}");
        let mut reader = csv::Reader::from_reader(text.as_bytes());
        let row = reader.records().next().unwrap().unwrap();
        assert_eq!(row.iter().collect::<Vec<_>>(), cells);
    }
}
