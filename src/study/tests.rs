use std::ops::ControlFlow;

use super::axis::lognormal_mu_sigma;
use super::*;

fn parse(text: &str) -> Result<Study, String> {
    Study::parse(text, |path| Err(format!("no scene files in these tests ({path})")))
}

const MAP: &str = r#"
metrics = ["residual_v1", "peak_M"]
[set]
t_end = 3.0
dt_out = 0.01
[parameters.t_rot]
start = 0.5
stop = 1.5
count = 3
[parameters.M2]
values = [6, 12]
"#;

#[test]
fn a_grid_study_numbers_its_cases_with_the_first_parameter_slowest() {
    let study = parse(MAP).unwrap();
    assert_eq!(study.cases(), 6);
    let all: Vec<Vec<f64>> = (0..6).map(|c| study.values(c)).collect();
    assert_eq!(
        all,
        [[0.5, 6.0], [0.5, 12.0], [1.0, 6.0], [1.0, 12.0], [1.5, 6.0], [1.5, 12.0]]
            .map(|r| r.to_vec())
    );
    let names: Vec<_> = study.columns().into_iter().map(|(n, _)| n).collect();
    assert_eq!(
        names,
        [
            "case",
            "t_rot [s]",
            "M2 [kg]",
            "residual_v1 [m]",
            "peak_M [N.m]",
            "status",
            "message",
            "steps"
        ]
    );
}

/// A case is the scene run with its values, and its peaks are those of the dense output:
/// above the peaks on the study's 0.01 s grid (a lower bound), and within the grid's own
/// error of a grid 1,000 times as fine.
#[test]
fn a_case_runs_as_the_scene_with_its_values() {
    let study = parse(MAP).unwrap();
    let row = study.run_case(3);
    assert_eq!(row.status, Status::Ok, "{}", row.message);
    assert_eq!(row.values, [1.0, 12.0]);
    // The same run by hand, sampled on a grid.
    let grid_peaks = |dt_out: f64| {
        let mut scene = Scene::default();
        for (k, v) in [("t_end", 3.0), ("dt_out", dt_out), ("t_rot", 1.0), ("M2", 12.0)] {
            scene.set_number(k, v).unwrap();
        }
        scene.max_rows = 10_000_000;
        let (mut residual, mut peak_m) = (0.0f64, 0.0f64);
        let report = crate::sim::simulate(&scene, |o| {
            peak_m = peak_m.max(o.reactions.m.abs());
            if o.t >= 1.0 {
                residual = residual.max(o.v1.abs()); // v1_eq = 0 at φ = π
            }
        })
        .unwrap();
        (residual, peak_m, report.stats.steps)
    };
    let (residual, peak_m) = (row.metrics[0].unwrap(), row.metrics[1].unwrap());
    let (coarse_residual, coarse_m, steps) = grid_peaks(0.01);
    assert_eq!(row.steps, steps);
    assert!(residual > coarse_residual && peak_m > coarse_m, "{row:?} {coarse_residual}");
    // A grid's peak falls short of the true one by about (ω·dt)²/8 of it: 1e-5 s and
    // ω ≈ 35 rad/s (the second mode) give 1.5e-8.
    let (fine_residual, fine_m, _) = grid_peaks(1e-5);
    for (dense, fine) in [(residual, fine_residual), (peak_m, fine_m)] {
        assert!(dense >= fine && dense - fine <= 2e-8 * dense, "dense {dense}, fine grid {fine}");
    }
    assert!(coarse_residual > 1e-3 && coarse_m > 1.0);
}

#[test]
fn residual_vibration_is_measured_from_the_static_deflection_at_the_final_angle() {
    // A turn to π/2: the beam ends bent under the body's weight.
    let study = parse(
        r#"
metrics = ["residual_v1", "max_v1"]
[set]
t_end = 2.0
phi_end = 1.5707963267948966
t_rot = 0.85
[parameters.M2]
values = [12]
"#,
    )
    .unwrap();
    let row = study.run_case(0);
    let model = BeamBody::new(crate::model::Params::default()).unwrap();
    let v1_eq = model.equilibrium(std::f64::consts::FRAC_PI_2, false).unwrap().0;
    assert!(v1_eq < -0.1, "{v1_eq}");
    let (residual, max_v1) = (row.metrics[0].unwrap(), row.metrics[1].unwrap());
    // The vibration about the bent state is smaller than the deflection itself.
    assert!(residual < max_v1 && max_v1 > 0.1, "{residual} {max_v1}");
    // The equilibrium agrees with the modes' computation.
    assert_eq!(model.modes(std::f64::consts::FRAC_PI_2).equilibrium.0, v1_eq);
}

#[test]
fn latin_hypercube_samples_fill_every_stratum_of_each_distribution() {
    let study = parse(
        r#"
metrics = ["peak_M"]
[sampling]
samples = 400
seed = 7
[parameters.EI]
distribution = "normal"
mean = 1000
sd = 100
min = 500
[parameters.M2]
distribution = "uniform"
low = 6
high = 24
[parameters.J_C]
distribution = "lognormal"
mean = 1.0
sd = 0.2
"#,
    )
    .unwrap();
    assert_eq!(study.cases(), 400);
    let n = 400.0;
    let mut strata = [vec![0; 400], vec![0; 400], vec![0; 400]];
    let (mu, sigma) = lognormal_mu_sigma(1.0, 0.2);
    let lo = normal_cdf(-5.0);
    for c in 0..400 {
        let v = study.values(c);
        let u = [
            (normal_cdf((v[0] - 1000.0) / 100.0) - lo) / (1.0 - lo),
            (v[1] - 6.0) / 18.0,
            normal_cdf((crate::math::ln(v[2]) - mu) / sigma),
        ];
        for (j, u) in u.into_iter().enumerate() {
            strata[j][((u * n) as usize).min(399)] += 1;
        }
    }
    for s in &strata {
        assert!(s.iter().all(|&k| k == 1), "{s:?}");
    }
    // Mean and standard deviation of the log-normal column (LHS: close to the exact ones).
    let col: Vec<f64> = (0..400).map(|c| study.values(c)[2]).collect();
    let mean = col.iter().sum::<f64>() / n;
    let sd = (col.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!((mean - 1.0).abs() < 2e-3 && (sd - 0.2).abs() < 1e-2, "{mean} {sd}");
}

#[test]
fn a_chunk_gives_the_rows_of_the_whole_study() {
    let text = r#"
metrics = ["max_v1"]
[set]
t_end = 0.5
[sampling]
samples = 5
seed = 3
[parameters.t_rot]
values = [0.3, 0.4]
[parameters.EI]
distribution = "uniform"
low = 900
high = 1100
"#;
    let study = parse(text).unwrap();
    assert_eq!(study.cases(), 10);
    let mut whole = Vec::new();
    run_cases(
        &study,
        0..10,
        3,
        |_| ControlFlow::Continue(()),
        |r| {
            whole.push(r);
            Ok::<_, ()>(())
        },
    )
    .unwrap();
    assert_eq!(whole.iter().map(|r| r.case).collect::<Vec<_>>(), (0..10).collect::<Vec<_>>());
    let mut chunk = Vec::new();
    run_cases(
        &study,
        4..7,
        1,
        |_| ControlFlow::Continue(()),
        |r| {
            chunk.push(r);
            Ok::<_, ()>(())
        },
    )
    .unwrap();
    assert_eq!(chunk, whole[4..7]);
    // The same 5 EI samples at each grid point, a Latin hypercube of uniform(900, 1100): one
    // in each fifth of the range (McKay, Beckman & Conover 1979).
    let ei = |cases: std::ops::Range<usize>| {
        whole[cases].iter().map(|r| r.values[1]).collect::<Vec<_>>()
    };
    assert_eq!(ei(0..5), ei(5..10));
    let mut strata: Vec<usize> =
        ei(0..5).iter().map(|x| ((x - 900.0) / 40.0).floor() as usize).collect();
    strata.sort_unstable();
    assert_eq!(strata, [0, 1, 2, 3, 4], "{:?}", ei(0..5));
}

#[test]
fn the_runner_stops_at_the_first_error_of_the_sink() {
    let study = parse(MAP).unwrap();
    let mut seen = 0;
    let result = run_cases(
        &study,
        0..6,
        2,
        |_| ControlFlow::Continue(()),
        |_| {
            seen += 1;
            if seen == 2 {
                Err("disk full")
            } else {
                Ok(())
            }
        },
    );
    assert_eq!(result, Err("disk full"));
    assert_eq!(seen, 2);
}

/// A progress that breaks (an interrupt) starts no case more; the cases running finish, and
/// the rows handed over are those of the first cases, with no gap.
#[test]
fn a_progress_that_breaks_stops_the_runner_with_no_gap_in_the_rows() {
    // More cases than the channel holds: the workers cannot finish them all before the
    // progress breaks, however the threads are scheduled.
    let text = "metrics = [\"max_v1\"]\n[set]\nt_end = 0.05\n[parameters.M2]\nstart = 6\nstop = 24\ncount = 1000\n";
    let study = parse(text).unwrap();
    let mut rows = Vec::new();
    let result = run_cases(
        &study,
        0..1000,
        2,
        |done| if done >= 1 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) },
        |r| {
            rows.push(r.case);
            Ok::<_, ()>(())
        },
    );
    assert_eq!(result, Ok(()));
    assert!(!rows.is_empty() && rows.len() < 1000, "{}", rows.len());
    assert_eq!(rows, (0..rows.len() as u64).collect::<Vec<_>>());
}

#[test]
fn a_case_that_leaves_the_range_of_validity_is_a_row_not_an_error() {
    // A soft beam: the tip section's rotation leaves the model's range.
    let study = parse(
        r#"
metrics = ["peak_M", "max_v1"]
[set]
t_end = 2.0
[parameters.EI]
values = [1000, 20]
"#,
    )
    .unwrap();
    let ok = study.run_case(0);
    assert_eq!(ok.status, Status::Ok, "{}", ok.message);
    let bad = study.run_case(1);
    assert_eq!(bad.status, Status::Stopped, "{bad:?}");
    assert!(bad.message.contains("range"), "{}", bad.message);
    assert_eq!(bad.metrics, [None, None]);
    assert!(bad.steps > 0);
}

#[test]
fn bad_study_files_name_the_field() {
    let cases = [
        ("[parameters.foo]\nvalues = [1]", "`parameters.foo`: unknown parameter"),
        ("[parameters.M2]\nstart = -1\nstop = 10\ncount = 3", "`parameters.M2.start`"),
        ("[parameters.M2]\nstart = 1\nstop = 10\ncount = 0", "`parameters.M2.count` = 0"),
        ("[parameters.M2]\nstart = 1\nstop = 10\ncout = 3", "`parameters.M2.cout`: unknown key"),
        (
            "[sampling]\nsamples = 10\nseed = 1\n[parameters.EI]\ndistribution = \"normal\"\nmean = 1000\nsd = 100",
            "`parameters.EI`: the distribution is unbounded below",
        ),
        (
            "[sampling]\nsamples = 0\nseed = 1\n[parameters.EI]\ndistribution = \"uniform\"\nlow = 1\nhigh = 2",
            "`sampling.samples` = 0",
        ),
        ("[parameters.EI]\ndistribution = \"uniform\"\nlow = 1\nhigh = 2", "`sampling` is missing"),
        ("[parameters.M2]\nstart = 1\nstop = 10\ncount = 3\nspacing = \"cubic\"", "`parameters.M2.spacing`"),
        ("metrics = [\"peak_Q\"]", "`metrics[0]`: unknown metric `peak_Q`"),
        ("[set]\nt_end = 0", "`set.t_end`"),
        ("[set]\nM2 = 3\n[parameters.M2]\nvalues = [1]", "`parameters.M2`: `M2` is also fixed"),
        ("[parameters.t_rot]\nvalues = [0.5, 20]", "`parameters.t_rot` reaches 20"),
        ("rtol = 2", "`rtol`"),
        ("scene = \"x.toml\"", "`scene`: no scene files"),
        ("sceen = \"x.toml\"", "`sceen`: unknown key"),
        ("[parameters.M2]\nvalues = [1, \"a\"]", "`parameters.M2.values[1]`: must be a number"),
        ("[parameters.l]\nstart = 0\nstop = 2\ncount = 3\nspacing = \"log\"", "log grid"),
        ("x = ", "line 1, column 5: not valid TOML"),
        ("[set]\nt_end = 1\nt_end = 2", "line 3, column 1: not valid TOML"),
        ("[set]\nt_end = \"5\"", "`set.t_end`: `t_end` = \"5\": must be a number"),
        ("[parameters.M2]\nvalues = [6, -1]", "`parameters.M2.values[1]`"),
        ("[set]\nn_elements = 33", "`n_elements` = 33 is out of range: must be an integer in 1..=32"),
        ("[set]\nn_elements = 0", "`n_elements` = 0 is out of range"),
        ("[set]\ndamping_beta = -1e-4", "`damping_beta` = -0.0001 is out of range: must be non-negative"),
        ("[parameters.n_elements]\nvalues = [1, 2, 40]", "`parameters.n_elements.values[2]`"),
        ("[parameters.n_elements]\nvalues = [1, 2.5]", "`n_elements` = 2.5: must be an integer"),
        ("[parameters.damping_ratio]\nvalues = [0.01, -0.02]", "`parameters.damping_ratio.values[1]`"),
        ("[parameters.M2]\nstart = 6\nstop = 9\ncount = 1", "`parameters.M2.stop` = 9"),
        ("[parameters.M2]\nstart = 6\nstop = 6\ncount = 3", "must differ from start"),
        ("metrics = \"peak_M\"", "must be a list of metric names: residual_v1"),
        (
            "[sampling]\nsamples = 9007199254740993\nseed = 1\n[parameters.EI]\ndistribution = \"uniform\"\nlow = 1\nhigh = 2",
            "`sampling.samples` = 9007199254740993: must be at most",
        ),
    ];
    for (text, want) in cases {
        let e = parse(text).unwrap_err();
        assert!(e.contains(want), "{text:?}\n  gave: {e}\n  want: {want}");
    }
    // The line of the field named, for the CLI's `FILE:LINE: …`.
    for (text, line) in [
        ("\n[parameters.M2]\nstart = 1\nstop = 10\ncount = 0", "line 5: `parameters.M2.count`"),
        ("rtol = 1e-6\nmetrics = [\"peak_Q\"]", "line 2: `metrics[0]`"),
        ("[set]\nt_end = 0", "line 2: `set.t_end`"),
    ] {
        let e = parse(text).unwrap_err();
        assert!(e.starts_with(line), "{text:?}\n  gave: {e}\n  want: {line}");
    }
}

#[test]
fn the_scene_file_comes_first_and_the_study_overrides_it() {
    let study = Study::parse("rtol = 1e-8\n[set]\nt_end = 4.0\n", |path| {
        assert_eq!(path, "base.toml");
        Ok("t_end = 2.0\nM2 = 20\n".into())
    });
    // No `scene` key: the loader is not called.
    let study = study.unwrap();
    assert_eq!(study.base.t_end, 4.0);
    let study = Study::parse("scene = \"base.toml\"\nrtol = 1e-8\n[set]\nt_end = 4.0\n", |path| {
        assert_eq!(path, "base.toml");
        Ok("t_end = 2.0\nM2 = 20\n".into())
    })
    .unwrap();
    assert_eq!((study.base.t_end, study.base.params.m2, study.base.solver.rtol), (4.0, 20.0, 1e-8));
    assert_eq!(study.scene_path(), Some("base.toml"));
}

/// The study's parameters are the settings table's rows marked `study`: each of them can be
/// varied, and no other setting can.
#[test]
fn the_parameters_a_study_takes_are_the_settings_table_s() {
    for s in SETTINGS {
        let x = match s.default {
            crate::settings::Value::Real(x) => x,
            _ => 1.0,
        };
        let text = format!("metrics = [\"max_v1\"]\n[parameters.{}]\nvalues = [{x:?}]\n", s.name);
        let parsed = parse(&text);
        assert_eq!(parsed.is_ok(), s.appears.study, "{}: {:?}", s.name, parsed.err());
    }
    let names: Vec<&str> = variables().map(|s| s.name).collect();
    let marked: Vec<&str> = SETTINGS.iter().filter(|s| s.appears.study).map(|s| s.name).collect();
    assert_eq!(names, marked);
}

/// The number of elements and the damping are study parameters like the others: each case of
/// a grid over n_elements and damping_ratio gives, bit for bit, the metrics of a study that sets
/// the same values in `[set]` (the parameter reaches the model as a scene key does); one and
/// two elements differ by more than a third of the measured model difference (residual_v1
/// 3.2e-3, peak_M_root 6.2e-3, relative), and damping lowers the residual vibration.
#[test]
fn a_study_varies_the_number_of_elements_and_the_damping() {
    let head = "metrics = [\"residual_v1\", \"peak_M_root\"]\n[set]\nt_end = 3.0\ndt_out = 0.01\n";
    let study = parse(&format!(
        "{head}[parameters.n_elements]\nvalues = [1, 2]\n[parameters.damping_ratio]\nvalues = [0, 0.05]\n"
    ))
    .unwrap();
    assert_eq!(study.cases(), 4);
    let rows: Vec<_> = (0..4).map(|c| study.run_case(c)).collect();
    for (c, r) in rows.iter().enumerate() {
        assert_eq!(r.status, Status::Ok, "{}", r.message);
        let (n, zeta) = (1 + c / 2, [0.0, 0.05][c % 2]);
        let set = parse(&format!("{head}n_elements = {n}\ndamping_ratio = {zeta}\n")).unwrap();
        assert_eq!(set.run_case(0).metrics, r.metrics, "case {c}: n = {n}, zeta = {zeta}");
    }
    let metric = |c: usize, k: usize| rows[c].metrics[k].unwrap();
    for k in 0..2 {
        let (one, two) = (metric(0, k), metric(2, k));
        assert!((one - two).abs() > 1e-3 * one, "metric {k}: one element {one}, two {two}");
    }
    assert!(metric(1, 0) < metric(0, 0) && metric(3, 0) < metric(2, 0), "damping lowers it");
}

/// A study runs the exact beam when its `[set]` says so: its metrics are the exact beam's
/// (those of a run of the same scene), not the quadratic beam's, and residual_v1 is measured
/// from the exact beam's own equilibrium.
#[test]
fn a_study_of_the_exact_beam_measures_the_exact_beam() {
    let text = |beam: &str| {
        format!(
            r#"
metrics = ["residual_v1", "max_v1"]
[set]
t_end = 2.0
phi_end = 1.5707963267948966
n_elements = 2
beam = "{beam}"
[parameters.M2]
values = [12]
"#
        )
    };
    let exact = parse(&text("exact")).unwrap().run_case(0);
    let quadratic = parse(&text("quadratic")).unwrap().run_case(0);
    let mut scene = crate::sim::Scene::default();
    for (k, v) in [("t_end", "2.0"), ("phi_end", "1.5707963267948966"), ("n_elements", "2")] {
        scene.set_text(k, v).unwrap();
    }
    scene.set_text("beam", "exact").unwrap();
    scene.set_text("dt_out", "0.001").unwrap();
    let mut max_v1 = 0.0f64;
    crate::sim::simulate(&scene, |o| max_v1 = max_v1.max(o.v1.abs())).unwrap();
    let (e, q) = (exact.metrics[1].unwrap(), quadratic.metrics[1].unwrap());
    // The study's peaks come from the dense output, not a grid: within the grid's 1 ms.
    assert!((e - max_v1).abs() < 1e-4 * max_v1 && (e - q).abs() > 1e-3, "{e} {max_v1} {q}");
    let model = crate::model::BeamN::new(scene.params, scene.formulation).unwrap();
    let q_eq = model.equilibrium(std::f64::consts::FRAC_PI_2, false).unwrap();
    let v1_eq = model.tip_values(q_eq.as_slice()).0;
    let params = crate::model::Params { beam: crate::model::BeamModel::Quadratic, ..scene.params };
    let quadratic_eq = crate::model::BeamN::new(params, scene.formulation).unwrap();
    let q_eq = quadratic_eq.equilibrium(std::f64::consts::FRAC_PI_2, false).unwrap();
    let v1_eq_quadratic = quadratic_eq.tip_values(q_eq.as_slice()).0;
    // The static deflections differ by the quadratic cut, about 1e-4 of 0.14 m.
    assert!((v1_eq - v1_eq_quadratic).abs() > 2e-5, "{v1_eq} {v1_eq_quadratic}");
    assert!(exact.metrics[0].unwrap() < e, "residual below the peak");
}

/// An integer parameter (n_elements) takes whole numbers only: a distribution, or a grid with
/// a point between two integers, is refused when the study is read (it ran and wrote "invalid"
/// rows), naming the parameter and what it takes. A grid of whole steps, linear or log, runs
/// each of its integers, and its column is an integer column.
#[test]
fn an_integer_parameter_takes_whole_numbers_and_has_an_integer_column() {
    let allowed = "`n_elements` must be an integer in 1..=32";
    for (axis, want) in [
        ("distribution = \"uniform\"\nlow = 1\nhigh = 4", "a distribution gives real numbers"),
        ("distribution = \"normal\"\nmean = 4\nsd = 1", "a distribution gives real numbers"),
        ("distribution = \"lognormal\"\nmean = 4\nsd = 1", "a distribution gives real numbers"),
        ("start = 1\nstop = 4\ncount = 3", "(start = 1, stop = 4, count = 3) has the point 2.5"),
        ("start = 1.5\nstop = 4.5\ncount = 4", "has the point 1.5"),
        ("start = 1\nstop = 32\ncount = 4\nspacing = \"log\"", "has the point 3.17"),
    ] {
        let sampling = if axis.starts_with("distribution") {
            "[sampling]\nsamples = 4\nseed = 1\n"
        } else {
            ""
        };
        let text = format!("metrics = [\"max_v1\"]\n{sampling}[parameters.n_elements]\n{axis}\n");
        let e = parse(&text).unwrap_err();
        let line = if sampling.is_empty() { 2 } else { 5 };
        let head = format!("line {line}: `parameters.n_elements`: {allowed}");
        assert!(e.starts_with(&head), "{axis:?}\n  gave: {e}\n  want: {head}");
        assert!(e.contains(want) && e.contains("`values = [1, 2, 4]`"), "{axis:?}: {e}");
    }
    // Out of range is the range's error, as for a list.
    let e = parse("[parameters.n_elements]\nstart = 0\nstop = 40\ncount = 41\n").unwrap_err();
    assert!(e.contains("`parameters.n_elements.start`: `n_elements` = 0 is out of range"), "{e}");

    let grids = [
        ("start = 1\nstop = 32\ncount = 32", (1..=32).map(f64::from).collect::<Vec<_>>()),
        ("start = 8\nstop = 2\ncount = 4", vec![8.0, 6.0, 4.0, 2.0]),
        (
            "start = 1\nstop = 32\ncount = 6\nspacing = \"log\"",
            vec![1.0, 2.0, 4.0, 8.0, 16.0, 32.0],
        ),
        ("start = 3\nstop = 3\ncount = 1", vec![3.0]),
    ];
    for (axis, want) in grids {
        let text = format!("metrics = [\"max_v1\"]\n[parameters.n_elements]\n{axis}\n");
        let study = parse(&text).unwrap();
        let values: Vec<f64> = (0..study.cases()).map(|c| study.values(c)[0]).collect();
        assert_eq!(values, want, "{axis:?}");
    }
    let text = "metrics = [\"max_v1\"]\n[parameters.n_elements]\nvalues = [1, 2]\n\
                [parameters.M2]\nvalues = [12]\n";
    let types: Vec<_> = parse(text).unwrap().columns().into_iter().map(|(_, t)| t).collect();
    use ColumnType::{Float, Int, Text};
    assert_eq!(types, [Int, Int, Float, Float, Text, Text, Int]);
}
