"""The kernels' scaffolding: named status codes, the one home of the small linear algebra and of
Numba's internals, named workspace fields, and the table that builds the public functions."""

from __future__ import annotations

import inspect
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

import armdyn as ad
from armdyn.dynamics import api, kernels, linalg, numba_compat, packed, status
from armdyn.dynamics.frames import WORLD

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ROOT / "src" / "armdyn"


def test_status_codes_are_distinct_and_decode_the_kernels() -> None:
    codes = {name: value for name, value in vars(status).items() if name.isupper()}
    per_argument = [status.WRONG_LENGTH + k for k in range(3)] + [status.NOT_FINITE + k for k in range(3)]
    values = per_argument + [v for name, v in codes.items() if name not in ("WRONG_LENGTH", "NOT_FINITE")]
    assert len(values) == len(set(values))
    arm = ad.models.puma560()
    model, q, tau = arm.packed, np.zeros(6), np.empty(6)
    assert kernels.inverse_dynamics(model, q, q, q, tau) == status.OK
    assert kernels.inverse_dynamics(model, q, q, np.zeros(5), tau) == status.WRONG_LENGTH + 2
    assert kernels.inverse_dynamics(model, np.full(6, np.inf), q, q, tau) == status.NOT_FINITE
    assert kernels.inertia_matrix(model, q, np.empty((6, 5))) == status.WRONG_SHAPE
    assert kernels.jacobian(model, q, 6, WORLD, np.empty((6, 6))) == status.BAD_LINK
    assert kernels.jacobian(model, q, 1, 7, np.empty((6, 6))) == status.BAD_FRAME
    assert kernels.SINGULAR_STATUS == status.SINGULAR


def test_kernels_write_no_bare_status_literal() -> None:
    pattern = re.compile(r"(status\s*[=!]=?\s*|return\s+)(?:[1-9]\d*)\s*$", re.M)
    for path in (SOURCES / "dynamics").glob("*.py"):
        assert not pattern.findall(path.read_text()), path.name


def test_numba_internals_are_touched_in_one_module_only() -> None:
    private = re.compile(r"_compile_for_args|_search_new_conversions|_explain_matching_error|_can_compile|"
                         r"_CacheLocator|_CacheImpl|_locator_classes|MethodType")  # fmt: skip
    homes = {p.relative_to(SOURCES).as_posix() for p in SOURCES.rglob("*.py") if private.search(p.read_text())}
    assert homes <= {"dynamics/numba_compat.py", "dynamics/cache.py"}, homes
    assert not re.search(r"_compile_for_args|MethodType|_CacheImpl", (SOURCES / "dynamics" / "cache.py").read_text())


def test_numba_is_pinned_to_the_supported_range() -> None:
    (low_major, low_minor), (high_major, high_minor) = numba_compat.SUPPORTED
    assert numba_compat.check_version()  # the installed Numba
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    pin = next(d for d in project["dependencies"] if d.startswith("numba"))
    assert pin == f"numba>={low_major}.{low_minor},<{high_major}.{high_minor}"
    with pytest.warns(RuntimeWarning, match=r"Numba 0\.59\.1 is installed"):
        assert not numba_compat.check_version("0.59.1")
    with pytest.warns(RuntimeWarning, match=r"install numba>="):
        assert not numba_compat.check_version(f"{high_major}.{high_minor}.0rc1")
    assert numba_compat.numba_version("0.68.1") == (0, 68)


def test_one_cholesky_and_its_solves() -> None:
    from numba import njit

    @njit
    def factor_and_solve(A: np.ndarray, X: np.ndarray) -> int:
        failed = linalg.cholesky(A)
        if failed < 0:
            linalg.cholesky_solve(A, X)
        return failed

    rng = np.random.default_rng(3)
    B = rng.normal(size=(5, 5))
    A = B @ B.T + 5 * np.eye(5)
    X = rng.normal(size=(5, 3))
    L, Y = A.copy(), X.copy()
    assert factor_and_solve(L, Y) == -1
    assert_allclose(Y, np.linalg.solve(A, X), rtol=1e-12)
    assert_allclose(np.tril(L), np.linalg.cholesky(A), rtol=1e-14)
    singular = A.copy()
    singular[3, :] = singular[:, 3] = 0.0
    assert factor_and_solve(singular, X.copy()) == 3
    pattern = re.compile(r"sqrt\((?:d|total|s|pivot)\)")  # a pivot's square root: only linalg factors a matrix
    sources = [*(SOURCES / "dynamics").glob("*.py"), SOURCES / "simulation.py"]
    homes = {p.name for p in sources if pattern.search(p.read_text())}
    assert homes <= {"linalg.py", "drives.py", "regressor.py"}, homes  # drives: the orifice law; regressor: NumPy


def test_workspace_sizes_follow_from_their_fields() -> None:
    assert packed.fields(12, 6, 6) == (0, 12, 18, 24)
    assert packed.RNEA_JOINT == packed.RNEA_FORCE + packed.SPATIAL
    assert packed.ABA_JOINT == packed.ABA_PIVOT + 2
    assert max(packed.ABA_JOINT, packed.CORIOLIS_JOINT, packed.ENERGY_JOINT) <= packed.WORK_PER_JOINT
    assert (packed.RNEA_JOINT, packed.GRAVITY_JOINT, packed.CORIOLIS_JOINT, packed.ABA_JOINT) == (30, 21, 64, 98)
    assert (packed.ENERGY_JOINT, packed.DERIVATIVE_JOINT) == (30, 88)


def test_public_functions_come_from_the_table() -> None:
    for name, row in api.TABLE.items():
        function = getattr(api, name)
        assert function.__module__ == "armdyn.dynamics.api"
        assert function.__doc__ and "Parameters" in function.__doc__
        parameters = list(inspect.signature(function).parameters)
        assert parameters[0] == "arm" and parameters[-1] == "out"
        assert f"_{name}_one(arm.packed" in api.SOURCES[name]
        assert getattr(api, f"_{name}_one") is row.one
    arm = ad.models.puma560()
    q = np.linspace(-1, 1, 6)
    assert_array_equal(api.inertia_matrix(arm, q), api.inertia_matrix(arm, q[None])[0])
    assert_array_equal(api.jacobian(arm, list(q), "tool", 2), api.jacobian(arm, q, frame="tool", link=2))
    with pytest.raises(ad.ModelError, match="q must have shape"):
        api.forward_dynamics(arm, q[:5], q, q)
