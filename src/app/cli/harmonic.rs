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
    #[command(flatten)]
    fatigue: FatigueArgs,
}

/// Fatigue assessment of the response (docs/fatigue.md): the alternating state is the response
/// at `--freq` (or a sweep's largest), the mean state the static case of the `--mean-*` loads.
#[derive(clap::Args)]
pub struct FatigueArgs {
    /// Assess fatigue with this material: a built-in name (60Si2Mn, 65Mn, 50CrVA, 51CrMoV4), a
    /// TOML file (*.toml) or `rm=MPA,re=MPA[,sw=MPA,tw=MPA,k=SLOPE,nd=CYCLES]`.
    #[arg(long, value_name = "MATERIAL")]
    fatigue: Option<String>,
    /// Mean load: total force on a group, `GROUP=FX,FY,FZ` (N), as `static --force`; repeatable.
    #[arg(long = "mean-force", value_name = "GROUP=FX,FY,FZ", allow_hyphen_values = true)]
    mean_force: Vec<String>,
    /// Mean load: pressure on a surface group, `GROUP=P` (Pa), as `static --pressure`.
    #[arg(long = "mean-pressure", value_name = "GROUP=P", allow_hyphen_values = true)]
    mean_pressure: Vec<String>,
    /// Mean load: body acceleration `GX,GY,GZ` (m/s²), as `static --gravity`.
    #[arg(long = "mean-gravity", value_name = "GX,GY,GZ", allow_hyphen_values = true)]
    mean_gravity: Option<String>,
    /// Cycles the part must survive (Basquin below the knee; default 1e9).
    #[arg(long, default_value_t = 1e9)]
    cycles: f64,
    /// Equivalent stress: principal (signed, largest magnitude; default) or von-mises (signed by
    /// the hydrostatic stress).
    #[arg(long = "fatigue-criterion", default_value = "principal")]
    fatigue_criterion: String,
    /// Mean-stress correction: fkm (Haigh diagram with M_σ; default), goodman or gerber.
    #[arg(long = "mean-stress", default_value = "fkm")]
    mean_stress: String,
    /// Surface roughness Rz (µm; 0: polished; 200: rolled).
    #[arg(long, default_value_t = 0.0)]
    roughness: f64,
    /// Equivalent diameter of the section for the size factor (mm; default: none).
    #[arg(long = "size-mm")]
    size_mm: Option<f64>,
    /// Reliability of the endurance limit: 0.5, 0.9, 0.95, 0.99, 0.999, … (default 0.5).
    #[arg(long, default_value_t = 0.5)]
    reliability: f64,
    /// Leave out nodes closer than this (m) to a fixed group: a rigid clamp is singular
    /// (docs/fatigue.md).
    #[arg(long = "clamp-distance", default_value_t = 0.0)]
    clamp_distance: f64,
    /// Rows of the hot-spot table.
    #[arg(long = "hot-spots", default_value_t = 10)]
    hot_spots: usize,
    /// Haigh diagram with the hot spots (SVG).
    #[arg(long)]
    haigh: Option<PathBuf>,
}

impl FatigueArgs {
    /// The request, checked before any work (None without `--fatigue`).
    fn request(&self) -> Result<Option<crate::app::harmonic::FatigueRequest>> {
        use crate::post::fatigue::{Criterion, FatigueMaterial, FatigueSettings, MeanStress, PartCondition};
        let Some(m) = &self.fatigue else {
            let used = [
                ("--mean-force", !self.mean_force.is_empty()),
                ("--mean-pressure", !self.mean_pressure.is_empty()),
                ("--mean-gravity", self.mean_gravity.is_some()),
                ("--haigh", self.haigh.is_some()),
            ];
            if let Some((o, _)) = used.iter().find(|x| x.1) {
                return Err(Error::option(o.to_string(), format!("{o} needs --fatigue MATERIAL")));
            }
            return Ok(None);
        };
        let material = FatigueMaterial::parse("--fatigue", m).map_err(|e| Error::option("--fatigue", e.to_string()))?;
        if !(self.cycles.is_finite() && self.cycles >= 1.0) {
            return Err(Error::option(
                "--cycles",
                format!("--cycles {}: must be at least 1", self.cycles),
            ));
        }
        if !(self.roughness.is_finite() && self.roughness >= 0.0) {
            return Err(Error::option(
                "--roughness",
                format!("--roughness {}: must be ≥ 0 µm", self.roughness),
            ));
        }
        if let Some(d) = self.size_mm.filter(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(Error::option("--size-mm", format!("--size-mm {d}: must be positive")));
        }
        if !(self.clamp_distance.is_finite() && self.clamp_distance >= 0.0) {
            return Err(Error::option(
                "--clamp-distance",
                format!("--clamp-distance {}: must be ≥ 0 m", self.clamp_distance),
            ));
        }
        crate::post::fatigue::reliability_factor(self.reliability)
            .map_err(|e| Error::option("--reliability", format!("--reliability: {e}")))?;
        let criterion = Criterion::parse("--fatigue-criterion", &self.fatigue_criterion)
            .map_err(|e| Error::option("--fatigue-criterion", e.to_string()))?;
        let mean_stress = MeanStress::parse("--mean-stress", &self.mean_stress)
            .map_err(|e| Error::option("--mean-stress", e.to_string()))?;
        let mut scratch = crate::model::ModelSpec::default();
        let mean_loads = crate::input::options::LoadOptions {
            force: self.mean_force.clone(),
            pressure: self.mean_pressure.clone(),
            gravity: self.mean_gravity.clone(),
            displace: vec![],
        }
        .apply(&mut scratch)
        .map_err(|e| {
            Error::option(
                "--mean-force",
                format!("mean load (--mean-force/--mean-pressure/--mean-gravity): {e}"),
            )
        })?;
        Ok(Some(crate::app::harmonic::FatigueRequest {
            settings: FatigueSettings {
                material,
                condition: PartCondition {
                    rz_um: self.roughness,
                    size_mm: self.size_mm,
                    reliability: self.reliability,
                },
                criterion,
                mean_stress,
                cycles: self.cycles,
            },
            mean_loads,
            clamp_distance: self.clamp_distance,
            hot_spots: self.hot_spots,
        }))
    }
}

pub fn harmonic_cmd(a: &HarmonicArgs) -> Result<i32> {
    use crate::app::harmonic as h;
    let spec = a.model.spec()?;
    let req = request(a)?;
    let fat = a.fatigue.request()?;
    check_outputs(
        &[
            ("--vtu", a.vtu.as_deref()),
            ("--msh-out", a.msh_out.as_deref()),
            ("--plot", a.plot.as_deref()),
            ("--haigh", a.fatigue.haigh.as_deref()),
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
        ..Default::default()
    };
    let sys = crate::system::System::build(model, &opts, &a.mesh)?;
    let run = h::run_with(&sys, &mesh, &req, h::Fields::Peak)?;
    let k = h::peak_index(&run.report);
    let fr = fat.as_ref().map(|f| h::fatigue(&sys, &mesh, &run, k, f)).transpose()?;
    if a.json {
        let mut v = serde_json::to_value(&run.report).map_err(|e| Error::output("JSON", e))?;
        if let (Some(f), Some(obj)) = (&fr, v.as_object_mut()) {
            obj.insert(
                "fatigue".into(),
                serde_json::to_value(&f.report).map_err(|e| Error::output("JSON", e))?,
            );
        }
        outln!(
            "{}",
            serde_json::to_string_pretty(&v).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", h::text(&run.report));
        if let Some(f) = &fr {
            out!("{}", h::fatigue_text(&f.report));
        }
    }
    if a.vtu.is_some() || a.msh_out.is_some() {
        let extra = fr.as_ref().map_or(vec![], |f| h::fatigue_fields(&f.field));
        let cells = sys.model().cell_blocks();
        h::write_fields_with(
            &mesh,
            Some(&cells),
            &run,
            k,
            a.vtu.as_deref(),
            a.msh_out.as_deref(),
            extra,
        )?;
        if run.report.points.len() > 1 {
            eprintln!(
                "note: fields written at {} Hz, the frequency of the largest response",
                crate::io::fmt_sig(run.report.points[k].freq_hz, 5)
            );
        }
    }
    if let (Some(f), Some(p)) = (&fr, &a.fatigue.haigh) {
        let svg = crate::post::fatigue::haigh_svg(&f.report.material, f.report.strength, &f.report.hot_spots);
        std::fs::write(p, svg).map_err(|e| Error::io(p, e))?;
    }
    if let Some(f) = &fr {
        for n in &f.report.notes {
            eprintln!("note: {n}");
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
    h::check_damping(&damping, "--damping", "--rayleigh", &freqs)?;
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
