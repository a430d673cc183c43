"""New multipliers applied through ros2_control's controller manager (ROS 2, ``--reload``).

ros2_controllers' ``diff_drive_controller`` reads its multipliers only in
``on_configure`` (``diff_drive_controller.cpp``): on Humble, Jazzy and Kilted they can be
set at any time (``set_parameters`` succeeds and changes nothing until the next
configure); after Kilted (Rolling) they are read-only, and reach a controller only through
the parameter files it is loaded with. So, through the controller manager's services
(``controller_manager_msgs``, ``tools/build_ros2_interfaces.py`` where no ROS is
installed):

- ``configure`` (settable): ``set_parameters`` on the controller, then deactivate,
  configure (the manager cleans an inactive controller up first), activate;
- ``load`` (read-only): the multipliers written into ``--params-file``, that file
  appended to the manager's ``NAME.params_file`` (later files override), then deactivate,
  unload, load, configure, activate. The manager reads the file: the path must be one it
  can read (its own machine).

Either way the controller's odometry restarts: ``on_configure`` resets its pose to zero,
and with position feedback its first update moves it by the wheels' rotation times the
radius change (Humble to Kilted keep the last wheel positions in metres at the old radii),
or, for a controller just loaded, by the wheels' whole travel. The routine takes the
odometry after the reload as a new origin (:meth:`umbmark.routines.passes.Home.reanchor`);
:func:`reload` returns once the controller is active again, its velocity topic subscribed
and its odometry fresh, and after reading the parameters back: anything but the values
asked, or a step the manager refuses, stops the robot (:class:`SafetyError`) and no
further pass is driven.
"""

from __future__ import annotations

import importlib.util
import math
import os
from dataclasses import dataclass
from typing import Any, Literal, Protocol

from umbmark.core.errors import InputError, SafetyError
from umbmark.robot.base import AppliedBy, ApplyMethod, ApplyResult, DriveParams
from umbmark.robot.ros_common import (
    MULTIPLIERS,
    RosOptions,
    multipliers,
    plan_apply,
    restart_commands,
    write_params,
)

__all__ = ["RESTART", "ReloadPlan", "ReloadTarget", "apply_params", "controller_names"]
__all__ += ["plan_reload", "reload", "reload_plan"]

#: What the routine does where the controller cannot take new parameters while it runs.
RESTART = (
    "the routine stops after the first pass for a controller restart, and umbmark selfcal "
    "--resume DIR goes on"
)
#: The type of a parameter file list on the manager (Jazzy and later; Humble: one string).
STRING, STRING_ARRAY = 4, 9


class ReloadTarget(Protocol):
    """What this module needs of :class:`umbmark.robot.ros2.Ros2Robot`."""

    @property
    def options(self) -> RosOptions: ...

    def call(self, kind: Any, service: str, request: Any) -> Any: ...  # noqa: ANN401

    def send_velocity(self, linear: float, angular: float) -> None: ...

    def now(self) -> float: ...

    def wait_back(self, since: float) -> None: ...

    def drive_params(self) -> DriveParams: ...


@dataclass(frozen=True)
class ReloadPlan:
    """How new multipliers will reach the controller, found before the robot moves:
    ``way`` (None: they cannot while the routine runs) and a line saying so."""

    way: Literal["configure", "load"] | None
    line: str


def controller_names(controller: str) -> tuple[str, str, str]:
    """The controller's name, its node and its controller manager's node:
    ``/ns/diff_drive_controller`` -> ``diff_drive_controller``,
    ``/ns/diff_drive_controller``, ``/ns/controller_manager``."""
    node = "/" + controller.strip("/")
    parent, _, name = node.rpartition("/")
    return name, node, f"{parent}/controller_manager"


def plan_reload(robot: ReloadTarget) -> ReloadPlan:
    """Ask the graph which way applying goes: the manager lists the controller active,
    and its multipliers are settable (``configure``), or read-only with ``--params-file``
    given and the manager holding the controller's parameter files (``load``)."""
    name, node, cm = controller_names(robot.options.controller)
    try:
        state = controller_state(robot, cm, name)
    except InputError as exc:
        return ReloadPlan(None, f"--reload: {exc}; {RESTART}")
    if state != "active":
        return ReloadPlan(
            None, f"--reload: {cm} lists {name} as {state or 'not loaded'}, not active; {RESTART}"
        )
    read_only = _read_only(robot, node)
    restarts = f"{node}'s odometry restarts there and is taken as the new origin"
    if not read_only:
        return ReloadPlan(
            "configure",
            f"applying: set_parameters on {node}, then {cm} deactivates, configures and "
            f"activates it (it reads its multipliers on configure); {restarts}",
        )
    path = robot.options.params_file
    if path is None:
        return ReloadPlan(
            None,
            f"--reload: {node}'s multipliers are read-only (ros2_controllers after Kilted): "
            f"they reach it only in a parameter file it is loaded with; give --params-file "
            f"PATH (a path {cm} can read) to reload it; {RESTART}",
        )
    if not parameter_files(robot, cm, name):
        return ReloadPlan(
            None,
            f"--reload: {cm} has no {name}.params_file, and loading {name} again would lose "
            f"its parameters; {RESTART}",
        )
    return ReloadPlan(
        "load",
        f"applying: {node}'s multipliers are read-only, so the new ones go into {path}, "
        f"appended to {cm}'s {name}.params_file, and {cm} unloads, loads, configures and "
        f"activates it; {restarts}",
    )


def reload(robot: ReloadTarget, way: Literal["configure", "load"], params: DriveParams) -> str:
    """Apply the multipliers of ``params`` ``way`` (the file ``--params-file`` already
    written for ``load``); what was done. The robot is stopped first and stands until
    the controller is back.

    Raises
    ------
    SafetyError
        The manager refused a step, or the controller does not hold the values asked
        afterwards: the robot stands, nothing further is driven (one line: what the
        controller is now).
    """
    name, node, cm = controller_names(robot.options.controller)
    robot.send_velocity(0.0, 0.0)
    if way == "configure":
        _set_multipliers(robot, node, params)
        _switch(robot, cm, name, activate=False)
        _step(robot, cm, name, "configure_controller")
    else:
        path = robot.options.params_file
        assert path is not None  # plan_reload saw to it
        files = parameter_files(robot, cm, name)
        if path not in files:
            _set_files(robot, cm, name, [*files, path])
        _switch(robot, cm, name, activate=False)
        _step(robot, cm, name, "unload_controller")
        _step(robot, cm, name, "load_controller")
        _step(robot, cm, name, "configure_controller")
    since = robot.now()
    _switch(robot, cm, name, activate=True)
    robot.wait_back(since)
    held = robot.drive_params()
    wrong = [
        f"{key} {getattr(held, key):.9g} (asked {value:.9g})"
        for key, value in multipliers(params).items()
        if not math.isclose(getattr(held, key), value, rel_tol=1e-8)
    ]
    if wrong:
        raise _stopped(robot, f"after the reload {node} holds {', '.join(wrong)}")
    how = "configured" if way == "configure" else "unloaded, loaded with the new file, configured"
    return f"{cm} {how} and activated {name} on the new multipliers"


# --- the manager's services ---------------------------------------------------------------


def controller_state(robot: ReloadTarget, cm: str, name: str) -> str | None:
    """The controller's lifecycle state as the manager lists it (None: not loaded)."""
    from controller_manager_msgs.srv import ListControllers

    answer = robot.call(ListControllers, f"{cm}/list_controllers", ListControllers.Request())
    for state in answer.controller:
        if state.name == name:
            return str(state.state)
    return None


def parameter_files(robot: ReloadTarget, cm: str, name: str) -> list[str]:
    """The manager's ``NAME.params_file``: the files the controller is loaded with."""
    from rcl_interfaces.srv import GetParameters

    request = GetParameters.Request()
    request.names = [f"{name}.params_file"]
    answer = robot.call(GetParameters, f"{cm}/get_parameters", request)
    if not answer.values:
        return []
    value = answer.values[0]
    if value.type == STRING_ARRAY:
        return [str(v) for v in value.string_array_value]
    if value.type == STRING and value.string_value:
        return [str(value.string_value)]
    return []


def _read_only(robot: ReloadTarget, node: str) -> bool:
    """Whether any of the controller's multipliers is declared read-only."""
    from rcl_interfaces.srv import DescribeParameters

    request = DescribeParameters.Request()
    request.names = list(MULTIPLIERS)
    answer = robot.call(DescribeParameters, f"{node}/describe_parameters", request)
    return any(d.read_only for d in answer.descriptors)


def _set_parameters(robot: ReloadTarget, node: str, values: list[Any]) -> list[str]:
    """Set parameters (rcl_interfaces Parameter messages); the reasons of any refused."""
    from rcl_interfaces.srv import SetParameters

    request = SetParameters.Request()
    request.parameters = values
    results = robot.call(SetParameters, f"{node}/set_parameters", request).results
    return [f"{p.name}: {r.reason or 'refused'}" for p, r in zip(values, results, strict=False)
            if not r.successful]  # fmt: skip


def _set_multipliers(robot: ReloadTarget, node: str, params: DriveParams) -> None:
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue

    values = [
        Parameter(name=k, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=v))
        for k, v in multipliers(params).items()
    ]
    refused = _set_parameters(robot, node, values)
    if refused:
        raise _stopped(robot, f"{node} refused the new multipliers ({'; '.join(refused)})")


def _set_files(robot: ReloadTarget, cm: str, name: str, files: list[str]) -> None:
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue

    value = ParameterValue(type=ParameterType.PARAMETER_STRING_ARRAY, string_array_value=files)
    refused = _set_parameters(robot, cm, [Parameter(name=f"{name}.params_file", value=value)])
    if refused:
        raise _stopped(robot, f"{cm} refused {name}.params_file ({'; '.join(refused)})")


def _switch(robot: ReloadTarget, cm: str, name: str, *, activate: bool) -> None:
    from controller_manager_msgs.srv import SwitchController

    request = SwitchController.Request()
    if activate:
        request.activate_controllers = [name]
    else:
        request.deactivate_controllers = [name]
    request.strictness = SwitchController.Request.STRICT
    answer = robot.call(SwitchController, f"{cm}/switch_controller", request)
    if not answer.ok:
        verb = "activate" if activate else "deactivate"
        message = getattr(answer, "message", "")  # Humble's answer has none
        detail = f" ({message})" if message else ""
        raise _stopped(robot, f"{cm} refused to {verb} {name}{detail}")


def _step(robot: ReloadTarget, cm: str, name: str, service: str) -> None:
    """``load_controller``, ``configure_controller`` or ``unload_controller``."""
    from controller_manager_msgs import srv

    kind = {
        "load_controller": srv.LoadController,
        "configure_controller": srv.ConfigureController,
        "unload_controller": srv.UnloadController,
    }[service]
    request = kind.Request()
    request.name = name
    if not robot.call(kind, f"{cm}/{service}", request).ok:
        verb = service.split("_", maxsplit=1)[0]
        raise _stopped(robot, f"{cm} failed to {verb} {name} on the new multipliers")


def _stopped(robot: ReloadTarget, what: str) -> SafetyError:
    """The robot stopped; the line says what the controller is now and that nothing
    further is driven."""
    robot.send_velocity(0.0, 0.0)
    name, _node, cm = controller_names(robot.options.controller)
    try:
        state = controller_state(robot, cm, name)
        now = f"{name} is {state} now" if state else f"{name} is not loaded now"
    except InputError:
        now = f"{cm} does not answer"
    return SafetyError(
        f"{what}: {now}; the robot stands and no further pass is driven on parameters that "
        f"were not applied (the controller manager's log says why)"
    )


# --- applying: the self-calibration's and the monitor's ROS 2 node's -----------------------


def reload_plan(target: ReloadTarget) -> ReloadPlan:
    """How new multipliers will reach ``target``'s controller (``options.reload``,
    ``controller_manager_msgs`` importable, then the manager asked: :func:`plan_reload`)."""
    if not target.options.reload:
        return ReloadPlan(
            None,
            "the controller reads its multipliers only when it is configured, and "
            f"--reload was not given: {RESTART}",
        )
    if importlib.util.find_spec("controller_manager_msgs") is None:
        return ReloadPlan(
            None,
            "--reload needs controller_manager_msgs, not installed here (no ROS "
            "installation: python tools/build_ros2_interfaces.py builds it into this "
            f"Python); {RESTART}",
        )
    return plan_reload(target)


def apply_params(
    target: ReloadTarget, plan_: ReloadPlan, params: DriveParams, method: ApplyMethod
) -> ApplyResult:
    """Write ``options.params_file`` (when given) and, where ``plan_`` allows, reload the
    controller through the controller manager; else say how to restart it on the new
    values. The result's method is the way taken: ``set_parameters`` or ``reload``
    through the manager, ``yaml`` where only the file was written, ``none`` where nothing
    was."""
    plan = plan_apply(params, "yaml" if method == "reconfigure" else method)
    if plan.method == "none":
        return ApplyResult("none", False, plan.reason)
    options = target.options
    path = options.params_file
    edit = None if path is None else write_params(path, params, options.controller, ros2=True)
    wrote = "" if edit is None else f"{edit.line()}; "
    file = None if path is None else os.fspath(path)
    line = None if edit is None else edit.line()
    if plan_.way is not None:
        done = reload(target, plan_.way, params)
        how: AppliedBy = "set_parameters" if plan_.way == "configure" else "reload"
        return ApplyResult(how, True, f"{wrote}{done}", file=file, wrote=line)
    return ApplyResult(
        "yaml" if edit is not None else "none",
        False,
        f"{wrote}restart the controller on them: "
        f"{restart_commands(options.controller, params, path)}",
        file=file,
        wrote=line,
    )
