"""The numbers a drive answers an SDO request with: E1100 result codes (byte 6 of a 60h download response,
byte 4 of some upload responses) and the CiA 301 SDO abort codes. One table for the PLC library's decoding
(`protocol.errors.describe`) and the emulated drive (its SDO server and services); docs/emulator.md says when
the drive sends each.
"""

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

# the result codes the emulated drive answers with (tests/vectors/sdo_frames.json covers each)
RESULT_NAMES = {
    RC_OK: "ok / finished",
    RC_NOT_FINISHED: "block not finished / busy",
    RC_RANGE_ERROR: "range error",
    RC_BLOCK_FINISHED: "block already finished",
    RC_SIZE_ERROR: "size error",
    RC_CURVE_EXISTS: "curve exists / not present",
    RC_MC_NOT_STOPPED: "MC software not stopped",
}

# --- CiA 301 SDO abort codes (section 7.2.4.3.17) ---
ABORT_TOGGLE = 0x05030000           # toggle bit not alternated (segmented transfer)
ABORT_TIMEOUT = 0x05040000
ABORT_COMMAND = 0x05040001          # client/server command specifier not valid or unknown
ABORT_OUT_OF_MEMORY = 0x05040005
ABORT_UNSUPPORTED = 0x06010000      # unsupported access to an object
ABORT_WRITE_ONLY = 0x06010001       # attempt to read a write-only object
ABORT_READ_ONLY = 0x06010002        # attempt to write a read-only object
ABORT_NO_OBJECT = 0x06020000        # object does not exist in the object dictionary
ABORT_NOT_MAPPABLE = 0x06040041
ABORT_HARDWARE = 0x06060000
ABORT_LENGTH = 0x06070010           # data type does not match, length of service parameter does not match
ABORT_LENGTH_HIGH = 0x06070012      # length of service parameter too high
ABORT_LENGTH_LOW = 0x06070013       # length of service parameter too low
ABORT_NO_SUBINDEX = 0x06090011      # sub-index does not exist
ABORT_RANGE = 0x06090030            # invalid value for parameter (value range exceeded)
ABORT_TOO_HIGH = 0x06090031
ABORT_TOO_LOW = 0x06090032
ABORT_GENERAL = 0x08000000          # general error
ABORT_TRANSFER = 0x08000020
ABORT_LOCAL_CONTROL = 0x08000021
ABORT_STATE = 0x08000022            # data cannot be transferred or stored because of the present device state
ABORT_NO_DATA = 0x08000024          # no data available

SDO_ABORTS: dict[int, str] = {
    ABORT_TOGGLE: "toggle bit not alternated",
    ABORT_TIMEOUT: "SDO protocol timed out",
    ABORT_COMMAND: "client/server command specifier not valid or unknown",
    ABORT_OUT_OF_MEMORY: "out of memory",
    ABORT_UNSUPPORTED: "unsupported access to an object",
    ABORT_WRITE_ONLY: "attempt to read a write only object",
    ABORT_READ_ONLY: "attempt to write a read only object",
    ABORT_NO_OBJECT: "object does not exist in the object dictionary",
    ABORT_NOT_MAPPABLE: "object cannot be mapped to the PDO",
    ABORT_HARDWARE: "access failed due to a hardware error",
    ABORT_LENGTH: "data type does not match, length of service parameter does not match",
    ABORT_LENGTH_HIGH: "data type does not match, length of service parameter too high",
    ABORT_LENGTH_LOW: "data type does not match, length of service parameter too low",
    ABORT_NO_SUBINDEX: "sub-index does not exist",
    ABORT_RANGE: "invalid value for parameter (download only)",
    ABORT_TOO_HIGH: "value of parameter written too high",
    ABORT_TOO_LOW: "value of parameter written too low",
    ABORT_GENERAL: "general error",
    ABORT_TRANSFER: "data cannot be transferred or stored to the application",
    ABORT_LOCAL_CONTROL: "data cannot be transferred because of local control",
    ABORT_STATE: "data cannot be transferred because of the present device state",
    ABORT_NO_DATA: "no data available",
}

# the abort codes the emulated drive answers with (tests/vectors/sdo_frames.json covers each)
DRIVE_ABORTS = frozenset({
    ABORT_TOGGLE, ABORT_COMMAND, ABORT_UNSUPPORTED, ABORT_WRITE_ONLY, ABORT_READ_ONLY, ABORT_NO_OBJECT,
    ABORT_LENGTH, ABORT_LENGTH_HIGH, ABORT_LENGTH_LOW, ABORT_NO_SUBINDEX, ABORT_RANGE, ABORT_GENERAL,
    ABORT_STATE, ABORT_NO_DATA,
})
