"""Outputs: HDF5 particle snapshots and gas fields with XDMF indexes (ParaView), probes CSV, restart files."""
from .gas_fields import GasFieldWriter, read_gas_fields
from .snapshots import ParticleWriter
from .probes_csv import ProbeWriter

__all__ = ["ParticleWriter", "ProbeWriter", "GasFieldWriter", "read_gas_fields"]
