"""TUM trajectory files (``timestamp tx ty tz qx qy qz qw``), as evo reads them.

Planar poses become 3-D ones with ``z = 0`` and a rotation about z, in the run's start
frame. Every file of a run has the same timestamps, one per wheel sample (the truth file
only those with ground truth), so that ``evo_ape tum truth.tum calibrated.tum`` matches
them exactly. The timestamps are, by default, the recording's own (``time="recording"``:
a bag's header or receive times, a run log's CSV time), so that evo can also associate
them with other trajectories of the same recording; ``time="run"`` writes seconds from
the run's start instead.
"""

from __future__ import annotations

import io
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Literal, cast

import numpy as np
from numpy.typing import NDArray

from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError, option
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.options.spec import TUM_TIME

__all__ = ["TUM_TIMES", "TumTime", "check_tum_time", "format_tum", "write_tum_runs"]

TumTime = Literal["recording", "run"]
#: The timestamps a TUM export can have (``--tum-time``, :mod:`umbmark.options.spec`).
TUM_TIMES = cast("tuple[TumTime, ...]", TUM_TIME.choices)


def check_tum_time(time: str) -> TumTime:
    """``time`` if it is one of :data:`TUM_TIMES`.

    Raises
    ------
    InputError
        Naming the option ``tum_time`` and the choices.
    """
    if time == "recording":
        return "recording"
    if time == "run":
        return "run"
    raise InputError(f"{option('tum_time', repr(time))}: use recording or run")


def format_tum(time: NDArray[np.float64], poses: NDArray[np.float64]) -> str:
    """TUM text of planar poses.

    Parameters
    ----------
    time : array, shape (n,)
        Timestamps [s]; written with nanosecond digits.
    poses : array, shape (n, 3)
        ``x, y`` [m], ``theta`` [rad]; rows with NaN are left out.
    """
    keep = np.all(np.isfinite(poses), axis=1)
    half = 0.5 * poses[keep, 2]
    rows = np.column_stack(
        [
            time[keep],
            poses[keep, 0],
            poses[keep, 1],
            np.zeros(half.size),
            np.zeros(half.size),
            np.zeros(half.size),
            np.sin(half),
            np.cos(half),
        ]
    )
    out = io.StringIO()
    out.write("# timestamp tx ty tz qx qy qz qw\n")
    np.savetxt(out, rows, fmt="%.9f")
    return out.getvalue()


def _slug(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", label).strip("_") or "run"


def write_tum_runs(
    folder: str | Path,
    runs: Sequence[Run],
    odometry: Mapping[str, WheelParams],
    *,
    time: TumTime = "recording",
) -> list[Path]:
    """Write ``<run>_truth.tum`` and ``<run>_<name>.tum`` for each odometry parameter set.

    Parameters
    ----------
    folder : path
        Where to write; made if missing.
    runs : sequence of Run
        Runs with their time series (``run.log``).
    odometry : mapping of str to WheelParams
        The parameter sets to integrate the odometry with, by name (``nominal``,
        ``calibrated``): one file each.
    time : {"recording", "run"}
        Timestamps: the recording's own (``log.start + log.time`` [s]) or seconds from
        the run's start (``log.time``).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    InputError
        If the folder cannot be made, or a run has no time series.
    """
    time = check_tum_time(time)
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot be made ({exc.strerror or exc})", source=folder) from None
    written = []
    for run in runs:
        if run.log is None:
            raise InputError(f"{run.label} has no time series to write", source=folder)
        stem = _slug(run.label)
        truth = run.log.truth
        if not run.log.headings:  # a position-only reference: no orientation, identity
            truth = np.column_stack([truth[:, :2], np.where(run.log.matched, 0.0, np.nan)])
        files = {f"{stem}_truth.tum": truth}
        for name, params in odometry.items():
            files[f"{stem}_{name}.tum"] = run.log.odometry(params)
        stamps = run.log.time + run.log.start if time == "recording" else run.log.time
        for filename, poses in files.items():
            path = folder / filename
            atomic_write_text(path, format_tum(stamps, poses))
            written.append(path)
    return written
