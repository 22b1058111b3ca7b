//! Linear isotropic elastic materials.
//!
//! A [`Material`] holds Young's modulus `E` (Pa), Poisson's ratio `ν` and density `ρ` (kg/m³).
//! Stresses and strains use Voigt notation in the order
//!
//! | index | 0 | 1 | 2 | 3 | 4 | 5 |
//! |---|---|---|---|---|---|---|
//! | stress | σ_xx | σ_yy | σ_zz | σ_yz | σ_xz | σ_xy |
//! | strain | ε_xx | ε_yy | ε_zz | γ_yz = 2ε_yz | γ_xz = 2ε_xz | γ_xy = 2ε_xy |
//!
//! with engineering shear strains, so that `σ = D ε` and the strain energy density is
//! `½ εᵀ D ε` (the order of Abaqus/CalculiX is `xx, yy, zz, xy, xz, yz`: writers permute).

use crate::error::{Error, Result};

/// A linear isotropic elastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Young's modulus `E` (Pa), positive.
    pub young: f64,
    /// Poisson's ratio `ν`, in the open interval (−1, 0.5).
    pub poisson: f64,
    /// Mass density `ρ` (kg/m³), positive.
    pub density: f64,
}

/// The range of a Young's modulus or a density [`Material::validate`] accepts (Pa, kg/m³, or
/// any consistent unit system): 30 orders of magnitude either side of 1, where K, M and their
/// products stay far inside double precision.
pub const MATERIAL_RANGE: (f64, f64) = (1e-30, 1e30);

impl Material {
    /// Structural steel: `E = 2.1e11` Pa, `ν = 0.3`, `ρ = 7850` kg/m³.
    pub const fn steel() -> Material {
        Material {
            young: 2.1e11,
            poisson: 0.3,
            density: 7850.0,
        }
    }

    /// Checks the constants: `E` and `ρ` positive, within [`MATERIAL_RANGE`], `ν ∈ (−1, 0.5)`.
    ///
    /// `name` (the material key or the group it is assigned to) is put into the error, which
    /// is an [`Error::InvalidMaterial`] naming the offending value and its allowed range.
    ///
    /// ```
    /// use vibrofem::material::Material;
    /// let bad = Material { poisson: 0.5, ..Material::steel() };
    /// let msg = bad.validate("rubber").unwrap_err().to_string();
    /// assert!(msg.contains("rubber") && msg.contains("0.5"));
    /// ```
    pub fn validate(&self, name: &str) -> Result<()> {
        match self.invalid() {
            Some((_, msg)) => Err(Error::InvalidMaterial {
                name: name.to_string(),
                msg,
            }),
            None => Ok(()),
        }
    }

    /// The first constant [`Material::validate`] refuses (`"young"`, `"poisson"` or
    /// `"density"`) and why; `None` when all three are valid. For a file, the key to name.
    pub fn invalid(&self) -> Option<(&'static str, String)> {
        if !(self.young.is_finite() && self.young > 0.0) {
            return Some((
                "young",
                format!("Young's modulus E = {} Pa: must be positive and finite", self.young),
            ));
        }
        // Beyond any material in any consistent unit system (steel is 2.1e11 Pa, or 2.1e5 in
        // N/mm²): a slip whose products overflow double precision in K or its residuals.
        let (lo, hi) = MATERIAL_RANGE;
        if !(lo..=hi).contains(&self.young) {
            return Some((
                "young",
                format!(
                    "Young's modulus E = {:e} Pa: outside {lo:e}…{hi:e}, a unit slip (steel is 2.1e11 Pa)",
                    self.young
                ),
            ));
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return Some((
                "poisson",
                format!(
                    "Poisson's ratio nu = {}: must lie in the open interval (-1, 0.5)",
                    self.poisson
                ),
            ));
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return Some((
                "density",
                format!("density rho = {} kg/m^3: must be positive and finite", self.density),
            ));
        }
        if !(lo..=hi).contains(&self.density) {
            return Some((
                "density",
                format!(
                    "density rho = {:e} kg/m^3: outside {lo:e}…{hi:e}, a unit slip (steel is 7850 kg/m^3)",
                    self.density
                ),
            ));
        }
        None
    }

    /// Parses `"steel"` (any case) or `"E,NU,RHO"`, e.g. `"2.1e11,0.3,7850"` (spaces around
    /// the commas allowed), and validates the result. Errors are [`Error::InvalidMaterial`]
    /// named after the input text.
    ///
    /// ```
    /// use vibrofem::material::Material;
    /// assert_eq!(Material::parse("2.1e11, 0.3, 7850").unwrap(), Material::steel());
    /// assert!(Material::parse("2.1e11,0.3").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<Material> {
        let text = s.trim();
        let fail = |msg: String| Error::InvalidMaterial {
            name: format!("'{text}'"),
            msg,
        };
        if text.eq_ignore_ascii_case("steel") {
            return Ok(Material::steel());
        }
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != 3 {
            return Err(fail(format!(
                "expected 'steel' or three comma-separated numbers E,NU,RHO \
                 (e.g. '2.1e11,0.3,7850'), got {} field{}",
                fields.len(),
                if fields.len() == 1 { "" } else { "s" }
            )));
        }
        let mut v = [0.0; 3];
        for (k, (field, what)) in fields
            .iter()
            .zip(["Young's modulus E", "Poisson's ratio NU", "density RHO"])
            .enumerate()
        {
            v[k] = field
                .parse::<f64>()
                .map_err(|_| fail(format!("{what}: '{field}' is not a number")))?;
        }
        let m = Material {
            young: v[0],
            poisson: v[1],
            density: v[2],
        };
        m.validate(&format!("'{text}'"))?;
        Ok(m)
    }

    /// Lamé constants `(λ, μ)`: `λ = E ν / ((1 + ν)(1 − 2ν))`, `μ = G = E / (2 (1 + ν))`.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
    }

    /// Shear modulus `G = μ = E / (2 (1 + ν))`.
    pub fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// Bulk modulus `K = E / (3 (1 − 2ν))`.
    pub fn bulk_modulus(&self) -> f64 {
        self.young / (3.0 * (1.0 - 2.0 * self.poisson))
    }

    /// The 3D elasticity matrix `D` with `σ = D ε` in the Voigt order of the module docs
    /// (`xx, yy, zz, yz, xz, xy`, engineering shear strains):
    ///
    /// ```text
    /// | λ+2μ  λ     λ     0  0  0 |
    /// | λ     λ+2μ  λ     0  0  0 |
    /// | λ     λ     λ+2μ  0  0  0 |
    /// | 0     0     0     μ  0  0 |
    /// | 0     0     0     0  μ  0 |
    /// | 0     0     0     0  0  μ |
    /// ```
    pub fn d_matrix(&self) -> [[f64; 6]; 6] {
        let (lam, mu) = self.lame();
        let mut d = [[0.0; 6]; 6];
        for i in 0..3 {
            d[i][..3].fill(lam);
            d[i][i] = lam + 2.0 * mu;
            d[i + 3][i + 3] = mu;
        }
        d
    }

    /// Stress from strain, `σ = D ε`, both in Voigt order, without forming `D`.
    pub fn stress(&self, strain: &[f64; 6]) -> [f64; 6] {
        let (lam, mu) = self.lame();
        let p = lam * (strain[0] + strain[1] + strain[2]);
        [
            p + 2.0 * mu * strain[0],
            p + 2.0 * mu * strain[1],
            p + 2.0 * mu * strain[2],
            mu * strain[3],
            mu * strain[4],
            mu * strain[5],
        ]
    }
}

impl std::str::FromStr for Material {
    type Err = Error;
    fn from_str(s: &str) -> Result<Material> {
        Material::parse(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_validate_messages() {
        assert_eq!(Material::parse(" Steel ").unwrap(), Material::steel());
        let m = Material::parse("7e10,0.33,2700").unwrap();
        assert_eq!(
            m,
            Material {
                young: 7e10,
                poisson: 0.33,
                density: 2700.0
            }
        );
        let e = Material::parse("7e10,abc,2700").unwrap_err().to_string();
        assert!(e.contains("Poisson") && e.contains("'abc'"), "{e}");
        let e = Material::parse("-1,0.3,1").unwrap_err().to_string();
        assert!(e.contains("Young") && e.contains("-1"), "{e}");
        let e = Material::parse("1,0.3,0").unwrap_err().to_string();
        assert!(e.contains("density") && e.contains("positive"), "{e}");
        let e = Material::parse("1,-1,1").unwrap_err().to_string();
        assert!(e.contains("(-1, 0.5)"), "{e}");
        let e = Material {
            young: f64::NAN,
            ..Material::steel()
        }
        .validate("g")
        .unwrap_err();
        assert!(matches!(e, Error::InvalidMaterial { ref name, .. } if name == "g"));
        assert!(Material::parse("").is_err());
        assert!(Material::parse("1,0.3,1,4").is_err());
    }

    #[test]
    fn d_matches_stress() {
        let m = Material::steel();
        let d = m.d_matrix();
        let eps = [1e-3, -2e-4, 5e-4, 3e-4, -1e-4, 2e-4];
        let s = m.stress(&eps);
        for i in 0..6 {
            let di: f64 = (0..6).map(|j| d[i][j] * eps[j]).sum();
            assert!((di - s[i]).abs() <= 1e-12 * s[i].abs().max(1e6));
        }
        // Uniaxial stress: σ_xx = E ε_xx when ε_yy = ε_zz = −ν ε_xx.
        let s = m.stress(&[1e-3, -0.3e-3, -0.3e-3, 0.0, 0.0, 0.0]);
        assert!((s[0] - 2.1e8).abs() < 1e-3 && s[1].abs() < 1e-3);
    }
}
