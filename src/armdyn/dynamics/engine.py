"""The public dynamics calls of one Robot: input handling around the compiled kernels.

A one-state call (1-D C-contiguous float64 arrays) goes straight to a Numba kernel that
checks shapes and finiteness itself and reports a status code; the kernel signatures
are explicit, so any other input (lists, other dtypes, leading batch dimensions) fails
the type match and takes the general path, which converts, checks, broadcasts and runs
one parallel batch kernel over all states. The fast paths are closures over the compiled
model, installed on the Robot instance, so a control loop pays one Python call.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from armdyn.dynamics import kernels as K
from armdyn.dynamics import vectorized as V
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
        self.inverse_dynamics = self._inverse_dynamics()
        vector, matrix = (self.n,), (self.n, self.n)
        self.gravity_vector = self._fast(K.gravity_one, ("q",), vector, self._rnea_batch(K.GRAVITY_ONLY, ("q",)))
        self.coriolis_vector = self._fast(
            K.coriolis_vector_one, ("q", "qd"), vector, self._rnea_batch(K.CORIOLIS, ("q", "qd"))
        )
        self.nonlinear_terms = self._fast(
            K.nonlinear_one, ("q", "qd"), vector, self._rnea_batch(K.NONLINEAR, ("q", "qd"))
        )
        self.friction = self._fast(K.friction_one, ("qd",), vector, self._batch(K.friction_batch, ("qd",), vector))
        self.inertia_matrix = self._fast(K.crba_one, ("q",), matrix, self._batch(K.crba_batch, ("q",), matrix))
        self.coriolis_matrix = self._fast(
            K.coriolis_one, ("q", "qd"), matrix, self._batch(K.coriolis_batch, ("q", "qd"), matrix)
        )
        self.forward_dynamics = self._fast(
            K.aba_one, ("q", "qd", "tau"), vector, self._batch(K.aba_batch, ("q", "qd", "tau"), vector)
        )
        self._energies = self._fast(K.energy_one, ("q", "qd"), (2,), self._batch(K.energy_batch, ("q", "qd"), (2,)))

    # ----- building the calls -------------------------------------------------------------------
    def _fast(
        self, kernel: Callable[..., int], names: tuple[str, ...], shape: tuple[int, ...], general: Callable
    ) -> Callable:
        """A call that tries the one-state kernel first and falls back to the general path."""
        model, empty, fail, ndarray = self.model, np.empty, self._raise, np.ndarray

        if len(names) == 1:

            def call(a: object, out: np.ndarray | None = None) -> np.ndarray:
                if a.__class__ is not ndarray or a.ndim != 1:
                    return general((a,), out)
                result = empty(shape) if out is None else out
                try:
                    status = kernel(model, a, result)
                except TypeError:  # another argument is not a 1-D float64 array
                    return general((a,), out)
                if status:
                    fail(status, names, shape)
                return result

        elif len(names) == 2:

            def call(a: object, b: object, out: np.ndarray | None = None) -> np.ndarray:
                if a.__class__ is not ndarray or a.ndim != 1:
                    return general((a, b), out)
                result = empty(shape) if out is None else out
                try:
                    status = kernel(model, a, b, result)
                except TypeError:  # another argument is not a 1-D float64 array
                    return general((a, b), out)
                if status:
                    fail(status, names, shape)
                return result

        else:

            def call(a: object, b: object, c: object, out: np.ndarray | None = None) -> np.ndarray:
                if a.__class__ is not ndarray or a.ndim != 1:
                    return general((a, b, c), out)
                result = empty(shape) if out is None else out
                try:
                    status = kernel(model, a, b, c, result)
                except TypeError:  # another argument is not a 1-D float64 array
                    return general((a, b, c), out)
                if status:
                    fail(status, names, shape)
                return result

        return call

    def _inverse_dynamics(self) -> Callable:
        model, empty, n, fail, kernel, ndarray = self.model, np.empty, self.n, self._raise, K.rnea_one, np.ndarray
        general = self._rnea_batch(K.INVERSE_DYNAMICS, ("q", "qd", "qdd"))

        def inverse_dynamics(
            q: object, qd: object, qdd: object, f_ext: object = None, out: np.ndarray | None = None
        ) -> np.ndarray:
            if f_ext is None and q.__class__ is ndarray and q.ndim == 1:
                result = empty(n) if out is None else out
                try:
                    status = kernel(model, q, qd, qdd, result)
                except TypeError:
                    return general((q, qd, qdd), out)
                if status:
                    fail(status, ("q", "qd", "qdd"), (n,))
                return result
            return general((q, qd, qdd), out, f_ext)

        return inverse_dynamics

    def _raise(self, status: int, names: tuple[str, ...], out_shape: tuple[int, ...]) -> None:
        """A kernel's status code as a ModelError: which argument, and what was expected."""
        code = status % 10
        name = names[code - 1] if code <= len(names) else {4: "out", 5: "f_ext"}[code]
        if status > 10:
            raise ModelError(f"{name} must be finite (it holds NaN or infinity) for '{self.robot.name}'")
        expected = {"out": out_shape, "f_ext": (6,)}.get(name, (self.n,))
        raise ModelError(f"{name} must have shape {expected} for '{self.robot.name}' (n = {self.n})")

    # ----- the general path ----------------------------------------------------------------------
    def _states(self, names: tuple[str, ...], values: tuple[object, ...]) -> tuple[tuple[int, ...], list[np.ndarray]]:
        """Convert, check and broadcast state arguments to (B, n) C arrays; return the batch shape."""
        arrays = []
        for name, value in zip(names, values, strict=True):
            try:
                array = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise ModelError(f"{name} must be an array of numbers of shape (..., {self.n})") from None
            if array.ndim == 0 or array.shape[-1] != self.n:
                raise ModelError(f"{name} must have shape (..., {self.n}) for '{self.robot.name}', got {array.shape}")
            if array.size and not (np.isfinite(array.min()) and np.isfinite(array.max())):  # NaN propagates
                raise ModelError(f"{name} must be finite (it holds NaN or infinity)")
            arrays.append(array)
        try:
            batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
        except ValueError:
            shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(names, arrays, strict=True))
            raise ModelError(f"the batch shapes of {shapes} do not broadcast together") from None
        shape = (*batch, self.n)
        flat = [_writable(a if a.shape == shape else np.broadcast_to(a, shape)).reshape(-1, self.n) for a in arrays]
        return batch, flat

    @staticmethod
    def _result(out: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
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

    def _batch(self, kernel: Callable[..., None], names: tuple[str, ...], trailing: tuple[int, ...]) -> Callable:
        def general(values: tuple[object, ...], out: np.ndarray | None) -> np.ndarray:
            batch, flat = self._states(names, values)
            result = self._result(out, (*batch, *trailing))
            target = result.reshape(-1, *trailing)
            if target.shape[0]:
                kernel(self.model, *flat, target)
            return result

        return general

    def _rnea_batch(self, flags: int, names: tuple[str, ...]) -> Callable:
        no_wrench = np.zeros((1, 6))

        def general(values: tuple[object, ...], out: np.ndarray | None, f_ext: object = None) -> np.ndarray:
            batch, flat = self._states(names, values)
            while len(flat) < 3:
                flat.append(flat[-1])
            wrench, mode = no_wrench, flags
            if f_ext is not None:
                wrench, mode = self._wrenches(f_ext, batch), flags | K.WITH_WRENCH
            result = self._result(out, (*batch, self.n))
            target = result.reshape(-1, self.n)
            if not target.shape[0]:
                return result
            if f_ext is None:  # vectorized across states
                V.rnea_blocks(self.model, flat[0], flat[1], flat[2], mode, target)
            else:
                K.rnea_batch(self.model, flat[0], flat[1], flat[2], wrench, mode, target)
            return result

        return general

    @staticmethod
    def _wrenches(f_ext: object, batch: tuple[int, ...]) -> np.ndarray:
        wrench = np.asarray(f_ext, dtype=float)
        if wrench.ndim == 0 or wrench.shape[-1] != 6 or not np.all(np.isfinite(wrench)):
            raise ModelError(f"f_ext must be a finite wrench [force; moment] of shape (..., 6), got {wrench.shape}")
        if wrench.ndim > 1 and wrench.shape[:-1] != batch:
            raise ModelError(f"f_ext batch shape {wrench.shape[:-1]} does not match the states' {batch}")
        return _writable(np.broadcast_to(wrench, (*batch, 6))).reshape(-1, 6)

    # ----- derived quantities --------------------------------------------------------------------
    def inertia_matrix_dot(self, q: object, qd: object) -> np.ndarray:
        """Mdot(q, qd) = Vm + Vm^T, exact for the Christoffel Vm (Mdot - 2 Vm skew)."""
        Vm = self.coriolis_matrix(q, qd)
        return Vm + np.swapaxes(Vm, -1, -2)

    def kinetic_energy(self, q: object, qd: object) -> float | np.ndarray:
        """K = 1/2 qd^T M(q) qd (3.2.29), from the link velocities."""
        values = self._energies(q, qd)
        return float(values[0]) if values.ndim == 1 else values[..., 0]

    def potential_energy(self, q: object) -> float | np.ndarray:
        """P(q) = -sum_i m_i g^T p_ci (3.2.35)."""
        values = self._energies(q, q)
        return float(values[1]) if values.ndim == 1 else values[..., 1]
