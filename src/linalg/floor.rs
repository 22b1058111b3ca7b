//! How far a modal run is from its floor: each phase's work counted, over the rate this machine
//! reaches on that kind of work, against the time the phase took.
//!
//! - **Factorisation**: the flops of one numeric LDLᵀ (Σ c_j² over the columns of L, counted
//!   from the supernode sizes) at the machine's DGEMM rate, measured once per process with
//!   faer's matrix product on a supernode-sized update (1024 × 256 times 256 × 1024, all
//!   worker threads, best of three).
//! - **Block solves**: the bytes of the factor read (each pass over L, forward and backward,
//!   reads every packed value once; a group of up to twelve right-hand sides is one pass) at the
//!   memory bandwidth, measured on the factor itself as a STREAM-like read (a parallel sum over
//!   up to 64 MiB of its values, best of two): for a factor larger than the cache it is the
//!   memory's rate, for a small one the cache's, which is what its solves read from.
//! - **Operator applications per converged mode**: a Krylov basis needs at least one vector
//!   per mode it holds, so the floor is one.
//!
//! The rest of the run (reading, assembly and ordering, the coarse estimate, the Lanczos
//! orthogonalisation, verification, post-processing) is reported in seconds beside them, so
//! the table shows where the time goes.

use serde::Serialize;
use std::sync::OnceLock;
use std::time::Instant;

/// Work done by the block solves with one factor: passes over it, right-hand sides, bytes of
/// the factor read and seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveWork {
    /// Passes over the factor (one per column group; each reads L forward and backward).
    pub passes: usize,
    /// Right-hand sides solved.
    pub columns: usize,
    /// Bytes of the factor read.
    pub bytes: f64,
    /// Wall time of the solves.
    pub seconds: f64,
}

impl SolveWork {
    /// Adds `o`.
    pub fn add(&mut self, o: &SolveWork) {
        self.passes += o.passes;
        self.columns += o.columns;
        self.bytes += o.bytes;
        self.seconds += o.seconds;
    }
}

/// This machine's DGEMM rate (GFLOP/s) and the seconds its measurement took, measured once per
/// process: faer's product of a 1024 × 256 and a 256 × 1024 matrix (the shape of a large
/// supernode's update) on all worker threads, best of three after one warm-up.
pub fn dgemm_rate() -> (f64, f64) {
    static RATE: OnceLock<(f64, f64)> = OnceLock::new();
    *RATE.get_or_init(|| {
        use faer::linalg::matmul::matmul;
        use faer::{Accum, Mat, Par};
        let t0 = Instant::now();
        let (m, k, n) = (1024usize, 256usize, 1024usize);
        let a = Mat::<f64>::from_fn(m, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
        let b = Mat::<f64>::from_fn(k, n, |i, j| ((i * 5 + j * 11) % 19) as f64 - 9.0);
        let mut c = Mat::<f64>::zeros(m, n);
        let mut best = f64::INFINITY;
        for rep in 0..4 {
            let t = Instant::now();
            matmul(c.as_mut(), Accum::Replace, a.as_ref(), b.as_ref(), 1.0, Par::rayon(0));
            if rep > 0 {
                best = best.min(t.elapsed().as_secs_f64());
            }
        }
        std::hint::black_box(c[(0, 0)]);
        (2.0 * (m * k * n) as f64 / best / 1e9, t0.elapsed().as_secs_f64())
    })
}

/// Read bandwidth (GB/s) over `values` (a factor's): parallel sums over up to four disjoint
/// slices of 64 MiB (fewer when `values` is shorter), the best of them, with the seconds it took.
/// Each slice is read once, so none comes from the last-level cache (a slice read twice gave
/// 28–44 GB/s at 119k DOFs, more than the memory sustains), and a pass disturbed by another
/// process leaves the others.
pub fn read_rate(values: &[f64]) -> (f64, f64) {
    use rayon::prelude::*;
    let t0 = Instant::now();
    let len = values.len().min(8 << 20);
    if len < 1 << 12 {
        return (0.0, 0.0);
    }
    let passes = (values.len() / len).clamp(1, 4);
    let chunk = len.div_ceil(rayon::current_num_threads().max(1) * 4).max(1 << 12);
    let mut best = f64::INFINITY;
    for v in values.chunks_exact(len).take(passes) {
        let t = Instant::now();
        // Four independent sums per chunk, so the loop is bound by the loads.
        let s: f64 = v
            .par_chunks(chunk)
            .map(|c| {
                let mut acc = [0.0f64; 4];
                let (quads, tail) = c.as_chunks::<4>();
                for q in quads {
                    for (a, x) in acc.iter_mut().zip(q) {
                        *a += x;
                    }
                }
                acc.iter().sum::<f64>() + tail.iter().sum::<f64>()
            })
            .sum();
        std::hint::black_box(s);
        best = best.min(t.elapsed().as_secs_f64());
    }
    (8.0 * len as f64 / best / 1e9, t0.elapsed().as_secs_f64())
}

/// One phase against its floor.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PhaseFloor {
    /// The phase's work in its own unit (flops, bytes).
    pub work: f64,
    /// The rate the floor assumes (GFLOP/s, GB/s).
    pub rate: f64,
    /// Work over rate, seconds.
    pub floor_s: f64,
    /// Seconds the phase took.
    pub measured_s: f64,
    /// Measured over floor (1 is the floor).
    pub ratio: f64,
}

impl PhaseFloor {
    fn new(work: f64, rate_per_s: f64, rate: f64, measured_s: f64) -> Self {
        let floor_s = if rate_per_s > 0.0 { work / rate_per_s } else { f64::NAN };
        PhaseFloor {
            work,
            rate,
            floor_s,
            measured_s,
            ratio: if floor_s > 0.0 { measured_s / floor_s } else { f64::NAN },
        }
    }
}

/// Operator applications against one per converged mode.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ApplicationsFloor {
    /// Operator applications (vectors solved for), the refinement's included.
    pub applications: usize,
    /// Modes converged (the pairs the iteration delivered, all verified).
    pub modes: usize,
    /// Applications per converged mode (the floor is 1).
    pub per_mode: f64,
}

/// The rest of the run, seconds: what has no floor counted here.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct OtherPhases {
    /// Reading the mesh.
    pub read: f64,
    /// Assembly, ordering and symbolic analysis (alongside each other: the longer strand).
    pub assemble_and_order: f64,
    /// The factor phase less the numeric factorisations: coarse estimate, probe solve, packing.
    pub coarse_estimate_and_packing: f64,
    /// The solve phase (the Lanczos iteration and the refinement) less all its block solves:
    /// M products, orthogonalisation, normalisation, Rayleigh–Ritz and restarts. (Every block
    /// solve counted in [`FloorReport::block_solves`] runs in this phase.)
    pub iteration_besides_solves: f64,
    /// Of which the orthogonalisation against the basis.
    pub orthogonalisation: f64,
    /// Verification and post-processing (participation, shapes).
    pub verify_and_post: f64,
}

/// A modal run's phases against their floors (the `floor` of `modes --json`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FloorReport {
    /// Measured DGEMM rate, GFLOP/s.
    pub dgemm_gflops: f64,
    /// Measured read bandwidth over the factor, GB/s.
    pub read_gbs: f64,
    /// Seconds spent measuring the two rates (part of the run's total).
    pub measure_s: f64,
    /// Numeric factorisations: flops at the DGEMM rate.
    pub factorisation: PhaseFloor,
    /// Block solves: bytes of the factor read at the read bandwidth.
    pub block_solves: PhaseFloor,
    /// Passes over the factor and right-hand sides of the block solves.
    pub solve_passes: usize,
    /// Right-hand sides solved.
    pub solve_columns: usize,
    /// Operator applications per converged mode.
    pub applications: ApplicationsFloor,
    /// The rest of the run, seconds.
    pub other_s: OtherPhases,
    /// Sum of the floors, seconds.
    pub floor_total_s: f64,
    /// The run's wall time, seconds.
    pub total_s: f64,
}

/// What a run counted, for [`FloorReport::new`].
pub struct RunWork {
    /// Flops of one numeric factorisation.
    pub factor_flops: f64,
    /// Numeric factorisations.
    pub factorisations: usize,
    /// Their summed seconds.
    pub factor_seconds: f64,
    /// The block solves.
    pub solves: SolveWork,
    /// Read bandwidth over the factor (GB/s) and the seconds its measurement took.
    pub read: (f64, f64),
    /// Operator applications.
    pub applications: usize,
    /// Modes delivered (converged and verified).
    pub modes: usize,
    /// The Lanczos iteration's parts: solves, M products, orthogonalisation, normalisation,
    /// Rayleigh–Ritz and restarts (seconds).
    pub iteration: [f64; 5],
    /// The run's phases as reported (`timings_s`): read, assemble, order, factor, solve,
    /// verify, post, total.
    pub phases: [f64; 8],
}

impl FloorReport {
    /// The report of a run's counted work; measures the DGEMM rate (once per process).
    pub fn new(w: &RunWork) -> FloorReport {
        let (dgemm, t_dgemm) = dgemm_rate();
        // The rate the solves themselves sustained is attainable too: the floor never sits
        // above the measured time because the probe was disturbed (one run's probe read 12.8
        // GB/s while its solves sustained 16.6: a floor of 1.74 s for 1.34 s measured).
        let (probe_gbs, t_read) = w.read;
        let sustained = if w.solves.seconds > 0.0 {
            w.solves.bytes / w.solves.seconds / 1e9
        } else {
            0.0
        };
        let read_gbs = if probe_gbs > 0.0 { probe_gbs.max(sustained) } else { 0.0 };
        let factorisation = PhaseFloor::new(
            w.factor_flops * w.factorisations as f64,
            dgemm * 1e9,
            dgemm,
            w.factor_seconds,
        );
        let block_solves = PhaseFloor::new(w.solves.bytes, read_gbs * 1e9, read_gbs, w.solves.seconds);
        let [read, assemble, order, factor, solve, verify, post, total] = w.phases;
        let it = w.iteration;
        let other_s = OtherPhases {
            read,
            assemble_and_order: assemble.max(order),
            coarse_estimate_and_packing: (factor - w.factor_seconds).max(0.0),
            // Less every block solve, not only the iteration's own (it[0]): the first block's
            // and the refinement's are in the solve phase too (0.14 s at 119k DOFs, counted
            // twice in the rest of the run before).
            iteration_besides_solves: (solve - w.solves.seconds.max(it[0])).max(0.0),
            orthogonalisation: it[2],
            verify_and_post: verify + post,
        };
        let floor_total_s = [factorisation.floor_s, block_solves.floor_s]
            .iter()
            .filter(|x| x.is_finite())
            .sum();
        FloorReport {
            dgemm_gflops: dgemm,
            read_gbs,
            measure_s: t_dgemm + t_read,
            factorisation,
            block_solves,
            solve_passes: w.solves.passes,
            solve_columns: w.solves.columns,
            applications: ApplicationsFloor {
                applications: w.applications,
                modes: w.modes,
                per_mode: if w.modes > 0 {
                    w.applications as f64 / w.modes as f64
                } else {
                    f64::NAN
                },
            },
            other_s,
            floor_total_s,
            total_s: total,
        }
    }

    /// The phases timed around the solve: reading, assembly and ordering, the whole run.
    pub fn retime(&mut self, read: f64, assemble_and_order: f64, total: f64) {
        self.other_s.read = read;
        self.other_s.assemble_and_order = assemble_and_order;
        self.total_s = total;
    }

    /// The compact table of the text report.
    pub fn table(&self) -> String {
        let f = &self.factorisation;
        let s = &self.block_solves;
        let a = &self.applications;
        let o = &self.other_s;
        // A figure with nothing to measure (no block solve of a dense run: 0 GB at 0 GB/s) is a
        // dash, not NaN.
        let num = |v: f64, prec: usize| {
            if v.is_finite() {
                format!("{v:.prec$}")
            } else {
                "—".to_string()
            }
        };
        let mut t = String::new();
        t.push_str("floor         work                                   floor [s]  measured [s]  × floor\n");
        t.push_str(&format!(
            "factorise     {:<38} {:>9}  {:>12}  {:>7}\n",
            format!("{:.3e} flop at {:.1} GFLOP/s (DGEMM)", f.work, f.rate),
            num(f.floor_s, 3),
            num(f.measured_s, 3),
            num(f.ratio, 2)
        ));
        t.push_str(&format!(
            "block solves  {:<38} {:>9}  {:>12}  {:>7}\n",
            format!(
                "{} passes, {:.2} GB at {:.1} GB/s (read)",
                self.solve_passes,
                s.work / 1e9,
                s.rate
            ),
            num(s.floor_s, 3),
            num(s.measured_s, 3),
            num(s.ratio, 2)
        ));
        t.push_str(&format!(
            "applications  {:<38} {:>9}  {:>12}  {:>7}\n",
            format!("{} for {} modes (floor: 1 per mode)", a.applications, a.modes),
            "",
            "",
            num(a.per_mode, 2)
        ));
        t.push_str(&format!(
            "rest [s]      read {:.2}, assemble+order {:.2}, coarse+pack {:.2}, iteration besides solves {:.2} (orthog. {:.2}), verify+post {:.2}; total {:.2}\n",
            o.read,
            o.assemble_and_order,
            o.coarse_estimate_and_packing,
            o.iteration_besides_solves,
            o.orthogonalisation,
            o.verify_and_post,
            self.total_s
        ));
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_of_counted_work() {
        let w = RunWork {
            factor_flops: 2e9,
            factorisations: 1,
            factor_seconds: 0.5,
            solves: SolveWork {
                passes: 3,
                columns: 18,
                bytes: 6e9,
                seconds: 1.2,
            },
            read: (10.0, 0.01),
            applications: 30,
            modes: 6,
            // The iteration's own solves 1.0 s of the 1.2 s of block solves (the first
            // block's and the refinement's besides): the rest of the solve phase is 0.5 s.
            iteration: [1.0, 0.1, 0.3, 0.05, 0.02],
            phases: [0.1, 0.4, 0.3, 0.8, 1.7, 0.2, 0.1, 3.5],
        };
        let r = FloorReport::new(&w);
        assert!(r.dgemm_gflops > 0.0);
        assert!((r.block_solves.floor_s - 0.6).abs() < 1e-12);
        assert!((r.block_solves.ratio - 2.0).abs() < 1e-12);
        assert!((r.applications.per_mode - 5.0).abs() < 1e-12);
        assert!((r.other_s.coarse_estimate_and_packing - 0.3).abs() < 1e-12);
        assert!((r.other_s.iteration_besides_solves - 0.5).abs() < 1e-12);
        assert!(r.table().lines().count() == 5);
        // A disturbed probe (2 GB/s, below the 5 GB/s the solves sustained): the floor is the
        // solves' own rate, never above the measured time.
        let slow = FloorReport::new(&RunWork { read: (2.0, 0.01), ..w });
        assert!((slow.read_gbs - 5.0).abs() < 1e-12);
        assert!((slow.block_solves.ratio - 1.0).abs() < 1e-12);
    }

    #[test]
    fn read_rate_of_a_buffer() {
        let v = vec![1.0f64; 1 << 16];
        let (gbs, secs) = read_rate(&v);
        assert!(gbs > 0.0 && secs >= 0.0);
        assert_eq!(read_rate(&v[..16]), (0.0, 0.0));
    }
}
