"""LVDT physics: sensor description, magnetics, non-ideal effects, simulation and fitting.

Layers (one way): :mod:`.effect_params` (effect names, parameters, bounds) ->
:mod:`.sensor` (validated construction) -> :mod:`.lvdt` (ideal magnetics
and demodulator) -> :mod:`.effects` (catalogue of non-ideal effects) -> :mod:`.simulate`
(all effects, recordings) -> :mod:`.fit` (calibrating unknown geometry).
:mod:`.filament` is an independent forward model (other formulation, own effects) used only
to prove ``flann diagnose`` on curves it did not make.  See
docs/physics.md.
"""
