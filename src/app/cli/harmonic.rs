//! `vibrofem harmonic`: steady-state response to harmonic forces.

use super::{check_outputs, emit, ordering, parse_bytes};
use crate::app::cli::args::{ModelArgs, length_scale};
use crate::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct HarmonicArgs {
    /// gmsh mesh file (MSH 2.2 or 4.1), or a generator (`box:`, `helix:`, `sandwich:`, `ibeam-*:`).
    mesh: String,
    #[command(flatten)]
    model: ModelArgs,
    /// Harmonic force on a group: `GROUP=FX,FY,FZ` amplitudes in N, optionally `@PHASE` in degrees;
    /// repeatable. Spread as a static force (coupled group: its reference node; surface: uniform
    /// traction; otherwise equally over the nodes).
    #[arg(
        long,
        value_name = "GROUP=FX,FY,FZ[@DEG]",
        allow_hyphen_values = true,
        required = true
    )]
    force: Vec<String>,
    /// One excitation frequency (Hz).
    #[arg(long, conflicts_with = "sweep", required_unless_present = "sweep")]
    freq: Option<f64>,
    /// A sweep: N frequencies from F0 to F1 Hz.
    #[arg(long, num_args = 3, value_names = ["F0", "F1", "N"])]
    sweep: Option<Vec<String>>,
    /// Modal damping ratio ζ (e.g. 0.02).
    #[arg(long, conflicts_with = "rayleigh")]
    damping: Option<f64>,
    /// Rayleigh damping C = αM + βK: `ALPHA,BETA` (1/s, s).
    #[arg(long, value_name = "ALPHA,BETA")]
    rayleigh: Option<String>,
    /// modal (superposition with static correction, default), direct (complex solve per
    /// frequency) or both (reports their difference).
    #[arg(long, default_value = "modal")]
    method: String,
    /// Modes superposed: the N lowest (default: every mode below 2 × the highest frequency).
    #[arg(long)]
    modes: Option<usize>,
    /// Groups to report and plot (repeatable; default: the loaded groups).
    #[arg(long)]
    probe: Vec<String>,
    /// Fill-reducing ordering: metis (default) or amd.
    #[arg(long, default_value = "metis")]
    ordering: String,
    /// Refuse models whose factorisation needs more memory than this (e.g. 8G, 500M).
    #[arg(long = "max-memory")]
    max_memory: Option<String>,
    /// Print the JSON report on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Write the response fields as VTU (ParaView); for a sweep, at the frequency of the largest
    /// response.
    #[arg(long)]
    vtu: Option<PathBuf>,
    /// The same as gmsh views.
    #[arg(long = "msh-out")]
    msh_out: Option<PathBuf>,
    /// FRF plot (SVG) of a sweep.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn harmonic_cmd(a: &HarmonicArgs) -> Result<i32> {
    use crate::app::harmonic as h;
    let spec = a.model.spec()?;
    let req = request(a)?;
    check_outputs(
        &[
            ("--vtu", a.vtu.as_deref()),
            ("--msh-out", a.msh_out.as_deref()),
            ("--plot", a.plot.as_deref()),
        ],
        None,
        &[("input mesh", std::path::Path::new(&a.mesh))],
    )?;
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let model = crate::model::Model::build(&mesh, &spec, &a.mesh)?;
    let opts = crate::system::SystemOptions {
        ordering: ordering(&a.ordering)?,
        max_memory: a.max_memory.as_deref().map(parse_bytes).transpose()?,
        mass: true,
    };
    let sys = crate::system::System::build(model, &opts, &a.mesh)?;
    let run = h::run_with(&sys, &mesh, &req, h::Fields::Peak)?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&run.report).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", h::text(&run.report));
    }
    if a.vtu.is_some() || a.msh_out.is_some() {
        let k = h::peak_index(&run.report);
        h::write_fields(&mesh, &run, k, a.vtu.as_deref(), a.msh_out.as_deref())?;
        if run.report.points.len() > 1 {
            eprintln!(
                "note: fields written at {} Hz, the frequency of the largest response",
                crate::io::fmt_sig(run.report.points[k].freq_hz, 5)
            );
        }
    }
    if let Some(p) = &a.plot {
        h::write_frf_svg(p, &run.report)?;
    }
    for n in sys.model().notes.iter().chain(&run.report.notes) {
        eprintln!("note: {n}");
    }
    Ok(0)
}

/// The request the options describe, checked before any work: forces, frequencies (named by the
/// option that gave them), damping, method.
fn request(a: &HarmonicArgs) -> Result<crate::app::harmonic::HarmonicRequest> {
    use crate::analysis::harmonic::{Damping, GroupForce};
    use crate::app::harmonic as h;
    use crate::io::fmt_sig;
    let forces = a
        .force
        .iter()
        .map(|f| GroupForce::parse("--force", f))
        .collect::<Result<Vec<_>>>()?;
    let freqs = match (&a.freq, &a.sweep) {
        (Some(f), _) => {
            if let Some(p) = h::frequency_problem(*f) {
                return Err(Error::option("--freq", format!("--freq {}: {p}", fmt_sig(*f, 4))));
            }
            vec![*f]
        }
        (None, Some(s)) => {
            let num = |t: &str| -> Result<f64> {
                t.trim()
                    .parse()
                    .map_err(|_| Error::option("--sweep", format!("--sweep: cannot read '{t}' as a number")))
            };
            let n: usize = s[2]
                .trim()
                .parse()
                .map_err(|_| Error::option("--sweep", format!("--sweep: N '{}' must be a whole number ≥ 2", s[2])))?;
            h::sweep_frequencies(num(&s[0])?, num(&s[1])?, n)?
        }
        (None, None) => return Err(Error::option("--freq", "give --freq HZ or --sweep F0 F1 N")),
    };
    let damping = match (&a.damping, &a.rayleigh) {
        (Some(z), _) => Damping::Ratio(*z),
        (None, Some(r)) => {
            let v = crate::input::options::numbers("--rayleigh", r, r)?;
            if v.len() != 2 {
                return Err(Error::option(
                    "--rayleigh",
                    format!("--rayleigh '{r}': expected ALPHA,BETA"),
                ));
            }
            Damping::Rayleigh {
                alpha: v[0],
                beta: v[1],
            }
        }
        (None, None) => {
            return Err(Error::option(
                "--damping",
                "give --damping RATIO (e.g. 0.02) or --rayleigh ALPHA,BETA: an undamped response is infinite at \
                 resonance",
            ));
        }
    };
    h::check_damping(&damping, "--damping", "--rayleigh")?;
    if a.plot.is_some() && freqs.len() < 2 {
        return Err(Error::option("--plot", "--plot draws an FRF: it needs --sweep"));
    }
    Ok(h::HarmonicRequest {
        forces,
        freqs_hz: freqs,
        damping,
        method: h::Method::parse(&a.method)?,
        modes: a.modes,
        probes: a.probe.clone(),
    })
}
