"""'30,000' is 30 with a decimal comma or 30000 with a thousands separator: the rest of the file
decides, and a file that does not is refused naming the cell, never read a thousand times off."""

import json

import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.recordings import parse_recordings

# a US spreadsheet's export: positions formatted with thousands separators (quoted), voltages
# with decimal points, some of which ('0.05', '2.9') cannot be thousands groups
THOUSANDS = ('displacement_um,voltage_v\n"-30,000",-5.185\n"-20,000",-4.717\n"-10,000",-2.896\n0,0.05\n'
             '"10,000",2.9\n"20,000",4.7\n"30,000",5.27\n')


def test_quoted_thousands_in_a_file_with_decimal_points_are_thousands(cli, tmp_path):
    rec = parse_recordings(THOUSANDS, source="th.csv")
    np.testing.assert_array_equal(rec.displacement_mm, [-30, -20, -10, 0, 10, 20, 30])
    np.testing.assert_array_equal(rec.voltage_v, [-5.185, -4.717, -2.896, 0.05, 2.9, 4.7, 5.27])
    assert "',' as thousands separator (line 2 '-30,000' read as -30000)" in rec.recognised
    assert "decimal comma" not in rec.recognised
    (tmp_path / "th.csv").write_text(THOUSANDS)
    rc, _, err = cli(["train", tmp_path / "th.csv", "-o", tmp_path / "th.json", "--terms", "3"])
    assert rc == 0 and "thousands separator" in err
    assert json.loads((tmp_path / "th.json").read_text())["displacement_range_mm"] == [-30.0, 30.0]


@pytest.mark.parametrize("text, why", [
    # nothing else tells which mark is the decimal one
    ('displacement_um,voltage_v\n"-30,000",-5\n"-20,000",-4\n0,0\n"30,000",5\n',
     "no other number in the file shows which is the decimal mark"),
    ('displacement_mm\tvoltage_v\n1,000\t2\n2,000\t3\n', "no other number"),
    # both marks proven decimal elsewhere
    ('displacement_um,voltage_v\n"-30,000",-5.185\n"-20,000","-4,5"\n0,0.5\n"30,000",5\n',
     r"the file uses both as decimal marks \(line 3 '-4,5', line 4 '0.5'\)"),
    # a point and a comma both before three digits: one of them is a thousands separator
    ('displacement_um;voltage_v\n-30.000;-5,185\n-20.000;-4,717\n',
     r"'\.' is also followed by three digits \(line 2 '-30.000'\)"),
])
def test_an_undecidable_grouped_cell_is_refused_naming_line_and_cell(cli, tmp_path, text, why):
    with pytest.raises(RecordingsError, match=r"^a\.csv: line 2, column '[^']+': '[^']+' is ambiguous: .*" + why):
        parse_recordings(text, source="a.csv")
    p = tmp_path / "a.csv"
    p.write_text(text)
    rc, _, err = cli(["train", p, "-o", tmp_path / "m.json", "--terms", "1"])
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("error: ") and "ambiguous" in lines[0]
    assert not (tmp_path / "m.json").exists()


@pytest.mark.parametrize("text, x, v", [
    # a European spreadsheet: semicolons, decimal commas, three decimals
    ("displacement_mm;voltage_v\n-30,000;-5,185\n-20,000;-4,717\n0;0,050\n", [-30, -20, 0], [-5.185, -4.717, 0.05]),
    # '0,250' cannot be a thousands group: commas are decimal marks, '1,000' is 1
    ('displacement_mm,voltage_v\n"1,000","0,250"\n"2,000","0,500"\n', [1, 2], [0.25, 0.5]),
    # a point before three digits is the decimal point it always was in CSV
    ("displacement_mm,voltage_v\n1.000,5.185\n2.000,6.250\n", [1, 2], [5.185, 6.25]),
    # decimal commas proven: the point groups thousands (a German export)
    ("displacement_um;voltage_v\n-30.000;-5,185\n0;0,05\n30.000;5,2\n", [-30, 0, 30], [-5.185, 0.05, 5.2]),
])
def test_grouped_cells_take_the_mark_the_file_proves(text, x, v):
    rec = parse_recordings(text)
    np.testing.assert_allclose(rec.displacement_mm, x, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(rec.voltage_v, v)
