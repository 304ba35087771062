//! `cargo xtask profile`: where the integrator's instructions go per accepted step
//! (callgrind, by source line), on the benchmark's four scenes.

use std::process::Command;

use crate::{project_root, python, run_cmd, Result};

/// `cargo xtask profile`: a release build with symbols and line tables (target/prof),
/// bench/python/profile_step.py on each benchmark scene at rtol 1e-6, and
/// bench/python/profile_lines.py on the paper's; target/prof/profile.md.
pub fn run() -> Result {
    crate::system::ensure("cargo xtask profile", &[crate::system::TEST_TOOLS])?;
    let python = python::ensure_venv()?;
    let root = project_root();
    let mut build = crate::cargo(["build", "--release", "--bin", "beam-body", "--target-dir"]);
    build
        .arg(root.join("target").join("prof"))
        .env("CARGO_PROFILE_RELEASE_STRIP", "none")
        .env("CARGO_PROFILE_RELEASE_DEBUG", "line-tables-only");
    run_cmd(&mut build)?;
    let binary = root.join("target").join("prof").join("release").join("beam-body");
    let mut report = String::from(
        "# Instructions per step\n\n`cargo xtask profile`: callgrind on one run of each scene \
         at rtol 1e-6, outputs only at 0 and t_end; instructions by the source line they \
         come from (bench/python/profile_step.py).\n",
    );
    for (label, scene, formulation) in [
        ("paper", "scenes/paper.toml", "reduced"),
        ("paper-dae", "scenes/paper.toml", "dae"),
        ("paper-dae-stabilized", "scenes/paper.toml", "dae_stabilized"),
        ("stiff", "scenes/stiff.toml", "reduced"),
    ] {
        let out = Command::new(&python)
            .arg(root.join("bench").join("python").join("profile_step.py"))
            .arg(&binary)
            .arg(root.join(scene))
            .args(["--formulation", formulation, "--label", label])
            .current_dir(&root)
            .output()
            .map_err(|e| format!("cannot run profile_step.py: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "profile_step.py failed on {label}: {}",
                String::from_utf8_lossy(&out.stderr)
            )
            .into());
        }
        report.push('\n');
        report.push_str(&String::from_utf8_lossy(&out.stdout));
    }
    // The paper's scene line by line: each instruction to the innermost line of ours in its
    // inline chain (bench/python/profile_lines.py).
    let out = Command::new(&python)
        .arg(root.join("bench").join("python").join("profile_lines.py"))
        .arg(&binary)
        .arg(root.join("scenes").join("paper.toml"))
        .args(["--top", "40"])
        .current_dir(root.join("bench").join("python"))
        .output()
        .map_err(|e| format!("cannot run profile_lines.py: {e}"))?;
    if !out.status.success() {
        return Err(
            format!("profile_lines.py failed: {}", String::from_utf8_lossy(&out.stderr)).into()
        );
    }
    report.push_str("\n## paper, the 40 costliest lines of ours\n\n");
    report.push_str(&String::from_utf8_lossy(&out.stdout));
    let path = root.join("target").join("prof").join("profile.md");
    crate::write_text(&path, &report)?;
    print!("{report}");
    eprintln!("wrote {}", crate::relative(&path));
    Ok(())
}
