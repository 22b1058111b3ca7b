//! Sparse factorisation and eigen solver on problems with known spectra.
//!
//! Reference: a free–free chain of n equal masses m joined by springs k has
//! λ_j = (4k/m)·sin²(jπ/(2n)), j = 0..n−1 (the discrete Laplacian with Neumann ends),
//! exact to rounding; copies of the chain give eigenvalues of exact multiplicity.

use std::sync::Arc;
use vibrofem::linalg::eigen::{EigenParams, Target, solve};
use vibrofem::linalg::factor::{Factor, Prefault, SymbolicFactor};
use vibrofem::linalg::sparse::SymMatrix;

/// `copies` uncoupled free–free chains of `n` masses, interleaved so that copies share no
/// block structure the ordering could exploit trivially.
fn chains(n: usize, copies: usize, k: f64, m: f64) -> (SymMatrix, SymMatrix) {
    let idx = |c: usize, i: usize| i * copies + c;
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    for c in 0..copies {
        for i in 0..n {
            mt.push((idx(c, i), idx(c, i), m));
            if i + 1 < n {
                kt.push((idx(c, i), idx(c, i), k));
                kt.push((idx(c, i + 1), idx(c, i + 1), k));
                kt.push((idx(c, i), idx(c, i + 1), -k));
            }
        }
    }
    let ks = SymMatrix::from_triplets(n * copies, &kt);
    let ms = SymMatrix::from_triplets(n * copies, &mt).on_pattern(ks.pattern.clone());
    (ks, ms)
}

fn exact(n: usize, copies: usize, k: f64, m: f64) -> Vec<f64> {
    let mut v: Vec<f64> = (0..n)
        .flat_map(|j| {
            let s = (j as f64 * std::f64::consts::PI / (2.0 * n as f64)).sin();
            std::iter::repeat_n(4.0 * k / m * s * s, copies)
        })
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

#[test]
fn inertia_counts_eigenvalues_below_shift() {
    let (k, m) = chains(50, 1, 1.0, 1.0);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let ex = exact(50, 1, 1.0, 1.0);
    // Shifts avoid 1.0, where the chain's end diagonal k − σm is exactly zero (an unpivoted
    // LDLᵀ then meets a zero pivot; the eigen solver nudges such shifts itself).
    for &s in &[-0.5, 0.1, 1.3, 2.5, 3.9] {
        let f = Factor::new(sym.clone(), &k.sub_scaled(s, &m)).unwrap();
        let below = ex.iter().filter(|&&l| l < s).count();
        assert_eq!(f.negative_pivots, below, "shift {s}");
    }
}

#[test]
fn lanczos_finds_triple_roots_of_three_identical_chains() {
    // Free–free: 3 zero eigenvalues (one per chain), then triples.
    let (k, m) = chains(400, 3, 1.0e6, 2.0);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Nearest(30),
        dense_below: 0,
        ..Default::default()
    };
    let sol = solve(&k, &m, &sym, &p).unwrap();
    let ex = exact(400, 3, 1.0e6, 2.0);
    assert_eq!(sol.lambda.len(), 30);
    for (i, (&got, &want)) in sol.lambda.iter().zip(&ex).enumerate() {
        // Rigid (zero) modes: absolute to the scale of the first elastic root; others 1e-9
        // relative (the solver's Ritz tolerance is 1e-10 on θ; eigenvalue error is ~tol²).
        let tol = if want == 0.0 { 1e-9 * ex[3] } else { 1e-9 * want };
        assert!((got - want).abs() <= tol, "mode {i}: {got} vs {want}");
    }
    assert!(sol.sturm.complete, "{:?}", sol.sturm);
    assert!(sol.m_orthonormality < 1e-10);
    assert!(sol.rel_residual.iter().all(|&r| r < 1e-8), "{:?}", sol.rel_residual);
}

#[test]
fn band_search_returns_every_mode_in_the_band() {
    let (k, m) = chains(300, 2, 1.0, 1.0);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let ex = exact(300, 2, 1.0, 1.0);
    let (lo, hi) = (0.05, 0.09);
    let p = EigenParams {
        target: Target::Band(lo, hi),
        dense_below: 0,
        ..Default::default()
    };
    let sol = solve(&k, &m, &sym, &p).unwrap();
    let want: Vec<f64> = ex.iter().copied().filter(|&l| l >= lo && l <= hi).collect();
    assert_eq!(sol.lambda.len(), want.len());
    for (g, w) in sol.lambda.iter().zip(&want) {
        assert!((g - w).abs() < 1e-9 * w);
    }
    assert!(sol.sturm.complete);
}

#[test]
fn dense_path_agrees_with_lanczos() {
    let (k, m) = chains(200, 2, 3.0, 0.5);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let a = solve(
        &k,
        &m,
        &sym,
        &EigenParams {
            target: Target::Nearest(10),
            dense_below: 0,
            ..Default::default()
        },
    )
    .unwrap();
    let b = solve(
        &k,
        &m,
        &sym,
        &EigenParams {
            target: Target::Nearest(10),
            dense_below: 1000,
            ..Default::default()
        },
    )
    .unwrap();
    for (x, y) in a.lambda.iter().zip(&b.lambda) {
        assert!((x - y).abs() <= 1e-9 * y.abs().max(a.lambda[2]));
    }
}

/// The system of a hex20 box solid (default steel, free), `size` in metres, `cells` per edge.
fn hex20_box(size: [f64; 3], cells: [usize; 3]) -> vibrofem::system::System {
    use vibrofem::mesh::{CellKind, generate::box_mesh};
    use vibrofem::model::{Model, ModelSpec};
    use vibrofem::system::{System, SystemOptions};
    let mesh = box_mesh(CellKind::Hex20, size, cells);
    let model = Model::build(&mesh, &ModelSpec::default(), "box").unwrap();
    System::build(model, &SystemOptions::default(), "box").unwrap()
}

/// A block of pseudo-random entries in [−0.5, 0.5) (xorshift64 from `state`).
fn random_block(n: usize, cols: usize, mut state: u64) -> faer::Mat<f64> {
    faer::Mat::from_fn(n, cols, |_, _| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    })
}

/// ‖A xᶜ − bᶜ‖ / ‖bᶜ‖ for every column c.
fn column_residuals(a: &SymMatrix, x: &faer::Mat<f64>, b: &faer::Mat<f64>) -> Vec<f64> {
    let (n, cols) = (b.nrows(), b.ncols());
    let mut ax = faer::Mat::zeros(n, cols);
    a.mul_block(x.as_ref(), ax.as_mut());
    (0..cols)
        .map(|c| {
            let r: f64 = (0..n).map(|i| (ax[(i, c)] - b[(i, c)]).powi(2)).sum::<f64>().sqrt();
            let nb: f64 = (0..n).map(|i| b[(i, c)].powi(2)).sum::<f64>().sqrt();
            r / nb
        })
        .collect()
}

/// The parallel block solve (subtrees at once, wide top supernodes as 64-column panels whose
/// products two tasks share) on a model large enough to use every one of those paths: blocks
/// of 1, 6 and 11 right-hand sides give the same bits with one worker thread and with two,
/// every column equals its solve alone, and ‖A X − B‖ / ‖B‖ stays at rounding level.
#[test]
fn parallel_block_solve_is_bit_identical_across_threads() {
    let sys = hex20_box([0.6, 0.4, 0.3], [12, 8, 6]);
    let (k, m) = (sys.k(), sys.m().unwrap());
    let a = k.sub_scaled(-1e5, m);
    let f = Factor::new(sys.symbolic().unwrap().clone(), &a).unwrap();
    let layout = f.solve_layout().expect("a supernodal factor");
    assert!(
        layout.subtrees >= 4 && layout.widest_top > 64 && layout.split_panels > 0,
        "the model must exercise subtrees, panels and split products: {layout:?}"
    );
    let n = k.n();
    let b = random_block(n, 11, 0x9e37_79b9_7f4a_7c15);
    let solve_on = |threads: usize, cols: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut x = b.get(.., 0..cols).to_owned();
        pool.install(|| f.solve_in_place(x.as_mut()));
        x
    };
    let one = solve_on(1, 11);
    let two = solve_on(2, 11);
    for (c, r) in column_residuals(&a, &two, &b).into_iter().enumerate() {
        // Positive definite (σ below every eigenvalue), well-scaled: rounding times a modest
        // growth.
        assert!(r < 1e-10, "column {c}: relative residual {r:.1e}");
    }
    for cols in [1, 6] {
        let part = solve_on(2, cols);
        for c in 0..cols {
            for i in 0..n {
                assert_eq!(
                    part[(i, c)].to_bits(),
                    two[(i, c)].to_bits(),
                    "{cols} columns: column {c}, row {i}"
                );
            }
        }
    }
    for c in 0..11 {
        for i in 0..n {
            assert_eq!(
                one[(i, c)].to_bits(),
                two[(i, c)].to_bits(),
                "column {c}, row {i}: 1 vs 2 threads"
            );
        }
    }
}

/// The supernodal block solve against its definition: for an indefinite K − σM of a hex20
/// solid (σ inside the spectrum), ‖A X − B‖ / ‖B‖ stays at rounding level for a block of 13
/// right-hand sides (split into column groups), every column of the block is bit for bit the
/// solve of that column alone (the grouping, hence the thread count, changes nothing), and faer's
/// solve on the factor unpacked from the solves' packed layout agrees.
#[test]
fn block_solve_matches_single_columns_and_has_small_residual() {
    let sys = hex20_box([0.3, 0.2, 0.1], [6, 4, 3]);
    let (k, m) = (sys.k(), sys.m().unwrap());
    // A shift between the 20th and 21st eigenvalues (dense reference): A is indefinite.
    let ev = vibrofem::linalg::dense::eigen_all(k, m, -1.0, false).unwrap().0;
    let sigma = 0.5 * (ev[19] + ev[20]);
    let a = k.sub_scaled(sigma, m);
    let f = Factor::new(sys.symbolic().unwrap().clone(), &a).unwrap();
    assert!(f.is_supernodal(), "the test must exercise the supernodal solve");
    assert_eq!(f.negative_pivots, 20);
    // The solves read the packed layout: a supernode wider than one 64-column panel loses the
    // upper triangle of its diagonal block beyond the first panel (faer's own solve below reads
    // the layout unpacked again).
    let layout = f.solve_layout().unwrap();
    assert!(layout.widest_top > 64, "the test must exercise a multi-panel supernode");
    assert!(f.bytes() < f.factorisation_bytes(), "the factor was not packed");
    let n = k.n();
    let b = random_block(n, 13, 0x2545_f491_4f6c_dd1d);
    let mut x = b.clone();
    f.solve_in_place(x.as_mut());
    let residuals = column_residuals(&a, &x, &b);
    for c in 0..13 {
        let r = residuals[c];
        // Backward stable LDLᵀ: the residual is rounding times the growth of the entries of
        // L·D·Lᵀ (at most ~1e3 here, an unpivoted indefinite factor of a well-spread shift).
        assert!(r < 1e-10, "column {c}: relative residual {r:.1e}");
        let mut one = faer::Mat::from_fn(n, 1, |i, _| b[(i, c)]);
        f.solve_in_place(one.as_mut());
        for i in 0..n {
            assert_eq!(one[(i, 0)].to_bits(), x[(i, c)].to_bits(), "column {c}, row {i}");
        }
        // faer's own solve agrees to rounding.
        let mut d = faer::Mat::from_fn(n, 1, |i, _| b[(i, c)]);
        f.solve_in_place_faer(d.as_mut());
        let (mut e2, mut x2) = (0.0f64, 0.0f64);
        for i in 0..n {
            e2 += (d[(i, 0)] - x[(i, c)]).powi(2);
            x2 += x[(i, c)].powi(2);
        }
        assert!(
            e2.sqrt() <= 1e-10 * x2.sqrt(),
            "column {c}: grouped and default solves differ"
        );
    }
}

/// A hex20 solid and a shift among its low modes (estimated from the default shift's scale):
/// K − σM indefinite, with a supernodal factor.
fn indefinite_hex20() -> (vibrofem::system::System, f64) {
    let sys = hex20_box([0.6, 0.3, 0.1], [12, 6, 3]);
    let sigma = -50.0 * vibrofem::linalg::eigen::default_shift(sys.k(), sys.m().unwrap());
    (sys, sigma)
}

/// The subtree-parallel numeric factorisation against faer's sequential walk over the same
/// supernodes: for an indefinite K − σM of a hex20 solid, read straight from K and M, the
/// factor is the same bit for bit (same kernels, same order of updates within each
/// supernode), with 1, 2 and 3 worker threads (different cuts of the elimination tree), and so
/// is its inertia.
#[test]
fn subtree_parallel_factor_equals_faers_bit_for_bit() {
    let (sys, sigma) = indefinite_hex20();
    let (k, m) = (sys.k(), sys.m().unwrap());
    let sym = sys.symbolic().unwrap().clone();
    let a = k.sub_scaled(sigma, m);
    let reference = Factor::new_faer(sym.clone(), &a).unwrap();
    assert!(
        reference.is_supernodal(),
        "the test must exercise the supernodal factorisation"
    );
    assert!(reference.negative_pivots > 0, "σ must lie inside the spectrum");
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let f = pool.install(|| Factor::new_shifted(sym.clone(), k, Some((m, sigma))).unwrap());
        assert_eq!(f.negative_pivots, reference.negative_pivots, "{threads} threads");
        let differ = entries_differing(&f, &reference);
        assert_eq!(differ, 0, "{threads} threads: {differ} entries of L differ from faer's");
    }
}

/// Entries of two factors' values that differ in any bit (all of them when the lengths do).
fn entries_differing(a: &Factor, b: &Factor) -> usize {
    if a.values().len() != b.values().len() {
        return a.values().len().max(b.values().len());
    }
    a.values()
        .iter()
        .zip(b.values())
        .filter(|(x, y)| x.to_bits() != y.to_bits())
        .count()
}

/// A factor made in a prefaulted buffer ([`Prefault`]: its pages made resident ahead by a
/// thread of its own, from the end) is the fresh allocation's factor bit for bit, with none, a
/// third and all of the pages resident when the factorisation starts (the supernodes that
/// straddle the boundary cleared in part), and with the thread possibly still running when the
/// factorisation takes the buffer (it is stopped and joined first). A thread still writing its
/// zeros during the factorisation, or a buffer not zero, would show as entries of L that differ.
#[test]
fn prefaulted_factor_equals_the_fresh_one_bit_for_bit() {
    let (sys, sigma) = indefinite_hex20();
    let (k, m) = (sys.k(), sys.m().unwrap());
    let sym = sys.symbolic().unwrap().clone();
    let fresh = Factor::new_shifted(sym.clone(), k, Some((m, sigma))).unwrap();
    assert!(
        fresh.is_supernodal(),
        "the test must exercise the supernodal factorisation"
    );
    let bytes = sym.factor_bytes();
    let buffers = [
        ("none resident", Prefault::start_limited(&sym, 0).unwrap().wait()),
        (
            "a third resident",
            Prefault::start_limited(&sym, bytes / 3).unwrap().wait(),
        ),
        (
            "all resident",
            Prefault::start_limited(&sym, usize::MAX).unwrap().wait(),
        ),
        ("still running", Prefault::start_limited(&sym, usize::MAX).unwrap()),
    ];
    for (what, buffer) in buffers {
        let f = Factor::new_shifted_prefaulted(sym.clone(), k, Some((m, sigma)), buffer).unwrap();
        assert_eq!(f.negative_pivots, fresh.negative_pivots, "{what}");
        let differ = entries_differing(&f, &fresh);
        assert_eq!(differ, 0, "{what}: {differ} entries of L differ");
    }
}

/// A band search factorises twice: at the lower end (the shift, whose inertia is the lower
/// Sturm count) and at the upper end, whose count serves both as the number of modes wanted and
/// as the final check.
#[test]
fn band_search_factorises_once_per_end() {
    let (k, m) = chains(300, 2, 1.0, 1.0);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Band(0.05, 0.09),
        dense_below: 0,
        ..Default::default()
    };
    let sol = solve(&k, &m, &sym, &p).unwrap();
    assert!(sol.sturm.complete);
    assert_eq!(sol.factorizations, 2);
    assert!(sol.memory.factor > 0 && sol.memory.lanczos_basis > 0);
}

/// Block size 1 on two identical chains joined by a weak spring at one end (1e-6 of the chain
/// springs): every eigenvalue comes in a pair split by far less than the spacing of the pairs,
/// which a single-vector Lanczos must still resolve; complete (Sturm) and right against a dense
/// reference.
#[test]
fn close_pairs_with_block_one_are_complete() {
    let n = 300;
    let (k0, m0) = chains(n, 2, 1.0e6, 2.0);
    // Couple node 0 of both copies (indices 0 and 1) with a spring 1e-6 k.
    let mut kt = Vec::new();
    for j in 0..k0.n() {
        let p = &k0.pattern;
        for q in p.col_ptr[j]..p.col_ptr[j + 1] {
            let i = p.row_idx[q] as usize;
            if i <= j {
                kt.push((i, j, k0.values[q]));
            }
        }
    }
    let kc = 1.0;
    kt.push((0, 0, kc));
    kt.push((1, 1, kc));
    kt.push((0, 1, -kc));
    let k = SymMatrix::from_triplets(k0.n(), &kt);
    let m = m0.on_pattern(k.pattern.clone());
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Nearest(9),
        block: 1,
        dense_below: 0,
        ..Default::default()
    };
    let sol = solve(&k, &m, &sym, &p).unwrap();
    let reference = vibrofem::linalg::dense::eigen_all(&k, &m, -1.0, false).unwrap().0;
    assert!(sol.sturm.complete, "{:?}", sol.sturm);
    assert_eq!(sol.lambda.len(), 9);
    for (i, (&got, &want)) in sol.lambda.iter().zip(&reference).enumerate() {
        let tol = 1e-9 * want.abs().max(reference[2]);
        assert!((got - want).abs() <= tol, "mode {i}: {got} vs {want}");
    }
}

/// For the lowest modes, when converged pairs beyond the wanted ones were found, the upper
/// Sturm point lies between the last wanted eigenvalue and the next one, so the check counts
/// exactly the wanted modes (a point above the highest pair found could pass an unconverged
/// neighbour and cost a second round of iteration and two more factorisations).
#[test]
fn upper_sturm_point_lies_between_the_wanted_and_the_next_mode() {
    let (k, m) = chains(300, 1, 1.0e6, 2.0);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let ex = exact(300, 1, 1.0e6, 2.0);
    for nm in [3, 5, 8] {
        let p = EigenParams {
            target: Target::Nearest(nm),
            dense_below: 0,
            ..Default::default()
        };
        let sol = solve(&k, &m, &sym, &p).unwrap();
        assert!(sol.sturm.complete, "{:?}", sol.sturm);
        assert_eq!(sol.factorizations, 2, "{nm} modes: one round");
        let up = sol.sturm.upper.0;
        assert!(
            up > ex[nm - 1] && up < ex[nm],
            "{nm} modes: upper point {up} not in ({}, {})",
            ex[nm - 1],
            ex[nm]
        );
        assert_eq!((sol.sturm.expected, sol.sturm.found), (nm, nm));
    }
}

/// The system of a box solid of `kind` cells (default steel, free).
fn box_system(kind: vibrofem::mesh::CellKind, size: [f64; 3], cells: [usize; 3]) -> vibrofem::system::System {
    use vibrofem::mesh::generate::box_mesh;
    use vibrofem::model::{Model, ModelSpec};
    use vibrofem::system::{System, SystemOptions};
    let mesh = box_mesh(kind, size, cells);
    let model = Model::build(&mesh, &ModelSpec::default(), "box").unwrap();
    System::build(model, &SystemOptions::default(), "box").unwrap()
}

/// All eigenvalues of a small pencil, verified (dense path).
fn all_eigenvalues(k: &SymMatrix, m: &SymMatrix) -> Vec<f64> {
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Nearest(k.n()),
        ..Default::default()
    };
    let sol = solve(k, m, &sym, &p).unwrap();
    assert!(sol.sturm.complete, "{:?}", sol.sturm);
    sol.lambda
}

/// The corner space of a tet10 mesh with straight edges is the space of its tet4 mesh, so the
/// Galerkin pencil (PᵀKP, PᵀMP) must have the spectrum of the tet4 model assembled directly on
/// the same box (an independent assembly: other shape functions, other quadrature). And, as a
/// Rayleigh–Ritz projection, each of its eigenvalues bounds the tet10 model's from above.
#[test]
fn corner_space_of_tet10_is_the_tet4_model() {
    use vibrofem::mesh::CellKind;
    let (size, cells) = ([0.3, 0.2, 0.1], [3, 2, 2]);
    let fine = box_system(CellKind::Tet10, size, cells);
    let lin = box_system(CellKind::Tet4, size, cells);
    let pr = fine.coarse_space().expect("a tet10 mesh has a corner space");
    assert_eq!(pr.n_coarse, lin.n_free(), "one coarse unknown per free tet4 DOF");
    let (kc, mc) = pr.galerkin(fine.k(), fine.m().unwrap());
    let coarse = all_eigenvalues(&kc, &mc);
    let tet4 = all_eigenvalues(lin.k(), lin.m().unwrap());
    let fine_all = all_eigenvalues(fine.k(), fine.m().unwrap());
    let scale = tet4.last().copied().unwrap();
    for (i, (a, b)) in coarse.iter().zip(&tet4).enumerate() {
        // Same space, same pencil up to the rounding of two assemblies: 1e-10 of the largest.
        assert!((a - b).abs() <= 1e-10 * scale, "mode {i}: Galerkin {a} vs tet4 {b}");
    }
    for (i, (a, f)) in coarse.iter().zip(&fine_all).enumerate().skip(6) {
        assert!(*a >= f * (1.0 - 1e-10), "mode {i}: coarse {a} below the model's {f}");
    }
    // A linear mesh has no smaller corner space.
    assert!(lin.coarse_space().is_none());
}

/// The one-factorisation solve (shift above the coarse bound, every eigenvalue below it found
/// and counted) against the two-factorisation solve on the same free–free hex20 solid: same
/// eigenvalues, a complete count, one factorisation. On a cube (repeated roots: the cut at
/// 8 or 10 modes falls inside clusters) the count covers the whole cluster straddling the cut.
#[test]
fn one_factorisation_solve_equals_the_two_factorisation_solve() {
    use vibrofem::linalg::eigen::solve_with;
    use vibrofem::mesh::CellKind;
    for (size, cells, nms) in [
        ([0.4, 0.2, 0.1], [6, 3, 2], vec![12, 20]),
        ([0.2, 0.2, 0.2], [3, 3, 3], vec![8, 10]),
    ] {
        let sys = box_system(CellKind::Hex20, size, cells);
        let (k, m) = (sys.k(), sys.m().unwrap());
        let sym = sys.symbolic().unwrap();
        for nm in nms {
            let p = EigenParams {
                target: Target::Nearest(nm),
                dense_below: 0,
                ..Default::default()
            };
            let two = solve(k, m, sym, &p).unwrap();
            let one = solve_with(k, m, sym, &p, sys.coarse_space()).unwrap();
            // The reference needs two or more (a second round when the cut splits a cluster).
            assert!(two.factorizations >= 2, "{size:?} {nm}: reference solve");
            assert_eq!(one.factorizations, 1, "{size:?} {nm}: {:?}", one.sturm);
            assert!(one.sturm.complete && one.sturm.expected >= nm, "{:?}", one.sturm);
            assert_eq!(one.sturm.lower, (f64::NEG_INFINITY, 0));
            assert_eq!(one.lambda.len(), nm);
            // Both verified to backward errors ~1e-14: their eigenvalues agree to far better
            // than 1e-9 of the first elastic one (rigid-body λ ≈ 0 compared absolutely).
            let scale = two.lambda[6];
            for (i, (a, b)) in one.lambda.iter().zip(&two.lambda).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-9 * b.abs().max(scale),
                    "{size:?} mode {i}: {a} vs {b}"
                );
            }
            assert!(
                one.backward_error.iter().all(|&e| e <= 1e-10),
                "{:?}",
                one.backward_error
            );
            assert!(one.m_orthonormality <= 1e-10);
        }
    }
}

/// A solid's consistent mass matrix is held without its zeros (M = Mₛ ⊗ I₃ node by node: a
/// third of K's entries), on a pattern inside K's. The factorisations read it from there and the
/// solves multiply by it; the modes must be those of the same M stored on K's pattern, bit for
/// bit (the dropped entries are exact zeros, and every sum skips only `+ 0·x`). An M with an
/// entry outside K's pattern cannot be factorised with K and is refused.
#[test]
fn mass_without_zeros_gives_the_modes_of_the_full_pattern() {
    use vibrofem::linalg::eigen::solve_with;
    use vibrofem::mesh::CellKind;
    let sys = box_system(CellKind::Tet10, [0.4, 0.2, 0.1], [6, 3, 2]);
    let (k, m) = (sys.k(), sys.m().unwrap());
    assert!(!Arc::ptr_eq(&k.pattern, &m.pattern));
    assert!(k.pattern.contains(&m.pattern) && !m.pattern.contains(&k.pattern));
    // Free–free solid: every node has its three components, so exactly one in three.
    assert_eq!(3 * m.pattern.nnz(), k.pattern.nnz());
    assert!(m.values.iter().all(|&v| v != 0.0));
    let full = m.on_pattern(k.pattern.clone());
    assert_eq!(full.values.iter().filter(|&&v| v != 0.0).count(), m.pattern.nnz());
    let sym = sys.symbolic().unwrap();
    let p = EigenParams {
        target: Target::Nearest(14),
        dense_below: 0,
        ..Default::default()
    };
    let a = solve_with(k, m, sym, &p, sys.coarse_space()).unwrap();
    let b = solve_with(k, &full, sym, &p, sys.coarse_space()).unwrap();
    assert!(a.sturm.complete && b.sturm.complete);
    assert_eq!(a.lambda.len(), 14);
    for (i, (x, y)) in a.lambda.iter().zip(&b.lambda).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "mode {i}: {x} vs {y}");
    }
    // Two-factorisation path (Sturm counts at both ends) on the compact M as well.
    let two = solve(k, m, sym, &p).unwrap();
    let scale = two.lambda[6];
    for (x, y) in two.lambda.iter().zip(&b.lambda) {
        assert!((x - y).abs() <= 1e-9 * y.abs().max(scale), "{x} vs {y}");
    }
    // An M coupling two equations that K does not: refused, not factorised wrongly.
    let n = k.n();
    let far = (0..n)
        .find(|&j| k.pattern.position(0, j).is_none())
        .expect("a sparse K");
    let bad = SymMatrix::from_triplets(n, &[(0, 0, 1.0), (0, far, 0.5)]);
    match solve(k, &bad, sym, &p) {
        Err(vibrofem::Error::InvalidInput(msg)) => assert!(msg.contains("pattern"), "{msg}"),
        other => panic!("an M outside K's pattern was accepted: {:?}", other.map(|s| s.lambda)),
    }
}

/// The sparse block products (`mul_block`, `abs_mul_norms`: chunks of up to eight columns with
/// their width known at compile time, rows of x asked for ahead of use) against a plain loop
/// over the stored entries, for 1 to 19 columns (every chunk width, and a remainder after full
/// chunks): each column equal to its product alone, bit for bit, and to the plain sums to
/// rounding (1e-13 relative: sums of ~80 products of like magnitude in another order). The
/// fused `mul_block_abs_norms` gives both, bit for bit.
#[test]
fn sparse_block_products_equal_plain_sums() {
    let sys = hex20_box([0.3, 0.2, 0.2], [4, 3, 3]);
    let k = sys.k();
    let (n, p) = (k.n(), &*k.pattern);
    let x = random_block(n, 19, 0x2545_f491_4f6c_dd1d);
    let plain = |c: usize, abs: bool| -> Vec<f64> {
        (0..n)
            .map(|j| {
                (p.col_ptr[j]..p.col_ptr[j + 1])
                    .map(|q| {
                        let (a, xi) = (k.values[q], x[(p.row_idx[q] as usize, c)]);
                        if abs { a.abs() * xi.abs() } else { a * xi }
                    })
                    .sum()
            })
            .collect()
    };
    for cols in 1..=19 {
        let xs = x.get(.., 0..cols);
        let mut y = faer::Mat::zeros(n, cols);
        k.mul_block(xs, y.as_mut());
        let norms = k.abs_mul_norms(xs);
        let mut fused = faer::Mat::zeros(n, cols);
        let fused_norms = k.mul_block_abs_norms(xs, fused.as_mut());
        for c in 0..cols {
            assert_eq!(
                fused_norms[c].to_bits(),
                norms[c].to_bits(),
                "{cols} columns: fused norm {c}"
            );
            for i in 0..n {
                assert_eq!(
                    fused[(i, c)].to_bits(),
                    y[(i, c)].to_bits(),
                    "{cols} columns: fused ({i}, {c})"
                );
            }
            let mut alone = faer::Mat::zeros(n, 1);
            k.mul_block(x.get(.., c..c + 1), alone.as_mut());
            let want = plain(c, false);
            let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..n {
                assert_eq!(
                    y[(i, c)].to_bits(),
                    alone[(i, 0)].to_bits(),
                    "{cols} columns: ({i}, {c})"
                );
                assert!(
                    (y[(i, c)] - want[i]).abs() <= 1e-13 * scale,
                    "{cols} columns: ({i}, {c})"
                );
            }
            assert_eq!(norms[c].to_bits(), k.abs_mul_norms(x.get(.., c..c + 1))[0].to_bits());
            let want_norm = plain(c, true).iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(
                (norms[c] - want_norm).abs() <= 1e-13 * want_norm,
                "{cols} columns: norm {c}"
            );
        }
    }
}

/// The system of a hex20 box with `fixes` (group, components).
fn fixed_box(fixes: &[(&str, vibrofem::dof::DofMask)]) -> vibrofem::system::System {
    use vibrofem::mesh::generate::box_mesh;
    use vibrofem::model::{Model, ModelSpec};
    use vibrofem::system::{System, SystemOptions};
    let mesh = box_mesh(vibrofem::mesh::CellKind::Hex20, [0.4, 0.2, 0.1], [6, 3, 2]);
    let spec = ModelSpec {
        fixes: fixes.iter().map(|(g, c)| (g.to_string(), *c)).collect(),
        ..Default::default()
    };
    let model = Model::build(&mesh, &spec, "box").unwrap();
    System::build(model, &SystemOptions::default(), "box").unwrap()
}

/// Solves `sys` for its 14 lowest modes with and without the rigid-body motions about `c` as
/// null-space candidates, by the one-factorisation solve (`one`) or the two-factorisation one,
/// and checks that `nz` of them were deflated and the solves agree.
fn check_deflation(sys: &vibrofem::system::System, c: [f64; 3], nz: usize, one: bool, what: &str) {
    use vibrofem::linalg::eigen::{NullCandidates, column, solve_with};
    use vibrofem::post::modal::rigid_vectors;
    let (k, m) = (sys.k(), sys.m().unwrap());
    let sym = sys.symbolic().unwrap();
    let model = sys.model();
    let r = rigid_vectors(&model.dofs, &model.nodes, c);
    let p = EigenParams {
        target: Target::Nearest(14),
        dense_below: 0,
        ..Default::default()
    };
    let pd = EigenParams {
        null_candidates: Some(NullCandidates(Arc::new(r.clone()))),
        ..p.clone()
    };
    let coarse = if one { sys.coarse_space() } else { None };
    let plain = solve_with(k, m, sym, &p, coarse).unwrap();
    let defl = solve_with(k, m, sym, &pd, coarse).unwrap();
    assert_eq!(defl.factorizations, if one { 1 } else { 2 }, "{what}");
    assert!(defl.sturm.complete, "{what}: {:?}", defl.sturm);
    assert!(
        defl.backward_error.iter().all(|&e| e <= 1e-10),
        "{what}: {:?}",
        defl.backward_error
    );
    assert!(defl.m_orthonormality <= 1e-12, "{what}: {}", defl.m_orthonormality);
    // Both verified to backward errors ~1e-14: their eigenvalues agree to far better than 1e-9
    // of the first elastic one (the rigid-body ones, λ ≈ 0, compared absolutely).
    let scale = plain.lambda[nz.max(6)];
    for (i, (a, b)) in defl.lambda.iter().zip(&plain.lambda).enumerate() {
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(scale),
            "{what} mode {i}: {a} vs {b}"
        );
    }
    // Exactly zero for the deflated ones, which come first.
    assert_eq!(
        defl.lambda.iter().take_while(|&&l| l == 0.0).count(),
        nz,
        "{what}: {:?}",
        defl.lambda
    );
    if nz == 0 {
        assert_eq!(defl.lambda, plain.lambda, "{what}: nothing deflated, same solve");
        assert_eq!(defl.applications, plain.applications, "{what}");
        return;
    }
    // Fewer on the one-factorisation path, whose shift above the wanted modes makes λ = 0 the
    // slowest to converge (90 against 108 on the free box). On the other the rigid-body modes,
    // nearest its shift below them, converge first: deflating them saved 12 of 74 on the shell
    // plate, none on the free box, and cost 3 on the box on rollers (one more block, three
    // fewer refined columns); never more than a block.
    assert!(
        if one {
            defl.applications < plain.applications
        } else {
            defl.applications <= plain.applications + p.block
        },
        "{what}: {} applications deflated, {} without",
        defl.applications,
        plain.applications
    );
    // The first deflated mode is the x translation, M-normalised: every x DOF moves by the same
    // amount, every other DOF not at all.
    let x0 = column(&defl.vectors, 0);
    let tx = column(&r, 0);
    let s = x0[tx.iter().position(|&v| v == 1.0).unwrap()];
    assert!(s.abs() > 0.0);
    let worst = x0.iter().zip(&tx).map(|(a, b)| (a - s * b).abs()).fold(0.0, f64::max);
    assert!(
        worst <= 1e-12 * s.abs(),
        "{what}: mode 1 is not the x translation ({worst:e})"
    );
}

/// The rigid-body motions offered as null-space candidates: on a free solid all six are null
/// vectors of K (K·r = 0 exactly for a rigid motion, since the strain of u = a + ω × x is
/// zero), so the solve deflates them and iterates only for the elastic modes. It must give the
/// eigenvalues of the solve without them (to the 1e-9 both are verified to), report the six at
/// λ = 0 as translations X, Y, Z then rotations, and need fewer operator applications; on the
/// one-factorisation path (hex20, coarse space) and on the two-factorisation one. On a model
/// resting on rollers (uz fixed on one face) only the in-plane motions (ux, uy, rz) are null
/// vectors: three are deflated and the result again matches. On a clamped one none is, and the
/// solve is the same bit for bit.
#[test]
fn rigid_motions_deflated_give_the_same_modes_with_fewer_applications() {
    use vibrofem::dof::{DofMask, TRANSLATIONS};
    const UZ: DofMask = 0b100;
    for (fixes, nz) in [(vec![], 6), (vec![("zmin", UZ)], 3), (vec![("xmin", TRANSLATIONS)], 0)] {
        let sys = fixed_box(&fixes);
        for one in [true, false] {
            check_deflation(
                &sys,
                [0.2, 0.1, 0.05],
                nz,
                one,
                &format!("fixes {fixes:?}, one factorisation {one}"),
            );
        }
    }
}

/// The same on a free quad4 shell plate (the two-factorisation path: a linear mesh has no
/// corner space): the rigid motions there carry the rotational DOFs too (a rotation ω turns
/// every node's rotation DOFs by ω), and all six are null vectors of the shell's K.
#[test]
fn rigid_motions_of_a_free_shell_are_deflated() {
    use vibrofem::model::{Model, ModelSpec, ShellPart};
    use vibrofem::section::ShellSection;
    use vibrofem::system::{System, SystemOptions};
    let mesh = crate::shell_orientation::plate(|_, _| false);
    let spec = ModelSpec {
        shells: vec![ShellPart {
            group: "plate".into(),
            section: ShellSection::new(0.004),
            material: None,
        }],
        ..Default::default()
    };
    let model = Model::build(&mesh, &spec, "plate").unwrap();
    let sys = System::build(model, &SystemOptions::default(), "plate").unwrap();
    check_deflation(&sys, [0.15, 0.1, 0.0], 6, false, "quad4 shell plate");
}
