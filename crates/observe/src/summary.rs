//! The jamming summary of a packing.
//!
//! With `N_nr` non-rattlers carrying `N_c` contacts among themselves and
//! `f = D + rot_dof` degrees of freedom per body:
//!
//! * `z_J = 2 N_c / N_nr`;
//! * the isostaticity margin `N_c − (f N_nr − D)`: with periodic boundaries
//!   the `D` global translations are free, so a rigid network needs at least
//!   `f N_nr − D + 1` contacts (one more than the degrees of freedom, to fix
//!   the pressure) and the margin of a jammed packing of spheres or rigid
//!   bodies made of spheres is at least 1. For spheres it reads
//!   `N_c − D (N_nr − 1)`.

use crate::contacts::{ContactNetwork, find_rattlers};
use jamkit_core::Shape;
use jamkit_engine::Scene;
use serde::{Deserialize, Serialize};

/// Contact statistics of a (jammed) packing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JammingSummary {
    /// Contacts among non-rattlers, `N_c`.
    pub n_contacts: usize,
    /// Contacts among all bodies, rattlers included.
    pub n_contacts_all: usize,
    /// Number of rattlers.
    pub n_rattlers: usize,
    /// `z_J = 2 N_c / N_nr` (0 when every body rattles).
    pub z_j: f64,
    /// `N_c − (f N_nr − D)`.
    pub iso_margin: i64,
    /// Virial pressure.
    pub pressure: f64,
    /// Which bodies rattle.
    pub rattler: Vec<bool>,
}

/// Contacts, rattlers (below `threshold` contacts) and isostaticity of a scene.
pub fn summarize<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    threshold: usize,
) -> JammingSummary {
    let network = ContactNetwork::of_scene(scene);
    let rattler = find_rattlers(&network, threshold);
    let n_contacts = network
        .contacts
        .iter()
        .filter(|&&(i, j)| !rattler[i as usize] && !rattler[j as usize])
        .count();
    let n_rattlers = rattler.iter().filter(|&&r| r).count();
    let n_nr = network.bodies - n_rattlers;
    let f = (D + scene.packing().shape.rot_dof()) as i64;
    let z_j = if n_nr > 0 {
        2.0 * n_contacts as f64 / n_nr as f64
    } else {
        0.0
    };
    let iso_margin = n_contacts as i64 - (f * n_nr as i64 - D as i64);
    JammingSummary {
        n_contacts,
        n_contacts_all: network.contacts.len(),
        n_rattlers,
        z_j,
        iso_margin,
        pressure: scene.pressure(),
        rattler,
    }
}
