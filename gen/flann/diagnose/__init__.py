"""``flann diagnose``: where simulation and recordings differ, and which physics is missing.

Layers (one way): :mod:`.data` (model-free checks, passes, noise, rails, outliers, regions)
-> :mod:`.calibrate` (ideal simulation: gain, origin, geometry) -> :mod:`.model` (calibrated
simulation + smooth shape term + catalogue effects as one least-squares family) ->
:mod:`.select` (forward selection by BIC and cross-validation) -> :mod:`.pipeline` (the
steps in order) -> :mod:`.explain` / :mod:`.report` (sentences, JSON, text, plot).
:mod:`.demo` proves it on recordings with concealed effects from two forward models.

Public API: :func:`diagnose` (Recordings, sensor=None, max_points=None) -> :class:`Diagnosis`.
"""

from .pipeline import Diagnosis, EffectReport, diagnose

__all__ = ["Diagnosis", "EffectReport", "diagnose"]
