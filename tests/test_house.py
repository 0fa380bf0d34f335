"""The structure of the package: imports point one way, the model is never written, the
Robot never changes after construction, and the kernel cache cannot go stale."""

from __future__ import annotations

import ast
import json
import pickle
import re
import shutil
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn.control import ComputedTorque, PDGravity
from armdyn.dynamics import cache
from armdyn.trajectories import Sinusoid

SOURCE = Path(ad.__file__).resolve().parent


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SOURCE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(path): path for path in sorted(SOURCE.rglob("*.py"))}


def _type_checking_lines(tree: ast.Module) -> set[int]:
    """Lines inside `if TYPE_CHECKING:` blocks (type-only imports)."""
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, (child.end_lineno or child.lineno) + 1))
    return lines


def imports_of(module: str) -> set[str]:
    """armdyn modules that ``module`` imports anywhere in its body (module level or inside
    functions), type-only imports excepted."""
    tree = ast.parse(MODULES[module].read_text())
    skipped = _type_checking_lines(tree)
    found: set[str] = set()
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skipped:
            continue
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name in MODULES)
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("armdyn"):
            for alias in node.names:
                candidate = f"{node.module}.{alias.name}"
                found.add(candidate if candidate in MODULES else node.module)
    found.discard(module)
    return found


def test_no_import_cycle_in_the_package() -> None:
    """Depth-first search for a cycle; lazy imports inside functions count as edges too."""
    graph = {module: imports_of(module) for module in MODULES}
    state: dict[str, str] = {}

    def visit(module: str, path: list[str]) -> None:
        state[module] = "open"
        for target in sorted(graph[module]):
            if state.get(target) == "open":
                cycle = [*path[path.index(target) :], target] if target in path else [module, target]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if target not in state:
                visit(target, [*path, target])
        state[module] = "done"

    for module in graph:
        if module not in state:
            visit(module, [module])


def test_model_layer_imports_numpy_and_errors_only() -> None:
    for module in MODULES:
        if module == "armdyn.model" or module.startswith("armdyn.model."):
            allowed = {m for m in MODULES if m.startswith("armdyn.model.")} | {"armdyn.errors"}
            assert imports_of(module) <= allowed, module


def test_algorithms_do_not_import_the_robot() -> None:
    """dynamics/ and kinematics are free functions of an ArmModel: the Robot sits above them."""
    for module in MODULES:
        if module.startswith("armdyn.dynamics") or module == "armdyn.kinematics":
            assert "armdyn.robot" not in imports_of(module), module


def _every_call(arm: ad.Robot, rng: np.random.Generator) -> None:
    """One state and a batch through every kind of call that reads the packed model."""
    n = arm.n
    for batch in ((), (5,)):
        q, qd, qdd = rng.uniform(-1, 1, (3, *batch, n))
        arm.inverse_dynamics(q, qd, qdd)
        arm.inverse_dynamics(q, qd, qdd, f_ext=np.ones(6))
        arm.forward_dynamics(q, qd, qdd)
        arm.inertia_matrix(q)
        arm.inertia_matrix_dot(q, qd)
        arm.coriolis_matrix(q, qd)
        arm.coriolis_vector(q, qd)
        arm.gravity_vector(q)
        arm.friction(qd)
        arm.nonlinear_terms(q, qd)
        arm.kinetic_energy(q, qd)
        arm.potential_energy(q)
        arm.jacobian(q)
        arm.regressor(q, qd, qdd)


def test_robot_does_not_change_after_construction() -> None:
    arm = ad.models.puma560()
    before = {key: id(value) for key, value in vars(arm).items()}
    _every_call(arm, np.random.default_rng(0))
    ad.simulate(arm, ComputedTorque(100, 20), Sinusoid(0.1, 0.5), t_final=0.05)
    ad.simulate(arm, PDGravity(100, 20), t_final=0.05, method="rk45")
    assert {key: id(value) for key, value in vars(arm).items()} == before
    with pytest.raises(AttributeError, match="immutable"):
        arm.name = "other"
    with pytest.raises(AttributeError, match="immutable"):
        arm.inverse_dynamics = None


def test_robot_survives_pickling() -> None:
    arm = ad.models.puma560()
    copy = pickle.loads(pickle.dumps(arm))
    np.testing.assert_array_equal(copy.packed, arm.packed)
    np.testing.assert_array_equal(copy.inertia_matrix(arm.qn), arm.inertia_matrix(arm.qn))


@pytest.mark.parametrize("name", ["puma560", "stanford", "two_link_planar"])
def test_packed_model_unchanged_by_every_call_from_two_threads(name: str) -> None:
    arm = ad.models.load(name)
    original = arm.packed.copy()
    rng = np.random.default_rng(1)
    q, qd, qdd = rng.uniform(-1, 1, (3, arm.n))
    expected = arm.inverse_dynamics(q, qd, qdd), arm.inertia_matrix(q), arm.forward_dynamics(q, qd, qdd)
    failures: list[str] = []

    def work(seed: int) -> None:
        try:
            local = np.random.default_rng(seed)
            for _ in range(20):
                _every_call(arm, local)
                got = arm.inverse_dynamics(q, qd, qdd), arm.inertia_matrix(q), arm.forward_dynamics(q, qd, qdd)
                if not all(np.array_equal(a, b) for a, b in zip(got, expected, strict=True)):
                    failures.append("a one-state result changed while another thread ran")
            ad.simulate(arm, ComputedTorque(100, 20), Sinusoid(0.1, 0.5), t_final=0.02)
        except Exception as error:  # a thread's exception would otherwise pass unseen
            failures.append(f"{type(error).__name__}: {error}")

    threads = [threading.Thread(target=work, args=(seed,)) for seed in (2, 3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not failures
    np.testing.assert_array_equal(arm.packed, original)


def test_two_threads_first_calls_compile_each_kernel_once() -> None:
    """A fresh interpreter whose first calls of each one-state kernel come from two threads at once: one
    compiles (or loads from the cache), the other waits for it; neither fails."""
    script = textwrap.dedent(
        """
        import threading
        import numpy as np
        import armdyn as ad

        arm = ad.models.puma560()
        q = np.full(6, 0.3)
        start, errors = threading.Barrier(2), []

        def first_calls():
            start.wait()
            try:
                arm.inverse_dynamics(q, q, q), arm.inertia_matrix(q), arm.jacobian(q)
            except Exception as error:
                errors.append(repr(error))

        threads = [threading.Thread(target=first_calls) for _ in range(2)]
        [t.start() for t in threads]
        [t.join() for t in threads]
        print(errors or "ok")
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "ok", done.stdout


def test_kernel_cache_folder_follows_every_compiled_source(tmp_path: Path) -> None:
    """Change a helper that kernels inline (not a kernel's own file): the cache folder changes."""
    copy = tmp_path / "armdyn"
    shutil.copytree(SOURCE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    before = cache.sources_hash(copy)
    assert before == cache.sources_hash(SOURCE)
    spatial = copy / "dynamics" / "spatial.py"
    spatial.write_text(spatial.read_text().replace("_ROUND = 6755399441055744.0", "_ROUND = 6755399441055744.0 + 0.0"))
    after = cache.sources_hash(copy)
    assert after != before
    assert cache.cache_folder(after, copy).name == f"kernels-{after}"
    cli = copy / "cli.py"  # no compiled code: the kernels' cache stays
    cli.write_text(cli.read_text() + "\n")
    assert cache.sources_hash(copy) == after


def test_stale_kernel_folders_are_removed(tmp_path: Path) -> None:
    current, stale = tmp_path / "kernels-new", tmp_path / "kernels-old"
    for folder in (current, stale):
        folder.mkdir()
        (folder / "x.nbi").write_text("")
    (tmp_path / "other").mkdir()
    cache.remove_stale(current)
    assert current.exists() and (tmp_path / "other").exists() and not stale.exists()


IMPORT_PROBE = """
import json, sys
import numba
def scipy_modules():
    return sorted(name for name in sys.modules if name == "scipy" or name.startswith("scipy."))
by_numba = scipy_modules()
import armdyn
heavy = ("sympy", "matplotlib", "dask", "distributed", "pandas", "xarray", "cvxpy", "pyarrow", "mujoco", "pinocchio")
imported = [name for name in heavy if name in sys.modules]
by_armdyn = sorted(set(scipy_modules()) - set(by_numba))
arm = armdyn.models.puma560()
arm.inverse_dynamics([0.1] * 6, [0.0] * 6, [0.0] * 6)
called = [name for name in heavy if name in sys.modules]
print(json.dumps({"imported": imported, "scipy": by_armdyn, "called": called}))
"""


def test_import_armdyn_and_the_first_call_load_no_heavy_package() -> None:
    """``import armdyn`` and a first inverse dynamics import none of SymPy, matplotlib, Dask, pandas, xarray,
    CVXPY, pyarrow, MuJoCo, Pinocchio, and no SciPy module beyond those Numba imports itself."""
    done = subprocess.run([sys.executable, "-c", IMPORT_PROBE], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result == {"imported": [], "scipy": [], "called": []}


def test_armdyn_kernels_are_cached_in_the_hashed_folder() -> None:
    from armdyn.dynamics.rnea import inverse_dynamics_one

    locator = inverse_dynamics_one._cache._impl._locator
    assert isinstance(locator, cache.KernelCacheLocator)
    assert Path(locator.get_cache_path()).is_relative_to(cache.FOLDER)


def _source_lines(pattern: str) -> dict[str, int]:
    """Module -> number of lines of its source matching the regular expression."""
    compiled = re.compile(pattern)
    return {
        name: count
        for name, path in MODULES.items()
        if (count := sum(1 for line in path.read_text().splitlines() if compiled.search(line)))
    }


def test_no_route_is_decided_by_a_class_name() -> None:
    """type(x).__name__ == "..." (or x.__class__.__name__) never decides what runs: isinstance or a protocol does."""
    offenders = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare) and any(
                isinstance(part, ast.Attribute) and part.attr == "__name__" and not _is_module_name(part)
                for part in [node.left, *node.comparators]
            ):
                offenders.append(f"{module}:{node.lineno}")
    assert not offenders, offenders


def _is_module_name(node: ast.Attribute) -> bool:
    return isinstance(node.value, ast.Name) and node.value.id == "__name__"


def test_one_home_for_rk4_cholesky_quintic_and_coulomb() -> None:
    # RK4's update y + h/6 (k1 + 2 k2 + 2 k3 + k4): compiled once and its NumPy reference (simulate's Python
    # loop) once; the passivity row of the property check integrates with scipy's DOP853; the CasADi and JAX
    # backends write one step on their own symbols and arrays
    assert _source_lines(r"/ 6(\.0)? \* \(.*\+ 2(\.0)? \* .*\+ 2(\.0)? \* ") == {
        "armdyn.simulation": 3,  # the compiled rk4_advance, and q and qd in the Python loop
        "armdyn.symbolic.backends": 1,  # runge_kutta_step, on CasADi SX and jax.numpy
    }
    # Cholesky: a pivot's square root, in dynamics/linalg.py only
    assert set(_source_lines(r"sqrt\((d|total|pivot|s)\)")) == {"armdyn.dynamics.linalg"}
    # the quintic time law 10 u^3 - 15 u^4 + 6 u^5
    assert _source_lines(r"10(\.0)? \* \w+ ?\*\* ?3") == {"armdyn.trajectories.joint": 1}
    # the Coulomb law's sign and its tanh smoothing, in dynamics/friction.py only
    # (the derivatives differentiate the smoothing; the generated code writes the law as text)
    smoothing = {"armdyn.dynamics.friction", "armdyn.dynamics.derivatives", "armdyn.symbolic.newton_euler"}
    assert set(_source_lines(r"math\.tanh\(|np\.tanh\(")) <= smoothing
    # (the generated code prints the same law as text for its own target languages)
    assert set(_source_lines(r"if rate > 0\.0 else|> 0\.0 else \(.* < 0\.0")) == {
        "armdyn.dynamics.friction",
        "armdyn.symbolic.newton_euler",
    }


# Names defined in more than one module on purpose: the Lagrange-Euler reference and the NumPy kinematics are the
# compiled functions' independent oracles, under the same names; the traced Newton-Euler of symbolic/ writes the
# kernels' steps as symbols, under their names; the command line's commands are named after what they run; the
# symbolic algebra's number, skew and cross are SymEngine's, beside the NumPy ones.
_REFERENCE = "armdyn.dynamics.lagrange"
ALLOWED_REPEATS = {
    **{
        name: ["armdyn.dynamics.api", _REFERENCE]
        for name in (
            "coriolis_vector",
            "inertia_matrix",
            "inertia_matrix_dot",
            "inverse_dynamics",
            "kinetic_energy",
            "potential_energy",
        )
    },
    **{name: ["armdyn.dynamics.api", _REFERENCE, "armdyn.symbolic.derive"] for name in ("friction", "gravity_vector")},
    "coriolis_matrix": ["armdyn.dynamics.api", _REFERENCE, "armdyn.symbolic.newton_euler"],
    **{
        name: ["armdyn.dynamics.api", "armdyn.kinematics"]
        for name in ("jacobian", "jacobian_dot", "link_transforms", "tool_pose")
    },
    "body_coriolis": ["armdyn.dynamics.coriolis", "armdyn.symbolic.newton_euler"],
    "body_regressor": ["armdyn.dynamics.regressor", "armdyn.symbolic.newton_euler"],
    "force_cross": ["armdyn.dynamics.derivatives", "armdyn.symbolic.newton_euler"],
    **{
        name: ["armdyn.dynamics.spatial", "armdyn.symbolic.newton_euler"]
        for name in ("force_to_parent", "joint_transform", "motion_to_child")
    },
    **{
        name: ["armdyn.cli", module]
        for name, module in (
            ("check", "armdyn.properties"),
            ("derive", "armdyn.symbolic.closed_form"),
            ("identify", "armdyn.identification.least_squares"),
            ("observe", "armdyn.observers.momentum"),
            ("simulate", "armdyn.simulation"),
        )
    },
    "number": ["armdyn.inputs", "armdyn.model.display", "armdyn.symbolic.algebra"],
    "skew": ["armdyn.kinematics", "armdyn.symbolic.algebra"],
    "cross": ["armdyn.symbolic.algebra", "armdyn.symbolic.newton_euler"],
    **{
        name: ["armdyn.symbolic.codegen", "armdyn.symbolic.newton_euler"]
        for name in ("FUNCTIONS", "c_source", "python_source")
    },
}


def test_every_public_name_is_defined_once() -> None:
    """A public name (no leading underscore) defined at module level in two modules of the package is two
    homes for one idea, or one name for two; re-exports in __init__ files do not count."""
    homes: dict[str, list[str]] = {}
    for module, path in MODULES.items():
        if path.name == "__init__.py":
            continue
        for node in ast.parse(path.read_text()).body:
            names = []
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                names = [node.name]
            elif isinstance(node, ast.Assign):
                names = [t.id for t in node.targets if isinstance(t, ast.Name)]
                names += [
                    e.id for t in node.targets if isinstance(t, ast.Tuple) for e in t.elts if isinstance(e, ast.Name)
                ]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names = [node.target.id]
            for name in names:
                if not name.startswith("_"):
                    homes.setdefault(name, []).append(module)
    repeated = {name: modules for name, modules in homes.items() if len(modules) > 1}
    assert repeated == ALLOWED_REPEATS, {k: v for k, v in repeated.items() if ALLOWED_REPEATS.get(k) != v}
