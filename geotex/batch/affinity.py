"""CPU pinning of local Dask workers: each worker process on its own cores.

One part already uses more than one core: manifold3d runs its booleans on a
TBB thread pool sized to the CPUs of the process affinity mask, and
:func:`geotex.check.intersections` sizes its thread pool the same way.  Two
worker processes on two cores would each start such pools and oversubscribe
the cores.  :func:`geotex.batch.run.local_cluster` therefore pins every worker
process to its own share of the cores (:func:`split_cpus`) when it has no more
workers than cores: the plan travels to the worker processes in the
environment variable :data:`PLAN_VARIABLE` and this module, a Dask worker
*preload*, pins each process in :func:`dask_setup` as the worker starts,
before it registers with the scheduler and so before any task (TBB reads the
affinity mask once, when its first parallel call initialises it).  A worker
that dies is restarted by its nanny under the same name and pinned again.

Linux only (``os.sched_setaffinity``); elsewhere nothing is pinned.
"""

from __future__ import annotations

import logging
import os
from typing import Sequence

from geotex.errors import InputError
from geotex.malloc import keep_freed_memory

__all__ = ["PLAN_VARIABLE", "available_cpus", "split_cpus", "encode_plan", "decode_plan",
           "pin_process", "dask_setup"]

#: Environment variable carrying the pinning plan to the local worker processes:
#: the CPU lists of workers 0, 1, ... separated by ``;`` (``"0;1"``, ``"0,1;2,3"``).
PLAN_VARIABLE = "GEOTEX_WORKER_CPUS"


def available_cpus() -> list[int] | None:
    """The CPUs this process may run on, sorted; ``None`` where affinity is not supported."""
    if not hasattr(os, "sched_getaffinity") or not hasattr(os, "sched_setaffinity"):
        return None
    return sorted(os.sched_getaffinity(0))


def split_cpus(cpus: Sequence[int], workers: int) -> list[list[int]] | None:
    """Split ``cpus`` evenly into ``workers`` disjoint, contiguous groups.

    Parameters
    ----------
    cpus : sequence of int
        The CPUs to share (e.g. :func:`available_cpus`).
    workers : int
        Number of worker processes (>= 1).

    Returns
    -------
    list of list of int, or None
        ``workers`` groups covering ``cpus`` (sizes differ by at most one,
        larger groups first); ``None`` when there are more workers than CPUs
        (then the workers are not pinned: the kernel shares the cores).

    Raises
    ------
    InputError
        ``workers`` < 1.
    """
    if workers < 1:
        raise InputError(f"workers must be at least 1 to split CPUs, got {workers}")
    cpus = sorted(int(c) for c in cpus)
    if workers > len(cpus):
        return None
    size, extra = divmod(len(cpus), workers)
    groups, start = [], 0
    for k in range(workers):
        stop = start + size + (1 if k < extra else 0)
        groups.append(cpus[start:stop])
        start = stop
    return groups


def encode_plan(groups: Sequence[Sequence[int]]) -> str:
    """``[[0], [1]]`` -> ``"0;1"`` (the value of :data:`PLAN_VARIABLE`)."""
    return ";".join(",".join(str(int(c)) for c in g) for g in groups)


def decode_plan(text: str) -> list[list[int]]:
    """``"0,1;2,3"`` -> ``[[0, 1], [2, 3]]`` (inverse of :func:`encode_plan`).

    Raises
    ------
    InputError
        Not a plan (a group that is empty or not integers).
    """
    try:
        groups = [[int(c) for c in g.split(",")] for g in text.split(";")]
    except ValueError:
        raise InputError(f"{PLAN_VARIABLE}={text!r}: expected CPU lists such as "
                         "'0,1;2,3'") from None
    return groups


def pin_process(cpus: Sequence[int]) -> None:
    """Pin every thread of this process to ``cpus`` (threads started later inherit it).

    ``os.sched_setaffinity(0, ...)`` changes only the calling thread on Linux,
    so every thread listed in ``/proc/self/task`` is pinned. Libraries that size
    a thread pool from the affinity mask (TBB in manifold3d, the thread pool of
    :mod:`geotex.check.intersections`) see ``cpus`` only if they initialise
    after this call: TBB keeps the pool it started with.

    Parameters
    ----------
    cpus : sequence of int
        CPUs to run on (a subset of :func:`available_cpus`).

    Raises
    ------
    InputError
        Affinity is not supported on this system, or ``cpus`` is empty.
    OSError
        The kernel refused the mask (a CPU that does not exist or is not allowed).
    """
    if available_cpus() is None:
        raise InputError("CPU pinning needs os.sched_setaffinity (Linux)")
    mask = {int(c) for c in cpus}
    if not mask:
        raise InputError("pin_process: no CPUs given")
    os.sched_setaffinity(0, mask)
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:             # no /proc: only the calling thread
        tids = []
    for tid in tids:
        try:
            os.sched_setaffinity(tid, mask)
        except ProcessLookupError:      # the thread ended meanwhile
            pass


def dask_setup(worker) -> None:
    """Dask worker preload hook: pin this worker process to its share of the CPUs.

    It also sets glibc's allocation thresholds (:func:`geotex.malloc.keep_freed_memory`).

    Reads :data:`PLAN_VARIABLE` (set by :func:`geotex.batch.run.local_cluster`)
    and the worker's name, which a ``LocalCluster`` sets to its index
    ``0 .. n-1``; does nothing without a plan, for a worker whose name is not
    an index of the plan, or where affinity is not supported; logs a warning
    (and leaves the worker unpinned) when the kernel refuses the mask.
    """
    keep_freed_memory()                 # as the command line does (geotex.malloc)
    text = os.environ.get(PLAN_VARIABLE)
    if not text or available_cpus() is None:
        return
    try:
        index = int(worker.name)
    except (TypeError, ValueError):
        return
    groups = decode_plan(text)
    if 0 <= index < len(groups):
        try:
            pin_process(groups[index])
        except OSError as exc:      # an unpinned worker still works: say so and go on
            logging.getLogger(__name__).warning(
                "worker %s: not pinned to CPUs %s (%s)", worker.name, groups[index], exc)
