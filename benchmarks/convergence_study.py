"""When do the papers' recursive algorithms converge?  The study behind docs/convergence.md.

Usage::

    python benchmarks/convergence_study.py            # full study (~5 min on 2 cores),
                                                      # writes docs/convergence.md tables
                                                      # and docs/figures/convergence/*.png
    python benchmarks/convergence_study.py --quick    # 2 seeds, fewer cells (< 1 min);
                                                      # prints the tables, writes no docs
    options: --jobs N (worker processes, default 2), --seeds N, --no-write

Three studies, each a list of *cells* (one combination of factors) run on several seeds:

* paper B's key-term RLS with internal-variable estimation (B4, B5),
  :func:`blockid.fitting.fit_key_term_rls`, on simulated Hammerstein-Wiener, Hammerstein
  and Wiener plants with paper B's orders (na = 3, nb = 3, nk = 8, r1 = r2 = 3);
* paper A's AW-RLS for the backlash model (A6-A8),
  :func:`blockid.fitting.fit_backlash_aw_rls`, on paper A's choke finger S2;
* paper A's hierarchical RLS (A10), ``fit_arx(method="hierarchical-rls")``, on a
  two-input two-output ARX of paper A's flow-field orders.

For every (cell, seed) the paper's method and blockid's default for that structure
(free-run simulation error, :func:`blockid.fitting.fit_simulation_error`; batch least
squares for ARX) are run on the same record and each outcome is put in one category:

* ``converged``: a model is returned and its parameter error is below ``THRESHOLD``;
* ``returned, err >= 5 %``: a model is returned (it passed blockid's checks) but its
  parameters are further off;
* ``rejected``: the recursion ran to the end but blockid's result checks refused the
  estimate (free-run worse than a linear ARX, a backlash with negative slope or dead
  band, a branch never driven);
* ``not converged``: the passes did not settle (key-term), or the one-step error stayed
  far above the least-squares optimum (H-RLS);
* ``diverged``: a non-finite or indefinite RLS step, an exploding internal signal, or an
  unstable linear block.

Parameter error: key-term and H-RLS ``||theta_hat - theta|| / ||theta||`` over the
identifiable parameters; AW-RLS the largest relative error of the four backlash
parameters ``m_L, c_L, m_R, c_R``. Returned models are also simulated free-run on a
fresh, noise-free validation record of the same kind (NRMSE fit %).

Seeds are fixed: record ``s`` of every cell with the same input kind uses the same input
and the same noise sequence (scaled to the cell's SNR), so cells differ only in the
factor that changes.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import re
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import blockid.fitting.backlash as _aw_module
import blockid.fitting.key_term as _kt_module
from blockid.blocks import Backlash, Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.errors import EstimationError
from blockid.fitting import (
    fit_arx,
    fit_backlash_aw_rls,
    fit_key_term_rls,
    fit_simulation_error,
)
from blockid.models import ARX, BacklashModel, Hammerstein, HammersteinWiener, Wiener
from blockid.plants.windtunnel import windtunnel_experiment

__all__ = [
    "CATEGORIES",
    "THRESHOLD",
    "KT_PLANTS",
    "kt_plant",
    "kt_signal",
    "kt_record",
    "b4_order",
    "aw_plant",
    "aw_signal",
    "aw_record",
    "tito_plant",
    "tito_record",
    "classify",
    "relative_error",
    "main",
]

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "convergence.md"
FIGURES = ROOT / "docs" / "figures" / "convergence"

#: A returned model counts as converged when its parameter error is below this.
THRESHOLD = 0.05
#: Outcome categories, in table order.
CATEGORIES = ("converged", "returned, err >= 5 %", "rejected", "not converged", "diverged")
COLOURS = {
    "converged": "#2b8a3e",
    "returned, err >= 5 %": "#f2c14e",
    "rejected": "#e07b39",
    "not converged": "#c0392b",
    "diverged": "#5b2c6f",
}


# ============================================================================ outcomes
def classify(error: EstimationError | None, err: float | None) -> str:
    """Category of one fit: the exception it raised (or None) and its parameter error."""
    if error is None:
        return "converged" if err is not None and err < THRESHOLD else "returned, err >= 5 %"
    msg = str(error)
    pole = re.search(r"largest pole magnitude ([0-9.eE+-]+)", msg)
    if "did not converge to a useful model" in msg or re.search(
        r"backlash slopes|negative dead-band|drove along its", msg
    ):
        return "rejected"
    if pole and float(pole.group(1)) < 1.0:  # stable, but too close to the unit circle
        return "rejected"
    if re.search(r"did not converge in \d+ passes|did not converge: its one-step", msg):
        return "not converged"
    if re.search(r"diverged|unstable|explodes|not finite", msg):
        return "diverged"
    raise RuntimeError(f"unclassified failure: {msg}")  # a new message: extend the rules


def relative_error(estimate: np.ndarray, truth: np.ndarray) -> float:
    """``||estimate - truth|| / ||truth||``."""
    return float(np.linalg.norm(estimate - truth) / np.linalg.norm(truth))


def fit_percent(y: np.ndarray, y_sim: np.ndarray) -> float:
    """Free-run NRMSE fit % over all columns (100 is perfect)."""
    y, y_sim = np.asarray(y, float), np.asarray(y_sim, float)
    den = np.linalg.norm(y - y.mean(axis=0))
    if not np.all(np.isfinite(y_sim)):
        return -np.inf
    return float(100.0 * (1.0 - np.linalg.norm(y - y_sim) / den))


def add_noise(y: np.ndarray, snr_db: float | None, rng: np.random.Generator) -> np.ndarray:
    """White output noise at ``snr_db`` (std ratio), per column; None: noise-free.

    The normal draws are taken whatever the SNR, so records of one seed share them.
    """
    e = rng.standard_normal(y.shape)
    if snr_db is None:
        return y
    return y + e * np.std(y, axis=0) * 10 ** (-snr_db / 20)


def _rngs(seed: int, tag: int) -> tuple[np.random.Generator, ...]:
    """Independent generators for (estimation record, validation record, start)."""
    return tuple(np.random.default_rng([seed, tag, k]) for k in range(3))


# ============================================================================ key-term
B_KT = [1.0, 0.5, 0.2]  # b_0 = 1 (normalisation of B2), b_1, b_2
#: Linear-block poles of the key-term plants (paper B's orders: na = 3).
KT_PLANTS: dict[str, list[complex]] = {
    "fast": [0.7, 0.5, -0.3],
    "medium": [0.8, 0.6, -0.3],
    "resonant": [0.9 * np.exp(0.8j), 0.9 * np.exp(-0.8j), 0.2],
    "slow resonant": [0.85 * np.exp(0.5j), 0.85 * np.exp(-0.5j), 0.3],
    "slow": [0.9, 0.8, 0.5],
}
KT_ORDERS = dict(na=3, nb=3, nk=8)
N_KT = 4000


def kt_plant(structure: str = "hammerstein-wiener", speed: str = "fast", nl: float = 1.0):
    """Paper B-like plant: two-segment cubic N1 (B1), ARX L (B2), cubic N2 (B3).

    ``nl`` scales the quadratic and cubic coefficients of both static blocks.
    """
    a = np.real(np.poly(KT_PLANTS[speed]))[1:]
    n1 = TwoSegmentPolynomial.from_segments(
        positive=[0.0, 0.3, 0.1 * nl, -0.05 * nl], negative=[0.0, 0.15, -0.05 * nl, 0.03 * nl]
    )
    n2 = Polynomial([1.0, 0.2 * nl, 0.05 * nl], constant=False)
    kw = dict(a=a, b=B_KT, **KT_ORDERS)
    if structure == "hammerstein-wiener":
        return HammersteinWiener("u", "y", input_block=n1, output_block=n2, **kw)
    if structure == "hammerstein":
        return Hammerstein("u", "y", input_block=n1, **kw)
    return Wiener("u", "y", output_block=n2, **kw)


def kt_signal(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Key-term inputs, all within [-1, 1]: ``white`` (uniform, a new value every
    sample), ``multisine`` (paper B: 0.05, 0.1, 0.2, 0.4, 0.5 Hz at 20 Hz, random
    phases, peak 1), ``held10`` (a uniform random level held 10 samples = 0.5 s)."""
    if kind == "white":
        return rng.uniform(-1.0, 1.0, n)
    if kind == "multisine":
        t = np.arange(n) / 20.0
        u = sum(
            np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
            for f in (0.05, 0.1, 0.2, 0.4, 0.5)
        )
        return u / np.max(np.abs(u))
    if kind.startswith("held"):
        hold = int(kind[4:])
        return np.repeat(rng.uniform(-1.0, 1.0, n // hold + 1), hold)[:n]
    raise ValueError(kind)


def b4_order(model: Any) -> np.ndarray:
    """The model's parameters in the order of key-term RLS's theta (B4): input block,
    ``b`` (free ones), ``a``, ``q_2..`` (``free_parameters`` has ``a`` before ``b``)."""
    v = model.free_parameters()
    n_in = 0 if model.input_block is None else model.input_block.to_vector().size
    n_b = model.nb - 1 if model.fixed_b0 else model.nb
    na = model.na
    return np.concatenate(
        [v[:n_in], v[n_in + na : n_in + na + n_b], v[n_in : n_in + na], v[n_in + na + n_b :]]
    )


def kt_record(cell: dict, seed: int):
    """(plant, estimation Dataset, validation (u, y_true), initial_parameters)."""
    plant = kt_plant(cell["structure"], cell["plant"], cell["nl"])
    r_est, r_val, r_init = _rngs(seed, 1)
    u = kt_signal(cell["input"], N_KT, r_est)
    y = add_noise(plant.simulate(u)[:, 0], cell["noise"], r_est)
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"], sampling_time=0.05)
    u_val = kt_signal(cell["input"], N_KT // 2, r_val)
    y_val = plant.simulate(u_val)[:, 0]
    init: Any = 0.01
    if cell["init"] != "paper":
        spread = {"truth ±5 %": 0.05, "truth ±0.1 %": 0.001, "truth": 0.0}[cell["init"]]
        truth = b4_order(plant)
        init = truth * (1.0 + spread * r_init.uniform(-1.0, 1.0, truth.size))
    return plant, data, (u_val, y_val), init


def kt_trial(cell: dict, seed: int) -> dict:
    plant, data, (u_val, y_val), init = kt_record(cell, seed)
    truth = plant.free_parameters()
    out = {}
    t0 = time.perf_counter()
    try:
        fit = fit_key_term_rls(
            data,
            cell["structure"],
            initial_parameters=init,
            forgetting=cell["forgetting"],
            **KT_ORDERS,
        )
        out["paper"] = _returned(fit.model, truth, u_val, y_val)
        out["paper"]["passes"] = fit.settings["passes_run"]
    except EstimationError as exc:
        out["paper"] = _failed(exc)
    out["paper"]["seconds"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    try:
        fit = fit_simulation_error(data, cell["structure"], r1=3, r2=3, **KT_ORDERS)
        out["default"] = _returned(fit.model, truth, u_val, y_val)
    except EstimationError as exc:
        out["default"] = _failed(exc)
    out["default"]["seconds"] = time.perf_counter() - t0
    return out


def _returned(model: Any, truth: np.ndarray, u_val, y_val, err: float | None = None) -> dict:
    if err is None:
        err = relative_error(model.free_parameters(), truth)
    y_sim = model.simulate(u_val, y_val[: model.max_lag])
    if y_sim.ndim == 2 and np.ndim(y_val) == 1:
        y_sim = y_sim[:, 0]
    return {"category": classify(None, err), "err": err, "fit": fit_percent(y_val, y_sim)}


def _failed(exc: EstimationError) -> dict:
    return {"category": classify(exc, None), "err": None, "fit": None, "message": str(exc)}


# ============================================================================ AW-RLS
AW_PLANTS = {"paper S2": [-1.0, 0.17], "slow": [-1.85, 0.855]}  # poles 0.78/0.22, 0.95/0.9
N_AW = 4000


def aw_plant(speed: str = "paper S2", band: float = 1.0) -> BacklashModel:
    """Paper A's choke finger (A3, A5; sign-corrected ``a``); ``band`` scales c_L, c_R."""
    block = Backlash(0.9, 0.8 * band, 0.9, 0.85 * band)
    return BacklashModel("u2", "v2", input_block=block, na=2, nb=1, nk=1, a=AW_PLANTS[speed])


def aw_signal(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Backlash commands, about ±5 (six dead bands of paper A's S2):
    ``every sample`` (uniform, new level every sample), ``heldH`` (uniform level held H
    samples), ``sine T`` (sinusoid, period T samples, random phase), ``slow multisine``
    (periods 500, 170, 77 samples), ``wind tunnel`` (the choke-finger command of
    :func:`blockid.plants.windtunnel.windtunnel_experiment`: levels held 1-4 s, plus
    dither, around the 110 kPa operating point)."""
    if kind == "every sample":
        return rng.uniform(-5.0, 5.0, n)
    if kind.startswith("held"):
        hold = int(kind[4:])
        return np.repeat(rng.uniform(-5.0, 5.0, n // hold + 1), hold)[:n]
    if kind.startswith("sine"):
        period = float(kind.split()[1])
        return 5.0 * np.sin(2 * np.pi * np.arange(n) / period + rng.uniform(0, 2 * np.pi))
    if kind == "slow multisine":
        t = np.arange(n)
        ph = rng.uniform(0, 2 * np.pi, 3)
        return (
            3.0 * np.sin(2 * np.pi * t / 500 + ph[0])
            + 1.5 * np.sin(2 * np.pi * t / 170 + ph[1])
            + 0.75 * np.sin(2 * np.pi * t / 77 + ph[2])
        )
    raise ValueError(kind)


def aw_record(cell: dict, seed: int):
    """(plant, estimation Dataset, validation (u, v_true), initial_parameters)."""
    plant = aw_plant(cell["plant"], cell["band"])
    r_est, r_val, r_init = _rngs(seed, 2)
    if cell["input"] == "wind tunnel":
        # the simulated tunnel's own S2 (same parameters), started at its operating point
        est = windtunnel_experiment(n_samples=N_AW, seed=seed, noise=False)
        val = windtunnel_experiment(n_samples=N_AW // 2, seed=seed, kind="validation", noise=False)
        u, v = est["u2"].to_numpy(), est["v2"].to_numpy()
        u_val, v_val = val["u2"].to_numpy(), val["v2"].to_numpy()
    else:
        u = aw_signal(cell["input"], N_AW, r_est)
        v = plant.simulate(u)[:, 0]
        u_val = aw_signal(cell["input"], N_AW // 2, r_val)
        v_val = plant.simulate(u_val)[:, 0]
    v = add_noise(v, cell["noise"], r_est)
    data = Dataset.from_arrays(u, v, inputs=["u2"], outputs=["v2"], sampling_time=0.05)
    init: Any = 0.01
    if cell["init"] != "paper":
        truth = np.concatenate([plant.input_block.to_theta(), plant.a])
        init = truth * (1.0 + 0.05 * r_init.uniform(-1.0, 1.0, truth.size))
    return plant, data, (u_val, v_val), init


def backlash_error(model: BacklashModel, plant: BacklashModel) -> float:
    """Largest relative error of ``m_L, c_L, m_R, c_R``."""
    got, true = model.input_block.to_vector(), plant.input_block.to_vector()
    return float(np.max(np.abs(got - true) / np.abs(true)))


def aw_trial(cell: dict, seed: int) -> dict:
    plant, data, (u_val, v_val), init = aw_record(cell, seed)
    out = {}
    for key in ("paper", "default"):
        t0 = time.perf_counter()
        try:
            if key == "paper":
                fit = fit_backlash_aw_rls(
                    data, initial_parameters=init, eps1=cell["eps1"], passes=cell["passes"]
                )
            else:
                fit = fit_simulation_error(data, "backlash", na=2, nb=1, nk=1)
            err = backlash_error(fit.model, plant)
            out[key] = _returned(fit.model, None, u_val, v_val, err=err)
        except EstimationError as exc:
            out[key] = _failed(exc)
        out[key]["seconds"] = time.perf_counter() - t0
    return out


# ============================================================================ H-RLS
N_HRLS = 20_000


def tito_plant() -> ARX:
    """Two-input two-output ARX with paper A's flow-field orders (na = 2 own and cross
    output lags, nb = 2 per input, nk = 1); poles 0.5 ± 0.39j, 0.45 ± 0.2j."""
    return ARX(
        ["v1", "v2"],
        ["y1", "y2"],
        na=2,
        nb=2,
        nk=1,
        a={
            "y1": {"y1": [-1.2, 0.4], "y2": [0.1, 0.0]},
            "y2": {"y1": [0.05, 0.02], "y2": [-0.9, 0.2]},
        },
        b={
            "y1": {"v1": [0.5, 0.2], "v2": [0.1, -0.05]},
            "y2": {"v1": [0.0, 0.03], "v2": [0.4, 0.1]},
        },
    )


def tito_signal(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Two inputs: ``white`` (Gaussian), ``held10`` (Gaussian levels held 10 samples)."""
    if kind == "white":
        return rng.standard_normal((n, 2))
    if kind.startswith("held"):
        hold = int(kind[4:])
        return np.repeat(rng.standard_normal((n // hold + 1, 2)), hold, axis=0)[:n]
    raise ValueError(kind)


def tito_record(cell: dict, seed: int):
    plant = tito_plant()
    r_est, r_val, _ = _rngs(seed, 3)
    n = cell.get("samples", N_HRLS)
    u = tito_signal(cell["input"], n, r_est)
    y = add_noise(plant.simulate(u), cell["noise"], r_est)
    data = Dataset.from_arrays(u, y, inputs=["v1", "v2"], outputs=["y1", "y2"])
    u_val = tito_signal(cell["input"], 2000, r_val)
    return plant, data, (u_val, plant.simulate(u_val))


def _arx_vector(model: ARX) -> np.ndarray:
    return np.concatenate([model.parameter_vector(i) for i in range(len(model.outputs))])


def hrls_trial(cell: dict, seed: int) -> dict:
    plant, data, (u_val, y_val) = tito_record(cell, seed)
    truth = _arx_vector(plant)
    out = {}
    for key in ("paper", "default"):
        t0 = time.perf_counter()
        kw = (
            dict(method="hierarchical-rls", forgetting=cell["forgetting"])
            if key == "paper"
            else dict(method="batch")
        )
        try:
            model = fit_arx(data, 2, 2, 1, **kw).model
            err = relative_error(_arx_vector(model), truth)
            out[key] = {
                "category": classify(None, err),
                "err": err,
                "fit": fit_percent(y_val, model.simulate(u_val, y_val[:2])),
            }
        except EstimationError as exc:
            out[key] = _failed(exc)
            if key == "paper":  # the estimate the convergence check refused
                model = fit_arx(data, 2, 2, 1, max_mse_ratio=None, allow_unstable=True, **kw).model
                out[key]["err_rejected"] = relative_error(_arx_vector(model), truth)
        out[key]["seconds"] = time.perf_counter() - t0
    return out


def kt_plant_table() -> str:
    """Markdown table of the key-term plants' linear blocks: poles, static gain, and the
    passivity margin ``min_w Re(1/A(e^jw)) - 1/2`` (the sufficient convergence condition
    of the related output-error pseudo-linear regression needs it > 0)."""
    w = np.linspace(0.0, np.pi, 20_001)
    lines = [
        "| plant | poles | 1/A(1) | min Re 1/A(e^jω) − 1/2 (at ω) |",
        "|---|---|---|---|",
    ]
    for name, poles in KT_PLANTS.items():
        A = np.real(np.poly(poles))
        # A(z^-1) = 1 + a_1 z^-1 + .. evaluated at z^-1 = e^-jw
        margin = np.real(1.0 / np.polyval(A[::-1], np.exp(-1j * w))) - 0.5
        k = int(np.argmin(margin))
        shown = ", ".join(
            f"{abs(p):.2g}∠±{abs(np.angle(p)):.2g}"
            if abs(np.imag(p)) > 1e-12
            else f"{np.real(p):.2g}"
            for p in poles
            if np.imag(p) >= 0
        )
        lines.append(f"| {name} | {shown} | {1.0 / A.sum():.1f} | {margin[k]:.3f} ({w[k]:.2f}) |")
    return "\n".join(lines)


def hrls_coupling(kind: str, seed: int = 0) -> list[float]:
    """Smallest eigenvalue ``mu`` of ``blockdiag(R)^-1 R`` per output, ``R = Phi' Phi``
    on a noise-free record (groups: paper A's output lags | input lags). With
    ``lambda = 1`` H-RLS's coupling error decays like ``t^-mu``
    (:mod:`blockid.estimators.hierarchical`); the value is invariant to column scaling."""
    plant, data, _ = tito_record({**HRLS_BASE, "input": kind}, seed)
    e = data.experiments[0]
    out = []
    for i in range(len(plant.outputs)):
        Phi, _ = plant.regressors(e.u, e.y, i)
        R = Phi.T @ Phi
        D = np.zeros_like(R)
        for g in plant.hierarchical_groups(i):
            D[np.ix_(g, g)] = R[np.ix_(g, g)]
        out.append(float(np.min(np.real(np.linalg.eigvals(np.linalg.solve(D, R))))))
    return out


# ============================================================================ cells
@dataclass
class Group:
    """Cells of one table: ``vary`` are the factor columns, ``fixed`` the rest."""

    study: str
    key: str
    title: str
    vary: tuple[str, ...]
    cells: list[dict] = field(default_factory=list)


KT_BASE = dict(
    structure="hammerstein-wiener",
    plant="fast",
    input="white",
    noise=None,
    init="paper",
    nl=1.0,
    forgetting="0.98:200,1",
)
AW_BASE = dict(
    plant="paper S2", input="every sample", noise=None, init="paper", eps1=10.0, band=1.0, passes=1
)
HRLS_BASE = dict(input="white", noise=None, forgetting=1.0, samples=N_HRLS)


def _cells(base: dict, *changes: dict) -> list[dict]:
    return [{**base, **c} for c in changes]


def groups(quick: bool) -> list[Group]:
    """Every table of the study (``quick``: a subset of the cells)."""
    kt_plants = ["fast", "slow"] if quick else list(KT_PLANTS)
    kt_inputs = ["white", "multisine"] if quick else ["white", "multisine", "held10"]
    snrs = [None, 40.0] if quick else [None, 40.0, 20.0]
    forgetting = ["0.98:200,1", "0.999"] if quick else ["0.98:200,1", "1", "0.98", "0.995", "0.999"]
    kt = [
        Group(
            "key-term",
            "kt-excitation",
            "Key-term RLS, Hammerstein-Wiener: excitation × plant (noise-free, θ(0) = 0.01, "
            "paper's forgetting)",
            ("input", "plant"),
            _cells(KT_BASE, *({"input": i, "plant": p} for i in kt_inputs for p in kt_plants)),
        ),
        Group(
            "key-term",
            "kt-forgetting",
            "Key-term RLS, Hammerstein-Wiener: forgetting × plant (noise-free, θ(0) = 0.01)",
            ("input", "plant", "forgetting"),
            _cells(
                KT_BASE,
                *(
                    {"plant": p, "forgetting": f}
                    for p in (kt_plants if quick else ["fast", "medium", "slow resonant", "slow"])
                    for f in forgetting
                ),
            )
            + _cells(KT_BASE, *({"input": i, "forgetting": "0.999"} for i in kt_inputs[1:])),
        ),
        Group(
            "key-term",
            "kt-noise-init",
            "Key-term RLS, Hammerstein-Wiener: noise × initialisation (paper's forgetting)",
            ("input", "plant", "noise", "init"),
            _cells(
                KT_BASE, *({"noise": s, "init": i} for s in snrs for i in ("paper", "truth ±5 %"))
            )
            + _cells(
                KT_BASE,
                {"input": "multisine", "init": "truth ±5 %"},
                {"plant": "slow", "init": "truth ±5 %"},
                {"plant": "slow", "init": "truth ±0.1 %"},
                {"plant": "slow", "init": "truth"},
                {"plant": "slow resonant", "init": "truth ±0.1 %"},
                {"plant": "slow resonant", "init": "truth"},
                {"init": "truth"},
            )[: 2 if quick else 7],
        ),
        Group(
            "key-term",
            "kt-nonlinearity",
            "Key-term RLS, Hammerstein-Wiener: nonlinearity strength (quadratic and cubic "
            "coefficients of N1 and N2 scaled; white input, noise-free, θ(0) = 0.01)",
            ("plant", "nl"),
            _cells(
                KT_BASE,
                *({"plant": p, "nl": x} for p in ("fast", "resonant") for x in (0.25, 1.0, 3.0)),
            )[: 3 if quick else 6],
        ),
        Group(
            "key-term",
            "kt-structures",
            "Key-term RLS, the comparison structures (θ(0) = 0.01, paper's forgetting)",
            ("structure", "input", "plant", "noise"),
            _cells(
                KT_BASE,
                *(
                    {"structure": s, **c}
                    for s in ("hammerstein", "wiener")
                    for c in ({}, {"noise": 40.0}, {"input": "multisine"}, {"plant": "slow"})
                ),
            ),
        ),
    ]
    aw_inputs = ["every sample", "held5", "wind tunnel"]
    if not quick:
        aw_inputs[1:2] = ["held2", "held5", "held20", "sine 50", "sine 200", "slow multisine"]
    near = {"init": "truth ±5 %"}
    aw = [
        Group(
            "aw-rls",
            "aw-excitation",
            "AW-RLS, backlash (paper A's S2): command × noise (θ(0) = 0.01, ε1 = 10, one pass)",
            ("input", "noise"),
            _cells(AW_BASE, *({"input": i, "noise": s} for i in aw_inputs for s in (None, 40.0))),
        ),
        Group(
            "aw-rls",
            "aw-other",
            "AW-RLS, backlash: noise, initialisation, passes, ε1, dead-band width, plant speed",
            ("input", "noise", "init", "passes", "eps1", "band", "plant"),
            _cells(
                AW_BASE,
                {"noise": 20.0},
                {**near},
                {**near, "noise": 40.0},
                {**near, "input": "held5"},
                {**near, "input": "held20"},
                {**near, "input": "sine 200"},
                {**near, "input": "slow multisine"},
                {**near, "input": "wind tunnel"},
                {"input": "held5", "passes": 5},
                {"input": "wind tunnel", "passes": 5},
                {"eps1": 1.0},
                {"eps1": 1.0, "noise": 40.0},
                {"eps1": 100.0},
                {"eps1": 100.0, "noise": 40.0},
                {"band": 0.25, "noise": 40.0},
                {"band": 3.0, "noise": 40.0},
                {"plant": "slow", "noise": 40.0},
                {"plant": "slow", "input": "held5"},
            )[: 4 if quick else None],
        ),
    ]
    h_forgetting = [1.0, 0.95] if quick else [1.0, 0.999, 0.99, 0.95]
    hrls = [
        Group(
            "h-rls",
            "hrls",
            "H-RLS, two-input two-output ARX (paper A's split: output lags | input lags)",
            ("input", "samples", "noise", "forgetting"),
            _cells(HRLS_BASE, *({"noise": s, "forgetting": f} for s in snrs for f in h_forgetting))
            + _cells(
                HRLS_BASE,
                {"samples": 2000},
                {"samples": 2000, "forgetting": 0.95},
                {"input": "held10"},
                {"input": "held10", "forgetting": 0.95},
            )[: 1 if quick else 4],
        )
    ]
    return kt + aw + hrls


TRIALS = {"key-term": kt_trial, "aw-rls": aw_trial, "h-rls": hrls_trial}


def _run_one(job: tuple[str, dict, int]) -> dict:
    study, cell, seed = job
    return TRIALS[study](cell, seed)


# ============================================================================ tables
def _fmt_factor(name: str, value: Any) -> str:
    if name == "noise":
        return "noise-free" if value is None else f"{value:g} dB"
    if name in ("nl", "band"):
        return f"×{value:g}"
    if name == "forgetting":
        return "0.98:200,1 (paper)" if value == "0.98:200,1" else f"λ = {float(value):g}"
    if name == "structure":
        return {"hammerstein-wiener": "H-W"}.get(value, value.capitalize())
    if name == "samples":
        return f"{value:,}"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _median(values: list[float | None], fmt: str) -> str:
    vals = [v for v in values if v is not None and np.isfinite(v)]
    return format(float(np.median(vals)), fmt) if vals else "–"


def _paper_err(paper: list[dict]) -> str:
    """Median error of the returned models; for H-RLS also of the refused estimates."""
    text = _median([p["err"] for p in paper], ".1e")
    refused = [p["err_rejected"] for p in paper if "err_rejected" in p]
    if refused:
        text += f" (refused: {_median(refused, '.1e')})"
    return text


def _fits(values: list[float | None]) -> str:
    """Median (worst) validation fit % of the returned models."""
    vals = [v for v in values if v is not None]
    if not vals:
        return "–"
    worst = min(vals)
    worst_txt = f"{worst:.1f}" if np.isfinite(worst) else "−∞"
    return f"{float(np.median(vals)):.1f} ({worst_txt})"


def _counts(results: list[dict]) -> str:
    c = Counter(r["category"] for r in results)
    return " / ".join(str(c.get(k, 0)) for k in CATEGORIES)


def table(group: Group, results: list[list[dict]]) -> str:
    """Markdown table of one group; ``results[i]`` are the seeds of ``group.cells[i]``."""
    head = [_header(v) for v in group.vary] + [
        "seeds",
        "paper's method: conv. / ret. ≥5 % / rej. / n.c. / div.",
        "median err",
        "val. fit % (worst)",
        "default: conv. / ret. ≥5 % / failed",
        "median err",
        "val. fit % (worst)",
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for cell, res in zip(group.cells, results, strict=True):
        paper = [r["paper"] for r in res]
        default = [r["default"] for r in res]
        dc = Counter(d["category"] for d in default)
        failed = sum(v for k, v in dc.items() if k not in CATEGORIES[:2])
        row = [_fmt_factor(v, cell[v]) for v in group.vary] + [
            str(len(res)),
            _counts(paper),
            _paper_err(paper),
            _fits([p["fit"] for p in paper]),
            f"{dc.get(CATEGORIES[0], 0)} / {dc.get(CATEGORIES[1], 0)} / {failed}",
            _median([d["err"] for d in default], ".1e"),
            _fits([d["fit"] for d in default]),
        ]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def _header(name: str) -> str:
    return {"nl": "nonlinearity", "band": "dead band", "eps1": "ε1", "init": "θ(0)"}.get(name, name)


#: Headline cells: (label, group key, factor values); :func:`summary` reports them.
HEADLINES = [
    (
        "key-term H-W, fast plant, white, noise-free",
        "kt-excitation",
        {"input": "white", "plant": "fast"},
    ),
    (
        "key-term H-W, medium plant, white, noise-free",
        "kt-excitation",
        {"input": "white", "plant": "medium"},
    ),
    (
        "key-term H-W, slow plant, white, noise-free",
        "kt-excitation",
        {"input": "white", "plant": "slow"},
    ),
    (
        "key-term H-W, fast plant, paper B's multisine, noise-free",
        "kt-excitation",
        {"input": "multisine", "plant": "fast"},
    ),
    (
        "key-term H-W, slow plant, paper B's multisine, noise-free",
        "kt-excitation",
        {"input": "multisine", "plant": "slow"},
    ),
    (
        "key-term H-W, fast plant, held levels, noise-free",
        "kt-excitation",
        {"input": "held10", "plant": "fast"},
    ),
    (
        "key-term H-W, medium plant, white, λ = 0.999",
        "kt-forgetting",
        {"plant": "medium", "forgetting": "0.999"},
    ),
    (
        "key-term H-W, fast plant, white, λ = 1 (no restart)",
        "kt-forgetting",
        {"plant": "fast", "forgetting": "1"},
    ),
    ("key-term H-W, fast plant, white, 40 dB", "kt-noise-init", {"noise": 40.0, "init": "paper"}),
    (
        "key-term H-W, slow plant, started exactly at the truth",
        "kt-noise-init",
        {"plant": "slow", "init": "truth"},
    ),
    (
        "key-term Hammerstein, fast plant, white, 40 dB",
        "kt-structures",
        {"structure": "hammerstein", "noise": 40.0},
    ),
    (
        "key-term Hammerstein, fast plant, multisine, noise-free",
        "kt-structures",
        {"structure": "hammerstein", "input": "multisine"},
    ),
    (
        "key-term Wiener, fast plant, multisine, noise-free",
        "kt-structures",
        {"structure": "wiener", "input": "multisine"},
    ),
    (
        "AW-RLS, command changing every sample, 40 dB",
        "aw-excitation",
        {"input": "every sample", "noise": 40.0},
    ),
    (
        "AW-RLS, levels held 5 samples, noise-free",
        "aw-excitation",
        {"input": "held5", "noise": None},
    ),
    (
        "AW-RLS, wind-tunnel commands, noise-free",
        "aw-excitation",
        {"input": "wind tunnel", "noise": None},
    ),
    (
        "AW-RLS, levels held 5 samples, θ(0) = truth ±5 %",
        "aw-other",
        {"input": "held5", "init": "truth ±5 %"},
    ),
    ("AW-RLS, slow plant, every sample, 40 dB", "aw-other", {"plant": "slow", "noise": 40.0}),
    (
        "H-RLS, λ = 1, 20 000 noise-free samples",
        "hrls",
        {"noise": None, "forgetting": 1.0, "input": "white", "samples": N_HRLS},
    ),
    (
        "H-RLS, λ = 0.99, 20 000 noise-free samples",
        "hrls",
        {"noise": None, "forgetting": 0.99, "input": "white", "samples": N_HRLS},
    ),
    (
        "H-RLS, λ = 0.95, 20 000 noise-free samples",
        "hrls",
        {"noise": None, "forgetting": 0.95, "input": "white", "samples": N_HRLS},
    ),
    (
        "H-RLS, λ = 0.95, 20 000 samples, 40 dB",
        "hrls",
        {"noise": 40.0, "forgetting": 0.95, "input": "white", "samples": N_HRLS},
    ),
]


def _describe(res: list[dict], who: str) -> str:
    """``conv. 8/10 (err ≤ 1e-07), ...`` for one method over the seeds of one cell."""
    n = len(res)
    c = Counter(r[who]["category"] for r in res)
    parts = []
    for cat in CATEGORIES:
        if c.get(cat):
            errs = [r[who]["err"] for r in res if r[who]["category"] == cat]
            tail = f" (err ≤ {max(errs):.1g})" if cat in CATEGORIES[:2] else ""
            parts.append(f"{cat} {c[cat]}/{n}{tail}")
    fits = [r[who]["fit"] for r in res if r[who]["fit"] is not None]
    if fits and min(fits) < 95.0:
        parts.append(f"validation fit < 95 % on {sum(f < 95.0 for f in fits)}/{n}")
    return ", ".join(parts)


def summary(all_groups: list[Group], results: dict[str, list[list[dict]]]) -> str:
    """The headline cells, computed: the paper's method, then the default."""
    by_key = {g.key: g for g in all_groups}
    lines = []
    for label, key, match in HEADLINES:
        g = by_key.get(key)
        found = (
            [
                res
                for cell, res in zip(g.cells, results[key], strict=True)
                if all(cell[k] == v for k, v in match.items())
            ]
            if g
            else []
        )
        if not found:  # not in a --quick run
            continue
        res = found[0]
        lines.append(
            f"- **{label}**: paper's method: {_describe(res, 'paper')}; "
            f"default: {_describe(res, 'default')}."
        )
    return "\n".join(lines)


# ============================================================================ figures
def recorded_history(call) -> tuple[Any, np.ndarray, np.ndarray, Exception | None]:
    """Run a recursive fit with ``record_history=True``: the result (or None), the rows of
    ``theta`` in the data's units, their update counts, and the error of a refused fit
    (which carries what it recorded up to the failure)."""
    try:
        fit = call(record_history=True)
        return fit, np.asarray(fit.history["theta"]), np.asarray(fit.history["update"]), None
    except EstimationError as exc:
        hist = exc.history or {}
        theta = np.asarray(hist.get("theta", np.zeros((0, 0))))
        return None, theta, np.asarray(hist.get("update", np.zeros(0))), exc


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: Per study: the factors every figure label shows, and the base the others differ from.
LABELS = {
    "key-term": (("structure", "input", "plant"), KT_BASE),
    "aw-rls": (("input", "noise"), AW_BASE),
    "h-rls": (("input", "noise", "forgetting"), HRLS_BASE),
}


def _label(study: str, cell: dict) -> str:
    """``white, fast; noise 40 dB`` — the always-shown factors, then those off the base."""
    always, base = LABELS[study]
    head = ", ".join(_fmt_factor(k, cell[k]) for k in always)
    extra = [
        f"{_header(k)} {_fmt_factor(k, v)}"
        for k, v in cell.items()
        if k not in always and v != base.get(k)
    ]
    return "; ".join([head, *extra])


def figure_outcomes(all_groups, results, study: str, path: Path, title: str) -> None:
    """Stacked bars of the outcome counts, paper's method beside the default, per cell."""
    plt = _pyplot()
    rows = []
    for g in all_groups:
        if g.study != study:
            continue
        for cell, res in zip(g.cells, results[g.key], strict=True):
            rows.append((_label(study, cell), res))
    n = len(rows)
    fig, axes = plt.subplots(1, 2, figsize=(12, 0.26 * n + 2.0), sharey=True)
    for ax, who, name in zip(
        axes, ("paper", "default"), ("paper's method", "default method"), strict=True
    ):
        left = np.zeros(n)
        for cat in CATEGORIES:
            counts = np.array([sum(r[who]["category"] == cat for r in res) for _, res in rows])
            ax.barh(np.arange(n), counts, left=left, color=COLOURS[cat], label=cat, height=0.8)
            left += counts
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("records (seeds)")
    axes[0].set_yticks(np.arange(n), [r[0] for r in rows], fontsize=7)
    axes[0].set_ylim(n - 0.5, -0.5)  # first cell on top (shared y axis: set once)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(CATEGORIES), fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 0.98))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_kt_trajectories(path: Path, seed: int) -> dict:
    """Linear-block parameters of key-term RLS over the updates of all passes: fast plant
    with white input (converges), fast plant with paper B's multisine (does not), slow
    plant with white input started 0.1 % from the truth (leaves it)."""
    plt = _pyplot()
    cases = {
        "fast plant, white input": {},
        "fast plant, paper B's multisine": {"input": "multisine"},
        "slow plant, white input, θ(0) = truth ±0.1 %": {"plant": "slow", "init": "truth ±0.1 %"},
    }
    fig, axes = plt.subplots(1, len(cases), figsize=(15, 4.4), sharey=True)
    info = {}
    names = ["b_1", "b_2", "a_1", "a_2", "a_3"]  # unit-free: unchanged by the normalisation
    for ax, (label, change) in zip(axes, cases.items(), strict=True):
        cell = {**KT_BASE, **change}
        plant, data, _, init = kt_record(cell, seed)
        fit, rows, updates, exc = recorded_history(
            lambda d=data, i=init, **kw: fit_key_term_rls(
                d, "hammerstein-wiener", initial_parameters=i, **KT_ORDERS, **kw
            )
        )
        if exc is None:
            outcome = f"converged in {fit.settings['passes_run']} passes"
        else:
            outcome = _short_reason(str(exc))
        hist = rows[:, 8:13]  # B4 order: f (4), p (4), b_1, b_2, a_1..a_3 (unit-free)
        truth = b4_order(plant)[8:13]
        passes = updates / (N_KT - 10)
        for j, name in enumerate(names):
            (line,) = ax.plot(passes, hist[:, j], lw=0.8, label=name)
            ax.axhline(truth[j], color=line.get_color(), ls="--", lw=0.8)
        ax.set_title(f"{label}:\n{outcome}", fontsize=9)
        ax.set_xlabel("passes over the 4000-sample record")
        ax.set_ylim(-3.0, 3.0)
        info[label] = outcome
    axes[0].set_ylabel("estimate (dashed: true value)")
    axes[0].legend(fontsize=8, ncol=5, loc="lower left")
    fig.suptitle(
        f"Key-term RLS (B5), Hammerstein-Wiener, noise-free estimation records (seed {seed}): "
        "linear-block parameters after every update",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return info


def figure_aw_trajectories(path: Path, seed: int) -> dict:
    """Backlash parameters of AW-RLS over the samples: command changing every sample
    (converges) and held 5 samples (stalls), noise-free, paper A's S2."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2), sharey=True)
    info = {}
    true = aw_plant().input_block.to_theta()
    labels = ["m_L", "m_L c_L", "m_R", "m_R c_R"]
    for ax, kind in zip(axes, ("every sample", "held5"), strict=True):
        cell = {**AW_BASE, "input": kind}
        _, data, _, _ = aw_record(cell, seed)
        _, hist, updates, exc = recorded_history(lambda d=data, **kw: fit_backlash_aw_rls(d, **kw))
        outcome = "converged" if exc is None else "refused: " + _short_reason(str(exc))
        for j, name in enumerate(labels):
            (line,) = ax.plot(updates, hist[:, j], lw=0.8, label=name)
            ax.axhline(true[j], color=line.get_color(), ls="--", lw=0.8)
        ax.set_xscale("log")
        ax.set_title(f"command {kind}: {outcome}", fontsize=9)
        ax.set_xlabel("sample (update)")
        ax.set_ylim(-1.5, 2.0)
        info[kind] = outcome
    axes[0].set_ylabel("estimate (dashed: true value)")
    axes[0].legend(fontsize=8, ncol=4, loc="lower left")
    fig.suptitle(
        f"AW-RLS (A8), backlash of paper A's S2, noise-free estimation record (seed {seed}): "
        "trajectories of θ1..θ4",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return info


def _short_reason(msg: str) -> str:
    """The first clause of a failure message, without the method name."""
    for prefix in ("AW-RLS: ", "AW-RLS ", "key-term RLS "):
        msg = msg.removeprefix(prefix)
    return re.split(r" \(|: |; ", msg)[0]


def _aw_data_units(rows: np.ndarray, data: Dataset) -> np.ndarray:
    """AW-RLS rows (centred, normalised signals) back in the data's units."""
    records, u_map, v_map = _kt_module.signals(data, True, center=True)
    return _aw_module._to_data_units(rows, u_map, v_map, 1)


def figure_free_run(path: Path, seed: int) -> dict:
    """Free-run simulation of the default fits on cases where the paper's method fails:
    paper B's H-W on levels held 10 samples and paper A's choke finger on the wind
    tunnel's held commands, both at 40 dB; simulated on a validation record with 40 dB
    noise."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(12, 7.5))
    r_noise = np.random.default_rng([seed, 9])
    cases = [
        (
            "kt",
            {**KT_BASE, "input": "held10", "noise": 40.0},
            kt_record,
            lambda d: fit_key_term_rls(d, "hammerstein-wiener", **KT_ORDERS),
            lambda d: fit_simulation_error(d, "hammerstein-wiener", r1=3, r2=3, **KT_ORDERS),
            "paper B's H-W structure (fast plant), validation record: levels held 0.5 s",
            "key-term RLS",
            "y",
        ),
        (
            "aw",
            {**AW_BASE, "input": "wind tunnel", "noise": 40.0},
            aw_record,
            fit_backlash_aw_rls,
            lambda d: fit_simulation_error(d, "backlash", na=2, nb=1, nk=1),
            "paper A's choke finger S2, validation record: wind-tunnel held commands",
            "AW-RLS",
            "v2 [mm]",
        ),
    ]
    info = {}
    for ax, (key, cell, record, paper, default, what, method, ylabel) in zip(
        axes, cases, strict=True
    ):
        _, data, (u_val, y_val), _ = record(cell, seed)
        y_meas = add_noise(y_val, 40.0, r_noise)
        try:
            paper(data)
            info[key] = f"{method} converged"
        except EstimationError as exc:
            info[key] = f"{method} failed: {_short_reason(str(exc))}"
        model = default(data).model
        y_sim = model.simulate(u_val, y_meas[: model.max_lag])[:, 0]
        info[f"{key}_fit"] = fit_percent(y_meas, y_sim)
        t = np.arange(y_val.size) * 0.05
        ax.plot(t, y_meas, color="0.55", lw=1.6, label="measured (40 dB noise)")
        ax.plot(
            t,
            y_sim,
            color="C0",
            lw=0.8,
            label=f"default fit, free run ({info[f'{key}_fit']:.1f} %)",
        )
        ax.plot(
            t,
            y_meas - y_sim + np.min(y_meas) - 0.1 * np.ptp(y_meas),
            color="C3",
            lw=0.6,
            label="measured − simulated (offset)",
        )
        ax.set_xlabel("time [s]")
        ax.set_ylabel(ylabel)
        ax.set_title(
            f"Free-run simulation, {what}\n({info[key]} on the estimation record)", fontsize=9
        )
        ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return info


# ============================================================================ doc
def write_section(doc: Path, name: str, markdown: str) -> None:
    """Write a generated section of ``doc`` (the shared helper of the benchmarks)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _report import write_section as _write

    _write(name, markdown, doc=doc)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 seeds, fewer cells, no docs")
    parser.add_argument("--seeds", type=int, default=None, help="records per cell (10; quick 2)")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    seeds = args.seeds or (2 if args.quick else 10)
    write = not (args.quick or args.no_write)
    t_start = time.perf_counter()

    all_groups = groups(args.quick)
    jobs = [(g.study, cell, s) for g in all_groups for cell in g.cells for s in range(seeds)]
    # fresh worker processes with one BLAS thread each: the fits are many small solves,
    # and BLAS threads competing for the same cores made the study several times slower
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=args.jobs, mp_context=context) as pool:
        flat = list(pool.map(_run_one, jobs, chunksize=4))
    results: dict[str, list[list[dict]]] = {}
    pos = 0
    for g in all_groups:
        results[g.key] = []
        for _ in g.cells:
            results[g.key].append(flat[pos : pos + seeds])
            pos += seeds

    tables = {g.key: f"**{g.title}**\n\n{table(g, results[g.key])}" for g in all_groups}
    for text in tables.values():
        print(text, "\n")
    numbers = summary(all_groups, results)
    coupling = {kind: max(hrls_coupling(kind)) for kind in ("white", "held10")}
    numbers += (
        "\n- **H-RLS coupling**: smallest eigenvalue μ of blockdiag(R)⁻¹R for paper A's split "
        "(the largest over the two outputs): "
        + "; ".join(
            f"{kind} input μ = {mu:.3f}, so t^-μ at t = 20 000 is {N_HRLS**-mu:.2f}"
            for kind, mu in coupling.items()
        )
        + "."
    )
    print(numbers, "\n")

    fig_dir = FIGURES if write else Path(tempfile.mkdtemp(prefix="convergence-"))
    fig_dir.mkdir(parents=True, exist_ok=True)
    titles = {
        "key-term": "Key-term RLS (paper B) vs simulation error: outcome per record",
        "aw-rls": "AW-RLS (paper A, backlash) vs simulation error: outcome per record",
        "h-rls": "H-RLS (paper A, TITO ARX) vs batch least squares: outcome per record",
    }
    for study, title in titles.items():
        figure_outcomes(all_groups, results, study, fig_dir / f"outcomes_{study}.png", title)
    kt_info = figure_kt_trajectories(fig_dir / "trajectories_key_term.png", seed=0)
    aw_info = figure_aw_trajectories(fig_dir / "trajectories_aw_rls.png", seed=0)
    fr_info = figure_free_run(fig_dir / "free_run_default_vs_paper.png", seed=0)
    print("figures:", fig_dir, kt_info, aw_info, fr_info)

    seconds = time.perf_counter() - t_start
    n_fits = 2 * len(jobs)
    provenance = (
        f"Generated by `python benchmarks/convergence_study.py` ({seeds} seeds per cell, "
        f"{n_fits} fits, {seconds:.0f} s with {args.jobs} worker processes, "
        f"Python {sys.version.split()[0]}, NumPy {np.__version__})."
    )
    print(provenance)
    if write:
        write_section(DOC, "provenance", provenance)
        write_section(DOC, "numbers", numbers)
        write_section(DOC, "table:kt-plants", kt_plant_table())
        for key, text in tables.items():
            write_section(DOC, f"table:{key}", text)
        figure_notes = (
            "- Key-term trajectories (seed 0): "
            + "; ".join(f"{k}: {v}" for k, v in kt_info.items())
            + ".\n"
            f"- AW-RLS trajectories (seed 0): command changing every sample "
            f"{aw_info['every sample']}; held 5 samples {aw_info['held5']}.\n"
            f"- Free run (seed 0): H-W on held levels: {fr_info['kt']}; the default fit "
            f"simulates the validation record with {fr_info['kt_fit']:.1f} % fit. Wind tunnel: "
            f"{fr_info['aw']}; default fit {fr_info['aw_fit']:.1f} %."
        )
        write_section(DOC, "figure-notes", figure_notes)
    return 0


if __name__ == "__main__":
    sys.exit(main())
