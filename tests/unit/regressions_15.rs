//! Regressions of issue 15 ("Findings from outside verification"), solver side: valid requests
//! that used to fail or be refused, and the acceptance test (backward error) that replaced the
//! fixed relative residual. Each test says why its tolerance is what it is.

use crate::common::rel;
use std::sync::Arc;
use vibrofem::analysis::modal::{ModalOptions, ModalReport, ModalTarget, run_modal};
use vibrofem::input::options::ModelOptions;
use vibrofem::input::source;
use vibrofem::linalg::eigen::{EigenParams, Target, backward_errors, solve};
use vibrofem::linalg::factor::SymbolicFactor;
use vibrofem::mesh::Mesh;
use vibrofem::model::Model;
use vibrofem::system::{System, SystemOptions};

fn spec(fix: &[&str]) -> vibrofem::model::ModelSpec {
    ModelOptions {
        fix: fix.iter().map(|s| s.to_string()).collect(),
        ..Default::default()
    }
    .spec()
    .unwrap()
}

fn run(mesh: &Mesh, fix: &[&str], target: ModalTarget, shift_hz: Option<f64>) -> ModalReport {
    let opts = ModalOptions {
        spec: spec(fix),
        target,
        shift_hz,
        ..Default::default()
    };
    run_modal(mesh, "test", &opts, 0.0).unwrap().report
}

fn verified(what: &str, r: &ModalReport) {
    assert!(
        r.complete && r.accurate,
        "{what}: complete {} accurate {}, max backward error {:.1e}, max rel. residual {:.1e}, notes {:?}",
        r.complete,
        r.accurate,
        r.max_backward_error,
        r.max_rel_residual,
        r.notes
    );
}

/// Item 1: a free tet10 bar asked for its lowest 3 modes, all rigid. The old acceptance test
/// (relative residual of rigid modes ≤ 1e-6 against an arbitrary stiffness scale) failed
/// although the modes were right; the backward error is at rounding level.
#[test]
fn rigid_modes_only_request_is_verified() {
    let mesh = source::load("box:1,0.1,0.1:12,1,1:tet10", 1.0).unwrap();
    let r = run(&mesh, &[], ModalTarget::Modes(3), None);
    eprintln!(
        "rigid only: rel. residual {:.1e}, backward error {:.1e}",
        r.max_rel_residual, r.max_backward_error
    );
    verified("3 rigid modes", &r);
    assert_eq!(r.n_rigid, 3);
    // Rigid-body modes: |f| is rounding of the order sqrt(ε·λ_max)/2π; 1e-2 Hz is far above
    // it and far below the first elastic mode (hundreds of Hz).
    assert!(
        r.frequencies_hz.iter().all(|f| f.abs() < 1e-2),
        "{:?}",
        r.frequencies_hz
    );
}

/// Item 13: a slender cantilever (4 m × 20 mm × 20 mm, hex20): its modes are right but the
/// relative residual ‖Kx − λMx‖/‖Kx‖ is ~1e-5 (Kx is a tiny difference of large terms). It must
/// be verified, and f1 must match Euler–Bernoulli, f1 = 1.875²/(2π)·sqrt(EI/(ρAL⁴)) =
/// 1.04434 Hz, to 2e-3 (shear and the two-element-thick hex20 section make it ~1e-3 stiffer).
#[test]
fn slender_cantilever_is_verified() {
    let mesh = source::load("box:4,0.02,0.02:80,2,2:hex20", 1.0).unwrap();
    let r = run(&mesh, &["xmin"], ModalTarget::Modes(2), None);
    eprintln!(
        "slender: f {:?}, rel. residual {:.1e}, backward error {:.1e}",
        r.frequencies_hz, r.max_rel_residual, r.max_backward_error
    );
    verified("slender cantilever", &r);
    let (e, rho, a, l) = (2.1e11f64, 7850.0f64, 0.02f64, 4.0f64);
    let f_eb = 1.875f64.powi(2) / (2.0 * std::f64::consts::PI) * (e * a * a / 12.0 / (rho * l.powi(4))).sqrt();
    assert!(
        rel(r.frequencies_hz[0], f_eb) < 2e-3,
        "{} vs {f_eb}",
        r.frequencies_hz[0]
    );
    // The two bending directions are equal by symmetry, to what the conditioning allows:
    // λ is known to about ε·λ_max/λ1 ~ 1e-16·1e12/43 ≈ 3e-6 relative (5e-7 seen in f).
    assert!(
        rel(r.frequencies_hz[0], r.frequencies_hz[1]) < 1e-5,
        "{:?}",
        r.frequencies_hz
    );
}

/// Item 13: a 1 m × 1 m × 1 mm hex20 sheet, free and clamped along one edge.
#[test]
fn thin_sheet_free_and_clamped_are_verified() {
    let mesh = source::load("box:1,1,0.001:8,8,1:hex20", 1.0).unwrap();
    let free = run(&mesh, &[], ModalTarget::Modes(8), None);
    eprintln!(
        "sheet free: f {:?}, rel. residual {:.1e}, backward error {:.1e}",
        free.frequencies_hz, free.max_rel_residual, free.max_backward_error
    );
    verified("free sheet", &free);
    assert_eq!(free.n_rigid, 6);
    let clamped = run(&mesh, &["xmin"], ModalTarget::Modes(3), None);
    eprintln!(
        "sheet clamped: f {:?}, rel. residual {:.1e}, backward error {:.1e}",
        clamped.frequencies_hz, clamped.max_rel_residual, clamped.max_backward_error
    );
    verified("clamped sheet", &clamped);
    // Kirchhoff plate clamped on one edge (a cantilever plate, square): f1 = 3.492/(2π)·
    // sqrt(D/(ρ h L⁴)) (Leissa), D = E h³ / (12 (1 − ν²)). An 8×8×1 hex20 mesh of a plate with
    // aspect 1000 is coarse and stiff: 5 % is the bound, the point being a verified run.
    let (e, nu, rho, h) = (2.1e11f64, 0.3f64, 7850.0f64, 0.001f64);
    let d = e * h.powi(3) / (12.0 * (1.0 - nu * nu));
    let f1 = 3.492 / (2.0 * std::f64::consts::PI) * (d / (rho * h)).sqrt();
    assert!(
        rel(clamped.frequencies_hz[0], f1) < 5e-2,
        "{} vs {f1}",
        clamped.frequencies_hz[0]
    );
}

/// The acceptance test stays a real check: an exact eigenpair passes it, the same vector with a
/// random perturbation of relative size 1e-6 does not. For a random δ the stiff components
/// dominate, so η ≈ ‖(K − λM)δ‖/‖|K||x|‖ ~ ‖δ‖/‖x‖ ~ 1e-6 (we ask for > 1e-8, 100× the
/// 1e-10 tolerance), while the computed pair is at rounding level (< 1e-10, the tolerance).
#[test]
fn perturbed_eigenvector_fails_the_backward_error_test() {
    let mesh = source::load("box:1,0.1,0.1:12,1,1:tet10", 1.0).unwrap();
    let model = Model::build(&mesh, &spec(&["xmin"]), "test").unwrap();
    let sys = System::build(model, &SystemOptions::default(), "test").unwrap();
    let (k, m) = (sys.k(), sys.m().unwrap());
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Nearest(3),
        ..Default::default()
    };
    let sol = solve(k, m, &sym, &p).unwrap();
    let good = backward_errors(k, m, &sol.lambda, sol.vectors.as_ref());
    assert!(good.iter().all(|&e| e < p.verify_tol), "{good:?}");
    let mut x = sol.vectors.clone();
    let n = x.nrows();
    let mut s = 0x1234_5678_9abc_def1u64;
    for c in 0..x.ncols() {
        let norm = (0..n).map(|i| x[(i, c)] * x[(i, c)]).sum::<f64>().sqrt();
        for i in 0..n {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            x[(i, c)] += 1e-6 * norm * 2.0 * u / (n as f64 / 3.0).sqrt();
        }
    }
    let bad = backward_errors(k, m, &sol.lambda, x.as_ref());
    eprintln!("backward errors: exact {good:?}, perturbed {bad:?}");
    assert!(bad.iter().all(|&e| e > 1e-8), "{bad:?}");
}

/// Item 13: `--shift 0` on a free body sits on the six rigid-body eigenvalues. The nudge off
/// them used to be relative to σ = 0 itself (to σ = 1e-305) and the run failed as singular.
#[test]
fn shift_zero_on_a_free_body() {
    let mesh = source::load("box:1,0.1,0.1:12,1,1:tet10", 1.0).unwrap();
    let r = run(&mesh, &[], ModalTarget::Modes(7), Some(0.0));
    verified("shift 0", &r);
    assert_eq!(r.n_rigid, 6);
    // The 7th is the first elastic mode, the same as with the default shift (to the 1e-9 at
    // which two verified solves of one K, M agree).
    let d = run(&mesh, &[], ModalTarget::Modes(7), None);
    assert!(
        rel(r.frequencies_hz[6], d.frequencies_hz[6]) < 1e-9,
        "{} vs {}",
        r.frequencies_hz[6],
        d.frequencies_hz[6]
    );
}

/// Two copies of `mesh`'s solid cells, the second moved by `dx` (unconnected).
fn two_bodies(mesh: &Mesh, dx: f64) -> Mesh {
    let mut out = mesh.clone();
    let n0 = mesh.nodes.len() as u32;
    for (i, p) in mesh.nodes.iter().enumerate() {
        out.nodes.push([p[0] + dx, p[1], p[2]]);
        out.node_tags.push(mesh.node_tags[i] + n0 as u64 + 1_000_000);
    }
    for (bi, b) in mesh.blocks.iter().enumerate() {
        if b.kind.dim() != 3 {
            continue;
        }
        let ob = &mut out.blocks[bi];
        ob.conn.extend(b.conn.iter().map(|&c| c + n0));
        ob.tags.extend(b.tags.iter().map(|&t| t + 1_000_000));
    }
    out
}

/// Item 13: two separate free bodies have 12 rigid-body modes at λ = 0, more than the block
/// size 6 finds as copies of one eigenvalue. They must all be found (and the first elastic
/// modes of the two identical bodies agree pairwise to rounding, 1e-8).
#[test]
fn two_free_bodies_twelve_rigid_modes() {
    let one = source::load("box:0.5,0.1,0.1:6,1,1:hex20", 1.0).unwrap();
    let mesh = two_bodies(&one, 1.0);
    let r = run(&mesh, &[], ModalTarget::Modes(14), None);
    eprintln!("two bodies: f {:?}, notes {:?}", r.frequencies_hz, r.notes);
    verified("two free bodies", &r);
    assert_eq!(
        r.frequencies_hz.iter().filter(|f| f.abs() < 1.0).count(),
        12,
        "{:?}",
        r.frequencies_hz
    );
    assert!(
        rel(r.frequencies_hz[12], r.frequencies_hz[13]) < 1e-8,
        "{:?}",
        r.frequencies_hz
    );
}

/// Item 11: a band from 0 Hz on a free body must hold its rigid-body modes, including those whose
/// computed λ rounds slightly below 0 (they used to be dropped while the Sturm count, taken at
/// the negative shift, expected them).
#[test]
fn band_from_zero_keeps_rigid_modes() {
    let mesh = source::load("box:1,0.1,0.1:12,1,1:tet10", 1.0).unwrap();
    let modes = run(&mesh, &[], ModalTarget::Modes(8), None);
    let hi = 0.5 * (modes.frequencies_hz[6] + modes.frequencies_hz[7]);
    let r = run(&mesh, &[], ModalTarget::Band(0.0, hi), None);
    eprintln!(
        "band: eigenvalues {:?}",
        r.modes.iter().map(|m| m.eigenvalue).collect::<Vec<_>>()
    );
    verified("band from 0", &r);
    assert_eq!(r.modes.len(), 7);
    assert_eq!(r.n_rigid, 6);
}

/// Item 12: a request for more modes than a model has, or a block wider than it, is capped
/// (with a note) and solved densely instead of iterating on and on.
#[test]
fn huge_mode_and_block_requests_are_capped() {
    let mesh = source::load("box:1,0.1,0.1:12,1,1:hex20", 1.0).unwrap();
    let opts = ModalOptions {
        spec: spec(&["xmin"]),
        target: ModalTarget::Modes(100_000),
        ..Default::default()
    };
    let r = run_modal(&mesh, "test", &opts, 0.0).unwrap().report;
    assert!(r.dofs > 300, "{} DOFs: the dense path would be taken anyway", r.dofs);
    assert_eq!(r.modes.len(), r.dofs);
    assert!(r.notes.iter().any(|n| n.contains("solved densely")), "{:?}", r.notes);
    verified("all modes", &r);
    let opts = ModalOptions {
        spec: spec(&["xmin"]),
        target: ModalTarget::Modes(3),
        block: 100_000,
        ..Default::default()
    };
    let b = run_modal(&mesh, "test", &opts, 0.0).unwrap().report;
    assert!(
        b.notes.iter().any(|n| n.contains("block size 100000 capped")),
        "{:?}",
        b.notes
    );
    verified("huge block", &b);
    // Same modes as the full solve, to the 1e-9 at which two verified solves agree.
    for i in 0..3 {
        assert!(rel(b.frequencies_hz[i], r.frequencies_hz[i]) < 1e-9);
    }
}

/// Item 12: a shift that is not a usable number is an input error, before any factorisation.
#[test]
fn non_finite_shift_is_an_input_error() {
    let mesh = source::load("box:0.5,0.1,0.1:6,1,1:hex20", 1.0).unwrap();
    for s in [f64::NAN, f64::INFINITY, 1e300] {
        let opts = ModalOptions {
            spec: spec(&["xmin"]),
            target: ModalTarget::Modes(3),
            shift_hz: Some(s),
            ..Default::default()
        };
        let e = run_modal(&mesh, "test", &opts, 0.0).err().expect("must fail");
        assert_eq!(e.exit_code(), 1, "{s}: {e}");
    }
}

/// Item 13: a spring with zero rotational stiffness on a one-node group of a solid (a node that
/// has no rotations) used to add three rotations nothing holds: `ZeroPivot`. Now only the
/// components the spring acts on are added, and the run is verified: a free box held by a
/// translational spring at one corner has 3 rigid rotations (about that corner).
#[test]
fn translational_spring_on_a_solid_node() {
    let mut mesh = source::load("box:1,0.1,0.1:12,1,1:tet10", 1.0).unwrap();
    node_group(&mut mesh, "pt", &[[0.0, 0.0, 0.0]]);
    let spec = ModelOptions {
        spring: vec!["pt=1e6,1e6,1e6,0,0,0".into()],
        ..Default::default()
    }
    .spec()
    .unwrap();
    let opts = ModalOptions {
        spec,
        target: ModalTarget::Modes(6),
        ..Default::default()
    };
    let r = run_modal(&mesh, "test", &opts, 0.0).unwrap().report;
    eprintln!("spring: f {:?}", r.frequencies_hz);
    verified("spring on a solid node", &r);
    // Three rigid rotations about the corner (|f| at rounding level, 1e-2 Hz as above), then
    // the spring-supported modes (k/m ~ 1e6/78.5 → about 18 Hz scale).
    assert_eq!(
        r.frequencies_hz.iter().filter(|f| f.abs() < 1e-2).count(),
        3,
        "{:?}",
        r.frequencies_hz
    );
    assert!(r.frequencies_hz[3] > 1.0, "{:?}", r.frequencies_hz);
}

/// Item 16: a name used in two dimensions is refused where it is ambiguous, resolved by the
/// formulation where it is not; unnamed groups are reachable as `dimension:tag`.
#[test]
fn group_names_in_two_dimensions_and_by_dimension_tag() {
    let mut mesh = vibrofem::mesh::generate::box_mesh(vibrofem::mesh::CellKind::Hex8, [1.0, 0.2, 0.2], [4, 1, 1]);
    let face = mesh.groups.iter().position(|g| g.name == "xmin").unwrap();
    mesh.groups[face].name = "volume".into();
    let (d, t) = (mesh.groups[face].dim, mesh.groups[face].tag);
    let e = mesh.group("volume").unwrap_err().to_string();
    assert!(e.contains("used by 2 groups") && e.contains(&format!("{d}:{t}")), "{e}");
    assert_eq!(mesh.group_of_dim("volume", 3).unwrap().dim, 3);
    assert_eq!(mesh.group_of_dim("volume", 2).unwrap().dim, 2);
    assert_eq!(mesh.group(&format!("{d}:{t}")).unwrap().dim, 2);
    // A fix on the ambiguous name is refused; by dimension:tag it holds the face.
    let mut opts = vibrofem::input::options::ModelOptions {
        fix: vec!["volume".into()],
        ..Default::default()
    };
    let e = vibrofem::model::Model::build(&mesh, &opts.spec().unwrap(), "m")
        .err()
        .unwrap();
    assert!(e.to_string().contains("used by 2 groups"), "{e}");
    opts.fix = vec![format!("{d}:{t}:ux,uy,uz")];
    let model = vibrofem::model::Model::build(&mesh, &opts.spec().unwrap(), "m").unwrap();
    assert_eq!(model.dofs.n_free, 3 * (mesh.n_nodes() - 4));
    // Solids resolve the name by their own dimension.
    let opts = vibrofem::input::options::ModelOptions {
        solid: vec!["volume".into()],
        ..Default::default()
    };
    assert!(vibrofem::model::Model::build(&mesh, &opts.spec().unwrap(), "m").is_ok());
}

#[test]
fn split_group_reads_dimension_tag_names() {
    use vibrofem::input::options::split_group;
    assert_eq!(split_group("2:5"), ("2:5", None));
    assert_eq!(split_group("2:5:ux"), ("2:5", Some("ux")));
    assert_eq!(split_group("top:guided=z"), ("top", Some("guided=z")));
    assert_eq!(split_group("top"), ("top", None));
    assert_eq!(split_group("x1:2"), ("x1", Some("2")));
}

#[test]
fn coupling_grammar() {
    use vibrofem::input::options::parse_coupling;
    let c = parse_coupling("end_top@0,0,0.06:guided=z").unwrap();
    assert_eq!(
        (c.group.as_str(), c.guided, c.reference),
        ("end_top", Some(2), Some([0.0, 0.0, 0.06]))
    );
    let c = parse_coupling("top:guided=x").unwrap();
    assert_eq!((c.group.as_str(), c.guided, c.reference), ("top", Some(0), None));
    let c = parse_coupling("2:5@-1,0,1").unwrap();
    assert_eq!((c.group.as_str(), c.reference), ("2:5", Some([-1.0, 0.0, 1.0])));
    assert!(parse_coupling("top:free").is_err());
    assert!(parse_coupling("top@1,2").is_err());
}

/// The tet10 cells around the corner node at the origin of a `box:` mesh, with the mid-edge
/// nodes of every edge from that corner moved to `frac` of the edge (¼: quarter-point cells, a
/// crack-tip rosette; negative: past the corner, an inverted cell).
fn tet10_with_corner_edges_at(frac: f64) -> Mesh {
    let mut mesh = source::load("box:0.1,0.02,0.02:10,2,2:tet10", 1.0).unwrap();
    let corner = mesh
        .nodes
        .iter()
        .position(|x| x.iter().all(|c| c.abs() < 1e-12))
        .unwrap() as u32;
    let b = mesh
        .blocks
        .iter()
        .find(|b| b.kind == vibrofem::mesh::CellKind::Tet10)
        .unwrap();
    // gmsh tet10 edges: node 4 on (0,1), 5 (1,2), 6 (2,0), 7 (3,0), 8 (3,2), 9 (3,1).
    const EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (2, 0), (3, 0), (3, 2), (3, 1)];
    let mut moves = Vec::new();
    for e in 0..b.len() {
        let c = b.cell(e);
        for (k, &(p, q)) in EDGES.iter().enumerate() {
            let (a, o) = if c[p] == corner {
                (c[p], c[q])
            } else if c[q] == corner {
                (c[q], c[p])
            } else {
                continue;
            };
            let (xa, xo) = (mesh.nodes[a as usize], mesh.nodes[o as usize]);
            moves.push((c[4 + k] as usize, [0, 1, 2].map(|i| xa[i] + frac * (xo[i] - xa[i]))));
        }
    }
    assert!(!moves.is_empty(), "the corner belongs to no tet10");
    for (n, x) in moves {
        mesh.nodes[n] = x;
    }
    mesh
}

/// Item 12: one Jacobian test for modes and statics. Quarter-point tet10 cells (Jacobian zero
/// at the corner node, positive at the integration points) are legitimate: both analyses run,
/// and the stresses at that node come from the integration points. Cells turned inside out by a
/// mid-edge node past the corner are refused by both, naming the element.
#[test]
fn quarter_point_tet10_is_accepted_by_modes_and_statics_and_inverted_by_neither() {
    use vibrofem::analysis::statics::{Load, StaticOptions, run_static};
    let quarter = tet10_with_corner_edges_at(0.25);
    let r = run(&quarter, &["xmax"], ModalTarget::Modes(3), None);
    verified("quarter-point tet10", &r);
    let cases = vec![vec![Load::Force {
        group: "xmin".into(),
        force: [0.0, 0.0, 100.0],
    }]];
    let opts = StaticOptions {
        spec: spec(&["xmax"]),
        cases,
    };
    let st = run_static(&quarter, "quarter", &opts).unwrap();
    let n = st.model.n_mesh_nodes;
    let u: Vec<f64> = (0..n)
        .flat_map(|a| (0..3).map(move |c| (a, c)))
        .map(|(a, c)| st.u[0][7 * a + c])
        .collect();
    let ns = vibrofem::post::stress::nodal_stress(&st.model.solids, n, &u).unwrap();
    assert!(ns.von_mises.iter().all(|v| v.is_finite()) && ns.von_mises.iter().any(|&v| v > 0.0));

    let inverted = tet10_with_corner_edges_at(-0.3);
    let e = Model::build(&inverted, &spec(&["xmax"]), "inverted")
        .and_then(|m| System::build(m, &SystemOptions::default(), "inverted"))
        .err()
        .expect("modes must refuse an inverted tet10");
    assert!(matches!(e, vibrofem::Error::InvertedElement { .. }), "{e}");
    let e = run_static(
        &inverted,
        "inverted",
        &StaticOptions {
            spec: spec(&["xmax"]),
            cases: vec![vec![]],
        },
    )
    .err()
    .expect("statics must refuse an inverted tet10");
    assert!(matches!(e, vibrofem::Error::InvertedElement { .. }), "{e}");
}

/// Item 15: a request for most of the spectrum (1000 of 1092 DOFs) is solved densely and must
/// verify: the reduction through M's Cholesky factor keeps the upper modes backward stable
/// (through K − σM they reached a backward error of 1.1e-10 and the run exited 2).
#[test]
fn most_of_the_spectrum_is_solved_densely_and_verified() {
    let mesh = source::load("box:0.2,0.1,0.05:12,6,3:hex8", 1.0).unwrap();
    let r = run(&mesh, &[], ModalTarget::Modes(1000), None);
    verified("1000 of 1092 modes", &r);
    assert_eq!(r.frequencies_hz.len(), 1000);
    assert!(r.notes.iter().any(|n| n.contains("solved densely")), "{:?}", r.notes);
}

/// Adds a group `name` of dimension `dim` made of the nodes at `points` (one point cell each),
/// enough for couplings, which act on a group's nodes.
fn node_group(mesh: &mut Mesh, name: &str, points: &[[f64; 3]]) {
    use vibrofem::mesh::{CellKind, CellRef, Group};
    let bi = mesh.block_index_mut(CellKind::Point1);
    let mut cells = Vec::new();
    for p in points {
        let a = mesh
            .nodes
            .iter()
            .position(|x| (0..3).all(|d| (x[d] - p[d]).abs() < 1e-12))
            .unwrap_or_else(|| panic!("no node at {p:?}")) as u32;
        let etag = mesh
            .blocks
            .iter()
            .flat_map(|b| b.tags.iter().copied())
            .max()
            .unwrap_or(0)
            + 1;
        mesh.blocks[bi].push(&[a], etag);
        cells.push(CellRef {
            block: bi as u32,
            index: (mesh.blocks[bi].len() - 1) as u32,
        });
    }
    let tag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0) + 1;
    mesh.groups.push(Group {
        name: name.into(),
        dim: 0,
        tag,
        cells,
    });
}

fn modal_of(mesh: &Mesh, opts: ModelOptions, n: usize) -> ModalReport {
    let o = ModalOptions {
        spec: opts.spec().unwrap(),
        target: ModalTarget::Modes(n),
        ..Default::default()
    };
    let r = run_modal(mesh, "test", &o, 0.0).unwrap().report;
    verified("coupling", &r);
    r
}

/// Item 13: a coupling of one solid node with its reference node placed elsewhere, and of solid
/// nodes on one line (an edge, along an axis or not), used to leave the reference node's
/// unresolvable rotations singular (`ZeroPivot`, exit 2). Those rotations are now held, with a
/// note. References: a point mass coupled to one node through a moved reference carries no
/// rotary effect (its rotations are held), so it equals the mass put on the node itself; and the
/// diagonal-edge model rotated 45° about z so that its edge lies along y (the axis-aligned path)
/// has the same frequencies (rotation invariance; 1e-9 covers rounding of the rotated geometry).
#[test]
fn couplings_of_a_point_or_a_line_of_solid_nodes() {
    let base = source::load("box:1,1,1:2,2,2:hex8", 1.0).unwrap();
    // One node, reference moved 1 m away.
    let mut mesh = base.clone();
    node_group(&mut mesh, "tip", &[[1.0, 1.0, 1.0]]);
    let coupled = modal_of(
        &mesh,
        ModelOptions {
            fix: vec!["xmin".into()],
            couple: vec!["tip@1,1,2".into()],
            point_mass: vec!["tip=500".into()],
            ..Default::default()
        },
        4,
    );
    let direct = modal_of(
        &mesh,
        ModelOptions {
            fix: vec!["xmin".into()],
            point_mass: vec!["tip=500".into()],
            ..Default::default()
        },
        4,
    );
    for (a, b) in coupled.frequencies_hz.iter().zip(&direct.frequencies_hz) {
        assert!(
            rel(*a, *b) < 1e-9,
            "{:?} vs {:?}",
            coupled.frequencies_hz,
            direct.frequencies_hz
        );
    }
    assert!(
        coupled.notes.iter().any(|n| n.contains("at one point")),
        "{:?}",
        coupled.notes
    );
    // Two nodes on a face diagonal (direction (1,1,0)/√2) with a heavy, rotary point mass on a
    // reference off the line; then the same body turned by 45° about z.
    let line_case = |mesh: &Mesh, a: [f64; 3], b: [f64; 3], reference: [f64; 3], mass: &str| {
        let mut m = mesh.clone();
        node_group(&mut m, "edge", &[a, b]);
        modal_of(
            &m,
            ModelOptions {
                fix: vec!["zmin".into()],
                couple: vec![format!("edge@{},{},{}", reference[0], reference[1], reference[2])],
                point_mass: vec![format!("edge={mass}")],
                ..Default::default()
            },
            6,
        )
    };
    let diag = line_case(
        &base,
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.7, 0.2, 1.3],
        "300,2,3,4,0,0,0",
    );
    assert!(diag.notes.iter().any(|n| n.contains("one line")), "{:?}", diag.notes);
    let (c, s) = (std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2);
    let rot = |p: [f64; 3]| [c * p[0] + s * p[1], -s * p[0] + c * p[1], p[2]];
    // Rotating by −45° about z maps (1,1,0)/√2 onto the x axis.
    let mut turned = base.clone();
    turned.nodes.iter_mut().for_each(|p| *p = rot(*p));
    // The rotary inertia would turn with the body (I' = R I Rᵀ): keep it isotropic in the x–y
    // plane (Ixx = Iyy) so that the same numbers describe both.
    let iso = "300,3,3,4,0,0,0";
    let d1 = line_case(&base, [0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.7, 0.2, 1.3], iso);
    let (a, b, r) = (rot([0.0, 0.0, 1.0]), rot([1.0, 1.0, 1.0]), rot([0.7, 0.2, 1.3]));
    let d2 = line_case(&turned, a, b, r, iso);
    for (a, b) in d1.frequencies_hz.iter().zip(&d2.frequencies_hz) {
        assert!(rel(*a, *b) < 1e-9, "{:?} vs {:?}", d1.frequencies_hz, d2.frequencies_hz);
    }
}

/// Item 9: a plate of one layer of well-shaped (cubic) plain hex8 cells passed without a word,
/// although one linear layer cannot bend (its first bending frequency is far too high). It is
/// now named; a chunky block with interior nodes and the incompatible-mode hex8 are not.
#[test]
fn one_layer_of_linear_solids_is_named() {
    let notes = |spec: &str, hex8: &str| {
        let mesh = source::load(spec, 1.0).unwrap();
        let opts = ModelOptions {
            hex8: hex8.into(),
            ..Default::default()
        };
        Model::build(&mesh, &opts.spec().unwrap(), "test").unwrap().notes
    };
    let plate = notes("box:0.1,0.1,0.01:10,10,1:hex8", "standard");
    assert!(plate.iter().any(|n| n.contains("one cell thick")), "{plate:?}");
    assert!(plate.iter().any(|n| n.contains("--hex8 incompatible")), "{plate:?}");
    let block = notes("box:0.4,0.4,0.4:4,4,4:hex8", "standard");
    assert!(!block.iter().any(|n| n.contains("one cell thick")), "{block:?}");
    let inc = notes("box:0.1,0.1,0.01:10,10,1:hex8", "incompatible");
    assert!(!inc.iter().any(|n| n.contains("one cell thick")), "{inc:?}");
}

/// Item 15: a request for a quarter or more of a model's modes (500 of 1755 here; 1000 of 3168
/// ran past ten minutes in Lanczos) is solved densely, through M's Cholesky factor so every pair
/// is backward stable, and verified like any other run.
#[test]
fn quarter_of_the_spectrum_is_solved_densely_and_verified() {
    let mesh = source::load("box:0.3,0.2,0.1:12,8,4:hex8", 1.0).unwrap();
    let r = run(&mesh, &[], ModalTarget::Modes(500), None);
    verified("500 of 1755 modes", &r);
    assert_eq!(r.frequencies_hz.len(), 500);
    assert!(r.notes.iter().any(|n| n.contains("solved densely")), "{:?}", r.notes);
    assert_eq!(r.n_rigid, 6);
}
