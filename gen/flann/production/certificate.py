"""The calibration certificate: one self-contained HTML file per sensor (the plot inline SVG),
printable on one or two A4 pages for a quality manager to sign.

Every figure and value is computed here; the template only places text (values escaped).
"""

from __future__ import annotations

from .. import __version__
from ..textgen import template
from .plot import error_plot_svg, error_plot_temperatures_svg
from .verdict import NOT_JUDGED, PASS

TEMPLATE = "production/templates/certificate.html.j2"
DECISION_RULE = ("simple acceptance (ILAC-G8 shared risk): PASS when the measured max error is "
                 "within the tolerance; U is stated, and a result within U of the tolerance is "
                 "marked marginal")


def _identification(res, dhash: str, mhash: str, rec_sha: str) -> tuple:
    t = res.trace
    return ("Identification", [
        ("certificate number", t.certificate_number if t else "-"),
        ("serial", f"{t.serial} (from the {t.serial_from})" if t else res.sensor),
        ("recording", res.recording),
        ("recording sha256", rec_sha or "-"),
        ("model sha256 (model.json)", mhash or "- (no model: not calibrated)"),
        ("design sha256 (VHDL files)", dhash),
        ("tool", f"flann {__version__}"),
    ])


def _traceability(res) -> tuple:
    t = res.trace
    blank = "not stated"
    return ("Traceability", [
        ("calibrated at", t.calibrated_at if t else blank),
        ("station", (t.station if t else "") or blank),
        ("operator", (t.operator if t else "") or blank),
        ("fixture", (t.fixture if t else "") or blank),
        ("calibration temperature", t.temperature_text() if t else blank),
        ("displacement reference standard", t.reference_text() if t else blank),
        ("reference standard calibration due", t.due_text() if t else blank),
    ])


def _specification(spec, verdict) -> tuple:
    rows = [("specification", spec.name or "-"), ("source", spec.source or "none"),
            ("tolerance", verdict.tolerance)]
    if verdict.range_text:
        rows.append(("judged over", verdict.range_text))
    if verdict.full_scale_mm is not None:
        rows.append(("full scale (FS)", f"{verdict.full_scale_mm:.4g} mm (half the span judged over, as flann eval reports it)"))
    rows.append(("decision rule", DECISION_RULE))
    rows.append(("verdict", verdict.verdict))
    return ("Specification and verdict", rows)


def _tolerance_mm(spec, verdict) -> float | None:
    if spec.max_error_mm is not None:
        return spec.max_error_mm
    if spec.max_error_pct_fs is not None and verdict.full_scale_mm:
        return spec.max_error_pct_fs / 100.0 * verdict.full_scale_mm
    return None


def _verdict_rows(verdict, u: float) -> list:
    """The verdict's compensated max error, in mm and in % FS, each with the expanded uncertainty U."""
    fs = verdict.full_scale_mm
    pct_u = f" ± {100 * u / fs:.2g}" if fs else ""
    return [
        ("compensated max error (hardware) over " + verdict.range_text,
         f"{verdict.max_error_mm:.4g} ± {u:.2g} mm" if verdict.max_error_mm is not None else "-"),
        ("compensated max error in % FS",
         f"{verdict.max_error_pct_fs:.4g}{pct_u} % FS" if verdict.max_error_pct_fs is not None else "-"),
    ]


def render_certificate(res, chk: dict, fam, dhash: str, mhash: str, findings, basis: str, *,
                       spec, verdict, trace, uncertainty, confounded=()) -> str:
    s, mspec = fam.spec, chk["spec"]
    u = uncertainty.expanded_mm
    results = ("Results (expanded uncertainty U, k = 2)", [
        *_verdict_rows(verdict, u),
        ("compensated max error, whole recording", f"{res.max_error_mm:.4g} ± {u:.2g} mm"),
        ("raw max error (least-squares line)", f"{res.raw_max_error_mm:.4g} ± {u:.2g} mm"),
        ("physical limit, worst over the stroke", f"{res.limit_mm:.4g} mm"),
        ("ratio to the limit", f"{res.ratio_to_limit:.3g}"),
        ("noise of one reading", f"{uncertainty.noise_v * 1e3:.3g} mV = {uncertainty.sigma_x_mm:.2g} mm"),
        ("positions recorded / model terms", f"{uncertainty.positions} / {uncertainty.terms}"),
        ("uncertainty method", uncertainty.method),
    ])
    hardware = ("Hardware figures", [
        ("max |twin - float model| over every input code", f"{res.twin_vs_float_lsb:.4f} LSB"),
        ("error bound of the formats", f"{chk['bound_lsb']:.4f} LSB"),
        ("input", f"{s.input_bits}-bit code x {s.input_lsb_v} V, clamp {mspec.clamp_lo}..{mspec.clamp_hi}"),
        ("output", f"{s.out_fmt.width}-bit code x {s.output_lsb_mm} mm"),
        ("latency", f"{fam.latency_cycles} cycles ({fam.cycles_per_sample} cycles/sample)"),
        ("weight memory", f"{fam.used_words} of {fam.mem_depth} words x 32 bits"),
        ("terms", f"{fam.terms}"),
    ])
    tables = [_identification(res, dhash, mhash, chk["rec"].sha256), _traceability(res),
              _specification(spec, verdict), results]
    if confounded:
        sets = " or ".join("{" + ", ".join(g) + "}" for g in confounded)
        diagnosis_head = (f"The recordings cannot tell these explanations apart (they fit equally "
                          f"well): {sets}. None of them is named alone.")
    else:
        diagnosis_head = ""
    plot = error_plot_svg(chk, trace.serial, _tolerance_mm(spec, verdict), spec.working_range_mm)
    return _render(res, trace, verdict, tables, plot, basis, findings, diagnosis_head, shipped=True,
                   after=[hardware])


def render_certificate_thermal(res, chk: dict, fam, dhash: str, mhash: str, findings, basis: str, *,
                               spec, verdict, trace, uncertainty, per_temperature, confounded=()) -> str:
    """The certificate of a sensor calibrated at several temperatures for a family design with
    temperature (``fam`` its FamilyThermalSpec): the results over every temperature, a table
    by temperature (error, verdict), the drift figure and one error curve per temperature."""
    u = uncertainty.expanded_mm

    def drift(value) -> str:
        return "-" if value is None else f"{value:.3g} ppm FS/degC"

    results = ("Results over every calibration temperature (expanded uncertainty U, k = 2)", [
        *_verdict_rows(verdict, u),
        ("compensated max error, whole recording", f"{res.max_error_mm:.4g} ± {u:.2g} mm"),
        ("raw max error (one least-squares line)", f"{res.raw_max_error_mm:.4g} ± {u:.2g} mm"),
        ("drift_ppm_fs_per_c (hardware)", drift(chk["drift_ppm_fs_per_c"])),
        ("drift_ppm_fs_per_c (raw sensor)", drift(chk["raw_drift_ppm_fs_per_c"])),
        ("drift method", "box method at every position: the largest change of the error across the "
                         "calibration temperatures, per degC of their range, in ppm of full scale "
                         f"({chk['full_scale_mm']:.4g} mm, half the recorded span, "
                         "as flann eval reports it)"),
        ("physical limit, worst over the stroke", f"{res.limit_mm:.4g} mm"),
        ("ratio to the limit", f"{res.ratio_to_limit:.3g}"),
        ("uncertainty method", uncertainty.method + " (the largest of the temperatures')"),
    ])
    by_t = {round(r["temperature_c"], 6): r for r in chk["by_temperature"]}
    rows = []
    for temp, v, ut in per_temperature:
        r = by_t.get(round(temp, 6), {})
        rows.append((f"{temp:g} degC ({r.get('points', 0)} readings)",
                     f"{v.verdict}: max {r.get('max_error_mm', float('nan')):.4g} ± {ut.expanded_mm:.2g} mm, "
                     f"RMS {r.get('rms_error_mm', float('nan')):.3g} mm"
                     + (f", {v.max_error_pct_fs:.3g} % FS" if v.max_error_pct_fs is not None else "")))
    by_temperature = ("Verdict at each calibration temperature", rows)
    s = fam.fam.spec
    t = fam.temp
    hardware = ("Hardware figures", [
        ("max |twin - float model|", f"{res.twin_vs_float_lsb:.4f} LSB over every input code at temperature "
                                     f"codes {', '.join(map(str, chk['temperature_checked_codes']))}"),
        ("error bound of the formats", f"{chk['bound_lsb']:.4f} LSB"),
        ("input", f"{s.input_bits}-bit code x {s.input_lsb_v} V"),
        ("temperature input", f"{t.bits}-bit code x {t.lsb_c} degC, calibrated codes {t.lo}..{t.hi} "
                              f"(t_n = (code - {t.mid}) / 2^{t.shift})"),
        ("output", f"{fam.out_fmt.width}-bit code x {fam.output_lsb_mm} mm"),
        ("latency", f"{fam.latency_cycles} cycles ({fam.cycles_per_sample} cycles/sample)"),
        ("weight memories", f"{fam.orders} temperature orders x {fam.fam.used_words} of {fam.fam.mem_depth} "
                            f"words x 32 bits (image {fam.image_words} words)"),
        ("terms", f"{fam.fam.terms} per temperature order"),
    ])
    tables = [_identification(res, dhash, mhash, chk["rec"].sha256), _traceability(res),
              _specification(spec, verdict), results, by_temperature]
    diagnosis_head = ""
    if confounded:
        sets = " or ".join("{" + ", ".join(g) + "}" for g in confounded)
        diagnosis_head = (f"The recordings cannot tell these explanations apart (they fit equally "
                          f"well): {sets}. None of them is named alone.")
    plot = error_plot_temperatures_svg(chk, trace.serial, _tolerance_mm(spec, verdict), spec.working_range_mm)
    return _render(res, trace, verdict, tables, plot, basis, findings, diagnosis_head, shipped=True,
                   after=[hardware], weights="model.json, weights.hex (every order's memory)")


def render_rejection(res, fam, dhash: str, spec, rec_sha: str = "") -> str:
    """The certificate of a sensor that could not be calibrated: FAIL and why."""
    tables = [_identification(res, dhash, "", rec_sha), _traceability(res),
              _specification(spec, res.verdict)]
    return _render(res, res.trace, res.verdict, tables, "", "", [], "", shipped=False)


def _render(res, trace, verdict, tables, plot, basis, findings, diagnosis_head, shipped, after=(),
            weights="model.json, weights.hex, weights.mem, weights.bmm") -> str:
    serial = trace.serial if trace else res.sensor
    if verdict.verdict == PASS:
        banner, kind = f"PASS: {verdict.tolerance}", "pass"
    elif verdict.verdict == NOT_JUDGED:
        banner, kind = f"NOT JUDGED: {verdict.reasons[0]}", "notjudged"
    else:
        banner, kind = "FAIL: " + "; ".join(r for r in verdict.reasons if not r.startswith("marginal")), "fail"
    notes = [r for r in verdict.reasons if r.startswith("marginal")]
    return template(TEMPLATE).render(
        sensor=serial, number=trace.certificate_number if trace else "", verdict_class=kind, banner=banner, notes=notes,
        plot=plot, tables=tables, after_tables=list(after), diagnosis_basis=basis, diagnosis_head=diagnosis_head,
        findings=(list(findings) or ["no missing physics found"]) if basis else [],
        warnings=res.warnings,
        shipped=(f"weights written: {weights}" if shipped and verdict.shipped
                 else "no weights written for this sensor"),
    )


__all__ = ["render_certificate", "render_certificate_thermal", "render_rejection", "DECISION_RULE"]
