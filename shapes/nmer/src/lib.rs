//! # Rigid bodies made of spheres: the `nmer` family (2D and 3D)
//!
//! A body of size `R⁰` is the union of `k` balls at fixed body-frame
//! offsets `R⁰ s_a` with radii `R⁰ ρ_a` (`a = 1 … k`): a dimer, a linear
//! trimer, a triangle, … The size distribution scales the whole body. The
//! body frame's origin is its centre of mass (`s_a` weighted by `ρ_a^D`).
//!
//! **Dimers.** `alpha: α` gives two equal spheres of radius `r = R⁰`
//! whose centres are `ℓ = 2r(α − 1)` apart, so that the aspect ratio is
//! `α = (ℓ + 2r)/(2r)`: offsets `±(α − 1) R⁰` along the body axis (the
//! body `x` axis in 2D, `z` in 3D). With the default binary sizes 0.5/0.7
//! the spheres are the disks of the `sphere` family; `α = 1` *is* that
//! family and the registry runs it as such.
//!
//! **Contacts.** Every sphere `a` of body `i` and sphere `b` of body `j`
//! form a contact of their own. With world offsets `d_a = R⁰_i R(o_i) s_a`,
//! `d_b = R⁰_j R(o_j) s_b` and `v = r_ij + d_b − d_a`, `n = v/|v|`:
//!
//! ```text
//! h_ab = |v| − R⁰_i ρ_a − R⁰_j ρ_b,
//! ∂h/∂r_j = n = −∂h/∂r_i,
//! ∂h/∂ω_i = −d_a × n,      ∂h/∂ω_j = d_b × n,
//! ```
//!
//! where `ω` is a small rotation vector applied as `exp(ω) ∘ o` (world
//! frame). In 2D `ω = θ ẑ` and `∂h/∂θ_i = −(d_a × n)_z`. A 3D body has
//! three rotational coordinates (the world components of `ω`), except a
//! **linear** body (all centres on one line, the body `z` axis), whose
//! rotation about its own axis moves nothing: it has two, the rotations
//! about `e₁ = R(o) x̂` and `e₂ = R(o) ŷ`, so `∂h/∂q_p = e_p · ∂h/∂ω`.
//! Second derivatives (for the Hessian) are in [`contact`].
//!
//! **Volume**: the exact volume of the union ([`volume`]): the lens of a
//! dimer with `α < 2` is counted once.
//!
//! **Inertia.** FIRE gives every translation the mass 1, so the default
//! moment of inertia is that of a unit mass spread over the spheres:
//! sphere `a` carries the mass `m_a = ρ_a^D / Σ_b ρ_b^D` (uniform density,
//! overlapping lenses counted twice: the minima do not depend on the
//! masses, only the route FIRE takes), a solid disk (`ρ²/2`) or ball
//! (`2ρ²/5`) about its centre:
//!
//! ```text
//! 2D:          I = (R⁰)² Σ_a m_a (|s_a|² + ρ_a²/2),
//! 3D linear:   I = (R⁰)² Σ_a m_a (s_{a,z}² + 2ρ_a²/5)   (both perpendicular axes),
//! 3D general:  I = (R⁰)² Σ_a m_a (2|s_a|²/3 + 2ρ_a²/5)   (trace/3 of the tensor).
//! ```
//!
//! FIRE takes one mass per coordinate, so a non-linear 3D body gets the
//! mean principal moment on all three world axes. `inertia: x` replaces
//! all of this by the constant `I = x`.
//!
//! **Rattlers and isostaticity.** A body has `f = D + rot_dof` degrees of
//! freedom (3 for a 2D body, 5 for a linear 3D body, 6 otherwise); a body
//! with fewer than `f + 1` contacts is a rattler (removed iteratively; the
//! experiment's `rattlers.min_contacts` overrides it). Bodies made of
//! spheres jam isostatic (Ikeda, appendix A): `N_c ≥ f N_nr − D + 1`, so
//! dimers reach `z_J = 2f = 4D − 2`.

pub mod contact;
pub mod orientation;
mod slots;
pub mod volume;

pub use orientation::{Angle, Quaternion};

use jamkit_core::Error;
use jamkit_core::{Dims, Family, FamilyInfo, ParamSpec, ShapeVisitor, Vector};
use serde::Deserialize;

/// The family's self-description.
pub const INFO: FamilyInfo = FamilyInfo {
    name: "nmer",
    about: "rigid bodies made of k spheres at fixed offsets (dimers of aspect ratio α, trimers, …): several contacts per pair (2D, 3D)",
    dims: Dims::Only(&[2, 3]),
    params: &[
        ParamSpec {
            name: "alpha",
            about: "a dimer of aspect ratio α = (ℓ + 2r)/(2r) ≥ 1, sphere radius r = R0 (α = 1 runs as the sphere family); give alpha or spheres",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "spheres",
            about: "a general body: list of (offset: [x, y(, z)], radius: ρ) in units of R0, at least 2 spheres, none inside another",
            is_list: true,
            default: Some("None"),
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia of every rotational coordinate; None: from the geometry (unit mass, uniform density)",
            is_list: false,
            default: Some("None"),
            added: None,
        },
    ],
};

/// Most spheres a body may have (the pair loop keeps offsets on the stack).
pub const MAX_SPHERES: usize = 16;

/// Relative distance from a line below which a body counts as linear.
///
/// NOTE: a body whose centres are within `10⁻⁹` (relative to its extent)
/// of one line is made exactly linear, a change far below any gap that
/// matters at jamming (overlaps ~10⁻⁸ of the radius are the smallest
/// contacts), and loses the rotation about its axis.
const LINEAR_TOL: f64 = 1e-9;

/// One sphere of a general body, in units of the body size `R⁰`.
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Body-frame offset of the centre (`D` numbers).
    pub offset: Vec<f64>,
    /// Radius.
    pub radius: f64,
}

/// Parameters of `nmer`, as read from an experiment file (defaults from
/// [`INFO`] are filled in before parsing). Exactly one of `alpha` and
/// `spheres` is given.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NmerParams {
    /// Aspect ratio of a dimer.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub alpha: Option<f64>,
    /// Spheres of a general body.
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub spheres: Option<Vec<SphereSpec>>,
    /// Moment of inertia (`None`: from the geometry).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
}

impl NmerParams {
    /// True for a dimer with `α = 1`: two coincident spheres, i.e. one
    /// sphere, which the registry runs as the `sphere` family.
    pub fn is_single_sphere(&self) -> bool {
        self.alpha == Some(1.0) && self.spheres.is_none()
    }
}

/// The `nmer` family's registration.
pub struct NmerFamily;

impl Family for NmerFamily {
    const INFO: FamilyInfo = INFO;
    const EXAMPLE: &'static str = "(alpha: 1.5)";
    type Params = NmerParams;

    /// `α = 1`: two coincident spheres are one sphere (same random stream,
    /// hence the same packing as `sphere` for the same seed).
    fn visit<V: ShapeVisitor>(
        p: &NmerParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        match (dim, p.is_single_sphere()) {
            (_, true) => jamkit_sphere::visit_ball(dim, visitor),
            (2, false) => Ok(visitor.visit::<2, _>(Nmer::<2>::new(p)?)),
            (3, false) => Ok(visitor.visit::<3, _>(Nmer::<3>::new(p)?)),
            _ => Err(Error::invalid(
                "dim",
                dim,
                "nmer bodies exist in dim 2 or 3",
            )),
        }
    }
}

/// A rigid body made of spheres in `D` dimensions (`D` = 2 or 3), in units
/// of its size `R⁰`.
#[derive(Clone, Debug, PartialEq)]
pub struct Nmer<const D: usize> {
    /// Body-frame offsets `s_a` from the centre of mass.
    offsets: Vec<Vector<D>>,
    /// Radii `ρ_a`.
    radii: Vec<f64>,
    /// All centres on the body `z` axis (3D: two rotational coordinates).
    linear: bool,
    /// Moment of inertia per `(R⁰)²`, or the fixed override.
    inertia: f64,
    /// Whether `inertia` is an override (not scaled by `(R⁰)²`).
    inertia_fixed: bool,
    /// Volume of the union per `(R⁰)^D`.
    unit_volume: f64,
    /// `max_a (|s_a| + ρ_a)`: the bounding radius per `R⁰`.
    unit_reach: f64,
}

impl<const D: usize> Nmer<D> {
    /// Build and validate a body. Fails with the field named on: a `D`
    /// other than 2 or 3; both or
    /// neither of `alpha`/`spheres`; `α` not finite or `< 1` (`α = 1` is
    /// one sphere, see [`NmerParams::is_single_sphere`]); fewer than 2 or
    /// more than [`MAX_SPHERES`] spheres; an offset of the wrong length or
    /// not finite; a radius not positive and finite; a sphere inside
    /// another; an inertia not positive and finite.
    pub fn new(p: &NmerParams) -> jamkit_core::Result<Self> {
        if !(D == 2 || D == 3) {
            return Err(Error::invalid("dim", D, "nmer bodies exist in dim 2 or 3"));
        }
        let axis = if D == 3 { 2 } else { 0 };
        let spheres: Vec<(Vector<D>, f64)> = match (&p.alpha, &p.spheres) {
            (Some(_), Some(_)) => {
                return Err(Error::invalid(
                    "params.alpha",
                    "given together with params.spheres",
                    "give either alpha (a dimer) or spheres (a general body), not both",
                ));
            }
            (None, None) => {
                return Err(Error::invalid(
                    "params",
                    "neither alpha nor spheres",
                    "give alpha (a dimer of aspect ratio α ≥ 1) or spheres: [(offset: [...], radius: ...), ...]",
                ));
            }
            (Some(alpha), None) => {
                let alpha = *alpha;
                if !(alpha.is_finite() && alpha >= 1.0) {
                    return Err(Error::invalid(
                        "params.alpha",
                        alpha,
                        "must be a finite number ≥ 1 (α = (ℓ + 2r)/(2r))",
                    ));
                }
                if alpha == 1.0 {
                    return Err(Error::invalid(
                        "params.alpha",
                        alpha,
                        "α = 1 is a single sphere: run the `sphere` family (the registry does so)",
                    ));
                }
                let half = Vector::<D>::from_fn(|a, _| if a == axis { alpha - 1.0 } else { 0.0 });
                vec![(-half, 1.0), (half, 1.0)]
            }
            (None, Some(list)) => {
                let mut out = Vec::with_capacity(list.len());
                for (k, s) in list.iter().enumerate() {
                    if s.offset.len() != D || !s.offset.iter().all(|x| x.is_finite()) {
                        return Err(Error::invalid(
                            format!("params.spheres[{k}].offset"),
                            format!("{:?}", s.offset),
                            format!("must be {D} finite numbers (dim = {D})"),
                        ));
                    }
                    if !(s.radius > 0.0 && s.radius.is_finite()) {
                        return Err(Error::invalid(
                            format!("params.spheres[{k}].radius"),
                            s.radius,
                            "must be positive and finite",
                        ));
                    }
                    out.push((Vector::<D>::from_fn(|a, _| s.offset[a]), s.radius));
                }
                out
            }
        };
        let k = spheres.len();
        if !(2..=MAX_SPHERES).contains(&k) {
            return Err(Error::invalid(
                "params.spheres",
                format!("{k} spheres"),
                format!(
                    "must hold 2 to {MAX_SPHERES} spheres (a single sphere is the `sphere` family)"
                ),
            ));
        }
        for a in 0..k {
            for b in 0..k {
                let d = (spheres[a].0 - spheres[b].0).norm();
                if a != b
                    && d + spheres[a].1 <= spheres[b].1
                    && (a > b || d > 0.0 || spheres[a].1 < spheres[b].1)
                {
                    return Err(Error::invalid(
                        format!("params.spheres[{a}]"),
                        format!("{:?} radius {}", spheres[a].0.as_slice(), spheres[a].1),
                        format!(
                            "lies inside spheres[{b}]: it adds nothing to the body and would double-count contacts; remove it"
                        ),
                    ));
                }
            }
        }
        if let Some(i) = p.inertia
            && !(i > 0.0 && i.is_finite())
        {
            return Err(Error::invalid(
                "params.inertia",
                i,
                "must be positive and finite",
            ));
        }

        // Centre of mass, uniform density, lenses counted twice.
        let weights: Vec<f64> = spheres.iter().map(|s| s.1.powi(D as i32)).collect();
        let total: f64 = weights.iter().sum();
        let masses: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let com = spheres
            .iter()
            .zip(&masses)
            .fold(Vector::<D>::zeros(), |acc, (s, m)| acc + s.0 * *m);
        let mut offsets: Vec<Vector<D>> = spheres.iter().map(|s| s.0 - com).collect();
        let radii: Vec<f64> = spheres.iter().map(|s| s.1).collect();

        // Linear bodies: put the line on the body axis exactly.
        let far = offsets.iter().copied().fold(Vector::<D>::zeros(), |m, s| {
            if s.norm() > m.norm() { s } else { m }
        });
        let extent = far.norm();
        // The axis's sign is a convention: point it along the body axis (a
        // dimer keeps its offsets), else along the first non-zero component.
        let sign = [axis, 0, 1]
            .iter()
            .map(|&c| far[c])
            .find(|x| x.abs() > 1e-12 * extent)
            .map_or(1.0, f64::signum);
        let u = far * (sign / extent);
        let linear = offsets
            .iter()
            .all(|s| (s - u * s.dot(&u)).norm() <= LINEAR_TOL * extent);
        if linear && D == 3 {
            for s in &mut offsets {
                let t = s.dot(&u);
                *s = Vector::<D>::from_fn(|a, _| if a == axis { t } else { 0.0 });
            }
        }

        let own = if D == 2 { 0.5 } else { 0.4 };
        let geometric: f64 = offsets
            .iter()
            .zip(&radii)
            .zip(&masses)
            .map(|((s, r), m)| {
                let lever = match (D, linear) {
                    (2, _) => s.norm_squared(),
                    (_, true) => s[axis] * s[axis],
                    _ => 2.0 / 3.0 * s.norm_squared(),
                };
                m * (lever + own * r * r)
            })
            .sum();
        let balls: Vec<(Vector<D>, f64)> =
            offsets.iter().copied().zip(radii.iter().copied()).collect();
        let unit_volume = if D == 2 {
            volume::union_area(
                &balls
                    .iter()
                    .map(|(c, r)| (Vector::<2>::new(c[0], c[1]), *r))
                    .collect::<Vec<_>>(),
            )
        } else {
            volume::union_volume(
                &balls
                    .iter()
                    .map(|(c, r)| (Vector::<3>::new(c[0], c[1], c[2]), *r))
                    .collect::<Vec<_>>(),
            )
        };
        let unit_reach = balls.iter().map(|(c, r)| c.norm() + r).fold(0.0, f64::max);
        Ok(Self {
            offsets,
            radii,
            linear,
            inertia: p.inertia.unwrap_or(geometric),
            inertia_fixed: p.inertia.is_some(),
            unit_volume,
            unit_reach,
        })
    }

    /// Number of spheres `k`.
    pub fn spheres(&self) -> usize {
        self.offsets.len()
    }

    /// Body-frame offsets `s_a` (from the centre of mass, units of `R⁰`).
    pub fn offsets(&self) -> &[Vector<D>] {
        &self.offsets
    }

    /// Radii `ρ_a` (units of `R⁰`).
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// Whether all centres lie on one line (3D: two rotational coordinates).
    pub fn is_linear(&self) -> bool {
        self.linear
    }

    /// Volume (area) of the union of the spheres per `(R⁰)^D`.
    pub fn unit_volume(&self) -> f64 {
        self.unit_volume
    }

    /// Moment of inertia of each rotational coordinate of a body of size `size`.
    pub fn moment_of_inertia(&self, size: f64) -> f64 {
        if self.inertia_fixed {
            self.inertia
        } else {
            self.inertia * size * size
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::Shape;
    use jamkit_core::{Pair, ShapeExt};
    use std::f64::consts::PI;

    fn dimer<const D: usize>(alpha: f64) -> Nmer<D> {
        Nmer::<D>::new(&NmerParams {
            alpha: Some(alpha),
            spheres: None,
            inertia: None,
        })
        .unwrap()
    }

    /// A dimer's geometry from α: centres ±(α − 1) on the axis, reach α,
    /// area 2π − lens (2D) and volume 8π/3 − lens (3D), written out with
    /// the textbook circle-segment and spherical-cap formulas.
    #[test]
    fn dimer_geometry_follows_alpha() {
        for alpha in [1.1, 1.5, 2.0, 2.5] {
            let d = 2.0 * (alpha - 1.0);
            let (s2, s3) = (dimer::<2>(alpha), dimer::<3>(alpha));
            assert_relative_eq!(s2.offsets()[1][0], alpha - 1.0, epsilon = 1e-15);
            assert_relative_eq!(s3.offsets()[1][2], alpha - 1.0, epsilon = 1e-15);
            assert_relative_eq!(
                Shape::<2>::bounding_radius(&s2, 0.5),
                0.5 * alpha,
                epsilon = 1e-15
            );
            // Two unit disks at distance d overlap in 2 segments of half-angle acos(d/2).
            let lens2 = if d < 2.0 {
                2.0 * (d / 2.0f64).acos() - 0.5 * d * (4.0 - d * d).sqrt()
            } else {
                0.0
            };
            assert_relative_eq!(s2.unit_volume(), 2.0 * PI - lens2, max_relative = 1e-13);
            // Two unit balls: 2 caps of height 1 − d/2.
            let h = (1.0 - d / 2.0f64).max(0.0);
            let lens3 = 2.0 * PI * h * h * (3.0 - h) / 3.0;
            assert_relative_eq!(
                s3.unit_volume(),
                8.0 * PI / 3.0 - lens3,
                max_relative = 1e-13
            );
            assert!(s3.is_linear() && Shape::<3>::rot_dof(&s3) == 2);
            assert_eq!(Shape::<3>::policy(&s3).rattler_threshold, 6);
            assert_eq!(Shape::<2>::policy(&s2).rattler_threshold, 4);
        }
    }

    /// Swapping the bodies (and reversing r_ij) gives the same contacts:
    /// the same gaps, `∂h/∂r_j` reversed, the rotational derivatives swapped.
    #[test]
    fn contacts_are_symmetric_in_the_two_bodies() {
        let s = dimer::<3>(1.7);
        let oi = Quaternion::normalized(0.3, -0.5, 0.2, 0.9).unwrap();
        let oj = Quaternion::normalized(-0.7, 0.1, 0.4, 0.2).unwrap();
        let r = Vector::<3>::new(0.5, 0.6, -0.3);
        let collect = |a: &Quaternion, b: &Quaternion, r: Vector<3>, sa: f64, sb: f64| {
            s.pair_contacts(&Pair::new(sa, *a, sb, *b, r), f64::INFINITY)
        };
        let ij = collect(&oi, &oj, r, 0.6, 0.5);
        let ji = collect(&oj, &oi, -r, 0.5, 0.6);
        assert_eq!(ij.len(), 4);
        // Sphere pair (a, b) of ij is pair (b, a) of ji: index 2a + b ↔ 2b + a.
        for a in 0..2 {
            for b in 0..2 {
                let (x, y) = (&ij[2 * a + b], &ji[2 * b + a]);
                assert_relative_eq!(x.gap, y.gap, epsilon = 1e-14);
                assert_relative_eq!(x.grad_r, -y.grad_r, epsilon = 1e-14);
                for k in 0..2 {
                    assert_relative_eq!(x.grad_rot_i[k], y.grad_rot_j[k], epsilon = 1e-14);
                }
            }
        }
    }

    /// A 3D chain given along a skew line is recognised as linear (two
    /// rotational coordinates) and put on the body z axis; a bent one has
    /// three. The centre of mass is the origin.
    #[test]
    fn linear_bodies_are_detected_and_aligned() {
        let chain = |bend: f64| NmerParams {
            alpha: None,
            spheres: Some(vec![
                SphereSpec {
                    offset: vec![1.0, 2.0, 3.0],
                    radius: 0.8,
                },
                SphereSpec {
                    offset: vec![1.5, 2.5, 3.5 + bend],
                    radius: 1.0,
                },
                SphereSpec {
                    offset: vec![2.0, 3.0, 4.0],
                    radius: 0.8,
                },
            ]),
            inertia: None,
        };
        let s = Nmer::<3>::new(&chain(0.0)).unwrap();
        assert!(s.is_linear());
        assert_eq!(Shape::<3>::rot_dof(&s), 2);
        for o in s.offsets() {
            assert_eq!((o[0], o[1]), (0.0, 0.0));
        }
        assert_relative_eq!(s.offsets()[2][2], 0.75f64.sqrt(), epsilon = 1e-14);
        let bent = Nmer::<3>::new(&chain(0.3)).unwrap();
        assert_eq!(Shape::<3>::rot_dof(&bent), 3);
        let com: Vector<3> = bent
            .offsets()
            .iter()
            .zip(bent.radii())
            .map(|(o, r)| o * r.powi(3))
            .sum();
        assert_relative_eq!(com.norm(), 0.0, epsilon = 1e-14);
    }

    /// Geometric inertia: a dimer in 2D has I = (R⁰)² ((α − 1)² + ½).
    #[test]
    fn inertia_from_geometry_and_override() {
        let s = dimer::<2>(1.5);
        assert_relative_eq!(
            s.moment_of_inertia(0.5),
            0.25 * (0.25 + 0.5),
            epsilon = 1e-15
        );
        let fixed = Nmer::<2>::new(&NmerParams {
            alpha: Some(1.5),
            spheres: None,
            inertia: Some(0.3),
        })
        .unwrap();
        assert_eq!(fixed.moment_of_inertia(0.7), 0.3);
    }
}
