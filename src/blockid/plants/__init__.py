"""Simulated seed plants: paper A's wind tunnel and paper B's electrohydraulic servo."""

from blockid.plants.electrohydraulic import (
    ElectrohydraulicParameters,
    electrohydraulic_experiment,
    electrohydraulic_static_spool,
    general_trajectory_current,
    multisine_current,
    simulate_electrohydraulic,
)
from blockid.plants.windtunnel import (
    CONDITIONS,
    WindTunnelParameters,
    flow_field_arx,
    simulate_windtunnel,
    windtunnel_experiment,
)

__all__ = [
    "CONDITIONS",
    "ElectrohydraulicParameters",
    "WindTunnelParameters",
    "electrohydraulic_experiment",
    "electrohydraulic_static_spool",
    "flow_field_arx",
    "general_trajectory_current",
    "multisine_current",
    "simulate_electrohydraulic",
    "simulate_windtunnel",
    "windtunnel_experiment",
]
