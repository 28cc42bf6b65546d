//! The measurements against analytic shapes sampled with particles: cones and wedges of a
//! known slope angle, deposits of a known front. The oracles are the shapes' parameters; the
//! tolerances are the sampling's resolution, derived here (not taken from the code under test):
//!
//! The highest lattice particle of a profile bin of width `w` lies between 0 and
//! `δ = s + w tan α` below the true surface at its own horizontal position (the column nearest
//! the bin's inner edge has its top within one spacing `s` of the surface, and the bin's highest
//! particle is at most `w` further out). Jitter of amplitude `j` per coordinate adds `2j`
//! vertically and `2j√2 < 3j` horizontally. For least-squares errors `eᵢ ∈ [0, δ]` on points
//! spread over a run `D`, the slope is off by `(δ/2) Σ|dᵢ − d̄| / Σ(dᵢ − d̄)²`, `1.5 δ / D` for
//! evenly spread points; the tests allow `2 δ / D` (points one per bin, not exactly even), with
//! `D = (0.6 H − δ) / tan α` the run of the 20–80 % band.

use granular_measure::{
    angle_of_repose, normalised_runout, radial_runout, runout, surface_profile, FrontMethod,
    MeasureError, PileShape, RadialRunoutOptions, ReposeOptions, RunoutOptions,
};
use proptest::prelude::*;
use sph_core::random::SplitMix64;
use sph_core::Vec3;

/// A small deterministic generator for jitter.
struct Jitter(SplitMix64);

impl Jitter {
    fn offset(&mut self, amplitude: f64) -> f64 {
        amplitude * (2.0 * self.0.unit() - 1.0)
    }
}

/// A cone of slope `alpha` and height `h` on the floor `y = 0`, its axis at `(cx, cz)`,
/// sampled on a cubic lattice of spacing `s` centred on the axis (jitter `j` per coordinate).
fn cone(alpha_deg: f64, h: f64, s: f64, (cx, cz): (f64, f64), j: f64, seed: u64) -> Vec<Vec3<f64>> {
    let tan = alpha_deg.to_radians().tan();
    let r_base = h / tan;
    let n = (r_base / s).ceil() as i64 + 1;
    let mut rng = Jitter(SplitMix64::new(seed));
    let mut out = Vec::new();
    for i in -n..=n {
        for k in -n..=n {
            let (dx, dz) = (i as f64 * s, k as f64 * s);
            let r = dx.hypot(dz);
            let mut l = 0;
            loop {
                let y = (l as f64 + 0.5) * s;
                if y > h - r * tan {
                    break;
                }
                out.push(Vec3::new(
                    cx + dx + rng.offset(j),
                    y + rng.offset(j),
                    cz + dz + rng.offset(j),
                ));
                l += 1;
            }
        }
    }
    out
}

/// A planar heap along `x` (3 layers in `z`): flanks of slope `left_deg` rising from
/// `x = x0` and `right_deg` falling to the +x side, apex height `h` at `x_apex`; `None` for a
/// flank means a vertical wall there (a heap against a wall).
fn wedge(
    left_deg: Option<f64>,
    right_deg: f64,
    h: f64,
    x_apex: f64,
    s: f64,
    j: f64,
    seed: u64,
) -> Vec<Vec3<f64>> {
    let tan_r = right_deg.to_radians().tan();
    let tan_l = left_deg.map(|a| a.to_radians().tan());
    let x_lo = tan_l.map_or(x_apex, |t| x_apex - h / t);
    let x_hi = x_apex + h / tan_r;
    let mut rng = Jitter(SplitMix64::new(seed));
    let mut out = Vec::new();
    let mut i = 0;
    loop {
        let x = x_lo + (i as f64 + 0.5) * s;
        if x > x_hi {
            break;
        }
        let top = if x <= x_apex {
            tan_l.map_or(h, |t| h - (x_apex - x) * t)
        } else {
            h - (x - x_apex) * tan_r
        };
        let mut l = 0;
        loop {
            let y = (l as f64 + 0.5) * s;
            if y > top {
                break;
            }
            for k in 0..3 {
                out.push(Vec3::new(
                    x + rng.offset(j),
                    y + rng.offset(j),
                    (k as f64 + 0.5) * s + rng.offset(j),
                ));
            }
            l += 1;
        }
        i += 1;
    }
    out
}

/// The slope tolerance of the module comment, on `tan`.
fn tan_tolerance(alpha_deg: f64, h: f64, s: f64, w: f64, j: f64) -> f64 {
    let tan = alpha_deg.to_radians().tan();
    let delta = s + 2.0 * j + (w + 3.0 * j) * tan;
    let run = (0.6 * h - delta) / tan;
    2.0 * delta / run
}

fn assert_angle(measured_deg: f64, alpha_deg: f64, tol_tan: f64) {
    let err = (measured_deg.to_radians().tan() - alpha_deg.to_radians().tan()).abs();
    assert!(
        err <= tol_tan,
        "measured {measured_deg:.3} deg for a slope of {alpha_deg:.3} deg: |d tan| = {err:.4} > {tol_tan:.4}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn cone_angle_within_sampling_resolution(
        alpha in 15.0f64..60.0,
        layers in 14.0f64..26.0,
        bin_over_s in 0.7f64..1.5,
        jitter_over_s in 0.0f64..0.2,
        axis_given in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let s = 0.01;
        let h = layers * s;
        let (w, j) = (bin_over_s * s, jitter_over_s * s);
        prop_assume!(0.6 * h / alpha.to_radians().tan() >= 6.0 * w);
        let axis = (0.37, -0.21);
        let pts = cone(alpha, h, s, axis, j, seed);
        let mut opts = ReposeOptions::conical(0.0, w).with_spacing(s);
        if axis_given {
            opts.shape = PileShape::Conical { axis_xz: Some([axis.0, axis.1]) };
        }
        let m = angle_of_repose(&pts, &opts).unwrap();
        assert_angle(m.angle_deg, alpha, tan_tolerance(alpha, h, s, w, j));
        prop_assert_eq!(m.flanks.len(), 1);
        // the pile height is the highest centre: within δ below h
        prop_assert!(m.pile_height_m <= h + j && m.pile_height_m >= h - s - 2.0 * j - w * alpha.to_radians().tan());
    }

    #[test]
    fn planar_heap_both_flanks(
        left in 15.0f64..65.0,
        right in 15.0f64..65.0,
        layers in 16.0f64..60.0,
        bin_over_s in 0.7f64..2.0,
        jitter_over_s in 0.0f64..0.2,
        seed in any::<u64>(),
    ) {
        let s = 0.005;
        let h = layers * s;
        let (w, j) = (bin_over_s * s, jitter_over_s * s);
        // each flank's 20-80 % band must span enough bins for a fit (else Degenerate, below)
        for a in [left, right] {
            prop_assume!(0.6 * h / a.to_radians().tan() >= 6.0 * w);
        }
        let pts = wedge(Some(left), right, h, 1.3, s, j, seed);
        let m = angle_of_repose(&pts, &ReposeOptions::planar(0.0, w)).unwrap();
        prop_assert_eq!(m.flanks.len(), 2);
        for f in &m.flanks {
            let truth = if f.side < 0 { left } else { right };
            assert_angle(f.angle_deg, truth, tan_tolerance(truth, h, s, w, j));
        }
        prop_assert!((m.angle_deg - 0.5 * (m.flanks[0].angle_deg + m.flanks[1].angle_deg)).abs() < 1e-12);
    }

    #[test]
    fn planar_heap_against_a_wall_has_one_flank(
        alpha in 15.0f64..65.0,
        layers in 16.0f64..60.0,
        seed in any::<u64>(),
    ) {
        let s = 0.005;
        let h = layers * s;
        prop_assume!(0.6 * h / alpha.to_radians().tan() >= 6.0 * s);
        let pts = wedge(None, alpha, h, 0.0, s, 0.1 * s, seed);
        let m = angle_of_repose(&pts, &ReposeOptions::planar(0.0, s)).unwrap();
        prop_assert_eq!(m.flanks.len(), 1);
        prop_assert_eq!(m.flanks[0].side, 1);
        assert_angle(m.angle_deg, alpha, tan_tolerance(alpha, h, s, s, 0.1 * s));
    }

    #[test]
    fn runout_front_of_a_deposit(
        length_over_s in 20.0f64..300.0,
        s in 0.002f64..0.02,
        stray in 0usize..5,
    ) {
        // A deposit from the wall x = 0.5 to x = 0.5 + L: a block two spacings high with a
        // wedge on top near the wall, then grains thrown ahead beyond a gap of 3 spacings.
        let (wall, l) = (0.5, length_over_s * s);
        let mut pts = Vec::new();
        let mut i = 0;
        loop {
            let x = wall + (i as f64 + 0.5) * s;
            if x > wall + l {
                break;
            }
            let top = 2.0 * s + (0.3 * l - (x - wall)).max(0.0);
            let mut y = 0.5 * s;
            while y <= top {
                pts.push(Vec3::new(x, y, 0.5 * s));
                y += s;
            }
            i += 1;
        }
        let last = pts.iter().map(|p| p.x).fold(f64::MIN, f64::max);
        for k in 0..stray {
            pts.push(Vec3::new(last + 3.0 * s + 4.0 * s * k as f64, 0.5 * s, 0.5 * s));
        }
        let front = runout(&pts, &RunoutOptions::connected(wall, s)).unwrap();
        // the last lattice column lies in (L - s, L]; plus the radius s/2
        prop_assert!(front > l - 0.5 * s - 1e-12 && front <= l + 0.5 * s + 1e-12, "front {} for L {}", front, l);
        let q = runout(&pts, &RunoutOptions {
            wall_x: wall,
            method: FrontMethod::Quantile { fraction_ahead: 0.0 },
            particle_radius_m: 0.5 * s,
        }).unwrap();
        let farthest = pts.iter().map(|p| p.x).fold(f64::MIN, f64::max) + 0.5 * s - wall;
        prop_assert!((q - farthest).abs() < 1e-12);
        let r = normalised_runout(front, 0.1 * l).unwrap();
        prop_assert!((r - (front - 0.1 * l) / (0.1 * l)).abs() < 1e-12);
    }
}

#[test]
fn flat_layer_is_degenerate() {
    let s = 0.01;
    let mut pts = Vec::new();
    for i in 0..100 {
        for l in 0..4 {
            pts.push(Vec3::new((i as f64 + 0.5) * s, (l as f64 + 0.5) * s, 0.005));
        }
    }
    let e = angle_of_repose(&pts, &ReposeOptions::planar(0.0, s)).unwrap_err();
    assert!(matches!(e, MeasureError::Degenerate { .. }), "{e}");
    // but its profile is flat at the top layer
    let profile = surface_profile(&pts, PileShape::Planar, s).unwrap();
    // 100 columns in 100 bins (floating-point edges may put two columns in one bin)
    assert!(
        profile.len() > 90 && profile.len() <= 100,
        "{}",
        profile.len()
    );
    assert!(profile.iter().all(|p| (p.y_m - 0.035).abs() < 1e-12));
}

#[test]
fn too_narrow_a_band_is_degenerate_not_a_number() {
    // 10 layers at 60 degrees: the 20-80 % band spans 6 s / tan 60 = 3.5 spacings, 2 bins of 2 s
    let s = 0.01;
    let pts = wedge(Some(60.0), 60.0, 10.0 * s, 0.5, s, 0.0, 1);
    let e = angle_of_repose(&pts, &ReposeOptions::planar(0.0, 2.0 * s)).unwrap_err();
    assert!(matches!(e, MeasureError::Degenerate { .. }), "{e}");
    assert!(e.to_string().contains("points per flank"), "{e}");
}

#[test]
fn bad_input_is_named() {
    let empty: Vec<Vec3<f32>> = Vec::new();
    assert!(matches!(
        angle_of_repose(&empty, &ReposeOptions::conical(0.0, 0.01)),
        Err(MeasureError::Empty { .. })
    ));
    assert!(matches!(
        runout(&empty, &RunoutOptions::connected(0.0, 0.01)),
        Err(MeasureError::Empty { .. })
    ));
    let mut pts = cone(30.0, 0.2, 0.01, (0.0, 0.0), 0.0, 1);
    pts[17].y = f64::NAN;
    let e = angle_of_repose(&pts, &ReposeOptions::conical(0.0, 0.01)).unwrap_err();
    assert!(
        matches!(e, MeasureError::NonFinite { index: 17, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("particle 17"));
    let e = runout(&pts, &RunoutOptions::connected(0.0, 0.01)).unwrap_err();
    assert!(matches!(e, MeasureError::NonFinite { index: 17, .. }));
    pts[17].y = 0.005;
    for (opts, name) in [
        (ReposeOptions::conical(0.0, 0.0), "bin_width_m"),
        (ReposeOptions::conical(f64::NAN, 0.01), "floor_y"),
        (
            ReposeOptions {
                fit_band: [0.5, 0.4],
                ..ReposeOptions::conical(0.0, 0.01)
            },
            "fit_band[1]",
        ),
        (
            ReposeOptions {
                min_fit_points: 2,
                ..ReposeOptions::conical(0.0, 0.01)
            },
            "min_fit_points",
        ),
    ] {
        match angle_of_repose(&pts, &opts) {
            Err(MeasureError::InvalidOption { option, .. }) => assert_eq!(option, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    // all particles below the floor
    assert!(matches!(
        angle_of_repose(&pts, &ReposeOptions::conical(1.0, 0.01)),
        Err(MeasureError::Degenerate { .. })
    ));
    assert!(normalised_runout(1.0, 0.0).is_err());
    assert!(normalised_runout(f64::NAN, 1.0).is_err());
    assert!(runout(
        &pts,
        &RunoutOptions {
            wall_x: 0.0,
            method: FrontMethod::Quantile {
                fraction_ahead: 0.7
            },
            particle_radius_m: 0.0
        }
    )
    .is_err());
}

#[test]
fn f32_positions_measure_like_f64() {
    let pts = cone(35.0, 0.2, 0.01, (0.0, 0.0), 0.0, 3);
    let pts32: Vec<Vec3<f32>> = pts.iter().map(|p| p.cast::<f32>()).collect();
    let opts = ReposeOptions::conical(0.0, 0.01);
    let a = angle_of_repose(&pts, &opts).unwrap().angle_deg;
    let b = angle_of_repose(&pts32, &opts).unwrap().angle_deg;
    assert!((a - b).abs() < 0.05, "{a} vs {b}");
}

#[test]
fn resolution_estimate_covers_the_error_of_a_lattice_cone() {
    for alpha in [20.0, 30.0, 40.0] {
        let s = 0.01;
        let pts = cone(alpha, 0.25, s, (0.0, 0.0), 0.0, 5);
        let m = angle_of_repose(&pts, &ReposeOptions::conical(0.0, s).with_spacing(s)).unwrap();
        let res = m.resolution_deg.unwrap();
        assert!(
            (m.angle_deg - alpha).abs() <= res,
            "alpha {alpha}: measured {:.3}, resolution {res:.3}",
            m.angle_deg
        );
    }
}

/// A planar heap on the floor `y = 0` between `x_lo` and `x_hi` whose surface height at `x`
/// is `top(x)`, sampled on a cubic lattice of spacing `s` whose columns start at `x_lo +
/// phase · s` (3 layers in `z`, jitter `j` per coordinate).
fn heap_of(
    top: impl Fn(f64) -> f64,
    (x_lo, x_hi): (f64, f64),
    phase: f64,
    s: f64,
    j: f64,
    seed: u64,
) -> Vec<Vec3<f64>> {
    let mut rng = Jitter(SplitMix64::new(seed));
    let mut out = Vec::new();
    let mut x = x_lo + phase * s;
    while x < x_hi {
        let mut y = 0.5 * s;
        while y <= top(x) {
            for k in 0..3 {
                out.push(Vec3::new(
                    x + rng.offset(j),
                    y + rng.offset(j),
                    (k as f64 + 0.5) * s + rng.offset(j),
                ));
            }
            y += s;
        }
        x += s;
    }
    out
}

/// The resolution of the `granular-repose` measurement in quick mode: a heap on a base of
/// half-width 0.4 m at spacing 10 mm (13.7 particles tall at 18.9°, 33.6 at 40°), measured
/// as the experiment does (bins of one spacing, the 20–80 % band, the steepest run of
/// 0.2 m: shorter runs follow the lattice's steps, 2.8° off at 0.1 m and 1.6° at 0.15 m),
/// over slopes of 15°–42°, lattice phases and jitter up to 0.15 spacing. The
/// oracle is the shape's angle; the bound (1°) is what the repose experiment needs (its
/// resolution better than ±1° in quick mode). The largest errors seen are printed (run with
/// `--nocapture`).
#[test]
fn quick_repose_heap_measured_within_one_degree() {
    let (s, half) = (0.01, 0.4);
    let opts = ReposeOptions::planar(0.0, s)
        .with_spacing(s)
        .with_steepest_run(0.2);
    let (mut worst_fit, mut worst_steep) = (0.0f64, 0.0f64);
    let mut seed = 11;
    for beta in [15.0, 18.9, 20.0, 26.6, 30.0, 32.7, 36.0, 40.0, 42.0] {
        let tan = f64::to_radians(beta).tan();
        for phase in [0.0, 0.25, 0.5, 0.75] {
            for j in [0.0, 0.05 * s, 0.15 * s] {
                seed += 1;
                let (x0, x1) = (1.0 - half, 1.0 + half);
                let pts = heap_of(
                    |x| half * tan - (x - 1.0).abs() * tan,
                    (x0, x1),
                    phase,
                    s,
                    j,
                    seed,
                );
                let m = angle_of_repose(&pts, &opts).unwrap();
                assert_eq!(m.flanks.len(), 2);
                let steep = m.steepest_deg.unwrap();
                worst_fit = worst_fit.max((m.angle_deg - beta).abs());
                worst_steep = worst_steep.max((steep - beta).abs());
                assert!(
                    (m.angle_deg - beta).abs() < 1.0 && (steep - beta).abs() < 1.0,
                    "slope {beta}, phase {phase}, jitter {j}: fit {:.3}, steepest {steep:.3}",
                    m.angle_deg
                );
            }
        }
    }
    println!("largest error: fit {worst_fit:.3} deg, steepest 0.2 m {worst_steep:.3} deg");
}

/// The steepest-slope measure finds the steep part of a concave flank (30° above, 15° below
/// a knee at half height) that the band fit averages away, and stays on the straight
/// flank's angle for a straight one.
#[test]
fn steepest_slope_of_a_kinked_flank() {
    let s = 0.005;
    let (t30, t15) = (f64::to_radians(30.0).tan(), f64::to_radians(15.0).tan());
    let (h, knee) = (0.3, 0.15);
    let x_knee = (h - knee) / t30;
    let top = |x: f64| {
        let d = (x - 1.0).abs();
        if d <= x_knee {
            h - d * t30
        } else {
            knee - (d - x_knee) * t15
        }
    };
    let half = x_knee + knee / t15;
    let pts = heap_of(top, (1.0 - half, 1.0 + half), 0.3, s, 0.0, 3);
    let m = angle_of_repose(&pts, &ReposeOptions::planar(0.0, s).with_steepest_run(0.1)).unwrap();
    let steep = m.steepest_deg.unwrap();
    assert!((steep - 30.0).abs() < 1.0, "steepest {steep}");
    assert!(m.angle_deg < 25.0, "band fit {}", m.angle_deg);
    // Without the option there is no steepest slope; with a run longer than the band, none.
    let m = angle_of_repose(&pts, &ReposeOptions::planar(0.0, s)).unwrap();
    assert_eq!(m.steepest_deg, None);
    let m = angle_of_repose(&pts, &ReposeOptions::planar(0.0, s).with_steepest_run(5.0)).unwrap();
    assert_eq!(m.steepest_deg, None);
    let e = angle_of_repose(&pts, &ReposeOptions::planar(0.0, s).with_steepest_run(-1.0));
    assert!(matches!(
        e,
        Err(MeasureError::InvalidOption {
            option: "steepest_run_m",
            ..
        })
    ));
}

/// The outermost bottom-layer centre of a lattice cone of slope `alpha` and height `h`
/// (layer centres at `(l + ½) s`): the bottom layer reaches `(h − s/2) / tan α`.
fn cone_outline(alpha_deg: f64, h: f64, s: f64) -> f64 {
    (h - 0.5 * s) / alpha_deg.to_radians().tan()
}

/// The largest connected set by breadth-first search over all pairs (the naive oracle of the
/// deposit): ties to the set holding the lowest index.
fn naive_largest_cluster(pts: &[Vec3<f64>], gap: f64) -> Vec<usize> {
    let n = pts.len();
    let mut label = vec![usize::MAX; n];
    let mut best: (usize, usize) = (0, usize::MAX);
    for start in 0..n {
        if label[start] != usize::MAX {
            continue;
        }
        label[start] = start;
        let mut queue = vec![start];
        let mut size = 0;
        while let Some(i) = queue.pop() {
            size += 1;
            for j in 0..n {
                if label[j] == usize::MAX && (pts[i] - pts[j]).norm() < gap {
                    label[j] = start;
                    queue.push(j);
                }
            }
        }
        if best.1 == usize::MAX || size > best.0 {
            best = (size, start);
        }
    }
    (0..n).filter(|&i| label[i] == best.1).collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// A lattice cone's runout is its bottom layer's outline: each sector's outermost centre
    /// lies within one spacing inside it (the lattice's resolution along a ray in a sector at
    /// least three spacings wide), the particle radius then added; jitter `j` moves it by
    /// at most `√2 j` more.
    #[test]
    fn radial_runout_of_a_cone_is_its_outline(
        alpha in 15.0f64..45.0,
        layers in 6.0f64..16.0,
        sectors in 1usize..24,
        jitter_over_s in 0.0f64..0.1,
        seed in any::<u64>(),
    ) {
        let s = 0.01;
        let h = layers * s;
        let j = jitter_over_s * s;
        let outline = cone_outline(alpha, h, s);
        prop_assume!(std::f64::consts::TAU * outline / sectors as f64 >= 3.0 * s);
        let axis = (0.37, -0.21);
        let mut pts = cone(alpha, h, s, axis, j, seed);
        let opts = RadialRunoutOptions {
            sectors,
            ..RadialRunoutOptions::connected([axis.0, axis.1], s)
        };
        let clean = radial_runout(&pts, &opts).unwrap();
        let centre = clean.radius_m - 0.5 * s;
        let jit = std::f64::consts::SQRT_2 * j;
        prop_assert!(centre >= outline - s - jit && centre <= outline + jit,
            "runout {} against the outline {outline} (s = {s})", clean.radius_m);
        prop_assert_eq!(clean.deposit.len(), pts.len());
        // grains thrown ahead, separated from the deposit, do not count
        let n = pts.len();
        for k in 0..8 {
            let phi = k as f64 * 0.8;
            let r = outline + 3.0 * s;
            pts.push(Vec3::new(axis.0 + r * phi.cos(), 0.5 * s, axis.1 + r * phi.sin()));
        }
        let thrown = radial_runout(&pts, &opts).unwrap();
        prop_assert_eq!(thrown.radius_m, clean.radius_m);
        prop_assert_eq!(thrown.deposit, (0..n).collect::<Vec<_>>());
    }

    /// The deposit is the largest connected set, as the naive search over all pairs finds it.
    #[test]
    fn deposit_is_the_largest_connected_set(
        blobs in proptest::collection::vec((-0.1f64..0.1, -0.1f64..0.1, 1usize..40), 1..5),
        gap in 0.005f64..0.03,
        seed in any::<u64>(),
    ) {
        let mut rng = Jitter(SplitMix64::new(seed));
        let mut pts = Vec::new();
        for &(x, z, count) in &blobs {
            for _ in 0..count {
                pts.push(Vec3::new(x + rng.offset(0.02), rng.offset(0.02), z + rng.offset(0.02)));
            }
        }
        let opts = RadialRunoutOptions { sectors: 1, ..RadialRunoutOptions::connected([0.0, 0.0], gap / 2.0) };
        let got = radial_runout(&pts, &opts).unwrap();
        prop_assert_eq!(got.deposit, naive_largest_cluster(&pts, gap));
    }
}

/// An elliptical layer (semi-axes 0.3 m along x, 0.15 m along z): each sector's front is the
/// largest ellipse radius over the sector's azimuths (oracle: 1000 azimuths per sector), to
/// within one spacing (lattice) and the particle radius added.
#[test]
fn radial_runout_of_an_ellipse_is_its_mean_sector_outline() {
    let (a, b, s) = (0.3, 0.15, 0.005);
    let mut pts = Vec::new();
    let n = (a / s) as i64 + 1;
    for i in -n..=n {
        for k in -n..=n {
            let (x, z) = (i as f64 * s, k as f64 * s);
            if (x / a).powi(2) + (z / b).powi(2) < 1.0 {
                pts.push(Vec3::new(x, 0.5 * s, z));
            }
        }
    }
    let sectors = 12;
    let opts = RadialRunoutOptions {
        sectors,
        ..RadialRunoutOptions::connected([0.0, 0.0], s)
    };
    let got = radial_runout(&pts, &opts).unwrap();
    let r_of = |phi: f64| 1.0 / ((phi.cos() / a).powi(2) + (phi.sin() / b).powi(2)).sqrt();
    let tau = std::f64::consts::TAU;
    for (k, front) in got.sector_fronts_m.iter().enumerate() {
        let oracle = (0..1000)
            .map(|m| -std::f64::consts::PI + tau * (k as f64 + m as f64 / 1000.0) / sectors as f64)
            .map(r_of)
            .fold(0.0, f64::max);
        let centre = front - 0.5 * s;
        assert!(
            centre <= oracle && centre >= oracle - s,
            "sector {k}: front {front} against the outline {oracle}"
        );
    }
}

#[test]
fn radial_runout_bad_input_is_named() {
    let s = 0.01;
    let half: Vec<Vec3<f64>> = (0..20)
        .flat_map(|i| {
            (0..10).map(move |k| Vec3::new(i as f64 * s - 0.1, 0.005, k as f64 * s + 0.001))
        })
        .collect();
    let opts = RadialRunoutOptions::connected([0.0, 0.0], s);
    let e = radial_runout(&half, &opts).unwrap_err();
    assert!(matches!(e, MeasureError::Degenerate { .. }), "{e}");
    assert!(e.to_string().contains("does not surround the axis"), "{e}");
    let e = radial_runout::<f64>(&[], &opts).unwrap_err();
    assert!(matches!(e, MeasureError::Empty { .. }), "{e}");
    let bad = |o: RadialRunoutOptions, name: &str| {
        let e = radial_runout(&half, &o).unwrap_err();
        assert!(e.to_string().contains(name), "{e}");
    };
    bad(RadialRunoutOptions { sectors: 0, ..opts }, "sectors");
    bad(
        RadialRunoutOptions {
            max_gap_m: 0.0,
            ..opts
        },
        "max_gap_m",
    );
    bad(
        RadialRunoutOptions {
            particle_radius_m: f64::NAN,
            ..opts
        },
        "particle_radius_m",
    );
    bad(
        RadialRunoutOptions {
            axis_xz: [f64::INFINITY, 0.0],
            ..opts
        },
        "axis_xz",
    );
    let mut nan = half.clone();
    nan[3].y = f64::NAN;
    let e = radial_runout(&nan, &opts).unwrap_err();
    assert!(matches!(e, MeasureError::NonFinite { index: 3, .. }), "{e}");
}
