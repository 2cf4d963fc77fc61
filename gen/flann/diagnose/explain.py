"""One plain sentence per effect: the residual pattern measured on the data, and its physics.

Each sentence is built from the fitted effect's *contribution* (the final model's output
minus the same model with that effect switched off) on the recorded points, so the numbers
quoted are the pattern the effect explains in these recordings.
"""

from __future__ import annotations

import numpy as np


def _mv(v: float) -> str:
    return f"{v * 1e3:.2g} mV"


def _where_max(x: np.ndarray, c: np.ndarray) -> float:
    return float(x[int(np.argmax(np.abs(c)))])


def explain(name: str, params: dict, contrib: np.ndarray, x: np.ndarray,
            direction: np.ndarray | None, temperature: np.ndarray | None,
            y: np.ndarray, slope: np.ndarray, origin: float) -> str:
    """Sentence for effect ``name``; ``contrib`` its contribution (V) at the points ``x``."""
    p = {k: v["value"] for k, v in params.items()}
    big = float(np.max(np.abs(contrib))) if contrib.size else 0.0
    if name == "null_offset":
        return (f"the residual is the same {_mv(p['offset_v'])} at every displacement and in "
                "both directions of travel, unlike anything that scales with the slope or the "
                "output: a constant electrical offset at the null (in-phase null residual or "
                "amplifier/demodulator DC offset).")
    if name == "quadrature_null":
        return (f"the unsigned output never falls to zero: near the null at {origin:.3g} mm the "
                f"recordings sit up to {_mv(big)} above the simulated V, and the gap fades as "
                f"sqrt(y^2+q^2) away from it: a quadrature null residual of "
                f"{_mv(p['quadrature_v'])} (capacitive coupling, phase mismatch) that the "
                "amplitude detector adds in quadrature.")
    if name == "zero_shift":
        return (f"the residual has one sign across the stroke and follows the slope, largest "
                f"({_mv(big)}) where the curve is steepest: the electrical null sits "
                f"{p['shift_mm']:+.3g} mm from the sensor's zero (core or actuator origin "
                "offset).")
    if name == "secondary_imbalance":
        halves = _halves(x, y, contrib, origin)
        near = np.abs(x - origin) <= 0.1 * np.ptp(x)
        far = np.abs(x - origin) >= 0.4 * np.ptp(x)
        shape = ""
        if near.any() and far.any():
            shape = (f" ({_mv(float(np.mean(contrib[near])))} near the null, "
                     f"{_mv(float(np.mean(contrib[far])))} towards the ends, following the sum "
                     "of the secondary voltages)")
        return (f"the residual has the same sign on both halves of the stroke{shape}, so one "
                f"half reads larger than the other{halves}: the two "
                f"secondaries are coupled unequally ({p['imbalance_fraction'] * 100:+.2g} %), "
                "leaving part of their common-mode voltage in the output.")
    if name == "backlash":
        if direction is not None:
            up = contrib[direction > 0]
            dn = contrib[direction < 0]
            dirs = (f" ({_mv(float(np.mean(up)))} on average moving +, "
                    f"{_mv(float(np.mean(dn)))} moving -)") if up.size and dn.size else ""
        else:
            dirs = ""
        return (f"the residual changes sign with the direction of travel{dirs} and is largest "
                f"({_mv(big)}) where the slope is steepest, near {_where_max(x, contrib):.3g} mm: "
                f"lost motion of {p['deadband_mm'] * 1e3:.3g} um in the actuator (the core lags "
                "the commanded position).")
    if name == "thermal_drift":
        trange = ""
        if temperature is not None:
            trange = f" (temperature {np.min(temperature):.3g}..{np.max(temperature):.3g} degC)"
        k = p["coefficient_per_c"]
        drift, note = f"{k * 100:+.3g} %/degC", ""
        seen = _drift_of_output(contrib, y, temperature, p.get("reference_temperature_c"))
        if seen is not None and abs(seen - k) > 0.1 * abs(k):
            # the coefficient scales the fitted simulation, not the shape term or the other
            # effects beside it: the drift of what was recorded is the number to act on
            drift = f"{seen * 100:+.3g} %/degC of the recorded output"
            note = (f"; coefficient_per_c ({k * 100:+.3g} %/degC) is relative to the fitted "
                    "simulation alone")
        return (f"the residual follows the recorded temperature{trange} rather than the "
                f"displacement, scaling with the output itself (up to {_mv(big)} where the "
                f"output is largest): the sensitivity drifts by {drift} (primary copper "
                f"resistance, core permeability){note}.")
    if name == "adc_clipping":
        rails = " and ".join(f"{p[k]:+.4g} V" for k in ("rail_high_v", "rail_low_v") if k in p)
        if "readings_on_rail" in p:
            n_on = int(p["readings_on_rail"])
            return (f"{n_on} readings at the end(s) of the stroke sit on a flat level "
                    f"({rails}) whose scatter is far below the noise elsewhere: the "
                    "converter or amplifier saturates at its rail(s).")
        n_clip = int(np.sum(np.abs(contrib) > 1e-9))
        return (f"beyond the natural roll-off the recordings stop at a flat {rails} while "
                f"the smooth curve keeps going ({n_clip} points, up to {_mv(big)}): the "
                "converter or amplifier saturates at its rail(s).")
    if name == "leadscrew_periodic":
        return (f"the residual oscillates with a period of {p['period_mm']:.4g} mm of "
                f"displacement, its amplitude following the slope (up to {_mv(big)}): a "
                f"periodic position error of {abs(p['amplitude_mm']) * 1e3:.3g} um in the "
                "actuator's lead screw (pitch, eccentricity).")
    return f"{name}: residual pattern up to {_mv(big)} explained by this effect."


def _drift_of_output(contrib, y, temperature, t_ref) -> float | None:
    """Relative drift per degC of the recorded output that ``contrib`` amounts to (least
    squares of contrib on y (T - t_ref)), or None without temperatures."""
    if temperature is None or t_ref is None:
        return None
    u = y * (np.asarray(temperature, float) - t_ref)
    den = float(u @ u)
    return float(contrib @ u) / den if den > 0 else None


def _halves(x, y, contrib, origin) -> str:
    neg = x < origin
    pos = x > origin
    if not (neg.any() and pos.any()):
        return ""
    # relative change of |output| on each half
    rn = float(np.mean(contrib[neg] * np.sign(y[neg])))
    rp = float(np.mean(contrib[pos] * np.sign(y[pos])))
    return (f" (the magnitude of the output changes by {rp * 1e3:+.2g} mV on the + half and "
            f"{rn * 1e3:+.2g} mV on the - half on average)")
