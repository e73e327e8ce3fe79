"""Keep freed memory in the process (glibc): fewer page faults on big jobs.

glibc hands every allocation above a threshold (dynamically 128 KB to
32 MB) to its own ``mmap`` and returns it to the system when freed, so each
new large array is faulted in page by page again.  Jobs over million-face
meshes allocate and free such arrays by the hundred; on the machines
geotex is benchmarked on the first touch of fresh memory cost 1.5-4 s of
system time in a 10 s ``geotex displace`` (``benchmarks/results/``).  The
command line therefore asks glibc to serve arrays up to 32 MB from its heap
and not to trim the heap: freed memory is reused instead of faulted in
again, for about 6 % more peak memory.  Nothing is done when the user set a
``MALLOC_*`` variable, or off glibc.
"""

from __future__ import annotations

import ctypes
import os
import sys

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_MMAP_THRESHOLD = 32 * 1024 * 1024          # glibc's largest mmap threshold
_TRIM_THRESHOLD = 2 ** 31 - 1              # (an int): never trim in practice


def keep_freed_memory() -> bool:
    """Set glibc's mmap and trim thresholds for this process; returns whether it did."""
    if not sys.platform.startswith("linux") or any(k.startswith("MALLOC_") for k in os.environ):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt      # the C library the interpreter runs on
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    ok = mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD) == 1
    return bool(ok and mallopt(_M_TRIM_THRESHOLD, _TRIM_THRESHOLD) == 1)
