//! Degrees of freedom: which components each node carries, which are fixed, and the
//! equation numbering of the free ones.
//!
//! Every node has up to seven components, `ux, uy, uz, rx, ry, rz, w` (component index 0..7):
//! translations, rotations, and the warping amplitude of thin-walled beams. Solids activate
//! the three translations; shells and beams the six; warping beams the seventh too. Free components are
//! numbered node-major in node order, so the free DOFs of one node are consecutive and the
//! numbering is monotone in the node index. Fixed components get no equation
//! (homogeneous Dirichlet conditions are eliminated).

/// Components per node.
pub const NCOMP: usize = 7;

/// Component names, in component order.
pub const COMPONENT_NAMES: [&str; NCOMP] = ["ux", "uy", "uz", "rx", "ry", "rz", "w"];

/// Bit mask of active or fixed components of a node (bit `c` = component `c`).
pub type DofMask = u8;

/// The three translations.
pub const TRANSLATIONS: DofMask = 0b000111;
/// All six translations and rotations.
pub const ALL6: DofMask = 0b111111;
/// The warping component.
pub const WARPING: DofMask = 0b1000000;

/// Parse a component list like `ux,uy` or `all` into a mask.
pub fn parse_components(s: &str) -> Option<DofMask> {
    let mut m = 0u8;
    for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        match part {
            "all" => m |= ALL6,
            "u" | "xyz" => m |= TRANSLATIONS,
            "r" => m |= ALL6 & !TRANSLATIONS,
            _ => m |= 1 << COMPONENT_NAMES.iter().position(|n| *n == part)?,
        }
    }
    (m != 0).then_some(m)
}

/// Equation numbering of a model's free DOFs.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Active components per node.
    pub active: Vec<DofMask>,
    /// Fixed components per node (subset of `active`).
    pub fixed: Vec<DofMask>,
    /// `eq[NCOMP*node + c]`: equation number of component `c` of `node`, or −1 if the component is
    /// inactive or fixed.
    pub eq: Vec<i64>,
    /// First equation of each node (`n_free` for nodes with no free DOF), length `n_nodes + 1`
    /// with the total at the end: the free DOFs of node `a` are `first[a]..first[a+1]`.
    pub first: Vec<usize>,
    /// Number of free DOFs (equations).
    pub n_free: usize,
}

impl DofMap {
    /// Number the free components, node-major.
    pub fn new(active: Vec<DofMask>, fixed: Vec<DofMask>) -> Self {
        assert_eq!(active.len(), fixed.len());
        let n = active.len();
        let mut eq = vec![-1i64; NCOMP * n];
        let mut first = Vec::with_capacity(n + 1);
        let mut next = 0usize;
        for a in 0..n {
            first.push(next);
            let free = active[a] & !fixed[a];
            for c in 0..NCOMP {
                if free & (1 << c) != 0 {
                    eq[NCOMP * a + c] = next as i64;
                    next += 1;
                }
            }
        }
        first.push(next);
        DofMap {
            active,
            fixed,
            eq,
            first,
            n_free: next,
        }
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.active.len()
    }

    /// Equation of component `c` of `node`, if free.
    pub fn eq_of(&self, node: usize, c: usize) -> Option<usize> {
        let e = self.eq[NCOMP * node + c];
        (e >= 0).then_some(e as usize)
    }

    /// The node and component of equation `eq` (for messages).
    pub fn node_comp_of(&self, eq: usize) -> (usize, usize) {
        // `first` is monotone: binary search the node whose range holds `eq`.
        let a = self.first.partition_point(|&f| f <= eq) - 1;
        let k = eq - self.first[a];
        let free = self.active[a] & !self.fixed[a];
        let c = (0..NCOMP).filter(|c| free & (1 << c) != 0).nth(k).unwrap_or(0);
        (a, c)
    }

    /// Expand a vector over free DOFs into a node-major array of `ncomp` components per node
    /// (components `0..ncomp`), with zeros for fixed or inactive components.
    pub fn expand(&self, x: &[f64], ncomp: usize) -> Vec<f64> {
        let n = self.n_nodes();
        let mut out = vec![0.0; n * ncomp];
        for a in 0..n {
            for c in 0..ncomp {
                if let Some(e) = self.eq_of(a, c) {
                    out[a * ncomp + c] = x[e];
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbering_is_node_major_and_skips_fixed() {
        let active = vec![TRANSLATIONS, TRANSLATIONS, ALL6];
        let fixed = vec![0, 0b010, 0b100000];
        let d = DofMap::new(active, fixed);
        assert_eq!(d.n_free, 3 + 2 + 5);
        assert_eq!(d.eq_of(1, 1), None);
        assert_eq!(d.eq_of(1, 2), Some(4));
        assert_eq!(d.first, vec![0, 3, 5, 10]);
        assert_eq!(d.node_comp_of(4), (1, 2));
        assert_eq!(d.node_comp_of(9), (2, 4));
        assert_eq!(parse_components("ux,uz"), Some(0b101));
        assert_eq!(parse_components("all"), Some(ALL6));
        assert_eq!(parse_components("foo"), None);
    }
}
