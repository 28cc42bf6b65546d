//! The fast stages against their naive oracles (proptest).

use proptest::prelude::*;
use sph_core::Vec3;
use ssfr_render::smooth::{bilateral_pass_naive, BilateralParams};
use ssfr_render::splat::splat_spheres_naive;
use ssfr_render::{Camera, ParticleView, SplatBuffers, Splatter, V3};

fn camera(w: usize, h: usize) -> ssfr_render::CameraFrame {
    Camera {
        eye: [0.2, 0.8, 1.5],
        target: [0.0, 0.1, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 50.0,
        width: w,
        height: h,
    }
    .frame()
    .unwrap()
}

/// Half chord (m) of the nearest sphere hit by pixel `k`'s ray (f64).
fn front_half_chord(cam: &ssfr_render::CameraFrame, centres: &[V3], radius: f32, k: usize) -> f32 {
    let (i, j) = (k % cam.width, k / cam.width);
    let d = cam.ray(i as f32 + 0.5, j as f32 + 0.5).cast::<f64>();
    let r = radius as f64;
    let mut best = (f64::INFINITY, 0.0);
    for p in centres {
        let c = cam.to_view(p).cast::<f64>();
        let (dc, dd) = (d.dot(&c), d.norm_squared());
        let disc = dc * dc - dd * (c.norm_squared() - r * r);
        if disc >= 0.0 && c.z - r > 1e-3 {
            let z = (dc - disc.sqrt()) / dd;
            if z < best.0 {
                best = (z, disc.sqrt() / dd.sqrt());
            }
        }
    }
    best.1 as f32
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Banded, binned, parallel splatting equals every-pixel-against-every-sphere in f64.
    #[test]
    fn splat_matches_naive(
        pts in prop::collection::vec((-0.4f32..0.4, -0.2f32..0.5, -0.4f32..0.4), 1..40),
        radius in 0.01f32..0.12,
        w in 8usize..48,
        h in 8usize..40,
    ) {
        let cam = camera(w, h);
        let positions: Vec<Vec3<f32>> = pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let centres: Vec<V3> = positions.clone();
        let mut s = Splatter::default();
        let mut out = SplatBuffers::default();
        s.splat(&cam, &ParticleView::spheres(&positions, radius), &mut out).unwrap();
        let (depth, thick) = splat_spheres_naive(&cam, &centres, radius);
        for k in 0..w * h {
            let (a, b) = (out.depth[k], depth[k]);
            // A ray grazing a sphere may hit in one precision and miss in the other.
            if a.is_finite() != b.is_finite() {
                prop_assert!(thick[k] < 1e-2 * radius || out.thickness[k] < 1e-2 * radius,
                    "pixel {k}: coverage differs beyond a grazing hit ({a} vs {b})");
                continue;
            }
            if a.is_finite() {
                // f32 rounding of Δ = (d·c)² − |d|²(|c|² − r²) (terms ≈ z²) is a few ε z²,
                // and √Δ ≈ h |d| (h = half chord of the front sphere), so the depth is off
                // by about ε z²/h: error analysis with 8 ε, plus 2e-5 relative.
                let h = front_half_chord(&cam, &centres, radius, k).max(1e-6);
                let tol = 2e-5 * b + 8.0 * f32::EPSILON * b * b / h;
                prop_assert!((a - b).abs() <= tol, "pixel {k}: depth {a} vs {b} (half chord {h})");
            }
            prop_assert!((out.thickness[k] - thick[k]).abs() <= 2e-3 * radius * positions.len() as f32 + 1e-3 * thick[k],
                "pixel {k}: thickness {} vs {}", out.thickness[k], thick[k]);
        }
    }

    /// The two-pass bilateral filter equals the naive passes (f64) applied in turn.
    #[test]
    fn bilateral_matches_naive(
        seed in 0u64..1000,
        w in 4usize..40,
        h in 4usize..30,
        radius_m in 0.001f32..0.05,
        falloff in 0.001f32..0.05,
    ) {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = || { x ^= x << 13; x ^= x >> 7; x ^= x << 17; (x >> 40) as f32 / (1u64 << 24) as f32 };
        let depth: Vec<f32> = (0..w * h)
            .map(|_| { let u = next(); if u < 0.2 { f32::INFINITY } else { 1.0 + 0.05 * next() } })
            .collect();
        let p = BilateralParams { radius_m, max_radius_px: 12, depth_falloff_m: falloff };
        let f = 100.0;
        let mut fast = depth.clone();
        let mut scratch = Vec::new();
        ssfr_render::smooth::bilateral_depth(&mut fast, &mut scratch, w, h, f, &p);
        let a = bilateral_pass_naive(&depth, w, h, f, &p, true);
        let b = bilateral_pass_naive(&a, w, h, f, &p, false);
        for k in 0..w * h {
            if b[k].is_finite() {
                prop_assert!((fast[k] - b[k]).abs() < 1e-5, "pixel {k}: {} vs {}", fast[k], b[k]);
            } else {
                prop_assert!(!fast[k].is_finite());
            }
        }
    }
}

/// Curvature flow flattens a noisy plane: the roughness drops and the mean stays.
#[test]
fn curvature_flow_smooths_a_noisy_plane() {
    let (w, h) = (64, 48);
    let mut x = 12345u64;
    let mut depth: Vec<f32> = (0..w * h)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            2.0 + 0.004 * ((x >> 40) as f32 / (1u64 << 24) as f32 - 0.5)
        })
        .collect();
    let rough = |d: &[f32]| {
        let m = d.iter().sum::<f32>() / d.len() as f32;
        (d.iter().map(|z| (z - m).powi(2)).sum::<f32>() / d.len() as f32).sqrt()
    };
    let (r0, m0) = (
        rough(&depth),
        depth.iter().sum::<f32>() / depth.len() as f32,
    );
    let (mut n, mut prev) = (Vec::new(), Vec::new());
    ssfr_render::smooth::curvature_flow(&mut depth, &mut n, &mut prev, w, h, 500.0, 0.01, 40);
    let (r1, m1) = (
        rough(&depth),
        depth.iter().sum::<f32>() / depth.len() as f32,
    );
    assert!(r1 < 0.2 * r0, "roughness {r0} -> {r1}");
    assert!((m1 - m0).abs() < 1e-4, "mean {m0} -> {m1}");
}

/// Named errors: NaN positions, zero radius, a camera looking away.
#[test]
fn bad_input_is_named() {
    let cam = Camera {
        eye: [0.0, 0.0, 1.0],
        target: [0.0, 0.0, 2.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 40.0,
        width: 16,
        height: 16,
    };
    let params =
        ssfr_render::RenderParams::new(cam, ssfr_render::Background::ground_only(-1.0, 0.1), 0.01);
    let mut r = ssfr_render::Renderer::default();
    let behind = [Vec3::new(0.0f32, 0.0, 0.0)];
    let e = r
        .render(&params, &ParticleView::spheres(&behind, 0.01))
        .unwrap_err();
    assert!(
        matches!(e, ssfr_render::SsfrError::NothingVisible { .. }),
        "{e}"
    );
    let nan = [Vec3::new(0.0f32, f32::NAN, 3.0)];
    let e = r
        .render(&params, &ParticleView::spheres(&nan, 0.01))
        .unwrap_err();
    assert!(e.to_string().contains("particle 0"), "{e}");
    let ok = [Vec3::new(0.0f32, 0.0, 3.0)];
    let e = r
        .render(&params, &ParticleView::spheres(&ok, 0.0))
        .unwrap_err();
    assert!(e.to_string().contains("particle_radius"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The box-restricted separable Gaussian equals the full-image one computed naively.
    #[test]
    fn gaussian_blur_matches_naive(
        spots in prop::collection::vec((0usize..40, 0usize..30, 0.0f32..1.0), 0..6),
        radius in 0usize..6,
    ) {
        let (w, h) = (40, 30);
        let mut data = vec![0.0f32; w * h];
        for &(i, j, v) in &spots {
            data[j * w + i] = v;
        }
        let mut fast = data.clone();
        let mut scratch = Vec::new();
        ssfr_render::smooth::gaussian_blur(&mut fast, &mut scratch, w, h, radius);
        let g = |k: isize| {
            let s = 0.5 * radius as f64;
            (-(k * k) as f64 / (2.0 * s * s)).exp()
        };
        let blur = |src: &[f64], horizontal: bool| -> Vec<f64> {
            let mut out = vec![0.0; w * h];
            for j in 0..h {
                for i in 0..w {
                    let (mut s, mut ws) = (0.0, 0.0);
                    for k in -(radius as isize)..=(radius as isize) {
                        let (ii, jj) = if horizontal { (i as isize + k, j as isize) } else { (i as isize, j as isize + k) };
                        if ii < 0 || jj < 0 || ii >= w as isize || jj >= h as isize { continue; }
                        s += g(k) * src[jj as usize * w + ii as usize];
                        ws += g(k);
                    }
                    out[j * w + i] = s / ws;
                }
            }
            out
        };
        let naive = if radius == 0 {
            data.iter().map(|&x| x as f64).collect()
        } else {
            let d: Vec<f64> = data.iter().map(|&x| x as f64).collect();
            blur(&blur(&d, true), false)
        };
        for k in 0..w * h {
            prop_assert!((fast[k] as f64 - naive[k]).abs() < 1e-5, "pixel {k}: {} vs {}", fast[k], naive[k]);
        }
    }
}

/// The grid-based anisotropy equals the all-pairs oracle, a flat sheet becomes flat
/// ellipsoids, and a lone particle stays a sphere.
#[test]
fn anisotropy_matches_naive_and_flattens_a_sheet() {
    use ssfr_render::anisotropy::{
        anisotropic_ellipsoids, anisotropic_ellipsoids_naive, AnisotropyParams,
    };
    let s = 0.02f32;
    let mut pts: Vec<V3> = Vec::new();
    for i in 0..20 {
        for k in 0..20 {
            pts.push(V3::new(
                i as f32 * s,
                0.5 + 0.001 * ((i * 7 + k * 3) % 5) as f32,
                k as f32 * s,
            ));
        }
    }
    pts.push(V3::new(2.0, 2.0, 2.0)); // alone
    let p = AnisotropyParams::new(0.75 * s, 4.0 * s);
    let (c, m) = anisotropic_ellipsoids(&pts, &p).unwrap();
    let (cn, mn) = anisotropic_ellipsoids_naive(&pts, &p);
    for k in 0..pts.len() {
        assert!((c[k] - cn[k]).norm() < 1e-6, "centre {k}");
        assert!((m[k] - mn[k]).norm() < 1e-5, "ellipsoid {k}");
    }
    // Interior of the sheet: the y extent is the shortest, 1/k_r of the longest.
    let mid = 10 * 20 + 10;
    let ext = |v: &nalgebra::Matrix3<f32>, a: usize| v.row(a).norm();
    assert!(ext(&m[mid], 1) < 0.5 * ext(&m[mid], 0), "{}", m[mid]);
    // Volume kept: det M = r³.
    assert!((m[mid].determinant() - (0.75 * s).powi(3)).abs() < 1e-3 * (0.75 * s).powi(3));
    let lone = pts.len() - 1;
    assert_eq!(m[lone], nalgebra::Matrix3::identity() * 0.75 * s);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// The general ellipsoid path with `M = r I` draws what the sphere path draws.
    #[test]
    fn ellipsoid_path_matches_sphere_path(
        pts in prop::collection::vec((-0.4f32..0.4, -0.2f32..0.5, -0.4f32..0.4), 1..30),
        radius in 0.02f32..0.1,
    ) {
        let cam = camera(40, 30);
        let positions: Vec<Vec3<f32>> = pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
        let m = vec![nalgebra::Matrix3::identity() * radius; positions.len()];
        let mut s = Splatter::default();
        let (mut a, mut b) = (SplatBuffers::default(), SplatBuffers::default());
        s.splat(&cam, &ParticleView::spheres(&positions, radius), &mut a).unwrap();
        let view = ParticleView { ellipsoids: Some(&m), ..ParticleView::spheres(&positions, radius) };
        s.splat(&cam, &view, &mut b).unwrap();
        for k in 0..40 * 30 {
            if a.depth[k].is_finite() != b.depth[k].is_finite() {
                // Only a grazing hit may differ between the two roundings.
                prop_assert!(a.thickness[k].max(b.thickness[k]) < 1e-2 * radius, "pixel {}", k);
                continue;
            }
            if a.depth[k].is_finite() {
                let h = front_half_chord(&cam, &positions, radius, k).max(1e-6);
                let z = a.depth[k];
                prop_assert!((a.depth[k] - b.depth[k]).abs() <= 2e-5 * z + 16.0 * f32::EPSILON * z * z / h);
            }
        }
    }
}

/// A scene with a floor, the tank's walls and two obstacles, at a small size.
fn march_scene(w: usize, h: usize) -> (ssfr_render::CameraFrame, ssfr_render::SceneBuffer) {
    use ssfr_render::{Background, Light, Obstacle, SceneBuffer, TankWalls};
    let cam = camera(w, h);
    let mut bg = Background::ground_only(-0.2, 0.1);
    bg.tank = Some(TankWalls {
        min: [-0.5, -0.2, -0.4],
        max: [0.5, 0.6, 0.3],
        colour: [0.5; 3],
        grid_m: 0.1,
    });
    bg.obstacles = vec![
        Obstacle::Sphere {
            center: [0.1, 0.0, -0.1],
            radius: 0.12,
            colour: [0.9, 0.2, 0.2],
        },
        Obstacle::Box {
            min: [-0.35, -0.2, -0.3],
            max: [-0.3, 0.3, 0.1],
            colour: [0.2, 0.9, 0.2],
        },
    ];
    let mut scene = SceneBuffer::default();
    bg.render(&cam, &Light::default(), &mut scene).unwrap();
    (cam, scene)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The tiled pixel walk of the refraction march finds the crossing the every-pixel
    /// oracle (f64) finds.
    #[test]
    fn march_matches_naive(
        w in 16usize..96,
        h in 12usize..64,
        rays in prop::collection::vec(
            (0.0f32..1.0, 0.0f32..1.0, 0.02f32..0.98, -1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
            1..24,
        ),
    ) {
        let (cam, scene) = march_scene(w, h);
        let mut tiles = ssfr_render::DepthTiles::default();
        tiles.build(&scene);
        for &(x, y, frac, rx, ry, rz) in &rays {
            let (i, j) = (((x * w as f32) as usize).min(w - 1), ((y * h as f32) as usize).min(h - 1));
            let zs = scene.depth[j * w + i];
            let z = if zs.is_finite() { frac * zs } else { 3.0 * frac };
            let p = cam.unproject_pixel(i, j, z);
            let r = V3::new(rx, ry, rz);
            prop_assume!(r.norm() > 0.1);
            let r = r.normalize();
            let fast = ssfr_render::march::march(&cam, &tiles, &p, &r);
            let naive = ssfr_render::march::march_naive(&cam, &scene, &p, &r);
            // f32 rounding of the clipped segment and of 1/z: 1e-3 pixels.
            let d = ((fast.0 - naive.0).powi(2) + (fast.1 - naive.1).powi(2)).sqrt();
            prop_assert!(d < 1e-3 * (1.0 + naive.0.abs().max(naive.1.abs()) / 64.0),
                "pixel ({i}, {j}) z {z} r {r:?}: {fast:?} vs {naive:?}");
        }
    }
}
