"""Live bounded-distortion editing: ``LiveSession`` (set up once, ``update(targets)`` per frame,
every frame certified from its own coordinates). See ``session``."""
from .frame import LiveFrame, SessionClosedError
from .session import LiveSession

__all__ = ["LiveFrame", "LiveSession", "SessionClosedError"]
