//! Finite-difference checks of analytic derivatives.
//!
//! Every family's gap derivatives end up in [`Scene::energy_gradient`]; this
//! module compares that gradient with a central difference of the energy in
//! every generalised coordinate (rotations included, applied through the
//! family's `rotate`). Tests of each family call it; so should a new family.

use crate::objective::Objective;
use crate::scene::Scene;
use jamkit_core::Shape;

/// Largest absolute difference between the analytic gradient and the
/// central difference `(V(q + ε e_a) − V(q − ε e_a)) / 2ε`, and the largest
/// gradient component (to make the error relative).
pub fn gradient_error<const D: usize, S: Shape<D>>(scene: &Scene<D, S>, step: f64) -> (f64, f64) {
    let mut work = scene.clone();
    let n = work.dof();
    let mut grad = vec![0.0; n];
    work.energy_gradient(&mut grad);
    let mut scratch = vec![0.0; n];
    let mut dq = vec![0.0; n];
    let mut max_err: f64 = 0.0;
    for a in 0..n {
        let mut plus = scene.clone();
        dq[a] = step;
        plus.displace(&dq);
        let e_plus = plus.energy_gradient(&mut scratch);
        let mut minus = scene.clone();
        dq[a] = -step;
        minus.displace(&dq);
        let e_minus = minus.energy_gradient(&mut scratch);
        dq[a] = 0.0;
        let numeric = (e_plus - e_minus) / (2.0 * step);
        max_err = max_err.max((numeric - grad[a]).abs());
    }
    let max_grad = grad.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    (max_err, max_grad)
}
