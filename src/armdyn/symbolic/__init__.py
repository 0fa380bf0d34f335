"""Closed-form equations: symbolic derivation, LaTeX, and code generation (Sections 3.2, 3.5 and 3.6)."""

from armdyn.symbolic.actuated import ActuatedClosedForm, SymbolicMotor, motor_symbols
from armdyn.symbolic.backends import CasadiCode, JaxCode, generate_code
from armdyn.symbolic.closed_form import ClosedForm, derive
from armdyn.symbolic.newton_euler import CompiledCode, GeneratedCode
from armdyn.symbolic.task import TaskClosedForm

__all__ = [
    "ActuatedClosedForm",
    "CasadiCode",
    "ClosedForm",
    "CompiledCode",
    "GeneratedCode",
    "JaxCode",
    "SymbolicMotor",
    "TaskClosedForm",
    "derive",
    "generate_code",
    "motor_symbols",
]
