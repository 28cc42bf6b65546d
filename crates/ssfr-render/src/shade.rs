//! Steps 6–8 of the paper: lighting, absorption and refraction, composed over the scene
//! buffer.
//!
//! For a liquid pixel at view position `P` with unit normal `N` (towards the camera),
//! `I = P/|P|` the incident direction, `V = −I`, `L` the direction to the light and
//! `t` the (blurred) thickness:
//!
//! * **Refraction** of the scene buffer, two ways ([`Refraction`]):
//!   - *basic* (van der Laan et al. 2009, §3.4; the paper's Fig. 4): the scene is sampled at
//!     the pixel offset by `N_xy · t · k` (`k` in pixels per metre), which ignores the
//!     refractive indices;
//!   - *improved* (the paper's Fig. 5 and eq. 6): `R = refract(I, N, n₁/n₂)` (Snell's law,
//!     as GLSL's `refract`; total internal reflection gives `R = 0` and the unrefracted
//!     pixel), followed from `P`. The paper does not say how far: we offer
//!     [`RefractDistance::Thickness`] (the sample is the projection of `P + R · t · s`, `s`
//!     the thickness scale below) and [`RefractDistance::SceneDepth`] (the paper's Fig. 7
//!     caption, "with better scene depth": the first crossing of the ray with the scene's
//!     depth buffer, found by walking the pixels of its screen path, see [`crate::march`]).
//!     `SceneDepth` is the default.
//! * **Absorption** (Beer–Lambert, step 7): the refracted colour is multiplied by
//!   `exp(−κ · s · t)` per channel (`κ` in 1/m). The thickness buffer sums the chords of the
//!   particles' spheres, which fill only part of the liquid (`π/6` of a cubic lattice of
//!   spacing `2r`); `s` = [`Material::thickness_scale`] (default `6/π`) turns it into the
//!   path length through the liquid.
//! * **Fresnel** (Schlick): `F = F₀ + (1 − F₀)(1 − N·V)⁵`, `F₀ = ((n₁ − n₂)/(n₁ + n₂))²`; the
//!   reflected colour is the background's sky in the reflected direction.
//! * **Diffuse and specular**: `c_d (a + (1 − a) max(N·L, 0))` weighted by
//!   [`Material::diffuse`], Blinn–Phong `(N·H)^shininess`.
//!
//! `colour = (1 − F) [(1 − d) · refracted · absorption + d · diffuse] + F · reflected +
//! specular`. Pixels without liquid show the scene buffer.

use rayon::prelude::*;

use crate::background::{Background, Light, SceneBuffer};
use crate::camera::CameraFrame;
use crate::error::{non_negative, positive};
use crate::march::{march, DepthTiles};
use crate::{SsfrError, V3};

/// How far the improved refraction follows the refracted ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefractDistance {
    /// The thickness (scaled to a path length by [`Material::thickness_scale`]).
    Thickness,
    /// Until it passes behind the scene buffer's depth (screen-space march).
    SceneDepth,
}

/// Refraction of the scene buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Refraction {
    /// van der Laan et al. (2009): offset `N_xy · thickness · offset_px_per_m` pixels.
    Basic {
        /// Pixels of offset per metre of thickness per unit of normal.
        offset_px_per_m: f32,
    },
    /// The paper's method: `refract(I, N, n₁/n₂)` (eq. 6), followed over `distance`.
    Improved {
        /// How far the refracted ray is followed.
        distance: RefractDistance,
    },
}

impl Default for Refraction {
    fn default() -> Self {
        Refraction::Improved {
            distance: RefractDistance::SceneDepth,
        }
    }
}

/// The liquid's optical parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Refractive index outside (air: 1.0).
    pub ior_outside: f32,
    /// Refractive index of the liquid (water: 1.33).
    pub ior_liquid: f32,
    /// Beer–Lambert absorption coefficient per channel (1/m).
    pub absorption_per_m: [f32; 3],
    /// Path length per metre of summed sphere chords (default `6/π`, see the module docs).
    pub thickness_scale: f32,
    /// Diffuse colour of the liquid (linear RGB).
    pub diffuse_colour: [f32; 3],
    /// Weight of the diffuse term in [0, 1] (0 = clear liquid).
    pub diffuse: f32,
    /// Specular strength (≥ 0).
    pub specular: f32,
    /// Blinn–Phong exponent (> 0).
    pub shininess: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            ior_outside: 1.0,
            ior_liquid: 1.33,
            absorption_per_m: [4.0, 1.5, 0.7],
            thickness_scale: 6.0 / std::f32::consts::PI,
            diffuse_colour: [0.15, 0.35, 0.6],
            diffuse: 0.1,
            specular: 0.6,
            shininess: 120.0,
        }
    }
}

impl Material {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), SsfrError> {
        positive("material.ior_outside", self.ior_outside)?;
        positive("material.ior_liquid", self.ior_liquid)?;
        for a in self.absorption_per_m {
            non_negative("material.absorption_per_m", a)?;
        }
        positive("material.thickness_scale", self.thickness_scale)?;
        if !(0.0..=1.0).contains(&self.diffuse) {
            return Err(SsfrError::invalid(
                "material.diffuse",
                format!("{}: must be in [0, 1]", self.diffuse),
            ));
        }
        non_negative("material.specular", self.specular)?;
        positive("material.shininess", self.shininess)
    }
}

/// GLSL's `refract(I, N, eta)` (eq. 6 of the paper): `I`, `N` unit, `N·I < 0`; zero on total
/// internal reflection.
#[inline]
pub fn refract(i: &V3, n: &V3, eta: f32) -> V3 {
    let ni = n.dot(i);
    let k = 1.0 - eta * eta * (1.0 - ni * ni);
    if k < 0.0 {
        V3::zeros()
    } else {
        i * eta - n * (eta * ni + k.sqrt())
    }
}

/// Inputs of [`shade`].
#[derive(Debug, Clone, Copy)]
pub struct ShadeInputs<'a> {
    /// The camera.
    pub camera: &'a CameraFrame,
    /// The background (for the sky reflected).
    pub background: &'a Background,
    /// The scene buffer.
    pub scene: &'a SceneBuffer,
    /// `scene`'s depth per tile ([`DepthTiles::build`]), for the scene-depth refraction.
    pub scene_tiles: &'a DepthTiles,
    /// The light.
    pub light: &'a Light,
    /// The material.
    pub material: &'a Material,
    /// The refraction method.
    pub refraction: &'a Refraction,
    /// Smoothed depth (m).
    pub depth: &'a [f32],
    /// Thickness (m of summed chords).
    pub thickness: &'a [f32],
    /// View-space normals.
    pub normals: &'a [[f32; 3]],
}

/// Shades every pixel into `colour` (linear RGB) and records in `sample_px` the pixel
/// coordinates of the scene sample the refraction used (`[NaN, NaN]` without liquid).
pub fn shade(
    inp: &ShadeInputs<'_>,
    colour: &mut Vec<[f32; 3]>,
    sample_px: &mut Vec<[f32; 2]>,
) -> Result<(), SsfrError> {
    inp.material.validate()?;
    let cam = inp.camera;
    let (w, h) = (cam.width, cam.height);
    // Every pixel is written below: no clearing pass.
    colour.resize(w * h, [0.0; 3]);
    sample_px.resize(w * h, [f32::NAN; 2]);
    let m = inp.material;
    let l = cam.dir_to_view(&inp.light.unit_direction()?);
    let lc = V3::from(inp.light.colour);
    let amb = inp.light.ambient.clamp(0.0, 1.0);
    let f0 = ((m.ior_outside - m.ior_liquid) / (m.ior_outside + m.ior_liquid)).powi(2);
    let eta = m.ior_outside / m.ior_liquid;
    let kappa = V3::from(m.absorption_per_m);
    if !inp.scene_tiles.fits(w, h) {
        return Err(SsfrError::invalid(
            "scene_tiles",
            format!("not built for the {w}x{h} scene buffer (rebuild with DepthTiles::build)"),
        ));
    }
    colour
        .par_chunks_mut(w)
        .zip(sample_px.par_chunks_mut(w))
        .enumerate()
        .for_each(|(j, (crow, srow))| {
            for i in 0..w {
                let k = j * w + i;
                let z = inp.depth[k];
                if !z.is_finite() {
                    crow[i] = inp.scene.colour[k];
                    srow[i] = [f32::NAN; 2];
                    continue;
                }
                let p = cam.unproject_pixel(i, j, z);
                let n = V3::from(inp.normals[k]);
                let inc = p.normalize();
                let v = -inc;
                let t = inp.thickness[k];
                let (u0, v0) = (i as f32 + 0.5, j as f32 + 0.5);
                let (su, sv) = match *inp.refraction {
                    Refraction::Basic { offset_px_per_m } => (
                        u0 + n.x * t * offset_px_per_m,
                        v0 - n.y * t * offset_px_per_m,
                    ),
                    Refraction::Improved { distance } => {
                        let r = refract(&inc, &n, eta);
                        if r == V3::zeros() {
                            (u0, v0)
                        } else {
                            match distance {
                                RefractDistance::Thickness => {
                                    let q = p + r * (t * m.thickness_scale);
                                    if q.z > 1e-4 {
                                        cam.project(&q)
                                    } else {
                                        (u0, v0)
                                    }
                                }
                                RefractDistance::SceneDepth => march(cam, inp.scene_tiles, &p, &r),
                            }
                        }
                    }
                };
                srow[i] = [su, sv];
                let absorb = (-kappa * (t * m.thickness_scale)).map(f32::exp);
                let refracted = inp.scene.sample(su, sv).component_mul(&absorb);
                let diffuse = V3::from(m.diffuse_colour).component_mul(&lc)
                    * (amb + (1.0 - amb) * n.dot(&l).max(0.0));
                let cos = n.dot(&v).clamp(0.0, 1.0);
                let fresnel = f0 + (1.0 - f0) * (1.0 - cos).powi(5);
                let refl_dir = inc - n * (2.0 * n.dot(&inc));
                let reflected = inp.background.sky(&cam.dir_to_world(&refl_dir));
                let half = (l + v).normalize();
                let spec = lc * (m.specular * n.dot(&half).max(0.0).powf(m.shininess));
                let c = (refracted * (1.0 - m.diffuse) + diffuse * m.diffuse) * (1.0 - fresnel)
                    + reflected * fresnel
                    + spec;
                crow[i] = [c.x, c.y, c.z];
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn refract_obeys_snell() {
        let n = V3::new(0.0, 1.0, 0.0);
        for deg in [0.0f32, 10.0, 30.0, 60.0, 85.0] {
            let a = deg.to_radians();
            let i = V3::new(a.sin(), -a.cos(), 0.0);
            let r = refract(&i, &n, 1.0 / 1.33);
            assert_relative_eq!(r.norm(), 1.0, epsilon = 1e-5);
            let sin_t = r.x;
            assert_relative_eq!(a.sin(), 1.33 * sin_t, epsilon = 1e-5);
        }
        // Total internal reflection from inside.
        let a = 60f32.to_radians();
        let i = V3::new(a.sin(), -a.cos(), 0.0);
        assert_eq!(refract(&i, &n, 1.33), V3::zeros());
    }
}
