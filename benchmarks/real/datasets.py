"""Loaders of the real benchmark data sets in ``../shared/data`` (never copied here).

One function per data set returns a :class:`Benchmark`: the estimation
:class:`~blockid.data.dataset.Dataset`, one or more test records, and the facts of the
set's ``SOURCE.md`` (units, standard split, how many test samples may initialise the
simulation, the published linear baseline and the best published result). The data
folder is ``$BLOCKID_BENCHMARK_DATA`` or ``<repo>/../shared/data``; a loader raises
:class:`MissingData` when its folder is absent, so the runner skips the set cleanly.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from blockid.data.dataset import Dataset, Experiment

REPO = Path(__file__).resolve().parents[2]
DATA = Path(os.environ.get("BLOCKID_BENCHMARK_DATA", REPO.parent / "shared" / "data"))


class MissingData(FileNotFoundError):
    """The data folder of a benchmark is absent."""


@dataclass(frozen=True)
class Reference:
    """A published number (in the benchmark's reporting unit) and where it comes from."""

    value: float
    what: str


@dataclass(frozen=True)
class TestRecord:
    """One test record; ``prefix`` holds the estimation samples that directly precede it
    in the same recording (``None`` for a separate recording).

    ``u`` and ``y`` are 1-D for the single-input single-output sets, and of shape (N, nu)
    and (N, ny) for the multivariable sets of :data:`MIMO` (also with one input or one
    output); ``prefix`` has the same layout."""

    name: str
    u: np.ndarray
    y: np.ndarray
    linear: Reference | None = None
    best: Reference | None = None
    prefix: tuple[np.ndarray, np.ndarray] | None = None


@dataclass(frozen=True)
class Benchmark:
    name: str
    title: str
    estimation: Dataset
    tests: list[TestRecord]
    unit: str
    scale: float  # reporting unit per data unit (1000: V -> mV)
    split: str
    n_init: int
    n_init_note: str
    source: Path
    budget: float
    priority: int  # 1: the main nonlinear benchmarks, 2: small SISO sets, 3: MIMO DaISy
    notes: list[str] = field(default_factory=list)


def _folder(name: str) -> Path:
    path = DATA / name
    if not (path / "SOURCE.md").exists():
        raise MissingData(f"{path} is absent")
    return path


def _dataset(
    name: str, parts: list[tuple[str, np.ndarray, np.ndarray]], ts: float, inp: str, out: str
) -> Dataset:
    exps = [Experiment(n, np.asarray(u, float), np.asarray(y, float)) for n, u, y in parts]
    return Dataset((inp,), (out,), ts, exps, source=name)


def _dataset_mimo(
    name: str, parts: list[tuple[str, np.ndarray, np.ndarray]], ts: float | None,
    inputs: list[str], outputs: list[str],
) -> Dataset:  # fmt: skip
    """:func:`_dataset` with several named inputs and outputs (``u``: (N, nu), ``y``:
    (N, ny))."""
    exps = [Experiment(n, np.asarray(u, float), np.asarray(y, float)) for n, u, y in parts]
    return Dataset(tuple(inputs), tuple(outputs), ts, exps, source=name)


def _tail(u: np.ndarray, y: np.ndarray, n: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(u[-n:], float), np.asarray(y[-n:], float)


# ----------------------------------------------------------------------------- the sets
def wh2009() -> Benchmark:
    path = _folder("wiener_hammerstein_2009")
    df = pd.read_csv(path / "WienerHammerBenchmark.csv", usecols=["uBenchMark", "yBenchMark"])
    u = df["uBenchMark"].to_numpy()[5200:184000]
    y = df["yBenchMark"].to_numpy()[5200:184000]
    n = 100_000
    est = _dataset("wh2009", [("estimation", u[:n], y[:n])], 1 / 51200, "u", "y")
    test = TestRecord(
        "test",
        u[n:],
        y[n:],
        linear=Reference(43.4, "LTI state space / ARX [C]"),
        best=Reference(0.241, "state-space encoder, Beintema et al. 2021 [C]"),
        prefix=_tail(u[:n], y[:n]),
    )
    return Benchmark(
        "wh2009", "Wiener-Hammerstein benchmark (SYSID 2009)", est, [test], "mV", 1000.0,
        "nonlinear_benchmarks: samples [5200:184000], estimation = first 100000, "
        "test = remaining 78800",
        50, "first 50 test samples (SOURCE.md)", path / "SOURCE.md", 600.0, 1,
        ["best block-oriented result: 0.28 mV (WH model from the nonparametric BLA "
         "separation, Schoukens/Pintelon/Rolain 2014); PNLSS 0.42 mV [C]",
         "issue 10 target: test RMSE <= 5 mV in under 10 minutes on an unloaded "
         "2-core machine"],
    )  # fmt: skip


def silverbox() -> Benchmark:
    path = _folder("silverbox")
    df = pd.read_csv(path / "SNLS80mV.csv")
    u, y = df["V1"].to_numpy(), df["V2"].to_numpy()
    ms_u, ms_y = u[40650:127400], y[40650:127400]
    n = int(0.75 * len(ms_u))
    est = _dataset("silverbox", [("multisine", ms_u[:n], ms_y[:n])], 1 / 610.35, "V1", "V2")
    au, ay = u[100:40575], y[100:40575]
    tests = [
        TestRecord(
            "multisine", ms_u[n:], ms_y[n:],
            linear=Reference(6.96, "LTI state space [C] (ARX 6.95)"),
            best=Reference(0.301, "GP-NARX [C]"),
            prefix=_tail(ms_u[:n], ms_y[:n]),
        ),
        TestRecord(
            "arrow full", au, ay,
            linear=Reference(14.4, "LTI state space [C] (ARX 14.2)"),
            best=Reference(0.26, "PNLSS, Paduart et al. 2010 [C]"),
        ),
        TestRecord(
            "arrow no extrapolation", au[:32000], ay[:32000],
            linear=Reference(6.58, "LTI state space [C] (ARX 6.59)"),
            best=Reference(0.259, "GP-NARX [C]"),
        ),
    ]  # fmt: skip
    return Benchmark(
        "silverbox", "Silverbox (SNLS80mV)", est, tests, "mV", 1000.0,
        "nonlinear_benchmarks: multisine part [40650:127400], estimation = its first 75 %, "
        "multisine test = its last 25 %; arrow full = [100:40575], arrow no extrapolation "
        "= its first 32000 samples",
        50, "first 50 test samples (SOURCE.md)", path / "SOURCE.md", 300.0, 1,
        ["issue 10 target: <= 3 mV on the arrow full"],
    )  # fmt: skip


def emps() -> Benchmark:
    path = _folder("emps")
    est_df = pd.read_csv(path / "DATA_EMPS.csv")
    test_df = pd.read_csv(path / "DATA_EMPS_PULSES.csv")
    est = _dataset(
        "emps", [("DATA_EMPS", est_df["vir"].to_numpy(), est_df["qm"].to_numpy())],
        1e-3, "vir", "qm",
    )  # fmt: skip
    test = TestRecord(
        "DATA_EMPS_PULSES", test_df["vir"].to_numpy(), test_df["qm"].to_numpy(),
        linear=Reference(5.53, "LTI state space [C] (LTI ARX 12.6 mm)"),
        best=Reference(2.64, "dynoNet, Forgione & Piga 2021 [C]"),
    )  # fmt: skip
    return Benchmark(
        "emps", "EMPS (electro-mechanical positioning system)", est, [test], "mm", 1000.0,
        "estimation = DATA_EMPS, test = DATA_EMPS_PULSES (input vir, output qm)",
        20, "first 20 test samples (SOURCE.md)", path / "SOURCE.md", 180.0, 1,
        ["closed-loop, integrating plant (position from force)"],
    )  # fmt: skip


def ced() -> Benchmark:
    path = _folder("coupled_electric_drives")
    df = pd.read_csv(path / "DATAUNIF.csv", usecols=["u11", "u12", "z11", "z12"])
    parts, tests = [], []
    refs = {1: (0.224, 0.115), 2: (0.384, 0.074)}
    for k in (1, 2):
        u, y = df[f"u1{k}"].to_numpy(), df[f"z1{k}"].to_numpy()
        parts.append((f"record {k}", u[:400], y[:400]))
        lin, best = refs[k]
        tests.append(
            TestRecord(
                f"test{k}", u[400:], y[400:],
                linear=Reference(lin, "LTI state space [C]"),
                best=Reference(best, "CT subnet, Beintema et al. 2023 [C]"),
                prefix=_tail(u[:400], y[:400], 400),
            )
        )  # fmt: skip
    est = _dataset("ced", parts, 0.02, "u", "z")
    return Benchmark(
        "ced", "Coupled electric drives (CE8, DATAUNIF)", est, tests, "ticks/s", 1.0,
        "nonlinear_benchmarks CED(): records u11->z11 and u12->z12, estimation = first 400 "
        "samples of each (one model for both), test = last 100 of each",
        4, "first 4 test samples (SOURCE.md)", path / "SOURCE.md", 120.0, 1,
        ["identify holds out its last experiment (record 2) to choose"],
    )  # fmt: skip


def bouc_wen() -> Benchmark:
    path = _folder("bouc_wen")
    tr = pd.read_csv(path / "bouc_wen_train_multisine_generated.csv")
    est = _dataset("bouc_wen", [("generated", tr["u"].to_numpy(), tr["y"].to_numpy())],
                   1 / 750, "u", "y")  # fmt: skip
    tests = []
    for name, file, best in (
        ("multisine", "bouc_wen_test_multisine.csv",
         Reference(18.7, "PNLSS with decoupling, Esfahani et al. 2017")),
        ("sine sweep", "bouc_wen_test_sinesweep.csv", None),
    ):  # fmt: skip
        df = pd.read_csv(path / file)
        tests.append(TestRecord(name, df["u"].to_numpy(), df["y"].to_numpy(), None, best))
    return Benchmark(
        "bouc_wen", "Bouc-Wen hysteresis (simulated)", est, tests, "um", 1e6,
        "estimation = the generated 40960-sample multisine record; tests = the official "
        "noiseless multisine (8192) and sine sweep (153000)",
        50, "not stated in SOURCE.md; 50 used (as WH 2009 / Silverbox)",
        path / "SOURCE.md", 240.0, 1,
        ["no published linear baseline: the table gives our ARX (chosen on estimation "
         "data) instead; best block-oriented / classic: NFIR 163 um (Belz 2017)"],
    )  # fmt: skip


def wh_process_noise() -> Benchmark:
    path = _folder("wiener_hammerstein_process_noise")
    est_df = pd.read_csv(path / "WH_EstimationExample.csv", header=None, skiprows=1)
    parts = [
        (f"realisation {k + 1}", est_df[10 + k].to_numpy(), est_df[20 + k].to_numpy())
        for k in range(10)
    ]
    est = _dataset("wh_process_noise", parts, 1 / 78125, "u", "y")
    test_df = pd.read_csv(path / "WH_TestDataset.csv", header=None, skiprows=1)
    tests = [
        TestRecord(name, test_df[2 + k].to_numpy(), test_df[4 + k].to_numpy())
        for k, name in enumerate(("multisine", "sine sweep"))
    ]
    return Benchmark(
        "wh_process_noise", "Wiener-Hammerstein with process noise", est, tests, "mV", 1000.0,
        "estimation = WH_EstimationExample (10 realisations of 8192, u -> y, measured u); "
        "tests = WH_TestDataset records 0 (multisine) and 1 (sine sweep)",
        50, "not stated in SOURCE.md; 50 used", path / "SOURCE.md", 240.0, 1,
        ["SOURCE.md collects no reference numbers: the table gives our ARX (chosen on "
         "estimation data) as the linear reference"],
    )  # fmt: skip


def _halves(
    name: str, folder: str, file: str, ucol: str, ycol: str, ts: float | None, title: str,
    unit: str = "", notes: list[str] | None = None,
) -> Callable[[], Benchmark]:  # fmt: skip
    def load() -> Benchmark:
        path = _folder(folder)
        df = pd.read_csv(path / file)
        u, y = df[ucol].to_numpy(), df[ycol].to_numpy()
        n = len(u) // 2
        est = _dataset(name, [("first half", u[:n], y[:n])], ts, ucol, ycol)
        test = TestRecord("second half", u[n:], y[n:], prefix=_tail(u[:n], y[:n], n))
        return Benchmark(
            name, title, est, [test], unit or "data units", 1.0,
            "no standard split (DaISy defines none); the common practice of SOURCE.md: "
            "first half for estimation, second half for test",
            10, "not stated; 10 used", path / "SOURCE.md", 60.0, 2,
            ["no published numbers: the table gives our ARX (chosen on estimation data) "
             "as the linear reference", *(notes or [])],
        )  # fmt: skip

    load.__name__ = name
    return load


daisy_ballbeam = _halves(
    "daisy_ballbeam", "daisy_ballbeam", "ballbeam.csv", "u_beam_angle", "y_ball_position", 0.1,
    "DaISy ball and beam", notes=["marginally stable (integrating) plant"],
)  # fmt: skip
daisy_dryer = _halves(
    "daisy_dryer", "daisy_dryer", "dryer.csv", "u_heater_voltage", "y_outlet_air_temperature",
    0.08, "DaISy hair dryer",
)  # fmt: skip
daisy_robot_arm = _halves(
    "daisy_flexible_robot_arm", "daisy_flexible_robot_arm", "robot_arm.csv",
    "u_reaction_torque", "y_arm_acceleration", None, "DaISy flexible robot arm",
)  # fmt: skip
daisy_heat_exchanger = _halves(
    "daisy_heat_exchanger", "daisy_heat_exchanger", "exchanger.csv", "u_liquid_flow_rate_q",
    "y_outlet_liquid_temperature_th", 1.0, "DaISy heat exchanger",
)  # fmt: skip
daisy_heating_system = _halves(
    "daisy_heating_system", "daisy_heating_system", "heating_system.csv", "u", "y", 2.0,
    "DaISy heating system",
)  # fmt: skip
daisy_wing_flutter = _halves(
    "daisy_wing_flutter", "daisy_wing_flutter", "flutter.csv", "u", "y", None,
    "DaISy wing flutter",
)  # fmt: skip
gas_furnace = _halves(
    "box_jenkins_gas_furnace", "box_jenkins_gas_furnace", "gas_furnace.csv", "InputGasRate",
    "CO2", 9.0, "Box-Jenkins gas furnace (series J)",
)  # fmt: skip

#: Every set in the order the runner takes them (most important first).
ALL: dict[str, Callable[[], Benchmark]] = {
    "wh2009": wh2009,
    "silverbox": silverbox,
    "emps": emps,
    "ced": ced,
    "bouc_wen": bouc_wen,
    "wh_process_noise": wh_process_noise,
    "daisy_dryer": daisy_dryer,
    "daisy_heat_exchanger": daisy_heat_exchanger,
    "daisy_ballbeam": daisy_ballbeam,
    "daisy_flexible_robot_arm": daisy_robot_arm,
    "daisy_heating_system": daisy_heating_system,
    "daisy_wing_flutter": daisy_wing_flutter,
    "box_jenkins_gas_furnace": gas_furnace,
}


# ----------------------------------------------------------------------------- MIMO sets
def _count(n: int, what: str) -> str:
    return f"{n} {what}" + ("" if n == 1 else "s")


def _halves_mimo(
    name: str, folder: str, file: str, input_columns: list[str], output_columns: list[str],
    ts: float | None, title: str, unit: str = "", notes: list[str] | None = None,
) -> Callable[[], Benchmark]:  # fmt: skip
    """:func:`_halves` for several inputs and outputs: the test record's ``u`` is (N, nu)
    and its ``y`` (N, ny), also when ``nu`` or ``ny`` is 1. No multivariable DaISy
    ``SOURCE.md`` defines a standard split, so every set is split in halves."""

    def load() -> Benchmark:
        path = _folder(folder)
        df = pd.read_csv(path / file)
        cols = [*input_columns, *output_columns]
        values = df[cols].to_numpy(float)
        bad = ~np.isfinite(values)
        if bad.any():
            row, col = np.argwhere(bad)[0]
            raise ValueError(f"{path / file}: {cols[col]} is {values[row, col]} at row {row}")
        nu = len(input_columns)
        u, y = values[:, :nu], values[:, nu:]
        n = len(u) // 2
        est = _dataset_mimo(name, [("first half", u[:n], y[:n])], ts, input_columns, output_columns)
        test = TestRecord("second half", u[n:], y[n:], prefix=_tail(u[:n], y[:n], n))
        return Benchmark(
            name, title, est, [test], unit or "data units", 1.0,
            "no standard split (SOURCE.md: DaISy defines none); the common practice of "
            f"SOURCE.md: first half for estimation ({n} samples), second half for test "
            f"({len(u) - n})",
            10, "not stated; 10 used", path / "SOURCE.md", 60.0, 3,
            [f"{_count(nu, 'input')}, {_count(len(output_columns), 'output')}",
             "no published numbers: the table gives our ARX (chosen on estimation data) "
             "as the linear reference", *(notes or [])],
        )  # fmt: skip

    load.__name__ = name
    return load


daisy_cd_player_arm = _halves_mimo(
    "daisy_cd_player_arm", "daisy_cd_player_arm", "CD_player_arm.csv",
    ["u1_force", "u2_force"], ["y1_tracking", "y2_tracking"], None,
    "DaISy CD player arm",
    notes=["sampling time not stated in the DaISy description",
           "closed-loop data converted to open-loop-equivalent data (SOURCE.md); the "
           "inputs are highly coloured"],
)  # fmt: skip
daisy_evaporator = _halves_mimo(
    "daisy_evaporator", "daisy_evaporator", "evaporator.csv",
    ["u1_feed_flow", "u2_vapor_flow", "u3_cooling_water_flow"],
    ["y1_dry_matter_content", "y2_product_flow", "y3_product_temperature"], None,
    "DaISy four-stage evaporator",
    notes=["sampling time not stated",
           "every column is normalised (zero mean, standard deviation about 1 over the "
           "whole record); the inputs take few distinct levels (53 to 275)"],
)  # fmt: skip
daisy_glass_furnace = _halves_mimo(
    "daisy_glass_furnace", "daisy_glass_furnace", "glassfurnace.csv",
    ["u1_heating", "u2_cooling", "u3_heating"],
    ["y1_temp", "y2_temp", "y3_temp", "y4_temp", "y5_temp", "y6_temp"], None,
    "DaISy glass furnace (Philips)",
    notes=["sampling time not stated; column t (a sample index) is not used",
           "every column is normalised (zero mean, standard deviation about 1 over the "
           "whole record); the outputs vary more in the second half (std 1.1-1.2 against "
           "0.7-1.0)"],
)  # fmt: skip
daisy_industrial_dryer = _halves_mimo(
    "daisy_industrial_dryer", "daisy_industrial_dryer", "dryer2.csv",
    ["u1_fuel_flow_rate", "u2_hot_gas_exhaust_fan_speed", "u3_raw_material_flow_rate"],
    ["y1_dry_bulb_temperature", "y2_wet_bulb_temperature", "y3_moisture_content"], 10.0,
    "DaISy industrial dryer (Cambridge Control)",
    notes=["column t (a sample index) is not used; zero-mean deviations, units not stated",
           "u1 and u2 are piecewise constant (held up to 137 and 230 samples); the halves "
           "are at different operating points (the fan speed u2 lies in [-11.7, 38.6] in "
           "the first half and in [-21.7, -1.3] in the second; 99 % of the test dry-bulb "
           "temperature lies outside its estimation range)"],
)  # fmt: skip
daisy_power_plant = _halves_mimo(
    "daisy_power_plant_120MW", "daisy_power_plant_120MW", "powerplant.csv",
    ["u1_gas_flow", "u2_turbine_valves_opening", "u3_superheater_spray_flow",
     "u4_gas_dampers", "u5_air_flow"],
    ["y1_steam_pressure", "y2_main_steam_temperature", "y3_reheat_steam_temperature"],
    1228.8, "DaISy 120 MW power plant (Pont-sur-Sambre)",
    notes=["only 200 samples (100 for estimation, 5 inputs); normal operating records "
           "(no designed excitation); column t (a sample index) and the three Yr columns "
           "(meaning not given in SOURCE.md) are not used; integer values, units not stated",
           "the halves are at different operating points: the gas flow u1 barely moves in "
           "the second half (std 11 against 254) while u3 and u5 move much more (std 332 "
           "and 344 against 32 and 71)"],
)  # fmt: skip
daisy_cstr = _halves_mimo(
    "daisy_sim_cstr", "daisy_sim_cstr", "cstr.csv",
    ["u_coolant_flow_q"], ["y1_concentration_Ca", "y2_temperature_T"], 6.0,
    "DaISy CSTR (simulated)", unit="mol/l (Ca), K (T)",
    notes=["SIMULATED (a CSTR model, not a measurement); strongly nonlinear",
           "sampling time 0.1 min (SOURCE.md), given here as 6 s; column t_min not used",
           "one input, two outputs; the input is held constant over blocks of 10 samples"],
)  # fmt: skip
daisy_steam_generator = _halves_mimo(
    "daisy_sim_steam_generator", "daisy_sim_steam_generator", "steamgen.csv",
    ["u1_fuel", "u2_air", "u3_level_reference", "u4_load_disturbance"],
    ["y1_drum_pressure_psi", "y2_excess_oxygen_pct", "y3_drum_water_level",
     "y4_steam_flow_kg_s"], 3.0,
    "DaISy steam generator (simulated)", unit="psi, %, level (unit not stated), kg/s",
    notes=["SIMULATED (Pellegrinetti & Bentsman model of the Abbott power plant "
           "boiler); water level stabilised by a PI loop; column t (seconds) not used"],
)  # fmt: skip
daisy_thermic_wall = _halves_mimo(
    "daisy_thermic_wall", "daisy_thermic_wall", "thermic_res_wall.csv",
    ["u1_internal_wall_temperature", "u2_external_wall_temperature"],
    ["y_heat_flow_density"], None, "DaISy thermic resistance wall",
    notes=["two inputs, one output (multi-input single-output); sampling time and units "
           "not stated"],
)  # fmt: skip
daisy_winding_process = _halves_mimo(
    "daisy_winding_process", "daisy_winding_process", "winding.csv",
    ["u1_S1_speed_reel1", "u2_S2_speed_reel2", "u3_S3_speed_reel3",
     "u4_I1_setpoint_current_motor1", "u5_I3_setpoint_current_motor3"],
    ["y1_T1_tension_reel1_2", "y2_T3_tension_reel2_3"], 0.1,
    "DaISy winding process",
    notes=["every column is normalised (zero mean, unit standard deviation over the "
           "whole record)"],
)  # fmt: skip

#: The multivariable DaISy sets (several inputs or outputs), in folder order; not in
#: :data:`ALL`.
MIMO: dict[str, Callable[[], Benchmark]] = {
    "daisy_cd_player_arm": daisy_cd_player_arm,
    "daisy_evaporator": daisy_evaporator,
    "daisy_glass_furnace": daisy_glass_furnace,
    "daisy_industrial_dryer": daisy_industrial_dryer,
    "daisy_power_plant_120MW": daisy_power_plant,
    "daisy_sim_cstr": daisy_cstr,
    "daisy_sim_steam_generator": daisy_steam_generator,
    "daisy_thermic_wall": daisy_thermic_wall,
    "daisy_winding_process": daisy_winding_process,
}

#: Folders that are not loaded (folder -> reason): none now, the multivariable sets
#: being in :data:`MIMO`.
NOT_RUN: dict[str, str] = {}
