#![forbid(unsafe_code)]
//! A variable-order, variable-step BDF integrator for small stiff ODE systems.
//!
//! Generic over the system's dimension `D` (nalgebra's `Dim`): fixed at compile time
//! (`Const<N>`: the data on the stack, nothing allocated by a step; the paper's two-coordinate
//! model) or at run time (`Dyn`: on the heap; the beam of n elements). The code is the same,
//! and for a fixed dimension it compiles to what a const-generic solver would. Independent of
//! the beam: it sees only an [`OdeSystem`]. No I/O, no `unsafe`.

/// `$e` with `$Q` a constant equal to the order `$q` (1..=QMAX; QMAX for anything larger),
/// so that loops over the order unroll: the order changes seldom, and a loop of one to six
/// short vector operations costs more in its control than in its arithmetic.
macro_rules! by_order {
    ($q:expr, $Q:ident => $e:expr) => {
        match $q {
            1 => {
                const $Q: usize = 1;
                $e
            }
            2 => {
                const $Q: usize = 2;
                $e
            }
            3 => {
                const $Q: usize = 3;
                $e
            }
            4 => {
                const $Q: usize = 4;
                $e
            }
            _ => {
                const $Q: usize = $crate::solver::coeffs::QMAX;
                $e
            }
        }
    };
}

mod band;
mod bdf;
mod coeffs;
mod config;
mod eigen;
mod error;
mod guard;
mod integrator;
mod lu;
pub mod problems;
mod radau;
mod second_order;
mod snapshot;
mod stats;
mod system;

pub use band::GenBand;
pub use bdf::{Bdf, StepOutcome};
pub use config::{check_rtol, BdfConfig, FixedStep, Method, ORDER_RANGE, RTOL_RANGE};
pub use error::{Allowed, SolverError};
pub use guard::{unstable_band, A_STABILITY_ANGLE_DEG};
pub use integrator::Integrator;
/// The Newton matrix's LU, public only so that the benchmark can price a factorisation and a
/// solve as the integrator does them (`cargo xtask bench`, costs.csv).
#[doc(hidden)]
pub use lu::Lu;
pub use radau::Radau;
pub use second_order::{BandRankOne, BandedParts, DenseParts, Layout, SecondOrder};
pub use stats::Stats;
pub use system::{OdeSystem, RangeViolation};
