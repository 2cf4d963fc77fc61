"""flann ise: xtclsh project, UCF with a LOC for every port bit, FuseSoC core."""

import json
import re
import warnings
from pathlib import Path

import pytest
import yaml

from flann.cli import main
from flann.errors import FlannError
from flann.implement.ise import write_ise

FIX = Path(__file__).parent / "fixtures" / "synth" / "good"
# flann_top ports of the fixture, by hand: clk rst in_valid in_ready in_data(12) out_valid out_data(18) out_sat
NETS = (["clk", "rst", "in_valid", "in_ready", "out_valid", "out_sat"]
        + [f"in_data<{i}>" for i in range(12)] + [f"out_data<{i}>" for i in range(18)])


def test_cli_writes_the_handoff(tmp_path, capsys):
    out = tmp_path / "ise"
    assert main(["ise", str(FIX), "--device", "xc2s200-pq208-5", "-o", str(out), "--no-timing-check"]) == 0
    assert "xtclsh flann_top.tcl" in capsys.readouterr().out
    for name in ("flann_top.tcl", "flann_top.ucf", "flann_top.core", "README.txt", "src/flann_top.vhd"):
        assert (out / name).is_file(), name
    assert (out / "src/flann_top.vhd").read_bytes() == (FIX / "flann_top.vhd").read_bytes()


def test_ucf_pins_every_port_bit_once(tmp_path):
    write_ise(FIX, "xc2s200-pq208-5", tmp_path, clock_mhz=50)
    ucf = (tmp_path / "flann_top.ucf").read_text()
    locs = dict(re.findall(r'^NET "([^"]+)" LOC = "(P\d+)";', ucf, re.M))
    assert sorted(locs) == sorted(NETS)
    assert len(set(locs.values())) == len(locs)  # no pin used twice
    assert all(1 <= int(p[1:]) <= 208 for p in locs.values())
    assert locs["clk"] == "P77"  # GCK1 on PQ208
    assert 'PERIOD "clk" 20 ns' in ucf  # 1 / 50 MHz
    assert "EXAMPLE ASSIGNMENT" in ucf


def test_tcl_targets_the_part_and_lists_sources_in_order(tmp_path):
    write_ise(FIX, "xc2s100-pq208-6", tmp_path)
    tcl = (tmp_path / "flann_top.tcl").read_text()
    for line in ('project set family "Spartan2"', 'project set device "xc2s100"', 'project set package "pq208"',
                 'project set speed "-6"', 'xfile add "src/flann_top.vhd"', 'xfile add "flann_top.ucf"',
                 'set_option "ROM Style" "Block" "Synthesize - XST"', 'process run "Generate Programming File"'):
        assert line in tcl, line
    assert "project new flann_top.ise" in tcl  # ISE 10.1 project file, not .xise


def test_core_file_is_capi2_yaml(tmp_path):
    write_ise(FIX, "xc2s200-pq208-5", tmp_path)
    text = (tmp_path / "flann_top.core").read_text()
    assert text.startswith("CAPI=2:")
    core = yaml.safe_load(text)
    assert core["filesets"]["rtl"]["files"] == ["src/flann_top.vhd"]
    assert core["targets"]["synth"]["tools"]["ise"]["device"] == "xc2s200"
    assert core["targets"]["default"]["toplevel"] == "flann_top"


def test_period_follows_clock(tmp_path):
    write_ise(FIX, "xc2s200-pq208-5", tmp_path, clock_mhz=40)
    assert 'PERIOD "clk" 25 ns' in (tmp_path / "flann_top.ucf").read_text()


def test_other_packages_get_no_pin_map(tmp_path, capsys):
    # DS001 user I/O chart: XC2S100 comes in TQ144, XC2S15 in VQ100/TQ144/CS144 but not PQ208
    assert main(["ise", str(FIX), "--device", "xc2s100-tq144-5", "-o", str(tmp_path / "a"),
                 "--no-timing-check"]) == 0
    ucf = (tmp_path / "a" / "flann_top.ucf").read_text()
    assert 'PERIOD "clk" 20 ns' in ucf
    assert "LOC" not in ucf.replace("no LOC", "").replace("add a LOC", "")
    assert 'project set package "tq144"' in (tmp_path / "a" / "flann_top.tcl").read_text()
    write_ise(FIX, "xc2s15-vq100-5", tmp_path / "b")
    assert main(["ise", str(FIX), "--device", "xc2s15-pq208-5", "-o", str(tmp_path / "c")]) == 2
    assert "not offered in pq208" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()


def test_small_device_in_pq208_warns(tmp_path):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        write_ise(FIX, "xc2s30-pq208-5", tmp_path / "b")
    assert any("132 user I/O" in str(x.message) for x in w)


@pytest.mark.synth
def test_period_lowered_to_the_estimate(tmp_path, capsys):
    # 200 MHz is above anything a Spartan-II path with a LUT and a routed net reaches:
    # TCKO 1.3 + route + TILO 0.7 + setup > 3 ns (-5)
    assert main(["ise", str(FIX), "--device", "xc2s200-pq208-5", "-o", str(tmp_path), "--clock-mhz", "200"]) == 0
    err = capsys.readouterr().err
    m = re.search(r"estimated at ([\d.]+) MHz .*PERIOD written for (\d+) MHz", err)
    assert m, err
    fmax, safe = float(m.group(1)), int(m.group(2))
    assert safe < 200 and safe * 1.2 <= fmax
    period = float(re.search(r'PERIOD "clk" ([\d.]+) ns', (tmp_path / "flann_top.ucf").read_text()).group(1))
    assert abs(period - 1000.0 / safe) < 1e-3


@pytest.mark.synth
def test_period_kept_when_met(tmp_path, capsys):
    assert main(["ise", str(FIX), "--device", "xc2s200-pq208-5", "-o", str(tmp_path), "--clock-mhz", "10"]) == 0
    assert "warning" not in capsys.readouterr().err
    assert 'PERIOD "clk" 100 ns' in (tmp_path / "flann_top.ucf").read_text()


def test_missing_manifest(tmp_path, capsys):
    assert main(["ise", str(tmp_path), "-o", str(tmp_path / "o")]) == 2
    assert "manifest.json not found" in capsys.readouterr().err


def test_pin_map_spills_inputs_onto_spare_output_pins():
    """46 input bits (a family's cfg port: 1 + 4 + 32 beside in_valid and an 8-bit in_data) and
    14 output bits: every bit gets its own pin, inputs take every left-side pin first."""
    from flann.hardware.target import parse_part
    from flann.implement.ise import INPUT_PINS, OUTPUT_PINS, Port, pin_map

    ports = [Port("clk", "in", 0), Port("rst", "in", 0), Port("in_valid", "in", 0), Port("in_ready", "out", 0),
             Port("in_data", "in", 8), Port("out_valid", "out", 0), Port("out_data", "out", 11),
             Port("out_sat", "out", 0), Port("cfg_we", "in", 0), Port("cfg_addr", "in", 4),
             Port("cfg_data", "in", 32)]
    rows, unplaced = pin_map(ports, parse_part("xc2s200-pq208-5"))
    locs = [loc for _, loc, _ in rows]
    assert len(rows) == 2 + 46 + 14 and len(set(locs)) == len(locs) and unplaced == []
    ins = {loc for _, loc, d in rows if d == "in"}
    assert set(INPUT_PINS) <= ins and len(ins - set(INPUT_PINS)) == 10
    assert ins - set(INPUT_PINS) <= set(OUTPUT_PINS)


def _placed_whole_or_listed(ports, rows, unplaced):
    """Every bit of a placed port has a LOC, an unplaced port none; no pin twice."""
    nets = [net for net, _, _ in rows]
    locs = [loc for _, loc, _ in rows]
    assert len(set(locs)) == len(locs)
    assert len(set(nets)) == len(nets)
    for p in ports:
        if p in unplaced:
            assert not set(p.bits()) & set(nets), p
        else:
            assert set(p.bits()) <= set(nets), p


def test_pin_map_beyond_its_pins_leaves_whole_ports_to_ise():
    from flann.hardware.target import parse_part
    from flann.implement.ise import INPUT_PINS, OUTPUT_PINS, Port, pin_map

    assert len(INPUT_PINS) + len(OUTPUT_PINS) == 70
    # 71 bits beside clk and rst; before cfg_data: 14 input + 14 output bits, 42 pins left
    # for its 43 bits, so it alone has no LOC (not 42 of its bits)
    ports = [Port("clk", "in", 0), Port("rst", "in", 0), Port("in_valid", "in", 0), Port("in_ready", "out", 0),
             Port("in_data", "in", 8), Port("out_valid", "out", 0), Port("out_data", "out", 11),
             Port("out_sat", "out", 0), Port("cfg_we", "in", 0), Port("cfg_addr", "in", 4),
             Port("cfg_data", "in", 43)]
    rows, unplaced = pin_map(ports, parse_part("xc2s200-pq208-5"))
    assert unplaced == [ports[-1]]
    assert len(rows) == 2 + 14 + 14
    _placed_whole_or_listed(ports, rows, unplaced)
    # a port after one left unplaced still gets pins when they are left: 42 - 40 = 2 for cfg_crc
    ports = [*ports[:-1], Port("cfg_data", "in", 43), Port("cfg_mask", "in", 40), Port("cfg_crc", "out", 2)]
    rows, unplaced = pin_map(ports, parse_part("xc2s200-pq208-5"))
    assert [p.name for p in unplaced] == ["cfg_data"]
    assert len(rows) == 2 + 14 + 14 + 40 + 2
    _placed_whole_or_listed(ports, rows, unplaced)


def test_ports_must_match_the_vhdl(tmp_path):
    import json
    import shutil

    d = tmp_path / "d"
    shutil.copytree(FIX, d)
    man = json.loads((d / "manifest.json").read_text())
    man["output_bits"] = 16  # the VHDL says 18
    (d / "manifest.json").write_text(json.dumps(man))
    with pytest.raises(FlannError, match="declares ports"):
        write_ise(d, "xc2s200-pq208-5", tmp_path / "o")


STUBS = """\
proc project {args} {
    if {[lindex $args 0] eq "set" && [lindex $args 1] eq "ROM Style"} { error "unknown property" }
    puts "project $args"
}
proc xfile {args} { puts "xfile $args" }
proc process {args} { puts "process $args" }
"""


@pytest.mark.skipif(__import__("shutil").which("tclsh") is None, reason="tclsh not installed")
def test_tcl_runs_under_tclsh_with_stubbed_ise_commands(tmp_path):
    import subprocess

    write_ise(FIX, "xc2s200-pq208-5", tmp_path)
    (tmp_path / "run.tcl").write_text(STUBS + "source flann_top.tcl\n")
    r = subprocess.run(["tclsh", "run.tcl"], cwd=tmp_path, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "project new flann_top.ise"
    assert "project set family Spartan2" in lines and "project set device xc2s200" in lines
    assert lines.index("xfile add src/flann_top.vhd") < lines.index("xfile add flann_top.ucf")
    assert any(ln.startswith('warning: option "ROM Style"') for ln in lines)  # skipped, not fatal
    assert lines[-2:] == ["process run {Generate Programming File}", "project close"]


@pytest.fixture
def family14(tmp_path, capsys):
    """A family design of two simulated sensors with a 14-bit ADC: its cfg write port makes
    more port bits than the example pin map has pins (the user's report: every PQ208 part refused)."""
    repo = Path(__file__).resolve().parents[2]
    recs = []
    for seed in (1, 2):
        recs.append(tmp_path / f"s{seed}.csv")
        assert main(["simulate", str(repo / "data" / "sensors" / "paper_lvdt.toml"), "--sweeps", "1", "--step-mm",
                     "0.5", "--noise-v", "0.002", "--seed", str(seed), "-o", str(recs[-1])]) == 0
    assert main(["gen", "--family", *map(str, recs), "--input-bits", "14", "-o", str(tmp_path / "fam")]) == 0
    capsys.readouterr()
    return tmp_path / "fam"


def _entity_ports(directory: Path) -> dict[str, int]:
    """name -> bits of the top entity's ports, read from its VHDL here (not by flann)."""
    top = json.loads((directory / "manifest.json").read_text())["top"]
    text = (directory / f"{top}.vhd").read_text()
    body = re.search(rf"entity {top} is\s+port \((.*?)\);\s+end entity", text, re.S).group(1)
    ports = {}
    for name, hi in re.findall(r"(\w+)\s*:\s*(?:in|out)\s+std_logic(?:_vector\((\d+) downto 0\))?", body):
        ports[name] = int(hi) + 1 if hi else 1
    return ports


def test_ports_beyond_the_pin_map_are_written_unplaced(family14, tmp_path, capsys):
    ports = _entity_ports(family14)
    assert sum(ports.values()) - 2 > 70   # beside clk and rst: more than the example pins
    out = tmp_path / "ise"
    assert main(["ise", str(family14), "--device", "xc2s200-pq208-5", "-o", str(out), "--no-timing-check"]) == 0
    err = capsys.readouterr().err
    ucf_path = next(out.glob("*.ucf"))
    ucf = ucf_path.read_text()
    assert 'PERIOD "clk" 20 ns' in ucf
    locs = re.findall(r'^NET "([^"<]+)(?:<(\d+)>)?" LOC = "(P\d+)";', ucf, re.M)
    pins = [pin for _, _, pin in locs]
    assert len(set(pins)) == len(pins)                  # no pin used twice
    loc_bits = {}
    for name, _, _ in locs:
        loc_bits[name] = loc_bits.get(name, 0) + 1
    listed = re.findall(r"^#\s+(\w+)(?:<\d+:0>)? \((?:in|out), (\d+) bits?\)$",
                        ucf.split("NO LOC", 1)[-1], re.M)
    assert listed                                        # some port is left to ISE
    for name, bits in ports.items():                     # each port: all bits LOC'd, or listed
        if name in loc_bits:
            assert loc_bits[name] == bits, name
            assert name not in dict(listed), name
        else:
            assert dict(listed).get(name) == str(bits), name
    assert loc_bits["clk"] == 1 and "in_data" in loc_bits and "out_data" in loc_bits
    # one warning line, naming the UCF just written and the ports left without a LOC
    warning = [ln for ln in err.splitlines() if ln.startswith("warning:")]
    assert len(warning) == 1 and str(ucf_path) in warning[0]
    assert all(name in warning[0] for name, _ in listed)
    assert "error" not in err
    assert "NO LOC" in (out / "README.txt").read_text()


def test_unplaced_warning_only_for_a_written_ucf(family14, tmp_path, capsys):
    # an existing directory that is not a flann ISE project is not overwritten: no warning
    # may point into it
    out = tmp_path / "taken"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    rc = main(["ise", str(family14), "--device", "xc2s200-pq208-5", "-o", str(out), "--no-timing-check"])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.splitlines()) == 1 and err.startswith("error: ")
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


@pytest.mark.parametrize("port", ["in std_logic_vector(7 downto 0)", {"direction": "inout", "width": 8},
                                  {"direction": "in", "width": -1}, {"direction": "in", "width": True},
                                  {"direction": "in"}])
def test_extra_ports_are_read_as_data(family14, tmp_path, cli, port):
    """The manifest lists a datapath's extra ports as direction and width (what flann gen
    writes); anything else is refused in one line, nothing written."""
    man = json.loads((family14 / "manifest.json").read_text())
    assert man["cfg_port"]["ports"]["cfg_we"] == {"direction": "in", "width": 0}
    assert man["cfg_port"]["ports"]["cfg_data"]["width"] == _entity_ports(family14)["cfg_data"]
    man["cfg_port"]["ports"]["cfg_addr"] = port
    (family14 / "manifest.json").write_text(json.dumps(man))
    rc, _out, err = cli(["ise", family14, "-o", tmp_path / "ise"])
    assert rc == 2 and err.startswith("error: manifest.json: cfg_port.ports.cfg_addr") and len(err.splitlines()) == 1
    assert not (tmp_path / "ise").exists()
