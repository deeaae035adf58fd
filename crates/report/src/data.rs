//! The packings of one or more runs, grouped into points of the paper's
//! near-disk ensembles: family, mode number `n`, amplitude `Δ` and `N`; and
//! of their 3D counterpart, near-spheres of one spherical-harmonic mode
//! (`harmonic`, mode number `l`).

use crate::ReportError;
use jamkit_core::gap_model::GapModel;
use jamkit_format::PackingFile;
use jamkit_observe::gaps::GapCounts;
use jamkit_observe::spectrum::{DosHistogram, DosParams};
use std::path::{Path, PathBuf};

/// One packing, reduced to what the figures need.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Packing fraction at jamming.
    pub phi: f64,
    /// `z_J` among non-rattlers (if contacts were measured).
    pub z_j: Option<f64>,
    /// Non-rattlers `N_nr`.
    pub n_nr: Option<usize>,
    /// Rattler fraction `N_r / N`.
    pub rattler_fraction: Option<f64>,
    /// `ω₁` (if the spectrum was measured and it is defined).
    pub omega_1: Option<f64>,
    /// `ω_*`.
    pub omega_star: Option<f64>,
    /// The binned spectrum.
    pub dos: Option<DosHistogram>,
    /// Its bins and thresholds.
    pub dos_params: Option<DosParams>,
    /// Gap counts.
    pub gaps: Option<GapCounts>,
}

impl Sample {
    /// `δz_J = z_J − z_iso`, `z_iso = 2d − 2d/N_nr` (the paper's Eq. (2),
    /// with the non-rattlers).
    pub fn dz(&self, dim: usize) -> Option<f64> {
        let (z, n) = (self.z_j?, self.n_nr? as f64);
        let d = dim as f64;
        (n > 0.0).then(|| z - (2.0 * d - 2.0 * d / n))
    }
}

/// All packings of one (family, n, Δ, N).
#[derive(Clone, Debug)]
pub struct Point {
    /// Family name.
    pub family: String,
    /// Dimension.
    pub dim: usize,
    /// Mode number.
    pub n: u32,
    /// Its name: `n` (the near-disks' `sin nθ`) or `l` (near-spheres of one
    /// mode `Y_lm`).
    pub mode: &'static str,
    /// Amplitude Δ.
    pub delta: f64,
    /// The gap model of the packings (the family parameter `gap`; absent
    /// is the paper's first order).
    pub gap: GapModel,
    /// Bodies.
    pub particles: usize,
    /// Its packings.
    pub samples: Vec<Sample>,
}

/// The packing files of the run (or archive) in `run`, sorted by name:
/// `run/packings/*.json` without the `.failed.json` states of failed
/// samples (which are not packings at jamming).
pub fn packing_paths(run: &Path) -> Result<Vec<PathBuf>, ReportError> {
    let dir = run.join("packings");
    let entries = std::fs::read_dir(&dir).map_err(|e| ReportError::Io {
        path: dir.clone(),
        error: e,
    })?;
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .filter(|p| !p.to_string_lossy().ends_with(".failed.json"))
        .collect();
    paths.sort();
    Ok(paths)
}

/// The points found in `dirs` (each a run's output directory), and the
/// number of packing files skipped (not a `fourier` near-disk with `n` and
/// `delta`, or unreadable). A packing present in several runs (same id and
/// settings) is taken once, with the observables of its first file.
pub fn load(dirs: &[impl AsRef<Path>]) -> Result<(Vec<Point>, usize), ReportError> {
    let mut skipped = 0;
    // Runs that share a grid point and seeds hold the same packing more
    // than once (same id, same settings): it counts once, from the file
    // with the most observables.
    let mut files: Vec<PackingFile> = Vec::new();
    for dir in dirs {
        for path in packing_paths(dir.as_ref())? {
            let Some(file) = PackingFile::load(&path) else {
                skipped += 1;
                continue;
            };
            let same = |f: &PackingFile| f.id == file.id && f.settings == file.settings;
            match files.iter_mut().find(|f| same(f)) {
                Some(f) if richness(&file) > richness(f) => *f = file,
                Some(_) => {}
                None => files.push(file),
            }
        }
    }
    let mut points: Vec<Point> = Vec::new();
    for file in &files {
        let param = |k: &str| file.params.get(k).and_then(|v| v.as_f64());
        let Some(((mode, n), delta)) = mode_number(file).zip(param("delta")) else {
            skipped += 1;
            continue;
        };
        let Some(gap) = gap_model(file) else {
            skipped += 1;
            continue;
        };
        let m = &file.measures;
        let sample = Sample {
            phi: m.phi,
            z_j: m.z_j,
            n_nr: m.n_rattlers.map(|r| file.particles - r),
            rattler_fraction: m.n_rattlers.map(|r| r as f64 / file.particles as f64),
            omega_1: m.spectrum.as_ref().and_then(|s| s.omega_1()),
            omega_star: m.spectrum.as_ref().and_then(|s| s.omega_star()),
            dos: m.spectrum.as_ref().map(|s| s.histogram.clone()),
            dos_params: m.spectrum.as_ref().map(|s| s.dos.clone()),
            gaps: m.gaps.clone(),
        };
        let key = |p: &Point| {
            p.family == file.family
                && p.dim == file.dim
                && p.mode == mode
                && p.n == n as u32
                && p.delta == delta
                && p.gap == gap
                && p.particles == file.particles
        };
        match points.iter_mut().find(|p| key(p)) {
            Some(p) => p.samples.push(sample),
            None => points.push(Point {
                family: file.family.clone(),
                dim: file.dim,
                n: n as u32,
                mode,
                delta,
                gap,
                particles: file.particles,
                samples: vec![sample],
            }),
        }
    }
    points.sort_by(|a, b| {
        (a.n, a.particles, a.gap as u8)
            .cmp(&(b.n, b.particles, b.gap as u8))
            .then(a.delta.total_cmp(&b.delta))
    });
    Ok((points, skipped))
}

/// The mode of a packing's shape, `(name, number)`: a near-disk's `n`, or
/// the `l` of a near-sphere with one mode (`harmonic` with `l` and `m`, not
/// a list of modes). `None` for every other shape.
fn mode_number(file: &PackingFile) -> Option<(&'static str, f64)> {
    let param = |k: &str| file.params.get(k).and_then(|v| v.as_f64());
    match param("n") {
        Some(n) => Some(("n", n)),
        None if file.family == "harmonic" => param("l").map(|l| ("l", l)),
        None => None,
    }
}

/// The gap model of a packing: its `gap` parameter, absent or `null` for
/// the paper's first order; `None` for a name no family writes.
fn gap_model(file: &PackingFile) -> Option<GapModel> {
    match file.params.get("gap") {
        None | Some(serde_json::Value::Null) => Some(GapModel::FirstOrder),
        Some(serde_json::Value::String(name)) => name.parse().ok(),
        Some(_) => None,
    }
}

/// How many observables a packing file holds.
fn richness(f: &PackingFile) -> usize {
    let m = &f.measures;
    [
        m.z_j.is_some(),
        m.pressure.is_some(),
        m.spectrum.is_some(),
        m.gaps.is_some(),
    ]
    .iter()
    .filter(|&&b| b)
    .count()
}

/// Mean and standard error of the mean of the values `f` gives (NaN when
/// there are none).
pub fn mean_sem<T>(items: &[T], f: impl Fn(&T) -> Option<f64>) -> (f64, f64) {
    let v: Vec<f64> = items.iter().filter_map(f).collect();
    jamkit_format::mean_sem(&v)
}
