"""The diagnosis: where a measured trace departs from the prediction, and why.

:mod:`~core.diagnosis.align` (each sample's place on the path),
:mod:`~core.diagnosis.resample` (measured feed on the path, calibration / held-out split,
the gap), :mod:`~core.diagnosis.fit` (an effect's parameters on calibration data),
:mod:`~core.diagnosis.parallel` (several fits at once, on worker processes),
:mod:`~core.diagnosis.gaps` (the gap map), :mod:`~core.diagnosis.diagnose` (ranking and
choosing effects) and :mod:`~core.diagnosis.rules` (every threshold and colour of the
diagnosis, read by the reports and the displays).

Imports :mod:`core.model`, :mod:`core.engine` and :mod:`core.view`.
"""
