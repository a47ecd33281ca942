"""The conditions the drive's SDO layer turns into answers: an abort raised by an object handler, and the
read-step conditions of the curve and command-table stores (answered according to the ProtocolOptions).

The numbers themselves (E1100 result codes, SDO abort codes) are the protocol catalogue's
(linmot_st/protocol/codes.py), re-exported here for the SDO server's modules; docs/emulator.md says when each
is sent."""

from __future__ import annotations

from ..protocol.codes import *  # noqa: F401,F403 (the numbers, for the SDO server's modules)
from ..protocol.codes import SDO_ABORTS


class SdoAbort(Exception):
    """Raised by an object handler: the SDO server answers with this abort code."""

    def __init__(self, code: int, reason: str = ""):
        super().__init__(f"SDO abort {code:08X}h ({SDO_ABORTS.get(code, 'unknown')}){': ' + reason if reason else ''}")
        self.code = code


class NotStarted(Exception):
    """A read step (61h/62h, 86h) without the start that opens the block (60h, 85h)."""


class NoMoreData(Exception):
    """A read step after the end of the block."""
