//! An optimised CVODE for the benchmark's `cvode` solver, built once from source without
//! cmake, bindgen or libclang: [`ensure_optimized_cvode`].
//!
//! Debian's `libsundials_cvode.so.6` is compiled without optimisation (the code of `gcc -O0`)
//! and runs about 3× slower than the same solver compiled as CMake's Release build compiles
//! it, with identical steps and counters, so a comparison against it would flatter us. This
//! builds SUNDIALS 7.1.1's CVODE, whose C sources the `sundials-sys` 0.6.2 crate vendors, with
//! the C compiler alone:
//!
//! 1. The source: `cargo fetch` on a throwaway manifest (`target/bench/sundials/fetch/`) that
//!    depends on `sundials-sys = "=0.6.2"` puts `sundials-sys-0.6.2.crate` in cargo's registry
//!    cache (crates.io is the only network access; nothing is compiled, so sundials-sys's
//!    build script, bindgen and libclang never run). Skipped when the cache holds it already.
//!    The `.crate` (a gzipped tarball) is unpacked with `tar` into `target/bench/sundials/src/`.
//! 2. The configuration: CMake would generate `sundials_config.h` and `sundials_export.h`;
//!    hand-written equivalents (`bench/sundials/*.h`, embedded here) hold CMake's defaults for
//!    a Release build of CVODE with gcc on Linux: double precision, 64-bit indices, no error
//!    checks, logging level 2, no MPI or third-party libraries.
//! 3. The build: of the sources CMake puts in `libsundials_cvode` and `libsundials_core`,
//!    those of CVODE with its dense and band direct solvers (CVODE without its band and BBD
//!    preconditioners, the SUNDIALS core, the serial N_Vector, the dense, band and sparse
//!    SUNMatrix, the dense and band SUNLinearSolvers, the Newton and fixed-point
//!    SUNNonlinearSolvers;
//!    plus `cvode_fused_stubs.c`, which CMake adds only with fused kernels: unused here), each
//!    compiled with `cc -std=gnu99 -O3 -DNDEBUG -fPIC` (CMake's
//!    Release flags and its `CMAKE_C_STANDARD` 99 with extensions), over the machine's cores,
//!    then linked into one shared library, `target/bench/sundials/libsundials_cvode_opt.so`,
//!    with `-Wl,--no-undefined` (every symbol resolved within it and libm/libc). Like
//!    Debian's library it holds its own copies of the generic layer, the vector, the matrix
//!    and the linear solver, which is what `cvode.rs` expects of a library named by
//!    `BEAM_BODY_CVODE_LIB`.
//!
//! A stamp file next to the library records the recipe (its version, the compiler and its
//! version, the flags, the source list, the headers); a library whose stamp differs is
//! rebuilt. The one-time cost is 1-2 s for the download and 4-8 s for the compile (2 cores).
//! On the paper scene at rtol 1e-6 this library takes 0.34× the time of Debian's (1.3 ms
//! against 3.8 ms, the same 2808 steps); `-O2` is as fast as `-O3`, within the noise.

use std::env;
use std::ffi::{c_char, c_int, CStr, OsString};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::thread;
use std::time::Instant;

/// Bumped whenever the recipe changes in a way the stamp would not otherwise show.
const RECIPE_VERSION: u32 = 2;
/// The crate that vendors SUNDIALS' sources, and its version (`=` in the manifest).
const CRATE: &str = "sundials-sys";
const CRATE_VERSION: &str = "0.6.2";
/// The SUNDIALS release vendored by that crate (checked against its CMakeLists.txt).
const SUNDIALS_VERSION: &str = "7.1.1";
/// The library built, and its stamp, in `<target>/bench/sundials/`.
const LIBRARY: &str = "libsundials_cvode_opt.so";
const STAMP: &str = "libsundials_cvode_opt.stamp";
/// CMake's `CMAKE_C_FLAGS_RELEASE` (`-O3 -DNDEBUG`), its C standard (99 with GNU
/// extensions), and position-independent code for a shared library.
const CFLAGS: [&str; 4] = ["-std=gnu99", "-O3", "-DNDEBUG", "-fPIC"];
/// The hand-written configuration headers, installed as `include/sundials/<name>`.
const HEADERS: [(&str, &str); 2] = [
    ("sundials_config.h", include_str!("sundials/sundials_config.h")),
    ("sundials_export.h", include_str!("sundials/sundials_export.h")),
];
/// The C sources compiled, relative to the crate's `vendor/` directory.
const SOURCES: [&str; 34] = [
    "src/cvode/cvode.c",
    "src/cvode/cvode_diag.c",
    "src/cvode/cvode_fused_stubs.c",
    "src/cvode/cvode_io.c",
    "src/cvode/cvode_ls.c",
    "src/cvode/cvode_nls.c",
    "src/cvode/cvode_proj.c",
    "src/sundials/sundials_adaptcontroller.c",
    "src/sundials/sundials_band.c",
    "src/sundials/sundials_context.c",
    "src/sundials/sundials_dense.c",
    "src/sundials/sundials_direct.c",
    "src/sundials/sundials_errors.c",
    "src/sundials/sundials_futils.c",
    "src/sundials/sundials_hashmap.c",
    "src/sundials/sundials_iterative.c",
    "src/sundials/sundials_linearsolver.c",
    "src/sundials/sundials_logger.c",
    "src/sundials/sundials_math.c",
    "src/sundials/sundials_matrix.c",
    "src/sundials/sundials_memory.c",
    "src/sundials/sundials_nonlinearsolver.c",
    "src/sundials/sundials_nvector.c",
    "src/sundials/sundials_nvector_senswrapper.c",
    "src/sundials/sundials_profiler.c",
    "src/sundials/sundials_version.c",
    "src/nvector/serial/nvector_serial.c",
    "src/sunmatrix/band/sunmatrix_band.c",
    "src/sunmatrix/dense/sunmatrix_dense.c",
    "src/sunmatrix/sparse/sunmatrix_sparse.c",
    "src/sunlinsol/band/sunlinsol_band.c",
    "src/sunlinsol/dense/sunlinsol_dense.c",
    "src/sunnonlinsol/fixedpoint/sunnonlinsol_fixedpoint.c",
    "src/sunnonlinsol/newton/sunnonlinsol_newton.c",
];
/// The include directories, after `include/` (the configuration headers), relative to
/// `vendor/`.
const INCLUDES: [&str; 3] = ["include", "src/sundials", "src/cvode"];

/// Returns the path of an optimised CVODE (SUNDIALS 7.1.1, `-O3`), building it first if
/// `<target_dir>/bench/sundials/` does not hold one built by the current recipe. The path is
/// absolute, for `BEAM_BODY_CVODE_LIB` (see `cvode.rs`). Needs `cargo` (crates.io, unless the
/// crate is in cargo's cache already), `tar` and a C compiler (`$CC`, else `cc`).
pub fn ensure_optimized_cvode(target_dir: &Path) -> Result<PathBuf, String> {
    let dir = target_dir.join("bench").join("sundials");
    let library = dir.join(LIBRARY);
    let stamp_path = dir.join(STAMP);
    let compiler = compiler();
    let stamp = stamp(&compiler);
    if library.is_file() && fs::read_to_string(&stamp_path).is_ok_and(|s| s == stamp) {
        return absolute(&library);
    }
    fs::create_dir_all(&dir).map_err(|err| format!("cannot create {}: {err}", dir.display()))?;
    let started = Instant::now();
    let vendor = vendored_sources(&dir)?;
    let fetched = started.elapsed();
    eprintln!(
        "building SUNDIALS {SUNDIALS_VERSION} CVODE with {} (one-time, ~10 s) into {}…",
        CFLAGS.join(" "),
        library.display()
    );
    let built = Instant::now();
    build(&dir, &vendor, &compiler, &library)?;
    let version = check_library(&library)?;
    if version != SUNDIALS_VERSION {
        return Err(format!(
            "{}: SUNDIALSGetVersion gives {version}, {SUNDIALS_VERSION} expected",
            library.display()
        ));
    }
    fs::write(&stamp_path, &stamp)
        .map_err(|err| format!("cannot write {}: {err}", stamp_path.display()))?;
    eprintln!(
        "built {} (SUNDIALS {version}): source {:.1} s, compile {:.1} s",
        library.display(),
        fetched.as_secs_f64(),
        built.elapsed().as_secs_f64()
    );
    absolute(&library)
}

fn absolute(path: &Path) -> Result<PathBuf, String> {
    fs::canonicalize(path).map_err(|err| format!("{}: {err}", path.display()))
}

/// The C compiler: `$CC` if set, else `cc`.
fn compiler() -> OsString {
    env::var_os("CC").filter(|cc| !cc.is_empty()).unwrap_or_else(|| "cc".into())
}

/// What the library is built from; a cached library is reused only if its stamp equals this.
fn stamp(compiler: &OsString) -> String {
    // The compiler's version, so that a new compiler rebuilds (empty if it cannot run; the
    // build then fails with the reason).
    let version = Command::new(compiler)
        .arg("--version")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|s| s.lines().next().map(str::to_string))
        .unwrap_or_default();
    let mut text = format!(
        "recipe {RECIPE_VERSION}\n{CRATE} {CRATE_VERSION} (SUNDIALS {SUNDIALS_VERSION})\n\
         compiler {} ({version})\ncflags {}\nsources {}\n",
        compiler.to_string_lossy(),
        CFLAGS.join(" "),
        SOURCES.join(" ")
    );
    for (name, content) in HEADERS {
        text.push_str(&format!("--- {name}\n{content}"));
    }
    text
}

// ---------------------------------------------------------------------------------------
// The source.

/// `<dir>/src/sundials-sys-0.6.2/vendor`, unpacked from the crate (fetched first if cargo's
/// cache lacks it) unless it is there already.
fn vendored_sources(dir: &Path) -> Result<PathBuf, String> {
    let src = dir.join("src");
    let vendor = src.join(format!("{CRATE}-{CRATE_VERSION}")).join("vendor");
    if complete(&vendor) {
        return Ok(vendor);
    }
    let crate_file = match cached_crate() {
        Some(file) => file,
        None => {
            fetch(dir)?;
            match cached_crate() {
                Some(file) => file,
                // Cargo skips the download when it has the crate unpacked in registry/src
                // already (its .crate may have been cleaned away): use that tree.
                None => {
                    return unpacked_crate().ok_or_else(|| {
                        format!(
                            "`cargo fetch` succeeded but {CRATE}-{CRATE_VERSION} is neither in {} \
                             nor in {}",
                            cargo_home().join("registry").join("cache").display(),
                            cargo_home().join("registry").join("src").display()
                        )
                    })
                }
            }
        }
    };
    eprintln!("unpacking {} into {}", crate_file.display(), src.display());
    // Into a fresh directory renamed into place, so an interrupted unpack leaves no half tree.
    let partial = dir.join("src.partial");
    for stale in [&partial, &src] {
        if stale.exists() {
            fs::remove_dir_all(stale)
                .map_err(|err| format!("cannot remove {}: {err}", stale.display()))?;
        }
    }
    fs::create_dir_all(&partial)
        .map_err(|err| format!("cannot create {}: {err}", partial.display()))?;
    let mut tar = Command::new("tar");
    tar.arg("-xzf").arg(&crate_file).arg("-C").arg(&partial);
    run(&mut tar)?;
    fs::rename(&partial, &src).map_err(|err| {
        format!("cannot rename {} to {}: {err}", partial.display(), src.display())
    })?;
    if !complete(&vendor) {
        return Err(format!("{} lacks SUNDIALS' sources", crate_file.display()));
    }
    let cmake = fs::read_to_string(vendor.join("CMakeLists.txt")).unwrap_or_default();
    let parts: Vec<&str> = SUNDIALS_VERSION.split('.').collect();
    for (name, value) in ["MAJOR", "MINOR", "PATCH"].iter().zip(parts) {
        if !cmake.contains(&format!("set(PACKAGE_VERSION_{name} \"{value}\")")) {
            return Err(format!("{}: not SUNDIALS {SUNDIALS_VERSION}", vendor.display()));
        }
    }
    Ok(vendor)
}

/// Whether `vendor` holds every source and include directory the build uses.
fn complete(vendor: &Path) -> bool {
    SOURCES.iter().all(|s| vendor.join(s).is_file())
        && INCLUDES.iter().all(|i| vendor.join(i).is_dir())
        && vendor.join("CMakeLists.txt").is_file()
}

/// `$CARGO_HOME`, else `~/.cargo`.
fn cargo_home() -> PathBuf {
    if let Some(home) = env::var_os("CARGO_HOME").filter(|h| !h.is_empty()) {
        return PathBuf::from(home);
    }
    PathBuf::from(env::var_os("HOME").unwrap_or_default()).join(".cargo")
}

/// `sundials-sys-0.6.2.crate` in cargo's download cache (`registry/cache/<registry>/`).
fn cached_crate() -> Option<PathBuf> {
    let cache = cargo_home().join("registry").join("cache");
    let name = format!("{CRATE}-{CRATE_VERSION}.crate");
    let mut registries: Vec<PathBuf> =
        fs::read_dir(cache).ok()?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    registries.sort();
    registries.into_iter().map(|r| r.join(&name)).find(|f| f.is_file())
}

/// `sundials-sys-0.6.2/vendor` as cargo unpacked it (`registry/src/<registry>/`), if complete.
fn unpacked_crate() -> Option<PathBuf> {
    let src = cargo_home().join("registry").join("src");
    let mut registries: Vec<PathBuf> =
        fs::read_dir(src).ok()?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    registries.sort();
    registries
        .into_iter()
        .map(|r| r.join(format!("{CRATE}-{CRATE_VERSION}")).join("vendor"))
        .find(|v| complete(v))
}

/// Downloads the crate into cargo's cache: `cargo fetch` on a manifest that depends on it.
fn fetch(dir: &Path) -> Result<(), String> {
    let project = dir.join("fetch");
    let lib = project.join("src").join("lib.rs");
    fs::create_dir_all(project.join("src"))
        .map_err(|err| format!("cannot create {}: {err}", project.display()))?;
    // `[workspace]`: its own workspace root, not a stray member of the project's workspace
    // (it lies under `target/`, inside the project).
    let manifest = format!(
        "# Written by `cargo xtask bench` (bench/src/bench/sundials_build.rs): only fetched,\n\
         # never built, for SUNDIALS' C sources vendored in {CRATE}.\n\
         [package]\nname = \"fetch-sundials-sources\"\nversion = \"0.0.0\"\nedition = \"2021\"\n\
         publish = false\n\n[dependencies]\n\
         {CRATE} = {{ version = \"={CRATE_VERSION}\", default-features = false }}\n\n\
         [workspace]\n"
    );
    let manifest_path = project.join("Cargo.toml");
    fs::write(&manifest_path, manifest)
        .and_then(|()| fs::write(&lib, ""))
        .map_err(|err| format!("cannot write {}: {err}", project.display()))?;
    eprintln!(
        "fetching {CRATE} {CRATE_VERSION} (SUNDIALS {SUNDIALS_VERSION}'s C sources) from crates.io"
    );
    let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.arg("fetch").arg("--manifest-path").arg(&manifest_path).current_dir(&project);
    // Only this platform's dependencies (not windows-sys' import libraries): they are
    // downloaded with the crate though never built.
    if let Some(host) = host_triple() {
        cmd.args(["--target", &host]);
    }
    run(&mut cmd).map_err(|err| {
        format!(
            "cannot fetch {CRATE} {CRATE_VERSION} from crates.io for SUNDIALS' sources (or set \
             BEAM_BODY_CVODE_LIB to a CVODE library): {err}"
        )
    })
}

/// rustc's host triple, from `rustc -vV`.
fn host_triple() -> Option<String> {
    let rustc = env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    let out = Command::new(rustc).arg("-vV").output().ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    text.lines().find_map(|l| l.strip_prefix("host: ")).map(|h| h.trim().to_string())
}

// ---------------------------------------------------------------------------------------
// The build.

/// Compiles [`SOURCES`] into `<dir>/obj/` in parallel and links them into `library`.
fn build(dir: &Path, vendor: &Path, compiler: &OsString, library: &Path) -> Result<(), String> {
    let include = dir.join("include");
    let headers = include.join("sundials");
    fs::create_dir_all(&headers)
        .map_err(|err| format!("cannot create {}: {err}", headers.display()))?;
    for (name, content) in HEADERS {
        let path = headers.join(name);
        fs::write(&path, content)
            .map_err(|err| format!("cannot write {}: {err}", path.display()))?;
    }
    let obj = dir.join("obj");
    if obj.exists() {
        fs::remove_dir_all(&obj)
            .map_err(|err| format!("cannot remove {}: {err}", obj.display()))?;
    }
    fs::create_dir_all(&obj).map_err(|err| format!("cannot create {}: {err}", obj.display()))?;

    let objects: Vec<PathBuf> = SOURCES
        .iter()
        .map(|s| obj.join(Path::new(s).with_extension("o").file_name().expect("a file name")))
        .collect();
    let compile = |i: usize| -> Result<(), String> {
        let mut cmd = Command::new(compiler);
        cmd.args(CFLAGS).arg("-I").arg(&include);
        for dir in INCLUDES {
            cmd.arg("-I").arg(vendor.join(dir));
        }
        cmd.arg("-c").arg(vendor.join(SOURCES[i])).arg("-o").arg(&objects[i]);
        run(&mut cmd)
    };
    // A queue of source indices shared by one worker per core.
    let next = AtomicUsize::new(0);
    let errors = Mutex::new(Vec::new());
    let jobs = thread::available_parallelism().map_or(2, |n| n.get()).clamp(1, 16);
    thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= SOURCES.len() {
                    break;
                }
                if let Err(err) = compile(i) {
                    errors.lock().unwrap_or_else(|e| e.into_inner()).push(err);
                    break;
                }
            });
        }
    });
    let errors = errors.into_inner().unwrap_or_else(|e| e.into_inner());
    if !errors.is_empty() {
        return Err(format!("building SUNDIALS failed:\n{}", errors.join("\n")));
    }

    // Linked under a temporary name and renamed into place.
    let partial = library.with_extension("so.partial");
    let mut link = Command::new(compiler);
    link.args(CFLAGS)
        .args(["-shared", "-Wl,--no-undefined", "-o"])
        .arg(&partial)
        .args(&objects)
        .arg("-lm");
    run(&mut link)?;
    fs::rename(&partial, library).map_err(|err| {
        format!("cannot rename {} to {}: {err}", partial.display(), library.display())
    })?;
    let _ = fs::remove_dir_all(&obj);
    Ok(())
}

/// Loads `library` and returns its `SUNDIALSGetVersion`.
fn check_library(library: &Path) -> Result<String, String> {
    // SAFETY: loading runs the library's initialisers (SUNDIALS has none with side effects);
    // `SUNDIALSGetVersion(char* version, int len)` writes a C string of at most `len` bytes.
    unsafe {
        let lib = libloading::Library::new(library)
            .map_err(|err| format!("cannot load {}: {err}", library.display()))?;
        let get = lib
            .get::<unsafe extern "C" fn(*mut c_char, c_int) -> c_int>(b"SUNDIALSGetVersion\0")
            .map_err(|err| format!("{}: {err}", library.display()))?;
        let mut buffer = [0 as c_char; 64];
        if get(buffer.as_mut_ptr(), buffer.len() as c_int) != 0 {
            return Err(format!("{}: SUNDIALSGetVersion failed", library.display()));
        }
        Ok(CStr::from_ptr(buffer.as_ptr()).to_string_lossy().into_owned())
    }
}

/// Runs `cmd`, its output captured: an `Err` with the command and its stderr if it fails.
fn run(cmd: &mut Command) -> Result<(), String> {
    let shown = format!(
        "{} {}",
        cmd.get_program().to_string_lossy(),
        cmd.get_args().map(|a| a.to_string_lossy()).collect::<Vec<_>>().join(" ")
    );
    match cmd.output() {
        Ok(Output { status, .. }) if status.success() => Ok(()),
        Ok(Output { status, stdout, stderr }) => Err(format!(
            "`{shown}` failed ({status}):\n{}{}",
            String::from_utf8_lossy(&stdout),
            String::from_utf8_lossy(&stderr)
        )),
        Err(err) => Err(format!("cannot run `{shown}`: {err}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_header_records_the_flags() {
        let config = HEADERS[0].1;
        assert!(config.contains(&format!("#define SUNDIALS_VERSION \"{SUNDIALS_VERSION}\"")));
        let release: Vec<&str> =
            CFLAGS.iter().copied().filter(|f| ["-O3", "-DNDEBUG"].contains(f)).collect();
        assert!(config.contains(&format!("#define SUN_C_COMPILER_FLAGS \"{}\"", release.join(" "))));
    }

    /// Fetches, builds and loads the library, then solves the paper scene with it through
    /// `cvode.rs`. Ignored by default (it needs crates.io unless cargo's cache holds the crate,
    /// and a C compiler); run it alone, since `cvode.rs` loads its library once per process:
    /// `cargo test -p beam-body-bench sundials_build -- --ignored`.
    #[test]
    #[ignore]
    fn builds_an_optimized_cvode_that_solves_the_paper_scene() {
        let target = crate::target_dir();
        let first = Instant::now();
        let library = ensure_optimized_cvode(&target).unwrap();
        eprintln!("ensure_optimized_cvode: {:.2} s", first.elapsed().as_secs_f64());
        let cached = Instant::now();
        assert_eq!(ensure_optimized_cvode(&target).unwrap(), library);
        eprintln!("again (cached): {:.3} ms", cached.elapsed().as_secs_f64() * 1e3);

        env::set_var("BEAM_BODY_CVODE_LIB", &library);
        let described = super::super::cvode::describe().unwrap();
        assert!(
            described.contains(SUNDIALS_VERSION) && described.contains(LIBRARY),
            "cvode.rs loaded {described} (run this test alone)"
        );
        let problem = super::super::problem::problem("paper").unwrap();
        let outcome = super::super::cvode::run(&problem, 1e-6).unwrap();
        assert_eq!(outcome.states.len(), problem.grid.len());
        let steps = outcome.counters.steps.unwrap();
        eprintln!("{described}: paper at rtol 1e-6 in {steps} steps");
        assert!(steps > 100);
    }
}
