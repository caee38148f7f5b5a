"""Simulated 2.4 m injector-driven transonic wind tunnel (paper A, SPEC.md "Paper A").

Three subsystems in a block-oriented network, sampled every ``dt = 50 ms``::

    u1 ──► S1 exhaust valve (A1)                  ──► v1 ──┐
    u2 ──► S2 choke finger: backlash (A3) ─► x ─► (A5) ──► v2 ──┴──► S3 flow field ──► y1, y2

S1 and S2 are exactly the difference equations the paper identified (Table 1, with the
sign of the S2 denominator corrected as SPEC.md explains), acting on the *absolute*
signals, so that an ARX or backlash model fitted to the recorded ``u``, ``v`` without an
intercept recovers those parameters:

.. math::

    v_1(t) = 0.39\\, u_1(t-1) + 0.62\\, v_1(t-1)                                   \\quad (A1)

    x(t) = \\mathrm{backlash}(u_2(t); m_L = m_R = 0.9,\\ c_L = 0.8,\\ c_R = 0.85)  \\quad (A3)

    v_2(t) = x(t-1) + 1.0\\, v_2(t-1) - 0.17\\, v_2(t-2)                           \\quad (A5)

The flow field S3 is a linear, slowly time-varying model of deviations from the
operating point :math:`(v_{1,op}, v_{2,op}) \\mapsto (P_{0,op}, Ma_{op})`, built from four
first-order lags (valve and throat mass-flow lags feeding the circuit pressure and the
test-section Mach number) and discretised exactly (zero-order hold):

.. math::

    \\tau_{q1}\\dot q_1 = -q_1 + g_1(t)\\,\\delta v_1, \\quad
    \\tau_{q2}\\dot q_2 = -q_2 + g_2(t)\\,\\delta v_2,

    \\tau_p \\dot p = -p + k_{p1} q_1 + k_{p2} q_2, \\quad
    \\tau_M \\dot m = -m + k_{M1} q_1 + k_{M2} q_2,

    y_1 = P_{0,op} + p + e_1, \\qquad y_2 = Ma_{op} + m + e_2,

where :math:`g_j(t) = 1 + d \\sin(2\\pi t / T_d + \\varphi_j)` are slow gain drifts with
random phases and :math:`e_1, e_2` measurement noise of the two pressure transducers.
With the gains frozen it is *exactly* a two-input two-output ARX with two own- and
cross-output lags, two coefficients per input and delay one (paper A's S3 orders);
:func:`flow_field_arx` returns those coefficients. See ``docs/plants/windtunnel.md`` for
every number and where it comes from.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.linalg import expm
from scipy.signal import lfilter, lfiltic

from blockid.blocks.backlash import Backlash
from blockid.errors import DataError, ParameterError

__all__ = [
    "CONDITIONS",
    "WindTunnelParameters",
    "simulate_windtunnel",
    "windtunnel_experiment",
    "flow_field_arx",
    "operating_point_commands",
]

#: Operating conditions studied in paper A (stagnation pressure / Mach number).
CONDITIONS: tuple[str, ...] = ("110kPa", "130kPa")
_KINDS: tuple[str, ...] = ("estimation", "validation")
_GAMMA = 1.4  # ratio of specific heats of air


@dataclass(frozen=True)
class WindTunnelParameters:
    """Every number of the simulated wind tunnel (defaults: the 110 kPa / Ma 0.578 point).

    Use :meth:`for_condition` for either of paper A's operating conditions and
    :func:`dataclasses.replace` to change single values.

    Attributes
    ----------
    condition : str
        Name of the operating condition (``"110kPa"`` or ``"130kPa"``).
    dt : float
        Sampling period [s]. Paper A: 50 ms.
    valve_a, valve_b : float
        S1 (A1) coefficients ``a_1`` [-] and ``b_1`` [mm per command unit]. Paper A,
        Table 1: -0.62, 0.39.
    finger_backlash : tuple of 4 float
        S2 backlash (A3) ``(m_left [-], c_left [mm], m_right [-], c_right [mm])``.
        Paper A, Table 1: (0.9, 0.8, 0.9, 0.85).
    finger_a : tuple of 2 float
        S2 linear block (A5) ``(a_1, a_2)`` [-]. Paper A prints (1.0, -0.17), which is
        unstable under (A5); SPEC.md's sign correction (-1.0, 0.17) is used.
    finger_b : float
        S2 linear block ``b_1`` [-], fixed to 1 by the key-term separation (A6).
    p0_op : float
        Stagnation pressure at the operating point [kPa]. Paper A.
    mach_op : float
        Test-section Mach number at the operating point [-]. Paper A.
    v1_op, v2_op : float
        Exhaust-valve and choke-finger positions at the operating point [mm]. At
        110 kPa the centres of paper A's Figure 4 ranges; at 130 kPa our choice.
    tau_valve_flow, tau_throat_flow : float
        Lag of the exhaust mass flow behind the valve position and of the throat flow
        behind the finger position [s]. Our choice.
    tau_pressure : float
        Fill/empty time constant of the tunnel circuit (stagnation pressure) [s].
        Our choice.
    tau_mach : float
        Time constant of the test-section Mach number [s]. Our choice.
    gain_p0_v1, gain_p0_v2 : float
        Static sensitivity of the stagnation pressure to the valve and finger
        positions [kPa/mm]. Chosen to reproduce paper A's Figure 4 ranges at
        110 kPa; scaled with ``p0_op`` at 130 kPa.
    gain_mach_v1, gain_mach_v2 : float
        Static sensitivity of the Mach number to the valve and finger positions [1/mm].
        Chosen for Figure 4 at 110 kPa; scaled by the choked-second-throat area-Mach
        relation at 130 kPa (:func:`_throat_mach_sensitivity`).
    drift_amplitude : float
        Relative amplitude ``d`` of the slow gain drift [-]. Our choice (2.5 %).
    drift_period : float
        Period ``T_d`` of the gain drift [s]; longer than a 60 s record. Our choice.
    pressure_noise_rel : float
        Standard deviation of each pressure transducer (stagnation and plenum static)
        relative to its reading [-]. Our choice (0.015 % of reading). The Mach number is
        computed from both pressures, so its noise follows from the isentropic relation.
    position_noise : float
        Standard deviation of the position measurements ``v1``, ``v2`` [mm]. Our choice.
    v1_span, v2_span : float
        Half-range of the demanded positions in :func:`windtunnel_experiment` [mm].
    hold_min, hold_max : float
        Range of the hold times of each commanded level [s].
    dither : float
        Standard deviation of the dither added to the demanded positions [mm].
    """

    condition: str = "110kPa"
    dt: float = 0.05  # s
    # S1, exhaust valve (A1)
    valve_a: float = -0.62  # -
    valve_b: float = 0.39  # mm per command unit
    # S2, choke finger (A3) + (A5)
    finger_backlash: tuple[float, float, float, float] = (0.9, 0.8, 0.9, 0.85)  # -, mm, -, mm
    finger_a: tuple[float, float] = (-1.0, 0.17)  # -
    finger_b: float = 1.0  # -
    # operating point
    p0_op: float = 110.0  # kPa
    mach_op: float = 0.578  # -
    v1_op: float = 417.5  # mm
    v2_op: float = 355.0  # mm
    # S3, flow field
    tau_valve_flow: float = 0.30  # s
    tau_throat_flow: float = 0.15  # s
    tau_pressure: float = 1.5  # s
    tau_mach: float = 0.25  # s
    gain_p0_v1: float = -0.009  # kPa/mm
    gain_p0_v2: float = -0.0012  # kPa/mm
    gain_mach_v1: float = 2.0e-5  # 1/mm
    gain_mach_v2: float = 1.5e-4  # 1/mm
    drift_amplitude: float = 0.025  # -
    drift_period: float = 120.0  # s
    # measurement noise
    pressure_noise_rel: float = 1.5e-4  # -
    position_noise: float = 0.02  # mm
    # experiment design (windtunnel_experiment)
    v1_span: float = 7.5  # mm
    v2_span: float = 19.0  # mm
    hold_min: float = 1.0  # s
    hold_max: float = 4.0  # s
    dither: float = 0.1  # mm

    @classmethod
    def for_condition(cls, condition: str) -> WindTunnelParameters:
        """Parameters of one of paper A's operating conditions, ``"110kPa"`` or ``"130kPa"``.

        At 130 kPa / Ma 0.822 the pressure sensitivities scale with the stagnation
        pressure and the Mach sensitivities with the area-Mach relation of the choked
        second throat; actuators, time constants and noise model are unchanged.

        Examples
        --------
        >>> p = WindTunnelParameters.for_condition("130kPa")
        >>> p.p0_op, p.mach_op, round(p.gain_mach_v2 / 1.5e-4, 3)
        (130.0, 0.822, 2.632)
        """
        name = _condition_name(condition)
        base = cls()
        if name == "110kPa":
            return base
        p_ratio = 130.0 / base.p0_op
        m_ratio = _throat_mach_sensitivity(0.822) / _throat_mach_sensitivity(base.mach_op)
        return dataclasses.replace(
            base,
            condition=name,
            p0_op=130.0,
            mach_op=0.822,
            v1_op=400.0,
            v2_op=452.0,
            gain_p0_v1=base.gain_p0_v1 * p_ratio,
            gain_p0_v2=base.gain_p0_v2 * p_ratio,
            gain_mach_v1=base.gain_mach_v1 * m_ratio,
            gain_mach_v2=base.gain_mach_v2 * m_ratio,
        )

    @property
    def backlash(self) -> Backlash:
        """The S2 backlash block (A3)."""
        return Backlash(*self.finger_backlash)

    @property
    def valve_gain(self) -> float:
        """Static gain of S1, ``b_1 / (1 + a_1)`` [mm per command unit] (≈ 1.026)."""
        return self.valve_b / (1.0 + self.valve_a)

    @property
    def finger_gain(self) -> float:
        """Static gain of the S2 linear block, ``b_1 / (1 + a_1 + a_2)`` [-] (≈ 5.88)."""
        return self.finger_b / (1.0 + sum(self.finger_a))

    @property
    def noise_std(self) -> tuple[float, float]:
        """Standard deviations of the ``y1`` [kPa] and ``y2`` [-] measurement noise."""
        s = self.pressure_noise_rel
        return s * self.p0_op, math.sqrt(2.0) * s * _mach_per_log_pressure_ratio(self.mach_op)


def operating_point_commands(params: WindTunnelParameters) -> tuple[float, float]:
    """Constant commands ``(u1, u2)`` that hold a plant at rest at its operating point.

    With these commands from the start, :func:`simulate_windtunnel` returns
    ``v = (v1_op, v2_op)`` and, noise aside, ``y = (p0_op, mach_op)`` at every sample
    (the simulator starts at rest in the middle of the backlash dead band).

    Examples
    --------
    >>> p = WindTunnelParameters()
    >>> [round(c, 4) for c in operating_point_commands(p)]
    [406.7949, 67.0806]
    """
    return params.v1_op / params.valve_gain, _midband_input(params, params.v2_op)


def simulate_windtunnel(
    u1: np.ndarray,
    u2: np.ndarray,
    condition: str = "110kPa",
    params: WindTunnelParameters | None = None,
    seed: int | np.random.SeedSequence | None = None,
    noise: bool = True,
) -> pd.DataFrame:
    """Run the wind tunnel on given actuator commands.

    Parameters
    ----------
    u1, u2 : array of float, shape (n,)
        Commands to the exhaust valve and the choke finger (command units; their
        static gains to position are ``params.valve_gain`` and
        ``m_right * params.finger_gain``).
    condition : {"110kPa", "130kPa"}
        Operating condition; ignored when ``params`` is given.
    params : WindTunnelParameters, optional
        Full parameter set (default: ``WindTunnelParameters.for_condition(condition)``).
    seed : int or SeedSequence, optional
        Seeds the drift phases and the measurement noise.
    noise : bool
        Add measurement noise to ``v1, v2, y1, y2`` (the drift is part of the plant and
        stays on; set ``drift_amplitude=0`` to remove it).

    Returns
    -------
    pandas.DataFrame
        Columns ``t`` [s], ``u1``, ``u2``, ``v1`` [mm], ``v2`` [mm], ``y1`` (stagnation
        pressure) [kPa], ``y2`` (Mach number) [-] and ``x_true``, the backlash output
        (noise-free). ``attrs`` holds the condition, ``dt`` and the operating point.

    Notes
    -----
    The plant starts at rest under the first commands: ``v1(-1) = valve_gain u1(0)``, the
    backlash in the middle of its dead band at ``u2(0)``, ``v2`` and the flow field in
    the matching steady state. S1 and S2 then follow (A1), (A3), (A5) exactly.
    """
    p = params if params is not None else WindTunnelParameters.for_condition(condition)
    u1 = _command("u1", u1)
    u2 = _command("u2", u2)
    if u1.size != u2.size:
        raise DataError(f"u1 and u2 must have the same length, got {u1.size} and {u2.size}")
    n = u1.size
    rng = np.random.default_rng(seed)

    # S1: v1(t) = b1 u1(t-1) - a1 v1(t-1)                                       (A1)
    b_s1, a_s1 = [0.0, p.valve_b], [1.0, p.valve_a]
    v1_rest = p.valve_gain * u1[0]
    v1 = lfilter(b_s1, a_s1, u1, zi=lfiltic(b_s1, a_s1, [v1_rest], [u1[0]]))[0]

    # S2: backlash (A3), then v2(t) = b1 x(t-1) - a1 v2(t-1) - a2 v2(t-2)       (A5)
    backlash = p.backlash
    x_rest = _midband_output(p, u2[0])
    x = backlash.simulate(u2, x0=x_rest)
    b_s2, a_s2 = [0.0, p.finger_b], [1.0, *p.finger_a]
    v2_rest = p.finger_gain * x_rest
    v2 = lfilter(b_s2, a_s2, x, zi=lfiltic(b_s2, a_s2, [v2_rest, v2_rest], [x_rest]))[0]

    # S3: flow field on the drifting deviations, exact ZOH discretisation.
    phases = rng.uniform(0.0, 2.0 * np.pi, size=2)
    t_drift = np.arange(-1, n) * p.dt  # sample -1 is the rest state before the record
    gains = 1.0 + p.drift_amplitude * np.sin(
        2.0 * np.pi * t_drift[:, None] / p.drift_period + phases
    )
    dv = np.column_stack(
        [np.concatenate([[v1_rest], v1]) - p.v1_op, np.concatenate([[v2_rest], v2]) - p.v2_op]
    )
    deviation = _simulate_flow_field(p, gains * dv)
    y1 = p.p0_op + deviation[:, 0]
    y2 = p.mach_op + deviation[:, 1]

    v1_meas, v2_meas = v1, v2
    if noise:
        eps = rng.normal(0.0, p.pressure_noise_rel, size=(n, 2))  # stagnation, plenum static
        y1 = y1 + p.p0_op * eps[:, 0]
        y2 = y2 + (eps[:, 0] - eps[:, 1]) * _mach_per_log_pressure_ratio(p.mach_op)
        v1_meas = v1 + rng.normal(0.0, p.position_noise, n)
        v2_meas = v2 + rng.normal(0.0, p.position_noise, n)

    frame = pd.DataFrame(
        {
            "t": np.arange(n) * p.dt,
            "u1": u1,
            "u2": u2,
            "v1": v1_meas,
            "v2": v2_meas,
            "y1": y1,
            "y2": y2,
            "x_true": x,
        }
    )
    frame.attrs.update(
        plant="windtunnel",
        condition=p.condition,
        dt=p.dt,
        p0_op=p.p0_op,
        mach_op=p.mach_op,
        v1_op=p.v1_op,
        v2_op=p.v2_op,
        noise=bool(noise),
    )
    return frame


def windtunnel_experiment(
    condition: str = "110kPa",
    n_samples: int = 1200,
    seed: int | None = 0,
    kind: str = "estimation",
    params: WindTunnelParameters | None = None,
    noise: bool = True,
) -> pd.DataFrame:
    """One recorded experiment around an operating point, as in paper A's Figure 4.

    Each actuator gets a demanded position that holds random levels, uniform in
    ``op ± span``, for random times uniform in ``[hold_min, hold_max]`` (the record
    starts with one hold at the operating point), plus white dither. The demanded
    positions are turned into commands through the nominal static gains (for the
    choke finger: the middle of the backlash dead band), so the positions land near
    the demanded ones, off by up to half the dead band on the choke finger.

    Parameters
    ----------
    condition : {"110kPa", "130kPa"}
        Operating condition; ignored when ``params`` is given.
    n_samples : int
        Record length (default 1200 samples = 60 s, as in paper A).
    seed : int, optional
        Seed; with the same seed the estimation and validation records still differ,
        as do the two conditions. ``None`` draws fresh entropy.
    kind : {"estimation", "validation"}
        Which record of the pair.
    params : WindTunnelParameters, optional
        Full parameter set (default: ``WindTunnelParameters.for_condition(condition)``).
    noise : bool
        Passed to :func:`simulate_windtunnel`.

    Returns
    -------
    pandas.DataFrame
        As :func:`simulate_windtunnel`, with ``attrs["kind"]`` and ``attrs["seed"]``.
    """
    p = params if params is not None else WindTunnelParameters.for_condition(condition)
    if kind not in _KINDS:
        raise ParameterError(f"kind must be one of {', '.join(_KINDS)}; got {kind!r}")
    if isinstance(n_samples, bool) or not isinstance(n_samples, int | np.integer):
        raise ParameterError(f"n_samples must be a whole number, got {n_samples!r}")
    if n_samples < 3:
        raise ParameterError(f"n_samples must be at least 3, got {n_samples}")
    if seed is not None and (not isinstance(seed, int | np.integer) or seed < 0):
        raise ParameterError(f"seed must be a non-negative whole number or None, got {seed!r}")
    cond_index = CONDITIONS.index(p.condition) if p.condition in CONDITIONS else len(CONDITIONS)
    root = np.random.SeedSequence(seed, spawn_key=(_KINDS.index(kind), cond_index))
    command_seed, plant_seed = root.spawn(2)
    rng = np.random.default_rng(command_seed)

    hold = (max(1, round(p.hold_min / p.dt)), max(1, round(p.hold_max / p.dt)))
    r1 = _piecewise_levels(rng, n_samples, p.v1_op, p.v1_span, hold)
    r2 = _piecewise_levels(rng, n_samples, p.v2_op, p.v2_span, hold)
    r1 = r1 + rng.normal(0.0, p.dither, n_samples)
    r2 = r2 + rng.normal(0.0, p.dither, n_samples)
    u1 = r1 / p.valve_gain
    u2 = _midband_input(p, r2)
    frame = simulate_windtunnel(u1, u2, params=p, seed=plant_seed, noise=noise)
    frame.attrs.update(kind=kind, seed=seed)
    return frame


def flow_field_arx(params: WindTunnelParameters) -> dict:
    """The flow field S3 with frozen gains, written as an exact TITO ARX model.

    .. math::

        \\delta y(t) = -A_1 \\delta y(t-1) - A_2 \\delta y(t-2)
                      + B_0 \\delta v(t-1) + B_1 \\delta v(t-2)

    with :math:`\\delta y = y - (P_{0,op}, Ma_{op})`, :math:`\\delta v = v - (v_{1,op},
    v_{2,op})`. A four-state system whose two outputs have observability indices
    (2, 2) has exactly this form: from :math:`s(t) = O^{-1}[y(t); y(t+1) - C B_d v(t)]`,
    :math:`O = [C; C A_d]`.

    Returns
    -------
    dict
        Keyword arguments for ``blockid.models.arx.ARX(["v1", "v2"], ["y1", "y2"], ...)``
        in the SPEC.md convention: ``na=2, nb=2, nk=1``, ``a[output][output]`` =
        ``[a_1, a_2]``, ``b[output][input]`` = ``[b_0, b_1]``, ``input_offset``,
        ``output_offset`` and ``sampling_time``.
    """
    ad, bd, c = _flow_field_discrete(params)
    obs = np.vstack([c, c @ ad])
    m = c @ ad @ ad @ np.linalg.inv(obs)
    m0, m1 = m[:, :2], m[:, 2:]
    a1, a2 = -m1, -m0
    b0 = c @ bd
    b1 = c @ ad @ bd - m1 @ c @ bd
    outputs, inputs = ("y1", "y2"), ("v1", "v2")
    return {
        "na": 2,
        "nb": 2,
        "nk": 1,
        "a": {
            yo: {yi: [float(a1[i, j]), float(a2[i, j])] for j, yi in enumerate(outputs)}
            for i, yo in enumerate(outputs)
        },
        "b": {
            yo: {vi: [float(b0[i, j]), float(b1[i, j])] for j, vi in enumerate(inputs)}
            for i, yo in enumerate(outputs)
        },
        "input_offset": [params.v1_op, params.v2_op],
        "output_offset": [params.p0_op, params.mach_op],
        "sampling_time": params.dt,
    }


# --------------------------------------------------------------------------- helpers


def _condition_name(condition: str) -> str:
    key = str(condition).replace(" ", "").lower()
    for name in CONDITIONS:
        if key in (name.lower(), name[:3]):
            return name
    raise ParameterError(
        f"unknown wind-tunnel condition {condition!r}; use one of {', '.join(CONDITIONS)}"
    )


def _command(name: str, values: np.ndarray) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise DataError(f"{name} must be a non-empty one-dimensional array, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise DataError(f"{name} has a non-finite value at sample {bad}; remove or fill it")
    return np.ascontiguousarray(arr)


def _midband_output(params: WindTunnelParameters, u: float) -> float:
    """Backlash output in the middle of the dead band at input ``u``."""
    m_left, c_left, m_right, c_right = params.finger_backlash
    return 0.5 * (m_left * (u + c_left) + m_right * (u - c_right))


def _midband_input(params: WindTunnelParameters, v2):
    """Input ``u2`` whose mid-band backlash output holds S2 at position ``v2`` (inverse)."""
    m_left, c_left, m_right, c_right = params.finger_backlash
    x = np.asarray(v2, dtype=float) / params.finger_gain
    u = (2.0 * x - m_left * c_left + m_right * c_right) / (m_left + m_right)
    return float(u) if u.ndim == 0 else u


def _piecewise_levels(
    rng: np.random.Generator, n: int, centre: float, span: float, hold: tuple[int, int]
) -> np.ndarray:
    """Levels uniform in ``centre ± span`` held for uniform ``hold`` samples; starts at centre."""
    out = np.empty(n)
    start, level = 0, centre
    while start < n:
        length = int(rng.integers(hold[0], hold[1] + 1))
        out[start : start + length] = level
        start += length
        level = centre + rng.uniform(-span, span)
    return out


def _flow_field_continuous(params: WindTunnelParameters):
    """``(A, B, C)`` of the flow field, states ``[q1, q2, p, m]``, inputs ``δv1, δv2``."""
    p = params
    a = np.array(
        [
            [-1.0 / p.tau_valve_flow, 0.0, 0.0, 0.0],
            [0.0, -1.0 / p.tau_throat_flow, 0.0, 0.0],
            [p.gain_p0_v1 / p.tau_pressure, p.gain_p0_v2 / p.tau_pressure, -1 / p.tau_pressure, 0],
            [p.gain_mach_v1 / p.tau_mach, p.gain_mach_v2 / p.tau_mach, 0.0, -1.0 / p.tau_mach],
        ]
    )
    b = np.array([[1.0 / p.tau_valve_flow, 0.0], [0.0, 1.0 / p.tau_throat_flow], [0, 0], [0, 0]])
    c = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    return a, b, c


def _flow_field_discrete(params: WindTunnelParameters):
    """Zero-order-hold discretisation ``(Ad, Bd, C)`` of the flow field at ``params.dt``."""
    a, b, c = _flow_field_continuous(params)
    n, m = b.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n], block[:n, n:] = a, b
    phi = expm(block * params.dt)
    return phi[:n, :n], phi[:n, n:], c


def _simulate_flow_field(params: WindTunnelParameters, dv: np.ndarray) -> np.ndarray:
    """Output deviations for samples ``0..n-1`` from input deviations ``dv[0] = δv(-1)``.

    The state starts at the steady state of ``δv(-1)``; ``s(t+1) = Ad s(t) + Bd δv(t)``,
    ``δy(t) = C s(t)``, so ``δy(t)`` depends on ``δv(t-1)`` and earlier (delay one).
    """
    ad, bd, c = _flow_field_discrete(params)
    forced = dv @ bd.T  # Bd δv(t) for t = -1..n-1
    state = np.linalg.solve(np.eye(ad.shape[0]) - ad, forced[0])  # rest before the record
    n = dv.shape[0] - 1
    out = np.empty((n, c.shape[0]))
    for t in range(n):
        # s(t) = Ad s(t-1) + Bd δv(t-1); the rest state is s(-1), the steady state.
        state = ad @ state + forced[t]
        out[t] = c @ state
    return out


def _throat_mach_sensitivity(mach: float) -> float:
    """``dM / (dA_t / A_ts)``: Mach change per throat-area change (test-section area units).

    The choke fingers set the area ``A_t`` of the choked second throat; the test-section
    Mach number follows from ``A_ts / A_t = A/A*(M)`` (isentropic area-Mach relation),
    so ``dM / d(A_t / A_ts) = A/A*(M) * M (1 + (γ-1)/2 M²) / (1 - M²)``. A finger
    movement changes ``A_t`` by the same area at both conditions, so the ratio of this
    function at the two Mach numbers is the ratio of the Mach sensitivities per mm.
    """
    k = 0.5 * (_GAMMA - 1.0)
    area_ratio = (1.0 / mach) * ((1.0 + k * mach**2) / (1.0 + k)) ** (
        (_GAMMA + 1.0) / (2.0 * (_GAMMA - 1.0))
    )
    return area_ratio * mach * (1.0 + k * mach**2) / (1.0 - mach**2)


def _mach_per_log_pressure_ratio(mach: float) -> float:
    """``dM / d ln(P0/ps)`` from ``P0/ps = (1 + (γ-1)/2 M²)^(γ/(γ-1))``."""
    k = 0.5 * (_GAMMA - 1.0)
    return (1.0 + k * mach**2) / (_GAMMA * mach)
