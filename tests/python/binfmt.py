"""A small reader of the three shared-library formats the FMU ships: ELF, PE32+ and Mach-O.

Standard library only (struct, hashlib), so that the checks of tests/python/binaries/test_fmu_binaries.py
depend on no binutils, LLVM tool or third-party parser: every figure they assert comes from the
bytes, decoded here from the formats' specifications (each structure cites its source).

- ELF, 64-bit little-endian (x86-64, aarch64): machine, the defined dynamic symbols (exports),
  the undefined ones with their version requirement (`pow@GLIBC_2.29`), DT_NEEDED, DT_SONAME.
- PE32+ (Windows x64 DLL): machine, the export directory's names, the imports per DLL (import
  and delay-import directories).
- Mach-O, thin 64-bit or fat/universal: per slice the cputype, LC_BUILD_VERSION or
  LC_VERSION_MIN_MACOSX, the install name, the dylibs it loads, the exported symbols (the export
  trie, walked), the imported symbols, and the LC_CODE_SIGNATURE, whose CodeDirectory is verified
  page by page (the hash of every page up to codeLimit must equal its code slot).

Entry point: `parse(data)` returns an `ElfFile`, a `PeFile` or a `MachOFile`; malformed input
raises `FormatError` (a ValueError) with the offset or field at fault.
"""

from __future__ import annotations

import hashlib
import struct
from dataclasses import dataclass, field


class FormatError(ValueError):
    """The bytes are not a well-formed file of the expected format."""


# --------------------------------------------------------------------------------------------------
# bytes helpers
# --------------------------------------------------------------------------------------------------


def _unpack(fmt: str, data: bytes, offset: int, what: str) -> tuple:
    size = struct.calcsize(fmt)
    if offset < 0 or offset + size > len(data):
        raise FormatError(f"{what}: {size} bytes at offset {offset:#x} run past the end ({len(data):#x})")
    return struct.unpack_from(fmt, data, offset)


def _cstring(data: bytes, offset: int, what: str, end: int | None = None) -> str:
    """The NUL-terminated string at offset (which must end before `end`, default the data's end)."""
    end = len(data) if end is None else min(end, len(data))
    if offset < 0 or offset >= end:
        raise FormatError(f"{what}: string offset {offset:#x} outside [0, {end:#x})")
    stop = data.find(b"\0", offset, end)
    if stop < 0:
        raise FormatError(f"{what}: string at {offset:#x} is not NUL-terminated before {end:#x}")
    return data[offset:stop].decode("utf-8", "replace")


def read_uleb128(data: bytes, offset: int, end: int | None = None) -> tuple[int, int]:
    """(value, next offset) of the unsigned LEB128 at offset (DWARF 5, section 7.6; the encoding
    of Mach-O's export trie and bind opcodes, mach-o/loader.h)."""
    end = len(data) if end is None else end
    value = shift = 0
    while True:
        if offset >= end:
            raise FormatError(f"ULEB128 runs past the end ({end:#x})")
        byte = data[offset]
        offset += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, offset
        if shift > 70:
            raise FormatError(f"ULEB128 at {offset:#x} is longer than 10 bytes")


def read_sleb128(data: bytes, offset: int, end: int | None = None) -> tuple[int, int]:
    """(value, next offset) of the signed LEB128 at offset (DWARF 5, section 7.6)."""
    end = len(data) if end is None else end
    value = shift = 0
    while True:
        if offset >= end:
            raise FormatError(f"SLEB128 runs past the end ({end:#x})")
        byte = data[offset]
        offset += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            if byte & 0x40:
                value -= 1 << shift
            return value, offset
        if shift > 70:
            raise FormatError(f"SLEB128 at {offset:#x} is longer than 10 bytes")


# --------------------------------------------------------------------------------------------------
# ELF
#
# Structures: System V ABI, "Object Files" chapter (ELF header, section header, symbol table,
# dynamic section); the Oracle "Linker and Libraries Guide" and the LSB Core specification,
# "Symbol Versioning" (SHT_GNU_versym / SHT_GNU_verneed / SHT_GNU_verdef: Elf64_Versym,
# Elf64_Verneed, Elf64_Vernaux, Elf64_Verdef, Elf64_Verdaux).
# --------------------------------------------------------------------------------------------------

ELF_MAGIC = b"\x7fELF"
ELFCLASS64 = 2
ELFDATA2LSB = 1
EM_NAMES = {3: "i386", 40: "arm", 62: "x86_64", 183: "aarch64", 243: "riscv"}
ET_DYN = 3

SHT_DYNSYM = 11
SHT_DYNAMIC = 6
SHT_GNU_VERDEF = 0x6FFFFFFD
SHT_GNU_VERNEED = 0x6FFFFFFE
SHT_GNU_VERSYM = 0x6FFFFFFF

SHN_UNDEF = 0
STB_GLOBAL, STB_WEAK = 1, 2
STV_DEFAULT, STV_PROTECTED = 0, 3
DT_NULL, DT_NEEDED, DT_SONAME = 0, 1, 14
VER_NDX_LOCAL, VER_NDX_GLOBAL = 0, 1
VERSYM_HIDDEN = 0x8000
VER_FLG_BASE = 0x1

# Elf64_Ehdr: e_ident[16], e_type, e_machine, e_version, e_entry, e_phoff, e_shoff, e_flags,
# e_ehsize, e_phentsize, e_phnum, e_shentsize, e_shnum, e_shstrndx (gABI, "ELF Header").
_ELF64_EHDR = "<16sHHIQQQIHHHHHH"
# Elf64_Shdr: sh_name, sh_type, sh_flags, sh_addr, sh_offset, sh_size, sh_link, sh_info,
# sh_addralign, sh_entsize (gABI, "Sections").
_ELF64_SHDR = "<IIQQQQIIQQ"
# Elf64_Sym: st_name, st_info, st_other, st_shndx, st_value, st_size (gABI, "Symbol Table").
_ELF64_SYM = "<IBBHQQ"
# Elf64_Dyn: d_tag (signed), d_un (gABI, "Dynamic Section").
_ELF64_DYN = "<qQ"
# Elf64_Verneed: vn_version, vn_cnt, vn_file, vn_aux, vn_next; Elf64_Vernaux: vna_hash,
# vna_flags, vna_other, vna_name, vna_next (LSB Core, "Version Needed Section").
_ELF_VERNEED = "<HHIII"
_ELF_VERNAUX = "<IHHII"
# Elf64_Verdef: vd_version, vd_flags, vd_ndx, vd_cnt, vd_hash, vd_aux, vd_next; Elf64_Verdaux:
# vda_name, vda_next (LSB Core, "Version Definition Section").
_ELF_VERDEF = "<HHHHIII"
_ELF_VERDAUX = "<II"


@dataclass
class ElfSymbol:
    name: str
    version: str | None  # the required (undefined) or defined version, None if unversioned
    binding: int  # STB_*
    type: int  # STT_*
    visibility: int  # STV_*
    defined: bool
    hidden_version: bool = False  # versym bit 15: not the default version of the name
    version_file: str | None = None  # for a required version: the file it is needed from (vn_file)

    def __str__(self) -> str:
        return f"{self.name}@{self.version}" if self.version else self.name


@dataclass
class ElfFile:
    machine: int
    e_type: int
    needed: list[str]
    soname: str | None
    dynamic_symbols: list[ElfSymbol]
    version_needs: dict[str, list[str]]  # file (e.g. libc.so.6) -> versions required from it
    version_definitions: list[str]  # versions this file defines (VER_FLG_BASE excluded)

    format = "elf"

    @property
    def machine_name(self) -> str:
        return EM_NAMES.get(self.machine, f"EM_{self.machine}")

    @property
    def exports(self) -> list[str]:
        """Defined global/weak symbols of default or protected visibility in .dynsym."""
        return sorted(
            {
                s.name
                for s in self.dynamic_symbols
                if s.defined
                and s.binding in (STB_GLOBAL, STB_WEAK)
                and s.visibility in (STV_DEFAULT, STV_PROTECTED)
                and s.name
            }
        )

    @property
    def undefined(self) -> list[ElfSymbol]:
        """Undefined dynamic symbols (the imports), each with its version requirement if any."""
        return [s for s in self.dynamic_symbols if not s.defined and s.name]

    @property
    def imports(self) -> list[str]:
        return sorted({s.name for s in self.undefined})

    def required_versions(self, prefix: str = "GLIBC_") -> list[str]:
        """The versions named prefix* required (Elf64_Vernaux entries and the symbols' versions),
        numbered ones lowest first, then the others (GLIBC_PRIVATE, GLIBC_ABI_DT_RELR) by name."""
        found = {s.version for s in self.undefined if s.version and s.version.startswith(prefix)}
        for versions in self.version_needs.values():
            found.update(v for v in versions if v.startswith(prefix))
        return sorted(found, key=version_key)

    def max_glibc(self) -> str | None:
        """The highest numbered GLIBC_x.y required, e.g. 'GLIBC_2.34'; GLIBC_ABI_DT_RELR counts as
        GLIBC_2.36 (the glibc that introduced it, for DT_RELR relocations)."""
        versions = [GLIBC_MARKERS.get(v, v) for v in self.required_versions("GLIBC_")]
        numbered = [v for v in versions if version_key(v)[0] == 0]
        return max(numbered, key=version_key) if numbered else None


#: Version names that stand for a glibc release without being numbered.
GLIBC_MARKERS = {"GLIBC_ABI_DT_RELR": "GLIBC_2.36"}


def version_key(name: str) -> tuple:
    """Sort key of NAME_x.y.z version names: (0, x, y, z) when numbered, else (1, name)."""
    tail = name.rsplit("_", 1)[-1]
    pieces = tail.split(".")
    if all(p.isdigit() for p in pieces):
        return (0, *(int(p) for p in pieces))
    return (1, name)


def parse_elf(data: bytes) -> ElfFile:
    if data[:4] != ELF_MAGIC:
        raise FormatError("not an ELF file (no \\x7fELF magic)")
    if len(data) < 64:
        raise FormatError(f"ELF header truncated ({len(data)} bytes)")
    ident = data[:16]
    if ident[4] != ELFCLASS64:
        raise FormatError(f"EI_CLASS = {ident[4]}: only ELFCLASS64 is supported")
    if ident[5] != ELFDATA2LSB:
        raise FormatError(f"EI_DATA = {ident[5]}: only little-endian (ELFDATA2LSB) is supported")
    (_, e_type, e_machine, _, _, _, e_shoff, _, _, _, _, e_shentsize, e_shnum, e_shstrndx) = _unpack(
        _ELF64_EHDR, data, 0, "ELF header"
    )
    if e_shoff == 0:
        raise FormatError("ELF file has no section header table")
    if e_shentsize != struct.calcsize(_ELF64_SHDR):
        raise FormatError(f"e_shentsize = {e_shentsize}, expected {struct.calcsize(_ELF64_SHDR)}")
    if e_shnum == 0:  # extended numbering: the count is section 0's sh_size (gABI, "Sections")
        e_shnum = _unpack(_ELF64_SHDR, data, e_shoff, "section header 0")[5]
    sections = [
        _unpack(_ELF64_SHDR, data, e_shoff + i * e_shentsize, f"section header {i}") for i in range(e_shnum)
    ]

    def body(index: int, what: str) -> bytes:
        if not 0 <= index < len(sections):
            raise FormatError(f"{what}: section index {index} out of range (e_shnum {len(sections)})")
        sh = sections[index]
        offset, size = sh[4], sh[5]
        if offset + size > len(data):
            raise FormatError(f"{what}: section {index} [{offset:#x}, +{size:#x}) runs past the end")
        return data[offset : offset + size]

    def first(sh_type: int):
        for i, sh in enumerate(sections):
            if sh[1] == sh_type:
                return i, sh
        return None, None

    # .dynsym and its string table (sh_link)
    dynsym_index, dynsym = first(SHT_DYNSYM)
    if dynsym is None:
        raise FormatError("no SHT_DYNSYM section (.dynsym): not a dynamic object")
    symbytes = body(dynsym_index, ".dynsym")
    dynstr = body(dynsym[6], ".dynstr")
    symsize = struct.calcsize(_ELF64_SYM)
    nsyms = len(symbytes) // symsize

    # version needs: versym index -> (file, version)
    need_by_index: dict[int, tuple[str, str]] = {}  # versym index -> (vn_file, version)
    version_needs: dict[str, list[str]] = {}
    vn_index, vn_sh = first(SHT_GNU_VERNEED)
    if vn_sh is not None:
        vnbytes = body(vn_index, ".gnu.version_r")
        vnstr = body(vn_sh[6], ".gnu.version_r strings")
        count = vn_sh[7]  # sh_info: number of entries
        offset = 0
        for _ in range(count):
            vn_version, vn_cnt, vn_file, vn_aux, vn_next = _unpack(_ELF_VERNEED, vnbytes, offset, "Elf64_Verneed")
            if vn_version != 1:
                raise FormatError(f"Elf64_Verneed at {offset:#x}: vn_version {vn_version} != 1")
            file = _cstring(vnstr, vn_file, "vn_file")
            aux = offset + vn_aux
            for _ in range(vn_cnt):
                _, _, vna_other, vna_name, vna_next = _unpack(_ELF_VERNAUX, vnbytes, aux, "Elf64_Vernaux")
                name = _cstring(vnstr, vna_name, "vna_name")
                need_by_index[vna_other & 0x7FFF] = (file, name)
                version_needs.setdefault(file, []).append(name)
                if vna_next == 0:
                    break
                aux += vna_next
            if vn_next == 0:
                break
            offset += vn_next

    # version definitions: versym index -> version
    def_by_index: dict[int, str] = {}
    version_definitions: list[str] = []
    vd_index, vd_sh = first(SHT_GNU_VERDEF)
    if vd_sh is not None:
        vdbytes = body(vd_index, ".gnu.version_d")
        vdstr = body(vd_sh[6], ".gnu.version_d strings")
        offset = 0
        for _ in range(vd_sh[7]):
            vd_version, vd_flags, vd_ndx, vd_cnt, _, vd_aux, vd_next = _unpack(
                _ELF_VERDEF, vdbytes, offset, "Elf64_Verdef"
            )
            if vd_version != 1:
                raise FormatError(f"Elf64_Verdef at {offset:#x}: vd_version {vd_version} != 1")
            if vd_cnt:
                vda_name, _ = _unpack(_ELF_VERDAUX, vdbytes, offset + vd_aux, "Elf64_Verdaux")
                name = _cstring(vdstr, vda_name, "vda_name")
                def_by_index[vd_ndx & 0x7FFF] = name
                if not vd_flags & VER_FLG_BASE:
                    version_definitions.append(name)
            if vd_next == 0:
                break
            offset += vd_next

    versym = None
    vs_index, vs_sh = first(SHT_GNU_VERSYM)
    if vs_sh is not None:
        versym = body(vs_index, ".gnu.version")
        if len(versym) < 2 * nsyms:
            raise FormatError(f".gnu.version has {len(versym) // 2} entries for {nsyms} symbols")

    symbols = []
    for i in range(1, nsyms):  # entry 0 is the reserved null symbol
        st_name, st_info, st_other, st_shndx, _, _ = struct.unpack_from(_ELF64_SYM, symbytes, i * symsize)
        name = _cstring(dynstr, st_name, f".dynsym[{i}].st_name") if st_name else ""
        defined = st_shndx != SHN_UNDEF
        version, hidden, version_file = None, False, None
        if versym is not None:
            (vs,) = struct.unpack_from("<H", versym, 2 * i)
            hidden = bool(vs & VERSYM_HIDDEN)
            idx = vs & 0x7FFF
            if idx not in (VER_NDX_LOCAL, VER_NDX_GLOBAL):
                if defined:
                    version = def_by_index.get(idx)
                elif idx in need_by_index:
                    version_file, version = need_by_index[idx]
                if version is None:
                    raise FormatError(f".dynsym[{i}] {name}: version index {idx} is neither needed nor defined")
        symbols.append(
            ElfSymbol(
                name=name,
                version=version,
                binding=st_info >> 4,
                type=st_info & 0xF,
                visibility=st_other & 0x3,
                defined=defined,
                hidden_version=hidden,
                version_file=version_file,
            )
        )

    # .dynamic: DT_NEEDED, DT_SONAME (strings in the section named by sh_link)
    needed: list[str] = []
    soname = None
    dyn_index, dyn_sh = first(SHT_DYNAMIC)
    if dyn_sh is not None:
        dynbytes = body(dyn_index, ".dynamic")
        dstr = body(dyn_sh[6], ".dynamic strings")
        dynsize = struct.calcsize(_ELF64_DYN)
        for off in range(0, len(dynbytes) - dynsize + 1, dynsize):
            tag, val = struct.unpack_from(_ELF64_DYN, dynbytes, off)
            if tag == DT_NULL:
                break
            if tag == DT_NEEDED:
                needed.append(_cstring(dstr, val, "DT_NEEDED"))
            elif tag == DT_SONAME:
                soname = _cstring(dstr, val, "DT_SONAME")

    return ElfFile(
        machine=e_machine,
        e_type=e_type,
        needed=needed,
        soname=soname,
        dynamic_symbols=symbols,
        version_needs=version_needs,
        version_definitions=version_definitions,
    )


# --------------------------------------------------------------------------------------------------
# PE32+
#
# Structures: Microsoft, "PE Format" (learn.microsoft.com/windows/win32/debug/pe-format): the MS-DOS
# stub's e_lfanew at 0x3c, the COFF File Header, the Optional Header (PE32+) and its data
# directories, the Section Table, "The .edata Section" (Export Directory Table, Export Name
# Pointer Table), "The .idata Section" (Import Directory Table, Import Lookup Table, Hint/Name
# Table) and "Delay-Load Import Tables" (Delay Load Directory Table).
# --------------------------------------------------------------------------------------------------

PE_MACHINES = {0x8664: "x86_64", 0xAA64: "aarch64", 0x14C: "i386"}
IMAGE_FILE_DLL = 0x2000
PE32PLUS_MAGIC = 0x20B

# COFF File Header: Machine, NumberOfSections, TimeDateStamp, PointerToSymbolTable,
# NumberOfSymbols, SizeOfOptionalHeader, Characteristics.
_COFF_HEADER = "<HHIIIHH"
# Section Table entry: Name[8], VirtualSize, VirtualAddress, SizeOfRawData, PointerToRawData,
# PointerToRelocations, PointerToLinenumbers, NumberOfRelocations, NumberOfLinenumbers,
# Characteristics.
_PE_SECTION = "<8sIIIIIIHHI"
# Export Directory Table: Export Flags, Time/Date Stamp, Major Version, Minor Version, Name RVA,
# Ordinal Base, Address Table Entries, Number of Name Pointers, Export Address Table RVA,
# Name Pointer RVA, Ordinal Table RVA.
_PE_EXPORT_DIR = "<IIHHIIIIIII"
# Import Directory Table entry: Import Lookup Table RVA, Time/Date Stamp, Forwarder Chain,
# Name RVA, Import Address Table RVA.
_PE_IMPORT_DESC = "<IIIII"
# Delay Load Directory Table entry: Attributes, Name, Module Handle, Delay Import Address Table,
# Delay Import Name Table, Bound Delay Import Table, Unload Delay Import Table, Time Stamp.
_PE_DELAY_DESC = "<IIIIIIII"
IMAGE_ORDINAL_FLAG64 = 1 << 63
DIR_EXPORT, DIR_IMPORT, DIR_DELAY_IMPORT = 0, 1, 13


@dataclass
class PeFile:
    machine: int
    characteristics: int
    dll_name: str | None  # the export directory's Name
    exports: list[str]  # named exports
    unnamed_exports: int  # export address table entries with no name (ordinal-only)
    imports: dict[str, list[str]]  # DLL -> names (an ordinal import is '#<n>')
    delay_imports: dict[str, list[str]]
    sections: list[str]

    format = "pe"

    @property
    def machine_name(self) -> str:
        return PE_MACHINES.get(self.machine, f"{self.machine:#06x}")

    @property
    def is_dll(self) -> bool:
        return bool(self.characteristics & IMAGE_FILE_DLL)

    def all_imports(self) -> dict[str, list[str]]:
        """Imports and delay imports together, DLL -> names."""
        merged: dict[str, list[str]] = {}
        for table in (self.imports, self.delay_imports):
            for dll, names in table.items():
                merged.setdefault(dll, []).extend(names)
        return merged


def parse_pe(data: bytes) -> PeFile:
    if data[:2] != b"MZ":
        raise FormatError("not a PE file (no MZ signature)")
    (e_lfanew,) = _unpack("<I", data, 0x3C, "e_lfanew")
    if data[e_lfanew : e_lfanew + 4] != b"PE\0\0":
        raise FormatError(f"no PE\\0\\0 signature at e_lfanew {e_lfanew:#x}")
    coff = e_lfanew + 4
    machine, nsections, _, _, _, opt_size, characteristics = _unpack(_COFF_HEADER, data, coff, "COFF header")
    opt = coff + struct.calcsize(_COFF_HEADER)
    (magic,) = _unpack("<H", data, opt, "optional header magic")
    if magic != PE32PLUS_MAGIC:
        raise FormatError(f"optional header magic {magic:#x}: only PE32+ ({PE32PLUS_MAGIC:#x}) is supported")
    if opt_size < 112:
        raise FormatError(f"SizeOfOptionalHeader {opt_size} < 112: no data directories")
    (n_dirs,) = _unpack("<I", data, opt + 108, "NumberOfRvaAndSizes")
    n_dirs = min(n_dirs, (opt_size - 112) // 8)
    dirs = [_unpack("<II", data, opt + 112 + 8 * i, f"data directory {i}") for i in range(n_dirs)]

    sec_table = opt + opt_size
    sections = [
        _unpack(_PE_SECTION, data, sec_table + 40 * i, f"section header {i}") for i in range(nsections)
    ]

    def offset_of(rva: int, what: str) -> int:
        for name, vsize, va, rawsize, rawptr, *_ in sections:
            if va <= rva < va + max(vsize, rawsize):
                if rva - va >= rawsize:
                    raise FormatError(f"{what}: RVA {rva:#x} is in {name!r}'s uninitialised tail")
                return rawptr + (rva - va)
        raise FormatError(f"{what}: RVA {rva:#x} is in no section")

    def string(rva: int, what: str) -> str:
        return _cstring(data, offset_of(rva, what), what)

    def directory(index: int):
        return dirs[index] if index < len(dirs) and dirs[index][0] else None

    # exports
    exports: list[str] = []
    unnamed = 0
    dll_name = None
    d = directory(DIR_EXPORT)
    if d:
        (_, _, _, _, name_rva, _, n_addr, n_names, eat_rva, names_rva, ords_rva) = _unpack(
            _PE_EXPORT_DIR, data, offset_of(d[0], "export directory"), "export directory"
        )
        dll_name = string(name_rva, "export DLL name") if name_rva else None
        named_ordinals = set()
        for i in range(n_names):
            (rva,) = _unpack("<I", data, offset_of(names_rva + 4 * i, "export name pointer"), "export name pointer")
            (ordinal,) = _unpack("<H", data, offset_of(ords_rva + 2 * i, "export ordinal"), "export ordinal")
            if ordinal >= n_addr:
                raise FormatError(f"export {i}: ordinal index {ordinal} >= Address Table Entries {n_addr}")
            exports.append(string(rva, f"export name {i}"))
            named_ordinals.add(ordinal)
        for i in range(n_addr):
            (rva,) = _unpack("<I", data, offset_of(eat_rva + 4 * i, "export address"), "export address")
            if rva and i not in named_ordinals:
                unnamed += 1

    def thunk_names(table_rva: int, what: str) -> list[str]:
        names = []
        pos = offset_of(table_rva, what)
        while True:
            (entry,) = _unpack("<Q", data, pos, what)
            pos += 8
            if entry == 0:
                return names
            if entry & IMAGE_ORDINAL_FLAG64:
                names.append(f"#{entry & 0xFFFF}")
            else:  # Hint/Name Table entry: 2-byte hint, then the name
                names.append(_cstring(data, offset_of((entry & 0x7FFFFFFF) + 2, what), what))

    imports: dict[str, list[str]] = {}
    d = directory(DIR_IMPORT)
    if d:
        pos = offset_of(d[0], "import directory")
        while True:
            ilt, _, _, name_rva, iat = _unpack(_PE_IMPORT_DESC, data, pos, "import directory entry")
            pos += 20
            if (ilt, name_rva, iat) == (0, 0, 0):
                break
            dll = string(name_rva, "import DLL name")
            imports.setdefault(dll, []).extend(thunk_names(ilt or iat, f"import lookup table of {dll}"))

    delay: dict[str, list[str]] = {}
    d = directory(DIR_DELAY_IMPORT)
    if d:
        pos = offset_of(d[0], "delay import directory")
        while True:
            entry = _unpack(_PE_DELAY_DESC, data, pos, "delay import directory entry")
            pos += 32
            if not any(entry):
                break
            _, name_rva, _, _, int_rva, *_ = entry
            dll = string(name_rva, "delay import DLL name")
            delay.setdefault(dll, []).extend(thunk_names(int_rva, f"delay import name table of {dll}"))

    return PeFile(
        machine=machine,
        characteristics=characteristics,
        dll_name=dll_name,
        exports=sorted(exports),
        unnamed_exports=unnamed,
        imports=imports,
        delay_imports=delay,
        sections=[s[0].rstrip(b"\0").decode("ascii", "replace") for s in sections],
    )


# --------------------------------------------------------------------------------------------------
# Mach-O
#
# Structures: Apple's <mach-o/loader.h> (cctools; apple-oss-distributions/cctools,
# include/mach-o/loader.h): mach_header_64, load_command, segment_command_64, dylib_command,
# symtab_command, linkedit_data_command, dyld_info_command and its description of the export trie
# and the bind opcodes, version_min_command, build_version_command, the LC_* and PLATFORM_*
# constants; <mach-o/fat.h>: fat_header, fat_arch, fat_arch_64 (big-endian); <mach-o/nlist.h>:
# nlist_64; <mach/machine.h>: CPU_TYPE_*; dyld's <mach-o/fixup-chains.h>:
# dyld_chained_fixups_header, dyld_chained_import(_addend)(64); and xnu's osfmk/kern/cs_blobs.h
# (apple/darwin-xnu): CS_SuperBlob, CS_BlobIndex, CS_CodeDirectory, CSMAGIC_*, CSSLOT_*,
# CS_HASHTYPE_*, the CS_* flags (CS_LINKER_SIGNED = 0x20000 is in later xnu's cs_blobs.h).
# --------------------------------------------------------------------------------------------------

MH_MAGIC_64 = 0xFEEDFACF
MH_MAGIC = 0xFEEDFACE
FAT_MAGIC = 0xCAFEBABE
FAT_MAGIC_64 = 0xCAFEBABF
CPU_ARCH_ABI64 = 0x01000000
CPU_TYPE_X86_64 = 7 | CPU_ARCH_ABI64
CPU_TYPE_ARM64 = 12 | CPU_ARCH_ABI64
CPU_NAMES = {CPU_TYPE_X86_64: "x86_64", CPU_TYPE_ARM64: "arm64", 7: "i386", 12: "arm"}
MH_DYLIB = 6

LC_REQ_DYLD = 0x80000000
LC_SYMTAB = 0x2
LC_LOAD_DYLIB = 0xC
LC_ID_DYLIB = 0xD
LC_LOAD_WEAK_DYLIB = 0x18 | LC_REQ_DYLD
LC_SEGMENT_64 = 0x19
LC_RPATH = 0x1C | LC_REQ_DYLD
LC_CODE_SIGNATURE = 0x1D
LC_REEXPORT_DYLIB = 0x1F | LC_REQ_DYLD
LC_LAZY_LOAD_DYLIB = 0x20
LC_DYLD_INFO = 0x22
LC_DYLD_INFO_ONLY = 0x22 | LC_REQ_DYLD
LC_LOAD_UPWARD_DYLIB = 0x23 | LC_REQ_DYLD
LC_VERSION_MIN_MACOSX = 0x24
LC_BUILD_VERSION = 0x32
LC_DYLD_EXPORTS_TRIE = 0x33 | LC_REQ_DYLD
LC_DYLD_CHAINED_FIXUPS = 0x34 | LC_REQ_DYLD

DYLIB_LOAD_COMMANDS = {
    LC_LOAD_DYLIB: "LC_LOAD_DYLIB",
    LC_LOAD_WEAK_DYLIB: "LC_LOAD_WEAK_DYLIB",
    LC_REEXPORT_DYLIB: "LC_REEXPORT_DYLIB",
    LC_LAZY_LOAD_DYLIB: "LC_LAZY_LOAD_DYLIB",
    LC_LOAD_UPWARD_DYLIB: "LC_LOAD_UPWARD_DYLIB",
}

PLATFORMS = {1: "macos", 2: "ios", 3: "tvos", 4: "watchos", 5: "bridgeos", 6: "maccatalyst",
             7: "iossimulator", 8: "tvossimulator", 9: "watchossimulator", 10: "driverkit"}
PLATFORM_MACOS = 1

EXPORT_SYMBOL_FLAGS_KIND_MASK = 0x03
EXPORT_SYMBOL_FLAGS_REEXPORT = 0x08
EXPORT_SYMBOL_FLAGS_STUB_AND_RESOLVER = 0x10

# nlist.h: n_type bits
N_STAB, N_PEXT, N_TYPE, N_EXT = 0xE0, 0x10, 0x0E, 0x01
N_UNDF, N_SECT = 0x0, 0xE

# cs_blobs.h
CSMAGIC_CODEDIRECTORY = 0xFADE0C02
CSMAGIC_EMBEDDED_SIGNATURE = 0xFADE0CC0
CSSLOT_CODEDIRECTORY = 0
CSSLOT_ALTERNATE_CODEDIRECTORIES = 0x1000
CSSLOT_SIGNATURESLOT = 0x10000
CS_SUPPORTSSCATTER = 0x20100
CS_SUPPORTSTEAMID = 0x20200
CS_SUPPORTSCODELIMIT64 = 0x20300
CS_SUPPORTSEXECSEG = 0x20400
CS_ADHOC = 0x2
CS_LINKER_SIGNED = 0x20000
CS_HASHES = {  # hashType -> (name, hash size, function of bytes)
    1: ("sha1", 20, lambda b: hashlib.sha1(b).digest()),
    2: ("sha256", 32, lambda b: hashlib.sha256(b).digest()),
    3: ("sha256-truncated", 20, lambda b: hashlib.sha256(b).digest()[:20]),
    4: ("sha384", 48, lambda b: hashlib.sha384(b).digest()),
}

# mach_header_64: magic, cputype, cpusubtype, filetype, ncmds, sizeofcmds, flags, reserved.
_MACH_HEADER_64 = "<IiiIIIII"
# fat_header: magic, nfat_arch; fat_arch: cputype, cpusubtype, offset, size, align;
# fat_arch_64: cputype, cpusubtype, offset, size, align, reserved (all big-endian).
_FAT_HEADER = ">II"
_FAT_ARCH = ">iiIII"
_FAT_ARCH_64 = ">iiQQII"
# segment_command_64 after cmd/cmdsize: segname[16], vmaddr, vmsize, fileoff, filesize, maxprot,
# initprot, nsects, flags.
_SEGMENT_64 = "<16sQQQQiiII"
# dylib_command after cmd/cmdsize: name (lc_str offset), timestamp, current_version,
# compatibility_version.
_DYLIB = "<IIII"
# nlist_64: n_strx, n_type, n_sect, n_desc, n_value.
_NLIST_64 = "<IBBHQ"
# dyld_chained_fixups_header: fixups_version, starts_offset, imports_offset, symbols_offset,
# imports_count, imports_format, symbols_format.
_CHAINED_FIXUPS_HEADER = "<IIIIIII"
# CS_CodeDirectory (big-endian): magic, length, version, flags, hashOffset, identOffset,
# nSpecialSlots, nCodeSlots, codeLimit, hashSize, hashType, platform, pageSize, spare2; then
# (version >= 0x20100) scatterOffset, (>= 0x20200) teamOffset, (>= 0x20300) spare3, codeLimit64,
# (>= 0x20400) execSegBase, execSegLimit, execSegFlags.
_CODE_DIRECTORY = ">IIIIIIIIIBBBBI"


def macos_version(encoded: int) -> str:
    """X.Y.Z from the nibble encoding xxxx.yy.zz of version_min_command / build_version_command."""
    major, minor, patch = encoded >> 16, (encoded >> 8) & 0xFF, encoded & 0xFF
    return f"{major}.{minor}" + (f".{patch}" if patch else "")


def version_tuple(text: str) -> tuple[int, ...]:
    return tuple(int(p) for p in text.split("."))


@dataclass
class Segment:
    name: str
    vmaddr: int
    vmsize: int
    fileoff: int
    filesize: int


@dataclass
class CodeDirectory:
    slot: int  # the SuperBlob slot it came from (0, or 0x1000+ for an alternate)
    version: int
    flags: int
    identifier: str
    team_id: str | None
    hash_type: int
    hash_size: int
    page_size: int  # bytes (1 << pageSize; 0 when the field is 0: one page up to codeLimit)
    code_limit: int
    n_code_slots: int
    n_special_slots: int
    exec_seg_base: int | None
    exec_seg_limit: int | None
    exec_seg_flags: int | None
    cdhash: str  # hex, the CodeDirectory blob's hash truncated to 20 bytes
    pages_checked: int = 0
    mismatched_pages: list[int] = field(default_factory=list)
    special_slots_checked: int = 0
    mismatched_special_slots: list[int] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)

    @property
    def hash_name(self) -> str:
        return CS_HASHES.get(self.hash_type, (f"type {self.hash_type}",))[0]

    @property
    def adhoc(self) -> bool:
        return bool(self.flags & CS_ADHOC)

    @property
    def linker_signed(self) -> bool:
        return bool(self.flags & CS_LINKER_SIGNED)

    @property
    def valid(self) -> bool:
        return (
            not self.problems
            and self.pages_checked == self.n_code_slots > 0
            and not self.mismatched_pages
            and not self.mismatched_special_slots
        )


@dataclass
class CodeSignature:
    offset: int  # LC_CODE_SIGNATURE dataoff (from the slice's start)
    size: int
    directories: list[CodeDirectory]
    blob_types: list[int]  # the SuperBlob index's slot types
    has_cms: bool  # a CSSLOT_SIGNATURESLOT (CMS) blob is present; an ad-hoc signature has none

    @property
    def primary(self) -> CodeDirectory:
        return self.directories[0]

    @property
    def valid(self) -> bool:
        return bool(self.directories) and all(cd.valid for cd in self.directories)


@dataclass
class MachOSlice:
    offset: int  # of the slice in the file (0 for a thin file)
    size: int
    cputype: int
    cpusubtype: int
    filetype: int
    flags: int
    platform: int | None = None
    minos: str | None = None
    sdk: str | None = None
    version_source: str | None = None  # LC_BUILD_VERSION or LC_VERSION_MIN_MACOSX
    install_name: str | None = None
    dylibs: list[tuple[str, str]] = field(default_factory=list)  # (load command, path), in order
    rpaths: list[str] = field(default_factory=list)
    segments: list[Segment] = field(default_factory=list)
    exports: list[str] = field(default_factory=list)  # export trie, sorted
    exports_source: str | None = None
    symtab_exports: list[str] = field(default_factory=list)  # N_SECT|N_EXT, not N_PEXT
    imports: dict[str, str] = field(default_factory=dict)  # symbol -> library (path or special)
    code_signature: CodeSignature | None = None
    load_commands: list[int] = field(default_factory=list)

    @property
    def cpu_name(self) -> str:
        return CPU_NAMES.get(self.cputype, f"cputype {self.cputype:#x}")

    @property
    def platform_name(self) -> str | None:
        return None if self.platform is None else PLATFORMS.get(self.platform, f"platform {self.platform}")


@dataclass
class MachOFile:
    fat: bool
    slices: list[MachOSlice]

    format = "macho"

    @property
    def archs(self) -> list[str]:
        return [s.cpu_name for s in self.slices]

    def slice(self, arch: str) -> MachOSlice:
        for s in self.slices:
            if s.cpu_name == arch:
                return s
        raise KeyError(f"no {arch} slice (slices: {self.archs})")


def walk_export_trie(trie: bytes) -> list[tuple[str, int, int]]:
    """(name, flags, value) of every terminal of the export trie (mach-o/loader.h, dyld_info_command:
    a node is a ULEB128 terminal size, the terminal's flags and address (or ordinal and name for a
    re-export, stub and resolver for EXPORT_SYMBOL_FLAGS_STUB_AND_RESOLVER), a child count byte,
    then per child a NUL-terminated edge label and the ULEB128 offset of the child node)."""
    out: list[tuple[str, int, int]] = []
    if not trie:
        return out
    seen: set[int] = set()
    stack = [(0, b"")]
    end = len(trie)
    while stack:
        node, prefix = stack.pop()
        if node in seen:
            raise FormatError(f"export trie: node {node:#x} reached twice (a cycle or shared node)")
        if node >= end:
            raise FormatError(f"export trie: node offset {node:#x} outside the trie ({end:#x} bytes)")
        seen.add(node)
        terminal_size, pos = read_uleb128(trie, node, end)
        children_at = pos + terminal_size
        if children_at >= end:
            raise FormatError(f"export trie: node {node:#x} terminal info runs past the end")
        if terminal_size:
            flags, p = read_uleb128(trie, pos, children_at)
            if flags & EXPORT_SYMBOL_FLAGS_REEXPORT:
                value, p = read_uleb128(trie, p, children_at)  # library ordinal
                _cstring(trie, p, "export trie re-export name", children_at)
            else:
                value, p = read_uleb128(trie, p, children_at)  # address (or stub)
                if flags & EXPORT_SYMBOL_FLAGS_STUB_AND_RESOLVER:
                    _, p = read_uleb128(trie, p, children_at)  # resolver
            out.append((prefix.decode("utf-8", "replace"), flags, value))
        count = trie[children_at]
        pos = children_at + 1
        for _ in range(count):
            stop = trie.find(b"\0", pos)
            if stop < 0:
                raise FormatError(f"export trie: edge label at {pos:#x} is not NUL-terminated")
            label = trie[pos:stop]
            child, pos = read_uleb128(trie, stop + 1, end)
            if child == 0:
                raise FormatError(f"export trie: edge {prefix + label!r} points back at the root")
            stack.append((child, prefix + label))
    return sorted(out)


def _bind_opcode_symbols(stream: bytes) -> list[tuple[str, int]]:
    """(symbol, library ordinal) of every BIND_OPCODE_SET_SYMBOL_TRAILING_FLAGS_IMM in a bind,
    weak-bind or lazy-bind opcode stream (mach-o/loader.h, BIND_OPCODE_*)."""
    out = []
    ordinal = 0
    pos, end = 0, len(stream)
    while pos < end:
        byte = stream[pos]
        pos += 1
        op, imm = byte & 0xF0, byte & 0x0F
        if op == 0x00:  # DONE (lazy-bind streams hold one run per symbol)
            continue
        if op == 0x10:  # SET_DYLIB_ORDINAL_IMM
            ordinal = imm
        elif op == 0x20:  # SET_DYLIB_ORDINAL_ULEB
            ordinal, pos = read_uleb128(stream, pos, end)
        elif op == 0x30:  # SET_DYLIB_SPECIAL_IMM (0 or a negative, sign-extended)
            ordinal = imm - 16 if imm else 0
        elif op == 0x40:  # SET_SYMBOL_TRAILING_FLAGS_IMM
            name = _cstring(stream, pos, "bind opcode symbol")
            pos = stream.index(b"\0", pos) + 1
            out.append((name, ordinal))
        elif op == 0x50:  # SET_TYPE_IMM
            pass
        elif op == 0x60:  # SET_ADDEND_SLEB
            _, pos = read_sleb128(stream, pos, end)
        elif op in (0x70, 0x80, 0xA0):  # SET_SEGMENT_AND_OFFSET_ULEB, ADD_ADDR_ULEB, DO_BIND_ADD_ADDR_ULEB
            _, pos = read_uleb128(stream, pos, end)
        elif op in (0x90, 0xB0):  # DO_BIND, DO_BIND_ADD_ADDR_IMM_SCALED
            pass
        elif op == 0xC0:  # DO_BIND_ULEB_TIMES_SKIPPING_ULEB
            _, pos = read_uleb128(stream, pos, end)
            _, pos = read_uleb128(stream, pos, end)
        elif op == 0xD0:  # THREADED: SET_BIND_ORDINAL_TABLE_SIZE_ULEB (0) or APPLY (1)
            if imm == 0:
                _, pos = read_uleb128(stream, pos, end)
        else:
            raise FormatError(f"bind opcode {byte:#04x} at {pos - 1:#x} is unknown")
    return out


def chained_fixup_imports(fx: bytes) -> list[tuple[str, int, bool]]:
    """(symbol, library ordinal, weak) of every import of an LC_DYLD_CHAINED_FIXUPS payload
    (fixup-chains.h: dyld_chained_fixups_header; imports_format 1 = dyld_chained_import, a uint32
    lib_ordinal:8 weak_import:1 name_offset:23; 2 = dyld_chained_import_addend, the same plus an
    int32 addend; 3 = dyld_chained_import_addend64, a uint64 lib_ordinal:16 weak_import:1
    reserved:15 name_offset:32 plus a uint64 addend). Ordinals >= 0xF0 (0xFFF0) are the negative
    special ordinals (-1 main executable, -2 flat lookup, -3 weak lookup)."""
    (_, _, imports_offset, symbols_offset, imports_count, imports_format, symbols_format) = _unpack(
        _CHAINED_FIXUPS_HEADER, fx, 0, "dyld_chained_fixups_header")
    if symbols_format != 0:
        raise FormatError(f"chained fixups symbols_format {symbols_format}: only uncompressed (0) is supported")
    sizes = {1: 4, 2: 8, 3: 16}
    if imports_format not in sizes:
        raise FormatError(f"chained fixups imports_format {imports_format} is unknown")
    out = []
    for k in range(imports_count):
        at = imports_offset + k * sizes[imports_format]
        if imports_format == 3:
            (word,) = _unpack("<Q", fx, at, "dyld_chained_import_addend64")
            ordinal, weak, name_offset = word & 0xFFFF, bool(word >> 16 & 1), word >> 32
            ordinal = ordinal - 0x10000 if ordinal >= 0xFFF0 else ordinal
        else:
            (word,) = _unpack("<I", fx, at, "dyld_chained_import")
            ordinal, weak, name_offset = word & 0xFF, bool(word >> 8 & 1), word >> 9
            ordinal = ordinal - 0x100 if ordinal >= 0xF0 else ordinal
        out.append((_cstring(fx, symbols_offset + name_offset, f"chained import {k} name"), ordinal, weak))
    return out


def _verify_code_directory(sl: bytes, cd_at: int, slot: int, blobs: dict[int, bytes]) -> CodeDirectory:
    """Parses the CS_CodeDirectory at sl[cd_at:] and checks every code slot against the hash of
    its page of the slice (and every special slot whose blob is in the SuperBlob)."""
    (magic, length, version, flags, hash_offset, ident_offset, n_special, n_code, code_limit, hash_size,
     hash_type, _, page_shift, _) = _unpack(_CODE_DIRECTORY, sl, cd_at, "CS_CodeDirectory")
    if magic != CSMAGIC_CODEDIRECTORY:
        raise FormatError(f"CodeDirectory magic {magic:#x} != {CSMAGIC_CODEDIRECTORY:#x}")
    if cd_at + length > len(sl):
        raise FormatError(f"CodeDirectory length {length:#x} at {cd_at:#x} runs past the slice")
    cd = sl[cd_at : cd_at + length]
    fixed = struct.calcsize(_CODE_DIRECTORY)
    team_id = None
    code_limit64 = exec_base = exec_limit = exec_flags = None
    if version >= CS_SUPPORTSTEAMID:
        (team_offset,) = _unpack(">I", cd, fixed + 4, "CodeDirectory teamOffset")
        if team_offset:
            team_id = _cstring(cd, team_offset, "CodeDirectory team identifier")
    if version >= CS_SUPPORTSCODELIMIT64:
        (_, code_limit64) = _unpack(">IQ", cd, fixed + 8, "CodeDirectory codeLimit64")
    if version >= CS_SUPPORTSEXECSEG:
        exec_base, exec_limit, exec_flags = _unpack(">QQQ", cd, fixed + 20, "CodeDirectory execSeg")
    limit = code_limit64 if code_limit64 else code_limit
    page_size = (1 << page_shift) if page_shift else 0
    hash_name, expected_size, digest = CS_HASHES.get(hash_type, (None, None, None))
    result = CodeDirectory(
        slot=slot,
        version=version,
        flags=flags,
        identifier=_cstring(cd, ident_offset, "CodeDirectory identifier"),
        team_id=team_id,
        hash_type=hash_type,
        hash_size=hash_size,
        page_size=page_size,
        code_limit=limit,
        n_code_slots=n_code,
        n_special_slots=n_special,
        exec_seg_base=exec_base,
        exec_seg_limit=exec_limit,
        exec_seg_flags=exec_flags,
        cdhash=(digest(cd)[:20].hex() if digest else ""),
    )
    if digest is None:
        result.problems.append(f"unknown hashType {hash_type}")
        return result
    if hash_size != expected_size:
        result.problems.append(f"hashSize {hash_size} != {expected_size} for {hash_name}")
        return result
    if limit > len(sl):
        result.problems.append(f"codeLimit {limit:#x} beyond the slice's {len(sl):#x} bytes")
        return result
    pages = (-(-limit // page_size) if page_size else 1) if limit else 0
    if pages != n_code:
        result.problems.append(f"nCodeSlots {n_code} != {pages} pages of {page_size} bytes up to codeLimit {limit:#x}")
    if hash_offset - n_special * hash_size < 0 or hash_offset + n_code * hash_size > length:
        result.problems.append("hash slots outside the CodeDirectory")
        return result
    for i in range(min(pages, n_code)):
        start = i * page_size if page_size else 0
        stop = min(start + page_size, limit) if page_size else limit
        stored = cd[hash_offset + i * hash_size : hash_offset + (i + 1) * hash_size]
        result.pages_checked += 1
        if digest(sl[start:stop]) != stored:
            result.mismatched_pages.append(i)
    # special slots: slot -n holds the hash of the SuperBlob's blob of type n (or zeros if absent)
    for n in range(1, n_special + 1):
        stored = cd[hash_offset - n * hash_size : hash_offset - (n - 1) * hash_size]
        if n in blobs:
            result.special_slots_checked += 1
            if digest(blobs[n]) != stored:
                result.mismatched_special_slots.append(n)
    return result


def _parse_code_signature(sl: bytes, dataoff: int, datasize: int) -> CodeSignature:
    if dataoff + datasize > len(sl):
        raise FormatError(f"LC_CODE_SIGNATURE [{dataoff:#x}, +{datasize:#x}) runs past the slice")
    # CS_SuperBlob: magic, length, count, then count CS_BlobIndex {type, offset} (big-endian)
    magic, length, count = _unpack(">III", sl, dataoff, "CS_SuperBlob")
    if magic != CSMAGIC_EMBEDDED_SIGNATURE:
        raise FormatError(f"code signature SuperBlob magic {magic:#x} != {CSMAGIC_EMBEDDED_SIGNATURE:#x}")
    if length > datasize:
        raise FormatError(f"SuperBlob length {length:#x} > LC_CODE_SIGNATURE datasize {datasize:#x}")
    index = [_unpack(">II", sl, dataoff + 12 + 8 * i, "CS_BlobIndex") for i in range(count)]
    blobs: dict[int, bytes] = {}
    cd_offsets: list[tuple[int, int]] = []
    for slot_type, offset in index:
        if offset + 8 > length:
            raise FormatError(f"blob of slot {slot_type:#x} at {offset:#x} outside the SuperBlob")
        bmagic, blen = _unpack(">II", sl, dataoff + offset, "blob header")
        if offset + blen > length:
            raise FormatError(f"blob of slot {slot_type:#x} (length {blen:#x}) runs past the SuperBlob")
        blobs[slot_type] = sl[dataoff + offset : dataoff + offset + blen]
        alternate = CSSLOT_ALTERNATE_CODEDIRECTORIES <= slot_type < CSSLOT_ALTERNATE_CODEDIRECTORIES + 5
        if slot_type == CSSLOT_CODEDIRECTORY or alternate:
            if bmagic != CSMAGIC_CODEDIRECTORY:
                raise FormatError(f"slot {slot_type:#x} holds magic {bmagic:#x}, not a CodeDirectory")
            cd_offsets.append((slot_type, dataoff + offset))
    if not any(s == CSSLOT_CODEDIRECTORY for s, _ in cd_offsets):
        raise FormatError("code signature has no CodeDirectory in slot 0")
    cd_offsets.sort()
    special = {t: b for t, b in blobs.items() if 0 < t < CSSLOT_ALTERNATE_CODEDIRECTORIES}
    return CodeSignature(
        offset=dataoff,
        size=datasize,
        directories=[_verify_code_directory(sl, at, slot, special) for slot, at in cd_offsets],
        blob_types=[t for t, _ in index],
        has_cms=CSSLOT_SIGNATURESLOT in blobs,
    )


def _parse_macho_slice(data: bytes, offset: int, size: int) -> MachOSlice:
    sl = data[offset : offset + size]
    if len(sl) != size:
        raise FormatError(f"slice [{offset:#x}, +{size:#x}) runs past the end of the file")
    (magic,) = _unpack("<I", sl, 0, "mach header magic")
    if magic == MH_MAGIC:
        raise FormatError("32-bit Mach-O (MH_MAGIC) is not supported")
    if magic != MH_MAGIC_64:
        raise FormatError(f"slice at {offset:#x}: magic {magic:#x} is not MH_MAGIC_64 (64-bit little-endian)")
    _, cputype, cpusubtype, filetype, ncmds, sizeofcmds, flags, _ = _unpack(_MACH_HEADER_64, sl, 0, "mach_header_64")
    out = MachOSlice(offset=offset, size=size, cputype=cputype, cpusubtype=cpusubtype & 0x00FFFFFF,
                     filetype=filetype, flags=flags)
    header_size = struct.calcsize(_MACH_HEADER_64)
    if header_size + sizeofcmds > size:
        raise FormatError(f"sizeofcmds {sizeofcmds:#x} runs past the slice")
    end_of_cmds = header_size + sizeofcmds
    pos = header_size
    symtab = dyld_info = exports_trie = chained = None
    for i in range(ncmds):
        cmd, cmdsize = _unpack("<II", sl, pos, f"load command {i}")
        if cmdsize < 8 or pos + cmdsize > end_of_cmds:
            raise FormatError(f"load command {i} ({cmd:#x}) at {pos:#x}: cmdsize {cmdsize} out of bounds")
        body = sl[pos : pos + cmdsize]
        out.load_commands.append(cmd)
        if cmd in DYLIB_LOAD_COMMANDS or cmd == LC_ID_DYLIB:
            name_off = _unpack(_DYLIB, body, 8, "dylib_command")[0]
            name = _cstring(body, name_off, f"{DYLIB_LOAD_COMMANDS.get(cmd, 'LC_ID_DYLIB')} name")
            if cmd == LC_ID_DYLIB:
                out.install_name = name
            else:
                out.dylibs.append((DYLIB_LOAD_COMMANDS[cmd], name))
        elif cmd == LC_RPATH:
            out.rpaths.append(_cstring(body, _unpack("<I", body, 8, "rpath_command")[0], "LC_RPATH path"))
        elif cmd == LC_BUILD_VERSION:
            platform, minos, sdk, _ = _unpack("<IIII", body, 8, "build_version_command")
            if out.version_source is None:
                out.platform, out.minos, out.sdk = platform, macos_version(minos), macos_version(sdk)
                out.version_source = "LC_BUILD_VERSION"
        elif cmd == LC_VERSION_MIN_MACOSX:
            version, sdk = _unpack("<II", body, 8, "version_min_command")
            if out.version_source is None:
                out.platform, out.minos, out.sdk = PLATFORM_MACOS, macos_version(version), macos_version(sdk)
                out.version_source = "LC_VERSION_MIN_MACOSX"
        elif cmd == LC_SEGMENT_64:
            segname, vmaddr, vmsize, fileoff, filesize, *_ = _unpack(_SEGMENT_64, body, 8, "segment_command_64")
            out.segments.append(Segment(segname.rstrip(b"\0").decode("ascii", "replace"), vmaddr, vmsize,
                                        fileoff, filesize))
        elif cmd == LC_SYMTAB:
            symtab = _unpack("<IIII", body, 8, "symtab_command")  # symoff, nsyms, stroff, strsize
        elif cmd in (LC_DYLD_INFO, LC_DYLD_INFO_ONLY):
            dyld_info = _unpack("<10I", body, 8, "dyld_info_command")
        elif cmd == LC_DYLD_EXPORTS_TRIE:
            exports_trie = _unpack("<II", body, 8, "linkedit_data_command")
        elif cmd == LC_DYLD_CHAINED_FIXUPS:
            chained = _unpack("<II", body, 8, "linkedit_data_command")
        elif cmd == LC_CODE_SIGNATURE:
            dataoff, datasize = _unpack("<II", body, 8, "linkedit_data_command")
            out.code_signature = _parse_code_signature(sl, dataoff, datasize)
        pos += cmdsize

    def blob(off: int, length: int, what: str) -> bytes:
        if off + length > size:
            raise FormatError(f"{what} [{off:#x}, +{length:#x}) runs past the slice")
        return sl[off : off + length]

    # exports: the export trie
    if exports_trie is not None:
        trie, out.exports_source = blob(*exports_trie, "LC_DYLD_EXPORTS_TRIE"), "LC_DYLD_EXPORTS_TRIE"
    elif dyld_info is not None and dyld_info[9]:
        trie, out.exports_source = blob(dyld_info[8], dyld_info[9], "dyld_info export"), "LC_DYLD_INFO"
    else:
        trie = b""
    out.exports = [name for name, _, _ in walk_export_trie(trie)]

    def library(ordinal: int) -> str:
        specials = {0: "<self>", -1: "<main executable>", -2: "<flat lookup>", -3: "<weak lookup>"}
        if ordinal in specials:
            return specials[ordinal]
        if 1 <= ordinal <= len(out.dylibs):
            return out.dylibs[ordinal - 1][1]
        return f"<ordinal {ordinal}>"

    # imports: undefined external symbols, chained-fixup imports and bind-opcode symbols
    if symtab is not None:
        symoff, nsyms, stroff, strsize = symtab
        strtab = blob(stroff, strsize, "string table")
        entry = struct.calcsize(_NLIST_64)
        table = blob(symoff, nsyms * entry, "symbol table")
        symtab_exports = set()
        for k in range(nsyms):
            n_strx, n_type, _, n_desc, _ = struct.unpack_from(_NLIST_64, table, k * entry)
            if n_type & N_STAB or not n_type & N_EXT:
                continue
            name = _cstring(strtab, n_strx, f"nlist[{k}] name") if n_strx else ""
            if (n_type & N_TYPE) == N_UNDF:
                ordinal = (n_desc >> 8) & 0xFF
                out.imports[name] = library({0xFE: -2, 0xFF: -1}.get(ordinal, ordinal))
            elif (n_type & N_TYPE) == N_SECT and not n_type & N_PEXT:
                symtab_exports.add(name)
        out.symtab_exports = sorted(symtab_exports)
    if chained is not None and chained[1]:
        for name, ordinal, _ in chained_fixup_imports(blob(*chained, "LC_DYLD_CHAINED_FIXUPS")):
            out.imports.setdefault(name, library(ordinal))
    if dyld_info is not None:
        for off, length, what in ((dyld_info[2], dyld_info[3], "bind"), (dyld_info[4], dyld_info[5], "weak bind"),
                                  (dyld_info[6], dyld_info[7], "lazy bind")):
            if length:
                for name, ordinal in _bind_opcode_symbols(blob(off, length, f"{what} opcodes")):
                    out.imports.setdefault(name, library(ordinal))
    return out


def parse_macho(data: bytes) -> MachOFile:
    (magic_be,) = _unpack(">I", data, 0, "magic")
    if magic_be in (FAT_MAGIC, FAT_MAGIC_64):
        _, nfat = _unpack(_FAT_HEADER, data, 0, "fat_header")
        fmt = _FAT_ARCH if magic_be == FAT_MAGIC else _FAT_ARCH_64
        if nfat == 0 or nfat > 32:
            raise FormatError(f"fat_header nfat_arch = {nfat}")
        slices = []
        ranges = []
        for i in range(nfat):
            cputype, cpusubtype, offset, size, align, *_ = _unpack(
                fmt, data, 8 + i * struct.calcsize(fmt), f"fat_arch {i}")
            if align > 30 or offset % (1 << align):
                raise FormatError(f"fat_arch {i}: offset {offset:#x} not aligned to 2^{align}")
            sl = _parse_macho_slice(data, offset, size)
            if (sl.cputype, sl.cpusubtype) != (cputype, cpusubtype & 0x00FFFFFF):
                raise FormatError(f"fat_arch {i} says cputype {cputype:#x}, its slice says {sl.cputype:#x}")
            for lo, hi in ranges:
                if offset < hi and lo < offset + size:
                    raise FormatError(f"fat_arch {i} [{offset:#x}, +{size:#x}) overlaps another slice")
            ranges.append((offset, offset + size))
            slices.append(sl)
        return MachOFile(fat=True, slices=slices)
    return MachOFile(fat=False, slices=[_parse_macho_slice(data, 0, len(data))])


# --------------------------------------------------------------------------------------------------
# dispatch
# --------------------------------------------------------------------------------------------------


def detect(data: bytes) -> str | None:
    """'elf', 'pe', 'macho' (thin 64-bit or fat) or None, from the magic number."""
    if data[:4] == ELF_MAGIC:
        return "elf"
    if data[:2] == b"MZ":
        return "pe"
    if len(data) >= 4:
        (le,) = struct.unpack_from("<I", data, 0)
        (be,) = struct.unpack_from(">I", data, 0)
        if le in (MH_MAGIC_64, MH_MAGIC) or be in (MH_MAGIC_64, MH_MAGIC, FAT_MAGIC, FAT_MAGIC_64):
            return "macho"
    return None


def parse(data: bytes) -> ElfFile | PeFile | MachOFile:
    kind = detect(data)
    if kind == "elf":
        return parse_elf(data)
    if kind == "pe":
        return parse_pe(data)
    if kind == "macho":
        return parse_macho(data)
    raise FormatError(f"unknown format (first bytes {data[:8].hex()})")
