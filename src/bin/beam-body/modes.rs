//! `beam-body modes`: small-oscillation periods about the static equilibrium.

use crate::args::scene_args;
use crate::{print, CmdResult};
use beam_body::model::BeamBody;
use std::f64::consts::PI;
use std::ffi::OsString;
use std::fmt::Write;

pub fn run(args: Vec<OsString>) -> CmdResult {
    let Some(cli) = scene_args("modes", args)? else {
        return Ok(());
    };
    let model = BeamBody::new(cli.scene.params).map_err(|e| e.to_string())?;
    let mut text = format!(
        "{:<6}  {:>19}  {:>19}  {:>17}  {:>17}\n",
        "phi", "v1_eq [m]", "theta1_eq [rad]", "T1 [s]", "T2 [s]"
    );
    for (label, phi) in [("0", 0.0), ("pi/2", PI / 2.0), ("pi", PI)] {
        let m = model.modes(phi);
        let fmt = |p: Option<f64>| p.map_or("unstable".to_string(), |t| format!("{t:.15}"));
        let [t1, t2] = m.periods();
        let (v, th) = m.equilibrium;
        let _ = writeln!(
            text,
            "{label:<6}  {v:>+19.12e}  {th:>+19.12e}  {:>17}  {:>17}",
            fmt(t1),
            fmt(t2)
        );
    }
    print(&text)
}
