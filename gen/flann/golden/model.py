"""The FLANN inverse model: trigonometric expansion, weights, and the ``model.json`` file.

Expansion in the paper's order, truncated to N terms::

    phi = [v_n, sin(pi v_n), cos(pi v_n), sin(2 pi v_n), cos(2 pi v_n), ...]
    v_n = (v - input_offset_v) / input_scale_v
    y_mm = bias + sum_i w_i phi_i(v_n)

Term i (0-based): i = 0 is v_n; for i >= 1 the harmonic is m = (i + 1) // 2, odd i is a
sine and even i a cosine.  This module is the single definition of that order; the
fixed-point spec, the bit-true twin and the VHDL generator all ask it.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ModelFileError
from ..fileio import atomic_write_text

FORMAT = "flann-model/1"


def term_kind(i: int) -> tuple[str, int]:
    """('lin', 1) for term 0, else ('sin'|'cos', harmonic m)."""
    if i < 0:
        raise ValueError("term index must be >= 0")
    if i == 0:
        return ("lin", 1)
    return ("sin" if i % 2 == 1 else "cos", (i + 1) // 2)


def harmonics(terms: int) -> int:
    """Highest harmonic m used by an N-term expansion."""
    return term_kind(terms - 1)[1] if terms > 1 else 0


def expand(v_n, terms: int) -> np.ndarray:
    """Expansion matrix, shape (len(v_n), terms), in the paper's order."""
    v = np.atleast_1d(np.asarray(v_n, dtype=float))
    if terms < 1:
        raise ValueError("terms must be >= 1")
    out = np.empty((v.size, terms))
    out[:, 0] = v
    m = np.arange(1, harmonics(terms) + 1)
    arg = np.pi * np.outer(v, m)
    out[:, 1::2] = np.sin(arg)[:, : out[:, 1::2].shape[1]]
    out[:, 2::2] = np.cos(arg)[:, : out[:, 2::2].shape[1]]
    return out


# Samples per block of the recurrence: the working arrays stay in the L2 cache.
_BLOCK = 4096


def evaluate(v_n, weights, bias: float = 0.0) -> np.ndarray:
    """``bias + sum_i w_i phi_i(v_n)`` without one sin and cos per term.

    With ``z = exp(i pi v_n)`` the trigonometric part is ``Re(sum_m c_m z^m)`` where
    ``c_m = w_cos(m) - i w_sin(m)``; Horner's rule in z (one complex multiply-add per
    harmonic, |z| = 1 so rounding does not grow with m beyond ~m ulp) replaces the
    2 x harmonics transcendental calls of :func:`expand` by one complex exponential.
    """
    v = np.atleast_1d(np.asarray(v_n, dtype=float))
    w = np.asarray(weights, dtype=float)
    if w.size < 1:
        raise ValueError("terms must be >= 1")
    M = harmonics(w.size)
    c = np.zeros(M + 1, dtype=complex)  # c[m] for m = 1..M; c[0] unused
    c[1:1 + w[1::2].size] -= 1j * w[1::2]
    c[1:1 + w[2::2].size] += w[2::2]
    out = np.empty(v.shape)
    flat_v, flat_out = v.reshape(-1), out.reshape(-1)
    for start in range(0, flat_v.size, _BLOCK):
        vb = flat_v[start:start + _BLOCK]
        y = bias + w[0] * vb
        if M:
            z = np.exp(1j * np.pi * vb)
            acc = np.full(vb.shape, c[M])
            for m in range(M - 1, 0, -1):
                acc *= z
                acc += c[m]
            acc *= z
            y += acc.real
        flat_out[start:start + _BLOCK] = y
    return out


@dataclass(frozen=True)
class FlannModel:
    weights: tuple[float, ...]
    bias: float = 0.0
    input_offset_v: float = 0.0
    input_scale_v: float = 1.0
    voltage_range_v: tuple[float, float] = (-1.0, 1.0)
    displacement_range_mm: tuple[float, float] = (-1.0, 1.0)
    training: dict = field(default_factory=dict)

    @property
    def terms(self) -> int:
        return len(self.weights)

    def normalise(self, voltage_v) -> np.ndarray:
        return (np.asarray(voltage_v, dtype=float) - self.input_offset_v) / self.input_scale_v

    def features(self, voltage_v) -> np.ndarray:
        return expand(self.normalise(voltage_v), self.terms)

    def predict(self, voltage_v) -> np.ndarray:
        """Displacement (mm) for voltages (V), float64 (trigonometric sum by recurrence)."""
        return evaluate(self.normalise(voltage_v), self.weights, self.bias)

    def predict_direct(self, voltage_v) -> np.ndarray:
        """The same sum term by term (one sin and cos per term): the reference for tests."""
        return self.bias + self.features(voltage_v) @ np.asarray(self.weights)

    # -- file -----------------------------------------------------------------
    def to_dict(self) -> dict:
        return {
            "format": FORMAT,
            "terms": self.terms,
            "input_offset_v": self.input_offset_v,
            "input_scale_v": self.input_scale_v,
            "bias": self.bias,
            "weights": list(self.weights),
            "voltage_range_v": list(self.voltage_range_v),
            "displacement_range_mm": list(self.displacement_range_mm),
            "training": self.training,
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2) + "\n"

    def save(self, path: str | Path) -> None:
        atomic_write_text(path, self.to_json())

    @classmethod
    def from_dict(cls, d: dict, source: str = "<dict>") -> "FlannModel":
        if not isinstance(d, dict):
            raise ModelFileError(f"{source}: not a JSON object")
        if d.get("format") != FORMAT:
            raise ModelFileError(
                f"{source}: format is {d.get('format')!r}, expected {FORMAT!r}"
            )
        try:
            weights = tuple(float(w) for w in d["weights"])
            terms = int(d["terms"])
            model = cls(
                weights=weights,
                bias=float(d["bias"]),
                input_offset_v=float(d["input_offset_v"]),
                input_scale_v=float(d["input_scale_v"]),
                voltage_range_v=tuple(float(x) for x in d["voltage_range_v"]),
                displacement_range_mm=tuple(float(x) for x in d["displacement_range_mm"]),
                training=dict(d.get("training", {})),
            )
        except KeyError as exc:
            raise ModelFileError(f"{source}: missing field {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: malformed field ({exc})") from None
        if terms != len(weights) or terms < 1:
            raise ModelFileError(f"{source}: 'terms' is {terms} but there are {len(weights)} weights")
        values = (*weights, model.bias, model.input_offset_v, model.input_scale_v,
                  *model.voltage_range_v, *model.displacement_range_mm)
        if not all(math.isfinite(x) for x in values):
            raise ModelFileError(f"{source}: non-finite number in model")
        if model.input_scale_v == 0:
            raise ModelFileError(f"{source}: input_scale_v must not be 0")
        if len(model.voltage_range_v) != 2 or len(model.displacement_range_mm) != 2:
            raise ModelFileError(f"{source}: ranges must be [lo, hi]")
        return model


def load_model(path: str | Path) -> FlannModel:
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise ModelFileError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ModelFileError(f"{path}: cannot read ({exc.__class__.__name__})") from None
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"{path}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    return FlannModel.from_dict(d, source=str(path))


def model_sha256(path: str | Path) -> str:
    """sha256 of the model file's bytes (stamped into generated VHDL)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


__all__ = ["FORMAT", "FlannModel", "evaluate", "expand", "harmonics", "load_model", "model_sha256",
           "term_kind", "asdict"]
