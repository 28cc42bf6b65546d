use crate::lanes::{self, Mask, LANES, V, V3};
use crate::{kepler, SymplecticError, Vec3, WorkCounters};

/// The Sun and `n` planets in mixed (democratic heliocentric) variables, Chegodaeva (2004)
/// eq. 9 after Duncan, Levison & Lee (1998): heliocentric positions `Q_i = q_i − q_0` and
/// barycentric momenta `P_i = p_i − m_i/M Σ p_j` of the planets `i = 1..n`. The barycentre
/// moves uniformly and is not integrated.
///
/// The Hamiltonian (eqs. 10–12) is split into
/// - `H_Kepl = Σ_i |P_i|²/2 (1/m_i + 1/m_0) − G m_i m_0/|Q_i|` — each planet on its own Kepler
///   orbit with `μ_i = G (m_0 + m_i)` and velocity `P_i (1/m_i + 1/m_0)`;
/// - `H_Sun = (1/m_0) Σ_{i<j} P_i·P_j` — the cross terms of `|Σ P_i|²/2m_0` (eq. 11);
/// - `H_Inter = −Σ_{i<j} G m_i m_j / |Q_i − Q_j|`.
///
/// Each part has an exact flow, exposed as a named piece.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Planets {
    g: f64,
    sun_mass: f64,
    masses: Vec<f64>,
    /// Heliocentric positions `Q_i`.
    positions: Vec<Vec3>,
    /// Barycentric momenta `P_i`.
    momenta: Vec<Vec3>,
    /// Time.
    time: f64,
    /// Work done so far (Kepler solves, pairwise forces).
    #[serde(default)]
    work: WorkCounters,
    /// Names of the planets (empty: unnamed, reported as `planet_<j>`).
    #[serde(default)]
    names: Vec<String>,
    /// Physical radii of the planets (empty: no collisions detected).
    #[serde(default)]
    radii: Vec<f64>,
}

impl Planets {
    /// Builds the system from heliocentric positions and velocities (`q_i − q_0`,
    /// `v_i − v_0`) of the planets, the Sun's mass and the constant of gravitation `g`.
    pub fn from_heliocentric(
        g: f64,
        sun_mass: f64,
        masses: &[f64],
        positions: &[Vec3],
        velocities: &[Vec3],
    ) -> Result<Self, SymplecticError> {
        let positive = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(SymplecticError::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite and > 0",
                })
            }
        };
        positive("G", g)?;
        positive("sun mass", sun_mass)?;
        if masses.len() != positions.len() || masses.len() != velocities.len() {
            return Err(SymplecticError::InvalidState {
                what: "planets",
                reason: format!(
                    "{} masses, {} positions, {} velocities: lengths differ",
                    masses.len(),
                    positions.len(),
                    velocities.len()
                ),
            });
        }
        for (i, ((&m, q), v)) in masses.iter().zip(positions).zip(velocities).enumerate() {
            positive("planet mass", m)?;
            if !(q.iter().chain(v.iter()).all(|x| x.is_finite())) || q.norm() == 0.0 {
                return Err(SymplecticError::InvalidState {
                    what: "planets",
                    reason: format!("planet {}: position {q:?}, velocity {v:?} must be finite, position non-zero", i + 1),
                });
            }
        }
        let total: f64 = sun_mass + masses.iter().sum::<f64>();
        // Velocity of the barycentre in the heliocentric frame (the Sun is at rest there).
        let v_cm: Vec3 = masses
            .iter()
            .zip(velocities)
            .map(|(&m, v)| v * m)
            .sum::<Vec3>()
            / total;
        let momenta = masses
            .iter()
            .zip(velocities)
            .map(|(&m, v)| (v - v_cm) * m)
            .collect();
        Ok(Self {
            g,
            sun_mass,
            masses: masses.to_vec(),
            positions: positions.to_vec(),
            momenta,
            time: 0.0,
            work: WorkCounters::default(),
            names: Vec::new(),
            radii: Vec::new(),
        })
    }

    /// The same planets with names (reported in statuses: `hill_sphere_Neptune`) and physical
    /// radii (a particle closer than a radius to the planet's centre has collided), one of
    /// each per planet in order.
    pub fn with_names_and_radii(
        mut self,
        names: &[&str],
        radii: &[f64],
    ) -> Result<Self, SymplecticError> {
        if names.len() != self.len() || radii.len() != self.len() {
            return Err(SymplecticError::InvalidState {
                what: "planets",
                reason: format!(
                    "{} planets, {} names, {} radii: need one name and one radius per planet",
                    self.len(),
                    names.len(),
                    radii.len()
                ),
            });
        }
        if let Some(r) = radii.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
            return Err(SymplecticError::InvalidParameter {
                name: "planet radius",
                value: *r,
                reason: "must be finite and > 0",
            });
        }
        self.names = names.iter().map(|n| n.to_string()).collect();
        self.radii = radii.to_vec();
        Ok(self)
    }

    /// Name of planet `j` (1-based, as in statuses): its given name or `planet_<j>`.
    pub fn name(&self, j: usize) -> String {
        match j.checked_sub(1).and_then(|i| self.names.get(i)) {
            Some(n) => n.clone(),
            None => format!("planet_{j}"),
        }
    }

    /// Physical radius of planet `j` (1-based), if given.
    pub fn radius(&self, j: usize) -> Option<f64> {
        j.checked_sub(1).and_then(|i| self.radii.get(i)).copied()
    }

    /// Number of planets.
    pub fn len(&self) -> usize {
        self.masses.len()
    }

    /// `true` without planets.
    pub fn is_empty(&self) -> bool {
        self.masses.is_empty()
    }

    /// Constant of gravitation.
    pub fn g(&self) -> f64 {
        self.g
    }

    /// Mass of the Sun.
    pub fn sun_mass(&self) -> f64 {
        self.sun_mass
    }

    /// Planet masses.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// Heliocentric positions `Q_i`.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Barycentric momenta `P_i`.
    pub fn momenta(&self) -> &[Vec3] {
        &self.momenta
    }

    /// Time elapsed since the initial state.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Work done by the pieces applied to this state so far ([`WorkCounters`]): one Kepler
    /// solve per planet and [`Planets::kepler_drift`], `n(n−1)/2` force evaluations per
    /// [`Planets::interaction_kick`].
    pub fn work(&self) -> WorkCounters {
        self.work
    }

    /// Barycentric velocities `P_i/m_i` of the planets.
    pub fn barycentric_velocities(&self) -> Vec<Vec3> {
        self.momenta
            .iter()
            .zip(&self.masses)
            .map(|(p, &m)| p / m)
            .collect()
    }

    /// Barycentric position and velocity of the Sun, `q_0 = −Σ m_i Q_i / M` and
    /// `v_0 = −Σ P_i / m_0` (the barycentre at rest at the origin).
    pub fn sun_barycentric_state(&self) -> (Vec3, Vec3) {
        let total = self.sun_mass + self.masses.iter().sum::<f64>();
        let position = -self
            .masses
            .iter()
            .zip(&self.positions)
            .map(|(&m, q)| q * m)
            .sum::<Vec3>()
            / total;
        (position, -self.momenta.iter().sum::<Vec3>() / self.sun_mass)
    }

    /// Heliocentric velocities `v_i − v_0` of the planets.
    pub fn heliocentric_velocities(&self) -> Vec<Vec3> {
        let sun_velocity = self.sun_barycentric_state().1;
        self.barycentric_velocities()
            .into_iter()
            .map(|v| v - sun_velocity)
            .collect()
    }

    /// The state as a flat vector `(Q_1, P_1, Q_2, P_2, ...)` (for Jacobians and checkpoints).
    pub fn state_vector(&self) -> Vec<f64> {
        let mut s = Vec::with_capacity(6 * self.len());
        for (q, p) in self.positions.iter().zip(&self.momenta) {
            s.extend_from_slice(q.as_slice());
            s.extend_from_slice(p.as_slice());
        }
        s
    }

    /// Sets the state from a vector laid out as [`Planets::state_vector`].
    pub fn set_state_vector(&mut self, s: &[f64]) -> Result<(), SymplecticError> {
        if s.len() != 6 * self.len() {
            return Err(SymplecticError::InvalidState {
                what: "planets",
                reason: format!(
                    "state vector of {} values for {} planets",
                    s.len(),
                    self.len()
                ),
            });
        }
        if let Some(k) = s.iter().position(|x| !x.is_finite()) {
            return Err(SymplecticError::InvalidState {
                what: "planets",
                reason: format!(
                    "state vector value {k} (planet {}) is {}: must be finite",
                    k / 6 + 1,
                    s[k]
                ),
            });
        }
        for (i, c) in s.chunks_exact(6).enumerate() {
            self.positions[i] = Vec3::new(c[0], c[1], c[2]);
            self.momenta[i] = Vec3::new(c[3], c[4], c[5]);
        }
        Ok(())
    }

    /// Sets the time (for resuming from a checkpoint).
    pub fn set_time(&mut self, t: f64) {
        self.time = t;
    }

    /// `H_Kepl`, eq. 10.
    pub fn kepler_energy(&self) -> f64 {
        let m0 = self.sun_mass;
        self.masses
            .iter()
            .zip(&self.positions)
            .zip(&self.momenta)
            .map(|((&m, q), p)| {
                0.5 * p.norm_squared() * (1.0 / m + 1.0 / m0) - self.g * m * m0 / q.norm()
            })
            .sum()
    }

    /// `H_Sun`, eq. 11.
    pub fn sun_energy(&self) -> f64 {
        let total: Vec3 = self.momenta.iter().sum();
        let squares: f64 = self.momenta.iter().map(|p| p.norm_squared()).sum();
        0.5 * (total.norm_squared() - squares) / self.sun_mass
    }

    /// `H_Inter`, eq. 12.
    pub fn interaction_energy(&self) -> f64 {
        let mut e = 0.0;
        for i in 0..self.len() {
            for j in i + 1..self.len() {
                e -= self.g * self.masses[i] * self.masses[j]
                    / (self.positions[i] - self.positions[j]).norm();
            }
        }
        e
    }

    /// Total energy `H = H_Kepl + H_Sun + H_Inter` (the barycentric N-body energy).
    pub fn energy(&self) -> f64 {
        self.kepler_energy() + self.sun_energy() + self.interaction_energy()
    }

    /// Piece **A**: the exact flow of `H_Kepl` for `dt` — each planet drifts on its Kepler
    /// orbit with `μ_i = G (m_0 + m_i)`.
    pub fn kepler_drift(&mut self, dt: f64) -> Result<(), SymplecticError> {
        // The planets' drifts are independent: up to `LANES` of them at once through the
        // lanes (the same IEEE operations as `drift_one`, bit for bit), a lane the lanes hand
        // back (see `lanes::drift`) by `drift_one` from its unchanged state.
        let n = self.len();
        for start in (0..n).step_by(LANES) {
            let count = (n - start).min(LANES);
            let live: Mask = std::array::from_fn(|l| l < count);
            let zero = V::splat(0.0);
            let (mut r, mut v): (V3, V3) = ([zero; 3], [zero; 3]);
            let (mut mu, mut factor) = (V::splat(1.0), [1.0; LANES]);
            for (l, f) in factor.iter_mut().enumerate().take(count) {
                let i = start + l;
                let m = self.masses[i];
                *f = 1.0 / m + 1.0 / self.sun_mass;
                mu.0[l] = self.g * (self.sun_mass + m);
                let vi = self.momenta[i] * *f;
                for c in 0..3 {
                    r[c].0[l] = self.positions[i][c];
                    v[c].0[l] = vi[c];
                }
            }
            let r0 = lanes::norm(&r);
            let mut redo: Mask = [false; LANES];
            let iterations = lanes::drift(&mut r, &mut v, r0, mu, V::splat(dt), live, &mut redo);
            for l in 0..count {
                let i = start + l;
                if redo[l] {
                    self.drift_one(i, dt)?;
                } else {
                    self.positions[i] = lanes::lane(&r, l);
                    self.momenta[i] = lanes::lane(&v, l) / factor[l];
                    self.work.kepler_solves += 1;
                    self.work.kepler_iterations += u64::from(iterations[l]);
                }
            }
        }
        self.time += dt;
        Ok(())
    }

    /// Planet `i`'s Kepler drift alone (the scalar path of [`Planets::kepler_drift`]).
    fn drift_one(&mut self, i: usize, dt: f64) -> Result<(), SymplecticError> {
        let m0 = self.sun_mass;
        let m = self.masses[i];
        let factor = 1.0 / m + 1.0 / m0;
        let mut v = self.momenta[i] * factor;
        let info =
            kepler::drift(&mut self.positions[i], &mut v, self.g * (m0 + m), dt).map_err(|e| {
                match e {
                    SymplecticError::InvalidState { reason, .. } => SymplecticError::InvalidState {
                        what: "planet Kepler drift",
                        reason: format!("planet {}: {reason}", i + 1),
                    },
                    other => other,
                }
            })?;
        self.work.kepler_solves += 1;
        self.work.kepler_iterations += u64::from(info.iterations);
        self.momenta[i] = v / factor;
        Ok(())
    }

    /// Piece **B**: the exact flow of `H_Inter` for `dt` (positions fixed, momenta kicked).
    pub fn interaction_kick(&mut self, dt: f64) {
        let n = self.len();
        self.work.force_evaluations += (n * n.saturating_sub(1) / 2) as u64;
        for i in 0..n {
            for j in i + 1..n {
                let d = self.positions[j] - self.positions[i];
                let r2 = d.norm_squared();
                let f = d * (self.g * self.masses[i] * self.masses[j] / (r2 * r2.sqrt()) * dt);
                self.momenta[i] += f;
                self.momenta[j] -= f;
            }
        }
    }

    /// Piece **C**: the exact flow of `H_Sun` for `dt` (momenta fixed, each position drifts
    /// by `dt/m_0 Σ_{j≠i} P_j`).
    pub fn sun_drift(&mut self, dt: f64) {
        let total: Vec3 = self.momenta.iter().sum();
        let k = dt / self.sun_mass;
        for (q, p) in self.positions.iter_mut().zip(&self.momenta) {
            *q += (total - p) * k;
        }
    }

    /// The first planet whose state is not finite (1-based), if any.
    pub fn first_non_finite(&self) -> Option<usize> {
        self.positions
            .iter()
            .zip(&self.momenta)
            .position(|(q, p)| !q.iter().chain(p.iter()).all(|x| x.is_finite()))
            .map(|i| i + 1)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn planet() -> impl Strategy<Value = (f64, [f64; 3], [f64; 3])> {
        (
            1e-10f64..1e-3,
            prop::array::uniform3(-40.0f64..40.0),
            prop::array::uniform3(-0.02f64..0.02),
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// The lanes' drift of several planets equals each planet's scalar drift bit for bit
        /// (positions, momenta, work), for any count of planets (full and partial chunks of
        /// lanes) and any conic (the velocities reach beyond escape).
        #[test]
        fn lanes_drift_equals_the_scalar_drift(
            bodies in prop::collection::vec(planet(), 1..10),
            dt in prop_oneof![-2000.0f64..-1.0, 1.0f64..2000.0],
        ) {
            let masses: Vec<f64> = bodies.iter().map(|b| b.0).collect();
            let q: Vec<Vec3> = bodies.iter().map(|b| Vec3::from(b.1) + Vec3::new(0.5, 0.0, 0.0)).collect();
            let v: Vec<Vec3> = bodies.iter().map(|b| Vec3::from(b.2)).collect();
            let Ok(start) = Planets::from_heliocentric(2.959_122_082_86e-4, 1.0, &masses, &q, &v) else {
                return Ok(());
            };
            let mut lanes = start.clone();
            let lanes_result = lanes.kepler_drift(dt);
            let mut scalar = start.clone();
            let scalar_result = (0..scalar.len()).try_for_each(|i| scalar.drift_one(i, dt));
            prop_assert_eq!(lanes_result.is_ok(), scalar_result.is_ok());
            let bits = |p: &Planets| -> Vec<u64> {
                p.positions.iter().chain(&p.momenta).flat_map(|x| x.iter().map(|c| c.to_bits())).collect()
            };
            prop_assert_eq!(bits(&lanes), bits(&scalar));
            prop_assert_eq!(lanes.work, scalar.work);
        }
    }
}
