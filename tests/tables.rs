//! The run tables as people load them: an absent optional parameter is an
//! empty cell (not `null`), a text parameter its plain text, and every row
//! has the header's number of cells.

use crate::common;
use jamkit_experiment::Experiment;

#[test]
fn results_csv_has_empty_cells_for_absent_optionals_and_plain_text() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"(name: "t", family: "fourier", params: {"n": 2, "delta": 0.1, "gap": ["FirstOrder", "SecondOrder"]},
        particles: 16, samples: 1, seed: 1, observables: [Contacts])"#;
    let e = Experiment::from_ron(text, "inline").unwrap();
    common::run_ok(&e, dir.path(), 1);
    let csv = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    assert!(!csv.contains("null"), "{csv}");
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2);
    let gaps: Vec<&str> = rows.iter().map(|r| r[col("gap")]).collect();
    assert_eq!(gaps, ["FirstOrder", "SecondOrder"]);
    for r in &rows {
        assert_eq!(r.len(), head.len());
        assert_eq!(r[col("inertia")], "", "inertia None is an empty cell");
        assert_eq!(r[col("n")], "2");
    }
}
