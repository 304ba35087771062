//! Everything an FMU state holds ([`Core`]): the state machine's state, the bound values,
//! the experiment, the run and the communication time. The instance works on it, and
//! [`state`](super::state) writes and reads it, neither through the other.
#![forbid(unsafe_code)]

use super::binding::{Values, MAX_STEPS_PER_DO_STEP};
use crate::model::{Kinematics, Reactions, Sample};
use crate::sim::Run;

/// The states of the FMI 2.0 co-simulation state machine (spec §4.2.4) that an instance can
/// be in. `stepInProgress` and `stepCanceled` never occur: steps are synchronous.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    Fatal,
}

impl State {
    const ALL: [State; 7] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
        State::Fatal,
    ];

    pub(super) fn bit(self) -> u32 {
        1 << self as u32
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            State::Instantiated => "instantiated",
            State::InitializationMode => "initialization mode",
            State::StepComplete => "step complete",
            State::StepFailed => "step failed",
            State::Terminated => "terminated",
            State::Error => "error",
            State::Fatal => "fatal",
        }
    }

    pub(super) fn to_index(self) -> u64 {
        self as u64
    }

    pub(super) fn from_index(k: u64) -> Option<State> {
        State::ALL.get(k as usize).copied()
    }
}

/// What fmi2SetupExperiment defined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Setup {
    pub tolerance: Option<f64>,
    pub start_time: f64,
    pub stop_time: Option<f64>,
}

/// Relative tolerance when the host defines none: the DefaultExperiment's.
const DEFAULT_TOLERANCE: f64 = super::variables::DEFAULT_EXPERIMENT.tolerance;

impl Setup {
    fn rtol(&self) -> f64 {
        self.tolerance.unwrap_or(DEFAULT_TOLERANCE)
    }
}

/// The outputs at the communication time, by group ([`Group`](super::binding::Group)),
/// each computed at its first request after a change. Not part of a serialized state.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct OutputCache {
    pub kinematics: Option<Kinematics>,
    pub reactions: Option<Reactions>,
    pub energy: Option<f64>,
}

/// Everything an FMU state holds: the whole instance except its name and logger.
#[derive(Clone, Debug)]
pub struct Core {
    pub(super) state: State,
    pub(super) values: Values,
    pub(super) setup: Setup,
    /// The integrator, from fmi2ExitInitializationMode on.
    pub(super) run: Option<Run>,
    /// φ' and φ'' sent for the next step only.
    pub(super) pending: [Option<f64>; 2],
    /// The communication time: the start time, then the end of the last step.
    pub(super) time: f64,
    pub(super) last_successful_time: f64,
    /// fmi2Terminated: the FMU stopped the run.
    pub(super) terminated: bool,
    /// Outputs at `time`, each group computed at its first request after a change.
    pub(super) cache: OutputCache,
}

impl Core {
    pub(super) fn new() -> Core {
        Core {
            state: State::Instantiated,
            values: Values::from_table(),
            setup: Setup { tolerance: None, start_time: 0.0, stop_time: None },
            run: None,
            pending: [None, None],
            time: 0.0,
            last_successful_time: 0.0,
            terminated: false,
            cache: OutputCache::default(),
        }
    }

    /// The host's sample of φ at `t`: the input's value and the derivatives sent for the
    /// next step.
    pub(super) fn sample(&self, t: f64) -> Sample {
        Sample { t, phi: self.values.phi, dphi: self.pending[0], ddphi: self.pending[1] }
    }

    /// A fresh integrator at the start time, after checking every parameter together: the
    /// CLI's [`Run::start`] on the FMU's settings, with the experiment's tolerance.
    pub(super) fn build_run(&self) -> Result<Run, String> {
        let mut scene = self.values.settings.clone();
        scene.solver.rtol = self.setup.rtol();
        let t0 = self.setup.start_time;
        Run::start(&scene, t0, self.sample(t0), MAX_STEPS_PER_DO_STEP).map_err(|e| e.to_string())
    }
}
