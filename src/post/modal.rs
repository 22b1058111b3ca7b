//! Modal post-processing: frequencies, rigid-body classification, participation factors and
//! effective modal masses.
//!
//! Mode shapes are M-normalised (φᵀMφ = 1, units m·kg^-½). For a rigid-body direction vector
//! r (unit translation along X, Y or Z, or a unit rotation about an axis through the centre
//! of mass), the participation factor is Γ = φᵀ M r and the effective mass Γ²; summed over
//! all modes the effective masses reach rᵀMr: the total mass for translations and the moment
//! of inertia about the axis for rotations. Only free DOFs count (mass on fixed nodes does not
//! move).

use crate::dof::DofMap;
use crate::linalg::sparse::SymMatrix;
use faer::{Mat, MatRef};
use rayon::prelude::*;
use serde::Serialize;

/// Frequency in Hz of an eigenvalue λ = ω² (negative λ, from rounding, gives a negative f).
pub fn hz(lambda: f64) -> f64 {
    lambda.signum() * lambda.abs().sqrt() / (2.0 * std::f64::consts::PI)
}

/// Eigenvalue λ = (2πf)² of a frequency (negative f gives negative λ).
pub fn lambda_of_hz(f: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    w.signum() * w * w
}

/// Number of rigid-body modes among ascending eigenvalues: those with |f| below 1e-3 of the
/// largest computed frequency and below 1e-2 Hz·(scale-free: 1e-4 of the first mode above
/// them). Rigid-body eigenvalues come out at rounding level, ~1e-8 of the first elastic one.
pub fn count_rigid(lambda: &[f64]) -> usize {
    let fmax = lambda.iter().map(|&l| hz(l).abs()).fold(0.0, f64::max);
    lambda.iter().take_while(|&&l| hz(l).abs() < 1e-3 * fmax).count().min(6)
}

/// Participation of one mode.
#[derive(Clone, Debug, Serialize)]
pub struct Participation {
    /// Participation factors Γ for X, Y, Z, RX, RY, RZ.
    pub factor: [f64; 6],
    /// Effective masses Γ² (kg for X/Y/Z, kg·m² for rotations).
    pub effective: [f64; 6],
}

/// Participation of all modes and the reference totals.
#[derive(Clone, Debug, Serialize)]
pub struct ParticipationTable {
    /// Per mode.
    pub modes: Vec<Participation>,
    /// rᵀMr per direction: total free mass (X, Y, Z) and moments of inertia about the centre
    /// of mass (RX, RY, RZ).
    pub total: [f64; 6],
    /// Cumulative effective mass ratio per direction after each mode.
    pub cumulative_ratio: Vec<[f64; 6]>,
    /// Centre of mass of the free mass (m).
    pub centre_of_mass: [f64; 3],
    /// Per mode: the shape is a rigid-body motion (lies in the span of the six rigid-body
    /// vectors to 1e-8 of its M-norm²).
    pub rigid: Vec<bool>,
}

/// Rigid-body direction vectors over the free DOFs (columns X, Y, Z, RX, RY, RZ) about `c`.
pub fn rigid_vectors(dofs: &DofMap, nodes: &[[f64; 3]], c: [f64; 3]) -> Mat<f64> {
    let mut r = Mat::zeros(dofs.n_free, 6);
    for (a, x) in nodes.iter().enumerate() {
        let d = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
        // Rotation θ about axis e: u = e × d, and the rotational DOFs rotate by e.
        let rot = [[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]];
        for comp in 0..3 {
            if let Some(e) = dofs.eq_of(a, comp) {
                r[(e, comp)] = 1.0;
                for ax in 0..3 {
                    r[(e, 3 + ax)] = rot[ax][comp];
                }
            }
            if let Some(e) = dofs.eq_of(a, 3 + comp) {
                r[(e, 3 + comp)] = 1.0;
            }
        }
    }
    r
}

/// Participation factors and effective masses of M-normalised modes `phi`.
pub fn participation(m: &SymMatrix, dofs: &DofMap, nodes: &[[f64; 3]], phi: MatRef<'_, f64>) -> ParticipationTable {
    participation_of(&ParticipationBasis::new(m, dofs, nodes), phi)
}

/// What the participation factors need of the model alone: the rigid-body vectors about the
/// centre of mass, their M-images, their Gram matrix's pseudo-inverse and its diagonal.
pub struct ParticipationBasis {
    c: [f64; 3],
    mr: Mat<f64>,
    total: [f64; 6],
    ginv: nalgebra::DMatrix<f64>,
    emax: f64,
}

impl ParticipationBasis {
    /// The basis of `m` on the free DOFs of `dofs` at `nodes`.
    pub fn new(m: &SymMatrix, dofs: &DofMap, nodes: &[[f64; 3]]) -> Self {
        // Centre of mass from the translational vectors: c_d = (r_dᵀ M x_d) / (r_dᵀ M r_d).
        let r0 = rigid_vectors(dofs, nodes, [0.0; 3]);
        let mut mr0 = Mat::zeros(dofs.n_free, 6);
        m.mul_block(r0.as_ref(), mr0.as_mut());
        let mut c = [0.0; 3];
        for d in 0..3 {
            let mut xd = vec![0.0; dofs.n_free];
            for (a, x) in nodes.iter().enumerate() {
                if let Some(e) = dofs.eq_of(a, d) {
                    xd[e] = x[d];
                }
            }
            let mass: f64 = col(mr0.as_ref(), d).iter().sum();
            let mom = dot(col(mr0.as_ref(), d), &xd);
            c[d] = if mass > 0.0 { mom / mass } else { 0.0 };
        }
        let r = rigid_vectors(dofs, nodes, c);
        let mut mr = Mat::zeros(dofs.n_free, 6);
        m.mul_block(r.as_ref(), mr.as_mut());
        // Gram matrix of the rigid-body vectors, G = RᵀMR (its diagonal: the totals), and its
        // pseudo-inverse (a model may not carry all six motions, e.g. fixed DOFs remove parts
        // of them).
        let mut g = nalgebra::DMatrix::zeros(6, 6);
        for i in 0..6 {
            for j in 0..6 {
                g[(i, j)] = dot(col(r.as_ref(), i), col(mr.as_ref(), j));
            }
        }
        let total: [f64; 6] = std::array::from_fn(|d| g[(d, d)]);
        let g = (&g + g.transpose()) * 0.5;
        let eig = g.clone().symmetric_eigen();
        let emax = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
        let mut ginv = nalgebra::DMatrix::zeros(6, 6);
        for k in 0..6 {
            let e = eig.eigenvalues[k];
            if e > 1e-12 * emax {
                let v = eig.eigenvectors.column(k);
                ginv += v * v.transpose() / e;
            }
        }
        ParticipationBasis {
            c,
            mr,
            total,
            ginv,
            emax,
        }
    }
}

/// [`participation`] with the model's part formed beforehand.
pub fn participation_of(b: &ParticipationBasis, phi: MatRef<'_, f64>) -> ParticipationTable {
    let ParticipationBasis {
        c,
        mr,
        total,
        ginv,
        emax,
    } = b;
    let (c, total, emax) = (*c, *total, *emax);
    let mut rigid = Vec::with_capacity(phi.ncols());
    let mut modes = Vec::with_capacity(phi.ncols());
    let mut cumulative_ratio = Vec::with_capacity(phi.ncols());
    let mut acc = [0.0; 6];
    // Γ_kd = φ_kᵀ M r_d, each a dot product in row order (modes in parallel).
    let gammas: Vec<[f64; 6]> = (0..phi.ncols())
        .into_par_iter()
        .map(|k| std::array::from_fn(|d| dot(col(phi, k), col(mr.as_ref(), d))))
        .collect();
    for gk in &gammas {
        let mut factor = [0.0; 6];
        let mut effective = [0.0; 6];
        for d in 0..6 {
            let g = gk[d];
            factor[d] = g;
            effective[d] = g * g;
            acc[d] += g * g;
        }
        let mut ratio = [0.0; 6];
        for d in 0..6 {
            ratio[d] = if total[d] > 0.0 { acc[d] / total[d] } else { 0.0 };
        }
        // M-norm² of the part of φ in span(R): Γᵀ G⁺ Γ (φ is M-normalised).
        let gv = nalgebra::DVector::from_column_slice(&factor);
        let inside = (gv.transpose() * ginv * &gv)[(0, 0)];
        rigid.push(emax > 0.0 && 1.0 - inside < 1e-8);
        modes.push(Participation { factor, effective });
        cumulative_ratio.push(ratio);
    }
    ParticipationTable {
        modes,
        total,
        cumulative_ratio,
        centre_of_mass: c,
        rigid,
    }
}

/// A connected part of a model (free equations linked through the stiffness: elements,
/// couplings, springs) that can move as a rigid body in some directions.
#[derive(Clone, Debug, Serialize)]
pub struct FreePart {
    /// Number of nodes with free DOFs in the part.
    pub nodes: usize,
    /// Index of one of its nodes (for messages).
    pub first_node: usize,
    /// Its nodes (model indices).
    #[serde(skip)]
    pub node_list: Vec<usize>,
    /// Free rigid motions among `ux, uy, uz, rx, ry, rz` (about the part's centroid) — the
    /// basic motions that are free on their own; `count` may be larger where only
    /// combinations are free.
    pub motions: Vec<&'static str>,
    /// Dimension of the part's free rigid-motion space.
    pub count: usize,
}

/// The parts of a model and their free rigid motions.
#[derive(Clone, Debug)]
pub struct RigidAnalysis {
    /// Number of connected parts (of free equations).
    pub n_parts: usize,
    /// The parts that have free rigid motions.
    pub free: Vec<FreePart>,
    /// Per mode of `phi`: the shape lies in the span of the free rigid motions of all parts (to
    /// 1e-8 of its M-norm²).
    pub rigid: Vec<bool>,
}

/// Connected parts of the model (union of equations coupled by `k`, and of the equations of one
/// node), the free rigid motions of each, and which modes are rigid-body modes.
///
/// For each part the six rigid-body vectors (rotations about the part's centroid, scaled by its
/// size so the test is independent of units) restricted to its equations give 6 × 6 matrices
/// `G_K = RᵀKR`, `G_M = RᵀMR`; the free motions are the generalised eigenvectors with Rayleigh
/// quotient below 1e-13 of `max_i K_ii / M_ii`. A free motion's quotient is rounding: measured
/// ≤ 4e-17 of that scale on a 1 m × 1 m × 1 mm hex20 sheet, a 4 m × 20 mm hex20 bar and tet10
/// boxes of 0.1 mm and 10 km; a body on springs has the quotient of its suspension frequency²
/// (a 1.6 Hz suspension of a 0.1 m hex20 cube: 4e-10), so suspension modes down to ~3e-7 of
/// the mesh's highest frequency scale are elastic, not rigid. A free motion must also have a
/// strain energy at rounding level against its stiffness scale ([`FREE_STIFFNESS`]), so that a
/// point mass that outweighs the structure cannot make a supported motion look free. The test is
/// scale-free: lengths, masses and stiffnesses of any magnitude give the same labels. A mode is
/// rigid when it lies in the span of all parts' free motions in the M-norm, so a loose part of
/// a supported model gets its rigid modes labelled rigid.
pub fn rigid_analysis(
    k: &SymMatrix,
    m: &SymMatrix,
    dofs: &DofMap,
    nodes: &[[f64; 3]],
    phi: MatRef<'_, f64>,
) -> RigidAnalysis {
    rigid_analysis_of(m, &RigidParts::new(k, m, dofs, nodes), phi)
}

/// What [`rigid_analysis`] needs of the model alone: its connected parts, their free rigid
/// motions and the parts' rigid-body vectors' M-images.
pub struct RigidParts {
    comp: Vec<usize>,
    nc: usize,
    basis: Vec<(usize, nalgebra::Vector6<f64>)>,
    /// The parts that have free rigid motions.
    pub free: Vec<FreePart>,
    mr: Mat<f64>,
}

/// [`rigid_analysis`] with the model's part formed beforehand.
pub fn rigid_analysis_of(m: &SymMatrix, p: &RigidParts, phi: MatRef<'_, f64>) -> RigidAnalysis {
    let rigid = if p.basis.is_empty() {
        vec![false; phi.ncols()]
    } else {
        modes_in_span(m, phi, &p.basis, &p.comp, p.nc, &p.mr)
    };
    RigidAnalysis {
        n_parts: p.nc,
        free: p.free.clone(),
        rigid,
    }
}

impl RigidParts {
    /// The parts of the model of `k`, `m` on the free DOFs of `dofs` at `nodes`.
    pub fn new(k: &SymMatrix, m: &SymMatrix, dofs: &DofMap, nodes: &[[f64; 3]]) -> Self {
        let (comp, nc) = connected_parts(k, dofs, nodes.len());
        let parts = PartShapes::of(&comp, nc, dofs, nodes);
        // Rigid vectors, each row about its part's centroid, rotations scaled by 1/size.
        let r = part_rigid_vectors(&comp, &parts, dofs, nodes);
        let (mut kr, mut mr) = (Mat::<f64>::zeros(dofs.n_free, 6), Mat::<f64>::zeros(dofs.n_free, 6));
        k.mul_block(r.as_ref(), kr.as_mut());
        m.mul_block(r.as_ref(), mr.as_mut());
        let (kd, md) = (k.diagonal(), m.diagonal());
        let grams = part_grams(&comp, nc, &r, &kr, &mr, &kd);
        let scale = kd
            .iter()
            .zip(&md)
            .filter(|&(_, &mi)| mi > 0.0)
            .map(|(&ki, &mi)| ki / mi)
            .fold(0.0f64, f64::max);
        let tol = 1e-13 * scale;
        let (basis, free) = free_motions(&grams, tol, &comp, &parts, dofs, nodes.len());
        RigidParts {
            comp,
            nc,
            basis,
            free,
            mr,
        }
    }
}

/// The connected parts of the free equations (union of equations coupled by `k`, and of the
/// equations of one node among the first `n_nodes`): the part of each equation, numbered by
/// first equation, and the number of parts.
fn connected_parts(k: &SymMatrix, dofs: &DofMap, n_nodes: usize) -> (Vec<usize>, usize) {
    let mut parts = crate::linalg::graph::Parts::of_pattern(&k.pattern);
    for a in 0..n_nodes.min(dofs.n_nodes()) {
        let (lo, hi) = (dofs.first[a], dofs.first[a + 1]);
        for e in lo + 1..hi {
            parts.join(lo, e);
        }
    }
    parts.labels()
}

/// Per part: its number of nodes with free DOFs, its first node, its centroid and its size
/// (bounding-box diagonal, 1 when zero or not finite).
struct PartShapes {
    count: Vec<usize>,
    first_node: Vec<usize>,
    centre: Vec<[f64; 3]>,
    size: Vec<f64>,
}

impl PartShapes {
    fn of(comp: &[usize], nc: usize, dofs: &DofMap, nodes: &[[f64; 3]]) -> PartShapes {
        let mut sum = vec![[0.0; 3]; nc];
        let mut cnt = vec![0usize; nc];
        let mut lo = vec![[f64::INFINITY; 3]; nc];
        let mut hi = vec![[f64::NEG_INFINITY; 3]; nc];
        let mut first_node = vec![usize::MAX; nc];
        for a in 0..nodes.len().min(dofs.n_nodes()) {
            if dofs.first[a] == dofs.first[a + 1] {
                continue;
            }
            let c = comp[dofs.first[a]];
            cnt[c] += 1;
            first_node[c] = first_node[c].min(a);
            for d in 0..3 {
                sum[c][d] += nodes[a][d];
                lo[c][d] = lo[c][d].min(nodes[a][d]);
                hi[c][d] = hi[c][d].max(nodes[a][d]);
            }
        }
        let centre: Vec<[f64; 3]> = (0..nc).map(|c| sum[c].map(|s| s / cnt[c].max(1) as f64)).collect();
        let size: Vec<f64> = (0..nc)
            .map(|c| {
                let d: f64 = (0..3).map(|i| (hi[c][i] - lo[c][i]).powi(2)).sum::<f64>().sqrt();
                if d > 0.0 && d.is_finite() { d } else { 1.0 }
            })
            .collect();
        PartShapes {
            count: cnt,
            first_node,
            centre,
            size,
        }
    }
}

/// The six rigid-body vectors `R` (n_free × 6) of every part, about the part's centroid, the
/// rotations scaled by 1/size.
fn part_rigid_vectors(comp: &[usize], parts: &PartShapes, dofs: &DofMap, nodes: &[[f64; 3]]) -> Mat<f64> {
    let (centre, size) = (&parts.centre, &parts.size);
    let mut r = Mat::<f64>::zeros(dofs.n_free, 6);
    for (a, x) in nodes.iter().enumerate().take(dofs.n_nodes()) {
        for comp_i in 0..6 {
            let Some(e) = dofs.eq_of(a, comp_i) else { continue };
            let c = comp[e];
            let d = [x[0] - centre[c][0], x[1] - centre[c][1], x[2] - centre[c][2]].map(|v| v / size[c]);
            let rot = [[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]];
            if comp_i < 3 {
                r[(e, comp_i)] = 1.0;
                for ax in 0..3 {
                    r[(e, 3 + ax)] = rot[ax][comp_i];
                }
            } else {
                r[(e, comp_i)] = 1.0 / size[c];
            }
        }
    }
    r
}

/// The 6 × 6 matrices of each part: `G_K = RᵀKR`, `G_M = RᵀMR` and `G_D = RᵀDR` with
/// D = diag(K) (the stiffness scale of the same motions), from `KR`, `MR` and K's diagonal.
struct PartGrams {
    k: Vec<nalgebra::Matrix6<f64>>,
    m: Vec<nalgebra::Matrix6<f64>>,
    d: Vec<nalgebra::Matrix6<f64>>,
}

fn part_grams(comp: &[usize], nc: usize, r: &Mat<f64>, kr: &Mat<f64>, mr: &Mat<f64>, kd: &[f64]) -> PartGrams {
    let zero = vec![nalgebra::Matrix6::<f64>::zeros(); nc];
    let mut g = PartGrams {
        k: zero.clone(),
        m: zero.clone(),
        d: zero,
    };
    for (e, &c) in comp.iter().enumerate() {
        for i in 0..6 {
            if r[(e, i)] == 0.0 {
                continue;
            }
            for j in 0..6 {
                g.k[c][(i, j)] += r[(e, i)] * kr[(e, j)];
                g.m[c][(i, j)] += r[(e, i)] * mr[(e, j)];
                g.d[c][(i, j)] += r[(e, i)] * kd[e].abs() * r[(e, j)];
            }
        }
    }
    g
}

/// Strain energy of a free motion relative to its stiffness scale, `yᵀG_K y / yᵀG_D y`, at or
/// below which the motion is free: rounding. A motion held by supports or springs has the
/// share of its stiffness scale that the supports carry: 7e-3 for the translation and 5e-6 for
/// the rotation about the clamp of a 40-element hex20 cantilever, 1e-9 for a 0.1 m hex20 cube on
/// 1 kN/m springs. A free body's share is rounding: at most 8e-17 on tet10 boxes of 0.1 mm and
/// 10 km, a 1 m × 1 m × 1 mm hex20 sheet, a 4 m hex20 bar and the 119k-DOF tet10 plate. The
/// quotient test alone cannot tell them apart once a point mass outweighs the structure: the
/// cantilever's tip mass 6e7 times its own mass brings the clamped translation's quotient
/// below the tolerance.
const FREE_STIFFNESS: f64 = 1e-12;

/// The free motions of each part: the generalised eigenvectors of (`G_K`, `G_M`) with Rayleigh
/// quotient below `tol`, as (part, coefficient vector of R), M-orthonormal; and the parts that
/// have any, described.
fn free_motions(
    g: &PartGrams,
    tol: f64,
    comp: &[usize],
    parts: &PartShapes,
    dofs: &DofMap,
    n_nodes: usize,
) -> (Vec<(usize, nalgebra::Vector6<f64>)>, Vec<FreePart>) {
    const NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];
    // Free motions per part: coefficient vectors (6) of R.
    let mut basis: Vec<(usize, nalgebra::Vector6<f64>)> = Vec::new();
    let mut free = Vec::new();
    for c in 0..g.k.len() {
        let gms = (g.m[c] + g.m[c].transpose()) * 0.5;
        let gks = (g.k[c] + g.k[c].transpose()) * 0.5;
        let em = gms.symmetric_eigen();
        let emax = em.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
        if emax <= 0.0 {
            continue;
        }
        // W = V_k diag(1/√e): M-orthonormal coordinates of the motions that carry mass.
        let cols: Vec<nalgebra::Vector6<f64>> = (0..6)
            .filter(|&i| em.eigenvalues[i] > 1e-10 * emax)
            .map(|i| em.eigenvectors.column(i) / em.eigenvalues[i].sqrt())
            .collect();
        let w = nalgebra::DMatrix::from_fn(6, cols.len(), |i, j| cols[j][i]);
        let gk6 = nalgebra::DMatrix::from_fn(6, 6, |i, j| gks[(i, j)]);
        let a = w.transpose() * &gk6 * &w;
        let a = (&a + a.transpose()) * 0.5;
        let ea = a.symmetric_eigen();
        let mut count = 0;
        for (i, &mu) in ea.eigenvalues.iter().enumerate() {
            let y = &w * ea.eigenvectors.column(i);
            let y6 = nalgebra::Vector6::from_fn(|k, _| y[k]);
            let scale = (y6.transpose() * g.d[c] * y6)[(0, 0)];
            // |·|: a prestressed K + K_σ can give a supported motion negative energy (a preload
            // past buckling), which is not freedom.
            if mu.abs() <= tol && (y6.transpose() * gks * y6)[(0, 0)].abs() <= FREE_STIFFNESS * scale {
                basis.push((c, y6));
                count += 1;
            }
        }
        if count == 0 {
            continue;
        }
        let motions = (0..6)
            .filter(|&d| {
                gms[(d, d)] > 1e-10 * emax
                    && (gks[(d, d)] / gms[(d, d)]).abs() <= tol
                    && gks[(d, d)].abs() <= FREE_STIFFNESS * g.d[c][(d, d)]
            })
            .map(|d| NAMES[d])
            .collect();
        let node_list = (0..n_nodes.min(dofs.n_nodes()))
            .filter(|&a| dofs.first[a] < dofs.first[a + 1] && comp[dofs.first[a]] == c)
            .collect();
        free.push(FreePart {
            nodes: parts.count[c],
            first_node: parts.first_node[c],
            node_list,
            motions,
            count,
        });
    }
    (basis, free)
}

/// Per mode of `phi`: whether it lies in the span of the free motions `basis` (to 1e-8 of its
/// M-norm²). The motions f_j = R y_j of a part are M-orthonormal (yᵢᵀ G_M y_j = δᵢⱼ by
/// construction) and parts do not share equations, so the M-norm² of φ's component in their
/// span is Σ_j (f_jᵀ M φ)², with f_jᵀ M φ = y_jᵀ (Σ_{e in part} MR_e φ_e).
fn modes_in_span(
    m: &SymMatrix,
    phi: MatRef<'_, f64>,
    basis: &[(usize, nalgebra::Vector6<f64>)],
    comp: &[usize],
    nc: usize,
    mr: &Mat<f64>,
) -> Vec<bool> {
    let n = comp.len();
    let mut mphi = Mat::<f64>::zeros(n, phi.ncols());
    m.mul_block(phi, mphi.as_mut());
    let mr: [&[f64]; 6] = std::array::from_fn(|i| col(mr.as_ref(), i));
    (0..phi.ncols())
        .into_par_iter()
        .map(|k| {
            let phik = col(phi, k);
            let mut p = vec![nalgebra::Vector6::<f64>::zeros(); nc];
            for (e, &v) in phik.iter().enumerate() {
                if v != 0.0 {
                    let pc = &mut p[comp[e]];
                    for i in 0..6 {
                        pc[i] += v * mr[i][e];
                    }
                }
            }
            let inside: f64 = basis.iter().map(|(c, y)| p[*c].dot(y).powi(2)).sum();
            let norm = dot(phik, col(mphi.as_ref(), k));
            norm > 0.0 && 1.0 - inside / norm < 1e-8
        })
        .collect()
}

/// Column `j` of `a` as a slice (`a` column-major with contiguous columns, as every `Mat` and
/// the views of whole columns here are).
fn col(a: MatRef<'_, f64>, j: usize) -> &[f64] {
    a.col(j).try_as_col_major().expect("contiguous column").as_slice()
}

/// `Σ_i a_i·b_i`, in index order.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
