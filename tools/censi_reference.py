"""Check the scan-matching estimator against the published results of Censi et al. 2013.

The reference implementation (github.com/AndreaCensi/calibration, no licence: its files
are not part of umbmark) holds, in ``reference-output/``, the tuple files of its three
data sets (``lstraight``, ``l90``, ``lmov``: the laser mounted straight, turned by 90
degrees, moved) and of their three disjoint thirds (``X_0`` ... ``X_2``), and each
one's ``X_results.json``: the wheelbase ``axle``, the wheel diameters ``l_diam`` and
``r_diam``, the laser's mounting ``l_x``, ``l_y``, ``l_theta`` and the covariance of
``(r_L, r_R, b, l_x, l_y, l_theta)`` (printed to six significant digits).

For each data set this prints ours against theirs, the differences against the targets
(wheelbase and diameters within 0.02 mm, the laser's position within 0.5 mm, its yaw
within 0.1 degree), the standard errors of both, and the scatter of the three thirds'
estimates against the thirds' mean standard error (ours, and theirs).

Run: python tools/censi_reference.py FOLDER
(FOLDER: the reference's ``reference-output``, extracted anywhere outside the repository).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

import umbmark

SETS = ("lstraight", "l90", "lmov")
#: The nominal parameters of the reference's robot: its solver states E_b against 0.09 m.
WHEELBASE, DIAMETER = 0.09, 0.041
TARGET_MM = {"b": 0.02, "d_L": 0.02, "d_R": 0.02, "l_x": 0.5, "l_y": 0.5}
TARGET_DEG = 0.1


def ours(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Our ``(b, d_L, d_R, l_x, l_y, l_theta)`` and standard errors [m, rad]."""
    out = umbmark.calibrate(
        path, method="scan-matching", wheelbase=WHEELBASE, wheel_diameter=DIAMETER
    ).to_dict()
    se = out["standard_errors"]
    values = [out["wheelbase"], out["wheel_diameter_left"], out["wheel_diameter_right"]]
    errors = [se["wheelbase"], se["wheel_diameter_left"], se["wheel_diameter_right"]]
    return np.array(values + out["laser_pose"]), np.array(errors + [se[k] for k in LASER])


LASER = ("laser_x", "laser_y", "laser_yaw")


def theirs(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """The published ``(b, d_L, d_R, l_x, l_y, l_theta)`` and standard errors."""
    ref = json.loads(path.read_text())
    cov = np.sqrt(np.diag(np.array(ref["covariance"])))  # r_L, r_R, b, l_x, l_y, l_theta
    values = [ref["axle"], ref["l_diam"], ref["r_diam"], ref["l_x"], ref["l_y"], ref["l_theta"]]
    return np.array(values), np.array([cov[2], 2 * cov[0], 2 * cov[1], *cov[3:]])


NAMES = ("b", "d_L", "d_R", "l_x", "l_y", "yaw")


def shown(values: np.ndarray) -> str:
    """mm for lengths, degrees for the yaw."""
    return " ".join(f"{v * 1e3:9.4f}" for v in values[:5]) + f" {math.degrees(values[5]):9.4f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="the reference's reference-output folder")
    args = parser.parse_args()
    header = " ".join(f"{n:>9s}" for n in NAMES)
    print(f"units: mm, yaw in degrees; nominal b = {WHEELBASE} m, D = {DIAMETER} m")
    failed = 0
    for name in SETS:
        for part in (name, *(f"{name}_{k}" for k in range(3))):
            mine, my_se = ours(args.folder / f"{part}.tuple")
            ref, ref_se = theirs(args.folder / f"{part}_results.json")
            diff = mine - ref
            limits = np.array([*(TARGET_MM[n] * 1e-3 for n in NAMES[:5]), math.radians(0.1)])
            ok = np.abs(diff) <= limits
            failed += int(not ok.all())
            print(f"\n{part}{'':12s}{header}")
            print(f"  ours          {shown(mine)}")
            print(f"  published     {shown(ref)}")
            print(f"  difference    {shown(diff)}   {'within' if ok.all() else 'BEYOND'} target")
            print(f"  our s.e.      {shown(my_se)}")
            print(f"  their s.e.    {shown(ref_se)}")
        thirds = [ours(args.folder / f"{name}_{k}.tuple") for k in range(3)]
        spread = np.std([t[0] for t in thirds], axis=0, ddof=1)
        print(f"  {name} thirds: scatter of the three estimates {shown(spread)}")
        print(f"  {name} thirds: our mean s.e.                  "
              f"{shown(np.mean([t[1] for t in thirds], axis=0))}")  # fmt: skip
        their = np.mean([theirs(args.folder / f"{name}_{k}_results.json")[1] for k in range(3)], 0)
        print(f"  {name} thirds: their mean s.e.                {shown(their)}")
    print(f"\n{'all within the targets' if not failed else f'{failed} set(s) beyond a target'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
