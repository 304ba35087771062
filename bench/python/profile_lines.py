"""Instructions per accepted step by source line of ours (`cargo xtask profile --lines`).

callgrind_annotate credits an instruction to the line its debug information names, which for
an inlined nalgebra or std operation is a line of nalgebra or std. Here each instruction goes
instead to the innermost line of our own `src/` in its inline chain (addr2line -i), so that
`a + b` on two vectors counts for the line of ours that wrote it.

Usage: profile_lines.py BINARY SCENE.toml [--formulation F] [--rtol X] [--top N]
(the binary built with line tables, as `cargo xtask profile` builds it).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

from profile_step import arguments, run_callgrind

#: A cost line of `positions: instr line`: the address (absolute, relative or the same), the
#: line (likewise) and the cost.
POSITION = re.compile(r"^(0x[0-9a-fA-F]+|[+-]\d+|\*)\s+(?:0x[0-9a-fA-F]+|[+-]\d+|\*|\d+)\s+(\d+)$")


def self_costs(path: Path, binary: Path) -> dict[int, int]:
    """Self cost (Ir) per instruction address in `binary` of a callgrind file written with
    --dump-instr=yes (the other objects' instructions, libc's and the loader's, left out)."""
    costs: dict[int, int] = defaultdict(int)
    names: dict[str, str] = {}
    addr = 0
    skip_next = False
    ours = False
    for line in path.read_text().splitlines():
        if not line or line[0].isalpha():
            # ob= names the object of the lines that follow (compressed: "(id) name" once,
            # then "(id)"). The cost line after calls= is an inclusive cost of the call, not
            # this address's own.
            m = re.match(r"c?ob=\((\d+)\)(?: (.*))?", line)
            if m and m.group(2):
                names[m.group(1)] = m.group(2)
            if m and line.startswith("ob="):
                ours = Path(names.get(m.group(1), "")).resolve() == binary
            skip_next = line.startswith("calls=")
            continue
        m = POSITION.match(line)
        if not m:
            continue
        pos = m.group(1)
        if pos.startswith("0x"):
            addr = int(pos, 16)
        elif pos != "*":
            addr += int(pos)
        if skip_next:
            skip_next = False
            continue
        if ours and m.group(2) is not None:
            costs[addr] += int(m.group(2))
    return costs


def load_base(binary: Path, cg: Path) -> int:
    """The difference between run-time and file addresses (PIE): from the address the
    callgrind file gives `main` and the one nm gives."""
    nm = subprocess.run(["nm", str(binary)], capture_output=True, text=True, check=True).stdout
    file_main = next(int(a, 16) for a, _, n in (l.split() for l in nm.splitlines()
                                                if len(l.split()) == 3) if n == "main")
    names: dict[str, str] = {}
    current = ""
    for line in cg.read_text().splitlines():
        m = re.match(r"(c?fn)=\((\d+)\)(?: (.*))?", line)
        if m:
            if m.group(3):
                names[m.group(2)] = m.group(3)
            if m.group(1) == "fn":
                current = names.get(m.group(2), "")
            continue
        m = POSITION.match(line)
        if current == "main" and m and m.group(1).startswith("0x"):
            return int(m.group(1), 16) - file_main
    raise SystemExit("main not found in the callgrind output")


def main() -> int:
    ap = arguments()
    ap.add_argument("--top", type=int, default=60)
    args = ap.parse_args()
    binary = Path(args.binary).resolve()
    with tempfile.TemporaryDirectory() as tmp:
        out, steps = run_callgrind(binary, Path(args.scene).resolve(), args.formulation,
                                   args.rtol, Path(tmp), ["--dump-instr=yes"])
        costs = self_costs(out, binary)
        base = load_base(binary, out)
    addrs = sorted(costs)
    # -a prints each address before its inline chain (innermost frame first).
    resolved = subprocess.run(["addr2line", "-a", "-i", "-e", str(binary)],
                              input="".join(f"{a - base:x}\n" for a in addrs),
                              capture_output=True, text=True, check=True).stdout.splitlines()
    chains: list[list[str]] = []
    for line in resolved:
        if line.startswith("0x"):
            chains.append([])
        else:
            chains[-1].append(line)
    by_line: dict[str, int] = defaultdict(int)
    for addr, chain in zip(addrs, chains, strict=True):
        ours = next((c for c in chain if "/src/" in c and "/rustc/" not in c
                     and ".cargo" not in c), chain[0] if chain else "??")
        by_line[ours.split(" (")[0]] += costs[addr]
    total = sum(by_line.values())
    print(f"{steps} accepted steps; {total / steps:,.0f} instructions per step in all\n")
    print("| instructions per step | line | source |")
    print("|---|---|---|")
    for where, count in sorted(by_line.items(), key=lambda kv: -kv[1])[:args.top]:
        src = ""
        m = re.match(r"(.*):(\d+)", where)
        if m and Path(m.group(1)).exists():
            lines = Path(m.group(1)).read_text().splitlines()
            n = int(m.group(2))
            if 0 < n <= len(lines):
                src = lines[n - 1].strip().replace("|", "\\|")[:90]
        short = re.sub(r".*/src/", "src/", where)
        print(f"| {count / steps:,.1f} | {short} | `{src}` |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
