"""The numbers the drive answers with: E1100 result codes (byte 6 of a 60h download response, byte 4 of some
upload responses) and the CiA 301 SDO abort codes the emulator uses, and the conditions the curve and
command-table stores report for a read step (the SDO layer turns them into answers according to the
ProtocolOptions). docs/emulator.md says when each is sent."""

from __future__ import annotations

# --- E1100 result codes (spec/linmot-canopen.md 3.6) ---
RC_OK = 0x00               # done / block finished / curve exists / flash idle
RC_NOT_FINISHED = 0x04     # block not finished (more to come); flash busy on poll reads; UPID list started
RC_RANGE_ERROR = 0xC2      # INFERRED use: a curve info-block or CT-entry field out of range (LinUDP "range error")
RC_BLOCK_FINISHED = 0xD0   # block already finished / no block open for writing
RC_SIZE_ERROR = 0xD1       # invalid block size (LinUDP "size error", SG5 CT write)
RC_CURVE_EXISTS = 0xD4     # add: curve already exists; get: curve (or CT entry) not present
RC_NOT_PRESENT = 0xD4
RC_MC_NOT_STOPPED = 0xD7   # flash save while MC software runs (LinRS state D7h)

RESULT_NAMES = {
    RC_OK: "ok / finished",
    RC_NOT_FINISHED: "block not finished / busy",
    RC_RANGE_ERROR: "range error",
    RC_BLOCK_FINISHED: "block already finished",
    RC_SIZE_ERROR: "size error",
    RC_CURVE_EXISTS: "curve exists / not present",
    RC_MC_NOT_STOPPED: "MC software not stopped",
}

# --- CiA 301 SDO abort codes ---
ABORT_TOGGLE = 0x05030000           # toggle bit not alternated (segmented transfer)
ABORT_COMMAND = 0x05040001          # client/server command specifier not valid or unknown
ABORT_UNSUPPORTED = 0x06010000      # unsupported access to an object
ABORT_WRITE_ONLY = 0x06010001       # attempt to read a write-only object
ABORT_READ_ONLY = 0x06010002        # attempt to write a read-only object
ABORT_NO_OBJECT = 0x06020000        # object does not exist in the object dictionary
ABORT_LENGTH = 0x06070010           # data type does not match, length of service parameter does not match
ABORT_LENGTH_HIGH = 0x06070012      # length of service parameter too high
ABORT_LENGTH_LOW = 0x06070013       # length of service parameter too low
ABORT_NO_SUBINDEX = 0x06090011      # sub-index does not exist
ABORT_RANGE = 0x06090030            # invalid value for parameter (value range exceeded)
ABORT_GENERAL = 0x08000000          # general error
ABORT_STATE = 0x08000022            # data cannot be transferred or stored because of the present device state
ABORT_NO_DATA = 0x08000024          # no data available

ABORT_NAMES = {
    ABORT_TOGGLE: "toggle bit not alternated",
    ABORT_COMMAND: "command specifier not valid or unknown",
    ABORT_UNSUPPORTED: "unsupported access to an object",
    ABORT_WRITE_ONLY: "attempt to read a write-only object",
    ABORT_READ_ONLY: "attempt to write a read-only object",
    ABORT_NO_OBJECT: "object does not exist",
    ABORT_LENGTH: "length of service parameter does not match",
    ABORT_LENGTH_HIGH: "length of service parameter too high",
    ABORT_LENGTH_LOW: "length of service parameter too low",
    ABORT_NO_SUBINDEX: "sub-index does not exist",
    ABORT_RANGE: "value range exceeded",
    ABORT_GENERAL: "general error",
    ABORT_STATE: "refused in the present device state",
    ABORT_NO_DATA: "no data available",
}


class SdoAbort(Exception):
    """Raised by an object handler: the SDO server answers with this abort code."""

    def __init__(self, code: int, reason: str = ""):
        super().__init__(f"SDO abort {code:08X}h ({ABORT_NAMES.get(code, 'unknown')}){': ' + reason if reason else ''}")
        self.code = code


class NotStarted(Exception):
    """A read step (61h/62h, 86h) without the start that opens the block (60h, 85h)."""


class NoMoreData(Exception):
    """A read step after the end of the block."""
