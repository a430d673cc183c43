"""The laser's mounting a scan-matching calibration found, in the forms a user applies it.

A calibration from motion intervals (:mod:`umbmark.calibration.scan`) fits the laser's
planar mounting ``x, y, yaw`` on the robot. :func:`mounting_forms` gives it as

- the URDF joint's ``<origin xyz="x y z" rpy="roll pitch yaw"/>`` of the laser (the
  laser's pose in the base frame; where the laser hangs under another link, the chain's
  last joint takes what is left of it);
- the arguments of ROS 2's ``static_transform_publisher`` (Humble and later: named
  flags ``--x .. --yaw``, ``--frame-id``, ``--child-frame-id``, radians);
- the arguments of ROS 1's ``static_transform_publisher`` (positional:
  ``x y z yaw pitch roll frame_id child_frame_id``: yaw first);
- the difference from the mounting the robot states now (TF, ``/tf_static``, its URDF)
  [mm, deg], and whether it lies outside the fit's 95 % interval.

The planar fit does not see the laser's height and tilt: ``z``, ``roll`` and ``pitch``
are the ones the robot states (0 where it states none, and the forms say so). Lengths
are written in metres to 0.1 mm, angles in radians to 1e-5 rad (0.0006 deg), as ROS
takes them.
"""

from __future__ import annotations

import math
import shlex
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from umbmark.model.scans import LaserMounting

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from umbmark.calibration.result import CalibrationResult

__all__ = ["AXES", "CSS", "MountingForms", "mounting_forms", "mounting_html"]

#: The fitted figures of the mounting: (component, name for people).
AXES = (("laser_x", "x"), ("laser_y", "y"), ("laser_yaw", "yaw"))


#: The style of the commands on a page: they wrap on a narrow page (and copy whole).
CSS = ".command { white-space: pre-wrap; overflow-wrap: anywhere; }\n"


def _metres(value: float) -> str:
    text = f"{value:.4f}"
    return "0.0000" if text == "-0.0000" else text


def _radians(value: float) -> str:
    text = f"{value:.5f}"
    return "0.00000" if text == "-0.00000" else text


def _wrap(angle: float) -> float:
    """``angle`` [rad] in ``(-pi, pi]``."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


@dataclass(frozen=True)
class MountingForms:
    """The fitted mounting, and the stated one it replaces.

    Attributes
    ----------
    fitted : LaserMounting
        ``x, y, yaw`` as fitted [m, m, rad]; the height, tilt and frames as stated.
    standard_errors : tuple of float
        One sigma of ``x, y, yaw`` [m, m, rad].
    intervals : tuple of (float, float)
        The 95 % intervals of ``x, y, yaw`` [m, m, rad].
    stated : LaserMounting or None
        The mounting the robot states now (None: not known).
    """

    fitted: LaserMounting
    standard_errors: tuple[float, float, float]
    intervals: tuple[tuple[float, float], ...]
    stated: LaserMounting | None

    @property
    def xyz_rpy(self) -> tuple[float, float, float, float, float, float]:
        """``x, y, z, roll, pitch, yaw`` [m, rad] to apply (``z``, roll, pitch stated)."""
        f = self.fitted
        z, roll, pitch = f.lift or (0.0, 0.0, 0.0)
        return f.x, f.y, z, roll, pitch, _wrap(f.yaw)

    def urdf_origin(self) -> str:
        """The laser joint's ``<origin xyz=".." rpy=".."/>`` [m, rad]."""
        x, y, z, roll, pitch, yaw = self.xyz_rpy
        xyz = " ".join(map(_metres, (x, y, z)))
        rpy = " ".join(map(_radians, (roll, pitch, yaw)))
        return f'<origin xyz="{xyz}" rpy="{rpy}"/>'

    def ros2_command(self) -> str:
        """ROS 2's (Humble and later) ``static_transform_publisher`` with named flags."""
        x, y, z, roll, pitch, yaw = self.xyz_rpy
        f = self.fitted
        return (
            f"ros2 run tf2_ros static_transform_publisher --x {_metres(x)} --y {_metres(y)} "
            f"--z {_metres(z)} --roll {_radians(roll)} --pitch {_radians(pitch)} "
            f"--yaw {_radians(yaw)} --frame-id {shlex.quote(f.base)} "
            f"--child-frame-id {shlex.quote(f.frame)}"
        )

    def ros1_command(self) -> str:
        """ROS 1's ``static_transform_publisher``: ``x y z yaw pitch roll frame child``."""
        x, y, z, roll, pitch, yaw = self.xyz_rpy
        f = self.fitted
        return (
            f"rosrun tf2_ros static_transform_publisher {_metres(x)} {_metres(y)} {_metres(z)} "
            f"{_radians(yaw)} {_radians(pitch)} {_radians(roll)} {shlex.quote(f.base)} "
            f"{shlex.quote(f.frame)}"
        )

    def difference(self) -> tuple[float, float, float] | None:
        """Fitted minus stated ``x, y, yaw`` [m, m, rad] (None: nothing stated)."""
        s = self.stated
        if s is None:
            return None
        f = self.fitted
        return f.x - s.x, f.y - s.y, _wrap(f.yaw - s.yaw)

    def outside(self) -> tuple[bool, bool, bool] | None:
        """Whether the stated ``x, y, yaw`` each lie outside the fit's 95 % interval
        (None: nothing stated)."""
        s = self.stated
        if s is None:
            return None
        f = self.fitted
        out = []
        for k, ((low, high), fit, stated) in enumerate(
            zip(self.intervals, (f.x, f.y, f.yaw), (s.x, s.y, s.yaw), strict=True)
        ):
            away = _wrap(stated - fit) if k == 2 else stated - fit
            out.append(not (low - fit <= away <= high - fit))
        return out[0], out[1], out[2]

    def verdict(self) -> str:
        """What to do with the fitted mounting, in one sentence."""
        outside = self.outside()
        difference = self.difference()
        if outside is None or difference is None:
            return (
                "no stated mounting of the laser was known to compare with: check the "
                "robot's against the fitted one below, and correct it where they differ"
            )
        named = [name for (_, name), o in zip(AXES, outside, strict=True) if o]
        dx, dy, dyaw = difference
        moved = (
            f"{math.hypot(dx, dy) * 1000:.1f} mm and {math.degrees(abs(dyaw)):.2f} deg from "
            "the stated one"
        )
        if not named:
            return (
                f"the fitted mounting lies {moved}, within the fit's 95 % intervals: the "
                "stated mounting is right, nothing to change"
            )
        return (
            f"the fitted mounting lies {moved}, outside the fit's 95 % interval in "
            f"{', '.join(named)}: correct the stated mounting (the URDF origin, or the static "
            "transform), as a wrong one bends maps and localization"
        )

    def lift_note(self) -> str:
        """Where ``z``, roll and pitch come from."""
        lift = self.fitted.lift
        if lift is None:
            return (
                "the planar fit does not see z, roll and pitch, and none was stated: 0 is "
                "written for them, put your laser's own"
            )
        return "z, roll and pitch as the robot states them (the planar fit does not see them)"

    def lines(self) -> list[str]:
        """The forms for a terminal, one a line (the commands whole, to copy)."""
        out = [f"Laser mounting: {self.verdict()}."]
        difference = self.difference()
        if difference is not None and self.stated is not None:
            s = self.stated
            dx, dy, dyaw = difference
            where = f" ({s.source})" if s.source else " by the robot"
            out.append(
                f"  stated{where}: x {s.x * 1000:.1f} mm, y {s.y * 1000:.1f} mm, yaw "
                f"{math.degrees(s.yaw):.3f} deg; fitted minus stated: x {dx * 1000:+.1f} mm, "
                f"y {dy * 1000:+.1f} mm, yaw {math.degrees(dyaw):+.3f} deg"
            )
        out += [
            f"  URDF joint origin of {self.fitted.frame}: {self.urdf_origin()}",
            f"  ROS 2: {self.ros2_command()}",
            f"  ROS 1: {self.ros1_command()}",
            f"  ({self.lift_note()}; metres and radians)",
        ]
        return out

    def to_dict(self) -> dict[str, Any]:
        """The forms as JSON (metres, radians)."""
        x, y, z, roll, pitch, yaw = self.xyz_rpy
        s = self.stated
        difference, outside = self.difference(), self.outside()
        return {
            "xyz": [x, y, z],
            "rpy": [roll, pitch, yaw],
            "base_frame": self.fitted.base,
            "laser_frame": self.fitted.frame,
            "z_roll_pitch_stated": self.fitted.lift is not None,
            "urdf_origin": self.urdf_origin(),
            "ros2_static_transform_publisher": self.ros2_command(),
            "ros1_static_transform_publisher": self.ros1_command(),
            "stated": None
            if s is None
            else {
                "x": s.x,
                "y": s.y,
                "yaw": s.yaw,
                "lift": None if s.lift is None else list(s.lift),
                "source": s.source,
            },
            "difference": None if difference is None else list(difference),
            "outside_interval_95": None if outside is None else list(outside),
            "verdict": self.verdict(),
        }


def mounting_forms(result: CalibrationResult) -> MountingForms | None:
    """The forms of ``result``'s fitted laser mounting (None: not a calibration from
    motion intervals). The height, tilt and frames come from
    :attr:`~umbmark.calibration.result.CalibrationResult.stated_mounting` (where none is
    stated: no height, no tilt, ``base_link`` and ``laser``)."""
    sensor = result.sensor
    if sensor is None:
        return None
    stated = result.stated_mounting
    x, y, yaw = sensor.laser_pose
    fitted = LaserMounting(
        x,
        y,
        yaw,
        lift=None if stated is None else stated.lift,
        base="base_link" if stated is None else stated.base,
        frame="laser" if stated is None else stated.frame,
        source="fitted",
    )
    est = result.estimate
    se = sensor.standard_errors
    intervals = []
    for (name, _), value in zip(AXES, (x, y, yaw), strict=True):
        found = est.interval(name)
        half = 1.96 * se[name]
        intervals.append(found if found is not None else (value - half, value + half))
    return MountingForms(
        fitted=fitted,
        standard_errors=(se["laser_x"], se["laser_y"], se["laser_yaw"]),
        intervals=tuple(intervals),
        stated=stated,
    )


def mounting_html(forms: MountingForms) -> str:
    """The forms as a section of an HTML page: what to do, the stated and fitted mounting
    with their difference (a table and a top view, inline SVG), the URDF origin and the
    publishers' commands (escaped)."""
    from html import escape

    from umbmark.outputs.html_parts import sentence, table

    f, s = forms.fitted, forms.stated
    difference, outside = forms.difference(), forms.outside()
    rows = []
    for k, (name, unit, scale) in enumerate(
        (("x, forward", "mm", 1000.0), ("y, left", "mm", 1000.0), ("yaw", "deg", 180 / math.pi))
    ):
        low, high = forms.intervals[k]
        fitted = (f.x, f.y, f.yaw)[k]
        rows.append(
            [
                f"{name} [{unit}]",
                "–" if s is None else f"{(s.x, s.y, s.yaw)[k] * scale:.2f}",
                f"{fitted * scale:.2f}",
                f"{forms.standard_errors[k] * scale:.2f}",
                f"{low * scale:.2f} to {high * scale:.2f}",
                "–" if difference is None else f"{difference[k] * scale:+.2f}",
                "–" if outside is None else ("yes" if outside[k] else "no"),
            ]
        )
    head = ["", "stated", "fitted", "standard error", "95 % interval",
            "fitted minus stated", "stated outside the interval"]  # fmt: skip
    where = f" ({escape(s.source)})" if s is not None and s.source else ""
    return (
        f'<p class="big" id="mounting-verdict">{escape(sentence(forms.verdict()))}.</p>\n'
        f"<p>The laser's mounting in <code>{escape(f.base)}</code>, stated{where} and "
        "fitted:</p>\n"
        + table(head, rows)
        + _mounting_figure(forms)
        + f"<p>The URDF joint origin of <code>{escape(f.frame)}</code> (its pose in "
        f"<code>{escape(f.base)}</code>; where the laser hangs under another link, compose "
        "the chain):</p>\n"
        f'<pre class="command" id="urdf-origin">{escape(forms.urdf_origin())}</pre>\n'
        "<p>Or publish it as a static transform, ROS 2 (Humble and later):</p>\n"
        f'<pre class="command" id="ros2-static-transform">{escape(forms.ros2_command())}</pre>\n'
        "<p>ROS 1 (positional: x y z yaw pitch roll, yaw first):</p>\n"
        f'<pre class="command" id="ros1-static-transform">{escape(forms.ros1_command())}</pre>\n'
        f"<p>Metres and radians; {escape(forms.lift_note())}. Apply one of them (not both: "
        "a second publisher of the same frame fights the first), restart what reads it, "
        "and run the calibration again to check.</p>\n"
    )


def _mounting_figure(forms: MountingForms) -> str:
    from umbmark.outputs.report_figures import inline_svg

    return (
        f'<figure id="mounting-figure">{inline_svg(_top_view(forms), "umbmark-mount")}'
        "<figcaption>The laser's mounting seen from above, in mm: the base frame's origin "
        "(the cross, x forward), the stated mounting (grey, dashed) and the fitted one "
        "(blue), each an arrow along the laser's x axis; the fitted one with its 95 % "
        "interval in x and y (the box).</figcaption></figure>\n"
    )


def _top_view(forms: MountingForms) -> Figure:
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    fig = Figure(figsize=(4.0, 4.0))
    ax = fig.add_subplot()
    f, s = forms.fitted, forms.stated
    points = [(0.0, 0.0), (f.x, f.y)] + ([] if s is None else [(s.x, s.y)])
    span = max(0.05, *(max(abs(x), abs(y)) for x, y in points)) * 1000.0
    arrow = 0.3 * span
    ax.plot([0.0], [0.0], "k+", markersize=12)
    for pose, style, colour, label, size in (
        (s, "--", "0.5", "stated", 11),
        (f, "-", "tab:blue", "fitted", 5),
    ):
        if pose is None:
            continue
        x, y = pose.x * 1000.0, pose.y * 1000.0
        ax.plot([x], [y], "o", color=colour, label=label, markersize=size, mfc="none")
        tip = (x + arrow * math.cos(pose.yaw), y + arrow * math.sin(pose.yaw))
        ax.plot([x, tip[0]], [y, tip[1]], style, color=colour)
    (xl, xh), (yl, yh) = forms.intervals[0], forms.intervals[1]
    box = Rectangle((xl * 1000, yl * 1000), (xh - xl) * 1000, (yh - yl) * 1000, fill=False,
                    edgecolor="tab:blue", linewidth=0.8)  # fmt: skip
    ax.add_patch(box)
    ax.set_xlim(-1.4 * span, 1.4 * span)
    ax.set_ylim(-1.4 * span, 1.4 * span)
    ax.set_aspect("equal")
    ax.set_xlabel("x, forward [mm]")
    ax.set_ylabel("y, left [mm]")
    ax.legend(loc="lower right", fontsize="small")
    ax.grid(True, linewidth=0.3)
    return fig
