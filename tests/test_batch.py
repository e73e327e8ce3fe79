"""Batch jobs on Dask: manifests, isolation, resume, a real LocalCluster, the CLI."""

from __future__ import annotations

import json
import os
import sys

import pytest

from geotex.batch import JOBS, Job, Part, read_manifest, read_parts, run
from geotex.batch.affinity import available_cpus, decode_plan, encode_plan, split_cpus
from geotex.batch.summary import read_summary
from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import InputError, MissingFileError
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import icosphere, torus

TILES = "knurl-1"          # one tile: the smallest catalog set


@pytest.fixture
def folder(tmp_path):
    """Three tiny parts, one of them open (it cannot be textured)."""
    d = tmp_path / "parts"
    d.mkdir()
    V, F = icosphere(2)
    write_mesh(d / "ball.stl", Mesh(V * 10.0, F))
    write_mesh(d / "holed.obj", Mesh(V, F[1:]))
    write_mesh(d / "ring.off", Mesh(*torus(1.0, 0.4, n_major=24, n_minor=12)))
    return d


@pytest.fixture
def manifest(folder):
    """The three parts small: 20 mm with 5 mm tiles (a few seconds each)."""
    m = folder / "parts.csv"
    m.write_text("# three tiny parts\n"
                 "input,name,size_mm,tile_size,seed\n"
                 "ball.stl,ball,20,5,0\n"
                 "holed.obj,,20,5,\n"
                 "ring.off,ring,20,5,3\n")
    return m


def _statuses(rows):
    return {r["part"]: r["status"] for r in rows}


# --- manifests ---------------------------------------------------------------

def test_manifest_rows_defaults_and_paths(manifest, folder):
    parts = read_manifest(manifest, job="texture", tiles=TILES, seed=7)
    assert [p.name for p in parts] == ["ball", "holed", "ring"]
    assert parts[0].input == str(folder / "ball.stl")
    assert parts[1].seed == 7 and parts[2].seed == 3
    assert parts[0].size_mm == 20.0 and parts[0].tile_size == 5.0
    assert all(p.tiles == TILES and p.job == "texture" for p in parts)
    assert parts[1].source == f"{manifest}:4"


def test_folder_parts(folder):
    parts = read_parts(folder, job="check")
    assert [p.name for p in parts] == ["ball", "holed", "ring"]   # parts.csv is not a mesh


@pytest.mark.parametrize("text, words", [
    ("", "is empty"),
    ("name,seed\nx,1\n", "no 'input' column"),
    ("input,colour\na.stl,red\n", "unknown column 'colour'"),
    ("input\n", "no parts"),
    ("input,size_mm\na.stl,-3\n", "column size_mm: '-3'"),
    ("input,tile_size\na.stl,abc\n", "column tile_size: 'abc'"),
    ("input,seed\na.stl,1.5\n", "column seed: '1.5'"),
    ("input,job\na.stl,paint\n", "column job: 'paint' is not one of"),
    ("input,name\na.stl,x\nb.stl,x\n", "part name 'x' is used twice"),
    ("input,name\na.stl\n", "1 cells, the header has 2"),
    ("input,job\na.stl,texture\n", "the texture job needs tiles: give --tiles"),
    ("input,job\na.stl,lapped\n", "the lapped job needs image"),
])
def test_manifest_errors_name_file_and_line(tmp_path, text, words):
    m = tmp_path / "m.csv"
    m.write_text(text)
    with pytest.raises(InputError) as err:
        read_manifest(m, job="check")
    msg = str(err.value)
    assert words in msg and str(m) in msg and "\n" not in msg


def test_missing_manifest_and_empty_folder(tmp_path):
    with pytest.raises(MissingFileError, match="no such manifest"):
        read_manifest(tmp_path / "none.csv")
    with pytest.raises(InputError, match="no input files"):
        read_parts(tmp_path, job="check")


def test_job_table_entries_are_complete():
    for name, job in JOBS.items():
        assert job.name == name and callable(job.run) and job.input in ("mesh", "shell")
        assert set(job.shared) <= {"tiles", "shell"}


# --- the engine, in process --------------------------------------------------

def test_sequential_batch_isolates_failures_and_resumes(manifest, tmp_path):
    out = tmp_path / "out"
    rows = run(manifest, job="texture", tiles=TILES, outdir=out, workers=0)
    assert _statuses(rows) == {"ball": "ok", "holed": "failed", "ring": "ok"}
    bad = rows[1]
    assert bad["reason"].startswith("holed.obj: ") and "open" in bad["reason"]
    assert not (out / "holed.stl").exists()
    for r in (rows[0], rows[2]):
        assert r["printable"] is True and r["tile_size"] == 5.0 and r["faces"] > 1000
        back = read_mesh(out / r["output"])
        assert len(back.faces) == r["faces"]
    assert sorted(p.name for p in out.iterdir()) == ["ball.stl", "ring.stl", "summary.csv",
                                                     "summary.json"]
    header = (out / "summary.csv").read_text().splitlines()[0]
    assert header.startswith("part,job,input,output,status,reason,faces,tile_size,coverage")
    assert [r["part"] for r in read_summary(out)] == ["ball", "holed", "ring"]

    # resume: the two good parts are skipped, the failing one runs again
    seen = []
    rows2 = run(manifest, job="texture", tiles=TILES, outdir=out, workers=0, resume=True,
                progress=lambda row, done, total: seen.append((row["part"], done, total)))
    assert _statuses(rows2) == {"ball": "skipped", "holed": "failed", "ring": "skipped"}
    assert sorted(seen) == [("ball", 1, 3), ("holed", 3, 3), ("ring", 2, 3)]
    assert rows2[0]["faces"] == rows[0]["faces"] and rows2[0]["printable"] is True

    # a changed output file, or changed options, are run again
    ring = out / "ring.stl"
    os.utime(ring, ns=(ring.stat().st_atime_ns, ring.stat().st_mtime_ns + 10**9))
    rows3 = run(manifest, job="texture", tiles=TILES, outdir=out, workers=0, resume=True)
    assert _statuses(rows3) == {"ball": "skipped", "holed": "failed", "ring": "ok"}
    rows4 = run(manifest, job="texture", tiles="studs", outdir=out, workers=0, resume=True)
    assert _statuses(rows4) == {"ball": "ok", "holed": "failed", "ring": "ok"}


def test_unknown_tile_set_fails_only_its_parts(folder, tmp_path):
    parts = read_parts(folder, job="check")
    parts.append(Part(name="tex", input=str(folder / "ball.stl"), job="texture",
                      tiles="no-such-set", source="test"))
    rows = run(parts, outdir=tmp_path / "o", workers=0)
    assert _statuses(rows) == {"ball": "ok", "holed": "failed", "ring": "ok", "tex": "failed"}
    assert "no-such-set" in rows[3]["reason"]
    assert "not watertight" in rows[1]["reason"]


def test_shared_tile_set_loaded_once(folder, tmp_path, monkeypatch):
    from geotex.batch import jobs

    calls = []
    loader = jobs.SHARED_LOADERS["tiles"]
    monkeypatch.setitem(jobs.SHARED_LOADERS, "tiles",
                        lambda name: calls.append(name) or loader(name))
    parts = [Part(name=f"h{i}", input=str(folder / "holed.obj"), job="texture", tiles=TILES,
                  source="test") for i in range(3)]
    rows = run(parts, outdir=tmp_path / "o", workers=0)
    assert calls == [TILES] and [r["status"] for r in rows] == ["failed"] * 3


def test_repair_and_check_jobs(tmp_path):
    from geotex.mesh.primitives import box

    V, F = box(divisions=2)
    write_mesh(tmp_path / "open_box.obj", Mesh(V * 20.0, F[1:]))
    rows = run([Part(name="fixed", input=str(tmp_path / "open_box.obj"), job="repair"),
                Part(name="as-is", input=str(tmp_path / "open_box.obj"), job="check")],
               outdir=tmp_path / "o", workers=0)
    assert _statuses(rows) == {"fixed": "ok", "as-is": "failed"}
    assert rows[0]["printable"] is True and rows[0]["output"] == "fixed.stl"
    fixed = read_mesh(tmp_path / "o" / "fixed.stl")
    assert check_mesh(fixed.vertices, fixed.faces).printable
    assert "not watertight" in rows[1]["reason"] and rows[1]["output"] == ""


def test_output_never_overwrites_an_input(folder):
    parts = read_parts(folder, job="repair")
    with pytest.raises(InputError, match="refusing to overwrite the input"):
        run(parts, outdir=folder, workers=0)


@pytest.mark.parametrize("kwargs, words", [
    ({"workers": -1}, "workers must be a non-negative integer"),
    ({"workers": 1.5}, "workers must be a non-negative integer"),
    ({"client": object(), "scheduler": "tcp://x:1"}, "either client or scheduler"),
])
def test_run_argument_errors(folder, tmp_path, kwargs, words):
    with pytest.raises(InputError, match=words):
        run(read_parts(folder, job="check"), outdir=tmp_path / "o", **kwargs)


# --- a real LocalCluster of 2 processes ---------------------------------------

@pytest.fixture(scope="module")
def client():
    pytest.importorskip("distributed")
    from distributed import Client

    from geotex.batch import local_cluster

    cluster = local_cluster(2)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.mark.parametrize("cpus, n, groups", [
    ([0, 1], 2, [[0], [1]]), ([0, 1], 1, [[0, 1]]), ([0, 1], 3, None),
    ([4, 2, 3], 2, [[2, 3], [4]]), (range(8), 3, [[0, 1, 2], [3, 4, 5], [6, 7]]),
])
def test_split_cpus(cpus, n, groups):
    got = split_cpus(list(cpus), n)
    assert got == groups
    if got is not None:
        assert decode_plan(encode_plan(got)) == got


def test_split_cpus_errors():
    with pytest.raises(InputError, match="at least 1"):
        split_cpus([0, 1], 0)
    with pytest.raises(InputError, match="CPU lists"):
        decode_plan("0,a;1")


def _thread_affinities():
    """Affinity masks of every thread of this (worker) process."""
    masks = set()
    for tid in os.listdir("/proc/self/task"):
        try:
            masks.add(frozenset(os.sched_getaffinity(int(tid))))
        except ProcessLookupError:
            pass
    return masks


def _assert_pinned(client):
    import cloudpickle

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    cpus = available_cpus()
    workers = client.run(_thread_affinities)
    assert len(workers) == 2
    masks = []
    for addr, per_thread in workers.items():
        assert len(per_thread) == 1, (addr, per_thread)     # every thread pinned alike
        masks.append(set(next(iter(per_thread))))
    # a task runs in a worker thread, which must have the same mask
    tasks = client.gather([client.submit(_thread_affinities, pure=False, workers=[a])
                           for a in workers])
    assert [set(next(iter(t))) for t in tasks] == masks
    if len(cpus) >= 2:      # pinned: disjoint, together every CPU of this process
        assert not masks[0] & masks[1]
        assert masks[0] | masks[1] == set(cpus)
    else:                   # more workers than CPUs: not pinned
        assert masks[0] == masks[1] == set(cpus)


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="no CPU affinity here")
def test_local_cluster_workers_are_pinned(client):
    _assert_pinned(client)


def test_local_cluster_batch(client, manifest, tmp_path):
    out = tmp_path / "out"
    seen = []
    rows = run(manifest, job="texture", tiles=TILES, outdir=out, client=client,
               progress=lambda row, done, total: seen.append(done))
    assert _statuses(rows) == {"ball": "ok", "holed": "failed", "ring": "ok"}
    assert sorted(seen) == [1, 2, 3]
    assert "open" in rows[1]["reason"]
    pids = {r["worker"] for r in rows}
    assert all(w and w.split(":")[1] != str(os.getpid()) for w in pids)   # ran on workers
    assert all(r["worker_peak_mb"] > 0 for r in rows)
    for r in (rows[0], rows[2]):
        mesh = read_mesh(out / r["output"])
        assert check_mesh(mesh.vertices, mesh.faces).printable
    # byte-identical to the sequential run: same inputs + seed, same bytes
    seq = run(manifest, job="texture", tiles=TILES, outdir=tmp_path / "seq", workers=0)
    for a, b in zip(rows, seq):
        if a["status"] == "ok":
            assert (out / a["output"]).read_bytes() == (tmp_path / "seq" / b["output"]).read_bytes()
    doc = json.loads((out / "summary.json").read_text())
    assert doc["meta"]["workers"] == 2


def _crash_part(part, shared, out):
    if part.name == "boom":
        os._exit(13)
    return {"faces": 0}


def test_dead_worker_is_retried_once_then_reported(client, tmp_path, monkeypatch):
    import cloudpickle
    from distributed.diagnostics.plugin import WorkerPlugin

    class CrashPlugin(WorkerPlugin):
        """Adds a job that kills its worker on the part named 'boom' (restarts too)."""

        name = "geotex-test-crash"

        def setup(self, worker):
            from geotex.batch import jobs

            jobs.JOBS["crash"] = Job("crash", _crash_part, suffix=None)

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    client.register_plugin(CrashPlugin())
    monkeypatch.setitem(JOBS, "crash", Job("crash", _crash_part, suffix=None))
    f = tmp_path / "x.stl"
    write_mesh(f, Mesh(*icosphere(1)))
    parts = [Part(name=n, input=str(f), job="crash", source="test") for n in ("a", "boom", "b")]
    rows = run(parts, outdir=tmp_path / "o", client=client)
    assert _statuses(rows) == {"a": "ok", "boom": "failed", "b": "ok"}, rows
    assert "worker running this part died 2 times" in rows[1]["reason"]
    client.wait_for_workers(2, timeout=60)
    if hasattr(os, "sched_setaffinity"):
        _assert_pinned(client)          # the restarted worker is pinned again


def test_scheduler_address(client, folder, tmp_path):
    """--scheduler: connect to a running scheduler (here the test cluster's)."""
    rows = run(read_parts(folder, job="check"), outdir=tmp_path / "o",
               scheduler=client.scheduler.address)
    assert _statuses(rows) == {"ball": "ok", "holed": "failed", "ring": "ok"}
    doc = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert doc["meta"]["scheduler"] == client.scheduler.address


# --- command line ------------------------------------------------------------

def _cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_batch_check_job_exit_status(capsys, folder, tmp_path):
    out = tmp_path / "o"
    code, stdout, err = _cli(capsys, "batch", folder, "-o", out, "--job", "check",
                             "--workers", "0")
    assert code == 1
    assert "3 parts: 2 ok, 1 failed, 0 skipped" in stdout
    assert err.strip().startswith("holed: failed: ") and err.count("\n") == 1
    assert (out / "summary.csv").exists()
    code, stdout, _ = _cli(capsys, "batch", folder, "-o", out, "--job", "check",
                           "--workers", "0", "--resume")
    assert code == 1 and "0 ok, 1 failed, 2 skipped" in stdout


@pytest.mark.parametrize("extra, words", [
    (["--workers", "-2"], "--workers -2"),
    (["--workers", "2", "--scheduler", "tcp://h:8786"], "--workers and --scheduler"),
    (["--scheduler", "h:8786"], "--scheduler h:8786"),
    (["--tiles", "no-such-set"], "--tiles no-such-set"),
    (["--seed", "-1"], "--seed -1"),
    (["--size-mm", "0"], "--size-mm 0"),
    (["--job", "paint"], "argument --job: invalid choice"),
])
def test_cli_batch_usage_errors(capsys, folder, tmp_path, extra, words):
    code, stdout, err = _cli(capsys, "batch", folder, "-o", tmp_path / "o", *extra)
    assert code == 2 and stdout == ""
    assert err.startswith("geotex: error: ") and words in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_cli_batch_file_errors(capsys, folder, tmp_path):
    code, _, err = _cli(capsys, "batch", tmp_path / "none.csv", "-o", tmp_path / "o")
    assert code == 2 and "none.csv: no such manifest file or folder" in err
    code, _, err = _cli(capsys, "batch", folder, "-o", folder, "--job", "check")
    assert code == 2 and "is the input folder" in err
    (tmp_path / "file").write_text("x")
    code, _, err = _cli(capsys, "batch", folder, "-o", tmp_path / "file", "--job", "check")
    assert code == 2 and "must be a folder" in err
    bad = tmp_path / "bad.csv"
    bad.write_text("input,size_mm\nball.stl,huge\n")
    code, _, err = _cli(capsys, "batch", bad, "-o", tmp_path / "o2", "--tiles", TILES)
    assert code == 2 and f"{bad}:2: column size_mm: 'huge'" in err


def test_displace_job_writes_a_printable_relief(tmp_path):
    write_mesh(tmp_path / "ball.stl", Mesh(icosphere(2)[0] * 10.0, icosphere(2)[1]))
    rows = run([Part(name="dots", input=str(tmp_path / "ball.stl"), job="displace",
                     image="dots", height=0.5, size_mm=30.0)],
               outdir=tmp_path / "o", workers=0)
    assert _statuses(rows) == {"dots": "ok"} and rows[0]["printable"] is True
    m = read_mesh(tmp_path / "o" / "dots.stl")
    assert check_mesh(m.vertices, m.faces).printable
