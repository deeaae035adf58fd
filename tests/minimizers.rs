//! The minimisers against the paper's FIRE: from the same start, on small
//! scenes of every family above jamming, FIRE with the Newton finish, FIRE
//! 2.0, FIRE with block masses and L-BFGS must end in the same local minimum as FIRE — the same energy
//! and the same contacts — and the paper's FIRE (`FireParams::paper()`)
//! must still give the packings it gave before the Newton finish existed.

use jamkit_core::Shape;
use jamkit_engine::hessian::{Hessian, HessianOptions};
use jamkit_engine::{
    Fire, FireParams, FireVariant, ForceCriterion, LbfgsChoice, LbfgsParams, Masses, NewtonParams,
    Objective, PreconParams, Scene, StopReason,
};
use jamkit_fourier::{FourierParams, NearDisk};
use jamkit_lobed::{LobedParams, lobed};
use jamkit_nmer::{Nmer, NmerParams};
use jamkit_sphere::Sphere;
use rand::{RngExt, SeedableRng};
use std::collections::BTreeSet;

use crate::common;
use common::compressed;

/// Pairs `(i, j)` in contact (`h < 0`).
fn contact_set<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>) -> BTreeSet<(usize, usize)> {
    let mut set = BTreeSet::new();
    scene.for_each_contact(0.0, |i, j, _, c| {
        if c.gap < 0.0 {
            set.insert((i, j));
        }
    });
    set
}

struct Minimum {
    energy: f64,
    contacts: BTreeSet<(usize, usize)>,
    newton_iterations: u64,
    reason: StopReason,
}

fn minimise<const D: usize, S: Shape<D>>(scene: &Scene<D, S>, params: FireParams) -> Minimum {
    let mut scene = scene.clone();
    let out = Fire::new(params).minimize(&mut scene).unwrap();
    Minimum {
        energy: out.energy,
        contacts: contact_set(&mut scene),
        newton_iterations: out.newton_iterations,
        reason: out.reason,
    }
}

/// The same minimum, two ways.
///
/// FIRE (the paper's) minimises a random compressed start; from its
/// minimum with every coordinate moved by up to 10⁻³, FIRE 2.0, FIRE with
/// the Newton finish from the first step (`after: 1`), the default
/// minimiser, FIRE with block masses and L-BFGS from the first step (with
/// the bodies' masses and with the blocks as `H₀`) come back to it. (From the random start itself the
/// minimisers take other paths through the landscape and may end in other
/// minima, as FIRE with any other parameter would: FIRE 2.0 did on every
/// family, and so did Newton taking over after 300 FIRE steps on one
/// disk scene.)
///
/// Energy tolerance: all stop on `Σ g² < 10⁻²⁵`; at a minimum whose
/// softest non-zero Hessian eigenvalue is `λ`, that leaves `V − V_min ≲
/// 10⁻²⁵/λ`, below 10⁻¹⁵ for any `λ > 10⁻¹⁰`, while `V ≈ 10⁻³ N`: a
/// relative 10⁻⁹ separates "the same minimum" from another one (the
/// minima of these scenes differ by percents) with room to spare. The
/// contact sets must be identical: at `V/N ~ 10⁻³` overlaps are ~10⁻²,
/// far from the `h = 0` edge where a residual force of 10⁻¹² could flip a
/// contact.
fn same_minimum<const D: usize, S: Shape<D>>(shape: S, n: usize, phi: f64, seeds: &[u64]) {
    // The family's time step, as `jamkit run` resolves it.
    let paper = FireParams::paper().for_family(&shape);
    let newton_first = FireParams {
        newton: Some(NewtonParams {
            after: 1,
            ..NewtonParams::default()
        }),
        ..paper.clone()
    };
    let fire2 = FireParams {
        variant: FireVariant::Fire2,
        ..paper.clone()
    };
    let default = FireParams::default().for_family(&shape);
    let blocks = FireParams {
        masses: Masses::Blocks(PreconParams::default()),
        ..paper.clone()
    };
    // L-BFGS from the start, with the bodies' masses and with the blocks
    // as its `H₀`.
    let lbfgs = |blocks| FireParams {
        lbfgs: LbfgsChoice::On(LbfgsParams {
            blocks,
            ..LbfgsParams::default()
        }),
        ..paper.clone()
    };
    let mut newton_used = 0;
    for &seed in seeds {
        let scene = compressed::<D, S>(shape.clone(), n, seed, phi);
        let mut at_minimum = scene.clone();
        let out = Fire::new(paper.clone()).minimize(&mut at_minimum).unwrap();
        assert_eq!(out.reason, StopReason::Force, "{shape:?}: above jamming");
        let reference = Minimum {
            energy: out.energy,
            contacts: contact_set(&mut at_minimum),
            newton_iterations: 0,
            reason: out.reason,
        };
        assert!(
            reference.energy / n as f64 > 1e-8,
            "{shape:?}: above jamming"
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + 100);
        let kick: Vec<f64> = (0..scene.dof())
            .map(|_| 1e-3 * (2.0 * rng.random::<f64>() - 1.0))
            .collect();
        let mut perturbed = at_minimum.clone();
        perturbed.displace(&kick);
        let runs = [
            ("fire2", fire2.clone()),
            ("newton", newton_first.clone()),
            ("default", default.clone()),
            ("block masses", blocks.clone()),
            ("lbfgs", lbfgs(false)),
            ("lbfgs blocks", lbfgs(true)),
        ];
        for (name, params) in runs {
            let other = minimise(&perturbed, params);
            assert_eq!(other.reason, StopReason::Force, "{shape:?} {name}");
            let rel = (other.energy - reference.energy).abs() / reference.energy;
            assert!(
                rel < 1e-9,
                "{shape:?} D={D} seed {seed} {name}: V = {:e} against FIRE's {:e}",
                other.energy,
                reference.energy
            );
            assert_eq!(
                other.contacts, reference.contacts,
                "{shape:?} D={D} seed {seed} {name}: contact sets differ"
            );
            newton_used += other.newton_iterations;
        }
    }
    assert!(
        newton_used > 0,
        "{shape:?}: the Newton finish was never used"
    );
}

#[test]
fn spheres_reach_fires_minimum_2d_and_3d() {
    same_minimum::<2, _>(Sphere, 32, 0.9, &[1, 2]);
    same_minimum::<3, _>(Sphere, 32, 0.7, &[1, 2]);
}

#[test]
fn near_disks_reach_fires_minimum() {
    for (n, delta) in [(2, 0.1), (5, 0.1), (2, 0.01)] {
        let shape = NearDisk::fourier(&FourierParams {
            n,
            delta,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap();
        same_minimum::<2, _>(shape, 24, 0.92, &[1, 2]);
    }
    same_minimum::<2, _>(common::multi_mode(), 24, 0.92, &[1]);
    let lobed = lobed(&LobedParams {
        delta: 0.15,
        kappa: 2.0,
        inertia: None,
    })
    .unwrap();
    same_minimum::<2, _>(lobed, 24, 0.92, &[1]);
}

#[test]
fn rigid_bodies_and_ellipses_reach_fires_minimum() {
    let dimer = NmerParams {
        alpha: Some(1.5),
        spheres: None,
        inertia: None,
    };
    same_minimum::<2, _>(Nmer::<2>::new(&dimer).unwrap(), 16, 0.92, &[1, 2]);
    same_minimum::<3, _>(Nmer::<3>::new(&dimer).unwrap(), 32, 0.7, &[1]);
    let ellipse = jamkit_ellipse::Ellipse::new(&jamkit_ellipse::EllipseParams {
        aspect: 1.5,
        inertia: None,
    })
    .unwrap();
    same_minimum::<2, _>(ellipse, 16, 0.92, &[1]);
}

/// The force criteria: `Max` stops on the largest squared component,
/// `PerBody` on the mean over bodies, `Sum` on the sum; checked on the
/// state each one stopped at.
#[test]
fn force_criteria_hold_where_they_stop() {
    let scene = compressed::<2, _>(Sphere, 64, 3, 0.9);
    for criterion in [
        ForceCriterion::Sum,
        ForceCriterion::PerBody,
        ForceCriterion::Max,
    ] {
        let mut s = scene.clone();
        let params = FireParams {
            force_criterion: criterion,
            newton: None,
            ..FireParams::default()
        };
        let out = Fire::new(params.clone()).minimize(&mut s).unwrap();
        assert_eq!(out.reason, StopReason::Force);
        let mut g = vec![0.0; s.dof()];
        s.energy_gradient(&mut g);
        let sum: f64 = g.iter().map(|x| x * x).sum();
        let max = g.iter().fold(0.0f64, |m, x| m.max(x * x));
        let measure = match criterion {
            ForceCriterion::Sum => sum,
            ForceCriterion::PerBody => sum / 64.0,
            ForceCriterion::Max => max,
        };
        assert!(measure < params.force_tol, "{criterion:?}: {measure:e}");
        // The looser criteria stop earlier: the sum must not already hold
        // for Max (else the test would not tell them apart).
        if criterion == ForceCriterion::Max {
            assert!(
                sum >= params.force_tol,
                "Max stopped where Sum also holds: {sum:e}"
            );
        }
    }
}

/// `force_tol_per_body: true` is the per-body sum whatever
/// `force_criterion` holds (the default `Max`, or the `Sum` that run
/// directories of the paper's path record); settings that contradict
/// each other are refused, naming the field.
#[test]
fn conflicting_minimizer_settings_are_refused() {
    for criterion in [
        ForceCriterion::Sum,
        ForceCriterion::PerBody,
        ForceCriterion::Max,
    ] {
        let p = FireParams {
            force_tol_per_body: true,
            force_criterion: criterion,
            ..FireParams::default()
        };
        assert!(p.validate("minimizer").is_ok(), "{criterion:?}");
        assert_eq!(p.criterion(), ForceCriterion::PerBody, "{criterion:?}");
    }
    let p = FireParams {
        newton: Some(NewtonParams {
            shift: 2.0,
            ..NewtonParams::default()
        }),
        ..FireParams::default()
    };
    let err = p.validate("minimizer").unwrap_err().to_string();
    assert!(err.contains("minimizer.newton.shift"), "{err}");
    let p = FireParams {
        variant: FireVariant::Fire2,
        masses: Masses::Blocks(PreconParams::default()),
        ..FireParams::default()
    };
    let err = p.validate("minimizer").unwrap_err().to_string();
    assert!(
        err.contains("minimizer.masses") && err.contains("variant: Fire"),
        "{err}"
    );
    let p = FireParams {
        masses: Masses::Blocks(PreconParams {
            floor: 0.0,
            ..PreconParams::default()
        }),
        ..FireParams::default()
    };
    let err = p.validate("minimizer").unwrap_err().to_string();
    assert!(err.contains("minimizer.masses.floor"), "{err}");
}

/// Each body's stiffness block (the block-preconditioned FIRE's mass) is
/// the body's own diagonal block of the stiffness part `K` of the Hessian,
/// which `tests/hessian.rs` checks against finite differences; the two are
/// assembled by separate code (first derivatives of the gaps only, against
/// the families' gap Hessians). Tolerance 1e-12 relative to the largest
/// entry: the same products summed in another order.
#[test]
fn stiffness_blocks_are_the_hessians_diagonal_blocks() {
    fn check<const D: usize, S: Shape<D>>(shape: S, n: usize, phi: f64) {
        let mut scene = compressed::<D, S>(shape.clone(), n, 3, phi);
        let k = Hessian::of_scene(
            &mut scene,
            &[],
            HessianOptions {
                stiffness_only: true,
                remove_rattlers: false,
            },
        )
        .unwrap()
        .dense();
        let mut blocks = Vec::new();
        assert!(scene.stiffness_blocks(&mut blocks), "{shape:?}");
        let f = scene.dof() / n;
        assert_eq!(blocks.len(), n * f * f);
        let scale = blocks.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0, "{shape:?}: no contact");
        for b in 0..n {
            for x in 0..f {
                for y in 0..f {
                    let want = k[(b * f + x, b * f + y)];
                    let got = blocks[b * f * f + x * f + y];
                    assert!(
                        (got - want).abs() <= 1e-12 * scale,
                        "{shape:?} D={D} body {b} ({x},{y}): {got:e} against {want:e}"
                    );
                }
            }
        }
    }
    let near_disk = NearDisk::fourier(&FourierParams {
        n: 3,
        delta: 0.2,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    let dimer = NmerParams {
        alpha: Some(1.5),
        spheres: None,
        inertia: None,
    };
    let ellipse = jamkit_ellipse::Ellipse::new(&jamkit_ellipse::EllipseParams {
        aspect: 1.5,
        inertia: None,
    })
    .unwrap();
    check::<2, _>(Sphere, 32, 0.9);
    check::<3, _>(Sphere, 32, 0.7);
    check::<2, _>(near_disk, 32, 0.92);
    check::<2, _>(common::multi_mode(), 24, 0.92);
    check::<2, _>(Nmer::<2>::new(&dimer).unwrap(), 16, 0.92);
    check::<3, _>(Nmer::<3>::new(&dimer).unwrap(), 32, 0.7);
    check::<2, _>(ellipse, 16, 0.92);
}

/// `bench packing --minimizer paper` gives, bit for bit, the packings of
/// commit 02d45c6 (before the Newton finish): the hashes of the final box,
/// centres and orientations printed by that commit's `jamkit bench packing`
/// for these arguments.
#[test]
fn paper_fire_gives_the_packings_it_gave_before() {
    let cases: [(&[&str], &str); 4] = [
        (&["--particles", "64", "--seeds", "2"], "b190abdb451c2b6e"),
        (
            &["--particles", "64", "--seeds", "1", "--dim", "3"],
            "f2bd0fc2cf52fb14",
        ),
        (
            &["--particles", "32", "--seeds", "1", "--family", "fourier"],
            "486f36f0964cb571",
        ),
        (
            &[
                "--particles",
                "32",
                "--seeds",
                "1",
                "--family",
                "fourier",
                "--n",
                "3",
                "--delta",
                "0.2",
            ],
            "1b8175aeb2058572",
        ),
    ];
    for (args, hash) in cases {
        let args = [&["bench", "packing", "--minimizer", "paper"][..], args].concat();
        let (code, text, err) = common::jamkit(&args);
        assert_eq!(code, 0, "{err}");
        let line = text.lines().nth(1).unwrap();
        assert_eq!(line.split(',').nth(10), Some(hash), "{args:?}: {line}");
    }
}

/// `bench packing --trace FILE`: one row per minimisation, whose FIRE steps
/// and Newton iterations add up to the packing's totals, the last row in
/// the paper's energy window.
#[test]
fn the_step_trace_adds_up() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.csv");
    let (code, text, err) = common::jamkit(&[
        "bench",
        "packing",
        "--particles",
        "64",
        "--seeds",
        "1",
        "--minimizer",
        "newton",
        "--newton-after",
        "100",
        "--trace",
        path.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let cols: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    let (steps, newton): (u64, u64) = (cols[7].parse().unwrap(), cols[11].parse().unwrap());
    let trace = std::fs::read_to_string(&path).unwrap();
    let rows: Vec<Vec<&str>> = trace
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert!(
        rows.len() > 100,
        "a jamming run makes hundreds of minimisations"
    );
    let sum = |k: usize| {
        rows.iter()
            .map(|r| r[k].parse::<u64>().unwrap())
            .sum::<u64>()
    };
    assert_eq!(sum(2), steps);
    assert_eq!(sum(3), newton);
    assert!(newton > 0, "the Newton finish was used");
    let last_e: f64 = rows.last().unwrap()[5].parse().unwrap();
    assert!(last_e > 1e-16 && last_e < 2e-16, "{last_e}");
}

/// Disks that give no second derivatives (`gap_hessians` left at the
/// trait's default), as a new family may before its Hessian is written.
#[derive(Clone, Debug)]
struct DisksWithoutHessian;

impl Shape<2> for DisksWithoutHessian {
    type Orientation = ();
    type Fast = jamkit_core::NoFastPath;
    fn family(&self) -> &'static str {
        "disks-without-hessian"
    }
    fn rot_dof(&self) -> usize {
        0
    }
    fn volume(&self, size: f64) -> f64 {
        Shape::<2>::volume(&Sphere, size)
    }
    fn bounding_radius(&self, size: f64) -> f64 {
        Shape::<2>::bounding_radius(&Sphere, size)
    }
    fn rotate(&self, _o: &mut (), _dq: &[f64]) {}
    fn contacts<F: FnMut(jamkit_core::Contact<2>)>(
        &self,
        pair: &jamkit_core::Pair<2, ()>,
        max_gap: f64,
        visit: F,
    ) {
        Shape::<2>::contacts(&Sphere, pair, max_gap, visit)
    }
}

/// A family without a Hessian is minimised by FIRE alone under the default
/// minimiser (the Newton finish is skipped, not an error), and ends where
/// the paper's FIRE with the same force rule ends: the same steps, the
/// same energy.
#[test]
fn a_family_without_hessian_is_minimised_by_fire_alone() {
    let scene = compressed::<2, _>(DisksWithoutHessian, 32, 1, 0.9);
    let mut with_default = scene.clone();
    let out = Fire::new(FireParams {
        newton: Some(NewtonParams {
            after: 10,
            ..NewtonParams::default()
        }),
        ..FireParams::default()
    })
    .minimize(&mut with_default)
    .unwrap();
    assert_eq!(out.reason, StopReason::Force);
    assert_eq!(out.newton_iterations, 0);
    let mut paper = scene.clone();
    let reference = Fire::new(FireParams {
        force_criterion: ForceCriterion::default(),
        ..FireParams::paper()
    })
    .minimize(&mut paper)
    .unwrap();
    assert_eq!((out.steps, out.energy), (reference.steps, reference.energy));
}

/// `masses: Blocks((jammed_only: true))`: the blocks act only in the
/// jamming search's minimisations that start from a decompressed jammed
/// state. A minimisation with no such start (here the first one, from a
/// compressed random state) is bit for bit the plain masses'; the jamming
/// search then ends in the paper's window; and the always-on blocks give a
/// different first minimisation (else the check would be empty).
#[test]
fn jammed_only_blocks_leave_other_minimisations_to_the_plain_masses() {
    let dimer = Nmer::<2>::new(&NmerParams {
        alpha: Some(1.5),
        spheres: None,
        inertia: None,
    })
    .unwrap();
    let with = |masses: Masses| {
        let mut scene = compressed::<2, _>(dimer.clone(), 24, 5, 0.9);
        let mut fire = Fire::new(FireParams {
            masses,
            ..FireParams::default()
        });
        let out = fire.minimize(&mut scene).unwrap();
        (out.steps, out.energy.to_bits())
    };
    let jammed_only = Masses::Blocks(PreconParams {
        jammed_only: true,
        ..PreconParams::default()
    });
    assert_eq!(with(jammed_only.clone()), with(Masses::Plain));
    assert_ne!(
        with(Masses::Blocks(PreconParams::default())),
        with(Masses::Plain)
    );
    let mut scene = compressed::<2, _>(dimer, 24, 5, 0.3);
    let mut fire = Fire::new(FireParams {
        masses: jammed_only,
        ..FireParams::default()
    });
    let params = jamkit_engine::JamParams::default();
    let out = jamkit_engine::jam(&mut scene, &mut fire, &params).unwrap();
    assert!(
        out.energy_per_particle > params.energy_low && out.energy_per_particle < params.energy_high,
        "V/N = {:e}",
        out.energy_per_particle
    );
}

/// `masses: Family` (the default) resolves, where the point's shape is
/// built, to the family's choice: block masses on jammed-only
/// minimisations for dimers in 3D, the plain masses for 2D dimers, every
/// other family
/// and for FIRE 2.0; an explicit choice is kept. The packing's settings
/// record the resolved masses (`Plain` by leaving them out).
#[test]
fn the_family_chooses_fires_masses_and_the_settings_record_its_choice() {
    let dimer = NmerParams {
        alpha: Some(1.1),
        spheres: None,
        inertia: None,
    };
    let jammed_only = Masses::Blocks(PreconParams {
        jammed_only: true,
        ..PreconParams::default()
    });
    let default = FireParams::default();
    assert_eq!(default.masses, Masses::Family);
    let dimer3 = Nmer::<3>::new(&dimer).unwrap();
    assert_eq!(default.for_family(&dimer3).masses, jammed_only);
    let dimer2 = Nmer::<2>::new(&dimer).unwrap();
    assert_eq!(default.for_family(&dimer2).masses, Masses::Plain, "2D");
    assert_eq!(
        default.for_family::<2, _>(&Sphere).masses,
        Masses::Plain,
        "disks"
    );
    assert_eq!(default.for_family::<3, _>(&Sphere).masses, Masses::Plain);
    let near_disk = NearDisk::fourier(&FourierParams {
        n: 2,
        delta: 0.1,
        inertia: None,
        gap: Default::default(),
    })
    .unwrap();
    assert_eq!(default.for_family(&near_disk).masses, Masses::Plain);
    let fire2 = FireParams {
        variant: FireVariant::Fire2,
        ..FireParams::default()
    };
    assert_eq!(fire2.for_family(&dimer3).masses, Masses::Plain, "FIRE 2.0");
    for chosen in [Masses::Plain, Masses::Blocks(PreconParams::default())] {
        let params = FireParams {
            masses: chosen.clone(),
            ..FireParams::default()
        };
        assert_eq!(params.for_family(&dimer3).masses, chosen);
    }
    assert_eq!(
        FireParams::paper().for_family(&dimer3).masses,
        Masses::Plain
    );

    let recorded = |e: jamkit_experiment::Experiment| recorded_minimizer(&e).get("masses").cloned();
    let nmer = |dim: usize, minimizer: &str| {
        small_experiment("nmer", dim, r#"{"alpha": 1.1}"#, 32, minimizer)
    };
    assert_eq!(
        recorded(nmer(3, "")),
        Some(serde_json::to_value(&jammed_only).unwrap())
    );
    assert_eq!(recorded(nmer(2, "")), None);
    assert_eq!(recorded(nmer(3, ", minimizer: (masses: Plain)")), None);
    assert_eq!(recorded(small_experiment("sphere", 2, "{}", 8, "")), None);
}

/// A run directory of packings made under the paper's summed force rule
/// (jamkit's default before `Max`; they record `force_criterion: "Sum"`)
/// is refused under the default, with the rule named and the fix said,
/// and resumed under an explicit `force_criterion: Sum`.
#[test]
fn summed_force_rule_packings_are_refused_under_the_default_and_resume_as_sum() {
    assert_eq!(FireParams::default().criterion(), ForceCriterion::Max);
    assert_eq!(FireParams::paper().criterion(), ForceCriterion::Sum);
    common::refused_then_resumed(
        &small_experiment("sphere", 2, "{}", 16, ", minimizer: (force_criterion: Sum)"),
        &small_experiment("sphere", 2, "{}", 16, ""),
        &[
            "minimizer.force_criterion",
            "\"Max\"",
            "\"Sum\" (the default before \"Max\"",
            "--set minimizer.force_criterion=Sum",
        ],
    );
}

/// A run directory of plain-mass dimer packings (as every run made before
/// the family's default existed; they record no `masses`) is refused under
/// the family's default, with the field named and the fix said, and
/// resumed under an explicit `masses: Plain`.
#[test]
fn plain_mass_packings_are_refused_under_the_family_default_and_resume_as_plain() {
    // `lbfgs: None` on both sides: the masses are the one difference here
    // (the L-BFGS default has its own test below).
    common::refused_then_resumed(
        &dimers3(", minimizer: (masses: Plain, lbfgs: None)"),
        &dimers3(", minimizer: (lbfgs: None)"),
        &[
            "minimizer.masses",
            "\"Blocks\"",
            "\"jammed_only\":true",
            "\"Plain\" (not written",
            "add `masses: Plain`",
        ],
    );
}

/// `bench packing` resolves its default masses as experiment files do:
/// the same packing as `--masses plain` for disks, as `--masses
/// blocks-jammed` for 3D dimers (which differs from the plain masses' one
/// here, else the check would be empty).
#[test]
fn bench_packing_takes_the_familys_masses() {
    let hash = bench_hash;
    let disks = ["--particles", "64"];
    assert_eq!(
        hash(&disks),
        hash(&[&disks[..], &["--masses", "plain"]].concat())
    );
    // Without L-BFGS, whose default for 3D dimers would leave FIRE's
    // masses unused on this small scene.
    let dimers = [
        "--family",
        "nmer",
        "--dim",
        "3",
        "--particles",
        "32",
        "--no-lbfgs",
    ];
    let family = hash(&dimers);
    assert_eq!(
        family,
        hash(&[&dimers[..], &["--masses", "family"]].concat())
    );
    assert_eq!(
        family,
        hash(&[&dimers[..], &["--masses", "blocks-jammed"]].concat())
    );
    assert_ne!(
        family,
        hash(&[&dimers[..], &["--masses", "plain"]].concat())
    );
}

/// L-BFGS from the start in the block metric is the family's choice for
/// dimers in 3D and no other family's: over every registered family in 2D
/// and 3D (its example parameters; `nmer`'s is a dimer), the recorded
/// `minimizer.lbfgs` of an experiment that leaves the field out is
/// `(after: 0, blocks: true)` for `nmer` in 3D and absent (no L-BFGS, so
/// the packings and their settings are those of before) everywhere else,
/// and for a 3D body of three spheres; FIRE 2.0, `lbfgs: None` and an
/// explicit `lbfgs` override the family.
#[test]
fn lbfgs_is_the_family_choice_of_3d_dimers_only() {
    use jamkit_registry::{EXAMPLES, FAMILIES, supports_dim};
    let recorded = |family: &str, dim: usize, params: &str, minimizer: &str| {
        let e = small_experiment(family, dim, params, 8, minimizer);
        recorded_minimizer(&e).get("lbfgs").cloned()
    };
    let family_default = serde_json::to_value(LbfgsChoice::family_default()).unwrap();
    let mut seen = 0;
    for (info, example) in FAMILIES.iter().zip(EXAMPLES) {
        let params = jamkit_registry::params_from_ron(example).unwrap();
        let params = ron::to_string(&params).unwrap();
        for dim in [2, 3] {
            if !supports_dim(info, dim) {
                continue;
            }
            seen += 1;
            let got = recorded(info.name, dim, &params, "");
            if info.name == "nmer" && dim == 3 {
                assert_eq!(got.as_ref(), Some(&family_default), "nmer 3D");
                for off in [
                    ", minimizer: (lbfgs: None)",
                    ", minimizer: (variant: Fire2)",
                ] {
                    assert_eq!(recorded(info.name, dim, &params, off), None, "{off}");
                }
            } else {
                assert_eq!(got, None, "{} {dim}D records L-BFGS", info.name);
            }
            let explicit = recorded(info.name, dim, &params, ", minimizer: (lbfgs: (after: 7))");
            assert_eq!(
                explicit.as_ref().and_then(|v| v["after"].as_u64()),
                Some(7),
                "{} {dim}D: an explicit lbfgs",
                info.name
            );
        }
    }
    assert!(seen >= 10, "only {seen} family/dimension pairs");
    let two = r#"{"spheres": [(offset: [0.0, 0.0, 0.0], radius: 0.5), (offset: [0.6, 0.0, 0.0], radius: 0.4)]}"#;
    let three = r#"{"spheres": [(offset: [0.0, 0.0, 0.0], radius: 0.5), (offset: [0.5, 0.0, 0.0], radius: 0.4), (offset: [0.0, 0.5, 0.0], radius: 0.4)]}"#;
    assert_eq!(
        recorded("nmer", 3, two, ""),
        Some(family_default),
        "two spheres"
    );
    assert_eq!(recorded("nmer", 3, three, ""), None, "a bent trimer");
}

/// L-BFGS as the 3D dimers' default leaves everything else bit for bit: the
/// default packings of the other families, and 3D dimers with
/// `--no-lbfgs` (experiment files: `lbfgs: None`), have the hashes that
/// `jamkit bench packing` of commit a8cbafb (FIRE for every family)
/// printed for these arguments (with the force rule and the search of
/// that commit's defaults, `--force-criterion sum --search extrapolated`,
/// and without the plateau escape, `--no-plateau-escape`, which moves the
/// 3D dimers' minimisations here).
/// The 3D dimers' default, `--lbfgs-after 0 --lbfgs-blocks`, makes other
/// packings here.
#[test]
fn the_lbfgs_default_leaves_other_families_and_no_lbfgs_as_they_were() {
    let hash = bench_hash;
    let dimers3 = ["--family", "nmer", "--dim", "3", "--particles", "32"];
    let cases: [(Vec<&str>, &str); 3] = [
        (vec!["--particles", "64"], "74b6d0966dd27b6f"),
        (
            vec!["--family", "nmer", "--dim", "2", "--particles", "64"],
            "41f437f54de38418",
        ),
        ([&dimers3[..], &["--no-lbfgs"]].concat(), "f9c97aeec4c4ba37"),
    ];
    for (args, old) in cases {
        let args = [
            &args[..],
            &[
                "--force-criterion",
                "sum",
                "--search",
                "extrapolated",
                "--no-plateau-escape",
            ],
        ]
        .concat();
        assert_eq!(hash(&args), old, "{args:?}");
    }
    let new = hash(&dimers3);
    assert_eq!(
        new,
        hash(&[&dimers3[..], &["--lbfgs-after", "0", "--lbfgs-blocks"]].concat())
    );
    assert_ne!(new, "f9c97aeec4c4ba37");
}

/// A run directory of 3D n-mer packings made before L-BFGS became their
/// default (they record no `lbfgs`) is refused under the new default, with
/// the field named and both fixes said, and resumes under an explicit
/// `lbfgs: None`.
#[test]
fn old_3d_nmer_packings_are_refused_under_the_lbfgs_default_and_resume_with_lbfgs_none() {
    let experiment = dimers3;
    common::refused_then_resumed(
        &experiment(", minimizer: (lbfgs: None)"),
        &experiment(""),
        &[
            "minimizer.lbfgs",
            "\"after\":0",
            "\"blocks\":true",
            "None (not written",
            "add `lbfgs: None`",
            "--set minimizer.lbfgs=None",
        ],
    );
    // The `--set` the message gives is the file's `lbfgs: None`, and a
    // `--set` of another field keeps the family's choice (left out, not
    // turned off).
    let set = |e: &jamkit_experiment::Experiment, kv: &str| {
        jamkit_experiment::overrides::apply(e, &[kv.to_string()]).unwrap()
    };
    let off = experiment(", minimizer: (lbfgs: None)");
    assert_eq!(set(&experiment(""), "minimizer.lbfgs=None"), off);
    assert_eq!(
        set(&experiment(""), "particles=16").minimizer.lbfgs,
        LbfgsChoice::Family
    );
    assert_eq!(set(&off, "particles=16").minimizer.lbfgs, LbfgsChoice::Off);
}

/// A packing made with L-BFGS records its evaluations (FIRE steps alone
/// would say 0 for a 3D n-mer), the same count `bench packing` prints for
/// the same packing, and results.csv gains an `lbfgs_evals` column; a
/// packing made without L-BFGS records none, and its table keeps its
/// columns.
#[test]
fn lbfgs_evaluations_are_recorded_where_lbfgs_ran() {
    let experiment =
        |family: &str, dim: usize, params: &str| small_experiment(family, dim, params, 32, "");
    let bench = |args: &[&str]| {
        let cells = bench_row(&[&["--particles", "32"][..], args].concat());
        (cells[4].clone(), cells[13].parse::<u64>().unwrap())
    };
    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&experiment("nmer", 3, r#"{"alpha": 1.1}"#), dir.path(), 1);
    let m = &report.packings[0].measures;
    let (phi, evals) = bench(&["--family", "nmer", "--dim", "3", "--alpha", "1.1"]);
    assert_eq!(format!("{:.6}", m.phi), phi, "the same packing");
    assert!(evals > 0);
    assert_eq!(m.lbfgs_evaluations, Some(evals));
    assert_eq!(m.fire_steps, 0, "L-BFGS from the start: no FIRE step");
    let table = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    assert!(
        table.lines().next().unwrap().ends_with(",lbfgs_evals"),
        "{table}"
    );
    assert!(
        table
            .lines()
            .nth(1)
            .unwrap()
            .ends_with(&format!(",{evals}"))
    );

    let dir = tempfile::tempdir().unwrap();
    let report = common::run_ok(&experiment("sphere", 2, "{}"), dir.path(), 1);
    assert_eq!(report.packings[0].measures.lbfgs_evaluations, None);
    let table = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    assert!(!table.contains("lbfgs_evals"), "{table}");
}

/// The cells of `jamkit bench packing --seeds 1 ARGS`' one packing row
/// (`seed,phi_j,…,packing_hash (10),…,lbfgs_evals (13)`).
fn bench_row(args: &[&str]) -> Vec<String> {
    let args = [&["bench", "packing", "--seeds", "1"][..], args].concat();
    let (code, text, err) = common::jamkit(&args);
    assert_eq!(code, 0, "{err}");
    let line = text.lines().nth(1).unwrap();
    line.split(',').map(String::from).collect()
}

/// The packing hash `jamkit bench packing --seeds 1 ARGS` prints.
fn bench_hash(args: &[&str]) -> String {
    bench_row(args)[10].clone()
}

/// One packing of `family` in `dim` dimensions with `params` (a RON map)
/// and `rest` after the seed (`, minimizer: (…)`, or empty).
fn small_experiment(
    family: &str,
    dim: usize,
    params: &str,
    particles: usize,
    rest: &str,
) -> jamkit_experiment::Experiment {
    let text = format!(
        r#"(name: "x", family: "{family}", dim: {dim}, params: {params}, particles: {particles}, samples: 1, seed: 1{rest})"#
    );
    jamkit_experiment::Experiment::from_ron(&text, "inline")
        .unwrap_or_else(|err| panic!("{text}: {err}"))
}

/// 32 dimers of α = 1.1 in 3D, `minimizer` after the seed.
fn dimers3(minimizer: &str) -> jamkit_experiment::Experiment {
    small_experiment("nmer", 3, r#"{"alpha": 1.1}"#, 32, minimizer)
}

/// The minimiser as the first packing of `e` records it (its settings).
fn recorded_minimizer(e: &jamkit_experiment::Experiment) -> serde_json::Value {
    let plan = jamkit_experiment::Plan::new(e).unwrap();
    plan.jobs[0].settings["minimizer"].clone()
}

/// `minimizer.lbfgs`' three states read and write back as they are:
/// left out is `Family` (and is left out again), `None` is `Off`, a
/// value is `On`; `Family` written alone is an error, since any value
/// would read back as another state.
#[test]
fn lbfgs_choice_reads_and_writes_its_three_states() {
    let read = |json: &str| serde_json::from_str::<FireParams>(json).unwrap().lbfgs;
    assert_eq!(read("{}"), LbfgsChoice::Family);
    assert_eq!(read(r#"{"lbfgs": null}"#), LbfgsChoice::Off);
    assert_eq!(
        read(r#"{"lbfgs": {"after": 7}}"#),
        LbfgsChoice::On(LbfgsParams {
            after: 7,
            ..LbfgsParams::default()
        })
    );
    for choice in [
        LbfgsChoice::Family,
        LbfgsChoice::Off,
        LbfgsChoice::On(LbfgsChoice::family_default()),
    ] {
        let params = FireParams {
            lbfgs: choice.clone(),
            ..FireParams::default()
        };
        let json = serde_json::to_value(&params).unwrap();
        assert_eq!(json.get("lbfgs").is_none(), choice.is_family());
        let back: FireParams = serde_json::from_value(json).unwrap();
        assert_eq!(back.lbfgs, choice);
    }
    assert!(serde_json::to_value(LbfgsChoice::Family).is_err());
}
