//! Classes of comets from their osculating orbits: the taxonomy of
//!
//! > H. F. Levison, "Comet taxonomy", in T. W. Rettig and J. M. Hahn (eds.), *Completing the
//! > Inventory of the Solar System*, Astronomical Society of the Pacific Conference Series
//! > 107, 173–191 (1996),
//!
//! by the Tisserand parameter with respect to Jupiter ([`tisserand_jupiter`]),
//!
//! `T_J = a_J/a + 2 cos i √((a/a_J)(1 − e²))`, `i` the inclination to Jupiter's orbital plane,
//!
//! ([`LevisonClass`], [`levison_class`]): *ecliptic* comets, `T_J > 2` — Jupiter-family
//! (`2 < T_J < 3`), Encke-type (`T_J > 3`, `a < a_J`) and Chiron-type (`T_J > 3`, `a > a_J`) —
//! and *nearly isotropic* comets, `T_J < 2` — Halley-type (`a < 40 AU`) and long-period
//! (`a ≥ 40 AU`; Levison splits these further into new and returning comets at
//! `a = 10⁴ AU`, not done here). `T_J` is nearly conserved through encounters with Jupiter
//! (it is the Jacobi constant of the circular restricted problem in these units), which is
//! why it sorts comets by dynamical origin. The taxonomy is one of comets; applied here to
//! any bound orbit as its inequalities read (a trans-Neptunian orbit has `T_J > 3` and
//! `a > a_J`: Chiron-type).
//!
//! Separately, the region of the Solar System an orbit occupies by its perihelion and
//! semi-major axis ([`OrbitalRegion`], [`orbital_region`]): trans-Neptunian, between the
//! giants (this crate's "Centaur": perihelion beyond Jupiter's orbit, semi-major axis inside
//! Neptune's), or reaching inside Jupiter's orbit. These boundaries are the crate's
//! convention for following a population among the giant planets, not a published
//! taxonomy.
//!
//! `a_J`, `a_N`: the J2000 mean semi-major axes of Jupiter and Neptune (E. M. Standish,
//! "Keplerian elements for approximate positions of the major planets", JPL Solar System
//! Dynamics, Table 1, valid 1800–2050). The elements of a population are barycentric; the
//! inclination in `T_J` is taken to Jupiter's osculating heliocentric orbital plane
//! ([`jupiter_orbit_normal`]), whatever the population's frame (the ecliptic of J2000 is
//! 1.3° from it, the equator 23°).

use serde::{Deserialize, Serialize};

use crate::ephemeris::{BodyStates, Ephemeris};
use crate::kepler::Elements;
use crate::Vec3;

/// Jupiter's semi-major axis, AU (Standish, J2000 mean elements).
pub const JUPITER_SEMI_MAJOR_AXIS_AU: f64 = 5.202_887_00;

/// Neptune's semi-major axis, AU (Standish, J2000 mean elements).
pub const NEPTUNE_SEMI_MAJOR_AXIS_AU: f64 = 30.069_922_76;

/// Levison's (1996) boundary between Halley-type and long-period comets, AU (an orbital
/// period of about 250 years).
pub const HALLEY_TYPE_MAX_SEMI_MAJOR_AXIS_AU: f64 = 40.0;

/// A comet's class in Levison's (1996) taxonomy ([`levison_class`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LevisonClass {
    /// Ecliptic, `2 < T_J ≤ 3`.
    JupiterFamily,
    /// Ecliptic, `T_J > 3`, `a < a_J`.
    EnckeType,
    /// Ecliptic, `T_J > 3`, `a ≥ a_J`.
    ChironType,
    /// Nearly isotropic, `T_J ≤ 2`, `a < 40 AU`.
    HalleyType,
    /// Nearly isotropic, `T_J ≤ 2`, `a ≥ 40 AU`.
    LongPeriod,
    /// Not classified: an unbound orbit (the taxonomy is of bound ones) or no `T_J` (no
    /// planet named Jupiter, a radial orbit).
    Unclassified,
}

impl LevisonClass {
    /// The label in tables: `jupiter_family`, `encke_type`, `chiron_type`, `halley_type`,
    /// `long_period`, `unclassified`.
    pub fn label(self) -> &'static str {
        match self {
            Self::JupiterFamily => "jupiter_family",
            Self::EnckeType => "encke_type",
            Self::ChironType => "chiron_type",
            Self::HalleyType => "halley_type",
            Self::LongPeriod => "long_period",
            Self::Unclassified => "unclassified",
        }
    }

    /// Whether Levison calls the class ecliptic (`T_J > 2`).
    pub fn is_ecliptic(self) -> bool {
        matches!(
            self,
            Self::JupiterFamily | Self::EnckeType | Self::ChironType
        )
    }
}

/// The region of an orbit by perihelion and semi-major axis ([`orbital_region`]; a
/// convention of this crate, module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OrbitalRegion {
    /// Bound, `a ≥ a_N`.
    TransNeptunian,
    /// Between the giants: `q ≥ a_J`, `a < a_N`.
    Centaur,
    /// Bound, `q < a_J`, `a < a_N`: perihelion inside Jupiter's orbit.
    PerihelionInsideJupiter,
    /// Unbound (`e ≥ 1`).
    Unbound,
}

impl OrbitalRegion {
    /// The label in tables: `trans_neptunian`, `centaur`, `perihelion_inside_jupiter`,
    /// `unbound`.
    pub fn label(self) -> &'static str {
        match self {
            Self::TransNeptunian => "trans_neptunian",
            Self::Centaur => "centaur",
            Self::PerihelionInsideJupiter => "perihelion_inside_jupiter",
            Self::Unbound => "unbound",
        }
    }
}

/// Tisserand parameter with respect to Jupiter,
/// `T_J = a_J/a + 2 cos i √((a/a_J)(1 − e²))` ([`JUPITER_SEMI_MAJOR_AXIS_AU`]), for a
/// semi-major axis `a` (AU), eccentricity `e` and inclination `i` to Jupiter's orbital plane
/// (rad); `NaN` for an unbound orbit (`a ≤ 0` or `e ≥ 1`).
pub fn tisserand_jupiter(semi_major_axis: f64, eccentricity: f64, inclination: f64) -> f64 {
    let a = semi_major_axis;
    if !(a > 0.0 && eccentricity < 1.0) {
        return f64::NAN;
    }
    let a_j = JUPITER_SEMI_MAJOR_AXIS_AU;
    let e2 = eccentricity * eccentricity;
    a_j / a + 2.0 * inclination.cos() * ((a / a_j) * (1.0 - e2)).sqrt()
}

/// The unit normal of Jupiter's osculating heliocentric orbit (along `Q × V`, its
/// heliocentric position and velocity) at the newest state of `ephemeris`, or `None` if no
/// planet is named Jupiter ([`Planets::name`](crate::Planets::name)). Jupiter's orbital plane
/// moves by less than half a degree over millions of years (its inclination to the invariable
/// plane is 0.3°), so one time serves a whole table.
pub fn jupiter_orbit_normal(ephemeris: &Ephemeris) -> Option<Vec3> {
    let planets = ephemeris.planets();
    let j = (1..=planets.len()).find(|&j| planets.name(j) == "Jupiter")?;
    let mut bodies = BodyStates::default();
    ephemeris
        .interpolate(ephemeris.newest_time(), &mut bodies, false)
        .ok()?;
    let q = bodies.positions[j] - bodies.positions[0];
    let v = bodies.velocities[j] - bodies.velocities[0];
    let h = q.cross(&v);
    (h.norm() > 0.0).then(|| h / h.norm())
}

/// The inclination (rad, in `[0, π]`) of the orbit through `position` with `velocity` (any
/// common origin) to the plane of unit normal `normal`: the angle between `r × v` and
/// `normal`. `NaN` for a radial orbit.
pub fn inclination_to_plane(position: &Vec3, velocity: &Vec3, normal: &Vec3) -> f64 {
    let h = position.cross(velocity);
    let n = h.norm();
    if n == 0.0 {
        return f64::NAN;
    }
    (h.dot(normal) / n).clamp(-1.0, 1.0).acos()
}

/// Levison's class of an orbit of semi-major axis `a` (AU), eccentricity `e` and Tisserand
/// parameter `t_j` ([`tisserand_jupiter`]). On the boundaries (measure zero):
/// `T_J = 3` is Jupiter-family, `T_J = 2` nearly isotropic.
pub fn levison_class(semi_major_axis: f64, eccentricity: f64, t_j: f64) -> LevisonClass {
    let a = semi_major_axis;
    if !(a > 0.0 && eccentricity < 1.0) || t_j.is_nan() {
        return LevisonClass::Unclassified;
    }
    if t_j > 3.0 {
        if a < JUPITER_SEMI_MAJOR_AXIS_AU {
            LevisonClass::EnckeType
        } else {
            LevisonClass::ChironType
        }
    } else if t_j > 2.0 {
        LevisonClass::JupiterFamily
    } else if a < HALLEY_TYPE_MAX_SEMI_MAJOR_AXIS_AU {
        LevisonClass::HalleyType
    } else {
        LevisonClass::LongPeriod
    }
}

/// The region of an orbit (module docs): unbound; trans-Neptunian for `a ≥ a_N`; Centaur
/// for `q ≥ a_J`; perihelion inside Jupiter's orbit otherwise.
pub fn orbital_region(el: &Elements) -> OrbitalRegion {
    let a = el.semi_major_axis;
    if !(a > 0.0 && el.eccentricity < 1.0) {
        return OrbitalRegion::Unbound;
    }
    if a >= NEPTUNE_SEMI_MAJOR_AXIS_AU {
        OrbitalRegion::TransNeptunian
    } else if el.perihelion >= JUPITER_SEMI_MAJOR_AXIS_AU {
        OrbitalRegion::Centaur
    } else {
        OrbitalRegion::PerihelionInsideJupiter
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el(a: f64, e: f64, i_deg: f64) -> Elements {
        Elements {
            semi_major_axis: a,
            eccentricity: e,
            inclination: i_deg.to_radians(),
            perihelion: a * (1.0 - e),
        }
    }

    /// A body on Jupiter's own orbit, taken circular and in Jupiter's plane (`a = a_J`,
    /// `e = 0`, `i = 0`): `T_J = a_J/a_J + 2 cos 0 √(1 · 1) = 1 + 2 = 3`, exactly in `f64`
    /// (`x/x = 1`, `√1 = 1`, `cos 0 = 1` are exact); on the boundary `T_J = 3`, Jupiter-family
    /// by the stated convention. Circular coplanar orbits have `T_J = 1/x + 2√x` with
    /// `x = a/a_J`, whose minimum is 3 at `x = 1` (derivative `−1/x² + 1/√x = 0`, second
    /// derivative `3/2 > 0`): a hair inside Jupiter's orbit they are Encke-type, a hair
    /// outside Chiron-type.
    #[test]
    fn jupiters_own_orbit_has_tisserand_three() {
        let a_j = JUPITER_SEMI_MAJOR_AXIS_AU;
        assert_eq!(tisserand_jupiter(a_j, 0.0, 0.0), 3.0);
        assert_eq!(levison_class(a_j, 0.0, 3.0), LevisonClass::JupiterFamily);
        for (a, class) in [
            (0.99 * a_j, LevisonClass::EnckeType),
            (1.01 * a_j, LevisonClass::ChironType),
        ] {
            let t = tisserand_jupiter(a, 0.0, 0.0);
            assert!(t > 3.0, "a = {a}: T_J = {t}");
            assert_eq!(levison_class(a, 0.0, t), class);
        }
    }

    /// Known comets, osculating elements (ecliptic J2000) as listed by the JPL Small-Body
    /// Database (ssd.jpl.nasa.gov), rounded: 1P/Halley (a 17.834 AU, e 0.96714, i 162.26°),
    /// listed T_J −0.605, and 2P/Encke (a 2.2151, e 0.8483, i 11.78°), listed T_J 3.025.
    /// Tolerance 0.01: the elements are rounded to 4–5 digits (≤ 10⁻³ in T_J), and the listed
    /// inclinations are to the ecliptic, not to Jupiter's plane (1.3° apart: at most
    /// `2 sin i · 0.023 · √((a/a_J)(1 − e²))` = 0.007, for Halley). Their classes, and those
    /// of 67P/Churyumov–Gerasimenko (a 3.463, e 0.641, i 7.04°), a Jupiter-family comet,
    /// 95P/(2060) Chiron (a 13.69, e 0.379, i 6.93°), after which Levison names the
    /// Chiron-type class, and the long-period C/1995 O1 Hale–Bopp (a 186, e 0.9951, i 89.4°).
    #[test]
    fn known_comets_have_their_published_tisserand_and_class() {
        let published = [
            (
                "1P/Halley",
                17.834,
                0.96714,
                162.26,
                -0.605,
                LevisonClass::HalleyType,
            ),
            (
                "2P/Encke",
                2.2151,
                0.8483,
                11.78,
                3.025,
                LevisonClass::EnckeType,
            ),
        ];
        for (name, a, e, i, listed, class) in published {
            let t = tisserand_jupiter(a, e, f64::to_radians(i));
            assert!(
                (t - listed).abs() < 0.01,
                "{name}: T_J {t}, listed {listed}"
            );
            assert_eq!(levison_class(a, e, t), class, "{name}");
        }
        let classes = [
            ("67P", 3.463, 0.641, 7.04, LevisonClass::JupiterFamily),
            ("Chiron", 13.69, 0.379, 6.93, LevisonClass::ChironType),
            ("Hale-Bopp", 186.0, 0.9951, 89.4, LevisonClass::LongPeriod),
        ];
        for (name, a, e, i, class) in classes {
            let t = tisserand_jupiter(a, e, f64::to_radians(i));
            assert_eq!(levison_class(a, e, t), class, "{name}: T_J {t}");
        }
        assert!(!LevisonClass::LongPeriod.is_ecliptic() && LevisonClass::EnckeType.is_ecliptic());
        // Unbound: no T_J, no class.
        assert!(tisserand_jupiter(-5.0, 1.5, 0.1).is_nan());
        assert_eq!(
            levison_class(-5.0, 1.5, f64::NAN),
            LevisonClass::Unclassified
        );
    }

    /// The q-and-a regions of known objects (JPL Small-Body Database elements, rounded):
    /// Chiron (q 8.5 AU) between the giants, Encke (q 0.34 AU) and Halley inside Jupiter's
    /// orbit, Eris (a 67.9 AU) and Pluto (a 39.5 AU) trans-Neptunian, a hyperbola unbound.
    #[test]
    fn known_objects_fall_in_their_regions() {
        use OrbitalRegion::*;
        assert_eq!(orbital_region(&el(13.7, 0.38, 6.9)), Centaur);
        assert_eq!(
            orbital_region(&el(2.2151, 0.8483, 11.78)),
            PerihelionInsideJupiter
        );
        assert_eq!(
            orbital_region(&el(17.834, 0.96714, 162.26)),
            PerihelionInsideJupiter
        );
        assert_eq!(orbital_region(&el(67.9, 0.44, 44.0)), TransNeptunian);
        assert_eq!(orbital_region(&el(39.5, 0.25, 17.1)), TransNeptunian);
        assert_eq!(orbital_region(&el(-5.0, 1.5, 10.0)), Unbound);
    }

    /// The inclination to a plane: an orbit in the plane is at 0, a retrograde one at π,
    /// a polar one at π/2, one tilted by 1.3° about the x axis at 1.3° (the angle put in).
    #[test]
    fn inclination_to_a_plane_is_the_angle_of_the_angular_momenta() {
        let z = Vec3::z();
        let (r, v) = (Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 0.007, 0.0));
        assert_eq!(inclination_to_plane(&r, &v, &z), 0.0);
        assert_eq!(inclination_to_plane(&r, &-v, &z), std::f64::consts::PI);
        let polar = Vec3::new(0.0, 0.0, 0.007);
        let i = inclination_to_plane(&r, &polar, &z);
        // acos of a rounded 0: within a few ulps of π/2.
        assert!((i - std::f64::consts::FRAC_PI_2).abs() < 1e-15, "{i}");
        let tilt = 1.3f64.to_radians();
        let tilted = Vec3::new(0.0, tilt.sin(), tilt.cos());
        let i = inclination_to_plane(&r, &v, &tilted);
        // acos near 0 loses half the digits: 1e-8 rad (√ε).
        assert!((i - tilt).abs() < 1e-8, "{} vs {}", i, tilt);
        assert!(inclination_to_plane(&r, &(r * 0.001), &z).is_nan());
    }

    /// Jupiter's orbit normal from the outer Solar System in the ecliptic of J2000 is 1.3°
    /// from the ecliptic pole (Standish's J2000 mean inclination 1.30530°; osculating at the
    /// 1994 epoch of the planets, within 0.01°), and the same plane in the equatorial frame
    /// is 23.4° from the equatorial pole at most (ε = 23.44°, Jupiter's plane 1.3° off the
    /// ecliptic).
    #[test]
    fn jupiters_orbit_normal_is_its_plane() {
        use crate::{outer_solar_system, Frame, Integrator};
        let eph = |frame| {
            Ephemeris::new(outer_solar_system(frame), Integrator::S2 { step: 365.25 }).unwrap()
        };
        let n = jupiter_orbit_normal(&eph(Frame::EclipticJ2000)).unwrap();
        let i = n.z.acos().to_degrees();
        assert!((i - 1.3053).abs() < 0.01, "{i}°");
        let n = jupiter_orbit_normal(&eph(Frame::Equatorial)).unwrap();
        let i = n.z.acos().to_degrees();
        assert!((22.1..24.8).contains(&i), "{i}°");
    }
}
