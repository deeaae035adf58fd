//! # Near-disks: the `fourier` and `fourier_sum` families
//!
//! A body of size `R⁰` and orientation `θ_i` has the polar outline
//!
//! ```text
//! R_i(φ) = R⁰ [1 + Δ F(θ_i − φ)],    F(ψ) = Σ_k a_k sin(n_k ψ + b_k)
//! ```
//!
//! (`fourier`: one mode with `a = 1/n`, `b = 0`, i.e. `F_n = sin(nψ)/n`, the
//! paper's model). Two bodies interact through the paper's first-order gap
//! (Ikeda, Eq. (8)),
//!
//! ```text
//! h_ij = |r_ij| − R_i⁰ − R_j⁰ − Δ [R_i⁰ F(θ_i − θ_ij) + R_j⁰ F(θ_j − θ_ji)],
//! θ_ij = atan2(y_j − y_i, x_j − x_i),   θ_ji = θ_ij + π,
//! ```
//!
//! exact to `O(Δ)`; its derivatives, with `u = r_ij/|r_ij|` and
//! `t = (−u_y, u_x)` (so `∂θ_ij/∂r_j = t/|r_ij|`), are
//!
//! ```text
//! ∂h/∂r_j = u + Δ [R_i⁰ F'(A_i) + R_j⁰ F'(A_j)] t / |r_ij|,
//! ∂h/∂θ_i = −Δ R_i⁰ F'(A_i),   ∂h/∂θ_j = −Δ R_j⁰ F'(A_j),
//! A_i = θ_i − θ_ij,   A_j = θ_j − θ_ij − π.
//! ```
//!
//! NOTE: no `atan2`, `sin` or `cos` in the pair loop: `e^{iθ_ij}` is the unit
//! vector `u`, `e^{iθ_i}` is stored with the orientation, and `e^{i n A}`
//! follows by complex multiplication, so angles near ±π need no care.
//!
//! Orientation convention: the outline of body `i` is
//! `R(φ) = R⁰ [1 + Δ F(θ_i − φ)]` in the lab direction `φ`, so that its
//! radius towards `j` is `R⁰[1 + Δ F(θ_i − θ_ij)]`, exactly the term in the
//! printed gap. (For the odd `F_n = sin(nψ)/n` this is the mirror image of
//! `R⁰[1 + Δ F(φ − θ_i)]`, the same body turned by `π/n`; for a sum of
//! modes with phases it is a different body, so the sign matters.)

use jamkit_core::math::{Unit, cmul, turn_unit};
use jamkit_core::{
    Contact, ContactLanes, Dims, Family, FamilyInfo, FastContacts, GapHessian, Look, Outline, Pair,
    PairLanes, ParamSpec, Policy, Shape, ShapeVisitor, Vector, contacts_one_by_one,
};
use jamkit_planar::first_order::{Profile, gap_hessian};
use jamkit_planar::gap2d::{self, GapModel, Jet3, SupportJet};
use serde::Deserialize;
use std::f64::consts::PI;

/// The `fourier` family's self-description.
pub const FOURIER_INFO: FamilyInfo = FamilyInfo {
    name: "fourier",
    about: "near-disks of radius R0 [1 + Δ F(θ − φ)] towards the direction φ, θ the body's angle, F(ψ) = sin(nψ)/n, with the paper's first-order gap, or a second-order or exact one (2D)",
    dims: Dims::Only(&[2]),
    params: &[
        ParamSpec {
            name: "n",
            about: "mode number, an integer ≥ 1",
            is_list: false,
            default: Some("2"),
            absent_is_omitted: false,
        },
        ParamSpec {
            name: "delta",
            about: "Δ, the amplitude; 0 gives disks (the sphere family)",
            is_list: false,
            default: None,
            absent_is_omitted: false,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia I of the angle θ; None: I = Δ (the paper's choice)",
            is_list: false,
            default: Some("None"),
            absent_is_omitted: false,
        },
        GAP_SPEC,
    ],
};

/// The `gap` parameter shared by both near-disk families.
const GAP_SPEC: ParamSpec = ParamSpec {
    name: "gap",
    about: "gap model, a string: \"FirstOrder\" (the paper's, error O(Δ²)), \"SecondOrder\" (error O(Δ³)), \"Exact\" (common normal; convex outlines only); None: FirstOrder",
    is_list: false,
    default: Some("None"),
    absent_is_omitted: false,
};

/// The `fourier_sum` family's self-description.
pub const FOURIER_SUM_INFO: FamilyInfo = FamilyInfo {
    name: "fourier_sum",
    about: "near-disks of radius R0 [1 + Δ F(θ − φ)] towards the direction φ, θ the body's angle, F(ψ) = Σ_k a_k sin(n_k ψ + b_k), with the first-order gap, or a second-order or exact one (2D)",
    dims: Dims::Only(&[2]),
    params: &[
        ParamSpec {
            name: "modes",
            about: "list of (n: integer ≥ 1, a: amplitude, b: phase in radians)",
            is_list: true,
            default: None,
            absent_is_omitted: false,
        },
        ParamSpec {
            name: "delta",
            about: "Δ, the overall amplitude",
            is_list: false,
            default: None,
            absent_is_omitted: false,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia; None: I = Δ",
            is_list: false,
            default: Some("None"),
            absent_is_omitted: false,
        },
        GAP_SPEC,
    ],
};

/// One Fourier mode `a sin(nθ + b)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mode {
    /// Mode number.
    pub n: u32,
    /// Amplitude.
    pub a: f64,
    /// Phase (radians).
    #[serde(default)]
    pub b: f64,
}

/// Parameters of `fourier`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FourierParams {
    /// Mode number.
    pub n: u32,
    /// Amplitude Δ.
    pub delta: f64,
    /// Moment of inertia (`None`: Δ).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
    /// The gap model (default: the paper's first order).
    #[serde(default, deserialize_with = "jamkit_planar::gap2d::deserialize_gap")]
    pub gap: GapModel,
}

/// Parameters of `fourier_sum`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FourierSumParams {
    /// The modes.
    pub modes: Vec<Mode>,
    /// Amplitude Δ.
    pub delta: f64,
    /// Moment of inertia (`None`: Δ).
    #[serde(default, deserialize_with = "jamkit_core::family::lenient_option")]
    pub inertia: Option<f64>,
    /// The gap model (default: the paper's first order).
    #[serde(default, deserialize_with = "jamkit_planar::gap2d::deserialize_gap")]
    pub gap: GapModel,
}

/// The `fourier` family's registration.
pub struct FourierFamily;

impl Family for FourierFamily {
    const INFO: FamilyInfo = FOURIER_INFO;
    const EXAMPLE: &'static str = "(n: 3, delta: 0.2)";
    type Params = FourierParams;

    fn visit<V: ShapeVisitor>(
        p: &FourierParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        visit_near_disk(NearDisk::fourier(p), p.delta, dim, visitor)
    }
}

/// The `fourier_sum` family's registration.
pub struct FourierSumFamily;

impl Family for FourierSumFamily {
    const INFO: FamilyInfo = FOURIER_SUM_INFO;
    const EXAMPLE: &'static str = "(modes: [(n: 2, a: 0.5), (n: 3, a: 0.1, b: 1.0)], delta: 0.2)";
    type Params = FourierSumParams;

    fn visit<V: ShapeVisitor>(
        p: &FourierSumParams,
        dim: usize,
        visitor: V,
    ) -> jamkit_core::Result<V::Output> {
        visit_near_disk(NearDisk::fourier_sum(p), p.delta, dim, visitor)
    }
}

/// Near-disks with `Δ = 0` are disks: they run as the sphere family, with
/// no rotational coordinates and the same random stream, hence the same
/// packing as `sphere` for the same seed.
fn visit_near_disk<V: ShapeVisitor>(
    shape: jamkit_core::Result<NearDisk>,
    delta: f64,
    dim: usize,
    visitor: V,
) -> jamkit_core::Result<V::Output> {
    let shape = shape?;
    if delta == 0.0 {
        jamkit_sphere::visit_ball(dim, visitor)
    } else {
        Ok(visitor.visit::<2, _>(shape))
    }
}

impl Outline for NearDisk {
    fn relative_radius(&self, psi: f64) -> f64 {
        NearDisk::relative_radius(self, psi)
    }
}

/// A near-disk family: `Δ`, the modes of `F`, and the moment of inertia.
#[derive(Clone, Debug, PartialEq)]
pub struct NearDisk {
    name: &'static str,
    delta: f64,
    modes: Vec<Mode>,
    /// `e^{i b_k}` of each mode.
    phases: Vec<(f64, f64)>,
    inertia: f64,
    /// `Σ |a_k|`, a bound on `|F|`.
    f_bound: f64,
    /// The gap model.
    gap: GapModel,
    /// Per unit size, how far the exact gap can fall below the first-order
    /// one (`Δ² F'²_max / (1 − Δ F_max)`, ∞ where that bound is not proven).
    exact_slack: f64,
}

/// An orientation: the shared planar rotation `e^{iθ}`
/// ([`jamkit_core::Rotation2`]); near-disks turn it by
/// [`Rotation2::turned`](jamkit_core::Rotation2::turned).
pub type Angle = jamkit_core::Rotation2;

/// `z²`, bit for bit `cmul(z, z)` (`ab + ba = 2ab` exactly).
#[inline(always)]
fn csq(z: (f64, f64)) -> (f64, f64) {
    (z.0 * z.0 - z.1 * z.1, 2.0 * (z.0 * z.1))
}

/// `z_i^n` and `z_j^n` for one mode number.
///
/// NOTE: the paper's modes (n ≤ 6) get straight-line code: `cpow`'s loop on
/// the bits of a run-time `n` kept the pair loop from overlapping pairs. Each
/// arm multiplies the same factors as `cpow` (products commute), so the
/// powers are bit for bit those of `cpow`.
#[inline(always)]
fn cpow_pair(z_i: (f64, f64), z_j: (f64, f64), n: u32) -> ((f64, f64), (f64, f64)) {
    match n {
        1 => (z_i, z_j),
        2 => (csq(z_i), csq(z_j)),
        3 => (cmul(csq(z_i), z_i), cmul(csq(z_j), z_j)),
        4 => (csq(csq(z_i)), csq(csq(z_j))),
        5 => (cmul(csq(csq(z_i)), z_i), cmul(csq(csq(z_j)), z_j)),
        6 => (cmul(csq(csq(z_i)), csq(z_i)), cmul(csq(csq(z_j)), csq(z_j))),
        _ => (cpow(z_i, n), cpow(z_j, n)),
    }
}

/// `F(A)` and `F'(A)` of both bodies of a pair for one mode with no phase,
/// from `(e^{inA_i}, e^{inA_j})` ([`NearDisk::f_pair`]).
#[inline(always)]
fn single_mode(m: Mode, (p_i, p_j): ((f64, f64), (f64, f64))) -> [(f64, f64); 2] {
    let (a, an) = (m.a, m.a * m.n as f64);
    [(a * p_i.1, an * p_i.0), (a * p_j.1, an * p_j.0)]
}

/// `z^n` by binary exponentiation.
#[inline(always)]
fn cpow(mut z: (f64, f64), mut n: u32) -> (f64, f64) {
    let mut acc = (1.0, 0.0);
    while n > 0 {
        if n & 1 == 1 {
            acc = cmul(acc, z);
        }
        z = cmul(z, z);
        n >>= 1;
    }
    acc
}

impl NearDisk {
    /// The `fourier` family: one mode `sin(nθ)/n`.
    pub fn fourier(p: &FourierParams) -> jamkit_core::Result<Self> {
        if p.n < 1 {
            return Err(jamkit_core::Error::invalid(
                "params.n",
                p.n.to_string(),
                "must be an integer ≥ 1",
            ));
        }
        Self::new(
            "fourier",
            p.delta,
            vec![Mode {
                n: p.n,
                a: 1.0 / p.n as f64,
                b: 0.0,
            }],
            p.inertia,
            p.gap,
        )
    }

    /// The `fourier_sum` family.
    pub fn fourier_sum(p: &FourierSumParams) -> jamkit_core::Result<Self> {
        Self::new("fourier_sum", p.delta, p.modes.clone(), p.inertia, p.gap)
    }

    fn new(
        name: &'static str,
        delta: f64,
        modes: Vec<Mode>,
        inertia: Option<f64>,
        gap: GapModel,
    ) -> jamkit_core::Result<Self> {
        let err = |field: &str, value: String, allowed: &str| {
            jamkit_core::Error::invalid(field, value, allowed)
        };
        if !delta.is_finite() || delta < 0.0 {
            return Err(err(
                "params.delta",
                delta.to_string(),
                "must be a finite number ≥ 0",
            ));
        }
        if modes.is_empty() {
            return Err(err(
                "params.modes",
                "[]".into(),
                "must list at least one mode (n, a, b)",
            ));
        }
        for (k, m) in modes.iter().enumerate() {
            if m.n < 1 {
                return Err(err(
                    &format!("params.modes[{k}].n"),
                    m.n.to_string(),
                    "must be an integer ≥ 1",
                ));
            }
            if !(m.a.is_finite() && m.b.is_finite()) {
                return Err(err(
                    &format!("params.modes[{k}]"),
                    format!("{m:?}"),
                    "a and b must be finite",
                ));
            }
        }
        // At Δ = 0 nothing turns (the registry runs such bodies as disks);
        // the default I = Δ would be 0, so take 1 there.
        let inertia = inertia.unwrap_or(if delta > 0.0 { delta } else { 1.0 });
        if !(inertia > 0.0 && inertia.is_finite()) {
            return Err(err(
                "params.inertia",
                inertia.to_string(),
                "must be positive and finite (the default I = Δ needs Δ > 0)",
            ));
        }
        let shape = Self {
            name,
            delta,
            phases: modes.iter().map(|m| (m.b.cos(), m.b.sin())).collect(),
            f_bound: modes.iter().map(|m| m.a.abs()).sum(),
            exact_slack: {
                let f_max: f64 = modes.iter().map(|m| m.a.abs()).sum();
                let df_max: f64 = modes.iter().map(|m| m.a.abs() * m.n as f64).sum();
                // The bound needs R_max/R_min = (1 + ΔF)/(1 − ΔF) < 1.85.
                if delta * f_max < 0.25 {
                    delta * delta * df_max * df_max / (1.0 - delta * f_max)
                } else {
                    f64::INFINITY
                }
            },
            modes,
            inertia,
            gap,
        };
        let min_r = shape.min_relative_radius();
        if min_r <= 0.0 {
            return Err(err(
                "params.delta",
                delta.to_string(),
                &format!(
                    "is so large that R(θ) ≤ 0 somewhere (min R/R0 = {min_r:.4}); the outline must stay star-shaped"
                ),
            ));
        }
        if gap == GapModel::Exact && !shape.is_convex() {
            return Err(err(
                "params.gap",
                "Exact".into(),
                &format!(
                    "needs a convex outline, and Δ = {delta} makes it non-convex (the common normal is then not unique); use FirstOrder or SecondOrder, or a smaller Δ"
                ),
            ));
        }
        Ok(shape)
    }

    /// The gap model.
    pub fn gap_model(&self) -> GapModel {
        self.gap
    }

    /// `Δ`.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// `F(φ)` and `F'(φ)` from `e^{iφ}`... for a given lab angle (slow path, for geometry).
    pub fn f_and_derivative(&self, phi: f64) -> (f64, f64) {
        let mut f = 0.0;
        let mut df = 0.0;
        for m in &self.modes {
            let arg = m.n as f64 * phi + m.b;
            f += m.a * arg.sin();
            df += m.a * m.n as f64 * arg.cos();
        }
        (f, df)
    }

    /// `F''(φ)`.
    pub fn f_second(&self, phi: f64) -> f64 {
        self.modes
            .iter()
            .map(|m| -m.a * (m.n as f64).powi(2) * (m.n as f64 * phi + m.b).sin())
            .sum()
    }

    /// `R(φ)/R⁰ = 1 + Δ F(φ)`.
    pub fn relative_radius(&self, phi: f64) -> f64 {
        1.0 + self.delta * self.f_and_derivative(phi).0
    }

    fn min_relative_radius(&self) -> f64 {
        (0..4096)
            .map(|k| self.relative_radius(2.0 * PI * k as f64 / 4096.0))
            .fold(f64::INFINITY, f64::min)
    }

    /// True when the outline is convex: the polar curvature numerator
    /// `r² + 2r'² − r r''` stays positive (sampled on 4096 angles).
    pub fn is_convex(&self) -> bool {
        (0..4096).all(|k| {
            let phi = 2.0 * PI * k as f64 / 4096.0;
            let (f, df) = self.f_and_derivative(phi);
            let (r, dr, ddr) = (
                1.0 + self.delta * f,
                self.delta * df,
                self.delta * self.f_second(phi),
            );
            r * r + 2.0 * dr * dr - r * ddr > 0.0
        })
    }

    /// Area in units of `(R⁰)²`: `π [1 + Δ² ⟨F²⟩]` with
    /// `⟨F²⟩ = (1/2π)∫F² = ½ Σ_{k,l: n_k = n_l} a_k a_l cos(b_k − b_l)`.
    pub fn relative_area(&self) -> f64 {
        let mut mean_f2 = 0.0;
        for p in &self.modes {
            for q in &self.modes {
                if p.n == q.n {
                    mean_f2 += 0.5 * p.a * q.a * (p.b - q.b).cos();
                }
            }
        }
        PI * (1.0 + self.delta * self.delta * mean_f2)
    }

    /// Asphericity `A = P²/(4π S)` by numerical integration of the perimeter
    /// `P = ∫ √(R² + R'²) dφ` (trapezoid rule on 8192 points, spectrally
    /// accurate for a periodic integrand).
    pub fn asphericity(&self) -> f64 {
        let m = 8192;
        let perimeter: f64 = (0..m)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / m as f64;
                let (f, df) = self.f_and_derivative(phi);
                ((1.0 + self.delta * f).powi(2) + (self.delta * df).powi(2)).sqrt()
            })
            .sum::<f64>()
            * 2.0
            * PI
            / m as f64;
        perimeter * perimeter / (4.0 * PI * self.relative_area())
    }

    /// The paper's first-order contact (module documentation) at distance
    /// `r = |r_ij|`.
    #[inline(always)]
    fn first_order(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
        r: f64,
    ) -> Contact<2> {
        // NOTE: coincident centres have no direction θ_ij; take θ_ij = 0
        // (deterministic; such a pair overlaps deeply and any direction
        // pushes it apart).
        let (u, inv_r) = if r > 0.0 {
            (r_ij * (1.0 / r), 1.0 / r)
        } else {
            (Vector::<2>::new(1.0, 0.0), 0.0)
        };
        let w_conj = (u[0], -u[1]);
        let [(f_i, df_i), (f_j, df_j)] = self.f_pair(o_i.unit(), o_j.unit(), w_conj);
        let d = self.delta;
        let gap = r - size_i - size_j - d * (size_i * f_i + size_j * f_j);
        let tangent = Vector::<2>::new(-u[1], u[0]);
        let grad_r = u + tangent * (d * (size_i * df_i + size_j * df_j) * inv_r);
        Contact {
            gap,
            grad_r,
            grad_rot_i: [-d * size_i * df_i, 0.0, 0.0],
            grad_rot_j: [-d * size_j * df_j, 0.0, 0.0],
        }
    }

    /// The first-order contacts of `W` pairs ([`Shape::contacts_lanes`]):
    /// `contacts`' bounding test and [`NearDisk::first_order`], lane by
    /// lane, the same operations in the same order, with the branch at
    /// `r = 0` turned into selects. `profile` maps `(e^{iA_i}, e^{iA_j})`
    /// to `[(F_i, F_i'), (F_j, F_j')]` ([`NearDisk::f_pair`]).
    ///
    /// NOTE: one loop over the lanes with no branch and no call in its body
    /// (for one mode `n` is a constant, so `e^{inA}` is a few products):
    /// the compiler vectorises it whole, and the AVX2 copy of the energy
    /// pass computes four pairs per instruction, square root and division
    /// included.
    #[inline(always)]
    fn first_order_lanes<const W: usize>(
        &self,
        p: &PairLanes<2, Angle, W>,
        out: &mut ContactLanes<2, W>,
        profile: impl Fn((f64, f64), (f64, f64)) -> [(f64, f64); 2],
    ) {
        let d = self.delta;
        for l in 0..W {
            let r = p.r2[l].sqrt();
            // `first_order`'s unit vector and 1/r, with its choice at r = 0.
            let inv = 1.0 / r;
            let positive = r > 0.0;
            let ux = if positive { p.r_ij[0][l] * inv } else { 1.0 };
            let uy = if positive { p.r_ij[1][l] * inv } else { 0.0 };
            let inv_r = if positive { inv } else { 0.0 };
            let w_conj = (ux, -uy);
            let (z_i, z_j) = (p.o_i[l].unit(), p.o_j[l].unit());
            let e_i = cmul(z_i, w_conj);
            let e_j = cmul((-z_j.0, -z_j.1), w_conj);
            let [(f_i, df_i), (f_j, df_j)] = profile(e_i, e_j);
            let (size_i, size_j) = (p.size_i[l], p.size_j[l]);
            out.found[l] = !(r - p.reach_i[l] - p.reach_j[l] > 0.0);
            out.gap[l] = r - size_i - size_j - d * (size_i * f_i + size_j * f_j);
            // u + t s with t = (−u_y, u_x), as `first_order` adds vectors.
            let s = d * (size_i * df_i + size_j * df_j) * inv_r;
            out.grad_r[0][l] = ux + -uy * s;
            out.grad_r[1][l] = uy + ux * s;
            out.grad_rot_i[0][l] = -d * size_i * df_i;
            out.grad_rot_j[0][l] = -d * size_j * df_j;
        }
    }

    /// [`NearDisk::first_order_lanes`] for one mode `m` with `m.n = N`, a
    /// constant, so that `e^{iNA}` is straight-line products.
    #[inline(always)]
    fn single_mode_lanes<const N: u32, const W: usize>(
        &self,
        m: Mode,
        pairs: &PairLanes<2, Angle, W>,
        out: &mut ContactLanes<2, W>,
    ) {
        self.first_order_lanes(pairs, out, |e_i, e_j| {
            single_mode(m, cpow_pair(e_i, e_j, N))
        });
    }

    /// The contact of the second-order or the exact gap.
    ///
    /// NOTE: kept out of line and cold: inlined into the pair loop, these
    /// paths made the paper's first-order packings 17 % slower (n = 2,
    /// Δ = 0.1, N = 256, same bits); out of line and with one `visit` call
    /// site the difference is within noise (4.53 vs 4.56 s user).
    #[cold]
    #[inline(never)]
    fn beyond_first_order(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
        max_gap: f64,
    ) -> Option<Contact<2>> {
        match self.gap {
            GapModel::SecondOrder => Some(
                self.second_order(size_i, o_i, size_j, o_j, r_ij)
                    .contact(r_ij),
            ),
            _ => self
                .exact_gap(size_i, o_i, size_j, o_j, r_ij, max_gap)
                .map(|e| e.contact()),
        }
    }

    /// `[F, F', F'', F''']` of both bodies of a pair (see
    /// [`NearDisk::f_pair`]), for the second-order gap.
    fn f_pair_jet3(&self, z_i: (f64, f64), z_j: (f64, f64), w_conj: (f64, f64)) -> [Jet3; 2] {
        let e = [cmul(z_i, w_conj), cmul((-z_j.0, -z_j.1), w_conj)];
        let mut out = [[0.0; 4]; 2];
        for (m, &phase) in self.modes.iter().zip(&self.phases) {
            let n = m.n as f64;
            for (o, &e) in out.iter_mut().zip(&e) {
                let p = cmul(cpow(e, m.n), phase);
                o[0] += m.a * p.1;
                o[1] += m.a * n * p.0;
                o[2] -= m.a * n * n * p.1;
                o[3] -= m.a * n * n * n * p.0;
            }
        }
        out
    }

    /// The second-order gap's partials (see [`jamkit_planar::gap2d`]).
    fn second_order(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
    ) -> gap2d::Partials {
        let r = r_ij.norm();
        let u = if r > 0.0 {
            r_ij * (1.0 / r)
        } else {
            Vector::<2>::new(1.0, 0.0)
        };
        let [p_i, p_j] = self.f_pair_jet3(o_i.unit(), o_j.unit(), (u[0], -u[1]));
        gap2d::second_order(r, size_i, size_j, self.delta, p_i, p_j)
    }

    /// The exact gap (see [`jamkit_planar::gap2d::exact`]), or `None` when
    /// it certainly exceeds `max_gap`. In the body frame the outline is
    /// `R(φ)/R⁰ = 1 + Δ F(−φ)`, and orientation `θ` turns it
    /// counter-clockwise by `θ`.
    ///
    /// Two uses of the first-order gap `h₁` (cheap):
    /// * a bound: `h ≥ h₁ − (s_i + s_j)`, with `s = R⁰ Δ² F'²_max / (1 − Δ F_max)`
    ///   (the support function exceeds the radius `R(ψ)` by at most
    ///   `(6/11) L²/R_min`, `L = max|R'|`, when `R_max < 1.85 R_min`; see
    ///   `docs/explanation/gap-models.md`, "Exact"), so far pairs skip the
    ///   iteration;
    /// * the first guess of the normal, `ψ₀ = θ_ij + Δ(R_i⁰F_i' + R_j⁰F_j')/r`,
    ///   exact to `O(Δ²)`.
    fn exact_gap(
        &self,
        size_i: f64,
        o_i: &Angle,
        size_j: f64,
        o_j: &Angle,
        r_ij: &Vector<2>,
        max_gap: f64,
    ) -> Option<gap2d::ExactGap> {
        let r = r_ij.norm();
        let first = self.first_order(size_i, o_i, size_j, o_j, r_ij, r);
        if first.gap - self.exact_slack * (size_i + size_j) > max_gap {
            return None;
        }
        let w0 = if r > 0.0 {
            let u = (r_ij[0] / r, r_ij[1] / r);
            turn_unit(u, -(first.grad_rot_i[0] + first.grad_rot_j[0]) / r)
        } else {
            (1.0, 0.0)
        };
        let d = self.delta;
        // R(φ)/R⁰ = 1 + Δ F(−φ) at p = e^{iφ}: e^{−iφ} = p̄.
        let outline = |p: Unit| {
            let (mut f, mut df, mut ddf) = (0.0, 0.0, 0.0);
            for (m, &phase) in self.modes.iter().zip(&self.phases) {
                let n = m.n as f64;
                let v = cmul(cpow_pair((p.0, -p.1), (1.0, 0.0), m.n).0, phase);
                f += m.a * v.1;
                df += m.a * n * v.0;
                ddf -= m.a * n * n * v.1;
            }
            (1.0 + d * f, -d * df, d * ddf)
        };
        // Each body's support search starts where its previous one ended,
        // turned by the change of direction: after the first Newton step on
        // ψ the support point moves by ~1e-4 rad and one inner step suffices.
        let support = |size: f64| {
            let last = std::cell::Cell::new(None::<(Unit, gap2d::SupportPoint)>);
            move |e: Unit| {
                let p0 = match last.get() {
                    Some((e_prev, sp)) => {
                        // dβ = arg(e ē_prev), small: sin dβ ≈ dβ to O(dβ³).
                        let turn = cmul(e, (e_prev.0, -e_prev.1));
                        turn_unit(sp.p, turn.1 * sp.dphi_dbeta)
                    }
                    None => e,
                };
                let (j, sp) = gap2d::polar_support_unit(e, p0, outline);
                last.set(Some((e, sp)));
                SupportJet {
                    h: size * j.h,
                    d1: size * j.d1,
                    d2: size * j.d2,
                }
            }
        };
        Some(gap2d::exact_unit(
            r_ij,
            w0,
            o_i.unit(),
            support(size_i),
            o_j.unit(),
            support(size_j),
        ))
    }

    /// `(F, F', F'')` of both bodies of a pair (see [`NearDisk::f_pair`]),
    /// for the Hessian.
    fn f_pair_second(
        &self,
        z_i: (f64, f64),
        z_j: (f64, f64),
        w_conj: (f64, f64),
    ) -> [(f64, f64, f64); 2] {
        self.f_pair_jet3(z_i, z_j, w_conj)
            .map(|[f, df, ddf, _]| (f, df, ddf))
    }

    /// `F(A)` and `F'(A)` for both bodies of a pair: `A_i = θ_i − θ_ij` and
    /// `A_j = θ_j − θ_ij − π`, from `z_i = e^{iθ_i}`, `z_j = e^{iθ_j}` and
    /// `w̄ = e^{−iθ_ij}`: `e^{iA_i} = z_i w̄`, `e^{iA_j} = −z_j w̄`, and
    /// `a sin(nA + b) = a Im(e^{inA} e^{ib})`, `a n cos(nA + b) = a n Re(…)`.
    #[inline(always)]
    fn f_pair(&self, z_i: (f64, f64), z_j: (f64, f64), w_conj: (f64, f64)) -> [(f64, f64); 2] {
        let e_i = cmul(z_i, w_conj);
        let e_j = cmul((-z_j.0, -z_j.1), w_conj);
        // The paper's family, one mode with no phase: no loop, no branch.
        if let [m] = self.modes[..]
            && m.b == 0.0
        {
            return single_mode(m, cpow_pair(e_i, e_j, m.n));
        }
        self.f_modes(e_i, e_j)
    }

    /// `F(A)` and `F'(A)` for both bodies of a pair from `e^{iA_i}` and
    /// `e^{iA_j}`, any modes ([`NearDisk::f_pair`]).
    #[inline(always)]
    fn f_modes(&self, e_i: (f64, f64), e_j: (f64, f64)) -> [(f64, f64); 2] {
        let mut out = [(0.0, 0.0); 2];
        for (m, &phase) in self.modes.iter().zip(&self.phases) {
            let (mut p_i, mut p_j) = cpow_pair(e_i, e_j, m.n);
            if m.b != 0.0 {
                p_i = cmul(p_i, phase);
                p_j = cmul(p_j, phase);
            }
            let (a, an) = (m.a, m.a * m.n as f64);
            out[0].0 += a * p_i.1;
            out[0].1 += an * p_i.0;
            out[1].0 += a * p_j.1;
            out[1].1 += an * p_j.0;
        }
        out
    }
}

impl Shape<2> for NearDisk {
    type Orientation = Angle;
    type Fast = Self;

    fn family(&self) -> &'static str {
        self.name
    }

    fn rot_dof(&self) -> usize {
        1
    }

    fn volume(&self, size: f64) -> f64 {
        self.relative_area() * size * size
    }

    fn bounding_radius(&self, size: f64) -> f64 {
        size * (1.0 + self.delta * self.f_bound)
    }

    fn rot_inertia(&self, _size: f64) -> jamkit_core::RotVec {
        [self.inertia, 1.0, 1.0]
    }

    #[inline]
    fn rotate(&self, o: &mut Angle, dq: &[f64]) {
        *o = o.turned(dq[0]);
    }

    /// Rattlers below three contacts (`d + 1`); near-disks jam hypostatic;
    /// a warning where the outline is not convex.
    fn policy(&self) -> Policy {
        let mut warnings = Vec::new();
        if !self.is_convex() {
            warnings.push(format!(
                "non-convex outline (Δ = {}): the first-order gap assumes convex bodies with one contact per pair",
                self.delta
            ));
        }
        Policy {
            rattler_threshold: 3,
            expects_isostatic: false,
            warnings,
            ..Policy::new(2)
        }
    }

    fn look(&self) -> Look {
        Look {
            outline: Some(std::sync::Arc::new(self.clone())),
            ..Look::default()
        }
    }

    #[inline(always)]
    fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, Angle>, max_gap: f64, mut visit: F) {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        let r = r_ij.norm();
        // The gap is at least |r| − bounding radii; skip pairs certainly apart.
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return;
        }
        // One call of `visit` for every model: a second call site (an early
        // return for the other models) cost the first-order pair loop 6 %.
        let contact = if self.gap == GapModel::FirstOrder {
            Some(self.first_order(size_i, o_i, size_j, o_j, r_ij, r))
        } else {
            self.beyond_first_order(size_i, o_i, size_j, o_j, r_ij, max_gap)
        };
        if let Some(c) = contact {
            visit(c);
        }
    }

    /// Second derivatives of the first-order gap
    /// ([`jamkit_planar::first_order`], with `P = F`).
    fn gap_hessians<V: FnMut(GapHessian<2>)>(
        &self,
        pair: &Pair<2, Angle>,
        max_gap: f64,
        mut visit: V,
    ) -> jamkit_core::Result<()> {
        let size_i = pair.size_i;
        let o_i = &pair.o_i;
        let size_j = pair.size_j;
        let o_j = &pair.o_j;
        let r_ij = &pair.r_ij;
        let r = r_ij.norm();
        if r - self.bounding_radius(size_i) - self.bounding_radius(size_j) > max_gap {
            return Ok(());
        }
        match self.gap {
            GapModel::FirstOrder => {}
            GapModel::SecondOrder => {
                visit(
                    self.second_order(size_i, o_i, size_j, o_j, r_ij)
                        .chain(r_ij),
                );
                return Ok(());
            }
            GapModel::Exact => {
                if let Some(e) = self.exact_gap(size_i, o_i, size_j, o_j, r_ij, max_gap) {
                    visit(e.hessian());
                }
                return Ok(());
            }
        }
        let u = if r > 0.0 {
            r_ij / r
        } else {
            Vector::<2>::new(1.0, 0.0)
        };
        let [p_i, p_j] = self
            .f_pair_second(o_i.unit(), o_j.unit(), (u[0], -u[1]))
            .map(|(value, slope, curvature)| Profile {
                value,
                slope,
                curvature,
            });
        visit(gap_hessian(r_ij, size_i, size_j, self.delta, p_i, p_j));
        Ok(())
    }
}

/// The first-order gap's lane kernel (at most one contact per pair, for
/// every gap model).
impl FastContacts<2, NearDisk> for NearDisk {
    const LANES: bool = true;

    /// Only the first-order gap has a lane kernel.
    ///
    /// NOTE: through the lanes (one `contacts` call per pair, apart pairs
    /// included), second-order packings took 1.40 s user against 0.95 s
    /// through the generic pass (N = 64, n = 3, Δ = 0.1; same bits).
    fn use_lanes(shape: &NearDisk) -> bool {
        shape.gap == GapModel::FirstOrder
    }

    /// The first-order contacts by [`NearDisk::first_order_lanes`]; the
    /// other gap models one pair at a time (correct, though the engine does
    /// not ask: [`NearDisk::use_lanes`]).
    ///
    /// NOTE: one copy of the kernel per mode number n ≤ 6 of the paper's
    /// family (`n` a literal in each arm, so `e^{inA}`'s products are
    /// straight-line code); the branch, once per chunk of pairs, goes the
    /// same way for every call of a run.
    #[inline(always)]
    fn contacts_lanes<const W: usize>(
        shape: &NearDisk,
        pairs: &PairLanes<2, Angle, W>,
        out: &mut ContactLanes<2, W>,
    ) {
        if shape.gap != GapModel::FirstOrder {
            return contacts_one_by_one(shape, pairs, out);
        }
        if let [m] = shape.modes[..]
            && m.b == 0.0
        {
            match m.n {
                1 => shape.single_mode_lanes::<1, W>(m, pairs, out),
                2 => shape.single_mode_lanes::<2, W>(m, pairs, out),
                3 => shape.single_mode_lanes::<3, W>(m, pairs, out),
                4 => shape.single_mode_lanes::<4, W>(m, pairs, out),
                5 => shape.single_mode_lanes::<5, W>(m, pairs, out),
                6 => shape.single_mode_lanes::<6, W>(m, pairs, out),
                n => shape.first_order_lanes(pairs, out, |e_i, e_j| {
                    single_mode(m, cpow_pair(e_i, e_j, n))
                }),
            }
        } else {
            shape.first_order_lanes(pairs, out, |e_i, e_j| shape.f_modes(e_i, e_j));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::ShapeExt;

    fn fourier(n: u32, delta: f64) -> NearDisk {
        NearDisk::fourier(&FourierParams {
            n,
            delta,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap()
    }

    fn gap(s: &NearDisk, ri: f64, ti: f64, rj: f64, tj: f64, d: Vector<2>) -> f64 {
        s.pair_contacts(
            &Pair::new(ri, Angle::new(ti), rj, Angle::new(tj), d),
            f64::INFINITY,
        )[0]
        .gap
    }

    /// The complex-arithmetic gap equals the paper's formula written with
    /// atan2 and sin, to round-off (1e-14 on gaps of order 1).
    #[test]
    fn gap_matches_the_printed_formula() {
        for n in 2..=5 {
            let s = fourier(n, 0.2);
            for &(x, y, ti, tj) in &[
                (1.1, 0.3, 0.4, -2.0),
                (-0.9, -0.8, 3.1, 1.0),
                (0.2, -1.3, -3.1, 3.0),
            ] {
                let d = Vector::<2>::new(x, y);
                let tij = y.atan2(x);
                let f = |a: f64| (n as f64 * a).sin() / n as f64;
                let expected =
                    d.norm() - 0.5 - 0.7 - 0.2 * (0.5 * f(ti - tij) + 0.7 * f(tj - tij - PI));
                assert_relative_eq!(gap(&s, 0.5, ti, 0.7, tj, d), expected, epsilon = 1e-14);
            }
        }
    }

    /// h_ij = h_ji: swapping the bodies and reversing the separation.
    #[test]
    fn gap_is_symmetric() {
        let s = fourier(3, 0.3);
        let d = Vector::<2>::new(0.8, -0.9);
        assert_relative_eq!(
            gap(&s, 0.5, 0.3, 0.7, -1.2, d),
            gap(&s, 0.7, -1.2, 0.5, 0.3, -d),
            epsilon = 1e-14
        );
    }

    /// A single mode (n, 1/n, 0) in `fourier_sum` is `fourier`, bit for bit.
    #[test]
    fn single_mode_sum_is_fourier() {
        let a = fourier(4, 0.1);
        let b = NearDisk::fourier_sum(&FourierSumParams {
            modes: vec![Mode {
                n: 4,
                a: 0.25,
                b: 0.0,
            }],
            delta: 0.1,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap();
        let d = Vector::<2>::new(0.7, 0.6);
        assert_eq!(
            gap(&a, 0.5, 1.0, 0.7, 2.0, d).to_bits(),
            gap(&b, 0.5, 1.0, 0.7, 2.0, d).to_bits()
        );
    }

    /// Area: closed form against a direct quadrature of ½∫R², which is
    /// spectrally accurate (1e-12) for these trigonometric polynomials.
    #[test]
    fn area_matches_quadrature() {
        let s = NearDisk::fourier_sum(&FourierSumParams {
            modes: vec![
                Mode {
                    n: 2,
                    a: 0.5,
                    b: 0.3,
                },
                Mode {
                    n: 2,
                    a: 0.2,
                    b: 1.1,
                },
                Mode {
                    n: 5,
                    a: 0.1,
                    b: 0.0,
                },
            ],
            delta: 0.3,
            inertia: None,
            gap: Default::default(),
        })
        .unwrap();
        let m = 4096;
        let quad: f64 = (0..m)
            .map(|k| 0.5 * s.relative_radius(2.0 * PI * k as f64 / m as f64).powi(2))
            .sum::<f64>()
            * 2.0
            * PI
            / m as f64;
        assert_relative_eq!(s.relative_area(), quad, max_relative = 1e-12);
    }

    /// A ≈ 1 + Δ²(1 − 1/n²)/2 for small Δ (the paper's Eq. (7)); the next
    /// order is O(Δ⁴), so at Δ = 0.01 the relative difference in A − 1 is ~1e-4.
    #[test]
    fn asphericity_matches_small_delta_expansion() {
        for n in 2..=5 {
            let delta = 0.01;
            let s = fourier(n, delta);
            let expected = 0.5 * delta * delta * (1.0 - 1.0 / (n * n) as f64);
            assert_relative_eq!(s.asphericity() - 1.0, expected, max_relative = 1e-3);
        }
    }

    #[test]
    fn nonsense_parameters_are_rejected_and_large_delta_is_non_convex() {
        assert!(
            NearDisk::fourier(&FourierParams {
                n: 0,
                delta: 0.1,
                inertia: None,
                gap: Default::default(),
            })
            .is_err()
        );
        assert!(
            NearDisk::fourier(&FourierParams {
                n: 2,
                delta: f64::NAN,
                inertia: None,
                gap: Default::default(),
            })
            .is_err()
        );
        assert!(
            NearDisk::fourier(&FourierParams {
                n: 2,
                delta: 2.5,
                inertia: None,
                gap: Default::default(),
            })
            .is_err()
        ); // 1 − Δ/2 < 0
        assert!(
            NearDisk::fourier_sum(&FourierSumParams {
                modes: vec![],
                delta: 0.1,
                inertia: None,
                gap: Default::default(),
            })
            .is_err()
        );
        assert!(fourier(2, 0.1).is_convex());
        assert!(!fourier(5, 0.5).is_convex());
    }

    /// The lane kernel (`contacts_lanes`) gives the contacts of `contacts`
    /// bit for bit, and none where `contacts` visits none: the paper's modes
    /// n = 1..7 (7 takes the loop of `cpow`), sums of modes with and without
    /// phases, the other gap models (one pair at a time), and pairs across
    /// θ_ij = ±π, at r = 0, barely touching and apart.
    #[test]
    fn contacts_lanes_match_contacts_bit_for_bit() {
        let sum = |modes: Vec<Mode>, gap| {
            NearDisk::fourier_sum(&FourierSumParams {
                modes,
                delta: 0.2,
                inertia: None,
                gap,
            })
            .unwrap()
        };
        let mode = |n, a, b| Mode { n, a, b };
        let mut shapes: Vec<NearDisk> = (1..=7).map(|n| fourier(n, 0.15)).collect();
        shapes.push(sum(vec![mode(3, 0.5, 0.0)], GapModel::FirstOrder));
        shapes.push(sum(vec![mode(2, 0.4, 0.3)], GapModel::FirstOrder));
        shapes.push(sum(
            vec![mode(2, 0.4, 0.3), mode(3, 0.2, -1.0), mode(7, 0.05, 2.0)],
            GapModel::FirstOrder,
        ));
        shapes.push(sum(
            vec![mode(2, 0.3, 0.0), mode(4, 0.1, 0.0)],
            GapModel::FirstOrder,
        ));
        shapes.push(sum(vec![mode(2, 0.5, 0.0)], GapModel::SecondOrder));
        shapes.push(sum(vec![mode(2, 0.5, 0.0)], GapModel::Exact));
        let tiny = 1e-300;
        // (size_i, θ_i, size_j, θ_j, r_ij)
        let pairs = [
            (0.5, 0.4, 0.7, -2.0, (1.1, 0.3)),
            (0.5, 3.1, 0.7, 1.0, (-0.9, -0.8)),
            (0.7, -3.1, 0.5, 3.0, (0.2, -1.3)),
            (0.5, 1.0, 0.5, -1.0, (-0.95, tiny)),
            (0.5, 1.0, 0.5, -1.0, (-0.95, -tiny)),
            (0.5, 1.0, 0.5, -1.0, (-0.95, 0.0)),
            (0.5, 1.0, 0.5, -1.0, (-0.95, -0.0)),
            (0.5, 1.0, 0.5, -1.0, (-1.2, 1e-9)),
            (0.5, 0.2, 0.7, 2.5, (0.0, 0.0)),
            (0.5, 0.2, 0.7, 2.5, (1e-12, 0.0)),
            (0.5, 0.2, 0.7, 2.5, (1.2, 0.0)),
            (0.5, 0.2, 0.7, 2.5, (0.0, -1.25)),
            (0.5, 0.2, 0.7, 2.5, (1.6, 0.1)),
            (0.5, 0.2, 0.7, 2.5, (-3.0, 2.0)),
            (0.6, -0.7, 0.6, 0.7, (0.9, 0.9)),
            (0.6, -0.7, 0.6, 0.7, (-1.19, 0.01)),
        ];
        const W: usize = 16;
        for s in &shapes {
            let mut lanes = PairLanes::<2, Angle, W> {
                size_i: [0.0; W],
                size_j: [0.0; W],
                reach_i: [0.0; W],
                reach_j: [0.0; W],
                o_i: [Angle::new(0.0); W],
                o_j: [Angle::new(0.0); W],
                r_ij: [[0.0; W]; 2],
                r2: [0.0; W],
            };
            for (l, &(size_i, t_i, size_j, t_j, (x, y))) in pairs.iter().enumerate() {
                let d = Vector::<2>::new(x, y);
                lanes.size_i[l] = size_i;
                lanes.size_j[l] = size_j;
                lanes.reach_i[l] = s.bounding_radius(size_i);
                lanes.reach_j[l] = s.bounding_radius(size_j);
                lanes.o_i[l] = Angle::new(t_i);
                lanes.o_j[l] = Angle::new(t_j);
                lanes.r_ij[0][l] = x;
                lanes.r_ij[1][l] = y;
                lanes.r2[l] = d.norm_squared();
            }
            // Stale contents must not leak into lanes without a contact.
            let mut out = ContactLanes::<2, W> {
                found: [true; W],
                gap: [f64::NAN; W],
                ..Default::default()
            };
            NearDisk::contacts_lanes(s, &lanes, &mut out);
            let bits = |c: Option<Contact<2>>| {
                c.map(|c| {
                    let mut b = vec![c.gap.to_bits(), c.grad_r[0].to_bits()];
                    b.push(c.grad_r[1].to_bits());
                    b.extend(
                        c.grad_rot_i
                            .iter()
                            .chain(&c.grad_rot_j)
                            .map(|x| x.to_bits()),
                    );
                    b
                })
            };
            let mut found = 0;
            for l in 0..W {
                let expected = s
                    .pair_contacts(
                        &Pair::new(
                            lanes.size_i[l],
                            lanes.o_i[l],
                            lanes.size_j[l],
                            lanes.o_j[l],
                            lanes.separation(l),
                        ),
                        0.0,
                    )
                    .pop();
                found += usize::from(expected.is_some());
                assert_eq!(
                    bits(out.get(l)),
                    bits(expected),
                    "{s:?}, pair {l}: {:?} against {expected:?}",
                    out.get(l)
                );
            }
            // Both kinds of lanes occur.
            assert!(0 < found && found < W, "{found}");
        }
    }
}
