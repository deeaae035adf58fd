//! jamkit's files, to read and write without running anything: the
//! packing file (`record`), its validation on load, the atomic writer, and
//! the tables a run writes beside its packings (`tables`: `results.csv`,
//! `summary.csv`, `dos.csv`, `gaps.csv`, through the `csv` crate), and the
//! GSD file layer (`gsd`, HOOMD-blue's format). The
//! drawing and report crates and `jamkit spectrum` depend on this crate,
//! not on the runner (`jamkit-experiment`), so reading a packing does not
//! pull in the thread pool, the progress bars or the families. Formats:
//! `docs/reference/output-files.md`.

pub mod error;
pub mod gsd;
pub mod provenance;
pub mod record;
pub mod tables;

pub use error::FormatError;
pub use jamkit_core::stats::mean_sem;
pub use record::{
    CellContacts, JamPoint, Measures, ModuliMeasures, PackingFile, SoftestMode, SpectrumMeasures,
    Stabilisation, without_configuration, write_atomic,
};
pub use tables::{
    PointSummary, dos_csv, gaps_csv, pooled_histogram, results_csv, summarize_points, summary_csv,
};
