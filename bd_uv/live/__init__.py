"""Live bounded-distortion editing: ``LiveSession`` (set up once, ``update(targets)`` per frame,
every frame certified from its own coordinates). See ``session``."""
from .session import LiveFrame, LiveSession, SessionClosedError

__all__ = ["LiveFrame", "LiveSession", "SessionClosedError"]
