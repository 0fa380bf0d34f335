"""The `armdyn` command: the built-in arms, their tables, and (later) the chapter's jobs."""

from __future__ import annotations

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from armdyn.errors import ModelError
from armdyn.model import catalog
from armdyn.model.robot import Robot

app = typer.Typer(help="armdyn: the dynamics of robot manipulators.", no_args_is_help=True, add_completion=False)
console = Console(width=None if Console().is_terminal else 140)


def _number(value: object, digits: int = 4) -> str:
    if hasattr(value, "free_symbols"):
        return str(value)
    value = float(value)
    if np.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.{digits}g}"


def _vector(values: object, digits: int = 4) -> str:
    return "[" + ", ".join(_number(v, digits) for v in np.asarray(values).ravel()) + "]"


def _arm(name: str) -> Robot:
    try:
        return catalog.load(name)
    except ModelError as error:
        console.print(f"[red]error:[/red] {error}")
        raise typer.Exit(2) from None


@app.command()
def models() -> None:
    """List the built-in arms."""
    table = Table(title="Built-in arms")
    for column in ("name", "joints", "DOF", "dynamics", "motors", "friction", "description"):
        table.add_column(column)
    for name in catalog.names():
        arm = catalog.load(name)
        kinds = "".join("R" if kind == "revolute" else "P" for kind in arm.kinds)
        table.add_row(
            name,
            kinds,
            str(arm.n),
            "yes" if arm.has_dynamics else "no",
            "yes" if np.any(arm.reflected_inertia > 0) else "no",
            "yes" if np.any(arm.viscous_friction > 0) or np.any(arm.coulomb_friction != 0) else "no",
            arm.description,
        )
    console.print(table)


@app.command()
def show(name: str) -> None:
    """Print an arm's DH (or joint) table and its dynamics table."""
    arm = _arm(name)
    console.print(f"[bold]{arm.name}[/bold]: {arm.description}  (n = {arm.n}, gravity {_vector(arm.gravity)})")
    console.print(_geometry_table(arm))
    console.print(_dynamics_table(arm))
    if arm.configurations:
        console.print(
            "configurations: " + "; ".join(f"{key} = {_vector(value)}" for key, value in arm.configurations.items())
        )


def _geometry_table(arm: Robot) -> Table:
    limits = arm.qlim
    if arm.dh is not None:
        table = Table(title=f"Denavit-Hartenberg parameters ({arm.dh['convention']})")
        for column in ("joint", "kind", "theta", "d", "a", "alpha", "q min", "q max"):
            table.add_column(column, justify="right")
        for index, row in enumerate(arm.dh["rows"]):
            revolute = row["kind"] == "revolute"
            theta = f"q{index + 1}" + ("" if row["theta"] == 0 else f" + {_number(row['theta'])}")
            d = f"q{index + 1}" + ("" if row["d"] == 0 else f" + {_number(row['d'])}")
            table.add_row(
                arm.joint_names[index],
                "R" if revolute else "P",
                theta if revolute else _number(row["theta"]),
                _number(row["d"]) if revolute else d,
                _number(row["a"]),
                _number(row["alpha"]),
                _number(limits[0, index]),
                _number(limits[1, index]),
            )
        return table
    table = Table(title="Joints")
    for column in ("joint", "kind", "parent", "axis", "placement xyz", "q min", "q max"):
        table.add_column(column, justify="right")
    for index, link in enumerate(arm.links):
        placement = link.joint.placement
        table.add_row(
            link.name,
            "R" if link.kind == "revolute" else "P",
            "base" if link.parent < 0 else arm.joint_names[link.parent],
            _vector(link.joint.axis, 3),
            _vector(placement[:3, 3], 4),
            _number(limits[0, index]),
            _number(limits[1, index]),
        )
    return table


def _dynamics_table(arm: Robot) -> Table:
    table = Table(title="Dynamics (inertia about the c.o.m. in the link frame; motor side Jm, B, Tc)")
    for column in ("link", "mass", "c.o.m.", "Ixx Iyy Izz", "Ixy Iyz Ixz", "Jm", "G", "B", "Tc+ / Tc-"):
        table.add_column(column, justify="right")
    for link in arm.links:
        body = link.inertial
        inertia = body.inertia
        table.add_row(
            link.name,
            _number(body.mass),
            _vector(body.com),
            _vector([inertia[0, 0], inertia[1, 1], inertia[2, 2]]),
            _vector([inertia[0, 1], inertia[1, 2], inertia[0, 2]]),
            _number(link.motor_inertia),
            _number(link.gear_ratio),
            _number(link.viscous),
            f"{_number(link.coulomb[0])} / {_number(link.coulomb[1])}",
        )
    return table


@app.command()
def derive(
    name: str,
    latex: bool = typer.Option(False, "--latex", help="Print LaTeX instead of the terminal form."),
    output: str | None = typer.Option(None, "--output", "-o", help="Write to this file instead of printing."),
    code: str | None = typer.Option(None, "--code", help="Generate code instead: 'python' or 'c'."),
    symbolic: bool = typer.Option(
        True, help="For the book's arms: keep their parameters as symbols (m1, m2, a1, ...)."
    ),
    method: str = typer.Option("auto", help="'lagrange' (the book's trace formula), 'recursive' or 'auto'."),
) -> None:
    """Derive an arm's robot equation in closed form: M, Vm, V, G (and F), as text, LaTeX or code."""
    from armdyn.symbolic import derive as derive_closed_form

    book = {"two_link_planar", "polar_rp", "cylindrical"}
    arm = getattr(catalog, name)(symbolic=True) if symbolic and name in book else _arm(name)
    try:
        form = derive_closed_form(arm, method=method)
    except ModelError as error:
        console.print(f"[red]error:[/red] {error}")
        raise typer.Exit(2) from None
    if code is not None:
        if code not in ("python", "c"):
            console.print("[red]error:[/red] --code must be 'python' or 'c'")
            raise typer.Exit(2)
        text = form.to_python() if code == "python" else form.to_c()
    else:
        text = form.latex() if latex else form.pretty()
    if output:
        with open(output, "w", encoding="utf-8") as handle:
            handle.write(text)
        console.print(f"wrote {output}")
    else:
        print(text)


@app.command()
def check(
    name: str,
    samples: int = typer.Option(300, help="Random joint configurations to sample before refining."),
    seed: int = typer.Option(0, help="Random seed."),
) -> None:
    """Check the properties of Table 3.3.1 on an arm and compute its bounds."""
    from armdyn.properties import check as check_properties

    report = check_properties(_arm(name), samples=samples, seed=seed)
    console.print(report.table())
    console.print("bounds: " + ", ".join(f"{key} = {value:.6g}" for key, value in report.bounds.items()))
    for note in report.notes:
        console.print(f"note: {note}")
    console.print("[green]all properties hold[/green]" if report.all_hold else "[red]some properties fail[/red]")
    if not report.all_hold:
        raise typer.Exit(1)


@app.command()
def identify(
    name: str,
    csv: str = typer.Argument(..., help="CSV with columns q1..qn, qd1..qdn, qdd1..qddn, tau1..taun (a header row)."),
) -> None:
    """Identify an arm's base parameters by least squares from measured samples in a CSV file."""
    from armdyn.dynamics.regressor import identify as identify_parameters

    arm = _arm(name)
    try:
        data = np.genfromtxt(csv, delimiter=",", names=True)
    except OSError as error:
        console.print(f"[red]error:[/red] {error}")
        raise typer.Exit(2) from None
    columns = {prefix: [f"{prefix}{i + 1}" for i in range(arm.n)] for prefix in ("q", "qd", "qdd", "tau")}
    missing = [c for group in columns.values() for c in group if c not in (data.dtype.names or ())]
    if missing:
        console.print(f"[red]error:[/red] {csv} lacks the columns {missing}")
        raise typer.Exit(2)
    arrays = {key: np.column_stack([data[c] for c in group]) for key, group in columns.items()}
    result = identify_parameters(arm, arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"])
    console.print(result.table())
    console.print(f"residual rms {result.residual_rms:.3g} N m over {result.samples} samples")


def main() -> None:
    app()


if __name__ == "__main__":
    main()
