"""The few tolerances ncperf uses, in one place (trimesh ``constants.py`` style).

Each value says why it has its value. Code takes them from :data:`TOL`; there
are no other epsilons.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Tolerances:
    #: Moves shorter than this (mm) are zero-length: 1e-6 mm is a hundred times
    #: below the finest resolution a CAM post writes (4 decimals in inch = 2.5 um).
    zero_length: float = 1e-6

    #: Direction change (rad) above which a junction is a tangential
    #: discontinuity (model 1). 1e-6 rad is a 1 nm deviation over 1 mm, below
    #: any program's resolution; smaller angles are rounding noise. Model 1
    #: itself predicts no slow-down for tiny angles, so the threshold only
    #: keeps noise out of the junction list.
    collinear_angle: float = 1e-6

    #: Direction change (rad) below which a junction counts as tangent for the
    #: curvature model (model 2). CAM systems write tangent line-arc
    #: transitions with 4-5 decimals, which leaves kinks of up to ~1e-3 rad on
    #: millimetre blocks; up to this angle the curvature jump, not the kink,
    #: is what the controller sees.
    tangent_angle: float = 2e-3

    #: Curvature jumps (1/mm) below this are not discontinuities: 1e-6 1/mm is
    #: the difference between radii of 1000 m and infinity.
    curvature_jump: float = 1e-6

    #: Arc end point off the circle through the start (mm): LinuxCNC's
    #: interpreter accepts |r_end - r_start| up to 2*0.01*sqrt(2) mm ...
    arc_end_abs: float = 2 * 0.01 * math.sqrt(2)
    #: ... or up to 0.1 % of the radius (its SPIRAL_RELATIVE_TOLERANCE);
    #: beyond both the block is rejected (rs274ngc interp_arc.cc).
    arc_end_rel: float = 1e-3

    #: R-format arcs whose chord exceeds 2R by less than this (mm) are taken as
    #: half circles (LinuxCNC RADIUS_TOLERANCE_MM = 0.00005 in).
    arc_radius: float = 0.00005 * 25.4

    #: Radius (mm) below which an arc is degenerate.
    min_arc_radius: float = 1e-6


TOL = Tolerances()
