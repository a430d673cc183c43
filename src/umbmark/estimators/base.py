"""What every estimator returns, and the error propagation they share."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..benchmark import Benchmark
from ..validation import check_positive

__all__ = ["ErrorEstimate", "SquareTest", "cg_vector", "propagate"]

FloatArray = NDArray[np.float64]


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


def cg_vector(bench: Benchmark) -> tuple[FloatArray, FloatArray]:
    """Centres of gravity as one vector and their covariance.

    Returns
    -------
    z : array, shape (4,)
        ``(x_cw, y_cw, x_ccw, y_ccw)`` [m].
    cov : array, shape (4, 4)
        Covariance of ``z``: each cluster's sample covariance divided by its size.
    """
    z = np.concatenate([bench.cw.cg, bench.ccw.cg])
    cov = np.zeros((4, 4))
    for k, cluster in enumerate(bench.clusters):
        cov[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = (
            np.cov(cluster.errors, rowvar=False, ddof=1) / cluster.n
        )
    return z, cov


def propagate(
    fn: Callable[[FloatArray], Mapping[str, float]],
    z: FloatArray,
    cov: FloatArray,
    step: float = 1e-6,
) -> dict[str, float]:
    """First-order standard errors of every output of ``fn`` at ``z``.

    Central differences give the Jacobian ``J``; the standard errors are the square
    roots of the diagonal of ``J cov J^T``.
    """
    keys = list(fn(z))
    jac = np.zeros((len(keys), len(z)))
    for j in range(len(z)):
        dz = np.zeros_like(z)
        dz[j] = step
        plus, minus = fn(z + dz), fn(z - dz)
        jac[:, j] = [(plus[k] - minus[k]) / (2.0 * step) for k in keys]
    var = np.einsum("ij,jk,ik->i", jac, cov, jac)
    return {k: float(math.sqrt(max(v, 0.0))) for k, v in zip(keys, var, strict=True)}
