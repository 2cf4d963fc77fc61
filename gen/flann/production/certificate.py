"""The calibration certificate: one self-contained HTML file per sensor (the plot inline SVG).

Every figure and value is computed here; the template only places text (values escaped).
"""

from __future__ import annotations

from .. import __version__
from ..textgen import template
from .plot import error_plot_svg

TEMPLATE = "production/templates/certificate.html.j2"


def render_certificate(res, chk: dict, fam, dhash: str, mhash: str, findings, basis: str) -> str:
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
        sensor=res.sensor, plot=error_plot_svg(chk, res.sensor), tables=figures, diagnosis_basis=basis,
        findings=list(findings) or ["no missing physics found"], warnings=res.warnings,
        verdict=f"max error {res.max_error_mm:.4g} mm = {res.ratio_to_limit:.3g} x the physical limit",
    )


__all__ = ["render_certificate"]
