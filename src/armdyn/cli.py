"""The `armdyn` command: the built-in arms, their tables, and the chapter's jobs.

Errors are handled once, for every command, by the app's command group (``_Group``): a
failure prints one line, ``error: ...``, on stderr and exits with a non-zero code — 2 for
bad input (an unknown arm, a bad number or option, an unreadable or malformed file, an
output path in a missing folder: armdyn's ModelError, ValueError, OSError, and typer's own
usage errors), 1 for an unexpected internal error (and for ``check`` when a property
fails). ``armdyn --debug COMMAND ...`` shows the full traceback instead. Warnings from the
library print as one line each, ``warning: ...``, on stderr.
"""

from __future__ import annotations

import csv as csv_files
import sys
import warnings
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import typer
from rich.console import Console
from rich.table import Table
from typer.core import TyperGroup

from armdyn import models as catalog
from armdyn.errors import ModelError
from armdyn.robot import Robot

INPUT_ERROR = 2
INTERNAL_ERROR = 1


def _error_line(text: str) -> None:
    """One line on stderr (the message's own line breaks and runs of spaces are collapsed)."""
    print("error: " + " ".join(text.split()), file=sys.stderr)


def _describe(error: BaseException) -> tuple[str, int]:
    """The message and exit code for an exception a command raised."""
    if isinstance(error, OSError) and error.filename is not None:
        return f"{error.filename}: {error.strerror or error}", INPUT_ERROR
    if isinstance(error, (ModelError, ValueError, OSError)):
        return str(error) or type(error).__name__, INPUT_ERROR
    return (
        f"internal error ({type(error).__name__}: {error}); run 'armdyn --debug ...' for the traceback",
        INTERNAL_ERROR,
    )


def _show_warning(message: Warning | str, *args: object, **kwargs: object) -> None:
    print("warning: " + " ".join(str(message).split()), file=sys.stderr)


class _Group(TyperGroup):
    """The app's command group: the one place where a command's failure becomes one line on
    stderr and an exit code (see the module docstring), unless ``--debug`` is given."""

    def invoke(self, ctx: typer.Context) -> Any:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            try:
                return super().invoke(ctx)
            except (typer.Exit, typer.Abort, typer.TyperException, BrokenPipeError):
                raise  # typer's own: exits and usage errors (handled in main), a closed pipe (exits quietly)
            except Exception as error:
                if ctx.params.get("debug"):
                    raise
                message, code = _describe(error)
                _error_line(message)
                raise typer.Exit(code) from None

    def main(self, *args: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        if not standalone_mode:
            return super().main(*args, standalone_mode=False, **kwargs)
        try:
            code = super().main(*args, standalone_mode=False, **kwargs)
        except typer.TyperException as error:  # a usage error: a bad option, a missing argument...
            if type(error).__name__ != "NoArgsIsHelpError":  # that one has printed the help already
                ctx = getattr(error, "ctx", None)
                hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
                _error_line(error.format_message() + hint)
            sys.exit(error.exit_code)
        except typer.Abort:
            _error_line("aborted")
            sys.exit(INTERNAL_ERROR)
        sys.exit(code if isinstance(code, int) else 0)


app = typer.Typer(
    cls=_Group, help="armdyn: the dynamics of robot manipulators.", no_args_is_help=True, add_completion=False
)
console = Console(width=None if Console().is_terminal else 140)


@app.callback()
def options(
    debug: bool = typer.Option(False, "--debug", help="On an error, show the full traceback instead of one line."),
) -> None:
    """armdyn: the dynamics of robot manipulators."""


def _fail(message: str) -> NoReturn:
    raise ModelError(message)


def _output_file(path: str, option: str) -> Path:
    """An output file whose folder exists, checked before any work is done (nothing is created)."""
    target = Path(path)
    folder = target.parent
    if not folder.exists():
        _fail(f"{option} {path}: the folder {folder} does not exist")
    if not folder.is_dir():
        _fail(f"{option} {path}: {folder} is not a folder")
    if target.is_dir():
        _fail(f"{option} {path} is a folder; give a file name")
    return target


def _output_folder(path: str, option: str) -> Path:
    """An output folder that exists or can be made in an existing folder (made later, by the caller)."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        _fail(f"{option} {path} is a file, not a folder")
    if not folder.exists() and not folder.absolute().parent.is_dir():
        _fail(f"{option} {path}: the folder {folder.absolute().parent} does not exist")
    return folder


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
    return catalog.load(name)  # a ModelError naming the known arms for an unknown name


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

    if code is not None and code not in ("python", "c"):
        _fail(f"--code must be 'python' or 'c', got '{code}'")
    target = _output_file(output, "--output") if output else None
    book = {"two_link_planar", "polar_rp", "cylindrical"}
    arm = getattr(catalog, name)(symbolic=True) if symbolic and name in book else _arm(name)
    form = derive_closed_form(arm, method=method)
    if code is not None:
        text = form.to_python() if code == "python" else form.to_c()
    else:
        text = form.latex() if latex else form.pretty()
    if target is not None:
        target.write_text(text, encoding="utf-8")
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
    output: str | None = typer.Option(
        None, "--output", "-o", help="Also write the estimates to this CSV file (name, estimate, std. error, model)."
    ),
) -> None:
    """Identify an arm's base parameters by least squares from measured samples in a CSV file."""
    from armdyn.dynamics.regressor import identify as identify_parameters

    arm = _arm(name)
    target = _output_file(output, "--output") if output else None
    arrays = _read_samples(csv, arm.n)
    result = identify_parameters(arm, arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"])
    console.print(result.table())
    console.print(f"residual rms {result.residual_rms:.3g} N m over {result.samples} samples")
    if target is not None:
        with target.open("w", newline="", encoding="utf-8") as handle:
            writer = csv_files.writer(handle)
            writer.writerow(["base parameter", "estimate", "standard error", "model value"])
            for row in zip(result.names, result.phi, result.standard_errors, result.base.phi, strict=True):
                writer.writerow([row[0], *(repr(float(value)) for value in row[1:])])
        console.print(f"wrote {output}")


def _read_samples(path: str, n: int) -> dict[str, np.ndarray]:
    """q, qd, qdd, tau (each (N, n)) from a CSV file with a header row; a ModelError naming the file,
    line and column for anything else (binary data, ragged rows, text where a number belongs)."""
    data = Path(path).read_bytes()  # an OSError names the file
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        _fail(f"{path} is not a text CSV file (it is not UTF-8 text)")
    if "\0" in text:
        _fail(f"{path} is not a text CSV file (it holds NUL bytes)")
    rows = [(number, row) for number, row in enumerate(csv_files.reader(text.splitlines()), 1) if any(row)]
    groups = {prefix: [f"{prefix}{i + 1}" for i in range(n)] for prefix in ("q", "qd", "qdd", "tau")}
    wanted = [column for group in groups.values() for column in group]
    if not rows:
        _fail(f"{path} is empty: it needs a header row ({', '.join(wanted)}) and samples")
    header = [cell.strip() for cell in rows[0][1]]
    missing = [column for column in wanted if column not in header]
    if missing:
        _fail(f"{path} lacks the columns {', '.join(missing)} (its header row is: {', '.join(header)})")
    if not rows[1:]:
        _fail(f"{path} has a header row but no samples")
    values = np.empty((len(rows) - 1, len(header)))
    for index, (number, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            _fail(f"{path}, line {number}: {len(row)} values, but the header row has {len(header)} columns")
        for column, cell in enumerate(row):
            try:
                values[index, column] = float(cell)
            except ValueError:
                _fail(f"{path}, line {number}, column {header[column]}: {cell.strip()!r} is not a number")
            if not np.isfinite(values[index, column]):
                _fail(f"{path}, line {number}, column {header[column]}: {cell.strip()} is not finite")
    where = {column: header.index(column) for column in wanted}
    return {key: values[:, [where[c] for c in group]] for key, group in groups.items()}


def _controller(kind: str, kp: float, kv: float, ki: float, period: float, limit: float) -> object:
    from armdyn import control

    kinds = {
        "computed-torque": lambda: control.ComputedTorque(kp, kv, ki),
        "pd-gravity": lambda: control.PDGravity(kp, kv),
        "pid": lambda: control.PID(kp, kv, ki),
        "none": lambda: None,
    }
    if kind not in kinds:
        _fail(f"--controller must be one of {', '.join(kinds)}, got '{kind}'")
    controller = kinds[kind]()
    if controller is None and (period != 0 or limit != np.inf):
        _fail("--period and --torque-limit need a controller (--controller none applies no torque)")
    if limit != np.inf:  # Saturated refuses NaN and limits <= 0
        controller = control.Saturated(controller, limit)
    if period != 0:  # Digital refuses a negative or non-finite period
        controller = control.Digital(controller, period)
    return controller


def _trajectory(kind: str, arm: Robot, amplitude: float, frequency: float) -> object:
    from armdyn import trajectories

    offset = arm.configurations.get("qz", np.zeros(arm.n))
    if kind == "sine":  # the book's pattern: sin on odd joints, cos on even ones (Example 4.4-1)
        phase = [0.0 if i % 2 == 0 else np.pi / 2 for i in range(arm.n)]
        return trajectories.Sinusoid(amplitude, frequency, phase, offset)
    if kind == "quintic":
        if not (np.isfinite(frequency) and frequency > 0):
            _fail(f"--frequency must be positive and finite for a quintic (it lasts 1/frequency s), got {frequency}")
        return trajectories.Quintic(offset, offset + amplitude, 0.0, 1.0 / frequency)
    if kind == "none":
        return None
    _fail(f"--trajectory must be sine, quintic or none, got '{kind}'")


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
    plot_file = _output_file(plot, "--plot") if plot else None
    csv_file = _output_file(csv, "--csv") if csv else None
    law = _controller(controller, kp, kv, ki, period, torque_limit)
    desired = _trajectory(trajectory, arm, amplitude, frequency)
    start = desired(0.0, arm.n)[0] if desired is not None and controller == "none" else None
    with Progress(transient=True, console=console) as bar:
        task = bar.add_task(f"simulating {t_final:g} s of {arm.name}", total=1.0)
        result = run(arm, law, desired, t_final=t_final, dt=dt, method=method, q0=start,
                     disturbance=None if disturbance == 0 else [disturbance] * arm.n,
                     progress=lambda fraction: bar.update(task, completed=fraction))  # fmt: skip
    _check_finite(result)
    _report(result)
    if plot_file is not None:
        result.plot(plot_file)
        console.print(f"wrote {plot}")
    if csv_file is not None:
        result.to_csv(csv_file)
        console.print(f"wrote {csv}")


def _check_finite(result: object) -> None:
    """A ModelError when a run diverged (its state became NaN or infinite)."""
    finite = np.isfinite(result.q).all(axis=-1) & np.isfinite(result.qd).all(axis=-1)
    if not finite.all():
        t = result.t[int(np.argmin(finite))]
        _fail(
            f"the simulation diverged: the state is not finite from t = {t:.6g} s (try a smaller --dt or lower gains)"
        )


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
def demo(
    output: str = typer.Option(
        "out", help="Folder for demo.png and demo.csv (made if missing; its parent must exist)."
    ),
) -> None:
    """The chapter end to end on the RR arm of Example 3.2-2: closed form, properties, and Example 4.4-1."""
    from armdyn import control, trajectories
    from armdyn.properties import check as check_properties
    from armdyn.simulation import simulate as run
    from armdyn.symbolic import derive as derive_closed_form

    folder = _output_folder(output, "--output")
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
    folder.mkdir(exist_ok=True)
    result.plot(folder / "demo.png", title="Example 4.4-1: PD computed-torque control of the two-link arm")
    result.to_csv(folder / "demo.csv")
    console.print(f"wrote {folder / 'demo.png'} and {folder / 'demo.csv'}")
    final = np.abs(result.error[-1])
    console.print(f"final tracking errors: e1 = {final[0]:.2e} rad, e2 = {final[1]:.2e} rad")


def main() -> None:
    """Run the command line (the ``armdyn`` script): errors are one line on stderr (see the module docstring)."""
    app()


if __name__ == "__main__":
    main()
