"""A reference the wheels' own odometry reproduces is no reference.

A ground truth computed from the wheels (the controller's odometry, published on any
topic or written into any column) follows the wheel angles exactly: its heading is a
constant times the right wheel's angle minus another times the left one's, and its path
is that heading integrated with the wheels' travel. Calibrating against it gives the
parameters it was computed with and return errors of rounding size (``E_max,syst =
0.0 mm``, ``3 x SEM = 0.0 mm``): nothing about the robot is measured.

:func:`check_not_reproduced` fits that odometry model to the reference, at the samples
where the reference and the wheels were stamped at the same instant, in closed form:

1. the heading: ``theta = a * phi_R - c * phi_L`` (linear least squares; ``a = r_R / b``,
   ``c = r_L / b``; any integration scheme turns the heading so);
2. the path: the odometry integrated with those radii over the nominal wheelbase, as an
   exact arc, a midpoint chord or Borenstein's segment (whichever fits best), scaled by
   one factor (radii and wheelbase scaled together), by linear least squares.

The reference was computed from the wheels when its heading fits to within rounding, a
residual under :data:`EXACT` rad per radian turned (root mean square), and its path
closely, under :data:`CLOSE` m per metre driven. It is refused when the fitted geometry is
the one the robot's odometry uses (the active parameters, or the nominal ones without the
wheel multipliers, each radius and the wheelbase to :data:`SAME_GEOMETRY`): calibrating
against it returns those parameters. One the wheels reproduce only with other radii or
another wheelbase is a noise-free reference of a robot with errors (a simulation without
noise or slip), the calibration itself: it is taken, with a note that it follows the
wheels without noise. The heading is what tells: whatever scheme and rate the
odometry was integrated with, a heading computed from the wheel angles is that linear
function of them, where any measured reference strays far more: motion capture by its
noise (1e-4 rad and more), a physics simulator by its wheels' slip, and even a
noise-free simulation by the quantization of its encoders (umbmark's ``simulate
--noise-free``: 2e-7 rad per radian, 190 times :data:`EXACT`; a simulated TurtleBot3's
model states: 3e-6). The README's ``simulate --bag`` against its ``/odom`` leaves 4e-16
rad per radian and 7e-16 m per metre; a controller's odometry integrated at 100 Hz and
recorded with 33 Hz joint states 2e-15 and 2e-7 (the path integrated over the longer
steps, well under :data:`CLOSE`). Where the two are never stamped at the same instant the
check is silent: interpolating either one leaves more than rounding (and the runs then
come back with ``E_max,syst`` and ``3 x SEM`` of hundredths of a millimetre, which the
verdict refuses: :mod:`umbmark.calibration.verdict`).

Position-only references (a GNSS fix, a tracked point) measure no heading and are not
judged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.core.messages import info
from umbmark.model.kinematics import INTEGRATION_METHODS, WheelParams
from umbmark.model.recording import Recording, RunLog
from umbmark.sources.bag.truth.independence import REFERENCES

__all__ = ["CLOSE", "EXACT", "MIN_SAMPLES", "Reproduction", "check_not_reproduced", "reproduction"]


#: A heading residual under this share of the angle turned [rad/rad] is rounding: the
#: heading was computed from the wheel angles ...
EXACT = 1e-9
#: ... and a path residual under this share of the distance driven [m/m] is the
#: odometry's own integration (its scheme, its rate).
CLOSE = 1e-5
#: Fewer samples stamped at the same instant than this: not judged.
MIN_SAMPLES = 20
#: Most ratio of the two fitted wheel radii that is a robot's (either way).
RADIUS_RATIO = 2.0
#: A fitted radius or wheelbase within this share of the odometry's is the odometry's
#: (the fit finds a computed reference's geometry to 1e-9; a robot's errors are 1e-3).
SAME_GEOMETRY = 1e-5
#: Two stamps this close [s] are the same instant (a float's rounding of epoch seconds).
SAME_INSTANT = 1e-6


@dataclass(frozen=True)
class Reproduction:
    """How closely the wheels' odometry reproduces a reference.

    Attributes
    ----------
    heading_rms : float
        Root-mean-square heading residual [rad] of the best heading fit.
    position_rms : float
        Root-mean-square position residual [m] of the best path fit.
    turned, driven : float
        The angle the reference turned [rad] and the distance it moved [m] over the
        samples compared.
    r_left, r_right, wheelbase : float
        The best-fitting wheel radii and wheelbase [m].
    samples : int
        The samples compared.
    """

    heading_rms: float
    position_rms: float
    turned: float
    driven: float
    r_left: float
    r_right: float
    wheelbase: float
    samples: int

    @property
    def physical(self) -> bool:
        """The fitted geometry is a robot's: positive radii and wheelbase, the two radii
        within a factor of :data:`RADIUS_RATIO` (a degenerate fit to few or uninformative
        samples can match them exactly with negative ones)."""
        positive = min(self.r_left, self.r_right, self.wheelbase) > 0.0
        return positive and 1.0 / RADIUS_RATIO <= self.r_left / self.r_right <= RADIUS_RATIO

    def same_geometry(self, geometry: tuple[float, float, float]) -> bool:
        """The fitted radii and wheelbase are ``geometry`` ``(r_L, r_R, b)`` [m], each to
        :data:`SAME_GEOMETRY` of itself."""
        fitted = (self.r_left, self.r_right, self.wheelbase)
        return all(abs(f - g) <= SAME_GEOMETRY * g for f, g in zip(fitted, geometry, strict=True))

    @property
    def exact(self) -> bool:
        """The heading is rounding, the path close (see the module), by a robot's
        geometry (:attr:`physical`)."""
        return (
            self.physical
            and self.heading_rms <= EXACT * max(self.turned, 1.0)
            and self.position_rms <= CLOSE * max(self.driven, 1.0)
        )


def _same_instant(log: RunLog, truth_time: FloatArray) -> NDArray[np.bool_]:
    """Which samples of ``log`` have a reference sample stamped at the same instant."""
    t = log.start + log.time
    k = np.clip(np.searchsorted(truth_time, t), 1, truth_time.size - 1)
    nearest = np.minimum(np.abs(truth_time[k] - t), np.abs(truth_time[k - 1] - t))
    return np.asarray((nearest <= SAME_INSTANT) & log.matched)


def reproduction(
    logs: Sequence[RunLog], truth_time: FloatArray, params: WheelParams
) -> Reproduction | None:
    """The best fit of the wheels' odometry to the references of ``logs`` (runs with
    headings), at the samples stamped at the instants of ``truth_time`` (the reference's
    own sample times, shape (m,)); None with fewer than :data:`MIN_SAMPLES` of them."""
    chosen = [(log, _same_instant(log, truth_time)) for log in logs if log.headings]
    chosen = [(log, same) for log, same in chosen if np.count_nonzero(same) >= 2]
    if sum(int(np.count_nonzero(same)) for _, same in chosen) < MIN_SAMPLES:
        return None
    phi = np.vstack([log.wheel_angles[same] for log, same in chosen])
    ref = np.vstack([log.truth[same] for log, same in chosen])
    design = np.column_stack([phi[:, 1], -phi[:, 0]])
    (a, c), *_ = np.linalg.lstsq(design, ref[:, 2], rcond=None)
    heading_rms = float(np.sqrt(np.mean((design @ np.array([a, c]) - ref[:, 2]) ** 2)))
    base = params.wheelbase
    radius = 0.5 * params.wheel_diameter
    fitted = WheelParams(
        wheelbase=base,
        wheel_diameter=params.wheel_diameter,
        c_left=max(float(c) * base / radius, 1e-12),
        c_right=max(float(a) * base / radius, 1e-12),
    )
    best: tuple[float, float] | None = None
    for method in INTEGRATION_METHODS:
        path = np.vstack([log.odometry(fitted, method)[same, :2] for log, same in chosen])
        norm = float(np.sum(path**2))
        scale = float(np.sum(path * ref[:, :2])) / norm if norm > 0.0 else 1.0
        rms = float(np.sqrt(np.mean(np.sum((scale * path - ref[:, :2]) ** 2, axis=1))))
        if best is None or rms < best[0]:
            best = (rms, scale)
    assert best is not None
    position_rms, scale = best
    turned = sum(float(np.sum(np.abs(np.diff(log.truth[same, 2])))) for log, same in chosen)
    driven = sum(
        float(np.sum(np.hypot(*np.diff(log.truth[same, :2], axis=0).T))) for log, same in chosen
    )
    return Reproduction(
        heading_rms=heading_rms,
        position_rms=position_rms,
        turned=turned,
        driven=driven,
        r_left=scale * float(c) * base,
        r_right=scale * float(a) * base,
        wheelbase=scale * base,
        samples=int(ref.shape[0]),
    )


def _odometry_geometries(params: WheelParams) -> list[tuple[float, float, float]]:
    """``(r_L, r_R, b)`` [m] the robot's odometry may use: the active parameters, and the
    nominal ones (no wheel multipliers)."""
    radius = 0.5 * params.wheel_diameter
    active = (params.c_left * radius, params.c_right * radius, params.wheelbase)
    return [active, (radius, radius, params.wheelbase)]


def check_not_reproduced(
    recording: Recording, logs: Sequence[RunLog], params: WheelParams
) -> str | None:
    """Refuse the reference of ``recording`` if the odometry of its wheels reproduces it
    with the geometry the robot's odometry uses (see the module); ``logs`` are its runs,
    integrated with ``params`` (the active parameters, where the fit starts from).

    Returns
    -------
    str or None
        A note when the wheels reproduce the reference exactly, but only with another
        geometry than the odometry's: a noise-free reference of a robot with errors,
        accepted.

    Raises
    ------
    InputError
        One line naming the recording, its reference and the fit.
    """
    if recording.truth is None or not recording.truth.headings:
        return None
    found = reproduction(logs, recording.truth.time, params)
    if found is None or not found.exact:
        return None
    if not any(found.same_geometry(g) for g in _odometry_geometries(params)):
        return info(
            f"{recording.truth_name} follows the wheels without noise: with wheel radii "
            f"{1000 * found.r_left:.3f} and {1000 * found.r_right:.3f} mm and a wheelbase of "
            f"{1000 * found.wheelbase:.2f} mm the wheels give its heading to "
            f"{found.heading_rms:.1g} rad, not with the odometry's (a noise-free "
            "simulation's truth, or an odometry computed with other parameters than those "
            "given): it is taken as the reference, and the calibration is that geometry"
        )
    raise InputError(
        f"{recording.truth_name} reproduces the wheels' own odometry: with wheel radii "
        f"{1000 * found.r_left:.3f} and {1000 * found.r_right:.3f} mm and a wheelbase of "
        f"{1000 * found.wheelbase:.2f} mm the wheels give its heading to "
        f"{found.heading_rms:.1g} rad and its path to {1000 * found.position_rms:.1g} mm "
        f"(root mean square over {found.driven:.1f} m, {math.degrees(found.turned):.0f} deg "
        "turned): it was computed from the wheels (a controller's odometry), and calibrating "
        f"against it returns the parameters it was computed with, whatever the robot; {REFERENCES}",
        source=recording.where,
    )
