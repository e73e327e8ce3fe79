"""Seeded hostile mesh files and a harness running ``geotex check`` on them.

Used by ``tests/test_fuzz.py`` (a few hundred cases) and
``benchmarks/fuzz.py`` (ten thousand).  :func:`make_cases` writes mutated
copies of small valid files in every format (byte flips, truncation, huge
header counts, NaN / inf / huge numbers, bad indices, corrupt zip and JSON
chunks, hostile references, wrong extensions); :func:`run_cases` runs
``geotex check`` on each, in a subprocess with an address-space limit and a
timeout, and :func:`verdict` says whether the outcome is an acceptable one:

* exit 0 or 1 with a report on stdout (a ``printable:`` line), or
* exit 2 with exactly one stderr line ``geotex: error: ...``,

within :data:`TIME_LIMIT` seconds and :data:`MEMORY_LIMIT` bytes of peak
resident memory.  Cases are batched (``python -m geotex.fuzzing FILE...``
runs the command line on each file in turn, isolated by ``try``/``except``,
and prints one JSON line per file, with the case's own seconds and peak: the
kernel's high-water mark is reset before each case, :func:`reset_peak_rss`).
Hostile cases (huge counts, bombs, references, deep nesting, large polygons)
go in small batches, or each in its own ``python -m geotex check FILE``
process (``hostile_batch=1``, what the benchmark does, timing the whole
process start-up included).  A case left unfinished by a batch (the batch was
killed or died) is run again alone.

The same seed gives the same files.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import os
import random
import re
import struct
import sys
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geotex.cli import main
from geotex.io import write_mesh
from geotex.mesh.primitives import box
from geotex.mesh.record import Mesh

__all__ = ["FuzzCase", "Outcome", "make_cases", "run_cases", "verdict", "seed_files",
           "TIME_LIMIT", "MEMORY_LIMIT", "ADDRESS_LIMIT", "run_batch", "peak_rss", "reset_peak_rss"]

TIME_LIMIT = 10.0                 # seconds per case
MEMORY_LIMIT = 1 << 30            # peak resident bytes per case (or batch)
ADDRESS_LIMIT = 3 << 29           # RLIMIT_AS of every subprocess (1.5 GiB)
FORMATS = ("stl", "stl-ascii", "obj", "ply", "ply-ascii", "off", "3mf", "glb")


@dataclass
class FuzzCase:
    """One mutated file: ``path``, the ``seed`` format, the ``mutation`` and
    whether it is ``hostile`` (run alone or in a small batch)."""
    path: Path
    seed: str
    mutation: str
    hostile: bool = False


@dataclass
class Outcome:
    case: FuzzCase
    code: int | None             # None: killed (timeout)
    stdout: str
    stderr: str
    seconds: float
    maxrss: int                  # bytes (the case's own peak, see reset_peak_rss)
    notes: list = field(default_factory=list)


# --------------------------------------------------------------------------- seed files


def seed_files(folder) -> dict[str, Path]:
    """Write small valid files (a subdivided box, a texture for OBJ and GLB)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    V, F = box(divisions=2)
    uv = V[:, :2].copy()
    tex = np.zeros((4, 4, 3), dtype=np.uint8)
    tex[::2, ::2] = 255
    plain = Mesh(V, F, name="seed")
    textured = Mesh(V, F, uv=uv, uv_faces=F, texture=tex, name="seed")
    out = {}
    for key in FORMATS:
        ext = key.split("-")[0]
        path = folder / f"seed_{key.replace('-', '_')}.{ext}"
        write_mesh(path, textured if ext in ("obj", "glb") else plain,
                   binary="ascii" not in key)
        out[key] = path
    return out


# --------------------------------------------------------------------------- mutations

_NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
_WEIRD_NUMBERS = [b"nan", b"inf", b"-inf", b"1e400", b"-1e308", b"1e-400",
                  b"99999999999999999999999", b"-0", b"0x1F", b"1..2", b"", b"1e",
                  b"4294967296", b"-2147483649", b"9223372036854775808", b"NaN"]
_WEIRD_INDICES = [b"0", b"-1", b"-999999", b"1000000", b"4294967295", b"2147483648",
                  b"9223372036854775807", b"99999999999999999999", b"1.5", b"x"]
_HUGE = [2 ** 31 - 1, 2 ** 31, 2 ** 32 - 1, 2 ** 40, 10 ** 12, 2 ** 62, 2 ** 64]


def _flip(rng, data):
    b = bytearray(data)
    for _ in range(rng.randint(1, 8)):
        i = rng.randrange(len(b))
        b[i] = rng.randrange(256) if rng.random() < 0.5 else b[i] ^ (1 << rng.randrange(8))
    return bytes(b)


def _truncate(rng, data):
    return data[:rng.randrange(0, len(data))]


def _splice_numbers(rng, data, pool):
    matches = list(_NUMBER.finditer(data))
    if not matches:
        return _flip(rng, data)
    b = data
    for m in sorted(rng.sample(matches, min(len(matches), rng.randint(1, 3))),
                    key=lambda m: -m.start()):
        b = b[:m.start()] + rng.choice(pool) + b[m.end():]
    return b


def _text_header(rng, key, data):
    n = str(rng.choice(_HUGE + [-1])).encode()
    if key.startswith("ply"):
        which = rng.choice([b"vertex", b"face"])
        return re.sub(rb"element " + which + rb" \d+", b"element " + which + b" " + n, data)
    if key == "off":
        return re.sub(rb"\A(OFF\s+)\d+ \d+", lambda m: m.group(1) + n + b" " + n, data)
    if key == "obj":
        return data + b"\nf 1 2 " + n + b"\n"
    if key == "stl-ascii":
        return data.replace(b"outer loop", b"outer loop\nvertex " + n + b" 0 0", 1)
    return data


def _binary_header(rng, key, data):
    b = bytearray(data)
    if key == "stl":
        struct.pack_into("<I", b, 80, rng.choice([2 ** 32 - 1, 2 ** 31, 10 ** 9]))
        return bytes(b)
    if key == "ply":
        return _text_header(rng, "ply", data)
    return data


def _binary_numbers(rng, key, data):
    """NaN / inf / huge float32 values, or bad indices, at random aligned spots."""
    b = bytearray(data)
    start = 84 if key == "stl" else (data.find(b"end_header\n") + 11 if key == "ply" else 20)
    for _ in range(rng.randint(1, 4)):
        if len(b) - start < 4:
            break
        i = start + 4 * rng.randrange((len(b) - start) // 4)
        value = rng.choice([float("nan"), float("inf"), -float("inf"), 3.4e38, -3.4e38])
        if rng.random() < 0.5:
            struct.pack_into("<f", b, i, value)
        else:
            struct.pack_into("<I", b, i, rng.choice([2 ** 32 - 1, 2 ** 31, 10 ** 6, 7]))
    return bytes(b)


def _zip_members(data):
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return [(info, z.read(info)) for info in z.infolist()]


def _rezip(members, *, stored=False):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED if stored else zipfile.ZIP_DEFLATED) as z:
        for name, payload in members:
            z.writestr(zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0)), payload,
                       compress_type=zipfile.ZIP_STORED if stored else zipfile.ZIP_DEFLATED)
    return buf.getvalue()


def _model_name(members):
    return next((i.filename for i, _ in members if i.filename.endswith(".model")), None)


def _threemf(rng, data, what):
    members = _zip_members(data)
    model = _model_name(members)
    items = [(i.filename, p) for i, p in members]
    if what == "xml":
        items = [(n, _splice_numbers(rng, p, _WEIRD_NUMBERS + _WEIRD_INDICES)
                  if n == model else p) for n, p in items]
    elif what == "xml-flip":
        items = [(n, _flip(rng, p) if n == model else p) for n, p in items]
    elif what == "xml-truncate":
        items = [(n, _truncate(rng, p) if n == model else p) for n, p in items]
    elif what == "drop-part":
        items = [(n, p) for n, p in items if n != model or rng.random() < 0.2]
    elif what == "unit":
        items = [(n, p.replace(b'unit="millimeter"', rng.choice(
            [b'unit="parsec"', b'unit=""', b'unit="meter"'])) if n == model else p)
            for n, p in items]
    elif what == "transform":
        t = rng.choice([b"1 0 0 0 1 0 0 0 1 nan 0 0", b"1e308 0 0 0 1e308 0 0 0 1e308 0 0 0",
                        b"1 2 3", b"0 0 0 0 0 0 0 0 0 0 0 0"])
        items = [(n, p.replace(b"<item objectid=\"1\"", b"<item objectid=\"1\" transform=\""
                               + t + b"\"") if n == model else p) for n, p in items]
    elif what == "bomb":
        size = rng.choice([20, 60]) << 20
        items = [(n, (p + b" " * size) if n == model else p) for n, p in items]
    elif what == "declared-size":
        blob = bytearray(_rezip(items))
        # lie about the inflated size in the central directory
        at = blob.rfind(b"PK\x01\x02")
        if at >= 0:
            struct.pack_into("<I", blob, at + 24, rng.choice([0, 1, 2 ** 32 - 1, 2 ** 31]))
        return bytes(blob)
    elif what == "entities":                       # "billion laughs"
        dtd = (b'<?xml version="1.0"?>\n<!DOCTYPE model [\n<!ENTITY a0 "lollollol">\n'
               + b"".join(b"<!ENTITY a%d \"" % i + b"&a%d;" % (i - 1) * 10 + b"\">\n"
                          for i in range(1, 10)) + b"]>\n")
        items = [(n, dtd + re.sub(rb"^<\?xml[^>]*>\s*", b"", p).replace(
            b"<resources>", b"<metadata name=\"x\">&a9;</metadata><resources>", 1))
            if n == model else (n, p) for n, p in items]
    elif what == "recursion":
        extra = b'<components><component objectid="1"/></components>'
        items = [(n, p.replace(b"<mesh>", extra + b"<mesh>", 1) if n == model else p)
                 for n, p in items]
    return _rezip(items, stored=what != "bomb" and rng.random() < 0.3)


def _glb_parts(data):
    jlen = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + jlen])
    rest = data[20 + jlen:]
    binary = rest[8:] if len(rest) >= 8 else b""
    return doc, binary


def _glb_pack(doc_bytes, binary):
    doc_bytes += b" " * (-len(doc_bytes) % 4)
    body = struct.pack("<II", len(doc_bytes), 0x4E4F534A) + doc_bytes
    if binary:
        binary += b"\x00" * (-len(binary) % 4)
        body += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


_JSON_VALUES = [None, True, -1, 0, 2 ** 40, 2 ** 64, 1.5, 1e308, "x", "", [], {}, [1, 2],
                {"a": 1}, "../../etc/passwd", "/dev/zero", "data:,", float("nan")]


def _mutate_json(rng, node, depth=0):
    """Replace a random value somewhere in the document."""
    if isinstance(node, dict) and node:
        key = rng.choice(sorted(node))
        if rng.random() < 0.35 or not isinstance(node[key], (dict, list)):
            node[key] = copy.deepcopy(rng.choice(_JSON_VALUES))
        else:
            _mutate_json(rng, node[key], depth + 1)
    elif isinstance(node, list) and node:
        i = rng.randrange(len(node))
        if rng.random() < 0.35 or not isinstance(node[i], (dict, list)):
            node[i] = copy.deepcopy(rng.choice(_JSON_VALUES))
        else:
            _mutate_json(rng, node[i], depth + 1)


def _glb(rng, data, what):
    doc, binary = _glb_parts(data)
    if what == "json-values":
        for _ in range(rng.randint(1, 3)):
            _mutate_json(rng, doc)
        return _glb_pack(json.dumps(doc).encode(), binary)
    if what == "json-text":
        text = _flip(rng, json.dumps(doc).encode())
        return _glb_pack(text, binary)
    if what == "deep":
        n = rng.choice([2000, 100000])
        return _glb_pack(b"{\"asset\":" + b"[" * n + b"]" * n + b"}", binary)
    if what == "uri":
        doc["buffers"][0]["uri"] = rng.choice([
            "/dev/zero", "/etc/passwd", "../../../../dev/zero", "file:///dev/zero",
            "http://example.com/x.bin", "sub/../../x.bin", "%2Fdev%2Fzero", "C:/x.bin",
            "missing.bin", ".", "data:application/octet-stream;base64,AAAA",
            "data:application/octet-stream;base64," + "A" * 4000, "data:text/plain,hello"])
        return _glb_pack(json.dumps(doc).encode(), b"")
    if what == "counts":
        acc = rng.choice(doc["accessors"])
        acc[rng.choice(["count", "byteOffset"])] = rng.choice(_HUGE)
        if rng.random() < 0.3:
            acc.pop("bufferView", None)
        if rng.random() < 0.3:
            doc["buffers"][0]["byteLength"] = rng.choice(_HUGE)
        return _glb_pack(json.dumps(doc).encode(), binary)
    if what == "chunk-length":
        b = bytearray(data)
        struct.pack_into("<I", b, rng.choice([8, 12]), rng.choice(_HUGE[:3] + [0, 7]))
        return bytes(b)
    return data


def _big_polygon(rng):
    n = rng.choice([1000, 12000, 60000])
    lines = ["v 0 0 0", "v 1 0 0", "v 1 1 0", "v 0 1 0", "v 0.5 0.5 0", "v 0.2 0.7 0"]
    k = rng.choice([6, 50])
    if k == 50:
        lines += [f"v {rng.random()!r} {rng.random()!r} 0" for _ in range(44)]
    lines.append("f " + " ".join(str(rng.randint(1, k)) for _ in range(n)))
    return ("\n".join(lines) + "\n").encode()


# (name, formats it applies to or None for all, hostile, function(rng, key, data))
_MUTATIONS = [
    ("flip", None, False, lambda r, k, d: _flip(r, d)),
    ("truncate", None, False, lambda r, k, d: _truncate(r, d)),
    ("numbers", ("stl-ascii", "obj", "ply-ascii", "off"), False,
     lambda r, k, d: _splice_numbers(r, d, _WEIRD_NUMBERS)),
    ("indices", ("obj", "ply-ascii", "off"), False,
     lambda r, k, d: _splice_numbers(r, d, _WEIRD_INDICES)),
    ("binary-numbers", ("stl", "ply"), False, _binary_numbers),
    ("header-count", ("stl", "ply", "ply-ascii", "off", "obj", "stl-ascii"), True,
     lambda r, k, d: _binary_header(r, k, d) if k in ("stl", "ply") else _text_header(r, k, d)),
    ("3mf-xml", ("3mf",), False, lambda r, k, d: _threemf(r, d, "xml")),
    ("3mf-xml-flip", ("3mf",), False, lambda r, k, d: _threemf(r, d, "xml-flip")),
    ("3mf-xml-truncate", ("3mf",), False, lambda r, k, d: _threemf(r, d, "xml-truncate")),
    ("3mf-drop-part", ("3mf",), False, lambda r, k, d: _threemf(r, d, "drop-part")),
    ("3mf-unit", ("3mf",), False, lambda r, k, d: _threemf(r, d, "unit")),
    ("3mf-transform", ("3mf",), False, lambda r, k, d: _threemf(r, d, "transform")),
    ("3mf-recursion", ("3mf",), True, lambda r, k, d: _threemf(r, d, "recursion")),
    ("3mf-entities", ("3mf",), True, lambda r, k, d: _threemf(r, d, "entities")),
    ("3mf-declared-size", ("3mf",), True, lambda r, k, d: _threemf(r, d, "declared-size")),
    ("3mf-bomb", ("3mf",), True, lambda r, k, d: _threemf(r, d, "bomb")),
    ("glb-json-values", ("glb",), False, lambda r, k, d: _glb(r, d, "json-values")),
    ("glb-json-text", ("glb",), False, lambda r, k, d: _glb(r, d, "json-text")),
    ("glb-chunk-length", ("glb",), False, lambda r, k, d: _glb(r, d, "chunk-length")),
    ("glb-deep", ("glb",), True, lambda r, k, d: _glb(r, d, "deep")),
    ("glb-uri", ("glb",), True, lambda r, k, d: _glb(r, d, "uri")),
    ("glb-counts", ("glb",), True, lambda r, k, d: _glb(r, d, "counts")),
    ("obj-polygon", ("obj",), True, lambda r, k, d: _big_polygon(r)),
]
_WRONG_EXT = ("stl", "obj", "ply", "off", "3mf", "glb", "txt", "")


def make_cases(folder, n: int, *, seed: int = 0, hostile_share: float = 0.15
               ) -> list[FuzzCase]:
    """Write ``n`` mutated files into ``folder`` (deterministic for a seed).

    Ordinary and hostile mutations each cycle through their (format,
    mutation) pairs, so a small ``n`` still covers all of them; about
    ``hostile_share`` of the cases (at least one of each hostile pair) are
    hostile, and one ordinary case in eight also gets a wrong extension.
    """
    folder = Path(folder)
    seeds = seed_files(folder / "seeds")
    raw = {k: p.read_bytes() for k, p in seeds.items()}
    # the OBJ and GLB seeds refer to their texture files by name: copy them
    for p in (folder / "seeds").iterdir():
        if p.suffix in (".mtl", ".png"):
            (folder / p.name).write_bytes(p.read_bytes())
    pairs = [(key, m) for m in _MUTATIONS for key in FORMATS
             if m[1] is None or key in m[1]]
    hostile = [p for p in pairs if p[1][2]]
    ordinary = [p for p in pairs if not p[1][2]]
    n_hostile = min(n, max(len(hostile), round(n * hostile_share)))
    plan = [hostile[i % len(hostile)] for i in range(n_hostile)]
    plan += [ordinary[i % len(ordinary)] for i in range(n - n_hostile)]
    rng = random.Random(seed)
    rng.shuffle(plan)
    cases = []
    for i, (key, (name, _, is_hostile, fn)) in enumerate(plan):
        data = fn(rng, key, raw[key])
        ext = key.split("-")[0]
        mutation = name
        if rng.random() < 0.125 and not is_hostile:
            ext = rng.choice([e for e in _WRONG_EXT if e != ext])
            mutation += f"+ext:{ext or 'none'}"
        stem = f"case{i:05d}_{key}_{name}"
        path = folder / (f"{stem}.{ext}" if ext else stem)
        path.write_bytes(data)
        cases.append(FuzzCase(path, key, mutation, is_hostile))
    return cases


# --------------------------------------------------------------------------- running


def _limit_address_space():  # pragma: no cover - runs in the child
    import resource
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_LIMIT, ADDRESS_LIMIT))
    os.nice(5)


def peak_rss(pid="self") -> int | None:
    """Peak resident bytes of a process's own program (``VmHWM``), None where unknown.

    ``ru_maxrss`` is not that: Linux starts a forked child's maximum at the
    parent's size (the copied address space), and ``exec`` keeps it, so a
    small program started from a large test process reports the parent's
    size.  ``VmHWM`` belongs to the address space the program made at exec.
    """
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def reset_peak_rss() -> bool:
    """Reset this process's ``VmHWM`` to its current size; False where the kernel cannot.

    Writing ``5`` to ``/proc/self/clear_refs`` (Linux 4.0 and later) restarts
    the high-water mark, so that :func:`peak_rss` after a case is that case's
    peak (the memory the process already held included), not the batch's.
    """
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


def run_limited(cmd, timeout, env):
    """Run ``cmd``; return (code or None, stdout, stderr, seconds, maxrss bytes).

    The peak is the child's own (:func:`peak_rss`, read while it runs) unless
    ``ru_maxrss`` exceeds this process's size at the start, in which case that
    is the child's.
    """
    import subprocess
    import tempfile

    own = peak_rss() or 0
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL,
                                preexec_fn=_limit_address_space, env=env)
        code, usage, polled = None, None, 0
        while True:
            polled = max(polled, peak_rss(proc.pid) or 0)
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                code = os.waitstatus_to_exitcode(status)
                proc.returncode = code
                break
            if time.perf_counter() - start > timeout:
                proc.kill()
                _, _, usage = os.wait4(proc.pid, 0)
                proc.returncode = -9
                break
            time.sleep(0.005)
        seconds = time.perf_counter() - start
        out.seek(0)
        err.seek(0)
        peak = usage.ru_maxrss * 1024
        if peak <= own:            # the inherited size of this process: use the polled peak
            peak = polled
        return (code, out.read().decode("utf-8", "replace"),
                err.read().decode("utf-8", "replace"), seconds, peak)


def limited_env():
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parent.parent)
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    env.pop("GEOTEX_DEBUG", None)
    env["PYTHONWARNINGS"] = "default"
    return env


def run_batch(command, cases, env) -> tuple:
    """Run ``command`` on the files of ``cases`` in one limited process.

    The process gets :data:`TIME_LIMIT` seconds per case and prints one JSON
    object with a ``"file"`` key per line for every file it finished.

    Returns
    -------
    code : int or None
        Exit status (None or -9 when killed at the time limit).
    stderr : str
    maxrss : int
        Peak resident size of the process, bytes.
    rows : dict
        The JSON rows by ``file``; a file without a row was not finished.
    """
    code, out, err, _, rss = run_limited(list(command) + [str(c.path) for c in cases],
                                         TIME_LIMIT * len(cases), env)
    rows = {}
    for line in out.splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        rows[row["file"]] = row
    return code, err, rss, rows


def run_cases(cases, *, batch: int = 40, hostile_batch: int = 1, workers: int = 2
              ) -> list[Outcome]:
    """Run ``geotex check`` on every case (see the module notes); outcomes in order.

    ``batch`` ordinary cases share a process, and ``hostile_batch`` hostile
    ones (1: each hostile case in its own ``python -m geotex check`` process).
    """
    from concurrent.futures import ThreadPoolExecutor

    env = limited_env()
    jobs = []
    hostile = [c for c in cases if c.hostile]
    ordinary = [c for c in cases if not c.hostile]
    for group, size in ((hostile, hostile_batch), (ordinary, batch)):
        jobs += [group[i:i + size] for i in range(0, len(group), max(1, size))]

    def run_job(group):
        if len(group) == 1 and group[0].hostile and hostile_batch == 1:
            c = group[0]
            code, out, err, sec, rss = run_limited([sys.executable, "-m", "geotex", "check",
                                                   str(c.path)], TIME_LIMIT, env)
            return [Outcome(c, code, out, err, sec, rss)]
        code, err, rss, rows = run_batch([sys.executable, "-m", "geotex.fuzzing"], group, env)
        results = []
        for c in group:
            row = rows.get(str(c.path))
            if row is None:           # the batch died: attribute by rerunning alone
                c2, o2, e2, s2, r2 = run_limited([sys.executable, "-m", "geotex", "check",
                                                 str(c.path)], TIME_LIMIT, env)
                results.append(Outcome(c, c2, o2, e2, s2, r2, [f"batch exit {code}"]))
                continue
            notes = [] if not err.strip() else [f"batch stderr: {err.strip()[:200]}"]
            results.append(Outcome(c, row["code"], row["stdout"], row["stderr"],
                                   row["seconds"], row["maxrss"] if row["own_peak"] else rss,
                                   notes))
        return results

    with ThreadPoolExecutor(max_workers=workers) as pool:
        done = list(pool.map(run_job, jobs))
    by_path = {o.case.path: o for group in done for o in group}
    return [by_path[c.path] for c in cases]


def verdict(outcome: Outcome) -> str | None:
    """None when the outcome is acceptable, else what is wrong with it."""
    o = outcome
    if o.code == -1 and "escaped:" in o.stderr:
        return f"exception escaped the command line: {o.stderr.strip()[-300:]!r}"
    if o.code is None or o.code < 0:
        return f"killed after {o.seconds:.1f} s (timeout or signal {o.code})"
    if o.seconds > TIME_LIMIT:
        return f"took {o.seconds:.1f} s"
    if o.maxrss > MEMORY_LIMIT:
        return f"peak memory {o.maxrss >> 20} MiB"
    if o.code in (0, 1):
        if "printable:" not in o.stdout:
            return f"exit {o.code} without a report"
        if o.stderr.strip():
            return f"exit {o.code} with stderr {o.stderr.strip()[:200]!r}"
        return None
    if o.code == 2:
        lines = o.stderr.splitlines()
        if len(lines) != 1 or not lines[0].startswith("geotex: error: "):
            return f"exit 2 with stderr {o.stderr.strip()[:300]!r}"
        return None
    return f"exit {o.code}: {o.stderr.strip()[:300]!r}"


def _drive(files) -> int:  # pragma: no cover - runs in the batch subprocess
    """Run ``geotex check`` on each file in this process; one JSON line each."""
    import resource

    real_stdout = sys.stdout
    for name in files:
        out, err = io.StringIO(), io.StringIO()
        own_peak = reset_peak_rss()
        start = time.perf_counter()
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                code = main(["check", name])
        except BaseException as exc:  # noqa: BLE001 - isolate every case
            code = -1
            err.write(f"escaped: {type(exc).__name__}: {exc}\n")
        row = {"file": name, "code": code, "stdout": out.getvalue()[-4000:],
               "stderr": err.getvalue()[:4000], "seconds": time.perf_counter() - start,
               "own_peak": own_peak and peak_rss() is not None,
               "maxrss": peak_rss()
               or resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}
        print(json.dumps(row), file=real_stdout, flush=True)
    return 0


if __name__ == "__main__":  # pragma: no cover
    import warnings
    warnings.simplefilter("default")
    sys.exit(_drive(sys.argv[1:]))
