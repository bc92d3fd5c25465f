"""Test configuration: headless matplotlib, one BLAS thread, opt-in slow tests.

Tests marked ``@pytest.mark.slow`` are skipped unless ``--runslow`` is given or the
marker expression selects them (``-m slow``). The marker is registered in pyproject.toml
(``[tool.pytest.ini_options]``, with ``--strict-markers``).
"""

from __future__ import annotations

import os

# Before numpy is imported anywhere: one BLAS/OpenMP thread unless the caller chose.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import matplotlib  # noqa: E402

matplotlib.use("Agg", force=True)

import pytest  # noqa: E402


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--runslow", action="store_true", default=False, help="also run tests marked slow")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--runslow") or "slow" in (config.getoption("-m") or ""):
        return
    skip = pytest.mark.skip(reason="slow test: use --runslow or -m slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
