"""What every estimator returns, and the error propagation they share."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.validation import check_positive
from umbmark.returns.clusters import Benchmark

__all__ = [
    "ErrorEstimate",
    "ModelCheckFailure",
    "SquareTest",
    "cg_blocks",
    "propagate_blocks",
    "welch_dof",
]


@dataclass(frozen=True)
class SquareTest:
    """The geometry of a square path test.

    Attributes
    ----------
    side_length : float
        ``L`` [m], the side of the square.
    wheelbase : float
        ``b`` [m] the odometry used during the runs (the paper's nominal wheelbase).
    """

    side_length: float
    wheelbase: float

    def __post_init__(self) -> None:
        for name in ("side_length", "wheelbase"):
            check_positive(name, getattr(self, name), unit="m")


@dataclass(frozen=True)
class ModelCheckFailure:
    """A failed model check of the end poses: one robot of the model does not explain both
    clusters (:func:`umbmark.estimators.diagnostics.check_model`).

    Attributes
    ----------
    p_value : float
        The check's p (below :data:`umbmark.estimators.endpose.LEVEL`).
    misfit : float
        How far the farther cluster's centre lies from the model's [m] (positions).
    swapped_p : float or None
        The check's p with every cw label made ccw and every ccw label cw (None: that fit
        could not be made).
    swapped_fits : bool
        With the labels swapped the runs pass the check (``swapped_p`` at or above its
        level): the labels are likely swapped.
    """

    p_value: float
    misfit: float
    swapped_p: float | None = None
    swapped_fits: bool = False


@dataclass(frozen=True)
class ErrorEstimate:
    """Systematic errors estimated from a test.

    Attributes
    ----------
    method : str
        The estimator's name (``paper``, ``heading``, ``exact``, ...).
    alpha, beta : float
        Type A error per turn and Type B error per leg [rad].
    E_d, E_b : float
        Wheel-diameter ratio ``D_R / D_L`` and wheelbase ratio ``b_actual / b_nominal``.
    components : mapping of str to float
        Intermediate figures (for example ``alpha_x``, ``E_d_y``), angles in radians.
    standard_errors : mapping of str to float
        One-sigma uncertainty of ``alpha``, ``beta``, ``E_d``, ``E_b`` from the spread of
        the runs (first-order propagation).
    warnings : tuple of str
        The result is valid but shaky, and why.
    E_s : float or None
        Scale error ``D_avg / D_n``, for estimators that can see it.
    dof : float, mapping of str to float, or None
        Degrees of freedom of the standard errors (of the scatter they come from), one for
        all or one per figure, for Student's t intervals; None: large-sample (normal)
        intervals.
    model_failure : ModelCheckFailure or None
        The model check of the end poses failed (None: it passed, or was not made); its
        warning is among ``warnings``.
    """

    method: str
    alpha: float
    beta: float
    E_d: float
    E_b: float
    components: Mapping[str, float] = field(default_factory=dict)
    standard_errors: Mapping[str, float] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    E_s: float | None = None
    dof: float | Mapping[str, float] | None = None
    model_failure: ModelCheckFailure | None = None

    def with_scale(self, E_s: float) -> ErrorEstimate:
        """This estimate of a square test, completed by a scale error ``E_s`` measured
        apart (straight runs): the turns saw ``E_b / E_s``, so ``E_b`` is scaled by it."""
        errors = dict(self.standard_errors)
        if "E_b" in errors:
            errors["E_b"] = errors["E_b"] * E_s
        return replace(self, E_b=self.E_b * E_s, E_s=E_s, standard_errors=errors)

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float] | None:
        """The ``level`` confidence interval of ``name`` (``E_d``, ``E_b``, ...), or None
        without a standard error: estimate -/+ Student's t quantile times the standard error."""
        from umbmark.core.stats import t_quantile

        se = self.standard_errors.get(name)
        value = getattr(self, name, self.components.get(name))
        if se is None or value is None or not math.isfinite(se):
            return None
        value = float(value)
        dof = self.dof.get(name) if isinstance(self.dof, Mapping) else self.dof
        dof = math.inf if dof is None or dof < 1 else dof
        half = t_quantile(0.5 + 0.5 * level, dof) * se
        return (value - half, value + half)


def welch_dof(parts: Sequence[tuple[float, float]]) -> float:
    """Degrees of freedom of a sum of independent variance estimates (Welch-Satterthwaite).

    ``parts`` holds each estimate's value and degrees of freedom.
    """
    total = sum(v for v, _ in parts)
    spread = sum(v * v / dof for v, dof in parts if dof > 0)
    return math.inf if spread <= 0.0 else total * total / spread


def cg_blocks(bench: Benchmark) -> tuple[FloatArray, list[tuple[FloatArray, float]]]:
    """Centres of gravity as one vector, and each cluster's covariance of its centre.

    Returns
    -------
    z : array, shape (4,)
        ``(x_cw, y_cw, x_ccw, y_ccw)`` [m].
    blocks : list of (array, shape (2, 2), float)
        Each cluster's sample covariance over its size, and its degrees of freedom
        (``n - 1``).
    """
    z = np.concatenate([bench.cw.cg, bench.ccw.cg])
    blocks = [
        (np.cov(c.errors, rowvar=False, ddof=1) / c.n, float(c.n - 1)) for c in bench.clusters
    ]
    return z, blocks


def propagate_blocks(
    fn: Callable[[FloatArray], Mapping[str, float]],
    z: FloatArray,
    blocks: Sequence[tuple[FloatArray, float]],
    step: float = 1e-6,
) -> tuple[dict[str, float], dict[str, float]]:
    """First-order standard errors of every output of ``fn`` at ``z``, and their degrees
    of freedom.

    ``z`` is the concatenation of independent blocks of variables, each with its
    covariance and the degrees of freedom it was estimated with. Each output's variance is
    the sum of the blocks' contributions; its degrees of freedom follow by
    Welch-Satterthwaite (:func:`welch_dof`).
    """
    keys = list(fn(z))
    jac = np.zeros((len(keys), len(z)))
    for j in range(len(z)):
        dz = np.zeros_like(z)
        dz[j] = step
        plus, minus = fn(z + dz), fn(z - dz)
        jac[:, j] = [(plus[k] - minus[k]) / (2.0 * step) for k in keys]
    errors, dofs = {}, {}
    for i, key in enumerate(keys):
        parts, start = [], 0
        for cov, dof in blocks:
            size = cov.shape[0]
            g = jac[i, start : start + size]
            parts.append((max(float(g @ cov @ g), 0.0), dof))
            start += size
        errors[key] = math.sqrt(sum(v for v, _ in parts))
        dofs[key] = welch_dof(parts)
    return errors, dofs
