//! Statics against scikit-fem on the same meshes with the same elements
//! (`validation/reference/static_*.json`, from `validation/skfem_static.py`): hex20 ↔ ElementHexS2
//! and tet10 ↔ ElementTetP2, exact quadrature on both sides, so both solve the same discrete
//! problem. Displacements must agree to 1e-8 of the largest displacement (both linear solves
//! reach ~1e-12; 1e-8 leaves room for their different orderings), reactions to 1e-8 of the
//! largest force, and the nodal von Mises stresses (same recovery: direct evaluation at the
//! element nodes, averaged) to 1e-7 of the peak.

use vibrofem::analysis::statics::{Load, StaticOptions, run_static};
use vibrofem::dof::TRANSLATIONS;
use vibrofem::io::gmsh;
use vibrofem::material::Material;
use vibrofem::model::ModelSpec;
use vibrofem::post::stress::nodal_stress;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

#[test]
fn statics_match_scikit_fem_on_the_same_meshes() {
    let dir = format!("{ROOT}/validation/reference");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("static_"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "static references missing in {dir}");
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
        let mesh = gmsh::read(
            std::path::Path::new(&format!("{ROOT}/{}", r["mesh"].as_str().unwrap())),
            1.0,
        )
        .unwrap();
        let m = &r["material"];
        let mut spec = ModelSpec {
            material: Material {
                young: m["young"].as_f64().unwrap(),
                poisson: m["poisson"].as_f64().unwrap(),
                density: m["density"].as_f64().unwrap(),
            },
            ..Default::default()
        };
        let mut loads = Vec::new();
        for bc in r["bcs"].as_array().unwrap() {
            let g = bc["group"].as_str().unwrap().to_string();
            match bc["type"].as_str().unwrap() {
                "fixed" => spec.fixes.push((g, TRANSLATIONS)),
                "displacement" => {
                    let v: Vec<f64> = bc["value"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .collect();
                    spec.prescribed
                        .push((g, [Some(v[0]), Some(v[1]), Some(v[2]), None, None, None]));
                }
                "traction" => {
                    let v: Vec<f64> = bc["total_force"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .collect();
                    loads.push(Load::Force {
                        group: g,
                        force: [v[0], v[1], v[2]],
                    });
                }
                t => panic!("{name}: unknown bc type {t}"),
            }
        }
        let run = run_static(
            &mesh,
            &name,
            &StaticOptions {
                spec,
                cases: vec![loads],
            },
        )
        .unwrap();
        let uref = r["displacement"].as_array().unwrap();
        assert_eq!(uref.len(), mesh.n_nodes(), "{name}");
        let u = &run.u[0];
        let mut umax = 0.0f64;
        let mut err = 0.0f64;
        for (a, ur) in uref.iter().enumerate() {
            for c in 0..3 {
                let want = ur[c].as_f64().unwrap();
                umax = umax.max(want.abs());
                err = err.max((u[vibrofem::dof::NCOMP * a + c] - want).abs());
            }
        }
        assert!(
            err <= 1e-8 * umax,
            "{name}: displacement differs by {err:.3e} (max {umax:.3e})"
        );
        // Reactions per fixed or prescribed group.
        let fmax = r["reactions"]
            .as_object()
            .unwrap()
            .values()
            .flat_map(|v| v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap().abs()))
            .fold(0.0f64, f64::max);
        for re in &run.cases[0].reactions {
            if let Some(want) = r["reactions"].get(&re.group) {
                for c in 0..3 {
                    let w = want[c].as_f64().unwrap();
                    assert!(
                        (re.resultant.force[c] - w).abs() <= 1e-8 * fmax,
                        "{name}: reaction {} {c}",
                        re.group
                    );
                }
            }
        }
        // Nodal von Mises.
        let u3: Vec<f64> = (0..mesh.n_nodes())
            .flat_map(|a| (0..3).map(move |c| (a, c)))
            .map(|(a, c)| u[7 * a + c])
            .collect();
        let ns = nodal_stress(&run.model.solids, mesh.n_nodes(), &u3).unwrap();
        let vref: Vec<f64> = r["stress"]["von_mises"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let vmax = vref.iter().fold(0.0f64, |a, &b| a.max(b));
        let verr = ns
            .von_mises
            .iter()
            .zip(&vref)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, f64::max);
        assert!(
            verr <= 1e-7 * vmax,
            "{name}: von Mises differs by {verr:.3e} (peak {vmax:.3e})"
        );
        eprintln!(
            "{name}: |Δu| {:.1e} of max, |Δσ_vM| {:.1e} of peak",
            err / umax,
            verr / vmax
        );
    }
}
