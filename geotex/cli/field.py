"""``geotex field MESH ... -o FIELD.npz``: a tangent direction field and its singularities."""

from __future__ import annotations

import json
from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "compute a tangent direction field (projected, curvature or smooth) and its singularities"


def register(sub):
    p = sub.add_parser("field", help=HELP, description=HELP + ". Writes an .npz field file "
                       "(see geotex.fields.store) and reports every singular vertex with its "
                       "index; on a closed mesh the indices sum to the Euler characteristic.")
    p.add_argument("mesh", help="mesh file")
    add_field_source_arguments(p)
    p.add_argument("--symmetry", type=int, default=None, choices=(1, 2, 4),
                   help="N-direction symmetry (default 1; 2 for --curvature)")
    p.add_argument("-o", "--output", required=True, help="field file to write (.npz)")
    p.add_argument("--seed", type=int, default=0, help="seed of the eigen solver (default 0)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)


def add_field_source_arguments(p) -> None:
    """Add the field source flags (``--up | --curvature | --constraints``) to a parser."""
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--up", metavar="X,Y,Z",
                     help="project this global direction onto the surface")
    src.add_argument("--curvature", action="store_true",
                     help="principal curvature directions (maximal curvature)")
    src.add_argument("--constraints", metavar="FILE.json",
                     help="smooth field through constraints: a JSON list of "
                          '{"face": i | "point": [x,y,z], "direction": [x,y,z], "weight": w, '
                          '"scale": s}; an empty list gives the globally smoothest field; '
                          "scales are interpolated into a per-vertex scale field")


def field_from_args(args, V, F, N: int):
    """Build the direction field the source flags ask for.

    Returns
    -------
    field : DirectionField
    scale : numpy.ndarray, (n,), or None
        The per-vertex scale field interpolated from constraint scales.
    method : str
        ``"smooth"``, ``"up"`` or ``"curvature"``.
    """
    import numpy as np

    from geotex.fields.directions import (DirectionField, constraint_scale_field,
                                          principal_direction_field, projected_direction_field,
                                          smooth_direction_field)
    from geotex.fields.frames import face_frames, tangent_angles
    from geotex.fields.singularities import singularities

    if args.constraints is not None:
        constraints = _constraints(args.constraints)
        field = smooth_direction_field(V, F, symmetry=N, constraints=constraints, seed=args.seed)
        return field, constraint_scale_field(V, F, constraints), "smooth"
    if args.up is not None:
        method = "up"
        up = _vector(args.up)
        if not any(up):
            raise UsageError(f"--up {args.up!r}: give a non-zero direction, e.g. 0,0,1")
        vectors, _ = projected_direction_field(V, F, up)
    else:
        method = "curvature"
        vectors = principal_direction_field(V, F).directions
    T1, T2, normals = face_frames(V, F)
    theta = tangent_angles(T1, T2, vectors)
    sing = tuple(singularities(V, F, vectors, symmetry=N))
    field = DirectionField(vectors=vectors, symmetry=N, values=np.exp(1j * N * theta),
                           singularities=sing, normals=normals,
                           constrained=np.zeros(0, dtype=np.int64))
    return field, None, method


def _vector(text: str, *, flag: str = "--up") -> list[float]:
    import math

    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise UsageError(f"{flag} {text!r}: give three comma-separated numbers, e.g. 0,0,1")
    return values


def _constraints(path: str) -> list:
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"{p}: no such constraints file")
    try:
        data = json.loads(p.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"{p}: not valid JSON ({exc.__class__.__name__}: {exc})") from None
    if isinstance(data, dict) and "constraints" in data:
        data = data["constraints"]
    if not isinstance(data, list) or not all(isinstance(c, dict) for c in data):
        raise UsageError(f"{p}: expected a JSON list of constraint objects")
    return data


def run(args) -> int:
    import numpy as np

    from geotex.fields.store import save_direction_field
    from geotex.io import read_mesh
    from geotex.mesh.topology import edge_topology

    out = guard_output(args.output, args.mesh)
    if out.suffix.lower() != ".npz":
        raise UsageError(f"{out}: field files are .npz; use a .npz file name")
    mesh = read_mesh(args.mesh)
    V, F = mesh.vertices, mesh.faces
    if mesh.n_faces == 0:
        raise UsageError(f"{args.mesh}: the mesh has no faces")
    N = args.symmetry or (2 if args.curvature else 1)
    if args.curvature and N == 1:
        raise UsageError("--curvature gives lines, not arrows: use --symmetry 2 or 4")
    field, scale, method = field_from_args(args, V, F, N)

    topo = edge_topology(F, mesh.n_vertices)
    chi = int(np.unique(F).size - topo.edges.shape[0] + F.shape[0])
    total = float(sum(k for _, k in field.singularities))
    save_direction_field(out, field, scale=scale,
                         metadata={"mesh": str(args.mesh), "method": method,
                                   "euler_characteristic": chi})
    summary = {"mesh": str(args.mesh), "output": str(out), "method": method, "symmetry": N,
               "faces": int(F.shape[0]),
               "singularities": [{"vertex": int(v), "index": float(k)}
                                 for v, k in field.singularities],
               "index_sum": total, "euler_characteristic": chi,
               "closed": bool(topo.boundary.size == 0),
               "scale_range": None if scale is None else [float(scale.min()), float(scale.max())]}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{args.mesh}: {method} {N}-direction field on {F.shape[0]} faces")
        print(f"singularities: {len(field.singularities)}, index sum {total:g} "
              f"(Euler characteristic {chi})")
        for v, k in field.singularities[:20]:
            print(f"  vertex {v}: index {k:+g}")
        if len(field.singularities) > 20:
            print(f"  ... {len(field.singularities) - 20} more (see --json)")
        print(f"wrote {out}")
    return EXIT_OK
