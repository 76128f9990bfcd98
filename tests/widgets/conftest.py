"""Kernel-free widget tests: capture what the canvases would send to the browser."""

from __future__ import annotations

import json

import ipycanvas
import numpy as np
import pytest
from ipycanvas.canvas import COMMANDS

NAMES = {index: name for name, index in COMMANDS.items()}


class CanvasRecorder:
    """Records every message the ipycanvas manager sends, decoded to (canvas_id, name, args)."""

    def __init__(self):
        self.messages: list[tuple[list, list]] = []

    def __call__(self, command, buffers=()):
        self.messages.append((command, list(buffers)))

    def clear(self) -> None:
        self.messages.clear()

    @staticmethod
    def _decode(message) -> list[tuple[str, list]]:
        command, _ = message
        batch = command if command and isinstance(command[0], list) else [command]
        return [(NAMES[c[0]], c[1]) for c in batch]

    def commands(self, message_index: int | None = None) -> list[tuple[str | None, str, list]]:
        """(canvas model id, command name, args) of one message, or of all messages."""
        chosen = self.messages if message_index is None else [self.messages[message_index]]
        result, current = [], None
        for message in chosen:
            for name, args in self._decode(message):
                if name == "switchCanvas":
                    current = args[0].replace("IPY_MODEL_", "")
                    continue
                result.append((current, name, args))
        return result

    def on(self, canvas, message_index: int | None = None) -> list[tuple[str, list]]:
        """(name, args) of the commands drawn on one canvas layer."""
        return [(n, a) for c, n, a in self.commands(message_index) if c == canvas.model_id]

    def message_bytes(self, message_index: int) -> int:
        """Bytes of one message as sent: the JSON command buffer plus the binary buffers."""
        command, buffers = self.messages[message_index]
        return len(json.dumps(command).encode()) + sum(memoryview(b).nbytes for b in buffers)


@pytest.fixture
def recorder(monkeypatch):
    """Replace the canvas manager's sender; yields the ``CanvasRecorder``."""
    manager = ipycanvas.canvas._CANVAS_MANAGER
    rec = CanvasRecorder()
    monkeypatch.setattr(manager, "_send_custom", rec)
    manager._current_canvas = None
    yield rec
    manager._caching = False
    manager._commands_cache, manager._buffers_cache = [], []


def pointer(multicanvas, event: str, x: float, y: float) -> None:
    """Fake a browser pointer event at canvas pixel (x, y); MultiCanvas events go to its top layer."""
    multicanvas[-1]._handle_frontend_event(None, {"event": event, "x": x, "y": y}, [])


def key(multicanvas, name: str, shift: bool = False) -> None:
    multicanvas[-1]._handle_frontend_event(
        None, {"event": "key_down", "key": name, "shift_key": shift, "ctrl_key": False, "meta_key": False}, [])


def client_ready(layer) -> None:
    layer._handle_frontend_event(None, {"event": "client_ready"}, [])


def path_points(commands) -> list[tuple[float, float]]:
    """Points of moveTo/lineTo commands, in order."""
    return [tuple(args[:2]) for name, args in commands if name in ("moveTo", "lineTo")]


def near(points, target, tolerance: float = 0.11) -> bool:
    target = np.asarray(target, dtype=float)
    return any(np.hypot(*(np.asarray(p, dtype=float) - target)) <= tolerance for p in points)
