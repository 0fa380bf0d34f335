"""The reference results of tests/golden/golden.npz, recomputed: equal bit for bit unless a case is listed in
TOLERANCES (written by tests/golden/make_golden.py, whose ``scenarios()`` holds every call into armdyn)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.golden.make_golden import GOLDEN, compact, scenarios

SCENARIOS = scenarios()

# scenario name -> tolerance relative to each array's largest entry, where a result may not repeat bit for bit.
TOLERANCES: dict[str, float] = {
    # A run's compiled loop freshly compiled in this process and the same loop loaded from Numba's cache differ
    # in the last bits for some laws (PD plus gravity, the exact Coulomb law: 5e-15 relative seen through 0.5 s
    # of closed loop, 3e-14 under an adaptive solver, whose steps those bits steer); so do many runs at once
    # between processes (4e-16 seen). Which of the two a test gets depends on the order the tests ran in.
    **{name: 1e-13 for name in SCENARIOS if name.startswith(("sim.", "drives.", "many.", "study."))},
    **{name: 1e-11 for name in SCENARIOS if name.startswith("sim.") and "rk" in name.rsplit(".", 1)[1]},
    # One Cholesky factorization serves every kernel now (dynamics/linalg.py), dividing by the pivots as the
    # simulation always did; the derivative and operational-space kernels multiplied by stored reciprocals.
    # One-shot quantities moved by about one ulp (1e-15 relative seen).
    **{name: 1e-14 for name in SCENARIOS if name.startswith("taskdyn.") or name.endswith(".fd_derivatives")},
    # The same change in task-space control, through 0.5 s of closed loop: 6e-13 relative seen (in the
    # accelerations and the task error, small against their largest values) ...
    **{name: 1e-11 for name in SCENARIOS if name.startswith("task.")},
    # ... and with the adaptive rk45, whose step sequence the last bits steer (1.1e-6 relative seen in the task
    # error, 3e-10 in q: within the solver's own tolerances, rtol 1e-8 and atol 1e-10).
    "task.puma560.osc_line_rk45": 1e-5,
}


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
            scale = float(np.max(np.abs(value))) if value.size else 0.0  # relative to the array's largest entry
            np.testing.assert_allclose(computed[key], value, rtol=0.0, atol=TOLERANCES[name] * scale, err_msg=message)
        else:
            np.testing.assert_array_equal(computed[key], value, err_msg=message, strict=True)
