"""``flann simulate SENSOR.toml --waveforms -o wave.csv``: sampled excitation and secondaries.

The options of this mode; the travel, step, sweeps, noise, seed, temperature profile and
temperatures (a calibration at several: the trajectory at each in turn) are the simulation's
own (``flann simulate``).
"""

from __future__ import annotations

from ..argtypes import bounded
from ..errors import FlannError
from ..physics.simulate import parse_temperatures
from ..physics.waveforms import SAMPLES_PER_CARRIER, WaveformSettings, parse_trajectory, simulate_waveforms
from ..recordings.waveform import write_waveforms
from .common import info

DEFAULT_TRAJECTORY = "steps:0.02"


def add_waveform_arguments(p) -> None:
    g = p.add_argument_group("waveforms (--waveforms)")
    g.add_argument("--waveforms", action="store_true",
                   help="write sampled waveforms (time_s,exc_v,sec_a_v,sec_b_v,displacement_mm,"
                        "temperature_c; docs/waveforms.md) in place of demodulated recordings")
    g.add_argument("--carrier-hz", type=bounded(float, 1.0, 1e6), default=None,
                   help="excitation frequency (default: the sensor's)")
    g.add_argument("--sample-rate-hz", type=bounded(float, 1.0, 1e8), default=None,
                   help=f"ADC sample rate (default {SAMPLES_PER_CARRIER} x the carrier)")
    g.add_argument("--adc-bits", type=bounded(int, 2, 32), default=12, help="ADC bits (default 12)")
    g.add_argument("--adc-range-v", type=bounded(float, 1e-6, 1e3), default=None,
                   help="ADC full scale, +-V (default: the smallest DAQ range above the secondaries' peak)")
    g.add_argument("--trajectory", default=DEFAULT_TRAJECTORY,
                   help="steps:DWELL_S (dwell at each --step-mm position of the sweeps) | "
                        "ramp:DURATION_S (--from-mm to --to-mm) | sine:FREQ_HZ:DURATION_S (about the "
                        f"travel's centre, half its span; default {DEFAULT_TRAJECTORY})")
    g.add_argument("--excitation-drift-pct", type=bounded(float, -99.0, 99.0), default=0.0,
                   help="excitation amplitude change over the run, linear, %% (default 0)")
    g.add_argument("--harmonic-pct", type=bounded(float, 0.0, 99.0), default=0.0,
                   help="third harmonic in the excitation, %% of the fundamental (default 0)")


def waveform_options_used(args) -> bool:
    return (args.carrier_hz is not None or args.sample_rate_hz is not None or args.adc_bits != 12
            or args.adc_range_v is not None or args.trajectory != DEFAULT_TRAJECTORY
            or args.excitation_drift_pct != 0.0 or args.harmonic_pct != 0.0)


def run_waveforms(args, s, travel_mm: tuple[float, float]) -> int:
    """Write the waveforms of sensor ``s`` (effects already chosen) to ``args.output``."""
    if args.plot:
        raise FlannError("simulate --waveforms: --plot is for demodulated recordings")
    temps = parse_temperatures(args.temperatures) if args.temperatures is not None else None
    settings = WaveformSettings(carrier_hz=args.carrier_hz, sample_rate_hz=args.sample_rate_hz,
                                adc_bits=args.adc_bits, adc_range_v=args.adc_range_v,
                                noise_v=args.noise_v, excitation_drift_pct=args.excitation_drift_pct,
                                harmonic_pct=args.harmonic_pct, seed=args.seed)
    wave = simulate_waveforms(s, settings, parse_trajectory(args.trajectory), travel_mm=travel_mm,
                              step_mm=args.step_mm, sweeps=args.sweeps,
                              temperature_profile=args.temperature_profile, temperatures=temps)
    carrier = args.carrier_hz or s.excitation_frequency_hz
    effects = "; ".join(f"{n}(" + ", ".join(f"{k}={v:g}" for k, v in p.items()) + ")"
                        for n, p in s.effects.items()) or "none"
    comments = (
        f"waveforms simulated by flann simulate --waveforms: sensor {s.name} ({args.sensor or 'default'})",
        f"carrier {carrier:g} Hz, trajectory {args.trajectory}, travel {travel_mm[0]:g}..{travel_mm[1]:g} mm",
        *wave.comments,
        f"noise {args.noise_v:g} V rms, seed {args.seed}, excitation drift {args.excitation_drift_pct:g} %, "
        f"third harmonic {args.harmonic_pct:g} %, temperature "
        + (f"a calibration at {', '.join(f'{t:g}' for t in temps)} degC, the trajectory at each" if temps
           else args.temperature_profile),
        f"effects: {effects}",
    )
    write_waveforms(args.output, wave, comments=comments)
    info(args, f"wrote {args.output}: {len(wave)} samples at {wave.sample_rate_hz:.6g} Hz, "
               f"{wave.time_s[-1]:.4g} s, effects: {effects}")
    return 0
