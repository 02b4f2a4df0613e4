"""The end speeds LinuxCNC 2.9's planner leaves lowered: its lazy look-ahead.

LinuxCNC plans while the program is read. Each time a segment joins its queue it walks the
queue backwards from the new segment (tp.c ``tpRunOptimization``) and sets every earlier
segment's final speed from the one after it, v_f^2 = v'^2 + 2 a_t L
(``tpComputeOptimalVelocity``), at most the lower of the two segments' speed limits. The new
segment itself is not final yet (the next blend may still cut it): the walk gives the one
before it only the peak of a triangle over the new segment's length at its tangential
acceleration, sqrt(a_t L) (``tpCalculateOptimizationInitialVel``, blendmath.h ``findVPeak``),
and a line added under G64 has term_cond PARABOLIC, which halves its acceleration
(tc.c ``tcGetOverallMaxAccel``): sqrt(a L / 2).

The walk is lazy (``TP_OPTIMIZATION_LAZY``): a segment whose final speed reached its limit
in some walk is marked "at max" for good (the mark is set, never cleared), and a walk stops
once it has passed more than ``TP_OPTIMIZATION_CUTOFF`` = 4 marked segments; it also stops
after ``ARC_BLEND_OPTIMIZATION_DEPTH`` (50) steps and at the second segment that does not
end tangentially (a stop), skipping the first. A final speed is the one the last walk that
reached it left. Where short segments run into a long one, the long one's open triangle
lowers the short ones' final speeds over as many segments as it takes to climb back to
their limit; when the segment after the long one arrives, the walk raises them again only
as far back as its fifth marked segment -- the short ones were marked at their limits
before -- and the ones further back keep the lowered speeds: the machine slows down on
them, at the blend arcs' tangential acceleration, for no geometric reason (gear teeth of
0.06 mm chords before a 1.2 mm flank: 42.6 mm/s recorded where the chords' limit is 58.8;
the closed form sqrt(a L / 2 + 2 sum a_t l) of the five segments nearest the flank gives
42.4).

:func:`lazy_caps` replays the walks over the segments LinuxCNC makes of a program -- what is
left of each block between its blend arcs, and the arcs -- and gives the speeds they leave
at the program's boundaries, as caps for the profile's passes (only lower than what full
look-ahead gives where a walk stopped early; the passes keep every speed consistent).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from core.model.jit import compiled_for

#: LinuxCNC 2.9: ``[TRAJ] ARC_BLEND_OPTIMIZATION_DEPTH`` (default 50, the walk's steps; ini
#: and milltask defaults) and tp.c ``TP_OPTIMIZATION_CUTOFF`` (a walk stops once it has
#: passed more marked segments than this).
OPT_DEPTH = 50
OPT_CUTOFF = 4
#: The share of a line's acceleration while it is the queue's last segment under G64: its
#: term_cond is PARABOLIC until the next segment is blended with it (tc.c).
OPEN_SHARE = 0.5


def lazy_walks(
    dn: NDArray[np.float64],
    lim2: NDArray[np.float64],
    tangent: NDArray[np.bool_],
    first: NDArray[np.int64],
    open2: NDArray[np.float64],
    depth: int = OPT_DEPTH,
    cutoff: int = OPT_CUTOFF,
) -> NDArray[np.float64]:
    """The squared final speed every planner segment is left with (inf: no walk set it).

    Segments s = 0..S-1 in path order; ``dn[s]`` = 2 a_t L of segment s, ``lim2[s]`` its
    squared speed limit at its end (the lower of its own and the next one's), ``tangent[s]``
    whether it ends tangentially (else a stop). Blocks k = 0..K-1 join the queue one after
    the other; ``first[k]`` is the index of block k's first segment (the segments before it
    are final when it joins), ``open2[k]`` the squared triangle peak of block k while it is
    the queue's last. After the last block the program's end is a stop: one more walk. The
    walk of tp.c ``tpRunOptimization`` step by step (see the module docstring; :func:`walks`),
    compiled by numba (:func:`_compiled`, the same function) where the diagnosis allows
    the kernels and on queues long enough that numba's start-up costs less than the Python
    loop (core.model.jit.compiled_for).
    """
    kernels = compiled_for(dn.size)
    fv2 = np.full(dn.size, np.inf)
    if dn.size == 0:
        return fv2
    if kernels is not None:
        _compiled(kernels)(
            dn, lim2, tangent, first, open2, depth, cutoff, fv2, np.zeros(dn.size, dtype=np.bool_)
        )
        return fv2
    # plain Python over lists: a float list's items are Python floats (no boxing per read)
    fv = fv2.tolist()
    walks(
        dn.tolist(),
        lim2.tolist(),
        tangent.tolist(),
        first.tolist(),
        open2.tolist(),
        depth,
        cutoff,
        fv,
        [False] * dn.size,
    )
    return np.array(fv, dtype=np.float64)


def walks(dn, lim2, tangent, first, open2, depth, cutoff, fv, at_max) -> None:
    """:func:`lazy_walks`' steps into ``fv`` (and the marks ``at_max``, all False at first),
    over lists (Python) or arrays (compiled by numba: :func:`_compiled`)."""
    n_seg = len(dn)
    n_blocks = len(first)
    for k in range(n_blocks + 1):
        # block k joins (k = K: the program's end, a stop after the last segment)
        last = (first[k] if k < n_blocks else n_seg) - 1
        hit = 0
        skipped = False
        for x in range(1, depth + 2):
            pv = last + 1 - x  # the segment whose final speed this step sets
            if pv < 0:
                break
            if not tangent[pv]:
                if skipped:
                    break
                skipped = True
                fv[pv] = 0.0
                continue
            tc = pv + 1
            if x == 1:
                # the new block (not final): the triangle over it, within the limit (at the
                # program's end the last segment is a stop: skipped above)
                o = open2[k]
                fv[pv] = o if o < lim2[pv] else lim2[pv]
                continue
            vs = fv[tc] + dn[tc]
            if vs >= lim2[pv]:
                vs = lim2[pv]
                at_max[pv] = True
            fv[pv] = vs
            if at_max[tc]:
                hit += 1
                if hit > cutoff:
                    break


@cache
def _compiled(kernels: ModuleType) -> Callable[..., None]:
    """:func:`walks` compiled with the kernels' settings (``kernels.kernel``: numba's njit,
    cached on disk, numpy's float rules; :mod:`core.model.compiled`), once per process."""
    return kernels.kernel(walks)


def lazy_caps(
    length: NDArray[np.float64],
    cap: NDArray[np.float64],
    b: NDArray[np.float64],
    acc: NDArray[np.float64],
    a_blend: NDArray[np.float64],
    h_start: NDArray[np.float64],
    h_end: NDArray[np.float64],
    r_start: NDArray[np.float64],
    r_end: NDArray[np.float64],
    rest: NDArray[np.float64] | None,
) -> NDArray[np.float64]:
    """(n + 1,) speed caps (mm/s) at the program's boundaries from LinuxCNC's lazy walks
    (:func:`lazy_walks`; inf where they leave none).

    The planner's segments, block by block: what is left of block k between the holds of
    its blend arcs (``length - h_start - h_end``, unless it is run as part of the next arc,
    ``rest``), limit ``cap[k]``, acceleration ``acc[k]``; then the arc at its end, if any
    (hold > 0): its length the travel on both sides plus the rest it runs, its limit the
    junction's cap ``b[k + 1]``, its acceleration the lower ``a_blend`` of the two blocks.
    The cap at boundary k + 1 (the corner, inside the arc) is the speed from which the
    arc's second half still reaches its final speed; at a corner without an arc, the
    final speed of what ends there.
    """
    n = length.size
    out = np.full(n + 1, np.inf)
    if n < 2:
        return out
    rest = np.zeros(n) if rest is None else rest
    arc = np.zeros(n, dtype=bool)
    arc[:-1] = h_end[:-1] > 0
    inner = length - h_start
    inner -= h_end
    own = (inner > 0) & ~((rest > 0) & arc)
    own |= ~arc & ~(h_start > 0)  # (a block with neither: itself, whatever its length)
    first = np.zeros(n, dtype=np.int64)
    np.cumsum((own + arc.astype(np.int64))[:-1], out=first[1:])
    total = int(first[-1]) + int(own[-1]) + int(arc[-1])
    k_own = np.flatnonzero(own)  # the blocks with each kind of segment
    k_arc = np.flatnonzero(arc)
    i_own = first[k_own]  # and the segments' indices
    i_arc = first[k_arc] + own[k_arc]
    # what ends at a corner without an arc (among the blocks' own segments)
    ends = ~arc[k_own]
    vmax = np.empty(total)
    vmax[i_own] = cap[k_own]
    vmax[i_arc] = b[k_arc + 1]
    lim2 = np.empty(total)
    np.minimum(vmax[:-1], vmax[1:], out=lim2[:-1])
    lim2[-1] = vmax[-1]
    del vmax
    # ... whose limit is also the corner's cap (a kink's speed, a stop)
    lim2[i_own[ends]] = np.minimum(lim2[i_own[ends]], b[k_own[ends] + 1])
    tangent = lim2 > 0
    tangent[-1] = False
    lim2 *= lim2
    dn = np.empty(total)
    dn[i_own] = 2.0 * acc[k_own] * np.maximum(inner[k_own], 0.0)
    del inner
    # an arc: the travel on both sides and the rest it runs, at the lower a_blend of its blocks
    arc_len = r_end[k_arc] * h_end[k_arc] + r_start[k_arc + 1] * h_start[k_arc + 1]
    arc_len += rest[k_arc]
    dn[i_arc] = 2.0 * np.minimum(a_blend[k_arc], a_blend[k_arc + 1]) * arc_len
    del arc_len
    # a block while it is the queue's last: from its start (trimmed by the arc before it)
    open2 = OPEN_SHARE * acc * (length - h_start)
    fv2 = lazy_walks(dn, lim2, tangent, first, open2)
    del lim2, tangent, first, open2
    # the corners: inside an arc the speed that still reaches the arc's final one over its
    # second half; else the final speed of what ends there
    v2 = np.full(n, np.inf)
    v2[k_arc] = fv2[i_arc] + 0.5 * dn[i_arc]
    v2[k_own[ends]] = fv2[i_own[ends]]
    out[1:] = np.sqrt(v2)
    out[-1] = np.inf
    return out
