"""The main job's rows, two checkouts back to back: CPU, stages and output bytes.

Runs, each command in its own process (``/usr/bin/time -v``), with checkout A
then B (B then A in odd rounds, so both meet the same load on the shared 2
cores):

* ``geotex map --tiles studs --shell SHELL.npz`` on the shells of Spot and
  Kitten decimated to 15k faces (as ``bench_main_job.py`` builds the bases,
  saved by ``geotex texture --shell-out`` of checkout A);
* ``geotex texture BASE --tiles studs --size-mm 80`` on the Spot base;
* ``geotex demo``.

Prints one JSON line per run (CPU = user + system s of the process and its
children, wall s, 1-minute load before the run, stage seconds from
``--report``, SHA-256 of the STL written, and for the demo of its STL and
3MF) and a markdown table of both checkouts per row.

Usage: ``python benchmarks/bench_main_job_pair.py A_DIR B_DIR [--rounds N]
[--data ../shared/data] [--work DIR]`` (``A_DIR``, ``B_DIR``: checkouts whose
``geotex`` goes on ``PYTHONPATH``; run from outside both).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _run(checkout: str, argv, cwd: Path) -> dict:
    """One process of ``python -m geotex ARGV`` with ``checkout`` on the path."""
    env = dict(os.environ, PYTHONPATH=checkout)
    load = os.getloadavg()[0]
    t = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "geotex", *argv],
                          cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    cpu = sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)",
                                            proc.stderr))
    if proc.returncode:
        raise SystemExit(f"{checkout}: geotex {' '.join(argv)} failed:\n{proc.stderr[-2000:]}")
    return {"cpu": round(cpu, 2), "wall": round(wall, 2), "load": round(load, 2)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--work", default=None)
    args = ap.parse_args(argv)
    sys.path.insert(0, str(HERE))
    from bench_main_job import decimated_base  # noqa: E402  (the same bases)

    data = Path(args.data)
    work = Path(args.work or tempfile.mkdtemp(prefix="geotex-bench-pair-"))
    work.mkdir(parents=True, exist_ok=True)
    bases = {"spot": data / "base" / "spot_odedstein.obj",
             "kitten": data / "base" / "kitten_gpjs.obj"}
    for name, src in bases.items():
        base = work / f"{name}_15k.obj"
        if not base.exists():
            decimated_base(src, 15000, base)
        shell = work / f"{name}_shell.npz"
        if not shell.exists():
            _run(args.a, ["texture", str(base), "--tiles", "studs", "-o",
                          str(work / f"{name}_warm.stl"), "--size-mm", "80",
                          "--shell-out", str(shell)], work)
    rows = {
        "map spot 15k shell": lambda out: ["map", "--tiles", "studs", "--shell",
                                           str(work / "spot_shell.npz"), "-o", str(out)],
        "map kitten 15k shell": lambda out: ["map", "--tiles", "studs", "--shell",
                                             str(work / "kitten_shell.npz"), "-o", str(out)],
        "texture spot 15k": lambda out: ["texture", str(work / "spot_15k.obj"), "--tiles",
                                         "studs", "-o", str(out), "--size-mm", "80"],
        "demo": None,
    }
    checkouts = {"A": args.a, "B": args.b}
    for who, path in checkouts.items():          # warm: numba caches, file caches
        _run(path, rows["map spot 15k shell"](work / f"warm_{who}.stl"), work)
    results = []
    for r in range(args.rounds):
        for row, make in rows.items():
            for who in (("A", "B") if r % 2 == 0 else ("B", "A")):
                tag = f"{row.replace(' ', '_')}_{who}_{r}"
                if make is None:
                    out_dir = work / tag
                    res = _run(checkouts[who], ["demo", "-o", str(out_dir)], work)
                    res["sha256"] = {p.suffix: _sha(p)[:16] for p in sorted(out_dir.iterdir())
                                     if p.suffix in (".stl", ".3mf")}
                    res["stages"] = json.loads((out_dir / "report.json").read_text()).get(
                        "seconds")
                else:
                    out, rep = work / f"{tag}.stl", work / f"{tag}.json"
                    res = _run(checkouts[who], make(out) + ["--report", str(rep)], work)
                    res["sha256"] = _sha(out)[:16]
                    res["stages"] = json.loads(rep.read_text())["seconds"]
                res.update(row=row, who=who, round=r)
                results.append(res)
                print(json.dumps(res), flush=True)
    print()
    print("| row | checkout | CPU s (per round) | wall s | load | stages s | SHA-256 |")
    print("|---|---|---|---|---|---|---|")
    for row in rows:
        for who in ("A", "B"):
            rs = [x for x in results if x["row"] == row and x["who"] == who]
            st = rs[-1]["stages"]
            st = (" / ".join(f"{k} {v}" for k, v in st.items()) if isinstance(st, dict)
                  else f"total {st}")
            print(f"| {row} | {who} | {' / '.join(str(x['cpu']) for x in rs)} | "
                  f"{' / '.join(str(x['wall']) for x in rs)} | "
                  f"{' / '.join(str(x['load']) for x in rs)} | {st} | {rs[-1]['sha256']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
