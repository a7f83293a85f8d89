"""Outputs: HDF5 particle snapshots with an XDMF index (ParaView), probes CSV, restart files."""
from .snapshots import ParticleWriter
from .probes_csv import ProbeWriter

__all__ = ["ParticleWriter", "ProbeWriter"]
