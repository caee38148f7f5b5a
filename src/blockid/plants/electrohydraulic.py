"""Simulated plant of paper B: a pilot-operated proportional valve drives an excavator arm.

An asymmetric (single-rod) cylinder lifts the arm of a mid-size (about 13 t class)
hydraulic excavator about its pivot. As on paper B's retrofitted machine, the computer's
current drives electro-proportional pilot valves (one per direction, each with a
threshold current); their pilot pressure acts on the ends of the spring-centred main
spool of the directional valve, whose V-notch metering edges open a progressive flow
area. The measured output is the arm's angular velocity, obtained as in paper B: the
arm angle from an inclinometer sampled at 20 Hz, differentiated numerically. The
equations, the parameter values and their justification are in
``docs/plants/electrohydraulic.md``. State ``x = [h, hdot, p1, p2, xv, pp]`` (SPEC.md's
five states, Paper B, and the pilot pressure difference ``pp``):

.. math::

    \\dot h &= v, \\qquad
    M(h)\\dot v + \\tfrac12 M'(h) v^2 = A_1 p_1 - A_2 p_2 - F_f(v) - F_c(v) - F_s(h) - F_l, \\\\
    \\dot p_1 &= \\frac{\\beta(p_1)}{V_{01} + A_1 h}\\bigl(Q_1 - A_1 v - C_i(p_1 - p_2)
        - C_e p_1\\bigr), \\\\
    \\dot p_2 &= \\frac{\\beta(p_2)}{V_{02} + A_2 (L - h)}\\bigl(-Q_2 + A_2 v
        + C_i(p_1 - p_2) - C_e p_2\\bigr), \\\\
    c_s \\dot x_v &= A_s p_p - k_s x_v - F_0\\,\\mathrm{sgn}(x_v)
        \\quad (x_v = 0 \\text{ held while } |A_s p_p| \\le F_0), \\\\
    \\tau_p \\dot p_p &= \\mathrm{sgn}(I)\\min\\bigl(k_p \\max(|I(t - \\tau_d)| - I_d, 0),
        p_{p,max}\\bigr) - p_p,

with ``M(h) = m_p + J theta'(h)^2`` (arm inertia through the linkage),
``beta(p) = beta_e (1 - exp(-p / p_a))`` (air release near zero pressure) and the
four-way valve flows through the metering area ``A(xv)`` (overlap ``x_ov``, then a
V-notch of length ``x_n``, then the full slot of width ``W``), ``k = Cd A(xv) sqrt(2 / rho)``:
``Q1 = k s(ps - p1)``, ``Q2 = k s(p2 - pr)`` for ``xv >= 0``; ``Q1 = -k s(p1 - pr)``,
``Q2 = -k s(ps - p2)`` for ``xv < 0``, where ``s(dp) = dp / (dp^2 + p_tr^2)^(1/4)`` is the
signed square root, regularised (laminar) near zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np
import pandas as pd
from scipy.optimize import brentq
from scipy.signal import butter, sosfiltfilt

from blockid._kernels import electrohydraulic as _k
from blockid._kernels import writable
from blockid.errors import ParameterError

__all__ = [
    "MIN_TRAJECTORY_DURATION",
    "PHASE_TRIALS",
    "VALIDATION_BANDWIDTH",
    "ElectrohydraulicParameters",
    "electrohydraulic_equilibrium",
    "electrohydraulic_static_spool",
    "electrohydraulic_static_velocity",
    "simulate_electrohydraulic",
    "multisine_current",
    "general_trajectory_current",
    "electrohydraulic_experiment",
]

#: Integration steps per 50 ms sample by default (1 ms RK4 step, see the docs for the
#: step-halving check); other sample times keep the step near 1 ms.
DEFAULT_STEP = 1.0e-3

#: Random phase sets searched for the lowest-crest-factor multisine of an experiment.
PHASE_TRIALS = 64

#: Default corner [Hz] of the validation command's low-pass: the top component of paper
#: B's multisine, so that validation stays in the band the estimation record excites.
VALIDATION_BANDWIDTH = 0.5

#: Shortest validation trajectory [s] (:func:`general_trajectory_current`).
MIN_TRAJECTORY_DURATION = 10.0


@dataclass(frozen=True)
class ElectrohydraulicParameters:
    """Physical parameters of the excavator-arm cylinder drive (SI units).

    Defaults describe the arm cylinder of a mid-size (about 13 t class) excavator;
    ``docs/plants/electrohydraulic.md`` justifies each value.

    Attributes
    ----------
    bore_diameter : float
        Piston diameter [m].
    rod_diameter : float
        Rod diameter [m]; ``A2 = pi/4 (bore^2 - rod^2)``.
    stroke : float
        Cylinder stroke ``L`` [m]; the piston displacement ``h`` lies in ``[0, L]``.
    dead_volume_head, dead_volume_rod : float
        Oil volume of each chamber at its end of stroke, hoses and valve ports
        included, ``V01``, ``V02`` [m^3].
    piston_mass : float
        Mass of piston and rod [kg].
    supply_pressure, return_pressure : float
        ``ps``, ``pr`` [Pa] (gauge).
    bulk_modulus : float
        Effective bulk modulus of oil and hoses ``beta_e`` [Pa].
    oil_density : float
        ``rho`` [kg/m^3].
    internal_leakage, external_leakage : float
        ``Ci``, ``Ce`` [m^3/(s Pa)].
    discharge_coefficient : float
        ``Cd`` of the valve orifices [-].
    area_gradient : float
        ``W`` [m^2/m]: metering area per spool displacement once the V-shaped notch has
        run into the full-width slot (the largest area gradient of the profile).
    notch_length : float
        ``x_n`` [m]: length of the V-shaped metering notch beyond the overlap; over it
        the area grows quadratically, ``W x_o^2 / (2 x_n)`` (fine metering).
    deadband_current : float
        ``Id`` [A]: threshold current of the electro-proportional pilot valves; no pilot
        pressure while ``|I| <= Id`` (paper B, Fig. 2a).
    pilot_gain : float
        ``kp`` [Pa/A]: pilot pressure per current above the threshold.
    pilot_pressure_max : float
        ``pp,max`` [Pa]: pilot supply pressure, the highest pilot pressure.
    pilot_time_constant : float
        ``tau_p`` [s] of the first-order pilot pressure response (solenoid, pilot valve,
        pilot line).
    spool_end_area : float
        ``As`` [m^2]: area of a main-spool end on which the pilot pressure acts.
    spool_preload : float
        ``F0`` [N]: preload of the centring spring; the spool leaves neutral only when
        ``|As pp| > F0`` (part of the main-valve dead band, paper B, Fig. 2b).
    spool_stiffness : float
        ``ks`` [N/m] of the centring spring.
    spool_damping : float
        ``cs`` [N s/m]: damping of the spool motion by the pilot oil that must flow
        through the pilot lines and damping orifices (linearised), so that the spool
        follows the pilot pressure with the time constant ``cs / ks``.
    spool_max : float
        Main-spool stroke to its end caps [m].
    spool_overlap : float
        Overlap of the main-spool lands [m]: no flow while ``|xv|`` is below it (paper B,
        Fig. 2b). The dead band seen at the cylinder is :attr:`deadband_total`.
    input_delay : float
        Pure delay ``tau_d`` [s] between the commanded current and the pilot valves,
        rounded to whole integration steps: what the model does not resolve (computer
        I/O latency, the inclinometer's filter and bus latency, the pump's pressure
        build-up); the default makes the plant's dead time paper B's ``nk = 8``.
    transition_pressure : float
        ``p_tr`` [Pa] of the regularised orifice square root.
    air_pressure : float
        ``p_a`` [Pa]: entrained air makes the effective bulk modulus
        ``beta_e (1 - exp(-p / p_a))``, vanishing towards zero pressure.
    min_pressure : float
        Lower clip of the chamber pressures [Pa]; the upper clip (relief setting) is
        ``1.1 ps``.
    arm_mass, arm_com_distance, arm_inertia : float
        Arm (with bucket) mass [kg], pivot-to-centre-of-mass distance [m] and moment of
        inertia about the pivot [kg m^2].
    pin_base_distance, pin_rod_distance : float
        Distances from the arm pivot to the cylinder base pin ``a`` and to the rod-eye
        pin ``b`` [m].
    retracted_length : float
        Pin-to-pin length of the fully retracted cylinder [m].
    angle_offset : float
        ``theta = phi + angle_offset`` [rad], ``phi`` the pivot angle of the linkage
        triangle; chosen so that the arm is horizontal near mid-stroke.
    gravity : float
        [m/s^2].
    coulomb_friction, static_friction : float
        Coulomb and breakaway seal friction [N].
    stribeck_velocity : float
        [m/s].
    friction_smoothing_velocity : float
        Velocity scale of the ``tanh`` that replaces ``sign(v)`` [m/s].
    viscous_friction : float
        ``Bp`` [N s/m].
    spring_stiffness, spring_free_position : float
        Linear spring ``ks (h - h_s)`` [N/m], [m] (hoses, cable carrier and linkage
        compliance acting on the rod).
    external_load : float
        Constant extra load force ``Fl`` on the rod [N] (payload; positive resists
        extension).
    angle_noise_std : float
        Standard deviation of the inclinometer noise [rad].
    initial_position : float
        Piston displacement at the start of an experiment [m].
    """

    bore_diameter: float = 0.120
    rod_diameter: float = 0.085
    stroke: float = 1.2
    dead_volume_head: float = 2.0e-3
    dead_volume_rod: float = 2.0e-3
    piston_mass: float = 150.0
    supply_pressure: float = 20.0e6
    return_pressure: float = 0.3e6
    bulk_modulus: float = 1.0e9
    oil_density: float = 860.0
    internal_leakage: float = 5.0e-13
    external_leakage: float = 1.0e-15
    discharge_coefficient: float = 0.65
    area_gradient: float = 4.67e-3
    notch_length: float = 4.0e-3
    deadband_current: float = 0.20
    pilot_gain: float = 3.65e6
    pilot_pressure_max: float = 3.9e6
    pilot_time_constant: float = 0.03
    spool_end_area: float = 3.8e-4
    spool_preload: float = 133.0
    spool_stiffness: float = 9.3e4
    spool_damping: float = 9.3e3
    spool_max: float = 9.0e-3
    spool_overlap: float = 1.0e-3
    input_delay: float = 0.25
    transition_pressure: float = 2.0e5
    air_pressure: float = 3.0e5
    min_pressure: float = 1.0e4
    arm_mass: float = 2500.0
    arm_com_distance: float = 2.3
    arm_inertia: float = 1.6e4
    pin_base_distance: float = 2.4
    pin_rod_distance: float = 0.8
    retracted_length: float = 1.8
    angle_offset: float = -1.46
    gravity: float = 9.81
    coulomb_friction: float = 1.5e3
    static_friction: float = 2.5e3
    stribeck_velocity: float = 0.01
    friction_smoothing_velocity: float = 1.0e-3
    viscous_friction: float = 5.0e3
    spring_stiffness: float = 2.0e4
    spring_free_position: float = 0.6
    external_load: float = 0.0
    angle_noise_std: float = 8.7e-4
    initial_position: float = 0.6

    @property
    def deadband_total(self) -> float:
        """Current dead band seen at the cylinder [A].

        The current at which the held spool reaches the end of the overlap:
        ``Id + (F0 + ks x_ov) / (As kp)``.
        """
        force = self.spool_preload + self.spool_stiffness * self.spool_overlap
        return self.deadband_current + force / (self.spool_end_area * self.pilot_gain)

    @property
    def spool_time_constant(self) -> float:
        """Time constant ``cs / ks`` [s] of the spool following the pilot force."""
        return self.spool_damping / self.spool_stiffness

    @property
    def area_head(self) -> float:
        """Head-side piston area ``A1`` [m^2]."""
        return math.pi / 4.0 * self.bore_diameter**2

    @property
    def area_rod(self) -> float:
        """Rod-side annulus area ``A2`` [m^2]."""
        return math.pi / 4.0 * (self.bore_diameter**2 - self.rod_diameter**2)

    def to_array(self) -> np.ndarray:
        """Validate and pack into the flat array used by the numba kernels.

        Raises
        ------
        ParameterError
            If a value is non-finite, of the wrong sign, or the linkage cannot be built.
        """
        for f in fields(self):
            value = getattr(self, f.name)
            if not np.isfinite(value):
                raise ParameterError(f"ElectrohydraulicParameters.{f.name} must be finite.")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in _NON_NEGATIVE and value < 0.0:
                raise ParameterError(f"ElectrohydraulicParameters.{f.name} must be >= 0.")
            if f.name not in _NON_NEGATIVE | _ANY_SIGN and value <= 0.0:
                raise ParameterError(f"ElectrohydraulicParameters.{f.name} must be > 0.")
        if self.rod_diameter >= self.bore_diameter:
            raise ParameterError(
                "ElectrohydraulicParameters.rod_diameter must be smaller than bore_diameter."
            )
        if self.return_pressure >= self.supply_pressure:
            raise ParameterError(
                "ElectrohydraulicParameters.return_pressure must be below supply_pressure."
            )
        if self.static_friction < self.coulomb_friction:
            raise ParameterError(
                "ElectrohydraulicParameters.static_friction must be >= coulomb_friction."
            )
        a, b = self.pin_base_distance, self.pin_rod_distance
        if not (abs(a - b) < self.retracted_length and self.retracted_length + self.stroke < a + b):
            raise ParameterError(
                "ElectrohydraulicParameters: the linkage triangle needs |a - b| < "
                "retracted_length and retracted_length + stroke < a + b; change "
                "pin_base_distance, pin_rod_distance, retracted_length or stroke."
            )
        if not 0.0 <= self.initial_position <= self.stroke:
            raise ParameterError(
                "ElectrohydraulicParameters.initial_position must lie in [0, stroke]."
            )
        p = np.empty(_k.N_PARAMETERS)
        p[_k.P_AREA_HEAD] = self.area_head
        p[_k.P_AREA_ROD] = self.area_rod
        p[_k.P_STROKE] = self.stroke
        p[_k.P_VOLUME_HEAD] = self.dead_volume_head
        p[_k.P_VOLUME_ROD] = self.dead_volume_rod
        p[_k.P_BULK_MODULUS] = self.bulk_modulus
        p[_k.P_LEAK_INTERNAL] = self.internal_leakage
        p[_k.P_LEAK_EXTERNAL] = self.external_leakage
        p[_k.P_DISCHARGE] = self.discharge_coefficient
        p[_k.P_AREA_GRADIENT] = self.area_gradient
        p[_k.P_DENSITY] = self.oil_density
        p[_k.P_SUPPLY] = self.supply_pressure
        p[_k.P_RETURN] = self.return_pressure
        p[_k.P_PILOT_GAIN] = self.pilot_gain
        p[_k.P_PILOT_TAU] = self.pilot_time_constant
        p[_k.P_DEADBAND] = self.deadband_current
        p[_k.P_SPOOL_MAX] = self.spool_max
        p[_k.P_TRANSITION] = self.transition_pressure
        p[_k.P_PRESSURE_MIN] = self.min_pressure
        p[_k.P_PRESSURE_MAX] = 1.1 * self.supply_pressure
        p[_k.P_PISTON_MASS] = self.piston_mass
        p[_k.P_ARM_INERTIA] = self.arm_inertia
        p[_k.P_ARM_MASS] = self.arm_mass
        p[_k.P_ARM_COM] = self.arm_com_distance
        p[_k.P_GRAVITY] = self.gravity
        p[_k.P_PIN_BASE] = self.pin_base_distance
        p[_k.P_PIN_ROD] = self.pin_rod_distance
        p[_k.P_LENGTH_MIN] = self.retracted_length
        p[_k.P_ANGLE_OFFSET] = self.angle_offset
        p[_k.P_COULOMB] = self.coulomb_friction
        p[_k.P_STATIC] = self.static_friction
        p[_k.P_STRIBECK_VELOCITY] = self.stribeck_velocity
        p[_k.P_SMOOTHING_VELOCITY] = self.friction_smoothing_velocity
        p[_k.P_VISCOUS] = self.viscous_friction
        p[_k.P_SPRING] = self.spring_stiffness
        p[_k.P_SPRING_FREE] = self.spring_free_position
        p[_k.P_LOAD] = self.external_load
        p[_k.P_DELAY] = self.input_delay
        p[_k.P_OVERLAP] = self.spool_overlap
        p[_k.P_AIR_PRESSURE] = self.air_pressure
        p[_k.P_PILOT_MAX] = self.pilot_pressure_max
        p[_k.P_SPOOL_END_AREA] = self.spool_end_area
        p[_k.P_SPOOL_PRELOAD] = self.spool_preload
        p[_k.P_SPOOL_STIFFNESS] = self.spool_stiffness
        p[_k.P_SPOOL_DAMPING] = self.spool_damping
        p[_k.P_NOTCH_LENGTH] = self.notch_length
        return p


# Fields that may be zero, and fields of either sign; all others must be positive.
_NON_NEGATIVE = frozenset(
    {
        "internal_leakage",
        "external_leakage",
        "deadband_current",
        "input_delay",
        "spool_overlap",
        "spool_preload",
        "spring_stiffness",
        "viscous_friction",
        "angle_noise_std",
        "return_pressure",
        "initial_position",
    }
)
_ANY_SIGN = frozenset({"spring_free_position", "external_load", "angle_offset"})


def _resolve_params(params: ElectrohydraulicParameters | None) -> ElectrohydraulicParameters:
    if params is None:
        return ElectrohydraulicParameters()
    if not isinstance(params, ElectrohydraulicParameters):
        raise ParameterError(
            "params must be an ElectrohydraulicParameters instance or None (defaults)."
        )
    return params


def electrohydraulic_equilibrium(
    position: float | None = None, params: ElectrohydraulicParameters | None = None
) -> np.ndarray:
    """Rest state at zero current: the arm held at ``position`` by the closed valve.

    With the spool inside its overlap no oil passes the valve; internal leakage
    equalises the chamber pressures, so at rest ``p1 = p2 = p_eq`` with
    ``(A1 - A2) p_eq = F_s(h) + F_l`` (gravity through the linkage plus spring and load).
    External leakage ``Ce`` makes the arm sink at ``Ce (p1 + p2) / (A1 - A2)``, about
    4e-6 m/s (0.25 mm in 55 s) at mid-stroke with the defaults, neglected here.

    Parameters
    ----------
    position : float, optional
        Piston displacement [m]; ``params.initial_position`` by default.
    params : ElectrohydraulicParameters, optional
        Plant parameters; defaults when omitted.

    Returns
    -------
    ndarray of float, shape (6,)
        ``[h, 0, p_eq, p_eq, 0, 0]``: spool at neutral, no pilot pressure.
    """
    params = _resolve_params(params)
    p = params.to_array()
    h = params.initial_position if position is None else float(position)
    if not 0.0 <= h <= params.stroke:
        raise ParameterError(f"position must lie in [0, stroke={params.stroke}] m, got {h}.")
    load = _load_force(h, params, p)
    p_eq = load / (params.area_head - params.area_rod)
    if not params.min_pressure < p_eq < 1.1 * params.supply_pressure:
        raise ParameterError(
            f"the closed valve cannot hold the arm at position {h} m (rest pressure "
            f"{p_eq:.3g} Pa outside the pressure range); change external_load or the arm."
        )
    return np.array([h, 0.0, p_eq, p_eq, 0.0, 0.0])


def _substeps(sample_time: float, substeps: int | None) -> int:
    if substeps is None:
        return max(1, int(round(sample_time / DEFAULT_STEP)))
    if isinstance(substeps, bool) or not isinstance(substeps, int | np.integer) or substeps < 1:
        raise ParameterError(f"substeps must be a positive integer, got {substeps!r}.")
    return int(substeps)


def _check_sample_time(sample_time: float) -> float:
    if not (isinstance(sample_time, int | float) and np.isfinite(sample_time) and sample_time > 0):
        raise ParameterError(
            f"sample_time must be a positive number of seconds, got {sample_time!r}."
        )
    return float(sample_time)


def simulate_electrohydraulic(
    current: np.ndarray,
    sample_time: float = 0.05,
    params: ElectrohydraulicParameters | None = None,
    seed: int | np.random.Generator | None = None,
    noise: bool = True,
    substeps: int | None = None,
) -> pd.DataFrame:
    """Simulate one experiment on the excavator arm and measure its angular velocity.

    The plant starts at rest (:func:`electrohydraulic_equilibrium` at
    ``params.initial_position``); the current is held over each sample and reaches the
    valve after ``params.input_delay``. The arm angle is read by an inclinometer with
    white noise of standard deviation ``params.angle_noise_std`` and the velocity is
    its central difference ``(theta_m[k+1] - theta_m[k-1]) / (2 Ts)`` (one-sided at the
    two ends, :func:`numpy.gradient`), as in paper B.

    Parameters
    ----------
    current : array_like, shape (n,)
        Valve current [A] per sample.
    sample_time : float
        Sampling period ``Ts`` [s]; paper B used 0.05 (20 Hz).
    params : ElectrohydraulicParameters, optional
        Plant parameters; defaults when omitted.
    seed : int or numpy.random.Generator, optional
        Seed of the measurement noise.
    noise : bool
        False gives the noise-free measurement (``angle_measured == angle``).
    substeps : int, optional
        RK4 steps per sample; by default the step is about 1 ms.

    Returns
    -------
    pandas.DataFrame
        Columns ``t`` [s], ``current`` [A], ``h`` [m], ``hdot`` [m/s], ``p1``, ``p2``
        [Pa], ``xv`` [m], ``pilot`` (pilot pressure difference) [Pa], ``angle`` (true)
        [rad], ``angle_measured`` [rad] and ``velocity`` [rad/s], the identification
        output.

    Examples
    --------
    >>> u = multisine_current(duration=5.0, seed=0)
    >>> df = simulate_electrohydraulic(u, seed=1)
    >>> list(df.columns)[-3:]
    ['angle', 'angle_measured', 'velocity']
    """
    params = _resolve_params(params)
    sample_time = _check_sample_time(sample_time)
    n_sub = _substeps(sample_time, substeps)
    u = np.asarray(current, dtype=float)
    if u.ndim != 1 or u.size < 3:
        raise ParameterError("current must be a 1-D array with at least 3 samples.")
    if not np.all(np.isfinite(u)):
        raise ParameterError("current contains NaN or inf; pass finite currents in ampere.")
    p = params.to_array()
    x0 = electrohydraulic_equilibrium(params.initial_position, params)
    states = _k.electrohydraulic_integrate(x0, p, writable(u, float), sample_time / n_sub, n_sub)
    angle, _ = _k.electrohydraulic_angle(np.ascontiguousarray(states[:, 0]), p)
    measured = angle.copy()
    if noise and params.angle_noise_std > 0.0:
        rng = np.random.default_rng(seed)
        measured += rng.normal(0.0, params.angle_noise_std, size=angle.size)
    velocity = np.gradient(measured, sample_time)
    return pd.DataFrame(
        {
            "t": np.arange(u.size) * sample_time,
            "current": u,
            "h": states[:, 0],
            "hdot": states[:, 1],
            "p1": states[:, 2],
            "p2": states[:, 3],
            "xv": states[:, 4],
            "pilot": states[:, 5],
            "angle": angle,
            "angle_measured": measured,
            "velocity": velocity,
        }
    )


def _n_samples(duration: float, sample_time: float) -> int:
    sample_time = _check_sample_time(sample_time)
    if not (np.isfinite(duration) and duration >= 3 * sample_time):
        raise ParameterError(
            f"duration must be at least three samples ({3 * sample_time} s), got {duration!r}."
        )
    return int(round(duration / sample_time))


def multisine_current(
    duration: float = 55.0,
    sample_time: float = 0.05,
    frequencies: tuple[float, ...] = (0.05, 0.1, 0.2, 0.4, 0.5),
    amplitude: float = 0.9,
    offset: float = 0.0,
    seed: int | np.random.Generator | None = None,
    phase_trials: int = 1,
) -> np.ndarray:
    """Paper B's identification input: equal-amplitude multisine with random phases.

    .. math::

        I(k) = I_0 + \\frac{A}{\\max_k |s(k)|}\\, s(k), \\qquad
        s(k) = \\sum_i \\sin(2\\pi f_i k T_s + \\varphi_i),
        \\quad \\varphi_i \\sim U[0, 2\\pi),

    so that the current spans ``offset +- amplitude`` exactly. With ``phase_trials > 1``
    that many phase sets are drawn and the one with the lowest crest factor
    ``max|s| / rms(s)`` is kept (the usual random-phase search for a multisine that
    puts more of its time near the peak amplitude).

    Parameters
    ----------
    duration : float
        Length [s].
    sample_time : float
        Sampling period [s].
    frequencies : tuple of float
        Component frequencies [Hz], below the Nyquist frequency.
    amplitude : float
        Peak deviation from ``offset`` [A].
    offset : float
        Mean current [A].
    seed : int or numpy.random.Generator, optional
        Seed of the phases.
    phase_trials : int
        Number of random phase sets to choose the lowest crest factor from.

    Returns
    -------
    ndarray of float, shape (round(duration / sample_time),)
        Current [A].

    Examples
    --------
    >>> u = multisine_current(seed=0)
    >>> u.shape, round(float(abs(u).max()), 6)
    ((1100,), 0.9)
    """
    n = _n_samples(duration, sample_time)
    freqs = np.asarray(frequencies, dtype=float)
    if (
        freqs.ndim != 1
        or freqs.size == 0
        or np.any(freqs <= 0)
        or np.any(freqs >= 0.5 / sample_time)
    ):
        raise ParameterError(
            "frequencies must be a non-empty sequence of positive frequencies below the "
            f"Nyquist frequency {0.5 / sample_time} Hz."
        )
    if not (np.isfinite(amplitude) and amplitude > 0):
        raise ParameterError(f"amplitude must be a positive current in A, got {amplitude!r}.")
    if not np.isfinite(offset):
        raise ParameterError(f"offset must be a finite current in A, got {offset!r}.")
    if (
        isinstance(phase_trials, bool)
        or not isinstance(phase_trials, int | np.integer)
        or phase_trials < 1
    ):
        raise ParameterError(f"phase_trials must be a positive integer, got {phase_trials!r}.")
    rng = np.random.default_rng(seed)
    t = np.arange(n) * sample_time
    best, best_crest = None, np.inf
    for _ in range(int(phase_trials)):
        phases = rng.uniform(0.0, 2.0 * np.pi, size=freqs.size)
        s = np.sin(2.0 * np.pi * freqs[None, :] * t[:, None] + phases[None, :]).sum(axis=1)
        crest = np.abs(s).max() / np.sqrt(np.mean(s**2))
        if crest < best_crest:
            best, best_crest = s, crest
    return offset + amplitude * best / np.abs(best).max()


def general_trajectory_current(
    duration: float = 55.0,
    sample_time: float = 0.05,
    seed: int | np.random.Generator | None = None,
    bandwidth: float | None = VALIDATION_BANDWIDTH,
) -> np.ndarray:
    """A validation command unlike the multisine: an operator's point-to-point moves.

    The arm is sent between random positions within the middle half of the stroke
    (where the multisine runs go): each move holds a random current (0.45-0.85 A in the
    needed direction) for the time the default plant's static characteristic
    (:func:`electrohydraulic_static_velocity`) needs to cover the distance, followed
    by a random pause (0.2-1.5 s). A 0.2 s first-order filter rounds the edges and
    band-limited noise (0.1-1.5 Hz, 0.05 A rms) imitates the operator's hand. With a
    ``bandwidth``, the command is then low-pass filtered there (second-order
    Butterworth run forwards and backwards: zero phase, -6 dB at ``bandwidth``), so that
    it stays in the band the multisine identified (paper B's top component is 0.5 Hz);
    ``None`` keeps the step-like moves, whose content above 0.5 Hz asks the models to
    extrapolate in frequency. The command stays within +-0.9 A.

    Parameters
    ----------
    duration : float
        Length [s], at least :data:`MIN_TRAJECTORY_DURATION`.
    sample_time : float
        Sampling period [s].
    seed : int or numpy.random.Generator, optional
        Seed of the random moves.
    bandwidth : float or None, default 0.5
        Corner frequency [Hz] of the final low-pass filter, from ``2 / duration``
        (two cycles in the record) to below the Nyquist frequency; None for no filter.

    Returns
    -------
    ndarray of float, shape (round(duration / sample_time),)
        Current [A], within +-0.9 A.

    Examples
    --------
    >>> u = general_trajectory_current(seed=0)
    >>> u.shape, bool(abs(u).max() <= 0.9)
    ((1100,), True)
    """
    n = _n_samples(duration, sample_time)
    if duration < MIN_TRAJECTORY_DURATION:
        raise ParameterError(
            f"duration must be at least {MIN_TRAJECTORY_DURATION:g} s for point-to-point moves "
            f"and their pauses, got {duration!r}."
        )
    nyquist = 0.5 / sample_time
    if bandwidth is not None:
        if isinstance(bandwidth, bool) or not isinstance(bandwidth, int | float | np.number):
            raise ParameterError(f"bandwidth must be a number in Hz or None, got {bandwidth!r}.")
        lowest = 2.0 / duration  # two cycles over the record: the moves can still happen
        if not (np.isfinite(bandwidth) and lowest <= bandwidth < nyquist):
            raise ParameterError(
                f"bandwidth must be a frequency from {lowest:.3g} Hz (two cycles in the "
                f"{duration:g} s record) to below the Nyquist frequency {nyquist:g} Hz, or "
                f"None, got {bandwidth!r}."
            )
    rng = np.random.default_rng(seed)
    plant = ElectrohydraulicParameters()
    stroke = plant.stroke
    raw = np.zeros(n)
    k = 0
    position = plant.initial_position
    while k < n:
        target = position
        while abs(target - position) < 0.15 * stroke:
            target = rng.uniform(0.25 * stroke, 0.75 * stroke)
        level = rng.uniform(0.45, 0.85) * np.sign(target - position)
        speed = abs(float(electrohydraulic_static_velocity(level, position=position)))
        hold = abs(target - position) / speed
        pause = rng.uniform(0.2, 1.5)
        for value, length in ((level, hold), (0.0, pause)):
            m = int(round(length / sample_time))
            raw[k : k + m] = value
            k += m
        position = target
    alpha = math.exp(-sample_time / 0.2)
    smooth = np.empty(n)
    state = 0.0
    for i in range(n):
        state = alpha * state + (1.0 - alpha) * raw[i]  # first-order smoothing
        smooth[i] = state
    spectrum = np.fft.rfft(rng.normal(size=n))
    freqs = np.fft.rfftfreq(n, sample_time)
    spectrum[(freqs < 0.1) | (freqs > 1.5)] = 0.0
    jitter = np.fft.irfft(spectrum, n)
    jitter *= 0.05 / jitter.std()
    command = smooth + jitter
    if bandwidth is not None:
        sos = butter(2, bandwidth / nyquist, output="sos")
        command = sosfiltfilt(sos, command)
    return np.clip(command, -0.9, 0.9)


def electrohydraulic_static_spool(
    current: np.ndarray | float, params: ElectrohydraulicParameters | None = None
) -> np.ndarray:
    """Main-spool position for a held current: the valve's static characteristic.

    The pilot pressure settles at ``p_set(I)`` and the spool where the pilot force
    balances the centring spring:

    .. math::

        x_v = \\mathrm{sgn}(I)\\,\\min\\Bigl(\\frac{\\max(A_s |p_{set}(I)| - F_0, 0)}{k_s},
            x_{max}\\Bigr).

    Parameters
    ----------
    current : float or array_like
        Held current(s) [A].
    params : ElectrohydraulicParameters, optional
        Plant parameters; defaults when omitted.

    Returns
    -------
    ndarray of float
        Spool displacement [m], same shape as ``current``.
    """
    params = _resolve_params(params)
    p = params.to_array()
    currents = np.asarray(current, dtype=float)
    out = np.zeros(currents.shape)
    for index, value in np.ndenumerate(currents):
        force = params.spool_end_area * abs(_k.electrohydraulic_pilot_setpoint(value, p))
        travel = min(
            max(force - params.spool_preload, 0.0) / params.spool_stiffness, params.spool_max
        )
        out[index] = math.copysign(travel, value) if travel > 0.0 else 0.0
    return out


def electrohydraulic_static_velocity(
    current: np.ndarray | float,
    position: float | None = None,
    params: ElectrohydraulicParameters | None = None,
) -> np.ndarray:
    """Steady piston velocity for a constant current: the plant's static characteristic.

    For a held current the spool settles at :func:`electrohydraulic_static_spool` and,
    neglecting leakage and the laminar regularisation, the orifice equations give
    ``p1 = ps - (A1 v / k)^2``, ``p2 = pr + (A2 v / k)^2`` when extending and
    ``p1 = pr + (A1 v / k)^2``, ``p2 = ps - (A2 v / k)^2`` when retracting
    (``k = Cd A(xv) sqrt(2 / rho)``, ``A`` the metering area). The speed solves the
    force balance at the given position, e.g. when extending

    .. math::

        A_1 p_s - A_2 p_r - (A_1^3 + A_2^3)\\,\\frac{v^2}{k^2}
            = F_s(h) + F_l + F_f(v) + B_p v .

    The different right-hand sides of the two directions (the load helps retraction)
    and the areas ``A1 > A2`` make the response direction dependent.

    Parameters
    ----------
    current : float or array_like
        Held current(s) [A].
    position : float, optional
        Piston displacement [m] at which the load is evaluated; mid-stroke by default.
    params : ElectrohydraulicParameters, optional
        Plant parameters; defaults when omitted.

    Returns
    -------
    ndarray of float
        Piston velocity [m/s], same shape as ``current`` (0 inside the dead band or
        when the load cannot be lifted).
    """
    params = _resolve_params(params)
    p = params.to_array()
    h = 0.5 * params.stroke if position is None else float(position)
    if not 0.0 <= h <= params.stroke:
        raise ParameterError(f"position must lie in [0, stroke={params.stroke}] m, got {h}.")
    currents = np.asarray(current, dtype=float)
    spools = electrohydraulic_static_spool(currents, params)
    a1, a2 = params.area_head, params.area_rod
    cubes = a1**3 + a2**3
    load = _load_force(h, params, p)

    def friction(v: float) -> float:
        stribeck = params.coulomb_friction + (
            params.static_friction - params.coulomb_friction
        ) * math.exp(-((v / params.stribeck_velocity) ** 2))
        return stribeck * math.tanh(v / params.friction_smoothing_velocity) + (
            params.viscous_friction * v
        )

    ps, pr = params.supply_pressure, params.return_pressure
    flow_scale = params.discharge_coefficient * math.sqrt(2.0 / params.oil_density)
    out = np.zeros(currents.shape)
    for index, value in np.ndenumerate(currents):
        area = _k.electrohydraulic_metering_area(spools[index], p)
        if area <= 0.0:
            continue
        k = flow_scale * area
        # Net force driving the motion at zero speed; the load helps retraction.
        drive = a1 * ps - a2 * pr - load if value > 0.0 else a2 * ps - a1 * pr + load

        def balance(v: float, drive=drive, k=k) -> float:
            return drive - cubes * (v / k) ** 2 - friction(v)

        upper = k * math.sqrt(max(drive, 0.0) / cubes) + 1e-9
        if balance(0.0) <= 0.0:
            continue  # stalled: the load cannot be moved in this direction
        speed = brentq(balance, 0.0, upper, xtol=1e-12)
        out[index] = speed if value > 0.0 else -speed
    return out


def _load_force(h: float, params: ElectrohydraulicParameters, p: np.ndarray) -> float:
    """Position-dependent load ``F_s(h) + F_l``: gravity through the linkage, spring, load."""
    theta, dtheta, _ = _k.electrohydraulic_geometry(h, p)
    return (
        params.arm_mass * params.gravity * params.arm_com_distance * math.cos(theta) * dtheta
        + params.spring_stiffness * (h - params.spring_free_position)
        + params.external_load
    )


def _trim_experiment(
    current: np.ndarray, params: ElectrohydraulicParameters
) -> tuple[np.ndarray, float, ElectrohydraulicParameters]:
    """Prepare a test run as an operator would: trim the offset, centre the motion.

    The current offset is chosen so that the static characteristic predicts no net
    displacement (the direction-dependent speeds would otherwise make the arm creep
    towards an end stop), and the start position is moved so that the noise-free run
    is centred in the stroke (two corrections). Returns the trimmed current (clipped
    to +-1 A), the offset and the parameters with the new ``initial_position``.
    """
    grid = np.linspace(current.min() - 0.3, current.max() + 0.3, 241)
    speed = electrohydraulic_static_velocity(grid, params=params)

    def net(offset: float) -> float:
        return float(np.interp(current + offset, grid, speed).mean())

    offset = brentq(net, -0.3, 0.3) if net(-0.3) < 0.0 < net(0.3) else 0.0
    trimmed = np.clip(current + offset, -1.0, 1.0)
    centre = 0.5 * params.stroke
    margin = 0.05 * params.stroke
    for _ in range(2):
        run = simulate_electrohydraulic(trimmed, params=params, noise=False)
        shift = centre - 0.5 * (run["h"].min() + run["h"].max())
        start = min(max(params.initial_position + shift, margin), params.stroke - margin)
        params = replace(params, initial_position=float(start))
    return trimmed, float(offset), params


def electrohydraulic_experiment(
    seed: int | None = None,
    n_repeats: int = 10,
    params: ElectrohydraulicParameters | None = None,
    validation_bandwidth: float | None = VALIDATION_BANDWIDTH,
) -> dict[str, pd.DataFrame]:
    """Paper B's data: an averaged multisine estimation record and a validation record.

    The same multisine (:func:`multisine_current`, 55 s at 20 Hz, the lowest crest
    factor of :data:`PHASE_TRIALS` random phase sets) is applied ``n_repeats`` times
    with independent inclinometer noise; the measured angles are averaged and
    differentiated (equivalently the velocities are averaged, the central difference
    being linear). The validation record is one measured run of
    :func:`general_trajectory_current`. Before each, the current offset is trimmed so
    that the arm does not creep, and the start position is chosen so that the motion
    is centred in the stroke (see ``docs/plants/electrohydraulic.md``); both are
    stored in ``DataFrame.attrs`` (``"offset"``, ``"initial_position"``). The trimmed
    validation command is clipped to the current range of the estimation record, and
    by default band-limited to the multisine's top frequency: validation stays where
    the models were identified, in amplitude and in frequency.

    Parameters
    ----------
    seed : int, optional
        Master seed; the phases, the moves and every run's noise derive from it.
    n_repeats : int
        Number of repeated estimation runs (paper B: 10).
    params : ElectrohydraulicParameters, optional
        Plant parameters; defaults when omitted.
    validation_bandwidth : float or None, default 0.5
        ``bandwidth`` of the validation command [Hz] (see
        :func:`general_trajectory_current`); None for the step-like moves that
        extrapolate in frequency.

    Returns
    -------
    dict
        ``{"estimation": DataFrame, "validation": DataFrame}``, each with columns
        ``t`` [s], ``current`` [A], ``velocity`` [rad/s].

    Examples
    --------
    >>> data = electrohydraulic_experiment(seed=0, n_repeats=2)
    >>> data["estimation"].shape, data["validation"].shape
    ((1100, 3), (1100, 3))
    """
    if isinstance(n_repeats, bool) or not isinstance(n_repeats, int | np.integer) or n_repeats < 1:
        raise ParameterError(f"n_repeats must be a positive integer, got {n_repeats!r}.")
    params = _resolve_params(params)
    seeds = np.random.SeedSequence(seed).spawn(n_repeats + 3)
    records = {}
    span = (-np.inf, np.inf)
    for name, raw, noise_seeds in (
        (
            "estimation",
            multisine_current(seed=np.random.default_rng(seeds[0]), phase_trials=PHASE_TRIALS),
            seeds[3:],
        ),
        (
            "validation",
            general_trajectory_current(
                seed=np.random.default_rng(seeds[1]), bandwidth=validation_bandwidth
            ),
            seeds[2:3],
        ),
    ):
        current, offset, run_params = _trim_experiment(raw, params)
        # The two trims differ, so the trimmed validation command could leave the
        # current range of the estimation record (which comes first): keep it inside.
        current = np.clip(current, *span)
        span = (float(current.min()), float(current.max()))
        runs = [
            simulate_electrohydraulic(current, params=run_params, seed=np.random.default_rng(s))
            for s in noise_seeds
        ]
        frame = pd.DataFrame(
            {
                "t": runs[0]["t"],
                "current": current,
                "velocity": np.mean([r["velocity"].to_numpy() for r in runs], axis=0),
            }
        )
        frame.attrs["offset"] = offset
        frame.attrs["initial_position"] = run_params.initial_position
        records[name] = frame
    return records
