//! The pipeline: [`RenderParams`] (a value with every parameter) and the [`Renderer`] that
//! owns the buffers and runs the steps, timing each.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use sph_core::{Real, Vec3};

use crate::background::{Background, Light, SceneBuffer};
use crate::camera::{Camera, CameraFrame};
use crate::image::RgbImage;
use crate::march::DepthTiles;
use crate::normals::normals_from_depth;
use crate::shade::{shade, Material, Refraction, ShadeInputs};
use crate::smooth::{
    add_surface_noise, bilateral_depth, curvature_flow, gaussian_blur, BilateralParams, NoiseParams,
};
use crate::splat::{ParticleView, SplatBuffers, Splatter};
use crate::SsfrError;

/// How the depth buffer is smoothed (the paper's step 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Smoothing {
    /// No smoothing (the raw splats).
    None,
    /// The paper's two-pass bilateral filter.
    Bilateral(BilateralParams),
    /// Screen-space curvature flow (van der Laan et al. 2009).
    CurvatureFlow {
        /// Iterations.
        iterations: usize,
        /// Depth jump (m) treated as a silhouette.
        depth_falloff_m: f32,
    },
}

/// Everything a frame depends on.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderParams {
    /// The camera (and image size).
    pub camera: Camera,
    /// The light.
    pub light: Light,
    /// The background scene.
    pub background: Background,
    /// Radius of the particles' spheres (m), for callers that draw spheres of one size
    /// ([`crate::ParticleView::spheres`]).
    pub particle_radius_m: f32,
    /// Depth smoothing.
    pub smoothing: Smoothing,
    /// Radius (pixels) of the Gaussian blur of the thickness (0 = none).
    pub thickness_blur_px: usize,
    /// Optional surface noise.
    pub noise: Option<NoiseParams>,
    /// The liquid's optical parameters.
    pub material: Material,
    /// The refraction method.
    pub refraction: Refraction,
    /// Anisotropic ellipsoids (Yu & Turk 2013) for callers that draw them
    /// ([`crate::anisotropy::anisotropic_ellipsoids`] then
    /// [`crate::ParticleView::ellipsoids`]); `None` = spheres.
    pub anisotropy: Option<crate::anisotropy::AnisotropyParams>,
}

impl RenderParams {
    /// Defaults for particles of radius `particle_radius_m` seen by `camera`: the bilateral
    /// filter with a radius of 3 particle radii and a depth fall-off of 2 radii, thickness
    /// blurred over 4 pixels, no noise, water, the improved refraction.
    pub fn new(camera: Camera, background: Background, particle_radius_m: f32) -> Self {
        Self {
            camera,
            light: Light::default(),
            background,
            particle_radius_m,
            smoothing: Smoothing::Bilateral(BilateralParams {
                radius_m: 3.0 * particle_radius_m,
                max_radius_px: 24,
                depth_falloff_m: 2.0 * particle_radius_m,
            }),
            thickness_blur_px: 4,
            noise: None,
            material: Material::default(),
            refraction: Refraction::default(),
            anisotropy: None,
        }
    }
}

/// Wall-clock seconds of each stage of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Background (only when camera, light or background changed).
    pub background_s: f64,
    /// Depth and thickness splatting.
    pub splat_s: f64,
    /// Depth smoothing.
    pub smooth_s: f64,
    /// Thickness blur.
    pub thickness_s: f64,
    /// Surface noise.
    pub noise_s: f64,
    /// Normals.
    pub normals_s: f64,
    /// Shading and composition.
    pub shade_s: f64,
}

impl StageTimes {
    /// Stage names and seconds, in pipeline order.
    pub fn stages(&self) -> [(&'static str, f64); 7] {
        [
            ("background", self.background_s),
            ("splat", self.splat_s),
            ("smooth", self.smooth_s),
            ("thickness", self.thickness_s),
            ("noise", self.noise_s),
            ("normals", self.normals_s),
            ("shade", self.shade_s),
        ]
    }

    /// Sum of the stages.
    pub fn total_s(&self) -> f64 {
        self.stages().iter().map(|s| s.1).sum()
    }
}

/// What one frame did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Stage times.
    pub times: StageTimes,
    /// Particles drawn (inside the view).
    pub particles_drawn: usize,
    /// Pixel tests of the splatting.
    pub splat_pixel_tests: u64,
    /// Pixels covered by liquid.
    pub liquid_pixels: usize,
}

/// The renderer: buffers kept between frames (no allocation once grown) and the steps.
///
/// ```
/// use ssfr_render::{Background, Camera, ParticleView, RenderParams, Renderer};
/// use sph_core::Vec3;
///
/// let camera = Camera { eye: [0.5, 0.6, 1.5], target: [0.5, 0.1, 0.0], up: [0.0, 1.0, 0.0],
///                       fov_y_deg: 45.0, width: 64, height: 48 };
/// let params = RenderParams::new(camera, Background::ground_only(0.0, 0.1), 0.02);
/// let positions: Vec<Vec3<f32>> =
///     (0..100).map(|k| Vec3::new(0.4 + 0.02 * (k % 10) as f32, 0.1, 0.02 * (k / 10) as f32)).collect();
/// let mut r = Renderer::default();
/// let stats = r.render(&params, &ParticleView::spheres(&positions, 0.02)).unwrap();
/// assert!(stats.liquid_pixels > 0);
/// let image = r.image();
/// assert_eq!((image.width, image.height), (64, 48));
/// ```
#[derive(Debug, Default)]
pub struct Renderer {
    splatter: Splatter,
    /// Depth (smoothed after [`Renderer::render`]) and thickness buffers.
    pub splats: SplatBuffers,
    /// The raw splatted depth of the last frame, before smoothing and noise.
    pub raw_depth: Vec<f32>,
    /// View-space normals of the last frame.
    pub normals: Vec<[f32; 3]>,
    /// The scene buffer.
    pub scene: SceneBuffer,
    /// The scene buffer's depth per tile (built with it), for the refraction march.
    pub scene_tiles: DepthTiles,
    /// Linear colour of the last frame.
    pub colour: Vec<[f32; 3]>,
    /// Pixel coordinates of the scene sample the refraction used per pixel (`NaN` without
    /// liquid).
    pub refraction_sample_px: Vec<[f32; 2]>,
    scratch: Vec<f32>,
    scratch2: Vec<f32>,
    scratch_n: Vec<[f32; 2]>,
    scene_key: Option<(Camera, Light, Background)>,
    frame: Option<CameraFrame>,
    /// The largest image (pixels) whose buffers were checked against the memory available.
    checked_pixels: usize,
}

impl Renderer {
    /// A flag that stops [`Renderer::render`] and [`Renderer::render_points`] with
    /// [`SsfrError::Cancelled`] once set (from another thread: Ctrl-C, a closed window);
    /// checked per particle in the ellipsoids' estimate, per band of rows in the splatting,
    /// and between the stages. `None` (the default) renders to the end.
    pub fn set_cancel(&mut self, cancel: Option<Arc<AtomicBool>>) {
        self.splatter.cancel = cancel;
    }

    fn check_cancelled(&self) -> Result<(), SsfrError> {
        match &self.splatter.cancel {
            Some(c) if c.load(Ordering::Relaxed) => Err(SsfrError::Cancelled),
            _ => Ok(()),
        }
    }

    /// The camera frame of the last render.
    pub fn camera_frame(&self) -> Option<&CameraFrame> {
        self.frame.as_ref()
    }

    /// Renders one frame of `particles` (steps 1–8); the background is re-rendered only when
    /// the camera, light or background changed. Errors: bad parameters or particles,
    /// [`SsfrError::OutOfMemory`] when the buffers of a larger image than before would not
    /// fit in the memory available (checked before they grow), and
    /// [`SsfrError::NothingVisible`] when no particle is in view.
    pub fn render<R: Real>(
        &mut self,
        params: &RenderParams,
        particles: &ParticleView<'_, R>,
    ) -> Result<FrameStats, SsfrError> {
        let cam = params.camera.frame()?;
        params.material.validate()?;
        let pixels = cam.width.saturating_mul(cam.height);
        if pixels > self.checked_pixels {
            crate::check_frame_memory(cam.width, cam.height, sph_core::memory::available_bytes())?;
            self.checked_pixels = pixels;
        }
        self.check_cancelled()?;
        let mut times = StageTimes::default();
        let key = (params.camera, params.light, params.background.clone());
        if self.scene_key.as_ref() != Some(&key) {
            let t = Instant::now();
            params
                .background
                .render(&cam, &params.light, &mut self.scene)?;
            self.scene_tiles.build(&self.scene);
            times.background_s = t.elapsed().as_secs_f64();
            self.scene_key = Some(key);
        }
        self.frame = Some(cam);
        let (w, h) = (cam.width, cam.height);

        let t = Instant::now();
        let drawn = self.splatter.splat(&cam, particles, &mut self.splats)?;
        times.splat_s = t.elapsed().as_secs_f64();
        if drawn == 0 {
            return Err(SsfrError::NothingVisible {
                particles: particles.positions.len(),
                eye: params.camera.eye,
                target: params.camera.target,
            });
        }
        self.raw_depth.clear();
        self.raw_depth.extend_from_slice(&self.splats.depth);

        let t = Instant::now();
        match params.smoothing {
            Smoothing::None => {}
            Smoothing::Bilateral(b) => {
                crate::error::positive("smoothing.radius_m", b.radius_m)?;
                crate::error::positive("smoothing.depth_falloff_m", b.depth_falloff_m)?;
                bilateral_depth(
                    &mut self.splats.depth,
                    &mut self.scratch,
                    w,
                    h,
                    cam.focal_px,
                    &b,
                )
            }
            Smoothing::CurvatureFlow {
                iterations,
                depth_falloff_m,
            } => {
                crate::error::positive("smoothing.depth_falloff_m", depth_falloff_m)?;
                curvature_flow(
                    &mut self.splats.depth,
                    &mut self.scratch_n,
                    &mut self.scratch,
                    w,
                    h,
                    cam.focal_px,
                    depth_falloff_m,
                    iterations,
                )
            }
        }
        times.smooth_s = t.elapsed().as_secs_f64();
        self.check_cancelled()?;

        let t = Instant::now();
        gaussian_blur(
            &mut self.splats.thickness,
            &mut self.scratch,
            w,
            h,
            params.thickness_blur_px,
        );
        times.thickness_s = t.elapsed().as_secs_f64();

        if let Some(noise) = &params.noise {
            crate::error::non_negative("noise.amplitude_m", noise.amplitude_m)?;
            let t = Instant::now();
            add_surface_noise(
                &mut self.splats.depth,
                &mut self.scratch,
                &mut self.scratch2,
                w,
                h,
                noise,
            );
            times.noise_s = t.elapsed().as_secs_f64();
        }

        let t = Instant::now();
        normals_from_depth(&cam, &self.splats.depth, &mut self.normals);
        times.normals_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        shade(
            &ShadeInputs {
                camera: &cam,
                background: &params.background,
                scene: &self.scene,
                scene_tiles: &self.scene_tiles,
                light: &params.light,
                material: &params.material,
                refraction: &params.refraction,
                depth: &self.splats.depth,
                thickness: &self.splats.thickness,
                normals: &self.normals,
            },
            &mut self.colour,
            &mut self.refraction_sample_px,
        )?;
        times.shade_s = t.elapsed().as_secs_f64();
        Ok(FrameStats {
            times,
            particles_drawn: drawn,
            splat_pixel_tests: self.splatter.pixel_tests,
            liquid_pixels: self.splats.depth.iter().filter(|z| z.is_finite()).count(),
        })
    }

    /// Renders particle centres `positions` with the radius of `params`: as spheres, or as
    /// Yu & Turk ellipsoids ([`crate::anisotropy::anisotropic_ellipsoids`]) when
    /// `params.anisotropy` asks for them. The one call a frame of a simulation needs.
    pub fn render_points<R: Real>(
        &mut self,
        params: &RenderParams,
        positions: &[Vec3<R>],
    ) -> Result<FrameStats, SsfrError> {
        let radius = params.particle_radius_m;
        match &params.anisotropy {
            None => self.render(params, &ParticleView::spheres(positions, radius)),
            Some(a) => {
                let (centres, ellipsoids) = crate::anisotropy::anisotropic_ellipsoids_cancellable(
                    positions,
                    a,
                    self.splatter.cancel.as_deref(),
                )?;
                let view = ParticleView {
                    ellipsoids: Some(&ellipsoids),
                    ..ParticleView::spheres(&centres, radius)
                };
                self.render(params, &view)
            }
        }
    }

    /// The last frame as an 8-bit sRGB image.
    pub fn image(&self) -> RgbImage {
        let (w, h) = (self.splats.width, self.splats.height);
        RgbImage::from_linear(w, h, &self.colour)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smooth::NoiseParams;

    fn params(width: usize, height: usize) -> RenderParams {
        let camera = Camera {
            eye: [0.5, 0.6, 1.5],
            target: [0.5, 0.1, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 45.0,
            width,
            height,
        };
        RenderParams::new(camera, Background::ground_only(0.0, 0.1), 0.02)
    }

    fn block() -> Vec<Vec3<f32>> {
        (0..100)
            .map(|k| Vec3::new(0.4 + 0.02 * (k % 10) as f32, 0.1, 0.02 * (k / 10) as f32))
            .collect()
    }

    /// The buffers a frame filled, measured, never exceed what the memory check counts.
    #[test]
    fn bytes_per_pixel_bound_the_buffers_a_frame_fills() {
        let (w, h) = (64, 48);
        let mut p = params(w, h);
        p.noise = Some(NoiseParams {
            amplitude_m: 1e-3,
            blur_px: 2,
            seed: 1,
        });
        let mut r = Renderer::default();
        r.render(&p, &ParticleView::spheres(&block(), 0.02))
            .unwrap();
        let image = r.image();
        fn bytes<T>(v: &[T]) -> usize {
            std::mem::size_of_val(v)
        }
        let measured = bytes(&r.splats.depth)
            + bytes(&r.splats.thickness)
            + bytes(&r.raw_depth)
            + bytes(&r.normals)
            + bytes(&r.scene.colour)
            + bytes(&r.scene.depth)
            + bytes(&r.colour)
            + bytes(&r.refraction_sample_px)
            + bytes(&r.scratch)
            + bytes(&r.scratch2)
            + bytes(&r.scratch_n)
            + image.data.len();
        assert!(measured > 0);
        assert!(
            measured as u64 <= crate::frame_bytes(w, h),
            "{measured} bytes > {} counted",
            crate::frame_bytes(w, h)
        );
    }

    #[test]
    fn a_set_cancel_flag_stops_the_render_and_a_clear_one_changes_nothing() {
        let p = params(64, 48);
        let mut plain = Renderer::default();
        plain.render_points(&p, &block()).unwrap();
        let flag = Arc::new(AtomicBool::new(false));
        let mut r = Renderer::default();
        r.set_cancel(Some(flag.clone()));
        r.render_points(&p, &block()).unwrap();
        assert_eq!(r.image().data, plain.image().data);
        flag.store(true, Ordering::Relaxed);
        assert_eq!(r.render_points(&p, &block()), Err(SsfrError::Cancelled));
        // The splatting alone (the check at the start of a frame bypassed).
        let cam = p.camera.frame().unwrap();
        let mut out = SplatBuffers::default();
        assert_eq!(
            r.splatter
                .splat(&cam, &ParticleView::spheres(&block(), 0.02), &mut out),
            Err(SsfrError::Cancelled)
        );
        // The ellipsoids' estimate alone.
        let a = crate::anisotropy::AnisotropyParams::new(0.02, 0.06);
        assert_eq!(
            crate::anisotropy::anisotropic_ellipsoids_cancellable(&block(), &a, Some(&flag))
                .map(|_| ()),
            Err(SsfrError::Cancelled)
        );
        flag.store(false, Ordering::Relaxed);
        assert_eq!(
            crate::anisotropy::anisotropic_ellipsoids_cancellable(&block(), &a, Some(&flag)),
            crate::anisotropy::anisotropic_ellipsoids(&block(), &a)
        );
    }

    #[test]
    fn an_image_larger_than_the_memory_is_refused_with_both_sizes() {
        let e = crate::check_frame_memory(8192, 8192, Some(1 << 30)).unwrap_err();
        let needed = (1u64 << 26) * crate::BYTES_PER_PIXEL as u64;
        assert_eq!(
            e,
            SsfrError::OutOfMemory {
                width: 8192,
                height: 8192,
                needed_bytes: needed,
                bytes_per_pixel: crate::BYTES_PER_PIXEL,
                available_bytes: 1 << 30,
            }
        );
        let text = e.to_string();
        assert!(
            text.contains(&needed.to_string()) && text.contains("1073741824"),
            "{text}"
        );
        assert!(crate::check_frame_memory(8192, 8192, Some(needed)).is_ok());
        assert!(crate::check_frame_memory(8192, 8192, None).is_ok());
    }
}
