"""The HTML page of UMBmark passes on one robot, written to a file: its name checked
before anything is computed (:func:`check_page_output`), then written whole
(:func:`write_passes_page`). ``umbmark report -o`` and the self-calibration's
``report.html`` write it."""

from __future__ import annotations

import os
from pathlib import Path

from umbmark.calibration.passes import Passes
from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError
from umbmark.outputs.files import OutputPlan

__all__ = ["check_page_output", "write_passes_page"]

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
