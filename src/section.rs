//! Cross-section properties of beams ([`BeamSection`]) and shells ([`ShellSection`]).
//!
//! # Beam section axes
//!
//! A beam's local axes are `x` along the element (node 0 → node 1), `y` from the element's
//! orientation vector (made orthogonal to `x`) and `z = x × y` (see [`crate::element::beam`]).
//! Section properties are about the centroid and refer to these axes, which must be principal
//! axes of the section:
//!
//! | field | meaning | bending it governs |
//! |---|---|---|
//! | `iy` = `∫ z² dA` | second moment about `y` | deflection `w` along `z` (rotation `θy`) |
//! | `iz` = `∫ y² dA` | second moment about `z` | deflection `v` along `y` (rotation `θz`) |
//! | `ky`, `kz` | shear factors: shear areas `ky A`, `kz A` | shear force along `y`, along `z` |
//!
//! The library shapes put the depth `h` along local `z` and the width (flange width) `b`
//! along local `y`, so an I-beam's strong axis is `y` (`iy` is the table's `I_x`) and its
//! orientation vector points along the flanges.
//!
//! ```text
//!  I / double-T (h, b, s, t)          channel (h, b, s, t)
//!
//!        z                               z
//!        ^                               ^
//!   +----|----+  ---                  +--|------+  ---
//!   +--+ | +--+  t                    |  |  +---+   t
//!      | | |                          |  |  |
//!      | +-|------> y            S  o | C+--|------> y     S: shear centre (ey < 0)
//!      |   |                          |     |              C: centroid
//!   +--+   +--+                       |  +--+
//!   +---------+                       +-----+
//!   |<-- b -->|  web thickness s      |<-b->|  web thickness s
//! ```
//!
//! Shear factors come from Cowper (1966), "The shear coefficient in Timoshenko's beam
//! theory", J. Appl. Mech. 33, 335–340, Table 1, evaluated at `ν = 0.3` ([`COWPER_POISSON`],
//! steel). They vary by about 1 % over ν ∈ [0.25, 0.35], far below the uncertainty of the
//! shear correction itself; [`BeamSection::with_shear_factors`] overrides them.
//!
//! The thin-walled formulas (torsion constant, warping constant, shear centre) are those of
//! Pilkey, *Formulas for Stress, Strain, and Structural Matrices* (2nd ed., 2005), §2.9–2.11 and
//! Table 2-5, and Roark's *Formulas for Stress and Strain* (7th ed.), Tables 10.1 and 10.7.
//! Fillets and flange slopes of rolled sections are ignored; the section-library tests quantify
//! what that costs against the GOST tables.

use crate::error::{Error, Result};

/// Poisson's ratio at which the library shapes evaluate Cowper's shear factors (steel).
pub const COWPER_POISSON: f64 = 0.3;

/// Cross-section of a beam: centroidal principal properties, shear factors, torsion and
/// warping constants, and the shear-centre offset.
///
/// All values are SI (m², m⁴, m⁶, m). Build one with a shape constructor
/// ([`rectangle`](Self::rectangle), [`circle`](Self::circle), [`tube`](Self::tube),
/// [`i_beam`](Self::i_beam), [`channel`](Self::channel), the GOST presets) or
/// [`custom`](Self::custom), then check it with [`validate`](Self::validate).
///
/// ```
/// use vibrofem::section::BeamSection;
/// let s = BeamSection::rectangle(0.02, 0.04);
/// assert!((s.iy - 0.02 * 0.04f64.powi(3) / 12.0).abs() < 1e-20);
/// assert_eq!(vibrofem::element::beam::dofs_per_node(&s), 6);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamSection {
    /// Area `A` (m²).
    pub area: f64,
    /// Second moment about local `y`, `Iy = ∫ z² dA` (m⁴).
    pub iy: f64,
    /// Second moment about local `z`, `Iz = ∫ y² dA` (m⁴).
    pub iz: f64,
    /// Saint-Venant torsion constant `J` (m⁴).
    pub j: f64,
    /// Shear factor for shear along local `y` (shear area `ky A`), in (0, 1].
    pub ky: f64,
    /// Shear factor for shear along local `z` (shear area `kz A`), in (0, 1].
    pub kz: f64,
    /// Warping constant `Cw` (sectorial moment of inertia about the shear centre, m⁶).
    pub cw: f64,
    /// Shear-centre position relative to the centroid, `[ey, ez]` in local `(y, z)` (m).
    /// Zero for doubly symmetric sections.
    pub shear_centre: [f64; 2],
    /// Request the warping degree of freedom (7 per node, Vlasov torsion with `E Cw`); see
    /// [`crate::element::beam`]. Off by default; [`with_warping`](Self::with_warping) sets it.
    pub warping: bool,
    /// Where the section's extreme fibres are, for the normal stress of its resultants
    /// ([`BeamSection::extreme_normal_stress`]); [`Fibres::Unknown`] for custom properties.
    pub fibres: Fibres,
}

/// The extreme fibres of a beam section, relative to the centroid in local `(y, z)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fibres {
    /// The vertices of the section's convex hull, where a stress linear over the section is
    /// largest and smallest (a rectangle's, an I-section's flange tips, a channel's corners).
    Corners([[f64; 2]; 4]),
    /// A circle or tube of this outer radius about the centroid.
    Round(f64),
    /// Not known (a section given by its properties).
    Unknown,
}

/// Cowper's shear factor of a solid rectangle, `10(1+ν)/(12+11ν)`.
fn cowper_rectangle(nu: f64) -> f64 {
    10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
}

/// Cowper's shear factor of a hollow circle with radius ratio `m = r_i/r_o`:
/// `6(1+ν)(1+m²)² / [(7+6ν)(1+m²)² + (20+12ν)m²]` (the solid circle at `m = 0`).
fn cowper_tube(nu: f64, m: f64) -> f64 {
    let q = (1.0 + m * m).powi(2);
    6.0 * (1.0 + nu) * q / ((7.0 + 6.0 * nu) * q + (20.0 + 12.0 * nu) * m * m)
}

/// Cowper's shear factor of a thin-walled I-section for shear along the web:
/// `10(1+ν)(1+3m)² / [12+72m+150m²+90m³ + ν(11+66m+135m²+90m³) + 30n²(m+m²) + 5νn²(8m+9m²)]`
/// with `m = 2 b t_f / (h_f t_w)`, `n = b / h_f`, `h_f` the distance between flange centroids.
fn cowper_i_web(nu: f64, b: f64, tf: f64, hf: f64, tw: f64) -> f64 {
    let m = 2.0 * b * tf / (hf * tw);
    let n = b / hf;
    let (m2, m3, n2) = (m * m, m * m * m, n * n);
    let den = 12.0
        + 72.0 * m
        + 150.0 * m2
        + 90.0 * m3
        + nu * (11.0 + 66.0 * m + 135.0 * m2 + 90.0 * m3)
        + 30.0 * n2 * (m + m2)
        + 5.0 * nu * n2 * (8.0 * m + 9.0 * m2);
    10.0 * (1.0 + nu) * (1.0 + 3.0 * m).powi(2) / den
}

/// Web-direction shear factor of a thin-walled open section with a web of height `hf`
/// (between flange centrelines) and thickness `tw`, and `nseg` flange segments of length
/// `l` and thickness `tf` attached at the web ends (half of them at each end: 4 half-flanges
/// of an I, 2 flanges of a channel), by the energy definition
/// `1/(k A) = (1/I²) ∫ Q(s)²/t(s) ds` with the thin-walled shear flow (Pilkey §2.8). All
/// quantities are centreline values.
fn energy_web_shear_factor(hf: f64, tw: f64, nseg: f64, l: f64, tf: f64) -> f64 {
    let a = 0.5 * hf;
    let area = nseg * l * tf + hf * tw;
    let inertia = tw * hf.powi(3) / 12.0 + nseg * l * tf * a * a;
    // Flanges: Q = tf ζ a from each tip, ∫₀ˡ Q²/tf dζ = tf a² l³/3 per segment.
    let flanges = nseg * tf * a * a * l.powi(3) / 3.0;
    // Web: Q(η) = Qf + tw (a² − η²)/2 with Qf the first moment of the flanges at one end.
    let qf = 0.5 * nseg * l * tf * a;
    let web = 2.0 * a * qf * qf / tw + 4.0 / 3.0 * qf * a.powi(3) + 4.0 / 15.0 * tw * a.powi(5);
    inertia * inertia / (area * (flanges + web))
}

/// Saint-Venant torsion constant of a thin rectangle `a × c` (`a` the long side) with
/// `n_free` free short ends, `(a c³/3)(1 − 0.315 n_free c/a)`: Roark Table 10.7 case 4 gives
/// `a c³ (1/3 − 0.21 c/a)` for both ends free, i.e. `0.105 c⁴` lost per free end. Ends joined
/// to another wall lose nothing (the junction gain of El Darwish and Johnston is ignored).
/// The corners of a `b × h` box about its centre (a rectangle's, an I-section's flange tips).
fn box_corners(b: f64, h: f64) -> Fibres {
    let (y, z) = (0.5 * b, 0.5 * h);
    Fibres::Corners([[-y, -z], [y, -z], [y, z], [-y, z]])
}

fn thin_rect_j(a: f64, c: f64, n_free: f64) -> f64 {
    a * c.powi(3) / 3.0 * (1.0 - 0.315 * n_free * c / a)
}

impl BeamSection {
    /// Custom properties: area `A`, principal second moments `Iy`, `Iz`, torsion constant
    /// `J`, shear factors `ky`, `kz` and warping constant `Cw`; shear centre at the centroid,
    /// no warping DOF.
    pub fn custom(area: f64, iy: f64, iz: f64, j: f64, ky: f64, kz: f64, cw: f64) -> BeamSection {
        BeamSection {
            area,
            iy,
            iz,
            j,
            ky,
            kz,
            cw,
            shear_centre: [0.0, 0.0],
            warping: false,
            fibres: Fibres::Unknown,
        }
    }

    /// The same section with its extreme fibres ([`Fibres`]).
    pub fn with_fibres(self, fibres: Fibres) -> BeamSection {
        BeamSection { fibres, ..self }
    }

    /// The largest magnitude of the normal stress `σ = N/A + M_y z/I_y − M_z y/I_z` (Pa) over
    /// the section's extreme fibres for the resultants `[N, Q_y, Q_z, T, M_y, M_z]` of
    /// [`crate::element::geometric::beam_resultants`] (the flexure formula with the axial
    /// stress; shear and torsion stresses are not included); `None` when the fibres are
    /// [`Fibres::Unknown`]. Local `y`, `z` are taken as principal axes, as the element does.
    ///
    /// ```
    /// use vibrofem::section::BeamSection;
    /// // 20 × 40 mm, M_y = 100 N·m: σ = M c / I = 100 · 0.02 / (0.02 · 0.04³ / 12) = 18.75 MPa.
    /// let s = BeamSection::rectangle(0.02, 0.04);
    /// let sigma = s.extreme_normal_stress(&[0.0, 0.0, 0.0, 0.0, 100.0, 0.0]).unwrap();
    /// assert!((sigma - 18.75e6).abs() < 1e-6);
    /// ```
    pub fn extreme_normal_stress(&self, r: &[f64; 6]) -> Option<f64> {
        let axial = r[0] / self.area;
        match self.fibres {
            Fibres::Corners(points) => Some(
                points
                    .iter()
                    .map(|&[y, z]| (axial + r[4] * z / self.iy - r[5] * y / self.iz).abs())
                    .fold(0.0, f64::max),
            ),
            // Bending about any axis: the moment's magnitude over I (Iy = Iz for a round section).
            Fibres::Round(ro) => Some(axial.abs() + r[4].hypot(r[5]) * ro / self.iy.max(self.iz)),
            Fibres::Unknown => None,
        }
    }

    /// The largest shear stress of the torque `t` (N·m) for a round section, `|T| r / J` at its
    /// outer radius (exact for circles and tubes, Saint-Venant); `None` for other sections,
    /// whose torsion stresses depend on their shape beyond `J`.
    ///
    /// ```
    /// use vibrofem::section::BeamSection;
    /// // d = 20 mm, T = 40 N·m: τ = 16 T/(π d³) = 25.46 MPa.
    /// let tau = BeamSection::circle(0.02).torsion_shear(40.0).unwrap();
    /// assert!((tau - 16.0 * 40.0 / (std::f64::consts::PI * 0.02f64.powi(3))).abs() < 1e-6);
    /// ```
    pub fn torsion_shear(&self, t: f64) -> Option<f64> {
        match self.fibres {
            Fibres::Round(ro) => Some(t.abs() * ro / self.j),
            _ => None,
        }
    }

    /// Solid rectangle, width `b` along local `y`, depth `h` along local `z`.
    ///
    /// `A = bh`, `Iy = b h³/12`, `Iz = h b³/12`; `J = a c³ [1/3 − 0.21 (c/a)(1 − c⁴/(12a⁴))]`
    /// with `a = max(b, h)`, `c = min(b, h)` (Roark Table 10.7 case 4, within 0.5 % of the
    /// exact series); Cowper's `k = 10(1+ν)/(12+11ν)` in both directions; `Cw = 0` (the
    /// warping stiffness of compact solid sections is negligible; use [`custom`](Self::custom)
    /// for thin strips, `Cw ≈ b³h³/144`).
    pub fn rectangle(b: f64, h: f64) -> BeamSection {
        let (a, c) = if b >= h { (b, h) } else { (h, b) };
        let j = a * c.powi(3) * (1.0 / 3.0 - 0.21 * (c / a) * (1.0 - c.powi(4) / (12.0 * a.powi(4))));
        let k = cowper_rectangle(COWPER_POISSON);
        BeamSection::custom(b * h, b * h.powi(3) / 12.0, h * b.powi(3) / 12.0, j, k, k, 0.0)
            .with_fibres(box_corners(b, h))
    }

    /// Solid circle of diameter `d`: `A = πd²/4`, `I = πd⁴/64`, `J = πd⁴/32`, Cowper's
    /// `k = 6(1+ν)/(7+6ν)`, `Cw = 0` (circular sections do not warp).
    pub fn circle(d: f64) -> BeamSection {
        let pi = std::f64::consts::PI;
        let i = pi * d.powi(4) / 64.0;
        let k = cowper_tube(COWPER_POISSON, 0.0);
        BeamSection::custom(pi * d * d / 4.0, i, i, 2.0 * i, k, k, 0.0).with_fibres(Fibres::Round(0.5 * d))
    }

    /// Circular tube of outer diameter `d` and wall thickness `wall` (`0 < wall ≤ d/2`):
    /// `A = π(r_o² − r_i²)`, `I = π(r_o⁴ − r_i⁴)/4`, `J = 2I` (exact), Cowper's hollow-circle
    /// factor with `m = r_i/r_o`, `Cw = 0`.
    pub fn tube(d: f64, wall: f64) -> BeamSection {
        let pi = std::f64::consts::PI;
        let ro = 0.5 * d;
        let ri = (ro - wall).max(0.0);
        let i = pi * (ro.powi(4) - ri.powi(4)) / 4.0;
        let k = cowper_tube(COWPER_POISSON, ri / ro);
        BeamSection::custom(pi * (ro * ro - ri * ri), i, i, 2.0 * i, k, k, 0.0).with_fibres(Fibres::Round(ro))
    }

    /// I / double-T section by dimensions: depth `h` (along local `z`), flange width `b`
    /// (along `y`), web thickness `s`, flange thickness `t`; fillets ignored.
    ///
    /// - `A = 2bt + (h − 2t)s`; `Iy = [b h³ − (b − s)(h − 2t)³]/12`;
    ///   `Iz = [2t b³ + (h − 2t) s³]/12` (exact for the three rectangles).
    /// - `J = 2 (b t³/3)(1 − 0.63 t/b) + (h − 2t) s³/3`: thin rectangles, each flange with two
    ///   free ends (Roark Table 10.7), the web with none.
    /// - `Cw = t b³ h_f²/24`, `h_f = h − t` (= `Iz,flange h_f²/2`; Pilkey Table 2-5).
    /// - `kz` (web direction): Cowper's I-section formula with `h_f`; `ky` (along the
    ///   flanges): `(5/6)·2bt/A`, the two flanges as rectangles carrying the whole shear.
    /// - Shear centre at the centroid (doubly symmetric).
    pub fn i_beam(h: f64, b: f64, s: f64, t: f64) -> BeamSection {
        let hw = h - 2.0 * t;
        let hf = h - t;
        let area = 2.0 * b * t + hw * s;
        let iy = (b * h.powi(3) - (b - s) * hw.powi(3)) / 12.0;
        let iz = (2.0 * t * b.powi(3) + hw * s.powi(3)) / 12.0;
        let j = 2.0 * thin_rect_j(b, t, 2.0) + hw * s.powi(3) / 3.0;
        let cw = t * b.powi(3) * hf * hf / 24.0;
        let kz = cowper_i_web(COWPER_POISSON, b, t, hf, s);
        let ky = (5.0 / 6.0 * 2.0 * b * t / area).min(1.0);
        BeamSection::custom(area, iy, iz, j, ky, kz, cw).with_fibres(box_corners(b, h))
    }

    /// Channel (U) section by dimensions: depth `h` (along local `z`), flange width `b`
    /// (along `y`, from the web's back to the flange tips), web thickness `s`, flange
    /// thickness `t`; fillets and flange slope ignored. The web's back is on the `−y` side,
    /// the flanges point to `+y`.
    ///
    /// - `A`, centroid, `Iy`, `Iz`: exact for the web `s × h` plus two flanges
    ///   `(b − s) × t`.
    /// - `J = 2 (b t³/3)(1 − 0.315 t/b) + (h − 2t) s³/3` (one free end per flange).
    /// - Shear centre on the symmetry axis, behind the web at `e = 3 b_f² t / (6 b_f t + h_f s)`
    ///   from the web centreline, `b_f = b − s/2`, `h_f = h − t` (Roark Table 10.1 / Pilkey
    ///   Table 2-5); `shear_centre = [s/2 − e − y_c, 0]` with `y_c` the centroid from the back.
    /// - `Cw = (t b_f³ h_f²/12)(3 b_f t + 2 h_f s)/(6 b_f t + h_f s)` (Pilkey Table 2-5).
    /// - `kz` (web direction): thin-walled shear-flow energy method (Cowper gives no channel);
    ///   the same method is within 3 % of Cowper's formula on I-sections. `ky = (5/6)·2bt/A`.
    pub fn channel(h: f64, b: f64, s: f64, t: f64) -> BeamSection {
        let hw = h - 2.0 * t;
        let hf = h - t;
        let bf = b - 0.5 * s;
        let (a_web, a_fl) = (h * s, (b - s) * t);
        let area = a_web + 2.0 * a_fl;
        // Centroid from the back of the web.
        let yc = (a_web * 0.5 * s + 2.0 * a_fl * (s + 0.5 * (b - s))) / area;
        let iy = s * h.powi(3) / 12.0 + 2.0 * ((b - s) * t.powi(3) / 12.0 + a_fl * (0.5 * (h - t)).powi(2));
        let iz = h * s.powi(3) / 12.0
            + a_web * (yc - 0.5 * s).powi(2)
            + 2.0 * (t * (b - s).powi(3) / 12.0 + a_fl * (s + 0.5 * (b - s) - yc).powi(2));
        let j = 2.0 * thin_rect_j(b, t, 1.0) + hw * s.powi(3) / 3.0;
        let e = 3.0 * bf * bf * t / (6.0 * bf * t + hf * s);
        let cw = t * bf.powi(3) * hf * hf / 12.0 * (3.0 * bf * t + 2.0 * hf * s) / (6.0 * bf * t + hf * s);
        let kz = energy_web_shear_factor(hf, s, 2.0, bf, t);
        let ky = (5.0 / 6.0 * 2.0 * b * t / area).min(1.0);
        BeamSection {
            shear_centre: [0.5 * s - e - yc, 0.0],
            fibres: Fibres::Corners([[-yc, -0.5 * h], [b - yc, -0.5 * h], [b - yc, 0.5 * h], [-yc, 0.5 * h]]),
            ..BeamSection::custom(area, iy, iz, j, ky, kz, cw)
        }
    }

    /// GOST 8239-89 hot-rolled I-beam No. 10: `h` 100, `b` 55, `s` 4.5, `t` 7.2 mm
    /// ([`i_beam`](Self::i_beam), in metres). The table (with fillets and sloped flanges)
    /// lists `A` = 12.0 cm², `I_x` = 198 cm⁴, `I_y` = 17.9 cm⁴; these formulas give 11.77 cm²,
    /// 194.4 cm⁴ and 20.0 cm⁴ (the uniform mean flange thickness puts more material at the
    /// flange tips than the sloped flange).
    pub fn gost_8239_i10() -> BeamSection {
        BeamSection::i_beam(0.100, 0.055, 0.0045, 0.0072)
    }

    /// GOST 8240-97 channel No. 10 (series U): `h` 100, `b` 46, `s` 4.5, `t` 7.6 mm
    /// ([`channel`](Self::channel), in metres). The table lists `A` = 10.9 cm²,
    /// `I_x` = 174 cm⁴, `I_y` = 20.4 cm⁴, `z_0` = 1.44 cm.
    pub fn gost_8240_channel10() -> BeamSection {
        BeamSection::channel(0.100, 0.046, 0.0045, 0.0076)
    }

    /// The same section with the warping degree of freedom requested (or not).
    pub fn with_warping(self, warping: bool) -> BeamSection {
        BeamSection { warping, ..self }
    }

    /// The same section with other shear factors (e.g. Cowper's at another ν, or a large
    /// value such as 1e6 for an Euler–Bernoulli beam).
    pub fn with_shear_factors(self, ky: f64, kz: f64) -> BeamSection {
        BeamSection { ky, kz, ..self }
    }

    /// Polar second moment about the centroid, `Ip = Iy + Iz` (the torsional rotary inertia
    /// per unit density and length).
    pub fn polar(&self) -> f64 {
        self.iy + self.iz
    }

    /// Checks the values: `A`, `Iy`, `Iz`, `J`, `ky`, `kz` positive and finite, `Cw ≥ 0`,
    /// finite shear-centre offset. `name` (the section or group) goes into the
    /// error message; the error ([`Error::param`]) names the field.
    ///
    /// ```
    /// use vibrofem::section::BeamSection;
    /// let bad = BeamSection::custom(1e-4, 1e-8, 0.0, 1e-8, 0.8, 0.8, 0.0);
    /// assert!(bad.validate("frame").unwrap_err().to_string().contains("Iz"));
    /// ```
    pub fn validate(&self, name: &str) -> Result<()> {
        let positive = [
            ("area", "area A", self.area),
            ("iy", "second moment Iy", self.iy),
            ("iz", "second moment Iz", self.iz),
            ("j", "torsion constant J", self.j),
            ("ky", "shear factor ky", self.ky),
            ("kz", "shear factor kz", self.kz),
        ];
        for (field, what, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::param(
                    format!("BeamSection::{field}"),
                    format!("beam section '{name}': {what} = {v}: must be positive and finite"),
                ));
            }
        }
        if !(self.cw.is_finite() && self.cw >= 0.0) {
            return Err(Error::param(
                "BeamSection::cw",
                format!(
                    "beam section '{name}': warping constant Cw = {}: must be non-negative and finite",
                    self.cw
                ),
            ));
        }
        if !self.shear_centre.iter().all(|c| c.is_finite()) {
            return Err(Error::param(
                "BeamSection::shear_centre",
                format!(
                    "beam section '{name}': shear centre offset {:?} is not finite",
                    self.shear_centre
                ),
            ));
        }
        Ok(())
    }
}

/// Default drilling-penalty factor of [`ShellSection`]: the drilling stiffness is
/// `α G t` per unit area with `α = 0.1`. Smaller values (such as the often quoted `1e-3`)
/// soften twisted and curved shells and the error does not vanish with mesh refinement;
/// larger ones over-constrain the constant-strain triangles. See [`crate::element::shell`].
pub const DEFAULT_DRILLING: f64 = 0.1;

/// Section of a shell: thickness, reference-surface offset and drilling-penalty factor.
///
/// Nodes lie on the reference surface. `offset` is the signed distance from the mid-surface
/// to the reference surface along the element normal `n` (right-hand rule on the node order):
/// the mid-surface is at `x − offset·n`. A plate meshed on its bottom face (the plate on the
/// `+n` side) has `offset = −t/2`, one meshed on its top face `offset = +t/2`. Any finite
/// offset is accepted (stiffener-like eccentricities too).
///
/// ```
/// use vibrofem::section::ShellSection;
/// let s = ShellSection::new(0.02).with_offset(-0.01);
/// assert!(s.validate("plate").is_ok());
/// assert!(ShellSection::new(0.0).validate("plate").is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShellSection {
    /// Thickness `t` (m), positive.
    pub thickness: f64,
    /// Offset of the reference (node) surface from the mid-surface along the normal (m).
    pub offset: f64,
    /// Drilling-penalty factor `α` (dimensionless, positive): drilling stiffness density
    /// `α G t` (see [`crate::element::shell`]); [`DEFAULT_DRILLING`] unless changed.
    pub drilling: f64,
}

impl ShellSection {
    /// Thickness `t`, no offset, default drilling factor.
    pub fn new(thickness: f64) -> ShellSection {
        ShellSection {
            thickness,
            offset: 0.0,
            drilling: DEFAULT_DRILLING,
        }
    }

    /// The same section with the reference surface at `offset` from the mid-surface.
    pub fn with_offset(self, offset: f64) -> ShellSection {
        ShellSection { offset, ..self }
    }

    /// The same section with drilling factor `alpha`.
    pub fn with_drilling(self, alpha: f64) -> ShellSection {
        ShellSection {
            drilling: alpha,
            ..self
        }
    }

    /// Checks thickness (positive, finite), offset (finite) and drilling factor (positive,
    /// finite); the error names `name` (the group).
    pub fn validate(&self, name: &str) -> Result<()> {
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(Error::param(
                "ShellSection::thickness",
                format!(
                    "shell section '{name}': thickness {} m: must be positive and finite",
                    self.thickness
                ),
            ));
        }
        if !self.offset.is_finite() {
            return Err(Error::param(
                "ShellSection::offset",
                format!("shell section '{name}': offset {} m is not finite", self.offset),
            ));
        }
        if !(self.drilling.is_finite() && self.drilling > 0.0) {
            return Err(Error::param(
                "ShellSection::drilling",
                format!(
                    "shell section '{name}': drilling factor {}: must be positive and finite",
                    self.drilling
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_shear_factor_matches_cowper_on_i_beam() {
        // GOST I10 centreline values: both methods describe the same web shear flow; Cowper
        // adds the Poisson effect, so a few per cent apart is expected.
        let (h, b, s, t) = (0.1, 0.055, 0.0045, 0.0072);
        let cowper = cowper_i_web(0.3, b, t, h - t, s);
        let energy = energy_web_shear_factor(h - t, s, 4.0, 0.5 * b, t);
        assert!((cowper - 0.331).abs() < 2e-3, "{cowper}");
        assert!((energy / cowper - 1.0).abs() < 0.03, "{energy} vs {cowper}");
    }

    #[test]
    fn cowper_limits() {
        assert!((cowper_rectangle(0.0) - 10.0 / 12.0).abs() < 1e-15);
        assert!((cowper_tube(0.3, 0.0) - 7.8 / 8.8).abs() < 1e-15);
        // Thin tube: 2(1+ν)/(4+3ν).
        assert!((cowper_tube(0.3, 1.0) - 2.6 / 4.9).abs() < 1e-15);
    }
}
