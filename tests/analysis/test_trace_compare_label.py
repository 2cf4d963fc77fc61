"""flann trace --compare --at CSV --plot names the CSV's inputs in the legend (it said "Table 1
inputs" whatever the file)."""

from flann.commands import trace as trace_command


def test_the_compare_plot_names_the_recordings_it_marks(cli, tmp_path, monkeypatch, small_designs):
    seen = {}
    monkeypatch.setattr(trace_command, "plot_compare", lambda *a, **kw: seen.update(kw))
    rec = tmp_path / "bench_run_7.csv"
    rec.write_text(small_designs["rec"].read_text())
    rc, out, err = cli(["trace", small_designs["model"], "--compare", "--input-bits", "8", "--at", rec,
                        "--plot", tmp_path / "t.png"])
    assert rc == 0, err
    assert seen["points_label"] == "inputs of bench_run_7.csv"
