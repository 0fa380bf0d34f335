"""The CasADi and JAX backends of the generated code (armdyn.symbolic.generate_code(..., backend=)): every
function equal to the compiled kernels on every built-in arm and three example-robot-data arms (UR5, the
Panda with its fingers locked, xArm7), the RK4 step equal to a hand-written RK4 of the forward dynamics under
simulate's smoothed friction, CasADi's and JAX's derivatives equal to armdyn's analytic ones, jit and vmap,
CasADi's C compiled, and the error paths."""

from __future__ import annotations

import dataclasses
import functools
import shutil
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armdyn as ad
from armdyn.dynamics.friction import coulomb_vector, sign_law_table, smooth_coulomb_vector
from armdyn.errors import MissingDependencyError, ModelError
from armdyn.simulation import _smoothing
from armdyn.symbolic import generate_code
from armdyn.symbolic.backends import JIT_OPTIONS
from tests.helpers import ROBOTS, URDFS

casadi = pytest.importorskip("casadi")
jax = pytest.importorskip("jax")
jax.config.update("jax_enable_x64", True)
jnp = jax.numpy

ALL = ("tau", "M", "G", "N", "Vm", "Wb", "qdd", "step")
LOCKED = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


def _urdf(path: Path, **options: Any) -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's mimic finger joint loads as an independent joint
        return ad.load_urdf(path, **options)


ARMS: dict[str, Callable[[], ad.Robot]] = {name: functools.partial(ad.models.load, name) for name in ad.models.names()}
ARMS |= {
    "ur5": lambda: _urdf(URDFS["ur5"]),
    "panda7": lambda: _urdf(URDFS["panda"], locked=LOCKED),
    "xarm7": lambda: _urdf(ROBOTS / "xarm_description" / "urdf" / "xarm7.urdf"),
}
CASES = list(ARMS)


@functools.cache
def arm_of(name: str) -> ad.Robot:
    return ARMS[name]()


@functools.cache
def code(name: str, backend: str) -> Any:
    return generate_code(arm_of(name), ALL, backend=backend)


def close(got: object, expected: object, tolerance: float = 1e-12) -> bool:
    got, expected = np.asarray(got, dtype=float), np.asarray(expected, dtype=float)
    assert got.shape == expected.shape, (got.shape, expected.shape)
    return bool(np.abs(got - expected).max() <= tolerance * max(1.0, np.abs(expected).max()))


def states(arm: ad.Robot, count: int = 3, speed: float = 1.5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(arm.n)
    return (
        rng.uniform(-1.5, 1.5, (count, arm.n)),
        rng.uniform(-speed, speed, (count, arm.n)),
        rng.normal(size=(count, arm.n)),
    )


def call(backend: str, function: Any, *states: np.ndarray) -> np.ndarray:
    """The function on a batch of states: CasADi's one state at a time, JAX's on the batch at once."""
    if backend == "jax":
        return np.asarray(function(*states))
    results = [np.array(function(*state)) for state in zip(*states, strict=True)]
    shape = results[0].shape
    return np.stack([r.ravel() if shape[1] == 1 else r for r in results])


@pytest.mark.parametrize("backend", ["casadi", "jax"])
@pytest.mark.parametrize("name", CASES)
def test_every_function_equals_the_kernels(name: str, backend: str) -> None:
    arm, generated = arm_of(name), code(name, backend)
    q, qd, qdd = states(arm)
    assert generated.functions.keys() == set(ALL)
    assert close(call(backend, generated.tau, q, qd, qdd), arm.inverse_dynamics(q, qd, qdd))
    assert close(call(backend, generated.M, q), arm.inertia_matrix(q))
    assert close(call(backend, generated.G, q), arm.gravity_vector(q))
    assert close(call(backend, generated.N, q, qd), arm.nonlinear_terms(q, qd))
    assert close(call(backend, generated.Vm, q, qd), arm.coriolis_matrix(q, qd))
    assert close(call(backend, generated.qdd, q, qd, qdd), arm.forward_dynamics(q, qd, qdd))
    Wb = call(backend, generated.Wb, q, qd, qdd)
    assert close(Wb, generated.base.regressor(q, qd, qdd))
    assert close(Wb @ generated.base.phi, arm.inverse_dynamics(q, qd, qdd), 1e-11)


def rk4(rate: Callable[[np.ndarray], np.ndarray], x: np.ndarray, dt: float) -> np.ndarray:
    k1 = rate(x)
    k2 = rate(x + dt / 2 * k1)
    k3 = rate(x + dt / 2 * k2)
    k4 = rate(x + dt * k3)
    return x + dt * (k1 + 2 * k2 + 2 * k3 + k4) / 6


def smoothed_rate(arm: ad.Robot, tau: np.ndarray, eps: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """x -> [qd; qdd] of armdyn's forward dynamics with simulate's smoothed Coulomb law in place of the exact one."""
    table, n = sign_law_table(arm), arm.n

    def rate(x: np.ndarray) -> np.ndarray:
        q, qd = x[:n], x[n:]
        smoothing = coulomb_vector(table, qd) - smooth_coulomb_vector(table, eps, qd) if eps.any() else 0.0
        return np.concatenate([qd, arm.forward_dynamics(q, qd, tau + smoothing)])

    return rate


@pytest.mark.parametrize("backend", ["casadi", "jax"])
@pytest.mark.parametrize("name", ["puma560", "scara", "stanford", pytest.param("panda7", marks=pytest.mark.slow)])
def test_the_step_is_rk4_of_the_forward_dynamics_with_simulates_smoothing(name: str, backend: str) -> None:
    """Slow joints (|qd| within a few eps) so the tanh is far from saturated; PUMA's Coulomb levels are
    asymmetric, the SCARA's symmetric, the Stanford arm has none."""
    arm, dt = arm_of(name), 0.01
    q, qd, tau = states(arm, speed=0.05)
    for smoothing in ("auto", 0.02, 0.0):
        generated = code(name, backend) if smoothing == "auto" else \
            generate_code(arm, ["step"], backend=backend, coulomb_smoothing=smoothing)  # fmt: skip
        got = call(backend, generated.step, np.hstack([q, qd]), tau, np.full(len(q), dt))
        for k in range(len(q)):
            eps = _smoothing(arm, smoothing, dt, q[k])  # simulate's eps for a run starting here
            expected = rk4(smoothed_rate(arm, tau[k], eps), np.r_[q[k], qd[k]], dt)
            assert close(got[k], expected), (smoothing, k)


def _casadi_jacobians(function: Any, n: int) -> Callable[..., list[np.ndarray]]:
    """The Jacobians of a CasADi function's one output with respect to each of its inputs, by casadi.jacobian."""
    symbols = [casadi.SX.sym(f"x{k}", n) for k in range(function.n_in())]
    output = function(*symbols)
    jacobian = casadi.Function("jacobian", symbols, [casadi.jacobian(output, s) for s in symbols])
    return lambda *args: [np.array(J) for J in jacobian(*args)]


@pytest.mark.parametrize("name", CASES)
def test_casadi_and_jax_derivatives_equal_the_analytic_ones(name: str) -> None:
    arm = arm_of(name)
    n = arm.n
    q, qd, qdd = states(arm, count=2)
    tau_jacobians = _casadi_jacobians(code(name, "casadi").tau, n)
    qdd_jacobians = _casadi_jacobians(code(name, "casadi").qdd, n)
    jax_code = code(name, "jax")
    tau_by_jax = jax.jacfwd(jax_code.tau, argnums=(0, 1, 2))  # eager: XLA compiles a scalar graph slowly
    qdd_by_jax = jax.jacfwd(jax_code.qdd, argnums=(0, 1, 2))
    for k in range(len(q)):
        d_q, d_qd = arm.inverse_dynamics_derivatives(q[k], qd[k], qdd[k])
        f_q, f_qd, f_tau = arm.forward_dynamics_derivatives(q[k], qd[k], qdd[k])
        M = arm.inertia_matrix(q[k])
        for got, expected in zip(tau_jacobians(q[k], qd[k], qdd[k]), (d_q, d_qd, M), strict=True):
            assert close(got, expected, 1e-10)
        for got, expected in zip(qdd_jacobians(q[k], qd[k], qdd[k]), (f_q, f_qd, f_tau), strict=True):
            assert close(got, expected, 1e-10)
        by_jax = tau_by_jax(q[k], qd[k], qdd[k])
        for got, expected in zip(by_jax, (d_q, d_qd, M), strict=True):
            assert close(got, expected, 1e-10)
        by_jax = qdd_by_jax(q[k], qd[k], qdd[k])
        for got, expected in zip(by_jax, (f_q, f_qd, f_tau), strict=True):
            assert close(got, expected, 1e-10)


@pytest.mark.parametrize("backend", ["casadi", "jax"])
def test_the_steps_jacobian_is_armdyns_rk4_derivatives_chain(backend: str) -> None:
    """d x_next / dx and d x_next / d tau of the step (CasADi's or JAX's differentiation) equal
    armdyn.statespace.rk4_step's chain of analytic derivatives through the four stages, the Coulomb law
    smoothed by the same eps (its slope included)."""
    arm, dt, eps = arm_of("puma560"), 0.01, 0.05
    n = arm.n
    q, qd, tau = (s[0] for s in states(arm, speed=0.1))
    x = np.r_[q, qd]
    generated = generate_code(arm, ["step"], backend=backend, coulomb_smoothing=eps)
    if backend == "casadi":
        J_x, J_tau, _ = _casadi_jacobians_step(generated.step, n)(x, tau, dt)
        x_next = np.array(generated.step(x, tau, dt)).ravel()
    else:
        J_x, J_tau = (np.asarray(J) for J in jax.jacfwd(generated.step, argnums=(0, 1))(x, tau, dt))
        x_next = np.asarray(generated.step(x, tau, dt))
    expected, A_d, B_d = ad.statespace.rk4_step(arm, q, qd, tau, dt, coulomb_smoothing=eps)
    assert close(x_next, expected)
    assert close(J_x, A_d, 1e-10)
    assert close(J_tau, B_d, 1e-10)


def _casadi_jacobians_step(step: Any, n: int) -> Callable[..., list[np.ndarray]]:
    x, tau, dt = casadi.SX.sym("x", 2 * n), casadi.SX.sym("tau", n), casadi.SX.sym("dt")
    output = step(x, tau, dt)
    jacobian = casadi.Function("jacobian", [x, tau, dt], [casadi.jacobian(output, s) for s in (x, tau, dt)])
    return lambda *args: [np.array(J) for J in jacobian(*args)]


def test_jax_jit_vmap_and_grad() -> None:
    arm = arm_of("puma560")
    generated = code("puma560", "jax")
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.uniform(-2, 2, (3, 256, arm.n))
    batched = jax.jit(jax.vmap(generated.tau))(q, qd, qdd)
    assert batched.dtype == jnp.float64
    assert close(batched, arm.inverse_dynamics(q, qd, qdd))
    unfused = jax.jit(jax.vmap(generated.tau), compiler_options=JIT_OPTIONS)(q, qd, qdd)
    assert close(unfused, arm.inverse_dynamics(q, qd, qdd))
    assert close(jax.jit(generated.M)(q[:8]), arm.inertia_matrix(q[:8]))  # leading axes without vmap
    weights = rng.normal(size=arm.n)
    gradient = jax.jit(jax.grad(lambda q0: generated.tau(q0, qd[0], qdd[0]) @ weights))(q[0])
    assert close(gradient, weights @ arm.inverse_dynamics_derivatives(q[0], qd[0], qdd[0])[0], 1e-10)


@pytest.mark.slow
def test_jax_jit_and_vmap_of_the_step() -> None:
    arm = arm_of("puma560")
    generated = code("puma560", "jax")
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.uniform(-2, 2, (3, 4, arm.n))
    steps = jax.jit(jax.vmap(generated.step, in_axes=(0, 0, None)))(np.hstack([q, qd]), qdd, 0.01)
    for k in range(4):
        assert close(steps[k], generated.step(np.r_[q[k], qd[k]], qdd[k], 0.01))


def test_forward_dynamics_keeps_the_cheaper_of_ltdl_and_casadis_solve() -> None:
    """The sparse L^T D L solve in SX beats casadi.solve on M; the function built is the cheaper one."""
    for name in ("puma560", "ur5"):
        generated = code(name, "casadi")
        counts = generated.qdd_counts
        assert counts["ltdl"] < counts["solve"]
        assert generated.qdd_method == "ltdl"
        assert generated.instruction_counts()["qdd"] == counts["ltdl"]


@pytest.mark.parametrize("name", ["puma560", "scara"])
def test_casadis_c_compiles_without_warnings(name: str, tmp_path: Path) -> None:
    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.skip("gcc is not on the PATH: the generated C is not compiled")
    source = code(name, "casadi").c("arm_")
    for function in ALL:
        assert f"int arm_{function}(const casadi_real** arg" in source
    path = tmp_path / "arm.c"
    path.write_text(source)
    result = subprocess.run([compiler, "-std=c99", "-Wall", "-Werror", "-c", str(path), "-o", str(tmp_path / "arm.o")],
                            capture_output=True, text=True, check=False)  # fmt: skip
    assert result.returncode == 0, result.stderr


def test_only_the_functions_asked_for_exist() -> None:
    generated = generate_code(ad.models.two_link_planar(), ["M", "qdd"], backend="casadi")
    assert list(generated.functions) == ["M", "qdd"]
    assert generated.M.name() == "M" and generated.M.name_in() == ["q"] and generated.M.name_out() == ["M"]
    assert generated.qdd.name_in() == ["q", "qd", "tau"]
    with pytest.raises(AttributeError, match="no step: generate it with functions including 'step'"):
        generated.step  # noqa: B018
    jax_code = generate_code(ad.models.two_link_planar(), ["step"], backend="jax")
    assert list(jax_code.functions) == ["step"]
    with pytest.raises(AttributeError, match="no tau"):
        jax_code.tau  # noqa: B018


def test_bad_requests_are_model_errors() -> None:
    arm = ad.models.puma560()
    with pytest.raises(ModelError, match=r"backend must be one of \('python', 'casadi', 'jax'\), got 'torch'"):
        generate_code(arm, backend="torch")
    with pytest.raises(ModelError, match="'qdd' and 'step' with backend 'casadi' or 'jax'"):
        generate_code(arm, ["tau", "qdd"])
    with pytest.raises(ModelError, match="functions must be"):
        generate_code(arm, ["tau", "qddd"], backend="casadi")
    with pytest.raises(ModelError, match="coulomb_smoothing must be"):
        generate_code(arm, ["step"], backend="jax", coulomb_smoothing="smooth")
    with pytest.raises(ModelError, match="coulomb_smoothing must be at least 0"):
        generate_code(arm, ["step"], backend="casadi", coulomb_smoothing=-1.0)
    link = dataclasses.replace(arm.links[1], stribeck=(1.0, 0.1))
    stribeck = arm.replace([*arm.links[:1], link, *arm.links[2:]])
    with pytest.raises(ModelError, match=f"link '{link.name}'.*Stribeck"):
        generate_code(stribeck, ["qdd"], backend="casadi")


@pytest.mark.parametrize(("backend", "module"), [("casadi", "casadi"), ("jax", "jax")])
def test_a_missing_extra_names_it(backend: str, module: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, module, None)  # import fails as if not installed
    with pytest.raises(MissingDependencyError, match=rf"pip install 'armdyn\[{backend}\]'") as caught:
        generate_code(ad.models.two_link_planar(), ["tau"], backend=backend)
    assert caught.value.extra == backend


@pytest.mark.parametrize("name", ["two_link_planar", pytest.param("puma560", marks=pytest.mark.slow)])
def test_jax_differentiates_a_one_second_rollout_as_the_chain_of_rk4_derivatives(name: str) -> None:
    """d x(1 s) / d x(0) of 100 steps of 10 ms by jax.jacfwd through lax.scan over the generated step equals the
    product of armdyn.statespace.rk4_step's analytic step derivatives to 1e-9, and the gradient of a cost of
    the final state with respect to every step's torque equals the chain's x(1 s)'s B_d terms."""
    arm, dt, steps, eps = ad.models.load(name), 0.01, 100, 0.05
    n = arm.n
    step = generate_code(arm, ["step"], backend="jax", coulomb_smoothing=eps).step
    rng = np.random.default_rng(12)
    q0, qd0 = rng.uniform(-0.5, 0.5, (2, n))
    taus = arm.gravity_vector(q0) + rng.uniform(-1, 1, (steps, n))

    def rollout(x0: Any, torques: Any) -> Any:
        final, _ = jax.lax.scan(lambda x, tau: (step(x, tau, dt), None), x0, torques)
        return final

    x0 = jnp.asarray(np.r_[q0, qd0])
    J_x0 = np.asarray(jax.jit(jax.jacfwd(rollout), compiler_options=JIT_OPTIONS)(x0, jnp.asarray(taus)))
    cost = jax.jit(jax.grad(lambda x, u: jnp.sum(rollout(x, u) ** 2), argnums=1), compiler_options=JIT_OPTIONS)
    d_cost = np.asarray(cost(x0, jnp.asarray(taus)))
    q, qd, chain, B = q0.copy(), qd0.copy(), np.eye(2 * n), []
    for tau in taus:
        x, A_d, B_d = ad.statespace.rk4_step(arm, q, qd, tau, dt, coulomb_smoothing=eps)
        chain, q, qd = A_d @ chain, x[:n], x[n:]
        B = [A_d @ b for b in B] + [B_d]  # d x_final / d tau_k, carried forward
    assert close(J_x0, chain, 1e-9)
    expected = np.stack([2.0 * np.r_[q, qd] @ b for b in B])
    assert close(d_cost, expected, 1e-9)
