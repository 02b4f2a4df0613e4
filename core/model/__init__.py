"""The model: what ncperf reasons about, with no behaviour of a machine in it.

:mod:`~core.model.toolpath` (the columnar tool path and its arc-length queries),
:mod:`~core.model.machine` (axis limits and controller times, from TOML),
:mod:`~core.model.trace` (a measured recording), :mod:`~core.model.geometry` (lines and
helical arcs, vectorised), :mod:`~core.model.tolerances` (every tolerance, with its reason)
and :mod:`~core.model.errors` (the errors a user's input can cause);
:mod:`~core.model.pieces` and :mod:`~core.model.arrays` (work over the moves' columns); two
helpers of the process, :mod:`~core.model.heap` (free heap pages back to the system) and
:mod:`~core.model.workers` (independent tasks on forked worker processes).

Imports nothing else of ncperf.
"""
