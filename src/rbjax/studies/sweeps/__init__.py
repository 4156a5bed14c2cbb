"""TOML sweeps (:mod:`~rbjax.studies.sweeps.sweep`; a study's rows run as
:mod:`rbjax.studies.parallel.rows` says) and a job array's parts
(:mod:`~rbjax.studies.sweeps.parts`)."""

from .parts import merge_parts, run_part
from .sweep import load_config, run_sweep, write_outputs

__all__ = ["load_config", "run_sweep", "write_outputs", "merge_parts", "run_part"]
