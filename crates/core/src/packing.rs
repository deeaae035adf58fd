//! A packing: bodies of one family in a periodic box.
//!
//! The state is stored per body (centre, orientation, size). Minimisers see
//! it as one flat vector of *generalised coordinates*: for each body its `D`
//! translations followed by its `rot_dof` rotational coordinates, with a mass
//! per coordinate (1 for translations, the family's inertia for rotations).
//! Rotational coordinates are applied as increments through
//! [`Shape::rotate`], so a family can keep a quaternion while FIRE sees three
//! small angles.

use crate::contact::Pair;
use crate::error::{Error, Result};
use crate::math::Vector;
use crate::orientation::BodyOrientation;
use crate::periodic::PeriodicBox;
use crate::shape::Shape;
use rand::{Rng, RngExt};

/// Most random draws for one body of an overlap-free start
/// ([`Policy::overlap_free_start`](crate::Policy::overlap_free_start)).
pub const MAX_PLACEMENT_TRIES: usize = 100_000;

/// Independent accumulators for [`largest_step_sq`].
const MAX_LANES: usize = 4;

/// `max_i Σ_{a < D} dq[i stride + a]²`, the largest squared translation.
///
/// NOTE: a pass of its own, with four bodies at a time in independent lanes
/// and a plain comparison (a `maxpd`): `f64::max` (NaN-aware) chained
/// through one accumulator made `displace` latency-bound, ~10 % of a disk
/// FIRE step. The maximum does not depend on the order; a NaN step is
/// ignored here as before (FIRE catches it in the energy).
#[inline]
fn largest_step_sq<const D: usize>(dq: &[f64], stride: usize) -> f64 {
    let sq = |c: &[f64]| {
        let mut s = 0.0;
        for a in 0..D {
            s += c[a] * c[a];
        }
        s
    };
    let mut lanes = [0.0f64; MAX_LANES];
    let mut blocks = dq.chunks_exact(MAX_LANES * stride);
    for block in &mut blocks {
        for (l, lane) in lanes.iter_mut().enumerate() {
            let s = sq(&block[l * stride..]);
            *lane = if s > *lane { s } else { *lane };
        }
    }
    for c in blocks.remainder().chunks_exact(stride) {
        let s = sq(c);
        lanes[0] = if s > lanes[0] { s } else { lanes[0] };
    }
    lanes
        .into_iter()
        .fold(0.0, |m, x| if x > m { x } else { m })
}

/// Bodies of one family in a periodic box.
#[derive(Clone, Debug)]
pub struct Packing<const D: usize, S: Shape<D>> {
    /// The family (its parameters).
    pub shape: S,
    /// The periodic box.
    pub bbox: PeriodicBox<D>,
    /// Centres, inside the box.
    pub positions: Vec<Vector<D>>,
    /// Orientations.
    pub orientations: Vec<S::Orientation>,
    /// Size `R⁰` of each body.
    pub sizes: Vec<f64>,
}

impl<const D: usize, S: Shape<D>> Packing<D, S> {
    /// Bodies with the given sizes placed uniformly at random (orientations
    /// uniform too) in a cubic box whose edge gives packing fraction `phi`;
    /// free of overlaps where the shape's policy asks for it
    /// ([`Policy::overlap_free_start`](crate::Policy::overlap_free_start)).
    pub fn random<R: Rng + ?Sized>(
        shape: S,
        sizes: Vec<f64>,
        phi: f64,
        rng: &mut R,
    ) -> Result<Self> {
        let overlap_free = shape.policy().overlap_free_start;
        Self::random_placed(shape, sizes, phi, overlap_free, rng)
    }

    /// [`Packing::random`] with overlaps allowed whatever the shape's
    /// policy: the same draws as its start for shapes that allow them (for
    /// tests of overlapping states, e.g. denser than a sequential placement
    /// reaches).
    pub fn random_overlapping<R: Rng + ?Sized>(
        shape: S,
        sizes: Vec<f64>,
        phi: f64,
        rng: &mut R,
    ) -> Result<Self> {
        Self::random_placed(shape, sizes, phi, false, rng)
    }

    fn random_placed<R: Rng + ?Sized>(
        shape: S,
        sizes: Vec<f64>,
        phi: f64,
        overlap_free: bool,
        rng: &mut R,
    ) -> Result<Self> {
        if !(phi > 0.0 && phi.is_finite()) {
            return Err(Error::invalid("phi", phi, "must be positive and finite"));
        }
        if sizes.is_empty() {
            return Err(Error::invalid("particles", 0, "must be at least 1"));
        }
        let total: f64 = sizes.iter().map(|&s| shape.volume(s)).sum();
        let edge = (total / phi).powf(1.0 / D as f64);
        let bbox = PeriodicBox::cubic(edge);
        if overlap_free {
            return Self::random_without_overlaps(shape, sizes, bbox, phi, rng);
        }
        let positions = (0..sizes.len())
            .map(|_| Vector::<D>::from_fn(|_, _| edge * rng.random::<f64>()))
            .map(|r| bbox.wrap(r))
            .collect();
        let orientations = (0..sizes.len())
            .map(|_| S::Orientation::random(rng))
            .collect();
        Ok(Self {
            shape,
            bbox,
            positions,
            orientations,
            sizes,
        })
    }

    /// Random sequential placement: each body in turn gets a uniform
    /// centre and orientation, redrawn until none of its contacts with the
    /// bodies already placed has a negative gap (at most
    /// [`MAX_PLACEMENT_TRIES`] draws per body, then an error). The stream
    /// draws centre then orientation per try, so the result is fixed by
    /// the seed. `O(N²)` contact tests, negligible at the dilute start.
    fn random_without_overlaps<R: Rng + ?Sized>(
        shape: S,
        sizes: Vec<f64>,
        bbox: PeriodicBox<D>,
        phi: f64,
        rng: &mut R,
    ) -> Result<Self> {
        let edge = bbox.edges()[0];
        let mut positions: Vec<Vector<D>> = Vec::with_capacity(sizes.len());
        let mut orientations = Vec::with_capacity(sizes.len());
        for (i, &size) in sizes.iter().enumerate() {
            let mut placed = false;
            for _ in 0..MAX_PLACEMENT_TRIES {
                let r = bbox.wrap(Vector::<D>::from_fn(|_, _| edge * rng.random::<f64>()));
                let o = S::Orientation::random(rng);
                let overlaps = positions.iter().zip(&orientations).zip(&sizes).any(
                    |((rj, oj), &sj): ((&Vector<D>, &S::Orientation), &f64)| {
                        let r_ij = bbox.minimum_image(r - rj);
                        let mut hit = false;
                        shape.contacts(&Pair::new(sj, *oj, size, o, r_ij), 0.0, |c| {
                            hit |= c.gap < 0.0
                        });
                        hit
                    },
                );
                if !overlaps {
                    positions.push(r);
                    orientations.push(o);
                    placed = true;
                    break;
                }
            }
            if !placed {
                return Err(Error::invalid(
                    "protocol.phi_start",
                    phi,
                    format!(
                        "no overlap-free place for body {i} after {MAX_PLACEMENT_TRIES} random tries; start from a lower packing fraction"
                    ),
                ));
            }
        }
        Ok(Self {
            shape,
            bbox,
            positions,
            orientations,
            sizes,
        })
    }

    /// Number of bodies `N`.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no bodies.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Generalised coordinates per body, `D + rot_dof`.
    pub fn dof_per_body(&self) -> usize {
        D + self.shape.rot_dof()
    }

    /// Total number of generalised coordinates.
    pub fn dof(&self) -> usize {
        self.len() * self.dof_per_body()
    }

    /// Summed volume of the bodies, `Σ_i S_i`.
    pub fn body_volume(&self) -> f64 {
        self.sizes.iter().map(|&s| self.shape.volume(s)).sum()
    }

    /// Packing fraction `φ = Σ_i S_i / V_box`, with true body volumes.
    pub fn phi(&self) -> f64 {
        self.body_volume() / self.bbox.volume()
    }

    /// Rescale the box and all centres affinely (sizes unchanged) to reach
    /// packing fraction `phi`.
    pub fn set_phi(&mut self, phi: f64) {
        let factor = (self.phi() / phi).powf(1.0 / D as f64);
        self.bbox.scale(factor);
        for r in &mut self.positions {
            *r = self.bbox.wrap(*r * factor);
        }
    }

    /// Inverse mass of every generalised coordinate: 1 for translations, the
    /// family's inverse inertia for rotations.
    pub fn inverse_masses(&self) -> Vec<f64> {
        let k = self.shape.rot_dof();
        let mut out = Vec::with_capacity(self.dof());
        for &s in &self.sizes {
            out.extend(std::iter::repeat_n(1.0, D));
            let inertia = self.shape.rot_inertia(s);
            out.extend(inertia[..k].iter().map(|&m| 1.0 / m));
        }
        out
    }

    /// Move every body by `dq` (flat generalised coordinates); returns the
    /// largest squared translation of a body, so that callers can tell when
    /// a neighbour list goes stale without a pass of their own.
    pub fn displace(&mut self, dq: &[f64]) -> f64 {
        let stride = self.dof_per_body();
        debug_assert_eq!(dq.len(), self.dof());
        for (i, chunk) in dq.chunks_exact(stride).enumerate() {
            let r = &mut self.positions[i];
            for a in 0..D {
                r[a] += chunk[a];
            }
            if stride > D {
                self.shape.rotate(&mut self.orientations[i], &chunk[D..]);
            }
        }
        largest_step_sq::<D>(dq, stride)
    }

    /// Bring every centre back into the primary cell.
    pub fn wrap_positions(&mut self) {
        for r in &mut self.positions {
            *r = self.bbox.wrap(*r);
        }
    }
}
