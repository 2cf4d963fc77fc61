"""An output LSB so coarse that the trained stroke holds fewer than 16 output codes is refused,
as the input side refuses fewer than 16 ADC codes over the trained voltage range."""

import warnings

import pytest

from flann.cli import main
from flann.errors import SpecError
from flann.golden.model import load_model
from flann.hardware.fixed.spec import derive_spec


@pytest.fixture(scope="module")
def model(default_model_json):
    m = load_model(default_model_json)
    assert sorted(m.displacement_range_mm) == [-30.0, 30.0]   # a 60 mm stroke
    return m


def derive(model, **opts):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return derive_spec(model, **opts)


def test_sixteen_codes_over_the_stroke_is_the_floor(model):
    assert derive(model, output_lsb_mm=3.75).output_lsb_mm == 3.75      # 60 / 3.75 = 16 codes
    with pytest.raises(SpecError, match=r"--output-lsb-mm\) gives the trained displacement range "
                                        r"-30\.\.30 mm only 15 output codes \(need >= 16\)"):
        derive(model, output_lsb_mm=4.0)                                 # 60 / 4 = 15


def test_output_bits_that_leave_too_few_codes_name_output_bits(model):
    # 4 bits: +-7 codes over the model's +-30 mm (and a little more): LSB >= 30 / 7 mm, < 15 codes
    with pytest.raises(SpecError, match=r"from --output-bits\).*\(need >= 16\): use more --output-bits"):
        derive(model, output_bits=4)


def test_gen_refuses_a_100mm_output_step_with_one_line(tmp_path, capsys, default_model_json):
    out = tmp_path / "g"
    try:
        rc = main(["gen", str(default_model_json), "-o", str(out), "--output-lsb-mm", "100"])
    except SystemExit as exc:
        rc = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("error: ")
    assert "output_lsb_mm = 100 mm (--output-lsb-mm)" in err[0] and "only 0.6 output codes" in err[0]
    assert not out.exists() or not any(out.iterdir())
