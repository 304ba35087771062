//! `cargo xtask gen`: the model descriptions from the interface tables in
//! `beam_body::fmu::variables`, the single source of truth: FMI 2.0's
//! `modelDescription/modelDescription.xml` (this module) and FMI 3.0's
//! `modelDescription/fmi3/modelDescription.xml` ([`crate::model_description3`]), which share
//! the writer and the helpers here.
//!
//! Both files are committed. Tests keep them honest: each must equal what its generator writes
//! now, byte for byte, and read back with quick-xml it must say what the tables say.
//! `cargo xtask fmu` refuses to package a stale file.

use beam_body::fmi::Version;
use beam_body::fmu::variables::{
    self as vars, Causality, EnumType, Type, Variability, Variable, CAPABILITIES,
    DEFAULT_EXPERIMENT, ENUM_TYPES, EVENT_INDICATORS, EXCHANGE_CAPABILITIES, LOG_CATEGORIES, UNITS,
    VARIABLES,
};
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

use crate::xml::escape_attr;
use crate::Result;

/// A real as the XML writes it: the shortest decimal string that parses back to the same
/// f64 (xs:double accepts both forms): Rust's `Display` ("0.000001", "3.141592653589793")
/// for ordinary magnitudes, the exponent form ("2.2250738585072014e-308", the `min` of a
/// positive parameter) for tiny and huge ones, where `Display` would write hundreds of
/// digits. Non-finite values have no place in the tables.
pub fn real(x: f64) -> Result<String> {
    if x.is_finite() {
        let ordinary = x == 0.0 || (1e-7..1e16).contains(&x.abs());
        Ok(if ordinary { x.to_string() } else { format!("{x:e}") })
    } else {
        Err(format!("the non-finite value {x} cannot be written to the modelDescription").into())
    }
}

pub(crate) fn boolean(b: bool) -> String {
    b.to_string()
}

/// `initial` as FMI 2.0 and 3.0 require it for each causality of ours: parameters are exact
/// (with a start), outputs and locals are calculated (no start), and the continuous inputs and
/// the independent variable have none (an input's start is implicitly approx in FMI 2.0, exact
/// in FMI 3.0; the independent variable must not have one).
pub fn initial(causality: Causality) -> Option<&'static str> {
    match causality {
        Causality::Parameter => Some("exact"),
        Causality::Input | Causality::Independent => None,
        Causality::Output | Causality::Local => Some("calculated"),
    }
}

pub fn causality_name(causality: Causality) -> &'static str {
    match causality {
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
        Causality::Local => "local",
        Causality::Independent => "independent",
    }
}

pub fn variability_name(variability: Variability) -> &'static str {
    match variability {
        Variability::Fixed => "fixed",
        Variability::Continuous => "continuous",
    }
}

/// The 1-based `<ModelVariables>` indices of the outputs, for `<ModelStructure>`.
pub fn output_indices() -> Vec<usize> {
    indices(|v| v.causality == Causality::Output)
}

/// The 1-based indices of the state derivatives, for `<Derivatives>`.
pub fn derivative_indices() -> Vec<usize> {
    indices(|v| v.derivative_of.is_some())
}

/// The 1-based indices of the variables computed at initialization (`initial` =
/// calculated): the outputs, the states among them, and the derivatives, in index order
/// (FMI 2.0 §2.2.8 lists no other locals).
pub fn initial_unknown_indices() -> Vec<usize> {
    indices(is_initial_unknown)
}

/// Whether `<ModelStructure>` lists the variable among the initial unknowns: the outputs,
/// the states and the state derivatives, all calculated. Neither FMI 2.0 nor
/// FMI 3.0 lists other locals there (FMI 3.0 §2.4.8 forbids the event indicators).
pub(crate) fn is_initial_unknown(v: &Variable) -> bool {
    v.causality == Causality::Output || v.derivative_of.is_some() || is_state(v)
}

/// Whether a variable is a continuous state: another is its derivative. FMI 2.0's states
/// are outputs; FMI 3.0's (the array q) are calculated locals, initial unknowns too.
pub(crate) fn is_state(v: &Variable) -> bool {
    VARIABLES.iter().any(|d| d.derivative_of == Some(v.vr()) && d.only == v.only)
}

/// The 1-based `<ModelVariables>` index of the variable with value reference `vr`: FMI 2.0's
/// list leaves out FMI 3.0's arrays, so the variables after them are not at `vr + 1`.
pub fn index_of(vr: u32) -> usize {
    variables(Version::Fmi2).position(|v| v.vr() == vr).expect("a variable of FMI 2.0's list") + 1
}

fn indices(keep: impl Fn(&Variable) -> bool) -> Vec<usize> {
    variables(Version::Fmi2).enumerate().filter(|(_, v)| keep(v)).map(|(row, _)| row + 1).collect()
}

/// The variables of `version`'s model description, in value-reference order: FMI 3.0's
/// arrays come after every variable both have, so FMI 2.0's 1-based indices are the same as
/// without them.
pub fn variables(version: Version) -> impl Iterator<Item = &'static Variable> {
    VARIABLES.iter().filter(move |v| v.in_version(version))
}

/// The rules the tables must follow for the XML to be valid FMI 2.0 and 3.0, checked before
/// writing.
pub(crate) fn check_rules(v: &Variable) -> Result {
    let has_start = match v.ty {
        Type::Real { start, .. } => start.is_some(),
        _ => true,
    };
    let problem = match (v.causality, v.variability, has_start) {
        (Causality::Parameter, Variability::Fixed, true) => None,
        (Causality::Parameter, _, _) => Some("a parameter must be fixed and have a start value"),
        (Causality::Input, Variability::Continuous, true) => match v.ty {
            Type::Real { .. } => None,
            _ => Some("a continuous input must be a Real"),
        },
        (Causality::Input, _, _) => Some("the input must be continuous and have a start value"),
        (Causality::Output, Variability::Continuous, false) => match v.ty {
            Type::Real { .. } => None,
            _ => Some("a continuous output must be a Real"),
        },
        (Causality::Output, _, _) => {
            Some("an output must be continuous and have no start value (initial = calculated)")
        }
        (Causality::Local, Variability::Continuous, false) => match v.ty {
            Type::Real { .. } => None,
            _ => Some("a local is a continuous Real"),
        },
        (Causality::Local, _, _) => {
            Some("a local is calculated: continuous, with no start value (initial = calculated)")
        }
        (Causality::Independent, Variability::Continuous, false) => match v.ty {
            Type::Real { .. } => None,
            _ => Some("the independent variable is a Real"),
        },
        (Causality::Independent, _, _) => {
            Some("the independent variable is continuous and has no start value")
        }
    };
    match problem {
        None => Ok(()),
        Some(problem) => Err(format!("variable `{}`: {problem}", v.name).into()),
    }
}

/// Attributes, in the order they are written; values unescaped.
pub(crate) type Attrs = Vec<(&'static str, String)>;

/// quick-xml's indenting writer with attribute lists.
pub(crate) struct Doc {
    writer: Writer<Vec<u8>>,
}

impl Doc {
    /// A document that starts with the XML declaration (UTF-8, as FMI requires).
    pub(crate) fn new() -> Doc {
        let mut doc = Doc { writer: Writer::new_with_indent(Vec::new(), b' ', 2) };
        doc.event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)));
        doc
    }

    fn start_tag<'a>(name: &'a str, attrs: &Attrs) -> BytesStart<'a> {
        let mut start = BytesStart::new(name);
        for (key, value) in attrs {
            start.push_attribute((key.as_bytes(), escape_attr(value).as_bytes()));
        }
        start
    }

    fn event(&mut self, event: Event) {
        // Writing into a Vec cannot fail.
        self.writer.write_event(event).expect("writing XML into memory");
    }

    pub(crate) fn empty(&mut self, name: &str, attrs: Attrs) {
        self.event(Event::Empty(Doc::start_tag(name, &attrs)));
    }

    pub(crate) fn start(&mut self, name: &str, attrs: Attrs) {
        self.event(Event::Start(Doc::start_tag(name, &attrs)));
    }

    pub(crate) fn end(&mut self, name: &str) {
        self.event(Event::End(BytesEnd::new(name)));
    }

    pub(crate) fn finish(self) -> String {
        let mut bytes = self.writer.into_inner();
        bytes.push(b'\n');
        String::from_utf8(bytes).expect("the XML is built from UTF-8 strings")
    }
}

/// The flags `<ModelExchange>` and `<CoSimulation>` share, the last four of each: the
/// memory, instantiation and FMU-state ones are the same; each has its own
/// `providesDirectionalDerivative`.
fn shared_flags(provides_directional_derivative: bool) -> Attrs {
    let caps = CAPABILITIES;
    vec![
        (
            "canBeInstantiatedOnlyOncePerProcess",
            boolean(caps.can_be_instantiated_only_once_per_process),
        ),
        (
            "canNotUseMemoryManagementFunctions",
            boolean(caps.can_not_use_memory_management_functions),
        ),
        ("canGetAndSetFMUstate", boolean(caps.can_get_and_set_fmu_state)),
        ("canSerializeFMUstate", boolean(caps.can_serialize_fmu_state)),
        ("providesDirectionalDerivative", boolean(provides_directional_derivative)),
    ]
}

/// `<fmiModelDescription>`'s attributes: `fmiVersion`, and the GUID under the name of the
/// version (`guid`, `instantiationToken`), then the model's names, the same in every version.
pub(crate) fn header(fmi_version: &str, guid_attribute: &'static str) -> Attrs {
    vec![
        ("fmiVersion", fmi_version.into()),
        ("modelName", vars::MODEL_NAME.into()),
        (guid_attribute, vars::guid().into()),
        ("description", vars::MODEL_DESCRIPTION.into()),
        ("version", vars::MODEL_VERSION.into()),
        ("generationTool", vars::GENERATION_TOOL.into()),
        ("variableNamingConvention", "flat".into()),
    ]
}

/// `<UnitDefinitions>`, the same in FMI 2.0 and 3.0.
pub(crate) fn write_units(doc: &mut Doc) {
    doc.start("UnitDefinitions", vec![]);
    for unit in UNITS {
        doc.start("Unit", vec![("name", unit.name.into())]);
        let exponents = [("kg", unit.kg), ("m", unit.m), ("s", unit.s), ("rad", unit.rad)];
        doc.empty(
            "BaseUnit",
            exponents.iter().filter(|(_, e)| *e != 0).map(|(k, e)| (*k, e.to_string())).collect(),
        );
        doc.end("Unit");
    }
    doc.end("UnitDefinitions");
}

/// The `<Item>`s of an enumeration type, 1-based, the same in FMI 2.0 and 3.0.
pub(crate) fn write_items(doc: &mut Doc, ty: &EnumType) {
    for (k, (name, description)) in ty.items.iter().enumerate() {
        doc.empty(
            "Item",
            vec![
                ("name", name.to_string()),
                ("value", (k + 1).to_string()),
                ("description", description.to_string()),
            ],
        );
    }
}

/// `<LogCategories>` and `<DefaultExperiment>`, the same in FMI 2.0 and 3.0.
pub(crate) fn write_categories_and_experiment(doc: &mut Doc) -> Result {
    doc.start("LogCategories", vec![]);
    for (name, description) in LOG_CATEGORIES {
        doc.empty(
            "Category",
            vec![("name", name.to_string()), ("description", description.to_string())],
        );
    }
    doc.end("LogCategories");

    let ex = DEFAULT_EXPERIMENT;
    doc.empty(
        "DefaultExperiment",
        vec![
            ("startTime", real(ex.start_time)?),
            ("stopTime", real(ex.stop_time)?),
            ("tolerance", real(ex.tolerance)?),
            ("stepSize", real(ex.step_size)?),
        ],
    );
    Ok(())
}

/// A variable's attributes that both versions write first: name, value reference,
/// description, causality and variability.
pub(crate) fn variable_attrs(v: &Variable) -> Attrs {
    vec![
        ("name", v.name.into()),
        ("valueReference", v.vr().to_string()),
        ("description", v.description.into()),
        ("causality", causality_name(v.causality).into()),
        ("variability", variability_name(v.variability).into()),
    ]
}

/// A real's unit, start, min and max (those it has), as both versions write them.
pub(crate) fn real_attrs(
    unit: Option<&'static str>,
    start: Option<f64>,
    min: Option<f64>,
    max: Option<f64>,
) -> Result<Attrs> {
    let mut attrs: Attrs = Vec::new();
    if let Some(unit) = unit {
        attrs.push(("unit", unit.into()));
    }
    for (key, value) in [("start", start), ("min", min), ("max", max)] {
        if let Some(value) = value {
            attrs.push((key, real(value)?));
        }
    }
    Ok(attrs)
}

/// An integer's start, min and max.
pub(crate) fn integer_attrs(start: i32, min: i32, max: i32) -> Attrs {
    vec![("start", start.to_string()), ("min", min.to_string()), ("max", max.to_string())]
}

/// An enumeration's type and start (its 1-based item).
pub(crate) fn enumeration_attrs(ty: &EnumType, start: i32) -> Attrs {
    vec![("declaredType", ty.name.into()), ("start", start.to_string())]
}

/// The whole FMI 2.0 modelDescription.xml.
pub fn generate() -> Result<String> {
    for v in VARIABLES {
        check_rules(v)?;
    }
    let mut doc = Doc::new();
    let mut attrs = header("2.0", "guid");
    attrs.push(("numberOfEventIndicators", EVENT_INDICATORS.to_string()));
    doc.start("fmiModelDescription", attrs);

    let me = EXCHANGE_CAPABILITIES;
    doc.empty(
        "ModelExchange",
        [
            ("modelIdentifier", vars::MODEL_IDENTIFIER.into()),
            ("needsExecutionTool", boolean(false)),
            ("completedIntegratorStepNotNeeded", boolean(me.completed_integrator_step_not_needed)),
        ]
        .into_iter()
        .chain(shared_flags(me.provides_directional_derivative))
        .collect(),
    );

    let caps = CAPABILITIES;
    let mut attrs: Attrs = vec![
        ("modelIdentifier", vars::MODEL_IDENTIFIER.into()),
        ("needsExecutionTool", boolean(false)),
        (
            "canHandleVariableCommunicationStepSize",
            boolean(caps.can_handle_variable_communication_step_size),
        ),
        ("canInterpolateInputs", boolean(caps.can_interpolate_inputs)),
    ];
    if caps.max_output_derivative_order > 0 {
        attrs.push(("maxOutputDerivativeOrder", caps.max_output_derivative_order.to_string()));
    }
    attrs.extend([
        // sic: FMI 2.0's spelling.
        ("canRunAsynchronuously", boolean(caps.can_run_asynchronuously)),
    ]);
    attrs.extend(shared_flags(caps.provides_directional_derivative));
    doc.empty("CoSimulation", attrs);

    write_units(&mut doc);

    doc.start("TypeDefinitions", vec![]);
    for ty in ENUM_TYPES {
        doc.start(
            "SimpleType",
            vec![("name", ty.name.into()), ("description", ty.description.into())],
        );
        doc.start("Enumeration", vec![]);
        write_items(&mut doc, ty);
        doc.end("Enumeration");
        doc.end("SimpleType");
    }
    doc.end("TypeDefinitions");

    write_categories_and_experiment(&mut doc)?;

    doc.start("ModelVariables", vec![]);
    for v in variables(Version::Fmi2) {
        write_variable(&mut doc, v)?;
    }
    doc.end("ModelVariables");

    doc.start("ModelStructure", vec![]);
    for (list, indices) in [
        ("Outputs", output_indices()),
        ("Derivatives", derivative_indices()),
        ("InitialUnknowns", initial_unknown_indices()),
    ] {
        doc.start(list, vec![]);
        for index in indices {
            doc.empty("Unknown", vec![("index", index.to_string())]);
        }
        doc.end(list);
    }
    doc.end("ModelStructure");

    doc.end("fmiModelDescription");
    Ok(doc.finish())
}

fn write_variable(doc: &mut Doc, v: &Variable) -> Result {
    let mut attrs = variable_attrs(v);
    if let Some(initial) = initial(v.causality) {
        attrs.push(("initial", initial.into()));
    }
    doc.start("ScalarVariable", attrs);
    match v.ty {
        Type::Real { unit, start, min, max } => {
            let mut attrs = real_attrs(unit, start, min, max)?;
            if let Some(state) = v.derivative_of {
                attrs.push(("derivative", index_of(state).to_string()));
            }
            doc.empty("Real", attrs);
        }
        Type::Integer { start, min, max } => doc.empty("Integer", integer_attrs(start, min, max)),
        Type::Enumeration { ty, start } => doc.empty("Enumeration", enumeration_attrs(ty, start)),
        Type::Boolean { start } => doc.empty("Boolean", vec![("start", boolean(start))]),
    }
    doc.end("ScalarVariable");
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    //! The committed file against the tables. The parse-back test reads the file with its own
    //! reader and compares with the tables directly, not with the generator's code.

    use std::collections::HashMap;
    use std::fs;

    use beam_body::fmu::variables::{
        self as vars, Causality, Type, Variability, CAPABILITIES, DEFAULT_EXPERIMENT, ENUM_TYPES,
        EVENT_INDICATORS, EXCHANGE_CAPABILITIES, LOG_CATEGORIES, UNITS,
    };

    use super::{generate, real};
    use crate::descriptions::{Description, FMI2};
    use crate::xml::Element;

    /// The committed text of `description`.
    pub(crate) fn committed(description: &Description) -> String {
        let path = description.path();
        fs::read_to_string(&path).unwrap_or_else(|err| {
            panic!("cannot read {}: {err}; run `cargo xtask gen`", path.display())
        })
    }

    /// The root element of the committed `description`.
    pub(crate) fn root_of(description: &Description) -> Element {
        Element::parse(&committed(description))
            .unwrap_or_else(|err| panic!("{} does not parse: {err}", description.relative_path))
    }

    fn root() -> Element {
        root_of(&FMI2)
    }

    /// The attributes of `e` as a map; fails on an attribute outside `allowed`.
    pub(crate) fn attrs<'a>(e: &'a Element, allowed: &[&str]) -> HashMap<&'a str, &'a str> {
        for (key, _) in &e.attrs {
            assert!(
                allowed.contains(&key.as_str()),
                "<{}> has an unexpected attribute {key}",
                e.name
            );
        }
        e.attrs.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
    }

    pub(crate) fn f64_of(text: &str) -> f64 {
        text.parse().unwrap_or_else(|err| panic!("{text:?} is not a double: {err}"))
    }

    #[test]
    fn committed_file_is_fresh() {
        let expected = generate().expect("the tables follow the FMI rules");
        if committed(&FMI2) != expected {
            panic!("{}", FMI2.stale_message());
        }
    }

    #[test]
    fn reals_round_trip_exactly() {
        for x in
            [0.0, -0.0, 2.5, 1e-6, 0.0085, 10.2, std::f64::consts::PI, 1e-300, 1.7e308, 0.1 + 0.2]
        {
            let text = real(x).unwrap();
            assert!(!text.contains("inf") && text.len() <= 24, "{text}");
            assert_eq!(text.contains('e'), x.abs() < 1e-7 && x != 0.0 || x.abs() >= 1e16, "{text}");
            assert_eq!(f64_of(&text).to_bits(), x.to_bits(), "{text}");
        }
        assert!(real(f64::NAN).is_err() && real(f64::INFINITY).is_err());
    }

    #[test]
    fn header_and_capabilities() {
        let root = root();
        assert_eq!(root.name, "fmiModelDescription");
        let a = attrs(
            &root,
            &[
                "fmiVersion",
                "modelName",
                "guid",
                "description",
                "version",
                "generationTool",
                "variableNamingConvention",
                "numberOfEventIndicators",
            ],
        );
        assert_eq!(a["fmiVersion"], "2.0");
        assert_eq!(a["modelName"], vars::MODEL_NAME);
        assert_eq!(a["guid"], vars::guid());
        assert_eq!(a["description"], vars::MODEL_DESCRIPTION);
        // The library's version, as Cargo.toml's [package] section gives it.
        let manifest = std::fs::read_to_string(crate::project_root().join("Cargo.toml")).unwrap();
        let package = &manifest[manifest.find("[package]").unwrap()..];
        let line = package.lines().find(|l| l.starts_with("version = ")).unwrap();
        assert_eq!(format!("version = \"{}\"", a["version"]), line);
        assert_eq!(a["generationTool"], vars::GENERATION_TOOL);
        assert_eq!(a["variableNamingConvention"], "flat");
        assert_eq!(a["numberOfEventIndicators"], EVENT_INDICATORS.to_string());

        let names: Vec<&str> = root.children.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "ModelExchange",
                "CoSimulation",
                "UnitDefinitions",
                "TypeDefinitions",
                "LogCategories",
                "DefaultExperiment",
                "ModelVariables",
                "ModelStructure"
            ]
        );

        let me = root.child("ModelExchange").unwrap();
        assert!(me.children.is_empty());
        let a = attrs(
            me,
            &[
                "modelIdentifier",
                "needsExecutionTool",
                "completedIntegratorStepNotNeeded",
                "canBeInstantiatedOnlyOncePerProcess",
                "canNotUseMemoryManagementFunctions",
                "canGetAndSetFMUstate",
                "canSerializeFMUstate",
                "providesDirectionalDerivative",
            ],
        );
        let (c, e) = (CAPABILITIES, EXCHANGE_CAPABILITIES);
        let flag = |b: bool| if b { "true" } else { "false" };
        assert_eq!(a["modelIdentifier"], vars::MODEL_IDENTIFIER);
        assert_eq!(a["needsExecutionTool"], "false");
        assert_eq!(
            a["completedIntegratorStepNotNeeded"],
            flag(e.completed_integrator_step_not_needed)
        );
        assert_eq!(
            a["canBeInstantiatedOnlyOncePerProcess"],
            flag(c.can_be_instantiated_only_once_per_process)
        );
        assert_eq!(
            a["canNotUseMemoryManagementFunctions"],
            flag(c.can_not_use_memory_management_functions)
        );
        assert_eq!(a["canGetAndSetFMUstate"], flag(c.can_get_and_set_fmu_state));
        assert_eq!(a["canSerializeFMUstate"], flag(c.can_serialize_fmu_state));
        assert_eq!(a["providesDirectionalDerivative"], flag(e.provides_directional_derivative));

        let cs = root.child("CoSimulation").unwrap();
        assert!(cs.children.is_empty());
        let a = attrs(
            cs,
            &[
                "modelIdentifier",
                "needsExecutionTool",
                "canHandleVariableCommunicationStepSize",
                "canInterpolateInputs",
                "maxOutputDerivativeOrder",
                "canRunAsynchronuously",
                "canBeInstantiatedOnlyOncePerProcess",
                "canNotUseMemoryManagementFunctions",
                "canGetAndSetFMUstate",
                "canSerializeFMUstate",
                "providesDirectionalDerivative",
            ],
        );
        assert_eq!(a["modelIdentifier"], vars::MODEL_IDENTIFIER);
        assert_eq!(a["needsExecutionTool"], "false");
        assert_eq!(
            a["canHandleVariableCommunicationStepSize"],
            flag(c.can_handle_variable_communication_step_size)
        );
        assert_eq!(a["canInterpolateInputs"], flag(c.can_interpolate_inputs));
        match a.get("maxOutputDerivativeOrder") {
            Some(n) => assert_eq!(n.parse::<u32>().unwrap(), c.max_output_derivative_order),
            None => assert_eq!(c.max_output_derivative_order, 0),
        }
        assert_eq!(a["canRunAsynchronuously"], flag(c.can_run_asynchronuously));
        assert_eq!(
            a["canBeInstantiatedOnlyOncePerProcess"],
            flag(c.can_be_instantiated_only_once_per_process)
        );
        assert_eq!(
            a["canNotUseMemoryManagementFunctions"],
            flag(c.can_not_use_memory_management_functions)
        );
        assert_eq!(a["canGetAndSetFMUstate"], flag(c.can_get_and_set_fmu_state));
        assert_eq!(a["canSerializeFMUstate"], flag(c.can_serialize_fmu_state));
        assert_eq!(a["providesDirectionalDerivative"], flag(c.provides_directional_derivative));
    }

    #[test]
    fn units_types_categories_experiment() {
        let root = root();

        let units: Vec<&Element> = root.child("UnitDefinitions").unwrap().children.iter().collect();
        assert_eq!(units.len(), UNITS.len());
        for (e, unit) in units.iter().zip(UNITS) {
            assert_eq!(e.name, "Unit");
            assert_eq!(attrs(e, &["name"])["name"], unit.name);
            let base = e.child("BaseUnit").unwrap();
            assert_eq!(e.children.len(), 1);
            let a = attrs(base, &["kg", "m", "s", "rad"]);
            for (key, exponent) in
                [("kg", unit.kg), ("m", unit.m), ("s", unit.s), ("rad", unit.rad)]
            {
                let written = a.get(key).map(|x| x.parse::<i32>().unwrap());
                assert_eq!(written, (exponent != 0).then_some(exponent), "{} {key}", unit.name);
            }
        }

        let types = &root.child("TypeDefinitions").unwrap().children;
        assert_eq!(types.len(), ENUM_TYPES.len());
        for (e, ty) in types.iter().zip(ENUM_TYPES) {
            assert_eq!(e.name, "SimpleType");
            let a = attrs(e, &["name", "description"]);
            assert_eq!((a["name"], a["description"]), (ty.name, ty.description));
            assert_eq!(e.children.len(), 1);
            let items = &e.child("Enumeration").unwrap().children;
            assert_eq!(items.len(), ty.items.len(), "{}", ty.name);
            for (k, (item, (name, description))) in items.iter().zip(ty.items).enumerate() {
                assert_eq!(item.name, "Item");
                let a = attrs(item, &["name", "value", "description"]);
                assert_eq!(a["name"], *name);
                assert_eq!(a["value"].parse::<usize>().unwrap(), k + 1, "{}.{name}", ty.name);
                assert_eq!(a["description"], *description);
            }
        }

        let categories = &root.child("LogCategories").unwrap().children;
        assert_eq!(categories.len(), LOG_CATEGORIES.len());
        for (e, (name, description)) in categories.iter().zip(LOG_CATEGORIES) {
            assert_eq!(e.name, "Category");
            let a = attrs(e, &["name", "description"]);
            assert_eq!((a["name"], a["description"]), (*name, *description));
        }

        let ex = root.child("DefaultExperiment").unwrap();
        let a = attrs(ex, &["startTime", "stopTime", "tolerance", "stepSize"]);
        assert_eq!(f64_of(a["startTime"]), DEFAULT_EXPERIMENT.start_time);
        assert_eq!(f64_of(a["stopTime"]), DEFAULT_EXPERIMENT.stop_time);
        assert_eq!(f64_of(a["tolerance"]), DEFAULT_EXPERIMENT.tolerance);
        assert_eq!(f64_of(a["stepSize"]), DEFAULT_EXPERIMENT.step_size);
    }

    #[test]
    fn every_scalar_variable_matches_the_table() {
        let root = root();
        let elements = &root.child("ModelVariables").unwrap().children;
        assert_eq!(elements.len(), super::variables(beam_body::fmi::Version::Fmi2).count());
        for (e, v) in elements.iter().zip(super::variables(beam_body::fmi::Version::Fmi2)) {
            let at = |what: &str| format!("variable {}: {what}", v.name);
            assert_eq!(e.name, "ScalarVariable");
            let a = attrs(
                e,
                &["name", "valueReference", "description", "causality", "variability", "initial"],
            );
            assert_eq!(a["name"], v.name);
            assert_eq!(a["valueReference"].parse::<u32>().unwrap(), v.vr(), "{}", at("vr"));
            assert_eq!(a["description"], v.description, "{}", at("description"));

            let (causality, variability, initial) = match v.causality {
                Causality::Parameter => ("parameter", "fixed", Some("exact")),
                Causality::Input => ("input", "continuous", None),
                Causality::Output => ("output", "continuous", Some("calculated")),
                Causality::Local => ("local", "continuous", Some("calculated")),
                Causality::Independent => ("independent", "continuous", None),
            };
            assert_eq!(a["causality"], causality, "{}", at("causality"));
            assert_eq!(a["variability"], variability, "{}", at("variability"));
            let table_variability = match v.variability {
                Variability::Fixed => "fixed",
                Variability::Continuous => "continuous",
            };
            assert_eq!(a["variability"], table_variability, "{}", at("variability"));
            assert_eq!(a.get("initial").copied(), initial, "{}", at("initial"));

            assert_eq!(e.children.len(), 1, "{}", at("one type element"));
            let t = &e.children[0];
            match v.ty {
                Type::Real { unit, start, min, max } => {
                    assert_eq!(t.name, "Real", "{}", at("type"));
                    let a = attrs(t, &["unit", "start", "min", "max", "derivative"]);
                    // A derivative names its state by its 1-based index in FMI 2.0's list,
                    // which leaves out FMI 3.0's arrays: counted here from the file.
                    let derivative = a.get("derivative").map(|k| {
                        let row = k.parse::<usize>().unwrap() - 1;
                        let state = &elements[row];
                        let names = ["name", "valueReference", "description", "causality"];
                        let more = ["variability", "initial"];
                        let a = attrs(state, &[&names[..], &more[..]].concat());
                        a["valueReference"].parse::<u32>().unwrap()
                    });
                    assert_eq!(derivative, v.derivative_of, "{}", at("derivative"));
                    assert_eq!(a.get("unit").copied(), unit, "{}", at("unit"));
                    for (key, value) in [("start", start), ("min", min), ("max", max)] {
                        let written = a.get(key).map(|x| f64_of(x).to_bits());
                        assert_eq!(written, value.map(f64::to_bits), "{}", at(key));
                    }
                    match v.causality {
                        Causality::Output | Causality::Local | Causality::Independent => {
                            assert!(start.is_none(), "{}", at("start"))
                        }
                        _ => assert!(start.is_some(), "{}", at("start")),
                    }
                }
                Type::Integer { start, min, max } => {
                    assert_eq!(t.name, "Integer", "{}", at("type"));
                    let a = attrs(t, &["start", "min", "max"]);
                    for (key, value) in [("start", start), ("min", min), ("max", max)] {
                        assert_eq!(a[key].parse::<i32>().unwrap(), value, "{}", at(key));
                    }
                }
                Type::Enumeration { ty, start } => {
                    assert_eq!(t.name, "Enumeration", "{}", at("type"));
                    let a = attrs(t, &["declaredType", "start"]);
                    assert_eq!(a["declaredType"], ty.name, "{}", at("declaredType"));
                    assert!(ENUM_TYPES.iter().any(|d| d.name == ty.name), "{}", at("declared"));
                    let start_value = a["start"].parse::<i32>().unwrap();
                    assert_eq!(start_value, start, "{}", at("start"));
                    assert!((1..=ty.items.len() as i32).contains(&start_value), "{}", at("start"));
                }
                Type::Boolean { start } => {
                    assert_eq!(t.name, "Boolean", "{}", at("type"));
                    let a = attrs(t, &["start"]);
                    assert_eq!(a["start"], if start { "true" } else { "false" }, "{}", at("start"));
                }
            }
        }
    }

    /// `<Outputs>` lists the outputs, `<Derivatives>` the state derivatives,
    /// `<InitialUnknowns>` both and the states (every variable with initial = calculated),
    /// each in index order, as FMI 2.0 §2.2.8 requires.
    #[test]
    fn model_structure_lists_outputs_derivatives_and_initial_unknowns() {
        let root = root();
        let rows = |keep: &dyn Fn(&vars::Variable) -> bool| -> Vec<usize> {
            super::variables(beam_body::fmi::Version::Fmi2)
                .enumerate()
                .filter(|(_, v)| keep(v))
                .map(|(r, _)| r + 1)
                .collect()
        };
        let outputs = rows(&|v| v.causality == Causality::Output);
        let derivatives = rows(&|v| v.derivative_of.is_some());
        // The states too: the filter of φ's phi_filtered is a calculated local (the others
        // are outputs or derivatives).
        let is_state = |v: &vars::Variable| {
            super::variables(beam_body::fmi::Version::Fmi2).any(|d| d.derivative_of == Some(v.vr()))
        };
        let unknowns =
            rows(&|v| v.causality == Causality::Output || v.derivative_of.is_some() || is_state(v));
        assert_eq!(derivatives.len(), vars::DERIVATIVES.len());
        let structure = root.child("ModelStructure").unwrap();
        let names: Vec<&str> = structure.children.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["Outputs", "Derivatives", "InitialUnknowns"]);
        for (list, expected) in
            [("Outputs", outputs), ("Derivatives", derivatives), ("InitialUnknowns", unknowns)]
        {
            let indices: Vec<usize> = structure
                .child(list)
                .unwrap()
                .children
                .iter()
                .map(|u| {
                    assert_eq!(u.name, "Unknown");
                    attrs(u, &["index"])["index"].parse().unwrap()
                })
                .collect();
            assert_eq!(indices, expected, "{list}");
        }
    }
}
