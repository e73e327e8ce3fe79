"""The batch engine: one Dask task per part, locally or on an existing cluster.

:func:`run` loads the heavy shared inputs (tile sets, catalog shells) once on
the client and scatters them to every worker, submits one task per part and
collects the summary rows as the parts finish.  A part that fails with a
:class:`~geotex.errors.GeotexError` returns its one-line reason (the task
succeeds, so it is not retried); any other exception is retried once
(``retries=1``), and a worker that dies while running a part has that part
rescheduled once (``distributed.scheduler.allowed-failures = 1`` on the local
cluster), after which the part is recorded as failed and the batch goes on.
"""

from __future__ import annotations

import json
import os
import socket
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Callable

from geotex.batch.affinity import PLAN_VARIABLE, available_cpus, encode_plan, split_cpus
from geotex.batch.jobs import JOBS, SHARED_LOADERS
from geotex.batch.manifest import Part, read_parts
from geotex.batch.summary import read_summary, write_summary
from geotex.errors import GeotexError, InputError

__all__ = ["run", "run_part", "import_modules", "local_cluster", "default_workers",
           "dask_client", "map_tasks",
           "SUMMARY_INTERVAL"]

#: Seconds between two rewrites of the summary while a batch runs.
SUMMARY_INTERVAL = 2.0
#: Times a part may be on a worker that dies before it counts as failed.
ALLOWED_WORKER_DEATHS = 1
#: Environment of the local worker processes.  One thread per library per worker
#: (the workers already use every core), but not Dask's default
#: ``MALLOC_TRIM_THRESHOLD_=65536``: returning freed memory to the system that
#: eagerly made a 100k-face texture part 1.6x slower here (10.6-11.8 s in a worker
#: against 6.4-6.7 s in this process; 6.9-8.2 s without it).
WORKER_ENVIRON = {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1}
#: Worker preload of the local cluster: pins each worker process to its CPUs.
PRELOAD = "geotex.batch.affinity"


def default_workers() -> int:
    """Workers of the default local cluster: the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:          # not Linux
        return max(1, os.cpu_count() or 1)


def _peak_mb() -> float | None:
    try:
        import resource
    except ImportError:             # Windows
        return None
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return round(kb / 1024.0, 1)


def _one_line(message: str) -> str:
    return " ".join(str(message).split())


def _with_file(part: Part, message: str) -> str:
    """The message, prefixed with the part's input file when it does not name it."""
    name = Path(part.input).name
    return message if name in message else f"{name}: {message}"


def _file_stamp(path: str | None) -> tuple[int | None, int | None]:
    if path is None:
        return None, None
    try:
        st = os.stat(path)
    except OSError:
        return None, None
    return st.st_size, st.st_mtime_ns


def _base_row(part: Part, out: Path | None) -> dict:
    return {"part": part.name, "job": part.job, "input": part.input,
            "output": out.name if out is not None else "", "status": "pending", "reason": "",
            "faces": None, "tile_size": None, "coverage": None, "seconds": None,
            "cpu_seconds": None,
            "printable": None, "bytes": None, "mtime_ns": None, "worker": None,
            "worker_peak_mb": None, "options": part.options()}


def run_part(part: Part, shared: dict, out: str | None) -> dict:
    """Run one part and return its summary row (the task every worker executes).

    Parameters
    ----------
    part : Part
    shared : dict
        The loaded shared inputs the part's job declared (``"tiles"``, ``"shell"``).
    out : str or None
        Output path.

    Returns
    -------
    dict
        The summary row: ``status`` ``ok``, or ``failed`` with the one-line
        reason of the :class:`~geotex.errors.GeotexError` that stopped it.
        Other exceptions propagate (the engine retries them once).
    """
    out_path = None if out is None else Path(out)
    row = _base_row(part, out_path)
    t, cpu = time.perf_counter(), time.process_time()
    try:
        row.update(JOBS[part.job].run(part, shared, out_path))
        row["status"] = "ok"
    except GeotexError as exc:
        row.update(status="failed", reason=_with_file(part, _one_line(exc)))
    except MemoryError:
        row.update(status="failed", reason=f"{part.input}: out of memory on the worker; "
                   "give the workers more memory or make the part smaller")
    row["seconds"] = round(time.perf_counter() - t, 3)
    row["cpu_seconds"] = round(time.process_time() - cpu, 3)
    if row["status"] == "ok":
        row["bytes"], row["mtime_ns"] = _file_stamp(out if out is not None else part.input)
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    row["worker_peak_mb"] = _peak_mb()
    return row


def import_modules(modules) -> int:
    """Import ``modules`` (run on every worker when a batch starts); returns how many."""
    import importlib

    for name in modules:
        importlib.import_module(name)
    return len(modules)


def _resumable(part: Part, prev: dict | None, out: Path | None) -> bool:
    """Whether the previous run's row says this part passed and its file is unchanged.

    The verdict of the previous run was computed on the file read back
    (:func:`geotex.printing.export_printable`); an unchanged size and
    modification time (nanoseconds) mean the same file, so it is not checked
    again (a full check of a 500k-face texture costs seconds).
    """
    if not prev or prev.get("status") not in ("ok", "skipped"):
        return False
    if prev.get("options") != json.loads(json.dumps(part.options())):
        return False
    if out is not None and prev.get("printable") is not True:
        return False
    stamp = _file_stamp(str(out) if out is not None else part.input)
    return stamp[0] is not None and stamp == (prev.get("bytes"), prev.get("mtime_ns"))


def _absolute(part: Part) -> Part:
    """The part with absolute paths for its files (workers may run in another folder)."""
    from dataclasses import replace

    if not isinstance(part, Part):
        return part
    change = {}
    for field in ("input", "image", "tiles"):
        value = getattr(part, field)
        if value and os.path.exists(value) and not os.path.isabs(value):
            change[field] = os.path.abspath(value)
    return replace(part, **change) if change else part


def _guard_outputs(parts: list[Part], outs: dict) -> None:
    """Refuse an output that would overwrite an input of the batch."""
    inputs = {}
    for p in parts:
        for src in (p.input, p.image, p.tiles):
            if src and os.path.exists(src):
                inputs[os.path.realpath(src)] = src
    for p in parts:
        out = outs[p.name]
        if out is not None and os.path.realpath(out) in inputs:
            raise InputError(f"{out}: refusing to overwrite the input "
                             f"{inputs[os.path.realpath(out)]}; choose another output folder")


def local_cluster(workers: int | None = None, *, memory_limit="auto", pin: bool = True):
    """A local Dask cluster of ``workers`` single-threaded processes.

    The scheduler allows one worker death per task (the part is rescheduled
    once); the workers run with :data:`WORKER_ENVIRON` and without Dask's
    statistical profiler (it samples every thread's stack every 10 ms for a
    dashboard the local cluster does not start).

    With ``pin`` (Linux, and no more workers than CPUs) every worker process is
    pinned to its own share of the CPUs of this process
    (:func:`geotex.batch.affinity.split_cpus`: 2 workers on 2 CPUs get one
    each, 1 worker keeps them all) as it starts, before any task: one part
    already runs thread pools sized to the CPUs it may use (manifold3d's TBB,
    the self-intersection test), and unpinned workers would oversubscribe the
    cores.  A worker restarted after a crash is pinned again.

    Parameters
    ----------
    workers : int, optional
        Default: :func:`default_workers`.
    memory_limit : str or int, optional
        Per worker (Dask's default splits the machine's memory between them).
    pin : bool, optional
        Pin the workers to disjoint CPUs (default ``True``).

    Returns
    -------
    distributed.LocalCluster
    """
    import logging

    # lazy: dask + distributed take ~0.8 s to import; `geotex --help` imports this module
    import dask
    from distributed import LocalCluster

    n = default_workers() if workers is None else int(workers)
    environ = dict(WORKER_ENVIRON)
    cpus = available_cpus() if pin else None
    groups = split_cpus(cpus, n) if cpus and n >= 1 else None
    if groups is not None and n > 1:
        environ[PLAN_VARIABLE] = encode_plan(groups)
    with dask.config.set({"distributed.scheduler.allowed-failures": ALLOWED_WORKER_DEATHS,
                          "distributed.nanny.pre-spawn-environ": environ,
                          "distributed.worker.profile.enabled": False}):
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                            dashboard_address=None, memory_limit=memory_limit,
                            silence_logs=logging.ERROR,
                            preload=[PRELOAD] if PLAN_VARIABLE in environ else None)


def _load_shared(parts: list[Part]) -> tuple[dict, dict]:
    """Load every shared input once: ``({key: object}, {key: error message})``."""
    loaded, errors = {}, {}
    for p in parts:
        for key in JOBS[p.job].shared_keys(p):
            if key in loaded or key in errors:
                continue
            try:
                loaded[key] = SHARED_LOADERS[key[0]](key[1])
            except GeotexError as exc:
                errors[key] = _one_line(exc)
    return loaded, errors


def run(parts, *, job: str = "texture", outdir, tiles: str | None = None, client=None,
        workers: int | None = None, scheduler: str | None = None, resume: bool = False,
        progress: Callable[[dict, int, int], None] | None = None) -> list[dict]:
    """Run a batch of parts and write its summary.

    Parameters
    ----------
    parts : list of Part, or str / os.PathLike
        The parts, or a manifest (CSV) or folder to read them from
        (:func:`geotex.batch.manifest.read_parts`).
    job : str, optional
        Job of parts that do not name one (when ``parts`` is a path).
    outdir : str or os.PathLike
        Output folder (created if missing): one output per part, plus
        ``summary.csv`` and ``summary.json``.
    tiles : str, optional
        Tile set of parts that do not name one (when ``parts`` is a path).
    client : distributed.Client, optional
        Run on this client's cluster (it is left open).
    workers : int, optional
        Without ``client`` or ``scheduler``: size of the local cluster of
        processes (default: the cores available).  ``0`` runs the parts one
        after another in this process, without Dask (the sequential baseline).
    scheduler : str, optional
        Address of a running ``dask scheduler`` (``tcp://host:8786``) to connect to.
    resume : bool, optional
        Skip parts that passed in the previous run (``OUTDIR/summary.json``)
        with the same options and whose file has the same size and
        modification time.
    progress : callable, optional
        ``progress(row, done, total)`` after every finished (or skipped) part.

    Returns
    -------
    list of dict
        The summary rows, in the order of ``parts`` (see :mod:`geotex.batch.summary`).

    Raises
    ------
    InputError
        Bad manifest, unknown job, no parts, both ``client`` and ``scheduler``,
        a negative ``workers``, or an output that would overwrite an input.
    """
    if not isinstance(parts, (list, tuple)):
        parts = read_parts(parts, job=job, tiles=tiles)
    parts = list(parts)
    if not parts:
        raise InputError("no parts to run")
    parts = [_absolute(p) for p in parts]
    for p in parts:
        if not isinstance(p, Part) or p.job not in JOBS:
            raise InputError(f"parts: expected Part records with a job among "
                             f"{', '.join(JOBS)}, got {p!r}")
    if len({p.name for p in parts}) != len(parts):
        raise InputError("parts: two parts have the same name")
    if client is not None and scheduler is not None:
        raise InputError("give either client or scheduler, not both")
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers
                                or workers < 0):
        raise InputError(f"workers must be a non-negative integer, got {workers!r}")
    outdir = Path(os.path.abspath(outdir))
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"{outdir}: exists and is not a folder; give an output folder")
    outdir.mkdir(parents=True, exist_ok=True)
    outs = {}
    for p in parts:
        name = JOBS[p.job].output_name(p)
        outs[p.name] = None if name is None else outdir / name
    _guard_outputs(parts, outs)

    start = time.perf_counter()
    rows = {p.name: _base_row(p, outs[p.name]) for p in parts}
    previous = {r["part"]: r for r in read_summary(outdir)} if resume else {}
    todo = []
    done = [0]
    meta = {"workers": None, "scheduler": None, "wall_seconds": None}
    last_write = [0.0]

    def finish(row: dict, *, force_write: bool = False) -> None:
        rows[row["part"]] = row
        done[0] += 1
        if progress is not None:
            progress(row, done[0], len(parts))
        now = time.perf_counter()
        if force_write or now - last_write[0] > SUMMARY_INTERVAL:
            write_summary(outdir, [rows[p.name] for p in parts], meta=meta)
            last_write[0] = now

    for p in parts:
        prev = previous.get(p.name)
        if _resumable(p, prev, outs[p.name]):
            finish(dict(prev, status="skipped",
                        reason="passed in the previous run; file unchanged"))
        else:
            todo.append(p)

    shared, shared_errors = _load_shared(todo)
    runnable = []
    for p in todo:
        bad = [shared_errors[k] for k in JOBS[p.job].shared_keys(p) if k in shared_errors]
        if bad:
            finish(dict(rows[p.name], status="failed", reason=bad[0], seconds=0.0))
        else:
            runnable.append(p)

    if runnable and workers == 0 and client is None and scheduler is None:
        meta["workers"] = 0
        for p in runnable:
            finish(run_part(p, {k: shared[(k, n)] for k, n in JOBS[p.job].shared_keys(p)},
                            None if outs[p.name] is None else str(outs[p.name])))
    elif runnable:
        _run_dask(runnable, shared, outs, finish, rows, meta, client=client, workers=workers,
                  scheduler=scheduler)
    meta["wall_seconds"] = round(time.perf_counter() - start, 3)
    result = [rows[p.name] for p in parts]
    write_summary(outdir, result, meta=meta)
    return result


@contextmanager
def dask_client(*, client=None, workers: int | None = None, scheduler: str | None = None):
    """A Dask client: the one given, one connected to ``scheduler``, or a local cluster's.

    A client or local cluster this function opened is closed on exit; a
    given ``client`` is left open.

    Parameters
    ----------
    client : distributed.Client, optional
    workers : int, optional
        Size of the local cluster (:func:`local_cluster`) when neither
        ``client`` nor ``scheduler`` is given.
    scheduler : str, optional
        Address of a running ``dask scheduler`` (``tcp://host:8786``).

    Yields
    ------
    distributed.Client

    Raises
    ------
    InputError
        The scheduler cannot be reached.
    """
    from distributed import Client

    own_cluster = own_client = None
    try:
        if client is None:
            if scheduler is not None:
                try:
                    client = own_client = Client(scheduler, timeout="20s")
                except (OSError, TimeoutError) as exc:
                    raise InputError(f"--scheduler {scheduler}: cannot connect "
                                     f"({_one_line(exc)}); start one with 'dask scheduler' "
                                     "and give its tcp:// address") from None
            else:
                own_cluster = local_cluster(workers)
                client = own_client = Client(own_cluster)
        yield client
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()


def _worker_count(client) -> int:
    """Workers connected to ``client`` (waiting up to a minute for the first)."""
    n = len(client.scheduler_info().get("workers", {}))
    if not n:
        client.wait_for_workers(1, timeout=60)
        n = len(client.scheduler_info().get("workers", {}))
    return n


def _import_on_workers(client, modules) -> None:
    try:
        client.run(import_modules, sorted(modules))
    except ImportError as exc:
        raise GeotexError(f"the Dask workers cannot import geotex ({_one_line(exc)}); "
                          "install the same geotex on every worker machine") from None


def map_tasks(function, shared, n: int, *, client=None, workers: int | None = None,
              scheduler: str | None = None, imports=("geotex",)):
    """Run ``function(shared, i)`` for ``i`` in ``range(n)`` on Dask; yield results as they come.

    ``shared`` is scattered to every worker once (tasks refer to it by
    future); every task is retried once if it raises or its worker dies.
    Used by :func:`geotex.tiles.build.build_tileset` (``map_tiles``) for
    ``geotex tiles build --workers N``.

    Parameters
    ----------
    function : callable
        ``function(shared, i)``, importable on the workers (a module-level function).
    shared : object
        Picklable input common to every task.
    n : int
        Number of tasks.
    client, workers, scheduler
        Where to run, as for :func:`dask_client`.
    imports : sequence of str
        Modules every worker imports once before the first task.

    Yields
    ------
    tuple (int, object)
        ``(i, function(shared, i))``, in the order the tasks finish.

    Raises
    ------
    InputError
        The scheduler cannot be reached.
    GeotexError
        The workers cannot import geotex; an exception raised by a task (after
        its retry) propagates as is.
    """
    from distributed import as_completed

    with dask_client(client=client, workers=workers, scheduler=scheduler) as cl:
        _worker_count(cl)
        _import_on_workers(cl, imports)
        future = cl.scatter(shared, broadcast=True, hash=False)
        name = getattr(function, "__name__", "task")
        stamp = f"{os.getpid()}-{time.time_ns()}"
        futures = {cl.submit(function, future, i, retries=1, pure=False,
                             key=f"geotex-{name}-{i}-{stamp}"): i for i in range(n)}
        try:
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
                fut.release()
        finally:
            for fut in futures:
                fut.cancel()
            future.release()


def _run_dask(parts, shared, outs, finish, rows, meta, *, client, workers, scheduler):
    """Submit one task per part to a Dask cluster and collect the rows as they finish."""
    from distributed import as_completed

    with dask_client(client=client, workers=workers, scheduler=scheduler) as client:
        if scheduler is not None:
            meta["scheduler"] = scheduler
        meta["workers"] = _worker_count(client)
        # every worker imports the jobs' libraries once, before the first part
        _import_on_workers(client, {m for p in parts for m in JOBS[p.job].imports})
        # heavy shared inputs go to every worker once; tasks refer to them by future
        futures = {key: client.scatter(obj, broadcast=True, hash=False)
                   for key, obj in shared.items()}
        # at most one part per worker thread is submitted at a time: Dask counts a
        # worker's death against every task assigned to it, so a part waiting
        # on a worker behind a crashing one would be charged with the crash too
        tasks, waiting = {}, list(reversed(parts))
        running = as_completed()

        def submit_more() -> None:
            threads = sum(w.get("nthreads", 1)
                          for w in client.scheduler_info().get("workers", {}).values())
            while waiting and running.count() < max(1, threads):
                p = waiting.pop()
                dep = {kind: futures[(kind, name)]
                       for kind, name in JOBS[p.job].shared_keys(p)}
                out = None if outs[p.name] is None else str(outs[p.name])
                fut = client.submit(run_part, p, dep, out, retries=1, pure=False,
                                    key=f"geotex-batch-{p.name}-{os.getpid()}-"
                                    f"{time.time_ns()}")
                tasks[fut.key] = p
                running.add(fut)

        submit_more()
        for fut in running:
            p = tasks[fut.key]
            try:
                row = fut.result()
            except Exception as exc:   # noqa: BLE001 - one part's crash must not stop the batch
                row = dict(rows[p.name], status="failed", reason=_task_failure(p, exc))
            finish(row)
            fut.release()
            submit_more()
        for fut in futures.values():
            fut.release()


def _task_failure(part: Part, exc: BaseException) -> str:
    """One line for a task that raised (after its retry) or whose worker died."""
    name = type(exc).__name__
    if name == "KilledWorker":
        return (f"{part.input}: the worker running this part died "
                f"{ALLOWED_WORKER_DEATHS + 1} times (a crash in a native library, or out "
                "of memory); nothing written")
    return f"{part.input}: internal error: {name}: {_one_line(exc)} (failed twice)"
