//! `vibrofem buckling`: the lowest positive load factors of a static load case (linear
//! buckling, `(K + λK_σ)φ = 0`) and their shapes.

use super::{check_outputs, emit, ordering, parse_bytes};
use crate::analysis::buckling::{BucklingOptions, BucklingReport, run_buckling};
use crate::app::cli::args::{LoadArgs, ModelArgs, length_scale};
use crate::io::fmt_sig;
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct BucklingArgs {
    /// gmsh mesh file (MSH 2.2 or 4.1), or a generated box `box:LX,LY,LZ:NX,NY,NZ:KIND`.
    mesh: String,
    #[command(flatten)]
    model: ModelArgs,
    /// The load case whose multiples buckle the structure: --force, --pressure, --gravity,
    /// --displace (at least one).
    #[command(flatten)]
    loads: LoadArgs,
    /// Number of load factors (the lowest positive ones).
    #[arg(long, default_value_t = 4)]
    modes: usize,
    /// Safety limit on the iteration: operator applications (vectors) before giving up.
    #[arg(long = "max-applications", default_value_t = 20000)]
    max_applications: usize,
    /// Fill-reducing ordering: metis (default) or amd.
    #[arg(long, default_value = "metis")]
    ordering: String,
    /// Refuse models whose factorisation needs more memory than this (e.g. 8G, 500M).
    #[arg(long = "max-memory")]
    max_memory: Option<String>,
    /// Print the JSON report on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Write the buckling shapes (largest translation 1) as a VTU file (ParaView).
    #[arg(long)]
    vtu: Option<PathBuf>,
    /// Write buckling.vtu (the shapes) and buckling.json (the report) into this folder.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The text table of a buckling report.
pub fn buckling_table(r: &BucklingReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "mesh     {}", r.mesh);
    let _ = writeln!(s, "model    {} nodes, {} free DOFs", r.nodes, r.dofs);
    let _ = writeln!(
        s,
        "load     applied force {} N; stress from {} MPa to {} MPa",
        fmt_sig(r.applied_force, 5),
        fmt_sig(r.compression.value / 1e6, 4),
        fmt_sig(r.tension.value / 1e6, 4)
    );
    let _ = writeln!(s);
    if r.no_buckling {
        let _ = writeln!(s, "no buckling under this load (no positive load factor)");
        return s;
    }
    let _ = writeln!(
        s,
        "{:>5} {:>16} {:>10} {:>10}",
        "mode", "load factor", "residual", "backward"
    );
    for m in &r.modes {
        let _ = writeln!(
            s,
            "{:>5} {:>16} {:>10.2e} {:>10.2e}",
            m.mode,
            fmt_sig(m.load_factor, 7),
            m.rel_residual,
            m.backward_error
        );
    }
    let _ = writeln!(
        s,
        "\nSturm    {} load factor(s) below {} (K + σK_σ), {} found: {}",
        r.sturm.count,
        fmt_sig(r.sturm.point, 6),
        r.sturm.found,
        if r.complete { "complete" } else { "INCOMPLETE" }
    );
    let t = &r.timings_s;
    let _ = writeln!(
        s,
        "time     {:.2} s (assemble {:.2}, static {:.2}, K_σ {:.2}, factor {:.2}, iterate {:.2}, verify {:.2})",
        t.total, t.assemble, t.statics, t.geometric, t.factor, t.solve, t.verify
    );
    s
}

pub fn run(a: &BucklingArgs) -> Result<i32> {
    let mut spec = a.model.spec()?;
    let loads = a.loads.apply(&mut spec)?;
    let l = &a.loads;
    if l.force.is_empty() && l.pressure.is_empty() && l.gravity.is_none() && l.displace.is_empty() {
        return Err(Error::option(
            "--force",
            "buckling needs a load case: give --force, --pressure, --gravity or --displace",
        ));
    }
    if a.modes == 0 {
        return Err(Error::option("--modes", "--modes must be at least 1"));
    }
    let opts = BucklingOptions {
        spec,
        modes: a.modes,
        ordering: ordering(&a.ordering)?,
        max_memory: a.max_memory.as_deref().map(parse_bytes).transpose()?,
        max_applications: a.max_applications,
    };
    let out_vtu = a.out.as_ref().map(|d| d.join("buckling.vtu"));
    let out_json = a.out.as_ref().map(|d| d.join("buckling.json"));
    check_outputs(
        &[
            ("--vtu", a.vtu.as_deref()),
            ("--out", out_vtu.as_deref()),
            ("--out", out_json.as_deref()),
        ],
        None,
        &[("input mesh", std::path::Path::new(&a.mesh))],
    )?;
    let t = std::time::Instant::now();
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let read_time = t.elapsed().as_secs_f64();
    log::info!("buckling: {} loads, {} load factors wanted", loads.len(), a.modes);
    let run = run_buckling(&mesh, &a.mesh, &opts, &loads, read_time)?;
    let json = serde_json::to_string_pretty(&run.report).map_err(|e| Error::output("JSON", e))?;
    if a.json {
        outln!("{json}");
    } else {
        out!("{}", buckling_table(&run.report));
    }
    for p in [a.vtu.as_deref(), out_vtu.as_deref()].into_iter().flatten() {
        for w in crate::app::output::write_shapes(
            &mesh,
            Some(&run.model),
            (&run.shapes, run.vectors.as_ref()),
            ("load_factors", &run.report.load_factors),
            Some(p),
            None,
        )? {
            eprintln!("wrote {}", w.display());
        }
    }
    if let Some(p) = &out_json {
        std::fs::write(p, format!("{json}\n")).map_err(|e| Error::output(p.display().to_string(), e))?;
        eprintln!("wrote {}", p.display());
    }
    for n in &run.report.notes {
        eprintln!("note: {n}");
    }
    if !run.report.complete {
        eprintln!("error: the Sturm count shows missed load factors (see 'complete' above)");
        return Ok(2);
    }
    if !run.report.accurate {
        eprintln!("error: accuracy not guaranteed (backward error or factorisation above tolerance)");
        return Ok(2);
    }
    Ok(0)
}
