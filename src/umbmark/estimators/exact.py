"""Inversion of the exact square geometry: no small-angle approximation.

The paper linearizes the square path (Eqs. 4.1-4.18), which loses accuracy as the errors
grow (later work; ``paper-notes.md``). This estimator instead finds the ``alpha`` and
``beta`` whose exact end positions (:func:`umbmark.model.square.square_end_pose`, legs as arcs
of length ``L``, the on-the-spot turns' sideways shift of Sec. 2.3 included) best match
both centres of gravity in the least-squares sense, starting from the paper's estimate.
``E_b`` then follows exactly from ``alpha`` (Eq. 4.27) and ``E_d`` from ``beta`` for an arc
of length ``L`` and the actual wheelbase ``E_b b``.

The fit (:mod:`umbmark.estimators.solve`) has two unknowns and four smooth residuals.
Large return errors that no robot of the exact geometry explains, or that several
explain, are refused (:func:`check_identified`): the square test does not identify them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.conventions import Direction
from umbmark.estimators.base import ErrorEstimate, SquareTest, cg_blocks, propagate_blocks
from umbmark.estimators.formulas import paper_components
from umbmark.estimators.registry import EXACT
from umbmark.estimators.solve import gauss_newton, jacobian
from umbmark.model.run import Run
from umbmark.model.square import icr_offset, square_end_pose
from umbmark.model.systematic import E_b_from_alpha, E_d_from_beta_arc
from umbmark.returns.clusters import Benchmark

__all__ = [
    "LARGE",
    "UNEXPLAINED",
    "beyond_square_test",
    "check_identified",
    "exact_components",
    "exact_end_positions",
    "exact_estimate",
    "fit_exact_geometry",
]


def exact_end_positions(alpha: float, beta: float, test: SquareTest) -> FloatArray:
    """``(x_cw, y_cw, x_ccw, y_ccw)`` [m] of a robot with errors ``alpha``, ``beta`` [rad]."""
    actual_b = float(E_b_from_alpha(alpha)) * test.wheelbase
    E_d = E_d_from_beta_arc(beta, test.side_length, actual_b)
    offset = icr_offset(E_d, actual_b)
    return np.concatenate(
        [
            square_end_pose(alpha, beta, test.side_length, d, turn_offset=offset)[:2]
            for d in (Direction.CW, Direction.CCW)
        ]
    )


def fit_exact_geometry(z: FloatArray, test: SquareTest, start: FloatArray) -> FloatArray:
    """The ``(alpha, beta)`` [rad] whose exact end positions best match ``z``.

    Least squares on the residuals ``(exact_end_positions(alpha, beta) - z) / L``, shape
    (4,), from ``start`` (shape (2,)); see :func:`umbmark.estimators.solve.gauss_newton`.
    """

    def residuals(p: FloatArray) -> FloatArray:
        return (exact_end_positions(float(p[0]), float(p[1]), test) - z) / test.side_length

    return gauss_newton(residuals, start)[0]


#: A fit from the paper's estimate that misses the centres by more than this fraction of
#: the side (4 cm on a 4 m square; the centres' own scatter is about a centimetre), where
#: a centre lies more than :data:`FAR` of the side from the start (large errors, far from
#: the small angles the paper's estimate assumes), started too far from the robot: it is
#: tried again from :data:`STARTS`.
RETRY = 0.01
FAR = 0.25
#: Starting ``(alpha, beta)`` [rad] of the retry: turns 60 degrees short to 60 long, legs
#: bending up to 60 degrees either way.
STARTS = tuple(
    (math.radians(a), math.radians(b)) for a in range(-60, 61, 20) for b in range(-60, 61, 30)
)
#: Two fits this far apart [rad] are two robots.
_DISTINCT = 1e-3


def _residual_rms(angles: FloatArray, z: FloatArray, test: SquareTest) -> float:
    with np.errstate(all="ignore"):
        residual = exact_end_positions(float(angles[0]), float(angles[1]), test) - z
    value = float(np.sqrt(np.mean(residual**2)))
    return value if math.isfinite(value) else math.inf


def _is_robot(angles: FloatArray, test: SquareTest) -> bool:
    """Whether ``(alpha, beta)`` [rad] are a robot's: positive, finite ``E_b`` and ``E_d``."""
    alpha, beta = float(angles[0]), float(angles[1])
    if not (math.isfinite(alpha) and math.isfinite(beta) and abs(alpha) < 0.5 * math.pi):
        return False
    E_b = float(E_b_from_alpha(alpha))
    E_d = float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase))
    return E_b > 0 and math.isfinite(E_d) and E_d > 0


def exact_components(z: FloatArray, test: SquareTest) -> dict[str, float]:
    """Solve the exact geometry for ``alpha``, ``beta`` given ``z = (x_cw, y_cw, x_ccw, y_ccw)``.

    The fit starts from the paper's estimate; where that leaves the centres missed by more
    than :data:`RETRY` of the side and a centre lies farther than :data:`FAR` of the side
    from the start (large errors, far from the small-angle solution), it is tried from
    every start of :data:`STARTS` too, and the closest fit of a robot (positive ``E_b``
    and ``E_d``) taken. ``roots`` counts the distinct robots that explain the centres as
    well (within the retry's bound, or twice the best miss): more than one, and the runs
    do not tell the robot.
    """
    side = test.side_length
    start = paper_components(z, test)
    angles = fit_exact_geometry(z, test, np.array([start["alpha"], start["beta"]]))
    best = _residual_rms(angles, z, test)
    roots = 1
    if not best <= RETRY * side and float(np.max(np.abs(z))) > FAR * side:
        with np.errstate(all="ignore"):
            fits = [angles, *(fit_exact_geometry(z, test, np.array(s)) for s in STARTS)]
        robots = [a for a in fits if _is_robot(a, test)] or [angles]
        misses = [_residual_rms(a, z, test) for a in robots]
        k = int(np.argmin(misses))
        angles, best = robots[k], misses[k]
        good = max(RETRY * side, 2.0 * best)
        found: list[FloatArray] = []
        for a, miss in zip(robots, misses, strict=True):
            if miss <= good and all(np.max(np.abs(a - b)) > _DISTINCT for b in found):
                found.append(a)
        roots = max(len(found), 1)
    alpha, beta = float(angles[0]), float(angles[1])
    E_b = float(E_b_from_alpha(alpha))
    return {
        "alpha": alpha,
        "beta": beta,
        "E_b": E_b,
        "E_d": float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase)),
        "residual_rms": best,
        "roots": float(roots),
    }


#: The exact geometry's closest robot missing the centres by more than this fraction of
#: the side (20 cm on a 4 m square) ends elsewhere: no robot driving the square ends there.
UNEXPLAINED = 0.05
#: ... which is judged only where E_max,syst exceeds this fraction of the side: smaller
#: errors are identified whatever else is wrong with the runs (the model check says what).
LARGE = 0.25


def beyond_square_test(why: str, e_max: float, side: float) -> str:
    """The refusal of return errors the square test cannot identify: why, and the remedy."""
    return (
        f"E_max,syst is {e_max:.4g} m on a {side:g} m square, and {why}: turning errors "
        "this large (a wheelbase tens of % off, as on skid-steer robots) are beyond what "
        "the square test identifies. Calibrate the turning coarsely first: turn the robot "
        "on the spot ten times as its odometry counts, measure the angle it truly turned, "
        "multiply wheel_separation_multiplier by the odometry's angle over the true one, "
        "and drive the square again"
    )


def check_identified(parts: Mapping[str, float], bench: Benchmark, test: SquareTest) -> None:
    """Refuse large return errors that no robot of the exact geometry explains, or that
    several explain (``parts`` from :func:`exact_components`).

    Raises
    ------
    ValueError
        Naming the cause and the remedy (:func:`beyond_square_test`).
    """
    side = test.side_length
    if bench.e_max_syst <= LARGE * side:
        return
    if parts["residual_rms"] > UNEXPLAINED * side:
        why = (
            "no robot driving the square ends where these runs end (the closest misses "
            f"their centres by {parts['residual_rms']:.3g} m)"
        )
        raise ValueError(beyond_square_test(why, bench.e_max_syst, side))
    if parts.get("roots", 1.0) > 1.0:
        why = f"{parts['roots']:.0f} different robots driving the square end where these runs end"
        raise ValueError(beyond_square_test(why, bench.e_max_syst, side))


def _errors_of(angles: FloatArray, test: SquareTest) -> dict[str, float]:
    """``alpha``, ``beta``, ``E_b`` (Eq. 4.27) and ``E_d`` (an arc with ``E_b b``)."""
    alpha, beta = float(angles[0]), float(angles[1])
    E_b = float(E_b_from_alpha(alpha))
    E_d = float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase))
    return {"alpha": alpha, "beta": beta, "E_b": E_b, "E_d": E_d}


def exact_estimate(
    bench: Benchmark, test: SquareTest, runs: Sequence[Run] | None = None
) -> ErrorEstimate:
    """``alpha``, ``beta``, ``E_d``, ``E_b`` from the exact square geometry.

    ``runs`` are not used: the centres of gravity are all the geometry needs (the
    dispatch gives every square estimator the runs).

    Raises
    ------
    ValueError
        For large errors the geometry does not identify (:func:`check_identified`).
    """
    z, blocks = cg_blocks(bench)
    parts = exact_components(z, test)
    check_identified(parts, bench, test)
    # The fit's response to the centres, by the implicit function theorem at the solution
    # (Gauss-Newton's linearization): d(alpha, beta)/dz = (J^T J)^-1 J^T, J = d(ends)/d(a, b).
    angles = np.array([parts["alpha"], parts["beta"]])
    jac = jacobian(lambda p: exact_end_positions(float(p[0]), float(p[1]), test), angles)
    response = np.linalg.solve(jac.T @ jac, jac.T)
    errors, dofs = propagate_blocks(
        lambda v: _errors_of(angles + response @ (v - z), test), z, blocks, step=1e-7
    )
    return ErrorEstimate(
        method=EXACT.name,
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={"residual_rms": parts["residual_rms"]},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
        dof={k: dofs[k] for k in ("alpha", "beta", "E_d", "E_b")},
    )
