//! A file that cannot be written is reported once, by the name the user
//! gave, and leaves no temporary file behind.

use std::path::Path;

mod common;
use common::jamkit;

/// `jamkit export … -o nodir/x.xyz`: the message names `nodir/x.xyz` (not
/// the temporary file beside it) and gives the cause once.
#[test]
fn a_write_into_a_missing_directory_names_the_file_once() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    common::small_quickstart(&run, 1, &[]);
    let target = tmp.path().join("nodir/x.xyz");
    let (code, _, err) = jamkit(&[
        "export",
        run.to_str().unwrap(),
        "-o",
        target.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains(target.to_str().unwrap()), "{err}");
    assert!(!err.contains("x.tmp"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

/// A write that fails at the rename (the target is a directory) removes
/// its temporary file.
#[test]
fn a_failed_write_leaves_no_temporary_file() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("taken");
    std::fs::create_dir(&target).unwrap();
    let err = jamkit_format::write_atomic(&target, b"data").unwrap_err();
    assert!(
        err.to_string().starts_with(target.to_str().unwrap()),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("taken")]);
    assert!(Path::new(&target).is_dir());
}
