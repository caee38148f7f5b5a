"""Numba kernels of the electrohydraulic excavator-arm plant, SPEC.md "Paper B" model.

The state is ``x = [h, hdot, p1, p2, xv]`` (piston displacement, velocity, head- and
rod-side pressures, spool displacement). The kernels do no validation: the public
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
    "electrohydraulic_geometry",
    "electrohydraulic_rhs",
    "electrohydraulic_integrate",
    "electrohydraulic_angle",
]

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
P_AREA_GRADIENT = 9  # W [m]
P_DENSITY = 10  # rho [kg/m^3]
P_SUPPLY = 11  # ps [Pa]
P_RETURN = 12  # pr [Pa]
P_SPOOL_GAIN = 13  # kv [m/A]
P_SPOOL_TAU = 14  # tau_v [s]
P_DEADBAND = 15  # Id [A]
P_SPOOL_MAX = 16  # spool saturation [m]
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
N_PARAMETERS = 40


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
def electrohydraulic_rhs(x, current, p, dx):
    """Right-hand side of the plant, SPEC.md Paper B state equations.

    .. math::

        M(h)\\ddot h + \\tfrac12 M'(h)\\dot h^2 &= A_1 p_1 - A_2 p_2 - F_f(\\dot h)
            - F_c(\\dot h) - F_s(h) - F_l, \\\\
        \\dot p_1 &= \\frac{\\beta(p_1)}{V_1}\\left(Q_1 - A_1\\dot h - C_i(p_1 - p_2)
            - C_e p_1\\right), \\\\
        \\dot p_2 &= \\frac{\\beta(p_2)}{V_2}\\left(-Q_2 + A_2\\dot h + C_i(p_1 - p_2)
            - C_e p_2\\right), \\\\
        \\dot x_v &= \\frac{\\mathrm{sat}(k_v I_v) - x_v}{\\tau_v}.

    Parameters
    ----------
    x : ndarray of float64, shape (5,)
        State ``[h, hdot, p1, p2, xv]``.
    current : float
        Valve current [A] acting now (already delayed).
    p : ndarray of float64
        Parameter array (``P_*`` layout).
    dx : ndarray of float64, shape (5,)
        Output: the state derivative.
    """
    h = x[0]
    v = x[1]
    p1 = x[2]
    p2 = x[3]
    xv = x[4]
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

    # Four-way valve orifices: the active lands are chosen by sgn(xv); the lands
    # overlap the ports by P_OVERLAP, so the opening is the spool travel beyond it.
    opening = max(abs(xv) - p[P_OVERLAP], 0.0)
    if xv < 0.0:
        opening = -opening
    k_flow = p[P_DISCHARGE] * p[P_AREA_GRADIENT] * np.sqrt(2.0 / p[P_DENSITY]) * opening
    p_tr = p[P_TRANSITION]
    if xv >= 0.0:  # supply -> chamber 1, chamber 2 -> return
        q1 = k_flow * _signed_sqrt(p[P_SUPPLY] - p1, p_tr)
        q2 = k_flow * _signed_sqrt(p2 - p[P_RETURN], p_tr)
    else:  # chamber 1 -> return, supply -> chamber 2
        q1 = k_flow * _signed_sqrt(p1 - p[P_RETURN], p_tr)
        q2 = k_flow * _signed_sqrt(p[P_SUPPLY] - p2, p_tr)
    volume1 = p[P_VOLUME_HEAD] + area1 * h
    volume2 = p[P_VOLUME_ROD] + area2 * (p[P_STROKE] - h)
    leak = p[P_LEAK_INTERNAL] * (p1 - p2)
    # Entrained air softens the oil near zero pressure: beta(p) = beta_e (1 - e^(-p/p_a)),
    # so a chamber emptied faster than it is fed approaches p = 0 smoothly (cavitation).
    beta1 = p[P_BULK_MODULUS] * -np.expm1(-p1 / p[P_AIR_PRESSURE])
    beta2 = p[P_BULK_MODULUS] * -np.expm1(-p2 / p[P_AIR_PRESSURE])
    dx[2] = beta1 / volume1 * (q1 - area1 * v - leak - p[P_LEAK_EXTERNAL] * p1)  # (B) x3'
    dx[3] = beta2 / volume2 * (-q2 + area2 * v + leak - p[P_LEAK_EXTERNAL] * p2)  # (B) x4'

    # Spool: dead band in current, first-order lag, saturated opening.
    excess = abs(current) - p[P_DEADBAND]
    effective = 0.0
    if excess > 0.0:
        effective = excess if current > 0.0 else -excess  # Iv = dead-band(I)
    target = p[P_SPOOL_GAIN] * effective
    limit = p[P_SPOOL_MAX]
    target = min(max(target, -limit), limit)
    dx[4] = (target - xv) / p[P_SPOOL_TAU]  # (B) x5'


@njit(cache=True)
def _constrain(x, p):
    """Inelastic end stops on ``h`` and the pressure clip (relief / cavitation)."""
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


@njit(cache=True)
def electrohydraulic_integrate(x0, p, current, dt, substeps):
    """Integrate the plant with classical fixed-step RK4 under a sampled current.

    The current is held constant over each sample (zero-order hold of length
    ``dt * substeps``) and delayed by ``p[P_DELAY]`` seconds, rounded to a whole number
    of integration steps; before time zero the current is zero.

    Parameters
    ----------
    x0 : ndarray of float64, shape (5,)
        Initial state at ``t = 0``.
    p : ndarray of float64
        Parameter array (``P_*`` layout).
    current : ndarray of float64, shape (n,)
        Valve current [A], sample ``k`` acting over ``[k Ts, (k+1) Ts)``.
    dt : float
        Integration step [s].
    substeps : int
        Integration steps per sample.

    Returns
    -------
    states : ndarray of float64, shape (n, 5)
        State at the sampling instants ``t_k = k dt substeps`` (row 0 is ``x0``).
    """
    n = current.shape[0]
    states = np.empty((n, 5))
    x = x0.copy()
    stage = np.empty(5)
    k1 = np.empty(5)
    k2 = np.empty(5)
    k3 = np.empty(5)
    k4 = np.empty(5)
    delay_steps = int(np.round(p[P_DELAY] / dt))
    for k in range(n):
        states[k] = x
        for j in range(substeps):
            index = (k * substeps + j - delay_steps) // substeps
            u = current[index] if index >= 0 else 0.0
            electrohydraulic_rhs(x, u, p, k1)
            for i in range(5):
                stage[i] = x[i] + 0.5 * dt * k1[i]
            electrohydraulic_rhs(stage, u, p, k2)
            for i in range(5):
                stage[i] = x[i] + 0.5 * dt * k2[i]
            electrohydraulic_rhs(stage, u, p, k3)
            for i in range(5):
                stage[i] = x[i] + dt * k3[i]
            electrohydraulic_rhs(stage, u, p, k4)
            for i in range(5):
                x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            _constrain(x, p)
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
