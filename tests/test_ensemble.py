"""simulate(..., runs=): N closed-loop runs in one compiled call, each equal to its single run."""

from __future__ import annotations

import numpy as np
import pytest

import armdyn as ad
from armdyn import control, simulation
from armdyn import trajectories as tr
from armdyn.dynamics.packed import HEADER, POSITION
from armdyn.errors import ModelError
from armdyn.simulation import SUMMARY_NAMES, plant_variants, run_summaries, simulate


@pytest.fixture(scope="module")
def puma() -> ad.Robot:
    return ad.models.puma560()


def test_one_run_equals_simulate(puma: ad.Robot) -> None:
    """Same RK4, same law: the run kept in full equals ad.simulate to rounding (here exactly)."""
    q0 = puma.configuration("qn")
    law, path = control.ComputedTorque(100.0, 20.0, 5.0), tr.Sinusoid(0.1, 0.5, 0.0, q0)
    many = simulate(puma, law, path, t_final=1.0, q0=q0, keep="full")
    single = ad.simulate(puma, law, path, t_final=1.0, q0=q0)
    for name, values in (("q", single.q), ("qd", single.qd), ("tau", single.tau), ("q_d", single.q_d)):
        assert np.abs(many.samples[name][0] - values).max() <= 1e-12 * max(1.0, np.abs(values).max()), name
    assert np.allclose(many.t, single.t) and many.finished.all()
    error = single.q_d - single.q
    late = single.t >= 1.0 - 1e-12
    assert np.allclose(many.summaries[0, 0], error[-1])
    assert np.allclose(many.summaries[0, 1], np.abs(error[late]).max(0))
    assert np.allclose(many.summaries[0, 2], np.sqrt(np.mean(error**2, axis=0)))
    assert np.allclose(many.summaries[0, 3], np.abs(single.tau).max(0))
    one, runs = single.to_xarray(), many.to_xarray()  # one run and many, under the same dimension names
    assert one["q"].dims == ("time", "joint") and runs["q"].dims == ("run", "time", "joint")
    assert list(one["joint"].values) == list(runs["joint"].values) == puma.joint_names
    np.testing.assert_allclose(runs["q"].isel(run=0).values, one["q"].values, rtol=0.0, atol=1e-12)
    assert np.allclose(one["error"].values, error) and one["energy"].dims == ("time",)


def test_one_result_interface_for_one_run_and_many(puma: ad.Robot) -> None:
    """A Result answers as many runs do: its summary row (NumPy, from its samples) equals the row the
    compiled many-run loop keeps for the same run, and single runs concatenated along "run" hold the
    many runs' Dataset."""
    import xarray

    rng = np.random.default_rng(11)
    q0 = puma.configuration("qn") + rng.uniform(-0.05, 0.05, (3, 6))
    law = control.PDGravity(80.0, 15.0)
    paths = [tr.Sinusoid(0.1, 0.7 + 0.2 * k, 0.0, q0[k]) for k in range(3)]
    many = simulate(puma, law, paths, t_final=1.5, q0=q0, keep="full")  # the error's window from 1 s on
    singles = [ad.simulate(puma, law, paths[k], t_final=1.5, q0=q0[k]) for k in range(3)]
    assert all(isinstance(r, ad.simulation.RunSummaries) for r in (many, *singles))
    assert [r.runs for r in singles] == [1, 1, 1] and many.runs == 3
    stacked = np.concatenate([r.summaries for r in singles])
    np.testing.assert_allclose(stacked, many.summaries, rtol=1e-10, atol=1e-12)
    late = [run_summaries(r.t, r.q, r.q_d, r.tau, 0.5) for r in singles]
    earlier = simulate(puma, law, paths, t_final=1.5, q0=q0, after=0.5)
    np.testing.assert_allclose(np.stack(late), earlier.summaries, rtol=1e-10, atol=1e-12)
    frames = [r.summary() for r in singles]
    assert list(frames[0].columns) == list(many.summary().columns) and bool(frames[0]["finished"].iloc[0])
    joined = xarray.concat([r.to_xarray() for r in singles], dim="run")
    whole = many.to_xarray()
    for name in ("q", "qd", "tau", "q_d", *SUMMARY_NAMES, "stopped_at", "reason"):
        assert joined[name].dims == whole[name].dims, name
        np.testing.assert_allclose(joined[name].values, whole[name].values, rtol=1e-10, atol=1e-12, err_msg=name)


def test_runs_with_different_plants_models_gains_and_starts_equal_their_single_runs(puma: ad.Robot) -> None:
    """Each run its own payload (plant), controller belief (model), gains, start, trajectory and disturbance:
    run k equals ad.simulate on arm.with_payload(...) with the same inputs, whatever the thread count."""
    rng = np.random.default_rng(3)
    runs = 5
    masses, centres = rng.uniform(0, 2, runs), rng.uniform(-0.05, 0.05, (runs, 3))
    plants = plant_variants(puma, runs, payload_mass=masses, payload_com=centres)
    models = plant_variants(puma, runs, payload_mass=0.5 * masses)
    q0 = puma.configuration("qn") + rng.uniform(-0.05, 0.05, (runs, 6))
    paths = [tr.Sinusoid(0.1, 0.5 + 0.1 * k, 0.0, q0[k]) for k in range(runs)]
    gains = np.stack([np.stack([np.full(6, 100.0 + 10 * k), np.full(6, 20.0), np.zeros(6)]) for k in range(runs)])
    tau_d = rng.uniform(-1, 1, (runs, 6))
    law = control.ComputedTorque(1.0, 1.0)
    one = simulate(puma, law, paths, t_final=0.5, q0=q0, plants=plants, models=models, gains=gains,
                        disturbance=tau_d, keep=1, threads=1)  # fmt: skip
    two = simulate(puma, law, paths, t_final=0.5, q0=q0, plants=plants, models=models, gains=gains,
                        disturbance=tau_d, keep=1, threads=2)  # fmt: skip
    assert np.array_equal(one.summaries, two.summaries) and np.array_equal(one.samples["q"], two.samples["q"])
    for k in range(runs):
        belief = puma.with_payload(0.5 * masses[k])
        single = ad.simulate(puma.with_payload(masses[k], centres[k]),
                             control.ComputedTorque(gains[k, 0], gains[k, 1], model=belief), paths[k], t_final=0.5,
                             q0=q0[k], disturbance=tau_d[k])  # fmt: skip
        assert np.abs(one.samples["q"][k] - single.q).max() < 1e-12, k


def test_decimated_samples_and_summaries_only(puma: ad.Robot) -> None:
    q0 = puma.configuration("qn")
    law, path = control.PDGravity(200.0, 30.0), tr.Sinusoid(0.05, 1.0, 0.0, q0)
    full = simulate(puma, law, path, t_final=0.3, q0=q0, keep="full")
    every = simulate(puma, law, path, t_final=0.3, q0=q0, keep=10)
    summary = simulate(puma, law, path, t_final=0.3, q0=q0, runs=1)
    assert every.samples["q"].shape == (1, 31, 6) and np.array_equal(every.samples["q"][0], full.samples["q"][0, ::10])
    assert summary.samples == {} and summary.t.size == 0 and np.array_equal(summary.summaries, full.summaries)
    frame = summary.summary()
    assert list(frame.index) == [0] and "max_error_after q2" in frame and bool(frame["finished"][0])
    dataset = every.to_xarray()
    assert dict(dataset.sizes) == {"run": 1, "time": 31, "joint": 6}
    assert set(SUMMARY_NAMES) <= set(dataset.data_vars)


def test_a_run_that_diverges_is_marked_and_the_others_finish() -> None:
    arm = ad.models.two_link_planar()
    law = control.PDGravity(1e9, 0.0)  # far beyond RK4's stability at 10 ms
    gains = [[[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]], [[1e9, 1e9], [0.0, 0.0], [0.0, 0.0]]]
    path = tr.Sinusoid(0.5, 1.0)
    result = simulate(arm, law, path, t_final=1.0, dt=1e-2, q0=[[0.0, 0.0], [0.5, 0.5]], gains=gains)
    assert result.finished.tolist() == [True, False] and result.outcome[1, 1] == 2


@pytest.mark.parametrize(
    "law", [None, control.PDGravity(80.0, 15.0), control.ComputedTorque(100.0, 20.0), control.PID(100.0, 20.0, 5.0)]
)
def test_many_runs_of_one_plant_advance_in_blocks_equal_to_the_run_by_run_loop(
    puma: ad.Robot, law: object, monkeypatch: pytest.MonkeyPatch
) -> None:
    """From BLOCKED_RUNS runs of one plant the runs advance together (run_blocks, a last block partial); each
    run's law, start, gains, trajectory and disturbance its own; the PUMA's Coulomb friction smoothed per run.
    They equal run_many's run-by-run loop to rounding (the articulated-body pass and a Cholesky solve), and a
    run that diverges stops at the same row."""
    runs = simulation.BLOCKED_RUNS + 5
    rng = np.random.default_rng(8)
    q0 = puma.configuration("qn") + rng.uniform(-0.1, 0.1, (runs, 6))
    gains = np.stack([np.stack([np.full(6, 60.0 + k), np.full(6, 15.0), np.zeros(6)]) for k in range(runs)])
    gains[3, 0] = 1e9  # far beyond RK4's stability at 1 ms: this run diverges
    paths = [tr.Sinusoid(0.1, 0.5 + 0.01 * k, 0.0, q0[k]) for k in range(runs)]
    options = {"t_final": 0.4, "q0": q0, "qd0": rng.uniform(-0.2, 0.2, (runs, 6)), "keep": 7,
               "disturbance": rng.uniform(-1, 1, (runs, 6))}  # fmt: skip
    if law is not None:
        options |= {"gains": gains}
    calls = []
    blocked = simulation.run_blocks

    def counted(*args: object) -> None:
        calls.append(len(args))
        blocked(*args)

    monkeypatch.setattr(simulation, "run_blocks", counted)
    together = simulate(puma, law, paths if law is not None else None, **options)
    assert calls, "the runs did not advance in blocks"
    monkeypatch.setattr(simulation, "BLOCKED_RUNS", runs + 1)
    one_by_one = simulate(puma, law, paths if law is not None else None, **options)
    assert len(calls) == 1
    np.testing.assert_array_equal(together.outcome, one_by_one.outcome)
    if law is not None:
        assert together.outcome[3, 1] == 2 and together.finished.sum() == runs - 1
    else:
        assert together.finished.all()
    kept = together.finished  # the diverged run's last values are huge: its rounding differs in absolute terms
    scale = np.abs(one_by_one.samples["tau"][kept]).max() + 1.0
    for name in ("q", "qd", "q_d"):
        got, want = together.samples[name][kept], one_by_one.samples[name][kept]
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-10, err_msg=name)
    tau, reference = together.samples["tau"][kept], one_by_one.samples["tau"][kept]
    np.testing.assert_allclose(tau, reference, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(together.summaries[kept], one_by_one.summaries[kept], rtol=1e-9, atol=1e-10 * scale)


def test_runs_with_payloads_and_scaled_masses_advance_in_blocks(
    puma: ad.Robot, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Plants that differ in masses, inertias and friction (a payload, plant_variants) share a block: each run's
    own in the block pass; a plant with other kinematics sends the runs run by run."""
    runs = simulation.BLOCKED_RUNS + 3
    rng = np.random.default_rng(9)
    payloads = {"payload_mass": rng.uniform(0, 2, runs), "payload_com": rng.uniform(-0.05, 0.05, (runs, 3))}
    scales = {"mass_scale": rng.uniform(0.8, 1.2, (runs, 6)), "friction_scale": rng.uniform(0.5, 1.5, (runs, 6))}
    plants = plant_variants(puma, runs, **payloads, **scales)
    assert simulation.blocks_apply(plants.packed, np.arange(runs))
    q0 = puma.configuration("qn") + rng.uniform(-0.1, 0.1, (runs, 6))
    options = {"t_final": 0.3, "q0": q0, "plants": plants, "keep": 5}
    law, path = control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 0.5, 0.0, puma.configuration("qn"))
    together = simulate(puma, law, path, **options)
    monkeypatch.setattr(simulation, "BLOCKED_RUNS", runs + 1)
    one_by_one = simulate(puma, law, path, **options)
    assert together.finished.all() and one_by_one.finished.all()
    for name in ("q", "qd"):
        np.testing.assert_allclose(together.samples[name], one_by_one.samples[name], rtol=0, atol=1e-10, err_msg=name)
    np.testing.assert_allclose(together.summaries, one_by_one.summaries, rtol=1e-9, atol=1e-9)
    other = plants.packed.copy()
    other[1, HEADER + POSITION] += 0.01  # another arm's kinematics: not one block
    assert not simulation.blocks_apply(other, np.arange(runs))
    assert not simulation.blocks_apply(plants.packed[:3], np.arange(3))


def test_plant_variants_equal_robots_built_one_by_one(puma: ad.Robot) -> None:
    """The packed variants equal with_payload's arms (mass properties by the parallel-axis theorem) and scaled links."""
    from armdyn.simulation import packed_plants

    masses, centres, moments = [0.0, 1.5], [[0, 0, 0], [0.01, 0.02, 0.1]], [[0, 0, 0], [0.01, 0.012, 0.015]]
    variants = plant_variants(puma, 2, payload_mass=masses, payload_com=centres, payload_inertia=moments)
    for k in range(2):
        packed, _ = packed_plants([puma.with_payload(masses[k], centres[k], moments[k])])
        body = np.arange(packed.shape[1]) >= 20  # the header's pivot floor scales with the arm's inertia
        assert np.abs(variants.packed[k, body] - packed[0, body]).max() < 1e-12
    scaled = plant_variants(puma, 1, mass_scale=2.0, friction_scale=0.0)
    q = puma.configuration("qn")
    heavy = simulate(puma, None, None, t_final=0.01, q0=q, plants=scaled, keep="full")
    light = simulate(puma.without_friction(), None, None, t_final=0.01, q0=q, keep="full")
    assert heavy.samples["q"].shape == light.samples["q"].shape


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"q0": np.zeros((3, 6)), "qd0": np.zeros((4, 6)), "keep": "summary"}, "disagree on the number of runs"),
        ({"runs": 2, "q0": np.zeros((3, 6))}, "runs = 2"),
        ({"keep": "everything"}, "keep must be"),
        ({"keep": -1}, "keep must be"),
        ({"gains": np.ones((2, 6))}, "gains must be"),
        ({"plants": "heavy"}, "plants must be None"),
        ({"trajectory": [tr.Sinusoid(0.1, 1.0), tr.Quintic(0.0, 1.0, 0.0, 1.0)], "runs": 2}, "one kind"),
        ({"runs": 1, "controller": lambda t, q, qd, q_d, qd_d, qdd_d, e: q}, "run armdyn.control's laws"),
    ],
)
def test_bad_inputs_are_model_errors(puma: ad.Robot, arguments: dict, message: str) -> None:
    options = {"controller": control.PDGravity(10.0, 1.0), "t_final": 0.01} | arguments
    with pytest.raises(ModelError, match=message):
        simulate(puma, **options)


def test_bad_variants_are_model_errors(puma: ad.Robot) -> None:
    for arguments, message in (
        ({"payload_mass": -1.0}, ">= 0"),
        ({"payload_inertia": [1.0, 0.1, 0.1]}, "triangle"),
        ({"mass_scale": 0.0}, "mass_scale must be > 0"),
        ({"payload_com": [0.0, 0.0]}, "payload_com must have the shape"),
    ):
        with pytest.raises(ModelError, match=message):
            plant_variants(puma, 2, **arguments)


@pytest.mark.slow
def test_the_envelope_figure(puma: ad.Robot, tmp_path) -> None:
    q0 = puma.configuration("qn")
    payloads = np.linspace(0.0, 2.0, 12)
    runs = simulate(puma, control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 0.5, 0.0, q0), t_final=0.2,
                         q0=q0, keep=5, plants=plant_variants(puma, 12, payload_mass=payloads))  # fmt: skip
    runs.plot(tmp_path / "envelope.png")
    simulate(puma, None, None, t_final=0.01, q0=q0, runs=1).plot(tmp_path / "histograms.png", quantity="max_tau")
    assert (tmp_path / "envelope.png").stat().st_size > 20_000 and (tmp_path / "histograms.png").exists()
    with pytest.raises(ModelError, match="quantity must be one of"):
        runs.plot(quantity="speed")


def test_keep_beyond_the_steps_and_counts_beyond_memory_are_refused_by_name() -> None:
    arm = ad.models.two_link_planar()
    pid = control.PID(10.0, 2.0)
    whole = simulate(arm, pid, t_final=0.01, runs=2, keep=10)  # keep = the 10 steps: the start and the end
    assert whole.samples["q"].shape == (2, 2, 2)
    for keep in (11, 10**20, 10**400):
        with pytest.raises(ModelError, match=r"keep must be .* from 1 to the run's 10 steps"):
            simulate(arm, pid, t_final=0.01, runs=2, keep=keep)
    with pytest.raises(ModelError, match=r"about 10\^400 runs .* memory available"):
        simulate(arm, pid, t_final=0.01, runs=10**400)
    for count in (10**12, 10**400):
        with pytest.raises(
            ModelError, match=r"count = (about 10\^400|1,000,000,000,000) variants needs .* memory available"
        ):
            plant_variants(arm, count)


def test_disagreeing_row_counts_name_the_arguments() -> None:
    arm = ad.models.two_link_planar()
    pid = control.PID(10.0, 2.0)
    with pytest.raises(ModelError, match=r"runs = 3, but q0 has 4 rows"):
        simulate(arm, pid, t_final=0.01, runs=3, q0=np.zeros((4, 2)))
    with pytest.raises(ModelError, match=r"disagree .*: q0 has 4, qd0 has 3 rows"):
        simulate(arm, pid, t_final=0.01, q0=np.zeros((4, 2)), qd0=np.zeros((3, 2)), keep="summary")
