"""Vectorised geometry of lines and (helical) circular arcs.

An arc is given by its start and end points, its centre (in the plane through
the start point), the unit normal of its plane, its direction (counter-clockwise
= positive rotation about the normal) and its sweep angle. A helical arc has an
end point off that plane; the offset is spread linearly over the sweep.

All functions take arrays over moves and return arrays; lengths in mm,
angles in rad.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.model.tolerances import TOL

TWO_PI = 2.0 * np.pi


def as_points(x: ArrayLike, name: str) -> NDArray[np.float64]:
    """Convert to an (n, 3) float64 array or raise with the shape in the message."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {a.shape}")
    return a


def norm(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row norms of an (n, 3) array."""
    return np.sqrt(np.einsum("ij,ij->i", v, v))


def unit(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-normalised copy; zero rows stay zero (and NaN rows NaN)."""
    n = norm(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = v / np.where(n > 0, n, 1.0)[:, None]
    return out


def dot(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise dot product of two (n, 3) arrays."""
    return np.einsum("ij,ij->i", a, b)


def cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise cross product of (n, 3) float64 arrays: ``np.cross(a, b)`` bit for bit (its
    products and differences in its order), without the copies of both inputs it makes
    (1M rows: 60 ms, not 90-150)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    tmp = np.empty(out.shape[:-1])
    for c, (p, q, r, s) in enumerate(((a1, b2, a2, b1), (a2, b0, a0, b2), (a0, b1, a1, b0))):
        oc = out[..., c]
        np.multiply(p, q, out=oc)
        np.multiply(r, s, out=tmp)
        oc -= tmp
    return out


def angle_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle (rad, [0, pi]) between row vectors, accurate for tiny angles.

    ``atan2(|a x b|, a.b)`` keeps full precision near 0 and pi, where
    ``arccos`` of the dot product loses half the digits.
    """
    return np.arctan2(norm(cross(a, b)), dot(a, b))


def max_share(a: ArrayLike, b: ArrayLike, sweep: ArrayLike) -> NDArray[np.float64]:
    """max over phi in [0, sweep] of |a cos(phi) + b sin(phi)|, elementwise.

    The function is sqrt(a^2 + b^2) cos(phi - phi0) with phi0 = atan2(b, a); its absolute
    value peaks where phi = phi0 (mod pi). If such an angle lies in the sweep the peak is
    the answer, else the larger of the two ends. This is an axis's largest share of a
    direction that turns by ``sweep`` in a plane (a, b: the axis's components of the
    direction at phi = 0 and of its in-plane perpendicular).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    sweep = np.asarray(sweep, dtype=np.float64)
    if not np.broadcast_shapes(a.shape, b.shape, sweep.shape):  # scalars: as one-element rows
        return max_share(a.reshape(1), b.reshape(1), sweep.reshape(1)).reshape(())
    # phi0 mod pi: atan2 is in [-pi, pi], where np.mod(phi, pi) is phi + pi below 0 (fmod
    # leaves phi as it is; one rounded addition), 0 at pi and phi elsewhere -- its values,
    # several times faster
    phi = np.arctan2(b, a)
    below = phi < 0
    phi[phi == np.pi] = 0.0
    np.add(phi, np.pi, out=phi, where=below)
    inside = phi <= sweep
    del phi, below
    # max(|a|, |a cos(sweep) + b sin(sweep)|), its temporaries written over
    out = a * np.cos(sweep)
    turned = b * np.sin(sweep)
    if turned.shape == out.shape:
        out += turned
    else:
        out = out + turned
    del turned
    np.abs(out, out=out)
    np.maximum(np.abs(a), out, out=out)
    # the peak sqrt(a^2 + b^2) only where it is the answer
    if a.shape == b.shape == out.shape and a.flags.c_contiguous and b.flags.c_contiguous:
        # (the same elements by their flat indices: 2-D indices cost several times more)
        k = np.flatnonzero(inside)
        if k.size:
            out.reshape(-1)[k] = np.hypot(a.reshape(-1)[k], b.reshape(-1)[k])
        return out
    k2 = np.nonzero(inside)
    if k2[0].size:
        a, b = np.broadcast_arrays(a, b, sweep)[:2]
        out[k2] = np.hypot(a[k2], b[k2])
    return out


def radial(
    points: NDArray[np.float64], center: NDArray[np.float64], normal: NDArray[np.float64]
) -> NDArray[np.float64]:
    """In-plane vector from the centre to each point (normal component removed)."""
    r = points - center
    return r - dot(r, normal)[:, None] * normal


def arc_sweep(
    start: ArrayLike,
    end: ArrayLike,
    center: ArrayLike,
    normal: ArrayLike,
    ccw: ArrayLike,
    turns: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Unsigned sweep angle of arcs, in (0, 2 pi (turns + 1)].

    Parameters
    ----------
    start, end, center : (n, 3) float, mm
    normal : (n, 3) float
        Unit plane normals; counter-clockwise is positive rotation about them.
    ccw : (n,) bool
        True for counter-clockwise (G3), False for clockwise (G2).
    turns : (n,) int, optional
        Extra full turns (LinuxCNC's ``P`` word minus one).

    Returns
    -------
    (n,) float, rad
        A start and end that coincide in the plane give a full circle (2 pi).
    """
    s = as_points(start, "start")
    e = as_points(end, "end")
    c = as_points(center, "center")
    nrm = as_points(normal, "normal")
    ccw = np.asarray(ccw, dtype=bool)
    r0 = radial(s, c, nrm)
    r1 = radial(e, c, nrm)
    a = np.arctan2(dot(nrm, np.cross(r0, r1)), dot(r0, r1))  # signed, (-pi, pi]
    a = np.where(ccw, a, -a)
    theta = np.mod(a, TWO_PI)
    closed = norm(r1 - r0) <= TOL.zero_length
    theta = np.where(closed, TWO_PI, theta)
    if turns is not None:
        theta = theta + TWO_PI * np.asarray(turns, dtype=np.float64)
    return theta


def arc_pitch(
    start: NDArray[np.float64],
    end: NDArray[np.float64],
    normal: NDArray[np.float64],
    sweep: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Helix rise per radian along the normal (mm/rad); 0 for planar arcs (NaN where the
    sweep is 0: no arc)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return dot(end - start, normal) / sweep


def arc_length(
    radius: NDArray[np.float64], sweep: NDArray[np.float64], pitch: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Length of helical arcs: sweep * sqrt(r^2 + c^2) with c the pitch per radian."""
    return sweep * np.hypot(radius, pitch)


def arc_tangent(
    rvec: NDArray[np.float64],
    normal: NDArray[np.float64],
    ccw: NDArray[np.bool_],
    pitch: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Unit tangent of helical arcs at the point with in-plane radius vector ``rvec``.

    d/dphi of c + Rot(s phi) r0 + c_p phi n is s n x r + c_p n, with s = +1 for
    counter-clockwise and -1 for clockwise arcs.
    """
    s = np.where(ccw, 1.0, -1.0)[:, None]
    return unit(s * np.cross(normal, rvec) + pitch[:, None] * normal)


def arc_curvature(radius: NDArray[np.float64], pitch: NDArray[np.float64]) -> NDArray[np.float64]:
    """Curvature of a helix, r / (r^2 + c^2) (1/mm); 1/r for planar arcs."""
    return radius / (radius**2 + pitch**2)


def arc_points(
    start: NDArray[np.float64],
    center: NDArray[np.float64],
    normal: NDArray[np.float64],
    ccw: NDArray[np.bool_],
    sweep: NDArray[np.float64],
    pitch: NDArray[np.float64],
    frac: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Points at fractions ``frac`` (0 = start, 1 = end) of helical arcs, one per row.

    Parameters
    ----------
    start, center, normal : (m, 3) float
    ccw : (m,) bool
    sweep, pitch, frac : (m,) float
        Sweep (rad), rise per radian (mm/rad), fraction of the sweep.

    Returns
    -------
    (m, 3) float, mm
    """
    phi = frac * sweep * np.where(ccw, 1.0, -1.0)
    r0 = radial(start, center, normal)
    # Rodrigues' rotation of r0 (perpendicular to n) by phi about n.
    rot = r0 * np.cos(phi)[:, None] + np.cross(normal, r0) * np.sin(phi)[:, None]
    rise = (pitch * frac * sweep)[:, None] * normal
    base = center + dot(start - center, normal)[:, None] * normal
    return base + rot + rise


#: Points computed together by :func:`sample_arcs`.
SAMPLE_PIECE = 262_144


def sample_arcs(
    start: NDArray[np.float64],
    center: NDArray[np.float64],
    normal: NDArray[np.float64],
    ccw: NDArray[np.bool_],
    sweep: NDArray[np.float64],
    pitch: NDArray[np.float64],
    counts: NDArray[np.int64],
) -> NDArray[np.float64]:
    """Points along arcs for drawing, ``counts[i] + 1`` per arc (start and end included).

    Returns
    -------
    (sum(counts + 1), 3) float, mm
        The arcs' points one after the other.
    """
    counts = np.asarray(counts, dtype=np.int64)
    m = counts + 1
    ends = np.cumsum(m)
    out = np.empty((int(ends[-1]) if ends.size else 0, 3))
    # In pieces of whole arcs of about SAMPLE_PIECE points: every point is computed from its
    # own arc's row, so the pieces change nothing but the size of the (points, 3)
    # temporaries (4M points at once: 870 MB).
    a = 0
    while a < m.size:
        done = ends[a - 1] if a else 0
        b = max(int(np.searchsorted(ends, done + SAMPLE_PIECE, side="right")), a + 1)
        owner = np.repeat(np.arange(a, b), m[a:b])
        first = ends[a:b] - m[a:b]
        k = np.arange(done, ends[b - 1]) - first[owner - a]
        frac = k / counts[owner]
        out[done : ends[b - 1]] = arc_points(
            start[owner], center[owner], normal[owner], ccw[owner], sweep[owner], pitch[owner], frac
        )
        a = b
    return out
