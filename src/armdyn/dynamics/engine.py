"""The public dynamics calls of one Robot: input handling around the compiled kernels.

A one-state call (1-D float64 arrays) goes straight to a Numba kernel that checks shapes
and finiteness itself and reports a status code; anything else (lists, other dtypes,
leading batch dimensions) takes the general path, which converts, broadcasts and runs
one parallel batch kernel over all states.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from armdyn.dynamics import kernels as K
from armdyn.dynamics.compiled import compile_robot
from armdyn.errors import ModelError
from armdyn.model.robot import Robot


def _writable(array: np.ndarray) -> np.ndarray:
    """A C-contiguous float64 array the kernels' signatures accept (copied only when needed)."""
    return np.require(array, dtype=np.float64, requirements=["C", "W"])


class Engine:
    """The dynamics of one Robot, compiled once (Robot methods dispatch here)."""

    PUBLIC = (
        "inverse_dynamics",
        "forward_dynamics",
        "inertia_matrix",
        "inertia_matrix_dot",
        "coriolis_matrix",
        "coriolis_vector",
        "gravity_vector",
        "friction",
        "nonlinear_terms",
        "kinetic_energy",
        "potential_energy",
    )

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.n = robot.n
        self.model = compile_robot(robot)
        self._no_wrench = np.zeros((1, 6))

    # ----- errors and the general path --------------------------------------------------------
    def _raise(self, status: int, names: tuple[str, ...], out_shape: tuple[int, ...]) -> None:
        """A kernel's status code as a ModelError: which argument, and what was expected."""
        code = status % 10
        name = names[code - 1] if code <= len(names) else {4: "out", 5: "f_ext"}[code]
        if status > 10:
            raise ModelError(f"{name} must be finite (it holds NaN or infinity) for '{self.robot.name}'")
        expected = {"out": out_shape, "f_ext": (6,)}.get(name, (self.n,))
        raise ModelError(f"{name} must have shape {expected} for '{self.robot.name}' (n = {self.n})")

    def _states(self, names: tuple[str, ...], *values: object) -> tuple[tuple[int, ...], list[np.ndarray]]:
        """Convert, check and broadcast state arguments to (B, n) C arrays; return the batch shape."""
        arrays = []
        for name, value in zip(names, values, strict=False):
            try:
                array = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise ModelError(f"{name} must be an array of numbers of shape (..., {self.n})") from None
            if array.ndim == 0 or array.shape[-1] != self.n:
                raise ModelError(f"{name} must have shape (..., {self.n}) for '{self.robot.name}', got {array.shape}")
            if not np.all(np.isfinite(array)):
                raise ModelError(f"{name} must be finite (it holds NaN or infinity)")
            arrays.append(array)
        try:
            batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
        except ValueError:
            shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(names, arrays, strict=False))
            raise ModelError(f"the batch shapes of {shapes} do not broadcast together") from None
        flat = [_writable(np.broadcast_to(a, (*batch, self.n))).reshape(-1, self.n) for a in arrays]
        return batch, flat

    def _batched(
        self,
        kernel: Callable[..., None],
        names: tuple[str, ...],
        values: tuple[object, ...],
        trailing: tuple[int, ...],
        out: np.ndarray | None,
    ) -> np.ndarray:
        batch, flat = self._states(names, *values)
        result = self._result(out, (*batch, *trailing))
        target = result.reshape(-1, *trailing)
        if target.shape[0]:
            kernel(self.model, *flat, target)
        return result

    # ----- the robot equation ------------------------------------------------------------------
    def inverse_dynamics(
        self, q: object, qd: object, qdd: object, f_ext: object = None, out: np.ndarray | None = None
    ) -> np.ndarray:
        """tau = M(q) qdd + Vm(q, qd) qd + F(qd) + G(q), plus J^T f_ext for a wrench f_ext = [force; moment]
        that the tool exerts on its surroundings (tool frame, about the tool point). RNEA, O(n)."""
        if f_ext is None:
            result = np.empty(self.n) if out is None else out
            try:
                status = K.rnea_one(self.model, q, qd, qdd, K.INVERSE_DYNAMICS, result)
            except TypeError:
                return self._rnea_general((q, qd, qdd), K.INVERSE_DYNAMICS, None, out)
            if status:
                self._raise(status, ("q", "qd", "qdd"), (self.n,))
            return result
        return self._rnea_general((q, qd, qdd), K.INVERSE_DYNAMICS | K.WITH_WRENCH, f_ext, out)

    def _rnea_general(self, values: tuple, flags: int, f_ext: object, out: np.ndarray | None) -> np.ndarray:
        names = ("q", "qd", "qdd")[: len(values)]
        batch, flat = self._states(names, *values)
        while len(flat) < 3:
            flat.append(flat[0])
        wrench = self._no_wrench
        if f_ext is not None:
            wrench = np.asarray(f_ext, dtype=float)
            if wrench.ndim == 0 or wrench.shape[-1] != 6 or not np.all(np.isfinite(wrench)):
                raise ModelError(f"f_ext must be a finite wrench [f; moment] of shape (..., 6), got {wrench.shape}")
            try:
                wrench_batch = np.broadcast_shapes(wrench.shape[:-1], batch)
            except ValueError:
                raise ModelError(f"f_ext batch shape {wrench.shape[:-1]} does not match the states' {batch}") from None
            if wrench_batch != batch:
                raise ModelError(f"f_ext batch shape {wrench.shape[:-1]} does not match the states' {batch}")
            wrench = _writable(np.broadcast_to(wrench, (*batch, 6))).reshape(-1, 6)
        result = self._result(out, (*batch, self.n))
        target = result.reshape(-1, self.n)
        if target.shape[0]:
            K.rnea_batch(self.model, flat[0], flat[1], flat[2], wrench, flags, target)
        return result

    def _result(self, out: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
        if out is None:
            return np.empty(shape)
        if not (
            isinstance(out, np.ndarray)
            and out.shape == shape
            and out.dtype == np.float64
            and out.flags.c_contiguous
            and out.flags.writeable
        ):
            got = getattr(out, "shape", type(out).__name__)
            raise ModelError(f"out must be a writable C-contiguous float64 array of shape {shape}, got {got}")
        return out

    def _rnea_part(self, flags: int, q: object, qd: object, out: np.ndarray | None) -> np.ndarray:
        result = np.empty(self.n) if out is None else out
        try:
            status = K.rnea_one(self.model, q, qd, qd, flags, result)
        except TypeError:
            values = (q,) if qd is q else (q, qd)
            return self._rnea_general(values, flags, None, out)
        if status:
            self._raise(status, ("q", "qd", "qdd"), (self.n,))
        return result

    def gravity_vector(self, q: object, out: np.ndarray | None = None) -> np.ndarray:
        """G(q) = dP/dq (3.2.43), by RNEA with gravity alone."""
        return self._rnea_part(K.GRAVITY_ONLY, q, q, out)

    def coriolis_vector(self, q: object, qd: object, out: np.ndarray | None = None) -> np.ndarray:
        """V(q, qd) = Vm(q, qd) qd, by RNEA with velocities alone."""
        return self._rnea_part(K.CORIOLIS, q, qd, out)

    def nonlinear_terms(self, q: object, qd: object, out: np.ndarray | None = None) -> np.ndarray:
        """N(q, qd) = Vm qd + F(qd) + G(q) (3.3.4, without disturbance)."""
        return self._rnea_part(K.NONLINEAR, q, qd, out)

    def friction(self, qd: object, out: np.ndarray | None = None) -> np.ndarray:
        """F(qd) = Fv qd + Fd(qd) (3.3.2): joint-side viscous plus Coulomb (Tc+ or Tc-), 0 at rest."""
        return self._rnea_part(K.WITH_FRICTION, qd, qd, out)

    def inertia_matrix(self, q: object, out: np.ndarray | None = None) -> np.ndarray:
        """M(q) by the composite-rigid-body algorithm, reflected motor inertia on the diagonal."""
        result = np.empty((self.n, self.n)) if out is None else out
        try:
            status = K.crba_one(self.model, q, result)
        except TypeError:
            return self._batched(K.crba_batch, ("q",), (q,), (self.n, self.n), out)
        if status:
            self._raise(status, ("q",), (self.n, self.n))
        return result

    def coriolis_matrix(self, q: object, qd: object, out: np.ndarray | None = None) -> np.ndarray:
        """The Christoffel Vm(q, qd) (3.3.48): Mdot - 2 Vm is skew and Vm(q, x) y = Vm(q, y) x."""
        result = np.empty((self.n, self.n)) if out is None else out
        try:
            status = K.coriolis_one(self.model, q, qd, result)
        except TypeError:
            return self._batched(K.coriolis_batch, ("q", "qd"), (q, qd), (self.n, self.n), out)
        if status:
            self._raise(status, ("q", "qd"), (self.n, self.n))
        return result

    def inertia_matrix_dot(self, q: object, qd: object) -> np.ndarray:
        """Mdot(q, qd) = Vm + Vm^T, exact for the Christoffel Vm (Mdot - 2 Vm skew)."""
        Vm = self.coriolis_matrix(q, qd)
        return Vm + np.swapaxes(Vm, -1, -2)

    def forward_dynamics(self, q: object, qd: object, tau: object, out: np.ndarray | None = None) -> np.ndarray:
        """qdd = M^-1 (tau - N(q, qd)) by the articulated-body algorithm, O(n)."""
        result = np.empty(self.n) if out is None else out
        try:
            status = K.aba_one(self.model, q, qd, tau, result)
        except TypeError:
            return self._batched(K.aba_batch, ("q", "qd", "tau"), (q, qd, tau), (self.n,), out)
        if status:
            self._raise(status, ("q", "qd", "tau"), (self.n,))
        return result

    def _energies(self, q: object, qd: object) -> np.ndarray:
        values = np.empty(2)
        try:
            status = K.energy_one(self.model, q, qd, values)
        except TypeError:
            return self._batched(K.energy_batch, ("q", "qd"), (q, qd), (2,), None)
        if status:
            self._raise(status, ("q", "qd"), (2,))
        return values

    def kinetic_energy(self, q: object, qd: object) -> float | np.ndarray:
        """K = 1/2 qd^T M(q) qd (3.2.29), from the link velocities."""
        values = self._energies(q, qd)
        return float(values[0]) if values.ndim == 1 else values[..., 0]

    def potential_energy(self, q: object) -> float | np.ndarray:
        """P(q) = -sum_i m_i g^T p_ci (3.2.35); zero at the arm's zero configuration is not implied."""
        values = self._energies(q, q)
        return float(values[1]) if values.ndim == 1 else values[..., 1]
