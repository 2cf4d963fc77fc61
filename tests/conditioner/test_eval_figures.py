"""The chain's figures in a data sheet's terms (flann.analysis.conditioner_figures), on a small
waveform in closed form through the conditioner's twin, its ratio read back to mm by the exact
inverse (no FLANN fitted): each figure against what it measures, and each able to fail."""

import math

import numpy as np
import pytest

from flann.analysis.conditioner_figures import chain_figures
from flann.hardware.conditioner.settings import calibrate, dwell_readings
from flann.hardware.conditioner.spec import Reference
from flann.hardware.conditioner.twin import ConditionerChain, RatioOut
from flann.recordings.waveform import Waveforms

CARRIER, N, RANGE_V = 2500.0, 32, 5.0
CENTRE_V, GAIN_V_PER_MM = 1.5, 0.1   # A, B = C +- g x / 2: the ratio is g x / 2C
POSITIONS = np.linspace(-10.0, 10.0, 9)
NAMES = ("effective_bits", "noise_free_bits", "bandwidth_hz", "settling_time_s",
         "excitation_rejection_ppm_fs_per_pct", "quadrature_rejection_ppm_fs", "phase_tolerance_deg")


def wave(noise_v: float = 0.5e-3, seed: int = 1, dwell_windows: int = 5) -> Waveforms:
    fs = CARRIER * N
    x = np.repeat(POSITIONS, dwell_windows * 5 * N)   # 5 periods a window at 500 Hz out
    t = np.arange(x.size) / fs
    w = 2 * math.pi * CARRIER * t
    rng = np.random.default_rng(seed)
    lsb = 2 * RANGE_V / 4096
    a = (CENTRE_V + GAIN_V_PER_MM * x / 2) * np.cos(w + 0.7) + rng.normal(0, noise_v, x.size)
    b = (CENTRE_V - GAIN_V_PER_MM * x / 2) * np.cos(w + 0.7) + rng.normal(0, noise_v, x.size)
    a, b = (np.round(v / lsb) * lsb for v in (a, b))
    return Waveforms(time_s=t, sec_a_v=a, sec_b_v=b, displacement_mm=x, exc_v=np.cos(w))


def to_mm(ratio, _temperature_c=None):
    return 2 * CENTRE_V * np.asarray(ratio) / GAIN_V_PER_MM


def figures(w: Waveforms, twin=None) -> dict:
    settings, conditioned = calibrate(w, 500.0, 12, RANGE_V)
    dw = dwell_readings(conditioned, w, settings.spec.window)
    return {f.name: f for f in chain_figures(settings, w, dw, to_mm, 10.0, twin and twin(settings.spec))}


@pytest.fixture(scope="module")
def measured():
    return figures(wave())


def test_every_figure_has_a_value_or_a_reason_and_a_verdict(measured):
    assert tuple(measured) == NAMES
    for f in measured.values():
        assert (f.value is not None and math.isfinite(f.value)) or f.reason
        assert f.reference and f.source and f.check().text
        assert f.to_json()["reference_value"] == f.limit


def test_the_bandwidth_is_the_boxcar_s(measured):
    # a window of whole periods integrates as a boxcar: -3 dB at 0.4429 x the output rate
    assert measured["bandwidth_hz"].value == pytest.approx(0.4429 * 500.0, rel=0.02)
    assert measured["bandwidth_hz"].ok is False   # below the AD598's 250 Hz


def test_a_step_settles_within_two_windows(measured):
    f = measured["settling_time_s"]
    window_s = 5 * N / (CARRIER * N)
    # the recording's steps land on window boundaries: one window; a step just into a window: two
    assert f.value == pytest.approx(window_s)
    assert f.detail["worst_case_s"] == pytest.approx(2 * window_s - 1 / (CARRIER * N))
    assert "recording" in f.source


def test_twice_the_noise_costs_one_effective_bit(measured):
    louder = figures(wave(noise_v=1e-3))
    lost = measured["effective_bits"].value - louder["effective_bits"].value
    assert 0.7 < lost < 1.3
    assert measured["noise_free_bits"].value < measured["effective_bits"].value


class DifferenceChain(ConditionerChain):
    """The ratio block replaced by the difference over a fixed sum: no longer ratiometric."""

    def __init__(self, spec):
        super().__init__(spec)
        f, ratio, fixed = spec.ratio_frac_bits, self.ratio, []

        class Difference:
            latency = ratio.latency

            def process(self, a, b):
                a, b = np.asarray(a), np.asarray(b)
                fixed[:] = fixed or [int(np.median(a + b))]   # the recording's sum, then held
                return RatioOut(((a - b) << f) // fixed[0], np.zeros_like(a))

        self.ratio = Difference()


def test_the_excitation_rejection_comes_from_the_ratio(measured):
    ratiometric = measured["excitation_rejection_ppm_fs_per_pct"]
    assert ratiometric.ok is True and ratiometric.value < 10
    difference = figures(wave(), DifferenceChain)["excitation_rejection_ppm_fs_per_pct"]
    # a 1 % larger excitation moves a difference's output by 1 % of its value
    assert difference.value > 1000 and difference.ok is False


class OffPhaseChain(ConditionerChain):
    """The demodulators' reference two table steps (2.8 deg) off the calibrated phase."""

    def process(self, codes_a, codes_b, ref):
        return super().process(codes_a, codes_b, Reference(ref.offset + 2, ref.tan))


def test_the_quadrature_rejection_comes_from_the_calibrated_phase(measured):
    calibrated = measured["quadrature_rejection_ppm_fs"].value
    off = figures(wave(), OffPhaseChain)["quadrature_rejection_ppm_fs"]
    # 10 % of full scale through sin(2.8 deg): about 5000 ppm FS
    assert calibrated < 100 and off.value > 2000 and off.ok is False


def test_the_phase_tolerance_shrinks_with_a_phase_imbalance(measured):
    w = wave()
    fs = CARRIER * N
    t = np.arange(len(w)) / fs
    x = w.displacement_mm
    lsb = 2 * RANGE_V / 4096
    # B lags A by 2 degrees: a phase error no longer cancels in the ratio
    b = np.round((CENTRE_V - GAIN_V_PER_MM * x / 2) * np.cos(2 * math.pi * CARRIER * t + 0.7 + math.radians(2))
                 / lsb) * lsb
    skewed = figures(Waveforms(time_s=t, sec_a_v=w.sec_a_v, sec_b_v=b, displacement_mm=x, exc_v=w.exc_v))
    assert 0 < skewed["phase_tolerance_deg"].value < measured["phase_tolerance_deg"].value


def test_a_figure_the_recording_cannot_give_is_said_not_computable():
    # one window a dwell: no window-to-window noise to measure
    f = figures(wave(dwell_windows=1))
    for name in ("effective_bits", "noise_free_bits"):
        assert f[name].value is None and "two windows" in f[name].reason
        assert f[name].ok is None and f[name].to_json()["value"] is None
        assert "not computable" in f[name].text()
    assert f["bandwidth_hz"].value is not None
