//! The Python virtual environment of the tests: `target/venv`, with `tests/requirements.txt`.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::{project_root, relative, run_cmd, target_dir, Result};

/// Makes sure `target/venv` exists and has the requirements installed; returns its python.
///
/// Pip runs only when the requirements changed since the last successful install: the
/// hash of `tests/requirements.txt` and of `python/pyproject.toml` (the study tool, which
/// the requirements install; its console script comes from there) is kept in
/// `target/venv/.requirements-hash`.
pub fn ensure_venv() -> Result<PathBuf> {
    let venv = target_dir().join("venv");
    let python = venv.join("bin").join("python");
    if !python.exists() {
        create_venv(&venv)?;
    }

    let requirements = project_root().join("tests").join("requirements.txt");
    let pyproject = project_root().join("python").join("pyproject.toml");
    let mut content = Vec::new();
    for file in [&requirements, &pyproject] {
        let bytes =
            fs::read(file).map_err(|err| format!("cannot read {}: {err}", relative(file)))?;
        content.extend_from_slice(&bytes);
    }
    let hash = format!("{:016x}", beam_body::hash::fnv1a_64(&content));
    let stamp = venv.join(".requirements-hash");
    if fs::read_to_string(&stamp).is_ok_and(|old| old.trim() == hash) {
        eprintln!("{} is up to date with {}", relative(&venv), relative(&requirements));
        return Ok(python);
    }

    let mut pip = Command::new(&python);
    pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "-r"])
        .arg(relative(&requirements))
        .current_dir(project_root());
    run_cmd(&mut pip).map_err(|err| {
        format!("{err}\n(if the venv itself is broken, delete it: rm -rf {})", relative(&venv))
    })?;
    fs::write(&stamp, format!("{hash}\n"))
        .map_err(|err| format!("cannot write {}: {err}", relative(&stamp)))?;
    Ok(python)
}

fn create_venv(venv: &Path) -> Result {
    let mut cmd = Command::new("python3");
    cmd.args(["-m", "venv"]).arg(relative(venv)).current_dir(project_root());
    if let Err(err) = run_cmd(&mut cmd) {
        // Don't leave a half-made venv behind: the next run would take it for a good one.
        let _ = fs::remove_dir_all(venv);
        let mut message = format!("cannot create the Python venv {}: {err}", relative(venv));
        if venv_module_missing() {
            message.push_str(
                "\npython3 lacks the `venv`/`ensurepip` modules; on Debian or Ubuntu install them \
                 with: apt-get install python3-venv",
            );
        }
        return Err(message.into());
    }
    Ok(())
}

/// True when python3 runs but cannot import `venv` and `ensurepip` (Debian splits them off).
fn venv_module_missing() -> bool {
    Command::new("python3")
        .args(["-c", "import ensurepip, venv"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| !status.success())
}
