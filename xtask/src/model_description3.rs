//! FMI 3.0's `modelDescription/fmi3/modelDescription.xml`, from the same interface tables as
//! FMI 2.0's ([`crate::model_description`], whose writer and helpers it uses; `cargo xtask gen`
//! writes both, `cargo xtask fmu` refuses either stale).
//!
//! What FMI 3.0 changes, as `fmi3ModelDescription.xsd` and the standard (§2.4) have it:
//!
//! - `instantiationToken` instead of `guid` (the same GUID); no `numberOfEventIndicators`
//!   (the `<EventIndicator>` elements count them);
//! - the capability flags: `canGetAndSetFMUState`, `canSerializeFMUState` (capital S),
//!   `providesDirectionalDerivatives` (plural); `needsCompletedIntegratorStep` (the negation of
//!   FMI 2.0's `completedIntegratorStepNotNeeded`); co-simulation's intermediate update,
//!   event mode and input smoothness; no `canInterpolateInputs`, `canRunAsynchronuously` or
//!   `canNotUseMemoryManagementFunctions`;
//! - `<EnumerationType>` instead of `<SimpleType><Enumeration>`;
//! - each variable is one element of its type (`<Float64>`, `<Int32>`, `<Enumeration>`,
//!   `<Boolean>`); an enumeration is read and written through fmi3GetInt64/fmi3SetInt64;
//! - `derivative` names the state by its value reference, not its 1-based index;
//! - exactly one variable is `independent` (time);
//! - `<ModelStructure>` lists value references in flat elements: `<Output>`,
//!   `<ContinuousStateDerivative>` (in the order of the continuous states), `<InitialUnknown>`
//!   (the outputs and the state derivatives; never the event indicators) and
//!   `<EventIndicator>` (in the order of fmi3GetEventIndicators).

use beam_body::fmi::Version;
use beam_body::fmu::variables::{
    self as vars, Causality, Dim, Type, Var, Variability, Variable, CAPABILITIES, DERIVATIVES3,
    ENUM_TYPES, EXCHANGE_CAPABILITIES, FMI3_CAPABILITIES, INDICATOR_VARIABLES, INTERMEDIATE_INPUTS,
    UNITS,
};
use vars::intermediate_update;

use crate::model_description::{
    boolean, check_rules, enumeration_attrs, header, initial, integer_attrs, is_initial_unknown,
    real_attrs, variable_attrs, variables, write_categories_and_experiment, write_items,
    write_units, Attrs, Doc,
};
use crate::Result;

/// The committed file, relative to the project root.
pub const RELATIVE_PATH: &str = "modelDescription/fmi3/modelDescription.xml";

/// The value references of `vars`.
fn vrs(vars: &[Var]) -> Vec<u32> {
    vars.iter().map(|v| v.vr()).collect()
}

/// The value references of the outputs, for `<Output>`, in value-reference order.
pub fn output_vrs() -> Vec<u32> {
    variables(Version::Fmi3)
        .filter(|v| v.causality == Causality::Output)
        .map(Variable::vr)
        .collect()
}

/// The value references of the state derivatives, for `<ContinuousStateDerivative>`: the
/// order of the continuous states ([`DERIVATIVES3`]: the arrays dq and ddq).
pub fn derivative_vrs() -> Vec<u32> {
    vrs(&DERIVATIVES3)
}

/// The value references of the initial unknowns, for `<InitialUnknown>`: the outputs and the
/// state derivatives, in value-reference order.
pub fn initial_unknown_vrs() -> Vec<u32> {
    variables(Version::Fmi3).filter(|v| is_initial_unknown(v)).map(Variable::vr).collect()
}

/// The value references of the event indicators, for `<EventIndicator>`, in the order of
/// fmi3GetEventIndicators ([`INDICATOR_VARIABLES`]).
pub fn event_indicator_vrs() -> Vec<u32> {
    vrs(&INDICATOR_VARIABLES)
}

/// The rules FMI 3.0 adds to FMI 2.0's ([`check_rules`]), over the whole table.
fn check_rules3() -> Result {
    let independent: Vec<&str> = variables(Version::Fmi3)
        .filter(|v| v.causality == Causality::Independent)
        .map(|v| v.name)
        .collect();
    if independent.len() != 1 {
        return Err(format!(
            "FMI 3.0 needs exactly one independent variable; the table has {independent:?}"
        )
        .into());
    }
    for var in INTERMEDIATE_INPUTS {
        let v = var.info();
        if v.causality != Causality::Input {
            return Err(format!(
                "variable `{}`: only inputs are listed for intermediate update (a parameter must \
                 not be)",
                v.name
            )
            .into());
        }
    }
    for var in INDICATOR_VARIABLES {
        let v = var.info();
        let continuous_real =
            matches!(v.ty, Type::Real { .. }) && v.variability == Variability::Continuous;
        if !continuous_real || !matches!(v.causality, Causality::Local | Causality::Output) {
            return Err(format!(
                "variable `{}`: an event indicator is a continuous Float64, local or output",
                v.name
            )
            .into());
        }
    }
    // Model Exchange lists every state derivative, and only those.
    let with_derivative: Vec<u32> =
        variables(Version::Fmi3).filter(|v| v.derivative_of.is_some()).map(Variable::vr).collect();
    let mut listed = derivative_vrs();
    listed.sort_unstable();
    if listed != with_derivative {
        return Err(format!(
            "the state derivatives {:?} are not the variables with a `derivative` {:?}",
            derivative_vrs(),
            with_derivative
        )
        .into());
    }
    Ok(())
}

/// The whole FMI 3.0 modelDescription.xml.
pub fn generate() -> Result<String> {
    for v in variables(Version::Fmi3) {
        check_rules(v)?;
    }
    check_rules3()?;
    let mut doc = Doc::new();
    doc.start("fmiModelDescription", header("3.0", "instantiationToken"));

    let me = EXCHANGE_CAPABILITIES;
    let mut attrs = interface_flags(me.provides_directional_derivative);
    attrs.extend([
        ("needsCompletedIntegratorStep", boolean(!me.completed_integrator_step_not_needed)),
        ("providesEvaluateDiscreteStates", boolean(false)),
    ]);
    doc.empty("ModelExchange", attrs);

    let (caps, caps3) = (CAPABILITIES, FMI3_CAPABILITIES);
    let mut attrs = interface_flags(caps.provides_directional_derivative);
    attrs.push((
        "canHandleVariableCommunicationStepSize",
        boolean(caps.can_handle_variable_communication_step_size),
    ));
    if caps.max_output_derivative_order > 0 {
        attrs.push(("maxOutputDerivativeOrder", caps.max_output_derivative_order.to_string()));
    }
    attrs.extend([
        (
            "recommendedIntermediateInputSmoothness",
            caps3.recommended_intermediate_input_smoothness.to_string(),
        ),
        ("providesIntermediateUpdate", boolean(caps3.provides_intermediate_update)),
        (
            "canReturnEarlyAfterIntermediateUpdate",
            boolean(caps3.can_return_early_after_intermediate_update),
        ),
        ("hasEventMode", boolean(caps3.has_event_mode)),
    ]);
    doc.empty("CoSimulation", attrs);

    write_units(&mut doc);

    doc.start("TypeDefinitions", vec![]);
    // A variable's unit comes with its declared type, one per unit, named after it (rust-fmi
    // 0.8, fmi-sim among its users, refuses `unit` on a <Float64> variable, which FMI 3.0 allows).
    for unit in UNITS {
        doc.empty("Float64Type", vec![("name", unit.name.into()), ("unit", unit.name.into())]);
    }
    for ty in ENUM_TYPES {
        doc.start(
            "EnumerationType",
            vec![("name", ty.name.into()), ("description", ty.description.into())],
        );
        write_items(&mut doc, ty);
        doc.end("EnumerationType");
    }
    doc.end("TypeDefinitions");

    write_categories_and_experiment(&mut doc)?;

    doc.start("ModelVariables", vec![]);
    for v in variables(Version::Fmi3) {
        write_variable(&mut doc, v)?;
    }
    doc.end("ModelVariables");

    doc.start("ModelStructure", vec![]);
    for (element, vrs) in [
        ("Output", output_vrs()),
        ("ContinuousStateDerivative", derivative_vrs()),
        ("InitialUnknown", initial_unknown_vrs()),
        ("EventIndicator", event_indicator_vrs()),
    ] {
        for vr in vrs {
            doc.empty(element, vec![("valueReference", vr.to_string())]);
        }
    }
    doc.end("ModelStructure");

    doc.end("fmiModelDescription");
    Ok(doc.finish())
}

/// The attributes `<ModelExchange>` and `<CoSimulation>` share, first: the identifier, the
/// instantiation and FMU-state flags (the same for both), and each one's
/// `providesDirectionalDerivatives`.
fn interface_flags(provides_directional_derivatives: bool) -> Attrs {
    let caps = CAPABILITIES;
    vec![
        ("modelIdentifier", vars::MODEL_IDENTIFIER.into()),
        ("needsExecutionTool", boolean(false)),
        (
            "canBeInstantiatedOnlyOncePerProcess",
            boolean(caps.can_be_instantiated_only_once_per_process),
        ),
        ("canGetAndSetFMUState", boolean(caps.can_get_and_set_fmu_state)),
        ("canSerializeFMUState", boolean(caps.can_serialize_fmu_state)),
        ("providesDirectionalDerivatives", boolean(provides_directional_derivatives)),
    ]
}

fn write_variable(doc: &mut Doc, v: &Variable) -> Result {
    let mut attrs = variable_attrs(v);
    if v.structural {
        // FMI 3.0 §2.4.7.4: a structural parameter, which a <Dimension> refers to.
        for (key, value) in attrs.iter_mut() {
            if *key == "causality" {
                *value = "structuralParameter".into();
            }
        }
    }
    if intermediate_update(v) {
        attrs.push(("intermediateUpdate", boolean(true)));
    }
    if let Some(initial) = initial(v.causality) {
        attrs.push(("initial", initial.into()));
    }
    let element = match v.ty {
        Type::Real { unit, start, min, max } => {
            if let Some(unit) = unit {
                attrs.push(("declaredType", unit.into()));
            }
            attrs.extend(real_attrs(None, start, min, max)?);
            if let Some(state) = v.derivative_of {
                // FMI 3.0 names the state by its value reference.
                attrs.push(("derivative", state.to_string()));
            }
            "Float64"
        }
        Type::Integer { start, min, max } if v.structural => {
            // A <Dimension> refers to a UInt64 (FMI 3.0 §2.4.7.4).
            attrs.extend(integer_attrs(start, min.max(0), max));
            "UInt64"
        }
        Type::Integer { start, min, max } => {
            attrs.extend(integer_attrs(start, min, max));
            "Int32"
        }
        Type::Enumeration { ty, start } => {
            attrs.extend(enumeration_attrs(ty, start));
            "Enumeration"
        }
        Type::Boolean { start } => {
            attrs.push(("start", boolean(start)));
            "Boolean"
        }
    };
    if v.dims.is_empty() {
        doc.empty(element, attrs);
        return Ok(());
    }
    doc.start(element, attrs);
    for d in v.dims {
        let attr = match *d {
            Dim::Param(vr) => ("valueReference", vr.to_string()),
            Dim::Fixed(k) => ("start", k.to_string()),
        };
        doc.empty("Dimension", vec![attr]);
    }
    doc.end(element);
    Ok(())
}

#[cfg(test)]
mod tests {
    //! The committed FMI 3.0 file against the tables, read back with the same reader as the
    //! FMI 2.0 one and compared with the tables directly, not with the generator's code.

    use beam_body::fmu::variables::{
        self as vars, Causality, Dim, Only, Type, Var, Variability, CAPABILITIES, DERIVATIVES3,
        ENUM_TYPES, EVENT_INDICATORS, EXCHANGE_CAPABILITIES, FMI3_CAPABILITIES,
        INDICATOR_VARIABLES, INTERMEDIATE_INPUTS, UNITS, VARIABLES,
    };

    use super::generate;
    use crate::descriptions::{FMI2, FMI3};
    use crate::model_description::tests::{attrs, committed, f64_of, root_of};
    use crate::xml::Element;

    fn root() -> Element {
        root_of(&FMI3)
    }

    fn flag(b: bool) -> &'static str {
        if b {
            "true"
        } else {
            "false"
        }
    }

    #[test]
    fn committed_file_is_fresh() {
        let expected = generate().expect("the tables follow the FMI 3.0 rules");
        if committed(&FMI3) != expected {
            panic!("{}", FMI3.stale_message());
        }
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
                "instantiationToken",
                "description",
                "version",
                "generationTool",
                "variableNamingConvention",
            ],
        );
        assert_eq!(a["fmiVersion"], "3.0");
        assert_eq!(a["modelName"], vars::MODEL_NAME);
        // The same GUID as FMI 2.0's, which the FMI 2.0 tests check against the tables.
        assert_eq!(a["instantiationToken"], vars::guid());
        assert_eq!(Some(a["instantiationToken"]), root_of(&FMI2).attr("guid"));
        assert_eq!(a["description"], vars::MODEL_DESCRIPTION);
        assert_eq!(Some(a["version"]), root_of(&FMI2).attr("version"));
        assert_eq!(a["generationTool"], vars::GENERATION_TOOL);
        assert_eq!(a["variableNamingConvention"], "flat");

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

        let (c, e, f) = (CAPABILITIES, EXCHANGE_CAPABILITIES, FMI3_CAPABILITIES);
        // The attributes both interfaces have, with the FMI 3.0 spellings.
        let common = |a: &std::collections::HashMap<&str, &str>| {
            assert_eq!(a["modelIdentifier"], vars::MODEL_IDENTIFIER);
            assert_eq!(a["needsExecutionTool"], "false");
            assert_eq!(
                a["canBeInstantiatedOnlyOncePerProcess"],
                flag(c.can_be_instantiated_only_once_per_process)
            );
            assert_eq!(a["canGetAndSetFMUState"], flag(c.can_get_and_set_fmu_state));
            assert_eq!(a["canSerializeFMUState"], flag(c.can_serialize_fmu_state));
        };
        const COMMON: [&str; 6] = [
            "modelIdentifier",
            "needsExecutionTool",
            "canBeInstantiatedOnlyOncePerProcess",
            "canGetAndSetFMUState",
            "canSerializeFMUState",
            "providesDirectionalDerivatives",
        ];

        let me = root.child("ModelExchange").unwrap();
        assert!(me.children.is_empty());
        let allowed: Vec<&str> = COMMON
            .into_iter()
            .chain(["needsCompletedIntegratorStep", "providesEvaluateDiscreteStates"])
            .collect();
        let a = attrs(me, &allowed);
        common(&a);
        assert_eq!(a["providesDirectionalDerivatives"], flag(e.provides_directional_derivative));
        assert_eq!(
            a["needsCompletedIntegratorStep"],
            flag(!e.completed_integrator_step_not_needed)
        );
        assert_eq!(a["providesEvaluateDiscreteStates"], "false");

        let cs = root.child("CoSimulation").unwrap();
        assert!(cs.children.is_empty());
        let allowed: Vec<&str> = COMMON
            .into_iter()
            .chain([
                "canHandleVariableCommunicationStepSize",
                "maxOutputDerivativeOrder",
                "recommendedIntermediateInputSmoothness",
                "providesIntermediateUpdate",
                "canReturnEarlyAfterIntermediateUpdate",
                "hasEventMode",
            ])
            .collect();
        let a = attrs(cs, &allowed);
        common(&a);
        assert_eq!(a["providesDirectionalDerivatives"], flag(c.provides_directional_derivative));
        assert_eq!(
            a["canHandleVariableCommunicationStepSize"],
            flag(c.can_handle_variable_communication_step_size)
        );
        match a.get("maxOutputDerivativeOrder") {
            Some(n) => assert_eq!(n.parse::<u32>().unwrap(), c.max_output_derivative_order),
            None => assert_eq!(c.max_output_derivative_order, 0),
        }
        assert_eq!(
            a["recommendedIntermediateInputSmoothness"].parse::<u32>().unwrap(),
            f.recommended_intermediate_input_smoothness
        );
        assert_eq!(a["providesIntermediateUpdate"], flag(f.provides_intermediate_update));
        assert_eq!(
            a["canReturnEarlyAfterIntermediateUpdate"],
            flag(f.can_return_early_after_intermediate_update)
        );
        assert_eq!(a["hasEventMode"], flag(f.has_event_mode));
    }

    /// Units, log categories and the default experiment are FMI 2.0's, element for element
    /// (the FMI 2.0 tests check those against the tables); the enumeration types are the
    /// tables'.
    #[test]
    fn units_types_categories_experiment() {
        let (root, root2) = (root(), root_of(&FMI2));
        for name in ["UnitDefinitions", "LogCategories", "DefaultExperiment"] {
            assert_eq!(root.child(name).unwrap(), root2.child(name).unwrap(), "{name}");
        }

        let types = &root.child("TypeDefinitions").unwrap().children;
        assert_eq!(types.len(), UNITS.len() + ENUM_TYPES.len());
        let (floats, types) = types.split_at(UNITS.len());
        for (e, unit) in floats.iter().zip(UNITS) {
            assert_eq!(e.name, "Float64Type");
            let a = attrs(e, &["name", "unit"]);
            assert_eq!((a["name"], a["unit"]), (unit.name, unit.name));
        }
        for (e, ty) in types.iter().zip(ENUM_TYPES) {
            assert_eq!(e.name, "EnumerationType");
            let a = attrs(e, &["name", "description"]);
            assert_eq!((a["name"], a["description"]), (ty.name, ty.description));
            assert_eq!(e.children.len(), ty.items.len(), "{}", ty.name);
            for (k, (item, (name, description))) in e.children.iter().zip(ty.items).enumerate() {
                assert_eq!(item.name, "Item");
                let a = attrs(item, &["name", "value", "description"]);
                assert_eq!(a["name"], *name);
                assert_eq!(a["value"].parse::<usize>().unwrap(), k + 1, "{}.{name}", ty.name);
                assert_eq!(a["description"], *description);
            }
        }
    }

    #[test]
    fn every_variable_matches_the_table() {
        let root = root();
        let elements = &root.child("ModelVariables").unwrap().children;
        let table: Vec<_> = VARIABLES.iter().filter(|v| v.only != Only::Fmi2).collect();
        assert_eq!(elements.len(), table.len());
        for (e, v) in elements.iter().zip(table) {
            let at = |what: &str| format!("variable {}: {what}", v.name);
            // An array's <Dimension>s, outermost first: a structural parameter's value
            // reference, or a fixed size.
            let dims: Vec<Dim> = e
                .children
                .iter()
                .map(|d| {
                    assert_eq!(d.name, "Dimension", "{}", at("child"));
                    let a = attrs(d, &["valueReference", "start"]);
                    match (a.get("valueReference"), a.get("start")) {
                        (Some(vr), None) => Dim::Param(vr.parse().unwrap()),
                        (None, Some(k)) => Dim::Fixed(k.parse().unwrap()),
                        _ => panic!("{}", at("a dimension has one of its two attributes")),
                    }
                })
                .collect();
            assert_eq!(dims, v.dims, "{}", at("dimensions"));
            for d in v.dims {
                if let Dim::Param(vr) = d {
                    let sized_by = &VARIABLES[*vr as usize];
                    assert!(sized_by.structural, "{}", at("sized by a structural parameter"));
                }
            }
            const COMMON: [&str; 7] = [
                "name",
                "valueReference",
                "description",
                "causality",
                "variability",
                "intermediateUpdate",
                "initial",
            ];
            let (element, extra): (&str, &[&str]) = match v.ty {
                Type::Real { .. } => {
                    ("Float64", &["declaredType", "start", "min", "max", "derivative"])
                }
                Type::Integer { .. } if v.structural => ("UInt64", &["start", "min", "max"]),
                Type::Integer { .. } => ("Int32", &["start", "min", "max"]),
                Type::Enumeration { .. } => ("Enumeration", &["declaredType", "start"]),
                Type::Boolean { .. } => ("Boolean", &["start"]),
            };
            assert_eq!(e.name, element, "{}", at("type"));
            let allowed: Vec<&str> = COMMON.iter().chain(extra).copied().collect();
            let a = attrs(e, &allowed);

            assert_eq!(a["name"], v.name);
            assert_eq!(a["valueReference"].parse::<u32>().unwrap(), v.vr(), "{}", at("vr"));
            assert_eq!(a["description"], v.description, "{}", at("description"));
            let (causality, variability, initial) = match v.causality {
                Causality::Parameter if v.structural => {
                    ("structuralParameter", "fixed", Some("exact"))
                }
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
            // The intermediate input phi, and every output (issue 43: fmusim names them all).
            let marked = INTERMEDIATE_INPUTS.contains(&v.var) || v.causality == Causality::Output;
            let intermediate = marked.then_some("true");
            assert_eq!(a.get("intermediateUpdate").copied(), intermediate, "{}", at("update"));

            match v.ty {
                Type::Real { unit, start, min, max } => {
                    // FMI 3.0: a derivative names its state by its value reference.
                    let derivative = a.get("derivative").map(|k| k.parse::<u32>().unwrap());
                    assert_eq!(derivative, v.derivative_of, "{}", at("derivative"));
                    // The unit by the declared type of its name (see `generate`).
                    assert_eq!(a.get("declaredType").copied(), unit, "{}", at("unit"));
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
                    for (key, value) in [("start", start), ("min", min), ("max", max)] {
                        assert_eq!(a[key].parse::<i64>().unwrap(), value as i64, "{}", at(key));
                    }
                }
                Type::Enumeration { ty, start } => {
                    assert_eq!(a["declaredType"], ty.name, "{}", at("declaredType"));
                    assert!(ENUM_TYPES.iter().any(|d| d.name == ty.name), "{}", at("declared"));
                    let start_value = a["start"].parse::<i32>().unwrap();
                    assert_eq!(start_value, start, "{}", at("start"));
                    assert!((1..=ty.items.len() as i32).contains(&start_value), "{}", at("start"));
                }
                Type::Boolean { start } => {
                    assert_eq!(a["start"], flag(start), "{}", at("start"));
                }
            }
        }

        // The new variables: time, the one independent variable, and the event indicators.
        let independent: Vec<&Element> =
            elements.iter().filter(|e| e.attr("causality") == Some("independent")).collect();
        assert_eq!(independent.len(), 1);
        assert_eq!(independent[0].attr("name"), Some("time"));
        assert_eq!(independent[0].attr("start"), None);
        let phi = elements.iter().find(|e| e.attr("name") == Some("phi")).unwrap();
        assert_eq!(phi.attr("intermediateUpdate"), Some("true"));
        assert_eq!(INTERMEDIATE_INPUTS, [Var::Phi]);
    }

    /// `<Output>` lists the outputs, `<ContinuousStateDerivative>` the state derivatives in
    /// the order of the states, `<InitialUnknown>` the outputs and the derivatives (not the
    /// event indicators, FMI 3.0 §2.4.8), `<EventIndicator>` the event indicators, in the
    /// schema's order of elements; each names its variable by value reference.
    #[test]
    fn model_structure_lists_outputs_derivatives_unknowns_and_indicators() {
        let root = root();
        let vrs = |keep: &dyn Fn(&vars::Variable) -> bool| -> Vec<u32> {
            VARIABLES.iter().filter(|v| v.only != Only::Fmi2 && keep(v)).map(|v| v.vr()).collect()
        };
        let outputs = vrs(&|v| v.causality == Causality::Output);
        let derivatives = vrs(&|v| v.derivative_of.is_some());
        // The outputs, the states (q, whose derivative is dq) and the state derivatives.
        let is_state =
            |v: &vars::Variable| VARIABLES.iter().any(|d| d.derivative_of == Some(v.vr()));
        let unknowns =
            vrs(&|v| v.causality == Causality::Output || v.derivative_of.is_some() || is_state(v));
        let indicators: Vec<u32> = INDICATOR_VARIABLES.iter().map(|v| v.vr()).collect();
        assert_eq!(derivatives, DERIVATIVES3.map(Var::vr));
        assert_eq!(indicators.len(), EVENT_INDICATORS);

        let structure = root.child("ModelStructure").unwrap();
        let mut expected: Vec<(&str, u32)> = Vec::new();
        for (element, list) in [
            ("Output", &outputs),
            ("ContinuousStateDerivative", &derivatives),
            ("InitialUnknown", &unknowns),
            ("EventIndicator", &indicators),
        ] {
            expected.extend(list.iter().map(|vr| (element, *vr)));
        }
        let written: Vec<(&str, u32)> = structure
            .children
            .iter()
            .map(|u| {
                assert!(u.children.is_empty());
                (u.name.as_str(), attrs(u, &["valueReference"])["valueReference"].parse().unwrap())
            })
            .collect();
        assert_eq!(written, expected);

        // Each derivative names a state, in the order of the states: the arrays q and dq, of
        // n_elements rows of two, so that x = (q, dq) is the model's order, then the two
        // scalars of the filter of φ.
        let by_vr = |vr: u32| &VARIABLES[vr as usize];
        let states: Vec<&str> =
            derivatives.iter().map(|&d| by_vr(by_vr(d).derivative_of.unwrap()).name).collect();
        assert_eq!(states, ["q", "dq", "phi_filtered", "dphi_filtered"]);
        let n_elements = Dim::Param(Var::NElements.vr());
        for &d in &derivatives[..2] {
            assert_eq!(by_vr(d).dims, [n_elements, Dim::Fixed(2)]);
        }
        assert!(derivatives[2..].iter().all(|&d| by_vr(d).dims.is_empty()));
        let indicator_names: Vec<&str> = indicators.iter().map(|&vr| by_vr(vr).name).collect();
        assert_eq!(indicator_names, ["range_margin_v1", "range_margin_theta1"]);
        assert!(indicators.iter().all(|vr| !unknowns.contains(vr)));
    }
}
