//! One packing on disk (`packings/<id>.json`): what was made, with which
//! settings, what was measured, and (unless left out) the configuration.
//! Written to a temporary name and renamed into place, so a killed run
//! never leaves a half-written file; the packing files are also the
//! checkpoint from which a rerun resumes. Format: `docs/reference/output-files.md`.

use crate::error::FormatError;
use jamkit_core::records::{DosHistogram, DosParams, GapCounts, Moduli, ModuliParams, ZeroModes};
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
    /// L-BFGS energy-and-gradient evaluations over the whole protocol,
    /// when the minimiser ran L-BFGS (`minimizer.lbfgs`; absent otherwise,
    /// so files without it are unchanged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lbfgs_evaluations: Option<u64>,
    /// Minimisations (density changes + 1).
    pub minimizations: u64,
    /// Moves of the minimiser's plateau escape over the whole protocol,
    /// when it made any (absent otherwise, so files without them are
    /// unchanged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plateau_escapes: Option<u64>,
    /// Times the minimiser's `stable_dt` lowered FIRE's `Δt_max` over the
    /// whole protocol, when it did (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_cuts: Option<u64>,
    /// Wall-clock seconds for the protocol and the observables.
    pub wall_s: f64,
    /// Empty, or why this packing deserves a second look.
    pub flag: String,
    /// Saddle escapes made after the jamming bisection (`None`: the escape
    /// was off), see `jamkit_engine::saddle`.
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
    /// The elastic moduli, when asked for (absent otherwise, so files
    /// without them are unchanged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moduli: Option<ModuliMeasures>,
    /// The packing's own jamming point, for protocols that go past it
    /// (`AboveJam`: measured before the compression by δφ; absent
    /// otherwise, so other files are unchanged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jam_point: Option<JamPoint>,
}

impl Measures {
    /// A configuration's packing fraction and `V/N` with nothing else
    /// measured (no protocol run, no observable).
    pub fn bare(phi: f64, energy_per_particle: f64) -> Self {
        Self {
            phi,
            energy_per_particle,
            n_contacts: None,
            n_rattlers: None,
            z_j: None,
            iso_margin: None,
            n_rot_rattlers: None,
            free_rotations: None,
            pressure: None,
            fire_steps: 0,
            lbfgs_evaluations: None,
            minimizations: 0,
            plateau_escapes: None,
            dt_cuts: None,
            wall_s: 0.0,
            flag: String::new(),
            saddle_escapes: None,
            spectrum: None,
            gaps: None,
            moduli: None,
            jam_point: None,
        }
    }
}

/// The jamming point a packing above jamming was compressed from: φ_J and
/// the contact numbers there, with the same rattler rule as the packing's
/// own (`None` where `Contacts` was not measured).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JamPoint {
    /// φ_J.
    pub phi: f64,
    /// `z_J = 2 N_c / N_nr` at φ_J.
    pub z: Option<f64>,
    /// Rattlers at φ_J.
    pub n_rattlers: Option<usize>,
    /// `N_c − (f N_nr − d)` at φ_J.
    pub iso_margin: Option<i64>,
    /// The jamming points this packing left, in order: each time it
    /// unjammed on its way up to φ_J + δφ it was jammed again from there
    /// (`protocol.rejams`), and `phi` above is the last. Empty, and not
    /// written out, for a packing that went up at the first try (so files
    /// written before it existed are unchanged).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub left: Vec<f64>,
}

/// The elastic moduli of one packing, as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModuliMeasures {
    /// `G`, `B` and what goes with them (`jamkit_observe::moduli`).
    pub moduli: Moduli,
    /// The options used.
    pub params: ModuliParams,
    /// Seconds for assembly, diagonalisation and the strain derivatives.
    pub wall_s: f64,
    /// With `protocol.shear_stabilised`: how the cell was stabilised and
    /// the moduli of the fixed box before (`moduli` above are the
    /// stabilised cell's). Absent otherwise, so other files are unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stabilisation: Option<Stabilisation>,
}

/// A shear stabilisation (`jamkit_engine::stabilise`), as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stabilisation {
    /// The cell's deformation `F` from the fixed box, row by row: the cell
    /// is `F · diag(box_edges)`. `det F = 1` at fixed volume; at the fixed
    /// pressure the runner stabilises at, `det F` is the cell's volume over
    /// the box's.
    pub deformation: Vec<Vec<f64>>,
    /// `max_k |σ : E_k| / p` over the deviatoric strains, at the end …
    pub residual: f64,
    /// … and in the fixed box.
    pub residual_before: f64,
    /// `V/N` in the fixed box (relaxed to the stabiliser's tolerance) …
    pub energy_before: f64,
    /// … and in the stabilised cell.
    pub energy_after: f64,
    /// The pressure in the fixed box …
    pub pressure_before: f64,
    /// … and in the stabilised cell (same volume).
    pub pressure_after: f64,
    /// Strain steps taken.
    pub iterations: u32,
    /// The smallest eigenvalue of the deviatoric stiffness at the end.
    pub stiffness_min: f64,
    /// The linear-response moduli of the fixed box (as without
    /// stabilisation).
    pub fixed_box: Moduli,
    /// Seconds for the stabilisation.
    pub wall_s: f64,
    /// With the `Moduli` observable's `solver: Sparse`: the strain steps
    /// whose stiffness fell back to the dense eigendecomposition. Absent
    /// when none did (and in files written before it existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dense_fallbacks: Option<u32>,
    /// The same steps, each with why its stiffness could not take the
    /// sparse path (step `0`: the relaxed fixed box; the reasons of
    /// `Moduli::dense_fallback`, e.g. the softest mode within twice the
    /// zero-mode threshold). Absent when none fell back (and in files
    /// written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dense_fallback_reasons: Option<Vec<(u32, String)>>,
    /// The contacts of the stabilised cell, with the same rattler rule as
    /// `Contacts` (by count). Absent in files made before they were
    /// recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contacts: Option<CellContacts>,
}

/// The contact numbers of a shear-stabilised (deformed) cell, as
/// `Contacts` counts them in the fixed box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellContacts {
    /// Contacts among non-rattlers, `N_c`.
    pub n_contacts: usize,
    /// Rattlers.
    pub n_rattlers: usize,
    /// `z = 2 N_c / N_nr`.
    pub z: f64,
    /// `N_c − (f N_nr − d)`.
    pub iso_margin: i64,
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
    /// The softest mode above `dos.omega_zero` (with `modes: true`, when
    /// there is one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub softest: Option<SoftestMode>,
}

/// The softest non-zero mode of a spectrum: the lowest eigenvalue with
/// `ω > omega_zero`, and the shape of its eigenvector.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SoftestMode {
    /// Its frequency `ω = √λ`.
    pub omega: f64,
    /// Its participation ratio, in `[1/N_b, 1]`.
    pub participation: f64,
    /// Its share of weight on rotational coordinates.
    pub rotational_share: f64,
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
    /// The version of jamkit that made the packing
    /// ([`crate::provenance::VERSION`]); `None` in files made before it was
    /// recorded. A file measured again keeps the version that made it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jamkit_version: Option<String>,
    /// The git commit of that jamkit, when it was built from a checkout.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub git_commit: Option<String>,
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

/// Write `contents` to `path` atomically (temporary file beside it, then
/// rename). A failure names `path`, the file the caller asked for, and
/// leaves no temporary file behind (a full disk leaves the directory as it
/// was).
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), FormatError> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, contents)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            FormatError::io(path, e)
        })
}

impl PackingFile {
    /// Save as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<(), FormatError> {
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
    pub fn load_checked(path: &Path) -> Result<Self, FormatError> {
        let text = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
        let file: Self = serde_json::from_slice(&text).map_err(|e| FormatError::Parse {
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
    pub fn check_as(&self, whose: impl std::fmt::Display) -> Result<(), FormatError> {
        self.check()
            .map_err(|(field, value, allowed)| FormatError::Invalid {
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
