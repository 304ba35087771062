//! Reading a study file: its tables and fields, each checked, with errors that name the
//! field and its line.

use super::*;

/// residual_v1 needs output times after the turn: t_end > t_rot for every case.
pub(super) fn check_residual_window(base: &Scene, parameters: &[Parameter]) -> Result<(), String> {
    let t_end = base.t_end;
    match parameters.iter().find(|p| p.name == "t_rot") {
        Some(p) => {
            let hi = p.axis.bounds().1;
            if hi >= t_end {
                let bound = match &p.axis {
                    Axis::Random(Distribution::Normal { .. }) => " (set `max` below it)",
                    Axis::Random(Distribution::LogNormal { .. }) => {
                        " (a log-normal is unbounded above: use a truncated normal)"
                    }
                    _ => "",
                };
                return Err(format!(
                    "`parameters.t_rot` reaches {hi}, but the metric residual_v1 needs \
                     t_rot < t_end = {t_end}{bound}"
                ));
            }
        }
        None if base.law.t_rot >= t_end => {
            return Err(format!(
                "`metrics`: residual_v1 needs t_rot < t_end, but t_rot = {} and t_end = {t_end}",
                base.law.t_rot
            ))
        }
        None => {}
    }
    Ok(())
}

/// Checks that every value the axis can give is one the scene accepts for `name`, by
/// setting its bounds on a scratch scene: the scene's own checks are the one definition of
/// the ranges.
pub(super) fn check_axis_range(
    base: &Scene,
    name: &str,
    axis: &Axis,
    field: &str,
) -> Result<(), String> {
    let (lo_key, hi_key) = match axis {
        // A list: every value, so that the error names the one that is out of range.
        Axis::Values(values) => {
            for (i, &v) in values.iter().enumerate() {
                if let Err(e) = base.clone().set_number(name, v) {
                    return Err(format!("`{field}.values[{i}]`: {e}"));
                }
            }
            return Ok(());
        }
        Axis::Grid { start, stop, .. } if start <= stop => ("start", "stop"),
        Axis::Grid { .. } => ("stop", "start"),
        Axis::Random(Distribution::Uniform { .. }) => ("low", "high"),
        Axis::Random(Distribution::Normal { .. }) => ("min", "max"),
        Axis::Random(Distribution::LogNormal { .. }) => ("mean", "mean"),
    };
    let (lo, hi) = axis.bounds();
    for (value, key) in [(lo, lo_key), (hi, hi_key)] {
        // An unbounded side is checked at the largest finite value.
        let probe = value.clamp(-f64::MAX, f64::MAX);
        if let Err(e) = base.clone().set_number(name, probe) {
            if value.is_infinite() {
                let side = if value < 0.0 { "below" } else { "above" };
                let allowed = e.rsplit_once("must be ").map_or(e.as_str(), |(_, a)| a);
                return Err(format!(
                    "`{field}`: the distribution is unbounded {side}, and `{name}` must be \
                     {allowed}: set `{field}.{key}` to truncate it"
                ));
            }
            return Err(format!("`{field}.{key}`: {e}"));
        }
    }
    Ok(())
}

/// An integer setting's axis gives whole numbers only: a list (each value checked by
/// [`check_axis_range`]), or a grid whose every point is one (a linear grid of whole steps,
/// `start = 1, stop = 8, count = 8`; a log grid such as 1, 2, 4, 8). A distribution gives
/// real numbers, and is refused.
pub(super) fn check_integer_axis(name: &str, axis: &Axis, field: &str) -> Result<(), String> {
    let must = format!("`{name}` must be {}", Setting::by_name(name)?.expects());
    let how = "list its values, `values = [1, 2, 4]`, or give a grid whose every point is a \
               whole number (start = 1, stop = 8, count = 8)";
    let (start, stop, count, log) = match *axis {
        Axis::Values(_) => return Ok(()),
        Axis::Random(_) => {
            return Err(format!("`{field}`: {must}, and a distribution gives real numbers: {how}"))
        }
        Axis::Grid { start, stop, count, log } => (start, stop, count, log),
    };
    // A linear grid's points are whole when its start and its step are; a log grid of whole
    // numbers below 2^53 has at most 54 points (its ratio's denominator divides the start).
    let points: Vec<u64> = if log { (0..count.min(64)).collect() } else { vec![0, 1, count - 1] };
    let off = points
        .into_iter()
        .filter(|&k| k < count)
        .map(|k| grid_point(start, stop, count, k, log))
        .find(|x| (x - x.round()).abs() > 1e-9 * x.abs().max(1.0));
    match off {
        None => Ok(()),
        Some(x) => Err(format!(
            "`{field}`: {must}, but this grid (start = {start}, stop = {stop}, count = {count}) \
             has the point {x}: {how}"
        )),
    }
}

pub(super) fn parse_axis(spec: &Table, field: &str) -> Result<Axis, String> {
    let num = |key: &str| number(spec.get(key), &format!("{field}.{key}"));
    if let Some(kind) = spec.get("distribution") {
        let kind = string(kind, &format!("{field}.distribution"))?;
        let d = match kind {
            "uniform" => {
                check_keys(spec, field, &["distribution", "low", "high"])?;
                let (low, high) = (num("low")?, num("high")?);
                if low >= high {
                    return Err(format!("`{field}.high` = {high}: must exceed low = {low}"));
                }
                Distribution::Uniform { low, high }
            }
            "normal" => {
                check_keys(spec, field, &["distribution", "mean", "sd", "min", "max"])?;
                let (mean, sd) = (num("mean")?, num("sd")?);
                positive(sd, &format!("{field}.sd"))?;
                let bound = |key: &str, default: f64| match spec.get(key) {
                    Some(_) => num(key),
                    None => Ok(default),
                };
                let (min, max) = (bound("min", f64::NEG_INFINITY)?, bound("max", f64::INFINITY)?);
                if min >= max {
                    return Err(format!("`{field}.max` = {max}: must exceed min = {min}"));
                }
                // Enough probability inside [min, max] to sample it by the quantile.
                if normal_cdf((max - mean) / sd) - normal_cdf((min - mean) / sd) < 1e-6 {
                    return Err(format!(
                        "`{field}`: [min, max] = [{min}, {max}] holds less than 1e-6 of the \
                         distribution's probability"
                    ));
                }
                Distribution::Normal { mean, sd, min, max }
            }
            "lognormal" | "log-normal" => {
                check_keys(spec, field, &["distribution", "mean", "sd"])?;
                let (mean, sd) = (num("mean")?, num("sd")?);
                positive(mean, &format!("{field}.mean"))?;
                positive(sd, &format!("{field}.sd"))?;
                Distribution::LogNormal { mean, sd }
            }
            other => {
                return Err(format!(
                    "`{field}.distribution` = \"{other}\": must be uniform, normal or lognormal"
                ))
            }
        };
        return Ok(Axis::Random(d));
    }
    if let Some(v) = spec.get("values") {
        check_keys(spec, field, &["values"])?;
        let Value::Array(items) = v else {
            return Err(format!("`{field}.values`: must be a list of numbers"));
        };
        if items.is_empty() {
            return Err(format!("`{field}.values`: the list is empty"));
        }
        let values = items
            .iter()
            .enumerate()
            .map(|(i, x)| number(Some(x), &format!("{field}.values[{i}]")))
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(Axis::Values(values));
    }
    if spec.contains_key("start") || spec.contains_key("stop") || spec.contains_key("count") {
        check_keys(spec, field, &["start", "stop", "count", "spacing"])?;
        let (start, stop) = (num("start")?, num("stop")?);
        let count = count(spec.get("count"), &format!("{field}.count"))?;
        let log = match spec.get("spacing") {
            None => false,
            Some(v) => match string(v, &format!("{field}.spacing"))? {
                "linear" => false,
                "log" => true,
                other => {
                    return Err(format!(
                        "`{field}.spacing` = \"{other}\": must be \"linear\" or \"log\""
                    ))
                }
            },
        };
        if log && !(start > 0.0 && stop > 0.0) {
            return Err(format!(
                "`{field}`: a log grid needs start and stop > 0, got {start} and {stop}"
            ));
        }
        if count > 1 && start == stop {
            return Err(format!(
                "`{field}.stop` = {stop}: must differ from start when count = {count} > 1"
            ));
        }
        if count == 1 && start != stop {
            return Err(format!(
                "`{field}.stop` = {stop}: a grid of count = 1 is its start alone, so stop must \
                 equal start = {start} (or use values = [...])"
            ));
        }
        return Ok(Axis::Grid { start, stop, count, log });
    }
    Err(format!(
        "`{field}`: give a grid (start, stop, count[, spacing]), a list (values = [...]) or a \
         distribution (distribution = \"uniform\" | \"normal\" | \"lognormal\")"
    ))
}

pub(super) fn check_keys(table: &Table, field: &str, allowed: &[&str]) -> Result<(), String> {
    for key in table.keys() {
        if !allowed.contains(&key.as_str()) {
            let path = if field.is_empty() { key.clone() } else { format!("{field}.{key}") };
            return Err(format!("`{path}`: unknown key; expected one of {}", allowed.join(", ")));
        }
    }
    Ok(())
}

pub(super) fn sub_table<'a>(v: &'a Value, field: &str) -> Result<&'a Table, String> {
    v.as_table().ok_or_else(|| format!("`{field}`: must be a table"))
}

pub(super) fn string<'a>(v: &'a Value, field: &str) -> Result<&'a str, String> {
    v.as_str().ok_or_else(|| format!("`{field}`: must be a string"))
}

pub(super) fn number(v: Option<&Value>, field: &str) -> Result<f64, String> {
    let x = match v {
        Some(Value::Float(x)) => *x,
        Some(Value::Integer(i)) => *i as f64,
        Some(_) => return Err(format!("`{field}`: must be a number")),
        None => return Err(format!("`{field}` is missing")),
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("`{field}` = {x}: must be finite"))
    }
}

pub(super) fn positive(x: f64, field: &str) -> Result<(), String> {
    if x > 0.0 {
        Ok(())
    } else {
        Err(format!("`{field}` = {x}: must be positive"))
    }
}

pub(super) fn count(v: Option<&Value>, field: &str) -> Result<u64, String> {
    match v {
        Some(Value::Integer(i)) if *i >= 1 => Ok(*i as u64),
        Some(Value::Integer(i)) => Err(format!("`{field}` = {i}: must be at least 1")),
        Some(_) => Err(format!("`{field}`: must be an integer, at least 1")),
        None => Err(format!("`{field}` is missing")),
    }
}

/// `message`, prefixed with the line of the field it names first (`` `parameters.EI.count`:
/// … ``), when the study's text has it.
pub(super) fn locate_field(text: &str, message: String) -> String {
    let field = message
        .strip_prefix('`')
        .and_then(|rest| rest.split_once('`'))
        .map(|(field, _)| field.to_string());
    match field {
        Some(field) => {
            // `metrics[2]` and `values[0]` are on the line of their list.
            let path: Vec<&str> =
                field.split('.').map(|k| k.split_once('[').map_or(k, |(k, _)| k)).collect();
            locate(text, &path, message)
        }
        None => message,
    }
}

impl Study {
    /// Parses and checks a study file. `load_scene` gets the value of its `scene` key (a
    /// path, relative to the study file) and returns the scene file's text. Errors name the
    /// field (`parameters.M2.count`) and what it allows.
    pub fn parse(
        text: &str,
        load_scene: impl FnOnce(&str) -> Result<String, String>,
    ) -> Result<Study, String> {
        Self::parse_table(text, load_scene).map_err(|e| locate_field(text, e))
    }

    fn parse_table(
        text: &str,
        load_scene: impl FnOnce(&str) -> Result<String, String>,
    ) -> Result<Study, String> {
        let table: Table = text.parse().map_err(|e| crate::scene::syntax_error(text, &e))?;
        // The study's own keys, and the settings a study file takes at its top level.
        let settings = SETTINGS.iter().filter(|s| s.appears.study_key).map(|s| s.name);
        let own = ["metrics", "sampling", "set", "parameters"];
        let top: Vec<&str> = std::iter::once("scene").chain(settings).chain(own).collect();
        check_keys(&table, "", &top)?;

        let mut base = Scene::default();
        let scene = match table.get("scene") {
            Some(v) => Some(string(v, "scene")?.to_string()),
            None => None,
        };
        if let Some(path) = &scene {
            let text = load_scene(path).map_err(|e| format!("`scene`: {e}"))?;
            base.apply_toml(&text).map_err(|e| format!("scene {path}: {e}"))?;
        }
        for key in SETTINGS.iter().filter(|s| s.appears.study_key).map(|s| s.name) {
            if let Some(v) = table.get(key) {
                base.set_toml(key, v).map_err(|e| format!("`{key}`: {e}"))?;
            }
        }
        let set = match table.get("set") {
            Some(v) => Some(sub_table(v, "set")?),
            None => None,
        };
        for (key, v) in set.into_iter().flatten() {
            base.set_toml(key, v).map_err(|e| format!("`set.{key}`: {e}"))?;
        }
        base.validate().map_err(|e| format!("the base scene: {e}"))?;

        let mut parameters = Vec::new();
        if let Some(v) = table.get("parameters") {
            for (name, spec) in sub_table(v, "parameters")? {
                let field = format!("parameters.{name}");
                if !variables().any(|s| s.name == name) {
                    let names: Vec<&str> = variables().map(|s| s.name).collect();
                    return Err(format!(
                        "`{field}`: unknown parameter `{name}`; a study can vary {}",
                        names.join(", ")
                    ));
                }
                if set.is_some_and(|s| s.contains_key(name)) {
                    return Err(format!("`{field}`: `{name}` is also fixed in [set]"));
                }
                let axis = parse_axis(sub_table(spec, &field)?, &field)?;
                if is_integer(name) {
                    check_integer_axis(name, &axis, &field)?;
                }
                check_axis_range(&base, name, &axis, &field)?;
                parameters.push(Parameter { name: name.clone(), axis });
            }
        }

        let random = parameters.iter().any(|p| matches!(p.axis, Axis::Random(_)));
        let (mut samples, mut seed) = (1, 0);
        match table.get("sampling") {
            Some(v) => {
                let s = sub_table(v, "sampling")?;
                check_keys(s, "sampling", &["samples", "seed"])?;
                if !random {
                    return Err("`sampling`: no parameter has a distribution".into());
                }
                samples = count(s.get("samples"), "sampling.samples")?;
                if samples > MAX_CASES {
                    return Err(format!(
                        "`sampling.samples` = {samples}: must be at most {MAX_CASES} (2^53)"
                    ));
                }
                seed = match s.get("seed") {
                    Some(Value::Integer(i)) if *i >= 0 => *i as u64,
                    Some(_) => return Err("`sampling.seed`: must be a non-negative integer".into()),
                    None => return Err("`sampling.seed` is missing: give a seed".into()),
                };
            }
            None if random => {
                return Err(
                    "`sampling` is missing: random parameters need `[sampling] samples = N` \
                     and `seed = S`"
                        .into(),
                )
            }
            None => {}
        }

        let metrics = match table.get("metrics") {
            None => Metric::ALL.to_vec(),
            Some(Value::Array(items)) => {
                let mut out = Vec::new();
                for (i, item) in items.iter().enumerate() {
                    let field = format!("metrics[{i}]");
                    let name = string(item, &field)?;
                    let m = Metric::by_name(name).ok_or_else(|| {
                        let all: Vec<_> = Metric::ALL.iter().map(|m| m.name()).collect();
                        format!("`{field}`: unknown metric `{name}`; one of {}", all.join(", "))
                    })?;
                    if out.contains(&m) {
                        return Err(format!("`{field}`: `{name}` is listed twice"));
                    }
                    out.push(m);
                }
                if out.is_empty() {
                    return Err("`metrics`: the list is empty".into());
                }
                out
            }
            Some(_) => {
                let all: Vec<_> = Metric::ALL.iter().map(|m| m.name()).collect();
                return Err(format!(
                    "`metrics`: must be a list of metric names: {}",
                    all.join(", ")
                ));
            }
        };
        if metrics.contains(&Metric::ResidualV1) {
            check_residual_window(&base, &parameters)?;
        }

        let mut cases: u64 = samples;
        for p in &parameters {
            if let Some(n) = p.axis.grid_len() {
                cases = cases
                    .checked_mul(n)
                    .filter(|&c| c <= MAX_CASES)
                    .ok_or_else(|| format!("`parameters`: more than {MAX_CASES} cases"))?;
            }
        }
        Ok(Study { base, scene, parameters, metrics, samples, seed, cases })
    }
}
