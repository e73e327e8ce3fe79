"""The sample's structure for hierarchical pattern mapping: its direction field and size.

:func:`_pattern_field` (the smooth line or cross field a structured sample is
aligned with), :func:`_pattern_size` (the repeat behind the band width and the
minimal patch size), :func:`_period_lattice` (the whole-period moves of a
periodic sample) and :func:`_angle_gap` (angles between directions of a given
symmetry).
"""

from __future__ import annotations

import numpy as np

from geotex.fields.combing import comb_direction_field
from geotex.fields.directions import smooth_direction_field
from geotex.image.fftmatch import quarter_turn_symmetry
from geotex.mesh.geometry import degenerate_faces
from geotex.patches.grow import face_adjacency

#: Quarter-turn symmetry of a sample's autocorrelation from which its field is a cross
#: field (4 directions) instead of a line field.
QUARTER_TURN = 0.8


def _angle_gap(a: float, b: float, sym: int) -> float:
    """Smallest angle between direction ``a`` and the ``sym`` representatives of ``b``."""
    step = 2 * np.pi / sym
    return abs((a - b + 0.5 * step) % step - 0.5 * step)


def _pattern_field(V, F, img, angle):
    """Smooth direction field for a structured sample: (per-face vectors, symmetry).

    The smoothest field of the surface (:func:`geotex.fields.smooth_direction_field`,
    no constraint), with 4-fold symmetry when the sample looks the same turned by a
    quarter turn (:func:`geotex.image.fftmatch.quarter_turn_symmetry` above
    ``QUARTER_TURN``), 2-fold (lines) otherwise; turned by ``angle`` degrees about
    the normals when given (the smoothest field is defined up to such a turn).  The
    vectors are combed (:func:`geotex.fields.comb_direction_field`): a patch without a
    textured neighbour to continue takes the representative nearest them, so that
    separately started regions agree on the pattern's sign except across the
    combing's cut edges.
    """
    sym = 4 if quarter_turn_symmetry(img) >= QUARTER_TURN else 2
    # faces of zero area (simplified meshes have some) carry no direction: the field is
    # solved without them (they weigh nothing in a cluster's direction) and they get a
    # neighbour's vector, or the x axis
    bad = degenerate_faces(V, F)
    keep = np.setdiff1d(np.arange(F.shape[0]), bad)
    fld = smooth_direction_field(V, F[keep], symmetry=sym)
    sub = comb_direction_field(V, F[keep], fld).vectors
    if angle is not None:
        a = np.radians(angle)
        sub = np.cos(a) * sub + np.sin(a) * np.cross(fld.normals, sub)
    vec = np.zeros((F.shape[0], 3))
    vec[keep] = sub
    vec[bad] = (1.0, 0.0, 0.0)
    if bad.size and keep.size:
        FF = face_adjacency(V, F).face_neighbors
        for _ in range(bad.size):            # waves: each bad face from a good neighbour
            nb = FF[bad]
            good = np.isin(nb, keep) & (nb >= 0)
            has = good.any(axis=1)
            if not has.any():
                break
            vec[bad[has]] = vec[nb[has, np.argmax(good[has], axis=1)]]
            keep = np.union1d(keep, bad[has])
            bad = bad[~has]
            if bad.size == 0:
                break
    return np.ascontiguousarray(vec), sym


def _pattern_size(ps, shape) -> float:
    """Pattern size (pixels) behind the band width and the minimal patch size.

    The longest repeat of ``ps`` within a quarter of the image (the repeats
    confirmed at twice their length, see
    :func:`geotex.image.fftmatch.pattern_scale`): a second repeat found
    further (the basket weave's 61 px beside its 34 px) only enters the
    lattice (continuations moved by whole periods, lattice snapping).  With it as the pattern
    size, the wider band and the larger forced clusters made the seams and
    the rotation across borders worse on Spot 10k (basket weave, seed 0:
    where the map jumps 1.52 -> 1.81 times the jump within patches,
    rotation median 7 -> 10 degrees); with the shorter repeat instead
    (bricks 20 px instead of 35) bricks took 14 s CPU on Spot 10k, over the
    10 s budget.
    """
    n = np.linalg.norm(ps.periods, axis=1)
    n_in = n[n <= min(shape[:2]) / 4.0]
    return float(n_in.max() if n_in.size else n.min())


def _period_lattice(periods, width, height):
    """Whole-period moves of a periodic sample, shortest first.

    ``periods`` (1 or 2, 2) the sample's repeats in pixels (one: stripes, moved
    along them by one period as the second vector), ``width`` and ``height``
    the image's size: every move ``k1 p1 + k2 p2`` with ``|k1|, |k2|`` up to
    the image's size over the shorter vector, without the zero move.

    Returns
    -------
    lattice : numpy.ndarray, (k, 2) float64
        The moves (pixels), by increasing length (stable among equal ones).
    basis : numpy.ndarray, (2, 2) float64
        Rows: the two lattice vectors.
    shortest : float
        The shorter vector's length.
    """
    p1 = periods[0]
    q = periods[1] if periods.shape[0] > 1 else \
        np.array([-p1[1], p1[0]])           # stripes: along them, by one period
    K = int(np.ceil(max(width, height) / max(min(np.linalg.norm(p1),
                                                  np.linalg.norm(q)), 1.0)))
    k1, k2 = np.meshgrid(np.arange(-K, K + 1), np.arange(-K, K + 1))
    lattice = k1.reshape(-1, 1) * p1 + k2.reshape(-1, 1) * q
    lattice = lattice[np.argsort(np.hypot(lattice[:, 0], lattice[:, 1]), kind="stable")]
    lattice = lattice[1:]                # without the zero move
    basis = np.array([p1, q], dtype=np.float64)
    return lattice, basis, min(np.linalg.norm(p1), np.linalg.norm(q))
