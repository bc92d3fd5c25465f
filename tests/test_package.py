"""Package namespace and thread limiting."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import chuteflow


def test_version_is_a_string():
    assert isinstance(chuteflow.__version__, str)
    assert chuteflow.__version__


def test_import_is_light():
    code = (
        "import sys, chuteflow; heavy = [m for m in ('numpy', 'sympy', 'scipy', "
        "'matplotlib', 'rich', 'typer') if m in sys.modules]; print(','.join(heavy))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout.strip()
    assert out == "", f"import chuteflow loaded {out}"


def test_lazy_names():
    from chuteflow.closures import ChuteModel
    from chuteflow.errors import ParameterError

    assert chuteflow.ChuteModel is ChuteModel
    assert chuteflow.ParameterError is ParameterError
    assert "solve_steady" in dir(chuteflow)
    with pytest.raises(AttributeError, match="no_such_name"):
        chuteflow.no_such_name  # noqa: B018


def test_limit_blas_threads(monkeypatch):
    from threadpoolctl import threadpool_info

    from chuteflow._threads import limit_blas_threads

    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(var, raising=False)
    with limit_blas_threads():
        assert all(p["num_threads"] == 1 for p in threadpool_info() if p["user_api"] == "blas")
        assert os.environ["OPENBLAS_NUM_THREADS"] == "1"


def test_no_module_is_shadowed_by_a_name_of_its_package():
    """``import chuteflow.x.y`` gives the module y: no package re-exports a function or
    class under the name of one of its modules (``chuteflow.stability.dispersion`` was the
    function and hid the module)."""
    import importlib
    import pkgutil
    import types

    import chuteflow

    shadowed = []
    for info in pkgutil.walk_packages(chuteflow.__path__, "chuteflow."):
        if not info.ispkg:
            continue
        pkg = importlib.import_module(info.name)
        for sub in pkgutil.iter_modules(pkg.__path__):
            importlib.import_module(f"{info.name}.{sub.name}")
            if not isinstance(getattr(pkg, sub.name, None), types.ModuleType):
                shadowed.append(f"{info.name}.{sub.name}")
    assert not shadowed
