//! The experiment file.
//!
//! ```ron
//! (
//!     name: "quickstart",
//!     dim: 2,                           // or a list: [2, 3]
//!     family: "sphere",
//!     params: {},                       // the family's parameters; a list scans
//!     sizes: Binary(small: 0.5, large: 0.7),
//!     particles: 256,                   // or a list: [64, 128, 256]
//!     samples: 4,
//!     seed: 1,
//!     protocol: Jam(phi_start: 0.1, eps: 1e-3, energy_low: 1e-16, energy_high: 2e-16),
//!     minimizer: (variant: Fire, dt_max: 0.5, force_tol: 1e-25),
//!     rattlers: (min_contacts: None),   // None: the family's default (d + 1 for disks)
//!     observables: [Contacts, Pressure],
//!     output: (packings: true),
//! )
//! ```
//!
//! Every field but `name`, `family` and `particles` has a default; unknown
//! fields are rejected. `docs/reference/experiment-file.md` lists every field.

use crate::error::ExperimentError;
use jamkit_core::{Potential, SizeDistribution};
use jamkit_engine::{FireParams, JamParams, JamSearch, PressureParams};
use jamkit_observe::gaps::GapParams;
use jamkit_observe::hessian::HessianOptions;
use jamkit_observe::moduli::{ModuliParams, ModuliSolver, StabiliseParams};
use jamkit_observe::spectrum::DosParams;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One value or a list of values (a list scans).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, expecting = "a value or a list of values")]
pub enum OneOrMany<T> {
    /// A single value.
    One(T),
    /// Several values, each a grid point.
    Many(Vec<T>),
}

impl<T: Clone> OneOrMany<T> {
    /// The values as a list.
    pub fn values(&self) -> Vec<T> {
        match self {
            OneOrMany::One(v) => vec![v.clone()],
            OneOrMany::Many(v) => v.clone(),
        }
    }

    /// The one value of a single target (a grid point's; the first of a
    /// list, `None` for an empty one).
    pub fn first(&self) -> Option<T> {
        match self {
            OneOrMany::One(v) => Some(v.clone()),
            OneOrMany::Many(v) => v.first().cloned(),
        }
    }
}

/// A whole experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Name, used in output.
    pub name: String,
    /// Spatial dimension `D` (a list scans; the grid's outermost axis).
    #[serde(default = "default_dim")]
    pub dim: OneOrMany<usize>,
    /// Shape family (see `jamkit shapes`).
    pub family: String,
    /// The family's parameters; a list where a scalar is expected scans.
    #[serde(default)]
    pub params: BTreeMap<String, ron::Value>,
    /// Size distribution of the bodies.
    #[serde(default)]
    pub sizes: SizeDistribution,
    /// Number of bodies `N` (a list scans).
    pub particles: OneOrMany<usize>,
    /// Samples per parameter point.
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// Base seed; sample `k` uses `seed + k`.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// How the packing fraction is driven.
    #[serde(default)]
    pub protocol: Protocol,
    /// FIRE's parameters and stopping criteria.
    #[serde(default)]
    pub minimizer: FireParams,
    /// Scanned settings of the protocol and the minimiser, e.g. a ladder of
    /// `minimizer.force_tol`: each entry is one axis of the grid, a map from
    /// a `--set` path (`minimizer.…` or `protocol.…`) to its values; the
    /// lists of one axis have one length and move together (a jamming
    /// window's `energy_low` with its `energy_high`). See [`Experiment::scanned`].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub scan: Vec<BTreeMap<String, Vec<ron::Value>>>,
    /// Contact potential `v(h)`.
    #[serde(default)]
    pub potential: Potential,
    /// Rattler removal.
    #[serde(default)]
    pub rattlers: Rattlers,
    /// What to measure on each packing.
    #[serde(default = "default_observables")]
    pub observables: Vec<Observable>,
    /// Engine tuning that does not change results beyond round-off.
    #[serde(default)]
    pub engine: EngineParams,
    /// What to write.
    #[serde(default)]
    pub output: OutputParams,
    /// `true`: the paper's path, bit for bit (FIRE all the way with plain
    /// masses and no L-BFGS, `Σ (∂V/∂q)²`, the plain bisection and no
    /// saddle escape),
    /// whatever jamkit's defaults (`paper` module).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub paper_path: bool,
}

fn default_dim() -> OneOrMany<usize> {
    OneOrMany::One(2)
}
fn default_samples() -> usize {
    1
}
fn default_seed() -> u64 {
    1
}
fn default_observables() -> Vec<Observable> {
    vec![Observable::Contacts, Observable::Pressure]
}

/// How the packing fraction is driven.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Protocol {
    /// The paper's bisection to the jamming point.
    Jam {
        /// Packing fraction of the random start.
        #[serde(default = "default_phi_start")]
        phi_start: f64,
        /// Initial step of φ.
        #[serde(default = "default_eps")]
        eps: f64,
        /// Lower edge of the window for `V/N`.
        #[serde(default = "default_energy_low")]
        energy_low: f64,
        /// Upper edge of the window for `V/N`.
        #[serde(default = "default_energy_high")]
        energy_high: f64,
        /// Give up after this many changes of φ.
        #[serde(default = "default_max_density_steps")]
        max_density_steps: u64,
        /// After the search, check the true Hessian for a negative
        /// eigenvalue (one sparse factorisation) and, on a saddle, push the
        /// packing along the negative mode and re-jam
        /// (`jamkit_engine::saddle`). On by default; `paper_path: true`
        /// turns it off. A packing records none when off, so that packings
        /// made before it existed (and the paper path's) record what they
        /// did; on a packing that is no saddle it moves nothing.
        #[serde(default = "default_escape_saddles")]
        escape_saddles: bool,
        /// How the search moves: `Adaptive` (the default: a jammed state is
        /// decompressed by the step its pressure predicts, and the
        /// compression step grows again where the jamming point has moved
        /// up; docs/explanation/physics.md), `Extrapolated` (the predicted
        /// decompressions alone) or `Bisection` (the paper's halved steps,
        /// the paper's path bit for bit). Always written to `experiment.ron`; left out of a packing's
        /// settings when `Bisection` (`sample::settings`).
        #[serde(default)]
        search: JamSearch,
    },
    /// Compress in steps of `eps` to packing fraction `phi`.
    Phi {
        /// Packing fraction of the random start.
        #[serde(default = "default_phi_start")]
        phi_start: f64,
        /// Target packing fraction (a list scans: one grid point each).
        phi: OneOrMany<f64>,
        /// Step of φ.
        #[serde(default = "default_eps")]
        eps: f64,
    },
    /// Bisect φ to a target pressure.
    Pressure {
        /// Packing fraction of the random start.
        #[serde(default = "default_phi_start")]
        phi_start: f64,
        /// Target pressure (a list scans: one grid point each).
        pressure: OneOrMany<f64>,
        /// Relative tolerance on the pressure.
        #[serde(default = "default_pressure_tol")]
        tol: f64,
        /// Initial step of φ.
        #[serde(default = "default_eps")]
        eps: f64,
        /// Give up after this many changes of φ.
        #[serde(default = "default_max_density_steps")]
        max_density_steps: u64,
        /// After the protocol, shear-stabilise the packing (Dagois-Bohy et
        /// al. 2012): relax the cell's shape and volume (every strain) with
        /// the coordinates at the packing's own pressure, minimising the
        /// enthalpy, until the deviatoric stress is below 10⁻⁶ p
        /// (`jamkit_engine::stabilise`).
        /// The `Moduli` observable (required) then measures the stabilised
        /// cell; the saved configuration and the other observables stay
        /// those of the fixed box (the engine's box cannot be sheared).
        /// Off by default, and not written out when off, so that settings
        /// of earlier runs are unchanged.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        shear_stabilised: bool,
        /// How the shear stabilisation runs (with `shear_stabilised` only):
        /// `(tol, max_iterations, max_step, margin)`, each left out at its
        /// default (`jamkit_observe::moduli::StabiliseParams`). Not written
        /// out when every field has its default, so that settings of
        /// earlier runs are unchanged.
        #[serde(default, skip_serializing_if = "StabiliseParams::is_default")]
        stabilise: StabiliseParams,
    },
    /// Jam (as `Jam`), then compress the jammed packing by `delta_phi`
    /// in steps of at most `compress_eps`, relaxing after each: a packing
    /// at a chosen distance `φ − φ_J = delta_phi` above its own jamming
    /// point (for the moduli above jamming: docs/how-to/moduli.md).
    AboveJam {
        /// Packing fraction of the random start.
        #[serde(default = "default_phi_start")]
        phi_start: f64,
        /// Initial step of φ of the jamming search.
        #[serde(default = "default_eps")]
        eps: f64,
        /// Lower edge of the window for `V/N` at φ_J.
        #[serde(default = "default_energy_low")]
        energy_low: f64,
        /// Upper edge of the window for `V/N` at φ_J.
        #[serde(default = "default_energy_high")]
        energy_high: f64,
        /// Give up after this many changes of φ in the jamming search.
        #[serde(default = "default_max_density_steps")]
        max_density_steps: u64,
        /// The jamming search (as `Jam`'s).
        #[serde(default)]
        search: JamSearch,
        /// `δφ = φ − φ_J` (a list scans: one grid point each).
        delta_phi: OneOrMany<f64>,
        /// Largest step of φ on the way from φ_J to φ_J + δφ.
        #[serde(default = "default_eps")]
        compress_eps: f64,
        /// How often a packing that unjams on its way up (a rearrangement
        /// into a state that jams above φ_J + δφ) is jammed again from
        /// where it stopped and compressed by δφ from its new φ_J, before
        /// the sample fails ([`DEFAULT_REJAMS`] by default). `0`: it fails
        /// at once; a packing's recorded settings leave it out at 0, as
        /// in packings made before the field existed, so that those resume
        /// under `rejams: 0`.
        #[serde(default = "default_rejams")]
        rejams: u32,
        /// After the protocol, shear-stabilise the packing (Dagois-Bohy et
        /// al. 2012): relax the cell's shape and volume (every strain) with
        /// the coordinates at the packing's own pressure, minimising the
        /// enthalpy, until the deviatoric stress is below 10⁻⁶ p
        /// (`jamkit_engine::stabilise`).
        /// The `Moduli` observable (required) then measures the stabilised
        /// cell; the saved configuration and the other observables stay
        /// those of the fixed box (the engine's box cannot be sheared).
        /// Off by default, and not written out when off, so that settings
        /// of earlier runs are unchanged.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        shear_stabilised: bool,
        /// How the shear stabilisation runs (with `shear_stabilised` only):
        /// `(tol, max_iterations, max_step, margin)`, each left out at its
        /// default (`jamkit_observe::moduli::StabiliseParams`). Not written
        /// out when every field has its default, so that settings of
        /// earlier runs are unchanged.
        #[serde(default, skip_serializing_if = "StabiliseParams::is_default")]
        stabilise: StabiliseParams,
    },
}

/// `AboveJam`'s `rejams` when the file leaves it out: a packing that
/// unjams on its way up is jammed again up to twice (an unjamming is rare,
/// and two in a row rarer still: docs/reports/elasticity.md).
pub const DEFAULT_REJAMS: u32 = 2;

fn default_rejams() -> u32 {
    DEFAULT_REJAMS
}
fn default_phi_start() -> f64 {
    0.1
}
fn default_eps() -> f64 {
    JamParams::default().eps
}
fn default_energy_low() -> f64 {
    JamParams::default().energy_low
}
fn default_energy_high() -> f64 {
    JamParams::default().energy_high
}
fn default_max_density_steps() -> u64 {
    JamParams::default().max_density_steps
}
fn default_escape_saddles() -> bool {
    true
}
fn default_pressure_tol() -> f64 {
    PressureParams::default().tol
}

impl Default for Protocol {
    fn default() -> Self {
        Protocol::Jam {
            phi_start: default_phi_start(),
            eps: default_eps(),
            energy_low: default_energy_low(),
            energy_high: default_energy_high(),
            max_density_steps: default_max_density_steps(),
            escape_saddles: default_escape_saddles(),
            search: JamSearch::default(),
        }
    }
}

impl Protocol {
    /// Packing fraction of the random start.
    pub fn phi_start(&self) -> f64 {
        match *self {
            Protocol::Jam { phi_start, .. }
            | Protocol::Phi { phi_start, .. }
            | Protocol::Pressure { phi_start, .. }
            | Protocol::AboveJam { phi_start, .. } => phi_start,
        }
    }

    /// The protocol at each of its targets (`Phi`'s φ, `Pressure`'s
    /// pressure, `AboveJam`'s δφ; a list scans), each with one value, in
    /// the order given; `Jam` as it is. With the targets' name in a label
    /// (`phi`, `p`, `dphi`) when there are several.
    pub fn targets(&self) -> (Vec<Protocol>, Option<&'static str>) {
        let each = |values: &OneOrMany<f64>, set: &dyn Fn(f64) -> Protocol, name| {
            let list: Vec<Protocol> = values.values().into_iter().map(set).collect();
            let named = (list.len() > 1).then_some(name);
            (list, named)
        };
        match self {
            Protocol::Jam { .. } => (vec![self.clone()], None),
            Protocol::Phi { phi, .. } => each(phi, &|v| self.with_target(v), "phi"),
            Protocol::Pressure { pressure, .. } => each(pressure, &|v| self.with_target(v), "p"),
            Protocol::AboveJam { delta_phi, .. } => {
                each(delta_phi, &|v| self.with_target(v), "dphi")
            }
        }
    }

    /// This protocol with its target (φ, pressure or δφ) set to `value`.
    fn with_target(&self, value: f64) -> Protocol {
        let mut out = self.clone();
        match &mut out {
            Protocol::Jam { .. } => {}
            Protocol::Phi { phi: t, .. }
            | Protocol::Pressure { pressure: t, .. }
            | Protocol::AboveJam { delta_phi: t, .. } => *t = OneOrMany::One(value),
        }
        out
    }

    /// Whether the packing is shear-stabilised after the protocol.
    pub fn shear_stabilised(&self) -> bool {
        match *self {
            Protocol::Pressure {
                shear_stabilised, ..
            }
            | Protocol::AboveJam {
                shear_stabilised, ..
            } => shear_stabilised,
            Protocol::Jam { .. } | Protocol::Phi { .. } => false,
        }
    }

    /// The shear stabilisation's settings (`Pressure` and `AboveJam`;
    /// `None` for the others).
    pub fn stabilise(&self) -> Option<&StabiliseParams> {
        match self {
            Protocol::Pressure { stabilise, .. } | Protocol::AboveJam { stabilise, .. } => {
                Some(stabilise)
            }
            Protocol::Jam { .. } | Protocol::Phi { .. } => None,
        }
    }

    /// A short name for tables.
    pub fn name(&self) -> &'static str {
        match self {
            Protocol::Jam { .. } => "jam",
            Protocol::Phi { .. } => "phi",
            Protocol::Pressure { .. } => "pressure",
            Protocol::AboveJam { .. } => "above_jam",
        }
    }
}

/// Rattler removal.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Rattlers {
    /// Bodies with fewer contacts are removed iteratively; `None` uses the
    /// family's default (`d + 1` for disks, spheres and near-disks).
    pub min_contacts: Option<usize>,
}

/// An observable measured on each packing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Observable {
    /// Contacts, rattlers, `z_J` and the isostaticity margin.
    Contacts,
    /// The virial pressure.
    Pressure,
    /// The Hessian's eigenvalues: `D(ω)` (`dos.csv`), `ω₁`, `ω_*` and the
    /// zero modes (`results.csv`). Written `Spectrum()` for the defaults.
    Spectrum {
        /// Only the stiffness part `K` (the paper's choice at φ_J).
        #[serde(default = "yes")]
        stiffness_only: bool,
        /// Leave out the rattlers' rows (kept, each adds `f` zero modes and
        /// `D(ω)` is normalised by all coordinates, as in the paper).
        #[serde(default)]
        remove_rattlers: bool,
        /// Also the eigenvectors: participation ratio and rotational share
        /// of every mode (in `eigenvalues/<id>.csv`; about twice the time).
        #[serde(default)]
        modes: bool,
        /// Write every eigenvalue to `eigenvalues/<id>.csv`.
        #[serde(default)]
        eigenvalues: bool,
        /// Bins and thresholds of `D(ω)`.
        #[serde(default)]
        dos: DosParams,
    },
    /// The gaps between non-rattlers: `Z(h)` and `g(h)` (`gaps.csv`).
    /// Written `Gaps()` for the defaults.
    Gaps {
        /// Largest gap counted (the paper: 2).
        #[serde(default = "default_h_cut")]
        h_cut: f64,
        /// Smallest sample point of `Z(h)`.
        #[serde(default = "default_h_min")]
        h_min: f64,
        /// Sample points per decade.
        #[serde(default = "default_points_per_decade")]
        points_per_decade: usize,
    },
    /// The shear and bulk moduli `G`, `B` by linear response
    /// (`jamkit_observe::moduli`; rattlers removed; `results.csv`).
    /// Written `Moduli()` for the defaults.
    Moduli {
        /// Modes with `ω ≤ omega_zero` are zero modes, left out of `H⁺`
        /// (the spectrum's threshold, 10⁻⁵).
        #[serde(default = "default_moduli_omega_zero")]
        omega_zero: f64,
        /// How `H⁺` is applied: `Sparse` (the default) or `Dense`
        /// (`jamkit_observe::moduli::ModuliSolver`; also each strain step
        /// of a shear stabilisation).
        #[serde(default)]
        solver: ModuliSolver,
    },
}

fn default_moduli_omega_zero() -> f64 {
    ModuliParams::default().omega_zero
}

fn yes() -> bool {
    true
}
fn default_h_cut() -> f64 {
    GapParams::default().h_cut
}
fn default_h_min() -> f64 {
    GapParams::default().h_min
}
fn default_points_per_decade() -> usize {
    GapParams::default().points_per_decade
}

/// The spectrum an experiment asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectrumRequest {
    /// What to assemble.
    pub hessian: HessianOptions,
    /// Eigenvectors too.
    pub modes: bool,
    /// Write the eigenvalues.
    pub eigenvalues: bool,
    /// Bins and thresholds.
    pub dos: DosParams,
}

impl Experiment {
    /// Whether `observable` is asked for (by variant, whatever its settings).
    pub fn wants(&self, observable: &Observable) -> bool {
        self.observables
            .iter()
            .any(|o| std::mem::discriminant(o) == std::mem::discriminant(observable))
    }

    /// The spectrum asked for, if any.
    pub fn spectrum(&self) -> Option<SpectrumRequest> {
        self.observables.iter().find_map(|o| match o {
            Observable::Spectrum {
                stiffness_only,
                remove_rattlers,
                modes,
                eigenvalues,
                dos,
            } => Some(SpectrumRequest {
                hessian: HessianOptions {
                    stiffness_only: *stiffness_only,
                    remove_rattlers: *remove_rattlers,
                },
                modes: *modes,
                eigenvalues: *eigenvalues,
                dos: dos.clone(),
            }),
            _ => None,
        })
    }

    /// The gap sampling asked for, if any.
    pub fn gaps(&self) -> Option<GapParams> {
        self.observables.iter().find_map(|o| match *o {
            Observable::Gaps {
                h_cut,
                h_min,
                points_per_decade,
            } => Some(GapParams {
                h_cut,
                h_min,
                points_per_decade,
            }),
            _ => None,
        })
    }

    /// The moduli asked for, if any.
    pub fn moduli(&self) -> Option<ModuliParams> {
        self.observables.iter().find_map(|o| match *o {
            Observable::Moduli { omega_zero, solver } => Some(ModuliParams { omega_zero, solver }),
            _ => None,
        })
    }

    /// Whether contacts and rattlers must be found (for themselves, or for
    /// the spectrum, the gaps and the moduli, which leave rattlers out).
    pub fn needs_contacts(&self) -> bool {
        self.wants(&Observable::Contacts)
            || self.spectrum().is_some()
            || self.gaps().is_some()
            || self.moduli().is_some()
    }

    fn validate_observables(&self) -> Result<(), ExperimentError> {
        for (k, o) in self.observables.iter().enumerate() {
            if self.observables[..k]
                .iter()
                .any(|p| std::mem::discriminant(p) == std::mem::discriminant(o))
            {
                return Err(ExperimentError::invalid(
                    "observables",
                    format!("{o:?}"),
                    "is listed twice; list each observable once",
                ));
            }
        }
        if let Some(s) = self.spectrum() {
            s.dos.validate("observables.Spectrum.dos")?;
        }
        if let Some(g) = self.gaps() {
            g.validate("observables.Gaps")?;
        }
        if let Some(m) = self.moduli() {
            m.validate("observables.Moduli")?;
        }
        Ok(())
    }
}

/// Engine tuning.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EngineParams {
    /// Verlet skin, in units of the smallest body's bounding radius.
    pub skin: f64,
}

impl Default for EngineParams {
    fn default() -> Self {
        Self { skin: 0.4 }
    }
}

/// What to write.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputParams {
    /// Write positions and orientations into `packings/<id>.json`. The
    /// record with the measured values is written either way (it is what
    /// makes a run resumable).
    pub packings: bool,
    /// Also write each packing as extended XYZ, `packings/<id>.xyz` (the
    /// frame of `jamkit export`, for OVITO and ASE), before its JSON; a
    /// resumed run writes the ones that are missing. Needs `packings`.
    /// Not written out when off, so that earlier runs read the same.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub extxyz: bool,
}

impl Default for OutputParams {
    fn default() -> Self {
        Self {
            packings: true,
            extxyz: false,
        }
    }
}

/// A scan setting as text, `minimizer.force_tol = 1e-22, …`.
pub fn scan_text(setting: &[(String, ron::Value)]) -> String {
    setting
        .iter()
        .map(|(k, v)| format!("{k} = {}", scan_value_text(v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A scanned value as text: a float in exponent form (`1e-22`), anything
/// else as compact RON.
pub fn scan_value_text(v: &ron::Value) -> String {
    match v {
        ron::Value::Number(n @ (ron::Number::F32(_) | ron::Number::F64(_))) => {
            format!("{:e}", n.into_f64())
        }
        other => ron::to_string(other).unwrap_or_else(|_| format!("{other:?}")),
    }
}

/// The largest `N` accepted (memory and time guard; the neighbour list is
/// `O(N)` but a run of a million bodies is not what a file typo should start).
pub const MAX_PARTICLES: usize = 10_000_000;

/// One grid point's scanned settings: `(path, value)` per scanned field.
pub type ScanSetting = Vec<(String, ron::Value)>;

impl Experiment {
    /// The setting paths of the `scan` axes (`minimizer.force_tol`, …), in
    /// the order of the packing ids: axis by axis, each axis's paths in
    /// name order. Empty when nothing scans. `results.csv` gives each a
    /// column.
    pub fn scan_paths(&self) -> Vec<String> {
        self.scan
            .iter()
            .flat_map(|axis| axis.keys().cloned())
            .collect()
    }

    /// The settings of the `scan` axes, in grid order (the first axis
    /// varies slowest), each with this experiment as it runs there: the
    /// values written in by the same path as `--set` (so checked like the
    /// file), `scan` emptied, and the whole checked by [`Self::validate`].
    /// One empty setting (this experiment) when nothing scans.
    pub fn scanned(&self) -> Result<Vec<(ScanSetting, Experiment)>, ExperimentError> {
        if self.scan.is_empty() {
            return Ok(vec![(Vec::new(), self.clone())]);
        }
        let mut last_parts: Vec<&str> = Vec::new();
        let mut combos: Vec<ScanSetting> = vec![Vec::new()];
        for (k, axis) in self.scan.iter().enumerate() {
            let field = |key: &str| format!("scan[{k}].{key}");
            let mut len = None;
            for (key, values) in axis {
                if !(key.starts_with("minimizer.") || key.starts_with("protocol.")) {
                    return Err(ExperimentError::invalid(
                        field(key),
                        "(given)",
                        "scans a field of `minimizer` or `protocol` (e.g. \"minimizer.force_tol\"); \
                         params, dim and particles scan as lists in place",
                    ));
                }
                let last = key.rsplit('.').next().unwrap_or(key);
                if last_parts.contains(&last) {
                    return Err(ExperimentError::invalid(
                        field(key),
                        "(given)",
                        format!("a second scanned field named `{last}`: packing ids would clash"),
                    ));
                }
                last_parts.push(last);
                if values.is_empty() || len.is_some_and(|n| n != values.len()) {
                    return Err(ExperimentError::invalid(
                        field(key),
                        format!("{} values", values.len()),
                        "at least one value, and as many as every other list of its axis",
                    ));
                }
                len = Some(values.len());
            }
            // Two equal settings would be two points with one label.
            for i in 0..len.unwrap_or(0) {
                let same = |j: usize| axis.values().all(|v| v[i] == v[j]);
                if (0..i).any(same) {
                    let setting: Vec<(String, ron::Value)> = axis
                        .iter()
                        .map(|(k, v)| (k.clone(), v[i].clone()))
                        .collect();
                    return Err(ExperimentError::invalid(
                        format!("scan[{k}]"),
                        scan_text(&setting),
                        "is listed twice; list each setting once",
                    ));
                }
            }
            let Some(len) = len else {
                return Err(ExperimentError::invalid(
                    format!("scan[{k}]"),
                    "{}",
                    "an axis names at least one field",
                ));
            };
            combos = combos
                .into_iter()
                .flat_map(|c| {
                    (0..len).map(move |i| {
                        let mut c = c.clone();
                        c.extend(axis.iter().map(|(key, v)| (key.clone(), v[i].clone())));
                        c
                    })
                })
                .collect();
        }
        let mut base = self.clone();
        base.scan.clear();
        combos
            .into_iter()
            .map(|setting| {
                let text = scan_text(&setting);
                let values: Vec<(String, serde_json::Value)> = setting
                    .iter()
                    .map(|(key, v)| {
                        serde_json::to_value(v)
                            .map(|v| (key.clone(), v))
                            .map_err(|e| ExperimentError::invalid("scan", &text, e.to_string()))
                    })
                    .collect::<Result<_, _>>()?;
                let e = crate::overrides::apply_values(&base, &values)
                    .and_then(|e| e.validate().map(|()| e))
                    .map_err(|e| ExperimentError::invalid("scan", &text, e.to_string()))?;
                Ok((setting, e))
            })
            .collect()
    }

    /// Parse RON text; `file` names the source in errors.
    pub fn from_ron(text: &str, file: &str) -> Result<Self, ExperimentError> {
        // Some editors start a UTF-8 file with a byte-order mark; it is not
        // part of the RON.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Optional fields take a bare value (`dt_max: 0.3`) as well as
        // `Some(0.3)`.
        ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| ExperimentError::Parse {
                file: file.to_string(),
                message: e.to_string(),
            })
    }

    /// Read and parse a file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, ExperimentError> {
        let text = std::fs::read_to_string(path).map_err(|e| ExperimentError::io(path, e))?;
        Self::from_ron(&text, &path.display().to_string())
    }

    /// Check every range that serde cannot; the family's own parameters are
    /// checked by the registry when the grid is expanded. Last, a dense
    /// eigen-solve (`Spectrum`, dense `Moduli`, `escape_saddles`) that
    /// cannot fit in this machine's memory is refused ([`crate::memory`]).
    pub fn validate(&self) -> Result<(), ExperimentError> {
        if self.name.trim().is_empty() {
            return Err(ExperimentError::invalid(
                "name",
                format!("{:?}", self.name),
                "must not be blank",
            ));
        }
        self.validate_dims()?;
        if self.output.extxyz && !self.output.packings {
            return Err(ExperimentError::invalid(
                "output.extxyz",
                true,
                "needs output.packings = true: the frame is the packing's configuration",
            ));
        }
        let particles = self.particles.values();
        if particles.is_empty() {
            return Err(ExperimentError::invalid(
                "particles",
                "[]",
                "must list at least one N",
            ));
        }
        for (k, &n) in particles.iter().enumerate() {
            if !(2..=MAX_PARTICLES).contains(&n) {
                return Err(ExperimentError::invalid(
                    "particles",
                    n,
                    format!("must be between 2 and {MAX_PARTICLES}"),
                ));
            }
            // Two equal entries would be two jobs with one id and one file.
            if particles[..k].contains(&n) {
                return Err(ExperimentError::invalid(
                    "particles",
                    n,
                    "is listed twice; list each N once",
                ));
            }
        }
        if self.samples == 0 {
            return Err(ExperimentError::invalid("samples", 0, "must be at least 1"));
        }
        self.sizes.validate()?;
        self.minimizer.validate("minimizer")?;
        self.validate_protocol()?;
        self.scanned()?;
        self.validate_observables()?;
        if self.protocol.shear_stabilised() && self.moduli().is_none() {
            return Err(ExperimentError::invalid(
                "protocol.shear_stabilised",
                true,
                "needs the Moduli observable (only the moduli are measured on the stabilised cell)",
            ));
        }
        if let Some(stabilise) = self.protocol.stabilise()
            && !stabilise.is_default()
        {
            if !self.protocol.shear_stabilised() {
                return Err(ExperimentError::invalid(
                    "protocol.stabilise",
                    format!("{stabilise:?}"),
                    "only applies with protocol.shear_stabilised = true; set it, or leave stabilise out",
                ));
            }
            stabilise.validate("protocol.stabilise")?;
        }
        if !(self.engine.skin > 0.0 && self.engine.skin <= 2.0) {
            return Err(ExperimentError::invalid(
                "engine.skin",
                self.engine.skin,
                "must lie in (0, 2] (units of the smallest bounding radius)",
            ));
        }
        if self.rattlers.min_contacts == Some(0) {
            return Err(ExperimentError::invalid(
                "rattlers.min_contacts",
                0,
                "must be at least 1, or None for the family's default",
            ));
        }
        Ok(())
    }

    /// Every listed dimension is one the family supports, none twice.
    pub(crate) fn validate_dims(&self) -> Result<(), ExperimentError> {
        let info = jamkit_registry::family_info(&self.family)?;
        let dims = self.dim.values();
        if dims.is_empty() {
            return Err(ExperimentError::invalid(
                "dim",
                "[]",
                format!(
                    "must list at least one dimension; family `{}` supports {}",
                    self.family,
                    jamkit_registry::describe_dims(&info)
                ),
            ));
        }
        for (k, &d) in dims.iter().enumerate() {
            if !jamkit_registry::supports_dim(&info, d) {
                return Err(ExperimentError::invalid(
                    "dim",
                    d,
                    format!(
                        "family `{}` supports {}",
                        self.family,
                        jamkit_registry::describe_dims(&info)
                    ),
                ));
            }
            if dims[..k].contains(&d) {
                return Err(ExperimentError::invalid(
                    "dim",
                    d,
                    "is listed twice; list each dimension once",
                ));
            }
        }
        Ok(())
    }

    fn validate_protocol(&self) -> Result<(), ExperimentError> {
        let phi_start = self.protocol.phi_start();
        if !(phi_start > 0.0 && phi_start < 1.0) {
            return Err(ExperimentError::invalid(
                "protocol.phi_start",
                phi_start,
                "must lie in (0, 1)",
            ));
        }
        let (targets, _) = self.protocol.targets();
        if targets.is_empty() {
            return Err(ExperimentError::invalid(
                "protocol",
                format!("{:?}", self.protocol),
                "a list of targets (phi, pressure or delta_phi) must hold at least one value",
            ));
        }
        for protocol in &targets {
            self.validate_target(protocol)?;
        }
        Ok(())
    }

    /// The checks of one protocol with a single target.
    fn validate_target(&self, protocol: &Protocol) -> Result<(), ExperimentError> {
        let single = |t: &OneOrMany<f64>| t.first().unwrap_or(f64::NAN);
        match *protocol {
            Protocol::Jam {
                eps,
                energy_low,
                energy_high,
                max_density_steps,
                search,
                ..
            }
            | Protocol::AboveJam {
                eps,
                energy_low,
                energy_high,
                max_density_steps,
                search,
                ..
            } => {
                JamParams {
                    eps,
                    energy_low,
                    energy_high,
                    max_density_steps,
                    search,
                }
                .validate("protocol")?;
                // NOTE: FIRE stops at V/N < energy_tol; if that were above the
                // window's lower edge, an unrelaxed state could be taken as
                // jammed.
                if self.minimizer.energy_tol > energy_low {
                    return Err(ExperimentError::invalid(
                        "minimizer.energy_tol",
                        self.minimizer.energy_tol,
                        format!("must not exceed protocol.energy_low = {energy_low:e}"),
                    ));
                }
                if let Protocol::AboveJam {
                    ref delta_phi,
                    compress_eps,
                    ..
                } = *protocol
                {
                    let delta_phi = single(delta_phi);
                    if !(delta_phi > 0.0 && delta_phi < 0.5) {
                        return Err(ExperimentError::invalid(
                            "protocol.delta_phi",
                            delta_phi,
                            "must lie in (0, 0.5) (φ − φ_J above the jamming point)",
                        ));
                    }
                    if !(compress_eps > 0.0 && compress_eps < 1.0) {
                        return Err(ExperimentError::invalid(
                            "protocol.compress_eps",
                            compress_eps,
                            "must lie in (0, 1)",
                        ));
                    }
                }
            }
            Protocol::Phi { ref phi, eps, .. } => {
                let phi = single(phi);
                if !(phi > 0.0 && phi.is_finite()) {
                    return Err(ExperimentError::invalid(
                        "protocol.phi",
                        phi,
                        "must be positive and finite",
                    ));
                }
                if !(eps > 0.0 && eps < 1.0) {
                    return Err(ExperimentError::invalid(
                        "protocol.eps",
                        eps,
                        "must lie in (0, 1)",
                    ));
                }
            }
            Protocol::Pressure {
                ref pressure,
                tol,
                eps,
                max_density_steps,
                ..
            } => {
                let pressure = single(pressure);
                if !(pressure > 0.0 && pressure.is_finite()) {
                    return Err(ExperimentError::invalid(
                        "protocol.pressure",
                        pressure,
                        "must be positive and finite",
                    ));
                }
                if !(tol > 0.0 && tol < 1.0) {
                    return Err(ExperimentError::invalid(
                        "protocol.tol",
                        tol,
                        "must lie in (0, 1)",
                    ));
                }
                if !(eps > 0.0 && eps < 1.0) {
                    return Err(ExperimentError::invalid(
                        "protocol.eps",
                        eps,
                        "must lie in (0, 1)",
                    ));
                }
                if max_density_steps == 0 {
                    return Err(ExperimentError::invalid(
                        "protocol.max_density_steps",
                        0,
                        "must be at least 1",
                    ));
                }
            }
        }
        Ok(())
    }
}
