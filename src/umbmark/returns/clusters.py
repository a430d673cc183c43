"""The UMBmark benchmark (Sec. 3): return errors, centres of gravity and E_max,syst.

- Eq. 3.1: return error ``eps = absolute - calculated`` (see :attr:`Run.return_error`).
- Eq. 3.2: centre of gravity of each direction's errors, ``X_cg = mean(eps_x)``.
- Eq. 3.3: ``r_cg = sqrt(X_cg^2 + Y_cg^2)``.
- Eq. 3.4: ``E_max,syst = max(r_cg,cw, r_cg,ccw)``.
- Sec. 5: the spread of each cluster and its standard error of the mean,
  ``SEM = sigma / sqrt(n)``; a second compensation pass is worth it when
  ``E_max,syst > 3 SEM``. :func:`sem_verdict` says it in words, its wording following
  the ratio ``E_max,syst / 3 SEM`` (:data:`CLEARLY_ABOVE`, :data:`WELL_ABOVE`).

The spread ``sigma`` of a cluster is the radial standard deviation
``sqrt(sum |eps_i - cg|^2 / (n - 1))``, so that ``SEM = sigma / sqrt(n)`` is the
root-mean-square distance of the measured centre of gravity from the true one, the
quantity ``r_cg`` is compared with. The rule is applied to the cluster that sets
``E_max,syst``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.conventions import Direction
from umbmark.model.run import Run, return_errors, split_by_direction

__all__ = [
    "CLEARLY_ABOVE",
    "MIN_RUNS_PER_DIRECTION",
    "NO_RETURN_ERROR",
    "WELL_ABOVE",
    "Benchmark",
    "Cluster",
    "scatter_standing",
    "sem_verdict",
    "umbmark_benchmark",
]

#: The spread of a cluster needs at least two runs.
MIN_RUNS_PER_DIRECTION = 2
#: Sec. 5: a second pass is worth it when E_max,syst exceeds this many SEMs.
SEM_RULE_FACTOR = 3.0
#: E_max,syst from this many times 3 SEM on stands "above" the scatter (below: "just above") ...
CLEARLY_ABOVE = 1.25
#: ... and from this many times 3 SEM on "well above" it.
WELL_ABOVE = 2.0
#: ``E_max,syst`` and ``3 SEM`` both under this [m] (``0.0 mm`` as printed): the runs show
#: neither an error nor any scatter, which no measured reference does.
NO_RETURN_ERROR = 5e-5


@dataclass(frozen=True)
class Cluster:
    """The return errors of one direction and their statistics.

    Attributes
    ----------
    direction : Direction
    errors : array, shape (n, 2)
        ``eps_x, eps_y`` of each run [m].
    cg : array, shape (2,)
        Centre of gravity ``(X_cg, Y_cg)`` [m], Eq. 3.2.
    """

    direction: Direction
    errors: NDArray[np.float64]
    cg: NDArray[np.float64]

    @classmethod
    def of(cls, direction: Direction, errors: NDArray[np.float64]) -> Cluster:
        """Build the cluster of ``errors`` (shape (n, 2), metres)."""
        errors = np.asarray(errors, dtype=np.float64).reshape(-1, 2)
        if len(errors) < MIN_RUNS_PER_DIRECTION:
            raise ValueError(
                f"{len(errors)} {direction.value} run(s): UMBmark needs at least "
                f"{MIN_RUNS_PER_DIRECTION} runs in each direction (the paper uses 5)"
            )
        return cls(direction=direction, errors=errors, cg=errors.mean(axis=0))

    @property
    def n(self) -> int:
        """Number of runs."""
        return len(self.errors)

    @property
    def r_cg(self) -> float:
        """Distance of the centre of gravity from the origin [m], Eq. 3.3."""
        return math.hypot(float(self.cg[0]), float(self.cg[1]))

    @property
    def std_xy(self) -> NDArray[np.float64]:
        """Sample standard deviation of ``eps_x`` and of ``eps_y`` [m], shape (2,)."""
        return np.asarray(self.errors.std(axis=0, ddof=1), dtype=np.float64)

    @property
    def sigma(self) -> float:
        """Radial sample standard deviation ``sqrt(sum |eps_i - cg|^2 / (n-1))`` [m]."""
        return float(np.sqrt(np.sum((self.errors - self.cg) ** 2) / (self.n - 1)))

    @property
    def sem(self) -> float:
        """Standard error of the centre of gravity, ``sigma / sqrt(n)`` [m]."""
        return self.sigma / math.sqrt(self.n)


@dataclass(frozen=True)
class Benchmark:
    """The result of a bi-directional square path experiment (UMBmark)."""

    cw: Cluster
    ccw: Cluster

    @property
    def clusters(self) -> tuple[Cluster, Cluster]:
        """``(cw, ccw)``."""
        return (self.cw, self.ccw)

    @property
    def worst(self) -> Cluster:
        """The cluster whose centre of gravity is farther from the origin."""
        return self.cw if self.cw.r_cg >= self.ccw.r_cg else self.ccw

    @property
    def e_max_syst(self) -> float:
        """``E_max,syst`` [m], Eq. 3.4."""
        return self.worst.r_cg

    @property
    def sem(self) -> float:
        """SEM [m] of the cluster that sets ``E_max,syst``."""
        return self.worst.sem

    @property
    def second_pass_threshold(self) -> float:
        """``3 SEM`` [m]: below it, another pass is unlikely to improve the result."""
        return SEM_RULE_FACTOR * self.sem

    @property
    def second_pass_recommended(self) -> bool:
        """Sec. 5's rule of thumb: ``E_max,syst > 3 SEM``."""
        return self.e_max_syst > self.second_pass_threshold

    @property
    def unmeasured(self) -> bool:
        """``E_max,syst`` and ``3 SEM`` both under :data:`NO_RETURN_ERROR`: the runs came
        back where the odometry says, without scatter (a reference that is the odometry)."""
        return max(self.e_max_syst, self.second_pass_threshold) < NO_RETURN_ERROR

    @property
    def sem_ratio(self) -> float:
        """``E_max,syst / 3 SEM`` (infinite for runs without scatter, NaN for neither)."""
        if self.second_pass_threshold > 0:
            return self.e_max_syst / self.second_pass_threshold
        return math.inf if self.e_max_syst > 0 else math.nan


def scatter_standing(bench: Benchmark) -> str:
    """Where E_max,syst stands against the runs' scatter, in words: ``"within"`` (at most
    3 SEM), ``"just above"`` (less than :data:`CLEARLY_ABOVE` times 3 SEM), ``"above"``
    (less than :data:`WELL_ABOVE` times) or ``"well above"``."""
    if not bench.second_pass_recommended:
        return "within"
    ratio = bench.sem_ratio
    if ratio < CLEARLY_ABOVE:
        return "just above"
    return "above" if ratio < WELL_ABOVE else "well above"


def sem_verdict(bench: Benchmark) -> str:
    """The 3 x SEM rule of Sec. 5 on ``bench``, in one line of plain text (mm).

    The one wording of the rule: the terminal, the HTML page and the JSON results
    (``verdict``) print this. "Well above the scatter" is said only from
    :data:`WELL_ABOVE` times 3 SEM on; the ratio is stated.
    """
    e, t = bench.e_max_syst * 1000.0, bench.second_pass_threshold * 1000.0
    if bench.unmeasured:
        return (
            f"E_max,syst = {e:.1f} mm and 3 x SEM = {t:.1f} mm: the runs came back where the "
            "odometry says, without any scatter: nothing was measured (a ground truth that "
            "reproduces the odometry)."
        )
    standing = scatter_standing(bench)
    if standing == "within":
        return (
            f"E_max,syst = {e:.1f} mm <= 3 x SEM = {t:.1f} mm: what remains is within the "
            "scatter of the runs; a further pass is unlikely to improve it (Sec. 5)."
        )
    ratio = bench.sem_ratio
    times = f" ({ratio:.2f} times 3 x SEM)" if math.isfinite(ratio) else " (runs without scatter)"
    head = f"E_max,syst = {e:.1f} mm > 3 x SEM = {t:.1f} mm{times}: the systematic error stands "
    if standing == "just above":
        return (
            f"{head}just above the scatter of the runs; another pass (apply the correction, "
            "then run UMBmark again) may still improve it a little (Sec. 5)."
        )
    return (
        f"{head}{standing} the scatter of the runs. Apply the correction, then run UMBmark "
        "again; another pass is worth it while E_max,syst stays above 3 x SEM (Sec. 5)."
    )


def umbmark_benchmark(runs: Sequence[Run]) -> Benchmark:
    """Evaluate a set of cw and ccw runs (Eqs. 3.1-3.4).

    Raises
    ------
    ValueError
        If a direction has fewer than two runs.
    """
    groups = split_by_direction(runs)
    return Benchmark(
        cw=Cluster.of(Direction.CW, return_errors(groups[Direction.CW])),
        ccw=Cluster.of(Direction.CCW, return_errors(groups[Direction.CCW])),
    )
