//! `vibrofem converge` pairs each level's modes with the finest level's by MAC, across mode
//! reordering, for scene levels and the built-in table levels alike.

#[test]
fn converge_pairs_modes_by_mac_across_reordering() {
    use vibrofem::app::converge::{LevelModes, mac, pair_by_mac};
    // A bar along x sampled at nested points (the fine level has the coarse points and their
    // midpoints). Shapes: bending in y (u_y = x²) and in z (u_z = x²), and axial (u_x = x).
    // The coarse level lists z bending first, the fine one y bending first: pairing must pick
    // the coarse level's second mode.
    let pts = |n: usize| -> Vec<[f64; 3]> { (0..=n).map(|i| [i as f64 / n as f64, 0.0, 0.0]).collect() };
    let shape = |p: &[[f64; 3]], c: usize, f: &dyn Fn(f64) -> f64| -> Vec<f64> {
        p.iter()
            .flat_map(|x| (0..3).map(move |k| if k == c { f(x[0]) } else { 0.0 }))
            .collect()
    };
    let level = |n: usize, order: [usize; 3], freqs: Vec<f64>| {
        let p = pts(n);
        let all = [
            shape(&p, 1, &|x| x * x),
            shape(&p, 2, &|x| x * x * (1.0 + 0.01 * x)),
            shape(&p, 0, &|x| x),
        ];
        LevelModes {
            shapes: order.iter().map(|&i| all[i].clone()).collect(),
            points: p,
            freqs,
        }
    };
    let coarse = level(4, [1, 0, 2], vec![10.0, 10.5, 50.0]);
    let fine = level(8, [0, 1, 2], vec![9.8, 9.9, 49.0]);
    let p = pair_by_mac(&[Some(coarse), None, Some(fine)]);
    assert_eq!(p[1], None);
    let (k, m) = p[0].unwrap();
    assert_eq!(k, 1, "coarse level: its second mode is the fine level's first");
    assert!(m > 0.999, "MAC {m}");
    assert_eq!(p[2].unwrap().0, 0);
    assert!((p[2].unwrap().1 - 1.0).abs() < 1e-12);
    // MAC of orthogonal shapes is 0, of scaled ones 1.
    assert_eq!(mac(&[1.0, 0.0], &[0.0, 2.0]), 0.0);
    assert!((mac(&[1.0, 2.0], &[-2.0, -4.0]) - 1.0).abs() < 1e-15);
}

/// Item 8: MAC pairing used to apply only to scene levels; the built-in S7 table levels (shell
/// and hex20 runners) returned no shapes, so a mode swap there went unnoticed. They now hand
/// back their elastic modes: two shell refinements of the table pair their first elastic mode
/// with the finest level's first (the same plate mode; a MAC near 1 shows the shapes are
/// sampled at the same points and consistently normalised).
#[test]
fn converge_table_levels_return_shapes_for_pairing() {
    use vibrofem::app::converge::{LevelSpec, Runner, pair_by_mac, run_level_modes};
    let levels: Vec<_> = [0.1, 0.05]
        .iter()
        .map(|&h| {
            let (value, _, _, _, modes) = run_level_modes(&LevelSpec {
                formulation: "shell".into(),
                mesh: format!("{h}"),
                runner: Runner::TableShell(h),
            })
            .unwrap();
            let m = modes.expect("table levels return their modes");
            assert!(m.freqs.len() >= 4 && m.shapes.len() == m.freqs.len(), "{:?}", m.freqs);
            assert_eq!(m.freqs[0], value);
            assert_eq!(m.shapes[0].len(), 3 * m.points.len());
            Some(m)
        })
        .collect();
    let p = pair_by_mac(&levels);
    for (i, x) in p.iter().enumerate() {
        let (k, m) = x.unwrap();
        assert_eq!(k, 0, "level {i}: paired with elastic mode {}", k + 1);
        assert!(m > 0.95, "level {i}: MAC {m}");
    }
}
