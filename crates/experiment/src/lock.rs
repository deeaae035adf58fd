//! Runs that share an output directory: a lock per packing under way, and
//! a refusal to mix settings.
//!
//! Parts of a run (`--shard`) or two identical runs may write into one
//! directory at the same time. Before making a packing a process creates
//! `packings/<id>.lock` exclusively (a file of its own, holding its host
//! name and process id, hard-linked to that name: the lock appears whole
//! or not at all), and removes it when the packing is saved or has failed; a
//! process that finds the lock held leaves that packing to its holder
//! (reported as *in flight elsewhere*; a later run gathers it). A lock left
//! by a process that died on the same host (no `/proc/<pid>`) is taken
//! over. One left by a dead process on another host cannot be told from a
//! live one: remove it by hand (docs/reference/output-files.md, "Atomic
//! writes and resuming").
//!
//! A packing file made with other settings (`sample::settings`: family,
//! parameters, sizes, protocol, minimiser, potential, rattlers, engine) is
//! never overwritten: the run is refused before it starts, naming the first
//! setting that differs, so that one directory never holds packings of two
//! experiments under one `experiment.ron`.

use crate::error::ExperimentError;
use std::path::{Path, PathBuf};

/// A held lock; dropping it removes the file.
#[derive(Debug)]
pub(crate) struct Held {
    path: PathBuf,
}

impl Drop for Held {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The outcome of [`claim`].
#[derive(Debug)]
pub(crate) enum Claim {
    /// This process makes the packing.
    Mine(Held),
    /// Another process does; its lock file's contents.
    Busy(String),
}

/// Where the lock of packing `id` lives.
pub fn lock_path(packing_dir: &Path, id: &str) -> PathBuf {
    packing_dir.join(format!("{id}.lock"))
}

/// `host=<name> pid=<id>` of this process.
fn holder() -> String {
    format!("host={} pid={}", host_name(), std::process::id())
}

fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .ok()
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

/// Whether a lock's holder is a dead process on this host.
fn stale(contents: &str) -> bool {
    let mut host = None;
    let mut pid = None;
    for word in contents.split_whitespace() {
        if let Some(h) = word.strip_prefix("host=") {
            host = Some(h);
        } else if let Some(p) = word.strip_prefix("pid=") {
            pid = p.parse::<u32>().ok();
        }
    }
    match (host, pid) {
        (Some(h), Some(p)) if h == host_name() => {
            p != std::process::id() && !Path::new(&format!("/proc/{p}")).exists()
        }
        _ => false,
    }
}

/// Take the lock of packing `id`, or say who holds it.
pub(crate) fn claim(packing_dir: &Path, id: &str) -> Result<Claim, ExperimentError> {
    let path = lock_path(packing_dir, id);
    // The lock appears with its contents or not at all: written to a file
    // of this process's own, then hard-linked to the lock's name (which
    // fails if the name exists). A process killed between an exclusive
    // create and its write would leave an empty lock that no one could
    // tell from a live one.
    let mine = packing_dir.join(format!("{id}.lock.{}", std::process::id()));
    std::fs::write(&mine, holder()).map_err(|e| ExperimentError::io(&mine, e))?;
    let claimed = (|| {
        for _ in 0..2 {
            match std::fs::hard_link(&mine, &path) {
                Ok(()) => return Ok(Claim::Mine(Held { path: path.clone() })),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let contents = std::fs::read_to_string(&path).unwrap_or_default();
                    if !stale(&contents) {
                        return Ok(Claim::Busy(contents.trim().to_string()));
                    }
                    // A dead holder on this host: take over (if another
                    // process takes it first, the next link says so).
                    let _ = std::fs::remove_file(&path);
                }
                Err(e) => return Err(ExperimentError::io(&path, e)),
            }
        }
        let contents = std::fs::read_to_string(&path).unwrap_or_default();
        Ok(Claim::Busy(contents.trim().to_string()))
    })();
    let _ = std::fs::remove_file(&mine);
    claimed
}

/// The first place where two settings records differ, as
/// `(key path, value in a, value in b)`; `None` when they are equal.
pub fn first_difference(
    a: &serde_json::Value,
    b: &serde_json::Value,
) -> Option<(String, String, String)> {
    use serde_json::Value;
    fn walk(a: &Value, b: &Value, path: &str) -> Option<(String, String, String)> {
        if a == b {
            return None;
        }
        if let (Value::Object(x), Value::Object(y)) = (a, b) {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            for k in keys {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                let (u, v) = (
                    x.get(k).unwrap_or(&Value::Null),
                    y.get(k).unwrap_or(&Value::Null),
                );
                if let Some(d) = walk(u, v, &p) {
                    return Some(d);
                }
            }
        }
        let show = |v: &Value| match v {
            Value::Null => "(not set)".to_string(),
            v => v.to_string(),
        };
        Some((path.to_string(), show(a), show(b)))
    }
    walk(a, b, "")
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn the_first_difference_is_named_with_its_path() {
        let a = json!({"protocol": {"Jam": {"eps": 0.001, "energy_low": 1e-16}}, "seed": 1});
        let b = json!({"protocol": {"Jam": {"eps": 0.002, "energy_low": 1e-16}}, "seed": 1});
        let (k, x, y) = first_difference(&a, &b).unwrap();
        assert_eq!(k, "protocol.Jam.eps");
        assert_eq!((x.as_str(), y.as_str()), ("0.001", "0.002"));
        assert!(first_difference(&a, &a).is_none());
        let c = json!({"protocol": {"Jam": {"eps": 0.001, "energy_low": 1e-16, "search": "Extrapolated"}}, "seed": 1});
        let (k, x, _) = first_difference(&a, &c).unwrap();
        assert_eq!(
            (k.as_str(), x.as_str()),
            ("protocol.Jam.search", "(not set)")
        );
    }

    #[test]
    fn a_lock_is_exclusive_and_released_on_drop() {
        let dir = tempfile_dir();
        let Claim::Mine(held) = claim(&dir, "a").unwrap() else {
            panic!("the first claim must succeed");
        };
        // This process holds it: alive, so a second claim is refused.
        match claim(&dir, "a").unwrap() {
            Claim::Busy(who) => assert!(who.contains(&format!("pid={}", std::process::id()))),
            Claim::Mine(_) => panic!("a held lock was taken twice"),
        }
        drop(held);
        assert!(!lock_path(&dir, "a").exists());
        assert!(matches!(claim(&dir, "a").unwrap(), Claim::Mine(_)));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_dead_holders_lock_is_taken_over_and_another_hosts_is_not() {
        let dir = tempfile_dir();
        // pid 0 never names a live process in /proc.
        std::fs::write(lock_path(&dir, "b"), format!("host={} pid=0", host_name())).unwrap();
        let Claim::Mine(held) = claim(&dir, "b").unwrap() else {
            panic!("a dead holder's lock must be taken over");
        };
        drop(held);
        std::fs::write(lock_path(&dir, "c"), "host=elsewhere.example pid=1").unwrap();
        assert!(matches!(claim(&dir, "c").unwrap(), Claim::Busy(w) if w.contains("elsewhere")));
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn tempfile_dir() -> PathBuf {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let d = std::env::temp_dir().join(format!(
            "jamkit-lock-test-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&d).unwrap();
        d
    }
}
