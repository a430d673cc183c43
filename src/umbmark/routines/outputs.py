"""The files of a self-calibration's folder beside its passes' run logs: checked before
the robot moves (:func:`check_outputs`), written when it has stopped
(:func:`write_outputs`): the page of all passes and the overlay of what the controller
holds."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from umbmark.calibration.passes import Holds, Passes, calibrate_passes, predict_after
from umbmark.core.errors import InputError, option
from umbmark.outputs.calibration import CalibrationReport
from umbmark.outputs.files import OutputPlan
from umbmark.outputs.passes_page import write_passes_page
from umbmark.routines.record import OVERLAY_FILE, REPORT_FILE, clear_selfcal

__all__ = ["check_outputs", "write_outputs"]


def check_outputs(folder: Path | None, page: Path | None, force: bool) -> None:
    """Refuse, before the robot moves, a folder holding anything but an earlier
    self-calibration (and, without ``force``, anything at all), or a page that exists."""
    if folder is not None:
        OutputPlan.of(logs=folder, force=True)  # a folder, or one that can be made
        clear_selfcal(folder, remove=False)  # nothing but an earlier self-calibration
        if not force and folder.is_dir() and any(folder.iterdir()):
            raise InputError(
                "holds an earlier self-calibration: choose a new or empty folder, leave "
                f"{option('out')} out (umbmark selfcal then makes selfcal-ROBOT-2, ...), or pass "
                f"{option('force')} to replace it",
                source=folder,
                python="holds an earlier self-calibration: choose a new or empty folder, "
                "or pass force=True to replace it",
            )
    if page is not None and (folder is None or page.parent.resolve() != folder.resolve()):
        OutputPlan.of(report=page, force=force)


def write_outputs(
    folders: Sequence[Path],
    held: CalibrationReport | None,
    holds: Holds,
    folder: Path | None,
    page: Path | None,
    force: bool,
    controller: str | None = None,
    command: str | None = None,
) -> list[Path]:
    """The page of all passes (their run logs in ``folders``) [``folder/report.html``]
    and, in ``folder``, the overlay of ``held``, the pass the controller holds; checked
    before the robot moved (:func:`check_outputs`). The page's overlay is keyed by
    ``controller`` (None: the default) as ``held``'s is; ``command``: the command line
    that ran, for the page's provenance (None: made from Python)."""
    written: list[Path] = []
    if not folders:
        return written
    page = page or (None if folder is None else folder / REPORT_FILE)
    if page is not None:
        found, _ = calibrate_passes(
            folders, {} if controller is None else {"controller": controller}
        )
        predicted = predict_after(found[0]) if len(found) == 1 else None
        pages = Passes(passes=tuple(found), predicted=predicted, holds=holds, command=command)
        written.append(write_passes_page(pages, page, force=force))
    if held is not None and folder is not None:
        written += held.write(yaml=folder / OVERLAY_FILE, force=force)
    return written
