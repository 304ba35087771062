//! `documentation/index.html` of the FMU, generated from the same interface tables as the
//! modelDescription. It lives only in target/ and in the .fmu, so it is never stale.
//!
//! A small, self-contained HTML5 page: no scripts, no external style sheets or images.

use std::fmt::Write as _;

use beam_body::fmu::variables::{
    self as vars, Dim, EnumType, Only, Type, Variable, CAPABILITIES, DEFAULT_EXPERIMENT,
    FORMULATION_TYPE, PHI_SOURCE_TYPE, VARIABLES,
};

use crate::model_description::{causality_name, initial, variability_name};

/// `text` escaped for HTML content and double-quoted attributes (the XML escaper serves both).
fn esc(text: &str) -> String {
    crate::xml::escape_attr(text)
}

/// The value of item `name` of an enumeration type (1-based).
fn item_value(ty: &EnumType, name: &str) -> usize {
    ty.items.iter().position(|(n, _)| *n == name).map(|k| k + 1).unwrap_or_else(|| {
        panic!("the enumeration {} has no item {name}", ty.name);
    })
}

/// The type, with what differs between the versions: FMI 3.0's arrays (their dimensions) and
/// structural parameter, FMI 2.0's own variables.
fn type_cell(v: &Variable) -> String {
    let base = match v.ty {
        Type::Real { .. } => "Real".into(),
        Type::Integer { .. } => "Integer".into(),
        Type::Enumeration { ty, .. } => format!("Enumeration ({})", esc(ty.name)),
        Type::Boolean { .. } => "Boolean".into(),
    };
    let dims: Vec<String> = v
        .dims
        .iter()
        .map(|d| match *d {
            Dim::Param(vr) => VARIABLES[vr as usize].name.to_string(),
            Dim::Fixed(k) => k.to_string(),
        })
        .collect();
    match v.only {
        Only::Fmi3 => format!("{base}[{}], FMI 3.0 only", dims.join(", ")),
        Only::Fmi2 => format!("{base}, FMI 2.0 only"),
        Only::Both if v.structural => format!("{base} (FMI 3.0: UInt64, structural parameter)"),
        Only::Both => base,
    }
}

fn start_cell(v: &Variable) -> String {
    match v.ty {
        Type::Real { start: Some(x), .. } => crate::model_description::real(x).unwrap_or_default(),
        Type::Real { start: None, .. } => String::new(),
        Type::Integer { start, .. } => start.to_string(),
        Type::Enumeration { ty, start } => {
            let name = usize::try_from(start - 1).ok().and_then(|k| ty.items.get(k));
            match name {
                Some((name, _)) => format!("{start} ({})", esc(name)),
                None => start.to_string(),
            }
        }
        Type::Boolean { start } => start.to_string(),
    }
}

fn range_cell(v: &Variable) -> String {
    // A parameter's range in the words of the settings table: "> 0" where the XML's `min` is
    // the smallest positive double.
    if let (Some(key), Type::Real { .. }) = (v.setting, v.ty) {
        return match beam_body::settings::Setting::of(key).range {
            beam_body::range::Range::Positive => "> 0".to_string(),
            beam_body::range::Range::NonNegative => "≥ 0".to_string(),
            beam_body::range::Range::Finite => "finite".to_string(),
            other => other.to_string(),
        };
    }
    let (min, max) = match v.ty {
        Type::Real { min, max, .. } => (min.map(|x| x.to_string()), max.map(|x| x.to_string())),
        Type::Integer { min, max, .. } => (Some(min.to_string()), Some(max.to_string())),
        Type::Enumeration { ty, .. } => (Some("1".into()), Some(ty.items.len().to_string())),
        Type::Boolean { .. } => (None, None),
    };
    match (min, max) {
        (Some(min), Some(max)) => format!("{min} … {max}"),
        (Some(min), None) => format!("≥ {min}"),
        (None, Some(max)) => format!("≤ {max}"),
        (None, None) => String::new(),
    }
}

/// The cells of a variable's row, HTML-escaped (valid in Markdown tables too): name, value
/// reference, causality (variability, initial), type, start, range, unit, description.
fn variable_cells(v: &Variable) -> [String; 8] {
    let (causality, variability) = (causality_name(v.causality), variability_name(v.variability));
    let causality = match initial(v.causality) {
        Some(initial) => format!("{causality} ({variability}, {initial})"),
        None => format!("{causality} ({variability})"),
    };
    let unit = match v.ty {
        Type::Real { unit: Some(unit), .. } => unit,
        _ => "",
    };
    [
        format!("<code>{}</code>", esc(v.name)),
        v.vr().to_string(),
        esc(&causality),
        type_cell(v),
        start_cell(v),
        range_cell(v),
        esc(unit),
        esc(v.description),
    ]
}

/// The variables as a Markdown table: the same rows as documentation/index.html.
pub fn variables_markdown() -> String {
    let mut md = String::from(
        "| name | vr | causality | type | start | range | unit | description |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for v in VARIABLES {
        let cells = variable_cells(v).map(|c| c.replace('|', "\\|"));
        let _ = writeln!(md, "| {} |", cells.join(" | "));
    }
    md
}

fn enum_table(html: &mut String, ty: &EnumType) {
    html.push_str("<table>\n<tr><th>value</th><th>name</th><th>meaning</th></tr>\n");
    for (k, (name, description)) in ty.items.iter().enumerate() {
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td><code>{}</code></td><td>{}</td></tr>",
            k + 1,
            esc(name),
            esc(description)
        );
    }
    html.push_str("</table>\n");
}

/// The whole page.
pub fn index_html() -> String {
    let mut h = String::new();
    let title = format!("{}: FMI 2.0 Co-Simulation FMU", vars::MODEL_NAME);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{}</title>\n<style>\n\
         body {{ font-family: sans-serif; max-width: 60em; margin: 2em auto; padding: 0 1em; \
         line-height: 1.45; }}\n\
         table {{ border-collapse: collapse; margin: 0.8em 0; }}\n\
         th, td {{ border: 1px solid #bbb; padding: 0.25em 0.5em; text-align: left; \
         vertical-align: top; }}\n\
         th {{ background: #eee; }}\n\
         code {{ font-size: 0.95em; }}\n\
         </style>\n</head>\n<body>\n<h1>{}</h1>\n",
        esc(&title),
        esc(&title)
    );

    h.push_str("<h2>The model</h2>\n");
    let _ = writeln!(
        h,
        "<p>An inextensible elastic cantilever beam (length <code>l</code>, bending stiffness \
         <code>EI</code>, mass per unit length <code>m</code>), clamped at one end and \
         discretised by Ritz with <code>n_elements</code> cubic Hermite elements: one by \
         default, the paper's model, whose two coordinates are the tip deflection \
         <code>v1</code> and the rotation <code>theta1</code> of the tip section; up to 32, with \
         two coordinates a node. <code>beam</code> chooses the beam theory: \
         <code>quadratic</code>, the paper's, keeps the geometric nonlinearity to second order \
         and holds while <code>|theta1|</code> stays within pi/2; <code>exact</code> is the \
         inextensible elastica, valid at any rotation, whose coordinates are the section angles. \
         Co-simulation runs every beam; Model Exchange runs n elements and the exact beam \
         in FMI 3.0 (states as arrays sized by <code>n_elements</code>), the paper's model \
         only in FMI 2.0, whose states are fixed. A \
         heavy rigid body (mass <code>M2</code>, moment of inertia <code>J_C</code> about its \
         centre of mass, which lies at distance <code>r</code> from the hinge) is hinged at the \
         tip and turned through a large prescribed angle <code>phi(t)</code> relative to the \
         tip section; gravity <code>g</code> acts along the undeformed beam axis. In the \
         quadratic beam inextensibility makes the tip's axial displacement quadratic in \
         <code>v1</code> and <code>theta1</code>, which keeps the vibrations' geometric \
         nonlinearity. The FMU \
         integrates the equations of motion with its own variable-order BDF and reports the \
         motion, the hinge reactions <code>N</code>, <code>P</code>, <code>M</code> and the \
         energy. Model and example (the default parameters and turn) are those of \
         S.&nbsp;V.&nbsp;Russkikh and F.&nbsp;N.&nbsp;Shklyarchuk, <cite>Numerical solution \
         of nonlinear equations of motion of composite elastic systems with constraints</cite>, \
         Mechanics of Composite Materials and Structures 26(1), 2020, pp. 139–150.</p>"
    );

    h.push_str("<h2>Formulations</h2>\n");
    let formulation = vars::Var::Formulation.info();
    let _ = writeln!(
        h,
        "<p>The parameter <code>{}</code> selects the equations (default: {}):</p>",
        esc(formulation.name),
        start_cell(formulation)
    );
    enum_table(&mut h, &FORMULATION_TYPE);

    h.push_str("<h2>How phi is supplied</h2>\n");
    let source = vars::Var::PhiSource.info();
    let phi = vars::Var::Phi.info();
    let extrapolation = vars::Var::PhiExtrapolation.info();
    let (input_name, law_name) = ("input", "law");
    let input = item_value(&PHI_SOURCE_TYPE, input_name);
    let law = item_value(&PHI_SOURCE_TYPE, law_name);
    let _ = writeln!(
        h,
        "<p>The equations need phi and its first two derivatives. The parameter \
         <code>{source}</code> (default: {default}) says where they come from:</p>",
        source = esc(source.name),
        default = start_cell(source),
    );
    enum_table(&mut h, &PHI_SOURCE_TYPE);
    let _ = writeln!(
        h,
        "<ul>\n\
         <li><code>{source} = {input_name}</code> ({input}), with derivatives: the host sets \
         the input <code>{phi}</code> and calls <code>fmi2SetRealInputDerivatives</code> with \
         order 1 and/or 2 (<code>canInterpolateInputs = {interpolate}</code>). Over the next \
         step from tc the FMU uses the Taylor polynomial phi(tc) + phi'(tc)(t − tc) + \
         ½ phi''(tc)(t − tc)² (a derivative not sent counts as 0). Derivatives apply to the \
         next step only; they must be sent again for every step.</li>\n\
         <li><code>{source} = {input_name}</code> ({input}), values only (what most hosts \
         send, FMPy's <code>simulate_fmu</code> among them): the polynomial of degree \
         <code>{extrapolation}</code> (default {degree}) through the last input values gives a \
         value and a slope at the end of the step; over the step the FMU uses the cubic from the \
         current phi and phi' to that target. phi and phi' stay continuous from step to step, \
         and the error falls at second order or better with the communication step. The run \
         starts with phi' = 0.</li>\n\
         <li><code>{source} = {law_name}</code> ({law}): the paper's law, \
         phi_end·sin²(π t / (2 t_rot)) for t ≤ t_rot, then phi_end (parameters \
         <code>t_rot</code> and <code>phi_end</code>); the input is ignored.</li>\n\
         </ul>\n\
         <p>The outputs <code>phi_applied</code>, <code>dphi_applied</code> and \
         <code>ddphi_applied</code> report the angle and derivatives that the model used.</p>",
        source = esc(source.name),
        phi = esc(phi.name),
        extrapolation = esc(extrapolation.name),
        degree = start_cell(extrapolation),
        interpolate = CAPABILITIES.can_interpolate_inputs,
    );

    h.push_str("<h2>Default experiment and capabilities</h2>\n<table>\n");
    let ex = DEFAULT_EXPERIMENT;
    let caps = CAPABILITIES;
    let rows: [(&str, String); 9] = [
        ("startTime, stopTime", format!("{} s, {} s", ex.start_time, ex.stop_time)),
        ("stepSize (communication step)", format!("{} s", ex.step_size)),
        ("tolerance (relative, of the internal BDF)", format!("{:e}", ex.tolerance)),
        (
            "canHandleVariableCommunicationStepSize",
            caps.can_handle_variable_communication_step_size.to_string(),
        ),
        ("canInterpolateInputs", caps.can_interpolate_inputs.to_string()),
        ("maxOutputDerivativeOrder", caps.max_output_derivative_order.to_string()),
        (
            "canGetAndSetFMUstate, canSerializeFMUstate",
            format!("{}, {}", caps.can_get_and_set_fmu_state, caps.can_serialize_fmu_state),
        ),
        ("providesDirectionalDerivative", caps.provides_directional_derivative.to_string()),
        ("guid", vars::guid().to_string()),
    ];
    for (key, value) in rows {
        let _ = writeln!(h, "<tr><th>{}</th><td>{}</td></tr>", esc(key), esc(&value));
    }
    h.push_str("</table>\n");

    h.push_str("<h2>Variables</h2>\n");
    h.push_str(
        "<p>Parameters are fixed (set them before <code>fmi2ExitInitializationMode</code>). \
         Outputs are calculated. Units are SI.</p>\n",
    );
    h.push_str(
        "<table>\n<tr><th>name</th><th>vr</th><th>causality</th><th>type</th><th>start</th>\
         <th>range</th><th>unit</th><th>description</th></tr>\n",
    );
    for v in VARIABLES {
        let cells = variable_cells(v).map(|c| format!("<td>{c}</td>")).concat();
        let _ = writeln!(h, "<tr>{cells}</tr>");
    }
    h.push_str("</table>\n");

    let _ = writeln!(
        h,
        "<p><small>Generated by {} from the interface tables that also generate \
         modelDescription.xml.</small></p>\n</body>\n</html>",
        esc(vars::GENERATION_TOOL)
    );
    h
}

#[cfg(test)]
mod tests {
    use beam_body::fmu::variables::{FORMULATION_TYPE, PHI_SOURCE_TYPE, VARIABLES};

    use super::{esc, index_html};

    #[test]
    fn page_names_every_variable_and_item() {
        let html = index_html();
        assert!(html.starts_with("<!DOCTYPE html>\n<html lang=\"en\">"));
        assert!(html.trim_end().ends_with("</html>"));
        for v in VARIABLES {
            assert!(html.contains(&format!("<td><code>{}</code></td>", esc(v.name))), "{}", v.name);
            assert!(html.contains(&esc(v.description)), "{}", v.name);
        }
        for (name, description) in FORMULATION_TYPE.items.iter().chain(PHI_SOURCE_TYPE.items) {
            assert!(html.contains(&format!("<code>{}</code>", esc(name))), "{name}");
            assert!(html.contains(&esc(description)), "{name}");
        }
        assert!(html.contains("Russkikh"));
        // Self-contained: nothing is fetched.
        for external in ["<script", "<link", "<img", "src=", "href="] {
            assert!(!html.contains(external), "{external}");
        }
    }

    #[test]
    fn tags_balance() {
        let html = index_html();
        for tag in ["html", "head", "body", "table", "tr", "td", "th", "p", "ul", "li", "code"] {
            let open = html.matches(&format!("<{tag}>")).count()
                + html.matches(&format!("<{tag} ")).count();
            let close = html.matches(&format!("</{tag}>")).count();
            assert_eq!(open, close, "<{tag}>");
        }
    }
}
