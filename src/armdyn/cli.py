"""The `armdyn` command: the built-in arms, their tables, and (later) the chapter's jobs."""

from __future__ import annotations

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from armdyn import models as catalog
from armdyn.errors import ModelError
from armdyn.robot import Robot

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


def _controller(kind: str, kp: float, kv: float, ki: float, period: float, limit: float) -> object:
    from armdyn import control

    kinds = {
        "computed-torque": lambda: control.ComputedTorque(kp, kv, ki),
        "pd-gravity": lambda: control.PDGravity(kp, kv),
        "pid": lambda: control.PID(kp, kv, ki),
        "none": lambda: None,
    }
    if kind not in kinds:
        console.print(f"[red]error:[/red] --controller must be one of {', '.join(kinds)}")
        raise typer.Exit(2)
    controller = kinds[kind]()
    if controller is not None and np.isfinite(limit):
        controller = control.Saturated(controller, limit)
    if controller is not None and period > 0:
        controller = control.Digital(controller, period)
    return controller


def _trajectory(kind: str, arm: Robot, amplitude: float, frequency: float) -> object:
    from armdyn import trajectories

    offset = arm.configurations.get("qz", np.zeros(arm.n))
    if kind == "sine":  # the book's pattern: sin on odd joints, cos on even ones (Example 4.4-1)
        phase = [0.0 if i % 2 == 0 else np.pi / 2 for i in range(arm.n)]
        return trajectories.Sinusoid(amplitude, frequency, phase, offset)
    if kind == "quintic":
        return trajectories.Quintic(offset, offset + amplitude, 0.0, 1.0 / max(frequency, 1e-9))
    if kind == "none":
        return None
    console.print("[red]error:[/red] --trajectory must be sine, quintic or none")
    raise typer.Exit(2)


@app.command()
def simulate(
    name: str,
    controller: str = typer.Option("computed-torque", help="computed-torque, pd-gravity, pid or none."),
    kp: float = typer.Option(100.0, help="Proportional gain (per joint)."),
    kv: float = typer.Option(20.0, help="Derivative gain."),
    ki: float = typer.Option(0.0, help="Integral gain."),
    trajectory: str = typer.Option("sine", help="sine, quintic or none (hold the start)."),
    amplitude: float = typer.Option(0.1, help="Trajectory amplitude (rad or m)."),
    frequency: float = typer.Option(0.5, help="Trajectory frequency (Hz)."),
    t_final: float = typer.Option(5.0, "--t-final", help="Simulated time (s)."),
    dt: float = typer.Option(1e-3, help="Integration step (s)."),
    method: str = typer.Option("rk4", help="rk4 or an adaptive solver: rk45, rk23, dop853, radau, bdf, lsoda."),
    period: float = typer.Option(0.0, help="Digital control sample period (s); 0 for continuous."),
    torque_limit: float = typer.Option(float("inf"), "--torque-limit", help="Saturate torques at +-this."),
    disturbance: float = typer.Option(0.0, help="A constant disturbance torque tau_d on every joint."),
    plot: str | None = typer.Option(None, help="Write the figure to this PNG file."),
    csv: str | None = typer.Option(None, help="Write the samples to this CSV file."),
) -> None:
    """Simulate an arm under control and report the tracking errors."""
    from rich.progress import Progress

    from armdyn.simulation import simulate as run

    arm = _arm(name)
    law = _controller(controller, kp, kv, ki, period, torque_limit)
    desired = _trajectory(trajectory, arm, amplitude, frequency)
    start = desired(0.0, arm.n)[0] if desired is not None and controller == "none" else None
    with Progress(transient=True, console=console) as bar:
        task = bar.add_task(f"simulating {t_final:g} s of {arm.name}", total=1.0)
        try:
            result = run(arm, law, desired, t_final=t_final, dt=dt, method=method, q0=start,
                         disturbance=None if disturbance == 0 else [disturbance] * arm.n,
                         progress=lambda fraction: bar.update(task, completed=fraction))  # fmt: skip
        except ModelError as error:
            console.print(f"[red]error:[/red] {error}")
            raise typer.Exit(2) from None
    _report(result)
    if plot:
        result.plot(plot)
        console.print(f"wrote {plot}")
    if csv:
        result.to_csv(csv)
        console.print(f"wrote {csv}")


def _report(result: object) -> None:
    table = Table(
        title=f"{result.arm.name}: {result.info['method']}, {len(result.t) - 1} steps of {result.info['dt']:g} s"
    )
    for column in ("joint", "final q", "final error", "max |error| after 1 s", "max |tau|"):
        table.add_column(column, justify="right")
    late = result.t >= min(1.0, result.t[-1])
    for i, joint in enumerate(result.arm.joint_names):
        error = result.error
        table.add_row(
            joint,
            f"{result.q[-1, i]:.6g}",
            "-" if error is None else f"{error[-1, i]:.3g}",
            "-" if error is None else f"{np.abs(error[late, i]).max():.3g}",
            f"{np.abs(result.tau[:, i]).max():.4g}",
        )
    console.print(table)


@app.command()
def demo(output: str = typer.Option("out", help="Folder for demo.png and demo.csv.")) -> None:
    """The chapter end to end on the RR arm of Example 3.2-2: closed form, properties, and Example 4.4-1."""
    from pathlib import Path

    from armdyn import control, trajectories
    from armdyn.properties import check as check_properties
    from armdyn.simulation import simulate as run
    from armdyn.symbolic import derive as derive_closed_form

    console.rule("[bold]armdyn: Chapter 3 on the two-link planar elbow arm (Example 3.2-2)")
    form = derive_closed_form(catalog.two_link_planar(symbolic=True))
    console.print(
        "The robot equation M(q) qdd + Vm(q, qd) qd + G(q) = tau, derived by the book's Lagrange-Euler route:\n"
    )
    print(form.pretty())
    console.rule("[bold]Table 3.3.1, for m1 = m2 = a1 = a2 = 1, |theta_i| <= pi/2 (Example 3.3-1)")
    arm = catalog.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
    report = check_properties(arm, samples=200, limits=[(-np.pi / 2, np.pi / 2)] * 2)
    console.print(report.table())
    console.print("bounds: " + ", ".join(f"{key} = {value:.4g}" for key, value in report.bounds.items()))
    console.rule("[bold]Example 4.4-1: PD computed-torque control, kp = 100, kv = 20, RK4 with a 1 ms step")
    desired = trajectories.Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])
    result = run(arm, control.ComputedTorque(100.0, 20.0), desired, t_final=5.0, dt=1e-3)
    _report(result)
    folder = Path(output)
    folder.mkdir(parents=True, exist_ok=True)
    result.plot(folder / "demo.png", title="Example 4.4-1: PD computed-torque control of the two-link arm")
    result.to_csv(folder / "demo.csv")
    console.print(f"wrote {folder / 'demo.png'} and {folder / 'demo.csv'}")
    final = np.abs(result.error[-1])
    console.print(f"final tracking errors: e1 = {final[0]:.2e} rad, e2 = {final[1]:.2e} rad")


def main() -> None:
    app()


if __name__ == "__main__":
    main()
