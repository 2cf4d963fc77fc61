"""flann ise DIR targets the part DIR was generated for (its manifest's), as flann synth does,
unless --device says otherwise; a package without the example pin map gets a UCF without LOCs."""

from __future__ import annotations

import re
import warnings

from flann.implement.ise import write_ise


def _design(cli, small_designs, out, device):
    rc, _out, err = cli(["gen", small_designs["model"], "-o", out, "--input-bits", 8, "--device", device])
    assert rc == 0, err
    return out


def test_ise_takes_the_manifests_part(small_designs, tmp_path, cli):
    d = _design(cli, small_designs, tmp_path / "d", "xc2s30-vq100-5")
    rc, out, err = cli(["ise", d, "-o", tmp_path / "i", "--no-timing-check"])
    assert rc == 0 and "for xc2s30-vq100-5" in out, err
    tcl = (tmp_path / "i" / "flann_top.tcl").read_text()
    assert 'project set device "xc2s30"' in tcl and 'project set package "vq100"' in tcl
    ucf = (tmp_path / "i" / "flann_top.ucf").read_text()
    # the PQ208 pin map is not written, as for --device on another package
    assert not re.search(r'LOC\s*=', ucf) and "PIN MAP: NONE" in ucf and "VQ100" in ucf
    # --device still chooses another part
    rc, out, err = cli(["ise", d, "-o", tmp_path / "j", "--no-timing-check", "--device", "xc2s200-pq208-5"])
    assert rc == 0 and "for xc2s200-pq208-5" in out, err
    assert re.search(r'NET "clk" LOC = "P77";', (tmp_path / "j" / "flann_top.ucf").read_text())


def test_write_ise_defaults_to_the_manifests_part(small_designs, tmp_path, cli):
    d = _design(cli, small_designs, tmp_path / "d", "xc2s50-pq208-6")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_ise(d, out_dir=tmp_path / "i")
    tcl = (tmp_path / "i" / "flann_top.tcl").read_text()
    assert 'project set device "xc2s50"' in tcl and 'project set speed "-6"' in tcl
