"""Sim-to-real gap diagnosis: where model and measurement part, which unmodelled effect, how far it shrinks.

``diagnose(request) -> dict`` is the entry point (``docs/contract.md`` "Diagnosis"); the method is
feature-space Bayesian model-class selection with a tolerance-propagated discrepancy
covariance (``docs/diagnosis.md`` §4). Modules: :mod:`.request` (validation), :mod:`.model`
(knobs on the base model, cached solver), :mod:`.features`, :mod:`.discrepancy` (Σ),
:mod:`.effects` (candidate catalogue), :mod:`.attribution` (evidence, decision),
:mod:`.validation` (held-out), :mod:`.report` (response, figure), :mod:`.api`.
"""

from __future__ import annotations

from rcsa.analysis.diagnosis.diagnose import diagnose
from rcsa.analysis.diagnosis.report import diagnosis_figure
from rcsa.analysis.diagnosis.state import Analysis, analyse

__all__ = ["Analysis", "analyse", "diagnose", "diagnosis_figure"]
