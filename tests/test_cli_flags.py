"""One flag vocabulary across the subcommands (flann.commands.common): ``-o/--output`` where a
command writes, ``--json [FILE]`` where it has a report, ``-j/--jobs N`` where work runs side
by side, ``--quiet`` everywhere; and what ``--json`` does with the word after it."""

import json
import os
import re

import pytest

from flann.cli import COMMANDS, _json_word_as_positional, build_parser
from flann.commands.common import cores_limited

# command -> the shared flags it has besides --quiet (which every command has)
FLAGS = {
    "train": {"output"},
    "predict": {"output"},
    "eval": {"json"},
    "paper": {"json"},
    "gen": {"output", "json"},
    "sim": {"json", "jobs"},
    "synth": {"output", "json", "jobs"},
    "explore": {"json"},
    "ise": {"output"},
    "trace": {"json", "jobs"},
    "simulate": {"output", "json"},
    "diagnose": {"json"},
    "calibrate": {"output", "jobs"},
}
SHOWN = {"output": r"-o \S+, --output \S+", "json": r"--json \[FILE\]", "jobs": r"-j N, --jobs N"}
HIDDEN_OUT = re.compile(r"(?<![\w-])--out(?![\w-])")


def test_every_command_is_in_the_table():
    assert set(FLAGS) == set(COMMANDS)


@pytest.mark.parametrize("command", sorted(FLAGS))
def test_help_lists_the_shared_flags(command, cli):
    rc, out, err = cli([command, "--help"])
    assert rc == 0, err
    text = " ".join(out.split())
    for flag, shown in SHOWN.items():
        assert bool(re.search(shown, out)) == (flag in FLAGS[command]), (command, flag)
    # one definition: the same words in every command's help
    assert "--quiet no progress or notes on stderr (warnings and errors still)" in text
    if "json" in FLAGS[command]:
        assert "as JSON; with FILE, write it there (the text as usual)" in text
    assert not HIDDEN_OUT.search(out), "--out is a hidden alias"


@pytest.mark.parametrize("command, argv", [
    ("gen", ["gen", "m.json", "--out", "d"]),
    ("calibrate", ["calibrate", "r.csv", "--out", "d", "--design", "fam"]),
])
def test_out_is_still_read_as_output(command, argv):
    args = build_parser(command).parse_args(argv)
    assert args.output == "d" and not hasattr(args, "out")


def test_gen_with_out_writes_the_design(cli, default_model_json, tmp_path):
    rc, out, err = cli(["gen", default_model_json, "--out", tmp_path / "d"])
    assert rc == 0, err
    assert (tmp_path / "d" / "manifest.json").is_file()


def test_gen_without_output_names_the_documented_flag(cli, default_model_json, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, _out, err = cli(["gen", default_model_json])
    assert rc == 2 and err.strip().splitlines() == [err.strip()]
    assert "-o/--output" in err and "--out " not in err


# -- the word after --json ------------------------------------------------------------------

@pytest.mark.parametrize("argv, other", [
    (["eval", "m.json", "r.csv", "--json"], None),
    (["eval", "m.json", "r.csv", "--json=f.json"], None),
    (["eval", "m.json", "r.csv", "--json", "-"], None),
    (["eval", "--json", "m.json", "r.csv"], ["eval", "--json=-", "m.json", "r.csv"]),
    (["eval", "--json", "--plot", "p.png"], None),
    (["x", "--", "--json", "w"], None),
])
def test_the_other_reading(argv, other):
    assert _json_word_as_positional(argv) == other


@pytest.mark.parametrize("argv, json_value, model", [
    (["eval", "m.json", "r.csv", "--json"], "-", "m.json"),
    (["eval", "m.json", "r.csv", "--json", "out.json"], "out.json", "m.json"),
    (["eval", "m.json", "r.csv", "--json=out.json"], "out.json", "m.json"),
    (["eval", "--json", "m.json", "r.csv"], "-", "m.json"),      # the inputs are not swallowed
    (["eval", "m.json", "--json", "r.csv"], "-", "m.json"),
    (["eval", "--json=out.json", "m.json", "r.csv"], "out.json", "m.json"),
])
def test_json_word_is_a_file_only_when_no_input_needs_it(argv, json_value, model):
    args = build_parser("eval").parse_args(argv)
    assert (args.json, args.model, args.recordings) == (json_value, model, "r.csv")


def test_json_before_a_missing_input_says_which_input(cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, _out, err = cli(["eval", "--json", "m.json"])
    assert rc == 2 and err.strip().splitlines() == [err.strip()]
    assert "required: recordings" in err


@pytest.mark.parametrize("where", ["after", "before", "between"])
def test_eval_json_on_stdout(where, cli, default_model_json, table1_csv):
    argv = {"after": ["eval", default_model_json, table1_csv, "--json"],
            "before": ["eval", "--json", default_model_json, table1_csv],
            "between": ["eval", default_model_json, "--json", table1_csv]}[where]
    rc, out, err = cli(argv)
    assert rc == 0, err
    res = json.loads(out)
    assert res["points"] == 13 and "compensated" in res and "raw" in res


@pytest.mark.parametrize("attached", [False, True])
def test_eval_json_file(attached, cli, default_model_json, table1_csv, tmp_path):
    path = tmp_path / "sub" / "eval.json"
    flag = [f"--json={path}"] if attached else ["--json", path]
    rc, out, err = cli(["eval", default_model_json, table1_csv, *flag])
    assert rc == 0, err
    assert json.loads(path.read_text())["points"] == 13
    assert "max error (mm)" in out        # the text report as without --json
    assert [p.name for p in path.parent.iterdir()] == ["eval.json"]   # written whole, no temporary left


def test_json_file_never_replaces_an_input(cli, default_model_json, table1_csv, tmp_path):
    rec = tmp_path / "rec.csv"
    rec.write_bytes(table1_csv.read_bytes())
    rc, _out, err = cli(["eval", default_model_json, rec, "--json", rec])
    assert rc == 2 and "also an input" in err
    assert rec.read_bytes() == table1_csv.read_bytes()


def test_diagnose_json_stdout_and_file(cli, table1_csv, tmp_path):
    rc, out, err = cli(["diagnose", table1_csv, "--json", "--quiet"])
    assert rc == 0, err
    on_stdout = json.loads(out)
    rc, out, err = cli(["diagnose", table1_csv, "--json", tmp_path / "d.json", "--quiet"])
    assert rc == 0, err
    assert json.loads((tmp_path / "d.json").read_text()) == on_stdout
    assert out.strip() and not out.lstrip().startswith("{")     # the text report
    # the recordings first after --json: diagnose cannot do without them, they are the input
    rc, out, err = cli(["diagnose", "--json", table1_csv, "--quiet"])
    assert rc == 0, err
    assert json.loads(out) == on_stdout


def test_gen_json_before_the_model(cli, default_model_json, tmp_path):
    rc, out, err = cli(["gen", "--json", default_model_json, "-o", tmp_path / "d", "--quiet"])
    assert rc == 0, err
    assert json.loads(out)["top"] and (tmp_path / "d" / "manifest.json").is_file()


def test_paper_json_file(cli, tmp_path):
    rc, out, err = cli(["paper", "--json", tmp_path / "p.json"])
    assert rc == 0, err
    assert json.loads((tmp_path / "p.json").read_text())["rows"]
    assert "Table 2 reproduced" in out


def test_simulate_fit_json_on_stdout(cli, table1_csv):
    rc, out, err = cli(["simulate", "--fit", table1_csv, "--json", "--quiet"])
    assert rc == 0, err
    assert json.loads(out)["points_used"] > 0


@pytest.mark.parametrize("mode", ["--describe", "--list-effects"])
def test_simulate_reports_as_json(mode, cli):
    rc, out, err = cli(["simulate", mode, "--json"])
    assert rc == 0, err
    assert json.loads(out)


# -- --quiet, -j ----------------------------------------------------------------------------

def test_quiet_leaves_stderr_empty(cli, tmp_path):
    rc, _out, err = cli(["simulate", "-o", tmp_path / "a.csv"])
    assert rc == 0 and "wrote" in err
    rc, _out, err = cli(["simulate", "-o", tmp_path / "b.csv", "--quiet"])
    assert rc == 0 and err == ""
    assert (tmp_path / "b.csv").read_bytes() == (tmp_path / "a.csv").read_bytes()


def test_quiet_train_says_nothing_but_writes_the_model(cli, table1_csv, tmp_path):
    rc, _out, err = cli(["train", table1_csv, "-o", tmp_path / "m.json", "--quiet"])
    # a verdict is said under --quiet too, and nothing else
    assert rc == 0 and len(err.splitlines()) == 1 and err.startswith("verdict: ")
    assert json.loads((tmp_path / "m.json").read_text())


@pytest.mark.parametrize("argv", [
    ["sim", "m.json", "-j", "0"],
    ["synth", "d", "-j", "0"],
    ["trace", "m.json", "-j", "0"],
], ids=lambda a: a[0])
def test_jobs_below_one_is_one_line(argv, cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, _out, err = cli(argv)
    assert rc == 2 and err.strip().splitlines() == [err.strip()]
    assert err.startswith("error: -j 0: must be >= 1")


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity") or len(os.sched_getaffinity(0)) < 2,
                    reason="needs a system that lets a process choose among 2+ cores")
def test_jobs_sets_the_shard_count():
    from flann.verify.shards import cores

    before = cores()
    with cores_limited(1):
        assert cores() == 1
    with cores_limited(before + 5), cores_limited(None):
        assert cores() == before
    assert cores() == before
