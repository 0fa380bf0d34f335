"""Robot: an ArmModel with its dynamics and kinematics as methods, the object users hold.

The only place where methods meet data. Each method is a free function of armdyn.dynamics
(or armdyn.kinematics) taking the arm first, and ``plot`` draws the arm through armdyn.plotting
(imported when first drawn; that module never imports this one); the arm is packed for the
compiled kernels once, when it is made, and never changes afterwards.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn import kinematics
from armdyn.dynamics import api
from armdyn.dynamics import regressor as parameterization
from armdyn.dynamics.packed import pack
from armdyn.model.arm import ArmModel

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from armdyn.viewer import Viewer


class Robot(ArmModel):
    """An arm: links in a kinematic tree with gravity, base and tool, friction, motors and limits,
    with the robot equation M(q) qdd + Vm(q, qd) qd + F(qd) + G(q) = tau (3.3.1).

    Build one with ``Robot.from_dh``, ``armdyn.load_urdf`` or ``armdyn.models``; the
    constructor takes a list of Links (see ArmModel). Every array method takes one state
    (n,) or a batch (..., n) and returns the matching shape.

    Attributes
    ----------
    packed : numpy.ndarray or None
        The model array the compiled kernels read, made with the arm (None for symbolic
        parameters). No call writes it; neither should you.
    """

    packed: np.ndarray | None

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        object.__setattr__(self, "packed", None if self.is_symbolic else pack(self))

    def to_urdf(self, path: str | Path | None = None) -> str:
        """The arm as URDF text, written to ``path`` when given (``armdyn.io.urdf_out.to_urdf``).

        Parameters
        ----------
        path : str or Path, optional
            The file to write.

        Returns
        -------
        str
            The URDF; ``load_urdf`` of it gives the same dynamics.

        Raises
        ------
        armdyn.ModelError
            For a symbolic arm, or a path that cannot be written.
        """
        from armdyn.io.urdf_out import to_urdf

        return to_urdf(self, path)

    def to_mjcf(self, path: str | Path | None = None) -> str:
        """The arm as MuJoCo MJCF text, written to ``path`` when given (``armdyn.io.mjcf_out.to_mjcf``).

        Parameters
        ----------
        path : str or Path, optional
            The file to write.

        Returns
        -------
        str
            The MJCF; MuJoCo computes the same M(q), bias and inverse dynamics from it.

        Raises
        ------
        armdyn.ModelError
            For a symbolic arm, or a path that cannot be written.
        """
        from armdyn.io.mjcf_out import to_mjcf

        return to_mjcf(self, path)

    # dynamics (armdyn.dynamics.api)
    inverse_dynamics = api.inverse_dynamics
    forward_dynamics = api.forward_dynamics
    inverse_dynamics_derivatives = api.inverse_dynamics_derivatives
    forward_dynamics_derivatives = api.forward_dynamics_derivatives
    inertia_matrix = api.inertia_matrix
    inertia_matrix_dot = api.inertia_matrix_dot
    coriolis_matrix = api.coriolis_matrix
    coriolis_vector = api.coriolis_vector
    gravity_vector = api.gravity_vector
    friction = api.friction
    nonlinear_terms = api.nonlinear_terms
    kinetic_energy = api.kinetic_energy
    potential_energy = api.potential_energy
    energies = api.energies

    # linear parameterization (armdyn.dynamics.regressor)
    regressor = parameterization.regressor
    parameters = parameterization.parameters

    # kinematics, compiled (armdyn.dynamics.api; armdyn.kinematics holds the NumPy reference)
    link_transforms = api.link_transforms
    tool_pose = api.tool_pose
    jacobian = api.jacobian
    jacobian_dot = api.jacobian_dot
    link_transform_derivatives = kinematics.link_transform_derivatives

    def plot(
        self, q: object = None, ax: Axes | None = None, path: str | Path | None = None, title: str | None = None
    ) -> Figure:
        """The arm at one configuration as a stick figure: links, joint axes, base and tool frames
        (armdyn.plotting.plot_arm; the forward kinematics of Appendix A). A planar arm is drawn in 2-D, any
        other in 3-D, with equal scales in metres.

        Parameters
        ----------
        q : array_like or str, optional
            Joint positions (n,), rad or m, or the name of one of the arm's configurations (e.g.
            "qr"); default its "qn", else its "qz", else zeros.
        ax : matplotlib.axes.Axes, optional
            Draw on these axes (3-D axes for a spatial arm); default a new figure's.
        path : str or Path, optional
            Also write the figure to this file (its format by the suffix: .png, .pdf, .svg, ...).
        title : str, optional
            The title; default the arm's name and q.

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on.

        Raises
        ------
        armdyn.ModelError
            When q is not n finite numbers or a configuration of the arm, the arm is symbolic, the
            folder of ``path`` does not exist or its suffix is no image format, or ``ax`` is 2-D
            for a spatial arm.
        """
        from armdyn.plotting import plot_arm

        return plot_arm(self, q, ax=ax, path=path, title=title)

    def view(self, **options: Any) -> Viewer:
        """The arm in 3-D in the browser (armdyn.viewer.Viewer): its URDF meshes or capsules, joint sliders, the
        tool frame and the overlays (inertia ellipsoids, Lambda, manipulability, centre of mass, gravity).

        Parameters
        ----------
        **options
            host, port, overlays, q and urdf, as armdyn.viewer.Viewer takes them.

        Returns
        -------
        armdyn.viewer.Viewer
            The running viewer: open its ``url``; ``close()`` it (or use it in a ``with`` block).

        Raises
        ------
        armdyn.MissingDependencyError
            When viser or trimesh is not installed (``pip install 'armdyn[view]'``).
        armdyn.ModelError
            As armdyn.viewer.Viewer.
        """
        from armdyn.viewer import Viewer

        return Viewer(self, **options)
