"""Closed-form equations: symbolic derivation, LaTeX, and code generation (BOOK.md section 4)."""

from armdyn.symbolic.closed_form import ClosedForm, derive

__all__ = ["ClosedForm", "derive"]
