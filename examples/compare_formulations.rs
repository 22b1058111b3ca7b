//! Formulation comparisons for scenes S1, S2, S5, S6 and S7: shells, beams and solids on the
//! same parts, with DOFs, wall time, values and errors against the converged or published
//! reference. Prints markdown tables (the source of docs/formulations.md).
//!
//! ```sh
//! cargo run --release --example compare_formulations            # every scene, ~1–2 min on 2 cores
//! cargo run --release --example compare_formulations -- s6 s7   # selected: obstacles, s1, s5, s6, s7
//! ```

use std::collections::HashMap;
use std::f64::consts::PI;
use std::time::Instant;

use vibrofem::analysis::modal::{ModalOptions, ModalRun, ModalTarget, run_modal};
use vibrofem::analysis::statics::{Load, StaticOptions, run_static};
use vibrofem::dof::ALL6;
use vibrofem::material::Material;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::mesh::parametric::{
    HelixParams, SandwichParams, helix_beam, helix_orientations, i_beam_line, i_beam_shell, i_beam_solid,
    i_beam_thicknesses, sandwich_table, sandwich_table_solid,
};
use vibrofem::mesh::{CellBlock, CellKind, CellRef, Group, Mesh};
use vibrofem::model::{BeamPart, CouplingSpec, Model, ModelSpec, Orientation, ShellPart};
use vibrofem::post::mass::group_mass_properties;
use vibrofem::section::{BeamSection, ShellSection};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// A verified modal run: the lowest `n` modes.
fn modal(mesh: &Mesh, spec: ModelSpec, n: usize) -> Res<(ModalRun, f64)> {
    let t = Instant::now();
    let run = run_modal(
        mesh,
        "compare",
        &ModalOptions {
            spec,
            target: ModalTarget::Modes(n),
            ..Default::default()
        },
        0.0,
    )?;
    let dt = t.elapsed().as_secs_f64();
    if !(run.report.complete && run.report.accurate) {
        return Err(format!("unverified modal run: {:?}", run.report.notes).into());
    }
    Ok((run, dt))
}

fn pct(v: f64, r: f64) -> String {
    format!("{:+.2} %", 100.0 * (v / r - 1.0))
}

fn shell_parts(list: &[(String, f64)], offset: impl Fn(f64) -> f64) -> Vec<ShellPart> {
    list.iter()
        .map(|(g, t)| ShellPart {
            group: g.clone(),
            section: ShellSection::new(*t).with_offset(offset(*t)),
            material: None,
        })
        .collect()
}

/// A plate `a × b × t` as MITC4 shells on `box_mesh`'s `zmin` face (normal −z): the offset
/// `+t/2` puts the mid-surface at `z = t/2`.
fn plate_shell(a: f64, b: f64, t: f64, nx: usize, ny: usize, mat: Material) -> (Mesh, ModelSpec) {
    let mesh = box_mesh(CellKind::Hex8, [a, b, t], [nx, ny, 1]);
    let spec = ModelSpec {
        material: mat,
        shells: shell_parts(&[("zmin".to_string(), t)], |t| 0.5 * t),
        ..Default::default()
    };
    (mesh, spec)
}

/// Metres to millimetres, rounded to 0.1 mm without a negative zero.
fn mm(v: f64) -> f64 {
    let r = (v * 1e4).round() / 10.0;
    if r == 0.0 { 0.0 } else { r }
}

fn steel(nu: f64) -> Material {
    Material {
        poisson: nu,
        ..Material::steel()
    }
}

// ---------------------------------------------------------------------------------------------
// S1, S2

fn s1_s2() -> Res<()> {
    println!("## S1 and S2: plates as MITC4 shells against the converged solids\n");
    println!(
        "Free–free, mode 7. Shells on the `zmin` face of `box_mesh(Hex8, …, [n, m, 1])` with offset +t/2 (the \
         mid-surface). References: converged hex20 solids (docs/validation.md): S1 720.43 Hz (ν = 0.3), 725.59 Hz (ν = 0.28); \
         S2 722.67 Hz. Solid rows are run here for the cost comparison.\n"
    );
    println!("| scene | model | mesh | DOFs | f7 [Hz] ν = 0.3 | error | f7 [Hz] ν = 0.28 | error | time [s] |");
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|");
    for (n, mesh_n) in [(10, "10×10"), (20, "20×20"), (30, "30×30"), (60, "60×60")] {
        let (m, s) = plate_shell(0.3, 0.3, 0.02, n, n, steel(0.3));
        let (r3, dt) = modal(&m, s, 7)?;
        let (m, s) = plate_shell(0.3, 0.3, 0.02, n, n, steel(0.28));
        let (r28, _) = modal(&m, s, 7)?;
        let (f3, f28) = (r3.report.frequencies_hz[6], r28.report.frequencies_hz[6]);
        println!(
            "| S1 | shell MITC4 | {mesh_n} | {} | {f3:.2} | {} | {f28:.2} | {} | {dt:.2} |",
            r3.report.dofs,
            pct(f3, 720.43),
            pct(f28, 725.59)
        );
    }
    for (n, nz) in [(10, 2), (20, 4)] {
        let m = box_mesh(CellKind::Hex20, [0.3, 0.3, 0.02], [n, n, nz]);
        let (r, dt) = modal(&m, ModelSpec::default(), 7)?;
        let f = r.report.frequencies_hz[6];
        println!(
            "| S1 | solid hex20 | {n}×{n}×{nz} | {} | {f:.2} | {} | | | {dt:.2} |",
            r.report.dofs,
            pct(f, 720.43)
        );
    }
    for (nx, ny) in [(18, 8), (36, 16), (72, 32)] {
        let (m, s) = plate_shell(0.9, 0.4, 0.116, nx, ny, steel(0.3));
        let (r, dt) = modal(&m, s, 7)?;
        let f = r.report.frequencies_hz[6];
        let (m, s) = plate_shell(0.9, 0.4, 0.116, nx, ny, steel(0.28));
        let (r28, _) = modal(&m, s, 7)?;
        let f28 = r28.report.frequencies_hz[6];
        println!(
            "| S2 | shell MITC4 | {nx}×{ny} | {} | {f:.2} | {} | {f28:.2} | {} | {dt:.2} |",
            r.report.dofs,
            pct(f, 722.67),
            pct(f28, 722.67)
        );
    }
    let m = box_mesh(CellKind::Hex20, [0.9, 0.4, 0.116], [18, 8, 2]);
    let (r, dt) = modal(&m, ModelSpec::default(), 7)?;
    let f = r.report.frequencies_hz[6];
    println!(
        "| S2 | solid hex20 | 18×8×2 | {} | {f:.2} | {} | | | {dt:.2} |\n",
        r.report.dofs,
        pct(f, 722.67)
    );
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// S5

/// Axial stiffness (N/m) of the S5 coil as a beam helix: bottom end clamped, top end guided
/// along z (no rotation, no lateral motion) and loaded by 600 N. Returns (k, DOFs, time).
fn coil_stiffness(kind: CellKind, per_turn: usize) -> Res<(f64, usize, f64)> {
    let p = HelixParams {
        kind,
        elems_per_turn: per_turn,
        ..HelixParams::paper()
    };
    let mesh = helix_beam(&p)?;
    let g = 7.7e10;
    let e = 2.0e11;
    let spec = ModelSpec {
        material: Material {
            young: e,
            poisson: e / (2.0 * g) - 1.0,
            density: 7850.0,
        },
        beams: vec![BeamPart {
            group: "wire".into(),
            section: BeamSection::circle(p.wire_diameter),
            orientation: Orientation::Radial {
                centre: [0.0; 3],
                axis: [0.0, 0.0, 1.0],
            },
            material: None,
        }],
        fixes: vec![("end_bottom".into(), ALL6)],
        couplings: vec![CouplingSpec {
            group: "end_top".into(),
            guided: Some(2),
            reference: None,
        }],
        ..Default::default()
    };
    let _ = helix_orientations(&p)?; // the radial orientation equals these at element midpoints
    let t = Instant::now();
    let run = run_static(
        &mesh,
        "coil",
        &StaticOptions {
            spec,
            cases: vec![vec![Load::Force {
                group: "end_top".into(),
                force: [0.0, 0.0, -600.0],
            }]],
        },
    )?;
    let dt = t.elapsed().as_secs_f64();
    let k = run.cases[0].references[0].stiffness.ok_or("no stiffness")?;
    Ok((k.abs(), run.dofs, dt))
}

fn s5() -> Res<()> {
    println!("## S5: coil spring as a beam along the helix\n");
    let p = HelixParams::paper();
    let (d, dm, g) = (p.wire_diameter, p.mean_diameter, 7.7e10);
    let k_hand = |i: f64| g * d.powi(4) / (8.0 * dm.powi(3) * i);
    println!(
        "d = 6 mm, D = 32 mm, 6 active turns, pitch 10 mm, G = 7.7e10 Pa (E = 2.0e11 Pa). Bottom end clamped, top \
         end guided along the axis (rigid coupling, no rotation), Q = 600 N. Hand formula k = G d⁴/(8 D³ i): \
         {:.0} N/m at i = 6 (deflection {:.2} mm), {:.0} N/m at i = 6.3 (the scene's value, {:.2} mm). Published \
         FE: 9.96 mm.\n",
        k_hand(6.0),
        600.0 / k_hand(6.0) * 1e3,
        k_hand(6.3),
        600.0 / k_hand(6.3) * 1e3
    );
    let c = dm / d;
    let k_shear = |i: f64| k_hand(i) / (1.0 + 0.5 / (c * c));
    println!(
        "With the direct-shear term (Wahl; Shigley eq. 10-8), δ = 8QD³i/(Gd⁴)·(1 + 1/(2C²)), C = D/d: {:.0} N/m at \
         i = 6.\n",
        k_shear(6.0)
    );
    println!(
        "| element | per turn | DOFs | k [N/m] | vs hand (i = 6) | vs hand + shear | deflection at 600 N [mm] | vs \
         finest | time [s] |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut rows = vec![];
    for kind in [CellKind::Line2, CellKind::Line3] {
        for n in [12, 24, 48] {
            rows.push((kind, n, coil_stiffness(kind, n)?));
        }
    }
    let finest = rows.last().map(|r| r.2.0).unwrap_or(1.0);
    for (kind, n, (k, dofs, dt)) in rows {
        println!(
            "| {} | {n} | {dofs} | {k:.0} | {} | {} | {:.3} | {} | {dt:.3} |",
            kind.name(),
            pct(k, k_hand(6.0)),
            pct(k, k_shear(6.0)),
            600.0 / k * 1e3,
            pct(600.0 / k, 600.0 / finest)
        );
    }
    println!();
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// S6

/// Labels the elastic modes of a beam-like part along x (section centroid on the x axis):
/// `V` bending in x–z (strong axis), `L` bending in x–y, `T` torsion, `A` axial, numbered
/// per family. Beam models have their nodes on the axis, where torsion moves nothing: a mode
/// with (numerically) zero translations is torsion.
fn classify(mesh: &Mesh, run: &ModalRun, first: usize) -> Vec<String> {
    let mut stations: HashMap<i64, Vec<usize>> = HashMap::new();
    for (a, p) in mesh.nodes.iter().enumerate() {
        stations.entry((p[0] * 1e6).round() as i64).or_default().push(a);
    }
    let norms: Vec<f64> = run
        .shapes
        .iter()
        .map(|s| s.iter().map(|v| v * v).sum::<f64>())
        .collect();
    let max_norm = norms.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut counts: HashMap<char, usize> = HashMap::new();
    let mut out = vec![];
    for (m, s) in run.shapes.iter().enumerate().skip(first) {
        let mut score = [0.0f64; 4]; // A, L, V, T
        for nodes in stations.values() {
            let k = nodes.len() as f64;
            let (mut u, mut v, mut w, mut num, mut den) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for &a in nodes {
                let (y, z) = (mesh.nodes[a][1], mesh.nodes[a][2]);
                let d = [s[3 * a], s[3 * a + 1], s[3 * a + 2]];
                u += d[0] / k;
                v += d[1] / k;
                w += d[2] / k;
                num += y * d[2] - z * d[1];
                den += y * y + z * z;
            }
            score[0] += u * u;
            score[1] += v * v;
            score[2] += w * w;
            if den > 0.0 {
                score[3] += (num / den).powi(2) * den / k;
            }
        }
        let c = if norms[m] < 1e-12 * max_norm {
            'T'
        } else {
            let i = (0..4).max_by(|&i, &j| score[i].total_cmp(&score[j])).unwrap_or(0);
            ['A', 'L', 'V', 'T'][i]
        };
        let n = counts.entry(c).or_insert(0);
        *n += 1;
        out.push(format!("{c}{n}"));
    }
    out
}

/// One S6 row: model, mesh, DOFs, mass, labelled modes 7–12, time.
type S6Row = (String, String, usize, f64, Vec<(String, f64)>, f64);

fn s6() -> Res<()> {
    println!("## S6: I-beam GOST 8239 No. 10, L = 1.2 m, free–free\n");
    let (h, b, s, t, l) = (0.1, 0.055, 0.0045, 0.0072, 1.2);
    let sec = BeamSection::gost_8239_i10();
    let mat = Material::steel();
    let eb = |bl: f64, i: f64| bl * bl / (2.0 * PI * l * l) * (mat.young * i / (mat.density * sec.area)).sqrt();
    let gj = mat.shear_modulus() * sec.j;
    let sv = |n: f64| n / (2.0 * l) * (gj / (mat.density * sec.polar())).sqrt();
    println!(
        "Steel, h 100, b 55, s 4.5, t 7.2 mm (fillets ignored). Modes 7–12 labelled L (lateral bending, x–y), V \
         (vertical bending, x–z), T (torsion). Euler–Bernoulli: L1 {:.1}, L2 {:.1}, V1 {:.1} Hz; Saint-Venant \
         torsion without warping: T1 {:.1}, T2 {:.1} Hz. Beam section: J = {:.3} cm⁴, Cw = {:.3} cm⁶.\n",
        eb(4.730041, sec.iz),
        eb(7.853205, sec.iz),
        eb(4.730041, sec.iy),
        sv(1.0),
        sv(2.0),
        sec.j * 1e8,
        sec.cw * 1e12
    );
    let mut rows: Vec<S6Row> = vec![];
    let mut add = |model: &str, mesh_label: String, mesh: &Mesh, spec: ModelSpec| -> Res<()> {
        let (run, dt) = modal(mesh, spec, 12)?;
        let labels = classify(mesh, &run, 6);
        let f = run.report.frequencies_hz[6..12].to_vec();
        rows.push((
            model.to_string(),
            mesh_label,
            run.report.dofs,
            run.report.mass_kg,
            labels.into_iter().zip(f).collect(),
            dt,
        ));
        Ok(())
    };
    for warping in [false, true] {
        for n in [24, 96] {
            let mesh = i_beam_line(l, n)?;
            let spec = ModelSpec {
                beams: vec![BeamPart {
                    group: "beam".into(),
                    section: sec.with_warping(warping),
                    orientation: Orientation::Vector([0.0, 1.0, 0.0]),
                    material: None,
                }],
                ..Default::default()
            };
            let name = if warping { "beam + warping" } else { "beam (no warping)" };
            add(name, format!("{n} line2"), &mesh, spec)?;
        }
    }
    for size in [0.01, 0.005] {
        let mesh = i_beam_shell(h, b, s, t, l, size)?;
        let spec = ModelSpec {
            shells: shell_parts(&i_beam_thicknesses(s, t), |_| 0.0),
            ..Default::default()
        };
        add("shell MITC4", format!("{:.0} mm", size * 1e3), &mesh, spec)?;
    }
    for size in [0.015, 0.01] {
        let mesh = i_beam_solid(h, b, s, t, l, size, CellKind::Hex20)?;
        add(
            "solid hex20",
            format!("{:.0} mm", size * 1e3),
            &mesh,
            ModelSpec::default(),
        )?;
    }
    // Reference: the finest solid, matched by label.
    let reference: HashMap<String, f64> = rows.last().map(|r| r.4.iter().cloned().collect()).unwrap_or_default();
    println!("| model | mesh | DOFs | mass [kg] | mode 7 | mode 8 | mode 9 | mode 10 | mode 11 | mode 12 | time [s] |");
    println!("|---|---|---:|---:|---|---|---|---|---|---|---:|");
    for (model, mesh, dofs, mass, modes, dt) in &rows {
        let cells: Vec<String> = modes
            .iter()
            .map(|(lab, f)| match reference.get(lab) {
                Some(r) => format!("{lab} {f:.1} ({})", pct(*f, *r)),
                None => format!("{lab} {f:.1}"),
            })
            .collect();
        println!(
            "| {model} | {mesh} | {dofs} | {mass:.3} | {} | {dt:.2} |",
            cells.join(" | ")
        );
    }
    println!("\n(errors against the finest solid, same label)\n");
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// S7

/// The S7 table with the plates as shells and the longitudinal webs as beams (rectangle
/// 4.5 × 100 mm, depth vertical) on the webs' centroid lines, each beam node tied to the top
/// and bottom plate nodes above and below it by a rigid coupling (plane sections stay plane
/// across the web; the web's own distortion in the y–z plane is not represented).
fn sandwich_shell_beam(p: &SandwichParams) -> Res<(Mesh, ModelSpec)> {
    let mut mesh = sandwich_table(p)?;
    let hz = p.mid_surface_spacing();
    let zc = 0.5 * p.bottom_thickness + 0.5 * p.web_height;
    let key = |x: f64, y: f64, z: f64| {
        (
            (x * 1e7).round() as i64,
            (y * 1e7).round() as i64,
            (z * 1e7).round() as i64,
        )
    };
    let index: HashMap<(i64, i64, i64), u32> = mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(i, q)| (key(q[0], q[1], q[2]), i as u32))
        .collect();
    let mut xs: Vec<f64> = mesh.nodes.iter().filter(|q| q[2] == 0.0).map(|q| q[0]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut lines = CellBlock::new(CellKind::Line2);
    let mut points = CellBlock::new(CellKind::Point1);
    let mut tag = mesh
        .blocks
        .iter()
        .map(|b| b.tags.iter().copied().max().unwrap_or(0))
        .max()
        .unwrap_or(0);
    let mut next = || {
        tag += 1;
        tag
    };
    let mut links: Vec<(String, Vec<u32>)> = vec![];
    let mut beam_cells = vec![];
    for (w, &y) in p.long_webs.iter().enumerate() {
        let mut prev: Option<u32> = None;
        for (i, &x) in xs.iter().enumerate() {
            let node = mesh.nodes.len() as u32;
            mesh.nodes.push([x, y, zc]);
            mesh.node_tags.push(mesh.nodes.len() as u64);
            let top = *index.get(&key(x, y, hz)).ok_or("no top plate node above a web")?;
            let bot = *index.get(&key(x, y, 0.0)).ok_or("no bottom plate node below a web")?;
            let mut cells = vec![];
            for a in [top, bot, node] {
                cells.push(points.len() as u32);
                points.push(&[a], next());
            }
            links.push((format!("link_{w}_{i}"), cells));
            if let Some(a) = prev {
                beam_cells.push(lines.len() as u32);
                lines.push(&[a, node], next());
            }
            prev = Some(node);
        }
    }
    let (bl, bp) = (mesh.blocks.len() as u32, mesh.blocks.len() as u32 + 1);
    mesh.blocks.push(lines);
    mesh.blocks.push(points);
    let mut gtag = mesh.groups.len() as i32;
    let mut group = |name: String, dim: u8, block: u32, cells: Vec<u32>| {
        gtag += 1;
        Group {
            name,
            dim,
            tag: gtag,
            cells: cells.into_iter().map(|index| CellRef { block, index }).collect(),
        }
    };
    let mut new_groups = vec![group("web_beams".into(), 1, bl, beam_cells)];
    for (name, cells) in &links {
        new_groups.push(group(name.clone(), 0, bp, cells.clone()));
    }
    mesh.groups.extend(new_groups);
    let thick: Vec<(String, f64)> = p
        .thicknesses()
        .into_iter()
        .filter(|(g, _)| g.ends_with("plate"))
        .collect();
    let spec = ModelSpec {
        shells: shell_parts(&thick, |_| 0.0),
        beams: vec![BeamPart {
            group: "web_beams".into(),
            section: BeamSection::rectangle(p.long_web_thickness, p.web_height),
            orientation: Orientation::Vector([0.0, 1.0, 0.0]),
            material: None,
        }],
        couplings: links
            .iter()
            .map(|(g, _)| CouplingSpec {
                group: g.clone(),
                guided: None,
                reference: None,
            })
            .collect(),
        ..Default::default()
    };
    Ok((mesh, spec))
}

/// Grid lines through every coordinate of `required`, each interval split evenly with spacing
/// at most `h` (at least one cell).
fn lines(required: &[f64], h: f64) -> Vec<f64> {
    let mut r = required.to_vec();
    r.sort_by(f64::total_cmp);
    r.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let mut out = vec![r[0]];
    for w in r.windows(2) {
        let n = ((w[1] - w[0]) / h - 1e-9).ceil().max(1.0) as usize;
        for k in 1..=n {
            out.push(w[0] + (w[1] - w[0]) * k as f64 / n as f64);
        }
    }
    out
}

/// The S7 solid (the geometry of `sandwich_table_solid`, longitudinal webs only) on a graded
/// grid: spacing `hx` along the table, `hy` across, `hz` through the web height; the plates
/// and the webs get one cell through their thickness.
fn sandwich_solid_graded(p: &SandwichParams, hx: f64, hy: f64, hz: f64) -> Res<Mesh> {
    if !p.trans_webs.is_empty() {
        return Err("graded solid: transverse webs are not handled".into());
    }
    let (lx, ht, hb) = (0.5 * p.length, 0.5 * p.top_width, 0.5 * p.bottom_width);
    let tl = 0.5 * p.long_web_thickness;
    let z1 = 0.5 * p.bottom_thickness;
    let z2 = z1 + p.web_height;
    let z3 = z2 + p.top_thickness;
    let xl = lines(&[-lx, lx], hx);
    let mut yr = vec![-ht, ht, -hb, hb];
    for &y in &p.long_webs {
        yr.extend([y - tl, y + tl]);
    }
    let yl = lines(&yr, hy);
    let zl: Vec<f64> = [vec![-z1], lines(&[z1, z2], hz), vec![z3]].concat();
    let classify = |c: [f64; 3]| {
        let [_, y, z] = c;
        if z < z1 {
            (y.abs() < hb).then_some(1)
        } else if z > z2 {
            (y.abs() < ht).then_some(0)
        } else if p.long_webs.iter().any(|&w| (y - w).abs() < tl) {
            Some(2)
        } else {
            None
        }
    };
    Ok(vibrofem::mesh::parametric::grid_solid_groups(
        [&xl, &yl, &zl],
        CellKind::Hex20,
        &["top_plate", "bottom_plate", "webs_long"],
        classify,
    )?)
}

/// The S7 shell model with the webs at their real (clear) height, tied to the plates by rigid
/// couplings (`vibrofem::app::design::sandwich_clear_webs`, the design chain's table model).
fn sandwich_shell_clear_webs(p: &SandwichParams) -> Res<(Mesh, ModelSpec)> {
    let (mesh, couplings) = vibrofem::app::design::sandwich_clear_webs(p)?;
    let spec = ModelSpec {
        shells: shell_parts(&p.thicknesses(), |_| 0.0),
        couplings,
        ..Default::default()
    };
    Ok((mesh, spec))
}

fn s7() -> Res<()> {
    println!("## S7: sandwich work table (reconstruction `SandwichParams::paper()`)\n");
    let p = SandwichParams::paper();
    println!(
        "Top plate 1200 × 600 × 25 mm, bottom plate 1200 × 400 × 8 mm, three longitudinal webs 100 mm (clear) × \
         4.5 mm at y = −150, 0, 150 mm; steel; free–free. Real mass {:.2} kg; the mid-surface shell model carries \
         {:.2} kg (junction strips counted twice). Published (the real, tapered table): 163 kg, f7 = 300.82 Hz. \
         Errors against the finest solid.\n",
        p.mass(7850.0),
        p.shell_mass(7850.0)
    );
    let mut rows: Vec<(String, String, usize, f64, Vec<f64>, f64)> = vec![];
    for size in [0.05, 0.025, 0.0125] {
        let q = SandwichParams {
            elem_size: size,
            ..p.clone()
        };
        let mesh = sandwich_table(&q)?;
        let spec = ModelSpec {
            shells: shell_parts(&q.thicknesses(), |_| 0.0),
            ..Default::default()
        };
        let (run, dt) = modal(&mesh, spec, 12)?;
        rows.push((
            "shell MITC4".into(),
            format!("{:.1} mm", size * 1e3),
            run.report.dofs,
            run.report.mass_kg,
            run.report.frequencies_hz[6..12].to_vec(),
            dt,
        ));
    }
    for size in [0.05, 0.025] {
        let q = SandwichParams {
            elem_size: size,
            ..p.clone()
        };
        let (mesh, spec) = sandwich_shell_beam(&q)?;
        let (run, dt) = modal(&mesh, spec, 12)?;
        rows.push((
            "shell plates + beam webs".into(),
            format!("{:.1} mm", size * 1e3),
            run.report.dofs,
            run.report.mass_kg,
            run.report.frequencies_hz[6..12].to_vec(),
            dt,
        ));
    }
    for size in [0.05, 0.025, 0.0125] {
        let q = SandwichParams {
            elem_size: size,
            ..p.clone()
        };
        let (mesh, spec) = sandwich_shell_clear_webs(&q)?;
        let (run, dt) = modal(&mesh, spec, 12)?;
        rows.push((
            "shell, clear-height webs + rigid links".into(),
            format!("{:.1} mm", size * 1e3),
            run.report.dofs,
            run.report.mass_kg,
            run.report.frequencies_hz[6..12].to_vec(),
            dt,
        ));
    }
    for size in [0.05, 0.025] {
        let mesh = sandwich_table_solid(&p, size, CellKind::Hex20)?;
        let (run, dt) = modal(&mesh, ModelSpec::default(), 12)?;
        rows.push((
            "solid hex20".into(),
            format!("{:.1} mm", size * 1e3),
            run.report.dofs,
            run.report.mass_kg,
            run.report.frequencies_hz[6..12].to_vec(),
            dt,
        ));
    }
    for (hx, hy, hz) in [(0.05, 0.025, 0.025), (0.05, 0.025, 0.0125), (0.05, 0.0125, 0.00625)] {
        let mesh = sandwich_solid_graded(&p, hx, hy, hz)?;
        let (run, dt) = modal(&mesh, ModelSpec::default(), 12)?;
        rows.push((
            "solid hex20 graded".into(),
            format!("{:.1}/{:.1}/{:.2} mm", hx * 1e3, hy * 1e3, hz * 1e3),
            run.report.dofs,
            run.report.mass_kg,
            run.report.frequencies_hz[6..12].to_vec(),
            dt,
        ));
    }
    let reference = rows.last().map(|r| r.4.clone()).unwrap_or_default();
    println!("Mode 7 is the table's torsion with racking (the top plate twists over the bottom plate, the webs bend");
    println!(
        "across their thickness), mode 8 lateral racking (top and bottom plates move in opposite y directions).\n"
    );
    println!("| model | size | DOFs | mass [kg] | f7 | f8 | f9 | f10 | f11 | f12 | time [s] |");
    println!("|---|---|---:|---:|---|---|---|---|---|---|---:|");
    for (model, size, dofs, mass, f, dt) in &rows {
        let cells: Vec<String> = f
            .iter()
            .zip(&reference)
            .map(|(v, r)| format!("{v:.1} ({})", pct(*v, *r)))
            .collect();
        println!(
            "| {model} | {size} | {dofs} | {mass:.2} | {} | {dt:.2} |",
            cells.join(" | ")
        );
    }
    println!();
    // Mass properties per group, the input of the two-mass model.
    println!("### S7 mass properties per group (`post::mass::group_mass_properties`)\n");
    println!("| model | group | mass [kg] | centre x, y, z [mm] | Ixx, Iyy, Izz about the centre [kg·m²] |");
    println!("|---|---|---:|---|---|");
    let solid = sandwich_table_solid(&p, 0.05, CellKind::Hex20)?;
    let shell = sandwich_table(&p)?;
    let shell_spec = ModelSpec {
        shells: shell_parts(&p.thicknesses(), |_| 0.0),
        ..Default::default()
    };
    for (name, mesh, spec) in [
        ("solid hex20 50 mm", &solid, ModelSpec::default()),
        ("shell 25 mm", &shell, shell_spec),
    ] {
        let model = Model::build(mesh, &spec, name)?;
        for g in group_mass_properties(&model, mesh)? {
            if g.group == "xmin" || g.group.starts_with('y') || g.group.starts_with('z') {
                continue;
            }
            println!(
                "| {name} | {} | {:.2} | {:.1}, {:.1}, {:.1} | {:.3}, {:.3}, {:.3} |",
                g.group,
                g.mass,
                mm(g.centre[0]),
                mm(g.centre[1]),
                mm(g.centre[2]),
                g.inertia[0][0],
                g.inertia[1][1],
                g.inertia[2][2]
            );
        }
    }
    println!();
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Shell obstacle course at model level

/// A structured quad4 surface `(u, v) ∈ [0, 1]² ↦ f(u, v)`, `nu × nv` cells. Groups:
/// `"surface"`, edges `"u0"`, `"u1"`, `"v0"`, `"v1"` (Line2) and one Point1 group per entry of
/// `points` (`(name, i, j)`); node `(i, j)` has index `j (nu + 1) + i`.
fn surface(nu: usize, nv: usize, f: impl Fn(f64, f64) -> [f64; 3], points: &[(&str, usize, usize)]) -> Mesh {
    let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    let mut mesh = Mesh::default();
    for j in 0..=nv {
        for i in 0..=nu {
            mesh.nodes.push(f(i as f64 / nu as f64, j as f64 / nv as f64));
        }
    }
    mesh.node_tags = (1..=mesh.nodes.len() as u64).collect();
    let mut tag = 0u64;
    let mut next = || {
        tag += 1;
        tag
    };
    let mut quads = CellBlock::new(CellKind::Quad4);
    for j in 0..nv {
        for i in 0..nu {
            quads.push(&[id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)], next());
        }
    }
    let mut lines = CellBlock::new(CellKind::Line2);
    let mut edges: Vec<Vec<u32>> = vec![vec![]; 4];
    for j in 0..nv {
        for (e, i) in [(0, 0), (1, nu)] {
            edges[e].push(lines.len() as u32);
            lines.push(&[id(i, j), id(i, j + 1)], next());
        }
    }
    for i in 0..nu {
        for (e, j) in [(2, 0), (3, nv)] {
            edges[e].push(lines.len() as u32);
            lines.push(&[id(i, j), id(i + 1, j)], next());
        }
    }
    let mut pts = CellBlock::new(CellKind::Point1);
    for &(_, i, j) in points {
        pts.push(&[id(i, j)], next());
    }
    let nq = quads.len() as u32;
    mesh.blocks = vec![quads, lines, pts];
    let cells = |block: u32, v: Vec<u32>| v.into_iter().map(|index| CellRef { block, index }).collect();
    let mut groups: Vec<(String, u8, Vec<CellRef>)> = vec![("surface".into(), 2, cells(0, (0..nq).collect()))];
    for (e, name) in ["u0", "u1", "v0", "v1"].iter().enumerate() {
        groups.push((name.to_string(), 1, cells(1, edges[e].clone())));
    }
    for (k, &(name, _, _)) in points.iter().enumerate() {
        groups.push((name.to_string(), 0, cells(2, vec![k as u32])));
    }
    mesh.groups = groups
        .into_iter()
        .enumerate()
        .map(|(t, (name, dim, cells))| Group {
            name,
            dim,
            tag: t as i32 + 1,
            cells,
        })
        .collect();
    mesh
}

fn mat(young: f64, poisson: f64, density: f64) -> Material {
    Material {
        young,
        poisson,
        density,
    }
}

fn one_shell(group: &str, section: ShellSection, material: Material) -> ModelSpec {
    ModelSpec {
        material,
        shells: vec![ShellPart {
            group: group.into(),
            section,
            material: None,
        }],
        ..Default::default()
    }
}

/// Component `c` of `node` in a linear static solution; with the DOF count and time.
fn static_value(mesh: &Mesh, spec: ModelSpec, loads: Vec<Load>, node: usize, c: usize) -> Res<(f64, usize, f64)> {
    let t = Instant::now();
    let run = run_static(
        mesh,
        "obstacle",
        &StaticOptions {
            spec,
            cases: vec![loads],
        },
    )?;
    Ok((
        run.u[0][vibrofem::dof::NCOMP * node + c],
        run.dofs,
        t.elapsed().as_secs_f64(),
    ))
}

fn obstacles() -> Res<()> {
    const UX: u8 = 1;
    const UY: u8 = 2;
    const UZ: u8 = 4;
    const RX: u8 = 8;
    const RY: u8 = 16;
    const RZ: u8 = 32;
    let fix = |l: &[(&str, u8)]| l.iter().map(|(g, m)| (g.to_string(), *m)).collect::<Vec<_>>();
    println!("## Shell obstacle course at model level (MITC4)\n");
    println!(
        "Meshes built in code (structured quads with named edge and point groups), symmetry through `fixes` with \
         component masks, loads through `Load::Force` on point groups. Pinched cylinder with rigid diaphragms \
         (MacNeal and Harder 1985, test 6; R 300, L 600, t 3, E 3e6, ν 0.3, P = 1): octant, reference 1.8248e-5. \
         Pinched hemisphere with an 18° hole (test 7; R 10, t 0.04, E 6.825e7, ν 0.3, F = ±2): quadrant, \
         reference 0.094. Twisted beam (test 5): 90° twist, tip load through a rigid coupling of the tip edge.\n"
    );
    println!("| case | mesh | DOFs | value | / reference | time [s] |");
    println!("|---|---|---:|---:|---:|---:|");
    for n in [8, 16, 24, 32] {
        let mesh = surface(
            n,
            n,
            |u, v| {
                let phi = 0.5 * PI * v;
                [300.0 * u, 300.0 * phi.sin(), 300.0 * phi.cos()]
            },
            &[("load", 0, 0)],
        );
        let mut spec = one_shell("surface", ShellSection::new(3.0), mat(3e6, 0.3, 1.0));
        spec.fixes = fix(&[
            ("u0", UX | RY | RZ),
            ("u1", UY | UZ | RX),
            ("v0", UY | RX | RZ),
            ("v1", UZ | RX | RY),
        ]);
        let load = vec![Load::Force {
            group: "load".into(),
            force: [0.0, 0.0, -0.25],
        }];
        let (w, dofs, dt) = static_value(&mesh, spec, load, 0, 2)?;
        println!(
            "| pinched cylinder | {n}×{n} | {dofs} | {:.4e} | {:.4} | {dt:.3} |",
            -w,
            -w / 1.8248e-5
        );
    }
    for n in [8, 16, 24, 32] {
        let top = 72f64.to_radians();
        let mesh = surface(
            n,
            n,
            |u, v| {
                let (phi, lam) = (0.5 * PI * u, top * v);
                [
                    10.0 * lam.cos() * phi.cos(),
                    10.0 * lam.cos() * phi.sin(),
                    10.0 * lam.sin(),
                ]
            },
            &[("a", 0, 0), ("b", n, 0), ("pin", n / 2, n)],
        );
        let mut spec = one_shell("surface", ShellSection::new(0.04), mat(6.825e7, 0.3, 1.0));
        spec.fixes = fix(&[("u0", UY | RX | RZ), ("u1", UX | RY | RZ), ("pin", UZ)]);
        let loads = vec![
            Load::Force {
                group: "a".into(),
                force: [1.0, 0.0, 0.0],
            },
            Load::Force {
                group: "b".into(),
                force: [0.0, -1.0, 0.0],
            },
        ];
        let (u, dofs, dt) = static_value(&mesh, spec, loads, 0, 0)?;
        println!(
            "| pinched hemisphere | {n}×{n} | {dofs} | {u:.4e} | {:.4} | {dt:.3} |",
            u / 0.094
        );
    }
    for (nx, ny) in [(12, 2), (24, 4)] {
        for (dir, name, reference) in [(1, "y", 1.754e-3), (2, "z", 5.424e-3)] {
            let mesh = surface(
                nx,
                ny,
                |u, v| {
                    let phi = 0.5 * PI * u;
                    let s = (v - 0.5) * 1.1;
                    [12.0 * u, s * phi.cos(), s * phi.sin()]
                },
                &[],
            );
            let mut spec = one_shell("surface", ShellSection::new(0.32), mat(29e6, 0.22, 1.0));
            spec.fixes = fix(&[("u0", ALL6)]);
            spec.couplings = vec![CouplingSpec {
                group: "u1".into(),
                guided: None,
                reference: None,
            }];
            let mut force = [0.0; 3];
            force[dir] = 1.0;
            let node = ny / 2 * (nx + 1) + nx;
            let loads = vec![Load::Force {
                group: "u1".into(),
                force,
            }];
            let (d, dofs, dt) = static_value(&mesh, spec, loads, node, dir)?;
            println!(
                "| twisted beam, load along {name} (ref. {reference:e}) | {nx}×{ny} | {dofs} | {d:.4e} | {:.4} | \
                 {dt:.3} |",
                d / reference
            );
        }
    }
    println!();

    println!("### NAFEMS FV12, free thin square plate\n");
    println!(
        "10 × 10 × 0.05 m, E 200 GPa, ν 0.3, ρ 8000 kg/m³, free; reference (thin-plate theory) 1.622, 2.360, 2.922, \
         4.233, 4.233, 7.416 Hz. Shells on `box_mesh`'s zmin face; the solid row is hex20 with one element through \
         the thickness.\n"
    );
    println!("| model | mesh | DOFs | f7 | f8 | f9 | f10 | f11 | f12 | time [s] |");
    println!("|---|---|---:|---|---|---|---|---|---|---:|");
    let reference = [1.622, 2.360, 2.922, 4.233, 4.233, 7.416];
    let fv12_row = |model: &str, mesh_label: String, mesh: &Mesh, spec: ModelSpec| -> Res<()> {
        let (run, dt) = modal(mesh, spec, 12)?;
        let cells: Vec<String> = (0..6)
            .map(|k| {
                let f = run.report.frequencies_hz[6 + k];
                format!("{f:.4} ({})", pct(f, reference[k]))
            })
            .collect();
        println!(
            "| {model} | {mesh_label} | {} | {} | {dt:.2} |",
            run.report.dofs,
            cells.join(" | ")
        );
        Ok(())
    };
    let fv_mat = mat(200e9, 0.3, 8000.0);
    for n in [8, 16, 24, 48] {
        let mesh = box_mesh(CellKind::Hex8, [10.0, 10.0, 0.05], [n, n, 1]);
        fv12_row(
            "shell MITC4",
            format!("{n}×{n}"),
            &mesh,
            one_shell("zmin", ShellSection::new(0.05), fv_mat),
        )?;
    }
    let mesh = box_mesh(CellKind::Hex20, [10.0, 10.0, 0.05], [40, 40, 1]);
    fv12_row(
        "solid hex20",
        "40×40×1".into(),
        &mesh,
        ModelSpec {
            material: fv_mat,
            ..Default::default()
        },
    )?;
    println!();

    println!("### Thin limit: simply supported square plate under uniform load\n");
    println!(
        "Side 1 m, steel, w = 0 on the edges (rotations free), uniform load; centre deflection over Kirchhoff's \
         0.00406235 q a⁴/D.\n"
    );
    println!("| mesh | h/L = 1e-1 | h/L = 1e-2 | h/L = 1e-4 |");
    println!("|---|---:|---:|---:|");
    for n in [8, 16, 32] {
        let mut cells = vec![];
        for t in [0.1, 0.01, 1e-4] {
            let material = Material::steel();
            let mesh = box_mesh(CellKind::Hex8, [1.0, 1.0, 0.01], [n, n, 1]);
            let mut spec = one_shell("zmin", ShellSection::new(t), material);
            spec.fixes = fix(&[("xmin", UZ | UX), ("xmax", UZ), ("ymin", UZ | UY), ("ymax", UZ)]);
            let d = material.young * t.powi(3) / (12.0 * (1.0 - material.poisson.powi(2)));
            let centre = mesh
                .nodes
                .iter()
                .position(|p| (p[0] - 0.5).abs() < 1e-9 && (p[1] - 0.5).abs() < 1e-9 && p[2] == 0.0)
                .ok_or("no centre node")?;
            let load = vec![Load::Force {
                group: "zmin".into(),
                force: [0.0, 0.0, -1.0],
            }];
            let (w, _, _) = static_value(&mesh, spec, load, centre, 2)?;
            cells.push(format!("{:.4}", -w / (0.00406235 / d)));
        }
        println!("| {n}×{n} | {} |", cells.join(" | "));
    }
    println!();
    Ok(())
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a.eq_ignore_ascii_case(s));
    let t = Instant::now();
    println!("# Formulation comparisons\n");
    println!(
        "Generated by `cargo run --release --example compare_formulations` ({} threads). Times are wall seconds \
         of the whole analysis (model build, assembly, ordering, factorisation, eigen solve and verification).\n",
        rayon::current_num_threads()
    );
    if want("obstacles") {
        obstacles()?;
    }
    if want("s1") || want("s2") {
        s1_s2()?;
    }
    if want("s5") {
        s5()?;
    }
    if want("s6") {
        s6()?;
    }
    if want("s7") {
        s7()?;
    }
    println!("Total time: {:.1} s", t.elapsed().as_secs_f64());
    Ok(())
}
