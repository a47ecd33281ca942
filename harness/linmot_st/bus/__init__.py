"""CAN bus: frames, the deterministic simulated bus in virtual time, python-can adapters."""

from .frame import Frame

__all__ = ["Frame"]
