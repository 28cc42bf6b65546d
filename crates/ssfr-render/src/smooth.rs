//! Step 3–4 of the paper: smoothing of the depth buffer, blurring of the thickness, and the
//! optional blurred surface noise.
//!
//! * [`bilateral_depth`]: the paper's two-pass (separable) bilateral filter. The spatial
//!   kernel is a Gaussian whose radius is given **in metres** (`radius_m`) and converted to
//!   pixels at each pixel's own depth, `R_px = radius_m f / z` (clamped to
//!   `max_radius_px`), with `σ_s = R_px / 2`; the range kernel is a Gaussian in the depth
//!   difference with `σ_z = depth_falloff_m` (van der Laan et al. 2009, §3.2). Pixels without
//!   liquid are neither changed nor used. Separating the bilateral filter is an approximation
//!   (it is not separable); the paper does it for speed, and so do we.
//!   Cost: `2 Σ_p (2 R_px(p) + 1)` taps over the liquid pixels `p`.
//! * [`curvature_flow`]: screen-space curvature flow (van der Laan, Green & Sainz 2009,
//!   §3.2, eqs. 5–9): the depth moves by the mean curvature of the surface it describes,
//!   `∂z/∂t = H`, `2H = ∇·n`. The normal is computed from world-scaled depth gradients
//!   `g = (∂z/∂x, ∂z/∂y)` (forward differences, pixel width `z/f`), `n_xy = g/√(1 + |g|²)`,
//!   and its divergence by backward differences, so that for small slopes one step is
//!   `z ← z + (λ/2) Δ_px z` with the 5-point Laplacian: explicit and stable for
//!   `λ ≤ 1/2` (we use `λ =` [`CURVATURE_FLOW_STEP`]). Where a neighbour is missing or
//!   farther than `depth_falloff_m` in depth, the difference is taken one-sided, or zero
//!   (no flux through silhouettes: the flow does not shrink the liquid's outline).
//!   Cost: `iterations × 2 × pixels`.
//! * [`gaussian_blur`]: a separable Gaussian of fixed pixel radius, for the thickness and the
//!   noise.
//! * [`add_surface_noise`]: white noise (a hash of pixel and seed) blurred by a Gaussian and
//!   added to the liquid's depth, in metres (the paper's step 4; it then bumps the normals,
//!   step 6).

use rayon::prelude::*;

/// Step `λ` of the curvature flow (stable for `λ ≤ 1/2`, see the module docs).
pub const CURVATURE_FLOW_STEP: f32 = 0.4;

/// Parameters of the bilateral filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BilateralParams {
    /// Filter radius in world units (m): `2σ_s` of the spatial Gaussian at each pixel's depth.
    pub radius_m: f32,
    /// Largest radius in pixels (bounds the cost for liquid close to the camera).
    pub max_radius_px: usize,
    /// `σ_z` of the range Gaussian (m).
    pub depth_falloff_m: f32,
}

/// The index of the pixel `k` steps from `(i, j)` along `x` (`horizontal`) or `y`, if it is
/// inside the image.
#[inline]
fn tap(i: usize, j: usize, k: isize, w: usize, h: usize, horizontal: bool) -> Option<usize> {
    let (ii, jj) = if horizontal {
        (i as isize + k, j as isize)
    } else {
        (i as isize, j as isize + k)
    };
    (ii >= 0 && jj >= 0 && ii < w as isize && jj < h as isize)
        .then(|| jj as usize * w + ii as usize)
}

/// One separable pass of the bilateral filter along `x` (`horizontal`) or `y`: per liquid
/// pixel, the taps inside the image (range clamped once) weighted by
/// `exp(−k²/(2σ_s²) − Δz²/(2σ_z²))`.
fn bilateral_pass(
    src: &[f32],
    dst: &mut [f32],
    w: usize,
    h: usize,
    focal_px: f32,
    p: &BilateralParams,
    horizontal: bool,
) {
    let inv_2sz2 = 1.0 / (2.0 * p.depth_falloff_m * p.depth_falloff_m);
    // Tap k of pixel q is q + k · stride; n pixels along the pass.
    let (stride, n) = if horizontal { (1, w) } else { (w, h) };
    dst.par_chunks_mut(w).enumerate().for_each(|(j, row)| {
        for (i, out) in row.iter_mut().enumerate() {
            let q = j * w + i;
            let z = src[q];
            if !z.is_finite() {
                *out = z;
                continue;
            }
            let r = (p.radius_m * focal_px / z).min(p.max_radius_px as f32);
            if r < 1.0 {
                *out = z;
                continue;
            }
            let sigma = 0.5 * r;
            let inv_2ss2 = 1.0 / (2.0 * sigma * sigma);
            let ri = r as usize;
            let pos = if horizontal { i } else { j };
            let (k0, k1) = (pos.min(ri), (n - 1 - pos).min(ri));
            let (mut sum, mut wsum) = (0.0f32, 0.0f32);
            let base = q - k0 * stride;
            for (t, zq) in src[base..=q + k1 * stride]
                .iter()
                .step_by(stride)
                .enumerate()
            {
                if !zq.is_finite() {
                    continue;
                }
                let k = t as f32 - k0 as f32;
                let dz = zq - z;
                let wt = (-(k * k) * inv_2ss2 - dz * dz * inv_2sz2).exp();
                sum += wt * zq;
                wsum += wt;
            }
            *out = sum / wsum;
        }
    });
}

/// The paper's two-pass bilateral filter of `depth` (in place, `scratch` as the
/// intermediate); see the module docs.
pub fn bilateral_depth(
    depth: &mut [f32],
    scratch: &mut Vec<f32>,
    w: usize,
    h: usize,
    focal_px: f32,
    params: &BilateralParams,
) {
    scratch.clear();
    scratch.resize(depth.len(), 0.0);
    bilateral_pass(depth, scratch, w, h, focal_px, params, true);
    bilateral_pass(scratch, depth, w, h, focal_px, params, false);
}

/// The naive oracle of one bilateral pass (sequential, f64): tests only.
pub fn bilateral_pass_naive(
    src: &[f32],
    w: usize,
    h: usize,
    focal_px: f32,
    p: &BilateralParams,
    horizontal: bool,
) -> Vec<f32> {
    let mut out = src.to_vec();
    for j in 0..h {
        for i in 0..w {
            let z = src[j * w + i] as f64;
            if !z.is_finite() {
                continue;
            }
            let r = (p.radius_m * focal_px / z as f32).min(p.max_radius_px as f32);
            if r < 1.0 {
                continue;
            }
            let sigma = 0.5 * r as f64;
            let (mut s, mut ws) = (0.0f64, 0.0f64);
            for k in -(r as isize)..=(r as isize) {
                let Some(q) = tap(i, j, k, w, h, horizontal) else {
                    continue;
                };
                let zq = src[q] as f64;
                if !zq.is_finite() {
                    continue;
                }
                let sz = p.depth_falloff_m as f64;
                let wt = (-((k * k) as f64) / (2.0 * sigma * sigma)
                    - (zq - z) * (zq - z) / (2.0 * sz * sz))
                    .exp();
                s += wt * zq;
                ws += wt;
            }
            out[j * w + i] = (s / ws) as f32;
        }
    }
    out
}

/// `iterations` steps of screen-space curvature flow on `depth` (in place); see the module
/// docs. `scratch` holds the normals, `previous` the depth of the previous step.
#[allow(clippy::too_many_arguments)]
pub fn curvature_flow(
    depth: &mut [f32],
    scratch: &mut Vec<[f32; 2]>,
    previous: &mut Vec<f32>,
    w: usize,
    h: usize,
    focal_px: f32,
    depth_falloff_m: f32,
    iterations: usize,
) {
    scratch.clear();
    scratch.resize(depth.len(), [0.0; 2]);
    let ok = |z0: f32, z1: f32| z1.is_finite() && (z1 - z0).abs() <= depth_falloff_m;
    for _ in 0..iterations {
        // Normals (x, y components) from forward differences, one-sided at edges.
        {
            let depth: &[f32] = depth;
            scratch.par_chunks_mut(w).enumerate().for_each(|(j, row)| {
                for (i, n) in row.iter_mut().enumerate() {
                    let z = depth[j * w + i];
                    if !z.is_finite() {
                        *n = [0.0; 2];
                        continue;
                    }
                    let diff = |fwd: Option<f32>, bwd: Option<f32>| match (fwd, bwd) {
                        (Some(f), _) if ok(z, f) => f - z,
                        (_, Some(b)) if ok(z, b) => z - b,
                        _ => 0.0,
                    };
                    let right = (i + 1 < w).then(|| depth[j * w + i + 1]);
                    let left = (i > 0).then(|| depth[j * w + i - 1]);
                    let down = (j + 1 < h).then(|| depth[(j + 1) * w + i]);
                    let up = (j > 0).then(|| depth[(j - 1) * w + i]);
                    let scale = focal_px / z;
                    let gx = diff(right, left) * scale;
                    // y up = rows up: the world y-derivative is minus the row derivative.
                    let gy = -diff(down, up) * scale;
                    let inv = 1.0 / (1.0 + gx * gx + gy * gy).sqrt();
                    *n = [gx * inv, gy * inv];
                }
            });
        }
        let normals: &[[f32; 2]] = scratch;
        // z += λ (z/f)² H, H = ½ ∇·n with backward differences (zero flux at edges).
        previous.clear();
        previous.extend_from_slice(depth);
        let snapshot: &[f32] = previous;
        depth.par_chunks_mut(w).enumerate().for_each(|(j, row)| {
            for (i, z) in row.iter_mut().enumerate() {
                let z0 = snapshot[j * w + i];
                if !z0.is_finite() {
                    continue;
                }
                let n = normals[j * w + i];
                let nl = if i > 0 && ok(z0, snapshot[j * w + i - 1]) {
                    normals[j * w + i - 1][0]
                } else {
                    n[0]
                };
                let nu = if j > 0 && ok(z0, snapshot[(j - 1) * w + i]) {
                    normals[(j - 1) * w + i][1]
                } else {
                    n[1]
                };
                // ∂n_x/∂x ∝ n_x(i) − n_x(i−1); ∂n_y/∂y = −∂n_y/∂v ∝ n_y(j−1) − n_y(j): the
                // backward differences pair with the forward ones above.
                let div_px = (n[0] - nl) + (nu - n[1]);
                let pixel = z0 / focal_px;
                // (z/f)² · ½ · (f/z) div_px
                *z = z0 + CURVATURE_FLOW_STEP * 0.5 * pixel * div_px;
            }
        });
    }
}

/// Separable Gaussian blur of `data` with `σ = radius_px / 2`, truncated at `radius_px`
/// (in place; `scratch` is the intermediate). Out-of-image taps are dropped (renormalised).
/// Only the rectangle of non-zero values grown by the radius is processed (outside it the
/// blur of zeros is zero): for the thickness, the cost follows the liquid's screen box.
/// The radius is capped at 64 pixels.
pub fn gaussian_blur(
    data: &mut [f32],
    scratch: &mut Vec<f32>,
    w: usize,
    h: usize,
    radius_px: usize,
) {
    if radius_px == 0 {
        return;
    }
    // The box of non-zero values.
    let (mut i0, mut i1, mut j0, mut j1) = (w, 0, h, 0);
    for (j, row) in data.chunks(w).enumerate() {
        if let Some(a) = row.iter().position(|&x| x != 0.0) {
            let b = row.iter().rposition(|&x| x != 0.0).unwrap_or(a);
            i0 = i0.min(a);
            i1 = i1.max(b + 1);
            j0 = j0.min(j);
            j1 = j1.max(j + 1);
        }
    }
    if i0 >= i1 {
        return;
    }
    let (i0, i1) = (i0.saturating_sub(radius_px), (i1 + radius_px).min(w));
    let (j0, j1) = (j0.saturating_sub(radius_px), (j1 + radius_px).min(h));
    let sigma = 0.5 * radius_px as f32;
    let mut weights = [0.0f32; 65];
    let radius_px = radius_px.min(64);
    for (k, wk) in weights.iter_mut().enumerate().take(radius_px + 1) {
        *wk = (-((k * k) as f32) / (2.0 * sigma * sigma)).exp();
    }
    scratch.clear();
    scratch.resize(data.len(), 0.0);
    let r = radius_px as isize;
    let pass = |src: &[f32], dst: &mut [f32], horizontal: bool| {
        dst[j0 * w..j1 * w]
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(jr, row)| {
                let j = j0 + jr;
                for (i, out) in row.iter_mut().enumerate().take(i1).skip(i0) {
                    let (mut s, mut ws) = (0.0, 0.0);
                    for k in -r..=r {
                        let Some(q) = tap(i, j, k, w, h, horizontal) else {
                            continue;
                        };
                        let wt = weights[k.unsigned_abs()];
                        s += wt * src[q];
                        ws += wt;
                    }
                    *out = s / ws;
                }
            });
    };
    pass(data, scratch, true);
    pass(scratch, data, false);
}

/// A hash of `(i, j, seed)` to `[-1, 1)` (SplitMix64 finaliser).
#[inline]
fn hash_noise(i: usize, j: usize, seed: u64) -> f32 {
    let mut x = (i as u64) ^ ((j as u64) << 21) ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 31;
    (x >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

/// Surface noise (the paper's step 4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseParams {
    /// Standard deviation of the white noise before the blur (m).
    pub amplitude_m: f32,
    /// Radius of the Gaussian blur (pixels).
    pub blur_px: usize,
    /// Seed (change it per frame for a moving surface).
    pub seed: u64,
}

/// Adds blurred noise to the liquid's depth (the paper's step 4); see [`NoiseParams`].
pub fn add_surface_noise(
    depth: &mut [f32],
    noise: &mut Vec<f32>,
    scratch: &mut Vec<f32>,
    w: usize,
    h: usize,
    params: &NoiseParams,
) {
    let (amplitude_m, seed) = (params.amplitude_m, params.seed);
    noise.clear();
    noise.extend((0..w * h).map(|k| hash_noise(k % w, k / w, seed) * 3f32.sqrt()));
    gaussian_blur(noise, scratch, w, h, params.blur_px);
    depth
        .par_iter_mut()
        .zip(noise.par_iter())
        .for_each(|(z, n)| {
            if z.is_finite() {
                *z += amplitude_m * n;
            }
        });
}
