"""The FMU's interface: FMPy's validation, the packaged modelDescription.xml, the capability flags.

Figures go to target/fmu-report.txt (fmu_report fixture).
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

import fmpy
import fmpy.validation
import pytest
from fmpy import read_model_description

from fmu_util import MODEL_DESCRIPTION_XML


def test_validate_fmu_reports_no_problem(fmu_file, fmu_report):
    problems = fmpy.validation.validate_fmu(str(fmu_file))
    fmu_report.figure("interface", "validate_fmu_problems", len(problems))
    assert problems == [], "fmpy.validation.validate_fmu found problems:\n" + "\n".join(problems)


def test_supported_platforms_are_the_desktop_ones(fmu_file, fmu_report):
    """FMPy's reading of binaries/: Linux, Windows and macOS (64-bit); the aarch64 folders are FMI 3.0
    platform tuples, which FMPy 0.3.32 does not list for Linux."""
    platforms = fmpy.supported_platforms(str(fmu_file))
    fmu_report.figure("interface", "supported_platforms", " ".join(platforms))
    assert {"linux64", "win64", "darwin64"} <= set(platforms), platforms


def test_aarch64_linux_fmu_validates(fmu_report):
    """The second archive (the aarch64 library in binaries/linux64/, where FMPy looks on Linux aarch64)
    carries the same modelDescription.xml and validates too."""
    env = os.environ.get("BEAM_BODY_FMU_AARCH64_LINUX")
    if not env:
        if os.environ.get("CI"):
            pytest.fail("$BEAM_BODY_FMU_AARCH64_LINUX is not set, and $CI is", pytrace=False)
        pytest.skip("$BEAM_BODY_FMU_AARCH64_LINUX is not set (`cargo xtask test` sets it)")
    problems = fmpy.validation.validate_fmu(env)
    assert problems == [], "fmpy.validation.validate_fmu found problems:\n" + "\n".join(problems)
    assert fmpy.supported_platforms(env) == ["linux64"]
    with zipfile.ZipFile(env) as z:
        assert z.read("modelDescription.xml") == MODEL_DESCRIPTION_XML.read_bytes()
    fmu_report.figure("interface", "aarch64_linux_fmu_bytes", Path(env).stat().st_size)


def test_packaged_model_description_is_the_committed_one(fmu_file):
    assert MODEL_DESCRIPTION_XML.is_file(), f"{MODEL_DESCRIPTION_XML} is missing: run `cargo xtask gen`"
    with zipfile.ZipFile(fmu_file) as z:
        names = z.namelist()
        assert "modelDescription.xml" in names
        assert "binaries/linux64/BeamBody.so" in names, f"no binaries/linux64/BeamBody.so in {names}"
        packaged = z.read("modelDescription.xml")
    committed = MODEL_DESCRIPTION_XML.read_bytes()
    assert packaged == committed, (
        "the FMU's modelDescription.xml differs from the committed modelDescription/modelDescription.xml: "
        "rebuild the FMU (`cargo xtask fmu`) or regenerate the file (`cargo xtask gen`)"
    )


def test_capability_flags_and_default_experiment(fmu_file):
    md = read_model_description(str(fmu_file))
    assert md.fmiVersion == "2.0"
    me = md.modelExchange
    assert me is not None and me.modelIdentifier == "BeamBody", "Model Exchange beside co-simulation"
    assert me.providesDirectionalDerivative is True and me.completedIntegratorStepNotNeeded is False
    assert md.numberOfEventIndicators == 2
    # The states are the paper's coordinates and their rates, then the two of the filter of phi; each
    # derivative names its state.
    states = [d.variable.derivative.name for d in md.derivatives]
    assert states == ["v1", "theta1", "dv1", "dtheta1", "phi_filtered", "dphi_filtered"], states
    assert [d.variable.name for d in md.derivatives[:4]] == [f"der({s})" for s in states[:4]]
    assert [d.variable.name for d in md.derivatives[4:]] == ["dphi_filtered", "ddphi_filtered"]
    cs = md.coSimulation
    assert cs is not None and cs.modelIdentifier == "BeamBody"
    flags = {
        "canHandleVariableCommunicationStepSize": True,
        "canInterpolateInputs": True,
        "canGetAndSetFMUstate": True,
        "canSerializeFMUstate": True,
        "canNotUseMemoryManagementFunctions": True,
    }
    for name, expected in flags.items():
        assert getattr(cs, name) is expected, f"<CoSimulation {name}> is {getattr(cs, name)!r}, expected {expected}"
    ex = md.defaultExperiment
    assert ex is not None
    got = tuple(float(x) for x in (ex.startTime, ex.stopTime, ex.tolerance, ex.stepSize))  # strings in FMPy
    assert got == (0.0, 10.2, 1e-6, 0.0085), f"DefaultExperiment (start, stop, tolerance, step) = {got}"
    # The variables the other tests use, with their enumerations (src/fmu/variables.rs).
    by_name = {v.name: v for v in md.modelVariables}
    assert by_name["phi"].causality == "input" and by_name["phi"].type == "Real"
    for out in ("v1", "theta1", "u2", "drift", "phi_applied", "dphi_applied", "ddphi_applied"):
        assert by_name[out].causality == "output", out
    assert [i.name for i in by_name["formulation"].declaredType.items] == ["reduced", "dae", "dae_stabilized", "linear"]
    assert [i.value for i in by_name["formulation"].declaredType.items] == ["1", "2", "3", "4"]
    assert [i.name for i in by_name["phi_source"].declaredType.items] == ["input", "law"]
    assert by_name["phi_source"].start == "1" and by_name["phi_extrapolation"].start == "3"


NUMBER_WORDS = {2: "two", 3: "three", 4: "four", 5: "five", 6: "six"}


@pytest.mark.parametrize("which", ["fmi2", "fmi3"])
def test_description_names_every_beam_and_formulation(which, fmu_file, fmu3_file):
    """Both FMUs' description and documentation say what the FMU holds (issue 43: both still read "Ritz,
    2 coordinates ... three formulations" after n elements, the exact beam and a fourth formulation
    came): n_elements, both beam theories by their values, and as many formulations as the description's
    own enumeration lists."""
    path = fmu_file if which == "fmi2" else fmu3_file
    md = read_model_description(str(path))
    text = md.description
    formulations = next(t for t in md.typeDefinitions if t.name == "Formulation").items
    beams = [i.name for i in next(t for t in md.typeDefinitions if t.name == "Beam").items]
    assert beams == ["quadratic", "exact"], beams
    assert "n_elements" in text and "beam = quadratic" in text and "beam = exact" in text, text
    assert f"{NUMBER_WORDS[len(formulations)]} formulations" in text, (len(formulations), text)
    assert "2 coordinates)" not in text.split("n_elements")[0], text
    with zipfile.ZipFile(path) as z:
        html = z.read("documentation/index.html").decode("utf-8")
    model = html.split("<h2>The model</h2>", 1)[1].split("<h2>", 1)[0]
    for needle in ("<code>n_elements</code>", "<code>exact</code>", "<code>quadratic</code>"):
        assert needle in model, f"documentation/index.html's model section lacks {needle}"
