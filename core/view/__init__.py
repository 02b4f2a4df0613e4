"""The view: what the displays (A3) and the reports read.

:mod:`~core.view.analysis` (the result of one analysis), :mod:`~core.view.annotations`
(colour classes and markers after the paper's Fig. 10 and 11),
:mod:`~core.view.zones` (the zones that lose the most time) and
:mod:`~core.view.targets` (what to draw into: files, comparisons, diagnoses).

Imports :mod:`core.model` and :mod:`core.engine`.
"""
