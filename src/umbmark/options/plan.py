"""The options of ``umbmark plan`` (of :func:`umbmark.plan`), written once
(:class:`~umbmark.options.spec.Spec`): name, flags, section of ``--help``, help, kind,
default, unit and bound, with the plan's bounds and defaults.

From these entries come ``umbmark plan``'s click options
(:func:`umbmark.cli.click_options.spec_option`), the defaults of :func:`umbmark.plan` and
the checks of each value (:meth:`Spec.check`, in :mod:`umbmark.jobs.plan` and
:mod:`umbmark.calibration.plan`). ``--wheelbase`` and ``--side-length`` are the shared
:data:`~umbmark.options.spec.WHEELBASE` and :data:`~umbmark.options.spec.SIDE_LENGTH`
in the plan's words. What stays a check of its own: the scatter (its hint in metres), the
reading error (at most the scatter), the targets (strictly between 0 and 1), and the
rules between options.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Literal, TypeAlias

from umbmark.core.bounds import MAX_SIDE_LENGTH
from umbmark.options.spec import SIDE_LENGTH, TEST, WHEELBASE, Bound, Spec

__all__ = [
    "DEFAULT_MARGIN",
    "DEFAULT_WHEELBASE",
    "MAX_MARGIN",
    "MAX_PLAN_RUNS",
    "NOISE_MODELS",
    "PLAN",
    "PLAN_OPTIONS",
    "Noise",
]

Noise: TypeAlias = Literal["slip", "tape"]
#: The noise models of :func:`umbmark.plan`, the default first.
NOISE_MODELS: tuple[Noise, ...] = ("slip", "tape")
#: Most runs per direction a plan predicts for or recommends.
MAX_PLAN_RUNS = 100
#: Room around the square that the robot and the start area need [m] ...
DEFAULT_MARGIN = 0.6
#: ... and the most it may be [m].
MAX_MARGIN = 5.0
#: Wheelbase of a plan without one [m] (nor a previous result's).
DEFAULT_WHEELBASE = 0.34

#: The options of ``umbmark plan``, in the order ``--help`` lists them.
PLAN_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "scatter",
        ("--scatter",),
        TEST,
        "Standard deviation of the return error per axis [m], as measured (a previous "
        "calibration's spread; the paper's runs: about 0.01).",
        kind="number",
        unit="m",
    ),
    Spec(
        "previous",
        ("--from",),
        TEST,
        "A previous calibrate --json result: its scatter (std_cw, std_ccw), the side it was "
        "measured on and its wheelbase.",
        kind="file",
    ),
    Spec(
        "noise",
        ("--noise",),
        TEST,
        "slip: scatter driven by the path (x and y correlated, growing with the side); tape: "
        "a reading error only (independent, the same on any side).",
        kind="choice",
        default=NOISE_MODELS[0],
        choices=NOISE_MODELS,
    ),
    Spec(
        "scatter_side",
        ("--scatter-side",),
        TEST,
        "Side of the square the scatter was measured on [m] (default: the planned side; "
        "--from: the result's).",
        kind="number",
        unit="m",
        bound=Bound("length", MAX_SIDE_LENGTH),
    ),
    Spec(
        "reading_error",
        ("--reading-error",),
        TEST,
        "slip: the part of the scatter per axis [m] that is a reading or placement error "
        "(independent in x and y, the same on any side).",
        kind="number",
        default=0.0,
        unit="m",
    ),
    replace(
        WHEELBASE,
        section=TEST,
        help=f"Wheelbase [m] (default: the --from result's, else {DEFAULT_WHEELBASE:g}).",
    ),
    replace(SIDE_LENGTH, help="Side of the square [m]: with --runs, predict instead of recommend."),
    Spec(
        "runs",
        ("--runs", "-n"),
        TEST,
        "Runs per direction.",
        kind="integer",
        bound=Bound("range", MAX_PLAN_RUNS, 2),
    ),
    Spec(
        "floor",
        ("--floor",),
        TEST,
        "Side of the free floor [m]: recommend the square that fits.",
        kind="number",
        unit="m",
        bound=Bound("length", MAX_SIDE_LENGTH + 5.0),
    ),
    Spec(
        "margin",
        ("--margin",),
        TEST,
        "Room the robot and the start area need beyond the square [m].",
        kind="number",
        default=DEFAULT_MARGIN,
        unit="m",
        bound=Bound("range", MAX_MARGIN, 0.0),
    ),
    Spec("target_E_d", ("--target-E-d",), TEST, "Standard error of E_d wanted.", kind="number"),
    Spec("target_E_b", ("--target-E-b",), TEST, "Standard error of E_b wanted.", kind="number"),
    Spec(
        "target_e_max",
        ("--target-e-max",),
        TEST,
        "E_max,syst [m] to reach: 3 x SEM must stay below it.",
        kind="number",
        unit="m",
    ),
)

#: The options of ``plan`` by keyword.
PLAN: dict[str, Spec] = {spec.name: spec for spec in PLAN_OPTIONS}
