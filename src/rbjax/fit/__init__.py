"""Fitting the rubber's properties to measured blocked-force histories.

The pipeline, one module each: :mod:`~rbjax.fit.records` (the conditioned records and the
features read off them) → :mod:`~rbjax.fit.layout` (model names and the fitted parameter vector,
from the terms' parameter declarations) → :mod:`~rbjax.fit.program` (prediction through the
measuring chain, residuals and optimistix Levenberg–Marquardt as one compiled program) →
:mod:`~rbjax.fit.uncertainty` (covariance, identifiability) → :mod:`~rbjax.fit.result`
(the frozen result); :mod:`~rbjax.fit.problem` holds one problem (records, layout, program,
onset alignment), :mod:`~rbjax.fit.driver` drives it (:func:`fit`, one step each:
:mod:`~rbjax.fit.setup` → :mod:`~rbjax.fit.start` → :mod:`~rbjax.fit.freedom` →
:mod:`~rbjax.fit.rounds` → :mod:`~rbjax.fit.estimates` → the result) and
:mod:`~rbjax.fit.prediction` compares given models (:func:`predict`, :func:`model_histories`).
"""

from .driver import fit
from .layout import (
    BALL_MODE_SUFFIX,
    MODEL_NAMES,
    STIFFENING_SUFFIX,
    all_model_names,
    fitted_parameter_names,
    model_from_name,
    parse_model_name,
    parse_model_terms,
)
from .options import FitOptions
from .prediction import model_histories, predict
from .program import OPTIMIZERS
from .records import FitData, load_data, prepare_data, record_features
from .result import FitResult, ParameterEstimate, Prediction
from .summary import fit_summary
from .summary_table import SummaryTable, read_summary, summary_table

__all__ = [
    "BALL_MODE_SUFFIX",
    "MODEL_NAMES",
    "OPTIMIZERS",
    "STIFFENING_SUFFIX",
    "FitData",
    "FitOptions",
    "FitResult",
    "SummaryTable",
    "ParameterEstimate",
    "Prediction",
    "all_model_names",
    "fit",
    "fit_summary",
    "fitted_parameter_names",
    "load_data",
    "model_from_name",
    "model_histories",
    "parse_model_name",
    "parse_model_terms",
    "predict",
    "prepare_data",
    "read_summary",
    "record_features",
    "summary_table",
]
