//! The `lobed` family (the example of `docs/tutorials/new-shape-rust.md`)
//! in the engine: the conformance kit on blunt to sharp lobes, and its
//! example experiment end to end.

use crate::common;
use jamkit_experiment::{Experiment, overrides};
use jamkit_lobed::{Lobed, LobedParams};
use std::path::Path;

fn lobed(delta: f64, kappa: f64) -> Lobed {
    jamkit_lobed::lobed(&LobedParams {
        delta,
        kappa,
        inertia: None,
    })
    .unwrap()
}

/// Blunt, medium and sharp lobes.
fn shapes() -> Vec<Lobed> {
    vec![
        lobed(0.3, 0.3),
        lobed(0.2, 1.0),
        lobed(0.1, 5.0),
        lobed(0.05, 20.0),
    ]
}

/// The conformance kit (`crates/kit`): forces and torques against finite
/// differences, the Hessian, `h_ij = h_ji`, translation and rotation
/// invariance, and a small jamming run, for blunt to sharp lobes (the
/// tolerances and their reasons are in the kit). The registered example
/// also runs through the registry in `tests/conformance.rs`.
#[test]
fn blunt_to_sharp_lobes_pass_the_kit() {
    for shape in shapes() {
        let done = jamkit_kit::check_family::<2, _>(shape);
        assert!(done.ran.contains(&"hessian") && done.ran.contains(&"rotation"));
    }
}

/// `experiments/examples/lobed.ron`, shrunk to N = 32 and one sample per Δ,
/// jams every packing into the paper's window 1e-16 < V/N < 2e-16.
#[test]
fn example_experiment_jams() {
    let report = common::run_file(
        "experiments/examples/lobed.ron",
        &["particles=32", "samples=1"],
        2,
    );
    assert_eq!(report.packings.len(), 2, "one packing per Δ");
    for p in &report.packings {
        assert_eq!(p.family, "lobed");
        common::assert_in_window(p);
        assert!(p.orientations.iter().all(|o| o.len() == 1));
    }
}

/// `--set params.inertia=0.5` (a bare number, no `Some`) reaches the family,
/// and a κ out of range is refused with the field named.
#[test]
fn parameters_can_be_set_from_the_command_line() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/examples/lobed.ron");
    let e = Experiment::from_file(&file).unwrap();
    for set in ["params.inertia=0.5", "params.inertia=Some(0.5)"] {
        let e = overrides::apply(&e, &[set.into()]).unwrap();
        e.validate().unwrap();
        jamkit_experiment::Plan::new(&e).unwrap_or_else(|err| panic!("{set}: {err}"));
    }
    let e = overrides::apply(&e, &["params.kappa=0.05".into()]).unwrap();
    let err = jamkit_experiment::Plan::new(&e).err().unwrap().to_string();
    assert!(err.contains("params.kappa"), "{err}");
}
