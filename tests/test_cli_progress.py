"""Progress lines go to a terminal only: a log or a pipe gets the result and nothing else."""

from flann.cli import main
from flann.analysis import explore
from flann.commands import explore as explore_command


def test_explore_keeps_progress_out_of_a_log(monkeypatch, capsys, default_model_json):
    seen = {}

    def fake(*a, progress=True, **kw):
        seen["explore"] = progress
        return []

    def fake_seed(*a, progress=True, **kw):
        seen["seed"] = progress
        return []

    monkeypatch.setattr(explore, "explore", fake)
    monkeypatch.setattr(explore, "seed_rows", fake_seed)
    monkeypatch.setattr(explore_command, "float18_rows", fake_seed)
    assert main(["explore", str(default_model_json), "--json"]) == 0
    assert main(["explore", str(default_model_json), "--json", "--seed-only"]) == 0
    assert seen == {"explore": False, "seed": False}     # capsys: stderr is not a terminal
