"""Where a study's independent tasks run, as an :class:`rbjax.Parallel` says
(:mod:`~rbjax.studies.parallel.executors`: in process, worker processes, a Dask cluster), the
local worker pools (:mod:`~rbjax.studies.parallel.worker_pool`) and a design's rows evaluated
in this process or as tasks (:mod:`~rbjax.studies.parallel.rows`)."""

from .executors import Task, TaskError, run_tasks

__all__ = ["Task", "TaskError", "run_tasks"]
