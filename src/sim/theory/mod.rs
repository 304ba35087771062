//! A beam theory: the one interface [`Run`](super::Run) and [`Equations`](super::Equations) know
//! a model by. The paper's two coordinates ([`Paper`], [`PaperDae`]), the beam in n quadratic
//! elements ([`Quadratic`]) and the exact beam ([`Exact`]) implement [`Theory`]; a scene builds
//! only the one it names ([`build`]). A new theory or basis is a new file here and one arm of
//! [`build`].
#![forbid(unsafe_code)]

mod exact;
mod paper;
mod quadratic;

pub use exact::Exact;
pub use paper::{Paper, PaperDae};
pub use quadratic::Quadratic;

use super::SimError;
use crate::model::{BeamBody, BeamN, EnergyBalance, Kinematics, PhiPiece};
use crate::scene::{InitialState, Scene};
use crate::solver::{Bdf, Layout, OdeSystem, Radau};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector};
use std::fmt::Debug;

/// A model of the beam and the body as a first-order system y′ = f(t, y) on a piece of φ:
/// what an integrator needs (the system, its start, the layout of its Jacobian) and what the
/// outputs need (the motion at a state, the beam's shape, the tip's values).
pub trait Theory: Clone + Debug + Send + Sync + 'static
where
    DefaultAllocator: Allocator<Self::D> + Allocator<Self::D, Self::D>,
{
    /// The dimension of the state: fixed (the paper's 4 or 6, on the stack) or run-time.
    type D: Dim;
    /// The system on a piece of φ.
    type System<'a>: OdeSystem<Self::D> + EnergyBalance<Self::D>
    where
        Self: 'a;

    /// The number of states.
    fn states(&self) -> usize;

    /// The system on piece `phi`; `range_check` false checks only that the state is a number.
    fn system(&self, phi: PhiPiece, range_check: bool) -> Self::System<'_>;

    /// The motion at (t, y) that the outputs follow from.
    fn kinematics(sys: &Self::System<'_>, t: f64, y: &OVector<f64, Self::D>) -> Kinematics;

    /// The state at the start on piece `phi` with the tip's values `init`; an error names the
    /// initial value no state of this theory has.
    fn start(&self, phi: PhiPiece, init: &InitialState) -> Result<OVector<f64, Self::D>, String>;

    /// The layout of the parts [`OdeSystem::second_order`] gives, `None` if it gives none.
    fn layout(&self) -> Option<Layout> {
        None
    }

    /// The states a benchmark records at (t, y), into `out`, and how many: by default the
    /// tip's (v1, ϑ1, v̇1, ϑ̇1).
    fn record(
        sys: &Self::System<'_>,
        t: f64,
        y: &OVector<f64, Self::D>,
        out: &mut [f64; 6],
    ) -> usize {
        let k = Self::kinematics(sys, t, y);
        out[..4].copy_from_slice(&[k.v1, k.theta1, k.dv1, k.dtheta1]);
        4
    }

    /// The coordinates q, their rates and accelerations at (t, y), each in `out` in turn: Model
    /// Exchange's states and their derivatives. By default the tip's two.
    fn motion(sys: &Self::System<'_>, t: f64, y: &OVector<f64, Self::D>, out: &mut Vec<f64>) {
        let k = Self::kinematics(sys, t, y);
        out.extend_from_slice(&[k.v1, k.theta1, k.dv1, k.dtheta1, k.ddv1, k.ddtheta1]);
    }

    /// Every node's deflection and slope (v_k, ϑ_k), k = 1..n, the tip last, at the state `y`.
    fn nodal_shape(&self, y: &[f64]) -> Vec<f64>;

    /// The tip's deflection and slope (v1, ϑ1) at the state `y`.
    fn tip(&self, y: &[f64]) -> (f64, f64);

    /// Whether the tip's deflection and slope have limits, |v1| ≤ l and |ϑ1| ≤ π/2 (the
    /// quadratic theories; the exact beam has none).
    fn tip_limits(&self) -> bool {
        true
    }
}

/// What to make of the theory a scene names ([`build`]): a run's integrator, a host's
/// equations. Generic over the theory, so each is written once. (The integrator of every
/// theory can be sent between threads: nalgebra cannot say so of a generic dimension.)
pub trait Build {
    type Out;
    fn build<T: Theory>(self, theory: T) -> Self::Out
    where
        DefaultAllocator: Allocator<T::D> + Allocator<T::D, T::D>,
        Bdf<T::D>: Send + Sync,
        Radau<T::D>: Send + Sync;
}

/// Builds the theory `scene` names, and only it, with the body `model`, and gives it to `b`.
/// The one place a theory is chosen.
pub fn build<B: Build>(scene: &Scene, model: BeamBody, b: B) -> Result<B::Out, SimError> {
    let formulation = scene.formulation;
    if scene.params.is_paper_model() {
        return Ok(if formulation.is_dae() {
            b.build(PaperDae::new(model, formulation))
        } else {
            b.build(Paper::new(model, formulation))
        });
    }
    Ok(match BeamN::new(scene.params, formulation).map_err(SimError::Setting)? {
        BeamN::Quadratic(model) => b.build(Quadratic::new(model, formulation)),
        BeamN::Exact(model) => b.build(Exact::new(model)),
    })
}

/// A state of dimension `D` from a slice (of the length a [`Theory::states`] gives).
pub fn vector<D: Dim>(x: &[f64]) -> OVector<f64, D>
where
    DefaultAllocator: Allocator<D>,
{
    OVector::from_iterator_generic(D::from_usize(x.len()), nalgebra::Const::<1>, x.iter().copied())
}
