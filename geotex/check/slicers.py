"""Second opinions on a written file: PrusaSlicer and admesh.

geotex's own check (:func:`geotex.check.check_mesh`, ``geotex check FILE``) is
one judge of printability; a slicer is the one that matters to the user.  This
module runs two independent programs on the *written file* (after float32
rounding, exactly what a printer's software reads) and turns their statistics
into strict verdicts:

``prusa-slicer --info FILE`` (STL or 3MF)
    PrusaSlicer loads the file, repairs it silently (admesh's algorithms, built
    in) and prints the statistics of that repair.  A file is accepted when it is
    ``manifold = yes`` *and* the repair had nothing to do: no open edges, no
    degenerate facets, no edges fixed, no facets removed or reversed, no
    backwards edges, a positive volume and the expected number of parts.
    ``manifold = yes`` alone is not enough: it is reported *after* the repair,
    so a file whose degenerate facets were dropped on load still says ``yes``.

``admesh FILE`` (STL only)
    admesh checks and fixes the mesh (exact and nearby edge matching, removal
    of unconnected facets, hole filling, orientation).  A file is accepted when
    the *original* mesh has no disconnected facets, and no degenerate facets,
    fixed edges, removed, added or reversed facets, nor backwards edges were
    counted, the volume is positive and the number of parts is the expected one.

    ``Normals fixed`` is *not* counted against the file.  admesh recomputes each
    facet's normal from its float32 vertices and "fixes" the stored normal when
    a component differs by 0.001 or more.  geotex stores unit normals computed
    from the float64 geometry, so tiny or sliver facets whose float32 corners
    tilt the plane get counted although the geometry is fine (slicers ignore
    stored normals and recompute them).  The count is kept as a note.

Neither program looks for self-intersections (a file whose float32 rounding
made two facets cross passes both; ``geotex check`` catches it), so these
verdicts complement :func:`geotex.check.check_mesh`, they do not replace it.
A 3MF stores decimal coordinates: PrusaSlicer may accept the 3MF of a solid
whose float32 STL has degenerate facets; judge the STL to see those.

Both programs run without a shell, with a timeout, in a temporary ``HOME``
(PrusaSlicer must not write its configuration into the user's home), with
``LC_ALL=C`` so numbers use a decimal point.

Examples
--------
>>> from geotex.check.slicers import slicer_verdicts
>>> # skipped in doctests: needs PrusaSlicer, admesh and a mesh file
>>> v = slicer_verdicts("part.stl")                          # doctest: +SKIP
>>> v["prusaslicer"]["ok"], v["admesh"]["ok"]                 # doctest: +SKIP
(True, True)
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

from geotex.errors import ExternalToolError, MissingFileError, ToolNotFoundError

__all__ = [
    "PRUSASLICER", "ADMESH", "DEFAULT_TIMEOUT",
    "prusaslicer_info", "admesh_report", "slicer_verdicts",
    "parse_prusaslicer_info", "parse_admesh_report",
    "prusaslicer_verdict", "admesh_verdict",
]

PRUSASLICER = "prusa-slicer"
ADMESH = "admesh"
DEFAULT_TIMEOUT = 300.0

_PACKAGES = {PRUSASLICER: "prusa-slicer", ADMESH: "admesh"}

# Counters PrusaSlicer prints only when non-zero (after its repair on load).
_PRUSA_COUNTS = ("open_edges", "degenerate_facets", "edges_fixed", "facets_removed",
                 "facets_reversed", "backwards_edges")


def _run(tool: str, args: list[str], path, timeout: float) -> tuple[int, str]:
    """Run ``tool *args path`` in a scratch HOME; return (exit code, stdout + stderr)."""
    exe = shutil.which(tool)
    if exe is None:
        raise ToolNotFoundError(
            f"{tool} is not installed (not on PATH): install it, e.g. "
            f"'apt-get install {_PACKAGES.get(tool, tool)}'", tool)
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such file")
    with tempfile.TemporaryDirectory(prefix="geotex-slicer-") as home:
        env = {"PATH": os.environ.get("PATH", os.defpath), "HOME": home,
               "XDG_CONFIG_HOME": os.path.join(home, "config"),
               "XDG_CACHE_HOME": os.path.join(home, "cache"),
               "XDG_DATA_HOME": os.path.join(home, "data"),
               "TMPDIR": home, "LC_ALL": "C", "LANG": "C"}
        try:
            proc = subprocess.run([exe, *args, str(path.resolve())], cwd=home, env=env,
                                  stdin=subprocess.DEVNULL, capture_output=True,
                                  timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            raise ExternalToolError(
                f"{path}: {tool} did not finish within {timeout:g} s; "
                f"give a longer timeout or a smaller file", tool) from None
        except OSError as exc:
            raise ExternalToolError(f"{path}: cannot run {exe}: {exc}", tool) from None
    text = (proc.stdout + b"\n" + proc.stderr).decode("utf-8", errors="replace")
    return proc.returncode, text


def _last_message(text: str) -> str:
    """The last meaningful line of a program's output (its error message)."""
    lines = [ln.strip() for ln in text.splitlines()
             if ln.strip() and not re.match(r"^\[\d{4}-\d\d-\d\d .*\]\s*\[\w+\]", ln.strip())]
    return lines[-1] if lines else "no output"


def _number(s: str):
    s = s.strip()
    try:
        return int(s)
    except ValueError:
        return float(s)


def parse_prusaslicer_info(text: str) -> dict:
    """Parse the output of ``prusa-slicer --info FILE``.

    Parameters
    ----------
    text : str
        Standard output (log lines are ignored).

    Returns
    -------
    dict
        ``objects``: one dict per ``[name]`` section with its ``key = value``
        pairs; and totals over the objects: ``number_of_facets``, ``manifold``
        (bool, all objects), the repair counters ``open_edges``,
        ``degenerate_facets``, ``edges_fixed``, ``facets_removed``,
        ``facets_reversed``, ``backwards_edges`` (0 when not printed),
        ``number_of_parts``, ``volume``.

    Raises
    ------
    ValueError
        If the text has no ``[name]`` section with ``number_of_facets``.
    """
    objects: list[dict] = []
    for line in text.splitlines():
        line = line.strip()
        m = re.fullmatch(r"\[(.+)\]", line)
        if m and not re.match(r"\d{4}-\d\d-\d\d", m.group(1)):
            objects.append({"name": m.group(1)})
            continue
        m = re.fullmatch(r"([a-z_]+)\s*=\s*(\S+)", line)
        if m and objects:
            key, value = m.groups()
            objects[-1][key] = value == "yes" if key == "manifold" else _number(value)
    objects = [o for o in objects if "number_of_facets" in o]
    if not objects:
        raise ValueError("no object statistics in prusa-slicer --info output")
    out = {"objects": objects,
           "number_of_facets": sum(o["number_of_facets"] for o in objects),
           "manifold": all(o.get("manifold", False) for o in objects),
           "number_of_parts": sum(o.get("number_of_parts", 0) for o in objects),
           "volume": float(sum(o.get("volume", 0.0) for o in objects))}
    for key in _PRUSA_COUNTS:
        out[key] = sum(o.get(key, 0) for o in objects)
    return out


def prusaslicer_info(path, *, timeout: float = DEFAULT_TIMEOUT) -> dict:
    """Run ``prusa-slicer --info`` on a mesh file and parse its statistics.

    Parameters
    ----------
    path : str or os.PathLike
        STL, 3MF or OBJ file.
    timeout : float, optional
        Seconds before the program is stopped.

    Returns
    -------
    dict
        See :func:`parse_prusaslicer_info`.

    Raises
    ------
    ToolNotFoundError
        If ``prusa-slicer`` is not on ``PATH``.
    ExternalToolError
        If it cannot load the file, fails, or times out.
    MissingFileError
        If ``path`` is not a file.
    """
    code, text = _run(PRUSASLICER, ["--info"], path, timeout)
    try:
        info = parse_prusaslicer_info(text)
    except ValueError:
        info = None
    if code != 0 or info is None:
        raise ExternalToolError(f"{path}: prusa-slicer --info failed (exit {code}): "
                                f"{_last_message(text)}", PRUSASLICER)
    return info


_ADMESH_ROWS = {
    "Number of facets": "facets",
    "Facets with 1 disconnected edge": "disconnected_1",
    "Facets with 2 disconnected edges": "disconnected_2",
    "Facets with 3 disconnected edges": "disconnected_3",
    "Total disconnected facets": "disconnected_facets",
}
_ADMESH_STATS = {
    "Degenerate facets": "degenerate_facets",
    "Edges fixed": "edges_fixed",
    "Facets removed": "facets_removed",
    "Facets added": "facets_added",
    "Facets reversed": "facets_reversed",
    "Backwards edges": "backwards_edges",
    "Normals fixed": "normals_fixed",
}


def parse_admesh_report(text: str) -> dict:
    """Parse the results table admesh prints.

    Parameters
    ----------
    text : str
        admesh's standard output.

    Returns
    -------
    dict
        ``facets``, ``disconnected_1``, ``disconnected_2``, ``disconnected_3``,
        ``disconnected_facets``: counts of the *original* mesh, each also as
        ``<name>_final`` after admesh's fixes; ``parts``, ``volume``,
        ``degenerate_facets``, ``edges_fixed``, ``facets_removed``,
        ``facets_added``, ``facets_reversed``, ``backwards_edges``,
        ``normals_fixed``; ``file_type``.

    Raises
    ------
    ValueError
        If the results table is missing or incomplete.
    """
    out: dict = {}
    for line in text.splitlines():
        label, sep, rest = line.partition(":")
        label = label.strip()
        if not sep:
            continue
        if label in _ADMESH_ROWS:
            nums = rest.split()
            if len(nums) == 2:
                out[_ADMESH_ROWS[label]] = int(nums[0])
                out[_ADMESH_ROWS[label] + "_final"] = int(nums[1])
        elif label == "Number of parts":
            m = re.match(r"\s*(\d+)\s+Volume\s*:\s*(\S+)", rest)
            if m:
                out["parts"], out["volume"] = int(m.group(1)), float(m.group(2))
        elif label in _ADMESH_STATS:
            out[_ADMESH_STATS[label]] = int(rest.split()[0])
        elif label == "File type":
            out["file_type"] = rest.strip()
    needed = ["facets", "disconnected_facets", "parts", *_ADMESH_STATS.values()]
    missing = [k for k in needed if k not in out]
    if missing:
        raise ValueError(f"admesh output lacks {', '.join(missing)}")
    return out


def admesh_report(path, *, timeout: float = DEFAULT_TIMEOUT) -> dict:
    """Run ``admesh`` (check and fix, writing nothing) on an STL file and parse it.

    Parameters
    ----------
    path : str or os.PathLike
        Binary or ASCII STL file (admesh reads nothing else).
    timeout : float, optional
        Seconds before the program is stopped.

    Returns
    -------
    dict
        See :func:`parse_admesh_report`.

    Raises
    ------
    ToolNotFoundError
        If ``admesh`` is not on ``PATH``.
    ExternalToolError
        If the file is not an STL, admesh cannot read it, fails, or times out.
    MissingFileError
        If ``path`` is not a file.
    """
    if Path(path).suffix.lower() != ".stl":
        raise ExternalToolError(f"{path}: admesh reads STL files only; convert it with "
                                f"'geotex convert {path} OUT.stl'", ADMESH)
    code, text = _run(ADMESH, [], path, timeout)
    try:
        rep = parse_admesh_report(text)
    except ValueError:
        rep = None
    if code != 0 or rep is None:
        raise ExternalToolError(f"{path}: admesh failed (exit {code}): {_last_message(text)}",
                                ADMESH)
    return rep


def _count_reasons(stats: dict, labels: dict) -> list[str]:
    return [f"{stats.get(k, 0)} {label}" for k, label in labels.items() if stats.get(k, 0)]


def _parts_volume_reasons(facets, parts, volume, expected_parts) -> list[str]:
    reasons = []
    if not facets:
        reasons.append("no facets")
    if expected_parts is not None and parts != expected_parts:
        reasons.append(f"{parts} parts, expected {expected_parts}")
    if volume is None or not volume > 0:
        reasons.append(f"volume {volume} is not positive")
    return reasons


def prusaslicer_verdict(info: dict, *, expected_parts: int | None = 1) -> dict:
    """Judge parsed ``prusa-slicer --info`` statistics strictly (see module notes).

    Parameters
    ----------
    info : dict
        From :func:`prusaslicer_info` or :func:`parse_prusaslicer_info`.
    expected_parts : int or None, optional
        Number of separate bodies the file should hold; None accepts any.

    Returns
    -------
    dict
        ``info`` plus ``ok`` (bool), ``reasons`` (list of str, empty when ok)
        and ``notes`` (list of str).
    """
    reasons = [] if info.get("manifold") else ["not manifold"]
    reasons += _count_reasons(info, {
        "open_edges": "open edges", "degenerate_facets": "degenerate facets",
        "edges_fixed": "edges fixed", "facets_removed": "facets removed",
        "facets_reversed": "facets reversed", "backwards_edges": "backwards edges"})
    reasons += _parts_volume_reasons(info.get("number_of_facets"), info.get("number_of_parts"),
                                     info.get("volume"), expected_parts)
    return {**info, "ok": not reasons, "reasons": reasons, "notes": []}


def admesh_verdict(report: dict, *, expected_parts: int | None = 1) -> dict:
    """Judge a parsed admesh report strictly (see module notes).

    Parameters
    ----------
    report : dict
        From :func:`admesh_report` or :func:`parse_admesh_report`.
    expected_parts : int or None, optional
        Number of separate bodies the file should hold; None accepts any.

    Returns
    -------
    dict
        ``report`` plus ``ok`` (bool), ``reasons`` (list of str, empty when
        ok) and ``notes`` (list of str: the normals admesh rewrote).
    """
    reasons = _count_reasons(report, {
        "disconnected_facets": "disconnected facets", "degenerate_facets": "degenerate facets",
        "edges_fixed": "edges fixed", "facets_removed": "facets removed",
        "facets_added": "facets added", "facets_reversed": "facets reversed",
        "backwards_edges": "backwards edges"})
    reasons += _parts_volume_reasons(report.get("facets"), report.get("parts"),
                                     report.get("volume"), expected_parts)
    notes = []
    if report.get("normals_fixed"):
        notes.append(f"{report['normals_fixed']} stored normals differ from the float32 "
                     f"facets' own normals (not a defect)")
    return {**report, "ok": not reasons, "reasons": reasons, "notes": notes}


def _cannot_load(exc: ExternalToolError, path) -> dict:
    msg = str(exc).removeprefix(f"{path}: ")
    return {"ok": False, "reasons": [f"cannot load: {msg}"], "notes": []}


def slicer_verdicts(path, *, expected_parts: int | None = 1,
                    timeout: float = DEFAULT_TIMEOUT) -> dict:
    """Judge a written mesh file with PrusaSlicer and admesh.

    Parameters
    ----------
    path : str or os.PathLike
        The file as written (STL or 3MF; admesh judges STL only).
    expected_parts : int or None, optional
        Number of separate bodies the file should hold; None accepts any.
    timeout : float, optional
        Seconds allowed to each program.

    Returns
    -------
    dict
        ``{"prusaslicer": {...}, "admesh": {...}}``: each with ``ok`` (bool;
        None for admesh on a non-STL file: not judged), ``reasons`` (why not
        ok; a file the program cannot load gets one reason ``"cannot load:
        ..."``), ``notes`` and the parsed statistics.

    Raises
    ------
    ToolNotFoundError
        If a program needed is not installed (the verdict would be incomplete).
    MissingFileError
        If ``path`` is not a file.
    """
    out = {}
    try:
        out["prusaslicer"] = prusaslicer_verdict(prusaslicer_info(path, timeout=timeout),
                                                 expected_parts=expected_parts)
    except ToolNotFoundError:
        raise
    except ExternalToolError as exc:
        out["prusaslicer"] = _cannot_load(exc, path)
    if Path(path).suffix.lower() != ".stl":
        out["admesh"] = {"ok": None, "reasons": [],
                         "notes": ["admesh reads STL only: not judged"]}
        return out
    try:
        out["admesh"] = admesh_verdict(admesh_report(path, timeout=timeout),
                                       expected_parts=expected_parts)
    except ToolNotFoundError:
        raise
    except ExternalToolError as exc:
        out["admesh"] = _cannot_load(exc, path)
    return out
