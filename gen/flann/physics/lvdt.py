"""Forward magnetics of a differential transformer: core position -> demodulated output.

Model (docs/physics.md has the derivation and sources): a *distributed magnetic circuit*
(magnetic transmission line) along the axis.  The bore inside the windings carries the axial
flux ``Phi(z)``; it is a series reluctance per unit length ``R'(z)`` -- low where the core
is (``1 / (mu0 (mu_r A_core + A_air))``), high in air (``1 / (mu0 A_air)``) -- shunted by
the leakage permeance per unit length ``G' = 2 pi mu0 / ln(r_housing / r_core)`` from the
bore to the housing (the flux return).  Each winding turn is an m.m.f. source in series with
the axial branch.  With ``u(z)`` the magnetic potential of the bore against the housing::

    dPhi/dz = -G' u,        du/dz = n(z) I - R'(z) Phi

so a core section of length ``>> lambda = 1/sqrt(R' G')`` under a uniform winding carries
the full ``mu0 mu_r A n I`` and the flux decays towards the core ends over ``lambda``.  The
flux linkage of a winding is ``sum n_w(z) Phi(z) dz``; dividing by the primary current gives
the mutual inductances ``M1(x)``, ``M2(x)`` to the secondaries and the primary's own
inductance ``Lp(x)``.  End-of-stroke roll-off is not fitted: it appears when the core end
leaves a secondary, at a place set by core length, winding lengths and gap, with a shape
set by ``lambda``.

R', G' and the turn densities are piecewise constant between 8 breakpoints (winding ends and
core ends), so the line is solved exactly, segment by segment, with semi-infinite air lines
at both ends (no grid, no truncated domain), for all core positions at once (vectorised).  Then::

    Ip = V_peak / (R_p + j w Lp(x)),    v1 = j w M1(x) Ip,    v2 = j w M2(x) Ip
    v_d = v1 - v2                       (secondaries in series opposition)
    phase-sensitive:  y = G Re(v_d e^{-j phi_ref}),  phi_ref = arg(j w Ip(0))
    amplitude:        y = G |v_d|

Secondaries are unloaded (high-impedance demodulator); eddy currents, hysteresis, core
saturation and inter-winding capacitance are left out of the ideal model.

Public API (stable):

* :func:`ideal_output_v` (sensor, displacement_mm) -> ndarray: demodulated output, no effects.
  Vectorised; exact below TABLE_MIN_POINTS distinct positions, else interpolated from a
  per-geometry table of exact solutions (~1e-7 of full scale); ~1-2 ms for 2000 new
  positions, ~0.3 ms when geometry and positions repeat (``bench/physics_speed.py``).
* :func:`secondary_emf_v` (sensor, core_position_mm, drive_scale=1) -> (v1, v2): complex
  peak e.m.f.s of the two secondaries (V).
* :func:`demodulate_v` (sensor, v_diff, quadrature_v=0) -> output volts.
* :func:`inductances_h` (sensor, core_position_mm, loop=False) -> (M1, M2, Lp[, L_loop]) in H,
  :func:`coupling_table` (sensor) -> :class:`CouplingTable`,
  :func:`primary_current_a`, :func:`flux_profile` (for plots), :func:`null_slope_v_per_mm`.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from .sensor import Sensor

MU0 = 4e-7 * math.pi  # H/m

_CACHE_SIZE = 32


@dataclass(frozen=True)
class CouplingTable:
    """Inductances vs core-centre position (position grid in mm, inductances in H)."""

    position_mm: np.ndarray
    m1_h: np.ndarray     # primary -> secondary 1 (+z side)
    m2_h: np.ndarray     # primary -> secondary 2 (-z side)
    lp_h: np.ndarray     # primary self-inductance (bore flux only)
    lloop_h: np.ndarray  # self-inductance of the two secondaries in series opposition


def _real_if_real(z: complex):
    return z.real if z.imag == 0 else z


@dataclass(frozen=True)
class Magnetics:
    """Per-unit-length constants of the transmission line and the winding layout (SI)."""

    r_core: complex    # series reluctance per metre, core-filled bore (1/(H m)); complex
                       # (a loss part) when eddy currents flow in the core
    r_air: float       # series reluctance per metre, air-filled bore
    g_leak: float      # leakage permeance per metre to the housing (H/m per m)
    half_core: float   # core half length (m)
    a1: float          # primary half length (m)
    a2: float          # inner end of a secondary (m)
    a3: float          # outer end of a secondary (m)
    n_p: float         # primary turns per metre
    n_s: float         # secondary turns per metre


def core_permeability_eff(s: Sensor) -> complex:
    """Effective (complex) relative permeability of the core at the excitation frequency.

    Eddy currents confine the a.c. flux to a skin depth ``delta = sqrt(2 / (w mu0 mu_r
    sigma))``.  Averaged over the section (e^{jwt} convention, Neubert; any text on eddy
    currents in laminations/rods):

    * tube of wall w (treated as a plate): ``mu_r tanh(g w/2) / (g w/2)``, ``g = (1+j)/delta``
    * solid rod of radius a: ``mu_r 2 J1(k a) / (k a J0(k a))``, ``k = (1-j)/delta``

    ``sigma = 0`` gives ``mu_r`` (real)."""
    mu_r = s.core_permeability_ratio
    sigma = s.core_conductivity_s_per_m
    if sigma <= 0:
        return complex(mu_r)
    delta = math.sqrt(2.0 / (s.omega_rad_s * MU0 * mu_r * sigma))
    mm = 1e-3
    if s.core_inner_diameter_mm > 0:
        half_wall = (s.core_outer_diameter_mm - s.core_inner_diameter_mm) / 4 * mm
        g = (1 + 1j) / delta * half_wall
        return complex(mu_r * np.tanh(g) / g)
    from scipy.special import jv

    ka = (1 - 1j) / delta * (s.core_outer_diameter_mm / 2 * mm)
    return complex(mu_r * 2 * jv(1, ka) / (ka * jv(0, ka)))


def magnetics(s: Sensor) -> Magnetics:
    mm = 1e-3
    a_core = math.pi / 4 * (s.core_outer_diameter_mm ** 2 - s.core_inner_diameter_mm ** 2) * mm ** 2
    r_mean = (s.coil_inner_diameter_mm + s.coil_outer_diameter_mm) / 4 * mm
    a_air = math.pi * r_mean ** 2          # flux tube linked by a mean turn
    r_core = s.core_outer_diameter_mm / 2 * mm
    r_housing = s.housing_inner_diameter_mm / 2 * mm
    a1 = s.primary_length_mm / 2 * mm
    a2 = a1 + s.secondary_gap_mm * mm
    a3 = a2 + s.secondary_length_mm * mm
    return Magnetics(
        r_core=_real_if_real(1.0 / (MU0 * (core_permeability_eff(s) * a_core + (a_air - a_core)))),
        r_air=1.0 / (MU0 * a_air),
        g_leak=2 * math.pi * MU0 / math.log(r_housing / r_core),
        half_core=s.core_length_mm / 2 * mm,
        a1=a1, a2=a2, a3=a3,
        n_p=s.primary_turns / (2 * a1),
        n_s=s.secondary_turns / (a3 - a2),
    )


@dataclass(frozen=True)
class _Segments:
    """Axial segments between sorted breakpoints; column j is core position j (arrays are
    (breakpoints, positions) so each sweep step reads contiguous rows)."""

    b: np.ndarray        # breakpoints (8, n), sorted along axis 0
    r: np.ndarray        # series reluctance per metre of each finite segment (7, n)
    n_p: np.ndarray      # turn densities of the windings in each segment (7, n)
    n_s1: np.ndarray
    n_s2: np.ndarray


def _segments(mg: Magnetics, pos_m: np.ndarray) -> _Segments:
    n = pos_m.size
    b = np.empty((8, n))
    b[:6] = np.array([-mg.a3, -mg.a2, -mg.a1, mg.a1, mg.a2, mg.a3])[:, None]
    b[6] = pos_m - mg.half_core
    b[7] = pos_m + mg.half_core
    b.sort(axis=0)
    mid = 0.5 * (b[1:] + b[:-1])
    r = np.where(np.abs(mid - pos_m) < mg.half_core, mg.r_core, mg.r_air)
    n_p = np.where(np.abs(mid) < mg.a1, mg.n_p, 0.0)
    n_s1 = np.where((mid > mg.a2) & (mid < mg.a3), mg.n_s, 0.0)
    n_s2 = np.where((mid < -mg.a2) & (mid > -mg.a3), mg.n_s, 0.0)
    return _Segments(b, r, n_p, n_s1, n_s2)


def _solve(mg: Magnetics, seg: _Segments, sources: tuple[np.ndarray, ...]):
    """Exact solution of the line for each source (m.m.f. per metre at 1 A, per segment).

    Returns, per source, the breakpoint potentials ``u`` (8, n) and the flux integrals
    ``int Phi dz`` over every finite segment (7, n).  Both ends are semi-infinite air lines
    (``Phi = -u/Z0`` on the left, ``+u/Z0`` on the right): no truncated domain.  The sweeps
    carry the affine relation ``Phi = Y u + J`` from each end (a Moebius map with |tanh| < 1,
    numerically stable for any segment length), then match them at every breakpoint.
    """
    g = mg.g_leak
    z0 = np.sqrt(seg.r / g)                      # characteristic "impedance" (1/H)
    length = np.diff(seg.b, axis=0)
    kl = np.sqrt(seg.r * g) * length
    ekl = np.exp(-kl)
    t = (1.0 - ekl * ekl) / (1.0 + ekl * ekl)    # tanh(kl)
    sech = 2.0 * ekl / (1.0 + ekl * ekl)         # 1/cosh(kl), no overflow
    zt = z0 * t
    tz = t / z0
    z0_air = math.sqrt(mg.r_air / g)
    n_seg = length.shape[0]
    dtype = np.result_type(seg.r, float)
    y_l = np.empty(seg.b.shape, dtype=dtype)
    y_r = np.empty(seg.b.shape, dtype=dtype)
    y_l[0] = -1.0 / z0_air
    for i in range(n_seg):
        y_l[i + 1] = (y_l[i] - tz[i]) / (1.0 - zt[i] * y_l[i])
    y_r[-1] = 1.0 / z0_air
    for i in range(n_seg - 1, -1, -1):
        y_r[i] = (y_r[i + 1] + tz[i]) / (1.0 + zt[i] * y_r[i + 1])
    gain_l = sech / (1.0 - zt * y_l[:-1])
    gain_r = sech / (1.0 + zt * y_r[1:])
    out = []
    for src in sources:
        phi_p = src / seg.r                      # particular flux of a uniform winding
        j_l = np.zeros(seg.b.shape, dtype=dtype)
        j_r = np.zeros(seg.b.shape, dtype=dtype)
        for i in range(n_seg):
            j_l[i + 1] = (j_l[i] - phi_p[i]) * gain_l[i] + phi_p[i]
        for i in range(n_seg - 1, -1, -1):
            j_r[i] = (j_r[i + 1] - phi_p[i]) * gain_r[i] + phi_p[i]
        u = (j_r - j_l) / (y_l - y_r)
        flux_integral = (src * length - np.diff(u, axis=0)) / seg.r
        out.append((u, flux_integral))
    return out


_INDUCTANCES: "OrderedDict[tuple, tuple[np.ndarray, ...]]" = OrderedDict()
_TABLES: "OrderedDict[tuple, tuple]" = OrderedDict()

# Calls with at least TABLE_MIN_POINTS distinct positions interpolate a per-geometry table
# of TABLE_POINTS exact solutions (cubic Hermite, 4th-order slopes; error ~1e-7 of full
# scale for the paper's sensor, tests/test_physics_lvdt.py).  The choice depends only on the
# number of positions, never on call history, so a least-squares fit (fixed positions) sees
# one consistent, C1-smooth function for its finite-difference Jacobians.
TABLE_MIN_POINTS = 400
TABLE_POINTS = 1601
# A caller that evaluates one geometry thousands of times (the diagnosis' fits, after its
# geometry is calibrated) takes the table at any number of positions: one table costs about
# as much as eight exact solves of 250 positions, and it is the same function at every call.
_TABULATED: ContextVar[bool] = ContextVar("tabulated", default=False)


@contextmanager
def tabulated():
    """Inside, every call interpolates the per-geometry table, whatever its number of
    positions (see TABLE_MIN_POINTS)."""
    token = _TABULATED.set(True)
    try:
        yield
    finally:
        _TABULATED.reset(token)


def _exact(s: Sensor, pos_mm: np.ndarray, loop: bool) -> list[np.ndarray]:
    mg = magnetics(s)
    seg = _segments(mg, pos_mm * 1e-3)
    sources = [seg.n_p]
    if loop:
        sources.append(seg.n_s1 - seg.n_s2)
    solved = _solve(mg, seg, tuple(sources))
    _u, fi = solved[0]
    res = [np.einsum("ij,ij->j", fi, seg.n_s1), np.einsum("ij,ij->j", fi, seg.n_s2),
           np.einsum("ij,ij->j", fi, seg.n_p)]
    if loop:
        _u, fl = solved[1]
        res.append(np.einsum("ij,ij->j", fl, seg.n_s1 - seg.n_s2))
    return res


def table_half_range_mm(s: Sensor) -> float:
    """Core positions covered by the interpolation table: until the core has left."""
    return s.coil_span_mm / 2 + s.core_length_mm / 2 + 0.1 * s.coil_span_mm


def _table(s: Sensor, loop: bool):
    """The geometry's table: its first position, its step, and per value and interval the
    cubic Hermite polynomial's coefficients (values, 4, intervals)."""
    key = (s.magnetics_key(), loop)
    hit = _TABLES.get(key)
    if hit is not None:
        _TABLES.move_to_end(key)
        return hit
    half = table_half_range_mm(s)
    pos = np.linspace(-half, half, TABLE_POINTS)
    y = np.stack(_exact(s, pos, loop))                     # (values, positions)
    d = np.gradient(y, axis=1)
    d[:, 2:-2] = (-y[:, 4:] + 8 * y[:, 3:-1] - 8 * y[:, 1:-3] + y[:, :-4]) / 12
    y0, y1, d0, d1 = y[:, :-1], y[:, 1:], d[:, :-1], d[:, 1:]
    # y(t) = y0 + d0 t + (3 (y1 - y0) - 2 d0 - d1) t^2 + (2 (y0 - y1) + d0 + d1) t^3
    coef = np.stack([y0, d0, 3 * (y1 - y0) - 2 * d0 - d1, 2 * (y0 - y1) + d0 + d1], 1)
    hit = (float(pos[0]), float(pos[1] - pos[0]), coef)
    _TABLES[key] = hit
    if len(_TABLES) > _CACHE_SIZE:
        _TABLES.popitem(last=False)
    return hit


def _interpolate(table, xq: np.ndarray) -> list[np.ndarray]:
    start, step, coef = table
    t = (xq - start) / step
    i = np.minimum(np.floor(t).astype(np.intp), coef.shape[2] - 1)
    t = t - i
    c = coef[:, :, i]                                      # (values, 4, positions)
    return list(((c[:, 3] * t + c[:, 2]) * t + c[:, 1]) * t + c[:, 0])


def inductances_h(s: Sensor, core_position_mm, loop: bool = False) -> tuple[np.ndarray, ...]:
    """(M1, M2, Lp) in henry at the core-centre positions (mm); with ``loop=True`` also the
    self-inductance of the two secondaries in series opposition.  Exact line solution for
    fewer than TABLE_MIN_POINTS distinct positions, otherwise a cached per-geometry table
    (see above); inside :func:`tabulated`, the table at any number.  Results are cached on geometry and positions, so a fit that varies only
    electrical parameters pays once."""
    x = np.asarray(core_position_mm, dtype=float)
    table = _TABULATED.get()
    key = (s.magnetics_key(), loop, table, x.shape, x.tobytes())
    hit = _INDUCTANCES.get(key)
    if hit is not None:
        _INDUCTANCES.move_to_end(key)
        return hit
    flat = x.ravel()
    if table and flat.size:
        out = tuple(r.reshape(x.shape) for r in _tabulate(s, flat, loop))
    elif TABLE_MIN_POINTS > flat.size > 1 and flat.min() < flat.max():
        # exact at every position as given, without sorting out the distinct ones (a fit's
        # many small calls): each position's solution is its own, the same numbers either
        # way; a single distinct position stays one (its flux sums take another path)
        out = tuple(r.reshape(x.shape) for r in _exact(s, flat, loop))
    else:
        out = _distinct(s, flat, loop, x.shape)
    for arr in out:
        arr.setflags(write=False)
    _keep(key, out, x.nbytes + sum(a.nbytes for a in out))
    return out


def _distinct(s: Sensor, flat: np.ndarray, loop: bool, shape) -> tuple[np.ndarray, ...]:
    """inductances_h on the distinct positions of ``flat``: exact, or interpolated from the
    table when there are at least TABLE_MIN_POINTS of them."""
    flat, inverse = np.unique(flat, return_inverse=True)
    res = _tabulate(s, flat, loop) if flat.size >= TABLE_MIN_POINTS else _exact(s, flat, loop)
    return tuple(r[inverse].reshape(shape) for r in res)


def _tabulate(s: Sensor, flat: np.ndarray, loop: bool) -> list[np.ndarray]:
    """The table's interpolation at the positions it spans, exact beyond them."""
    inside = np.abs(flat) <= table_half_range_mm(s)
    if inside.all():
        return _interpolate(_table(s, loop), flat)
    interp = _interpolate(_table(s, loop), flat[inside])
    res = [np.empty(flat.size, dtype=complex) for _ in range(4 if loop else 3)]
    exact = _exact(s, flat[~inside], loop)
    for k in range(len(res)):
        res[k][inside] = interp[k]
        res[k][~inside] = exact[k]
    if not any(np.iscomplexobj(v) for v in interp):
        res = [r.real.copy() for r in res]
    return res


# Inductances kept: the most recent results up to this many and this many bytes (positions
# and values).  A diagnosis revisits positions (a fit's trial points, the starts of the
# next fits, the same point under another number of shape terms, the geometry grid of the
# previous sensor recorded at the same positions): about a quarter of its line solutions
# were repeats that 32 entries had already dropped.
_INDUCTANCE_ENTRIES = 8192
_INDUCTANCE_BYTES = 64e6
_INDUCTANCE_SIZES: dict = {}
_inductance_bytes = [0]


def _keep(key, out, size: int) -> None:
    if key in _INDUCTANCE_SIZES:
        _inductance_bytes[0] -= _INDUCTANCE_SIZES.pop(key)
    _INDUCTANCES[key] = out
    _INDUCTANCE_SIZES[key] = size
    _inductance_bytes[0] += size
    while len(_INDUCTANCES) > 1 and (len(_INDUCTANCES) > _INDUCTANCE_ENTRIES
                                     or _inductance_bytes[0] > _INDUCTANCE_BYTES):
        old, _ = _INDUCTANCES.popitem(last=False)
        _inductance_bytes[0] -= _INDUCTANCE_SIZES.pop(old)


def coupling_table(s: Sensor, half_range_mm: float | None = None, n: int = 401) -> CouplingTable:
    """Inductances on a uniform grid of core positions (default: until the core has left
    the windings at both ends), for plots and inspection."""
    if half_range_mm is None:
        half_range_mm = s.coil_span_mm / 2 + s.core_length_mm / 2 + 0.1 * s.coil_span_mm
    pos = np.linspace(-half_range_mm, half_range_mm, n)
    m1, m2, lp, ll = inductances_h(s, pos, loop=True)
    return CouplingTable(pos, m1, m2, lp, ll)


def primary_current_a(s: Sensor, lp_h) -> np.ndarray:
    """Complex peak primary current for a voltage-driven primary of inductance ``lp_h``."""
    return s.excitation_peak_v / (s.primary_resistance_ohm + 1j * s.omega_rad_s * np.asarray(lp_h))


_REFERENCE_PHASES: dict[tuple, float] = {}


def reference_phase_rad(s: Sensor) -> float:
    """Phase-sensitive detector reference, trimmed at null as in practice: the phase of
    the differential e.m.f. for a small core movement, ``arg(j w Ip(0) dM_d/dx(0))``
    (``arg(j w Ip(0))`` when the inductances are real, i.e. without eddy currents).
    Cached on what it depends on (every simulated output asks for it)."""
    key = (s.magnetics_key(), s.primary_resistance_ohm, s.excitation_amplitude_vpp,
           s.excitation_frequency_hz)
    hit = _REFERENCE_PHASES.get(key)
    if hit is not None:
        return hit
    m1, m2, lp = inductances_h(s, np.array([-1e-3, 0.0, 1e-3]))
    slope = (m1[2] - m2[2]) - (m1[0] - m2[0])
    slope_phase = float(np.angle(slope)) if np.iscomplexobj(slope) and slope != 0 else 0.0
    phase = float(np.angle(1j * s.omega_rad_s * primary_current_a(s, lp[1]))) + slope_phase
    if len(_REFERENCE_PHASES) >= 4096:   # a float each; a diagnosis tries ~1,000 geometries
        _REFERENCE_PHASES.clear()
    _REFERENCE_PHASES[key] = phase
    return phase


def secondary_emf_v(s: Sensor, core_position_mm, drive_scale=1.0) -> tuple[np.ndarray, np.ndarray]:
    """Complex peak e.m.f.s (v1, v2) of the unloaded secondaries; ``drive_scale``
    multiplies the primary current (e.g. thermal drift of the primary's resistance)."""
    m1, m2, lp = inductances_h(s, core_position_mm)
    jw_ip = 1j * s.omega_rad_s * primary_current_a(s, lp) * drive_scale
    return jw_ip * m1, jw_ip * m2


def demodulate_v(s: Sensor, v_diff, quadrature_v=0.0) -> np.ndarray:
    """Output volts of the demodulator for a complex differential e.m.f. ``v_diff``.

    ``quadrature_v`` is an output-referred residual in quadrature with the reference (the
    null residual of capacitive coupling and harmonics): the phase-sensitive detector rejects
    it, the amplitude detector adds it in quadrature.
    """
    g = s.demodulator_gain_ratio
    rotated = np.asarray(v_diff) * np.exp(-1j * reference_phase_rad(s))
    if s.demodulator_kind == "phase_sensitive":
        return g * rotated.real
    return g * np.hypot(rotated.real, rotated.imag + quadrature_v / g)


def ideal_output_v(s: Sensor, displacement_mm) -> np.ndarray:
    """Demodulated output (V) of the ideal sensor (no effects) with the core centre at
    ``displacement_mm``.  Vectorised (see :func:`inductances_h` for exact vs table)."""
    v1, v2 = secondary_emf_v(s, displacement_mm)
    return demodulate_v(s, v1 - v2)


def null_slope_v_per_mm(s: Sensor, dx_mm: float = 0.01) -> float:
    """Sensitivity of the ideal output at null (V/mm), by a central difference."""
    y = ideal_output_v(s, np.array([-dx_mm, dx_mm]))
    return float((y[1] - y[0]) / (2 * dx_mm))


def flux_profile(s: Sensor, core_position_mm: float, z_mm) -> np.ndarray:
    """Axial flux (Wb per A of primary current) at the axial positions ``z_mm`` with the
    core centre at ``core_position_mm`` (for plots and tests)."""
    mg = magnetics(s)
    seg = _segments(mg, np.array([core_position_mm * 1e-3]))
    (u, _fi), = _solve(mg, seg, (seg.n_p,))
    b, r, src, u = seg.b[:, 0], seg.r[:, 0], seg.n_p[:, 0], u[:, 0]
    g = mg.g_leak
    z = np.asarray(z_mm, dtype=float) * 1e-3
    z0_air = math.sqrt(mg.r_air / g)
    k_air = math.sqrt(mg.r_air * g)
    out = np.empty(z.shape, dtype=np.result_type(seg.r, float))
    left, right = z < b[0], z >= b[-1]
    out[left] = -u[0] / z0_air * np.exp(k_air * (z[left] - b[0]))
    out[right] = u[-1] / z0_air * np.exp(-k_air * (z[right] - b[-1]))
    for i in range(b.size - 1):
        m = (z >= b[i]) & (z < b[i + 1])
        if not m.any():
            continue
        z0 = np.sqrt(r[i] / g)
        k = np.sqrt(r[i] * g)
        length = b[i + 1] - b[i]
        # u = alpha e^{-k d} + beta e^{-k (L - d)} from both ends (no growing exponentials);
        # Phi = s/R' - u'/R' = phi_p + (alpha e^{-k d} - beta e^{-k (L - d)}) / Z0.
        e = np.exp(-k * length)
        det = 1.0 - e * e
        alpha = (u[i] - e * u[i + 1]) / det
        beta = (u[i + 1] - e * u[i]) / det
        d = z[m] - b[i]
        out[m] = (src[i] / r[i] + (alpha * np.exp(-k * d) - beta * np.exp(-k * (length - d))) / z0)
    return out


def describe(s: Sensor) -> dict[str, float]:
    """Derived quantities of the ideal sensor at null (for ``flann simulate --describe``)."""
    mg = magnetics(s)
    m1, _m2, lp = (v[0] for v in inductances_h(s, np.zeros(1)))
    ip = primary_current_a(s, lp)
    half = s.coil_span_mm / 2 + s.core_length_mm
    z = np.linspace(-half, half, 2001)
    phi = np.abs(flux_profile(s, 0.0, z))
    a_core = math.pi / 4 * (s.core_outer_diameter_mm ** 2 - s.core_inner_diameter_mm ** 2) * 1e-6
    mu = core_permeability_eff(s)
    return {
        "null_slope_v_per_mm": null_slope_v_per_mm(s),
        "primary_inductance_h": float(abs(lp)),
        "primary_current_ma_peak": float(abs(ip) * 1e3),
        "secondary_emf_v_peak_at_null": float(abs(s.omega_rad_s * m1 * ip)),
        "core_peak_flux_density_mt": float(phi.max() * abs(ip) / a_core * 1e3),
        "core_decay_length_mm": float(1e3 / np.abs(np.sqrt(complex(mg.r_core) * mg.g_leak))),
        "core_permeability_eff_abs": float(abs(mu)),
        "core_permeability_eff_phase_deg": float(np.degrees(np.angle(mu))),
    }
