"""Shared fixtures: the example-robot-data URDFs and the demo run (shared functions are in helpers.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.helpers import URDFS


@pytest.fixture(params=sorted(URDFS))
def urdf_path(request: pytest.FixtureRequest) -> Path:
    """The Panda and UR5 URDFs of example-robot-data."""
    return URDFS[request.param]


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[object, Path]:
    """``armdyn demo -o FOLDER`` run once for the whole session (it takes seconds): (its CliRunner result,
    the folder it wrote)."""
    from typer.testing import CliRunner

    from armdyn.cli import app

    folder = tmp_path_factory.mktemp("demo") / "out"
    return CliRunner().invoke(app, ["demo", "-o", str(folder)], prog_name="armdyn"), folder
