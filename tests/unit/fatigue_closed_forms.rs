//! Fatigue and coil-spring library (`post::fatigue`, `post::spring`): closed forms, the
//! harmonic amplitudes against brute-force phase sampling, the FKM Haigh diagram's continuity,
//! Basquin's inverse, the material parser's errors.

use vibrofem::post::fatigue::{
    Criterion, FatigueMaterial, MeanStress, alternating, cycles_to_failure, equivalent_reversed, finite_life_strength,
    fkm_amplitude_at, fkm_k_ak, mean_equivalent, roughness_factor, safety, signed_principal,
};
use vibrofem::post::spring;
use vibrofem::post::stress::{principal, von_mises};

/// Brute force: the maximum over 200 000 phases of f(A cos φ − B sin φ).
fn sampled(re: &[f64; 6], im: &[f64; 6], f: impl Fn(&[f64; 6]) -> f64) -> f64 {
    let n = 200_000;
    (0..n)
        .map(|k| {
            let phi = std::f64::consts::PI * k as f64 / n as f64;
            let t: [f64; 6] = std::array::from_fn(|i| re[i] * phi.cos() - im[i] * phi.sin());
            f(&t)
        })
        .fold(0.0, f64::max)
}

#[test]
fn harmonic_amplitudes_match_phase_sampling() {
    let re = [120e6, -30e6, 15e6, 8e6, -22e6, 40e6];
    let im = [-50e6, 70e6, 5e6, -12e6, 9e6, 25e6];
    let vm = alternating(Criterion::SignedVonMises, &re, &im).value;
    let vm_ref = sampled(&re, &im, von_mises);
    // The sampled maximum is below the true one by O(h²) relative, h = π/2e5: 1e-9 covers it.
    assert!(
        vm >= vm_ref * (1.0 - 1e-12) && (vm - vm_ref).abs() < 1e-9 * vm,
        "{vm} {vm_ref}"
    );
    let pr = alternating(Criterion::SignedPrincipal, &re, &im).value;
    let pr_ref = sampled(&re, &im, |t| {
        let p = principal(t);
        p[0].abs().max(p[2].abs())
    });
    assert!((pr - pr_ref).abs() < 1e-9 * pr, "{pr} {pr_ref}");
    // Exact cases: a rotating uniaxial stress σ(cos φ, −sin φ) has amplitude σ; in-phase parts
    // σ(1 + i) have amplitude σ√2.
    let s = 100e6;
    let a = alternating(
        Criterion::SignedPrincipal,
        &[s, 0.0, 0.0, 0.0, 0.0, 0.0],
        &[0.0, s, 0.0, 0.0, 0.0, 0.0],
    );
    assert!((a.value - s).abs() < 1e-12 * s);
    let a = alternating(
        Criterion::SignedPrincipal,
        &[s, 0.0, 0.0, 0.0, 0.0, 0.0],
        &[s, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    assert!((a.value - s * 2f64.sqrt()).abs() < 1e-12 * s);
    let a = alternating(
        Criterion::SignedVonMises,
        &[s, 0.0, 0.0, 0.0, 0.0, 0.0],
        &[s, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    assert!((a.value - s * 2f64.sqrt()).abs() < 1e-9 * s);
}

#[test]
fn mean_on_the_plane_of_the_alternating_principal() {
    // Alternating bending along x, a mean of 30 MPa along x and 80 MPa along y: the mean that
    // counts is the one on the x plane.
    let alt = alternating(Criterion::SignedPrincipal, &[100e6, 0.0, 0.0, 0.0, 0.0, 0.0], &[0.0; 6]);
    let mean = [30e6, 80e6, 0.0, 0.0, 0.0, 0.0];
    assert!((mean_equivalent(Criterion::SignedPrincipal, &mean, &alt) - 30e6).abs() < 1e-6);
    // Signed von Mises: compressive hydrostatic part gives a negative mean.
    let vm = mean_equivalent(Criterion::SignedVonMises, &[-50e6, 0.0, 0.0, 0.0, 0.0, 0.0], &alt);
    assert!((vm + 50e6).abs() < 1e-6);
    // Signed principal of a tensor with a rotated uniaxial stress.
    let (l, n) = signed_principal(&[50e6, 50e6, 0.0, 0.0, 0.0, 50e6]);
    assert!((l - 100e6).abs() < 1e-3 && (n[0].abs() - 0.5f64.sqrt()).abs() < 1e-12);
}

#[test]
fn goodman_gerber_fkm_closed_forms() {
    let (se, rm) = (300e6, 1000e6);
    let (sa, sm) = (120e6, 200e6);
    let g = safety(MeanStress::Goodman, sa, sm, se, rm, 0.0);
    assert!((g - 1.0 / (0.4 + 0.2)).abs() < 1e-12);
    // Gerber: n sa/se + (n sm/rm)² = 1 at the returned n.
    let n = safety(MeanStress::Gerber, sa, sm, se, rm, 0.0);
    assert!((n * sa / se + (n * sm / rm).powi(2) - 1.0).abs() < 1e-12);
    // FKM at every range: the scaled point lies on the Haigh line.
    let m = 0.3;
    for r in [-3.0, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 3.0, 5.0] {
        let (sa, sm) = (100e6, r * 100e6);
        let n = safety(MeanStress::Fkm, sa, sm, se, rm, m);
        let on_line = fkm_amplitude_at(m, se, n * sm);
        assert!(
            (n * sa - on_line).abs() < 1e-6,
            "R-range r = {r}: {} vs {on_line}",
            n * sa
        );
    }
    // Continuity of K_AK across the range limits (σm/σa = −1, 1, 3).
    for r in [-1.0, 1.0, 3.0] {
        let (lo, hi) = (fkm_k_ak(m, 1.0, r - 1e-9), fkm_k_ak(m, 1.0, r + 1e-9));
        assert!((lo - hi).abs() < 1e-8, "jump at {r}: {lo} {hi}");
    }
    // Compressive mean: no credit with Goodman/Gerber.
    assert_eq!(safety(MeanStress::Goodman, sa, -sm, se, rm, 0.0), se / sa);
    // Life: at the equivalent reversed amplitude the Basquin strength gives safety 1.
    let s_ar = equivalent_reversed(MeanStress::Goodman, 400e6, 100e6, rm, 0.0);
    let n_f = cycles_to_failure(s_ar, se, 5.0, 1e6);
    let s_n = finite_life_strength(se, 5.0, 1e6, n_f);
    assert!((safety(MeanStress::Goodman, 400e6, 100e6, s_n, rm, 0.0) - 1.0).abs() < 1e-12);
}

#[test]
fn roughness_factor_and_material_errors() {
    assert_eq!(roughness_factor(0.5, 1000e6), 1.0);
    let m = FatigueMaterial::builtin("60si2mn").unwrap();
    assert_eq!(m.r_m, 1570e6);
    assert!(m.source.contains("GB/T 1222-2007"));
    let e = FatigueMaterial::parse("--fatigue", "unobtainium")
        .unwrap_err()
        .to_string();
    assert!(e.contains("--fatigue") && e.contains("60Si2Mn"), "{e}");
    let e = FatigueMaterial::parse("--fatigue", "rm=500,re=900")
        .unwrap_err()
        .to_string();
    assert!(e.contains("R_e") && e.contains("R_m"), "{e}");
    let e = FatigueMaterial::parse("--fatigue", "rm=500,xx=3")
        .unwrap_err()
        .to_string();
    assert!(e.contains("'xx'"), "{e}");
    let u = FatigueMaterial::parse("--fatigue", "rm=1000,re=800,sw=420,k=6,nd=2e6").unwrap();
    assert_eq!((u.sigma_w, u.slope, u.knee_cycles), (420e6, 6.0, 2e6));
}

#[test]
fn surge_frequency_is_half_sqrt_k_over_m() {
    // f = ½√(k/m) of the active coils between fixed plates, k = d⁴G/(8D³N), m = ρ π²d²DN/4.
    let (d, big_d, n, g, rho) = (0.006, 0.032, 6.0, 7.7e10, 7850.0);
    let k = spring::rate(d, big_d, g, n);
    let m = rho * std::f64::consts::PI.powi(2) * d * d * big_d * n / 4.0;
    let f = spring::surge_frequency(d, big_d, n, g, rho);
    assert!((f - 0.5 * (k / m).sqrt()).abs() < 1e-12 * f);
    let (k1, cl) = spring::surge_clearance(333.0, 100.0, 5).unwrap();
    assert_eq!(k1, 3);
    assert!((cl - 0.11).abs() < 1e-12);
}
