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
