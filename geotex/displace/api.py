"""``geotex displace`` as Python: a height map on a part, as a printable solid.

:func:`displaced_mesh` works on arrays (millimetres) and returns the judged
solid; :func:`displace_file` reads a part, optionally scales it, and writes
the result only when it is printable as stored (the verified export of
:mod:`geotex.printing`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from geotex.check.report import check_mesh, recheck_moved
from geotex.displace.heightmap import filtered_height_map, load_height_map
from geotex.displace.mappings import mapping_options, projected_heights
from geotex.displace.masks import (PAINT_TOLERANCE, MaskOptions, face_selection, mask_weights,
                                   selected_faces)
from geotex.errors import InputError
from geotex.io import read_mesh
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.record import Mesh
from geotex.options import finite_number, positive_number
from geotex.printing import export_printable, printable_stored_solid, stored_form, stored_precision
from geotex.progress import report
from geotex.relief import DEFAULT_MAX_FACES, displaced_solid, edge_length_for_faces

__all__ = ["displaced_mesh", "displace_file", "stored_judge", "DisplaceResult", "depth_warnings",
           "refuse_broken_part", "DEFAULT_TARGET_FACES", "DISPLACE_STAGES"]

#: Default size of the refined mesh.
DEFAULT_TARGET_FACES = 1_000_000
#: Depth above this fraction of the smallest extent draws a warning.
WARN_DEPTH_FRACTION = 0.10
#: Progress stages of :func:`displace_file`.
DISPLACE_STAGES = ("read", "map", "refine", "normals", "heights", "displace", "decimate",
                   "check", "write")


@dataclass(frozen=True)
class DisplaceResult:
    """The displaced solid as stored, its verdict, and what was done.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
    faces : numpy.ndarray, (m, 3) int64
    report : CheckReport or None
    stats : dict
    warnings : tuple of str
    """

    vertices: np.ndarray
    faces: np.ndarray
    report: object
    stats: dict = field(default_factory=dict)
    warnings: tuple = ()


def depth_warnings(V, depth: float) -> tuple[str, ...]:
    """Warn about a depth that is large for the part; refuse an absurd one.

    Returns
    -------
    tuple of str
        A warning when ``depth`` is above 10 % of the smallest extent.

    Raises
    ------
    InputError
        When ``depth`` is at least the smallest extent or above a quarter of
        the largest (the relief would swallow the part).
    """
    ext = np.ptp(np.asarray(V), axis=0)
    small, large = float(ext.min()), float(ext.max())
    if depth >= small or depth > 0.25 * large:
        raise InputError(f"depth {depth:g} mm is absurd for a part of {ext[0]:.4g} x "
                         f"{ext[1]:.4g} x {ext[2]:.4g} mm; use a depth below "
                         f"{WARN_DEPTH_FRACTION * small:.3g} mm (10 % of the smallest extent)")
    if depth > WARN_DEPTH_FRACTION * small:
        return (f"depth {depth:g} mm is more than 10 % of the part's smallest extent "
                f"({small:.4g} mm): expect reduced relief where it would cross itself",)
    return ()


def stored_judge(precision):
    """The verdict callable of :func:`geotex.relief.displaced_solid` for a file format.

    ``judge(V, F) -> (V_stored, F_stored, CheckReport)``: the solid rounded
    and welded as the file stores it (:func:`geotex.printing.stored_form`),
    checked without manifold3d's second opinion (what it checks, closed,
    manifold and oriented, the topology stage checks too; see
    :func:`geotex.check.report.check_mesh`), with every crossing pair listed
    so the relief can be lowered there without a second search.  Other
    failures go through :func:`geotex.printing.printable_stored_solid` (its
    rebuild of what rounding broke).

    Called again on the same faces after the relief was lowered (only some
    vertices moved), it judges locally: the stored form keeps the previous
    numbering, and :func:`geotex.check.report.recheck_moved` gives exactly
    the report a full check would (new crossings only among the faces at
    moved vertices); where that cannot be done (a weld changes, the box
    changes, several shells...) it judges in full.
    """

    last = []          # (faces, rounded input, stored V, stored F, vertex map, report)

    def judge(Vx, Fx):
        n_in = np.shape(Vx)[0]
        rep = _rejudged(last, Vx, Fx, precision) if last else None
        if rep is not None:
            Vs, Fs = rep[0], last[0][3]
            rep = rep[1]
        else:
            last[:] = []
            Vs, Fs = stored_form(Vx, Fx, precision=precision)
            # only the stored form is judged: the input is released before the check
            # (where the memory peak is), and faces the stored form numbers as they
            # were (vertices already in order of first use, none welded) are shared
            del Vx
            if (isinstance(Fx, np.ndarray) and Fx.dtype == Fs.dtype
                    and Fx.flags.c_contiguous and np.array_equal(Fs, Fx)):
                Fs = Fx
            rep = check_mesh(Vs, Fs, manifold3d=False, max_examples=2 ** 62)
        if rep.printable or all(r.endswith("self-intersecting face pairs")
                                for r in rep.reasons):
            last[:] = [_judged_state(n_in, Fx, Vs, Fs, rep)]
            return Vs, Fs, rep
        last[:] = []
        # the stored form is its own stored form: judging it again as the verified
        # export does gives what the input would give
        s = printable_stored_solid(Vs, Fs, precision=precision, manifold3d=False)
        return s.vertices, s.faces, s.report

    return judge


def _rounded(Vx, precision):
    """Coordinates as :func:`geotex.printing.stored_form` stores them (``-0.0`` as ``0.0``)."""
    p = np.dtype(precision).type
    return (np.asarray(Vx, dtype=np.float64).astype(p) + p(0.0)).astype(np.float64)


def _judged_state(n_in, Fx, Vs, Fs, rep):
    """What :func:`_rejudged` needs of a judged call of ``n_in`` input vertices:
    the map input -> stored vertex (``None`` when the stored form welded two
    input vertices: then there is no shortcut; ``"same"`` when it is the
    identity) and the input's rounded coordinates, taken from the stored ones
    (they are those, with ``-0.0`` as ``0.0``)."""
    R = Vs + 0.0                                  # -0.0 -> 0.0, else equal
    if Fs is Fx and Vs.shape[0] == n_in:
        # every vertex stored as itself: no map, and no copy unless a -0.0 differs
        if not (np.signbit(Vs) & (Vs == 0.0)).any():
            R = Vs
        return (Fx, R, Vs, Fs, "same", rep)
    vmap = np.full(n_in, -1, dtype=np.int64)
    vmap[np.asarray(Fx).ravel()] = Fs.ravel()
    if int((vmap >= 0).sum()) != Vs.shape[0]:
        return (Fx, None, Vs, Fs, None, rep)
    R0 = np.zeros((n_in, 3))                      # unreferenced rows are never compared
    used = vmap >= 0
    R0[used] = R[vmap[used]]
    return (Fx, R0, Vs, Fs, vmap, rep)


def _rejudged(last, Vx, Fx, precision):
    """The judge's answer for ``(Vx, Fx)`` from the previous call's, when only
    vertices moved: ``(V_stored, report)`` or ``None`` (judge in full).

    The stored form keeps the previous numbering when the previous one welded
    no two input vertices and no moved vertex lands on another vertex (which
    :func:`geotex.check.report.recheck_moved` checks: it returns ``None``
    then); the report is the local re-check, equal to a full
    :func:`geotex.check.report.check_mesh` of the stored arrays.
    """
    F0, R0, Vs0, Fs, vmap, rep0 = last[0]
    if vmap is None or Fx is not F0 or np.asarray(Vx).shape[0] != R0.shape[0]:
        return None
    R = _rounded(Vx, precision)
    diff = R.view(np.uint64) != R0.view(np.uint64)
    moved = np.flatnonzero(diff[:, 0] | diff[:, 1] | diff[:, 2])
    del diff
    Vs = Vs0.copy()
    if isinstance(vmap, str):                     # "same": stored vertex i is input vertex i
        Vs[moved] = R[moved]
    else:
        moved = moved[vmap[moved] >= 0]
        Vs[vmap[moved]] = R[moved]
    del R
    rep = recheck_moved(Vs0, Vs, Fs, rep0, max_examples=2 ** 62)
    return None if rep is None else (Vs, rep)


def displaced_mesh(V, F, image, *, depth: float, mapping: str = "triplanar", scale_u=None,
                   scale_v=None, offset_u: float = 0.0, offset_v: float = 0.0,
                   rotation: float = 0.0, sharpness: float = 4.0, blend: float = 0.15,
                   axis: str = "z", cap_angle: float = 20.0, symmetric: bool = False,
                   blur: float = 0.0, invert: bool = False, masks: MaskOptions | None = None,
                   edge_length: float | None = None,
                   target_faces: int = DEFAULT_TARGET_FACES,
                   max_faces: int = DEFAULT_MAX_FACES, decimate_to: int | None = None,
                   uv=None, field=None, seed: int = 0, precision=np.float32,
                   judge: bool = True, check_base: bool = True,
                   progress=None) -> DisplaceResult:
    """Displace a part (millimetres) by a height map under a mapping.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A closed, manifold, consistently oriented part without
        self-intersections, in millimetres (refused at once otherwise; see
        ``check_base``).
    image : str, os.PathLike or array_like
        A library name (:func:`geotex.displace.library.library_names`), an
        image file or an array (see :func:`~geotex.displace.heightmap.load_height_map`).
    depth : float
        Relief depth in mm (white = ``depth`` outward; with ``symmetric``,
        ``depth / 2`` either side, 50 % grey neutral).
    mapping : str, optional
        One of :data:`geotex.displace.mappings.MAPPINGS`.
    scale_u, scale_v, offset_u, offset_v, rotation, sharpness, blend, axis, cap_angle
        See :class:`geotex.displace.mappings.MappingOptions`.
    symmetric : bool, optional
    blur : float, optional
        Gaussian blur of the image, mm on the surface (pixels for ``uv``).
    invert : bool, optional
        Dark high.
    masks : MaskOptions, optional
        Default: the bed faces (within 5 degrees of -z) stay flat.
    edge_length : float, optional
        Longest refined edge, mm; default from ``target_faces``.
    target_faces : int, optional
        Approximate refined face count (default 1,000,000).
    max_faces : int, optional
        Safety cap.
    decimate_to : int, optional
        QEM-decimate the result to this many faces.
    uv : numpy.ndarray, (m, 3, 2), optional
        Per-corner texture coordinates (``uv`` mapping).
    field : str or sequence, optional
        ``pgp``: the cross field, a direction the image's "up" follows
        (default ``(0, 0, 1)``: horizontal courses on upright walls),
        ``"smooth"`` or ``"curvature"``; ``lapped``: the "up" direction
        (default ``(0, 0, 1)``).
    seed : int, optional
    precision : type, optional
        Coordinates as the output file stores them (float32 for STL).
    judge : bool, optional
        Judge the result as stored (and lower the relief where it crosses
        itself); ``False`` skips the check (the result is then not verified).
    check_base : bool, optional
        Refuse a broken part before any work (:func:`refuse_broken_part`);
        ``False`` when the caller has checked it already (as
        :func:`displace_file` does on the file as read).
    progress : callable, optional

    Returns
    -------
    DisplaceResult

    Raises
    ------
    InputError
        A part that is not a closed solid (``check_base``), coordinates
        beyond a quarter of ``precision``'s range or 1e15 mm, bad options, an
        absurd depth, a mapping that cannot be made, or a result above
        ``max_faces``.
    """
    V, F = as_mesh_arrays(V, F)
    if F.shape[0] == 0:
        raise InputError("the part has no faces")
    d = positive_number(depth, name="depth")
    # coordinates the output cannot store, or the mappings cannot turn into tile
    # indices, are refused before any work (were NumPy cast warnings, then a refusal
    # of the finished relief)
    reach = float(np.abs(V).max())
    limit = min(float(np.finfo(precision).max) / 4, 1e15)
    if not reach + d <= limit:
        raise InputError(f"coordinates reach {reach:.3g} mm, beyond the {limit:.3g} mm that "
                         f"{np.dtype(precision).name} output and the mappings handle; scale "
                         "the part down")
    if check_base:
        refuse_broken_part(V, F)
    warns = list(depth_warnings(V, d))
    opt = mapping_options(mapping, scale_u=scale_u, scale_v=scale_v, offset_u=offset_u,
                          offset_v=offset_v, rotation=rotation, sharpness=sharpness,
                          blend=blend, axis=axis, cap_angle=cap_angle)
    b = finite_number(blur, name="blur")
    if b < 0:
        raise InputError(f"blur must be >= 0, got {blur!r}")
    H0 = load_height_map(image)
    if edge_length is None:
        edge_length = edge_length_for_faces(V, F, target_faces)
    L = positive_number(edge_length, name="edge_length")
    sec = {}
    t = time.perf_counter()
    report(progress, "map")
    # low-pass the image to the vertex spacing (sampling finer detail aliases)
    if mapping == "uv":
        sigma = b
    else:
        px = opt.scale_u / H0.shape[1]
        aa = 0.5 * L / px if L > px else 0.0
        sigma = math.hypot(b / px, aa)
    H = filtered_height_map(H0, sigma_pixels=sigma, invert=invert)
    if mapping == "uv":
        if uv is None:
            raise InputError("the uv mapping needs texture coordinates: the part file has "
                             "none (use an OBJ with vt or a GLB with TEXCOORD_0)")
        uvc = np.asarray(uv, dtype=np.float64)
        if uvc.shape != (F.shape[0], 3, 2):
            raise InputError(f"uv must be per-corner coordinates of shape ({F.shape[0]}, 3, 2)")
        sampler = lambda p: projected_heights(p, H, opt, uv=uvc)  # noqa: E731
    elif mapping == "pgp":
        # lazy: the PGP and lapped paths pull in the field, patch and image machinery
        from geotex.displace.seamless import pgp_corner_coordinates, pgp_heights

        field = (0.0, 0.0, 1.0) if field is None else field
        coords = pgp_corner_coordinates(V, F, tile=opt.scale_u, field=field, seed=seed)
        off = (opt.offset_u / opt.scale_u, opt.offset_v / opt.scale_u)
        # a direction field is the image's "up": the parameterization's s axis runs
        # along it, so the image is turned by -90 degrees (u = -t, v = s)
        turn = 0.0 if isinstance(field, str) else -90.0
        sampler = lambda p: pgp_heights(p, H, coords, offset=off,  # noqa: E731
                                        rotation=opt.rotation + turn)
    elif mapping == "lapped":
        if isinstance(field, str):
            raise InputError(f"field {field!r}: the lapped mapping needs a direction X,Y,Z "
                             "for the image's up")
        from geotex.displace.seamless import lapped_height_texture, lapped_heights  # lazy: see pgp

        up = (0.0, 0.0, 1.0) if field is None else field
        lt = lapped_height_texture(V, F, H, tile=opt.scale_u, up=up, seed=seed)
        sampler = lambda p: lapped_heights(p, lt)  # noqa: E731
    else:
        sampler = lambda p: projected_heights(p, H, opt)  # noqa: E731
    sec["map"] = time.perf_counter() - t
    masks = MaskOptions() if masks is None else masks
    faces_on = selected_faces(V, F, masks)
    if not faces_on.any():
        raise InputError("the mask leaves no face to texture; loosen the mask options")
    weights = lambda p: mask_weights(p, faces_on, width=masks.width,  # noqa: E731
                                     curve=masks.curve)
    judge_fn = stored_judge(precision) if judge else None
    res = displaced_solid(V, F, sampler, depth=d, edge_length=L, symmetric=symmetric,
                          precision=precision,
                          weights=weights, max_faces=max_faces, decimate_to=decimate_to,
                          judge=judge_fn, progress=progress)
    stats = dict(res.stats)
    stats["seconds"] = dict(sec, **stats["seconds"])
    stats["mapping"] = mapping
    stats["depth_mm"] = d
    stats["tile_mm"] = [opt.scale_u, opt.scale_v]
    if res.stats.get("relief_reduced_rounds"):
        warns.append(f"relief lowered locally in {res.stats['relief_reduced_rounds']} "
                     "round(s) where the surface would have crossed itself")
    return DisplaceResult(res.vertices, res.faces, res.report, stats, tuple(warns))


def _read_part(path, *, step_quality: str = "standard"):
    from pathlib import Path

    if isinstance(path, Mesh):                       # a mesh a command already holds
        mesh = path
        uv = None
        if mesh.uv is not None:
            uv = np.asarray(mesh.uv, dtype=np.float64)[np.asarray(mesh.uv_faces)]
        return mesh.vertices, mesh.faces, uv
    p = Path(path)
    if p.suffix.lower() in (".step", ".stp"):
        # lazy: STEP input pulls in gmsh and the repair steps (pymeshlab)
        from geotex.displace.step import read_step

        V, F = read_step(p, quality=step_quality)
        return V, F, None
    mesh = read_mesh(p)
    uv = None
    if mesh.uv is not None:
        uv = np.asarray(mesh.uv, dtype=np.float64)[np.asarray(mesh.uv_faces)]
    return mesh.vertices, mesh.faces, uv


def refuse_broken_part(V, F, *, name: str = "the part") -> None:
    """Refuse a part that is not a closed, manifold, oriented solid free of self-intersections.

    Run on the part before any refinement, so that a broken part is refused at
    once (a relief built on it would only be judged not printable after all
    the work).  Degenerate faces and several bodies are accepted: the relief
    copes with both.  One :func:`geotex.check.report.check_mesh` of the base
    (topology and self-intersections; manifold3d's opinion is not asked, its
    closed / manifold / oriented verdict is the topology stage's).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    name : str, optional
        How the message names the part (a file name).

    Raises
    ------
    InputError
        Naming every problem found, and ``geotex repair`` as the way out.
    """
    r = check_mesh(V, F, manifold3d=False, max_examples=1)
    problems = []
    if r.boundary_edges:
        problems.append(f"open ({r.boundary_edges} boundary edges)")
    if r.non_manifold_edges:
        problems.append(f"non-manifold ({r.non_manifold_edges} edges)")
    if not r.orientation_consistent:
        problems.append(f"inconsistently oriented ({r.inconsistent_edges} edges)")
    if r.self_intersecting_pairs:
        problems.append(f"{r.self_intersecting_pairs} self-intersecting face pairs")
    if problems:
        raise InputError(f"{name}: not a closed solid to displace: " + ", ".join(problems)
                         + "; run 'geotex repair' on it first")


def displace_file(base, image, output, *, depth: float, size_mm: float | None = None,
                  step_quality: str = "standard", mask_file=None, mask_color=None,
                  mask_tolerance: float = PAINT_TOLERANCE, force: bool = False, progress=None,
                  **options) -> DisplaceResult:
    """Read a part, displace it by a height map, and write it only if printable.

    Parameters
    ----------
    base : str, os.PathLike or geotex.mesh.record.Mesh
        STL/OBJ/PLY/OFF/3MF/GLB (or STEP/STP through gmsh, when installed), or a
        mesh already read.
    image : str, os.PathLike or array_like
        Library name, image file or array.
    output : str or os.PathLike
        ``.stl`` or ``.3mf`` (``.obj``/``.ply``/``.off`` accepted).
    depth : float
        Millimetres.
    size_mm : float, optional
        Scale the part so its largest extent is this many millimetres.
    step_quality : str, optional
        STEP tessellation preset (``coarse``, ``standard``, ``fine``).
    mask_file : str or os.PathLike, optional
        A face selection: JSON face indices, or a painted copy of the base
        (PLY with per-face or per-vertex colours, OBJ with vertex colours),
        matched to the base as read (before ``size_mm``); see
        :func:`geotex.displace.masks.face_selection`.  It replaces the
        ``faces`` of ``options["masks"]``.
    mask_color : sequence of 3 floats, optional
        The paint colour (0..255); default: any colour but the most common.
    mask_tolerance : float, optional
        Per-channel colour tolerance (0..255).
    force : bool, optional
        Write even when not printable.
    progress : callable, optional
        Called with each of ``DISPLACE_STAGES``.
    **options
        Passed to :func:`displaced_mesh`.

    Returns
    -------
    DisplaceResult

    Raises
    ------
    InputError
        Unreadable files, a part that is not a closed solid (refused before
        any relief work), a bad selection file, bad options.
    NotPrintableError
        The result is not printable as stored (nothing written) and not ``force``.
    """
    from pathlib import Path

    t = time.perf_counter()
    report(progress, "read")
    V, F, uv = _read_part(base, step_quality=step_quality)
    name = (base.name or "part") if isinstance(base, Mesh) else str(base)
    if F.shape[0] == 0:
        raise InputError(f"{name}: the mesh has no faces")
    refuse_broken_part(V, F, name=name)
    if mask_file is not None:
        sel = face_selection(mask_file, V, F, color=mask_color, tolerance=mask_tolerance)
        masks = options.get("masks") or MaskOptions()
        options["masks"] = replace(masks, faces=np.flatnonzero(sel))
    elif mask_color is not None:
        raise InputError("mask color needs a painted face-selection file")
    if size_mm is not None:
        s = positive_number(size_mm, name="size_mm") / float(np.ptp(V, axis=0).max())
        V = V * s
    read_s = time.perf_counter() - t
    if options.get("mapping") == "uv" and "uv" not in options:
        options["uv"] = uv
    res = displaced_mesh(V, F, image, depth=depth, progress=progress, check_base=False,
                         precision=stored_precision(Path(output).suffix), **options)
    t = time.perf_counter()
    report(progress, "write")
    rep = export_printable(output, res.vertices, res.faces, report=res.report, force=force,
                           name=base.name if isinstance(base, Mesh) else Path(base).stem)
    stats = dict(res.stats)
    stats["seconds"] = dict(stats["seconds"], read=round(read_s, 3),
                            write=round(time.perf_counter() - t, 3))
    if mask_file is not None:
        stats["mask_file_faces"] = int(options["masks"].faces.size)
    return DisplaceResult(res.vertices, res.faces, rep, stats, res.warnings)
