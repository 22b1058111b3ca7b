//! Times the numeric factorisation of K − σM, vibrofem's subtree-parallel one against faer's,
//! on one thread and on all, and solves with the factor for blocks of 1, 6, 12 and 18
//! right-hand sides: vibrofem's block solve against faer's own sequential solve (medians of
//! three factorisations, of seven solves). A development aid for the solver; the numbers are printed, never asserted.
//!
//! ```text
//! cargo run --release --example solve_bench -- MESH.msh    # mesh lengths in mm
//! ```
use std::time::Instant;
use vibrofem::linalg::factor::Factor;
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::{System, SystemOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: solve_bench MESH.msh (lengths in mm)")?;
    let mesh = vibrofem::io::gmsh::read(std::path::Path::new(&path), 1e-3)?;
    let model = Model::build(&mesh, &ModelSpec::default(), &path)?;
    let sys = System::build(model, &SystemOptions::default(), &path)?;
    let (k, m) = (sys.k(), sys.m()?);
    // A small negative shift, as the eigen solver's default for a free body.
    let a = k.sub_scaled(-1e5, m);
    let sym = sys.symbolic()?.clone();
    let all = rayon::current_num_threads();
    println!("{} DOFs, {} entries in L, {:.3e} flop", k.n(), sym.nnz_l, sym.flops);
    // A second argument `solves` skips the factorisation timings.
    let factorisations = std::env::args().nth(2).as_deref() != Some("solves");
    for threads in [1, all].into_iter().filter(|_| factorisations) {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        for (name, own) in [("vibrofem", true), ("faer", false)] {
            let mut ts = vec![];
            for _ in 0..3 {
                let f = pool.install(|| {
                    if own {
                        Factor::new_shifted(sym.clone(), k, Some((m, -1e5)))
                    } else {
                        Factor::new_faer(sym.clone(), &a)
                    }
                })?;
                ts.push(f.numeric_seconds);
            }
            ts.sort_by(f64::total_cmp);
            println!(
                "factorisation, {threads} thread(s), {name:<8}: {:.2} s ({:.1} GFLOP/s)",
                ts[1],
                sym.flops / ts[1] / 1e9
            );
        }
    }
    let f = Factor::new_shifted(sym.clone(), k, Some((m, -1e5)))?;
    let n = k.n();
    for cols in [1usize, 6, 12, 18] {
        let b = faer::Mat::from_fn(n, cols, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
        for (name, faer_solve) in [("vibrofem", false), ("faer", true)] {
            let mut ts = vec![];
            for _ in 0..7 {
                let mut x = b.clone();
                let t = Instant::now();
                if faer_solve {
                    f.solve_in_place_faer(x.as_mut())
                } else {
                    f.solve_in_place(x.as_mut())
                }
                ts.push(t.elapsed().as_secs_f64());
            }
            ts.sort_by(f64::total_cmp);
            println!(
                "{cols:>2} right-hand sides, {name:<8}: {:.3} s (fastest {:.3} s)",
                ts[3], ts[0]
            );
        }
    }
    Ok(())
}
