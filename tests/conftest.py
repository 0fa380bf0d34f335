"""Shared fixtures: where example-robot-data keeps its URDFs, and random arms for hypothesis."""

from __future__ import annotations

import sysconfig
from pathlib import Path

import numpy as np
import pytest

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
URDFS = {
    "panda": ROBOTS / "panda_description" / "urdf" / "panda.urdf",
    "ur5": ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf",
}


@pytest.fixture(params=sorted(URDFS))
def urdf_path(request: pytest.FixtureRequest) -> Path:
    """The Panda and UR5 URDFs of example-robot-data."""
    return URDFS[request.param]


def pinocchio_pair(path: Path):
    """(armdyn arm, pinocchio model, pinocchio data, q index map, v index map), joints mapped by name."""
    import warnings

    import pinocchio as pin

    import armdyn as ad

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(path)
    model = pin.buildModelFromUrdf(str(path))
    ids = [model.getJointId(name) for name in arm.joint_names]
    q_index = np.array([model.joints[i].idx_q for i in ids])
    v_index = np.array([model.joints[i].idx_v for i in ids])
    return arm, model, model.createData(), q_index, v_index


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[object, Path]:
    """``armdyn demo -o FOLDER`` run once for the whole session (it takes seconds): (its CliRunner result,
    the folder it wrote)."""
    from typer.testing import CliRunner

    from armdyn.cli import app

    folder = tmp_path_factory.mktemp("demo") / "out"
    return CliRunner().invoke(app, ["demo", "-o", str(folder)], prog_name="armdyn"), folder
