"""Commands a drive series does not have: the catalogue row's `drives` decides (the B1100 has no cam motions,
[MC] 5.5). The MC knows its series from the drive model (E1100Drive sets mc.series)."""

from __future__ import annotations

from ...protocol import words as W
from ...protocol.commands import CommandDef


def on_series(handler):
    """A handler that answers 0081h (unknown command) on a drive whose series the row does not list: the B1100
    has no cam motions ([MC] 5.5)."""
    def run(mc, c: CommandDef, f: dict, t: int) -> bool:
        if getattr(mc, "series", "E1100") not in c.drives:
            return mc._fail(W.ERR_UNKNOWN_MOTION_CMD, t)
        return handler(mc, c, f, t)
    return run
