//! Fixtures shared by the end-to-end tests (`tests/integration.rs` declares
//! the module; a file that needs them has `use crate::common;`).
#![allow(dead_code)]

use jamkit_core::{Pair, ShapeExt};
use jamkit_experiment::Experiment;
use jamkit_experiment::runner::{RunOptions, RunReport, run};
use jamkit_fourier::{FourierSumParams, Mode, NearDisk};
use std::path::Path;

/// A three-mode `fourier_sum` near-disk (n = 2, 3, 7 with phases), Δ = 0.2:
/// the hard case for derivative checks.
pub fn multi_mode() -> NearDisk {
    let modes = vec![
        Mode {
            n: 2,
            a: 0.4,
            b: 0.3,
        },
        Mode {
            n: 3,
            a: 0.2,
            b: -1.0,
        },
        Mode {
            n: 7,
            a: 0.05,
            b: 2.0,
        },
    ];
    NearDisk::fourier_sum(&FourierSumParams {
        modes,
        delta: 0.2,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap()
}

/// Options of a quiet run into `dir` on `jobs` threads, unsharded.
pub fn options(dir: &Path, jobs: usize) -> RunOptions {
    RunOptions {
        out: dir.to_path_buf(),
        jobs: Some(jobs),
        log: jamkit_experiment::Log::Quiet,
        shard: None,
    }
}

/// Run `e` into `dir` without a progress bar.
pub fn run_into(e: &Experiment, dir: &Path, jobs: usize) -> RunReport {
    run(e, &options(dir, jobs)).unwrap()
}

/// Run the experiment file `file` (relative to the workspace root) with
/// the `--set` overrides `sets` into a temporary directory; every sample
/// must succeed.
pub fn run_file(file: &str, sets: &[&str], jobs: usize) -> RunReport {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let e = Experiment::from_file(&path).unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let e = jamkit_experiment::overrides::apply(&e, &sets).unwrap();
    e.validate().unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_ok(&e, dir.path(), jobs)
}

/// [`run_into`], and every sample must succeed.
pub fn run_ok(e: &Experiment, dir: &Path, jobs: usize) -> RunReport {
    let report = run_into(e, dir, jobs);
    assert!(report.failures.is_empty(), "{:?}", report.failures);
    report
}

/// A run directory made by `old` (every packing new) is refused by `new`
/// with an error holding every one of `parts`, and resumed by `old` again
/// (every packing reused): a setting whose default changed.
pub fn refused_then_resumed(old: &Experiment, new: &Experiment, parts: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let made = run_ok(old, dir.path(), 1);
    assert!(!made.packings.is_empty());
    assert_eq!(made.reused, 0);
    let err = run(new, &options(dir.path(), 1)).unwrap_err().to_string();
    for part in parts {
        assert!(err.contains(part), "{part:?} missing from: {err}");
    }
    let again = run_ok(old, dir.path(), 1);
    assert_eq!(
        (again.packings.len(), again.reused),
        (made.packings.len(), made.packings.len())
    );
}

/// Run the `jamkit` binary in the workspace root: exit code, stdout, stderr.
pub fn jamkit(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_jamkit"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// `jamkit run FILE --out OUT --quiet --set S …` of an experiment file
/// named from the workspace root; it must succeed.
#[allow(dead_code)]
pub fn run_cli(file: &str, out: &Path, sets: &[&str]) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let mut args = vec![
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    for s in sets {
        args.extend(["--set", s]);
    }
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
}

/// `jamkit export RUN -o TARGET`: exit code, stdout, stderr.
#[allow(dead_code)]
pub fn export(run: &Path, target: &Path) -> (i32, String, String) {
    jamkit(&[
        "export",
        run.to_str().unwrap(),
        "-o",
        target.to_str().unwrap(),
    ])
}

/// The packing files (`packings/*.json`) of a run directory, sorted by name.
#[allow(dead_code)]
pub fn packing_paths(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut paths: Vec<_> = std::fs::read_dir(dir.join("packings"))
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    paths.sort();
    paths
}

/// `experiments/quickstart.ron`, as a path string for `jamkit` arguments.
#[allow(dead_code)]
pub fn quickstart() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments/quickstart.ron")
        .to_str()
        .unwrap()
        .to_string()
}

/// `jamkit run` of the quickstart at 16 disks and `samples` samples into
/// `out`, quietly, with the arguments `extra` appended; it must succeed.
#[allow(dead_code)]
pub fn small_quickstart(out: &Path, samples: usize, extra: &[&str]) {
    let (file, samples) = (quickstart(), format!("samples={samples}"));
    let mut args = vec![
        "run",
        file.as_str(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "particles=16",
        "--set",
        samples.as_str(),
        "--quiet",
    ];
    args.extend(extra);
    let (code, _, err) = jamkit(&args);
    assert_eq!(code, 0, "{err}");
}

/// `results.csv` of `dir` without its `wall_s` column (the one number that
/// depends on the machine, not on the packing).
#[allow(dead_code)]
pub fn results_without_timing(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let wall = rows[0].iter().position(|c| c == "wall_s").unwrap();
    rows.into_iter()
        .map(|mut r| {
            r.remove(wall);
            r
        })
        .collect()
}

/// `n` bodies placed at φ = 0.1 and compressed affinely to `phi` (above
/// jamming for every family the tests use at their `phi`).
#[allow(dead_code)]
pub fn compressed<const D: usize, S: jamkit_core::Shape<D>>(
    shape: S,
    n: usize,
    seed: u64,
    phi: f64,
) -> jamkit_engine::Scene<D, S> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let sizes = jamkit_core::SizeDistribution::default().sample(n, &mut rng);
    let mut packing = jamkit_core::Packing::<D, S>::random(shape, sizes, 0.1, &mut rng).unwrap();
    packing.set_phi(phi);
    jamkit_engine::Scene::new(packing, jamkit_core::Potential::Harmonic, 0.2)
}

/// The scene's energy pass (the family's warm lanes where it has them,
/// memos and all) gives the energy and gradient of the generic pass one
/// pair at a time bit for bit, call after call, while 97 bodies at
/// φ = 0.86 move down the gradient and every tenth call jump (centres by
/// up to 0.1, turns by up to 2 rad): warm pairs, pairs that turn far,
/// pairs new to a rebuilt list, in a list whose length is no multiple of
/// the chunk. `what` names the shape in a failure.
pub fn assert_lanes_match_the_generic_pass<S: jamkit_core::Shape<2>>(shape: S, what: &str) {
    use jamkit_core::{Packing, Potential, SizeDistribution};
    use jamkit_engine::{Objective, Scene};
    use rand::{RngExt, SeedableRng};
    let bits = |g: &[f64]| g.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let sizes = SizeDistribution::default().sample(97, &mut rng);
    let packing = Packing::<2, S>::random(shape, sizes, 0.86, &mut rng).unwrap();
    let mut lanes = Scene::new(packing, Potential::Harmonic, 0.2);
    let mut generic = lanes.clone();
    let (mut g, mut h) = (vec![0.0; lanes.dof()], vec![0.0; lanes.dof()]);
    let mut jumps = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    for call in 0..60 {
        let e = lanes.energy_gradient(&mut g);
        let f = generic.energy_gradient_generic(&mut h);
        let what = format!("{what}, call {call}");
        assert!(e > 0.0, "{what}");
        assert_eq!(e.to_bits(), f.to_bits(), "{what}");
        assert_eq!(bits(&g), bits(&h), "{what}");
        let mut dq: Vec<f64> = g.iter().map(|x| -0.02 * x).collect();
        if call % 10 == 9 {
            for (k, x) in dq.iter_mut().enumerate() {
                let big = if k % 3 == 2 { 2.0 } else { 0.1 };
                *x += big * (jumps.random::<f64>() - 0.5);
            }
        }
        lanes.displace(&dq);
        generic.displace(&dq);
    }
}

/// A compact overlapping cluster of 30 bodies of a 3D quaternion family,
/// turned by rotations about two skew axes (centres about the middle,
/// every orientation `Q → U Q`), keeps its energy to 1e-12 relative (only
/// the order of round-off changes). The conformance kit turns about the z
/// axis only, and skips bodies with two rotational coordinates.
pub fn check_general_rotation<S>(shape: S)
where
    S: jamkit_core::Shape<3, Orientation = jamkit_core::Quaternion>,
{
    use jamkit_core::{Packing, Potential, Quaternion, SizeDistribution, Vector};
    use jamkit_engine::{Objective, Scene};
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let sizes = SizeDistribution::default().sample(30, &mut rng);
    let mut p = Packing::<3, S>::random(shape.clone(), sizes, 0.01, &mut rng).unwrap();
    let centre = *p.bbox.edges() * 0.5;
    for (k, r) in p.positions.iter_mut().enumerate() {
        let a = k as f64 * 2.399;
        let rho = 0.5 * (k as f64).cbrt();
        let z = 0.9 * ((k * 7) as f64).sin();
        *r = centre + Vector::<3>::new(rho * a.cos(), rho * a.sin(), z);
    }
    let energy = |p: Packing<3, S>| {
        let mut s = Scene::new(p, Potential::Harmonic, 0.2);
        let mut g = vec![0.0; s.dof()];
        s.energy_gradient(&mut g)
    };
    let e0 = energy(p.clone());
    assert!(e0 > 1e-3, "the cluster should overlap: V = {e0}");
    for u in [
        Quaternion::normalized(0.4, 0.7, -0.3, 0.5).unwrap(),
        Quaternion::normalized(-0.1, 0.2, 0.9, -0.4).unwrap(),
    ] {
        let mut q = p.clone();
        for (r, o) in q.positions.iter_mut().zip(q.orientations.iter_mut()) {
            *r = centre + u.apply(&(*r - centre));
            *o = u.mul(o).renormalized();
        }
        let e1 = energy(q);
        assert!(
            (e1 - e0).abs() < 1e-12 * e0,
            "{shape:?}: V {e0} → {e1} after turning"
        );
    }
}

/// The packings of an experiment written inline (RON), run into a
/// temporary directory; every sample must succeed.
pub fn run_inline(text: &str) -> Vec<jamkit_format::PackingFile> {
    let e = Experiment::from_ron(text, "inline").unwrap();
    e.validate().unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_ok(&e, dir.path(), 1).packings
}

/// A jammed packing: inside the paper's window `10⁻¹⁶ < V/N < 2·10⁻¹⁶`.
pub fn assert_in_window(p: &jamkit_format::PackingFile) {
    assert!(
        p.energy_per_particle > 1e-16 && p.energy_per_particle < 2e-16,
        "{}: V/N = {}",
        p.id,
        p.energy_per_particle
    );
}

/// The packings of a family's sphere limit are the sphere family's, bit
/// for bit (centres and φ), with no orientations stored.
pub fn assert_sphere_packings(
    spheres: &[jamkit_format::PackingFile],
    limit: &[jamkit_format::PackingFile],
) {
    for (a, b) in spheres.iter().zip(limit) {
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.phi.to_bits(), b.phi.to_bits());
        assert!(b.orientations.is_empty());
    }
}

/// One packing of the 3D family `family` with `params` (a RON map;
/// N = 64, seed 2, contacts only) and the parameters it stored, for
/// [`check_counts_from_file`].
pub fn packing_with_params_3d(
    family: &str,
    params: &str,
) -> (jamkit_format::PackingFile, jamkit_registry::ParamMap) {
    let text = format!(
        r#"(name: "r", dim: 3, family: "{family}", params: {params}, particles: 64, samples: 1, seed: 2, observables: [Contacts])"#
    );
    let p = run_inline(&text).remove(0);
    let map = jamkit_registry::params_from_json(&p.params).unwrap();
    (p, map)
}

/// The rattler convention and the isostatic count of a 3D quaternion
/// family, recomputed from one packing file alone: contacts are the pairs
/// with a negative gap (minimum image), bodies with fewer than d + 1 = 4
/// contacts are removed until none is left, and the remaining set must be
/// the file's non-rattlers with its contact count; the isostatic margin
/// must be `N_c − (f N_nr − 3)` with `f = 3 + rot_dof`, which is returned.
pub fn check_counts_from_file<S>(shape: &S, p: &jamkit_format::PackingFile) -> i64
where
    S: jamkit_core::Shape<3, Orientation = jamkit_core::Quaternion>,
{
    use jamkit_core::Vector;
    let n = p.particles;
    let o: Vec<jamkit_core::Quaternion> = p
        .orientations
        .iter()
        .map(|c| jamkit_core::Quaternion::from_coords(c).unwrap())
        .collect();
    assert!(p.orientations.iter().all(|q| q.len() == 4));
    let mut pairs = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let r = Vector::<3>::from_fn(|a, _| {
                let (d, l) = (p.positions[j][a] - p.positions[i][a], p.box_edges[a]);
                d - l * (d / l).round()
            });
            for c in shape.pair_contacts(&Pair::new(p.radii[i], o[i], p.radii[j], o[j], r), 0.0) {
                if c.gap < 0.0 {
                    pairs.push((i, j));
                }
            }
        }
    }
    let mut alive = vec![true; n];
    loop {
        let mut count = vec![0usize; n];
        for &(i, j) in &pairs {
            if alive[i] && alive[j] {
                count[i] += 1;
                count[j] += 1;
            }
        }
        let drop: Vec<usize> = (0..n).filter(|&i| alive[i] && count[i] < 4).collect();
        if drop.is_empty() {
            break;
        }
        for i in drop {
            alive[i] = false;
        }
    }
    let rattler: Vec<bool> = alive.iter().map(|a| !a).collect();
    assert_eq!(rattler, p.rattler, "rattlers of {}", p.id);
    let n_c = pairs.iter().filter(|(i, j)| alive[*i] && alive[*j]).count();
    let n_nr = alive.iter().filter(|a| **a).count();
    assert_eq!(p.measures.n_contacts, Some(n_c), "{}", p.id);
    let f = 3 + shape.rot_dof() as i64;
    let margin = n_c as i64 - (f * n_nr as i64 - 3);
    assert_eq!(p.measures.iso_margin, Some(margin), "{}", p.id);
    margin
}
