//! The sweep's markdown report: one table per group, with the columns that group is about.

use std::fmt::Write as _;

use super::{Case, Row};

/// A column of a group's table.
#[derive(Clone, Copy)]
enum Col {
    Case,
    Formulation,
    Status,
    Stiffness,
    Periods,
    Error,
    ErrorPerPeriod,
    PositionError,
    MaxError,
    Drift,
    EnergyDrift,
    Amplitude,
    Steps,
    Rejected,
    Time,
    TStop,
    TRefStop,
    Message,
}

use Col::*;

impl Col {
    fn header(self) -> &'static str {
        match self {
            Case => "case",
            Formulation => "formulation",
            Status => "status",
            Stiffness => "ω_max·t_rot",
            Periods => "periods",
            Error => "error",
            ErrorPerPeriod => "error / (periods·rtol^(5/6))",
            PositionError => "position error",
            MaxError => "max error",
            Drift => "max drift [m]",
            EnergyDrift => "energy drift",
            Amplitude => "fast amplitude",
            Steps => "steps",
            Rejected => "rejected",
            Time => "time",
            TStop => "stopped at [s]",
            TRefStop => "reference leaves range at [s]",
            Message => "message",
        }
    }

    fn cell(self, case: &Case, row: &Row) -> String {
        let count = |n: u64| if n == 0 { "—".to_string() } else { n.to_string() };
        match self {
            Case => case.name.clone(),
            Formulation => case.scene.formulation.name().to_string(),
            Status => row.status.clone(),
            Stiffness => sci(row.stiffness),
            Periods => sci(row.periods),
            Error => sci(row.error),
            ErrorPerPeriod => {
                sci(row.error / (case.scene.solver.rtol.powf(5.0 / 6.0) * row.periods.max(1.0)))
            }
            PositionError => sci(row.position_error),
            MaxError => sci(row.max_error),
            Drift => sci(row.drift),
            EnergyDrift => sci(row.energy_drift),
            Amplitude => sci(row.amplitude),
            Steps => count(row.steps),
            Rejected => count(if row.steps == 0 { 0 } else { row.rejected }),
            Time => duration(row.time_s),
            TStop => fixed(row.t_stop),
            TRefStop => fixed(row.t_ref_stop),
            Message => row.message.replace('|', "\\|"),
        }
    }
}

/// 3 significant digits, "—" for NaN.
fn sci(x: f64) -> String {
    if x.is_nan() {
        "—".into()
    } else {
        format!("{x:.2e}")
    }
}

fn fixed(x: f64) -> String {
    if x.is_nan() {
        "—".into()
    } else if x.is_infinite() {
        "never".into()
    } else {
        format!("{x:.4}")
    }
}

/// A wall time with 3 significant digits, in ms below 1 s.
pub fn duration(s: f64) -> String {
    let ms = s * 1e3;
    if !s.is_finite() {
        "—".into()
    } else if ms < 10.0 {
        format!("{ms:.3} ms")
    } else if ms < 100.0 {
        format!("{ms:.1} ms")
    } else if s < 1.0 {
        format!("{ms:.0} ms")
    } else {
        format!("{s:.2} s")
    }
}

/// What a group shows and how to read it.
fn group_layout(group: &str) -> (&'static str, &'static [Col]) {
    match group {
        "stiffness" => (
            "EI from 0.1 to 10⁷ times the paper's, with the paper's turn. ω_max·t_rot is the \
             stiffness ratio (radians of the fastest mode per turn time). The paper's law jumps \
             in φ'' at 0 and t_rot, so every scene rings in its fast mode, undamped, for up to \
             10⁵ periods; the error is mostly the phase of that ringing and grows with the \
             number of periods (up to saturation near 1), while the energy stays put. Tightening \
             rtol shrinks it.",
            &[
                Case,
                Formulation,
                Status,
                Stiffness,
                Periods,
                Error,
                ErrorPerPeriod,
                EnergyDrift,
                Steps,
                Rejected,
                Time,
                Message,
            ],
        ),
        "mass" | "turn" | "gravity" => (
            match group {
                "mass" => {
                    "A massless beam, a point-mass body (J_C = 0), a body hinged at its \
                     centre of mass (r = 0), and M2 from 10⁻³ to 10³ times the paper's."
                }
                "turn" => {
                    "Turns of π, 4π and 10π in t_rot = 0.85 s (the paper's), 0.2 s and \
                     0.05 s."
                }
                _ => {
                    "No gravity, and gravity reversed along the beam at 0.9 and 1.1 times the \
                     buckling value (found by bisection on the lowest mode's frequency)."
                }
            },
            &[
                Case,
                Formulation,
                Status,
                Stiffness,
                Error,
                PositionError,
                Steps,
                Rejected,
                Time,
                TStop,
                TRefStop,
                Message,
            ],
        ),
        "tolerance" => (
            "The paper's scene from rtol 1e-2 to 1e-14 (the solver's lower limit); the \
             reference runs at rtol 1e-12, and at 1e-14 for the cases below 1e-10.",
            &[Case, Status, Error, PositionError, MaxError, Steps, Rejected, Time, Message],
        ),
        "guard" => (
            "The stability guard on and off, on the model: the paper's turn and the free \
             vibration from a deflection near the first mode's shape, EI × 10² to 10⁵.",
            &[Case, Status, Error, PositionError, EnergyDrift, Steps, Rejected, Time, Message],
        ),
        "guard, test problem" => (
            "solver::problems::SlowAndFast: a driven first-order lag beside an undamped \
             oscillator of frequency ω and amplitude 1e-9, below atol = 1e-6; rtol 1e-5, \
             t = 0…200. The error is that of the lag at the end (its amplitude is 0.45); \
             the fast amplitude is the largest the oscillator reaches. The lag alone would \
             take steps h ≈ 0.1–0.2, so the trap is at ω ≈ 5–50, where h·ω lies in the \
             unstable bands of BDF3–5: at ω = 30 the unguarded run lets the oscillator grow \
             4 decades and needs 5× the steps, and the guard caps the order to BDF2, which \
             damps it. At ω = 10 the guard declines: BDF1 and BDF2 would take steps with \
             h·ω < 1, where they damp a mode by more than rtol per period, and the guard \
             cannot tell a mode below the tolerance (harmless to damp) from one above it \
             (the model's free vibration, which the band-only guard spoiled). The error test \
             then bounds the growth. At ω = 3 the mode is resolved, at ω ≥ 100 h·ω is above \
             every band: no trap, and the guard changes nothing.",
            &[Case, Status, Error, Amplitude, Steps, Rejected, Time, Message],
        ),
        "elements" => (
            "The beam as n cubic Hermite elements (`n_elements`), stiff (EI × 10⁴) and not, \
             with 1 % Rayleigh damping of its first two modes, and undamped. The reference is \
             our own BDF at rtol 1e-10 on the same equations (an explicit reference would need \
             about 10⁷ steps a second at EI × 10⁴; the Python oracle checks the equations independently), so the \
             error is integration error. Undamped, every mode rings for ever and BDF3–5 must \
             resolve the highest one. BDF2 alone (`max_order = 2`) damps the modes it does not \
             resolve: at n = 8 it takes a twelfth of the steps, for an error of 7e-3 against \
             3e-6.",
            &[Case, Status, Error, PositionError, MaxError, Steps, Rejected, Time, Message],
        ),
        "horizon" => (
            "The paper's turn, then constant φ up to t_end: energy and constraint drift. The \
             energy drift is relative to the energy just after the turn.",
            &[Case, Formulation, Status, Drift, EnergyDrift, Steps, Rejected, Time, TStop, Message],
        ),
        "communication" => (
            "Through the packaged FMU, φ from the law, communication steps H from 1e-6 s to \
             10 s (at most 2·10⁴ steps, hence shorter horizons for the smallest H).",
            &[Case, Status, Error, PositionError, MaxError, Time, Message],
        ),
        _ => ("", &[Case, Formulation, Status, Error, Steps, Time, TStop, Message]),
    }
}

/// The report: a summary of statuses, then one section per group in case order.
pub fn markdown(list: &[Case], rows: &[(usize, Row)], preamble: &str) -> String {
    let mut md = String::from(preamble);
    let mut counts: Vec<(String, usize)> = Vec::new();
    for (_, r) in rows {
        match counts.iter_mut().find(|(s, _)| *s == r.status) {
            Some((_, n)) => *n += 1,
            None => counts.push((r.status.clone(), 1)),
        }
    }
    let summary: Vec<String> = counts.iter().map(|(s, n)| format!("{n} {s}")).collect();
    let _ = writeln!(md, "{} cases: {}.\n", rows.len(), summary.join(", "));
    let mut groups: Vec<&str> = Vec::new();
    for (id, _) in rows {
        if !groups.contains(&list[*id].group) {
            groups.push(list[*id].group);
        }
    }
    for group in groups {
        let (about, cols) = group_layout(group);
        let _ = writeln!(md, "## {group}\n");
        if !about.is_empty() {
            let _ = writeln!(md, "{about}\n");
        }
        let headers: Vec<&str> = cols.iter().map(|c| c.header()).collect();
        let _ = writeln!(md, "| {} |", headers.join(" | "));
        let _ = writeln!(md, "|{}", "---|".repeat(cols.len()));
        for (id, r) in rows.iter().filter(|(id, _)| list[*id].group == group) {
            let cells: Vec<String> = cols.iter().map(|c| c.cell(&list[*id], r)).collect();
            let _ = writeln!(md, "| {} |", cells.join(" | "));
        }
        md.push('\n');
    }
    md
}
