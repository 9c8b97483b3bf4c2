"""A node's persisted state (`NodeState`): what must survive a crash of the asset's process,
one JSON document rewritten atomically on every change."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from transfertwin._atomic import write_atomic

__all__ = ["NodeState"]


class NodeState:
    """A node's persisted state: one JSON document, rewritten atomically on every change.

    Args:
        path: The file (created with its folder on the first `save`).
        initial: The state when the file does not exist yet.
    """

    def __init__(self, path: Path, initial: dict[str, Any]) -> None:
        self.path = path
        self.data: dict[str, Any] = dict(initial)
        if path.is_file():
            self.data.update(json.loads(path.read_text()))

    def save(self) -> None:
        """Write the whole state (readers see the old file or the new one, never a part)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(self.path, json.dumps(self.data, indent=1, sort_keys=True) + "\n")
