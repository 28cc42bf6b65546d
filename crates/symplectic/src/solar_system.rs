//! The outer Solar System of Chegodaeva's experiments: the Sun (carrying the masses of the
//! inner planets) and the four giant planets, with the constant of gravitation, in the
//! equatorial or the ecliptic frame.
//!
//! Initial conditions from
//!
//! > E. Hairer, C. Lubich and G. Wanner, *Geometric Numerical Integration: Structure-Preserving
//! > Algorithms for Ordinary Differential Equations*, 2nd ed., Springer 2006, Section I.2.4
//! > ("The outer solar system"), Table 2.1. doi:10.1007/3-540-30666-8
//!
//! Epoch 1994 September 5, 0h; heliocentric positions (AU) and velocities (AU/day) in the
//! equatorial frame; masses in solar masses; `G` in AU³ M☉⁻¹ day⁻². The same table is kept as
//! reference data (`reference-data/symplectic-100myr/outer_solar_system.csv`, with its SOURCE note);
//! the crate's tests check these constants against it digit for digit.
//!
//! The ecliptic frame of J2000 (the frame of the paper's orbital elements) is reached by a
//! rotation about `x` by the obliquity [`OBLIQUITY_J2000_RAD`](crate::OBLIQUITY_J2000_RAD)
//! ([`equatorial_to_ecliptic`]).

use crate::{equatorial_to_ecliptic, Planets, SymplecticError, Vec3};

/// `G = 2.95912208286·10⁻⁴ AU³ M☉⁻¹ day⁻²` (Hairer, Lubich & Wanner 2006, Sec. I.2.4).
pub const G_AU3_PER_MSUN_DAY2: f64 = 2.959_122_082_86e-4;

/// Mass of the Sun in solar masses, including the four inner planets (same table).
pub const SUN_MASS_WITH_INNER_PLANETS: f64 = 1.000_005_976_82;

/// Frame of the returned state vectors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Frame {
    /// Earth's equator and equinox (the frame of Table 2.1).
    Equatorial,
    /// The ecliptic of J2000: Table 2.1 rotated about `x` by the J2000 obliquity.
    EclipticJ2000,
}

/// One giant planet of Table 2.1: name, mass (M☉), heliocentric position (AU) and velocity
/// (AU/day), equatorial frame, epoch 1994-09-05 0h.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GiantPlanet {
    /// Name.
    pub name: &'static str,
    /// Mass in solar masses.
    pub mass_msun: f64,
    /// Heliocentric equatorial position (AU).
    pub position_au: [f64; 3],
    /// Heliocentric equatorial velocity (AU/day).
    pub velocity_au_per_day: [f64; 3],
}

/// The astronomical unit in kilometres (IAU 2012 Resolution B2: 149 597 870.7 km).
pub const AU_KM: f64 = 149_597_870.7;

/// The nominal solar radius in km, 695 700 (IAU 2015 Resolution B3, "On recommended nominal
/// conversion constants for selected solar and planetary properties", Prša et al., AJ 152,
/// 41 (2016), doi:10.3847/0004-6256/152/2/41).
pub const SUN_NOMINAL_RADIUS_KM: f64 = 695_700.0;

/// The nominal solar radius in AU, [`SUN_NOMINAL_RADIUS_KM`] / [`AU_KM`] = 0.004 650 47 AU: a
/// particle closer than this to the Sun's centre has collided with it
/// ([`RemovalRules::sun_collision`](crate::RemovalRules::sun_collision)).
pub const SUN_RADIUS_AU: f64 = SUN_NOMINAL_RADIUS_KM / AU_KM;

/// Equatorial radii (1 bar level) of Jupiter, Saturn, Uranus and Neptune in km: 71 492,
/// 60 268, 25 559, 24 764 (B. A. Archinal et al., "Report of the IAU Working Group on
/// Cartographic Coordinates and Rotational Elements: 2015", *Celestial Mechanics and Dynamical
/// Astronomy* 130, 22 (2018), doi:10.1007/s10569-017-9805-5, Table 5). A particle closer
/// than this to a planet's centre has collided with it.
pub const GIANT_PLANET_RADII_KM: [f64; 4] = [71_492.0, 60_268.0, 25_559.0, 24_764.0];

/// Jupiter, Saturn, Uranus and Neptune as printed in Table 2.1.
pub const GIANT_PLANETS: [GiantPlanet; 4] = [
    GiantPlanet {
        name: "Jupiter",
        mass_msun: 0.000_954_786_104_043,
        position_au: [-3.502_365_3, -3.816_984_7, -1.550_796_3],
        velocity_au_per_day: [0.005_654_29, -0.004_124_90, -0.001_905_89],
    },
    GiantPlanet {
        name: "Saturn",
        mass_msun: 0.000_285_583_733_151,
        position_au: [9.075_531_4, -3.045_835_3, -1.648_370_8],
        velocity_au_per_day: [0.001_683_18, 0.004_835_25, 0.001_924_62],
    },
    GiantPlanet {
        name: "Uranus",
        mass_msun: 0.000_043_727_316_454_6,
        position_au: [8.310_142_0, -16.290_108_6, -7.252_127_8],
        velocity_au_per_day: [0.003_541_78, 0.001_371_02, 0.000_550_29],
    },
    GiantPlanet {
        name: "Neptune",
        mass_msun: 0.000_051_775_913_844_9,
        position_au: [11.470_766_6, -25.729_482_9, -10.816_945_6],
        velocity_au_per_day: [0.002_889_30, 0.001_145_27, 0.000_396_77],
    },
];

/// The Sun (with the inner planets' masses) and Jupiter, Saturn, Uranus, Neptune at the epoch
/// 1994-09-05 0h, in AU, days and solar masses with [`G_AU3_PER_MSUN_DAY2`], in `frame`:
/// the system of Chegodaeva's experiments (Hairer, Lubich & Wanner 2006, Table 2.1).
///
/// ```
/// use symplectic::{outer_solar_system, Frame, Integrator};
/// let mut planets = outer_solar_system(Frame::EclipticJ2000);
/// assert_eq!(planets.len(), 4);
/// let e0 = planets.energy();
/// Integrator::S2 { step: 365.0 }.run(&mut planets, 100)?;
/// assert!(((planets.energy() - e0) / e0).abs() < 1e-4);
/// # Ok::<(), symplectic::SymplecticError>(())
/// ```
pub fn outer_solar_system(frame: Frame) -> Planets {
    let rotate = |v: [f64; 3]| {
        let v = Vec3::from(v);
        match frame {
            Frame::Equatorial => v,
            Frame::EclipticJ2000 => equatorial_to_ecliptic(&v),
        }
    };
    let masses: Vec<f64> = GIANT_PLANETS.iter().map(|p| p.mass_msun).collect();
    let positions: Vec<Vec3> = GIANT_PLANETS
        .iter()
        .map(|p| rotate(p.position_au))
        .collect();
    let velocities: Vec<Vec3> = GIANT_PLANETS
        .iter()
        .map(|p| rotate(p.velocity_au_per_day))
        .collect();
    let built: Result<Planets, SymplecticError> = Planets::from_heliocentric(
        G_AU3_PER_MSUN_DAY2,
        SUN_MASS_WITH_INNER_PLANETS,
        &masses,
        &positions,
        &velocities,
    );
    let names: Vec<&str> = GIANT_PLANETS.iter().map(|p| p.name).collect();
    let radii = GIANT_PLANET_RADII_KM.map(|r| r / AU_KM);
    // The constants above are finite, positive and non-zero: construction cannot fail
    // (checked by the unit test below).
    built
        .and_then(|p| p.with_names_and_radii(&names, &radii))
        .expect("the tabulated outer Solar System is a valid state")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_frames_build_and_share_the_energy() {
        let eq = outer_solar_system(Frame::Equatorial);
        let ecl = outer_solar_system(Frame::EclipticJ2000);
        // A rotation changes no distance or speed: same energy to round-off.
        assert!(((eq.energy() - ecl.energy()) / eq.energy()).abs() < 1e-14);
        assert_ne!(eq.positions()[0], ecl.positions()[0]);
    }
}
