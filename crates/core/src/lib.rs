//! # jamkit-core
//!
//! The vocabulary every other jamkit crate speaks:
//!
//! * [`math`]: the only module that names the linear-algebra crate
//!   (`Vector<D>`, `RotVec`), so that the rest of the code reads as physics;
//! * [`periodic`]: the periodic box and its minimum-image convention;
//! * [`shape`]: the [`Shape`] trait a shape family implements, its geometry
//!   (volume, bounding radius, rotational coordinates and the *contacts*
//!   of a [`Pair`] of bodies), and the engine's optional fast paths
//!   ([`FastContacts`]);
//! * [`contact`]: a [`Pair`] of bodies and its [`Contact`]s, each a gap `h`
//!   with its derivatives; [`lanes`]: the same, several pairs side by side;
//! * [`policy`] and [`look`]: what a family says as plain data, the
//!   minimiser's and the analysis' [`Policy`] and the [`Look`] the drawing
//!   and export read;
//! * [`family`]: a family's one registration ([`Family`]), the
//!   [`ShapeVisitor`] the registry hands shapes to;
//! * [`rotation`]: [`Rotation2`] and [`Angle`], the planar orientations shared by the 2D
//!   families (the 2D near-disk gaps live in `jamkit-planar`);
//! * [`orientation`]: [`BodyOrientation`], what every orientation type does
//!   by itself (reference, random draw, file numbers), so families don't;
//! * [`quaternion`]: [`Quaternion`], the 3D orientation of the rigid 3D
//!   families (`nmer`, `harmonic`, `ellipsoid`; the exact gap of convex 3D
//!   bodies lives in `jamkit-gap3d`);
//! * [`potential`]: scalar contact potentials `v(h)` (harmonic, Hertzian);
//! * [`sizes`]: size distributions (binary, monodisperse, uniform);
//! * [`packing`]: a configuration of bodies in a box, in flat generalised
//!   coordinates;
//! * [`error`]: the errors the engine can report.
//!
//! Geometry (the gap) belongs to shapes, energy to potentials: a new family
//! never touches the potential, and a new potential never touches a family.

pub mod contact;
pub mod error;
pub mod family;
pub mod gap_model;
pub mod lanes;
pub mod look;
pub mod math;
pub mod orientation;
pub mod packing;
pub mod periodic;
pub mod policy;
pub mod potential;
pub mod quaternion;
pub mod records;
pub mod rotation;
pub mod shape;
pub mod sizes;
pub mod stats;

pub use contact::{Contact, GapHessian, MEMO_LEN, Pair, PairMemo, Warm};
pub use error::{Error, Result};
pub use family::{Added, Dims, Family, FamilyInfo, ParamSpec, ShapeVisitor};
pub use lanes::{ContactLanes, MAX_SLOTS, PairLanes, SlotPairs};
pub use look::{Look, Outline, RoundOutline, SharedOutline, SharedSurface, Surface};
pub use math::{MAX_ROT, Matrix, RotVec, Vector};
pub use orientation::BodyOrientation;
pub use packing::Packing;
pub use periodic::PeriodicBox;
pub use policy::Policy;
pub use potential::Potential;
pub use quaternion::Quaternion;
pub use rotation::{Angle, Rotation2};
pub use shape::{
    FastContacts, Kernel, NoFastPath, Shape, ShapeExt, contacts_one_by_one,
    contacts_warm_one_by_one,
};
pub use sizes::SizeDistribution;
