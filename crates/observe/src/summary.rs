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
//! * rotational rattlers (Shiraishi, Mizuno & Ikeda 2019): non-rattlers
//!   whose contacts constrain only `r_b < f` of their coordinates (a body
//!   made of spheres held on one sphere), with `f − r_b` free rotations.
//!   Counting those as missing contacts, `z_corr = z_J + 2 Σ_b (f − r_b) /
//!   N_nr = 2 f + 2 (margin − D) / N_nr` is `2 f` up to `O(1/N_nr)`.

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
    /// Non-rattlers whose contacts constrain fewer than `f` of their
    /// coordinates (`r_b < f`, [`RattlerRule::Rank`]): rotational rattlers,
    /// e.g. a dimer held on one sphere. 0 for [`RattlerRule::Count`].
    pub n_rot_rattlers: usize,
    /// `Σ_b (f − r_b)` over the non-rattlers: their free rotational
    /// coordinates (0 for [`RattlerRule::Count`]).
    pub free_rotations: usize,
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
    let f = D + scene.packing().shape.rot_dof();
    let (rattler, coordinates, rotations) = match rule {
        RattlerRule::Count(threshold) => {
            let rattler = find_rattlers(&network, threshold);
            let kept = rattler.iter().filter(|&&r| !r).count() as i64;
            (rattler, f as i64 * kept, FreeRotations::default())
        }
        RattlerRule::Rank => {
            let rows = contact_rows(scene);
            let (rattler, rank) = find_rattlers_by_rank(&network, &rows);
            let sum = (0..network.bodies)
                .filter(|&b| !rattler[b])
                .map(|b| rank[b] as i64)
                .sum();
            let rotations = FreeRotations::of(&rattler, &rank, f);
            (rattler, sum, rotations)
        }
    };
    let count = ContactCount::of(&network, &rattler, coordinates, D);
    JammingSummary {
        n_contacts: count.n_contacts,
        n_contacts_all: count.n_contacts_all,
        n_rattlers: count.n_rattlers,
        z_j: count.z,
        iso_margin: count.iso_margin,
        n_rot_rattlers: rotations.bodies,
        free_rotations: rotations.coordinates,
        pressure: scene.pressure(),
        rattler,
    }
}

/// The contact numbers of a network with its rattlers flagged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactCount {
    /// Contacts among non-rattlers, `N_c`.
    pub n_contacts: usize,
    /// Contacts among all bodies, rattlers included.
    pub n_contacts_all: usize,
    /// Number of rattlers.
    pub n_rattlers: usize,
    /// `z = 2 N_c / N_nr` (0 when every body rattles).
    pub z: f64,
    /// `N_c − (coordinates − D)`.
    pub iso_margin: i64,
}

impl ContactCount {
    /// Count `network`'s contacts among the bodies not flagged in
    /// `rattler`; `coordinates` is what the non-rattlers' contacts must
    /// constrain (`f N_nr` by the count rule, `Σ_b r_b` by rank) and `dim`
    /// the global translations left free.
    pub fn of(network: &ContactNetwork, rattler: &[bool], coordinates: i64, dim: usize) -> Self {
        let n_contacts = network
            .contacts
            .iter()
            .filter(|&&(i, j)| !rattler[i as usize] && !rattler[j as usize])
            .count();
        let n_rattlers = rattler.iter().filter(|&&r| r).count();
        let n_nr = network.bodies - n_rattlers;
        let z = if n_nr > 0 {
            2.0 * n_contacts as f64 / n_nr as f64
        } else {
            0.0
        };
        Self {
            n_contacts,
            n_contacts_all: network.contacts.len(),
            n_rattlers,
            z,
            iso_margin: n_contacts as i64 - (coordinates - dim as i64),
        }
    }
}

/// Rotational rattlers and their free coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct FreeRotations {
    /// Non-rattlers with `r_b < f`.
    bodies: usize,
    /// `Σ_b (f − r_b)` over the non-rattlers.
    coordinates: usize,
}

impl FreeRotations {
    /// From the rattler flags and ranks of [`find_rattlers_by_rank`], with
    /// `f` coordinates per body.
    fn of(rattler: &[bool], rank: &[usize], f: usize) -> Self {
        let mut out = Self::default();
        for (&gone, &r) in rattler.iter().zip(rank) {
            if !gone && r < f {
                out.bodies += 1;
                out.coordinates += f - r;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3D dimers along `x` (`f = 5`: rows `(n, (s × n)_y, (s × n)_z)` for a
    /// contact with normal `n` on the sphere at offset `s`; the spin about
    /// the axis is not a coordinate). Body 0 touches bodies 1–4 on its
    /// sphere at `s = (1, 0, 0)` only: its rows span the 3 translations (a
    /// rotation about that sphere's centre moves none of its contacts), so
    /// it stays with 4 ≥ 3 + 1 contacts and is one rotational rattler with
    /// `f − D = 2` free coordinates. Body 5 touches 1–4 on both spheres,
    /// `s = (±1, 0, 0)`, with 7 contacts of rank 5: pinned, not counted.
    /// Bodies 1–4 are pinned to a frame body 6 by five independent rows
    /// each.
    #[test]
    fn bodies_held_on_one_sphere_are_rotational_rattlers() {
        fn row(s: [f64; 3], n: [f64; 3]) -> Vec<f64> {
            let norm = n.iter().map(|x| x * x).sum::<f64>().sqrt();
            let n = n.map(|x| x / norm);
            vec![
                n[0],
                n[1],
                n[2],
                s[2] * n[0] - s[0] * n[2],
                s[0] * n[1] - s[1] * n[0],
            ]
        }
        let normals = [
            [1.0, 0.2, 0.1],
            [0.1, 1.0, -0.3],
            [-0.4, 0.3, 1.0],
            [-0.6, -0.7, -0.5],
        ];
        let other = |k: usize| vec![1.0, 0.1 * k as f64, 0.3, 0.0, 0.2];
        let (left, right) = ([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        let mut contacts = Vec::new();
        let mut rows = Vec::new();
        for (k, n) in normals.iter().enumerate() {
            contacts.push((0, k as u32 + 1));
            rows.push([row(right, *n), other(k)]);
        }
        let both = [right, left];
        for (k, n) in normals.iter().enumerate() {
            for s in &both[..if k == 3 { 1 } else { 2 }] {
                contacts.push((k as u32 + 1, 5));
                rows.push([other(k), row(*s, *n)]);
            }
        }
        for j in 1..=4u32 {
            for a in 0..5 {
                let mut r = vec![0.0; 5];
                r[a] = 1.0;
                contacts.push((j, 6));
                rows.push([r.clone(), r]);
            }
        }
        let net = ContactNetwork {
            bodies: 7,
            contacts,
        };
        let (rattler, rank) = find_rattlers_by_rank(&net, &rows);
        assert!(rattler.iter().all(|&r| !r), "{rattler:?}");
        assert_eq!(rank, vec![3, 5, 5, 5, 5, 5, 5]);
        assert_eq!(
            FreeRotations::of(&rattler, &rank, 5),
            FreeRotations {
                bodies: 1,
                coordinates: 2
            }
        );
        // A rattler is not counted, whatever its rank.
        let mut gone = rattler.clone();
        gone[0] = true;
        assert_eq!(FreeRotations::of(&gone, &rank, 5), FreeRotations::default());
    }
}
