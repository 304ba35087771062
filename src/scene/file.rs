//! Scene files: TOML, read by the `toml` crate (as study files are), so that what TOML allows
//! works (`# comments`, 'literal strings', `1_000`) and what it refuses is refused (a duplicate
//! key, a bare word). Each key is a setting of the table, with a value of its type: a number
//! for a real, an integer, a string for a choice, true or false. Errors name the line and the
//! key.
#![forbid(unsafe_code)]

use super::Scene;
use crate::settings::{Kind, Setting, Value};
use toml::de::{DeTable, DeValue};

/// The value of `setting` that a TOML value gives; the error says what the setting takes.
pub fn toml_value(setting: &Setting, v: &toml::Value) -> Result<Value, String> {
    let value = match (setting.kind, v) {
        (Kind::Real { .. }, toml::Value::Float(x)) => Value::Real(*x),
        (Kind::Real { .. }, toml::Value::Integer(k)) => Value::Real(*k as f64),
        (Kind::Integer, toml::Value::Integer(k)) => Value::Integer(*k),
        (Kind::Choice(ty), toml::Value::String(name)) => match ty.index(name) {
            Some(k) => Value::Choice(k),
            None => {
                return Err(format!(
                    "`{}` = \"{name}\": must be one of {}",
                    setting.name,
                    ty.names()
                ))
            }
        },
        (Kind::Bool, toml::Value::Boolean(b)) => Value::Bool(*b),
        _ => {
            return Err(format!(
                "`{}` = {}: must be {}, not {}",
                setting.name,
                shown(v),
                setting.expects(),
                type_name(v)
            ))
        }
    };
    setting.check(value)
}

/// A scalar as the file writes it, for messages.
fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("{s:?}"),
        toml::Value::Integer(k) => k.to_string(),
        toml::Value::Float(x) => format!("{x:?}"),
        toml::Value::Boolean(b) => b.to_string(),
        toml::Value::Datetime(d) => d.to_string(),
        toml::Value::Array(_) => "[...]".to_string(),
        toml::Value::Table(_) => "{...}".to_string(),
    }
}

fn type_name(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a real number",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        toml::Value::Array(_) => "a list",
        toml::Value::Table(_) => "a table",
    }
}

/// A TOML syntax error on one line: "line L, column C: what". A duplicate key is named, with
/// the line that gave it first.
pub fn syntax_error(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim().replace('\n', " ");
    let Some(span) = e.span() else {
        return format!("not valid TOML: {message}");
    };
    let (line, column) = line_column(text, span.start);
    let key = text.get(span).map(str::trim).filter(|k| !k.is_empty() && !k.contains('\n'));
    let what = match key {
        Some(key) if message == "duplicate key" => {
            let (name, first) = duplicate(text, line, key);
            let first = first.map_or(String::new(), |l| format!(" (first given on line {l})"));
            format!("duplicate key `{name}`{first}: a key may be given only once")
        }
        _ => message,
    };
    format!("line {line}, column {column}: not valid TOML: {what}")
}

/// The name of the duplicate `key` on `line` (a table's whole name, `parameters.EI`), and the
/// line before it that gave it first: the same `[table]` anywhere before, or `key = …` in the
/// same table (after the last table header).
fn duplicate(text: &str, line: usize, key: &str) -> (String, Option<usize>) {
    let lines: Vec<&str> = text.lines().collect();
    let header = |l: &str| {
        let l = l.split('#').next().unwrap_or("").trim();
        let inner = l.strip_prefix('[').and_then(|l| l.strip_suffix(']'))?;
        (!inner.starts_with('[')).then(|| dotted(inner))
    };
    let before = &lines[..line.saturating_sub(1).min(lines.len())];
    if let Some(table) = lines.get(line.saturating_sub(1)).and_then(|l| header(l)) {
        let first = before.iter().position(|l| header(l).as_ref() == Some(&table));
        return (table, first.map(|k| k + 1));
    }
    let name = dotted(key);
    for (k, l) in before.iter().enumerate().rev() {
        if l.trim_start().starts_with('[') {
            break;
        }
        if l.split_once('=').is_some_and(|(left, _)| dotted(left) == name) {
            return (name, Some(k + 1));
        }
    }
    (name, None)
}

/// A (dotted) key by its names: `a . "b"` is `a.b`.
fn dotted(key: &str) -> String {
    let unquoted = |k: &str| {
        let k = k.trim();
        let quoted = |q: char| k.len() >= 2 && k.starts_with(q) && k.ends_with(q);
        if quoted('"') || quoted('\'') {
            k[1..k.len() - 1].to_string()
        } else {
            k.to_string()
        }
    };
    key.split('.').map(unquoted).collect::<Vec<_>>().join(".")
}

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// `message`, prefixed with the line of the key at `path` (a table's keys, then the key) in
/// the TOML `text`: "line 3: …". Unchanged if the key is not found.
pub fn locate(text: &str, path: &[&str], message: String) -> String {
    let Ok(doc) = DeTable::parse(text) else {
        return message;
    };
    let mut table = doc.get_ref();
    for (depth, name) in path.iter().enumerate() {
        let Some((key, value)) = table.iter().find(|(k, _)| k.get_ref() == name) else {
            return message;
        };
        match value.get_ref() {
            DeValue::Table(inner) if depth + 1 < path.len() => table = inner,
            _ => {
                let (line, _) = line_column(text, key.span().start);
                return format!("line {line}: {message}");
            }
        }
    }
    message
}

impl Scene {
    /// The scene of a scene file: the defaults, then each of its keys in order.
    pub fn from_toml(text: &str) -> Result<Scene, String> {
        let mut scene = Scene::default();
        scene.apply_toml(text)?;
        Ok(scene)
    }

    /// Sets each key of a scene file, in order.
    pub fn apply_toml(&mut self, text: &str) -> Result<(), String> {
        let table: toml::Table = text.parse().map_err(|e| syntax_error(text, &e))?;
        for (key, v) in &table {
            self.set_toml(key, v).map_err(|e| locate(text, &[key], e))?;
        }
        Ok(())
    }

    /// Sets the setting called `name` from a TOML value.
    pub fn set_toml(&mut self, name: &str, v: &toml::Value) -> Result<(), String> {
        let setting = Setting::by_name(name).map_err(|e| match v {
            toml::Value::Table(_) => {
                format!("`[{name}]`: a scene has no tables, only `setting = value` lines")
            }
            _ => e,
        })?;
        let value = toml_value(setting, v)?;
        self.set(setting.key, value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::RangeCheck;

    #[test]
    fn valid_toml_is_read_as_toml() {
        let text = "range_check = \"warn\"   # say so\n\
                    phi_source = 'input'\n\
                    EI = 1_000\n\
                    t_end = 5\n\
                    stability_guard = false\n";
        let s = Scene::from_toml(text).unwrap();
        assert_eq!(s.range_check, RangeCheck::Warn);
        assert_eq!(s.phi_source, super::super::PhiSource::Input);
        assert_eq!((s.params.ei, s.t_end, s.solver.stability_guard), (1000.0, 5.0, false));
    }

    #[test]
    fn invalid_toml_and_wrong_types_are_refused_with_the_line() {
        let e = Scene::from_toml("t_end = 2\nformulation = dae\n").unwrap_err();
        assert!(e.starts_with("line 2, column 15: not valid TOML"), "{e}");
        let e = Scene::from_toml("t_end = 2\nt_end = 3\n").unwrap_err();
        assert!(e.starts_with("line 2") && e.contains("not valid TOML"), "{e}");
        let e = Scene::from_toml("EI = 2000.0\nt_end = \"5\"\n").unwrap_err();
        assert_eq!(
            e,
            "line 2: `t_end` = \"5\": must be a number, positive and finite [s], not a string"
        );
        let e = Scene::from_toml("\n\nbeam_theory = \"exact\"\n").unwrap_err();
        assert!(e.starts_with("line 3: unknown setting `beam_theory`"), "{e}");
        let e = Scene::from_toml("formulation = \"dae-stabilized\"").unwrap_err();
        assert!(e.contains("must be one of reduced, dae, dae_stabilized, linear"), "{e}");
        let e = Scene::from_toml("max_order = 3.0").unwrap_err();
        assert!(e.contains("`max_order` = 3.0: must be an integer in 1..=5, not a real"), "{e}");
        let e = Scene::from_toml("[model]\nEI = 1.0").unwrap_err();
        assert!(e.starts_with("line 1: `[model]`: a scene has no tables"), "{e}");
    }

    /// The `toml` crate says only "duplicate key": the message names the key and the line
    /// that gave it first.
    #[test]
    fn a_duplicate_key_is_named_with_both_lines() {
        let e = Scene::from_toml("t_end = 2\nEI = 900\n\n  t_end = 3\n").unwrap_err();
        assert_eq!(
            e,
            "line 4, column 3: not valid TOML: duplicate key `t_end` (first given on line 1): \
             a key may be given only once"
        );
        let e = Scene::from_toml("EI = 1\n\"EI\" = 2\n").unwrap_err();
        assert!(e.contains("duplicate key `EI` (first given on line 1)"), "{e}");
        // In a table (a study file's), the first is the one in the same table.
        let text = "[a]\nx = 1\n[b]\nx = 1\nx = 2\n[a]\n";
        let e = syntax_error(text, &text.parse::<toml::Table>().unwrap_err());
        let want = "line 5, column 1: not valid TOML: duplicate key `x` (first given on line 4)";
        assert!(e.starts_with(want), "{e}");
        let text = "[a]\nx = 1\n[b]\n[ a ]\n";
        let e = syntax_error(text, &text.parse::<toml::Table>().unwrap_err());
        assert!(e.contains("duplicate key `a` (first given on line 1)"), "{e}");
        let text = "[parameters.EI]\nvalues = [1.0]\n\n[parameters . \"EI\"] # again\n";
        let e = syntax_error(text, &text.parse::<toml::Table>().unwrap_err());
        assert!(e.contains("duplicate key `parameters.EI` (first given on line 1)"), "{e}");
    }
}
