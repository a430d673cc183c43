"""The verdict on applying a correction, as the HTML page shows it (at its head).

:func:`verdict_section` is the page's first section: the last pass's verdict (apply;
apply with care: why; do not apply: why, and what to record instead), whose correction
is the one to apply now, and each earlier pass's in one line. :data:`WITHHELD` is what
the overlay section says instead of the overlay when the verdict is "do not apply".
"""

from __future__ import annotations

from html import escape
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from umbmark.calibration.passes import Holds, Passes
    from umbmark.calibration.verdict import Verdict

__all__ = ["CSS", "WITHHELD", "verdict_box", "verdict_section"]

#: The style of the verdict's box: green to apply, orange with care, red not to.
CSS = """
.apply { padding: .75rem 1rem; border-left: .4rem solid #2a7; background: #eefaf3; }
.apply.care { border-color: #c60; background: #fff6ec; }
.apply.do-not-apply { border-color: #c22; background: #fdeeee; }
"""


def verdict_box(verdict: Verdict, lead: str, capitalize: bool = True) -> str:
    """The verdict in its coloured box, after ``lead``: its reasons, and what instead."""
    reasons = "".join(f"<li>{escape(reason)}</li>\n" for reason in verdict.reasons)
    listed = f"<ul>\n{reasons}</ul>\n" if reasons else ""
    if verdict.instead:
        what = "Instead" if verdict.level == "do-not-apply" else "To be sure"
        listed += f'<p class="instead">{what}: {escape(verdict.instead)}.</p>\n'
    return (
        f'<div class="apply {verdict.level}" id="apply-verdict" data-level="{verdict.level}">'
        f'<p class="big">{escape(lead)}'
        f"{escape(verdict.words.capitalize() if capitalize else verdict.words)}</p>\n"
        f"{listed}</div>\n"
    )


def verdict_section(page: Passes) -> str:
    """The last pass's verdict in a box, and the earlier passes' in a line each; after a
    self-calibration (``page.holds``), what the controller holds first, the verdict of
    the pass it holds in the box, and every other pass in a line (applied or not)."""
    if page.holds is not None:
        return _holds_section(page, page.holds)
    n = len(page.passes)
    lead = "" if n == 1 else f"Pass {n}, the last: "
    earlier = "".join(
        f"<li>Pass {k}: {escape(one.verdict.words)}</li>\n"
        for k, one in enumerate(page.passes[:-1], 1)
    )
    return verdict_box(page.last.verdict, lead) + (f"<ul>\n{earlier}</ul>\n" if earlier else "")


def _named(k: int, labels: tuple[str, ...]) -> str:
    """The pass's name as the terminal says it, capitalized: ``Pass 2``, ``Verification``."""
    label = labels[k - 1]
    return label[:1].upper() + label[1:]


def _holds_section(page: Passes, holds: Holds) -> str:
    said = f'<p class="big" id="holds" data-pass="{holds.held or ""}">{escape(holds.words())}</p>\n'
    # the pass it holds; with none applied, the last pass's correction, to apply by hand
    shown = holds.held or len(page.passes)
    lead = f"{_named(shown, holds.labels)}, {holds.applied_words(shown)}; its verdict: "
    box = verdict_box(page.passes[shown - 1].verdict, lead, capitalize=False)
    lines = "".join(
        f"<li>{escape(_named(k, holds.labels))}: {escape(one.verdict.words)}; "
        f"{holds.applied_words(k)}</li>\n"
        for k, one in enumerate(page.passes, 1)
        if k != shown
    )
    return said + box + (f"<ul>\n{lines}</ul>\n" if lines else "")


#: What the overlay section says when the verdict is "do not apply" (not overridden).
WITHHELD = (
    '<p id="overlay-withheld">No overlay: the verdict is do not apply (its reasons head the '
    "page). <code>--override-verdict</code> writes it all the same.</p>\n"
)
#: What stands instead of the overlay of a calibration given no nominal geometry.
NO_NOMINAL = (
    '<p id="overlay-withheld">No overlay: no nominal geometry was given (wheelbase and wheel '
    "diameter); the diameters, wheelbase and mounting above are absolute.</p>\n"
)
