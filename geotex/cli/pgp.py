"""``geotex pgp MESH (--up|--curvature|--constraints) --scale S -o P.npz``: tile coordinates."""

from __future__ import annotations

import json
import sys
import time

from geotex.cli._common import EXIT_OK, UsageError, flag_error, guard_output
from geotex.cli.field import add_field_source_arguments, field_from_args
from geotex.errors import InputError

HELP = "periodic global parameterization: seamless tile coordinates steered by a cross field"

def register(sub):
    p = sub.add_parser("pgp", help=HELP, description=HELP + ". Builds a 4-direction field "
                       "like 'geotex field' and writes per-corner (s, t) tile coordinates "
                       "(.npz: coords (m,3,2), singular (m,), cone_vertices, cone_indices, "
                       "metadata) that agree across every non-singular edge up to a "
                       "90-degree rotation and an integer translation.")
    p.add_argument("mesh", help="mesh file")
    add_field_source_arguments(p)
    p.add_argument("--scale", required=True, metavar="S",
                   help="tile size in surface units (mesh units, e.g. mm); constraint "
                        "scales, when given, override it")
    p.add_argument("-o", "--output", required=True, help="parameterization file to write (.npz)")
    p.add_argument("--solver", choices=("auto", "direct", "multilevel"), default="auto",
                   help="eigen solve: one factorization of the whole system, or two-level "
                        "(clusters + smoothing); auto: two-level from 20000 vertices on")
    p.add_argument("--seed", type=int, default=0, help="seed of the eigen solvers (default 0)")
    p.add_argument("--update", metavar="OLD.npz", default=None,
                   help="local update: keep OLD.npz (a PGP file of this mesh) everywhere but "
                        "in the effect area around --around, which is re-solved with the new "
                        "field with its border locked (the field outside stays OLD's)")
    p.add_argument("--around", metavar="X,Y,Z", default=None,
                   help="with --update: the point where the constraints changed")
    p.add_argument("--radius", metavar="R", default=None,
                   help="with --update: effect area radius in surface units (distance over "
                        "the surface; default 3 tiles)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)


def _scale(text: str, *, flag: str = "--scale") -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise UsageError(f"{flag} {text!r}: give a positive length in surface units")
    return value


def _previous(args, m: int, n: int):
    """The PGP file to update (``--update``), checked against the mesh; None without it."""
    from geotex.param.pgp_store import load_parameterization

    if args.update is None:
        if args.around is not None or args.radius is not None:
            raise UsageError("--around and --radius go with --update OLD.npz")
        return None
    if args.around is None:
        raise UsageError("--update needs --around X,Y,Z: the point where the constraints "
                         "changed")
    try:
        old = load_parameterization(args.update)
    except InputError as exc:
        raise UsageError(f"--update {exc}") from None
    if old.coords.shape[0] != m or old.functions.shape[0] != n:
        raise UsageError(f"--update {args.update}: made for a mesh of {old.coords.shape[0]} "
                         f"faces, but {args.mesh} has {m}")
    return old


def _updated(args, V, F, old, field, scale, scale_field):
    """Re-solve the effect area around ``--around``; the field outside stays ``old``'s."""
    import numpy as np

    from geotex.cli.field import _vector
    from geotex.param.pgp_update import updated_parameterization
    from geotex.patches.effect import effect_area

    point = np.asarray(_vector(args.around, flag="--around"), dtype=np.float64)
    radius = 3.0 * scale if args.radius is None else _scale(args.radius, flag="--radius")
    seed = int(np.argmin(np.linalg.norm(V[F].mean(axis=1) - point, axis=1)))
    area = effect_area(V, F, [seed], max_distance=radius)
    inside = np.zeros(F.shape[0], dtype=bool)
    inside[area] = True
    vectors = np.where(inside[:, None], field.vectors, old.axes)
    sizes = np.where(np.isin(np.arange(V.shape[0]), F[area]),
                     scale if scale_field is None else scale_field, old.scale)
    return updated_parameterization(V, F, old, vectors, scale=sizes, faces=inside), area.size


def _cli_error(exc: InputError, mesh: str) -> InputError:
    """A library error in the command's terms: the scale by its flag, a mesh by its file."""
    new = flag_error(exc, {"scale": "--scale"})
    if new is exc and str(exc).startswith("F "):       # the mesh arrays' own checks
        new = UsageError(f"{mesh}: the mesh {str(exc)[2:]}")
    return new


def run(args) -> int:
    from geotex.io import read_mesh
    from geotex.mesh.geometry import mean_edge_length
    from geotex.param.pgp import periodic_parameterization
    from geotex.param.pgp_store import save_parameterization

    out = guard_output(args.output, args.mesh)
    if out.suffix.lower() != ".npz":
        raise UsageError(f"{out}: PGP files are .npz; use a .npz file name")
    scale = _scale(args.scale)
    mesh = read_mesh(args.mesh)
    V, F = mesh.vertices, mesh.faces
    if mesh.n_faces == 0:
        raise UsageError(f"{args.mesh}: the mesh has no faces")
    old = _previous(args, F.shape[0], V.shape[0])
    t0 = time.perf_counter()
    area = None
    try:
        field, scale_field, method = field_from_args(args, V, F, 4)
        t1 = time.perf_counter()
        if old is None:
            p = periodic_parameterization(V, F, field, seed=args.seed, solver=args.solver,
                                          scale=scale if scale_field is None else scale_field)
        else:
            p, area = _updated(args, V, F, old, field, scale, scale_field)
    except InputError as exc:
        raise _cli_error(exc, args.mesh) from None
    t2 = time.perf_counter()
    edge = mean_edge_length(V, F)
    if float(p.scale.min()) < edge:
        print(f"geotex: warning: tiles of {p.scale.min():g} are smaller than the mesh's "
              f"triangles (mean edge {edge:.3g}): a texture will alias; give a larger "
              "--scale or refine the mesh", file=sys.stderr)
    cones = [{"vertex": v, "index": k} for v, k in p.cones]
    save_parameterization(out, p, metadata={
        "mesh": str(args.mesh), "method": method,
        "scale": scale if scale_field is None else "constraints", "solver": args.solver,
        "index_sum": p.index_sum, "seam_residual": p.seam_residual})
    summary = {"mesh": str(args.mesh), "output": str(out), "method": method,
               "faces": int(F.shape[0]),
               "scale_range": [float(p.scale.min()), float(p.scale.max())],
               "singularities": cones,
               "dislocations": [{"face": f, "winding": [a, b]} for f, a, b in p.dislocations],
               "singular_faces": int(p.singular.sum()),
               "index_sum": p.index_sum, "seam_residual": p.seam_residual,
               "gradient_error": p.gradient_error, "distortion": p.distortion,
               "timings": {"field_s": round(t1 - t0, 4), "pgp_s": round(t2 - t1, 4)}}
    if area is not None:
        summary["update"] = {"from": str(args.update), "area_faces": area}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{args.mesh}: PGP on {F.shape[0]} faces ({method} field), "
              f"tile size {p.scale.min():g}..{p.scale.max():g}")
        if area is not None:
            print(f"local update of {args.update}: {area} faces re-solved, the rest kept")
        print(f"cones: {len(cones)}, index sum {p.index_sum:g}; dislocations: "
              f"{len(p.dislocations)}; singular faces: {int(p.singular.sum())}")
        print(f"seam residual {p.seam_residual:.3g} tile units, gradient error "
              f"{p.gradient_error:.3g}; field {t1 - t0:.2f} s, pgp {t2 - t1:.2f} s")
        print(f"wrote {out}")
    return EXIT_OK
