//! A [`Scene`] as the minimisers see it: its [`Objective`], with the
//! Hessian and the stiffness blocks assembled by [`crate::hessian`].

use crate::objective::Objective;
use crate::scene::Scene;
use jamkit_core::Shape;

impl<const D: usize, S: Shape<D>> Objective for Scene<D, S> {
    fn dof(&self) -> usize {
        self.packing.dof()
    }

    fn bodies(&self) -> usize {
        self.packing.len()
    }

    fn inverse_masses(&self) -> &[f64] {
        &self.inverse_masses
    }

    fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
        Scene::energy_gradient(self, grad)
    }

    fn displace(&mut self, dq: &[f64]) {
        let max_sq = self.packing.displace(dq);
        self.neighbors.record_motion(max_sq.sqrt());
    }

    fn phi(&self) -> f64 {
        self.packing.phi()
    }

    fn translations_per_body(&self) -> usize {
        D
    }

    fn hessian_entries(&mut self, entries: &mut Vec<(u32, u32, f64)>) -> jamkit_core::Result<bool> {
        // A family without second derivatives is minimised by FIRE alone.
        match crate::hessian::Hessian::of_scene(self, &[], Default::default()) {
            Ok(h) => {
                entries.extend_from_slice(&h.entries);
                Ok(true)
            }
            Err(jamkit_core::Error::Unsupported(_)) => Ok(false),
            Err(e) => Err(e),
        }
    }

    fn stiffness_blocks(&mut self, blocks: &mut Vec<f64>) -> bool {
        crate::hessian::stiffness_blocks(self, blocks);
        true
    }

    fn save(&mut self) {
        let (positions, orientations) = &mut self.saved;
        positions.clone_from(&self.packing.positions);
        orientations.clone_from(&self.packing.orientations);
    }

    fn restore(&mut self) {
        let (positions, orientations) = &self.saved;
        self.packing.positions.clone_from(positions);
        self.packing.orientations.clone_from(orientations);
        self.rebuild_neighbors();
    }
}
