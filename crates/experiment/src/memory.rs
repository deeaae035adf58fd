//! The dense matrices some measurements build, against the machine's
//! memory: an experiment whose dense eigen-solve cannot fit is refused at
//! validation, before any packing is made, instead of failing (or being
//! killed) when its first packing is measured.
//!
//! Two things diagonalise the Hessian densely: the `Spectrum` observable
//! (every eigenvalue; with `modes`, every eigenvector too) and the `Moduli`
//! observable with `solver: Dense` (every mode, for the pseudo-inverse);
//! the saddle escape (`protocol.escape_saddles`) is sparse. The
//! Hessian has `n = N (d + k)` rows, `N` bodies of `d` translational and
//! `k` rotational coordinates (rattlers' rows included: they are removed
//! only with `remove_rattlers`, and a packing may have none), and the
//! eigen-solve holds, at the same time, the dense `n × n` Hessian and the
//! solver's working copy of it (faer's `self_adjoint_evd` scratch), plus the
//! `n × n` eigenvectors when they are computed: 2 or 3 matrices of `n²`
//! 8-byte floats. That is a lower bound (the solver's smaller buffers are
//! left out), so a refused file could not have run.
//!
//! The rule: refuse when one sample's lower bound exceeds the machine's
//! physical memory, `MemTotal` of `/proc/meminfo`. Not `MemAvailable`,
//! which changes with whatever else runs and with the page cache: a file
//! valid on a machine stays valid there. Samples running in parallel
//! (`--jobs`) each hold their own matrices, which the check does not
//! count. Where `/proc/meminfo` is absent (not Linux) nothing is checked.

use crate::error::ExperimentError;
use crate::schema::Experiment;

/// Bytes of one matrix entry (`f64`).
const ENTRY: u64 = 8;

/// The machine's physical memory in bytes (`MemTotal` of `/proc/meminfo`),
/// `None` where it cannot be read.
pub fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    mem_total(&text)
}

/// `MemTotal` of the text of `/proc/meminfo`, in bytes (the file gives kB,
/// meaning KiB).
fn mem_total(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemTotal:"))?;
    let mut words = line["MemTotal:".len()..].split_whitespace();
    let kib: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") | None => kib.checked_mul(1024),
        Some(_) => None,
    }
}

/// One dense eigen-solve an experiment asks for.
#[derive(Clone, Debug)]
pub struct DenseSolve {
    /// The field that asks for it.
    pub field: &'static str,
    /// Its value, as written in the file.
    pub value: String,
    /// `n × n` matrices held at once: the Hessian, the solver's copy and,
    /// when computed, the eigenvectors.
    pub matrices: u64,
    /// What the matrices are, for the message.
    pub what: &'static str,
    /// What to ask for instead, given the largest `N` that fits.
    alternative: fn(max_particles: u64) -> String,
}

/// The dense eigen-solves of one sample of `experiment`.
pub fn dense_solves(experiment: &Experiment) -> Vec<DenseSolve> {
    const VALUES: &str = "the Hessian and the eigensolver's working copy";
    const VECTORS: &str = "the Hessian, the eigensolver's working copy and the eigenvectors";
    let mut out = Vec::new();
    if let Some(s) = experiment.spectrum() {
        let (matrices, what, value) = if s.modes {
            (3, VECTORS, "Spectrum(modes: true)")
        } else {
            (2, VALUES, "Spectrum")
        };
        out.push(DenseSolve {
            field: "observables",
            value: value.into(),
            matrices,
            what,
            alternative: if s.modes {
                |n| {
                    format!(
                        "Spectrum has no sparse solver: leave out `modes: true` (the eigenvalues alone hold 2 of the 3 matrices), use at most particles = {n} here, or leave Spectrum out"
                    )
                }
            } else {
                |n| {
                    format!(
                        "Spectrum has no sparse solver: use at most particles = {n} here, or leave Spectrum out"
                    )
                }
            },
        });
    }
    if let Some(m) = experiment.moduli()
        && m.solver.is_dense()
    {
        out.push(DenseSolve {
            field: "observables",
            value: "Moduli(solver: Dense)".into(),
            matrices: 3,
            what: VECTORS,
            alternative: |n| {
                format!(
                    "use Moduli(solver: Sparse) (a sparse Cholesky factorisation, no dense matrix; it falls back to the dense path, which would not fit either, only for a packing with zero modes besides the translations, a negative mode or a softest mode with λ ≤ 2 omega_zero²), or at most particles = {n} here"
                )
            },
        });
    }
    out
}

/// Bytes of `matrices` dense `rows × rows` matrices of `f64` (saturating).
pub fn dense_bytes(rows: u64, matrices: u64) -> u64 {
    rows.saturating_mul(rows)
        .saturating_mul(ENTRY)
        .saturating_mul(matrices)
}

/// The largest `N` whose `matrices` dense matrices of `N × coordinates`
/// rows fit in `memory` bytes.
pub fn max_particles(memory: u64, coordinates: u64, matrices: u64) -> u64 {
    let rows = ((memory / (ENTRY * matrices)) as f64).sqrt() as u64;
    // The square root in floating point may be one off either way.
    let mut rows = rows + 1;
    while rows > 0 && dense_bytes(rows, matrices) > memory {
        rows -= 1;
    }
    rows / coordinates.max(1)
}

/// `bytes` in GB (10⁹ bytes), for messages.
fn gb(bytes: u64) -> String {
    let g = bytes as f64 / 1e9;
    if g >= 100.0 {
        format!("{g:.0} GB")
    } else {
        format!("{g:.1} GB")
    }
}

/// Refuse a dense eigen-solve of one sample that cannot fit in `memory`
/// bytes: `particles` bodies in `dim` dimensions with `rot_dof` rotational
/// coordinates each, for `family`. The error names the field and value,
/// the memory needed and available, and the alternative.
pub fn check_dense_solves(
    solves: &[DenseSolve],
    (family, dim, rot_dof): (&str, usize, usize),
    particles: usize,
    memory: u64,
) -> Result<(), ExperimentError> {
    let coordinates = (dim + rot_dof) as u64;
    let rows = (particles as u64).saturating_mul(coordinates);
    for s in solves {
        let needed = dense_bytes(rows, s.matrices);
        if needed > memory {
            let fit = max_particles(memory, coordinates, s.matrices);
            return Err(ExperimentError::invalid(
                s.field,
                &s.value,
                format!(
                    "at particles = {particles}, dim = {dim} (family `{family}`: {coordinates} coordinates per body, a Hessian of {rows} rows) its dense eigen-solve needs at least {} ({} matrices of {rows} × {rows} 8-byte floats: {}), more than this machine's memory, {} (MemTotal in /proc/meminfo); {}",
                    gb(needed),
                    s.matrices,
                    s.what,
                    gb(memory),
                    (s.alternative)(fit),
                ),
            ));
        }
    }
    Ok(())
}

/// The dense eigen-solves of one grid point (`experiment`'s observables,
/// the point's `dim`, `particles`, and the family's `rot_dof` there)
/// checked against `memory`, this machine's ([`machine_memory`]; nothing
/// is checked where it cannot be read). Asked for every point as the grid
/// is planned ([`crate::plan::Plan::new`]), so `jamkit validate` and `jamkit run`
/// both refuse such a file.
pub(crate) fn check_point(
    experiment: &Experiment,
    (dim, particles, rot_dof): (usize, usize, usize),
    memory: Option<u64>,
) -> Result<(), ExperimentError> {
    let Some(memory) = memory else {
        return Ok(());
    };
    let solves = dense_solves(experiment);
    if solves.is_empty() {
        return Ok(());
    }
    check_dense_solves(
        &solves,
        (&experiment.family, dim, rot_dof),
        particles,
        memory,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn experiment(observables: &str, protocol: &str) -> Experiment {
        Experiment::from_ron(
            &format!(
                r#"(name: "m", family: "sphere", dim: 3, particles: 30000,
                protocol: {protocol}, observables: [{observables}])"#
            ),
            "m",
        )
        .unwrap()
    }

    /// 30000 spheres in 3D: a Hessian of 90000 rows, 64.8 GB a matrix.
    #[test]
    fn a_spectrum_of_30000_spheres_in_3d_needs_two_hessians_of_65_gb() {
        let e = experiment("Contacts, Spectrum()", "Jam()");
        let solves = dense_solves(&e);
        assert_eq!(solves.len(), 1);
        assert_eq!(dense_bytes(90_000, 1), 64_800_000_000);
        let sphere = ("sphere", 3, 0);
        // Fits in 130 GB, not in 64 GB.
        check_dense_solves(&solves, sphere, 30_000, 130_000_000_000).unwrap();
        let err = check_dense_solves(&solves, sphere, 30_000, 64_000_000_000)
            .unwrap_err()
            .to_string();
        for part in [
            "observables = Spectrum:",
            "particles = 30000",
            "a Hessian of 90000 rows",
            "needs at least 130 GB",
            "more than this machine's memory, 64.0 GB",
            "Spectrum has no sparse solver",
        ] {
            assert!(err.contains(part), "{part:?} missing from: {err}");
        }
        // The largest N that fits in 64 GB, named in the message, fits.
        let fit = max_particles(64_000_000_000, 3, 2);
        assert!(
            err.contains(&format!("at most particles = {fit} here")),
            "{err}"
        );
        check_dense_solves(&solves, sphere, fit as usize, 64_000_000_000).unwrap();
        check_dense_solves(&solves, sphere, fit as usize + 1, 64_000_000_000).unwrap_err();
    }

    /// Rotational coordinates enlarge the Hessian: 3D ellipsoids have 6
    /// per body, so the same N needs four times the memory of spheres.
    #[test]
    fn rotational_coordinates_count_in_the_rows() {
        let e = experiment("Spectrum()", "Jam()");
        let solves = dense_solves(&e);
        let memory = dense_bytes(90_000, 2);
        check_dense_solves(&solves, ("sphere", 3, 0), 30_000, memory).unwrap();
        let err = check_dense_solves(&solves, ("ellipsoid", 3, 3), 30_000, memory)
            .unwrap_err()
            .to_string();
        assert!(err.contains("6 coordinates per body"), "{err}");
        assert!(err.contains("at most particles = 15000 here"), "{err}");
    }

    /// Dense moduli hold the eigenvectors too, and name their
    /// alternative; sparse moduli and the saddle escape build no dense
    /// matrix.
    #[test]
    fn dense_moduli_are_counted_sparse_moduli_and_saddle_escapes_are_not() {
        let memory = dense_bytes(90_000, 2);
        let sphere = ("sphere", 3, 0);
        let dense = experiment("Moduli(solver: Dense)", "Pressure(pressure: 1e-3)");
        let err = check_dense_solves(&dense_solves(&dense), sphere, 30_000, memory)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("observables = Moduli(solver: Dense):")
                && err.contains("3 matrices")
                && err.contains("use Moduli(solver: Sparse)"),
            "{err}"
        );
        for sparse in ["Moduli(solver: Sparse)", "Moduli()"] {
            let sparse = experiment(sparse, "Pressure(pressure: 1e-3)");
            assert!(dense_solves(&sparse).is_empty());
        }
        let escape = experiment("Contacts", "Jam(escape_saddles: true)");
        assert!(dense_solves(&escape).is_empty());
        let plain = experiment("Contacts, Pressure, Gaps()", "Jam()");
        assert!(dense_solves(&plain).is_empty());
    }

    #[test]
    fn mem_total_is_read_in_bytes() {
        let text =
            "MemTotal:       16314572 kB\nMemFree:         1234 kB\nMemAvailable:   9000000 kB\n";
        assert_eq!(mem_total(text), Some(16_314_572 * 1024));
        assert_eq!(mem_total("MemFree: 1 kB\n"), None);
        assert_eq!(mem_total("MemTotal: lots\n"), None);
    }
}
