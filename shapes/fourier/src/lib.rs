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
//!
//! The families are their profile: [`FourierProfile`] gives `F`, its
//! derivatives to the third, range and moments, and the shared near-disk
//! (`jamkit_planar::profiled::Profiled`, orientations [`Angle`]) does the
//! rest, the second-order and exact gap models included. [`NearDisk`] wraps
//! it with the family's name and the first-order lane kernel (`W` pairs at
//! once, a copy per mode number n ≤ 6), which gives `Profiled`'s contacts
//! bit for bit.

use jamkit_core::math::{Unit, cmul};
use jamkit_core::{
    Contact, ContactLanes, Dims, Family, FamilyInfo, FastContacts, GapHessian, Look, Outline, Pair,
    PairLanes, PairMemo, ParamSpec, Policy, Shape, ShapeVisitor, Warm, contacts_one_by_one,
    contacts_warm_one_by_one,
};
use jamkit_planar::gap2d::{GapModel, Jet3};
use jamkit_planar::profiled::{NearDiskProfile, Profiled};
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
            added: None,
        },
        ParamSpec {
            name: "delta",
            about: "Δ, the amplitude; 0 gives disks (the sphere family)",
            is_list: false,
            default: None,
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia I of the angle θ; None: I = Δ (the paper's choice)",
            is_list: false,
            default: Some("None"),
            added: None,
        },
        GAP_SPEC,
    ],
};

/// The `gap` parameter shared by both near-disk families.
const GAP_SPEC: ParamSpec = ParamSpec {
    name: "gap",
    about: "gap model, a string: \"FirstOrder\" (the paper's, error O(Δ²)), \"SecondOrder\" (error O(Δ³)), \"Exact\" (common normals; several contacts per pair on a non-convex outline); None: FirstOrder",
    is_list: false,
    default: Some("None"),
    added: None,
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
            added: None,
        },
        ParamSpec {
            name: "delta",
            about: "Δ, the overall amplitude",
            is_list: false,
            default: None,
            added: None,
        },
        ParamSpec {
            name: "inertia",
            about: "moment of inertia; None: I = Δ",
            is_list: false,
            default: Some("None"),
            added: None,
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

/// An orientation: the shared planar rotation `e^{iθ}`
/// ([`jamkit_core::Rotation2`]); near-disks turn it by
/// [`Rotation2::turned`](jamkit_core::Rotation2::turned).
pub type Angle = jamkit_core::Rotation2;

/// `z²`, bit for bit `cmul(z, z)` (`ab + ba = 2ab` exactly).
#[inline(always)]
fn csq(z: Unit) -> Unit {
    (z.0 * z.0 - z.1 * z.1, 2.0 * (z.0 * z.1))
}

/// `z^n`: straight-line products for the paper's modes (n ≤ 6), binary
/// exponentiation above.
///
/// NOTE: a loop on the bits of a run-time `n` kept the pair loop from
/// overlapping pairs. Each arm multiplies the same factors as the binary
/// loop (products commute), so the powers are bit for bit the loop's.
#[inline(always)]
fn cpow(z: Unit, n: u32) -> Unit {
    match n {
        1 => z,
        2 => csq(z),
        3 => cmul(csq(z), z),
        4 => csq(csq(z)),
        5 => cmul(csq(csq(z)), z),
        6 => cmul(csq(csq(z)), csq(z)),
        mut n => {
            let (mut z, mut acc) = (z, (1.0, 0.0));
            while n > 0 {
                if n & 1 == 1 {
                    acc = cmul(acc, z);
                }
                z = cmul(z, z);
                n >>= 1;
            }
            acc
        }
    }
}

/// The profile `F(ψ) = Σ_k a_k sin(n_k ψ + b_k)` of both families, from
/// `e^{iψ}`: `a sin(nψ + b) = a Im(e^{inψ} e^{ib})`,
/// `a n cos(nψ + b) = a n Re(…)`.
#[derive(Clone, Debug, PartialEq)]
pub struct FourierProfile {
    family: &'static str,
    modes: Vec<Mode>,
    /// `e^{i b_k}` of each mode.
    phases: Vec<Unit>,
    /// `min F` on 4096 angles, and `Σ |a_k|`, a bound on `|F|`.
    range: (f64, f64),
}

impl FourierProfile {
    /// The profile of `modes` (checked: at least one, `n ≥ 1`, `a` and `b`
    /// finite; errors name `params.modes`).
    fn new(family: &'static str, modes: Vec<Mode>) -> jamkit_core::Result<Self> {
        if modes.is_empty() {
            return Err(jamkit_core::Error::invalid(
                "params.modes",
                "[]",
                "must list at least one mode (n, a, b)",
            ));
        }
        for (k, m) in modes.iter().enumerate() {
            if m.n < 1 {
                return Err(jamkit_core::Error::invalid(
                    format!("params.modes[{k}].n"),
                    m.n.to_string(),
                    "must be an integer ≥ 1",
                ));
            }
            if !(m.a.is_finite() && m.b.is_finite()) {
                return Err(jamkit_core::Error::invalid(
                    format!("params.modes[{k}]"),
                    format!("{m:?}"),
                    "a and b must be finite",
                ));
            }
        }
        let mut profile = Self {
            family,
            phases: modes.iter().map(|m| (m.b.cos(), m.b.sin())).collect(),
            range: (0.0, modes.iter().map(|m| m.a.abs()).sum()),
            modes,
        };
        profile.range.0 = (0..4096)
            .map(|k| profile.f_and_derivative(2.0 * PI * k as f64 / 4096.0).0)
            .fold(f64::INFINITY, f64::min);
        Ok(profile)
    }

    /// The modes.
    pub fn modes(&self) -> &[Mode] {
        &self.modes
    }

    /// `F(φ)` and `F'(φ)` at the angle `φ` (slow path, for geometry).
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

    /// `[F, F', F'', F‴]` of one mode with no phase from `e^{inA}`.
    #[inline(always)]
    fn single_jet(m: Mode, p: Unit) -> Jet3 {
        let n = m.n as f64;
        [
            m.a * p.1,
            m.a * n * p.0,
            -(m.a * n * n * p.1),
            -(m.a * n * n * n * p.0),
        ]
    }

    /// `F` and `F'` of one mode with no phase from `e^{inA}`.
    #[inline(always)]
    fn single(m: Mode, p: Unit) -> (f64, f64) {
        (m.a * p.1, m.a * m.n as f64 * p.0)
    }
}

impl NearDiskProfile for FourierProfile {
    const FAMILY: &'static str = "fourier";
    /// Body `j` gets `−e^{iA}` for every set of modes.
    const HALF_TURN_SYMMETRIC: bool = false;
    const HESSIAN_DIVIDES: bool = true;

    /// `F(A)` and `F'(A)`; the paper's family (one mode with no phase) with
    /// no loop and no branch but the first.
    #[inline(always)]
    fn value_slope(&self, cos: f64, sin: f64) -> (f64, f64) {
        let e = (cos, sin);
        if let [m] = self.modes[..]
            && m.b == 0.0
        {
            return Self::single(m, cpow(e, m.n));
        }
        let mut out = (0.0, 0.0);
        for (m, &phase) in self.modes.iter().zip(&self.phases) {
            let mut p = cpow(e, m.n);
            if m.b != 0.0 {
                p = cmul(p, phase);
            }
            out.0 += m.a * p.1;
            out.1 += m.a * m.n as f64 * p.0;
        }
        out
    }

    fn curvature(&self, cos: f64, sin: f64) -> f64 {
        self.jet(cos, sin)[2]
    }

    fn range(&self) -> (f64, f64) {
        self.range
    }

    /// `⟨F⟩ = 0`, `⟨F²⟩ = ½ Σ_{k,l: n_k = n_l} a_k a_l cos(b_k − b_l)`.
    fn moments(&self) -> (f64, f64) {
        let mut mean_f2 = 0.0;
        for p in &self.modes {
            for q in &self.modes {
                if p.n == q.n {
                    mean_f2 += 0.5 * p.a * q.a * (p.b - q.b).cos();
                }
            }
        }
        (0.0, mean_f2)
    }

    fn describe(&self) -> String {
        match self.modes[..] {
            [m] if self.family == "fourier" => format!("n = {}", m.n),
            _ => format!("modes = {:?}", self.modes),
        }
    }

    #[inline(always)]
    fn jet3(&self, cos: f64, sin: f64) -> Option<Jet3> {
        Some(self.jet(cos, sin))
    }

    /// `Σ |a_k| n_k`.
    fn slope_bound(&self) -> Option<f64> {
        Some(self.modes.iter().map(|m| m.a.abs() * m.n as f64).sum())
    }
}

impl FourierProfile {
    /// `[F, F', F'', F‴]` at `e^{iA} = (cos, sin)`; the paper's family (one
    /// mode with no phase) with no loop, bit for bit the loop's numbers
    /// (`cmul(p, (1, 0)) = p` and `0 − x = −x`).
    #[inline(always)]
    fn jet(&self, cos: f64, sin: f64) -> Jet3 {
        if let [m] = self.modes[..]
            && m.b == 0.0
        {
            return Self::single_jet(m, cpow((cos, sin), m.n));
        }
        let mut o = [0.0; 4];
        for (m, &phase) in self.modes.iter().zip(&self.phases) {
            let n = m.n as f64;
            let p = cmul(cpow((cos, sin), m.n), phase);
            o[0] += m.a * p.1;
            o[1] += m.a * n * p.0;
            o[2] -= m.a * n * n * p.1;
            o[3] -= m.a * n * n * n * p.0;
        }
        o
    }
}

/// A near-disk of `fourier` or `fourier_sum`: the shared near-disk
/// ([`Profiled`]) of [`FourierProfile`] with orientations [`Angle`], and
/// the family's name. Everything but the lane kernel is `Profiled`'s.
#[derive(Clone, Debug, PartialEq)]
pub struct NearDisk {
    name: &'static str,
    shape: Profiled<FourierProfile, Angle>,
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
        let mode = Mode {
            n: p.n,
            a: 1.0 / p.n as f64,
            b: 0.0,
        };
        Self::new("fourier", p.delta, vec![mode], p.inertia, p.gap)
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
        let profile = FourierProfile::new(name, modes)?;
        let shape = Profiled::with_orientation(profile, delta, inertia)?.with_gap(gap)?;
        Ok(Self { name, shape })
    }

    /// The shared near-disk.
    pub fn profiled(&self) -> &Profiled<FourierProfile, Angle> {
        &self.shape
    }

    /// The gap model.
    pub fn gap_model(&self) -> GapModel {
        self.shape.gap_model()
    }

    /// `Δ`.
    pub fn delta(&self) -> f64 {
        self.shape.delta()
    }

    /// `F(φ)` and `F'(φ)` at the angle `φ` (slow path, for geometry).
    pub fn f_and_derivative(&self, phi: f64) -> (f64, f64) {
        self.shape.profile().f_and_derivative(phi)
    }

    /// `F''(φ)`.
    pub fn f_second(&self, phi: f64) -> f64 {
        self.shape.profile().f_second(phi)
    }

    /// `R(φ)/R⁰ = 1 + Δ F(φ)`.
    pub fn relative_radius(&self, phi: f64) -> f64 {
        self.shape.relative_radius(phi)
    }

    /// True when the outline is convex ([`Profiled::is_convex`]).
    pub fn is_convex(&self) -> bool {
        self.shape.is_convex()
    }

    /// The convex limit of the one-mode outline `R⁰[1 + Δ sin(nθ)/n]`:
    /// convex for `Δ < 1/(n + 1/n)`. The curvature numerator
    /// `r² + 2r'² − r r''` first vanishes at the troughs (`sin nθ = −1`,
    /// `r' = 0`), where it is `r (r − Δ n)` with `r = 1 − Δ/n`.
    pub fn convex_limit(n: u32) -> f64 {
        let n = f64::from(n);
        1.0 / (n + 1.0 / n)
    }

    /// Area in units of `(R⁰)²`: `π [1 + Δ² ⟨F²⟩]` with
    /// `⟨F²⟩ = (1/2π)∫F² = ½ Σ_{k,l: n_k = n_l} a_k a_l cos(b_k − b_l)`.
    pub fn relative_area(&self) -> f64 {
        self.shape.relative_area()
    }

    /// Asphericity `A = P²/(4π S)` by numerical integration of the perimeter
    /// `P = ∫ √(R² + R'²) dφ` (trapezoid rule on 8192 points, spectrally
    /// accurate for a periodic integrand).
    pub fn asphericity(&self) -> f64 {
        let m = 8192;
        let d = self.delta();
        let perimeter: f64 = (0..m)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / m as f64;
                let (f, df) = self.f_and_derivative(phi);
                ((1.0 + d * f).powi(2) + (d * df).powi(2)).sqrt()
            })
            .sum::<f64>()
            * 2.0
            * PI
            / m as f64;
        perimeter * perimeter / (4.0 * PI * self.relative_area())
    }

    /// The first-order contacts of `W` pairs ([`FastContacts::contacts_lanes`]):
    /// `contacts`' bounding test and [`Profiled::first_order`], lane by
    /// lane, the same operations in the same order, with the branch at
    /// `r = 0` turned into selects. `profile` maps `e^{iA}` to `(F, F')`.
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
        profile: impl Fn(Unit) -> (f64, f64),
    ) {
        let d = self.delta();
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
            // The phases of `Profiled::phases`, bit for bit.
            let e_i = cmul(z_i, w_conj);
            let e_j = cmul((-z_j.0, -z_j.1), w_conj);
            let ((f_i, df_i), (f_j, df_j)) = (profile(e_i), profile(e_j));
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
        self.first_order_lanes(pairs, out, |e| FourierProfile::single(m, cpow(e, N)));
    }

    /// [`Profiled::exact_warm_lanes`] for one mode `m` with `m.n = N`, a
    /// constant.
    #[inline(always)]
    fn single_mode_warm_lanes<const N: u32, const W: usize>(
        &self,
        m: Mode,
        pairs: &PairLanes<2, Angle, W>,
        lm: (usize, f64),
        memos: (&mut [PairMemo], &[u32; W]),
        scratch: &mut Vec<[f64; W]>,
        out: &mut ContactLanes<2, W>,
    ) {
        self.shape.exact_warm_lanes(
            pairs,
            lm,
            memos,
            scratch,
            out,
            |e| FourierProfile::single(m, cpow(e, N)),
            |e| FourierProfile::single_jet(m, cpow(e, N)),
        );
    }
}

impl Outline for NearDisk {
    fn relative_radius(&self, psi: f64) -> f64 {
        NearDisk::relative_radius(self, psi)
    }
}

/// [`Profiled`]'s, with the family's name and the lane kernel.
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
        self.shape.volume(size)
    }

    fn bounding_radius(&self, size: f64) -> f64 {
        self.shape.bounding_radius(size)
    }

    fn rot_inertia(&self, size: f64) -> jamkit_core::RotVec {
        self.shape.rot_inertia(size)
    }

    #[inline]
    fn rotate(&self, o: &mut Angle, dq: &[f64]) {
        self.shape.rotate(o, dq)
    }

    fn policy(&self) -> Policy {
        self.shape.policy()
    }

    fn look(&self) -> Look {
        Look {
            outline: Some(std::sync::Arc::new(self.clone())),
            ..Look::default()
        }
    }

    #[inline(always)]
    fn contacts<F: FnMut(Contact<2>)>(&self, pair: &Pair<2, Angle>, max_gap: f64, visit: F) {
        self.shape.contacts(pair, max_gap, visit)
    }

    #[inline(always)]
    fn contact_warm(&self, pair: &Pair<2, Angle>, max_gap: f64, memo: &mut PairMemo) -> Warm<2> {
        self.shape.contact_warm(pair, max_gap, memo)
    }

    fn gap_hessians<V: FnMut(GapHessian<2>)>(
        &self,
        pair: &Pair<2, Angle>,
        max_gap: f64,
        visit: V,
    ) -> jamkit_core::Result<()> {
        self.shape.gap_hessians(pair, max_gap, visit)
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
        shape.gap_model() == GapModel::FirstOrder
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
        if shape.gap_model() != GapModel::FirstOrder {
            return contacts_one_by_one(shape, pairs, out);
        }
        let profile = shape.shape.profile();
        if let [m] = profile.modes[..]
            && m.b == 0.0
        {
            match m.n {
                1 => shape.single_mode_lanes::<1, W>(m, pairs, out),
                2 => shape.single_mode_lanes::<2, W>(m, pairs, out),
                3 => shape.single_mode_lanes::<3, W>(m, pairs, out),
                4 => shape.single_mode_lanes::<4, W>(m, pairs, out),
                5 => shape.single_mode_lanes::<5, W>(m, pairs, out),
                6 => shape.single_mode_lanes::<6, W>(m, pairs, out),
                n => shape.first_order_lanes(pairs, out, |e| FourierProfile::single(m, cpow(e, n))),
            }
        } else {
            shape.first_order_lanes(pairs, out, |e| profile.value_slope(e.0, e.1));
        }
    }

    /// The convex exact gap's warm contacts go a chunk at a time to
    /// [`Profiled::exact_warm_lanes`].
    fn use_warm_lanes(shape: &NearDisk) -> bool {
        shape.gap_model() == GapModel::Exact && shape.shape.arcs().is_none()
    }

    /// [`Profiled::exact_warm_lanes`], with one copy per mode number
    /// n ≤ 6 of the paper's family as in [`NearDisk::contacts_lanes`].
    #[inline(always)]
    fn contacts_warm_lanes<const W: usize>(
        shape: &NearDisk,
        pairs: &PairLanes<2, Angle, W>,
        len: usize,
        max_gap: f64,
        memos: &mut [PairMemo],
        at: &[u32; W],
        scratch: &mut Vec<[f64; W]>,
        out: &mut ContactLanes<2, W>,
    ) {
        if !Self::use_warm_lanes(shape) {
            return contacts_warm_one_by_one(shape, pairs, len, max_gap, memos, at, out);
        }
        let profile = shape.shape.profile();
        let lm = (len, max_gap);
        if let [m] = profile.modes[..]
            && m.b == 0.0
        {
            match m.n {
                1 => shape.single_mode_warm_lanes::<1, W>(m, pairs, lm, (memos, at), scratch, out),
                2 => shape.single_mode_warm_lanes::<2, W>(m, pairs, lm, (memos, at), scratch, out),
                3 => shape.single_mode_warm_lanes::<3, W>(m, pairs, lm, (memos, at), scratch, out),
                4 => shape.single_mode_warm_lanes::<4, W>(m, pairs, lm, (memos, at), scratch, out),
                5 => shape.single_mode_warm_lanes::<5, W>(m, pairs, lm, (memos, at), scratch, out),
                6 => shape.single_mode_warm_lanes::<6, W>(m, pairs, lm, (memos, at), scratch, out),
                n => shape.shape.exact_warm_lanes(
                    pairs,
                    lm,
                    (memos, at),
                    scratch,
                    out,
                    |e| FourierProfile::single(m, cpow(e, n)),
                    |e| FourierProfile::single_jet(m, cpow(e, n)),
                ),
            }
        } else {
            shape.shape.exact_warm_lanes(
                pairs,
                lm,
                (memos, at),
                scratch,
                out,
                |e| profile.value_slope(e.0, e.1),
                |e| profile.jet(e.0, e.1),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use jamkit_core::{ShapeExt, Vector};

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

    /// `convex_limit` against the sampled curvature of `is_convex`: convex
    /// 0.1 % below the limit, not 0.1 % above it (8192 angles resolve the
    /// troughs' curvature far finer than that).
    #[test]
    fn the_convex_limit_separates_convex_and_non_convex_outlines() {
        for n in [2, 3, 4, 5, 8, 16, 32] {
            let limit = NearDisk::convex_limit(n);
            assert!(
                fourier(n, 0.999 * limit).is_convex(),
                "n = {n} below {limit}"
            );
            assert!(
                !fourier(n, 1.001 * limit).is_convex(),
                "n = {n} above {limit}"
            );
        }
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
            let mut lanes = PairLanes::<2, Angle, W>::filled(Angle::new(0.0));
            for (l, &(size_i, t_i, size_j, t_j, (x, y))) in pairs.iter().enumerate() {
                let pair = Pair {
                    size_i,
                    o_i: Angle::new(t_i),
                    size_j,
                    o_j: Angle::new(t_j),
                    r_ij: Vector::<2>::new(x, y),
                };
                let reach = (s.bounding_radius(size_i), s.bounding_radius(size_j));
                lanes.set(l, &pair, reach);
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
                let expected = s.pair_contacts(&lanes.pair(l), 0.0).pop();
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
