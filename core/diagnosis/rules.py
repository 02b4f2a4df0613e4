"""Every threshold, parameter and colour of the diagnosis, in one place.

The diagnosis (:mod:`core.diagnosis.diagnose`), its reports (:mod:`core.cli`) and its
displays (the SVG adapter) read them from here; change one here and every one of them
follows.
"""

from __future__ import annotations

# ---------------------------------------------------------------- the gap, on the path
#: Comparison step along the path (mm); coarser for long programs (MAX_POINTS).
STEP = 0.1
MAX_POINTS = 200_000
#: Time weights use the measured feed, but never below this share of F (stops would weigh
#: without bound).
TIME_FLOOR = 0.02
#: Samples further apart than this many sample periods leave a hole: not compared.
GAP_PERIODS = 20
#: Stretches of one run used for calibration / held-out data (alternating).
CHUNKS = 16
#: Gaps are reported in mm/min (as F words); the diagnosis computes in mm/s.
PER_MIN = 60.0

# ---------------------------------------------------------------- the gap map
#: A stretch belongs to the gap map where |measured - predicted| exceeds this share of F.
GAP_SHARE = 0.05
#: Gap-map stretches closer than this (mm) are one zone.
MERGE_MM = 1.0
#: Zones listed, worst (most seconds) first.
ZONES = 10

# ---------------------------------------------------------------- naming an effect
#: The best effect must remove this share of the held-out gap; later ones ADD_SHARE of
#: what is left, until less than STOP_SHARE of the gap before is left.
BEST_SHARE = 0.20
ADD_SHARE = 0.10
STOP_SHARE = 0.10
#: ... and remove at least this share of the programmed feed (RMS over the held-out data):
#: a gap already within 0.75 % of F is explained, whatever share of it an effect could fit.
MIN_FEED_SHARE = 0.0075
#: Most effects chosen together.
MAX_CHOSEN = 4
#: Effects whose held-out gaps differ by less than this share of what the best removes are
#: equally good; the one with the fewest parameters is ranked first.
TIE_SHARE = 0.05

# ---------------------------------------------------------------- fitting
#: Grid points per parameter when fitting (then REFINE rounds of local refinement).
GRID_1D = 11
GRID_2D = 6
GRID_ND = 4
REFINE = 8

# ---------------------------------------------------------------- display
#: Gap classes of the displays: (measured - predicted) / F, from "much slower" to "much
#: faster"; the labels are made from the edges, so the two cannot disagree.
GAP_EDGES = (-0.20, -0.10, 0.10, 0.20)


def _pct(x: float) -> str:
    return f"{abs(x) * 100:.0f}"


GAP_LABELS = (
    f"measured {_pct(GAP_EDGES[0])} % slower or more",
    f"{_pct(GAP_EDGES[1])}-{_pct(GAP_EDGES[0])} % slower",
    f"within {_pct(GAP_EDGES[2])} %",
    f"{_pct(GAP_EDGES[2])}-{_pct(GAP_EDGES[3])} % faster",
    f"measured {_pct(GAP_EDGES[3])} % faster or more",
)
GAP_COLOURS = ("#b2182b", "#f4a582", "#1a9850", "#92c5de", "#2166ac")
