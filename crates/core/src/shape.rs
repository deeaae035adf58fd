//! The shape-family trait.
//!
//! A *shape family* (disks and spheres, Fourier near-disks, rigid n-mers, …)
//! describes one kind of body up to a scale `R⁰` (its *size*) and an
//! orientation. The engine asks a family only a handful of questions:
//!
//! * how many rotational coordinates a body has ([`Shape::rot_dof`]: zero for
//!   spheres, so that a sphere scene carries no rotational coordinates at all);
//! * its volume and a bounding radius (for the packing fraction and the
//!   neighbour list);
//! * how a small change of its rotational coordinates moves the orientation
//!   ([`Shape::rotate`]);
//! * the **contacts** between two bodies: each a gap `h` (negative when the
//!   bodies overlap) with its derivatives with respect to the separation and
//!   to both bodies' rotational coordinates ([`Shape::contacts`]).
//!
//! A near-disk yields one contact per pair, a dimer up to four; the energy is
//! then `Σ v(h)` over all contacts, with `v` a [`Potential`](crate::Potential).
//!
//! Gaps depend on the two centres only through `r_ij = r_j − r_i` (minimum
//! image), so `∂h/∂r_i = −∂h/∂r_j` and a [`Contact`] stores one of them.

use crate::error::{Error, Result};
use crate::math::{MAX_ROT, Matrix, RotVec, Vector};
use crate::orientation::BodyOrientation;
use rand::Rng;
use std::fmt::Debug;

/// One contact between bodies `i` and `j`: a gap with its first derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact<const D: usize> {
    /// The gap `h_ij` (negative for an overlap).
    pub gap: f64,
    /// `∂h/∂r_j = −∂h/∂r_i`.
    pub grad_r: Vector<D>,
    /// `∂h/∂q_i` for the rotational coordinates of body `i` (first `rot_dof` entries).
    pub grad_rot_i: RotVec,
    /// `∂h/∂q_j` for the rotational coordinates of body `j`.
    pub grad_rot_j: RotVec,
}

impl<const D: usize> Contact<D> {
    /// A contact between bodies without rotational coordinates.
    #[inline(always)]
    pub fn translational(gap: f64, grad_r: Vector<D>) -> Self {
        Self {
            gap,
            grad_r,
            grad_rot_i: [0.0; 3],
            grad_rot_j: [0.0; 3],
        }
    }
}

/// One contact's gap with its first **and second** derivatives, for the
/// Hessian of the energy.
///
/// The gap depends on the centres only through `r_ij = r_j − r_i`, so with
/// `∂/∂r_i = −∂/∂r_j` every second derivative involving `r_i` follows from
/// the ones stored here:
///
/// ```text
/// ∂²h/∂r_i∂r_i = ∂²h/∂r_j∂r_j = −∂²h/∂r_i∂r_j = rr,
/// ∂²h/∂r_j∂q_i[a] = r_qi[a],   ∂²h/∂r_i∂q_i[a] = −r_qi[a]   (same for q_j).
/// ```
///
/// Rotational derivatives are taken with respect to the increments that
/// [`Shape::rotate`] applies, at zero increment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GapHessian<const D: usize> {
    /// The gap and its first derivatives.
    pub contact: Contact<D>,
    /// `∂²h/∂r_j∂r_j` (symmetric).
    pub rr: Matrix<D>,
    /// `∂²h/∂r_j∂q_i[a]` for each rotational coordinate `a` of body `i`.
    pub r_qi: [Vector<D>; MAX_ROT],
    /// `∂²h/∂r_j∂q_j[a]`.
    pub r_qj: [Vector<D>; MAX_ROT],
    /// `∂²h/∂q_i[a]∂q_i[b]` (symmetric).
    pub qi_qi: [RotVec; MAX_ROT],
    /// `∂²h/∂q_j[a]∂q_j[b]` (symmetric).
    pub qj_qj: [RotVec; MAX_ROT],
    /// `∂²h/∂q_i[a]∂q_j[b]`, indexed `[a][b]`.
    pub qi_qj: [RotVec; MAX_ROT],
}

impl<const D: usize> GapHessian<D> {
    /// A contact between bodies without rotational coordinates.
    pub fn translational(gap: f64, grad_r: Vector<D>, rr: Matrix<D>) -> Self {
        Self {
            contact: Contact::translational(gap, grad_r),
            rr,
            r_qi: [Vector::<D>::zeros(); MAX_ROT],
            r_qj: [Vector::<D>::zeros(); MAX_ROT],
            qi_qi: [[0.0; MAX_ROT]; MAX_ROT],
            qj_qj: [[0.0; MAX_ROT]; MAX_ROT],
            qi_qj: [[0.0; MAX_ROT]; MAX_ROT],
        }
    }
}

/// `W` pairs side by side, for [`Shape::contacts_lanes`]: each field holds
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
/// ([`Shape::contact_slots`]).
pub const MAX_SLOTS: usize = 16;

/// `W` pairs side by side for [`Shape::slot_contacts_lanes`]: the two
/// bodies (their places in the scene, for the family's body terms, see
/// [`Shape::body_terms`]) and the separation, one entry per lane.
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

/// [`Shape::contacts_lanes`] one pair at a time through
/// [`Shape::contacts`] (its default; a family that overrides it for some
/// parameters calls this for the others). A pair with more than one contact
/// keeps the last: only families with [`Shape::LANE_CONTACTS`] are asked.
#[inline(always)]
pub fn contacts_one_by_one<const D: usize, S: Shape<D>, const W: usize>(
    shape: &S,
    pairs: &PairLanes<D, S::Orientation, W>,
    out: &mut ContactLanes<D, W>,
) {
    for l in 0..W {
        out.found[l] = false;
        shape.contacts(
            pairs.size_i[l],
            &pairs.o_i[l],
            pairs.size_j[l],
            &pairs.o_j[l],
            &pairs.separation(l),
            0.0,
            |c| out.set(l, &c),
        );
    }
}

/// A family of bodies, generic over the dimension `D`.
///
/// Implementations are small values (the family's parameters) shared by all
/// bodies of a scene; per-body data is the size `R⁰` and the orientation.
pub trait Shape<const D: usize>: Clone + Debug + Send + Sync + 'static {
    /// Orientation of one body (`()` for spheres, an angle in 2D, a unit
    /// quaternion in 3D).
    type Orientation: BodyOrientation;

    /// The family's registry name (`"sphere"`, `"fourier"`, …).
    fn family(&self) -> &'static str;

    /// Number of rotational coordinates per body (≤ [`MAX_ROT`](crate::MAX_ROT)).
    fn rot_dof(&self) -> usize;

    /// Volume (area in 2D) of a body of size `size`.
    fn volume(&self, size: f64) -> f64;

    /// Radius of a ball around the centre that contains the body; two bodies
    /// whose centres are farther apart than the sum have no contact.
    fn bounding_radius(&self, size: f64) -> f64;

    /// True only for a family of balls: no rotational coordinates, bounding
    /// radius = size, and one contact per pair, exactly
    /// `Contact::translational(|r| − R_i − R_j, r/|r|)` as computed by the
    /// `sphere` family (`(1/|r|) r`, and the first axis at `r = 0`). The
    /// engine then evaluates the energy with a kernel of its own that
    /// handles several pairs per instruction; `tests` check that it gives
    /// the same bits as [`Shape::contacts`].
    const BALL: bool = false;

    /// True when every pair has at most one contact and the family computes
    /// them several pairs at a time in [`Shape::contacts_lanes`]. Where
    /// [`Shape::use_lanes`] agrees, the engine's energy pass then asks for a
    /// chunk of pairs per call and sums with no branch per pair; `tests`
    /// check that it gives the same bits as the pass through
    /// [`Shape::contacts`].
    const LANE_CONTACTS: bool = false;

    /// Whether the energy pass should use [`Shape::contacts_lanes`] for
    /// these parameters (only asked when [`Shape::LANE_CONTACTS`]). Default
    /// true; a family says no where its lanes would only call
    /// [`Shape::contacts`] one pair after the other, which the generic pass
    /// does with less overhead.
    fn use_lanes(&self) -> bool {
        true
    }

    /// Contacts per pair on the engine's *slots* path (default 0: not on
    /// it). A family whose pair of bodies has at most this many contacts,
    /// each at a fixed place `s` (a *slot*: for bodies made of spheres,
    /// sphere `a` of `i` against sphere `b` of `j`), visited by
    /// [`Shape::contacts`] in slot order, may compute them a chunk of pairs
    /// at a time in [`Shape::slot_contacts_lanes`], from terms of each body
    /// computed once per energy evaluation ([`Shape::body_terms`]). The
    /// energy pass then sums each pair's slots in order with no branch per
    /// pair or contact; `tests` check that it gives the same bits as the
    /// pass through [`Shape::contacts`]. At most [`MAX_SLOTS`].
    fn contact_slots(&self) -> usize {
        0
    }

    /// Numbers per body for [`Shape::body_terms`] (only asked when
    /// [`Shape::contact_slots`] is not 0).
    fn body_terms_len(&self) -> usize {
        0
    }

    /// Write the terms of one body (size `size`, orientation `o`) that
    /// [`Shape::slot_contacts_lanes`] reads, [`Shape::body_terms_len`]
    /// numbers, into `out`: what [`Shape::contacts`] computes anew for
    /// every pair (e.g. the rotated sphere offsets), once per evaluation.
    fn body_terms(&self, _size: f64, _o: &Self::Orientation, _out: &mut [f64]) {}

    /// The contacts of `W` pairs with `max_gap = 0`, slot by slot: lane `l`
    /// of `out[s]` gets the contact [`Shape::contacts`] visits at slot `s`
    /// of pair `l`, bit for bit, or none (`found` false) where it visits
    /// none. `terms` holds [`Shape::body_terms`] of every body of the scene,
    /// [`Shape::body_terms_len`] numbers each, in body order. `out` has
    /// [`Shape::contact_slots`] entries; every lane's `found` must be
    /// written. The default finds no contact (it is never asked: a family
    /// with [`Shape::contact_slots`] 0 is not on this path).
    #[inline(always)]
    fn slot_contacts_lanes<const W: usize>(
        &self,
        _terms: &[f64],
        _pairs: &SlotPairs<D, W>,
        out: &mut [ContactLanes<D, W>],
    ) {
        for slots in out {
            slots.found = [false; W];
        }
    }

    /// The largest FIRE time step for packings of this family (translations
    /// of unit mass, rotations of [`Shape::rot_inertia`]); `None`: the
    /// engine's default 0.5. FIRE's semi-implicit Euler step is stable
    /// below `2/ω_max`, `ω_max` the highest vibration frequency of a
    /// jammed packing, and FIRE crawls well before that limit (at
    /// `0.87 · 2/ω_max` it stalled on 3D dimers). A family whose bodies
    /// touch at several points per pair, and so vibrate faster than
    /// spheres (`ω_max² ≈ 12` for 3D dimers against 6 for spheres), says
    /// so here. An experiment's `minimizer.dt_max` overrides it.
    fn fire_dt_max(&self) -> Option<f64> {
        None
    }

    /// Whether FIRE's masses default, for this family, to each body's own
    /// stiffness block in the jamming search's minimisations that start
    /// from a decompressed jammed state (`masses: Blocks((jammed_only:
    /// true))` of `jamkit_engine`), instead of the bodies' own masses
    /// everywhere. A family says yes where that was measured faster with
    /// the same ensembles (docs/reports/minimizers.md, "Block masses only
    /// from jammed states"); an experiment's `minimizer.masses` overrides it.
    /// Default: no (the bodies' own masses, the paper's).
    fn fire_jammed_block_masses(&self) -> bool {
        false
    }

    /// Whether FIRE, for this family, hands every minimisation to L-BFGS
    /// from the start with the block metric (`lbfgs: (after: 0, blocks:
    /// true)` of `jamkit_engine`) when the experiment leaves
    /// `minimizer.lbfgs` out and runs FIRE (not FIRE 2.0). A family says
    /// yes where that was measured faster with the same ensembles
    /// (docs/reports/minimizers.md, "L-BFGS … the 3D dimer default"); an
    /// experiment's `minimizer.lbfgs` overrides it (`None`: FIRE alone).
    /// Default: no (FIRE alone, the paper's).
    fn lbfgs_blocks_by_default(&self) -> bool {
        false
    }

    /// Inertia of each rotational coordinate (the mass FIRE gives it).
    fn rot_inertia(&self, _size: f64) -> RotVec {
        [1.0; 3]
    }

    /// The orientation all bodies start from before randomisation (by
    /// default the orientation type's own, [`BodyOrientation::reference`]).
    fn reference_orientation(&self) -> Self::Orientation {
        Self::Orientation::reference()
    }

    /// A uniformly random orientation ([`BodyOrientation::random`] by
    /// default).
    fn random_orientation<R: Rng + ?Sized>(&self, rng: &mut R) -> Self::Orientation {
        Self::Orientation::random(rng)
    }

    /// Apply a change `dq` (length `rot_dof`) of the rotational coordinates.
    fn rotate(&self, orientation: &mut Self::Orientation, dq: &[f64]);

    /// The orientation written as numbers for output (empty for spheres;
    /// [`BodyOrientation::to_coords`] by default).
    fn orientation_coords(&self, orientation: &Self::Orientation) -> Vec<f64> {
        orientation.to_coords()
    }

    /// The inverse of [`Shape::orientation_coords`]; `None` if the numbers do
    /// not describe an orientation ([`BodyOrientation::from_coords`] by
    /// default).
    fn orientation_from_coords(&self, coords: &[f64]) -> Option<Self::Orientation> {
        Self::Orientation::from_coords(coords)
    }

    /// Visit the contacts between body `i` (size `size_i`, orientation `o_i`)
    /// and body `j`, whose centre is at `r_ij = r_j − r_i` from `i`'s.
    ///
    /// Every contact whose gap may be at most `max_gap` must be visited;
    /// contacts whose gap certainly exceeds `max_gap` may be skipped (a
    /// cheap bounding test saves the full computation for far pairs). The
    /// energy passes `max_gap = 0`; gap statistics pass their cut.
    #[allow(clippy::too_many_arguments)]
    fn contacts<F: FnMut(Contact<D>)>(
        &self,
        size_i: f64,
        o_i: &Self::Orientation,
        size_j: f64,
        o_j: &Self::Orientation,
        r_ij: &Vector<D>,
        max_gap: f64,
        visit: F,
    );

    /// The contacts [`Shape::contacts`] visits for one pair, collected (for
    /// tests and tools; the pair loop visits them without a `Vec`). With
    /// `max_gap = ∞` every contact of the pair, also far apart.
    fn pair_contacts(
        &self,
        size_i: f64,
        o_i: &Self::Orientation,
        size_j: f64,
        o_j: &Self::Orientation,
        r_ij: &Vector<D>,
        max_gap: f64,
    ) -> Vec<Contact<D>> {
        let mut found = Vec::new();
        self.contacts(size_i, o_i, size_j, o_j, r_ij, max_gap, |c| found.push(c));
        found
    }

    /// The contacts of `W` pairs with `max_gap = 0` (the energy's): lane `l`
    /// gets the contact [`Shape::contacts`] visits for pair `l`, bit for
    /// bit, or none where it visits none. Every lane of `out` must be
    /// written (`found` at least): it holds the previous call's contacts.
    /// Used only when [`Shape::LANE_CONTACTS`] (at most one contact per
    /// pair).
    ///
    /// The default calls [`Shape::contacts`] for one pair after the other.
    #[inline(always)]
    fn contacts_lanes<const W: usize>(
        &self,
        pairs: &PairLanes<D, Self::Orientation, W>,
        out: &mut ContactLanes<D, W>,
    ) {
        contacts_one_by_one(self, pairs, out);
    }

    /// Like [`Shape::contacts`], with the second derivatives of each gap
    /// (for the Hessian; not a hot path). Must visit the same contacts, with
    /// the same gaps and first derivatives, as `contacts`.
    ///
    /// The default reports that the family provides no second derivatives.
    #[allow(clippy::too_many_arguments)]
    fn gap_hessians<F: FnMut(GapHessian<D>)>(
        &self,
        _size_i: f64,
        _o_i: &Self::Orientation,
        _size_j: f64,
        _o_j: &Self::Orientation,
        _r_ij: &Vector<D>,
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

    /// The planar outline of the family's bodies, for drawing (an optional
    /// ability: `None` where the family has none, e.g. bodies made of
    /// spheres, which are drawn from [`Shape::sphere_decomposition`]).
    fn outline(&self) -> Option<crate::family::SharedOutline> {
        None
    }

    /// The surface of the family's star-shaped 3D bodies, for drawing (an
    /// optional ability: `None` where the family has none; balls are drawn
    /// as balls, bodies made of spheres from
    /// [`Shape::sphere_decomposition`]).
    fn surface(&self) -> Option<crate::family::SharedSurface> {
        None
    }

    /// The semi-axes of an ellipse or ellipsoid body along its body axes,
    /// per unit size `R⁰` (an optional ability: `None` where the body is not
    /// one, or is a ball). Exporters write them where a viewer draws
    /// ellipsoids (extended XYZ's `aspherical_shape`, OVITO); a planar body
    /// gives its third axis as the second.
    fn ellipsoid_axes(&self) -> Option<[f64; 3]> {
        None
    }

    /// Whether the random start must be free of overlaps. Non-convex
    /// bodies (bodies made of spheres) can interpenetrate into a *locked*
    /// pair at a random start (two dimers crossed at their centres feel no
    /// net force: a local minimum of the energy with a finite overlap), so
    /// they are placed one by one, each redrawn until it overlaps none
    /// placed before ([`Packing::random`](crate::Packing::random)). Default
    /// false: convex bodies relax any start, and keep their random stream.
    fn overlap_free_start(&self) -> bool {
        false
    }

    /// Fewest contacts a non-rattler keeps (rattlers are removed iteratively
    /// below this). Default `D + 1`, the paper's choice for disks and
    /// near-disks.
    fn rattler_threshold(&self) -> usize {
        D + 1
    }

    /// Caveats about these parameters that do not stop a run but qualify its
    /// results (e.g. a non-convex outline where the gap model assumes one
    /// contact per pair). Written into each packing's `flag`.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }

    /// Whether jammed packings of this family are expected to be isostatic
    /// (`N_c ≥ f N_nr − D + 1`, `f = D + rot_dof`): true for spheres and rigid
    /// bodies made of spheres, false for near-disks, which jam hypostatic.
    fn expects_isostatic(&self) -> bool {
        true
    }
}
