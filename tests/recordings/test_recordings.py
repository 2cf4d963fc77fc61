import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.recordings import parse_recordings, read_recordings


def test_paper_table_reads_with_provenance():
    rec = read_recordings("data/paper_table1.csv")
    assert len(rec) == 13
    assert rec.voltage_v[8] == pytest.approx(1.810)
    assert rec.displacement_mm[0] == -30
    assert rec.comments and "Table 1" in rec.comments[0]


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("displacement_mm\n1\n", "missing column"),
        ("displacement_mm,voltage_v\n1,abc\n", "not a number"),
        ("displacement_mm,voltage_v\n1,nan\n", "not finite"),
        ("displacement_mm,voltage_v\n1,inf\n", "not finite"),
        ("displacement_mm,voltage_v,direction\n1,2,0\n", r"not \+1 or -1"),
        ("displacement_mm,voltage_v\n", "no data rows"),
        ("displacement_mm,voltage_v\n1,2,3\n", "cells"),
    ],
)
def test_bad_recordings_name_the_problem(text, fragment):
    with pytest.raises(RecordingsError, match=fragment):
        parse_recordings(text, source="x.csv")


def test_unknown_column_warns_and_is_ignored():
    with pytest.warns(UserWarning, match="ignoring unknown column"):
        rec = parse_recordings("displacement_mm,voltage_v,humidity\n1,2,3\n")
    assert set(rec.columns()) == {"displacement_mm", "voltage_v"}
    np.testing.assert_array_equal(rec.voltage_v, [2.0])


def _sweeps_text(second_pass_offset_v: float, with_time: bool) -> str:
    """Two forward passes over a smooth curve; the second shifted by an offset."""
    x = np.arange(-10, 11, 1.0)
    v = np.tanh(x / 8.0)
    rows = ["displacement_mm,voltage_v,direction" + (",time_s" if with_time else "")]
    t = 0
    for off in (0.0, second_pass_offset_v):
        for xi, vi in zip(x, v + off):
            rows.append(f"{xi},{vi:.6f},1" + (f",{t}" if with_time else ""))
            t += 1
    return "\n".join(rows) + "\n"


def test_repeated_sweeps_within_noise_are_accepted_with_time_column():
    from flann.recordings import prepare_for_fit

    rec = parse_recordings(_sweeps_text(0.0005, with_time=True))
    assert len(prepare_for_fit(rec)) == 42


@pytest.mark.parametrize("offset, with_time", [(0.0005, False), (0.3, True)])
def test_repeats_are_refused_without_time_or_beyond_noise(offset, with_time):
    from flann.recordings import prepare_for_fit

    rec = parse_recordings(_sweeps_text(offset, with_time=with_time), source="r.csv")
    with pytest.raises(RecordingsError, match="appears twice"):
        prepare_for_fit(rec)
