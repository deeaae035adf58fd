//! How one job of a run ended in this process: what the runner makes of
//! each job, and what the run's log reports of it.

use jamkit_format::PackingFile;

/// How one job ended in this process.
pub(crate) enum Outcome {
    /// Made here (`false`) or read back / measured on a saved packing
    /// (`true`).
    Done(Box<PackingFile>, bool),
    /// Another process holds its lock (the lock file's contents).
    Elsewhere(String),
    /// Not started: the run was asked to stop (`runner::Hooks::stop`).
    Stopped,
}
