//! # jamkit-observe
//!
//! What is measured on a packing once it is made:
//!
//! * [`contacts`]: the contact network (`h < 0`) and iterative rattler
//!   removal;
//! * [`summary`]: contact number, rattler fraction, pressure and the
//!   isostaticity margin of a jammed packing.

pub mod contacts;
pub mod summary;

pub use contacts::{ContactNetwork, find_rattlers};
pub use summary::{JammingSummary, summarize};
