//! Which jamkit wrote a file: the crate version and, when built from a git
//! checkout, the commit. Every packing file and `experiment.ron` records
//! it, so that a result can be traced to the code that made it; files
//! written before it was recorded load as before.

/// The version of jamkit (the workspace's `version`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit jamkit was built from, if it was built from a checkout.
pub fn git_commit() -> Option<&'static str> {
    let commit = env!("JAMKIT_GIT_COMMIT");
    (!commit.is_empty()).then_some(commit)
}

/// One line for humans and file headers: `jamkit 0.1.0 (git 1ffea38…)`,
/// or `jamkit 0.1.0` outside a checkout.
pub fn describe() -> String {
    match git_commit() {
        Some(c) => format!("jamkit {VERSION} (git {c})"),
        None => format!("jamkit {VERSION}"),
    }
}

/// `(jamkit_version, git_commit)` of a packing file made now.
pub fn stamp() -> (Option<String>, Option<String>) {
    (Some(VERSION.to_string()), git_commit().map(String::from))
}
