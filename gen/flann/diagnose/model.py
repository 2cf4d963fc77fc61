"""The calibrated ideal simulation plus candidate effects, as one least-squares family.

Every candidate effect is the physics simulator's own (:data:`flann.physics.effects.EFFECTS`,
applied by :func:`flann.physics.simulate.simulate_output_v`): this module only decides which
parameters are free, where the fit starts, and which effects the recordings can test.

Free parameters of the baseline (the ideal simulation):

* ``gain_ratio`` -- the demodulator gain (its sign is the output's sign convention);
* ``origin_mm`` -- the displacement at which the core is centred, unless the origin is
  known (a sensor file was given): recordings may start at 0 mm with the null mid-way;
* ``shape_1..K`` -- when the geometry is unknown, the leading K modes of how the output's
  shape changes with the winding/core geometry (derivatives of the simulated output with
  respect to the geometry fields, at the calibrated geometry, made orthogonal to gain and
  origin).  They let the geometry re-adjust, to first order, together with every
  candidate effect, so a geometry the nonlinear calibration got slightly wrong is never
  mistaken for missing physics, and an effect is not blamed on geometry either.

Geometry itself (winding lengths, core length, bore) is calibrated once, nonlinearly, by
:mod:`flann.diagnose.calibrate`: rebuilding the magnetics table costs ~0.1 s, too slow to
repeat inside every candidate fit.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from ..physics.effects import EFFECTS
from ..physics.lvdt import tabulated
from ..physics.simulate import simulate_output_v
from .select import Fit, make_folds


def simulate_at_fixed_geometry(*args, **kwargs) -> np.ndarray:
    """The simulator at a calibrated geometry, which a diagnosis evaluates thousands of
    times: through the geometry's magnetics table (:func:`flann.physics.lvdt.tabulated`),
    the same function at every call whatever its number of positions."""
    with tabulated():
        return simulate_output_v(*args, **kwargs)


# candidate numbers of smooth shape terms (chosen by cross-validation).  The grid goes
# on while it pays: a sensor whose geometry is a few % off the simulated one (a production
# line diagnosed with the nominal sensor file) leaves a misfit ~1,000x its noise, which
# needs up to ~16 terms; the search stops after STOP_AFTER numbers in a row that do not
# improve the best out-of-fold error by 1 %.
SHAPE_TERMS = (0, 2, 3, 4, 6, 8, 10, 12, 14, 16)
STOP_AFTER = 2
# relative singular-value cut-off of the shape term's least squares
RCOND = 1e-10
# the shape bases a family keeps for reuse, at most (bytes)
CACHE_BYTES = 200e6
# readings a fitted rail clips that rise by more than this fraction of the unclipped model's
# rise, and by RAIL_T standard errors, are not on a rail (see PhysicsFamily.implausible)
RAIL_SLOPE = 0.1
RAIL_T = 3.0
# simulated outputs a family keeps (a fit's Jacobian asks for a handful at a time)
SIM_CACHE = 64
# Levenberg-Marquardt stops when the relative change of the sum of squares (and of the
# step) would move BIC (n ln RSS) by less than this: far inside the 10 an effect must move
# it by and the 2 of a tie; tighter only wandered on (up to 4x the evaluations).  On 2,000
# points that is 1e-5 of the RSS, on a production line's 250 bin means 8e-5.
TOL_BIC = 0.02
TOL_MIN, TOL_MAX = 1e-8, 1e-4


def fit_tolerance(points: int) -> float:
    """The relative change of the sum of squares (and of the step) at which a fit on
    ``points`` points stops: TOL_BIC of BIC."""
    return float(np.clip(TOL_BIC / max(points, 1), TOL_MIN, TOL_MAX))

# secondary_imbalance's extra, diagnosis-only parameter (not in the catalogue): how much
# the sum of the secondaries bends along the stroke beyond the calibrated simulation's,
# as a factor 1 + c (core / half-range)^2 on the imbalance's contribution
SUM_CURVATURE = "sum_curvature"
NEUTRAL_EXTRA = {"secondary_imbalance": {SUM_CURVATURE: 0.0}}

# Effects the diagnosis tries, in catalogue order (secondary_loading is left out: with
# unknown geometry its position-dependent gain is a shape change, not a signature).
CANDIDATES = ("null_offset", "quadrature_null", "zero_shift", "secondary_imbalance",
              "backlash", "thermal_drift", "adc_clipping", "leadscrew_periodic")


@dataclass(frozen=True)
class Data:
    """The points being diagnosed (outliers and fold-back already removed by the caller)."""

    x: np.ndarray
    y: np.ndarray
    direction: np.ndarray | None        # +-1, given or inferred from the sweep order
    temperature_c: np.ndarray | None
    time_s: np.ndarray | None


@dataclass(frozen=True)
class ParamSpec:
    name: str          # "baseline.gain_ratio", "backlash.deadband_mm", ...
    lower: float
    upper: float
    unit: str


class ShapeModes:
    """K functions of the core position: first-order geometry corrections (unit gain)."""

    def __init__(self, grid_mm: np.ndarray, modes: np.ndarray, fields: tuple[str, ...],
                 slope: np.ndarray):
        self.grid_mm = grid_mm
        self.modes = modes            # (K, grid) per unit of the demodulator gain
        self.fields = fields
        self.slope = slope            # d(ideal output)/dx per unit gain on the grid

    @property
    def k(self) -> int:
        return int(self.modes.shape[0])

    def evaluate(self, core_mm: np.ndarray) -> np.ndarray:
        return np.stack([np.interp(core_mm, self.grid_mm, m) for m in self.modes])


class OddBasis:
    """Smooth odd functions of the core position: the shape of this sensor that the
    physics model's geometry cannot take (model-form error).

    ``k`` differences of Gaussians ``g(u - c_j) - g(u + c_j)``, centres ``c_j = j U / k``
    over the recorded half-range ``U``, width ``U / k``: odd about the null, the same in
    both directions of travel and at every time, and too broad to draw a short period, a
    flat rail or the rounded tip of a V.  With ``warp`` (a grid and the simulated slope on
    it) the same k functions times the slope are added: a smooth warp of the displacement
    axis, ``y(u + d(u)) - y(u) ~ slope(u) d(u)``.  A winding or core a few % longer moves
    the knee where the curve bends into saturation; the misfit is then sharp at the knee
    while the warp ``d`` is smooth, so a few warp terms take what plain terms would need
    dozens for (and what they would leave as a ripple that looks like a lead screw).
    Their coefficients are linear and solved in closed form inside every fit (variable
    projection), so they cost no iterations.

    With ``known`` (a grid and rows of functions on it: the simulated output per unit
    gain and the geometry's shape modes) every term has its least-squares share of those
    functions over the recorded range taken out.  Odd terms can draw a change of gain or
    geometry; left in, neither is identified (any gain fits, the terms making up the
    rest: its standard error reached 75 % of its value, and a 30 um backlash was read as
    100 um).  The fitted curve is the same; the terms keep only what the simulation
    cannot draw.
    """

    def __init__(self, half_range_mm: float, k: int, rectified: bool = False, warp=None,
                 known=None):
        self.half = max(float(half_range_mm), 1e-9)
        self.k = int(k)
        self.rectified = rectified
        self.warp = warp
        self.known = known
        self.centres = self.half * np.arange(1, self.k + 1) / max(self.k, 1)
        self.width = self.half / max(self.k, 1)
        self._share = None
        self._modes_seen = (None, None)   # the last positions' shape modes (see _known_at)
        if known is not None:
            u = np.linspace(-self.half, self.half, 401)
            self._share = np.linalg.lstsq(self._known_at(u), self._raw(u), rcond=RCOND)[0]

    @property
    def ncols(self) -> int:
        """Columns of the basis matrix (coefficients of the shape term)."""
        return self.k * (1 if self.warp is None else 2)

    def evaluate(self, core_mm: np.ndarray, shift_mm: float = 0.0) -> np.ndarray:
        """(n, ncols) basis matrix at the core positions, the terms moved by a zero shift.

        The shares taken out are of the functions as the fit has them: the simulated output
        moved by the shift (the simulation applies it), the shape modes where they are (the
        fit evaluates them at the unshifted positions), so the span is the fit's own."""
        raw = self._raw(np.asarray(core_mm, float) - shift_mm)
        return raw if self._share is None else raw - self._known_at(core_mm, shift_mm) @ self._share

    def _known_at(self, core_mm: np.ndarray, shift_mm: float = 0.0) -> np.ndarray:
        grid, rows = self.known
        u = np.asarray(core_mm, float)
        # the output row first (moved by the shift), then the modes, which do not move: a
        # fit's every zero shift asks at the same positions, so the last ones are kept
        seen, modes = self._modes_seen
        if seen is None or seen.shape != u.shape or not np.array_equal(seen, u):
            modes = [np.interp(u, grid, r) for r in rows[1:]]
            self._modes_seen = (u.copy(), modes)
        return np.stack([np.interp(u - shift_mm, grid, rows[0])] + modes, 1)

    def _raw(self, core_mm: np.ndarray) -> np.ndarray:
        u = np.asarray(core_mm, float)[:, None]
        c = self.centres[None, :]
        b = np.exp(-((u - c) / self.width) ** 2) - np.exp(-((u + c) / self.width) ** 2)
        w = None
        if self.warp is not None:
            grid, slope = self.warp
            # the simulated slope already carries the rectified curve's sign
            w = b * np.interp(u[:, 0], grid, slope)[:, None]
        if self.rectified:   # an amplitude detector folds the odd shape into an even one
            b = b * np.where(u >= 0, 1.0, -1.0)
        return b if w is None else np.hstack([b, w])

    def describe(self) -> str:
        warp = (f", plus the same {self.k} times the simulated slope (a smooth warp of the "
                "displacement axis)") if self.warp is not None else ""
        return (f"{self.k} odd Gaussian terms in core position (width {self.width:.3g} mm)"
                f"{warp}, complexity chosen by 5-fold cross-validation with the named effects "
                "in place")


def _points_key(idx: np.ndarray, core: np.ndarray) -> tuple:
    """The cache key of the points ``idx`` at the core positions ``core``: made once per
    evaluation, which asks for its simulations, shape basis and modes row by row."""
    return idx.size, hash(idx.tobytes()), hash(core.tobytes())


def _shape_coef(ncols: int, B, pinv, y, target, lo, hi) -> np.ndarray:
    """The shape terms' coefficients that take ``y`` to ``target`` where it is within the rails
    (none without a target, or when too few points are)."""
    if target is None:
        return np.zeros(ncols)
    free = (y < hi) & (y > lo)
    if free.all():
        return pinv() @ (target - y)
    if free.sum() > ncols:
        return np.linalg.lstsq(B[free], (target - y)[free], rcond=RCOND)[0]
    return np.zeros(ncols)


class PhysicsFamily:
    """Least-squares fits of the calibrated ideal simulation + any set of catalogue effects."""

    def __init__(self, sensor, data: Data, origin_known: bool, shape: ShapeModes | None,
                 gain0: float, origin0: float, scale: float = 1.0,
                 shape_ref: OddBasis | None = None, origin_from_travel: bool = False,
                 terms: int = 0, equivalent_terms: tuple[int, ...] = ()):
        self.sensor = sensor.replace(effects={})
        self.shape_ref = shape_ref  # half-range, rectification and warp of the shape term
        # shape terms of a fit that starts from nothing, and the numbers of terms that
        # cross-validate as well (see choose_terms); a fit carries its own in ``extra``
        self.terms = int(terms) if shape_ref is not None else 0
        self.equivalent_terms = tuple(equivalent_terms)
        self.origin_from_travel = origin_from_travel
        self.data = data
        self.origin_known = origin_known
        self.shape = shape
        self.gain0 = float(gain0)
        self.origin0 = float(origin0)
        self.scale = float(scale)     # sensor mm per recorded displacement unit
        y = data.y
        self.v_range = float(np.ptp(y)) or 1.0
        self.t_ref = (float(np.mean(data.temperature_c))
                      if data.temperature_c is not None else 20.0)
        self.untestable = self._untestable()
        self.candidates = tuple(c for c in CANDIDATES if c not in self.untestable)
        self._shape_cache: dict = {}
        self._sim_cache: dict = {}
        self._plans: dict = {}
        self._bases: dict = {}
        self._gains_ok: set = set()   # gains a sensor accepts (every copy's: the same sensor)
        self.nfev = 0

    # -- which effects these recordings can reveal ----------------------------------
    def _untestable(self) -> dict[str, str]:
        d = self.data
        out = {}
        if self.sensor.demodulator_kind == "phase_sensitive":
            out["quadrature_null"] = "a phase-sensitive detector rejects quadrature"
        if not self.origin_known:
            out["zero_shift"] = ("the travel is not centred on 0 mm and there is no sensor file: "
                                 "the null position is calibration (origin_mm)")
        if d.direction is None or np.unique(d.direction).size < 2:
            out["backlash"] = "needs travel in both directions"
        if d.temperature_c is None or np.ptp(d.temperature_c) == 0:
            out["thermal_drift"] = "needs a temperature_c column that varies"
        if np.unique(d.x).size < 12:
            out["leadscrew_periodic"] = "needs at least 12 distinct displacements"
        return out

    # -- parameters ------------------------------------------------------------------
    def specs(self, effects, clip_sides: str = "both") -> list[ParamSpec]:
        span_x = float(np.ptp(self.data.x))        # recorded units (origin)
        span = span_x * self.scale                 # sensor mm (position effects)
        out = [ParamSpec("baseline.gain_ratio", *sorted((self.gain0 * 0.2, self.gain0 * 5.0)), "")]
        if not self.origin_known:
            out.append(ParamSpec("baseline.origin_mm", self.origin0 - span_x,
                                 self.origin0 + span_x, "mm"))
        if self.shape is not None:
            out += [ParamSpec(f"baseline.shape_{k + 1}", -2.0, 2.0, "") for k in range(self.shape.k)]
        ymax = float(np.max(np.abs(self.data.y)))
        for e in effects:
            if e == "null_offset":
                out.append(ParamSpec("null_offset.offset_v", -self.v_range, self.v_range, "V"))
            elif e == "quadrature_null":
                out.append(ParamSpec("quadrature_null.quadrature_v", 0.0, self.v_range, "V"))
            elif e == "zero_shift":
                out.append(ParamSpec("zero_shift.shift_mm", -span / 2, span / 2, "mm"))
            elif e == "secondary_imbalance":
                out += [ParamSpec("secondary_imbalance.imbalance_fraction", -0.5, 0.5, ""),
                        ParamSpec("secondary_imbalance.sum_curvature", -0.9, 3.0, "")]
            elif e == "backlash":
                out.append(ParamSpec("backlash.deadband_mm", 0.0, span / 10, "mm"))
            elif e == "thermal_drift":
                out.append(ParamSpec("thermal_drift.coefficient_per_c", -0.05, 0.05, "1/degC"))
            elif e == "adc_clipping":
                # each rail on its own (amplifier rails are rarely symmetric)
                if clip_sides in ("high", "both"):
                    out.append(ParamSpec("adc_clipping.rail_high_v", -3 * ymax, 3 * ymax, "V"))
                if clip_sides in ("low", "both"):
                    out.append(ParamSpec("adc_clipping.rail_low_v", -3 * ymax, 3 * ymax, "V"))
            elif e == "leadscrew_periodic":
                step = self._typical_step()
                out += [ParamSpec("leadscrew_periodic.amplitude_mm", -span / 20, span / 20, "mm"),
                        # at least 3 readings per period: nearer the sampling limit a period
                        # is an alias of point-to-point scatter (rounding of the readings)
                        ParamSpec("leadscrew_periodic.period_mm", 3 * step,
                                  max(self.max_period(), 3.05 * step), "mm"),
                        ParamSpec("leadscrew_periodic.phase_rad", -4 * math.pi, 4 * math.pi, "rad")]
            else:
                raise ValueError(f"unknown candidate {e}")
        return out

    def _half_range(self) -> float:
        if self.shape_ref is not None:
            return self.shape_ref.half
        return max(float(np.max(np.abs((self.data.x - self.origin0) * self.scale))), 1e-9)

    def max_period(self) -> float:
        """A lead-screw period must be short against the stroke: the smooth shape term
        draws anything slower."""
        return float(np.ptp(self.data.x)) * self.scale / 8

    def _typical_step(self) -> float:
        """The median step between the positions of one direction of travel: where the two
        directions sample different positions (bin means of each pass), a period shorter
        than three of a pass's steps would alias the direction split into a ripple."""
        d = self.data
        groups = ([d.x[d.direction == s] for s in np.unique(d.direction)]
                  if d.direction is not None else [d.x])
        steps = [float(np.median(np.diff(u))) for u in map(np.unique, groups) if u.size > 1]
        return max(steps) * self.scale if steps else 1.0

    # -- the model -------------------------------------------------------------------
    def _unpack(self, theta: np.ndarray, names: list[str]):
        pos, plan = self._plan(names)
        gain = theta[0]
        origin = self.origin0 if self.origin_known else theta[1]
        shape = None if self.shape is None else theta[pos - self.shape.k:pos]
        eff: dict[str, dict[str, float]] = {}
        for e, full, params in plan:
            eff[e] = dict(full)
            eff[e].update((p, float(theta[i])) for p, i in params)
        return float(gain), float(origin), shape, eff

    def _plan(self, names) -> tuple:
        """How a parameter vector with ``names`` unpacks (every evaluation asks): where the
        effects start, and per effect its neutral parameters and (name, index) of the fitted
        ones; and the indices :meth:`_physical` bounds."""
        key = tuple(names)
        hit = self._plans.get(key)
        if hit is None:
            pos = 1 + (not self.origin_known) + (0 if self.shape is None else self.shape.k)
            grouped: dict[str, list] = {}
            for i, name in enumerate(names[pos:], pos):
                e, p = name.split(".", 1)
                grouped.setdefault(e, []).append((p, i))
            plan = []
            for e, params in grouped.items():
                full = {**EFFECTS[e].neutral(), **NEUTRAL_EXTRA.get(e, {})}
                if e == "thermal_drift":
                    full["reference_temperature_c"] = self.t_ref
                plan.append((e, full, tuple(params)))
            one = np.array([i for i, n in enumerate(names) if n in self._ONE_SIDED], dtype=np.intp)
            two = [i for i, n in enumerate(names) if n not in self._ONE_SIDED and n in self._CLIPPED]
            bounds = np.array([self._CLIPPED[names[i]] for i in two], dtype=float).reshape(-1, 2)
            turn = [i for i, n in enumerate(names) if n in self._TURNS]
            hit = self._plans[key] = (pos, tuple(plan), one, np.array(two, dtype=np.intp), bounds,
                                      tuple(turn))
        return hit[:2]

    _ONE_SIDED = ("quadrature_null.quadrature_v", "backlash.deadband_mm",
                  "leadscrew_periodic.period_mm")
    # (lower, upper); the sum's bend keeps 1 + c u^2 > 0 so the imbalance keeps its sign
    _CLIPPED = {"secondary_imbalance.imbalance_fraction": (-0.9, 0.9),
                "secondary_imbalance.sum_curvature": (-0.9, 3.0),
                "thermal_drift.coefficient_per_c": (-0.2, 0.2)}

    # angles, with the range the catalogue accepts
    _TURNS = {"leadscrew_periodic.phase_rad": EFFECTS["leadscrew_periodic"].bounds()["phase_rad"]}

    def _physical(self, theta: np.ndarray, names: list[str]) -> np.ndarray:
        """Map unconstrained fit parameters to physical ones (non-negative, bounded); a 2-D
        ``theta`` maps each row (elementwise: the same numbers as row by row)."""
        th = np.array(theta, dtype=float)
        self._plan(names)
        _, _, one, two, bounds, turn = self._plans[tuple(names)]
        if one.size:
            th[..., one] = np.abs(th[..., one])
        if two.size:
            th[..., two] = np.clip(th[..., two], bounds[:, 0], bounds[:, 1])
        for i in turn:
            # a phase the fit wound past the catalogue's range (the simulator refuses it and
            # the whole diagnosis failed) is the same phase within one turn
            lo, hi = self._TURNS[names[i]]
            for row in th.reshape(-1, th.shape[-1]):
                if not lo <= row[i] <= hi:
                    row[i] = math.pi - (math.pi - row[i]) % (2 * math.pi)
        return th

    @staticmethod
    def _canonical(theta: np.ndarray, names: list[str]) -> np.ndarray:
        """Same model, conventional parameters: a positive lead-screw amplitude, its phase
        in (-pi, pi]."""
        th = np.array(theta, dtype=float)
        if "leadscrew_periodic.amplitude_mm" in names:
            ia = names.index("leadscrew_periodic.amplitude_mm")
            ip = names.index("leadscrew_periodic.phase_rad")
            if th[ia] < 0:
                th[ia] = -th[ia]
                th[ip] += math.pi
            th[ip] = math.pi - (math.pi - th[ip]) % (2 * math.pi)
        return th

    def evaluate(self, theta: np.ndarray, names: list[str], idx: np.ndarray,
                 coef: np.ndarray | None = None, target: np.ndarray | None = None,
                 want_coef: bool = False, basis: OddBasis | None = None):
        """Model output at the points ``idx``.  With a shape term (``basis``), its
        coefficients are ``coef`` or, given ``target``, solved by least squares against it
        (on the points the rails leave free); ``want_coef`` returns (output, coef)."""
        self.nfev += 1
        gain, origin, shape, eff = self._unpack(self._physical(theta, names), names)
        d = self.data
        curvature = eff.get("secondary_imbalance", {}).pop(SUM_CURVATURE, 0.0)
        inner = {k: v for k, v in eff.items() if EFFECTS[k].stage != "output"}
        core = (d.x[idx] - self.origin0) * self.scale
        at = _points_key(idx, core)
        # The core positions use the calibrated origin, so the simulator's magnetics cache
        # is hit whenever no position effect is on; a change of origin enters to first
        # order through the slope (it is ~1e-3 mm inside the effect fits).
        y = self._simulate(gain, inner, idx, core, at)
        if curvature:
            # the imbalance's even part follows the sum of the secondaries, whose change
            # along the stroke the calibrated simulation knows only roughly: let it bend
            without = {k: v for k, v in inner.items() if k != "secondary_imbalance"}
            y0 = self._simulate(gain, without, idx, core, at)
            u = core / self._half_range()
            y = y + curvature * u ** 2 * (y - y0)
        if self.shape is not None:
            modes = self._modes_at(idx, core, at)
            if origin != self.origin0:
                y = y - gain * (origin - self.origin0) * self.scale * modes[0]
            if shape is not None:
                y = y + gain * (shape @ modes[1:])
        elif origin != self.origin0:
            y = y - gain * (origin - self.origin0) * self.scale * self._slope_at(idx, core)
        if "null_offset" in eff:
            y = y + eff["null_offset"]["offset_v"]
        hi = eff.get("adc_clipping", {}).get("rail_high_v", math.inf)
        lo = eff.get("adc_clipping", {}).get("rail_low_v", -math.inf)
        if basis is not None:
            # the shape follows a zero shift (it may be large); the origin's own change
            # inside a fit (~1e-3 mm) would only move it by a negligible amount, and keeping
            # it fixed lets every evaluation reuse one factorisation of the basis
            shift = eff.get("zero_shift", {}).get("shift_mm", 0.0)
            B, pinv = self._basis_at(basis, idx, core, shift, at)
            if coef is None:
                coef = _shape_coef(basis.ncols, B, pinv, y, target, lo, hi)
            y = y + B @ coef
        if "adc_clipping" in eff:
            y = np.clip(y, lo, hi)
        return (y, coef) if want_coef else y

    def evaluate_many(self, thetas, names: list[str], idx: np.ndarray,
                      coef: np.ndarray | None = None, target: np.ndarray | None = None,
                      basis: OddBasis | None = None) -> np.ndarray:
        """:meth:`evaluate` at each of ``thetas`` as rows of one array, the same numbers bit
        for bit: every step is :meth:`evaluate`'s own, in its order, the elementwise ones
        done on all rows at once (a scalar per row times an array is the same product either
        way) and the rest (simulations, products with a matrix, the shape term's solve) row
        by row as there.  A finite-difference Jacobian evaluates one point per parameter, and
        their Python overhead was most of a diagnosis' time."""
        m = len(thetas)
        d = self.data
        core = (d.x[idx] - self.origin0) * self.scale
        at = _points_key(idx, core)
        rows = [self._unpack(th, names) for th in self._physical(thetas, names)]
        self.nfev += m
        sims, curv, y0 = [], np.zeros(m), {}
        for r, (gain, _origin, _shape, eff) in enumerate(rows):
            curvature = eff.get("secondary_imbalance", {}).pop(SUM_CURVATURE, 0.0)
            inner = {k: v for k, v in eff.items() if EFFECTS[k].stage != "output"}
            sims.append(self._simulate(gain, inner, idx, core, at))
            if curvature:
                curv[r] = curvature
                without = {k: v for k, v in inner.items() if k != "secondary_imbalance"}
                y0[r] = self._simulate(gain, without, idx, core, at)
        y = np.array(sims)
        if y0:
            bent = np.array(sorted(y0))
            u = core / self._half_range()
            y[bent] = y[bent] + curv[bent, None] * u ** 2 * (y[bent] - np.array([y0[r] for r in bent]))
        gains = [row[0] for row in rows]
        moved = [r for r, row in enumerate(rows) if row[1] != self.origin0]
        if self.shape is not None:
            modes = self._modes_at(idx, core, at)
            if moved:
                step = np.array([gains[r] * (rows[r][1] - self.origin0) * self.scale for r in moved])
                y[moved] = y[moved] - step[:, None] * modes[0]
            if rows[0][2] is not None:
                y = y + np.array(gains)[:, None] * np.array([row[2] @ modes[1:] for row in rows])
        elif moved:
            step = np.array([gains[r] * (rows[r][1] - self.origin0) * self.scale for r in moved])
            y[moved] = y[moved] - step[:, None] * self._slope_at(idx, core)
        effs = [row[3] for row in rows]
        if "null_offset" in effs[0]:
            y = y + np.array([e["null_offset"]["offset_v"] for e in effs])[:, None]
        clip = "adc_clipping" in effs[0]
        hi = [e.get("adc_clipping", {}).get("rail_high_v", math.inf) for e in effs]
        lo = [e.get("adc_clipping", {}).get("rail_low_v", -math.inf) for e in effs]
        if basis is not None:
            for r, e in enumerate(effs):
                shift = e.get("zero_shift", {}).get("shift_mm", 0.0)
                B, pinv = self._basis_at(basis, idx, core, shift, at)
                c = coef
                yr = y[r]
                if c is None:
                    c = _shape_coef(basis.ncols, B, pinv, yr, target, lo[r], hi[r])
                y[r] = yr + B @ c
        if clip:
            y = np.clip(y, np.array(lo)[:, None], np.array(hi)[:, None])
        return y

    def _points(self, points, names, idx: np.ndarray, coef=None, target=None, basis=None) -> list:
        """:meth:`evaluate` at each of ``points``: together (:meth:`evaluate_many`), or one by
        one where that cannot be quiet (an exception, a floating-point warning), which then
        raises or warns as :meth:`evaluate` always did."""
        try:
            with np.errstate(over="raise", divide="raise", invalid="raise"):
                return list(self.evaluate_many(points, names, idx, coef=coef, target=target, basis=basis))
        except Exception:   # noqa: BLE001 -- one by one, as a map would
            return [self.evaluate(p, names, idx, coef=coef, target=target, basis=basis) for p in points]

    def _evaluator(self, names, idx: np.ndarray, target: np.ndarray, basis):
        """A ``workers`` map for least_squares: its finite-difference points through
        :meth:`_points`, each returned as ``fun`` returns one (the model minus ``target``)."""
        def columns(_fun, points):
            return [y - target for y in self._points(list(points), names, idx, target=target, basis=basis)]
        return columns

    def _simulate(self, gain: float, inner: dict, idx: np.ndarray, core: np.ndarray,
                  at: tuple | None = None) -> np.ndarray:
        """The simulated output with the simulator's own effects ``inner`` at the points
        ``idx``, cached on what it depends on: a finite-difference step of a parameter the
        simulator does not see (origin, shape, offset, the sum's bend, rails; the gain
        without a quadrature null) then costs no simulation.  Without a quadrature null the
        demodulator is ``gain x`` the same rotated e.m.f. (its quadrature term is 0), so the
        output at unit gain times ``gain`` is the same numbers as a simulation at ``gain``.
        ``at``: the points' key (:func:`_points_key`), when the caller has it."""
        linear = "quadrature_null" not in inner
        if gain not in self._gains_ok:   # checked as a simulation at this gain would be
            self.sensor.replace(demodulator_gain_ratio=gain)
            if len(self._gains_ok) >= 256:
                self._gains_ok.clear()
            self._gains_ok.add(gain)
        if at is None:
            at = _points_key(idx, core)
        key = (None if linear else gain, tuple((e, tuple(p.items())) for e, p in inner.items()), at)
        y = self._sim_cache.get(key)
        if y is None:
            d = self.data
            if len(self._sim_cache) >= SIM_CACHE:
                self._sim_cache.clear()
            s = self.sensor.replace(demodulator_gain_ratio=1.0 if linear else gain, effects=inner)
            y = simulate_at_fixed_geometry(
                s, core, direction=None if d.direction is None else d.direction[idx],
                temperature_c=None if d.temperature_c is None else d.temperature_c[idx],
                time_s=None if d.time_s is None else d.time_s[idx])
            self._sim_cache[key] = y
        return gain * y if linear else y

    def _basis_at(self, basis: OddBasis, idx: np.ndarray, core: np.ndarray, shift: float, at: tuple):
        """The shape basis at ``core`` and a function giving its pseudo-inverse, both cached:
        inside a fit the basis moves only with a zero shift, so the finite-difference
        steps of every other parameter reuse one factorisation (a least-squares solve per
        evaluation was most of the diagnosis' time on 2,000 points)."""
        key = ("disc", basis.k, at, shift)
        hit = self._shape_cache.get(key)
        if hit is None:
            # bounded in bytes too: an entry (basis and pseudo-inverse) is 2 n K floats, and
            # 400 of them on 10,000 points with 32 columns held 2 GB
            held = self._shape_cache.setdefault(("bytes",), [0.0])
            if len(self._shape_cache) > 400 or held[0] > CACHE_BYTES:
                self._shape_cache.clear()
                held = self._shape_cache.setdefault(("bytes",), [0.0])
            B = basis.evaluate(core, shift)
            held[0] += 2 * B.nbytes
            store: list = []

            def pinv():
                if not store:
                    store.append(np.linalg.pinv(B, rcond=RCOND))
                return store[0]

            hit = (B, pinv)
            self._shape_cache[key] = hit
        return hit

    def _modes_at(self, idx: np.ndarray, core: np.ndarray, at: tuple) -> np.ndarray:
        """[slope, shape_1..K] at the points idx (per unit gain), cached per index set and
        positions."""
        key = ("modes", at)
        hit = self._shape_cache.get(key)
        if hit is None:
            slope = np.interp(core, self.shape.grid_mm, self.shape.slope)
            hit = np.vstack([slope[None, :], self.shape.evaluate(core)])
            self._shape_cache[key] = hit
        return hit

    def _slope_at(self, idx: np.ndarray, core: np.ndarray) -> np.ndarray:
        key = ("slope", idx.size, hash(idx.tobytes()))
        hit = self._shape_cache.get(key)
        if hit is None:
            h = 0.01
            s1 = self.sensor.replace(demodulator_gain_ratio=1.0)
            hit = (simulate_at_fixed_geometry(s1, core + h) - simulate_at_fixed_geometry(s1, core - h)) / (2 * h)
            self._shape_cache[key] = hit
        return hit

    def data_y(self, idx: np.ndarray) -> np.ndarray:
        return self.data.y[idx]

    # -- starting values ---------------------------------------------------------------
    def _start(self, effects, names, idx, start: Fit | None, basis) -> np.ndarray:
        theta = np.empty(len(names))
        known = dict(zip(start.names, start.theta)) if start is not None else {}
        base = {"baseline.gain_ratio": self.gain0, "baseline.origin_mm": self.origin0}
        resid = None
        for i, n in enumerate(names):
            if n in known:
                theta[i] = known[n]
            elif n in base:
                theta[i] = base[n]
            elif n.startswith("baseline.shape_"):
                theta[i] = 0.0
            else:
                theta[i] = np.nan
        missing = [i for i in range(len(names)) if np.isnan(theta[i])]
        if missing:
            if start is not None:
                resid = self.data_y(idx) - self.evaluate(start.theta, start.names, idx,
                                                          target=self.data_y(idx), basis=basis)
                base_theta, base_names = start.theta, start.names
            else:
                base_names = [n for n in names if n.startswith("baseline.")]
                base_theta = theta[:len(base_names)]
                resid = self.data_y(idx) - self.evaluate(base_theta, base_names, idx,
                                                          target=self.data_y(idx), basis=basis)
            want = {names[i].split(".", 1)[0] for i in missing}
            guesses = self._guess(resid, idx, dict(zip(base_names, base_theta)), want)
            if "secondary_imbalance" in want:
                guesses.update(self._guess_imbalance(resid, idx, base_theta, base_names,
                                                     basis))
            for i in missing:
                theta[i] = guesses.get(names[i], 0.0)
        return theta

    def _guess(self, resid: np.ndarray, idx: np.ndarray, base: dict,
               want: set[str]) -> dict[str, float]:
        """Effect-specific starting values from the residual of the model without them."""
        d = self.data
        gain = base.get("baseline.gain_ratio", self.gain0)
        origin = base.get("baseline.origin_mm", self.origin0)
        x = (d.x[idx] - origin) * self.scale
        h = 0.01
        s0 = self.sensor.replace(demodulator_gain_ratio=gain)
        slope = (simulate_at_fixed_geometry(s0, x + h) - simulate_at_fixed_geometry(s0, x - h)) / (2 * h)
        g = {}
        g["null_offset.offset_v"] = float(np.mean(resid))
        g["quadrature_null.quadrature_v"] = max(float(np.min(np.abs(d.y[idx]))), 1e-4 * self.v_range)
        denom = float(np.dot(slope, slope)) or 1.0
        g["zero_shift.shift_mm"] = float(-np.dot(resid, slope) / denom)
        if d.direction is not None:
            dd = d.direction[idx]
            g["backlash.deadband_mm"] = max(float(-2 * np.dot(resid * dd, slope) / denom), 1e-4)
        g["adc_clipping.rail_high_v"] = float(np.max(d.y[idx]))
        g["adc_clipping.rail_low_v"] = float(np.min(d.y[idx]))
        g["secondary_imbalance.imbalance_fraction"] = 0.0
        g["thermal_drift.coefficient_per_c"] = 0.0
        if "leadscrew_periodic" in want:
            g.update(self._guess_leadscrew(x, resid, slope))
        return g

    def _guess_imbalance(self, resid, idx, base_theta, base_names,
                         basis) -> dict[str, float]:
        """The imbalance and the sum's bend by linear regression of the residual on the
        imbalance's contribution D and on u^2 D (the model is e D (1 + c u^2)), less what
        the shape term and the null position can take.  Starting from zero, the fit can
        slide to the edge of the bend's range (clipped: no gradient) and stay there."""
        trial = 0.01
        names = list(base_names) + ["secondary_imbalance.imbalance_fraction"]
        base = np.asarray(base_theta, float)
        on = self.evaluate(np.r_[base, trial], names, idx)
        off = self.evaluate(np.r_[base, 0.0], names, idx)
        h = 1e-3
        k_o = names.index("baseline.origin_mm") if "baseline.origin_mm" in names else None
        cols = [off / max(float(np.max(np.abs(off))), 1e-12)]
        if k_o is not None:
            moved = base.copy()
            moved[k_o] += h
            cols.append(self.evaluate(np.r_[moved, 0.0], names, idx) - off)
        core = (self.data.x[idx] - self.origin0) * self.scale
        if basis is not None:
            cols.append(basis.evaluate(core))
        A = np.column_stack(cols)
        unit = on - off
        u2 = (core / self._half_range()) ** 2
        X = np.column_stack([unit, u2 * unit]) / trial
        X = X - A @ np.linalg.lstsq(A, X, rcond=RCOND)[0]
        r = resid - A @ np.linalg.lstsq(A, resid, rcond=RCOND)[0]
        if not np.all(np.isfinite(X)) or not float(np.sum(X * X)) > 0:
            return {}
        a, b = np.linalg.lstsq(X, r, rcond=RCOND)[0]
        e = float(np.clip(a, -0.5, 0.5))
        c = float(np.clip(b / a, *self._CLIPPED[f"secondary_imbalance.{SUM_CURVATURE}"])) \
            if abs(a) > 0 else 0.0
        return {"secondary_imbalance.imbalance_fraction": e,
                f"secondary_imbalance.{SUM_CURVATURE}": c}

    def _guess_leadscrew(self, x, resid, slope) -> dict[str, float]:
        """Period, amplitude and phase from a periodogram of the position error resid/slope."""
        w = np.abs(slope) > 0.3 * np.max(np.abs(slope))
        if w.sum() < 12:
            return {}
        xe = x[w]
        e = -resid[w] / slope[w]  # core error estimate: resid = slope * (core - x)
        lo = max(2.05 * self._typical_step(), 1e-3)
        hi = max(float(np.ptp(xe)) / 3, lo * 1.01)
        # uniform frequency grid, 3x oversampled against the resolution 1/span
        f_hi, f_lo = 1.0 / lo, 1.0 / hi
        n_f = int(np.clip(3 * (f_hi - f_lo) * float(np.ptp(xe)), 50, 3000))
        periods = 1.0 / np.linspace(f_lo, f_hi, n_f)
        e = e - np.mean(e)
        ph = 2 * np.pi * xe[None, :] / periods[:, None]
        c, sn = np.cos(ph), np.sin(ph)
        cc, ss = np.sum(c * c, 1), np.sum(sn * sn, 1)
        a_c = (c @ e) / cc
        a_s = (sn @ e) / ss
        k = int(np.argmax(a_c ** 2 + a_s ** 2))
        best = (0.0, float(periods[k]), float(a_s[k]), float(a_c[k]))
        _, p, a_s, a_c = best
        # a_s sin + a_c cos = amp sin(2 pi x/p + phase)
        return {"leadscrew_periodic.amplitude_mm": float(math.hypot(a_s, a_c)),
                "leadscrew_periodic.period_mm": float(p),
                "leadscrew_periodic.phase_rad": float(math.atan2(a_c, a_s))}

    # -- fitting -----------------------------------------------------------------------
    def fit(self, effects, idx: np.ndarray, start: Fit | None = None) -> Fit:
        """Levenberg-Marquardt (MINPACK: no threaded BLAS, fast on a busy machine); bounds
        are enforced by :meth:`_physical` (|.| for one-sided, clipping for two-sided).

        Clipping is tried with the upper rail, the lower rail and both, each with the shape
        term as chosen and with fewer terms (a rail and a smooth shape both flatten the
        ends: BIC decides which needs fewer parameters), unless ``start`` already says."""
        effects = tuple(effects)
        k0 = self.terms
        if start is not None and "k_shape" in start.extra:
            k0 = start.extra["k_shape"]
        if "adc_clipping" not in effects:
            if ("leadscrew_periodic" in effects and k0 > 0 and not (
                    start is not None and "leadscrew_periodic.period_mm" in start.names)):
                # a ripple and the shape term's warp both move the position locally: the
                # shape may have taken a lead screw before it was tried (a 20 um, 2 mm
                # ripple on a 22 mm travel raised K to 6); BIC decides, as for a rail
                fits = [self._fit(effects, idx, start, "both", k)
                        for k in [k0] + [k for k in self.fewer_terms if k < k0]]
                ok = [f for f in fits if f.ok] or fits
                return min(ok, key=lambda f: f.bic)
            return self._fit(effects, idx, start, "both", k0)
        if start is not None and any(n.startswith("adc_clipping.") for n in start.names):
            return self._fit(effects, idx, start, self._sides(start), k0)
        ks = [k0] + [k for k in self.fewer_terms if k < k0]
        fits = [self._fit(effects, idx, start, side, k)
                for side in ("high", "low", "both") for k in ks]
        ok = [f for f in fits if f.ok] or fits
        return min(ok, key=lambda f: f.bic)

    fewer_terms = (0, 2)

    def with_shape_range(self, half_range_mm: float, rectified: bool) -> "PhysicsFamily":
        """This family with a smooth shape term over the recorded half-range of core
        positions (no terms chosen yet: see :meth:`with_terms`)."""
        grid = np.linspace(-1.5 * half_range_mm, 1.5 * half_range_mm, 601)
        s1 = self.sensor.replace(demodulator_gain_ratio=1.0)
        h = 1e-3 * max(half_range_mm, 1e-6)
        slope = (simulate_at_fixed_geometry(s1, grid + h) - simulate_at_fixed_geometry(s1, grid - h)) / (2 * h)
        top = float(np.max(np.abs(slope)))
        warp = (grid, slope / top) if top > 0 and np.all(np.isfinite(slope)) else None
        rows = [simulate_at_fixed_geometry(s1, grid)]
        if self.shape is not None:
            rows += list(self.shape.evaluate(grid))
        known = (grid, np.stack(rows)) if np.all(np.isfinite(rows)) else None
        return self._copy(shape_ref=OddBasis(half_range_mm, 1, rectified, warp, known), terms=0,
                          equivalent_terms=(), fresh_cache=True)

    def with_terms(self, k: int, equivalent_terms: tuple[int, ...] = ()) -> "PhysicsFamily":
        """This family with ``k`` shape terms for fits that start from nothing."""
        return self._copy(terms=k, equivalent_terms=equivalent_terms)

    def with_data(self, data: Data) -> "PhysicsFamily":
        """This family (its calibration, ranges and candidates) evaluated on ``data``."""
        return self._copy(data=data, fresh_cache=True)

    def _copy(self, fresh_cache: bool = False, **changes) -> "PhysicsFamily":
        new = copy.copy(self)
        for k, v in changes.items():
            setattr(new, k, v)
        if new.shape_ref is None:
            new.terms = 0
        new._plans = {}
        new._bases = {}
        if fresh_cache:
            new._shape_cache = {}
            new._sim_cache = {}
        return new

    def basis(self, k: int):
        """The shape term with ``k`` terms (None for none)."""
        ref = self.shape_ref
        if k == 0 or ref is None:
            return None
        # built once per family and number of terms (a copy with another shape range builds
        # its own, see _copy): every prediction and fit asks, and each build is a least squares
        hit = self._bases.get(k)
        if hit is None:
            hit = self._bases[k] = OddBasis(ref.half, k, ref.rectified, ref.warp, ref.known)
        return hit

    @staticmethod
    def _sides(fit: Fit | None) -> str:
        if fit is None:
            return "both"
        have = [s for n, s in (("adc_clipping.rail_high_v", "high"),
                               ("adc_clipping.rail_low_v", "low")) if n in fit.names]
        return have[0] if len(have) == 1 else "both"

    def choose_terms(self, effects, idx: np.ndarray, start: Fit | None = None,
                     ) -> tuple[int, dict, Fit]:
        """Number of smooth shape terms for the model with ``effects``, by 5-fold
        cross-validation; returns (terms, out-of-fold RMS by terms, the fit with them).

        Chosen with the effects in place: a large even effect (a zero shift, say) hides
        the odd misfit of the shape until it is fitted, and the misfit then pushes a
        second, spurious effect in.  Each number of terms is fitted (nonlinear) on all
        points; the folds then refit the model linearised about that fit (every parameter
        and shape coefficient re-adjusts through its Jacobian column), so the shape term's
        interaction with the null position is kept and a fold costs one small least
        squares.  The smallest number within 1 % of the best out-of-fold error is taken."""
        effects = tuple(effects)
        sides = self._sides(start)
        if self.shape_ref is None:
            return 0, {}, self._fit(effects, idx, start, sides, 0), ()
        folds = make_folds(np.arange(idx.size))
        table, fits = {}, {}
        stale = 0
        for k in SHAPE_TERMS:
            basis = self.basis(k)
            if idx.size - len(self.specs(effects, sides)) - (basis.ncols if basis else 0) < 10:
                continue
            if stale >= STOP_AFTER:
                break
            # each number of terms starts where the previous one ended (more terms can
            # always do what fewer did; a cold start may fall into another minimum)
            f = self._fit(effects, idx, fits[max(fits)] if fits else start, sides, k)
            if (start is not None and start.ok and self.terms_of(start) == k
                    and tuple(start.effects) == effects and start.rss < f.rss):
                f = start      # the chain found a worse minimum than the fit it came from
            if not f.ok:
                continue
            e = self.fold_residuals(f, idx, folds)
            table[k] = math.sqrt(sum(float(e[test] @ e[test]) for test in folds) / idx.size)
            stale = stale + 1 if len(table) > 1 and table[k] > 0.99 * min(
                v for j, v in table.items() if j != k) else 0
            fits[k] = f
        if not table:
            return 0, {}, self._fit(effects, idx, start, sides, 0), ()
        best = min(table.values())
        tied = sorted(k for k, v in table.items() if v <= best * 1.01)
        return tied[0], table, fits[tied[0]], tuple(tied)

    def fold_residuals(self, fit: Fit, idx: np.ndarray, folds: list[np.ndarray]) -> np.ndarray:
        """Out-of-fold residuals of ``fit``'s model (``folds``: positions in ``idx``): each
        fold predicted by the model refitted on the other points, linearised about ``fit``
        (every parameter and shape coefficient re-adjusts through its Jacobian column), so
        a fold costs one small least squares instead of a nonlinear refit.  Kept on the fit."""
        key = ("fold_residuals", idx.tobytes(), tuple(t.tobytes() for t in folds))
        hit = fit.extra.get(key[0])
        if hit is not None and hit[0] == key:
            return hit[1]
        X = self._jacobian(fit, idx)
        out = np.empty(idx.size)
        for test in folds:
            train = np.setdiff1d(np.arange(idx.size), test, assume_unique=True)
            c = np.linalg.lstsq(X[train], fit.resid[train], rcond=1e-10)[0]
            out[test] = fit.resid[test] - X[test] @ c
        fit.extra[key[0]] = (key, out)
        return out

    def implausible(self, candidate: str, fit: Fit, idx: np.ndarray) -> str:
        """Why ``fit`` does not show the physics ``candidate`` names ("" when it may).

        A fitted rail must be flat: the readings where the unclipped model passes it sit on
        it, whatever the model would have read there.  On the ends of a curve the model
        overshoots (a temperature recording's bin means), a "rail" cutting the model off
        lowers BIC although the readings it clips still rise with the curve: not a
        converter's rail.  Judged by the slope of those readings against the unclipped
        model (0 on a rail, 1 on the curve), which the clipped readings must span well enough
        to tell.  A lead screw's fitted period must lie in its range (:meth:`_period_outside`).
        """
        if candidate == "leadscrew_periodic":
            return self._period_outside(fit)
        if candidate != "adc_clipping":
            return ""
        theta = fit.theta.copy()
        sides = [(i, n.endswith("_high_v")) for i, n in enumerate(fit.names)
                 if n.startswith("adc_clipping.")]
        for i, high in sides:
            theta[i] = math.inf if high else -math.inf
        u = self.evaluate_like(fit, theta, idx)
        y = self.data_y(idx)
        for i, high in sides:
            rail = float(fit.theta[i])
            on = u > rail if high else u < rail
            where = f"{rail:+.4g} V"
            du = u[on] - np.mean(u[on]) if on.any() else np.zeros(0)
            spread = float(du @ du)
            # below one noise of spread the slope is not known to within 1: nothing flat seen
            if on.sum() < 2 or spread <= fit.rms ** 2:
                return (f"a rail at {where} would clip {int(on.sum())} reading(s) over which "
                        "the curve hardly moves: no flat run to tell from the curve's end")
            slope = float(du @ (y[on] - np.mean(y[on]))) / spread
            se = fit.rms / math.sqrt(spread)
            if slope > RAIL_SLOPE and slope > RAIL_T * se:
                return (f"the readings beyond {where} still follow the curve ({slope:.0%} of its "
                        "rise): not a flat rail")
        return ""

    def _period_outside(self, fit: Fit) -> str:
        """Why a fitted lead-screw period is not one ("" when it is): the fit bounds it only
        by its sign, and a period that ran beyond a few steps .. 1/8 of the stroke (see
        :meth:`specs`) draws a smooth warp of the axis, the shape term's job, or aliases the
        scatter of the readings."""
        spec = self.specs_by_name(["leadscrew_periodic"])["leadscrew_periodic.period_mm"]
        period = fit.value("leadscrew_periodic.period_mm")
        if spec.lower <= period <= spec.upper:
            return ""
        k = 1.0 / self.scale      # recorded units
        return (f"the fitted period {period * k:.3g} mm is outside {spec.lower * k:.3g}.."
                f"{spec.upper * k:.3g} mm (three steps of one direction to 1/8 of the stroke): "
                "not a lead screw's ripple")

    def shape_may_hide(self, candidate: str) -> bool:
        """Whether the shape term chosen without ``candidate`` may already draw it, so that
        the candidate is only seen with the shape's complexity chosen again.  On a rectified
        output the odd terms fold into a V that, with enough of them, fills in the tip as a
        quadrature null does (a 40 mV null raised the terms from 0 to 6, which then left it
        +5 BIC; with the null in place cross-validation takes 0 terms, 63 BIC better)."""
        return (candidate == "quadrature_null" and self.shape_ref is not None
                and self.shape_ref.rectified)

    def least_evidence(self, effects, candidate: str, idx: np.ndarray, without: Fit,
                       with_: Fit) -> float:
        """The largest ΔBIC of adding ``candidate`` over the shape terms that cross-validate
        as well as the chosen ones.  A shape of equal quality that makes the candidate
        unnecessary means the shape can make it: with a large zero shift, two broad terms
        let the shift trade against an offset (0.6 mm became 0.33 mm + -117 mV), while three
        to six terms, as good by cross-validation, need no offset."""
        worst = with_.bic - without.bic
        k_now = self.terms_of(without)
        # a candidate the shape may hide, with its own complexity: the question is whether
        # an equally good shape without it fits as well as the candidate with its shape
        own = self.shape_may_hide(candidate) and self.terms_of(with_) != k_now
        for k in without.extra.get("equivalent_terms", self.equivalent_terms):
            if k == k_now:
                continue
            f0 = self._fit(tuple(effects), idx, without, self._sides(without), k)
            f1 = with_ if own else self._fit(tuple(effects) + (candidate,), idx, with_,
                                             self._sides(with_), k)
            if f0.ok and f1.ok:
                worst = max(worst, f1.bic - f0.bic)
        return worst

    def _jacobian(self, fit: Fit, idx: np.ndarray) -> np.ndarray:
        """d(model)/d(parameters, shape coefficients) at ``fit`` (finite differences)."""
        k = self.terms_of(fit)
        coef = fit.extra.get("coef")
        basis = self.basis(k)
        if coef is None:
            coef = np.zeros(0 if basis is None else basis.ncols)
        coef = np.asarray(coef, float)
        y0 = self.evaluate(fit.theta, fit.names, idx, coef=coef, basis=basis)
        steps, points = [], []
        for j, th in enumerate(fit.theta):
            h = 1e-6 * max(abs(th), 1e-3)
            t1 = fit.theta.copy()
            t1[j] += h
            steps.append(h)
            points.append(t1)
        ys = self._points(points, fit.names, idx, coef=coef, basis=basis)
        cols = [(y1 - y0) / h for y1, h in zip(ys, steps)]
        for j in range(coef.size):
            c1 = coef.copy()
            c1[j] += 1.0
            cols.append(self.evaluate(fit.theta, fit.names, idx, coef=c1, basis=basis) - y0)
        return np.stack(cols, 1)

    def refine(self, effects, fit: Fit, idx: np.ndarray) -> Fit:
        """``fit`` with the shape term's complexity chosen again now that ``effects`` are
        in the model (see :meth:`choose_terms`); the fit carries its number of terms, the
        cross-validation table and the equally good numbers of terms."""
        if fit.extra.get("chosen_for") == tuple(effects):
            return fit      # re-chosen for these very effects when it was a candidate
        return self.rechoose(effects, idx, fit)

    def rechoose(self, effects, idx: np.ndarray, fit: Fit) -> Fit:
        """``fit`` with the number of shape terms chosen for ``effects``."""
        _, table, f, tied = self.choose_terms(effects, idx, fit)
        f.extra["cv_table"] = table
        f.extra["chosen_for"] = tuple(effects)
        if tied:
            f.extra["equivalent_terms"] = tied
        return f

    def _fit(self, effects, idx, start, clip_sides, k_shape) -> Fit:
        # the same fit is asked for again (a re-choice of the shape term walks the numbers of
        # terms from the fit it was given): the cache goes with the family's data and shape
        # range, the key holds the rest a fit depends on (a copy out: callers annotate extra)
        key = ("fit", tuple(effects), idx.tobytes(), clip_sides, k_shape, self.terms, self.origin0,
               self.gain0, self.scale, None if start is None else (tuple(start.names), start.theta.tobytes()))
        f = self._shape_cache.get(key)
        if f is None:
            f = self._fit_now(effects, idx, start, clip_sides, self.basis(k_shape))
            f.extra["k_shape"] = k_shape
            self._shape_cache[key] = f
        return replace(f, extra=dict(f.extra))

    def _fit_now(self, effects, idx, start, clip_sides, basis) -> Fit:
        specs = self.specs(effects, clip_sides)
        names = [p.name for p in specs]
        lo = np.array([p.lower for p in specs])
        hi = np.array([p.upper for p in specs])
        theta0 = np.clip(self._start(effects, names, idx, start, basis), lo, hi)
        y = self.data_y(idx)
        k_extra = basis.ncols if basis is not None else 0

        def fun(th):
            return self.evaluate(th, names, idx, target=y, basis=basis) - y

        starts = [theta0]
        imb = "secondary_imbalance.imbalance_fraction"
        if imb in names and (start is None or imb not in start.names):
            # the imbalance's fit has a second minimum at zero imbalance with the sum's bend
            # at its limit (no gradient there): start on both sides of zero as well
            ie, ic = names.index(imb), names.index(f"secondary_imbalance.{SUM_CURVATURE}")
            for e in (0.01, -0.01):
                t = theta0.copy()
                t[ie], t[ic] = e, 0.0
                starts.append(t)
        res = None
        tol = fit_tolerance(idx.size)
        for t0 in starts:
            try:
                r = least_squares(fun, t0, method="lm", x_scale="jac",
                                  max_nfev=40 * (len(names) + 1), xtol=tol, ftol=tol,
                                  workers=self._evaluator(names, idx, y, basis))
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                continue
            if res is None or r.cost < res.cost:
                res = r
        if res is None:
            return Fit(effects, names, theta0, np.full(len(names), np.nan), -fun(theta0), idx,
                       ok=False, k_extra=k_extra)
        theta = self._canonical(self._physical(res.x, names), names)
        pred, coef = self.evaluate(theta, names, idx, target=y, want_coef=True, basis=basis)
        resid = y - pred
        stderr = _stderr(res.jac, resid, len(names) + k_extra)[:len(names)]
        return Fit(effects, names, theta, stderr, resid, idx,
                   ok=bool(np.all(np.isfinite(resid))), extra={"coef": coef}, k_extra=k_extra)

    def predict(self, fit: Fit, idx: np.ndarray) -> np.ndarray:
        return self.evaluate(fit.theta, fit.names, idx, coef=fit.extra.get("coef"),
                             basis=self.basis(self.terms_of(fit)))

    def terms_of(self, fit: Fit) -> int:
        """Number of shape terms of ``fit``."""
        return fit.extra.get("k_shape", self.terms)

    def evaluate_like(self, fit: Fit, theta: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """``theta`` in ``fit``'s parameterisation, with its shape term."""
        return self.evaluate(theta, fit.names, idx, coef=fit.extra.get("coef"),
                             basis=self.basis(self.terms_of(fit)))

    def shape_term(self, fit: Fit, idx: np.ndarray) -> np.ndarray:
        """The smooth shape term's contribution (V) at ``idx`` (zeros without one)."""
        basis = self.basis(self.terms_of(fit))
        if basis is None or fit.extra.get("coef") is None:
            return np.zeros(idx.size)
        core = (self.data.x[idx] - self.origin0) * self.scale
        return basis.evaluate(core) @ fit.extra["coef"]

    def specs_by_name(self, effects) -> dict[str, ParamSpec]:
        return {p.name: p for p in self.specs(effects)}

    def units(self) -> dict[str, str]:
        return {p.name: p.unit for p in self.specs(CANDIDATES)}


def _stderr(jac, resid: np.ndarray, k: int) -> np.ndarray:
    n = resid.size
    if n <= k:
        return np.full(k, np.nan)
    jac = np.asarray(jac, dtype=float)
    s2 = float(np.dot(resid, resid)) / (n - k)
    try:
        cov = np.linalg.pinv(jac.T @ jac) * s2
    except np.linalg.LinAlgError:
        return np.full(k, np.nan)
    return np.sqrt(np.clip(np.diag(cov), 0.0, None))
