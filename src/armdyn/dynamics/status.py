"""The status codes the compiled one-state kernels return, named once.

A kernel returns OK when it has computed its result; any other code means it has written
nothing the caller should read, and the caller's general path (armdyn.inputs and the checks
beside it) decides again and raises the error that names the argument and the rule broken.
Numba reads these module-level integers as compile-time constants.
"""

from __future__ import annotations

OK = 0
"""Computed."""
WRONG_LENGTH = 1
"""State argument k (0 for the first) does not have n values: WRONG_LENGTH + k (1, 2, 3)."""
NOT_FINITE = 11
"""State argument k holds NaN, infinity or a value of inputs.LARGEST_STATE or more in magnitude:
NOT_FINITE + k (11, 12, 13)."""
WRONG_SHAPE = 4
"""A result (or an option array such as the Coulomb smoothing eps) does not have its shape."""
BAD_LINK = 5
"""A link index that is neither frames.TOOL nor the index of a link."""
BAD_FRAME = 6
"""A frame that is neither frames.WORLD nor frames.LOCAL."""
TASK_SINGULAR = 7
"""The task Jacobian J is not certified regular (operational.py)."""
BAD_ROWS = 8
"""Task rows that are not 1 to n indices among 0-5 (operational.py)."""
NOT_SQUARE = 9
"""A square task quantity asked of an output with m != n (operational.py)."""
SHARED = 10
"""A result's memory lies within the span of another result or of a state it is computed from (the
caller's general path checks exactly and names them)."""
SINGULAR = 50
"""M(q) is singular (forward dynamics and its derivatives)."""
