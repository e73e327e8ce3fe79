"""Every closed catalog tile set on every catalog shell: ``geotex map``, judged on the written file.

The test suite keeps a covering of this matrix (every set once, every shell
once: ``tests/test_mapping.py``); this script records the whole of it.  Each
pair runs ``geotex map --tiles SET --shell SHELL -o OUT.stl --report`` in its
own process (wall time, peak memory), and the written STL is judged by
``geotex check``, PrusaSlicer (``--info``) and admesh
(:func:`geotex.check.slicers.slicer_verdicts`).

Run:  python benchmarks/catalog_matrix.py [--workdir DIR] [--shells S ...] [--sets T ...]
Writes benchmarks/results/catalog_matrix.md and .json (with --shells or --sets,
only those pairs, to catalog_matrix_part.md and .json unless --name is given).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from corpus import geotex_check, geotex_cmd, judge_slicers, run_measured, verdict_word  # noqa: E402

TIMEOUT = 900.0


def main() -> None:
    from geotex.shells import list_shells
    from geotex.tiles.catalog import list_tilesets

    ap = argparse.ArgumentParser()
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--shells", nargs="*", default=None, help="only these catalog shells")
    ap.add_argument("--sets", nargs="*", default=None, help="only these catalog tile sets")
    ap.add_argument("--name", default=None, help="stem of the result files")
    args = ap.parse_args()
    name = args.name or ("catalog_matrix_part" if args.shells or args.sets else "catalog_matrix")
    work = Path(args.workdir or tempfile.mkdtemp(prefix="geotex-matrix-"))
    work.mkdir(parents=True, exist_ok=True)
    sets = [r["name"] for r in list_tilesets() if r["kind"] != "planar"
            and (not args.sets or r["name"] in args.sets)]
    shells = [r["name"] for r in list_shells() if not args.shells or r["name"] in args.shells]
    env = dict(os.environ)
    rows = []
    for shell in shells:
        for tiles in sets:
            out = work / f"{shell}-{tiles}.stl"
            rep = work / f"{shell}-{tiles}.json"
            run = run_measured([*geotex_cmd(), "map", "--tiles", tiles, "--shell", shell,
                                "-o", str(out), "--report", str(rep)],
                               timeout=TIMEOUT, log=work / f"{shell}-{tiles}.log", env=env)
            row = {"shell": shell, "tiles": tiles, **run}
            if run["exit"] == 0 and out.exists():
                doc = json.loads(rep.read_text())
                stats = doc["stats"]
                row.update(faces=stats["faces"], quads=stats["quads"],
                           elements=stats["elements"], folded=stats["elements_folded"],
                           floating=stats["elements_floating"],
                           retries=stats["union_retries"],
                           at_defects=stats.get("elements_left_out_at_defects"))
                row["geotex"], row["reason"] = geotex_check(out, env)
                sv = judge_slicers(out)
                row["prusa"] = verdict_word(sv.get("prusaslicer")) if "error" not in sv else "error"
                row["admesh"] = verdict_word(sv.get("admesh")) if "error" not in sv else "error"
                out.unlink()
            else:
                row["geotex"] = f"not written (exit {run['exit']})"
            rows.append(row)
            print(json.dumps(row), flush=True)
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": platform.machine(), "cores": os.cpu_count(),
            "python": platform.python_version(), "load_1min_end": f"{os.getloadavg()[0]:.1f}"}
    outdir = Path(args.out)
    (outdir / f"{name}.json").write_text(json.dumps({"meta": meta, "rows": rows},
                                                           indent=1) + "\n")
    ok = sum(1 for r in rows if r.get("geotex") == "printable" and r.get("prusa") == "ok"
             and r.get("admesh") == "ok")
    lines = ["# Every catalog tile set on every catalog shell", "",
             f"{meta['date']}, {meta['machine']}, {meta['cores']} cores, Python "
             f"{meta['python']} (1-min load at the end {meta['load_1min_end']}). "
             "`geotex map --tiles SET --shell SHELL` in its own process; the written STL judged "
             "by `geotex check`, PrusaSlicer `--info` and admesh. "
             f"**{ok} of {len(rows)} pairs accepted by all three.**", "",
             "| shell | tiles | faces | elements | folded / floating left out | retries | "
             "left out at defects | wall s | peak MB | geotex check | PrusaSlicer | admesh |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['shell']} | {r['tiles']} | {r.get('faces', '')} | "
                     f"{r.get('elements', '')} | {r.get('folded', '')} / {r.get('floating', '')} | "
                     f"{r.get('retries', '')} | {r.get('at_defects', '')} | {r['seconds']} | {r['peak_mb']} | "
                     f"{r['geotex']} | {r.get('prusa', '')} | {r.get('admesh', '')} |")
    (outdir / f"{name}.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {outdir / (name + '.md')}")


if __name__ == "__main__":
    main()
