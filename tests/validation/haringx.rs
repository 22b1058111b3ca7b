//! Haringx's buckling criterion for helical compression springs
//! (`post::spring::buckling_deflection`) against Shigley's form of the same theory.
//!
//! Reference: Budynas & Nisbett, Shigley's Mechanical Engineering Design, 9th ed. 2011, ch. 10
//! "Stability": y_cr = L0·C1·[1 − √(1 − C2/λ_eff²)], C1 = E/(2(E − G)),
//! C2 = 2π²(E − G)/(2G + E), λ_eff = αL0/D, and absolute stability for steel when
//! L0 < 2.63 D/α (its Eq. for steel, E = 207 GPa, G = 79.3 GPa). The function is written in
//! EN 13906-1's form (G/E ratios): agreement to rounding (1e-12) checks the algebra; the
//! stability limit is checked to Shigley's three printed digits.

use std::f64::consts::PI;
use vibrofem::post::spring::buckling_deflection;

#[test]
fn haringx_critical_deflection_matches_shigley() {
    let (e, g) = (207e9, 79.3e9);
    let c1 = e / (2.0 * (e - g));
    let c2 = 2.0 * PI * PI * (e - g) / (2.0 * g + e);
    let d = 0.032;
    for alpha in [0.5, 0.707, 1.0, 2.0] {
        for l0_over_d in [3.0, 6.0, 10.0, 20.0] {
            let l0 = l0_over_d * d;
            let lam = alpha * l0 / d;
            let got = buckling_deflection(l0, d, alpha, e, g).unwrap();
            if c2 / (lam * lam) >= 1.0 {
                assert!(got.is_none(), "α {alpha}, L0/D {l0_over_d}: stable, got {got:?}");
            } else {
                let y = l0 * c1 * (1.0 - (1.0 - c2 / (lam * lam)).sqrt());
                let s = got.expect("unstable spring");
                assert!((s / y - 1.0).abs() < 1e-12, "α {alpha}, L0/D {l0_over_d}: {s} vs {y}");
            }
        }
    }
    // Absolute stability for steel: L0 < 2.63 D/α (Shigley's rounding of 2.624).
    let limit = PI * ((2.0 * (e - g)) / (2.0 * g + e)).sqrt();
    assert!((limit - 2.63).abs() < 0.01, "{limit}");
    for alpha in [0.5, 1.0, 2.0] {
        assert!(
            buckling_deflection(0.999 * limit * d / alpha, d, alpha, e, g)
                .unwrap()
                .is_none()
        );
        assert!(
            buckling_deflection(1.001 * limit * d / alpha, d, alpha, e, g)
                .unwrap()
                .is_some()
        );
    }
    // Bad input names the spring.
    assert!(buckling_deflection(0.1, d, 0.5, g, e).is_err());
}
