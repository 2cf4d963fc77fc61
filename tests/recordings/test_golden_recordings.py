"""Validation before fitting: duplicates, fold-back (and --trim), flat-end noise, too few points."""

import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.golden.paper import s_curve
from flann.recordings import Recordings, monotonic_span, parse_recordings, prepare_for_fit


def folding(x):
    # x exp(-x^2 / 2a^2) peaks at x = a = 35 mm: beyond +-35 mm the voltage falls again,
    # as when the core leaves the coils
    return 6.0 * (x / 35.0) * np.exp(0.5 - 0.5 * (x / 35.0) ** 2)


def test_duplicate_displacement_with_other_voltage_in_same_direction():
    text = "displacement_mm,voltage_v\n0,0.0\n5,1.0\n5,1.2\n10,2.0\n"
    with pytest.raises(RecordingsError, match=r"lines 3 and 4: displacement 5 mm appears twice"):
        prepare_for_fit(parse_recordings(text, "d.csv"))


def test_same_displacement_in_the_two_directions_is_fine():
    text = ("displacement_mm,voltage_v,direction\n0,0.0,1\n5,1.0,1\n10,2.0,1\n"
            "10,2.1,-1\n5,1.2,-1\n0,0.1,-1\n")
    rec = parse_recordings(text, "h.csv")
    assert prepare_for_fit(rec) is rec


def test_fold_back_is_refused_and_located():
    x = np.arange(-45.0, 45.5, 0.5)
    rec = Recordings(x, folding(x), source="fold.csv")
    with pytest.raises(RecordingsError, match=r"beyond 35 mm.*below -35 mm.*--trim"):
        prepare_for_fit(rec)


def test_trim_keeps_the_monotonic_span():
    x = np.arange(-45.0, 45.5, 0.5)
    rec = Recordings(x, folding(x), source="fold.csv")
    with pytest.warns(UserWarning, match=r"-35 \.\. 35 mm"):
        kept = prepare_for_fit(rec, trim=True)
    assert kept.displacement_mm.min() == -35.0 and kept.displacement_mm.max() == 35.0
    assert np.all(np.diff(kept.voltage_v) > 0)


def test_fold_back_inside_the_span_cannot_be_trimmed():
    x = np.linspace(-30.0, 30.0, 121)
    v = s_curve(x)
    v[60:70] -= np.linspace(0.0, 3.0, 10)       # falls ~0.17 V per step for 9 steps at the null
    span = monotonic_span(Recordings(x, v, source="dip.csv"))
    assert span.foldback and not span.trimmable
    with pytest.raises(RecordingsError, match="cannot remove it"):
        prepare_for_fit(Recordings(x, v, source="dip.csv"), trim=True)


def test_noise_wiggles_on_flat_ends_are_not_a_fold_back():
    x = np.linspace(-60.0, 60.0, 1201)         # far into saturation: ends nearly flat
    v = s_curve(x, noise_v=2e-3, seed=3)
    assert np.count_nonzero(np.diff(v) < 0) > 50  # the data do wiggle back point to point
    rec = Recordings(x, v, source="flat.csv")
    assert not monotonic_span(rec).foldback
    assert prepare_for_fit(rec) is rec


def test_too_few_points():
    with pytest.raises(RecordingsError, match="need at least 3"):
        prepare_for_fit(parse_recordings("displacement_mm,voltage_v\n0,0\n1,1\n", "two.csv"))


def test_up_and_down_sweep_without_direction_column_is_fine():
    # the usual bench file: out and back, the turning point read twice, no direction column
    x = np.arange(-10.0, 10.5, 1.0)
    up, down = np.tanh(x / 8.0), np.tanh(x / 8.0) + 0.004      # 4 mV hysteresis
    rows = [f"{a:g},{b:.6f}" for a, b in zip(x, up)] + [f"{a:g},{b:.6f}" for a, b in zip(x[::-1], down[::-1])]
    rec = parse_recordings("displacement_mm,voltage_v\n" + "\n".join(rows) + "\n", "updown.csv")
    assert len(prepare_for_fit(rec)) == 42


def test_two_passes_the_same_way_are_still_repeats():
    x = np.arange(-10.0, 10.5, 1.0)
    rows = [f"{a:g},{np.tanh(a / 8.0) + off:.6f}" for off in (0.0, 0.3) for a in x]
    rec = parse_recordings("displacement_mm,voltage_v\n" + "\n".join(rows) + "\n", "twice.csv")
    with pytest.raises(RecordingsError, match=r"appears twice in direction \+1 \(sweeps told apart by the row order\)"):
        prepare_for_fit(rec)


def test_readings_repeated_at_each_step_within_noise_are_fine():
    # three readings per position while the actuator dwells, 0.1 mV apart, no time column
    x = np.repeat(np.arange(-10.0, 10.5, 1.0), 3)
    v = np.tanh(x / 8.0) + np.tile([0.0, 1e-4, -1e-4], 21)
    rec = Recordings(x, v, source="dwell.csv")
    assert len(prepare_for_fit(rec)) == 63
    v[31] += 0.3                                     # a reading far off its neighbours: refused
    with pytest.raises(RecordingsError, match="appears twice"):
        prepare_for_fit(Recordings(x, v, source="dwell.csv"))


def _four_sweeps(noise_v=8e-4, n=200, seed=5):
    rng = np.random.default_rng(seed)
    x = np.linspace(-10.0, 10.0, n)
    xs = np.concatenate([x, x[::-1], x, x[::-1]])
    d = np.concatenate([np.ones(n), -np.ones(n)] * 2)
    v = 7.0 * np.tanh(xs / 9.0) + rng.normal(0.0, noise_v, xs.size)
    return xs, v, d


def test_four_sweeps_with_noise_are_data():
    # the case: two forward and two reverse sweeps, readings 0.87 mV apart are noise
    xs, v, d = _four_sweeps()
    rec = Recordings(xs, v, direction=d, source="four.csv")
    assert len(prepare_for_fit(rec)) == xs.size


def test_a_repeat_far_beyond_the_noise_is_refused_naming_line_and_noise_units():
    xs, v, d = _four_sweeps()
    v[450] += 0.5          # a glitch on the second forward sweep
    with pytest.raises(RecordingsError, match=r"rows 51 and 451: .* they are [0-9.]+ noise units apart \(noise [0-9.e-]+ V from [0-9]+ repeated readings"):
        prepare_for_fit(Recordings(xs, v, direction=d, source="four.csv"))


def test_converter_of_finds_step_and_bits_of_the_grid():
    from flann.recordings import converter_of
    lsb = 2 * 7.35 / 2 ** 12          # 12-bit, the range 5 % above the largest reading
    v = np.round(7.0 * np.tanh(np.linspace(-3, 3, 400)) / lsb) * lsb
    bits, step = converter_of(v)
    assert bits == 12 and abs(step - lsb) < 1e-9 * lsb
    assert converter_of(v + np.random.default_rng(0).normal(0, 1e-4, v.size)) is None


def test_repeat_noise_on_a_converter_grid_is_not_zero():
    from flann.recordings.checks import repeat_noise_v
    lsb = 5e-3
    rng = np.random.default_rng(2)
    x = np.repeat(np.arange(200.0), 4)
    v = np.round((0.01 * x + rng.normal(0, 2e-3, x.size)) / lsb) * lsb   # most repeats read one code
    sigma, pairs = repeat_noise_v(x, v)
    assert pairs == 600
    assert 1.5e-3 < sigma < 3.5e-3    # noise (2 mV) and quantisation (1.4 mV) together: 2.4 mV


def _arctan_sweeps(x, noise, seed=0):
    """Two sweeps (forward and back) of an arctan sensor, one reading per position and direction."""
    rng = np.random.default_rng(seed)
    xs = np.concatenate([x, x[::-1]])
    d = np.concatenate([np.ones(x.size), -np.ones(x.size)])
    return xs, 5.0 * np.arctan(xs / 12.0) + rng.normal(0.0, noise, xs.size), d


def test_one_glitch_is_not_a_fold_back():
    """A single reading 0.3 V off (150 noise units) was refused as a fold-back inside the span;
    it is the outlier screen's to find."""
    xs, v, d = _arctan_sweeps(np.arange(-25.0, 25.05, 0.1).round(1), 0.002)
    v[np.flatnonzero((xs == 5.0) & (d == 1))[0]] -= 0.3
    span = monotonic_span(Recordings(xs, v, direction=d, source="glitch.csv"))
    assert not span.foldback


def test_a_fold_back_of_some_noise_units_at_the_ends_is_found():
    """Past its turning points the voltage falls 56 mV over the last 0.75 mm (2 mV noise, about
    a half per cent of an 11 V span): below the old 1 %-of-span floor, yet no inverse exists."""
    x = np.arange(-30.0, 30.01, 0.25)
    xs, v, d = _arctan_sweeps(x, 0.002)
    past = np.clip(np.abs(xs) - 29.25, 0.0, None)
    v -= np.sign(xs) * 0.135 * past      # the curve falls 56 mV from 29.25 to 30 mm
    span = monotonic_span(Recordings(xs, v, direction=d, source="ends.csv"))
    assert span.foldback and span.trimmable
    kept = xs[span.mask]
    assert 29.0 <= kept.max() <= 29.5 and -29.5 <= kept.min() <= -29.0


def test_repeated_sweeps_do_not_inflate_the_fold_back_threshold():
    """Two sweeps in one direction interleave in displacement order; differences of single
    readings then carry the slope and made the noise estimate 20x too large."""
    x = np.arange(-30.0, 30.01, 0.25)
    xs, v, d = _arctan_sweeps(x, 0.002)
    xs2, v2, d2 = _arctan_sweeps(x, 0.002, seed=1)
    span = monotonic_span(Recordings(np.r_[xs, xs2], np.r_[v, v2], direction=np.r_[d, d2], source="two.csv"))
    assert span.noise_v < 0.004
