//! System packages that the commands need beyond Rust and Python, and their installation:
//! with apt-get when running as root on Debian, otherwise named with the command that installs
//! them.

use std::path::Path;
use std::process::{Command, Stdio};

use crate::{run_cmd, Result};

/// How to tell that a package is installed.
#[derive(Clone, Copy, Debug)]
pub enum Probe {
    /// A program on PATH that answers `--version`.
    Program(&'static str),
    /// A file that the package installs.
    File(&'static str),
}

/// A Debian package and how to tell that it is installed.
#[derive(Clone, Copy, Debug)]
pub struct Package {
    pub name: &'static str,
    pub probe: Probe,
}

const fn program(name: &'static str, program: &'static str) -> Package {
    Package { name, probe: Probe::Program(program) }
}

const fn file(name: &'static str, path: &'static str) -> Package {
    Package { name, probe: Probe::File(path) }
}

/// The C host fixture (cc), libFuzzer (g++) and the C host's memcheck runs (valgrind).
pub const TEST_TOOLS: &[Package] =
    &[program("gcc", "cc"), program("g++", "g++"), program("valgrind", "valgrind")];

/// The cross builds of `cargo xtask fmu --all-platforms` (platforms.rs):
/// - Debian's Rust 1.96 and the standard library's sources, for `-Zbuild-std` (rustup's
///   `target add` downloads from outside the package registries);
/// - the linkers: mingw-w64's gcc (Windows), the aarch64 cross gcc with its glibc (Linux
///   aarch64), and lld's ld64 (macOS), with llvm's objcopy (rustc strips Mach-O with it) and
///   lipo (the universal binary).
pub const CROSS_TOOLCHAINS: &[Package] = &[
    file("rustc-web", "/usr/bin/rustc"),
    file("cargo-web", "/usr/bin/cargo"),
    file("rust-web-src", "/usr/lib/rustlib/src/rust/library/std/Cargo.toml"),
    program("gcc-mingw-w64-x86-64", "x86_64-w64-mingw32-gcc"),
    program("gcc-aarch64-linux-gnu", "aarch64-linux-gnu-gcc"),
    file("libc6-dev-arm64-cross", "/usr/aarch64-linux-gnu/lib/crt1.o"),
    program("lld-22", "ld64.lld-22"),
    program("llvm-22", "llvm-lipo-22"),
];

/// What the cross-built binaries run on here: wine for the Windows DLL, qemu's user mode for
/// Linux aarch64; and Ecos's runtime library (TBB), for the tests in third-party hosts.
pub const FOREIGN_RUNNERS: &[Package] = &[
    file("wine", "/usr/bin/wine"),
    file("wine64", "/usr/lib/wine/wine64"),
    program("qemu-user", "qemu-aarch64"),
    file("libtbb12", "/usr/lib/x86_64-linux-gnu/libtbb.so.12"),
];

fn installed(package: &Package) -> bool {
    match package.probe {
        Probe::Program(program) => Command::new(program)
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success()),
        Probe::File(path) => Path::new(path).exists(),
    }
}

/// Installs the packages of `groups` that are missing, with one apt-get call when running as
/// root on Debian; otherwise fails, naming them. `why` says what needs them.
pub fn ensure(why: &str, groups: &[&[Package]]) -> Result {
    let missing: Vec<&str> =
        groups.iter().flat_map(|g| g.iter()).filter(|p| !installed(p)).map(|p| p.name).collect();
    if missing.is_empty() {
        return Ok(());
    }
    let root = Command::new("id").arg("-u").output().is_ok_and(|o| o.stdout.trim_ascii() == b"0");
    if !(root && Path::new("/usr/bin/apt-get").exists()) {
        return Err(format!(
            "{why} needs the system packages {} (Debian: apt-get install {})",
            missing.join(", "),
            missing.join(" ")
        )
        .into());
    }
    eprintln!("{why} needs {}: installing them with apt-get", missing.join(", "));
    run_cmd(Command::new("apt-get").args(["update", "-qq"]))?;
    run_cmd(
        Command::new("apt-get")
            .args(["install", "-y", "-qq"])
            .env("DEBIAN_FRONTEND", "noninteractive")
            .args(&missing),
    )?;
    match groups.iter().flat_map(|g| g.iter()).find(|p| !installed(p)) {
        None => Ok(()),
        Some(p) => {
            Err(format!("apt-get installed {}, but {:?} is still missing", p.name, p.probe).into())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probes_tell_present_from_absent() {
        assert!(installed(&file("x", "/")));
        assert!(!installed(&file("x", "/no/such/file/anywhere")));
        assert!(installed(&program("x", "cargo")));
        assert!(!installed(&program("x", "no-such-program-anywhere")));
    }
}
