"""What an arm is: links in a kinematic tree with gravity, base and tool, friction, motors, limits.

Data and validation only: no algorithm lives here (armdyn.dynamics and armdyn.kinematics
are free functions of an ArmModel; armdyn.robot.Robot joins the two for users).
"""

from __future__ import annotations

import dataclasses
import reprlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Self, cast

import numpy as np

from armdyn.errors import ModelError
from armdyn.model import display
from armdyn.model.inertial import Inertial, parameter_array, real_array, real_number, whole_number
from armdyn.model.joint import Joint, check_rigid, dh_joint, dh_parameters

_NO_LIMITS = (-np.inf, np.inf)
_DH_KEYS = frozenset(
    {"kind", "a", "alpha", "d", "theta", "mass", "com", "inertia", "Jm", "G", "B", "Tc", "qlim", "name", "stribeck",
     "sigmoid"}
)  # fmt: skip


@dataclass(frozen=True, eq=False)
class Link:
    """One joint and the body it moves, with the joint's friction and motor.

    Friction and motor follow the Robotics Toolbox: ``viscous`` (B) and ``coulomb``
    ((Tc+, Tc-), the friction torque for positive and for negative velocity, so Tc- <= 0)
    act on the motor side of a gear of ratio ``gear_ratio`` (G) whose rotor has inertia
    ``motor_inertia`` (Jm). At the joint they appear as G^2 Jm, G^2 B and |G| Tc. With
    the default G = 1 and Jm = 0 the friction values are joint-side values.

    Two further friction laws act on the joint side (whatever the gear): the Stribeck
    breakaway friction Fs exp(-(qd/vs)^2) sgn(qd) on top of the Coulomb step (Armstrong-Helouvry,
    Dupont and Canudas de Wit, "A survey of models, analysis tools and compensation methods for
    the control of machines with friction", Automatica 30(7), 1994), and the sigmoid law of
    Gaz, Cognetti, Oliva, Robuffo Giordano and De Luca ("Dynamic identification of the Franka
    Emika Panda robot with retrieval of feasible parameters using penalty-based optimization",
    IEEE RA-L 4(4), 2019), F(qd) = A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift)),
    zero at rest and increasing. The joint's friction is F(qd) = G^2 B qd + |G| Tc(qd) + Stribeck
    + sigmoid.

    Parameters
    ----------
    name : str
        The joint's name, unique within an arm.
    joint : Joint
        The joint.
    inertial : Inertial
        Mass properties of the body the joint moves, in its link frame.
    parent : int, optional
        Index of the parent link in the arm, -1 (default) for the base.
    viscous : float, optional
        Viscous friction coefficient B, motor side, >= 0 (default 0).
    coulomb : (float, float), optional
        Coulomb friction (Tc+, Tc-), motor side, with Tc+ >= 0 >= Tc- (default (0, 0)).
    motor_inertia : float, optional
        Rotor inertia Jm, >= 0 (default 0).
    gear_ratio : float, optional
        Gear ratio G, finite and non-zero (default 1); negative reverses the motor.
    limits : (float, float), optional
        Joint limits (lower, upper), rad or m (default unlimited, (-inf, inf)).
    stribeck : (float, float), optional
        Stribeck friction (Fs, vs), joint side: Fs >= 0 the breakaway torque (force) above the
        Coulomb level, vs the Stribeck velocity, > 0 when Fs > 0 (default (0, 0): none).
    sigmoid : (float, float, float), optional
        Sigmoid friction (A, alpha, shift) of Gaz et al. (2019), joint side: A >= 0 its span,
        alpha >= 0 its steepness (s/rad or s/m), shift its velocity offset (default (0, 0, 0):
        none; A = 0 means none).

    Raises
    ------
    armdyn.ModelError
        When ``joint`` is not a Joint or ``inertial`` not an Inertial, B, Jm or G is not a
        finite real number, Tc is not two finite real numbers, a sign rule is broken (B >= 0,
        Tc+ >= 0 >= Tc-, Jm >= 0, G != 0), the limits are not two real numbers (infinite for
        none) with lower <= upper, ``parent`` is below -1, ``stribeck`` is not two finite
        numbers with Fs >= 0 and vs > 0 when Fs > 0, or ``sigmoid`` not three finite numbers
        with A >= 0 and alpha >= 0; the message names the argument and the link. Numbers of
        1e15 or more in magnitude are refused.
    TypeError
        When ``parent`` is not an integer.
    """

    name: str
    joint: Joint
    inertial: Inertial
    parent: int = -1
    viscous: float = 0.0
    coulomb: tuple[float, float] = (0.0, 0.0)
    motor_inertia: float = 0.0
    gear_ratio: float = 1.0
    limits: tuple[float, float] = _NO_LIMITS
    stribeck: tuple[float, float] = (0.0, 0.0)
    sigmoid: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        where = f"link '{self.name}'"
        if not isinstance(self.joint, Joint):
            raise ModelError(f"{where}: joint must be a Joint, got {reprlib.repr(self.joint)}")
        if not isinstance(self.inertial, Inertial):
            raise ModelError(f"{where}: inertial must be an Inertial, got {reprlib.repr(self.inertial)}")
        object.__setattr__(self, "parent", whole_number(self.parent, "parent", where, -1))
        viscous = real_number(self.viscous, "viscous friction B", where)
        if viscous < 0:
            raise ModelError(f"{where}: viscous friction must be finite and >= 0 (dissipative), got {viscous:g}")
        object.__setattr__(self, "viscous", viscous)
        object.__setattr__(self, "coulomb", _coulomb(self.coulomb, where))
        motor_inertia = real_number(self.motor_inertia, "motor inertia Jm", where)
        if motor_inertia < 0:
            raise ModelError(f"{where}: motor inertia Jm must be finite and >= 0, got {motor_inertia:g}")
        object.__setattr__(self, "motor_inertia", motor_inertia)
        gear_ratio = real_number(self.gear_ratio, "gear ratio G", where)
        if gear_ratio == 0:
            raise ModelError(f"{where}: gear ratio G must be finite and non-zero, got {gear_ratio:g}")
        object.__setattr__(self, "gear_ratio", gear_ratio)
        object.__setattr__(self, "limits", _limits(self.limits, where))
        object.__setattr__(self, "stribeck", _stribeck(self.stribeck, where))
        object.__setattr__(self, "sigmoid", _sigmoid(self.sigmoid, where))

    @property
    def kind(self) -> str:
        return self.joint.kind


class ArmModel:
    """An arm: a kinematic tree of links (parents before children), immutable.

    armdyn.Robot is this data with the dynamics and kinematics as methods; the algorithms
    themselves take any ArmModel. A named configuration is also an attribute, read only
    (``arm.qn``; ``arm.configuration("qn")`` gives a copy to change).

    Parameters
    ----------
    links : sequence of Link
        The links, each after its parent; joint names unique.
    name : str, optional
        The arm's name, used in messages (default "robot").
    gravity : array_like, optional
        Acceleration of gravity in the world frame, 3 values (default [0, 0, -9.81]); SymPy
        expressions are accepted for closed-form work.
    base : array_like, optional
        Pose of the root in the world, a 4x4 homogeneous transform (default identity).
    tool : array_like, optional
        Pose of the tool in the frame of link ``tool_link``, 4x4 (default identity).
    tool_link : int, optional
        Index of the link carrying the tool (default the last link).
    configurations : mapping of str to array_like, optional
        Named joint vectors of n values each, e.g. {"qz": [0, 0]}.
    dh : mapping, optional
        The Denavit-Hartenberg table the arm was built from (``from_dh`` fills it:
        {"convention": ..., "rows": [...]}).
    description : str, optional
        A line describing the arm (default "").

    Attributes
    ----------
    n : int
        Number of joints (degrees of freedom).
    name, description : str
        As given.

    The arm never changes once made: assigning an attribute raises AttributeError, and
    ``replace``, ``with_payload`` and the like give new arms.

    ``print(arm)`` (and ``repr(arm)``) shows a summary, as the Robotics Toolbox prints a
    robot: its DH table or joint table and its dynamics; a Jupyter notebook shows the same
    as HTML tables.

    Raises
    ------
    armdyn.ModelError
        When ``links`` is not a sequence of Links or is empty, a parent index does not name
        an earlier link (or -1), two joints share a name, gravity is not a 3-vector of finite
        real numbers (or SymPy expressions), base or tool is not a finite real 4x4 rigid
        transform, ``tool_link`` is not a link index, ``configurations`` is not a mapping of
        identifiers to n finite real values each, or a name clashes with an attribute; the
        message names the argument. Numbers of 1e15 or more in magnitude are refused.
    TypeError
        When ``tool_link`` is not an integer.
    """

    def __init__(
        self,
        links: Sequence[Link],
        *,
        name: str = "robot",
        gravity: Iterable[object] = (0.0, 0.0, -9.81),
        base: np.ndarray | None = None,
        tool: np.ndarray | None = None,
        tool_link: int | None = None,
        configurations: Mapping[str, Iterable[float]] | None = None,
        dh: Mapping[str, Any] | None = None,
        description: str = "",
    ) -> None:
        where = f"robot '{name}'"
        self._links = _checked_links(links, where)
        self.n = len(self._links)  # a plain attribute: read in every compiled call
        self.name = name
        self.description = description
        self._gravity = _frozen(_gravity(gravity, where))
        self._base = _frozen(_transform(base, "base", where))
        self._tool = _frozen(_transform(tool, "tool", where))
        self._tool_link = _tool_link(tool_link, self.n, where)
        self._configurations = _configurations(configurations, self.n, where)
        self._dh = dict(dh) if dh else None
        for key, vector in self._configurations.items():  # also as attributes, read only: arm.qn
            if hasattr(self, key):
                raise ModelError(f"{where}: configuration name '{key}' is not free for an attribute")
            setattr(self, key, vector)
        self._parents = _frozen(np.array([link.parent for link in self._links], dtype=int))
        self._ancestors = _frozen(_ancestor_table(self._parents))
        self._sealed = True

    def __setattr__(self, name: str, value: object) -> None:
        if self.__dict__.get("_sealed"):
            raise AttributeError(f"{type(self).__name__} '{self.name}' is immutable: replace(...) gives a changed copy")
        object.__setattr__(self, name, value)

    # ----- construction -------------------------------------------------------------
    @classmethod
    def from_dh(
        cls,
        table: Sequence[Mapping[str, Any]],
        convention: str = "standard",
        **robot_options: Any,
    ) -> Self:
        """An arm from a Denavit-Hartenberg table, one mapping per joint (Appendix A).

        Each joint's parent is the joint before it (a serial chain).

        Parameters
        ----------
        table : sequence of mapping
            One row per joint. Row keys (all optional): ``kind`` ('R' or 'P', default
            'R'), ``a``, ``alpha``, ``d``, ``theta`` (for a revolute joint theta is the
            offset added to q; for a prismatic one d is), ``mass``, ``com`` (in the DH link
            frame), ``inertia`` (about the c.o.m.: 3 moments, 6 values
            [Ixx Iyy Izz Ixy Iyz Ixz] or 3x3), ``Jm``, ``G``, ``B``, ``Tc`` ((Tc+, Tc-)),
            ``qlim`` ((lower, upper)), ``name`` (default joint1, joint2, ...), ``strict``
            (triangle-inequality check, default True).
        convention : str, optional
            'standard' (default) or 'modified' (Craig) DH.
        **robot_options
            Further keywords for the constructor: name, gravity, base, tool, tool_link,
            configurations, description.

        Returns
        -------
        ArmModel
            The arm, of the class this is called on (``Robot.from_dh`` makes a Robot).

        Raises
        ------
        armdyn.ModelError
            When ``table`` is not a sequence of mappings, a row has an unknown key, an unknown
            joint kind, a DH parameter that is neither a finite real number nor a SymPy
            expression, or invalid mass properties, friction, motor or limits (see Inertial
            and Link; the message names the key's quantity and the link); when ``convention``
            is neither 'standard' nor 'modified'; and as the constructor.
        """
        if not isinstance(convention, str) or convention not in ("standard", "modified"):
            raise ModelError(f"DH convention must be 'standard' or 'modified', got {reprlib.repr(convention)}")
        links = []
        rows = []
        for index, row in enumerate(_dh_rows(table)):
            name = str(row.get("name", f"joint{index + 1}"))
            where = f"link '{name}'"
            unknown = set(row) - _DH_KEYS - {"strict"}
            if unknown:
                raise ModelError(f"{where}: unknown DH row keys {sorted(unknown, key=str)} (known: {sorted(_DH_KEYS)})")
            a, alpha, d, theta = dh_parameters(
                row.get("a", 0.0), row.get("alpha", 0.0), row.get("d", 0.0), row.get("theta", 0.0), where
            )
            joint = dh_joint(row.get("kind", "R"), a, alpha, d, theta, convention, name)
            inertial = Inertial(
                row.get("mass", 0.0),
                row.get("com", np.zeros(3)),
                row.get("inertia", np.zeros(3)),
                name,
                row.get("strict", True),
            )
            links.append(
                Link(
                    name,
                    joint,
                    inertial,
                    parent=index - 1,
                    viscous=row.get("B", 0.0),
                    coulomb=row.get("Tc", (0.0, 0.0)),
                    motor_inertia=row.get("Jm", 0.0),
                    gear_ratio=row.get("G", 1.0),
                    limits=row.get("qlim", _NO_LIMITS),
                    stribeck=row.get("stribeck", (0.0, 0.0)),
                    sigmoid=row.get("sigmoid", (0.0, 0.0, 0.0)),
                )
            )
            rows.append({"kind": joint.kind, "a": a, "alpha": alpha, "d": d, "theta": theta})
        return cls(links, dh={"convention": convention, "rows": rows}, **robot_options)

    def replace(self, links: Sequence[Link] | None = None, **changes: Any) -> Self:
        """A copy with some links or options changed (the arm itself never changes).

        Parameters
        ----------
        links : sequence of Link, optional
            The new links (default the arm's own).
        **changes
            Constructor options to change: name, gravity, base, tool, tool_link,
            configurations, dh, description.

        Returns
        -------
        ArmModel
            The new arm, of the same class.

        Raises
        ------
        armdyn.ModelError
            When the changed arm is invalid (see the class docstring).
        """
        options: dict[str, Any] = {
            "name": self.name,
            "gravity": self._gravity,
            "base": self._base,
            "tool": self._tool,
            "tool_link": self._tool_link,
            "configurations": self._configurations,
            "dh": self._dh,
            "description": self.description,
        }
        options.update(changes)
        return type(self)(self._links if links is None else links, **options)

    def with_payload(self, mass: float, com: Iterable[float] = (0.0, 0.0, 0.0), inertia: object = None) -> Self:
        """The arm carrying a payload rigidly attached to the tool link (added, never overwriting).

        The payload's mass properties are added to the tool link's (parallel-axis theorem).

        Parameters
        ----------
        mass : float
            The payload's mass (kg).
        com : array_like, optional
            Its centre of mass in the tool link's frame (default the frame origin).
        inertia : array_like, optional
            Its inertia about its own centre of mass, in the tool link's axes: 3 moments,
            6 values [Ixx Iyy Izz Ixy Iyz Ixz] or 3x3 (default none: a point mass).

        Returns
        -------
        ArmModel
            The arm with the payload, of the same class.

        Raises
        ------
        armdyn.ModelError
            When the payload's mass properties are invalid (see Inertial).
        """
        tool = self._links[self._tool_link]
        # Inertial takes array_like values (it checks and converts them); its fields are typed as the arrays kept
        given = cast(np.ndarray, np.zeros((3, 3)) if inertia is None else inertia)
        payload = Inertial(mass, cast(np.ndarray, com), given, f"{tool.name} payload")
        links = list(self._links)
        links[self._tool_link] = dataclasses.replace(tool, inertial=tool.inertial + payload)
        return self.replace(links)

    def without_friction(self) -> Self:
        """The same arm with no friction (viscous, Coulomb, Stribeck or sigmoid).

        Returns
        -------
        ArmModel
            The arm without friction, of the same class; motors are kept.
        """
        return self.replace(
            [
                dataclasses.replace(link, viscous=0.0, coulomb=(0.0, 0.0), stribeck=(0.0, 0.0), sigmoid=(0.0, 0.0, 0.0))
                for link in self._links
            ]
        )

    def without_motors(self) -> Self:
        """The same arm with no motor rotor inertia (friction, if any, is kept at the joint side).

        Returns
        -------
        ArmModel
            The arm with Jm = 0 and G = 1, its friction moved to the joint side (G^2 B and
            |G| Tc), of the same class.
        """
        links = [
            dataclasses.replace(
                link,
                viscous=link.gear_ratio**2 * link.viscous,
                coulomb=(abs(link.gear_ratio) * link.coulomb[0], abs(link.gear_ratio) * link.coulomb[1]),
                motor_inertia=0.0,
                gear_ratio=1.0,
            )
            for link in self._links
        ]
        return self.replace(links)

    def with_gravity(self, gravity: Iterable[object]) -> Self:
        """The same arm under another gravity.

        Parameters
        ----------
        gravity : array_like
            Acceleration of gravity in the world frame, 3 values (SymPy expressions accepted).

        Returns
        -------
        ArmModel
            The arm with the new gravity, of the same class.

        Raises
        ------
        armdyn.ModelError
            When ``gravity`` is not a finite 3-vector.
        """
        return self.replace(gravity=gravity)

    def reduced(self, locked: Mapping[str, float]) -> Self:
        """The arm with some joints locked: each becomes fixed at a given value.

        Pinocchio's reduced model (``pin.buildReducedModel``). A locked joint's body is
        merged into its parent's at the locked configuration (parallel-axis theorem, as the
        URDF loader merges fixed joints), or onto the base when its parent is the base; the
        joints below it stay, re-attached to that parent with their placements composed
        through the locked joint. Any tree reduces so: a locked joint only turns one
        moving frame into a fixed one. The locked joints' friction and motors go with them.
        Kinematics and dynamics of the remaining joints equal those of the full arm with the
        locked joints held at their values (and zero velocity and acceleration).

        The tool stays on the same body: when its link is locked it moves to the link that
        absorbs it, with ``tool`` composed so that the tool pose is unchanged. Named
        configurations keep the remaining joints' values; the DH table (which no longer
        describes the arm) is dropped.

        Parameters
        ----------
        locked : mapping of str to float
            Joint name to the value (rad or m) it is locked at, within the joint's limits.

        Returns
        -------
        ArmModel
            The reduced arm, of the same class, with ``n - len(locked)`` joints in the same
            order.

        Raises
        ------
        armdyn.ModelError
            When ``locked`` is not a mapping, names a joint the arm does not have, holds a
            value that is not a finite real number or lies outside the joint's limits; when
            every joint is locked; when the locked joints weld the tool to the base (no
            moving joint left between them); or, for an arm with SymPy parameters, when the
            tool's new pose would hold symbols.
        """
        where = f"robot '{self.name}'"
        if not isinstance(locked, Mapping):
            raise ModelError(f"{where}: locked must be a mapping of joint name to value, got {locked!r}")
        values = {}
        for name, value in locked.items():
            if name not in self.joint_names:
                raise ModelError(f"{where}: cannot lock joint '{name}': no such joint (the joints: {self.joint_names})")
            link = self._links[self.joint_names.index(name)]
            try:  # a real number; not a string, a bool or a complex number that float() would take
                real = (
                    not isinstance(value, (str, bytes, bool, np.bool_)) and np.isrealobj(value) and np.ndim(value) == 0
                )
                number = float(value) if real else np.nan
            except (TypeError, ValueError):
                number = np.nan
            if not np.isfinite(number):
                raise ModelError(f"{where}: joint '{name}' must be locked at a finite real number, got {value!r}")
            lower, upper = link.limits
            if not lower <= number <= upper:
                unit = "rad" if link.kind == "revolute" else "m"
                raise ModelError(
                    f"{where}: joint '{name}' cannot be locked at {number:g} {unit}: outside its limits "
                    f"[{lower:g}, {upper:g}]"
                )
            values[name] = number
        if len(values) == self.n:
            raise ModelError(f"{where}: locking every joint ({sorted(values)}) leaves no joint to move")
        links: list[Link] = []
        # For each link of this arm: (index of the reduced link whose frame carries it, or -1 for the base; its
        # frame's pose in that frame, None for identity)
        anchors: list[tuple[int, np.ndarray | None]] = []
        for link in self._links:
            owner, pose = (-1, None) if link.parent < 0 else anchors[link.parent]
            joint = link.joint
            placement = joint.placement if pose is None else pose @ joint.placement
            if link.name in values:
                frame = placement @ _motion(joint, values[link.name]) @ joint.frame_offset
                anchors.append((owner, frame))
                if owner >= 0:
                    body = links[owner].inertial + link.inertial.transformed(frame)
                    links[owner] = dataclasses.replace(links[owner], inertial=body)
                continue
            moved = joint if pose is None else dataclasses.replace(joint, placement=placement)
            links.append(dataclasses.replace(link, joint=moved, parent=owner))
            anchors.append((len(links) - 1, None))
        tool_link, pose = anchors[self._tool_link]
        if tool_link < 0:
            raise ModelError(
                f"{where}: locking {sorted(values)} welds the tool (on link '{self._links[self._tool_link].name}') to "
                "the base: no moving joint is left between them; keep one of them free"
            )
        tool = self._tool if pose is None else pose @ self._tool
        try:  # an arm with SymPy parameters may compose them into the tool, which must be numbers
            tool = np.array(tool, dtype=float)
        except TypeError:
            raise ModelError(
                f"{where}: locking {sorted(values)} moves the tool onto link '{self._links[tool_link].name}' through "
                "symbolic (SymPy) parameters, and a tool pose must be numbers; lock joints that do not carry the tool"
            ) from None
        kept = [i for i, name in enumerate(self.joint_names) if name not in values]
        locks = "locked " + ", ".join(f"{name}={value:g}" for name, value in values.items()) if values else ""
        return self.replace(
            links,
            tool_link=tool_link,
            tool=tool,
            configurations={key: vector[kept] for key, vector in self._configurations.items()},
            dh=None if values else self._dh,
            description="; ".join(text for text in (self.description, locks) if text),
        )

    # ----- structure ----------------------------------------------------------------
    @property
    def links(self) -> tuple[Link, ...]:
        return self._links

    @property
    def joint_names(self) -> list[str]:
        return [link.name for link in self._links]

    @property
    def kinds(self) -> list[str]:
        return [link.kind for link in self._links]

    @property
    def parents(self) -> np.ndarray:
        """Index of each link's parent (-1 for the base)."""
        return self._parents

    @property
    def is_chain(self) -> bool:
        return bool(np.all(self.parents == np.arange(-1, self.n - 1)))

    @property
    def ancestors(self) -> np.ndarray:
        """Boolean (n, n): [i, j] is True when joint j moves link i (j is i or an ancestor)."""
        return self._ancestors

    @property
    def gravity(self) -> np.ndarray:
        return self._gravity

    @property
    def base(self) -> np.ndarray:
        return self._base

    @property
    def tool(self) -> np.ndarray:
        return self._tool

    @property
    def tool_link(self) -> int:
        return self._tool_link

    @property
    def dh(self) -> dict[str, Any] | None:
        """The Denavit-Hartenberg table the arm was built from, if any."""
        return self._dh

    @property
    def is_symbolic(self) -> bool:
        """True when some parameter is a SymPy expression (for closed-form derivation)."""
        return self._gravity.dtype == object or any(
            link.inertial.is_symbolic or link.joint.placement.dtype == object for link in self._links
        )

    @property
    def has_dynamics(self) -> bool:
        """True when some link has mass or inertia."""
        return any(
            link.inertial.is_symbolic or link.inertial.mass > 0 or np.any(link.inertial.inertia != 0)
            for link in self._links
        )

    # ----- per-joint data, joint side --------------------------------------------------
    @property
    def qlim(self) -> np.ndarray:
        """Joint limits, shape (2, n): lower row, upper row (inf where unlimited)."""
        return _frozen(np.array([link.limits for link in self._links]).T)

    @property
    def reflected_inertia(self) -> np.ndarray:
        """G^2 Jm per joint: the motor rotor inertia seen at the joint."""
        return _frozen(np.array([link.gear_ratio**2 * link.motor_inertia for link in self._links]))

    @property
    def viscous_friction(self) -> np.ndarray:
        """G^2 B per joint: the viscous coefficient seen at the joint (the diagonal of Fv)."""
        return _frozen(np.array([link.gear_ratio**2 * link.viscous for link in self._links]))

    @property
    def coulomb_friction(self) -> np.ndarray:
        """|G| (Tc+, Tc-) per joint, shape (n, 2): Coulomb friction seen at the joint."""
        return _frozen(np.array([[abs(link.gear_ratio) * c for c in link.coulomb] for link in self._links]))

    @property
    def stribeck_friction(self) -> np.ndarray:
        """(Fs, vs) per joint, shape (n, 2): the Stribeck friction, joint side (zeros for none)."""
        return _frozen(np.array([link.stribeck for link in self._links], dtype=float).reshape(len(self._links), 2))

    @property
    def sigmoid_friction(self) -> np.ndarray:
        """(A, alpha, shift) per joint, shape (n, 3): the sigmoid friction, joint side (zeros for none)."""
        return _frozen(np.array([link.sigmoid for link in self._links], dtype=float).reshape(len(self._links), 3))

    @property
    def configurations(self) -> dict[str, np.ndarray]:
        return {key: value.copy() for key, value in self._configurations.items()}

    def configuration(self, name: str) -> np.ndarray:
        """A named joint configuration (for the PUMA 560: qz, qr, qs, qn), as a new array.

        Parameters
        ----------
        name : str
            The configuration's name.

        Returns
        -------
        numpy.ndarray
            The joint vector, (n,), a copy.

        Raises
        ------
        armdyn.ModelError
            When the arm has no configuration of that name.
        TypeError
            When ``name`` is not a string.
        """
        if not isinstance(name, str):
            raise TypeError(f"a configuration name must be a str, got {reprlib.repr(name)} ({type(name).__name__})")
        try:
            return self._configurations[name].copy()
        except KeyError:
            raise ModelError(
                f"robot '{self.name}' has no configuration '{name}' (it has {sorted(self._configurations)})"
            ) from None

    # ----- display ------------------------------------------------------------------
    def __repr__(self) -> str:
        """The arm's summary, as the Robotics Toolbox prints a robot (``print(arm)`` shows the same).

        The name, the number of joints and their kinds; the Denavit-Hartenberg table (theta,
        d, a, alpha, the offset added to q, the joint limits) when the arm was built from one,
        else a table of the joints (kind, parent, axis, placement as xyz and roll-pitch-yaw,
        limits); then the masses, whether inertias are given, gravity, friction, motors, the
        tool and base when they are not the identity, and the named configurations. Angles
        in degrees, lengths in metres, SymPy parameters by name (see armdyn.model.display).
        """
        return display.summary(self).text()

    def _repr_html_(self) -> str:
        """The same summary as HTML tables, for Jupyter notebooks."""
        return display.summary(self).html()


def _dh_rows(table: object) -> tuple[Mapping[str, Any], ...]:
    """The rows of a DH table, each a mapping."""
    if table is None or isinstance(table, (str, bytes, Mapping, set, frozenset)) or not isinstance(table, Iterable):
        raise ModelError(f"a DH table must be a sequence of rows, one mapping per joint, got {reprlib.repr(table)}")
    rows = tuple(table)
    for index, row in enumerate(rows):
        if not isinstance(row, Mapping):
            raise ModelError(
                f"DH table row {index + 1} must be a mapping of DH keys (a, alpha, d, theta, ...), "
                f"got {reprlib.repr(row)}"
            )
    return rows


def _checked_links(links: object, where: str) -> tuple[Link, ...]:
    """The links as a tuple: at least one, each a Link after its parent, joint names unique."""
    if (
        links is None
        or isinstance(links, (Link, str, bytes, Mapping, set, frozenset))
        or not isinstance(links, Iterable)
    ):
        raise ModelError(f"{where}: links must be a sequence of Link objects, got {reprlib.repr(links)}")
    items = tuple(links)
    if not items:
        raise ModelError(f"{where}: an arm needs at least one joint")
    names: list[object] = []  # a list: a name need not be hashable
    for index, link in enumerate(items):
        if not isinstance(link, Link):
            raise ModelError(f"{where}: links[{index}] is not a Link, got {reprlib.repr(link)}")
        parent = link.parent  # a Link checked it; this guards one changed behind its back
        if isinstance(parent, bool) or not isinstance(parent, (int, np.integer)) or not -1 <= parent < index:
            raise ModelError(
                f"link '{link.name}': parent index {parent!r} must name an earlier link (or -1 for the base)"
            )
        if link.name in names:
            raise ModelError(f"link '{link.name}': joint names must be unique")
        names.append(link.name)
    return items


def _gravity(value: object, where: str) -> np.ndarray:
    """Gravity as a 3-vector: finite real floats, or an object array holding SymPy expressions."""
    gravity = parameter_array(value, "gravity", where)
    if gravity.shape != (3,):
        raise ModelError(f"{where}: gravity must be a 3-vector, got shape {gravity.shape}")
    return gravity


def _transform(value: object, key: str, where: str) -> np.ndarray:
    """A base or tool pose: the identity for None, else a finite real 4x4 rigid transform."""
    if value is None:
        return np.eye(4)
    array = real_array(value, key, where)
    if array.shape != (4, 4):
        raise ModelError(f"{where}: {key} must be a finite 4x4 homogeneous transform, got shape {array.shape}")
    check_rigid(array, f"{where}: {key}")
    return array


def _tool_link(value: object, n: int, where: str) -> int:
    """The index of the link carrying the tool: the last link for None."""
    if value is None:
        return n - 1
    index = whole_number(value, "tool_link", where, 0)
    if index >= n:
        raise ModelError(f"{where}: tool_link {index} is not a link index (0..{n - 1})")
    return index


def _configurations(value: object, n: int, where: str) -> dict[str, np.ndarray]:
    """Named joint vectors: a mapping of identifiers to n finite real values each, read only."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ModelError(
            f"{where}: configurations must be a mapping of names to {n} joint values, got {reprlib.repr(value)}"
        )
    configurations = {}
    for key, vector in value.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise ModelError(f"{where}: configuration name {key!r} is not free for an attribute (not an identifier)")
        array = real_array(vector, f"configuration '{key}'", where)
        if array.shape != (n,):
            raise ModelError(f"{where}: configuration '{key}' must have {n} values, got {array.shape}")
        configurations[key] = _frozen(array)
    return configurations


def _coulomb(value: object, where: str) -> tuple[float, float]:
    """Coulomb friction (Tc+, Tc-): two finite real numbers with Tc+ >= 0 >= Tc-."""
    coulomb = real_array(value, "Coulomb friction Tc", where)
    if coulomb.shape != (2,):
        raise ModelError(f"{where}: Coulomb friction must be two finite numbers (Tc+, Tc-), got shape {coulomb.shape}")
    if coulomb[0] < 0 or coulomb[1] > 0:
        raise ModelError(
            f"{where}: Coulomb friction must be Tc+ >= 0 (positive velocity) and Tc- <= 0 "
            f"(negative velocity), got {tuple(coulomb.tolist())}"
        )
    return float(coulomb[0]), float(coulomb[1])


def _stribeck(value: object, where: str) -> tuple[float, float]:
    """Stribeck friction (Fs, vs): two finite real numbers, Fs >= 0, and vs > 0 when Fs > 0."""
    stribeck = real_array(value, "Stribeck friction (Fs, vs)", where)
    if stribeck.shape != (2,):
        raise ModelError(f"{where}: Stribeck friction must be two finite numbers (Fs, vs), got shape {stribeck.shape}")
    force, speed = float(stribeck[0]), float(stribeck[1])
    if force < 0:
        raise ModelError(f"{where}: Stribeck friction must have Fs >= 0 (its breakaway torque), got Fs = {force:g}")
    if force > 0 and not speed > 0:
        raise ModelError(f"{where}: Stribeck friction with Fs > 0 must have vs > 0 (its velocity), got vs = {speed:g}")
    return force, speed


def _sigmoid(value: object, where: str) -> tuple[float, float, float]:
    """Sigmoid friction (A, alpha, shift): three finite real numbers with A >= 0 and alpha >= 0."""
    sigmoid = real_array(value, "sigmoid friction (A, alpha, shift)", where)
    if sigmoid.shape != (3,):
        raise ModelError(
            f"{where}: sigmoid friction must be three finite numbers (A, alpha, shift), got shape {sigmoid.shape}"
        )
    amplitude, steepness, shift = (float(x) for x in sigmoid)
    if amplitude < 0 or steepness < 0:
        raise ModelError(
            f"{where}: sigmoid friction must have A >= 0 and alpha >= 0 (dissipative), got A = {amplitude:g}, "
            f"alpha = {steepness:g}"
        )
    return amplitude, steepness, shift


def _limits(value: object, where: str) -> tuple[float, float]:
    """Joint limits (lower, upper): two real numbers, lower <= upper, an infinite one meaning none."""
    bounds = real_array(value, "joint limits", where, bounds=True)
    if bounds.shape != (2,):
        raise ModelError(f"{where}: joint limits must be two numbers (lower, upper), got shape {bounds.shape}")
    lower, upper = float(bounds[0]), float(bounds[1])
    if lower > upper or lower == np.inf or upper == -np.inf:  # (inf, inf) would hold the joint nowhere
        raise ModelError(
            f"{where}: joint limits must satisfy lower <= upper (lower below +inf, upper above -inf), "
            f"got ({lower:g}, {upper:g})"
        )
    return lower, upper


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


def _ancestor_table(parents: np.ndarray) -> np.ndarray:
    table = np.eye(len(parents), dtype=bool)
    for i, parent in enumerate(parents):
        if parent >= 0:
            table[i] |= table[parent]
    return table


def _motion(joint: Joint, value: float) -> np.ndarray:
    """The joint's 4x4 motion at ``value``: a rotation about its axis (Rodrigues) or a translation along it."""
    motion = np.eye(4)
    if joint.is_revolute:
        x, y, z = joint.axis
        k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        motion[:3, :3] = np.eye(3) + np.sin(value) * k + (1.0 - np.cos(value)) * (k @ k)
    else:
        motion[:3, 3] = value * joint.axis
    return motion
