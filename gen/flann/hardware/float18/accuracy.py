"""How far a float18 design is from its float model, and when ``flann gen`` says so.

float18 has no error budget: its 11 fraction bits round every product and every partial
sum to half an ulp of that value, so a model whose terms cancel (partial sums far above
the output) loses accuracy that no generator option recovers.  The check is the bit-true
twin against the float model over every input code (a sample of them for inputs wider
than :data:`EXHAUSTIVE_CODES`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..adc import model_accuracy_mm
from .spec import F18Spec, FlannF18Top

# every code up to 12-bit inputs (the widest float18 holds exactly): 4096 codes x the terms
# is a fraction of a second; wider inputs are sampled with as many codes
EXHAUSTIVE_CODES = 1 << 12


@dataclass(frozen=True)
class FloatModelError:
    max_err_mm: float               # max |twin - float model| over the codes checked
    at_code: int                    # the code where it is largest
    codes: int                      # codes checked
    exhaustive: bool                # every input code
    code_step_mm: float             # output change per input code: the stroke over the codes
    model_error_mm: float | None    # the model's own RMS error: held-out, else on its training data
    max_partial_mm: float           # largest |partial sum| of the running sum
    max_out_mm: float               # largest |output|

    @property
    def tolerance_mm(self) -> float:
        """Above this, float18 rounding, not the model or the converter, is the design's
        largest error: the larger of the model's own error and one input code's step."""
        return max(self.code_step_mm, self.model_error_mm or 0.0)

    @property
    def large(self) -> bool:
        return self.max_err_mm > self.tolerance_mm


def model_error_mm(model) -> float | None:
    """The model's own RMS error (mm): held-out when its training record has it, else on its training data."""
    own = model_accuracy_mm(model)
    if own is None and isinstance(model.training, dict):
        own = model.training.get("train_rms_error_mm")
    return float(own) if isinstance(own, (int, float)) and np.isfinite(own) else None


def _codes(spec: F18Spec, limit: int, seed: int) -> tuple[np.ndarray, bool]:
    n = spec.code_max - spec.code_min + 1
    if n <= limit:
        return np.arange(spec.code_min, spec.code_max + 1, dtype=np.int64), True
    # the ends (where |y| and the partial sums are largest) and a random spread between
    rng = np.random.default_rng(seed)
    ends = np.r_[spec.code_min:spec.code_min + 64, spec.code_max - 63:spec.code_max + 1]
    mid = rng.integers(spec.code_min, spec.code_max + 1, size=limit - ends.size)
    return np.unique(np.r_[ends, mid]).astype(np.int64), False


def float_model_error(spec: F18Spec, limit: int = EXHAUSTIVE_CODES, seed: int = 0) -> FloatModelError:
    """max |twin - float model| (mm) over every input code, or ``limit`` of them when there are more."""
    codes, exhaustive = _codes(spec, limit, seed)
    t = FlannF18Top(spec).trace(codes)
    fmt = spec.fmt
    ref = spec.float_reference(codes)
    err = np.abs(fmt.decode_array(t.out) - ref)
    i = int(np.argmax(err))
    # the ends of the clamped range hold the output's extremes (a monotone inverse)
    ends = spec.float_reference(np.array([spec.code_min, spec.code_max], dtype=np.int64))
    return FloatModelError(
        max_err_mm=float(err[i]), at_code=int(codes[i]), codes=int(codes.size), exhaustive=exhaustive,
        code_step_mm=(float(abs(ends[1] - ends[0])) or 1.0) / (spec.code_max - spec.code_min),
        model_error_mm=model_error_mm(spec.model),
        max_partial_mm=float(np.abs(fmt.decode_array(t.running)).max()),
        max_out_mm=float(np.abs(fmt.decode_array(t.out)).max()))


def warning_text(e: FloatModelError, where: str = "") -> str | None:
    """One warning for a design whose error is large (None otherwise)."""
    if not e.large:
        return None
    over = "every input code" if e.exhaustive else f"{e.codes} sampled input codes"
    step = f"the output change per input code ({e.code_step_mm:.3g} mm)"
    bound = (f"{step}; the model records no error of its own" if e.model_error_mm is None
             else f"both the model's own RMS error ({e.model_error_mm:.3g} mm) and {step}")
    ratio = e.max_partial_mm / max(e.max_out_mm, 1e-300)
    cancel = (f"; its partial sums reach {e.max_partial_mm:.3g} mm, {ratio:.1f}x the largest output, and each "
              "addition rounds to half an ulp of the partial sum" if ratio > 2 else "")
    return (f"{where + ': ' if where else ''}the float18 design is {e.max_err_mm:.3g} mm off its float model "
            f"(max over {over}, at code {e.at_code}), more than {bound}: float18 rounding is the design's "
            f"largest error{cancel}; "
            "the fixed-point design (--format fixed) keeps it within its error budget, and `flann trace DIR` "
            "shows where it arises")


__all__ = ["EXHAUSTIVE_CODES", "FloatModelError", "float_model_error", "model_error_mm", "warning_text"]
