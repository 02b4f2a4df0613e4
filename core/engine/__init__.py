"""The engine: what the machine does with a tool path.

:mod:`~core.engine.indicators` (A2 results and their combination),
:mod:`~core.engine.profile` (the feed profile over the whole program, the cycle time),
:mod:`~core.engine.effects` (controller effects beyond the paper's models) and
:mod:`~core.engine.predict` (a prediction built from a machine and its effects).

Imports :mod:`core.model` only.
"""
