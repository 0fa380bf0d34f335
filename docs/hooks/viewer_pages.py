"""Write the 3-D viewer's saved pages into the site when it is built.

Each page is what ``Viewer.save_html`` writes: viser's client with the scene (and a run's frames) inline, one file
that replays offline. They are made here, from armdyn itself, rather than kept in the repository; the docs pages
embed them with an ``<iframe>``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any


def on_post_build(config: Any, **kwargs: Any) -> None:
    """assets/viewer/puma560-run.html: the PUMA 560 under computed torque for 2 s, its Lambda and manipulability
    ellipsoids shown; assets/viewer/puma560-lambda.html: the arm at qn with the two ellipsoids."""
    import numpy as np

    import armdyn as ad
    from armdyn.control import ComputedTorque
    from armdyn.trajectories import Sinusoid

    target = Path(config["site_dir"]) / "assets" / "viewer"
    target.mkdir(parents=True, exist_ok=True)
    puma = ad.models.puma560()
    start = puma.configuration("qn")
    path = Sinusoid(0.4, 0.5, np.arange(6) % 2 * np.pi / 2, start)
    run = ad.simulate(puma, ComputedTorque(100.0, 20.0), path, t_final=2.0, q0=start)
    with run.view(overlays=("lambda", "manipulability")) as viewer:
        viewer.save_html(target / "puma560-run.html")
    with puma.view(overlays=("lambda", "manipulability"), q=start) as viewer:
        viewer.save_html(target / "puma560-lambda.html")
