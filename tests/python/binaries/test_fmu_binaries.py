"""Every binary in the FMU, read with tests/python/binfmt.py (the standard library only: no binutils,
no LLVM tool, nothing that has to run the binary; macOS and Windows binaries cannot run here).

The FMU holds one library per desktop platform, cross-built on Linux x86-64:

    binaries/linux64/BeamBody.so            ELF x86-64
    binaries/aarch64-linux/BeamBody.so      ELF aarch64
    binaries/win64/BeamBody.dll             PE32+ x86-64
    binaries/darwin64/BeamBody.dylib        Mach-O universal: x86_64 + arm64
    binaries/aarch64-darwin/BeamBody.dylib  Mach-O thin arm64

and a second archive, $BEAM_BODY_FMU_AARCH64_LINUX, holds the aarch64 ELF in binaries/linux64/ and
binaries/aarch64-linux/ (for hosts that look for linux64 only); any other binary in it must be
byte-identical to the main FMU's. Its checks run when the variable is set; when it is not, they
skip, and with $CI set its test_binaries_layout fails.

The FMI 3.0 archive (fmu3_file: $BEAM_BODY_FMU_FMI3, else target/fmu/BeamBody-fmi3.fmu) holds the same
libraries in FMI 3.0's platform-tuple folders:

    binaries/x86_64-linux/BeamBody.so       ELF x86-64          = the FMI 2.0 archive's linux64
    binaries/aarch64-linux/BeamBody.so      ELF aarch64         = aarch64-linux
    binaries/x86_64-windows/BeamBody.dll    PE32+ x86-64        = win64
    binaries/x86_64-darwin/BeamBody.dylib   Mach-O thin x86_64  = darwin64's x86_64 slice
    binaries/aarch64-darwin/BeamBody.dylib  Mach-O thin arm64   = aarch64-darwin

x86_64-linux always; the other four when the all-platforms build ran (`cargo xtask fmu --all-platforms`,
which `cargo xtask test` runs: the FMI 2.0 archive then holds its cross-built folders too), and then all
four (a partial set fails test_binaries_layout). When it did not, their checks skip, and with $CI set
they fail. Every binary of the FMI 3.0 archive gets the checks below, and
test_fmi3_binaries_are_the_fmi2_libraries checks that each is byte for byte the FMI 2.0 archive's library
(or, for x86_64-darwin, the x86_64 slice of its universal dylib), which the same checks cover there.

For each binary (each slice of a universal one):
- the format and machine its folder promises;
- the exports are exactly the 44 FMI 2.0 functions (25 common + 9 co-simulation + 10 Model Exchange) and the 75 FMI 3.0
  functions (61 common + 10 Model Exchange + 3 co-simulation + 1 scheduled execution), one library for both archives
  (Mach-O names carry a leading underscore), nothing more: a host resolves these by name, and anything else is a
  leak;
- no sin, cos, tan, exp, log, log2, log10, pow, atan2, hypot, fma, cbrt (or float/sincos variants,
  or msvcrt's _hypot) is imported: the library carries its own libm (src/math.rs) so that every
  platform computes the same bits, and a platform libm would silently break that;
- Windows: imports only from a short list of system DLLs; nothing from bcryptprimitives.dll
  (ProcessPrng, which wine 8 lacks) and no mingw runtime DLL (libgcc_s_seh-1.dll,
  libwinpthread-1.dll) that a user's machine would not have;
- Linux: DT_NEEDED only libc.so.6, libgcc_s.so.1 and the dynamic loader (x86-64: __tls_get_addr),
  and no symbol version above GLIBC_2.34, the documented floor (Debian 12, Ubuntu 22.04, RHEL 9,
  Amazon Linux 2023);
- macOS: minos at most 10.12 (x86_64) and 11.0 (arm64), the install name @rpath/BeamBody.dylib,
  libSystem as the only library, and a code signature whose every page hash verifies on each arm64
  slice (arm64 macOS kills a process that maps unsigned code; an ad-hoc, linker-made signature is
  enough).

Sizes, the highest GLIBC_ version, minos/sdk and the number of verified pages go to
target/fmu-report.txt (fmu_report fixture).
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import pytest

import binfmt

# --------------------------------------------------------------------------------------------------
# what the FMU must hold
# --------------------------------------------------------------------------------------------------

#: FMI 2.0 standard, section 2.1 (functions common to Model Exchange and Co-Simulation).
FMI2_COMMON_FUNCTIONS = (
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
)
#: FMI 2.0 standard, section 4.2 (Co-Simulation).
FMI2_CO_SIMULATION_FUNCTIONS = (
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
)
#: FMI 2.0 standard, section 3.2 (Model Exchange).
FMI2_MODEL_EXCHANGE_FUNCTIONS = (
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
)
FMI2_FUNCTIONS = FMI2_COMMON_FUNCTIONS + FMI2_CO_SIMULATION_FUNCTIONS + FMI2_MODEL_EXCHANGE_FUNCTIONS
assert len(FMI2_COMMON_FUNCTIONS) == 25 and len(FMI2_CO_SIMULATION_FUNCTIONS) == 9
assert len(FMI2_MODEL_EXCHANGE_FUNCTIONS) == 10
assert len(set(FMI2_FUNCTIONS)) == 44

#: FMI 3.0 standard, headers/fmi3Functions.h (FMI-Standard-3.0), in its order: "Common Functions".
FMI3_COMMON_FUNCTIONS = (
    # Inquire version numbers and set debug logging
    "fmi3GetVersion",
    "fmi3SetDebugLogging",
    # Creation and destruction of FMU instances
    "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation",
    "fmi3InstantiateScheduledExecution",
    "fmi3FreeInstance",
    # Enter and exit initialization mode, terminate and reset
    "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode",
    "fmi3EnterEventMode",
    "fmi3Terminate",
    "fmi3Reset",
    # Getting and setting variable values
    "fmi3GetFloat32",
    "fmi3GetFloat64",
    "fmi3GetInt8",
    "fmi3GetUInt8",
    "fmi3GetInt16",
    "fmi3GetUInt16",
    "fmi3GetInt32",
    "fmi3GetUInt32",
    "fmi3GetInt64",
    "fmi3GetUInt64",
    "fmi3GetBoolean",
    "fmi3GetString",
    "fmi3GetBinary",
    "fmi3GetClock",
    "fmi3SetFloat32",
    "fmi3SetFloat64",
    "fmi3SetInt8",
    "fmi3SetUInt8",
    "fmi3SetInt16",
    "fmi3SetUInt16",
    "fmi3SetInt32",
    "fmi3SetUInt32",
    "fmi3SetInt64",
    "fmi3SetUInt64",
    "fmi3SetBoolean",
    "fmi3SetString",
    "fmi3SetBinary",
    "fmi3SetClock",
    # Getting Variable Dependency Information
    "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies",
    # Getting and setting the internal FMU state
    "fmi3GetFMUState",
    "fmi3SetFMUState",
    "fmi3FreeFMUState",
    "fmi3SerializedFMUStateSize",
    "fmi3SerializeFMUState",
    "fmi3DeserializeFMUState",
    # Getting partial derivatives
    "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative",
    # Entering and exiting the Configuration or Reconfiguration Mode
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    # Clock related functions
    "fmi3GetIntervalDecimal",
    "fmi3GetIntervalFraction",
    "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction",
    "fmi3SetIntervalDecimal",
    "fmi3SetIntervalFraction",
    "fmi3SetShiftDecimal",
    "fmi3SetShiftFraction",
    "fmi3EvaluateDiscreteStates",
    "fmi3UpdateDiscreteStates",
)
#: fmi3Functions.h, "Functions for Model Exchange".
FMI3_MODEL_EXCHANGE_FUNCTIONS = (
    "fmi3EnterContinuousTimeMode",
    "fmi3CompletedIntegratorStep",
    "fmi3SetTime",
    "fmi3SetContinuousStates",
    "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators",
    "fmi3GetContinuousStates",
    "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators",
    "fmi3GetNumberOfContinuousStates",
)
#: fmi3Functions.h, "Functions for Co-Simulation" (Simulating the FMU).
FMI3_CO_SIMULATION_FUNCTIONS = (
    "fmi3EnterStepMode",
    "fmi3GetOutputDerivatives",
    "fmi3DoStep",
)
#: fmi3Functions.h, "Functions for Scheduled Execution" (the FMU returns fmi3Error: it has none).
FMI3_SCHEDULED_EXECUTION_FUNCTIONS = ("fmi3ActivateModelPartition",)
FMI3_FUNCTIONS = (FMI3_COMMON_FUNCTIONS + FMI3_MODEL_EXCHANGE_FUNCTIONS + FMI3_CO_SIMULATION_FUNCTIONS
                  + FMI3_SCHEDULED_EXECUTION_FUNCTIONS)
assert len(FMI3_COMMON_FUNCTIONS) == 61 and len(FMI3_MODEL_EXCHANGE_FUNCTIONS) == 10
assert len(FMI3_CO_SIMULATION_FUNCTIONS) == 3 and len(set(FMI3_FUNCTIONS)) == 75
#: What every library exports: one library serves both archives.
EXPORTED_FUNCTIONS = FMI2_FUNCTIONS + FMI3_FUNCTIONS

#: The C library's math functions the model must not import (it uses its own libm, src/math.rs).
MATH_FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "log2", "log10", "pow", "atan2", "hypot", "fma", "cbrt")
FORBIDDEN_MATH = frozenset(
    set(MATH_FUNCTIONS) | {f + "f" for f in MATH_FUNCTIONS} | {"sincos", "sincosf"}
)
#: msvcrt's spellings on Windows.
FORBIDDEN_MATH_WINDOWS = FORBIDDEN_MATH | {"_hypot", "_hypotf"}
#: Mach-O symbol names carry a leading underscore; Apple's libm also has __sincos_stret.
FORBIDDEN_MATH_MACHO = frozenset({"_" + f for f in FORBIDDEN_MATH} | {"___sincos_stret", "___sincosf_stret"})

#: What the DLL imports today (checked on the real build); compared case-insensitively, as Windows does.
WINDOWS_ALLOWED_DLLS = ("KERNEL32.dll", "ntdll.dll", "msvcrt.dll", "api-ms-win-core-synch-l1-2-0.dll")
WINDOWS_REFUSED_DLLS = {
    "bcryptprimitives.dll": "std's ProcessPrng: missing in wine 8 (the library must not ask the OS for random numbers)",
    "libgcc_s_seh-1.dll": "a mingw runtime DLL: not on a user's machine (link it statically)",
    "libwinpthread-1.dll": "a mingw runtime DLL: not on a user's machine (link it statically)",
}
#: What the ELF builds need today; libm.so.6 is not among them (the model has its own libm). The
#: x86-64 build also needs the dynamic loader, for __tls_get_addr (general-dynamic TLS; aarch64 uses
#: TLS descriptors and does not).
LINUX_ALLOWED_NEEDED = {
    "x86_64": ("libc.so.6", "libgcc_s.so.1", "ld-linux-x86-64.so.2"),
    "aarch64": ("libc.so.6", "libgcc_s.so.1", "ld-linux-aarch64.so.1"),
}
#: The documented glibc floor: Debian 12 (2.36), Ubuntu 22.04 (2.35), RHEL 9 (2.34), Amazon Linux 2023 (2.34).
GLIBC_FLOOR = "2.34"
MACOS_MAX_MINOS = {"x86_64": "10.12", "arm64": "11.0"}
MACOS_INSTALL_NAME = "@rpath/BeamBody.dylib"
LIBSYSTEM = "/usr/lib/libSystem.B.dylib"


@dataclass(frozen=True)
class Expect:
    kind: str  # 'elf', 'pe', 'macho'
    archs: tuple[str, ...]  # machine per file, or the slices of a Mach-O, in order
    fat: bool = False  # Mach-O universal


#: The main FMU.
LAYOUT = {
    "binaries/linux64/BeamBody.so": Expect("elf", ("x86_64",)),
    "binaries/aarch64-linux/BeamBody.so": Expect("elf", ("aarch64",)),
    "binaries/win64/BeamBody.dll": Expect("pe", ("x86_64",)),
    "binaries/darwin64/BeamBody.dylib": Expect("macho", ("x86_64", "arm64"), fat=True),
    "binaries/aarch64-darwin/BeamBody.dylib": Expect("macho", ("arm64",)),
}
#: $BEAM_BODY_FMU_AARCH64_LINUX: the aarch64 ELF in both Linux folders. Any other binary it holds must
#: be one of LAYOUT's and byte-identical to the main FMU's (so the main FMU's checks cover it).
AARCH64_LINUX_LAYOUT = {
    "binaries/linux64/BeamBody.so": Expect("elf", ("aarch64",)),
    "binaries/aarch64-linux/BeamBody.so": Expect("elf", ("aarch64",)),
}
AARCH64_LINUX_ENV = "BEAM_BODY_FMU_AARCH64_LINUX"
#: The FMI 3.0 archive: FMI 3.0's platform tuples, one architecture per folder.
FMI3_LAYOUT = {
    "binaries/x86_64-linux/BeamBody.so": Expect("elf", ("x86_64",)),
    "binaries/aarch64-linux/BeamBody.so": Expect("elf", ("aarch64",)),
    "binaries/x86_64-windows/BeamBody.dll": Expect("pe", ("x86_64",)),
    "binaries/x86_64-darwin/BeamBody.dylib": Expect("macho", ("x86_64",)),
    "binaries/aarch64-darwin/BeamBody.dylib": Expect("macho", ("arm64",)),
}
#: In every build of the FMI 3.0 archive; the others come with the all-platforms build.
FMI3_ALWAYS = "binaries/x86_64-linux/BeamBody.so"
#: The FMI 2.0 archive's library each FMI 3.0 binary is, and the slice (Mach-O universal) or None.
FMI3_SAME_AS = {
    "binaries/x86_64-linux/BeamBody.so": ("binaries/linux64/BeamBody.so", None),
    "binaries/aarch64-linux/BeamBody.so": ("binaries/aarch64-linux/BeamBody.so", None),
    "binaries/x86_64-windows/BeamBody.dll": ("binaries/win64/BeamBody.dll", None),
    "binaries/x86_64-darwin/BeamBody.dylib": ("binaries/darwin64/BeamBody.dylib", "x86_64"),
    "binaries/aarch64-darwin/BeamBody.dylib": ("binaries/aarch64-darwin/BeamBody.dylib", None),
}
ARCHIVES = {"fmu": LAYOUT, "aarch64-linux-fmu": AARCH64_LINUX_LAYOUT, "fmu3": FMI3_LAYOUT}
CASES = [(archive, member) for archive, layout in ARCHIVES.items() for member in layout]


def _cases(kind: str | None = None):
    return [
        pytest.param(a, m, id=f"{a}:{m.removeprefix('binaries/')}")
        for a, m in CASES
        if kind is None or ARCHIVES[a][m].kind == kind
    ]


# --------------------------------------------------------------------------------------------------
# loading
# --------------------------------------------------------------------------------------------------


def archive_path(request, archive: str, layout_test: bool = False) -> Path:
    """The archive's path. With $BEAM_BODY_FMU_AARCH64_LINUX unset, its checks skip, except that
    test_binaries_layout fails when $CI is set (one clear failure, not one per check)."""
    if archive == "fmu":
        return request.getfixturevalue("fmu_file")
    if archive == "fmu3":
        return request.getfixturevalue("fmu3_file")
    env = os.environ.get(AARCH64_LINUX_ENV)
    if not env:
        if os.environ.get("CI") and layout_test:
            pytest.fail(
                f"${AARCH64_LINUX_ENV} is not set, and $CI is: the aarch64-Linux FMU "
                "(the aarch64 ELF in binaries/linux64/ and binaries/aarch64-linux/) must be checked in CI",
                pytrace=False,
            )
        pytest.skip(
            f"${AARCH64_LINUX_ENV} is not set (the aarch64-Linux FMU is checked when it is"
            + ("; test_binaries_layout fails for it under $CI)" if os.environ.get("CI") else ")")
        )
    path = Path(env)
    if not path.is_file():
        pytest.fail(f"${AARCH64_LINUX_ENV} = {env}: no such file", pytrace=False)
    return path


def binaries_in(path: Path) -> set[str]:
    with zipfile.ZipFile(path) as z:
        return {n for n in z.namelist() if n.startswith("binaries/") and not n.endswith("/")}


def all_platforms_built(request) -> bool:
    """Whether the archives come from the all-platforms build: the FMI 2.0 archive or the FMI 3.0
    archive holds a cross-built folder (a host-only `cargo xtask fmu` writes this machine's only). Under
    $CI, always (the suite builds every platform there)."""
    if os.environ.get("CI"):
        return True
    main = binaries_in(request.getfixturevalue("fmu_file"))
    fmi3 = binaries_in(request.getfixturevalue("fmu3_file"))
    return bool(main - {"binaries/linux64/BeamBody.so"}) or bool(fmi3 - {FMI3_ALWAYS})


def fmi3_required(request) -> set[str]:
    """The FMI 3.0 archive's binaries this build must hold."""
    return set(FMI3_LAYOUT) if all_platforms_built(request) else {FMI3_ALWAYS}


_CACHE: dict = {}


def load(request, archive: str, member: str):
    """(label, bytes, parsed) of the member; a missing member or a FormatError fails the test (an FMI 3.0
    cross-built binary after a host-only build skips)."""
    path = archive_path(request, archive)
    key = (str(path), member)
    if key not in _CACHE:
        with zipfile.ZipFile(path) as z:
            if member not in z.namelist():
                if archive == "fmu3" and member not in fmi3_required(request):
                    pytest.skip(f"{path.name} has no {member}: a host-only build (`cargo xtask fmu`); "
                                "`cargo xtask fmu --all-platforms` builds it")
                pytest.fail(f"{path} has no {member}", pytrace=False)
            data = z.read(member)
        try:
            parsed = binfmt.parse(data)
        except binfmt.FormatError as err:
            pytest.fail(f"{path}!{member}: {err}", pytrace=False)
        _CACHE[key] = (data, parsed)
    data, parsed = _CACHE[key]
    short = member.removeprefix("binaries/")
    label = short if archive == "fmu" else f"{archive}:{short}"
    return label, data, parsed


def expected(archive: str, member: str) -> Expect:
    return ARCHIVES[archive][member]


def units(parsed):
    """(unit label, exports, imports, object) per file, or per slice of a Mach-O."""
    if parsed.format == "macho":
        return [(s.cpu_name, s.exports, list(s.imports), s) for s in parsed.slices]
    if parsed.format == "pe":
        imports = [f"{dll}!{name}" for dll, names in parsed.all_imports().items() for name in names]
        return [(parsed.machine_name, parsed.exports, imports, parsed)]
    return [(parsed.machine_name, parsed.exports, [str(s) for s in parsed.undefined], parsed)]


# --------------------------------------------------------------------------------------------------
# layout
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("archive", list(ARCHIVES))
def test_binaries_layout(request, archive, fmu_report):
    path = archive_path(request, archive, layout_test=True)
    layout = ARCHIVES[archive]
    with zipfile.ZipFile(path) as z:
        present = {n: z.read(n) for n in z.namelist() if n.startswith("binaries/") and not n.endswith("/")}
    fmu_report.note("binaries", f"{archive} {path.name}: {', '.join(sorted(present))}")
    required = fmi3_required(request) if archive == "fmu3" else set(layout)
    missing = sorted(required - set(present))
    extra = sorted(set(present) - set(layout))
    problems = []
    if missing:
        problems.append(f"missing: {missing}")
    if archive in ("fmu", "fmu3"):
        if extra:
            problems.append(f"unexpected: {extra}")
    elif extra:  # must be copies of the main FMU's, which the checks below cover
        with zipfile.ZipFile(request.getfixturevalue("fmu_file")) as z:
            main = set(z.namelist())
            for name in extra:
                if name not in LAYOUT:
                    problems.append(f"unexpected: {name}")
                elif name not in main or z.read(name) != present[name]:
                    problems.append(f"{name} differs from the main FMU's (so no check covers it)")
    assert not problems, (
        f"{path}: binaries/ does not match the layout {sorted(layout)}:\n  " + "\n  ".join(problems)
    )


# --------------------------------------------------------------------------------------------------
# every binary
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("archive,member", _cases())
def test_format_and_machine(request, archive, member, fmu_report):
    label, data, parsed = load(request, archive, member)
    want = expected(archive, member)
    fmu_report.figure("binaries", f"{label}.size_bytes", len(data))
    assert parsed.format == want.kind, f"{label}: a {parsed.format} file, expected {want.kind}"
    if parsed.format == "elf":
        assert parsed.machine_name == want.archs[0], (
            f"{label}: ELF e_machine {parsed.machine_name}, expected {want.archs[0]}"
        )
        assert parsed.e_type == binfmt.ET_DYN, f"{label}: e_type {parsed.e_type}, expected ET_DYN (shared object)"
    elif parsed.format == "pe":
        assert parsed.machine_name == want.archs[0], (
            f"{label}: PE Machine {parsed.machine:#06x}, expected {want.archs[0]}"
        )
        assert parsed.is_dll, f"{label}: IMAGE_FILE_DLL is not set (characteristics {parsed.characteristics:#06x})"
    else:
        kind = "universal" if parsed.fat else "thin"
        assert parsed.fat == want.fat, f"{label}: a {kind} Mach-O, expected {'universal' if want.fat else 'thin'}"
        assert tuple(parsed.archs) == want.archs, f"{label}: slices {parsed.archs}, expected {list(want.archs)}"
        for s in parsed.slices:
            assert s.filetype == binfmt.MH_DYLIB, f"{label} [{s.cpu_name}]: filetype {s.filetype}, expected MH_DYLIB"
            if parsed.fat:
                fmu_report.figure("binaries", f"{label}[{s.cpu_name}].size_bytes", s.size)


@pytest.mark.parametrize("archive,member", _cases())
def test_exports_are_exactly_the_fmi2_and_fmi3_functions(request, archive, member):
    label, _, parsed = load(request, archive, member)
    prefix = "_" if parsed.format == "macho" else ""
    want = {prefix + f for f in EXPORTED_FUNCTIONS}
    problems = []
    for unit, exports, _, _ in units(parsed):
        got = set(exports)
        if got != want:
            problems.append(
                f"[{unit}] {len(got)} exports; missing {sorted(want - got)}; unexpected {sorted(got - want)}"
            )
    if parsed.format == "pe" and parsed.unnamed_exports:
        problems.append(f"{parsed.unnamed_exports} export(s) by ordinal only")
    assert not problems, (
        f"{label}: the exports are not exactly the 44 FMI 2.0 and 75 FMI 3.0 functions:\n  " + "\n  ".join(problems)
    )


@pytest.mark.parametrize("member", list(FMI3_LAYOUT), ids=[m.removeprefix("binaries/") for m in FMI3_LAYOUT])
def test_fmi3_binaries_are_the_fmi2_libraries(request, member, fmu_report):
    """Each binary of the FMI 3.0 archive is byte for byte the FMI 2.0 archive's library for the same
    platform (x86_64-darwin: the x86_64 slice of darwin64's universal dylib), so that one build serves
    both versions and the FMI 2.0 archive's checks cover it too."""
    label, data, _ = load(request, "fmu3", member)
    source, arch = FMI3_SAME_AS[member]
    main = request.getfixturevalue("fmu_file")
    with zipfile.ZipFile(main) as z:
        if source not in z.namelist():
            pytest.fail(f"the FMI 3.0 archive holds {member}, the FMI 2.0 archive {main.name} no {source}: "
                        "the two come from different builds", pytrace=False)
        other = z.read(source)
    if arch is not None:
        fat = binfmt.parse(other)
        s = fat.slice(arch)
        other = other[s.offset:s.offset + s.size]
    what = source.removeprefix("binaries/") + (f" [{arch}]" if arch else "")
    fmu_report.note("binaries", f"{label} = {what}: {data == other}")
    assert data == other, f"{label} ({len(data)} bytes) differs from the FMI 2.0 archive's {what} ({len(other)} bytes)"


@pytest.mark.parametrize("archive,member", _cases())
def test_no_platform_math_import(request, archive, member):
    label, _, parsed = load(request, archive, member)
    forbidden = {"elf": FORBIDDEN_MATH, "pe": FORBIDDEN_MATH_WINDOWS, "macho": FORBIDDEN_MATH_MACHO}[parsed.format]
    found = []
    for unit, _, imports, _ in units(parsed):
        for entry in imports:
            name = entry.split("!", 1)[-1].split("@", 1)[0]
            if name in forbidden:
                found.append(f"[{unit}] {entry}")
    assert not found, (
        f"{label} imports the platform's math functions (the model must use its own libm, src/math.rs, "
        "so that every platform computes the same bits):\n  " + "\n  ".join(found)
    )


# --------------------------------------------------------------------------------------------------
# Windows
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("archive,member", _cases("pe"))
def test_windows_imports_only_system_dlls(request, archive, member, fmu_report):
    label, _, pe = load(request, archive, member)
    imports = pe.all_imports()
    allowed = {d.lower() for d in WINDOWS_ALLOWED_DLLS}
    refused = {d.lower(): why for d, why in WINDOWS_REFUSED_DLLS.items()}
    fmu_report.note("binaries", f"{label} imports: " + ", ".join(f"{d} ({len(n)})" for d, n in sorted(imports.items())))
    fmu_report.figure("binaries", f"{label}.imported_functions", sum(len(n) for n in imports.values()))
    problems = []
    for dll, names in sorted(imports.items()):
        if dll.lower() in refused:
            problems.append(f"{dll} ({', '.join(names)}): {refused[dll.lower()]}")
        elif dll.lower() not in allowed:
            problems.append(f"{dll} ({', '.join(names)}): not in the allowed list {list(WINDOWS_ALLOWED_DLLS)}")
    if pe.delay_imports:
        problems.append(f"delay-load imports: {sorted(pe.delay_imports)}")
    assert not problems, f"{label} imports from DLLs it must not need:\n  " + "\n  ".join(problems)


# --------------------------------------------------------------------------------------------------
# Linux
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("archive,member", _cases("elf"))
def test_linux_needed_and_glibc_floor(request, archive, member, fmu_report):
    label, _, elf = load(request, archive, member)
    max_glibc = elf.max_glibc()
    fmu_report.note("binaries", f"{label} DT_NEEDED: {', '.join(elf.needed)}; DT_SONAME: {elf.soname}")
    fmu_report.figure("binaries", f"{label}.max_glibc", max_glibc, f"floor GLIBC_{GLIBC_FLOOR}")
    problems = []
    allowed = LINUX_ALLOWED_NEEDED.get(elf.machine_name, ())
    unexpected = [n for n in elf.needed if n not in allowed]
    if unexpected:
        users = sorted(str(s) for s in elf.undefined if s.version_file in unexpected)
        problems.append(
            f"DT_NEEDED {unexpected} beyond the allowed {list(allowed)}"
            + (f" (versioned symbols from them: {', '.join(users)})" if users else "")
        )
    floor = binfmt.version_key(f"GLIBC_{GLIBC_FLOOR}")
    for version in elf.required_versions("GLIBC_"):
        numbered = binfmt.GLIBC_MARKERS.get(version, version)
        key = binfmt.version_key(numbered)
        if key[0] != 0:
            problems.append(f"requires {version} (not a public glibc release)")
        elif key > floor:
            users = sorted(str(s) for s in elf.undefined if s.version == version) or [version]
            problems.append(f"requires {version} > GLIBC_{GLIBC_FLOOR}: {', '.join(users)}")
    assert not problems, f"{label}:\n  " + "\n  ".join(problems)


# --------------------------------------------------------------------------------------------------
# macOS
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("archive,member", _cases("macho"))
def test_macos_minos_install_name_and_libraries(request, archive, member, fmu_report):
    label, _, macho = load(request, archive, member)
    problems = []
    for s in macho.slices:
        unit = f"[{s.cpu_name}]"
        fmu_report.figure("binaries", f"{label}[{s.cpu_name}].minos", s.minos, f"sdk {s.sdk}, {s.version_source}")
        if s.platform != binfmt.PLATFORM_MACOS:
            problems.append(f"{unit} platform {s.platform_name}, expected macos")
        limit = MACOS_MAX_MINOS.get(s.cpu_name)
        if s.minos is None:
            problems.append(f"{unit} no LC_BUILD_VERSION or LC_VERSION_MIN_MACOSX")
        elif limit is None or binfmt.version_tuple(s.minos) > binfmt.version_tuple(limit):
            problems.append(f"{unit} minos {s.minos} > {limit}")
        if s.install_name != MACOS_INSTALL_NAME:
            problems.append(f"{unit} install name (LC_ID_DYLIB) {s.install_name!r}, expected {MACOS_INSTALL_NAME!r}")
        if s.dylibs != [("LC_LOAD_DYLIB", LIBSYSTEM)]:
            problems.append(f"{unit} loads {s.dylibs}, expected only LC_LOAD_DYLIB {LIBSYSTEM}")
        outside = sorted(n for n, lib in s.imports.items() if lib != LIBSYSTEM)
        if outside:
            problems.append(f"{unit} symbols bound outside libSystem: {outside}")
    assert not problems, f"{label}:\n  " + "\n  ".join(problems)


@pytest.mark.parametrize("archive,member", _cases("macho"))
def test_macos_code_signature_verifies(request, archive, member, fmu_report):
    """Every arm64 slice must carry a code signature that verifies; an x86_64 slice need not be
    signed, but a signature it carries must verify too."""
    label, _, macho = load(request, archive, member)
    problems = []
    for s in macho.slices:
        unit = f"[{s.cpu_name}]"
        cs = s.code_signature
        if cs is None:
            if s.cpu_name == "arm64":
                problems.append(f"{unit} no LC_CODE_SIGNATURE: arm64 macOS refuses unsigned code")
            else:
                fmu_report.note("binaries", f"{label}{unit} unsigned")
            continue
        for cd in cs.directories:
            kinds = [k for k, on in (("adhoc", cd.adhoc), ("linker-signed", cd.linker_signed)) if on]
            fmu_report.figure(
                "binaries",
                f"{label}[{s.cpu_name}].signature_pages_verified",
                cd.pages_checked,
                f"{cd.hash_name}, {cd.page_size}-byte pages up to codeLimit {cd.code_limit:#x}; identifier "
                f"{cd.identifier!r}, flags {cd.flags:#x} ({', '.join(kinds) or 'none'}), cdhash {cd.cdhash}",
            )
            if not cd.valid:
                problems.append(
                    f"{unit} CodeDirectory slot {cd.slot:#x} ({cd.identifier!r}) does not verify: "
                    f"{len(cd.mismatched_pages)} of {cd.pages_checked} pages differ "
                    f"(first {cd.mismatched_pages[:5]}), special slots differing {cd.mismatched_special_slots}, "
                    f"{'; '.join(cd.problems) or 'no structural problem'}"
                )
            if cd.code_limit != cs.offset:
                problems.append(
                    f"{unit} codeLimit {cd.code_limit:#x} != the signature's offset {cs.offset:#x}: "
                    "part of the file is not covered"
                )
    assert not problems, f"{label}: code signature:\n  " + "\n  ".join(problems)
