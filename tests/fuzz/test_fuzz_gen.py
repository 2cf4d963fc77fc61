"""Generator fuzzing, small fixed-seed set (the larger run: bench/fuzz_gen.py)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from flann.verify.fuzz import draw_case, run_cases

pytestmark = [pytest.mark.sim,
              pytest.mark.skipif(shutil.which("ghdl") is None, reason="needs ghdl (scripts/ensure_tools.sh)")]


def test_draws_cover_the_option_space():
    """The generator of cases reaches every option value it claims to (no simulation)."""
    rng = np.random.default_rng(0)
    seen = {"format": set(), "lanes": set(), "mult_style": set(), "interp": set(), "input_bits": set()}
    for i in range(200):
        _, c = draw_case(rng, i)
        seen["format"].add(c.number_format)
        seen["interp"].add(c.options["interp"])
        seen["input_bits"].add(c.options["input_bits"])
        if c.number_format == "fixed":
            seen["lanes"].add(c.options["lanes"])
            seen["mult_style"].add(c.options["mult_style"])
        assert 3 <= c.terms <= 51
    assert seen["format"] == {"fixed", "float18"} and seen["lanes"] == {1, 2, 3}
    assert seen["mult_style"] == {"shiftadd", "lut"} and seen["interp"] == {True, False}
    assert seen["input_bits"] == {8, 10, 12, 14, 16}


def test_fixed_seed_cases_agree(tmp_path):
    cases = run_cases(seed=7, n=3, work=tmp_path)
    for c in cases:
        assert c.outcome in ("ok", "refused"), (c.index, c.options, c.detail)
        if c.outcome == "ok":
            assert c.mismatches == 0 and c.codes_hdl > 0
            assert c.codes_twin == 1 << c.options["input_bits"]
    assert sum(c.outcome == "ok" for c in cases) >= 2
