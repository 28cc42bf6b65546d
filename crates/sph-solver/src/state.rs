//! What a solver carries from one frame to the next besides the [`sph_core::ParticleSet`]:
//! the [`SolverState`] of resumable runs.

use sph_core::Real;

use crate::SolverError;

/// Everything a solver carries from one frame to the next besides the `ParticleSet`:
/// [`crate::FluidSolver::save_state`] writes it, [`crate::FluidSolver::restore_state`]
/// puts it into a fresh solver with the same parameters, which then continues bit for bit
/// as the solver that wrote it would have.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SolverState<R> {
    /// [`crate::FluidSolver::name`] of the solver that wrote it.
    pub solver: String,
    /// Frames ([`crate::FluidSolver::step`] calls, failed ones included) completed.
    pub frames: u64,
    /// Carried per-particle (or per-passive-point) data in the current particle order, by
    /// name, flattened (a `Vec3` field is 3 values per point, a symmetric tensor 6, …).
    pub arrays: Vec<(String, Vec<R>)>,
}

impl<R> SolverState<R> {
    /// A state of solver `solver` after `frames` frames, carrying `arrays` (for readers of
    /// checkpoint files).
    pub fn new(solver: impl Into<String>, frames: u64, arrays: Vec<(String, Vec<R>)>) -> Self {
        Self {
            solver: solver.into(),
            frames,
            arrays,
        }
    }

    /// The array named `name`, if carried.
    pub fn array(&self, name: &str) -> Option<&[R]> {
        self.arrays
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| &v[..])
    }
}

/// One array a solver accepts in [`crate::FluidSolver::restore_state`]: its name and the
/// number of values it must have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArraySpec {
    /// Name of the array.
    pub name: &'static str,
    /// Number of values (points × components).
    pub len: usize,
}

/// The arrays of a saved state matched against what a solver accepts, in the order of
/// `accepted` (`None` where absent). Refuses ([`SolverError::InvalidSolverState`]) an array
/// whose name is not accepted or appears twice, a length other than the accepted one, and a
/// non-finite value, naming the array (and the value's index).
pub fn match_arrays<'a, R: Real>(
    solver: &str,
    arrays: &'a [(String, Vec<R>)],
    accepted: &[ArraySpec],
) -> Result<Vec<Option<&'a [R]>>, SolverError> {
    let refuse = |reason: String| SolverError::InvalidSolverState {
        solver: solver.to_owned(),
        reason,
    };
    let mut found: Vec<Option<&'a [R]>> = vec![None; accepted.len()];
    for (name, values) in arrays {
        let Some(k) = accepted.iter().position(|a| a.name == name) else {
            let names: Vec<_> = accepted.iter().map(|a| a.name).collect();
            return Err(refuse(format!(
                "array `{name}` is not carried by this solver (it carries {names:?})"
            )));
        };
        if found[k].is_some() {
            return Err(refuse(format!("array `{name}` appears twice")));
        }
        if values.len() != accepted[k].len {
            return Err(refuse(format!(
                "array `{name}` has {} values, expected {} for this particle count",
                values.len(),
                accepted[k].len
            )));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite_value()) {
            return Err(refuse(format!(
                "array `{name}` value {i} is not finite ({})",
                values[i].as_f64()
            )));
        }
        found[k] = Some(&values[..]);
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::{match_arrays, ArraySpec};
    use crate::SolverError;

    #[test]
    fn match_arrays_refuses_unknown_duplicate_short_and_non_finite() {
        let spec = [ArraySpec {
            name: "pressure",
            len: 2,
        }];
        let ok = vec![("pressure".to_string(), vec![1.0f64, 2.0])];
        let m = match_arrays("IISPH", &ok, &spec).unwrap();
        assert_eq!(m[0], Some(&[1.0, 2.0][..]));
        assert_eq!(match_arrays::<f64>("IISPH", &[], &spec).unwrap()[0], None);
        let bad = |arrays: Vec<(String, Vec<f64>)>| match match_arrays("IISPH", &arrays, &spec) {
            Err(SolverError::InvalidSolverState { reason, .. }) => reason,
            other => panic!("{other:?}"),
        };
        assert!(bad(vec![("stress".into(), vec![0.0; 2])]).contains("`stress` is not carried"));
        assert!(bad(vec![("pressure".into(), vec![0.0; 3])]).contains("has 3 values, expected 2"));
        assert!(bad(vec![("pressure".into(), vec![0.0, f64::NAN])]).contains("value 1"));
        assert!(bad(vec![
            ("pressure".into(), vec![0.0; 2]),
            ("pressure".into(), vec![0.0; 2])
        ])
        .contains("twice"));
    }
}
