"""Studies built on the solve and the fit: model selection by held-out error
(:mod:`~rbjax.studies.selection.select`), the growth of L_FE per doubling of drop height
(:mod:`~rbjax.studies.growth`), sensitivities (:mod:`rbjax.studies.sensitivity`) and TOML
sweeps (:mod:`~rbjax.studies.sweeps.sweep`), their independent tasks run where an
:class:`rbjax.Parallel` says (in process, worker processes, a Dask cluster;
:mod:`rbjax.studies.parallel`)."""

from .design import DesignResult, DesignSearch, design
from .growth import (
    Growth,
    GrowthError,
    growth_per_doubling_dB,
    growth_table,
    model_growth,
    recording_growth,
)
from .parallel.executors import Task, TaskError, run_tasks
from .selection.cross_validation import cross_validate
from .selection.hold_out_comparison import held_out_comparison
from .selection.race import Race
from .selection.results import Candidate, Selection
from .selection.rule import recommend
from .selection.select import select_model
from .sweeps.parts import merge_parts, run_part
from .sweeps.sweep import load_config, run_sweep, write_outputs

__all__ = [
    "DesignResult",
    "DesignSearch",
    "design",
    "Task",
    "TaskError",
    "run_tasks",
    "Growth",
    "GrowthError",
    "growth_per_doubling_dB",
    "growth_table",
    "model_growth",
    "recording_growth",
    "Candidate",
    "Selection",
    "Race",
    "cross_validate",
    "held_out_comparison",
    "recommend",
    "select_model",
    "load_config",
    "run_sweep",
    "run_part",
    "merge_parts",
    "write_outputs",
]
