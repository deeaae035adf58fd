//! The shape-family trait.
//!
//! A *shape family* (disks and spheres, Fourier near-disks, rigid n-mers, …)
//! describes one kind of body up to a scale `R⁰` (its *size*) and an
//! orientation. [`Shape`] is its geometry, and only that:
//!
//! * how many rotational coordinates a body has ([`Shape::rot_dof`]: zero for
//!   spheres, so that a sphere scene carries no rotational coordinates at all),
//!   and how a small change of them moves the orientation ([`Shape::rotate`]);
//! * its volume, a bounding radius (for the packing fraction and the
//!   neighbour list) and its moment of inertia;
//! * the **contacts** between two bodies ([`Shape::contacts`]): each a gap
//!   `h` (negative when the bodies overlap) with its derivatives with respect
//!   to the separation and to both bodies' rotational coordinates, and, for
//!   the Hessian, their second derivatives ([`Shape::gap_hessians`]);
//!   a family whose gap is an iterative solve may start it where the
//!   pair's last solve ended ([`Shape::contacts_warm`]).
//!
//! Three optional abilities stand beside it: the engine's fast paths
//! ([`Shape::Fast`], a [`FastContacts`]), the minimiser's and the analysis'
//! [`Policy`] and the drawing's and export's [`Look`], both plain data.
//!
//! A near-disk yields one contact per pair, a dimer up to four; the energy is
//! then `Σ v(h)` over all contacts, with `v` a [`Potential`](crate::Potential).

use crate::contact::{Contact, GapHessian, Pair, PairMemo, Warm};
use crate::error::{Error, Result};
use crate::lanes::{ContactLanes, PairLanes, SlotPairs};
use crate::look::Look;
use crate::math::{RotVec, Vector};
use crate::orientation::BodyOrientation;
use crate::policy::Policy;
use std::fmt::Debug;

/// A family of bodies, generic over the dimension `D`: its geometry.
///
/// Implementations are small values (the family's parameters) shared by all
/// bodies of a scene; per-body data is the size `R⁰` and the orientation.
/// A new family writes the two types and the six methods without a default;
/// the rest are optional abilities.
pub trait Shape<const D: usize>: Clone + Debug + Send + Sync + 'static {
    /// Orientation of one body (`()` for spheres, an angle in 2D, a unit
    /// quaternion in 3D); how it is drawn at random and written to a file is
    /// the type's own ([`BodyOrientation`]).
    type Orientation: BodyOrientation;

    /// The engine's fast paths for this family ([`FastContacts`]):
    /// [`NoFastPath`](crate::NoFastPath) for none.
    type Fast: FastContacts<D, Self>;

    /// The family's registry name (`"sphere"`, `"fourier"`, …).
    fn family(&self) -> &'static str;

    /// Number of rotational coordinates per body (≤ [`MAX_ROT`](crate::MAX_ROT)).
    fn rot_dof(&self) -> usize;

    /// Volume (area in 2D) of a body of size `size`.
    fn volume(&self, size: f64) -> f64;

    /// Radius of a ball around the centre that contains the body; two bodies
    /// whose centres are farther apart than the sum have no contact.
    fn bounding_radius(&self, size: f64) -> f64;

    /// Moment of inertia of each rotational coordinate of a body of size
    /// `size` (the mass FIRE gives it). Default 1.
    fn rot_inertia(&self, _size: f64) -> RotVec {
        [1.0; 3]
    }

    /// Apply a change `dq` (length `rot_dof`) of the rotational coordinates.
    fn rotate(&self, orientation: &mut Self::Orientation, dq: &[f64]);

    /// Visit the contacts of `pair`.
    ///
    /// Every contact whose gap may be at most `max_gap` must be visited;
    /// contacts whose gap certainly exceeds `max_gap` may be skipped (a
    /// cheap bounding test saves the full computation for far pairs). The
    /// energy passes `max_gap = 0`; gap statistics pass their cut.
    fn contacts<F: FnMut(Contact<D>)>(
        &self,
        pair: &Pair<D, Self::Orientation>,
        max_gap: f64,
        visit: F,
    );

    /// [`Shape::contacts`] for a pair of the engine's neighbour list, with
    /// `memo`, what this method kept of the same pair's last solve (`None`
    /// for a pair new to the list): a family whose gap is an iterative
    /// solve may start there and write where it ended. The contacts must
    /// be those of [`Shape::contacts`] to the tolerance the family states
    /// for its solver, whatever the memo holds (also one from a very
    /// different configuration), and a function of `pair` and `memo` alone
    /// (the engine's runs stay reproducible bit for bit).
    ///
    /// The default visits what [`Shape::contact_warm`] found, or calls
    /// [`Shape::contacts`] where it has no warm solve.
    #[inline(always)]
    fn contacts_warm<F: FnMut(Contact<D>)>(
        &self,
        pair: &Pair<D, Self::Orientation>,
        max_gap: f64,
        memo: &mut PairMemo,
        mut visit: F,
    ) {
        match self.contact_warm(pair, max_gap, memo) {
            Warm::Cold => self.contacts(pair, max_gap, visit),
            Warm::Solved(Some(c)) => visit(c),
            Warm::Solved(None) => {}
        }
    }

    /// The warm solve of [`Shape::contacts_warm`]'s default, for a family
    /// with at most one contact per pair: the contact of `pair` (`None`
    /// where its gap certainly exceeds `max_gap`) started from `memo`, with
    /// [`Shape::contacts_warm`]'s promises, or [`Warm::Cold`] for none.
    /// The default: [`Warm::Cold`].
    #[inline(always)]
    fn contact_warm(
        &self,
        _pair: &Pair<D, Self::Orientation>,
        _max_gap: f64,
        _memo: &mut PairMemo,
    ) -> Warm<D> {
        Warm::Cold
    }

    /// Like [`Shape::contacts`], with the second derivatives of each gap
    /// (for the Hessian; not a hot path). Must visit the same contacts, with
    /// the same gaps and first derivatives, as `contacts`.
    ///
    /// The default reports that the family provides no second derivatives.
    fn gap_hessians<F: FnMut(GapHessian<D>)>(
        &self,
        _pair: &Pair<D, Self::Orientation>,
        _max_gap: f64,
        _visit: F,
    ) -> Result<()> {
        Err(Error::Unsupported(format!(
            "family `{}` provides no second derivatives of its gap (no Hessian) in dimension {D}",
            self.family()
        )))
    }

    /// The body as a union of balls, when it is one (bodies made of
    /// spheres): each ball's centre relative to the body's centre, in the
    /// world frame, and its radius, for a body of size `size` and
    /// orientation `orientation`. Packing files write it (key `spheres`) so
    /// that any tool can recompute contacts without knowing the family's
    /// orientation convention. Default `None`.
    fn sphere_decomposition(
        &self,
        _size: f64,
        _orientation: &Self::Orientation,
    ) -> Option<Vec<(Vector<D>, f64)>> {
        None
    }

    /// How the minimiser and the analysis treat this family's packings
    /// (plain data, asked once per scene). Default [`Policy::new`]`(D)`.
    fn policy(&self) -> Policy {
        Policy::new(D)
    }

    /// How the bodies are drawn and exported. Default: nothing to say
    /// (bodies made of spheres are drawn from
    /// [`Shape::sphere_decomposition`]).
    fn look(&self) -> Look {
        Look::default()
    }
}

/// Which of the engine's energy kernels a family's packings take (see
/// [`FastContacts`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Every pair through [`Shape::contacts`].
    Pairs,
    /// The balls kernel ([`FastContacts::BALL`]).
    Balls,
    /// The lanes kernel ([`FastContacts::LANES`]).
    Lanes,
    /// The slots kernel, with this many slots per pair
    /// ([`FastContacts::contact_slots`]).
    Slots(usize),
}

/// Conveniences every [`Shape`] has, for tests and tools.
pub trait ShapeExt<const D: usize>: Shape<D> {
    /// The energy kernel the engine takes for these parameters, in the
    /// engine's order of preference.
    fn kernel(&self) -> Kernel {
        if <Self::Fast as FastContacts<D, Self>>::BALL {
            Kernel::Balls
        } else if Self::Fast::contact_slots(self) > 0 {
            Kernel::Slots(Self::Fast::contact_slots(self))
        } else if <Self::Fast as FastContacts<D, Self>>::LANES && Self::Fast::use_lanes(self) {
            Kernel::Lanes
        } else {
            Kernel::Pairs
        }
    }

    /// The contacts [`Shape::contacts`] visits for one pair, collected (the
    /// pair loop visits them without a `Vec`). With `max_gap = ∞` every
    /// contact of the pair, also far apart.
    fn pair_contacts(&self, pair: &Pair<D, Self::Orientation>, max_gap: f64) -> Vec<Contact<D>> {
        let mut found = Vec::new();
        self.contacts(pair, max_gap, |c| found.push(c));
        found
    }
}

impl<const D: usize, S: Shape<D>> ShapeExt<D> for S {}

/// [`FastContacts::contacts_lanes`] one pair at a time through
/// [`Shape::contacts`] (its default; a family that overrides it for some
/// parameters calls this for the others). A pair with more than one contact
/// keeps the last: only families with [`FastContacts::LANES`] are asked.
#[inline(always)]
pub fn contacts_one_by_one<const D: usize, S: Shape<D>, const W: usize>(
    shape: &S,
    pairs: &PairLanes<D, S::Orientation, W>,
    out: &mut ContactLanes<D, W>,
) {
    for l in 0..W {
        out.found[l] = false;
        let pair = pairs.pair(l);
        shape.contacts(&pair, 0.0, |c| out.set(l, &c));
    }
}

/// The engine's fast paths for the family `S`: optional abilities that let
/// the energy pass compute several pairs per call. A family names them in
/// [`Shape::Fast`]: [`NoFastPath`] for none (every pair through
/// [`Shape::contacts`], which is always correct), or a type implementing
/// this trait (usually the shape itself) that switches on one of three
/// kernels:
///
/// * **balls** ([`FastContacts::BALL`]): one contact per pair, the sphere
///   family's, several pairs per instruction;
/// * **lanes** ([`FastContacts::LANES`]): at most one contact per pair,
///   computed `W` pairs at a time ([`FastContacts::contacts_lanes`]);
/// * **slots** ([`FastContacts::contact_slots`]): up to
///   [`MAX_SLOTS`](crate::MAX_SLOTS) contacts per pair, each at a fixed
///   place (sphere `a` of one body against sphere `b` of the other), from
///   terms computed once per body ([`FastContacts::body_terms`]).
///
/// Each kernel must give the same bits as the pass through
/// [`Shape::contacts`]; the conformance kit (`jamkit-kit`) and the engine's
/// tests check it. Every item has a default that leaves the path off, so an
/// implementation names only the kernel it switches on.
pub trait FastContacts<const D: usize, S: Shape<D>> {
    /// True only for a family of balls: no rotational coordinates, bounding
    /// radius = size, and one contact per pair, exactly
    /// `Contact::translational(|r| − R_i − R_j, r/|r|)` as computed by the
    /// `sphere` family (`(1/|r|) r`, and the first axis at `r = 0`). The
    /// engine then evaluates the energy with a kernel of its own that
    /// handles several pairs per instruction.
    const BALL: bool = false;

    /// True when every pair has at most one contact and the family computes
    /// them several pairs at a time in [`FastContacts::contacts_lanes`].
    /// Where [`FastContacts::use_lanes`] agrees, the engine's energy pass
    /// then asks for a chunk of pairs per call and sums with no branch per
    /// pair.
    const LANES: bool = false;

    /// Whether the energy pass should use [`FastContacts::contacts_lanes`]
    /// for these parameters (only asked when [`FastContacts::LANES`]).
    /// Default true; a family says no where its lanes would only call
    /// [`Shape::contacts`] one pair after the other, which the generic pass
    /// does with less overhead.
    fn use_lanes(_shape: &S) -> bool {
        true
    }

    /// The contacts of `W` pairs with `max_gap = 0` (the energy's): lane `l`
    /// gets the contact [`Shape::contacts`] visits for pair `l`, bit for
    /// bit, or none where it visits none. Every lane of `out` must be
    /// written (`found` at least): it holds the previous call's contacts.
    /// The default calls [`Shape::contacts`] for one pair after the other.
    #[inline(always)]
    fn contacts_lanes<const W: usize>(
        shape: &S,
        pairs: &PairLanes<D, S::Orientation, W>,
        out: &mut ContactLanes<D, W>,
    ) {
        contacts_one_by_one(shape, pairs, out);
    }

    /// Contacts per pair on the engine's *slots* path (default 0: not on
    /// it). A family whose pair of bodies has at most this many contacts,
    /// each at a fixed place `s` (a *slot*), visited by [`Shape::contacts`]
    /// in slot order, may compute them a chunk of pairs at a time in
    /// [`FastContacts::slot_contacts_lanes`], from terms of each body
    /// computed once per energy evaluation ([`FastContacts::body_terms`]).
    /// At most [`MAX_SLOTS`](crate::MAX_SLOTS).
    fn contact_slots(_shape: &S) -> usize {
        0
    }

    /// Numbers per body for [`FastContacts::body_terms`] (only asked when
    /// [`FastContacts::contact_slots`] is not 0).
    fn body_terms_len(_shape: &S) -> usize {
        0
    }

    /// Write the terms of one body (size `size`, orientation `o`) that
    /// [`FastContacts::slot_contacts_lanes`] reads,
    /// [`FastContacts::body_terms_len`] numbers, into `out`: what
    /// [`Shape::contacts`] computes anew for every pair (e.g. the rotated
    /// sphere offsets), once per evaluation.
    fn body_terms(_shape: &S, _size: f64, _o: &S::Orientation, _out: &mut [f64]) {}

    /// The contacts of `W` pairs with `max_gap = 0`, slot by slot: lane `l`
    /// of `out[s]` gets the contact [`Shape::contacts`] visits at slot `s`
    /// of pair `l`, bit for bit, or none (`found` false) where it visits
    /// none. `terms` holds [`FastContacts::body_terms`] of every body of the
    /// scene, in body order. `out` has [`FastContacts::contact_slots`]
    /// entries; every lane's `found` must be written.
    #[inline(always)]
    fn slot_contacts_lanes<const W: usize>(
        _shape: &S,
        _terms: &[f64],
        _pairs: &SlotPairs<D, W>,
        out: &mut [ContactLanes<D, W>],
    ) {
        for slots in out {
            slots.found = [false; W];
        }
    }

    /// Whether the generic pass (the one that keeps a [`PairMemo`] per
    /// listed pair, [`Shape::contacts_warm`]) should ask for its contacts a
    /// chunk of pairs at a time through [`FastContacts::contacts_warm_lanes`]
    /// (default false: one pair at a time).
    fn use_warm_lanes(_shape: &S) -> bool {
        false
    }

    /// The warm contacts of the first `len` of `W` pairs whose bounding
    /// balls overlap, with `max_gap`: lane `l < len` gets the contact
    /// [`Shape::contacts_warm`] visits for pair `l` with memo
    /// `memos[at[l]]`, bit for bit, or none, and that memo what that call
    /// leaves in it (the lanes' places `at` differ from each other). Lanes
    /// from `len` on hold arbitrary pairs and places, and are ignored. At
    /// most one contact per pair (a pair with more keeps the last).
    /// `scratch` is the family's to use as it likes (the engine keeps it
    /// between calls, with whatever the last call left in it). The default
    /// calls [`Shape::contacts_warm`] for one pair after the other.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn contacts_warm_lanes<const W: usize>(
        shape: &S,
        pairs: &PairLanes<D, S::Orientation, W>,
        len: usize,
        max_gap: f64,
        memos: &mut [PairMemo],
        at: &[u32; W],
        _scratch: &mut Vec<[f64; W]>,
        out: &mut ContactLanes<D, W>,
    ) {
        contacts_warm_one_by_one(shape, pairs, len, max_gap, memos, at, out);
    }
}

/// [`FastContacts::contacts_warm_lanes`] one pair at a time through
/// [`Shape::contacts_warm`], for lanes `0..len` with memos `memos[at[l]]` (its default; a family
/// that overrides it for some parameters calls this for the others).
#[inline(always)]
pub fn contacts_warm_one_by_one<const D: usize, S: Shape<D>, const W: usize>(
    shape: &S,
    pairs: &PairLanes<D, S::Orientation, W>,
    len: usize,
    max_gap: f64,
    memos: &mut [PairMemo],
    at: &[u32; W],
    out: &mut ContactLanes<D, W>,
) {
    for l in 0..len.min(W) {
        out.found[l] = false;
        let pair = pairs.pair(l);
        shape.contacts_warm(&pair, max_gap, &mut memos[at[l] as usize], |c| {
            out.set(l, &c)
        });
    }
}

/// No fast path: every pair goes through [`Shape::contacts`].
#[derive(Clone, Copy, Debug, Default)]
pub struct NoFastPath;

impl<const D: usize, S: Shape<D>> FastContacts<D, S> for NoFastPath {}
