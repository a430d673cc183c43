"""Where a self-calibration stopped for a controller restart, and how it goes on.

A ROS 2 ``diff_drive_controller`` reads its multipliers only when it is configured: where
the routine cannot reconfigure it, it stops after a pass with the new parameters pending,
writes the overlay and ``selfcal-state.json`` in its folder, and ``umbmark selfcal
--resume DIR`` continues after a person restarted the controller. The state file holds the
test's settings, the passes driven (their folders, relative to DIR, and the parameters
active during each) and the parameters pending; :func:`pending_problem` says whether the
controller now holds them (a further pass is never driven on parameters not applied).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError
from umbmark.robot.base import DriveParams

__all__ = ["STATE_FILE", "SelfCalState", "pending_problem", "read_state", "write_state"]

#: The state file's name in the self-calibration's folder.
STATE_FILE = "selfcal-state.json"
#: Its format's version.
VERSION = 1
#: The longest state file read [bytes].
MAX_STATE = 1_000_000


@dataclass(frozen=True)
class SelfCalState:
    """A self-calibration stopped for a controller restart.

    Attributes
    ----------
    settings : dict
        ``side_length`` [m], ``runs``, ``measure``, ``max_passes``, ``verify``.
    passes : tuple of (str, str, DriveParams)
        Each pass driven: its label, its folder (relative to the state's folder), the
        parameters active during it.
    pending : DriveParams
        The parameters the controller must hold when the routine goes on.
    """

    settings: dict[str, Any]
    passes: tuple[tuple[str, str, DriveParams], ...]
    pending: DriveParams


def write_state(folder: Path, state: SelfCalState) -> Path:
    """Write ``folder/selfcal-state.json`` atomically; returns its path."""
    data = {
        "version": VERSION,
        "settings": state.settings,
        "passes": [
            {"label": label, "folder": where, "params": asdict(params)}
            for label, where, params in state.passes
        ],
        "pending": asdict(state.pending),
    }
    path = folder / STATE_FILE
    atomic_write_text(path, json.dumps(data, indent=2) + "\n")
    return path


def _params(data: object, path: Path) -> DriveParams:
    names = DriveParams.__dataclass_fields__
    if not isinstance(data, dict) or set(data) != set(names):
        raise InputError("has parameters without the controller's five values", source=path)
    values = {k: data[k] for k in names}
    for k, v in values.items():
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not 0.0 < v < math.inf:
            raise InputError(f"has {k} {v!r}, not a positive number", source=path)
    return DriveParams(**{k: float(v) for k, v in values.items()})


def read_state(folder: Path) -> SelfCalState:
    """The state a stopped self-calibration left in ``folder``.

    Raises
    ------
    InputError
        No state file there (nothing to resume), or one that cannot be read.
    """
    path = folder / STATE_FILE
    if not path.is_file():
        raise InputError(
            f"has no {STATE_FILE}: it is not a self-calibration stopped for a controller restart",
            source=folder,
        )
    if path.stat().st_size > MAX_STATE:
        raise InputError(f"is larger than {MAX_STATE} bytes", source=path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"is not JSON ({exc})", source=path) from None
    if not isinstance(data, dict) or data.get("version") != VERSION:
        raise InputError(f"is not a version {VERSION} self-calibration state", source=path)
    settings, passes = data.get("settings"), data.get("passes")
    if not isinstance(settings, dict) or not isinstance(passes, list):
        raise InputError("has no settings or passes", source=path)
    read = []
    for p in passes:
        if not isinstance(p, dict) or not all(
            isinstance(p.get(k), str) for k in ("label", "folder")
        ):
            raise InputError("has a pass without its label and folder", source=path)
        if Path(p["folder"]).is_absolute() or ".." in Path(p["folder"]).parts:
            raise InputError(f"has a pass folder {p['folder']!r} outside it", source=path)
        read.append((p["label"], p["folder"], _params(p.get("params"), path)))
    return SelfCalState(dict(settings), tuple(read), _params(data.get("pending"), path))


def pending_problem(held: DriveParams, pending: DriveParams) -> str | None:
    """Why the controller does not hold the pending multipliers (None: it does, to 1e-6)."""
    wrong = []
    for name in (
        "wheel_separation_multiplier",
        "left_wheel_radius_multiplier",
        "right_wheel_radius_multiplier",
    ):
        want, got = getattr(pending, name), getattr(held, name)
        if not abs(got - want) <= 1e-6 * max(1.0, abs(want)):
            wrong.append(f"{name} {got:.6g}, not {want:.6g}")
    if not wrong:
        return None
    return "the controller holds " + "; ".join(wrong) + ": restart it on the overlay first"
