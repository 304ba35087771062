//! The beam–body system of Russkikh & Shklyarchuk (2020): an inextensible elastic cantilever
//! with a heavy rigid body hinged at its tip and turned through a large prescribed angle
//! φ(t); the beam by Ritz in n cubic Hermite elements (one: the paper's two coordinates v1,
//! ϑ1), its nonlinearity cut at second order as in the paper or kept whole (the exact beam).
//!
//! - [`model`]: parameters, the four formulations, φ sources, hinge reactions. No I/O.
//! - [`solver`]: our BDF integrator, generic over the system size. No I/O.
//! - [`settings`]: the one table of settings; [`scene`]: a run's settings, checked together.
//! - [`sim`]: the driver that runs a scene and samples it on an output grid.
//! - [`math`]: sin, cos, exp, pow, ..., one implementation on every platform.
//! - `study` (feature `cli`, on by default): design studies, many runs of one scene over
//!   parameter grids and Latin hypercube samples, with metrics per run.
//!
//! The FMU sits on top of these: [`fmu`] binds the model to [`fmi`], the generic FMI core;
//! `fmi2` and `fmi3` export the FMI 2.0 and 3.0 C APIs over it, on the C edge they share
//! ([`capi`]). These three hold all the crate's `unsafe` code.
//!
//! ```
//! use beam_body::sim::{simulate, Scene};
//!
//! // The paper's parameters and turn, for the first second, in the dae_stabilized formulation.
//! let mut scene = Scene::default();
//! scene.set_text("t_end", "1.0").unwrap();
//! scene.set_text("formulation", "dae_stabilized").unwrap();
//! let mut rows = Vec::new();
//! let stats = simulate(&scene, |o| rows.push(*o)).unwrap().stats;
//! let last = rows.last().unwrap();
//! assert_eq!(last.t, 1.0);
//! assert_eq!(last.drift, 0.0); // projected onto u2 = u1(v1, ϑ1)
//! assert!(last.v1.abs() < 1.0 && stats.rejected() < stats.steps);
//! ```

#![deny(unsafe_code)]

pub mod capi;
pub mod choice;
#[cfg(feature = "cli")]
pub mod csv;
pub mod fmi;
pub mod fmi2;
pub mod fmi3;
pub mod fmu;
pub mod hash;
pub mod math;
pub mod model;
pub mod range;
pub mod scene;
pub mod settings;
pub mod sim;
pub mod solver;
#[cfg(feature = "cli")]
pub mod study;
pub mod visit;
