//! Saddle escape at the end of the jamming search.
//!
//! **Why.** FIRE stops where the force falls below its tolerance, and a
//! saddle of `V` with forces below it is such a place: measured on binary
//! disks at N = 4096 (seed 2 of `experiments/quickstart.ron`, the default
//! path), the search ended with every contact closed, the largest force
//! component at the tolerance and two negative eigenvalues of the Hessian
//! (`−9.9·10⁻⁹`, `−4.8·10⁻⁹`, extended modes): one contact short of
//! isostatic. A lower force tolerance does not help (the forces reach
//! round-off first). The Newton finish does not get there either: it gives
//! up where `H + μI` is not positive definite (`crate::newton`).
//!
//! **Detection.** The true Hessian `H = ∂²V/∂q∂q` (every contact, with
//! [`SaddleParams::full_hessian`]; else `K + T` of the non-rattlers, their
//! rows removed) is assembled sparse and factorised by faer's sparse
//! Cholesky at the shift `μ = threshold · d̄`, `d̄` the mean of the positive
//! diagonal entries, as the Newton finish does. It succeeds exactly when no
//! eigenvalue lies below `−μ`: the state is not a saddle and nothing else
//! is done (one factorisation, the cost of one Newton iteration). The zero
//! modes (the global translations, rattlers' coordinates) sit at `0 > −μ`
//! and never count.
//!
//! **The mode.** Where the factorisation fails, the shift is doubled until
//! `H + cI` factorises (then `c > −λ_min ≥ c/2`), and inverse iteration
//! with `(H + cI)⁻¹` from a fixed start vector converges to the lowest
//! eigenvector: its eigenvalue `1/(c + λ_min)` is the largest, and the
//! zero modes' `1/c` at most half of it. The iteration stops when the
//! Rayleigh quotient `ρ = vᵀHv / vᵀv` changes by less than
//! [`RAYLEIGH_TOL`] (relative) between two iterations; any direction with
//! `ρ < −μ` lowers the energy, so the mode need not be exact. A quotient
//! not below `−μ` (a factorisation that failed on round-off) counts as no
//! saddle.
//!
//! **The escape.** The packing is kicked along the mode, by
//! [`SaddleParams::kick`] (doubled at every further push) on the sign that
//! lowers `V` at a small trial amplitude, and the jamming search is re-run
//! from the current φ with a small initial `ε`, so that the packing ends
//! again in the window `E_low < V/N < E_high` with the same FIRE
//! tolerances; then the check again, at most [`SaddleParams::max_rounds`]
//! times. Why a kick and not a line search to the lowest `V` along the
//! mode: measured on the disks at N = 4096 above, the end state's residual
//! gradient (at FIRE's tolerance) tilts the line, and along the falling
//! sign `V` falls only for `~10⁻⁶` of the mode before an open contact
//! (gap `10⁻⁸`) closes; closing it leaves a negative mode of nearly the
//! same eigenvalue (one constraint on a soft subspace of several modes),
//! and FIRE, whose force tolerance admits `~10⁻⁵` of a mode with curvature
//! `−10⁻⁸`, slides back onto the saddle's slope. A kick of `10⁻⁴` body
//! sizes gives FIRE forces far above its tolerance and a different end
//! state: there the third push (kick `4·10⁻⁴`) ended on a minimum with
//! three more contacts (iso_margin 2).
//!
//! **Inside a minimisation.** The Newton finish finds the lowest mode of
//! a state stalled on a saddle by the same factorisation and iteration
//! ([`negative_curvature`]) and pushes along it ([`crate::newton`],
//! plateaus).
//!
//! **Bit for bit.** The check reads the configuration and moves nothing,
//! so on a state that is not a saddle the packing is the search's, bit for
//! bit. The factorisation, the iteration and the pushes are
//! sequential with a fixed order of operations, so an escape, too, depends
//! on the configuration only (not on the thread count).

use crate::hessian::{Hessian, HessianOptions};
use crate::newton::{mean_positive_diagonal, sparse_cholesky, upper_triplets};
use crate::{Fire, JamParams, Objective, Scene, Work, jam};
use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::Triplet;
use jamkit_core::{Error, Result, Shape};

/// Relative change of the Rayleigh quotient between two inverse
/// iterations below which the mode is taken as found.
pub const RAYLEIGH_TOL: f64 = 1e-6;

/// Largest kick, in units of the smallest body size.
pub const MAX_KICK: f64 = 0.1;

/// Inverse iterations at most per mode.
pub const MAX_ITERATIONS: u32 = 200;

/// Parameters of the saddle escape.
#[derive(Clone, Debug, PartialEq)]
pub struct SaddleParams {
    /// A state is a saddle when `H` has an eigenvalue below
    /// `−threshold · d̄`, `d̄` the mean positive diagonal entry of `H`. The
    /// default `10⁻¹⁰` is the Newton finish's shift: far above the
    /// factorisation's round-off (`~10⁻¹⁵ d̄`) and below the saddles seen
    /// (`~−10⁻⁸` with `d̄ = O(1)` for harmonic disks).
    pub threshold: f64,
    /// Trial amplitude that picks the sign of the push: the largest
    /// coordinate change, in units of the smallest body size (`10⁻⁹`: the
    /// energy along the falling sign of the mode of the disks at N = 4096
    /// falls only up to `~10⁻⁶`, where a contact closes).
    pub step: f64,
    /// Amplitude of the first push, in the same units (`10⁻⁴`, module
    /// documentation); it doubles with every push, up to [`MAX_KICK`].
    pub kick: f64,
    /// Initial `ε` of the jamming search after each push.
    pub eps: f64,
    /// Use the true Hessian `∂²V/∂q∂q` (every contact, rattlers kept: their
    /// rows add zero modes, never negative ones) rather than `K + T` of the
    /// non-rattlers. Measured (docs/reports/sanity.md): on rigid dimers the
    /// negative modes of the latter are an artefact of dropping the
    /// contacts of bodies below the rattler threshold that still carry
    /// force; the true Hessian has none there.
    pub full_hessian: bool,
    /// At most this many pushes.
    pub max_rounds: u32,
}

impl Default for SaddleParams {
    fn default() -> Self {
        Self {
            threshold: 1e-10,
            step: 1e-9,
            kick: 1e-4,
            eps: 1e-6,
            max_rounds: 20,
            full_hessian: true,
        }
    }
}

/// What the escape did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SaddleOutcome {
    /// Kicks made (0: the end state of the search is no saddle).
    pub rounds: u32,
    /// Whether the last state checked is still a saddle (the cap was hit).
    pub still_saddle: bool,
    /// Rayleigh quotient of the last mode found relative to `d̄`
    /// (`ρ/d̄ < −threshold`), or 0 when the last state checked is no saddle.
    pub curvature_rel: f64,
    /// The work of the re-run searches.
    pub work: Work,
    /// Final packing fraction.
    pub phi: f64,
    /// Final `V/N`.
    pub energy_per_particle: f64,
}

/// A direction of negative curvature of `h`: `None` when `H + threshold·d̄ I`
/// is positive definite (or the mode found does not curve below
/// `−threshold·d̄`), else the Rayleigh quotient `ρ` of the mode, `d̄` and the
/// mode (unit length, in `h`'s rows), as the module documentation
/// describes.
pub fn negative_mode(h: &Hessian, threshold: f64) -> Result<Option<(f64, f64, Vec<f64>)>> {
    negative_curvature(h.size, &h.entries, threshold)
}

/// [`negative_mode`] of the symmetric `n × n` matrix with these entries
/// (`(row, column, value)`, both triangles, repeated pairs adding): the
/// Hessian of a scene, or of an objective in its flat coordinates (the
/// Newton finish's plateau escape, [`crate::newton`]).
pub fn negative_curvature(
    n: usize,
    entries: &[(u32, u32, f64)],
    threshold: f64,
) -> Result<Option<(f64, f64, Vec<f64>)>> {
    if n == 0 {
        return Ok(None);
    }
    let mut diag = Vec::new();
    let Some(mean) = mean_positive_diagonal(n, entries, &mut diag) else {
        return Ok(None);
    };
    let mu = threshold * mean;
    let mut upper = Vec::new();
    upper_triplets(entries, &mut upper);
    let factor = |shift: f64| {
        let mut t = upper.clone();
        t.extend((0..n).map(|a| Triplet::new(a, a, shift)));
        sparse_cholesky(n, &t)
    };
    if factor(mu).is_some() {
        return Ok(None);
    }
    // Every eigenvalue is at least −(largest absolute row sum), so a shift
    // beyond it factorises: the doubling ends.
    let mut row_sum = vec![0.0; n];
    for &(r, _, v) in entries {
        row_sum[r as usize] += v.abs();
    }
    let bound = row_sum.iter().fold(0.0f64, |m, &s| m.max(s));
    let mut shift = 2.0 * mu;
    let llt = loop {
        if let Some(llt) = factor(shift) {
            break llt;
        }
        if shift > 2.0 * bound {
            return Err(Error::Unsupported(format!(
                "saddle check: the Hessian does not factorise at the shift {shift:e} beyond its row sums {bound:e}"
            )));
        }
        shift *= 2.0;
    };
    // A fixed start vector (splitmix64 of the row): the same bits on every
    // machine, with a component along every mode.
    let mut v = Mat::<f64>::from_fn(n, 1, |a, _| {
        let mut z = (a as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let mut rho = f64::INFINITY;
    let mut x = vec![0.0; n];
    let mut hx = vec![0.0; n];
    for _ in 0..MAX_ITERATIONS {
        llt.solve_in_place(v.as_mut());
        let norm = (0..n).map(|a| v[(a, 0)] * v[(a, 0)]).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Ok(None);
        }
        for (a, xa) in x.iter_mut().enumerate() {
            *xa = v[(a, 0)] / norm;
            v[(a, 0)] = *xa;
        }
        hx.fill(0.0);
        for &(r, c, value) in entries {
            hx[r as usize] += value * x[c as usize];
        }
        let next: f64 = x.iter().zip(&hx).map(|(a, b)| a * b).sum();
        let settled = (next - rho).abs() <= RAYLEIGH_TOL * next.abs();
        rho = next;
        if settled {
            break;
        }
    }
    Ok((rho < -mu).then_some((rho, mean, x)))
}

/// A direction of negative curvature of the scene's Hessian (see
/// [`negative_mode`]), spread back to the scene's flat coordinates (zero on
/// removed rattlers): `(ρ/d̄, mode)`.
fn scene_mode<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattlers: &mut impl FnMut(&mut Scene<D, S>) -> Vec<bool>,
    params: &SaddleParams,
) -> Result<Option<(f64, Vec<f64>)>> {
    let rattler = if params.full_hessian {
        Vec::new()
    } else {
        rattlers(scene)
    };
    let h = Hessian::of_scene(
        scene,
        &rattler,
        HessianOptions {
            stiffness_only: false,
            remove_rattlers: true,
        },
    )?;
    let Some((rho, mean, mode)) = negative_mode(&h, params.threshold)? else {
        return Ok(None);
    };
    let mut flat = vec![0.0; scene.dof()];
    let stride = scene.dof() / scene.bodies();
    // Rows come body by body, `stride` coordinates each, in FIRE's order.
    for (row, x) in mode.into_iter().enumerate() {
        flat[h.body[row] as usize * stride + row % stride] = x;
    }
    Ok(Some((rho / mean, flat)))
}

/// Push `scene` off saddles of its Hessian and re-jam, as described in the
/// module documentation; `rattlers` marks the rattlers of a scene (asked
/// only without [`SaddleParams::full_hessian`]).
pub fn escape_saddles<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    fire: &mut Fire,
    jam_params: &JamParams,
    params: &SaddleParams,
    mut rattlers: impl FnMut(&mut Scene<D, S>) -> Vec<bool>,
) -> Result<SaddleOutcome> {
    let mut out = SaddleOutcome {
        phi: scene.phi(),
        energy_per_particle: scene.energy() / scene.bodies() as f64,
        ..SaddleOutcome::default()
    };
    let size = scene
        .packing()
        .sizes
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let rejam = JamParams {
        eps: params.eps,
        ..jam_params.clone()
    };
    loop {
        let found = scene_mode(scene, &mut rattlers, params)?;
        out.still_saddle = found.is_some();
        out.curvature_rel = found.as_ref().map_or(0.0, |f| f.0);
        let Some((_, mode)) = found else {
            return Ok(out);
        };
        if out.rounds >= params.max_rounds {
            return Ok(out);
        }
        let biggest = mode.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let unit: Vec<f64> = mode.iter().map(|x| x * size / biggest).collect();
        let kick = (params.kick * 2f64.powi(out.rounds.min(30) as i32)).min(MAX_KICK);
        push(scene, &unit, params.step, kick);
        let o = jam(scene, fire, &rejam)?;
        out.rounds += 1;
        out.work += o.work;
        out.phi = o.phi;
        out.energy_per_particle = o.energy_per_particle;
    }
}

/// Move `scene` by `kick · unit` (largest component = `kick` × the
/// smallest body size) along the sign whose trial amplitude `step` gives
/// the lower energy. Deterministic: the trials start from the saved
/// configuration and their order is fixed.
fn push<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>, unit: &[f64], step: f64, kick: f64) {
    scene.save();
    let mut trial = |amp: f64| {
        scene.restore();
        let dq: Vec<f64> = unit.iter().map(|x| x * amp).collect();
        scene.displace(&dq);
        scene.energy()
    };
    let sign = if trial(-step) < trial(step) {
        -1.0
    } else {
        1.0
    };
    scene.restore();
    let dq: Vec<f64> = unit.iter().map(|x| x * sign * kick).collect();
    scene.displace(&dq);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FireParams;
    use jamkit_core::{Packing, PeriodicBox, Potential, Vector};
    use jamkit_sphere::Sphere;

    /// 16 equal disks (radius 1/2) on a square lattice of spacing 0.99 in a
    /// periodic box: every contact overlaps by 0.01 and the forces cancel
    /// by symmetry, but the compressed contacts' prestress makes shearing
    /// neighbouring rows or columns against each other lower the energy,
    /// `λ = 4 h / r = −0.0404` for the alternating shear (an unstable
    /// equilibrium, the Hessian's lowest eigenvalue).
    fn square_lattice() -> Scene<2, Sphere> {
        let a = 0.99;
        let positions = (0..16)
            .map(|k| Vector::<2>::new(a * (k % 4) as f64 + 0.3, a * (k / 4) as f64 + 0.2))
            .collect();
        let packing = Packing {
            shape: Sphere,
            bbox: PeriodicBox::<2>::cubic(4.0 * a),
            positions,
            orientations: vec![(); 16],
            sizes: vec![0.5; 16],
        };
        Scene::new(packing, Potential::Harmonic, 0.2)
    }

    fn hessian(scene: &mut Scene<2, Sphere>) -> Hessian {
        Hessian::of_scene(scene, &[], HessianOptions::default()).unwrap()
    }

    /// The sum of the positive diagonal entries of the dense `H` over its
    /// size (the tests' scale of `H`).
    fn mean_diagonal(h: &Hessian) -> f64 {
        let d = h.dense();
        (0..h.size)
            .map(|a| d[(a, a)])
            .filter(|&x| x > 0.0)
            .sum::<f64>()
            / h.size as f64
    }

    fn lowest_dense(h: &Hessian) -> f64 {
        let evd = h.dense().self_adjoint_eigen(faer::Side::Lower).unwrap();
        evd.S()[0]
    }

    /// The check finds the lattice's negative mode: its Rayleigh quotient is
    /// the lowest eigenvalue of the dense solve (4h/r = −0.0404 analytically)
    /// to 10⁻⁵ relative (the iteration stops when the quotient changes by
    /// less than 10⁻⁶ between iterations, and with the shift's bracket it
    /// converges by at least 0.67² per iteration), and the mode has unit
    /// length and `xᵀHx = ρ`.
    #[test]
    fn the_check_finds_the_negative_mode_of_a_compressed_square_lattice() {
        let mut scene = square_lattice();
        let h = hessian(&mut scene);
        let lowest = lowest_dense(&h);
        assert!((lowest - 4.0 * -0.01 / 0.99).abs() < 1e-9, "{lowest}");
        let (rho, mean, x) = negative_mode(&h, 1e-10).unwrap().expect("a saddle");
        assert!(
            (rho - lowest).abs() < 1e-5 * lowest.abs(),
            "{rho} against {lowest}"
        );
        assert!(mean > 1.0 && mean < 3.0, "{mean}");
        let norm: f64 = x.iter().map(|a| a * a).sum();
        assert!((norm - 1.0).abs() < 1e-12, "{norm}");
        let hx = h.apply(&x);
        let quotient: f64 = x.iter().zip(&hx).map(|(a, b)| a * b).sum();
        assert!((quotient - rho).abs() < 1e-12, "{quotient} {rho}");
    }

    /// [`escape_saddles`] with the default settings and no rattlers.
    fn escape(scene: &mut Scene<2, Sphere>, fire: &mut Fire, params: &JamParams) -> SaddleOutcome {
        escape_saddles(scene, fire, params, &SaddleParams::default(), |_| {
            Vec::new()
        })
        .unwrap()
    }

    /// The escape pushes the lattice off its saddle and re-jams: at least one
    /// push, the end state in the window and with no eigenvalue below
    /// `−10⁻¹⁰ d̄` (checked by the dense solve, independent of the
    /// factorisation).
    #[test]
    fn the_escape_leaves_the_lattice_saddle_for_a_jammed_minimum() {
        let mut scene = square_lattice();
        let mut fire = Fire::new(FireParams::default());
        let params = JamParams::default();
        let out = escape(&mut scene, &mut fire, &params);
        assert!(out.rounds >= 1 && !out.still_saddle, "{out:?}");
        let e = scene.energy() / 16.0;
        assert!(e > params.energy_low && e < params.energy_high, "{e}");
        assert_eq!(out.energy_per_particle, e);
        let h = hessian(&mut scene);
        let mean = mean_diagonal(&h);
        let lowest = lowest_dense(&h);
        assert!(lowest > -1e-10 * mean, "{lowest} (mean diagonal {mean})");
    }

    /// On jammed binary disks that are minima (the dense solve's lowest
    /// eigenvalue is not below `−10⁻¹⁰ d̄`), the escape makes no push and
    /// leaves every coordinate as the search left it, bit for bit.
    #[test]
    fn the_escape_leaves_a_jammed_minimum_untouched() {
        let mut scene = crate::random_disks(32, 0.1, 3);
        let mut fire = Fire::new(FireParams::default());
        let params = JamParams::default();
        jam(&mut scene, &mut fire, &params).unwrap();
        let h = hessian(&mut scene);
        let mean = mean_diagonal(&h);
        let lowest = lowest_dense(&h);
        assert!(lowest > -1e-10 * mean, "seed 3 is a saddle: {lowest}");
        assert!(negative_mode(&h, 1e-10).unwrap().is_none());
        let before = scene.packing().positions.clone();
        let out = escape(&mut scene, &mut fire, &params);
        assert_eq!((out.rounds, out.still_saddle), (0, false));
        assert_eq!(scene.packing().positions, before);
    }
}
