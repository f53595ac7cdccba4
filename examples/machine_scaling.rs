//! What the machine itself gives from one thread to two, to read the step's scaling against
//! (docs/BENCHMARKS.md, "Where the shortfall comes from"): a compute-bound loop, and a
//! read-modify-write stream over an array of each thread's own, small enough for the caches
//! and too large for them; and what one fork-join of rayon costs (a step has about twenty
//! parallel loops per body).
//!
//! ```text
//! cargo run --release --example machine_scaling
//! ```

use std::hint::black_box;
use std::sync::Barrier;
use std::time::Instant;

use rayon::prelude::*;

/// Independent multiply-add chains: bound by the floating-point units, not by memory.
fn compute(rounds: usize) -> f64 {
    let mut x = [0.0f64; 8];
    for (k, v) in x.iter_mut().enumerate() {
        *v = 1.0 + k as f64 * 1e-3;
    }
    for _ in 0..rounds {
        for v in x.iter_mut() {
            *v = black_box(*v) * 0.999_999_99 + 1e-9;
        }
    }
    x.iter().sum()
}

/// `passes` read-modify-write sweeps over `values`.
fn stream(values: &mut [f64], passes: usize) -> f64 {
    for _ in 0..passes {
        for v in values.iter_mut() {
            *v = *v * 1.000_000_1 + 1.0;
        }
        black_box(&mut *values);
    }
    values[values.len() / 2]
}

/// Wall time for `threads` threads each running `work` once, after each has run `setup`
/// (the work starts together, behind a barrier, and ends with the slowest thread).
fn timed<T: Send>(
    threads: usize,
    setup: impl Fn() -> T + Sync,
    work: impl Fn(T) -> f64 + Sync,
) -> f64 {
    let ready = Barrier::new(threads);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let input = setup();
                    ready.wait();
                    let start = Instant::now();
                    black_box(work(input));
                    start.elapsed().as_secs_f64()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("worker panicked"))
            .fold(0.0, f64::max)
    })
}

fn main() {
    println!("| loop | 1 thread (s) | 2 threads, same work each (s) | aggregate speed-up |");
    println!("|---|---|---|---|");
    let report = |name: &str, one: f64, two: f64| {
        println!("| {name} | {one:.3} | {two:.3} | {:.2}x |", 2.0 * one / two);
    };
    let rounds = 100_000_000;
    let compute_run = |threads| timed(threads, || rounds, compute);
    report(
        "compute (8 multiply-add chains)",
        compute_run(1),
        compute_run(2),
    );
    let joins = 100_000;
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        let seconds = pool.install(|| {
            let start = Instant::now();
            for _ in 0..joins {
                (0..1024usize).into_par_iter().for_each(|k| {
                    black_box(k);
                });
            }
            start.elapsed().as_secs_f64()
        });
        println!(
            "| one parallel loop over 1024 empty items, {threads} thread(s) | {:.2} us per loop | | |",
            1e6 * seconds / joins as f64
        );
    }
    for (mib, passes) in [(8, 200), (128, 12)] {
        let len = mib * 1024 * 1024 / 8;
        let run = |threads| {
            timed(
                threads,
                || vec![1.0f64; len],
                |mut v| stream(&mut v, passes),
            )
        };
        report(
            &format!("stream, {mib} MiB per thread, {passes} passes"),
            run(1),
            run(2),
        );
    }
}
