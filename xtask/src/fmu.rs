//! `cargo xtask fmu`.
//!
//! The FMU does not exist yet (a later issue). Packaging it belongs here: once the cdylib
//! exports the FMI 2.0 co-simulation API, this module will zip
//!
//! ```text
//! modelDescription.xml
//! binaries/linux64/BeamBody.so     (target/release/libbeam_body.so)
//! documentation/index.html
//! ```
//!
//! into `target/fmu/BeamBody.fmu` (std only: stored zip entries need nothing but a CRC-32).
//! Until then this command runs the paper's scene through the standalone solver and prints
//! a summary of the result.

use std::fs;
use std::process::Command;

use crate::{build_release_binary, project_root, relative, run_cmd, summary, target_dir, Result};

pub fn run() -> Result {
    let root = project_root();
    let scene = root.join("scenes").join("paper.toml");
    if !scene.is_file() {
        return Err(format!("the paper's scene {} does not exist", relative(&scene)).into());
    }
    let binary = build_release_binary()?;

    let out_dir = target_dir().join("fmu");
    fs::create_dir_all(&out_dir)
        .map_err(|err| format!("cannot create {}: {err}", relative(&out_dir)))?;
    let csv = out_dir.join("paper.csv");

    // The solver's stderr (its run statistics) goes straight through.
    let mut simulate = Command::new(&binary);
    simulate.arg("simulate").arg(relative(&scene)).arg("-o").arg(relative(&csv)).current_dir(&root);
    run_cmd(&mut simulate)?;

    println!("\n{}:", relative(&csv));
    summary::print_paper_run(&summary::Table::read(&csv)?)
}
