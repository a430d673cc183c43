"""Reading odometry parameters from files: controller parameter YAML and umbmark results.

Two questions are asked of such files:

- **What was active during the runs?** (:func:`read_parameter_file`) A ros2_control or
  ROS 1 ``diff_drive_controller`` parameter file gives its multipliers and, where it has
  them, ``wheel_separation`` and ``wheel_radius``; a previous result
  (``umbmark calibrate -o result.json``) whose new values were applied gives those.
- **What does a calibration ask for?** (:func:`read_calibrated_params`) The new
  wheelbase and wheel factors of a result, to replay or simulate with.

ros2_control's ``diff_drive_controller`` scales its configured geometry by three
multipliers: effective separation ``wheel_separation_multiplier * wheel_separation`` and
effective radii ``left/right_wheel_radius_multiplier * wheel_radius``. ROS 1's has
parameters of the same names, without the ``ros__parameters`` level. Writing them is
:mod:`umbmark.sources.params.writer`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from umbmark.core.bounds import LENGTH_RANGE, MULTIPLIER_RANGE
from umbmark.core.errors import InputError, option
from umbmark.model.kinematics import WheelParams
from umbmark.sources.text import finite, load_json, load_yaml

__all__ = [
    "DEFAULT_CONTROLLER",
    "CalibratedParams",
    "ControllerParams",
    "check_controller_name",
    "is_result_file",
    "key_path_of",
    "named_controller",
    "read_calibrated_params",
    "read_controller_params",
    "read_parameter_file",
    "result_nominal",
]

DEFAULT_CONTROLLER = "diff_drive_controller"
MULTIPLIER_KEYS = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
    "wheel_radius_multiplier",
)
GEOMETRY_KEYS = ("wheel_separation", "wheel_radius")
#: Keys that mark a mapping as a differential-drive controller's parameters.
DIFF_DRIVE_KEYS = frozenset(
    {*MULTIPLIER_KEYS, *GEOMETRY_KEYS, "left_wheel_names", "right_wheel_names", "open_loop"}
)
#: Largest parameter file or result read [bytes]: real ones are a few kilobytes.
MAX_FILE_BYTES = 16 * 1024 * 1024


def _small_file(path: str | Path) -> None:
    """Refuse what is not a regular file of at most :data:`MAX_FILE_BYTES` (a folder, a
    device such as ``/dev/zero`` or a pipe would be read without end) before reading it.

    A missing or unreadable file is left to the reader, which names the problem.
    """
    where = Path(path)
    try:
        info = where.stat()
    except OSError:
        return
    if where.is_dir():
        raise InputError("is a folder, not a parameter file or result", source=path)
    if not where.is_file():
        raise InputError(
            "is not a regular file (a device, pipe or socket): give a parameter file or result",
            source=path,
        )
    if info.st_size > MAX_FILE_BYTES:
        raise InputError(
            f"is {info.st_size / 1e6:.0f} MB: larger than any parameter file or result "
            f"({MAX_FILE_BYTES // (1024 * 1024)} MB at most)",
            source=path,
        )


@dataclass(frozen=True)
class ControllerParams:
    """The ``diff_drive_controller`` parameters a file says were active during the runs,
    as the controller itself reads them.

    Attributes
    ----------
    wheel_separation_multiplier, left_wheel_radius_multiplier, right_wheel_radius_multiplier : float
        The multipliers in effect (1.0 where the file does not set them). ROS 1's
        controller takes ``wheel_radius_multiplier``, when it is set, for both wheels and
        ignores the left and right ones; so does this.
    wheel_separation, wheel_radius : float or None
        Configured geometry [m], where the file has it.
    controller : str
        The controller's node name (its last part, without namespaces).
    key_path : tuple of str
        The keys leading to the controller's parameters in the file (``("robot1",
        "diff_cont")``, ``("/robot1/diff_cont",)``, ``("/**",)``), so that an overlay is
        keyed as the file is and the parameter server matches it.
    ros2 : bool
        A ros2_control file (``ros__parameters``), else ROS 1.
    open_loop : bool
        The controller's odometry integrates its commands, not the wheels.
    left_joints, right_joints : tuple of str
        The wheel joints (ros2_control ``left_wheel_names``, ROS 1 ``left_wheel``): several
        per side are averaged, as the controller does.
    radius_multiplier : float or None
        ROS 1's ``wheel_radius_multiplier`` when the file sets it.
    odom_frame_id, base_frame_id : str or None
        The frames of the controller's odometry (for ``--odom-tf``).
    named : bool
        Something named the controller (its file, ``--controller``, a result or the
        history that carried its name); else :data:`DEFAULT_CONTROLLER` is taken, and
        the overlays say so.
    """

    wheel_separation_multiplier: float = 1.0
    left_wheel_radius_multiplier: float = 1.0
    right_wheel_radius_multiplier: float = 1.0
    wheel_separation: float | None = None
    wheel_radius: float | None = None
    controller: str = DEFAULT_CONTROLLER
    key_path: tuple[str, ...] = (DEFAULT_CONTROLLER,)
    ros2: bool = True
    open_loop: bool = False
    left_joints: tuple[str, ...] = ()
    right_joints: tuple[str, ...] = ()
    radius_multiplier: float | None = None
    odom_frame_id: str | None = None
    base_frame_id: str | None = None
    named: bool = False

    @property
    def name(self) -> str:
        """The controller's name with its namespace: ``/robot1/diff_cont`` (``/**`` for
        a file's wildcard block)."""
        return "/" + "/".join(k.strip("/") for k in self.key_path if k.strip("/"))


def key_path_of(name: str) -> tuple[str, ...]:
    """The keys of a controller's block for its name, outermost first:
    ``/robot1/diff_cont`` is ``robot1: diff_cont:``; a wildcard (``/**``) stays one key."""
    name = name.strip()
    if "*" in name:
        return (name,)
    return tuple(k for k in name.split("/") if k) or (DEFAULT_CONTROLLER,)


def named_controller(name: str | None) -> ControllerParams:
    """The controller of this name (``/robot1/diff_cont``), where no parameter file says
    more of it; None: :data:`DEFAULT_CONTROLLER`, not named."""
    keys = key_path_of(name or DEFAULT_CONTROLLER)
    return ControllerParams(controller=keys[-1], key_path=keys, named=name is not None)


def check_controller_name(name: object, source: str | Path) -> str | None:
    """A result's or the history's ``controller``: a name such as ``/robot1/diff_cont``
    (None where it holds none).

    Raises
    ------
    InputError
        Anything else.
    """
    if name is None:
        return None
    if (
        not isinstance(name, str)
        or not name.strip("/ ")
        or len(name) > 256
        or any(c.isspace() for c in name)
    ):
        shown = f"{name!r}"[:40]
        raise InputError(
            f"controller is {shown}, not a controller's name (e.g. /robot1/diff_cont)",
            source=str(source),
        )
    return name


@dataclass(frozen=True)
class CalibratedParams:
    """The odometry parameters a calibration result asks for.

    Attributes
    ----------
    wheelbase : float
        New effective wheelbase [m].
    c_left, c_right : float
        New absolute wheel factors.
    wheel_diameter_left, wheel_diameter_right : float or None
        New effective diameters [m], when the result knew the nominal diameter.
    separation_multiplier : float
        New ``wheel_separation_multiplier``.
    configured_wheelbase : float or None
        The configured wheelbase [m] the multiplier scales (``wheel_separation``).
    wheel_diameter : float or None
        The nominal diameter ``D_n`` [m] the result knew.
    spot_wheelbase : float or None
        For a model whose wheelbase depends on turning (``trajectory-scrub``): the
        wheelbase of turns on the spot [m]; ``wheelbase`` is then the arcs' (see
        :class:`umbmark.model.kinematics.WheelParams`).
    source : str
        The file.
    controller : str or None
        The controller the result is for, with its namespace (``/robot1/diff_cont``);
        None where nothing named it.
    gyro_scale, gyro_bias : float or None
        A calibration with a gyro: its scale ``k_g`` (None where not determined) and its
        bias [rad/s] (``new``'s ``gyro_scale_multiplier`` and ``gyro_bias``).
    """

    wheelbase: float
    c_left: float
    c_right: float
    wheel_diameter_left: float | None = None
    wheel_diameter_right: float | None = None
    separation_multiplier: float = 1.0
    configured_wheelbase: float | None = None
    wheel_diameter: float | None = None
    spot_wheelbase: float | None = None
    source: str = ""
    controller: str | None = None
    gyro_scale: float | None = None
    gyro_bias: float | None = None

    def applied_to(self, nominal: WheelParams) -> WheelParams:
        """``nominal`` with this result's wheelbase(s) and wheel factors.

        Where the result knows the absolute diameters, they carry over even to a robot
        description with another nominal diameter.
        """
        c_left, c_right = self.c_left, self.c_right
        if self.wheel_diameter_left is not None and self.wheel_diameter_right is not None:
            c_left = self.wheel_diameter_left / nominal.wheel_diameter
            c_right = self.wheel_diameter_right / nominal.wheel_diameter
        corrected = nominal.with_corrections(
            c_left=c_left, c_right=c_right, wheelbase=self.wheelbase
        )
        return replace(corrected, spot_wheelbase=self.spot_wheelbase)


# --- results ---------------------------------------------------------------------------


def _result_data(path: str | Path) -> dict[str, Any]:
    _small_file(path)
    data = load_json(path)
    if not isinstance(data, dict) or not isinstance(data.get("new"), dict):
        raise InputError(
            "is not an umbmark calibration result (no 'new' parameters; write one with "
            "umbmark calibrate -o FILE)",
            source=path,
        )
    return data


def read_calibrated_params(path: str | Path) -> CalibratedParams:
    """Read the new parameters from a result JSON written by ``umbmark calibrate -o``.

    Raises
    ------
    InputError
        If the file is not such a result.
    """
    data = _result_data(path)
    new = data["new"]

    def number(container: dict[str, object], key: str, where: str) -> float:
        raw = container.get(key)
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            raise InputError(f"{where}{key} is missing or not a number", source=path)
        value = finite(raw)
        if value is None or value <= 0:
            shown = f"{raw!r}"[:24]
            raise InputError(f"{where}{key} is {shown}, not a positive number", source=path)
        low, high = (
            MULTIPLIER_RANGE
            if key.startswith(("c_", "wheel_separation_m", "gyro_scale"))
            else LENGTH_RANGE
        )
        if not low <= value <= high:
            raise InputError(
                f"{where}{key} is {value:g}, outside the plausible {low:g} to {high:g}",
                source=path,
            )
        return value

    def optional(container: dict[str, object], key: str, where: str) -> float | None:
        return None if container.get(key) is None else number(container, key, where)

    active = data.get("active")
    if not isinstance(active, dict):
        active = {}
    controller = check_controller_name(data.get("controller"), path)
    model = data.get("model")
    if isinstance(model, dict):
        # The fitted model replays as fitted; "new" holds the single set for controllers.
        return CalibratedParams(
            wheelbase=number(model, "wheelbase", "model."),
            c_left=number(new, "c_L", "new."),
            c_right=number(new, "c_R", "new."),
            wheel_diameter_left=number(model, "wheel_diameter_left", "model."),
            wheel_diameter_right=number(model, "wheel_diameter_right", "model."),
            spot_wheelbase=optional(model, "spot_wheelbase", "model."),
            source=str(path),
            controller=controller,
        )
    return CalibratedParams(
        wheelbase=number(new, "wheelbase", "new."),
        c_left=number(new, "c_L", "new."),
        c_right=number(new, "c_R", "new."),
        wheel_diameter_left=optional(data, "wheel_diameter_left", ""),
        wheel_diameter_right=optional(data, "wheel_diameter_right", ""),
        separation_multiplier=optional(new, "wheel_separation_multiplier", "new.") or 1.0,
        configured_wheelbase=optional(active, "wheelbase", "active."),
        wheel_diameter=optional(active, "wheel_diameter", "active."),
        source=str(path),
        controller=controller,
        gyro_scale=optional(new, "gyro_scale_multiplier", "new."),
        gyro_bias=_bias(new, path),
    )


def _bias(new: dict[str, object], path: str | Path) -> float | None:
    """A result's gyro bias [rad/s] (``new.gyro_bias``): a finite number within what a
    gyro's bias can be, or None where not given."""
    raw = new.get("gyro_bias")
    if raw is None:
        return None
    value = finite(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else None
    if value is None or abs(value) > _MAX_BIAS:
        raise InputError(
            f"new.gyro_bias is {f'{raw!r}'[:24]}, not a gyro's bias in rad/s", source=path
        )
    return value


#: The largest gyro bias a result may hold [rad/s] (10 deg/s: far beyond a MEMS part's).
_MAX_BIAS = 0.175


def result_nominal(path: str | Path) -> tuple[float | None, float | None]:
    """The nominal wheelbase and wheel diameter [m] a result file was computed for (its
    ``active`` block: ``wheelbase``, ``wheel_diameter``), None where it does not say.

    Raises
    ------
    InputError
        If the file is not a result, or the values are not plausible lengths.
    """
    data = _result_data(path)
    active = data.get("active")
    if not isinstance(active, dict):
        return None, None
    out: list[float | None] = []
    for key in ("wheelbase", "wheel_diameter"):
        raw = active.get(key)
        if raw is None:
            out.append(None)
            continue
        value = finite(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else None
        low, high = LENGTH_RANGE
        if value is None or not low <= value <= high:
            shown = f"{raw!r}"[:24]
            raise InputError(
                f"active.{key} is {shown}, not a plausible length ({low:g} to {high:g} m)",
                source=path,
            )
        out.append(value)
    return out[0], out[1]


def is_result_file(path: str | Path) -> bool:
    """Whether ``path`` looks like a calibration result (JSON with new parameters)."""
    try:
        _result_data(path)
    except InputError:
        return False
    return True


# --- controller parameter files --------------------------------------------------------


def read_parameter_file(path: str | Path, controller: str | None = None) -> ControllerParams:
    """What was active during the runs, from a controller parameter YAML or a result JSON.

    A result's new values count as applied: the configured wheelbase stays, the
    separation multiplier and the wheel factors are the result's new ones, and the
    controller is the one it names (its ``controller``) unless ``controller`` is given.

    Raises
    ------
    InputError
        If the file is neither, or names no such controller.
    """
    if Path(path).suffix.lower() != ".json" and not is_result_file(path):
        return read_controller_params(path, controller)
    new = read_calibrated_params(path)
    return replace(
        named_controller(controller or new.controller),  # the one given, else the result's
        wheel_separation_multiplier=new.separation_multiplier,
        left_wheel_radius_multiplier=new.c_left,
        right_wheel_radius_multiplier=new.c_right,
        wheel_separation=new.configured_wheelbase,
        wheel_radius=None if new.wheel_diameter is None else 0.5 * new.wheel_diameter,
    )


def read_controller_params(path: str | Path, controller: str | None = None) -> ControllerParams:
    """Read a ros2_control or ROS 1 ``diff_drive_controller`` parameter file.

    Parameters
    ----------
    path : path
        A YAML parameter file: ``node: ros__parameters: {...}`` (ros2_control, with or
        without namespaces, ``/**`` wildcards allowed) or ``node: {...}`` (ROS 1).
    controller : str, optional
        The controller's node name (its last part, or the namespaced name); by default
        the one node that has diff-drive parameters.

    Raises
    ------
    InputError
        If the file is not YAML, names no such controller, or sets an implausible value.
    """
    _small_file(path)
    data = load_yaml(path)
    blocks = _parameter_blocks(data)
    candidates = {
        "/".join(k.strip("/") for k in keys): (keys, ros2, params) for keys, ros2, params in blocks
    }
    if controller is not None:
        wanted = controller.strip("/")
        matches = [n for n in candidates if wanted in (n, n.rsplit("/", 1)[-1])]
        if len(matches) != 1:
            found = ", ".join(sorted(candidates)) or "none"
            many = "several match" if matches else "none matches"
            raise InputError(
                f"has no single diff-drive controller {controller!r} ({many}; controllers "
                f"with diff-drive parameters: {found})",
                source=path,
            )
        name = matches[0]
    elif len(candidates) == 1:
        name = next(iter(candidates))
    elif not candidates:
        raise InputError(
            "has no diff_drive_controller parameters (wheel_separation, *_multiplier, "
            "*_wheel_names)",
            source=path,
        )
    else:
        raise InputError(
            f"has several controllers ({', '.join(sorted(candidates))}); "
            f"name one with {option('controller')}",
            source=path,
        )
    keys, ros2, params = candidates[name]
    return _controller(params, keys, ros2, path)


def _number(
    params: dict[str, Any], key: str, bounds: tuple[float, float], path: object
) -> float | None:
    if key not in params:
        return None
    value = finite(params[key])
    if value is None:
        shown = f"{params[key]!r}"[:24]
        raise InputError(f"{key} is {shown}, not a number", source=str(path))
    low, high = bounds
    if not low <= value <= high:
        unit = " m" if key in GEOMETRY_KEYS else ""
        raise InputError(
            f"{key} is {value:g}{unit}, outside {low:g} to {high:g}{unit}"
            + (" (lengths are in metres)" if key in GEOMETRY_KEYS and value > high else ""),
            source=str(path),
        )
    return float(value)


def _names(params: dict[str, Any], *keys: str) -> tuple[str, ...]:
    for key in keys:
        value = params.get(key)
        if isinstance(value, str) and value:
            return (value,)
        if isinstance(value, list) and all(isinstance(v, str) for v in value):
            return tuple(value)
    return ()


def _controller(
    params: dict[str, Any], keys: tuple[str, ...], ros2: bool, path: object
) -> ControllerParams:
    """The parameters as ``diff_drive_controller`` reads them (ROS 1 and 2)."""
    multiplier = {k: _number(params, k, MULTIPLIER_RANGE, path) for k in MULTIPLIER_KEYS}
    both = multiplier["wheel_radius_multiplier"]
    # ROS 1: wheel_radius_multiplier, when set, is both wheels' and the others are ignored.
    left = both if both is not None else multiplier["left_wheel_radius_multiplier"]
    right = both if both is not None else multiplier["right_wheel_radius_multiplier"]
    open_loop = params.get("open_loop", False)
    if not isinstance(open_loop, bool):
        raise InputError(f"open_loop is {open_loop!r}, not true or false", source=str(path))
    left_joints = _names(params, "left_wheel_names", "left_wheel")
    right_joints = _names(params, "right_wheel_names", "right_wheel")
    if len(left_joints) != len(right_joints):
        raise InputError(
            f"names {len(left_joints)} left and {len(right_joints)} right wheel joints: the "
            "controller needs as many on each side",
            source=str(path),
        )
    frames = {k: params.get(k) for k in ("odom_frame_id", "base_frame_id")}
    name = "/".join(k.strip("/") for k in keys).rsplit("/", 1)[-1] or keys[-1]
    return ControllerParams(
        wheel_separation_multiplier=multiplier["wheel_separation_multiplier"] or 1.0,
        left_wheel_radius_multiplier=left or 1.0,
        right_wheel_radius_multiplier=right or 1.0,
        wheel_separation=_number(params, "wheel_separation", LENGTH_RANGE, path),
        wheel_radius=_number(params, "wheel_radius", LENGTH_RANGE, path),
        controller=name,
        key_path=keys,
        ros2=ros2,
        open_loop=open_loop,
        left_joints=left_joints,
        right_joints=right_joints,
        radius_multiplier=both,
        odom_frame_id=frames["odom_frame_id"] if isinstance(frames["odom_frame_id"], str) else None,
        base_frame_id=frames["base_frame_id"] if isinstance(frames["base_frame_id"], str) else None,
        named=True,
    )


#: Deepest nesting of parameter files searched (namespaces in namespaces).
_MAX_DEPTH = 16


def _parameter_blocks(
    data: object, keys: tuple[str, ...] = (), depth: int = 0
) -> list[tuple[tuple[str, ...], bool, dict[str, Any]]]:
    """Every mapping that holds diff-drive parameters: its key path (``ros__parameters``
    levels left out), whether it is a ros2_control block, and the parameters."""
    found: list[tuple[tuple[str, ...], bool, dict[str, Any]]] = []
    if not isinstance(data, dict) or depth > _MAX_DEPTH:
        return found
    for name, value in data.items():
        if not isinstance(value, dict):
            continue
        path = (*keys, str(name))
        inner = value.get("ros__parameters")
        if isinstance(inner, dict) and DIFF_DRIVE_KEYS & set(inner):
            found.append((path, True, inner))
        elif DIFF_DRIVE_KEYS & set(value):
            found.append((path, False, value))
        else:
            found.extend(_parameter_blocks(value, path, depth + 1))
    return found
