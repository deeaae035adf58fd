//! # jamkit-experiment
//!
//! Experiments are data. A RON file names a family and its parameters, the
//! number of particles and samples, the protocol and the observables; this
//! crate turns it into packings on disk:
//!
//! * [`schema`]: the experiment file's fields, defaults and validation;
//! * [`overrides`]: `--set KEY=VALUE` edits of any field;
//! * [`grid`]: expansion of lists into parameter points and samples;
//! * [`plan`]: an experiment made ready to run, once: validated, its grid
//!   expanded, each point's shape built, every job listed with its settings;
//! * [`memory`]: the dense eigen-solves of an experiment against the
//!   machine's memory, checked at validation;
//! * [`registry`]: the explicit list of shape families, and the one place
//!   where a family name becomes a typed `Scene<D, S>`;
//! * [`runner`]: runs the samples in parallel, resumes, collects records;
//! * [`record`]: packing files, `results.csv`, `summary.csv`, `dos.csv`
//!   and `gaps.csv`, written atomically;
//! * [`analyze`]: a sphere packing from another code (extended XYZ or
//!   `x y (z) r` text) measured as our own (`jamkit analyze`);
//! * [`extxyz`], [`gsd`]: packings as extended XYZ and as HOOMD-blue's
//!   GSD (`jamkit export`);
//! * [`archive`]: a run's measures without the configurations, small
//!   enough to commit (`jamkit archive`);
//! * [`reload`]: a saved packing back as a typed scene (for the spectrum of
//!   a packing on disk, and for new observables on a resumed run).

pub mod analyze;
pub mod archive;
pub mod batchlog;
pub mod error;
pub mod extxyz;
pub mod grid;
pub mod gsd;
pub mod lock;
pub mod memory;
pub mod merge;
mod outcome;
pub mod overrides;
mod paper;
pub mod plan;
pub mod reload;
pub mod runner;
pub mod sample;
pub mod schema;

pub use batchlog::Log;
pub use error::ExperimentError;
pub use plan::Plan;
pub use schema::Experiment;
