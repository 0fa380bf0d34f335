"""The built-in arms, looked up by name: the book's examples and classic industrial arms.

The book's three examples (Examples 3.2-1 and 3.2-2, Exercise 3.2-3) take ``symbolic=True`` to carry SymPy
symbols (m1, m2, a1, a2, g, ...) as parameters, ready for closed-form derivation.
``load_dh_file`` reads an arm of one's own from a DH table in a JSON or YAML file.
"""

from __future__ import annotations

import os
import re
import reprlib
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.arm import Link
from armdyn.model.inertial import Inertial, Scalar, parameter
from armdyn.model.joint import Joint
from armdyn.robot import Robot

_PI = np.pi


def _as_published(build: Callable[[], Robot]) -> Robot:
    """Build an arm whose published inertias break the triangle inequality, without warnings."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*triangle inequality")
        return build()


def _named(table: list[dict], strict: bool = True) -> list[dict]:
    """DH rows with joint names q1..qn (and the triangle-inequality check on or off)."""
    return [{**row, "name": f"q{index + 1}", "strict": strict} for index, row in enumerate(table)]


def _symbols(names: str) -> tuple:
    import sympy

    return sympy.symbols(names, positive=True)


def _checked(arm: str, masses: dict[str, object], others: dict[str, object]) -> list[Scalar]:
    """The parameters of a book example, in order (masses first): SymPy expressions as given,
    numbers as finite real floats, masses (and inertias) >= 0; else a ModelError naming the
    parameter and what it is."""
    what = {"m": "mass", "J": "inertia", "a": "length", "g": "gravity"}
    values = [parameter(v, f"{what[k[0]]} {k}", arm, minimum=0.0) for k, v in masses.items()]
    return values + [parameter(v, f"{what[k[0]]} {k}", arm) for k, v in others.items()]


def _planar_gravity(g: Scalar) -> list[Scalar]:
    """The book's planar arms move in the vertical x-y plane with y up."""
    return [0, -g, 0] if hasattr(g, "free_symbols") else [0.0, -float(g), 0.0]


def two_link_planar(
    m1: object = 1.0, m2: object = 1.0, a1: object = 1.0, a2: object = 1.0, g: object = 9.8, symbolic: bool = False
) -> Robot:
    """Example 3.2-2: the two-link planar elbow (RR) arm, point masses at the link ends.

    Standard DH: a1, a2, alpha = 0; the arm moves in the vertical x-y plane, gravity -g y.
    Configurations: qz (zero), qh (arm up, q = [pi/2, 0]).

    Parameters
    ----------
    m1, m2 : float, optional
        The point masses at the ends of links 1 and 2 (kg, default 1).
    a1, a2 : float, optional
        The link lengths (m, default 1).
    g : float, optional
        The acceleration of gravity (m/s^2, default 9.8).
    symbolic : bool, optional
        True replaces all five parameters by the positive SymPy symbols m1, m2, a1, a2, g,
        for closed-form derivation (default False).

    Returns
    -------
    Robot
        The arm, named "two_link_planar".

    Raises
    ------
    armdyn.ModelError
        When a mass is negative or a parameter is neither a finite real number nor a SymPy
        expression (the message names it).
    """
    if symbolic:
        m1, m2, a1, a2, g = _symbols("m1 m2 a1 a2 g")
    m1, m2, a1, a2, g = _checked("two_link_planar", {"m1": m1, "m2": m2}, {"a1": a1, "a2": a2, "g": g})
    table = [
        {"a": a1, "mass": m1, "name": "theta1"},
        {"a": a2, "mass": m2, "name": "theta2"},
    ]
    zeros = [0.0, 0.0]
    return Robot.from_dh(
        table,
        name="two_link_planar",
        gravity=_planar_gravity(g),
        configurations={"qz": zeros, "qh": [_PI / 2, 0.0]},
        description="Example 3.2-2, two-link planar elbow arm (point masses)",
    )


def polar_rp(m: object = 1.0, g: object = 9.8, symbolic: bool = False) -> Robot:
    """Example 3.2-1: the two-link polar (RP) arm, a point mass m at radius r.

    q = [theta, r]: theta turns the arm in the vertical x-y plane (gravity -g y), r is
    the extension along the arm; the mass sits at the end of the prismatic link. The
    extension is limited to [0.1, 1.5] m: at r = 0 the point mass would sit on the axis,
    where M = diag(m r^2, m) is singular.

    Parameters
    ----------
    m : float, optional
        The point mass (kg, default 1).
    g : float, optional
        The acceleration of gravity (m/s^2, default 9.8).
    symbolic : bool, optional
        True replaces m and g by the positive SymPy symbols m and g (default False).

    Returns
    -------
    Robot
        The arm, named "polar_rp", with the configuration qz = [0, 1].

    Raises
    ------
    armdyn.ModelError
        When a mass is negative or a parameter is neither a finite real number nor a SymPy
        expression (the message names it).
    """
    if symbolic:
        (m,) = _symbols("m,")
        (g,) = _symbols("g,")
    m, g = _checked("polar_rp", {"m": m}, {"g": g})
    links = [
        Link("theta", Joint("revolute", name="theta"), Inertial(0.0, name="theta")),
        Link(
            "r",
            Joint("prismatic", axis=np.array([1.0, 0.0, 0.0]), name="r"),
            Inertial(m, name="r"),
            parent=0,
            limits=(0.1, 1.5),
        ),
    ]
    return Robot(
        links,
        name="polar_rp",
        gravity=_planar_gravity(g),
        configurations={"qz": [0.0, 1.0]},
        description="Example 3.2-1, two-link polar arm (point mass)",
    )


def cylindrical(J: object = 1.0, m1: object = 1.0, m2: object = 1.0, g: object = 9.8, symbolic: bool = False) -> Robot:
    """Exercise 3.2-3: the three-link cylindrical arm, q = [theta, h, r].

    The base turns about the vertical z axis with inertia J (a massless disc, so that J
    alone appears); the vertical stage (mass m1) slides along z by h; the radial stage
    (point mass m2) slides out along the arm by r. Gravity -g z.

    Parameters
    ----------
    J : float, optional
        The inertia of the base about the vertical axis (kg m^2, default 1).
    m1, m2 : float, optional
        The masses of the vertical and of the radial stage (kg, default 1).
    g : float, optional
        The acceleration of gravity (m/s^2, default 9.8).
    symbolic : bool, optional
        True replaces J, m1, m2 and g by positive SymPy symbols of those names (default
        False).

    Returns
    -------
    Robot
        The arm, named "cylindrical", with the configuration qz = [0, 0, 1].

    Raises
    ------
    armdyn.ModelError
        When a mass or J is negative or a parameter is neither a finite real number nor a
        SymPy expression (the message names it).
    """
    if symbolic:
        J, m1, m2, g = _symbols("J m1 m2 g")
    J, m1, m2, g = _checked("cylindrical", {"J": J, "m1": m1, "m2": m2}, {"g": g})
    disc = np.array([[J / 2, 0, 0], [0, J / 2, 0], [0, 0, J]])  # float, or object with a SymPy J
    links = [
        Link("theta", Joint("revolute", name="theta"), Inertial(0, np.zeros(3), disc, "theta")),
        Link("h", Joint("prismatic", name="h"), Inertial(m1, name="h"), parent=0),
        Link(
            "r",
            Joint("prismatic", axis=np.array([1.0, 0.0, 0.0]), name="r"),
            Inertial(m2, name="r"),
            parent=1,
            limits=(0.0, np.inf),
        ),
    ]
    gravity = [0, 0, -g]
    return Robot(
        links,
        name="cylindrical",
        gravity=gravity,
        configurations={"qz": [0.0, 0.0, 1.0]},
        description="Exercise 3.2-3, three-link cylindrical arm",
    )


def puma560() -> Robot:
    """The Unimation PUMA 560, Armstrong/Corke parameters as the Robotics Toolbox ships them.

    Standard DH; masses, centres of mass and inertias of Armstrong, Khatib and Burdick
    (1986); motor inertia Jm, gear ratio G, viscous B and Coulomb Tc friction (motor
    side) of Corke and Armstrong-Helouvry (1994). As published, the inertias of links 1
    and 3 break the triangle inequality (link 1 is given only its Iyy about the vertical
    axis); they are kept as published so that results match the literature.
    Joint limits and configurations are the Toolbox's (Puma560.py): limits +-160, -45..225,
    -225..45, -110..170, +-100, +-266 degrees; qz (zero), qr (ready, arm up), qs (stretched),
    qn = [0, pi/4, -pi, 0, pi/4, 0] (nominal), each within the limits.

    Returns
    -------
    Robot
        The arm, named "puma560": 6 revolute joints with limits, motors and friction.
    """
    deg = _PI / 180
    table = [
        {"d": 26.45 * 0.0254, "alpha": _PI / 2, "mass": 0.0, "com": [0, 0, 0], "inertia": [0, 0.35, 0, 0, 0, 0],
         "Jm": 200e-6, "G": -62.6111, "B": 1.48e-3, "Tc": (0.395, -0.435), "qlim": (-160 * deg, 160 * deg)},
        {"a": 0.4318, "mass": 17.4, "com": [-0.3638, 0.006, 0.2275], "inertia": [0.13, 0.524, 0.539, 0, 0, 0],
         "Jm": 200e-6, "G": 107.815, "B": 0.817e-3, "Tc": (0.126, -0.071), "qlim": (-45 * deg, 225 * deg)},
        {"d": 0.15005, "a": 0.0203, "alpha": -_PI / 2, "mass": 4.8, "com": [-0.0203, -0.0141, 0.070],
         "inertia": [0.066, 0.086, 0.0125, 0, 0, 0], "Jm": 200e-6, "G": -53.7063, "B": 1.38e-3,
         "Tc": (0.132, -0.105), "qlim": (-225 * deg, 45 * deg)},
        {"d": 0.4318, "alpha": _PI / 2, "mass": 0.82, "com": [0, 0.019, 0],
         "inertia": [1.8e-3, 1.3e-3, 1.8e-3, 0, 0, 0],
         "Jm": 33e-6, "G": 76.0364, "B": 71.2e-6, "Tc": (11.2e-3, -16.9e-3), "qlim": (-110 * deg, 170 * deg)},
        {"alpha": -_PI / 2, "mass": 0.34, "com": [0, 0, 0], "inertia": [0.3e-3, 0.4e-3, 0.3e-3, 0, 0, 0],
         "Jm": 33e-6, "G": 71.923, "B": 82.6e-6, "Tc": (9.26e-3, -14.5e-3), "qlim": (-100 * deg, 100 * deg)},
        {"mass": 0.09, "com": [0, 0, 0.032], "inertia": [0.15e-3, 0.15e-3, 0.04e-3, 0, 0, 0],
         "Jm": 33e-6, "G": 76.686, "B": 36.7e-6, "Tc": (3.96e-3, -10.5e-3), "qlim": (-266 * deg, 266 * deg)},
    ]  # fmt: skip
    return _as_published(
        lambda: Robot.from_dh(
            _named(table, strict=False),
            name="puma560",
            gravity=[0.0, 0.0, -9.81],
            configurations={
                "qz": [0, 0, 0, 0, 0, 0],
                "qr": [0, _PI / 2, -_PI / 2, 0, 0, 0],
                "qs": [0, 0, -_PI / 2, 0, 0, 0],
                "qn": [0, _PI / 4, -_PI, 0, _PI / 4, 0],
            },
            description="Unimation PUMA 560 (Armstrong/Corke dynamics, motors and friction)",
        )
    )


def stanford() -> Robot:
    """The Stanford arm (RRPRRR), standard DH, dynamics as the Robotics Toolbox ships them.

    Kinematics from Stanford AIM-177, dynamics from Paul (1981, Tables 6.5 and 6.6) as
    the Toolbox gives them: motor inertias are already reflected (G = 1), no friction.
    As published, link 5's inertia breaks the triangle inequality and some centres of
    mass lie far outside the links (-6.447 m for link 3); they are kept as published.
    qz puts the prismatic joint at 0, outside its limits, as the Toolbox does.

    Returns
    -------
    Robot
        The arm, named "stanford": joints RRPRRR with limits, no friction.
    """
    deg, inch = _PI / 180, 0.0254
    table = [
        {"d": 0.412, "alpha": -_PI / 2, "mass": 9.29, "com": [0, 0.0175, -0.1105],
         "inertia": [0.276, 0.255, 0.071, 0, 0, 0], "Jm": 0.953, "G": 1, "qlim": (-170 * deg, 170 * deg)},
        {"d": 0.154, "alpha": _PI / 2, "mass": 5.01, "com": [0, -1.054, 0],
         "inertia": [0.108, 0.018, 0.100, 0, 0, 0], "Jm": 2.193, "G": 1, "qlim": (-170 * deg, 170 * deg)},
        {"kind": "P", "theta": -_PI / 2, "a": 0.0203, "mass": 4.25, "com": [0, 0, -6.447],
         "inertia": [2.51, 2.51, 0.006, 0, 0, 0], "Jm": 0.782, "G": 1, "qlim": (12 * inch, 50 * inch)},
        {"alpha": -_PI / 2, "mass": 1.08, "com": [0, 0.092, -0.054],
         "inertia": [0.002, 0.001, 0.001, 0, 0, 0], "Jm": 0.106, "G": 1, "qlim": (-170 * deg, 170 * deg)},
        {"alpha": _PI / 2, "mass": 0.630, "com": [0, 0.566, 0.003],
         "inertia": [0.003, 0.0004, 0, 0, 0, 0], "Jm": 0.097, "G": 1, "qlim": (-90 * deg, 90 * deg)},
        {"mass": 0.51, "com": [0, 0, 1.554],
         "inertia": [0.013, 0.013, 0.0003, 0, 0, 0], "Jm": 0.020, "G": 1, "qlim": (-170 * deg, 170 * deg)},
    ]  # fmt: skip
    return _as_published(
        lambda: Robot.from_dh(
            _named(table, strict=False),
            name="stanford",
            gravity=[0.0, 0.0, -9.81],
            configurations={"qz": [0, 0, 0.5, 0, 0, 0]},
            description="Stanford arm (RRPRRR)",
        )
    )


def scara() -> Robot:
    """A four-axis SCARA (RRPR), the geometry of the Adept Cobra 600.

    Standard DH (a1 = 0.325 m, a2 = 0.275 m, d1 = 0.387 m, alpha2 = pi so the quill
    moves down). The masses and inertias are representative values for an arm of this
    size (slender links, a 2 kg quill), not a manufacturer's data sheet.
    Configurations: qz (zero), qr.

    Returns
    -------
    Robot
        The arm, named "scara": joints RRPR with limits and friction.
    """
    deg = _PI / 180
    table = [
        {"d": 0.387, "a": 0.325, "mass": 8.0, "com": [-0.1625, 0, 0], "inertia": [0.02, 0.08, 0.08, 0, 0, 0],
         "B": 0.5, "Tc": (0.3, -0.3), "qlim": (-50 * deg, 50 * deg)},
        {"a": 0.275, "alpha": _PI, "mass": 6.0, "com": [-0.1375, 0, 0], "inertia": [0.01, 0.045, 0.045, 0, 0, 0],
         "B": 0.4, "Tc": (0.2, -0.2), "qlim": (-88 * deg, 88 * deg)},
        {"kind": "P", "mass": 2.0, "com": [0, 0, 0.1], "inertia": [0.007, 0.007, 0.0005, 0, 0, 0],
         "B": 5.0, "Tc": (2.0, -2.0), "qlim": (0.0, 0.210)},
        {"mass": 0.5, "com": [0, 0, 0.02], "inertia": [0.0005, 0.0005, 0.0003, 0, 0, 0],
         "B": 0.05, "Tc": (0.02, -0.02), "qlim": (-190 * deg, 190 * deg)},
    ]  # fmt: skip
    return Robot.from_dh(
        _named(table),
        name="scara",
        gravity=[0.0, 0.0, -9.81],
        configurations={"qz": [0, 0, 0, 0], "qr": [0, _PI / 4, 0.1, 0]},
        description="SCARA (RRPR), Adept Cobra 600 geometry, representative dynamics",
    )


def panda_gaz2019() -> Robot:
    """The Franka Emika Panda as identified from a real robot by Gaz, Cognetti, Oliva, Robuffo Giordano
    and De Luca, "Dynamic identification of the Franka Emika Panda robot with retrieval of feasible
    parameters using penalty-based optimization", IEEE RA-L 4(4), 2019.

    Modified (Craig) DH of the Panda's data sheet, to the flange (d = 0.333, 0, 0.316, 0, 0.384, 0, 0 m;
    a = 0, 0, 0, 0.0825, -0.0825, 0, 0.088 m; alpha = 0, -pi/2, pi/2, pi/2, -pi/2, pi/2, pi/2). Masses,
    centres of mass and inertias about the centres of mass (link-frame axes) as the authors publish them
    in Tables VIII and IX of their supplementary material (five significant digits); the friction of
    each joint is their sigmoid law F = A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift)),
    with A, alpha and shift from the same material. No motor inertia, viscous or Coulomb friction beyond
    that law. The inertias of links 2 and 7 break the triangle inequality as published; they are kept
    as published. Joint limits and configurations are the Panda's data sheet's.

    Returns
    -------
    Robot
        The arm, named "panda_gaz2019": 7 revolute joints with limits and sigmoid friction.
    """
    deg = _PI / 180
    lower = [-166, -101, -166, -176, -166, -1, -166]
    upper = [166, 101, 166, -4, 166, 215, 166]
    masses = [4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522]
    coms = [[3.875e-03, 2.081e-03, 0.0], [-3.141e-03, -2.872e-02, 3.495e-03], [2.7518e-02, 3.9252e-02, -6.6502e-02],
            [-5.317e-02, 1.04419e-01, 2.7454e-02], [-1.1953e-02, 4.1065e-02, -3.8437e-02],
            [6.0149e-02, -1.4117e-02, -1.0517e-02], [1.0517e-02, -4.252e-03, 6.1597e-02]]  # fmt: skip
    # Ixx, Ixy, Ixz, Iyy, Iyz, Izz about the centre of mass, as published
    inertias = [[7.0337e-01, -1.3900e-04, 6.7720e-03, 7.0661e-01, 1.9169e-02, 9.1170e-03],
                [7.9620e-03, -3.9250e-03, 1.0254e-02, 2.8110e-02, 7.0400e-04, 2.5995e-02],
                [3.7242e-02, -4.7610e-03, -1.1396e-02, 3.6155e-02, -1.2805e-02, 1.0830e-02],
                [2.5853e-02, 7.7960e-03, -1.3320e-03, 1.9552e-02, 8.6410e-03, 2.8323e-02],
                [3.5549e-02, -2.1170e-03, -4.0370e-03, 2.9474e-02, 2.2900e-04, 8.6270e-03],
                [1.9640e-03, 1.0900e-04, -1.1580e-03, 4.3540e-03, 3.4100e-04, 5.4330e-03],
                [1.2516e-02, -4.2800e-04, -1.1960e-03, 1.0027e-02, -7.4100e-04, 4.8150e-03]]  # fmt: skip
    amplitude = [0.54615, 0.87224, 0.64068, 1.2794, 0.83904, 0.30301, 0.56489]
    slope = [5.1181, 9.0657, 10.136, 5.5903, 8.3469, 17.133, 10.336]
    shift = [0.039533, 0.025882, -0.04607, 0.036194, 0.026226, -0.021047, 0.0035526]
    d = [0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0]
    a = [0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088]
    alpha = [0.0, -_PI / 2, _PI / 2, _PI / 2, -_PI / 2, _PI / 2, _PI / 2]
    table = []
    for i in range(7):
        xx, xy, xz, yy, yz, zz = inertias[i]
        table.append({
            "d": d[i], "a": a[i], "alpha": alpha[i], "mass": masses[i], "com": coms[i],
            "inertia": [xx, yy, zz, xy, yz, xz], "sigmoid": (amplitude[i], slope[i], shift[i]),
            "qlim": (lower[i] * deg, upper[i] * deg), "strict": False,
        })  # fmt: skip
    return Robot.from_dh(
        _named(table, strict=False),
        convention="modified",
        name="panda_gaz2019",
        gravity=[0.0, 0.0, -9.81],
        configurations={"qz": [0.0] * 7, "qr": [0, -_PI / 4, 0, -3 * _PI / 4, 0, _PI / 2, _PI / 4]},
        description="Franka Emika Panda, dynamics identified by Gaz et al. (2019), sigmoid friction",
    )


_CATALOG: dict[str, Callable[[], Robot]] = {
    "two_link_planar": two_link_planar,
    "polar_rp": polar_rp,
    "cylindrical": cylindrical,
    "puma560": puma560,
    "stanford": stanford,
    "scara": scara,
}
_IDENTIFIED: dict[str, Callable[[], Robot]] = {"panda_gaz2019": panda_gaz2019}


def names() -> list[str]:
    """The names of the built-in arms.

    Returns
    -------
    list of str
        The names ``load`` takes, the book's examples first.
    """
    return list(_CATALOG)


def identified_names() -> list[str]:
    """The names of the built-in arms identified from real robots (``load`` takes them too).

    Returns
    -------
    list of str
        Published models of real arms: "panda_gaz2019" (``panda_gaz2019``).
    """
    return list(_IDENTIFIED)


def load(name: str) -> Robot:
    """A built-in arm by name (see names()).

    Parameters
    ----------
    name : str
        One of ``names()``, in any case.

    Returns
    -------
    Robot
        A new arm with its default (numeric) parameters.

    Raises
    ------
    armdyn.ModelError
        When no built-in arm has that name.
    TypeError
        When ``name`` is not a string.
    """
    if not isinstance(name, str):
        raise TypeError(f"the name of a built-in arm must be a str, got {reprlib.repr(name)} ({type(name).__name__})")
    try:
        return {**_CATALOG, **_IDENTIFIED}[name.lower()]()
    except KeyError:
        known = ", ".join([*_CATALOG, *_IDENTIFIED])
        raise ModelError(f"no built-in arm named '{name}' (known: {known})") from None


# ----- DH table files ---------------------------------------------------------------------------------
_FILE_KEYS = ("rows", "name", "gravity", "convention", "description", "configurations")
_TEXT_KEYS = ("kind", "name", "strict")  # row keys whose values are not numbers


def _value(text: str, where: str) -> float:
    """A number written as text: a float, or arithmetic on numbers and pi ("-pi/2", "0.5*pi", "2**-3").

    Parameters
    ----------
    text : str
        The text.
    where : str
        What the text is, for the error message.

    Returns
    -------
    float
        Its value.

    Raises
    ------
    armdyn.ModelError
        When the text is neither a number nor such an expression.
    """
    import ast
    import operator

    binary: dict[type[ast.operator], Callable[[float, float], float]] = {ast.Add: operator.add, ast.Sub: operator.sub,
        ast.Mult: operator.mul, ast.Div: operator.truediv, ast.Pow: operator.pow}  # fmt: skip
    unary: dict[type[ast.unaryop], Callable[[float], float]] = {ast.USub: operator.neg, ast.UAdd: operator.pos}

    def evaluate(node: ast.AST) -> float:
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return _PI
        if isinstance(node, ast.BinOp) and type(node.op) in binary:
            return binary[type(node.op)](evaluate(node.left), evaluate(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in unary:
            return unary[type(node.op)](evaluate(node.operand))
        raise ValueError

    try:
        return float(text)
    except ValueError:
        pass
    try:
        if re.search(r"0[xXoObB]|_", text):  # decimal numbers only, as float() takes them
            raise ValueError
        return float(evaluate(ast.parse(text.strip(), mode="eval").body))
    except (SyntaxError, ValueError, TypeError, ArithmeticError, RecursionError):
        raise ModelError(
            f"{where}: {text!r} is not a number (write a number, or arithmetic on numbers and pi such as -pi/2)"
        ) from None


def _numbers(value: object, where: str) -> object:
    """Strings inside a number, list or table read from a file, replaced by their values (see ``_value``)."""
    if isinstance(value, str):
        return _value(value, where)
    if isinstance(value, list):
        return [_numbers(item, where) for item in value]
    return value


def load_dh_file(path: str | os.PathLike[str], strict: bool = True) -> Robot:
    """An arm from a Denavit-Hartenberg table file, JSON or YAML (by suffix).

    The file holds either the list of rows itself, or a mapping with the key ``rows`` and
    optionally ``name`` (default the file's stem), ``gravity`` (3 values, default
    [0, 0, -9.81]), ``convention`` ('standard' or 'modified'), ``description`` and
    ``configurations`` (name to n joint values). Each row is a mapping with the keys of
    ``Robot.from_dh``: kind ('R' or 'P'), a, alpha, d, theta, mass, com, inertia, Jm, G, B,
    Tc, qlim, name, strict. Numbers may also be written as text with arithmetic on pi
    ("-pi/2", "pi/4"). Reading YAML (.yaml, .yml) needs PyYAML; JSON needs nothing more.

    Parameters
    ----------
    path : str or os.PathLike
        The file: .json, .yaml or .yml.
    strict : bool, optional
        The triangle-inequality check for rows that do not set ``strict`` themselves
        (default True: inertias that break it are refused; False loads them with a warning).

    Returns
    -------
    Robot
        The arm.

    Raises
    ------
    armdyn.ModelError
        When the suffix is none of those, the file is not valid JSON or YAML, its content is
        not a table as above, a value is not a number, PyYAML is missing for a YAML file, or
        ``Robot.from_dh`` refuses a row (the message names the file).
    OSError
        When the file cannot be read.
    """
    import json

    file = Path(path)
    suffix = file.suffix.lower()
    if suffix not in (".json", ".yaml", ".yml"):
        raise ModelError(f"{file}: a DH table file must end in .json, .yaml or .yml")
    data = file.read_bytes()  # an OSError names the file
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ModelError(f"{file} is not a text file (it is not UTF-8 text)") from None
    if suffix == ".json":
        try:
            content = json.loads(text)
        except json.JSONDecodeError as error:
            raise ModelError(f"{file}, line {error.lineno}: not valid JSON ({error.msg})") from None
    else:
        try:
            import yaml
        except ImportError:
            raise ModelError(
                f"{file}: reading YAML needs PyYAML (pip install pyyaml); or write the table as JSON"
            ) from None
        try:
            content = yaml.safe_load(text)
        except yaml.YAMLError as error:
            raise ModelError(f"{file}: not valid YAML ({' '.join(str(error).split())})") from None
    if isinstance(content, list):
        content = {"rows": content}
    if not isinstance(content, dict) or "rows" not in content:
        raise ModelError(f"{file}: a DH table file holds a list of rows, or a mapping with the key 'rows'")
    unknown = sorted(str(key) for key in content if key not in _FILE_KEYS)
    if unknown:
        raise ModelError(f"{file}: unknown keys {unknown} (known: {', '.join(_FILE_KEYS)})")
    rows = content["rows"]
    if not isinstance(rows, list) or not rows:
        raise ModelError(f"{file}: 'rows' must be a non-empty list of rows, one per joint")
    table = []
    for index, row in enumerate(rows):
        if not isinstance(row, dict):
            raise ModelError(f"{file}, row {index + 1}: a row is a mapping of DH keys (a, alpha, d, theta, ...)")
        values = {key: value if key in _TEXT_KEYS else _numbers(value, f"{file}, row {index + 1}, {key}")
                  for key, value in row.items()}  # fmt: skip
        table.append({"strict": strict, **values})
    options: dict[str, object] = {"name": str(content.get("name", file.stem))}
    if "gravity" in content:
        options["gravity"] = _numbers(content["gravity"], f"{file}, gravity")
    if "description" in content:
        options["description"] = str(content["description"])
    if "configurations" in content:
        configurations = content["configurations"]
        if not isinstance(configurations, dict):
            raise ModelError(f"{file}: 'configurations' must map names to joint values")
        options["configurations"] = {
            str(key): _numbers(value, f"{file}, configuration {key}") for key, value in configurations.items()
        }
    try:
        return Robot.from_dh(table, convention=str(content.get("convention", "standard")), **options)
    except ModelError as error:
        raise ModelError(f"{file}: {error}") from None
    except (TypeError, ValueError) as error:
        raise ModelError(f"{file}: {' '.join(str(error).split())}") from None
