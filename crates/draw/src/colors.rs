//! Fill colours by body size.
//!
//! One size: one colour. Two sizes (a binary mixture): blue for the small
//! bodies, orange for the large ones (the Okabe–Ito pair, readable by
//! colour-blind readers). More sizes (polydisperse): a viridis-like ramp
//! from the smallest (dark violet) to the largest (yellow). Rattlers are
//! light grey whatever their size.

/// An RGB colour.
pub type Rgb = (u8, u8, u8);

/// The fill of every body when all have one size.
pub const MONO: Rgb = (86, 180, 233);
/// The fill of the small bodies of a binary mixture.
pub const SMALL: Rgb = (86, 180, 233);
/// The fill of the large bodies of a binary mixture.
pub const LARGE: Rgb = (230, 159, 0);
/// The fill of rattlers.
pub const RATTLER_FILL: Rgb = (225, 225, 225);
/// The (dashed) outline of rattlers.
pub const RATTLER_EDGE: Rgb = (90, 90, 90);
/// The outline of the other bodies and of the box.
pub const EDGE: Rgb = (0, 0, 0);

/// Anchors of the polydisperse ramp (viridis at 0, ¼, ½, ¾, 1).
const RAMP: [Rgb; 5] = [
    (68, 1, 84),
    (59, 82, 139),
    (33, 145, 140),
    (94, 201, 98),
    (253, 231, 37),
];

/// The ramp at `t ∈ [0, 1]` (clamped), linear between the anchors.
pub fn ramp(t: f64) -> Rgb {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (RAMP.len() - 1) as f64;
    let k = (x.floor() as usize).min(RAMP.len() - 2);
    let f = x - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (RAMP[k], RAMP[k + 1]);
    (mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// The distinct sizes, ascending; sizes within a relative `1e-9` count as
/// one.
pub fn distinct_sizes(sizes: &[f64]) -> Vec<f64> {
    let mut sorted: Vec<f64> = sizes.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::new();
    for s in sorted {
        match out.last() {
            Some(&last) if (s - last).abs() <= 1e-9 * last.abs().max(s.abs()) => {}
            _ => out.push(s),
        }
    }
    out
}

/// The fill colour of each body from its size (rattlers not considered).
pub fn size_colors(sizes: &[f64]) -> Vec<Rgb> {
    let distinct = distinct_sizes(sizes);
    match distinct.len() {
        0 | 1 => vec![MONO; sizes.len()],
        2 => {
            let mid = 0.5 * (distinct[0] + distinct[1]);
            sizes
                .iter()
                .map(|&s| if s < mid { SMALL } else { LARGE })
                .collect()
        }
        _ => {
            let (lo, hi) = (distinct[0], distinct[distinct.len() - 1]);
            sizes.iter().map(|&s| ramp((s - lo) / (hi - lo))).collect()
        }
    }
}

/// The colour key of bodies of `sizes`, filled as [`size_colors`] fills
/// them: one entry per size for one or two sizes; for more, the ramp's
/// ends and middle with their sizes.
pub fn size_key(sizes: &[f64]) -> Vec<(Rgb, String)> {
    let d = distinct_sizes(sizes);
    let label = |s: f64| format!("R⁰ = {}", (s * 1e4).round() / 1e4);
    match d.len() {
        0 => Vec::new(),
        1 => vec![(MONO, label(d[0]))],
        2 => vec![(SMALL, label(d[0])), (LARGE, label(d[1]))],
        _ => {
            let (lo, hi) = (d[0], d[d.len() - 1]);
            vec![
                (ramp(0.0), label(lo)),
                (ramp(0.5), label(0.5 * (lo + hi))),
                (ramp(1.0), label(hi)),
            ]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_mixtures_get_two_colors() {
        let c = size_colors(&[0.5, 0.7, 0.5, 0.7 + 1e-13]);
        assert_eq!(c, vec![SMALL, LARGE, SMALL, LARGE]);
    }

    #[test]
    fn the_key_names_each_colour_with_its_size() {
        assert!(size_key(&[]).is_empty());
        assert_eq!(size_key(&[1.0, 1.0]), vec![(MONO, "R⁰ = 1".to_string())]);
        let binary = size_key(&[0.7, 0.5, 0.7]);
        assert_eq!(
            binary,
            vec![(SMALL, "R⁰ = 0.5".into()), (LARGE, "R⁰ = 0.7".into())]
        );
        let poly = size_key(&[1.0, 2.0, 1.5, 1.25]);
        assert_eq!(poly.len(), 3);
        assert_eq!(poly[0], (ramp(0.0), "R⁰ = 1".into()));
        assert_eq!(poly[2], (ramp(1.0), "R⁰ = 2".into()));
        assert_eq!(poly[1].1, "R⁰ = 1.5");
    }

    #[test]
    fn one_size_gets_one_color() {
        assert_eq!(size_colors(&[1.0, 1.0]), vec![MONO, MONO]);
        assert!(size_colors(&[]).is_empty());
    }

    #[test]
    fn polydisperse_sizes_follow_the_ramp() {
        let c = size_colors(&[1.0, 2.0, 1.5, 1.25]);
        assert_eq!(c[0], RAMP[0]);
        assert_eq!(c[1], RAMP[4]);
        assert_eq!(c[2], RAMP[2]);
        assert_eq!(c[3], RAMP[1]);
        assert_eq!(ramp(f64::NAN), RAMP[0]);
        assert_eq!(ramp(7.0), RAMP[4]);
    }
}
