//! The 3D machine (issue 13, item 2): the condensed leaf against its FE model, the general
//! spring element's input checks, and the machine with a rigid table against the lumped
//! two-mass model.

use vibrofem::app::design::{Design, coil_fe, leaf_fe};
use vibrofem::app::design::{analyse, coil_stiffness, leaf_end_stiffness, leaf_matrix};
use vibrofem::app::dynamics::electromagnet::RectifiedDrive;
use vibrofem::app::dynamics::two_mass::TwoMass;

/// The FE leaf of `d` clamped at `xmin`, its `xmax` face rigidly coupled (guided along `guided`
/// if given).
fn leaf_spec(d: &Design, guided: Option<usize>) -> vibrofem::model::ModelSpec {
    let l = &d.leaf;
    vibrofem::model::ModelSpec {
        material: vibrofem::material::Material {
            young: l.material[0],
            poisson: l.material[1],
            density: l.material[2],
        },
        fixes: vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)],
        couplings: vec![vibrofem::model::CouplingSpec {
            group: "xmax".into(),
            guided,
            reference: None,
        }],
        ..Default::default()
    }
}

#[test]
fn condensed_leaf_reproduces_the_fe_leaf() {
    let d = Design::paper();
    let h = 0.009;
    let kbb = leaf_end_stiffness(&d, h).unwrap();
    let (k_leaf, _) = leaf_fe(&d, h).unwrap();
    let l = &d.leaf;
    let mesh =
        vibrofem::mesh::generate::try_box_mesh(vibrofem::mesh::CellKind::Hex20, [l.length, l.width, h], l.divisions)
            .unwrap();
    // The guided stiffness is the condensed matrix's vertical entry. Reference: a static run of
    // the same FE leaf with its end guided (moving only vertically, not rotating) under 1000 N:
    // the same linear FE solution reached another way (a load on a guided end there, the
    // inverse of the end's flexibility here), so they agree to solver rounding; 1e-6 has room.
    let guided = vibrofem::analysis::statics::run_static(
        &mesh,
        "leaf (guided)",
        &vibrofem::analysis::statics::StaticOptions {
            spec: leaf_spec(&d, Some(2)),
            cases: vec![vec![vibrofem::analysis::statics::Load::Force {
                group: "xmax".into(),
                force: [0.0, 0.0, 1000.0],
            }]],
        },
    )
    .unwrap();
    let k_guided = 1000.0 / guided.cases[0].references[0].displacement[2];
    for k in [kbb[2][2], k_leaf] {
        assert!((k - k_guided).abs() / k_guided < 1e-6, "{k} vs {k_guided}");
    }
    // A general load on the free end (force in y and z, the end face rigid but free to rotate)
    // gives, through the condensed 6×6, the FE leaf's displacement and rotations.
    let spec = leaf_spec(&d, None);
    let f = [200.0, 300.0, 1000.0];
    let run = vibrofem::analysis::statics::run_static(
        &mesh,
        "leaf",
        &vibrofem::analysis::statics::StaticOptions {
            spec,
            cases: vec![vec![vibrofem::analysis::statics::Load::Force {
                group: "xmax".into(),
                force: f,
            }]],
        },
    )
    .unwrap();
    let u_fe = run.cases[0].references[0].displacement;
    let k = nalgebra::Matrix6::from_fn(|i, j| kbb[i][j]);
    let u = k
        .lu()
        .solve(&nalgebra::Vector6::new(f[0], f[1], f[2], 0.0, 0.0, 0.0))
        .unwrap();
    // Translations against the largest translation, rotations against the largest rotation:
    // both are the same linear FE solution, so 1e-6 bounds solver rounding with room.
    let (tmax, rmax) = (
        u_fe[..3].iter().fold(0.0f64, |a, v| a.max(v.abs())),
        u_fe[3..].iter().fold(0.0f64, |a, v| a.max(v.abs())),
    );
    for c in 0..6 {
        let scale = if c < 3 { tmax } else { rmax };
        assert!(
            (u[c] - u_fe[c]).abs() < 1e-6 * scale,
            "component {c}: {} vs {}",
            u[c],
            u_fe[c]
        );
    }
    // The 12×12 strains nothing in a rigid motion (rotation about z moves the end sideways).
    let k12 = leaf_matrix(&kbb, l.length);
    let t = vibrofem::model::rigid_offset([l.length, 0.0, 0.0]);
    let mut rigid = [0.0; 12];
    rigid[5] = 1e-3;
    for i in 0..6 {
        rigid[6 + i] = t[i][5] * 1e-3;
    }
    let kmax = k12.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for i in 0..12 {
        let fi: f64 = (0..12).map(|j| k12[i * 12 + j] * rigid[j]).sum();
        assert!(fi.abs() < 1e-9 * kmax, "row {i}: {fi}");
    }
}

#[test]
fn coil_isolator_axial_and_lateral_stiffness() {
    let d = Design::paper();
    let (ax, lat) = coil_stiffness(&d).unwrap();
    // Axial: the same guided helix as the design chain's coil model.
    let k = coil_fe(&d).unwrap();
    assert!((ax - k).abs() / k < 1e-9, "{ax} vs {k}");
    // Lateral, both ends parallel: the spring as an equivalent column of height H = n·p with
    // bending stiffness B = 2H/(nπD(1/EI + 1/GJ)) and shear stiffness S = 8EI·H/(πnD³)
    // (Haringx): 1/k = H³/(12B) + H/S. The formula ignores the helix angle (5.7°) and the wire's
    // axial and shear compliance, which the axial stiffness shows at 1.5 %; 5 % covers them.
    let c = &d.coil;
    let e = 2.0 * c.shear_modulus * 1.3;
    let i = std::f64::consts::PI * c.wire.powi(4) / 64.0;
    let (ei, gj) = (e * i, c.shear_modulus * 2.0 * i);
    let hgt = c.turns * c.pitch;
    let n = c.turns;
    let dm = c.mean_diameter;
    let b = 2.0 * hgt / (n * std::f64::consts::PI * dm * (1.0 / ei + 1.0 / gj));
    let s = 8.0 * ei * hgt / (std::f64::consts::PI * n * dm.powi(3));
    let k_hand = 1.0 / (hgt.powi(3) / (12.0 * b) + hgt / s);
    assert!((lat - k_hand).abs() / k_hand < 0.05, "{lat} vs {k_hand}");
}

#[test]
fn general_spring_matrices_are_checked() {
    use vibrofem::model::{CouplingSpec, Model, ModelSpec, SpringMatrixSpec};
    let mesh = vibrofem::mesh::generate::box_mesh(vibrofem::mesh::CellKind::Hex8, [0.2, 0.1, 0.1], [2, 1, 1]);
    let spec = |k: Vec<f64>| ModelSpec {
        couplings: vec![CouplingSpec {
            group: "xmax".into(),
            guided: None,
            reference: None,
        }],
        spring_matrices: vec![SpringMatrixSpec {
            a: "xmax".into(),
            b: None,
            k,
            label: "mount".into(),
        }],
        ..Default::default()
    };
    let mut k = vec![0.0; 36];
    k[0] = 1e6;
    k[1] = 5e5;
    let e = Model::build(&mesh, &spec(k.clone()), "box").err().unwrap().to_string();
    assert!(e.contains("mount") && e.contains("not symmetric"), "{e}");
    k[6] = 5e5;
    k[7] = 1e5; // det < 0: indefinite
    let e = Model::build(&mesh, &spec(k.clone()), "box").err().unwrap().to_string();
    assert!(e.contains("positive semi-definite"), "{e}");
    let e = Model::build(&mesh, &spec(vec![0.0; 144]), "box")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("36 entries"), "{e}");
    k[7] = 1e6;
    Model::build(&mesh, &spec(k), "box").unwrap();
}

#[test]
fn rigid_symmetric_machine_equals_the_two_mass_model() {
    let mut d = Design::paper();
    d.machine.table_model = "rigid".into();
    // Issue 29: the paper's force law, and the magnets' stiffness −2P̄/δ in both models.
    d.drive.force_law = "paper".into();
    let h = 0.0099;
    let r = analyse(&d, h).unwrap();
    // The two-mass model of the same parts: m1 = table + active extras, c12 = n·k_c·k_zz,
    // c13 = n·k_axial, the same dashpots and the same first harmonic of the drive.
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
    let w = r.working.expect("a working mode");
    let fw = r.modes[w].frequency_hz;
    // Symmetric springs and forces: vertical motion decouples exactly into the two-mass system
    // (rounding only), so 1e-6 on frequency.
    assert!((fw - f2).abs() / f2 < 1e-6, "working {fw} vs two-mass {f2}");
    let bounce = r
        .modes
        .iter()
        .find(|m| m.name == "isolation: bounce")
        .expect("a bounce mode");
    assert!(
        (bounce.frequency_hz - f1).abs() / f1 < 1e-6,
        "{} vs {f1}",
        bounce.frequency_hz
    );
    // The forced response: the 12-DOF machine is solved in its full modal basis with the full
    // modal damping matrix, i.e. exactly; the amplitude is uniform on a rigid table.
    let omega = std::f64::consts::TAU * d.excitation_hz;
    let force = RectifiedDrive::from_magnets(d.drive.magnets, d.drive.pull, omega / 2.0)
        .unwrap()
        .harmonic_amplitude();
    let ss = tm.steady_state(omega, force).unwrap();
    assert!(
        (r.mean - ss.amp1()).abs() / ss.amp1() < 1e-6,
        "{} vs {}",
        r.mean,
        ss.amp1()
    );
    assert!(
        (r.reactive_amplitude - ss.amp2()).abs() / ss.amp2() < 1e-6,
        "{} vs {}",
        r.reactive_amplitude,
        ss.amp2()
    );
    assert!(r.nonuniformity < 1e-6, "{}", r.nonuniformity);
    // Listed up to 3 × the excitation: the two bodies' 12 modes less the stiff ones on the
    // leaves' in-plane and axial stiffness.
    assert!(!r.modes.is_empty() && r.modes.len() <= 12);
}

#[test]
fn machine_layout_errors_name_the_key() {
    let mut d = Design::paper();
    d.machine.leaves.pop();
    let e = d.validate().err().unwrap().to_string();
    assert!(e.contains("machine.leaves") && e.contains("leaf.count"), "{e}");
    let mut d = Design::paper();
    d.machine.table_model = "solid".into();
    let e = d.validate().err().unwrap().to_string();
    assert!(e.contains("machine.table_model"), "{e}");
    let mut d = Design::paper();
    d.machine.magnets[0] = [5.0, 5.0];
    let e = analyse(&d, 0.0099).err().unwrap().to_string();
    assert!(e.contains("machine.magnets") && e.contains("magnet 1"), "{e}");
}

#[test]
fn channel_spacers_add_their_flanges() {
    // Channel No. 10 (GOST 8240): flanges 46 × 7.6 mm on both plates along each of the three
    // longitudinal webs; the flange strips' equivalent thickness keeps the steel's mass exact.
    use vibrofem::app::design::table_mass;
    let d = Design::paper();
    let mut c = d.clone();
    c.spacers = "channel10".into();
    let added = table_mass(&c).unwrap() - table_mass(&d).unwrap();
    let want = 3.0 * 2.0 * 0.046 * 0.0076 * 1.2 * 7850.0;
    assert!((added - want).abs() < 1e-9 * want, "{added} vs {want}");
    let e = {
        let mut b = d.clone();
        b.spacers = "channel8".into();
        b.validate().err().unwrap().to_string()
    };
    assert!(e.contains("spacers"), "{e}");
}

/// The paper design with a search over two table variants (3 transverse webs, top 20 and 16 mm),
/// one run whole at most: the table search alone, at the nominal point (issue 29 added pulls,
/// leaf moves, a margin and the envelope to the defaults).
fn two_variant_search() -> Design {
    let mut d = Design::paper();
    d.search.top_thickness = vec![0.02, 0.016];
    d.search.bottom_thickness = vec![0.008];
    d.search.bottom_width = vec![0.4];
    d.search.long_web_span = vec![0.3];
    d.search.n_long_webs = vec![3];
    d.search.n_trans_webs = vec![3];
    d.search.spacers = vec!["plates".into()];
    d.search.max_full_runs = 1;
    d.search.pull = vec![];
    d.search.leaf_shift = vec![0.0];
    d.search.required_margin = 0.0;
    d.search.over_envelope = false;
    d
}

#[test]
fn search_reports_the_lightest_passing_variant() {
    use vibrofem::app::design::search;
    // Two table variants (3 transverse webs, top 16 and 20 mm): both reach the amplitude and
    // the first-mode limit. With the given 10 % uniformity limit neither passes (their
    // work-surface amplitude varies by about 15 % with the reconstruction's leaf layout); with
    // a 20 % limit the lighter one passes and is the one reported.
    let mut d = two_variant_search();
    let o = search(&d, None, &|_| {}).unwrap();
    assert_eq!(o.candidates.len(), 2);
    assert!(o.candidates[0].mass_kg < o.candidates[1].mass_kg, "lightest first");
    assert!(o.best.is_none());
    let failed = o.candidates[0].failed.as_ref().unwrap();
    assert!(failed.iter().all(|f| f.starts_with("surface_uniformity")), "{failed:?}");
    d.machine.max_nonuniformity = 0.2;
    let o = search(&d, None, &|_| {}).unwrap();
    let (v, r) = o.best.expect("a passing variant");
    assert!(v.name.starts_with("top 16 mm"), "{}", v.name);
    assert!(r.checks.iter().all(|c| c.ok), "{:?}", r.checks);
    assert_eq!(o.spacer_effect.len(), 2);
}

#[test]
fn passing_variant_folder_holds_only_a_passing_variant() {
    // The design job's search runs variants whole, each writing its plots; the folder
    // `passing-variant/` must appear only when one passes (with its report), and an earlier
    // run's must not stay beside a report whose search found none. Same two variants as above:
    // neither passes at the 10 % uniformity limit, the lighter one at 20 %.
    use vibrofem::app::design::job;
    let mut d = two_variant_search();
    d.envelope.enabled = false;
    let out = crate::support::tmp("passing_variant");
    let vdir = out.join("passing-variant");
    std::fs::create_dir_all(&vdir).unwrap();
    std::fs::write(vdir.join("report.md"), "an earlier run's variant").unwrap();
    let j = job::run(&d, &out, &|_| {}).unwrap();
    let (o, _, _) = j.search.as_ref().expect("the nominal design fails: the search runs");
    assert!(o.best.is_none() && j.variant.is_none());
    assert!(!vdir.exists(), "no variant passed, yet {} is there", vdir.display());
    assert!(!out.join("passing-variant.partial").exists());
    assert!(out.join("search.txt").is_file() && out.join("report.md").is_file());
    d.machine.max_nonuniformity = 0.2;
    let j = job::run(&d, &out, &|_| {}).unwrap();
    assert!(j.variant.is_some());
    let report = std::fs::read_to_string(vdir.join("report.md")).unwrap();
    assert!(report.contains("top 16 mm"), "{}", &report[..report.len().min(400)]);
    assert!(vdir.join("table_modes.vtu").is_file());
    assert!(!out.join("passing-variant.partial").exists());
    let _ = std::fs::remove_dir_all(&out);
}
