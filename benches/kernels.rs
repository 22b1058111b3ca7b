//! Kernel benchmarks on generated meshes (no files needed): element matrices, assembly,
//! ordering + factorisation, and the eigen solve. Run with `cargo bench --bench kernels`.
//! End-to-end comparisons with scikit-fem live in `validation/bench_plate.py`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::sync::Arc;
use vibrofem::assembly::{NodeGraph, assemble, dof_pattern};
use vibrofem::element::{MassLumping, solid};
use vibrofem::material::Material;
use vibrofem::mesh::{CellKind, generate::box_mesh};
use vibrofem::model::{Model, ModelSpec};
use vibrofem::ordering::nested_dissection;
use vibrofem::solve::eigen::{EigenParams, Target, solve};
use vibrofem::solve::factor::{Factor, SymbolicFactor};

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
    let model = Model::build(&mesh, &ModelSpec::default(), "bench").unwrap();
    let sets = model.element_sets();
    let mut g = c.benchmark_group("plate tet10 12x12x2");
    g.sample_size(10);
    g.bench_function("pattern", |b| {
        b.iter(|| {
            let graph = NodeGraph::build(mesh.n_nodes(), &sets, Some(&model.dofs));
            dof_pattern(&graph, &model.dofs)
        })
    });
    let graph = NodeGraph::build(mesh.n_nodes(), &sets, Some(&model.dofs));
    let pattern = Arc::new(dof_pattern(&graph, &model.dofs));
    g.bench_function("assemble K and M", |b| {
        b.iter(|| assemble(pattern.clone(), &model.dofs, &sets, true).unwrap())
    });
    let km = assemble(pattern.clone(), &model.dofs, &sets, true).unwrap();
    g.bench_function("METIS ordering + symbolic", |b| {
        b.iter(|| {
            let (f, i) = nested_dissection(&graph, &model.dofs).unwrap();
            SymbolicFactor::new(&pattern, Some((&f, &i))).unwrap()
        })
    });
    g.bench_function("AMD ordering + symbolic", |b| {
        b.iter(|| SymbolicFactor::new(&pattern, None).unwrap())
    });
    let (f, i) = nested_dissection(&graph, &model.dofs).unwrap();
    let sym = Arc::new(SymbolicFactor::new(&pattern, Some((&f, &i))).unwrap());
    let a = km.k.sub_scaled(-1e4, &km.m);
    g.bench_function("numeric LDLT", |b| b.iter(|| Factor::new(sym.clone(), &a).unwrap()));
    g.bench_function("eigen 18 lowest (with verification)", |b| {
        b.iter(|| {
            solve(
                &km.k,
                &km.m,
                &sym,
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
