"""One argument-checking rule for every fast path: a one-state call never takes an argument that the general path
refuses. Every public function with a compiled one-state path is called with the same bad argument (None, NaN,
infinity, a wrong length, text, a bad ``out``, aliased outputs, infinite damping, a bool smoothing) once with one
state (the fast path) and once with a batch of one (the general path; for the task-space functions also through an
equal user Output, which only the general path takes): each refuses it with the same error class, a ModelError."""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from functools import partial

import numpy as np
import pytest

import armdyn as ad
from armdyn import task_space as ts
from armdyn.dynamics import api
from armdyn.errors import ModelError
from armdyn.symbolic import derive, generate_code

ARM = ad.models.two_link_planar()
N = ARM.n
GOOD = (np.array([0.3, 0.7]), np.array([0.4, -0.2]), np.array([-0.5, 0.9]))  # J of PlanarPosition is regular here


def _outcome(call: Callable[[], object]) -> type[BaseException] | None:
    try:
        call()
    except Exception as error:  # the class is the outcome compared
        return type(error)
    return None


def _batch(value: object) -> object:
    """The same argument for a batch of one state (the general path)."""
    return value[None] if isinstance(value, np.ndarray) else value


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


BAD_STATES = {
    "None": lambda: None,
    "NaN": lambda: np.full(N, np.nan),
    "infinity": lambda: np.array([0.1, np.inf]),
    "too short": lambda: np.zeros(N - 1),
    "too long": lambda: np.zeros(N + 1),
    "beyond 1e15": lambda: np.array([0.1, 2e15]),
    "text": lambda: "0.1 0.2",
}
BAD_OUTS = {
    "wrong shape": lambda shape: np.zeros((*shape[:-1], shape[-1] + 1)),
    "read-only": lambda shape: _frozen(np.zeros(shape)),
    "float32": lambda shape: np.zeros(shape, dtype=np.float32),
    "not contiguous": lambda shape: np.zeros((*shape, 2))[..., 0],
    "a list": lambda shape: np.zeros(shape).tolist(),
}


def _same_refusal(fast: Callable[[], object], general: Callable[[], object], *others: Callable[[], object]) -> None:
    """The fast and the general call (and any other route) all refuse, with the same ModelError class."""
    outcomes = [_outcome(call) for call in (fast, general, *others)]
    assert outcomes[1] is not None and issubclass(outcomes[1], ModelError), outcomes
    assert all(o is outcomes[1] for o in outcomes), outcomes


# ----- the dynamics and kinematics of armdyn.dynamics.api (one state: the compiled entry) ---------------------
def _states_of(function: Callable) -> list[str]:
    skip = {"arm", "out", "f_ext", "frame", "link", "coulomb_smoothing"}
    return [p for p in inspect.signature(function).parameters if p not in skip]


API = sorted(api.TABLE)


@pytest.mark.parametrize("name", API)
@pytest.mark.parametrize("bad", sorted(BAD_STATES))
def test_dynamics_refuse_a_bad_state_alike_on_both_paths(name: str, bad: str) -> None:
    function = getattr(api, name)
    count = len(_states_of(function))
    for k in range(count):
        states = [GOOD[i].copy() for i in range(count)]
        states[k] = BAD_STATES[bad]()
        batch = [_batch(s) for s in states]
        _same_refusal(partial(function, ARM, *states), partial(function, ARM, *batch))


@pytest.mark.parametrize("name", API)
@pytest.mark.parametrize("bad", sorted(BAD_OUTS))
def test_dynamics_refuse_a_bad_out_alike_on_both_paths(name: str, bad: str) -> None:
    function = getattr(api, name)
    states = [GOOD[i].copy() for i in range(len(_states_of(function)))]
    shape = function(ARM, *states).shape
    _same_refusal(lambda: function(ARM, *states, out=BAD_OUTS[bad](shape)),
                  lambda: function(ARM, *[s[None] for s in states], out=BAD_OUTS[bad]((1, *shape))))  # fmt: skip


# ----- the analytic derivatives ---------------------------------------------------------------------------------
DERIVATIVES = {"inverse_dynamics_derivatives": 2, "forward_dynamics_derivatives": 3}


@pytest.mark.parametrize("name", sorted(DERIVATIVES))
@pytest.mark.parametrize("bad", sorted(BAD_STATES))
def test_derivatives_refuse_a_bad_state_alike_on_both_paths(name: str, bad: str) -> None:
    function = getattr(api, name)
    for k in range(3):
        states = [x.copy() for x in GOOD]
        states[k] = BAD_STATES[bad]()
        _same_refusal(partial(function, ARM, *states), partial(function, ARM, *[_batch(s) for s in states]))


@pytest.mark.parametrize("name", sorted(DERIVATIVES))
@pytest.mark.parametrize("smoothing", [True, False, np.True_, math.nan, math.inf, -0.1, "0.1", [0.1, 0.1, 0.1]])
def test_derivatives_refuse_a_bad_smoothing_alike_on_both_paths(name: str, smoothing: object) -> None:
    """coulomb_smoothing=True (a bool, no width in rad/s) is refused as simulate refuses it."""
    function = getattr(api, name)
    _same_refusal(lambda: function(ARM, *GOOD, coulomb_smoothing=smoothing),
                  lambda: function(ARM, *(x[None] for x in GOOD), coulomb_smoothing=smoothing),
                  lambda: ad.simulate(ARM, t_final=0.01, dt=0.01, coulomb_smoothing=smoothing))  # fmt: skip


def _aliased_outs(count: int, batch: tuple[int, ...]) -> dict[str, tuple]:
    shape = (*batch, N, N)
    A = np.zeros(shape)
    big = np.zeros((*batch, N, 2 * N))
    overlapping = (big[..., :N], big[..., N:])  # not C-contiguous: refused as such, still refused
    whole = np.zeros((2, *shape))
    return {
        "the same array twice": (A,) * count,
        "a view of the same array": (A, A.reshape(shape)) + tuple(np.zeros(shape) for _ in range(count - 2)),
        "overlapping halves": overlapping + tuple(np.zeros(shape) for _ in range(count - 2)),
        "one array's parts, then the first again": (*(whole[i] for i in range(count - 1)), whole[0]),
        "too few": (np.zeros(shape),) * (count - 1),
        "not a tuple": np.zeros(shape),
    }


@pytest.mark.parametrize("name", sorted(DERIVATIVES))
@pytest.mark.parametrize("case", sorted(_aliased_outs(3, ())))
def test_derivatives_refuse_aliased_outputs_alike_on_both_paths(name: str, case: str) -> None:
    """out=(A, A) used to return the second result twice: refused (np.shares_memory), one state or a batch."""
    function = getattr(api, name)
    count = DERIVATIVES[name]
    _same_refusal(lambda: function(ARM, *GOOD, out=_aliased_outs(count, ())[case]),
                  lambda: function(ARM, *(x[None] for x in GOOD), out=_aliased_outs(count, (1,))[case]))  # fmt: skip


@pytest.mark.parametrize("name", sorted(DERIVATIVES))
def test_derivatives_refuse_an_output_that_aliases_a_state(name: str) -> None:
    """A state that is a view of an output would be overwritten while it is read: refused on both paths. The oracle:
    with separate arrays, the outputs equal a fresh call's."""
    function = getattr(api, name)
    count = DERIVATIVES[name]
    for k in range(3):
        outs = [np.zeros((N, N)) for _ in range(count)]
        states = [x.copy() for x in GOOD]
        outs[0][0] = states[k]
        states[k] = outs[0][0]  # q (or qd, ...) lives in the first row of the first output
        batch_outs = [np.zeros((1, N, N)) for _ in range(count)]
        batch_outs[0][0, 0] = GOOD[k]
        batch = [x[None].copy() for x in GOOD]
        batch[k] = batch_outs[0][0, :1]
        _same_refusal(partial(function, ARM, *states, out=tuple(outs)),
                      partial(function, ARM, *batch, out=tuple(batch_outs)))  # fmt: skip
    separate = tuple(np.zeros((N, N)) for _ in range(count))
    got = function(ARM, *GOOD, out=separate)
    for g, s, fresh in zip(got, separate, function(ARM, *GOOD), strict=True):
        assert g is s
        np.testing.assert_array_equal(g, fresh)


# ----- task space: the compiled one-state kernels of the built-in row outputs --------------------------------
def _general_output() -> ts.Output:
    """PlanarPosition as a user Output: the same J, taken only by the general path."""
    return ts.Output(lambda q: ARM.tool_pose(q)[:2, 3], lambda q: ARM.jacobian(q)[:2],
                     jacobian_dot=lambda q, qd: ARM.jacobian_dot(q, qd)[:2])  # fmt: skip


TASK = {  # name -> (state names, takes damping)
    "task_inertia": (("q",), True),
    "task_coriolis": (("q", "qd"), True),
    "task_gravity": (("q",), True),
    "task_nonlinear": (("q", "qd"), True),
    "task_friction": (("q", "qd"), True),
    "task_force": (("q", "tau"), True),
    "task_inverse_dynamics": (("q", "qd", "yddot"), True),
    "task_regressor": (("q", "qd", "yddot"), True),
    "task_forward_dynamics": (("q", "qd", "f"), False),
    "operational_inertia": (("q",), True),
    "operational_space": (("q", "qd"), True),
    "operational_coriolis": (("q", "qd"), True),
}


def _task_calls(name: str, states: list, **options: object) -> tuple[Callable, ...]:
    function = getattr(ts, name)
    batch = [_batch(s) for s in states]
    return (lambda: function(ARM, ts.PlanarPosition(), *states, **options),
            lambda: function(ARM, ts.PlanarPosition(), *batch, **options),
            lambda: function(ARM, _general_output(), *states, **options))  # fmt: skip


@pytest.mark.parametrize("name", sorted(TASK))
@pytest.mark.parametrize("bad", sorted(BAD_STATES))
def test_task_space_refuses_a_bad_state_alike_on_every_path(name: str, bad: str) -> None:
    """qd, tau or yddot passed as None used to be computed with q in their place on the fast path."""
    for k in range(len(TASK[name][0])):
        states: list = [x.copy() for x in GOOD[: len(TASK[name][0])]]
        states[k] = BAD_STATES[bad]()
        _same_refusal(*_task_calls(name, states))


BAD_OPTIONS = [("damping", v) for v in (math.inf, -math.inf, math.nan, 0.0, -1.0, True, "1e-3")]
BAD_OPTIONS += [("max_condition", v) for v in (math.inf, -math.inf, math.nan, 0.0, 0.5, True, "1e8")]


@pytest.mark.parametrize("name", sorted(name for name, (_, takes) in TASK.items() if takes))
@pytest.mark.parametrize(("option", "value"), BAD_OPTIONS)
def test_task_space_refuses_a_bad_option_alike_on_every_path(name: str, option: str, value: object) -> None:
    """damping=inf (and max_condition=inf) used to be taken by the fast path, refused by the general one."""
    states = [x.copy() for x in GOOD[: len(TASK[name][0])]]
    _same_refusal(*_task_calls(name, states, **{option: value}))


TASK_OUT = ["task_inertia", "task_coriolis", "task_gravity", "task_nonlinear", "task_friction", "task_force",
            "task_inverse_dynamics", "task_regressor", "task_forward_dynamics", "operational_inertia"]  # fmt: skip


@pytest.mark.parametrize("name", TASK_OUT)
@pytest.mark.parametrize("bad", sorted(BAD_OUTS))
def test_task_space_refuses_a_bad_out_alike_on_every_path(name: str, bad: str) -> None:
    function = getattr(ts, name)
    states = [x.copy() for x in GOOD[: len(TASK[name][0])]]
    shape = function(ARM, ts.PlanarPosition(), *states).shape
    batch = [s[None] for s in states]
    _same_refusal(partial(function, ARM, ts.PlanarPosition(), *states, out=BAD_OUTS[bad](shape)),
                  partial(function, ARM, ts.PlanarPosition(), *batch, out=BAD_OUTS[bad]((1, *shape))),
                  partial(function, ARM, _general_output(), *states, out=BAD_OUTS[bad](shape)))  # fmt: skip


def test_operational_space_and_coriolis_take_out() -> None:
    """The two functions the docs said take out= (and did not): their results written into the arrays given, equal
    to a fresh call's; aliased or misshapen arrays refused on both paths."""
    output = ts.PlanarPosition()
    for batch in ((), (3,)):
        q, qd = (np.broadcast_to(x, (*batch, N)).copy() for x in GOOD[:2])
        fresh = ts.operational_space(ARM, output, q, qd)
        arrays = tuple(np.full(getattr(fresh, f).shape, np.nan) for f in ("J", "Lambda", "Jbar", "mu", "p",
                                                                           "friction", "Nproj"))  # fmt: skip
        got = ts.operational_space(ARM, output, q, qd, out=arrays)
        for name, array in zip(("J", "Lambda", "Jbar", "mu", "p", "friction", "Nproj"), arrays, strict=True):
            assert getattr(got, name) is array
            np.testing.assert_array_equal(array, getattr(fresh, name))
        again = ts.operational_space(ARM, output, q, qd, out=got)  # an OperationalSpace as out
        assert again.Lambda is arrays[1]
        mu_x, coupling = ts.operational_coriolis(ARM, output, q, qd)
        pair = (np.full(mu_x.shape, np.nan), np.full(coupling.shape, np.nan))
        written = ts.operational_coriolis(ARM, output, q, qd, out=pair)
        assert written[0] is pair[0] and written[1] is pair[1]
        np.testing.assert_array_equal(pair[0], mu_x)
        np.testing.assert_array_equal(pair[1], coupling)
    shared = np.zeros((N, N))
    for out in ((shared,) * 7, (shared, shared[:, :N]), (np.zeros(3),) * 2, "out"):
        _same_refusal(partial(ts.operational_space, ARM, output, *GOOD[:2], out=out),
                      partial(ts.operational_space, ARM, _general_output(), *GOOD[:2], out=out))  # fmt: skip
    with pytest.raises(ModelError, match="share memory"):
        ts.operational_coriolis(ARM, output, *GOOD[:2], out=(shared, shared[0]))


# ----- generated code and the compiled closed form -------------------------------------------------------------
@pytest.fixture(scope="module")
def compiled() -> dict[str, object]:
    return {"generated": generate_code(ARM).compile(), "closed form": derive(ARM).compile()}


GENERATED = {"tau": 3, "M": 1, "G": 1, "N": 2, "Vm": 2}


@pytest.mark.parametrize("kind", ["generated", "closed form"])
@pytest.mark.parametrize("bad", sorted(BAD_STATES))
def test_compiled_code_refuses_a_bad_state_alike_on_both_paths(compiled: dict, kind: str, bad: str) -> None:
    code = compiled[kind]
    for name, count in GENERATED.items():
        if not hasattr(code, name) or (kind == "closed form" and name == "N"):
            continue
        function = getattr(code, name)
        for k in range(count):
            states = [x.copy() for x in GOOD[:count]]
            states[k] = BAD_STATES[bad]()
            _same_refusal(partial(function, *states), partial(function, *[_batch(s) for s in states]))


@pytest.mark.parametrize("kind", ["generated", "closed form"])
@pytest.mark.parametrize("bad", sorted(BAD_OUTS))
def test_compiled_code_refuses_a_bad_out_alike_on_both_paths(compiled: dict, kind: str, bad: str) -> None:
    code = compiled[kind]
    for name, count in (("tau", 3), ("M", 1)):
        function = getattr(code, name)
        shape = function(*GOOD[:count]).shape
        _same_refusal(partial(function, *GOOD[:count], out=BAD_OUTS[bad](shape)),
                      partial(function, *[x[None] for x in GOOD[:count]], out=BAD_OUTS[bad]((1, *shape))))  # fmt: skip
