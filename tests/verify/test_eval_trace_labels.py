"""Labels that say what a figure is: eval's two |hardware - float| figures, and which member of
a family design flann trace traced; the README's eval row names the design it refuses."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_eval_says_what_each_hardware_minus_float_includes(small_designs, cli):
    argv = ["eval", small_designs["model"], small_designs["rec"], "--design", small_designs["dir"] / "fixed"]
    rc, out, err = cli([*argv, "--json"])
    assert rc == 0, err
    hw = json.loads(out)["hardware"]
    rc, out, err = cli(argv)
    assert rc == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("hardware: "))
    m = re.search(r"\|hardware - float\| <= (\S+) mm at the readings \(ADC quantisation included\), (\S+) mm at "
                  r"the readings' ADC codes$", line)
    assert m, line
    assert float(m.group(1)) == float(f"{hw['max_abs_hardware_minus_float_mm']:.4g}")
    assert float(m.group(2)) == float(f"{hw['max_abs_hardware_minus_float_at_codes_mm']:.4g}")


def test_eval_of_a_float18_design_judges_its_twin(small_designs, cli):
    """The float18 design has no output LSB: its twin at the ADC codes is judged against the float
    model like every datapath's, and the README's row says every datapath."""
    rc, out, err = cli(["eval", small_designs["model"], small_designs["rec"], "--design",
                        small_designs["dir"] / "float18", "--json"])
    assert rc == 0, err
    rep = json.loads(out)
    assert rep["hardware"]["number_format"] == "float18" and rep["hardware"]["output_lsb_mm"] is None
    assert rep["verdict"]["status"] in ("good", "bad") and rep["verdict"]["checks"]
    row = next(ln for ln in (ROOT / "README.md").read_text().splitlines() if ln.startswith("| `flann eval "))
    assert "every datapath" in row


def test_trace_of_a_family_names_the_datapath_and_member(small_designs, cli):
    fam = small_designs["dir"] / "family"
    first = json.loads((fam / "manifest.json").read_text())["images"][0]["name"]
    rc, out, err = cli(["trace", fam])
    assert rc == 0, err
    assert out.splitlines()[0].startswith(f"flann trace (family: member {first}, the memory's initial weights "
                                          "from init_model.json): ")
    rc, out, err = cli(["trace", fam, "--json"])
    d = json.loads(out)
    assert (d["format"], d["datapath"]) == ("fixed", "family")
    assert d["traced"] == f"family: member {first}, the memory's initial weights from init_model.json"


def test_trace_of_a_one_model_design_names_its_datapath(small_designs, cli):
    for name in ("fixed", "float18"):
        rc, out, err = cli(["trace", small_designs["dir"] / name])
        assert rc == 0 and out.startswith(f"flann trace ({name}): "), err
