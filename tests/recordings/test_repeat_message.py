"""A repeat refused names the reading and the other one beside it; readings at several
temperatures at one position are said to be that, with the command that fits them."""

import numpy as np
import pytest

from flann.errors import RecordingsError
from flann.recordings import Recordings, parse_recordings, prepare_for_fit


def test_a_repeat_among_three_names_the_other_line_and_its_voltage():
    # line 4 is off; of the others, line 5 (1.0002 V) is their median
    text = "displacement_mm,voltage_v\n0,0\n1,0.999\n1,1.5\n1,1.0002\n1,1.001\n2,2\n3,3\n"
    with pytest.raises(RecordingsError,
                       match=r"^r\.csv: lines 4 and 5: displacement 1 mm appears twice with different "
                             r"voltages \(1\.5 V, 1\.0002 V\): line 4 is"):
        prepare_for_fit(parse_recordings(text, "r.csv"))


def test_the_reading_named_is_never_the_refused_one_itself():
    x = np.repeat(np.arange(10.0), 4)
    v = x + np.tile([0.0, 1e-4, -1e-4, 2e-4], 10)
    for row in range(x.size):
        bad = v.copy()
        bad[row] += 0.5
        with pytest.raises(RecordingsError) as info:
            prepare_for_fit(Recordings(x, bad, source="d.csv"))
        a, b = (int(t) for t in str(info.value).split(":")[1].split("rows ")[1].split(" and "))
        assert a != b and row + 1 in (a, b)
        assert f"{bad[row]:.6g} V" in str(info.value)


def _three_temperatures():
    """One sweep at each of 20, 40 and 60 degC, the gain rising 0.1 %/degC."""
    rows = [(i, round(0.2 * i * (1 + 1e-3 * (t - 20)) + 0.0002 * i ** 3, 6), t)
            for t in (20, 40, 60) for i in range(-20, 21)]
    return "displacement_mm,voltage_v,temperature_c\n" + "".join(f"{a},{b},{c}\n" for a, b, c in rows)


def test_several_temperatures_are_not_called_repeats(cli, tmp_path):
    p = tmp_path / "t0.csv"
    p.write_text(_three_temperatures())
    rc, _, err = cli(["train", p, "-o", tmp_path / "m.json"])
    error = [line for line in err.splitlines() if line.startswith("error: ")]
    assert rc == 2 and len(error) == 1 and not (tmp_path / "m.json").exists()
    assert ("lines 42 and 83: displacement 20 mm reads 5.6 V at 20 degC and 5.68 V at 40 degC" in error[0])
    assert "3 temperatures (20, 40, 60 degC)" in error[0] and "flann train --temperature" in error[0]
    assert "appears twice" not in error[0] and "two files joined" not in error[0]
    rc, _, _ = cli(["train", p, "--temperature", "-o", tmp_path / "m.json"])
    assert rc == 0


def test_a_glitch_at_one_temperature_is_still_a_repeat():
    text = ("displacement_mm,voltage_v,temperature_c\n" + "".join(f"{i},{0.2 * i:g},20\n" for i in range(6))
            + "5,1.6,20\n" + "".join(f"{i},{0.2 * i:g},20\n" for i in range(6, 10)))
    with pytest.raises(RecordingsError, match=r"lines 7 and 8: displacement 5 mm appears twice"):
        prepare_for_fit(parse_recordings(text, "g.csv"))
