//! The screen-space renderer per stage at 1280 × 720: 100k particles filling the dam break's
//! water column (0.4 × 0.8 × 0.6 m, spacing 12.4 mm, spheres of 0.75 × spacing) in the
//! 1.6 × 1.0 × 0.6 m tank, seen from the front and above by a camera framing the tank
//! (`cargo bench -p benches --bench ssfr`). Each stage runs on the buffers a full frame
//! left. The cost model of each stage (pixels touched) is in the `ssfr-render` crate
//! documentation, section "Cost".
use criterion::{criterion_group, criterion_main, Criterion};
use sph_core::{sampling::cubic_lattice, Aabb, Vec3};
use ssfr_render::config::SceneInfo;
use ssfr_render::normals::normals_from_depth;
use ssfr_render::shade::{shade, ShadeInputs};
use ssfr_render::smooth::{bilateral_depth, curvature_flow, gaussian_blur};
use ssfr_render::{
    ParticleView, RefractDistance, Refraction, RenderConfig, RenderParams, Renderer, SceneBuffer,
    Smoothing, SplatBuffers, Splatter,
};

/// About `n` particles on a cubic lattice filling the water column; positions and spacing.
fn column(n: usize) -> (Vec<Vec3<f32>>, f32) {
    let s = (0.4f32 * 0.8 * 0.6 / n as f32).cbrt();
    let column = Aabb::new(Vec3::zeros(), Vec3::new(0.4, 0.8, 0.6)).expect("box");
    (cubic_lattice(&column, s, 4 * n).expect("lattice"), s)
}

fn params(s: f32) -> RenderParams {
    let info = SceneInfo {
        tank: Some(([0.0; 3], [1.6, 1.0, 0.6])),
        liquid: None,
        particle_spacing: s,
        obstacles: Vec::new(),
    };
    RenderConfig::default().resolve(&info).expect("defaults")
}

fn stages(c: &mut Criterion) {
    let (positions, s) = column(100_000);
    let p = params(s);
    let r = p.particle_radius_m;
    let view = ParticleView::spheres(&positions, r);
    let mut renderer = Renderer::default();
    renderer.render(&p, &view).expect("frame");
    let cam = *renderer.camera_frame().expect("camera");
    let (w, h) = (cam.width, cam.height);
    let mut group = c.benchmark_group("ssfr-1280x720-100k");
    group.sample_size(10);

    group.bench_function("frame (bilateral, improved refraction)", |b| {
        b.iter(|| renderer.render(&p, &view).expect("frame"))
    });
    let mut scene = SceneBuffer::default();
    group.bench_function("background", |b| {
        b.iter(|| p.background.render(&cam, &p.light, &mut scene).expect("bg"))
    });
    let mut splatter = Splatter::default();
    let mut splats = SplatBuffers::default();
    group.bench_function("splat", |b| {
        b.iter(|| splatter.splat(&cam, &view, &mut splats).expect("splat"))
    });
    let raw = splats.depth.clone();
    let mut scratch = Vec::new();
    let Smoothing::Bilateral(bp) = p.smoothing else {
        unreachable!("the default smoothing is bilateral")
    };
    let mut depth = raw.clone();
    group.bench_function("bilateral", |b| {
        b.iter(|| {
            depth.copy_from_slice(&raw);
            bilateral_depth(&mut depth, &mut scratch, w, h, cam.focal_px, &bp)
        })
    });
    let (mut ns, mut prev) = (Vec::new(), Vec::new());
    group.bench_function("curvature flow (60 iterations)", |b| {
        b.iter(|| {
            depth.copy_from_slice(&raw);
            curvature_flow(
                &mut depth,
                &mut ns,
                &mut prev,
                w,
                h,
                cam.focal_px,
                2.0 * r,
                60,
            )
        })
    });
    let thick0 = splats.thickness.clone();
    let mut thick = thick0.clone();
    group.bench_function("thickness blur", |b| {
        b.iter(|| {
            thick.copy_from_slice(&thick0);
            gaussian_blur(&mut thick, &mut scratch, w, h, p.thickness_blur_px)
        })
    });
    let smoothed = renderer.splats.depth.clone();
    let mut normals = Vec::new();
    group.bench_function("normals", |b| {
        b.iter(|| normals_from_depth(&cam, &smoothed, &mut normals))
    });
    let (mut colour, mut samples) = (Vec::new(), Vec::new());
    for (name, refraction) in [
        (
            "shade (basic refraction)",
            Refraction::Basic {
                offset_px_per_m: 200.0,
            },
        ),
        (
            "shade (improved, scene depth)",
            Refraction::Improved {
                distance: RefractDistance::SceneDepth,
            },
        ),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                shade(
                    &ShadeInputs {
                        camera: &cam,
                        background: &p.background,
                        scene: &renderer.scene,
                        scene_tiles: &renderer.scene_tiles,
                        light: &p.light,
                        material: &p.material,
                        refraction: &refraction,
                        depth: &smoothed,
                        thickness: &renderer.splats.thickness,
                        normals: &renderer.normals,
                    },
                    &mut colour,
                    &mut samples,
                )
                .expect("shade")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, stages);
criterion_main!(benches);
