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

use crate::contacts::{ContactNetwork, contact_rows, find_rattlers, find_rattlers_by_rank};
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

/// Which bodies are rattlers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RattlerRule {
    /// Fewer than this many contacts (iterated): `d + 1` for disks and
    /// near-disks, `f + 1` as set by a family or the experiment.
    Count(usize),
    /// Fewer than `r_b + 1` contacts, `r_b` the rank of the body's contact
    /// gradients in its own coordinates ([`find_rattlers_by_rank`]): for
    /// bodies made of spheres, where a body held on one sphere keeps its
    /// contacts but not its rotation. Its margin counts `r_b` coordinates.
    Rank,
}

/// Contacts, rattlers (below `threshold` contacts) and isostaticity of a scene.
pub fn summarize<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    threshold: usize,
) -> JammingSummary {
    summarize_with(scene, RattlerRule::Count(threshold))
}

/// Contacts, rattlers by `rule` and isostaticity of a scene. With
/// [`RattlerRule::Rank`] the margin is `N_c − (Σ_b r_b − D)` over the
/// non-rattlers (`r_b = f` for a body pinned on several spheres).
pub fn summarize_with<const D: usize, S: Shape<D>>(
    scene: &mut Scene<D, S>,
    rule: RattlerRule,
) -> JammingSummary {
    let network = ContactNetwork::of_scene(scene);
    let f = (D + scene.packing().shape.rot_dof()) as i64;
    let (rattler, coordinates) = match rule {
        RattlerRule::Count(threshold) => {
            let rattler = find_rattlers(&network, threshold);
            let kept = rattler.iter().filter(|&&r| !r).count() as i64;
            (rattler, f * kept)
        }
        RattlerRule::Rank => {
            let rows = contact_rows(scene);
            let (rattler, rank) = find_rattlers_by_rank(&network, &rows);
            let sum = (0..network.bodies)
                .filter(|&b| !rattler[b])
                .map(|b| rank[b] as i64)
                .sum();
            (rattler, sum)
        }
    };
    let n_contacts = network
        .contacts
        .iter()
        .filter(|&&(i, j)| !rattler[i as usize] && !rattler[j as usize])
        .count();
    let n_rattlers = rattler.iter().filter(|&&r| r).count();
    let n_nr = network.bodies - n_rattlers;
    let z_j = if n_nr > 0 {
        2.0 * n_contacts as f64 / n_nr as f64
    } else {
        0.0
    };
    let iso_margin = n_contacts as i64 - (coordinates - D as i64);
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
