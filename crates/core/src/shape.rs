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
//!   the Hessian, their second derivatives ([`Shape::gap_hessians`]).
//!
//! Three optional abilities stand beside it: the engine's fast paths
//! ([`Shape::Fast`], see [`crate::fast`]), the minimiser's and the analysis'
//! [`Policy`] and the drawing's and export's [`Look`], both plain data.
//!
//! A near-disk yields one contact per pair, a dimer up to four; the energy is
//! then `Σ v(h)` over all contacts, with `v` a [`Potential`](crate::Potential).
//!
//! Gaps depend on the two centres only through `r_ij = r_j − r_i` (minimum
//! image), so `∂h/∂r_i = −∂h/∂r_j` and a [`Contact`] stores one of them.

use crate::error::{Error, Result};
use crate::fast::FastContacts;
use crate::math::{MAX_ROT, Matrix, RotVec, Vector};
use crate::orientation::BodyOrientation;
use crate::policy::{Look, Policy};
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

/// What a family is asked about one pair of bodies: body `i` (size
/// `size_i`, orientation `o_i`) and body `j`, whose centre is at
/// `r_ij = r_j − r_i` (minimum image) from `i`'s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair<const D: usize, O> {
    /// `R⁰_i`.
    pub size_i: f64,
    /// Orientation of body `i`.
    pub o_i: O,
    /// `R⁰_j`.
    pub size_j: f64,
    /// Orientation of body `j`.
    pub o_j: O,
    /// `r_ij = r_j − r_i`.
    pub r_ij: Vector<D>,
}

impl<const D: usize, O: Copy> Pair<D, O> {
    /// Body `i` (`size_i`, `o_i`) and body `j` (`size_j`, `o_j`) at `r_ij`.
    pub fn new(size_i: f64, o_i: O, size_j: f64, o_j: O, r_ij: Vector<D>) -> Self {
        Self {
            size_i,
            o_i,
            size_j,
            o_j,
            r_ij,
        }
    }

    /// The same pair seen from `j`: `i` and `j` swapped, `r_ij → −r_ij`.
    pub fn swapped(&self) -> Self {
        Self::new(self.size_j, self.o_j, self.size_i, self.o_i, -self.r_ij)
    }
}

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

    /// The engine's fast paths for this family ([`crate::fast`]):
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
/// [`crate::fast`]).
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
