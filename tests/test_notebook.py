"""The notebook display end to end: a notebook run by a Jupyter kernel of this interpreter shows an arm
and a property report as HTML, a closed form as LaTeX and a simulated run as a PNG image."""

from __future__ import annotations

import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

pytestmark = pytest.mark.slow

CELLS = {
    "kernel": "import sys\n\nimport armdyn as ad\n\nprint(sys.executable)\nprint(sys.prefix)",
    "arm": "ad.models.two_link_planar()",
    "closed form": "ad.symbolic.derive(ad.models.two_link_planar(symbolic=True))",
    "report": "ad.properties.check(ad.models.two_link_planar(), samples=20)",
    "result": (
        "import numpy as np\n"
        "from armdyn.control import ComputedTorque\n"
        "from armdyn.trajectories import Sinusoid\n\n"
        "desired = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])  # Example 4.4-1\n"
        "ad.simulate(ad.models.two_link_planar(), ComputedTorque(100.0, 20.0), desired, t_final=1.0)"
    ),
}


def test_a_notebook_shows_latex_html_and_png(tmp_path: Path) -> None:
    path = tmp_path / "display.ipynb"
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(source) for source in CELLS.values()])
    nbformat.write(notebook, path)
    notebook = nbformat.read(path, as_version=4)
    NotebookClient(
        notebook, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    nbformat.write(notebook, path)
    outputs = dict(zip(CELLS, (cell.outputs for cell in notebook.cells), strict=True))

    printed = "".join(output.text for output in outputs["kernel"] if output.output_type == "stream")
    assert printed.split("\n")[:2] == [sys.executable, sys.prefix]  # this interpreter, this virtualenv

    def shown(name: str) -> dict[str, object]:
        results = [output for output in outputs[name] if output.output_type == "execute_result"]
        assert len(results) == 1, f"{name}: {outputs[name]}"
        return results[0].data

    arm = shown("arm")
    assert "armdyn-joints" in arm["text/html"] and arm["text/plain"].startswith("Robot: two_link_planar, 2 joints")
    latex = shown("closed form")["text/latex"]
    assert latex.startswith("$$\\begin{aligned}") and "m_{2}" in latex
    assert "armdyn-properties" in shown("report")["text/html"]
    assert "image/png" in shown("result")
