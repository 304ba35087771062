//! The beam–body model: parameters, φ(t) sources, the four formulations, hinge reactions and
//! energy. Equations are derived in `dynamics.rs` from the energies of
//! `shared/model-notes.md` (paper eq. 8–13). No I/O, no `unsafe`.
#![forbid(unsafe_code)]

mod balance;
mod band;
mod beam_n;
mod dense;
mod differences;
mod dynamics;
mod dynamics_n;
mod elements;
mod exact;
mod filter;
mod formulation;
mod jacobian_n;
mod kinematics;
mod params;
mod phi;
mod signal;
mod systems;
mod systems_exact;
mod systems_n;

pub use balance::{Energy, EnergyBalance, Power};
pub use beam_n::BeamN;
pub use dynamics::{BeamBody, Modes, Reactions};
pub use dynamics_n::{BeamBodyN, MAX_ELEMENTS};
pub use elements::Elements;
pub use exact::{ExactBeam, PointMotion, GAUSS_POINTS};
pub use filter::PhiFilter;
pub use formulation::{BeamModel, Formulation, RangeCheck};
pub use kinematics::{pq, u1, u1_accel_bias};
pub use params::{ParamError, Params};
pub use phi::{PaperLaw, Phi, PhiPiece, Poly};
pub use signal::{HostSignal, Interpolation, Sample, SignalError, HISTORY};
pub use systems::{DaeSystem, Kinematics, Outputs, TwoDofSystem};
pub use systems_exact::ExactSystem;
pub use systems_n::ElementsSystem;
