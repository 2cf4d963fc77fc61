"""``flann diagnose``: locate and name the physics missing between simulation and recordings."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from ..argtypes import bounded, png_path
from ..diagnose import diagnose
from ..diagnose.data import MAX_POINTS, shared_reading
from ..diagnose.demo import demo_table, run_demo
from ..diagnose.report import format_text, plot, to_json
from ..diagnose.waveform import diagnose_waveforms, format_wave_text, is_waveform_csv, plot_wave, wave_to_json
from ..errors import FlannError
from ..physics.sensor import load_sensor
from ..recordings import read_recordings
from ..recordings.waveform import read_waveforms
from .common import add_common, emit_json, json_to_stdout, json_word_as_input, on_terminal

HELP = "locate and name the physics missing between simulation and recordings"


def add_arguments(p) -> None:
    p.add_argument("recordings", nargs="?", help="recordings CSV (displacement_mm, voltage_v, "
                   "optional direction, time_s, temperature_c), or a waveform recording "
                   "(time_s, sec_a_v, sec_b_v, displacement_mm, optional exc_v; docs/waveforms.md)")
    p.add_argument("--sensor", metavar="SENSOR.toml",
                   help="sensor description (flann-sensor/1, a .toml file), or the ID of one sensor in "
                        "a file of several (its sensor column); a description's geometry is then taken as "
                        "known and only gain and origin are calibrated (default: the paper's "
                        "LVDT with geometry calibrated to the recordings); for a waveform recording, the "
                        "phase its secondaries should have")
    p.add_argument("--plot", metavar="OUT.png", type=png_path, help="residuals before/after, mismatch shaded")
    p.add_argument("--demo", action="store_true",
                   help="run the concealed-effect demonstration (simulated recordings) and "
                        "print the table")
    p.add_argument("--limits", action="store_true",
                   help="with --demo: also measure detection limits (slow: many simulations)")
    p.add_argument("--max-points", type=bounded(int, 0), default=MAX_POINTS, metavar="N",
                   help="diagnose a recording of more rows than N on about N means of "
                        "neighbouring readings of a pass (the report says so); 0: every row "
                        "(time and memory grow quickly; default %(default)d)")
    add_common(p, json="the diagnosis")


def _progress(args):
    if not on_terminal(args):  # progress is for a person watching, not for logs
        return None

    def show(msg: str) -> None:
        print(f"  {msg}", file=sys.stderr, flush=True)

    return show


def run(args) -> int:
    if args.demo:
        if args.recordings or args.sensor or args.plot:
            raise FlannError("--demo takes no recordings, --sensor or --plot (it simulates its own)")
        results = run_demo(progress=_progress(args), limits=args.limits)
        if args.json:
            obj = [r.to_json() for r in results.cases] + [r.to_json() for r in results.independent]
            if results.limits or results.alarms or results.independent_alarms:
                obj = {"cases": obj, "false_alarms": results.alarms,
                       "detection_limits": results.limits,
                       "independent_false_alarms": results.independent_alarms,
                       "independent_detection_limits": results.independent_limits}
            emit_json(args, obj)
        if not json_to_stdout(args):
            print(demo_table(results), end="")
        return 0 if results.all_right else 1

    json_word_as_input(args, "recordings")   # `flann diagnose --json rec.csv`
    if not args.recordings:
        raise FlannError("diagnose needs a recordings CSV (or --demo)")

    # --sensor names a sensor description (a file) or the ID of a sensor in a multi-sensor file
    sensor_id = args.sensor if args.sensor and not (args.sensor.endswith(".toml") or Path(args.sensor).exists()) \
        else None
    sensor = load_sensor(args.sensor) if args.sensor and sensor_id is None else None
    if is_waveform_csv(args.recordings):
        wave = read_waveforms(args.recordings, announce=not args.quiet)
        wd = diagnose_waveforms(wave, sensor=sensor)
        return _report(args, wave_to_json(wd), format_wave_text(wd), lambda path: plot_wave(wd, path))
    rec, said = shared_reading(read_recordings(args.recordings, announce=not args.quiet, sensor=sensor_id))
    dg = diagnose(rec, sensor=sensor, progress=_progress(args),
                  max_points=args.max_points)
    for line in said:   # what train says of the same readings, once the recording is diagnosed
        warnings.warn(line)
    return _report(args, to_json(dg), format_text(dg), lambda path: plot(dg, path))


def _report(args, obj: dict, text: str, draw) -> int:
    """The plot, then the JSON or the text; both reports are built before any file is written,
    so a failure leaves no output behind."""
    if args.plot:
        draw(args.plot)
    if not emit_json(args, obj):
        print(text, end="")
    return 0
