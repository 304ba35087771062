"""The source's layout rules (ARCHITECTURE.md; issue 45): no import cycle between the modules of src/
(the library) or of xtask/src/, no file of src/ over 750 lines before its tests, and the two front
documents short: README.md a front page of at most 250 lines, ARCHITECTURE.md a map of at most 300.

An import is a path `crate::a::b` or `super::...` in the code (comments and tests left out), taken to
the deepest module it names; a module's own parent or children do not count (a parent declares its
children, a child uses its parent's items). A cycle through three or more modules counts as well as one
through two.
"""

from __future__ import annotations

import os
import re
from collections import defaultdict

import pytest

from conftest import REPO

MAX_LINES = 750


def modules(root) -> dict:
    """{module path (tuple): file} of the crate under `root`, without its binaries."""
    found = {}
    for dirpath, _, files in os.walk(root):
        for name in files:
            if not name.endswith(".rs"):
                continue
            path = os.path.join(dirpath, name)
            parts = os.path.relpath(path, root)[:-3].split(os.sep)
            if parts[-1] in ("mod", "lib", "main"):
                parts = parts[:-1]
            if parts and parts[0] == "bin":
                continue
            found[tuple(parts)] = path
    return found


def code(path) -> str:
    """The file before its tests, without comments."""
    text = open(path, encoding="utf-8").read().split("#[cfg(test)]")[0]
    return re.sub(r"//[^\n]*", "", text)


def imports(found: dict) -> dict:
    """{module: the modules it imports}."""

    def resolve(current, path):
        parts = path.split("::")
        if parts[0] == "crate":
            base, parts = [], parts[1:]
        elif parts[0] == "self":
            base, parts = list(current), parts[1:]
        else:
            base = list(current[:-1])
            parts = parts[1:]
            while parts and parts[0] == "super":
                base, parts = base[:-1], parts[1:]
        for k in range(len(parts), 0, -1):
            if tuple(base + parts[:k]) in found:
                return tuple(base + parts[:k])
        return None

    graph = defaultdict(set)
    for module, path in found.items():
        for m in re.finditer(r"\b((?:crate|super|self)(?:::[A-Za-z_]\w*)+)", code(path)):
            target = resolve(module, m.group(1))
            if target and module[: len(target)] != target and target[: len(module)] != module:
                graph[module].add(target)
    return graph


def cycles(graph: dict) -> list:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append("::".join(w))
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in list(graph):
        if v not in index:
            visit(v)
    return out


@pytest.mark.parametrize("root", ["src", "xtask/src"])
def test_no_import_cycles(root):
    found = modules(REPO / root)
    assert len(found) > 5, found
    assert not cycles(imports(found)), cycles(imports(found))


def test_the_detector_sees_a_cycle():
    graph = {("a",): {("b",)}, ("b",): {("c",)}, ("c",): {("a",)}, ("d",): {("a",)}}
    assert cycles(graph) == [["a", "b", "c"]]


def test_no_source_file_is_over_750_lines_before_its_tests():
    long = {}
    for dirpath, _, files in os.walk(REPO / "src"):
        for name in files:
            if name.endswith(".rs"):
                path = os.path.join(dirpath, name)
                text = open(path, encoding="utf-8").read().split("#[cfg(test)]")[0]
                n = text.count("\n")
                if n > MAX_LINES:
                    long[os.path.relpath(path, REPO)] = n
    assert not long, long


@pytest.mark.parametrize("name,limit", [("README.md", 250), ("ARCHITECTURE.md", 300)])
def test_the_front_documents_stay_short(name, limit):
    """History and long measurements belong in docs/; these two are read first."""
    lines = (REPO / name).read_text(encoding="utf-8").count("\n")
    assert lines <= limit, f"{name} has {lines} lines; at most {limit} (move detail to docs/)"

