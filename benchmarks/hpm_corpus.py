"""Robustness sweep: ``geotex hpm`` over the whole shared corpus, default options.

Runs the CLI as a user would, one subprocess at a time (timeout 300 s each):

* ``texture``: every mesh file of ``base/`` (subfolders included) and
  ``broken/`` with the bricks image: ``geotex hpm MESH --image
  t1_bricks.png -o OUT.glb --report R.json`` (everything else default: scale a
  quarter of the diagonal, seed 0). A written GLB is read back: as many
  triangles as the input (or as the report's refined mesh, for a base too
  coarse for the image, which the command refines), finite texture
  coordinates, the input image as its texture; the report's placed patches
  and unfolded faces are listed.
* ``images``: every image of ``images/`` (recursively) on Bob (genus 1) and on
  the double torus (genus 2), judged the same way.
* ``relief``: every closed base with the bricks image: ``... --displace 1
  --size-mm 80 --faces 300000 -o OUT.stl``, the file judged by ``geotex check``.

A refusal (exit 1 or 2) is acceptable when stderr is one line
``geotex: error: ...``, there is no traceback and no output file is left;
anything else that is not a success is a failure (exit 3, a traceback, a
timeout, an unreadable or wrong output, a relief that is not printable).

Writes ``benchmarks/results/hpm_corpus.md`` and ``.json`` row by row.

    python benchmarks/hpm_corpus.py [--data ../shared/data] [--only STEM ...] [--workdir DIR]
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

import numpy as np

from corpus import REPO, TIMEOUT, geotex_cmd, run_measured
from pgp_corpus import (IMAGE_SUFFIXES, MESH_SUFFIXES, check_verdict, mesh_facts,
                        unsuccessful)

HERE = Path(__file__).resolve().parent
BRICKS = "images/quilting_classic/t1_bricks.png"
ALL_IMAGES_ON = ["base/bob_uv/bob_tri.obj", "base/double_torus_gpjs.obj"]
COLUMNS = ["step", "file", "options", "exit", "s", "peak_mb", "faces", "placed",
           "unfolded", "result", "note"]


class Sweep:
    def __init__(self, data: Path, workdir: Path, out: Path, env: dict, meta: dict):
        self.data, self.workdir, self.out, self.env, self.meta = data, workdir, out, env, meta
        self.rows: list[dict] = []
        self.n = 0

    def run(self, cmd: list[str]) -> tuple[dict, str]:
        self.n += 1
        log, err = self.workdir / f"{self.n:03d}.out", self.workdir / f"{self.n:03d}.err"
        res = run_measured(cmd, timeout=TIMEOUT, log=log, env=self.env, err_log=err)
        return res, err.read_text(errors="replace")

    def add(self, row: dict) -> None:
        row["note"] = str(row.get("note", "")).replace(str(self.data) + "/", "").replace(
            str(self.workdir) + "/", "")
        self.rows.append(row)
        self.write()
        print(" | ".join(str(row.get(c, "")) for c in COLUMNS)[:300], flush=True)

    def texture(self, path: Path, image: Path, facts: dict, step: str) -> None:
        from geotex.io import read_mesh

        glb = self.workdir / f"{path.stem}__{image.stem}.glb"
        rep = self.workdir / f"{path.stem}__{image.stem}.json"
        cmd = [*geotex_cmd(), "hpm", str(path), "--image", str(image), "-o", str(glb),
               "--report", str(rep)]
        res, err = self.run(cmd)
        row = {"step": step, "file": str(path.relative_to(self.data)),
               "options": f"{image.relative_to(self.data)} -> .glb", "exit": res["exit"],
               "s": res["seconds"], "peak_mb": res["peak_mb"], "faces": facts.get("faces")}
        if unsuccessful(row, res, err, glb):
            self.add(row)
            return
        bad, notes = [], []
        try:
            doc = json.loads(rep.read_text())
            levels = doc["levels"]
            row.update(placed=sum(lv["placed"] for lv in levels),
                       unfolded=levels[-1]["filled_faces"])
        except (OSError, ValueError, KeyError):
            doc = {}
            bad.append("no report")
        expected = facts.get("faces")
        if doc.get("input_faces") == expected and doc.get("faces", expected) > expected:
            expected = doc["faces"]                       # a coarse base, refined to fit
            notes.append(f"refined from {facts.get('faces')} to {expected} faces")
        try:
            m = read_mesh(glb)
            if m.faces.shape[0] != expected:
                bad.append(f"{m.faces.shape[0]} triangles written for {expected}")
            if m.uv is None or not np.isfinite(m.uv).all():
                bad.append("texture coordinates missing or not finite")
            if m.texture is None:
                bad.append("no texture image in the GLB")
        except Exception as exc:                                     # noqa: BLE001
            bad.append(f"written GLB unreadable: {exc!r}")
        row.update(result="FAIL" if bad else "ok", note="; ".join(bad + notes))
        self.add(row)

    def relief(self, path: Path, image: Path) -> None:
        stl = self.workdir / f"{path.stem}__{image.stem}_relief.stl"
        cmd = [*geotex_cmd(), "hpm", str(path), "--image", str(image), "--displace", "1",
               "--size-mm", "80", "--faces", "300000", "-o", str(stl)]
        res, err = self.run(cmd)
        row = {"step": "relief", "file": str(path.relative_to(self.data)),
               "options": f"{image.relative_to(self.data)} --displace 1 --size-mm 80 "
                          "--faces 300000 -> .stl", "exit": res["exit"], "s": res["seconds"],
               "peak_mb": res["peak_mb"]}
        if unsuccessful(row, res, err, stl):
            self.add(row)
            return
        row.update(check_verdict(stl, self.env))
        self.add(row)

    def write(self) -> None:
        self.out.with_suffix(".json").write_text(json.dumps(
            {"meta": self.meta, "rows": self.rows}, indent=1, default=str))
        fails = sum(r["result"] == "FAIL" for r in self.rows)
        lines = [
            "# Robustness sweep: `geotex hpm` over the shared corpus", "",
            f"Run {self.meta['date']} on {self.meta['machine']} (commit {self.meta['commit']}); "
            f"`benchmarks/hpm_corpus.py`. Default options, seed 0; seconds and peak memory "
            "of each process (the machine may be shared: seconds are indicative).", "",
            f"**{len(self.rows)} runs, {fails} failures** (a failure: exit 3, a traceback, a "
            "timeout, a refusal that is not one line or leaves a file, a written GLB with the "
            "wrong triangle count, missing or non-finite texture coordinates, or a relief "
            "`geotex check` refuses). `refused` rows are clean one-line refusals of files "
            "that are not closed manifold meshes.", "",
            "| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
        for r in self.rows:
            lines.append("| " + " | ".join(str(r.get(c, "")).replace("|", "/")
                                           for c in COLUMNS) + " |")
        self.out.with_suffix(".md").write_text("\n".join(lines) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=str(REPO.parent / "shared" / "data"))
    ap.add_argument("--only", nargs="*", help="file stems to run (all by default)")
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--out", default=str(HERE / "results" / "hpm_corpus.md"))
    args = ap.parse_args(argv)
    data = Path(args.data).resolve()
    workdir = Path(args.workdir or tempfile.mkdtemp(prefix="geotex-hpm-corpus-"))
    workdir.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONPATH=str(REPO))
    commit = os.popen(f"git -C {REPO} rev-parse --short HEAD").read().strip()
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores", "commit": commit}
    sweep = Sweep(data, workdir, Path(args.out), env, meta)
    meshes = sorted(p for d in ("base", "broken") for p in (data / d).rglob("*")
                    if p.suffix.lower() in MESH_SUFFIXES)
    images = sorted(p for p in (data / "images").rglob("*")
                    if p.suffix.lower() in IMAGE_SUFFIXES)
    keep = (lambda p: p.stem in args.only) if args.only else (lambda p: True)
    bricks = data / BRICKS
    closed = []
    for path in filter(keep, meshes):
        facts = mesh_facts(path)
        sweep.texture(path, bricks, facts, "texture")
        if facts.get("closed") and path.is_relative_to(data / "base"):
            closed.append(path)
    for rel in ALL_IMAGES_ON:
        path = data / rel
        if keep(path):
            facts = mesh_facts(path)
            for image in images:
                if image != bricks:
                    sweep.texture(path, image, facts, "images")
    for path in closed:
        sweep.relief(path, bricks)
    print(f"wrote {sweep.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
