//! High-cycle fatigue assessment: a mean state plus an alternating state per node, equivalent
//! stresses by a stated criterion, mean-stress correction (Goodman, Gerber, the FKM Haigh
//! diagram), an endurance limit corrected for surface, size and reliability, and finite life by
//! Basquin. See docs/fatigue.md for the method and its sources.
//!
//! # Equivalent stresses
//! Two criteria, each giving a signed mean and a positive amplitude:
//! - [`Criterion::SignedPrincipal`] (the default): the amplitude is the largest principal
//!   stress in magnitude of the alternating tensor, maximised over the phase of a harmonic
//!   response; the mean is the normal stress of the mean tensor on the plane of that principal
//!   stress (`nᵀ σ_m n`, the mean acting on the plane that cycles hardest). This is the normal
//!   stress criterion for bending-dominated parts (leaves, beams, plates), where cracks open on
//!   the plane of the largest normal stress; it is also what the hand calculation of a leaf
//!   (σ = M c / I) gives. Where the alternating tensor vanishes, the mean's signed principal is
//!   used.
//! - [`Criterion::SignedVonMises`]: the amplitude is the largest von Mises stress of the
//!   alternating tensor over the phase; the mean is the von Mises stress of the mean tensor with
//!   the sign of its hydrostatic stress (tr σ_m), so a compressive mean counts as compressive
//!   (Sines' observation that the hydrostatic part drives the mean-stress effect). Use it for
//!   multiaxial states without a dominant direction. It is never larger than the Tresca stress,
//!   and for a wide plate in bending it lies below the principal stress (ν couples the width):
//!   for leaves the signed principal is the safe choice.
//!
//! # Harmonic amplitudes
//! A harmonic response gives a complex stress Σ = A + iB; at phase φ the stress is
//! Re(Σ e^{iφ}) = A cos φ − B sin φ. The von Mises amplitude is exact: vm² is a quadratic form,
//! so its maximum over φ is the larger eigenvalue of the 2 × 2 matrix [[q(A), −b], [−b, q(B)]]
//! (q the form, b its bilinear form). The principal amplitude is sampled at 360 phases over the
//! half period and refined by golden-section search around the best sample (to 1e-12 of the
//! value). A static case scaled to an amplitude is the case B = 0.
//!
//! # Mean-stress correction
//! Each gives a safety factor along a proportional load line (σ_a/σ_m fixed: the alternating and
//! mean loads scaled together, FKM's overload case F2):
//! - Goodman: 1/n = σ_a/S_e + σ_m/R_m;
//! - Gerber: n σ_a/S_e + (n σ_m/R_m)² = 1;
//! - FKM: the Haigh diagram of the FKM guideline (FKM-Richtlinie "Rechnerischer
//!   Festigkeitsnachweis für Maschinenbauteile", 6th ed. 2012, §4.4 component strength, mean
//!   stress factor K_AK in four ranges of the stress ratio R) with the mean-stress sensitivity
//!   M_σ = a_M·10⁻³·R_m/MPa + b_M (a_M = 0.35, b_M = −0.1 for steel).
//!
//! Goodman and Gerber give no credit for a compressive mean (n = S_e/σ_a for σ_m ≤ 0, the
//! practice of Shigley's Mechanical Engineering Design, 9th ed., §6-12); FKM's range I/II does.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// One MPa in Pa.
const MPA: f64 = 1e6;

/// Fatigue data of a material (SI units, Pa), with where each number comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FatigueMaterial {
    /// Name (e.g. `60Si2Mn`).
    pub name: String,
    /// Tensile strength R_m (Pa).
    pub r_m: f64,
    /// Yield strength R_e (R_p0.2) (Pa).
    pub r_e: f64,
    /// Fully reversed normal-stress endurance limit σ_W at the knee, polished specimen (Pa).
    pub sigma_w: f64,
    /// Fully reversed torsional endurance limit τ_W (Pa).
    pub tau_w: f64,
    /// S–N slope k (Basquin exponent: N ∝ S^−k) below the knee.
    pub slope: f64,
    /// Knee cycles N_D: beyond it the endurance limit holds (horizontal S–N line).
    pub knee_cycles: f64,
    /// Where the numbers come from.
    pub source: String,
}

/// FKM factor f_W,σ: σ_W = f_W,σ·R_m for steels other than case-hardening, stainless and forging
/// steel (FKM-Richtlinie, 6th ed. 2012, §4.2 material properties).
pub const FKM_F_W_SIGMA: f64 = 0.45;
/// FKM factor f_W,τ = 1/√3 (von Mises) for steel: τ_W = f_W,τ·σ_W (same section).
pub const FKM_F_W_TAU: f64 = 0.577;
/// FKM S–N slope for normal stress, steel (k_σ = 5) and knee N_D,σ = 10⁶ (same edition, §4.4).
pub const FKM_SLOPE_SIGMA: f64 = 5.0;
/// Knee cycles of the FKM S–N line for steel.
pub const FKM_KNEE: f64 = 1e6;

impl FatigueMaterial {
    /// A material from its strengths with the FKM estimates for the rest: σ_W = 0.45 R_m,
    /// τ_W = 0.577 σ_W, k = 5, N_D = 10⁶ (FKM-Richtlinie, 6th ed. 2012, §4.2, §4.4).
    pub fn from_strengths(name: &str, r_m: f64, r_e: f64, source: &str) -> FatigueMaterial {
        let sigma_w = FKM_F_W_SIGMA * r_m;
        FatigueMaterial {
            name: name.into(),
            r_m,
            r_e,
            sigma_w,
            tau_w: FKM_F_W_TAU * sigma_w,
            slope: FKM_SLOPE_SIGMA,
            knee_cycles: FKM_KNEE,
            source: format!(
                "{source}; σ_W = {FKM_F_W_SIGMA}·R_m, τ_W = {FKM_F_W_TAU}·σ_W, k = {FKM_SLOPE_SIGMA}, N_D = 1e6 \
                 (FKM-Richtlinie, 6th ed. 2012, §4.2)"
            ),
        }
    }

    /// The built-in spring steels (names matched without case, `-` and spaces):
    /// - `60Si2Mn`: GB/T 1222-2007, quenched 870 °C oil, tempered 480 °C: R_m ≥ 1570 MPa,
    ///   R_eL ≥ 1375 MPa;
    /// - `65Mn`: GB/T 1222-2007, quenched 830 °C oil, tempered 540 °C: R_m ≥ 980 MPa,
    ///   R_eL ≥ 785 MPa;
    /// - `50CrVA`: GB/T 1222-2007, quenched 850 °C oil, tempered 500 °C: R_m ≥ 1275 MPa,
    ///   R_eL ≥ 1130 MPa;
    /// - `51CrMoV4`: Saarstahl data sheet 52CrMoV4 (51CrMoV4, 1.7701), hardened and tempered
    ///   16 mm flats: R_m 1400–1700 MPa (the minimum taken), R_p0.2 ≥ 1200 MPa.
    ///
    /// The endurance data are the FKM estimates of [`FatigueMaterial::from_strengths`] (minimum
    /// strengths: a conservative estimate).
    pub fn builtin(name: &str) -> Option<FatigueMaterial> {
        let key: String = name
            .chars()
            .filter(|c| !matches!(c, '-' | ' ' | '_'))
            .collect::<String>()
            .to_ascii_lowercase();
        let gb = "GB/T 1222-2007 (spring steels), minimum R_m and R_eL";
        let m = match key.as_str() {
            "60si2mn" | "60si2mna" | "60si2" => Self::from_strengths(
                "60Si2Mn",
                1570.0 * MPA,
                1375.0 * MPA,
                &format!("{gb}, quenched 870 °C oil, tempered 480 °C"),
            ),
            "65mn" => Self::from_strengths(
                "65Mn",
                980.0 * MPA,
                785.0 * MPA,
                &format!("{gb}, quenched 830 °C oil, tempered 540 °C"),
            ),
            "50crva" | "50crv" => Self::from_strengths(
                "50CrVA",
                1275.0 * MPA,
                1130.0 * MPA,
                &format!("{gb}, quenched 850 °C oil, tempered 500 °C"),
            ),
            "51crmov4" | "52crmov4" => Self::from_strengths(
                "51CrMoV4",
                1400.0 * MPA,
                1200.0 * MPA,
                "Saarstahl material sheet 52CrMoV4 (51CrMoV4, 1.7701), hardened and tempered, minimum R_m and R_p0.2",
            ),
            _ => return None,
        };
        Some(m)
    }

    /// Names of the built-in materials.
    pub const BUILTIN: [&'static str; 4] = ["60Si2Mn", "65Mn", "50CrVA", "51CrMoV4"];

    /// Reads `TEXT` as given on a command line or in a design file: a built-in name, a TOML
    /// file (`*.toml`, the fields of [`FatigueMaterial`] in Pa, `source` optional), or
    /// `rm=…,re=…[,sw=…,tw=…,k=…,nd=…]` in MPa (missing endurance data take the FKM estimates).
    /// `what` names the option or key in errors.
    pub fn parse(what: &str, text: &str) -> Result<FatigueMaterial> {
        let t = text.trim();
        if let Some(m) = Self::builtin(t) {
            return Ok(m);
        }
        #[cfg(feature = "app")]
        if t.ends_with(".toml") {
            return Self::from_toml_file(what, std::path::Path::new(t));
        }
        if t.contains('=') {
            return Self::from_pairs(what, t);
        }
        Err(Error::param(
            what,
            format!(
                "{what}: unknown fatigue material '{t}': give one of {} , a TOML file (*.toml) or \
                 rm=MPA,re=MPA[,sw=MPA,tw=MPA,k=SLOPE,nd=CYCLES]",
                Self::BUILTIN.join(", ")
            ),
        ))
    }

    fn from_pairs(what: &str, t: &str) -> Result<FatigueMaterial> {
        let mut v = std::collections::HashMap::new();
        for pair in t.split(',') {
            let (k, x) = pair
                .split_once('=')
                .ok_or_else(|| Error::param(what, format!("{what}: '{pair}' is not KEY=VALUE")))?;
            let k = k.trim().to_ascii_lowercase();
            if !["rm", "re", "sw", "tw", "k", "nd"].contains(&k.as_str()) {
                return Err(Error::param(
                    what,
                    format!("{what}: unknown key '{k}' (rm, re, sw, tw in MPa; k; nd)"),
                ));
            }
            let x: f64 = x
                .trim()
                .parse()
                .map_err(|_| Error::param(what, format!("{what}: {k} = '{}' is not a number", x.trim())))?;
            v.insert(k, x);
        }
        let (Some(&rm), Some(&re)) = (v.get("rm"), v.get("re")) else {
            return Err(Error::param(what, format!("{what}: give at least rm=MPA,re=MPA")));
        };
        let mut m = Self::from_strengths("user", rm * MPA, re * MPA, &format!("given on {what}"));
        if let Some(&sw) = v.get("sw") {
            m.sigma_w = sw * MPA;
            m.tau_w = FKM_F_W_TAU * m.sigma_w;
        }
        if let Some(&tw) = v.get("tw") {
            m.tau_w = tw * MPA;
        }
        if let Some(&k) = v.get("k") {
            m.slope = k;
        }
        if let Some(&nd) = v.get("nd") {
            m.knee_cycles = nd;
        }
        if v.len() > 2 {
            m.source = format!("given on {what} (missing values: FKM estimates)");
        }
        m.validate(what)?;
        Ok(m)
    }

    #[cfg(feature = "app")]
    /// Reads a TOML file with the fields of [`FatigueMaterial`] (Pa; `source` may be omitted).
    pub fn from_toml_file(what: &str, path: &std::path::Path) -> Result<FatigueMaterial> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct File {
            name: Option<String>,
            r_m: f64,
            r_e: f64,
            sigma_w: f64,
            tau_w: f64,
            slope: f64,
            knee_cycles: f64,
            source: Option<String>,
        }
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let f: File = toml::from_str(&text)
            .map_err(|e| Error::param(what, format!("{what}: {}: {}", path.display(), e.message())))?;
        let m = FatigueMaterial {
            name: f.name.unwrap_or_else(|| path.display().to_string()),
            r_m: f.r_m,
            r_e: f.r_e,
            sigma_w: f.sigma_w,
            tau_w: f.tau_w,
            slope: f.slope,
            knee_cycles: f.knee_cycles,
            source: f.source.unwrap_or_else(|| format!("file {}", path.display())),
        };
        m.validate(&format!("{what} ({})", path.display()))?;
        Ok(m)
    }

    /// Checks the data: strengths positive and ordered (σ_W < R_e ≤ R_m), slope > 1, knee ≥ 1.
    pub fn validate(&self, what: &str) -> Result<()> {
        let bad = |m: String| {
            Err(Error::param(
                what,
                format!("{what}: fatigue material '{}': {m}", self.name),
            ))
        };
        for (k, x) in [
            ("R_m", self.r_m),
            ("R_e", self.r_e),
            ("sigma_w", self.sigma_w),
            ("tau_w", self.tau_w),
        ] {
            if !(x.is_finite() && x > 0.0) {
                return bad(format!("{k} = {x} must be positive"));
            }
        }
        if self.r_e > self.r_m {
            return bad(format!("R_e = {} exceeds R_m = {}", self.r_e, self.r_m));
        }
        if self.sigma_w >= self.r_m {
            return bad(format!("sigma_w = {} must lie below R_m = {}", self.sigma_w, self.r_m));
        }
        if !(self.slope.is_finite() && self.slope > 1.0) {
            return bad(format!("slope k = {} must exceed 1", self.slope));
        }
        if !(self.knee_cycles.is_finite() && self.knee_cycles >= 1.0) {
            return bad(format!("knee_cycles = {} must be at least 1", self.knee_cycles));
        }
        Ok(())
    }

    /// FKM mean-stress sensitivity for normal stress, M_σ = a_M·10⁻³·R_m/MPa + b_M with
    /// a_M = 0.35, b_M = −0.1 (steel; FKM-Richtlinie, 6th ed. 2012, §4.4).
    pub fn mean_stress_sensitivity(&self) -> f64 {
        fkm_mean_stress_sensitivity(self.r_m, 0.35, -0.1)
    }
}

/// M_σ = a_M·10⁻³·R_m/MPa + b_M (FKM-Richtlinie, 6th ed. 2012, §4.4); R_m in Pa.
pub fn fkm_mean_stress_sensitivity(r_m: f64, a_m: f64, b_m: f64) -> f64 {
    a_m * 1e-3 * r_m / MPA + b_m
}

/// FKM roughness factor K_R,σ = 1 − a_R·lg(R_z/µm)·lg(2 R_m / R_m,N,min), a_R = 0.22 and
/// R_m,N,min = 400 MPa for steel (FKM-Richtlinie, 6th ed. 2012, §4.3 design parameters);
/// 1 for a polished surface (R_z ≤ 1 µm).
pub fn roughness_factor(rz_um: f64, r_m: f64) -> f64 {
    if rz_um <= 1.0 {
        return 1.0;
    }
    1.0 - 0.22 * rz_um.log10() * (2.0 * r_m / (400.0 * MPA)).log10()
}

/// Marin surface factor k_a = a·S_ut^b (S_ut in Pa, evaluated in MPa) for a finish `ground`,
/// `machined` (or cold-drawn), `hot-rolled` or `forged` (Budynas & Nisbett, Shigley's Mechanical
/// Engineering Design, 9th ed., §6-9, Table 6-2: a = 1.58, 4.51, 57.7, 272 MPa and
/// b = −0.085, −0.265, −0.718, −0.995).
pub fn marin_surface_factor(finish: &str, s_ut: f64) -> Result<f64> {
    let (a, b) = match finish {
        "ground" => (1.58, -0.085),
        "machined" | "cold-drawn" => (4.51, -0.265),
        "hot-rolled" => (57.7, -0.718),
        "forged" | "as-forged" => (272.0, -0.995),
        _ => {
            return Err(Error::param(
                "finish",
                format!("surface finish '{finish}': give ground, machined, cold-drawn, hot-rolled or forged"),
            ));
        }
    };
    Ok((a * (s_ut / MPA).powf(b)).min(1.0))
}

/// Size factor k_b for bending and torsion of a round section of diameter `d_mm` (Budynas &
/// Nisbett, Shigley's Mechanical Engineering Design, 9th ed., §6-9, Eq. (6-20)):
/// 1.24 d^−0.107 for 2.79 ≤ d ≤ 51 mm, 1.51 d^−0.157 for 51 < d ≤ 254 mm, 1 below 2.79 mm.
pub fn size_factor(d_mm: f64) -> f64 {
    if d_mm < 2.79 {
        1.0
    } else if d_mm <= 51.0 {
        1.24 * d_mm.powf(-0.107)
    } else {
        1.51 * d_mm.min(254.0).powf(-0.157)
    }
}

/// Equivalent diameter of a rectangular h × b section in non-rotating bending, d_e = 0.808 √(h b)
/// (Shigley, 9th ed., Table 6-3); same unit as h and b.
pub fn equivalent_diameter_rect(h: f64, b: f64) -> f64 {
    0.808 * (h * b).sqrt()
}

/// Reliability factor k_e (Shigley, 9th ed., Table 6-5, k_e = 1 − 0.08 z_a) for the tabulated
/// reliabilities 0.5, 0.9, 0.95, 0.99, 0.999, 0.9999, 0.99999, 0.999999.
pub fn reliability_factor(r: f64) -> Result<f64> {
    const TABLE: [(f64, f64); 8] = [
        (0.5, 1.000),
        (0.9, 0.897),
        (0.95, 0.868),
        (0.99, 0.814),
        (0.999, 0.753),
        (0.9999, 0.702),
        (0.99999, 0.659),
        (0.999999, 0.620),
    ];
    TABLE
        .iter()
        .find(|(p, _)| (p - r).abs() < 1e-12)
        .map(|x| x.1)
        .ok_or_else(|| {
            Error::param(
                "reliability",
                format!(
                    "reliability {r}: give one of 0.5, 0.9, 0.95, 0.99, 0.999, 0.9999, 0.99999, 0.999999 \
                     (Shigley, 9th ed., Table 6-5)"
                ),
            )
        })
}

/// The endurance limit of a part: the material's σ_W times the surface, size and reliability
/// factors, each with its source.
#[derive(Clone, Debug, Serialize)]
pub struct Endurance {
    /// The material's σ_W (Pa).
    pub material: f64,
    /// Surface factor K_R (FKM roughness).
    pub surface: f64,
    /// Size factor k_b.
    pub size: f64,
    /// Reliability factor k_e.
    pub reliability: f64,
    /// The corrected endurance limit S_e (Pa).
    pub value: f64,
    /// One line per factor: value, input and source.
    pub factors: Vec<String>,
}

/// Surface, size and reliability of a part for [`Endurance::new`].
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PartCondition {
    /// Surface roughness R_z (µm); ≤ 1 is polished.
    pub rz_um: f64,
    /// Equivalent diameter of the section (mm) for the size factor; `None`: no size effect.
    pub size_mm: Option<f64>,
    /// Reliability (0.5 … 0.999999, tabulated values).
    pub reliability: f64,
}

impl Endurance {
    /// S_e = σ_W · K_R · k_b · k_e for `m` and the part's condition `c`.
    pub fn new(m: &FatigueMaterial, c: &PartCondition) -> Result<Endurance> {
        if !(c.rz_um.is_finite() && c.rz_um >= 0.0) {
            return Err(Error::param(
                "rz",
                format!("surface roughness Rz = {} µm must be ≥ 0", c.rz_um),
            ));
        }
        let surface = roughness_factor(c.rz_um, m.r_m);
        let size = c.size_mm.map_or(1.0, size_factor);
        let reliability = reliability_factor(c.reliability)?;
        let factors = vec![
            format!(
                "surface K_R = {surface:.4} (Rz = {} µm, R_m = {:.0} MPa; FKM-Richtlinie 6th ed. 2012, §4.3: \
                 1 − 0.22·lg Rz·lg(2 R_m/400 MPa))",
                c.rz_um,
                m.r_m / MPA
            ),
            match c.size_mm {
                Some(d) => {
                    format!("size k_b = {size:.4} (equivalent diameter {d:.2} mm; Shigley's MED 9th ed., Eq. (6-20))")
                }
                None => "size k_b = 1 (not applied)".into(),
            },
            format!(
                "reliability k_e = {reliability:.3} ({} %; Shigley's MED 9th ed., Table 6-5)",
                c.reliability * 100.0
            ),
        ];
        Ok(Endurance {
            material: m.sigma_w,
            surface,
            size,
            reliability,
            value: m.sigma_w * surface * size * reliability,
            factors,
        })
    }
}

/// Basquin: the fully reversed strength at `cycles`, S_N = S_e (N_D/N)^(1/k) below the knee,
/// S_e at and beyond it.
pub fn finite_life_strength(se: f64, slope: f64, knee: f64, cycles: f64) -> f64 {
    if cycles >= knee {
        se
    } else {
        se * (knee / cycles.max(1.0)).powf(1.0 / slope)
    }
}

/// Basquin: cycles to failure at a fully reversed amplitude `s_ar`, N = N_D (S_e/s_ar)^k
/// (infinite at or below S_e).
pub fn cycles_to_failure(s_ar: f64, se: f64, slope: f64, knee: f64) -> f64 {
    if s_ar <= se {
        f64::INFINITY
    } else {
        knee * (se / s_ar).powf(slope)
    }
}

/// The mean-stress correction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MeanStress {
    /// Goodman line.
    Goodman,
    /// Gerber parabola.
    Gerber,
    /// FKM Haigh diagram with M_σ.
    Fkm,
}

impl MeanStress {
    /// `goodman`, `gerber` or `fkm`; `what` names the option or key in the error.
    pub fn parse(what: &str, s: &str) -> Result<MeanStress> {
        match s.trim().to_ascii_lowercase().as_str() {
            "goodman" => Ok(MeanStress::Goodman),
            "gerber" => Ok(MeanStress::Gerber),
            "fkm" | "haigh" => Ok(MeanStress::Fkm),
            _ => Err(Error::param(
                what,
                format!("{what}: mean-stress correction '{s}': give goodman, gerber or fkm"),
            )),
        }
    }

    /// The name used in output.
    pub fn name(self) -> &'static str {
        match self {
            MeanStress::Goodman => "goodman",
            MeanStress::Gerber => "gerber",
            MeanStress::Fkm => "fkm",
        }
    }
}

/// FKM mean-stress factor K_AK for sensitivity `m` at amplitude `sa` and mean `sm` (overload
/// case F2, constant stress ratio R = (sm − sa)/(sm + sa)), FKM-Richtlinie 6th ed. 2012, §4.4:
/// - range I (R > 1, sm < −sa): 1/(1 − M);
/// - range II (−∞ ≤ R ≤ 0): 1/(1 + M sm/sa);
/// - range III (0 < R < 0.5): (1 + M/3)/(1 + M) / (1 + (M/3) sm/sa);
/// - range IV (R ≥ 0.5, sm ≥ 3 sa): (3 + M)/(3 (1 + M)²).
pub fn fkm_k_ak(m: f64, sa: f64, sm: f64) -> f64 {
    if sa <= 0.0 {
        return (3.0 + m) / (3.0 * (1.0 + m).powi(2));
    }
    let r = sm / sa;
    if r < -1.0 {
        1.0 / (1.0 - m)
    } else if r <= 1.0 {
        1.0 / (1.0 + m * r)
    } else if r < 3.0 {
        (1.0 + m / 3.0) / (1.0 + m) / (1.0 + m / 3.0 * r)
    } else {
        (3.0 + m) / (3.0 * (1.0 + m).powi(2))
    }
}

/// The amplitude on the FKM Haigh line at mean `sm` for endurance `se` and sensitivity `m`
/// (the closed form of σ_a = K_AK(σ_a, σ_m)·S_e in each range of [`fkm_k_ak`]).
pub fn fkm_amplitude_at(m: f64, se: f64, sm: f64) -> f64 {
    if sm < -se / (1.0 - m) {
        se / (1.0 - m)
    } else if sm <= se / (1.0 + m) {
        se - m * sm
    } else {
        let sa3 = se * (1.0 + m / 3.0) / (1.0 + m) - m / 3.0 * sm;
        if sm < 3.0 * sa3 {
            sa3
        } else {
            se * (3.0 + m) / (3.0 * (1.0 + m).powi(2))
        }
    }
}

/// Safety factor along the proportional load line for amplitude `sa` ≥ 0 and mean `sm` (Pa),
/// endurance `se`, tensile strength `rm`, FKM sensitivity `m` (used by [`MeanStress::Fkm`]).
/// Infinite when nothing is loaded.
pub fn safety(ms: MeanStress, sa: f64, sm: f64, se: f64, rm: f64, m: f64) -> f64 {
    let sa = sa.abs();
    if sa == 0.0 && sm <= 0.0 {
        return f64::INFINITY;
    }
    match ms {
        MeanStress::Goodman if sm <= 0.0 => se / sa,
        MeanStress::Goodman => 1.0 / (sa / se + sm / rm),
        MeanStress::Gerber if sm <= 0.0 => se / sa,
        MeanStress::Gerber if sa == 0.0 => rm / sm,
        MeanStress::Gerber => {
            let q = 2.0 * sm * se / (rm * sa);
            0.5 * (rm / sm).powi(2) * (sa / se) * (-1.0 + (1.0 + q * q).sqrt())
        }
        MeanStress::Fkm if sa == 0.0 => f64::INFINITY,
        MeanStress::Fkm => fkm_k_ak(m, sa, sm) * se / sa,
    }
}

/// The fully reversed amplitude equivalent to (sa, sm) under the correction: the S_N at which
/// the point lies on the failure line (Goodman sa/(1 − sm/R_m), Gerber sa/(1 − (sm/R_m)²),
/// FKM sa/K_AK); infinite at or beyond R_m. Compressive means give sa for Goodman and Gerber.
pub fn equivalent_reversed(ms: MeanStress, sa: f64, sm: f64, rm: f64, m: f64) -> f64 {
    let sa = sa.abs();
    match ms {
        _ if sm >= rm => f64::INFINITY,
        MeanStress::Goodman | MeanStress::Gerber if sm <= 0.0 => sa,
        MeanStress::Goodman => sa / (1.0 - sm / rm),
        MeanStress::Gerber => sa / (1.0 - (sm / rm).powi(2)),
        MeanStress::Fkm => sa / fkm_k_ak(m, sa, sm),
    }
}

/// First-cycle yield (Langer): n_y = R_e / (|σ_a| + |σ_m|).
pub fn yield_safety(sa: f64, sm: f64, re: f64) -> f64 {
    re / (sa.abs() + sm.abs())
}

/// The equivalent-stress criterion (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// Largest-magnitude principal stress; mean on its plane.
    SignedPrincipal,
    /// von Mises; mean signed by the hydrostatic stress.
    SignedVonMises,
}

impl Criterion {
    /// `principal` or `von-mises`.
    pub fn parse(what: &str, s: &str) -> Result<Criterion> {
        match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "principal" | "signed-principal" => Ok(Criterion::SignedPrincipal),
            "von-mises" | "vonmises" | "signed-von-mises" | "mises" => Ok(Criterion::SignedVonMises),
            _ => Err(Error::param(
                what,
                format!("{what}: criterion '{s}': give principal or von-mises"),
            )),
        }
    }

    /// The name used in output.
    pub fn name(self) -> &'static str {
        match self {
            Criterion::SignedPrincipal => "signed principal",
            Criterion::SignedVonMises => "signed von Mises",
        }
    }
}

/// von Mises quadratic form's bilinear part b(a, b) (b(s, s) = vm(s)²).
fn vm_bilinear(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    let d = |s: &[f64; 6]| [s[0] - s[1], s[1] - s[2], s[2] - s[0]];
    let (da, db) = (d(a), d(b));
    0.5 * (da[0] * db[0] + da[1] * db[1] + da[2] * db[2]) + 3.0 * (a[3] * b[3] + a[4] * b[4] + a[5] * b[5])
}

/// Unit eigenvector of the symmetric tensor `s` (Voigt) for its eigenvalue `lam`.
fn eigenvector(s: &[f64; 6], lam: f64) -> [f64; 3] {
    let m = [
        [s[0] - lam, s[5], s[4]],
        [s[5], s[1] - lam, s[3]],
        [s[4], s[3], s[2] - lam],
    ];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let mut best = [1.0, 0.0, 0.0];
    let mut norm = 0.0;
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let c = cross(m[i], m[j]);
        let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        if n > norm {
            norm = n;
            best = c;
        }
    }
    if norm <= 1e-300 {
        // Repeated eigenvalue: any vector of its eigenspace; pick the axis of largest |diagonal|.
        let k = (0..3).max_by(|&a, &b| s[a].abs().total_cmp(&s[b].abs())).unwrap_or(0);
        let mut e = [0.0; 3];
        e[k] = 1.0;
        return e;
    }
    best.map(|x| x / norm)
}

/// The signed principal stress of largest magnitude of `s` and its direction.
pub fn signed_principal(s: &[f64; 6]) -> (f64, [f64; 3]) {
    let p = crate::post::stress::principal(s);
    let lam = if p[0].abs() >= p[2].abs() { p[0] } else { p[2] };
    (lam, eigenvector(s, lam))
}

/// Normal stress of `s` on the plane with unit normal `n`, nᵀ s n.
pub fn normal_stress(s: &[f64; 6], n: &[f64; 3]) -> f64 {
    s[0] * n[0] * n[0]
        + s[1] * n[1] * n[1]
        + s[2] * n[2] * n[2]
        + 2.0 * (s[3] * n[1] * n[2] + s[4] * n[0] * n[2] + s[5] * n[0] * n[1])
}

/// The alternating amplitude of a harmonic stress A + iB under the criterion, with the
/// principal direction at the worst phase (signed principal only).
#[derive(Clone, Copy, Debug)]
pub struct Amplitude {
    /// Amplitude (Pa, ≥ 0).
    pub value: f64,
    /// Unit normal of the plane of the alternating principal stress (signed principal only).
    pub direction: Option<[f64; 3]>,
}

/// The largest |principal| of A cos φ − B sin φ.
fn principal_at(re: &[f64; 6], im: &[f64; 6], phi: f64) -> f64 {
    let (c, s) = (phi.cos(), phi.sin());
    let t: [f64; 6] = std::array::from_fn(|i| re[i] * c - im[i] * s);
    let p = crate::post::stress::principal(&t);
    p[0].abs().max(p[2].abs())
}

/// Alternating amplitude of the harmonic stress `re + i·im` (the module docs give the method).
pub fn alternating(crit: Criterion, re: &[f64; 6], im: &[f64; 6]) -> Amplitude {
    match crit {
        Criterion::SignedVonMises => {
            let (qa, qb, b) = (vm_bilinear(re, re), vm_bilinear(im, im), vm_bilinear(re, im));
            let lam = 0.5 * (qa + qb) + (0.25 * (qa - qb).powi(2) + b * b).sqrt();
            Amplitude {
                value: lam.max(0.0).sqrt(),
                direction: None,
            }
        }
        Criterion::SignedPrincipal => {
            const N: usize = 360;
            let h = std::f64::consts::PI / N as f64;
            let mut best = (0.0, principal_at(re, im, 0.0));
            if im.iter().any(|&x| x != 0.0) {
                for k in 1..N {
                    let v = principal_at(re, im, k as f64 * h);
                    if v > best.1 {
                        best = (k as f64 * h, v);
                    }
                }
                // Golden-section refinement on [φ − h, φ + h].
                let g = 0.5 * (5f64.sqrt() - 1.0);
                let (mut a, mut b) = (best.0 - h, best.0 + h);
                for _ in 0..60 {
                    let (x1, x2) = (b - g * (b - a), a + g * (b - a));
                    if principal_at(re, im, x1) > principal_at(re, im, x2) {
                        b = x2;
                    } else {
                        a = x1;
                    }
                }
                let phi = 0.5 * (a + b);
                let v = principal_at(re, im, phi);
                if v > best.1 {
                    best = (phi, v);
                }
            }
            let (c, s) = (best.0.cos(), best.0.sin());
            let t: [f64; 6] = std::array::from_fn(|i| re[i] * c - im[i] * s);
            let (lam, n) = signed_principal(&t);
            Amplitude {
                value: lam.abs(),
                direction: Some(n),
            }
        }
    }
}

/// The signed mean equivalent stress of `mean` for the amplitude `alt` (module docs).
pub fn mean_equivalent(crit: Criterion, mean: &[f64; 6], alt: &Amplitude) -> f64 {
    match crit {
        Criterion::SignedVonMises => {
            let vm = crate::post::stress::von_mises(mean);
            let tr = mean[0] + mean[1] + mean[2];
            if tr < 0.0 { -vm } else { vm }
        }
        Criterion::SignedPrincipal => match alt.direction {
            Some(n) if alt.value > 0.0 => normal_stress(mean, &n),
            _ => signed_principal(mean).0,
        },
    }
}

/// What an assessment needs besides the stresses.
#[derive(Clone, Debug, Serialize)]
pub struct FatigueSettings {
    /// The material.
    pub material: FatigueMaterial,
    /// Surface, size, reliability.
    pub condition: PartCondition,
    /// Equivalent-stress criterion.
    pub criterion: Criterion,
    /// Mean-stress correction.
    pub mean_stress: MeanStress,
    /// Cycles the part must survive (the endurance is the Basquin strength there).
    pub cycles: f64,
}

/// Per-node result of [`assess`] (arrays indexed by dense node index).
#[derive(Clone, Debug, Serialize)]
pub struct FatigueField {
    /// Alternating equivalent stress σ_a (Pa).
    pub sigma_a: Vec<f64>,
    /// Mean equivalent stress σ_m (Pa, signed).
    pub sigma_m: Vec<f64>,
    /// Safety factor against fatigue at the given cycles (infinite where unloaded).
    pub safety: Vec<f64>,
    /// Basquin cycles to failure (infinite below the endurance).
    pub life: Vec<f64>,
    /// First-cycle yield safety R_e/(|σ_a| + |σ_m|).
    pub yield_safety: Vec<f64>,
    /// The corrected endurance limit at the knee.
    pub endurance: Endurance,
    /// The strength used: Basquin at the given cycles (Pa).
    pub strength: f64,
    /// FKM mean-stress sensitivity M_σ.
    pub m_sigma: f64,
}

/// The fatigue field from a mean tensor per node and an alternating harmonic tensor per node
/// (`alt_re`, `alt_im`, Voigt order, Pa; `alt_im` all zero for a scaled static case). Nodes with
/// `active[a] == false` (no solid element) get infinite safety.
pub fn assess(
    s: &FatigueSettings,
    mean: &[[f64; 6]],
    alt_re: &[[f64; 6]],
    alt_im: &[[f64; 6]],
    active: &[bool],
) -> Result<FatigueField> {
    let n = mean.len();
    if alt_re.len() != n || alt_im.len() != n || active.len() != n {
        return Err(Error::param(
            "fatigue",
            format!(
                "fatigue: {} mean, {} + {} alternating tensors and {} flags: one each per node",
                n,
                alt_re.len(),
                alt_im.len(),
                active.len()
            ),
        ));
    }
    if !(s.cycles.is_finite() && s.cycles >= 1.0) {
        return Err(Error::param(
            "cycles",
            format!("cycles = {} must be at least 1", s.cycles),
        ));
    }
    s.material.validate("fatigue material")?;
    let endurance = Endurance::new(&s.material, &s.condition)?;
    let m = &s.material;
    let strength = finite_life_strength(endurance.value, m.slope, m.knee_cycles, s.cycles);
    let m_sigma = m.mean_stress_sensitivity();
    let mut f = FatigueField {
        sigma_a: vec![0.0; n],
        sigma_m: vec![0.0; n],
        safety: vec![f64::INFINITY; n],
        life: vec![f64::INFINITY; n],
        yield_safety: vec![f64::INFINITY; n],
        endurance,
        strength,
        m_sigma,
    };
    for a in (0..n).filter(|&a| active[a]) {
        let amp = alternating(s.criterion, &alt_re[a], &alt_im[a]);
        let sm = mean_equivalent(s.criterion, &mean[a], &amp);
        f.sigma_a[a] = amp.value;
        f.sigma_m[a] = sm;
        f.safety[a] = safety(s.mean_stress, amp.value, sm, strength, m.r_m, m_sigma);
        let s_ar = equivalent_reversed(s.mean_stress, amp.value, sm, m.r_m, m_sigma);
        f.life[a] = cycles_to_failure(s_ar, f.endurance.value, m.slope, m.knee_cycles);
        f.yield_safety[a] = yield_safety(amp.value, sm, m.r_e);
    }
    Ok(f)
}

/// One row of the hot-spot table.
#[derive(Clone, Debug, Serialize)]
pub struct HotSpot {
    /// Node tag.
    pub node: u64,
    /// The first physical group holding the node (highest dimension first), or `""`.
    pub group: String,
    /// Coordinates (m).
    pub coords: [f64; 3],
    /// σ_a (Pa).
    pub sigma_a: f64,
    /// σ_m (Pa).
    pub sigma_m: f64,
    /// Safety factor.
    pub safety: f64,
    /// Basquin cycles to failure (`null` in JSON when infinite).
    pub life: Option<f64>,
}

/// The `n` nodes of lowest safety, ascending, among those with finite safety.
pub fn hot_spots(mesh: &crate::mesh::Mesh, f: &FatigueField, n: usize) -> Vec<HotSpot> {
    let mut idx: Vec<usize> = (0..f.safety.len()).filter(|&a| f.safety[a].is_finite()).collect();
    idx.sort_by(|&a, &b| f.safety[a].total_cmp(&f.safety[b]).then(a.cmp(&b)));
    idx.truncate(n);
    let mut groups: Vec<&crate::mesh::Group> = mesh.groups.iter().collect();
    groups.sort_by_key(|g| std::cmp::Reverse(g.dim));
    let group_of = |a: usize| -> String {
        groups
            .iter()
            .find(|g| mesh.group_nodes(g).binary_search(&(a as u32)).is_ok())
            .map_or(String::new(), |g| g.name.clone())
    };
    idx.into_iter()
        .map(|a| HotSpot {
            node: mesh.node_tags.get(a).copied().unwrap_or(a as u64 + 1),
            group: group_of(a),
            coords: mesh.nodes[a],
            sigma_a: f.sigma_a[a],
            sigma_m: f.sigma_m[a],
            safety: f.safety[a],
            life: f.life[a].is_finite().then_some(f.life[a]),
        })
        .collect()
}

/// A Haigh diagram (SVG text): the Goodman line, the Gerber parabola and the FKM diagram for
/// the strength `se` (Pa) of `m`, the first-cycle yield line σ_a + |σ_m| = R_e, and the points
/// (σ_m, σ_a) of `spots` (MPa on the axes).
pub fn haigh_svg(m: &FatigueMaterial, se: f64, spots: &[HotSpot]) -> String {
    let (w, h, pad) = (640.0, 420.0, 50.0);
    let (rm, re) = (m.r_m / MPA, m.r_e / MPA);
    let se = se / MPA;
    let x0 = -re;
    let (xr, yr) = (
        rm - x0,
        (se * 1.25).max(spots.iter().map(|s| s.sigma_a / MPA).fold(0.0, f64::max) * 1.1),
    );
    let px = |x: f64| pad + (x - x0) / xr * (w - 2.0 * pad);
    let py = |y: f64| h - pad - y / yr * (h - 2.0 * pad);
    let poly = |pts: Vec<(f64, f64)>, colour: &str, dash: &str| -> String {
        let d: Vec<String> = pts
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", px(x), py(y.max(0.0))))
            .collect();
        format!(
            "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\" {dash} points=\"{}\"/>\n",
            d.join(" ")
        )
    };
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"18\" text-anchor=\"middle\" font-size=\"13\">Haigh diagram: {} (S_e = {se:.0} MPa, R_m = {rm:.0} MPa)</text>\n",
        w / 2.0,
        m.name
    );
    s += &format!(
        "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n",
        px(x0),
        py(0.0),
        px(rm),
        py(0.0),
        px(0.0),
        py(0.0),
        px(0.0),
        py(yr)
    );
    s += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">mean stress σ_m [MPa]</text>\n<text x=\"14\" y=\"{}\" transform=\"rotate(-90 14 {})\" text-anchor=\"middle\">amplitude σ_a [MPa]</text>\n",
        w / 2.0,
        h - 12.0,
        h / 2.0,
        h / 2.0
    );
    for v in [x0, 0.0, rm / 2.0, rm] {
        s += &format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{v:.0}</text>\n",
            px(v),
            py(0.0) + 14.0
        );
    }
    s += &format!(
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{se:.0}</text>\n",
        px(0.0) - 4.0,
        py(se) + 4.0
    );
    let n = 100;
    let xs = |a: f64, b: f64| (0..=n).map(move |i| a + (b - a) * i as f64 / n as f64);
    s += &poly(vec![(0.0, se), (rm, 0.0)], "#1f77b4", "");
    s += &poly(
        xs(0.0, rm).map(|x| (x, se * (1.0 - (x / rm).powi(2)))).collect(),
        "#2ca02c",
        "",
    );
    let msig = m.mean_stress_sensitivity();
    let fkm: Vec<(f64, f64)> = xs(x0, rm).map(|x| (x, fkm_amplitude_at(msig, se, x))).collect();
    s += &poly(fkm, "#d62728", "");
    s += &poly(
        vec![(-re, 0.0), (0.0, re.min(yr)), (re, 0.0)],
        "#7f7f7f",
        "stroke-dasharray=\"5,4\"",
    );
    for (i, (name, c)) in [
        ("Goodman", "#1f77b4"),
        ("Gerber", "#2ca02c"),
        ("FKM (M_σ)", "#d62728"),
        ("yield σ_a + |σ_m| = R_e", "#7f7f7f"),
    ]
    .iter()
    .enumerate()
    {
        let y = 40.0 + 15.0 * i as f64;
        s += &format!(
            "<line x1=\"{}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"{c}\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">{name}</text>\n",
            w - 200.0,
            w - 180.0,
            w - 175.0,
            y + 4.0
        );
    }
    for (i, p) in spots.iter().enumerate() {
        s += &format!(
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3.5\" fill=\"black\"><title>node {} ({}) σ_m {:.1} MPa, σ_a {:.1} MPa, safety {:.3}</title></circle>\n",
            px(p.sigma_m / MPA),
            py(p.sigma_a / MPA),
            p.node,
            p.group,
            p.sigma_m / MPA,
            p.sigma_a / MPA,
            p.safety
        );
        if i == 0 {
            s += &format!(
                "<text x=\"{:.1}\" y=\"{:.1}\">node {}: n = {:.2}</text>\n",
                px(p.sigma_m / MPA) + 6.0,
                py(p.sigma_a / MPA) - 6.0,
                p.node,
                p.safety
            );
        }
    }
    s + "</svg>\n"
}
