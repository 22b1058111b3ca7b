//! Design-file values checked before any work (issue 28 items 5 and 13): every value's range is
//! validated when the file is read, and the error names the file, the line and the key — never
//! a late failure of the FE parts, the two-mass model or the integrator, and never advice about
//! a setting a design file cannot reach.

use vibrofem::Error;
use vibrofem::app::design::Design;

/// Reads a design file holding `text` and expects it refused at `key` on `line`.
fn refused(name: &str, text: &str, key: &str, line: usize) -> String {
    let dir = std::env::temp_dir().join(format!("vibrofem-design-inputs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    let e = match Design::from_toml(&p) {
        Ok(_) => panic!("{name}: accepted {text:?}"),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert!(
        msg.contains(&format!("{name}, line {line}, key '{key}'")),
        "{name}: the error should name the file, line {line} and key '{key}': {msg}"
    );
    assert!(
        matches!(&e, Error::Input { line: Some(l), key: Some(k), .. } if *l == line && k == key),
        "{e:?}"
    );
    for unreachable in ["max_steps", "rtol", "atol", "--"] {
        assert!(
            !msg.contains(unreachable),
            "{name}: advice a design file cannot follow: {msg}"
        );
    }
    msg
}

#[test]
fn negative_limits_are_refused() {
    // A negative limit turned its check into "ok" whatever the value.
    refused(
        "allow.toml",
        "version = 1\n[leaf]\nallowable = -170e6\n",
        "leaf.allowable",
        3,
    );
    refused(
        "shear.toml",
        "version = 1\n[coil]\nallowable_shear = -5.6e8\n",
        "coil.allowable_shear",
        3,
    );
    refused(
        "power.toml",
        "version = 1\n[drive]\ninstalled_power = -2640.0\n",
        "drive.installed_power",
        3,
    );
}

#[test]
fn masses_must_be_finite_and_in_range() {
    // NaN passed the "not negative" test and reached the FE work.
    refused(
        "nan.toml",
        "version = 1\n[masses]\nactive_extra = nan\n",
        "masses.active_extra",
        3,
    );
    refused("inf.toml", "version = 1\n[masses]\nload = inf\n", "masses.load", 3);
    // A load share is a fraction of the load.
    let m = refused(
        "share.toml",
        "version = 1\n[masses]\nload_share = 5.0\n",
        "masses.load_share",
        3,
    );
    assert!(m.contains("between 0 and 1"), "{m}");
    refused(
        "share_neg.toml",
        "version = 1\n[masses]\nload_share = -0.5\n",
        "masses.load_share",
        3,
    );
}

#[test]
fn detuning_far_from_resonance_is_refused() {
    refused("z.toml", "version = 1\ntarget_detuning = 1e6\n", "target_detuning", 2);
    refused(
        "z_small.toml",
        "version = 1\ntarget_detuning = 1e-4\n",
        "target_detuning",
        2,
    );
}

#[test]
fn excitation_beyond_the_model_is_refused_at_once() {
    // 1e5 Hz used to fail after 8 s in the transient with "raise max_steps".
    let t = std::time::Instant::now();
    let m = refused("f.toml", "version = 1\nexcitation_hz = 1e5\n", "excitation_hz", 2);
    assert!(t.elapsed().as_secs_f64() < 1.0, "{m}");
    assert!(m.contains("1000"), "{m}");
    // Too low for the start-up transient to reach its steady periods (it reads the last ten).
    let m = refused(
        "slow.toml",
        "version = 1\nexcitation_hz = 1.0\n[drive]\ntransient_s = 0.6\n",
        "drive.transient_s",
        4,
    );
    assert!(m.contains("10 s"), "{m}");
    // Too many periods for the integrator, though within 30 s.
    refused(
        "fast.toml",
        "version = 1\nexcitation_hz = 900.0\n[drive]\ntransient_s = 20.0\n",
        "drive.transient_s",
        4,
    );
}

#[test]
fn damping_must_not_be_negative() {
    refused("mu1.toml", "version = 1\n[damping]\nmu1 = -2400.0\n", "damping.mu1", 3);
    refused("mu12.toml", "version = 1\n[damping]\nmu12 = nan\n", "damping.mu12", 3);
}

/// Values far outside any machine of the family (a unit slip) are refused on reading, naming the
/// key and printed with an exponent: they failed after the FE work as a reference node "not
/// free", an "undamped resonance" (a dashpot of 1e300 N·s/m) or a helix of 300-digit cells.
#[test]
fn absurd_values_are_refused_on_reading() {
    for (name, text, key) in [
        ("pull.toml", "[drive]\npull = 1e300\n", "drive.pull"),
        ("mu.toml", "[damping]\nmu1 = 1e300\n", "damping.mu1"),
        ("m2.toml", "[masses]\nreactive = 1e300\n", "masses.reactive"),
        ("m2tiny.toml", "[masses]\nreactive = 1e-300\n", "masses.reactive"),
        ("load.toml", "[masses]\nload = 1e300\n", "masses.load"),
        ("turns.toml", "[coil]\nturns = 1e7\n", "coil.turns"),
        ("turns0.toml", "[coil]\nturns = 1e-300\n", "coil.turns"),
        ("g.toml", "[coil]\nshear_modulus = 1e300\n", "coil.shear_modulus"),
        ("h.toml", "[leaf]\nthickness = 1e-6\n", "leaf.thickness"),
        // Given alone it sets the excitation, whose error named 'excitation_hz'.
        ("mains.toml", "[drive]\nmains_hz = 1e300\n", "drive.mains_hz"),
        ("level.toml", "[machine]\nleaf_level = 1e300\n", "machine.leaf_level"),
    ] {
        let m = refused(name, &format!("version = 1\n{text}"), key, 3);
        assert!(m.contains("check the units") || m.contains("within 100 m"), "{m}");
        assert!(!m.contains("00000000000"), "{name}: a value printed in full: {m}");
    }
}

/// A design at the highest excitation the files allow runs its start-up: a breakpoint of the
/// rectified force that rounded to just below the transient's end left a segment shorter than
/// any step ("ode: step size underflow at t = 0.6").
#[test]
fn the_highest_excitation_runs_its_start_up() {
    let dir = std::env::temp_dir().join(format!("vibrofem-design-inputs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("f1000.toml");
    let text = "version = 1\nexcitation_hz = 1000.0\n[search]\nenabled = false\n[envelope]\nenabled = false\n";
    std::fs::write(&p, text).unwrap();
    let d = Design::from_toml(&p).unwrap();
    let r = vibrofem::app::design::run_design(&d, None, &|_| {}).unwrap();
    let row = r
        .quantities
        .iter()
        .find(|q| q.id == "transient_x1")
        .expect("a transient row");
    assert!(row.value.is_finite() && row.value > 0.0, "{}", row.value);
    // A user's design: the row is the paper's chain on its masses, not the paper's figure.
    assert!(row.published.is_none() && !row.note.contains("Fig. 22"), "{}", row.note);
}

#[test]
fn efficiency_is_a_fraction() {
    // Both failed after the FE work, in eq. (6), without file or key.
    refused(
        "eta5.toml",
        "version = 1\n[drive]\nefficiency = 5.0\n",
        "drive.efficiency",
        3,
    );
    let m = refused(
        "eta.toml",
        "version = 1\n[drive]\nefficiency = 1.5\n",
        "drive.efficiency",
        3,
    );
    assert!(m.contains("at most 1"), "{m}");
    Design::from_toml(&{
        let p = std::env::temp_dir().join(format!("vibrofem-eta1-{}.toml", std::process::id()));
        std::fs::write(&p, "version = 1\n[drive]\nefficiency = 1.0\n").unwrap();
        p
    })
    .unwrap();
}

#[test]
fn clamping_coefficient_is_a_fraction() {
    // 1e300 made the leaves rigid and the machine "under-constrained" (exit 2) after the FE work.
    refused(
        "clamp.toml",
        "version = 1\n[leaf]\nclamping = 1e300\n",
        "leaf.clamping",
        3,
    );
    refused(
        "clamp0.toml",
        "version = 1\n[leaf]\nclamping = 0.0\n",
        "leaf.clamping",
        3,
    );
}

#[test]
fn counts_and_parts_name_their_key() {
    // These were refused without a key (and so without a line).
    refused("leaves.toml", "version = 1\n[leaf]\ncount = 0\n", "leaf.count", 3);
    refused(
        "magnets.toml",
        "version = 1\n[drive]\nmagnets = 0\n",
        "drive.magnets",
        3,
    );
    // The spring index D/d must exceed 1 (Wahl's factor failed late).
    refused(
        "coil.toml",
        "version = 1\n[coil]\nmean_diameter = 0.005\n",
        "coil.mean_diameter",
        3,
    );
    // The leaves' steel is checked like the table's.
    refused(
        "leafsteel.toml",
        "version = 1\n[leaf]\nmaterial = [2.1e11, 0.7, 7850.0]\n",
        "leaf.material",
        3,
    );
}

/// Three values that got past the checks and failed late, without the key: a coil pitch below
/// the wire (the helix builder refused it after the first FE parts had run), a leaf of 1e-9 m
/// (the start-up integrator stopped after millions of steps) and a table of 1e9 m (its
/// generator blamed the element size).
#[test]
fn coil_pitch_leaf_length_and_table_size_name_their_key() {
    refused("pitch.toml", "version = 1\n[coil]\npitch = 0.001\n", "coil.pitch", 3);
    let m = refused("leaflen.toml", "version = 1\n[leaf]\nlength = 1e-9\n", "leaf.length", 3);
    assert!(m.contains("leaf.thickness"), "{m}");
    let m = refused(
        "tablelen.toml",
        "version = 1\n[table]\nlength = 1e9\n",
        "table.length",
        3,
    );
    assert!(m.contains("table.element_size"), "{m}");
}

#[test]
fn search_lists_are_counted_before_they_are_expanded() {
    // Issue 28 item 8: lists of 300 × 300 × 300 values were expanded into designs (a clone and a
    // validation each, minutes of work and gigabytes) before the 1000-variant cap refused them.
    // Their product is counted when the file is read.
    let list = |n: usize, x0: f64| {
        let v: Vec<String> = (0..n).map(|i| format!("{}", x0 + 1e-4 * i as f64)).collect();
        format!("[{}]", v.join(", "))
    };
    let text = format!(
        "version = 1\n[search]\ntop_thickness = {}\nbottom_thickness = {}\nbottom_width = {}\n",
        list(300, 0.012),
        list(300, 0.008),
        list(300, 0.5)
    );
    let msg = refused("search.toml", &text, "search.top_thickness", 3);
    // 300³ times the default lists' 2 × 2 (webs, spacers) × 3 × 2 (pulls per magnet, leaf
    // shifts: the search also varies the drive and the leaf positions, issue 29 item 7).
    assert!(
        msg.contains("648000000 combinations") && msg.contains("at most 100000"),
        "{msg}"
    );
}
