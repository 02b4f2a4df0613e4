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

    #: Moves shorter than this (mm) are points, not blocks: the least command increment of
    #: ISO controls (Fanuc IS-B 0.001 mm; Siemens 840D MD10200 INT_INCR_PER_MM = 1000).
    #: A machine cannot move less, so a CAM system's 0.0001 mm corner arc is no block that
    #: the block cycle time (model 3) could slow down to 0.5 mm/min.
    resolution: float = 1e-3

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

    #: A G or M code (stored as ten times its number) within this of a whole tenth is that
    #: code (G64.1 is 641): the words are parsed from decimal text, so only the float
    #: rounding of x10 separates them, ~1e-13.
    code_number: float = 1e-6

    #: A tool axis i,j,k further than this from unit length (CL data) is a misreading, not
    #: rounding: CAM systems write it with 6-7 decimals.
    unit_vector: float = 1e-3

    #: Direction components (and lengths of direction vectors) closer than this are equal
    #: (zero): far below the 6-7 decimals CAM writes, far above float rounding.
    direction: float = 1e-9

    #: Two unit tangents whose difference perpendicular to the first is below this are
    #: parallel or reversed (model 1 then needs any perpendicular; the radius is 0 anyway).
    reversal: float = 1e-12

    # ---------------------------------------------------------------- numerical slack
    #: Relative slack on comparisons of results that went through sums or iterations
    #: (cycle times, scores, lengths): values within 1e-9 of each other are equal, well
    #: above the accumulated rounding of a million-term sum (~1e-10 relative).
    rel_equal: float = 1e-9

    #: Relative slack on comparisons of a value with the same value computed another way in
    #: one or two operations (a share of F, a full turn): a few ulps, 1e-12.
    float_slack: float = 1e-12

    #: Relative margin by which a value computed in a few dozen float operations must clear
    #: the value it is compared with for the comparison to be the one exact arithmetic would
    #: give (the rounding is ~30 ulps, 7e-15, of the terms' size): a ramp's place against
    #: a goal (:func:`core.engine.profile._bisect_ramp`).
    sure_compare: float = 1e-13

    #: Speeds and speed changes (mm/s) below this are nil: a nanometre per second.
    nil_speed: float = 1e-9

    #: Distances (mm) below this are nil where a length is the result of subtractions (a
    #: cruise between two ramps): a picometre, below any physical meaning.
    nil_distance: float = 1e-9

    #: Arc lengths (mm) rising by less than this are one point for interpolation, which
    #: needs strictly rising abscissae.
    same_s: float = 1e-12

    #: Smallest positive number used to keep a division defined in a branch whose result is
    #: not used (the other branch of an ``np.where``).
    tiny: float = 1e-300

    #: A first-order lag whose pole exp(-dt / tau) is below this passes its input unchanged
    #: (tau under dt / 14: less than a thousandth of a sample's weight carries over).
    negligible_pole: float = 1e-6

    # ---------------------------------------------------------------- alignment (traces)
    #: Distances (mm) that count as equal when two passes of the path coincide (a plunge
    #: down its own retract): a micrometre, below the resolution of the recordings.
    pass_tie: float = 1e-3

    #: The same in the sequential search without program lines, per mm of arc length from
    #: where the samples' own travel puts them (that estimate drifts, so the weight is lower).
    sequence_tie: float = 1e-4

    #: The rigid offset between a trace and its program is converged when an iteration
    #: moves it by less than this (mm): a tenth of a micrometre.
    offset_step: float = 1e-4

    #: Speeds (mm/s) below this are a stop when converting distance to time (1 um/s).
    min_speed: float = 1e-3


TOL = Tolerances()


#: Default time step (s) of a sampled profile: 1 ms, the servo cycle of the traces it is
#: compared with (LinuxCNC, the reference interpreter). Here, with no numpy, so that the
#: command line's parser can show it without importing the engine.
SAMPLE_DT = 0.001
