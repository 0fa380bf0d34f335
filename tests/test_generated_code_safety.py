"""Generated code that no model can write into, and that compiles under -Wall -Wextra -Werror: a robot name or a
parameter name becomes an escaped comment or an identifier in the C and Python of generate_code and of the closed
form; a C prefix that is no identifier, ``functions=None`` and a closed form with NaN or infinity are ModelErrors."""

from __future__ import annotations

import ctypes
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import sympy

import armdyn as ad
from armdyn.errors import ArgumentError, ModelError
from armdyn.symbolic import derive, generate_code
from armdyn.symbolic.codegen import comment_text, identifiers

HOSTILE = "evil */ int injected(void) { return 42; } /* \n#define cos sin\n\u2028"
COMPILER = shutil.which("cc") or shutil.which("gcc")
STRICT = ["-O1", "-std=c99", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC"]


def _strict_c(source: str, folder: Path, name: str = "arm") -> ctypes.CDLL:
    """The source compiled with the system compiler under -Wall -Wextra -Werror (a failure shows its message)."""
    if COMPILER is None:
        pytest.skip("no C compiler (cc or gcc) on this machine: the generated C cannot be compiled here")
    (folder / f"{name}.c").write_text(source, encoding="utf-8")
    run = subprocess.run([COMPILER, *STRICT, "-o", str(folder / f"{name}.so"), str(folder / f"{name}.c"), "-lm"],
                         capture_output=True, text=True)  # fmt: skip
    assert run.returncode == 0, run.stderr
    return ctypes.CDLL(str(folder / f"{name}.so"))


def _link(name: str, kind: str, axis: list[float], parent: int, origin: list[float]) -> ad.Link:
    placement = np.eye(4)
    placement[:3, 3] = origin
    inertial = ad.Inertial(1.5, [0.1, 0.05, -0.02], np.diag([0.02, 0.03, 0.04]), name)
    return ad.Link(name, ad.Joint(kind, placement, axis, np.eye(4), name), inertial, parent=parent, viscous=0.1,
                   coulomb=(0.2, -0.1), motor_inertia=1e-4, gear_ratio=20.0)  # fmt: skip


def one_joint() -> ad.Robot:
    return ad.Robot([_link("j1", "revolute", [0, 0, 1], -1, [0, 0, 0])], name="one_joint", gravity=[0, -9.81, 0])


def prismatic_only() -> ad.Robot:
    links = [_link("x", "prismatic", [1, 0, 0], -1, [0, 0, 0]), _link("y", "prismatic", [0, 1, 0], 0, [0.1, 0, 0]),
             _link("z", "prismatic", [0, 0, 1], 1, [0, 0.1, 0])]  # fmt: skip
    return ad.Robot(links, name="gantry", gravity=[0, 0, -9.81])


ARMS = {name: (lambda name=name: ad.models.load(name)) for name in ad.models.names()}
ARMS.update({"one_joint": one_joint, "prismatic_only": prismatic_only})
REFERENCE = {
    "tau": lambda arm, q, qd, qdd: arm.inverse_dynamics(q, qd, qdd),
    "M": lambda arm, q, qd, qdd: arm.inertia_matrix(q),
    "G": lambda arm, q, qd, qdd: arm.gravity_vector(q),
    "N": lambda arm, q, qd, qdd: arm.nonlinear_terms(q, qd),
    "Vm": lambda arm, q, qd, qdd: arm.coriolis_matrix(q, qd),
}


@pytest.mark.parametrize("name", sorted(ARMS))
def test_generated_c_compiles_under_wextra_werror_and_equals_the_kernels(name: str, tmp_path: Path) -> None:
    """Every built-in arm, a one-joint arm and a prismatic-only arm (whose functions leave q or qd unread):
    the C of every function compiles with -Wall -Wextra -Werror and equals the compiled kernels (1e-12)."""
    arm = ARMS[name]()
    code = generate_code(arm, ("tau", "M", "G", "N", "Vm"))
    library = _strict_c(code.c(), tmp_path)
    pointer = ctypes.POINTER(ctypes.c_double)
    rng = np.random.default_rng(arm.n)
    q, qd, qdd = rng.uniform(-1.2, 1.2, (3, arm.n))
    given = {"q": q, "qd": qd, "qdd": qdd}
    for function, generated in code.functions.items():
        expected = np.asarray(REFERENCE[function](arm, q, qd, qdd)).ravel()
        out = np.zeros(expected.size)
        args = [np.ascontiguousarray(given[a]).ctypes.data_as(pointer) for a in generated.arguments]
        getattr(library, f"armdyn_{function}")(*args, out.ctypes.data_as(pointer))
        assert np.abs(out - expected).max() <= 1e-12 * max(1.0, np.abs(expected).max()), function


@pytest.mark.parametrize("build", [one_joint, prismatic_only, lambda: ad.models.two_link_planar(symbolic=True)])
def test_closed_form_c_compiles_under_wextra_werror(build, tmp_path: Path) -> None:
    """The closed form's C (unused states and parameters included) compiles under -Wall -Wextra -Werror."""
    _strict_c(derive(build()).to_c(), tmp_path)


def test_a_robot_name_cannot_write_code_into_the_generated_c(tmp_path: Path) -> None:
    """A robot named with "*/", "/*" and newlines (as a URDF can name it) stays inside its comment: the C compiles
    under -Wall -Wextra -Werror, defines no function of the name's text, and the comment shows the name escaped."""
    links = list(ad.models.two_link_planar().links)
    arm = ad.Robot(links, name=HOSTILE, gravity=[0, -9.8, 0])
    source = generate_code(arm, ("tau", "Wb")).c()
    library = _strict_c(source, tmp_path)
    assert not hasattr(library, "injected")
    assert not any(line.lstrip().startswith("#define") for line in source.splitlines())
    assert source.count("*/") == source.count("/*")
    first = source.splitlines()[0]
    assert first == f"/* {comment_text(HOSTILE)}: the robot equation, generated by armdyn */"
    assert "\\n#define cos sin\\n\\u2028" in first
    tau = np.zeros(2)
    pointer = ctypes.POINTER(ctypes.c_double)
    q, qd, qdd = np.array([0.3, -0.4]), np.array([0.5, 0.2]), np.array([-1.0, 0.7])
    library.armdyn_tau(*(x.ctypes.data_as(pointer) for x in (q, qd, qdd)), tau.ctypes.data_as(pointer))
    np.testing.assert_allclose(tau, arm.inverse_dynamics(q, qd, qdd), rtol=1e-12)


def test_a_urdf_robot_name_cannot_write_code(tmp_path: Path) -> None:
    """The same through load_urdf: the name read from <robot name="..."> is a comment of the C."""
    urdf = tmp_path / "hostile.urdf"
    urdf.write_text(
        '<robot name="x */ int injected(void) { return 1; } /* y">'
        '<link name="base"/><link name="l1"><inertial><mass value="1"/><origin xyz="0.5 0 0"/>'
        '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>'
        '<limit lower="-3" upper="3" effort="10" velocity="1"/></joint></robot>',
        encoding="utf-8",
    )
    arm = ad.load_urdf(urdf)
    assert "*/ int injected" in arm.name
    library = _strict_c(generate_code(arm).c(), tmp_path)
    assert not hasattr(library, "injected")


def test_parameter_names_become_identifiers_in_the_closed_forms_code(tmp_path: Path) -> None:
    """A symbolic parameter named with code in it is an argument under an identifier in the C and the Python (its
    name in an escaped comment); the Python runs and gives the closed form's value (the numeric arm's torques)."""
    hostile = sympy.Symbol("m*/x\nimport os; os.remove('/')")
    closed = derive(ad.models.two_link_planar(m1=hostile))
    renamed = identifiers([hostile.name])[hostile.name]
    assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", renamed)
    python = closed.to_python()
    assert "import os" not in python.replace(comment_text(repr(hostile.name)), "")
    namespace: dict = {}
    exec(compile(python, "<closed form>", "exec"), namespace)
    q, qd, qdd = np.array([0.3, -0.4]), np.array([0.5, 0.2]), np.array([-1.0, 0.7])
    tau = namespace["tau"](q, qd, qdd, np.zeros(2), 1.7)
    np.testing.assert_allclose(tau, ad.models.two_link_planar(m1=1.7).inverse_dynamics(q, qd, qdd), rtol=1e-12)
    c = closed.to_c()
    assert f"double {renamed})" in c
    _strict_c(c, tmp_path)


def test_identifiers_are_unique_and_keep_plain_names() -> None:
    names = ["m1", "a*b", "a_b", "if", "q", "1x", "int", "é"]
    chosen = identifiers(names)
    assert chosen["m1"] == "m1" and chosen["a_b"] == "a_b"
    assert len(set(chosen.values())) == len(names)
    assert all(re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", x) for x in chosen.values())
    assert {chosen["if"], chosen["q"], chosen["int"]}.isdisjoint({"if", "q", "int"})


@pytest.mark.parametrize("prefix", ["1x", "a-b", "a b", "armdyn_*/", "é", "x;"])
def test_a_c_prefix_that_is_no_identifier_is_refused(prefix: str) -> None:
    code = generate_code(ad.models.two_link_planar(), ["G"])
    with pytest.raises(ModelError, match="prefix must be"):
        code.c(prefix)
    with pytest.raises(ArgumentError):
        code.c(None)  # type: ignore[arg-type]
    assert "void my_G(" in code.c("my_") and "void G(" in code.c("")


@pytest.mark.parametrize("functions", [None, 5, [None], [["tau"]], []])
def test_functions_that_are_no_names_are_refused(functions: object) -> None:
    with pytest.raises(ModelError, match="functions must be some of"):
        generate_code(ad.models.two_link_planar(), functions)  # type: ignore[arg-type]


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, "heavy", True])
def test_compiling_a_closed_form_with_a_value_that_is_not_finite_is_a_model_error(value: object) -> None:
    """NaN, infinity, text or a bool as a parameter's value: a ModelError naming it (not Numba's TypingError);
    the same closed form with finite values compiles and equals the numeric arm."""
    closed = derive(ad.models.two_link_planar(symbolic=True))
    values = {"a1": 1.0, "a2": 0.8, "g": 9.8, "m1": 2.0, "m2": 1.0}
    with pytest.raises(ModelError, match="values\\['m1'\\]"):
        closed.compile({**values, "m1": value})
    with pytest.raises(ArgumentError):
        closed.compile([("m1", 2.0)])  # type: ignore[arg-type]
    q = np.array([0.3, -0.4])
    numeric = ad.models.two_link_planar(m1=2.0, m2=1.0, a1=1.0, a2=0.8, g=9.8)
    np.testing.assert_allclose(closed.compile(values).M(q), numeric.inertia_matrix(q), rtol=1e-12)


@pytest.mark.parametrize("route", [["--method", "newton-euler"], ["--no-symbolic"]])
def test_derive_c_writes_a_header_of_declarations_and_a_source_of_prefixed_definitions(
    tmp_path: Path, route: list[str]
) -> None:
    """Before, `derive --code c` gave bare globals M, Vm, G and tau and save("x.h") wrote definitions: two
    files including it failed to link. Now: x.h declares, x.c defines armdyn_-prefixed functions; two
    translation units including the header link into one program whose tau equals the kernels'."""
    from tests.helpers import invoke

    if COMPILER is None:
        pytest.skip("no C compiler (cc or gcc) on this machine: the generated C cannot be compiled here")
    written = invoke("derive", "two_link_planar", "--code", "c", *route, "-o", tmp_path / "arm.c")
    assert written.exit_code == 0, written.output
    header = (tmp_path / "arm.h").read_text()
    assert "#ifndef ARMDYN_" in header and "void armdyn_tau(" in header and "{" not in header
    assert (tmp_path / "arm.c").read_text().startswith('#include "arm.h"')
    main = tmp_path / "main.c"
    main.write_text(
        '#include <stdio.h>\n#include "arm.h"\nvoid other(void);\nint main(void) {\n'
        "    double q[2] = {0.3, -0.4}, qd[2] = {0.2, 0.1}, qdd[2] = {-0.5, 0.7}, tau[2];\n"
        '    armdyn_tau(q, qd, qdd, tau);\n    other();\n    printf("%.17g %.17g\\n", tau[0], tau[1]);\n'
        "    return 0;\n}\n"
    )
    (tmp_path / "other.c").write_text('#include "arm.h"\nvoid other(void) {}\n')
    program = tmp_path / "program"
    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror"]
    sources = [str(tmp_path / name) for name in ("main.c", "other.c", "arm.c")]
    subprocess.run([COMPILER, *flags, "-o", str(program), *sources, "-lm"], check=True, cwd=tmp_path)
    printed = np.array(subprocess.run([str(program)], check=True, capture_output=True, text=True).stdout.split(),
                       dtype=float)  # fmt: skip
    arm = ad.models.two_link_planar()
    expected = arm.inverse_dynamics([0.3, -0.4], [0.2, 0.1], [-0.5, 0.7])
    np.testing.assert_allclose(printed, expected, rtol=1e-12, atol=1e-12)


def test_a_closed_forms_header_and_source_agree_and_save_writes_each(tmp_path: Path) -> None:
    form = derive(ad.models.two_link_planar(symbolic=True))
    header, source = form.to_c_header("rr_"), form.to_c("rr_")
    declared = re.findall(r"void (rr_\w+)\(", header)
    defined = re.findall(r"void (rr_\w+)\(", source)
    assert declared == defined == ["rr_M", "rr_Vm", "rr_G", "rr_tau"]
    assert form.save(tmp_path / "rr.h").read_text() == form.to_c_header()
    assert form.save(tmp_path / "rr.c").read_text() == form.to_c()
    with pytest.raises(ModelError, match="prefix must be empty or start a C identifier"):
        form.to_c_header("1x")
