"""The reading options are written once, in the option spec: the typed views
(``SourceOptions``, ``ReadOptions``' fields) are generated from it and must be what the
tool writes now, and ``BagOptions`` takes the spec's names, so that the step from the
reading options to a bag's is one loop over the shared names."""

from __future__ import annotations

import dataclasses
import importlib.util
import typing
from pathlib import Path
from types import ModuleType

import pytest

from umbmark.model.kinematics import WheelParams
from umbmark.options.spec import BAGS, READ, READ_OPTIONS, Spec
from umbmark.runs.read import bag_options
from umbmark.runs.read_fields import ReadFields, SourceOptions
from umbmark.runs.read_options import ReadOptions
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.params.reader import ControllerParams

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "gen_read_options.py"
GENERATED = ROOT / "src" / "umbmark" / "runs" / "read_fields.py"


@pytest.fixture(scope="module")
def tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_read_options", TOOL)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_generated_module_is_what_the_tool_writes_now(tool: ModuleType) -> None:
    assert tool.TARGET == GENERATED
    assert GENERATED.read_text(encoding="utf-8") == tool.render(), (
        "src/umbmark/runs/read_fields.py is stale: run "
        "PYTHONPATH=src python tools/gen_read_options.py"
    )
    assert tool.main(["--check"]) == 0


def test_a_new_spec_is_a_new_keyword_and_field(
    tool: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    added = Spec("wheel_count", ("--wheel-count",), BAGS, "Wheels, with --wheel-topic.", "number")
    monkeypatch.setattr(tool, "READ_OPTIONS", (*READ_OPTIONS, added))
    text = tool.render()
    assert "    wheel_count: float | None\n" in text  # SourceOptions
    assert "    wheel_count: float | None = None\n" in text  # ReadFields
    assert "        Wheels, with ``wheel_topic``.\n" in text  # its help, flags as keywords
    assert tool.main(["--check"]) == 1  # the module on disk lacks it


def test_the_python_type_follows_the_kind(tool: ModuleType) -> None:
    assert tool.python_type(READ["unit"]) == 'Literal["m", "cm", "mm"]'
    assert tool.python_type(READ["max_gap"]) == "float"  # a default: never None
    assert tool.python_type(READ["wheel_diameter"]) == "float | None"
    assert tool.python_type(READ["truth_offset"]) == "tuple[float, float] | None"
    assert tool.python_type(READ["odom_tf"]) == "tuple[str, str] | None"
    assert tool.python_type(READ["msg_dir"]) == "PathLike | None"
    assert tool.python_type(READ["left_joint"]) == "str | Sequence[str] | None"  # py_type given


def test_the_typed_views_hold_every_reading_option_in_the_spec_order() -> None:
    names = [spec.name for spec in READ_OPTIONS]
    assert list(typing.get_type_hints(SourceOptions)) == names
    assert [f.name for f in dataclasses.fields(ReadOptions)] == names
    assert issubclass(ReadOptions, ReadFields)
    for f in dataclasses.fields(ReadOptions):
        assert f.default == READ[f.name].default, f.name
    hints = typing.get_type_hints(SourceOptions)
    assert typing.get_args(hints["split"]) == ("rests", "none", "windows")
    assert typing.get_args(hints["time_source"]) == ("header", "bag")


def test_bag_options_take_the_spec_names_and_defaults() -> None:
    own = {"odom_geometry"}  # computed from the active parameters, no option
    for f in dataclasses.fields(BagOptions):
        if f.name in own:
            continue
        assert f.name in READ, f"BagOptions.{f.name} is no reading option's name"
        assert f.default == READ[f.name].default, f.name


def test_the_reading_options_reach_the_bag_by_name() -> None:
    given = ReadOptions(
        wheel_topic="/w",
        left_ticks_topic="/lt",
        right_ticks_topic="/rt",
        ticks_per_rev=4096.0,
        truth_topic="/mocap",
        truth_model="robot",
        time_source="bag",
        left_joint=["l1", "l2"],
        right_joint="r1,r2",
    )
    bag = bag_options(given, None, ControllerParams())
    assert (bag.wheel_topic, bag.left_ticks_topic, bag.right_ticks_topic) == ("/w", "/lt", "/rt")
    assert (bag.ticks_per_rev, bag.truth_topic, bag.truth_model) == (4096.0, "/mocap", "robot")
    assert bag.time_source == "bag"
    assert (bag.left_joints, bag.right_joints) == (("l1", "l2"), ("r1", "r2"))
    assert bag.odom_geometry is None
    fields = bag_options(
        ReadOptions(msg_dir="defs", left_field="a", right_field="b"), None, ControllerParams()
    )
    assert (fields.msg_dir, fields.left_field, fields.right_field) == (Path("defs"), "a", "b")
    other = bag_options(
        ReadOptions(odom_tf=["odom", "base_link"]),  # type: ignore[arg-type]
        WheelParams(wheelbase=0.5, wheel_diameter=0.2, c_left=1.1, c_right=0.9),
        ControllerParams(),
    )
    assert other.odom_tf == ("odom", "base_link")
    geometry = other.odom_geometry
    assert geometry is not None
    # radius 0.1 m times each wheel's factor; the separation is the wheelbase
    assert (geometry.left_radius, geometry.right_radius) == pytest.approx((0.11, 0.09))
    assert geometry.separation == 0.5
