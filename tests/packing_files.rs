//! A packing file that no computation can use is refused on load with an
//! error naming the file, the field, the value and what is allowed — never
//! a panic (before, `jamkit spectrum` panicked on a zero radius in the
//! neighbour list and accepted negative radii and a zero box).

use std::path::Path;

use crate::common;
use common::jamkit;

#[test]
fn broken_packing_files_are_refused_by_name() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let (code, _, err) = jamkit(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "particles=16",
        "--set",
        "samples=1",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let good: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("packings/sphere_d2_N16_s1.json")).unwrap(),
    )
    .unwrap();
    let spectrum = |v: &serde_json::Value, name: &str| {
        let path = tmp.path().join(format!("{name}.json"));
        std::fs::write(&path, serde_json::to_string(v).unwrap()).unwrap();
        let eig = tmp.path().join(format!("{name}.csv"));
        jamkit(&[
            "spectrum",
            path.to_str().unwrap(),
            "--out",
            eig.to_str().unwrap(),
        ])
    };
    // The good file works.
    let (code, _, err) = spectrum(&good, "good");
    assert_eq!(code, 0, "{err}");
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 6] = [
        (
            "zero_radius",
            |v| v["radii"][3] = 0.0.into(),
            "radii[3] = 0: must be positive and finite",
        ),
        (
            "negative_radius",
            |v| v["radii"][0] = (-0.5).into(),
            "radii[0] = -0.5: must be positive",
        ),
        (
            "zero_box",
            |v| v["box"][1] = 0.0.into(),
            "box[1] = 0: must be positive and finite",
        ),
        (
            "short_box",
            |v| v["box"] = serde_json::json!([10.0]),
            "box = 1 edges",
        ),
        (
            "missing_centre",
            |v| {
                v["positions"].as_array_mut().unwrap().pop();
            },
            "positions = 15 entries: must have one entry per body",
        ),
        (
            "bad_dim",
            |v| v["dim"] = 7.into(),
            "dim = 7: must be 2, 3 or 4",
        ),
    ];
    for (name, edit, needle) in cases {
        let mut v = good.clone();
        edit(&mut v);
        let (code, _, err) = spectrum(&v, name);
        assert_eq!(code, 1, "{name}: exit {code} (101 is a panic): {err}");
        assert!(err.contains(needle), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}.json")),
            "{name}: the file is named: {err}"
        );
    }
}
