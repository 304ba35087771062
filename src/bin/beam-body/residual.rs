//! `beam-body residual`: the residuals of the equations of motion at states read from stdin,
//! for the independent oracle.

use crate::args::scene_args;
use crate::{stdout_failed, CmdResult, Failure};
use beam_body::model::{BeamBody, Formulation, Phi};
use beam_body::scene::Scene;
use beam_body::settings::{Key, Setting};
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
    paper_model_only(&cli.scene)?;
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

/// The settings of the paper's model that `residual` cannot honour, with their values: it
/// evaluates the two-coordinate equations (one element of the quadratic beam, undamped,
/// weightless), so another beam, damping or the beam's weight would be ignored in silence.
fn beyond_paper_model(scene: &Scene) -> Vec<String> {
    const BEYOND: [Key; 6] = [
        Key::NElements,
        Key::Beam,
        Key::DampingAlpha,
        Key::DampingBeta,
        Key::DampingRatio,
        Key::BeamGravity,
    ];
    BEYOND
        .into_iter()
        .map(Setting::of)
        .filter(|s| scene.get(s.key) != s.default)
        .map(|s| format!("{} = {}", s.name, s.show(scene.get(s.key))))
        .collect()
}

/// Refuses a scene that is not the paper's model, naming each setting that differs.
fn paper_model_only(scene: &Scene) -> Result<(), Failure> {
    let beyond = beyond_paper_model(scene);
    if beyond.is_empty() {
        return Ok(());
    }
    Err(Failure::Usage(format!(
        "residual evaluates the paper's equations, of one element of the quadratic beam without \
         damping or the beam's weight, and cannot take {}: leave n_elements = 1, beam = \
         quadratic, damping_* = 0 and beam_gravity = false",
        beyond.join(", ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_beyond_the_paper_model_are_named() {
        let mut scene = Scene::default();
        assert!(beyond_paper_model(&scene).is_empty());
        let beyond = [("n_elements", "4"), ("beam", "exact"), ("damping_ratio", "0.01")];
        let more = [("damping_alpha", "0.5"), ("damping_beta", "1e-3"), ("beam_gravity", "true")];
        for (name, value) in beyond.into_iter().chain(more) {
            scene.set_text(name, value).unwrap();
        }
        assert_eq!(
            beyond_paper_model(&scene),
            [
                "n_elements = 4",
                "beam = exact",
                "damping_alpha = 0.5",
                "damping_beta = 0.001",
                "damping_ratio = 0.01",
                "beam_gravity = true"
            ]
        );
        // The paper's values, given explicitly, are the paper's model.
        let mut scene = Scene::default();
        scene.set_text("n_elements", "1").unwrap();
        scene.set_text("beam", "quadratic").unwrap();
        assert!(paper_model_only(&scene).is_ok());
    }
}
