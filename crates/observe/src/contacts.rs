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

/// Each contact's gap gradient in the two bodies' own coordinates
/// (`D` translations then the rotational ones), in the order of
/// [`ContactNetwork::of_scene`]: `[∂h/∂q_i, ∂h/∂q_j]` per contact.
pub fn contact_rows<const D: usize, S: Shape<D>>(scene: &mut Scene<D, S>) -> Vec<[Vec<f64>; 2]> {
    let k = scene.packing().shape.rot_dof();
    let mut rows = Vec::new();
    scene.for_each_contact(0.0, |_, _, _, c| {
        if c.gap < 0.0 {
            let mut ri: Vec<f64> = (0..D).map(|a| -c.grad_r[a]).collect();
            ri.extend_from_slice(&c.grad_rot_i[..k]);
            let mut rj: Vec<f64> = (0..D).map(|a| c.grad_r[a]).collect();
            rj.extend_from_slice(&c.grad_rot_j[..k]);
            rows.push([ri, rj]);
        }
    });
    rows
}

/// Rattlers by rank, for bodies made of spheres. A body whose contacts all
/// sit on one of its spheres is held like a disk: its contact gradients span
/// only `D` of its `f` coordinates (a rotation about that sphere's centre
/// moves none of them), and its contacts carry force. So a body counts the
/// coordinates its contacts constrain, `r_b = rank` of its contacts'
/// gradient rows, and is a rattler while it has fewer than `r_b + 1`
/// contacts among the bodies not yet removed (iterated, as the count
/// rule). A body touching on several spheres has `r_b = f` and the rule is
/// the count rule `f + 1`. Returns the rattler flags and each body's rank.
pub fn find_rattlers_by_rank(
    network: &ContactNetwork,
    rows: &[[Vec<f64>; 2]],
) -> (Vec<bool>, Vec<usize>) {
    let n = network.bodies;
    let mut rattler = vec![false; n];
    let mut rank = vec![0; n];
    loop {
        let mut own: Vec<Vec<&[f64]>> = vec![Vec::new(); n];
        for (&(i, j), [ri, rj]) in network.contacts.iter().zip(rows) {
            let (i, j) = (i as usize, j as usize);
            if !rattler[i] && !rattler[j] {
                own[i].push(ri);
                own[j].push(rj);
            }
        }
        let mut changed = false;
        for b in 0..n {
            if rattler[b] {
                continue;
            }
            rank[b] = numerical_rank(&own[b]);
            if own[b].len() < rank[b] + 1 {
                rattler[b] = true;
                changed = true;
            }
        }
        if !changed {
            return (rattler, rank);
        }
    }
}

/// Rank of a few short rows by modified Gram–Schmidt; a residual below
/// `10⁻⁹` of the longest row counts as dependent.
///
/// NOTE: gradient rows have entries of order 1 (unit normals, lever arms of
/// order the body size), and a dependent row (a second contact on the same
/// sphere) leaves a residual at round-off, ~10⁻¹⁶; 10⁻⁹ separates the two
/// by seven orders of magnitude.
fn numerical_rank(rows: &[&[f64]]) -> usize {
    let scale = rows
        .iter()
        .map(|r| r.iter().map(|x| x * x).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for r in rows {
        let mut v = r.to_vec();
        for b in &basis {
            let dot: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
            for (x, y) in v.iter_mut().zip(b) {
                *x -= dot * y;
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > 1e-9 * scale {
            basis.push(v.iter().map(|x| x / norm).collect());
            if basis.len() == r.len() {
                break;
            }
        }
    }
    basis.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Body 0 of a 2D dimer touches bodies 1–3 on one sphere (rows of rank
    /// 2: the rotation about that sphere is free): it needs 3 contacts and
    /// stays. Body 4 touches 1–3 on two spheres (rank 3) with 3 contacts:
    /// it needs 4 and rattles. Bodies 1–3 are pinned by ≥ 4 independent
    /// rows each.
    #[test]
    fn rank_rule_keeps_bodies_held_on_one_sphere() {
        // Rows (n_x, n_y, s × n) for a sphere at offset s = (1, 0): the
        // third entry is n_y, so the rows span 2 dimensions.
        let one_sphere = |nx: f64, ny: f64| vec![nx, ny, ny];
        let free = |a: f64, b: f64, c: f64| vec![a, b, c];
        let mut contacts = Vec::new();
        let mut rows = Vec::new();
        for (j, (nx, ny)) in [(1.0, 0.0), (0.0, 1.0), (-0.6, -0.8)]
            .into_iter()
            .enumerate()
        {
            contacts.push((0, j as u32 + 1));
            rows.push([one_sphere(nx, ny), free(1.0, 0.2 * j as f64, 0.5)]);
        }
        for (j, r) in [[1.0, 0.0, 0.3], [0.0, 1.0, -0.4], [0.7, 0.7, 0.9]]
            .iter()
            .enumerate()
        {
            contacts.push((4, j as u32 + 1));
            rows.push([r.to_vec(), free(0.3, 1.0, j as f64)]);
        }
        // Pin bodies 1–3 to a fixed frame body 5 with three more rows each.
        for j in 1..=3u32 {
            for r in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
                contacts.push((j, 5));
                rows.push([r.to_vec(), r.to_vec()]);
            }
        }
        let net = ContactNetwork {
            bodies: 6,
            contacts,
        };
        let (rattler, rank) = find_rattlers_by_rank(&net, &rows);
        assert_eq!(rattler, vec![false, false, false, false, true, false]);
        assert_eq!(rank[0], 2);
        assert_eq!(rank[1], 3);
        assert_eq!(numerical_rank(&[&[1.0, 2.0], &[2.0, 4.0 + 1e-14]]), 1);
    }

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
