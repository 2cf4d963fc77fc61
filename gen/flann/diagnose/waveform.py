"""Diagnosis of a waveform recording: the effects a DC output curve confounds, told apart.

A float lock-in per dwell (the samples at one ``displacement_mm``) against the excitation
gives each secondary's phasor; rotated onto the detector's reference (the phase of A - B's
slope at the null) they give the in-phase and quadrature amplitudes ``A_I, A_Q, B_I, B_Q``.
From them, each against a noise-based threshold (``Z_FOUND`` standard errors):

* imbalance against zero shift: with ``A(x) = (1 + e/2) f(x - s)`` and ``B(x) = (1 - e/2)
  f(-(x - s))``, the mirrored pair ``A_I(u) - B_I(-u) = e f(u) - 2 s f'(u)`` (to first order)
  is linear in ``e`` and ``s``: one least-squares fit separates them; a shift it finds is
  refitted about (both curves translated by it) until none is left, so it is exact;
* quadrature null: the quadrature of A - B at the null (a demodulator offset cannot be in
  the secondaries: it is made after them);
* phase shift: the reference phase against the excitation, against the sensor model's;
* excitation drift: the excitation amplitude over time (else the secondaries' sum at
  repeated positions), and the ratio (A - B)/(A + B), which cancels it.

Public API: :func:`is_waveform_csv` (path), :func:`diagnose_waveforms` (Waveforms, sensor=None)
-> :class:`WaveDiagnosis`; :func:`wave_to_json`, :func:`format_wave_text`, :func:`plot_wave`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import FlannError
from ..fileio import atomic_save_figure
from ..physics.lvdt import reference_phase_rad
from ..recordings.waveform import carrier_hz, is_waveform_csv
from ..physics.sensor import default_sensor

Z_FOUND = 5.0                  # standard errors for a figure to name an effect
# a sensor description's phase is good to about a degree (winding resistances and the core's
# eddy currents are known to a few %): a smaller difference is not a phase shift
PHASE_TOLERANCE_DEG = 1.0
# an excitation that moves by less than this over the run moves a 16-bit reading by < 1 LSB
DRIFT_FLOOR_PCT = 0.01
SETTLE_FRACTION = 0.1          # the start of each dwell skipped: the core and filters settle
MIN_PERIODS = 2                # carrier periods a dwell needs after settling
MIN_POSITIONS = 5              # distinct positions the evidence needs
SHIFT_ITERATIONS = 20          # refits about the shift found (each leaves a fraction of the last)
SHIFT_CONVERGED = 0.01         # a shift left below this part of its standard error is none

_EXPLAIN = {
    "secondary_imbalance": "the secondaries' sensitivities differ (turns or coupling mismatch)",
    "zero_shift": "the core's null is not at zero displacement",
    "quadrature_null": "a quadrature residual at the null (capacitive coupling, phase mismatch "
                       "between the secondaries)",
    "phase_shift": "the secondaries' phase against the excitation differs from the sensor "
                   "model's (loaded secondaries, source resistance, eddy currents)",
    "excitation_drift": "the excitation amplitude changes over the run",
}


@dataclass(frozen=True)
class Dwell:
    """One dwell: phasors (peak volts) relative to the excitation's phase (to the secondaries'
    sum's when no excitation was recorded), before rotation onto the reference."""

    position_mm: float
    time_s: float          # mid-time
    exc: complex | None
    a: complex
    b: complex
    noise_v: float         # rms of what the lock-in's fit leaves on the secondaries
    samples: int


@dataclass(frozen=True)
class Evidence:
    """One figure and its verdict: ``found`` when ``|value| > threshold``; ``value`` None and
    ``reason`` set when the recording cannot give it."""

    name: str              # the effect it speaks for
    figure: str            # what was measured
    value: float | None
    stderr: float | None
    unit: str
    threshold: float | None
    found: bool
    reason: str = ""


@dataclass(frozen=True)
class WaveEffect:
    name: str
    explanation: str
    params: dict           # name -> (value, stderr, unit)


@dataclass(frozen=True)
class WaveDiagnosis:
    source: str
    carrier_hz: float
    sample_rate_hz: float
    reference_deg: float           # detector reference phase against the excitation
    noise_v: float
    dwells: tuple[Dwell, ...]
    a_i: np.ndarray                # per dwell, on the reference
    a_q: np.ndarray
    b_i: np.ndarray
    b_q: np.ndarray
    null_mm: float | None          # where A_I = B_I
    phase_a_deg: float             # each secondary's phase (median where it is above half its peak)
    phase_b_deg: float
    evidence: tuple[Evidence, ...]
    effects: tuple[WaveEffect, ...]
    not_in_waveforms: tuple[tuple[str, str], ...]
    notes: tuple[str, ...] = field(default_factory=tuple)


# -- the lock-in --------------------------------------------------------------------------

def _lockin(t: np.ndarray, w_rad_s: float, *chans: np.ndarray) -> tuple[list[complex], np.ndarray]:
    """Peak phasors ``P`` (``v = Re(P e^{jwt})``) of the carrier on each channel, by least
    squares with a DC and a third-harmonic term; and the rms each fit leaves."""
    tc = t - t[0]
    m = np.column_stack([np.ones_like(tc), np.cos(w_rad_s * tc), np.sin(w_rad_s * tc),
                         np.cos(3 * w_rad_s * tc), np.sin(3 * w_rad_s * tc)])
    ys = np.column_stack(chans)
    coef, *_ = np.linalg.lstsq(m, ys, rcond=None)
    rest = ys - m @ coef
    rot = np.exp(1j * w_rad_s * t[0])     # phasors on the common time origin
    return ([complex(coef[1, i] - 1j * coef[2, i]) / rot for i in range(ys.shape[1])],
            np.sqrt(np.mean(rest ** 2, axis=0) * m.shape[0] / max(1, m.shape[0] - m.shape[1])))


def _dwells(wave, fc: float) -> list[Dwell]:
    x, t, fs = wave.displacement_mm, wave.time_s, wave.sample_rate_hz
    edges = np.flatnonzero(np.diff(x) != 0) + 1
    w = 2 * math.pi * fc
    out = []
    for seg in np.split(np.arange(x.size), edges):
        seg = seg[int(SETTLE_FRACTION * seg.size):]
        if seg.size < MIN_PERIODS * fs / fc:
            continue
        chans = [wave.sec_a_v[seg], wave.sec_b_v[seg]] + ([wave.exc_v[seg]] if wave.exc_v is not None else [])
        ph, rms = _lockin(t[seg], w, *chans)
        a, b = ph[0], ph[1]
        ref = ph[2] if wave.exc_v is not None else a + b
        unit = ref / abs(ref) if abs(ref) > 0 else 1.0
        out.append(Dwell(position_mm=float(x[seg[0]]), time_s=float(np.mean(t[seg])),
                         exc=ph[2] if wave.exc_v is not None else None, a=a / unit, b=b / unit,
                         noise_v=float(np.sqrt(0.5 * (rms[0] ** 2 + rms[1] ** 2))), samples=int(seg.size)))
    return out


# -- evidence ------------------------------------------------------------------------------

def _by_position(pos: np.ndarray, *vals: np.ndarray):
    """Distinct positions (sorted), the mean of each value there, and the dwells at each."""
    keys = np.round(pos, 9)
    u, inv, counts = np.unique(keys, return_inverse=True, return_counts=True)
    means = [np.bincount(inv, weights=v, minlength=u.size) / counts for v in vals]
    return u, means, counts


def _fit(X: np.ndarray, y: np.ndarray, sigma_y: np.ndarray):
    """Weighted least squares: coefficients and standard errors, the larger of the noise's
    and the residuals' (a misfit of the model widens them rather than naming an effect)."""
    wts = 1.0 / sigma_y
    coef, *_ = np.linalg.lstsq(X * wts[:, None], y * wts, rcond=None)
    cov = np.linalg.pinv((X * wts[:, None]).T @ (X * wts[:, None]))
    dof = y.size - X.shape[1]
    chi2 = float(np.sum(((y - X @ coef) * wts) ** 2) / dof) if dof > 0 else 1.0
    return coef, np.sqrt(np.diag(cov) * max(1.0, chi2))


def _pair_fit(u, ai, bi, sig, pos, shift):
    """One first-order fit about ``shift``: both measured curves translated by ``shift``
    (cubic interpolation), paired about the translated origin, ``A(v + shift) - B(shift - v)
    = e f(v) - 2 ds f'(v)``; the pairs whose points fall outside the travel are left out."""
    lo, hi = float(u[0]), float(u[-1])
    v = pos[(pos + shift >= lo - 1e-9) & (pos + shift <= hi + 1e-9)
            & (shift - pos >= lo - 1e-9) & (shift - pos <= hi + 1e-9)]
    if v.size < MIN_POSITIONS:
        return None
    v = np.sort(v)
    if shift == 0.0:           # the mirrored pairs themselves: no interpolation
        at = {round(float(p), 6): i for i, p in enumerate(u)}
        ia, ib = np.array([at[round(float(p), 6)] for p in v]), np.array([at[round(-float(p), 6)] for p in v])
        a, b, sa, sb = ai[ia], bi[ib], sig[ia], sig[ib]
    else:
        a, b = CubicSpline(u, ai)(v + shift), CubicSpline(u, bi)(shift - v)
        sa, sb = np.interp(v + shift, u, sig), np.interp(shift - v, u, sig)
    f = 0.5 * (a + b)
    fp = np.gradient(f, v)
    return _fit(np.column_stack([f, -2 * fp]), a - b, np.sqrt(sa ** 2 + sb ** 2))


def _imbalance_shift(u, ai, bi, sig) -> tuple[Evidence, Evidence, dict]:
    """``A_I(u) - B_I(-u) = e f(u) - 2 s f'(u)`` over the mirrored positions, to first order
    in ``s``.  A shift beyond its standard error is then refitted about, the measured curves
    translated by it, until the shift left is a small part of its standard error: the first
    order's error vanishes with the shift left, so the shift and the imbalance are the exact
    ones (a first-order misfit, on secondaries whose amplitude is nearly exponential, is
    otherwise taken for an imbalance: there a scale is nearly a translation)."""
    idx = {round(float(p), 6): i for i, p in enumerate(u)}
    mirrored = np.array([p for p in u if round(-float(p), 6) in idx])
    if mirrored.size < MIN_POSITIONS:
        why = (f"{mirrored.size} position(s) mirrored about 0 mm; the fit needs {MIN_POSITIONS} "
               "(record a travel symmetric about 0)")
        return (Evidence("secondary_imbalance", "sensitivity imbalance e", None, None, "1", None, False, why),
                Evidence("zero_shift", "null shift s (core centred at)", None, None, "mm", None, False, why), {})
    (e, ds), (se, ss) = _pair_fit(u, ai, bi, sig, mirrored, 0.0)
    s = float(ds)
    # a shift within its standard error leaves a first-order error below the noise: the
    # mirrored pairs, which keep the travel's ends, stand
    for _ in range(SHIFT_ITERATIONS if abs(s) > ss else 0):
        hit = _pair_fit(u, ai, bi, sig, mirrored, s)
        if hit is None:        # the shift leaves too few pairs in the travel: keep the last fit
            break
        (e, ds), (se, ss) = hit
        s += float(ds)
        if abs(ds) < SHIFT_CONVERGED * ss:
            break
    ev_e = Evidence("secondary_imbalance", "sensitivity imbalance e (A over B)", float(e), float(se),
                    "1", Z_FOUND * float(se), abs(e) > Z_FOUND * se)
    ev_s = Evidence("zero_shift", "null shift s (core centred at)", float(s), float(ss), "mm",
                    Z_FOUND * float(ss), abs(s) > Z_FOUND * ss)
    ratio = (1 + e / 2) / (1 - e / 2)
    return ev_e, ev_s, {"imbalance_fraction": (float(e), float(se), "1"),
                        "sensitivity_ratio": (float(ratio), float(se * ratio / (1 - e * e / 4)), "1"),
                        "shift_mm": (float(s), float(ss), "mm")}


def _null_position(u, di) -> float | None:
    k = np.flatnonzero(np.sign(di[:-1]) != np.sign(di[1:]))
    if di.size and np.any(di == 0):
        return float(u[np.flatnonzero(di == 0)[0]])
    if not k.size:
        return None
    k = int(k[np.argmin(np.abs(u[k]))])
    return float(u[k] - di[k] * (u[k + 1] - u[k]) / (di[k + 1] - di[k]))


def _quadrature(u, dq, sig, null_mm, gain) -> tuple[Evidence, dict]:
    if null_mm is None:
        return Evidence("quadrature_null", "quadrature of A - B at the null", None, None, "V", None,
                        False, "A - B does not cross zero in the recorded travel"), {}
    near = np.argsort(np.abs(u - null_mm))[:3]
    if near.size < 2:
        return Evidence("quadrature_null", "quadrature of A - B at the null", None, None, "V", None,
                        False, "fewer than 2 positions"), {}
    X = np.column_stack([np.ones(near.size), u[near] - null_mm])
    (q, _slope), (sq, _) = _fit(X, dq[near], np.sqrt(2.0) * sig[near])
    ev = Evidence("quadrature_null", "quadrature of A - B at the null", float(q), float(sq), "V",
                  Z_FOUND * float(sq), abs(q) > Z_FOUND * sq)
    # output-referred as the DC diagnosis reports it: the demodulator's gain on A - B
    return ev, {"quadrature_v": (float(abs(q) * gain), float(sq * gain), "V")}


def _drift_within_positions(pos, t, v):
    """Relative change per second of ``v`` among dwells at the same position: (k, stderr), or
    None when no position was recorded twice."""
    keys = np.round(pos, 9)
    rows_r, rows_t = [], []
    for key in np.unique(keys):
        m = keys == key
        if m.sum() < 2 or abs(np.mean(v[m])) == 0:
            continue
        rows_r.append(v[m] / np.mean(v[m]) - 1.0)
        rows_t.append(t[m] - np.mean(t[m]))
    if not rows_r:
        return None
    r, tt = np.concatenate(rows_r), np.concatenate(rows_t)
    den = float(np.sum(tt ** 2))
    if den == 0:
        return None
    k = float(np.sum(r * tt) / den)
    dof = max(1, r.size - len(rows_r) - 1)
    return k, math.sqrt(float(np.sum((r - k * tt) ** 2)) / dof / den)


def _excitation(dw, t, pos, ai, bi, t0, span) -> tuple[list[Evidence], dict]:
    """Changes over the recording (``span`` seconds from ``t0``), in % of the start's value."""

    def pct(k, sk):   # k: relative change per second about the dwells' mean time
        at_start = 1.0 + k * (t0 - float(np.mean(t)))
        return 100 * k * span / at_start, 100 * sk * span / abs(at_start)

    if t.size < 2:
        why = "one dwell: no time to drift in"
        return [Evidence("excitation_drift", "excitation amplitude change over the run", None, None,
                         "%", None, False, why)], {}
    if dw[0].exc is not None:
        e = np.array([abs(d.exc) for d in dw])
        X = np.column_stack([np.ones_like(t), t - t.mean()])
        resid_sig = max(float(np.std(e)) * 1e-9, 1e-12)
        (e0, k), (_, sk) = _fit(X, e, np.full(t.size, resid_sig))
        drift, sdrift = pct(k / e0, sk / e0)
        figure = "excitation amplitude change over the run"
    else:
        hit = _drift_within_positions(pos, t, ai + bi)
        if hit is None:
            return [Evidence("excitation_drift", "secondaries' sum change over the run", None, None, "%",
                             None, False, "no excitation recorded and no position recorded twice")], {}
        drift, sdrift = pct(*hit)
        figure = "secondaries' sum change over the run (no excitation recorded)"
    threshold = max(Z_FOUND * sdrift, DRIFT_FLOOR_PCT)
    out = [Evidence("excitation_drift", figure, float(drift), float(sdrift), "%", threshold,
                    abs(drift) > threshold)]
    # the ratio's own change among repeated positions, where A - B is not near zero
    di, ratio = ai - bi, (ai - bi) / (ai + bi)
    strong = np.abs(di) > 0.2 * np.max(np.abs(di))
    hit_d = _drift_within_positions(pos[strong], t[strong], di[strong])
    hit_r = _drift_within_positions(pos[strong], t[strong], ratio[strong])
    for name, hit in (("A - B change over the run", hit_d), ("ratio (A - B)/(A + B) change over the run", hit_r)):
        if hit is None:
            out.append(Evidence("excitation_drift", name, None, None, "%", None, False,
                                "no position recorded twice"))
        else:
            v, sd = pct(*hit)
            thr = max(Z_FOUND * sd, DRIFT_FLOOR_PCT)
            out.append(Evidence("excitation_drift", name, v, sd, "%", thr, abs(v) > thr))
    return out, {"drift_pct": (float(drift), float(sdrift), "%")}


def diagnose_waveforms(wave, sensor=None) -> WaveDiagnosis:
    """Lock in on each dwell of ``wave`` and weigh the evidence (module docstring).  ``sensor``
    gives the phase to compare with (without it the phase is not judged) and the demodulator
    gain that refers the quadrature to the output (default: the seed paper's LVDT's)."""
    fs = wave.sample_rate_hz
    fc = carrier_hz(wave)
    if not (0 < fc < fs / 2):
        raise FlannError(f"{wave.source}: no carrier found in the waveforms")
    dw = _dwells(wave, fc)
    pos = np.array([d.position_mm for d in dw])
    if np.unique(np.round(pos, 9)).size < MIN_POSITIONS:
        raise FlannError(f"{wave.source}: {np.unique(np.round(pos, 9)).size} dwell position(s) of at "
                         f"least {MIN_PERIODS} carrier periods; the diagnosis needs {MIN_POSITIONS} "
                         "(record with a stepped trajectory, e.g. flann simulate --waveforms "
                         "--trajectory steps:0.01)")
    t = np.array([d.time_s for d in dw])
    a = np.array([d.a for d in dw])
    b = np.array([d.b for d in dw])
    noise = float(np.sqrt(np.mean([d.noise_v ** 2 for d in dw])))
    # per-dwell standard error of a lock-in amplitude: white noise over n samples
    sig_dw = np.array([max(d.noise_v, 1e-9) * math.sqrt(2.0 / d.samples) for d in dw])

    # the reference: the phase of A - B's slope where |A - B| is within half its largest
    dd = a - b
    near = np.abs(dd) <= 0.5 * np.max(np.abs(dd))
    if np.unique(np.round(pos[near], 9)).size < 2:
        near = np.ones_like(near)
    X = np.column_stack([np.ones(near.sum()), pos[near]])
    cr, *_ = np.linalg.lstsq(X, dd[near].real, rcond=None)
    ci, *_ = np.linalg.lstsq(X, dd[near].imag, rcond=None)
    slope = complex(cr[1], ci[1])
    phi = float(np.angle(slope))
    rot = np.exp(-1j * phi)
    ar, br = a * rot, b * rot

    u, (ai, aq, bi, bq), counts = _by_position(pos, ar.real, ar.imag, br.real, br.imag)
    sig_u = _by_position(pos, sig_dw)[1][0] / np.sqrt(counts)
    null_mm = _null_position(u, ai - bi)

    s = (sensor or default_sensor()).replace(effects={}, excitation_frequency_hz=fc)
    ev_e, ev_s, params = _imbalance_shift(u, ai, bi, sig_u)
    ev_q, q_params = _quadrature(u, aq - bq, sig_u, null_mm, s.demodulator_gain_ratio)
    params.update(q_params)
    evidence = [ev_e, ev_s, ev_q]

    # phase: the slope's standard error across its direction
    sel = pos[near]
    s_slope = float(np.sqrt(2.0) * np.mean(sig_dw[near]) / math.sqrt(max(1e-30, np.sum((sel - sel.mean()) ** 2))))
    if dw[0].exc is None or sensor is None:
        why = ("no excitation recorded: the phases are relative to the secondaries' sum" if dw[0].exc is None
               else "no sensor description (--sensor): the phase this sensor should have is unknown")
        evidence.append(Evidence("phase_shift", "reference phase against the sensor model's", None, None,
                                 "deg", None, False, why))
    else:
        dphi = math.degrees(math.remainder(phi - reference_phase_rad(s), 2 * math.pi))
        sphi = math.degrees(s_slope / abs(slope))
        thr = max(Z_FOUND * sphi, PHASE_TOLERANCE_DEG)
        evidence.append(Evidence("phase_shift", f"reference phase {math.degrees(phi):.3f} deg against the "
                                 f"sensor model's ({s.name})", dphi, sphi, "deg", thr, abs(dphi) > thr))
        params["phase_deg"] = (dphi, sphi, "deg")
    ex_ev, ex_params = _excitation(dw, t, pos, ar.real, br.real, float(wave.time_s[0]),
                                    float(wave.time_s[-1] - wave.time_s[0]))
    evidence += ex_ev
    params.update(ex_params)

    keys = {"secondary_imbalance": ("imbalance_fraction", "sensitivity_ratio"), "zero_shift": ("shift_mm",),
            "quadrature_null": ("quadrature_v",), "phase_shift": ("phase_deg",),
            "excitation_drift": ("drift_pct",)}
    verdict: dict[str, bool] = {}
    for ev in evidence:   # an effect's first figure decides; the others show how it acts
        verdict.setdefault(ev.name, ev.found)
    effects = tuple(WaveEffect(name, _EXPLAIN[name], {k: params[k] for k in keys[name] if k in params})
                    for name in keys if verdict.get(name))
    absent = (("null_offset", "made by a demodulator after the secondaries: not in a waveform recording "
                              "(a DC output's offset that this quadrature does not explain is the "
                              "demodulator's)"),
              ("adc_clipping", "a demodulator output's rails: not in a waveform recording"))
    notes = []
    if wave.exc_v is None:
        notes.append("no excitation recorded: the carrier and the phases are taken from the secondaries' sum")
    strong_a, strong_b = np.abs(a) > 0.5 * np.max(np.abs(a)), np.abs(b) > 0.5 * np.max(np.abs(b))
    return WaveDiagnosis(source=wave.source, carrier_hz=fc, sample_rate_hz=fs, reference_deg=math.degrees(phi),
                         noise_v=noise, dwells=tuple(dw), a_i=ar.real, a_q=ar.imag, b_i=br.real, b_q=br.imag,
                         null_mm=null_mm, phase_a_deg=float(np.degrees(np.median(np.angle(a[strong_a])))),
                         phase_b_deg=float(np.degrees(np.median(np.angle(b[strong_b])))), evidence=tuple(evidence), effects=effects,
                         not_in_waveforms=absent, notes=tuple(notes))


# -- reports -------------------------------------------------------------------------------

def _num(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def wave_to_json(dg: WaveDiagnosis) -> dict:
    return {
        "kind": "waveform", "source": dg.source, "carrier_hz": _num(dg.carrier_hz),
        "sample_rate_hz": _num(dg.sample_rate_hz), "reference_deg": _num(dg.reference_deg),
        "noise_v": _num(dg.noise_v), "null_mm": _num(dg.null_mm),
        "phase_a_deg": _num(dg.phase_a_deg), "phase_b_deg": _num(dg.phase_b_deg),
        "effects": [{"name": e.name, "explanation": e.explanation,
                     "params": {k: {"value": _num(v), "stderr": _num(s), "unit": un}
                                for k, (v, s, un) in e.params.items()},
                     "evidence": [_evidence_json(x) for x in dg.evidence if x.name == e.name and x.found]}
                    for e in dg.effects],
        "evidence": [_evidence_json(x) for x in dg.evidence],
        "not_in_waveforms": [{"name": n, "why": why} for n, why in dg.not_in_waveforms],
        "dwells": [{"position_mm": d.position_mm, "time_s": d.time_s,
                    "exc_v": _num(abs(d.exc)) if d.exc is not None else None,
                    "a_i_v": _num(dg.a_i[k]), "a_q_v": _num(dg.a_q[k]),
                    "b_i_v": _num(dg.b_i[k]), "b_q_v": _num(dg.b_q[k]),
                    "phase_a_deg": _num(math.degrees(np.angle(d.a))),
                    "phase_b_deg": _num(math.degrees(np.angle(d.b)))} for k, d in enumerate(dg.dwells)],
        "notes": list(dg.notes),
    }


def _evidence_json(x: Evidence) -> dict:
    out = {"effect": x.name, "figure": x.figure, "value": _num(x.value), "stderr": _num(x.stderr),
           "unit": x.unit, "threshold": _num(x.threshold), "found": bool(x.found)}
    if x.reason:
        out["not_computable"] = x.reason
    return out


def format_wave_text(dg: WaveDiagnosis) -> str:
    lines = [f"waveform diagnosis of {dg.source}: {len(dg.dwells)} dwells, carrier {dg.carrier_hz:.6g} Hz, "
             f"{dg.sample_rate_hz:.6g} samples/s, noise {dg.noise_v * 1e3:.3g} mV rms per secondary",
             f"  reference (phase of A - B's slope at the null) {dg.reference_deg:.3f} deg against the "
             + ("excitation" if dg.dwells[0].exc is not None else "secondaries' sum")
             + (f"; null (A_I = B_I) at {dg.null_mm:+.4f} mm" if dg.null_mm is not None else "; no null in the travel"),
             f"  phase of A {dg.phase_a_deg:.3f} deg, of B {dg.phase_b_deg:.3f} deg (median where each is "
             "above half its peak)",
             "", "evidence (found when |value| > threshold; thresholds "
             f"{Z_FOUND:g} standard errors, phase at least {PHASE_TOLERANCE_DEG:g} deg, "
             f"drift at least {DRIFT_FLOOR_PCT:g} %):"]
    for x in dg.evidence:
        if x.value is None:
            lines.append(f"  {x.name:<20} {x.figure}: not computable: {x.reason}")
            continue
        verdict = "FOUND" if x.found else "none"
        lines.append(f"  {x.name:<20} {x.figure}: {x.value:+.4g} +- {x.stderr:.2g} {x.unit} "
                     f"(threshold {x.threshold:.2g} {x.unit}): {verdict}")
    lines.append("")
    if dg.effects:
        lines.append("effects: " + ", ".join(e.name for e in dg.effects))
        for e in dg.effects:
            ps = ", ".join(f"{k} = {v:+.4g} +- {s:.2g} {u}" for k, (v, s, u) in e.params.items())
            lines.append(f"  {e.name}: {e.explanation}" + (f" ({ps})" if ps else ""))
    else:
        lines.append("effects: none (no figure beyond its threshold)")
    for name, why in dg.not_in_waveforms:
        lines.append(f"  {name}: {why}")
    lines += [f"note: {n}" for n in dg.notes]
    return "\n".join(lines) + "\n"


def plot_wave(dg: WaveDiagnosis, path) -> None:
    """Each secondary's in-phase amplitude and the quadrature amplitudes against position; the
    excitation amplitude against time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pos = np.array([d.position_mm for d in dg.dwells])
    t = np.array([d.time_s for d in dg.dwells])
    fig, axes = plt.subplots(3, 1, figsize=(8, 9))
    ax = axes[0]
    ax.plot(pos, dg.a_i, "o", label="A in phase")
    ax.plot(pos, dg.b_i, "s", label="B in phase")
    if dg.null_mm is not None:
        ax.axvline(dg.null_mm, color="grey", ls=":", label=f"null {dg.null_mm:+.3f} mm")
    ax.set_ylabel("amplitude (V peak)")
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.plot(pos, dg.a_q * 1e3, "o", label="A quadrature")
    ax.plot(pos, dg.b_q * 1e3, "s", label="B quadrature")
    ax.plot(pos, (dg.a_q - dg.b_q) * 1e3, "k.-", label="A - B quadrature")
    ax.axhline(0, color="grey", lw=0.5)
    ax.set_xlabel("displacement (mm)")
    ax.set_ylabel("quadrature (mV peak)")
    ax.legend(fontsize=8)
    ax = axes[2]
    if dg.dwells[0].exc is not None:
        e = np.array([abs(d.exc) for d in dg.dwells])
        ax.plot(t, 100 * (e / e[0] - 1), "o-", label=f"excitation (first dwell {e[0]:.4g} V peak)")
        ax.set_ylabel("excitation change (%)")
    else:
        ax.plot(t, dg.a_i + dg.b_i, "o", label="A + B in phase (no excitation recorded)")
        ax.set_ylabel("A + B (V peak)")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=8)
    fig.suptitle(f"waveform diagnosis: {', '.join(e.name for e in dg.effects) or 'no effect found'}")
    fig.tight_layout()
    atomic_save_figure(fig, path)
    plt.close(fig)
