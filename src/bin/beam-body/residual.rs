//! `beam-body residual`: the residuals of the equations of motion at states read from stdin,
//! for the independent oracle.

use crate::args::scene_args;
use crate::{stdout_failed, CmdResult, Failure};
use beam_body::model::{BeamBody, Formulation, Phi};
use nalgebra::{Vector2, Vector3};
use std::ffi::OsString;
use std::io::{self, BufRead, BufWriter, Write};

pub fn run(args: Vec<OsString>) -> CmdResult {
    let Some(cli) = scene_args("residual", args)? else {
        return Ok(());
    };
    if !cli.given.contains(&"formulation") {
        return Err(Failure::Usage(
            "residual needs --formulation F (reduced, dae, dae_stabilized or linear): the \
             equations and the number of values per line depend on it"
                .into(),
        ));
    }
    let model = BeamBody::new(cli.scene.params).map_err(|e| e.to_string())?;
    let form = cli.scene.formulation;
    let width = if form.is_dae() { 12 } else { 9 };
    let mut out = BufWriter::new(io::stdout().lock());
    for (i, line) in io::stdin().lock().lines().enumerate() {
        let line = line.map_err(|e| format!("reading stdin failed: {e}"))?;
        if line.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|e| format!("stdin line {}: {e}", i + 1))?;
        if v.len() != width {
            return Err(Failure::Usage(format!(
                "stdin line {}: {} numbers, the {form} formulation needs {width}",
                i + 1,
                v.len()
            )));
        }
        let phi = Phi { phi: v[0], dphi: v[1], ddphi: v[2] };
        let row: Vec<f64> = if form.is_dae() {
            let (x, xd, xdd) = (
                Vector3::new(v[3], v[4], v[5]),
                Vector3::new(v[6], v[7], v[8]),
                Vector3::new(v[9], v[10], v[11]),
            );
            let (a, b) = model.dae(&phi, x, xd);
            let acc = model.dae_accel(&phi, x, xd);
            (a * xdd - b).iter().chain(acc.iter()).copied().collect()
        } else {
            let linear = form == Formulation::Linear;
            let (q, qd, qdd) =
                (Vector2::new(v[3], v[4]), Vector2::new(v[5], v[6]), Vector2::new(v[7], v[8]));
            let (m, f) =
                if linear { model.linear(&phi, q, qd) } else { model.reduced(&phi, q, qd) };
            let acc = model.two_dof_accel(linear, &phi, q, qd);
            (m * qdd - f).iter().chain(acc.iter()).copied().collect()
        };
        let text: Vec<String> = row.iter().map(|x| format!("{x:e}")).collect();
        writeln!(out, "{}", text.join(" ")).map_err(stdout_failed)?;
    }
    out.flush().map_err(stdout_failed)
}
