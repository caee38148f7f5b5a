"""Numba kernels of the electrohydraulic excavator-arm plant, SPEC.md "Paper B" model.

The state is ``x = [h, hdot, p1, p2, xv, pp]``: piston displacement, velocity, head- and
rod-side pressures, main-spool displacement and the pilot pressure difference across the
main spool's ends (SPEC.md's five states plus the pilot stage, see
``docs/plants/electrohydraulic.md``). The kernels do no validation: the public
:func:`blockid.plants.electrohydraulic.simulate_electrohydraulic` checks its inputs
and packs :class:`~blockid.plants.electrohydraulic.ElectrohydraulicParameters` into
the flat parameter array whose layout is given by the ``P_*`` index constants below.

``electrohydraulic_rhs`` is the single right-hand side; the integrator, the steady
state helpers and the tests all use it (the tests also check it against a
plain-Python twin).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "N_PARAMETERS",
    "N_STATES",
    "electrohydraulic_geometry",
    "electrohydraulic_metering_area",
    "electrohydraulic_pilot_setpoint",
    "electrohydraulic_rhs",
    "electrohydraulic_integrate",
    "electrohydraulic_angle",
]

#: Length of the state vector ``[h, hdot, p1, p2, xv, pp]``.
N_STATES = 6

# Layout of the flat parameter array (SI units throughout).
P_AREA_HEAD = 0  # A1, head-side piston area [m^2]
P_AREA_ROD = 1  # A2, rod-side annulus area [m^2]
P_STROKE = 2  # L, cylinder stroke [m]
P_VOLUME_HEAD = 3  # V01, dead volume of chamber 1 incl. hose [m^3]
P_VOLUME_ROD = 4  # V02, dead volume of chamber 2 incl. hose [m^3]
P_BULK_MODULUS = 5  # beta_e [Pa]
P_LEAK_INTERNAL = 6  # Ci [m^3/(s Pa)]
P_LEAK_EXTERNAL = 7  # Ce [m^3/(s Pa)]
P_DISCHARGE = 8  # Cd [-]
P_AREA_GRADIENT = 9  # W, metering area gradient beyond the notch (slot width) [m]
P_DENSITY = 10  # rho [kg/m^3]
P_SUPPLY = 11  # ps [Pa]
P_RETURN = 12  # pr [Pa]
P_PILOT_GAIN = 13  # kp, pilot pressure per current above the threshold [Pa/A]
P_PILOT_TAU = 14  # tau_p, pilot pressure (EPPR) time constant [s]
P_DEADBAND = 15  # Id, threshold current of the pilot valve [A]
P_SPOOL_MAX = 16  # main-spool stroke to its end caps [m]
P_TRANSITION = 17  # laminar/turbulent transition pressure of the orifice [Pa]
P_PRESSURE_MIN = 18  # lower pressure clip [Pa]
P_PRESSURE_MAX = 19  # upper pressure clip (relief) [Pa]
P_PISTON_MASS = 20  # piston + rod mass [kg]
P_ARM_INERTIA = 21  # arm inertia about its pivot [kg m^2]
P_ARM_MASS = 22  # arm mass [kg]
P_ARM_COM = 23  # pivot -> arm centre of mass [m]
P_GRAVITY = 24  # g [m/s^2]
P_PIN_BASE = 25  # a, pivot -> cylinder base pin [m]
P_PIN_ROD = 26  # b, pivot -> cylinder rod-eye pin [m]
P_LENGTH_MIN = 27  # pin-to-pin length of the retracted cylinder [m]
P_ANGLE_OFFSET = 28  # theta = phi + offset [rad]
P_COULOMB = 29  # Coulomb friction force [N]
P_STATIC = 30  # static (breakaway) friction force [N]
P_STRIBECK_VELOCITY = 31  # Stribeck velocity [m/s]
P_SMOOTHING_VELOCITY = 32  # tanh regularisation velocity of the friction sign [m/s]
P_VISCOUS = 33  # viscous friction coefficient [N s/m]
P_SPRING = 34  # spring stiffness [N/m]
P_SPRING_FREE = 35  # spring free position [m]
P_LOAD = 36  # constant external load force on the rod [N]
P_DELAY = 37  # pure input delay [s]
P_OVERLAP = 38  # overlap of the main-spool lands [m]
P_AIR_PRESSURE = 39  # pressure scale of the entrained-air compliance [Pa]
P_PILOT_MAX = 40  # pilot supply pressure, upper limit of the pilot pressure [Pa]
P_SPOOL_END_AREA = 41  # As, area of a main-spool end (pilot chamber) [m^2]
P_SPOOL_PRELOAD = 42  # F0, centring-spring preload [N]
P_SPOOL_STIFFNESS = 43  # ks, centring-spring stiffness [N/m]
P_SPOOL_DAMPING = 44  # cs, damping of the spool by the pilot flow [N s/m]
P_NOTCH_LENGTH = 45  # xn, length of the V-shaped metering notch [m]
N_PARAMETERS = 46


@njit(cache=True)
def electrohydraulic_geometry(h, p):
    """Arm angle and its derivatives with respect to the piston displacement.

    The cylinder (pin-to-pin length ``l = l_min + h``) and the two pin radii ``a``, ``b``
    about the arm pivot form a triangle; by the law of cosines

    .. math::

        \\cos\\varphi = \\frac{a^2 + b^2 - l^2}{2ab}, \\qquad \\theta = \\varphi + \\theta_0,
        \\qquad \\frac{d\\theta}{dh} = \\frac{l}{ab\\sin\\varphi}.

    Parameters
    ----------
    h : float
        Piston displacement [m].
    p : ndarray of float64
        Parameter array (``P_*`` layout).

    Returns
    -------
    theta, dtheta, d2theta : float
        Arm angle [rad] (elevation of the arm's centre-of-mass line above the
        horizontal), ``dtheta/dh`` [rad/m] and ``d2theta/dh2`` [rad/m^2].
    """
    a = p[P_PIN_BASE]
    b = p[P_PIN_ROD]
    length = p[P_LENGTH_MIN] + h
    cos_phi = (a * a + b * b - length * length) / (2.0 * a * b)
    sin_phi = np.sqrt(1.0 - cos_phi * cos_phi)
    theta = np.arccos(cos_phi) + p[P_ANGLE_OFFSET]
    dtheta = length / (a * b * sin_phi)
    d2theta = 1.0 / (a * b * sin_phi) - length * cos_phi * dtheta / (a * b * sin_phi * sin_phi)
    return theta, dtheta, d2theta


@njit(cache=True)
def _signed_sqrt(dp, p_transition):
    """Regularised ``sign(dp) sqrt(|dp|)``: linear (laminar) for ``|dp| << p_transition``."""
    return dp / (dp * dp + p_transition * p_transition) ** 0.25


@njit(cache=True)
def electrohydraulic_pilot_setpoint(current, p):
    """Pilot pressure difference the pilot valves settle to for a held current [Pa].

    Two electro-proportional pilot valves, one per spool end, selected by the sign of
    the current; each passes nothing below its threshold current ``Id`` and is limited
    by the pilot supply:

    .. math::

        p_{set}(I) = \\mathrm{sgn}(I)\\,\\min\\bigl(k_p \\max(|I| - I_d, 0),\\ p_{p,max}\\bigr).
    """
    excess = abs(current) - p[P_DEADBAND]
    if excess <= 0.0:
        return 0.0
    target = min(p[P_PILOT_GAIN] * excess, p[P_PILOT_MAX])
    return target if current > 0.0 else -target


@njit(cache=True)
def electrohydraulic_metering_area(xv, p):
    """Open area of each metering edge of the main spool [m^2].

    The lands overlap the ports by ``x_ov``; beyond it a V-shaped notch of length
    ``x_n`` opens (width growing linearly, area quadratically) and then the full slot of
    width ``W`` (area linear, same gradient at ``x_n``):

    .. math::

        x_o = \\max(|x_v| - x_{ov}, 0), \\qquad
        A(x_o) = \\begin{cases} W x_o^2 / (2 x_n), & x_o \\le x_n, \\\\
                 W (x_o - x_n / 2), & x_o > x_n. \\end{cases}
    """
    opening = abs(xv) - p[P_OVERLAP]
    if opening <= 0.0:
        return 0.0
    notch = p[P_NOTCH_LENGTH]
    if opening <= notch:
        return p[P_AREA_GRADIENT] * opening * opening / (2.0 * notch)
    return p[P_AREA_GRADIENT] * (opening - 0.5 * notch)


@njit(cache=True)
def _spool_rate(xv, pp, p):
    """Main-spool velocity: pilot force against the preloaded centring spring.

    ``c_s xv' = A_s pp - k_s xv - F0 sgn(xv)``; at neutral the spring retainers hold the
    spool (``xv' = 0``) while ``|A_s pp| <= F0``; the end caps stop it at ``+-x_max``.
    """
    drive = p[P_SPOOL_END_AREA] * pp
    preload = p[P_SPOOL_PRELOAD]
    if xv > 0.0:
        spring = p[P_SPOOL_STIFFNESS] * xv + preload
    elif xv < 0.0:
        spring = p[P_SPOOL_STIFFNESS] * xv - preload
    else:
        spring = min(max(drive, -preload), preload)
    rate = (drive - spring) / p[P_SPOOL_DAMPING]
    limit = p[P_SPOOL_MAX]
    if (xv >= limit and rate > 0.0) or (xv <= -limit and rate < 0.0):
        rate = 0.0
    return rate


@njit(cache=True)
def electrohydraulic_rhs(x, current, p, dx):
    """Right-hand side of the plant, SPEC.md Paper B state equations with a pilot stage.

    .. math::

        M(h)\\ddot h + \\tfrac12 M'(h)\\dot h^2 &= A_1 p_1 - A_2 p_2 - F_f(\\dot h)
            - F_c(\\dot h) - F_s(h) - F_l, \\\\
        \\dot p_1 &= \\frac{\\beta(p_1)}{V_1}\\left(Q_1 - A_1\\dot h - C_i(p_1 - p_2)
            - C_e p_1\\right), \\\\
        \\dot p_2 &= \\frac{\\beta(p_2)}{V_2}\\left(-Q_2 + A_2\\dot h + C_i(p_1 - p_2)
            - C_e p_2\\right), \\\\
        c_s \\dot x_v &= A_s p_p - k_s x_v - F_0\\,\\mathrm{sgn}(x_v), \\\\
        \\tau_p \\dot p_p &= p_{set}(I) - p_p,

    with ``Q1``, ``Q2`` through the metering area ``A(xv)``
    (:func:`electrohydraulic_metering_area`) and ``p_set`` from
    :func:`electrohydraulic_pilot_setpoint`.

    Parameters
    ----------
    x : ndarray of float64, shape (6,)
        State ``[h, hdot, p1, p2, xv, pp]``.
    current : float
        Pilot valve current [A] acting now (already delayed).
    p : ndarray of float64
        Parameter array (``P_*`` layout).
    dx : ndarray of float64, shape (6,)
        Output: the state derivative.
    """
    h = x[0]
    v = x[1]
    p1 = x[2]
    p2 = x[3]
    xv = x[4]
    pp = x[5]
    area1 = p[P_AREA_HEAD]
    area2 = p[P_AREA_ROD]

    # Mechanics: generalised coordinate h, arm inertia reflected through the linkage.
    theta, dtheta, d2theta = electrohydraulic_geometry(h, p)
    mass = p[P_PISTON_MASS] + p[P_ARM_INERTIA] * dtheta * dtheta  # M(h)
    dmass = 2.0 * p[P_ARM_INERTIA] * dtheta * d2theta  # M'(h)
    gravity = p[P_ARM_MASS] * p[P_GRAVITY] * p[P_ARM_COM] * np.cos(theta) * dtheta
    spring = p[P_SPRING] * (h - p[P_SPRING_FREE]) + gravity  # Fs(x1): spring + gravity
    stribeck = p[P_COULOMB] + (p[P_STATIC] - p[P_COULOMB]) * np.exp(
        -((v / p[P_STRIBECK_VELOCITY]) ** 2)
    )
    friction = stribeck * np.tanh(v / p[P_SMOOTHING_VELOCITY])  # Ff(x2), smooth sign
    viscous = p[P_VISCOUS] * v  # Fc(x2)
    force = area1 * p1 - area2 * p2 - friction - viscous - spring - p[P_LOAD]
    dx[0] = v  # (B) x1' = x2
    dx[1] = (force - 0.5 * dmass * v * v) / mass  # (B) x2'

    # Four-way valve orifices (B, g1 and g2): the active metering edges are chosen by
    # sgn(xv); their open area A(xv) is the progressive notch profile.
    k_flow = p[P_DISCHARGE] * electrohydraulic_metering_area(xv, p) * np.sqrt(2.0 / p[P_DENSITY])
    p_tr = p[P_TRANSITION]
    if xv >= 0.0:  # supply -> chamber 1, chamber 2 -> return
        q1 = k_flow * _signed_sqrt(p[P_SUPPLY] - p1, p_tr)
        q2 = k_flow * _signed_sqrt(p2 - p[P_RETURN], p_tr)
    else:  # chamber 1 -> return, supply -> chamber 2
        q1 = -k_flow * _signed_sqrt(p1 - p[P_RETURN], p_tr)
        q2 = -k_flow * _signed_sqrt(p[P_SUPPLY] - p2, p_tr)
    volume1 = p[P_VOLUME_HEAD] + area1 * h
    volume2 = p[P_VOLUME_ROD] + area2 * (p[P_STROKE] - h)
    leak = p[P_LEAK_INTERNAL] * (p1 - p2)
    # Entrained air softens the oil near zero pressure: beta(p) = beta_e (1 - e^(-p/p_a)),
    # so a chamber emptied faster than it is fed approaches p = 0 smoothly (cavitation).
    beta1 = p[P_BULK_MODULUS] * -np.expm1(-p1 / p[P_AIR_PRESSURE])
    beta2 = p[P_BULK_MODULUS] * -np.expm1(-p2 / p[P_AIR_PRESSURE])
    dx[2] = beta1 / volume1 * (q1 - area1 * v - leak - p[P_LEAK_EXTERNAL] * p1)  # (B) x3'
    dx[3] = beta2 / volume2 * (-q2 + area2 * v + leak - p[P_LEAK_EXTERNAL] * p2)  # (B) x4'

    # Main spool (replaces (B) x5'): pilot force against the centring spring.
    dx[4] = _spool_rate(xv, pp, p)
    # Pilot stage: threshold current, pilot pressure lag.
    dx[5] = (electrohydraulic_pilot_setpoint(current, p) - pp) / p[P_PILOT_TAU]


@njit(cache=True)
def _constrain(x, xv_old, p):
    """Projections after a step: end stops, pressure clip, spool stops and neutral seat.

    Inelastic end stops on ``h``; pressures clipped to the relief / cavitation range;
    the spool clipped to its stroke, and seated at neutral when it crossed zero while the
    pilot force is below the spring preload (the retainers catch it there).
    """
    if x[0] <= 0.0:
        x[0] = 0.0
        if x[1] < 0.0:
            x[1] = 0.0
    elif x[0] >= p[P_STROKE]:
        x[0] = p[P_STROKE]
        if x[1] > 0.0:
            x[1] = 0.0
    for i in (2, 3):
        x[i] = min(max(x[i], p[P_PRESSURE_MIN]), p[P_PRESSURE_MAX])
    x[4] = min(max(x[4], -p[P_SPOOL_MAX]), p[P_SPOOL_MAX])
    crossed = (xv_old > 0.0 and x[4] <= 0.0) or (xv_old < 0.0 and x[4] >= 0.0)
    if crossed and abs(p[P_SPOOL_END_AREA] * x[5]) <= p[P_SPOOL_PRELOAD]:
        x[4] = 0.0


@njit(cache=True)
def electrohydraulic_integrate(x0, p, current, dt, substeps):
    """Integrate the plant with classical fixed-step RK4 under a sampled current.

    The current is held constant over each sample (zero-order hold of length
    ``dt * substeps``) and delayed by ``p[P_DELAY]`` seconds, rounded to a whole number
    of integration steps; before time zero the current is zero. After every step the
    projections of ``_constrain`` apply (end stops, pressure clip, spool seat).

    Parameters
    ----------
    x0 : ndarray of float64, shape (6,)
        Initial state at ``t = 0``.
    p : ndarray of float64
        Parameter array (``P_*`` layout).
    current : ndarray of float64, shape (n,)
        Pilot valve current [A], sample ``k`` acting over ``[k Ts, (k+1) Ts)``.
    dt : float
        Integration step [s].
    substeps : int
        Integration steps per sample.

    Returns
    -------
    states : ndarray of float64, shape (n, 6)
        State at the sampling instants ``t_k = k dt substeps`` (row 0 is ``x0``).
    """
    n = current.shape[0]
    states = np.empty((n, N_STATES))
    x = x0.copy()
    stage = np.empty(N_STATES)
    k1 = np.empty(N_STATES)
    k2 = np.empty(N_STATES)
    k3 = np.empty(N_STATES)
    k4 = np.empty(N_STATES)
    delay_steps = int(np.round(p[P_DELAY] / dt))
    for k in range(n):
        states[k] = x
        for j in range(substeps):
            index = (k * substeps + j - delay_steps) // substeps
            u = current[index] if index >= 0 else 0.0
            xv_old = x[4]
            electrohydraulic_rhs(x, u, p, k1)
            for i in range(N_STATES):
                stage[i] = x[i] + 0.5 * dt * k1[i]
            electrohydraulic_rhs(stage, u, p, k2)
            for i in range(N_STATES):
                stage[i] = x[i] + 0.5 * dt * k2[i]
            electrohydraulic_rhs(stage, u, p, k3)
            for i in range(N_STATES):
                stage[i] = x[i] + dt * k3[i]
            electrohydraulic_rhs(stage, u, p, k4)
            for i in range(N_STATES):
                x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            _constrain(x, xv_old, p)
    return states


@njit(cache=True)
def electrohydraulic_angle(h, p):
    """Arm angle [rad] and ``dtheta/dh`` [rad/m] for an array of displacements."""
    n = h.shape[0]
    theta = np.empty(n)
    dtheta = np.empty(n)
    for i in range(n):
        theta[i], dtheta[i], _ = electrohydraulic_geometry(h[i], p)
    return theta, dtheta
