//! What the benchmarks share about their output: the sink of the lines
//! they print, files written whole, and the commit and machine a
//! measurement names.

use anyhow::{Context, Result};
use std::path::Path;

/// Where a benchmark sends each line of its standard output (without the
/// newline): the command line prints them, a test collects them.
pub type Print<'a> = &'a mut dyn FnMut(&str);

/// Write `text` to `path` atomically (a reader never sees half a file).
pub fn write(path: &Path, text: &str) -> Result<()> {
    jamkit_format::write_atomic(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// The commit (marked when the tree has uncommitted changes) and the
/// machine (CPU model and cores) a benchmark ran on.
pub fn environment() -> (String, String) {
    let cmd = |prog: &str, args: &[&str]| {
        std::process::Command::new(prog)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let mut commit =
        cmd("git", &["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
    if cmd("git", &["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty())
    {
        commit.push_str(" (with uncommitted changes)");
    }
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| cpu_model(&s))
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(0);
    (commit, format!("{cpu}, {cores} cores"))
}

/// The first `model name` of a `/proc/cpuinfo` text.
fn cpu_model(cpuinfo: &str) -> Option<String> {
    cpuinfo
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map(|m| m.trim().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_model_is_the_first_model_name_line() {
        let info = "processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel name\t: AMD EPYC 7B13\n\
                    processor\t: 1\nmodel name\t: other\n";
        assert_eq!(cpu_model(info).as_deref(), Some("AMD EPYC 7B13"));
        assert_eq!(cpu_model("processor\t: 0\n"), None);
    }

    #[test]
    fn write_creates_the_file_and_names_a_path_it_cannot_write() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.md");
        write(&path, "text\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "text\n");
        let bad = dir.path().join("absent/t.md");
        let err = format!("{:#}", write(&bad, "x").unwrap_err());
        assert!(err.contains("absent/t.md"), "{err}");
    }
}
