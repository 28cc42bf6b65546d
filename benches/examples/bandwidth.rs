//! The roofline's ceilings of this machine: memory copy and fill bandwidth of 256 MiB
//! arrays on 1 and on 2 threads, and one core's peak `f32` and `f64` fused multiply–add
//! throughput at the widest vector width the processor reports at run time (AVX-512, else
//! AVX2 with FMA, else scalar `mul_add`):
//!
//! ```text
//! cargo run --release -p benches --example bandwidth -- [ROUNDS]
//! ```
//!
//! Each figure is the best of `ROUNDS` (default 7) repetitions, with the median beside it,
//! so that a neighbour's load on a shared machine shows as spread rather than as a lower
//! ceiling. Copy bandwidth counts the bytes read plus the bytes written (a copy of `B` bytes
//! moves `2B`); a threaded copy splits the arrays into one contiguous half per thread. The
//! FMA loop keeps twelve independent accumulators (more than latency × issue width of a
//! current x86 core, 4 cycles × 2 pipes), so it measures the issue rate and not the latency;
//! one FMA is counted as two floating-point operations.
#![allow(unsafe_code)] // the FMA loops are `#[target_feature]` functions, called after detection
use std::hint::black_box;
use std::time::Instant;

/// Bytes of each array of the bandwidth test (256 MiB, far beyond the caches).
const BANDWIDTH_BYTES: usize = 256 << 20;
/// Iterations of the FMA loop per timing (each updates all twelve accumulators).
const FMA_ITERATIONS: usize = 20_000_000;

/// Best and median of `samples` (seconds).
fn best_median(mut samples: Vec<f64>) -> (f64, f64) {
    samples.sort_by(f64::total_cmp);
    (samples[0], samples[samples.len() / 2])
}

/// `threads` scoped threads, each running `f` on its own contiguous part of `dst` and `src`.
fn split_run(dst: &mut [u64], src: &[u64], threads: usize, f: impl Fn(&mut [u64], &[u64]) + Sync) {
    let part = dst.len().div_ceil(threads);
    std::thread::scope(|scope| {
        for (d, s) in dst.chunks_mut(part).zip(src.chunks(part)) {
            let f = &f;
            scope.spawn(move || f(d, s));
        }
    });
}

/// Copy and fill bandwidth (GB/s, best and median) on `threads` threads.
fn bandwidth(threads: usize, rounds: usize) -> ((f64, f64), (f64, f64)) {
    let n = BANDWIDTH_BYTES / 8;
    let src: Vec<u64> = (0..n as u64).collect();
    let mut dst = vec![0u64; n];
    let (mut copy, mut fill) = (Vec::new(), Vec::new());
    for round in 0..rounds as u64 {
        let t = Instant::now();
        split_run(&mut dst, black_box(&src), threads, |d, s| {
            d.copy_from_slice(s)
        });
        copy.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        split_run(&mut dst, &src, threads, |d, _| d.fill(black_box(round)));
        fill.push(t.elapsed().as_secs_f64());
        black_box(&dst);
    }
    let bytes = BANDWIDTH_BYTES as f64;
    let rate = |(best, median): (f64, f64)| (bytes / best / 1e9, bytes / median / 1e9);
    let (c, f) = (rate(best_median(copy)), rate(best_median(fill)));
    // A copy reads and writes every byte.
    ((2.0 * c.0, 2.0 * c.1), f)
}

/// The FMA loops, one per vector width, each returning a value that depends on every
/// accumulator (so that nothing is optimised away).
#[cfg(target_arch = "x86_64")]
mod fma {
    use std::arch::x86_64::*;

    macro_rules! fma_loop {
        ($name:ident, $feature:literal, $vec:ty, $set1:ident, $fmadd:ident, $add:ident, $t:ty, $reduce:expr) => {
            /// Twelve independent FMA chains of `iterations` steps; the sum of their lanes.
            #[target_feature(enable = $feature)]
            pub unsafe fn $name(iterations: usize, a: $t, b: $t) -> $t {
                let (va, vb) = ($set1(a), $set1(b));
                let mut acc: [$vec; 12] = [$set1(1.0); 12];
                for _ in 0..iterations {
                    for x in acc.iter_mut() {
                        *x = $fmadd(*x, va, vb);
                    }
                }
                let mut s = acc[0];
                for x in &acc[1..] {
                    s = $add(s, *x);
                }
                $reduce(s)
            }
        };
    }
    fma_loop!(
        f32_avx512,
        "avx512f",
        __m512,
        _mm512_set1_ps,
        _mm512_fmadd_ps,
        _mm512_add_ps,
        f32,
        |s| _mm512_reduce_add_ps(s)
    );
    fma_loop!(
        f64_avx512,
        "avx512f",
        __m512d,
        _mm512_set1_pd,
        _mm512_fmadd_pd,
        _mm512_add_pd,
        f64,
        |s| _mm512_reduce_add_pd(s)
    );
    fma_loop!(
        f32_avx2,
        "avx,fma",
        __m256,
        _mm256_set1_ps,
        _mm256_fmadd_ps,
        _mm256_add_ps,
        f32,
        |s| {
            let mut l = [0.0f32; 8];
            _mm256_storeu_ps(l.as_mut_ptr(), s);
            l.iter().sum()
        }
    );
    fma_loop!(
        f64_avx2,
        "avx,fma",
        __m256d,
        _mm256_set1_pd,
        _mm256_fmadd_pd,
        _mm256_add_pd,
        f64,
        |s| {
            let mut l = [0.0f64; 4];
            _mm256_storeu_pd(l.as_mut_ptr(), s);
            l.iter().sum()
        }
    );
}

/// Scalar fallback: twelve chains of `mul_add`.
fn scalar_fma<T: Copy + std::ops::Add<Output = T> + MulAdd>(
    iterations: usize,
    a: T,
    b: T,
    one: T,
) -> T {
    let mut acc = [one; 12];
    for _ in 0..iterations {
        for x in acc.iter_mut() {
            *x = x.mul_add_(a, b);
        }
    }
    acc[1..].iter().fold(acc[0], |s, &x| s + x)
}

/// `mul_add` of both float types.
trait MulAdd {
    /// `self · a + b`, rounded once.
    fn mul_add_(self, a: Self, b: Self) -> Self;
}
macro_rules! mul_add_impl {
    ($($t:ty),*) => {$(
        impl MulAdd for $t {
            fn mul_add_(self, a: $t, b: $t) -> $t {
                self.mul_add(a, b)
            }
        }
    )*};
}
mul_add_impl!(f32, f64);

/// The widest FMA loop available at run time for `f32` and `f64`: `(name, lanes of f32,
/// f32 loop, f64 loop)`.
type FmaLoops = (&'static str, usize, fn(usize) -> f32, fn(usize) -> f64);

fn widest_fma() -> FmaLoops {
    // a < 1 and b small keep the chains finite and normal (x → b/(1 − a) = 1).
    const A: f64 = 0.999_999;
    const B: f64 = 1e-6;
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: avx512f was detected just above.
            return (
                "AVX-512",
                16,
                |n| unsafe { fma::f32_avx512(n, A as f32, B as f32) },
                |n| unsafe { fma::f64_avx512(n, A, B) },
            );
        }
        if std::arch::is_x86_feature_detected!("avx") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: avx and fma were detected just above.
            return (
                "AVX2+FMA",
                8,
                |n| unsafe { fma::f32_avx2(n, A as f32, B as f32) },
                |n| unsafe { fma::f64_avx2(n, A, B) },
            );
        }
    }
    (
        "scalar mul_add",
        1,
        |n| scalar_fma(n, A as f32, B as f32, 1.0),
        |n| scalar_fma(n, A, B, 1.0),
    )
}

/// Peak FMA throughput of one core (GFLOP/s, best and median; 2 per FMA) of `run`, whose
/// vectors hold `lanes` values.
fn fma_rate<T>(run: fn(usize) -> T, lanes: usize, rounds: usize) -> (f64, f64) {
    black_box(run(FMA_ITERATIONS / 10));
    let samples = (0..rounds)
        .map(|_| {
            let t = Instant::now();
            black_box(run(black_box(FMA_ITERATIONS)));
            t.elapsed().as_secs_f64()
        })
        .collect();
    let (best, median) = best_median(samples);
    let flops = 2.0 * 12.0 * lanes as f64 * FMA_ITERATIONS as f64;
    (flops / best / 1e9, flops / median / 1e9)
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(7)
        .max(1);
    println!("best (median) of {rounds} rounds; copy counts bytes read + written");
    for threads in [1, 2] {
        let (copy, fill) = bandwidth(threads, rounds);
        println!(
            "{threads} thread(s): copy {:.1} ({:.1}) GB/s, fill {:.1} ({:.1}) GB/s written",
            copy.0, copy.1, fill.0, fill.1
        );
    }
    let (name, lanes, f32_loop, f64_loop) = widest_fma();
    let s = fma_rate(f32_loop, lanes, rounds);
    let d = fma_rate(f64_loop, (lanes / 2).max(1), rounds);
    println!(
        "one core, {name}: f32 {:.1} ({:.1}) GFLOP/s, f64 {:.1} ({:.1}) GFLOP/s (2 per FMA)",
        s.0, s.1, d.0, d.1
    );
}
