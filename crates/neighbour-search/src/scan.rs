//! The innermost loop shared by every fast method: one particle against ranges of a
//! structure-of-arrays block of candidates (the cell-sorted particles of the grids, or the
//! candidates the relation table gathers for one run).
//!
//! On x86-64 CPUs with AVX-512F or AVX2 (detected at run time; nothing is compiled with
//! `target-cpu=native`), 16 or 8 candidates are tested per instruction sequence and the
//! indices that pass are left-packed without a branch (AVX-512's in-register compress, or
//! for AVX2 one permutation from a 256-entry table); range ends and the particle itself
//! are masked out. Elsewhere a portable
//! branch-free loop does the same one candidate at a time. Both evaluate
//! `(dx·dx + dy·dy) + dz·dz < h²` with the same IEEE operations in the same order as
//! [`crate::squared_distance`] (no fused multiply-add), so their results are identical.

// Unsafe: disjoint parallel writes through `SyncPtr` (each index written by one task), and unchecked indexing in the hot loop behind checked bounds; see the SAFETY comments.
#![allow(unsafe_code)]

use std::any::TypeId;
use std::collections::TryReserveError;

use sph_core::Real;

/// Most lanes processed per step (AVX-512: 16). Blocks carry this many padding entries after
/// their last candidate, so that a step may read past the end of a range.
pub(crate) const LANES: usize = 16;

/// Candidates in structure-of-arrays form (`ids` are the caller's indices), each slice
/// followed by at least [`LANES`] padding entries.
#[derive(Clone, Copy)]
pub(crate) struct Block<'a, R> {
    pub xs: &'a [R],
    pub ys: &'a [R],
    pub zs: &'a [R],
    pub ids: &'a [u32],
}

/// Candidates gathered into one contiguous structure-of-arrays block (per cell or run).
#[derive(Debug, Clone, Default)]
pub(crate) struct Gathered<R> {
    xs: Vec<R>,
    ys: Vec<R>,
    zs: Vec<R>,
    ids: Vec<u32>,
}

impl<R: Real> Gathered<R> {
    pub fn clear(&mut self) {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.ids.clear();
    }

    /// Candidates (padding included) the buffers hold without reallocating.
    pub fn capacity(&self) -> usize {
        self.ids
            .capacity()
            .min(self.xs.capacity())
            .min(self.ys.capacity())
            .min(self.zs.capacity())
    }

    /// Grows the buffers to hold `capacity` candidates (padding included) without
    /// reallocating; no allocation when they already do.
    pub fn reserve_total(&mut self, capacity: usize) {
        // `reserve_exact`: `reserve` would round up (amortised doubling), and the tasks
        // would then outgrow one another at every search.
        let more = capacity.saturating_sub(self.len());
        self.xs.reserve_exact(more);
        self.ys.reserve_exact(more);
        self.zs.reserve_exact(more);
        self.ids.reserve_exact(more);
    }

    /// Number of candidates gathered.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Appends one candidate.
    #[inline]
    pub fn push(&mut self, x: R, y: R, z: R, id: u32) {
        self.xs.push(x);
        self.ys.push(y);
        self.zs.push(z);
        self.ids.push(id);
    }

    /// Appends a run of candidates.
    #[inline]
    pub fn extend(&mut self, xs: &[R], ys: &[R], zs: &[R], ids: &[u32]) {
        append(&mut self.xs, xs);
        append(&mut self.ys, ys);
        append(&mut self.zs, zs);
        append(&mut self.ids, ids);
    }

    /// Appends the candidates of a run whose id is below `bound` (the active points of
    /// [`crate::NeighbourSearch::search_active`]), in their order.
    #[inline]
    pub fn extend_below(&mut self, xs: &[R], ys: &[R], zs: &[R], ids: &[u32], bound: u32) {
        for (k, &id) in ids.iter().enumerate() {
            if id < bound {
                self.push(xs[k], ys[k], zs[k], id);
            }
        }
    }

    /// Pads the block and scans particle `e` of it against all others: appends its
    /// neighbours' ids to `out`, returns how many (an error if `out` cannot grow). Call
    /// [`Gathered::finish`] first.
    #[inline]
    pub fn neighbours_of(
        &self,
        len: usize,
        e: usize,
        r2: R,
        out: &mut Vec<u32>,
    ) -> Result<u32, TryReserveError> {
        let block = Block {
            xs: &self.xs,
            ys: &self.ys,
            zs: &self.zs,
            ids: &self.ids,
        };
        let p = [self.xs[e], self.ys[e], self.zs[e]];
        scan_ranges(p, block, &[(0, len as u32)], e, r2, out)
    }

    /// Scans the `count` particles `own..own + count` of the block (a cell's own particles,
    /// contiguous in it) each against all `len` candidates, skipping itself, as
    /// [`Gathered::neighbours_of`] would one after another: appends their lists to `out`
    /// in that order and `(ids[e], length)` to `particles`; returns the pairs found. One
    /// reservation and one kernel dispatch per run instead of per particle; the lists are
    /// the same, entry for entry. On a failed allocation nothing is appended. The
    /// particles may also lie after the candidates (`own >= len`: passive points scanned
    /// against the active candidates only, none of them itself).
    #[allow(clippy::too_many_arguments)]
    pub fn neighbours_of_run(
        &self,
        len: usize,
        own: usize,
        ids: &[u32],
        r2: R,
        out: &mut Vec<u32>,
        particles: &mut Vec<(u32, u32)>,
    ) -> Result<usize, TryReserveError> {
        let count = ids.len();
        assert!(own + count + LANES <= self.ids.len() && len + LANES <= self.ids.len());
        // Each list has at most `len` entries, and a kernel writes at most LANES entries
        // past the running count.
        out.try_reserve(count * len + LANES)?;
        particles.try_reserve(count)?;
        let block = Block {
            xs: &self.xs,
            ys: &self.ys,
            zs: &self.zs,
            ids: &self.ids,
        };
        let first = particles.len();
        particles.extend(ids.iter().map(|&id| (id, 0)));
        let before = out.len();
        // SAFETY: `out` has room for `count * len + LANES` more entries: the lists before
        // a particle's hold at most `len` entries each, its own at most `len`, and a kernel
        // writes at most LANES entries past its running count. Reads stay below
        // `len + LANES <= self.ids.len()` (asserted above). Every counted entry is
        // initialised by the kernel.
        unsafe {
            let dst = out.as_mut_ptr().add(before);
            let found = scan_run(block, len, own, r2, &mut particles[first..], dst);
            out.set_len(before + found);
            Ok(found)
        }
    }

    /// Appends the padding the scan needs; returns the number of real candidates.
    pub fn finish(&mut self) -> usize {
        let len = self.len();
        pad(&mut self.xs, &mut self.ys, &mut self.zs, &mut self.ids);
        len
    }
}

/// `dst.extend_from_slice(src)` as a plain element loop: the slices here are a few cells
/// long, where a `memcpy` call per slice and a capacity check per `push` both cost more
/// than the copy itself.
#[inline(always)]
fn append<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
    let old = dst.len();
    dst.reserve(src.len());
    // SAFETY: capacity for `src.len()` more elements was reserved; all of them are written
    // before the length is set.
    unsafe {
        let p = dst.as_mut_ptr().add(old);
        for (k, &v) in src.iter().enumerate() {
            p.add(k).write(v);
        }
        dst.set_len(old + src.len());
    }
}

/// Appends [`LANES`] padding entries (at infinity: they would fail every test anyway).
pub(crate) fn pad<R: Real>(xs: &mut Vec<R>, ys: &mut Vec<R>, zs: &mut Vec<R>, ids: &mut Vec<u32>) {
    let inf = R::of_f64(f64::INFINITY);
    for _ in 0..LANES {
        xs.push(inf);
        ys.push(inf);
        zs.push(inf);
        ids.push(u32::MAX);
    }
}

/// Appends to `out` the ids of the candidates in `ranges` (indices into `block`) that are
/// neighbours of the point `p` (strictly closer than `r`, `r2 = r·r`), skipping index
/// `skip` (the particle itself); returns how many, or the error of a failed allocation
/// (`out` unchanged).
#[inline]
pub(crate) fn scan_ranges<R: Real>(
    p: [R; 3],
    block: Block<'_, R>,
    ranges: &[(u32, u32)],
    skip: usize,
    r2: R,
    out: &mut Vec<u32>,
) -> Result<u32, TryReserveError> {
    let n = block.xs.len();
    assert!(block.ys.len() == n && block.zs.len() == n && block.ids.len() == n);
    let room: usize = ranges.iter().map(|&(a, b)| (b - a) as usize + LANES).sum();
    for &(_, b) in ranges {
        assert!(
            b as usize + LANES <= n,
            "range end {b} not followed by padding ({n})"
        );
    }
    out.try_reserve(room)?;
    let before = out.len();
    // SAFETY: `out` has room for `room` more entries; a kernel writes at most LANES
    // entries past its count per step and at most (b − a) counted entries per range, so
    // never beyond `room`; it initialises every entry it counts. Reads stay below
    // `b + LANES <= n` (asserted above).
    unsafe {
        let dst = out.as_mut_ptr().add(before);
        let found = scan(p, block, ranges, skip, r2, dst);
        out.set_len(before + found);
        Ok(found as u32)
    }
}

/// Reinterprets a slice of `R` as a slice of `T` when they are the same type.
#[inline(always)]
fn same<R: 'static, T: 'static>(s: &[R]) -> Option<&[T]> {
    (TypeId::of::<R>() == TypeId::of::<T>())
        // SAFETY: R and T are the same type.
        .then(|| unsafe { std::slice::from_raw_parts(s.as_ptr() as *const T, s.len()) })
}

#[inline]
unsafe fn scan<R: Real>(
    p: [R; 3],
    b: Block<'_, R>,
    ranges: &[(u32, u32)],
    skip: usize,
    r2: R,
    out: *mut u32,
) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            let q = [p[0].as_f64(), p[1].as_f64(), p[2].as_f64(), r2.as_f64()];
            if let (Some(xs), Some(ys), Some(zs)) = (same::<R, f32>(b.xs), same(b.ys), same(b.zs)) {
                let q = q.map(|v| v as f32); // exact: the values are f32
                let blk = Block {
                    xs,
                    ys,
                    zs,
                    ids: b.ids,
                };
                return unsafe { avx512::scan_f32(q, blk, ranges, skip, out) };
            }
            if let (Some(xs), Some(ys), Some(zs)) = (same::<R, f64>(b.xs), same(b.ys), same(b.zs)) {
                let blk = Block {
                    xs,
                    ys,
                    zs,
                    ids: b.ids,
                };
                return unsafe { avx512::scan_f64(q, blk, ranges, skip, out) };
            }
        }
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            let q = [p[0].as_f64(), p[1].as_f64(), p[2].as_f64(), r2.as_f64()];
            if let (Some(xs), Some(ys), Some(zs)) = (same::<R, f32>(b.xs), same(b.ys), same(b.zs)) {
                let q = q.map(|v| v as f32); // exact: the values are f32
                let blk = Block {
                    xs,
                    ys,
                    zs,
                    ids: b.ids,
                };
                return unsafe { avx2::scan_f32(q, blk, ranges, skip, out) };
            }
            if let (Some(xs), Some(ys), Some(zs)) = (same::<R, f64>(b.xs), same(b.ys), same(b.zs)) {
                let blk = Block {
                    xs,
                    ys,
                    zs,
                    ids: b.ids,
                };
                return unsafe { avx2::scan_f64(q, blk, ranges, skip, out) };
            }
        }
    }
    unsafe { scan_portable(p, b, ranges, skip, r2, out) }
}

/// Scans particles `own..own + lens.len()` of `b` each against candidates `0..len`,
/// skipping itself, writing the lists one after another from `out` and each length to
/// `lens[e].1`; returns the total. The kernel is chosen once for the run, and the loop over
/// the particles runs inside it.
///
/// # Safety
/// As [`scan`], for each particle: `out` has room for `lens.len() * len + LANES` entries
/// and the block is padded after `len`.
#[inline]
unsafe fn scan_run<R: Real>(
    b: Block<'_, R>,
    len: usize,
    own: usize,
    r2: R,
    lens: &mut [(u32, u32)],
    out: *mut u32,
) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            if let (Some(xs), Some(ys), Some(zs)) = (same::<R, f32>(b.xs), same(b.ys), same(b.zs)) {
                let blk = Block {
                    xs,
                    ys,
                    zs,
                    ids: b.ids,
                };
                let r2 = r2.as_f64() as f32; // exact: the value is f32
                return unsafe { avx512::run_f32(blk, len, own, r2, lens, out) };
            }
            if let (Some(xs), Some(ys), Some(zs)) = (same::<R, f64>(b.xs), same(b.ys), same(b.zs)) {
                let blk = Block {
                    xs,
                    ys,
                    zs,
                    ids: b.ids,
                };
                return unsafe { avx512::run_f64(blk, len, own, r2.as_f64(), lens, out) };
            }
        }
    }
    let mut found = 0;
    for (e, l) in lens.iter_mut().enumerate() {
        let i = own + e;
        let p = [b.xs[i], b.ys[i], b.zs[i]];
        // SAFETY: see the function's contract.
        let n = unsafe { scan(p, b, &[(0, len as u32)], i, r2, out.add(found)) };
        l.1 = n as u32;
        found += n;
    }
    found
}

/// The portable kernel: branch-free compaction, one candidate at a time.
#[inline]
unsafe fn scan_portable<R: Real>(
    p: [R; 3],
    b: Block<'_, R>,
    ranges: &[(u32, u32)],
    skip: usize,
    r2: R,
    out: *mut u32,
) -> usize {
    let mut found = 0;
    for &(lo, hi) in ranges {
        for t in lo as usize..hi as usize {
            let dx = p[0] - b.xs[t];
            let dy = p[1] - b.ys[t];
            let dz = p[2] - b.zs[t];
            // SAFETY: found is below the room reserved by the caller.
            unsafe { *out.add(found) = b.ids[t] };
            found += ((dx * dx + dy * dy + dz * dz < r2) & (t != skip)) as usize;
        }
    }
    found
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::Block;
    use std::arch::x86_64::*;

    /// `LEFT_PACK[mask]` lists the set lanes of `mask` first (then zeros).
    static LEFT_PACK: [[u32; 8]; 256] = {
        let mut t = [[0u32; 8]; 256];
        let mut mask = 0;
        while mask < 256 {
            let (mut lane, mut k) = (0, 0);
            while lane < 8 {
                if mask & (1 << lane) != 0 {
                    t[mask][k] = lane as u32;
                    k += 1;
                }
                lane += 1;
            }
            mask += 1;
        }
        t
    };

    /// Lanes `[t, t + 8)` that lie inside `[t, end)` and are not `skip`.
    #[inline(always)]
    fn valid_lanes(t: usize, end: usize, skip: usize) -> usize {
        let left = end - t;
        let mut m = if left >= 8 {
            0xff
        } else {
            (1usize << left) - 1
        };
        let s = skip.wrapping_sub(t);
        if s < 8 {
            m &= !(1 << s);
        }
        m
    }

    #[inline(always)]
    unsafe fn pack(mask: usize, ids: *const u32, out: *mut u32) -> usize {
        unsafe {
            let idv = _mm256_loadu_si256(ids as *const __m256i);
            let perm = _mm256_loadu_si256(LEFT_PACK[mask].as_ptr() as *const __m256i);
            _mm256_storeu_si256(out as *mut __m256i, _mm256_permutevar8x32_epi32(idv, perm));
        }
        mask.count_ones() as usize
    }

    #[target_feature(enable = "avx2,popcnt")]
    pub(super) unsafe fn scan_f32(
        q: [f32; 4],
        b: Block<'_, f32>,
        ranges: &[(u32, u32)],
        skip: usize,
        out: *mut u32,
    ) -> usize {
        let (vx, vy, vz) = (
            _mm256_set1_ps(q[0]),
            _mm256_set1_ps(q[1]),
            _mm256_set1_ps(q[2]),
        );
        let vr2 = _mm256_set1_ps(q[3]);
        let mut found = 0;
        for &(lo, hi) in ranges {
            let (mut t, end) = (lo as usize, hi as usize);
            while t < end {
                // SAFETY: t + 8 <= end + 7 < len (padding); `out` has room (see caller).
                unsafe {
                    let dx = _mm256_sub_ps(vx, _mm256_loadu_ps(b.xs.as_ptr().add(t)));
                    let dy = _mm256_sub_ps(vy, _mm256_loadu_ps(b.ys.as_ptr().add(t)));
                    let dz = _mm256_sub_ps(vz, _mm256_loadu_ps(b.zs.as_ptr().add(t)));
                    let d2 = _mm256_add_ps(
                        _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                        _mm256_mul_ps(dz, dz),
                    );
                    let near = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, vr2)) as usize;
                    let mask = near & valid_lanes(t, end, skip);
                    found += pack(mask, b.ids.as_ptr().add(t), out.add(found));
                }
                t += 8;
            }
        }
        found
    }

    #[target_feature(enable = "avx2,popcnt")]
    pub(super) unsafe fn scan_f64(
        q: [f64; 4],
        b: Block<'_, f64>,
        ranges: &[(u32, u32)],
        skip: usize,
        out: *mut u32,
    ) -> usize {
        let (vx, vy, vz) = (
            _mm256_set1_pd(q[0]),
            _mm256_set1_pd(q[1]),
            _mm256_set1_pd(q[2]),
        );
        let vr2 = _mm256_set1_pd(q[3]);
        let half = |t: usize| -> usize {
            // SAFETY: t + 4 <= len (padding).
            unsafe {
                let dx = _mm256_sub_pd(vx, _mm256_loadu_pd(b.xs.as_ptr().add(t)));
                let dy = _mm256_sub_pd(vy, _mm256_loadu_pd(b.ys.as_ptr().add(t)));
                let dz = _mm256_sub_pd(vz, _mm256_loadu_pd(b.zs.as_ptr().add(t)));
                let d2 = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                    _mm256_mul_pd(dz, dz),
                );
                _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(d2, vr2)) as usize
            }
        };
        let mut found = 0;
        for &(lo, hi) in ranges {
            let (mut t, end) = (lo as usize, hi as usize);
            while t < end {
                let mask = (half(t) | half(t + 4) << 4) & valid_lanes(t, end, skip);
                // SAFETY: t + 8 <= end + 7 < len (padding); `out` has room (see caller).
                found += unsafe { pack(mask, b.ids.as_ptr().add(t), out.add(found)) };
                t += 8;
            }
        }
        found
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::Block;
    use std::arch::x86_64::*;

    /// Lanes `[t, t + 16)` that lie inside `[t, end)` and are not `skip`.
    #[inline(always)]
    fn valid_lanes(t: usize, end: usize, skip: usize) -> u16 {
        let left = end - t;
        let mut m = if left >= 16 {
            0xffff
        } else {
            ((1u32 << left) - 1) as u16
        };
        let s = skip.wrapping_sub(t);
        if s < 16 {
            m &= !(1 << s);
        }
        m
    }

    /// Left-packs the ids of the set lanes (in-register compress, then a full store into
    /// the reserved room).
    #[inline(always)]
    unsafe fn pack(mask: u16, ids: *const u32, out: *mut u32) -> usize {
        unsafe {
            let idv = _mm512_loadu_si512(ids as *const __m512i);
            _mm512_storeu_si512(out as *mut __m512i, _mm512_maskz_compress_epi32(mask, idv));
        }
        mask.count_ones() as usize
    }

    #[inline]
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn scan_f32(
        q: [f32; 4],
        b: Block<'_, f32>,
        ranges: &[(u32, u32)],
        skip: usize,
        out: *mut u32,
    ) -> usize {
        let (vx, vy, vz) = (
            _mm512_set1_ps(q[0]),
            _mm512_set1_ps(q[1]),
            _mm512_set1_ps(q[2]),
        );
        let vr2 = _mm512_set1_ps(q[3]);
        let mut found = 0;
        for &(lo, hi) in ranges {
            let (mut t, end) = (lo as usize, hi as usize);
            while t < end {
                // SAFETY: t + 16 <= end + 15 < len (padding); `out` has room (see caller).
                unsafe {
                    let dx = _mm512_sub_ps(vx, _mm512_loadu_ps(b.xs.as_ptr().add(t)));
                    let dy = _mm512_sub_ps(vy, _mm512_loadu_ps(b.ys.as_ptr().add(t)));
                    let dz = _mm512_sub_ps(vz, _mm512_loadu_ps(b.zs.as_ptr().add(t)));
                    let d2 = _mm512_add_ps(
                        _mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)),
                        _mm512_mul_ps(dz, dz),
                    );
                    let near = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(d2, vr2);
                    let mask = near & valid_lanes(t, end, skip);
                    found += pack(mask, b.ids.as_ptr().add(t), out.add(found));
                }
                t += 16;
            }
        }
        found
    }

    /// [`super::scan_run`] in `f32` lanes.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn run_f32(
        b: Block<'_, f32>,
        len: usize,
        own: usize,
        r2: f32,
        lens: &mut [(u32, u32)],
        out: *mut u32,
    ) -> usize {
        let mut found = 0;
        let ranges = [(0, len as u32)];
        for (e, l) in lens.iter_mut().enumerate() {
            let i = own + e;
            let q = [b.xs[i], b.ys[i], b.zs[i], r2];
            // SAFETY: the caller's contract of `scan_run`.
            let n = unsafe { scan_f32(q, b, &ranges, i, out.add(found)) };
            l.1 = n as u32;
            found += n;
        }
        found
    }

    /// [`super::scan_run`] in `f64` lanes.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn run_f64(
        b: Block<'_, f64>,
        len: usize,
        own: usize,
        r2: f64,
        lens: &mut [(u32, u32)],
        out: *mut u32,
    ) -> usize {
        let mut found = 0;
        let ranges = [(0, len as u32)];
        for (e, l) in lens.iter_mut().enumerate() {
            let i = own + e;
            let q = [b.xs[i], b.ys[i], b.zs[i], r2];
            // SAFETY: the caller's contract of `scan_run`.
            let n = unsafe { scan_f64(q, b, &ranges, i, out.add(found)) };
            l.1 = n as u32;
            found += n;
        }
        found
    }

    #[inline]
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn scan_f64(
        q: [f64; 4],
        b: Block<'_, f64>,
        ranges: &[(u32, u32)],
        skip: usize,
        out: *mut u32,
    ) -> usize {
        let (vx, vy, vz) = (
            _mm512_set1_pd(q[0]),
            _mm512_set1_pd(q[1]),
            _mm512_set1_pd(q[2]),
        );
        let vr2 = _mm512_set1_pd(q[3]);
        let half = |t: usize| -> u16 {
            // SAFETY: t + 8 <= len (padding).
            unsafe {
                let dx = _mm512_sub_pd(vx, _mm512_loadu_pd(b.xs.as_ptr().add(t)));
                let dy = _mm512_sub_pd(vy, _mm512_loadu_pd(b.ys.as_ptr().add(t)));
                let dz = _mm512_sub_pd(vz, _mm512_loadu_pd(b.zs.as_ptr().add(t)));
                let d2 = _mm512_add_pd(
                    _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                    _mm512_mul_pd(dz, dz),
                );
                _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d2, vr2) as u16
            }
        };
        let mut found = 0;
        for &(lo, hi) in ranges {
            let (mut t, end) = (lo as usize, hi as usize);
            while t < end {
                let mask = (half(t) | half(t + 8) << 8) & valid_lanes(t, end, skip);
                // SAFETY: t + 16 <= end + 15 < len (padding); `out` has room (see caller).
                found += unsafe { pack(mask, b.ids.as_ptr().add(t), out.add(found)) };
                t += 16;
            }
        }
        found
    }
}

/// Grows every task's gathering buffers to the largest capacity any of them reached, so
/// that a later search, whose tasks take other cells as the particles move, reallocates only
/// for a block larger than any gathered so far (without this a warm step still allocates in
/// a task that had only small blocks before).
pub(crate) fn equalise_capacities<R: Real, T>(tasks: &mut [(T, Gathered<R>)]) {
    let most = tasks.iter().map(|t| t.1.capacity()).max().unwrap_or(0);
    for (_, g) in tasks.iter_mut() {
        if g.capacity() < most {
            g.reserve_total(most);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn both<R: Real>(
        pts: &[[f64; 3]],
        ranges: &[(u32, u32)],
        skip: usize,
        q: [f64; 3],
        r: f64,
    ) -> (Vec<u32>, Vec<u32>) {
        let (mut xs, mut ys, mut zs, mut ids) = (vec![], vec![], vec![], vec![]);
        for (i, p) in pts.iter().enumerate() {
            xs.push(R::of_f64(p[0]));
            ys.push(R::of_f64(p[1]));
            zs.push(R::of_f64(p[2]));
            ids.push(i as u32);
        }
        pad(&mut xs, &mut ys, &mut zs, &mut ids);
        let b = Block {
            xs: &xs,
            ys: &ys,
            zs: &zs,
            ids: &ids,
        };
        let p = q.map(R::of_f64);
        let r2 = R::of_f64(r) * R::of_f64(r);
        let mut fast = vec![7];
        scan_ranges(p, b, ranges, skip, r2, &mut fast).unwrap();
        let room: usize = ranges.iter().map(|&(a, b)| (b - a) as usize).sum();
        let mut slow = vec![0u32; room];
        let n = unsafe { scan_portable(p, b, ranges, skip, r2, slow.as_mut_ptr()) };
        slow.truncate(n);
        slow.insert(0, 7);
        // The AVX2 kernel directly, where the CPU has it (the dispatcher prefers AVX-512).
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            let room = room + LANES * ranges.len();
            let mut avx2_out = vec![0u32; room];
            let q4 = [p[0].as_f64(), p[1].as_f64(), p[2].as_f64(), r2.as_f64()];
            let n = if let (Some(x), Some(y), Some(z)) = (same::<R, f32>(&xs), same(&ys), same(&zs))
            {
                let blk = Block {
                    xs: x,
                    ys: y,
                    zs: z,
                    ids: &ids,
                };
                unsafe {
                    avx2::scan_f32(
                        q4.map(|v| v as f32),
                        blk,
                        ranges,
                        skip,
                        avx2_out.as_mut_ptr(),
                    )
                }
            } else {
                let (x, y, z) = (
                    same::<R, f64>(&xs).unwrap(),
                    same(&ys).unwrap(),
                    same(&zs).unwrap(),
                );
                let blk = Block {
                    xs: x,
                    ys: y,
                    zs: z,
                    ids: &ids,
                };
                unsafe { avx2::scan_f64(q4, blk, ranges, skip, avx2_out.as_mut_ptr()) }
            };
            avx2_out.truncate(n);
            avx2_out.insert(0, 7);
            assert_eq!(avx2_out, slow, "AVX2 kernel differs from the portable one");
        }
        (fast, slow)
    }

    /// A run scanned at once against its particles scanned one at a time (the selected
    /// kernel) and the portable kernel, in precision `R`.
    fn run_matches<R: Real>(pts: &[[f64; 3]], own: usize, count: usize, r: f64) {
        let mut g = Gathered::<R>::default();
        for (i, p) in pts.iter().enumerate() {
            g.push(
                R::of_f64(p[0]),
                R::of_f64(p[1]),
                R::of_f64(p[2]),
                100 + i as u32,
            );
        }
        let len = g.finish();
        let r2 = R::of_f64(r) * R::of_f64(r);
        let ids: Vec<u32> = (0..count as u32).map(|e| 1000 + e).collect();
        let (mut run, mut run_lens) = (vec![7u32], vec![(1u32, 2u32)]);
        let found = g
            .neighbours_of_run(len, own, &ids, r2, &mut run, &mut run_lens)
            .unwrap();
        let (mut one, mut one_lens) = (vec![7u32], vec![(1u32, 2u32)]);
        let mut slow = vec![7u32];
        for (e, &id) in ids.iter().enumerate() {
            let n = g.neighbours_of(len, own + e, r2, &mut one).unwrap();
            one_lens.push((id, n));
            let b = Block {
                xs: &g.xs,
                ys: &g.ys,
                zs: &g.zs,
                ids: &g.ids,
            };
            let p = [g.xs[own + e], g.ys[own + e], g.zs[own + e]];
            let mut buf = vec![0u32; len + LANES];
            let k =
                unsafe { scan_portable(p, b, &[(0, len as u32)], own + e, r2, buf.as_mut_ptr()) };
            slow.extend_from_slice(&buf[..k]);
        }
        assert_eq!(found, run.len() - 1);
        assert_eq!(run, one, "run kernel differs from the per-particle one");
        assert_eq!(run_lens, one_lens);
        assert_eq!(run, slow, "run kernel differs from the portable one");
    }

    proptest! {
        /// A cell's particles scanned in one run give the lists, entry for entry and in
        /// order, of the per-particle scan and of the portable kernel, in both precisions.
        #[test]
        fn run_and_per_particle_agree(
            pts in proptest::collection::vec([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], 1..70),
            own_at in 0.0..1.0f64,
            count_at in 0.0..1.0f64,
            r in 0.01..1.5f64,
        ) {
            let n = pts.len();
            let own = ((own_at * n as f64) as usize).min(n - 1);
            let count = ((count_at * (n - own) as f64) as usize).max(1);
            run_matches::<f32>(&pts, own, count, r);
            run_matches::<f64>(&pts, own, count, r);
        }
    }

    proptest! {
        /// The run-time selected kernel (AVX2 where available) equals the portable one
        /// and the direct definition, in both precisions, for any ranges and skip.
        #[test]
        fn simd_and_portable_agree(
            pts in proptest::collection::vec([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], 1..70),
            cuts in proptest::collection::vec(0.0..1.0f64, 0..6),
            skip_at in 0.0..1.2f64,
            q in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
            r in 0.01..1.5f64,
        ) {
            let n = pts.len();
            let mut c: Vec<u32> = cuts.iter().map(|f| (f * n as f64) as u32).collect();
            c.push(0);
            c.push(n as u32);
            c.sort_unstable();
            let ranges: Vec<(u32, u32)> = c.windows(2).step_by(2).map(|w| (w[0], w[1])).collect();
            let skip = (skip_at * n as f64) as usize; // sometimes beyond every range
            let mut direct = vec![7u32];
            for &(a, b) in &ranges {
                for (t, p) in pts.iter().enumerate().take(b as usize).skip(a as usize) {
                    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                    if t != skip && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r {
                        direct.push(t as u32);
                    }
                }
            }
            let (fast, slow) = both::<f64>(&pts, &ranges, skip, q, r);
            prop_assert_eq!(&fast, &slow);
            prop_assert_eq!(&fast, &direct);
            let (fast, slow) = both::<f32>(&pts, &ranges, skip, q, r);
            prop_assert_eq!(fast, slow);
        }
    }
}
