"""Start-up of the command line (issue 9, item 5): a fresh process per call.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``). Run alone: ``python benchmarks/bench_startup.py``.

- ``startup_steady_json``: median wall time of ``python -m chuteflow steady --theta 16
  --nu0 0.05 --json`` with a warm code cache (chuteflow/_codegen.py). Target < 0.5 s.
- ``startup_eig``: the same for ``eig --theta 16 --nu0 0.05 --k 0.005``. Target < 1 s.

Baseline: the same command with the code cache disabled (``CHUTEFLOW_CACHE_DIR=off``), so
that sympy derives and lambdifies the closures and equations again, as every process did
before the cache. The note gives the median CPU time of the child processes too (less
sensitive to other jobs on a shared machine) and ``python -c pass`` as the floor.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

COMMANDS = {
    "startup_steady_json": (["steady", "--theta", "16", "--nu0", "0.05", "--json"], 0.5),
    "startup_eig": (["eig", "--theta", "16", "--nu0", "0.05", "--k", "0.005"], 1.0),
}


def _time(argv, repeat, env):
    walls, cpus = [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, *argv], env=env, check=True, capture_output=True)
        walls.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def run(quick: bool = False) -> list[dict]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    cold_env = dict(env, CHUTEFLOW_CACHE_DIR="off")
    repeat = 3 if quick else 7
    floor, floor_cpu = _time(["-c", "pass"], repeat, env)
    rows = []
    for name, (args, target) in COMMANDS.items():
        argv = ["-m", "chuteflow", *args]
        _time(argv, 1, env)  # fills the cache if it is cold
        wall, cpu = _time(argv, repeat, env)
        base, base_cpu = _time(argv, 1 if quick else 2, cold_env)
        rows.append(
            {
                "name": name,
                "seconds": wall,
                "baseline_seconds": base,
                "ratio": base / wall,
                "note": f"chuteflow {' '.join(args)}; CPU {cpu:.2f} s (baseline without the code "
                f"cache: {base_cpu:.2f} s CPU); python -c pass {floor:.2f} s wall, "
                f"{floor_cpu:.2f} s CPU; target < {target:g} s wall",
            }
        )
    return rows


if __name__ == "__main__":
    import json

    print(json.dumps(run(quick="--quick" in sys.argv), indent=1))
