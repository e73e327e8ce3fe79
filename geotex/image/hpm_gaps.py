"""Face level of hierarchical pattern mapping: face groups and the last gaps.

:func:`_face_groups` cuts the faces left after the cluster levels into small
connected groups for the face-level fits; :func:`_fill_gaps` textures what is
still left by unfolding each face from a textured neighbour.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components


def _face_groups(FF: np.ndarray, todo: np.ndarray, size: int) -> list:
    """The faces ``todo`` (m,) bool cut into groups of at most ``size`` adjacent faces.

    Connected components of the remaining faces (across shared edges), each
    cut into consecutive runs of its breadth-first order (a run is connected
    or nearly so; the projection flattening does not need more).
    """
    idx = np.flatnonzero(todo)
    if idx.size == 0:
        return []
    slot = np.full(FF.shape[0], -1, np.int64)
    slot[idx] = np.arange(idx.size)
    nb = FF[idx]
    a = np.repeat(np.arange(idx.size), 3)
    b = np.where(nb >= 0, slot[np.maximum(nb, 0)], -1).ravel()
    keep = b >= 0
    G = sp.csr_matrix((np.ones(int(keep.sum())), (a[keep], b[keep])), shape=(idx.size,) * 2)
    ncomp, lab = connected_components(G, directed=False)
    first = np.full(ncomp, -1, np.int64)
    first[lab[::-1]] = np.arange(idx.size)[::-1]
    out = []
    for k in range(ncomp):
        order = breadth_first_order(G, int(first[k]), directed=False,
                                    return_predecessors=False)
        out.extend(idx[order[j:j + size]] for j in range(0, order.size, size))
    return out


def _fill_gaps(V, F, FF, st) -> int:
    """Texture the remaining faces by unfolding them from a textured neighbour."""
    filled = 0
    while not st.done.all():
        todo = np.flatnonzero(~st.done)
        nb = FF[todo]
        ok = (nb >= 0) & st.done[np.maximum(nb, 0)]
        has = ok.any(axis=1)
        if not has.any():
            # a part with no texture at all: give it a flat projection at the origin
            f0 = todo[0]
            st.corner[f0] = 0.0
            st.done[f0] = True
            filled += 1
            continue
        fa = todo[has]
        k = np.argmax(ok[has], axis=1)
        g = nb[has, k]
        a = F[fa, k]
        b = F[fa, (k + 1) % 3]
        c = F[fa, (k + 2) % 3]
        # g's corner positions for a and b
        ga = np.argmax(F[g] == a[:, None], axis=1)
        gb = np.argmax(F[g] == b[:, None], axis=1)
        gc = 3 - ga - gb
        ua, ub, ug = st.corner[g, ga], st.corner[g, gb], st.corner[g, gc]
        pa, pb = V[a], V[b]
        ev = pb - pa
        le = np.linalg.norm(ev, axis=1)
        ex = ev / np.maximum(le, 1e-300)[:, None]
        # coordinates of c and of g's third vertex in the edge frame (s along, t across)
        def st_coords(p):
            d = p - pa
            s = np.sum(d * ex, axis=1)
            t = np.linalg.norm(d - s[:, None] * ex, axis=1)
            return s, t
        sc, tc = st_coords(V[c])
        # texture-space frame from g: along the edge, and toward g's third vertex
        du = ub - ua
        lu = np.linalg.norm(du, axis=1)
        ux = du / np.maximum(lu, 1e-300)[:, None]
        uy = np.stack([-ux[:, 1], ux[:, 0]], 1)
        side = np.sign(np.sum((ug - ua) * uy, axis=1))
        side[side == 0] = 1.0
        k_scale = lu / np.maximum(le, 1e-300)
        uc = ua + (sc * k_scale)[:, None] * ux - (side * tc * k_scale)[:, None] * uy
        st.corner[fa, k] = ua
        st.corner[fa, (k + 1) % 3] = ub
        st.corner[fa, (k + 2) % 3] = uc
        st.done[fa] = True
        filled += fa.size
    return filled
