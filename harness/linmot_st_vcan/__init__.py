"""A real Linux SocketCAN stack with vcan interfaces for the tests, on machines whose kernel has no CAN.

`Machine().run(argv)` starts a User-Mode Linux guest (Debian's kernel, fetched into a cache by fetch.py)
with vcan0 and vcan1 up and runs argv there with the host's files and the project's venv; `pytest_plugin`
runs the tests marked `socketcan` inside such a guest; `testing` has the helpers those tests share
(emulated drives served by `linmot-st emulate`, candump recordings). docs/bus.md, "A real SocketCAN stack".
"""

from __future__ import annotations

import os

from .fetch import Tools, Unavailable, cache_dir, ensure
from .uml import GuestRun, GuestStartError, Machine

__all__ = ["GuestRun", "GuestStartError", "Machine", "Tools", "Unavailable", "cache_dir", "ensure", "native"]


def native(interfaces: tuple[str, ...] = ("vcan0",)) -> bool:
    """True when this kernel has the interfaces itself (a Linux machine with `modprobe vcan`, or the guest)."""
    return all(os.path.exists(f"/sys/class/net/{name}") for name in interfaces)
