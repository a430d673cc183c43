"""A fleet's per-robot reading options: a small YAML file, one mapping per robot.

```yaml
amr1:                       # the robot's name (as the path pattern or the recording names it)
  truth_topic: /mocap/amr1  # reading options by keyword, as umbmark.calibrate takes them
  wheelbase: 0.34
amr2:
  scan_topic: /front/scan
```

Options given on the command line apply to every robot; a robot's own win over them.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from umbmark.core.errors import InputError

__all__ = ["MAX_ROBOT_OPTIONS_BYTES", "read_robot_options"]

#: Largest per-robot options file [bytes].
MAX_ROBOT_OPTIONS_BYTES = 1 << 20


def read_robot_options(path: str | os.PathLike[str]) -> dict[str, dict[str, Any]]:
    """The per-robot options of ``path``: robot name to reading options by keyword.

    Raises
    ------
    InputError
        A file that cannot be read, is too large, is not YAML, is not a mapping of robot
        names to mappings, or names an option no reader takes.
    """
    import yaml

    from umbmark.options.spec import READ, WHEELBASE

    where = Path(path)
    try:
        if where.stat().st_size > MAX_ROBOT_OPTIONS_BYTES:
            raise InputError(f"larger than {MAX_ROBOT_OPTIONS_BYTES} bytes", source=where)
        text = where.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError("no such file", source=where) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot be read ({exc})", source=where) from None
    try:
        data = yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else "not YAML"
        raise InputError(f"is not YAML ({first})", source=where) from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise InputError("should map each robot's name to its options", source=where)
    known = {*READ, WHEELBASE.name}
    out: dict[str, dict[str, Any]] = {}
    for robot, options in data.items():
        if not isinstance(options, dict):
            raise InputError(f"robot {robot!r}: give a mapping of options", source=where)
        unknown = sorted(str(k) for k in options if k not in known)
        if unknown:
            raise InputError(
                f"robot {robot!r}: {unknown[0]!r} is no reading option (keywords such as "
                "truth_topic, scan_topic, wheelbase)",
                source=where,
            )
        out[str(robot)] = {str(k): v for k, v in options.items()}
    return out
