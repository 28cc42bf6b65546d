//! The volume-map cache: a hit is bit-identical to a cold build, every key field misses, and
//! corrupt, truncated, foreign or other-version files are refused with named errors.

use std::fs;
use std::path::{Path, PathBuf};

use sph_core::{Aabb, BoxSdf, Inverted, Sdf, Sphere, Vec3};
use sph_kernels::KernelKind;
use sph_solver::boundary::{
    Boundary, CacheUse, Interpolation, VolumeMap, VolumeMapBoundary, VolumeMapCache, VolumeMapKey,
    VolumeMapOptions,
};
use sph_solver::{MapFileProblem, SolverError};

/// A fresh directory under the system's temporary directory, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let d = std::env::temp_dir().join(format!("sph-solver-vmap-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        Self(d)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

const H: f64 = 0.1;

fn domain() -> Aabb<f64> {
    Aabb::new(Vec3::zeros(), Vec3::new(0.5, 0.4, 0.3)).unwrap()
}

/// A small tank (edges and corners: the quadrature runs) and a sphere.
fn solids() -> Vec<Box<dyn Sdf<f64>>> {
    vec![
        Box::new(Inverted(BoxSdf::new(domain()).unwrap())),
        Box::new(Sphere::new(Vec3::new(0.25, 0.2, 0.15), 0.08).unwrap()),
    ]
}

fn options() -> VolumeMapOptions {
    VolumeMapOptions {
        polar_directions: 6,
        azimuth_directions: 12,
        ..VolumeMapOptions::default()
    }
}

fn build(cache: Option<&VolumeMapCache>) -> VolumeMapBoundary<f64> {
    VolumeMapBoundary::with_cache(
        solids(),
        KernelKind::CubicSpline,
        H,
        domain(),
        0.0,
        options(),
        cache,
    )
    .unwrap()
}

/// Ψ and ∇Ψ on a lattice through the domain and beyond it, as bit patterns.
fn samples(b: &VolumeMapBoundary<f64>) -> Vec<[u64; 4]> {
    let mut out = Vec::new();
    for i in 0..=23 {
        for j in 0..=19 {
            for k in 0..=17 {
                let x = Vec3::new(
                    -0.12 + 0.0321 * i as f64,
                    -0.12 + 0.0333 * j as f64,
                    -0.12 + 0.0311 * k as f64,
                );
                let s = b.sample(&x);
                let g = s.volume_gradient;
                out.push([
                    s.volume.to_bits(),
                    g.x.to_bits(),
                    g.y.to_bits(),
                    g.z.to_bits(),
                ]);
            }
        }
    }
    out
}

fn uses(b: &VolumeMapBoundary<f64>) -> Vec<CacheUse> {
    b.maps().iter().map(|m| m.stats().cache).collect()
}

#[test]
fn cache_hit_is_bit_identical_to_a_cold_build() {
    let dir = TempDir::new("hit");
    let cache = VolumeMapCache::new(&dir.0).unwrap();
    let cold = build(None);
    assert_eq!(uses(&cold), [CacheUse::NoCache; 2]);
    let stored = build(Some(&cache));
    assert_eq!(uses(&stored), [CacheUse::Stored; 2]);
    assert_eq!(fs::read_dir(&dir.0).unwrap().count(), 2);
    let hit = build(Some(&cache));
    assert_eq!(uses(&hit), [CacheUse::Hit; 2]);
    assert!(hit.cache_warnings().is_empty());
    assert!(
        hit.maps()[0].stats().quadrature_nodes > 0,
        "the tank ran the quadrature"
    );
    let reference = samples(&cold);
    assert!(reference.iter().any(|s| f64::from_bits(s[0]) > 0.0));
    assert!(
        samples(&stored) == reference,
        "a built map differs from a cold build"
    );
    assert!(
        samples(&hit) == reference,
        "a cache hit differs from a cold build"
    );
    for (a, b) in cold.maps().iter().zip(hit.maps()) {
        let (a, b) = (a.stats(), b.stats());
        assert_eq!(
            (
                a.dims,
                a.nodes,
                a.band_nodes,
                a.quadrature_nodes,
                a.stored_nodes
            ),
            (
                b.dims,
                b.nodes,
                b.band_nodes,
                b.quadrature_nodes,
                b.stored_nodes
            )
        );
    }
}

#[test]
fn trilinear_maps_are_cached_bit_identically() {
    let dir = TempDir::new("trilinear");
    let cache = VolumeMapCache::new(&dir.0).unwrap();
    let opts = VolumeMapOptions {
        interpolation: Interpolation::TrilinearCorrection,
        ..options()
    };
    let make = |c| {
        VolumeMapBoundary::with_cache(solids(), KernelKind::Poly6, H, domain(), 0.0, opts, c)
            .unwrap()
    };
    let cold = make(None);
    make(Some(&cache));
    let hit = make(Some(&cache));
    assert_eq!(uses(&hit), [CacheUse::Hit; 2]);
    assert!(samples(&hit) == samples(&cold));
}

/// The key of the first solid with one input changed.
fn key_with(
    solid: &dyn Sdf<f64>,
    kernel: KernelKind,
    h: f64,
    domain: Aabb<f64>,
    options: VolumeMapOptions,
) -> VolumeMapKey {
    VolumeMapKey::new(solid, kernel, h, &domain, &options).expect("cacheable")
}

#[test]
fn every_key_field_changes_the_key() {
    let tank = Inverted(BoxSdf::new(domain()).unwrap());
    let base = key_with(&tank, KernelKind::CubicSpline, H, domain(), options());
    // Equal inputs give equal keys (the cache can hit at all).
    assert_eq!(
        base,
        key_with(&tank, KernelKind::CubicSpline, H, domain(), options())
    );
    let o = options();
    let grown = Aabb::new(Vec3::zeros(), Vec3::new(0.5, 0.4, 0.31)).unwrap();
    let other_box = Inverted(BoxSdf::new(grown).unwrap());
    let not_inverted = BoxSdf::new(domain()).unwrap();
    let changed: Vec<(&str, VolumeMapKey)> = vec![
        (
            "solid geometry",
            key_with(&other_box, KernelKind::CubicSpline, H, domain(), o),
        ),
        (
            "solid inversion",
            key_with(&not_inverted, KernelKind::CubicSpline, H, domain(), o),
        ),
        (
            "kernel",
            key_with(&tank, KernelKind::WendlandC2, H, domain(), o),
        ),
        (
            "support radius",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H * (1.0 + f64::EPSILON),
                domain(),
                o,
            ),
        ),
        (
            "domain",
            key_with(&tank, KernelKind::CubicSpline, H, grown, o),
        ),
        (
            "cells_per_support",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H,
                domain(),
                VolumeMapOptions {
                    cells_per_support: 5,
                    ..o
                },
            ),
        ),
        (
            "polar_directions",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H,
                domain(),
                VolumeMapOptions {
                    polar_directions: 7,
                    ..o
                },
            ),
        ),
        (
            "azimuth_directions",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H,
                domain(),
                VolumeMapOptions {
                    azimuth_directions: 13,
                    ..o
                },
            ),
        ),
        (
            "ray_samples",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H,
                domain(),
                VolumeMapOptions {
                    ray_samples: 9,
                    ..o
                },
            ),
        ),
        (
            "max_nodes",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H,
                domain(),
                VolumeMapOptions {
                    max_nodes: o.max_nodes - 1,
                    ..o
                },
            ),
        ),
        (
            "interpolation",
            key_with(
                &tank,
                KernelKind::CubicSpline,
                H,
                domain(),
                VolumeMapOptions {
                    interpolation: Interpolation::TrilinearCorrection,
                    ..o
                },
            ),
        ),
    ];
    // Precision: the same tank in f32.
    let d32 = Aabb::new(Vec3::zeros(), Vec3::new(0.5f32, 0.4, 0.3)).unwrap();
    let tank32 = Inverted(BoxSdf::new(d32).unwrap());
    let k32 = VolumeMapKey::new(&tank32, KernelKind::CubicSpline, H as f32, &d32, &o).unwrap();
    assert_ne!(base.as_bytes(), k32.as_bytes(), "precision");
    assert_ne!(base.digest_hex(), k32.digest_hex(), "precision");
    for (field, key) in &changed {
        assert_ne!(&base, key, "{field}");
        assert_ne!(base.digest_hex(), key.digest_hex(), "{field}");
    }
}

#[test]
fn a_changed_input_misses_the_cache() {
    let dir = TempDir::new("miss");
    let cache = VolumeMapCache::new(&dir.0).unwrap();
    let sphere = || -> Vec<Box<dyn Sdf<f64>>> {
        vec![Box::new(
            Sphere::new(Vec3::new(0.25, 0.2, 0.15), 0.08).unwrap(),
        )]
    };
    let make = |kernel, h: f64, opts| {
        VolumeMapBoundary::with_cache(sphere(), kernel, h, domain(), 0.0, opts, Some(&cache))
            .unwrap()
    };
    assert_eq!(
        uses(&make(KernelKind::CubicSpline, H, options())),
        [CacheUse::Stored]
    );
    assert_eq!(
        uses(&make(KernelKind::CubicSpline, H, options())),
        [CacheUse::Hit]
    );
    assert_eq!(
        uses(&make(KernelKind::Poly6, H, options())),
        [CacheUse::Stored]
    );
    assert_eq!(
        uses(&make(KernelKind::CubicSpline, 0.09, options())),
        [CacheUse::Stored]
    );
    let finer = VolumeMapOptions {
        cells_per_support: 3,
        ..options()
    };
    assert_eq!(
        uses(&make(KernelKind::CubicSpline, H, finer)),
        [CacheUse::Stored]
    );
    assert_eq!(fs::read_dir(&dir.0).unwrap().count(), 4);
}

/// A solid that does not describe itself.
struct UserSolid;

impl Sdf<f64> for UserSolid {
    fn signed_distance(&self, p: &Vec3<f64>) -> f64 {
        p.y - 0.1
    }
}

#[test]
fn solids_without_a_fingerprint_are_not_cached() {
    let dir = TempDir::new("uncacheable");
    let cache = VolumeMapCache::new(&dir.0).unwrap();
    assert!(VolumeMapKey::new(&UserSolid, KernelKind::Poly6, H, &domain(), &options()).is_none());
    for _ in 0..2 {
        let b = VolumeMapBoundary::with_cache(
            vec![Box::new(UserSolid)],
            KernelKind::Poly6,
            H,
            domain(),
            0.0,
            options(),
            Some(&cache),
        )
        .unwrap();
        assert_eq!(uses(&b), [CacheUse::Uncacheable]);
    }
    assert_eq!(fs::read_dir(&dir.0).unwrap().count(), 0);
}

/// The tank's key and a file holding its map.
fn written(dir: &Path) -> (VolumeMapKey, PathBuf, Vec<u8>) {
    let tank = Inverted(BoxSdf::new(domain()).unwrap());
    let key = key_with(&tank, KernelKind::CubicSpline, H, domain(), options());
    let b = VolumeMapBoundary::new(
        vec![Box::new(tank)],
        KernelKind::CubicSpline,
        H,
        domain(),
        0.0,
        options(),
    )
    .unwrap();
    let path = dir.join("tank.vmap");
    b.maps()[0].write_file(&path, &key).unwrap();
    let bytes = fs::read(&path).unwrap();
    (key, path, bytes)
}

/// The refusal of `bytes` as the map of `key`, with the directory replaced by `<dir>`.
fn refusal(dir: &Path, key: &VolumeMapKey, bytes: &[u8]) -> (MapFileProblem, String) {
    let path = dir.join("damaged.vmap");
    fs::write(&path, bytes).unwrap();
    let e = VolumeMap::<f64>::read_file(&path, key).unwrap_err();
    let message = e.to_string().replace(&dir.display().to_string(), "<dir>");
    match e {
        SolverError::MapFile { path: p, problem } => {
            assert_eq!(p, path);
            (problem, message)
        }
        e => panic!("not a map-file error: {e}"),
    }
}

#[test]
fn damaged_and_foreign_files_are_refused_with_named_errors() {
    let dir = TempDir::new("damaged");
    let (key, path, bytes) = written(&dir.0);
    assert!(VolumeMap::<f64>::read_file(&path, &key).is_ok());
    let n = bytes.len();

    let (p, m) = refusal(&dir.0, &key, &bytes[..n - 1000]);
    assert_eq!(
        p,
        MapFileProblem::Truncated {
            expected: n as u64,
            found: n as u64 - 1000
        }
    );
    insta::assert_snapshot!("truncated", m);

    let (p, m) = refusal(&dir.0, &key, &bytes[..5]);
    assert!(matches!(p, MapFileProblem::Truncated { .. }), "{p:?}");
    insta::assert_snapshot!("truncated_in_magic", m);

    let mut longer = bytes.clone();
    longer.extend_from_slice(b"more");
    let (p, m) = refusal(&dir.0, &key, &longer);
    assert!(matches!(p, MapFileProblem::TrailingBytes { .. }), "{p:?}");
    insta::assert_snapshot!("trailing_bytes", m);

    // One flipped bit in every eighth of the payload: never loaded.
    for at in (1..8).map(|e| 100 + (n - 150) * e / 8) {
        let mut corrupt = bytes.clone();
        corrupt[at] ^= 0x10;
        let (p, m) = refusal(&dir.0, &key, &corrupt);
        assert_eq!(p, MapFileProblem::ChecksumMismatch, "byte {at}");
        if at == 100 + (n - 150) / 8 {
            insta::assert_snapshot!("checksum_mismatch", m);
        }
    }

    let (p, m) = refusal(&dir.0, &key, b"# a scene file, not a map\n[fluid]\n");
    assert_eq!(p, MapFileProblem::BadMagic);
    insta::assert_snapshot!("bad_magic", m);

    let mut other_version = bytes.clone();
    other_version[8..12].copy_from_slice(&99u32.to_le_bytes());
    let (p, m) = refusal(&dir.0, &key, &other_version);
    assert_eq!(
        p,
        MapFileProblem::UnsupportedVersion {
            found: 99,
            supported: sph_solver::boundary::volume_map::FORMAT_VERSION
        }
    );
    insta::assert_snapshot!("unsupported_version", m);

    // A valid file of another map (another kernel) at this key's place.
    let poly6 = key_with(
        &Inverted(BoxSdf::new(domain()).unwrap()),
        KernelKind::Poly6,
        H,
        domain(),
        options(),
    );
    let (p, m) = refusal(&dir.0, &poly6, &bytes);
    assert_eq!(p, MapFileProblem::ForeignKey);
    insta::assert_snapshot!("foreign_key", m);

    let e = VolumeMap::<f64>::read_file(&dir.0.join("missing.vmap"), &key).unwrap_err();
    assert!(
        matches!(
            &e,
            SolverError::MapFile {
                problem: MapFileProblem::Io {
                    operation: "read",
                    ..
                },
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_refused_cache_file_is_rebuilt_replaced_and_reported() {
    let dir = TempDir::new("replace");
    let cache = VolumeMapCache::new(&dir.0).unwrap();
    let cold = build(Some(&cache));
    let tank_key = key_with(
        &Inverted(BoxSdf::new(domain()).unwrap()),
        KernelKind::CubicSpline,
        H,
        domain(),
        options(),
    );
    let path = cache.path(&tank_key);
    let bytes = fs::read(&path).unwrap();
    fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let rebuilt = build(Some(&cache));
    assert_eq!(uses(&rebuilt), [CacheUse::Replaced, CacheUse::Hit]);
    assert_eq!(rebuilt.cache_warnings().len(), 1);
    let warning = rebuilt.cache_warnings()[0].to_string();
    assert!(
        warning.contains(&path.display().to_string()) && warning.contains("truncated"),
        "{warning}"
    );
    assert!(samples(&rebuilt) == samples(&cold));
    assert_eq!(uses(&build(Some(&cache))), [CacheUse::Hit; 2]);
    // The replacement is a whole file (only the recorded build time differs).
    assert_eq!(fs::read(&path).unwrap().len(), bytes.len());
}

#[test]
fn concurrent_builds_of_one_map_leave_a_valid_file() {
    let dir = TempDir::new("concurrent");
    let cache = VolumeMapCache::new(&dir.0).unwrap();
    let cold = samples(&build(None));
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..3).map(|_| s.spawn(|| build(Some(&cache)))).collect();
        for h in handles {
            let b = h.join().unwrap();
            assert!(b.cache_warnings().is_empty(), "{:?}", b.cache_warnings());
            assert!(samples(&b) == cold);
        }
    });
    // Two map files, no temporary files left behind, and both load.
    let names: Vec<_> = fs::read_dir(&dir.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    assert!(names
        .iter()
        .all(|n| n.ends_with(".vmap") && !n.starts_with('.')));
    let hit = build(Some(&cache));
    assert_eq!(uses(&hit), [CacheUse::Hit; 2]);
    assert!(samples(&hit) == cold);
}
