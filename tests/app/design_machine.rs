//! Issue 29: the 3D machine as the model of record — the magnets' force laws and stiffness,
//! the force on the floor from both models, the rigid symmetric machine against the two-mass
//! model under each law, and the design file's drive keys.

use vibrofem::app::design::{Design, analyse};
use vibrofem::app::dynamics::electromagnet::{ForceLaw, MagnetDrive, magnet_stiffness};
use vibrofem::app::dynamics::two_mass::TwoMass;

/// Fourier coefficients (a_n, b_n) of `f` over one mains period 2π/ω at n·ω, by the rectangle
/// rule on `m` samples: exact (to rounding) for a trigonometric polynomial of degree < m/2.
fn fourier(f: &dyn Fn(f64) -> f64, omega: f64, n: usize, m: usize) -> (f64, f64) {
    let t_per = std::f64::consts::TAU / omega;
    let (mut a, mut b) = (0.0, 0.0);
    for j in 0..m {
        let t = t_per * j as f64 / m as f64;
        let x = (n as f64 * omega * t).cos();
        let y = (n as f64 * omega * t).sin();
        a += f(t) * x;
        b += f(t) * y;
    }
    let s = if n == 0 { 1.0 } else { 2.0 };
    (s * a / m as f64, s * b / m as f64)
}

#[test]
fn flux_law_has_a_mean_and_one_harmonic_at_twice_the_mains() {
    // sin²x = 1/2 − cos(2x)/2 (Abramowitz & Stegun 4.3.31): with a sinusoidal flux the pull is
    // P/2 + (P/2)·(−cos 2ωt), nothing else. 1024 samples integrate every harmonic up to the 511th
    // exactly, so 1e-9·P bounds rounding only.
    let p = 2960.0;
    let w = std::f64::consts::TAU * 50.0;
    let d = MagnetDrive::from_magnets(ForceLaw::Flux, 8, 370.0, w).unwrap();
    assert!((d.mean() - p / 2.0).abs() < 1e-9 * p);
    assert!((d.harmonic_amplitude() - p / 2.0).abs() < 1e-9 * p);
    let f = |t: f64| d.force(t);
    for n in 0..=20 {
        let (a, b) = fourier(&f, w, n, 1024);
        let want = match n {
            0 => p / 2.0,
            2 => -p / 2.0,
            _ => 0.0,
        };
        assert!((a - want).abs() < 1e-9 * p, "cos {n}ω: {a} vs {want}");
        assert!(b.abs() < 1e-9 * p, "sin {n}ω: {b}");
        // The law's own coefficients (per harmonic k of Ω = 2ω) say the same.
        if n % 2 == 0 {
            assert!((d.cos_coefficient(n as u32 / 2) - want).abs() < 1e-9 * p);
        }
    }
}

#[test]
fn paper_law_has_the_rectified_sine_series() {
    // |sin x| = 2/π − (4/π)·Σ cos(2kx)/(4k² − 1) (the paper's eq. (8); Abramowitz & Stegun
    // 4.3 / any table of Fourier series): mean 2P/π, 2ω amplitude 4P/(3π), 4ω 4P/(15π), no odd
    // harmonics of ω. The kinks converge slowly (1/k²) but the rectangle rule on 2¹⁶ samples
    // aliases only harmonics above 2¹⁵, whose coefficients are below 1e-9·P.
    let p = 2960.0;
    let w = std::f64::consts::TAU * 50.0;
    let d = MagnetDrive::from_magnets(ForceLaw::Paper, 8, 370.0, w).unwrap();
    let pi = std::f64::consts::PI;
    assert!((d.mean() - 2.0 * p / pi).abs() < 1e-9 * p);
    assert!((d.harmonic_amplitude() - 4.0 * p / (3.0 * pi)).abs() < 1e-9 * p);
    let f = |t: f64| d.force(t);
    for n in 0..=8 {
        let (a, b) = fourier(&f, w, n, 1 << 16);
        let want = if n % 2 == 1 {
            0.0
        } else {
            d.cos_coefficient(n as u32 / 2)
        };
        assert!((a - want).abs() < 1e-8 * p, "cos {n}ω: {a} vs {want}");
        assert!(b.abs() < 1e-8 * p, "sin {n}ω: {b}");
    }
    assert!((d.cos_coefficient(2) + 4.0 * p / (15.0 * pi)).abs() < 1e-9 * p);
}

#[test]
fn magnet_stiffness_is_the_pull_gradient() {
    // F = C/δ² (constant current linkage) → dF/dδ = −2F/δ; checked by a central difference.
    let (f0, delta): (f64, f64) = (1480.0, 1.8e-3);
    let c = f0 * delta * delta;
    let h: f64 = 1e-7;
    let fd = (c / (delta + h).powi(2) - c / (delta - h).powi(2)) / (2.0 * h);
    let k = magnet_stiffness(f0, delta).unwrap();
    assert!((k - fd).abs() < 1e-6 * fd.abs(), "{k} vs {fd}");
    assert!(magnet_stiffness(f0, 0.0).is_err());
}

#[test]
fn two_mass_floor_force_is_the_isolators_impedance_times_x2() {
    let m = TwoMass::paper();
    let omega = std::f64::consts::TAU * 100.0;
    let f = 1256.0;
    let ss = m.steady_state(omega, f).unwrap();
    let ff = m.floor_force(omega, f).unwrap().norm();
    let want = (m.c13.powi(2) + (omega * m.mu13).powi(2)).sqrt() * ss.amp2();
    assert!((ff - want).abs() < 1e-9 * want, "{ff} vs {want}");
    // Textbook limit: with the leaves (almost) gone the reactive mass is a single mass driven
    // by F on the isolators, whose force transmissibility is
    // T = |k + icΩ| / |k − mΩ² + icΩ| (Harris' Shock and Vibration Handbook, 5th ed., ch. 30,
    // eq. 30.1 and Table 30.1, force excitation of a mass on a Voigt isolator). c12 = 1e-6 N/m
    // perturbs it by c12/(m2Ω²) ≈ 1e-14.
    let single = TwoMass::new(m.m1, m.m2, 1e-6, m.c13, 0.0, 0.0, m.mu13).unwrap();
    let ff = single.floor_force(omega, f).unwrap().norm() / f;
    let k = nalgebra::Complex::new(m.c13, omega * m.mu13);
    let t = k.norm() / (k - m.m2 * omega * omega).norm();
    assert!((ff - t).abs() < 1e-9 * t, "{ff} vs {t}");
    // The misleading figure the report used to give as isolation: 1/(r² − 1) of the whole
    // loaded mass is about 1/400, where the reactive machine puts ~0.1 of F on the floor.
    assert!(want / f > 0.05, "{}", want / f);
}

#[test]
fn dissipated_power_is_the_dashpots_mean_work() {
    // Ω²/2·(μ1|X1|² + μ12|X1 − X2|² + μ13|X2|²) for the eq. (1) terms.
    let m = TwoMass::paper();
    let omega = std::f64::consts::TAU * 100.0;
    let s = m.steady_state(omega, 1256.0).unwrap();
    let want =
        0.5 * omega * omega * (m.mu1 * s.x1.norm_sqr() + m.mu12 * (s.x1 - s.x2).norm_sqr() + m.mu13 * s.x2.norm_sqr());
    let p = m.dissipated_power(omega, 1256.0).unwrap();
    assert!((p - want).abs() < 1e-9 * want, "{p} vs {want}");
    // Equals the mean input power F·v of the drive: ½·Re(F̄·iΩ(X2 − X1)) with +F on m2, −F on m1.
    let input = 0.5 * (nalgebra::Complex::new(0.0, omega) * (s.x2 - s.x1) * 1256.0).re;
    assert!((p - input).abs() < 1e-9 * want, "{p} vs {input}");
}

#[test]
fn rigid_symmetric_machine_equals_the_two_mass_model_under_each_law() {
    for law in ["paper", "flux"] {
        let mut d = Design::paper();
        d.machine.table_model = "rigid".into();
        d.drive.force_law = law.into();
        let h = 0.0099;
        let r = analyse(&d, h).unwrap();
        // The same parts lumped: the magnets' stiffness −2P̄/δ beside the leaves in both.
        let m1 = r.table_mass + d.masses.active_extra;
        let c12 = d.leaf.count as f64 * d.leaf.clamping * r.leaf_kzz + d.magnet_stiffness().unwrap();
        let c13 = d.coil.count as f64 * r.coil_axial;
        let tm = TwoMass::new(
            m1,
            d.masses.reactive,
            c12,
            c13,
            d.damping.mu1,
            d.damping.mu12,
            d.damping.mu13,
        )
        .unwrap();
        let [f1, f2] = tm.natural_frequencies_hz().unwrap();
        let fw = r.modes[r.working.expect("a working mode")].frequency_hz;
        // Symmetric springs and forces: the vertical motion decouples exactly (rounding only).
        assert!((fw - f2).abs() / f2 < 1e-6, "{law}: working {fw} vs {f2}");
        let bounce = r.modes.iter().find(|m| m.name == "isolation: bounce").unwrap();
        assert!(
            (bounce.frequency_hz - f1).abs() / f1 < 1e-6,
            "{law}: {} vs {f1}",
            bounce.frequency_hz
        );
        let drive = d.magnet_drive().unwrap();
        let omega = std::f64::consts::TAU * d.excitation_hz;
        let ss = tm.steady_state(omega, drive.harmonic_amplitude()).unwrap();
        assert!(
            (r.mean - ss.amp1()).abs() / ss.amp1() < 1e-6,
            "{law}: {} vs {}",
            r.mean,
            ss.amp1()
        );
        assert!((r.reactive_amplitude - ss.amp2()).abs() / ss.amp2() < 1e-6, "{law}");
        // The floor force, total and per isolator (equal shares on the symmetric layout), at
        // the excitation and at every harmonic the law has (paper: 2Ω, 3Ω; flux: none).
        let want_k = if law == "paper" { 3 } else { 1 };
        assert_eq!(r.floor.len(), want_k, "{law}");
        for fl in &r.floor {
            let k = fl.harmonic;
            let ff = tm
                .floor_force(k as f64 * omega, drive.cos_coefficient(k).abs())
                .unwrap()
                .norm();
            assert!((fl.total - ff).abs() < 1e-6 * ff, "{law} k = {k}: {} vs {ff}", fl.total);
            for p in &fl.per_isolator {
                assert!((p - ff / 8.0).abs() < 1e-6 * ff, "{law} k = {k}: {p} vs {}", ff / 8.0);
            }
        }
        // The relative motion across every leaf and magnet is the two-mass |X1 − X2|.
        for x in r.leaf_relative.iter().chain(&r.magnet_relative) {
            assert!((x - ss.relative_amp()).abs() < 1e-6 * ss.relative_amp(), "{law}: {x}");
        }
        // The machine's dissipation is the two-mass model's.
        let p2 = tm.dissipated_power(omega, drive.harmonic_amplitude()).unwrap();
        assert!(
            (r.dissipated_power - p2).abs() < 1e-6 * p2,
            "{law}: {} vs {p2}",
            r.dissipated_power
        );
    }
}

#[test]
fn machine_modes_have_unique_names() {
    let mut d = Design::paper();
    d.machine.table_model = "rigid".into();
    let r = analyse(&d, 0.0099).unwrap();
    let mut names: Vec<&str> = r.modes.iter().map(|m| m.name.as_str()).collect();
    let n = names.len();
    names.sort();
    names.dedup();
    assert_eq!(
        names.len(),
        n,
        "{:?}",
        r.modes.iter().map(|m| &m.name).collect::<Vec<_>>()
    );
    for want in [
        "isolation: sway x",
        "isolation: sway y",
        "isolation: yaw",
        "working mode",
    ] {
        assert!(names.iter().any(|m| m.starts_with(want)), "{want} in {names:?}");
    }
}

/// Writes a design file and reads it.
fn read(name: &str, text: &str) -> vibrofem::Result<Design> {
    let dir = std::env::temp_dir().join(format!("vibrofem-design-machine-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    Design::from_toml(&p)
}

#[test]
fn drive_keys_are_checked_when_the_file_is_read() {
    let e = read("law.toml", "version = 1\n[drive]\nforce_law = \"sine\"\n")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("law.toml, line 3, key 'drive.force_law'"), "{e}");
    // Both given, inconsistent: the mains at 60 Hz drives the magnets at 120 Hz, not 100.
    let e = read(
        "mains.toml",
        "version = 1\nexcitation_hz = 100.0\n[drive]\nmains_hz = 60.0\n",
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("line 4, key 'drive.mains_hz'") && e.contains("excitation_hz"),
        "{e}"
    );
    // The mains alone sets the excitation; the excitation alone sets the mains.
    let d = read("mains60.toml", "version = 1\n[drive]\nmains_hz = 60.0\n").unwrap();
    assert_eq!(d.excitation_hz, 120.0);
    let d = read("exc.toml", "version = 1\nexcitation_hz = 50.0\n").unwrap();
    assert_eq!(d.mains_hz(), 25.0);
    let e = read("gap.toml", "version = 1\n[drive]\ngap = 0.0\n")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("key 'drive.gap'"), "{e}");
    // New designs take the flux law; only the built-in design is compared with the paper.
    assert_eq!(Design::paper().drive.force_law, "flux");
    assert!(Design::paper().is_builtin());
    let mut d = Design::paper();
    d.excitation_hz = 50.0;
    assert!(!d.is_builtin());
}
