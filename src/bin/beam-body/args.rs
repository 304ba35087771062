//! The command line: the scene a command runs (a scene file, then `--set` and the flags over
//! it, in order), and the help, generated from the settings table.

use crate::location::at_file;
use crate::{print, Failure};
use beam_body::csv;
use beam_body::scene::Scene;
use beam_body::settings::{Setting, SETTINGS};
use lexopt::prelude::*;
use std::ffi::OsString;

pub const COMMANDS: &str = "the commands are simulate, modes, residual, study and help";

/// `beam-body X.Y.Z`.
pub fn version() -> String {
    format!("beam-body {}\n", env!("CARGO_PKG_VERSION"))
}

pub fn main_help() -> String {
    format!(
        "beam-body {}: the beam-body system of Russkikh & Shklyarchuk (2020), without FMI

usage: beam-body COMMAND [ARGUMENTS]

commands:
  simulate SCENE.toml [OPTIONS]        run a scene: CSV rows to stdout, or to -o FILE
  modes [SCENE.toml] [OPTIONS]         small-oscillation periods at phi = 0, pi/2, pi
  residual --formulation F [OPTIONS]   residuals of the equations of motion (stdin to stdout)
  study STUDY.toml [OPTIONS]           a design study: one CSV row per case
  help [COMMAND]                       this text, or a command's

`beam-body COMMAND --help` says more; `beam-body --version` prints the version.
",
        env!("CARGO_PKG_VERSION")
    )
}

/// The help of `command`, `None` for an unknown one.
pub fn command_help(command: &str) -> Option<String> {
    Some(match command {
        "simulate" => format!(
            "usage: beam-body simulate SCENE.toml [OPTIONS] [-o OUT.csv]

Runs the scene and writes CSV to stdout (or to OUT.csv): a header, then a row at
t = k*dt_out up to and including t_end. Its columns, with their units:
  {}
Numbers are in the shortest form that reads back exactly (0.0085, -0.591, 1e-7).
Run statistics go to stderr. A run of more than `max_rows` rows is refused before it
starts. A closed stdout (`| head`) stops the run at once.

{}{}",
            outputs_header(),
            options_help(&[(
                "-o, --output FILE",
                "write the CSV to FILE instead of stdout (-: stdout)"
            )]),
            settings_help()
        ),
        "modes" => format!(
            "usage: beam-body modes [SCENE.toml] [OPTIONS] [--count K]

Small-oscillation periods of the scene's model about its static equilibrium with the
body held at phi = 0, pi/2 and pi: the first two, or the first K (at most 2*n_elements)
with --count K.

{}{}",
            options_help(&[("--count K", "the first K modes (at most 2*n_elements)")]),
            settings_help()
        ),
        "residual" => format!(
            "usage: beam-body residual --formulation F [OPTIONS]

Reads states from stdin, one per line, and writes for each the residuals of the
equations of motion, then the accelerations of the model's right-hand side:
  reduced, linear:     phi dphi ddphi v1 theta1 dv1 dtheta1 ddv1 ddtheta1
  dae, dae_stabilized: phi dphi ddphi v1 theta1 u2 dv1 dtheta1 du2 ddv1 ddtheta1 ddu2
(SI units). The independent oracle of the tests uses it. --formulation is required.
These are the paper's equations, of one element of the quadratic beam without damping or
the beam's weight: n_elements, beam, damping_* and beam_gravity other than that are refused.

{}{}",
            options_help(&[]),
            settings_help()
        ),
        "study" => super::study::HELP.to_string(),
        _ => return None,
    })
}

/// The CSV header of `simulate`.
fn outputs_header() -> String {
    let names: Vec<String> = beam_body::model::Outputs::COLUMNS
        .iter()
        .map(|(name, unit)| csv::header(name, Some(unit)))
        .collect();
    names.join(",")
}

/// The options of a command: `--set`, the flags of the settings, then the command's `own`
/// (flag, what it does).
fn options_help(own: &[(&str, &str)]) -> String {
    let mut text = String::from("options:\n");
    text.push_str("  --set NAME=VALUE        set any setting below (repeatable; after the file)\n");
    for s in SETTINGS.iter() {
        if let Some(flag) = s.appears.flag {
            let left = format!("{flag} VALUE");
            text.push_str(&format!("  {left:<23} the same as --set {}=VALUE\n", s.name));
        }
    }
    for (flag, what) in own {
        text.push_str(&format!("  {flag:<23} {what}\n"));
    }
    text.push_str("  -h, --help              this text\n\n");
    text
}

/// Every setting: name, unit, default, allowed values, description.
fn settings_help() -> String {
    let mut text = String::from(
        "settings (a scene file holds `NAME = VALUE` lines in TOML: numbers, \"names\", true or\n\
         false; the defaults are the paper's scene):\n",
    );
    for s in SETTINGS {
        let unit = s.unit().map_or(String::new(), |u| format!(" [{u}]"));
        let default = s.show(s.default);
        text.push_str(&format!("  {}{unit} = {default}   ({})\n", s.name, s.allowed()));
        for line in wrap(s.description, 84) {
            text.push_str(&format!("      {line}\n"));
        }
    }
    text
}

/// `text` in lines of at most `width` characters, broken at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in text.split_whitespace() {
        let line = lines.last_mut().expect("one line at least");
        if !line.is_empty() && line.len() + 1 + word.len() > width {
            lines.push(word.to_string());
        } else {
            if !line.is_empty() {
                line.push(' ');
            }
            line.push_str(word);
        }
    }
    lines
}

/// What `simulate`, `modes` and `residual` take: the scene, its file, the output file, and
/// the settings the command line named.
pub struct SceneArgs {
    pub scene: Scene,
    pub file: Option<String>,
    pub output: Option<String>,
    /// The settings set on the command line (by `--set` or a flag), by name.
    pub given: Vec<&'static str>,
    /// `modes --count K`: how many modes.
    pub count: Option<usize>,
}

/// Parses `[SCENE.toml] [--set NAME=VALUE | --FLAG VALUE]... [-o FILE]` for `command`:
/// the scene file first, then the command line over it in the order written. `Ok(None)`
/// when `--help` printed the help.
pub fn scene_args(command: &str, args: Vec<OsString>) -> Result<Option<SceneArgs>, Failure> {
    let output_allowed = command == "simulate";
    let mut parser = lexopt::Parser::from_args(args);
    let (mut file, mut output, mut count) = (None, None, None);
    let mut sets: Vec<(&'static Setting, String, String)> = Vec::new();
    let bad =
        |e: lexopt::Error| Failure::Usage(format!("{command}: {e} (beam-body {command} --help)"));
    while let Some(arg) = parser.next().map_err(bad)? {
        match arg {
            Long("help") | Short('h') => {
                print(&command_help(command).expect("a known command"))?;
                return Ok(None);
            }
            Long("set") => {
                let kv = text(parser.value().map_err(bad)?, "--set")?;
                let (name, value) = kv
                    .split_once('=')
                    .ok_or_else(|| Failure::Usage(format!("--set {kv}: expected NAME=VALUE")))?;
                let setting = Setting::by_name(name.trim())?;
                sets.push((setting, value.to_string(), format!("--set {kv}")));
            }
            Short('o') | Long("output") if output_allowed => {
                output = Some(text(parser.value().map_err(bad)?, "-o")?);
            }
            Long("count") if command == "modes" => {
                let value = text(parser.value().map_err(bad)?, "--count")?;
                let k = value.parse::<usize>().ok().filter(|k| (1..=64).contains(k));
                count = Some(k.ok_or_else(|| {
                    Failure::Usage(format!("--count {value}: must be an integer in 1..=64"))
                })?);
            }
            Long(flag) => {
                let flag = format!("--{flag}");
                let Some(setting) = SETTINGS.iter().find(|s| s.appears.flag == Some(&flag)) else {
                    return Err(Failure::Usage(format!(
                        "{command}: unknown option `{flag}` (beam-body {command} --help)"
                    )));
                };
                let value = text(parser.value().map_err(bad)?, &flag)?;
                sets.push((setting, value.clone(), format!("{flag} {value}")));
            }
            Value(v) if file.is_none() => file = Some(text(v, "the scene file")?),
            other => return Err(bad(other.unexpected())),
        }
    }
    let mut scene = Scene::default();
    if let Some(path) = &file {
        let content = std::fs::read_to_string(path)
            .map_err(|e| Failure::Usage(format!("cannot read the scene file {path}: {e}")))?;
        scene.apply_toml(&content).map_err(|e| Failure::Usage(at_file(path, &e)))?;
    }
    for (setting, value, typed) in &sets {
        let checked = setting.parse(value).and_then(|v| scene.set(setting.key, v));
        checked.map_err(|e| Failure::Usage(format!("{typed}: {e}")))?;
    }
    let given = sets.iter().map(|(s, _, _)| s.name).collect();
    Ok(Some(SceneArgs { scene, file, output, given, count }))
}

/// An argument as UTF-8 text.
fn text(value: OsString, what: &str) -> Result<String, Failure> {
    value
        .into_string()
        .map_err(|v| Failure::Usage(format!("{what} {}: not valid UTF-8", v.to_string_lossy())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_setting_is_in_the_help() {
        let help = command_help("simulate").unwrap();
        for s in SETTINGS {
            assert!(help.contains(&format!("\n  {}", s.name)), "{}", s.name);
        }
        assert!(help.contains("--fixed-order VALUE"));
    }
}
