# ruff: noqa: E501
"""Build the ROS 2 interface packages that have no wheel into the ROS 2 Python environment.

``umbmark selfcal --ros2 --reload`` talks to the controller manager, and the laser's mounting
is read from ``/tf_static``: these need ``controller_manager_msgs`` and ``tf2_msgs``, which
have no wheels on the package index (rclpy and the common messages do). This script
generates and compiles them from their ``.msg``/``.srv``/``.action`` files with the ROS 2
Kilted interface generators (wheels: ``ros-kilted-rosidl-default-generators``,
``ros-kilted-ament-cmake``), CMake and a C/C++ compiler, and installs them into the
environment whose Python runs it (its prefix is an ament prefix: ``lib/``, ``share/``,
``include/``). No ROS installation is needed.

Run: .venv-ros2/bin/python tools/build_ros2_interfaces.py
(after ``pip install -e ".[ros2]"`` in that environment; nothing is done when both packages
import already). Needs ``cmake`` (3.16 or later), ``gcc``/``g++`` and Python's headers.

The interface texts below are copied verbatim (not part of umbmark's own code):
- ``controller_manager_msgs`` 5.16.0 from github.com/ros-controls/ros2_control, branch
  ``kilted`` (commit cbe7d2c38b716569622786fa9732e3eaca78aca1); repository licence
  Apache-2.0, package.xml states BSD.
- ``tf2_msgs`` 0.36.4 from github.com/ros2/geometry2, branch ``jazzy`` (commit
  646342c6164e837d69460e3d28e7a025396544f6; the interfaces are the same on Kilted and
  Rolling); licence BSD (package.xml), repository BSD-3-Clause.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

#: What the build needs from the package index (installed into this environment).
BUILD_REQUIREMENTS = [
    "ros-kilted-rosidl-default-generators>=1.7",
    "ros-kilted-ament-cmake>=2.7",
    "ros-kilted-ament-cmake-include-directories>=2.7",
    "ros-kilted-rosidl-core-generators>=0.3",
    "ros-kilted-ament-cmake-ros-core>=0.14",
    "ros-kilted-ament-package>=0.17",
    "catkin-pkg>=1.0",
]

# The interface files, verbatim (lines as long as upstream's).
CONTROLLER_MANAGER_MSGS: dict[str, str] = {
    "msg/ChainConnection.msg": """\
string name        # name of controller exporting reference_interfaces
string[] reference_interfaces        # list of reference exported by controller
""",
    "msg/ControllerManagerActivity.msg": """\
# This message is used to provide the activity within the controller manager regarding the change in state of controllers and hardware interfaces

# The header is used to provide timestamp information
std_msgs/Header header

# The current state of the controllers
NamedLifecycleState[] controllers

# The current state of the hardware components
NamedLifecycleState[] hardware_components
""",
    "msg/ControllerState.msg": """\
string name        # controller name
string state        # controller state: unconfigured, inactive, active, or finalized
string type        # the controller class name, e.g. joint_trajectory_controller/JointTrajectoryController
bool is_async       # true, if controller runs asynchronously. false, if controller runs synchronously
uint16 update_rate        # update rate of the controller in Hz
string[] claimed_interfaces        # command interfaces currently owned by controller
string[] required_command_interfaces        # command interfaces required by controller
string[] required_state_interfaces        # state interfaces required by controller
bool is_chainable        # specifies whether or not controller can export references for a controller chain
bool is_chained        # specifies whether or not controller's exported references are claimed by another controller
string[] exported_state_interfaces        # state interfaces to be exported (only applicable if is_chainable is true)
string[] reference_interfaces        # references to be exported (only applicable if is_chainable is true)
ChainConnection[] chain_connections        # specifies list of controllers and their exported references that the controller is chained to
""",
    "msg/HardwareComponentState.msg": """\
string name # Name of the hardware component
string type # Type of the hardware component
bool is_async # If the hardware component is running asynchronously
uint16 rw_rate # read/write rate of the hardware component in Hz
string plugin_name # The name of the plugin that is used to load the hardware component
lifecycle_msgs/State state # State of the hardware component
HardwareInterface[] command_interfaces # Command interfaces of the hardware component
HardwareInterface[] state_interfaces # State interfaces of the hardware component
""",
    "msg/HardwareInterface.msg": """\
string name
string data_type
bool is_available
bool is_claimed
""",
    "msg/NamedLifecycleState.msg": """\
# This message is used to provide information about the lifecycle state of the controller or the hardware components

# The name of the controller or hardware interface
string name

# The current lifecycle state of the controller or hardware components
lifecycle_msgs/State state
""",
    "srv/CleanupController.srv": """\
# The CleanupController service allows you to cleanup a single controller
# from controller_manager

# To cleanup a controller, specify the "name" of the controller.
# The return value "ok" indicates if the controller was successfully
# cleaned up or not

string name
---
bool ok
""",
    "srv/ConfigureController.srv": """\
# The ConfigureController service allows you to configure a single controller
# inside controller_manager

# To configure a controller, specify the "name" of the controller.
# The return value "ok" indicates if the controller was successfully
# configured or not.

string name
---
bool ok
""",
    "srv/ListControllerTypes.srv": """\
# The ListControllers service returns a list of controller types that are known
# to the controller manager plugin mechanism.

---
string[] types
string[] base_classes
""",
    "srv/ListControllers.srv": """\
# The ListControllers service returns a list of controller names/states/types of the
# controllers that are loaded inside the controller_manager.

---
controller_manager_msgs/ControllerState[] controller
""",
    "srv/ListHardwareComponents.srv": """\
# The ListHardwareComponents service returns a list of hardware HardwareComponentsState.
# This will convey name, component_type, state and type of the components
# that are loaded inside the resource_manager.

---
HardwareComponentState[] component
""",
    "srv/ListHardwareInterfaces.srv": """\

---
HardwareInterface[] command_interfaces
HardwareInterface[] state_interfaces
""",
    "srv/LoadController.srv": """\
# The LoadController service allows you to load a single controller
# inside controller_manager

# To load a controller, specify the "name" of the controller.
# The return value "ok" indicates if the controller was successfully
# constructed and initialized or not.

string name
---
bool ok
""",
    "srv/ReloadControllerLibraries.srv": """\
# The ReloadControllerLibraries service will reload all controllers that are available in
# the system as plugins

# Reloading libraries only works if there are no controllers loaded. If there
# are still some controllers loaded, the reloading will fail.
# If this bool is set to true, all loaded controllers will get
# killed automatically, and the reloading can succeed.
bool force_kill
---
bool ok
""",
    "srv/SetHardwareComponentState.srv": """\
# The SetHardwareComponentState service allows to control life-cycle of a single hardware component.
# Supported states are defined in the design document of LifecycleNodes available at:
# https://design.ros2.org/articles/node_lifecycle.html
# To control life-cycle of a hardware component, specify its "name" and "target_state".
# Target state may be defined by "id" using a constant from `lifecycle_msgs/msg/State` or a label
# using definitions from `hardware_interface/types/lifecycle_state_names.hpp` file.
# The return value "ok" indicates if the component has successfully changed its state to "target_state".
# The return value "state" returns current state of the hardware component.

string name
lifecycle_msgs/State target_state
---
bool ok
lifecycle_msgs/State state
""",
    "srv/SwitchController.srv": """\
# The SwitchController service allows you to deactivate a number of controllers
# and activate a number of controllers, all in one single timestep of the
# controller manager's control loop.

# To switch controllers, specify
#  * the list of controller names to activate,
#  * the list of controller names to deactivate, and
#  * the strictness (STRICT, BEST_EFFORT, AUTO, or FORCE_AUTO)
#    * STRICT means that switching will fail if anything goes wrong (an invalid
#      controller name, a controller that failed to activate, etc.).
#    * BEST_EFFORT:
#      Transitions are only triggered if the controller is not yet in the target state.
#      If it is already in the target state, no error occurs.
#      Returns 'false' if all controllers of 'activate_controllers' or 'deactivate_controllers' are not yet loaded or configured,
#      or the pending transitions of all existing controllers of 'activate_controllers'
#      or 'deactivate_controllers' fail.
#      Returns 'true' otherwise.
#    * AUTO means that the controller manager will automatically resolve the controller
#      chain in order to activate and/or deactivate the specified controllers.
#      This is useful in complex systems when you want all dependent controllers to start
#      within the same update iteration.
#    * FORCE_AUTO means that the controller manager will take all necessary steps to activate
#      the specified controllers without requiring you to explicitly list the controllers
#      to be deactivated. This is useful when the controller being activated depends on
#      another unknown controller that is currently running. The controller manager will
#      deactivate any controllers that block the activation of the requested controller,
#      following the mutually exclusive joint interface switching principle. For example,
#      to activate a controller that uses a joint's position interface, the controller manager
#      will automatically deactivate any controllers that use conflicting interfaces for
#      the same joint.
#  * activate the controllers as soon as their hardware dependencies are ready, will
#    wait for all interfaces to be ready otherwise
#  * the timeout before aborting pending controllers. Zero for infinite

# The return value "ok" indicates if the controllers were switched
# successfully or not. The meaning of success depends on the
# specified strictness.
# The return value "message" provides some human-readable information.


string[] activate_controllers
string[] deactivate_controllers
int32 strictness
int32 BEST_EFFORT=1
int32 STRICT=2
int32 AUTO=3
int32 FORCE_AUTO=4
bool activate_asap
builtin_interfaces/Duration timeout
---
bool ok
string message
""",
    "srv/UnloadController.srv": """\
# The UnloadController service allows you to unload a single controller
# from controller_manager

# To unload a controller, specify the "name" of the controller.
# The return value "ok" indicates if the controller was successfully
# unloaded or not

string name
---
bool ok
""",
}
TF2_MSGS: dict[str, str] = {
    "msg/TF2Error.msg": """\
uint8 NO_ERROR = 0
uint8 LOOKUP_ERROR = 1
uint8 CONNECTIVITY_ERROR = 2
uint8 EXTRAPOLATION_ERROR = 3
uint8 INVALID_ARGUMENT_ERROR = 4
uint8 TIMEOUT_ERROR = 5
uint8 TRANSFORM_ERROR = 6

uint8 error
string error_string
""",
    "msg/TFMessage.msg": """\
geometry_msgs/TransformStamped[] transforms
""",
    "srv/FrameGraph.srv": """\
---
string frame_yaml
""",
    "action/LookupTransform.action": """\
#Simple API
string target_frame
string source_frame
builtin_interfaces/Time source_time
builtin_interfaces/Duration timeout

#Advanced API
builtin_interfaces/Time target_time
string fixed_frame

#Whether or not to use the advanced API
bool advanced

---
geometry_msgs/TransformStamped transform
tf2_msgs/TF2Error error
---
""",
}


#: name -> (version, dependencies, interface files)
PACKAGES: dict[str, tuple[str, list[str], dict[str, str]]] = {
    "controller_manager_msgs": (
        "5.16.0",
        ["builtin_interfaces", "lifecycle_msgs", "std_msgs"],
        CONTROLLER_MANAGER_MSGS,
    ),
    "tf2_msgs": ("0.36.4", ["builtin_interfaces", "geometry_msgs"], TF2_MSGS),
}

PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>{name}</name>
  <version>{version}</version>
  <description>{name}, built by umbmark's tools/build_ros2_interfaces.py</description>
  <maintainer email="none@example.com">none</maintainer>
  <license>BSD</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
{depends}
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export>
    <build_type>ament_cmake</build_type>
  </export>
</package>
"""

CMAKE_LISTS = """cmake_minimum_required(VERSION 3.16)
project({name})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
{finds}
rosidl_generate_interfaces(${{PROJECT_NAME}}
  {files}
  DEPENDENCIES {deps}
)
# The message wheels were built in a manylinux container: their Python targets name that
# container's Python and NumPy headers. Point them at this environment's.
get_property(imported DIRECTORY PROPERTY IMPORTED_TARGETS)
foreach(target IN LISTS imported)
  get_target_property(dirs ${{target}} INTERFACE_INCLUDE_DIRECTORIES)
  if(dirs AND "${{dirs}}" MATCHES "^/opt/python/")
    set_target_properties(${{target}} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES
      "${{Python3_INCLUDE_DIRS}};${{Python3_NumPy_INCLUDE_DIRS}}")
  endif()
endforeach()
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""


def importable(name: str) -> bool:
    """Whether a fresh interpreter of this environment imports the package."""
    code = f"import {name}.msg" if name != "controller_manager_msgs" else f"import {name}.srv"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, check=False)
    return done.returncode == 0


def write_package(root: Path, name: str) -> None:
    """The package's source tree: package.xml, CMakeLists.txt and its interface files."""
    version, deps, files = PACKAGES[name]
    root.mkdir(parents=True)
    depends = "\n".join(f"  <depend>{d}</depend>" for d in deps)
    (root / "package.xml").write_text(
        PACKAGE_XML.format(name=name, version=version, depends=depends)
    )
    (root / "CMakeLists.txt").write_text(
        CMAKE_LISTS.format(
            name=name,
            finds="\n".join(f"find_package({d} REQUIRED)" for d in deps),
            files="\n  ".join(f'"{f}"' for f in files),
            deps=" ".join(deps),
        )
    )
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)


def build(name: str, work: Path, jobs: int) -> None:
    """Configure, compile and install one package into this environment's prefix."""
    prefix = Path(sys.prefix)
    src, bld = work / name, work / f"build-{name}"
    write_package(src, name)
    site = Path(sysconfig.get_paths()["purelib"]).relative_to(prefix)
    env = {
        **os.environ,
        "AMENT_PREFIX_PATH": str(prefix),
        "CMAKE_PREFIX_PATH": str(prefix),
        "PATH": f"{prefix / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
    }
    run = [
        ["cmake", "-S", str(src), "-B", str(bld), f"-DCMAKE_INSTALL_PREFIX={prefix}",
         f"-DCMAKE_PREFIX_PATH={prefix}", f"-DPython3_EXECUTABLE={sys.executable}",
         f"-DPYTHON_INSTALL_DIR={site}",
         "-DBUILD_TESTING=OFF", "-DCMAKE_BUILD_TYPE=Release"],
        ["cmake", "--build", str(bld), "--parallel", str(jobs)],
        ["cmake", "--install", str(bld)],
    ]  # fmt: skip
    for cmd in run:
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            tail = "\n".join((done.stdout + done.stderr).splitlines()[-40:])
            sys.exit(f"{name}: `{' '.join(cmd[:2])}` failed:\n{tail}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--force", action="store_true", help="build even if importable")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    todo = [n for n in PACKAGES if args.force or not importable(n)]
    if not todo:
        print("controller_manager_msgs and tf2_msgs import already: nothing to build")
        return 0
    for tool in ("cmake", "cc", "c++"):
        if shutil.which(tool) is None:
            sys.exit(f"{tool} is not on PATH: it is needed to build {', '.join(todo)}")
    pip = [sys.executable, "-m", "pip", "install", "-q", *BUILD_REQUIREMENTS]
    if subprocess.run(pip, check=False).returncode != 0:
        sys.exit("could not install the interface generators: " + " ".join(BUILD_REQUIREMENTS))
    with tempfile.TemporaryDirectory(prefix="umbmark-ros2-interfaces-") as tmp:
        for name in todo:
            start = time.monotonic()
            build(name, Path(tmp), args.jobs)
            if not importable(name):
                sys.exit(f"{name} was built and installed into {sys.prefix} but does not import")
            print(f"{name}: built and installed in {time.monotonic() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
