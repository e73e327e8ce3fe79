"""Robustness sweep: ``geotex pgp`` and ``geotex tile-image`` over the whole shared corpus.

Runs the CLI as a user would, one subprocess at a time (timeout 300 s each):

* ``pgp``: every mesh file of ``base/`` (subfolders included) and ``broken/``:
  ``geotex pgp MESH --up 0,0,1 --scale S -o P.npz --json`` with S = bounding-box
  diagonal / 30 (surface units), and also ``--curvature`` on the closed bases.
  Judged: seam residual <= 1e-6 tile units; on closed meshes the index sum
  equals the Euler characteristic (summed over components).
* ``tile-image``: every image of ``images/`` (recursively) on Spot and on Bob
  (genus 1), and the bricks image on every closed base:
  ``geotex tile-image MESH --image IMG --param P.npz --make-tileable 128 -o OUT.glb``.
  The written GLB is read back and its visible seam measured
  (:func:`geotex.image.seams.edge_contrast`, about 1 = no seam in the statistics).
* ``relief``: every closed base with the bricks image:
  ``... --displace 1 --size-mm 80 -o OUT.stl``, the file judged by ``geotex check``.
* On the torus: every image as it is (no ``--make-tileable``), the embark images
  (grey JPEG, alpha PNG) as height maps, and a few bad options and files
  (``bad option`` rows: they must be refused).

A refusal (exit 1 or 2) is acceptable when stderr is one line
``geotex: error: ...``, there is no traceback and no output file is left;
anything else that is not a success is a failure (exit 3, a traceback, a
timeout, a residual or index sum off, a written file not printable).

Writes ``benchmarks/results/pgp_corpus.md`` and ``.json`` row by row.

    python benchmarks/pgp_corpus.py [--data ../shared/data] [--only STEM ...] [--workdir DIR]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from corpus import REPO, TIMEOUT, geotex_check, geotex_cmd, run_measured

HERE = Path(__file__).resolve().parent
MESH_SUFFIXES = {".stl", ".obj", ".ply", ".off", ".3mf", ".glb"}
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".gif", ".tif", ".tiff", ".webp"}
ALL_IMAGES_ON = ["base/spot_odedstein.obj", "base/bob_uv/bob_tri.obj"]
ONE_IMAGE = "images/quilting_classic/t1_bricks.png"
TORUS = "base/torus_odedstein.obj"
TILE_PX = 128
RESIDUAL_MAX = 1e-6
COLUMNS = ["step", "file", "options", "exit", "s", "faces", "chi", "singularities",
           "index sum", "seam residual", "edge contrast", "result", "note"]


def mesh_facts(path: Path) -> dict:
    """Faces, Euler characteristic (all components) and closedness as geotex reads the file."""
    from geotex.io import read_mesh

    try:
        m = read_mesh(path)
    except Exception as exc:                                     # noqa: BLE001
        return {"readable": False, "error": f"{type(exc).__name__}: {exc}"}
    V, F = m.vertices, m.faces
    if len(F) == 0:
        return {"readable": True, "faces": 0, "closed": False, "chi": None, "diag": 0.0}
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(E, axis=0, return_counts=True)
    used = np.unique(F)
    diag = float(np.linalg.norm(np.ptp(V[used], axis=0)))
    return {"readable": True, "faces": int(len(F)), "closed": bool(np.all(counts == 2)),
            "chi": int(used.size - counts.size + len(F)), "diag": diag}


def stderr_verdict(err: str, out: Path, code: int) -> tuple[str, str]:
    """('refused', message) for a clean refusal, else ('FAIL', why)."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    msg = lines[-1] if lines else "(no message)"
    problems = []
    if code not in (1, 2):
        problems.append(f"exit {code}")
    if "Traceback" in err:
        problems.append("traceback")
    if len(lines) != 1 or not lines[0].startswith("geotex: error: "):
        problems.append(f"{len(lines)} stderr lines")
    if out.exists():
        problems.append("output left behind")
    return ("FAIL", "; ".join(problems) + f": {msg}") if problems else ("refused", msg)


def unsuccessful(row: dict, res: dict, err: str, out: Path) -> bool:
    """Fill ``row``'s result and note for a run that did not succeed; False when it did.

    A timeout, a refusal (judged by :func:`stderr_verdict`), a traceback or a
    missing output file; the caller judges what a successful run wrote.
    """
    if res["timed_out"]:
        row.update(result="FAIL", note=f"timeout after {TIMEOUT:g} s")
    elif res["exit"] != 0:
        row["result"], row["note"] = stderr_verdict(err, out, res["exit"])
    elif "Traceback" in err:
        row.update(result="FAIL", note="exit 0 with a traceback on stderr")
    elif not out.exists():
        row.update(result="FAIL", note="exit 0 but no output file")
    else:
        return False
    return True


def check_verdict(path: Path, env: dict) -> dict:
    """``result`` ('ok' when ``geotex check`` calls the written file printable, else
    'FAIL') and ``note`` (the verdict and its first reasons)."""
    verdict, reason = geotex_check(path, env)
    return {"result": "ok" if verdict == "printable" else "FAIL",
            "note": f"geotex check: {verdict}" + (f" ({reason})" if reason else "")}


class Sweep:
    def __init__(self, data: Path, workdir: Path, out: Path, env: dict, meta: dict):
        self.data, self.workdir, self.out, self.env, self.meta = data, workdir, out, env, meta
        self.rows: list[dict] = []
        self.n = 0

    def run(self, cmd: list[str], out: Path) -> tuple[dict, str, str]:
        self.n += 1
        log, err = self.workdir / f"{self.n:03d}.out", self.workdir / f"{self.n:03d}.err"
        res = run_measured(cmd, timeout=TIMEOUT, log=log, env=self.env, err_log=err)
        return res, log.read_text(errors="replace"), err.read_text(errors="replace")

    def add(self, row: dict) -> None:
        self.rows.append(row)
        self.write()
        print(" | ".join(str(row.get(c, "")) for c in COLUMNS)[:300], flush=True)

    def base_row(self, step: str, path: Path, options: str, res: dict) -> dict:
        return {"step": step, "file": str(path.relative_to(self.data)), "options": options,
                "exit": res["exit"], "s": res["seconds"], "peak_mb": res["peak_mb"]}

    def failure(self, row: dict, res: dict, err: str, out: Path) -> bool:
        """Fill result/note for a run that did not succeed; False when it did."""
        if not unsuccessful(row, res, err, out):
            return False
        row["note"] = row["note"].replace(str(self.data) + "/", "").replace(
            str(self.workdir) + "/", "")
        return True

    # ---------------------------------------------------------------- steps

    def pgp(self, path: Path, facts: dict, field: list[str], tag: str) -> Path | None:
        npz = self.workdir / f"{path.stem}_{tag}.npz"
        scale = facts.get("diag", 0.0) / 30 if facts.get("diag") else 1.0
        cmd = [*geotex_cmd(), "pgp", str(path), *field, "--scale", f"{scale:.6g}",
               "-o", str(npz), "--json"]
        res, out, err = self.run(cmd, npz)
        row = self.base_row("pgp", path, " ".join(field) + f" --scale {scale:.4g}", res)
        row.update(faces=facts.get("faces"), chi=facts.get("chi"))
        if self.failure(row, res, err, npz):
            self.add(row)
            return None
        try:
            doc = json.loads(next(ln for ln in out.splitlines() if ln.startswith("{")))
        except (StopIteration, json.JSONDecodeError):
            row.update(result="FAIL", note="no JSON on stdout")
            self.add(row)
            return None
        row.update(singularities=len(doc["singularities"]), **{
            "index sum": doc["index_sum"], "seam residual": doc["seam_residual"],
            "singular faces": doc["singular_faces"], "timings": doc["timings"]})
        bad = []
        if not doc["seam_residual"] <= RESIDUAL_MAX:
            bad.append(f"seam residual {doc['seam_residual']:.3g} > {RESIDUAL_MAX:g}")
        if facts.get("closed") and abs(doc["index_sum"] - facts["chi"]) > 1e-9:
            bad.append(f"index sum {doc['index_sum']:g} != chi {facts['chi']}")
        note = "" if facts.get("closed") else "open / non-manifold: index sum not judged"
        row.update(result="FAIL" if bad else "ok", note="; ".join(bad) or note)
        self.add(row)
        return npz

    def tile_image(self, path: Path, npz: Path, image: Path, *, tileable: bool = True) -> None:
        from geotex.image.seams import edge_contrast
        from geotex.io import read_mesh
        from geotex.mesh.topology import position_welded_faces

        glb = self.workdir / f"{path.stem}__{image.stem}{'' if tileable else '_asis'}.glb"
        make = ["--make-tileable", str(TILE_PX)] if tileable else []
        cmd = [*geotex_cmd(), "tile-image", str(path), "--image", str(image), "--param",
               str(npz), *make, "-o", str(glb)]
        res, _, err = self.run(cmd, glb)
        row = self.base_row("tile-image", path, f"{image.relative_to(self.data)} "
                            f"{'' if tileable else '(as is, no --make-tileable) '}-> .glb", res)
        if self.failure(row, res, err, glb):
            self.add(row)
            return
        try:
            m = read_mesh(glb)
            # a GLB splits vertices per corner (one uv each): weld by position for the edges
            F = position_welded_faces(m.vertices, m.faces)
            c = edge_contrast(m.vertices, F, m.uv, m.uv_faces, m.texture)
            row.update({"faces": int(len(m.faces)), "edge contrast": round(c.ratio, 3),
                        "result": "ok"})
        except Exception as exc:                                 # noqa: BLE001
            row.update(result="FAIL", note=f"written GLB unreadable: {exc!r}")
        self.add(row)

    def relief(self, path: Path, npz: Path, image: Path) -> None:
        stl = self.workdir / f"{path.stem}__{image.stem}_relief.stl"
        cmd = [*geotex_cmd(), "tile-image", str(path), "--image", str(image), "--param",
               str(npz), "--make-tileable", str(TILE_PX), "--displace", "1", "--size-mm",
               "80", "-o", str(stl)]
        res, _, err = self.run(cmd, stl)
        row = self.base_row("relief", path, f"{image.relative_to(self.data)} --displace 1 "
                            "--size-mm 80 -> .stl", res)
        if self.failure(row, res, err, stl):
            self.add(row)
            return
        row.update(check_verdict(stl, self.env))
        self.add(row)

    def bad_option(self, path: Path, argv: list[str], label: str) -> None:
        """A command with a bad option or file: it must be refused in one line."""
        out = Path(argv[argv.index("-o") + 1])
        out.unlink(missing_ok=True)
        res, _, err = self.run([*geotex_cmd(), *argv], out)
        row = self.base_row("bad option", path, label, res)
        if not self.failure(row, res, err, out):
            row.update(result="FAIL", note="accepted")
        self.add(row)

    # ---------------------------------------------------------------- output

    def write(self) -> None:
        load = os.getloadavg()[0]
        self.meta["load_1min_end"] = round(load, 2)
        self.out.with_suffix(".json").write_text(
            json.dumps({"meta": self.meta, "rows": self.rows}, indent=1, default=str) + "\n")
        tally: dict[str, int] = {}
        for r in self.rows:
            tally[r.get("result", "")] = tally.get(r.get("result", ""), 0) + 1
        m = self.meta
        lines = [f"# `geotex pgp` / `geotex tile-image` over the shared corpus (robustness sweep)",
                 "", f"{m['date']}, commit `{m['commit']}`, {m['machine']}, 1-minute load "
                 f"{m['load_1min_start']} at the start, {m['load_1min_end']} at the last row "
                 "(other jobs on the machine). `python benchmarks/pgp_corpus.py`, one "
                 f"subprocess at a time, timeout {TIMEOUT:g} s.", "",
                 "Steps: `pgp` = `geotex pgp MESH --up 0,0,1 | --curvature --scale S -o P.npz "
                 "--json` with S = bounding-box diagonal / 30 on every mesh file of "
                 "`base/` and `broken/` (`--curvature` on closed ones); `tile-image` = "
                 f"`geotex tile-image MESH --image IMG --param P.npz (the --up one) "
                 f"--make-tileable {TILE_PX} -o OUT.glb`, the GLB read back and its seam "
                 "measured (edge contrast: mean colour jump across edges / mean change inside "
                 "faces, `geotex.image.seams.edge_contrast`; 1 = no seam in the statistics); "
                 "`relief` = the same with `--displace 1 --size-mm 80 -o OUT.stl`, judged by "
                 "`geotex check` on the written file.", "",
                 f"ok: success and judged right (seam residual <= {RESIDUAL_MAX:g}; index sum "
                 "= Euler characteristic chi on closed meshes; file printable). refused: exit "
                 "1/2 with one line `geotex: error: ...`, no traceback, no file left. "
                 "FAIL: anything else.", "",
                 "**" + ", ".join(f"{v} {k}" for k, v in sorted(tally.items())) +
                 f" of {len(self.rows)} rows.**", "",
                 "| " + " | ".join(COLUMNS) + " |", "|" + "|".join("---" for _ in COLUMNS) + "|"]
        for r in self.rows:
            cells = []
            for c in COLUMNS:
                v = r.get(c)
                if c == "seam residual" and isinstance(v, float):
                    v = f"{v:.2g}"
                elif c == "index sum" and isinstance(v, float):
                    v = f"{v:g}"
                cells.append("" if v is None else str(v).replace("|", "/"))
            lines.append("| " + " | ".join(cells) + " |")
        self.out.with_suffix(".md").write_text("\n".join(lines) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("/work/shared/data"))
    ap.add_argument("--out", type=Path, default=HERE / "results" / "pgp_corpus.md")
    ap.add_argument("--only", action="append", default=[],
                    help="only mesh files with this stem (repeatable)")
    ap.add_argument("--workdir", type=Path, help="keep outputs here (default: temporary)")
    args = ap.parse_args(argv)
    data = args.data.resolve()
    meshes = sorted(p for sub in ("base", "broken") for p in (data / sub).rglob("*")
                    if p.suffix.lower() in MESH_SUFFIXES)
    if args.only:
        meshes = [p for p in meshes if p.stem in args.only]
    images = sorted(p for p in (data / "images").rglob("*")
                    if p.suffix.lower() in IMAGE_SUFFIXES)
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.pop("DISPLAY", None)
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--", "geotex"],
                           capture_output=True, text=True).stdout.strip()
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "commit": commit + ("+dirty" if dirty else ""),
            "machine": f"{os.uname().machine}, {os.cpu_count()} cores",
            "load_1min_start": round(os.getloadavg()[0], 2), "timeout": TIMEOUT}
    tmp = None
    if args.workdir:
        workdir = args.workdir
        workdir.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="geotex-pgp-corpus-")
        workdir = Path(tmp.name)
    sweep = Sweep(data, workdir, args.out, env, meta)
    t0 = time.perf_counter()
    try:
        closed: dict[Path, Path] = {}
        for path in meshes:
            facts = mesh_facts(path)
            npz = sweep.pgp(path, facts, ["--up", "0,0,1"], "up")
            if facts.get("closed"):
                sweep.pgp(path, facts, ["--curvature"], "curv")
                if npz is not None:
                    closed[path] = npz
        bricks = data / ONE_IMAGE
        for rel in ALL_IMAGES_ON:
            path = data / rel
            if path in closed:
                for image in images:
                    sweep.tile_image(path, closed[path], image)
        for path, npz in closed.items():
            if str(path.relative_to(data)) not in ALL_IMAGES_ON:
                sweep.tile_image(path, npz, bricks)
        for path, npz in closed.items():
            sweep.relief(path, npz, bricks)
        torus = data / TORUS
        if torus in closed:                    # images used as they are, and as height maps
            for image in images:
                sweep.tile_image(torus, closed[torus], image, tileable=False)
            for image in images:
                if image.parent.name == "embark":
                    sweep.relief(torus, closed[torus], image)
            other = next((npz for p, npz in closed.items() if p != torus), None)
            out = str(workdir / "refused.out")
            tile = ["tile-image", str(torus), "--image", str(bricks), "--param",
                    str(closed[torus])]
            for argv, label in [
                    (["pgp", str(torus), "--up", "0,0,0", "--scale", "0.1", "-o", out + ".npz"],
                     "pgp --up 0,0,0"),
                    (["pgp", str(torus), "--up", "0,0,1", "--scale", "0", "-o", out + ".npz"],
                     "pgp --scale 0"),
                    ([*tile, "--make-tileable", "100000", "-o", out + ".glb"],
                     "tile-image --make-tileable 100000"),
                    ([*tile, "--make-tileable", "4", "-o", out + ".glb"],
                     "tile-image --make-tileable 4"),
                    ([*tile[:-1], str(other), "-o", out + ".glb"],
                     "tile-image --param (another mesh's)"),
                    ([*tile[:-1], str(torus), "-o", out + ".glb"],
                     "tile-image --param (a mesh file)"),
                    ([*tile[:3], str(torus), *tile[4:], "-o", out + ".glb"],
                     "tile-image --image (a mesh file)"),
                    ([*tile, "-o", out + ".stl"], "tile-image -o .stl without --displace")]:
                sweep.bad_option(torus, argv, label)
    finally:
        if tmp is not None:
            tmp.cleanup()
    print(f"wrote {args.out} ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
