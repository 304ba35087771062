//! The FMI 2.0 API, co-simulation and Model Exchange, through the 44 exported `fmi2…`
//! functions, called exactly as a C host calls them: raw pointers, NULLs, a variadic
//! logger, value references.
//!
//! The host side (logger, collector, wrappers) is in `common/mod.rs`. Every test checks the
//! returned fmi2Status and, for errors, that a message naming the problem was logged with
//! the host's componentEnvironment, the instance's name, a declared category and "%s".

mod arguments;
#[path = "../common/mod.rs"]
mod common;
mod exchange;
mod fmu_state;
mod instances;
mod lifecycle;
mod logging;
mod sequences;
mod steps;

use beam_body::fmi::{reseal, reseal_checksum, HEADER};
use beam_body::fmi2::exports::*;
use beam_body::fmi2::types::*;
use beam_body::fmu::variables::{
    guid, BaseType, Type, Var, DEFAULT_EXPERIMENT, LOG_CATEGORIES, VARIABLES,
};
use common::*;
use std::f64::consts::PI;
use std::ffi::{c_char, CStr, CString};
use std::ptr::{null, null_mut};

/// The paper's law φ = π sin²(πt / (2·0.85)) for t < 0.85, then π.
pub(crate) fn paper_phi(t: f64) -> f64 {
    if t < 0.85 {
        PI * beam_body::math::powi(beam_body::math::sin(PI * t / (2.0 * 0.85)), 2)
    } else {
        PI
    }
}

/// The start value of a parameter or the input, from the variable table.
pub(crate) fn table_real(var: Var) -> f64 {
    match var.info().ty {
        Type::Real { start: Some(s), .. } => s,
        other => panic!("{var:?} has no real start: {other:?}"),
    }
}

pub(crate) const REAL_PARAMS: [Var; 16] = [
    Var::L,
    Var::Ei,
    Var::M,
    Var::M2,
    Var::JC,
    Var::R,
    Var::G,
    Var::TRot,
    Var::PhiEnd,
    Var::Atol,
    Var::FixedStep,
    Var::Phi0,
    Var::V10,
    Var::Theta10,
    Var::Dv10,
    Var::Dtheta10,
];
pub(crate) const INT_PARAMS: [Var; 5] =
    [Var::Formulation, Var::PhiSource, Var::MaxOrder, Var::FixedOrder, Var::PhiExtrapolation];

/// Every log record names a declared category.
pub(crate) fn assert_declared_categories(records: &[Record]) {
    for r in records {
        assert!(LOG_CATEGORIES.iter().any(|(c, _)| *c == r.category), "undeclared category: {r:?}");
    }
}

/// Sets up a step that fails for real: the paper's fixed-step BDF5 with a 0.5 s step on a
/// beam 10⁴ times stiffer than the paper's; Newton's iteration fails in the first step.
pub(crate) fn stiff_fixed_step(h: &Host) {
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.set_real(Var::FixedStep, 0.5));
    h.expect_ok(h.set_integer(Var::FixedOrder, 5));
    h.expect_ok(h.set_real(Var::Ei, 1e7));
    h.initialize();
}

/// Makes the first step, [0, 0.5], fail ([`stiff_fixed_step`]).
pub(crate) fn fail_a_step(h: &Host) {
    stiff_fixed_step(h);
    let status = h.step(0.0, 0.5);
    let r = h.expect_status(status, DISCARD, &["fmi2DoStep: integration failed: ", "Newton"]);
    assert_eq!(r.category, "logStatusDiscard");
    assert_eq!(r.message.matches("integration failed").count(), 1, "said once: {r:?}");
}

#[allow(unused_imports)]
use arguments::*;
#[allow(unused_imports)]
use fmu_state::*;
#[allow(unused_imports)]
use instances::*;
#[allow(unused_imports)]
use lifecycle::*;
#[allow(unused_imports)]
use logging::*;
#[allow(unused_imports)]
use sequences::*;
#[allow(unused_imports)]
use steps::*;
