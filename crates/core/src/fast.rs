//! The engine's fast paths: optional abilities of a family that let the
//! energy pass compute several pairs per call.
//!
//! A family names its fast paths in [`Shape::Fast`]: [`NoFastPath`] for
//! none (every pair through [`Shape::contacts`], which is always correct),
//! or a type implementing [`FastContacts`] (usually the shape itself) that
//! switches on one of three kernels:
//!
//! * **balls** ([`FastContacts::BALL`]): one contact per pair, the sphere
//!   family's, several pairs per instruction;
//! * **lanes** ([`FastContacts::LANES`]): at most one contact per pair,
//!   computed `W` pairs at a time ([`FastContacts::contacts_lanes`]);
//! * **slots** ([`FastContacts::contact_slots`]): up to [`MAX_SLOTS`]
//!   contacts per pair, each at a fixed place (sphere `a` of one body against
//!   sphere `b` of the other), from terms computed once per body
//!   ([`FastContacts::body_terms`]).
//!
//! Each kernel must give the same bits as the pass through
//! [`Shape::contacts`]; the conformance kit (`jamkit-kit`) and the engine's
//! tests check it.

use crate::math::{MAX_ROT, Vector};
use crate::shape::{Contact, Pair, Shape};

/// `W` pairs side by side, for [`FastContacts::contacts_lanes`]: each field holds
/// one entry per pair (*lane*), so that a family can write its contact as
/// plain loops over lanes that the compiler turns into vector instructions.
#[derive(Clone, Copy, Debug)]
pub struct PairLanes<const D: usize, O, const W: usize> {
    /// `R⁰_i`.
    pub size_i: [f64; W],
    /// `R⁰_j`.
    pub size_j: [f64; W],
    /// `bounding_radius(R⁰_i)`, bit for bit.
    pub reach_i: [f64; W],
    /// `bounding_radius(R⁰_j)`, bit for bit.
    pub reach_j: [f64; W],
    /// Orientation of body `i`.
    pub o_i: [O; W],
    /// Orientation of body `j`.
    pub o_j: [O; W],
    /// `r_ij = r_j − r_i` (minimum image), one array per axis.
    pub r_ij: [[f64; W]; D],
    /// `|r_ij|²`, bit for bit `Vector::norm_squared` of `r_ij`.
    pub r2: [f64; W],
}

impl<const D: usize, O: Copy, const W: usize> PairLanes<D, O, W> {
    /// Lane `l`'s separation as a vector.
    #[inline(always)]
    pub fn separation(&self, l: usize) -> Vector<D> {
        Vector::<D>::from_fn(|a, _| self.r_ij[a][l])
    }
}

/// The contacts of [`PairLanes`], one per lane at most, laid out the same way.
#[derive(Clone, Copy, Debug)]
pub struct ContactLanes<const D: usize, const W: usize> {
    /// Whether the lane's pair has a contact (the other fields of a lane
    /// without one are arbitrary, and ignored).
    pub found: [bool; W],
    /// The gap.
    pub gap: [f64; W],
    /// `∂h/∂r_j`, one array per axis.
    pub grad_r: [[f64; W]; D],
    /// `∂h/∂q_i`, one array per rotational coordinate.
    pub grad_rot_i: [[f64; W]; MAX_ROT],
    /// `∂h/∂q_j`.
    pub grad_rot_j: [[f64; W]; MAX_ROT],
}

impl<const D: usize, const W: usize> Default for ContactLanes<D, W> {
    fn default() -> Self {
        Self {
            found: [false; W],
            gap: [0.0; W],
            grad_r: [[0.0; W]; D],
            grad_rot_i: [[0.0; W]; MAX_ROT],
            grad_rot_j: [[0.0; W]; MAX_ROT],
        }
    }
}

impl<const D: usize, const W: usize> ContactLanes<D, W> {
    /// Store `c` as lane `l`'s contact.
    #[inline(always)]
    pub fn set(&mut self, l: usize, c: &Contact<D>) {
        self.found[l] = true;
        self.gap[l] = c.gap;
        for a in 0..D {
            self.grad_r[a][l] = c.grad_r[a];
        }
        for a in 0..MAX_ROT {
            self.grad_rot_i[a][l] = c.grad_rot_i[a];
            self.grad_rot_j[a][l] = c.grad_rot_j[a];
        }
    }

    /// Lane `l`'s contact, if it has one.
    pub fn get(&self, l: usize) -> Option<Contact<D>> {
        self.found[l].then(|| Contact {
            gap: self.gap[l],
            grad_r: Vector::<D>::from_fn(|a, _| self.grad_r[a][l]),
            grad_rot_i: std::array::from_fn(|a| self.grad_rot_i[a][l]),
            grad_rot_j: std::array::from_fn(|a| self.grad_rot_j[a][l]),
        })
    }
}

/// The most contacts per pair on the engine's slots path
/// ([`FastContacts::contact_slots`]).
pub const MAX_SLOTS: usize = 16;

/// `W` pairs side by side for [`FastContacts::slot_contacts_lanes`]: the two
/// bodies (their places in the scene, for the family's body terms, see
/// [`FastContacts::body_terms`]) and the separation, one entry per lane.
#[derive(Clone, Copy, Debug)]
pub struct SlotPairs<const D: usize, const W: usize> {
    /// Body `i`.
    pub body_i: [usize; W],
    /// Body `j`.
    pub body_j: [usize; W],
    /// `r_ij = r_j − r_i` (minimum image), one array per axis.
    pub r_ij: [[f64; W]; D],
    /// `|r_ij|²`, bit for bit `Vector::norm_squared` of `r_ij`.
    pub r2: [f64; W],
}

impl<const D: usize, const W: usize> SlotPairs<D, W> {
    /// Lane `l`'s separation as a vector.
    #[inline(always)]
    pub fn separation(&self, l: usize) -> Vector<D> {
        Vector::<D>::from_fn(|a, _| self.r_ij[a][l])
    }
}

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
        let pair = Pair {
            size_i: pairs.size_i[l],
            o_i: pairs.o_i[l],
            size_j: pairs.size_j[l],
            o_j: pairs.o_j[l],
            r_ij: pairs.separation(l),
        };
        shape.contacts(&pair, 0.0, |c| out.set(l, &c));
    }
}

/// The fast paths of the family `S` (see the module documentation). Every
/// item has a default that leaves the path off, so an implementation names
/// only the kernel it switches on.
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
    /// At most [`MAX_SLOTS`].
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
}

/// No fast path: every pair goes through [`Shape::contacts`].
#[derive(Clone, Copy, Debug, Default)]
pub struct NoFastPath;

impl<const D: usize, S: Shape<D>> FastContacts<D, S> for NoFastPath {}
