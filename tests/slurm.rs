//! The Slurm path of docs/how-to/slurm.md on a real one-node cluster:
//! `tests/slurm/run.sh` installs Slurm and MUNGE from Debian's packages if
//! needed, starts slurmctld and slurmd on this machine, runs
//! `experiments/slurm/jam-array.sbatch` as a 4-task array, gathers, and
//! compares with one plain run (timing aside).
//!
//! It needs root (it starts the daemons). Under CI (`CI` set), which runs as
//! root, a missing root is a failure; on a developer's machine without root
//! the test says it did not run and passes.

use std::path::Path;
use std::process::Command;

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

#[test]
fn a_slurm_array_gathers_to_one_plain_run() {
    let ci = std::env::var_os("CI").is_some_and(|v| !v.is_empty());
    if !is_root() {
        assert!(!ci, "CI must run the Slurm test as root");
        eprintln!("slurm test not run: it needs root (tests/slurm/run.sh)");
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("bash")
        .arg(root.join("tests/slurm/run.sh"))
        .arg(env!("CARGO_BIN_EXE_jamkit"))
        .current_dir(root)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}\n{err}");
    assert!(
        text.contains("4 array tasks gathered = one plain run"),
        "{text}\n{err}"
    );
}
