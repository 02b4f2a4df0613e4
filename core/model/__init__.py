"""The model: what ncperf reasons about, with no behaviour of a machine in it.

:mod:`~core.model.toolpath` (the columnar tool path and its arc-length queries),
:mod:`~core.model.machine` (axis limits and controller times, from TOML),
:mod:`~core.model.trace` (a measured recording), :mod:`~core.model.geometry` (lines and
helical arcs, vectorised), :mod:`~core.model.tolerances` (every tolerance, with its reason)
and :mod:`~core.model.errors` (the errors a user's input can cause).

Imports nothing else of ncperf.
"""
