//! Cell coordinates, validation and packed cell keys shared by the grid methods.

// Unsafe: the call of a function compiled for AVX-512, behind the run-time detection of the features; see the SAFETY comment.
#![allow(unsafe_code)]

use rayon::prelude::*;
use sph_core::{Real, Vec3};

use crate::SearchError;

/// Relative margin by which the cell edge exceeds the search radius.
///
/// Cells are `h · (1 + CELL_MARGIN)` wide instead of exactly `h`. The neighbour test is done
/// in the caller's precision `R` (`|x_i − x_j|² < h²`), while cell coordinates are computed
/// in `f64` as `floor(x / cell)`. Rounding in either could otherwise place two particles that
/// pass the test two cells apart (e.g. at coordinates of 10⁷ cells, where the ulp of `x/cell`
/// is ~2·10⁻⁹ cells). The test accepts pairs closer than `h(1 + 1.5 ε_R)` at most, and the
/// `f64` division errs by at most `|x/cell| · 1.1·10⁻¹⁶ ≤ 2.4·10⁻⁷` cells inside the `i32`
/// range, so `10⁻⁶` covers both for `f32` (ε = 1.2·10⁻⁷) and `f64`. This is the one
/// deviation from Im & Chan's "cell size equal to h"; it adds 3·10⁻⁶ to the candidate volume.
pub const CELL_MARGIN: f64 = 1e-6;

/// Largest |cell coordinate| accepted, leaving room for the ±1 neighbour offsets.
const CELL_LIMIT: f64 = (i32::MAX - 2) as f64;

/// Squared distance `dx² + dy² + dz²`, evaluated in this exact order by every method and by
/// the oracle, so that ties at the radius are decided identically.
#[inline(always)]
pub fn squared_distance<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> R {
    let dx = a.x - b.x;
    let dy = a.y - b.y;
    let dz = a.z - b.z;
    dx * dx + dy * dy + dz * dz
}

/// The neighbour criterion of this crate: `j` is a neighbour of `i` when `j ≠ i` and
/// `|x_i − x_j|² < h²` (computed by [`squared_distance`] in `R`). The test is **exclusive**:
/// a particle at distance exactly `h` is not a neighbour (every SPH kernel of `sph-kernels`
/// is zero there). Coincident particles (distance 0) are neighbours of each other.
#[inline(always)]
pub fn is_neighbour<R: Real>(a: &Vec3<R>, b: &Vec3<R>, radius_squared: R) -> bool {
    squared_distance(a, b) < radius_squared
}

/// Checks the radius; returns the cell edge length in `f64`.
pub(crate) fn cell_size<R: Real>(radius: R) -> Result<f64, SearchError> {
    let h = radius.as_f64();
    if !(h.is_finite() && h > 0.0) {
        return Err(SearchError::InvalidRadius { value: h });
    }
    // radius² must also be representable (no overflow to inf, no underflow to 0) in R.
    let r2 = radius * radius;
    if !(r2.is_finite_value() && r2 > R::zero()) {
        return Err(SearchError::InvalidRadius { value: h });
    }
    Ok(h * (1.0 + CELL_MARGIN))
}

#[inline(always)]
fn cell_of_axis(x: f64, cell: f64) -> Option<i32> {
    // Division, not multiplication by an inverse, keeps the error bound of CELL_MARGIN.
    let q = x / cell;
    // NaN and ±∞ fail this test too.
    if q.is_nan() || q.abs() > CELL_LIMIT {
        return None;
    }
    Some(floor_i32(q))
}

/// Validates the positions and writes each particle's integer cell `floor(x / cell)`
/// (Im & Chan 2016, eq. 5), in parallel, and returns the componentwise min and max of the
/// cells (`None` without particles). Errors name the first offending particle.
///
/// The loop is branch-free (an invalid coordinate is replaced by 0 and flagged), so that it
/// vectorises; the bounds are reduced in the same pass.
pub(crate) fn compute_cells<R: Real>(
    positions: &[Vec3<R>],
    cell: f64,
    out: &mut Vec<[i32; 3]>,
) -> Result<CellBounds, SearchError> {
    if positions.len() > u32::MAX as usize / 27 {
        return Err(SearchError::TooManyParticles {
            count: positions.len(),
            limit: u32::MAX as usize / 27,
        });
    }
    out.clear();
    out.resize(positions.len(), [0; 3]);
    if positions.is_empty() {
        return Ok(None);
    }
    type Acc = CellsAcc;
    let id = || -> Acc { (true, [i32::MAX; 3], [i32::MIN; 3]) };
    let merge = |(g0, mut lo, mut hi): Acc, (g1, l, h): Acc| -> Acc {
        for a in 0..3 {
            lo[a] = lo[a].min(l[a]);
            hi[a] = hi[a].max(h[a]);
        }
        (g0 && g1, lo, hi)
    };
    let (ok, lo, hi) = out
        .par_chunks_mut(CELLS_CHUNK)
        .zip(positions.par_chunks(CELLS_CHUNK))
        .map(|(cells, pts)| cells_chunk(cells, pts, cell))
        .reduce(id, merge);
    if ok {
        return Ok(Some((lo, hi)));
    }
    // Slow path, only on error: find the first offending particle deterministically.
    for (index, p) in positions.iter().enumerate() {
        for (a, axis) in ['x', 'y', 'z'].into_iter().enumerate() {
            let x = p[a].as_f64();
            if !x.is_finite() {
                return Err(SearchError::NonFinitePosition {
                    index,
                    axis,
                    value: x,
                });
            }
            if cell_of_axis(x, cell).is_none() {
                return Err(SearchError::CellCoordinateOverflow {
                    index,
                    axis,
                    position: x,
                    radius: cell / (1.0 + CELL_MARGIN),
                    cell: (x / cell).floor(),
                });
            }
        }
    }
    unreachable!("a cell failed but no particle was found at fault")
}

/// One task of [`compute_cells`]: the cells of `pts` into `cells`, whether all were valid,
/// and their componentwise min and max. On x86-64 with AVX-512F and DQ (detected at run
/// time) the same loop is compiled for them, which vectorises its `f64` divisions and
/// conversions; the operations, and so the cells, are the same.
fn cells_chunk<R: Real>(cells: &mut [[i32; 3]], pts: &[Vec3<R>], cell: f64) -> CellsAcc {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
    {
        // SAFETY: the features were detected.
        return unsafe { cells_chunk_avx512(cells, pts, cell) };
    }
    cells_chunk_body(cells, pts, cell)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq")]
unsafe fn cells_chunk_avx512<R: Real>(
    cells: &mut [[i32; 3]],
    pts: &[Vec3<R>],
    cell: f64,
) -> CellsAcc {
    cells_chunk_body(cells, pts, cell)
}

/// Whether every cell was valid, and the componentwise min and max of the cells.
type CellsAcc = (bool, [i32; 3], [i32; 3]);

/// The loop of [`cells_chunk`], branch-free (an invalid coordinate is replaced by 0 and
/// flagged) so that it vectorises.
#[inline(always)]
fn cells_chunk_body<R: Real>(cells: &mut [[i32; 3]], pts: &[Vec3<R>], cell: f64) -> CellsAcc {
    let (mut good, mut lo, mut hi) = (true, [i32::MAX; 3], [i32::MIN; 3]);
    for (c, p) in cells.iter_mut().zip(pts) {
        for a in 0..3 {
            let q = p[a].as_f64() / cell;
            // False for NaN and ±∞ too.
            let valid = q.abs() <= CELL_LIMIT;
            let v = floor_i32(if valid { q } else { 0.0 });
            good &= valid;
            c[a] = v;
            lo[a] = lo[a].min(v);
            hi[a] = hi[a].max(v);
        }
    }
    (good, lo, hi)
}

/// Particles per task of [`compute_cells`].
const CELLS_CHUNK: usize = 8192;

/// Componentwise min and max of the cells of a set of particles (`None` when empty).
pub(crate) type CellBounds = Option<([i32; 3], [i32; 3])>;

/// `floor(q)` for `|q| <= CELL_LIMIT`, without a libm call (baseline x86-64 has no rounding
/// instruction): truncation towards zero is exact here (|q| < 2³¹), corrected by one below
/// zero.
#[inline(always)]
fn floor_i32(q: f64) -> i32 {
    let t = q as i64;
    (t - ((t as f64) > q) as i64) as i32
}

/// An integer sort key: `u64` when the packed cell fits 64 bits, `u128` otherwise.
pub(crate) trait Key:
    Copy + Send + Sync + Eq + Ord + Default + std::hash::Hash + std::fmt::Debug + 'static
{
    /// The key shifted right by `shift`, truncated to `usize` (the radix sort masks it).
    fn shifted(self, shift: u32) -> usize;
    /// `(x << sx) | (y << sy) | z`.
    fn compose(x: u64, y: u64, z: u64, sx: u32, sy: u32) -> Self;
}

impl Key for u64 {
    #[inline(always)]
    fn shifted(self, shift: u32) -> usize {
        (self >> shift) as usize
    }
    #[inline(always)]
    fn compose(x: u64, y: u64, z: u64, sx: u32, sy: u32) -> Self {
        // sx == 64 only when x's field is empty (x == 0).
        x.checked_shl(sx).unwrap_or(0) | y.checked_shl(sy).unwrap_or(0) | z
    }
}

impl Key for u128 {
    #[inline(always)]
    fn shifted(self, shift: u32) -> usize {
        (self >> shift) as usize
    }
    #[inline(always)]
    fn compose(x: u64, y: u64, z: u64, sx: u32, sy: u32) -> Self {
        ((x as u128) << sx) | ((y as u128) << sy) | z as u128
    }
}

/// Order-preserving packing of cell coordinates into one integer key: lexicographic order
/// of `(X, Y, Z)` equals numeric order of the key (Im & Chan's Fig. 2 comparison). The width
/// of each field is set by the occupied range of that axis (plus `pad` cells each side), not
/// by a grid allocated in memory: nothing here scales with the extent of the scene.
#[derive(Debug, Clone, Copy)]
pub(crate) struct KeyPacker {
    origin: [i64; 3],
    shift_x: u32,
    shift_y: u32,
    /// Total number of key bits used (at most 3 × 33).
    pub bits: u32,
}

impl KeyPacker {
    pub fn new(lo: [i32; 3], hi: [i32; 3], pad: i32) -> Self {
        let mut width = [0u32; 3];
        let mut origin = [0i64; 3];
        for a in 0..3 {
            origin[a] = lo[a] as i64 - pad as i64;
            let span = (hi[a] as i64 + pad as i64) - origin[a] + 1; // >= 1
            width[a] = 64 - ((span - 1) as u64).leading_zeros();
        }
        Self {
            origin,
            shift_x: width[1] + width[2],
            shift_y: width[2],
            bits: width[0] + width[1] + width[2],
        }
    }

    /// `true` when keys fit a `u64`.
    pub fn fits_u64(&self) -> bool {
        self.bits <= 64
    }

    #[inline(always)]
    pub fn pack<K: Key>(&self, c: [i32; 3]) -> K {
        let x = (c[0] as i64 - self.origin[0]) as u64;
        let y = (c[1] as i64 - self.origin[1]) as u64;
        let z = (c[2] as i64 - self.origin[2]) as u64;
        K::compose(x, y, z, self.shift_x, self.shift_y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells of the run-time selected loop (AVX-512 where available) are those of the
    /// baseline-compiled loop, bit for bit, including negative, huge and non-finite
    /// coordinates, in both precisions.
    #[test]
    fn selected_cells_loop_equals_baseline() {
        fn check<R: Real>() {
            let mut seed = 0x9e3779b97f4a7c15u64;
            let mut next = || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                seed
            };
            let special = [
                f64::NAN,
                f64::INFINITY,
                -f64::INFINITY,
                3e9,
                -3e9,
                -0.0,
                0.05,
            ];
            let pts: Vec<Vec3<R>> = (0..1000)
                .map(|k| {
                    let v = |r: u64| {
                        if k % 97 == 0 && r.is_multiple_of(3) {
                            special[(r % special.len() as u64) as usize]
                        } else {
                            (r % 2_000_001) as f64 * 1e-3 - 1000.0
                        }
                    };
                    Vec3::new(
                        R::of_f64(v(next())),
                        R::of_f64(v(next())),
                        R::of_f64(v(next())),
                    )
                })
                .collect();
            for cell in [0.05 * (1.0 + CELL_MARGIN), 1e-3, 7.3] {
                let (mut a, mut b) = (vec![[0; 3]; pts.len()], vec![[0; 3]; pts.len()]);
                let fast = cells_chunk(&mut a, &pts, cell);
                let base = cells_chunk_body(&mut b, &pts, cell);
                assert_eq!(a, b);
                assert_eq!(fast, base);
            }
        }
        check::<f32>();
        check::<f64>();
    }

    #[test]
    fn packing_preserves_lexicographic_order() {
        let lo = [-5, 3, -1_000_000];
        let hi = [7, 3, 1_000_000];
        let p = KeyPacker::new(lo, hi, 1);
        assert!(p.fits_u64());
        let cells = [
            [-6, 2, -1_000_001],
            [-6, 2, 5],
            [-6, 3, -1_000_001],
            [0, 4, 1_000_001],
            [8, 2, -1_000_001],
            [8, 4, 1_000_001],
        ];
        for w in cells.windows(2) {
            assert!(
                p.pack::<u64>(w[0]) < p.pack::<u64>(w[1]),
                "{:?} {:?}",
                w[0],
                w[1]
            );
            assert!(p.pack::<u128>(w[0]) < p.pack::<u128>(w[1]));
        }
        let wide = KeyPacker::new([i32::MIN + 2; 3], [i32::MAX - 2; 3], 1);
        assert!(!wide.fits_u64());
        assert!(wide.pack::<u128>([i32::MIN + 1, 0, 0]) < wide.pack::<u128>([i32::MIN + 1, 0, 1]));
        assert!(
            wide.pack::<u128>([0, i32::MAX - 1, i32::MAX - 1])
                < wide.pack::<u128>([1, i32::MIN + 1, i32::MIN + 1])
        );
    }
}
