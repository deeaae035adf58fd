//! Every packing file and `experiment.ron` names the jamkit that wrote it
//! (version, and the git commit of a build from a checkout), and files
//! written before that was recorded still load, resume and merge.

use jamkit_format::PackingFile;
use std::path::Path;

use crate::common;
use common::{jamkit, packing_paths, quickstart};

const VERSION: &str = env!("CARGO_PKG_VERSION");

/// A quickstart of 16 disks and 2 samples into `out`, `extra` appended.
fn small_run(out: &Path, extra: &[&str]) {
    common::small_quickstart(out, 2, extra);
}

#[test]
fn packings_and_experiment_ron_name_the_jamkit_that_wrote_them() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    small_run(&out, &[]);
    let from_checkout = Path::new(env!("CARGO_MANIFEST_DIR")).join(".git").exists();
    for path in packing_paths(&out) {
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(json["jamkit_version"], VERSION, "{}", path.display());
        if from_checkout {
            let commit = json["git_commit"].as_str().unwrap_or_default();
            assert!(!commit.is_empty(), "{}: no git_commit", path.display());
        }
    }
    let ron = std::fs::read_to_string(out.join("experiment.ron")).unwrap();
    let first = ron.lines().next().unwrap_or_default();
    assert!(
        first.starts_with(&format!("// jamkit {VERSION}")),
        "experiment.ron begins with {first:?}"
    );
    let (code, version, _) = jamkit(&["--version"]);
    assert_eq!(code, 0);
    assert!(version.contains(VERSION), "{version}");
}

/// Removes what a file written before provenance lacks: the two keys of
/// every packing file, the header line of `experiment.ron`.
fn make_old(dir: &Path) {
    for path in packing_paths(dir) {
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let map = json.as_object_mut().unwrap();
        assert!(map.remove("jamkit_version").is_some());
        map.remove("git_commit");
        std::fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    }
    let path = dir.join("experiment.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let body: Vec<&str> = text.lines().skip_while(|l| l.starts_with("//")).collect();
    std::fs::write(&path, body.join("\n")).unwrap();
}

#[test]
fn files_without_provenance_load_resume_and_merge() {
    let tmp = tempfile::tempdir().unwrap();
    let old = tmp.path().join("old");
    small_run(&old, &[]);
    make_old(&old);
    for path in packing_paths(&old) {
        let file = PackingFile::load_checked(&path).unwrap();
        assert_eq!((file.jamkit_version, file.git_commit), (None, None));
    }
    // A rerun reuses the old packings as they are: nothing to measure again.
    let before: Vec<String> = packing_paths(&old)
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let (code, out_text, err) = jamkit(&[
        "run",
        quickstart().as_str(),
        "--out",
        old.to_str().unwrap(),
        "--set",
        "particles=16",
        "--set",
        "samples=2",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out_text.contains("(2 reused"), "{out_text}");
    let after: Vec<String> = packing_paths(&old)
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    assert_eq!(before, after);
    // One part written without the header, one with it: one experiment.
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    small_run(&a, &["--shard", "1/2"]);
    small_run(&b, &["--shard", "2/2"]);
    make_old(&a);
    let merged = tmp.path().join("merged");
    let (code, _, err) = jamkit(&[
        "merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(packing_paths(&merged).len(), 2);
}

/// A packing file committed with the study data, written before the
/// version was recorded, loads.
#[test]
fn a_committed_old_packing_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments/paper3d/data/paper3d-n512/packings");
    let path = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "json"))
        .expect("a committed packing");
    let file = PackingFile::load_checked(&path).unwrap();
    assert_eq!(file.jamkit_version, None);
    assert!(file.particles > 0);
}
