//! The AVX2 copies of the hot loops (chosen at run time, `jamkit_engine::simd`)
//! give the same packings, bit for bit, as the baseline x86-64 copies that
//! `JAMKIT_PORTABLE=1` forces. On a CPU without AVX2 both runs take the
//! baseline path and the test is trivially true.

use std::process::Command;

/// `bench packing` lines without the timing columns (wall s, µs per step,
/// CPU s).
fn packings(args: &[&str], portable: bool) -> Vec<String> {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_jamkit"));
    cmd.args(["bench", "packing"]).args(args);
    if portable {
        cmd.env("JAMKIT_PORTABLE", "1");
    } else {
        cmd.env_remove("JAMKIT_PORTABLE");
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .skip(1)
        .map(|line| {
            let cols: Vec<&str> = line.split(',').collect();
            [&cols[..8], &cols[10..12]].concat().join(",")
        })
        .collect()
}

#[test]
fn avx2_and_baseline_paths_give_identical_packings() {
    for args in [
        &["--particles", "64", "--seeds", "1,2"][..],
        &["--particles", "64", "--seeds", "1", "--dim", "3"],
        &["--particles", "64", "--seeds", "1", "--minimizer", "newton"],
        &["--particles", "32", "--seeds", "1", "--family", "fourier"],
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
    ] {
        let fast = packings(args, false);
        assert!(!fast.is_empty());
        assert_eq!(fast, packings(args, true), "{args:?}");
    }
}
