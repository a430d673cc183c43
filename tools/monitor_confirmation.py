"""How far a robot drives before the monitor confirms a wheel changed, with a stretch that
turned too little giving ``E_d`` and ``E_s`` from the window's wheelbase, and without.

The simulated warehouse robot (:mod:`umbmark.monitor.simulated`: ordinary missions, a 10 Hz
laser and 50 Hz wheels, no IMU, as the ROS change tests drive) has its right wheel made
``--wheel-change`` smaller at ``--change-after`` minutes. For each seed the core
(:class:`umbmark.monitor.core.Monitor`) is fed twice on the same messages:

- **held**: as the monitor runs, where a stretch's own motion fixes no wheelbase its
  ``E_d`` and ``E_s`` come from the window's (:mod:`umbmark.estimators.scan_radii`);
- **without**: such a stretch gives nothing, as before (``Held.of`` made to give None).

Printed per seed and mode:

- the metres driven from the change to its confirmation, and the figure confirmed;
- the stretches with an estimate;
- the changes confirmed before the wheel was changed, and those of other figures, which
  are false flags.

    PYTHONPATH=src python tools/monitor_confirmation.py --seeds 6
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from unittest import mock  # noqa: E402

from umbmark.monitor import core as core_module  # noqa: E402
from umbmark.monitor.core import Monitor  # noqa: E402
from umbmark.monitor.setup import MonitorSetup  # noqa: E402
from umbmark.monitor.simulated import NOMINAL, SimChange, SimRobotSetup, feed, messages  # noqa: E402
from umbmark.robot.base import DriveParams, Pose2D  # noqa: E402

#: The figures a wheel changed moves (``E_d = D_R / D_L``, ``E_s`` their mean).
WHEEL_FIGURES = ("E_d", "E_s")


@dataclass
class Outcome:
    """One run: metres from the change to its confirmation (nan: none), the figure, the
    stretches with an estimate and those that gave nothing, the false flags."""

    metres: float
    figure: str
    stretches: int
    empty: int
    false: list[str]


def run(seed: int, minutes: float, change_after: float, wheel: float, held: bool) -> Outcome:
    """The core over one simulated robot whose right wheel changed (module notes)."""
    e_d, e_b, e_s = SimRobotSetup().errors
    at = 60.0 * change_after
    right = 1.0 + wheel  # the right wheel's diameter: E_d and E_s follow (jobs/monitor.py)
    changed = (e_d * right, e_b, e_s * (1.0 + e_d * right) / (1.0 + e_d))
    sim = SimRobotSetup(seed=seed, imu_rate=0.0, changes=(SimChange(at, errors=changed),))
    setup = MonitorSetup("wheel", DriveParams(NOMINAL[0], 0.5 * NOMINAL[1]), Pose2D(*sim.stated),
                         inputs=("wheels", "scan"))  # fmt: skip
    patch = mock.patch.object(core_module.Held, "of", return_value=None) if not held else None
    if patch is not None:
        patch.start()
    try:
        core = Monitor(setup)
        at_change, confirmed_at, figure, false = math.nan, math.nan, "", []
        seen = 0
        for message, _ in messages(sim, 60.0 * minutes):
            if message.time > 60.0 * minutes:
                break
            if math.isnan(at_change) and message.time >= at:
                at_change = core.odometer
            feed(core, message)
            if len(core.confirmed) == seen:
                continue
            for change in list(core.confirmed.values())[seen:]:
                if math.isnan(at_change) or change.figure not in WHEEL_FIGURES:
                    false.append(f"{change.figure} at {core.odometer:.0f} m")
                elif math.isnan(confirmed_at):
                    confirmed_at, figure = core.odometer, change.figure
            seen = len(core.confirmed)
    finally:
        if patch is not None:
            patch.stop()
    empty = core.left_out.get("stretch determined nothing", 0)
    return Outcome(confirmed_at - at_change, figure, core.stretches, empty, false)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--minutes", type=float, default=14.0, help="robot time per run")
    parser.add_argument("--change-after", type=float, default=5.0, help="[min]")
    parser.add_argument("--wheel-change", type=float, default=-0.006,
                        help="the right wheel's diameter ratio less 1")  # fmt: skip
    args = parser.parse_args()
    if not (1 <= args.seeds <= 100 and 0.0 < args.change_after < args.minutes <= 600.0):
        parser.error("--seeds 1-100, 0 < --change-after < --minutes <= 600")
    cpu = time.process_time()
    found: dict[str, list[float]] = {"held": [], "without": []}
    print("seed  mode      confirmed after [m]  figure  stretches  gave nothing  false flags")
    for seed in range(1, args.seeds + 1):
        for mode in ("held", "without"):
            out = run(seed, args.minutes, args.change_after, args.wheel_change, mode == "held")
            found[mode].append(out.metres)
            metres = "never" if math.isnan(out.metres) else f"{out.metres:.0f}"
            print(f"{seed:4d}  {mode:8s}  {metres:>19s}  {out.figure or '-':6s}  "
                  f"{out.stretches:9d}  {out.empty:12d}  {', '.join(out.false) or 'none'}",
                  flush=True)  # fmt: skip
            print(
                f"  ({time.process_time() - cpu:.0f} s of CPU so far)", file=sys.stderr, flush=True
            )
    for mode, metres in found.items():
        kept = [m for m in metres if not math.isnan(m)]
        if kept:
            median = statistics.median(kept)
            print(f"{mode}: confirmed in {len(kept)} of {len(metres)} runs, after "
                  f"{min(kept):.0f}-{max(kept):.0f} m (median {median:.0f} m)")  # fmt: skip
        else:
            print(f"{mode}: never confirmed in {len(metres)} runs")
    print(f"({time.process_time() - cpu:.0f} s of CPU)")


if __name__ == "__main__":
    main()
