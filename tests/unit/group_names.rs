//! Group names: a name used in two dimensions is refused where it is ambiguous and resolved by
//! the formulation where it is not; unnamed groups are reachable as `dimension:tag`.

/// Item 16: a name used in two dimensions is refused where it is ambiguous, resolved by the
/// formulation where it is not; unnamed groups are reachable as `dimension:tag`.
#[test]
fn group_names_in_two_dimensions_and_by_dimension_tag() {
    let mut mesh = vibrofem::mesh::generate::box_mesh(vibrofem::mesh::CellKind::Hex8, [1.0, 0.2, 0.2], [4, 1, 1]);
    let face = mesh.groups.iter().position(|g| g.name == "xmin").unwrap();
    mesh.groups[face].name = "volume".into();
    let (d, t) = (mesh.groups[face].dim, mesh.groups[face].tag);
    let e = mesh.group("volume").unwrap_err().to_string();
    assert!(e.contains("used by 2 groups") && e.contains(&format!("{d}:{t}")), "{e}");
    assert_eq!(mesh.group_of_dim("volume", 3).unwrap().dim, 3);
    assert_eq!(mesh.group_of_dim("volume", 2).unwrap().dim, 2);
    assert_eq!(mesh.group(&format!("{d}:{t}")).unwrap().dim, 2);
    // A fix on the ambiguous name is refused; by dimension:tag it holds the face.
    let mut opts = vibrofem::input::options::ModelOptions {
        fix: vec!["volume".into()],
        ..Default::default()
    };
    let e = vibrofem::model::Model::build(&mesh, &opts.spec().unwrap(), "m")
        .err()
        .unwrap();
    assert!(e.to_string().contains("used by 2 groups"), "{e}");
    opts.fix = vec![format!("{d}:{t}:ux,uy,uz")];
    let model = vibrofem::model::Model::build(&mesh, &opts.spec().unwrap(), "m").unwrap();
    assert_eq!(model.dofs.n_free, 3 * (mesh.n_nodes() - 4));
    // Solids resolve the name by their own dimension.
    let opts = vibrofem::input::options::ModelOptions {
        solid: vec!["volume".into()],
        ..Default::default()
    };
    assert!(vibrofem::model::Model::build(&mesh, &opts.spec().unwrap(), "m").is_ok());
}

#[test]
fn split_group_reads_dimension_tag_names() {
    use vibrofem::input::options::split_group;
    assert_eq!(split_group("2:5"), ("2:5", None));
    assert_eq!(split_group("2:5:ux"), ("2:5", Some("ux")));
    assert_eq!(split_group("top:guided=z"), ("top", Some("guided=z")));
    assert_eq!(split_group("top"), ("top", None));
    assert_eq!(split_group("x1:2"), ("x1", Some("2")));
}
