//! `cargo xtask bench-ab [REV] [--rounds R] [--sample SCENE FORMULATION RTOL]`: the time per
//! step of the library of a git revision against the working tree's, both at once.
//!
//! The runner (`bench/ab/runner.rs`) is built twice in `target/ab/`: against REV (default
//! HEAD), checked out in the worktree `target/ab/rev`, and against the working tree, both with
//! the workspace's release profile (fat LTO) plus line tables. Each round runs the two at the
//! same time, one on each core (`taskset`), swapping the cores every round and which starts
//! first every other round: what the rest of the machine does (here it moves the absolute times
//! by 30 % from hour to hour) falls on both. A round is ten solves of each of ten cases (the
//! first untimed), the median per case; the report is the median over the rounds, per case,
//! and the ratio REV / tree with its geometric mean. Two runs of the same build agree within
//! ±2 % on the geometric mean and ±5 % per case.
//!
//! `--sample`: instead, the working tree's runner alone on one case for 40 s of CPU time under
//! SIGPROF, each sample credited to the innermost line of `src/` in its inline chain (addr2line
//! -i): where the time stalls, which callgrind's instruction counts do not show.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::{project_root, relative, run_cmd, target_dir, write_text, Result};

/// The parsed options.
struct Options {
    rev: String,
    rounds: usize,
    sample: Option<[String; 3]>,
}

fn parse(options: &[String]) -> Result<Options> {
    let mut parsed = Options { rev: "HEAD".into(), rounds: 8, sample: None };
    let mut rest = options.iter();
    while let Some(option) = rest.next() {
        match option.as_str() {
            "--rounds" => {
                let value = rest.next().ok_or("`--rounds` needs a number")?;
                parsed.rounds =
                    value.parse().ok().filter(|r| (2..=1000).contains(r)).ok_or_else(|| {
                        format!("`--rounds {value}`: must be a number in 2..=1000")
                    })?;
            }
            "--sample" => {
                let mut next = || rest.next().cloned();
                match (next(), next(), next()) {
                    (Some(scene), Some(formulation), Some(rtol)) => {
                        parsed.sample = Some([scene, formulation, rtol]);
                    }
                    _ => return Err("`--sample` needs SCENE FORMULATION RTOL".into()),
                }
            }
            other if other.starts_with('-') => {
                return Err(format!("`bench-ab` has no option `{other}`").into());
            }
            rev => parsed.rev = rev.to_string(),
        }
    }
    Ok(parsed)
}

pub fn run(options: &[String]) -> Result {
    let options = parse(options)?;
    let root = project_root();
    let dir = target_dir().join("ab");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", relative(&dir)))?;
    let tree = build(&dir, "ab-tree", &root)?;
    if let Some([scene, formulation, rtol]) = &options.sample {
        return sample(&dir, &tree, scene, formulation, rtol);
    }
    let worktree = dir.join("rev");
    checkout(&root, &worktree, &options.rev)?;
    let rev = build(&dir, "ab-rev", &worktree)?;
    compare(&options, &rev, &tree)
}

/// `git worktree` at `rev` in `path` (made or moved there). The revision is resolved in the
/// repository first: inside the worktree, HEAD would name the worktree's own.
fn checkout(root: &Path, path: &Path, rev: &str) -> Result {
    let git = |args: &[&str], dir: &Path| -> Result {
        run_cmd(Command::new("git").arg("-C").arg(dir).args(args))
    };
    let resolved = Command::new("git")
        .arg("-C")
        .arg(root)
        .args(["rev-parse", "--verify", &format!("{rev}^{{commit}}")])
        .output()
        .map_err(|e| format!("git rev-parse: {e}"))?;
    if !resolved.status.success() {
        return Err(format!("`{rev}` is not a commit of this repository").into());
    }
    let sha = String::from_utf8_lossy(&resolved.stdout).trim().to_string();
    let rev = sha.as_str();
    if path.join(".git").exists() {
        git(&["checkout", "--quiet", "--detach", rev], path)
    } else {
        let target = path.to_string_lossy().into_owned();
        git(&["worktree", "add", "--quiet", "--force", "--detach", &target, rev], root)
    }
}

/// Builds the runner as the binary `name` against the library at `library`; its path.
fn build(dir: &Path, name: &str, library: &Path) -> Result<PathBuf> {
    let root = project_root();
    let crate_dir = dir.join(name);
    std::fs::create_dir_all(&crate_dir)
        .map_err(|e| format!("cannot create {}: {e}", relative(&crate_dir)))?;
    // A library with the settings table (src/settings.rs, later src/settings/) reads scene
    // files with the feature `cli`; the runner's feature `settings` picks the matching calls
    // (runner.rs).
    let src = library.join("src");
    let settings = src.join("settings.rs").exists() || src.join("settings").is_dir();
    let (features, runner_features) = if settings {
        (", features = [\"cli\"]", "[features]\ndefault = [\"settings\"]\nsettings = []\n\n")
    } else {
        ("", "[features]\nsettings = []\n\n")
    };
    let manifest = format!(
        "# Written by `cargo xtask bench-ab`.\n[package]\nname = \"{name}\"\nversion = \"0.0.0\"\n\
         edition = \"2021\"\npublish = false\n\n{runner_features}[[bin]]\nname = \"{name}\"\n\
         path = \"{}\"\n\n[dependencies]\n\
         beam-body = {{ path = \"{}\", default-features = false{features} }}\n\
         libc = \"0.2\"\n\n[profile.release]\nlto = \"fat\"\ncodegen-units = 1\n\
         panic = \"unwind\"\ndebug = \"line-tables-only\"\n\n[workspace]\n",
        root.join("bench").join("ab").join("runner.rs").display(),
        library.display(),
    );
    write_text(&crate_dir.join("Cargo.toml"), &manifest)?;
    // The workspace's lock, so that both build with the versions the project uses.
    let lock = crate_dir.join("Cargo.lock");
    if !lock.exists() {
        std::fs::copy(root.join("Cargo.lock"), &lock)
            .map_err(|e| format!("cannot copy Cargo.lock: {e}"))?;
    }
    let mut cargo = crate::cargo(["build", "--release", "--manifest-path"]);
    cargo
        .arg(crate_dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", dir.join("target"))
        .env("BEAM_BODY_ROOT", &root);
    run_cmd(&mut cargo)?;
    Ok(dir.join("target").join("release").join(name))
}

/// (scene, rtol) → (steps, ns per step) of one runner's output.
type Round = BTreeMap<(String, String), (u64, f64)>;

fn parse_round(text: &str) -> Result<Round> {
    let mut round = Round::new();
    for line in text.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let [scene, rtol, steps, ns] = fields[..] else {
            return Err(format!("the runner printed `{line}`").into());
        };
        let number = |x: &str| x.parse::<f64>().map_err(|_| format!("not a number: `{line}`"));
        round.insert((scene.into(), rtol.into()), (number(steps)? as u64, number(ns)?));
    }
    Ok(round)
}

fn compare(options: &Options, rev: &Path, tree: &Path) -> Result {
    let mut rounds: [Vec<Round>; 2] = [Vec::new(), Vec::new()];
    for r in 0..options.rounds {
        let cores = if r % 2 == 0 { ["0", "1"] } else { ["1", "0"] };
        let start = |binary: &Path, core: &str| {
            Command::new("taskset")
                .args(["-c", core])
                .arg(binary)
                .arg("20")
                .stdout(Stdio::piped())
                .spawn()
                .map_err(|e| format!("cannot start {} under taskset: {e}", relative(binary)))
        };
        let (a, b) = if (r / 2) % 2 == 0 {
            let a = start(rev, cores[0])?;
            (a, start(tree, cores[1])?)
        } else {
            let b = start(tree, cores[1])?;
            (start(rev, cores[0])?, b)
        };
        for (k, child) in [a, b].into_iter().enumerate() {
            let out = child.wait_with_output().map_err(|e| format!("runner: {e}"))?;
            if !out.status.success() {
                return Err(format!("the runner failed: {}", out.status).into());
            }
            rounds[k].push(parse_round(&String::from_utf8_lossy(&out.stdout))?);
        }
        eprintln!("bench-ab: round {}/{}", r + 1, options.rounds);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "time per step, median of {} rounds: {} (REV) against the working tree\n",
        options.rounds, options.rev
    );
    println!("| case | REV ns/step | tree ns/step | REV / tree | steps REV | steps tree |");
    println!("|---|---|---|---|---|---|");
    let mut log_sum = 0.0;
    let cases: Vec<_> = rounds[0][0].keys().cloned().collect();
    for case in &cases {
        let series = |k: usize| -> Result<(f64, u64)> {
            let values: Option<Vec<(u64, f64)>> =
                rounds[k].iter().map(|round| round.get(case).copied()).collect();
            let values = values.ok_or("a round lacks a case")?;
            Ok((median(values.iter().map(|v| v.1).collect()), values[0].0))
        };
        let ((a, sa), (b, sb)) = (series(0)?, series(1)?);
        log_sum += (a / b).ln();
        println!("| {} {} | {a:.1} | {b:.1} | {:.3} | {sa} | {sb} |", case.0, case.1, a / b);
    }
    println!("\ngeometric mean of REV / tree: {:.3}", (log_sum / cases.len() as f64).exp());
    Ok(())
}

fn sample(dir: &Path, tree: &Path, scene: &str, formulation: &str, rtol: &str) -> Result {
    let samples = dir.join("samples.txt");
    let out = samples.to_string_lossy().into_owned();
    run_cmd(Command::new(tree).args(["sample", scene, formulation, rtol, "40", &out]))?;
    let text = std::fs::read_to_string(&samples).map_err(|e| format!("{out}: {e}"))?;
    let mut lines = text.lines().map(|l| u64::from_str_radix(l, 16));
    let main_at_run = lines.next().ok_or("no samples")?.map_err(|e| e.to_string())?;
    let addresses: Vec<u64> =
        lines.collect::<std::result::Result<_, _>>().map_err(|e| e.to_string())?;
    // The load offset: main's address at run time less its address in the file.
    let nm = Command::new("nm").arg(tree).output().map_err(|e| format!("nm: {e}"))?;
    let symbols = String::from_utf8_lossy(&nm.stdout);
    let main_in_file = symbols
        .lines()
        .filter_map(|l| l.split_once(' '))
        .find(|(_, rest)| rest.contains("ab_tree4main17h"))
        .and_then(|(a, _)| u64::from_str_radix(a, 16).ok())
        .ok_or("the runner's main is not in its symbol table")?;
    let offset = main_at_run.wrapping_sub(main_in_file);
    let mut counts: HashMap<u64, usize> = HashMap::new();
    for a in &addresses {
        *counts.entry(a.wrapping_sub(offset)).or_default() += 1;
    }
    let unique: Vec<u64> = counts.keys().copied().collect();
    let input: String = unique.iter().map(|a| format!("{a:x}\n")).collect();
    let mut addr2line = Command::new("addr2line")
        .args(["-a", "-i", "-e"])
        .arg(tree)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("addr2line: {e}"))?;
    {
        use std::io::Write;
        let mut stdin = addr2line.stdin.take().ok_or("addr2line: no stdin")?;
        stdin.write_all(input.as_bytes()).map_err(|e| format!("addr2line: {e}"))?;
    }
    let resolved = addr2line.wait_with_output().map_err(|e| format!("addr2line: {e}"))?;
    let mut by_line: HashMap<String, usize> = HashMap::new();
    let mut chains: Vec<Vec<String>> = Vec::new();
    for line in String::from_utf8_lossy(&resolved.stdout).lines() {
        if line.starts_with("0x") {
            chains.push(Vec::new());
        } else if let Some(chain) = chains.last_mut() {
            chain.push(line.to_string());
        }
    }
    let src = format!("{}/src/", project_root().display());
    for (a, chain) in unique.iter().zip(&chains) {
        let ours = chain.iter().find(|l| l.contains(&src)).or(chain.first());
        let key = ours
            .map_or("??".to_string(), |l| l.split(" (").next().unwrap_or(l).replace(&src, "src/"));
        *by_line.entry(key).or_default() += counts[a];
    }
    let total = addresses.len().max(1);
    let mut sorted: Vec<_> = by_line.into_iter().collect();
    sorted.sort_by_key(|entry| std::cmp::Reverse(entry.1));
    println!("{total} samples of {scene} ({formulation}, rtol {rtol})\n");
    println!("| share | line | source |\n|---|---|---|");
    for (line, n) in sorted.iter().take(40) {
        let text = line
            .split_once(':')
            .and_then(|(file, no)| {
                let no: usize = no.parse().ok()?;
                let body = std::fs::read_to_string(project_root().join(file)).ok()?;
                body.lines().nth(no.checked_sub(1)?).map(|s| s.trim().replace('|', "\\|"))
            })
            .unwrap_or_default();
        println!("| {:.1} % | {line} | `{text}` |", 100.0 * *n as f64 / total as f64);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(xs: &[&str]) -> Vec<String> {
        xs.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn options_name_what_is_wrong() {
        let o = parse(&strings(&["abc123", "--rounds", "5"])).unwrap();
        assert_eq!((o.rev.as_str(), o.rounds, o.sample.is_none()), ("abc123", 5, true));
        assert_eq!(parse(&[]).unwrap().rev, "HEAD");
        let o = parse(&strings(&["--sample", "paper", "dae", "1e-6"])).unwrap();
        assert_eq!(o.sample.unwrap()[1], "dae");
        for (bad, needle) in [
            (&["--rounds", "1"][..], "2..=1000"),
            (&["--rounds"][..], "needs a number"),
            (&["--sample", "paper"][..], "SCENE FORMULATION RTOL"),
            (&["--fast"][..], "no option `--fast`"),
        ] {
            let err = parse(&strings(bad)).err().expect("an error").to_string();
            assert!(err.contains(needle), "{bad:?}: {err}");
        }
    }

    #[test]
    fn runner_lines_parse_and_bad_ones_are_named() {
        let round = parse_round("paper 1e-4 1368 259.81\nstiff 1e-4 58317 324.2\n").unwrap();
        assert_eq!(round[&("paper".to_string(), "1e-4".to_string())], (1368, 259.81));
        assert_eq!(round.len(), 2);
        let err = parse_round("paper 1e-4 x 2.0").unwrap_err().to_string();
        assert!(err.contains("paper 1e-4 x 2.0"), "{err}");
        assert!(parse_round("paper 1e-4").is_err());
    }
}
