//! The beam–body system of Russkikh & Shklyarchuk (2020): an inextensible elastic cantilever
//! (Ritz, two coordinates v1, ϑ1) with a heavy rigid body hinged at its tip and turned
//! through a large prescribed angle φ(t).
//!
//! - [`model`]: parameters, the four formulations, φ sources, hinge reactions. No I/O.
//! - [`solver`]: our BDF integrator, generic over the system size. No I/O.
//! - [`sim`]: the driver that runs a scene and samples it on an output grid.
//!
//! The FMI 2.0 layer (`fmi2`, the only `unsafe` code) sits on top of these.

pub mod model;
pub mod sim;
pub mod solver;
