//! Hosts written by others that the suite builds from a registry: rust-fmi's simulator
//! `fmi-sim` (crates.io), an FMI 2.0 and 3.0 host with Model Exchange (forward Euler) and
//! co-simulation. Installed once into `target/tools/`, whose binary the tests find through
//! `BEAM_BODY_FMI_SIM`.

use std::path::PathBuf;

use crate::{cargo, relative, run_cmd, target_dir, Result};

/// The version the tests were written against (its ME step is its output interval).
pub const FMI_SIM_VERSION: &str = "0.7.0";

/// `target/tools/fmi-sim-<version>/bin/fmi-sim`, built with `cargo install --locked` when it
/// is not there (about 5 minutes on 2 cores: arrow and clap).
pub fn ensure_fmi_sim() -> Result<PathBuf> {
    let root = target_dir().join("tools").join(format!("fmi-sim-{FMI_SIM_VERSION}"));
    let binary = root.join("bin").join("fmi-sim");
    if binary.is_file() {
        eprintln!("{} is installed", relative(&binary));
        return Ok(binary);
    }
    let mut cmd =
        cargo(["install", "--locked", "--quiet", "fmi-sim", "--version", FMI_SIM_VERSION]);
    cmd.arg("--root").arg(&root);
    run_cmd(&mut cmd).map_err(|err| format!("installing fmi-sim {FMI_SIM_VERSION}: {err}"))?;
    Ok(binary)
}
