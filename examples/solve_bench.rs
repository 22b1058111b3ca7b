//! Times one factorisation of K − σM and solves with it for blocks of 1, 6, 12 and 18
//! right-hand sides: vibrofem's block solve against faer's own sequential solve (medians of
//! three). A development aid for the solver; the numbers are printed, never asserted.
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
    let t = Instant::now();
    let f = Factor::new(sys.symbolic()?.clone(), &a)?;
    println!(
        "{} DOFs: factorised in {:.2} s ({:.2} s numeric)",
        k.n(),
        t.elapsed().as_secs_f64(),
        f.numeric_seconds
    );
    let n = k.n();
    for cols in [1usize, 6, 12, 18] {
        let b = faer::Mat::from_fn(n, cols, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
        for (name, faer_solve) in [("vibrofem", false), ("faer", true)] {
            let mut ts = vec![];
            for _ in 0..3 {
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
            println!("{cols:>2} right-hand sides, {name:<8}: {:.3} s", ts[1]);
        }
    }
    Ok(())
}
