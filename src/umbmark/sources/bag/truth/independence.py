"""A ground truth must not be the odometry it judges.

Where the wheels are read back from the controller's odometry (``odom_topic`` or
``odom_tf``), a ground truth that *is* that odometry makes every estimate come out as
the parameters given (``E_d = E_b = 1``, return errors of rounding size): nothing is
measured. Three ways to be the same data are refused, each with its reason:

1. the same topic for both (:func:`check_distinct`);
2. the same transforms: a TF ground truth whose moving transforms are all among the
   odometry's own (``odom -> base_link`` both times, or ``map -> odom -> base_link``
   where ``map -> odom`` never moves) (:func:`check_chain`);
3. a ground truth that reproduces the odometry to within noise: after both are put in
   the frame of their first common sample, the root-mean-square distance between them is
   under :data:`REPRODUCED_SHARE` of the distance driven (:func:`check_not_reproduced`).
   The controller's ``/odom`` topic against its own ``odom -> base_link`` transform, or
   an EKF that fuses nothing but the wheel odometry, are caught here. An independent
   reference disagrees with an odometry by its noise and by the odometry's drift, which
   even a well calibrated robot accumulates at millimetres per metre.

Wheels read from joint states, encoder counts or wheel transforms are not judged by
these rules: a simulator's ground truth (Gazebo's ``p3d`` odometry, its model states, or a
diff-drive plugin whose ``/odom`` comes from the world pose) may agree closely with
perfect simulated wheels, and is a valid reference for them. A reference that the wheels'
odometry reproduces *exactly*, to rounding, whatever the wheels are read from and
whatever the topic (the controller's ``/odom`` against the ``/joint_states`` it was
computed from), is refused once the runs are found: :mod:`umbmark.runs.reproduced`.
"""

from __future__ import annotations

import math

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.core.geometry import relative_positions
from umbmark.model.recording import PoseSeries
from umbmark.sources.bag.truth.transforms import Edge, chain_steps

__all__ = [
    "INSTEAD",
    "REFERENCES",
    "REPRODUCED_SHARE",
    "check_chain",
    "check_distinct",
    "check_not_reproduced",
    "disagreement",
]

#: A ground truth closer to the odometry than this share of the distance driven (root
#: mean square over the recording; 1e-4 is 0.1 mm per metre) is that odometry.
REPRODUCED_SHARE = 1e-4
#: Shortest distance driven [m] over which the comparison means something.
MIN_DRIVEN = 0.5

#: What to give instead of a reference that is the odometry, in any format ...
REFERENCES = (
    "give a reference that does not come from the wheels (motion capture, a simulator's "
    "ground truth, RTK GPS, a localization such as AMCL)"
)
#: ... and in a bag (every refusal here ends with it).
INSTEAD = f"{REFERENCES}; umbmark info lists the candidates"


def _refuse(problem: str, src: str, python: str | None = None) -> InputError:
    """The refusal; ``python``: the problem as Python callers name the options."""
    why = (
        f"calibrating the odometry against itself gives E_d = E_b = 1 whatever the robot; {INSTEAD}"
    )
    return InputError(
        f"{problem}: {why}",
        source=src,
        python=None if python is None else f"{python}: {why}",
    )


def _frame(name: str) -> str:
    return name.strip().lstrip("/")


def check_distinct(
    truth_topic: str | None,
    tf_truth: tuple[str, str] | None,
    odom_topic: str | None,
    odom_tf: tuple[str, str] | None,
    src: str,
) -> None:
    """Refuse a ground truth that names the odometry's own topic or transform pair.

    Raises
    ------
    InputError
        Saying which option names what, and what to use instead.
    """
    if truth_topic is not None and odom_topic is not None and truth_topic == odom_topic:
        raise _refuse(
            f"the ground truth ({option('truth_topic', truth_topic)}) is the controller's "
            f"odometry the wheels are read from ({option('odom_topic', odom_topic)})",
            src,
        )
    if tf_truth is not None and odom_tf is not None:
        truth = {_frame(tf_truth[0]), _frame(tf_truth[1])}
        if truth == {_frame(odom_tf[0]), _frame(odom_tf[1])}:
            raise _refuse(
                f"the ground truth ({option('tf_parent', tf_truth[0])} "
                f"{option('tf_child', tf_truth[1])}) is the odometry's own transform "
                f"({option('odom_tf', f'{odom_tf[0]} {odom_tf[1]}')})",
                src,
                python=f"the ground truth (tf_parent={tf_truth[0]!r}, tf_child="
                f"{tf_truth[1]!r}) is the odometry's own transform (odom_tf={tuple(odom_tf)!r})",
            )


def _moving(steps: list[tuple[Edge, bool]]) -> set[tuple[str, str]]:
    """The pairs of the transforms of a chain that move."""
    out = set()
    for edge, _ in steps:
        if edge.static or edge.time.size < 2:
            continue
        if float(np.max(np.ptp(edge.poses, axis=0))) > 0.0:
            out.add((edge.parent, edge.child))
    return out


def check_chain(
    edges: dict[tuple[str, str], Edge],
    tf_truth: tuple[str, str],
    odom_tf: tuple[str, str],
    src: str,
) -> None:
    """Refuse a TF ground truth whose moving transforms are all the odometry's.

    Raises
    ------
    InputError
        Naming the transforms they share.
    """
    truth_steps = chain_steps(edges, _frame(tf_truth[0]), _frame(tf_truth[1]))
    odom_steps = chain_steps(edges, _frame(odom_tf[0]), _frame(odom_tf[1]))
    if truth_steps is None or odom_steps is None:
        return  # reading them says what is wrong
    truth, odometry = _moving(truth_steps), _moving(odom_steps)
    if truth and truth <= odometry:
        shared = ", ".join(f"{p} -> {c}" for p, c in sorted(truth))
        raise _refuse(
            f"the ground truth {tf_truth[0]} -> {tf_truth[1]} moves only through the "
            f"odometry's own transforms ({shared}; the others never move)",
            src,
        )


def disagreement(odometry: PoseSeries, truth: PoseSeries) -> tuple[float, float] | None:
    """How far ``truth`` strays from ``odometry``: the root-mean-square distance [m]
    between them, both in the frame of the first odometry sample inside the time both
    cover (the truth interpolated at the odometry's times), and the distance the
    odometry drove [m] over that time; None where they overlap in fewer than 2 samples.
    """
    t = odometry.time
    inside = (t >= truth.time[0]) & (t <= truth.time[-1])
    if np.count_nonzero(inside) < 2:
        return None
    t = t[inside]
    odo = odometry.poses[inside]
    ref = np.column_stack(
        [np.interp(t, truth.time, truth.poses[:, k]) for k in range(2)]
        + [np.interp(t, truth.time, np.unwrap(truth.poses[:, 2]))]
    )

    a = relative_positions(odo, float(odo[0, 2]))
    if truth.headings:
        b = relative_positions(ref, float(ref[0, 2]))
    else:  # no heading: the best rotation of the truth onto the odometry
        raw = relative_positions(ref, 0.0)
        angle = math.atan2(
            float(np.sum(raw[:, 0] * a[:, 1] - raw[:, 1] * a[:, 0])),
            float(np.sum(raw[:, 0] * a[:, 0] + raw[:, 1] * a[:, 1])),
        )
        b = relative_positions(raw, -angle)
    rms = float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))
    driven = float(np.sum(np.hypot(*np.diff(odo[:, :2], axis=0).T)))
    return rms, driven


def check_not_reproduced(odometry: PoseSeries, truth: PoseSeries, what: str, src: str) -> None:
    """Refuse a ground truth that reproduces the odometry the wheels come from.

    Parameters
    ----------
    odometry, truth : PoseSeries
        The controller's odometry and the ground truth as read.
    what : str
        The two, for the message (``ground truth /odometry/filtered and odometry /odom``).

    Raises
    ------
    InputError
        When the truth is closer to the odometry than :data:`REPRODUCED_SHARE` of the
        distance driven (over at least :data:`MIN_DRIVEN`).
    """
    found = disagreement(odometry, truth)
    if found is None:
        return
    rms, driven = found
    if driven < MIN_DRIVEN or rms >= REPRODUCED_SHARE * driven:
        return
    raise _refuse(
        f"the {what} agree to {1000 * rms:.3g} mm (root mean square) over {driven:.1f} m "
        f"driven, less than {1000 * REPRODUCED_SHARE:.1f} mm per metre: the ground truth "
        "reproduces the odometry the wheels are read from",
        src,
    )
