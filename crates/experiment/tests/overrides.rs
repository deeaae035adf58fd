//! `--set KEY=VALUE` on an experiment: top-level, nested and enum fields,
//! lists, and the errors that name a wrong key or value.

use jamkit_experiment::overrides::apply;
use jamkit_experiment::{Experiment, schema};

fn base() -> Experiment {
    Experiment::from_ron(r#"(name: "t", family: "sphere", particles: 16)"#, "t").unwrap()
}

#[test]
fn sets_top_level_nested_and_enum_fields() {
    let sets = [
        "particles=[8, 16]",
        "protocol.eps=1e-4",
        "minimizer.variant=Fire2",
        "samples=3",
        "rattlers.min_contacts=Some(2)",
        "potential=Hertzian",
        "observables=[Contacts]",
        "name=trial",
    ];
    let e = apply(&base(), &sets.map(String::from)).unwrap();
    assert_eq!(e.particles.values(), vec![8, 16]);
    assert_eq!(e.samples, 3);
    assert_eq!(e.minimizer.variant, jamkit_engine::FireVariant::Fire2);
    assert_eq!(e.rattlers.min_contacts, Some(2));
    assert_eq!(e.potential, jamkit_core::Potential::Hertzian);
    assert_eq!(e.observables, vec![schema::Observable::Contacts]);
    // `Gaps()`: a struct variant with its defaults, as in a file.
    let g = apply(
        &base(),
        &["observables=[Contacts, Gaps(), Spectrum(modes: true)]".into()],
    )
    .unwrap();
    assert_eq!(g.gaps(), Some(jamkit_observe::gaps::GapParams::default()));
    assert!(g.spectrum().is_some_and(|s| s.modes));
    assert_eq!(e.name, "trial");
    match e.protocol {
        schema::Protocol::Jam { eps, .. } => assert_eq!(eps, 1e-4),
        other => panic!("{other:?}"),
    }
    let sets = [
        "protocol=Phi(phi: 0.9, eps: 0.01)",
        "sizes=Mono(radius: 0.5)",
        "rattlers.min_contacts=None",
    ];
    let e = apply(&e, &sets.map(String::from)).unwrap();
    assert_eq!(
        e.protocol,
        schema::Protocol::Phi {
            phi_start: 0.1,
            phi: schema::OneOrMany::One(0.9),
            eps: 0.01
        }
    );
    assert_eq!(e.sizes, jamkit_core::SizeDistribution::Mono { radius: 0.5 });
    assert_eq!(e.rattlers.min_contacts, None);
}

/// `dim` takes a value or a list, like `particles`; a list back to one
/// value is the plain number again (what the settings record).
#[test]
fn dim_takes_a_value_or_a_list() {
    use jamkit_experiment::schema::OneOrMany;
    let both = apply(&base(), &["dim=[2, 3]".into()]).unwrap();
    assert_eq!(both.dim, OneOrMany::Many(vec![2, 3]));
    let three = apply(&both, &["dim=3".into()]).unwrap();
    assert_eq!(three.dim, OneOrMany::One(3));
    assert_eq!(
        serde_json::to_value(&three.dim).unwrap(),
        serde_json::json!(3)
    );
    let err = apply(&base(), &["dim=two".into()]).unwrap_err().to_string();
    assert!(err.contains("a value or a list of values"), "{err}");
}

#[test]
fn unknown_key_is_named() {
    let err = apply(&base(), &["protocol.epz=1".into()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("epz") && err.contains("eps"), "{err}");
    let err = apply(&base(), &["output.nothing.deeper=1".into()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("nothing") && err.contains("packings"), "{err}");
    let err = apply(&base(), &["particles=-3".into()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("not a valid experiment"), "{err}");
}

/// An override edits one field and keeps every other as the file set it,
/// including settings that differ from their defaults and that a packing's
/// record leaves out (`unjam_forecast: false`, `masses: Plain`,
/// `escape_saddles: false`, `rejams: 0`): the experiment goes through its
/// serialised form and back.
#[test]
fn an_override_keeps_the_other_fields_that_differ_from_their_defaults() {
    let jam = Experiment::from_ron(
        r#"(name: "t", family: "sphere", particles: 16,
            protocol: Jam(escape_saddles: false),
            minimizer: (unjam_forecast: false, masses: Plain, force_criterion: Sum))"#,
        "t",
    )
    .unwrap();
    let edited = apply(&jam, &["seed=2".into()]).unwrap();
    assert_eq!(edited.seed, 2);
    assert_eq!(edited.minimizer, jam.minimizer);
    assert!(!edited.minimizer.unjam_forecast);
    assert_eq!(edited.minimizer.masses, jamkit_engine::Masses::Plain);
    assert_eq!(edited.protocol, jam.protocol);
    match edited.protocol {
        schema::Protocol::Jam { escape_saddles, .. } => assert!(!escape_saddles),
        other => panic!("expected Jam, got {other:?}"),
    }

    let above = Experiment::from_ron(
        r#"(name: "t", family: "sphere", particles: 16,
            protocol: AboveJam(delta_phi: 1e-3, rejams: 0))"#,
        "t",
    )
    .unwrap();
    let edited = apply(&above, &["samples=2".into()]).unwrap();
    assert_eq!(edited.protocol, above.protocol);
    match edited.protocol {
        schema::Protocol::AboveJam { rejams, .. } => assert_eq!(rejams, 0),
        other => panic!("expected AboveJam, got {other:?}"),
    }
}
