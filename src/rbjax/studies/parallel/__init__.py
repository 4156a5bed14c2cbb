"""Where a study's independent tasks run (:mod:`~rbjax.studies.parallel.executors`: in process,
worker processes, a Dask cluster) and the local worker pools
(:mod:`~rbjax.studies.parallel.worker_pool`)."""

from .executors import Parallel, Task, TaskError, run_tasks

__all__ = ["Parallel", "Task", "TaskError", "run_tasks"]
