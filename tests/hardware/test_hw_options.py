"""One home for the generator defaults: the options object, argparse built from it."""

import argparse

import pytest

from flann.cli import build_parser
from flann.errors import SpecError
from flann.hardware import options as gen_options
from flann.hardware.fixed.spec import derive_spec
from flann.hardware.options import GenOptions
from flann.hardware.target import DEFAULT_PART, parse_part
from flann.golden.model import load_model


@pytest.mark.parametrize("command", ["gen", "sim", "trace"])
def test_every_command_parses_to_the_library_defaults(command):
    argv = [command, "m.json"] + (["-o", "x"] if command == "gen" else [])
    args = build_parser(command).parse_args(argv)
    assert gen_options.from_args(args) == GenOptions()


def test_flags_keep_their_names_and_switch_the_right_field():
    p = argparse.ArgumentParser()
    gen_options.add_arguments(p)
    o = gen_options.from_args(p.parse_args(["--no-clamp", "--no-interp", "--lanes", "3", "--mult-style", "lut",
                                            "--device", "xc2s50-pq208-6", "--input-lsb-v", "0.002"]))
    assert (o.clamp, o.interp, o.lanes, o.mult_style, o.device, o.input_lsb_v) == \
        (False, False, 3, "lut", "xc2s50-pq208-6", 0.002)
    assert o.changed() == {"clamp": False, "interp": False, "lanes": 3, "mult_style": "lut",
                           "device": "xc2s50-pq208-6", "input_lsb_v": 0.002}
    with pytest.raises(SystemExit):
        p.parse_args(["--mult-style", "dsp"])


def test_default_part_is_orderable_and_is_what_a_spec_gets(default_model_json):
    assert parse_part(DEFAULT_PART).name == DEFAULT_PART
    model = load_model(default_model_json)
    assert derive_spec(model).device == DEFAULT_PART
    assert derive_spec(model, GenOptions(lanes=2)) == derive_spec(model, lanes=2)


def test_unknown_option_names_itself():
    with pytest.raises(SpecError, match="lane_count"):
        GenOptions.of(lane_count=2)
