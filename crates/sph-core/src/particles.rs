use crate::{CoreError, Real, Vec3};

/// Checks that every position is finite; the error names the first offending particle and axis.
pub fn validate_finite_positions<R: Real>(positions: &[Vec3<R>]) -> Result<(), CoreError> {
    for (index, p) in positions.iter().enumerate() {
        for (axis, name) in ['x', 'y', 'z'].into_iter().enumerate() {
            if !p[axis].is_finite_value() {
                return Err(CoreError::NonFinitePosition {
                    index,
                    axis: name,
                    value: p[axis].as_f64(),
                });
            }
        }
    }
    Ok(())
}

/// Reorders `data` so that `data_new[k] = data_old[permutation[k]]`, using `scratch` as the
/// second buffer (the two are swapped, so no allocation happens once `scratch` has grown).
///
/// The permutation is not re-validated here (this is the hot path); use
/// [`ParticleSet::permute`], which validates once for all arrays.
///
/// # Panics
/// Panics if an entry of `permutation` is out of range for `data` (a caller bug, not user input).
pub fn apply_permutation<T: Copy>(data: &mut Vec<T>, permutation: &[u32], scratch: &mut Vec<T>) {
    scratch.clear();
    scratch.extend(permutation.iter().map(|&i| data[i as usize]));
    std::mem::swap(data, scratch);
}

/// Structure-of-arrays particle set: one array per attribute, all of the same length.
///
/// Units are the caller's; the SPH crates use SI (m, m/s, kg, kg/m³). Solvers keep their own
/// extra per-particle arrays beside this set and reorder them with the same permutation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParticleSet<R: Real> {
    /// Positions.
    pub positions: Vec<Vec3<R>>,
    /// Velocities.
    pub velocities: Vec<Vec3<R>>,
    /// Masses.
    pub masses: Vec<R>,
    /// Densities (the last computed value).
    pub densities: Vec<R>,
}

impl<R: Real> ParticleSet<R> {
    /// An empty set.
    pub fn new() -> Self {
        Self {
            positions: Vec::new(),
            velocities: Vec::new(),
            masses: Vec::new(),
            densities: Vec::new(),
        }
    }

    /// Particles at `positions`, at rest, each with `mass` and density `rest_density`.
    pub fn from_positions(positions: Vec<Vec3<R>>, mass: R, rest_density: R) -> Self {
        let n = positions.len();
        Self {
            positions,
            velocities: vec![Vec3::zeros(); n],
            masses: vec![mass; n],
            densities: vec![rest_density; n],
        }
    }

    /// Appends one particle.
    pub fn push(&mut self, position: Vec3<R>, velocity: Vec3<R>, mass: R, density: R) {
        self.positions.push(position);
        self.velocities.push(velocity);
        self.masses.push(mass);
        self.densities.push(density);
    }

    /// Reserves room for `additional` more particles in every array, failing (rather than
    /// aborting) when the memory cannot be had: for sizes a user's input sets.
    pub fn try_reserve(
        &mut self,
        additional: usize,
    ) -> Result<(), std::collections::TryReserveError> {
        self.positions.try_reserve(additional)?;
        self.velocities.try_reserve(additional)?;
        self.masses.try_reserve(additional)?;
        self.densities.try_reserve(additional)
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// `true` when the set holds no particle.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Checks array lengths and that positions and velocities are finite.
    pub fn validate(&self) -> Result<(), CoreError> {
        let n = self.positions.len();
        for (what, len) in [
            ("velocities", self.velocities.len()),
            ("masses", self.masses.len()),
            ("densities", self.densities.len()),
        ] {
            if len != n {
                return Err(CoreError::LengthMismatch {
                    what,
                    found: len,
                    expected: n,
                });
            }
        }
        validate_finite_positions(&self.positions)?;
        for (index, v) in self.velocities.iter().enumerate() {
            if let Some(axis) = (0..3).find(|&a| !v[a].is_finite_value()) {
                return Err(CoreError::NonFiniteVelocity {
                    index,
                    axis: ['x', 'y', 'z'][axis],
                    value: v[axis].as_f64(),
                });
            }
        }
        Ok(())
    }

    /// Reorders every attribute by `permutation` (`new[k] = old[permutation[k]]`), e.g. the
    /// cell order returned by the neighbour search, using `scratch` so that no allocation
    /// happens once it has grown. The permutation is validated (length, range, no repeats).
    pub fn permute(
        &mut self,
        permutation: &[u32],
        scratch: &mut PermutationScratch<R>,
    ) -> Result<(), CoreError> {
        validate_permutation(permutation, self.len(), &mut scratch.seen)?;
        apply_permutation(&mut self.positions, permutation, &mut scratch.vectors);
        apply_permutation(&mut self.velocities, permutation, &mut scratch.vectors);
        apply_permutation(&mut self.masses, permutation, &mut scratch.scalars);
        apply_permutation(&mut self.densities, permutation, &mut scratch.scalars);
        Ok(())
    }
}

/// Reusable buffers for [`ParticleSet::permute`].
#[derive(Debug, Clone, Default)]
pub struct PermutationScratch<R: Real> {
    vectors: Vec<Vec3<R>>,
    scalars: Vec<R>,
    seen: Vec<bool>,
}

fn validate_permutation(perm: &[u32], n: usize, seen: &mut Vec<bool>) -> Result<(), CoreError> {
    if perm.len() != n {
        return Err(CoreError::LengthMismatch {
            what: "permutation",
            found: perm.len(),
            expected: n,
        });
    }
    seen.clear();
    seen.resize(n, false);
    for (position, &value) in perm.iter().enumerate() {
        let i = value as usize;
        if i >= n || seen[i] {
            return Err(CoreError::InvalidPermutation { position, value });
        }
        seen[i] = true;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn validate_names_particle_and_axis() {
        let mut set = ParticleSet::from_positions(vec![Vec3::new(0.0f32, 0.0, 0.0); 3], 1.0, 1.0);
        set.positions[2].z = f32::NAN;
        match set.validate() {
            Err(CoreError::NonFinitePosition {
                index: 2,
                axis: 'z',
                ..
            }) => {}
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn permute_rejects_bad_permutations() {
        let mut set = ParticleSet::from_positions(vec![Vec3::new(0.0f64, 0.0, 0.0); 3], 1.0, 1.0);
        let mut s = PermutationScratch::default();
        assert!(matches!(
            set.permute(&[0, 1], &mut s),
            Err(CoreError::LengthMismatch { .. })
        ));
        assert_eq!(
            set.permute(&[0, 1, 1], &mut s),
            Err(CoreError::InvalidPermutation {
                position: 2,
                value: 1
            })
        );
        assert_eq!(
            set.permute(&[0, 7, 1], &mut s),
            Err(CoreError::InvalidPermutation {
                position: 1,
                value: 7
            })
        );
    }

    proptest! {
        #[test]
        fn permute_moves_every_attribute_together(keys in proptest::collection::vec(any::<u16>(), 0..64)) {
            let n = keys.len();
            let mut set = ParticleSet::<f64>::new();
            for (i, &k) in keys.iter().enumerate() {
                let x = i as f64;
                set.push(Vec3::new(x, k as f64, 0.0), Vec3::new(-x, 0.0, 0.0), x + 1.0, 2.0 * x);
            }
            let mut perm: Vec<u32> = (0..n as u32).collect();
            perm.sort_by_key(|&i| (keys[i as usize], i));
            let mut s = PermutationScratch::default();
            set.permute(&perm, &mut s).unwrap();
            for (k, &pk) in perm.iter().enumerate() {
                let i = pk as f64;
                prop_assert_eq!(set.positions[k].x, i);
                prop_assert_eq!(set.velocities[k].x, -i);
                prop_assert_eq!(set.masses[k], i + 1.0);
                prop_assert_eq!(set.densities[k], 2.0 * i);
            }
            prop_assert!(set.positions.windows(2).all(|w| w[0].y <= w[1].y));
        }
    }
}
