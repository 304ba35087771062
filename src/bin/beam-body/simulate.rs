//! `beam-body simulate`: a scene's outputs as CSV.

use crate::args::scene_args;
use crate::output::Output;
use crate::progress::Progress;
use crate::{interrupt, note, CmdResult, Failure};
use beam_body::csv;
use beam_body::model::Outputs;
use beam_body::sim::{self, simulate_partial, SimError};
use beam_body::solver::Method;
use std::ffi::OsString;
use std::io::Write;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

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
    // Everything is checked before the output is touched: settings that do not make a run, a
    // count of rows too large for the disk, the model and the start.
    scene.validate()?;
    let rows = scene.rows()?;
    sim::check(&scene).map_err(|e| Failure::Usage(e.to_string()))?;
    interrupt::install();
    let mut out = Output::open(cli.output.as_deref())?;
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
    if let Err(e) = writeln!(out.writer(), "{}", header.join(",")) {
        let failure = out.failed(e);
        out.abandon();
        return Err(failure);
    }

    let mut io_error = None;
    let mut line = String::with_capacity(400);
    let (mut written, mut max_drift, mut last_t) = (0u64, 0.0f64, f64::NAN);
    let (mut e_min, mut e_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let start = Instant::now();
    let (mut nodes, n_nodes) = (Vec::new(), scene.params.n_elements);
    let t_end = scene.t_end;
    let mut progress =
        Progress::new(t_end, Duration::from_secs(2), false, false, move |t, rate| {
            format!("t = {t:.4} of {t_end} s, {rate:.3} simulated s per s")
        });
    let (report, result) = simulate_partial(&scene, |o, run| {
        if interrupt::interrupted() {
            return ControlFlow::Break(());
        }
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
        if let Err(e) = out.writer().write_all(line.as_bytes()) {
            io_error = Some(e);
            return ControlFlow::Break(());
        }
        written += 1;
        last_t = o.t;
        max_drift = max_drift.max(o.drift.abs());
        e_min = e_min.min(o.energy);
        e_max = e_max.max(o.energy);
        progress.update(o.t);
        ControlFlow::Continue(())
    });
    progress.finish();
    let elapsed = start.elapsed();
    if let Some(e) = io_error {
        let failure = out.failed(e);
        out.abandon();
        return Err(failure);
    }
    let upto = if written > 0 { format!(", up to t = {last_t}") } else { String::new() };
    match &result {
        Err(SimError::Stopped) if interrupt::interrupted() => {
            let wrote = out.abandon();
            return Err(Failure::Interrupted(format!(
                "interrupted: {written} of {rows} rows{upto} written to {wrote}; a run cannot \
                 resume: run it again"
            )));
        }
        Err(e) => {
            let wrote = out.abandon();
            return Err(Failure::Usage(format!(
                "{e} ({written} of {rows} rows{upto} written to {wrote})"
            )));
        }
        Ok(()) => out.finish()?,
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
        let config = scene.solver_config(1);
        let method = match config.method {
            Method::Bdf => format!(
                "bdf, max order {}, guard {}",
                s.max_order,
                if s.stability_guard { "on" } else { "off" }
            ),
            Method::Radau => Method::Radau.name().to_string(),
        };
        format!("{method}, rtol {:e}, atol {:e}", s.rtol, config.atol())
    };
    note(format_args!("beam-body: {}, {mode}", scene.describe()));
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
    let balance = report.energy_error.map_or("off".into(), |e| format!("{e:.1e}"));
    note(format_args!(
        "  rows {written}  max |drift| {max_drift:.3e} m  energy range {:.6e} J  energy balance \
         error {balance}  wall {:.3} ms",
        e_max - e_min,
        elapsed.as_secs_f64() * 1e3
    ));
    Ok(())
}
