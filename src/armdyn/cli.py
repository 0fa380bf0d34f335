"""The `armdyn` command: the built-in arms, their tables, and the chapter's jobs.

Errors are handled once, for every command, by the app's command group (``_Group``): a
failure prints one line, ``error: ...``, on stderr and exits with a non-zero code — 2 for
bad input (an unknown arm, a bad number or option, an unreadable or malformed file, an
output path in a missing folder: armdyn's ModelError, ValueError, OSError, and typer's own
usage errors), 1 for an unexpected internal error (and for ``check`` when a property
fails). ``armdyn --debug COMMAND ...`` shows the full traceback instead. Warnings from the
library print as one line each, ``warning: ...``, on stderr.

An arm is named by a built-in name, a URDF file (.urdf), a MuJoCo MJCF file (.xml) or a DH table file (.json, .yaml,
.yml; see ``armdyn.models.load_dh_file``), the same way for every command (``_arm``). While
a command works, a spinner or progress bar shows on stderr (``_Activity``): when stderr is
a terminal, always with ``armdyn --progress``, never with ``--no-progress``. Tables carry
their units in the column headings; ``--output``/``-o`` writes what a command produces.
"""

from __future__ import annotations

import csv as csv_files
import io
import os
import re
import stat
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, SupportsFloat, cast

import numpy as np
import typer
from numba.core import event as numba_events
from numpy.typing import ArrayLike
from rich.console import Console
from rich.table import Table
from typer._click.exceptions import NoArgsIsHelpError  # typer's own click names it nowhere public
from typer.core import TyperGroup

from armdyn import models as catalog
from armdyn.errors import MissingDependencyError, ModelError, SimulationError, SingularError
from armdyn.files import atomic_write, write_text
from armdyn.robot import Robot

if TYPE_CHECKING:
    from rich.console import JustifyMethod
    from typer._click.core import Context as ClickContext  # typer's own click, the base of typer.Context

    from armdyn.actuators.arm import ActuatedArm
    from armdyn.actuators.packing import DriveRecord
    from armdyn.control.drives import CurrentComputedTorque, DrivePID
    from armdyn.control.task import TaskComputedTorque, Tracking
    from armdyn.identification.excitation import FourierTrajectory
    from armdyn.simulation import Result
    from armdyn.symbolic.closed_form import ClosedForm
    from armdyn.task_space import TaskOutput
    from armdyn.trajectories import Circle, Line, PoseLine, Quintic, Sinusoid

INPUT_ERROR = 2
INTERNAL_ERROR = 1
INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command stopped by Ctrl-C


COMPILING = "compiling kernels (first run only)..."
COMPILING_LINE = (
    "armdyn: compiling its kernels (the first run after installing or changing armdyn: about 2 to 4 minutes on "
    "2 cores, all at once for `armdyn demo`, less for one command); they are cached for later runs"
)


class _Activity:
    """What the running command is doing, on stderr: a spinner with a message, or a progress bar.

    Shown when stderr is a terminal (``mode`` None, the default), always (``mode`` True,
    ``armdyn --progress``) or never (``mode`` False, ``--no-progress``). One display at a
    time; it is stopped before the command prints anything on stdout (``_Console``) and
    when the command ends (``_Group``). While Numba compiles a kernel (the first run after
    installing or changing armdyn: the cached kernels are loaded afterwards) the message
    says so (``_Compiling``).
    """

    def __init__(self) -> None:
        self.mode: bool | None = None
        self.command = ""
        self.compiling = 0  # the depth of the Numba compilations under way
        self.announced = False  # the one line that says kernels compile, where no spinner shows it
        self._message = ""
        self._live: Any = None  # a rich Status or Progress while shown
        self._task: Any = None  # the Progress task

    def _console(self) -> Console | None:
        if self.mode is False or (self.mode is None and not sys.stderr.isatty()):
            return None
        display = Console(file=sys.stderr, force_terminal=True if self.mode else None)
        return display if display.is_terminal else None

    def _text(self) -> str:
        if not self.compiling:
            return self._message
        return f"{self._message}: {COMPILING}" if self._message else COMPILING

    def refresh(self) -> None:
        """Show the message again (after a change of it, or of ``compiling``)."""
        from rich.status import Status

        if isinstance(self._live, Status):
            self._live.update(self._text())
        elif self._live is not None:
            self._live.update(self._task, description=self._text(), refresh=True)
        elif self.compiling:
            self.status(self._message or self.command)

    def status(self, message: str) -> None:
        """Show a spinner with this message (in place of what is shown)."""
        from rich.status import Status

        self._message = message
        if isinstance(self._live, Status):
            self.refresh()
            return
        display = self._console()
        if display is None:
            return
        self.stop()
        self._live = display.status(self._text())
        self._live.start()

    def bar(self, message: str) -> Callable[..., None] | None:
        """Show a progress bar; the callback to call with the fraction done (and optionally the stage),
        or None when nothing is shown."""
        from rich import progress as bars

        display = self._console()
        if display is None:
            return None
        self.stop()
        self._message = message
        columns = (bars.SpinnerColumn(), bars.TextColumn("{task.description}"), bars.BarColumn(),
                   bars.TaskProgressColumn(), bars.TimeElapsedColumn(), bars.TimeRemainingColumn())  # fmt: skip
        bar = bars.Progress(*columns, console=display, transient=True)
        task = bar.add_task(self._text(), total=1.0)
        bar.start()
        self._live, self._task = bar, task

        def update(fraction: float, stage: str | None = None) -> None:
            if self._live is bar:
                self._message = message if stage is None else f"{message}: {stage}"
                bar.update(task, completed=float(fraction), description=self._text(), refresh=True)

        return update

    def echo(self, line: str) -> None:
        """One line on stderr, above the spinner or bar when one is shown."""
        if self._live is not None:
            self._live.console.print(line, markup=False, highlight=False, soft_wrap=True)
        else:
            print(line, file=sys.stderr)

    def stop(self) -> None:
        """Stop the spinner or bar (it leaves nothing behind)."""
        if self._live is not None:
            live, self._live, self._task = self._live, None, None
            live.stop()


_activity = _Activity()


class _Compiling(numba_events.Listener):
    """Numba's compile events (fired on a cache miss only): the spinner says that kernels compile."""

    def on_start(self, event: object) -> None:
        _activity.compiling += 1
        if _activity.compiling == 1:
            if _activity.mode is not False and _activity._console() is None and not _activity.announced:
                _activity.announced = True  # a log or a pipe: one line, so a long silence is explained
                print(COMPILING_LINE, file=sys.stderr, flush=True)
            _activity.refresh()

    def on_end(self, event: object) -> None:
        _activity.compiling = max(0, _activity.compiling - 1)
        if _activity.compiling == 0:
            _activity.refresh()


numba_events.register("numba:compile", _Compiling())


def _error_line(text: str) -> None:
    """One line on stderr (the message's own line breaks and runs of spaces are collapsed)."""
    print("error: " + " ".join(text.split()), file=sys.stderr)


def _describe(error: BaseException) -> tuple[str, int]:
    """The message and exit code for an exception a command raised."""
    if isinstance(error, OSError) and error.filename is not None:
        return f"{error.filename}: {error.strerror or error}", INPUT_ERROR
    if isinstance(error, (ModelError, SimulationError, MissingDependencyError, ValueError, OSError)):
        return str(error) or type(error).__name__, INPUT_ERROR
    return (
        f"internal error ({type(error).__name__}: {error}); run 'armdyn --debug ...' for the traceback",
        INTERNAL_ERROR,
    )


def _show_warning(message: Warning | str, *args: object, **kwargs: object) -> None:
    _activity.echo("warning: " + " ".join(str(message).split()))


class _Group(TyperGroup):
    """The app's command group: the one place where a command's failure becomes one line on
    stderr and an exit code (see the module docstring), unless ``--debug`` is given."""

    def invoke(self, ctx: ClickContext) -> Any:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            try:
                try:
                    return super().invoke(ctx)
                finally:
                    _activity.stop()
                    _activity.mode = None  # the next command (in this process) decides afresh
            except (typer.Exit, typer.Abort, typer.TyperException, BrokenPipeError):
                raise  # typer's own: exits and usage errors (handled in main), a closed pipe (exits quietly)
            except KeyboardInterrupt as stop:  # Ctrl-C: one line saying what was kept (a study's blocks), exit 130
                if ctx.params.get("debug"):
                    raise
                _error_line(str(stop) or "interrupted")
                raise typer.Exit(INTERRUPTED) from None
            except Exception as error:
                if ctx.params.get("debug"):
                    raise
                message, code = _describe(error)
                _error_line(message)
                raise typer.Exit(code) from None

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        windows_expand_args: bool = True,
        **kwargs: Any,
    ) -> Any:
        given = (args, prog_name, complete_var)
        if not standalone_mode:
            return super().main(*given, standalone_mode=False, windows_expand_args=windows_expand_args, **kwargs)
        try:
            code = super().main(*given, standalone_mode=False, windows_expand_args=windows_expand_args, **kwargs)
        except typer.TyperException as error:  # a usage error: a bad option, a missing argument...
            if not isinstance(error, NoArgsIsHelpError):  # that one has printed the help already
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


class _Console(Console):
    """The console of the commands' output (stdout): stops the spinner or bar before it prints."""

    def print(self, *objects: Any, **options: Any) -> None:
        """Print, as rich's Console.print, once the spinner or bar on stderr is gone.

        Parameters
        ----------
        *objects : object
            What to print.
        **options
            rich's Console.print options.
        """
        _activity.stop()
        super().print(*objects, **options)


console = _Console(width=None if Console().is_terminal else 140)


ACTUATORS_HELP = (
    "Drive every joint through its actuator (Section 3.6): dc (DC motors with their electrics; the PUMA 560's "
    "own motors with representative electrics), flexible (the same behind elastic shafts) or hydraulic (servo "
    "valves with rotary motors or pistons); representative drives sized from the arm's gravity load; or file (an "
    "MJCF file's own dcmotor actuators)."
)

DRIVE_GAINS = (
    "with --actuators and --controller pid, the gains act on each drive's input: V per rad of the motor "
    "(default kp 20, kv 0.5) or, hydraulic, valve A per rad or m of the joint (default kp 0.1, kv 0)"
)
SIMULATE_DRIVES_HELP = (
    "--controller pid is independent joint PID on each drive's input (voltage or valve current); "
    "computed-torque (dc) is computed torque turned into current commands through the motor model."
)


def _version(value: bool) -> None:
    if value:
        from armdyn import __version__

        print(f"armdyn {__version__}")
        raise typer.Exit()


@app.callback()
def options(
    ctx: typer.Context,
    debug: bool = typer.Option(False, "--debug", help="On an error, show the full traceback instead of one line."),
    progress: bool | None = typer.Option(
        None,
        "--progress/--no-progress",
        help="Show spinners and progress bars on stderr even when it is not a terminal (or never). "
        "Default: only on a terminal.",
    ),
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print armdyn's version and exit."
    ),
) -> None:
    """armdyn: the dynamics of robot manipulators."""
    _activity.mode = progress
    _activity.command = ctx.invoked_subcommand or ""


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
    if target.exists() and not target.is_file():
        _fail(f"{option} {path} is not a regular file (a device or a pipe); give a file name")
    _writable(folder, f"{option} {path}")
    return target


def _writable(folder: Path, what: str) -> None:
    """A ModelError, before any work, when files cannot be made in ``folder`` (a read-only folder)."""
    if not os.access(folder, os.W_OK | os.X_OK):
        _fail(f"{what}: the folder {folder} is not writable")


def _output_folder(path: str, option: str) -> Path:
    """An output folder that exists or can be made in an existing folder (made later, by the caller)."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        _fail(f"{option} {path} is a file, not a folder")
    if not folder.exists() and not folder.absolute().parent.is_dir():
        _fail(f"{option} {path}: the folder {folder.absolute().parent} does not exist")
    _writable(folder if folder.exists() else folder.absolute().parent, f"{option} {path}")
    return folder


def _make_folder(folder: Path) -> None:
    """Make an output folder (its parent exists: ``_output_folder``); a ModelError naming it when it cannot be."""
    try:
        folder.mkdir(exist_ok=True)
    except OSError as error:
        _fail(f"could not make the folder {folder}: {error.strerror or error}")


def _animation_file(path: str, option: str) -> Path:
    """An animation's file, checked as ``_output_file``, ending in .gif (or .mp4 with ffmpeg installed)."""
    from armdyn.plotting import check_animation_path

    return _plotting_file(path, option, check_animation_path)


def _picture_file(path: str, option: str) -> Path:
    """A picture's file, checked as ``_output_file``, its suffix an image format (.png, .pdf, .svg, ...)."""
    from armdyn.plotting import check_picture_path

    return _plotting_file(path, option, check_picture_path)


def _plotting_file(path: str, option: str, check: Callable[[Path], Path]) -> Path:
    target = _output_file(path, option)
    try:
        return check(target)
    except ModelError as error:
        _fail(f"{option} {error}")


TABLE_FORMATS = {".csv": "CSV", ".md": "Markdown", ".txt": "text"}


def _table_file(path: str, option: str) -> Path:
    """An output file for tables, its format named by its suffix (TABLE_FORMATS), checked as ``_output_file``."""
    target = _output_file(path, option)
    if target.suffix.lower() not in TABLE_FORMATS:
        _fail(f"{option} {path}: the file must end in .csv, .md or .txt (CSV, Markdown or text)")
    return target


@dataclass
class _Sheet:
    """A table as text: what the commands print (as a rich Table) and write (CSV, Markdown, text)."""

    title: str
    columns: list[str]
    rows: list[list[str]]
    caption: str = ""

    def rich(self, justify: JustifyMethod = "right") -> Table:
        table = Table(title=self.title, caption=self.caption or None)
        for column in self.columns:
            table.add_column(column, justify=justify, overflow="fold")
        for row in self.rows:
            table.add_row(*row)
        return table


def _write_sheets(target: Path, sheets: Sequence[_Sheet], notes: Sequence[str] = ()) -> None:
    """Write tables to a file in the format of its suffix: CSV (a header row and the rows; with
    several tables, each after a row holding its title, separated by an empty row), Markdown
    (a heading and a table each, then the notes) or text (as printed, then the notes)."""
    suffix = target.suffix.lower()
    if suffix == ".csv":
        with atomic_write(target, newline="", encoding="utf-8") as handle:
            writer = csv_files.writer(handle)
            for index, sheet in enumerate(sheets):
                if len(sheets) > 1:
                    if index:
                        writer.writerow([])
                    writer.writerow([sheet.title])
                writer.writerow(sheet.columns)
                writer.writerows(sheet.rows)
        return
    if suffix == ".md":

        def cells(values: Sequence[str]) -> str:
            return "| " + " | ".join(value.replace("|", "\\|") for value in values) + " |"

        lines = []
        for sheet in sheets:
            lines += [f"## {sheet.title}", "", cells(sheet.columns), "|" + "---|" * len(sheet.columns)]
            lines += [cells(row) for row in sheet.rows]
            lines += ["", sheet.caption, ""] if sheet.caption else [""]
        lines += [f"- {note}" for note in notes]
        write_text(target, "\n".join(lines).rstrip() + "\n")
        return
    text = io.StringIO()
    plain = Console(file=text, width=160, no_color=True, highlight=False)
    for sheet in sheets:
        plain.print(sheet.rich())
    for note in notes:
        plain.print(note, markup=False)
    write_text(target, text.getvalue())


def _units(arm: Robot, revolute: str, prismatic: str) -> str:
    """The unit of a joint quantity of the arm, for a column heading: e.g. "rad", "m" or "rad; m for P"."""
    kinds = set(arm.kinds)
    if kinds == {"revolute"}:
        return revolute
    if kinds == {"prismatic"}:
        return prismatic
    return f"{revolute}; {prismatic} for P"


def _number(value: object, digits: int = 4) -> str:
    if hasattr(value, "free_symbols"):
        return str(value)
    number = float(cast("SupportsFloat", value))
    if np.isinf(number):
        return "inf" if number > 0 else "-inf"
    return f"{number + 0.0:.{digits}g}"  # + 0.0: -0 prints as 0


def _vector(values: object, digits: int = 4) -> str:
    return "[" + ", ".join(_number(v, digits) for v in np.asarray(values).ravel()) + "]"


ARM_FILES = (".urdf", ".xml", ".mjcf", ".json", ".yaml", ".yml")
ARM_HELP = (
    "A built-in arm (see 'armdyn models'), a URDF file (.urdf), a MuJoCo MJCF file (.xml) or a DH table file "
    "(.json, .yaml)."
)
STRICT_HELP = "Refuse inertias that break the triangle inequality (and, in a URDF, joints that move no mass)."


def _arm(name: str, strict: bool = True, locked: dict[str, float] | None = None) -> Robot:
    """The arm a command names: a built-in arm, a URDF file (.urdf), a MuJoCo MJCF file (.xml, .mjcf,
    read by ``armdyn.load_mjcf``) or a DH table file (.json, .yaml, .yml); ``strict`` as
    ``armdyn.load_urdf`` and ``armdyn.models.load_dh_file`` take it.

    Parameters
    ----------
    name : str
        The built-in name (any case) or the file's path.
    strict : bool, optional
        For a file: refuse inertias that break the triangle inequality, and URDF joints that
        move no mass (default True); False loads them with a warning.

    Returns
    -------
    Robot
        The arm.

    Raises
    ------
    armdyn.ModelError
        For an unknown name (the message lists the built-in arms), a file of another kind, or
        a file the loader refuses.
    OSError
        When the file cannot be read.
    """
    _activity.status(f"{_activity.command} {name}".strip())
    suffix = Path(name).suffix.lower()
    if locked and suffix not in (".urdf", ".xml", ".mjcf"):
        _fail(f"--lock takes joints of a URDF or MJCF file; {name} is not one")
    if suffix == ".urdf":
        from armdyn.urdf import load_urdf

        return load_urdf(name, strict=strict, locked=locked)
    if suffix in (".xml", ".mjcf"):
        from armdyn.io.mjcf import load_mjcf

        arm = load_mjcf(name, strict=strict, locked=locked)
        assert isinstance(arm, Robot)  # without drives=True
        return arm
    if suffix == ".json" and _is_model_file(name):
        from armdyn.io.model_file import load_arm

        return load_arm(name)
    if suffix in ARM_FILES:
        return catalog.load_dh_file(name, strict=strict)
    try:
        return catalog.load(name)
    except ModelError as error:
        path = Path(name)
        if path.is_file():
            _fail(
                f"{name}: an arm file must be a URDF (.urdf), an MJCF (.xml, .mjcf) or a DH table (.json, .yaml, .yml)"
            )
        if path.suffix or len(path.parts) > 1:
            _fail(f"{name}: no such file (an arm is a built-in name, {', '.join(catalog.names())}; a URDF file, "
                  ".urdf; an MJCF file, .xml; or a DH table file, .json or .yaml)")  # fmt: skip
        raise ModelError(
            f"{error}; or give a URDF file (.urdf), an MJCF file (.xml) or a DH table file (.json, .yaml)"
        ) from None


def _is_model_file(path: str) -> bool:
    """Whether a .json file is armdyn's own model file (``armdyn.io.model_file``) rather than a DH table."""
    import json

    from armdyn.io.model_file import FORMAT

    try:
        with open(path, encoding="utf-8") as handle:
            data = json.load(handle)
    except (OSError, ValueError):
        return False  # the DH-table reader names the problem
    return isinstance(data, dict) and data.get("format") == FORMAT


def _values(text: str, option: str) -> np.ndarray:
    """Numbers separated by commas; each may be arithmetic on pi, e.g. "-pi/2"."""
    parts = [part.strip() for part in text.split(",")]
    if not all(parts):
        _fail(f"{option} {text!r}: give numbers separated by commas")
    return np.array([catalog._value(part, option) for part in parts])


def _per_joint(text: str, option: str, n: int) -> float | np.ndarray:
    """One number for every joint (a float), or n numbers separated by commas."""
    values = _values(text, option)
    if len(values) == 1:
        return float(values[0])
    if len(values) != n:
        _fail(f"{option} has {len(values)} values, but the arm has {n} joints (give 1 value, or {n})")
    return values


def _joint_state(text: str, option: str, arm: Robot) -> np.ndarray:
    """A joint vector: one of the arm's named configurations, one number for every joint, or n numbers."""
    if text.strip() in arm.configurations:
        return np.array(arm.configurations[text.strip()], dtype=float)
    if re.fullmatch(r"\s*[A-Za-z_]\w*\s*", text) and text.strip() != "pi":
        known = ", ".join(arm.configurations) or "none"
        _fail(f"{option} {text.strip()!r}: {arm.name} has no configuration of that name (it has: {known}); "
              f"or give 1 or {arm.n} numbers separated by commas")  # fmt: skip
    return np.broadcast_to(_per_joint(text, option, arm.n), (arm.n,)).copy()


@app.command()
def models(
    output: str | None = typer.Option(None, "--output", "-o", help="Also write the list to this .csv, .md or .txt."),
) -> None:
    """List the built-in arms."""
    target = _table_file(output, "--output") if output else None
    sheet = _Sheet("Built-in arms", ["name", "joints", "DOF", "dynamics", "motors", "friction", "description"], [])
    for name in catalog.names():
        arm = catalog.load(name)
        kinds = "".join("R" if kind == "revolute" else "P" for kind in arm.kinds)
        sheet.rows.append([
            name,
            kinds,
            str(arm.n),
            "yes" if arm.has_dynamics else "no",
            "yes" if np.any(arm.reflected_inertia > 0) else "no",
            "yes" if np.any(arm.viscous_friction > 0) or np.any(arm.coulomb_friction != 0) else "no",
            arm.description,
        ])  # fmt: skip
    console.print(sheet.rich(justify="left"))
    if target is not None:
        _write_sheets(target, [sheet])
        console.print(f"wrote {output}")


DRAW_HELP = "Also draw the arm (a stick figure with its joint axes and frames) to this image: .png, .pdf, .svg, ..."
DRAW_Q_HELP = (
    "The configuration --draw draws (rad or m): a configuration of the arm (qz, qr, ...), one number for every "
    "joint, or one per joint separated by commas. Default: the arm's qn, else its qz, else zeros."
)


@app.command()
def show(
    name: str = typer.Argument(..., help=ARM_HELP),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    output: str | None = typer.Option(
        None, "--output", "-o", help="Also write the tables to this file: .csv, .md or .txt (by its suffix)."
    ),
    actuators: str | None = typer.Option(None, "--actuators", help=ACTUATORS_HELP),
    draw: str | None = typer.Option(None, "--draw", help=DRAW_HELP),
    q: str | None = typer.Option(None, "--q", help=DRAW_Q_HELP),
) -> None:
    """Print an arm's DH (or joint) table and its dynamics table, with units; with --actuators, its drives
    (Section 3.6) with their time constants; with --draw, a picture of the arm."""
    target = _table_file(output, "--output") if output else None
    picture = _picture_file(draw, "--draw") if draw else None
    arm = _arm(name, strict)
    configuration = _joint_state(q, "--q", arm) if q is not None else None
    if configuration is not None and picture is None:
        _fail("--q is the configuration of the picture: give --draw PATH too")
    driven = _actuated(arm, name, actuators) if actuators is not None else None
    from rich.markup import escape

    gravity = f"gravity {_vector(arm.gravity)} m/s^2"
    described = f"{arm.name}: {arm.description}" if arm.description else arm.name
    console.print(f"[bold]{escape(described)}[/bold]  (n = {arm.n}, {gravity})", highlight=False)
    sheets = [_geometry_sheet(arm), _dynamics_sheet(arm)]
    if driven is not None:
        sheets += _drive_sheets(driven)
    for sheet in sheets:
        console.print(sheet.rich())
    if arm.configurations:
        console.print(
            "configurations: " + "; ".join(f"{key} = {_vector(value)}" for key, value in arm.configurations.items())
        )
    if target is not None:
        if arm.configurations:
            unit = _units(arm, "rad", "m")
            columns = ["name", *(f"{joint} ({unit})" for joint in arm.joint_names)]
            rows = [[key, *(_number(v, 8) for v in value)] for key, value in arm.configurations.items()]
            sheets.append(_Sheet("Configurations", columns, rows))
        _write_sheets(target, sheets, [f"{described} (n = {arm.n}, {gravity})"])
        console.print(f"wrote {output}")
    if picture is not None:
        named = q.strip() if q is not None and q.strip() in arm.configurations else None
        arm.plot(named if named is not None else configuration, path=picture)
        console.print(f"wrote {draw}")


def _actuated(arm: Robot, name: str, kind: str) -> ActuatedArm:
    """The arm with drives of ``kind`` (armdyn.actuators.representative_drives; the built-in PUMA 560's motors; an
    MJCF file's dcmotor actuators, armdyn.load_mjcf(drives=True))."""
    from armdyn import actuators

    kinds = ("dc", "flexible", "hydraulic", "file")
    if kind not in kinds:
        _fail(f"--actuators must be one of {', '.join(kinds)}, got '{kind}'")
    if kind == "file":
        if Path(name).suffix.lower() not in (".xml", ".mjcf"):
            _fail(f"--actuators file reads the dcmotor actuators of an MJCF file (.xml, .mjcf); {name} is not one")
        from armdyn.io.mjcf import load_mjcf

        driven = load_mjcf(name, drives=True)
        assert isinstance(driven, actuators.ActuatedArm)
        return driven
    if kind == "dc" and name.lower() == "puma560":
        return actuators.puma560_with_drives()
    return actuators.representative_drives(arm, kind)


def _drive_sheets(driven: ActuatedArm) -> list[_Sheet]:
    """The drives of an ActuatedArm as tables: DC motors with their electrical and mechanical time
    constants, hydraulic drives with their pressure pole and oil-column frequency."""
    from armdyn.actuators import DCMotor

    q = np.asarray(driven.robot.configurations.get("qz", np.zeros(driven.n)), dtype=float)
    inertia = np.diag(driven.mechanical_robot().inertia_matrix(q))
    joints = driven.robot.joint_names
    motors = [(j, d) for j, d in enumerate(driven.drives) if isinstance(d, DCMotor)]
    valves = [(j, d) for j, d in enumerate(driven.drives) if not isinstance(d, DCMotor)]
    flexible = any(d.flexible for _, d in motors)
    sheets = []
    if motors:
        columns = ["joint", "drive", "r", "J_M kg m^2", "K_M N m/A", "K_b V s", "R_a ohm", "L mH", "v max V",
                   "i max A", "L/R_a ms", "tau_m ms", *(["shaft K"] if flexible else [])]  # fmt: skip
        rows = []
        for j, d in motors:
            seen = d.rotor_inertia + d.gear_ratio**2 * inertia[j]  # the motor's own plus the link at qz
            mechanical = seen * d.resistance / (d.torque_constant * d.back_emf)
            shaft = [_number(d.stiffness) if d.flexible else "rigid"] if flexible else []
            rows.append([joints[j], d.name, _number(d.gear_ratio), _number(d.rotor_inertia), _number(d.torque_constant),
                         _number(d.back_emf), _number(d.resistance), _number(1e3 * d.inductance),
                         _number(d.voltage_limit), _number(d.current_limit),
                         _number(1e3 * d.inductance / d.resistance), _number(1e3 * mechanical), *shaft])  # fmt: skip
        title = "DC drives (tau_m = J R_a / (K_M K_b), J the rotor's and the link's inertia at qz)"
        sheets.append(_Sheet(title, columns, rows))
    if valves:
        columns = ["joint", "drive", "A m^2 or D_m m^3", "K_q m^2/s", "K_c + C_tp m^3/(s Pa)", "V_t l", "P_s MPa",
                   "tau_v ms", "i max mA", "oil column Hz"]  # fmt: skip
        rows = []
        for j, valve in valves:
            column = np.sqrt(valve.area**2 / (valve.capacitance * inertia[j])) / (2 * np.pi)
            rows.append([joints[j], valve.name, _number(valve.area), _number(valve.linearized_flow_gain),
                         _number(valve.total_coefficient), _number(1e3 * valve.volume),
                         _number(valve.supply_pressure / 1e6), _number(1e3 * valve.valve_time_constant),
                         _number(1e3 * valve.current_limit), _number(column)])  # fmt: skip
        sheets.append(_Sheet("Hydraulic drives (Merritt 1967; the oil column with the link's inertia at qz)", columns,
                             rows))  # fmt: skip
    return sheets


def _geometry_sheet(arm: Robot) -> _Sheet:
    limits = arm.qlim
    unit = _units(arm, "rad", "m")
    bounds = [f"q min ({unit})", f"q max ({unit})"]
    if arm.dh is not None:
        sheet = _Sheet(f"Denavit-Hartenberg parameters ({arm.dh['convention']})",
                       ["joint", "kind", "theta (rad)", "d (m)", "a (m)", "alpha (rad)", *bounds], [])  # fmt: skip
        for index, row in enumerate(arm.dh["rows"]):
            revolute = row["kind"] == "revolute"
            theta = f"q{index + 1}" + ("" if row["theta"] == 0 else f" + {_number(row['theta'])}")
            d = f"q{index + 1}" + ("" if row["d"] == 0 else f" + {_number(row['d'])}")
            sheet.rows.append([
                arm.joint_names[index],
                "R" if revolute else "P",
                theta if revolute else _number(row["theta"]),
                _number(row["d"]) if revolute else d,
                _number(row["a"]),
                _number(row["alpha"]),
                _number(limits[0, index]),
                _number(limits[1, index]),
            ])  # fmt: skip
        return sheet
    sheet = _Sheet("Joints", ["joint", "kind", "parent", "axis", "placement xyz (m)", *bounds], [])
    for index, link in enumerate(arm.links):
        placement = link.joint.placement
        sheet.rows.append([
            link.name,
            "R" if link.kind == "revolute" else "P",
            "base" if link.parent < 0 else arm.joint_names[link.parent],
            _vector(link.joint.axis, 3),
            _vector(placement[:3, 3], 4),
            _number(limits[0, index]),
            _number(limits[1, index]),
        ])  # fmt: skip
    return sheet


def _dynamics_sheet(arm: Robot) -> _Sheet:
    friction = _units(arm, "N m", "N")
    columns = ["link", "mass (kg)", "c.o.m. (m)", "Ixx Iyy Izz (kg m^2)", "Ixy Iyz Ixz (kg m^2)", "Jm (kg m^2)",
               "G (ratio)", f"B ({_units(arm, 'N m/(rad/s)', 'N/(m/s)')})", f"Tc+ / Tc- ({friction})"]  # fmt: skip
    stribeck, sigmoid = bool(np.any(arm.stribeck_friction[:, 0])), bool(np.any(arm.sigmoid_friction[:, 0]))
    speed = _units(arm, "rad/s", "m/s")
    columns += [f"Stribeck Fs ({friction}) / vs ({speed})"] if stribeck else []
    columns += [f"sigmoid A ({friction}) / alpha ({_units(arm, 's/rad', 's/m')}) / shift ({speed})"] if sigmoid else []
    title = "Dynamics (inertia about the c.o.m. in the link frame; motor side Jm, B, Tc"
    title += "; joint side Stribeck and sigmoid)" if stribeck or sigmoid else ")"
    sheet = _Sheet(title, columns, [])
    for link in arm.links:
        body = link.inertial
        inertia = body.inertia
        sheet.rows.append([
            link.name,
            _number(body.mass),
            _vector(body.com),
            _vector([inertia[0, 0], inertia[1, 1], inertia[2, 2]]),
            _vector([inertia[0, 1], inertia[1, 2], inertia[0, 2]]),
            _number(link.motor_inertia),
            _number(link.gear_ratio),
            _number(link.viscous),
            f"{_number(link.coulomb[0])} / {_number(link.coulomb[1])}",
        ])  # fmt: skip
        if stribeck:
            sheet.rows[-1].append(f"{_number(link.stribeck[0])} / {_number(link.stribeck[1])}")
        if sigmoid:
            sheet.rows[-1].append(" / ".join(_number(x) for x in link.sigmoid))
    return sheet


@app.command()
def derive(
    name: str = typer.Argument(..., help=ARM_HELP),
    latex: bool = typer.Option(False, "--latex", help="Print LaTeX instead of the terminal form."),
    output: str | None = typer.Option(None, "--output", "-o", help="Write to this file instead of printing."),
    code: str | None = typer.Option(None, "--code", help="Generate code instead: 'python' or 'c'."),
    symbolic: bool = typer.Option(
        True, help="For the book's arms: keep their parameters as symbols (m1, m2, a1, ...)."
    ),
    method: str = typer.Option(
        "auto",
        help="'lagrange' (the book's trace formula), 'recursive', 'newton-euler' (--code only: straight-line "
        "code of the customized Newton-Euler recursion, for arms of any size) or 'auto' (newton-euler for "
        "--code of a numeric arm of 5 joints or more, else recursive).",
    ),
    task: str | None = typer.Option(
        None,
        "--task",
        help="Task coordinates instead (Section 3.5): position or planar, as many as joints: "
        "Mbar, Vmbar, Gbar, Fbar, Nbar.",
    ),
    functions: str | None = typer.Option(
        None,
        "--functions",
        help="With --code, the Newton-Euler route's functions, comma-separated, of tau, M, G, N, Vm and Wb "
        "(the base regressor, with the base parameters); default tau,M,G,N.",
    ),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
) -> None:
    """Derive an arm's robot equation in closed form: M, Vm, V, G (and F), as text, LaTeX or code."""
    from armdyn.symbolic import derive as derive_closed_form

    if code is not None and code not in ("python", "c"):
        _fail(f"--code must be 'python' or 'c', got '{code}'")
    if method == "newton-euler" and code is None:
        _fail("--method newton-euler generates code: give --code python or --code c")
    if functions is not None:
        if code is None or task is not None or method not in ("auto", "newton-euler"):
            _fail("--functions chooses what the Newton-Euler route generates: give it with --code python or "
                  "--code c, without --task, and with --method auto or newton-euler")  # fmt: skip
        method = "newton-euler"
    if code is not None and task is None and method in ("auto", "newton-euler"):
        generated = _generated_code(name, code, method, symbolic, strict, functions)
        if generated is not None:
            _write_code(generated, output)
            return
    if task is not None and code is not None:
        _fail("--task and --code exclude each other: code is generated for the joint-space equation")
    chosen = _task_output(task) if task is not None else None
    if code is not None and latex:
        _fail(f"--latex and --code {code} exclude each other: give --latex for the equations in LaTeX, "
              f"or --code {code} for {'Python' if code == 'python' else 'C'} source")  # fmt: skip
    target = _output_file(output, "--output") if output else None
    book = {"two_link_planar", "polar_rp", "cylindrical"}
    arm = getattr(catalog, name.lower())(symbolic=True) if symbolic and name.lower() in book else _arm(name, strict)
    progress = _activity.bar(f"deriving the closed form of {arm.name}")
    options: dict[str, Any] = {"method": method} | ({} if progress is None else {"progress": progress})
    form = derive_closed_form(arm, **options) if chosen is None else derive_closed_form(arm, output=chosen, **options)
    _activity.status(f"writing the equations of {arm.name}" + (f" as {code} code" if code else ""))
    if code is not None:
        joint = cast("ClosedForm", form)  # the joint-space equation of a Robot: --code excludes --task
        _activity.stop()
        _write_code((joint.to_python(), None) if code == "python" else (joint.to_c(), joint.to_c_header()), output)
        return
    elif latex:
        text = cast("ClosedForm", form).latex_document() if target is not None and chosen is None else form.latex()
    else:  # the terminal gets a summary of long entries; a file gets every entry in full
        text = form.pretty(limit=None) if target is not None else form.pretty()
    _activity.stop()
    if target is not None:
        write_text(target, text)
        console.print(f"wrote {output}")
    else:
        print(text)


def _generated_code(name: str, language: str, method: str, symbolic: bool, strict: bool,
                    functions: str | None = None) -> tuple[str, str | None] | None:  # fmt: skip
    """Source from armdyn.symbolic.generate_code for ``derive --code`` (method newton-euler, or auto for
    a numeric arm of 5 joints or more); None where the closed form's code is wanted instead."""
    from armdyn.symbolic import generate_code
    from armdyn.symbolic.newton_euler import FUNCTIONS

    book = {"two_link_planar", "polar_rp", "cylindrical"}
    if method == "auto" and symbolic and name.lower() in book:
        return None
    arm = _arm(name, strict)
    if method == "auto" and (arm.is_symbolic or arm.n < 5):
        return None
    if arm.is_symbolic:
        _fail(f"--method newton-euler needs numeric parameters; '{arm.name}' has symbols")
    names = FUNCTIONS if functions is None else [f.strip() for f in functions.split(",") if f.strip()]
    try:
        code = generate_code(arm, names)
    except ModelError as error:
        _fail(f"--functions: {error}")
    counts = ", ".join(f"{key} {value['total']}" for key, value in code.operation_counts().items())
    _activity.status(f"generated {language} for {arm.name}: operations {counts}")
    return (code.python(), None) if language == "python" else (code.c(), code.c_header())


def _write_code(code: tuple[str, str | None], output: str | None) -> None:
    """Generated source on stdout, or in ``output``: C to a .c file goes with its header, a .h beside it that
    the .c includes; a .h alone is the header (the declarations)."""
    source, header = code
    if not output:
        print(source)
        return
    target = _output_file(output, "--output")
    if header is not None and target.suffix == ".h":
        write_text(target, header)
        console.print(f"wrote {output}")
    elif header is not None:
        declarations = target.with_suffix(".h")
        write_text(declarations, header)
        write_text(target, f'#include "{declarations.name}"\n' + source)
        console.print(f"wrote {target} and {declarations}")
    else:
        write_text(target, source)
        console.print(f"wrote {output}")


CHECK_SAMPLES = 1_000_000
"""The most samples ``check --samples`` takes (armdyn.properties.check's own limit): beyond it a
check takes minutes, and its arrays of M(q) gigabytes, while the extremes found no longer change."""


@app.command()
def check(
    name: str = typer.Argument(..., help=ARM_HELP),
    samples: int = typer.Option(
        300,
        max=CHECK_SAMPLES,
        help=f"Random joint configurations to sample before refining (at most {CHECK_SAMPLES:,}).",
    ),
    seed: int = typer.Option(0, help="Random seed."),
    limits: str = typer.Option(
        "arm",
        help="The joint range to check over: lower:upper per joint, separated by commas "
        "('-1.5708:1.5708,-1.5708:1.5708'; pi allowed: '-pi/2:pi/2'; one pair for every joint), or 'arm': the "
        "arm's own limits (a whole turn for a revolute joint without them, 1 m for a prismatic one).",
    ),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    output: str | None = typer.Option(
        None, "--output", "-o", help="Also write the table to this file: .csv, .md or .txt (by its suffix)."
    ),
    task: str | None = typer.Option(
        None,
        "--task",
        help="Check in task coordinates (Section 3.5) instead of joint coordinates: 'position' (tool point, 3), "
        "'pose' (tool position and angular velocity, 6) or 'planar' (tool x, y, 2); at most as many coordinates "
        "as joints (fewer: Khatib's Lambda).",
    ),
    max_condition: float | None = typer.Option(
        None,
        "--max-condition",
        help="With --task: keep only the sampled configurations where cond J is below this (default 1000), the "
        "region the bounds hold over (they grow without bound near singularities).",
    ),
    only: str | None = typer.Option(
        None,
        "--only",
        help="Check only these groups of rows, separated by commas: inertia, coriolis, skew, friction, gravity, "
        "linearity, passivity (e.g. 'passivity,skew'). Default: all.",
    ),
) -> None:
    """Check the properties of Table 3.3.1 on an arm and compute its bounds (with units).

    A row that cannot be evaluated on the arm says "could not be checked" and why; the others are
    still printed, and the exit status is 1, as for a property that fails.
    """
    from armdyn.properties import GROUPS
    from armdyn.properties import check as check_properties

    target = _table_file(output, "--output") if output else None
    groups = None if only is None else [group.strip() for group in only.split(",")]
    unknown = [group for group in groups or [] if group not in GROUPS]
    if unknown:
        _fail(f"--only names unknown groups {', '.join(map(repr, unknown))}: give some of {', '.join(GROUPS)}, "
              "separated by commas")  # fmt: skip
    if max_condition is not None and task is None:
        _fail("--max-condition applies to task coordinates only: give --task with it")
    arm = _arm(name, strict)
    ranges = _limits(limits, arm)
    chosen = None if task is None else _task_output(task)
    options: dict[str, Any] = {} if chosen is None else {"task": chosen, "max_condition": max_condition}
    where = "" if chosen is None else f" in task coordinates {chosen!r}"
    refined = "L-BFGS-B" if chosen is None else "SLSQP"
    _activity.status(f"checking Table 3.3.1 on {arm.name}{where} ({samples} samples, refined by {refined})")
    report = check_properties(arm, samples=samples, seed=seed, limits=ranges, only=groups, **options)
    if chosen is None:
        report.references.update(_book_values(arm, report.ranges))
    console.print(report.table())
    bounds = "bounds: " + ", ".join(
        f"{key} = {value:.6g}" + (f" {report.units[key]}" if report.units.get(key) else "")
        for key, value in report.bounds.items()
    )
    console.print(bounds, highlight=False)
    notes = list(report.notes)
    if report.references:
        notes.append(
            "book values: Example 3.3-1 (the book's Section 3.3), the RR arm of Example 3.2-2 with |theta_i| <= pi/2"
        )
    for note in notes:
        console.print(f"note: {note}", highlight=False, markup=False)
    for row in report.unchecked:
        console.print(f"could not be checked: {row.name}: {row.unchecked}", style="red", highlight=False, markup=False)
    if report.all_hold:
        console.print("[green]all properties hold[/green]")
    elif len(report.unchecked) < len(report.rows):
        failing = [row for row in report.rows if not row.holds and row.unchecked is None]
        console.print("[red]some properties fail[/red]" if failing else "[green]all properties checked hold[/green]")
    if target is not None:
        columns, rows = report.records(digits=8)
        sheet = _Sheet(report.title(8), columns, rows)
        _write_sheets(target, [sheet], [bounds, *(f"note: {note}" for note in notes)])
        console.print(f"wrote {output}")
    if not report.all_hold:
        raise typer.Exit(1)


def _task_output(coordinates: str, option: str = "--task") -> TaskOutput:
    """The task output that ``check --task``, ``simulate --task`` and ``task --coordinates`` name (TASK_OUTPUTS)."""
    from armdyn import task_space

    outputs = {"position": task_space.ToolPosition, "pose": task_space.ToolPose, "planar": task_space.PlanarPosition}
    if coordinates not in outputs:
        _fail(f"{option} must be one of {', '.join(TASK_OUTPUTS)}, got {coordinates!r}")
    return outputs[coordinates]()


def _limits(text: str, arm: Robot) -> list[tuple[float, float]] | None:
    """The ranges of ``check --limits``: None for 'arm' (the arm's own), else (lower, upper) per joint."""
    if text.strip().lower() == "arm":
        return None
    pairs = []
    for part in text.split(","):
        ends = part.split(":")
        if len(ends) != 2:
            _fail(f"--limits {text!r}: give lower:upper for each joint, separated by commas "
                  "(e.g. -1.5708:1.5708,-1.5708:1.5708), or 'arm' for the arm's own limits")  # fmt: skip
        lower, upper = (catalog._value(end.strip(), "--limits") for end in ends)
        pairs.append((lower, upper))
    if len(pairs) == 1:
        pairs *= arm.n
    if len(pairs) != arm.n:
        _fail(f"--limits has {len(pairs)} lower:upper pairs, but the arm has {arm.n} joints (give 1 pair, or {arm.n})")
    return pairs


def _book_values(arm: Robot, ranges: Sequence[tuple[float, float]]) -> dict[str, float]:
    """The bounds Example 3.3-1 gives (Lewis, Dawson and Abdallah 2004), when ``arm`` is the RR arm of Example 3.2-2
    (any masses m1, m2 and lengths a1, a2) and the ranges are |theta_i| <= pi/2; else none.

    ||M(q)||_1 lies between m1 = (m1+m2) a1^2 + 2 m2 a2^2 and m2 = m1 + 3 m2 a1 a2 (the 1-norm is
    the first column sum, (m1+m2) a1^2 + 2 m2 a2^2 + 3 m2 a1 a2 cos(theta2)); gb = (m1+m2) g a1 +
    2 m2 g a2; for unit masses and lengths mu1 = 3 - sqrt 8, mu2 = 3 + sqrt 8 (at theta2 = 0).
    """
    if arm.n != 2 or arm.dh is None or arm.is_symbolic or set(arm.kinds) != {"revolute"}:
        return {}
    if not np.allclose(np.asarray(ranges, dtype=float), [(-np.pi / 2, np.pi / 2)] * 2, atol=1e-4):
        return {}
    mass1, mass2 = (float(cast("SupportsFloat", link.inertial.mass)) for link in arm.links)  # numeric: checked
    a1, a2 = (float(row["a"]) for row in arm.dh["rows"])
    g = -float(arm.gravity[1])
    try:
        book = catalog.two_link_planar(mass1, mass2, a1, a2, g)
    except ModelError:
        return {}
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-np.pi, np.pi, (3, 8, 2))
    if not np.allclose(arm.inverse_dynamics(q, qd, qdd), book.inverse_dynamics(q, qd, qdd), rtol=1e-9, atol=1e-12):
        return {}
    lower = (mass1 + mass2) * a1**2 + 2 * mass2 * a2**2
    values = {"m1": lower, "m2": lower + 3 * mass2 * a1 * a2, "gb": (mass1 + mass2) * g * a1 + 2 * mass2 * g * a2}
    if np.allclose([mass1, mass2, a1, a2], 1.0):
        values.update(mu1=3 - np.sqrt(8), mu2=3 + np.sqrt(8))
    return values


@app.command()
def identify(
    name: str = typer.Argument(..., help=ARM_HELP),
    csv: str | None = typer.Argument(
        None,
        help="CSV with columns q1..qn, qd1..qdn, qdd1..qddn, tau1..taun (a header row), a regular file of at most "
        "256 MiB; none with --generate.",
    ),
    output: str | None = typer.Option(
        None, "--output", "-o", help="Also write the estimates to this CSV file (name, estimate, std. error, model)."
    ),
    generate: bool = typer.Option(
        False,
        "--generate",
        help="Generate the samples instead of reading them: an optimized excitation trajectory (a Fourier series "
        "per joint, Swevers et al. 1997) tracked by the simulated arm under computed torque, Coulomb friction by "
        "the exact sign law, with --noise on the torques.",
    ),
    noise: float = typer.Option(0.1, "--noise", help="With --generate: the torque noise's standard deviation (N m)."),
    seed: int = typer.Option(0, "--seed", help="With --generate: the seed of the trajectory's start and the noise."),
    period: float = typer.Option(
        10.0, "--period", help="With --generate: the trajectory's period (s), also the seconds of data."
    ),
    harmonics: int = typer.Option(5, "--harmonics", help="With --generate: the trajectory's harmonics per joint."),
    dt: float = typer.Option(1e-3, "--dt", help="With --generate: the sample interval and simulation step (s)."),
    velocity_band: float = typer.Option(
        0.0,
        "--velocity-band",
        help="Leave out each joint's equations where its speed is below this (rad/s or m/s): friction near zero "
        "velocity that is not the Coulomb sign law (simulate's smoothed friction; stiction). Default 0.",
    ),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    log: str | None = typer.Option(
        None,
        "--log",
        help="A robot's log to identify from: a CSV, NPZ or Parquet file of time, q (optionally qd) and tau or motor "
        "current, or a folder in the format of Gaz et al.'s Panda log. Writes a report and the identified arm to -o "
        "DIR.",
    ),
    columns: str | None = typer.Option(
        None, "--columns", help='With --log: the column map, e.g. "t=time,q=pos{j},tau=effort{j}" ({j} is 1..n).'
    ),
    current: bool = typer.Option(False, "--current", help="With --log: the log holds motor currents, not torques."),
    gains: str | None = typer.Option(
        None, "--gains", help="With --current: the current-to-torque gains per joint (N m/A), separated by commas."
    ),
    gains_from_payload: tuple[str, float] | None = typer.Option(
        None,
        "--gains-from-payload",
        help="With --current: estimate the gains from a second log RUN carrying a payload of known MASS (kg) "
        "(Gautier and Briot 2014); its centre of mass is --payload-com.",
        metavar="RUN MASS",
    ),
    payload_com: str = typer.Option(
        "0,0,0",
        "--payload-com",
        help="With --gains-from-payload: the payload's centre of mass in the tool link's frame (m), x,y,z; off the "
        "last joint's axis, or that joint's gain is not determined.",
    ),
    friction: str = typer.Option(
        "sigmoid", "--friction", help="With --log: the friction law, viscous, coulomb, stribeck or sigmoid."
    ),
    consistent: bool = typer.Option(
        True,
        "--consistent/--no-consistent",
        help="With --log: also the physically consistent estimate (every pseudo-inertia positive semidefinite), "
        "from which the identified arm is built.",
    ),
    validate_log: str | None = typer.Option(None, "--validate", help="With --log: a second log to predict."),
    holdout: float = typer.Option(
        0.0, "--holdout", help="With --log: the share of the log, at its end, kept out of the estimate and predicted."
    ),
    reference: str | None = typer.Option(
        None, "--reference", help="With --log: an arm predicting the same held-out samples, for comparison."
    ),
    cutoff: float | None = typer.Option(None, "--cutoff", help="With --log: the low-pass cut-off (Hz)."),
    decimate: int | None = typer.Option(None, "--decimate", help="With --log: the decimation factor."),
    mass_tolerance: float | None = typer.Option(
        None,
        "--mass-tolerance",
        help="With --log and --consistent: each link's mass within this share of the arm's own (0.1: within 10%).",
    ),
    lock: str | None = typer.Option(
        None,
        "--lock",
        help='With --log and a URDF or MJCF arm: joints held fixed, "name=value,..." (e.g. a gripper\'s fingers).',
    ),
) -> None:
    """Identify an arm's base parameters by least squares: from measured samples in a CSV file, or
    from samples generated along an optimized excitation trajectory (--generate); or identify a
    physically consistent arm from a robot's log (--log), with a validation report."""
    from armdyn.identification import identify as identify_parameters

    if log is not None:
        if csv is not None or generate:
            _fail("--log identifies from a robot's log; give it without a samples CSV file and without --generate")
        _identify_log(
            name, log, output, strict, columns=columns, current=current, gains=gains, payload=gains_from_payload,
            friction=friction, consistent=consistent, validate_log=validate_log, holdout=holdout,
            reference=reference, cutoff=cutoff, decimate=decimate, velocity_band=velocity_band, lock=lock,
            payload_com=payload_com, mass_tolerance=mass_tolerance,
        )  # fmt: skip
        return
    log_options = (("--columns", columns), ("--gains", gains), ("--gains-from-payload", gains_from_payload),
                   ("--validate", validate_log), ("--reference", reference), ("--cutoff", cutoff),
                   ("--decimate", decimate), ("--lock", lock), ("--mass-tolerance", mass_tolerance))  # fmt: skip
    given = [option for option, value in log_options if value is not None]
    given += [option for option, on in (("--current", current), ("--holdout", holdout != 0.0)) if on]
    given += ["--friction"] if friction != "sigmoid" else []
    given += ["--payload-com"] if payload_com != "0,0,0" else []
    if given:
        _fail(f"{', '.join(given)} {'goes' if len(given) == 1 else 'go'} with --log")

    if generate and csv is not None:
        _fail(f"give either a CSV file of samples or --generate, not both (got {csv} and --generate)")
    if not generate:
        if csv is None:
            _fail("give a CSV file of samples (columns q1..qn, qd1..qdn, qdd1..qddn, tau1..taun), or --generate")
        defaults = (("--noise", noise, 0.1), ("--seed", seed, 0), ("--period", period, 10.0),
                    ("--harmonics", harmonics, 5), ("--dt", dt, 1e-3))  # fmt: skip
        given = [option for option, value, default in defaults if value != default]
        if given:
            _fail(f"{', '.join(given)} {'goes' if len(given) == 1 else 'go'} with --generate, not with a CSV file")
    for option, value in (("--velocity-band", velocity_band), ("--noise", noise)):  # before any work
        if not (np.isfinite(value) and value >= 0):
            _fail(f"{option} must be a finite number >= 0, got {value}")
    target = _output_file(output, "--output") if output else None
    arm = _arm(name, strict)
    if generate:
        arrays, trajectory = _generated_samples(arm, noise, seed, period, harmonics, dt)
    else:
        assert csv is not None  # checked above: a CSV file, or --generate
        arrays, trajectory = _read_samples(csv, arm.n), None
    _activity.status(f"identifying the base parameters of {arm.name} from {len(arrays['q'])} samples")
    result = identify_parameters(arm, arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"],
                                 velocity_band=velocity_band)  # fmt: skip
    console.print(result.table())
    left_out = f", {result.left_out} joint equations left out by --velocity-band" if result.left_out else ""
    console.print(f"residual rms {result.residual_rms:.3g} N m over {result.samples} samples{left_out}")
    if trajectory is not None:
        z = np.abs(result.normalized_errors)
        console.print(
            f"generated: a Fourier series of {harmonics} harmonics per joint, period {period:g} s, optimized to "
            f"cond(W) {trajectory.condition_number:.3g} over a period; {len(arrays['q'])} samples simulated under "
            f"computed torque every {dt:g} s, torque noise {noise:g} N m (seed {seed})",
            highlight=False,
        )
        console.print(
            f"{np.count_nonzero(z <= 3)} of {len(z)} base parameters within 3 standard errors of the model values; "
            f"largest |estimate - model| = {z.max():.3g} standard errors",
            highlight=False,
        )
    if target is not None:
        with atomic_write(target, newline="", encoding="utf-8") as handle:
            writer = csv_files.writer(handle)
            writer.writerow(["base parameter", "estimate", "standard error", "model value"])
            for row in zip(result.names, result.phi, result.standard_errors, result.base.phi, strict=True):
                writer.writerow([row[0], *(repr(float(value)) for value in row[1:])])
        console.print(f"wrote {output}")


def _column_map(text: str, option: str = "--columns") -> dict[str, str]:
    """--columns "t=time,q=q{j},tau=tau{j}" (or --lock "name=value,...") as a mapping."""
    mapping = {}
    for part in text.split(","):
        key, sep, value = part.partition("=")
        if not sep or not key.strip() or not value.strip():
            _fail(f"{option} {text!r}: give name=value pairs separated by commas, e.g. t=time,q=q{{j}},tau=tau{{j}}")
        mapping[key.strip()] = value.strip()
    return mapping


def _identify_log(
    name: str, path: str, output: str | None, strict: bool, *, columns: str | None, current: bool,
    gains: str | None, payload: tuple[str, float] | None, friction: str, consistent: bool,
    validate_log: str | None, holdout: float, reference: str | None, cutoff: float | None,
    decimate: int | None, velocity_band: float, lock: str | None, payload_com: str = "0,0,0",
    mass_tolerance: float | None = None,
) -> None:  # fmt: skip
    """``identify ARM --log FILE``: the whole workflow of armdyn.identification, its report and exports."""
    from armdyn.identification.log import read_log
    from armdyn.identification.report import write_report
    from armdyn.identification.workflow import identify_log, validate

    if output is None:
        _fail("--log writes a report and the identified arm: give the folder with -o DIR")
    if velocity_band != 0.0:
        _fail("--velocity-band goes with a samples CSV file; a log's friction law covers slow samples")
    if not (np.isfinite(holdout) and 0.0 <= holdout <= 0.9):
        _fail(f"--holdout must be a share between 0 and 0.9, got {holdout}")
    if holdout and validate_log:
        _fail("give either --holdout or --validate, not both")
    if (gains is not None or payload is not None) and not current:
        _fail("--gains and --gains-from-payload go with --current (a log of motor currents)")
    if current and gains is None and payload is None:
        _fail("--current needs the current-to-torque gains: --gains G1,G2,... or --gains-from-payload RUN MASS")
    folder = _output_folder(output, "-o")
    locked = (
        {key: float(catalog._value(value, "--lock")) for key, value in _column_map(lock, "--lock").items()}
        if lock
        else None
    )
    arm = _arm(name, strict, locked)
    mapping = _column_map(columns) if columns else None
    _activity.status(f"reading {path}")
    data = read_log(path, columns=mapping)
    held = data.current is not None
    if current != held:
        what = "motor currents" if held else "torques"
        _fail(f"{path}: the log holds {what}; {'give --current' if held else 'leave out --current'}")
    gain_values = _values(gains, "--gains") if gains is not None else None
    if payload is not None:
        from armdyn.identification.gains import identify_gains
        from armdyn.identification.preprocess import prepare

        run, mass = payload
        _activity.status(f"estimating the drive gains from {run} (payload {mass:g} kg)")
        loaded = read_log(run, columns=mapping)
        com = _values(payload_com, "--payload-com")
        if com.shape != (3,):
            _fail(f"--payload-com must be three numbers x,y,z (m), got {payload_com!r}")
        estimate = identify_gains(arm, cast(Any, prepare(data)), cast(Any, prepare(loaded)), mass, payload_com=com)
        gain_values = np.asarray(estimate.gains)
        console.print("gains from the payload run (N m/A): " + ", ".join(f"{g:.6g}" for g in gain_values))
    model = identify_log(
        arm, data, friction=friction, consistent=consistent, holdout=holdout, gains=gain_values, cutoff=cutoff,
        decimate=decimate, mass_tolerance=mass_tolerance, progress=_activity.status,
    )  # fmt: skip
    held_out = (
        read_log(validate_log, columns=mapping) if validate_log else (data.split(1 - holdout)[1] if holdout else None)
    )
    validation = model.validate(held_out, gain_values) if held_out is not None else None
    compared = None
    if reference is not None and held_out is not None:
        other = _arm(reference, strict)
        compared = validate(other.inverse_dynamics, held_out, model.prepared, gain_values)
    _make_folder(folder)
    report = write_report(model, folder, validation, compared, reference or "reference")
    console.print(
        f"identified {arm.name} from {model.prepared.q.shape[0]} samples ({friction} friction); condition number "
        f"{model.condition_number:.4g}",
        highlight=False,
    )
    if validation is not None:
        table = Table(title="Held-out samples: predicted against measured torque")
        headers = ["joint", "rms (N m)", "normalized rms"] + ([f"{reference} rms", "change"] if compared else [])
        for header in headers:
            table.add_column(header, justify="left" if header == "joint" else "right")
        for j, joint in enumerate(validation.joint_names):
            row = [joint, f"{validation.rms[j]:.4g}", f"{validation.normalized_rms[j]:.3g}"]
            if compared is not None:
                row += [f"{compared.rms[j]:.4g}", f"{100 * (validation.rms[j] / compared.rms[j] - 1):+.1f}%"]
            table.add_row(*row)
        console.print(table)
    if model.arm is not None:
        from armdyn.io.mjcf_out import to_mjcf
        from armdyn.io.model_file import save_arm
        from armdyn.io.urdf_out import to_urdf

        to_urdf(model.arm, folder / "identified.urdf")
        save_arm(model.arm, folder / "identified.json")
        written = [folder / "identified.urdf", folder / "identified.json"]
        try:
            to_mjcf(model.arm, folder / "identified.xml")
            written.insert(1, folder / "identified.xml")
        except ModelError as error:  # an inertia MuJoCo cannot hold: the other files still carry the arm
            warnings.warn(f"identified.xml not written: {error}", stacklevel=1)
        console.print("wrote " + ", ".join(str(path) for path in written))
    console.print(f"wrote {report} and report.html")


@app.command()
def observe(
    name: str = typer.Argument(..., help=ARM_HELP),
    log: str = typer.Option(..., "--log", help="The log: CSV, NPZ, Parquet, or the Panda log folder (as identify)."),
    output: str = typer.Option(..., "--output", "-o", help="The folder for residuals.csv, the report and the figure."),
    columns: str | None = typer.Option(None, "--columns", help='The column map, e.g. "t=time,q=q{j},tau=tau{j}".'),
    gains: str = typer.Option("25", "--gains", help="The observer's gain K per joint (1/s): one number or n."),
    free: float = typer.Option(
        0.3, "--free", help="The share of the log, at its start, taken as free of contact: the band is set from it."
    ),
    quantile: float = typer.Option(0.999, "--quantile", help="The band's quantile of the free residuals per joint."),
    margin: float = typer.Option(2.0, "--margin", help="The band widened about its centre by this factor."),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    lock: str | None = typer.Option(None, "--lock", help='A URDF or MJCF file\'s joints held fixed, "name=value,...".'),
) -> None:
    """Run the generalized-momentum observer over a log (the external joint torque without a sensor), set a band
    from its collision-free start, and report detections, the link in contact and the residual's rms."""
    from armdyn.identification.log import read_log
    from armdyn.identification.preprocess import prepare
    from armdyn.observers.contact import contact_link
    from armdyn.observers.detection import Band, detect, plot_residuals
    from armdyn.observers.momentum import observe as residual_of

    if not (np.isfinite(free) and 0.05 <= free <= 0.95):
        _fail(f"--free must be a share of the log between 0.05 and 0.95, got {free}")
    folder = _output_folder(output, "-o")
    locked = (
        {key: float(catalog._value(value, "--lock")) for key, value in _column_map(lock, "--lock").items()}
        if lock
        else None
    )
    arm = _arm(name, strict, locked)
    _activity.status(f"reading {log}")
    data = read_log(log, columns=_column_map(columns) if columns else None)
    data.check_arm(arm)
    if data.tau is None:
        _fail(f"{log}: the observer needs the applied joint torques (tau columns); this log holds motor currents")
    K = _values(gains, "--gains")
    qd = data.qd if data.qd is not None else None
    if qd is None:  # velocities by central differences of the low-passed positions, at the log's own times
        prepared = prepare(data, decimate=1, trim=0.0)
        qd = np.column_stack([np.interp(data.t, prepared.t, prepared.qd[:, j]) for j in range(arm.n)])
    _activity.status(f"observing {data.samples} samples")
    r = residual_of(arm, data.t, data.q, qd, data.tau, gains=K if K.size > 1 else float(K[0]))
    settle = data.t[0] + 5.0 / float(np.min(K))
    cut = data.t[0] + free * (data.t[-1] - data.t[0])
    free_part = (data.t > settle) & (data.t <= cut)
    if np.count_nonzero(free_part) < 20:
        _fail(f"--free {free}: the collision-free part after the observer settles ({settle:.3g} s) has too few samples")
    band = Band.from_residuals(r[free_part], quantile=quantile, margin=margin)
    watched = data.t > cut
    before = r.copy()
    before[~watched] = band.centre  # the collision-free part, where the band was set, is not watched
    detection = detect(data.t, before, band)
    _make_folder(folder)
    table = np.column_stack([data.t, r])
    header = "t," + ",".join(f"r{j + 1}" for j in range(arm.n))
    with atomic_write(folder / "residuals.csv", newline="", encoding="utf-8") as handle:
        np.savetxt(handle, table, delimiter=",", header=header, comments="")
    plot_residuals(data.t, r, band, detection, path=folder / "residuals.png")
    rms = np.sqrt(np.mean(r[watched] ** 2, axis=0))
    lines = [f"# Momentum observer on {log}", "", f"arm {arm.name}, gains {K.tolist()} 1/s, {data.samples} samples; "
             f"band from {free:.0%} of the log (quantile {quantile}, margin {margin})", "",
             "| joint | band low | band high | residual rms after (N m) |", "|---|---|---|---|"]  # fmt: skip
    for j, joint in enumerate(arm.joint_names):
        lines.append(f"| {joint} | {band.lower[j]:.4g} | {band.upper[j]:.4g} | {rms[j]:.4g} |")
    if detection.time is None:
        verdict = "no contact detected after the collision-free part"
    else:
        k = int(np.searchsorted(data.t, detection.time))
        link = contact_link(r[k], np.vstack([band.lower, band.upper]))
        named = arm.joint_names[link] if link is not None else "none"
        first = arm.joint_names[detection.joint] if detection.joint is not None else "none"
        verdict = (f"contact detected at t = {detection.time:.4g} s on joint {first}; "
                   f"the last link in contact: {named}; {len(detection.intervals)} interval(s)")  # fmt: skip
    lines += ["", verdict]
    write_text(folder / "report.md", "\n".join(lines) + "\n")
    console.print(verdict, highlight=False)
    console.print(f"wrote {folder / 'residuals.csv'}, {folder / 'residuals.png'} and {folder / 'report.md'}")


def _generated_samples(
    arm: Robot, noise: float, seed: int, period: float, harmonics: int, dt: float
) -> tuple[dict[str, np.ndarray], FourierTrajectory]:
    """``identify --generate``: an excitation trajectory optimized for the arm, and one period of samples
    simulated along it with torque noise (armdyn.identification.excitation), as (q, qd, qdd, tau arrays, the
    trajectory)."""
    from armdyn.identification.excitation import excitation_trajectory, identification_data

    _activity.status(f"optimizing an excitation trajectory for {arm.name} ({harmonics} harmonics, {period:g} s)")
    trajectory = excitation_trajectory(arm, period=period, harmonics=harmonics, seed=seed)
    _activity.status(f"simulating {period:g} s of {arm.name} along it (computed torque, noise {noise:g} N m)")
    data = identification_data(arm, trajectory, dt=dt, noise=noise, seed=seed)
    return {"q": data.q, "qd": data.qd, "qdd": data.qdd, "tau": data.tau}, trajectory


CSV_BYTES = 256 * 2**20
"""The largest samples file ``identify`` reads (256 MiB, millions of samples): its values are
parsed one by one, and a device such as /dev/zero would never end."""


def _read_samples(path: str, n: int) -> dict[str, np.ndarray]:
    """q, qd, qdd, tau (each (N, n)) from a CSV file with a header row; a ModelError naming the file,
    line and column for anything else (binary data, ragged rows, text where a number belongs)."""
    data = _csv_bytes(path)
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


def _csv_bytes(path: str) -> bytes:
    """The bytes of a regular file of at most CSV_BYTES; a ModelError for a device, a pipe or a
    larger file (read no further than the cap, should it grow), an OSError naming a missing one."""
    info = os.stat(path)  # an OSError names the file
    if not stat.S_ISREG(info.st_mode):
        _fail(f"{path} is not a regular file (a device, a pipe or a folder); give a CSV file of samples")
    too_large = f"{path} is larger than {CSV_BYTES:,} bytes, the most identify reads; give fewer samples"
    if info.st_size > CSV_BYTES:
        _fail(too_large)
    with open(path, "rb") as handle:
        data = handle.read(CSV_BYTES + 1)
    if len(data) > CSV_BYTES:
        _fail(too_large)
    return data


def _controller(kind: str, kp: object, kv: object, ki: object, period: float, limit: ArrayLike) -> object:
    """The controller of ``simulate``: gains and torque limit one number or one per joint."""
    from armdyn import control

    kinds: dict[str, Callable[[], Callable[..., np.ndarray] | None]] = {
        "computed-torque": lambda: control.ComputedTorque(kp, kv, ki),
        "pd-gravity": lambda: control.PDGravity(kp, kv),
        "pid": lambda: control.PID(kp, kv, ki),
        "none": lambda: None,
    }
    if kind not in kinds:
        _fail(f"--controller must be one of {', '.join(kinds)}, got '{kind}'")
    controller = kinds[kind]()
    limited = not np.all(np.asarray(limit, dtype=float) == np.inf)
    if controller is None:
        if period != 0 or limited:
            _fail("--period and --torque-limit need a controller (--controller none applies no torque)")
        return None
    if limited:  # Saturated refuses NaN and limits <= 0
        controller = control.Saturated(controller, limit)
    if period != 0:  # Digital refuses a negative or non-finite period
        controller = control.Digital(controller, period)
    return controller


def _trajectory(
    kind: str, arm: Robot, amplitude: float, frequency: float, start: np.ndarray | None = None
) -> Sinusoid | Quintic | None:
    """The desired trajectory of ``simulate``, about ``start`` (default the arm's qz, or zeros)."""
    from armdyn import trajectories

    lower, upper = arm.qlim
    offset = start if start is not None else _inside_limits(arm, arm.configurations.get("qz", np.zeros(arm.n)))
    if kind == "sine":  # the book's pattern: sin on odd joints, cos on even ones (Example 4.4-1)
        phase = [0.0 if i % 2 == 0 else np.pi / 2 for i in range(arm.n)]
        if start is None:  # the default path swings inside the joints' limits: a smaller swing, a centre moved in
            swing = np.minimum(amplitude, 0.4 * (upper - lower))
            offset = np.clip(offset, lower + 1.1 * swing, upper - 1.1 * swing)  # a margin for the tracking error
            return trajectories.Sinusoid(swing, frequency, phase, offset)
        return trajectories.Sinusoid(amplitude, frequency, phase, offset)
    if kind == "quintic":
        if not (np.isfinite(frequency) and frequency > 0):
            _fail(f"--frequency must be positive and finite for a quintic (it lasts 1/frequency s), got {frequency}")
        goal = offset + amplitude
        if start is None:  # the default move ends inside the joints' limits
            offset = np.clip(offset, lower, upper)
            goal = np.clip(offset + amplitude, lower, upper)
        return trajectories.Quintic(offset, goal, 0.0, 1.0 / frequency)
    if kind == "none":
        return None
    _fail(f"--trajectory must be sine, quintic or none, got '{kind}'")


PER_JOINT = "one number for every joint, or one per joint separated by commas"
Q0_HELP = (
    f"Start positions (rad or m): a configuration of the arm (qz, qn, ...) or {PER_JOINT}. The trajectory runs "
    "about it. Default: the arm's qz, or zeros, moved inside the joint limits (the default path then stays inside "
    "them)."
)
ANIMATE_HELP = (
    "Write an animation of the run to this .gif (or .mp4, with ffmpeg installed): the arm moving along the "
    "desired tool path, beside the tracking error against time."
)
SIMULATE_OUTPUT_HELP = (
    "Write ARM.png (the figure), ARM.csv (the samples) and ARM-report.md (the report table) into this folder "
    "(made if missing; its parent must exist)."
)


SIMULATE_TASK_HELP = (
    "Control in task coordinates instead of joints: position (the tool point), pose (the tool's position and "
    "orientation) or planar (its x, y). --controller computed-torque needs as many coordinates as joints, "
    "operational-space (redundant arms) as many or fewer, with the start as the null-space posture; --kp, --kv "
    "are one number each; --trajectory line (by --move and --turn over 1/--frequency s, a quintic law), circle "
    "(radius --amplitude, one turn in 1/--frequency s, starting at the tool) or none (hold the tool)."
)


def _default_start(arm: Robot) -> np.ndarray:
    return _inside_limits(arm, arm.configurations.get("qn", arm.configurations.get("qz", np.zeros(arm.n))))


def _inside_limits(arm: Robot, q: object) -> np.ndarray:
    """A default configuration moved inside the joints' limits (qz = 0 lies outside some arms' limits)."""
    lower, upper = arm.qlim
    return np.clip(np.asarray(q, dtype=float), lower, upper)


def _one_number(text: str, option: str) -> float:
    values = _values(text, option)
    if len(values) != 1:
        _fail(f"{option} takes one number with --task (the task coordinates share the gain), got {len(values)}")
    return float(values[0])


def _three(text: str, option: str) -> np.ndarray:
    values = np.asarray(_values(text, option), dtype=float)
    if values.shape != (3,):
        _fail(f"{option} takes three numbers x,y,z, got {len(values)}")
    return values


def _task_controller(
    arm: Robot, task: str, controller: str, kp: str, kv: str, trajectory: str, amplitude: float, frequency: float,
    start: np.ndarray, move: str, turn: str,
) -> TaskComputedTorque:  # fmt: skip
    """The task-space law of ``simulate --task``: the output, a path from the tool's start, and the law."""
    from armdyn import control, trajectories

    output = _task_output(task)
    gain_p, gain_v = (_one_number(value, option) for value, option in ((kp, "--kp"), (kv, "--kv")))
    y0 = output.value(arm, start)
    if not (np.isfinite(frequency) and frequency > 0):
        _fail(f"--frequency must be positive and finite for a task path (it lasts 1/frequency s), got {frequency}")
    if trajectory == "line":
        shift = _three(move, "--move")
        if task == "pose":
            from scipy.spatial.transform import Rotation

            begin = arm.tool_pose(start)
            end = begin.copy()
            end[:3, 3] += shift
            end[:3, :3] = Rotation.from_rotvec(_three(turn, "--turn")).as_matrix() @ begin[:3, :3]
            path: Line | Circle | PoseLine = trajectories.PoseLine(begin, end, 1.0 / frequency)
        else:
            path = trajectories.Line(tuple(y0), tuple(y0 + shift[: len(y0)]), 1.0 / frequency)
    elif trajectory == "circle":
        if task == "pose":
            _fail("--trajectory circle takes --task position or planar (a pose follows a line)")
        centre = y0.copy()
        centre[0] -= amplitude
        path = trajectories.Circle(tuple(centre), amplitude, 1.0 / frequency)
    elif trajectory == "none":
        if task != "pose":
            path = trajectories.Line(tuple(y0), tuple(y0), 1.0)
        else:
            pose = arm.tool_pose(start)
            path = trajectories.PoseLine(pose, pose, 1.0)
    else:
        _fail(f"--trajectory with --task must be line, circle or none, got {trajectory!r}")
    if controller == "computed-torque":
        return control.TaskComputedTorque(output, path, gain_p, gain_v)
    if controller == "operational-space":
        return control.OperationalSpaceControl(output, path, gain_p, gain_v, start, gain_p / 4, gain_v / 2)
    _fail(f"--controller with --task must be computed-torque or operational-space, got {controller!r}")


def _task_report(result: Result) -> _Sheet:
    """Print the report of a task-space run (a row per task coordinate) and return it."""
    task = cast("Tracking", result.task)
    unit = "m, rad" if task.output.startswith("ToolPose") else "m"
    labels = ["x", "y", "z", "rx", "ry", "rz"][: task.error.shape[1]]
    late = result.t >= min(1.0, result.t[-1])
    title = (f"{result.arm.name}, task {task.output}: {result.info['controller']}; {result.info['method']}, "
             f"{len(result.t) - 1} steps of {result.info['dt']:g} s")  # fmt: skip
    columns = ["coordinate", f"final y ({unit})", f"final error ({unit})", f"max |error| after 1 s ({unit})"]
    rows = [[label, f"{task.y[-1, i]:.6g}", f"{task.error[-1, i]:.3g}", f"{np.abs(task.error[late, i]).max():.3g}"]
            for i, label in enumerate(labels)]  # fmt: skip
    sheet = _Sheet(title, columns, rows)
    console.print(sheet.rich())
    return sheet


VIEW_HTML_HELP = (
    "Write the scene (and the run) as one self-contained offline page to this .html file, then exit (no server "
    "is left running)."
)
VIEW_PORT_HELP = "The viewer's port on 127.0.0.1 (0, the default: a free port)."
SIMULATE_VIEW_HELP = (
    "Play the run back in 3-D in the browser (a viser page on 127.0.0.1: time slider, play/pause, desired path and "
    "trace, torques as link colours) until Ctrl-C. Needs the extra view: pip install 'armdyn[view]'."
)
VIEW_OVERLAYS_HELP = "Overlays shown at the start, separated by commas: inertia, lambda, manipulability, com, gravity."


def _page_file(path: str, option: str) -> Path:
    """A saved page's file, checked as ``_output_file``, ending in .html or .htm."""
    target = _output_file(path, option)
    if target.suffix.lower() not in (".html", ".htm"):
        _fail(f"{option} {path}: the page is written as HTML; give a file ending in .html")
    return target


def _wait_for_ctrl_c() -> None:
    """Block until Ctrl-C (its KeyboardInterrupt ends the wait)."""
    while True:
        time.sleep(1.0)


def _in_browser(make: Callable[[], Any], page_file: Path | None, page: str | None, serve: bool) -> None:
    """Start a viewer with ``make()``: write its page to ``page_file`` and close it, or (``serve``) print its address
    and serve it until Ctrl-C."""
    _activity.status("starting the 3-D viewer")
    viewer = make()
    try:
        if page_file is not None:
            _activity.status(f"writing the page {page}")
            viewer.save_html(page_file)
            console.print(f"wrote {page}")
        if serve:
            _activity.stop()
            console.print(f"viewer: open {viewer.url} in a browser (Ctrl-C to stop)")
            _wait_for_ctrl_c()
    except KeyboardInterrupt:
        pass
    finally:
        viewer.close()


CONVERT_FORMATS = {".urdf": "URDF", ".xml": "MuJoCo MJCF", ".mjcf": "MuJoCo MJCF", ".json": "armdyn's model file"}


@app.command()
def convert(
    name: str = typer.Argument(..., help=ARM_HELP),
    output: str = typer.Argument(
        ..., help="The file to write, its format by its suffix: .urdf, .xml or .mjcf (MuJoCo), .json (armdyn's)."
    ),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    actuators: str | None = typer.Option(
        None, "--actuators", help="With an MJCF output, write the arm's drives too (as --actuators of 'show')."
    ),
) -> None:
    """Write an arm as URDF, MuJoCo MJCF or armdyn's model file, with the same dynamics (M, C, G, friction, motors):
    armdyn.load_urdf, armdyn.load_mjcf and armdyn.load_arm read it back; MuJoCo and Pinocchio compute its dynamics."""
    target = _output_file(output, "OUTPUT")
    suffix = target.suffix.lower()
    if suffix not in CONVERT_FORMATS:
        _fail(f"OUTPUT {output}: the suffix must be one of {', '.join(CONVERT_FORMATS)} (URDF, MJCF, armdyn's JSON)")
    if actuators is not None and suffix not in (".xml", ".mjcf"):
        _fail(f"--actuators: only an MJCF file holds drives (as MuJoCo dcmotor actuators); {output} is not one")
    arm = _arm(name, strict)
    if suffix == ".urdf":
        arm.to_urdf(target)
    elif suffix == ".json":
        from armdyn.io.model_file import save_arm

        save_arm(arm, target)
    else:
        from armdyn.io.mjcf_out import to_mjcf

        to_mjcf(_actuated(arm, name, actuators) if actuators is not None else arm, target)
    console.print(f"wrote {output} ({CONVERT_FORMATS[suffix]}, {arm.name}, n = {arm.n})")


@app.command()
def view(
    name: str = typer.Argument(..., help=ARM_HELP),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    port: int = typer.Option(0, "--port", help=VIEW_PORT_HELP),
    html: str | None = typer.Option(None, "--html", help=VIEW_HTML_HELP),
    q: str | None = typer.Option(None, "--q", help=DRAW_Q_HELP.replace("--draw draws", "the viewer shows first")),
    overlays: str | None = typer.Option(None, "--overlays", help=VIEW_OVERLAYS_HELP),
) -> None:
    """Show an arm in 3-D in the browser (a viser page on 127.0.0.1): its URDF meshes, MJCF geoms or capsules, joint
    sliders, the tool frame and the overlays; with --html, write the scene as one offline page and exit."""
    page_file = _page_file(html, "--html") if html is not None else None
    arm = _arm(name, strict)
    configuration = _joint_state(q, "--q", arm) if q is not None else None
    chosen = tuple(part.strip() for part in overlays.split(",")) if overlays is not None else ()
    if any(not part for part in chosen):
        _fail(f"--overlays {overlays!r}: give overlay names separated by commas, such as lambda,gravity")
    _in_browser(lambda: arm.view(port=port, q=configuration, overlays=chosen), page_file, html, page_file is None)


@app.command()
def simulate(
    name: str = typer.Argument(..., help=ARM_HELP),
    controller: str | None = typer.Option(
        None,
        help="computed-torque (the default), pd-gravity, pid or none; with --actuators pid (the default) or "
        "computed-torque; with --task computed-torque or operational-space.",
    ),
    kp: str | None = typer.Option(
        None, help=f"Proportional gain: {PER_JOINT} (400,400,400,50,50,50). Default 100; {DRIVE_GAINS}."
    ),
    kv: str | None = typer.Option(None, help=f"Derivative gain: {PER_JOINT}. Default 20; {DRIVE_GAINS}."),
    ki: str = typer.Option("0", help=f"Integral gain: {PER_JOINT}."),
    trajectory: str | None = typer.Option(
        None,
        help="sine (about the start, the default), quintic (from it) or none (hold it); with --task: line "
        "(the default), circle or none.",
    ),
    amplitude: float = typer.Option(0.1, help="Trajectory amplitude (rad or m)."),
    frequency: float = typer.Option(0.5, help="Trajectory frequency (Hz)."),
    t_final: float = typer.Option(5.0, "--t-final", help="Simulated time (s)."),
    dt: float = typer.Option(1e-3, help="Integration step (s)."),
    method: str = typer.Option("rk4", help="rk4 or an adaptive solver: rk45, rk23, dop853, radau, bdf, lsoda."),
    period: float = typer.Option(0.0, help="Digital control sample period (s); 0 for continuous."),
    torque_limit: str = typer.Option(
        "inf", "--torque-limit", help=f"Saturate torques at +-this (N m or N): {PER_JOINT}; inf for none."
    ),
    disturbance: str = typer.Option("0", help=f"A constant disturbance torque tau_d (N m or N): {PER_JOINT}."),
    q0: str | None = typer.Option(None, "--q0", help=Q0_HELP),
    qd0: str | None = typer.Option(None, "--qd0", help=f"Start velocities (rad/s or m/s): {PER_JOINT}. Default 0."),
    task: str | None = typer.Option(None, "--task", help=SIMULATE_TASK_HELP),
    move: str = typer.Option("0.1,0,0", "--move", help="Task line: the tool's displacement dx,dy,dz (m)."),
    turn: str = typer.Option("0,0,0", "--turn", help="Task line of a pose: the tool's rotation rx,ry,rz (rad)."),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    plot: str | None = typer.Option(None, help="Write the figure to this PNG file."),
    csv: str | None = typer.Option(None, help="Write the samples to this CSV file."),
    animate: str | None = typer.Option(None, "--animate", help=ANIMATE_HELP),
    output: str | None = typer.Option(None, "--output", "-o", help=SIMULATE_OUTPUT_HELP),
    actuators: str | None = typer.Option(None, "--actuators", help=ACTUATORS_HELP + " " + SIMULATE_DRIVES_HELP),
    joint_limits: str = typer.Option(
        "warn",
        "--joint-limits",
        help="What the arm's joint limits do: warn (a warning when a joint leaves them), stop (end the run there), "
        "spring (stiff spring-damper stops, as MuJoCo's soft limits; not with --actuators) or ignore.",
    ),
    view: bool = typer.Option(False, "--view", help=SIMULATE_VIEW_HELP),
    html: str | None = typer.Option(None, "--html", help=VIEW_HTML_HELP),
    port: int = typer.Option(0, "--port", help=VIEW_PORT_HELP),
) -> None:
    """Simulate an arm under control and report the tracking errors (with units); with --task, control
    in task coordinates (Section 3.5) along a line or a circle of the tool; with --actuators, through its
    drives' dynamics (Section 3.6)."""
    from armdyn.simulation import RunInterrupted
    from armdyn.simulation import simulate as run

    if controller is None:
        controller = "pid" if actuators is not None else "computed-torque"
    plot_file = _output_file(plot, "--plot") if plot else None
    csv_file = _output_file(csv, "--csv") if csv else None
    animation_file = _animation_file(animate, "--animate") if animate else None
    page_file = _page_file(html, "--html") if html is not None else None
    folder = _output_folder(output, "--output") if output else None
    arm = _arm(name, strict)
    start = _joint_state(q0, "--q0", arm) if q0 is not None else None
    velocity = _joint_state(qd0, "--qd0", arm) if qd0 is not None else None
    tau_d = np.broadcast_to(_per_joint(disturbance, "--disturbance", arm.n), (arm.n,))
    driven: ActuatedArm | None = None
    law: object  # the controller: joint-space, task-space or the drives'
    if actuators is not None:  # the arm through its drives' dynamics
        options = (("--task", task is not None), ("--period", period != 0), ("--torque-limit", torque_limit != "inf"),
                   ("--method", method != "rk4"), ("--disturbance", bool(np.any(tau_d))))  # fmt: skip
        refused = [option for option, given in options if given]
        if refused:
            _fail(f"{', '.join(refused)} do not apply with --actuators (the drives' dynamics run by compiled RK4; "
                  "their limits are the drives' voltage and current limits)")  # fmt: skip
        driven = _actuated(arm, name, actuators)
        law = _drive_controller(driven, actuators, controller, kp, kv, ki)
        desired = _trajectory("sine" if trajectory is None else trajectory, arm, amplitude, frequency, start)
        if start is None and desired is not None:
            start = desired(0.0, arm.n)[0]
    elif task is not None:
        if period != 0 or torque_limit != "inf":
            _fail("--period and --torque-limit apply to joint-space control, not to --task")
        start = start if start is not None else _default_start(arm)
        path = "line" if trajectory is None else trajectory
        kp, kv = ("100" if kp is None else kp), ("20" if kv is None else kv)
        law = _task_controller(arm, task, controller, kp, kv, path, amplitude, frequency, start, move, turn)
        desired = None
    else:
        named = (("100" if kp is None else kp, "--kp"), ("20" if kv is None else kv, "--kv"), (ki, "--ki"))
        gain_p, gain_v, gain_i = (_per_joint(value, option, arm.n) for value, option in named)
        law = _controller(controller, gain_p, gain_v, gain_i, period, _per_joint(torque_limit, "--torque-limit", arm.n))
        desired = _trajectory("sine" if trajectory is None else trajectory, arm, amplitude, frequency, start)
    if start is None and desired is not None and controller == "none":
        start = desired(0.0, arm.n)[0]
    if start is None:  # the arm starts where the path starts from, inside its limits
        start = _inside_limits(arm, arm.configurations.get("qz", np.zeros(arm.n)))
    interrupted = False
    try:
        if driven is not None:
            _activity.status(f"simulating {t_final:g} s of {arm.name} with its drives (compiled RK4)")
            result = cast("Result", run(driven, law, desired, t_final=t_final, dt=dt, q0=start, qd0=velocity,
                                        joint_limits=joint_limits))  # fmt: skip
        else:
            progress = _activity.bar(f"simulating {t_final:g} s of {arm.name} ({method})")
            tau_d_run = None if not np.any(tau_d) else tau_d.copy()
            result = cast("Result", run(arm, law, desired, t_final=t_final, dt=dt, method=method, q0=start,
                                        qd0=velocity, disturbance=tau_d_run, progress=progress,
                                        joint_limits=joint_limits))  # fmt: skip
    except RunInterrupted as stop:  # Ctrl-C: what was computed is reported and written, then exit 130
        _activity.stop()
        result, interrupted = cast("Result", stop.result), True
        if len(result.t) < 2:
            _error_line("interrupted before the first samples: nothing to write")
            raise typer.Exit(INTERRUPTED) from None
        _error_line(f"interrupted at t = {result.t[-1]:.6g} s of {t_final:g} s: the report and the files below "
                    "hold the run up to then")  # fmt: skip
    _check_finite(result)
    report = _report(result) if result.task is None else _task_report(result)
    reports = [report] + ([_drive_report(result, driven)] if driven is not None else [])
    if folder is not None:
        _make_folder(folder)
        stem = re.sub(r"[^\w-]+", "_", arm.name).strip("_") or "arm"
        (result.plot if result.task is None else result.plot_task)(folder / f"{stem}.png")
        result.to_csv(folder / f"{stem}.csv")
        _write_sheets(folder / f"{stem}-report.md", reports)
        console.print(f"wrote {folder / f'{stem}.png'}, {folder / f'{stem}.csv'} and {folder / f'{stem}-report.md'}")
    if plot_file is not None:
        (result.plot if result.task is None else result.plot_task)(plot_file)
        console.print(f"wrote {plot}")
    if csv_file is not None:
        result.to_csv(csv_file)
        console.print(f"wrote {csv}")
    if animation_file is not None:
        _activity.status(f"writing the animation {animate}")
        result.animate(animation_file)
        console.print(f"wrote {animate}")
    if page_file is not None or view:
        limits = _per_joint(torque_limit, "--torque-limit", arm.n) if driven is None and task is None else np.inf
        finite = bool(np.all(np.isfinite(limits)))
        _in_browser(lambda: result.view(port=port, torque_limits=limits if finite else None), page_file, html, view)
    if interrupted:
        raise typer.Exit(INTERRUPTED)


def _drive_controller(
    driven: ActuatedArm, kind: str, controller: str, kp: str | None, kv: str | None, ki: str
) -> DrivePID | CurrentComputedTorque:
    """The drive-level law of ``simulate --actuators``."""
    from armdyn import control

    n = driven.n
    if controller == "pid":
        defaults = ("0.1", "0") if kind == "hydraulic" else ("20", "0.5")
        named = ((kp, defaults[0], "--kp"), (kv, defaults[1], "--kv"), (ki, "0", "--ki"))
        gains = (_per_joint(default if value is None else value, option, n) for value, default, option in named)
        return control.DrivePID(*gains)
    if controller == "computed-torque":
        if kind != "dc":
            _fail(f"--controller computed-torque with --actuators runs through current commands: it needs dc drives, "
                  f"not {kind} (use --controller pid)")  # fmt: skip
        named = ((kp, "100", "--kp"), (kv, "20", "--kv"), (ki, "0", "--ki"))
        gains = (_per_joint(default if value is None else value, option, n) for value, default, option in named)
        return control.CurrentComputedTorque(*gains)
    _fail(f"--controller with --actuators must be pid or computed-torque, got '{controller}'")


def _drive_report(result: Result, driven: ActuatedArm) -> _Sheet:
    """Print what the drives did (peak input, current, load pressure) and return it as a sheet."""
    record, joints = cast("DriveRecord", result.drives), driven.robot.joint_names
    columns = ["joint", "drive", "max |input| (V or A)", "input limit", "max |i| (A)", "i limit (A)",
               "max |P_L| (MPa)"]  # fmt: skip
    sheet = _Sheet(f"{driven.name}: drives ({result.info['substeps']} RK4 steps per sample)", columns, [])
    names = record.names
    for j, drive in enumerate(driven.drives):
        current = f"i {joints[j]}" in names
        pressure = f"PL {joints[j]}" in names
        limit = getattr(drive, "voltage_limit", None) or getattr(drive, "current_limit", None)
        sheet.rows.append([
            joints[j], drive.name, f"{np.abs(record.v[:, j]).max():.4g}", _number(limit),
            f"{np.abs(record.x[:, names.index(f'i {joints[j]}')]).max():.4g}" if current else "-",
            _number(drive.current_limit) if current else "-",
            f"{np.abs(record.x[:, names.index(f'PL {joints[j]}')]).max() / 1e6:.4g}" if pressure else "-",
        ])  # fmt: skip
    console.print(sheet.rich())
    return sheet


def _distribution(text: str | None, option: str, relative: bool = False) -> object:
    """A study's distribution from the command line: "a:b" (uniform on [a, b]), "x%" (uniform on
    [-x/100, x/100], a relative error), or one number (that constant; for a relative error +-x)."""
    from armdyn.study import Uniform

    if text is None:
        return None
    try:
        if text.strip().endswith("%"):
            half = float(text.strip()[:-1]) / 100
            return Uniform(-half, half)
        if ":" in text:
            low, high = (catalog._value(part.strip(), option) for part in text.split(":", 1))
            return Uniform(low, high)
        value = catalog._value(text.strip(), option)
    except ModelError as error:
        _fail(f"{option} {text!r}: {error}")
    except ValueError:
        _fail(f"{option} {text!r}: give a:b (uniform), x% or a number")
    return Uniform(-abs(value), abs(value)) if relative else Uniform(value, value)


STUDY_SPEC_HELP = (
    "The requirement each run must meet: clauses 'quantity < bound' joined by 'and'; quantities final_error, "
    "max_error_after (max-error-after-1s sets the window), rms_error, max_tau (largest over joints, or one joint: "
    "'max_error_after q2'), payload, mass_scale, friction_scale."
)


@app.command()
def study(
    name: str = typer.Argument(..., help=ARM_HELP),
    runs: int = typer.Option(1000, "--runs", help="The number of runs."),
    payload: str | None = typer.Option(None, "--payload", help="Payload at the tool (kg): a:b uniform, or one mass."),
    mass_error: str | None = typer.Option(
        None, "--mass-error", help="Each link's relative mass error: x% (uniform +-x %), a:b, or one number (+-)."
    ),
    friction_error: str | None = typer.Option(
        None, "--friction-error", help="Each joint's relative friction error, as --mass-error."
    ),
    start_error: str | None = typer.Option(
        None, "--start-error", help="Offset of each joint's start (rad or m): a:b, or one number (+-)."
    ),
    controller: str = typer.Option("computed-torque", help="computed-torque, pd-gravity or pid (on the nominal arm)."),
    kp: str = typer.Option("100", help=f"Proportional gain: {PER_JOINT}."),
    kv: str = typer.Option("20", help=f"Derivative gain: {PER_JOINT}."),
    ki: str = typer.Option("0", help=f"Integral gain: {PER_JOINT}."),
    trajectory: str = typer.Option("sine", help="sine (about the start), quintic (from it) or none (hold it)."),
    amplitude: float = typer.Option(0.1, help="Trajectory amplitude (rad or m)."),
    frequency: float = typer.Option(0.5, help="Trajectory frequency (Hz)."),
    t_final: float = typer.Option(5.0, "--t-final", help="Each run's length (s)."),
    dt: float = typer.Option(1e-3, help="RK4 step (s)."),
    spec: str = typer.Option("max-error-after-1s<1e-3", "--spec", help=STUDY_SPEC_HELP),
    confidence: float = typer.Option(0.95, help="Confidence of the interval."),
    seed: int = typer.Option(0, help="The seed: the same seed gives the same runs wherever they run."),
    block: int = typer.Option(1000, help="Runs per block (the unit of sampling, of work and of files)."),
    scheduler: str = typer.Option("local", help="local (this process), local-cluster (Dask) or tcp://host:port."),
    workers: int = typer.Option(2, help="Worker processes of --scheduler local-cluster."),
    output: str | None = typer.Option(
        None, "--out", "-o", help="A folder for the blocks (Parquet), made if missing: a rerun resumes there."
    ),
    damaged: str = typer.Option(
        "recompute", help="A damaged block found in --out on a rerun: recompute (with a warning) or refuse."
    ),
    plot: str | None = typer.Option(None, help="Write the figure (histograms of the spec's quantities) to this PNG."),
    q0: str | None = typer.Option(None, "--q0", help=Q0_HELP),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
) -> None:
    """A Monte Carlo study: the probability that the controlled arm meets a spec under uncertain payload,
    masses, friction and start, with its Clopper-Pearson interval; locally or on a Dask cluster."""
    from armdyn.study import Study, runs_needed

    plot_file = _output_file(plot, "--plot") if plot else None
    folder = _output_folder(output, "--out") if output else None
    arm = _arm(name, strict)
    start = _joint_state(q0, "--q0", arm) if q0 is not None else _default_start(arm)
    named = ((kp, "--kp"), (kv, "--kv"), (ki, "--ki"))
    gain_p, gain_v, gain_i = (_per_joint(value, option, arm.n) for value, option in named)
    if controller not in ("computed-torque", "pd-gravity", "pid"):
        _fail(f"--controller must be computed-torque, pd-gravity or pid, got '{controller}'")
    if damaged not in ("recompute", "refuse"):
        _fail(f"--damaged must be recompute or refuse, got '{damaged}'")
    law = _controller(controller, gain_p, gain_v, gain_i, 0.0, np.inf)
    desired = _trajectory(trajectory, arm, amplitude, frequency, start)
    declared = Study(arm, law, desired, spec=spec, t_final=t_final, dt=dt, q0=start, block=block,
                     payload=_distribution(payload, "--payload"),
                     mass_error=_distribution(mass_error, "--mass-error", relative=True),
                     friction_error=_distribution(friction_error, "--friction-error", relative=True),
                     start_error=_distribution(start_error, "--start-error", relative=True))  # fmt: skip
    if scheduler != "local":
        _activity.status(f"starting the study on {scheduler}")
    progress = _activity.bar(f"{runs} runs of {arm.name} ({scheduler})")
    result = declared.run(runs, seed=seed, scheduler=None if scheduler == "local" else scheduler, out=folder,
                          confidence=confidence, workers=workers, progress=progress, damaged=damaged)  # fmt: skip
    _activity.stop()
    if "dashboard" in result.info:
        console.print(f"Dask dashboard: {result.info['dashboard']} ({result.info['workers']} workers)")
    estimate = result.estimate
    sheet = _Sheet(f"{arm.name}: {spec}", ["quantity", "value"], [
        ["runs (finished)", f"{estimate.runs} ({int(cast(Any, result.table)['finished'].sum())})"],
        ["P(spec holds)", f"{estimate.probability:.4f}"],
        [f"{estimate.confidence:.0%} interval (Clopper-Pearson)", f"[{estimate.low:.4f}, {estimate.high:.4f}]"],
        [f"runs for +-0.01 at {estimate.confidence:.0%} (Hoeffding)", str(runs_needed(0.01, estimate.confidence))],
        ["blocks computed / read from --out", f"{result.info['computed']} / {result.info['read']}"],
    ])  # fmt: skip
    console.print(sheet.rich(justify="left"))
    if plot_file is not None:
        result.plot(plot_file)
        console.print(f"wrote {plot}")


def _check_finite(result: Result) -> None:
    """A ModelError when a run diverged (its state became NaN or infinite)."""
    finite = np.isfinite(result.q).all(axis=-1) & np.isfinite(result.qd).all(axis=-1)
    if not finite.all():
        t = result.t[int(np.argmin(finite))]
        _fail(
            f"the simulation diverged: the state is not finite from t = {t:.6g} s (try a smaller --dt or lower gains)"
        )


def _report(result: Result) -> _Sheet:
    """Print the report of a run (a table per joint, with units) and return it."""
    arm = result.arm
    position, torque = _units(arm, "rad", "m"), _units(arm, "N m", "N")
    columns = ["joint", f"final q ({position})", f"final error ({position})", f"max |error| after 1 s ({position})",
               f"max |tau| ({torque})"]  # fmt: skip
    title = f"{arm.name}: {result.info['method']}, {len(result.t) - 1} steps of {result.info['dt']:g} s"
    sheet = _Sheet(title, columns, [])
    late = result.t >= min(1.0, result.t[-1])
    for i, joint in enumerate(arm.joint_names):
        error = result.error
        sheet.rows.append([
            joint,
            f"{result.q[-1, i]:.6g}",
            "-" if error is None else f"{error[-1, i]:.3g}",
            "-" if error is None else f"{np.abs(error[late, i]).max():.3g}",
            f"{np.abs(result.tau[:, i]).max():.4g}",
        ])  # fmt: skip
    console.print(sheet.rich())
    return sheet


@app.command()
def demo(
    output: str = typer.Option(
        "out",
        "--output",
        "-o",
        help="Folder for demo.png, demo.csv, demo.gif and demo-drives.png (made if missing; its parent must exist).",
    ),
) -> None:
    """The chapter end to end on the RR arm of Example 3.2-2: closed form, properties, Example 4.4-1, task
    space (Section 3.5) and the arm through its DC motors (Section 3.6)."""
    from armdyn import control, trajectories
    from armdyn.properties import check as check_properties
    from armdyn.simulation import simulate as run
    from armdyn.symbolic import derive as derive_closed_form

    folder = _output_folder(output, "--output")
    _activity.status("deriving the closed form of the two-link planar arm")
    form = derive_closed_form(catalog.two_link_planar(symbolic=True), method="lagrange")
    console.rule("[bold]armdyn: Chapter 3 on the two-link planar elbow arm (Example 3.2-2)")
    console.print(
        "The robot equation M(q) qdd + Vm(q, qd) qd + G(q) = tau, derived by the book's Lagrange-Euler route:\n"
    )
    print(form.pretty())
    console.rule("[bold]Table 3.3.1, for m1 = m2 = a1 = a2 = 1, |theta_i| <= pi/2 (Example 3.3-1)")
    arm = catalog.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
    _activity.status("checking Table 3.3.1")
    report = check_properties(arm, samples=200, limits=[(-np.pi / 2, np.pi / 2)] * 2)
    report.references.update(_book_values(arm, report.ranges))
    console.print(report.table())
    console.print(
        "bounds: " + ", ".join(f"{key} = {value:.4g} {report.units[key]}" for key, value in report.bounds.items()),
        highlight=False,
    )
    console.rule("[bold]Example 4.4-1: PD computed-torque control, kp = 100, kv = 20, RK4 with a 1 ms step")
    desired = trajectories.Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])
    progress = _activity.bar("simulating Example 4.4-1")
    result = cast(
        "Result", run(arm, control.ComputedTorque(100.0, 20.0), desired, t_final=5.0, dt=1e-3, progress=progress)
    )
    _report(result)
    _make_folder(folder)
    result.plot(folder / "demo.png", title="Example 4.4-1: PD computed-torque control of the two-link arm")
    result.to_csv(folder / "demo.csv")
    _activity.status("writing the animation of Example 4.4-1")
    result.animate(folder / "demo.gif", title="Example 4.4-1: PD computed-torque control of the two-link arm")
    console.print(f"wrote {folder / 'demo.png'}, {folder / 'demo.csv'} and {folder / 'demo.gif'} (the arm moving)")
    error = result.error
    assert error is not None  # the run tracks the demo's trajectory
    final = np.abs(error[-1])
    console.print(f"final tracking errors: e1 = {final[0]:.2e} rad, e2 = {final[1]:.2e} rad")
    _demo_task_space(arm)
    _demo_actuators(arm, desired, folder)


def _demo_task_space(arm: Robot) -> None:
    """The demo's Section 3.5: the tool's dynamics in Cartesian coordinates at one configuration."""
    from armdyn import task_space

    console.rule("[bold]Section 3.5: the tool point's dynamics in Cartesian coordinates, at q = (0.3, 1.2) rad")
    q, tool = np.array([0.3, 1.2]), task_space.PlanarPosition()
    for label, value, unit in (
        ("Mbar = J^-T M J^-1", task_space.task_inertia(arm, tool, q), "kg"),
        ("Gbar = J^-T G", task_space.task_gravity(arm, tool, q), "N"),
    ):
        console.print(f"{label} ({unit}):\n{np.array2string(np.asarray(value), precision=4)}", highlight=False)


def _demo_actuators(arm: Robot, desired: Sinusoid | Quintic | None, folder: Path) -> None:
    """The demo's Section 3.6: Example 3.6-1's poles and the arm driven through DC motors with their electrics."""
    from armdyn import actuators, control
    from armdyn.simulation import simulate as run

    console.rule("[bold]Section 3.6: Example 3.6-1 and the arm through its DC motors' electrics")
    _, denominator = actuators.example_3_6_1()
    poles = ", ".join(f"{pole.real:.3f}" for pole in np.sort(np.roots(denominator)))
    formula = "H(s) = k_m / ((L s + R)(J s + b_m) + k_m k_m')"
    console.print(f"Example 3.6-1: {formula}, poles {poles} (the book: -2.3, -8.7)")
    driven = actuators.representative_drives(arm, "dc")
    _activity.status("simulating the arm through its motors (compiled RK4 with the electrics)")
    result = cast("Result", run(driven, control.DrivePID(20.0, 0.5, 20.0), desired, t_final=5.0, dt=1e-3))
    _report(result)
    _drive_report(result, driven)
    result.plot(folder / "demo-drives.png", title="The two-link arm through DC motors: independent joint PID on "
                "the voltages, Example 4.4-1's path")  # fmt: skip
    console.print(f"wrote {folder / 'demo-drives.png'}")


def main() -> None:
    """Run the command line (the ``armdyn`` script): errors are one line on stderr (see the module docstring)."""
    app()


if __name__ == "__main__":
    main()


TASK_OUTPUTS = ("position", "pose", "planar")


@app.command()
def task(
    name: str = typer.Argument(..., help=ARM_HELP),
    coordinates: str = typer.Option(
        "position",
        "--coordinates",
        "-c",
        help="The task coordinates: 'position' (tool point, 3), 'pose' (tool position and angular velocity, 6) or "
        "'planar' (tool x, y, 2). With fewer coordinates than joints, Khatib's Lambda, mu and p instead.",
    ),
    q: str | None = typer.Option(None, "--q", help=f"The configuration (rad or m): a named one, or {PER_JOINT}."),
    qd: str | None = typer.Option(None, "--qd", help=f"Joint velocities (rad/s or m/s): {PER_JOINT}. Default 0."),
    damping: float | None = typer.Option(None, "--damping", help="Damped least-squares inverse near a singular J."),
    max_condition: float | None = typer.Option(
        None, "--max-condition", help="The largest cond J computed without --damping (default 1e8)."
    ),
    strict: bool = typer.Option(True, "--strict/--no-strict", help=STRICT_HELP),
    output: str | None = typer.Option(
        None, "--output", "-o", help="Also write the tables to this file: .csv, .md or .txt (by its suffix)."
    ),
) -> None:
    """The robot equation in task coordinates (Section 3.5): Mbar, Nbar and Gbar at a state, and cond J."""

    target = _table_file(output, "--output") if output else None
    arm = _arm(name, strict)
    chosen = _task_output(coordinates, "--coordinates")
    start = _joint_state(q, "--q", arm) if q is not None else np.zeros(arm.n)
    rates = np.broadcast_to(_per_joint(qd, "--qd", arm.n), (arm.n,)).copy() if qd is not None else np.zeros(arm.n)
    options: dict[str, Any] = {} if damping is None else {"damping": damping}
    if max_condition is not None:
        options["max_condition"] = max_condition
    try:
        _task_tables(arm, coordinates, chosen, start, rates, options, target)
    except SingularError as singular:  # the advice in the command's own options
        advice = str(singular).replace("raise max_condition", "raise --max-condition")
        _fail(advice.replace("pass damping=...", "give --damping VALUE"))


def _task_tables(
    arm: Robot, coordinates: str, chosen: TaskOutput, start: np.ndarray, rates: np.ndarray, options: dict[str, Any],
    target: Path | None,
) -> None:  # fmt: skip
    """The tables of ``armdyn task``: the task-space inertia, bias and gravity at a state, and cond J."""
    from armdyn import task_space

    labels = {"position": ["x", "y", "z"], "pose": ["x", "y", "z", "wx", "wy", "wz"], "planar": ["x", "y"]}[coordinates]
    if len(labels) < arm.n:  # a redundant arm: Khatib's operational space
        space = task_space.operational_space(arm, chosen, start, rates, **options)
        inertia, names = (
            space.Lambda,
            (
                f"Lambda = (J M^-1 J^T)^-1 ({arm.name}, {coordinates}, m = {len(labels)} < n = {arm.n})",
                "mu = Jbar^T Vm qd - Lambda Jdot qd and p = Jbar^T G",
            ),
        )
        bias, gravity, heads = space.mu, space.p, ["coordinate", "mu", "p"]
    else:
        inertia = task_space.task_inertia(arm, chosen, start, **options)
        bias = task_space.task_nonlinear(arm, chosen, start, rates, **options)
        gravity = task_space.task_gravity(arm, chosen, start, **options)
        names = (
            f"Mbar = J^-T M J^-1 ({arm.name}, {coordinates})",
            "Nbar = J^-T (N - M J^-1 Jdot qd) and Gbar = J^-T G",
        )
        heads = ["coordinate", "Nbar", "Gbar"]
    condition = float(task_space.condition_number(arm, chosen, start))
    sheets = [
        _Sheet(names[0], ["", *labels],
               [[label, *(_number(v, 6) for v in row)] for label, row in zip(labels, inertia, strict=True)]),
        _Sheet(names[1], heads,
               [[label, _number(n, 6), _number(g, 6)] for label, n, g in zip(labels, bias, gravity, strict=True)]),
    ]  # fmt: skip
    for sheet in sheets:
        console.print(sheet.rich())
    state = f"q = {_vector(start)}, qd = {_vector(rates)}"
    damping = options.get("damping")
    console.print(f"{state}; cond J = {condition:.4g}" + ("" if damping is None else f" (damping {damping:g})"))
    if target is not None:
        _write_sheets(target, sheets, [state, f"cond J = {condition:.6g}"])
        console.print(f"wrote {target}")
