"""How the robot equation is computed: free functions of an arm, one algorithm per file.

Importing this package first installs the cache locator of armdyn's compiled kernels
(cache.py), before any kernel is compiled or loaded from disk.
"""

from armdyn.dynamics import cache

cache.install()
