"""The electrohydraulic plant's kernels (blockid._kernels.electrohydraulic) against the
plain-Python twin of its documented equations (tests/reference.py): the linkage, the
right-hand side, the metering area and pilot set-point, the integration against
solve_ivp."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from blockid._kernels.electrohydraulic import (
    electrohydraulic_geometry,
    electrohydraulic_integrate,
    electrohydraulic_metering_area,
    electrohydraulic_pilot_setpoint,
    electrohydraulic_rhs,
)
from blockid.plants.electrohydraulic import (
    ElectrohydraulicParameters,
    electrohydraulic_equilibrium,
)

from reference import ref_area, ref_geometry, ref_pilot_setpoint, ref_rhs, ref_simulate

P = ElectrohydraulicParameters()
TS = 0.05


def test_geometry_matches_law_of_cosines_and_finite_differences():
    p = P.to_array()
    for h in np.linspace(0.01, P.stroke - 0.01, 7):
        theta, dth, d2th = electrohydraulic_geometry(h, p)
        ref = ref_geometry(h)
        np.testing.assert_allclose([theta, dth, d2th], ref, rtol=1e-12)
        eps = 1e-5
        hp, hm = h + eps, h - eps
        fd = (electrohydraulic_geometry(hp, p)[0] - electrohydraulic_geometry(hm, p)[0]) / (hp - hm)
        fd2 = (electrohydraulic_geometry(hp, p)[1] - electrohydraulic_geometry(hm, p)[1]) / (
            hp - hm
        )
        assert fd == pytest.approx(dth, rel=1e-6)
        assert fd2 == pytest.approx(d2th, rel=1e-4)
    # Arm roughly horizontal at mid-stroke, about +-50 degrees at the ends.
    ends = [electrohydraulic_geometry(h, p)[0] for h in (0.0, P.stroke)]
    assert abs(electrohydraulic_geometry(0.5 * P.stroke, p)[0]) < 0.1
    assert -1.0 < ends[0] < -0.7 and 0.7 < ends[1] < 1.0


def test_rhs_matches_python_reference(rng):
    p = P.to_array()
    dx = np.empty(6)
    for _ in range(300):
        x = np.array(
            [
                rng.uniform(0, P.stroke),
                rng.uniform(-0.4, 0.4),
                rng.uniform(0.05e6, 21e6),
                rng.uniform(0.05e6, 21e6),
                rng.choice([rng.uniform(-P.spool_max, P.spool_max), 0.0, P.spool_max]),
                rng.uniform(-3e6, 3e6),
            ]
        )
        current = rng.choice([rng.uniform(-1.2, 1.2), rng.uniform(-0.2, 0.2), 0.0])
        electrohydraulic_rhs(x, current, p, dx)
        np.testing.assert_allclose(dx, ref_rhs(x, current), rtol=1e-9, atol=1e-12)


def test_metering_area_and_pilot_setpoint_match_reference():
    p = P.to_array()
    for xv in np.linspace(-P.spool_max, P.spool_max, 401):
        assert electrohydraulic_metering_area(xv, p) == pytest.approx(ref_area(xv), abs=1e-15)
    for current in np.linspace(-1.5, 1.5, 301):
        assert electrohydraulic_pilot_setpoint(current, p) == pytest.approx(
            ref_pilot_setpoint(current), abs=1e-6
        )
    # Progressive profile: a quarter of the notch's end area at half its length, the
    # slot's gradient W beyond it, continuous slope at the joint.
    xn, xo = P.notch_length, P.spool_overlap
    end = electrohydraulic_metering_area(xo + xn, p)
    assert end == pytest.approx(0.5 * P.area_gradient * xn)
    assert electrohydraulic_metering_area(xo + 0.5 * xn, p) == pytest.approx(0.25 * end)
    eps = 1e-7
    for x in (xo + xn - eps, xo + xn + eps, P.spool_max - eps):
        slope = (
            electrohydraulic_metering_area(x + 0.5 * eps, p)
            - electrohydraulic_metering_area(x - 0.5 * eps, p)
        ) / eps
        assert slope == pytest.approx(P.area_gradient, rel=1e-4)
    assert electrohydraulic_metering_area(xo, p) == 0.0
    # Pilot supply limits the pilot pressure.
    capped = dataclasses.replace(P, pilot_pressure_max=1e6)
    assert electrohydraulic_pilot_setpoint(-1.0, capped.to_array()) == -1e6


def test_kernel_matches_solve_ivp_reference():
    t = np.arange(80) * TS  # 4 s, the first 0.25 s is the input delay
    current = 0.6 * np.sin(2 * np.pi * 0.4 * t) + 0.27 * np.sin(2 * np.pi * 1.3 * t + 1.0)
    x0 = electrohydraulic_equilibrium()
    fast = electrohydraulic_integrate(x0, P.to_array(), current, TS / 50, 50)
    slow = ref_simulate(current, x0)
    assert np.ptp(fast[:, 0]) > 0.05  # the arm really moved
    assert fast[:, 2:4].min() > 1e5  # no clipping, which the twin does not model
    assert np.abs(fast[:, 4]).max() < P.spool_max  # no end cap either
    assert np.sum(np.diff(np.sign(slow[:, 4])) != 0) >= 4  # the spool passed neutral
    for i in range(6):
        scale = np.ptp(slow[:, i])
        # The spool's seat at neutral is a projection (first order in the step, inside
        # the overlap where it changes no flow); everything else agrees to 1e-5.
        tol = 1e-3 if i == 4 else 1e-5
        assert np.abs(fast[:, i] - slow[:, i]).max() < tol * scale, i
