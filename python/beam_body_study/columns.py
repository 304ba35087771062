"""The columns of a study's table, as `beam-body study` writes their headers.

A column with a unit is headed `name [unit]` (`peak_M [N.m]`); `case`, `status`, `message`,
`steps` and the dimensionless ones are bare. A user names a column by its bare name, or by the
whole header: `find` accepts both, so that nobody has to type a unit on the command line.
"""

from __future__ import annotations

import re

from .errors import StudyError

_HEADER = re.compile(r"^(?P<name>.*?) \[(?P<unit>[^\]]*)\]$")


def bare(header: str) -> str:
    """`peak_M [N.m]` -> `peak_M`; a bare header is its own name."""
    m = _HEADER.match(header)
    return m.group("name") if m else header


def unit(header: str) -> str | None:
    """`peak_M [N.m]` -> `N.m`; None for a bare header."""
    m = _HEADER.match(header)
    return m.group("unit") if m else None


def find(headers, wanted: str, option: str) -> str:
    """The header that `wanted` names (the whole header, or its bare name). Else a StudyError
    naming the option, the name and every column, so that the user can pick one."""
    headers = list(headers)
    if wanted in headers:
        return wanted
    # Case matters: `m` (the beam's mass per length) and `M2` are different parameters.
    matches = [h for h in headers if bare(h) == bare(wanted)]
    if len(matches) == 1:
        return matches[0]
    listed = ", ".join(headers)
    raise StudyError(f"{option} {wanted}: the table has no such column; its columns are "
                     f"{listed} (the unit in brackets may be left out)")


_SUPERSCRIPT = str.maketrans("23", "²³")


def pretty_unit(text: str) -> str:
    """The CSV's ASCII unit for a picture: `N.m2` -> `N·m²`, `m/s2` -> `m/s²`."""
    text = text.replace(".", "·")
    return re.sub(r"(?<=[A-Za-z])([23])(?![0-9])", lambda m: m.group(1).translate(_SUPERSCRIPT),
                  text)


def label(header: str) -> str:
    """An axis label: the bare name and the unit, drawn as a person writes it."""
    u = unit(header)
    return f"{bare(header)} [{pretty_unit(u)}]" if u else header
