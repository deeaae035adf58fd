//! Pairs and contacts side by side, one entry per pair (*lane*), for the
//! engine's fast paths ([`FastContacts`](crate::FastContacts)).

use crate::contact::Contact;
use crate::contact::Pair;
use crate::math::{MAX_ROT, Vector};

/// `W` pairs side by side, for [`FastContacts::contacts_lanes`](crate::FastContacts::contacts_lanes): each field holds
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
    /// Every lane zero, with both orientations `o`: a batch to fill.
    #[inline]
    pub fn filled(o: O) -> Self {
        Self {
            size_i: [0.0; W],
            size_j: [0.0; W],
            reach_i: [0.0; W],
            reach_j: [0.0; W],
            o_i: [o; W],
            o_j: [o; W],
            r_ij: [[0.0; W]; D],
            r2: [0.0; W],
        }
    }

    /// Lane `l`'s separation as a vector.
    #[inline(always)]
    pub fn separation(&self, l: usize) -> Vector<D> {
        Vector::<D>::from_fn(|a, _| self.r_ij[a][l])
    }

    /// Put `pair` in lane `l`, with the bodies' bounding radii `reach`
    /// (`bounding_radius` of `size_i` and `size_j`).
    #[inline]
    pub fn set(&mut self, l: usize, pair: &Pair<D, O>, reach: (f64, f64)) {
        self.size_i[l] = pair.size_i;
        self.size_j[l] = pair.size_j;
        (self.reach_i[l], self.reach_j[l]) = reach;
        self.o_i[l] = pair.o_i;
        self.o_j[l] = pair.o_j;
        for a in 0..D {
            self.r_ij[a][l] = pair.r_ij[a];
        }
        self.r2[l] = pair.r_ij.norm_squared();
    }

    /// Lane `l` as one [`Pair`].
    #[inline(always)]
    pub fn pair(&self, l: usize) -> Pair<D, O> {
        Pair {
            size_i: self.size_i[l],
            o_i: self.o_i[l],
            size_j: self.size_j[l],
            o_j: self.o_j[l],
            r_ij: self.separation(l),
        }
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
/// ([`FastContacts::contact_slots`](crate::FastContacts::contact_slots)).
pub const MAX_SLOTS: usize = 16;

/// `W` pairs side by side for [`FastContacts::slot_contacts_lanes`](crate::FastContacts::slot_contacts_lanes): the two
/// bodies (their places in the scene, for the family's body terms, see
/// [`FastContacts::body_terms`](crate::FastContacts::body_terms)) and the separation, one entry per lane.
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
