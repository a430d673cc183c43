"""The options of ``umbmark reproduce table1`` and ``fig4`` (of
:func:`umbmark.reproduce_table1` and :func:`umbmark.reproduce_fig4`), written once
(:class:`~umbmark.options.spec.Spec`), with their bounds. ``--seed`` is the simulator's
:data:`~umbmark.options.simulate.SEED` in ``table1``'s words; ``--force`` the shared
:data:`~umbmark.options.spec.FORCE`.

From these entries come the click options (:func:`umbmark.cli.click_options.spec_option`)
and the checks of ``seeds`` (:meth:`Spec.check`). ``--tape-thickness`` is in millimetres
and ``--leg-bend`` in degrees on the command line, in metres and radians in the library:
their bounds are checked by :mod:`umbmark.jobs.reproduce` in the library's units.
"""

from __future__ import annotations

from dataclasses import replace

from umbmark.options.simulate import SEED
from umbmark.options.spec import OUTPUTS, Bound, Spec

__all__ = [
    "FIG4_OPTIONS",
    "MAX_LEG_BEND",
    "MAX_SEEDS",
    "MAX_TAPE_THICKNESS",
    "REPRODUCE",
    "TABLE1_OPTIONS",
]

#: The section of ``reproduce``'s ``--help`` that lists its options.
OPTIONS = "Options"
#: Most seeds ``reproduce_table1`` runs: each costs about a second.
MAX_SEEDS = 1000
#: Thickest tape of ``reproduce_table1`` [m]: 0.4 mm gives return errors of 3.4 m on
#: the 4 m square before correction.
MAX_TAPE_THICKNESS = 0.0003
#: Largest leg bend of ``reproduce_fig4`` [deg].
MAX_LEG_BEND = 10.0

#: The options of ``umbmark reproduce table1`` (besides ``--json``), in ``--help`` order.
TABLE1_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "seeds",
        ("--seeds",),
        OPTIONS,
        f"Repetitions of every experiment (random seeds), 1 to {MAX_SEEDS} (about a second each).",
        kind="integer",
        default=10,
        bound=Bound("range", MAX_SEEDS, 1),
    ),
    replace(SEED, section=OPTIONS, help="Base seed (0 to 2^63-1)."),
    Spec(
        "tape_thickness",
        ("--tape-thickness",),
        OPTIONS,
        "Model the tape of experiments 7 and 8 by its physical thickness [mm] (for example "
        f"0.15; at most {MAX_TAPE_THICKNESS * 1000:g}) instead of sizing it by the paper's "
        "figures before correction.",
        kind="number",
        unit="mm",
    ),
)

#: The options of ``umbmark reproduce fig4`` (besides ``--json`` and ``--force``).
FIG4_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "plot",
        ("--plot",),
        OUTPUTS,
        "Draw the paths of the tuned robot (Figs. 4 and 5) to a .png, .svg or .pdf file.",
        kind="file",
    ),
    Spec(
        "leg_bend",
        ("--leg-bend",),
        OPTIONS,
        "How much each leg bends left [deg].",
        kind="number",
        default=1.0,
        unit="deg",
    ),
)

#: The options of ``reproduce`` by keyword.
REPRODUCE: dict[str, Spec] = {spec.name: spec for spec in TABLE1_OPTIONS + FIG4_OPTIONS}
