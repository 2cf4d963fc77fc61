"""flann train --input-bits/--input-lsb-v: a converter that cannot carry the recording's
voltages is refused up front with gen's reason (range or code count), not as a derived
datapath width of some fitted candidate."""

import numpy as np
import pytest


@pytest.fixture
def recording(tmp_path):
    # an LVDT-like S curve, +-4.17 V over +-30 mm (41 positions, two readings each)
    x = np.repeat(np.arange(-30.0, 30.01, 1.5), 2)
    v = 6.0 * np.tanh(x / 35.0)
    p = tmp_path / "rec.csv"
    p.write_text("displacement_mm,voltage_v\n" + "".join(f"{float(a)!r},{float(b)!r}\n" for a, b in zip(x, v)))
    return p


def one_error(rc, err):
    assert rc == 2 and "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    return lines[0]


@pytest.mark.parametrize("opts, fragments", [
    # 12 bits x 1 mV cover -2.048..2.047 V: the +-4.17 V recording does not fit
    (("--input-bits", 12, "--input-lsb-v", 0.001),
     ("does not fit the ADC's range -2.048..2.047 V", "(--input-bits 12 --input-lsb-v 0.001)")),
    # 8.34 V span at 1 V per code: 8.3 codes
    (("--input-bits", 12, "--input-lsb-v", 1),
     ("--input-lsb-v", "only 8.3", "need >= 16")),
    # 4 bits at the default LSB (range + 10 %): 16 / 1.1 = 14.5 codes
    (("--input-bits", 4), ("input_bits = 4", "14.5 codes", "need >= 16")),
])
def test_unusable_converter_is_refused_with_gens_reason(cli, tmp_path, recording, opts, fragments):
    out = tmp_path / "t.json"
    line = one_error(*cli(["train", recording, "-o", out, *opts])[::2])
    for f in fragments:
        assert f in line, line
    assert "phase_bits" not in line and "--terms auto (the default)" not in line
    assert not out.exists()


def test_train_and_gen_give_one_reason(cli, tmp_path, recording):
    model = tmp_path / "m.json"
    assert cli(["train", recording, "-o", model])[0] == 0
    gen_line = one_error(*cli(["gen", model, "-o", tmp_path / "g", "--input-bits", 12,
                               "--input-lsb-v", 0.001])[::2])
    train_line = one_error(*cli(["train", recording, "-o", tmp_path / "t.json", "--input-bits", 12,
                                 "--input-lsb-v", 0.001])[::2])
    # the same sentence but for the trained range's last digits (a fitted model's range is
    # the curve's, the recording's its readings')
    head = "does not fit the ADC's range -2.048..2.047 V (--input-bits 12 --input-lsb-v 0.001): "
    assert gen_line.split("V does not fit")[1] == train_line.split("V does not fit")[1]
    assert head in gen_line


def test_a_converter_that_fits_still_trains(cli, tmp_path, recording):
    out = tmp_path / "t.json"
    rc, _, err = cli(["train", recording, "-o", out, "--input-bits", 12, "--input-lsb-v", 0.003])
    assert rc == 0 and out.exists(), err
    assert "12-bit x 0.003 V converter" in err
