#![forbid(unsafe_code)]
//! A variable-order, variable-step BDF integrator for small stiff ODE systems.
//!
//! Generic over the system size `N` (const generics, stack-only data), independent of the
//! beam: it sees only an [`OdeSystem`]. No I/O, no `unsafe`.

mod bdf;
mod coeffs;
mod config;
mod eigen;
mod error;
mod guard;
mod lu;
pub mod problems;
mod snapshot;
mod stats;
mod system;

pub use bdf::{Bdf, StepOutcome};
pub use config::{check_rtol, BdfConfig, FixedStep};
pub use error::SolverError;
pub use guard::{unstable_band, A_STABILITY_ANGLE_DEG};
pub(crate) use snapshot::visit_usize;
pub use snapshot::StateVisitor;
pub use stats::Stats;
pub use system::{OdeSystem, RangeViolation};
