"""LVDT physics: sensor description, magnetics, non-ideal effects, simulation and fitting.

Layers (one way): :mod:`.sensor` (validated construction) -> :mod:`.lvdt` (ideal magnetics
and demodulator) -> :mod:`.effects` (catalogue of non-ideal effects) -> :mod:`.simulate`
(all effects, recordings) -> :mod:`.fit` (calibrating unknown geometry).  See
docs/physics.md.
"""
