//! `jamkit archive`: a run's measures without the configurations. The
//! archive must be smaller, keep every measure, leave a packing in flight
//! out, hold the tables of the packings it holds (a finished run's own,
//! byte for byte), and give `jamkit report` the same fits as the run itself.

use crate::common;
use jamkit_experiment::Experiment;
use jamkit_experiment::archive::archive;
use jamkit_format::{PackingFile, without_configuration};

#[test]
fn archive_keeps_measures_and_gives_the_same_report() {
    let run = tempfile::tempdir().unwrap();
    let text = r#"(name: "arch", family: "fourier",
        params: {"n": 2, "delta": [0.01, 0.03, 0.1, 0.3]}, particles: [16, 32], samples: 2, seed: 7,
        observables: [Contacts, Spectrum(), Gaps(h_min: 1e-8, points_per_decade: 4)])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    common::run_ok(&e, run.path(), 2);
    // A packing "in flight": its lock is present.
    let packings = run.path().join("packings");
    let mut ids: Vec<String> = std::fs::read_dir(&packings)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    ids.sort();
    assert_eq!(ids.len(), 16);
    let tables = ["results.csv", "summary.csv", "dos.csv", "gaps.csv"];
    // A finished run's archive holds the run's own tables, byte for byte
    // (written again from the archived packings, in the run's order).
    let whole = tempfile::tempdir().unwrap();
    assert_eq!(archive(run.path(), whole.path()).unwrap().packings, 16);
    for table in std::iter::once("experiment.ron").chain(tables) {
        assert_eq!(
            std::fs::read(run.path().join(table)).unwrap(),
            std::fs::read(whole.path().join(table)).unwrap(),
            "{table}"
        );
    }
    // A directory whose experiment.ron is another file of the same grid
    // without `Gaps` (several files run into one directory, as the
    // paper-size profile was) keeps its gap table: the packings hold gaps.
    let own = std::fs::read(run.path().join("experiment.ron")).unwrap();
    let without_gaps = text.replace(", Gaps(h_min: 1e-8, points_per_decade: 4)", "");
    assert_ne!(without_gaps, text);
    std::fs::write(run.path().join("experiment.ron"), &without_gaps).unwrap();
    let other = tempfile::tempdir().unwrap();
    archive(run.path(), other.path()).unwrap();
    assert_eq!(
        std::fs::read(run.path().join("gaps.csv")).unwrap(),
        std::fs::read(other.path().join("gaps.csv")).unwrap()
    );
    std::fs::write(run.path().join("experiment.ron"), own).unwrap();
    let busy = &ids[0];
    std::fs::write(packings.join(format!("{busy}.lock")), "host=x pid=1").unwrap();

    let out = tempfile::tempdir().unwrap();
    let report = archive(run.path(), out.path()).unwrap();
    assert_eq!((report.packings, report.in_flight), (15, 1));
    // At N = 16 and 32 the binned spectrum is most of a file; at N = 1024
    // the configuration is (125 kB against 2–5 kB).
    assert!(
        report.bytes.1 < report.bytes.0,
        "{:?} bytes before and after",
        report.bytes
    );
    assert!(
        !out.path()
            .join("packings")
            .join(format!("{busy}.json"))
            .exists()
    );
    for id in &ids[1..] {
        let name = format!("{id}.json");
        let full = PackingFile::load_checked(&packings.join(&name)).unwrap();
        let kept = PackingFile::load_checked(&out.path().join("packings").join(&name)).unwrap();
        assert!(kept.positions.is_empty() && kept.radii.is_empty());
        assert_eq!(kept, without_configuration(&full), "{id}");
    }
    // With a packing left out, the tables are those of the 15 archived
    // (the run's own still count 16): its point has one sample, not two.
    let read =
        |dir: &std::path::Path, table: &str| std::fs::read_to_string(dir.join(table)).unwrap();
    assert_eq!(
        read(run.path(), "experiment.ron"),
        read(out.path(), "experiment.ron")
    );
    let results = read(out.path(), "results.csv");
    assert_eq!(results.lines().count(), 1 + 15, "{results}");
    assert!(!results.contains(busy.as_str()), "{results}");
    let summary = read(out.path(), "summary.csv");
    let column = summary
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "samples")
        .unwrap();
    let samples: Vec<&str> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(column).unwrap())
        .collect();
    assert_eq!(samples.len(), 8, "{summary}");
    assert_eq!(
        samples.iter().filter(|&&n| n == "1").count(),
        1,
        "{summary}"
    );
    assert_eq!(
        samples.iter().filter(|&&n| n == "2").count(),
        7,
        "{summary}"
    );
    assert_ne!(read(run.path(), "summary.csv"), summary);

    // The report of the archive is the report of the run, fit for fit
    // (the busy packing left out of both).
    std::fs::remove_file(packings.join(format!("{busy}.json"))).unwrap();
    let options = jamkit_report::Options {
        resamples: 50,
        ..Default::default()
    };
    let figs = tempfile::tempdir().unwrap();
    let from_run =
        jamkit_report::report(&[run.path().to_path_buf()], figs.path(), &options).unwrap();
    let from_archive =
        jamkit_report::report(&[out.path().to_path_buf()], figs.path(), &options).unwrap();
    assert!(!from_run.fits.is_empty());
    assert_eq!(from_run.fits.len(), from_archive.fits.len());
    for (a, b) in from_run.fits.iter().zip(&from_archive.fits) {
        assert_eq!(
            (&a.quantity, a.n, a.particles),
            (&b.quantity, b.n, b.particles)
        );
        assert_eq!(a.fit, b.fit, "{}", a.quantity);
    }
}

#[test]
fn archive_names_a_missing_run() {
    let out = tempfile::tempdir().unwrap();
    let err = archive(&out.path().join("nowhere"), out.path())
        .unwrap_err()
        .to_string();
    assert!(err.contains("nowhere"), "{err}");
}
