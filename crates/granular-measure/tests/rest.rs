//! The rest criterion's sample against naive oracles: the percentile speed against a full
//! sort (nearest rank, `⌈p N⌉`-th smallest), the deep particles against an O(N²) scan that
//! finds each particle's column top by comparing it with every other particle.

use granular_measure::rest::percentile_rank;
use granular_measure::{rest_sample, PileShape, RestSettings};
use proptest::prelude::*;
use sph_core::Vec3;

/// The deep particles' largest speed and count, O(N²): particle `i` is deep when some
/// particle of its column (same `⌊(x − x_min)/s⌋`, and same `⌊(z − z_min)/s⌋` for a conical
/// pile) lies at least `k s` above it.
fn deep_oracle(x: &[Vec3<f64>], v: &[Vec3<f64>], s: f64, k: f64, conical: bool) -> (f64, usize) {
    let x0 = x.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let z0 = x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let col = |p: &Vec3<f64>| {
        (
            ((p.x - x0) / s).floor() as i64,
            if conical {
                ((p.z - z0) / s).floor() as i64
            } else {
                0
            },
        )
    };
    let mut out = (0.0f64, 0usize);
    for (i, p) in x.iter().enumerate() {
        let deep = x
            .iter()
            .any(|q| col(q) == col(p) && q.y - p.y >= (k - 1e-9) * s);
        if deep {
            out = (out.0.max(v[i].norm()), out.1 + 1);
        }
    }
    out
}

fn particles() -> impl Strategy<Value = Vec<(f64, f64, f64, f64, f64, f64)>> {
    prop::collection::vec(
        (
            0.0..0.2f64,
            0.0..0.1f64,
            0.0..0.05f64,
            -0.1..0.1f64,
            -0.1..0.1f64,
            -0.1..0.1f64,
        ),
        1..200,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn the_sample_matches_the_sort_and_scan_oracles(
        ps in particles(),
        percentile in 0.01..1.0f64,
        deep_spacings in 0.5..4.0f64,
        conical in any::<bool>(),
    ) {
        let x: Vec<Vec3<f64>> = ps.iter().map(|p| Vec3::new(p.0, p.1, p.2)).collect();
        let v: Vec<Vec3<f64>> = ps.iter().map(|p| Vec3::new(p.3, p.4, p.5)).collect();
        let s = 0.01;
        let settings = RestSettings { percentile, deep_spacings, ..RestSettings::default() };
        let shape = if conical { PileShape::Conical { axis_xz: None } } else { PileShape::Planar };
        let got = rest_sample(&x, &v, s, shape, 0.0, Some(30.0), &settings).unwrap();
        let mut sorted: Vec<f64> = v.iter().map(|u| u.norm()).collect();
        sorted.sort_by(f64::total_cmp);
        let rank = (percentile * sorted.len() as f64).ceil().max(1.0) as usize;
        prop_assert_eq!(got.percentile_speed_m_s, sorted[rank.min(sorted.len()) - 1]);
        prop_assert_eq!(percentile_rank(sorted.len(), percentile), rank.min(sorted.len()) - 1);
        let (deep, count) = deep_oracle(&x, &v, s, deep_spacings, conical);
        prop_assert_eq!(got.deep_max_speed_m_s, deep);
        prop_assert_eq!(got.deep_particles, count);
        prop_assert_eq!(got.angle_deg, Some(30.0));
    }
}

/// A settled lattice heap (a planar wedge at 30°, every 1 cm, 3 particles across) with its
/// surface layer sliding at 0.1 m/s and the rest still: the percentile sees the still bulk
/// when the sliding layer is under 1 % of the particles, and the deep speed stays 0 however
/// fast the surface moves, because the sliding particles are within two spacings of it.
#[test]
fn a_sliding_surface_layer_is_not_deep() {
    let s = 0.01;
    let tan = 30f64.to_radians().tan();
    let (mut x, mut top) = (Vec::new(), Vec::new());
    for i in 0..=100 {
        let h = ((100 - i) as f64 * s * tan / s).floor() as usize;
        for k in 0..3 {
            for j in 0..=h {
                x.push(Vec3::new(i as f64 * s, j as f64 * s, k as f64 * s));
                top.push(j == h);
            }
        }
    }
    let v: Vec<Vec3<f64>> = top
        .iter()
        .map(|&t| Vec3::new(if t { 0.1 } else { 0.0 }, 0.0, 0.0))
        .collect();
    let r = rest_sample(
        &x,
        &v,
        s,
        PileShape::Planar,
        0.0,
        None,
        &RestSettings::default(),
    )
    .unwrap();
    assert_eq!(r.deep_max_speed_m_s, 0.0);
    assert!(r.deep_particles > 0);
    // The top layer is 303 of 3 × Σ(h + 1) particles, more than 1 %: the percentile sees it.
    assert!(top.iter().filter(|&&t| t).count() * 100 > x.len());
    assert_eq!(r.percentile_speed_m_s, 0.1);
}
