//! Cell kinds, in gmsh's node ordering.
//!
//! vibrofem keeps gmsh's node ordering everywhere internally; writers permute only at output
//! (see `io::vtk`). The reference-element diagrams of each kind are in the docs of
//! [`crate::fe::shape`].

/// The cells vibrofem reads. Solid analysis uses the 3D kinds; lower-dimensional kinds carry
/// boundary groups (and later shells and beams).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CellKind {
    /// 1-node point (gmsh 15).
    Point1,
    /// 2-node line (gmsh 1).
    Line2,
    /// 3-node line (gmsh 8).
    Line3,
    /// 3-node triangle (gmsh 2).
    Tri3,
    /// 6-node triangle (gmsh 9).
    Tri6,
    /// 4-node quadrilateral (gmsh 3).
    Quad4,
    /// 8-node serendipity quadrilateral (gmsh 16).
    Quad8,
    /// 9-node Lagrange quadrilateral (gmsh 10).
    Quad9,
    /// 4-node tetrahedron (gmsh 4).
    Tet4,
    /// 10-node tetrahedron (gmsh 11).
    Tet10,
    /// 8-node hexahedron (gmsh 5).
    Hex8,
    /// 20-node serendipity hexahedron (gmsh 17).
    Hex20,
    /// 27-node Lagrange hexahedron (gmsh 12).
    Hex27,
    /// 6-node wedge / prism (gmsh 6).
    Wedge6,
    /// 15-node serendipity wedge (gmsh 18).
    Wedge15,
}

impl CellKind {
    /// Every kind, for sweeps in tests.
    pub const ALL: [CellKind; 15] = [
        CellKind::Point1,
        CellKind::Line2,
        CellKind::Line3,
        CellKind::Tri3,
        CellKind::Tri6,
        CellKind::Quad4,
        CellKind::Quad8,
        CellKind::Quad9,
        CellKind::Tet4,
        CellKind::Tet10,
        CellKind::Hex8,
        CellKind::Hex20,
        CellKind::Hex27,
        CellKind::Wedge6,
        CellKind::Wedge15,
    ];

    /// The solid (3D) kinds.
    pub const SOLIDS: [CellKind; 7] = [
        CellKind::Tet4,
        CellKind::Tet10,
        CellKind::Hex8,
        CellKind::Hex20,
        CellKind::Hex27,
        CellKind::Wedge6,
        CellKind::Wedge15,
    ];

    /// Number of nodes.
    pub const fn n_nodes(self) -> usize {
        match self {
            CellKind::Point1 => 1,
            CellKind::Line2 => 2,
            CellKind::Line3 => 3,
            CellKind::Tri3 => 3,
            CellKind::Tri6 => 6,
            CellKind::Quad4 => 4,
            CellKind::Quad8 => 8,
            CellKind::Quad9 => 9,
            CellKind::Tet4 => 4,
            CellKind::Tet10 => 10,
            CellKind::Hex8 => 8,
            CellKind::Hex20 => 20,
            CellKind::Hex27 => 27,
            CellKind::Wedge6 => 6,
            CellKind::Wedge15 => 15,
        }
    }

    /// Topological dimension of the reference cell.
    pub const fn dim(self) -> usize {
        match self {
            CellKind::Point1 => 0,
            CellKind::Line2 | CellKind::Line3 => 1,
            CellKind::Tri3 | CellKind::Tri6 | CellKind::Quad4 | CellKind::Quad8 | CellKind::Quad9 => 2,
            CellKind::Tet4
            | CellKind::Tet10
            | CellKind::Hex8
            | CellKind::Hex20
            | CellKind::Hex27
            | CellKind::Wedge6
            | CellKind::Wedge15 => 3,
        }
    }

    /// Polynomial order of the geometry/field interpolation (1 or 2).
    pub const fn order(self) -> usize {
        match self {
            CellKind::Point1
            | CellKind::Line2
            | CellKind::Tri3
            | CellKind::Quad4
            | CellKind::Tet4
            | CellKind::Hex8
            | CellKind::Wedge6 => 1,
            CellKind::Line3
            | CellKind::Tri6
            | CellKind::Quad8
            | CellKind::Quad9
            | CellKind::Tet10
            | CellKind::Hex20
            | CellKind::Hex27
            | CellKind::Wedge15 => 2,
        }
    }

    /// The linear kind on this kind's corner nodes (which are its first nodes, in gmsh
    /// order): `Tet10` → `Tet4`, `Hex20`/`Hex27` → `Hex8`; a linear kind is its own.
    pub const fn linear(self) -> CellKind {
        match self {
            CellKind::Line3 => CellKind::Line2,
            CellKind::Tri6 => CellKind::Tri3,
            CellKind::Quad8 | CellKind::Quad9 => CellKind::Quad4,
            CellKind::Tet10 => CellKind::Tet4,
            CellKind::Hex20 | CellKind::Hex27 => CellKind::Hex8,
            CellKind::Wedge15 => CellKind::Wedge6,
            k => k,
        }
    }

    /// gmsh element type id.
    pub const fn gmsh_type(self) -> i32 {
        match self {
            CellKind::Point1 => 15,
            CellKind::Line2 => 1,
            CellKind::Line3 => 8,
            CellKind::Tri3 => 2,
            CellKind::Tri6 => 9,
            CellKind::Quad4 => 3,
            CellKind::Quad8 => 16,
            CellKind::Quad9 => 10,
            CellKind::Tet4 => 4,
            CellKind::Tet10 => 11,
            CellKind::Hex8 => 5,
            CellKind::Hex20 => 17,
            CellKind::Hex27 => 12,
            CellKind::Wedge6 => 6,
            CellKind::Wedge15 => 18,
        }
    }

    /// The kind for a gmsh element type id, if supported.
    pub fn from_gmsh_type(t: i32) -> Option<CellKind> {
        CellKind::ALL.iter().copied().find(|k| k.gmsh_type() == t)
    }

    /// Short lower-case name (`tet10`, `hex20`, ...), as used on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            CellKind::Point1 => "point1",
            CellKind::Line2 => "line2",
            CellKind::Line3 => "line3",
            CellKind::Tri3 => "tri3",
            CellKind::Tri6 => "tri6",
            CellKind::Quad4 => "quad4",
            CellKind::Quad8 => "quad8",
            CellKind::Quad9 => "quad9",
            CellKind::Tet4 => "tet4",
            CellKind::Tet10 => "tet10",
            CellKind::Hex8 => "hex8",
            CellKind::Hex20 => "hex20",
            CellKind::Hex27 => "hex27",
            CellKind::Wedge6 => "wedge6",
            CellKind::Wedge15 => "wedge15",
        }
    }
}

impl std::fmt::Display for CellKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// gmsh's name of an element type id, for error messages about types vibrofem does not support.
pub fn gmsh_type_name(t: i32) -> &'static str {
    match t {
        1 => "2-node line",
        2 => "3-node triangle",
        3 => "4-node quadrangle",
        4 => "4-node tetrahedron",
        5 => "8-node hexahedron",
        6 => "6-node prism",
        7 => "5-node pyramid",
        8 => "3-node line",
        9 => "6-node triangle",
        10 => "9-node quadrangle",
        11 => "10-node tetrahedron",
        12 => "27-node hexahedron",
        13 => "18-node prism",
        14 => "14-node pyramid",
        15 => "1-node point",
        16 => "8-node quadrangle",
        17 => "20-node hexahedron",
        18 => "15-node prism",
        19 => "13-node pyramid",
        _ => "unknown type",
    }
}
