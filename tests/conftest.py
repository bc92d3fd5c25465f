"""Test configuration: headless matplotlib, one BLAS thread, opt-in slow tests, and the
paper's named flows shared by every test (``p1_flow``, ``flows("P4")``: solved once per
session from :data:`chuteflow.papers.mitarai2004.points.POINTS`).

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


@pytest.fixture(scope="session")
def flows():
    """The paper's named steady flows (§4.2: P1–P5 at φ = 0.05, Q1–Q3 at φ = 0.10), solved
    lazily once per session: ``flows("P3")``."""
    from chuteflow.closures import ChuteModel
    from chuteflow.papers.mitarai2004.points import POINTS
    from chuteflow.steady import solve_steady

    cache: dict = {}

    def get(name: str):
        if name not in cache:
            p = POINTS[name]
            cache[name] = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
        return cache[name]

    return get


@pytest.fixture(scope="session")
def p1_flow(flows):
    """The steady flow P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05), solved once per session."""
    return flows("P1")
