//! `beam-body modes`: small-oscillation periods about the static equilibrium.

use crate::args::scene_args;
use crate::{print, CmdResult, Failure};
use beam_body::model::{BeamBody, BeamN};
use std::f64::consts::PI;
use std::ffi::OsString;
use std::fmt::Write;

pub fn run(args: Vec<OsString>) -> CmdResult {
    let Some(cli) = scene_args("modes", args)? else {
        return Ok(());
    };
    let params = cli.scene.params;
    if let Some(k) = cli.count {
        check_count(k, params.n_elements)?;
    }
    // (φ, equilibrium (v1, ϑ1), ω² ascending) at each held angle.
    let angles = [("0", 0.0), ("pi/2", PI / 2.0), ("pi", PI)];
    let mut rows = Vec::new();
    if params.is_paper_model() && cli.count.is_none() {
        let model = BeamBody::new(params).map_err(|e| e.to_string())?;
        for (label, phi) in angles {
            let m = model.modes(phi);
            rows.push((label, m.equilibrium, m.omega2.to_vec()));
        }
    } else {
        let model = BeamN::new(params, cli.scene.formulation)?;
        for (label, phi) in angles {
            let (q, omega2) = model.modes(phi).ok_or_else(|| {
                format!("no static equilibrium found with the body held at phi = {label}")
            })?;
            rows.push((label, model.tip_values(q.as_slice()), omega2));
        }
    }
    let count = cli.count.unwrap_or(2).min(rows[0].2.len());
    let mut text = format!("{:<6}  {:>19}  {:>19}", "phi", "v1_eq [m]", "theta1_eq [rad]");
    for k in 1..=count {
        let _ = write!(text, "  {:>17}", format!("T{k} [s]"));
    }
    text.push('\n');
    for (label, (v, th), omega2) in rows {
        let _ = write!(text, "{label:<6}  {v:>+19.12e}  {th:>+19.12e}");
        for w2 in &omega2[..count] {
            let period = (*w2 > 0.0).then(|| 2.0 * PI / w2.sqrt());
            let shown = period.map_or("unstable".to_string(), |t| format!("{t:.15}"));
            let _ = write!(text, "  {shown:>17}");
        }
        text.push('\n');
    }
    print(&text)
}

/// `--count K` within the model's modes: the beam in n elements has 2n coordinates (a
/// deflection and a slope per node), so 2n modes.
fn check_count(k: usize, n_elements: usize) -> Result<(), Failure> {
    let modes = 2 * n_elements;
    if k <= modes {
        return Ok(());
    }
    let (plural, needed) = (if n_elements == 1 { "" } else { "s" }, k.div_ceil(2));
    Err(Failure::Usage(format!(
        "--count {k}: the beam in {n_elements} element{plural} has {modes} coordinates (a \
         deflection and a slope per node), so {modes} modes: ask for at most {modes}, or give \
         it {needed} elements or more (--elements {needed})"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_beyond_the_modes_is_refused_naming_the_limit() {
        assert!(check_count(2, 1).is_ok() && check_count(8, 4).is_ok());
        let Err(Failure::Usage(e)) = check_count(4, 1) else { panic!("--count 4 accepted") };
        assert_eq!(
            e,
            "--count 4: the beam in 1 element has 2 coordinates (a deflection and a slope per \
             node), so 2 modes: ask for at most 2, or give it 2 elements or more (--elements 2)"
        );
        let Err(Failure::Usage(e)) = check_count(7, 3) else { panic!("--count 7 accepted") };
        assert!(e.contains("3 elements has 6 coordinates") && e.ends_with("(--elements 4)"), "{e}");
    }
}
