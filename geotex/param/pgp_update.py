"""Local update of a periodic global parameterization (material-space textures §2.1).

When the orientation or scale constraints change in one place, only the
*effect area* of the change needs a new solve (:func:`geotex.patches.effect.effect_area`
grows it); everywhere else the periodic functions stay as they were.  The
update:

1. combs the new field over the whole mesh and finds the corner rotations
   (cheap, and needed for the frames);
2. carries the previous functions of every vertex outside the area into the
   new vertex frames: outside the area the field is unchanged, so a vertex's
   new axis is its old axis turned by a multiple of 90 degrees (the combing
   may choose another arm), and the 4-vector is turned with it;
3. solves the PGP energy for the vertices inside the area with those
   functions locked (``A_ff X_f = -A_fb X_b``, one sparse positive definite
   factorization of the area's block only, energy assembled over the area's
   faces only);
4. extracts the corner coordinates over the whole mesh as
   :func:`~geotex.param.pgp.periodic_parameterization` does.

Outside the area the result is the previous one (the same coordinates, up to
the grid symmetry the new combing picks); inside, it is the minimiser of the
same energy for the new field with the area's border locked, which is the
paper's local update (it keeps the border instead of re-solving the
eigenproblem everywhere).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.errors import InputError
from geotex.linalg import factor
from geotex.param.pgp import (_P, PeriodicParameterization, _energy, _extracted, _setup,
                              _transfers)

__all__ = ["updated_parameterization"]


def _quarter_turns(old_axes: np.ndarray, new_axes: np.ndarray, normals: np.ndarray
                   ) -> np.ndarray:
    """Multiples of 90 degrees from ``old_axes`` to ``new_axes`` about ``normals``, (k,)."""
    cross = np.einsum("ij,ij->i", normals, np.cross(old_axes, new_axes))
    angle = np.arctan2(cross, np.einsum("ij,ij->i", old_axes, new_axes))
    return np.mod(np.rint(angle / (0.5 * np.pi)).astype(np.int64), 4)


def _locked_solve(Aff: sp.csr_matrix, rhs: np.ndarray) -> np.ndarray:
    """Solve ``Aff x = rhs`` block by block: the ``u`` and ``v`` halves couple only
    through odd corner rotations, so the system falls apart into a few blocks."""
    coo = Aff.tocoo()
    halves = Aff.shape[0] // 2
    H = sp.csr_matrix((np.ones(coo.row.size, np.int8), (coo.row // 2, coo.col // 2)),
                      shape=(halves, halves))
    count, label = connected_components(H, directed=False)
    x = np.zeros(Aff.shape[0])
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(count + 1))
    for c in range(count):
        h = order[starts[c]:starts[c + 1]]
        idx = np.stack([2 * h, 2 * h + 1], axis=1).ravel()
        b = rhs[idx]
        if not np.any(b):
            raise InputError("the effect area touches no vertex outside it; give faces that "
                             "leave part of the mesh locked")
        x[idx] = factor(Aff[idx][:, idx].tocsc(), hpd=True,
                        what="updated_parameterization").solve(b)
    return x


def updated_parameterization(V, F, previous, field, *, scale,
                             faces) -> PeriodicParameterization:
    """Re-solve a periodic global parameterization inside an effect area only.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        The mesh ``previous`` was computed on.
    previous : PeriodicParameterization or geotex.param.pgp_store.PgpFile
        The parameterization before the change (its ``functions`` and
        ``axes`` are used).
    field : DirectionField or array_like, (m, 3)
        The new orientation; it must equal the previous one outside ``faces``
        (up to the cross field's quarter turns).
    scale : float or array_like, (n,)
        The new tile size (surface units); must equal the previous one at
        the vertices outside ``faces``.
    faces : array_like of int, or (m,) bool
        The effect area: the faces where the field or the scale changed and
        around them (e.g. :func:`geotex.patches.effect.effect_area` of the
        changed constraints' faces).  Vertices all of whose faces lie in it
        are re-solved; every other vertex keeps its function.

    Returns
    -------
    PeriodicParameterization

    Raises
    ------
    InputError
        Malformed arrays, ``previous`` made for another mesh, an empty area,
        or an area that touches no locked vertex in some part (nothing would
        hold its solution).
    SolverError
        If the area's system cannot be factored.

    Examples
    --------
    >>> from geotex.mesh.primitives import grid_plane
    >>> from geotex.param.pgp import periodic_parameterization
    >>> V, F = grid_plane(6, 6)
    >>> p = periodic_parameterization(V, F, np.tile([1.0, 0, 0], (len(F), 1)), scale=0.5)
    >>> q = updated_parameterization(V, F, p, np.tile([1.0, 0, 0], (len(F), 1)), scale=0.5,
    ...                              faces=np.arange(10, 30))
    >>> bool(np.allclose(q.coords, p.coords))
    True
    """
    st = _setup(V, F, field, scale)
    n, m = st.V.shape[0], st.F.shape[0]
    if previous.functions.shape != (n, 4) or previous.axes.shape != (m, 3):
        raise InputError(f"previous was computed on another mesh ({previous.functions.shape[0]} "
                         f"vertices, {previous.axes.shape[0]} faces; this one has {n}, {m})")
    area = np.zeros(m, dtype=bool)
    sel = np.asarray(faces)
    if sel.dtype == bool:
        if sel.shape != (m,):
            raise InputError(f"faces as a mask must have shape ({m},), got {sel.shape}")
        area = sel.copy()
    else:
        sel = sel.ravel()
        if sel.size and (sel.dtype.kind not in "iu" or sel.min() < 0 or sel.max() >= m):
            raise InputError(f"faces must be face ids in [0, {m}) or an ({m},) boolean mask")
        area[sel.astype(np.int64)] = True
    if not area.any():
        raise InputError("faces is empty: there is nothing to update")
    F = st.F
    # free vertices: every incident face in the area
    outside = np.zeros(n, dtype=bool)
    outside[F[~area].ravel()] = True
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    free = used & ~outside
    # previous functions in the new vertex frames (the arm of the first corner's face)
    _, first_corner = np.unique(F.ravel(), return_index=True)
    ref_face = np.zeros(n, dtype=np.int64)
    ref_face[np.unique(F.ravel())] = first_corner // 3
    turns = _quarter_turns(previous.axes[ref_face], st.arms[ref_face, 0], st.conn.N[ref_face])
    X = np.einsum("vab,vb->va", _P[(4 - turns) % 4], previous.functions)
    fi = np.flatnonzero(free)
    if fi.size:
        # the energy of the faces around free vertices: all of them lie in the area
        near = area & free[F].any(axis=1)
        sub = np.flatnonzero(near)
        I, J, T = _transfers(st.V, F[sub], st.k[sub], st.arms[sub], st.S_face[sub])
        A = _energy(I, J, T, st.weight[sub], n)
        idx = (4 * fi[:, None] + np.arange(4)).ravel()
        fixed = np.ones(4 * n, dtype=bool)
        fixed[idx] = False
        A = A.tocsr()[idx]
        Aff = A[:, idx]
        rhs = -(A[:, fixed] @ X.ravel()[fixed])
        X[fi] = _locked_solve(Aff, rhs).reshape(-1, 4)
    lams = tuple(previous.eigenvalues)
    return _extracted(st, X, lams)
