//! `Equations`: a scene's equations of motion for an integrator that is not ours (FMI Model
//! Exchange): the state-space form x′ = f(t, x) of the formulations that are ODEs in
//! minimal coordinates, x = (q, q̇), with the outputs and the range of validity at any
//! (t, x). The same theory [`Run`](super::Run) steps ([`Theory`]); only the integrator differs.
#![forbid(unsafe_code)]

use super::theory::{self, vector, Build, Theory};
use super::SimError;
use crate::model::{BeamBody, Kinematics, PaperLaw, Phi, PhiPiece, Poly, RangeCheck};
use crate::scene::{InitialState, PhiSource, Scene};
use crate::solver::{Bdf, OdeSystem, Radau, RangeViolation};
use nalgebra::allocator::Allocator;
use nalgebra::DefaultAllocator;
use std::fmt::Debug;

/// A theory's state-space form on slices, whatever the theory.
trait StateSpace: Debug + Send + Sync {
    fn clone_box(&self) -> Box<dyn StateSpace>;
    fn states(&self) -> usize;
    fn start(&self, piece: PhiPiece, init: &InitialState) -> Result<Vec<f64>, String>;
    fn derivatives(&self, t: f64, piece: PhiPiece, x: &[f64], out: &mut [f64]);
    fn kinematics(&self, t: f64, piece: PhiPiece, x: &[f64]) -> Kinematics;
    fn check_range(
        &self,
        t: f64,
        piece: PhiPiece,
        x: &[f64],
        check: bool,
    ) -> Result<(), RangeViolation>;
    fn nodal_shape(&self, x: &[f64]) -> Vec<f64>;
    fn tip(&self, x: &[f64]) -> (f64, f64);
    fn tip_limits(&self) -> bool;
}

impl Clone for Box<dyn StateSpace> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

impl<T: Theory> StateSpace for T
where
    DefaultAllocator: Allocator<T::D> + Allocator<T::D, T::D>,
{
    fn clone_box(&self) -> Box<dyn StateSpace> {
        Box::new(self.clone())
    }

    fn states(&self) -> usize {
        Theory::states(self)
    }

    fn start(&self, piece: PhiPiece, init: &InitialState) -> Result<Vec<f64>, String> {
        Ok(Theory::start(self, piece, init)?.as_slice().to_vec())
    }

    fn derivatives(&self, t: f64, piece: PhiPiece, x: &[f64], out: &mut [f64]) {
        out.copy_from_slice(self.system(piece, true).rhs(t, &vector(x)).as_slice());
    }

    fn kinematics(&self, t: f64, piece: PhiPiece, x: &[f64]) -> Kinematics {
        T::kinematics(&self.system(piece, true), t, &vector(x))
    }

    fn check_range(
        &self,
        t: f64,
        piece: PhiPiece,
        x: &[f64],
        check: bool,
    ) -> Result<(), RangeViolation> {
        self.system(piece, check).check_range(t, &vector(x))
    }

    fn nodal_shape(&self, x: &[f64]) -> Vec<f64> {
        Theory::nodal_shape(self, x)
    }

    fn tip(&self, x: &[f64]) -> (f64, f64) {
        Theory::tip(self, x)
    }

    fn tip_limits(&self) -> bool {
        Theory::tip_limits(self)
    }
}

/// Boxes the theory a scene names as a [`StateSpace`].
struct Boxed;

impl Build for Boxed {
    type Out = Box<dyn StateSpace>;

    fn build<T: Theory>(self, theory: T) -> Self::Out
    where
        DefaultAllocator: Allocator<T::D> + Allocator<T::D, T::D>,
        Bdf<T::D>: Send + Sync,
        Radau<T::D>: Send + Sync,
    {
        Box::new(theory)
    }
}

/// A scene's equations in state-space form, for a host's integrator.
#[derive(Clone, Debug)]
pub struct Equations {
    model: BeamBody,
    theory: Box<dyn StateSpace>,
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
        let model = scene.check_model(phi0).map_err(SimError::Setting)?;
        Ok(Equations {
            model,
            theory: theory::build(scene, model, Boxed)?,
            law: (scene.phi_source == PhiSource::Law).then_some(law),
            initial: scene.initial,
            range_check: scene.range_check,
        })
    }

    pub fn model(&self) -> &BeamBody {
        &self.model
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
        self.theory.states()
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
    /// elements: its static shape with them, [`Theory::start`]).
    pub fn start(&self, piece: PhiPiece) -> Result<Vec<f64>, SimError> {
        self.theory.start(piece, &self.initial).map_err(SimError::Setting)
    }

    /// f(t, x) on `piece` into `out`.
    pub fn derivatives(&self, t: f64, piece: PhiPiece, x: &[f64], out: &mut [f64]) {
        self.theory.derivatives(t, piece, x, out);
    }

    /// The motion at (t, x) on `piece`: the outputs follow from it.
    pub fn kinematics(&self, t: f64, piece: PhiPiece, x: &[f64]) -> Kinematics {
        self.theory.kinematics(t, piece, x)
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
        self.theory.check_range(t, piece, x, check)
    }

    /// Every node's (v_k, ϑ_k) at x, the tip last ([`Theory::nodal_shape`]); (v1, ϑ1) for
    /// the paper's model.
    pub fn nodal_shape(&self, x: &[f64]) -> Vec<f64> {
        self.theory.nodal_shape(x)
    }

    /// The tip's deflection and slope (v1, ϑ1) at x ([`Theory::tip`]).
    pub fn tip(&self, x: &[f64]) -> (f64, f64) {
        self.theory.tip(x)
    }

    /// Whether the tip's deflection and slope have limits ([`Theory::tip_limits`]): not the
    /// exact beam's.
    pub fn tip_limits(&self) -> bool {
        self.theory.tip_limits()
    }
}
