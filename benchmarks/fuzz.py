"""Fuzz benchmark: ``geotex check`` on 10,000 seeded hostile mesh files.

Every case is a mutated copy of a small valid file (STL ascii + binary, OBJ,
PLY ascii + binary, OFF, 3MF, GLB; byte flips, truncation, huge header
counts, NaN / inf / huge numbers, bad indices, corrupt zip and JSON chunks,
hostile references, zip bombs, large polygons, wrong extensions: see
:mod:`geotex.fuzzing`).  Each runs through ``geotex check`` in a subprocess
limited to 1.5 GiB of address space and 10 s; an outcome is acceptable when
it is exit 0 / 1 with a report, or exit 2 with exactly one line
``geotex: error: ...`` on stderr, within 10 s and 1 GiB resident.

The peer: trimesh (``trimesh.load(path, force="mesh")``) on a subset of the
same files, in subprocesses with the same limits: how often it loads a
mesh, raises, or is killed (time / memory).

Results go to ``benchmarks/results/fuzz.md``.

Run:  nice python benchmarks/fuzz.py [--cases 10000] [--seed 0] [--peer-cases 2000]
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

from geotex.fuzzing import (ADDRESS_LIMIT, MEMORY_LIMIT, TIME_LIMIT, make_cases, run_cases,
                            verdict)

RESULTS = Path(__file__).parent / "results" / "fuzz.md"

_PEER = r"""
import json, resource, sys, time, warnings
warnings.simplefilter("ignore")
import trimesh
for name in sys.argv[1:]:
    start = time.perf_counter()
    try:
        m = trimesh.load(name, force="mesh")
        outcome = "loaded" if len(getattr(m, "faces", [])) else "loaded (no faces)"
    except BaseException as exc:
        outcome = "raised " + type(exc).__name__
    print(json.dumps({"file": name, "outcome": outcome,
                      "seconds": time.perf_counter() - start,
                      "maxrss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}),
          flush=True)
"""


def run_peer(cases, *, batch: int = 25, workers: int = 2):
    """trimesh on every case; list of (case, outcome, seconds, maxrss)."""
    from concurrent.futures import ThreadPoolExecutor

    from geotex.fuzzing import limited_env, run_batch, run_limited   # the geotex runs' limits

    env = limited_env()

    def job(group):
        _, _, rss, rows = run_batch([sys.executable, "-c", _PEER], group, env)
        results = []
        for c in group:
            row = rows.get(str(c.path))
            if row is not None:
                results.append((c, row["outcome"], row["seconds"], rss))
                continue
            code, out, err, sec, rss1 = run_limited([sys.executable, "-c", _PEER, str(c.path)],
                                                    TIME_LIMIT, env)
            line = out.strip().splitlines()[-1:] if out.strip() else []
            if line:
                row = json.loads(line[0])
                results.append((c, row["outcome"], row["seconds"], rss1))
            elif code is None or code == -9:
                results.append((c, "killed: timeout", sec, rss1))
            else:
                tail = (err.strip().splitlines() or ["?"])[-1][:60]
                results.append((c, f"died (exit {code}): {tail}", sec, rss1))
        return results

    groups = [cases[i:i + batch] for i in range(0, len(cases), batch)]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return [r for g in pool.map(job, groups) for r in g]


def _category(o) -> str:
    if o.code in (0, 1, 2):
        return {0: "exit 0 (printable)", 1: "exit 1 (not printable)",
                2: "exit 2 (refused: one-line error)"}[o.code]
    if o.code is None or o.code == -9:
        return "killed at the time limit"
    return f"exit {o.code}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--hostile-share", type=float, default=0.06)
    ap.add_argument("--peer-cases", type=int, default=2000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="geotex-fuzz-") as tmp:
        t0 = time.perf_counter()
        cases = make_cases(tmp, args.cases, seed=args.seed, hostile_share=args.hostile_share)
        t_make = time.perf_counter() - t0
        t0 = time.perf_counter()
        outcomes = run_cases(cases, workers=args.workers)
        t_run = time.perf_counter() - t0
        step = max(1, len(cases) // max(args.peer_cases, 1))
        peer_cases = cases[::step][:args.peer_cases]
        t0 = time.perf_counter()
        try:
            peer = run_peer(peer_cases, workers=args.workers) if peer_cases else []
            peer_error = None
        except Exception as exc:  # the peer is optional
            peer, peer_error = [], f"{type(exc).__name__}: {exc}"
        t_peer = time.perf_counter() - t0
        text = report(args, cases, outcomes, peer, peer_error, t_make, t_run, t_peer)
    Path(args.out).write_text(text)
    print(text)
    return 0


def report(args, cases, outcomes, peer, peer_error, t_make, t_run, t_peer) -> str:
    defects = [(o, verdict(o)) for o in outcomes if verdict(o)]
    counts = collections.Counter(_category(o) for o in outcomes)
    hostile = [o for o in outcomes if o.case.hostile]
    lines = [
        "# Fuzz: `geotex check` on hostile mesh files",
        "",
        f"{len(cases)} cases (seed {args.seed}; {len(hostile)} hostile, each in its own "
        f"process; the others {40} per process), limits {TIME_LIMIT:g} s per case, "
        f"{ADDRESS_LIMIT >> 20} MiB address space (RLIMIT_AS), {MEMORY_LIMIT >> 20} MiB "
        "resident.  Acceptable: exit 0/1 with a report, or exit 2 with exactly one "
        "line `geotex: error: ...` on stderr.",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared with other jobs "
        f"during the run), Python {platform.python_version()}; {args.workers} workers.  "
        f"Making the files {t_make:.0f} s, running geotex {t_run:.0f} s wall, trimesh "
        f"{t_peer:.0f} s wall.",
        "",
        "## Outcomes",
        "",
        "| outcome | cases |",
        "|---|---:|",
    ]
    for k, v in sorted(counts.items()):
        lines.append(f"| {k} | {v} |")
    lines.append(f"| **defects** (anything else: traceback, exit 3, timeout, memory, "
                 f"stray stderr) | **{len(defects)}** |")
    lines += ["", "## Per mutation", "",
              "| mutation | cases | exit 0 | exit 1 | exit 2 | defects | slowest s |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    by_mut = collections.defaultdict(list)
    for o in outcomes:
        by_mut[o.case.mutation.split("+")[0]].append(o)
    for mut in sorted(by_mut):
        group = by_mut[mut]
        c = collections.Counter(o.code for o in group)
        bad = sum(1 for o in group if verdict(o))
        lines.append(f"| {mut} | {len(group)} | {c.get(0, 0)} | {c.get(1, 0)} | "
                     f"{c.get(2, 0)} | {bad} | {max(o.seconds for o in group):.2f} |")
    lines += ["", "## Slowest cases", "",
              "Seconds of the whole `geotex check` process for hostile cases (start-up "
              "included, about 0.5 s), of the case alone for batched ones.", "",
              "| case | mutation | exit | seconds | peak resident MiB |",
              "|---|---|---:|---:|---:|"]
    for o in sorted(outcomes, key=lambda o: -o.seconds)[:12]:
        lines.append(f"| {o.case.path.name} | {o.case.mutation} | {o.code} | "
                     f"{o.seconds:.2f} | {o.maxrss / 2**20:.0f} |")
    peak_h = max((o.maxrss for o in hostile), default=0)
    peak_all = max((o.maxrss for o in outcomes), default=0)
    top = max(hostile, key=lambda o: o.maxrss) if hostile else None
    lines += ["", "## Peak memory", "",
              f"* largest peak resident memory of a single-case process: "
              f"{peak_h / 2**20:.0f} MiB"
              + (f" ({top.case.path.name}, {top.case.mutation})" if top else ""),
              f"* largest peak of any process (batches of 40 included): "
              f"{peak_all / 2**20:.0f} MiB", ""]
    if defects:
        lines += ["## Defects", ""]
        for o, why in defects[:50]:
            lines.append(f"* {o.case.path.name} ({o.case.mutation}): {why}")
        lines.append("")
    lines += ["## Peer: trimesh on the same files", ""]
    if peer_error:
        lines.append(f"trimesh could not be run: {peer_error}")
    else:
        import trimesh
        pc = collections.Counter(p[1] if not p[1].startswith("raised") else "raised an exception"
                                 for p in peer)
        exc = collections.Counter(p[1][7:] for p in peer if p[1].startswith("raised"))
        lines += [f"trimesh {trimesh.__version__}, `trimesh.load(path, force=\"mesh\")`, on "
                  f"{len(peer)} of the cases (one in {max(1, len(cases) // max(len(peer), 1))}"
                  "), batches of 25 with the same limits.  trimesh does not check "
                  "printability, so this compares reading only.", "",
                  "| outcome | cases |", "|---|---:|"]
        for k, v in sorted(pc.items()):
            lines.append(f"| {k} | {v} |")
        lines += ["", "Exceptions raised: " + ", ".join(f"{k} {v}" for k, v in
                                                         exc.most_common(10)) + ".", ""]
        slow = sorted(peer, key=lambda p: -p[2])[:5]
        lines.append("Slowest trimesh loads: " + "; ".join(
            f"{p[0].case.path.name if hasattr(p[0], 'case') else p[0].path.name} "
            f"{p[2]:.2f} s ({p[1]})" for p in slow) + ".")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
