"""Studies (``fluidem sweep``): one case run over a set of values of some of its keys, each run a member.

A study is a folder of run directories, one per member, plus ``study.toml`` (the definition: case,
varied keys and values, seeds, end time, members) and ``study.csv`` (one row per member: the varied
values, status, error and every scalar of its ``summary.json``).

Modules: ``definition`` (the study and its members, ``study.toml``), ``table`` (a member's state from
its folder, ``study.csv``), ``member`` (one member run in a worker process), ``execution`` (the
members on Dask) and ``runner`` (checks, folder, the ``fluidem.sweep`` function).
"""
from .definition import SEED_KEY, STUDY_FILE, TABLE_FILE, Member, StudyDefinition, parse_seeds, parse_vary
from .runner import run_study, sweep

__all__ = ["SEED_KEY", "STUDY_FILE", "TABLE_FILE", "Member", "StudyDefinition", "parse_seeds", "parse_vary",
           "run_study", "sweep"]
