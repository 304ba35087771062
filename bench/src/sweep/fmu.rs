//! The sweep's cases that go through the packaged FMU (`target/sweep/fmu/BeamBody/`, loaded
//! by the native host, [`crate::import`]): communication steps from 1e-6 s to 10 s with φ from the law, and a
//! step in the φ input.

use std::path::PathBuf;

use beam_body::fmu::variables::{Var, MODEL_IDENTIFIER};
use beam_body::sim::Scene;

use crate::bench::fmu::set_scene;
use crate::import::{take_messages, Call, CoSimulation, Common, Fmi2Error, Fmu2, InstanceCS};
use crate::target_dir;

/// How φ reaches the FMU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FmuPhi {
    /// phi_source = law (the scene's turn).
    Law,
    /// phi_source = input, values only: 0 before `t_jump`, `jump` from then on.
    Step { t_jump: f64, jump: f64 },
}

/// An FMU run: communication step `h` from 0 to the scene's t_end (a multiple of `h`),
/// recording every `stride`-th communication point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FmuRun {
    pub h: f64,
    pub stride: usize,
    pub phi: FmuPhi,
}

/// Where `cargo xtask sweep` extracts the FMU.
pub fn extracted_dir() -> PathBuf {
    target_dir().join("sweep").join("fmu").join(MODEL_IDENTIFIER)
}

/// Runs the scene through the FMU: the states (v1, ϑ1, v̇1, ϑ̇1) at t = 0 and every
/// `stride`-th communication point, or the FMU's message when a step is discarded.
pub fn run(scene: &Scene, how: &FmuRun) -> Result<Vec<[f64; 4]>, String> {
    let fmu = Fmu2::load(&extracted_dir()).map_err(|e| format!("loading the FMU: {e}"))?;
    let source = match how.phi {
        FmuPhi::Law => "law",
        FmuPhi::Step { .. } => "input",
    };
    let text = |e: Box<dyn std::error::Error>| e.to_string();
    let mut instance = fmu.instantiate(MODEL_IDENTIFIER, false).map_err(text)?;
    set_scene(&mut instance, scene, source).map_err(text)?;
    let n = (scene.t_end / how.h).round() as u64;
    let rtol = Some(scene.solver.rtol);
    instance.setup_experiment(rtol, 0.0, None).call("fmi2SetupExperiment").map_err(text)?;
    instance.enter_initialization_mode().call("fmi2EnterInitializationMode").map_err(text)?;
    instance.exit_initialization_mode().call("fmi2ExitInitializationMode").map_err(text)?;
    let states = [Var::V1, Var::Theta1, Var::Dv1, Var::Dtheta1].map(|v| v.vr());
    let mut out = Vec::new();
    let mut record = |instance: &mut InstanceCS| -> Result<(), String> {
        let mut y = [0.0; 4];
        instance.get_real(&states, &mut y).call("fmi2GetReal").map_err(text)?;
        out.push(y);
        Ok(())
    };
    record(&mut instance)?;
    for k in 0..n {
        let tc = k as f64 * how.h;
        if let FmuPhi::Step { t_jump, jump } = how.phi {
            let phi = if tc >= t_jump { jump } else { 0.0 };
            instance.set_real(&[Var::Phi.vr()], &[phi]).call("fmi2SetReal").map_err(text)?;
        }
        match instance.do_step(tc, how.h, true) {
            Err(Fmi2Error::Discard) => {
                let message = take_messages().pop();
                return Err(
                    message.map_or("fmi2Discard without a message".into(), |m| m.to_string())
                );
            }
            result => result.call("fmi2DoStep").map_err(text)?,
        };
        if (k + 1) % how.stride as u64 == 0 {
            record(&mut instance)?;
        }
    }
    instance.terminate().call("fmi2Terminate").map_err(text)?;
    Ok(out)
}
