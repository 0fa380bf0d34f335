"""The reference results of tests/golden/golden.npz, recomputed: equal bit for bit unless a case is listed in
TOLERANCES (written by tests/golden/make_golden.py, whose ``scenarios()`` holds every call into armdyn)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.golden.make_golden import GOLDEN, compact, scenarios

SCENARIOS = scenarios()

# scenario name -> rtol, for a case whose order of additions had to change; say why beside each entry, e.g.
#   "dyn.puma560.rnea": 1e-14,  # the forward pass now sums the link forces in another order
# Many runs at once (simulate with runs=, and the studies built on it) vary from one process to the next by an
# ulp or two (4e-16 relative seen): the parallel loop's vectorized kernels take an aligned or unaligned path
# by where the allocator put each run's arrays, and the two round differently. One run is bit for bit.
TOLERANCES: dict[str, float] = {name: 1e-14 for name in SCENARIOS if name.startswith(("many.", "study."))}


def _stored() -> dict[str, dict[str, np.ndarray]]:
    cases: dict[str, dict[str, np.ndarray]] = {}
    with np.load(GOLDEN) as data:
        for key in data.files:
            name, _, array = key.partition("/")
            cases.setdefault(name, {})[array] = data[key]
    return cases


STORED = _stored()


def test_every_stored_case_has_its_scenario_and_back() -> None:
    assert sorted(STORED) == sorted(SCENARIOS)
    assert set(TOLERANCES) <= set(SCENARIOS)


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_scenario_reproduces_its_reference(name: str) -> None:
    expected = STORED[name]
    computed = compact(SCENARIOS[name]())
    assert sorted(computed) == sorted(expected), name
    for key, value in expected.items():
        message = f"{name}/{key}"
        if name in TOLERANCES and key != "shape" and not key.endswith(".shape"):
            np.testing.assert_allclose(computed[key], value, rtol=TOLERANCES[name], atol=0.0, err_msg=message)
        else:
            np.testing.assert_array_equal(computed[key], value, err_msg=message, strict=True)
