//! What the engine asks and a family answers about a pair of bodies: the
//! [`Pair`] (sizes, orientations, separation), each [`Contact`] (a gap and
//! its first derivatives), for the Hessian its [`GapHessian`], and what a
//! family may keep of a pair's last solve ([`PairMemo`]) and what its warm
//! solve found ([`Warm`]).
//!
//! Gaps depend on the two centres only through `r_ij = r_j − r_i` (minimum
//! image), so `∂h/∂r_i = −∂h/∂r_j` and a [`Contact`] stores one of them.

use crate::math::{MAX_ROT, Matrix, RotVec, Vector};

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
/// [`Shape::rotate`](crate::Shape::rotate) applies, at zero increment.
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
}

/// Numbers a family may keep per listed pair between two evaluations
/// ([`PairMemo`]): nine, three unit vectors' worth (the 3D exact gap keeps
/// a normal and two support points; the 2D one uses the first six).
pub const MEMO_LEN: usize = 9;

/// What a family keeps of one listed pair's last solve, to start the next
/// one there ([`Shape::contacts_warm`](crate::Shape::contacts_warm)):
/// `None` for a pair with no solve yet. The engine stores one per pair of
/// its neighbour list, carries it over by `(i, j)` when the list is rebuilt
/// and starts a pair new to the list at `None`, so that it is a function of
/// the run alone (not of threads or shards).
pub type PairMemo = Option<[f64; MEMO_LEN]>;

/// What a family's warm solve of one listed pair found
/// ([`Shape::contact_warm`](crate::Shape::contact_warm)), for a family with
/// at most one contact per pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Warm<const D: usize> {
    /// No warm solve for this pair (e.g. not for this gap model):
    /// [`Shape::contacts`](crate::Shape::contacts) answers.
    Cold,
    /// The contact, or `None` where the gap certainly exceeds `max_gap`.
    Solved(Option<Contact<D>>),
}
