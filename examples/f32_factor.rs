//! Measures a single-precision LDLᵀ of K − σM with iterative refinement in double precision
//! against the double-precision factor, on faer's own supernodal factorisation (AMD ordering)
//! for both: factor time and bytes, solve time, refinement steps to a given backward residual,
//! and the error against the double-precision solve. A development aid; nothing is asserted.
//!
//! ```text
//! cargo run --release --example f32_factor -- MESH.msh SIGMA [SIGMA ...]   # mesh lengths in mm
//! ```
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{LdltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, Mat, Par, Side};
use std::time::Instant;
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::{System, SystemOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: f32_factor MESH.msh SIGMA...")?;
    let sigmas: Vec<f64> = args.map(|s| s.parse()).collect::<Result<_, _>>()?;
    let mesh = vibrofem::io::gmsh::read(std::path::Path::new(&path), 1e-3)?;
    let model = Model::build(&mesh, &ModelSpec::default(), &path)?;
    let sys = System::build(model, &SystemOptions::default(), &path)?;
    let (k, m) = (sys.k(), sys.m()?);
    let n = k.n();
    let structure = k.pattern.to_faer();
    let sym = factorize_symbolic_cholesky(
        structure.as_ref(),
        Side::Upper,
        SymmetricOrdering::Amd,
        Default::default(),
    )?;
    println!("{n} DOFs, {} entries in L (AMD)", sym.len_val());
    let par = Par::rayon(0);
    for sigma in sigmas {
        let a = k.sub_scaled(sigma, m);
        let a32: Vec<f32> = a.values.iter().map(|&v| v as f32).collect();
        let t = Instant::now();
        let v64 = factor(&sym, structure.as_ref(), &a.values, par)?;
        let t64 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let v32 = factor(&sym, structure.as_ref(), &a32, par)?;
        let t32 = t.elapsed().as_secs_f64();
        println!(
            "σ = {sigma:.4e}: factor f64 {t64:.2} s ({} MB), f32 {t32:.2} s ({} MB)",
            8 * v64.len() / 1_000_000,
            4 * v32.len() / 1_000_000
        );
        let cols = 6;
        let mut x0 = Mat::from_fn(n, cols, |i, j| (((i * 7 + j * 13) % 17) as f64 - 8.0) / 8.0);
        let mut b = Mat::zeros(n, cols);
        m.mul_block(x0.as_ref(), b.as_mut());
        x0 = b.clone();
        let solve64 = |x: &mut Mat<f64>| {
            let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<f64>(cols, Par::Seq));
            LdltRef::new(&sym, &v64).solve_in_place_with_conj(Conj::No, x.as_mut(), Par::Seq, MemStack::new(&mut mem));
        };
        let solve32 = |x: &Mat<f64>| -> Mat<f64> {
            let mut y = Mat::<f32>::from_fn(n, cols, |i, j| x[(i, j)] as f32);
            let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<f32>(cols, Par::Seq));
            LdltRef::new(&sym, &v32).solve_in_place_with_conj(Conj::No, y.as_mut(), Par::Seq, MemStack::new(&mut mem));
            Mat::from_fn(n, cols, |i, j| y[(i, j)] as f64)
        };
        let mut xr = x0.clone();
        let t = Instant::now();
        solve64(&mut xr);
        let ts64 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut x = solve32(&b);
        let ts32 = t.elapsed().as_secs_f64();
        let bn: Vec<f64> = (0..cols).map(|c| b.col(c).norm_l2()).collect();
        let xn: Vec<f64> = (0..cols).map(|c| xr.col(c).norm_l2()).collect();
        println!("  solve of {cols} columns: f64 {ts64:.3} s, f32 {ts32:.3} s (faer, sequential)");
        // b − A·x and its largest relative column norm.
        let residual = |x: &Mat<f64>| -> (Mat<f64>, f64) {
            let mut ax = Mat::zeros(n, cols);
            a.mul_block(x.as_ref(), ax.as_mut());
            let r = &b - &ax;
            let res = (0..cols).map(|c| r.col(c).norm_l2() / bn[c]).fold(0.0f64, f64::max);
            (r, res)
        };
        println!("  the f64 solve: residual ‖b − Ax‖/‖b‖ {:.2e}", residual(&xr).1);
        for step in 0..12 {
            let (r, res) = residual(&x);
            let err = (0..cols)
                .map(|c| (&x - &xr).col(c).norm_l2() / xn[c])
                .fold(0.0f64, f64::max);
            println!("  step {step}: residual ‖b − Ax‖/‖b‖ {res:.2e}, error against the f64 solve {err:.2e}");
            if res < 1e-14 || !res.is_finite() {
                break;
            }
            let d = solve32(&r);
            x += &d;
        }
    }
    Ok(())
}

/// The numeric LDLᵀ of the matrix with `values` on `structure` (upper triangle), in `T`'s precision.
fn factor<T: ComplexField>(
    sym: &SymbolicCholesky<usize>,
    structure: SymbolicSparseColMatRef<'_, usize>,
    values: &[T],
    par: Par,
) -> Result<Vec<T>, Box<dyn std::error::Error>> {
    let mut v = vec![T::zero_impl(); sym.len_val()];
    let mut mem = MemBuffer::new(sym.factorize_numeric_ldlt_scratch::<T>(par, Default::default()));
    sym.factorize_numeric_ldlt(
        &mut v,
        SparseColMatRef::new(structure, values),
        Side::Upper,
        Default::default(),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )?;
    Ok(v)
}
