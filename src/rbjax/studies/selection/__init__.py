"""Choosing the impact model the force histories support: the candidates
(:mod:`~rbjax.studies.selection.candidates`), leave-one-height-out cross-validation
(:mod:`~rbjax.studies.selection.cross_validation`), the rule that recommends one
(:mod:`~rbjax.studies.selection.rule`), the selection itself
(:mod:`~rbjax.studies.selection.select`), its results
(:mod:`~rbjax.studies.selection.results`), the comparison of named models on held-out heights
(:mod:`~rbjax.studies.selection.hold_out_comparison`) and the summary-table selection
(:mod:`~rbjax.studies.selection.summary`)."""

from .select import select_model

__all__ = ["select_model"]
