"""The Stribeck and sigmoid friction laws (Link.stribeck, Link.sigmoid): one law in the model, every kernel,
simulate, the controllers and the Lagrange-Euler reference."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import armdyn as ad
from armdyn import ModelError
from armdyn.control import ComputedTorque
from armdyn.dynamics import lagrange
from armdyn.dynamics.friction import friction_vector
from armdyn.simulation import simulate


def gaz_sigmoid(A: float, alpha: float, shift: float, qd: np.ndarray) -> np.ndarray:
    """The sigmoid law as Gaz et al. (IEEE RA-L 4(4), 2019) write it, for moderate alpha qd (no overflow guard)."""
    return A / (1 + np.exp(-alpha * (qd + shift))) - A / (1 + np.exp(-alpha * shift))


def with_laws(arm: ad.Robot, seed: int) -> ad.Robot:
    """The arm with random Stribeck and sigmoid friction on every joint (Coulomb and viscous kept)."""
    rng = np.random.default_rng(seed)
    links = [
        dataclasses.replace(
            link,
            stribeck=(rng.uniform(0.5, 2.0), rng.uniform(0.05, 0.3)),
            sigmoid=(rng.uniform(1.0, 5.0), rng.uniform(5.0, 40.0), rng.uniform(-0.1, 0.1)),
        )
        for link in arm.links
    ]
    return arm.replace(links)


def planar3(seed: int) -> ad.Robot:
    """A random three-joint arm from a DH table whose rows carry every friction law."""
    rng = np.random.default_rng(seed)
    rows = [
        {
            "a": rng.uniform(0.2, 0.5),
            "alpha": rng.choice([0.0, np.pi / 2]),
            "mass": rng.uniform(1.0, 3.0),
            "com": rng.uniform(-0.1, 0.1, 3),
            "inertia": rng.uniform(0.01, 0.02, 3),
            "B": rng.uniform(0.0, 0.5),
            "Tc": (rng.uniform(0.0, 1.0), -rng.uniform(0.0, 1.0)),
            "stribeck": (rng.uniform(0.2, 1.0), rng.uniform(0.05, 0.2)),
            "sigmoid": (rng.uniform(0.5, 3.0), rng.uniform(2.0, 30.0), rng.uniform(-0.2, 0.2)),
        }
        for _ in range(3)
    ]
    return ad.Robot.from_dh(rows, name="planar3")


ARMS = {
    "puma560": lambda: with_laws(ad.models.load("puma560"), 1),
    "planar3": lambda: planar3(2),
}


@pytest.fixture(params=sorted(ARMS), scope="module")
def arm(request: pytest.FixtureRequest) -> ad.Robot:
    return ARMS[request.param]()


def states(arm: ad.Robot, count: int, seed: int, slowest: float = 0.05) -> tuple[np.ndarray, ...]:
    """Random states with every |qd_j| at least ``slowest`` (away from the sign laws' step)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.5, 1.5, (count, arm.n))
    qd = rng.uniform(slowest, 2.0, (count, arm.n)) * rng.choice([-1.0, 1.0], (count, arm.n))
    qdd = rng.uniform(-3.0, 3.0, (count, arm.n))
    return q, qd, qdd


def test_friction_is_the_published_laws(arm: ad.Robot) -> None:
    """arm.friction (the compiled law) equals B qd + Tc + Fs exp(-(qd/vs)^2) sgn qd + the sigmoid of Gaz et al.,
    written out here from the papers, and the NumPy mirror; zero at rest."""
    _, qd, _ = states(arm, 50, 3, slowest=0.0)
    qd[0] = 0.0
    expected = np.zeros_like(qd)
    for j, link in enumerate(arm.links):
        G = link.gear_ratio
        Fs, vs = link.stribeck
        expected[:, j] = (G**2 * link.viscous * qd[:, j]
                          + np.where(qd[:, j] > 0, abs(G) * link.coulomb[0], 0.0)
                          + np.where(qd[:, j] < 0, abs(G) * link.coulomb[1], 0.0)
                          + Fs * np.exp(-((qd[:, j] / vs) ** 2)) * np.sign(qd[:, j])
                          + gaz_sigmoid(*link.sigmoid, qd[:, j]))  # fmt: skip
    np.testing.assert_allclose(arm.friction(qd), expected, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(arm.friction(qd[5]), expected[5], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(friction_vector(arm, qd), expected, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(lagrange.friction(arm, qd), expected, rtol=1e-13, atol=1e-13)
    assert np.abs(arm.friction(np.zeros(arm.n))).max() < 1e-14


def test_friction_dissipates(arm: ad.Robot) -> None:
    """F(qd) qd >= 0 per joint, over fast and slow speeds of both signs."""
    speeds = np.concatenate([np.linspace(-50, 50, 2001), np.geomspace(1e-9, 1.0, 200), -np.geomspace(1e-9, 1.0, 200)])
    qd = np.repeat(speeds[:, None], arm.n, axis=1)
    assert np.all(arm.friction(qd) * qd >= 0.0)


def test_sigmoid_does_not_overflow() -> None:
    """A steep sigmoid at high speed: A - A / (1 + exp(-alpha shift)) above, its negative part below, finite."""
    link = ad.Link("j", ad.Joint("revolute"), ad.Inertial(1.0, [0.1, 0, 0], [0.01] * 3), sigmoid=(2.0, 1e4, 0.01))
    arm = ad.Robot([link])
    rest = 2.0 / (1 + np.exp(-1e4 * 0.01))
    qd = np.array([[1e6], [-1e6], [1e14], [-1e14]])
    F = arm.friction(qd)
    assert np.all(np.isfinite(F))
    np.testing.assert_allclose(F[:, 0], [2.0 - rest, -rest, 2.0 - rest, -rest], rtol=1e-15, atol=1e-15)
    assert np.all(np.isfinite(friction_vector(arm, qd)))


def test_rnea_is_the_robot_equation(arm: ad.Robot) -> None:
    """tau = M qdd + Vm qd + G + F(qd) to 1e-10, and the Lagrange-Euler reference."""
    q, qd, qdd = states(arm, 20, 4)
    tau = arm.inverse_dynamics(q, qd, qdd)
    M = arm.inertia_matrix(q)
    expected = np.einsum("...jk,...k->...j", M, qdd) + arm.coriolis_vector(q, qd) + arm.gravity_vector(q)
    expected += arm.friction(qd)
    scale = np.abs(tau).max()
    assert np.abs(tau - expected).max() < 1e-10 * scale
    assert np.abs(tau - lagrange.inverse_dynamics(arm, q, qd, qdd)).max() < 1e-10 * scale
    for k in range(3):  # one state
        assert np.abs(arm.inverse_dynamics(q[k], qd[k], qdd[k]) - tau[k]).max() < 1e-12 * scale
    bare = arm.replace([dataclasses.replace(link, stribeck=(0.0, 0.0), sigmoid=(0.0, 0.0, 0.0)) for link in arm.links])
    extra = tau - bare.inverse_dynamics(q, qd, qdd)
    assert np.abs(extra).min() > 0  # the laws are in the kernels, not only in F


def test_aba_inverts_rnea(arm: ad.Robot) -> None:
    """forward_dynamics(q, qd, inverse_dynamics(q, qd, qdd)) = qdd, one state and a batch (the blocked kernel)."""
    q, qd, qdd = states(arm, 70, 5)
    tau = arm.inverse_dynamics(q, qd, qdd)
    np.testing.assert_allclose(arm.forward_dynamics(q, qd, tau), qdd, rtol=0, atol=1e-9)
    for k in range(3):
        np.testing.assert_allclose(arm.forward_dynamics(q[k], qd[k], tau[k]), qdd[k], rtol=0, atol=1e-9)
    np.testing.assert_allclose(arm.forward_dynamics(q[:3], qd[:3], tau[:3]), qdd[:3], rtol=0, atol=1e-9)


def smoothed_minus_exact(arm: ad.Robot, qd: np.ndarray, eps: float | None) -> np.ndarray:
    if eps is None:
        return np.zeros_like(qd)
    return friction_vector(arm, qd, np.full(arm.n, eps)) - friction_vector(arm, qd)


@pytest.mark.parametrize("eps", [None, 0.3])
def test_inverse_dynamics_derivatives_match_differences(arm: ad.Robot, eps: float | None) -> None:
    """d tau/dq and d tau/dqd against central differences, away from qd = 0; with a smoothing eps, of the
    smoothed law (the NumPy mirror's)."""
    q, qd, qdd = (x[0] for x in states(arm, 1, 6, slowest=0.2))

    def tau(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return arm.inverse_dynamics(q, qd, qdd) + smoothed_minus_exact(arm, qd, eps)

    d_q, d_qd = arm.inverse_dynamics_derivatives(q, qd, qdd, coulomb_smoothing=eps)
    h = 1e-6
    eye = np.eye(arm.n)
    fd_q = np.column_stack([(tau(q + h * e, qd) - tau(q - h * e, qd)) / (2 * h) for e in eye])
    fd_qd = np.column_stack([(tau(q, qd + h * e) - tau(q, qd - h * e)) / (2 * h) for e in eye])
    scale = max(1.0, np.abs(fd_qd).max(), np.abs(fd_q).max())
    np.testing.assert_allclose(d_q, fd_q, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(d_qd, fd_qd, rtol=0, atol=1e-6 * scale)


@pytest.mark.parametrize("eps", [None, 0.3])
def test_forward_dynamics_derivatives_match_differences(arm: ad.Robot, eps: float | None) -> None:
    """d qdd/dq, d qdd/dqd, d qdd/dtau against central differences of the (smoothed) plant, away from qd = 0."""
    q, qd, qdd = (x[0] for x in states(arm, 1, 7, slowest=0.2))
    tau0 = arm.inverse_dynamics(q, qd, qdd)

    def qdd_of(q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        return arm.forward_dynamics(q, qd, tau - smoothed_minus_exact(arm, qd, eps))

    d_q, d_qd, d_tau = arm.forward_dynamics_derivatives(q, qd, tau0, coulomb_smoothing=eps)
    h = 1e-6
    eye = np.eye(arm.n)
    fd_q = np.column_stack([(qdd_of(q + h * e, qd, tau0) - qdd_of(q - h * e, qd, tau0)) / (2 * h) for e in eye])
    fd_qd = np.column_stack([(qdd_of(q, qd + h * e, tau0) - qdd_of(q, qd - h * e, tau0)) / (2 * h) for e in eye])
    fd_tau = np.column_stack([(qdd_of(q, qd, tau0 + h * e) - qdd_of(q, qd, tau0 - h * e)) / (2 * h) for e in eye])
    for analytic, numeric in ((d_q, fd_q), (d_qd, fd_qd), (d_tau, fd_tau)):
        np.testing.assert_allclose(analytic, numeric, rtol=0, atol=1e-6 * max(1.0, np.abs(numeric).max()))


def test_simulated_energy_balance_with_the_laws(arm: ad.Robot) -> None:
    """Without torque, H(T) - H(0) = -integral qd^T F_smooth(qd) dt, F_smooth the simulated plant's law (the
    Coulomb and Stribeck signs smoothed with eps); and the run differs from the one without the new laws."""
    eps = 0.05
    q0 = arm.configuration("qn") if "qn" in arm.configurations else np.full(arm.n, 0.3)
    dt = 2e-4
    result = simulate(arm, None, None, t_final=0.4, dt=dt, q0=q0, qd0=np.full(arm.n, 0.5), coulomb_smoothing=eps)
    power = np.einsum("ti,ti->t", result.qd, friction_vector(arm, result.qd, np.full(arm.n, eps)))
    dissipated = np.sum(power[:-1] + power[1:]) * dt / 2  # trapezoid, O(dt^2)
    gained = result.energy[-1] - result.energy[0]
    assert dissipated > 0
    assert abs(gained + dissipated) < 1e-3 * dissipated
    bare = arm.replace([dataclasses.replace(link, stribeck=(0.0, 0.0), sigmoid=(0.0, 0.0, 0.0)) for link in arm.links])
    other = simulate(bare, None, None, t_final=0.4, dt=dt, q0=q0, qd0=np.full(arm.n, 0.5), coulomb_smoothing=eps)
    assert np.abs(other.q[-1] - result.q[-1]).max() > 1e-3


def test_computed_torque_cancels_the_laws_as_the_plant_smooths_them(arm: ad.Robot) -> None:
    """Computed torque with the plant as its model cancels its friction (the Stribeck sign smoothed as the
    plant's): it tracks as well as on the arm without the new laws (what is left is the torque held over each
    RK4 step), ten times better than a model without them; the compiled loop and the Python loop (the NumPy
    mirror of the smoothed law) give the same run."""
    path = ad.trajectories.Sinusoid(0.3, 1.0, 0.0, np.full(arm.n, 0.2))
    q0, qd0, _ = path(0.0)
    start = {"q0": q0, "qd0": qd0, "t_final": 0.3, "dt": 1e-3, "coulomb_smoothing": 0.02}
    bare = arm.replace([dataclasses.replace(link, stribeck=(0.0, 0.0), sigmoid=(0.0, 0.0, 0.0)) for link in arm.links])
    compiled = simulate(arm, ComputedTorque(100.0, 20.0), path, **start)
    reference = simulate(bare, ComputedTorque(100.0, 20.0), path, **start)
    wrong = simulate(arm, ComputedTorque(100.0, 20.0, model=bare), path, **start)
    error, floor = np.abs(compiled.error).max(), np.abs(reference.error).max()
    assert error < 2 * floor
    assert np.abs(wrong.error).max() > 10 * error
    law = ComputedTorque(100.0, 20.0, model=arm)

    def mine(t, q, qd, q_d, qd_d, qdd_d, e_int, coulomb_smoothing=None):  # type: ignore[no-untyped-def]
        return law(t, q, qd, q_d, qd_d, qdd_d, e_int, coulomb_smoothing=coulomb_smoothing)

    with pytest.warns(Warning):  # the Python loop's PythonLoopWarning
        python = simulate(arm, mine, path, **start)
    np.testing.assert_allclose(python.q, compiled.q, rtol=0, atol=1e-12)


def test_plant_variants_scale_every_friction_force() -> None:
    """friction_scale multiplies B, Tc, Fs and the sigmoid's A (not vs, alpha or shift): a variant runs as the arm
    built with those values."""
    arm = planar3(3)
    scaled = arm.replace(
        [dataclasses.replace(link, viscous=2 * link.viscous, coulomb=(2 * link.coulomb[0], 2 * link.coulomb[1]),
                             stribeck=(2 * link.stribeck[0], link.stribeck[1]),
                             sigmoid=(2 * link.sigmoid[0], *link.sigmoid[1:])) for link in arm.links]
    )  # fmt: skip
    variants = ad.simulation.plant_variants(arm, 1, friction_scale=2.0)
    q0, qd0 = np.full(3, 0.2), np.full(3, 0.7)
    ran = simulate(arm, None, None, t_final=0.1, dt=1e-3, q0=q0, qd0=qd0, plants=variants, keep="full",
                   coulomb_smoothing="auto")  # fmt: skip
    one = simulate(scaled, None, None, t_final=0.1, dt=1e-3, q0=q0, qd0=qd0)
    np.testing.assert_allclose(ran.samples["q"][0], one.q, rtol=0, atol=1e-12)


def test_linearize_refuses_the_exact_stribeck_law_at_rest() -> None:
    arm = planar3(4).replace([dataclasses.replace(link, coulomb=(0.0, 0.0), viscous=0.1) for link in planar3(4).links])
    with pytest.raises(ModelError, match="Stribeck friction of joint 'joint1'"):
        ad.statespace.linearize(arm, np.zeros(3), np.zeros(3), np.zeros(3))
    ad.statespace.linearize(arm, np.zeros(3), np.zeros(3), np.zeros(3), coulomb_smoothing=0.01)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("stribeck", (-1.0, 0.1), "Fs >= 0"),
        ("stribeck", (1.0, 0.0), "vs > 0"),
        ("stribeck", (1.0, -0.1), "vs > 0"),
        ("stribeck", (1.0, 0.1, 0.0), "two finite numbers"),
        ("stribeck", (np.nan, 0.1), "Stribeck"),
        ("sigmoid", (-1.0, 1.0, 0.0), "A >= 0 and alpha >= 0"),
        ("sigmoid", (1.0, -1.0, 0.0), "A >= 0 and alpha >= 0"),
        ("sigmoid", (1.0, 1.0), "three finite numbers"),
        ("sigmoid", (1.0, np.inf, 0.0), "sigmoid"),
        ("sigmoid", "abc", "sigmoid"),
    ],
)
def test_bad_friction_values_are_refused(field: str, value: object, message: str) -> None:
    joint, body = ad.Joint("revolute"), ad.Inertial(1.0, [0.1, 0, 0], [0.01] * 3)
    with pytest.raises(ModelError, match=f"link 'elbow'.*{message}"):
        ad.Link("elbow", joint, body, **{field: value})
    with pytest.raises(ModelError, match=f"link 'elbow'.*{message}"):
        ad.Robot.from_dh([{"a": 0.3, "mass": 1.0, "name": "elbow", field: value}])


def test_no_stribeck_force_needs_no_speed() -> None:
    link = ad.Link("j", ad.Joint("revolute"), ad.Inertial(1.0, [0.1, 0, 0], [0.01] * 3), stribeck=(0.0, 0.0))
    assert link.stribeck == (0.0, 0.0) and link.sigmoid == (0.0, 0.0, 0.0)


def test_without_friction_drops_every_law(arm: ad.Robot) -> None:
    assert not np.any(arm.without_friction().friction(np.full(arm.n, 0.7)))
    kept = arm.without_motors()
    np.testing.assert_allclose(kept.friction(np.full(arm.n, 0.7)), arm.friction(np.full(arm.n, 0.7)), rtol=1e-14)


def test_display_shows_the_laws_when_present() -> None:
    arm = planar3(5)
    text = str(arm)
    assert "Stribeck friction" in text and "sigmoid friction" in text
    plain = str(arm.without_friction())
    assert "Stribeck" not in plain and "sigmoid" not in plain


def test_symbolic_routes_refuse_the_laws_by_name() -> None:
    from armdyn.symbolic import derive, generate_code

    arm = ad.models.two_link_planar()
    links = list(arm.links)
    links[1] = dataclasses.replace(links[1], sigmoid=(1.0, 10.0, 0.0))
    arm = arm.replace(links)
    with pytest.raises(ModelError, match=f"link '{links[1].name}'.*sigmoid friction"):
        derive(arm)
    with pytest.raises(ModelError, match=f"link '{links[1].name}'.*sigmoid friction"):
        generate_code(arm, ["tau"])
    form = derive(arm, friction=False)  # no friction asked: the rest of the equation
    assert form.M.shape == (2, 2)
    generate_code(arm, ["M", "G"])


def test_adaptive_solver_follows_the_same_smoothed_plant() -> None:
    """simulate's scipy path (its own NumPy mirror of the smoothed laws) agrees with the compiled RK4 run."""
    arm = planar3(6)
    start = {"q0": np.full(3, 0.2), "qd0": np.array([0.5, -0.3, 0.05]), "t_final": 0.2, "dt": 1e-4,
             "coulomb_smoothing": 0.05}  # fmt: skip
    fixed = simulate(arm, None, None, **start)
    adaptive = simulate(arm, None, None, method="rk45", **start)
    np.testing.assert_allclose(adaptive.q, fixed.q, rtol=0, atol=1e-6)


def test_show_lists_the_laws_per_link() -> None:
    from armdyn.cli import _dynamics_sheet

    sheet = _dynamics_sheet(planar3(7))
    assert any(c.startswith("Stribeck Fs") for c in sheet.columns) and any(
        c.startswith("sigmoid A") for c in sheet.columns
    )
    link = planar3(7).links[0]
    assert sheet.rows[0][-2].startswith(f"{link.stribeck[0]:.5g}"[:4])
    assert all(not c.startswith(("Stribeck", "sigmoid")) for c in _dynamics_sheet(ad.models.load("puma560")).columns)
