"""Shell files (``.npz``): arrays plus a JSON metadata string, byte-reproducible.

Written as a deflate-compressed zip of ``.npy`` members with a fixed member
order and fixed timestamps, so the same shell always gives the same bytes.
Base vertices, offset directions and ``P`` (tile units) stay float64; the
quad data is integral (exact), indices are int32.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np

from geotex.errors import InputError, MeshFileError, MissingFileError
from geotex.param.polycube import PolyCube
from geotex.shells.build import Shell

__all__ = ["save_shell", "load_shell", "shell_metadata", "FORMAT"]

FORMAT = "geotex-shell-1"

_ARRAYS = {  # name: (attribute of PolyCube or Shell, dtype)
    "V": ("V", np.float64), "F": ("F", np.int32), "D": ("D", np.float64),
    "labels": ("labels", np.int8), "chart": ("chart", np.int32),
    "chart_label": ("chart_label", np.int8), "planes": ("planes", np.int32),
    "P": ("P", np.float64), "quad_chart": ("quad_chart", np.int32),
    "quad_ij": ("quad_ij", np.int32), "quad_corners": ("quad_corners", np.int32),
    "quad_edge": ("quad_edge", np.int32), "quad_edge_forward": ("quad_edge_forward", np.bool_),
    "edge_axis": ("edge_axis", np.int8), "edge_quads": ("edge_quads", np.int32),
    "edge_sides": ("edge_sides", np.int8),
}
_DATE = (2020, 1, 1, 0, 0, 0)


def shell_metadata(shell: Shell) -> dict:
    """The JSON metadata stored with a shell."""
    from geotex import __version__

    pc = shell.polycube
    return {
        "format": FORMAT, "name": shell.name, "tile_size": pc.tile_size,
        "vertices": int(pc.V.shape[0]), "faces": int(pc.F.shape[0]),
        "charts": int(pc.chart_label.size), "quads": pc.n_quads,
        "edges": int(pc.edge_axis.size), "max_height": shell.max_height,
        "distortion": {k: float(v) for k, v in pc.distortion.items()},
        "attempts": pc.attempts, "source": shell.source, "geotex_version": __version__,
        "recipe": shell.recipe,
    }


def save_shell(path, shell: Shell) -> Path:
    """Write ``shell`` to ``path`` (``.npz``), atomically and reproducibly.

    Raises
    ------
    InputError
        If the path does not end in ``.npz``.
    MeshFileError
        If the file cannot be written.
    """
    from geotex.io.atomic import atomic_output

    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise InputError(f"{path}: shell files are .npz; use a .npz file name")
    pc = shell.polycube
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, (attr, dtype) in _ARRAYS.items():
            src = shell if attr == "D" else pc
            arr = np.ascontiguousarray(np.asarray(getattr(src, attr)).astype(dtype))
            _member(zf, key, arr)
        meta = json.dumps(shell_metadata(shell), sort_keys=True)
        _member(zf, "metadata", np.frombuffer(meta.encode("utf-8"), dtype=np.uint8))
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def _member(zf: zipfile.ZipFile, key: str, arr: np.ndarray) -> None:
    data = io.BytesIO()
    np.lib.format.write_array(data, arr, allow_pickle=False)
    info = zipfile.ZipInfo(f"{key}.npy", date_time=_DATE)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    zf.writestr(info, data.getvalue(), compresslevel=9)


def load_shell(path) -> Shell:
    """Read a shell file written by :func:`save_shell`.

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MeshFileError
        If it is not a geotex shell file, or is truncated or corrupted.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: shell file not found")
    try:
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in list(_ARRAYS) + ["metadata"] if k not in z.files]
            if missing:
                raise MeshFileError(path, "not a geotex shell file (missing "
                                    + ", ".join(missing) + "); build one with 'geotex shell build'")
            arrays = {k: z[k] for k in _ARRAYS}
            meta = json.loads(bytes(z["metadata"]).decode("utf-8"))
    except MeshFileError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, UnicodeDecodeError,
            json.JSONDecodeError) as exc:
        raise MeshFileError(path, f"cannot read the shell file (truncated or corrupted?): "
                            f"{exc}") from None
    if meta.get("format") != FORMAT:
        raise MeshFileError(path, f"unknown shell format {meta.get('format')!r} "
                            f"(expected {FORMAT})")
    a = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
    n, m = a["V"].shape[0], a["F"].shape[0]
    ok = (a["V"].ndim == 2 and a["V"].shape[1] == 3 and a["D"].shape == a["V"].shape
          and a["P"].shape == a["V"].shape and a["F"].ndim == 2 and a["F"].shape[1] == 3
          and m > 0 and a["F"].min() >= 0 and a["F"].max() < n
          and a["labels"].shape == (m,) and a["chart"].shape == (m,)
          and a["quad_corners"].shape == (a["quad_chart"].size, 4, 3)
          and a["quad_edge"].shape == (a["quad_chart"].size, 4)
          and a["chart"].max() < a["chart_label"].size
          and a["quad_edge"].max() < a["edge_axis"].size)
    if not ok:
        raise MeshFileError(path, "inconsistent shell file (array shapes or indices do not "
                            "match); rebuild it with 'geotex shell build'")
    i64 = lambda k: a[k].astype(np.int64)  # noqa: E731
    pc = PolyCube(tile_size=float(meta["tile_size"]), V=a["V"].astype(np.float64),
                  F=i64("F"), labels=i64("labels"), chart=i64("chart"),
                  chart_label=i64("chart_label"), planes=i64("planes"),
                  P=a["P"].astype(np.float64), quad_chart=i64("quad_chart"),
                  quad_ij=i64("quad_ij"), quad_corners=i64("quad_corners"),
                  quad_edge=i64("quad_edge"), quad_edge_forward=a["quad_edge_forward"].astype(bool),
                  edge_axis=i64("edge_axis"), edge_quads=i64("edge_quads"),
                  edge_sides=i64("edge_sides"), distortion=dict(meta.get("distortion", {})),
                  attempts=int(meta.get("attempts", 1)))
    return Shell(name=str(meta.get("name", path.stem)), polycube=pc,
                 D=a["D"].astype(np.float64), max_height=float(meta["max_height"]),
                 source=str(meta.get("source", "")), recipe=dict(meta.get("recipe", {})))
