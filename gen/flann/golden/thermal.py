"""The two-input FLANN: displacement from voltage and temperature, ``x(v, T)``, and its file.

The expansion is the one-input model's trigonometric expansion of v (:func:`.model.expand`,
the same term order) times a low-order power series of the normalised temperature, after
the first-harmonic products (t_n v, t_n^2 v) and the temperature's own terms (t_n, t_n^2)
have brought the voltage back to the mid temperature's gain and null::

    t_n = (T - temperature_offset_c) / temperature_scale_c        (calibration range -> [-1, 1])
    v'  = v (1 + sum_k input_gain_t[k] t_n^(k+1)) + sum_k input_offset_t_v[k] t_n^(k+1)
    v_n = (v' - input_offset_v) / input_scale_v
    f_j(v) = bias[j] + sum_{i < terms[j]} weights[j][i] phi_i(v_n)   (a one-input FLANN per order)
    x_mm = f_0(v) + t_n (f_1(v) + t_n (f_2(v) + ...))                (Horner in t_n)

so order 0 is an ordinary FLANN at the mid temperature, and the cross terms
``t_n^j phi_i(v_n)`` of order j use only the first ``terms[j]`` terms of the expansion (the
cheapest that reach the accuracy, see :mod:`.thermal_train`).  Correcting the gain and null
on the input first matters at the ends of the stroke: where the curve rolls off, x(v) is
steep and curved, and a gain change of 1 % moves it by several % of the stroke, which a
power series in T after the expansion only reaches with orders a 3-temperature
calibration cannot determine.  In hardware the input correction is 2 multiplies by the
temperature and one by v; the expansion is the same serial multiply-accumulate run once
per order, each result folded in by one multiply by the temperature.

``model.json`` of a two-input model: format ``flann-thermal-model/1`` and ``"inputs":
["voltage_v", "temperature_c"]``; one-input models (``flann-model/1``) are unchanged.
:func:`load_any_model` reads either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ModelFileError
from ..inputs import number, parse_json, read_text
from ..recordings.checks import TEMPERATURE_RESOLUTION_C, temperature_groups
from .model import MAX_TERMS, FlannModel, ModelFile, evaluate, expand

FORMAT = "flann-thermal-model/1"
INPUTS = ("voltage_v", "temperature_c")
# the output saturates this share of the calibrated displacement span beyond each end of it
# (about the fit's own error at the stroke's ends)
OUTPUT_MARGIN = 0.01


def power_columns(t_n, orders: int) -> np.ndarray:
    """[1, t_n, t_n^2, ...]: shape (len(t_n), orders)."""
    t = np.atleast_1d(np.asarray(t_n, dtype=float))
    return t[:, None] ** np.arange(orders)[None, :]


def thermal_design(v_n, t_n, terms: tuple[int, ...]) -> np.ndarray:
    """Design matrix, columns order by order: ``t_n^j [1, phi_0 .. phi_{terms[j]-1}]``."""
    v = np.atleast_1d(np.asarray(v_n, dtype=float))
    powers = power_columns(t_n, len(terms))
    phi = expand(v, max(max(terms), 1))
    cols = []
    for j, n in enumerate(terms):
        cols.append(powers[:, j:j + 1])
        if n:
            cols.append(powers[:, j:j + 1] * phi[:, :n])
    return np.hstack(cols)


def corrected_voltage(voltage_v, t_n, gain_t, offset_t_v) -> np.ndarray:
    """``v (1 + sum_k gain_t[k] t_n^(k+1)) + sum_k offset_t_v[k] t_n^(k+1)``."""
    v = np.asarray(voltage_v, dtype=float)
    t = np.asarray(t_n, dtype=float)
    gain, offset, tk = np.ones(v.shape), np.zeros(v.shape), np.ones(v.shape)
    for k in range(max(len(gain_t), len(offset_t_v))):
        tk = tk * t
        if k < len(gain_t):
            gain = gain + gain_t[k] * tk
        if k < len(offset_t_v):
            offset = offset + offset_t_v[k] * tk
    return v * gain + offset


@dataclass(frozen=True)
class ThermalModel(ModelFile):
    weights: tuple[tuple[float, ...], ...]   # per temperature order j
    bias: tuple[float, ...]                  # per temperature order j
    input_offset_v: float = 0.0
    input_scale_v: float = 1.0
    temperature_offset_c: float = 0.0
    temperature_scale_c: float = 1.0
    input_gain_t: tuple[float, ...] = ()       # v' = v (1 + g1 t_n + g2 t_n^2) + ...
    input_offset_t_v: tuple[float, ...] = ()   # ... + o1 t_n + o2 t_n^2   (V)
    voltage_range_v: tuple[float, float] = (-1.0, 1.0)
    temperature_range_c: tuple[float, float] = (0.0, 1.0)
    displacement_range_mm: tuple[float, float] = (-1.0, 1.0)
    training: dict = field(default_factory=dict)
    # trained from waveforms: the conditioner whose ratio is its voltage input, as FlannModel keeps it
    conditioner: dict | None = None

    inputs = INPUTS

    @property
    def terms(self) -> tuple[int, ...]:
        """Expansion terms of each temperature order (the bias of each order not counted)."""
        return tuple(len(w) for w in self.weights)

    @property
    def orders(self) -> int:
        return len(self.bias)

    @property
    def coefficients(self) -> int:
        """Weights and biases: the words of the weight memory."""
        return sum(self.terms) + self.orders

    def normalise(self, voltage_v, temperature_c) -> tuple[np.ndarray, np.ndarray]:
        """(v_n, t_n): the corrected, normalised voltage and the normalised temperature."""
        v = np.asarray(voltage_v, dtype=float)
        t_n = (np.broadcast_to(np.asarray(temperature_c, dtype=float), v.shape)
               - self.temperature_offset_c) / self.temperature_scale_c
        v_c = corrected_voltage(v, t_n, self.input_gain_t, self.input_offset_t_v)
        return (v_c - self.input_offset_v) / self.input_scale_v, t_n

    def order_outputs(self, v_n) -> list[np.ndarray]:
        """f_j of every temperature order j (mm) at normalised voltages."""
        return [evaluate(v_n, w, b) if w else np.full(np.shape(v_n), b, dtype=float)
                for w, b in zip(self.weights, self.bias)]

    def predict(self, voltage_v, temperature_c) -> np.ndarray:
        """Displacement (mm) at voltages (V) and temperatures (degC), float64."""
        v_n, t_n = self.normalise(voltage_v, temperature_c)
        parts = self.order_outputs(v_n)
        acc = parts[-1]
        for part in reversed(parts[:-1]):
            acc = acc * t_n + part
        return acc

    inputs = INPUTS
    single_curve = False     # a curve per temperature: the one-curve reading does not screen them

    def predict_at(self, voltage_v, temperature_c=None) -> np.ndarray:
        return self.predict(voltage_v, temperature_c)

    def trained_range(self) -> tuple[str, str]:
        vlo, vhi = sorted(self.voltage_range_v)
        tlo, thi = sorted(self.temperature_range_c)
        return f"[{vlo:g}, {vhi:g}] V or calibrated temperatures [{tlo:g}, {thi:g}] degC", "readings"

    def predict_direct(self, voltage_v, temperature_c) -> np.ndarray:
        """The same sum term by term from the design matrix: the reference for tests."""
        v_n, t_n = self.normalise(voltage_v, temperature_c)
        coef = np.concatenate([[b, *w] for w, b in zip(self.weights, self.bias)])
        return thermal_design(v_n, t_n, self.terms) @ coef

    def output_limits_mm(self) -> tuple[float, float]:
        """(lo, hi) mm: the calibrated displacement range widened by ``OUTPUT_MARGIN`` of its span.
        The clamp of voltage and temperature is one rectangle, but at each temperature the sensor
        covers only part of the voltages: a pair it never gives evaluates the polynomial in t_n
        outside the calibration (45 mm on a +-25 mm sensor), so the output saturates here."""
        lo, hi = sorted(float(x) for x in self.displacement_range_mm)
        margin = OUTPUT_MARGIN * (hi - lo)
        return lo - margin, hi + margin

    def saturate(self, displacement_mm) -> tuple[np.ndarray, np.ndarray]:
        """(displacement held within :meth:`output_limits_mm`, flags where it was)."""
        x = np.asarray(displacement_mm, dtype=float)
        lo, hi = self.output_limits_mm()
        return np.clip(x, lo, hi), (x < lo) | (x > hi)

    def clamp(self, voltage_v, temperature_c) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(voltage, temperature, outside flags): both clamped to the calibrated ranges, as
        the hardware's range checks do."""
        v = np.asarray(voltage_v, dtype=float)
        t = np.broadcast_to(np.asarray(temperature_c, dtype=float), v.shape)
        vlo, vhi = sorted(self.voltage_range_v)
        tlo, thi = sorted(self.temperature_range_c)
        outside = (v < vlo) | (v > vhi) | (t < tlo) | (t > thi)
        return np.clip(v, vlo, vhi), np.clip(t, tlo, thi), outside

    # -- file -----------------------------------------------------------------
    def to_dict(self) -> dict:
        out = {
            "format": FORMAT,
            "inputs": list(INPUTS),
            "terms": list(self.terms),
            "input_offset_v": self.input_offset_v,
            "input_scale_v": self.input_scale_v,
            "temperature_offset_c": self.temperature_offset_c,
            "temperature_scale_c": self.temperature_scale_c,
            "input_gain_t": list(self.input_gain_t),
            "input_offset_t_v": list(self.input_offset_t_v),
            "bias": list(self.bias),
            "weights": [list(w) for w in self.weights],
            "voltage_range_v": list(self.voltage_range_v),
            "temperature_range_c": list(self.temperature_range_c),
            "displacement_range_mm": list(self.displacement_range_mm),
            "training": self.training,
        }
        if self.conditioner is not None:
            out["conditioner"] = self.conditioner
        return out

    @classmethod
    def from_dict(cls, d: dict, source: str = "<dict>") -> "ThermalModel":
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            raise ModelFileError(f"{source}: format is {d.get('format') if isinstance(d, dict) else None!r}, "
                                 f"expected {FORMAT!r}")
        if d.get("inputs") != list(INPUTS):
            raise ModelFileError(f"{source}: inputs must be {list(INPUTS)}, got {d.get('inputs')!r}")
        def num(value, label, **kw):
            return number(value, label, source, ModelFileError, **kw)

        def nums(key, **kw):
            values = d[key]
            if not isinstance(values, list):
                raise ModelFileError(f"{source}: {key} must be a list of numbers")
            return tuple(num(x, f"{key}[{i}]", **kw) for i, x in enumerate(values))

        try:
            if not isinstance(d["weights"], list) or not all(isinstance(ws, list) for ws in d["weights"]):
                raise ModelFileError(f"{source}: weights must be a list of lists of numbers")
            weights = tuple(tuple(num(w, f"weights[{k}][{i}]") for i, w in enumerate(ws))
                            for k, ws in enumerate(d["weights"]))
            bias = nums("bias")
            terms = nums("terms", integer=True, lo=0, hi=MAX_TERMS)
            conditioner = d.get("conditioner")
            if conditioner is not None and not isinstance(conditioner, dict):
                raise ModelFileError(f"{source}: 'conditioner' must be an object")
            model = cls(
                weights=weights, bias=bias,
                input_offset_v=num(d["input_offset_v"], "input_offset_v"),
                input_scale_v=num(d["input_scale_v"], "input_scale_v", tiny=1e-9),
                temperature_offset_c=num(d["temperature_offset_c"], "temperature_offset_c"),
                temperature_scale_c=num(d["temperature_scale_c"], "temperature_scale_c", tiny=1e-9),
                input_gain_t=nums("input_gain_t"),
                input_offset_t_v=nums("input_offset_t_v"),
                voltage_range_v=nums("voltage_range_v"),
                temperature_range_c=nums("temperature_range_c"),
                displacement_range_mm=nums("displacement_range_mm"),
                training=dict(d.get("training", {})) if isinstance(d.get("training", {}), dict) else {},
                conditioner=conditioner,
            )
        except KeyError as exc:
            raise ModelFileError(f"{source}: missing field {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ModelFileError(f"{source}: malformed field ({exc})") from None
        if not bias or len(bias) != len(weights) or terms != model.terms:
            raise ModelFileError(f"{source}: 'terms' {list(terms)} does not match the weights "
                                 f"{[len(w) for w in weights]} and {len(bias)} biases")
        values = (*bias, *(w for ws in weights for w in ws), *model.input_gain_t,
                  *model.input_offset_t_v, model.input_offset_v, model.input_scale_v,
                  model.temperature_offset_c, model.temperature_scale_c, *model.voltage_range_v,
                  *model.temperature_range_c, *model.displacement_range_mm)
        if not all(math.isfinite(x) for x in values):
            raise ModelFileError(f"{source}: non-finite number in model")
        if model.input_scale_v == 0 or model.temperature_scale_c == 0:
            raise ModelFileError(f"{source}: input_scale_v and temperature_scale_c must not be 0")
        if any(len(r) != 2 for r in (model.voltage_range_v, model.temperature_range_c,
                                     model.displacement_range_mm)):
            raise ModelFileError(f"{source}: ranges must be [lo, hi]")
        return model


def load_any_model(path: str | Path) -> FlannModel | ThermalModel:
    """A one-input model (:func:`.model.load_model`) or a two-input one, by its format."""
    d = parse_json(read_text(path, ModelFileError, "a model.json"), str(path), ModelFileError)
    if isinstance(d, dict) and d.get("format") == FORMAT:
        return ThermalModel.from_dict(d, source=str(path))
    return FlannModel.from_dict(d, source=str(path))


def is_thermal(model) -> bool:
    return isinstance(model, ThermalModel)


__all__ = ["FORMAT", "INPUTS", "corrected_voltage", "TEMPERATURE_RESOLUTION_C", "ThermalModel", "is_thermal",
           "load_any_model", "power_columns", "temperature_groups", "thermal_design"]
