"""Unit tests of tests/python/binfmt.py, the ELF / PE32+ / Mach-O reader behind test_fmu_binaries.py.

The parser is checked against real binaries, the FMU's own (fixture `fmu_file`) and this machine's
libc and libm, by facts that do not come from the parser itself:
- the x86-64 ELF's exports all resolve through the dynamic loader (ctypes), and every versioned
  symbol it needs from libc.so.6 is defined with that version by the system's libc.so.6;
- libm.so.6 defines pow@GLIBC_2.29 (glibc 2.29's new pow) and its DT_SONAME is libm.so.6;
- the five builds export the same 44 names (PE, ELF and Mach-O decode them in different ways);
- a Mach-O's export trie lists exactly the symbol table's external definitions (two encodings);
- a universal file's slice parses the same as the slice on its own (offsets are slice-relative);
- the code signature verifies as built; one flipped byte anywhere in the signed range makes exactly
  that page fail, and a flipped stored hash makes that slot fail.
And against synthetic input: corrupted headers raise FormatError, a hand-built export trie (shared
prefixes, a re-export) walks to the expected names, a cyclic trie is refused, LEB128 decodes as
DWARF's examples say.
"""

from __future__ import annotations

import ctypes
import struct
import zipfile
from pathlib import Path

import pytest

import binfmt

LINUX64 = "binaries/linux64/BeamBody.so"
AARCH64_LINUX = "binaries/aarch64-linux/BeamBody.so"
WIN64 = "binaries/win64/BeamBody.dll"
DARWIN64 = "binaries/darwin64/BeamBody.dylib"
AARCH64_DARWIN = "binaries/aarch64-darwin/BeamBody.dylib"

SYSTEM_LIBDIRS = ("/lib/x86_64-linux-gnu", "/usr/lib/x86_64-linux-gnu", "/lib64", "/usr/lib64")


@pytest.fixture(scope="module")
def member(fmu_file):
    """member(name) -> the bytes of binaries/... in the FMU; a missing one is a failure."""
    cache: dict[str, bytes] = {}

    def read(name: str) -> bytes:
        if name not in cache:
            with zipfile.ZipFile(fmu_file) as z:
                if name not in z.namelist():
                    pytest.fail(f"{fmu_file} has no {name} (the parser tests need every format)", pytrace=False)
                cache[name] = z.read(name)
        return cache[name]

    return read


def system_library(name: str) -> Path:
    for d in SYSTEM_LIBDIRS:
        p = Path(d) / name
        if p.is_file():
            return p.resolve()
    pytest.fail(f"{name} not found in {SYSTEM_LIBDIRS}", pytrace=False)


def flipped(data: bytes, offset: int) -> bytes:
    b = bytearray(data)
    b[offset] ^= 0xFF
    return bytes(b)


def patched(data: bytes, offset: int, fmt: str, *values) -> bytes:
    b = bytearray(data)
    struct.pack_into(fmt, b, offset, *values)
    return bytes(b)


# --------------------------------------------------------------------------------------------------
# LEB128, export trie (synthetic)
# --------------------------------------------------------------------------------------------------


def test_leb128_decodes_dwarf_examples():
    # DWARF 5, section 7.6, figures 22 and 23 (and the Wikipedia example 624485)
    assert binfmt.read_uleb128(b"\x02", 0) == (2, 1)
    assert binfmt.read_uleb128(b"\x7f", 0) == (127, 1)
    assert binfmt.read_uleb128(b"\x80\x01", 0) == (128, 2)
    assert binfmt.read_uleb128(b"\xe5\x8e\x26", 0) == (624485, 3)
    assert binfmt.read_sleb128(b"\x7e", 0) == (-2, 1)
    assert binfmt.read_sleb128(b"\xff\x7e", 0) == (-129, 2)
    assert binfmt.read_sleb128(b"\x80\x7f", 0) == (-128, 2)
    with pytest.raises(binfmt.FormatError):
        binfmt.read_uleb128(b"\x80\x80", 0)


def _trie() -> bytes:
    """_a (address 0x10), _ab (0x20, below _a's node) and _b (re-export of _c from dylib 1)."""
    root = b"\x00\x02" + b"_a\0" + bytes([10]) + b"_b\0" + bytes([21])  # 10 bytes
    node_a = b"\x02\x00\x10" + b"\x01" + b"b\0" + bytes([17])  # at 10, 7 bytes
    node_ab = b"\x02\x00\x20\x00"  # at 17, 4 bytes
    node_b = b"\x05\x08\x01_c\0\x00"  # at 21: flags REEXPORT, ordinal 1, name "_c"
    trie = root + node_a + node_ab + node_b
    assert (len(root), len(root + node_a), len(root + node_a + node_ab)) == (10, 17, 21)
    return trie


def test_export_trie_walk_synthetic():
    assert binfmt.walk_export_trie(_trie()) == [
        ("_a", 0, 0x10),
        ("_ab", 0, 0x20),
        ("_b", binfmt.EXPORT_SYMBOL_FLAGS_REEXPORT, 1),
    ]
    assert binfmt.walk_export_trie(b"") == []


def test_export_trie_refuses_cycles_and_truncation():
    trie = bytearray(_trie())
    trie[16] = 10  # _a's child edge "b" now points back at _a's own node
    with pytest.raises(binfmt.FormatError, match="twice"):
        binfmt.walk_export_trie(bytes(trie))
    with pytest.raises(binfmt.FormatError):
        binfmt.walk_export_trie(_trie()[:19])


def test_chained_fixup_imports_synthetic():
    """The three import formats of LC_DYLD_CHAINED_FIXUPS (the real builds use LC_DYLD_INFO_ONLY)."""
    names = b"\0_free\0_malloc\0"  # offsets 1 and 7

    def payload(fmt: int, entries: bytes, count: int) -> bytes:
        header = struct.pack("<IIIIIII", 0, 28, 28, 28 + len(entries), count, fmt, 0)
        return header + entries + names

    one = struct.pack("<II", 1 | 1 << 9, 0xFE | 1 << 8 | 7 << 9)  # (dylib 1, _free), (flat, weak, _malloc)
    assert binfmt.chained_fixup_imports(payload(1, one, 2)) == [("_free", 1, False), ("_malloc", -2, True)]
    two = struct.pack("<IiIi", 1 | 1 << 9, 8, 2 | 7 << 9, -8)
    assert binfmt.chained_fixup_imports(payload(2, two, 2)) == [("_free", 1, False), ("_malloc", 2, False)]
    three = struct.pack("<QQ", 0xFFFF | 1 << 16 | 7 << 32, 0)
    assert binfmt.chained_fixup_imports(payload(3, three, 1)) == [("_malloc", -1, True)]
    with pytest.raises(binfmt.FormatError, match="imports_format"):
        binfmt.chained_fixup_imports(payload(4, one, 2))
    with pytest.raises(binfmt.FormatError):
        binfmt.chained_fixup_imports(payload(1, one, 3))  # a third entry reads the names as an import


# --------------------------------------------------------------------------------------------------
# ELF
# --------------------------------------------------------------------------------------------------


def test_elf_x86_64_exports_resolve_through_the_loader(member, tmp_path):
    data = member(LINUX64)
    elf = binfmt.parse(data)
    assert elf.format == "elf" and elf.machine_name == "x86_64"
    path = tmp_path / "BeamBody.so"
    path.write_bytes(data)
    lib = ctypes.CDLL(str(path))
    unresolved = [name for name in elf.exports if not hasattr(lib, name)]
    assert elf.exports and not unresolved, f"exports the loader cannot resolve: {unresolved}"
    assert not hasattr(lib, "fmi2NotAFunction")
    # the loader also finds no defined symbol the parser missed among the FMI names
    assert all(hasattr(lib, n) == (n in elf.exports) for n in ("fmi2DoStep", "fmi2GetReal", "fmi2Reset"))


def test_elf_version_requirements_match_the_system_libraries(member):
    """Every versioned symbol the x86-64 build needs from libc.so.6, ld-linux-x86-64.so.2 and
    libgcc_s.so.1 is defined, with that version, by this machine's copy of that library (versym +
    verneed decoding checked against versym + verdef decoding of another file)."""
    elf = binfmt.parse(member(LINUX64))
    assert set(elf.version_needs) <= set(elf.needed), f"versions needed from files not in DT_NEEDED: {elf.needed}"
    assert "libc.so.6" in elf.version_needs, f"no version needed from libc.so.6: {elf.version_needs}"
    checked = 0
    for file in elf.version_needs:
        lib = binfmt.parse(system_library(file).read_bytes())
        assert lib.soname == file
        defined = {(s.name, s.version) for s in lib.dynamic_symbols if s.defined}
        wanted = [s for s in elf.undefined if s.version_file == file]
        assert wanted, f"{file}: versions {elf.version_needs[file]} needed, but no symbol uses them"
        assert {s.version for s in wanted} <= set(elf.version_needs[file])
        missing = [str(s) for s in wanted if (s.name, s.version) not in defined]
        assert not missing, f"needed from {file} but not defined with that version by {system_library(file)}: {missing}"
        checked += len(wanted)
    assert checked >= 10


def test_elf_system_libm():
    libm = binfmt.parse(system_library("libm.so.6").read_bytes())
    assert libm.soname == "libm.so.6"
    assert libm.machine_name == "x86_64"
    pow_versions = {s.version for s in libm.dynamic_symbols if s.defined and s.name == "pow"}
    assert "GLIBC_2.29" in pow_versions, f"pow versions in libm: {pow_versions}"
    default = [s for s in libm.dynamic_symbols if s.defined and s.name == "pow" and not s.hidden_version]
    assert [s.version for s in default] == ["GLIBC_2.29"], "pow's default version is GLIBC_2.29"
    assert "GLIBC_2.2.5" in libm.version_definitions and "GLIBC_2.29" in libm.version_definitions
    assert "pow" in libm.exports and "libc.so.6" in libm.needed


def test_elf_aarch64(member):
    x86 = binfmt.parse(member(LINUX64))
    arm = binfmt.parse(member(AARCH64_LINUX))
    assert arm.machine_name == "aarch64" and arm.machine == 183
    assert arm.exports == x86.exports
    assert arm.max_glibc() is not None and arm.max_glibc().startswith("GLIBC_2.")


def test_elf_corruptions_are_refused(member):
    data = member(LINUX64)
    with pytest.raises(binfmt.FormatError, match="magic"):
        binfmt.parse_elf(b"\x7fELG" + data[4:])
    with pytest.raises(binfmt.FormatError, match="ELFCLASS64"):
        binfmt.parse(data[:4] + b"\x01" + data[5:])
    with pytest.raises(binfmt.FormatError, match="little-endian"):
        binfmt.parse(data[:5] + b"\x02" + data[6:])
    with pytest.raises(binfmt.FormatError):
        binfmt.parse(data[:40])
    with pytest.raises(binfmt.FormatError):
        binfmt.parse(patched(data, 0x28, "<Q", len(data) + 64))  # e_shoff past the end
    with pytest.raises(binfmt.FormatError):
        binfmt.parse(data[: len(data) // 2] + b"\0" * (len(data) - len(data) // 2))  # sections zeroed
    # e_machine really comes from the header
    assert binfmt.parse(patched(data, 0x12, "<H", 183)).machine_name == "aarch64"


def test_elf_bad_version_index_is_refused(member):
    data = member(LINUX64)
    elf = binfmt.parse(data)
    # find .gnu.version and point the first versioned undefined symbol at an unknown index
    (e_shoff,) = struct.unpack_from("<Q", data, 0x28)
    (e_shnum,) = struct.unpack_from("<H", data, 0x3C)
    for i in range(e_shnum):
        sh = struct.unpack_from("<IIQQQQIIQQ", data, e_shoff + 64 * i)
        if sh[1] == binfmt.SHT_GNU_VERSYM:
            versym_off = sh[4]
            break
    else:
        pytest.fail("no .gnu.version in the x86-64 build")
    index = next(i for i, s in enumerate(elf.dynamic_symbols, start=1) if s.version and not s.defined)
    with pytest.raises(binfmt.FormatError, match="version index"):
        binfmt.parse(patched(data, versym_off + 2 * index, "<H", 0x7FF0))


# --------------------------------------------------------------------------------------------------
# PE32+
# --------------------------------------------------------------------------------------------------


def test_pe_exports_and_imports(member):
    pe = binfmt.parse(member(WIN64))
    elf = binfmt.parse(member(LINUX64))
    assert pe.format == "pe" and pe.machine == 0x8664 and pe.is_dll
    assert pe.exports == elf.exports, "the DLL and the .so export different names"
    assert pe.unnamed_exports == 0
    assert any(d.lower() == "kernel32.dll" for d in pe.imports), f"no KERNEL32.dll import: {list(pe.imports)}"
    assert all(names for names in pe.imports.values())
    assert ".text" in pe.sections, pe.sections


def test_pe_names_come_from_the_file(member):
    data = member(WIN64)
    assert b"fmi2DoStep\0" in data
    renamed = data.replace(b"fmi2DoStep\0", b"fmi2DoStop\0")
    exports = binfmt.parse(renamed).exports
    assert "fmi2DoStop" in exports and "fmi2DoStep" not in exports


def test_pe_corruptions_are_refused(member):
    data = member(WIN64)
    (e_lfanew,) = struct.unpack_from("<I", data, 0x3C)
    with pytest.raises(binfmt.FormatError, match="MZ"):
        binfmt.parse_pe(b"ZM" + data[2:])
    with pytest.raises(binfmt.FormatError, match="PE"):
        binfmt.parse(patched(data, e_lfanew, "<4s", b"PE\0\1"))
    with pytest.raises(binfmt.FormatError):
        binfmt.parse(patched(data, 0x3C, "<I", len(data) - 2))
    with pytest.raises(binfmt.FormatError, match="PE32"):
        binfmt.parse(patched(data, e_lfanew + 24, "<H", 0x10B))
    with pytest.raises(binfmt.FormatError):
        binfmt.parse(data[:4096])
    # an export directory RVA in no section
    with pytest.raises(binfmt.FormatError, match="RVA"):
        binfmt.parse(patched(data, e_lfanew + 24 + 112, "<I", 0x7FFFFFF0))


# --------------------------------------------------------------------------------------------------
# Mach-O
# --------------------------------------------------------------------------------------------------


def test_macho_thin_arm64(member):
    data = member(AARCH64_DARWIN)
    macho = binfmt.parse(data)
    elf = binfmt.parse(member(LINUX64))
    assert macho.format == "macho" and not macho.fat and macho.archs == ["arm64"]
    (s,) = macho.slices
    assert s.cputype == binfmt.CPU_TYPE_ARM64 and s.filetype == binfmt.MH_DYLIB and s.offset == 0
    assert s.exports == s.symtab_exports, "export trie and symbol table disagree"
    assert s.exports == ["_" + n for n in elf.exports]
    assert s.exports_source in ("LC_DYLD_EXPORTS_TRIE", "LC_DYLD_INFO")
    assert s.minos and s.sdk and s.platform == binfmt.PLATFORM_MACOS
    assert s.imports and all(name for name in s.imports)
    assert s.segments and s.segments[0].name == "__TEXT"


def test_macho_universal_slices_parse_as_thin_files(member):
    data = member(DARWIN64)
    fat = binfmt.parse(data)
    assert fat.fat and sorted(fat.archs) == ["arm64", "x86_64"]
    assert struct.unpack_from(">I", data, 0)[0] == binfmt.FAT_MAGIC
    for s in fat.slices:
        assert s.offset > 0 and s.offset % 4096 == 0
        assert s.exports == s.symtab_exports, f"[{s.cpu_name}] export trie and symbol table disagree"
        (alone,) = binfmt.parse(data[s.offset : s.offset + s.size]).slices
        alone.offset = s.offset
        assert alone == s, f"[{s.cpu_name}] parses differently inside the universal file"
    assert fat.slice("x86_64").cputype == binfmt.CPU_TYPE_X86_64
    with pytest.raises(KeyError):
        fat.slice("ppc")


def test_macho_fat_corruptions_are_refused(member):
    data = member(DARWIN64)
    with pytest.raises(binfmt.FormatError, match="nfat_arch"):
        binfmt.parse(patched(data, 4, ">I", 0))
    with pytest.raises(binfmt.FormatError, match="cputype"):
        binfmt.parse(patched(data, 8, ">i", binfmt.CPU_TYPE_ARM64 if binfmt.parse(data).archs[0] != "arm64"
                             else binfmt.CPU_TYPE_X86_64))
    with pytest.raises(binfmt.FormatError, match="past the end"):
        binfmt.parse(patched(data, 8 + 12, ">I", len(data)))  # first slice's size
    with pytest.raises(binfmt.FormatError, match="little-endian"):
        binfmt.parse(b"\xfe\xed\xfa\xcf" + member(AARCH64_DARWIN)[4:])  # big-endian 64-bit magic
    thin = member(AARCH64_DARWIN)
    with pytest.raises(binfmt.FormatError, match="sizeofcmds"):
        binfmt.parse(patched(thin, 20, "<I", len(thin)))


def _signed_arm64(member):
    data = member(AARCH64_DARWIN)
    (s,) = binfmt.parse(data).slices
    assert s.code_signature is not None, "the thin arm64 build carries no LC_CODE_SIGNATURE"
    return data, s


def test_code_signature_verifies_as_built(member):
    data, s = _signed_arm64(member)
    cs = s.code_signature
    cd = cs.primary
    assert cs.valid and cd.valid, f"{cd}"
    assert cd.hash_type == 2 and cd.hash_size == 32 and cd.page_size == 4096
    assert cd.code_limit == cs.offset, "the signature covers the file up to itself"
    assert cd.pages_checked == cd.n_code_slots == -(-cd.code_limit // cd.page_size)
    assert cd.identifier
    assert cd.adhoc, f"flags {cd.flags:#x}: expected an ad-hoc signature"


def _text_offset(s) -> int:
    """A file offset inside __TEXT, past the header and load commands (a byte of code)."""
    text = next(seg for seg in s.segments if seg.name == "__TEXT")
    return text.fileoff + text.filesize // 2


def test_code_signature_fails_on_a_flipped_code_byte(member):
    data, s = _signed_arm64(member)
    cd = s.code_signature.primary
    # a byte of code, the mach header's flags, the last signed byte
    for offset in (_text_offset(s), 0x18, cd.code_limit - 1):
        (bad,) = binfmt.parse(flipped(data, offset)).slices
        cs = bad.code_signature
        assert not cs.valid, f"a flipped byte at {offset:#x} went unnoticed"
        assert cs.primary.mismatched_pages == [offset // cd.page_size]


def test_code_signature_fails_on_a_flipped_stored_hash(member):
    data, s = _signed_arm64(member)
    cs = s.code_signature
    cd = cs.primary
    # the CodeDirectory's hashOffset (big-endian, at +16 of the blob); slot 3's hash
    blob = next(o for t, o in _blob_index(data, cs.offset) if t == 0)
    (hash_offset,) = struct.unpack_from(">I", data, cs.offset + blob + 16)
    (bad,) = binfmt.parse(flipped(data, cs.offset + blob + hash_offset + 3 * cd.hash_size)).slices
    assert bad.code_signature.primary.mismatched_pages == [3]
    assert not bad.code_signature.valid


def test_code_signature_bad_superblob_is_refused(member):
    data, s = _signed_arm64(member)
    with pytest.raises(binfmt.FormatError, match="SuperBlob magic"):
        binfmt.parse(patched(data, s.code_signature.offset, ">I", 0xFADE0CC1))
    blob = next(o for t, o in _blob_index(data, s.code_signature.offset) if t == 0)
    with pytest.raises(binfmt.FormatError, match="CodeDirectory"):
        binfmt.parse(patched(data, s.code_signature.offset + blob, ">I", 0xFADE0C03))


def test_code_signature_in_a_universal_file(member):
    """A flipped byte in the arm64 slice of the universal file fails that slice only."""
    data = member(DARWIN64)
    fat = binfmt.parse(data)
    arm = fat.slice("arm64")
    assert arm.code_signature is not None and arm.code_signature.valid
    bad = binfmt.parse(flipped(data, arm.offset + _text_offset(arm)))
    assert not bad.slice("arm64").code_signature.valid
    x86 = bad.slice("x86_64")
    assert x86.code_signature is None or x86.code_signature.valid


def _blob_index(data: bytes, at: int) -> list[tuple[int, int]]:
    _, _, count = struct.unpack_from(">III", data, at)
    return [struct.unpack_from(">II", data, at + 12 + 8 * i) for i in range(count)]


def test_detect():
    assert binfmt.detect(b"\x7fELF\x02\x01") == "elf"
    assert binfmt.detect(b"MZ\x90\x00") == "pe"
    assert binfmt.detect(b"\xcf\xfa\xed\xfe") == "macho"
    assert binfmt.detect(b"\xca\xfe\xba\xbe") == "macho"
    assert binfmt.detect(b"PK\x03\x04") is None
    with pytest.raises(binfmt.FormatError, match="unknown format"):
        binfmt.parse(b"PK\x03\x04")
