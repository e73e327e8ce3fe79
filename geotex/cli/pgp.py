"""``geotex pgp MESH (--up|--curvature|--constraints) --scale S -o P.npz``: tile coordinates."""

from __future__ import annotations

import json
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
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)


def _scale(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise UsageError(f"--scale {text!r}: give a positive tile size in surface units")
    return value


def run(args) -> int:
    from geotex.io import read_mesh
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
    t0 = time.perf_counter()
    field, scale_field, method = field_from_args(args, V, F, 4)
    t1 = time.perf_counter()
    try:
        p = periodic_parameterization(V, F, field, seed=args.seed, solver=args.solver,
                                      scale=scale if scale_field is None else scale_field)
    except InputError as exc:            # rephrased when it is about the scale
        raise flag_error(exc, {"scale": "--scale"}) from None
    t2 = time.perf_counter()
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
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{args.mesh}: PGP on {F.shape[0]} faces ({method} field), "
              f"tile size {p.scale.min():g}..{p.scale.max():g}")
        print(f"cones: {len(cones)}, index sum {p.index_sum:g}; dislocations: "
              f"{len(p.dislocations)}; singular faces: {int(p.singular.sum())}")
        print(f"seam residual {p.seam_residual:.3g} tile units, gradient error "
              f"{p.gradient_error:.3g}; field {t1 - t0:.2f} s, pgp {t2 - t1:.2f} s")
        print(f"wrote {out}")
    return EXIT_OK
