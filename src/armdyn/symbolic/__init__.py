"""Closed-form equations: symbolic derivation, LaTeX, and code generation (BOOK.md sections 4 and 6)."""

from armdyn.symbolic.closed_form import ClosedForm, derive
from armdyn.symbolic.task import TaskClosedForm

__all__ = ["ClosedForm", "TaskClosedForm", "derive"]
