"""Controllers, trajectories and the state derivative called directly: a bad argument is a
ModelError (or TypeError) that names it, and valid calls (one state, a batch, lists) agree."""

from __future__ import annotations

import re
from collections.abc import Callable
from fractions import Fraction
from types import GeneratorType

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

import armdyn as ad
from armdyn import control, statespace, trajectories

ARM = ad.models.two_link_planar()
N = ARM.n
RNG = np.random.default_rng(7)
STATES = dict(zip(("q", "qd", "q_d", "qd_d", "qdd_d", "e_int"), RNG.uniform(-1, 1, (6, N)), strict=True))
LAWS: dict[str, Callable[[], object]] = {
    "ComputedTorque": lambda: control.ComputedTorque(100.0, 20.0, 1.0, model=ARM),
    "PDGravity": lambda: control.PDGravity(10.0, 2.0, model=ARM),
    "PID": lambda: control.PID(10.0, 2.0, 1.0),
}
USED = {  # the states each law reads (the others it ignores)
    "ComputedTorque": ("q", "qd", "q_d", "qd_d", "qdd_d", "e_int"),
    "PDGravity": ("q", "qd", "q_d", "qd_d"),
    "PID": ("q", "qd", "q_d", "qd_d", "e_int"),
}
BAD_STATES = {
    "n-1 values": np.zeros(N - 1),
    "n+1 values": np.zeros(N + 1),
    "a column (n, 1)": np.zeros((N, 1)),
    "0-d array": np.array(0.5),
    "a scalar": 0.5,
    "empty": np.zeros(0),
    "empty list": [],
    "NaN": np.array([np.nan] + [0.0] * (N - 1)),
    "infinity": np.array([0.0] * (N - 1) + [-np.inf]),
    "NaN in a batch": np.array([[0.0] * N, [np.nan] * N]),
    "complex": np.zeros(N) + 1e-3j,
    "text": np.array(["x"] * N),
    "numeric text": np.array(["0.5"] * N),
    "bytes": np.array([b"0.5"] * N),
    "datetime64": np.full(N, "2020-01-01", dtype="datetime64[D]"),
    "None": None,
    "None entry": [None] + [0.0] * (N - 1),
    "dict": {"q": 1.0},
    "ragged list": [[0.0] * N, [0.0] * (N - 1)],
    "huge python int": [10**400] + [0.0] * (N - 1),
    "1e300 entry": np.array([1e300] + [0.0] * (N - 1)),
    "a generator": (x for x in np.zeros(N)),
}


def names(message: str, name: str) -> bool:
    """Whether ``message`` names the argument as a word of its own (q, not the q in q_d)."""
    return re.search(rf"(?<![\w.]){re.escape(name)}(?![\w])", message) is not None


def law_call(kind: str, **changed: object) -> np.ndarray:
    """The law called directly with the valid states, some of them replaced."""
    states = {**STATES, **changed}
    return LAWS[kind]()(0.0, *states.values())


@pytest.mark.parametrize("label", sorted(BAD_STATES))
@pytest.mark.parametrize("kind,argument", [(kind, name) for kind, used in USED.items() for name in used])
def test_a_bad_state_names_its_argument(kind: str, argument: str, label: str) -> None:
    value = BAD_STATES[label]
    if isinstance(value, GeneratorType):
        value = (x for x in np.zeros(N))  # a fresh generator for each case
    with pytest.raises((ad.ModelError, TypeError)) as raised:
        law_call(kind, **{argument: value})
    assert names(str(raised.value), argument), str(raised.value)


@pytest.mark.parametrize("kind", sorted(LAWS))
def test_a_batch_that_does_not_broadcast_names_the_arguments(kind: str) -> None:
    others = {name: np.stack([STATES[name]] * 2) for name in USED[kind]}
    with pytest.raises(ad.ModelError) as raised:
        law_call(kind, **{**others, "q": np.stack([STATES["q"]] * 3)})
    assert names(str(raised.value), "q") and names(str(raised.value), "qd"), str(raised.value)


@pytest.mark.parametrize("kind", sorted(LAWS))
def test_a_batch_gives_each_state_its_own_torque(kind: str) -> None:
    batch = {name: np.stack([STATES[name], STATES[name] * 0.5 + 0.1, -STATES[name]]) for name in STATES}
    together = law_call(kind, **batch)
    one_by_one = [law_call(kind, **{name: batch[name][k] for name in STATES}) for k in range(3)]
    assert together.shape == (3, N)
    assert_allclose(together, one_by_one, rtol=1e-13, atol=1e-13)
    nested = law_call(kind, q=batch["q"].reshape(3, 1, N))  # the other states broadcast against it
    assert_allclose(nested[:, 0], [law_call(kind, q=batch["q"][k]) for k in range(3)], rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("kind", sorted(LAWS))
def test_lists_fractions_and_the_fast_path_agree_bitwise(kind: str) -> None:
    plain = law_call(kind)
    assert_array_equal(law_call(kind, **{name: value.tolist() for name, value in STATES.items()}), plain)
    quarters = [Fraction(round(x * 4), 4) for x in STATES["qd"]]
    assert_array_equal(law_call(kind, qd=quarters), law_call(kind, qd=np.array([float(x) for x in quarters])))


def test_computed_torque_is_the_formula_it_always_was() -> None:
    s = STATES
    u = s["qdd_d"] + np.full(N, 20.0) * (s["qd_d"] - s["qd"]) + np.full(N, 100.0) * (s["q_d"] - s["q"])
    u = u + np.full(N, 1.0) * s["e_int"]
    expected = ARM.inertia_matrix(s["q"]) @ u + ARM.nonlinear_terms(s["q"], s["qd"])
    assert_array_equal(law_call("ComputedTorque"), expected)
    per_joint = control.ComputedTorque([100.0] * N, [20.0] * N, [1.0] * N, model=ARM)
    assert_array_equal(per_joint(0.0, *s.values()), expected)
    assert_array_equal(control.ComputedTorque(100, 20, 1, model=ARM)(0.0, *s.values()), expected)  # int gains


@pytest.mark.parametrize("gain", ["kp", "kv", "ki"])
@pytest.mark.parametrize("value", [np.nan, -1.0, [1.0] * (N + 1), "high", np.eye(N)])
def test_a_bad_gain_names_it(gain: str, value: object) -> None:
    law = control.PID(**{"kp": 1.0, "kv": 1.0, "ki": 1.0, gain: value})
    with pytest.raises(ad.ModelError, match=gain):
        law(0.0, *STATES.values())


def test_a_model_based_law_needs_a_robot() -> None:
    with pytest.raises(ad.ModelError, match="model="):
        control.PDGravity(1.0, 1.0)(0.0, *STATES.values())
    with pytest.raises(TypeError, match="model"):
        control.ComputedTorque(1.0, 1.0, model="puma")(0.0, *STATES.values())
    with pytest.raises(ad.ModelError, match="coulomb_smoothing"):
        LAWS["ComputedTorque"]()(0.0, *STATES.values(), coulomb_smoothing=[-1.0] * N)


def test_a_tiny_coulomb_smoothing_gives_the_sign_law_without_a_warning() -> None:
    arm = ARM.replace([link.__class__(**{**link.__dict__, "coulomb": (0.5, -0.5)}) for link in ARM.links])
    law = control.ComputedTorque(100.0, 20.0, model=arm)
    qd = np.array([1e14, -1e14])
    with np.errstate(all="raise"):
        tiny = law(0.0, STATES["q"], qd, *list(STATES.values())[2:], coulomb_smoothing=np.full(N, 1e-300))
    assert_array_equal(tiny, law(0.0, STATES["q"], qd, *list(STATES.values())[2:], coulomb_smoothing=np.zeros(N)))


@pytest.mark.parametrize(
    "make,name",
    [
        (lambda: control.Saturated(control.PID(1.0, 1.0), 10**400), "limit"),
        (lambda: control.Saturated(control.PID(1.0, 1.0), [1.0, np.nan]), "limit"),
        (lambda: control.Saturated(control.PID(1.0, 1.0), 1j), "limit"),
        (lambda: control.Saturated(control.PID(1.0, 1.0), []), "limit"),
        (lambda: control.Saturated(control.PID(1.0, 1.0), [1.0] * (N + 1))(0.0, *STATES.values()), "limit"),
        (lambda: control.Digital(control.PID(1.0, 1.0), 10**400), "period"),
        (lambda: control.Digital(control.PID(1.0, 1.0), None), "period"),
        (lambda: control.Digital(control.PID(1.0, 1.0), "0.01"), "period"),
        (lambda: control.Digital(control.PID(1.0, 1.0), -0.01), "period"),
    ],
)
def test_saturated_and_digital_name_a_bad_limit_or_period(make: Callable[[], object], name: str) -> None:
    with pytest.raises(ad.ModelError, match=name):
        make()


def test_saturated_and_digital_pass_valid_calls_through() -> None:
    pid = control.PID(10.0, 2.0, 1.0)
    tau = pid(0.0, *STATES.values())
    clipped = control.Saturated(pid, [0.5, np.inf])(0.0, *STATES.values())
    assert_array_equal(clipped, [np.clip(tau[0], -0.5, 0.5), tau[1]])
    digital = control.Digital(pid, Fraction(1, 100))
    assert digital.period == 0.01 and isinstance(digital.period, float)
    assert_array_equal(digital(0.0, *STATES.values()), tau)


# ----- trajectories -------------------------------------------------------------------------

BAD_TIMES = [np.nan, np.inf, -np.inf, None, 1j, "0.3", {"t": 0.3}, 1e300, 10**400, [0.1, np.nan]]
BAD_PARAMETERS = [[0.1] * 4, [], [[0.1, 0.2, 0.3]], np.nan, [0.1, np.inf, 0.1], "fast", None, 1j, 1e300, 10**400]


@pytest.mark.parametrize("t", BAD_TIMES, ids=repr)
@pytest.mark.parametrize("kind", ["Sinusoid", "Quintic", "CartesianCircle"])
def test_a_bad_time_names_t(kind: str, t: object) -> None:
    trajectory = {
        "Sinusoid": trajectories.Sinusoid([0.1, 0.2, 0.3], 0.5),
        "Quintic": trajectories.Quintic(0.0, [0.1, 0.2, 0.3], 0.0, 1.0),
        "CartesianCircle": trajectories.CartesianCircle(1.0, 1.0, (1.0, 0.5), 0.2, 2.0),
    }[kind]
    with pytest.raises(ad.ModelError) as raised:
        trajectory(t)
    assert names(str(raised.value), "t"), str(raised.value)


@pytest.mark.parametrize("value", BAD_PARAMETERS, ids=repr)
@pytest.mark.parametrize("name", ["amplitude", "frequency", "phase", "offset"])
def test_a_bad_sinusoid_parameter_names_it(name: str, value: object) -> None:
    arguments = {"amplitude": [0.1, 0.2, 0.3], "frequency": 0.5, name: value}
    with pytest.raises(ad.ModelError) as raised:
        trajectories.Sinusoid(**arguments)(0.3, 3)
    assert names(str(raised.value), name), str(raised.value)


@pytest.mark.parametrize("value", BAD_PARAMETERS, ids=repr)
@pytest.mark.parametrize("name", ["q0", "q1"])
def test_a_bad_quintic_end_names_it(name: str, value: object) -> None:
    arguments = {"q0": [0.1, 0.2, 0.3], "q1": 0.0, name: value}
    with pytest.raises(ad.ModelError) as raised:
        trajectories.Quintic(**arguments)(0.3, 3)
    assert names(str(raised.value), name), str(raised.value)


@pytest.mark.parametrize("value", [None, "0.0", [0.0], np.array([0.0, 0.0]), np.inf, np.nan, 1j, 10**400])
@pytest.mark.parametrize("name", ["t0", "t1"])
def test_a_bad_quintic_time_names_it(name: str, value: object) -> None:
    with pytest.raises(ad.ModelError) as raised:
        trajectories.Quintic(0.0, 1.0, **{"t0": -1.0, "t1": 1.0, name: value})
    assert names(str(raised.value), name), str(raised.value)


@pytest.mark.parametrize("n", [0, -1, 1.5, "3", True])
def test_a_bad_joint_count_names_n(n: object) -> None:
    with pytest.raises((ad.ModelError, TypeError), match="n must"):
        trajectories.Sinusoid(0.1, 0.5)(0.3, n)


def test_a_quintic_of_a_tiny_span_is_at_rest_outside_it_and_refused_inside() -> None:
    brief = trajectories.Quintic([0.0, 1.0], [1.0, 3.0], 0.0, 1e-300)
    with np.errstate(all="raise"):
        q, qd, qdd = brief(0.3)
    assert_array_equal(q, [1.0, 3.0]) and assert_array_equal(qd, 0.0) and assert_array_equal(qdd, 0.0)
    with np.errstate(all="raise"):
        q, qd, qdd = trajectories.Quintic(0.0, 0.0, -1e-300, 1e-300)(0.0, 1)  # the middle: a = 0 there
    assert_array_equal(qdd, [0.0])
    with pytest.raises(ad.ModelError, match="t falls inside"):
        brief(2.5e-301)


def test_trajectories_give_a_batch_of_times_what_they_give_each_time() -> None:
    times = np.array([[0.0, 0.3], [0.7, 1.4]])
    for trajectory in (
        trajectories.Sinusoid([0.1, 0.2], [0.5, 1.0], phase=[0.0, np.pi / 2], offset=0.3),
        trajectories.Quintic([0.0, 1.0], [1.0, 3.0], 0.2, 1.2),
        trajectories.CartesianCircle(1.0, 1.0, (1.0, 0.5), 0.2, 2.0),
    ):
        together = trajectory(times)
        for k in np.ndindex(times.shape):
            for part, one in zip(together, trajectory(float(times[k])), strict=True):
                assert_allclose(part[k], one, rtol=1e-13, atol=1e-13)


def test_a_circle_outside_the_workspace_or_on_its_boundary_is_refused() -> None:
    with pytest.raises(ad.ModelError, match="workspace"):
        trajectories.CartesianCircle(1.0, 1.0, (1.5, 0.0), 0.5, 2.0)(0.0)  # reaches x = 2, the stretched arm
    with pytest.raises(ad.ModelError, match="period"):
        trajectories.CartesianCircle(1.0, 1.0, (1.0, 0.5), 0.2, 0.0)
    with pytest.raises(ad.ModelError, match="centre"):
        trajectories.CartesianCircle(1.0, 1.0, (1.0, 0.5, 0.0), 0.2, 2.0)


# ----- the state derivative -----------------------------------------------------------------


def test_state_derivative_names_x_and_tau_when_their_batches_do_not_broadcast() -> None:
    x = np.concatenate([STATES["q"], STATES["qd"]])
    with pytest.raises(ad.ModelError) as raised:
        statespace.state_derivative(ARM, np.stack([x] * 3), np.stack([STATES["e_int"]] * 2))
    message = str(raised.value)
    assert names(message, "x") and names(message, "tau") and not names(message, "q"), message
    batch = statespace.state_derivative(ARM, np.stack([x] * 3), STATES["e_int"])
    assert_array_equal(batch[1], statespace.state_derivative(ARM, x, STATES["e_int"]))
