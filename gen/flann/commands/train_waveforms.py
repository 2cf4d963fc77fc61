"""``flann train wave.csv`` and ``flann eval model.json wave.csv``: a waveform recording read
through the conditioner's twin.

Training calibrates the conditioner on the record (:func:`flann.hardware.conditioner.settings.calibrate`),
its ratio averaged per dwell gives the readings the FLANN is fitted to, and the model keeps the
conditioner's settings; evaluation reads a held-out record at the model's settings, the same
readings (docs/conditioner.md, "Training from waveforms").
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from ..analysis.conditioner_figures import pooled_rms
from ..argtypes import bounded
from ..errors import FlannError
from ..hardware.conditioner.settings import (DEFAULT_OUTPUT_RATE_HZ, ConditionerSettings, calibrate, condition_with,
                                              dwell_readings, of_model)
from ..recordings.waveform import is_waveform_csv, read_waveforms
from .common import info

FLAGS = ("output_rate_hz", "adc_bits", "adc_range_v")


def add_waveform_arguments(p) -> None:
    g = p.add_argument_group("a waveform recording (time_s, sec_a_v, sec_b_v; docs/waveforms.md)")
    g.add_argument("--output-rate-hz", type=bounded(float, 0, lo_open=True), default=None,
                   help=f"the conditioner's ratio rate, whole carrier periods a ratio (default {DEFAULT_OUTPUT_RATE_HZ:g})")
    g.add_argument("--adc-bits", type=bounded(int, 4, 24), default=None,
                   help="the secondaries' converters (default: from the samples' grid)")
    g.add_argument("--adc-range-v", type=bounded(float, 0, lo_open=True), default=None,
                   help="their range +-V (default: from the samples' grid)")


def is_waveform(args) -> bool:
    """``args.recordings`` is a waveform recording; the waveform flags are refused for any other."""
    if is_waveform_csv(args.recordings):
        return True
    given = [f"--{f.replace('_', '-')}" for f in FLAGS if getattr(args, f, None) is not None]
    if given and Path(args.recordings).is_file():
        raise FlannError(f"{', '.join(given)}: set the conditioner of a waveform recording; "
                         f"{args.recordings} holds demodulated readings")
    return False


def _refuse_flags(args, flags) -> None:
    for flag, value, default in flags:
        if value != default:
            raise FlannError(f"{flag}: a model trained from waveforms takes the conditioner's ratio "
                             "(A-B)/(A+B) as its input; leave it out")


def _readings(args, wave, settings, conditioned, found: str):
    """The conditioned windows averaged per dwell, and the line saying so (unless --quiet)."""
    sha = hashlib.sha256(Path(args.recordings).read_bytes()).hexdigest()
    dw = dwell_readings(conditioned, wave, settings.spec.window, sha)
    rec = dw.recordings
    positions = len(set(rec.displacement_mm.tolist()))
    info(args, f"{args.recordings}: waveforms{found}: {settings.line()}; {positions} positions, {len(rec)} dwells "
               f"averaged over {dw.windows} windows ({dw.left_out} left out: moving, saturated or across a "
               "temperature step)")
    return dw


def read_conditioned(args) -> tuple:
    """(dwell readings, settings, conditioned windows): the record through the conditioner
    calibrated on it, one reading per dwell; the line saying what was found is printed (unless
    --quiet)."""
    _refuse_flags(args, (("--ab", args.ab, "ratio"), ("--sensor-id", args.sensor_id, None),
                         ("--input-bits", args.input_bits, None), ("--input-lsb-v", args.input_lsb_v, None)))
    wave = read_waveforms(args.recordings, announce=not args.quiet)
    rate = args.output_rate_hz if args.output_rate_hz is not None else DEFAULT_OUTPUT_RATE_HZ
    settings, conditioned = calibrate(wave, rate, args.adc_bits, args.adc_range_v)
    return _readings(args, wave, settings, conditioned, ""), settings, conditioned


def window_noise_mm(model, dwells, conditioned) -> float | None:
    """The output's noise at the ratio's rate (mm rms): each dwell's windows through the model,
    about their dwell's mean, pooled; None when no dwell holds two windows."""
    outs = [model.predict(conditioned.ratio[g]) for g in dwells.groups if g.size >= 2]
    return pooled_rms(outs) if outs else None


def read_held_out(args, model) -> tuple:
    """(dwell readings, settings, conditioned windows, the waveforms) of a waveform recording at the conditioner
    settings ``model`` keeps (``flann eval``): the record is not calibrated on, its reference
    turned by its excitation."""
    settings = of_model(model, args.model)
    if settings is None:
        raise FlannError(f"{args.recordings}: a waveform recording, but {args.model} was trained from demodulated "
                         "readings (its input is a voltage, not the conditioner's ratio): train it from waveforms")
    _refuse_flags(args, (("--ab", args.ab, "ratio"), ("--sensor-id", args.sensor_id, None)))
    wave = read_waveforms(args.recordings, announce=not args.quiet)
    conditioned = condition_with(settings, wave)
    return _readings(args, wave, settings, conditioned, " at the model's conditioner"), settings, conditioned, wave


def converter_of_ratio(settings: ConditionerSettings) -> dict:
    """The converter in front of the FLANN: the conditioner's ratio code."""
    bits, lsb = settings.ratio_converter
    return {"input_bits": bits, "input_lsb_v": lsb, "from": "the conditioner's ratio"}


__all__ = ["add_waveform_arguments", "is_waveform", "read_conditioned", "read_held_out", "converter_of_ratio",
           "window_noise_mm"]
