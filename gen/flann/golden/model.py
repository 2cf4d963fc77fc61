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
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ModelFileError
from ..fileio import atomic_write_text
from ..inputs import number, parse_json, read_text

FORMAT = "flann-model/1"
# The most expansion terms flann fits, stores and builds: the paper's largest (61); more
# adds harmonics no 13..2,000-point sweep resolves and hardware no Spartan-II holds.
MAX_TERMS = 61
# |input_scale_v| bounds: a scale of 1e-320 (subnormal) turns every prediction into NaN
SCALE_V = (1e-9, 1e9)


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


class ModelFile:
    """A model's file, for every model kind: ``to_dict()`` as JSON (two-space indent, final
    newline), written atomically, so every model.json is laid out alike."""

    def to_dict(self) -> dict:
        raise NotImplementedError

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2) + "\n"

    def save(self, path: str | Path) -> None:
        atomic_write_text(path, self.to_json())


@dataclass(frozen=True)
class FlannModel(ModelFile):
    weights: tuple[float, ...]
    bias: float = 0.0
    input_offset_v: float = 0.0
    input_scale_v: float = 1.0
    voltage_range_v: tuple[float, float] = (-1.0, 1.0)
    displacement_range_mm: tuple[float, float] = (-1.0, 1.0)
    training: dict = field(default_factory=dict)
    # a model trained from waveforms: the conditioner whose ratio is its input, as
    # flann.hardware.conditioner.settings.ConditionerSettings writes and reads it (kept as
    # written here: the golden model computes on the ratio and needs none of it)
    conditioner: dict | None = None

    # the model protocol the commands use, whatever the model's inputs (ThermalModel has the same)
    inputs = ("voltage_v",)
    single_curve = True      # its readings are one curve v(x): the shared reading screens them

    @property
    def terms(self) -> int:
        return len(self.weights)

    def predict_at(self, voltage_v, temperature_c=None) -> np.ndarray:
        """:meth:`predict` with the readings' inputs (a one-input model takes no temperature)."""
        return self.predict(voltage_v)

    def saturate(self, displacement_mm) -> tuple[np.ndarray, np.ndarray]:
        """(displacement, flags): a one-input model's output is never beyond its limits once its
        voltage is clamped."""
        x = np.asarray(displacement_mm, dtype=float)
        return x, np.zeros(x.shape, dtype=bool)

    def trained_range(self) -> tuple[str, str]:
        """(the trained range in words, what its readings are called)."""
        lo, hi = sorted(self.voltage_range_v)
        return f"[{lo:g}, {hi:g}] V", "voltages"

    def normalise(self, voltage_v) -> np.ndarray:
        return (np.asarray(voltage_v, dtype=float) - self.input_offset_v) / self.input_scale_v

    def features(self, voltage_v) -> np.ndarray:
        return expand(self.normalise(voltage_v), self.terms)

    def predict(self, voltage_v) -> np.ndarray:
        """Displacement (mm) for voltages (V), float64 (trigonometric sum by recurrence)."""
        return evaluate(self.normalise(voltage_v), self.weights, self.bias)

    def clamp(self, voltage_v, temperature_c=None) -> tuple[np.ndarray, None, np.ndarray]:
        """(voltage, None, outside flags): the voltage clamped to the trained range, as the
        hardware's range check does (the same shape as a two-input model's ``clamp``)."""
        v = np.asarray(voltage_v, dtype=float)
        lo, hi = sorted(self.voltage_range_v)
        return np.clip(v, lo, hi), None, (v < lo) | (v > hi)

    def predict_direct(self, voltage_v) -> np.ndarray:
        """The same sum term by term (one sin and cos per term): the reference for tests."""
        return self.bias + self.features(voltage_v) @ np.asarray(self.weights)

    # -- file -----------------------------------------------------------------
    def to_dict(self) -> dict:
        out = {
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
        if self.conditioner is not None:
            out["conditioner"] = self.conditioner
        return out

    @classmethod
    def from_dict(cls, d: dict, source: str = "<dict>") -> "FlannModel":
        if not isinstance(d, dict):
            raise ModelFileError(f"{source}: not a JSON object")
        if d.get("format") != FORMAT:
            raise ModelFileError(
                f"{source}: format is {d.get('format')!r}, expected {FORMAT!r}"
            )
        try:
            terms = number(d["terms"], "'terms'", source, ModelFileError, integer=True, lo=1, hi=MAX_TERMS)
            weights = d["weights"]
            if not isinstance(weights, list):
                raise ModelFileError(f"{source}: 'weights' must be a list of numbers, got {type(weights).__name__}")
            weights = tuple(number(w, f"weights[{i}]", source, ModelFileError) for i, w in enumerate(weights))
            ranges = {}
            for key in ("voltage_range_v", "displacement_range_mm"):
                r = d[key]
                if not isinstance(r, list) or len(r) != 2:
                    raise ModelFileError(f"{source}: {key} must be [lo, hi]")
                ranges[key] = tuple(number(x, key, source, ModelFileError) for x in r)
                if ranges[key][0] == ranges[key][1]:   # what the model was trained over: never one point
                    raise ModelFileError(f"{source}: {key} = {list(r)} is a single point; a trained model spans a range")
            training = d.get("training", {})
            if not isinstance(training, dict):
                raise ModelFileError(f"{source}: 'training' must be an object")
            conditioner = d.get("conditioner")
            if conditioner is not None and not isinstance(conditioner, dict):
                raise ModelFileError(f"{source}: 'conditioner' must be an object")
            model = cls(
                weights=weights,
                bias=number(d["bias"], "bias", source, ModelFileError),
                input_offset_v=number(d["input_offset_v"], "input_offset_v", source, ModelFileError),
                input_scale_v=number(d["input_scale_v"], "input_scale_v", source, ModelFileError,
                                     lo=-SCALE_V[1], hi=SCALE_V[1], tiny=SCALE_V[0]),
                training=dict(training), conditioner=conditioner, **ranges,
            )
        except KeyError as exc:
            raise ModelFileError(f"{source}: missing field {exc.args[0]!r}") from None
        if terms != len(weights):
            raise ModelFileError(f"{source}: 'terms' is {terms} but there are {len(weights)} weights")
        if model.input_scale_v == 0:
            raise ModelFileError(f"{source}: input_scale_v must not be 0")
        return model


def load_model(path: str | Path) -> FlannModel:
    text = read_text(path, ModelFileError, "a model.json")
    return FlannModel.from_dict(parse_json(text, str(path), ModelFileError), source=str(path))


def model_sha256(path: str | Path) -> str:
    """sha256 of the model file's bytes (stamped into generated VHDL)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def text_sha256(model_json: str) -> str:
    """sha256 of a model's file text (``to_json()``, the bytes :func:`model_sha256` reads back
    once written): the hash a certificate and a design name the model by."""
    return hashlib.sha256(model_json.encode()).hexdigest()


__all__ = ["FORMAT", "MAX_TERMS", "FlannModel", "ModelFile", "evaluate", "expand", "harmonics", "load_model", "model_sha256", "text_sha256",
           "term_kind", "asdict"]
