//! Fatigue assessment (`post::fatigue`, `post::spring`) against closed forms and published
//! worked examples:
//!
//! - a uniaxial bar (FE-recovered stresses of an imposed uniform strain) with a mean and an
//!   alternating load: Goodman and Gerber safety factors in closed form to 1e-9;
//! - Budynas & Nisbett, Shigley's Mechanical Engineering Design, 9th ed. (McGraw-Hill 2011),
//!   §6-12, Example 6-10 (AISI 1050 CD bar, 0–16 kip, K_f = 1.85): Gerber n_f = 3.66, Langer
//!   n_y = 5.01 (the page is not cited: the number was not verifiable here);
//! - the Instructor's Solutions Manual to Budynas & Nisbett, Shigley's Mechanical Engineering
//!   Design, 8th ed. (2008), ch. 10: Prob. 10-3 and 10-4 (pp. 261–262, music-wire spring: S_ut,
//!   K_B, rate, solid length, free length, overrun to closure) and Prob. 10-24 (p. 277, A313
//!   stainless: S_ut, S_su, S_sy and the Goodman–Zimmerli endurance S_se);
//! - the FKM roughness factor's worked example (R_m = 600 MPa, R_z = 100 µm → K_R = 0.79) of
//!   quadco.engineering, "Surface roughness factor K_R" (FKM-Richtlinie, 6th ed., §4.3).
//!
//! Tolerances: the published results are rounded to three significant figures, so 1 % (the
//! issue's bound) holds them with room for the book's intermediate rounding; closed forms to 1e-9.

use vibrofem::material::Material;
use vibrofem::mesh::CellKind;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::model::{Model, ModelSpec};
use vibrofem::post::fatigue::{
    Criterion, FatigueMaterial, FatigueSettings, MeanStress, PartCondition, assess, hot_spots, marin_surface_factor,
    roughness_factor, safety, yield_safety,
};
use vibrofem::post::spring;
use vibrofem::post::stress::nodal_stress;

/// 1 kpsi in Pa.
const KPSI: f64 = 6.894_757_293e6;

fn close(what: &str, got: f64, want: f64, rel: f64) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "{what}: {got} against {want} (rel. error {:.2e} > {rel:.0e})",
        (got - want).abs() / want.abs()
    );
}

/// Nodal stresses of a hex20 bar under the uniform uniaxial strain field of a stress `s` along x.
fn bar_stress(s: f64) -> (vibrofem::mesh::Mesh, Vec<[f64; 6]>) {
    let mesh = box_mesh(CellKind::Hex20, [0.2, 0.02, 0.02], [6, 2, 2]);
    let mat = Material::steel();
    let model = Model::build(
        &mesh,
        &ModelSpec {
            material: mat,
            ..Default::default()
        },
        "bar",
    )
    .unwrap();
    let eps = s / mat.young;
    let u: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|x| [eps * x[0], -mat.poisson * eps * x[1], -mat.poisson * eps * x[2]])
        .collect();
    let ns = nodal_stress(&model.solids, model.n_mesh_nodes, &u).unwrap();
    (mesh, ns.stress)
}

#[test]
fn uniaxial_bar_goodman_gerber_closed_form() {
    // Mean 250 MPa, alternating 180 MPa along the bar; 60Si2Mn with a polished surface, no size
    // effect, 50 % reliability: S_e = σ_W = 0.45·1570 MPa.
    let (sm, sa) = (250e6, 180e6);
    let (mesh, mean) = bar_stress(sm);
    let (_, alt) = bar_stress(sa);
    let zero = vec![[0.0; 6]; alt.len()];
    let active = vec![true; alt.len()];
    let mat = FatigueMaterial::builtin("60Si2Mn").unwrap();
    let (se, rm) = (0.45 * 1570e6, 1570e6);
    for (ms, want) in [
        (MeanStress::Goodman, 1.0 / (sa / se + sm / rm)),
        (
            MeanStress::Gerber,
            0.5 * (rm / sm).powi(2) * (sa / se) * (-1.0 + (1.0 + (2.0 * sm * se / (rm * sa)).powi(2)).sqrt()),
        ),
    ] {
        for crit in [Criterion::SignedPrincipal, Criterion::SignedVonMises] {
            let s = FatigueSettings {
                material: mat.clone(),
                condition: PartCondition {
                    rz_um: 0.0,
                    size_mm: None,
                    reliability: 0.5,
                },
                criterion: crit,
                mean_stress: ms,
                cycles: 1e7,
            };
            let f = assess(&s, &mean, &alt, &zero, &active).unwrap();
            for a in 0..f.safety.len() {
                close(&format!("{ms:?} {crit:?} node {a}"), f.safety[a], want, 1e-9);
            }
            let hs = hot_spots(&mesh, &f, 3);
            assert_eq!(hs.len(), 3);
            close("hot spot σ_a", hs[0].sigma_a, sa, 1e-9);
            close("hot spot σ_m", hs[0].sigma_m, sm, 1e-9);
            assert!(!hs[0].group.is_empty());
        }
    }
    // Finite life below the knee: at 1e5 cycles the strength is S_e (1e6/1e5)^(1/5).
    let s = FatigueSettings {
        material: mat,
        condition: PartCondition {
            rz_um: 0.0,
            size_mm: None,
            reliability: 0.5,
        },
        criterion: Criterion::SignedPrincipal,
        mean_stress: MeanStress::Goodman,
        cycles: 1e5,
    };
    let f = assess(&s, &mean, &alt, &zero, &active).unwrap();
    let sn = se * 10f64.powf(0.2);
    close("Basquin strength", f.strength, sn, 1e-12);
    close("Goodman at 1e5", f.safety[0], 1.0 / (sa / sn + sm / rm), 1e-9);
}

#[test]
fn shigley_9th_example_6_10_gerber() {
    // AISI 1050 CD: S_ut = 100 kpsi, S_y = 84 kpsi; 1.5 in bar, 0–16 kip, K_f = 1.85.
    let (sut, sy) = (100.0 * KPSI, 84.0 * KPSI);
    let ka = marin_surface_factor("machined", sut).unwrap();
    close("k_a (book: 0.797)", ka, 0.797, 0.002);
    // k_b = 1 (axial), k_c = 0.85 (axial), S_e' = 0.5 S_ut.
    let se = ka * 0.85 * 0.5 * sut;
    close("S_e (book: 33.9 kpsi)", se / KPSI, 33.9, 0.005);
    let area = std::f64::consts::PI * 1.5f64.powi(2) / 4.0;
    let s = 1.85 * 8.0 / area * KPSI; // σ_a = σ_m = K_f F_a / A, F_a = 8 kip
    close("σ_a (book: 8.38 kpsi)", s / KPSI, 8.38, 0.005);
    close(
        "Gerber n_f (book: 3.66)",
        safety(MeanStress::Gerber, s, s, se, sut, 0.0),
        3.66,
        0.01,
    );
    close("Langer n_y (book: 5.01)", yield_safety(s, s, sy), 5.01, 0.01);
}

#[test]
fn budynas_8th_solutions_manual_springs() {
    // Prob. 10-3: music wire d = 0.105 in, OD = 1.225 in, plain ground ends, N_t = 12.
    let (d, od, nt) = (0.105, 1.225, 12.0);
    let na = nt - 1.0;
    let sut = spring::wire_strength(201.0, 0.145, d);
    close("S_ut (278.7 kpsi)", sut, 278.7, 0.01);
    let ssy = 0.45 * sut;
    let big_d = od - d;
    let c = big_d / d;
    close("C (10.67)", c, 10.67, 0.01);
    let kb = spring::bergstrasser_factor(c);
    close("K_B (1.126)", kb, 1.126, 0.01);
    // F at S_sy from τ = K_B 8FD/(πd³).
    let f_sy = ssy * 1e3 / spring::shear_stress(kb, 1.0, d, big_d);
    close("F at S_sy (45.2 lbf)", f_sy, 45.2, 0.01);
    let k = spring::rate(d, big_d, 11.75e6, na);
    close("k (11.55 lbf/in)", k, 11.55, 0.01);
    // Plain ground: L_s = d N_t; free length such that the spring reaches S_sy at solid.
    let (_, ls, _) = spring::lengths(spring::Ends::PlainGround, d, 0.0, na);
    close("L_s (1.26 in)", ls, 1.26, 0.01);
    let l0 = f_sy / k + ls;
    close("L_0 (5.17 in)", l0, 5.17, 0.01);
    // Prob. 10-4: F_1 = 30 lbf, y_1 = F_1/k = 2.60 in, ξ = y_s/y_1 − 1 = 0.50, from the manual's
    // rounded L_0 = 5.17 in, L_s = 1.26 in and y_1 = 2.60 in (each checked to 1 % above; the
    // unrounded chain gives 0.507, 1.4 % off the printed two digits).
    close("y_1 (2.60 in)", 30.0 / k, 2.60, 0.01);
    let b = spring::binding(5.17, 1.26, 2.60, 0.0, 0.0);
    close("ξ (0.50)", b.overrun, 0.50, 0.01);
    // Prob. 10-24, A313 stainless (A = 169 kpsi·in^m, m = 0.146 for d ≤ 0.1 in; A = 128,
    // m = 0.263 above), S_su = 0.67 S_ut, S_sy = 0.35 S_ut, Goodman–Zimmerli with unpeened
    // S_sa = 35, S_sm = 55 kpsi.
    let table = [
        (0.080, 169.0, 0.146, 244.363, 163.723, 85.527, Some(52.706)),
        (0.0915, 169.0, 0.146, 239.618, 160.544, 83.866, Some(53.239)),
        (0.1055, 128.0, 0.263, 231.257, 154.942, 80.940, None),
        (0.1205, 128.0, 0.263, 223.311, 149.618, 78.159, None),
    ];
    for (d, a, m, sut_w, ssu_w, ssy_w, sse_w) in table {
        let sut = spring::wire_strength(a, m, d);
        close(&format!("S_ut d = {d}"), sut, sut_w, 1e-4);
        let ssu = spring::torsional_ultimate(sut);
        close(&format!("S_su d = {d}"), ssu, ssu_w, 1e-4);
        close(&format!("S_sy d = {d}"), 0.35 * sut, ssy_w, 1e-4);
        if let Some(w) = sse_w {
            let (ssa, ssm) = spring::ZIMMERLI_UNPEENED;
            let sse = spring::zimmerli_endurance(spring::SpringCriterion::Goodman, ssa / KPSI, ssm / KPSI, ssu);
            // Zimmerli's data in SI (241, 379 MPa) round the book's 35 and 55 kpsi by 0.1 %.
            close(&format!("S_se d = {d}"), sse, w, 0.005);
        }
    }
}

#[test]
fn fkm_roughness_worked_example() {
    close("K_R (0.79)", roughness_factor(100.0, 600e6), 0.79, 0.005);
}

/// The hot spot of a clamped cantilever (hex20, guided nowhere: tip force) read at a distance
/// D = L/6 from the clamp, at three mesh levels (each a node row at D): it converges (each
/// refinement changes it less than half as much as the one before, the last by under 2.5 %),
/// and lies within 4 % of beam theory σ = 6F(L − D)/(b h²) there (the hot spot is at the free
/// edge of the wide leaf, where the anticlastic curvature the plate's width restrains elsewhere
/// raises the stress by a few per cent over the beam value). The value on the clamp face itself is printed: it
/// is the singular one the distance avoids.
#[test]
fn clamp_hot_spot_converges() {
    use vibrofem::analysis::statics::{Load, StaticOptions, run_static};
    let (l, b, h, f) = (0.169, 0.146, 0.009, 1000.0);
    let dist = l / 6.0;
    let mut at_distance = vec![];
    for (level, div) in [[6, 2, 1], [12, 4, 2], [24, 8, 4]].into_iter().enumerate() {
        let mesh = box_mesh(CellKind::Hex20, [l, b, h], div);
        let spec = ModelSpec {
            material: Material::steel(),
            fixes: vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)],
            ..Default::default()
        };
        let run = run_static(
            &mesh,
            "cantilever",
            &StaticOptions {
                spec,
                cases: vec![vec![Load::Force {
                    group: "xmax".into(),
                    force: [0.0, 0.0, f],
                }]],
            },
        )
        .unwrap();
        let n = run.model.n_mesh_nodes;
        let u: Vec<f64> = (0..n)
            .flat_map(|a| (0..3).map(move |c| (a, c)))
            .map(|(a, c)| run.u[0][vibrofem::dof::NCOMP * a + c])
            .collect();
        let ns = nodal_stress(&run.model.solids, n, &u).unwrap();
        let zero = vec![[0.0; 6]; n];
        let far: Vec<bool> = mesh.nodes.iter().map(|x| x[0] >= dist * (1.0 - 1e-9)).collect();
        let s = FatigueSettings {
            material: FatigueMaterial::builtin("60Si2Mn").unwrap(),
            condition: PartCondition {
                rz_um: 0.0,
                size_mm: None,
                reliability: 0.5,
            },
            criterion: Criterion::SignedPrincipal,
            mean_stress: MeanStress::Goodman,
            cycles: 1e9,
        };
        let fa = assess(&s, &zero, &ns.stress, &zero, &far).unwrap();
        let hs = hot_spots(&mesh, &fa, 1);
        let all = vec![true; n];
        let clamp = hot_spots(&mesh, &assess(&s, &zero, &ns.stress, &zero, &all).unwrap(), 1);
        eprintln!(
            "level {level}: hot spot at D {:.3} MPa (x = {:.4} m), on the clamp {:.3} MPa",
            hs[0].sigma_a / 1e6,
            hs[0].coords[0],
            clamp[0].sigma_a / 1e6
        );
        at_distance.push(hs[0].sigma_a);
    }
    let beam = 6.0 * f * (l - dist) / (b * h * h);
    let (d1, d2) = (
        (at_distance[1] - at_distance[0]).abs(),
        (at_distance[2] - at_distance[1]).abs(),
    );
    assert!(
        d2 <= 0.5 * d1 && d2 < 0.025 * at_distance[2],
        "not converging: {at_distance:?}"
    );
    close("hot spot at D against beam theory", at_distance[2], beam, 0.04);
}
