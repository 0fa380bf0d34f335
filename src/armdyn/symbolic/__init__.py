"""Closed-form equations: symbolic derivation, LaTeX, and code generation (BOOK.md sections 4, 6 and 7)."""

from armdyn.symbolic.actuated import ActuatedClosedForm, SymbolicMotor, motor_symbols
from armdyn.symbolic.closed_form import ClosedForm, derive
from armdyn.symbolic.newton_euler import CompiledCode, GeneratedCode, generate_code
from armdyn.symbolic.task import TaskClosedForm

__all__ = [
    "ActuatedClosedForm",
    "ClosedForm",
    "CompiledCode",
    "GeneratedCode",
    "SymbolicMotor",
    "TaskClosedForm",
    "derive",
    "generate_code",
    "motor_symbols",
]
