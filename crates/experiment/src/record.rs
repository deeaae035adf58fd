//! What a run writes: one JSON file per packing, `results.csv` with a row per
//! packing, `summary.csv` with mean and standard error per parameter point.
//! Every file is written to a temporary name and renamed into place, so a
//! killed run never leaves a half-written file; the packing files are also
//! the checkpoint from which a rerun resumes. Formats: `docs/formats.md`.

use crate::error::ExperimentError;
use jamkit_observe::gaps::GapCounts;
use jamkit_observe::spectrum::{DosHistogram, DosParams, ZeroModes};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The values measured on one packing (one row of `results.csv`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measures {
    /// Packing fraction at the end of the protocol (φ_J for `Jam`).
    pub phi: f64,
    /// `V/N` at the end.
    pub energy_per_particle: f64,
    /// Contacts among non-rattlers, `N_c`.
    pub n_contacts: Option<usize>,
    /// Number of rattlers.
    pub n_rattlers: Option<usize>,
    /// `z_J = 2 N_c / N_nr`.
    pub z_j: Option<f64>,
    /// `N_c − (f N_nr − d)`.
    pub iso_margin: Option<i64>,
    /// Virial pressure.
    pub pressure: Option<f64>,
    /// FIRE steps over the whole protocol.
    pub fire_steps: u64,
    /// Minimisations (density changes + 1).
    pub minimizations: u64,
    /// Wall-clock seconds for the protocol and the observables.
    pub wall_s: f64,
    /// Empty, or why this packing deserves a second look.
    pub flag: String,
    /// Saddle escapes made after the jamming bisection (`None`: the escape
    /// was off), see `jamkit_observe::saddle`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub saddle_escapes: Option<u32>,
    /// The Hessian's spectrum, when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<SpectrumMeasures>,
    /// Gap counts below each sample point, when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gaps: Option<GapCounts>,
    /// Rotational rattlers: non-rattlers whose contacts constrain fewer
    /// than `f` of their coordinates (a body made of spheres held on one
    /// sphere), see `jamkit_observe::JammingSummary`. 0 when rattlers go by
    /// count; `None` in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_rot_rattlers: Option<usize>,
    /// Their free coordinates, `Σ_b (f − r_b)` over the non-rattlers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_rotations: Option<usize>,
}

/// The spectrum of one packing, as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpectrumMeasures {
    /// Rows of the Hessian (`N_dof`).
    pub coordinates: usize,
    /// Zero modes by origin.
    pub zero_modes: ZeroModes,
    /// Smallest eigenvalue.
    pub lambda_min: f64,
    /// Largest eigenvalue.
    pub lambda_max: f64,
    /// The binned frequencies (summed over samples for `dos.csv`).
    pub histogram: DosHistogram,
    /// The bins and thresholds used.
    pub dos: DosParams,
    /// Seconds for assembly and diagonalisation.
    pub wall_s: f64,
}

/// One packing on disk (`packings/<id>.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PackingFile {
    /// Identifier (also the file name).
    pub id: String,
    /// The experiment's name.
    pub experiment: String,
    /// Family name.
    pub family: String,
    /// Family parameters at this grid point.
    pub params: serde_json::Value,
    /// Spatial dimension.
    pub dim: usize,
    /// Number of bodies.
    pub particles: usize,
    /// Seed of the random start.
    pub seed: u64,
    /// Protocol name (`jam`, `phi`, `pressure`).
    pub protocol: String,
    /// Every setting that shapes this packing (family, parameters, sizes,
    /// protocol, minimiser, potential, rattlers, engine): a rerun reuses the
    /// file only if these are unchanged.
    pub settings: serde_json::Value,
    /// The observables measured on it; a rerun that asks for others
    /// measures them again on the saved configuration.
    #[serde(default)]
    pub observables: serde_json::Value,
    /// Packing fraction.
    pub phi: f64,
    /// `V/N`.
    pub energy_per_particle: f64,
    /// Everything measured.
    pub measures: Measures,
    /// Box edge lengths.
    #[serde(rename = "box")]
    pub box_edges: Vec<f64>,
    /// Centres (N × D), empty when `output.packings` is false.
    pub positions: Vec<Vec<f64>>,
    /// Size `R⁰` of each body.
    pub radii: Vec<f64>,
    /// Orientation coordinates (N × k); empty for spheres.
    pub orientations: Vec<Vec<f64>>,
    /// Rattler flags (empty when contacts were not measured).
    pub rattler: Vec<bool>,
    /// For bodies made of spheres (`Shape::sphere_decomposition`), every
    /// sphere as `[x, y(, z), radius, body]`: world-frame centre (the
    /// body's wrapped centre plus the sphere's offset, so it may lie just
    /// outside the box), radius and body index. Absent for other families
    /// and when `output.packings` is false.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spheres: Vec<Vec<f64>>,
}

/// `file` without its configuration (centres, sizes, orientations,
/// rattler flags, spheres): what the tables need, at a fraction of the
/// memory.
pub fn without_configuration(file: &PackingFile) -> PackingFile {
    PackingFile {
        positions: Vec::new(),
        radii: Vec::new(),
        orientations: Vec::new(),
        rattler: Vec::new(),
        spheres: Vec::new(),
        ..file.clone()
    }
}

/// Write `contents` to `path` atomically (temporary file, then rename).
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), ExperimentError> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, contents).map_err(|e| ExperimentError::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| ExperimentError::io(path, e))
}

impl PackingFile {
    /// Save as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<(), ExperimentError> {
        let text = serde_json::to_vec_pretty(self).expect("a packing serialises");
        write_atomic(path, &text)
    }

    /// Load; `None` if the file is missing or unreadable (then it is redone).
    pub fn load(path: &Path) -> Option<Self> {
        let text = std::fs::read(path).ok()?;
        serde_json::from_slice(&text).ok()
    }

    /// Load, with an error that says what is wrong with the file: not a
    /// packing record, or one whose configuration no computation can use
    /// ([`PackingFile::check`]).
    pub fn load_checked(path: &Path) -> Result<Self, ExperimentError> {
        let text = std::fs::read(path).map_err(|e| ExperimentError::io(path, e))?;
        let file: Self = serde_json::from_slice(&text).map_err(|e| ExperimentError::Parse {
            file: path.display().to_string(),
            message: format!("not a jamkit packing file: {e}"),
        })?;
        file.check_as(path.display())?;
        Ok(file)
    }

    /// The configuration is usable: `dim` from 2 to 4, `box` of `dim`
    /// positive finite edges, and (when the configuration is stored) one
    /// centre of `dim` finite coordinates, one positive finite size and
    /// (if any) one row of finite orientation coordinates per body. The
    /// first offence as `(field, value, what is allowed)`.
    pub fn check(&self) -> Result<(), (String, String, String)> {
        let bad = |field: String, value: String, allowed: &str| Err((field, value, allowed.into()));
        if !(2..=4).contains(&self.dim) {
            return bad("dim".into(), self.dim.to_string(), "must be 2, 3 or 4");
        }
        if self.box_edges.len() != self.dim {
            return bad(
                "box".into(),
                format!("{} edges", self.box_edges.len()),
                "must have one edge per dimension",
            );
        }
        for (a, &l) in self.box_edges.iter().enumerate() {
            if !(l.is_finite() && l > 0.0) {
                return bad(
                    format!("box[{a}]"),
                    l.to_string(),
                    "must be positive and finite",
                );
            }
        }
        if self.positions.is_empty() {
            return Ok(());
        }
        let n = self.particles;
        for (field, len) in [
            ("positions", self.positions.len()),
            ("radii", self.radii.len()),
        ] {
            if len != n {
                return bad(
                    field.into(),
                    format!("{len} entries"),
                    "must have one entry per body (particles)",
                );
            }
        }
        for (i, r) in self.positions.iter().enumerate() {
            if r.len() != self.dim || !r.iter().all(|x| x.is_finite()) {
                return bad(
                    format!("positions[{i}]"),
                    format!("{r:?}"),
                    "must be dim finite coordinates",
                );
            }
        }
        for (i, &r) in self.radii.iter().enumerate() {
            if !(r.is_finite() && r > 0.0) {
                return bad(
                    format!("radii[{i}]"),
                    r.to_string(),
                    "must be positive and finite",
                );
            }
        }
        if !self.orientations.is_empty() {
            if self.orientations.len() != n {
                return bad(
                    "orientations".into(),
                    format!("{} entries", self.orientations.len()),
                    "must be empty or have one entry per body",
                );
            }
            for (i, o) in self.orientations.iter().enumerate() {
                if !o.iter().all(|x| x.is_finite()) {
                    return bad(
                        format!("orientations[{i}]"),
                        format!("{o:?}"),
                        "must be finite",
                    );
                }
            }
        }
        Ok(())
    }

    /// [`PackingFile::check`] as an error whose field names `whose` (a
    /// path, or `packing <id>`).
    pub fn check_as(&self, whose: impl std::fmt::Display) -> Result<(), ExperimentError> {
        self.check()
            .map_err(|(field, value, allowed)| ExperimentError::Invalid {
                field: format!("{whose}: {field}"),
                value,
                allowed,
            })
    }

    /// Load only if it was made with exactly these settings.
    pub fn load_matching(path: &Path, settings: &serde_json::Value) -> Option<Self> {
        Self::load(path).filter(|f| &f.settings == settings)
    }

    /// The isostatic contact number of this packing's non-rattlers,
    /// `z_iso = 2 n_coord / N_nr`, with `n_coord` the coordinates the
    /// margin counts (`iso_margin = N_c − (n_coord − d)`, so
    /// `n_coord = N_c − iso_margin + d`): `2 f` when every non-rattler
    /// counts `f` coordinates, less when bodies made of spheres are held
    /// on one sphere only (the rank rule counts `d` coordinates for them).
    /// `z_J − z_iso = 2 (iso_margin − d) / N_nr`. `None` without contacts
    /// or when every body rattles.
    pub fn z_iso(&self) -> Option<f64> {
        let m = &self.measures;
        let kept = self.particles.checked_sub(m.n_rattlers?)?;
        if kept == 0 {
            return None;
        }
        let coordinates = m.n_contacts? as i64 - m.iso_margin? + self.dim as i64;
        Some(2.0 * coordinates as f64 / kept as f64)
    }

    /// The contact number corrected for rotational rattlers (Shiraishi,
    /// Mizuno & Ikeda 2019): each free rotational coordinate counts as a
    /// missing contact, `z_corr = z_J + 2 free_rotations / N_nr`. Since
    /// the margin counts `Σ_b r_b = f N_nr − free_rotations` coordinates,
    /// `z_corr = 2 f + 2 (iso_margin − d) / N_nr = z_J − z_iso + 2 f`: `2 f`
    /// up to `O(1/N_nr)` for a packing with a small margin. Equal to `z_J`
    /// when rattlers go by count. `None` without contacts, in files
    /// written before `free_rotations` was recorded, or when every body
    /// rattles.
    pub fn z_corr(&self) -> Option<f64> {
        let m = &self.measures;
        let kept = self.particles.checked_sub(m.n_rattlers?)?;
        if kept == 0 {
            return None;
        }
        Some(m.z_j? + 2.0 * m.free_rotations? as f64 / kept as f64)
    }

    /// The fraction of non-rattlers that are rotational rattlers
    /// (`None` as for [`Self::z_corr`]).
    pub fn rot_rattler_fraction(&self) -> Option<f64> {
        let m = &self.measures;
        let kept = self.particles.checked_sub(m.n_rattlers?)?;
        if kept == 0 {
            return None;
        }
        Some(m.n_rot_rattlers? as f64 / kept as f64)
    }
}

/// Quote a CSV field when needed.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
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
                Some(serde_json::Value::String(s)) => csv_field(s),
                Some(v) => csv_field(&v.to_string()),
            }
        })
        .collect()
}

/// `results.csv`: one row per packing.
pub fn results_csv(files: &[PackingFile]) -> String {
    let names = param_names(files);
    let mut head = vec!["id", "family", "dim", "particles", "seed"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    head.extend(names.iter().cloned());
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
    // Only when some packing escaped saddles, so that tables of runs
    // without the escape keep their columns.
    let with_escapes = files.iter().any(|f| f.measures.saddle_escapes.is_some());
    if with_escapes {
        head.push("saddle_escapes".into());
    }
    if with_spectrum {
        head.extend(SPECTRUM_COLUMNS.map(String::from));
    }
    if with_gaps {
        head.push("gaps".into());
    }
    let mut out = head.join(",") + "\n";
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
            csv_field(&m.flag),
        ]);
        if with_escapes {
            row.push(opt(&m.saddle_escapes));
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
        out += &(row.join(",") + "\n");
    }
    out
}

const SPECTRUM_COLUMNS: [&str; 9] = [
    "omega_1",
    "omega_star",
    "zero_modes",
    "zero_translations",
    "zero_rattlers",
    "zero_extra",
    "lambda_min",
    "lambda_max",
    "spectrum_s",
];

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
    let mut out = String::from("point,omega,omega_lo,omega_hi,count,dos\n");
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
            out += &format!(
                "{},{c:e},{:e},{:e},{n},{d:e}\n",
                csv_field(label),
                w[0],
                w[1]
            );
        }
    }
    out
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
    let mut out = String::from("point,h,count_below,z,g\n");
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
            out += &format!(
                "{},{h:e},{},{},{g}\n",
                csv_field(label),
                c.below[k],
                num(z, true)
            );
        }
    }
    out
}

/// Mean and standard error of the mean (0 for a single value): the one
/// definition in `jamkit_core::stats`.
pub use jamkit_core::stats::mean_sem;

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
    let mut out = head.join(",") + "\n";
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
        out += &(row.join(",") + "\n");
    }
    out
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
        assert!(!results_csv(std::slice::from_ref(&file)).contains("NaN"));
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
        let csv = results_csv(&[file]);
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let row: Vec<&str> = lines.next().unwrap().split(',').collect();
        let cell = |c: &str| row[head.iter().position(|h| *h == c).unwrap()];
        assert_eq!(cell("n_rot_rattlers"), "3");
        assert_eq!(cell("z_corr"), "5.75");
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(csv_field("plain"), "plain");
        assert_eq!(csv_field("a\"b,"), "\"a\"\"b,\"");
    }
}
