//! Contacts and rattlers.
//!
//! A *contact* is a gap `h < 0` (an overlap): with a repulsive potential that
//! vanishes at `h = 0`, only overlapping pairs carry force. Bodies made of
//! several spheres can touch another body at several points; each point is
//! a contact of its own.
//!
//! A *rattler* is a body held by too few contacts to be mechanically stable:
//! fewer than a threshold (`d + 1` for disks and near-disks, as in
//! O'Hern et al. 2003 and the paper). Removing one lowers its partners'
//! counts, so removal is iterated until no body falls below the threshold.

use jamkit_core::Shape;
use jamkit_engine::Scene;

/// The contacts of a packing, as `(i, j)` pairs with `i < j` (a pair appears
/// once per contact point).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactNetwork {
    /// Number of bodies.
    pub bodies: usize,
    /// One entry per contact.
    pub contacts: Vec<(u32, u32)>,
}

impl ContactNetwork {
    /// Every contact (`h < 0`) of the scene.
    pub fn of_scene<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>) -> Self {
        let bodies = scene.packing().len();
        let mut contacts = Vec::new();
        scene.for_each_contact(0.0, |i, j, _, c| {
            if c.gap < 0.0 {
                contacts.push((i as u32, j as u32));
            }
        });
        Self { bodies, contacts }
    }

    /// Contacts of each body.
    pub fn counts(&self) -> Vec<usize> {
        let mut z = vec![0; self.bodies];
        for &(i, j) in &self.contacts {
            z[i as usize] += 1;
            z[j as usize] += 1;
        }
        z
    }
}

/// Flag rattlers: iteratively remove bodies with fewer than `threshold`
/// contacts among the bodies not yet removed.
pub fn find_rattlers(network: &ContactNetwork, threshold: usize) -> Vec<bool> {
    let n = network.bodies;
    let mut z = network.counts();
    // Adjacency in CSR form, one entry per contact end.
    let mut start = vec![0usize; n + 1];
    for &(i, j) in &network.contacts {
        start[i as usize + 1] += 1;
        start[j as usize + 1] += 1;
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut adjacent = vec![0u32; 2 * network.contacts.len()];
    for &(i, j) in &network.contacts {
        adjacent[fill[i as usize]] = j;
        fill[i as usize] += 1;
        adjacent[fill[j as usize]] = i;
        fill[j as usize] += 1;
    }
    let mut rattler = vec![false; n];
    let mut queue: Vec<usize> = (0..n).filter(|&i| z[i] < threshold).collect();
    for &i in &queue {
        rattler[i] = true;
    }
    while let Some(i) = queue.pop() {
        for &j in &adjacent[start[i]..start[i + 1]] {
            let j = j as usize;
            if rattler[j] {
                continue;
            }
            z[j] -= 1;
            if z[j] < threshold {
                rattler[j] = true;
                queue.push(j);
            }
        }
    }
    rattler
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangle 0-1-2 with a tail 2-3-4: with threshold 2 the tail peels
    /// off in two rounds, the triangle stays.
    #[test]
    fn rattler_removal_is_iterative() {
        let net = ContactNetwork {
            bodies: 6,
            contacts: vec![(0, 1), (1, 2), (0, 2), (2, 3), (3, 4)],
        };
        assert_eq!(
            find_rattlers(&net, 2),
            vec![false, false, false, true, true, true]
        );
        // Threshold 3 empties everything: no body of a triangle has 3 contacts.
        assert!(find_rattlers(&net, 3).iter().all(|&r| r));
    }

    /// A double contact (dimers) counts twice.
    #[test]
    fn multiple_contacts_per_pair_count_separately() {
        let net = ContactNetwork {
            bodies: 2,
            contacts: vec![(0, 1), (0, 1)],
        };
        assert_eq!(net.counts(), vec![2, 2]);
        assert_eq!(find_rattlers(&net, 2), vec![false, false]);
    }
}
