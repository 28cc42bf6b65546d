//! The conical heap's angle per azimuthal sector (`granular_measure::cone`): exact cones in
//! particles, cones whose flanks differ by sector, a lattice cone within the fit's resolution
//! bound, grains fallen off the rim left out, and every bad input an error.

use granular_measure::{cone_angle_by_sector, ConeBase, ConeOptions, MeasureError, Vec3};
use proptest::prelude::*;

const BASE: ConeBase = ConeBase {
    centre_xz: [2.0, 3.0],
    radius_m: 1.0,
    top_y: 0.5,
};

/// Grains exactly on the surface `y = top + (R − r) tan α(φ)` on a polar grid (radii every
/// 0.01 m, azimuths every degree from 0.5°), an apex grain, and interior grains at least
/// 0.05 m below the surface (never the highest of a radial bin).
fn exact_cone(angle_deg: impl Fn(f64) -> f64) -> Vec<Vec3<f64>> {
    let ConeBase {
        centre_xz: [cx, cz],
        radius_m,
        top_y,
    } = BASE;
    let surface =
        |r: f64, phi_deg: f64| top_y + (radius_m - r) * angle_deg(phi_deg).to_radians().tan();
    let mut p = Vec::new();
    for i in 1..=100 {
        let r = 0.01 * f64::from(i);
        for j in 0..360 {
            let phi = f64::from(j) + 0.5;
            let (x, z) = (
                cx + r * phi.to_radians().cos(),
                cz + r * phi.to_radians().sin(),
            );
            let y_top = surface(r, phi);
            p.push(Vec3::new(x, y_top, z));
            let mut y = top_y;
            while y < y_top - 0.05 {
                p.push(Vec3::new(x, y, z));
                y += 0.05;
            }
        }
    }
    p.push(Vec3::new(cx, surface(0.0, 0.5), cz));
    p
}

#[test]
fn an_exact_cone_measures_its_angle_in_every_sector() {
    for alpha in [20.0, 30.0, 40.0] {
        let m = cone_angle_by_sector(&exact_cone(|_| alpha), &ConeOptions::new(BASE, 12, 0.02))
            .unwrap();
        assert_eq!(m.fitted, 12);
        for s in &m.sectors {
            let a = s.angle_deg.unwrap();
            assert!(
                (a - alpha).abs() < 1e-9,
                "sector {:?}: {a} against {alpha}",
                s.azimuth_deg
            );
            assert!(s.points >= 20, "{} points", s.points);
        }
        assert!((m.mean_deg - alpha).abs() < 1e-9);
        assert!(m.std_deg < 1e-9 && m.max_deg - m.min_deg < 1e-9);
        let h = alpha.to_radians().tan();
        assert!((m.height_m - h).abs() < 1e-12, "{} against {h}", m.height_m);
    }
}

/// Flanks of 26°–34° by sector (as a heap leaning one way): each sector its own angle, the
/// mean, standard deviation and range over azimuth those of the sectors' angles.
#[test]
fn an_asymmetric_cone_gives_the_spread_of_its_flanks() {
    let n = 8;
    let per_sector: Vec<f64> = (0..n)
        .map(|k| 30.0 + 4.0 * (2.0 * std::f64::consts::PI * (k as f64 + 0.5) / n as f64).cos())
        .collect();
    let angle = |phi: f64| per_sector[(phi / 45.0) as usize];
    let m = cone_angle_by_sector(&exact_cone(angle), &ConeOptions::new(BASE, n, 0.02)).unwrap();
    for (s, want) in m.sectors.iter().zip(&per_sector) {
        assert!((s.angle_deg.unwrap() - want).abs() < 1e-9);
    }
    let mean = per_sector.iter().sum::<f64>() / n as f64;
    let var = per_sector.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
    assert!(
        (m.mean_deg - mean).abs() < 1e-9,
        "{} against {mean}",
        m.mean_deg
    );
    assert!(
        (m.std_deg - var.sqrt()).abs() < 1e-9,
        "{} against {}",
        m.std_deg,
        var.sqrt()
    );
    // 30 ± 4 cos(22.5°) at the sectors nearest +x and −x.
    let extreme = 4.0 * (std::f64::consts::PI / 8.0).cos();
    assert!((m.max_deg - (30.0 + extreme)).abs() < 1e-9);
    assert!((m.min_deg - (30.0 - extreme)).abs() < 1e-9);
    // The spread is the flanks': a symmetric cone has none (previous test).
    assert!(m.std_deg > 2.0);
}

/// A cone of grains on a cubic lattice at spacing `s` = 10 mm, `R` = 50 spacings: every
/// sector within the fit's resolution bound of `granular_measure::repose` (`cos² α · 1.5 δ /
/// D`, `δ = s + bin · tan α`, `D` the sector's fitted run), computed here from the lattice.
#[test]
fn a_lattice_cone_stands_within_the_resolution_bound() {
    let s = 0.01;
    let alpha: f64 = 30.0;
    let t = alpha.to_radians().tan();
    let ConeBase {
        centre_xz: [cx, cz],
        radius_m,
        top_y,
    } = BASE;
    let n = (radius_m / s).round() as i32;
    let mut p = Vec::new();
    for i in -n..=n {
        for k in -n..=n {
            let (x, z) = (cx + f64::from(i) * s, cz + f64::from(k) * s);
            let r = (x - cx).hypot(z - cz);
            let mut y = top_y + 0.5 * s;
            while r <= radius_m && y <= top_y + (radius_m - r) * t {
                p.push(Vec3::new(x, y, z));
                y += s;
            }
        }
    }
    let m = cone_angle_by_sector(&p, &ConeOptions::new(BASE, 12, s)).unwrap();
    assert_eq!(m.fitted, 12);
    let delta = s + s * t;
    for sec in &m.sectors {
        let a = sec.angle_deg.unwrap();
        let bound = (alpha.to_radians().cos().powi(2) * 1.5 * delta / sec.run_m).to_degrees();
        assert!(
            (a - alpha).abs() <= bound,
            "sector {:?}: {a:.3}° against {alpha}° ± {bound:.3}°",
            sec.azimuth_deg
        );
    }
}

/// A sector whose innermost bin holds only a buried grain (its surface grains near the axis
/// gone, one grain left at mid-height): the points nearer the axis than the sector's crest
/// are not on the flank, and the sector still measures its generatrix. With that grain in
/// the fit, the sector measured 24.76° (the fit before the crest rule).
#[test]
fn a_buried_grain_inside_the_crest_is_not_on_the_flank() {
    let alpha = 30.0;
    let [cx, cz] = BASE.centre_xz;
    let mut p: Vec<Vec3<f64>> = exact_cone(|_| alpha)
        .into_iter()
        .filter(|g| {
            let (dx, dz) = (g.x - cx, g.z - cz);
            let phi = dz.atan2(dx).to_degrees().rem_euclid(360.0);
            !(phi < 30.0 && dx.hypot(dz) < 0.1)
        })
        .collect();
    let h = alpha.to_radians().tan();
    let phi = 15f64.to_radians();
    p.push(Vec3::new(
        cx + 0.02 * phi.cos(),
        BASE.top_y + 0.5 * h,
        cz + 0.02 * phi.sin(),
    ));
    let m = cone_angle_by_sector(&p, &ConeOptions::new(BASE, 12, 0.02)).unwrap();
    let a = m.sectors[0].angle_deg.unwrap();
    assert!((a - alpha).abs() < 1e-9, "sector 0: {a} against {alpha}");
    assert!((m.mean_deg - alpha).abs() < 1e-9, "{}", m.mean_deg);
}

/// Grains that fell over the rim (below the base's top, outside its radius) are not the
/// heap's: the measurement is the same with them.
#[test]
fn grains_off_the_base_are_left_out() {
    let heap = exact_cone(|_| 30.0);
    let with = cone_angle_by_sector(&heap, &ConeOptions::new(BASE, 12, 0.02)).unwrap();
    let mut spilled = heap.clone();
    for j in 0..720 {
        let phi = f64::from(j).to_radians() / 2.0;
        for (r, y) in [(1.1, 0.45), (1.3, 0.1), (1.05, 0.49), (1.5, 0.0)] {
            spilled.push(Vec3::new(2.0 + r * phi.cos(), y, 3.0 + r * phi.sin()));
        }
    }
    let without = cone_angle_by_sector(&spilled, &ConeOptions::new(BASE, 12, 0.02)).unwrap();
    assert_eq!(with, without);
}

fn invalid(positions: &[Vec3<f64>], o: &ConeOptions) -> &'static str {
    match cone_angle_by_sector(positions, o) {
        Err(MeasureError::InvalidOption { option, .. }) => option,
        other => panic!("expected an invalid option, got {other:?}"),
    }
}

#[test]
fn bad_input_is_an_error() {
    let heap = exact_cone(|_| 30.0);
    let ok = ConeOptions::new(BASE, 12, 0.02);
    assert!(matches!(
        cone_angle_by_sector::<f64>(&[], &ok),
        Err(MeasureError::Empty { .. })
    ));
    let mut nan = heap.clone();
    nan[7].y = f64::NAN;
    assert!(matches!(
        cone_angle_by_sector(&nan, &ok),
        Err(MeasureError::NonFinite { index: 7, .. })
    ));
    let with = |f: &dyn Fn(&mut ConeOptions)| {
        let mut o = ok;
        f(&mut o);
        o
    };
    assert_eq!(invalid(&heap, &with(&|o| o.sectors = 2)), "sectors");
    assert_eq!(invalid(&heap, &with(&|o| o.sectors = 361)), "sectors");
    assert_eq!(
        invalid(&heap, &with(&|o| o.base.radius_m = 0.0)),
        "base.radius_m"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.base.radius_m = f64::INFINITY)),
        "base.radius_m"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.base.centre_xz[1] = f64::NAN)),
        "base.centre_xz"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.base.top_y = f64::NAN)),
        "base.top_y"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.bin_width_m = -1.0)),
        "bin_width_m"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.fit_band = [0.5, 0.5])),
        "fit_band[1]"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.fit_band = [-0.1, 0.5])),
        "fit_band[0]"
    );
    assert_eq!(
        invalid(&heap, &with(&|o| o.min_fit_points = 2)),
        "min_fit_points"
    );
}

#[test]
fn a_heap_that_cannot_be_measured_is_degenerate() {
    let ok = ConeOptions::new(BASE, 12, 0.02);
    let degenerate = |p: &[Vec3<f64>]| {
        matches!(
            cone_angle_by_sector(p, &ok),
            Err(MeasureError::Degenerate { .. })
        )
    };
    // Everything below the base's top (all fell off), or outside its radius.
    assert!(degenerate(&[
        Vec3::new(2.0, 0.4, 3.0),
        Vec3::new(2.1, 0.3, 3.0)
    ]));
    assert!(degenerate(&[Vec3::new(4.0, 0.9, 3.0)]));
    // A flat layer at the base's top: no height.
    let flat: Vec<_> = (0..100)
        .map(|i| Vec3::new(1.5 + 0.01 * f64::from(i), 0.5, 3.0))
        .collect();
    assert!(degenerate(&flat));
    // A few grains: fewer than half the sectors fitted.
    let few = [
        Vec3::new(2.0, 0.9, 3.0),
        Vec3::new(2.5, 0.7, 3.0),
        Vec3::new(2.6, 0.6, 3.0),
    ];
    assert!(degenerate(&few));
}

proptest! {
    /// Whatever the grains and options, a result or an error, never a panic, and a result's
    /// figures are consistent (min ≤ mean ≤ max, spread ≥ 0, at least half fitted).
    #[test]
    fn never_panics(
        pts in prop::collection::vec((-3.0f64..3.0, -1.0f64..2.0, -3.0f64..3.0), 0..300),
        sectors in 0usize..400,
        bin in -0.1f64..0.3,
        lo in -0.2f64..1.0,
        hi in 0.0f64..1.2,
    ) {
        let p: Vec<Vec3<f64>> = pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let mut o = ConeOptions::new(BASE, sectors, bin);
        o.fit_band = [lo, hi];
        if let Ok(m) = cone_angle_by_sector(&p, &o) {
            prop_assert!(m.min_deg <= m.mean_deg + 1e-9 && m.mean_deg <= m.max_deg + 1e-9);
            prop_assert!(m.std_deg >= 0.0);
            prop_assert!(2 * m.fitted >= o.sectors);
        }
    }
}
