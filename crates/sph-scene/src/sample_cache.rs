//! The fluid sample of a scene, kept from the particle checks of [`Scene::check`] for the
//! set-up that follows them ([`Scene::fluid_particles`]), so that loading and running a
//! scene samples its lattice (and builds the grids of its fluid meshes) once.

use std::fmt;
use std::sync::{Arc, Mutex};

use sph_core::{TriangleMesh, Vec3};

use crate::SceneError;

/// The sampled positions (m) of each fluid, in file order.
pub(crate) type FluidSample = Arc<Vec<Vec<Vec3<f64>>>>;

/// What a sample depends on: the spacing and each fluid's region (a block's corners, a
/// mesh by identity: meshes are shared, placed, behind an `Arc` that the cache holds too,
/// so they cannot change in place).
#[derive(Clone)]
pub(crate) struct SampleKey {
    pub(crate) spacing: f64,
    pub(crate) fluids: Vec<FluidKey>,
}

/// One fluid's part of a [`SampleKey`].
#[derive(Clone)]
pub(crate) enum FluidKey {
    Block {
        min: [f64; 3],
        max: [f64; 3],
    },
    Mesh(Arc<TriangleMesh<f64>>),
    Cylinder {
        base_center: [f64; 3],
        radius_height: [f64; 2],
    },
}

impl PartialEq for SampleKey {
    fn eq(&self, other: &Self) -> bool {
        let bits = |v: &[f64; 3]| v.map(f64::to_bits);
        self.spacing.to_bits() == other.spacing.to_bits()
            && self.fluids.len() == other.fluids.len()
            && self
                .fluids
                .iter()
                .zip(&other.fluids)
                .all(|pair| match pair {
                    (FluidKey::Block { min: a, max: b }, FluidKey::Block { min: c, max: d }) => {
                        bits(a) == bits(c) && bits(b) == bits(d)
                    }
                    (FluidKey::Mesh(a), FluidKey::Mesh(b)) => Arc::ptr_eq(a, b),
                    (
                        FluidKey::Cylinder {
                            base_center: a,
                            radius_height: [r, h],
                        },
                        FluidKey::Cylinder {
                            base_center: c,
                            radius_height: [q, k],
                        },
                    ) => {
                        bits(a) == bits(c)
                            && r.to_bits() == q.to_bits()
                            && h.to_bits() == k.to_bits()
                    }
                    _ => false,
                })
    }
}

struct Entry {
    key: SampleKey,
    sample: FluidSample,
}

/// Up to [`FluidSampleCache::CAPACITY`] samples, shared by clones of a scene (the scene and
/// its [`Scene::quick`](crate::Scene::quick) variant), each used only for a scene whose
/// spacing and fluids are those it was sampled from. Its `Debug` form is constant, so that
/// a scene's description does not depend on what was cached.
#[derive(Clone, Default)]
pub(crate) struct FluidSampleCache(Arc<Mutex<Vec<Entry>>>);

impl fmt::Debug for FluidSampleCache {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("FluidSampleCache")
    }
}

impl FluidSampleCache {
    /// A scene and its `[quick]` variant.
    const CAPACITY: usize = 2;

    /// The sample for `key`: the cached one, or `sample()`'s, then cached.
    pub(crate) fn get_or_sample(
        &self,
        key: SampleKey,
        sample: impl FnOnce() -> Result<Vec<Vec<Vec3<f64>>>, SceneError>,
    ) -> Result<FluidSample, SceneError> {
        let found = |entries: &Vec<Entry>| {
            entries
                .iter()
                .find(|e| e.key == key)
                .map(|e| Arc::clone(&e.sample))
        };
        // A poisoned lock only means another thread panicked while holding it; the entries
        // are whole (pushed and removed under the lock), so they stay usable.
        let lock = || self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = found(&lock()) {
            return Ok(s);
        }
        let fresh: FluidSample = Arc::new(sample()?);
        let mut entries = lock();
        if entries.len() == Self::CAPACITY {
            entries.remove(0);
        }
        entries.push(Entry {
            key,
            sample: Arc::clone(&fresh),
        });
        Ok(fresh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    fn block(spacing: f64, top: f64) -> SampleKey {
        SampleKey {
            spacing,
            fluids: vec![FluidKey::Block {
                min: [0.0; 3],
                max: [1.0, top, 1.0],
            }],
        }
    }

    #[test]
    fn samples_once_per_key_and_keeps_two() {
        let cache = FluidSampleCache::default();
        let calls = Cell::new(0);
        let get = |key: SampleKey| {
            cache
                .get_or_sample(key, || {
                    calls.set(calls.get() + 1);
                    Ok(vec![vec![Vec3::new(calls.get() as f64, 0.0, 0.0)]])
                })
                .unwrap()
        };
        let a = get(block(0.1, 1.0));
        assert!(Arc::ptr_eq(&a, &get(block(0.1, 1.0))));
        assert_eq!(calls.get(), 1);
        // Another spacing, another region: sampled anew.
        let b = get(block(0.05, 1.0));
        assert_eq!(calls.get(), 2);
        assert!(!Arc::ptr_eq(&a, &b));
        assert!(Arc::ptr_eq(&a, &get(block(0.1, 1.0))));
        get(block(0.1, 0.9));
        assert_eq!(calls.get(), 3);
        // Capacity two: the oldest entry (spacing 0.1, top 1.0) was dropped.
        get(block(0.1, 1.0));
        assert_eq!(calls.get(), 4);
        // A clone shares the cache (a scene and its quick copy).
        let clone = cache.clone();
        clone
            .get_or_sample(block(0.1, 1.0), || unreachable!())
            .unwrap();
        // Equal meshes by identity only.
        let mesh = Arc::new(
            TriangleMesh::new(
                vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()],
                vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            )
            .unwrap(),
        );
        let m = |mesh: &Arc<TriangleMesh<f64>>| SampleKey {
            spacing: 0.1,
            fluids: vec![FluidKey::Mesh(Arc::clone(mesh))],
        };
        assert!(m(&mesh) == m(&mesh));
        assert!(m(&mesh) != m(&Arc::new((*mesh).clone())));
    }
}
