//! `beam-body simulate`: a scene's outputs as CSV.

use crate::args::scene_args;
use crate::{note, stdout_failed, CmdResult, Failure};
use beam_body::csv;
use beam_body::model::Outputs;
use beam_body::sim::{simulate_partial, SimError};
use std::ffi::OsString;
use std::io::{self, BufWriter, Write};
use std::ops::ControlFlow;
use std::time::Instant;

pub fn run(args: Vec<OsString>) -> CmdResult {
    let Some(cli) = scene_args("simulate", args)? else {
        return Ok(());
    };
    if cli.file.is_none() {
        return Err(Failure::Usage(
            "simulate needs a scene file, e.g. scenes/paper.toml (beam-body simulate --help)"
                .into(),
        ));
    }
    let scene = cli.scene;
    // Refused before the output file is created: settings that do not make a run, a count of
    // rows too large for the disk. (simulate_partial checks the same again, in microseconds.)
    scene.validate()?;
    let rows = scene.rows()?;
    let to_stdout = cli.output.is_none();
    let sink: Box<dyn Write> = match &cli.output {
        Some(path) => Box::new(
            std::fs::File::create(path)
                .map_err(|e| Failure::Usage(format!("cannot create {path}: {e}")))?,
        ),
        None => Box::new(io::stdout().lock()),
    };
    // 64 KiB: a system call per 200 rows instead of 25 (8 KiB).
    let mut out = BufWriter::with_capacity(1 << 16, sink);
    let failed = |e: io::Error, out: &Option<String>| match out {
        None => stdout_failed(e),
        Some(path) => Failure::Usage(format!("writing {path} failed: {e}")),
    };
    let (beam, shape) = (scene.columns >= 1, scene.columns == 2);
    let extra = if beam { &Outputs::BEAM_COLUMNS[..] } else { &[] };
    let mut header: Vec<String> = Outputs::COLUMNS
        .iter()
        .chain(extra)
        .map(|(name, unit)| csv::header(name, Some(unit)))
        .collect();
    if shape {
        for k in 1..=scene.params.n_elements {
            header.push(csv::header(&format!("v_{k}"), Some("m")));
            header.push(csv::header(&format!("theta_{k}"), Some("rad")));
        }
    }
    writeln!(out, "{}", header.join(",")).map_err(|e| failed(e, &cli.output))?;

    let mut io_error = None;
    let mut line = String::with_capacity(400);
    let (mut written, mut max_drift) = (0u64, 0.0f64);
    let (mut e_min, mut e_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let start = Instant::now();
    let (mut nodes, n_nodes) = (Vec::new(), scene.params.n_elements);
    let (report, result) = simulate_partial(&scene, |o, run| {
        line.clear();
        for (k, v) in o.values().iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            csv::push_number(&mut line, *v);
        }
        if beam {
            for v in o.beam_values() {
                line.push(',');
                csv::push_number(&mut line, v);
            }
        }
        if shape {
            // The output times lie in the last step: its dense output holds them.
            // (outputs_at just interpolated at o.t: this cannot fail.)
            if run.coordinates_at(o.t, &mut nodes).is_err() {
                nodes.resize(2 * n_nodes, f64::NAN);
            }
            for v in &nodes {
                line.push(',');
                csv::push_number(&mut line, *v);
            }
        }
        line.push('\n');
        // The first failed write ends the run: nothing is computed for a closed pipe.
        if let Err(e) = out.write_all(line.as_bytes()) {
            io_error = Some(e);
            return ControlFlow::Break(());
        }
        written += 1;
        max_drift = max_drift.max(o.drift.abs());
        e_min = e_min.min(o.energy);
        e_max = e_max.max(o.energy);
        ControlFlow::Continue(())
    });
    let elapsed = start.elapsed();
    if let Some(e) = io_error.or_else(|| out.flush().err()) {
        return Err(failed(e, &cli.output));
    }
    drop(out);
    if let Err(e) = &result {
        let stopped = matches!(e, SimError::Stopped);
        debug_assert!(!stopped, "only a failed write stops the run, and it returned above");
        return Err(Failure::Usage(format!(
            "{e} ({written} of {rows} rows written{})",
            if to_stdout { "" } else { " to the file" }
        )));
    }
    if let Some(w) = &report.warning {
        note(format_args!("beam-body: warning: {w}"));
    }
    let stats = report.stats;
    let s = &scene.solver;
    let mode = if s.fixed_step > 0.0 {
        let order = if s.fixed_order == 0 { 2 } else { s.fixed_order };
        format!("fixed step h = {:e} s, order {order}", s.fixed_step)
    } else {
        format!(
            "rtol {:e}, atol {:e}, max order {}, guard {}",
            s.rtol,
            s.atol(),
            s.max_order,
            if s.stability_guard { "on" } else { "off" }
        )
    };
    note(format_args!("beam-body: {} formulation, {mode}", scene.formulation));
    note(format_args!(
        "  steps {}  rejected {} (error test {}, Newton {})  f-evals {} (+{} for Jacobians)",
        stats.steps,
        stats.rejected(),
        stats.error_test_failures,
        stats.newton_failures,
        stats.rhs_evals,
        stats.rhs_evals_jac
    ));
    note(format_args!(
        "  Jacobians {}  LU factorizations {}  Newton iterations {}  order caps {}  restarts {}",
        stats.jac_evals,
        stats.lu_factorizations,
        stats.newton_iters,
        stats.order_caps,
        stats.restarts
    ));
    note(format_args!(
        "  rows {written}  max |drift| {max_drift:.3e} m  energy range {:.6e} J  wall {:.3} ms",
        e_max - e_min,
        elapsed.as_secs_f64() * 1e3
    ));
    Ok(())
}
