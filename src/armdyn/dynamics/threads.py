"""The threads of batch calls: how many, and what they do between calls.

Batch calls run their states in parallel on Numba's OpenMP threads. By default an OpenMP
thread spins for a while after a parallel region ends, waiting for the next: it keeps a core
busy and slows the single-threaded work that follows (a control loop that mixes batch and
one-state calls ran 1.5-2x slower for about 10 ms after each batch). armdyn therefore asks
OpenMP to let idle threads sleep (OMP_WAIT_POLICY=PASSIVE) unless the user has set the
policy, before the OpenMP runtime starts. The number of threads is Numba's: the
NUMBA_NUM_THREADS environment variable before start-up (default: every core), or
``set_threads`` at any time (at most that number).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # read once, when the OpenMP runtime loads


def set_threads(count: int) -> None:
    """Run batch calls on ``count`` threads from now on (in this thread).

    Parameters
    ----------
    count : int
        From 1 to the number Numba started with (NUMBA_NUM_THREADS, by default the cores).

    Raises
    ------
    armdyn.ModelError
        When ``count`` is below 1 or above Numba's thread count.
    TypeError
        When ``count`` is not an integer.
    """
    import numba

    from armdyn import inputs

    largest = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]  # Numba sets its config at run time
    count = inputs.integer(count, "count", 1, largest, " (NUMBA_NUM_THREADS at start-up)")
    numba.set_num_threads(count)


def threads() -> int:
    """The number of threads batch calls run on (in this thread).

    Returns
    -------
    int
        Numba's current thread count.
    """
    import numba

    return numba.get_num_threads()
