"""The JSON text of every report (``--json``, ``to_json()``), written in one place."""

from __future__ import annotations

import json
from typing import Protocol

__all__ = ["JsonText"]


class _HasDict(Protocol):
    def to_dict(self) -> object: ...


class JsonText:
    """Mixin of the reports: :meth:`to_json` is the JSON text of their ``to_dict()``."""

    __slots__ = ()

    def to_json(self: _HasDict) -> str:
        """The JSON text of :meth:`to_dict`: strict (no NaN, no infinity), indented by two,
        ending in a newline."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"
