//! Memory before assembly: the factor estimate from the node graph, the limit checked before
//! anything large is allocated, the budget (the smallest limit that applies), and byte counts
//! printed in sensible units.

use vibrofem::assembly::NodeGraph;
use vibrofem::input::source;
use vibrofem::linalg::ordering::{factor_entries, node_nested_dissection};
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::{System, SystemOptions, memory_budget};

/// Item 14: the factor size known before assembly (elimination tree of the node graph) is a
/// lower bound of what the symbolic analysis finds, and close to it (supernode padding only).
#[test]
fn factor_estimate_before_assembly_bounds_the_symbolic_count() {
    for (src, fix) in [
        ("box:0.1,0.1,0.1:8,8,8:hex8", false),
        ("box:0.1,0.1,0.1:5,5,5:hex20", true),
        ("box:0.3,0.3,0.02:10,10,2:tet10", true),
    ] {
        let mesh = source::load(src, 1.0).unwrap();
        let spec = ModelSpec {
            fixes: if fix {
                vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)]
            } else {
                vec![]
            },
            ..Default::default()
        };
        let model = Model::build(&mesh, &spec, src).unwrap();
        let sets = model.element_sets();
        let graph = NodeGraph::build(model.dofs.n_nodes(), &sets, Some(&model.dofs));
        let order = node_nested_dissection(&graph, &model.dofs).unwrap();
        let est = factor_entries(&graph, &model.dofs, &order, u64::MAX);
        // A cap stops the count early, above the cap.
        let capped = factor_entries(&graph, &model.dofs, &order, est / 10);
        assert!(capped > est / 10 && capped < est, "{src}: capped {capped} of {est}");
        drop(sets);
        let sys = System::build(model, &SystemOptions::default(), src).unwrap();
        let nnz_l = sys.symbolic().unwrap().nnz_l as u64;
        assert!(est <= nnz_l, "{src}: estimate {est} above the symbolic count {nnz_l}");
        assert!(
            est as f64 >= 0.9 * nnz_l as f64,
            "{src}: estimate {est} far below {nnz_l}"
        );
    }
}

/// Item 14: a model beyond the memory limit is refused before assembly with the estimate,
/// as an input error; the same model under a sufficient limit builds.
#[test]
fn memory_limit_is_checked_before_assembly() {
    let src = "box:0.1,0.1,0.1:6,6,6:hex20";
    let mesh = source::load(src, 1.0).unwrap();
    let build = |limit: u64| {
        let model = Model::build(&mesh, &ModelSpec::default(), src).unwrap();
        let opts = SystemOptions {
            max_memory: Some(limit),
            ..Default::default()
        };
        System::build(model, &opts, src)
    };
    let e = build(1 << 20).err().expect("1 MiB must be refused");
    let msg = e.to_string();
    assert_eq!(e.exit_code(), 1, "{msg}");
    assert!(
        msg.contains("needs at least") && msg.contains("--max-memory is 1.00 MiB"),
        "{msg}"
    );
    assert!(build(1 << 30).is_ok());
}

/// Item 14: the budget is the smallest of the limits that apply; an explicit limit is one of
/// them and below every other here.
#[test]
fn memory_budget_takes_the_smallest_limit() {
    let b = memory_budget(Some(1234)).unwrap();
    assert_eq!(b.bytes, 1234);
    assert_eq!(b.what, "--max-memory is");
    if let Some(sys) = memory_budget(None) {
        assert!(sys.bytes > 0, "{}", sys.what);
        // An explicit limit replaces what the system has available (only hard limits, ulimit
        // and cgroup, still apply), even when it is larger.
        assert_ne!(memory_budget(Some(u64::MAX)).unwrap().what, "the system has available");
    }
}

/// Item 12: byte counts print in the unit that fits (not "0.00 GiB" for a KiB).
#[test]
fn byte_counts_print_with_sensible_units() {
    use vibrofem::io::fmt_bytes;
    assert_eq!(fmt_bytes(1024), "1.00 KiB");
    assert_eq!(fmt_bytes(500 << 20), "500 MiB");
    assert_eq!(fmt_bytes(4 << 30), "4.00 GiB");
    assert_eq!(fmt_bytes(12), "12 bytes");
}
