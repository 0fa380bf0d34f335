"""The linear parameterization tau = W(q, qd, qdd) phi in closed form (Table 3.3.1, property 9).

For an arm whose mass parameters are SymPy symbols (the book's examples), phi is those
symbols (and the friction symbols v_i, k_i when derived with friction="symbolic"), and
W = d tau / d phi. For an arm with numeric parameters, the arm is derived once more with
every link's ten inertial parameters [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]
(about the link origin, in the link frame) as symbols, and per joint the viscous v, the
Coulomb Tc+ and Tc- and the reflected motor inertia Ia; phi_values holds their values.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, cast

import numpy as np
import symengine as se
import sympy

from armdyn.errors import ModelError
from armdyn.model.inertial import _trusted
from armdyn.symbolic.derive import derive_raw

if TYPE_CHECKING:
    from armdyn.robot import Robot
    from armdyn.symbolic.closed_form import ClosedForm

INERTIAL_NAMES = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")


def _mass_symbols(form: ClosedForm) -> list[sympy.Symbol]:
    """Symbols of the links' mass properties, in link order, as they first appear."""
    found: list[sympy.Symbol] = []
    for link in form.robot.links:
        body = link.inertial
        for value in [body.mass, *np.asarray(body.com, dtype=object).ravel(), *body.inertia.ravel()]:
            for s in sorted(getattr(sympy.sympify(value), "free_symbols", ()), key=lambda x: x.name):
                if s not in found:
                    found.append(s)
    return found


def linear_parameterization(form: ClosedForm) -> tuple[sympy.Matrix, sympy.Matrix, list[float] | None]:
    if form.robot.is_symbolic:
        return _symbolic(form)
    return _numeric(form)


def _symbolic(form: ClosedForm) -> tuple[sympy.Matrix, sympy.Matrix, None]:
    phi = _mass_symbols(form) + [sympy.Symbol(s.name) for s in form.raw.parameters]
    tau = form.tau
    W = tau.jacobian(phi).applyfunc(lambda e: sympy.factor_terms(sympy.trigsimp(e)))
    rest = (tau - W * sympy.Matrix(phi)).applyfunc(lambda e: sympy.simplify(e))
    if any(x != 0 for x in rest):
        raise ModelError(
            "tau is not linear in the arm's symbolic mass parameters (a symbolic centre of mass or "
            "inertia enters through products); use numeric values or symbols for m*c and I directly"
        )
    return W, sympy.Matrix(phi), None


def _numeric(form: ClosedForm) -> tuple[sympy.Matrix, sympy.Matrix, list[float]]:
    robot = form.robot
    links, names, values = [], [], []
    for i, link in enumerate(robot.links):
        symbols = sympy.symbols([f"{name}{i + 1}" for name in INERTIAL_NAMES])
        m, mx, my, mz, ixx, ixy, iyy, ixz, iyz, izz = symbols
        h = sympy.Matrix([mx, my, mz])
        about_origin = sympy.Matrix([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        com = h / m
        about_com = about_origin - m * ((com.T * com)[0] * sympy.eye(3) - com * com.T)
        body = _trusted(m, np.array(list(com), dtype=object), np.array(about_com.tolist(), dtype=object), link.name)
        links.append(dataclasses.replace(link, inertial=body, viscous=0.0, coulomb=(0.0, 0.0), motor_inertia=0.0))
        own = link.inertial
        inertia = own.inertia_about_origin()
        names += symbols
        values += [own.mass, *own.first_moment, inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2]]
        values += [inertia[1, 2], inertia[2, 2]]
    twin = cast("Robot", robot.replace(links))  # replace keeps the class
    raw = derive_raw(twin, "recursive", False)
    drives, drive_values = [], []
    viscous, coulomb, armature = robot.viscous_friction, robot.coulomb_friction, robot.reflected_inertia
    tau, indicators = [], {}
    for i in range(robot.n):
        v, up, down, ia = se.symbols(f"v{i + 1} Tcp{i + 1} Tcn{i + 1} Ia{i + 1}")
        # [qd > 0] and [qd < 0] as placeholders while differentiating (SymEngine leaves d Piecewise/dx
        # as a Piecewise of zeros), then as the Piecewise the kernels' law is
        above, below = se.Symbol(f"_above{i + 1}"), se.Symbol(f"_below{i + 1}")
        indicators[above] = se.Piecewise((1, se.Gt(raw.qd[i], 0)), (0, True))
        indicators[below] = se.Piecewise((1, se.Lt(raw.qd[i], 0)), (0, True))
        tau.append(raw.tau[i] + v * raw.qd[i] + up * above + down * below + ia * raw.qdd[i])
        drives += [v, up, down, ia]
        drive_values += [viscous[i], coulomb[i, 0], coulomb[i, 1], armature[i]]
    phi = [se.Symbol(str(s)) for s in names] + drives
    W = [[form._sympy(se.diff(t, p).subs(indicators), collapse=False) for p in phi] for t in tau]
    return sympy.Matrix(W), sympy.Matrix([sympy.Symbol(p.name) for p in phi]), [float(x) for x in values + drive_values]
