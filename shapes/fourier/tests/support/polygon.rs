//! A near-disk's outline as a fine polygon, for checks of the exact gap
//! that share nothing with it: point in polygon, distance to the edges,
//! depth of one polygon in another. Included by `#[path]` from the tests
//! that use it.

use jamkit_fourier::NearDisk;
use jamkit_planar::gap2d::ExactGap;
use std::f64::consts::TAU;

/// The outline of a body as a polygon of `m` vertices (lab frame,
/// counter-clockwise, at polar angles 2πk/m about its centre `c`).
pub struct Polygon {
    c: [f64; 2],
    v: Vec<[f64; 2]>,
}

impl Polygon {
    pub fn new(s: &NearDisk, size: f64, theta: f64, c: [f64; 2], m: usize) -> Self {
        let v = (0..m)
            .map(|k| {
                let phi = TAU * k as f64 / m as f64;
                // R(φ) = R⁰ [1 + Δ F(θ − φ)] in the lab direction φ.
                let r = size * s.relative_radius(theta - phi);
                [c[0] + r * phi.cos(), c[1] + r * phi.sin()]
            })
            .collect();
        Self { c, v }
    }

    /// The sector of `p` (the polygon is star-shaped about its centre).
    fn sector(&self, p: [f64; 2]) -> usize {
        let m = self.v.len();
        let a = (p[1] - self.c[1]).atan2(p[0] - self.c[0]).rem_euclid(TAU);
        ((a / TAU * m as f64) as usize).min(m - 1)
    }

    /// Whether `p` is inside: on the inner side of its sector's edge.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let m = self.v.len();
        let k = self.sector(p);
        let (a, b) = (self.v[k], self.v[(k + 1) % m]);
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0.0
    }

    /// The distance from `p` to the polygon's edges within 64 sectors of
    /// its own.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        let m = self.v.len();
        let k = self.sector(p) + m;
        (k - 64..k + 64)
            .map(|e| {
                let (a, b) = (self.v[e % m], self.v[(e + 1) % m]);
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy))
                    .clamp(0.0, 1.0);
                (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// How deep the other polygon's vertices reach into this one (0: none
    /// inside).
    pub fn depth_of(&self, other: &Polygon) -> f64 {
        other
            .v
            .iter()
            .filter(|p| self.contains(**p))
            .map(|p| self.distance(*p))
            .fold(0.0, f64::max)
    }
}

/// The support points of a contact: `a` on body `i` (centre at 0), `b` on
/// body `j` (centre at `r`).
pub fn support_points(e: &ExactGap, r: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let (c, s) = e.normal;
    let a = [
        e.jet_i.h * c - e.jet_i.d1 * s,
        e.jet_i.h * s + e.jet_i.d1 * c,
    ];
    let b = [
        r[0] - e.jet_j.h * c + e.jet_j.d1 * s,
        r[1] - e.jet_j.h * s - e.jet_j.d1 * c,
    ];
    (a, b)
}
