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

/// Linear constraints on the raw DOFs (index `NCOMP·node + component`).
///
/// Every active component is either free, fixed (u = value, 0 by default) or a slave of a
/// multi-point constraint u_s = Σ c_k·u_mk over master components, which must themselves be
/// free or fixed (not slaves). Rigid couplings, guided ends and general MPCs are all written
/// this way; the reduced unknowns û are the free components, and u = T û + g.
#[derive(Clone, Debug, Default)]
pub struct Constraints {
    /// Fixed components per node.
    pub fixed: Vec<DofMask>,
    /// Prescribed values of fixed raw DOFs (absent: 0).
    pub value: std::collections::BTreeMap<usize, f64>,
    /// Slave raw DOF → its masters `(raw DOF, coefficient)`.
    pub mpc: std::collections::BTreeMap<usize, Vec<(usize, f64)>>,
}

impl Constraints {
    /// No constraint on `n` nodes.
    pub fn new(n: usize) -> Self {
        Constraints {
            fixed: vec![0; n],
            ..Default::default()
        }
    }
}

/// Equation numbering of a model's free DOFs, with the constraint transformation.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Active components per node.
    pub active: Vec<DofMask>,
    /// Fixed components per node (subset of `active`).
    pub fixed: Vec<DofMask>,
    /// Slave components per node (subset of `active`, disjoint from `fixed`).
    pub slave: Vec<DofMask>,
    /// `eq[NCOMP*node + c]`: equation number of component `c` of `node`, or −1 if the component is
    /// inactive, fixed or a slave.
    pub eq: Vec<i64>,
    /// First equation of each node (`n_free` for nodes with no free DOF), length `n_nodes + 1`
    /// with the total at the end: the free DOFs of node `a` are `first[a]..first[a+1]`.
    pub first: Vec<usize>,
    /// Number of free DOFs (equations).
    pub n_free: usize,
    /// Prescribed values of fixed raw DOFs.
    pub value: std::collections::BTreeMap<usize, f64>,
    /// Slave raw DOF → masters.
    pub mpc: std::collections::BTreeMap<usize, Vec<(usize, f64)>>,
    /// Per node: the other nodes its DOFs depend on through constraints (empty for most).
    pub deps: Vec<Vec<u32>>,
    /// Per node: true if some component is a slave or has a non-zero prescribed value, so
    /// assembly must go through the general (transformed) path.
    pub special: Vec<bool>,
}

/// How a raw DOF depends on the unknowns: `u = Σ c·û_eq + constant`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Expansion {
    /// `(equation, coefficient)` terms.
    pub terms: Vec<(usize, f64)>,
    /// Constant part (prescribed values).
    pub constant: f64,
}

/// Components `first..first + 3` of every one of the first `n_nodes` nodes of a full vector
/// (`NCOMP` per node, as [`DofMap::full`] gives): the translations (`first` 0) or the
/// rotations (`first` 3), node-major, for the result files.
pub fn node_triplets(full: &[f64], n_nodes: usize, first: usize) -> Vec<f64> {
    let mut out = vec![0.0; 3 * n_nodes];
    for a in 0..n_nodes {
        out[3 * a..3 * a + 3].copy_from_slice(&full[NCOMP * a + first..NCOMP * a + first + 3]);
    }
    out
}

impl DofMap {
    /// Number the free components, node-major (fixed components only).
    pub fn new(active: Vec<DofMask>, fixed: Vec<DofMask>) -> Self {
        let n = active.len();
        let c = Constraints {
            fixed,
            ..Constraints::new(n)
        };
        Self::with_constraints(active, c).expect("fixed-only constraints are always consistent")
    }

    /// Number the free components under general constraints. Errors if a master is itself a
    /// slave or inactive, or a slave is also fixed.
    pub fn with_constraints(active: Vec<DofMask>, c: Constraints) -> crate::Result<Self> {
        let n = active.len();
        assert_eq!(c.fixed.len(), n);
        let mut slave = vec![0 as DofMask; n];
        for &s in c.mpc.keys() {
            let (a, comp) = (s / NCOMP, s % NCOMP);
            if a >= n || active[a] & (1 << comp) == 0 {
                return Err(crate::Error::param(
                    "constraints",
                    format!(
                        "constraint on node {a} component {} which no element uses",
                        COMPONENT_NAMES[comp]
                    ),
                ));
            }
            if c.fixed[a] & (1 << comp) != 0 {
                return Err(crate::Error::param(
                    "constraints",
                    format!(
                        "conflicting constraints: node {a} component {} is both fixed and coupled",
                        COMPONENT_NAMES[comp]
                    ),
                ));
            }
            slave[a] |= 1 << comp;
        }
        for (&s, masters) in &c.mpc {
            for &(m, _) in masters {
                let (b, comp) = (m / NCOMP, m % NCOMP);
                if b >= n || active[b] & (1 << comp) == 0 || slave[b] & (1 << comp) != 0 {
                    return Err(crate::Error::param(
                        "constraints",
                        format!(
                            "conflicting constraints: node {} is coupled to node {b} component {}, which is itself \
                         constrained or unused",
                            s / NCOMP,
                            COMPONENT_NAMES[comp]
                        ),
                    ));
                }
            }
        }
        let mut eq = vec![-1i64; NCOMP * n];
        let mut first = Vec::with_capacity(n + 1);
        let mut next = 0usize;
        for a in 0..n {
            first.push(next);
            let free = active[a] & !c.fixed[a] & !slave[a];
            for comp in 0..NCOMP {
                if free & (1 << comp) != 0 {
                    eq[NCOMP * a + comp] = next as i64;
                    next += 1;
                }
            }
        }
        first.push(next);
        let mut deps = vec![Vec::new(); n];
        let mut special = vec![false; n];
        for (&s, masters) in &c.mpc {
            let a = s / NCOMP;
            special[a] = true;
            for &(m, _) in masters {
                let b = (m / NCOMP) as u32;
                if b as usize != a && !deps[a].contains(&b) {
                    deps[a].push(b);
                }
            }
        }
        for (&r, &v) in &c.value {
            if v != 0.0 {
                special[r / NCOMP] = true;
            }
        }
        // A slave whose master has a prescribed value also carries a constant.
        for (&s, masters) in &c.mpc {
            if masters.iter().any(|(m, _)| c.value.get(m).is_some_and(|v| *v != 0.0)) {
                special[s / NCOMP] = true;
            }
        }
        for d in &mut deps {
            d.sort_unstable();
        }
        Ok(DofMap {
            active,
            fixed: c.fixed,
            slave,
            eq,
            first,
            n_free: next,
            value: c.value,
            mpc: c.mpc,
            deps,
            special,
        })
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

    /// Prescribed value of a fixed raw DOF (0 if none was given).
    pub fn value_of(&self, raw: usize) -> f64 {
        self.value.get(&raw).copied().unwrap_or(0.0)
    }

    /// How raw DOF `raw` depends on the unknowns.
    pub fn expansion(&self, raw: usize) -> Expansion {
        let (a, c) = (raw / NCOMP, raw % NCOMP);
        if let Some(e) = self.eq_of(a, c) {
            return Expansion {
                terms: vec![(e, 1.0)],
                constant: 0.0,
            };
        }
        if let Some(masters) = self.mpc.get(&raw) {
            let mut x = Expansion::default();
            for &(m, coef) in masters {
                match self.eq_of(m / NCOMP, m % NCOMP) {
                    Some(e) => x.terms.push((e, coef)),
                    None => x.constant += coef * self.value_of(m),
                }
            }
            return x;
        }
        Expansion {
            terms: vec![],
            constant: if self.fixed[a] & (1 << c) != 0 {
                self.value_of(raw)
            } else {
                0.0
            },
        }
    }

    /// The expansions of an element's local DOFs (`ndpn` per node of `nodes`, node-major);
    /// components the model does not use expand to nothing.
    pub fn local_expansions(&self, nodes: &[u32], ndpn: usize) -> Vec<Expansion> {
        nodes
            .iter()
            .flat_map(|&a| (0..ndpn).map(move |c| (a as usize, c)))
            .map(|(a, c)| {
                if self.active[a] & (1 << c) != 0 {
                    self.expansion(NCOMP * a + c)
                } else {
                    Default::default()
                }
            })
            .collect()
    }

    /// The node and component of equation `eq` (for messages).
    pub fn node_comp_of(&self, eq: usize) -> (usize, usize) {
        // `first` is monotone: binary search the node whose range holds `eq`.
        let a = self.first.partition_point(|&f| f <= eq) - 1;
        let k = eq - self.first[a];
        let free = self.active[a] & !self.fixed[a] & !self.slave[a];
        let c = (0..NCOMP).filter(|c| free & (1 << c) != 0).nth(k).unwrap_or(0);
        (a, c)
    }

    /// The full raw solution u = T û + g (NCOMP components per node; inactive ones 0).
    pub fn full(&self, x: &[f64]) -> Vec<f64> {
        let n = self.n_nodes();
        let mut u = vec![0.0; NCOMP * n];
        for a in 0..n {
            for c in 0..NCOMP {
                if self.active[a] & (1 << c) == 0 {
                    continue;
                }
                let r = NCOMP * a + c;
                u[r] = match self.eq_of(a, c) {
                    Some(e) => x[e],
                    None => {
                        let ex = self.expansion(r);
                        ex.constant + ex.terms.iter().map(|&(e, k)| k * x[e]).sum::<f64>()
                    }
                };
            }
        }
        u
    }

    /// Expand a vector over free DOFs into a node-major array of `ncomp` components per node
    /// (components `0..ncomp`) through the constraints, for the first `n_nodes` nodes.
    pub fn expand_nodes(&self, x: &[f64], ncomp: usize, n_nodes: usize) -> Vec<f64> {
        let u = self.full(x);
        let mut out = vec![0.0; n_nodes * ncomp];
        for a in 0..n_nodes.min(self.n_nodes()) {
            for c in 0..ncomp {
                out[a * ncomp + c] = u[NCOMP * a + c];
            }
        }
        out
    }

    /// Expand a vector over free DOFs into a node-major array of `ncomp` components per node.
    /// Homogeneous: prescribed values are not added (for mode shapes).
    pub fn expand(&self, x: &[f64], ncomp: usize) -> Vec<f64> {
        let n = self.n_nodes();
        let mut out = vec![0.0; n * ncomp];
        for a in 0..n {
            for c in 0..ncomp {
                let r = NCOMP * a + c;
                out[a * ncomp + c] = match self.eq_of(a, c) {
                    Some(e) => x[e],
                    None => self.mpc.get(&r).map_or(0.0, |ms| {
                        ms.iter()
                            .filter_map(|&(m, k)| self.eq_of(m / NCOMP, m % NCOMP).map(|e| k * x[e]))
                            .sum()
                    }),
                };
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
