"""A sensor the project did not make through the whole conditioner chain: waveforms built from
the closed-form family of ../shared/checks/e2e_sensors.py, then train -> gen -> eval.

    PYTHONPATH=gen .venv/bin/python bench/conditioner_closed_form.py [--seed 1] [--family PATH]

The family draws a demodulated curve s(x) (a saturating S-curve: span, sensitivity, roll-off,
asymmetry, sign, origin, noise).  Its secondaries are built here, flann is not told the form:

    A(x) = C + s(x)/2,  B(x) = C - s(x)/2,   C = 0.55 max|s| over the stroke

(so A - B = s and (A - B)/(A + B) = s / 2C, within +-0.91), A at 0.7 rad against the excitation
and B at 0.72 rad (a small phase imbalance), a 5 kHz carrier sampled at 32 x, the family's
noise on each secondary, 12-bit converters ranged at the smallest of +-2.5, 5, 10 V above the
peak.  Dwell 10 ms at 41 positions over the stroke for training; the held-out recording dwells
at the 40 positions between them, with another noise seed; the ratio at 625 Hz (a 277 Hz
bandwidth, the AD598's 250 Hz judged), the training screen told to keep every reading (each is
the average of whole windows of a curve in closed form: no glitch to screen).  Each figure `flann eval --json`
gives is printed with its verdict against its data-sheet reference.  The options change the
carrier, the sample rate, the output rate, the noise, the positions and the dwell, e.g. the
setting docs/conditioner.md's "Effective bits" measures on the LVDT:

    ... bench/conditioner_closed_form.py --carrier-hz 10000 --samples-per-period 256 \
        --output-rate-hz 588 --noise-v 0.0001 --positions 21 --dwell-s 0.01
"""

import argparse
import contextlib
import importlib.util
import io
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from flann.cli import main as flann
from flann.recordings.waveform import Waveforms, write_waveforms

CARRIER_HZ = 5000.0
SAMPLES_PER_PERIOD = 32
ADC_BITS = 12
RANGES_V = (2.5, 5.0, 10.0)
PHASE_A, PHASE_B = 0.70, 0.72   # rad against the excitation
EXCITATION_V = 5.0
DWELL_S = 0.01
POSITIONS = 41
OUTPUT_RATE_HZ = 625.0   # 8 carrier periods a window: a bandwidth (0.443 x the rate) of 277 Hz, above 250
TARGET_BITS = 16   # the effective bits at 250 Hz with 12-bit converters
FIGURES = ("linearity_pct_fs", "effective_bits", "noise_free_bits", "bandwidth_hz", "settling_time_s",
           "excitation_rejection_ppm_fs_per_pct", "quadrature_rejection_ppm_fs", "phase_tolerance_deg")


def load_family(path: Path):
    spec = importlib.util.spec_from_file_location("e2e_sensors", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def waveforms(family, p, positions, seed: int, range_v: float, centre_v: float, a) -> Waveforms:
    fs = a.carrier_hz * a.samples_per_period
    per = int(round(a.dwell_s * fs))
    x = np.repeat(positions, per)
    t = np.arange(x.size) / fs
    s = family.s_curve(x, p)
    w = 2 * math.pi * a.carrier_hz * t
    rng = np.random.default_rng(seed)
    lsb = 2 * range_v / 2 ** ADC_BITS
    noise = p["noise_v"] if a.noise_v is None else a.noise_v
    sa = (centre_v + s / 2) * np.cos(w + PHASE_A) + rng.normal(0, noise, x.size)
    sb = (centre_v - s / 2) * np.cos(w + PHASE_B) + rng.normal(0, noise, x.size)
    top = range_v - lsb
    sa, sb = (np.clip(np.round(v / lsb) * lsb, -range_v, top) for v in (sa, sb))
    return Waveforms(time_s=t, sec_a_v=sa, sec_b_v=sb, displacement_mm=x, exc_v=EXCITATION_V * np.cos(w))


def run(argv) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = flann([str(a) for a in argv])
    return rc, out.getvalue() + err.getvalue()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1, help="the family's draw (default 1: its first sensor)")
    ap.add_argument("--family", type=Path, default=Path("..") / "shared" / "checks" / "e2e_sensors.py")
    ap.add_argument("--carrier-hz", type=float, default=CARRIER_HZ)
    ap.add_argument("--samples-per-period", type=int, default=SAMPLES_PER_PERIOD)
    ap.add_argument("--output-rate-hz", type=float, default=OUTPUT_RATE_HZ)
    ap.add_argument("--noise-v", type=float, default=None, help="rms on each secondary (default: the family's)")
    ap.add_argument("--positions", type=int, default=POSITIONS)
    ap.add_argument("--dwell-s", type=float, default=DWELL_S)
    ap.add_argument("--hardware", action="store_true", help="also flann sim and flann synth the design")
    a = ap.parse_args()
    if not a.family.is_file():
        print(f"error: {a.family}: the closed-form family's script not found (give --family)", file=sys.stderr)
        return 2
    family = load_family(a.family)
    p = family.draw(np.random.default_rng(a.seed))
    lo, hi = (0.0, 2 * p["span_mm"]) if p["start_at_zero"] else (-p["span_mm"], p["span_mm"])
    train_x = np.linspace(lo, hi, a.positions)
    held_x = 0.5 * (train_x[1:] + train_x[:-1])
    peak_s = float(np.max(np.abs(family.s_curve(np.linspace(lo, hi, 2001), p))))
    centre = 0.55 * peak_s
    range_v = next((r for r in RANGES_V if r >= 1.05 * (centre + peak_s / 2)), RANGES_V[-1])
    print(f"sensor (seed {a.seed}): span {p['span_mm']:g} mm ({lo:g}..{hi:g}), amplitude {p['amp_v']:.3g} V, "
          f"sharpness {p['sharp']:.3g}, asymmetry {p['asym']:+.3f}, sign {p['sign']:+g}, noise "
          f"{1e3 * p['noise_v']:.3g} mV; secondaries {centre:.3g} V +- s/2 at {PHASE_A}/{PHASE_B} rad, "
          f"{1e3 * (p['noise_v'] if a.noise_v is None else a.noise_v):.3g} mV rms; {ADC_BITS}-bit +-{range_v:g} V "
          f"converters, {a.carrier_hz:g} Hz x {a.samples_per_period}, {a.positions} positions, dwell {a.dwell_s:g} s")
    with tempfile.TemporaryDirectory(prefix="closed_form_") as tmp:
        d = Path(tmp)
        write_waveforms(d / "wave.csv", waveforms(family, p, train_x, a.seed + 100, range_v, centre, a))
        write_waveforms(d / "held_out.csv", waveforms(family, p, held_x, a.seed + 200, range_v, centre, a))
        steps = [("train", ["train", d / "wave.csv", "-o", d / "model.json", "--adc-bits", ADC_BITS,
                            "--adc-range-v", range_v, "--outliers", "keep", "--output-rate-hz", a.output_rate_hz]),
                 # an output LSB finer than the ratio's noise: the words keep the conditioner's bits
                 ("gen", ["gen", d / "model.json", "-o", d / "design", "--output-lsb-mm", 2 * p["span_mm"] / 2 ** 18]),
                 ("eval", ["eval", d / "model.json", d / "held_out.csv", "--design", d / "design", "--json",
                           "--quiet", "--outliers", "keep"])]
        if a.hardware:
            steps += hardware_steps(d / "design")
        outs = run_steps(steps)
        if outs is None:
            return 1
        return judge(outs)


def synth_line(r: dict) -> tuple[str, bool]:
    """The whole chain's resources and clock, judged against the part and the 50 MHz asked."""
    if "logic_cells" in r:
        return (f"{r['device']}: {r['logic_cells']} logic cells ({r['lc_pct']:g} %), {r['brams']} block RAMs, "
                f"{r['fmax_mhz']:g} MHz placed and routed: {'meets' if r['timing_met'] else 'misses'} "
                f"{r['clock_mhz']:g} MHz; bitstream {r['bitstream']}"), bool(r["timing_met"])
    t = r["timing"]
    return (f"{r['device']}: {r['luts']} LUT4 ({r['lut_pct']:g} %), {r['ffs']} flip-flops, {r['brams']} of "
            f"{r['device_brams']} block RAMs: {'fits' if r['fits'] else 'does not fit'} (smallest "
            f"{r['smallest_device']}); Fmax estimate {t['fmax_mhz_estimate']:g} MHz: "
            f"{'meets' if t['meets_clock'] else 'misses'} {t['clock_mhz']:g} MHz"), bool(r["fits"] and t["meets_clock"])


def hardware_steps(design: Path) -> list:
    """flann sim and flann synth (Spartan-II, then placed and routed on an iCE40-HX8K) of a design."""
    return [("sim", ["sim", design]), ("synth", ["synth", design, "--json"]),
            ("synth", ["synth", design, "--device", "ice40-hx8k-ct256", "--json", "-o", design.parent / "ice40"])]


def run_steps(steps) -> list[tuple[str, str]] | None:
    """Each (name, argv) through flann in turn, train's and sim's verdict printed: (name, output)
    of each, or None at the first that fails (its last line printed)."""
    outs = []
    for name, argv in steps:
        rc, text = run(argv)
        if rc != 0:
            print(f"{name}: exit {rc}: {text.strip().splitlines()[-1] if text.strip() else ''}")
            return None
        if name in ("train", "sim"):
            print(f"{name}: " + next((s for s in text.splitlines() if s.startswith("verdict")), "?"))
        outs.append((name, text))
    return outs


def eval_result(outs) -> dict:
    """``flann eval --json``'s result in a run of :func:`run_steps` (its JSON, then its lines)."""
    text = dict(outs)["eval"]
    return json.loads(text[: text.rindex("}") + 1])


def judge(outs) -> int:
    """The eval's figures and the synth's lines of a run of :func:`run_steps`, each judged:
    0 when every one meets its reference."""
    res, missed = eval_result(outs), 0
    for name, text in outs:
        if name == "synth":
            line, ok = synth_line(json.loads(text[text.index("{"): text.rindex("}") + 1]))
            missed += not ok
            print("synth: " + line)
    return 1 if print_figures(res) or missed else 0


def print_figures(res: dict) -> int:
    """Each figure of ``flann eval --json`` with its verdict against its data-sheet reference;
    0 when every judged figure meets it."""
    lin, missed = res["linearity_pct_fs"], 0
    for chain in ("float", "hardware"):
        ok = lin[chain] is not None and lin[chain] <= lin["reference_pct_fs"]
        missed += lin[chain] is not None and not ok
        print(f"linearity_pct_fs ({chain}) {lin[chain]:.4f} % FS: {'within' if ok else 'beyond'} the "
              f"{lin['reference']} of {lin['reference_pct_fs']:g}")
    for name in FIGURES[1:]:
        f = res[name]
        if f["value"] is None:
            print(f"{name}: not computable: {f['reason']}")
            continue
        missed += f["ok"] is False
        word = {True: "meets", False: "misses", None: "not judged against"}[f["ok"]]
        unmet = f" ({f['unmet']})" if f.get("unmet") else ""
        print(f"{name} {f['value']:.4g} {f['unit']}: {word} the {f['reference']} "
              f"({'<=' if f['at_most'] else '>='} {f['reference_value']:g}){unmet}; from {f['source']}")
    hw = res["effective_bits"].get("hardware_bits")
    if hw is not None:
        missed += hw < TARGET_BITS
        print(f"effective_bits of the design's output words {hw:.4g} bits: {'meets' if hw >= TARGET_BITS else 'misses'} "
              f"the {TARGET_BITS} asked (their noise and their LSB's rounding, through the bit-true chain)")
    print(res["verdict"]["line"])
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
