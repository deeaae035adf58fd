//! [`Strained`]: a packing in a deformed periodic cell (Lees–Edwards for a
//! simple shear), an [`Objective`] the minimisers relax at fixed strain; the
//! cell of the elastic moduli's check by deformation and of the shear
//! stabilisation ([`crate::stabilise`]).

use crate::hessian::add_contact;
use crate::objective::Objective;
use crate::scene::Scene;
use jamkit_core::{
    Error, GapHessian, Matrix, Packing, Pair, PeriodicBox, Potential, Result, Shape, Vector,
};

/// `E` of a simple shear of the `(a, b)` plane: `x_a += γ x_b`.
pub fn simple_shear<const D: usize>(a: usize, b: usize) -> Matrix<D> {
    let mut e = Matrix::<D>::zeros();
    e[(a, b)] = 1.0;
    e
}

/// The shear planes `(a, b)`, `a < b`: `(0, 1)` in 2D; `(0, 1)`, `(0, 2)`,
/// `(1, 2)` in 3D.
pub fn shear_planes<const D: usize>() -> Vec<(usize, usize)> {
    (0..D)
        .flat_map(|a| (a + 1..D).map(move |b| (a, b)))
        .collect()
}

/// A packing in a homogeneously deformed periodic cell, with the pairs and
/// image vectors of the undeformed one fixed: the separation of pair `ij`
/// is `F R_ij + u_j − u_i`, `R_ij` its minimum image when it was built and
/// `u` the displacements since. An [`Objective`] in the same coordinates
/// as the [`Scene`] it was built from (translations then rotations, body
/// by body), with the same Hessian, so the engine's minimisers relax it.
///
/// Like the engine's neighbour list, the pairs are listed again while a
/// minimiser moves the bodies: as soon as some body has moved by a quarter
/// of the margin since the last listing ([`Objective::displace`]). Without
/// it a rearrangement (a plastic event under strain) would run on the fixed
/// list, where unlisted neighbours do not repel: bodies slide through each
/// other and the listed energy falls to zero (3D spheres, N = 128,
/// δφ = 10⁻¹: bodies moved by up to 1.9; `tests/moduli.rs`,
/// `dense_3d_spheres_stabilise`).
#[derive(Clone, Debug)]
pub struct Strained<const D: usize, S: Shape<D>> {
    pub(crate) shape: S,
    pub(crate) potential: Potential,
    pub(crate) sizes: Vec<f64>,
    pub(crate) orientations: Vec<S::Orientation>,
    pub(crate) geometry: Geometry<D>,
    /// The geometry and orientations at the last [`Objective::save`].
    pub(crate) saved: Option<Box<(Geometry<D>, Vec<S::Orientation>)>>,
    pub(crate) bbox: PeriodicBox<D>,
    pub(crate) inverse_masses: Vec<f64>,
    pub(crate) margin: f64,
    pub(crate) phi: f64,
}

/// The cell and the bodies' centres of a [`Strained`] packing (what a
/// listing of the pairs changes).
#[derive(Clone, Debug)]
pub(crate) struct Geometry<const D: usize> {
    pub(crate) displacement: Vec<Vector<D>>,
    pub(crate) pairs: Vec<(u32, u32, Vector<D>)>,
    pub(crate) deformation: Matrix<D>,
    pub(crate) volume: f64,
    /// The centres as of the last listing (or as built), for listing the
    /// pairs again.
    pub(crate) positions: Vec<Vector<D>>,
    /// The deformation folded in by [`Strained::rebase`]: the cell is
    /// `lattice · diag(L)` of the box it was built from.
    pub(crate) lattice: Matrix<D>,
}

impl<const D: usize, S: Shape<D>> Strained<D, S> {
    /// The packing of `scene`, undeformed, with every pair whose bounding
    /// balls come within `margin` of each other.
    pub fn new(scene: &Scene<D, S>, margin: f64) -> Result<Self> {
        if !(margin > 0.0 && margin.is_finite()) {
            return Err(Error::invalid(
                "margin",
                margin,
                "must be positive and finite",
            ));
        }
        scene.check_box()?;
        let p: &Packing<D, S> = scene.packing();
        if 2.0 * (2.0 * max_reach(p) + margin) > p.bbox.min_edge() {
            return Err(Error::invalid(
                "margin",
                margin,
                format!(
                    "must leave every pair range below half the box edge {}",
                    p.bbox.min_edge()
                ),
            ));
        }
        let reach: Vec<f64> = p
            .sizes
            .iter()
            .map(|&s| p.shape.bounding_radius(s))
            .collect();
        let mut pairs = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let r = p.bbox.minimum_image(p.positions[j] - p.positions[i]);
                let cut = reach[i] + reach[j] + margin;
                if r.norm_squared() < cut * cut {
                    pairs.push((i as u32, j as u32, r));
                }
            }
        }
        Ok(Self {
            shape: p.shape.clone(),
            potential: scene.potential(),
            sizes: p.sizes.clone(),
            orientations: p.orientations.clone(),
            geometry: Geometry {
                displacement: vec![Vector::<D>::zeros(); p.len()],
                pairs,
                deformation: Matrix::<D>::identity(),
                volume: p.bbox.volume(),
                positions: p.positions.clone(),
                lattice: Matrix::<D>::identity(),
            },
            saved: None,
            bbox: p.bbox.clone(),
            inverse_masses: p.inverse_masses(),
            margin,
            phi: p.phi(),
        })
    }

    /// Deform the cell to `F = I + γ E` (the displacements are kept),
    /// `F` relative to the cell as built or as last [`Self::rebase`]d.
    pub fn set_strain(&mut self, gamma: f64, e: &Matrix<D>) {
        self.geometry.deformation = Matrix::<D>::identity() + e * gamma;
    }

    /// Deform the cell by `F` (relative as for [`Self::set_strain`]).
    pub fn set_deformation(&mut self, f: Matrix<D>) {
        self.geometry.deformation = f;
    }

    /// The cell's deformation from the box it was built from,
    /// `F · lattice` (the cell is `F · lattice · diag(L)`).
    pub fn total_deformation(&self) -> Matrix<D> {
        self.geometry.deformation * self.geometry.lattice
    }

    /// Make the current cell and configuration the reference: each pair
    /// vector becomes its current separation `F R_ij + u_j − u_i`, each
    /// centre `F x_i + u_i`, the deformation is folded into the lattice
    /// and the displacements are zeroed. Energy, forces and stress are
    /// unchanged (up to round-off); strains set afterwards act on the
    /// current cell.
    pub fn rebase(&mut self) {
        let f = self.geometry.deformation;
        for (i, j, r) in &mut self.geometry.pairs {
            *r = f * *r + self.geometry.displacement[*j as usize]
                - self.geometry.displacement[*i as usize];
        }
        for (x, u) in self
            .geometry
            .positions
            .iter_mut()
            .zip(&mut self.geometry.displacement)
        {
            *x = f * *x + *u;
            *u = Vector::<D>::zeros();
        }
        self.geometry.lattice = f * self.geometry.lattice;
        self.geometry.volume *= determinant(&f);
        self.geometry.deformation = Matrix::<D>::identity();
    }

    /// [`Self::rebase`], then list the pairs again in the deformed cell:
    /// each pair's image is the minimum image in the coordinates of the
    /// undeformed box, `r = M ⌊M⁻¹ (x_j − x_i)⌉_L` with `M` the lattice.
    /// Exact while the lattice is near `I`: refused when an entry of
    /// `M − I` exceeds 0.2 or the pair range no longer fits in the sheared
    /// cell.
    pub fn relist(&mut self) -> Result<()> {
        self.rebase();
        let m = self.geometry.lattice;
        let strain = (m - Matrix::<D>::identity()).abs().max();
        if !(strain <= 0.2) {
            return Err(Error::invalid(
                "strain",
                strain,
                "the cell's strain (largest entry of F − I) must stay at or below 0.2 for its pair list",
            ));
        }
        let reach: Vec<f64> = (self.sizes.iter())
            .map(|&s| self.shape.bounding_radius(s))
            .collect();
        let widest = reach.iter().copied().fold(0.0, f64::max);
        // A sheared cell is narrower than its box by at most `D · strain`
        // of an edge.
        let width = self.bbox.min_edge() * (1.0 - D as f64 * strain);
        if 2.0 * (2.0 * widest + self.margin) > width {
            return Err(Error::invalid(
                "strain",
                strain,
                format!(
                    "the sheared cell (narrowest width about {width}) must stay wider than twice the pair range {}",
                    2.0 * widest + self.margin
                ),
            ));
        }
        if !self.list_pairs() {
            return Err(Error::invalid(
                "strain",
                strain,
                "the cell's deformation must be invertible",
            ));
        }
        Ok(())
    }

    /// List the pairs of the rebased cell (the listing of [`Self::relist`],
    /// without its checks of the lattice); `false` when the lattice is
    /// singular (the list is then left as it was).
    fn list_pairs(&mut self) -> bool {
        let m = self.geometry.lattice;
        let Some(inv) = inverse(&m) else {
            return false;
        };
        let reach: Vec<f64> = (self.sizes.iter())
            .map(|&s| self.shape.bounding_radius(s))
            .collect();
        let reduced: Vec<Vector<D>> = self.geometry.positions.iter().map(|x| inv * x).collect();
        self.geometry.pairs.clear();
        for i in 0..reduced.len() {
            for j in i + 1..reduced.len() {
                let r = m * self.bbox.minimum_image(reduced[j] - reduced[i]);
                let cut = reach[i] + reach[j] + self.margin;
                if r.norm_squared() < cut * cut {
                    self.geometry.pairs.push((i as u32, j as u32, r));
                }
            }
        }
        true
    }

    /// The energy of the cell.
    pub fn energy(&self) -> f64 {
        let mut grad = vec![0.0; Objective::dof(self)];
        self.energy_and_gradient(&mut grad)
    }

    /// The cell's volume, `V₀ det F`.
    pub fn volume(&self) -> f64 {
        self.geometry.volume * determinant(&self.geometry.deformation)
    }

    /// The bodies' centres in the deformed cell, `F x_i + u_i` (not wrapped
    /// into the cell: a body's centre minus its position in the box it was
    /// built from, mapped by [`Self::total_deformation`], is its non-affine
    /// displacement).
    pub fn centres(&self) -> Vec<Vector<D>> {
        let g = &self.geometry;
        (g.positions.iter().zip(&g.displacement))
            .map(|(x, u)| g.deformation * x + u)
            .collect()
    }

    /// The largest displacement of a centre since the pairs were listed.
    pub fn max_displacement(&self) -> f64 {
        self.geometry
            .displacement
            .iter()
            .map(|u| u.norm())
            .fold(0.0, f64::max)
    }

    /// Fail when some body moved so far since the pairs were listed that a
    /// pair missing from the list could touch (or an image vector could
    /// have changed). A minimiser step that moves a body further than a
    /// quarter of the margin before the list catches up only bends the
    /// path: the list made then is complete for the state it ends in as
    /// long as this check holds.
    pub fn check_pairs(&self) -> Result<()> {
        let moved = self.max_displacement();
        if 2.0 * moved >= self.margin {
            return Err(Error::Unsupported(format!(
                "a body moved by {moved:e} in the strained cell, more than half the pair margin {:e}: the strain is too large for a fixed pair list",
                self.margin
            )));
        }
        Ok(())
    }

    /// The strained separation of pair `(i, j)` whose separation in the
    /// cell as built is `r0`: `F r0 + u_j − u_i`.
    fn separation(&self, i: usize, j: usize, r0: &Vector<D>) -> Vector<D> {
        self.geometry.deformation * r0 + self.geometry.displacement[j]
            - self.geometry.displacement[i]
    }

    /// Every listed pair as `(i, j, r0, pair)`: `r0` its separation in the
    /// cell as built, `pair` the two bodies at their strained separation.
    fn strained_pairs(
        &self,
    ) -> impl Iterator<Item = (usize, usize, Vector<D>, Pair<D, S::Orientation>)> + '_ {
        self.geometry.pairs.iter().map(move |&(i, j, r0)| {
            let (i, j) = (i as usize, j as usize);
            let r = self.separation(i, j, &r0);
            let pair = Pair::new(
                self.sizes[i],
                self.orientations[i],
                self.sizes[j],
                self.orientations[j],
                r,
            );
            (i, j, r0, pair)
        })
    }

    /// Visit every contact of the strained cell as `(i, j, r0, r, contact)`:
    /// `r0` the pair's separation in the cell as built, `r` the strained
    /// one.
    pub fn for_each_contact<F>(&self, mut visit: F)
    where
        F: FnMut(usize, usize, &Vector<D>, &Vector<D>, &jamkit_core::Contact<D>),
    {
        for (i, j, r0, pair) in self.strained_pairs() {
            self.shape
                .contacts(&pair, 0.0, |c| visit(i, j, &r0, &pair.r_ij, &c));
        }
    }

    /// Visit every pair's contacts with their second derivatives as
    /// `(i, j, r, gap Hessian)`, `r` the strained separation.
    pub fn for_each_gap_hessian(
        &self,
        visit: &mut dyn FnMut(usize, usize, &Vector<D>, &GapHessian<D>),
    ) -> Result<()> {
        for (i, j, _, pair) in self.strained_pairs() {
            self.shape
                .gap_hessians(&pair, 0.0, |c| visit(i, j, &pair.r_ij, &c))?;
        }
        Ok(())
    }

    /// The family's shape.
    pub fn shape(&self) -> &S {
        &self.shape
    }

    /// The contact potential.
    pub fn potential(&self) -> Potential {
        self.potential
    }

    /// The stress tensor `σ_ab = (1/V) Σ_c v' g_a r_b` in the deformed cell.
    pub fn stress(&self) -> Matrix<D> {
        let mut sum = Matrix::<D>::zeros();
        self.for_each_contact(|_, _, _, r, c| {
            sum += c.grad_r * r.transpose() * self.potential.derivative(c.gap);
        });
        sum / self.volume()
    }

    /// `∂U/∂γ = Σ_c v' g·(E R_ij)` at the current cell and coordinates, for
    /// a strain `F → F + dγ E F₀` about the cell as built (`F₀ = I`): the
    /// derivative of the energy along the line `F = I + γ E` at fixed `u`
    /// and `q` (for finite-difference checks of [`strain_derivatives`]).
    pub fn strain_derivative(&self, e: &Matrix<D>) -> f64 {
        let mut sum = 0.0;
        self.for_each_contact(|_, _, r0, _, c| {
            sum += self.potential.derivative(c.gap) * c.grad_r.dot(&(e * r0));
        });
        sum
    }

    /// `p = −tr σ / D`.
    pub fn pressure(&self) -> f64 {
        -self.stress().trace() / D as f64
    }

    /// The energy and its gradient in the coordinates `(u, q)`.
    pub fn energy_and_gradient(&self, grad: &mut [f64]) -> f64 {
        let k = self.shape.rot_dof();
        let stride = D + k;
        grad.fill(0.0);
        let mut energy = 0.0;
        self.for_each_contact(|i, j, _, _, c| {
            let (v, dv) = self.potential.energy_and_derivative(c.gap);
            energy += v;
            for a in 0..D {
                grad[i * stride + a] -= dv * c.grad_r[a];
                grad[j * stride + a] += dv * c.grad_r[a];
            }
            for a in 0..k {
                grad[i * stride + D + a] += dv * c.grad_rot_i[a];
                grad[j * stride + D + a] += dv * c.grad_rot_j[a];
            }
        });
        energy
    }
}

/// `det m` by Gaussian elimination with partial pivoting (nalgebra's needs
/// bounds a generic `D` does not give).
pub fn determinant<const D: usize>(m: &Matrix<D>) -> f64 {
    let mut a = *m;
    let mut det = 1.0;
    for col in 0..D {
        let pivot = (col..D)
            .max_by(|&x, &y| a[(x, col)].abs().total_cmp(&a[(y, col)].abs()))
            .unwrap_or(col);
        if a[(pivot, col)] == 0.0 {
            return 0.0;
        }
        if pivot != col {
            a.swap_rows(pivot, col);
            det = -det;
        }
        det *= a[(col, col)];
        for row in col + 1..D {
            let f = a[(row, col)] / a[(col, col)];
            for c in col..D {
                a[(row, c)] -= f * a[(col, c)];
            }
        }
    }
    det
}

/// `m⁻¹` by Gauss–Jordan elimination with partial pivoting; `None` when
/// `m` is singular.
pub(crate) fn inverse<const D: usize>(m: &Matrix<D>) -> Option<Matrix<D>> {
    let mut a = *m;
    let mut inv = Matrix::<D>::identity();
    for col in 0..D {
        let pivot = (col..D).max_by(|&x, &y| a[(x, col)].abs().total_cmp(&a[(y, col)].abs()))?;
        if a[(pivot, col)] == 0.0 {
            return None;
        }
        a.swap_rows(pivot, col);
        inv.swap_rows(pivot, col);
        let d = a[(col, col)];
        for c in 0..D {
            a[(col, c)] /= d;
            inv[(col, c)] /= d;
        }
        for row in (0..D).filter(|&r| r != col) {
            let f = a[(row, col)];
            for c in 0..D {
                a[(row, c)] -= f * a[(col, c)];
                inv[(row, c)] -= f * inv[(col, c)];
            }
        }
    }
    Some(inv)
}

pub(crate) fn max_reach<const D: usize, S: Shape<D>>(p: &Packing<D, S>) -> f64 {
    p.sizes
        .iter()
        .map(|&s| p.shape.bounding_radius(s))
        .fold(0.0, f64::max)
}

impl<const D: usize, S: Shape<D>> Objective for Strained<D, S> {
    fn dof(&self) -> usize {
        self.sizes.len() * (D + self.shape.rot_dof())
    }

    fn bodies(&self) -> usize {
        self.sizes.len()
    }

    fn inverse_masses(&self) -> &[f64] {
        &self.inverse_masses
    }

    fn energy_gradient(&mut self, grad: &mut [f64]) -> f64 {
        self.energy_and_gradient(grad)
    }

    /// Move the bodies by `dq`; when some body has now moved by a quarter
    /// of the margin since the pairs were listed, [`Strained::rebase`] and
    /// list them again (energy and forces unchanged up to round-off).
    fn displace(&mut self, dq: &[f64]) {
        let stride = D + self.shape.rot_dof();
        for (i, chunk) in dq.chunks_exact(stride).enumerate() {
            for a in 0..D {
                self.geometry.displacement[i][a] += chunk[a];
            }
            if stride > D {
                self.shape.rotate(&mut self.orientations[i], &chunk[D..]);
            }
        }
        if 4.0 * self.max_displacement() >= self.margin {
            self.rebase();
            self.list_pairs();
        }
    }

    fn phi(&self) -> f64 {
        self.phi
    }

    fn translations_per_body(&self) -> usize {
        D
    }

    fn hessian_entries(&mut self, entries: &mut Vec<(u32, u32, f64)>) -> Result<bool> {
        let k = self.shape.rot_dof();
        let stride = (D + k) as u32;
        for (i, j, _, pair) in self.strained_pairs() {
            let (i, j) = (i as u32, j as u32);
            let outcome = self.shape.gap_hessians(&pair, 0.0, |c| {
                add_contact::<D>(
                    entries,
                    [i * stride, j * stride],
                    k,
                    self.potential,
                    &c,
                    false,
                )
            });
            match outcome {
                Ok(()) => {}
                Err(Error::Unsupported(_)) => return Ok(false),
                Err(e) => return Err(e),
            }
        }
        Ok(true)
    }

    /// Saves the geometry with the orientations: a listing of the pairs
    /// between save and restore changes the reference the displacements
    /// are measured from.
    fn save(&mut self) {
        match &mut self.saved {
            Some(saved) => {
                saved.0.clone_from(&self.geometry);
                saved.1.clone_from(&self.orientations);
            }
            None => {
                self.saved = Some(Box::new((self.geometry.clone(), self.orientations.clone())));
            }
        }
    }

    fn restore(&mut self) {
        if let Some(saved) = &self.saved {
            self.geometry.clone_from(&saved.0);
            self.orientations.clone_from(&saved.1);
        }
    }
}
