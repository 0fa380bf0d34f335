"""What ``print(arm)`` and a notebook show of an arm: its table and its dynamics, as text or HTML.

The summary follows the print of a robot in the Robotics Toolbox for Python: a title line
(name, number of joints and their kinds), the Denavit-Hartenberg table when the arm was built
from one (``ArmModel.from_dh``) or else a table of the joints (kind, parent, axis and the
placement of the joint frame as xyz and roll-pitch-yaw), then one line for each part of the
dynamics: masses, inertias, gravity, friction, motors, the tool and base when they are not the
identity, and the named configurations.

Angles are shown in degrees (``90°``), lengths in metres, every number with at most five
significant digits; a SymPy parameter is shown as itself (``a1``, ``m2``). ``text_table`` and
``html_table`` draw any table of strings.
"""

from __future__ import annotations

import html
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from armdyn.model.arm import ArmModel, Link

DEGREE = "°"
_DIGITS = 5  # significant digits of every number shown
_ZERO = 1e-12  # magnitudes below this are shown as 0 (round-off of cos(pi/2) and the like)
_AXES = {(1, 0, 0): "+x", (0, 1, 0): "+y", (0, 0, 1): "+z", (-1, 0, 0): "-x", (0, -1, 0): "-y", (0, 0, -1): "-z"}


@dataclass(frozen=True)
class Summary:
    """An arm's summary as strings, drawn by ``text`` (print, repr) and ``html`` (notebooks).

    Parameters
    ----------
    title : str
        The first line: class, name, joints and their kinds, the kind of table.
    description : str
        The arm's description ("" for none).
    headers : list of str
        The columns of the joint table.
    rows : list of list of str
        One row per joint.
    facts : list of (str, list of str)
        The dynamics and the rest, one entry per quantity: its name and its lines.
    align : str
        One letter per column of the joint table: "l" (text, left-aligned) or "r" (numbers).
    """

    title: str
    description: str
    headers: list[str]
    rows: list[list[str]]
    facts: list[tuple[str, list[str]]]
    align: str

    def text(self) -> str:
        """The summary as plain text: title, description, the boxed table, aligned facts.

        Returns
        -------
        str
            Lines separated by newlines, without a final newline.
        """
        lines = [self.title]
        if self.description:
            lines.append(self.description)
        lines.append(text_table(self.headers, self.rows, self.align))
        width = max((len(key) for key, _ in self.facts), default=0) + 2
        for key, values in self.facts:
            for k, value in enumerate(values):
                lines.append(f"{key if k == 0 else '':<{width}}{value}".rstrip())
        return "\n".join(lines)

    def html(self) -> str:
        """The summary as HTML: the title, the joint table and a table of the facts, all escaped.

        Returns
        -------
        str
            A ``<div>`` holding a paragraph and two ``<table>`` elements (classes
            ``armdyn-joints`` and ``armdyn-dynamics``).
        """
        head = f"<strong>{html.escape(self.title)}</strong>"
        if self.description:
            head += f"<br><em>{html.escape(self.description)}</em>"
        facts = "".join(
            f'<tr><th style="text-align:left">{html.escape(key)}</th>'
            f'<td style="text-align:left">{"<br>".join(html.escape(value) for value in values)}</td></tr>'
            for key, values in self.facts
        )
        return (
            f'<div class="armdyn-arm"><p>{head}</p>'
            f"{html_table(self.headers, self.rows, css_class='armdyn-joints', align=self.align)}"
            f'<table class="armdyn-dynamics"><tbody>{facts}</tbody></table></div>'
        )


def text_table(headers: Sequence[str], rows: Sequence[Sequence[str]], align: str = "") -> str:
    """A table of strings drawn with box-drawing characters.

    Parameters
    ----------
    headers : sequence of str
        The column names.
    rows : sequence of sequence of str
        The cells, as many per row as there are headers.
    align : str, optional
        One letter per column, "l" (left) or "r" (right); default: the first column left,
        the others right.

    Returns
    -------
    str
        The table, one line per row, between rules; no final newline.
    """
    widths = [max([len(header), *(len(row[k]) for row in rows)]) for k, header in enumerate(headers)]
    align = align or "l" + "r" * (len(headers) - 1)

    def line(cells: Sequence[str]) -> str:
        columns = zip(cells, widths, align, strict=True)
        parts = [f"{cell:<{w}}" if a == "l" else f"{cell:>{w}}" for cell, w, a in columns]
        return "│ " + " │ ".join(parts) + " │"

    def rule(left: str, middle: str, right: str) -> str:
        return left + middle.join("─" * (w + 2) for w in widths) + right

    lines = [rule("┌", "┬", "┐"), line(headers), rule("├", "┼", "┤")]
    lines += [line(row) for row in rows]
    lines.append(rule("└", "┴", "┘"))
    return "\n".join(lines)


def html_table(headers: Sequence[str], rows: Iterable[Sequence[str]], css_class: str = "", align: str = "") -> str:
    """An HTML table of strings, every cell escaped.

    Parameters
    ----------
    headers : sequence of str
        The column names, in the ``<thead>``.
    rows : iterable of sequence of str
        The cells of each row, in the ``<tbody>``.
    css_class : str, optional
        The table's ``class`` attribute (default none).
    align : str, optional
        One letter per column, "l" (left) or "r" (right), set on every cell; default: left
        as well (numbers are then best given right-aligned: ``"lrr"``).

    Returns
    -------
    str
        The ``<table>`` element.
    """
    attribute = f' class="{html.escape(css_class)}"' if css_class else ""
    parts = [f"<table{attribute}>"]
    styles = [f' style="text-align:{"right" if a == "r" else "left"}"' for a in align or "l" * len(headers)]

    def cells(tag: str, texts: Sequence[str]) -> str:
        return "".join(f"<{tag}{s}>{html.escape(t)}</{tag}>" for t, s in zip(texts, styles, strict=True))

    parts.append(f"<thead><tr>{cells('th', headers)}</tr></thead>")
    body = "".join(f"<tr>{cells('td', row)}</tr>" for row in rows)
    parts.append(f"<tbody>{body}</tbody></table>")
    return "".join(parts)


# ----- numbers ------------------------------------------------------------------------------------
def _is_expression(value: object) -> bool:
    """True for a SymPy expression holding symbols (shown as itself, never converted)."""
    return bool(getattr(value, "free_symbols", None))


def number(value: object) -> str:
    """A number with at most five significant digits ("0.4318", "-9.81", "2e-04"), or a SymPy
    expression as itself ("a1"); infinities as "inf" and "-inf", magnitudes below 1e-12 as "0".

    Parameters
    ----------
    value : float or sympy.Expr
        The value.

    Returns
    -------
    str
        Its text.
    """
    if _is_expression(value):
        return str(value)
    x = float(value)  # type: ignore[arg-type]
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if abs(x) < _ZERO:
        return "0"
    return f"{x:.{_DIGITS}g}"


def angle(value: object) -> str:
    """An angle given in radians, shown in degrees ("90°"); a SymPy expression as itself.

    Parameters
    ----------
    value : float or sympy.Expr
        The angle (rad).

    Returns
    -------
    str
        Its text.
    """
    if _is_expression(value):
        return str(value)
    x = float(value)  # type: ignore[arg-type]
    if math.isinf(x):
        return number(x)
    return number(math.degrees(x)) + DEGREE


def _joint_value(value: object, revolute: bool) -> str:
    return angle(value) if revolute else number(value)


def _numbers(values: Iterable[object]) -> str:
    return ", ".join(number(v) for v in values)


def _is_zero(value: object) -> bool:
    return not _is_expression(value) and abs(float(value)) < _ZERO  # type: ignore[arg-type]


def _is_identity(transform: np.ndarray) -> bool:
    array = np.asarray(transform)
    if array.dtype == object:
        return all(not _is_expression(x) for x in array.ravel()) and np.allclose(array.astype(float), np.eye(4))
    return bool(np.allclose(array, np.eye(4), rtol=0.0, atol=_ZERO))


def _rpy(rotation: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad) of a rotation R = Rz(yaw) Ry(pitch) Rx(roll), as URDF writes them."""
    r = rotation
    cos_pitch = math.hypot(r[0, 0], r[1, 0])
    pitch = math.atan2(-r[2, 0], cos_pitch)
    if cos_pitch < 1e-9:  # gimbal lock: the yaw is taken as 0
        return math.atan2(-r[1, 2], r[1, 1]), pitch, 0.0
    return math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0])


def _pose(transform: np.ndarray) -> tuple[str, str]:
    """(xyz, rpy) of a 4x4 pose as text: metres and degrees; "symbolic" for a rotation holding symbols."""
    array = np.asarray(transform)
    xyz = _numbers(array[:3, 3])
    try:
        rotation = np.array(array[:3, :3], dtype=float)
    except TypeError:
        return xyz, "symbolic"
    return xyz, ", ".join(angle(a) for a in _rpy(rotation))


def _axis(axis: np.ndarray) -> str:
    key = tuple(round(float(x)) for x in axis)
    if key in _AXES and np.allclose(axis, key, rtol=0.0, atol=1e-12):
        return _AXES[key]
    return _numbers(axis)


# ----- the summary --------------------------------------------------------------------------------
def summary(arm: ArmModel) -> Summary:
    """The summary of an arm (see the module docstring).

    Parameters
    ----------
    arm : ArmModel
        The arm (a Robot or any ArmModel).

    Returns
    -------
    Summary
        Its title, table and facts as strings.
    """
    kinds = "".join("R" if link.joint.is_revolute else "P" for link in arm.links)
    table = _dh_table(arm)
    if table is None:
        headers, rows = _joint_table(arm)
        align = "llll" + "r" * (len(headers) - 4)
        shape = "a serial chain" if arm.is_chain else "a tree"
        title = f"{type(arm).__name__}: {arm.name}, {arm.n} joint{'s' if arm.n != 1 else ''} ({kinds}), {shape}"
    else:
        headers, rows = table
        align = "l" + "r" * (len(headers) - 1)
        convention = arm.dh["convention"] if arm.dh else "standard"
        title = (
            f"{type(arm).__name__}: {arm.name}, {arm.n} joint{'s' if arm.n != 1 else ''} ({kinds}), "
            f"{convention} DH parameters"
        )
    symbols = _symbol_names(arm)
    if symbols:
        title += f", symbolic parameters {', '.join(symbols)}"
    return Summary(title, arm.description, headers, rows, _facts(arm), align)


def _limits(link: Link) -> list[str]:
    return [_joint_value(bound, link.joint.is_revolute) for bound in link.limits]


def _dh_table(arm: ArmModel) -> tuple[list[str], list[list[str]]] | None:
    """The DH table: theta, d, a, alpha, offset (the constant added to q) and limits; None without one."""
    dh = arm.dh
    rows = (dh or {}).get("rows")
    if not rows or len(rows) != arm.n or not arm.is_chain:
        return None
    headers = ["joint", "theta", "d", "a", "alpha", "offset", "q min", "q max"]
    cells = []
    for i, (link, row) in enumerate(zip(arm.links, rows, strict=True)):
        variable = f"q{i + 1}"
        if link.joint.is_revolute:
            theta, d, offset = variable, number(row["d"]), angle(row["theta"])
        else:
            theta, d, offset = angle(row["theta"]), variable, number(row["d"])
        cells.append([link.name, theta, d, number(row["a"]), angle(row["alpha"]), offset, *_limits(link)])
    return headers, cells


def _joint_table(arm: ArmModel) -> tuple[list[str], list[list[str]]]:
    """Name, kind, parent, axis, placement (xyz, rpy) and limits of each joint; the frame offset when some has one."""
    offsets = any(not _is_identity(link.joint.frame_offset) for link in arm.links)
    headers = ["joint", "kind", "parent", "axis", "xyz (m)", "rpy"]
    if offsets:
        headers += ["offset xyz (m)", "offset rpy"]
    headers += ["q min", "q max"]
    names = arm.joint_names
    cells = []
    for link in arm.links:
        joint = link.joint
        parent = "base" if link.parent < 0 else names[link.parent]
        row = [link.name, joint.kind, parent, _axis(joint.axis), *_pose(joint.placement)]
        if offsets:
            row += list(_pose(joint.frame_offset))
        cells.append(row + _limits(link))
    return headers, cells


def _symbol_names(arm: ArmModel) -> list[str]:
    """The names of the SymPy symbols among the arm's parameters, sorted."""
    if not arm.is_symbolic:
        return []
    values: list[object] = [arm.gravity]
    for link in arm.links:
        values += [link.inertial.mass, link.inertial.com, link.inertial.inertia]
        values += [link.joint.placement, link.joint.frame_offset]
    names = set()
    for value in values:
        for item in np.asarray(value, dtype=object).ravel():
            names |= {str(s) for s in getattr(item, "free_symbols", ())}
    return sorted(names)


def _facts(arm: ArmModel) -> list[tuple[str, list[str]]]:
    links, n = arm.links, arm.n
    facts: list[tuple[str, list[str]]] = []
    masses = [link.inertial.mass for link in links]
    if all(_is_zero(m) for m in masses):
        facts.append(("mass", ["none (no dynamics: kinematics only)"]))
    else:
        facts.append(("mass", [f"{_numbers(masses)} kg"]))
    given = sum(any(not _is_zero(x) for x in np.asarray(link.inertial.inertia).ravel()) for link in links)
    if given == 0:
        facts.append(("inertia", ["none (point masses)"]))
    else:
        which = "every link" if given == n else f"{given} of {n} links"
        facts.append(("inertia", [f"given for {which} (about the centre of mass)"]))
    facts.append(("gravity", [f"{_numbers(arm.gravity)} m/s²"]))
    viscous = arm.viscous_friction
    if np.any(viscous != 0):
        facts.append(("viscous friction", [f"G²B = {_numbers(viscous)} (at the joints)"]))
    else:
        facts.append(("viscous friction", ["none"]))
    coulomb = arm.coulomb_friction
    if np.any(coulomb != 0):
        lines = [f"|G|Tc+ = {_numbers(coulomb[:, 0])}", f"|G|Tc- = {_numbers(coulomb[:, 1])}"]
        facts.append(("Coulomb friction", lines))
    else:
        facts.append(("Coulomb friction", ["none"]))
    stribeck = arm.stribeck_friction
    if np.any(stribeck[:, 0] != 0):
        lines = [f"Fs = {_numbers(stribeck[:, 0])}", f"vs = {_numbers(stribeck[:, 1])}"]
        facts.append(("Stribeck friction", lines))
    sigmoid = arm.sigmoid_friction
    if np.any(sigmoid[:, 0] != 0):
        lines = [f"A = {_numbers(sigmoid[:, 0])}", f"alpha = {_numbers(sigmoid[:, 1])}",
                 f"shift = {_numbers(sigmoid[:, 2])}"]  # fmt: skip
        facts.append(("sigmoid friction", lines))
    reflected = arm.reflected_inertia
    ratios = np.array([link.gear_ratio for link in links])
    motors = []
    if np.any(reflected != 0):
        motors.append(f"reflected inertia G²Jm = {_numbers(reflected)}")
    if np.any(ratios != 1):
        motors.append(f"gear ratio G = {_numbers(ratios)}")
    facts.append(("motors", motors or ["none"]))
    if not _is_identity(arm.tool) or arm.tool_link != n - 1:
        xyz, rpy = _pose(arm.tool)
        facts.append(("tool", [f"on {links[arm.tool_link].name}: xyz {xyz} m, rpy {rpy}"]))
    if not _is_identity(arm.base):
        xyz, rpy = _pose(arm.base)
        facts.append(("base", [f"xyz {xyz} m, rpy {rpy}"]))
    configurations = arm.configurations
    if configurations:
        revolute = [link.joint.is_revolute for link in links]
        facts.append(
            (
                "configurations",
                [
                    f"{key} = " + ", ".join(_joint_value(x, r) for x, r in zip(vector, revolute, strict=True))
                    for key, vector in configurations.items()
                ],
            )
        )
    return facts
