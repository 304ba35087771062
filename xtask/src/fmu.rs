//! `cargo xtask fmu [--all-platforms]`: build, package and run the FMU.
//!
//! 1. Refuse a stale `modelDescription/modelDescription.xml` or
//!    `modelDescription/fmi3/modelDescription.xml` (regenerated in memory and compared byte
//!    for byte).
//! 2. Run the paper's scene (`scenes/paper.toml`) through the standalone solver: the
//!    reference, `target/fmu/paper.csv`.
//! 3. Build the library as a cdylib for this machine, and with `--all-platforms` for every
//!    platform ([`platforms`]).
//! 4. Zip `target/fmu/BeamBody.fmu` (FMI 2.0):
//!    ```text
//!    modelDescription.xml              (modelDescription/modelDescription.xml)
//!    binaries/linux64/BeamBody.so      (this machine's build; with --all-platforms also
//!                                       win64, darwin64, aarch64-darwin and aarch64-linux)
//!    documentation/index.html          (generated from the interface tables)
//!    ```
//!    and `target/fmu/BeamBody-fmi3.fmu` (FMI 3.0), the same libraries in FMI 3.0's folders:
//!    ```text
//!    modelDescription.xml              (modelDescription/fmi3/modelDescription.xml)
//!    binaries/x86_64-linux/BeamBody.so (this machine's build; with --all-platforms also
//!                                       x86_64-windows, x86_64-darwin, aarch64-darwin and
//!                                       aarch64-linux)
//!    documentation/index.html
//!    ```
//!    and, with `--all-platforms`, `target/fmu/BeamBody-aarch64-linux.fmu` (FMI 2.0). When the
//!    test venv (`target/venv`) exists, FMPy's `validate_fmu` (FMI 2.0 and 3.0: the schema,
//!    the variables, the model structure) must find no problem in any of them.
//! 5. Extract it to `target/fmu/BeamBody/`, load this machine's library there with the
//!    native host ([`crate::import`]), run the same scene through the FMI 2.0 API with the
//!    built-in law and the DefaultExperiment (`target/fmu/paper_fmu.csv`), check that a
//!    serialized FMU state restores to a bit-identical continuation, and compare with the
//!    standalone solver.
//! 6. Say which platforms the archives hold and, without `--all-platforms`, which are missing
//!    and how to build them ([`platforms_summary`]).

use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use beam_body::fmu::variables::{Var, DEFAULT_EXPERIMENT, MODEL_IDENTIFIER, PHI_SOURCE_TYPE};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

use crate::descriptions::Description;
use crate::import::{Call, CoSimulation, Common, Fmi2Error, Fmu2, InstanceCS};
use crate::platforms::{self, Archive};
use crate::summary::{sig, Table};
use crate::{
    build_release_binary, descriptions, docs, project_root, relative, run_cmd, summary, target_dir,
    Result,
};

/// The outputs that the host records and compares, in CSV column order after `t`.
const RECORDED: [Var; 3] = [Var::V1, Var::Theta1, Var::U2];

/// The archives that [`build_package`] wrote.
pub struct Packages {
    /// `target/fmu/BeamBody.fmu` (FMI 2.0).
    pub main: PathBuf,
    /// `target/fmu/BeamBody-aarch64-linux.fmu` (FMI 2.0), with `--all-platforms`.
    pub aarch64_linux: Option<PathBuf>,
    /// `target/fmu/BeamBody-fmi3.fmu` (FMI 3.0).
    pub fmi3: PathBuf,
    /// Each archive, with its binaries: (folder, size in bytes).
    listing: Vec<(PathBuf, Vec<(&'static str, u64)>)>,
}

/// Checks the modelDescriptions, builds the cdylib (with `all`, for every platform) and zips
/// the archives of [`platforms::ARCHIVES`] (without `all`: [`platforms::HOST_ARCHIVES`]) into
/// `target/fmu/`.
pub fn build_package(all: bool) -> Result<Packages> {
    build_package_in(&target_dir().join("fmu"), all)
}

/// [`build_package`] into `out_dir`: the benchmark and the sweep package this machine's FMU
/// apart, so that they leave `target/fmu/` (all platforms after `cargo xtask test`) alone.
pub fn build_package_in(out_dir: &Path, all: bool) -> Result<Packages> {
    descriptions::check_fresh()?;
    fs::create_dir_all(out_dir)
        .map_err(|err| format!("cannot create {}: {err}", relative(out_dir)))?;
    let built = platforms::build(all)?;
    let mut listing = Vec::new();
    for archive in platforms::archives(all) {
        let fmu = out_dir.join(archive.file);
        let mut binaries = Vec::new();
        for &(folder, source) in archive.binaries {
            binaries.push((folder, built.path(source)?));
        }
        package(archive.description, &binaries, &fmu)?;
        let sizes = binaries
            .iter()
            .map(|(folder, path)| (*folder, fs::metadata(path).map(|m| m.len()).unwrap_or(0)))
            .collect();
        listing.push((fmu, sizes));
    }
    let written = |file: &str| {
        let path = out_dir.join(file);
        listing.iter().any(|(fmu, _)| *fmu == path).then_some(path)
    };
    let main = written(platforms::MAIN_FILE).ok_or("no FMI 2.0 archive was written")?;
    let fmi3 = written(platforms::FMI3_FILE).ok_or("no FMI 3.0 archive was written")?;
    let aarch64_linux = written(platforms::AARCH64_LINUX_FILE);
    Ok(Packages { main, aarch64_linux, fmi3, listing })
}

pub fn run(all: bool) -> Result {
    descriptions::check_fresh()?;
    let out_dir = target_dir().join("fmu");
    fs::create_dir_all(&out_dir)
        .map_err(|err| format!("cannot create {}: {err}", relative(&out_dir)))?;

    let reference_csv = run_standalone(&out_dir)?;

    let packages = build_package(all)?;
    for (fmu, binaries) in &packages.listing {
        println!("\n{}:", relative(fmu));
        for (folder, size) in binaries {
            let name = format!("binaries/{folder}/{}", platforms::library_name(folder));
            println!("  {name:<37} {} ({size} bytes)", mib(*size));
        }
        let fmu_size = fs::metadata(fmu).map(|m| m.len()).unwrap_or(0);
        println!("  {:<37} {} (zipped)", relative(fmu), mib(fmu_size));
        validate_with_fmpy(fmu)?;
    }

    let dir = out_dir.join(MODEL_IDENTIFIER);
    extract(&packages.main, &dir)?;
    let run = run_fmu(&dir)?;
    let fmu_csv = out_dir.join("paper_fmu.csv");
    write_csv(&fmu_csv, &run.rows)?;
    print_fmu_run(&run, &dir, &fmu_csv);
    compare(&run.rows, &reference_csv, &fmu_csv)?;
    if let Some(err) = run.state_mismatch {
        return Err(err.into());
    }

    // The same scene through FMI 3.0: the same library and core, so the same bits.
    let dir3 = out_dir.join(format!("{MODEL_IDENTIFIER}-fmi3"));
    extract(&packages.fmi3, &dir3)?;
    let started = Instant::now();
    let rows3 = run_fmu3(&dir3)?;
    let wall = started.elapsed().as_secs_f64();
    println!(
        "
{} through the native FMI 3.0 host: {} x fmi3DoStep, {:.1} us per step",
        relative(&packages.fmi3),
        rows3.len() - 1,
        wall * 1e6 / (rows3.len() - 1) as f64
    );
    match rows3.iter().zip(&run.rows).position(|(a, b)| a.map(f64::to_bits) != b.map(f64::to_bits))
    {
        None if rows3.len() == run.rows.len() => {
            println!("  identical to the FMI 2.0 run, bit for bit, at all {} points", rows3.len());
        }
        k => {
            return Err(format!(
                "the FMI 3.0 run differs from the FMI 2.0 run (same library, same core) at row \
                 {k:?} of {} against {}",
                rows3.len(),
                run.rows.len()
            )
            .into())
        }
    }
    println!("\n{}", platforms_summary(platforms::archives(all)));
    Ok(())
}

/// Which platforms `archives` hold, archives that hold the same ones together; and, where
/// some of [`platforms::PLATFORMS`] are missing (`cargo xtask fmu` builds this machine's
/// binary only), which, and how to get them.
fn platforms_summary(archives: &[Archive]) -> String {
    // Each archive's platforms, in the order of PLATFORMS.
    let held = |archive: &Archive| -> Vec<&str> {
        let tuples: Vec<&str> =
            archive.binaries.iter().flat_map(|(_, source)| source.platforms()).copied().collect();
        platforms::PLATFORMS.iter().map(|(t, _)| *t).filter(|t| tuples.contains(t)).collect()
    };
    let mut groups: Vec<(Vec<&str>, Vec<&str>)> = Vec::new();
    for archive in archives {
        let platforms = held(archive);
        match groups.iter_mut().find(|(p, _)| *p == platforms) {
            Some((_, files)) => files.push(archive.file),
            None => groups.push((platforms, vec![archive.file])),
        }
    }
    let all = platforms::PLATFORMS.len();
    let mut text = String::from("Platforms:");
    for (tuples, files) in &groups {
        let names: Vec<&str> = tuples.iter().map(|t| platforms::platform_name(t)).collect();
        let verb = if files.len() == 1 { "holds" } else { "hold" };
        let what = match names.len() {
            n if n == all => format!("all {n} platforms of the README ({})", names.join(", ")),
            1 => format!("{} only", names[0]),
            _ => names.join(", "),
        };
        text.push_str(&format!("\n  {} {verb} {what}", files.join(" and ")));
    }
    let missing: Vec<&str> = platforms::PLATFORMS
        .iter()
        .filter(|(t, _)| !groups.iter().any(|(held, _)| held.contains(t)))
        .map(|(_, name)| *name)
        .collect();
    if !missing.is_empty() {
        text.push_str(&format!(
            "\n  not built: {}: a host there finds no binary.\n  \
             To build them: `cargo xtask fmu --all-platforms` (Debian's Rust and cross linkers,\n  \
             installed with apt-get as root; about 2 minutes a platform), which also writes\n  \
             {} for FMI 2.0 hosts on Linux aarch64; `cargo xtask test` builds\n  \
             every platform too.",
            missing.join(", "),
            platforms::AARCH64_LINUX_FILE
        ));
    }
    text
}

/// The paper's scene with the law through FMI 3.0 (fmi3EnterInitializationMode with the
/// DefaultExperiment, fmi3DoStep at its step): t and the [`RECORDED`] outputs at every point.
fn run_fmu3(dir: &Path) -> Result<Vec<[f64; 4]>> {
    use crate::import::{Call as _, CoSimulation3, Common3, GetSet3};
    let fmu = crate::import::Fmu3::load(dir)?;
    let ex = DEFAULT_EXPERIMENT;
    let points = communication_points(ex.start_time, ex.stop_time, ex.step_size);
    let vrs = RECORDED.map(Var::vr);
    let law = i64::from(law_item()?);
    let mut instance = fmu.instantiate(MODEL_IDENTIFIER)?;
    let version = instance.get_version().to_owned();
    if version != "3.0" {
        return Err(format!("fmi3GetVersion returned {version:?}, not \"3.0\"").into());
    }
    instance.set_int64(&[Var::PhiSource.vr()], &[law]).call("fmi3SetInt64")?;
    let (tolerance, stop) = (Some(ex.tolerance), Some(ex.stop_time));
    instance
        .enter_initialization_mode(tolerance, ex.start_time, stop)
        .call("fmi3EnterInitializationMode")?;
    instance.exit_initialization_mode().call("fmi3ExitInitializationMode")?;
    let mut rows = Vec::with_capacity(points.len());
    let mut read = |instance: &mut crate::import::InstanceCS3, t: f64| -> Result {
        let mut values = [0.0; 3];
        instance.get_float64(&vrs, &mut values).call("fmi3GetFloat64")?;
        rows.push([t, values[0], values[1], values[2]]);
        Ok(())
    };
    read(&mut instance, points[0])?;
    for pair in points.windows(2) {
        let (tc, h) = (pair[0], pair[1] - pair[0]);
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
        instance
            .do_step(tc, h, true, &mut event, &mut terminate, &mut early, &mut last)
            .call("fmi3DoStep")?;
        if event || terminate || early || last != pair[1] {
            return Err(format!(
                "fmi3DoStep({tc}, {h}): eventHandlingNeeded {event}, terminateSimulation \
                 {terminate}, earlyReturn {early}, lastSuccessfulTime {last}"
            )
            .into());
        }
        read(&mut instance, pair[1])?;
    }
    instance.terminate().call("fmi3Terminate")?;
    Ok(rows)
}

fn mib(bytes: u64) -> String {
    format!("{:.2} MiB", bytes as f64 / (1024.0 * 1024.0))
}

/// The standalone solver on the paper's scene: the reference CSV (as before the FMU).
fn run_standalone(out_dir: &Path) -> Result<PathBuf> {
    let root = project_root();
    let scene = root.join("scenes").join("paper.toml");
    if !scene.is_file() {
        return Err(format!("the paper's scene {} does not exist", relative(&scene)).into());
    }
    let binary = build_release_binary()?;
    let csv = out_dir.join("paper.csv");
    // The solver's stderr (its run statistics) goes straight through.
    let mut simulate = Command::new(&binary);
    simulate.arg("simulate").arg(relative(&scene)).arg("-o").arg(relative(&csv)).current_dir(&root);
    run_cmd(&mut simulate)?;

    println!("\n{} (standalone solver):", relative(&csv));
    summary::print_paper_run(&Table::read(&csv)?)?;
    Ok(csv)
}

/// Writes the .fmu with `description` as its modelDescription.xml and `binaries` (folder under
/// binaries/, library). Entries carry no timestamps (the zip crate's default date,
/// 1980-01-01), so the same inputs give the same archive.
fn package(description: &Description, binaries: &[(&str, &Path)], fmu: &Path) -> Result {
    let model_description = fs::read(description.path())
        .map_err(|err| format!("cannot read {}: {err}", description.relative_path))?;
    let mut libraries = Vec::new();
    for (folder, path) in binaries {
        let bytes =
            fs::read(path).map_err(|err| format!("cannot read {}: {err}", relative(path)))?;
        libraries.push((format!("binaries/{folder}/{}", platforms::library_name(folder)), bytes));
    }
    let documentation = docs::index_html();

    let file =
        fs::File::create(fmu).map_err(|err| format!("cannot create {}: {err}", relative(fmu)))?;
    let mut zip = ZipWriter::new(file);
    let deflated = SimpleFileOptions::DEFAULT.compression_method(CompressionMethod::Deflated);
    let files = deflated.unix_permissions(0o644);
    let executables = deflated.unix_permissions(0o755);
    let write_all = |zip: &mut ZipWriter<fs::File>| -> zip::result::ZipResult<()> {
        zip.start_file("modelDescription.xml", files)?;
        zip.write_all(&model_description)?;
        zip.add_directory("binaries/", executables)?;
        for (name, bytes) in &libraries {
            let folder = &name[..name.rfind('/').unwrap_or(0) + 1];
            zip.add_directory(folder, executables)?;
            zip.start_file(name.as_str(), executables)?;
            zip.write_all(bytes)?;
        }
        zip.add_directory("documentation/", executables)?;
        zip.start_file("documentation/index.html", files)?;
        zip.write_all(documentation.as_bytes())?;
        Ok(())
    };
    write_all(&mut zip).map_err(|err| format!("cannot write {}: {err}", relative(fmu)))?;
    zip.finish().map_err(|err| format!("cannot finish {}: {err}", relative(fmu)))?;
    Ok(())
}

/// `fmpy.validation.validate_fmu` on the .fmu (the schema of its FMI version, names, start
/// values, causality and variability, units, ModelStructure; FMI 3.0: one independent variable,
/// unique value references) when the test venv exists; it must find nothing.
fn validate_with_fmpy(fmu: &Path) -> Result {
    let python = target_dir().join("venv").join("bin").join("python");
    if !python.exists() {
        println!(
            "  FMPy validation skipped: no {} (`cargo xtask test` creates it)",
            relative(&python)
        );
        return Ok(());
    }
    const SCRIPT: &str = "import sys\n\
        from fmpy.validation import validate_fmu\n\
        problems = validate_fmu(sys.argv[1])\n\
        print('\\n'.join(problems))\n\
        sys.exit(1 if problems else 0)\n";
    let output = Command::new(&python)
        .args(["-c", SCRIPT])
        .arg(fmu)
        .output()
        .map_err(|err| format!("cannot run {}: {err}", relative(&python)))?;
    if output.status.success() {
        println!("  fmpy.validation.validate_fmu: no problems");
        Ok(())
    } else {
        Err(format!(
            "fmpy.validation.validate_fmu({}) found problems:\n{}{}",
            relative(fmu),
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        )
        .into())
    }
}

/// Extracts the .fmu into a clean `dir`, which the host then loads: the run uses exactly
/// the packaged files.
pub fn extract(fmu: &Path, dir: &Path) -> Result {
    if dir.exists() {
        fs::remove_dir_all(dir).map_err(|err| format!("cannot remove {}: {err}", relative(dir)))?;
    }
    let file =
        fs::File::open(fmu).map_err(|err| format!("cannot open {}: {err}", relative(fmu)))?;
    let mut archive =
        ZipArchive::new(file).map_err(|err| format!("{} is not a zip: {err}", relative(fmu)))?;
    archive
        .extract(dir)
        .map_err(|err| format!("cannot extract {} to {}: {err}", relative(fmu), relative(dir)))?;
    Ok(())
}

/// What the native host saw.
struct FmuRun {
    version: String,
    types_platform: String,
    /// t, then the [`RECORDED`] outputs, at every communication point.
    rows: Vec<[f64; 4]>,
    steps: usize,
    /// Instantiate to Terminate of the main run (the state check excluded).
    wall: Duration,
    state_bytes: usize,
    state_time: f64,
    /// Why the restored continuation differs, if it does.
    state_mismatch: Option<String>,
}

/// The communication points: t_k = start + k·h, the last exactly at stop (the standalone
/// solver's output grid). Each step is t_{k+1} − t_k, which is exact (Sterbenz), so
/// tc + h lands exactly on the next point.
fn communication_points(start: f64, stop: f64, h: f64) -> Vec<f64> {
    let ratio = (stop - start) / h;
    let n = (ratio - 1e-9).ceil().max(1.0) as usize;
    (0..=n).map(|k| if k == n { stop } else { start + k as f64 * h }).collect()
}

/// The value of `phi_source`'s item `law` (1-based, as the model description numbers it).
fn law_item() -> Result<i32> {
    let k = PHI_SOURCE_TYPE.items.iter().position(|(name, _)| *name == "law");
    Ok(k.ok_or("the PhiSource enumeration has no item `law`")? as i32 + 1)
}

fn run_fmu(dir: &Path) -> Result<FmuRun> {
    let fmu = Fmu2::load(dir)?;
    let ex = DEFAULT_EXPERIMENT;
    let points = communication_points(ex.start_time, ex.stop_time, ex.step_size);
    let vrs = RECORDED.map(Var::vr);
    let law = law_item()?;

    let started = Instant::now();
    let mut instance = fmu.instantiate(MODEL_IDENTIFIER, false)?;
    let version = instance.get_version().to_owned();
    let types_platform = instance.get_types_platform().to_owned();
    if version != "2.0" {
        return Err(format!("fmi2GetVersion returned {version:?}, not \"2.0\"").into());
    }
    instance.set_integer(&[Var::PhiSource.vr()], &[law]).call("fmi2SetInteger")?;
    let (tolerance, stop) = (Some(ex.tolerance), Some(ex.stop_time));
    instance.setup_experiment(tolerance, ex.start_time, stop).call("fmi2SetupExperiment")?;
    instance.enter_initialization_mode().call("fmi2EnterInitializationMode")?;
    instance.exit_initialization_mode().call("fmi2ExitInitializationMode")?;

    let read = |instance: &mut InstanceCS, t: f64| -> Result<[f64; 4]> {
        let mut values = [0.0; 3];
        instance.get_real(&vrs, &mut values).call("fmi2GetReal")?;
        Ok([t, values[0], values[1], values[2]])
    };

    let mid = (points.len() - 1) / 2;
    let mut rows = vec![read(&mut instance, points[0])?];
    let mut snapshot = None;
    for (k, pair) in points.windows(2).enumerate() {
        if k == mid {
            // rust-fmi frees the FMU states when the instance is dropped (no fmi2FreeFMUstate).
            let state = instance.get_fmu_state().call("fmi2GetFMUstate")?;
            snapshot = Some(instance.serialize_fmu_state(&state).call("fmi2SerializeFMUstate")?);
        }
        let (tc, h) = (pair[0], pair[1] - pair[0]);
        step(&mut instance, tc, h)?;
        rows.push(read(&mut instance, pair[1])?);
    }
    let wall = started.elapsed();

    // The FMU state: restore the serialized snapshot and repeat the second half.
    let bytes = snapshot.ok_or("no FMU state was taken")?;
    let state = instance.deserialize_fmu_state(&bytes).call("fmi2DeSerializeFMUstate")?;
    instance.set_fmu_state(&state).call("fmi2SetFMUstate")?;
    let mut state_mismatch = None;
    for (k, pair) in points.windows(2).enumerate().skip(mid) {
        let (tc, h) = (pair[0], pair[1] - pair[0]);
        step(&mut instance, tc, h)?;
        let again = read(&mut instance, pair[1])?;
        if again.map(f64::to_bits) != rows[k + 1].map(f64::to_bits) && state_mismatch.is_none() {
            state_mismatch = Some(format!(
                "after restoring the FMU state serialized at t = {}, the run differs at t = {}: \
                 {:?} instead of {:?} (t, v1, theta1, u2)",
                points[mid],
                pair[1],
                again,
                rows[k + 1]
            ));
        }
    }
    instance.terminate().call("fmi2Terminate")?;
    drop(instance);

    Ok(FmuRun {
        version,
        types_platform,
        steps: points.len() - 1,
        rows,
        wall,
        state_bytes: bytes.len(),
        state_time: points[mid],
        state_mismatch,
    })
}

/// One doStep; a Discard is an error here (the paper's scene must run through).
fn step(instance: &mut InstanceCS, tc: f64, h: f64) -> Result {
    match instance.do_step(tc, h, false) {
        Err(Fmi2Error::Discard) => {
            let reached = instance.last_successful_time().call("fmi2GetRealStatus")?;
            let terminated = instance.terminated().call("fmi2GetBooleanStatus")?;
            let mut err = format!(
                "fmi2DoStep({tc}, {h}) returned fmi2Discard: last successful time {reached}, \
                 terminated {terminated}"
            );
            for message in crate::import::take_messages() {
                err.push_str(&format!("\n  logged: {message}"));
            }
            Err(err.into())
        }
        result => result.call("fmi2DoStep").map(drop),
    }
}

/// The FMU's rows in the CLI's CSV form (beam_body::csv): headers with units, numbers that
/// read back exactly.
fn write_csv(path: &Path, rows: &[[f64; 4]]) -> Result {
    use beam_body::fmu::variables::Type;
    let mut text = beam_body::csv::header("t", Some("s"));
    for var in RECORDED {
        let unit = match var.info().ty {
            Type::Real { unit, .. } => unit,
            _ => None,
        };
        text.push(',');
        text.push_str(&beam_body::csv::header(var.info().name, unit));
    }
    text.push('\n');
    for row in rows {
        for (k, x) in row.iter().enumerate() {
            if k > 0 {
                text.push(',');
            }
            beam_body::csv::push_number(&mut text, *x);
        }
        text.push('\n');
    }
    crate::write_text(path, &text)
}

fn print_fmu_run(run: &FmuRun, dir: &Path, csv: &Path) {
    let folder = platforms::HOST_FOLDER;
    let so = dir.join("binaries").join(folder).join(platforms::library_name(folder));
    println!("\n{} (native FMI 2.0 host, {}):", relative(csv), relative(&so));
    println!("  fmi2GetVersion {}, fmi2GetTypesPlatform {}", run.version, run.types_platform);
    let ex = DEFAULT_EXPERIMENT;
    println!(
        "  steps         {} x fmi2DoStep, h = {} s, t = {} .. {} s, tolerance {:e}, phi_source = law",
        run.steps, ex.step_size, ex.start_time, ex.stop_time, ex.tolerance
    );
    println!(
        "  wall time     {:.3} s (instantiate to the last step), {:.1} us per step",
        run.wall.as_secs_f64(),
        run.wall.as_secs_f64() * 1e6 / run.steps as f64
    );
    match &run.state_mismatch {
        None => println!(
            "  FMU state     {} bytes serialized at t = {} s; restored, the rest repeats bit for bit",
            run.state_bytes,
            sig(run.state_time)
        ),
        Some(err) => println!("  FMU state     {} bytes; MISMATCH: {err}", run.state_bytes),
    }
}

/// Max |FMU − standalone| of the recorded outputs, on the common time grid.
fn compare(rows: &[[f64; 4]], reference: &Path, fmu_csv: &Path) -> Result {
    let table = Table::read(reference)?;
    let t_ref = table.values("t")?;
    if t_ref.len() != rows.len() {
        return Err(format!(
            "{} has {} rows but the FMU run has {}: the scene and the DefaultExperiment differ",
            relative(reference),
            t_ref.len(),
            rows.len()
        )
        .into());
    }
    let dt = t_ref.iter().zip(rows).map(|(a, row)| (a - row[0]).abs()).fold(0.0, f64::max);
    if dt > 1e-9 {
        return Err(format!(
            "the output times of {} and {} differ by up to {dt:e} s",
            relative(reference),
            relative(fmu_csv)
        )
        .into());
    }
    println!("  max |FMU - standalone| ({}):", relative(reference));
    for (column, var) in RECORDED.iter().enumerate() {
        let info = var.info();
        let reference = table.values(info.name)?;
        let (k, diff) = reference
            .iter()
            .zip(rows)
            .map(|(a, row)| (a - row[column + 1]).abs())
            .enumerate()
            .fold(
                (0, 0.0_f64),
                |best, (k, d)| if d > best.1 || d.is_nan() { (k, d) } else { best },
            );
        let unit = match info.ty {
            beam_body::fmu::variables::Type::Real { unit: Some(unit), .. } => unit,
            _ => "",
        };
        println!("    {:<8} {:<12} {unit:<4} at t = {}", info.name, sig(diff), sig(rows[k][0]));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{communication_points, platforms, platforms_summary};

    /// `cargo xtask fmu` builds this machine's binary only: its summary says so, names the
    /// platforms left out and how to get them. With `--all-platforms` it names all five.
    #[test]
    fn the_summary_says_which_platforms_the_archives_hold() {
        let host = platforms::platform_name(platforms::HOST_TUPLE);
        let text = platforms_summary(platforms::archives(false));
        let first = format!("Platforms:\n  BeamBody.fmu and BeamBody-fmi3.fmu hold {host} only\n");
        assert!(text.starts_with(&first), "{text}");
        for (_, name) in platforms::PLATFORMS.iter().filter(|(_, n)| *n != host) {
            assert!(text.contains(name), "{name}: {text}");
        }
        for needle in ["not built: ", "`cargo xtask fmu --all-platforms`", "`cargo xtask test`"] {
            assert!(text.contains(needle), "{needle}: {text}");
        }
        let text = platforms_summary(platforms::archives(true));
        assert_eq!(
            text,
            "Platforms:\n  BeamBody.fmu and BeamBody-fmi3.fmu hold all 5 platforms of the README \
             (Linux x86-64, Windows x86-64, macOS x86-64, macOS arm64, Linux aarch64)\n  \
             BeamBody-aarch64-linux.fmu holds Linux aarch64 only"
        );
    }

    #[test]
    fn communication_points_end_exactly_and_steps_add_up() {
        let points = communication_points(0.0, 10.2, 0.0085);
        assert_eq!(points.len(), 1201);
        assert_eq!(points[0], 0.0);
        assert_eq!(*points.last().unwrap(), 10.2);
        for (k, pair) in points.windows(2).enumerate() {
            let h = pair[1] - pair[0];
            assert!(h > 0.0);
            assert_eq!(pair[0] + h, pair[1], "step {k}");
            if k + 1 < 1200 {
                assert_eq!(pair[1], (k + 1) as f64 * 0.0085);
            }
        }
        assert_eq!(communication_points(0.0, 1.0, 0.3), [0.0, 0.3, 0.6, 0.8999999999999999, 1.0]);
    }
}
