"""The generated robot equation as CasADi expressions and as JAX functions, for optimal control.

``generate_code(arm, functions, backend="casadi")`` and ``backend="jax"`` take the straight-line code that
the customized Newton-Euler tracer writes (Khalil and Kleinfinger, "Minimum operations and minimum parameters
of the dynamic models of tree structure robots", IEEE J. Robotics and Automation 3(6), 1987; the module
armdyn.symbolic.newton_euler) and build the value of each of its live nodes, once and in order, with the
backend's operations: ``casadi.SX`` scalars, or ``jax.numpy`` arrays (one scalar of each state, or a batch).
Nothing is re-derived: every function is the traced tau, M, G, N, Vm or base regressor W_b node for node,
and each backend's own automatic differentiation gives their Jacobians.

Two functions exist only here:

- "qdd", the forward dynamics qdd = M(q)^-1 (tau - N(q, qd)) (Section 3.4), from M and N traced into one
  graph (their rotations shared) and Featherstone's sparse L^T D L factorization of M, which follows the
  parent array of the tree and so creates no fill-in (Rigid Body Dynamics Algorithms, 2008, 6.5); the
  factorization and its two triangular solves are written out in the backend's scalars: n^3/6 multiply-adds
  for a chain, fewer for a tree, and one division per joint. CasADi keeps it or its own ``casadi.solve``
  on the same M, whichever has fewer instructions (``CasadiCode.qdd_counts``: the L^T D L solve, by a
  fifth to two fifths fewer on the arms measured); the articulated-body recursion is not traced (it
  divides, which the tracer does not record).
- "step", one step of the classical fourth-order Runge-Kutta method of the state equation
  xd = [qd; qdd(q, qd, tau)], x = [q; qd], tau held over the step, as ``armdyn.simulate`` integrates it
  (Lewis, Dawson and Abdallah 2004, Chapter 4). Its Coulomb friction is smoothed as simulate smooths it
  (armdyn.dynamics.friction.smooth_coulomb): Fd_i = tanh(qd_i / eps_i) Tc+_i for qd_i >= 0 and
  -tanh(qd_i / eps_i) Tc-_i for qd_i < 0, with ``coulomb_smoothing="auto"`` (the default) eps_i =
  max(1e-3 rad/s, max(|Tc+_i|, |Tc-_i|) dt / M_ii(q)), simulate's rule, evaluated at the step's start
  (simulate evaluates it once, at the run's start); a number sets every eps_i, and 0 is the exact law.

Elsewhere (tau, N, "qdd") the Coulomb law is exact, as in the Python backend: Tc+ for qd > 0, Tc- for qd < 0,
0 at rest, written ``Tc sign(qd)`` where Tc- = -Tc+ and with the backend's if-else (``casadi.if_else``,
``jax.numpy.where``) otherwise.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from armdyn import inputs
from armdyn.dynamics.friction import refuse_nonlinear_friction
from armdyn.dynamics.regressor import BaseParameters, base_parameters
from armdyn.errors import MissingDependencyError, ModelError
from armdyn.robot import Robot
from armdyn.symbolic.codegen import c_prefix
from armdyn.symbolic.newton_euler import (
    ARGUMENTS,
    FUNCTIONS,
    GeneratedCode,
    GeneratedFunction,
    Graph,
    Trace,
    bodies,
    composite_inertia_matrix,
    generate,
    newton_euler,
)

BACKENDS = ("python", "casadi", "jax")
DYNAMICS_ARGUMENTS = {"qdd": ("q", "qd", "tau"), "step": ("x", "tau", "dt")}  # the functions only these backends make
SMOOTHING_FLOOR = 1e-3  # simulate's smallest automatic eps (rad/s or m/s)
JIT_OPTIONS = {"xla_disable_hlo_passes": "fusion"}
"""``jax.jit(code.tau, compiler_options=JIT_OPTIONS)``: XLA's CPU loop fusion of a large scalar graph can recompute
shared subexpressions (the 7-joint Panda's jitted tau over 100,000 states: 9.4 s fused, 0.33 s unfused; its M
and qdd take about as long either way); without fusion each node is one vectorized operation over the batch."""


@dataclass(frozen=True)
class Operations:
    """A backend's scalar functions; + - * / are its numbers' own operators.

    Parameters
    ----------
    sin, cos, tanh, sign : callable
        Elementwise functions.
    where : callable
        ``where(condition, a, b)``: a where the condition holds, b elsewhere.
    maximum : callable
        The elementwise larger of two values.
    """

    sin: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    tanh: Callable[[Any], Any]
    sign: Callable[[Any], Any]
    where: Callable[[Any, Any, Any], Any]
    maximum: Callable[[Any, Any], Any]


def evaluate(function: GeneratedFunction, values: Mapping[str, Any], ops: Operations) -> list[Any]:
    """The outputs of a traced function, each live node built once, in order, from its operands.

    Parameters
    ----------
    function : GeneratedFunction
        Traced code (armdyn.symbolic.newton_euler).
    values : mapping of str to scalar
        The inputs by the names of the trace ("q[0]", "qd[1]", ...).
    ops : Operations
        The backend's functions.

    Returns
    -------
    list
        The outputs, flat (a matrix row by row); a constant output stays a float.

    Raises
    ------
    KeyError
        When an input of the trace is missing from ``values``.
    """
    nodes = function.graph.nodes
    value: dict[int, Any] = {}
    for index in function.order:
        op, a, b = nodes[index]
        if op == "in":
            result = values[a]
        elif op == "+":
            result = value[a] + value[b]
        elif op == "-":
            result = value[a] - value[b]
        elif op == "*":
            result = value[a] * value[b]
        elif op == "*k":
            result = value[a] * b
        elif op == "+k":
            result = value[a] + b
        elif op == "neg":
            result = -value[a]
        elif op == "sin":
            result = ops.sin(value[a])
        elif op == "cos":
            result = ops.cos(value[a])
        else:
            result = exact_coulomb(value[a], b, ops)
        value[index] = result
    return [value[x.index] if isinstance(x, Trace) else float(x) for x in function.outputs]


def exact_coulomb(rate: Any, levels: tuple[float, float], ops: Operations) -> Any:
    """Fd = Tc+ for qd > 0, Tc- for qd < 0, 0 at rest (friction.coulomb_torque): Tc+ sign(qd) when Tc- = -Tc+.

    Parameters
    ----------
    rate : scalar
        The joint velocity qd.
    levels : tuple of float
        (Tc+, Tc-), joint side.
    ops : Operations
        The backend's functions.

    Returns
    -------
    scalar
        The Coulomb torque.
    """
    plus, minus = levels
    if plus == -minus:
        return plus * ops.sign(rate)
    return ops.where(rate > 0.0, plus, ops.where(rate < 0.0, minus, 0.0))


def smooth_coulomb_law(rate: Any, levels: tuple[float, float], eps: Any, ops: Operations) -> Any:
    """simulate's smoothed Coulomb law: tanh(qd / eps) Tc+ for qd >= 0, -tanh(qd / eps) Tc- for qd < 0
    (friction.smooth_coulomb).

    Parameters
    ----------
    rate : scalar
        The joint velocity qd.
    levels : tuple of float
        (Tc+, Tc-), joint side.
    eps : scalar
        The smoothing velocity, > 0.
    ops : Operations
        The backend's functions.

    Returns
    -------
    scalar
        The smoothed Coulomb torque.
    """
    plus, minus = levels
    smooth = ops.tanh(rate / eps)
    if plus == -minus:
        return plus * smooth
    return ops.where(rate >= 0.0, plus, -minus) * smooth


def _times(x: Any, y: Any) -> Any:
    """x y, or the float 0 when either is the float 0 (a structural zero stays one)."""
    if (isinstance(x, float) and x == 0.0) or (isinstance(y, float) and y == 0.0):
        return 0.0
    return x * y


def _minus(x: Any, y: Any) -> Any:
    """x - y, x itself when y is the float 0."""
    return x if isinstance(y, float) and y == 0.0 else x - y


def ltdl_solve(H: list[list[Any]], b: list[Any], parents: Sequence[int]) -> tuple[list[Any], list[Any]]:
    """x with H x = b for a joint-space inertia matrix of a tree, by its sparse factorization H = L^T D L
    (Featherstone 2008, 6.5, Tables 6.3 and 6.4): L unit lower triangular with the sparsity of the parent
    array, no fill-in; then L^T y = b, z = D^-1 y and L x = z. The entries can be any backend's scalars;
    a float 0 is a structural zero and costs nothing.

    Parameters
    ----------
    H : list of lists
        The n x n matrix by rows (overwritten by L and D).
    b : list
        The right-hand side, n.
    parents : sequence of int
        Each joint's parent (-1 for the base), each before its children.

    Returns
    -------
    tuple of lists
        (x, D): the solution and the pivots D (the diagonal of D).
    """
    n = len(b)
    inverse: list[Any] = [0.0] * n
    for k in range(n - 1, -1, -1):
        inverse[k] = 1.0 / H[k][k]
        i = parents[k]
        while i >= 0:
            a = _times(H[k][i], inverse[k])
            j = i
            while j >= 0:
                H[i][j] = _minus(H[i][j], _times(a, H[k][j]))
                j = parents[j]
            H[k][i] = a
            i = parents[i]
    x = list(b)
    for i in range(n - 1, -1, -1):
        j = parents[i]
        while j >= 0:
            x[j] = _minus(x[j], _times(H[i][j], x[i]))
            j = parents[j]
    x = [x[i] * inverse[i] for i in range(n)]
    for i in range(n):
        j = parents[i]
        while j >= 0:
            x[i] = _minus(x[i], _times(H[i][j], x[j]))
            j = parents[j]
    return x, [H[i][i] for i in range(n)]


def runge_kutta_step(rate: Callable[[Any], Any], x: Any, dt: Any) -> Any:
    """One step of the classical fourth-order Runge-Kutta method of xd = rate(x) (simulate's RK4).

    Parameters
    ----------
    rate : callable
        x -> xd, on the backend's vectors.
    x : vector
        The state at the step's start.
    dt : scalar
        The step.

    Returns
    -------
    vector
        The state after the step.
    """
    k1 = rate(x)
    k2 = rate(x + 0.5 * dt * k1)
    k3 = rate(x + 0.5 * dt * k2)
    k4 = rate(x + dt * k3)
    return x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


@dataclass(frozen=True)
class Dynamics:
    """M and N traced into one graph for the forward dynamics, with what the step's friction needs.

    Parameters
    ----------
    function : GeneratedFunction
        Outputs M (n x n, by rows) then N (n).
    n : int
        The joints.
    parents : tuple of int
        Each joint's parent (-1 for the base).
    coulomb : tuple of tuple
        (Tc+, Tc-) per joint, joint side.
    exact : bool
        Whether N includes the exact Coulomb law (else the caller adds a smoothed one).
    """

    function: GeneratedFunction
    n: int
    parents: tuple[int, ...]
    coulomb: tuple[tuple[float, float], ...]
    exact: bool


def trace_dynamics(packed: np.ndarray, exact: bool) -> Dynamics:
    """M (composite-rigid-body algorithm) and N = Vm qd + F + G (Newton-Euler with qdd = 0) in one graph,
    N with the exact Coulomb law or without any (viscous friction kept).

    Parameters
    ----------
    packed : numpy.ndarray
        The arm's packed model (``Robot.packed``).
    exact : bool
        Whether N includes the exact Coulomb law.

    Returns
    -------
    Dynamics
        The traced function and the tree.
    """
    arm = bodies(packed)
    n = len(arm)
    graph = Graph()
    M = composite_inertia_matrix(graph, packed)
    N = newton_euler(graph, packed, True, False, True, exact)
    if not exact:
        N = [N[i] + arm[i].viscous * graph.input(f"qd[{i}]") for i in range(n)]
    function = GeneratedFunction("dynamics", ("q", "qd"), graph, list(M) + list(N), (n * n + n,))
    return Dynamics(function, n, tuple(b.parent for b in arm), tuple(b.coulomb for b in arm), exact)


def accelerations(dynamics: Dynamics, q: Sequence[Any], qd: Sequence[Any], tau: Sequence[Any], ops: Operations,
                  eps: Sequence[Any] | Callable[[list[Any]], Sequence[Any]] | None = None,
                  ) -> tuple[list[Any], Sequence[Any] | None]:  # fmt: skip
    """qdd = M^-1 (tau - N - Fd) by ``ltdl_solve``, Fd the smoothed Coulomb law of ``eps`` (when N has none).

    Parameters
    ----------
    dynamics : Dynamics
        The traced M and N.
    q, qd, tau : sequence of scalars
        The state and the torque, n each.
    ops : Operations
        The backend's functions.
    eps : sequence, callable or None
        The smoothing velocities per joint, or a function of M's diagonal giving them, or None for the exact
        Coulomb law (N's own, or added here when N has none).

    Returns
    -------
    tuple
        (qdd, eps): the accelerations and the smoothing velocities used.
    """
    n = dynamics.n
    values = {f"q[{i}]": q[i] for i in range(n)} | {f"qd[{i}]": qd[i] for i in range(n)}
    outputs = evaluate(dynamics.function, values, ops)
    H = [outputs[n * r : n * r + n] for r in range(n)]
    N = outputs[n * n :]
    if callable(eps):
        eps = eps([H[i][i] for i in range(n)])
    rhs = [tau[i] - N[i] for i in range(n)]
    if not dynamics.exact:
        for i, levels in enumerate(dynamics.coulomb):
            if levels != (0.0, 0.0):
                law = (
                    exact_coulomb(qd[i], levels, ops) if eps is None else smooth_coulomb_law(qd[i], levels, eps[i], ops)
                )
                rhs[i] = rhs[i] - law
    return ltdl_solve(H, rhs, dynamics.parents)[0], eps


def smoothing_rule(dynamics: Dynamics, smoothing: str | float, dt: Any, ops: Operations
                   ) -> Sequence[Any] | Callable[[list[Any]], Sequence[Any]] | None:  # fmt: skip
    """The step's eps per joint: simulate's "auto" rule max(1e-3, max|Tc| dt / M_ii) as a function of M's
    diagonal at the step's start, one number for every joint, or None (0: the exact law).

    Parameters
    ----------
    dynamics : Dynamics
        The traced M and N (without Coulomb friction).
    smoothing : str or float
        "auto" or eps >= 0.
    dt : scalar
        The step.
    ops : Operations
        The backend's functions.

    Returns
    -------
    sequence, callable or None
        As ``accelerations`` takes it.
    """
    if smoothing == "auto":
        largest = [max(abs(plus), abs(minus)) for plus, minus in dynamics.coulomb]

        def rule(diagonal: list[Any]) -> list[Any]:
            return [ops.maximum(SMOOTHING_FLOOR, largest[i] * dt / diagonal[i]) if largest[i] > 0 else 1.0
                    for i in range(dynamics.n)]  # fmt: skip

        return rule
    if smoothing == 0.0:
        return None
    return [float(smoothing)] * dynamics.n


def smoothing_choice(value: object) -> str | float:
    """coulomb_smoothing as "auto" or a float >= 0.

    Parameters
    ----------
    value : object
        What was given.

    Returns
    -------
    str or float
        "auto" or the number.

    Raises
    ------
    armdyn.ModelError
        When it is neither "auto" nor a finite number >= 0.
    """
    if isinstance(value, str):
        if value != "auto":
            raise ModelError(f"coulomb_smoothing must be 'auto' or a number >= 0, got {value!r}")
        return value
    return inputs.number(value, "coulomb_smoothing", minimum=0.0)


def _traced(packed: np.ndarray, names: Sequence[str], columns: Sequence[int]) -> dict[str, GeneratedFunction]:
    """The traced functions of the Python backend among ``names``."""
    return {name: generate(packed, name, columns) for name in names if name not in DYNAMICS_ARGUMENTS}


# ----- CasADi ---------------------------------------------------------------------------------------------------


def _import_casadi() -> Any:
    try:
        import casadi
    except ImportError:
        raise MissingDependencyError("casadi", "casadi", needed_by="generate_code(backend='casadi')") from None
    return casadi


class CasadiCode:
    """The robot equation of one numeric arm as ``casadi.Function`` s of SX straight-line code:
    ``tau(q, qd, qdd)``, ``M(q)``, ``G(q)``, ``N(q, qd)``, ``Vm(q, qd)``, ``Wb(q, qd, qdd)``,
    ``qdd(q, qd, tau)`` (forward dynamics) and ``step(x, tau, dt)`` (one RK4 step, x = [q; qd]), those
    asked for, each an attribute and in ``functions``; their Jacobians are CasADi's
    (``Function.jacobian()``, ``casadi.jacobian``).

    Make one with ``armdyn.symbolic.generate_code(arm, functions, backend="casadi")``. With "qdd",
    ``qdd_counts`` holds the instruction counts of the two forward dynamics compared ({"ltdl": ...,
    "solve": ...}) and ``qdd_method`` the one built.

    Parameters
    ----------
    robot : Robot
        The numeric arm.
    names : sequence of str
        The functions to build (checked by generate_code).
    base : BaseParameters, optional
        The base parameters of "Wb" (W_b ``base.phi`` = tau), None without it.
    coulomb_smoothing : str or float, optional
        The step's eps: "auto" (simulate's rule at the step's start) or a number (0: exact law).

    Raises
    ------
    armdyn.MissingDependencyError
        When CasADi is not installed (``pip install 'armdyn[casadi]'``).
    """

    def __init__(self, robot: Robot, names: Sequence[str], base: BaseParameters | None = None,
                 coulomb_smoothing: str | float = "auto") -> None:  # fmt: skip
        casadi = _import_casadi()
        self.robot = robot
        self.base = base
        self.coulomb_smoothing = coulomb_smoothing
        packed = robot.packed
        assert packed is not None  # checked by generate_code
        n = robot.n
        ops = Operations(casadi.sin, casadi.cos, casadi.tanh, casadi.sign, casadi.if_else, casadi.fmax)
        symbols = {name: casadi.SX.sym(name, n) for name in ("q", "qd", "qdd", "tau")}
        values = {f"{name}[{i}]": symbols[name][i] for name in ("q", "qd", "qdd") for i in range(n)}
        self.expressions: dict[str, tuple[list[Any], list[str], Any, str]] = {}  # name: inputs, names, output, name
        columns = [] if base is None else [int(c) for c in base.columns]
        for name, function in _traced(packed, names, columns).items():
            outputs = evaluate(function, values, ops)
            rows, cols = function.shape if len(function.shape) == 2 else (function.shape[0], 1)
            matrix = casadi.reshape(casadi.vertcat(*[casadi.SX(x) for x in outputs]), cols, rows).T
            self.expressions[name] = ([symbols[a] for a in function.arguments], list(function.arguments), matrix, name)
        if "qdd" in names:
            dynamics = trace_dynamics(packed, exact=True)
            q, qd, tau = symbols["q"], symbols["qd"], symbols["tau"]
            qdd, _ = accelerations(dynamics, _split(q, n), _split(qd, n), _split(tau, n), ops)
            M, N = _casadi_matrices(casadi, dynamics, q, qd, ops)
            by_solve = casadi.solve(M, tau - N)  # CasADi's generic symbolic solve, for comparison
            candidates = {"ltdl": casadi.vertcat(*qdd), "solve": by_solve}
            self.qdd_counts = {kind: int(casadi.Function("qdd", [q, qd, tau], [value]).n_instructions())
                               for kind, value in candidates.items()}  # fmt: skip
            self.qdd_method = min(self.qdd_counts, key=lambda kind: self.qdd_counts[kind])
            self.expressions["qdd"] = ([q, qd, tau], ["q", "qd", "tau"], candidates[self.qdd_method], "qdd")
        if "step" in names:
            dynamics = trace_dynamics(packed, exact=False)
            x, tau, dt = casadi.SX.sym("x", 2 * n), symbols["tau"], casadi.SX.sym("dt")
            rule = smoothing_rule(dynamics, coulomb_smoothing, dt, ops)
            eps: list[Any] = []

            def rate(state: Any) -> Any:
                qdd, used = accelerations(dynamics, _split(state[:n], n), _split(state[n:], n), _split(tau, n), ops,
                                          eps[0] if eps else rule)  # fmt: skip
                eps.append(used)  # the first stage's eps serves the whole step
                return casadi.vertcat(state[n:], *qdd)

            self.expressions["step"] = ([x, tau, dt], ["x", "tau", "dt"], runge_kutta_step(rate, x, dt), "x_next")
        self.functions: dict[str, Any] = {name: self._function(name, name) for name in names}

    def _function(self, name: str, label: str) -> Any:
        """The casadi.Function of one of the expressions, named ``label``."""
        casadi = _import_casadi()
        arguments, argument_names, output, output_name = self.expressions[name]
        return casadi.Function(label, arguments, [output], argument_names, [output_name])

    def __getattr__(self, name: str) -> Any:
        functions = self.__dict__.get("functions", {})
        if name in functions:
            return functions[name]
        raise AttributeError(f"this code has no {name}: generate it with functions including '{name}'")

    def __repr__(self) -> str:
        return f"CasadiCode('{self.robot.name}', n={self.robot.n}, functions={tuple(self.functions)})"

    def instruction_counts(self) -> dict[str, int]:
        """What each function costs in CasADi's virtual machine.

        Returns
        -------
        dict of str to int
            ``Function.n_instructions()`` per function (inputs, constants and outputs included).
        """
        return {name: int(f.n_instructions()) for name, f in self.functions.items()}

    def c(self, prefix: str = "armdyn_") -> str:
        """C source of every function by ``casadi.CodeGenerator``, with CasADi's calling convention
        (``int armdyn_tau(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w,
        int mem)`` and its ``_work``, ``_n_in`` ... companions).

        Parameters
        ----------
        prefix : str, optional
            Put before each function's name (default "armdyn_"): empty or the start of a C identifier.

        Returns
        -------
        str
            The source, one translation unit (C99).

        Raises
        ------
        armdyn.ModelError
            When ``prefix`` is not empty or the start of a C identifier.
        """
        prefix = c_prefix(prefix)
        casadi = _import_casadi()
        generator = casadi.CodeGenerator("armdyn", {"with_header": False})
        for name in self.functions:
            generator.add(self._function(name, prefix + name))
        return str(generator.dump())


def _casadi_matrices(casadi: Any, dynamics: Dynamics, q: Any, qd: Any, ops: Operations) -> tuple[Any, Any]:
    """M and N of the traced dynamics as SX (n x n and n x 1)."""
    n = dynamics.n
    values = {f"q[{i}]": q[i] for i in range(n)} | {f"qd[{i}]": qd[i] for i in range(n)}
    outputs = [casadi.SX(x) for x in evaluate(dynamics.function, values, ops)]
    return casadi.reshape(casadi.vertcat(*outputs[: n * n]), n, n).T, casadi.vertcat(*outputs[n * n :])


def _split(vector: Any, n: int) -> list[Any]:
    """The n entries of a CasADi column."""
    return [vector[i] for i in range(n)]


# ----- JAX ------------------------------------------------------------------------------------------------------


def _import_jax() -> Any:
    try:
        import jax
    except ImportError:
        raise MissingDependencyError("jax", "jax", needed_by="generate_code(backend='jax')") from None
    return jax


class JaxCode:
    """The robot equation of one numeric arm as pure ``jax.numpy`` functions in float64, which ``jax.jit``,
    ``jax.vmap``, ``jax.grad`` and ``jax.jacfwd`` take: ``tau(q, qd, qdd)``, ``M(q)``, ``G(q)``, ``N(q, qd)``,
    ``Vm(q, qd)``, ``Wb(q, qd, qdd)``, ``qdd(q, qd, tau)`` and ``step(x, tau, dt)``, those asked for, each an
    attribute and in ``functions``; each takes one state (n,) or a batch (..., n).

    Make one with ``armdyn.symbolic.generate_code(arm, functions, backend="jax")``. Making one turns on JAX's
    float64 (``jax.config.update("jax_enable_x64", True)``). Under ``jax.jit`` on the CPU, pass
    ``compiler_options=JIT_OPTIONS`` (this module's) for large batches: XLA's fusion of a graph of thousands
    of scalar operations can recompute shared ones (the Panda's tau: 28 times slower fused than unfused).

    Parameters
    ----------
    robot : Robot
        The numeric arm.
    names : sequence of str
        The functions to build (checked by generate_code).
    base : BaseParameters, optional
        The base parameters of "Wb", None without it.
    coulomb_smoothing : str or float, optional
        The step's eps: "auto" (simulate's rule at the step's start) or a number (0: exact law).

    Raises
    ------
    armdyn.MissingDependencyError
        When JAX is not installed (``pip install 'armdyn[jax]'``).
    """

    def __init__(self, robot: Robot, names: Sequence[str], base: BaseParameters | None = None,
                 coulomb_smoothing: str | float = "auto") -> None:  # fmt: skip
        jax = _import_jax()
        jax.config.update("jax_enable_x64", True)
        import jax.numpy as jnp

        self.robot = robot
        self.base = base
        self.coulomb_smoothing = coulomb_smoothing
        packed = robot.packed
        assert packed is not None  # checked by generate_code
        n = robot.n
        ops = Operations(jnp.sin, jnp.cos, jnp.tanh, jnp.sign, jnp.where, jnp.maximum)
        columns = [] if base is None else [int(c) for c in base.columns]
        self.functions: dict[str, Callable[..., Any]] = {}
        for name, function in _traced(packed, names, columns).items():
            self.functions[name] = _jax_function(jnp, function, ops, n)
        if "qdd" in names:
            self.functions["qdd"] = _jax_forward_dynamics(jnp, trace_dynamics(packed, exact=True), ops)
        if "step" in names:
            self.functions["step"] = _jax_step(jnp, trace_dynamics(packed, exact=False), ops, coulomb_smoothing)
        self.functions = {name: self.functions[name] for name in names}

    def __getattr__(self, name: str) -> Any:
        functions = self.__dict__.get("functions", {})
        if name in functions:
            return functions[name]
        raise AttributeError(f"this code has no {name}: generate it with functions including '{name}'")

    def __repr__(self) -> str:
        return f"JaxCode('{self.robot.name}', n={self.robot.n}, functions={tuple(self.functions)})"


def _columns(jnp: Any, arrays: Sequence[Any], n: int) -> tuple[list[list[Any]], tuple[int, ...]]:
    """Each argument's n entries (arrays of the batch's shape) and the batch's shape."""
    arrays = [jnp.asarray(a, dtype=jnp.float64) for a in arrays]
    batch = tuple(np.broadcast_shapes(*[a.shape[:-1] for a in arrays]))
    return [[a[..., i] for i in range(n)] for a in arrays], batch


def _stacked(jnp: Any, values: Sequence[Any], batch: tuple[int, ...], shape: tuple[int, ...]) -> Any:
    """The scalars (arrays or floats) as one array (*batch, *shape)."""
    full = [jnp.broadcast_to(jnp.asarray(v, dtype=jnp.float64), batch) for v in values]
    return jnp.stack(full, axis=-1).reshape(batch + shape)


def _jax_function(jnp: Any, function: GeneratedFunction, ops: Operations, n: int) -> Callable[..., Any]:
    """One traced function as a function of jax arrays."""
    arguments = function.arguments

    def traced(*states: Any) -> Any:
        entries, batch = _columns(jnp, states, n)
        values = {f"{a}[{i}]": entries[k][i] for k, a in enumerate(arguments) for i in range(n)}
        return _stacked(jnp, evaluate(function, values, ops), batch, function.shape)

    traced.__name__ = traced.__qualname__ = function.name
    traced.__doc__ = (
        f"{function.name}({', '.join(arguments)}) of armdyn's generated code, for jax arrays (n,) or (..., n)."
    )
    return traced


def _jax_forward_dynamics(jnp: Any, dynamics: Dynamics, ops: Operations) -> Callable[..., Any]:
    """qdd(q, qd, tau) = M^-1 (tau - N) by the sparse L^T D L solve, on jax arrays."""
    n = dynamics.n

    def qdd(q: Any, qd: Any, tau: Any) -> Any:
        (q_, qd_, tau_), batch = _columns(jnp, (q, qd, tau), n)
        return _stacked(jnp, accelerations(dynamics, q_, qd_, tau_, ops)[0], batch, (n,))

    qdd.__doc__ = "qdd(q, qd, tau): the forward dynamics M^-1 (tau - N), for jax arrays (n,) or (..., n)."
    return qdd


def _jax_step(jnp: Any, dynamics: Dynamics, ops: Operations, smoothing: str | float) -> Callable[..., Any]:
    """step(x, tau, dt): one RK4 step of [qd; qdd], the Coulomb law smoothed, on jax arrays."""
    n = dynamics.n

    def step(x: Any, tau: Any, dt: Any) -> Any:
        x = jnp.asarray(x, dtype=jnp.float64)
        (tau_,), batch = _columns(jnp, (tau,), n)
        h = jnp.asarray(dt, dtype=jnp.float64)
        rule = smoothing_rule(dynamics, smoothing, h, ops)
        eps: list[Any] = []

        def rate(state: Any) -> Any:
            q_ = [state[..., i] for i in range(n)]
            qd_ = [state[..., n + i] for i in range(n)]
            qdd, used = accelerations(dynamics, q_, qd_, tau_, ops, eps[0] if eps else rule)
            eps.append(used)  # the first stage's eps serves the whole step
            shape = np.broadcast_shapes(batch, state.shape[:-1])
            return jnp.concatenate([jnp.broadcast_to(state[..., n:], (*shape, n)), _stacked(jnp, qdd, shape, (n,))],
                                   axis=-1)  # fmt: skip

        return runge_kutta_step(rate, x, h[..., None])

    step.__doc__ = "step(x, tau, dt): one RK4 step of x = [q; qd] under tau, for jax arrays (2n,) or (..., 2n)."
    return step


def generate_code(arm: Robot, functions: Sequence[str] = FUNCTIONS, backend: str = "python",
                  coulomb_smoothing: float | str = "auto") -> GeneratedCode | CasadiCode | JaxCode:  # fmt: skip
    """Generated code for the robot equation of a numeric arm, by a customized Newton-Euler recursion
    (Khalil and Kleinfinger 1987; armdyn.symbolic.newton_euler): tau, M, G and N as straight-line code whose
    cost grows linearly with the joints (M: with their number of pairs), printed as Python and C (the
    "python" backend) or built as CasADi or JAX functions (this module's docstring).

    Parameters
    ----------
    arm : Robot
        An arm with numeric parameters (``Robot.packed`` not None).
    functions : sequence of str, optional
        Which of "tau", "M", "G", "N", "Vm" (the Christoffel-consistent Coriolis matrix) and "Wb" (the
        base regressor: W_b(q, qd, qdd) phi_b = tau, with the regrouped base parameters phi_b, friction and
        motor inertia included, in ``GeneratedCode.base``) to generate (default tau, M, G and N); with the
        "casadi" and "jax" backends also "qdd" (forward dynamics, qdd(q, qd, tau)) and "step" (one RK4 step
        of the state x = [q; qd], step(x, tau, dt)).
    backend : str, optional
        "python" (default: source for Python, C and Numba), "casadi" (``casadi.Function`` s of SX, with
        CasADi's derivatives and C code generator) or "jax" (pure ``jax.numpy`` functions in float64);
        see armdyn.symbolic.backends.
    coulomb_smoothing : float or "auto", optional
        "step" only: eps of the smoothed Coulomb law, as ``simulate``'s (default "auto": its rule
        max(1e-3, max|Tc| dt / M_ii), at the step's start); 0 is the exact law.

    Returns
    -------
    GeneratedCode, CasadiCode or JaxCode
        GeneratedCode (python): its ``python()``, ``c()``, ``operation_counts()`` and ``compile()``;
        CasadiCode and JaxCode: the functions as attributes (``.tau``, ``.M`` ...) and in ``.functions``.

    Raises
    ------
    armdyn.ModelError
        When a function name or the backend is unknown, "qdd" or "step" is asked of the python backend,
        ``coulomb_smoothing`` is not "auto" or a number >= 0, or tau, N, "qdd" or "step" is asked of an arm
        with Stribeck or sigmoid friction (the message names the link).
    armdyn.ArgumentError
        When ``arm`` is not a Robot or has symbolic parameters (use derive for closed forms in symbols).
    armdyn.MissingDependencyError
        When the backend's package is not installed (``pip install 'armdyn[casadi]'`` or ``'armdyn[jax]'``).
    """
    inputs.arm_argument(arm, Robot, numeric=True, why=" (use derive for closed forms in symbols)")
    packed = arm.packed
    assert packed is not None  # a numeric arm is packed
    try:
        names = [functions] if isinstance(functions, str) else list(functions)
    except TypeError:
        names = None
    if not isinstance(backend, str) or backend not in BACKENDS:
        raise ModelError(f"backend must be one of {BACKENDS}, got {backend!r}")
    smoothing = smoothing_choice(coulomb_smoothing)
    known = tuple(ARGUMENTS) + (tuple(DYNAMICS_ARGUMENTS) if backend != "python" else ())
    if names is None or not names or any(not isinstance(f, str) or f not in known for f in names):
        dynamics = " ('qdd' and 'step' with backend 'casadi' or 'jax')" if backend == "python" else ""
        raise ModelError(f"functions must be some of {known}{dynamics} (one or more names), got {functions!r}")
    if "tau" in names or "N" in names:
        refuse_nonlinear_friction(arm, "generated code of tau and N")
    if "qdd" in names or "step" in names:
        refuse_nonlinear_friction(arm, "generated code of the forward dynamics")
    base = base_parameters(arm, at_rest=True) if "Wb" in names else None
    if backend == "casadi":
        return CasadiCode(arm, list(dict.fromkeys(names)), base, smoothing)
    if backend == "jax":
        return JaxCode(arm, list(dict.fromkeys(names)), base, smoothing)
    columns = () if base is None else [int(c) for c in base.columns]
    return GeneratedCode(arm, {name: generate(packed, name, columns) for name in names}, base)
