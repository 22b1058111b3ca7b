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
        let mass: f64 = (0..dofs.n_free).map(|i| mr0[(i, d)]).sum();
        let mom: f64 = (0..dofs.n_free).map(|i| mr0[(i, d)] * xd[i]).sum();
        c[d] = if mass > 0.0 { mom / mass } else { 0.0 };
    }
    let r = rigid_vectors(dofs, nodes, c);
    let mut mr = Mat::zeros(dofs.n_free, 6);
    m.mul_block(r.as_ref(), mr.as_mut());
    let mut total = [0.0; 6];
    for d in 0..6 {
        total[d] = (0..dofs.n_free).map(|i| r[(i, d)] * mr[(i, d)]).sum();
    }
    // Gram matrix of the rigid-body vectors, G = RᵀMR, and its pseudo-inverse (a model may not
    // carry all six motions, e.g. fixed DOFs remove parts of them).
    let mut g = nalgebra::DMatrix::zeros(6, 6);
    for i in 0..6 {
        for j in 0..6 {
            g[(i, j)] = (0..dofs.n_free).map(|k| r[(k, i)] * mr[(k, j)]).sum::<f64>();
        }
    }
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
    let mut rigid = Vec::with_capacity(phi.ncols());
    let mut modes = Vec::with_capacity(phi.ncols());
    let mut cumulative_ratio = Vec::with_capacity(phi.ncols());
    let mut acc = [0.0; 6];
    for k in 0..phi.ncols() {
        let mut factor = [0.0; 6];
        let mut effective = [0.0; 6];
        for d in 0..6 {
            let g: f64 = (0..dofs.n_free).map(|i| phi[(i, k)] * mr[(i, d)]).sum();
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
        let inside = (gv.transpose() * &ginv * &gv)[(0, 0)];
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
