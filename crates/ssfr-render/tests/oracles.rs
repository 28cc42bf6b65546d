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

/// One sphere a pixel's ray meets or grazes, analysed in f64: the entry depth, the f32 error
/// bounds of the depth and of the chord, and whether the hit survives f32 rounding.
struct RayHit {
    depth_m: f64,
    depth_err_m: f64,
    chord_err_m: f64,
    certain: bool,
}

/// The spheres pixel `k`'s ray may hit in f32. Per sphere `Δ = (d·c)² − |d|²(|c|² − r²)`,
/// the entry depth is `(d·c − √Δ)/|d|²` and the chord `2√Δ/|d|`. Rounding the terms in f32
/// (`d·c` and `|c|² − r²` included) errs by `δ ≤ 8 ε ((d·c)² + |d|²|c|²)`, and
/// `|√Δ₁ − √Δ₂| ≤ min(√δ, δ/√Δ)`: the depth is off by at most `min(√δ, δ/√Δ)/|d|²` and the
/// chord by `2 min(√δ, δ/√Δ)/|d|`. A sphere with `|Δ| < δ` may be hit in one precision and
/// missed in the other (a grazing ray); one with `Δ ≥ δ` is hit in both. `ulps` is the 8
/// of that bound (the ellipsoid path, which transforms the ray first, takes 16).
fn ray_hits(
    cam: &ssfr_render::CameraFrame,
    centres: &[V3],
    radius: f32,
    k: usize,
    ulps: f64,
) -> Vec<RayHit> {
    let (i, j) = (k % cam.width, k / cam.width);
    let d = cam.ray(i as f32 + 0.5, j as f32 + 0.5).cast::<f64>();
    let r = radius as f64;
    let mut hits = Vec::new();
    for p in centres {
        let c = cam.to_view(p).cast::<f64>();
        if c.z - r <= 1e-3 {
            continue; // in front of the near plane: drawn by neither
        }
        let (dc, dd) = (d.dot(&c), d.norm_squared());
        let disc = dc * dc - dd * (c.norm_squared() - r * r);
        let delta = ulps * f32::EPSILON as f64 * (dc * dc + dd * c.norm_squared());
        if disc > -delta {
            let root_err = delta.sqrt().min(delta / disc.max(0.0).sqrt());
            hits.push(RayHit {
                depth_m: (dc - disc.max(0.0).sqrt()) / dd,
                depth_err_m: root_err / dd,
                chord_err_m: 2.0 * root_err / dd.sqrt(),
                certain: disc >= delta,
            });
        }
    }
    hits
}

/// Checks one pixel of the fast splatting (`depth`, `thick`, f32) against the naive f64
/// oracle (`depth_ref`, `thick_ref`) within the bounds of [`ray_hits`]; 2e-5 relative on the
/// depth and 1e-5 on the thickness for the remaining f32 steps (the camera transform, the
/// summation order over spheres).
fn check_pixel(
    hits: &[RayHit],
    depth: f32,
    thick: f32,
    depth_ref: f32,
    thick_ref: f32,
) -> Result<(), String> {
    let certain_front = hits
        .iter()
        .filter(|h| h.certain)
        .map(|h| h.depth_m)
        .fold(f64::INFINITY, f64::min);
    if !depth.is_finite() {
        if certain_front.is_finite() {
            return Err(format!("missed a certain hit at depth {certain_front}"));
        }
    } else {
        let tol = |h: &RayHit| h.depth_err_m + 2e-5 * h.depth_m;
        let of_a_sphere = hits
            .iter()
            .any(|h| (depth as f64 - h.depth_m).abs() <= tol(h));
        let nearest_ok = hits
            .iter()
            .filter(|h| h.certain)
            .all(|h| depth as f64 <= h.depth_m + tol(h));
        if !of_a_sphere || !nearest_ok {
            return Err(format!(
                "depth {depth} vs {depth_ref}: not the nearest sphere's entry"
            ));
        }
    }
    let tol = hits.iter().map(|h| h.chord_err_m).sum::<f64>() + 1e-5 * thick_ref as f64;
    if (thick as f64 - thick_ref as f64).abs() > tol {
        return Err(format!("thickness {thick} vs {thick_ref} (bound {tol})"));
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

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
            let hits = ray_hits(&cam, &centres, radius, k, 8.0);
            if let Err(e) = check_pixel(&hits, out.depth[k], out.thickness[k], depth[k], thick[k]) {
                prop_assert!(false, "pixel {k}: {e}");
            }
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
    #![proptest_config(ProptestConfig::with_cases(32))]

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
            let hits = ray_hits(&cam, &positions, radius, k, 16.0);
            if let Err(e) = check_pixel(&hits, b.depth[k], b.thickness[k], a.depth[k], a.thickness[k]) {
                prop_assert!(false, "pixel {k}: ellipsoid path {e}");
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
