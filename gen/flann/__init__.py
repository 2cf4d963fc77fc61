"""FLANN LVDT compensator: golden model, VHDL-93 generator, co-simulation, physics and diagnosis."""

import os as _os

# Small matrices only (<= a few thousand x 62): BLAS threads buy nothing and, on a busy
# machine, oversubscription slows QR/lstsq by ~100x; one thread also keeps results
# bit-identical run to run.  Only effective if numpy is not imported yet; users can override.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

__version__ = "0.1.0"
