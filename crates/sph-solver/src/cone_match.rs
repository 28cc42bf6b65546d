//! How a Drucker–Prager cone is matched to Mohr–Coulomb: the vocabulary the granular
//! solvers share (in scene files `cone_match = "plane-strain-associated"`,
//! `"plane-strain"` or `"simple-shear"` in `[solver]`).
//!
//! A friction angle `φ` and a cohesion `c` fix Mohr–Coulomb's `|τ| ≤ c + σ_n tan φ`; a
//! Drucker–Prager cone `√J2 + α_φ I1 ≤ k_c` (Bui et al. 2008's notation, `I1` the trace of
//! the stress, tension positive) can agree with it in one state of stress only. The match
//! names that state and fixes `α_φ` and `k_c` ([`ConeMatch::alpha_phi`],
//! [`ConeMatch::k_c`]). Each solver says what the match means in its own cone: the
//! elastic–plastic solver uses `α_φ` and `k_c` as they are; the thesis's granular IISPH
//! (`‖s‖_F ≤ α p`) has `α = 3√2 α_φ` (crate `iisph-granular`, `cone_alpha`).
//!
//! | match | `α_φ` | `k_c` | repose `β` at φ = 20°, 30°, 40° |
//! |---|---|---|---|
//! | `PlaneStrainAssociated` | `tan φ/√(9 + 12 tan² φ)` | `3c/√(9 + 12 tan² φ)` | 18.5°, 25.7°, 31.1° |
//! | `PlaneStrain` | `sin φ / 3` | `c cos φ` | 18.9°, 26.6°, 32.7° |
//! | `SimpleShear` | `tan φ / 3` | `c` | 20°, 30°, 40° |
//!
//! The repose column is [`ConeMatch::predicted_repose_angle_deg`]: in a surface layer that
//! flowed and stopped the stress is close to simple shear on the planes of slip, with
//! `√J2 = |τ|` and `−I1/3 = σ_n`, so a cohesionless slope rests at `tan β = 3 α_φ`. Under
//! [`ConeMatch::SimpleShear`] the friction angle is the angle of repose.

/// Which state of stress the Drucker–Prager cone is made to agree with Mohr–Coulomb in
/// (module docs). No default: each solver names its own (`DEFAULT_CONE_MATCH` in crates
/// `elastoplastic-granular` and `iisph-granular`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum ConeMatch {
    /// Bui et al. (2008)'s match: the cone through Mohr–Coulomb in plane strain for an
    /// associated material (`ψ = φ`), the match of their column collapse.
    PlaneStrainAssociated,
    /// Plane strain at zero dilatancy: the plastic strain rate has no out-of-plane part, so
    /// `s_zz = 0`, `√J2` is the Mohr circle's radius and `−I1/3` its centre, and
    /// Mohr–Coulomb is `√J2 ≤ −(I1/3) sin φ + c cos φ` exactly (Neder 2024's eq. 14, after
    /// Alduán & Otaduy 2011).
    PlaneStrain,
    /// Simple shear on the planes of slip (the stress of a flank that flowed and stopped):
    /// `√J2 = |τ|`, `−I1/3 = σ_n`, so Coulomb's law on the slip planes is
    /// `√J2 ≤ −(I1/3) tan φ + c` (the `μ_s = tan φ` of μ(I)-type continuum codes).
    SimpleShear,
}

/// `tan a/√(9 + 12 tan² a)` for an angle `a` in degrees: the plane-strain Drucker–Prager
/// coefficient of Bui et al. (2008) ([`ConeMatch::PlaneStrainAssociated`]).
pub fn plane_strain_alpha(angle_deg: f64) -> f64 {
    let t = angle_deg.to_radians().tan();
    t / (9.0 + 12.0 * t * t).sqrt()
}

impl ConeMatch {
    /// Every match, in the order of the module docs' table.
    pub const ALL: [ConeMatch; 3] = [
        ConeMatch::PlaneStrainAssociated,
        ConeMatch::PlaneStrain,
        ConeMatch::SimpleShear,
    ];

    /// `α_φ` of the cone `√J2 + α_φ I1 ≤ k_c` for an angle `a` (degrees): that of a
    /// friction angle, or `α_ψ` of a dilatancy angle.
    pub fn alpha_phi(self, angle_deg: f64) -> f64 {
        let a = angle_deg.to_radians();
        match self {
            ConeMatch::PlaneStrainAssociated => plane_strain_alpha(angle_deg),
            ConeMatch::PlaneStrain => a.sin() / 3.0,
            ConeMatch::SimpleShear => a.tan() / 3.0,
        }
    }

    /// `k_c` (Pa) of cohesion `c` (Pa) at friction angle `φ` (degrees).
    pub fn k_c(self, cohesion: f64, friction_angle_deg: f64) -> f64 {
        let t = friction_angle_deg.to_radians().tan();
        match self {
            ConeMatch::PlaneStrainAssociated => 3.0 * cohesion / (9.0 + 12.0 * t * t).sqrt(),
            ConeMatch::PlaneStrain => cohesion * friction_angle_deg.to_radians().cos(),
            ConeMatch::SimpleShear => cohesion,
        }
    }

    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ConeMatch::PlaneStrainAssociated => "plane-strain-associated",
            ConeMatch::PlaneStrain => "plane-strain",
            ConeMatch::SimpleShear => "simple-shear",
        }
    }

    /// The slope (degrees) a cohesionless heap of zero dilatancy that formed by flowing
    /// comes to rest at: `atan(3 α_φ)` (module docs).
    pub fn predicted_repose_angle_deg(self, friction_angle_deg: f64) -> f64 {
        (3.0 * self.alpha_phi(friction_angle_deg))
            .atan()
            .to_degrees()
    }

    /// The steepest slope (degrees) a settled cohesionless wedge holds: the cone's
    /// Mohr–Coulomb angle in plane strain, `asin(3 α_φ)` (90° when `3 α_φ ≥ 1`).
    pub fn max_stable_slope_deg(self, friction_angle_deg: f64) -> f64 {
        (3.0 * self.alpha_phi(friction_angle_deg))
            .min(1.0)
            .asin()
            .to_degrees()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The repose angles of the table, from the closed forms: `atan(sin φ)` in plane
    /// strain, `φ` in simple shear, and the names read back through serde.
    #[test]
    fn the_table_and_the_names() {
        for phi in [20.0f64, 30.0, 40.0] {
            let ps = ConeMatch::PlaneStrain.predicted_repose_angle_deg(phi);
            assert!((ps - phi.to_radians().sin().atan().to_degrees()).abs() < 1e-12);
            let ss = ConeMatch::SimpleShear.predicted_repose_angle_deg(phi);
            assert!((ss - phi).abs() < 1e-12);
        }
        let psa = ConeMatch::PlaneStrainAssociated.predicted_repose_angle_deg(30.0);
        assert!((psa - 25.7).abs() < 0.05, "{psa}");
        #[derive(serde::Deserialize)]
        struct T {
            m: ConeMatch,
        }
        for m in ConeMatch::ALL {
            let t: T = toml_like(m.name());
            assert_eq!(t.m, m);
        }
        fn toml_like(name: &str) -> T {
            use serde::de::value::{Error, MapDeserializer};
            use serde::Deserialize;
            let map = MapDeserializer::<_, Error>::new(std::iter::once(("m", name)));
            T::deserialize(map).unwrap()
        }
    }
}
