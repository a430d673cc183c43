"""The report job: UMBmark passes on one robot as one self-contained HTML page.

:func:`report` is what ``umbmark report`` does. Each source is one **pass** of UMBmark on
the same robot, in the order driven: pass 1 the runs before any correction, pass 2 the
runs driven after applying pass 1's correction, and so on. Every pass is calibrated on
its own (:func:`umbmark.calibrate`); from pass 2 on, the parameters active during the
runs are the previous pass's new ones. With a single pass of recorded runs the page also
shows the *predicted* after: the same runs' wheel data integrated again with the new
parameters (what :func:`umbmark.replay` does), which is a prediction, not a measured pass.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.calibration.passes import Passes, calibrate_passes, predict_after
from umbmark.core.errors import InputError, option, python_api
from umbmark.estimators.registry import DEFAULT
from umbmark.outputs.passes_page import check_page_output, write_passes_page
from umbmark.runs.read import RunSource, source_name
from umbmark.runs.read_options import ReadOptions, SourceOptions

if TYPE_CHECKING:
    from typing_extensions import Unpack

    from umbmark.calibration.validation import ValidationReport

__all__ = ["MAX_PASSES", "PassesReport", "report"]

#: Most passes one page holds (the paper needed two; a few more are plausible).
MAX_PASSES = 10
_HTML = (".html", ".htm")


@dataclass(frozen=True, repr=False)
class PassesReport(Passes):
    """UMBmark passes on one robot (:class:`umbmark.calibration.passes.Passes`), and the
    page about them."""

    def html(self) -> str:
        """The self-contained HTML page (what ``umbmark report -o`` writes)."""
        from umbmark.outputs.html_report import passes_html

        return passes_html(self)

    @python_api
    def write(self, output: str | os.PathLike[str], *, force: bool = False) -> Path:
        """Write :meth:`html` to ``output`` (.html or .htm), atomically; a file that exists
        is replaced only with ``force``.

        Raises
        ------
        InputError
            For a name that is not .html, an input's name, a file that cannot be
            written, or one that exists (without ``force``).
        """
        return write_passes_page(self, output, force=force)


def report(
    source: RunSource,
    *more_passes: RunSource,
    side_length: float | None = None,
    wheelbase: float | None = None,
    method: str = DEFAULT.name,
    fit_truth_offset: bool = False,
    validate: bool = False,
    output: str | os.PathLike[str] | None = None,
    force: bool = False,
    override_verdict: bool = False,
    command: str | None = None,
    **options: Unpack[SourceOptions],
) -> PassesReport:
    """UMBmark passes on one robot as one self-contained HTML page.

    What ``umbmark report`` does, with the same options as keywords (lengths in metres,
    angles in radians).

    Parameters
    ----------
    source, *more_passes : path or sequence of Run
        One source per pass, in the order driven: pass 1 the runs before any correction,
        pass 2 the runs driven after applying pass 1's correction, ... Each is read and
        calibrated as :func:`umbmark.calibrate` does, and must hold square runs in both
        directions.
    side_length, wheelbase, method, fit_truth_offset, override_verdict :
        As for :func:`umbmark.calibrate`, for every pass (``method="auto"`` chooses
        for each pass on its own; ``override_verdict`` shows the overlay of a pass whose
        verdict is "do not apply").
    force : bool
        Replace ``output`` if it exists; nothing else.
    validate : bool
        Add :func:`umbmark.validate` of the last pass (held-out replay of its recorded
        runs) to the page.
    output : path, optional
        Write the page here (.html or .htm); checked before anything is read.
    command : str, optional
        The command line or call to state in the provenance.
    **options
        How to read the sources (:class:`umbmark.runs.read_options.ReadOptions`). The
        ``current_*`` parameters say what was active during pass 1; from pass 2 on, the
        previous pass's new ``c_L``, ``c_R`` and ``wheel_separation_multiplier`` are taken
        as active (they override ``current_*``; a note says so).

    Returns
    -------
    PassesReport

    Raises
    ------
    InputError
        Bad input: one line naming the file (or flag) and the problem; a pass without
        square runs in both directions is bad input here.

    Examples
    --------
    >>> page = umbmark.report("before.csv", "after.csv", side_length=4, wheelbase=0.34,
    ...                       unit="mm", output="umbmark.html")
    >>> page.e_max_syst  # [m], before and after
    """
    sources = (source, *more_passes)
    if len(sources) > MAX_PASSES:
        raise InputError(f"{len(sources)} passes: give at most {MAX_PASSES}, one source each")
    names = [source_name(s) for s in sources]
    current = options.get("current_params")
    if output is not None:
        check_page_output(
            output, [*names, *([] if current is None else [str(current)])], force=force
        )
    passes, pass_options = calibrate_passes(
        sources,
        options,
        side_length=side_length,
        wheelbase=wheelbase,
        method=method,
        fit_truth_offset=fit_truth_offset,
        override_verdict=override_verdict,
    )
    predicted = predict_after(passes[0]) if len(passes) == 1 else None
    validation = None
    if validate:
        validation = _validate(sources[-1], side_length, wheelbase, pass_options)
    page = PassesReport(
        passes=tuple(passes), predicted=predicted, validation=validation, command=command
    )
    if output is not None:
        page.write(output, force=force)
    return page


def _validate(
    source: RunSource,
    side_length: float | None,
    wheelbase: float | None,
    options: SourceOptions,
) -> ValidationReport:
    """The held-out validation of one pass's source (a path of recorded runs), as
    :func:`umbmark.validate` makes it."""
    from umbmark.calibration.heldout import validate_read
    from umbmark.runs.active import read_each

    if not isinstance(source, (str, os.PathLike)):
        raise InputError(
            f"{option('validate')} replays recorded runs: give the pass as a file or folder"
        )
    read = read_each(
        [source], ReadOptions.of(options), wheelbase=wheelbase, side_length=side_length
    )
    return validate_read(read)
