//! Verlet neighbour lists built from a cell list.
//!
//! Each body `i` has a reach `b_i` (its bounding radius). The list holds every
//! pair `i < j` with `|r_ij| < b_i + b_j + skin` at the time of the build, so
//! it stays complete until some body has moved by more than `skin / 2`. The
//! build bins bodies into cells at least `2 b_max + skin` wide and scans the
//! `3^D` neighbouring cells; when the box is too small for three cells in
//! some direction it falls back to all pairs.
//!
//! The list is stored compressed (CSR): the partners of `i` are
//! `partners[start[i]..start[i + 1]]`, all greater than `i`.
//!
//! Data kept per pair beside the list (the families' [`PairMemo`]s)
//! follows a rebuild by [`NeighborList::carry_over`]: a pair listed before
//! keeps its entry, a pair new to the list starts at the default.
//!
//! [`PairMemo`]: jamkit_core::PairMemo

use jamkit_core::{PeriodicBox, Vector};

/// A half Verlet list (pairs `i < j`) with a skin.
#[derive(Clone, Debug)]
pub struct NeighborList<const D: usize> {
    skin: f64,
    start: Vec<u32>,
    partners: Vec<u32>,
    /// `owners[k]`: the body `i` whose partner is `partners[k]`.
    owners: Vec<u32>,
    /// `[b_i, b_j]` of each pair (read in list order instead of gathered).
    pair_reach: Vec<[f64; 2]>,
    reference: Vec<Vector<D>>,
    /// The pairs of the build before the last (for [`NeighborList::carry_over`]).
    previous: (Vec<u32>, Vec<u32>),
    drift: f64,
    builds: u64,
    // Scratch for the cell list, kept to avoid allocating on every rebuild.
    cell_of: Vec<usize>,
    cell_start: Vec<usize>,
    cell_members: Vec<u32>,
}

impl<const D: usize> NeighborList<D> {
    /// An empty list with the given skin; call [`NeighborList::build`] before use.
    pub fn new(skin: f64) -> Self {
        Self {
            skin,
            start: vec![0],
            partners: Vec::new(),
            owners: Vec::new(),
            pair_reach: Vec::new(),
            reference: Vec::new(),
            previous: (Vec::new(), Vec::new()),
            drift: 0.0,
            builds: 0,
            cell_of: Vec::new(),
            cell_start: Vec::new(),
            cell_members: Vec::new(),
        }
    }

    /// The skin width.
    pub fn skin(&self) -> f64 {
        self.skin
    }

    /// How many times the list was built.
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// Number of stored pairs.
    pub fn pair_count(&self) -> usize {
        self.partners.len()
    }

    /// Partners `j > i` of body `i`.
    #[inline(always)]
    pub fn partners(&self, i: usize) -> &[u32] {
        &self.partners[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// Every pair `(owners[k], partners[k])` in list order: `i` ascending,
    /// and the partners of each `i` ascending, as [`NeighborList::partners`]
    /// visits them.
    pub fn pairs(&self) -> (&[u32], &[u32]) {
        (&self.owners, &self.partners)
    }

    /// The reaches `[b_i, b_j]` of every pair, in the order of
    /// [`NeighborList::pairs`].
    pub fn pair_reach(&self) -> &[[f64; 2]] {
        &self.pair_reach
    }

    /// Record a move in which no body was displaced by more than `max_step`.
    ///
    /// The sum of these bounds since the last build bounds every body's
    /// displacement, so the list is certainly fresh while it stays below half
    /// the skin, and [`NeighborList::needs_rebuild`] is checked against the
    /// exact displacements only after that.
    #[inline]
    pub fn record_motion(&mut self, max_step: f64) {
        self.drift += max_step;
    }

    /// True when the list may have gone stale: some body moved more than
    /// half the skin since the last build (or the body count changed).
    pub fn needs_rebuild(&mut self, positions: &[Vector<D>]) -> bool {
        if positions.len() != self.reference.len() {
            return true;
        }
        if self.drift <= 0.5 * self.skin {
            return false;
        }
        let limit = 0.25 * self.skin * self.skin;
        let stale = positions
            .iter()
            .zip(&self.reference)
            .any(|(r, r0)| (r - r0).norm_squared() > limit);
        if !stale {
            // The exact check tightens the bound to the largest displacement.
            self.drift = positions
                .iter()
                .zip(&self.reference)
                .map(|(r, r0)| (r - r0).norm_squared())
                .fold(0.0, f64::max)
                .sqrt();
        }
        stale
    }

    /// Rebuild from (wrapped) positions and per-body reaches.
    pub fn build(&mut self, bbox: &PeriodicBox<D>, positions: &[Vector<D>], reach: &[f64]) {
        let n = positions.len();
        self.builds += 1;
        self.drift = 0.0;
        self.reference.clear();
        self.reference.extend_from_slice(positions);
        self.start.clear();
        self.start.push(0);
        std::mem::swap(&mut self.previous.0, &mut self.owners);
        std::mem::swap(&mut self.previous.1, &mut self.partners);
        self.partners.clear();
        self.owners.clear();
        self.pair_reach.clear();
        let max_reach = reach.iter().copied().fold(0.0, f64::max);
        let width = 2.0 * max_reach + self.skin;
        let mut cells = [0usize; D];
        for a in 0..D {
            cells[a] = (bbox.edges()[a] / width).floor() as usize;
        }
        if cells.iter().any(|&c| c < 3) || n < 64 {
            self.build_all_pairs(bbox, positions, reach);
        } else {
            self.build_cells(bbox, positions, reach, cells);
        }
    }

    /// Data kept per pair across the last build: `old` is in the order of
    /// the pairs before it, and `new` gets one entry per pair of the list
    /// in the order of [`NeighborList::pairs`], the old entry of the same
    /// `(i, j)` where there was one, else `T::default()`. Both lists are
    /// sorted by `(i, j)`, so this is one merge.
    pub fn carry_over<T: Copy + Default>(&self, old: &[T], new: &mut Vec<T>) {
        let (old_owners, old_partners) = (&self.previous.0, &self.previous.1);
        new.clear();
        if old.len() != old_partners.len() {
            new.resize(self.partners.len(), T::default());
            return;
        }
        let mut k = 0;
        for (&i, &j) in self.owners.iter().zip(&self.partners) {
            while k < old.len() && (old_owners[k], old_partners[k]) < (i, j) {
                k += 1;
            }
            new.push(
                if k < old.len() && (old_owners[k], old_partners[k]) == (i, j) {
                    old[k]
                } else {
                    T::default()
                },
            );
        }
    }

    fn within(&self, bbox: &PeriodicBox<D>, ri: &Vector<D>, rj: &Vector<D>, cut: f64) -> bool {
        bbox.minimum_image(rj - ri).norm_squared() < cut * cut
    }

    fn build_all_pairs(&mut self, bbox: &PeriodicBox<D>, positions: &[Vector<D>], reach: &[f64]) {
        let n = positions.len();
        for i in 0..n {
            for j in i + 1..n {
                if self.within(
                    bbox,
                    &positions[i],
                    &positions[j],
                    reach[i] + reach[j] + self.skin,
                ) {
                    self.partners.push(j as u32);
                    self.owners.push(i as u32);
                    self.pair_reach.push([reach[i], reach[j]]);
                }
            }
            self.start.push(self.partners.len() as u32);
        }
    }

    fn build_cells(
        &mut self,
        bbox: &PeriodicBox<D>,
        positions: &[Vector<D>],
        reach: &[f64],
        cells: [usize; D],
    ) {
        let n = positions.len();
        let total: usize = cells.iter().product();
        let coords = |r: &Vector<D>| -> [usize; D] {
            let w = bbox.wrap(*r);
            let mut c = [0usize; D];
            for a in 0..D {
                c[a] = ((w[a] / bbox.edges()[a] * cells[a] as f64) as usize).min(cells[a] - 1);
            }
            c
        };
        let index = |c: &[usize; D]| -> usize {
            let mut k = 0;
            for a in (0..D).rev() {
                k = k * cells[a] + c[a];
            }
            k
        };
        // Counting sort of bodies into cells.
        self.cell_of.clear();
        self.cell_of
            .extend(positions.iter().map(|r| index(&coords(r))));
        self.cell_start.clear();
        self.cell_start.resize(total + 1, 0);
        for &c in &self.cell_of {
            self.cell_start[c + 1] += 1;
        }
        for c in 0..total {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cell_members.clear();
        self.cell_members.resize(n, 0);
        let mut fill = self.cell_start.clone();
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.cell_members[fill[c]] = i as u32;
            fill[c] += 1;
        }
        let stencil = 3usize.pow(D as u32);
        let mut found: Vec<u32> = Vec::new();
        for i in 0..n {
            let ci = coords(&positions[i]);
            found.clear();
            for s in 0..stencil {
                let mut rest = s;
                let mut c = [0usize; D];
                for a in 0..D {
                    let offset = rest % 3;
                    rest /= 3;
                    c[a] = (ci[a] + cells[a] + offset - 1) % cells[a];
                }
                let k = index(&c);
                for &j in &self.cell_members[self.cell_start[k]..self.cell_start[k + 1]] {
                    let ju = j as usize;
                    if ju > i
                        && self.within(
                            bbox,
                            &positions[i],
                            &positions[ju],
                            reach[i] + reach[ju] + self.skin,
                        )
                    {
                        found.push(j);
                    }
                }
            }
            // Ascending partners: memory order, and the same list whatever the cell layout.
            found.sort_unstable();
            self.partners.extend_from_slice(&found);
            self.owners
                .extend(std::iter::repeat_n(i as u32, found.len()));
            self.pair_reach
                .extend(found.iter().map(|&j| [reach[i], reach[j as usize]]));
            self.start.push(self.partners.len() as u32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn brute<const D: usize>(
        bbox: &PeriodicBox<D>,
        pos: &[Vector<D>],
        reach: &[f64],
        cut: f64,
    ) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for i in 0..pos.len() {
            for j in i + 1..pos.len() {
                if bbox.minimum_image(pos[j] - pos[i]).norm() < reach[i] + reach[j] + cut {
                    out.push((i, j));
                }
            }
        }
        out
    }

    fn check<const D: usize>(n: usize, edge: f64) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let bbox = PeriodicBox::<D>::cubic(edge);
        let pos: Vec<Vector<D>> = (0..n)
            .map(|_| Vector::<D>::from_fn(|_, _| edge * rng.random::<f64>()))
            .collect();
        let reach: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { 0.5 } else { 0.7 }).collect();
        let mut list = NeighborList::<D>::new(0.3);
        list.build(&bbox, &pos, &reach);
        let mut got = Vec::new();
        for i in 0..n {
            got.extend(list.partners(i).iter().map(|&j| (i, j as usize)));
        }
        assert_eq!(got, brute(&bbox, &pos, &reach, 0.3));
    }

    /// Entries kept per pair follow their `(i, j)` through a rebuild that
    /// drops some pairs and adds others; new pairs start at the default.
    #[test]
    fn carry_over_keeps_each_pair_s_entry() {
        let bbox = PeriodicBox::<2>::cubic(10.0);
        let mut pos = vec![
            Vector::<2>::new(1.0, 1.0),
            Vector::<2>::new(2.0, 1.0),
            Vector::<2>::new(1.5, 1.8),
            Vector::<2>::new(6.0, 6.0),
        ];
        let reach = [0.5; 4];
        let mut list = NeighborList::<2>::new(0.3);
        list.build(&bbox, &pos, &reach);
        let (o, p) = list.pairs();
        let before: Vec<(u32, u32)> = o.iter().copied().zip(p.iter().copied()).collect();
        assert_eq!(before, [(0, 1), (0, 2), (1, 2)]);
        let tags: Vec<u32> = before.iter().map(|&(i, j)| 10 * i + j + 1).collect();
        // Body 2 leaves, body 3 joins body 1.
        pos[2] = Vector::<2>::new(5.0, 5.0);
        pos[3] = Vector::<2>::new(2.5, 1.5);
        list.build(&bbox, &pos, &reach);
        let mut kept = Vec::new();
        list.carry_over(&tags, &mut kept);
        let (o, p) = list.pairs();
        let after: Vec<(u32, u32)> = o.iter().copied().zip(p.iter().copied()).collect();
        assert_eq!(after, [(0, 1), (1, 3)]);
        assert_eq!(kept, [2, 0]);
        // Entries of the wrong length (none kept yet): all default.
        list.carry_over(&[], &mut kept);
        assert_eq!(kept, [0, 0]);
    }

    /// The cell list finds exactly the pairs an all-pairs scan finds.
    #[test]
    fn cell_list_matches_all_pairs_2d_and_3d() {
        check::<2>(500, 20.0);
        check::<3>(400, 9.0);
        check::<2>(100, 3.0); // fewer than three cells: all-pairs path
    }
}
