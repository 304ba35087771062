"""The FMI 3.0 archive, BeamBody-fmi3.fmu: FMPy's validation, its modelDescription.xml against the committed
one and against the FMI 2.0 archive's, its binaries in FMI 3.0's platform-tuple folders.

The FMI 2.0 archive's own validation is test_fmu_interface.py's. FMPy 0.3.32 reads neither a variable's
intermediateUpdate nor FMI 3.0's providesDirectionalDerivatives (it knows FMI 2.0's singular spelling only),
so those are read from the XML itself.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile

import fmpy.validation
import pytest

from fmu_util import MODEL_DESCRIPTION3_XML

#: FMI 3.0's platform tuples of the desktop platforms (the folders under binaries/).
TUPLES = {"x86_64-linux", "x86_64-windows", "x86_64-darwin", "aarch64-darwin", "aarch64-linux"}
#: The continuous states, in the order of fmi3GetContinuousStates: the arrays q and dq, of n_elements rows of
#: two (FMI 2.0's are the scalars v1, theta1, dv1, dtheta1). Then the event indicators.
STATES = ["q", "dq", "phi_filtered", "dphi_filtered"]
#: FMI 3.0's own variables (arrays sized by n_elements), and FMI 2.0's (its scalar state derivatives).
ONLY3 = ["nodal_v", "nodal_theta", "q", "dq", "ddq"]
ONLY2 = ["der(v1)", "der(theta1)", "der(dv1)", "der(dtheta1)"]
INDICATORS = ["range_margin_v1", "range_margin_theta1"]
#: FMI 2.0's element of each type, in FMI 3.0.
TYPES = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Enumeration", "Boolean": "Boolean"}


@pytest.fixture(scope="module")
def xml3(fmu3_file) -> ET.Element:
    """The root of the archive's modelDescription.xml, as the standard library reads it."""
    with zipfile.ZipFile(fmu3_file) as z:
        return ET.fromstring(z.read("modelDescription.xml"))


def test_validate_fmu3_reports_no_problem(fmu3_file, fmu_report):
    """FMPy's validate_fmu on an FMI 3.0 archive: the fmi3 XSD, names, start values, causality/variability/
    initial, units, the model structure, one independent variable, unique value references."""
    problems = fmpy.validation.validate_fmu(str(fmu3_file))
    fmu_report.figure("interface", "validate_fmu3_problems", len(problems))
    assert problems == [], "fmpy.validation.validate_fmu found problems:\n" + "\n".join(problems)


def test_archive_holds_the_committed_description_and_fmi3_folders(fmu3_file, fmu_file):
    assert MODEL_DESCRIPTION3_XML.is_file(), f"{MODEL_DESCRIPTION3_XML} is missing: run `cargo xtask gen`"
    with zipfile.ZipFile(fmu3_file) as z3, zipfile.ZipFile(fmu_file) as z2:
        names = z3.namelist()
        assert z3.read("modelDescription.xml") == MODEL_DESCRIPTION3_XML.read_bytes(), (
            "the FMI 3.0 FMU's modelDescription.xml differs from modelDescription/fmi3/modelDescription.xml: "
            "rebuild the FMU (`cargo xtask fmu`) or regenerate the file (`cargo xtask gen`)"
        )
        # The same documentation and, for this machine, the same library as the FMI 2.0 archive.
        assert z3.read("documentation/index.html") == z2.read("documentation/index.html")
        assert "binaries/x86_64-linux/BeamBody.so" in names, names
        assert z3.read("binaries/x86_64-linux/BeamBody.so") == z2.read("binaries/linux64/BeamBody.so")
    libraries = [n for n in names if n.startswith("binaries/") and not n.endswith("/")]
    folders = {n.split("/")[1] for n in libraries}
    assert folders <= TUPLES, f"binaries/ folders that are not FMI 3.0 platform tuples: {folders - TUPLES}"
    for name in libraries:
        folder, file = name.split("/")[1:]
        extension = {"windows": "dll", "darwin": "dylib", "linux": "so"}[folder.split("-")[1]]
        assert file == f"BeamBody.{extension}", name


def test_header_and_interfaces(md3, xml3, fmu_model_description):
    assert md3.fmiVersion == "3.0"
    assert md3.instantiationToken == fmu_model_description.guid, "the FMI 2.0 archive's guid"
    assert md3.modelName == fmu_model_description.modelName == "BeamBody"
    me, cs = md3.modelExchange, md3.coSimulation
    assert me is not None and me.modelIdentifier == "BeamBody", "Model Exchange beside co-simulation"
    assert cs is not None and cs.modelIdentifier == "BeamBody"
    assert me.needsCompletedIntegratorStep is True and me.providesEvaluateDiscreteStates is False
    for interface in (me, cs):
        assert interface.canGetAndSetFMUstate is True and interface.canSerializeFMUstate is True
    assert cs.canHandleVariableCommunicationStepSize is True
    assert cs.maxOutputDerivativeOrder == 2
    assert cs.providesIntermediateUpdate is True
    assert cs.recommendedIntermediateInputSmoothness == 2
    assert cs.hasEventMode is False and cs.canReturnEarlyAfterIntermediateUpdate is False
    # FMI 3.0's spelling, which FMPy does not read.
    assert xml3.find("ModelExchange").get("providesDirectionalDerivatives") == "true"
    assert xml3.find("CoSimulation").get("providesDirectionalDerivatives") == "false"
    # FMI 2.0's attributes that FMI 3.0 dropped are not written.
    for interface in ("ModelExchange", "CoSimulation"):
        attributes = set(xml3.find(interface).attrib)
        dropped = {"canInterpolateInputs", "canRunAsynchronuously", "canNotUseMemoryManagementFunctions",
                   "canGetAndSetFMUstate", "canSerializeFMUstate", "providesDirectionalDerivative",
                   "completedIntegratorStepNotNeeded"}
        assert not attributes & dropped, f"{interface}: {attributes & dropped}"


def test_time_is_the_independent_variable(md3):
    independent = [v for v in md3.modelVariables if v.causality == "independent"]
    assert [v.name for v in independent] == ["time"]
    time = independent[0]
    assert time.type == "Float64" and time.variability == "continuous"
    # The unit through the declared type of its name (rust-fmi refuses `unit` on a variable).
    assert time.start is None and time.initial is None and time.unit is None
    assert time.declaredType.name == "s" and time.declaredType.unit == "s"


def test_phi_and_the_outputs_are_marked_intermediate_update(xml3):
    """phi, the one input a host may set inside a step, and every output, which it may read there
    (issue 43: fmusim's --intermediate-update lists every output it records, and FMI 3.0 lets a host
    list only variables so marked). Nothing else: no parameter, no other input, no local."""
    variables = list(xml3.find("ModelVariables"))
    marked = [v.get("name") for v in variables if v.get("intermediateUpdate") == "true"]
    inputs = [v.get("name") for v in variables if v.get("causality") == "input"]
    outputs = [v.get("name") for v in variables if v.get("causality") == "output"]
    assert "phi" in inputs and len(inputs) > 1 and len(outputs) >= 14, (inputs, outputs)
    assert marked == ["phi"] + outputs, sorted(set(marked) ^ set(["phi"] + outputs))
    phi = next(v for v in variables if v.get("name") == "phi")
    assert phi.tag == "Float64" and phi.get("causality") == "input"


def test_states_and_event_indicators(md3):
    # At the start value n_elements = 1: two arrays of one row of two, then the two scalar states of
    # the filter of phi.
    assert md3.numberOfContinuousStates == 6
    assert [d.variable.derivative.name for d in md3.derivatives] == STATES
    assert [d.variable.name for d in md3.derivatives] == ["dq", "ddq", "dphi_filtered", "ddphi_filtered"]
    n_elements = next(v for v in md3.modelVariables if v.name == "n_elements")
    for d in md3.derivatives[2:]:
        assert d.variable.dimensions == [] and d.variable.derivative.dimensions == [], d.variable.name
    for d in md3.derivatives[:2]:
        for v in (d.variable, d.variable.derivative):
            assert [dim.variable for dim in v.dimensions[:1]] == [n_elements], v.name
            assert v.shape == (1, 2), v.name
    # The states are initial unknowns (calculated locals), as their derivatives are.
    unknowns = {u.variable.name for u in md3.initialUnknowns}
    assert {"q", "dq", "ddq"} <= unknowns
    # FMI 3.0: `derivative` is the state's value reference.
    for d in md3.derivatives:
        assert d.variable.derivative.valueReference in {v.valueReference for v in md3.modelVariables}
    assert md3.numberOfEventIndicators == 2
    assert [e.variable.name for e in md3.eventIndicators] == INDICATORS
    indicators = {e.variable.name for e in md3.eventIndicators}
    assert not indicators & {u.variable.name for u in md3.initialUnknowns}, "indicators are no initial unknowns"
    outputs = [v.name for v in md3.modelVariables if v.causality == "output"]
    assert [o.variable.name for o in md3.outputs] == outputs


def test_n_elements_is_a_structural_parameter_sizing_the_arrays(md3, xml3):
    """n_elements is a UInt64 structural parameter (a <Dimension> refers to one, FMI 3.0 §2.4.7.4), fixed, with
    FMI 2.0's start and range; the nodal shape has one value per node, q, dq and ddq a row of two per node."""
    by_name = {v.name: v for v in md3.modelVariables}
    n = by_name["n_elements"]
    assert (n.type, n.causality, n.variability) == ("UInt64", "structuralParameter", "fixed")
    # FMPy 0.3.32 reads no range of a UInt64: from the XML.
    element = next(v for v in xml3.find("ModelVariables") if v.get("name") == "n_elements")
    assert (element.get("start"), element.get("min"), element.get("max")) == ("1", "1", "32")
    arrays = [v.name for v in md3.modelVariables if v.dimensions]
    assert arrays == ONLY3
    for name in ONLY3:
        v = by_name[name]
        assert v.type == "Float64" and v.dimensions[0].variable is n, name
        assert v.shape == ((1,) if name.startswith("nodal") else (1, 2)), name
    assert [by_name[x].causality for x in ONLY3] == ["output", "output", "local", "local", "local"]
    assert by_name["nodal_v"].declaredType.unit == "m" and by_name["nodal_theta"].declaredType.unit == "rad"


def test_every_variable_is_the_fmi2_one(md3, fmu_model_description):
    """The variables both archives have, in the same order, with the same value references, causality,
    variability, initial, start, unit and range; each in FMI 3.0's element of its type. FMI 3.0 has its arrays
    besides, and FMI 2.0 its scalar state derivatives; n_elements is FMI 3.0's structural parameter."""
    v2s = [v for v in fmu_model_description.modelVariables if v.name not in ONLY2]
    v3s = [v for v in md3.modelVariables if v.name not in ONLY3]
    assert [v.name for v in fmu_model_description.modelVariables if v.name in ONLY2] == ONLY2
    assert [v.name for v in md3.modelVariables if v.name in ONLY3] == ONLY3
    assert [v.name for v in v3s] == [v.name for v in v2s]
    for v2, v3 in zip(v2s, v3s):
        if v2.name == "n_elements":
            assert (v3.type, v3.causality, v3.start) == ("UInt64", "structuralParameter", v2.start)
            continue
        assert v3.type == TYPES[v2.type], v2.name
        # `initial` as FMPy reads it: written, or its default (exact, for the inputs, in both versions).
        for attribute in ("valueReference", "description", "causality", "variability", "initial", "start",
                          "min", "max"):
            assert getattr(v3, attribute) == getattr(v2, attribute), f"{v2.name}.{attribute}"
        if v2.declaredType is not None:
            assert v3.declaredType.name == v2.declaredType.name, v2.name
        elif v2.type == "Real":
            # FMI 3.0: the unit by the declared type named after it.
            unit3 = v3.declaredType.unit if v3.declaredType is not None else None
            assert unit3 == v2.unit, v2.name
        state2 = v2.derivative.name if v2.derivative is not None else None
        state3 = v3.derivative.name if v3.derivative is not None else None
        assert state3 == state2, v2.name
