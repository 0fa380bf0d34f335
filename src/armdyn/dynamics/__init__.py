"""How the robot equation is computed: free functions of an arm, one algorithm per file.

Importing this package first installs the cache locator of armdyn's compiled kernels
(cache.py), before any kernel is compiled or loaded from disk, and sets the idle policy of
the batch threads (threads.py) before the OpenMP runtime starts.
"""

from armdyn.dynamics import cache, threads  # noqa: F401 - threads sets the idle policy on import

cache.install()
