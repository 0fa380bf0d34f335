"""Generated code for the robot equation (armdyn.symbolic.generate_code): the customized Newton-Euler and
composite-rigid-body recursions traced into straight-line code, equal to the compiled kernels through Python,
Numba and C (compiled with the system compiler), lean (operation counts), for arms up to 12 joints."""

from __future__ import annotations

import ctypes
import math
import re
import shutil
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn.errors import ModelError
from armdyn.symbolic import generate_code
from armdyn.symbolic.newton_euler import python_source
from tests.helpers import ROBOTS, URDFS
from tests.strategies import random_robot

XARM7 = ROBOTS / "xarm_description" / "urdf" / "xarm7.urdf"


def _urdf(path: Path) -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's mimic finger joint loads as an independent joint
        return ad.load_urdf(path)


ARMS = {name: (lambda name=name: ad.models.load(name)) for name in ad.models.names()}
ARMS.update({"ur5": lambda: _urdf(URDFS["ur5"]), "panda": lambda: _urdf(URDFS["panda"]), "xarm7": lambda: _urdf(XARM7)})


def reference(arm: ad.Robot, name: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The compiled kernels' value of one function, flat."""
    values = {
        "tau": lambda: arm.inverse_dynamics(q, qd, qdd),
        "M": lambda: arm.inertia_matrix(q),
        "G": lambda: arm.gravity_vector(q),
        "N": lambda: arm.nonlinear_terms(q, qd),
    }
    return np.asarray(values[name]()).ravel()


def close(got: np.ndarray, expected: np.ndarray) -> bool:
    return np.abs(got - expected).max() <= 1e-12 * max(1.0, np.abs(expected).max())


def states(arm: ad.Robot, count: int = 3) -> np.ndarray:
    return np.random.default_rng(arm.n).uniform(-1.5, 1.5, (count, 3, arm.n))


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(ARMS))
def test_python_and_c_equal_the_kernels(name: str, tmp_path: Path) -> None:
    """Every built-in arm and three example-robot-data arms (UR5, Panda, the 7-joint xArm7): the generated
    Python, and the generated C compiled with the system compiler, equal the kernels to 1e-12 relative."""
    arm = ARMS[name]()
    code = generate_code(arm)
    namespace: dict = {}
    exec(compile(code.python(), "<generated>", "exec"), namespace)
    library = _compiled_c(code.c(), tmp_path)
    pointer = ctypes.POINTER(ctypes.c_double)
    for q, qd, qdd in states(arm):
        given = {"q": q, "qd": qd, "qdd": qdd}
        for function, generated in code.functions.items():
            expected = reference(arm, function, q, qd, qdd)
            args = [np.ascontiguousarray(given[a]) for a in generated.arguments]
            out = np.zeros(expected.size)
            namespace[function](*args, out)
            assert close(out, expected), (function, "python")
            if library is not None:
                c_out = np.zeros(expected.size)
                getattr(library, f"armdyn_{function}")(*[a.ctypes.data_as(pointer) for a in args],
                                                       c_out.ctypes.data_as(pointer))  # fmt: skip
                assert close(c_out, expected), (function, "c")
    if library is None:
        pytest.fail("no C compiler (cc) on this machine: the C route is untested")


def _compiled_c(source: str, folder: Path) -> ctypes.CDLL | None:
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        return None
    (folder / "arm.c").write_text(source, encoding="utf-8")
    subprocess.run([compiler, "-O2", "-std=c99", "-Wall", "-Werror", "-shared", "-fPIC", "-o", str(folder / "arm.so"),
                    str(folder / "arm.c"), "-lm"], check=True, capture_output=True)  # fmt: skip
    return ctypes.CDLL(str(folder / "arm.so"))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["puma560", "xarm7"])
def test_numba_one_state_and_batch_equal_the_kernels(name: str) -> None:
    arm = ARMS[name]()
    compiled = generate_code(arm).compile()
    for q, qd, qdd in states(arm, 2):
        assert close(compiled.tau(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd))
        assert close(compiled.M(q).ravel(), arm.inertia_matrix(q).ravel())
        assert close(compiled.G(q), arm.gravity_vector(q))
        assert close(compiled.N(q, qd), arm.nonlinear_terms(q, qd))
    Q, QD, QDD = np.random.default_rng(3).uniform(-1, 1, (3, 2, 50, arm.n))
    assert compiled.tau(Q, QD, QDD).shape == (2, 50, arm.n)
    assert close(compiled.tau(Q, QD, QDD).ravel(), arm.inverse_dynamics(Q, QD, QDD).ravel())
    assert close(compiled.M(Q).ravel(), arm.inertia_matrix(Q).ravel())
    out = np.empty((arm.n, arm.n))
    assert compiled.M(Q[0, 0], out=out) is out
    with pytest.raises(ModelError, match="qd"):
        compiled.tau(Q[0, 0], [np.nan] * arm.n, QDD[0, 0])


def _generated_python(code: object) -> dict:
    namespace: dict = {}
    exec(compile(code.python(), "<generated>", "exec"), namespace)
    return namespace


@pytest.mark.slow
@pytest.mark.parametrize("name", ["puma560", "stanford", "scara", "polar_rp", "ur5", "panda"])
def test_the_base_regressor_where_asked(name: str, tmp_path: Path) -> None:
    """generate_code(arm, ["Wb"]) gives the base regressor: W_b equals the kept columns of the regressor, and
    W_b phi_b = tau with the regrouped base parameters (friction and motors included), through the generated
    Python and C, to 1e-12 relative; at rest a joint's Coulomb columns are 0 as in the regressor."""
    arm = ARMS[name]()
    code = generate_code(arm, ["Wb"])
    base = code.base
    assert code.functions["Wb"].shape == (arm.n, len(base)) and len(base) < 14 * arm.n
    namespace, library = _generated_python(code), _compiled_c(code.c(), tmp_path)
    pointer = ctypes.POINTER(ctypes.c_double)
    phi_in_c = (ctypes.c_double * len(base)).in_dll(library, "armdyn_phi_base")
    assert namespace["BASE_NAMES"] == base.names and np.array_equal(namespace["PHI_BASE"], base.phi)
    rest = states(arm)
    rest[0, 1, 0], rest[1, 1, :] = 0.0, 0.0
    for q, qd, qdd in rest:
        expected = base.regressor(q, qd, qdd)
        out, c_out = np.zeros(expected.size), np.zeros(expected.size)
        namespace["Wb"](q, qd, qdd, out)
        library.armdyn_Wb(*[x.ctypes.data_as(pointer) for x in (q, qd, qdd, c_out)])
        assert close(out, expected.ravel()) and close(c_out, expected.ravel())
        tau = arm.inverse_dynamics(q, qd, qdd)
        assert close(out.reshape(arm.n, -1) @ namespace["PHI_BASE"], tau)
        assert close(c_out.reshape(arm.n, -1) @ np.array(phi_in_c), tau)


@pytest.mark.slow
def test_the_compiled_base_regressor_for_one_state_and_a_batch() -> None:
    arm = ad.models.scara()
    code = generate_code(arm, ["Wb", "tau"])
    compiled = code.compile()
    Q, QD, QDD = np.random.default_rng(4).uniform(-1, 1, (3, 4, 25, arm.n))
    W = compiled.Wb(Q, QD, QDD)
    assert W.shape == (4, 25, arm.n, len(code.base))
    assert close(W.ravel(), code.base.regressor(Q, QD, QDD).ravel())
    assert close(compiled.Wb(Q[1, 2], QD[1, 2], QDD[1, 2]).ravel(), W[1, 2].ravel())
    assert close((W @ code.base.phi).ravel(), compiled.tau(Q, QD, QDD).ravel())
    with pytest.raises(ModelError, match="out"):
        compiled.Wb(Q[0, 0], QD[0, 0], QDD[0, 0], out=np.empty((arm.n, arm.n)))
    with pytest.raises(ModelError, match="no Vm"):
        compiled.Vm(Q[0, 0], QD[0, 0])


def test_operation_counts_are_lean() -> None:
    """At most the Robotics Toolbox's symbolic RNE after common-subexpression elimination (PUMA 560 tau 890,
    Stanford 742, Panda 2,130 operations), friction and motors included."""
    puma = generate_code(ad.models.puma560()).operation_counts()
    assert puma["tau"]["total"] <= 890
    # and about a third of the general recursive Newton-Euler's 150 n - 48 multiplications and 131 n - 48
    # additions (Luh, Walker and Paul 1980, as counted by Hollerbach 1980)
    assert puma["tau"]["multiplications"] <= 0.35 * (150 * 6 - 48)
    assert puma["tau"]["additions"] <= 0.35 * (131 * 6 - 48)
    assert set(puma["tau"]) == {"multiplications", "additions", "calls", "total"}
    assert generate_code(ad.models.stanford(), ["tau"]).operation_counts()["tau"]["total"] <= 742
    assert generate_code(ARMS["panda"](), ["tau"]).operation_counts()["tau"]["total"] <= 2130
    # the cost grows linearly with the joints: a 12-joint chain costs about twice a 6-joint one
    six, twelve = (generate_code(random_robot(5, n, chain=True), ["tau"]).operation_counts()["tau"]["total"]
                   for n in (6, 12))  # fmt: skip
    assert twelve < 2.6 * six


@pytest.mark.slow
def test_a_twelve_joint_arm_compiles_and_every_line_is_one_operation() -> None:
    """No expression is deep: each line of the generated Python holds one operation."""
    arm = random_robot(11, 12, chain=True)
    code = generate_code(arm, ["tau", "M"])
    for line in code.python().splitlines():
        if re.match(r"\s+x\d+ = ", line):
            assert len(re.findall(r"[+*]| - ", line.split("=", 1)[1])) <= 1, line
    compiled = code.compile()
    q, qd, qdd = states(arm, 1)[0]
    assert close(compiled.tau(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd))
    assert close(compiled.M(q).ravel(), arm.inertia_matrix(q).ravel())


def test_a_float_twist_of_pi_over_two_leaves_no_round_off_term() -> None:
    """DH twists given as floats (np.pi / 2, cosine 6e-17) are exact zeros and ones in the code."""
    rows = [
        dict(a=0.1, alpha=np.pi / 2, d=0.3, mass=1.0, com=[0.0, 0.05, 0.0], inertia=[0.01, 0.02, 0.015]),
        dict(a=0.4, alpha=0.0, mass=2.0, com=[-0.2, 0.0, 0.0], inertia=[0.01, 0.05, 0.05]),
        dict(a=0.0, alpha=-np.pi / 2, d=0.1, mass=0.5, com=[0.0, 0.0, 0.02], inertia=[0.002, 0.002, 0.001]),
    ]
    arm = ad.Robot.from_dh(rows, name="spatial3")
    code = generate_code(arm)
    literals = [float(x) for x in re.findall(r"(?<![\w.\]])\d+\.\d+(?:e-?\d+)?", code.python())]
    assert literals and min(abs(x) for x in literals if x != 0) > 1e-12
    namespace: dict = {"math": math}
    exec(compile(python_source(code.functions["tau"]), "<tau>", "exec"), namespace)
    q, qd, qdd = states(arm, 1)[0]
    out = np.zeros(3)
    namespace["tau"](q, qd, qdd, out)
    assert close(out, arm.inverse_dynamics(q, qd, qdd))


def test_bad_requests_are_model_errors() -> None:
    with pytest.raises(ModelError, match="symbolic"):
        generate_code(ad.models.two_link_planar(symbolic=True))
    with pytest.raises(ModelError, match="functions must be"):
        generate_code(ad.models.puma560(), ["Vm2"])
    compiled = generate_code(ad.models.two_link_planar(), ["G"]).compile()
    with pytest.raises(ModelError, match="no tau"):
        compiled.tau(np.zeros(2), np.zeros(2), np.zeros(2))


def test_the_command_line_generates_code_for_larger_arms(tmp_path: Path) -> None:
    """`armdyn derive ARM --code c` takes the Newton-Euler route for a numeric arm of 5 joints or more (and with
    --method newton-euler for any); the book's symbolic arms keep their closed form's code."""
    from typer.testing import CliRunner

    from armdyn.cli import app

    runner = CliRunner()
    puma = runner.invoke(app, ["derive", "puma560", "--code", "c", "-o", str(tmp_path / "puma.c")])
    assert puma.exit_code == 0, puma.output
    assert (
        "void armdyn_tau(const double *q, const double *qd, const double *qdd, double *out)"
        in (tmp_path / "puma.c").read_text()
    )
    small = runner.invoke(app, ["derive", "two_link_planar", "--method", "newton-euler", "--code", "python"])
    assert small.exit_code == 0 and "def M(q, out):" in small.output
    refused = runner.invoke(app, ["derive", "puma560", "--method", "newton-euler"])
    assert refused.exit_code == 2 and "give --code" in refused.output
    chosen = runner.invoke(app, ["derive", "scara", "--code", "c", "--functions", "Wb,tau"])
    assert chosen.exit_code == 0, chosen.output
    assert "armdyn_phi_base[" in chosen.output and "void armdyn_Wb(" in chosen.output
    assert "void armdyn_M(" not in chosen.output
    unknown = runner.invoke(app, ["derive", "scara", "--code", "c", "--functions", "Wx"])
    assert unknown.exit_code == 2 and "functions must be some of" in unknown.output
    alone = runner.invoke(app, ["derive", "scara", "--functions", "Wb"])
    assert alone.exit_code == 2 and "give it with --code" in alone.output


@pytest.mark.slow
@pytest.mark.parametrize("name", ["puma560", "stanford", "polar_rp", "xarm7"])
def test_the_coriolis_matrix_where_asked(name: str, tmp_path: Path) -> None:
    """generate_code(arm, ["Vm"]) gives the Christoffel-consistent Vm of the kernels (Python and C, 1e-12)."""
    arm = ARMS[name]()
    code = generate_code(arm, ["Vm"])
    namespace: dict = {}
    exec(compile(code.python(), "<generated>", "exec"), namespace)
    library = _compiled_c(code.c(), tmp_path)
    pointer = ctypes.POINTER(ctypes.c_double)
    for q, qd, _ in states(arm):
        expected = arm.coriolis_matrix(q, qd).ravel()
        out, c_out = np.zeros(expected.size), np.zeros(expected.size)
        namespace["Vm"](q, qd, out)
        assert close(out, expected)
        library.armdyn_Vm(q.ctypes.data_as(pointer), qd.ctypes.data_as(pointer), c_out.ctypes.data_as(pointer))
        assert close(c_out, expected)
    if name == "polar_rp":
        compiled = code.compile()
        q, qd, _ = states(arm, 1)[0]
        assert close(compiled.Vm(q, qd).ravel(), arm.coriolis_matrix(q, qd).ravel())
