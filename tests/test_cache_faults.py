"""Faults that must not stop armdyn or lose a result: a compiled-code cache that cannot be written
(a read-only install and a read-only home) or holds a truncated file; an output file that cannot
be written (a full disk, a missing or read-only folder) leaves no partial file and names the file."""

from __future__ import annotations

import errno
import json
import os
import shutil
import stat
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armdyn as ad
from armdyn import files
from armdyn.dynamics import api
from tests.helpers import assert_one_error_line, invoke

SOURCE = Path(ad.__file__).resolve().parent
PROBE = """
import json, warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import numpy as np
    import armdyn
    from armdyn.dynamics import api
    arm = armdyn.models.puma560()
    q = np.linspace(0.1, 0.6, arm.n)
    tau = api.inverse_dynamics(arm, q, 2 * q, -q)
print(json.dumps({"tau": tau.tolist(), "warnings": [f"{w.category.__name__}: {w.message}" for w in caught]}))
"""


def _expected_tau() -> list[float]:
    """The oracle: the first inverse dynamics of the probe, computed in this process."""
    arm = ad.models.puma560()
    q = np.linspace(0.1, 0.6, arm.n)
    return api.inverse_dynamics(arm, q, 2 * q, -q).tolist()


def _probe(path: Path, **env: str) -> dict[str, Any]:
    """Run PROBE in a fresh interpreter with armdyn from ``path`` and the environment ``env``."""
    environment = {key: value for key, value in os.environ.items() if not key.startswith(("NUMBA_CACHE", "PYTHON"))}
    environment |= {"PYTHONPATH": str(path), "PYTHONDONTWRITEBYTECODE": "1"} | env
    done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=environment, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def _listing(root: Path) -> set[str]:
    return {str(path.relative_to(root)) for path in root.rglob("*")}


# ----- the compiled-code cache --------------------------------------------------------------------------
def test_import_and_first_inverse_dynamics_in_a_read_only_install_with_a_read_only_home(tmp_path: Path) -> None:
    """No folder for the cache can be made: every __pycache__ of the package is a file, the home and the
    user's cache are under a file (so that this holds for root too, whom permission bits do not stop), and the
    package is read-only. armdyn imports, warns once, and computes the in-process value."""
    site = tmp_path / "site"
    shutil.copytree(SOURCE, site / "armdyn", ignore=shutil.ignore_patterns("__pycache__"))
    for folder in [site / "armdyn", *(path for path in (site / "armdyn").rglob("*") if path.is_dir())]:
        (folder / "__pycache__").write_text("")  # a file: no __pycache__ folder (Numba's nor Python's) can be made
    home = tmp_path / "home"
    home.write_text("")  # a file: nothing can be made under it
    for path in [site, *site.rglob("*")]:
        path.chmod(path.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    before = _listing(tmp_path)
    try:
        run = _probe(site, HOME=str(home), XDG_CACHE_HOME=str(home / "cache"))
    finally:
        for path in [site, *site.rglob("*")]:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)
    assert run["tau"] == _expected_tau()
    assert len(run["warnings"]) == 1, run["warnings"]
    assert run["warnings"][0].startswith("RuntimeWarning: armdyn's compiled-code cache: none of")
    assert "compiled in memory" in run["warnings"][0]
    assert _listing(tmp_path) == before  # nothing written anywhere


@pytest.mark.slow  # about 25 s: three compiles in fresh processes
def test_a_truncated_cache_file_is_removed_and_compiled_again(tmp_path: Path) -> None:
    """Compile into a fresh cache, truncate its data file, then its index: each next process warns,
    removes the entry, computes the value of the intact cache, and saves the entry afresh."""
    cache = tmp_path / "cache"
    first = _probe(SOURCE.parent, NUMBA_CACHE_DIR=str(cache))
    assert first["warnings"] == [] and first["tau"] == _expected_tau()
    (index,) = cache.rglob("rnea.inverse_dynamics_one-*.nbi")
    (data,) = cache.rglob("rnea.inverse_dynamics_one-*.nbc")
    for damaged in (data, index):
        size = damaged.stat().st_size
        with open(damaged, "r+b") as handle:
            handle.truncate(size // 2)
        run = _probe(SOURCE.parent, NUMBA_CACHE_DIR=str(cache))
        assert run["tau"] == first["tau"]
        assert len(run["warnings"]) == 1, run["warnings"]
        assert "could not be read" in run["warnings"][0] and damaged.name in run["warnings"][0]
    again = _probe(SOURCE.parent, NUMBA_CACHE_DIR=str(cache))
    assert again == first  # the cache was saved whole again: loaded without a warning


# ----- output files: whole or not at all ----------------------------------------------------------------
class _FullDisk:
    """A file that takes ``room`` bytes, then raises ENOSPC, as a full disk does."""

    def __init__(self, handle: Any, room: int) -> None:
        self.handle, self.room = handle, room

    def write(self, data: Any) -> int:
        if len(data) > self.room:
            self.handle.write(bytes(data[: self.room]) if isinstance(data, (bytes, memoryview)) else data[: self.room])
            self.handle.flush()
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self.room -= len(data)
        return self.handle.write(data)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.handle, name)

    def __enter__(self) -> _FullDisk:
        return self

    def __exit__(self, *exc: object) -> None:
        self.handle.close()


@pytest.fixture
def full_disk(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Every file armdyn.files opens takes 10 bytes, then the disk is full."""
    monkeypatch.setattr(files, "open", lambda *a, **k: _FullDisk(open(*a, **k), 10), raising=False)  # noqa: SIM115
    yield


def test_a_failed_write_keeps_the_earlier_file_and_leaves_no_temporary(tmp_path: Path, full_disk: None) -> None:
    target = tmp_path / "table.csv"
    target.write_text("the earlier table\n")
    with pytest.raises(ad.ModelError, match=rf"could not write {target}: No space left on device \(ENOSPC\)"):
        files.write_text(target, "a,b\n" * 1000)
    assert target.read_text() == "the earlier table\n"
    assert _listing(tmp_path) == {"table.csv"}


@pytest.mark.parametrize(
    ("args", "written"),
    [
        (["simulate", "two_link_planar", "--t-final", "0.05", "--csv", "{out}/run.csv"], "run.csv"),
        (["derive", "two_link_planar", "--code", "python", "-o", "{out}/rr.py"], "rr.py"),
        (["show", "puma560", "-o", "{out}/puma.md"], "puma.md"),
        (["models", "-o", "{out}/models.csv"], "models.csv"),
        (["simulate", "two_link_planar", "--t-final", "0.05", "-o", "{out}/run"], "run"),
    ],
    ids=["simulate --csv", "derive --code", "show -o .md", "models -o .csv", "simulate -o"],
)
def test_cli_output_on_a_full_disk_leaves_no_partial_file(
    tmp_path: Path, full_disk: None, monkeypatch: pytest.MonkeyPatch, args: list[str], written: str
) -> None:
    from matplotlib.figure import Figure

    def savefig(self: Figure, path: Any, **options: Any) -> None:  # the figure's file: 10 bytes, then full
        Path(path).write_bytes(b"\x89PNG\r\n\x1a\n\0\0")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Figure, "savefig", savefig)
    out = tmp_path / "out"
    out.mkdir()
    line = assert_one_error_line(invoke(*[arg.format(out=out) for arg in args]), "No space left on device")
    assert str(out) in line  # the file is named
    left = [path for path in out.rglob("*") if path.is_file()]
    assert left == [], left  # no 0-byte or partial file, no temporary file


def test_result_files_in_a_missing_folder_name_it(tmp_path: Path) -> None:
    from armdyn.control import ComputedTorque
    from armdyn.trajectories import Sinusoid

    arm = ad.models.two_link_planar()
    result = ad.simulate(arm, ComputedTorque(100.0, 20.0), Sinusoid([0.1, 0.1], [0.5, 0.5]), t_final=0.02, dt=1e-3)
    missing = tmp_path / "no" / "such"
    for write, name in ((result.to_csv, "run.csv"), (result.to_npz, "run.npz"), (result.plot, "run.png")):
        with pytest.raises(ad.ModelError, match=f"{missing / name}: the folder {missing} does not exist"):
            write(missing / name)
    assert not (tmp_path / "no").exists()
    result.to_npz(tmp_path / "run")  # np.savez's name: .npz added
    with np.load(tmp_path / "run.npz") as saved:
        assert np.array_equal(saved["q"], result.q) and np.array_equal(saved["tau"], result.tau)
    assert _listing(tmp_path) == {"run.npz"}


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="a folder no one can write in: Linux's /proc")
def test_result_file_in_a_folder_that_cannot_be_written_names_it() -> None:
    """/proc refuses new files to root too (permission bits do not stop root)."""
    from armdyn.control import ComputedTorque

    arm = ad.models.two_link_planar()
    result = ad.simulate(arm, ComputedTorque(100.0, 20.0), None, t_final=0.01, dt=1e-3, q0=[0.1, 0.2])
    with pytest.raises(ad.ModelError, match=r"could not write /proc/armdyn-run\.csv: "):
        result.to_csv("/proc/armdyn-run.csv")
    line = assert_one_error_line(invoke("models", "-o", "/proc/armdyn-models.csv"), "/proc/armdyn-models.csv")
    assert "could not write" in line


def test_cli_output_in_a_read_only_folder_is_refused_before_the_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    if os.access(folder, os.W_OK):  # root: permission bits do not stop it, so the check is told the mode
        monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != folder)
    try:
        for args in (["simulate", "two_link_planar", "--t-final", "0.05", "--csv", folder / "run.csv"],
                     ["simulate", "two_link_planar", "--t-final", "0.05", "-o", folder / "run"],
                     ["show", "puma560", "-o", folder / "puma.md"]):  # fmt: skip
            assert_one_error_line(invoke(*args), str(folder), "is not writable")
        assert _listing(folder) == set()
    finally:
        folder.chmod(0o755)
