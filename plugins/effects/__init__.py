"""Unmodelled effects as plugins (``ncperf_effects``), one module each.

Each names what a real controller does beyond the paper's models, its parameters with
bounds, and how it changes the prediction (:mod:`core.engine.effects`). ``ncperf diagnose`` fits
them to measured traces; a machine file switches them on with ``[effects.NAME]`` tables.

The list of the built-in ones is :data:`core.plugins.BUILTIN_EFFECTS`.
"""
