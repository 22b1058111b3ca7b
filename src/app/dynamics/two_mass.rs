//! The lumped two-mass model of the vibratory table (docs/spec/paper.md §5–§7, eq. (1)–(7)).
//!
//! ```text
//! m1·x1'' + c12·(x1 − x2) + μ1·x1' + μ12·(x1' − x2')           = −F·sin Ωt
//! m2·x2'' + c12·(x2 − x1) + c13·x2 + μ13·x2' + μ12·(x2' − x1') = +F·sin Ωt        (1)
//! ```
//!
//! m1 is the active mass (work table plus its share of the load, carries the magnet armatures), m2
//! the reactive mass (carries the magnet cores), c12 the leaf springs between them, c13 the
//! isolators from m2 to the floor. The force ±F is internal (armature pulled towards core).
//!
//! In matrix form `M x'' + C x' + K x = f`, with `f = (−1, +1)·F sin Ωt`.
//!
//! # The k-term variants
//! The paper's printed dynamic-stiffness terms (§6) put c13 and μ13 in the m1 row, which disagrees
//! with eq. (1) and the paper's own Mathcad listing (§19). [`KTerms::Eq1`] (default) implements
//! eq. (1); [`KTerms::AsPrinted`] the printed k-terms, i.e. the isolators on m1 (both are
//! consistent linear systems). They differ by about 3 % in X1 at 100 Hz.
//!
//! # Steady state and phase convention
//! With `x_j(t) = Im(X_j·e^{iΩt}) = |X_j|·sin(Ωt + φ_j)`, the complex amplitudes solve
//! `[K − Ω²M + iΩC]·X = (−F, +F)` (eq. (2)); they are computed by the paper's eq. (3)–(4). The phase
//! φ_j = arg X_j (rad) is measured against the force +F·sin Ωt acting on m2.

use nalgebra::{Complex, Matrix2, SymmetricEigen};

use crate::{Error, Result};

/// Which dynamic-stiffness terms to use (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum KTerms {
    /// Eq. (1) and the Mathcad listing: isolators c13, μ13 act on the reactive mass m2.
    #[default]
    Eq1,
    /// The k-terms as printed in §6: c13 and μ13 sit in the m1 row
    /// (`k11 = c12 + c13 − m1Ω² + i(μ1 + μ13 + μ12)Ω`, `k22 = c12 − m2Ω² + iμ12Ω`).
    AsPrinted,
}

/// Which of the two masses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mass {
    /// The active mass m1 (work table).
    Active,
    /// The reactive mass m2 (magnet cores).
    Reactive,
}

/// Two-mass model parameters (SI units). Construct with [`TwoMass::new`], which validates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoMass {
    /// Active mass m1, kg (> 0).
    pub m1: f64,
    /// Reactive mass m2, kg (> 0).
    pub m2: f64,
    /// Stiffness of the elastic system between the masses (leaf springs) c12, N/m (> 0).
    pub c12: f64,
    /// Isolator stiffness to the floor c13 (all isolators together), N/m (> 0).
    pub c13: f64,
    /// Viscous damping of the active mass to ground (load medium) μ1, N·s/m (≥ 0).
    pub mu1: f64,
    /// Viscous damping in the elastic system c12, μ12, N·s/m (≥ 0).
    pub mu12: f64,
    /// Viscous damping in the isolators μ13, N·s/m (≥ 0).
    pub mu13: f64,
    /// Dynamic-stiffness variant (default [`KTerms::Eq1`]).
    pub k_terms: KTerms,
}

/// Dynamic-stiffness terms k_ij(Ω) of eq. (2), N/m (complex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicStiffness {
    /// k11(Ω), N/m.
    pub k11: Complex<f64>,
    /// k12(Ω), N/m.
    pub k12: Complex<f64>,
    /// k21(Ω) = k12(Ω), N/m.
    pub k21: Complex<f64>,
    /// k22(Ω), N/m.
    pub k22: Complex<f64>,
}

/// Steady-state harmonic response at one forcing frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyState {
    /// Forcing angular frequency Ω, rad/s.
    pub omega: f64,
    /// Force amplitude F, N.
    pub force: f64,
    /// Complex amplitude X1 of the active mass, m (eq. (3)).
    pub x1: Complex<f64>,
    /// Complex amplitude X2 of the reactive mass, m (eq. (3)).
    pub x2: Complex<f64>,
    /// The paper's determinant D = k12·k21 − k11·k22 (eq. (4)), N²/m².
    pub determinant: Complex<f64>,
    /// Dynamic factor γ1 = |X1|·m1·Ω²/F of the active mass (eq. (7)), dimensionless.
    pub gamma1: f64,
    /// Dynamic factor γ2 = |X2|·m2·Ω²/F of the reactive mass (eq. (7)), dimensionless.
    pub gamma2: f64,
}

impl SteadyState {
    /// Forcing frequency Ω/2π, Hz.
    pub fn freq_hz(&self) -> f64 {
        self.omega / (2.0 * std::f64::consts::PI)
    }
    /// Amplitude |X1| of the active mass, m.
    pub fn amp1(&self) -> f64 {
        self.x1.norm()
    }
    /// Amplitude |X2| of the reactive mass, m.
    pub fn amp2(&self) -> f64 {
        self.x2.norm()
    }
    /// Phase φ1 = arg X1 of the active mass against the force on m2, rad in (−π, π].
    pub fn phase1(&self) -> f64 {
        self.x1.arg()
    }
    /// Phase φ2 = arg X2 of the reactive mass against the force on m2, rad in (−π, π].
    pub fn phase2(&self) -> f64 {
        self.x2.arg()
    }
    /// Amplitude of the relative motion |X1 − X2| (leaf-spring deflection), m.
    pub fn relative_amp(&self) -> f64 {
        (self.x1 - self.x2).norm()
    }
}

/// A resonance peak of an amplitude–frequency curve, located by golden-section refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResonancePeak {
    /// Frequency of the peak, Hz.
    pub freq_hz: f64,
    /// The steady state at the peak.
    pub state: SteadyState,
}

/// Relative threshold below which the excitation is treated as an exact undamped resonance:
/// |D| ≤ 1e-10·(|p1·p2| + |s|·(|p1| + |p2|)), where D = −(p1·p2 + s·(p1 + p2)) is eq. (4) written
/// with the coupling s = c12 + iΩμ12 and the grounded parts p1 = k11 + k12, p2 = k22 + k21. The
/// terms cancel only at a natural frequency; at the threshold the amplitude would be ~1e10 times
/// the quasi-static scale F/c, which only an (almost) undamped system at (almost) exactly a natural
/// frequency reaches.
pub const RESONANCE_REL_TOL: f64 = 1e-10;

fn positive(name: &str, v: f64, unit: &str) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        return Err(Error::param(
            name,
            format!("two-mass model: {name} must be finite and > 0 {unit}, got {v}"),
        ));
    }
    Ok(())
}

fn non_negative(name: &str, v: f64, unit: &str) -> Result<()> {
    if !(v.is_finite() && v >= 0.0) {
        return Err(Error::param(
            name,
            format!("two-mass model: {name} must be finite and ≥ 0 {unit}, got {v}"),
        ));
    }
    Ok(())
}

pub(crate) fn check_omega(name: &str, omega: f64) -> Result<()> {
    if !(omega.is_finite() && omega >= 0.0) {
        return Err(Error::param(
            name,
            format!("{name} must be finite and ≥ 0 rad/s, got {omega}"),
        ));
    }
    Ok(())
}

impl TwoMass {
    /// Builds a validated model with the eq. (1) k-terms. Units: kg, N/m, N·s/m.
    ///
    /// Errors ([`Error::Invalid`], naming the parameter): a mass or stiffness that is not
    /// finite and > 0; a damping coefficient that is negative or not finite.
    pub fn new(m1: f64, m2: f64, c12: f64, c13: f64, mu1: f64, mu12: f64, mu13: f64) -> Result<Self> {
        let m = TwoMass {
            m1,
            m2,
            c12,
            c13,
            mu1,
            mu12,
            mu13,
            k_terms: KTerms::Eq1,
        };
        m.validate()?;
        Ok(m)
    }

    /// The paper's machine (docs/spec/scenes.md S8): m1 = 206.7 kg, m2 = 161.8 kg, c12 = 3.808e7 N/m,
    /// c13 = 8 × 60 266 N/m, μ1 = 2400, μ12 = 1830, μ13 = 230 N·s/m.
    pub fn paper() -> Self {
        TwoMass {
            m1: 206.7,
            m2: 161.8,
            c12: 3.808e7,
            c13: 8.0 * 60266.0,
            mu1: 2400.0,
            mu12: 1830.0,
            mu13: 230.0,
            k_terms: KTerms::Eq1,
        }
    }

    /// The same model with another k-term variant.
    pub fn with_k_terms(mut self, k_terms: KTerms) -> Self {
        self.k_terms = k_terms;
        self
    }

    /// Checks the parameters (see [`TwoMass::new`]).
    pub fn validate(&self) -> Result<()> {
        positive("m1 (active mass)", self.m1, "kg")?;
        positive("m2 (reactive mass)", self.m2, "kg")?;
        positive("c12 (leaf-spring stiffness)", self.c12, "N/m")?;
        positive("c13 (isolator stiffness)", self.c13, "N/m")?;
        non_negative("mu1 (damping of m1)", self.mu1, "N·s/m")?;
        non_negative("mu12 (damping of c12)", self.mu12, "N·s/m")?;
        non_negative("mu13 (isolator damping)", self.mu13, "N·s/m")?;
        Ok(())
    }

    /// Reduced mass m_red = m1·m2/(m1 + m2), kg (eq. (5)).
    pub fn reduced_mass(&self) -> f64 {
        self.m1 * self.m2 / (self.m1 + self.m2)
    }

    /// Whether all damping coefficients are zero.
    pub fn is_undamped(&self) -> bool {
        self.mu1 == 0.0 && self.mu12 == 0.0 && self.mu13 == 0.0
    }

    /// The mass the isolators c13, μ13 act on: m2 for [`KTerms::Eq1`], m1 for [`KTerms::AsPrinted`].
    pub fn isolated_mass(&self) -> Mass {
        match self.k_terms {
            KTerms::Eq1 => Mass::Reactive,
            KTerms::AsPrinted => Mass::Active,
        }
    }

    /// Grounded stiffness and damping of each mass, [(K_g1, C_g1), (K_g2, C_g2)] in N/m and N·s/m:
    /// the springs and dampers from each mass to the fixed frame (c13, μ13 on the isolated mass, μ1
    /// on m1).
    pub fn grounded(&self) -> [(f64, f64); 2] {
        match self.k_terms {
            KTerms::Eq1 => [(0.0, self.mu1), (self.c13, self.mu13)],
            KTerms::AsPrinted => [(self.c13, self.mu1 + self.mu13), (0.0, 0.0)],
        }
    }

    /// Mass, damping and stiffness matrices (kg, N·s/m, N/m) of `M x'' + C x' + K x = f`.
    pub fn matrices(&self) -> (Matrix2<f64>, Matrix2<f64>, Matrix2<f64>) {
        let m = Matrix2::new(self.m1, 0.0, 0.0, self.m2);
        let (c, k) = match self.k_terms {
            KTerms::Eq1 => (
                Matrix2::new(self.mu1 + self.mu12, -self.mu12, -self.mu12, self.mu12 + self.mu13),
                Matrix2::new(self.c12, -self.c12, -self.c12, self.c12 + self.c13),
            ),
            KTerms::AsPrinted => (
                Matrix2::new(self.mu1 + self.mu12 + self.mu13, -self.mu12, -self.mu12, self.mu12),
                Matrix2::new(self.c12 + self.c13, -self.c12, -self.c12, self.c12),
            ),
        };
        (m, c, k)
    }

    /// The dynamic-stiffness terms k_ij(Ω) = K_ij − Ω²M_ij + iΩC_ij of eq. (2), N/m.
    pub fn dynamic_stiffness(&self, omega: f64) -> DynamicStiffness {
        let (m, c, k) = self.matrices();
        let e = |i: usize, j: usize| Complex::new(k[(i, j)] - omega * omega * m[(i, j)], omega * c[(i, j)]);
        DynamicStiffness {
            k11: e(0, 0),
            k12: e(0, 1),
            k21: e(1, 0),
            k22: e(1, 1),
        }
    }

    /// Steady-state response to the internal force ±F·sin Ωt (Ω in rad/s, F in N), by eq. (3)–(4).
    ///
    /// Errors: invalid parameters, Ω negative or not finite, F not finite, and an excitation at an
    /// undamped natural frequency (|D| below [`RESONANCE_REL_TOL`] of its terms), whose amplitude is
    /// unbounded.
    pub fn steady_state(&self, omega: f64, force: f64) -> Result<SteadyState> {
        self.validate()?;
        check_omega("forcing frequency Ω", omega)?;
        if !force.is_finite() {
            return Err(Error::param(
                "force",
                format!("force amplitude F must be finite, got {force} N"),
            ));
        }
        // Eq. (3)–(4) in a form free of cancellation: with s = −k12 = c12 + iΩμ12 (the coupling) and
        // the grounded parts p1 = k11 + k12, p2 = k22 + k21 (computed directly, not by subtraction),
        //   D = k12·k21 − k11·k22 = −(p1·p2 + s·(p1 + p2)),  k12 + k22 = p2,  k11 + k21 = p1.
        // Algebraically identical to the paper's expressions; numerically it avoids losing
        // log10(c12/c13) digits when c13 ≪ c12 at low frequency.
        let [(kg1, cg1), (kg2, cg2)] = self.grounded();
        let w2 = omega * omega;
        let sc = Complex::new(self.c12, omega * self.mu12);
        let p1 = Complex::new(kg1 - self.m1 * w2, omega * cg1);
        let p2 = Complex::new(kg2 - self.m2 * w2, omega * cg2);
        let d = -(p1 * p2 + sc * (p1 + p2)); // eq. (4)
        // Resonance: the terms of D cancel (det(K − Ω²M) = 0 with no damping to stop it).
        let scale = (p1 * p2).norm() + sc.norm() * (p1.norm() + p2.norm());
        if d.norm().is_nan() || d.norm() <= RESONANCE_REL_TOL * scale {
            let wn = self.natural_frequencies()?;
            return Err(Error::param(
                "omega",
                format!(
                    "excitation at Ω = {omega} rad/s ({:.6} Hz) is at an undamped resonance of the two-mass \
                 model (natural frequencies {:.6} Hz and {:.6} Hz, damping μ1 = {}, μ12 = {}, μ13 = {} N·s/m): \
                 the steady-state amplitude is unbounded; add damping or move the excitation",
                    omega / (2.0 * std::f64::consts::PI),
                    wn[0] / (2.0 * std::f64::consts::PI),
                    wn[1] / (2.0 * std::f64::consts::PI),
                    self.mu1,
                    self.mu12,
                    self.mu13
                ),
            ));
        }
        // Unit-force receptances (eq. (3) with F = 1), m/N.
        let h1 = p2 / d;
        let h2 = -p1 / d;
        if !(h1.re.is_finite() && h1.im.is_finite() && h2.re.is_finite() && h2.im.is_finite()) {
            return Err(Error::param(
                "omega",
                format!("steady state at Ω = {omega} rad/s is not finite (parameters out of floating-point range?)"),
            ));
        }
        Ok(SteadyState {
            omega,
            force,
            x1: h1 * force,
            x2: h2 * force,
            determinant: d,
            gamma1: h1.norm() * self.m1 * w2,
            gamma2: h2.norm() * self.m2 * w2,
        })
    }

    /// Static displacements (x1, x2), m, under a constant internal force pair (−P on m1, +P on m2),
    /// P in N. For either variant the relative displacement is x1 − x2 = −P/c12; with
    /// [`KTerms::Eq1`] x2 = 0 (the isolators carry no net load from an internal force).
    pub fn static_response(&self, p: f64) -> Result<(f64, f64)> {
        self.validate()?;
        if !p.is_finite() {
            return Err(Error::param("p", format!("static force P must be finite, got {p} N")));
        }
        // K x = (−P, P). det K = c12·c13 > 0.
        let (_, _, k) = self.matrices();
        let det = k[(0, 0)] * k[(1, 1)] - k[(0, 1)] * k[(1, 0)];
        let x1 = (-p * k[(1, 1)] - k[(0, 1)] * p) / det;
        let x2 = (k[(0, 0)] * p + k[(1, 0)] * p) / det;
        Ok((x1, x2))
    }

    /// Both undamped natural frequencies ω_I ≤ ω_II, rad/s, in closed form.
    ///
    /// `det(K − λM) = m1·m2·λ² − (K11·m2 + K22·m1)·λ + c12·c13 = 0`, with K11 = c12 (+ c13 as
    /// printed), K22 = c12 + c13 (eq. (1)) or c12. The discriminant is written as
    /// `(K11·m2 − K22·m1)² + 4·c12²·m1·m2` (no cancellation) and the small root as
    /// `c12·c13/(m1·m2·λ_II)`, so both are accurate to rounding even for c13 ≪ c12.
    /// Limits: c13 → 0 gives ω_I → 0 and ω_II → sqrt(c12/m_red); m2 → ∞ gives ω_II → sqrt(c12/m1).
    pub fn natural_frequencies(&self) -> Result<[f64; 2]> {
        self.validate()?;
        let (_, _, k) = self.matrices();
        let (k11, k22) = (k[(0, 0)], k[(1, 1)]);
        let a = self.m1 * self.m2;
        let b = k11 * self.m2 + k22 * self.m1;
        let disc = (k11 * self.m2 - k22 * self.m1).powi(2) + 4.0 * self.c12 * self.c12 * a;
        let lam_hi = (b + disc.sqrt()) / (2.0 * a);
        let lam_lo = self.c12 * self.c13 / (a * lam_hi);
        Ok([lam_lo.sqrt(), lam_hi.sqrt()])
    }

    /// Both undamped natural frequencies, Hz (see [`TwoMass::natural_frequencies`]).
    pub fn natural_frequencies_hz(&self) -> Result<[f64; 2]> {
        let w = self.natural_frequencies()?;
        Ok(w.map(|v| v / (2.0 * std::f64::consts::PI)))
    }

    /// The same two frequencies (rad/s) from a dense symmetric generalized eigen solve of (K, M)
    /// (nalgebra, via M^{-1/2}·K·M^{-1/2}); a cross-check of the closed form.
    pub fn natural_frequencies_eigen(&self) -> Result<[f64; 2]> {
        self.validate()?;
        let (m, _, k) = self.matrices();
        let s = Matrix2::new(1.0 / m[(0, 0)].sqrt(), 0.0, 0.0, 1.0 / m[(1, 1)].sqrt());
        let a = s * k * s;
        let eig = SymmetricEigen::new(a);
        let mut l = [eig.eigenvalues[0], eig.eigenvalues[1]];
        l.sort_by(f64::total_cmp);
        Ok([l[0].max(0.0).sqrt(), l[1].max(0.0).sqrt()])
    }

    /// Natural frequency of the uncoupled pair ω0 = sqrt(c12/m_red), rad/s (eq. (5), isolators and
    /// damping neglected).
    pub fn omega0(&self) -> f64 {
        (self.c12 / self.reduced_mass()).sqrt()
    }

    /// Resonance tuning z = Ω/ω0 (eq. (5)) at the forcing frequency Ω (rad/s).
    pub fn detuning(&self, omega: f64) -> Result<f64> {
        self.validate()?;
        check_omega("forcing frequency Ω", omega)?;
        Ok(omega / self.omega0())
    }

    /// Amplitude–frequency and phase curves: the steady state at `n` frequencies spaced evenly from
    /// `f_lo` to `f_hi` (Hz), force amplitude F (N).
    ///
    /// Errors: bad range (`f_lo` < 0, `f_hi` ≤ `f_lo`, `n` < 3) and, for an undamped model, a sample
    /// falling exactly on a natural frequency.
    pub fn frequency_response(&self, f_lo: f64, f_hi: f64, n: usize, force: f64) -> Result<Vec<SteadyState>> {
        check_range(f_lo, f_hi, n)?;
        (0..n)
            .map(|i| {
                let f = f_lo + (f_hi - f_lo) * i as f64 / (n - 1) as f64;
                self.steady_state(2.0 * std::f64::consts::PI * f, force)
            })
            .collect()
    }

    /// Resonance peaks of |X_j| for the chosen mass between `f_lo` and `f_hi` (Hz): every local
    /// maximum on an `n`-point grid, refined by golden-section search on the bracketing grid
    /// interval (bracket shrunk to 1e-10 relative; since |X| is flat at its maximum, the location is
    /// accurate to about sqrt(machine ε) ≈ 1e-8 relative). Sorted by frequency. The grid must be fine
    /// enough to separate the peaks (a few points per half-power bandwidth).
    ///
    /// Errors: bad range; an undamped model (its peaks are infinite: use
    /// [`TwoMass::natural_frequencies`]).
    pub fn resonance_peaks(&self, which: Mass, f_lo: f64, f_hi: f64, n: usize) -> Result<Vec<ResonancePeak>> {
        self.validate()?;
        check_range(f_lo, f_hi, n)?;
        if self.is_undamped() {
            return Err(Error::param(
                "damping",
                "resonance peaks of an undamped two-mass model are unbounded; use the natural frequencies",
            ));
        }
        let tau = std::f64::consts::TAU;
        let amp = |f: f64| -> Result<f64> {
            let s = self.steady_state(tau * f, 1.0)?;
            Ok(match which {
                Mass::Active => s.amp1(),
                Mass::Reactive => s.amp2(),
            })
        };
        let fs: Vec<f64> = (0..n)
            .map(|i| f_lo + (f_hi - f_lo) * i as f64 / (n - 1) as f64)
            .collect();
        let a: Vec<f64> = fs.iter().map(|&f| amp(f)).collect::<Result<_>>()?;
        let mut peaks = Vec::new();
        for i in 1..n - 1 {
            if a[i] > a[i - 1] && a[i] >= a[i + 1] {
                let f = golden_max(&amp, fs[i - 1], fs[i + 1])?;
                peaks.push(ResonancePeak {
                    freq_hz: f,
                    state: self.steady_state(tau * f, 1.0)?,
                });
            }
        }
        Ok(peaks)
    }

    /// Force transmitted to the floor through the isolators, complex amplitude in N, at Ω (rad/s)
    /// for the force amplitude F (N): `(c13 + iΩμ13)·X_iso`, X_iso the amplitude of the mass the
    /// isolators carry ([`TwoMass::isolated_mass`]).
    pub fn floor_force(&self, omega: f64, force: f64) -> Result<Complex<f64>> {
        let s = self.steady_state(omega, force)?;
        let x = match self.isolated_mass() {
            Mass::Active => s.x1,
            Mass::Reactive => s.x2,
        };
        Ok(Complex::new(self.c13, omega * self.mu13) * x)
    }

    /// Power dissipated by the model's dashpots at the steady state, W, for Ω (rad/s) and F (N):
    /// the mean of Σ c·v² over a period, Ω²/2·Xᴴ C X (= Ω²/2·(μ1|X1|² + μ12|X1 − X2|² + μ13|X2|²)
    /// for the eq. (1) terms); the power the drive must supply to the mechanics in steady state.
    pub fn dissipated_power(&self, omega: f64, force: f64) -> Result<f64> {
        let s = self.steady_state(omega, force)?;
        let (_, c, _) = self.matrices();
        let x = [s.x1, s.x2];
        let mut p = 0.0;
        for i in 0..2 {
            for j in 0..2 {
                p += (x[i].conj() * c[(i, j)] * x[j]).re;
            }
        }
        Ok(0.5 * omega * omega * p)
    }

    /// Drive power by eq. (6), W, at the steady state for Ω (rad/s) and F (N), with efficiency η
    /// (0 < η ≤ 1) and the attached load mass m_pr (kg, ≥ 0) moving with m1:
    /// `N = Ω³/(2η)·(X1²·m1/γ1 + X2²·m2/γ2 + X1²·m_pr)`.
    pub fn drive_power(&self, omega: f64, force: f64, eta: f64, m_pr: f64) -> Result<f64> {
        let s = self.steady_state(omega, force)?;
        super::tuning::drive_power(
            omega,
            eta,
            &[(s.amp1(), self.m1, s.gamma1), (s.amp2(), self.m2, s.gamma2)],
            s.amp1(),
            m_pr,
        )
    }
}

fn check_range(f_lo: f64, f_hi: f64, n: usize) -> Result<()> {
    if !(f_lo.is_finite() && f_hi.is_finite() && f_lo >= 0.0 && f_hi > f_lo) {
        return Err(Error::param(
            "f_lo",
            format!("frequency range must satisfy 0 ≤ f_lo < f_hi (finite, Hz), got {f_lo} … {f_hi}"),
        ));
    }
    if n < 3 {
        return Err(Error::param(
            "n",
            format!("frequency sweep needs at least 3 points, got {n}"),
        ));
    }
    Ok(())
}

/// Golden-section search for the maximum of a unimodal function on [a, b].
fn golden_max(f: &dyn Fn(f64) -> Result<f64>, mut a: f64, mut b: f64) -> Result<f64> {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - g * (b - a);
    let mut x2 = a + g * (b - a);
    let mut f1 = f(x1)?;
    let mut f2 = f(x2)?;
    for _ in 0..200 {
        if (b - a) <= 1e-10 * b.abs().max(1e-12) {
            break;
        }
        if f1 < f2 {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2)?;
        } else {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1)?;
        }
    }
    Ok(0.5 * (a + b))
}

/// Unwraps a sequence of phases (rad) so that consecutive values differ by less than π.
pub fn unwrap_phase(phases: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(phases.len());
    let mut offset = 0.0;
    let tau = std::f64::consts::TAU;
    for (i, &p) in phases.iter().enumerate() {
        if i > 0 {
            let prev = phases[i - 1];
            let d = p - prev;
            if d > std::f64::consts::PI {
                offset -= tau;
            } else if d < -std::f64::consts::PI {
                offset += tau;
            }
        }
        out.push(p + offset);
    }
    out
}
