//! The `[render]` table of a scene file: camera, light, background, smoothing, refraction
//! and material, every field optional, with defaults that frame the tank.
//!
//! ```toml
//! [render]
//! width = 1280                   # pixels (default 1280)
//! height = 720                   # pixels (default 720)
//! particle_radius = 0.009375     # m, sphere radius (default 0.75 x particle spacing,
//!                                # see RADIUS_OVER_SPACING)
//! thickness_blur_px = 4          # pixels (default 4)
//! background = { ground = true, tank = true, obstacles = true, checker = 0.1 }
//!
//! [render.camera]                # default: the tank (or the liquid) framed from the front
//! eye = [0.8, 1.3, 2.6]          # m
//! target = [0.8, 0.35, 0.3]      # m
//! up = [0.0, 1.0, 0.0]           # default +y
//! fov_deg = 40.0                 # vertical field of view (default 40)
//!
//! [render.light]
//! direction = [-0.4, 1.0, 0.6]   # towards the light
//! colour = [1.0, 1.0, 1.0]
//! ambient = 0.35
//!
//! [render.smoothing]
//! method = "bilateral"           # "bilateral" | "curvature-flow" | "none"
//! radius = 0.01875               # m, bilateral (default 3 particle radii)
//! max_radius_px = 24             # bilateral
//! depth_falloff = 0.0125         # m (default 2 particle radii)
//! # iterations = 60              # curvature-flow
//!
//! [render.refraction]
//! method = "improved"            # "improved" | "basic"
//! distance = "scene-depth"       # improved: "scene-depth" | "thickness"
//! # offset_px_per_m = 200.0      # basic
//!
//! [render.material]              # water by default
//! ior_liquid = 1.33
//! absorption = [4.0, 1.5, 0.7]  # 1/m per RGB channel
//!
//! [render.anisotropy]            # optional: ellipsoids (Yu & Turk 2013), all fields
//! support = 0.05                 # optional: m (default 4 spacings), lambda = 0.9,
//!                                # max_stretch = 4.0, min_neighbours = 25
//!
//! [render.noise]                 # optional surface noise
//! amplitude = 0.0005             # m
//! blur_px = 3
//! ```
//!
//! Unknown fields are refused; errors name the field path (`render.camera.eye`).

use serde::Deserialize;

use crate::background::{
    Background, Ground, Light, Obstacle, TankWalls, CHECKER_DARK, CHECKER_LIGHT,
};
use crate::camera::Camera;
use crate::render::{RenderParams, Smoothing};
use crate::shade::{Material, RefractDistance, Refraction};
use crate::smooth::{BilateralParams, NoiseParams};
use crate::SsfrError;

/// The `[render]` table.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderConfig {
    /// Image width (pixels).
    pub width: Option<usize>,
    /// Image height (pixels).
    pub height: Option<usize>,
    /// Particle radius (m).
    pub particle_radius: Option<f32>,
    /// Thickness blur (pixels).
    pub thickness_blur_px: Option<usize>,
    /// Camera.
    pub camera: Option<CameraConfig>,
    /// Light.
    pub light: Option<LightConfig>,
    /// Background.
    pub background: Option<BackgroundConfig>,
    /// Depth smoothing.
    pub smoothing: Option<SmoothingConfig>,
    /// Refraction.
    pub refraction: Option<RefractionConfig>,
    /// Material.
    pub material: Option<MaterialConfig>,
    /// Surface noise.
    pub noise: Option<NoiseConfig>,
    /// Anisotropic ellipsoids (Yu & Turk 2013) instead of spheres.
    pub anisotropy: Option<AnisotropyConfig>,
}

/// `[render.anisotropy]`: Yu & Turk's parameters (see [`crate::anisotropy`]).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnisotropyConfig {
    /// Neighbourhood radius (m, default 4 particle spacings = twice an SPH support of 2 s).
    pub support: Option<f32>,
    /// Centre smoothing λ (default 0.9).
    pub lambda: Option<f32>,
    /// Largest stretch k_r (default 4).
    pub max_stretch: Option<f32>,
    /// Fewest neighbours N_ε (default 25).
    pub min_neighbours: Option<usize>,
}

/// `[render.camera]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraConfig {
    /// Position (m).
    pub eye: Option<[f32; 3]>,
    /// Point looked at (m).
    pub target: Option<[f32; 3]>,
    /// Up direction.
    pub up: Option<[f32; 3]>,
    /// Vertical field of view (degrees).
    pub fov_deg: Option<f32>,
}

/// `[render.light]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightConfig {
    /// Direction towards the light.
    pub direction: Option<[f32; 3]>,
    /// Colour (linear RGB).
    pub colour: Option<[f32; 3]>,
    /// Ambient fraction.
    pub ambient: Option<f32>,
}

/// `render.background`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundConfig {
    /// Draw the ground plane (default true).
    pub ground: Option<bool>,
    /// Draw the tank's walls (default true).
    pub tank: Option<bool>,
    /// Draw the scene's solids (default true).
    pub obstacles: Option<bool>,
    /// Checker size (m, default 0.1).
    pub checker: Option<f32>,
}

/// `[render.smoothing]`, selected by `method`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SmoothingConfig {
    /// The paper's bilateral filter.
    Bilateral {
        /// Radius (m).
        radius: Option<f32>,
        /// Largest radius (pixels).
        max_radius_px: Option<usize>,
        /// Depth fall-off (m).
        depth_falloff: Option<f32>,
    },
    /// Curvature flow.
    CurvatureFlow {
        /// Iterations (default 60).
        iterations: Option<usize>,
        /// Depth jump treated as a silhouette (m).
        depth_falloff: Option<f32>,
    },
    /// No smoothing.
    None {},
}

/// `[render.refraction]`, selected by `method`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case", deny_unknown_fields)]
pub enum RefractionConfig {
    /// van der Laan's offset.
    Basic {
        /// Pixels per metre of thickness (default 200).
        offset_px_per_m: Option<f32>,
    },
    /// The paper's refract(I, N, n1/n2).
    Improved {
        /// `"scene-depth"` (default) or `"thickness"`.
        distance: Option<DistanceConfig>,
    },
}

/// How far the improved refraction goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DistanceConfig {
    /// March against the scene depth.
    SceneDepth,
    /// The thickness.
    Thickness,
}

/// `[render.material]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Refractive index of the liquid.
    pub ior_liquid: Option<f32>,
    /// Refractive index outside.
    pub ior_outside: Option<f32>,
    /// Absorption per channel (1/m).
    pub absorption: Option<[f32; 3]>,
    /// Path length per metre of summed chords.
    pub thickness_scale: Option<f32>,
    /// Diffuse colour.
    pub diffuse_colour: Option<[f32; 3]>,
    /// Diffuse weight.
    pub diffuse: Option<f32>,
    /// Specular strength.
    pub specular: Option<f32>,
    /// Blinn–Phong exponent.
    pub shininess: Option<f32>,
}

/// `[render.noise]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseConfig {
    /// Standard deviation before the blur (m).
    pub amplitude: f32,
    /// Blur radius (pixels, default 3).
    pub blur_px: Option<usize>,
}

/// What the scene knows and the renderer needs for its defaults: the tank, the liquid's
/// bounds, the particle spacing and the solids to draw.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneInfo {
    /// The tank box (m), if any.
    pub tank: Option<([f32; 3], [f32; 3])>,
    /// Bounds of the liquid (m), used when there is no tank.
    pub liquid: Option<([f32; 3], [f32; 3])>,
    /// Particle spacing (m).
    pub particle_spacing: f32,
    /// The solids, as background obstacles.
    pub obstacles: Vec<Obstacle>,
}

impl RenderConfig {
    /// Parses the contents of a `[render]` table given as TOML text; errors name the field
    /// path. (A `RenderConfig` is also `serde::Deserialize`, for any other format.)
    pub fn from_toml_str(text: &str) -> Result<RenderConfig, SsfrError> {
        let de = toml::de::Deserializer::parse(text).map_err(|e| SsfrError::Config {
            field: String::new(),
            reason: e.message().to_string(),
        })?;
        serde_path_to_error::deserialize(de).map_err(|e| SsfrError::Config {
            field: e.path().to_string(),
            reason: e.inner().message().to_string(),
        })
    }

    /// The render parameters for a scene, defaults filled in (see the module docs).
    pub fn resolve(&self, info: &SceneInfo) -> Result<RenderParams, SsfrError> {
        let cfg = |field: &str, reason: String| SsfrError::Config {
            field: field.into(),
            reason,
        };
        let r = self
            .particle_radius
            .unwrap_or(crate::RADIUS_OVER_SPACING * info.particle_spacing);
        if !(r.is_finite() && r > 0.0) {
            return Err(cfg(
                "particle_radius",
                format!("{r}: must be finite and > 0"),
            ));
        }
        let width = self.width.unwrap_or(1280);
        let height = self.height.unwrap_or(720);
        crate::check_image_size(width, height)?;
        let cam_cfg = self.camera.clone().unwrap_or_default();
        let fov = cam_cfg.fov_deg.unwrap_or(40.0);
        let frame_box = info.tank.or(info.liquid).unwrap_or(([0.0; 3], [1.0; 3]));
        let (lo, hi) = (crate::V3::from(frame_box.0), crate::V3::from(frame_box.1));
        let centre = (lo + hi) * 0.5;
        let radius = 0.5 * (hi - lo).norm();
        let target = cam_cfg
            .target
            .unwrap_or([centre.x, lo.y + 0.35 * (hi.y - lo.y), centre.z]);
        let eye = cam_cfg.eye.unwrap_or_else(|| {
            let half_v = 0.5 * fov.to_radians();
            let half_h = (half_v.tan() * width as f32 / height as f32).atan();
            let dist = 0.9 * radius / half_v.min(half_h).sin();
            let dir = crate::V3::new(0.0, 0.55, 1.0).normalize();
            let e = crate::V3::from(target) + dir * dist;
            [e.x, e.y, e.z]
        });
        let camera = Camera {
            eye,
            target,
            up: cam_cfg.up.unwrap_or([0.0, 1.0, 0.0]),
            fov_y_deg: fov,
            width,
            height,
        };
        camera.frame().map_err(|e| match e {
            SsfrError::Invalid { field, reason } => cfg(&field, reason),
            other => other,
        })?;
        let lc = self.light.clone().unwrap_or_default();
        let d = Light::default();
        let light = Light {
            direction: lc.direction.unwrap_or(d.direction),
            colour: lc.colour.unwrap_or(d.colour),
            ambient: lc.ambient.unwrap_or(d.ambient),
        };
        let bc = self.background.clone().unwrap_or_default();
        let checker = bc.checker.unwrap_or(0.1);
        let ground_y = lo.y;
        let background = Background {
            ground: bc.ground.unwrap_or(true).then_some(Ground {
                height_m: ground_y,
                checker_m: checker,
                colours: [CHECKER_LIGHT, CHECKER_DARK],
            }),
            tank: match (bc.tank.unwrap_or(true), info.tank) {
                (true, Some((min, max))) => Some(TankWalls {
                    min,
                    max,
                    colour: [0.75, 0.75, 0.78],
                    grid_m: checker,
                }),
                _ => None,
            },
            obstacles: if bc.obstacles.unwrap_or(true) {
                info.obstacles.clone()
            } else {
                Vec::new()
            },
            ..Background::ground_only(ground_y, checker)
        };
        background.validate().map_err(|e| match e {
            SsfrError::Invalid { field, reason } => cfg(&field, reason),
            other => other,
        })?;
        let mut params = RenderParams::new(camera, background, r);
        params.light = light;
        if let Some(b) = self.thickness_blur_px {
            params.thickness_blur_px = b;
        }
        params.smoothing = match &self.smoothing {
            None => params.smoothing,
            Some(SmoothingConfig::None {}) => Smoothing::None,
            Some(SmoothingConfig::Bilateral {
                radius,
                max_radius_px,
                depth_falloff,
            }) => Smoothing::Bilateral(BilateralParams {
                radius_m: radius.unwrap_or(3.0 * r),
                max_radius_px: max_radius_px.unwrap_or(24),
                depth_falloff_m: depth_falloff.unwrap_or(2.0 * r),
            }),
            Some(SmoothingConfig::CurvatureFlow {
                iterations,
                depth_falloff,
            }) => Smoothing::CurvatureFlow {
                iterations: iterations.unwrap_or(60),
                depth_falloff_m: depth_falloff.unwrap_or(2.0 * r),
            },
        };
        params.refraction = match &self.refraction {
            None => params.refraction,
            Some(RefractionConfig::Basic { offset_px_per_m }) => Refraction::Basic {
                offset_px_per_m: offset_px_per_m.unwrap_or(200.0),
            },
            Some(RefractionConfig::Improved { distance }) => Refraction::Improved {
                distance: match distance {
                    Some(DistanceConfig::Thickness) => RefractDistance::Thickness,
                    _ => RefractDistance::SceneDepth,
                },
            },
        };
        if let Some(m) = &self.material {
            let d = Material::default();
            params.material = Material {
                ior_outside: m.ior_outside.unwrap_or(d.ior_outside),
                ior_liquid: m.ior_liquid.unwrap_or(d.ior_liquid),
                absorption_per_m: m.absorption.unwrap_or(d.absorption_per_m),
                thickness_scale: m.thickness_scale.unwrap_or(d.thickness_scale),
                diffuse_colour: m.diffuse_colour.unwrap_or(d.diffuse_colour),
                diffuse: m.diffuse.unwrap_or(d.diffuse),
                specular: m.specular.unwrap_or(d.specular),
                shininess: m.shininess.unwrap_or(d.shininess),
            };
        }
        params.material.validate().map_err(|e| match e {
            SsfrError::Invalid { field, reason } => cfg(&field, reason),
            other => other,
        })?;
        params.anisotropy = self.anisotropy.as_ref().map(|a| {
            let d = crate::anisotropy::AnisotropyParams::new(r, 4.0 * info.particle_spacing);
            crate::anisotropy::AnisotropyParams {
                support_m: a.support.unwrap_or(d.support_m),
                lambda: a.lambda.unwrap_or(d.lambda),
                max_stretch: a.max_stretch.unwrap_or(d.max_stretch),
                min_neighbours: a.min_neighbours.unwrap_or(d.min_neighbours),
                ..d
            }
        });
        params.noise = self.noise.as_ref().map(|n| NoiseParams {
            amplitude_m: n.amplitude,
            blur_px: n.blur_px.unwrap_or(3),
            seed: 0,
        });
        Ok(params)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_and_mistyped_fields_name_their_path() {
        let e = RenderConfig::from_toml_str("[camera]\neye = [0, 1]\n").unwrap_err();
        assert!(e.to_string().contains("render.camera.eye"), "{e}");
        let e = RenderConfig::from_toml_str("[camera]\nfov = 40\n").unwrap_err();
        assert!(e.to_string().contains("fov"), "{e}");
        let e =
            RenderConfig::from_toml_str("[smoothing]\nmethod = \"bilateral\"\niterations = 3\n")
                .unwrap_err();
        assert!(e.to_string().contains("iterations"), "{e}");
        let e = RenderConfig::from_toml_str("[refraction]\nmethod = \"magic\"\n").unwrap_err();
        assert!(e.to_string().contains("refraction"), "{e}");
    }

    #[test]
    fn defaults_frame_the_tank() {
        let info = SceneInfo {
            tank: Some(([0.0; 3], [1.6, 1.0, 0.6])),
            particle_spacing: 0.025,
            ..SceneInfo::default()
        };
        let p = RenderConfig::default().resolve(&info).unwrap();
        let f = p.camera.frame().unwrap();
        for x in [0.0, 1.6] {
            for y in [0.0, 1.0] {
                for z in [0.0, 0.6] {
                    let v = f.to_view(&crate::V3::new(x, y, z));
                    let (u, w) = f.project(&v);
                    assert!(v.z > 0.0 && (0.0..1280.0).contains(&u) && (0.0..720.0).contains(&w));
                }
            }
        }
        let e = RenderConfig::from_toml_str("width = 0")
            .unwrap()
            .resolve(&info)
            .unwrap_err();
        assert!(matches!(e, SsfrError::ImageSize { .. }));
        let p = RenderConfig::from_toml_str(
            "[smoothing]\nmethod = \"curvature-flow\"\niterations = 10",
        )
        .unwrap()
        .resolve(&info)
        .unwrap();
        assert!(matches!(
            p.smoothing,
            Smoothing::CurvatureFlow { iterations: 10, .. }
        ));
    }
}
