"""Point functions defined above the sweep layer resolve in a fresh process from their spec."""

from __future__ import annotations

import subprocess
import sys


def test_spec_carries_module_and_fresh_process_resolves_it():
    from chuteflow.reduced.diagram import Reduced1D

    spec = Reduced1D().spec()
    assert spec["module"] == "chuteflow.reduced.diagram"
    # a spawned worker or a Dask worker has imported only chuteflow.sweep
    code = (
        "import sys; from chuteflow.sweep.points import point_function; "
        f"f = point_function({spec!r}); "
        "assert 'chuteflow.reduced' in sys.modules; print(type(f).__name__)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "Reduced1D"
