"""--mult-digit-bits sets the shift-add multiplier's digit: given with another multiplier style it
would be recorded in the manifest and used nowhere, so it is refused in one line."""

from __future__ import annotations

import json

import pytest


@pytest.mark.parametrize("command", ["gen", "sim", "trace"])
@pytest.mark.parametrize("digit", ["4", "2"])   # the default value given is given too
def test_digit_with_the_lut_multiplier_is_refused(small_designs, tmp_path, cli, command, digit):
    out = tmp_path / "q"
    argv = [command, small_designs["model"], "--mult-style", "lut", "--mult-digit-bits", digit, "--input-bits", 8]
    rc, stdout, err = cli(argv + (["-o", out] if command == "gen" else []))
    assert rc == 2 and stdout == "" and len(err.strip().splitlines()) == 1
    assert err.startswith(f"error: --mult-digit-bits {digit}:") and "--mult-style lut" in err
    assert not out.exists()


def test_digit_with_shift_add_and_lut_alone_still_generate(small_designs, tmp_path, cli):
    model = small_designs["model"]
    assert cli(["gen", model, "-o", tmp_path / "s", "--mult-digit-bits", 4, "--input-bits", 8])[0] == 0
    assert json.loads((tmp_path / "s" / "manifest.json").read_text())["spec"]["mult_digit_bits"] == 4
    assert cli(["gen", model, "-o", tmp_path / "l", "--mult-style", "lut", "--input-bits", 8])[0] == 0
    assert json.loads((tmp_path / "l" / "manifest.json").read_text())["spec"]["mult_style"] == "lut"
