"""What the self-calibration and ``umbmark report`` write of passes: the HTML page of
UMBmark passes on one robot, its name checked before anything is computed
(:func:`check_page_output`), then written whole (:func:`write_passes_page`); and the
controller overlay of the pass the controller holds (:func:`write_overlay`)."""

from __future__ import annotations

import os
from pathlib import Path

from umbmark.calibration.passes import Passes
from umbmark.calibration.result import CalibrationResult
from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError
from umbmark.outputs.files import OutputPlan

__all__ = ["check_page_output", "write_overlay", "write_passes_page"]

_HTML = (".html", ".htm")


def write_passes_page(page: Passes, output: str | os.PathLike[str], *, force: bool = False) -> Path:
    """Write the page of ``page`` (:func:`umbmark.outputs.html_report.passes_html`) to
    ``output`` (.html or .htm), atomically; a file that exists is replaced only with
    ``force``.

    Raises
    ------
    InputError
        For a name that is not .html, an input's name, a file that cannot be written, or
        one that exists (without ``force``).
    """
    from umbmark.outputs.html_report import passes_html

    inputs = [s for p in page.passes for s in p.sources]
    path = check_page_output(output, inputs, force=force)
    atomic_write_text(path, passes_html(page))
    return path


def check_page_output(
    output: str | os.PathLike[str], inputs: list[str], *, force: bool = False
) -> Path:
    """Check the page's file name (``-o``) before anything is computed.

    Raises
    ------
    InputError
        If it does not end in .html or .htm, is an input or lies inside an input folder,
        cannot be written, or exists (without ``force``).
    """
    path = Path(output)
    target = path.resolve()
    for name in inputs:
        source = Path(name)
        if not source.exists():
            continue
        source = source.resolve()
        if target == source:
            raise InputError(
                f"-o {path} would overwrite an input ({source}); write the page elsewhere"
            )
        if source.is_dir() and target.is_relative_to(source):
            raise InputError(
                f"-o {path} is inside an input folder ({source}); write the page elsewhere"
            )
    if path.suffix.lower() not in _HTML:
        raise InputError(f"-o {path}: the file name should end in .html or .htm")
    OutputPlan.of(report=path, force=force)  # a writable folder, new unless force
    return path


def write_overlay(
    result: CalibrationResult, output: str | os.PathLike[str], *, force: bool = False
) -> Path:
    """Write the ros2_control overlay of ``result``'s new parameters to ``output``,
    atomically; a file that exists is replaced only with ``force``.

    Raises
    ------
    InputError
        For an input's name, a file that cannot be written or that exists (without
        ``force``), or a result whose verdict is "do not apply" (unless it was forced).
    """
    if result.overlay_withheld:
        raise InputError(f"{output}: {result.verdict.line()}", source=result.source)
    plan = OutputPlan.of(force=force, inputs=result.sources, yaml=output)
    assert plan.yaml is not None
    atomic_write_text(plan.yaml, result.overlay_yaml())
    return plan.yaml
