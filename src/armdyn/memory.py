"""How much memory this process can still fill, so that a request too large for it is refused
before anything is allocated (an allocation the system grants lazily would otherwise fail
later, or take the process down, when it is filled)."""

from __future__ import annotations

import os

from armdyn.errors import ModelError

SMALL = 64 * 2**20  # bytes below which a request is not checked (reading the limits costs tens of us)


def affordable(nbytes: float, what: str) -> None:
    """A ModelError naming ``what`` when it needs more bytes than this process can still fill.

    Parameters
    ----------
    nbytes : float
        The bytes asked for.
    what : str
        What asks for them, for the message ("a batch of 10 states").

    Raises
    ------
    armdyn.ModelError
        When ``nbytes`` exceeds ``available()``.
    """
    if nbytes < SMALL:
        return
    room = available()
    if room is not None and nbytes > room:
        raise ModelError(
            f"{what} needs {size(nbytes)}, more than the {size(room)} of memory available: split it into smaller parts"
        )


def size(nbytes: float) -> str:
    """A number of bytes for a message: "14.6 GiB"."""
    for unit in ("B", "KiB", "MiB", "GiB"):
        if nbytes < 1024:
            return f"{nbytes:.3g} {unit}"
        nbytes /= 1024
    return f"{nbytes:.3g} TiB"


def available() -> int | None:
    """The bytes this process can still fill: the least of the system's available memory, a
    cgroup's limit (a container's) and an address-space limit (RLIMIT_AS), each left out where
    the system does not say it; None when it says none of them."""
    found = [m for m in (_system(), _cgroup(), _address_space()) if m is not None]
    return min(found) if found else None


def _system() -> int | None:
    """Linux's MemAvailable (free memory plus the caches it can drop), else the free physical memory."""
    try:
        with open("/proc/meminfo", encoding="ascii") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def _cgroup() -> int | None:
    """What a cgroup v2 memory limit leaves (a container can be killed beyond it, MemAvailable notwithstanding)."""
    try:
        with open("/sys/fs/cgroup/memory.max", encoding="ascii") as handle:
            limit = handle.read().strip()
        if limit == "max":
            return None
        with open("/sys/fs/cgroup/memory.current", encoding="ascii") as handle:
            return int(limit) - int(handle.read().strip())
    except (OSError, ValueError):
        return None


def _address_space() -> int | None:
    """What the soft RLIMIT_AS leaves of this process's address space (Linux's VmSize used)."""
    try:
        import resource

        limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    except (ImportError, OSError, ValueError):  # no resource module on Windows
        return None
    if limit == resource.RLIM_INFINITY:
        return None
    try:
        with open("/proc/self/status", encoding="ascii") as handle:
            used = next((int(line.split()[1]) * 1024 for line in handle if line.startswith("VmSize:")), 0)
    except (OSError, ValueError, IndexError):
        used = 0
    return limit - used
