"""What a held-out validation found (:class:`ValidationReport`): each candidate's mean
end-position error on runs it never saw, fold by fold, and the recommendation
(:func:`umbmark.calibration.heldout.validate_read` computes it). :attr:`ValidationReport.coverage`
states which kinds of motion were held out (:mod:`umbmark.estimators.motions`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from umbmark.core.jsontext import JsonText
from umbmark.core.messages import join_names
from umbmark.estimators.motions import KINDS, MotionKind

__all__ = ["Fold", "ValidationReport"]


@dataclass(frozen=True)
class Fold:
    """One held-out part and how each candidate predicted it.

    Attributes
    ----------
    held_out : str
        The source (or run) held out.
    runs : int
        Runs held out.
    errors : dict of str to float or None
        Mean end-position error [m] of the held-out runs with each candidate's
        calibration from the rest; None where the candidate could not calibrate (square
        estimators need squares in both directions).
    motions : tuple of str
        The kinds of motion the held-out runs hold (``straight``, ``arc``, ``spot``).
    trained_on : tuple of str
        The kinds the rest hold, which calibrated.
    refused : dict of str to str
        Why a candidate did not calibrate, where the validation itself decided it
        (``trajectory-scrub`` on runs that do not identify its turn-rate term).
    """

    held_out: str
    runs: int
    errors: dict[str, float | None]
    motions: tuple[MotionKind, ...] = ()
    trained_on: tuple[MotionKind, ...] = ()
    refused: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True, repr=False)
class ValidationReport(JsonText):
    """Held-out end errors of every candidate, and the recommendation.

    Attributes
    ----------
    sources : tuple of str
    scheme : str
        ``leave one source out`` or ``leave one run out``.
    candidates : tuple of str
    folds : tuple of Fold
    notes : tuple of str
        What was done, for people (a candidate not calibrated with a fold held out).
    warnings : tuple of str
        What makes the inputs doubtful (as read).
    """

    sources: tuple[str, ...]
    scheme: str
    candidates: tuple[str, ...]
    folds: tuple[Fold, ...]
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    def __repr__(self) -> str:
        return (
            f"ValidationReport(sources={len(self.sources)}, scheme={self.scheme!r}, "
            f"folds={len(self.folds)}, recommended={self.recommended!r})"
        )

    def mean_error(self, candidate: str) -> float | None:
        """Mean over the folds of the held-out end error [m]; None unless the candidate
        could calibrate in every fold."""
        values = [fold.errors.get(candidate) for fold in self.folds]
        if not values or any(v is None for v in values):
            return None
        return float(np.mean([v for v in values if v is not None]))

    @property
    def ranking(self) -> list[tuple[str, float]]:
        """Candidates that calibrated in every fold, best first, with their mean error [m]."""
        scored = [(c, self.mean_error(c)) for c in self.candidates]
        return sorted(((c, e) for c, e in scored if e is not None), key=lambda item: item[1])

    @property
    def covered(self) -> tuple[MotionKind, ...]:
        """The kinds of motion held out in some fold: what the figures speak for."""
        return tuple(k for k in KINDS if any(k in fold.motions for fold in self.folds))

    @property
    def coverage(self) -> str:
        """What the figures cover and what they do not, from the held-out runs' motion."""
        held = join_names([KINDS[k] for k in self.covered]) or "no motion"
        missing = [KINDS[k] for k in KINDS if k not in self.covered]
        if missing:
            text = (
                f"the held-out runs hold only {held}: the figures say nothing about "
                f"{join_names(missing, 'or')}"
            )
        else:
            text = f"the held-out runs hold {held}"
        for kind in self.covered:
            folds = [f for f in self.folds if kind in f.motions]
            if all(kind not in f.trained_on for f in folds):
                names = ", ".join(Path(f.held_out).name for f in folds)
                text += (
                    f"; {KINDS[kind]} are held out only against calibrations from runs "
                    f"without them ({names}): those figures test extrapolation to them"
                )
        return text

    @property
    def recommended(self) -> str | None:
        """The estimator with the lowest mean held-out error (None if no estimator beats
        the nominal parameters)."""
        for candidate, _ in self.ranking:
            return None if candidate == "nominal" else candidate
        return None

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres): what ``validate --json`` prints."""
        return {
            "sources": list(self.sources),
            "scheme": self.scheme,
            "folds": [
                {
                    "held_out": f.held_out,
                    "runs": f.runs,
                    "end_error": dict(f.errors),
                    "motions": list(f.motions),
                    "calibrated_on": list(f.trained_on),
                    "refused": dict(f.refused),
                }
                for f in self.folds
            ],
            "mean_end_error": {c: self.mean_error(c) for c in self.candidates},
            "recommended": self.recommended,
            "coverage": {
                "held_out": list(self.covered),
                "not_held_out": [k for k in KINDS if k not in self.covered],
                "statement": self.coverage,
            },
            "notes": list(self.notes),
            "warnings": list(self.warnings),
        }
