//! The benchmarks of `jamkit bench`, and the speed-against-error study of
//! `docs/reports/speed-vs-error.md`.
//!
//! * [`packing`]: whole jammed packings, one thread, each line ending with
//!   a hash of the final state (`bench packing`);
//! * [`eval`]: one energy-and-gradient evaluation against N (`bench eval`);
//! * [`spectrum`]: Hessian assembly and dense eigensolvers (`bench spectrum`);
//! * [`pair`]: time and error of one pair evaluation per near-disk gap
//!   model, with the fitted orders of the errors (`bench pair`);
//! * [`accuracy`]: the whole study, [`pair`] and two experiment files run
//!   by the runner and compared by `jamkit_report::accuracy` (`bench
//!   accuracy`).
//!
//! Each module's `Options` is its subcommand's flags (`clap::Args`), and
//! its `run` takes them and a sink for the lines the command prints on
//! standard output; progress goes to standard error. Files are written
//! only under the output directories the options name ([`output`]).

pub mod accuracy;
pub mod eval;
pub mod output;
pub mod packing;
pub mod pair;
pub mod spectrum;
