"""What ``flann sim`` returns for every datapath: one :class:`SimResult`, and the summary fields
every datapath's bench reports the same way."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..golden.verdict import Check, Verdict, combine
from ..hardware.design import Design
from .runner import throughput


@dataclass
class SimResult:
    """One design verified: ``summary`` is what ``flann sim --json`` prints, ``curve`` what its
    plot draws (None: nothing to draw), ``passed`` the verdict of every bench and check run."""

    summary: dict
    curve: object | None
    spec: object
    passed: bool
    bound_lsb: float | None = None   # the design's stated bound on |HDL - float model| (output LSBs)

    def judged_with(self, name: str, about: dict, passed: bool) -> "SimResult":
        """This result with one more check (its summary entry ``name``) folded into the verdict."""
        self.summary[name] = about
        self.passed = self.passed and passed
        self.summary["all_passed"] = self.passed
        return self

    @classmethod
    def from_summary(cls, summary: dict, curve, spec, bound_lsb: float | None = None) -> "SimResult":
        return cls(summary, curve, spec, bool(summary["all_passed"]), bound_lsb)

    def verdict(self) -> Verdict:
        """Judged against the twin (bit for bit, every bench) and, where the design states one,
        against its bound on the error from the float model."""
        s = self.summary
        n, bad = s.get("codes_tested") or 0, s.get("mismatches")
        exact = self.passed and bad == 0 and n > 0
        twin = Check("hdl_vs_twin", exact,
                     f"{bad} mismatches with the twin over {n} samples, every bench passed" if exact else
                     f"the HDL disagrees with its twin ({bad} mismatches over {n} samples) or a bench failed",
                     "" if exact else "see the failed benches above; regenerate the design with flann gen")
        err = s.get("max_err_lsb")
        bound = None
        if self.bound_lsb is not None and err is not None:
            ok = err <= self.bound_lsb + 1e-9
            bound = Check("hdl_vs_float_bound", ok,
                          f"max |HDL - float model| {err:.4g} LSB {'within' if ok else 'beyond'} the design's "
                          f"stated bound {self.bound_lsb:.4g} LSB", "" if ok else "regenerate with wider widths")
        return combine(twin, bound)


def summary(design: Design, codes: int, mismatches, max_err_mm, benches: dict, ok: bool, lsb=None) -> dict:
    """The fields every bench's summary holds, in ``flann sim --json``'s names."""
    man = design.manifest
    return {"codes_tested": codes, "mismatches": mismatches,
            "max_err_lsb": round(max_err_mm / lsb, 4) if (lsb and max_err_mm is not None) else None,
            "max_err_mm": None if max_err_mm is None else round(float(max_err_mm), 6),
            "cycles_per_sample": man["cycles_per_sample"], **throughput(man["cycles_per_sample"]),
            "benches": benches, "all_passed": ok, "latency_cycles": man["latency_cycles"],
            "output_lsb_mm": lsb, "model_sha256": man.get("model_sha256", ""), "design": str(design.directory)}


def bench_entry(res) -> dict:
    """A cocotb bench's result as the summary's ``benches`` lists it."""
    return {"tests": res.tests, "failures": res.failures, "failed": res.failed_tests, "seconds": round(res.seconds, 1)}


def temperature_fields(s: dict, temps, every: bool, voltage_codes: int) -> None:
    s["temperature_codes"] = "every" if every else temps
    s["temperature_codes_tested"] = len(temps)
    s["voltage_codes_tested"] = voltage_codes


def sweep_about(backend: str, *runs, samples: int) -> dict:
    """The summary's ``sweep`` entry of two-input sweeps (one run per image, each of ``samples``)."""
    secs = sum(r.seconds for r in runs)
    return {"engine": "ghdl", "backend": f"ghdl-{backend}", "shards": max(r.shards for r in runs),
            "seconds": round(secs, 1), "codes_per_s": round(samples * len(runs) / secs, 1) if secs > 0 else None}


def sweep_rows(path: Path, samples: int):
    """A two-input sweep's output file as (voltage codes, temperature codes, out, sat), or None
    when the harness did not write every sample (the bench has failed and says why)."""
    if not path.is_file():
        return None
    rows = np.loadtxt(path, dtype=np.int64, ndmin=2)
    if rows.shape != (samples, 5):
        return None
    return rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3].astype(bool)


__all__ = ["SimResult", "summary", "bench_entry", "temperature_fields", "sweep_about", "sweep_rows"]
