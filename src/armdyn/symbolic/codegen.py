"""Code generation from the closed form: common-subexpression elimination (SymEngine),
Python and C source, and Numba-compiled functions that take one state or a batch."""

from __future__ import annotations

import keyword
import math
import re
from collections.abc import Callable
from typing import cast

import numba
import numpy as np
import symengine as se
import sympy

from armdyn import inputs
from armdyn.errors import ArgumentError, ModelError
from armdyn.symbolic.derive import Derivation

FUNCTIONS = {  # name -> (state arguments, shape of the result)
    "M": (("q",), "matrix"),
    "Vm": (("q", "qd"), "matrix"),
    "G": (("q",), "vector"),
    "tau": (("q", "qd", "qdd"), "vector"),
}


def _entries(raw: Derivation, name: str) -> list[tuple[tuple[int, ...], se.Basic]]:
    n = len(raw.q)
    if name == "M":
        return [((i, j), raw.M[i][j]) for i in range(n) for j in range(n)]
    if name == "Vm":
        return [((i, j), raw.Vm[i][j]) for i in range(n) for j in range(n)]
    if name == "G":
        return [((i,), x) for i, x in enumerate(raw.G)]
    # tau as M qdd + V + F + G, not expanded: the terms of M, V and G then share subexpressions
    return [
        ((i,), se.Add(*(raw.M[i][j] * raw.qdd[j] for j in range(n)), raw.V[i], raw.F[i], raw.G[i])) for i in range(n)
    ]


def count_operations(expr: se.Basic) -> int:
    """Additions, multiplications, powers (as multiplications) and function calls in an expression."""
    if not expr.args:
        return 0
    own = len(expr.args) - 1 if isinstance(expr, (se.Add, se.Mul)) else 1
    if isinstance(expr, se.Pow) and expr.args[1].is_Integer:
        own = max(abs(int(expr.args[1])) - 1, 1)
    return own + sum(count_operations(a) for a in expr.args)


def _cse(exprs: list[se.Basic]) -> tuple[list[tuple[se.Symbol, se.Basic]], list[se.Basic]]:
    replacements, reduced = se.cse(exprs)
    return list(replacements), list(reduced)


def operation_counts(raw: Derivation, cse: bool) -> dict[str, int]:
    counts = {}
    for name in FUNCTIONS:
        exprs = [x for _, x in _entries(raw, name)]
        if cse:
            replacements, reduced = _cse(exprs)
            exprs = [x for _, x in replacements] + reduced
        counts[name] = sum(count_operations(x) for x in exprs)
    return counts


_C_KEYWORDS = frozenset({
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern", "float",
    "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed", "sizeof",
    "static", "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while", "_Bool", "_Complex",
    "_Imaginary",
})  # fmt: skip
_TAKEN = frozenset({"q", "qd", "qdd", "out", "cos", "sin", "sign", "math", "INFINITY", "NAN", *FUNCTIONS})


def _free(name: str) -> bool:
    """Whether ``name`` is a C and Python identifier that the generated code does not use itself."""
    return (name.isascii() and name.isidentifier() and name not in _TAKEN and name not in _C_KEYWORDS
            and not keyword.iskeyword(name))  # fmt: skip


def identifiers(names: list[str]) -> dict[str, str]:
    """A C and Python identifier for each name, in the same order: the name itself where it is one (ASCII
    letters, digits and underscores, not starting with a digit, no keyword of either language and no name
    the generated code uses itself), else the name with every other character as "_" and "p_" before it
    where needed, made unique with a number. A model's parameter can then never write code."""
    chosen: dict[str, str] = {}
    for name in names:
        candidate = name
        if not _free(name):
            candidate = "".join(c if c.isascii() and (c.isalnum() or c == "_") else "_" for c in name)
            candidate = candidate if _free(candidate) else f"p_{candidate}"
        unique, k = candidate, 2
        while unique in chosen.values() or (unique != name and unique in names):
            unique, k = f"{candidate}_{k}", k + 1
        chosen[name] = unique
    return chosen


def comment_text(text: str) -> str:
    """``text`` safe inside a C block comment and a Python comment: characters that are not printable
    (a newline among them) as escapes, and the comment delimiters "*/" and "/*" broken by a space."""
    shown = "".join(c if c.isprintable() else ascii(c)[1:-1] for c in text)
    while "*/" in shown or "/*" in shown:
        shown = shown.replace("/*", "/ *").replace("*/", "* /")
    return shown


def literal(expr: se.Basic) -> se.Basic:
    """``expr`` with each constant that is not an integer (109/400, sqrt(2)/4, a double) as a
    symbol named by its double's shortest round-trip repr, so Python and C read the exact double;
    a ModelError for a constant that is NaN or infinite (no code computes with it)."""
    if not expr.free_symbols:
        if expr.is_Integer:
            return expr
        value = float(expr)
        if not math.isfinite(value):
            raise ModelError(
                f"the closed form holds {value} (a parameter's value or a term that is not finite): code needs "
                "finite numbers"
            )
        named = se.Symbol(repr(abs(value)))
        return -named if value < 0 else named
    if isinstance(expr, se.Mul):
        constant = [a for a in expr.args if not a.free_symbols]
        rest = [literal(a) for a in expr.args if a.free_symbols]
        return se.Mul(*([literal(se.Mul(*constant))] if constant else []), *rest)
    if not expr.args:
        return expr
    return expr.func(*(literal(a) for a in expr.args))


def _body(
    raw: Derivation,
    name: str,
    line: Callable[[str, str], str],
    value: Callable[[se.Basic], str],
    choose: Callable[[list[tuple[str, str]], str], str],
    renamed: dict[str, str] | None = None,
) -> list[str]:
    """Statements: trigonometric and state variables that the expressions use, the Coulomb laws
    (Tc+ for qd > 0, Tc- for qd < 0, 0 at rest), CSE temporaries, results; the parameters
    ``renamed`` (name -> identifier) under their identifiers."""
    entries = _entries(raw, name)
    if renamed:
        symbols = {se.Symbol(old): se.Symbol(new) for old, new in renamed.items() if old != new}
        entries = [(index, expr.xreplace(symbols)) for index, expr in entries]
    laws: dict[se.Basic, se.Symbol] = {}
    for _, expr in entries:
        for law in sorted(expr.atoms(se.Piecewise), key=str):
            laws.setdefault(law, se.Symbol(f"coulomb{len(laws) + 1}"))
    exprs = [literal(x.subs(laws) if laws else x) for _, x in entries]
    replacements, reduced = _cse(exprs)
    used = set()
    for expr in [x for _, x in replacements] + reduced + list(laws):
        used |= {s.name for s in expr.free_symbols}
    lines = []
    for i, (c, s) in raw.trig.items():
        if c.name in used:
            lines.append(line(c.name, f"cos(q[{i}])"))
        if s.name in used:
            lines.append(line(s.name, f"sin(q[{i}])"))
    for group in (raw.q, raw.qd, raw.qdd):
        for i, symbol in enumerate(group):
            if symbol.name in used:
                array = symbol.name.rstrip("0123456789")
                lines.append(line(symbol.name, f"{array}[{i}]"))
    for law, symbol in laws.items():
        args = law.args
        cases = [(_case_value(args[k], value), value(args[k + 1])) for k in range(0, len(args) - 2, 2)]
        lines.append(line(symbol.name, choose(cases, _case_value(args[-2], value))))
    lines += [line(str(symbol), value(expr)) for symbol, expr in replacements]
    for (index, _), expr in zip(entries, reduced, strict=True):
        target = f"out[{', '.join(map(str, index))}]" if len(index) > 1 else f"out[{index[0]}]"
        lines.append(line(target, value(expr)))
    return lines


def _case_value(expr: se.Basic, value: Callable[[se.Basic], str]) -> str:
    text = value(literal(expr))
    return f"{text}.0" if expr.is_Integer else text


def _python_value(expr: se.Basic) -> str:
    return str(expr)


def _python_choice(cases: list[tuple[str, str]], otherwise: str) -> str:
    text = otherwise
    for result, condition in reversed(cases):
        text = f"({result} if {condition} else {text})"
    return text


def _renamings(renamed: dict[str, str], start: str, end: str) -> list[str]:
    """Comment lines naming each parameter whose identifier is not its own name."""
    return [f"{start}parameter {new} is {comment_text(repr(old))}{end}" for old, new in renamed.items() if old != new]


def python_source(raw: Derivation, parameters: list[str], returns: bool = True) -> str:
    """The four functions as Python source; ``out`` receives the result (and is returned). A parameter
    whose name is no identifier is written as one (``identifiers``), said in a comment."""
    renamed = identifiers(parameters)
    extra = "".join(f", {renamed[p]}" for p in parameters)
    parts = ["from math import cos, sin", "from numpy import sign", *_renamings(renamed, "# ", ""), ""]
    for name, (args, _) in FUNCTIONS.items():
        parts.append(f"def {name}({', '.join(args)}, out{extra}):")
        parts += [f"    {s}" for s in
                  _body(raw, name, lambda t, v: f"{t} = {v}", _python_value, _python_choice, renamed)]  # fmt: skip
        parts += ["    return out" if returns else "    return", "", ""]
    return "\n".join(parts).rstrip() + "\n"


def _unused(arguments: list[str], lines: list[str]) -> list[str]:
    """``(void)x;`` for each argument no line reads, so that the C compiles under -Wall -Wextra -Werror
    (a one-joint arm's G never reads qd, a prismatic-only arm's M never reads q)."""
    read = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", " ".join(lines)))
    return [f"(void){a};" for a in arguments if a not in read]


def c_prefix(prefix: object) -> str:
    """A prefix of generated C function names: empty or the start of a C identifier, else a ModelError (an
    ArgumentError when it is not a string)."""
    if not isinstance(prefix, str):
        raise ArgumentError(f"prefix must be a string, got {type(prefix).__name__}")
    if prefix and not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", prefix):
        raise ModelError(
            f"prefix must be empty or start a C identifier (ASCII letters, digits and underscores, not starting "
            f"with a digit), as the default 'armdyn_', got {prefix!r}"
        )
    return prefix


def header_guard(name: str, prefix: str) -> str:
    """An include guard from an arm's name: PREFIX + the name's letters and digits, upper case, + _H."""
    letters = re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_").upper() or "ARM"
    return f"{prefix.upper()}{letters}_H" if prefix else f"ARMDYN_{letters}_H"


def c_header(declarations: list[str], guard: str, comment: str) -> str:
    """A C header: the declarations between an include guard, under a comment."""
    return (f"/* {comment_text(comment)} */\n#ifndef {guard}\n#define {guard}\n\n" + "\n".join(declarations)
            + f"\n\n#endif /* {guard} */\n")  # fmt: skip


def _c_signature(name: str, parameters: list[str], prefix: str) -> str:
    renamed = identifiers(parameters)
    extra = "".join(f", double {renamed[p]}" for p in parameters)
    signature = ", ".join(f"const double *{a}" for a in FUNCTIONS[name][0])
    return f"void {prefix}{name}({signature}, double *out{extra})"


def c_declarations(parameters: list[str], prefix: str = "armdyn_") -> list[str]:
    """The declarations of c_source's four functions, for a header."""
    return [_c_signature(name, parameters, prefix) + ";" for name in FUNCTIONS]


def c_source(raw: Derivation, parameters: list[str], prefix: str = "armdyn_") -> str:
    """The four functions as C99, named ``prefix`` + M, Vm, G, tau; matrices are row major
    (out[i * n + j]). A parameter whose name is no identifier is written as one (``identifiers``),
    said in a comment."""
    n = len(raw.q)
    renamed = identifiers(parameters)

    def c_line(target: str, value: str) -> str:
        if target.startswith("out["):
            index = target[4:-1].split(", ")
            flat = index[0] if len(index) == 1 else f"{int(index[0]) * n + int(index[1])}"
            return f"out[{flat}] = {value};"
        return f"const double {target} = {value};"

    def c_value(expr: se.Basic) -> str:
        return sympy.ccode(sympy.sympify(expr), standard="c99")

    def c_choice(cases: list[tuple[str, str]], otherwise: str) -> str:
        text = otherwise
        for result, condition in reversed(cases):
            text = f"(({condition}) ? {result} : {text})"
        return text

    parts = ["#include <math.h>", *_renamings(renamed, "/* ", " */"), ""]
    for name, (args, _) in FUNCTIONS.items():
        parts.append(_c_signature(name, parameters, prefix) + " {")
        body = _body(raw, name, c_line, c_value, c_choice, renamed)
        parts += [f"    {s}" for s in _unused([*args, *(renamed[p] for p in parameters)], body) + body]
        parts += ["}", ""]
    return "\n".join(parts)


class CompiledClosedForm:
    """The closed form as Numba functions M(q), Vm(q, qd), G(q), tau(q, qd, qdd): each takes one
    state (n,) or a batch (..., n) and an optional ``out`` array, as the Robot methods do."""

    def __init__(self, n: int, one: dict[str, Callable], batch: dict[str, Callable]) -> None:
        self.n = n
        self._one = one
        self._batch = batch

    def M(self, q: object, out: np.ndarray | None = None) -> np.ndarray:
        """M(q), (..., n, n)."""
        return self._call("M", (q,), out)

    def Vm(self, q: object, qd: object, out: np.ndarray | None = None) -> np.ndarray:
        """Vm(q, qd), (..., n, n)."""
        return self._call("Vm", (q, qd), out)

    def G(self, q: object, out: np.ndarray | None = None) -> np.ndarray:
        """G(q), (..., n)."""
        return self._call("G", (q,), out)

    def tau(self, q: object, qd: object, qdd: object, out: np.ndarray | None = None) -> np.ndarray:
        """tau(q, qd, qdd), (..., n)."""
        return self._call("tau", (q, qd, qdd), out)

    def _call(self, name: str, states: tuple[object, ...], out: np.ndarray | None) -> np.ndarray:
        n = self.n
        trailing = (n, n) if FUNCTIONS[name][1] == "matrix" else (n,)
        one_state = all(s.__class__ is np.ndarray and s.shape == (n,) for s in states)
        if one_state and (out is None or (out.__class__ is np.ndarray and out.shape == trailing)):
            result = np.empty(trailing) if out is None else out
            try:  # the checked entry's signature takes C-contiguous float64 arrays only
                if self._one[name](*states, result) == 0:
                    return result
            except TypeError:
                pass
        batch, flat = inputs.batch_states(FUNCTIONS[name][0], states, n)
        result = inputs.result(out, (*batch, *trailing))
        self._batch[name](*flat, result.reshape(-1, *trailing))
        return result


def batch_loop(one: Callable, arity: int) -> Callable:
    """A parallel loop of ``one(*states, out)`` over the rows of a batch."""
    if arity == 1:

        def loop1(a: np.ndarray, out: np.ndarray) -> None:
            for k in numba.prange(a.shape[0]):
                one(a[k], out[k])

        return numba.njit(parallel=True)(loop1)
    if arity == 2:

        def loop2(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
            for k in numba.prange(a.shape[0]):
                one(a[k], b[k], out[k])

        return numba.njit(parallel=True)(loop2)

    def loop3(a: np.ndarray, b: np.ndarray, c: np.ndarray, out: np.ndarray) -> None:
        for k in numba.prange(a.shape[0]):
            one(a[k], b[k], c[k], out[k])

    return numba.njit(parallel=True)(loop3)


def compile_closed_form(raw: Derivation, values: dict[str, float]) -> CompiledClosedForm:
    """Generate Python with the parameter values as constants, and compile it with Numba."""
    mapping = {se.Symbol(k): v for k, v in values.items()}

    def numeric(x: se.Basic) -> se.Basic:
        return x.subs(mapping)

    substituted = Derivation(
        **{
            **raw.__dict__,
            "M": [[numeric(x) for x in row] for row in raw.M],
            "Vm": [[numeric(x) for x in row] for row in raw.Vm],
            **{name: [numeric(x) for x in getattr(raw, name)] for name in ("G", "tau", "V", "F")},
        }
    )
    try:
        return _compiled(substituted, len(raw.q))
    except RecursionError:  # an expression nested deeper than Python's compiler goes (a 7-joint arm's)
        raise ModelError(
            f"the closed form of this {len(raw.q)}-joint arm is too deep for Python's compiler: "
            "armdyn.symbolic.generate_code(arm).compile() gives tau, M, G, N (and Vm where asked) as lean "
            "straight-line code of the customized Newton-Euler recursion"
        ) from None


def _compiled(substituted: Derivation, n: int) -> CompiledClosedForm:
    namespace: dict[str, object] = {"cos": math.cos, "sin": math.sin, "sign": np.sign}
    exec(compile(python_source(substituted, [], returns=False), "<armdyn closed form>", "exec"), namespace)
    vector, matrix = "float64[::1]", "float64[:, ::1]"
    one: dict[str, Callable[..., int]] = {}
    batch: dict[str, Callable[..., None]] = {}
    for name, (args, kind) in FUNCTIONS.items():
        result = matrix if kind == "matrix" else vector
        signature = f"({', '.join([vector] * len(args))}, {result})"
        generated = cast(Callable[..., None], namespace[name])  # defined by the exec above
        inner = numba.njit("void" + signature, fastmath={"contract"}, error_model="numpy")(generated)
        batch[name] = batch_loop(inner, len(args))
        checked = _checked_source(name, args, kind, n)
        scope = {"inner": inner, "LARGEST": inputs.LARGEST_STATE}
        exec(compile(checked, f"<armdyn closed form {name}, checked>", "exec"), scope)
        one[name] = numba.njit("int64" + signature, error_model="numpy")(cast(Callable[..., int], scope["checked"]))
    return CompiledClosedForm(n, one, batch)


def _checked_source(name: str, args: tuple[str, ...], kind: str, n: int) -> str:
    """A one-state entry that checks lengths, finiteness and magnitude before it calls the
    generated function, and returns a status (0 when computed), as the kernels' entries do."""
    shape = f"out.shape[0] != {n} or out.shape[1] != {n}" if kind == "matrix" else f"out.shape[0] != {n}"
    lines = [f"def checked({', '.join(args)}, out):", f"    if {shape}:", "        return 4"]
    for code, arg in enumerate(args, 1):
        lines += [f"    if {arg}.shape[0] != {n}:", f"        return {code}", f"    for k in range({n}):",
                  f"        if not abs({arg}[k]) < LARGEST:", f"            return {code + 10}"]  # fmt: skip
    lines += [f"    inner({', '.join(args)}, out)", "    return 0"]
    return "\n".join(lines) + "\n"
