"""Measure the project's current figures by running flann, and write docs/results.md.

    .venv/bin/python bench/results.py            # every step (synthesis and simulation included)
    .venv/bin/python bench/results.py --quick    # without the GHDL/Yosys steps
    .venv/bin/python bench/results.py --out FILE # write elsewhere than docs/results.md

Every figure in the page comes from a flann command's JSON, run here; nothing is typed by hand.
A step that fails writes "failed: <reason>" in its place and the script goes on.  The page holds
no timestamps or durations, so two runs on the same tree diff cleanly; the time each step took
goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "docs" / "results.md"
STEP_TIMEOUT_S = 3600

# the five-command flow of the README, as a user types it (run in a scratch directory)
SENSOR = "data/sensors/paper_lvdt.toml"
FLOW = [
    ["simulate", SENSOR, "--sweeps", "2", "--step-mm", "0.5", "--noise-v", "0.002", "-o", "rec.csv"],
    ["train", "rec.csv", "-o", "model.json", "--input-bits", "12"],
    ["gen", "model.json", "-o", "my_design", "--input-bits", "12"],
]
EVAL = ["eval", "model.json", "rec.csv", "--design", "my_design"]
HELD_OUT = ["simulate", SENSOR, "--sweeps", "2", "--step-mm", "0.1", "--noise-v", "0", "--seed", "9",
            "-o", "held.csv"]
EVAL_HELD = ["eval", "model.json", "held.csv", "--design", "my_design"]
SIM = ["sim", "my_design"]
SYNTH = ["synth", "hdl"]
F18_GEN = ["gen", "data/default_model.json", "--format", "float18", "-o", "f18_design"]
F18_SYNTH = ["synth", "f18_design"]
PAPER_MODEL = ["train", "data/paper_table1.csv", "--terms", "51", "--normalise", "none", "-o", "paper_model.json"]
TRACE = ["trace", "paper_model.json", "--format", "float18", "--compare"]
FIT = ["simulate", "--fit", "data/paper_table1.csv"]
DEMO = ["diagnose", "--demo", "--quiet"]

BENCH_SCRIPTS = [
    ("bench/results.py", "this page"),
    ("bench/bench_golden.py", "golden-model throughput, 51 terms, one core"),
    ("bench/bench_sim.py", "exhaustive verification speed (`--engine ghdl\\|verilator`, `--input-bits`, `--netlist`)"),
    ("bench/fuzz_gen.py", "generator fuzzing: random configurations, refusals, mismatches"),
    ("bench/hw_tradeoffs.py", "what each generator option costs: error bound, twin error, LUT4, block RAMs, cycles"),
    ("bench/bench_float18.py", "fixed point against float18: resources and accuracy"),
    ("bench/physics_speed.py", "physics model speed"),
    ("bench/bench_diagnose.py", "diagnosis runtime on 2,001 points"),
    ("bench/diagnose_seeds.py", "identical sensors, 20 noise seeds per concealed effect: the same answer, the concealed set offered, spread against stated uncertainty"),
    ("bench/bench_calibrate.py", "production line with the paper's LVDT: sensors/min, CPU per sensor"),
    ("bench/bench_line.py", "production line without a sensor file, against a spec: verdicts, sensors/min"),
    ("bench/family_reach.py", "a family design's error against each member's own design"),
    ("bench/family_headroom.py", "sensors outside a family's gen set: calibrated or refused"),
    ("bench/recordings_memory.py", "`flann train` memory and time on long recordings"),
    ("bench/odd_members.py", "the forward curve's member kinds on sensors the project did not make"),
    ("bench/e2e_hardware.py", "hardware max error / physical limit on a closed-form sensor family"),
    ("bench/dense_lvdt_share.py", "share of a dense held-out sweep within +-0.06 mm"),
    ("bench/thermal_family.py", "temperature compensation on a closed-form family: drift raw, float, hardware"),
    ("bench/thermal_line.py", "production line with temperature: gen --family, sim, synth, calibrate"),
    ("bench/small_parts.py", "LUT4 and block RAMs of many designs on a small part"),
    ("bench/seams.sh", "every command's output into the next, on a sensor the project did not make"),
]


class StepFailed(Exception):
    """A step's one-line reason."""


def flann_exe() -> list[str]:
    exe = Path(sys.executable).parent / "flann"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("flann")
    if found:
        return [found]
    return [sys.executable, "-c", "import sys; from flann.cli import main; sys.exit(main())"]


def one_line(text: str) -> str:
    lines = [ln.strip() for ln in (text or "").splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("error:")]
    line = (errors or lines or ["no message"])[-1]
    line = line.replace("|", "/")
    return line if len(line) <= 200 else line[:197] + "..."


def flann(argv: list[str], cwd: Path, timeout: float = STEP_TIMEOUT_S, ok_codes=(0,)) -> str:
    """Run one flann command; its stdout, or StepFailed with its one-line reason.  A check that
    failed (exit 1: a mismatch, a wrong demo case) still reports: with ``ok_codes=(0, 1)`` its
    stdout is returned, and the page shows the verdict."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    t0 = time.monotonic()
    print(f"[results] flann {' '.join(argv)}", file=sys.stderr, flush=True)
    try:
        p = subprocess.run(flann_exe() + argv, cwd=cwd, env=env, capture_output=True, text=True,
                           timeout=timeout, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise StepFailed(f"flann {argv[0]} did not finish in {timeout:.0f} s") from None
    except OSError as e:
        raise StepFailed(f"flann could not be started: {e}") from None
    print(f"[results]   {time.monotonic() - t0:.1f} s, exit {p.returncode}", file=sys.stderr, flush=True)
    if p.returncode not in ok_codes or (p.returncode != 0 and not p.stdout.strip()):
        raise StepFailed(f"flann {argv[0]} exit {p.returncode}: {one_line(p.stderr)}")
    return p.stdout


def parse_json(text: str):
    start = min((i for i in (text.find("{"), text.find("[")) if i >= 0), default=-1)
    if start < 0:
        raise StepFailed("no JSON on stdout")
    try:
        return json.JSONDecoder().raw_decode(text[start:])[0]
    except ValueError as e:
        raise StepFailed(f"unreadable JSON: {e}") from None


def flann_json(argv: list[str], cwd: Path, to_file: str | None = None):
    """``--json`` on stdout (put last, so no positional is taken for its file), or ``--json FILE``."""
    if to_file:
        flann([*argv, "--json", to_file], cwd, ok_codes=(0, 1))
        try:
            return json.loads((cwd / to_file).read_text())
        except (OSError, ValueError) as e:
            raise StepFailed(f"{to_file}: {e}") from None
    return parse_json(flann([*argv, "--json"], cwd, ok_codes=(0, 1)))


def tool_version(cmd: list[str]) -> str:
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired):
        return "not found"
    if p.returncode != 0:
        return "not found"
    lines = [ln.strip() for ln in (p.stdout or p.stderr).splitlines() if ln.strip()]
    return lines[0].replace("|", "/") if lines else "unknown"


# ---- formatting ---------------------------------------------------------------------------

def g(x, digits: int = 3) -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return f"{x:,}"
    if abs(x) >= 10 ** digits:
        return f"{x:,.0f}"
    return f"{x:.{digits}g}"


def cmd(argv: list[str]) -> str:
    return "`flann " + " ".join(argv) + "`"


def table(header: list[str], rows: list[list[str]], align: str | None = None) -> list[str]:
    align = align or "l" * len(header)
    sep = ["---:" if a == "r" else "---" for a in align]
    out = ["| " + " | ".join(header) + " |", "| " + " | ".join(sep) + " |"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out


class Step:
    """A measured step: its JSON, or the reason it failed; the time it took goes to stderr."""

    def __init__(self, name: str, fn, skip: str | None = None):
        self.name, self.value, self.error = name, None, None
        if skip:
            self.error = skip
            return
        t0 = time.monotonic()
        try:
            self.value = fn()
        except StepFailed as e:
            self.error = f"failed: {e}"
        except Exception as e:  # noqa: BLE001 -- a broken step is reported, the page still written
            self.error = f"failed: {type(e).__name__}: {one_line(str(e))}"
        TIMES.append((name, time.monotonic() - t0, self.error))

    @property
    def ok(self) -> bool:
        return self.error is None


TIMES: list[tuple[str, float, str | None]] = []


# ---- the sections -------------------------------------------------------------------------

def paper_section(s: Step) -> list[str]:
    out = ["## The seed paper's Table 2", "",
           f"{cmd(['paper', '--json'])}: LMS on raw volts as the paper did, weights and bias starting at 1. "
           "The reference is the paper's own Table 2 (its `paper_pct`).", ""]
    if not s.ok:
        return out + [s.error, ""]
    d = s.value
    try:
        from flann.golden.paper import PAPER_RAW_PCT
    except Exception:  # noqa: BLE001
        PAPER_RAW_PCT = None
    rows = [["raw sensor (its least-squares line)", f"{d['raw_linearity_pct']:.2f} %",
             "-" if PAPER_RAW_PCT is None else f"{PAPER_RAW_PCT:.2f} %",
             verdict_pct(d["raw_linearity_pct"], PAPER_RAW_PCT), "-"]]
    for r in d["rows"]:
        rows.append([str(r["terms"]), f"{r['linearity_pct']:.2f} %", f"{r['paper_pct']:.2f} %",
                     verdict_pct(r["linearity_pct"], r["paper_pct"]), f"{g(r['loo_max_error_mm'])} mm"])
    out += table(["terms", "% of linearity range (ours)", "paper", "verdict", "leave-one-out max error"],
                 rows, "lrrll")
    out += ["", f"Linearity tolerance: +-{g(d['tolerance_pct_fs'])} % of full scale. The 11- and 25-term "
            "rows are figures of unconverged LMS and move with the learning rate and epoch count, "
            "which the paper does not give (`flann paper --sensitivity` prints the grid).", ""]
    return out


def verdict_pct(ours, paper) -> str:
    if paper is None:
        return "-"
    d = ours - paper
    return "matches the paper" if abs(d) < 0.005 else f"differs by {d:+.2f} points"


def flow_section(ev: Step, held: Step, sim: Step) -> list[str]:
    out = ["## Your sensor in five commands", "",
           "The README's flow on the paper's LVDT from the physics simulator (two sweeps, 0.5 mm steps, "
           "2 mV noise), run in a scratch directory:", "", "```sh"]
    out += ["flann " + " ".join(a) for a in FLOW]
    out += ["flann " + " ".join(EVAL) + " --json", "flann " + " ".join(SIM) + " --json", "```", ""]
    out += [f"### Accuracy ({cmd(EVAL + ['--json'])})", ""]
    out += accuracy_table(ev, "the training recordings")
    out += [f"### On a noise-free held-out sweep ({cmd(HELD_OUT)}, then {cmd(EVAL_HELD + ['--json'])})", ""]
    out += accuracy_table(held, "0.1 mm steps, no noise, not used for training")
    out += [f"### Verification ({cmd(SIM + ['--json'])})", ""]
    if not sim.ok:
        return out + [sim.error, ""]
    d = sim.value
    rows = [["input codes tested", g(d.get("codes_tested")), "every code of the converter", "-"],
            ["mismatches against the bit-true twin", g(d.get("mismatches")), "0",
             "bit-exact" if d.get("mismatches") == 0 else "MISMATCHES"],
            ["max \\|HDL - float model\\|", f"{g(d.get('max_err_lsb'))} LSB = {g(d.get('max_err_mm'))} mm",
             "1 output LSB (the error budget)",
             "within the bound" if (d.get("max_err_lsb") or 0) <= 1 else "OVER the bound"],
            ["cycles per sample", g(d.get("cycles_per_sample")), "-", "-"],
            ["samples/s at the design's nominal clock", g(d.get("samples_per_s"), 4),
             f"{g((d.get('clock_hz') or 0) / 1e6)} MHz, not a timing result", "-"]]
    out += table(["figure", "value", "reference", "verdict"], rows, "lrll")
    return out + [""]


def accuracy_table(s: Step, what: str) -> list[str]:
    if not s.ok:
        return [s.error, ""]
    d = s.value
    raw, fl, hw = d.get("raw", {}), d.get("compensated", {}), d.get("hardware") or {}
    lim = hw.get("physical_limit_mm") or {}
    lsb = hw.get("output_lsb_mm")
    at_codes = hw.get("max_abs_hardware_minus_float_at_codes_mm")
    rows = [["raw sensor (least-squares line)", g(raw.get("max_error_mm")), g(raw.get("rms_error_mm")), "-",
             "-"],
            ["float model", g(fl.get("max_error_mm")), g(fl.get("rms_error_mm")),
             g(hw.get("float_ratio_to_limit")), improvement(raw, fl)],
            [f"hardware (bit-true twin, {hw.get('input_bits', '?')}-bit ADC codes)", g(hw.get("max_error_mm")),
             g(hw.get("rms_error_mm")), g(hw.get("ratio_to_limit")), improvement(raw, hw)]]
    out = [f"{g(d.get('points'))} points ({what}), full scale {g(d.get('full_scale_mm'))} mm.", ""]
    out += table(["", "max error (mm)", "RMS error (mm)", "max error / physical limit", "verdict"], rows, "lrrrl")
    out += ["",
            f"Physical limit (half an ADC LSB over the sensor's local slope): {g(lim.get('min'))} to "
            f"{g(lim.get('max'))} mm, median {g(lim.get('median'))} mm. "
            f"Hardware against float model at the readings' ADC codes: {g(at_codes)} mm, "
            + (f"{'within' if at_codes is not None and at_codes <= lsb * (1 + 1e-9) else 'OVER'} one output "
               f"LSB ({g(lsb)} mm)." if lsb else "no output LSB stated."), ""]
    return out


def improvement(raw: dict, other: dict) -> str:
    a, b = raw.get("max_error_mm"), other.get("max_error_mm")
    if not a or not b:
        return "-"
    return f"{a / b:.3g}x smaller max error than the raw sensor"


def synth_section(fixed: Step, f18: Step) -> list[str]:
    out = ["## Synthesis", "",
           f"{cmd(SYNTH + ['--json'])} on the checked-in default design (`hdl/`: the paper's 51 terms on "
           "Table 1, 12-bit input), GHDL synthesis and Yosys `synth_xilinx -family xcv`; Fmax is the "
           "Spartan-II estimate from the mapped netlist (docs/synthesis.md), not place and route. "
           f"The float18 row: {cmd(F18_GEN)}, then {cmd(F18_SYNTH + ['--json'])}.", ""]
    rows = [synth_row("**ours, default fixed point**", fixed), synth_row("float18, default model", f18)]
    out += table(["design", "LUT4", "FF", "block RAMs", "cycles/sample", "Fmax estimate (MHz)",
                  "smallest Spartan-II", "verdict"], rows, "lrrrrrll")
    return out + [""]


def synth_row(label: str, s: Step) -> list[str]:
    if not s.ok:
        return [label, s.error, "", "", "", "", "", ""]
    d = s.value
    t = d.get("timing") or {}
    parts = [f"fits {d.get('device')}" if d.get("fits") else f"does NOT fit {d.get('device')}"]
    if t:
        clock = g(t.get("clock_mhz"))
        parts.append(f"meets the {clock} MHz clock" if t.get("meets_clock")
                     else f"misses the {clock} MHz clock")
    nc = d.get("netlist_check")
    if nc:
        parts.append(f"mapped netlist {g(nc.get('codes'))} codes, {g(nc.get('mismatches'))} mismatches")
    return [label, g(d.get("luts")), g(d.get("ffs")), g(d.get("brams")), g(d.get("cycles_per_sample")),
            g(t.get("fmax_mhz_estimate")), str(d.get("smallest_device") or "none"), "; ".join(parts)]


def trace_section(s: Step) -> list[str]:
    out = ["## float18 against fixed point on the paper's model", "",
           f"{cmd(PAPER_MODEL)} (51 terms through the 13 points, raw volts, as the paper), then "
           f"{cmd(TRACE + ['--json'])}: every input code of a 12-bit converter through each datapath's "
           "bit-true twin, against the float64 model.", ""]
    if not s.ok:
        return out + [s.error, ""]
    rows = []
    for fmt in ("float18", "fixed"):
        d = s.value.get(fmt)
        if not d:
            rows.append([fmt, "failed: no trace in the JSON", "", "", ""])
            continue
        tot, dom = d.get("total", {}), d.get("dominant", {})
        rows.append([fmt, g(d.get("codes")), g(tot.get("max_mm")), g(tot.get("rms_mm")),
                     f"{dom.get('stage', '?')} ({g(100 * (dom.get('stage_share') or 0))} % of the error variance)"])
    out += table(["format", "codes", "max \\|hardware - model\\| (mm)", "RMS (mm)", "dominant stage"], rows, "lrrrl")
    f, x = s.value.get("float18", {}).get("total", {}), s.value.get("fixed", {}).get("total", {})
    if f.get("max_mm") and x.get("max_mm"):
        out += ["", f"float18's max error is {f['max_mm'] / x['max_mm']:.3g}x the fixed-point design's."]
    return out + [""]


def fit_section(s: Step) -> list[str]:
    out = ["## The physics simulator calibrated to Table 1", "",
           f"{cmd(FIT + ['--json', 'fit.json'])}: winding lengths, gap and gain fitted, the ideal model "
           "(no effects).", ""]
    if not s.ok:
        return out + [s.error, ""]
    d = s.value
    rows = [["RMS residual", f"{g(1e3 * d['rms_v'])} mV over {d.get('points_used')} points",
             f"noise estimate {g(1e3 * d['noise_v'])} mV"],
            ["even part of the data (y(x) + y(-x))/2",
             "-" if d.get("even_part_rms_v") is None else f"{g(1e3 * d['even_part_rms_v'])} mV RMS",
             "the floor for any symmetric sensor model"]]
    for e in d.get("excluded", []):
        rows.append([f"excluded row {e['row']}", f"{g(e['displacement_mm'])} mm, {g(e['voltage_v'], 4)} V",
                     f"{g(e['residual_v'])} V off the curve: outlier, not fitted"])
    for k, v in d.get("params", {}).items():
        se = (d.get("stderr") or {}).get(k)
        rows.append([f"`{k}`", g(v, 4) + ("" if se is None else f" +- {g(se, 2)}"), "fitted"])
    out += table(["figure", "value", "reference"], rows)
    return out + [""]


def demo_section(s: Step) -> list[str]:
    out = ["## Diagnosis on concealed effects", "",
           f"{cmd(DEMO + ['--json'])}: recordings simulated with hidden effects, diagnosed without being "
           "told them. The reference is the hidden set: a case is right when the named set is it "
           "(controls: nothing named).", ""]
    if not s.ok:
        return out + [s.error, ""]
    cases = s.value
    sim = [c for c in cases if not c.get("model")]
    ind = [c for c in cases if c.get("model")]
    groups = [("The project's simulator", sim),
              ("An independent forward model (`flann.physics.filament`, never called by the diagnosis)", ind)]
    for title, group in groups:
        if not group:
            continue
        rows = []
        for c in group:
            rec, true = c.get("recovered"), c.get("true_value")
            name = f"{c['parameter'].split('.')[-1]} = " if c.get("parameter") else ""
            param = "-" if true is None and rec is None else (
                name + ("not recovered" if rec is None else f"{g(rec['value'])} +- {g(rec['stderr'], 2)}")
                + f" (true {g(true)})")
            rows.append([c["case"], ", ".join(c.get("hidden_effects") or []) or "none",
                         ", ".join(c.get("named") or []) or "nothing", param,
                         f"{g(1e3 * c['rms_before_v'])} -> {g(1e3 * c['rms_after_v'])}",
                         "yes" if c.get("right") else "NO"])
        right = sum(1 for c in group if c.get("right"))
        out += [f"**{title}**: {right} of {len(group)} cases right.", ""]
        out += table(["case", "hidden", "named", "recovered parameter", "RMS residual (mV): simulation -> with the named effects", "right"], rows)
        out += [""]
    return out


def bench_section() -> list[str]:
    out = ["## Other benchmark scripts", "",
           "Speed and size figures that depend on the machine, or take long, are printed by these "
           "scripts rather than kept here (`.venv/bin/python bench/NAME.py --help`):", ""]
    out += table(["script", "what it measures"], [[f"`{a}`", b] for a, b in BENCH_SCRIPTS])
    return out + [""]


# ---- main ---------------------------------------------------------------------------------

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the GHDL/Yosys steps (synthesis and simulation)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help="page to write (default docs/results.md)")
    args = ap.parse_args(argv)
    t_start = time.monotonic()
    quick = "skipped (--quick)" if args.quick else None
    with tempfile.TemporaryDirectory(prefix="flann-results-") as tmp:
        work = Path(tmp)
        (work / "data").symlink_to(ROOT / "data", target_is_directory=True)
        (work / "hdl").symlink_to(ROOT / "hdl", target_is_directory=True)

        paper = Step("paper", lambda: flann_json(["paper"], work))
        fit = Step("simulate --fit", lambda: flann_json(FIT, work, to_file="fit.json"))

        def five():
            for a in FLOW:
                flann(a, work)
            return flann_json(EVAL, work)
        ev = Step("five-command flow + eval", five)
        held = Step("held-out eval", lambda: (ev.ok or _raise("needs the five-command flow, which failed"),
                                              flann(HELD_OUT, work), flann_json(EVAL_HELD, work))[-1])
        sim = Step("sim my_design", lambda: (ev.ok or _raise("needs my_design, which failed"),
                                             flann_json(SIM, work))[-1], skip=quick)
        synth = Step("synth hdl", lambda: flann_json(SYNTH, work), skip=quick)
        f18 = Step("synth float18", lambda: (flann(F18_GEN, work), flann_json(F18_SYNTH, work))[-1], skip=quick)
        trace = Step("trace paper model", lambda: (flann(PAPER_MODEL, work), flann_json(TRACE, work))[-1])
        demo = Step("diagnose --demo", lambda: flann_json(DEMO, work))

    versions = [f"flann: {tool_version(flann_exe() + ['--version'])}",
                f"GHDL: {tool_version(['ghdl', '--version'])}",
                f"Yosys: {tool_version(['yosys', '-V'])}"]
    how = ".venv/bin/python bench/results.py" + (" --quick" if args.quick else "")
    lines = ["# Measured results", "",
             f"Generated by `{how}`: every figure below is a flann command's JSON, run by that script. "
             "Do not edit this page by hand; run the script again.", "",
             "Tools: " + "; ".join(versions) + ".", ""]
    lines += paper_section(paper)
    lines += flow_section(ev, held, sim)
    lines += synth_section(synth, f18)
    lines += trace_section(trace)
    lines += fit_section(fit)
    lines += demo_section(demo)
    lines += bench_section()
    text = "\n".join(lines).rstrip("\n") + "\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp_out = args.out.with_name(args.out.name + ".tmp")
    tmp_out.write_text(text)
    tmp_out.replace(args.out)
    for name, secs, err in TIMES:
        print(f"[results] {name:<28s} {secs:7.1f} s  {err or 'ok'}", file=sys.stderr)
    print(f"[results] wrote {args.out} in {time.monotonic() - t_start:.0f} s", file=sys.stderr)
    return 0 if all(e is None or e.startswith("skipped") for _, _, e in TIMES) else 1


def _raise(reason: str):
    raise StepFailed(reason)


if __name__ == "__main__":
    sys.exit(main())
