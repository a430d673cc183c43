"""TUM trajectory files (``timestamp tx ty tz qx qy qz qw``), as evo reads them.

Planar poses become 3-D ones with ``z = 0`` and a rotation about z. Timestamps are
seconds from the run's start, the same for every file of a run, so that
``evo_traj tum truth.tum nominal.tum calibrated.tum --plot`` lines them up.
"""

from __future__ import annotations

import io
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..kinematics import WheelParams
from ..runs import Run
from .atomic import atomic_write_text

__all__ = ["format_tum", "write_tum_runs"]


def format_tum(time: NDArray[np.float64], poses: NDArray[np.float64]) -> str:
    """TUM text of planar poses.

    Parameters
    ----------
    time : array, shape (n,)
        Seconds.
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
    folder: str | Path, runs: Sequence[Run], odometry: Mapping[str, WheelParams]
) -> list[Path]:
    """Write ``<run>_truth.tum`` and ``<run>_<name>.tum`` for each odometry parameter set.

    Raises
    ------
    InputError
        If the folder cannot be made, or a run has no time series.
    """
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
        files = {f"{stem}_truth.tum": run.log.truth}
        for name, params in odometry.items():
            files[f"{stem}_{name}.tum"] = run.log.odometry(params)
        for filename, poses in files.items():
            path = folder / filename
            atomic_write_text(path, format_tum(run.log.time, poses))
            written.append(path)
    return written
