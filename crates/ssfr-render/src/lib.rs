#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Screen-space fluid rendering on the CPU.
//!
//! Implements section IV ("Fluid surface rendering") of
//!
//! > Jaeyong Im and Chee-Kong Chan, *SPH neighbour searching and screen space fluid
//! > rendering for unlimited scenes*, International Journal of Modeling and Optimization
//! > 6(2), April 2016 (no DOI printed on the paper)
//!
//! after the method it builds on,
//!
//! > van der Laan, W. J., Green, S. and Sainz, M., *Screen space fluid rendering with
//! > curvature flow*, Proceedings of the 2009 Symposium on Interactive 3D Graphics and
//! > Games (I3D '09), pp. 91–98, 2009. DOI: 10.1145/1507149.1507164
//!
//! with the optional anisotropic kernels of
//!
//! > Yu, J. and Turk, G., *Reconstructing surfaces of particle-based fluids using
//! > anisotropic kernels*, ACM Transactions on Graphics 32(1), article 5, 2013.
//! > DOI: 10.1145/2421636.2421641
//!
//! # The pipeline (the paper's steps 1–8)
//!
//! 0. [`Background::render`]: the non-fluid scene (ground, tank walls, obstacles, sky) into a
//!    colour and depth [`SceneBuffer`], rendered first; refraction samples it.
//! 1. – 2. [`Splatter::splat`] ([`splat`]): each particle as a sphere (or ellipsoid) into a
//!    nearest-depth buffer and additively into a thickness buffer (exact ray–quadric
//!    intersection per pixel).
//! 3. [`smooth::bilateral_depth`]: the paper's two-pass bilateral filter with a world-space
//!    radius; or [`smooth::curvature_flow`] (van der Laan 2009); the thickness is blurred
//!    with a Gaussian.
//! 4. [`smooth::add_surface_noise`]: optional blurred noise on the surface depth.
//! 5. [`normals::normals_from_depth`]: view-space normals, the smaller one-sided
//!    difference at discontinuities.
//! 6. – 8. [`shade::shade`]: diffuse and specular light, Schlick's Fresnel, Beer–Lambert
//!    absorption from the thickness, and refraction of the scene buffer either by van der
//!    Laan's screen-space offset or by the paper's `refract(I, N, n₁/n₂)` (eq. 6)
//!    ([`Refraction`]).
//!
//! Optional: [`anisotropy::anisotropic_ellipsoids`] turns particles into ellipsoids (Yu &
//! Turk 2013) for [`ParticleView::ellipsoids`].
//!
//! [`Renderer`] owns the buffers and runs the steps, timing each ([`StageTimes`]);
//! [`RenderConfig`] reads the `[render]` table of a scene file.
//!
//! # Deviations and choices where the paper is silent
//!
//! * CPU, not GPU: every pixel of a splat intersects its own ray with the sphere exactly
//!   (a point sprite approximates the sphere by a screen-aligned hemisphere); the thickness
//!   is the exact chord length. Parallel over bands of rows (rayon), deterministic.
//! * The paper's text of step 1 is lost in the extraction ("the method in \[21\]"); we follow
//!   van der Laan 2009 §3.1 (spheres into the depth buffer).
//! * The bilateral filter's radius is in metres (converted per pixel by its depth), its range
//!   kernel a Gaussian of `σ_z` metres; both are parameters ([`BilateralParams`]).
//! * The paper's improved refraction does not say how far the refracted ray is followed; the
//!   default marches it against the scene depth (its Fig. 7, "with better scene depth"),
//!   [`RefractDistance::Thickness`] follows it over the thickness.
//! * The thickness sums sphere chords; [`Material::thickness_scale`] converts it to a path
//!   length (`6/π` for a cubic lattice of spacing `2r`).
//! * The reflected colour is the background's sky (no reflection of the scene itself).
//! * Particles too close to the camera plane ([`splat::NEAR_M`]) are skipped, not clipped.
//! * Per-particle velocity is not used (no foam or spray); per-particle radii and ellipsoids
//!   are.
//!
//! # Cost (1280 × 720 = 0.92 M pixels)
//!
//! Pixels touched per stage, for `N` particles of radius `r` at depth `z` seen with focal
//! length `f` pixels, `P` liquid pixels:
//!
//! * Background: one ray per pixel (0.92 M), once per camera (with one pass to build the
//!   refraction's depth pyramid, [`DepthTiles`]).
//! * Splatting: `Σ_i (box of particle i in pixels)`, about `N (2 f r/z)²` pixel tests
//!   ([`FrameStats::splat_pixel_tests`] counts them), each a square root and, where the ray
//!   hits, two divisions; the per-pixel ray terms are tabulated once per camera; particle
//!   set-up and binning `O(N)` (36 bytes per sphere).
//! * Bilateral filter: `2 Σ_p (2 R_px(p) + 1)` taps over the liquid pixels, one `exp` each
//!   (`R_px = radius_m f / z`, clamped to `max_radius_px`), plus two passes over the image.
//! * Curvature flow: `2 × iterations` passes over the pixels.
//! * Thickness blur: `2 (2 R + 1)` taps per pixel of the liquid's screen box grown by `R`.
//! * Normals: one pass over the pixels.
//! * Shading: one pass over the pixels (12 bytes of colour read and written, 8 of sample
//!   coordinates written per pixel) and, per liquid pixel, a few `exp`/`powf` and the
//!   scene-depth refraction's walk of the depth pyramid ([`march`]): the coarse cells of
//!   the refracted ray's screen path plus about `2 × 4` cells per level where it comes near
//!   the scene, instead of one projected sample per 4 pixels of the path.
//!
//! For the benchmark frame (`benches/benches/ssfr.rs` and the `ssfr-performance`
//! experiment: 98,304 particles filling the dam break's 0.4 × 0.8 × 0.6 m column, spacing
//! 12.4 mm, spheres of 9.3 mm, default camera about 2.6 m away, 1280 × 720) this is
//! 6.76 M splat pixel tests (counted), `P` = 75 k liquid pixels, a bilateral radius of about
//! 11 pixels (3 r f / z with f = 989 px, z ≈ 2.6 m) so about 3.5 M filter taps and
//! `exp`s, about 0.6 M pyramid cells for the 75 k refracted rays (counted, 8 per ray),
//! 0.92 M pixels per full-image pass (about 20 MB of memory traffic in the shading), and
//! 0.92 M background rays once per camera. The bound is arithmetic, not memory: the
//! splatting's square roots and divisions and the filter's exponentials (about 10 M
//! transcendental operations per frame) dominate, followed by the shading's per-pixel
//! lighting and walk.

pub mod anisotropy;
mod background;
mod camera;
pub mod config;
mod error;
mod image;
pub mod march;
pub mod normals;
mod render;
pub mod shade;
pub mod smooth;
pub mod splat;

pub use background::{ray_box, Background, Ground, Light, Obstacle, SceneBuffer, TankWalls};
pub use camera::{Camera, CameraFrame};
pub use config::{RenderConfig, SceneInfo};
pub use error::SsfrError;
pub use image::{image_difference, RgbImage};
pub use march::DepthTiles;
pub use render::{FrameStats, RenderParams, Renderer, Smoothing, StageTimes};
pub use shade::{Material, RefractDistance, Refraction};
pub use smooth::{BilateralParams, NoiseParams};
pub use sph_core::Vec3;
pub use splat::{ParticleView, SplatBuffers, Splatter};

/// Default sphere radius over the particle spacing `s`: 0.75. Spheres of radius `s/2` on a
/// cubic lattice only touch, and a camera sees through the gaps between them into deeper
/// layers (depth jumps of several radii); from `s/√2 ≈ 0.71 s` on, the gaps of a lattice
/// face are closed. At `0.75 s` the splats of a lattice face whose outer particles lie half a
/// spacing inside the liquid's surface reach `0.25 s` beyond it at the sphere tops and stay
/// `0.25 s` short of it in the middle of a lattice square, so the surface they make lies
/// around the true one (measured by the `ssfr-depth-accuracy` experiment).
pub const RADIUS_OVER_SPACING: f32 = 0.75;

/// Largest image accepted (64 M pixels).
pub const MAX_PIXELS: usize = 1 << 26;

/// Bytes per pixel of a [`Renderer`]'s buffers and its image, all at their largest: depth
/// and thickness, the camera's ray tables (`|d|²`, `|d|`), the raw depth, the normals, the
/// scene buffer (colour, depth) and its depth pyramid (`1/z` over squares of 1, 4, 16, ...
/// pixels: under 4·4/3 bytes, counted as 6), the colour, the refraction's sample
/// coordinates, the smoothing and noise scratch buffers, and the 8-bit RGB image.
pub const BYTES_PER_PIXEL: usize = {
    use std::mem::size_of;
    let f = size_of::<f32>();
    2 * f // splat depth, thickness
        + 2 * f // ray tables
        + f // raw depth
        + size_of::<[f32; 3]>() // normals
        + size_of::<[f32; 3]>() + f // scene colour, depth
        + 6 // scene depth pyramid
        + size_of::<[f32; 3]>() // colour
        + size_of::<[f32; 2]>() // refraction sample coordinates
        + 2 * f + size_of::<[f32; 2]>() // scratch buffers
        + 3 // the RGB image
};

/// Bytes a [`Renderer`]'s buffers take for an image of `width × height` pixels.
pub fn frame_bytes(width: usize, height: usize) -> u64 {
    (width as u64)
        .saturating_mul(height as u64)
        .saturating_mul(BYTES_PER_PIXEL as u64)
}

/// `Ok` when the buffers of a `width × height` image ([`frame_bytes`]) fit in
/// `available_bytes` (the memory the process may still allocate; `None`: unknown, not
/// checked), else [`SsfrError::OutOfMemory`] with both sizes. [`Renderer::render`] checks
/// [`sph_core::memory::available_bytes`] this way before its buffers grow.
pub fn check_frame_memory(
    width: usize,
    height: usize,
    available_bytes: Option<u64>,
) -> Result<(), SsfrError> {
    let needed_bytes = frame_bytes(width, height);
    match available_bytes {
        Some(available_bytes) if needed_bytes > available_bytes => Err(SsfrError::OutOfMemory {
            width,
            height,
            needed_bytes,
            bytes_per_pixel: BYTES_PER_PIXEL,
            available_bytes,
        }),
        _ => Ok(()),
    }
}

/// 3-vector of `f32` (the renderer works in single precision).
pub type V3 = nalgebra::Vector3<f32>;

/// `Ok` for `1 ≤ width · height ≤ MAX_PIXELS`.
pub fn check_image_size(width: usize, height: usize) -> Result<(), SsfrError> {
    if width == 0 || height == 0 {
        return Err(SsfrError::ImageSize {
            width,
            height,
            reason: "zero-size image",
        });
    }
    if width.saturating_mul(height) > MAX_PIXELS {
        return Err(SsfrError::ImageSize {
            width,
            height,
            reason: "more than 2^26 pixels",
        });
    }
    Ok(())
}
