//! Steady-state harmonic response: u(t) = Re(û e^{iωt}) under F(t) = Re(F̂ e^{iωt}).
//!
//! Two methods on one assembled [`System`]:
//! - [`superpose`]: modal superposition over verified modes, with the static (residual)
//!   correction for the modes left out: û = Σ_j φ_j φ_jᵀF̂ / (λ_j − ω² + iωc_j) + R F̂, where
//!   R = (K − σM)⁻¹ − Σ_j φ_j φ_jᵀ / (λ_j − σ) is the residual flexibility at σ (σ = 0, or a small
//!   negative shift when the model has rigid-body modes). Cheap for many frequencies.
//! - [`direct`]: the complex system (K − ω²M + iωC) û = F̂, one sparse LU per frequency; the
//!   check on the other.
//!
//! Damping ([`Damping`]): a modal damping ratio ζ (c_j = 2ζω_j), or Rayleigh damping C = αM + βK
//! (c_j = α + βλ_j). A modal ratio has no damping matrix; [`direct`] takes it as structural
//! damping K(1 + 2iζ), equal to the modal form at each resonance (documented where it is used).
//!
//! Units: SI (N, m, s); ω in rad/s; phases in radians here (degrees in reports).

use crate::analysis::modal::ModalRun;
use crate::dof::NCOMP;
use crate::system::System;
use crate::{Error, Result};
use faer::c64;
use faer::linalg::solvers::SolveCore;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};

// The loads are plain data of the model layer (read by `crate::input` too), re-exported here.
pub use crate::model::GroupForce;

/// How the structure dissipates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Damping {
    /// Modal damping ratio ζ, the same for every mode.
    Ratio(f64),
    /// Rayleigh damping C = αM + βK (α in 1/s, β in s).
    Rayleigh {
        /// Mass-proportional coefficient α (1/s).
        alpha: f64,
        /// Stiffness-proportional coefficient β (s).
        beta: f64,
    },
}

impl Damping {
    /// Refuse values that make no physical sense (negative, non-finite).
    pub fn validate(&self) -> Result<()> {
        match *self {
            Damping::Ratio(z) if !(z.is_finite() && z >= 0.0) => Err(Error::option(
                "--damping",
                format!("--damping: the damping ratio must be a finite number ≥ 0, got {z}"),
            )),
            Damping::Rayleigh { alpha, beta }
                if !(alpha.is_finite() && beta.is_finite() && alpha >= 0.0 && beta >= 0.0) =>
            {
                Err(Error::option(
                    "--rayleigh",
                    format!("--rayleigh: α and β must be finite numbers ≥ 0, got {alpha}, {beta}"),
                ))
            }
            _ => Ok(()),
        }
    }

    /// Modal damping coefficient c_j = 2ζ_jω_j of a mode with eigenvalue λ = ω_j².
    pub fn modal(&self, lambda: f64) -> f64 {
        match *self {
            Damping::Ratio(z) => 2.0 * z * lambda.max(0.0).sqrt(),
            Damping::Rayleigh { alpha, beta } => alpha + beta * lambda,
        }
    }

    /// The damping ratio this gives a mode of eigenvalue λ.
    pub fn ratio(&self, lambda: f64) -> f64 {
        let w = lambda.max(0.0).sqrt();
        if w > 0.0 { self.modal(lambda) / (2.0 * w) } else { 0.0 }
    }
}

/// Load vector on the free DOFs from nodal forces and moments: `(node, [Fx, Fy, Fz, Mx, My, Mz])`
/// complex amplitudes (N, N·m). Forces on a coupled (slave) DOF go to its masters (Tᵀ); a force
/// on a fixed DOF is refused (it would go into the support unused).
pub fn load_vector(sys: &System, forces: &[(usize, [c64; 6])]) -> Result<Vec<c64>> {
    let dofs = sys.dofs();
    let mut f = vec![c64::new(0.0, 0.0); dofs.n_free];
    // Where a bad load is: the node's component (by its mesh tag), else the argument.
    let at = |a: usize, c: usize, msg: String| match sys.model().node_tags.get(a) {
        Some(&tag) => Error::dof(tag, crate::dof::COMPONENT_NAMES[c], msg),
        None => Error::param("forces", msg),
    };
    for &(a, fa) in forces {
        if a >= dofs.n_nodes() {
            return Err(Error::param(
                "forces",
                format!("harmonic load on node {a}: the model has {} nodes", dofs.n_nodes()),
            ));
        }
        for (c, &v) in fa.iter().enumerate() {
            if v == c64::new(0.0, 0.0) {
                continue;
            }
            if !(v.re.is_finite() && v.im.is_finite()) {
                return Err(at(a, c, format!("harmonic load on node {a} is not finite")));
            }
            if dofs.active[a] & (1 << c) == 0 {
                return Err(at(
                    a,
                    c,
                    format!(
                        "harmonic load on node {a} component {}: no element uses that degree of freedom",
                        crate::dof::COMPONENT_NAMES[c]
                    ),
                ));
            }
            let ex = dofs.expansion(NCOMP * a + c);
            if ex.terms.is_empty() {
                return Err(at(
                    a,
                    c,
                    format!(
                        "harmonic load on node {a} component {}: the degree of freedom is held, the load would go \
                     into the support",
                        crate::dof::COMPONENT_NAMES[c]
                    ),
                ));
            }
            for (e, k) in ex.terms {
                f[e] += v * k;
            }
        }
    }
    Ok(f)
}

/// Free-DOF load vector of a raw (NCOMP per node) real load times a complex factor: Tᵀ f.
pub fn reduce_raw(sys: &System, f_raw: &[f64], factor: c64) -> Vec<c64> {
    let dofs = sys.dofs();
    let mut f = vec![c64::new(0.0, 0.0); dofs.n_free];
    for (r, &v) in f_raw.iter().enumerate() {
        if v == 0.0 || dofs.active[r / NCOMP] & (1 << (r % NCOMP)) == 0 {
            continue;
        }
        for (e, k) in dofs.expansion(r).terms {
            f[e] += factor * (k * v);
        }
    }
    f
}

/// The shift at which the residual flexibility is evaluated: 0 for a supported structure; for
/// one with rigid-body modes (K singular) a negative shift a tenth of the first elastic
/// eigenvalue below zero (K − σM is then positive definite and conditioned as a supported K).
fn residual_shift(modes: &ModalRun) -> Result<f64> {
    let n_rigid = modes.report.n_rigid;
    if n_rigid == 0 {
        return Ok(0.0);
    }
    match modes.lambda.get(n_rigid) {
        Some(&l) if l > 0.0 => Ok(-0.1 * l),
        _ => Err(Error::param(
            "modes",
            format!(
                "the static correction of a model with {n_rigid} rigid-body modes needs at least one elastic mode \
             among the modes superposed (it places its shift below the first); ask for more modes"
            ),
        )),
    }
}

/// Refuse a load of the wrong length, a negative or non-finite frequency, or bad damping; the
/// number of free DOFs otherwise.
fn check_request(sys: &System, load: &[c64], omegas: &[f64], damping: &Damping) -> Result<usize> {
    damping.validate()?;
    let n = sys.n_free();
    if load.len() != n {
        return Err(Error::param(
            "load",
            format!("harmonic load has {} entries, the system {n} free DOFs", load.len()),
        ));
    }
    if let Some(w) = omegas.iter().find(|w| !(w.is_finite() && **w >= 0.0)) {
        return Err(Error::param(
            "omegas",
            format!("harmonic frequency must be finite and ≥ 0, got {w} rad/s"),
        ));
    }
    Ok(n)
}

/// Steady-state response by modal superposition, one free-DOF vector per angular frequency in
/// `omegas` (rad/s). With `residual`, the static correction for the modes not in `modes` is added
/// (one factorisation of K − σM and one solve, whatever the number of frequencies). Rigid-body
/// modes count with λ = 0 exactly (see [`Superposition`]).
pub fn superpose(
    sys: &System,
    modes: &ModalRun,
    load: &[c64],
    omegas: &[f64],
    damping: &Damping,
    residual: bool,
) -> Result<Vec<Vec<c64>>> {
    check_request(sys, load, omegas, damping)?;
    let s = Superposition::new(sys, modes, load, damping, residual)?;
    omegas.iter().map(|&w| s.at(w)).collect()
}

/// The frequency-independent part of a modal superposition (modal loads, the static residual),
/// evaluated one frequency at a time with [`Superposition::at`] (a sweep keeps one response at
/// a time, not all of them).
///
/// Verified rigid-body modes (the first `modes.report.n_rigid`) are taken with λ = 0 exactly:
/// their computed eigenvalues are rounding (±1e-5 rad²/s² on a steel block), which at a low
/// excitation frequency (ω² = 4e-5 at 1 mHz) would change the response by tens of per cent.
pub struct Superposition<'a> {
    modes: &'a ModalRun,
    lambda: Vec<f64>,
    q: Vec<c64>,
    residual: Option<Vec<c64>>,
    damping: Damping,
    n_rigid: usize,
}

impl<'a> Superposition<'a> {
    /// Modal loads q_j = φ_jᵀF and, with `residual`, the static correction R F.
    pub fn new(
        sys: &System,
        modes: &'a ModalRun,
        load: &[c64],
        damping: &Damping,
        residual: bool,
    ) -> Result<Superposition<'a>> {
        let n = check_request(sys, load, &[], damping)?;
        let phi = &modes.vectors;
        let k = phi.ncols();
        if phi.nrows() != n {
            return Err(Error::param(
                "modes",
                format!(
                    "the modes have {} rows, the system {n} free DOFs: they belong to another model",
                    phi.nrows()
                ),
            ));
        }
        let n_rigid = modes.report.n_rigid.min(k);
        let lambda: Vec<f64> = (0..k)
            .map(|j| if j < n_rigid { 0.0 } else { modes.lambda[j] })
            .collect();
        // Modal loads q_j = φ_jᵀ F.
        let q: Vec<c64> = (0..k)
            .map(|j| {
                let mut s = c64::new(0.0, 0.0);
                for i in 0..n {
                    s += load[i] * phi[(i, j)];
                }
                s
            })
            .collect();
        // Modes spanning every degree of freedom leave no residual (a whole body coupled to one
        // node: its six rigid-body modes, and no elastic one to place a shift by).
        let residual = if residual && k < n {
            let sigma = residual_shift(modes)?;
            let mut r = solve_real_shifted(sys, sigma, load)?;
            for j in 0..k {
                let c = q[j] / (lambda[j] - sigma);
                for i in 0..n {
                    r[i] -= c * phi[(i, j)];
                }
            }
            Some(r)
        } else {
            None
        };
        Ok(Superposition {
            modes,
            lambda,
            q,
            residual,
            damping: *damping,
            n_rigid,
        })
    }

    /// The response at angular frequency `w` (rad/s).
    pub fn at(&self, w: f64) -> Result<Vec<c64>> {
        if !(w.is_finite() && w >= 0.0) {
            return Err(Error::param(
                "omega",
                format!("harmonic frequency must be finite and ≥ 0, got {w} rad/s"),
            ));
        }
        let phi = &self.modes.vectors;
        let n = phi.nrows();
        let mut u = self.residual.clone().unwrap_or_else(|| vec![c64::new(0.0, 0.0); n]);
        for (j, (&lam, &qj)) in self.lambda.iter().zip(&self.q).enumerate() {
            let den = c64::new(lam - w * w, w * self.damping.modal(lam));
            if den.norm() == 0.0 {
                return Err(Error::param(
                    if j < self.n_rigid { "omega" } else { "damping" },
                    if j < self.n_rigid {
                        format!(
                            "response at 0 Hz of a model with rigid-body modes (mode {}): an unbalanced force has \
                         no static response on a free body; support the model or give a frequency above 0",
                            j + 1
                        )
                    } else {
                        format!(
                            "undamped response at {:.6} Hz, the frequency of mode {}: infinite; give --damping or \
                         --rayleigh",
                            w / (2.0 * std::f64::consts::PI),
                            j + 1
                        )
                    },
                ));
            }
            let c = qj / den;
            for i in 0..n {
                u[i] += c * phi[(i, j)];
            }
        }
        Ok(u)
    }
}

/// The static (residual) correction for the modes after the first `q.len()` of `modes`:
/// R F̂ = (K − σM)⁻¹F̂ − Σ_j φ_j q_j / (λ_j − σ), with q_j = φ_jᵀF̂ (one factorisation, one solve).
fn static_correction(sys: &System, modes: &ModalRun, q: &[c64], load: &[c64]) -> Result<Vec<c64>> {
    let sigma = residual_shift(modes)?;
    let phi = &modes.vectors;
    let mut r = solve_real_shifted(sys, sigma, load)?;
    for (j, &qj) in q.iter().enumerate() {
        let c = qj / (modes.lambda[j] - sigma);
        for (i, ri) in r.iter_mut().enumerate() {
            *ri -= c * phi[(i, j)];
        }
    }
    Ok(r)
}

/// Steady-state response at one angular frequency ω (rad/s) by modal superposition with a full
/// modal damping matrix: discrete dashpots (C not proportional to K or M) couple the modes, so
/// the modal coordinates solve (Λ − ω²I + iωC_r) q = Φᵀ F̂ together, with C_r = Φᵀ C Φ given as
/// `modal_damping` over the first `modal_damping.nrows()` modes of `modes`. With `residual`, the
/// static correction for the modes left out is added as in [`superpose`].
pub fn superpose_coupled(
    sys: &System,
    modes: &ModalRun,
    load: &[c64],
    omega: f64,
    modal_damping: &nalgebra::DMatrix<f64>,
    residual: bool,
) -> Result<Vec<c64>> {
    let n = check_request(sys, load, &[omega], &Damping::Ratio(0.0))?;
    let k = modal_damping.nrows();
    let phi = &modes.vectors;
    if modal_damping.ncols() != k || k > phi.ncols() || phi.nrows() != n {
        return Err(Error::param(
            "modal_damping",
            format!(
                "a {}×{} modal damping matrix for {} modes of {} rows (the system has {n} free DOFs)",
                modal_damping.nrows(),
                modal_damping.ncols(),
                phi.ncols(),
                phi.nrows()
            ),
        ));
    }
    let q: Vec<c64> = (0..k)
        .map(|j| (0..n).fold(c64::new(0.0, 0.0), |s, i| s + load[i] * phi[(i, j)]))
        .collect();
    let x = coupled_modal(modes, &q, omega, modal_damping)?;
    let mut u = if residual {
        static_correction(sys, modes, &q, load)?
    } else {
        vec![c64::new(0.0, 0.0); n]
    };
    add_modes(&mut u, phi, &x);
    Ok(u)
}

/// [`superpose_coupled`] with the static correction from a given static solution
/// `static_solution` = K⁻¹F̂ (a model without rigid-body modes: the shift is 0), instead of a
/// factorisation of K: û = Σ_j φ_j x_j + K⁻¹F̂ − Σ_j φ_j q_j/λ_j. For a reduced model whose static
/// solve is exact in its basis (see `app::design::reduced`).
pub fn superpose_coupled_given(
    sys: &System,
    modes: &ModalRun,
    load: &[c64],
    omega: f64,
    modal_damping: &nalgebra::DMatrix<f64>,
    static_solution: Vec<c64>,
) -> Result<Vec<c64>> {
    let n = check_request(sys, load, &[omega], &Damping::Ratio(0.0))?;
    let k = modal_damping.nrows();
    let phi = &modes.vectors;
    if modal_damping.ncols() != k || k > phi.ncols() || phi.nrows() != n || static_solution.len() != n {
        return Err(Error::param(
            "modal_damping",
            format!(
                "a {}×{} modal damping matrix for {} modes of {} rows and a static solution of {} (the system has \
                 {n} free DOFs)",
                modal_damping.nrows(),
                modal_damping.ncols(),
                phi.ncols(),
                phi.nrows(),
                static_solution.len()
            ),
        ));
    }
    if modes.report.n_rigid > 0 {
        return Err(Error::param(
            "modes",
            "a given static solution needs a model without rigid-body modes (K not singular)",
        ));
    }
    let q: Vec<c64> = (0..k)
        .map(|j| (0..n).fold(c64::new(0.0, 0.0), |s, i| s + load[i] * phi[(i, j)]))
        .collect();
    let x = coupled_modal(modes, &q, omega, modal_damping)?;
    let mut u = static_solution;
    for (j, &qj) in q.iter().enumerate() {
        let c = qj / modes.lambda[j];
        for (i, ui) in u.iter_mut().enumerate() {
            *ui -= c * phi[(i, j)];
        }
    }
    add_modes(&mut u, phi, &x);
    Ok(u)
}

/// u += Σ_j x_j φ_j.
fn add_modes(u: &mut [c64], phi: &faer::Mat<f64>, x: &nalgebra::DVector<nalgebra::Complex<f64>>) {
    for j in 0..x.len() {
        let c = c64::new(x[j].re, x[j].im);
        for (i, ui) in u.iter_mut().enumerate() {
            *ui += c * phi[(i, j)];
        }
    }
}

/// The modal coordinates of a coupled superposition: (Λ − ω²I + iωC_r) x = q.
fn coupled_modal(
    modes: &ModalRun,
    q: &[c64],
    omega: f64,
    modal_damping: &nalgebra::DMatrix<f64>,
) -> Result<nalgebra::DVector<nalgebra::Complex<f64>>> {
    let k = q.len();
    let a = nalgebra::DMatrix::from_fn(k, k, |i, j| {
        let diag = if i == j { modes.lambda[i] - omega * omega } else { 0.0 };
        nalgebra::Complex::new(diag, omega * modal_damping[(i, j)])
    });
    let rhs = nalgebra::DVector::from_fn(k, |j, _| nalgebra::Complex::new(q[j].re, q[j].im));
    let x = a.lu().solve(&rhs).ok_or_else(|| Error::Singular {
        equation: None,
        at: None,
        msg: format!(
            "the reduced dynamic stiffness Λ − ω²I + iωC_r is singular at {:.6} Hz",
            omega / (2.0 * std::f64::consts::PI)
        ),
    })?;
    Ok(x)
}

/// Solve (K − σM) x = f for a complex f with the real LDLᵀ on the system's ordering (real and
/// imaginary parts as two right-hand sides).
fn solve_real_shifted(sys: &System, sigma: f64, f: &[c64]) -> Result<Vec<c64>> {
    let shift = if sigma == 0.0 { None } else { Some((sys.m()?, sigma)) };
    let fac = crate::linalg::factor::Factor::new_shifted(sys.symbolic()?.clone(), sys.k(), shift)
        .map_err(|e| e.locate(|eq| sys.describe_equation(eq)))?;
    let n = f.len();
    let mut b = faer::Mat::from_fn(n, 2, |i, c| if c == 0 { f[i].re } else { f[i].im });
    fac.solve_in_place(b.as_mut());
    Ok((0..n).map(|i| c64::new(b[(i, 0)], b[(i, 1)])).collect())
}

/// Direct solve of (K − ω²M + iωC) û = F̂ at one angular frequency ω (rad/s), sparse LU with
/// partial pivoting. Rayleigh damping uses C = αM + βK; a modal ratio ζ is taken as structural
/// damping iωC = 2iζK (the same response as modal damping at every resonance, not between).
pub fn direct(sys: &System, load: &[c64], omega: f64, damping: &Damping) -> Result<Vec<c64>> {
    let n = check_request(sys, load, &[omega], damping)?;
    let k = sys.k();
    let m = sys.m()?;
    let p = &k.pattern;
    let w2 = omega * omega;
    // A = (1 + iωβ)K − (ω² − iωα)M for Rayleigh; (1 + 2iζ)K − ω²M for a modal ratio.
    let (ck, cm) = match *damping {
        Damping::Rayleigh { alpha, beta } => (c64::new(1.0, omega * beta), c64::new(w2, -omega * alpha)),
        Damping::Ratio(z) => (c64::new(1.0, 2.0 * z), c64::new(w2, 0.0)),
    };
    // M on K's pattern (it may store only its nonzeros).
    let m = m.on_pattern(k.pattern.clone());
    let values: Vec<c64> = k
        .values
        .iter()
        .zip(&m.values)
        .map(|(&kv, &mv)| ck * kv - cm * mv)
        .collect();
    let symbolic = SymbolicSparseColMat::new_checked(
        n,
        n,
        p.col_ptr.clone(),
        None,
        p.row_idx.iter().map(|&i| i as usize).collect(),
    );
    let a = SparseColMat::new(symbolic, values);
    let lu = a.sp_lu().map_err(|e| Error::Singular {
        equation: None,
        at: None,
        msg: format!(
            "K − ω²M + iωC is singular at {:.6} Hz ({e:?}): an undamped resonance or an unsupported \
             rigid-body motion; give --damping or --rayleigh, or support the model",
            omega / (2.0 * std::f64::consts::PI)
        ),
    })?;
    let mut x = faer::Mat::from_fn(n, 1, |i, _| load[i]);
    lu.solve_in_place_with_conj(faer::Conj::No, x.as_mut());
    let mut u: Vec<c64> = (0..n).map(|i| x[(i, 0)]).collect();
    // Two steps of iterative refinement with the residual F − A u (A applied through K and M):
    // near a lightly damped resonance A is ill-conditioned and one LU solve alone loses digits.
    for _ in 0..2 {
        let re: Vec<f64> = u.iter().map(|v| v.re).collect();
        let im: Vec<f64> = u.iter().map(|v| v.im).collect();
        let (kr, ki, mr, mi) = (k.mul_vec(&re), k.mul_vec(&im), m.mul_vec(&re), m.mul_vec(&im));
        let mut r = faer::Mat::from_fn(n, 1, |i, _| {
            load[i] - (ck * c64::new(kr[i], ki[i]) - cm * c64::new(mr[i], mi[i]))
        });
        lu.solve_in_place_with_conj(faer::Conj::No, r.as_mut());
        for (i, v) in u.iter_mut().enumerate() {
            *v += r[(i, 0)];
        }
    }
    if u.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
        return Err(Error::Singular {
            equation: None,
            at: None,
            msg: format!(
                "direct harmonic solve at {:.6} Hz gave non-finite values: the system is singular there",
                omega / (2.0 * std::f64::consts::PI)
            ),
        });
    }
    Ok(u)
}

/// [`direct`] on a model with rigid-body modes `rigid` (M-orthonormal columns, e.g. the verified
/// rigid-body modes of a modal solve): the rigid part of the response is taken exactly,
/// φᵀF̂ / (−ω² + iωc(0)) per mode (K φ = 0), and only the load orthogonal to them, F̂ − Mφφᵀ F̂,
/// goes through the complex solve, whose rigid part is projected out. Without this, the rounding
/// of K's null space (rigid "eigenvalues" of ±1e-5 rad²/s²) competes with ω² at low frequencies.
/// Refuses ω = 0 (no static response of a free body to an unbalanced force).
pub fn direct_free(
    sys: &System,
    load: &[c64],
    omega: f64,
    damping: &Damping,
    rigid: faer::MatRef<'_, f64>,
) -> Result<Vec<c64>> {
    let n = check_request(sys, load, &[omega], damping)?;
    let r = rigid.ncols();
    if r == 0 {
        return direct(sys, load, omega, damping);
    }
    if rigid.nrows() != n {
        return Err(Error::param(
            "rigid",
            format!(
                "the rigid-body modes have {} rows, the system {n} free DOFs: they belong to another model",
                rigid.nrows()
            ),
        ));
    }
    let den = c64::new(-omega * omega, omega * damping.modal(0.0));
    if den.norm() == 0.0 {
        return Err(Error::param(
            "omega",
            "response at 0 Hz of a model with rigid-body modes: an unbalanced force has no static response on \
             a free body; support the model or give a frequency above 0",
        ));
    }
    let mut mr = faer::Mat::<f64>::zeros(n, r);
    sys.m()?.mul_block(rigid, mr.as_mut());
    let dot = |a: faer::MatRef<'_, f64>, j: usize, v: &[c64]| -> c64 {
        let mut s = c64::new(0.0, 0.0);
        for (i, vi) in v.iter().enumerate() {
            s += vi * a[(i, j)];
        }
        s
    };
    let q: Vec<c64> = (0..r).map(|j| dot(rigid, j, load)).collect();
    let mut f = load.to_vec();
    for (j, &qj) in q.iter().enumerate() {
        for (i, fi) in f.iter_mut().enumerate() {
            *fi -= qj * mr[(i, j)];
        }
    }
    let mut u = direct(sys, &f, omega, damping)?;
    for (j, &qj) in q.iter().enumerate() {
        let c = qj / den - dot(mr.as_ref(), j, &u);
        for (i, ui) in u.iter_mut().enumerate() {
            *ui += c * rigid[(i, j)];
        }
    }
    Ok(u)
}

/// Per-node complex displacement `[ux, uy, uz, rx, ry, rz]` from a free-DOF vector (constrained
/// components through their constraints, fixed ones 0: a harmonic load has no prescribed motion).
pub fn expand(sys: &System, u: &[c64]) -> Vec<[c64; 6]> {
    let dofs = sys.dofs();
    let re: Vec<f64> = u.iter().map(|v| v.re).collect();
    let im: Vec<f64> = u.iter().map(|v| v.im).collect();
    let r = dofs.expand(&re, NCOMP);
    let i = dofs.expand(&im, NCOMP);
    (0..dofs.n_nodes())
        .map(|a| std::array::from_fn(|c| c64::new(r[NCOMP * a + c], i[NCOMP * a + c])))
        .collect()
}

/// Peak displacement of a node over one period: the semi-major axis of the orbit traced by
/// Re(û e^{iωt}) for û = a + ib (equals |û| when the components are in phase).
pub fn peak(u: &[c64; 3]) -> f64 {
    if u.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
        return f64::NAN;
    }
    // Squares of components beyond 1e154 overflow (and below 1e-154 underflow): compute those
    // on the components divided by a power of two (exact).
    let s = u.iter().map(|v| v.re.abs().max(v.im.abs())).fold(0.0, f64::max);
    if s > 1e150 || (s > 0.0 && s < 1e-150) {
        let k = 2f64.powi(s.log2().floor() as i32);
        return k * peak(&u.map(|v| v / k));
    }
    let aa: f64 = u.iter().map(|v| v.re * v.re).sum();
    let bb: f64 = u.iter().map(|v| v.im * v.im).sum();
    let ab: f64 = u.iter().map(|v| v.re * v.im).sum();
    let h = 0.5 * (aa - bb);
    (0.5 * (aa + bb) + (h * h + ab * ab).sqrt()).max(0.0).sqrt()
}

/// Free-DOF load vector of group forces with their phases.
pub fn group_load(sys: &System, mesh: &crate::mesh::Mesh, forces: &[GroupForce]) -> Result<Vec<c64>> {
    let mut f = vec![c64::new(0.0, 0.0); sys.n_free()];
    for gf in forces {
        let raw = crate::analysis::statics::load_vector(
            mesh,
            sys.model(),
            &[crate::analysis::statics::Load::Force {
                group: gf.group.clone(),
                force: gf.force,
            }],
        )?;
        let ph = gf.phase_deg.to_radians();
        for (a, b) in f.iter_mut().zip(reduce_raw(sys, &raw, c64::new(ph.cos(), ph.sin()))) {
            *a += b;
        }
    }
    Ok(f)
}
