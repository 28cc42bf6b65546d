//! Test particles (massless comets) with Emel'yanenko's variable time step.

use serde::{Deserialize, Serialize};

use crate::ephemeris::{BodyStates, Ephemeris};
use crate::{SymplecticError, Vec3, WorkCounters, S6_C1, S6_C2, S6_D1, S6_D2};

/// Which coordinates the particle is integrated in (Chegodaeva 2004).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Variant {
    /// Eqs. 36–38, the variant the paper recommends: barycentric position and velocity,
    /// `H₀ = v²/2 − G M/r` with `M` the total mass and `r = |q|`, and
    /// `H₁ = Σ_{j=0..n} G m_j (1/|q − q_j(t)| − 1/r)`, `H = H₀ − H₁`.
    Barycentric,
    /// Eqs. 15–32: heliocentric position `Q` and barycentric velocity `V`,
    /// `H_Kepl = V²/2 − G m₀/|Q|` (eq. 18), `H_Sun = −V·ΣP_i(t)/m₀` (eq. 19),
    /// `H_Inter = Σ G m_i/|Q − Q_i(t)|` (eq. 20), `H = H_Kepl − H_Sun − H_Inter`.
    Mixed,
}

/// The particle maps, built from the two exact flows of the logarithmic Hamiltonian.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scheme {
    /// Eq. 27: `E₁(h/2) E₀(h) E₁(h/2)`.
    S2,
    /// Eq. 7 with `A → E₀`, `B → E₁`: `E₁(d₁h) E₀(c₂h) E₁(d₂h) E₀(c₁h) E₁(d₂h) E₀(c₂h) E₁(d₁h)`.
    S6,
}

/// One exact flow of the split logarithmic Hamiltonian `Γ = Γ₀ + Γ₁`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParticlePiece {
    /// `E₀`: flow of `Γ₀ = ln(K₀/r)`, a Kepler drift over the physical time `h/(K₀/r)`.
    KeplerDrift,
    /// `E₁`: flow of `Γ₁ = −ln(K₁/r)`, the perturbation at fixed time.
    Perturbation,
}

/// A piece applied for `coefficient × h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleStage {
    /// The flow.
    pub piece: ParticlePiece,
    /// Fraction of the step `h`.
    pub coefficient: f64,
}

const fn stage(piece: ParticlePiece, coefficient: f64) -> ParticleStage {
    ParticleStage { piece, coefficient }
}

/// Eq. 27.
pub const PARTICLE_S2_STAGES: [ParticleStage; 3] = [
    stage(ParticlePiece::Perturbation, 0.5),
    stage(ParticlePiece::KeplerDrift, 1.0),
    stage(ParticlePiece::Perturbation, 0.5),
];

/// Eq. 7 applied to `Γ₀` (A) and `Γ₁` (B).
pub const PARTICLE_S6_STAGES: [ParticleStage; 7] = [
    stage(ParticlePiece::Perturbation, S6_D1),
    stage(ParticlePiece::KeplerDrift, S6_C2),
    stage(ParticlePiece::Perturbation, S6_D2),
    stage(ParticlePiece::KeplerDrift, S6_C1),
    stage(ParticlePiece::Perturbation, S6_D2),
    stage(ParticlePiece::KeplerDrift, S6_C2),
    stage(ParticlePiece::Perturbation, S6_D1),
];

/// A test particle in the extended phase space: position, velocity, `q₄ = t`, `p₄ = −H`, and
/// its step `h` in the new independent variable `s`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TestParticle {
    /// Barycentric (variant [`Variant::Barycentric`]) or heliocentric ([`Variant::Mixed`])
    /// position.
    pub position: Vec3,
    /// Barycentric velocity (both variants).
    pub velocity: Vec3,
    /// `q₄ = t`, the particle's own time.
    pub time: f64,
    /// `p₄`, equal to `−H` on the exact trajectory.
    pub p4: f64,
    /// Step `h` in `s` (units of `s`: `ds = (K₀/r) dt`, so energy × time).
    pub step: f64,
    /// Steps taken.
    pub steps: u64,
    /// Work done on this particle: its Kepler solves and body–particle force evaluations (the
    /// interpolations of the planets are counted by the [`Ephemeris`]).
    #[serde(default)]
    pub work: WorkCounters,
}

/// Emel'yanenko's explicit symplectic integrator with variable time step for a test
/// particle, as Chegodaeva (2004) builds it (eqs. 21–32 mixed, 36–38 barycentric), after
///
/// > V. V. Emel'yanenko, "An explicit symplectic integrator for cometary orbits",
/// > *Celestial Mechanics and Dynamical Astronomy* (the paper's reference 4 gives 2001,
/// > vol. 74, pp. 287–295, the volume and pages of the Mikkola–Tanikawa entry; we could not
/// > verify the correct ones), and S. Mikkola & K. Tanikawa, "Explicit symplectic algorithms
/// > for time-transformed Hamiltonians", *Celest. Mech. Dyn. Astron.* 74, 287–295 (1999).
///
/// Phase space is extended by `q₄ = t`, `p₄ = −H`; with `dτ = dt/r` the Hamiltonian
/// `K = r(H + p₄)` is split by adding `rB₀ + B₁` to both parts (eq. 22):
/// `K₀ = r(H₀ + p₄ + B₀ + B₁/r)`, `K₁ = r(H₁ + B₀ + B₁/r)`, and the logarithmic
/// Hamiltonian `Γ = ln(K₀/r) − ln(K₁/r)` (eqs. 23–26) is integrated with [`Scheme`]. Both
/// parts have exact flows:
///
/// - `E₀` (`Γ₀ = ln F₀`, `F₀ = K₀/r = H₀ + p₄ + B₀ + B₁/r`): `F₀` is conserved, `t` advances
///   by `Δt = h/F₀` (eq. 28), and the particle moves on the Kepler orbit of
///   `μ' = G M − B₁` (barycentric) or `G m₀ − B₁` (mixed) for `Δt`; `p₄` is unchanged.
/// - `E₁` (`Γ₁ = −ln F₁`, `F₁ = K₁/r`): `t` is fixed (eq. 31) and `F₁` conserved; with
///   `σ = h/F₁`, `v += σ ∂F₁/∂q`, `p₄ += σ ∂F₁/∂t` (eqs. 30, 32). In the mixed variant
///   `F₁` also depends on `V` through `H_Sun`, so `Q` moves by `σ ΣP_i/m₀` (eq. 29) and the
///   kicks are integrals along that straight segment: these are the "cumbersome
///   expressions" of the paper. We evaluate them with 4-point Gauss–Legendre quadrature,
///   whose relative error `~(|ΔQ|/d)⁸` (`d` the distance to the nearest body, `|ΔQ|` about
///   the Sun's barycentric speed × `Δt`, 10⁻² AU at most) is far below round-off.
///
/// **Deviation:** eq. 38 writes the barycentric Kepler part with `μ = G M + C₀ − B₁` where
/// `C₀` is the constant `K₀`; that is the form `Γ₀ = ln K₀` (a Kepler problem in the
/// regularised time), whereas eqs. 22–28 define `Γ₀ = ln(K₀/r)` with `dt = ds/F₀`. We follow
/// eqs. 22–28 consistently for both variants; both forms integrate the same `Γ`.
///
/// `F₀` or `F₁` reaching zero or below means `B₀, B₁` no longer dominate the perturbation
/// (the paper's condition 35, violated for perihelia below ≈ 26 AU with `B₀ = 0`,
/// `B₁ = 0.21·10⁻⁶`): the step stops with [`SymplecticError::RegularisationLost`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ParticleIntegrator {
    /// Coordinates.
    pub variant: Variant,
    /// Composition.
    pub scheme: Scheme,
    /// `B₀` (energy units, AU²/day² in the experiments).
    pub b0: f64,
    /// `B₁` (energy × length, AU³/day²).
    pub b1: f64,
}

/// Outcome of one particle step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleStepInfo {
    /// Physical time advanced.
    pub dt: f64,
    /// `(H + p₄)/|H|` at the end of the step: the extended-Hamiltonian error.
    pub relative_error: f64,
}

/// Scratch for [`ParticleIntegrator::step`] (reused between steps, no allocation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParticleScratch {
    bodies: BodyStates,
    kick: KickTerms,
}

/// The barycentric `E₁` terms at one time and position: `F₁ = K₁/r`, `∂F₁/∂q` and
/// `Σ G m_j (q − q_j)·q̇_j/|q − q_j|³` (`∂F₁/∂t`), kept to serve the next kick at the same
/// `(t, q)` without evaluating the forces again. `NaN` time: holds nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct KickTerms {
    time: f64,
    position: Vec3,
    f1: f64,
    gradient: Vec3,
    dt_part: f64,
}

impl Default for KickTerms {
    fn default() -> Self {
        Self {
            time: f64::NAN,
            position: Vec3::zeros(),
            f1: f64::NAN,
            gradient: Vec3::zeros(),
            dt_part: f64::NAN,
        }
    }
}

impl KickTerms {
    /// `F₁ = K₁/r` of these terms (`NaN` if they hold nothing).
    pub(crate) fn f1(&self) -> f64 {
        self.f1
    }

    /// Whether these are the terms at `(time, position)` (bit for bit; the bodies are a
    /// function of the time, so nothing else enters).
    fn holds(&self, time: f64, position: &Vec3) -> bool {
        self.time.to_bits() == time.to_bits()
            && self
                .position
                .iter()
                .zip(position.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

impl ParticleScratch {
    /// The bodies at the end of the last step (or the last particle built).
    pub fn bodies(&self) -> &BodyStates {
        &self.bodies
    }
}

/// Where a mixed-variant orbit stands against its validity domain
/// ([`ParticleIntegrator::mixed_domain`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MixedDomain {
    /// Smallest `(B₀ + B₁/r)/(|V(r)| u☉)` over the orbit.
    pub ratio: f64,
    /// Heliocentric distance where it is smallest.
    pub at_distance: f64,
    /// Smallest `B₁` (with the integrator's `B₀`) that gives [`MIXED_DOMAIN_MIN_RATIO`].
    pub b1_needed: f64,
}

/// Smallest ratio `(B₀ + B₁/r)/(|V| u☉)` over the orbit that the mixed variant accepts (see
/// [`ParticleIntegrator::mixed_domain`]). Chegodaeva's condition 35 asks `B₀ + B₁/r` to
/// dominate the perturbation far from the planets without a number; we read "dominate" as a
/// factor 2, which keeps `K₁/r` above half its regularising part and the step within a factor
/// 2 of its regular law. Measured on the paper's two particles (S2, steps 298/310 d, 2 kyr,
/// through the public API): ratios 0.16 and 0.13 (the paper's `B₁ = 0.21·10⁻⁶`, which it
/// chose for the barycentric variant) lose `K₁/r > 0` after 3284 and 1945 d, with steps 10
/// times shorter after 3211 and 1835 d, 50 times shorter after 6768 and 1730 d (a property of
/// the trajectory, not of the step);
/// ratios 0.31 and 0.39 lose `K₀/r > 0` within 5 and 20 years; 0.61–1.23 within 5–1700
/// years, except 1.17 (particle 1), which held for 2 kyr; 1.56 and 1.84 held for 2 kyr but with
/// steps swinging up to 1100 d and `|ΔH|` up to 3·10⁻³; 2.3–6.2 held with `|ΔH| ≤ 7·10⁻⁴`
/// (`cargo run --release -p symplectic --example mixed_domain_scan`).
pub const MIXED_DOMAIN_MIN_RATIO: f64 = 2.0;

/// Chegodaeva's (2004) `B₀` for her numerical experiments: 0 (energy units, AU²/day²).
/// With [`PAPER_B1`], the barycentric variant's regularisation; valid for perihelia beyond
/// ≈ 26 AU (condition 35).
pub const PAPER_B0: f64 = 0.0;

/// Chegodaeva's (2004) `B₁` for her numerical experiments: 0.21·10⁻⁶ AU³/day² (energy ×
/// length), chosen for the barycentric variant; the mixed variant needs more
/// ([`ParticleIntegrator::mixed_domain`]).
pub const PAPER_B1: f64 = 0.21e-6;

const GAUSS4_NODES: [f64; 4] = [
    0.069_431_844_202_973_71,
    0.330_009_478_207_571_87,
    0.669_990_521_792_428_1,
    0.930_568_155_797_026_3,
];
const GAUSS4_WEIGHTS: [f64; 4] = [
    0.173_927_422_568_726_93,
    0.326_072_577_431_273_07,
    0.326_072_577_431_273_07,
    0.173_927_422_568_726_93,
];

impl ParticleIntegrator {
    /// The integrator; `b0 >= 0`, `b1 >= 0`, not both zero.
    pub fn new(
        variant: Variant,
        scheme: Scheme,
        b0: f64,
        b1: f64,
    ) -> Result<Self, SymplecticError> {
        for (name, v) in [("B0", b0), ("B1", b1)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SymplecticError::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite and >= 0",
                });
            }
        }
        if b0 == 0.0 && b1 == 0.0 {
            return Err(SymplecticError::InvalidParameter {
                name: "B1",
                value: b1,
                reason: "B0 and B1 cannot both be zero (K1/r would vanish far from the planets)",
            });
        }
        Ok(Self {
            variant,
            scheme,
            b0,
            b1,
        })
    }

    /// The integrator with the paper's regularisation constants [`PAPER_B0`] and
    /// [`PAPER_B1`] (chosen for [`Variant::Barycentric`]).
    pub fn paper(variant: Variant, scheme: Scheme) -> Self {
        Self {
            variant,
            scheme,
            b0: PAPER_B0,
            b1: PAPER_B1,
        }
    }

    /// The stages of the map.
    pub fn stages(&self) -> &'static [ParticleStage] {
        match self.scheme {
            Scheme::S2 => &PARTICLE_S2_STAGES,
            Scheme::S6 => &PARTICLE_S6_STAGES,
        }
    }

    /// Builds a particle at time `time` from its position and barycentric velocity, with
    /// `p₄ = −H` and the step `h` chosen so that the first physical step is `initial_dt`
    /// (`h = initial_dt · F₀`).
    pub fn particle(
        &self,
        position: Vec3,
        velocity: Vec3,
        time: f64,
        initial_dt: f64,
        ephemeris: &mut Ephemeris,
        scratch: &mut ParticleScratch,
    ) -> Result<TestParticle, SymplecticError> {
        check_initial(&position, &velocity, initial_dt)?;
        ephemeris.bodies_at(time, &mut scratch.bodies)?;
        self.particle_from_bodies(
            position,
            velocity,
            time,
            initial_dt,
            &scratch.bodies,
            ephemeris.planets(),
        )
    }

    /// [`ParticleIntegrator::particle`] with the bodies already at `time` (`bodies`) and the
    /// planets for the mixed variant's domain check: the read-only form used by
    /// [`Population`](crate::Population) to build particles in parallel.
    pub(crate) fn particle_from_bodies(
        &self,
        position: Vec3,
        velocity: Vec3,
        time: f64,
        initial_dt: f64,
        bodies: &BodyStates,
        planets: &crate::Planets,
    ) -> Result<TestParticle, SymplecticError> {
        check_initial(&position, &velocity, initial_dt)?;
        if self.variant == Variant::Mixed {
            self.check_mixed_domain(&position, &velocity, planets)?;
        }
        let mut p = TestParticle {
            position,
            velocity,
            time,
            p4: 0.0,
            step: 0.0,
            steps: 0,
            work: WorkCounters::default(),
        };
        p.p4 = -self.hamiltonian(&p, bodies);
        let f0 = self.f0(&p, bodies)?;
        p.step = initial_dt * f0;
        Ok(p)
    }

    /// Validity domain of the mixed variant: the smallest, over the particle's heliocentric
    /// osculating orbit, of `(B₀ + B₁/r) / (|V(r)| · u☉)`, where `|V(r)|` is the speed on that
    /// orbit at distance `r` (vis-viva with `μ = G m₀`) and `u☉ = Σ m_i v_i,max / m₀` bounds the
    /// Sun's barycentric speed `|ΣP_i|/m₀` (`v_i,max` the perihelion speed of planet `i`).
    /// Returns the smallest ratio, where it occurs and the `B₁` that would meet
    /// [`MIXED_DOMAIN_MIN_RATIO`] ([`MixedDomain`]).
    ///
    /// Why: in mixed coordinates `K₁/r = B₀ + B₁/r − V·ΣP_i/m₀ + Σ G m_i/|Q − Q_i|`
    /// (eqs. 19–22). The Sun term `H_Sun = −V·ΣP_i/m₀` changes sign with the phase of Jupiter
    /// and reaches `|V| u☉`; unless `B₀ + B₁/r` dominates it (the paper's condition 35) `K₁/r`
    /// turns negative on the exact trajectory, and the physical step `Δt = h/(K₀/r)` swings
    /// with Jupiter's phase by up to a factor `ρ/(ρ − 1)` for a ratio `ρ`.
    pub fn mixed_domain(
        &self,
        position: &Vec3,
        velocity: &Vec3,
        planets: &crate::Planets,
    ) -> Result<MixedDomain, SymplecticError> {
        let g = planets.g();
        let m0 = planets.sun_mass();
        let mut sun_speed = 0.0;
        for ((&m, q), v) in planets
            .masses()
            .iter()
            .zip(planets.positions())
            .zip(planets.heliocentric_velocities())
        {
            let mu = g * (m0 + m);
            let el = crate::kepler::elements(q, &v, mu)?;
            let v_max2 = mu * (2.0 / el.perihelion - 1.0 / el.semi_major_axis);
            sun_speed += m * v_max2.max(0.0).sqrt() / m0;
        }
        let mu = g * m0;
        let el = crate::kepler::elements(position, velocity, mu)?;
        let q = el.perihelion;
        let aphelion = if el.eccentricity < 1.0 {
            el.semi_major_axis * (1.0 + el.eccentricity)
        } else {
            1e6 * q
        };
        const SAMPLES: usize = 512;
        let (mut worst, mut at, mut b1_needed) = (f64::INFINITY, q, 0.0f64);
        for k in 0..=SAMPLES {
            let r = q * (aphelion / q).powf(k as f64 / SAMPLES as f64);
            let speed = (mu * (2.0 / r - 1.0 / el.semi_major_axis)).max(0.0).sqrt();
            let sun_term = speed * sun_speed;
            let ratio = (self.b0 + self.b1 / r) / sun_term;
            if ratio < worst {
                (worst, at) = (ratio, r);
            }
            b1_needed = b1_needed.max((MIXED_DOMAIN_MIN_RATIO * sun_term - self.b0) * r);
        }
        Ok(MixedDomain {
            ratio: worst,
            at_distance: at,
            b1_needed,
        })
    }

    fn check_mixed_domain(
        &self,
        position: &Vec3,
        velocity: &Vec3,
        planets: &crate::Planets,
    ) -> Result<(), SymplecticError> {
        let MixedDomain {
            ratio,
            at_distance,
            b1_needed,
        } = self.mixed_domain(position, velocity, planets)?;
        if ratio >= MIXED_DOMAIN_MIN_RATIO {
            return Ok(());
        }
        Err(SymplecticError::OutsideMixedDomain {
            ratio,
            required: MIXED_DOMAIN_MIN_RATIO,
            at_distance,
            b0: self.b0,
            b1: self.b1,
            b1_needed,
        })
    }

    /// The particle's Hamiltonian `H` at its time (bodies must be at that time).
    pub fn hamiltonian(&self, p: &TestParticle, bodies: &BodyStates) -> f64 {
        let r = p.position.norm();
        let v2 = p.velocity.norm_squared();
        match self.variant {
            Variant::Barycentric => {
                let mut pot = 0.0;
                for (gm, qj) in bodies.gm.iter().zip(&bodies.positions) {
                    pot += gm / (p.position - qj).norm();
                }
                0.5 * v2 - pot
            }
            Variant::Mixed => {
                let (sun_momentum, _) = planets_momentum_over_m0(bodies);
                let sun = bodies.positions[0];
                let mut pot = bodies.gm[0] / r;
                for (gm, qj) in bodies.gm.iter().zip(&bodies.positions).skip(1) {
                    pot += gm / (p.position - (qj - sun)).norm();
                }
                0.5 * v2 + p.velocity.dot(&sun_momentum) - pot
            }
        }
    }

    /// `F₀ = K₀/r`.
    fn f0(&self, p: &TestParticle, bodies: &BodyStates) -> Result<f64, SymplecticError> {
        self.f0_at_distance(p, p.position.norm(), bodies)
    }

    /// `F₀` with `r = |q|` given.
    fn f0_at_distance(
        &self,
        p: &TestParticle,
        r: f64,
        bodies: &BodyStates,
    ) -> Result<f64, SymplecticError> {
        let mu = self.kepler_mu(bodies);
        let f0 = 0.5 * p.velocity.norm_squared() - mu / r + p.p4 + self.b0;
        check_positive("K0/r", f0, p.time)
    }

    /// `μ'` of the Kepler part of `Γ₀`.
    pub(crate) fn kepler_mu(&self, bodies: &BodyStates) -> f64 {
        match self.variant {
            Variant::Barycentric => bodies.total_gm() - self.b1,
            Variant::Mixed => bodies.gm[0] - self.b1,
        }
    }

    /// Piece `E₀` for `h`: Kepler drift over `Δt = h/F₀`. Returns `Δt`.
    pub fn kepler_drift(
        &self,
        p: &mut TestParticle,
        h: f64,
        bodies: &BodyStates,
    ) -> Result<f64, SymplecticError> {
        let r = p.position.norm();
        let f0 = self.f0_at_distance(p, r, bodies)?;
        let dt = h / f0;
        let mu = self.kepler_mu(bodies);
        if mu.is_nan() || mu <= 0.0 {
            return Err(SymplecticError::InvalidParameter {
                name: "B1",
                value: self.b1,
                reason: "B1 must be smaller than G M (the Kepler part needs a positive μ)",
            });
        }
        let info = crate::kepler::drift_from_distance(&mut p.position, &mut p.velocity, r, mu, dt)?;
        p.work.kepler_solves += 1;
        p.work.kepler_iterations += u64::from(info.iterations);
        p.time += dt;
        Ok(dt)
    }

    /// Piece `E₁` for `h` at the particle's time; `bodies` must be at that time.
    pub fn perturbation(
        &self,
        p: &mut TestParticle,
        h: f64,
        bodies: &BodyStates,
    ) -> Result<(), SymplecticError> {
        self.perturbation_cached(p, h, bodies, &mut KickTerms::default())
    }

    /// The barycentric `E₁` terms at `(t, q)` ([`KickTerms`]): one square root and one
    /// division per body.
    fn barycentric_kick_terms(&self, time: f64, q: Vec3, bodies: &BodyStates) -> KickTerms {
        let inv_r = 1.0 / q.norm();
        let q_r3 = q * (inv_r * inv_r * inv_r);
        let mut f1 = self.b0 + self.b1 * inv_r;
        let mut gradient = -q_r3 * self.b1;
        let mut dt_part = 0.0;
        for ((gm, qj), vj) in bodies
            .gm
            .iter()
            .zip(&bodies.positions)
            .zip(&bodies.velocities)
        {
            let d = q - qj;
            let inv_d = 1.0 / d.norm();
            let inv_d3 = inv_d * inv_d * inv_d;
            f1 += gm * (inv_d - inv_r);
            gradient += (q_r3 - d * inv_d3) * *gm;
            dt_part += gm * d.dot(vj) * inv_d3;
        }
        KickTerms {
            time,
            position: q,
            f1,
            gradient,
            dt_part,
        }
    }

    /// [`ParticleIntegrator::perturbation`], reusing in the barycentric variant the terms of
    /// the last kick at the same time and position (`cache`): the closing `E₁` of a step and
    /// the opening one of the next are at the same `(t, q)`, and `F₁` depends on nothing else
    /// there, so the second costs no force evaluation and the result is bit for bit the same.
    pub(crate) fn perturbation_cached(
        &self,
        p: &mut TestParticle,
        h: f64,
        bodies: &BodyStates,
        cache: &mut KickTerms,
    ) -> Result<(), SymplecticError> {
        match self.variant {
            Variant::Barycentric => {
                if !cache.holds(p.time, &p.position) {
                    *cache = self.barycentric_kick_terms(p.time, p.position, bodies);
                }
                p.work.force_evaluations += bodies.gm.len() as u64;
                let f1 = check_positive("K1/r", cache.f1, p.time)?;
                let sigma = h / f1;
                p.velocity += cache.gradient * sigma;
                p.p4 += cache.dt_part * sigma;
            }
            Variant::Mixed => {
                let (s_over_m0, s_dot_over_m0) = planets_momentum_over_m0(bodies);
                let sun = bodies.positions[0];
                let sun_v = bodies.velocities[0];
                let q0 = p.position;
                let v0 = p.velocity;
                // F1 (n potential terms) and the gradient at the 4 quadrature nodes (4n).
                p.work.force_evaluations += 5 * (bodies.gm.len() as u64 - 1);
                let f1 = check_positive("K1/r", self.mixed_f1(q0, v0, s_over_m0, bodies), p.time)?;
                let sigma = h / f1;
                // Q moves along a straight segment (eq. 29); V and p4 are line integrals of
                // ∂F1/∂Q and ∂F1/∂t (eqs. 30, 32). ∫V = σV0 + ∫(σ − u) ∂F1/∂Q du.
                let dq = s_over_m0 * sigma;
                let mut int_grad = Vec3::zeros();
                let mut int_weighted_grad = Vec3::zeros();
                let mut int_dt_pot = 0.0;
                for (&x, &w) in GAUSS4_NODES.iter().zip(&GAUSS4_WEIGHTS) {
                    let q = q0 + dq * x;
                    let r = q.norm();
                    let mut grad = -q * (self.b1 / (r * r * r));
                    let mut dt_pot = 0.0;
                    for j in 1..bodies.gm.len() {
                        let d = q - (bodies.positions[j] - sun);
                        let dn = d.norm();
                        let d3 = dn * dn * dn;
                        grad -= d * (bodies.gm[j] / d3);
                        // ∂/∂t of G m_j/|Q − Q_j(t)| = G m_j (Q − Q_j)·Q̇_j/d³.
                        dt_pot += bodies.gm[j] * d.dot(&(bodies.velocities[j] - sun_v)) / d3;
                    }
                    int_grad += grad * (w * sigma);
                    int_weighted_grad += grad * (w * sigma * sigma * (1.0 - x));
                    int_dt_pot += dt_pot * (w * sigma);
                }
                let int_v = v0 * sigma + int_weighted_grad;
                p.position = q0 + dq;
                p.velocity = v0 + int_grad;
                // ∂F1/∂t = ∂H_Inter/∂t − V·Ṡ/m0.
                p.p4 += int_dt_pot - int_v.dot(&s_dot_over_m0);
            }
        }
        Ok(())
    }

    /// `F₁ = K₁/r` of the mixed variant.
    fn mixed_f1(&self, q: Vec3, v: Vec3, s_over_m0: Vec3, bodies: &BodyStates) -> f64 {
        let sun = bodies.positions[0];
        let mut f1 = self.b0 + self.b1 / q.norm() - v.dot(&s_over_m0);
        for j in 1..bodies.gm.len() {
            f1 += bodies.gm[j] / (q - (bodies.positions[j] - sun)).norm();
        }
        f1
    }

    /// One step of the map: the particle advances by `h` in `s`, its clock by the sum of the
    /// drifts' `Δt`, the planets being taken from `ephemeris` at each `E₁`.
    pub fn step(
        &self,
        p: &mut TestParticle,
        ephemeris: &mut Ephemeris,
        scratch: &mut ParticleScratch,
    ) -> Result<ParticleStepInfo, SymplecticError> {
        let t_start = p.time;
        self.advance(
            p,
            &mut scratch.bodies,
            f64::NAN,
            &mut scratch.kick,
            &mut |t: f64, out: &mut BodyStates| ephemeris.bodies_at(t, out),
        )?;
        let hamiltonian = self.hamiltonian(p, &scratch.bodies);
        Ok(ParticleStepInfo {
            dt: p.time - t_start,
            relative_error: (hamiltonian + p.p4) / hamiltonian.abs(),
        })
    }

    /// The map proper, shared by [`ParticleIntegrator::step`] and
    /// [`Population`](crate::Population): the stages of the scheme, fetching the bodies with
    /// `fetch` whenever the particle's time differs from `bodies_time` (the time `bodies`
    /// holds, `NaN` if none), and once more at the end, so that `bodies` ends at the particle's
    /// new time. `kick` carries the last barycentric kick's terms between stages and steps
    /// ([`KickTerms`]). Returns that time.
    pub(crate) fn advance(
        &self,
        p: &mut TestParticle,
        bodies: &mut BodyStates,
        mut bodies_time: f64,
        kick: &mut KickTerms,
        fetch: &mut impl FnMut(f64, &mut BodyStates) -> Result<(), SymplecticError>,
    ) -> Result<f64, SymplecticError> {
        let h = p.step;
        for s in self.stages() {
            if bodies_time != p.time {
                fetch(p.time, bodies)?;
                bodies_time = p.time;
            }
            match s.piece {
                ParticlePiece::KeplerDrift => {
                    self.kepler_drift(p, s.coefficient * h, bodies)?;
                }
                ParticlePiece::Perturbation => {
                    self.perturbation_cached(p, s.coefficient * h, bodies, kick)?
                }
            }
        }
        if bodies_time != p.time {
            fetch(p.time, bodies)?;
        }
        p.steps += 1;
        if !(p
            .position
            .iter()
            .chain(p.velocity.iter())
            .all(|x| x.is_finite())
            && p.p4.is_finite())
        {
            return Err(SymplecticError::InvalidState {
                what: "test particle",
                reason: format!("non-finite state at t = {} after step {}", p.time, p.steps),
            });
        }
        Ok(p.time)
    }

    /// The extended-Hamiltonian error `(H + p₄)/|H|` of `p` now.
    pub fn relative_error(
        &self,
        p: &TestParticle,
        ephemeris: &mut Ephemeris,
        scratch: &mut ParticleScratch,
    ) -> Result<f64, SymplecticError> {
        ephemeris.bodies_at(p.time, &mut scratch.bodies)?;
        let h = self.hamiltonian(p, &scratch.bodies);
        Ok((h + p.p4) / h.abs())
    }
}

/// `ΣP_i/m₀` and its time derivative, from the barycentric states: the barycentric momenta
/// of the planets sum to `−m₀ v₀`.
fn planets_momentum_over_m0(bodies: &BodyStates) -> (Vec3, Vec3) {
    let m0 = bodies.gm[0];
    let mut s = Vec3::zeros();
    let mut s_dot = Vec3::zeros();
    for j in 1..bodies.gm.len() {
        s += bodies.velocities[j] * bodies.gm[j];
        s_dot += bodies.accelerations[j] * bodies.gm[j];
    }
    (s / m0, s_dot / m0)
}

fn check_initial(position: &Vec3, velocity: &Vec3, initial_dt: f64) -> Result<(), SymplecticError> {
    if !position
        .iter()
        .chain(velocity.iter())
        .all(|x| x.is_finite())
        || position.norm() == 0.0
    {
        return Err(SymplecticError::InvalidState {
            what: "test particle",
            reason: format!(
                "position {position:?} and velocity {velocity:?} must be finite, position non-zero"
            ),
        });
    }
    if !(initial_dt.is_finite() && initial_dt > 0.0) {
        return Err(SymplecticError::InvalidParameter {
            name: "initial particle step",
            value: initial_dt,
            reason: "must be finite and > 0",
        });
    }
    Ok(())
}

fn check_positive(quantity: &'static str, value: f64, time: f64) -> Result<f64, SymplecticError> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(SymplecticError::RegularisationLost {
            quantity,
            value,
            time,
        })
    }
}
