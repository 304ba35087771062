//! `Equations`: a scene's equations of motion for an integrator that is not ours (FMI Model
//! Exchange): the state-space form x′ = f(t, x) of the formulations that are ODEs in
//! minimal coordinates, x = (q, q̇), with the outputs and the range of validity at any
//! (t, x). The same model and systems [`Run`](super::Run) steps; only the integrator differs.
#![forbid(unsafe_code)]

use super::systems::{build_model, two_dof};
use super::SimError;
use crate::model::{
    BeamBody, BeamN, Formulation, Kinematics, PaperLaw, Phi, PhiPiece, Poly, RangeCheck,
};
use crate::scene::{InitialState, PhiSource, Scene};
use crate::solver::{OdeSystem, RangeViolation};
use nalgebra::{DVector, Vector4};

/// A scene's equations in state-space form, for a host's integrator.
#[derive(Clone, Debug)]
pub struct Equations {
    model: BeamBody,
    elements: Option<Box<BeamN>>,
    formulation: Formulation,
    /// The law that turns the body; `None` when a host sends φ, φ′ and φ″.
    law: Option<PaperLaw>,
    initial: InitialState,
    range_check: RangeCheck,
}

impl Equations {
    /// The equations of `scene` from `t0`, where the host's φ is `phi0` (the law's is its
    /// own). The DAE formulations are refused: they are not ODEs in minimal coordinates.
    pub fn new(scene: &Scene, t0: f64, phi0: f64) -> Result<Equations, SimError> {
        if scene.formulation.is_dae() {
            return Err(SimError::Setting(format!(
                "`formulation` = {} is a DAE, which a host's ODE integrator cannot take: \
                 Model Exchange exports the formulations in minimal coordinates, reduced and \
                 linear; the DAEs run in co-simulation",
                scene.formulation
            )));
        }
        let law = scene.law;
        let phi0 = if scene.phi_source == PhiSource::Law { law.eval(t0).phi } else { phi0 };
        let (model, elements) = build_model(scene, phi0)?;
        Ok(Equations {
            model,
            elements,
            formulation: scene.formulation,
            law: (scene.phi_source == PhiSource::Law).then_some(law),
            initial: scene.initial,
            range_check: scene.range_check,
        })
    }

    pub fn model(&self) -> &BeamBody {
        &self.model
    }

    /// The beam in n elements, when the scene has one.
    pub fn elements(&self) -> Option<&BeamN> {
        self.elements.as_deref()
    }

    /// The law that turns the body, if φ is not a host's.
    pub fn law(&self) -> Option<&PaperLaw> {
        self.law.as_ref()
    }

    /// `range_check` as set.
    pub fn range_check(&self) -> RangeCheck {
        self.range_check
    }

    /// The number of states: 4 (the paper's model), 4n (n elements).
    pub fn state_count(&self) -> usize {
        self.elements.as_ref().map_or(4, |e| 2 * e.dofs())
    }

    /// The piece of φ at `t`: the law's turn before its end (and at it, until the host has
    /// handled the event there: `turned` false), its hold after; or the host's φ, φ′, φ″ at
    /// t as a Taylor polynomial.
    pub fn piece(&self, t: f64, turned: bool, host: Phi) -> PhiPiece {
        match self.law {
            Some(law) if turned => law.piece_from(law.breakpoint().max(t)),
            Some(law) => PhiPiece::Turn(law),
            None => PhiPiece::Poly(Poly::taylor(t, host)),
        }
    }

    /// The start state at `t0` on `piece`: the scene's initial tip values (the beam in n
    /// elements: its static shape with them, [`SystemN::start`](crate::model::SystemN)).
    pub fn start(&self, piece: PhiPiece) -> Result<Vec<f64>, SimError> {
        let i = self.initial;
        match &self.elements {
            None => Ok(vec![i.v1, i.theta1, i.dv1, i.dtheta1]),
            Some(e) => {
                let sys = e.system(piece, self.formulation, true);
                let y = sys.start(i.v1, i.theta1, i.dv1, i.dtheta1).map_err(SimError::Setting)?;
                Ok(y.as_slice().to_vec())
            }
        }
    }

    /// f(t, x) on `piece` into `out`.
    pub fn derivatives(&self, t: f64, piece: PhiPiece, x: &[f64], out: &mut [f64]) {
        match &self.elements {
            None => {
                let sys = two_dof(&self.model, piece, self.formulation);
                out.copy_from_slice(sys.rhs(t, &Vector4::from_column_slice(x)).as_slice());
            }
            Some(e) => {
                let sys = e.system(piece, self.formulation, true);
                out.copy_from_slice(sys.rhs(t, &DVector::from_column_slice(x)).as_slice());
            }
        }
    }

    /// The motion at (t, x) on `piece`: the outputs follow from it.
    pub fn kinematics(&self, t: f64, piece: PhiPiece, x: &[f64]) -> Kinematics {
        match &self.elements {
            None => two_dof(&self.model, piece, self.formulation)
                .kinematics(t, &Vector4::from_column_slice(x)),
            Some(e) => e
                .system(piece, self.formulation, true)
                .kinematics(t, &DVector::from_column_slice(x)),
        }
    }

    /// Whether x is inside the range of validity (`check`: with the limits of the model,
    /// else only that its coordinates are numbers): [`OdeSystem::check_range`].
    pub fn check_range(
        &self,
        t: f64,
        piece: PhiPiece,
        x: &[f64],
        check: bool,
    ) -> Result<(), RangeViolation> {
        match &self.elements {
            None => {
                let sys = crate::model::TwoDofSystem {
                    range_check: check,
                    ..two_dof(&self.model, piece, self.formulation)
                };
                sys.check_range(t, &Vector4::from_column_slice(x))
            }
            Some(e) => e
                .system(piece, self.formulation, check)
                .check_range(t, &DVector::from_column_slice(x)),
        }
    }

    /// Every node's (v_k, ϑ_k) at x, the tip last ([`BeamN::nodal_shape`]); (v1, ϑ1) for
    /// the paper's model.
    pub fn nodal_shape(&self, x: &[f64]) -> Vec<f64> {
        match &self.elements {
            None => x[..2].to_vec(),
            Some(e) => e.nodal_shape(&x[..e.dofs()]),
        }
    }

    /// The tip's deflection and slope (v1, ϑ1) at x ([`BeamN::tip_values`]).
    pub fn tip(&self, x: &[f64]) -> (f64, f64) {
        match &self.elements {
            None => (x[0], x[1]),
            Some(e) => e.tip_values(&x[..e.dofs()]),
        }
    }
}
