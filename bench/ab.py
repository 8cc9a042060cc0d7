"""A/B comparison: the same benchmark rows on two checkouts, run alternately.

Each benchmark row compares a path with its own floor in the same process (a ratio); this
script runs chosen row functions of the ``bench/`` modules in two checkouts, each with its own
virtual environment (``<checkout>/.venv/bin/python``), alternating the two from round to round
(``A B``, then ``B A``, ...) so that a change of the machine's load falls on both, and reports
for every ratio of every row (the ``1.42x`` figures of its text) the median and the range over
the rounds in each checkout.

    python bench/ab.py /path/to/base [--new .] [--rounds 3] [--json out.json] \\
        public:inverse_rows:delta dynamics:robot_rows:gough_stewart dynamics:control_loop_rows

A row function is named ``module:function[:arg...]`` (arguments as Python literals, else
strings); it runs in a fresh process of the checkout, with ``<checkout>/bench`` first on the path
and the checkout as working directory, and returns the module's rows (benchmark, figure,
target).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

RUNNER = """
import ast, importlib, json, os, sys
tree, spec = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(tree, "bench"))
mod, fn, *args = spec.split(":")
def lit(s):
    try:
        return ast.literal_eval(s)
    except (ValueError, SyntaxError):
        return s
load = os.getloadavg()[0]
rows = getattr(importlib.import_module(mod), fn)(*map(lit, args))
print("@@AB@@" + json.dumps({"rows": [list(r) for r in rows], "load": load}))
"""

RATIO = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?)x(?!\w)")
"""A ratio in a row's figure: ``1.42x``."""


def run(tree: Path, spec: str) -> dict[str, object]:
    """The rows of ``spec`` in the checkout ``tree`` (a fresh process of its environment)."""
    python = tree / ".venv" / "bin" / "python"
    proc = subprocess.run(
        [str(python), "-c", RUNNER, str(tree), spec],
        cwd=tree,
        capture_output=True,
        text=True,
        check=False,
    )
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith("@@AB@@"):
            return json.loads(line[6:])  # type: ignore[no-any-return]
    raise RuntimeError(f"{spec} failed in {tree}:\n{proc.stderr[-2000:]}")


def ratios(figure: str) -> list[float]:
    """The ratios (``1.42x``) of a row's figure, in order."""
    return [float(m) for m in RATIO.findall(figure)]


def summary(values: list[float]) -> str:
    """Median and range: ``1.42x (1.38-1.47)``."""
    if not values:
        return "-"
    med = statistics.median(values)
    return f"{med:.2f}x ({min(values):.2f}-{max(values):.2f})"


def report(results: dict[str, dict[str, list[dict[str, object]]]]) -> str:
    """A markdown table: every ratio of every row, median and range in each checkout."""
    lines = ["| row | ratio | A (base) | B (new) | B / A |", "|---|---|---|---|---|"]
    for sides in results.values():
        runs_a, runs_b = sides["A"], sides["B"]
        n_rows = min(len(r["rows"]) for r in runs_a + runs_b)  # type: ignore[arg-type]
        for i in range(n_rows):
            label = str(runs_b[0]["rows"][i][0])  # type: ignore[index]
            per_a = [ratios(str(r["rows"][i][1])) for r in runs_a]  # type: ignore[index]
            per_b = [ratios(str(r["rows"][i][1])) for r in runs_b]  # type: ignore[index]
            n = min(len(x) for x in per_a + per_b)
            for j in range(n):
                a = [x[j] for x in per_a]
                b = [x[j] for x in per_b]
                change = statistics.median(b) / statistics.median(a) if statistics.median(a) else 0
                lines.append(
                    f"| {label[:90]} | {j + 1} | {summary(a)} | {summary(b)} | {change:.3f} |"
                )
    loads = [
        float(r["load"])  # type: ignore[arg-type]
        for sides in results.values()
        for runs in sides.values()
        for r in runs
    ]
    if loads:
        lines.append("")
        lines.append(f"Load average at the runs' starts: {min(loads):.1f} to {max(loads):.1f}.")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("base", type=Path, help="the base checkout (A), with its .venv")
    parser.add_argument("specs", nargs="+", help="row functions: module:function[:arg...]")
    parser.add_argument("--new", type=Path, default=Path(__file__).resolve().parents[1])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", type=Path, help="write every run's rows there")
    args = parser.parse_args(argv)
    trees = {"A": args.base.resolve(), "B": args.new.resolve()}
    results: dict[str, dict[str, list[dict[str, object]]]] = {
        s: {"A": [], "B": []} for s in args.specs
    }
    for k in range(args.rounds):
        for spec in args.specs:
            for side in "AB" if k % 2 == 0 else "BA":
                out = run(trees[side], spec)
                results[spec][side].append(out)
                figs = "; ".join(str(r[1])[:70] for r in out["rows"])  # type: ignore[attr-defined]
                print(f"round {k + 1} {side} {spec}: {figs}", file=sys.stderr, flush=True)
            if args.json:
                tmp = args.json.with_name(args.json.name + ".tmp")
                tmp.write_text(json.dumps({"trees": {s: str(p) for s, p in trees.items()},
                                           "results": results}, indent=1))  # fmt: skip
                os.replace(tmp, args.json)
    print(report(results))


if __name__ == "__main__":
    main()
