"""Number cells are ASCII numbers: Python's float() also reads '1_0' (as 10), full-width and
Arabic-Indic digits, which no logger writes; such a cell is refused, naming file, line and cell."""

import json

import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.recordings import parse_recordings


@pytest.mark.parametrize("cell", ["1_0", "0.1_5", "\uff11", "\u0663", "1\u0660", "\u00b2", "+\uff15e1"])
def test_non_ascii_or_underscored_number_is_refused(cell):
    text = f"displacement_mm,voltage_v\n0,0\n{cell},0.5\n2,0.6\n"
    with pytest.raises(RecordingsError) as info:
        parse_recordings(text, source="u.csv")
    msg = str(info.value)
    assert msg.startswith("u.csv: line 3, column 'displacement_mm':")
    assert f"'{cell}' is not a number" in msg


@pytest.mark.parametrize("text, x, v", [
    ("displacement_mm,voltage_v\n-1.5,+.25\n1e1,-2.E-1\n", [-1.5, 10.0], [0.25, -0.2]),
    ("displacement_mm;voltage_v\n-1,5;0,25\n3;1,5E-1\n", [-1.5, 3.0], [0.25, 0.15]),
    ('displacement_mm,voltage_v\n"2,5","-0,75"\n4.,1\n', [2.5, 4.0], [-0.75, 1.0]),
])
def test_ascii_numbers_and_decimal_commas_still_read(text, x, v):
    rec = parse_recordings(text, source="ok.csv")
    np.testing.assert_array_equal(rec.displacement_mm, x)
    np.testing.assert_array_equal(rec.voltage_v, v)


def test_predict_refuses_the_testers_file_with_one_line(cli, tmp_path):
    model = {"format": "flann-model/1", "terms": 1, "input_offset_v": 0.0, "input_scale_v": 1.0,
             "bias": 0.0, "weights": [1.0], "voltage_range_v": [-2.0, 2.0],
             "displacement_range_mm": [-2.0, 2.0], "training": {}}
    (tmp_path / "m.json").write_text(json.dumps(model))
    data = tmp_path / "u.csv"
    data.write_text("voltage_v\n0.1_5\n\uff11\n\u0663\n", encoding="utf-8")
    out = tmp_path / "p.csv"
    rc, _, err = cli(["predict", tmp_path / "m.json", data, "-o", out])
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "u.csv: line 2" in lines[0] and "'0.1_5'" in lines[0]
    assert "Traceback" not in err and not out.exists()
