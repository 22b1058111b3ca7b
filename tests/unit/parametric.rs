//! Built-in parametric geometry (`mesh::parametric`): the sandwich work table (shell and solid),
//! the helical coil centreline and the I-beam (shell, line, solid).
//!
//! Checked on every mesh: node and cell counts against hand counts of the grids, no two nodes
//! at the same place, conformity (junction lines share their nodes; the only free edges or
//! faces are on the part's real boundary), orientation (one shell normal per group, positive
//! hexahedron volumes), and areas, volumes and masses against closed forms. Bad parameters
//! must give an error that names the parameter.

#![allow(clippy::needless_range_loop)]

use crate::common::{cross, dot, rel};
use std::collections::{HashMap, HashSet};
use std::f64::consts::PI;

use vibrofem::element::{beam, shell, solid};
use vibrofem::mesh::parametric::{
    self, HelixParams, SandwichParams, grid_solid, helix_beam, helix_orientations, i_beam_line, i_beam_shell,
    i_beam_solid, sandwich_table, sandwich_table_solid,
};
use vibrofem::mesh::{CellKind, Mesh};

const STEEL: f64 = 7850.0;

// ---------------------------------------------------------------------------------------------
// helpers

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Coordinates of the nodes of cell `c` of group `g`.
fn cell_coords(m: &Mesh, block: u32, index: u32) -> (CellKind, Vec<[f64; 3]>) {
    let b = &m.blocks[block as usize];
    (
        b.kind,
        b.cell(index as usize).iter().map(|&n| m.nodes[n as usize]).collect(),
    )
}

/// Cells of a group as (kind, node indices).
fn group_cells(m: &Mesh, name: &str) -> Vec<(CellKind, Vec<u32>)> {
    let g = m.group(name).unwrap();
    g.cells
        .iter()
        .map(|c| {
            let b = &m.blocks[c.block as usize];
            (b.kind, b.cell(c.index as usize).to_vec())
        })
        .collect()
}

/// No two nodes at the same place (coordinates rounded to 1e-9 m), tags 1..=N, every node used.
fn assert_no_duplicates(m: &Mesh) {
    let keys: HashSet<[i64; 3]> = m.nodes.iter().map(|p| p.map(|c| (c * 1e9).round() as i64)).collect();
    assert_eq!(keys.len(), m.n_nodes(), "duplicate nodes");
    assert_eq!(m.node_tags, (1..=m.n_nodes() as u64).collect::<Vec<_>>());
    let mut used = vec![false; m.n_nodes()];
    for b in &m.blocks {
        for &n in &b.conn {
            used[n as usize] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "unused node");
    let tags: Vec<u64> = m.blocks.iter().flat_map(|b| b.tags.iter().copied()).collect();
    assert_eq!(tags, (1..=tags.len() as u64).collect::<Vec<_>>(), "element tags");
}

/// Every node of a quadratic cell that is not a corner sits at the centroid of its corners
/// (edges, faces, body) in gmsh's order.
fn assert_midside_nodes(m: &Mesh) {
    for b in &m.blocks {
        let extra = vibrofem::mesh::generate::higher_order_nodes(b.kind);
        let nc = b.kind.n_nodes() - extra.len();
        for i in 0..b.len() {
            let x: Vec<[f64; 3]> = b.cell(i).iter().map(|&n| m.nodes[n as usize]).collect();
            for (e, set) in extra.iter().enumerate() {
                let mut c = [0.0; 3];
                for &k in *set {
                    for d in 0..3 {
                        c[d] += x[k][d] / set.len() as f64;
                    }
                }
                assert!(norm(sub(c, x[nc + e])) < 1e-12, "{} node {} misplaced", b.kind, nc + e);
            }
        }
    }
}

/// Corner edges of 2D cells of the group `name` (sorted node pairs) with their cell counts.
fn edge_counts(m: &Mesh, name: &str) -> HashMap<(u32, u32), usize> {
    let mut e = HashMap::new();
    for (_, c) in group_cells(m, name) {
        for k in 0..4 {
            let (a, b) = (c[k], c[(k + 1) % 4]);
            *e.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    e
}

/// Unit normal `(x1 − x0) × (x3 − x0)` of a quad.
fn quad_normal(x: &[[f64; 3]]) -> [f64; 3] {
    let n = cross(sub(x[1], x[0]), sub(x[3], x[0]));
    let l = norm(n);
    n.map(|c| c / l)
}

/// Every cell of group `name` has the unit normal `n`.
fn assert_normals(m: &Mesh, name: &str, n: [f64; 3]) {
    let g = m.group(name).unwrap();
    assert!(!g.cells.is_empty());
    for c in &g.cells {
        let (_, x) = cell_coords(m, c.block, c.index);
        assert!(
            dot(quad_normal(&x), n) > 1.0 - 1e-12,
            "{name}: normal {:?}",
            quad_normal(&x)
        );
    }
}

/// Sum of the shell areas of group `name` (Quad4).
fn shell_area(m: &Mesh, name: &str) -> f64 {
    let g = m.group(name).unwrap();
    g.cells
        .iter()
        .map(|c| {
            let (kind, x) = cell_coords(m, c.block, c.index);
            shell::area(kind, &x).unwrap()
        })
        .sum()
}

/// Sum of the solid volumes of group `name`, checking every cell is positively oriented.
fn solid_volume(m: &Mesh, name: &str) -> f64 {
    let g = m.group(name).unwrap();
    assert_eq!(g.dim, 3);
    g.cells
        .iter()
        .map(|c| {
            let (kind, x) = cell_coords(m, c.block, c.index);
            let v = solid::volume(kind, &x).unwrap();
            assert!(v > 0.0);
            v
        })
        .sum()
}

/// Nodes of the cells of group `name` that satisfy `on`.
fn group_nodes_where(m: &Mesh, name: &str, on: impl Fn([f64; 3]) -> bool) -> Vec<u32> {
    let g = m.group(name).unwrap();
    m.group_nodes(g)
        .into_iter()
        .filter(|&n| on(m.nodes[n as usize]))
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

/// Hexahedron faces (corner indices).
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [0, 1, 5, 4],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [4, 5, 6, 7],
];

/// Area of the faces used by exactly one hexahedron of the mesh (its boundary), asserting no
/// face is used by more than two.
fn free_face_area(m: &Mesh) -> f64 {
    let mut faces: HashMap<[u32; 4], (usize, [u32; 4])> = HashMap::new();
    for b in m.blocks.iter().filter(|b| b.kind.dim() == 3) {
        for i in 0..b.len() {
            let c = b.cell(i);
            for f in HEX_FACES {
                let ids = f.map(|k| c[k]);
                let mut key = ids;
                key.sort_unstable();
                faces.entry(key).or_insert((0, ids)).0 += 1;
            }
        }
    }
    let mut area = 0.0;
    for (count, ids) in faces.values() {
        assert!(*count <= 2, "a face shared by {count} cells");
        if *count == 1 {
            let x = ids.map(|n| m.nodes[n as usize]);
            // Rectangles: the diagonals' cross product is twice the area.
            area += 0.5 * norm(cross(sub(x[2], x[0]), sub(x[3], x[1])));
        }
    }
    area
}

fn err_of(r: vibrofem::Result<Mesh>) -> String {
    r.expect_err("expected an error").to_string()
}

// ---------------------------------------------------------------------------------------------
// Sandwich table, shells

#[test]
fn sandwich_paper_counts_groups_and_conventions() {
    let p = SandwichParams::paper();
    let m = sandwich_table(&p).unwrap();
    // Grid by hand (h = 25 mm): x: 1.2/0.025 = 48 cells. y: lines at ±0.3, ±0.2, ±0.15, 0:
    // 4 + 2 + 6 + 6 + 2 + 4 = 24 cells (16 under the bottom plate). Webs: H = 0.1 + 0.0165 =
    // 0.1165 m, ⌈0.1165/0.025⌉ = 5 cells high.
    assert!((p.mid_surface_spacing() - 0.1165).abs() < 1e-15);
    assert_eq!(group_cells(&m, "top_plate").len(), 48 * 24);
    assert_eq!(group_cells(&m, "bottom_plate").len(), 48 * 16);
    assert_eq!(group_cells(&m, "webs_long").len(), 3 * 48 * 5);
    assert_eq!(group_cells(&m, "table").len(), 48 * 24 + 48 * 16 + 3 * 48 * 5);
    assert_eq!(m.n_cells_of_dim(2), 2640);
    // Nodes: top 49 × 25, bottom 49 × 17, the webs' 4 inner z levels 3 × 49 × 4.
    assert_eq!(m.n_nodes(), 49 * 25 + 49 * 17 + 3 * 49 * 4);
    // Perimeters: 2 × (48 + 24) and 2 × (48 + 16) edges.
    assert_eq!(group_cells(&m, "top_edges").len(), 144);
    assert_eq!(group_cells(&m, "bottom_edges").len(), 128);
    assert!(m.group("webs_trans").is_err(), "no transverse webs: no group");
    for name in ["top_plate", "bottom_plate", "webs_long", "table"] {
        assert_eq!(m.group(name).unwrap().dim, 2);
    }
    assert_eq!(m.group("bottom_edges").unwrap().dim, 1);
    assert_eq!(m.blocks[0].kind, CellKind::Quad4, "2D cells come first");
    assert_no_duplicates(&m);

    // Coordinates: centred, bottom mid-surface at z = 0, top at z = H.
    let (lo, hi) = m.bounding_box();
    assert_eq!(lo, [-0.6, -0.3, 0.0]);
    assert!(hi[0] == 0.6 && hi[1] == 0.3 && (hi[2] - 0.1165).abs() < 1e-15);
    for n in group_nodes_where(&m, "top_plate", |_| true) {
        assert!((m.nodes[n as usize][2] - 0.1165).abs() < 1e-15);
    }
    for n in group_nodes_where(&m, "bottom_edges", |_| true) {
        let x = m.nodes[n as usize];
        assert!(x[2] == 0.0 && (close(x[0].abs(), 0.6) || close(x[1].abs(), 0.2)));
    }
    // Bottom perimeter is counter-clockwise seen from +z: signed area (shoelace) = +L × B.
    let mut shoelace = 0.0;
    for (_, c) in group_cells(&m, "bottom_edges") {
        let (a, b) = (m.nodes[c[0] as usize], m.nodes[c[1] as usize]);
        shoelace += 0.5 * (a[0] * b[1] - b[0] * a[1]);
    }
    assert!((shoelace - 1.2 * 0.4).abs() < 1e-12);

    // Spacing ≤ h everywhere.
    for (_, c) in group_cells(&m, "table") {
        for k in 0..4 {
            let d = norm(sub(m.nodes[c[k] as usize], m.nodes[c[(k + 1) % 4] as usize]));
            assert!(d <= 0.025 + 1e-12, "edge {d}");
        }
    }
    // Thicknesses per group.
    assert_eq!(
        p.thicknesses(),
        vec![
            ("top_plate".to_string(), 0.025),
            ("bottom_plate".to_string(), 0.008),
            ("webs_long".to_string(), 0.0045)
        ]
    );
}

#[test]
fn sandwich_junctions_are_conforming() {
    let mut p = SandwichParams::paper();
    p.trans_webs = vec![-0.4, 0.0, 0.4];
    p.trans_web_thickness = 0.006;
    let m = sandwich_table(&p).unwrap();
    assert_no_duplicates(&m);
    let hz = p.mid_surface_spacing();
    let nz = 5;
    // Junction line bottom plate / middle web (y = 0, z = 0): the same 49 nodes in both.
    let on = |x: [f64; 3]| x[1] == 0.0 && x[2] == 0.0;
    let bot = group_nodes_where(&m, "bottom_plate", on);
    let web = group_nodes_where(&m, "webs_long", on);
    assert_eq!(bot.len(), 49);
    assert_eq!(bot, web);
    // Top plate / outer web (y = 0.15, z = H).
    let on = |x: [f64; 3]| close(x[1], 0.15) && close(x[2], hz);
    let top = group_nodes_where(&m, "top_plate", on);
    assert_eq!(top.len(), 49);
    assert_eq!(top, group_nodes_where(&m, "webs_long", on));
    // Transverse web / bottom plate (x = 0.4, z = 0): across the bottom plate's width (16 cells).
    let on = |x: [f64; 3]| close(x[0], 0.4) && x[2] == 0.0;
    let tr = group_nodes_where(&m, "webs_trans", on);
    assert_eq!(tr.len(), 17);
    assert_eq!(tr, group_nodes_where(&m, "bottom_plate", on));
    // Crossing of a transverse and a longitudinal web (x = −0.4, y = −0.15): a vertical line of
    // nz + 1 nodes shared by both.
    let on = |x: [f64; 3]| close(x[0], -0.4) && close(x[1], -0.15);
    let tr = group_nodes_where(&m, "webs_trans", on);
    assert_eq!(tr.len(), nz + 1);
    assert_eq!(tr, group_nodes_where(&m, "webs_long", on));

    // No hanging edge anywhere: every edge used by a single cell lies on the real boundary
    // (plate perimeters, the webs' free vertical ends at x = ±0.6, the transverse webs' free
    // ends at y = ±0.2 between the plates).
    for ((a, b), count) in edge_counts(&m, "table") {
        let (xa, xb) = (m.nodes[a as usize], m.nodes[b as usize]);
        let mid = [0.5 * (xa[0] + xb[0]), 0.5 * (xa[1] + xb[1]), 0.5 * (xa[2] + xb[2])];
        let boundary = close(mid[0].abs(), 0.6)
            || (mid[2] == 0.0 && close(mid[1].abs(), 0.2))
            || (close(mid[2], hz) && close(mid[1].abs(), 0.3))
            || (xa[2] != xb[2] && close(mid[1].abs(), 0.2));
        assert!(count >= 2 || boundary, "free edge inside the table at {mid:?}");
        assert!(count <= 4, "edge shared by {count} cells");
    }
    // T-junction edges: used by 3 cells (two plate cells and one web cell); crossings: 4.
    let counts: Vec<usize> = edge_counts(&m, "table").into_values().collect();
    assert!(counts.contains(&3) && counts.contains(&4));
}

#[test]
fn sandwich_normals_areas_and_masses() {
    let mut p = SandwichParams::paper();
    p.trans_webs = vec![-0.5, 0.5];
    p.trans_web_thickness = 0.008;
    p.elem_size = 0.02;
    let m = sandwich_table(&p).unwrap();
    assert_normals(&m, "top_plate", [0.0, 0.0, 1.0]);
    assert_normals(&m, "bottom_plate", [0.0, 0.0, 1.0]);
    assert_normals(&m, "webs_long", [0.0, 1.0, 0.0]);
    assert_normals(&m, "webs_trans", [1.0, 0.0, 0.0]);
    let hz = p.mid_surface_spacing();
    let areas = [
        ("top_plate", 1.2 * 0.6),
        ("bottom_plate", 1.2 * 0.4),
        ("webs_long", 3.0 * 1.2 * hz),
        ("webs_trans", 2.0 * 0.4 * hz),
    ];
    let mut shell_volume = 0.0;
    let thick: HashMap<String, f64> = p.thicknesses().into_iter().collect();
    assert_eq!(thick.len(), 4);
    for (g, a) in areas {
        let got = shell_area(&m, g);
        assert!(rel(got, a) < 1e-13, "{g}: area {got} vs {a}");
        shell_volume += got * thick[g];
    }
    assert!(rel(shell_area(&m, "table"), areas.iter().map(|a| a.1).sum()) < 1e-13);
    // The shell model carries Σ area × thickness.
    assert!(rel(shell_volume, p.shell_volume()) < 1e-13);
    assert!(rel(p.shell_mass(STEEL), STEEL * shell_volume) < 1e-13);
    // Real volume by hand: plates + webs over the 0.1 m clear height − 6 crossings.
    let v = 1.2 * 0.6 * 0.025 + 1.2 * 0.4 * 0.008 + 3.0 * 1.2 * 0.1 * 0.0045 + 2.0 * 0.4 * 0.1 * 0.008
        - 6.0 * 0.0045 * 0.008 * 0.1;
    assert!(rel(p.volume(), v) < 1e-14);
    // The documented difference: junction strips and crossings counted twice by the shells.
    let diff = 0.0165 * (3.0 * 1.2 * 0.0045 + 2.0 * 0.4 * 0.008) + 6.0 * 0.0045 * 0.008 * 0.1;
    assert!(rel(p.shell_volume() - p.volume(), diff) < 1e-10);
}

#[test]
fn sandwich_paper_mass() {
    // S7 reconstruction: 0.018 + 0.00384 + 0.00162 = 0.02346 m³ → 184.161 kg (published 163 kg
    // for the real table, whose top plate is thinned toward the edges).
    let p = SandwichParams::paper();
    assert!(rel(p.volume(), 0.02346) < 1e-14);
    assert!(rel(p.mass(STEEL), 184.161) < 1e-12);
    // The shell model adds the junction strips: 3 × 1.2 × 0.0045 × 0.0165 m³ = 2.098 kg (+1.1 %).
    assert!(rel(p.shell_mass(STEEL) - p.mass(STEEL), 3.0 * 1.2 * 0.0045 * 0.0165 * STEEL) < 1e-10);
    assert_eq!(SandwichParams::evenly_spaced(3, -0.15, 0.15), p.long_webs);
    assert_eq!(SandwichParams::evenly_spaced(1, -0.15, 0.15), vec![0.0]);
    assert!(SandwichParams::evenly_spaced(0, -0.15, 0.15).is_empty());
}

#[test]
fn sandwich_quadratic_shells_share_midside_nodes() {
    for (kind, nodes) in [
        // Quad9: lattice of half-steps: top 97 × 49, bottom 97 × 33, webs 3 × 97 × 9 inner
        // half-levels. Quad8: the same without the 2640 cell centres.
        (CellKind::Quad9, 97 * 49 + 97 * 33 + 3 * 97 * 9),
        (CellKind::Quad8, 97 * 49 + 97 * 33 + 3 * 97 * 9 - 2640),
    ] {
        let p = SandwichParams {
            shell_kind: kind,
            ..SandwichParams::paper()
        };
        let m = sandwich_table(&p).unwrap();
        assert_eq!(m.n_cells_of_dim(2), 2640);
        assert_eq!(m.n_nodes(), nodes, "{kind}");
        assert_eq!(m.blocks[0].kind, kind);
        assert_eq!(m.blocks[1].kind, CellKind::Line3);
        assert_no_duplicates(&m);
        assert_midside_nodes(&m);
        // Junction y = 0, z = 0: corners and midside nodes (2 × 48 + 1) shared.
        let on = |x: [f64; 3]| x[1] == 0.0 && x[2] == 0.0;
        let bot = group_nodes_where(&m, "bottom_plate", on);
        assert_eq!(bot.len(), 97);
        assert_eq!(bot, group_nodes_where(&m, "webs_long", on));
    }
}

#[test]
fn sandwich_web_positions_need_not_be_on_the_uniform_grid() {
    // Odd positions: lines are inserted, spacing stays ≤ h, webs conform.
    let p = SandwichParams {
        long_webs: vec![-0.137, 0.011, 0.1234, 0.19],
        trans_webs: vec![-0.3333, 0.21],
        elem_size: 0.03,
        ..SandwichParams::paper()
    };
    let m = sandwich_table(&p).unwrap();
    assert_no_duplicates(&m);
    for y in [-0.137, 0.011, 0.1234, 0.19] {
        let on = |x: [f64; 3]| (x[1] - y).abs() < 1e-12 && x[2] == 0.0;
        let bot = group_nodes_where(&m, "bottom_plate", on);
        assert!(bot.len() >= 41, "x has ≥ 40 cells");
        assert_eq!(bot, group_nodes_where(&m, "webs_long", on));
    }
    for (_, c) in group_cells(&m, "table") {
        for k in 0..4 {
            let d = norm(sub(m.nodes[c[k] as usize], m.nodes[c[(k + 1) % 4] as usize]));
            assert!(d <= 0.03 + 1e-12);
        }
    }
    assert!(rel(shell_area(&m, "webs_trans"), 2.0 * 0.4 * p.mid_surface_spacing()) < 1e-13);
}

// ---------------------------------------------------------------------------------------------
// Sandwich table, solid

#[test]
fn sandwich_solid_volumes_and_layout() {
    let p = SandwichParams::paper();
    let m = sandwich_table_solid(&p, 0.025, CellKind::Hex8).unwrap();
    assert_no_duplicates(&m);
    let parts = [
        ("top_plate", 1.2 * 0.6 * 0.025),
        ("bottom_plate", 1.2 * 0.4 * 0.008),
        ("webs_long", 3.0 * 1.2 * 0.1 * 0.0045),
    ];
    let mut sum = 0.0;
    for (g, v) in parts {
        let got = solid_volume(&m, g);
        assert!(rel(got, v) < 1e-12, "{g}: {got} vs {v}");
        sum += got;
    }
    let total = solid_volume(&m, "table");
    assert!(rel(total, sum) < 1e-13);
    assert!(rel(total, p.volume()) < 1e-12);
    assert!(m.group("webs_trans").is_err());
    // The plates' mid-planes are the shell model's mid-surfaces.
    let (lo, hi) = m.bounding_box();
    assert!(close(lo[2], -0.004) && close(hi[2], 0.1165 + 0.0125));
    assert_eq!([lo[0], lo[1], hi[0], hi[1]], [-0.6, -0.3, 0.6, 0.3]);
    // Cells: x 48; y lines at ±0.3, ±0.2, ±0.15 ± 0.00225, ±0.00225: 4 + 2 + 1 + 6 + 1 + 6 + 1
    // + 2 + 4 = 27 cells (19 under the bottom plate); z: 1 (bottom) + 4 (webs) + 1 (top).
    assert_eq!(group_cells(&m, "top_plate").len(), 48 * 27);
    assert_eq!(group_cells(&m, "bottom_plate").len(), 48 * 19);
    assert_eq!(
        group_cells(&m, "webs_long").len(),
        3 * 48 * 4,
        "webs: one cell thick, 4 high"
    );
    // The boundary (free faces) is exactly the solid's surface area: no face is left unshared
    // inside, none shared by three.
    let (l, bt, bb, tt, tb, hw, tw) = (1.2, 0.6, 0.4, 0.025, 0.008, 0.1, 0.0045);
    let area = 2.0 * l * bt + 2.0 * (l + bt) * tt - 3.0 * l * tw + 2.0 * l * bb + 2.0 * (l + bb) * tb - 3.0 * l * tw
        + 3.0 * (2.0 * l * hw + 2.0 * hw * tw);
    assert!(rel(free_face_area(&m), area) < 1e-12);
    // The underside of the bottom plate is "zmin", with outward normals −z.
    assert!(rel(shell_area(&m, "zmin"), l * bb) < 1e-12);
    assert_normals(&m, "zmin", [0.0, 0.0, -1.0]);
    assert_normals(&m, "zmax", [0.0, 0.0, 1.0]);
    assert_normals(&m, "xmax", [1.0, 0.0, 0.0]);
    assert!(rel(shell_area(&m, "xmin"), bt * tt + bb * tb + 3.0 * hw * tw) < 1e-12);
}

#[test]
fn sandwich_solid_with_transverse_webs_quadratic() {
    let p = SandwichParams {
        trans_webs: vec![-0.3, 0.3],
        trans_web_thickness: 0.006,
        ..SandwichParams::paper()
    };
    for kind in [CellKind::Hex20, CellKind::Hex27] {
        let m = sandwich_table_solid(&p, 0.05, kind).unwrap();
        assert_no_duplicates(&m);
        assert_midside_nodes(&m);
        let v_trans = 2.0 * (0.4 * 0.1 * 0.006 - 3.0 * 0.0045 * 0.006 * 0.1);
        assert!(rel(solid_volume(&m, "webs_trans"), v_trans) < 1e-12);
        assert!(rel(solid_volume(&m, "webs_long"), 3.0 * 1.2 * 0.1 * 0.0045) < 1e-12);
        assert!(rel(solid_volume(&m, "table"), p.volume()) < 1e-12);
        free_face_area(&m); // no face shared by three cells
        // Faces of the quadratic kind.
        let face = if kind == CellKind::Hex20 {
            CellKind::Quad8
        } else {
            CellKind::Quad9
        };
        assert!(group_cells(&m, "zmin").iter().all(|(k, _)| *k == face));
    }
}

// ---------------------------------------------------------------------------------------------
// grid_solid

#[test]
fn grid_solid_keeps_selected_cells() {
    let l = [0.0, 0.5, 1.0];
    let m = grid_solid([&l, &l, &l], CellKind::Hex8, |c| c[0] < 0.5 || c[2] < 0.5).unwrap();
    assert_eq!(m.n_cells_of_dim(3), 6);
    assert_eq!(m.n_nodes(), 27 - 3);
    assert!(rel(solid_volume(&m, "volume"), 0.75) < 1e-14);
    // Free faces: the L-block's surface: 2 × 0.75 (y faces) + 1 + 1 + 0.5 + 0.5 + 0.5 + 0.5.
    assert!(rel(free_face_area(&m), 5.5) < 1e-14);
    // Only bounding-box faces are grouped: zmax has the 2 faces over x < 0.5.
    assert_eq!(group_cells(&m, "zmax").len(), 2);
    // Hex20 on the 2 × 2 × 2 grid: 27 corners + 54 edge midpoints, shared.
    let m = grid_solid([&l, &l, &l], CellKind::Hex20, |_| true).unwrap();
    assert_eq!(m.n_nodes(), 27 + 54);
    assert_no_duplicates(&m);
    assert_midside_nodes(&m);
    assert!(rel(solid_volume(&m, "volume"), 1.0) < 1e-14);
}

// ---------------------------------------------------------------------------------------------
// Helix

#[test]
fn helix_paper_geometry_and_length() {
    let p = HelixParams::paper();
    let m = helix_beam(&p).unwrap();
    let ne = 6 * 24;
    assert_eq!(p.n_elements(), ne);
    assert_eq!(m.n_nodes(), ne + 1);
    assert_eq!(m.n_cells_of_dim(1), ne);
    assert_no_duplicates(&m);
    let r = 0.016;
    for x in &m.nodes {
        assert!((x[0].hypot(x[1]) - r).abs() < 1e-15);
    }
    // Ends.
    let end = |g: &str| {
        let c = group_cells(&m, g);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].0, CellKind::Point1);
        m.nodes[c[0].1[0] as usize]
    };
    assert_eq!(end("end_bottom"), [r, 0.0, 0.0]);
    let top = end("end_top");
    assert!(norm(sub(top, [r, 0.0, 0.06])) < 1e-15);
    assert_eq!(m.group("end_top").unwrap().dim, 0);
    assert_eq!(group_cells(&m, "wire").len(), ne);
    assert_eq!(group_cells(&m, "coil").len(), ne);

    // Length: exact helix n √((πD)² + p²); the chords of 24 elements per turn are shorter by
    // the factor sin(x)/x (x = Δθ/2 = π/24) on the circumferential part only:
    // 1 − L_h/L = f (1 − sin x / x) + O(x⁴), f = (πD)²/((πD)² + p²).
    let exact = 6.0 * ((PI * 0.032f64).powi(2) + 0.01f64.powi(2)).sqrt();
    assert!(rel(p.wire_length(), exact) < 1e-15);
    let lh: f64 = group_cells(&m, "wire")
        .iter()
        .map(|(k, c)| beam::length(*k, &[m.nodes[c[0] as usize], m.nodes[c[1] as usize]]))
        .sum();
    let x = PI / 24.0;
    let chord_err = 1.0 - x.sin() / x; // 2.85e-3
    let f = (PI * 0.032f64).powi(2) / ((PI * 0.032f64).powi(2) + 1e-4);
    let err = 1.0 - lh / exact;
    assert!(err > 0.0 && err < chord_err, "chord error {err}");
    assert!((err - f * chord_err).abs() < 1e-5, "{err} vs {}", f * chord_err);
    // Exact chord sum by hand.
    let dtheta = 2.0 * x;
    let chord = ((2.0 * r * x.sin()).powi(2) + (0.01 * dtheta / (2.0 * PI)).powi(2)).sqrt();
    assert!(rel(lh, ne as f64 * chord) < 1e-12);
    // Mass.
    assert!(rel(p.mass(STEEL), STEEL * PI * 0.006f64.powi(2) / 4.0 * exact) < 1e-15);
}

#[test]
fn helix_line3_and_orientations() {
    let p = HelixParams {
        kind: CellKind::Line3,
        turns: 6.3,
        ..HelixParams::paper()
    };
    let m = helix_beam(&p).unwrap();
    let ne = 152; // ⌈6.3 × 24⌉ = ⌈151.2⌉
    assert_eq!(p.n_elements(), ne);
    assert_eq!(m.n_nodes(), 2 * ne + 1);
    assert_no_duplicates(&m);
    let wire = group_cells(&m, "wire");
    assert!(wire.iter().all(|(k, _)| *k == CellKind::Line3));
    // Midside nodes on the helix between their end nodes.
    for (_, c) in &wire {
        assert_eq!(c[2], c[0] + 1);
        assert_eq!(c[1], c[0] + 2);
    }
    // Arc length of quadratic elements: the interpolation error is O(Δθ⁴).
    let lh: f64 = wire
        .iter()
        .map(|(k, c)| beam::length(*k, &c.iter().map(|&n| m.nodes[n as usize]).collect::<Vec<_>>()))
        .sum();
    assert!(rel(lh, p.wire_length()) < 2e-5, "{}", rel(lh, p.wire_length()));
    assert!(rel(m.nodes[2 * ne][2], 0.063) < 1e-14);

    // One orientation per element: unit, horizontal, radial at the mid-angle, exactly
    // perpendicular to the chord, and accepted by the beam's local axes.
    let o = helix_orientations(&p).unwrap();
    assert_eq!(o.len(), ne);
    for ((_, c), v) in wire.iter().zip(&o) {
        let (a, b, mid) = (m.nodes[c[0] as usize], m.nodes[c[1] as usize], m.nodes[c[2] as usize]);
        assert!((norm(*v) - 1.0).abs() < 1e-15 && v[2] == 0.0);
        let chord = sub(b, a);
        assert!(dot(chord, *v).abs() < 1e-13 * norm(chord));
        let radial = [mid[0] / 0.016, mid[1] / 0.016, 0.0];
        assert!(dot(radial, *v) > 1.0 - 1e-14);
        let axes = beam::local_axes(chord, *v).unwrap();
        assert!(dot(axes[1], *v) > 1.0 - 1e-14);
    }
}

// ---------------------------------------------------------------------------------------------
// I-beam

const H: f64 = 0.1;
const B: f64 = 0.055;
const S: f64 = 0.0045;
const T: f64 = 0.0072;
const L: f64 = 1.2;

#[test]
fn i_beam_shell_mesh() {
    let m = i_beam_shell(H, B, S, T, L, 0.01).unwrap();
    assert_no_duplicates(&m);
    // x: 120 cells; y: lines at ±0.0275, 0 → 3 + 3 cells; web height 0.0928 → 10 cells.
    assert_eq!(group_cells(&m, "flange_top").len(), 120 * 6);
    assert_eq!(group_cells(&m, "flange_bottom").len(), 120 * 6);
    assert_eq!(group_cells(&m, "web").len(), 120 * 10);
    assert_eq!(group_cells(&m, "beam").len(), 120 * 22);
    assert_eq!(m.n_nodes(), 121 * (7 + 7 + 9));
    assert_normals(&m, "flange_top", [0.0, 0.0, 1.0]);
    assert_normals(&m, "flange_bottom", [0.0, 0.0, 1.0]);
    assert_normals(&m, "web", [0.0, 1.0, 0.0]);
    let hf = H - T;
    assert!(rel(shell_area(&m, "flange_top"), B * L) < 1e-13);
    assert!(rel(shell_area(&m, "web"), hf * L) < 1e-13);
    for z in [-hf / 2.0, hf / 2.0] {
        let on = |x: [f64; 3]| x[1] == 0.0 && close(x[2], z);
        let web = group_nodes_where(&m, "web", on);
        assert_eq!(web.len(), 121);
        let fl = if z > 0.0 { "flange_top" } else { "flange_bottom" };
        assert_eq!(web, group_nodes_where(&m, fl, on));
    }
    // End sections: 2 × 6 flange edges + 10 web edges at each end, all at x = 0 or L.
    for (g, x) in [("end_a", 0.0), ("end_b", L)] {
        let c = group_cells(&m, g);
        assert_eq!(c.len(), 22);
        assert_eq!(m.group(g).unwrap().dim, 1);
        assert!(
            c.iter()
                .flat_map(|(_, c)| c.iter())
                .all(|&n| m.nodes[n as usize][0] == x)
        );
    }
    assert_eq!(
        parametric::i_beam_thicknesses(S, T),
        vec![("flange_top".into(), T), ("flange_bottom".into(), T), ("web".into(), S)]
    );
}

#[test]
fn i_beam_line_mesh() {
    let m = i_beam_line(L, 40).unwrap();
    assert_eq!(m.n_nodes(), 41);
    assert_eq!(group_cells(&m, "beam").len(), 40);
    assert_no_duplicates(&m);
    let a = group_cells(&m, "end_a");
    let b = group_cells(&m, "end_b");
    assert_eq!(m.nodes[a[0].1[0] as usize], [0.0, 0.0, 0.0]);
    assert_eq!(m.nodes[b[0].1[0] as usize], [L, 0.0, 0.0]);
    let len: f64 = group_cells(&m, "beam")
        .iter()
        .map(|(k, c)| beam::length(*k, &[m.nodes[c[0] as usize], m.nodes[c[1] as usize]]))
        .sum();
    assert!(rel(len, L) < 1e-14);
}

#[test]
fn i_beam_solid_mesh() {
    let area = 2.0 * B * T + (H - 2.0 * T) * S;
    for kind in [CellKind::Hex8, CellKind::Hex20] {
        let m = i_beam_solid(H, B, S, T, L, 0.01, kind).unwrap();
        assert_no_duplicates(&m);
        assert_midside_nodes(&m);
        assert!(rel(solid_volume(&m, "volume"), area * L) < 1e-12);
        assert!(rel(solid_volume(&m, "beam"), area * L) < 1e-12);
        assert!(rel(solid_volume(&m, "flange_top"), B * T * L) < 1e-12);
        assert!(rel(solid_volume(&m, "web"), (H - 2.0 * T) * S * L) < 1e-12);
        // End faces: the section's area.
        assert!(rel(shell_area_any(&m, "end_a"), area) < 1e-12);
        assert!(rel(shell_area_any(&m, "end_b"), area) < 1e-12);
        // Web one cell thick (s < h), flanges one cell thick (t < h).
        // Section cells: y grid: 3 + 1 + 3 over the flange (b/2 − s/2 = 25.25 mm → 3 cells);
        // z grid: 1 + 9 + 1 (web 85.6 mm → 9 cells). Flanges 7 cells, web 9 cells.
        assert_eq!(m.n_cells_of_dim(3), 120 * (7 + 7 + 9));
        if kind == CellKind::Hex8 {
            assert!(
                rel(
                    free_face_area(&m),
                    2.0 * area + L * (2.0 * (B + B - S) + 4.0 * T + 2.0 * (H - 2.0 * T))
                ) < 1e-12
            );
        }
    }
}

/// Area of a group of faces (Quad4/Quad8/Quad9 rectangles in any plane).
fn shell_area_any(m: &Mesh, name: &str) -> f64 {
    group_cells(m, name)
        .iter()
        .map(|(_, c)| {
            let x: Vec<[f64; 3]> = c[..4].iter().map(|&n| m.nodes[n as usize]).collect();
            0.5 * norm(cross(sub(x[2], x[0]), sub(x[3], x[1])))
        })
        .sum()
}

// ---------------------------------------------------------------------------------------------
// Bad input

#[test]
fn bad_sandwich_parameters_name_the_parameter() {
    let base = SandwichParams::paper();
    let cases: Vec<(SandwichParams, &str)> = vec![
        (
            SandwichParams {
                top_thickness: -0.01,
                ..base.clone()
            },
            "top_thickness",
        ),
        (
            SandwichParams {
                bottom_width: 0.0,
                ..base.clone()
            },
            "bottom_width",
        ),
        (
            SandwichParams {
                web_height: f64::NAN,
                ..base.clone()
            },
            "web_height",
        ),
        (
            SandwichParams {
                elem_size: 0.0,
                ..base.clone()
            },
            "elem_size",
        ),
        (
            SandwichParams {
                long_web_thickness: -1.0,
                ..base.clone()
            },
            "long_web_thickness",
        ),
        (
            SandwichParams {
                long_webs: vec![-0.15, 0.0, 0.002],
                ..base.clone()
            },
            "overlap",
        ),
        (
            SandwichParams {
                long_webs: vec![0.0, 0.25],
                ..base.clone()
            },
            "outside the plates",
        ),
        (
            SandwichParams {
                long_webs: vec![0.0, 0.199],
                ..base.clone()
            },
            "long_webs",
        ),
        (
            SandwichParams {
                trans_webs: vec![0.7],
                ..base.clone()
            },
            "trans_webs",
        ),
        (
            SandwichParams {
                trans_webs: vec![0.1, 0.105],
                trans_web_thickness: 0.01,
                ..base.clone()
            },
            "trans_web_thickness",
        ),
        (
            SandwichParams {
                long_webs: vec![],
                ..base.clone()
            },
            "long_webs and trans_webs",
        ),
        (
            SandwichParams {
                shell_kind: CellKind::Tri3,
                ..base.clone()
            },
            "shell_kind",
        ),
        (
            SandwichParams {
                elem_size: 1e-7,
                ..base.clone()
            },
            "elem_size",
        ),
    ];
    for (p, word) in cases {
        let e = err_of(sandwich_table(&p));
        assert!(e.contains(word), "'{e}' should name {word}");
        assert!(e.starts_with("sandwich table"), "{e}");
        // The solid checks the same geometry, and ignores the shell mesh controls.
        let r = sandwich_table_solid(&p, 0.05, CellKind::Hex8);
        if word == "elem_size" || word == "shell_kind" {
            assert!(r.is_ok());
        } else {
            let e = err_of(r);
            assert!(e.contains(word), "solid: '{e}' should name {word}");
        }
    }
    assert!(err_of(sandwich_table_solid(&base, -0.05, CellKind::Hex8)).contains("h must be positive"));
    assert!(err_of(sandwich_table_solid(&base, 1e-5, CellKind::Hex8)).contains("limit"));
    assert!(err_of(sandwich_table_solid(&base, 0.05, CellKind::Tet10)).contains("hex8, hex20 or hex27"));
    // A web exactly touching the bottom plate's edge is fine; touching webs are fine.
    let ok = SandwichParams {
        long_webs: vec![-0.2 + 0.00225, 0.0, 0.0045, 0.2 - 0.00225],
        ..base
    };
    assert!(sandwich_table(&ok).is_ok());
    assert!(sandwich_table_solid(&ok, 0.05, CellKind::Hex8).is_ok());
}

#[test]
fn bad_helix_and_i_beam_parameters_name_the_parameter() {
    let base = HelixParams::paper();
    let cases: Vec<(HelixParams, &str)> = vec![
        (
            HelixParams {
                mean_diameter: -0.03,
                ..base.clone()
            },
            "mean_diameter",
        ),
        (
            HelixParams {
                pitch: 0.005,
                ..base.clone()
            },
            "pitch",
        ),
        (
            HelixParams {
                turns: 0.0,
                ..base.clone()
            },
            "turns",
        ),
        (
            HelixParams {
                elems_per_turn: 2,
                ..base.clone()
            },
            "elems_per_turn",
        ),
        (
            HelixParams {
                wire_diameter: 0.04,
                pitch: 0.05,
                ..base.clone()
            },
            "wire_diameter",
        ),
        (
            HelixParams {
                kind: CellKind::Quad4,
                ..base.clone()
            },
            "kind",
        ),
    ];
    for (p, word) in cases {
        let e = err_of(helix_beam(&p));
        assert!(e.contains(word) && e.starts_with("helix"), "'{e}' should name {word}");
        assert!(helix_orientations(&p).is_err());
    }

    let e = err_of(i_beam_shell(H, B, S, 0.06, L, 0.01));
    assert!(e.contains("flange thickness t"), "{e}");
    let e = err_of(i_beam_solid(H, B, 0.06, T, L, 0.01, CellKind::Hex8));
    assert!(e.contains("web thickness s"), "{e}");
    let e = err_of(i_beam_shell(H, B, S, T, -1.0, 0.01));
    assert!(e.contains("length must be positive"), "{e}");
    let e = err_of(i_beam_shell(H, B, S, T, L, 0.0));
    assert!(e.contains("elem_size"), "{e}");
    let e = err_of(i_beam_solid(H, B, S, T, L, 0.01, CellKind::Wedge6));
    assert!(e.contains("hex8"), "{e}");
    let e = err_of(i_beam_line(L, 0));
    assert!(e.contains("n_elem"), "{e}");
    let e = err_of(i_beam_line(0.0, 4));
    assert!(e.contains("length"), "{e}");
    let l = [0.0, 1.0, 1.0];
    assert!(err_of(grid_solid([&l, &l, &l], CellKind::Hex8, |_| true)).contains("strictly increasing"));
    let l = [0.0, 1.0];
    assert!(err_of(grid_solid([&l, &l, &l], CellKind::Hex8, |_| false)).contains("no grid cell"));
}
