"""armdyn's own model file: everything an arm holds, as JSON, read back exactly.

``save_arm(arm, path)`` writes and ``load_arm(path)`` reads a JSON file (suffix .json) of this
form (numbers as JSON numbers, written with ``repr`` so that each reads back as the same double;
4x4 poses and 3x3 tensors as lists of rows)::

    {
      "format": "armdyn-arm",          the file's kind
      "version": 1,                    this layout
      "name": str, "description": str,
      "gravity": [gx, gy, gz],         world frame, m/s^2
      "base": 4x4, "tool": 4x4,        the root in the world; the tool in its link's frame
      "tool_link": int,                index of the link that carries the tool
      "configurations": {name: [q1, ..., qn]},
      "dh": null or {"convention": str, "rows": [{"kind", "a", "alpha", "d", "theta"}, ...]},
      "links": [                       parents before children
        {
          "name": str, "parent": int (-1 for the base),
          "joint": {"name": str, "kind": "revolute" | "prismatic",
                    "placement": 4x4, "axis": [x, y, z], "frame_offset": 4x4},
          "inertial": {"name": str, "mass": m, "com": [x, y, z],
                       "inertia": 3x3 about the centre of mass, "strict": bool},
          "viscous": B, "coulomb": [Tc+, Tc-], "motor_inertia": Jm, "gear_ratio": G,
          "limits": [lower, upper] (null for none),
          "stribeck": null or [Fs, vs], "sigmoid": null or [A, alpha, shift]
        }, ...
      ]
    }

The fields are those of armdyn.model.arm.ArmModel, Link, Joint and Inertial (see them for
units and rules; B, Tc and Jm are motor side, Stribeck and sigmoid friction joint side). Every
key is required and no other is allowed, so that a misspelt key is an error, not a default.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import reprlib
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.arm import ArmModel, Link
from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint
from armdyn.robot import Robot

FORMAT, VERSION = "armdyn-arm", 1
SUFFIX = ".json"
_ARM_KEYS = (
    "format",
    "version",
    "name",
    "description",
    "gravity",
    "base",
    "tool",
    "tool_link",
    "configurations",
    "dh",
    "links",
)
_LINK_KEYS = (
    "name",
    "parent",
    "joint",
    "inertial",
    "viscous",
    "coulomb",
    "motor_inertia",
    "gear_ratio",
    "limits",
    "stribeck",
    "sigmoid",
)
_JOINT_KEYS = ("name", "kind", "placement", "axis", "frame_offset")
_INERTIAL_KEYS = ("name", "mass", "com", "inertia", "strict")
_LAWS = ("stribeck", "sigmoid")  # friction laws a Link may or may not have (getattr, None when it has not)


def arm_to_dict(arm: ArmModel) -> dict[str, Any]:
    """The arm as the JSON object of the model file (see the module docstring), numbers as Python floats.

    Parameters
    ----------
    arm : ArmModel
        A numeric arm (a Robot or any ArmModel).

    Returns
    -------
    dict
        The object, ready for ``json.dumps``.

    Raises
    ------
    armdyn.ModelError
        When ``arm`` is not an ArmModel, has symbolic (SymPy) parameters, or its DH table holds
        values JSON cannot (anything but text, numbers, lists and mappings).
    """
    if not isinstance(arm, ArmModel):
        raise ModelError(f"a model file holds an ArmModel (a Robot), got {reprlib.repr(arm)}")
    if arm.is_symbolic:
        raise ModelError(
            f"robot '{arm.name}' has symbolic (SymPy) parameters, and a model file holds numbers: "
            "substitute numbers first"
        )
    return {
        "format": FORMAT,
        "version": VERSION,
        "name": arm.name,
        "description": arm.description,
        "gravity": _floats(arm.gravity),
        "base": _floats(arm.base),
        "tool": _floats(arm.tool),
        "tool_link": arm.tool_link,
        "configurations": {key: _floats(value) for key, value in arm.configurations.items()},
        "dh": None if arm.dh is None else _plain(arm.dh, f"robot '{arm.name}': dh"),
        "links": [_link_to_dict(link) for link in arm.links],
    }


def save_arm(arm: ArmModel, path: str | os.PathLike[str]) -> Path:
    """Write the arm to armdyn's model file (JSON; the layout in the module docstring).

    Every number is written with ``repr`` (as ``json`` does), so ``load_arm`` gives back an
    arm equal in every number: links (joint kind, placement, axis, frame offset, mass
    properties, friction including Stribeck and sigmoid where the Link has them, motor,
    limits), gravity, base, tool and tool link, configurations, name, description and DH table.

    Parameters
    ----------
    arm : ArmModel
        A numeric arm (a Robot or any ArmModel).
    path : str or os.PathLike
        The file to write, named with the suffix .json.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    armdyn.ModelError
        When the path does not end in .json, the arm is not an ArmModel or has symbolic
        parameters (see ``arm_to_dict``), or the file cannot be written (the message names it).
    """
    file = Path(path)
    if file.suffix.lower() != SUFFIX:
        raise ModelError(f"{file}: an armdyn model file is JSON and is named with the suffix {SUFFIX}")
    text = json.dumps(arm_to_dict(arm), indent=1, allow_nan=False)
    # rows of numbers on one line each (a pose reads as four rows), keys one per line
    text = re.sub(r"\[[-+0-9.eEnul,\s]*\]", _one_line, text)
    try:
        file.write_text(text + "\n", encoding="utf-8")
    except OSError as error:
        raise ModelError(f"{file}: cannot write the model file ({error.strerror or error})") from None
    return file


def load_arm(path: str | os.PathLike[str]) -> Robot:
    """Read an arm from armdyn's model file (JSON; the layout in the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file, as ``save_arm`` writes it.

    Returns
    -------
    Robot
        The arm, equal in every number to the one saved. Inertias that break the triangle
        inequality load without a warning when the file marks them ``"strict": false`` (they
        were accepted so when the arm was made).

    Raises
    ------
    armdyn.ModelError
        When the file is missing or unreadable, is not JSON (the message gives the line), holds
        NaN or Infinity, is not an armdyn model file ("format"), has another version than 1, lacks
        a key or holds one that the layout does not have (the message names the file and the
        key, e.g. ``links[2].inertial.mass``), holds a value of the wrong kind, or describes an
        invalid arm (as ArmModel, Link, Joint and Inertial refuse it, naming the link); when
        it gives Stribeck or sigmoid friction and this version's Link has no such field.
    """
    file = Path(path)
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise ModelError(f"{file}: cannot read the model file ({reason})") from None
    try:
        data = json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as error:
        raise ModelError(f"{file}: not JSON (line {error.lineno}, column {error.colno}: {error.msg})") from None
    except ValueError as error:  # a NaN or Infinity constant
        raise ModelError(f"{file}: {error}") from None
    return arm_from_dict(data, str(file))


def arm_from_dict(data: object, source: str = "model file") -> Robot:
    """The arm that a model file's JSON object describes (see the module docstring).

    Parameters
    ----------
    data : dict
        The object, as ``json.loads`` gives it.
    source : str, optional
        Names the origin in error messages (``load_arm`` gives the file; default "model file").

    Returns
    -------
    Robot
        The arm.

    Raises
    ------
    armdyn.ModelError
        As ``load_arm``, the message starting with ``source``.
    """
    fields = _fields(data, "", _ARM_KEYS, source)
    if fields["format"] != FORMAT:
        raise ModelError(f"{source}: key 'format' is {fields['format']!r}: not an armdyn model file ('{FORMAT}')")
    version = fields["version"]
    if isinstance(version, bool) or version != VERSION:
        raise ModelError(f"{source}: key 'version' is {version!r}: this armdyn reads version {VERSION}")
    links = fields["links"]
    if not isinstance(links, list):
        raise ModelError(f"{source}: key 'links' must be a list of links, got {reprlib.repr(links)}")
    configurations, dh = fields["configurations"], fields["dh"]
    if not isinstance(configurations, Mapping):
        raise ModelError(f"{source}: key 'configurations' must be an object, got {reprlib.repr(configurations)}")
    if dh is not None and not isinstance(dh, Mapping):
        raise ModelError(f"{source}: key 'dh' must be an object or null, got {reprlib.repr(dh)}")
    try:
        with warnings.catch_warnings():  # an inertia the file marks strict: false was accepted when the arm was made
            warnings.filterwarnings("ignore", message=".*triangle inequality")
            return Robot(
                [_link_from_dict(link, f"links[{index}].", source) for index, link in enumerate(links)],
                name=_text(fields["name"], "name", source),
                description=_text(fields["description"], "description", source),
                gravity=fields["gravity"],
                base=fields["base"],
                tool=fields["tool"],
                tool_link=fields["tool_link"],
                configurations=configurations,
                dh=dh,
            )
    except (ModelError, TypeError) as error:
        if str(error).startswith(f"{source}: "):
            raise
        raise ModelError(f"{source}: {error}") from None


def _one_line(match: re.Match[str]) -> str:
    """A list of numbers that json.dumps spread over lines, on one line (JSON text never holds a raw newline, so a
    list on one line, which might be inside a string, is left as it is)."""
    text = match.group(0)
    return "[" + " ".join(text[1:-1].split()) + "]" if "\n" in text else text


def _floats(array: object) -> Any:
    """An array as nested lists of Python floats (json writes each with repr)."""
    return np.asarray(array, dtype=float).tolist()


def _plain(value: object, where: str) -> Any:
    """A DH table (text, numbers, lists and mappings) as JSON values, numbers as Python ints and floats."""
    if value is None or isinstance(value, (str, bool)):
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        number = float(value)
        if not np.isfinite(number):
            raise ModelError(f"{where}: holds {number}, which JSON cannot")
        return number
    if isinstance(value, Mapping):
        return {str(key): _plain(item, f"{where}.{key}") for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(item, f"{where}[{index}]") for index, item in enumerate(value)]
    raise ModelError(f"{where}: holds {reprlib.repr(value)}, which a model file cannot (numbers and text only)")


def _link_to_dict(link: Link) -> dict[str, Any]:
    joint, body = link.joint, link.inertial
    laws = {key: None if getattr(link, key, None) is None else _floats(getattr(link, key)) for key in _LAWS}
    return {
        "name": link.name,
        "parent": link.parent,
        "joint": {
            "name": joint.name,
            "kind": joint.kind,
            "placement": _floats(joint.placement),
            "axis": _floats(joint.axis),
            "frame_offset": _floats(joint.frame_offset),
        },
        "inertial": {
            "name": body.name,
            "mass": float(body.mass),
            "com": _floats(body.com),
            "inertia": _floats(body.inertia),
            "strict": bool(body.strict),
        },
        "viscous": float(link.viscous),
        "coulomb": _floats(link.coulomb),
        "motor_inertia": float(link.motor_inertia),
        "gear_ratio": float(link.gear_ratio),
        "limits": [None if np.isinf(value) else float(value) for value in link.limits],
        **laws,
    }


def _link_from_dict(data: object, where: str, source: str) -> Link:
    fields = _fields(data, where, _LINK_KEYS, source)
    joint = _fields(fields["joint"], f"{where}joint.", _JOINT_KEYS, source)
    body = _fields(fields["inertial"], f"{where}inertial.", _INERTIAL_KEYS, source)
    if not isinstance(body["strict"], bool):
        raise ModelError(f"{source}: key '{where}inertial.strict' must be true or false, got {body['strict']!r}")
    limits = fields["limits"]
    if not isinstance(limits, list) or len(limits) != 2:
        raise ModelError(f"{source}: key '{where}limits' must be [lower, upper] (null for none), got {limits!r}")
    lower, upper = (-np.inf if limits[0] is None else limits[0]), (np.inf if limits[1] is None else limits[1])
    known = {field.name for field in dataclasses.fields(Link)}
    laws = {}
    for key in _LAWS:
        value = fields[key]
        if value is None or (key not in known and isinstance(value, list) and not any(value)):
            continue  # absent, or zero where this Link has no such law: the same friction
        if key not in known:
            raise ModelError(f"{source}: key '{where}{key}': this version of armdyn has no {key} friction")
        laws[key] = value
    name = _text(fields["name"], f"{where}name", source)
    return Link(
        name,
        Joint(
            _text(joint["kind"], f"{where}joint.kind", source),
            joint["placement"],
            joint["axis"],
            joint["frame_offset"],
            _text(joint["name"], f"{where}joint.name", source),
        ),
        Inertial(
            body["mass"],
            body["com"],
            body["inertia"],
            _text(body["name"], f"{where}inertial.name", source),
            body["strict"],
        ),
        parent=fields["parent"],
        viscous=fields["viscous"],
        coulomb=fields["coulomb"],
        motor_inertia=fields["motor_inertia"],
        gear_ratio=fields["gear_ratio"],
        limits=(lower, upper),
        **laws,
    )


def _fields(data: object, where: str, keys: tuple[str, ...], source: str) -> dict[str, Any]:
    """A JSON object's values for exactly ``keys``: a missing or an unknown key is refused, named with ``where``."""
    what = f"key '{where[:-1]}'" if where else "the top level"
    if not isinstance(data, dict):
        raise ModelError(f"{source}: {what} must be a JSON object, got {reprlib.repr(data)}")
    missing = [key for key in keys if key not in data]
    if missing:
        raise ModelError(
            f"{source}: missing key '{where}{missing[0]}'" + (f" (and {missing[1:]})" if missing[1:] else "")
        )
    unknown = [key for key in data if key not in keys]
    if unknown:
        raise ModelError(f"{source}: unknown key '{where}{unknown[0]}' (version {VERSION} has {', '.join(keys)})")
    return data


def _text(value: object, key: str, source: str) -> str:
    if not isinstance(value, str):
        raise ModelError(f"{source}: key '{key}' must be text, got {reprlib.repr(value)}")
    return value


def _refuse_constant(constant: str) -> None:
    raise ValueError(f"holds {constant}, which a model file never does (a bound without a value is null)")
