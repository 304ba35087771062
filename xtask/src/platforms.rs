//! The platforms the FMU carries binaries for, and how each is built on this machine (Linux
//! x86-64) from package registries only.
//!
//! - linux64 is the host build, with the toolchain that runs xtask.
//! - Every other target is cross-built by Debian's Rust (`rustc-web` 1.96), which can build
//!   the standard library from `rust-web-src` (`-Zbuild-std`, allowed by `RUSTC_BOOTSTRAP`;
//!   the standard library's own dependencies come from crates.io), because rustup's `target
//!   add` downloads from outside the registries. The linkers: mingw-w64's gcc (Windows), the
//!   aarch64 cross gcc (Linux aarch64) and lld's ld64 against a `libSystem.tbd` stub taken from
//!   the `ziglang` wheel on PyPI (macOS).
//!
//! The archives and their folders ([`ARCHIVES`]):
//!
//! - `BeamBody.fmu`, FMI 2.0: folders as FMI 2.0.4 §2.3 has them (win64, linux64 and darwin64
//!   are 64-bit x86; other platforms use FMI 3.0's platform tuples), with two concessions to
//!   the hosts that exist, which look in the FMI 2.0 folders on every architecture: darwin64
//!   holds a universal binary, so that FMPy on an Apple-silicon Mac finds its arm64 slice there,
//!   and Linux aarch64 gets a second archive, `BeamBody-aarch64-linux.fmu`, whose linux64 holds
//!   the aarch64 binary (an ELF file has one architecture, so one archive cannot serve both
//!   Linux architectures from linux64). docs/decisions.md says why (*Where the binaries go*).
//! - `BeamBody-fmi3.fmu`, FMI 3.0 (its own modelDescription.xml): the same libraries, which
//!   export the fmi2 and the fmi3 functions, in folders named by FMI 3.0's platform tuples:
//!   x86_64-linux, x86_64-windows, x86_64-darwin (the x86_64 build, not the universal one),
//!   aarch64-darwin and aarch64-linux, one folder per architecture, so one archive serves all.

use std::fs;
use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use beam_body::fmu::variables::MODEL_IDENTIFIER;

use crate::descriptions::{self, Description};
use crate::{cargo, project_root, relative, run_cmd, system, target_dir, Result};

/// The FMI 2.0 `binaries/` folder of the host build (the machine xtask runs on).
pub const HOST_FOLDER: &str = host_folder();
/// The FMI 3.0 `binaries/` folder (platform tuple) of the host build.
pub const HOST_TUPLE: &str = host_tuple();

const fn host_folder() -> &'static str {
    if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        "linux64"
    } else if cfg!(all(target_os = "windows", target_arch = "x86_64")) {
        "win64"
    } else if cfg!(target_os = "macos") {
        "darwin64"
    } else if cfg!(all(target_os = "linux", target_arch = "aarch64")) {
        "aarch64-linux"
    } else {
        "unknown"
    }
}

const fn host_tuple() -> &'static str {
    if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        "x86_64-linux"
    } else if cfg!(all(target_os = "windows", target_arch = "x86_64")) {
        "x86_64-windows"
    } else if cfg!(all(target_os = "macos", target_arch = "x86_64")) {
        "x86_64-darwin"
    } else if cfg!(all(target_os = "macos", target_arch = "aarch64")) {
        "aarch64-darwin"
    } else if cfg!(all(target_os = "linux", target_arch = "aarch64")) {
        "aarch64-linux"
    } else {
        "unknown"
    }
}

/// A target that Debian's Rust cross-builds.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Cross {
    Win64,
    LinuxAarch64,
    MacX86_64,
    MacArm64,
}

impl Cross {
    pub const ALL: [Cross; 4] =
        [Cross::Win64, Cross::LinuxAarch64, Cross::MacX86_64, Cross::MacArm64];

    pub fn triple(self) -> &'static str {
        match self {
            Cross::Win64 => "x86_64-pc-windows-gnu",
            Cross::LinuxAarch64 => "aarch64-unknown-linux-gnu",
            Cross::MacX86_64 => "x86_64-apple-darwin",
            Cross::MacArm64 => "aarch64-apple-darwin",
        }
    }

    /// The file Cargo writes.
    fn output(self) -> &'static str {
        match self {
            Cross::Win64 => "beam_body.dll",
            Cross::LinuxAarch64 => "libbeam_body.so",
            Cross::MacX86_64 | Cross::MacArm64 => "libbeam_body.dylib",
        }
    }

    /// Cargo's per-target variable `CARGO_TARGET_<TRIPLE>_<what>`.
    fn var(self, what: &str) -> String {
        format!("CARGO_TARGET_{}_{what}", self.triple().to_uppercase().replace('-', "_"))
    }

    fn is_apple(self) -> bool {
        matches!(self, Cross::MacX86_64 | Cross::MacArm64)
    }

    /// The linker, and the flags beyond the release profile.
    fn linker_and_flags(self) -> (&'static str, Vec<String>) {
        match self {
            // No link timestamp: the same sources give the same DLL.
            Cross::Win64 => {
                ("x86_64-w64-mingw32-gcc", vec!["-C link-arg=-Wl,--no-insert-timestamp".into()])
            }
            Cross::LinuxAarch64 => ("aarch64-linux-gnu-gcc", vec![]),
            // rustc hands the exported-symbols list and -dead_strip to ld64.lld directly; the
            // install name would otherwise be the build path.
            Cross::MacX86_64 | Cross::MacArm64 => (
                "ld64.lld-22",
                vec![
                    "-C linker-flavor=ld64.lld".into(),
                    "-C link-arg=-install_name".into(),
                    format!("-C link-arg=@rpath/{MODEL_IDENTIFIER}.dylib"),
                ],
            ),
        }
    }
}

/// Where a binary in an archive comes from.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Source {
    Host,
    Cross(Cross),
    /// The two macOS builds joined into one universal (fat) Mach-O.
    MacUniversal,
}

/// An archive: its file name under target/fmu/, its modelDescription.xml and its binaries
/// (folder under binaries/, source).
pub struct Archive {
    pub file: &'static str,
    pub description: &'static Description,
    pub binaries: &'static [(&'static str, Source)],
}

/// The FMI 2.0 FMU for every desktop platform.
pub const MAIN_FILE: &str = "BeamBody.fmu";
/// The FMI 2.0 FMU for hosts on Linux aarch64.
pub const AARCH64_LINUX_FILE: &str = "BeamBody-aarch64-linux.fmu";
/// The FMI 3.0 FMU for every desktop platform.
pub const FMI3_FILE: &str = "BeamBody-fmi3.fmu";

/// The FMI 2.0 FMU for every desktop platform, the one for FMI 2.0 hosts on Linux aarch64,
/// and the FMI 3.0 FMU.
pub const ARCHIVES: [Archive; 3] = [
    Archive {
        file: MAIN_FILE,
        description: &descriptions::FMI2,
        binaries: &[
            ("linux64", Source::Host),
            ("win64", Source::Cross(Cross::Win64)),
            ("darwin64", Source::MacUniversal),
            ("aarch64-darwin", Source::Cross(Cross::MacArm64)),
            ("aarch64-linux", Source::Cross(Cross::LinuxAarch64)),
        ],
    },
    Archive {
        file: AARCH64_LINUX_FILE,
        description: &descriptions::FMI2,
        binaries: &[
            ("linux64", Source::Cross(Cross::LinuxAarch64)),
            ("aarch64-linux", Source::Cross(Cross::LinuxAarch64)),
        ],
    },
    Archive {
        file: FMI3_FILE,
        description: &descriptions::FMI3,
        binaries: &[
            ("x86_64-linux", Source::Host),
            ("x86_64-windows", Source::Cross(Cross::Win64)),
            ("x86_64-darwin", Source::Cross(Cross::MacX86_64)),
            ("aarch64-darwin", Source::Cross(Cross::MacArm64)),
            ("aarch64-linux", Source::Cross(Cross::LinuxAarch64)),
        ],
    },
];

/// The host-only archives of `cargo xtask fmu`: FMI 2.0 and FMI 3.0.
pub const HOST_ARCHIVES: [Archive; 2] = [
    Archive {
        file: MAIN_FILE,
        description: &descriptions::FMI2,
        binaries: &[(HOST_FOLDER, Source::Host)],
    },
    Archive {
        file: FMI3_FILE,
        description: &descriptions::FMI3,
        binaries: &[(HOST_TUPLE, Source::Host)],
    },
];

/// The archives `cargo xtask fmu` writes: [`ARCHIVES`] with `--all-platforms` (`all`), else
/// [`HOST_ARCHIVES`].
pub fn archives(all: bool) -> &'static [Archive] {
    if all {
        &ARCHIVES
    } else {
        &HOST_ARCHIVES
    }
}

/// The platforms the README describes, by FMI 3.0 platform tuple, with their names: those of
/// [`FMI3_FILE`] in [`ARCHIVES`], one folder each.
pub const PLATFORMS: [(&str, &str); 5] = [
    ("x86_64-linux", "Linux x86-64"),
    ("x86_64-windows", "Windows x86-64"),
    ("x86_64-darwin", "macOS x86-64"),
    ("aarch64-darwin", "macOS arm64"),
    ("aarch64-linux", "Linux aarch64"),
];

/// The name of the platform of [`PLATFORMS`] with this tuple.
pub fn platform_name(tuple: &str) -> &'static str {
    PLATFORMS.iter().find(|(t, _)| *t == tuple).map_or("an unknown platform", |p| p.1)
}

impl Source {
    /// The platforms (FMI 3.0 tuples) that a binary from this source runs on.
    pub fn platforms(self) -> &'static [&'static str] {
        match self {
            Source::Host => std::slice::from_ref(&HOST_TUPLE),
            Source::Cross(Cross::Win64) => &["x86_64-windows"],
            Source::Cross(Cross::LinuxAarch64) => &["aarch64-linux"],
            Source::Cross(Cross::MacX86_64) => &["x86_64-darwin"],
            Source::Cross(Cross::MacArm64) => &["aarch64-darwin"],
            Source::MacUniversal => &["x86_64-darwin", "aarch64-darwin"],
        }
    }
}

/// The shared-library file name in a `binaries/` folder.
pub fn library_name(folder: &str) -> String {
    let extension = if folder.starts_with("win") || folder.ends_with("-windows") {
        "dll"
    } else if folder.starts_with("darwin") || folder.ends_with("-darwin") {
        "dylib"
    } else {
        "so"
    };
    format!("{MODEL_IDENTIFIER}.{extension}")
}

/// Target directory of the cross builds: Debian's rustc has artifacts of its own.
fn cross_dir() -> PathBuf {
    target_dir().join("cross")
}

/// The built libraries, by source.
pub struct Built {
    pub host: PathBuf,
    cross: Vec<(Cross, PathBuf)>,
    mac_universal: Option<PathBuf>,
}

impl Built {
    pub fn path(&self, source: Source) -> Result<&Path> {
        let found = match source {
            Source::Host => Some(&self.host),
            Source::Cross(c) => self.cross.iter().find(|(k, _)| *k == c).map(|(_, p)| p),
            Source::MacUniversal => self.mac_universal.as_ref(),
        };
        found.map(PathBuf::as_path).ok_or_else(|| format!("{source:?} was not built").into())
    }
}

/// Builds the host library and, with `all`, every cross target and the universal macOS
/// binary.
pub fn build(all: bool) -> Result<Built> {
    let host = build_host()?;
    if !all {
        return Ok(Built { host, cross: Vec::new(), mac_universal: None });
    }
    system::ensure("cargo xtask fmu --all-platforms", &[system::CROSS_TOOLCHAINS])?;
    let sdk = macos_sdk()?;
    let mut cross = Vec::new();
    for target in Cross::ALL {
        cross.push((target, build_cross(target, &sdk)?));
    }
    let mac = |c| cross.iter().find(|(k, _)| *k == c).map(|(_, p): &(Cross, PathBuf)| p.clone());
    let (arm64, x86_64) = (mac(Cross::MacArm64), mac(Cross::MacX86_64));
    let universal = cross_dir().join("universal-apple-darwin").join("libbeam_body.dylib");
    fs::create_dir_all(universal.parent().unwrap_or(Path::new(".")))?;
    run_cmd(
        Command::new("llvm-lipo-22")
            .arg("-create")
            .args(arm64.iter().chain(x86_64.iter()))
            .arg("-output")
            .arg(&universal),
    )?;
    Ok(Built { host, cross, mac_universal: Some(universal) })
}

/// The arguments of Cargo that build the FMU's binary: `rustc --release --lib --crate-type
/// cdylib`, without the default features (the study code, which an FMU does not use). The
/// crate type is given here, not in Cargo.toml, so that the cdylib is the unit's only crate
/// type and gets the release profile's LTO.
const CDYLIB: [&str; 6] =
    ["rustc", "--release", "--lib", "--no-default-features", "--crate-type", "cdylib"];

/// Builds the host's cdylib ([`CDYLIB`]) and returns it.
fn build_host() -> Result<PathBuf> {
    run_cmd(&mut cargo(CDYLIB))?;
    let name = if cfg!(windows) {
        "beam_body.dll"
    } else if cfg!(target_os = "macos") {
        "libbeam_body.dylib"
    } else {
        "libbeam_body.so"
    };
    existing(target_dir().join("release").join(name))
}

fn existing(path: PathBuf) -> Result<PathBuf> {
    if path.is_file() {
        Ok(path)
    } else {
        Err(format!("the build did not produce {}", relative(&path)).into())
    }
}

/// One cross build with Debian's cargo and rustc, std built from source.
fn build_cross(target: Cross, sdk: &Path) -> Result<PathBuf> {
    let started = Instant::now();
    let mut cmd = debian_cargo(target, sdk)?;
    cmd.args(CDYLIB).arg("--target").arg(target.triple()).arg("-Zbuild-std=std,panic_unwind");
    run_cmd(&mut cmd)?;
    let out = cross_dir().join(target.triple()).join("release").join(target.output());
    let out = existing(out)?;
    eprintln!("{}: {:.0} s", target.triple(), started.elapsed().as_secs_f64());
    Ok(out)
}

/// The library's Rust tests (unit and integration tests, release profile) built for Linux
/// aarch64 and run under qemu's user mode, with the cross glibc as the loader's root.
pub fn test_linux_aarch64() -> Result {
    system::ensure("the aarch64 tests", &[system::CROSS_TOOLCHAINS, system::FOREIGN_RUNNERS])?;
    let target = Cross::LinuxAarch64;
    let mut cmd = debian_cargo(target, Path::new(""))?;
    cmd.args(["test", "--release", "-p", "beam-body", "--lib", "--tests", "--target"])
        .arg(target.triple())
        .arg("-Zbuild-std")
        .env(target.var("RUNNER"), "qemu-aarch64 -L /usr/aarch64-linux-gnu");
    run_cmd(&mut cmd)
}

/// Debian's cargo and rustc, configured for `target`: its linker and flags, the macOS SDK
/// and objcopy, and the cross target directory.
fn debian_cargo(target: Cross, sdk: &Path) -> Result<Command> {
    let (linker, flags) = target.linker_and_flags();
    let mut cmd = Command::new("/usr/bin/cargo");
    cmd.current_dir(project_root())
        .env("CARGO_TARGET_DIR", cross_dir())
        .env("RUSTC", "/usr/bin/rustc")
        .env("RUSTC_BOOTSTRAP", "1")
        .env(target.var("LINKER"), linker)
        .env(target.var("RUSTFLAGS"), flags.join(" "));
    // The toolchain that runs xtask must not leak into Debian's.
    for leak in ["RUSTUP_TOOLCHAIN", "RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS", "RUSTC_WRAPPER"] {
        cmd.env_remove(leak);
    }
    if target.is_apple() {
        // rustc strips Mach-O with `rust-objcopy`, which rustup ships and Debian does not;
        // llvm's objcopy under that name does the same.
        let bin = cross_dir().join("bin");
        link_tool(&bin.join("rust-objcopy"), Path::new("/usr/bin/llvm-objcopy-22"))?;
        let path = std::env::var_os("PATH").unwrap_or_default();
        let path = std::env::join_paths(std::iter::once(bin).chain(std::env::split_paths(&path)))?;
        cmd.env("PATH", path).env("SDKROOT", sdk);
    }
    Ok(cmd)
}

fn link_tool(link: &Path, to: &Path) -> Result {
    if fs::read_link(link).is_ok_and(|t| t == to) {
        return Ok(());
    }
    fs::create_dir_all(link.parent().unwrap_or(Path::new(".")))?;
    let _ = fs::remove_file(link);
    std::os::unix::fs::symlink(to, link)
        .map_err(|err| format!("cannot link {} to {}: {err}", relative(link), to.display()).into())
}

/// The ziglang wheel whose `libSystem.tbd` the macOS link uses: pinned by version and hash
/// (the manylinux x86-64 wheel; pip downloads it on any host with `--platform`).
const ZIGLANG: &str = "ziglang==0.17.1";
const ZIGLANG_SHA256: &str = "ea6cc5d87b033cf0aedfbc8f9549a908cae6c50ac31f1698188fa48a74524b54";
const ZIGLANG_PLATFORM: &str = "manylinux_2_12_x86_64";
const TBD_IN_WHEEL: &str = "ziglang/lib/libc/darwin/libSystem.tbd";

/// An SDK root for ld64.lld with `usr/lib/libSystem.tbd` (and `libc.tbd`, `libm.tbd`, which
/// are libSystem in Apple's SDKs too; std links all three), made once from the ziglang wheel.
fn macos_sdk() -> Result<PathBuf> {
    let sdk = cross_dir().join("macos-sdk");
    let lib = sdk.join("usr").join("lib");
    let stamp = sdk.join("source.txt");
    let source = format!(
        "{TBD_IN_WHEEL} from {ZIGLANG} (sha256 {ZIGLANG_SHA256}), arm64e entries as arm64\n"
    );
    if fs::read_to_string(&stamp).is_ok_and(|s| s == source) {
        return Ok(sdk);
    }
    let downloads = cross_dir().join("downloads");
    fs::create_dir_all(&downloads)?;
    let requirement = downloads.join("ziglang.txt");
    crate::write_text(&requirement, &format!("{ZIGLANG} --hash=sha256:{ZIGLANG_SHA256}\n"))?;
    run_cmd(
        Command::new("python3")
            .args(["-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:"])
            .args(["--platform", ZIGLANG_PLATFORM, "--require-hashes", "-r"])
            .arg(&requirement)
            .arg("-d")
            .arg(&downloads),
    )?;
    let wheel = fs::read_dir(&downloads)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("ziglang-0.17.1-")))
        .ok_or("pip download left no ziglang wheel")?;
    let mut archive = zip::ZipArchive::new(fs::File::open(&wheel)?)
        .map_err(|err| format!("{} is not a wheel: {err}", relative(&wheel)))?;
    let mut tbd = String::new();
    archive
        .by_name(TBD_IN_WHEEL)
        .map_err(|err| format!("{} has no {TBD_IN_WHEEL}: {err}", relative(&wheel)))?
        .read_to_string(&mut tbd)?;
    let tbd = arm64e_as_arm64(&tbd);
    fs::create_dir_all(&lib)?;
    for name in ["libSystem.tbd", "libc.tbd", "libm.tbd"] {
        crate::write_text(&lib.join(name), &tbd)?;
    }
    crate::write_text(&stamp, &source)?;
    Ok(sdk)
}

/// The stub's target lists with `arm64e` read as `arm64`, and the `arm64e.x1` variants
/// dropped. Zig's stub lists most of libSystem for arm64e only (zig's linker takes it for
/// arm64); lld takes the targets literally, and LLVM 19 cannot even parse `arm64e.x1`.
fn arm64e_as_arm64(tbd: &str) -> String {
    let mut out = String::with_capacity(tbd.len());
    let mut rest = tbd;
    while let Some(at) = rest.find("targets:") {
        let (head, tail) = rest.split_at(at);
        out.push_str(head);
        let (Some(open), Some(close)) = (tail.find('['), tail.find(']')) else {
            out.push_str(tail);
            return out;
        };
        let mut targets: Vec<String> = Vec::new();
        for item in tail[open + 1..close].split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let item = match item.strip_prefix("arm64e") {
                Some(platform) if platform.starts_with('-') => format!("arm64{platform}"),
                Some(_) => continue,
                None => item.to_string(),
            };
            if !targets.contains(&item) {
                targets.push(item);
            }
        }
        out.push_str("targets: [ ");
        out.push_str(&targets.join(", "));
        out.push_str(" ]");
        rest = &tail[close + 1..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stub_targets_read_arm64e_as_arm64() {
        let tbd = "--- !tapi-tbd\ntargets:         [ x86_64-macos, arm64e-macos, \n                   arm64e.x1-macos, arm64e-maccatalyst ]\nexports:\n  - targets:         [ x86_64-macos, arm64-macos, arm64e-macos ]\n    symbols: [ _sin ]\n";
        assert_eq!(
            arm64e_as_arm64(tbd),
            "--- !tapi-tbd\ntargets: [ x86_64-macos, arm64-macos, arm64-maccatalyst ]\nexports:\n  - targets: [ x86_64-macos, arm64-macos ]\n    symbols: [ _sin ]\n"
        );
    }

    #[test]
    fn library_names_follow_the_folder() {
        assert_eq!(library_name("linux64"), "BeamBody.so");
        assert_eq!(library_name("aarch64-linux"), "BeamBody.so");
        assert_eq!(library_name("win64"), "BeamBody.dll");
        assert_eq!(library_name("darwin64"), "BeamBody.dylib");
        assert_eq!(library_name("aarch64-darwin"), "BeamBody.dylib");
        assert_eq!(library_name("x86_64-linux"), "BeamBody.so");
        assert_eq!(library_name("x86_64-windows"), "BeamBody.dll");
        assert_eq!(library_name("x86_64-darwin"), "BeamBody.dylib");
    }

    /// The FMI 3.0 archive: its own modelDescription, one platform tuple per architecture, a
    /// thin binary in each (no universal one), and every library the FMI 2.0 archive carries.
    #[test]
    fn the_fmi3_archive_has_every_platform_in_its_tuple() {
        let fmi3 = ARCHIVES.iter().find(|a| a.file == FMI3_FILE).unwrap();
        assert_eq!(fmi3.description.relative_path, descriptions::FMI3.relative_path);
        let expected = [
            ("x86_64-linux", Source::Host),
            ("x86_64-windows", Source::Cross(Cross::Win64)),
            ("x86_64-darwin", Source::Cross(Cross::MacX86_64)),
            ("aarch64-darwin", Source::Cross(Cross::MacArm64)),
            ("aarch64-linux", Source::Cross(Cross::LinuxAarch64)),
        ];
        assert_eq!(fmi3.binaries, expected);
        for archive in ARCHIVES.iter().filter(|a| a.file != FMI3_FILE) {
            assert_eq!(archive.description.relative_path, descriptions::FMI2.relative_path);
        }
        let host: Vec<_> =
            HOST_ARCHIVES.iter().map(|a| (a.file, a.description.relative_path)).collect();
        assert_eq!(
            host,
            [
                (MAIN_FILE, descriptions::FMI2.relative_path),
                (FMI3_FILE, descriptions::FMI3.relative_path)
            ]
        );
        assert_eq!(HOST_ARCHIVES[1].binaries, [(HOST_TUPLE, Source::Host)]);
    }

    /// [`PLATFORMS`] are the FMI 3.0 archive's folders, in its order, and every binary of
    /// every archive runs on some of them.
    #[test]
    fn the_platforms_are_the_fmi3_archive_s_folders() {
        let fmi3 = ARCHIVES.iter().find(|a| a.file == FMI3_FILE).unwrap();
        let folders: Vec<_> = fmi3.binaries.iter().map(|(f, _)| *f).collect();
        let tuples: Vec<_> = PLATFORMS.iter().map(|(t, _)| *t).collect();
        assert_eq!(folders, tuples);
        for (folder, source) in fmi3.binaries {
            assert_eq!(source.platforms(), [*folder], "{folder}");
        }
        for archive in ARCHIVES.iter().chain(&HOST_ARCHIVES) {
            for (_, source) in archive.binaries {
                assert!(source.platforms().iter().all(|p| tuples.contains(p)), "{source:?}");
            }
        }
    }

    #[test]
    fn every_archive_binary_has_a_distinct_folder() {
        for archive in ARCHIVES.iter().chain(&HOST_ARCHIVES) {
            let mut folders: Vec<_> = archive.binaries.iter().map(|(f, _)| *f).collect();
            folders.sort_unstable();
            folders.dedup();
            assert_eq!(folders.len(), archive.binaries.len(), "{}", archive.file);
        }
    }
}
