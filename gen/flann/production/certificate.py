"""The calibration certificate: one self-contained HTML file per sensor (plots as base64 PNG).

Every figure and value is computed here; the template only places text (values escaped).
"""

from __future__ import annotations

import base64
import io

import numpy as np

from .. import __version__
from ..textgen import template

TEMPLATE = "production/templates/certificate.html.j2"


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=96)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def error_plot(chk: dict, sensor: str) -> str:
    """Raw (least-squares line) and compensated (hardware twin) error vs displacement, with the limit."""
    import matplotlib  # lazy: only when certificates are written

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.asarray(chk["rec"].displacement_mm, dtype=float)
    o = np.argsort(x, kind="stable")
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.5, 5.6), sharex=True)
    a1.plot(x[o], chk["raw_err_mm"][o], lw=0.8, color="C3")
    a1.set_ylabel("raw error (mm)")
    a1.set_title(f"{sensor}: raw sensor (its least-squares line)", fontsize=10)
    a2.plot(x[o], chk["hw_err_mm"][o], lw=0.8, color="C0", label="compensated (hardware twin)")
    lim = chk["limit_mm"][o]
    a2.plot(x[o], lim, ls=":", color="k", lw=1, label="physical limit (half LSB / slope)")
    a2.plot(x[o], -lim, ls=":", color="k", lw=1)
    a2.set_ylabel("compensated error (mm)")
    a2.set_xlabel("displacement (mm)")
    a2.legend(loc="best", fontsize=8)
    a2.set_title("compensated by the FPGA design (bit-true twin)", fontsize=10)
    fig.tight_layout()
    try:
        return _png(fig)
    finally:
        plt.close(fig)


def render_certificate(res, chk: dict, fam, dhash: str, mhash: str, findings) -> str:
    s, spec = fam.spec, chk["spec"]
    figures = [
        ("Measured figures", [
            ("points in the recording", f"{len(chk['rec'])}"),
            ("raw max error (least-squares line)", f"{res.raw_max_error_mm:.4g} mm"),
            ("compensated max error (hardware)", f"{res.max_error_mm:.4g} mm"),
            ("physical limit, worst over the stroke", f"{res.limit_mm:.4g} mm"),
            ("ratio to the limit", f"{res.ratio_to_limit:.3g}"),
        ]),
        ("Hardware figures", [
            ("max |twin - float model| over every input code", f"{res.twin_vs_float_lsb:.4f} LSB"),
            ("error bound of the formats", f"{chk['bound_lsb']:.4f} LSB"),
            ("input", f"{s.input_bits}-bit code x {s.input_lsb_v} V, clamp {spec.clamp_lo}..{spec.clamp_hi}"),
            ("output", f"{s.out_fmt.width}-bit code x {s.output_lsb_mm} mm"),
            ("latency", f"{fam.latency_cycles} cycles ({fam.cycles_per_sample} cycles/sample)"),
            ("weight memory", f"{fam.used_words} of {fam.mem_depth} words x 32 bits"),
            ("terms", f"{fam.terms}"),
        ]),
        ("Identity", [
            ("sensor", res.sensor),
            ("recording", res.recording),
            ("recording sha256", chk["rec"].sha256 or "-"),
            ("model sha256 (model.json)", mhash),
            ("design sha256 (VHDL files)", dhash),
            ("generator", f"flann {__version__}"),
        ]),
    ]
    return template(TEMPLATE).render(
        sensor=res.sensor, plot=error_plot(chk, res.sensor), tables=figures,
        findings=list(findings) or ["no missing physics found"], warnings=res.warnings,
        verdict=f"max error {res.max_error_mm:.4g} mm = {res.ratio_to_limit:.3g} x the physical limit",
    )


__all__ = ["render_certificate", "error_plot"]
