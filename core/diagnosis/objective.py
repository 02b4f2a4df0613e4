"""What a fit minimises: the feed gap, or the block-time error.

Fitting (:mod:`core.diagnosis.fit`), forward selection
(:func:`core.diagnosis.diagnose.add_effects`) and calibration take an :class:`Objective`:
the gap on calibration or held-out data, and the held-out pieces of the significance test.

* :data:`FEED`: RMS over time of measured - predicted feed on the path (mm/min;
  :mod:`core.diagnosis.resample`), for traces that sample the motion finely.
* :data:`BLOCK_TIME`: RMS over windows of feed blocks of measured - predicted time between
  observed program-line changes (ms; :mod:`core.diagnosis.blocktime`), for recordings that
  sample coarsely (MTConnect).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from core.diagnosis import blocktime, resample
from core.engine.predict import Prediction


@dataclass(frozen=True)
class Objective:
    """A gap and its test samples over one kind of data.

    Attributes
    ----------
    name : str
        "feed" or "block-time" (the ``--objective`` values).
    unit : str
        Of the gap: "mm/min" or "ms".
    what : str
        What the gap is, for reports.
    gap : callable (predictions, data, which) -> float
        ``which``: "calibration", "held_out" or "all".
    chunks : callable (predictions, data) -> (squared gaps, weights)
        Per held-out piece, for the sign-flip test.
    """

    name: str
    unit: str
    what: str
    gap: Callable[[Sequence[Prediction], Sequence[Any], str], float]
    chunks: Callable[
        [Sequence[Prediction], Sequence[Any]], tuple[NDArray[np.float64], NDArray[np.float64]]
    ]


FEED = Objective(
    "feed",
    "mm/min",
    "RMS over time of measured - predicted feed",
    resample.gap,
    resample.held_out_chunks,
)
BLOCK_TIME = Objective(
    "block-time",
    "ms",
    "RMS over windows of feed blocks of measured - predicted time between observed line changes",
    blocktime.gap,
    blocktime.held_out_chunks,
)
OBJECTIVES = {o.name: o for o in (FEED, BLOCK_TIME)}
