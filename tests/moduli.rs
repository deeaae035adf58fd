//! Elastic moduli (docs/reports/elasticity.md): the strain derivatives of the energy and the
//! stress tensor against finite differences for every family with a
//! Hessian, and the linear-response moduli against a deformation of the
//! cell relaxed by the engine's minimiser.

use jamkit_core::{Matrix, Packing, Potential, Shape, SizeDistribution};
use jamkit_ellipse::{Ellipse, EllipseParams};
use jamkit_ellipsoid::Ellipsoid;
use jamkit_engine::{Fire, Objective, Scene};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_harmonic::{Harmonic, HarmonicParams};
use jamkit_nmer::{Nmer, NmerParams};
use jamkit_observe::hessian::{Hessian, HessianOptions};
use jamkit_observe::moduli::{
    self, CellContacts, ModuliParams, ModuliSolver, Strained, by_deformation,
    deformation_minimizer, shear_planes, simple_shear, strain_derivatives, stress_tensor,
};
use jamkit_observe::{RattlerRule, summarize_with};
use jamkit_sphere::Sphere;
use rand::SeedableRng;

/// The runner's composition: the engine's shear stabilisation with the
/// linear-response stiffness, rattlers below `threshold` contacts.
fn stabilise<const D: usize, S: Shape<D>>(
    scene: &Scene<D, S>,
    threshold: usize,
    ensemble: moduli::Ensemble,
    params: &moduli::StabiliseParams,
    fire: &jamkit_engine::FireParams,
) -> jamkit_core::Result<moduli::Stabilised<D, S>> {
    jamkit_engine::stabilise::stabilise(
        scene,
        ensemble,
        params,
        fire,
        moduli::cell_stiffness(threshold, &params.moduli),
    )
}

use crate::common;

fn near_disk(n: u32, delta: f64) -> NearDisk {
    NearDisk::fourier(&FourierParams {
        n,
        delta,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap()
}

fn ellipse(aspect: f64) -> Ellipse {
    Ellipse::new(&EllipseParams {
        aspect,
        inertia: None,
    })
    .unwrap()
}

fn dimer<const D: usize>(alpha: f64) -> Nmer<D> {
    Nmer::<D>::new(&NmerParams {
        alpha: Some(alpha),
        spheres: None,
        inertia: None,
    })
    .unwrap()
}

/// The strains checked: every simple shear, its transpose (`a > b`), the
/// isotropic dilation and a generic `E` with every entry set.
/// The paper's 3D near-sphere: one zonal mode l = 2, m = 0, first-order
/// gap (`experiments/elasticity/above_jam_3d.ron`).
fn near_sphere(delta: f64) -> Harmonic {
    Harmonic::new(&HarmonicParams {
        l: Some(2),
        m: Some(0),
        modes: None,
        delta,
        inertia: None,
        gap: Default::default(),
        exact_solver: Default::default(),
    })
    .unwrap()
}

fn strains<const D: usize>() -> Vec<Matrix<D>> {
    let mut out = Vec::new();
    for (a, b) in shear_planes::<D>() {
        out.push(simple_shear::<D>(a, b));
        out.push(simple_shear::<D>(b, a));
    }
    out.push(Matrix::<D>::identity());
    out.push(Matrix::<D>::from_fn(|a, b| {
        0.3 + 0.7 * a as f64 - 0.45 * b as f64
    }));
    out
}

/// Central differences of the strained cell against the analytic strain
/// derivatives, on a dense random configuration (φ = 0.9, most pairs
/// overlap, so both the `v''` and the `v'` terms are large):
///
/// * `∂U/∂γ` ([`Strained::strain_derivative`] and `U_γ` of
///   [`strain_derivatives`]) against `(U(δ) − U(−δ))/2δ`;
/// * `A = ∂²U/∂γ²` against the central difference of `∂U/∂γ`;
/// * `Ξ = ∂²U/∂γ∂q` against the central difference of the gradient.
///
/// δ = 1e-6: truncation ~δ² U''' ~ 1e-12, round-off ~1e-16 U/δ ~ 1e-10
/// for `U` and its derivatives of order one; so 1e-6 of the largest entry
/// leaves four orders of margin and still catches a wrong term or factor
/// (the `v'` terms alone are ~0.1 of the entries here).
fn check_strain_derivatives<const D: usize, S: Shape<D>>(shape: S, n: usize, seed: u64) {
    let name = format!("{} D = {D}", shape.family());
    let mut scene = jamkit_kit::dense(shape, n, seed);
    let hessian = Hessian::of_scene(&mut scene, &[], HessianOptions::default()).unwrap();
    let base = Strained::new(&scene, 0.05).unwrap();
    let dof = scene.dof();
    // The strained cell at F = I is the scene: same energy and gradient.
    let (mut g_scene, mut g_cell) = (vec![0.0; dof], vec![0.0; dof]);
    let u_scene = scene.energy_gradient(&mut g_scene);
    let u_cell = base.energy_and_gradient(&mut g_cell);
    assert!(u_scene > 0.1, "{name}: the configuration should overlap");
    assert!((u_scene - u_cell).abs() < 1e-12 * u_scene, "{name}: energy");
    for (a, b) in g_scene.iter().zip(&g_cell) {
        assert!((a - b).abs() < 1e-12 * u_scene, "{name}: gradient {a} {b}");
    }
    let step = 1e-6;
    let at = |gamma: f64, e: &Matrix<D>| {
        let mut s = base.clone();
        s.set_strain(gamma, e);
        let mut g = vec![0.0; dof];
        let u = s.energy_and_gradient(&mut g);
        (u, s.strain_derivative(e), g)
    };
    for e in strains::<D>() {
        let d = strain_derivatives(&mut scene, &[], &hessian, &e).unwrap();
        let (up, dp, gp) = at(step, &e);
        let (um, dm, gm) = at(-step, &e);
        let scale = d.first.abs().max(d.affine.abs()).max(1.0);
        let fd_first = (up - um) / (2.0 * step);
        assert!(
            (fd_first - d.first).abs() < 1e-6 * scale,
            "{name} E = {e}: U_γ {} vs FD {fd_first}",
            d.first
        );
        assert!(
            (base.strain_derivative(&e) - d.first).abs() < 1e-10 * scale,
            "{name}: strained cell's U_γ"
        );
        let fd_affine = (dp - dm) / (2.0 * step);
        assert!(
            (fd_affine - d.affine).abs() < 1e-6 * scale,
            "{name} E = {e}: A {} vs FD {fd_affine}",
            d.affine
        );
        let xi_scale = d.xi.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (row, &x) in d.xi.iter().enumerate() {
            let fd = (gp[row] - gm[row]) / (2.0 * step);
            assert!(
                (fd - x).abs() < 1e-6 * xi_scale,
                "{name} E = {e}: Ξ[{row}] = {x} vs FD {fd}"
            );
        }
        // Ξ is a force field with no net force (a gap depends on r_j − r_i).
        for a in 0..D {
            let net: f64 = d.xi.chunks(hessian.size / n).map(|b| b[a]).sum();
            assert!(net.abs() < 1e-10 * xi_scale, "{name}: net Ξ {net}");
        }
    }
}

#[test]
fn strain_derivatives_match_finite_differences_for_every_family() {
    check_strain_derivatives::<2, _>(Sphere, 24, 1);
    check_strain_derivatives::<3, _>(Sphere, 64, 2);
    check_strain_derivatives::<2, _>(near_disk(2, 0.1), 24, 3);
    check_strain_derivatives::<2, _>(near_disk(3, 0.05), 24, 4);
    check_strain_derivatives::<2, _>(ellipse(1.5), 24, 5);
    check_strain_derivatives::<2, _>(dimer::<2>(1.5), 16, 6);
    check_strain_derivatives::<3, _>(dimer::<3>(1.5), 64, 7);
    check_strain_derivatives::<3, _>(near_sphere(0.1), 64, 9);
    check_strain_derivatives::<3, _>(Ellipsoid::spheroid(1.5).unwrap(), 96, 10);
    check_strain_derivatives::<3, _>(Ellipsoid::spheroid(1.0 / 1.3).unwrap(), 96, 18);
    let lobed = jamkit_lobed::lobed(&jamkit_lobed::LobedParams {
        delta: 0.15,
        kappa: 2.0,
        inertia: None,
    })
    .unwrap();
    check_strain_derivatives::<2, _>(lobed, 24, 8);
}

/// The stress tensor `σ_ab = (1/V) Σ v' g_a r_b` is `(1/V) ∂U/∂γ` of the
/// simple shear `E = e_a e_bᵀ` (diagonal: uniaxial stretch), by central
/// differences of the energy (tolerance as above), and its trace gives the
/// engine's virial pressure to round-off (1e-12 relative).
fn check_stress<const D: usize, S: Shape<D>>(shape: S, n: usize, seed: u64) {
    let name = format!("{} D = {D}", shape.family());
    let mut scene = jamkit_kit::dense(shape, n, seed);
    let sigma = stress_tensor(&mut scene);
    let volume = scene.packing().bbox.volume();
    let base = Strained::new(&scene, 0.05).unwrap();
    let step = 1e-6;
    let scale = sigma.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 0.01, "{name}: the configuration should be stressed");
    for a in 0..D {
        for b in 0..D {
            let e = simple_shear::<D>(a, b);
            let energy = |gamma: f64| {
                let mut s = base.clone();
                s.set_strain(gamma, &e);
                let mut g = vec![0.0; scene.dof()];
                s.energy_and_gradient(&mut g)
            };
            let fd = (energy(step) - energy(-step)) / (2.0 * step * volume);
            assert!(
                (fd - sigma[(a, b)]).abs() < 1e-6 * scale,
                "{name}: σ[{a}{b}] = {} vs FD {fd}",
                sigma[(a, b)]
            );
        }
    }
    let p = scene.pressure();
    assert!(
        (-sigma.trace() / D as f64 - p).abs() < 1e-12 * p.abs(),
        "{name}: −tr σ / D vs pressure {p}"
    );
    assert!(
        (base.pressure() - p).abs() < 1e-12 * p.abs(),
        "{name}: strained cell's pressure"
    );
}

#[test]
fn stress_tensor_matches_finite_differences_for_every_family() {
    check_stress::<2, _>(Sphere, 24, 11);
    check_stress::<3, _>(Sphere, 64, 12);
    check_stress::<2, _>(near_disk(2, 0.1), 24, 13);
    check_stress::<2, _>(ellipse(2.0), 24, 14);
    check_stress::<2, _>(dimer::<2>(1.5), 16, 15);
    check_stress::<3, _>(dimer::<3>(1.5), 64, 16);
    check_stress::<3, _>(near_sphere(0.1), 64, 17);
    check_stress::<3, _>(Ellipsoid::spheroid(1.5).unwrap(), 96, 19);
}

/// The isotropic `∂U/∂γ` against the engine's own box: rescaling the
/// scene's box and centres by `1 + γ` (`Scene::set_phi`, independent of
/// [`Strained`]) changes the energy at the rate `U_γ = Σ v' g·r = −D V p`.
/// δ = 1e-6 as above; `set_phi` goes through φ, which costs a relative
/// 1e-16/δ ~ 1e-10 of round-off in γ, so 1e-6 still has margin.
#[test]
fn isotropic_strain_derivative_matches_the_engine_box() {
    let mut scene = jamkit_kit::dense(near_disk(2, 0.1), 24, 21);
    let hessian = Hessian::of_scene(&mut scene, &[], HessianOptions::default()).unwrap();
    let d = strain_derivatives(&mut scene, &[], &hessian, &Matrix::<2>::identity()).unwrap();
    let phi = scene.phi();
    let step = 1e-6;
    let energy = |gamma: f64| {
        let mut s = scene.clone();
        s.set_phi(phi / (1.0f64 + gamma).powi(2));
        s.energy()
    };
    let fd = (energy(step) - energy(-step)) / (2.0 * step);
    assert!(
        (fd - d.first).abs() < 1e-6 * d.first.abs(),
        "U_γ {} vs FD {fd}",
        d.first
    );
    let p = scene.pressure();
    let v = scene.packing().bbox.volume();
    assert!((d.first + 2.0 * v * p).abs() < 1e-12 * d.first.abs());
}

/// `n` bodies compressed affinely from φ = 0.1 to `phi` (above jamming)
/// and relaxed with the deformation check's minimiser.
fn relaxed<const D: usize, S: Shape<D>>(shape: S, n: usize, seed: u64, phi: f64) -> Scene<D, S> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(n, &mut rng);
    let mut packing = Packing::<D, S>::random(shape, sizes, 0.1, &mut rng).unwrap();
    packing.set_phi(phi);
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.2);
    let fire = deformation_minimizer().for_family(&scene.packing().shape);
    Fire::new(fire).minimize(&mut scene).unwrap();
    scene
}

/// Linear response against deformation. Both measure the same derivative,
/// `dσ_ab/dγ` (and `−(1/D) dp/dγ`), so they differ by the strain's
/// nonlinearity (central differences: `O(γ²)` relative, unless a contact
/// opens or closes within ±γ) and by the residual force of the
/// relaxations (`max g² < 10⁻²⁶`: forces ≲ 10⁻¹³, displacements ≲
/// 10⁻¹³/λ_min, a stress error ≲ 10⁻¹³ and ≲ 10⁻⁷ relative after the
/// division by 2γ = 2·10⁻⁶). `tol` = 10⁻⁶ is the allowed relative
/// difference; measured: 10⁻¹¹ … 10⁻⁸ (docs/reports/elasticity.md). The rattler
/// rule is the experiments' (`Rank` for bodies made of spheres).
fn check_against_deformation<const D: usize, S: Shape<D>>(
    mut scene: Scene<D, S>,
    rule: RattlerRule,
    gamma: f64,
    tol: f64,
) -> (moduli::Moduli, moduli::Deformation) {
    let name = format!("{} D = {D}", scene.packing().shape.family());
    let summary = summarize_with(&mut scene, rule);
    let lr = moduli::measure(&mut scene, &summary.rattler, &ModuliParams::default()).unwrap();
    let def = by_deformation(&scene, gamma, 0.05, &deformation_minimizer()).unwrap();
    assert_eq!(lr.negative_modes, 0, "{name}: {lr:?}");
    // Zero modes besides the translations may remain (a 2D dimer held on
    // one of its spheres turns freely about it), but no strain may load
    // them: then `H⁺` would leave out a floppy response.
    assert!(lr.zero_modes.extra >= 0, "{name}: {lr:?}");
    assert!(lr.floppy_share < 1e-12, "{name}: {lr:?}");
    assert!(
        (lr.pressure - def.pressure).abs() < 1e-9 * lr.pressure,
        "{name}: pressures {} {}",
        lr.pressure,
        def.pressure
    );
    for (k, (l, d)) in lr.shear_planes.iter().zip(&def.shear_planes).enumerate() {
        assert!(*l > 0.0 && l.is_finite(), "{name}: G plane {k} = {l}");
        assert!(
            (l - d).abs() < tol * l,
            "{name}: G plane {k}: linear response {l} vs deformation {d}"
        );
    }
    assert!(
        (lr.bulk - def.bulk).abs() < tol * lr.bulk,
        "{name}: B linear response {} vs deformation {}",
        lr.bulk,
        def.bulk
    );
    assert!(lr.shear < lr.shear_affine && lr.bulk < lr.bulk_affine);
    (lr, def)
}

/// Disks over the strains γ = 10⁻⁷ … 10⁻⁵. At 10⁻⁷ the
/// relaxations' residual stress (~10⁻¹³) is 10⁻⁶ of `2γG`, so the bound is
/// 10⁻⁵ there; at 10⁻⁵ the `O(γ²)` nonlinearity is still ≪ 10⁻⁶.
#[test]
fn disk_moduli_agree_with_deformation() {
    for (gamma, tol) in [(1e-7, 1e-5), (1e-6, 1e-6), (1e-5, 1e-6)] {
        let scene = relaxed::<2, _>(Sphere, 32, 1, 0.88);
        let (lr, def) = check_against_deformation(scene, RattlerRule::Count(3), gamma, tol);
        eprintln!("disks γ = {gamma:e}: {lr:?}\n{def:?}");
    }
}

#[test]
fn sphere_moduli_agree_with_deformation_3d() {
    let (lr, def) = check_against_deformation(
        relaxed::<3, _>(Sphere, 64, 2, 0.70),
        RattlerRule::Count(4),
        1e-6,
        1e-6,
    );
    eprintln!("spheres: {lr:?}\n{def:?}");
}

/// The 3D near-spheres of the 3D runs (l = 2, m = 0, Δ = 0.1, two
/// rotational coordinates per body).
#[test]
fn near_sphere_moduli_agree_with_deformation_3d() {
    let (lr, def) = check_against_deformation(
        relaxed::<3, _>(near_sphere(0.1), 64, 6, 0.72),
        RattlerRule::Count(4),
        1e-6,
        1e-6,
    );
    eprintln!("near-spheres: {lr:?}\n{def:?}");
}

#[test]
fn near_disk_moduli_agree_with_deformation() {
    let scene = relaxed::<2, _>(near_disk(2, 0.1), 32, 3, 0.90);
    let (lr, def) = check_against_deformation(scene, RattlerRule::Count(3), 1e-6, 1e-6);
    eprintln!("near-disks: {lr:?}\n{def:?}");
}

#[test]
fn ellipse_and_dimer_moduli_agree_with_deformation() {
    let (lr, def) = check_against_deformation(
        relaxed::<2, _>(ellipse(1.5), 32, 4, 0.90),
        RattlerRule::Count(3),
        1e-6,
        1e-6,
    );
    eprintln!("ellipses: {lr:?}\n{def:?}");
    let (lr, def) = check_against_deformation(
        relaxed::<2, _>(dimer::<2>(1.5), 32, 5, 0.90),
        RattlerRule::Rank,
        1e-6,
        1e-6,
    );
    eprintln!("dimers: {lr:?}\n{def:?}");
}

/// The sparse path (`solver: Sparse`: one body's translations pinned,
/// sparse Cholesky, Lanczos for the softest mode) against the dense
/// eigendecomposition on the same packing. Both compute `A − Ξᵀ H⁺ Ξ`
/// in double precision; the dense one sums `(u·Ξ)²/λ` over modes, the
/// sparse one `Ξ·x` with `H x = Ξ`, and both are backward stable, so they
/// differ by round-off amplified by the condition number on the
/// non-affine term: `~ε λ_max/λ_min ≈ 10⁻¹⁶ · 10⁴…10⁶` here, and the
/// non-affine term is at most a few times `G`. `1e-8` relative (of the
/// affine part, which bounds both terms' size) leaves two orders of
/// margin and still catches a mode left out or counted twice (a share
/// ≥ 10⁻³ of the non-affine term on these packings). `soft_share` is a
/// ratio of one mode's term, from the Lanczos eigenvector (residual
/// 10⁻⁹ relative): `1e-6` absolute. The zero-mode counts must be equal.
/// When the sparse path falls back (a 2D dimer's free rotation about one
/// of its spheres is a zero mode besides the translations), its result
/// must be the dense one, bit for bit, with the reason given.
fn check_sparse_against_dense<const D: usize, S: Shape<D>>(
    mut scene: Scene<D, S>,
    rule: RattlerRule,
) -> moduli::Moduli {
    let name = format!("{} D = {D}", scene.packing().shape.family());
    let summary = summarize_with(&mut scene, rule);
    let dense_params = ModuliParams {
        solver: ModuliSolver::Dense,
        ..Default::default()
    };
    let dense = moduli::measure(&mut scene, &summary.rattler, &dense_params).unwrap();
    let params = ModuliParams {
        solver: ModuliSolver::Sparse,
        ..Default::default()
    };
    let sparse = moduli::measure(&mut scene, &summary.rattler, &params).unwrap();
    let rattlers = summary.rattler.iter().filter(|&&r| r).count();
    eprintln!("{name} ({rattlers} rattlers):\n dense  {dense:?}\n sparse {sparse:?}");
    assert_eq!(dense.dense_fallback, None);
    if let Some(reason) = &sparse.dense_fallback {
        assert!(!reason.is_empty());
        let fallback = moduli::Moduli {
            dense_fallback: None,
            ..sparse.clone()
        };
        assert_eq!(fallback, dense, "{name}: a fallback is the dense path");
        return sparse;
    }
    let close = |a: f64, b: f64, scale: f64, what: &str| {
        assert!(
            (a - b).abs() <= 1e-8 * scale.abs(),
            "{name}: {what}: sparse {a} dense {b} (scale {scale})"
        );
    };
    for (k, (s, d)) in sparse
        .shear_planes
        .iter()
        .zip(&dense.shear_planes)
        .enumerate()
    {
        close(*s, *d, dense.shear_affine, &format!("G plane {k}"));
    }
    close(sparse.shear, dense.shear, dense.shear_affine, "G");
    close(sparse.bulk, dense.bulk, dense.bulk_affine, "B");
    assert_eq!(sparse.shear_affine, dense.shear_affine);
    assert_eq!(sparse.bulk_affine, dense.bulk_affine);
    assert_eq!(sparse.pressure, dense.pressure);
    assert_eq!(sparse.coordinates, dense.coordinates);
    assert_eq!(sparse.zero_modes, dense.zero_modes, "{name}");
    assert_eq!(sparse.negative_modes, dense.negative_modes, "{name}");
    // Ξ is orthogonal to the translations: its share on them is round-off
    // (both paths), far below the 1e-12 the deformation checks allow.
    assert!(
        sparse.floppy_share < 1e-20,
        "{name}: {}",
        sparse.floppy_share
    );
    assert!(dense.floppy_share < 1e-20, "{name}: {}", dense.floppy_share);
    let (s, d) = (sparse.soft_share.unwrap(), dense.soft_share.unwrap());
    assert!(
        (s - d).abs() < 1e-6,
        "{name}: soft share sparse {s} dense {d}"
    );
    sparse
}

#[test]
fn sparse_moduli_agree_with_dense_for_every_family() {
    let mut compared = 0;
    let mut count = |m: &moduli::Moduli| {
        assert!(m.dense_fallback.is_none(), "{m:?}");
        compared += 1;
    };
    // Disks (with rattlers: 32 bodies at φ = 0.84 leave some).
    let mut scene = relaxed::<2, _>(Sphere, 32, 1, 0.84);
    let rattlers = summarize_with(&mut scene, RattlerRule::Count(3)).rattler;
    assert!(
        rattlers.iter().any(|&r| r),
        "the disk case must have rattlers"
    );
    count(&check_sparse_against_dense(scene, RattlerRule::Count(3)));
    count(&check_sparse_against_dense(
        relaxed::<2, _>(near_disk(2, 0.1), 32, 3, 0.90),
        RattlerRule::Count(3),
    ));
    count(&check_sparse_against_dense(
        relaxed::<2, _>(ellipse(1.5), 32, 4, 0.90),
        RattlerRule::Count(3),
    ));
    count(&check_sparse_against_dense(
        relaxed::<3, _>(Sphere, 64, 2, 0.70),
        RattlerRule::Count(4),
    ));
    count(&check_sparse_against_dense(
        relaxed::<3, _>(near_sphere(0.1), 64, 6, 0.72),
        RattlerRule::Count(4),
    ));
    count(&check_sparse_against_dense(
        relaxed::<3, _>(dimer::<3>(1.5), 48, 7, 0.72),
        RattlerRule::Rank,
    ));
    assert_eq!(compared, 6);
    // 2D dimers: compared, or fallen back to the dense path for a reason.
    let dimers = check_sparse_against_dense(
        relaxed::<2, _>(dimer::<2>(1.5), 32, 5, 0.90),
        RattlerRule::Rank,
    );
    eprintln!("2D dimers: fallback {:?}", dimers.dense_fallback);
}

/// The sparse path falls back to the dense one, and says why: when the
/// Cholesky factorisation fails (the rattlers kept, with their zero rows
/// and floppy modes: `H_r` is singular), and when the softest mode is at
/// the zero-mode threshold (`omega_zero` raised to `(λ_1 λ_2)^{1/4}`: the dense path
/// leaves that mode out of `H⁺`, so the sparse one must not be taken).
#[test]
fn sparse_moduli_fall_back_to_dense_and_say_why() {
    let mut scene = relaxed::<2, _>(Sphere, 32, 1, 0.84);
    let sparse = ModuliParams {
        solver: ModuliSolver::Sparse,
        ..Default::default()
    };
    // No rattler mask: the rattlers' rows stay, with no contact or too few.
    let dense_params = ModuliParams {
        solver: ModuliSolver::Dense,
        ..Default::default()
    };
    let dense = moduli::measure(&mut scene, &[], &dense_params).unwrap();
    let m = moduli::measure(&mut scene, &[], &sparse).unwrap();
    eprintln!("{:?}", m.dense_fallback);
    assert!(dense.zero_modes.extra > 0, "{dense:?}");
    let reason = m.dense_fallback.clone().unwrap();
    assert!(reason.contains("Cholesky"), "{reason}");
    assert_eq!(
        moduli::Moduli {
            dense_fallback: None,
            ..m
        },
        dense
    );
    // The softest mode at the threshold.
    let summary = summarize_with(&mut scene, RattlerRule::Count(3));
    let first = moduli::measure(&mut scene, &summary.rattler, &sparse).unwrap();
    assert_eq!(first.dense_fallback, None);
    let spectrum = spectrum_without_rattlers(&mut scene, &summary.rattler);
    let (lambda_1, lambda_2) = (spectrum.eigenvalues[2], spectrum.eigenvalues[3]);
    assert!(spectrum.eigenvalues[1] < 1e-10 && lambda_1 > 1e-10);
    // Between the two softest modes: the dense path counts λ_1 as zero.
    let omega_zero = (lambda_1 * lambda_2).sqrt().sqrt();
    let mut at = |omega_zero: f64, solver| {
        let params = ModuliParams { omega_zero, solver };
        moduli::measure(&mut scene, &summary.rattler, &params).unwrap()
    };
    let raised = at(omega_zero, ModuliSolver::Sparse);
    let reason = raised.dense_fallback.clone().unwrap();
    assert!(reason.contains("threshold"), "{reason}");
    assert_eq!(raised.zero_modes.total, 3);
    assert_eq!(
        moduli::Moduli {
            dense_fallback: None,
            ..raised
        },
        at(omega_zero, ModuliSolver::Dense)
    );
}

/// The stiffness tensor of the stabilisation's steps
/// ([`moduli::stiffness_tensor`]: the dilation and every deviatoric
/// strain, cross terms included) by the sparse path against the dense
/// one, on disks (with rattlers), near-disks and 3D spheres, to 1e-8 of
/// its largest entry (the tolerance and its reason as in
/// `check_sparse_against_dense`). Then a shear stabilisation at fixed
/// pressure by either path: the sparse one takes no dense step on this
/// stable packing, and both end in the same cell. Their steps differ by
/// the round-off of `C` (~10⁻¹³ relative), and each relaxation stops at
/// `max g² < 10⁻²⁶`, so the deformations may differ by ~10⁻¹³/λ_min; 1e-9
/// absolute on `F` (entries of order one) is far above that and far below
/// the strain steps (≥ 10⁻⁶ here).
#[test]
fn sparse_stiffness_tensor_and_stabilisation_agree_with_dense() {
    fn check<const D: usize, S: Shape<D>>(mut scene: Scene<D, S>, rule: RattlerRule) {
        let name = format!("{} D = {D}", scene.packing().shape.family());
        let summary = summarize_with(&mut scene, rule);
        let mut cell = Strained::new(&scene, 0.1).unwrap();
        let mut basis = moduli::deviatoric_basis::<D>();
        basis.insert(0, Matrix::<D>::identity() / (D as f64).sqrt());
        let p = scene.pressure();
        let tensor = |cell: &mut Strained<D, S>, solver| {
            let params = ModuliParams {
                solver,
                ..Default::default()
            };
            moduli::stiffness_tensor(cell, &summary.rattler, &params, &basis, p).unwrap()
        };
        let (dense, none) = tensor(&mut cell, ModuliSolver::Dense);
        let (sparse, fallback) = tensor(&mut cell, ModuliSolver::Sparse);
        assert_eq!((none, fallback), (None, None), "{name}");
        let scale = dense.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (k, (a, b)) in sparse.iter().zip(&dense).enumerate() {
            for (l, (x, y)) in a.iter().zip(b).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-8 * scale,
                    "{name}: C[{k}][{l}] sparse {x} dense {y}"
                );
            }
        }
        eprintln!("{name}: C = {dense:?}");
    }
    check(relaxed::<2, _>(Sphere, 32, 1, 0.84), RattlerRule::Count(3));
    check(
        relaxed::<2, _>(near_disk(2, 0.1), 32, 3, 0.90),
        RattlerRule::Count(3),
    );
    check(relaxed::<3, _>(Sphere, 64, 2, 0.70), RattlerRule::Count(4));

    let mut scene = negative_g_disks();
    let p = scene.pressure();
    let run = |solver| {
        let params = moduli::StabiliseParams {
            moduli: ModuliParams {
                solver,
                ..Default::default()
            },
            ..Default::default()
        };
        let ensemble = moduli::Ensemble::Pressure(p);
        stabilise(&scene, 3, ensemble, &params, &deformation_minimizer()).unwrap()
    };
    let (dense, sparse) = (run(ModuliSolver::Dense), run(ModuliSolver::Sparse));
    let difference = (dense.deformation - sparse.deformation).abs().max();
    eprintln!(
        "stabilised in {} (dense) and {} (sparse) steps, {} fallbacks; |ΔF| = {difference:e}",
        dense.iterations,
        sparse.iterations,
        sparse.dense_fallbacks.len()
    );
    assert_eq!(dense.dense_fallbacks, []);
    assert_eq!(sparse.dense_fallbacks, []);
    assert_eq!(dense.iterations, sparse.iterations);
    assert!(difference < 1e-9, "{difference:e}");
    assert!(sparse.residual < moduli::StabiliseParams::default().tol);
}

/// The stabilisation counts zero modes with the `Moduli` observable's
/// `omega_zero` (`StabiliseParams::moduli`), not the default. With `λ_zero = 0.9 λ_1` (`λ_1`
/// the softest mode of the fixed box's Hessian, rattlers removed) the
/// dense path still inverts that mode, but the sparse one needs
/// `λ_1 > 2 λ_zero` and so falls back at the first step (and at the next
/// ones while the cell's `λ_1` stays below `2 λ_zero`), each recorded with
/// its step and its reason, and ends in the dense path's cell. With the
/// default threshold the sparse path takes no dense step on this packing
/// (the test above), so the fallbacks could not come from elsewhere.
#[test]
fn stabilisation_takes_the_observables_omega_zero_and_records_its_fallbacks() {
    let mut scene = negative_g_disks();
    let summary = summarize_with(&mut scene, RattlerRule::Count(3));
    let spectrum = spectrum_without_rattlers(&mut scene, &summary.rattler);
    let lambda_1 = spectrum.eigenvalues[2];
    assert!(spectrum.eigenvalues[1] < 1e-10 && lambda_1 > 1e-10);
    let omega_zero = (0.9 * lambda_1).sqrt();
    let p = scene.pressure();
    let run = |solver| {
        let params = moduli::StabiliseParams {
            moduli: ModuliParams { omega_zero, solver },
            ..Default::default()
        };
        let ensemble = moduli::Ensemble::Pressure(p);
        stabilise(&scene, 3, ensemble, &params, &deformation_minimizer()).unwrap()
    };
    let (dense, sparse) = (run(ModuliSolver::Dense), run(ModuliSolver::Sparse));
    assert_eq!(dense.dense_fallbacks, []);
    let steps: Vec<u32> = sparse.dense_fallbacks.iter().map(|(k, _)| *k).collect();
    eprintln!(
        "λ_1 = {lambda_1:e}: fell back at steps {steps:?} of {}",
        sparse.iterations
    );
    // The fixed box falls back by construction; the cell stiffens as it
    // relaxes, so later steps may pass the rule. Steps recorded once each,
    // in order, within the run.
    assert_eq!(steps.first(), Some(&0));
    assert!(steps.windows(2).all(|w| w[0] < w[1]));
    assert!(steps.iter().all(|&k| k <= sparse.iterations));
    for (k, why) in &sparse.dense_fallbacks {
        assert!(why.contains("threshold"), "step {k}: {why}");
    }
    // The same cell as the dense path's, to the tolerance (and its reason)
    // of `sparse_stiffness_tensor_and_stabilisation_agree_with_dense`.
    assert_eq!(sparse.iterations, dense.iterations);
    let difference = (dense.deformation - sparse.deformation).abs().max();
    assert!(difference < 1e-9, "{difference:e}");
    // A threshold that is not positive is named as the observable's.
    let params = moduli::StabiliseParams {
        moduli: ModuliParams {
            omega_zero: -1.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let e = stabilise(
        &scene,
        3,
        moduli::Ensemble::Pressure(p),
        &params,
        &deformation_minimizer(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("observables.Moduli.omega_zero"), "{e}");
}

#[test]
fn bad_inputs_are_named() {
    let scene = jamkit_kit::dense::<2, _>(Sphere, 24, 1);
    let e = Strained::new(&scene, -1.0).unwrap_err().to_string();
    assert!(e.contains("margin"), "{e}");
    let e = by_deformation(&scene, 0.5, 0.05, &deformation_minimizer())
        .unwrap_err()
        .to_string();
    assert!(e.contains("gamma") && e.contains("0.5"), "{e}");
    let e = ModuliParams {
        omega_zero: f64::NAN,
        ..Default::default()
    }
    .validate("observables.Moduli")
    .unwrap_err()
    .to_string();
    assert!(e.contains("observables.Moduli.omega_zero"), "{e}");
}

/// `Moduli()` through the runner: `results.csv` gets `G`, `B` and the
/// diagnostics for every packing of a `Pressure` protocol, finite and
/// with `B` positive and `G` below its affine part; the virial pressure of the
/// moduli agrees with the `Pressure` column (the same sum, 1e-9), which is
/// within the protocol's tolerance of the target; and the packing file
/// keeps them.
#[test]
fn moduli_observable_through_the_runner() {
    let text = r#"(name: "el", family: "sphere", particles: 32, samples: 2, seed: 1,
        protocol: Pressure(pressure: 1e-3, tol: 1e-2),
        observables: [Contacts, Pressure, Moduli()])"#;
    let e = jamkit_experiment::Experiment::from_ron(text, "inline").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&e, dir.path(), 1);
    let text = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let mut rows = 0;
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let num = |name: &str| cells[col(name)].parse::<f64>().unwrap();
        let (g, b) = (num("G"), num("B"));
        // G may be negative: at fixed box shape a small packing can be
        // unstable to shear (Dagois-Bohy et al. 2012); B may not.
        assert!(g.is_finite() && b > 0.0 && b.is_finite(), "{line}");
        assert!(g < num("G_affine") && b < num("B_affine"), "{line}");
        let p = num("pressure");
        assert!((num("moduli_pressure") - p).abs() < 1e-9 * p, "{line}");
        assert!((p - 1e-3).abs() < 1e-2 * 1e-3, "{line}");
        assert_eq!(num("moduli_negative_modes"), 0.0, "{line}");
        rows += 1;
    }
    assert_eq!(rows, 2);
    for f in &report.packings {
        let m = f.measures.moduli.as_ref().expect("moduli stored");
        assert_eq!(m.params, ModuliParams::default());
        assert_eq!(m.moduli.zero_modes.translations, 2);
    }
}

/// A bad option of the observable is refused when the file is read, with
/// the field, the value and what is allowed.
#[test]
fn moduli_observable_options_are_checked() {
    let text = r#"(name: "el", family: "sphere", particles: 32,
        observables: [Moduli(omega_zero: -1.0)])"#;
    let e = jamkit_experiment::Experiment::from_ron(text, "inline")
        .unwrap()
        .validate()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("observables.Moduli.omega_zero") && e.contains("-1") && e.contains("positive"),
        "{e}"
    );
}

/// The full spectrum (rotations included) of `scene` with the rattlers'
/// rows removed, as `Moduli` counts its modes.
fn spectrum_without_rattlers<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rattler: &[bool],
) -> jamkit_observe::spectrum::Spectrum {
    let options = HessianOptions {
        stiffness_only: false,
        remove_rattlers: true,
    };
    jamkit_observe::spectrum::measure(scene, rattler, options, false, &Default::default()).unwrap()
}

/// The packing of the runner test's first sample (disks, N = 32, seed 1,
/// `Pressure` p = 10⁻³ to 1 %), made through the engine: `G < 0` in its
/// fixed box.
fn negative_g_disks() -> Scene<2, Sphere> {
    pressure_disks(1, 1e-3)
}

/// Disks, N = 32, `Pressure` protocol to `pressure` (1 %) from seed `seed`.
fn pressure_disks(seed: u64, pressure: f64) -> Scene<2, Sphere> {
    use jamkit_engine::{FireParams, PressureParams, compress_to_pressure};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = SizeDistribution::default().sample(32, &mut rng);
    let packing = Packing::<2, _>::random(Sphere, sizes, 0.1, &mut rng).unwrap();
    let mut scene = Scene::new(packing, Potential::Harmonic, 0.4 * 0.5);
    let params = PressureParams {
        pressure,
        tol: 1e-2,
        ..PressureParams::default()
    };
    let mut fire = Fire::new(FireParams::default().for_family::<2, _>(&Sphere));
    compress_to_pressure(&mut scene, &mut fire, &params).unwrap();
    scene
}

/// The packing of the runner test's first sample, remade through the
/// engine: disks, N = 32, p = 10⁻³. Its linear-response `G` is negative
/// (with no negative mode of `H`): the packing is stable at fixed box but
/// its shear stress falls under shear, as Dagois-Bohy et al. (PRL 109,
/// 095703, 2012) found for a fraction of small packings near jamming.
/// The deformation check confirms the sign and the value (1e-6 relative).
#[test]
fn negative_shear_modulus_is_confirmed_by_deformation() {
    let mut scene = negative_g_disks();
    let summary = summarize_with(&mut scene, RattlerRule::Count(3));
    let lr = moduli::measure(&mut scene, &summary.rattler, &ModuliParams::default()).unwrap();
    let def = by_deformation(&scene, 1e-6, 0.05, &deformation_minimizer()).unwrap();
    eprintln!("{lr:?}\n{def:?}");
    assert_eq!(lr.negative_modes, 0);
    assert!(lr.shear < 0.0, "{lr:?}");
    assert!(
        (lr.shear - def.shear).abs() < 1e-6 * lr.shear.abs(),
        "{lr:?} {def:?}"
    );
    assert!(
        (lr.bulk - def.bulk).abs() < 1e-6 * lr.bulk,
        "{lr:?} {def:?}"
    );
    // The softest mode's share of the non-affine term, against the
    // modulus with that mode left out of `H⁺` (`omega_zero` raised to
    // between ω_1 and ω_2): `G_without − G` is its term, `G_affine − G` the
    // whole non-affine term (one plane in 2D). Same sums, another path
    // through the code: 1e-9 relative allows the round-off of the
    // differences.
    assert_eq!(lr.shear_min(), lr.shear);
    let spectrum = spectrum_without_rattlers(&mut scene, &summary.rattler);
    let above: Vec<f64> = (spectrum.eigenvalues.iter().copied())
        .filter(|&l| l > 1e-10)
        .collect();
    let omega_zero = (above[0] * above[1]).sqrt().sqrt();
    let without = moduli::measure(
        &mut scene,
        &summary.rattler,
        &ModuliParams {
            omega_zero,
            ..Default::default()
        },
    )
    .unwrap();
    let share = (without.shear - lr.shear) / (lr.shear_affine - lr.shear);
    let soft = lr.soft_share.unwrap();
    eprintln!(
        "λ_1 {} λ_2 {}: soft share {soft}, without it G = {}",
        above[0], above[1], without.shear
    );
    assert!((soft - share).abs() < 1e-9, "{soft} vs {share}");
    assert!(soft > 0.0 && soft <= 1.0, "{soft}");
}

/// `AboveJam(delta_phi: …)`: the jamming search of `Jam` (the same φ_J as
/// a `Jam` run with the same seeds), then a compression to φ_J + δφ: the
/// final φ minus the `Jam` run's φ_J is δφ to 1e-12 (round-off of φ
/// through the box volume), and the
/// packing has a positive pressure and finite moduli with `B > 0`. The
/// jamming point it records (`jam_point`) is the `Jam` run's packing,
/// exactly: the same φ_J, `z_J`, rattlers and isostatic margin; reading
/// its contacts moves no body (the same final positions, bit for bit, as a
/// run that records no contacts); and `results.csv` carries it.
#[test]
fn above_jam_protocol_compresses_from_each_packings_own_jamming_point() {
    let jam = r#"(name: "j", family: "sphere", particles: 32, samples: 2, seed: 4,
        observables: [Contacts, Pressure])"#;
    let above = r#"(name: "a", family: "sphere", particles: 32, samples: 2, seed: 4,
        protocol: AboveJam(delta_phi: 1e-3),
        observables: [Contacts, Pressure, Moduli()])"#;
    let parse = |t: &str| jamkit_experiment::Experiment::from_ron(t, "inline").unwrap();
    let (d1, d2) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let jammed = common::run_ok(&parse(jam), d1.path(), 1);
    let compressed = common::run_ok(&parse(above), d2.path(), 1);
    assert_eq!(jammed.packings.len(), 2);
    for (j, a) in jammed.packings.iter().zip(&compressed.packings) {
        assert_eq!(a.protocol, "above_jam");
        assert!((a.phi - j.phi - 1e-3).abs() < 1e-12, "{} {}", a.phi, j.phi);
        let p = a.measures.pressure.unwrap();
        assert!(p > 1e-4 && p < 1e-1, "p = {p}");
        let m = &a.measures.moduli.as_ref().unwrap().moduli;
        assert!(m.shear.is_finite() && m.bulk > 0.0, "{m:?}");
        assert!((m.pressure - p).abs() < 1e-9 * p);
        let at = a.measures.jam_point.as_ref().expect("AboveJam records φ_J");
        assert_eq!(at.phi, j.phi);
        assert_eq!(at.z, j.measures.z_j);
        assert_eq!(at.n_rattlers, j.measures.n_rattlers);
        assert_eq!(at.iso_margin, j.measures.iso_margin);
        assert!(
            j.measures.jam_point.is_none(),
            "Jam records no second point"
        );
    }
    // Compressed by 10⁻³, the disks gain contacts: z − z_J > 0 on the mean.
    let dz: f64 = compressed
        .packings
        .iter()
        .map(|a| a.measures.z_j.unwrap() - a.measures.jam_point.as_ref().unwrap().z.unwrap())
        .sum();
    assert!(dz > 0.0, "Σ (z − z_J) = {dz}");
    let results = std::fs::read_to_string(d2.path().join("results.csv")).unwrap();
    let head = results.lines().next().unwrap();
    assert!(
        head.ends_with("jam_phi,jam_z,jam_rattlers,jam_iso_margin"),
        "{head}"
    );
    let quiet = r#"(name: "a", family: "sphere", particles: 32, samples: 2, seed: 4,
        protocol: AboveJam(delta_phi: 1e-3), observables: [Pressure])"#;
    let d3 = tempfile::tempdir().unwrap();
    let without = common::run_ok(&parse(quiet), d3.path(), 1);
    for (a, b) in compressed.packings.iter().zip(&without.packings) {
        assert_eq!(a.positions, b.positions);
        assert_eq!(b.measures.jam_point.as_ref().unwrap().z, None);
    }
    let bad = r#"(name: "a", family: "sphere", particles: 32,
        protocol: AboveJam(delta_phi: -1e-3))"#;
    let e = parse(bad).validate().unwrap_err().to_string();
    assert!(
        e.contains("protocol.delta_phi") && e.contains("-0.001"),
        "{e}"
    );
}

/// A compression by δφ can rearrange a barely jammed packing into a state
/// that jams above φ_J + δφ (N = 64 disks, seed 1, δφ = 3·10⁻³: V/N fell
/// to 7·10⁻¹⁷ with no contact left). `AboveJam` then fails that sample,
/// naming what happened, instead of recording an unjammed packing as one
/// δφ above jamming, under `rejams: 0`; δφ = 10⁻³ on the same seed
/// succeeds.
#[test]
fn above_jam_refuses_a_packing_that_unjammed() {
    let text = |dphi: &str| {
        format!(
            r#"(name: "a", family: "sphere", particles: 64, samples: 1, seed: 1,
            protocol: AboveJam(delta_phi: {dphi}, rejams: 0), observables: [Contacts])"#
        )
    };
    let parse = |t: &str| jamkit_experiment::Experiment::from_ron(t, "inline").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_into(&parse(&text("3e-3")), dir.path(), 1);
    assert_eq!(report.failures.len(), 1);
    let message = report.failures[0].to_string();
    assert!(
        message.contains("unjammed while compressed by delta_phi = 3e-3")
            && message.contains("protocol.rejams"),
        "{message}"
    );
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&parse(&text("1e-3")), dir.path(), 1);
    assert!(report.packings[0].measures.energy_per_particle > 1e-10);
}

/// With `rejams` (2 by default), the packing of
/// `above_jam_refuses_a_packing_that_unjammed` is jammed again from where it unjammed and compressed by δφ from its new
/// jamming point: the sample succeeds, its first φ_J (recorded in
/// `jam_point.left`) is bit for bit that of `Jam` on the same seed, the new
/// φ_J lies at least δφ above it (the state at φ_J + δφ had V/N below the
/// window, so its own jamming point is higher; 1e-12 for the round-off of
/// φ from the box), the packing sits δφ above the new one (to 1e-12, as in
/// `protocol_targets_given_as_lists_scan`) with V/N above the window, and
/// `results.csv` counts the re-jams. A packing that goes up at the first
/// try is the same under the default and under `rejams: 0` (φ and V/N bit
/// for bit, the same FIRE steps) and, under `rejams: 0`, writes no `left`
/// and no `rejams` setting, so files of runs made before the field existed
/// are unchanged.
#[test]
fn above_jam_jams_again_a_packing_that_unjammed() {
    let parse = |t: &str| jamkit_experiment::Experiment::from_ron(t, "inline").unwrap();
    let above = |dphi: &str, rejams: &str| {
        parse(&format!(
            r#"(name: "a", family: "sphere", particles: 64, samples: 1, seed: 1,
            protocol: AboveJam(delta_phi: {dphi}{rejams}), observables: [Contacts])"#
        ))
    };
    let jam = parse(
        r#"(name: "a", family: "sphere", particles: 64, samples: 1, seed: 1,
        protocol: Jam(), observables: [Contacts])"#,
    );
    let dir = tempfile::tempdir().unwrap();
    let phi_j = common::run_ok(&jam, dir.path(), 1).packings[0].measures.phi;

    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&above("3e-3", ""), dir.path(), 1);
    let m = &report.packings[0].measures;
    let point = m.jam_point.as_ref().unwrap();
    assert!(
        !point.left.is_empty() && point.left.len() <= 2,
        "{:?}",
        point.left
    );
    assert_eq!(point.left[0].to_bits(), phi_j.to_bits(), "{:?}", point.left);
    for pair in point.left.windows(2) {
        assert!(pair[1] >= pair[0] + 3e-3 - 1e-12, "{:?}", point.left);
    }
    let last = *point.left.last().unwrap();
    assert!(point.phi >= last + 3e-3 - 1e-12, "{} {last}", point.phi);
    assert!(
        (m.phi - point.phi - 3e-3).abs() < 1e-12,
        "{} {}",
        m.phi,
        point.phi
    );
    assert!(m.energy_per_particle > 2e-16, "{}", m.energy_per_particle);
    let results = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    let mut lines = results.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = head.iter().position(|c| *c == "jam_rejams").unwrap();
    assert_eq!(row[column], point.left.len().to_string());

    // Went up at the first try: nothing new in the file or the table.
    let dir = tempfile::tempdir().unwrap();
    let with = common::run_ok(&above("1e-3", ""), dir.path(), 1);
    let with = &with.packings[0].measures;
    assert!(with.jam_point.as_ref().unwrap().left.is_empty());
    let results = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    assert!(!results.lines().next().unwrap().contains("jam_rejams"));
    let dir = tempfile::tempdir().unwrap();
    let without = common::run_ok(&above("1e-3", ", rejams: 0"), dir.path(), 1);
    let without = &without.packings[0].measures;
    assert_eq!(with.phi.to_bits(), without.phi.to_bits());
    assert_eq!(
        with.energy_per_particle.to_bits(),
        without.energy_per_particle.to_bits()
    );
    assert_eq!(with.fire_steps, without.fire_steps);
    let file = std::fs::read_dir(dir.path().join("packings"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    let text = std::fs::read_to_string(file.path()).unwrap();
    assert!(
        !text.contains("rejams") && !text.contains("\"left\""),
        "{text}"
    );
}

/// A list of targets scans, one grid point per value, innermost: `AboveJam`
/// with `delta_phi: [1e-3, 1e-2]` makes two points whose ids end in
/// `_dphi1e-3` and `_dphi1e-2`, each packing δφ above its own φ_J (to
/// 1e-12); a `Pressure` list lands each point within 1 % of its own
/// target (the bisection stops within `tol` = 10⁻³ of it; 1 % leaves room
/// for a final relaxation); a single value keeps the ids it always had; an empty list
/// or a bad value is refused by name.
#[test]
fn protocol_targets_given_as_lists_scan() {
    let parse = |t: &str| jamkit_experiment::Experiment::from_ron(t, "inline").unwrap();
    let above = r#"(name: "a", family: "sphere", particles: 32, samples: 1, seed: 4,
        protocol: AboveJam(delta_phi: [1e-3, 1e-2]), observables: [Contacts, Pressure])"#;
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&parse(above), dir.path(), 1);
    let ids: Vec<&str> = report.packings.iter().map(|f| f.id.as_str()).collect();
    assert_eq!(
        ids,
        ["sphere_d2_N32_dphi1e-3_s4", "sphere_d2_N32_dphi1e-2_s4"]
    );
    for (f, dphi) in report.packings.iter().zip([1e-3, 1e-2]) {
        let jam = f.measures.jam_point.as_ref().unwrap().phi;
        assert!((f.phi - jam - dphi).abs() < 1e-12, "{} {jam} {dphi}", f.phi);
        assert_eq!(f.settings["protocol"]["AboveJam"]["delta_phi"], dphi);
    }
    let pressure = r#"(name: "p", family: "sphere", particles: 32, samples: 1, seed: 4,
        protocol: Pressure(pressure: [1e-3, 1e-2]), observables: [Pressure])"#;
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&parse(pressure), dir.path(), 1);
    assert_eq!(report.packings.len(), 2);
    for (f, p) in report.packings.iter().zip([1e-3, 1e-2]) {
        let got = f.measures.pressure.unwrap();
        assert!((got - p).abs() <= 0.011 * p, "{got} against {p}");
    }
    let single = parse(
        r#"(name: "s", family: "sphere", particles: 32, protocol: AboveJam(delta_phi: 1e-3))"#,
    );
    let points = jamkit_experiment::Plan::new(&single).unwrap().points;
    assert_eq!(points.len(), 1);
    assert_eq!(points[0].label("sphere"), "sphere_d2_N32");
    for (bad, named) in [
        ("AboveJam(delta_phi: [])", "at least one value"),
        ("AboveJam(delta_phi: [1e-3, -1.0])", "protocol.delta_phi"),
        ("Pressure(pressure: [1e-3, 0.0])", "protocol.pressure"),
    ] {
        let e = parse(&format!(
            r#"(name: "b", family: "sphere", particles: 32, protocol: {bad})"#
        ))
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains(named), "{bad}: {e}");
    }
}

/// The shipped 3D experiment (`experiments/elasticity/above_jam_3d.ron`:
/// spheres and near-spheres l = 2, m = 0 at Δ = 0.01 and 0.1, `AboveJam`)
/// at N = 32, one seed and one δφ: every packing is δφ above its own φ_J
/// (1e-12), in 3D, with finite moduli, `B > 0`, the non-affine relaxation
/// lowering both, no negative mode, three translations, and the Hessian's
/// rows `f (N − N_r)` (f = 3 for the spheres, 5 for the axisymmetric
/// near-spheres: two rotational coordinates).
#[test]
fn shipped_3d_above_jam_file_gives_finite_moduli() {
    let report = common::run_file(
        "experiments/elasticity/above_jam_3d.ron",
        &["particles=32", "samples=1", "protocol.delta_phi=1e-2"],
        1,
    );
    assert_eq!(report.packings.len(), 3);
    for f in &report.packings {
        assert_eq!(f.dim, 3, "{}", f.id);
        let jam = f.measures.jam_point.as_ref().expect("AboveJam records φ_J");
        assert!(
            (f.phi - jam.phi - 1e-2).abs() < 1e-12,
            "{}: {} {}",
            f.id,
            f.phi,
            jam.phi
        );
        let m = &f.measures.moduli.as_ref().expect("moduli measured").moduli;
        assert_eq!(m.shear_planes.len(), 3, "{}", f.id);
        assert!(
            m.shear.is_finite() && m.bulk.is_finite() && m.bulk > 0.0,
            "{}: {m:?}",
            f.id
        );
        assert!(
            m.shear < m.shear_affine && m.bulk < m.bulk_affine,
            "{}: {m:?}",
            f.id
        );
        assert_eq!(m.negative_modes, 0, "{}", f.id);
        assert_eq!(m.zero_modes.translations, 3, "{}", f.id);
        let delta = f.params["delta"].as_f64().unwrap();
        let dof = if delta == 0.0 { 3 } else { 5 };
        let bodies = f.particles - f.measures.n_rattlers.unwrap();
        assert_eq!(m.coordinates, dof * bodies, "{}", f.id);
    }
}

/// 3D spheroids (the `ellipsoid` family's exact gap, prolate α = 1.2 and
/// oblate 1/1.2, three rotational coordinates per body) and 3D dimers
/// (α = 1.1, rattlers by rank), as in
/// `experiments/elasticity/above_jam_3d_{ellipsoids,dimers}.ron`. The
/// tolerance is the other families' 10⁻⁶ at γ = 10⁻⁶ (see
/// `check_against_deformation`: nonlinearity `O(γ²)` and residual stress
/// ~10⁻⁷ relative); measured 10⁻¹⁰ … 10⁻⁸ (docs/reports/elasticity.md).
#[test]
fn ellipsoid_and_dimer_moduli_agree_with_deformation_3d() {
    for alpha in [1.2, 1.0 / 1.2] {
        let (lr, def) = check_against_deformation(
            relaxed::<3, _>(Ellipsoid::spheroid(alpha).unwrap(), 48, 7, 0.72),
            RattlerRule::Count(4),
            1e-6,
            1e-6,
        );
        eprintln!("spheroids α = {alpha}: {lr:?}\n{def:?}");
    }
    let (lr, def) = check_against_deformation(
        relaxed::<3, _>(dimer::<3>(1.1), 48, 8, 0.72),
        RattlerRule::Rank,
        1e-6,
        1e-6,
    );
    eprintln!("3D dimers: {lr:?}\n{def:?}");
}

/// Shear stabilisation (Dagois-Bohy et al. 2012) of the fixed-box packing
/// with `G < 0` above, at fixed pressure (its own): the cell's shape and
/// volume relax with the coordinates. After it the deviatoric stress is
/// below the tolerance (10⁻⁶ p) and the pressure is p (10⁻⁶), the
/// enthalpy `U + pV` has not risen (10⁻¹² relative: round-off of the
/// relaxations), the Hessian has no negative mode, and `G ≥ 0` (every
/// plane): at a minimum over all deformations the relaxed enthalpy cannot
/// fall along a simple shear (volume-preserving). The stabilised cell's
/// linear-response moduli agree with its own deformation check (γ =
/// 10⁻⁶, 10⁻⁶ relative as for the fixed box, `check_against_deformation`).
/// At fixed volume this packing unjams (its energy falls to zero, which
/// `stabilise` refuses, naming it); a packing at p = 10⁻² (seed 3)
/// stabilises at fixed volume: `det F = 1` (10⁻¹²), the energy has not
/// risen, and the same checks hold.
#[test]
fn shear_stabilisation_makes_the_negative_g_packing_stable() {
    let params = moduli::StabiliseParams::default();
    let stabilised = |scene: &mut Scene<2, Sphere>, ensemble| {
        let summary = summarize_with(scene, RattlerRule::Count(3));
        let fixed = moduli::measure(scene, &summary.rattler, &ModuliParams::default()).unwrap();
        let s = stabilise(scene, 3, ensemble, &params, &deformation_minimizer());
        (fixed, s)
    };
    let check = |mut s: moduli::Stabilised<2, Sphere>| {
        eprintln!(
            "stabilised in {} steps: F = {:?}, residual {:e} (before {:e}), U {:e} -> {:e}, p {:e} -> {:e}, C_min {:e}",
            s.iterations,
            s.deformation,
            s.residual,
            s.residual_before,
            s.energy_before,
            s.energy_after,
            s.pressure_before,
            s.pressure_after,
            s.stiffness_min
        );
        assert!(s.residual < params.tol, "{}", s.residual);
        assert!(s.residual_before > params.tol, "{}", s.residual_before);
        assert!(s.objective_after <= s.objective_before * (1.0 + 1e-12));
        assert!(s.stiffness_min >= 0.0);
        let lr =
            moduli::measure_strained(&mut s.cell, &s.rattler, &ModuliParams::default()).unwrap();
        eprintln!("stabilised: {lr:?}");
        assert_eq!(lr.negative_modes, 0, "{lr:?}");
        assert!(lr.shear_min() >= 0.0, "{lr:?}");
        assert!((lr.pressure - s.pressure_after).abs() < 1e-9 * lr.pressure);
        let def = moduli::by_deformation_strained(&s.cell, 1e-6, &deformation_minimizer()).unwrap();
        eprintln!("{def:?}");
        for (l, d) in lr.shear_planes.iter().zip(&def.shear_planes) {
            assert!((l - d).abs() < 1e-6 * l, "{lr:?} {def:?}");
        }
        assert!(
            (lr.bulk - def.bulk).abs() < 1e-6 * lr.bulk,
            "{lr:?} {def:?}"
        );
        assert_eq!(lr.zero_modes.extra, 0, "{lr:?}");
        let count = s.cell.contact_count(&s.rattler);
        eprintln!("stabilised cell's contacts: {count:?}");
        assert!(count.iso_margin >= SHEAR_STABLE_MARGIN_2D, "{count:?}");
        s
    };
    let mut scene = negative_g_disks();
    let p = scene.pressure();
    let (fixed, s) = stabilised(&mut scene, moduli::Ensemble::Pressure(p));
    eprintln!("fixed box: {fixed:?}");
    assert!(fixed.shear < 0.0, "{fixed:?}");
    let s = check(s.unwrap());
    assert!((s.pressure_after / p - 1.0).abs() < 1e-6);
    let (_, unjammed) = stabilised(&mut scene, moduli::Ensemble::Volume);
    let err = unjammed.unwrap_err().to_string();
    assert!(
        err.contains("unjammed") && err.contains("fixed volume"),
        "{err}"
    );

    let mut scene = pressure_disks(3, 1e-2);
    let (fixed, s) = stabilised(&mut scene, moduli::Ensemble::Volume);
    eprintln!("fixed box: {fixed:?}");
    let s = check(s.unwrap());
    assert!((s.deformation.determinant() - 1.0).abs() < 1e-12);
    assert!((s.cell.volume() / scene.packing().bbox.volume() - 1.0).abs() < 1e-12);
    assert!(s.energy_after <= s.energy_before * (1.0 + 1e-12));
}

/// The smallest isostaticity margin `N_c − 2 (N_nr − 1)` of a disk packing
/// (harmonic, `p > 0`) stable in its cell against every deviatoric strain:
/// `d(d+1)/2`. The argument: the contact forces are a self-stress of the network with the
/// bodies' coordinates and the `d(d+1)/2 − 1` deviatoric strains as its
/// degrees of freedom (force balance on every body, and a vanishing
/// deviatoric stress), so the `N_c × (2 N_nr + 2)` compatibility matrix
/// has rank `≤ N_c − 1` and at least `2 N_nr + 3 − N_c` floppy modes. On a
/// floppy mode the Hessian is the pre-stress term, `≤ 0` for disks
/// (`v' < 0`, `∂²h` positive semi-definite), plus `−p |ε|²` from a
/// volume-preserving strain `ε`: a mode with `ε ≠ 0` would make the
/// cell's stiffness `C` negative, and one with `ε = 0` that is not a
/// translation would be a zero or negative mode of `H` (every contact's
/// relative displacement would vanish). With `C ≥ 0` and no extra zero
/// or negative mode only the 2 translations remain, so
/// `2 N_nr + 3 − N_c ≤ 2`. (In the fixed box the same argument without
/// the strains gives the familiar `≥ 1`.)
const SHEAR_STABLE_MARGIN_2D: i64 = 3;

/// The contacts of a `Strained` cell are those `Contacts` counts: in the
/// undeformed cell of a relaxed packing (disks at φ = 0.88 and n = 2
/// near-disks, Δ = 0.1, at φ = 0.90; N = 32) the cell's own listing (every
/// pair within the margin, minimum images) gives the same contacts, the
/// same rattlers (count rule `d + 1`) and so the same `N_c`, `z`, rattler
/// count and margin as `summarize` on the engine's neighbour list,
/// exactly. A contact missed by the cell's pair list (or counted twice)
/// would show here.
#[test]
fn strained_cell_counts_contacts_as_contacts_does() {
    fn check<S: Shape<2>>(mut scene: Scene<2, S>) {
        let summary = summarize_with(&mut scene, RattlerRule::Count(3));
        let cell = Strained::new(&scene, 0.1).unwrap();
        let rattler = cell.rattlers(3);
        assert_eq!(rattler, summary.rattler);
        let count = cell.contact_count(&rattler);
        eprintln!("{count:?}");
        assert!(count.n_contacts > 0);
        assert_eq!(count.n_contacts, summary.n_contacts);
        assert_eq!(count.n_contacts_all, summary.n_contacts_all);
        assert_eq!(count.n_rattlers, summary.n_rattlers);
        assert_eq!(count.z, summary.z_j);
        assert_eq!(count.iso_margin, summary.iso_margin);
    }
    check(relaxed::<2, _>(Sphere, 32, 1, 0.88));
    check(relaxed::<2, _>(near_disk(2, 0.1), 32, 3, 0.90));
}

/// The strained cell follows a rearrangement. Disks (N = 32, φ = 0.88),
/// sheared by γ = 0.15 in one go (far beyond the strain at which such a
/// packing yields) and relaxed with the deformation check's minimiser:
/// bodies move by
/// more than the pair margin (0.1) from their affine positions, so the
/// pairs they touch at the end were not all listed at the start. The cell
/// lists its pairs again as bodies move (a quarter of the margin), so the
/// relaxed cell is a minimum of the true energy: a fresh listing of every
/// pair gives the same energy and forces (10⁻¹² relative and absolute: the
/// rebasing's round-off), the largest force is below the minimiser's
/// `max_i g² < 10⁻²⁶`, and `check_pairs` passes. On a fixed list unlisted
/// neighbours would not repel and bodies would slide through them: in the
/// 3D case of `dense_3d_spheres_stabilise` the listed energy fell to zero
/// and the true one rose ×50.
#[test]
fn strained_cell_follows_a_rearrangement() {
    let scene = relaxed::<2, _>(Sphere, 32, 1, 0.88);
    let margin = 0.1;
    let start = scene.packing().positions.clone();
    let mut cell = Strained::new(&scene, margin).unwrap();
    cell.set_strain(0.15, &simple_shear::<2>(0, 1));
    cell.relist().unwrap();
    let fire = deformation_minimizer().for_family::<2, Sphere>(&scene.packing().shape);
    let out = Fire::new(fire).minimize(&mut cell).unwrap();
    cell.check_pairs().unwrap();
    let f = cell.total_deformation();
    let moved = (cell.centres().iter().zip(&start))
        .map(|(c, x)| (c - f * x).norm())
        .fold(0.0, f64::max);
    eprintln!(
        "{} FIRE steps, {} Newton, V = {:e}, largest non-affine displacement {moved}",
        out.steps, out.newton_iterations, out.energy
    );
    assert!(moved > margin, "{moved}");
    let mut fresh = cell.clone();
    fresh.relist().unwrap();
    let n = Objective::dof(&cell);
    let (mut g, mut g_fresh) = (vec![0.0; n], vec![0.0; n]);
    let e = cell.energy_and_gradient(&mut g);
    let e_fresh = fresh.energy_and_gradient(&mut g_fresh);
    assert!(e > 0.0 && (e - e_fresh).abs() < 1e-12 * e, "{e} {e_fresh}");
    for (a, b) in g.iter().zip(&g_fresh) {
        assert!((a - b).abs() < 1e-12, "{a} {b}");
        assert!(b * b < 1e-26, "{b}");
    }
}

/// Packings a cell on a fixed pair list cannot stabilise: 3D spheres,
/// N = 128, δφ = 10⁻¹ above their own φ_J
/// (`experiments/elasticity/above_jam_3d.ron`, seeds 1 and 2). On a fixed
/// list both fail with "no strain step lowers the energy" (seed 1 after 11
/// steps: residual 3.2 % of p, smallest stiffness −0.24): along the
/// stress-lowering strain the packing rearranges, which a fixed pair list
/// cannot follow. With the cell listing its pairs again as bodies move,
/// each stabilises: residual below 10⁻⁶ p, stiffness `C` with no negative
/// eigenvalue, `G_min ≥ 0`, no negative mode, the pressure held (10⁻⁶) and
/// the enthalpy not risen (10⁻¹² relative).
#[test]
fn dense_3d_spheres_stabilise() {
    let report = common::run_file(
        "experiments/elasticity/above_jam_3d.ron",
        &[
            "samples=2",
            r#"params={"l": 2, "m": 0, "delta": 0.0}"#,
            "protocol.delta_phi=1e-1",
            "protocol.shear_stabilised=true",
        ],
        1,
    );
    assert_eq!(report.packings.len(), 2);
    for c in &report.packings {
        let m = c.measures.moduli.as_ref().unwrap();
        let s = m.stabilisation.as_ref().expect("stabilisation stored");
        eprintln!(
            "{}: fixed box G = {:e}, stabilised G = {:e} (G_min {:e}), {} steps, residual {:e}",
            c.id,
            s.fixed_box.shear,
            m.moduli.shear,
            m.moduli.shear_min(),
            s.iterations,
            s.residual
        );
        assert!(s.residual < 1e-6 && s.residual_before > 1e-6, "{s:?}");
        assert!(s.stiffness_min >= 0.0, "{s:?}");
        assert!(m.moduli.shear_min() >= 0.0, "{m:?}");
        assert_eq!(m.moduli.negative_modes, 0);
        assert!(
            (s.pressure_after / s.pressure_before - 1.0).abs() < 1e-6,
            "{s:?}"
        );
        let f = Matrix::<3>::from_fn(|a, b| s.deformation[a][b]);
        let v_per_body = c.box_edges.iter().product::<f64>() / c.particles as f64;
        let h_before = s.energy_before + s.pressure_before * v_per_body;
        let h_after = s.energy_after + s.pressure_before * v_per_body * f.determinant();
        assert!(h_after <= h_before * (1.0 + 1e-12), "{s:?}");
    }
}

/// The runner tests' experiment file: disks, N = 32, `samples` samples
/// from seed 1 at `Pressure` p = 10⁻³, measuring `Contacts`, `Pressure`
/// and `Moduli()`, with `protocol_extra` (e.g. `", shear_stabilised:
/// true"`) appended to the protocol's fields.
fn stabilisation_runner_text(samples: usize, protocol_extra: &str) -> String {
    format!(
        r#"(name: "el", family: "sphere", particles: 32, samples: {samples}, seed: 1,
        protocol: Pressure(pressure: 1e-3, tol: 1e-2{protocol_extra}),
        observables: [Contacts, Pressure, Moduli()])"#
    )
}

/// [`stabilisation_runner_text`], read.
fn stabilisation_runner_experiment(
    samples: usize,
    protocol_extra: &str,
) -> jamkit_experiment::Experiment {
    jamkit_experiment::Experiment::from_ron(
        &stabilisation_runner_text(samples, protocol_extra),
        "inline",
    )
    .unwrap()
}

/// A file that scans `protocol.shear_stabilised` over `[false, true]`
/// measures each point's packing with that point's setting: the moduli of
/// the `true` point are the stabilised cell's (with the fixed box's kept
/// beside them), those of the `false` point the fixed box's alone, and the
/// two points share the configuration (the setting acts on the
/// measurement only).
#[test]
fn a_scanned_shear_stabilisation_acts_on_its_own_point() {
    let text = stabilisation_runner_text(1, "").replace(
        "observables:",
        r#"scan: [{"protocol.shear_stabilised": [false, true]}], observables:"#,
    );
    let e = jamkit_experiment::Experiment::from_ron(&text, "inline").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&e, dir.path(), 1);
    assert_eq!(report.packings.len(), 2);
    let stabilised: Vec<(bool, bool)> = report
        .packings
        .iter()
        .map(|f| {
            let asked = f.settings["protocol"]["Pressure"]["shear_stabilised"] == true;
            let moduli = f.measures.moduli.as_ref().unwrap();
            (asked, moduli.stabilisation.is_some())
        })
        .collect();
    assert_eq!(stabilised, [(false, false), (true, true)]);
    assert_eq!(report.packings[0].positions, report.packings[1].positions);
}

/// `protocol.shear_stabilised` through the runner (disks, N = 32,
/// `Pressure` p = 10⁻³, the runner test's two samples, of which the first
/// has `G < 0` in its fixed box; `Pressure` stabilises at fixed pressure,
/// the packing's own: the second sample unjams when stabilised at fixed
/// volume). Off (left out or `false`): the packing
/// files are bit for bit the same, settings included (the field is not
/// written), wall times aside. On: the same configuration is saved (the
/// stabilised cell is the moduli's only), the fixed-box moduli stored
/// beside the stabilised ones are bit for bit those of the run without
/// it, and every stabilised packing has `G ≥ 0`, no negative mode, and a
/// residual deviatoric stress below 10⁻⁶ p; `results.csv` reports the
/// stabilised `G`. A file asking for it without `Moduli` is refused,
/// naming the field.
#[test]
fn shear_stabilised_option_through_the_runner() {
    let run = |stab: &str| {
        let e = stabilisation_runner_experiment(2, stab);
        let dir = tempfile::tempdir().unwrap();
        let report = common::run_ok(&e, dir.path(), 1);
        let csv = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
        let mut files = report.packings;
        files.sort_by(|a, b| a.id.cmp(&b.id));
        (files, csv)
    };
    let without_wall = |f: &jamkit_format::PackingFile| {
        let mut v = serde_json::to_value(f).unwrap();
        v["measures"]["wall_s"] = 0.into();
        v["measures"]["moduli"]["wall_s"] = 0.into();
        if v["measures"]["moduli"]["stabilisation"].is_object() {
            v["measures"]["moduli"]["stabilisation"]["wall_s"] = 0.into();
        }
        v
    };
    let (plain, plain_csv) = run("");
    assert!(!plain_csv.contains("stab_z"), "{plain_csv}");
    let (off, _) = run(", shear_stabilised: false");
    let (on, csv) = run(", shear_stabilised: true");
    assert_eq!(plain.len(), 2);
    for ((a, b), c) in plain.iter().zip(&off).zip(&on) {
        assert_eq!(without_wall(a), without_wall(b));
        assert!(b.measures.moduli.as_ref().unwrap().stabilisation.is_none());
        assert_eq!(a.positions, c.positions);
        let m = c.measures.moduli.as_ref().unwrap();
        let s = m.stabilisation.as_ref().expect("stabilisation stored");
        assert_eq!(s.fixed_box, a.measures.moduli.as_ref().unwrap().moduli);
        eprintln!(
            "{}: fixed box G = {:e}, stabilised G = {:e}, {s:?}",
            c.id, s.fixed_box.shear, m.moduli.shear
        );
        assert!(m.moduli.shear_min() >= 0.0, "{m:?}");
        assert_eq!(m.moduli.negative_modes, 0);
        assert!(s.residual < 1e-6, "{s:?}");
        // At fixed pressure p* (the packing's own) the enthalpy
        // `U + p* V` must not rise; the volume is the box's times det F.
        let f = &s.deformation;
        let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
        let v_per_body = c.box_edges.iter().product::<f64>() / c.particles as f64;
        let h_before = s.energy_before + s.pressure_before * v_per_body;
        let h_after = s.energy_after + s.pressure_before * v_per_body * det;
        assert!(h_after <= h_before * (1.0 + 1e-12), "{s:?}");
        assert!(
            (s.pressure_after / s.pressure_before - 1.0).abs() < 1e-6,
            "{s:?}"
        );
        // The stabilised cell's contacts (disks: at least the margin a
        // cell stable to shear needs), stored with the moduli.
        let cc = s.contacts.as_ref().expect("stabilised contacts stored");
        assert!(cc.iso_margin >= SHEAR_STABLE_MARGIN_2D, "{cc:?}");
        assert_eq!(
            cc.iso_margin,
            cc.n_contacts as i64 - 2 * (32 - cc.n_rattlers as i64 - 1)
        );
        assert_eq!(
            cc.z,
            2.0 * cc.n_contacts as f64 / (32 - cc.n_rattlers) as f64
        );
        assert!(
            csv.contains(&format!(
                "{},{},{},{}",
                cc.n_contacts, cc.n_rattlers, cc.z, cc.iso_margin
            )),
            "{csv}"
        );
        assert!(c.settings["protocol"]["Pressure"]["shear_stabilised"] == true);
        assert!(
            a.settings["protocol"]["Pressure"]
                .get("shear_stabilised")
                .is_none()
        );
    }
    let first = on[0].measures.moduli.as_ref().unwrap();
    assert!(first.stabilisation.as_ref().unwrap().fixed_box.shear < 0.0);
    assert!(csv.contains(&format!("{:e}", first.moduli.shear)), "{csv}");
    let text = stabilisation_runner_text(2, ", shear_stabilised: true").replace(", Moduli()", "");
    let err = jamkit_experiment::Experiment::from_ron(&text, "inline")
        .unwrap()
        .validate()
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("protocol.shear_stabilised") && err.contains("Moduli"),
        "{err}"
    );
}

/// A shear stabilisation that fails leaves a trace, as a failed minimisation
/// does (the runner's `<id>.failed.json`): here forced by a cap of one
/// strain step (`protocol.stabilise.max_iterations`) on the fixed-box
/// packing with `G < 0` of `shear_stabilised_option_through_the_runner`,
/// which needs 5. The failed file holds the fixed-box packing (its
/// configuration and moduli bit for bit those of the run without the
/// option) flagged with the error, no `<id>.json` is written (a rerun tries
/// again), and a rerun with the default cap stabilises it and removes the
/// failed file. Bad `stabilise` settings are refused, naming the field.
#[test]
fn a_failed_shear_stabilisation_keeps_the_fixed_box_packing() {
    let experiment = |stab: &str| {
        let e = stabilisation_runner_experiment(1, stab);
        e.validate().map(|_| e)
    };
    let plain_dir = tempfile::tempdir().unwrap();
    let plain = common::run_ok(&experiment("").unwrap(), plain_dir.path(), 1).packings;
    let dir = tempfile::tempdir().unwrap();
    let capped = experiment(", shear_stabilised: true, stabilise: (max_iterations: 1)").unwrap();
    let report = common::run_into(&capped, dir.path(), 1);
    assert!(report.packings.is_empty());
    assert_eq!(report.failures.len(), 1);
    let packings = dir.path().join("packings");
    let id = "sphere_d2_N32_s1";
    let path = jamkit_experiment::runner::failed_path(&packings, id);
    let message = report.failures[0].to_string();
    assert!(
        message.contains("did not converge in 1 strain steps")
            && message.contains(&path.display().to_string()),
        "the error says why and names the saved file: {message}"
    );
    assert!(!packings.join(format!("{id}.json")).exists());
    let failed = jamkit_format::PackingFile::load_checked(&path).unwrap();
    let flag = &failed.measures.flag;
    assert!(
        flag.contains("shear stabilisation failed") && flag.contains("fixed-box packing"),
        "{flag}"
    );
    let m = failed.measures.moduli.as_ref().unwrap();
    assert!(m.stabilisation.is_none());
    let fixed = plain[0].measures.moduli.as_ref().unwrap();
    assert_eq!(m.moduli, fixed.moduli);
    assert!(m.moduli.shear < 0.0, "the fixed box's G < 0: {m:?}");
    assert_eq!(failed.positions, plain[0].positions);
    assert_eq!(failed.measures.n_contacts, plain[0].measures.n_contacts);
    assert_eq!(
        failed.settings["protocol"]["Pressure"]["stabilise"]["max_iterations"],
        1
    );
    // The default cap: stabilised, and the failed file is gone.
    let full = common::run_ok(
        &experiment(", shear_stabilised: true").unwrap(),
        dir.path(),
        1,
    );
    assert!(!path.exists(), "a successful rerun removes the failed file");
    let s = full.packings[0].measures.moduli.as_ref().unwrap();
    assert!(s.stabilisation.as_ref().unwrap().iterations > 1);
    assert!(
        full.packings[0].settings["protocol"]["Pressure"]
            .get("stabilise")
            .is_none(),
        "default settings are not written (earlier runs resume)"
    );
    // `jamkit plot` draws the fixed box's G beside the stabilised one,
    // and says that the plain run has none.
    let fig = tempfile::tempdir().unwrap();
    let plots = jamkit_report::runplot::plot(&[dir.path().to_path_buf()], fig.path()).unwrap();
    let name = |f: &std::path::PathBuf| f.file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        plots
            .figures
            .iter()
            .any(|f| name(f).starts_with("shear_modulus_fixed_box_vs_")),
        "{:?}",
        plots.figures
    );
    let plots =
        jamkit_report::runplot::plot(&[plain_dir.path().to_path_buf()], fig.path()).unwrap();
    assert!(
        plots
            .index
            .contains("G of the fixed box (before the shear stabilisation) against"),
        "{}",
        plots.index
    );
    // Bad input.
    for (stab, field) in [
        (
            ", shear_stabilised: true, stabilise: (max_iterations: 0)",
            "protocol.stabilise.max_iterations",
        ),
        (
            ", shear_stabilised: true, stabilise: (tol: 2.0)",
            "protocol.stabilise.tol",
        ),
        (
            ", shear_stabilised: true, stabilise: (margin: -0.1)",
            "protocol.stabilise.margin",
        ),
        (", stabilise: (max_iterations: 3)", "protocol.stabilise"),
    ] {
        let err = experiment(stab).unwrap_err().to_string();
        assert!(err.contains(field), "{stab}: {err}");
    }
    let err = jamkit_experiment::Experiment::from_ron(
        &stabilisation_runner_text(1, ", shear_stabilised: true, stabilise: (max_steps: 3)"),
        "inline",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("max_steps"), "{err}");
}
