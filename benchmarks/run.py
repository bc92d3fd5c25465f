"""Run chuteflow's benchmarks and print a table.

Every ``benchmarks/bench_*.py`` module has ``run(quick: bool) -> list[dict]``; each row has
``name``, ``seconds``, ``baseline_seconds``, ``ratio`` (baseline / chuteflow unless the
module's note says otherwise) and ``note``. Benchmarks measure wall time on this machine:
run them on an otherwise idle machine (e.g. ``nice python benchmarks/run.py``) and compare
ratios, not seconds, across machines.

Usage::

    python benchmarks/run.py [--quick] [--json FILE] [NAME ...]

NAME selects modules (``steady`` for ``bench_steady.py``) or rows whose name contains it.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for p in (ROOT / "src", ROOT):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

KEYS = ("name", "seconds", "baseline_seconds", "ratio", "note")


def discover() -> list[str]:
    """Names of the benchmark modules (``bench_<name>.py``), sorted."""
    return sorted(p.stem[len("bench_") :] for p in (ROOT / "benchmarks").glob("bench_*.py"))


def run_module(name: str, quick: bool) -> list[dict]:
    """Import ``benchmarks/bench_<name>.py`` and run it; a failure becomes one row."""
    t0 = time.perf_counter()
    try:
        mod = importlib.import_module(f"benchmarks.bench_{name}")
        rows = list(mod.run(quick=quick))
    except Exception as exc:  # reported as a row, the others still run
        traceback.print_exc()
        return [
            {
                "name": f"{name}: FAILED",
                "seconds": math.nan,
                "baseline_seconds": math.nan,
                "ratio": math.nan,
                "note": f"{type(exc).__name__}: {exc}",
            }
        ]
    for r in rows:
        missing = [k for k in KEYS if k not in r]
        if missing:
            raise ValueError(f"bench_{name}: row {r.get('name')!r} lacks {missing}")
        r.setdefault("module", name)
    print(f"[{name}: {time.perf_counter() - t0:.1f} s]", file=sys.stderr)
    return rows


def _fmt(v, spec):
    return "–" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def print_table(rows: list[dict]) -> None:
    try:
        from rich.console import Console
        from rich.table import Table
    except ImportError:  # pragma: no cover
        for r in rows:
            print(r)
        return
    t = Table(title="chuteflow benchmarks")
    for col, just in (
        ("benchmark", "left"),
        ("chuteflow (s)", "right"),
        ("baseline (s)", "right"),
        ("ratio", "right"),
        ("note", "left"),
    ):
        t.add_column(col, justify=just, overflow="fold")
    for r in rows:
        t.add_row(
            r["name"],
            _fmt(r["seconds"], ".4g"),
            _fmt(r["baseline_seconds"], ".4g"),
            _fmt(r["ratio"], ".3g"),
            str(r["note"]),
        )
    Console(width=160).print(t)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="modules or row names to run (default: all)")
    ap.add_argument("--quick", action="store_true", help="smaller problems (CI smoke run)")
    ap.add_argument("--json", type=Path, help="also write the rows to this JSON file")
    args = ap.parse_args(argv)
    mods = discover()
    names = args.names
    wanted = [m for m in mods if not names or any(n == m for n in names)]
    by_row = bool(names) and not wanted  # NAME is part of a row name: run all, filter
    if by_row:
        wanted = mods
    rows = []
    for m in wanted:
        rows += run_module(m, args.quick)
    if by_row:
        rows = [r for r in rows if any(n in r["name"] for n in names)]
    print_table(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=float))
    return 1 if any("FAILED" in r["name"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
