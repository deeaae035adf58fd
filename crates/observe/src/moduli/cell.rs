//! The contacts and the strain derivatives of a [`Strained`] cell (module
//! documentation of [`super`], "Check by deformation").

use crate::contacts::{ContactNetwork, find_rattlers};
use crate::hessian::Hessian;
use crate::summary::ContactCount;
use jamkit_core::{Potential, Result, Shape, Vector};
use jamkit_engine::Objective;
use jamkit_engine::cell::Strained;

use super::*;

/// The contact network of a [`Strained`] cell, as [`crate::summarize`]
/// counts it for a packing in its fixed box.
pub trait CellContacts {
    /// Every contact (`h < 0`) of the cell, in its deformed shape.
    fn contacts(&self) -> ContactNetwork;
    /// Rattlers of the cell: bodies with fewer than `threshold` contacts
    /// (`h < 0`), removed iteratively ([`crate::contacts::find_rattlers`]).
    fn rattlers(&self, threshold: usize) -> Vec<bool>;
    /// The contact numbers of the cell with the rattlers `rattler` (by
    /// count, as [`CellContacts::rattlers`]; `f = D + rot_dof` coordinates
    /// per non-rattler).
    fn contact_count(&self, rattler: &[bool]) -> ContactCount;
}

impl<const D: usize, S: Shape<D>> CellContacts for Strained<D, S> {
    /// Every contact (`h < 0`) of the cell, in its deformed shape.
    fn contacts(&self) -> ContactNetwork {
        let mut network = ContactNetwork {
            bodies: Objective::bodies(self),
            contacts: Vec::new(),
        };
        self.for_each_contact(|i, j, _, _, c| {
            if c.gap < 0.0 {
                network.contacts.push((i as u32, j as u32));
            }
        });
        network
    }

    /// Rattlers of the cell: bodies with fewer than `threshold` contacts
    /// (`h < 0`), removed iteratively ([`find_rattlers`]).
    fn rattlers(&self, threshold: usize) -> Vec<bool> {
        find_rattlers(&self.contacts(), threshold)
    }

    /// The contact numbers of the cell with the rattlers `rattler` (by
    /// count, as [`Self::rattlers`]; `f = D + rot_dof` coordinates per
    /// non-rattler): what [`crate::summarize`] gives for a packing in its
    /// fixed box, here in the deformed cell.
    fn contact_count(&self, rattler: &[bool]) -> ContactCount {
        let f = (D + self.shape().rot_dof()) as i64;
        let kept = rattler.iter().filter(|&&r| !r).count() as i64;
        ContactCount::of(&self.contacts(), rattler, f * kept, D)
    }
}

impl<const D: usize, S: Shape<D>> Cell<D> for Strained<D, S> {
    fn body_count(&self) -> usize {
        Objective::bodies(self)
    }

    fn rot_coordinates(&self) -> usize {
        self.shape().rot_dof()
    }

    fn pair_potential(&self) -> Potential {
        self.potential()
    }

    fn cell_volume(&self) -> f64 {
        self.volume()
    }

    fn visit_gap_hessians(
        &mut self,
        visit: &mut dyn FnMut(usize, usize, &Vector<D>, &jamkit_core::GapHessian<D>),
    ) -> Result<()> {
        self.for_each_gap_hessian(visit)
    }

    fn full_hessian(&mut self, rattler: &[bool]) -> Result<Hessian> {
        let (n, k, potential) = (self.body_count(), self.rot_coordinates(), self.potential());
        Hessian::of_contacts::<D>(n, k, potential, rattler, FULL_HESSIAN, |visit| {
            self.visit_gap_hessians(&mut |i, j, _, c| visit(i, j, c))
        })
    }
}
