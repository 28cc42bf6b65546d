//! `SampledGrid`: exact reproduction of trilinear fields, gradient against finite
//! differences, parallel construction against a sequential one, argument errors, and a
//! property test against an independent trilinear oracle.

use proptest::prelude::*;
use sph_core::{CoreError, SampledGrid, Vec3};

/// `a + b·x + c·y + d·z + e·xy + f·yz + g·xz + h·xyz`, trilinear in (x, y, z), and its gradient.
#[derive(Clone, Copy)]
struct Trilinear([f64; 8]);

impl Trilinear {
    fn value(&self, p: Vec3<f64>) -> f64 {
        let [a, b, c, d, e, f, g, h] = self.0;
        a + b * p.x
            + c * p.y
            + d * p.z
            + e * p.x * p.y
            + f * p.y * p.z
            + g * p.x * p.z
            + h * p.x * p.y * p.z
    }

    fn gradient(&self, p: Vec3<f64>) -> Vec3<f64> {
        let [_, b, c, d, e, f, g, h] = self.0;
        Vec3::new(
            b + e * p.y + g * p.z + h * p.y * p.z,
            c + e * p.x + f * p.z + h * p.x * p.z,
            d + f * p.y + g * p.x + h * p.x * p.y,
        )
    }
}

const FIELD: Trilinear = Trilinear([0.7, -1.3, 2.1, 0.4, 0.9, -0.6, 1.7, -0.8]);

fn field_grid() -> SampledGrid<f64> {
    let origin = Vec3::new(-0.9, 0.2, -1.4);
    SampledGrid::from_fn(origin, 0.3, [7, 5, 9], |_, p| FIELD.value(p)).unwrap()
}

#[test]
fn trilinear_field_is_reproduced() {
    let g = field_grid();
    let b = g.grid_box();
    // Points inside cells, on nodes, on faces and at the corners of the box.
    let mut pts = vec![
        b.min,
        b.max,
        g.node_position(3, 2, 4),
        g.node_position(6, 0, 8),
    ];
    for s in 0..200 {
        let t = Vec3::new(
            (s as f64 * 0.618_034).fract(),
            (s as f64 * 0.414_214).fract(),
            (s as f64 * 0.732_051).fract(),
        );
        pts.push(b.min + t.component_mul(&b.extent()));
    }
    for p in pts {
        let (v, grad) = g.sample(&p).unwrap();
        assert!((v - FIELD.value(p)).abs() < 1e-12, "{p:?}: {v}");
        assert!((grad - FIELD.gradient(p)).norm() < 1e-11, "{p:?}: {grad:?}");
        // Equal up to rounding on the faces, where clamping and the box test round apart.
        let (vc, gc, off) = g.sample_clamped(&p);
        assert!(
            (vc - v).abs() < 1e-12 && (gc - grad).norm() < 1e-11,
            "{p:?}"
        );
        assert!(off.norm() < 1e-15, "{p:?}: {off:?}");
    }
}

#[test]
fn gradient_matches_central_differences() {
    // A field that is not trilinear, so the gradient varies within cells.
    let g: SampledGrid<f64> =
        SampledGrid::from_fn(Vec3::new(0.1, -0.3, 0.5), 0.25, [6, 6, 6], |_, p| {
            (3.0 * p.x).sin() * p.y.exp() + p.z * p.z * p.x
        })
        .unwrap();
    let h = 1e-6;
    for cell in [[0usize, 0, 0], [2, 3, 1], [4, 4, 4], [1, 4, 2]] {
        for frac in [[0.3, 0.5, 0.7], [0.11, 0.83, 0.42]] {
            let c = g.node_position(cell[0], cell[1], cell[2]);
            let p = c + Vec3::new(frac[0], frac[1], frac[2]) * g.cell_size();
            let (_, grad) = g.sample(&p).unwrap();
            for a in 0..3 {
                let mut e = Vec3::zeros();
                e[a] = h;
                let fd =
                    (g.sample(&(p + e)).unwrap().0 - g.sample(&(p - e)).unwrap().0) / (2.0 * h);
                assert!(
                    (fd - grad[a]).abs() < 1e-6,
                    "axis {a} at {p:?}: {fd} vs {}",
                    grad[a]
                );
            }
        }
    }
}

#[test]
fn outside_points_are_none_and_clamped_with_their_offset() {
    let g = field_grid();
    let b = g.grid_box();
    let p = Vec3::new(b.max.x + 0.5, b.min.y - 0.25, 0.0);
    assert!(g.sample(&p).is_none());
    assert!(g.sample(&Vec3::new(f64::NAN, 0.0, 0.0)).is_none());
    assert!(g.sample(&Vec3::new(0.0, f64::INFINITY, 0.0)).is_none());
    let q = Vec3::new(b.max.x, b.min.y, 0.0);
    let (v, grad, off) = g.sample_clamped(&p);
    assert!((off - (p - q)).norm() < 1e-15, "{off:?}");
    assert_eq!(off.z, 0.0);
    assert_eq!((v, grad), g.sample(&q).unwrap());
}

#[test]
fn from_fn_equals_sequential_evaluation() {
    let origin = Vec3::new(1.0, -2.0, 0.5);
    let (cell, dims) = (0.17, [13, 4, 11]);
    let f = |n: [usize; 3], p: Vec3<f64>| {
        (n[0] * 31 + n[1] * 7 + n[2]) as f64 * 1e-3 + p.x * p.y - p.z.cos()
    };
    let par = SampledGrid::<f32>::from_fn(origin, cell, dims, f).unwrap();
    let mut seq = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = origin + Vec3::new(i as f64, j as f64, k as f64) * cell;
                assert_eq!(par.node_position(i, j, k), p);
                seq.push(f([i, j, k], p) as f32);
            }
        }
    }
    assert_eq!(par.values(), &seq[..]);
    assert_eq!(par.node_value(5, 3, 10), Some(seq[5 + 13 * (3 + 4 * 10)]));
    assert_eq!(par.node_value(13, 0, 0), None);
    let from_values = SampledGrid::from_values(origin, cell, dims, seq).unwrap();
    assert_eq!(par, from_values);
    assert_eq!(par.origin(), origin);
    assert_eq!(par.dims(), dims);
    assert_eq!(par.cell_size(), cell);
}

#[test]
fn covering_counts_nodes() {
    let min = Vec3::new(-1.0, 0.0, 2.0);
    let max = Vec3::new(1.0, 0.05, 2.0);
    let dims = SampledGrid::<f64>::covering(min, max, 0.1).unwrap();
    assert_eq!(dims, [21, 2, 2]);
    // The last node reaches max on every axis, for awkward quotients too.
    for (lo, hi, cell) in [
        (0.0, 0.3, 0.1),
        (-0.7, 0.71, 0.07),
        (1e3, 1e3 + 1.0, 1.0 / 3.0),
    ] {
        let min = Vec3::repeat(lo);
        let max = Vec3::repeat(hi);
        let d = SampledGrid::<f32>::covering(min, max, cell).unwrap();
        for a in 0..3 {
            assert!(
                lo + (d[a] - 1) as f64 * cell >= hi,
                "{lo} {hi} {cell}: {d:?}"
            );
            assert!(
                lo + (d[a] - 3) as f64 * cell < hi,
                "{lo} {hi} {cell}: {d:?}"
            );
        }
    }
}

#[test]
fn bad_arguments_are_errors() {
    let (o, one) = (Vec3::zeros(), Vec3::repeat(1.0));
    type G = SampledGrid<f64>;
    for cell in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        let e = G::covering(o, one, cell).unwrap_err();
        assert!(e.to_string().contains("grid cell size"), "{e}");
        let e = G::from_fn(o, cell, [2, 2, 2], |_, _| 0.0).unwrap_err();
        assert!(e.to_string().contains("grid cell size"), "{e}");
    }
    let e = G::covering(Vec3::new(0.0, f64::NAN, 0.0), one, 0.1).unwrap_err();
    assert!(e.to_string().contains("grid min"), "{e}");
    let e = G::covering(o, Vec3::new(1.0, 1.0, f64::INFINITY), 0.1).unwrap_err();
    assert!(e.to_string().contains("grid max"), "{e}");
    let e = G::covering(o, Vec3::new(1.0, -1.0, 1.0), 0.1).unwrap_err();
    assert!(e.to_string().contains("grid max y"), "{e}");
    let e = G::covering(o, one, 1e-3).unwrap_err();
    assert!(
        matches!(e, CoreError::GridTooLarge { nx: 1001, ny: 1001, nz: 1001, max } if max == G::MAX_NODES),
        "{e}"
    );
    let e = G::covering(Vec3::repeat(-1e300), Vec3::repeat(1e300), 1e-300).unwrap_err();
    assert!(
        matches!(e, CoreError::GridTooLarge { nx: usize::MAX, .. }),
        "{e}"
    );

    let e = G::from_fn(o, 0.1, [2, 1, 2], |_, _| 0.0).unwrap_err();
    assert!(e.to_string().contains("grid nodes along y"), "{e}");
    let e = G::from_fn(o, 0.1, [usize::MAX, 2, 2], |_, _| 0.0).unwrap_err();
    assert!(matches!(e, CoreError::GridTooLarge { .. }), "{e}");
    let e = G::from_fn(o, 0.1, [1 << 9, 1 << 9, 1 << 9], |_, _| 0.0).unwrap_err();
    assert!(matches!(e, CoreError::GridTooLarge { .. }), "{e}");
    let e = G::from_fn(Vec3::new(f64::NAN, 0.0, 0.0), 0.1, [2, 2, 2], |_, _| 0.0).unwrap_err();
    assert!(e.to_string().contains("grid origin"), "{e}");
    let e = G::from_fn(Vec3::repeat(1e308), 1e308, [3, 2, 2], |_, _| 0.0).unwrap_err();
    assert!(e.to_string().contains("far corner"), "{e}");
    let e = G::from_values(o, 0.1, [2, 2, 3], vec![0.0; 8]).unwrap_err();
    assert!(
        matches!(
            e,
            CoreError::LengthMismatch {
                found: 8,
                expected: 12,
                ..
            }
        ),
        "{e}"
    );
    let e = G::from_values(o, 0.1, [0, 2, 3], vec![]).unwrap_err();
    assert!(e.to_string().contains("grid nodes along x"), "{e}");
}

/// Independent oracle: `Σ_nodes value · Π_a hat(u_a − i_a)` with `hat(s) = max(0, 1 − |s|)`
/// at grid coordinates `u` (clamped into the box), and its gradient from one-sided derivatives
/// of the hat functions (from above, except at the upper end of an axis).
fn oracle(g: &SampledGrid<f64>, p: Vec3<f64>) -> (f64, Vec3<f64>, Vec3<f64>) {
    let dims = g.dims();
    let h = g.cell_size();
    let mut u = [0.0; 3];
    let mut off = Vec3::zeros();
    for a in 0..3 {
        let top = (dims[a] - 1) as f64;
        let x = (p[a] - g.origin()[a]) / h;
        u[a] = x.clamp(0.0, top);
        if x < 0.0 || x > top {
            off[a] = p[a] - (g.origin()[a] + u[a] * h);
        }
    }
    let hat = |s: f64| (1.0 - s.abs()).max(0.0);
    let dhat = |s: f64, from_below: bool| {
        let rising = if from_below {
            s > -1.0 && s <= 0.0
        } else {
            (-1.0..0.0).contains(&s)
        };
        let falling = if from_below {
            s > 0.0 && s <= 1.0
        } else {
            (0.0..1.0).contains(&s)
        };
        if rising {
            1.0
        } else if falling {
            -1.0
        } else {
            0.0
        }
    };
    let (mut v, mut grad) = (0.0, Vec3::zeros());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let c = g.node_value(i, j, k).unwrap();
                let s = [u[0] - i as f64, u[1] - j as f64, u[2] - k as f64];
                let w = s.map(hat);
                let dw: Vec<f64> = (0..3)
                    .map(|a| dhat(s[a], u[a] == (dims[a] - 1) as f64))
                    .collect();
                v += c * w[0] * w[1] * w[2];
                grad += Vec3::new(
                    dw[0] * w[1] * w[2],
                    w[0] * dw[1] * w[2],
                    w[0] * w[1] * dw[2],
                ) * (c / h);
            }
        }
    }
    (v, grad, off)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn sampling_matches_the_oracle(
        nx in 2usize..6, ny in 2usize..6, nz in 2usize..6,
        ox in -5.0..5.0f64, oy in -5.0..5.0f64, oz in -5.0..5.0f64,
        cell in 0.05..2.0f64,
        seed in any::<u64>(),
        t in prop::collection::vec((-0.3..1.3f64, -0.3..1.3f64, -0.3..1.3f64), 1..16),
    ) {
        let origin = Vec3::new(ox, oy, oz);
        let dims = [nx, ny, nz];
        // Node values from a hash of the index, in [-10, 10).
        let g = SampledGrid::<f64>::from_fn(origin, cell, dims, |n, _| {
            let mut s = seed ^ ((n[0] as u64) << 40) ^ ((n[1] as u64) << 20) ^ n[2] as u64;
            s = s.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            s ^= s >> 29;
            s = s.wrapping_mul(0xbf58_476d_1ce4_e5b9);
            s ^= s >> 32;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0
        }).unwrap();
        let b = g.grid_box();
        for (tx, ty, tz) in t {
            let p = b.min + Vec3::new(tx, ty, tz).component_mul(&b.extent());
            let (v, grad, off) = g.sample_clamped(&p);
            let (ov, ograd, ooff) = oracle(&g, p);
            prop_assert!((v - ov).abs() < 1e-9, "value {v} vs {ov} at {p:?}");
            prop_assert!((grad - ograd).norm() < 1e-8 / cell, "gradient {grad:?} vs {ograd:?}");
            prop_assert!((off - ooff).norm() < 1e-12, "offset {off:?} vs {ooff:?}");
            // Clearly inside (away from the faces, where p rounds either way).
            let inside = [tx, ty, tz].iter().all(|t| (1e-9..=1.0 - 1e-9).contains(t));
            match g.sample(&p) {
                Some((sv, sg)) => {
                    prop_assert!(off.norm() < 1e-12, "{off:?}");
                    prop_assert!((sv - v).abs() < 1e-9 && (sg - grad).norm() < 1e-8 / cell);
                }
                None => prop_assert!(!inside, "{p:?}"),
            }
        }
    }
}
