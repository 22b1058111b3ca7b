//! Kernel benchmarks on generated meshes (no files needed): element matrices, assembly,
//! ordering + factorisation, and the eigen solve. Run with `cargo bench --bench kernels`.
//! End-to-end comparisons with scikit-fem live in `validation/bench_plate.py`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use vibrofem::assembly::assemble;
use vibrofem::element::{MassLumping, solid};
use vibrofem::linalg::eigen::{EigenParams, Target, solve};
use vibrofem::linalg::factor::Factor;
use vibrofem::material::Material;
use vibrofem::mesh::{CellKind, generate::box_mesh};
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::{System, SystemOptions};

fn element_kernels(c: &mut Criterion) {
    let mat = Material::steel();
    for kind in [
        CellKind::Tet4,
        CellKind::Tet10,
        CellKind::Hex8,
        CellKind::Hex20,
        CellKind::Hex27,
    ] {
        let mesh = box_mesh(kind, [1.0, 1.0, 1.0], [1, 1, 1]);
        let b = mesh.blocks.iter().find(|b| b.kind == kind).unwrap();
        let x: Vec<[f64; 3]> = b.cell(0).iter().map(|&a| mesh.nodes[a as usize]).collect();
        let nd = 3 * kind.n_nodes();
        let mut ke = vec![0.0; nd * nd];
        c.bench_function(&format!("stiffness {kind}"), |bch| {
            bch.iter(|| solid::stiffness(kind, black_box(&x), &mat, &mut ke).unwrap())
        });
        c.bench_function(&format!("mass {kind}"), |bch| {
            bch.iter(|| solid::mass(kind, black_box(&x), 7850.0, MassLumping::Consistent, &mut ke).unwrap())
        });
    }
}

fn assembly_and_solve(c: &mut Criterion) {
    // S1 plate, tet10, ~20k DOFs.
    let mesh = box_mesh(CellKind::Tet10, [0.3, 0.3, 0.02], [12, 12, 2]);
    let mut g = c.benchmark_group("plate tet10 12x12x2");
    g.sample_size(10);
    g.bench_function("model build", |b| {
        b.iter(|| Model::build(&mesh, &ModelSpec::default(), "bench").unwrap())
    });
    let opts = SystemOptions::default();
    g.bench_function("system build (graph, pattern, K and M, METIS, symbolic)", |b| {
        b.iter(|| {
            let model = Model::build(&mesh, &ModelSpec::default(), "bench").unwrap();
            System::build(model, &opts, "bench").unwrap()
        })
    });
    let model = Model::build(&mesh, &ModelSpec::default(), "bench").unwrap();
    let sys = System::build(model, &opts, "bench").unwrap();
    g.bench_function("assemble K and M (pattern given)", |b| {
        let sets = sys.model().element_sets();
        b.iter(|| assemble(sys.pattern().clone(), sys.dofs(), &sets, true).unwrap())
    });
    let (k, m) = (sys.k(), sys.m().unwrap());
    let a = k.sub_scaled(-1e4, m);
    g.bench_function("numeric LDLT", |b| {
        b.iter(|| Factor::new(sys.symbolic().unwrap().clone(), &a).unwrap())
    });
    g.bench_function("eigen 18 lowest (with verification)", |b| {
        b.iter(|| {
            solve(
                k,
                m,
                sys.symbolic().unwrap(),
                &EigenParams {
                    target: Target::Nearest(18),
                    ..Default::default()
                },
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, element_kernels, assembly_and_solve);
criterion_main!(benches);
