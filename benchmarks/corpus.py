"""Corpus run of the main job: every printable base through `geotex texture`, three judges.

For each closed base mesh of the shared corpus and for generated closed shapes
(plates of genus 0..12: geotex.mesh.primitives.plate_with_holes when geotex has
it, else a voxel plate with square holes built here; a block with a thin fin;
geotex's sphere_with_rod when it has one), run

    geotex texture BASE --tiles SET -o OUT.stl --report R.json --size-mm 80

with default options in a subprocess (timeout 300 s), the tile set rotating over
the catalog sets that cover closed shapes; record wall time and peak memory
(the child's own rusage), then judge the written file with `geotex check`,
PrusaSlicer (`prusa-slicer --info`) and admesh (geotex.check.slicers).  The
peer programs' own time is recorded too.

Writes benchmarks/results/corpus.md and corpus.json (or --name NAME.md/.json),
row by row, so an interrupted run keeps what it did.

    python benchmarks/corpus.py [--quick] [--only NAME] [--jobs 1] [--name corpus]

Bases listed as "not printable input" are confirmed with `geotex check` first.
Report fields are read defensively: a field the current code does not write is
left blank.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
DATA = Path("/work/shared/data/base")
TIMEOUT = 300.0
sys.path.insert(0, str(REPO))          # judge with this checkout's geotex, as the runs use it
SIZE_MM = 80.0
TILE_SETS = ["studs", "knurl", "knurl-1", "chainmail", "studs-complete"]

BASES = [
    "spot_odedstein.obj", "spot_lowres_odedstein.obj", "spot_uv/spot.obj", "bob_uv/bob_tri.obj",
    "bob_small_geometrycentral.ply", "blub_fish_lowres_odedstein.obj", "fertility_libigl.off",
    "kitten_gpjs.obj", "rocker_arm_ajacobson.obj", "torus_odedstein.obj",
    "double_torus_gpjs.obj", "bust_max_planck_decimated_libigl.obj", "fandisk_trimesh.obj",
    "sphere_odedstein.obj", "cube_odedstein.obj", "plate_holes_trimesh.STL",
]
NOT_PRINTABLE = ["teapot_ajacobson.obj", "wingnut_odedstein.obj"]
QUICK = ["cube_odedstein.obj", "bob_small_geometrycentral.ply", "spot_lowres_odedstein.obj"]
GENERATED = [f"plate_genus{g}" for g in range(13)] + ["block_thin_fin"]
try:                                   # thin part from geotex's own primitives, when it has one
    from geotex.mesh import primitives as _primitives
    if hasattr(_primitives, "sphere_with_rod"):
        GENERATED.append("sphere_with_rod")
except ImportError:
    pass

COLUMNS = ["base", "genus", "faces in", "tile set", "tile mm", "quads", "bare quads",
           "covered 1 tile", "covered 1/4 tile", "faces out", "seconds", "peak MB", "geotex", "prusa", "admesh",
           "failure reason"]


# ---------------------------------------------------------------- generated shapes

def voxel_boundary(occ: np.ndarray, xs, ys, zs) -> tuple[np.ndarray, np.ndarray]:
    """Outward triangulated boundary of a set of cells of a rectilinear grid.

    occ is (nx, ny, nz) bool; xs, ys, zs the nx+1, ny+1, nz+1 grid coordinates.
    The result is closed and manifold when no two filled cells touch only along
    an edge or at a corner.
    """
    occ = np.asarray(occ, bool)
    n = np.array(occ.shape)
    pad = np.pad(occ, 1)
    axes = [np.asarray(xs, float), np.asarray(ys, float), np.asarray(zs, float)]
    corner_id = lambda i, j, k: (i * (n[1] + 1) + j) * (n[2] + 1) + k  # noqa: E731
    quads = []
    for ax in range(3):
        lo = np.take(pad, np.arange(0, n[ax] + 1), axis=ax)      # cell before the plane
        hi = np.take(pad, np.arange(1, n[ax] + 2), axis=ax)      # cell after the plane
        sl = [slice(1, -1)] * 3
        sl[ax] = slice(None)
        lo, hi = lo[tuple(sl)], hi[tuple(sl)]
        for sign, mask in ((1, lo & ~hi), (-1, hi & ~lo)):
            idx = np.argwhere(mask)                               # plane index along ax
            u, v = (ax + 1) % 3, (ax + 2) % 3                     # u x v = +ax
            corners = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = idx.copy()
                c[:, u] += du
                c[:, v] += dv
                corners.append(corner_id(c[:, 0], c[:, 1], c[:, 2]))
            q = np.stack(corners, axis=1)
            quads.append(q if sign > 0 else q[:, ::-1])
    Q = np.vstack(quads)
    F = np.vstack([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]])
    used, F = np.unique(F, return_inverse=True)
    F = F.reshape(-1, 3).astype(np.int64)
    i, rem = np.divmod(used, (n[1] + 1) * (n[2] + 1))
    j, k = np.divmod(rem, n[2] + 1)
    V = np.stack([axes[0][i], axes[1][j], axes[2][k]], axis=1)
    return V, F


def plate_with_holes(genus: int) -> tuple[np.ndarray, np.ndarray]:
    """A 10-unit-cell plate, 6 thick, with `genus` square holes on a near-square lattice."""
    cols = max(1, int(np.ceil(np.sqrt(max(genus, 1)))))
    rows = max(1, int(np.ceil(max(genus, 1) / cols)))
    occ = np.ones((2 * cols + 1, 2 * rows + 1, 1), bool)
    for h in range(genus):
        r, c = divmod(h, cols)
        occ[2 * c + 1, 2 * r + 1, 0] = False
    xs = np.arange(occ.shape[0] + 1) * 10.0
    ys = np.arange(occ.shape[1] + 1) * 10.0
    return voxel_boundary(occ, xs, ys, [0.0, 6.0])


def block_thin_fin() -> tuple[np.ndarray, np.ndarray]:
    """A 40 x 40 x 12 block with a 0.8-thick, 20-high fin standing on it."""
    xs = [0.0, 19.6, 20.4, 40.0]
    ys = [0.0, 5.0, 35.0, 40.0]
    zs = [0.0, 12.0, 32.0]
    occ = np.zeros((3, 3, 2), bool)
    occ[:, :, 0] = True
    occ[1, 1, 1] = True
    return voxel_boundary(occ, xs, ys, zs)


def generated_shape(name: str) -> tuple[np.ndarray, np.ndarray]:
    if name.startswith("plate_genus"):
        g = int(name.removeprefix("plate_genus"))
        try:
            from geotex.mesh import primitives
            if hasattr(primitives, "plate_with_holes"):
                return primitives.plate_with_holes(g)
        except Exception:                                       # noqa: BLE001
            pass
        return plate_with_holes(g)
    if name == "block_thin_fin":
        return block_thin_fin()
    if name == "sphere_with_rod":
        from geotex.mesh import primitives
        return primitives.sphere_with_rod()
    raise KeyError(name)


# ---------------------------------------------------------------- helpers

def genus_of(F: np.ndarray, n_vertices: int) -> int | str:
    """Genus from the Euler characteristic of a closed connected mesh ('' if not closed)."""
    E = np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(E, axis=0, return_counts=True)
    if not np.all(counts == 2):
        return ""
    used = np.unique(F).size
    chi = used - counts.size + F.shape[0]
    return int((2 - chi) // 2)


def dig(doc, *paths):
    """First value found at one of the dotted paths of a nested dict, else None."""
    for p in paths:
        cur = doc
        for key in p.split("."):
            if isinstance(cur, dict) and key in cur:
                cur = cur[key]
            else:
                cur = None
                break
        if cur is not None:
            return cur
    return None


def geotex_cmd() -> list[str]:
    exe = Path(sys.executable).with_name("geotex")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "geotex"]


def run_measured(cmd: list[str], *, timeout: float, log: Path, env: dict,
                 err_log: Path | None = None) -> dict:
    """Run cmd; return exit code, wall seconds, peak RSS (MB) of the child, timed_out.

    stdout goes to ``log``; stderr too, or to ``err_log`` when given.
    """
    with open(log, "wb") as fh, open(err_log or os.devnull, "wb") as eh:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=fh,
                                stderr=eh if err_log is not None else subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, env=env)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            timer.cancel()
        seconds = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
    return {"exit": proc.returncode, "seconds": round(seconds, 2),
            "peak_mb": round(usage.ru_maxrss / 1024.0, 1),
            "timed_out": seconds >= timeout and proc.returncode < 0}


def last_error(text: str) -> str:
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    errs = [ln for ln in lines if "error" in ln.lower() or "Traceback" in ln]
    return (errs[-1] if errs else (lines[-1] if lines else ""))[:400]


def geotex_check(path: Path, env: dict) -> tuple[str, str]:
    """Verdict of `geotex check FILE` (exit 0 / 1 / 2) and its first reason."""
    try:
        proc = subprocess.run([*geotex_cmd(), "check", str(path), "--json"], env=env,
                              capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return "timeout", f"geotex check took more than {TIMEOUT:g} s"
    verdict = {0: "printable", 1: "not printable"}.get(proc.returncode,
                                                       f"unreadable (exit {proc.returncode})")
    reason = ""
    try:
        doc = json.loads(proc.stdout)
        reasons = doc.get("reasons") or []
        reason = "; ".join(reasons[:2])
    except (json.JSONDecodeError, AttributeError):
        reason = "" if proc.returncode == 0 else last_error(proc.stdout + proc.stderr)
    return verdict, reason


def judge_slicers(path: Path) -> dict:
    from geotex.check.slicers import slicer_verdicts
    from geotex.errors import GeotexError

    t0 = time.perf_counter()
    try:
        v = slicer_verdicts(path, timeout=TIMEOUT)
    except GeotexError as exc:
        return {"error": str(exc)}
    v["seconds"] = round(time.perf_counter() - t0, 2)
    return v


def verdict_word(v: dict | None) -> str:
    if not v:
        return ""
    if v.get("ok") is None:
        return "not judged"
    return "ok" if v["ok"] else "FAIL: " + ", ".join(v.get("reasons", []))


# ---------------------------------------------------------------- one row

def run_row(i: int, name: str, workdir: Path, env: dict) -> dict:
    from geotex.io import read_mesh, write_mesh
    from geotex.mesh.record import Mesh

    tiles = TILE_SETS[i % len(TILE_SETS)]
    stem = Path(name).stem if name not in GENERATED else name
    row_dir = workdir / f"{i:02d}_{stem}"
    row_dir.mkdir(parents=True, exist_ok=True)
    if name in GENERATED:
        V, F = generated_shape(name)
        base = row_dir / f"{name}.stl"
        write_mesh(base, Mesh(V, F, name=name))
        # the file is what geotex reads: count what was written
        m = read_mesh(base)
    else:
        base = DATA / name
        m = read_mesh(base)
    row = {"base": stem, "genus": genus_of(m.faces, len(m.vertices)),
           "faces in": int(len(m.faces)), "tile set": tiles}
    out, rep = row_dir / f"{stem}_{tiles}.stl", row_dir / "report.json"
    cmd = [*geotex_cmd(), "texture", str(base), "--tiles", tiles, "-o", str(out),
           "--report", str(rep), "--size-mm", f"{SIZE_MM:g}"]
    log = row_dir / "texture.log"
    run = run_measured(cmd, timeout=TIMEOUT, log=log, env=env)
    text = log.read_text(errors="replace")
    row.update({"seconds": run["seconds"], "peak MB": run["peak_mb"], "exit": run["exit"]})
    doc = {}
    if rep.exists():
        try:
            doc = json.loads(rep.read_text())
        except json.JSONDecodeError:
            doc = {}
    ts = dig(doc, "tile_size", "stats.tile_size", "shell.tile_size", "map.tile_size")
    if ts is None:
        m_ts = re.search(r"(\d+) tiles of ([0-9.eE+-]+)", text)
        ts = float(m_ts.group(2)) if m_ts else None
    row.update(covered_fields(doc))
    row.update({
        "tile mm": ts,
        "quads": dig(doc, "stats.quads", "shell.quads", "map.quads", "quads"),
        "bare quads": dig(doc, "stats.bare_quads", "map.bare_quads", "bare_quads"),
        "faces out": dig(doc, "stats.faces", "check.faces", "map.faces"),
        "report": doc,
    })
    failure = []
    if run["timed_out"]:
        failure.append(f"timeout after {TIMEOUT:g} s")
    elif run["exit"] != 0:
        failure.append(f"texture exit {run['exit']}: {last_error(text)}")
    if out.exists():
        g, g_reason = geotex_check(out, env)
        row["geotex"] = g
        if g != "printable" and g_reason:
            failure.append(f"check: {g_reason}")
        sv = judge_slicers(out)
        row["slicers"] = sv
        if "error" in sv:
            row["prusa"] = row["admesh"] = "error"
            failure.append(sv["error"])
        else:
            row["prusa"] = verdict_word(sv["prusaslicer"])
            row["admesh"] = verdict_word(sv["admesh"])
        if row.get("faces out") is None:
            row["faces out"] = int(len(read_mesh(out).faces))
    else:
        row["geotex"] = "no file"
    row["failure reason"] = "; ".join(failure)
    return row


# ---------------------------------------------------------------- output

def fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v).replace("|", "\\|").replace("\n", " ")


def covered_fields(doc: dict) -> dict:
    """Coverage columns from a --report JSON: within one tile (the target) and a quarter."""
    out = {}
    for col, key in (("covered 1 tile", "within_tile"), ("covered 1/4 tile",
                                                          "within_quarter_tile")):
        v = dig(doc, f"coverage.{key}", f"shell.coverage.{key}")
        out[col] = v if isinstance(v, (int, float)) else None
    return out


def write_results(rows: list[dict], rejected: list[dict], meta: dict, name: str) -> None:
    res = HERE / "results"
    res.mkdir(exist_ok=True)
    rows = sorted(rows, key=lambda r: r["_order"])
    with open(res / f"{name}.json", "w") as fh:
        json.dump({"meta": meta, "rows": rows, "not_printable_input": rejected}, fh,
                  indent=1, sort_keys=True, default=str)
    ok = sum(1 for r in rows if r.get("geotex") == "printable" and r.get("prusa") == "ok"
             and r.get("admesh") == "ok")
    lines = [f"# Corpus run of `geotex texture` ({meta['date']})", "",
             f"Command per row: `geotex texture BASE --tiles SET -o OUT.stl --report R.json "
             f"--size-mm {SIZE_MM:g}` (default options, timeout {TIMEOUT:g} s), then the "
             f"written STL judged by `geotex check`, PrusaSlicer {meta.get('prusaslicer', '')} "
             f"(`--info`) and admesh {meta.get('admesh', '')} (strict criteria: "
             f"`geotex/check/slicers.py`).", "",
             f"geotex commit `{meta['commit']}`; machine: {meta['machine']}; jobs {meta['jobs']}.",
             f"Seconds and peak MB (maximum resident set) are those of the `geotex texture` "
             f"process; the judges' own time is in the .json (`slicers.seconds`). "
             f"Tile mm: the tile size chosen automatically, at print size; coverage: the "
             f"share of the base area within one tile (target >= 0.99) and within a quarter "
             f"tile of the fitted surface (`coverage.within_tile`, `within_quarter_tile`); "
             f"quads, bare quads, faces out come from the "
             f"report (blank: not reported). geotex `no file`: the job wrote nothing.", "",
             f"**{ok} of {len(rows)} rows accepted by all three judges.**", "",
             "| " + " | ".join(COLUMNS) + " |",
             "|" + "|".join("---" for _ in COLUMNS) + "|"]
    for r in rows:
        lines.append("| " + " | ".join(fmt(r.get(c)) for c in COLUMNS) + " |")
    if rejected:
        lines += ["", "## Not printable input (skipped)", "",
                  "| base | geotex check | reason |", "|---|---|---|"]
        lines += [f"| {fmt(r['base'])} | {fmt(r['geotex'])} | {fmt(r['reason'])} |"
                  for r in rejected]
    (res / f"{name}.md").write_text("\n".join(lines) + "\n")


def tool_version(cmd: list[str]) -> str:
    if shutil.which(cmd[0]) is None:
        return "(missing)"
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=60,
                           env={**os.environ, "HOME": tempfile.gettempdir()})
    except (subprocess.TimeoutExpired, OSError):
        return ""
    text = p.stdout + p.stderr
    m = re.search(r"PrusaSlicer-([\w.+]+)", text) or re.search(r"version\s+(\d+\.\d+(\.\d+)?)", text)
    return m.group(1) if m else ""


def main(argv=None) -> int:
    global DATA
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", action="append", default=[],
                    help="run only this base (file name, stem or generated name; repeatable)")
    ap.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    ap.add_argument("--jobs", type=int, default=1, help="rows run at once (default 1)")
    ap.add_argument("--name", default="corpus",
                    help="results file name in benchmarks/results (default corpus)")
    ap.add_argument("--data", default=str(DATA),
                    help=f"folder of the base meshes (default {DATA})")
    ap.add_argument("--workdir", help="keep outputs here (default: a temporary directory)")
    args = ap.parse_args(argv)
    DATA = Path(args.data)

    names = QUICK if args.quick else BASES + GENERATED
    if args.only:
        names = [n for n in BASES + GENERATED
                 if n in args.only or Path(n).stem in args.only or n.split("/")[0] in args.only]
        if not names:
            ap.error(f"--only {args.only}: no such base")
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.pop("DISPLAY", None)
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--", "geotex"],
                           capture_output=True, text=True).stdout.strip()
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "commit": commit + ("+dirty" if dirty else ""), "jobs": args.jobs,
            "machine": f"{os.cpu_count()} cores", "timeout": TIMEOUT, "size_mm": SIZE_MM,
            "prusaslicer": tool_version(["prusa-slicer", "--help"]),
            "admesh": tool_version(["admesh", "--version"])}

    tmp = None
    if args.workdir:
        workdir = Path(args.workdir)
        workdir.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="geotex-corpus-")
        workdir = Path(tmp.name)

    rejected = []
    if not args.quick and not args.only:
        for n in NOT_PRINTABLE:
            g, reason = geotex_check(DATA / n, env)
            rejected.append({"base": Path(n).stem, "geotex": g, "reason": reason})
            print(f"{n}: geotex check says {g}: {reason}", flush=True)

    rows: list[dict] = []
    lock = threading.Lock()
    order = {n: (BASES + GENERATED).index(n) for n in names}

    def one(n):
        t0 = time.perf_counter()
        try:
            row = run_row(order[n], n, workdir, env)
        except Exception as exc:                                  # noqa: BLE001
            row = {"base": Path(n).stem, "failure reason": f"benchmark error: {exc!r}"}
        row["_order"] = order[n]
        with lock:
            rows.append(row)
            write_results(rows, rejected, meta, args.name)
        print(f"{row['base']}: {row.get('geotex')} / prusa {row.get('prusa')} / admesh "
              f"{row.get('admesh')} ({time.perf_counter() - t0:.0f} s) "
              f"{row.get('failure reason', '')}", flush=True)

    try:
        with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            list(pool.map(one, names))
    finally:
        if tmp is not None:
            tmp.cleanup()
    print(f"wrote {HERE / 'results' / (args.name + '.md')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
