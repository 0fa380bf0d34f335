"""Robot: links in a kinematic tree with gravity, base and tool, friction, motors, limits.

Pure data and validation. The thin methods at the end call the algorithm modules,
imported when first used, so that nothing here depends on an algorithm at import time.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.inertial import Inertial, inertia_from_vector
from armdyn.model.joint import Joint, dh_joint

_NO_LIMITS = (-np.inf, np.inf)


@dataclass(frozen=True, eq=False)
class Link:
    """One joint and the body it moves, with the joint's friction and motor.

    Friction and motor follow the Robotics Toolbox: ``viscous`` (B) and ``coulomb``
    ((Tc+, Tc-), the friction torque for positive and for negative velocity, so Tc- <= 0)
    act on the motor side of a gear of ratio ``gear_ratio`` (G) whose rotor has inertia
    ``motor_inertia`` (Jm). At the joint they appear as G^2 Jm, G^2 B and |G| Tc. With
    the default G = 1 and Jm = 0 the friction values are joint-side values.
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

    def __post_init__(self) -> None:
        where = f"link '{self.name}'"
        if not np.isfinite(self.viscous) or self.viscous < 0:
            raise ModelError(f"{where}: viscous friction must be finite and >= 0 (dissipative), got {self.viscous}")
        coulomb = tuple(float(c) for c in np.asarray(self.coulomb, dtype=float).reshape(-1))
        if len(coulomb) != 2 or not all(np.isfinite(coulomb)):
            raise ModelError(f"{where}: Coulomb friction must be two finite numbers (Tc+, Tc-), got {self.coulomb}")
        if coulomb[0] < 0 or coulomb[1] > 0:
            raise ModelError(
                f"{where}: Coulomb friction must be Tc+ >= 0 (positive velocity) and Tc- <= 0 "
                f"(negative velocity), got {coulomb}"
            )
        if not np.isfinite(self.motor_inertia) or self.motor_inertia < 0:
            raise ModelError(f"{where}: motor inertia Jm must be finite and >= 0, got {self.motor_inertia}")
        if not np.isfinite(self.gear_ratio) or self.gear_ratio == 0:
            raise ModelError(f"{where}: gear ratio G must be finite and non-zero, got {self.gear_ratio}")
        lower, upper = (float(v) for v in self.limits)
        if np.isnan(lower) or np.isnan(upper) or lower > upper:
            raise ModelError(f"{where}: joint limits must satisfy lower <= upper, got {self.limits}")
        object.__setattr__(self, "coulomb", coulomb)
        object.__setattr__(self, "viscous", float(self.viscous))
        object.__setattr__(self, "motor_inertia", float(self.motor_inertia))
        object.__setattr__(self, "gear_ratio", float(self.gear_ratio))
        object.__setattr__(self, "limits", (lower, upper))

    @property
    def kind(self) -> str:
        return self.joint.kind


class Robot:
    """An arm: a kinematic tree of links (parents before children), immutable.

    gravity: acceleration of gravity in the world frame (default [0, 0, -9.81]);
    base: pose of the root in the world; tool: pose of the tool in the frame of link
    ``tool_link`` (default the last link); configurations: named joint vectors.
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
        self._links = tuple(links)
        self.name = name
        self.description = description
        if not self._links:
            raise ModelError(f"robot '{name}': an arm needs at least one joint")
        names = [link.name for link in self._links]
        for index, link in enumerate(self._links):
            if not isinstance(link, Link):
                raise ModelError(f"robot '{name}': item {index} is not a Link")
            if not -1 <= link.parent < index:
                raise ModelError(
                    f"link '{link.name}': parent index {link.parent} must name an earlier link (or -1 for the base)"
                )
            if names.count(link.name) > 1:
                raise ModelError(f"link '{link.name}': joint names must be unique")
        gravity_array = np.array(list(gravity), dtype=object)
        if gravity_array.shape != (3,):
            raise ModelError(f"robot '{name}': gravity must be a 3-vector, got {gravity}")
        if not any(hasattr(g, "free_symbols") for g in gravity_array):
            gravity_array = gravity_array.astype(float)
            if not np.all(np.isfinite(gravity_array)):
                raise ModelError(f"robot '{name}': gravity must be finite")
        self._gravity = _frozen(gravity_array)
        self._base = _frozen(_transform(base, f"robot '{name}': base"))
        self._tool = _frozen(_transform(tool, f"robot '{name}': tool"))
        self._tool_link = self.n - 1 if tool_link is None else int(tool_link)
        if not 0 <= self._tool_link < self.n:
            raise ModelError(f"robot '{name}': tool_link {tool_link} is not a link index (0..{self.n - 1})")
        self._configurations = {}
        for key, value in (configurations or {}).items():
            vector = np.array(value, dtype=float)
            if vector.shape != (self.n,):
                raise ModelError(f"robot '{name}': configuration '{key}' must have {self.n} values, got {vector.shape}")
            self._configurations[key] = _frozen(vector)
        self._dh = dict(dh) if dh else None
        self._cache: dict[str, Any] = {}

    # ----- construction -------------------------------------------------------------
    @classmethod
    def from_dh(
        cls,
        table: Sequence[Mapping[str, Any]],
        convention: str = "standard",
        **robot_options: Any,
    ) -> Robot:
        """An arm from a Denavit-Hartenberg table, one mapping per joint.

        Row keys (all optional): ``kind`` ('R' or 'P', default 'R'), ``a``, ``alpha``,
        ``d``, ``theta`` (for a revolute joint theta is the offset added to q; for a
        prismatic one d is), ``mass``, ``com`` (in the DH link frame), ``inertia``
        (about the c.o.m.: 3 moments, 6 values [Ixx Iyy Izz Ixy Iyz Ixz] or 3x3),
        ``Jm``, ``G``, ``B``, ``Tc`` ((Tc+, Tc-)), ``qlim`` ((lower, upper)), ``name``,
        ``strict`` (triangle-inequality check, default True). ``convention`` is
        'standard' or 'modified'; further keywords go to Robot().
        """
        links = []
        rows = []
        for index, row in enumerate(table):
            known = {"kind", "a", "alpha", "d", "theta", "mass", "com", "inertia", "Jm", "G", "B", "Tc", "qlim", "name"}
            unknown = set(row) - known - {"strict"}
            name = str(row.get("name", f"joint{index + 1}"))
            if unknown:
                raise ModelError(f"link '{name}': unknown DH row keys {sorted(unknown)} (known: {sorted(known)})")
            kind = row.get("kind", "R")
            a, alpha, d, theta = (row.get(key, 0.0) for key in ("a", "alpha", "d", "theta"))
            joint = dh_joint(kind, a, alpha, d, theta, convention, name)
            inertial = Inertial(
                row.get("mass", 0.0),
                row.get("com", np.zeros(3)),
                inertia_from_vector(row.get("inertia", np.zeros(3))),
                name,
                strict=row.get("strict", True),
            )
            links.append(
                Link(
                    name,
                    joint,
                    inertial,
                    parent=index - 1,
                    viscous=row.get("B", 0.0),
                    coulomb=tuple(row.get("Tc", (0.0, 0.0))),
                    motor_inertia=row.get("Jm", 0.0),
                    gear_ratio=row.get("G", 1.0),
                    limits=tuple(row.get("qlim", _NO_LIMITS)),
                )
            )
            rows.append({"kind": joint.kind, "a": a, "alpha": alpha, "d": d, "theta": theta})
        return cls(links, dh={"convention": convention, "rows": rows}, **robot_options)

    def replace(self, links: Sequence[Link] | None = None, **changes: Any) -> Robot:
        """A copy with some links or options changed (the Robot itself never changes)."""
        options = {
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
        return Robot(self._links if links is None else links, **options)

    def with_payload(self, mass: float, com: Iterable[float] = (0.0, 0.0, 0.0), inertia: object = None) -> Robot:
        """The arm carrying a payload rigidly attached to the tool link (added, never overwriting).

        com is in the tool link's frame; inertia is about the payload's own centre of mass.
        """
        tool = self._links[self._tool_link]
        payload = Inertial(mass, com, np.zeros((3, 3)) if inertia is None else inertia, f"{tool.name} payload")
        links = list(self._links)
        links[self._tool_link] = dataclasses.replace(tool, inertial=tool.inertial + payload)
        return self.replace(links)

    def without_friction(self) -> Robot:
        """The same arm with no viscous or Coulomb friction."""
        return self.replace([dataclasses.replace(link, viscous=0.0, coulomb=(0.0, 0.0)) for link in self._links])

    def without_motors(self) -> Robot:
        """The same arm with no motor rotor inertia (friction, if any, is kept at the joint side)."""
        links = [
            dataclasses.replace(
                link,
                viscous=link.gear_ratio**2 * link.viscous,
                coulomb=tuple(abs(link.gear_ratio) * c for c in link.coulomb),
                motor_inertia=0.0,
                gear_ratio=1.0,
            )
            for link in self._links
        ]
        return self.replace(links)

    def with_gravity(self, gravity: Iterable[object]) -> Robot:
        return self.replace(gravity=gravity)

    # ----- structure ----------------------------------------------------------------
    @property
    def links(self) -> tuple[Link, ...]:
        return self._links

    @property
    def n(self) -> int:
        """Number of joints (degrees of freedom)."""
        return len(self._links)

    @property
    def joint_names(self) -> list[str]:
        return [link.name for link in self._links]

    @property
    def kinds(self) -> list[str]:
        return [link.kind for link in self._links]

    @property
    def parents(self) -> np.ndarray:
        return self._cached("parents", lambda: _frozen(np.array([link.parent for link in self._links])))

    @property
    def is_chain(self) -> bool:
        return bool(np.all(self.parents == np.arange(-1, self.n - 1)))

    @property
    def ancestors(self) -> np.ndarray:
        """Boolean (n, n): [i, j] is True when joint j moves link i (j is i or an ancestor)."""

        def build() -> np.ndarray:
            table = np.eye(self.n, dtype=bool)
            for i, parent in enumerate(self.parents):
                if parent >= 0:
                    table[i] |= table[parent]
            return _frozen(table)

        return self._cached("ancestors", build)

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
    def configurations(self) -> dict[str, np.ndarray]:
        return {key: value.copy() for key, value in self._configurations.items()}

    def configuration(self, name: str) -> np.ndarray:
        """A named joint configuration (for the PUMA 560: qz, qr, qs, qn), as a new array."""
        try:
            return self._configurations[name].copy()
        except KeyError:
            raise ModelError(
                f"robot '{self.name}' has no configuration '{name}' (it has {sorted(self._configurations)})"
            ) from None

    def __getattr__(self, name: str) -> np.ndarray:
        configurations = self.__dict__.get("_configurations", {})
        if name in configurations:
            return configurations[name].copy()
        raise AttributeError(f"'Robot' object has no attribute '{name}'")

    def __repr__(self) -> str:
        kinds = "".join("R" if kind == "revolute" else "P" for kind in self.kinds)
        return f"Robot('{self.name}', n={self.n}, joints={kinds})"

    def _cached(self, key: str, build: Any) -> Any:
        if key not in self._cache:
            self._cache[key] = build()
        return self._cache[key]

    # ----- dynamics (armdyn.dynamics.engine: compiled kernels) --------------------------------
    def _engine(self) -> Any:
        """Compile the arm once; its bound engine methods then shadow these wrappers on the instance."""
        engine = self.__dict__.get("_compiled_engine")
        if engine is None:
            from armdyn.dynamics.engine import Engine

            engine = Engine(self)
            self.__dict__["_compiled_engine"] = engine
            for name in Engine.PUBLIC:
                self.__dict__[name] = getattr(engine, name)
        return engine

    def __getstate__(self) -> dict[str, Any]:
        from armdyn.dynamics.engine import Engine

        skip = {"_compiled_engine", *Engine.PUBLIC}
        return {key: value for key, value in self.__dict__.items() if key not in skip}

    def inverse_dynamics(self, q: Any, qd: Any, qdd: Any, f_ext: Any = None, out: Any = None) -> np.ndarray:
        """tau = M(q) qdd + Vm(q, qd) qd + F(qd) + G(q) (RNEA, O(n)), friction and reflected motor
        inertia included; plus J^T f_ext for a wrench f_ext = [force; moment] the tool exerts
        (tool frame, about the tool point)."""
        return self._engine().inverse_dynamics(q, qd, qdd, f_ext, out)

    def forward_dynamics(self, q: Any, qd: Any, tau: Any, out: Any = None) -> np.ndarray:
        """qdd = M(q)^-1 (tau - N(q, qd)) (ABA, O(n))."""
        return self._engine().forward_dynamics(q, qd, tau, out)

    def inertia_matrix(self, q: Any, out: Any = None) -> np.ndarray:
        """M(q), shape (..., n, n) (CRBA), with G^2 Jm on the diagonal."""
        return self._engine().inertia_matrix(q, out)

    def inertia_matrix_dot(self, q: Any, qd: Any) -> np.ndarray:
        """dM/dt = Vm + Vm^T, shape (..., n, n)."""
        return self._engine().inertia_matrix_dot(q, qd)

    def coriolis_matrix(self, q: Any, qd: Any, out: Any = None) -> np.ndarray:
        """The Christoffel form Vm(q, qd) (3.3.48), (..., n, n): Mdot - 2 Vm is skew symmetric."""
        return self._engine().coriolis_matrix(q, qd, out)

    def coriolis_vector(self, q: Any, qd: Any, out: Any = None) -> np.ndarray:
        """V(q, qd) = Vm(q, qd) qd."""
        return self._engine().coriolis_vector(q, qd, out)

    def gravity_vector(self, q: Any, out: Any = None) -> np.ndarray:
        """G(q)."""
        return self._engine().gravity_vector(q, out)

    def friction(self, qd: Any, out: Any = None) -> np.ndarray:
        """F(qd) = Fv qd + Fd(qd), joint side (G^2 B qd and |G| Tc+ or |G| Tc-)."""
        return self._engine().friction(qd, out)

    def nonlinear_terms(self, q: Any, qd: Any, out: Any = None) -> np.ndarray:
        """N(q, qd) = Vm qd + F + G."""
        return self._engine().nonlinear_terms(q, qd, out)

    def kinetic_energy(self, q: Any, qd: Any) -> Any:
        """K = 1/2 qd^T M(q) qd: a float for one state, an array (...) for a batch."""
        return self._engine().kinetic_energy(q, qd)

    def potential_energy(self, q: Any) -> Any:
        """P(q) = -sum m_i g^T p_ci: a float for one state, an array (...) for a batch."""
        return self._engine().potential_energy(q)

    def regressor(self, q: Any, qd: Any, qdd: Any) -> np.ndarray:
        """W(q, qd, qdd), shape (..., n, 14 n), with W @ parameters() = inverse_dynamics (recursive, O(n d))."""
        from armdyn.dynamics import regressor

        return regressor.regressor(self, q, qd, qdd)

    def parameters(self) -> np.ndarray:
        """phi: per link [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] (about the link origin),
        then per joint [Fv, Fc+, Fc-, Ia] (joint-side friction, reflected motor inertia)."""
        from armdyn.dynamics import regressor

        return regressor.parameters(self)

    # ----- kinematics (armdyn.kinematics) ----------------------------------------------
    def link_transforms(self, q: np.ndarray) -> np.ndarray:
        """T_i(q) of every link in the world frame, shape (..., n, 4, 4)."""
        from armdyn import kinematics

        return kinematics.link_transforms(self, q)

    def tool_pose(self, q: np.ndarray) -> np.ndarray:
        """Pose of the tool in the world frame, shape (..., 4, 4)."""
        from armdyn import kinematics

        return kinematics.tool_pose(self, q)

    def jacobian(self, q: np.ndarray, frame: str = "base", link: int | None = None) -> np.ndarray:
        """Geometric Jacobian of the tool (or of a link's frame), (..., 6, n), linear rows first."""
        from armdyn import kinematics

        return kinematics.jacobian(self, q, frame, link)

    def jacobian_dot(self, q: np.ndarray, qd: np.ndarray, frame: str = "base", link: int | None = None) -> np.ndarray:
        """Time derivative of the geometric Jacobian, (..., 6, n)."""
        from armdyn import kinematics

        return kinematics.jacobian_dot(self, q, qd, frame, link)

    def link_transform_derivatives(self, q: np.ndarray) -> np.ndarray:
        """dT_i/dq_j, shape (..., n, n, 4, 4) indexed [i, j] (zero when j does not move i)."""
        from armdyn import kinematics

        return kinematics.link_transform_derivatives(self, q)


def _transform(value: np.ndarray | None, where: str) -> np.ndarray:
    if value is None:
        return np.eye(4)
    array = np.array(value, dtype=float)
    if array.shape != (4, 4) or not np.all(np.isfinite(array)):
        raise ModelError(f"{where} must be a finite 4x4 homogeneous transform, got shape {array.shape}")
    return array


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array
