//! `cargo xtask`'s launcher (the alias in `.cargo/config.toml` runs this package).
//!
//! xtask depends on the `fmi` crate, whose `fmi-sys` runs bindgen at build time, and bindgen
//! loads libclang: without it xtask does not compile, so it cannot install anything. This
//! std-only crate looks for libclang where clang-sys (bindgen's loader) does, installs the
//! Debian package `libclang-dev` with apt-get when it is missing and we run as root (else it
//! names the package), then runs `cargo run --quiet --package xtask -- ARGS` with the cargo
//! that started it, the same stdio, and its exit status.

use std::env;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

const PACKAGE: &str = "libclang-dev";

fn main() -> ExitCode {
    if let Err(err) = ensure_libclang() {
        eprintln!("error: {err}");
        return ExitCode::FAILURE;
    }
    let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut xtask = Command::new(&cargo);
    xtask.args(["run", "--quiet", "--package", "xtask", "--"]).args(env::args_os().skip(1));
    #[cfg(unix)]
    let err = std::os::unix::process::CommandExt::exec(&mut xtask);
    #[cfg(not(unix))]
    let err = match xtask.status() {
        Ok(status) => {
            let code = status.code().and_then(|c| u8::try_from(c).ok());
            return code.map_or(ExitCode::FAILURE, ExitCode::from);
        }
        Err(err) => err,
    };
    eprintln!("error: cannot run {}: {err}", cargo.to_string_lossy());
    ExitCode::FAILURE
}

fn ensure_libclang() -> Result<(), String> {
    let search = Search::from_env();
    if search.find(llvm_prefix).is_some() {
        return Ok(());
    }
    if let Some(path) = &search.libclang_path {
        let path = path.display();
        return Err(format!("LIBCLANG_PATH={path} holds no libclang (clang-sys looks only there)"));
    }
    let ok = |cmd: &mut Command| {
        cmd.stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok_and(|s| s.success())
    };
    let root = Command::new("id").arg("-u").output().is_ok_and(|o| o.stdout.trim_ascii() == b"0");
    if !(root && ok(Command::new("apt-get").arg("--version"))) {
        return Err(format!(
            "libclang was not found (xtask's dependency fmi-sys runs bindgen, which loads it); \
             install it (Debian: apt-get install {PACKAGE}) or set LIBCLANG_PATH to its directory"
        ));
    }
    eprintln!("libclang was not found: installing {PACKAGE} with apt-get");
    for args in [&["update", "-qq"][..], &["install", "-y", "-qq", PACKAGE]] {
        let failed = match Command::new("apt-get").args(args).status() {
            Ok(status) if status.success() => continue,
            Ok(status) => status.to_string(),
            Err(err) => err.to_string(),
        };
        return Err(format!("`apt-get {}` failed ({failed})", args.join(" ")));
    }
    match search.find(llvm_prefix) {
        Some(_) => Ok(()),
        None => Err(format!("{PACKAGE} is installed, but libclang is still not found")),
    }
}

/// Where clang-sys looks for libclang at run time (its `build/common.rs`, Linux): only
/// `$LIBCLANG_PATH` (the file or its directory) when set; else `$LD_LIBRARY_PATH`,
/// `$LIBRARY_PATH`, `$(llvm-config --prefix)/{lib,lib64}`, `/usr/local/llvm*/lib*`, and
/// `/usr/lib*` and `/usr/local/lib*` with up to two levels of subdirectories.
struct Search {
    /// `/`, or a fake tree in the tests.
    root: PathBuf,
    libclang_path: Option<PathBuf>,
    library_paths: Vec<PathBuf>,
}

impl Search {
    fn from_env() -> Search {
        let paths = |var| env::var_os(var).map(|v| env::split_paths(&v).collect::<Vec<_>>());
        let library_paths = [paths("LD_LIBRARY_PATH"), paths("LIBRARY_PATH")];
        Search {
            root: PathBuf::from("/"),
            libclang_path: env::var_os("LIBCLANG_PATH").map(PathBuf::from),
            library_paths: library_paths.into_iter().flatten().flatten().collect(),
        }
    }

    /// The first libclang found; `llvm_prefix` (`llvm-config --prefix`) is asked last.
    fn find(&self, llvm_prefix: impl FnOnce() -> Option<PathBuf>) -> Option<PathBuf> {
        if let Some(path) = &self.libclang_path {
            let named = path.file_name().and_then(|n| n.to_str()).is_some_and(is_libclang);
            return if named && path.is_file() { Some(path.clone()) } else { in_dir(path) };
        }
        let usr = self.root.join("usr");
        let local = usr.join("local");
        let mut dirs = self.library_paths.clone();
        dirs.extend(subdirs(&local, "llvm").iter().flat_map(|d| subdirs(d, "lib")));
        if let Some(found) = dirs.iter().find_map(|d| in_dir(d)) {
            return Some(found);
        }
        // /usr/lib*, then /usr/lib*/*, then /usr/lib*/*/* (and the same under /usr/local).
        let mut level = [subdirs(&usr, "lib"), subdirs(&local, "lib")].concat();
        for depth in 0..3 {
            if depth > 0 {
                level = level.iter().flat_map(|d| subdirs(d, "")).collect();
            }
            if let Some(found) = level.iter().find_map(|d| in_dir(d)) {
                return Some(found);
            }
        }
        let prefix = llvm_prefix()?;
        ["lib", "lib64"].iter().find_map(|lib| in_dir(&prefix.join(lib)))
    }
}

fn llvm_prefix() -> Option<PathBuf> {
    let out = Command::new("llvm-config").arg("--prefix").output().ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    out.status.success().then(|| PathBuf::from(text.trim()))
}

/// clang-sys's file names: `libclang.so`, `libclang-*.so`, `libclang.so.*`, `libclang-*.so.*`;
/// not `libclang-cpp.so.*` (the C++ library, without the C API that bindgen loads).
fn is_libclang(name: &str) -> bool {
    let versioned = name.strip_prefix("libclang-").is_some_and(|rest| {
        !rest.starts_with("cpp") && (rest.ends_with(".so") || rest.contains(".so."))
    });
    name == "libclang.so" || name.starts_with("libclang.so.") || versioned
}

/// A libclang in `dir`.
fn in_dir(dir: &Path) -> Option<PathBuf> {
    let mut names = dir.read_dir().ok()?.filter_map(|e| e.ok()).map(|e| e.file_name());
    let name = names.find(|n| n.to_str().is_some_and(is_libclang))?;
    Some(dir.join(name))
}

/// The subdirectories of `dir` (symlinks followed) whose names start with `prefix`.
fn subdirs(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let Ok(entries) = dir.read_dir() else { return Vec::new() };
    let names = entries.filter_map(|e| e.ok()).map(|e| e.file_name());
    let matching = names.filter(|n| n.to_str().is_some_and(|n| n.starts_with(prefix)));
    matching.map(|n| dir.join(n)).filter(|p| p.is_dir()).collect()
}

#[cfg(test)]
mod tests {
    use std::fs;
    use std::path::PathBuf;

    use super::{is_libclang, Search};

    /// A fake root holding `files` (empty), removed when dropped.
    struct Tree(PathBuf);

    impl Tree {
        fn new(name: &str, files: &[&str]) -> Tree {
            let pid = std::process::id();
            let root = std::env::temp_dir().join(format!("xtask-launch-{pid}-{name}"));
            let _ = fs::remove_dir_all(&root);
            for file in files {
                let path = root.join(file);
                fs::create_dir_all(path.parent().unwrap()).unwrap();
                fs::write(path, b"").unwrap();
            }
            fs::create_dir_all(&root).unwrap();
            Tree(root)
        }

        fn search(&self) -> Search {
            Search { root: self.0.clone(), libclang_path: None, library_paths: Vec::new() }
        }

        /// What [`Search::find`] finds in the tree, relative to its root.
        fn found(&self, search: &Search, llvm_prefix: Option<&str>) -> Option<String> {
            let found = search.find(|| llvm_prefix.map(|p| self.0.join(p)))?;
            Some(found.strip_prefix(&self.0).unwrap().to_str().unwrap().to_owned())
        }
    }

    impl Drop for Tree {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn file_names() {
        for name in ["libclang.so", "libclang.so.1", "libclang-14.so", "libclang-14.so.1"] {
            assert!(is_libclang(name), "{name}");
        }
        for name in ["libclang-cpp.so.14", "libclangAST.a", "libclang.a", "libclang-14.a"] {
            assert!(!is_libclang(name), "{name}");
        }
    }

    #[test]
    fn system_directories() {
        let found = |name, files: &[&str]| {
            let tree = Tree::new(name, files);
            tree.found(&tree.search(), None)
        };
        assert_eq!(
            found("none", &["usr/lib/x86_64-linux-gnu/libc.so.6", "usr/include/clang.h"]),
            None
        );
        let multiarch = "usr/lib/x86_64-linux-gnu/libclang-14.so.1";
        assert_eq!(found("multiarch", &[multiarch]).as_deref(), Some(multiarch));
        let llvm = "usr/lib/llvm-19/lib/libclang.so";
        assert_eq!(found("llvm", &["usr/lib/llvm-19/lib/x.a", llvm]).as_deref(), Some(llvm));
        let local = "usr/local/llvm20/lib64/libclang.so.20";
        assert_eq!(found("local", &[local]).as_deref(), Some(local));
        // Not the C++ library, and not three levels below /usr/lib (clang-sys stops at two).
        let cpp = "usr/lib/llvm-14/lib/libclang-cpp.so.14";
        assert_eq!(found("deep", &[cpp, "usr/lib/a/b/c/libclang.so"]), None);
    }

    #[test]
    fn environment() {
        let tree = Tree::new("env", &["opt/llvm/lib64/libclang.so", "usr/lib/libclang.so"]);
        let lib = "opt/llvm/lib64/libclang.so";
        // LIBCLANG_PATH is the only place searched when set: a directory or the file itself.
        let mut search = tree.search();
        search.libclang_path = Some(tree.0.join("opt"));
        assert_eq!(tree.found(&search, None), None);
        search.libclang_path = Some(tree.0.join("opt/llvm/lib64"));
        assert_eq!(tree.found(&search, None).as_deref(), Some(lib));
        search.libclang_path = Some(tree.0.join(lib));
        assert_eq!(tree.found(&search, None).as_deref(), Some(lib));
        // LD_LIBRARY_PATH and LIBRARY_PATH come before the system directories.
        let mut search = tree.search();
        search.library_paths = vec![tree.0.join("nowhere"), tree.0.join("opt/llvm/lib64")];
        assert_eq!(tree.found(&search, None).as_deref(), Some(lib));
        // `llvm-config --prefix`: its lib and lib64.
        let tree = Tree::new("prefix", &[lib]);
        assert_eq!(tree.found(&tree.search(), None), None);
        assert_eq!(tree.found(&tree.search(), Some("opt/llvm")).as_deref(), Some(lib));
    }
}
