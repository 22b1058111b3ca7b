//! Couplings and springs on solid nodes (which have no rotations): a coupling of one node or of
//! nodes on one line, a translational spring on one node, and the coupling grammar
//! (`GROUP[@X,Y,Z][:guided=AXIS]`).

use super::modal_requests::verified;
use crate::common::rel;
use vibrofem::analysis::modal::{ModalOptions, ModalReport, ModalTarget, run_modal};
use vibrofem::input::options::ModelOptions;
use vibrofem::input::source;
use vibrofem::mesh::Mesh;

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
