"""SteadyFlow compares and hashes by value, and records its model in summaries and Datasets.

No physics numbers: identities of the result object (the solver is deterministic, so the same
call gives the same arrays bit for bit).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from chuteflow.closures import ChuteModel
from chuteflow.steady import solve_steady

CS = ChuteModel(radial="carnahan_starling")


def test_equal_flows_compare_and_hash_equal():
    a, b = solve_steady(16.0, 0.05), solve_steady(16.0, 0.05)
    assert a is not b
    assert a == b
    assert hash(a) == hash(b)
    assert {a: 1}[b] == 1
    assert (a != b) is False


def test_different_flows_differ():
    a = solve_steady(16.0, 0.05)
    c = solve_steady(16.0, 0.05, CS)
    assert a != c
    assert hash(a) != hash(c)
    assert a != solve_steady(16.0, 0.06)
    shifted = dataclasses.replace(a, u=a.u + 1e-12)  # same labels, other profile
    assert shifted != a
    assert hash(shifted) == hash(a)
    assert a != "not a flow"
    nan = dataclasses.replace(a, convergence=float("nan"))
    assert nan == dataclasses.replace(a, convergence=float("nan"))  # NaN fields compare equal


def test_summary_and_dataset_record_the_model():
    c = solve_steady(16.0, 0.05, CS)
    s = c.to_dict()
    assert {k: s[k] for k in CS.to_dict()} == CS.to_dict()
    ds = c.to_xarray()
    assert ChuteModel.from_dict({k: ds.attrs[k] for k in CS.to_dict()}) == CS
    assert np.array_equal(ds["nu"].values, c.nu)
